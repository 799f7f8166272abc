//! A bound on the distance of the camera from the object over a sublevel set of the reprojection
//! cost, from the directions in which the object is seen. The pose certificate
//! ([`super::certificate`]) starts from it where the points give no depth bounds (lines alone, or
//! fewer than two points seen far enough apart).
//!
//! Let `c` be a pivot of the object (any fixed object point), `P = R c + t` the pivot in the camera
//! frame, `D = ‖P‖` and `u = P / D`. Every observation `k` is at most `δₖ` from the pivot, and on the
//! sublevel set it is seen close to where it was observed; both facts constrain `u` for a given `D`
//! (each [`Sight`] holds the proof of its own), as `hₖ(u) ≤ δₖ / D` for a function `hₖ` that is
//! `Lₖ`-Lipschitz in `u` (chord distance on the unit sphere). So at the true direction
//! `F(u) = maxₖ hₖ(u)₊ / δₖ ≤ 1 / D` where `D > maxₖ δₖ`, and
//! `D ≤ max(maxₖ δₖ, 1 / min_u F)`. The least value of `F` over the sphere is bounded from below
//! on the shared branch and bound (`global::branch_and_bound`), over the cells of a cube map: on a
//! cell whose centre `u_c` is within the angle `ρ` of its corners (so within the chord `ρ` of all its
//! directions), `F ≥ maxₖ (hₖ(u_c) − Lₖ ρ)₊ / δₖ`. Where the directions of all the observations
//! can nearly meet (concurrent image lines, one point), `min F` is 0 and there is no bound.

use crate::global::branch_and_bound::{
    branch_and_bound, Bound, BoundingOracle, BranchAndBoundOptions, Corner, Region, SubRegions,
};
use nalgebra::{Matrix2, Vector2, Vector3};

/// What one observation says about the direction `u` of the pivot: `h(u) ≤ offset / D`.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Sight {
    /// A point seen along the unit ray `direction`, within the angle `tolerance` of it on the
    /// sublevel set, `offset` from the pivot. Its camera-frame position is within `offset` of
    /// `P = D u`, hence within the angle `asin(offset / D)` of `u` (for `D > offset`), and
    /// `angle(u, b) ≤ tolerance + asin(offset / D)`: `h(u) = sin(min(π/2, (angle(u, b) − tolerance)₊))`,
    /// 1-Lipschitz in the angle, so in the chord.
    Ray {
        direction: Vector3<f64>,
        tolerance: f64,
        offset: f64,
    },
    /// A 3-D line passing `offset` from the pivot, seen as the segment with unit endpoint rays `ê₁`,
    /// `ê₂`, each of which is within the angle `asin(sₖ)` of the true interpretation plane (unit
    /// normal `m̂`) on the sublevel set. The plane holds the line, so `P` is within `offset` of it:
    /// `|u · m̂| ≤ offset / D`. With `l̂` the unit normal of the observed plane through `ê₁`, `ê₂`,
    /// `m̂ = κ l̂ + v` with `v` in that plane, `vᵀêₖ = m̂ᵀêₖ`, so `|vᵀêₖ| ≤ sₖ` and, with the Gram
    /// matrix `Γ` of `ê₁, ê₂` and `z(u) = Γ⁻¹ [ê₁ ê₂]ᵀ u`, `u · v = z(u) · [ê₁ ê₂]ᵀ v`, so
    /// `|u · v| ≤ |z₁| s₁ + |z₂| s₂`, and `‖v‖² ≤ (s₁² + s₂²) / λ_min(Γ)`, so `|κ| ≥ √(1 − ‖v‖²)`:
    /// `h(u) = |κ|_min |u · l̂| − |z₁(u)| s₁ − |z₂(u)| s₂ ≤ |u · m̂|`, Lipschitz with
    /// `|κ|_min + ‖s‖ / √λ_min(Γ)`.
    Plane {
        ends: [Vector3<f64>; 2],
        sines: [f64; 2],
        offset: f64,
    },
}

/// A [`Sight`] prepared for the search: `h(u)` and its Lipschitz constant.
struct Prepared {
    kind: Kind,
    offset: f64,
    lipschitz: f64,
}

enum Kind {
    Ray {
        direction: Vector3<f64>,
        tolerance: f64,
    },
    Plane {
        normal: Vector3<f64>,
        kappa: f64,
        dual: [Vector3<f64>; 2],
        sines: [f64; 2],
    },
}

impl Prepared {
    /// `None` for a sight that says nothing (a degenerate segment, or tolerances too wide).
    fn of(sight: &Sight) -> Option<Prepared> {
        match *sight {
            Sight::Ray {
                direction,
                tolerance,
                offset,
            } => Some(Prepared {
                kind: Kind::Ray {
                    direction: direction.normalize(),
                    tolerance,
                },
                offset,
                lipschitz: 1.0,
            }),
            Sight::Plane { ends, sines, offset } => {
                let e = ends.map(|e| e.normalize());
                let normal = e[0].cross(&e[1]);
                let cos = e[0].dot(&e[1]);
                let gram = Matrix2::new(1.0, cos, cos, 1.0);
                let lambda_min = 1.0 - cos.abs();
                let inverse = gram.try_inverse()?;
                let v2 = (sines[0] * sines[0] + sines[1] * sines[1]) / lambda_min;
                if !(normal.norm() > 0.0 && lambda_min > 0.0 && v2 < 1.0) {
                    return None;
                }
                // z(u) = Γ⁻¹ [ê₁ ê₂]ᵀ u: zₖ(u) = dualₖ · u.
                let dual = [
                    e[0] * inverse[(0, 0)] + e[1] * inverse[(0, 1)],
                    e[0] * inverse[(1, 0)] + e[1] * inverse[(1, 1)],
                ];
                let kappa = (1.0 - v2).sqrt();
                let s_norm = Vector2::new(sines[0], sines[1]).norm();
                Some(Prepared {
                    kind: Kind::Plane {
                        normal: normal.normalize(),
                        kappa,
                        dual,
                        sines,
                    },
                    offset,
                    lipschitz: kappa + s_norm / lambda_min.sqrt(),
                })
            }
        }
    }

    /// `h(u)` for a unit `u`.
    fn h(&self, u: &Vector3<f64>) -> f64 {
        match &self.kind {
            Kind::Ray { direction, tolerance } => {
                let angle = u.cross(direction).norm().atan2(u.dot(direction));
                (angle - tolerance).clamp(0.0, std::f64::consts::FRAC_PI_2).sin()
            }
            Kind::Plane {
                normal,
                kappa,
                dual,
                sines,
            } => kappa * u.dot(normal).abs() - dual[0].dot(u).abs() * sines[0] - dual[1].dot(u).abs() * sines[1],
        }
    }

    /// `h₊ / δ` for a value `h` (`+∞` where `δ = 0` and `h > 0`).
    fn ratio(&self, h: f64) -> f64 {
        if h <= 0.0 {
            0.0
        } else {
            h / self.offset
        }
    }
}

/// Relative gap at which the search for `min F` stops: the distance bound is then within 10 % of
/// the best this argument gives.
const GAP: f64 = 0.1;
/// Cells the search bounds at most (each costs one pass over the observations).
const MAX_CELLS: usize = 4000;

/// The sphere search: the box `[0, 6] × [−1, 1]²` holds the six faces of the cube, face
/// `k = ⌊x⌋` spanning `[k, k + 1] × [−1, 1]²`'s first coordinate as `a ∈ [−1, 1]`.
struct SphereSearch {
    sights: Vec<Prepared>,
}

/// The unit direction of the cube-map coordinates `(x, b)` (face `⌊x⌋`, clamped to 5).
fn direction(face: usize, a: f64, b: f64) -> Vector3<f64> {
    let sign = if face % 2 == 0 { 1.0 } else { -1.0 };
    let axis = face / 2;
    let mut p = Vector3::zeros();
    p[axis] = sign;
    p[(axis + 1) % 3] = a;
    p[(axis + 2) % 3] = b;
    p.normalize()
}

impl SphereSearch {
    fn value(&self, u: &Vector3<f64>, radius: f64) -> f64 {
        self.sights
            .iter()
            .map(|s| s.ratio(s.h(u) - s.lipschitz * radius))
            .fold(0.0, f64::max)
    }
}

impl BoundingOracle for SphereSearch {
    type Candidate = ();
    type Inherited = ();

    fn bound(&mut self, region: &Region) -> Bound<()> {
        let face = (region.lower[0].floor() as usize).min(5);
        if region.upper[0] > (face + 1) as f64 {
            // A box over several faces: no bound yet (it is split at a face boundary first), and the
            // value at its first face's centre.
            return Bound::Bounded {
                lower: 0.0,
                relaxed_minimizer: None,
                candidate: Some((self.value(&direction(face, 0.0, 0.0), 0.0), ())),
                solver_iterations: 0,
            };
        }
        let a = |x: f64| 2.0 * (x - face as f64) - 1.0;
        let (a0, a1, b0, b1) = (a(region.lower[0]), a(region.upper[0]), region.lower[1], region.upper[1]);
        let centre = direction(face, 0.5 * (a0 + a1), 0.5 * (b0 + b1));
        // Every direction of the cell is within the largest chord to a corner (the cell is a convex
        // spherical quadrilateral within a hemisphere around its centre); raised for rounding.
        let radius = [(a0, b0), (a0, b1), (a1, b0), (a1, b1)]
            .iter()
            .map(|&(a, b)| (direction(face, a, b) - centre).norm())
            .fold(0.0, f64::max)
            * (1.0 + 1e-9)
            + 1e-12;
        Bound::Bounded {
            lower: self.value(&centre, radius),
            relaxed_minimizer: None,
            candidate: Some((self.value(&centre, 0.0), ())),
            solver_iterations: 0,
        }
    }

    fn subdivide(&self, region: &Region, _relaxed_minimizer: Option<&[f64]>) -> SubRegions {
        let (lo, hi) = (&region.lower, &region.upper);
        let corner = |x: f64, y: f64| Corner::from_buf_and_len([x, y, 0.0, 0.0], 2);
        if hi[0] - lo[0] > 1.0 {
            // Several faces: cut at a face boundary.
            let cut = (0.5 * (lo[0] + hi[0])).round();
            return SubRegions::from_iter([
                Region::new(corner(lo[0], lo[1]), corner(cut, hi[1])),
                Region::new(corner(cut, lo[1]), corner(hi[0], hi[1])),
            ]);
        }
        let (mx, my) = (0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]));
        SubRegions::from_iter([
            Region::new(corner(lo[0], lo[1]), corner(mx, my)),
            Region::new(corner(mx, lo[1]), corner(hi[0], my)),
            Region::new(corner(lo[0], my), corner(mx, hi[1])),
            Region::new(corner(mx, my), corner(hi[0], hi[1])),
        ])
    }
}

/// An upper bound on the pivot's distance `D` from the camera for every pose on which each sight
/// holds (module documentation), or `None` when the sights do not bound it.
pub(crate) fn distance_bound(sights: &[Sight]) -> Option<f64> {
    let prepared: Vec<Prepared> = sights.iter().filter_map(Prepared::of).collect();
    let largest_offset = prepared.iter().map(|s| s.offset).fold(0.0, f64::max);
    let mut search = SphereSearch { sights: prepared };
    let root = Region::new(vec![0.0, -1.0], vec![6.0, 1.0]);
    let opts = BranchAndBoundOptions {
        max_relative_gap: GAP,
        max_nodes: MAX_CELLS,
        trivial_lower_bound: 0.0,
    };
    let least = branch_and_bound(&mut search, root, None, &opts).lower_bound;
    (least > 0.0 && least.is_finite()).then(|| largest_offset.max(1.0 / least))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Three lines through the corners of a triangle around the pivot: the bound holds the true
    /// distance, and a cluster of concurrent lines gives none.
    #[test]
    fn lines_around_the_pivot_bound_the_distance() {
        let pivot = Vector3::new(0.1, -0.2, 8.0);
        let sight = |a: Vector3<f64>, b: Vector3<f64>| {
            let (a, b) = (pivot + a, pivot + b);
            let offset = (a - pivot).cross(&(b - a)).norm() / (b - a).norm();
            Sight::Plane {
                ends: [a, b],
                sines: [1e-4, 1e-4],
                offset,
            }
        };
        let triangle = [
            sight(Vector3::new(-1.0, 0.5, 0.0), Vector3::new(1.0, 0.6, 0.2)),
            sight(Vector3::new(1.0, 0.6, 0.0), Vector3::new(0.0, -1.0, 0.3)),
            sight(Vector3::new(0.0, -1.0, 0.0), Vector3::new(-1.0, 0.5, -0.2)),
        ];
        let bound = distance_bound(&triangle).expect("a triangle bounds the distance");
        assert!(bound >= pivot.norm(), "{bound} < {}", pivot.norm());
        assert!(bound < 100.0 * pivot.norm(), "{bound}");
        let star = [
            sight(Vector3::new(-1.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0)),
            sight(Vector3::new(0.0, -1.0, 0.0), Vector3::new(0.0, 1.0, 0.0)),
        ];
        assert!(distance_bound(&star).is_none());
    }
}

#[cfg(test)]
mod properties {
    use super::*;
    use crate::rng::Rng;

    /// A unit vector within the angle `angle` of the unit `v` (at exactly that angle).
    fn tilted(v: &Vector3<f64>, angle: f64, rng: &mut Rng) -> Vector3<f64> {
        let side = v.cross(&rng.unit_vector3()).normalize();
        (v * angle.cos() + side * angle.sin()).normalize()
    }

    /// Each sight's `h` against its claim, with tolerances far above a pixel's so that every term
    /// counts: for a ray, `h(u) ≤ sin(angle(u, x))` for every `x` within the tolerance of the ray;
    /// for a plane, `h(u) ≤ |u · m̂|` for every plane whose normal `m̂` is within `asin(sₖ)` of
    /// perpendicular to each end (normals found by sampling, then a hill climb on `h(u) − |u · m̂|`);
    /// and `|h(u) − h(u')| ≤ L ‖u − u'‖` at random nearby pairs.
    #[test]
    fn each_sight_is_below_its_claim_and_lipschitz() {
        let mut rng = Rng::new(41);
        let (mut checked, mut tight) = (0usize, 0usize);
        for _ in 0..300 {
            let ray = rng.uniform() < 0.3;
            let sight = if ray {
                Sight::Ray {
                    direction: rng.unit_vector3(),
                    tolerance: rng.uniform_in(0.0, 0.3),
                    offset: 1.0,
                }
            } else {
                let e0 = rng.unit_vector3();
                let e1 = tilted(&e0, rng.uniform_in(0.05, 1.5), &mut rng);
                Sight::Plane {
                    ends: [e0 * rng.uniform_in(0.5, 2.0), e1],
                    sines: [rng.uniform_in(0.0, 0.1), rng.uniform_in(0.0, 0.1)],
                    offset: 1.0,
                }
            };
            let Some(prepared) = Prepared::of(&sight) else {
                continue;
            };
            for _ in 0..20 {
                let u = rng.unit_vector3();
                let near = tilted(&u, rng.uniform_in(0.0, 0.2), &mut rng);
                let slope = (prepared.h(&u) - prepared.h(&near)).abs() / (u - near).norm();
                assert!(
                    slope <= prepared.lipschitz * (1.0 + 1e-9),
                    "slope {slope} > {}",
                    prepared.lipschitz
                );
                // The claim's side: the largest h(u) − claim over the admissible truths.
                let excess = |truth: &Vector3<f64>| match sight {
                    Sight::Ray {
                        direction, tolerance, ..
                    } => {
                        // The worst truth: the direction within the tolerance of the ray nearest u,
                        // on the great circle from the ray to u (`truth` unused).
                        let _ = truth;
                        let b = direction.normalize();
                        let apart = u.cross(&b).norm().atan2(u.dot(&b));
                        let angle = (apart - tolerance).max(0.0);
                        prepared.h(&u) - angle.min(std::f64::consts::FRAC_PI_2).sin()
                    }
                    Sight::Plane { ends, sines, .. } => {
                        let m = truth.normalize();
                        let admissible = ends.iter().zip(sines).all(|(e, s)| m.dot(&e.normalize()).abs() <= s);
                        if admissible {
                            prepared.h(&u) - u.dot(&m).abs()
                        } else {
                            f64::NEG_INFINITY
                        }
                    }
                };
                let start = match sight {
                    Sight::Ray { .. } => Vector3::new(1.0, 0.0, 0.0),
                    Sight::Plane { ends, .. } => ends[0].cross(&ends[1]).normalize(),
                };
                let mut best = (start, excess(&start));
                for step in 0..300 {
                    let scale = 0.05 * 0.99f64.powi(step);
                    let candidate = (best.0 + rng.unit_vector3() * scale).normalize();
                    let value = excess(&candidate);
                    if value > best.1 {
                        best = (candidate, value);
                    }
                }
                assert!(best.1 <= 1e-12, "{sight:?} at {u:?}: h exceeds its claim by {}", best.1);
                if best.1 > -1e-3 {
                    tight += 1;
                }
                checked += 1;
            }
        }
        assert!(
            checked > 3000 && tight > 100,
            "{checked} checked, {tight} within 1e-3 of the claim"
        );
    }

    /// The distance bound against scenes built here: a pivot `D` from the camera, points and lines
    /// around it, each observed at the edge of its tolerance (rays tilted by exactly their
    /// tolerance, segment ends on a plane tilted by the largest angle the sines allow); the bound is at
    /// least `D` (and exists on most scenes).
    #[test]
    fn the_distance_bound_holds_with_observations_at_their_tolerance() {
        let mut rng = Rng::new(42);
        let mut bounded = 0;
        for case in 0..200 {
            let distance = 10f64.powf(rng.uniform_in(0.0, 2.0));
            let u = Vector3::new(rng.uniform_in(-0.3, 0.3), rng.uniform_in(-0.3, 0.3), 1.0).normalize();
            let pivot = u * distance;
            let size = distance * rng.uniform_in(0.05, 0.5);
            let tolerance = 10f64.powf(rng.uniform_in(-4.0, -1.5));
            let mut sights = Vec::new();
            for _ in 0..(case % 3) {
                let x = pivot + rng.unit_vector3() * size * rng.uniform();
                sights.push(Sight::Ray {
                    direction: tilted(&x.normalize(), tolerance, &mut rng),
                    tolerance,
                    offset: (x - pivot).norm(),
                });
            }
            for _ in 0..(3 + case % 5) {
                let a = pivot + rng.unit_vector3() * size * rng.uniform();
                let b = pivot + rng.unit_vector3() * size * rng.uniform();
                let d = b - a;
                let offset = (a - pivot).cross(&d).norm() / d.norm();
                // The observed ends: the true ends' rays turned about the segment's mid-ray so that
                // the observed plane is as far from the true one as the sines let it be.
                let normal = a.cross(&b).normalize();
                let (ea, eb) = (a.normalize(), b.normalize());
                let s = tolerance;
                let tilt = |e: Vector3<f64>, sign: f64| (e + normal * (sign * s)).normalize();
                sights.push(Sight::Plane {
                    ends: [tilt(ea, 1.0), tilt(eb, -1.0)],
                    sines: [s * 1.001, s * 1.001],
                    offset,
                });
            }
            if let Some(bound) = distance_bound(&sights) {
                assert!(
                    bound >= distance * (1.0 - 1e-9),
                    "case {case}: bound {bound} below the true distance {distance}"
                );
                bounded += 1;
            }
        }
        assert!(bounded > 100, "only {bounded} of 200 scenes bounded");
    }
}
