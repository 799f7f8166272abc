//! Test helpers shared by the tests of the solvers with lines: seeded noise-free samples, the residuals
//! of the six constraints, the conditioning of a sample at its true pose, and the checks every returned
//! pose must pass.

use super::{Feature, Pose};
use crate::rng::Rng;
use nalgebra::{Matrix3, SMatrix, Vector3};

/// Machine epsilon.
pub const EPS: f64 = f64::EPSILON;

/// Accuracy required of the recovered pose: `‖R − R*‖_F` and `‖t − t*‖ / scene scale`.
pub const POSE_TOLERANCE: f64 = 1e-8;

/// Conditioning up to which every instance must meet [`POSE_TOLERANCE`]: the returned poses solve the
/// constraints to rounding (a few ε), so their error is about `κ ε` times a modest constant, with `κ`
/// the condition number of the six constraints' Jacobian at the truth ([`Sample::conditioning`]).
/// `κ ≤ 1e5` keeps `κ ε ≤ 2.2e-11`, 450 times below the tolerance.
pub const KAPPA_LIMIT: f64 = 1e5;

/// The constant `C` of the bound `error ≤ C κ ε` required of every instance, however ill-conditioned.
pub const CONDITIONED_ERROR: f64 = 1e3;

/// A sample of three features and the pose that generated it.
#[derive(Debug, Clone)]
pub struct Sample {
    pub features: [Feature; 3],
    pub rotation: Matrix3<f64>,
    pub translation: Vector3<f64>,
}

/// A random camera-frame point with depth in [1, 6] inside the frustum `|x|, |y| ≤ half_width z`.
pub fn camera_point(rng: &mut Rng, half_width: f64) -> Vector3<f64> {
    let z = rng.uniform_in(1.0, 6.0);
    Vector3::new(
        z * rng.uniform_in(-half_width, half_width),
        z * rng.uniform_in(-half_width, half_width),
        z,
    )
}

impl Sample {
    /// A sample with the given camera-frame geometry: `points` (camera frame) and `lines` (two camera-
    /// frame points each), the features in the order `kinds` (`true` = point), under `(rotation,
    /// translation)`. Object points of a line are two other points of it, so they differ from the ones
    /// the normal was made from.
    pub fn from_camera_frame(
        rng: &mut Rng,
        kinds: [bool; 3],
        points: &[Vector3<f64>],
        lines: &[[Vector3<f64>; 2]],
        rotation: Matrix3<f64>,
        translation: Vector3<f64>,
    ) -> Sample {
        let to_world = |c: &Vector3<f64>| rotation.transpose() * (c - translation);
        let (mut next_point, mut next_line) = (points.iter(), lines.iter());
        let features = kinds.map(|is_point| {
            if is_point {
                let c = next_point.next().expect("enough points");
                Feature::Point {
                    bearing: *c,
                    point: to_world(c),
                }
            } else {
                let [a, b] = next_line.next().expect("enough lines");
                let (s, u) = (rng.uniform_in(-0.5, 0.4), rng.uniform_in(0.6, 1.5));
                Feature::Line {
                    normal: a.cross(b),
                    endpoints: [to_world(&(a + (b - a) * s)), to_world(&(a + (b - a) * u))],
                }
            }
        });
        Sample {
            features,
            rotation,
            translation,
        }
    }

    /// A random sample of the mix `kinds`: features in the frustum of half-width `half_width`, a
    /// uniform rotation, a translation of length up to 4.
    pub fn random(rng: &mut Rng, kinds: [bool; 3], half_width: f64) -> Sample {
        let points: Vec<_> = (0..3).map(|_| camera_point(rng, half_width)).collect();
        let lines: Vec<_> = (0..3)
            .map(|_| [camera_point(rng, half_width), camera_point(rng, half_width)])
            .collect();
        let rotation = rng.rotation();
        let translation = rng.unit_vector3() * rng.uniform_in(0.0, 4.0);
        Sample::from_camera_frame(rng, kinds, &points, &lines, rotation, translation)
    }

    /// The scene scale of translation errors: the largest distance of an object point from either
    /// origin.
    pub fn scale(&self) -> f64 {
        let mut scale: f64 = 0.0;
        for world in self.world_points() {
            let cam = self.rotation * world + self.translation;
            scale = scale.max(world.norm()).max(cam.norm());
        }
        scale
    }

    fn world_points(&self) -> Vec<Vector3<f64>> {
        self.features
            .iter()
            .flat_map(|f| match f {
                Feature::Point { point, .. } => vec![*point],
                Feature::Line { endpoints, .. } => endpoints.to_vec(),
            })
            .collect()
    }

    /// The larger of `‖R − R*‖_F` and `‖t − t*‖ / scale` for the closest of `poses` (∞ if none).
    pub fn error(&self, poses: &[Pose]) -> f64 {
        let scale = self.scale();
        poses
            .iter()
            .map(
                |Pose {
                     rotation: r,
                     translation: t,
                 }| (r - self.rotation).norm().max((t - self.translation).norm() / scale),
            )
            .fold(f64::INFINITY, f64::min)
    }

    /// `κ`: the condition number of the Jacobian of the six [`residuals`] at the true pose, with
    /// respect to a left rotation increment (radians) and the translation divided by [`Sample::scale`].
    pub fn conditioning(&self) -> f64 {
        let scale = self.scale();
        let mut jac = SMatrix::<f64, 6, 6>::zeros();
        let mut row = 0;
        let mut push = |direction: Vector3<f64>, world: &Vector3<f64>, jac: &mut SMatrix<f64, 6, 6>| {
            // d(uᵀ x / ‖x‖) for x = R X + t, R ← (I + [δ]×) R, t ← t + scale dτ, to first order at uᵀx = 0.
            let rotated = self.rotation * world;
            let norm = (rotated + self.translation).norm();
            let rot = rotated.cross(&direction) / norm;
            let trans = direction * scale / norm;
            for k in 0..3 {
                jac[(row, k)] = rot[k];
                jac[(row, k + 3)] = trans[k];
            }
            row += 1;
        };
        for feature in &self.features {
            match feature {
                Feature::Point { bearing, point } => {
                    let (y, u) = bearing_frame(bearing);
                    push(u, point, &mut jac);
                    push(y.cross(&u), point, &mut jac);
                }
                Feature::Line { normal, endpoints } => {
                    for p in endpoints {
                        push(normal.normalize(), p, &mut jac);
                    }
                }
            }
        }
        let singular = jac.singular_values();
        singular.max() / singular.min()
    }
}

/// The six constraint residuals of a pose, each a sine: for a point, `‖y × x‖ / ‖x‖` (two components
/// folded into one norm here); for a line, `n · x / max(‖x‖, D)` for each object point `x` in the
/// camera frame, with `D` the largest distance between the sample's world points (so that a pose
/// placing an object point next to the camera centre is judged by the object's size, not by the
/// vanishing distance). Returns the largest absolute residual and whether every point is in front
/// (`y · x > 0`).
pub fn residuals(
    features: &[Feature; 3],
    Pose {
        rotation: r,
        translation: t,
    }: &Pose,
) -> (f64, bool) {
    let world: Vec<Vector3<f64>> = features
        .iter()
        .flat_map(|f| match f {
            Feature::Point { point, .. } => vec![*point],
            Feature::Line { endpoints, .. } => endpoints.to_vec(),
        })
        .collect();
    let extent = world
        .iter()
        .flat_map(|p| world.iter().map(move |q| (p - q).norm()))
        .fold(0.0, f64::max);
    let (mut worst, mut in_front): (f64, bool) = (0.0, true);
    for feature in features {
        match feature {
            Feature::Point { bearing, point } => {
                let x = r * point + t;
                let y = bearing.normalize();
                worst = worst.max(y.cross(&x).norm() / x.norm());
                in_front &= y.dot(&x) > 0.0;
            }
            Feature::Line { normal, endpoints } => {
                for p in endpoints {
                    let x = r * p + t;
                    worst = worst.max((normal.normalize().dot(&x) / x.norm().max(extent)).abs());
                }
            }
        }
    }
    (worst, in_front)
}

/// Every pose is finite, a rotation to rounding, satisfies the six constraints within `angle`, and
/// puts every point in front of the camera; at most `max` poses.
pub fn assert_valid(poses: &[Pose], features: &[Feature; 3], angle: f64, max: usize, what: &str) {
    assert!(poses.len() <= max, "{what}: {} solutions", poses.len());
    for pose in poses {
        let Pose {
            rotation: r,
            translation: t,
        } = pose;
        assert!(
            r.iter().chain(t.iter()).all(|v| v.is_finite()),
            "{what}: non-finite pose"
        );
        // Products of exact rotations (Rodrigues) and orthonormal frames: a few ε per entry.
        let orthogonality = (r.transpose() * r - Matrix3::identity()).amax();
        assert!(
            orthogonality < 1e-14 && (r.determinant() - 1.0).abs() < 1e-14,
            "{what}: R not a rotation"
        );
        let (worst, in_front) = residuals(features, pose);
        assert!(in_front, "{what}: a point behind the camera");
        assert!(worst <= angle, "{what}: a constraint off by {worst:e}");
    }
}

/// What [`check_random_draws`] saw.
#[derive(Debug)]
pub struct DrawSummary {
    /// Draws with the truth within [`POSE_TOLERANCE`].
    pub found: usize,
    /// Draws with `κ > KAPPA_LIMIT`.
    pub ill_conditioned: usize,
    /// Draws with 0, 1, ..., 8 solutions.
    pub counts: [usize; 9],
    /// The largest constraint residual of any returned pose.
    pub worst_residual: f64,
}

/// Which random samples [`check_random_draws`] solves: `draws` of them from `seed`, in a field of view
/// of `±half_width`.
#[derive(Debug, Clone, Copy)]
pub struct Draws {
    /// The seed of the draws.
    pub seed: u64,
    /// How many samples.
    pub draws: usize,
    /// The half-width of the field of view ([`Sample::random`]).
    pub half_width: f64,
}

/// Solves the random samples `draws` of the mix `kinds` with `solver`, asserting that every returned
/// pose is valid (constraints within `angle`, at most `max` poses) and that the truth is among them to
/// `C κ ε`, and to [`POSE_TOLERANCE`] when `κ ≤ KAPPA_LIMIT`.
pub fn check_random_draws(
    name: &str,
    solver: impl Fn(&[Feature; 3]) -> Vec<Pose>,
    kinds: [bool; 3],
    draws: Draws,
    angle: f64,
    max: usize,
) -> DrawSummary {
    let Draws {
        seed,
        draws,
        half_width,
    } = draws;
    let mut rng = Rng::new(seed);
    let mut summary = DrawSummary {
        found: 0,
        ill_conditioned: 0,
        counts: [0; 9],
        worst_residual: 0.0,
    };
    for draw in 0..draws {
        let sample = Sample::random(&mut rng, kinds, half_width);
        let poses = solver(&sample.features);
        let what = format!("{name}, seed {seed}, draw {draw}");
        assert_valid(&poses, &sample.features, angle, max, &what);
        for pose in &poses {
            summary.worst_residual = summary.worst_residual.max(residuals(&sample.features, pose).0);
        }
        summary.counts[poses.len().min(8)] += 1;
        let (error, kappa) = (sample.error(&poses), sample.conditioning());
        if error <= POSE_TOLERANCE {
            summary.found += 1;
        }
        if kappa > KAPPA_LIMIT {
            summary.ill_conditioned += 1;
        } else {
            assert!(error <= POSE_TOLERANCE, "{what}: error {error:e} with κ = {kappa:e}");
        }
        assert!(
            error <= CONDITIONED_ERROR * kappa * EPS,
            "{what}: error {error:e} with κ = {kappa:e}"
        );
    }
    println!(
        "{name}, field of view ±{half_width}: true pose within {POSE_TOLERANCE:e} in {}/{draws} draws; {} with κ > \
         {KAPPA_LIMIT:e}; draws with 0..8 solutions: {:?}; largest constraint residual {:e}",
        summary.found, summary.ill_conditioned, summary.counts, summary.worst_residual
    );
    summary
}

/// `solve` returns no pose when any bearing or normal, or any object point, of `sample` holds NaN or ±inf.
pub fn assert_non_finite_gives_no_pose(solve: fn(&[Feature; 3]) -> Vec<Pose>, sample: &Sample) {
    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        for i in 0..3 {
            let mut f = sample.features;
            match &mut f[i] {
                Feature::Point { bearing, .. } => bearing.x = bad,
                Feature::Line { normal, .. } => normal.z = bad,
            }
            assert!(solve(&f).is_empty(), "{bad} in feature {i}");
            let mut f = sample.features;
            match &mut f[i] {
                Feature::Point { point, .. } => point.y = bad,
                Feature::Line { endpoints, .. } => endpoints[0].x = bad,
            }
            assert!(solve(&f).is_empty(), "{bad} in object {i}");
        }
    }
}

/// Huge and tiny scenes (object points scaled by 1e∓150): `solve` returns as many poses as on `sample`
/// itself, each valid ([`assert_valid`] with at most `max` poses).
pub fn assert_scale_invariant(solve: fn(&[Feature; 3]) -> Vec<Pose>, sample: &Sample, max: usize) {
    let expected = solve(&sample.features).len();
    for scale in [1e-150, 1e150] {
        let scaled = sample.features.map(|f| match f {
            Feature::Point { bearing, point } => Feature::Point {
                bearing,
                point: point * scale,
            },
            Feature::Line { normal, endpoints } => Feature::Line {
                normal,
                endpoints: endpoints.map(|p| p * scale),
            },
        });
        let poses = solve(&scaled);
        assert_eq!(poses.len(), expected, "scale {scale:e}");
        assert_valid(&poses, &scaled, 1e-9, max, &format!("scale {scale:e}"));
    }
}

/// [`assert_multistart_finds_nothing_more`] on 100 random samples of the mix `kinds` (40 starts each),
/// solved by `solve`; requires at least 100 distinct converged solutions to have been checked, so that
/// the search was not vacuous.
pub fn check_multistart_completeness(name: &str, solve: fn(&[Feature; 3]) -> Vec<Pose>, kinds: [bool; 3], seed: u64) {
    let mut rng = Rng::new(seed);
    let mut checked = 0;
    for draw in 0..100 {
        let sample = Sample::random(&mut rng, kinds, 1.0);
        let poses = solve(&sample.features);
        checked += assert_multistart_finds_nothing_more(&sample, &poses, &mut rng, 40, &format!("draw {draw}"));
    }
    println!("{name} multistart: {checked} distinct solutions checked");
    assert!(checked >= 100, "{checked}");
}

/// An independent search for solutions: Gauss-Newton (square, 6x6) on the six constraints from
/// `starts` random poses near the scene; every converged solution (residuals ≤ 1e-13, points in front,
/// well conditioned) must be among `poses` to [`POSE_TOLERANCE`]. Returns how many distinct converged
/// solutions were checked.
pub fn assert_multistart_finds_nothing_more(
    sample: &Sample,
    poses: &[Pose],
    rng: &mut Rng,
    starts: usize,
    what: &str,
) -> usize {
    let mut seen: Vec<Pose> = Vec::new();
    for _ in 0..starts {
        let mut r = rng.rotation();
        let mut t = sample.translation + rng.unit_vector3() * rng.uniform_in(0.0, 2.0 * sample.scale());
        for _ in 0..60 {
            let (res, jac) = constraint_system(&sample.features, &Pose::new(r, t));
            let Some(step) = jac.lu().solve(&(-res)) else { break };
            r = nalgebra::Rotation3::new(Vector3::new(step[0], step[1], step[2])).into_inner() * r;
            t += Vector3::new(step[3], step[4], step[5]);
            if !r.iter().chain(t.iter()).all(|v| v.is_finite()) {
                break;
            }
        }
        let candidate = Pose::new(r, t);
        if !r.iter().chain(t.iter()).all(|v| v.is_finite()) {
            continue;
        }
        let (worst, in_front) = residuals(&sample.features, &candidate);
        if worst > 1e-13
            || !in_front
            || seen.iter().any(
                |Pose {
                     rotation: s,
                     translation: u,
                 }| (s - r).norm() + (u - t).norm() < 1e-6,
            )
        {
            continue;
        }
        seen.push(candidate);
        let as_truth = Sample {
            rotation: r,
            translation: t,
            ..sample.clone()
        };
        if as_truth.conditioning() > KAPPA_LIMIT {
            continue;
        }
        let error = as_truth.error(poses);
        assert!(
            error <= POSE_TOLERANCE,
            "{what}: multistart found a solution the solver missed ({error:e})"
        );
    }
    seen.len()
}

/// The six residuals (`uᵀx/‖x‖`-free, plain `uᵀx` for speed of convergence: points `y × x` projected
/// on two directions orthogonal to `y`, lines `n · x`) and their Jacobian in a left rotation increment
/// and the translation.
fn constraint_system(
    features: &[Feature; 3],
    Pose {
        rotation: r,
        translation: t,
    }: &Pose,
) -> (SMatrix<f64, 6, 1>, SMatrix<f64, 6, 6>) {
    let mut res = SMatrix::<f64, 6, 1>::zeros();
    let mut jac = SMatrix::<f64, 6, 6>::zeros();
    let mut row = 0;
    let mut push =
        |u: Vector3<f64>, world: &Vector3<f64>, res: &mut SMatrix<f64, 6, 1>, jac: &mut SMatrix<f64, 6, 6>| {
            let rotated = r * world;
            res[row] = u.dot(&(rotated + t));
            let rot = rotated.cross(&u);
            for k in 0..3 {
                jac[(row, k)] = rot[k];
                jac[(row, k + 3)] = u[k];
            }
            row += 1;
        };
    for feature in features {
        match feature {
            Feature::Point { bearing, point } => {
                let (y, u) = bearing_frame(bearing);
                push(u, point, &mut res, &mut jac);
                push(y.cross(&u), point, &mut res, &mut jac);
            }
            Feature::Line { normal, endpoints } => {
                for p in endpoints {
                    push(normal.normalize(), p, &mut res, &mut jac);
                }
            }
        }
    }
    (res, jac)
}

/// The unit bearing `y` and a unit vector orthogonal to it.
fn bearing_frame(bearing: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let y = bearing.normalize();
    let axis = if y.x.abs() < 0.6 { 0 } else { 1 };
    (y, y.cross(&Vector3::ith(axis, 1.0)).normalize())
}

/// Offsets from an exact degeneracy swept by [`sweep_degeneracy`] (relative to the scene's size).
pub const OFFSETS: [f64; 8] = [1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14, 0.0];

/// Bound on the six constraints' residuals (sines) of poses returned near a degeneracy. The kernel
/// accepts rotations whose normalised constraints hold to 1e-9 (its `RESIDUAL_TOLERANCE`): next to a
/// double root Newton's method converges only linearly and stops there. A line's residual is that
/// times `‖R cᵢ‖ / ‖x‖`-like ratios of object size to depth, and the normalisation of the eliminated
/// constraints, both below 100 in these scenes (depths 1-6, objects within the frustum).
pub const NEAR_DEGENERATE_RESIDUAL: f64 = 1e-7;

/// Draws per offset in [`sweep_degeneracy`].
pub const SWEEP_DRAWS: usize = 100;

/// Near a degeneracy, built by `make(rng, offset)` at each of [`OFFSETS`]: every returned pose is
/// finite, a rotation, puts every point in front and satisfies the six constraints within `angle`
/// ([`NEAR_DEGENERATE_RESIDUAL`] is the bound to use); the
/// truth is found to [`POSE_TOLERANCE`] whenever `κ ≤ KAPPA_LIMIT` and `offset ≥ truth_down_to` (a
/// solver whose own elimination degenerates before the problem does passes a larger `truth_down_to`
/// and says why), and whenever poses are returned and
/// the truth is not among them to `C κ ε`, the draw is counted as lost (only allowed when `κ` exceeds
/// the limit). Prints one line per offset: how many draws returned no pose, how many found the truth,
/// how many lost it, and the largest `κ`. Returns, per offset, (no pose, found, lost).
pub fn sweep_degeneracy(
    name: &str,
    solver: impl Fn(&[Feature; 3]) -> Vec<Pose>,
    seed: u64,
    angle: f64,
    max: usize,
    truth_down_to: f64,
    mut make: impl FnMut(&mut Rng, f64) -> Sample,
) -> Vec<(usize, usize, usize)> {
    let mut rng = Rng::new(seed);
    let mut rows = Vec::new();
    for offset in OFFSETS {
        let (mut empty, mut found, mut lost, mut worst_kappa, mut worst_residual) = (0, 0, 0, 0.0f64, 0.0f64);
        for draw in 0..SWEEP_DRAWS {
            let sample = make(&mut rng, offset);
            let poses = solver(&sample.features);
            let what = format!("{name}, offset {offset:e}, draw {draw}");
            assert_valid(&poses, &sample.features, angle, max, &what);
            for pose in &poses {
                worst_residual = worst_residual.max(residuals(&sample.features, pose).0);
            }
            let (error, kappa) = (sample.error(&poses), sample.conditioning());
            let kappa = if kappa.is_finite() { kappa } else { f64::INFINITY };
            worst_kappa = worst_kappa.max(kappa);
            if kappa <= KAPPA_LIMIT && offset >= truth_down_to {
                assert!(error <= POSE_TOLERANCE, "{what}: error {error:e} with κ = {kappa:e}");
            }
            if poses.is_empty() {
                empty += 1;
            } else if error <= (CONDITIONED_ERROR * kappa * EPS).max(POSE_TOLERANCE) {
                found += 1;
            } else {
                lost += 1;
            }
        }
        println!(
            "{name}, offset {offset:e}: {empty} draws with no pose, truth within max(Cκε, 1e-8) in {found}, lost in \
             {lost}; largest κ {worst_kappa:.1e}; largest constraint residual {worst_residual:.1e}"
        );
        rows.push((empty, found, lost));
    }
    rows
}

/// A random unit vector orthogonal to `v`.
pub fn orthogonal_unit(rng: &mut Rng, v: &Vector3<f64>) -> Vector3<f64> {
    v.cross(&rng.unit_vector3()).normalize()
}

/// A random pose: uniform rotation, translation of length up to 4.
pub fn random_pose(rng: &mut Rng) -> (Matrix3<f64>, Vector3<f64>) {
    (rng.rotation(), rng.unit_vector3() * rng.uniform_in(0.0, 4.0))
}
