//! The minimal solvers of a rig (a generalised camera) with lines: gP2P1L, gP1P2L and gP3L, and
//! [`solve_generalized`], which dispatches a sample of any three [`RigFeature`]s to its solver (gP3P,
//! [`super::gp3p()`], for three points).
//!
//! Frame: the rig's, `x_rig = R X_world + t`. A point is seen along a ray with origin `o` (its camera's
//! centre) and direction `y`: `R X + t = o + λ y`, `λ > 0`. A segment is seen by a camera of centre `c`
//! in the interpretation plane through `c` with normal `n`: `n · (R P + t − c) = 0` for every point `P`
//! of the object line. The line's direction `d` gives `nᵀ R d = 0` as for one camera; the offsets `o` and
//! `c`, which do not vanish when the cameras do not share one centre, make the other constraints on `R`
//! affine, `⟨M, R⟩ = c`, solved by the shared kernel with constants
//! ([`super::rotation_constraints`], `affine_rotations`). The depths and the translation then follow
//! linearly, as for one camera.
//!
//! Miraldo, Dias & Ramalingam ("A minimal closed-form solution for multi-perspective pose estimation
//! using points and lines", ECCV 2018) solve the two mixed cases for multi-camera rigs, 2 points + 1
//! line with a quartic and 1 point + 2 lines with an octic; the eliminations here are our own, through
//! the kernel's degree-8 polynomial, and return every real pose with positive depths that satisfies the
//! constraints (at most 8).
//!
//! - **gP2P1L** (`gp2p1l`): with `e = X₂ − X₁`, `Δo = o₂ − o₁`, `m = y₁ × y₂`, `g₁ = (m × y₂) / ‖m‖²`,
//!   `g₂ = (m × y₁) / ‖m‖²`, the points give `R e − Δo = λ₂ y₂ − λ₁ y₁`, so `mᵀ R e = mᵀ Δo` and
//!   `λⱼ = gⱼᵀ (R e − Δo)`. With `t = o₁ + λ₁ y₁ − R X₁` and `p` the point of the line nearest `X₁`,
//!   minus `X₁`, the line gives `nᵀ R d = 0` and `nᵀ R p + (nᵀ y₁) g₁ᵀ R e = (nᵀ y₁) g₁ᵀ Δo − nᵀ (o₁ − c)`.
//! - **gP1P2L** (`gp1p2l`): `t = o + λ y − R X`; line `i` (`pᵢ` its point nearest `X`, minus `X`,
//!   `sᵢ = nᵢᵀ y`) gives `nᵢᵀ R dᵢ = 0` and `nᵢᵀ R pᵢ + nᵢᵀ (o − cᵢ) + λ sᵢ = 0`; eliminating `λ`:
//!   `⟨s₂ n₁ p₁ᵀ − s₁ n₂ p₂ᵀ, R⟩ = s₁ n₂ᵀ (o − c₂) − s₂ n₁ᵀ (o − c₁)`.
//! - **gP3L** (`gp3l`): the three direction constraints fix `R` as for one camera (P3L: Dhome et al.,
//!   IEEE PAMI 1989; Chen, ICCV 1990); the three planes then fix `t` linearly, `nᵢ · t = nᵢ · (cᵢ − R Pᵢ)`.
//!
//! Like the single camera's solvers these never fail loudly: invalid or degenerate input (non-finite
//! values, zero directions or normals, coincident points, parallel rays of the two points of gP2P1L)
//! gives no pose, and every returned pose is checked against the original constraints.

use super::input::{finite, unit, Line, SOLUTION_TOLERANCE};
use super::rotation_constraints::{affine_rotations, rotations};
use super::{gp3p, Pose};
use crate::pose::generalized::Ray;
use nalgebra::{Matrix3, Vector3};

/// One correspondence of a rig's sample, rig frame (image side) and world frame (object side).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RigFeature {
    /// A point on a ray: `R point + t = ray.origin + λ ray.direction`, `λ > 0`.
    Point {
        /// The ray of the observation (its camera's centre, the bearing turned into the rig's frame).
        ray: Ray,
        /// The object point, world frame.
        point: Vector3<f64>,
    },
    /// An object line in an interpretation plane: `normal · (R P + t − centre) = 0` for both
    /// `endpoints` (two distinct points of the object line, world frame).
    Line {
        /// The plane's normal, rig frame (any non-zero multiple).
        normal: Vector3<f64>,
        /// A point of the plane: the centre of the camera that saw the segment, rig frame.
        centre: Vector3<f64>,
        /// Two points of the object line, world frame.
        endpoints: [Vector3<f64>; 2],
    },
}

/// A validated ray: finite origin, unit direction.
fn ray(r: &Ray) -> Option<(Vector3<f64>, Vector3<f64>)> {
    Some((finite(&r.origin)?, unit(&r.direction)?))
}

/// `R X + t` on the ray `(o, y)`, in front ([`SOLUTION_TOLERANCE`], relative to the distance from `o`).
fn point_holds(o: &Vector3<f64>, y: &Vector3<f64>, x: &Vector3<f64>, pose: &Pose) -> bool {
    let v = pose.transform(x) - o;
    y.dot(&v) > 0.0 && y.cross(&v).norm() <= SOLUTION_TOLERANCE * v.norm()
}

/// Both object points of `line` on its plane through `c` ([`SOLUTION_TOLERANCE`], relative to their
/// distance from `c`).
fn line_holds(line: &Line, c: &Vector3<f64>, pose: &Pose) -> bool {
    line.endpoints.iter().all(|p| {
        let v = pose.transform(p) - c;
        line.normal.dot(&v).abs() <= SOLUTION_TOLERANCE * v.norm()
    })
}

/// gP2P1L: every pose with `points[j]` on `rays[j]` at positive depth and the object line through
/// `endpoints` in the plane of `normal` through `centre` (module documentation); at most 8.
pub fn gp2p1l(
    rays: &[Ray; 2],
    points: &[Vector3<f64>; 2],
    normal: &Vector3<f64>,
    centre: &Vector3<f64>,
    endpoints: &[Vector3<f64>; 2],
) -> Vec<Pose> {
    let (Some((o1, y1)), Some((o2, y2))) = (ray(&rays[0]), ray(&rays[1])) else {
        return Vec::new();
    };
    let (Some(x1), Some(x2), Some(c), Some(line)) = (
        finite(&points[0]),
        finite(&points[1]),
        finite(centre),
        Line::new(normal, endpoints),
    ) else {
        return Vec::new();
    };
    let (e, shift, m) = (x2 - x1, o2 - o1, y1.cross(&y2));
    let m_squared = m.norm_squared();
    if !(m_squared > 0.0) || unit(&e).is_none() {
        return Vec::new();
    }
    let (g1, g2) = (m.cross(&y2) / m_squared, m.cross(&y1) / m_squared);
    let n = line.normal;
    let p = line.offset_from(&x1);
    let s = n.dot(&y1);
    let offset = n * p.transpose() + (g1 * s) * e.transpose();
    let offset_constant = s * g1.dot(&shift) - n.dot(&(o1 - c));
    affine_rotations(
        &n,
        &line.direction,
        [m * e.transpose(), offset],
        [m.dot(&shift), offset_constant],
    )
    .into_iter()
    .filter_map(|r| {
        let moved = r * e - shift;
        let (depth1, depth2) = (g1.dot(&moved), g2.dot(&moved));
        let t = 0.5 * ((o1 + y1 * depth1 - r * x1) + (o2 + y2 * depth2 - r * x2));
        let pose = Pose::new(r, t);
        let holds =
            point_holds(&o1, &y1, &x1, &pose) && point_holds(&o2, &y2, &x2, &pose) && line_holds(&line, &c, &pose);
        (depth1 > 0.0 && depth2 > 0.0 && holds).then_some(pose)
    })
    .collect()
}

/// gP1P2L: every pose with `point` on `ray` at positive depth and each object line `i` (through
/// `endpoints[i]`) in the plane of `normals[i]` through `centres[i]` (module documentation); at most 8.
pub fn gp1p2l(
    ray_: &Ray,
    point: &Vector3<f64>,
    normals: &[Vector3<f64>; 2],
    centres: &[Vector3<f64>; 2],
    endpoints: &[[Vector3<f64>; 2]; 2],
) -> Vec<Pose> {
    let (Some((o, y)), Some(x)) = (ray(ray_), finite(point)) else {
        return Vec::new();
    };
    let (Some(first), Some(second), Some(c1), Some(c2)) = (
        Line::new(&normals[0], &endpoints[0]),
        Line::new(&normals[1], &endpoints[1]),
        finite(&centres[0]),
        finite(&centres[1]),
    ) else {
        return Vec::new();
    };
    let (lines, c) = ([first, second], [c1, c2]);
    let p = lines.map(|l| l.offset_from(&x));
    let s = lines.map(|l| l.normal.dot(&y));
    let free = [first.normal.dot(&(o - c1)), second.normal.dot(&(o - c2))];
    let depth_constraint = first.normal * (p[0] * s[1]).transpose() - second.normal * (p[1] * s[0]).transpose();
    let depth_constant = s[0] * free[1] - s[1] * free[0];
    let s_squared = s[0] * s[0] + s[1] * s[1];
    if !(s_squared > 0.0) {
        return Vec::new();
    }
    affine_rotations(
        &first.normal,
        &first.direction,
        [second.direction_constraint(), depth_constraint],
        [0.0, depth_constant],
    )
    .into_iter()
    .filter_map(|r| {
        let depth = -(0..2)
            .map(|i| s[i] * (lines[i].normal.dot(&(r * p[i])) + free[i]))
            .sum::<f64>()
            / s_squared;
        let pose = Pose::new(r, o + y * depth - r * x);
        let holds = point_holds(&o, &y, &x, &pose) && (0..2).all(|i| line_holds(&lines[i], &c[i], &pose));
        (depth > 0.0 && holds).then_some(pose)
    })
    .collect()
}

/// gP3L: every pose with each object line `i` (through `endpoints[i]`) in the plane of `normals[i]`
/// through `centres[i]` (module documentation); at most 8.
pub fn gp3l(normals: &[Vector3<f64>; 3], centres: &[Vector3<f64>; 3], endpoints: &[[Vector3<f64>; 2]; 3]) -> Vec<Pose> {
    let mut lines = Vec::with_capacity(3);
    for ((n, e), c) in normals.iter().zip(endpoints).zip(centres) {
        match (Line::new(n, e), finite(c)) {
            (Some(line), Some(c)) => lines.push((line, c)),
            _ => return Vec::new(),
        }
    }
    let normal_matrix = Matrix3::from_rows(&lines.iter().map(|(l, _)| l.normal.transpose()).collect::<Vec<_>>());
    // LU with partial pivoting, as P3L: backward stable where `N` is nearly singular.
    let lu = normal_matrix.lu();
    if !lu.is_invertible() {
        return Vec::new();
    }
    let origin = lines.iter().map(|(l, _)| l.midpoint).sum::<Vector3<f64>>() / 3.0;
    let offsets: Vec<Vector3<f64>> = lines.iter().map(|(l, _)| l.offset_from(&origin)).collect();
    let [(first, _), (second, _), (third, _)] = [lines[0], lines[1], lines[2]];
    rotations(
        &first.normal,
        &first.direction,
        [second.direction_constraint(), third.direction_constraint()],
    )
    .into_iter()
    .filter_map(|r| {
        // nᵢ · (R (origin + offsetᵢ) + t − cᵢ) = 0 with t = t' − R origin.
        let h = Vector3::from_fn(|i, _| lines[i].0.normal.dot(&(lines[i].1 - r * offsets[i])));
        let pose = Pose::new(r, lu.solve(&h)? - r * origin);
        lines.iter().all(|(l, c)| line_holds(l, c, &pose)).then_some(pose)
    })
    .collect()
}

/// Every pose that explains the three correspondences of `sample` exactly, from the solver for its mix
/// of points and lines (in any order): [`super::gp3p()`], [`gp2p1l`], [`gp1p2l`] or [`gp3l`].
/// Degenerate or invalid samples give an empty vector.
pub fn solve_generalized(sample: &[RigFeature; 3]) -> Vec<Pose> {
    let (mut rays, mut points, mut normals, mut centres, mut ends) = (vec![], vec![], vec![], vec![], vec![]);
    for feature in sample {
        match *feature {
            RigFeature::Point { ray, point } => {
                rays.push(ray);
                points.push(point);
            }
            RigFeature::Line {
                normal,
                centre,
                endpoints,
            } => {
                normals.push(normal);
                centres.push(centre);
                ends.push(endpoints);
            }
        }
    }
    match normals.len() {
        0 => gp3p(&[rays[0], rays[1], rays[2]], &[points[0], points[1], points[2]]),
        1 => gp2p1l(
            &[rays[0], rays[1]],
            &[points[0], points[1]],
            &normals[0],
            &centres[0],
            &ends[0],
        ),
        2 => gp1p2l(
            &rays[0],
            &points[0],
            &[normals[0], normals[1]],
            &[centres[0], centres[1]],
            &[ends[0], ends[1]],
        ),
        _ => gp3l(
            &[normals[0], normals[1], normals[2]],
            &[centres[0], centres[1], centres[2]],
            &[ends[0], ends[1], ends[2]],
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// A random rig instance: a true pose, three cameras' centres 0.3 apart (rig frame), and `kinds`
    /// (true: a point) as features seen from them, objects 2-20 units away.
    fn instance(rng: &mut Rng, kinds: [bool; 3], central: bool) -> ([RigFeature; 3], Pose) {
        let truth = Pose::new(rng.rotation(), Vector3::new(rng.normal(), rng.normal(), rng.normal()));
        let inverse = truth.inverse();
        let features = kinds.map(|is_point| {
            let c = if central {
                Vector3::zeros()
            } else {
                0.3 * Vector3::new(rng.normal(), rng.normal(), rng.normal())
            };
            let far = |rng: &mut Rng| c + rng.unit_vector3() * rng.uniform_in(2.0, 20.0);
            if is_point {
                let x = far(rng);
                RigFeature::Point {
                    ray: Ray {
                        origin: c,
                        direction: (x - c) * rng.uniform_in(0.5, 2.0),
                    },
                    point: inverse.transform(&x),
                }
            } else {
                let (a, b) = (far(rng), far(rng));
                RigFeature::Line {
                    normal: (a - c).cross(&(b - c)),
                    centre: c,
                    endpoints: [inverse.transform(&a), inverse.transform(&b)],
                }
            }
        });
        (features, truth)
    }

    fn error(poses: &[Pose], truth: &Pose) -> f64 {
        poses
            .iter()
            .map(|p| (p.rotation - truth.rotation).norm() + (p.translation - truth.translation).norm() / 10.0)
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn random_rig_samples_give_the_true_pose_among_at_most_eight() {
        // Per mix, 2000 instances: the true pose within 1e-6 (relative to the 2-20 unit scene) in at
        // least 99.5 % of them; the rest are near-degenerate draws (a plane nearly through a point,
        // nearly parallel rays) where the constraints fix the pose poorly, as for one camera.
        let mut rng = Rng::new(808);
        for kinds in [[true, true, false], [true, false, false], [false, false, false]] {
            let (mut found, trials) = (0, 2000);
            for _ in 0..trials {
                let (sample, truth) = instance(&mut rng, kinds, false);
                let poses = solve_generalized(&sample);
                assert!(poses.len() <= 8, "{kinds:?}: {} poses", poses.len());
                found += usize::from(error(&poses, &truth) < 1e-6);
            }
            assert!(found as f64 >= 0.995 * trials as f64, "{kinds:?}: {found} of {trials}");
        }
    }

    #[test]
    fn every_returned_pose_satisfies_the_constraints() {
        let mut rng = Rng::new(809);
        for kinds in [[true, true, false], [true, false, false], [false, false, false]] {
            for _ in 0..300 {
                let (sample, _) = instance(&mut rng, kinds, false);
                for pose in solve_generalized(&sample) {
                    for f in &sample {
                        match *f {
                            RigFeature::Point { ray, point } => {
                                let v = pose.transform(&point) - ray.origin;
                                assert!(v.dot(&ray.direction) > 0.0);
                                assert!(ray.direction.normalize().cross(&v).norm() <= 1e-7 * v.norm());
                            }
                            RigFeature::Line {
                                normal,
                                centre,
                                endpoints,
                            } => {
                                for p in endpoints {
                                    let v = pose.transform(&p) - centre;
                                    assert!(normal.normalize().dot(&v).abs() <= 1e-7 * v.norm());
                                }
                            }
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn with_every_camera_at_the_origin_they_find_the_single_cameras_poses() {
        // A central rig is one camera: the same poses as p2p1l, p1p2l and p3l (bearings = directions,
        // normals as given), to rounding.
        let mut rng = Rng::new(810);
        for kinds in [[true, true, false], [true, false, false], [false, false, false]] {
            for _ in 0..200 {
                let (sample, _) = instance(&mut rng, kinds, true);
                let ours = solve_generalized(&sample);
                let single = super::super::solve(&sample.map(|f| match f {
                    RigFeature::Point { ray, point } => super::super::Feature::Point {
                        bearing: ray.direction,
                        point,
                    },
                    RigFeature::Line { normal, endpoints, .. } => super::super::Feature::Line { normal, endpoints },
                }));
                for p in &single {
                    assert!(error(&ours, p) < 1e-7, "{kinds:?}: a single-camera pose missing");
                }
                for p in &ours {
                    assert!(error(&single, p) < 1e-7, "{kinds:?}: a pose the single camera has not");
                }
            }
        }
    }

    #[test]
    fn scaling_the_scene_scales_the_translations() {
        let mut rng = Rng::new(811);
        for kinds in [[true, true, false], [true, false, false], [false, false, false]] {
            let (sample, _) = instance(&mut rng, kinds, false);
            let scaled = sample.map(|f| match f {
                RigFeature::Point { ray, point } => RigFeature::Point {
                    ray: Ray {
                        origin: 7.0 * ray.origin,
                        direction: ray.direction,
                    },
                    point: 7.0 * point,
                },
                RigFeature::Line {
                    normal,
                    centre,
                    endpoints,
                } => RigFeature::Line {
                    normal,
                    centre: 7.0 * centre,
                    endpoints: endpoints.map(|p| 7.0 * p),
                },
            });
            let (a, b) = (solve_generalized(&sample), solve_generalized(&scaled));
            assert_eq!(a.len(), b.len(), "{kinds:?}");
            for p in &a {
                let q = Pose::new(p.rotation, 7.0 * p.translation);
                assert!(error(&b, &q) < 1e-8, "{kinds:?}");
            }
        }
    }

    #[test]
    fn invalid_or_degenerate_samples_give_no_pose() {
        let mut rng = Rng::new(812);
        let (sample, _) = instance(&mut rng, [true, true, false], false);
        let mut bad = sample;
        if let RigFeature::Point { ray, .. } = &mut bad[0] {
            ray.direction = Vector3::zeros();
        }
        assert!(solve_generalized(&bad).is_empty());
        let mut bad = sample;
        if let RigFeature::Line { centre, .. } = &mut bad[2] {
            centre.x = f64::NAN;
        }
        assert!(solve_generalized(&bad).is_empty());
        let mut bad = sample;
        if let RigFeature::Line { endpoints, .. } = &mut bad[2] {
            endpoints[1] = endpoints[0];
        }
        assert!(solve_generalized(&bad).is_empty());
        // Two points on parallel rays: the depths are not linear in R this way.
        let mut bad = sample;
        let first = match bad[0] {
            RigFeature::Point { ray, .. } => ray.direction,
            _ => unreachable!(),
        };
        if let RigFeature::Point { ray, .. } = &mut bad[1] {
            ray.direction = first;
        }
        assert!(solve_generalized(&bad).is_empty());
    }
}
