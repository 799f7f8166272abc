//! A chart of 3-D lines by their images in two views, in which every line cheaper than the local
//! line lies in a known ball (the domain of the Taylor certificate, [`super::taylor_search`]).
//!
//! **The chart.** Pick two views `a`, `b`. An image line of view `v` is described by its whitened
//! residual `zᵥ = Lᵥ rᵥ ∈ ℝ²` (eqs. 17-18, [`super::residual`]): in the frame of the observed line
//! the candidate line `(α, β, γ)` has `D (D (α, β)/γ − n) = rᵥ`, so with `γ = 1` its pixel
//! coordinates are `lᵥ(zᵥ) = (μ, 1 − μ·o)`, `μ = n/D + Lᵥ⁻¹ zᵥ / D²`, affine in `zᵥ`. The line
//! back-projects to the plane `πᵥ = Pᵥᵀ lᵥ(zᵥ)` through the camera centre, and the 3-D line of
//! `z = (z_a, z_b)` is the meet of the two planes, whose Plücker coordinates (eq. 3, dual form of
//! eq. 2: `l₁₂ : l₁₃ : l₁₄ : l₂₃ : l₄₂ : l₃₄ = l*₃₄ : l*₄₂ : l*₂₃ : l*₁₄ : l*₁₃ : l*₁₂` with
//! `L* = π_a π_bᵀ − π_b π_aᵀ`) are **bilinear** in `(z_a, z_b)`. So every view's residual
//! `Aᵥ𝓛/(cᵥᵀ𝓛)` (eqs. 6-7, 17-18) is a ratio of quadratic polynomials in `z`, and the residuals of
//! views `a` and `b` are `z_a` and `z_b` themselves (the meet lies in `π_a`, so its image in view `a`
//! is `l_a`).
//!
//! **What it covers.** Every 3-D line `𝓛` not through a camera centre has images `l_a`, `l_b` and, unless it
//! lies in an epipolar plane of the pair (then `π_a = π_b`), `𝓛 = π_a ∧ π_b`. A line whose cost of
//! eq. 19 is at most `U` has `‖z_a‖² + ‖z_b‖² ≤ U`: the ball `‖z‖ ≤ √U`. The pair is accepted only
//! when no image line of view `a` in the disc `‖z_a‖ ≤ √U` passes through the epipole `e_a = P_a C_b`
//! (`|l_a(z_a)·e_a| > 0` on the disc, an affine function), or the same with `a`, `b` swapped: then no
//! line of the ball lies in an epipolar plane (its image would pass through the epipole) or passes
//! through the other centre, and the chart covers **every line cheaper than `U`**.
//!
//! **Branching coordinates.** `z = z* + M w`, with `z*` the local line's chart point and `M = T⁻ᵀ`
//! for the Gauss-Newton information `Σ Jᵥᵀ Jᵥ = T Tᵀ` at `z*`: the cost's level sets near the local line
//! are nearly balls in `w` and its Hessian nearly `2I`.
//!
//! **The pair.** Among the accepted pairs, the one with least `tr((I_a + I_b)⁻¹ Σᵥ Iᵥ)`
//! (`Iᵥ = JᵥᵀJᵥ` at the local line): the two views that alone pin the line down best relative to
//! all of them, so that the ball is small on the scale of the other views' curvature.

use super::LineProblem;
use crate::geometry::plucker::{self, OrthonormalLine};
use crate::global::branch_and_bound::Region;
use crate::global::taylor_bound::{Quadratic, QuadraticRatio};
use crate::triangulation::conditioning::Similarity;
use crate::triangulation::fractional_residual::{self, FractionalResidual};
use crate::triangulation::line::residual::LINE_FRAME_DISTANCE;
use crate::triangulation::views;
use nalgebra::{Matrix3x4, Matrix4, Matrix4x2, SMatrix, Vector4, Vector6};

/// Views beyond which pair selection considers only the most informative ones (the selection
/// is quadratic in the number of views).
const MAX_PAIR_CANDIDATES: usize = 24;
/// The epipole must stay this factor beyond the disc of accepted image lines.
const EPIPOLE_MARGIN: f64 = 1.05;

/// The chart of the module docs in the conditioned frame `sim` of a problem.
pub(crate) struct TwoViewChart {
    /// The views `(a, b)`.
    pub pair: (usize, usize),
    /// The planes of the pair as affine maps of `w`: `π_a = p₀ + P w`, `π_b = q₀ + Q w`.
    planes: [(Vector4<f64>, Matrix4<f64>); 2],
    /// `z*` and `M` (module docs).
    centre: Vector4<f64>,
    map: Matrix4<f64>,
    /// Every view's whitened residual as a ratio of quadratics in `w` (views `a`, `b` exactly affine).
    pub views: Vec<QuadraticRatio<2, 4>>,
    /// Per view, `u(w) = Mᵀ P_𝓛 𝓛(w)` (`M` the left 3x3 of the conditioned camera), whose norm is
    /// `|det M| ‖d‖` times the distance from the camera centre to the line (`d` its direction).
    moments: Vec<[Quadratic<4>; 3]>,
    /// The direction `d(w)` of the line.
    direction: [Quadratic<4>; 3],
    /// Per view, `Mᵀ P_𝓛` (3x6): `u = Mᵀ P_𝓛 𝓛`.
    moment_rows: Vec<SMatrix<f64, 3, 6>>,
    /// Per view, `|det M|` times the least distance from the camera centre allowed in the domain
    /// ([`CENTRE_CLEARANCE`] times the local line's).
    clearance: Vec<f64>,
}

/// The domain leaves out lines closer to a camera centre than this fraction of the local line's
/// distance from it: near a centre the line's image in that view can be any line through one point, so
/// eq. 19 approaches values no physical line seen as a segment has (module docs).
pub const CENTRE_CLEARANCE: f64 = 0.01;

/// Where a box lies relative to the lines too close to a camera centre.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Clearance {
    /// Every line of the box is too close to some camera centre: outside the domain.
    Inside,
    /// Every line of the box is clear of every camera centre.
    Clear,
    /// Undecided.
    Straddles,
}

/// The primal Plücker coordinates (eq. 3) of the meet of the planes `p`, `q` (module docs).
pub(crate) fn meet(p: &Vector4<f64>, q: &Vector4<f64>) -> Vector6<f64> {
    let k = plucker::from_homogeneous_points(p, q);
    Vector6::new(k[5], k[4], k[3], k[2], k[1], k[0])
}

/// `π = π₀ + G z` of view `v` (module docs): the plane of the image line with whitened residual `z`.
fn plane_of_residual(problem: &LineProblem, camera: &Matrix3x4<f64>, v: usize) -> (Vector4<f64>, Matrix4x2<f64>) {
    let (frame, d) = (&problem.frames[v], LINE_FRAME_DISTANCE);
    let w_inv = problem.whitenings[v]
        .try_inverse()
        .unwrap_or_else(nalgebra::Matrix2::zeros);
    let l0 = nalgebra::Vector3::new(
        frame.normal.x / d,
        frame.normal.y / d,
        1.0 - frame.normal.dot(&frame.origin) / d,
    );
    let mut e = SMatrix::<f64, 3, 2>::zeros();
    e.fixed_view_mut::<2, 2>(0, 0).copy_from(&(w_inv / (d * d)));
    let last = -(frame.origin.transpose() * w_inv) / (d * d);
    e.set_row(2, &last);
    (camera.transpose() * l0, camera.transpose() * e)
}

impl TwoViewChart {
    /// The chart around the frame line `line` (Plücker, in `sim`'s frame) for lines cheaper than
    /// `bound`, from the views' residuals in that frame (`problem.views(sim)`); `None` when no pair
    /// of views is accepted (module docs).
    pub fn new(
        problem: &LineProblem,
        sim: &Similarity,
        residuals: &[FractionalResidual<2, 6>],
        line: &Vector6<f64>,
        bound: f64,
    ) -> Option<TwoViewChart> {
        let cameras: Vec<Matrix3x4<f64>> = problem.cameras.iter().map(|p| sim.camera(p)).collect();
        let planes: Vec<_> = cameras
            .iter()
            .enumerate()
            .map(|(v, p)| plane_of_residual(problem, p, v))
            .collect();
        let pair = select_pair(&cameras, &planes, residuals, line, bound.sqrt())?;
        let centre = {
            let (za, zb) = (residuals[pair.0].residual(line), residuals[pair.1].residual(line));
            Vector4::new(za.x, za.y, zb.x, zb.y)
        };
        let mut chart = TwoViewChart {
            pair,
            planes: [(Vector4::zeros(), Matrix4::zeros()); 2],
            centre,
            map: Matrix4::identity(),
            views: Vec::new(),
            moments: Vec::new(),
            direction: [Quadratic::zero(); 3],
            moment_rows: cameras
                .iter()
                .map(|p| p.fixed_view::<3, 3>(0, 0).transpose() * plucker::camera(p))
                .collect(),
            clearance: Vec::new(),
        };
        chart.build(&[planes[pair.0], planes[pair.1]], residuals);
        // Whiten w by the Gauss-Newton information at z* (w = 0).
        let info = chart.views.iter().fold(Matrix4::zeros(), |acc, v| {
            let jac = SMatrix::<f64, 2, 4>::from_fn(|k, i| {
                v.numerator[k].gradient[i] / v.denominator.constant
                    - v.numerator[k].constant * v.denominator.gradient[i] / v.denominator.constant.powi(2)
            });
            acc + jac.transpose() * jac
        });
        if let Some(map) = info.cholesky().and_then(|c| c.l().try_inverse()).map(|l| l.transpose()) {
            chart.whiten(&map);
        }
        let zero = Vector4::zeros();
        let norm = |q: &[Quadratic<4>; 3]| q.iter().map(|c| c.value(&zero).powi(2)).sum::<f64>().sqrt();
        let d0 = norm(&chart.direction);
        chart.clearance = chart.moments.iter().map(|u| CENTRE_CLEARANCE * norm(u) / d0).collect();
        Some(chart)
    }

    /// Builds the planes and the polynomial forms in `w = z − z*` (the map `M = I`).
    fn build(&mut self, planes: &[(Vector4<f64>, Matrix4x2<f64>); 2], residuals: &[FractionalResidual<2, 6>]) {
        for (s, (pi0, g)) in planes.iter().enumerate() {
            let z0 = self.centre.fixed_rows::<2>(2 * s).into_owned();
            let mut p = Matrix4::zeros();
            p.fixed_columns_mut::<2>(2 * s).copy_from(g);
            self.planes[s] = (pi0 + g * z0, p);
        }
        let [(p0, p), (q0, q)] = self.planes;
        // 𝓛(w) = meet(p₀ + P w, q₀ + Q w): six quadratic forms.
        let mut coords = [Quadratic::<4>::zero(); 6];
        let constant = meet(&p0, &q0);
        let linear: [Vector6<f64>; 4] =
            std::array::from_fn(|i| meet(&p.column(i).into_owned(), &q0) + meet(&p0, &q.column(i).into_owned()));
        for i in 0..4 {
            for j in 0..4 {
                let h = meet(&p.column(i).into_owned(), &q.column(j).into_owned());
                for (k, c) in coords.iter_mut().enumerate() {
                    c.hessian[(i, j)] += h[k];
                    c.hessian[(j, i)] += h[k];
                }
            }
        }
        for (k, c) in coords.iter_mut().enumerate() {
            c.constant = constant[k];
            c.gradient = Vector4::from_fn(|i, _| linear[i][k]);
        }
        let combine = |row: &Vector6<f64>| Quadratic::combination(row.iter().copied().zip(coords.iter()));
        // d = (l₁₄, −l₄₂, l₃₄) (plucker::direction_moment).
        self.direction = [coords[2], Quadratic::combination([(-1.0, &coords[4])]), coords[5]];
        self.moments = self
            .moment_rows
            .iter()
            .map(|rows| [0, 1, 2].map(|k| combine(&rows.row(k).transpose())))
            .collect();
        self.views = residuals
            .iter()
            .enumerate()
            .map(|(v, r)| {
                if v == self.pair.0 || v == self.pair.1 {
                    // Exactly the chart coordinates: z_v = z*_v + w_v.
                    let s = usize::from(v == self.pair.1);
                    let affine = |k: usize| Quadratic {
                        constant: self.centre[2 * s + k],
                        gradient: Vector4::ith(2 * s + k, 1.0),
                        hessian: Matrix4::zeros(),
                    };
                    QuadraticRatio {
                        numerator: [affine(0), affine(1)],
                        denominator: Quadratic {
                            constant: 1.0,
                            ..Quadratic::zero()
                        },
                    }
                } else {
                    QuadraticRatio {
                        numerator: [0, 1].map(|k| combine(&r.numerator.row(k).transpose())),
                        denominator: combine(&r.denominator),
                    }
                }
            })
            .collect();
    }

    /// Changes the branching coordinates to `w'` with `w = map · w'` (so `z = z* + map · w'`): every
    /// form is substituted, no form is rebuilt.
    fn whiten(&mut self, map: &Matrix4<f64>) {
        self.map *= map;
        for (_, p) in self.planes.iter_mut() {
            *p *= map;
        }
        let sub = |q: &Quadratic<4>| q.substitute(map);
        for v in self.views.iter_mut() {
            v.numerator = v.numerator.map(|n| sub(&n));
            v.denominator = sub(&v.denominator);
        }
        for u in self.moments.iter_mut() {
            *u = u.map(|c| sub(&c));
        }
        self.direction = self.direction.map(|c| sub(&c));
    }

    /// The 3-D line (Plücker, conditioned frame) at `w`.
    pub fn line(&self, w: &Vector4<f64>) -> Vector6<f64> {
        let [(p0, p), (q0, q)] = self.planes;
        meet(&(p0 + p * w), &(q0 + q * w))
    }

    /// Where the box `[lower, upper]` lies relative to the lines closer to a camera centre than the
    /// clearance (interval bounds of `‖u‖` and `|det M| ‖d‖`).
    pub fn clearance(&self, lower: &[f64], upper: &[f64]) -> Clearance {
        let m = Vector4::from_fn(|i, _| 0.5 * (lower[i] + upper[i]));
        let h = Vector4::from_fn(|i, _| 0.5 * (upper[i] - lower[i]));
        let ranges = |q: &[Quadratic<4>; 3]| q.map(|c| c.range(&m, &h));
        let d = ranges(&self.direction);
        let (d_min, d_max) = (
            d.iter().map(|x| x.mig().powi(2)).sum::<f64>().sqrt(),
            d.iter().map(|x| x.mag().powi(2)).sum::<f64>().sqrt(),
        );
        let mut clear = true;
        for (u, &c) in self.moments.iter().zip(&self.clearance) {
            let u = ranges(u);
            let u_min = u.iter().map(|x| x.mig().powi(2)).sum::<f64>().sqrt();
            let u_max = u.iter().map(|x| x.mag().powi(2)).sum::<f64>().sqrt();
            if u_max < c * d_min {
                return Clearance::Inside;
            }
            clear &= u_min > c * d_max;
        }
        if clear {
            Clearance::Clear
        } else {
            Clearance::Straddles
        }
    }

    /// True when the line `l` (Plücker, conditioned frame) is at least the clearance away from every
    /// camera centre.
    pub fn is_clear(&self, l: &Vector6<f64>) -> bool {
        let (d, _) = plucker::direction_moment(l);
        let d = d.norm();
        self.moment_rows
            .iter()
            .zip(&self.clearance)
            .all(|(rows, &c)| (rows * l).norm() >= c * d)
    }

    /// The bounding box, in `w`, of the ball `‖z‖ ≤ radius`.
    pub fn root(&self, radius: f64) -> Region {
        // w = M⁻¹ (z − z*): row i of M⁻¹ dotted with the ball.
        let inv = self.map.try_inverse().unwrap_or_else(Matrix4::identity);
        let offset = -(inv * self.centre);
        let (lower, upper): (Vec<f64>, Vec<f64>) = (0..4)
            .map(|i| {
                let half = radius * inv.row(i).norm();
                (offset[i] - half, offset[i] + half)
            })
            .unzip();
        Region::new(lower, upper)
    }
}

/// The accepted pair with the least score of the module docs (views with non-singular `Iᵥ` sums).
fn select_pair(
    cameras: &[Matrix3x4<f64>],
    planes: &[(Vector4<f64>, Matrix4x2<f64>)],
    residuals: &[FractionalResidual<2, 6>],
    line: &Vector6<f64>,
    radius: f64,
) -> Option<(usize, usize)> {
    let x = OrthonormalLine::from_plucker(line)?;
    let tangent = x.tangent();
    let info: Vec<Matrix4<f64>> = residuals
        .iter()
        .map(|r| fractional_residual::linearize(std::slice::from_ref(r), line, &tangent).gauss_newton)
        .collect();
    let total: Matrix4<f64> = info.iter().sum();
    let mut candidates: Vec<usize> = (0..info.len()).collect();
    candidates.sort_by(|&i, &j| info[j].trace().total_cmp(&info[i].trace()));
    candidates.truncate(MAX_PAIR_CANDIDATES);
    let centres: Vec<Vector4<f64>> = cameras.iter().map(|p| views::centre(p).push(1.0)).collect();
    let mut best: Option<(f64, (usize, usize))> = None;
    for (k, &a) in candidates.iter().enumerate() {
        for &b in &candidates[k + 1..] {
            let Some(inv) = (info[a] + info[b]).try_inverse() else {
                continue;
            };
            let score = (inv * total).trace();
            if !(score.is_finite() && score > 0.0) || best.is_some_and(|(s, _)| s <= score) {
                continue;
            }
            // l_v(z)·e_v = π_v(z)·C_other = (π₀ + G z)·C_other, affine in z: no zero on the disc.
            let clear = |v: usize, other: usize| {
                let (pi0, g) = planes[v];
                let c = centres[other];
                pi0.dot(&c).abs() > EPIPOLE_MARGIN * radius * (g.transpose() * c).norm()
            };
            if clear(a, b) || clear(b, a) {
                best = Some((score, (a, b)));
            }
        }
    }
    best.map(|(_, pair)| pair)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;
    use crate::triangulation::line::tests::noisy_problem;
    use nalgebra::{Matrix2, Vector3};

    #[test]
    fn meet_of_two_planes_is_the_line_through_their_common_points() {
        let mut rng = Rng::new(8);
        for _ in 0..20 {
            let (a, b) = (
                Vector3::from_fn(|_, _| rng.normal()),
                Vector3::from_fn(|_, _| rng.normal()),
            );
            let plane = |c: Vector3<f64>| {
                let n = (a - c).cross(&(b - c));
                Vector4::new(n.x, n.y, n.z, -n.dot(&c))
            };
            let l = meet(
                &plane(Vector3::from_fn(|_, _| rng.normal())),
                &plane(Vector3::from_fn(|_, _| rng.normal())),
            );
            let expected = plucker::from_points(&a, &b);
            let cos = l.normalize().dot(&expected.normalize()).abs();
            assert!((cos - 1.0).abs() < 1e-9, "{cos}");
        }
    }

    /// The chart's pair is the accepted pair of least score `tr((I_a + I_b)⁻¹ Σᵥ Iᵥ)` (module docs):
    /// every pair of views is scored here and tested for the epipole condition, and none that is
    /// accepted scores less than the chosen one.
    #[test]
    fn the_chosen_pair_has_the_least_score_of_the_accepted_pairs() {
        let mut compared = 0;
        for seed in 0..12u64 {
            let n = 3 + seed as usize % 5;
            let (problem, (a, b)) = noisy_problem(n, 40 + seed, |i| Matrix2::new(0.5 + 0.3 * i as f64, 0.0, 0.2, 1.0));
            let sim = Similarity::of_cameras(&problem.cameras);
            let line = plucker::transform(&sim.matrix(), &plucker::from_points(&a, &b));
            let residuals = problem.views(&sim);
            let bound = 4.0 * fractional_residual::cost(&residuals, &line);
            let Some(chart) = TwoViewChart::new(&problem, &sim, &residuals, &line, bound) else {
                continue;
            };
            let cameras: Vec<Matrix3x4<f64>> = problem.cameras.iter().map(|p| sim.camera(p)).collect();
            let tangent = OrthonormalLine::from_plucker(&line).unwrap().tangent();
            let info: Vec<Matrix4<f64>> = residuals
                .iter()
                .map(|r| fractional_residual::linearize(std::slice::from_ref(r), &line, &tangent).gauss_newton)
                .collect();
            let total: Matrix4<f64> = info.iter().sum();
            let score = |i: usize, j: usize| ((info[i] + info[j]).try_inverse().unwrap() * total).trace();
            // The image line of view v on the disc ‖z_v‖ ≤ √bound misses the epipole of the other view.
            let clear = |v: usize, other: usize| {
                let (pi0, g) = plane_of_residual(&problem, &cameras[v], v);
                let c = views::centre(&cameras[other]).push(1.0);
                pi0.dot(&c).abs() > EPIPOLE_MARGIN * bound.sqrt() * (g.transpose() * c).norm()
            };
            let chosen = score(chart.pair.0, chart.pair.1);
            for i in 0..n {
                for j in i + 1..n {
                    if clear(i, j) || clear(j, i) {
                        // Scores of a few 4×4 inverses: rounding ~1e-12 relative.
                        assert!(
                            chosen <= score(i, j) * (1.0 + 1e-9),
                            "seed {seed}: pair {:?} scores {chosen}, the accepted pair ({i}, {j}) {}",
                            chart.pair,
                            score(i, j)
                        );
                        compared += 1;
                    }
                }
            }
        }
        assert!(compared >= 50, "{compared}");
    }

    #[test]
    fn chart_residuals_equal_the_views_residuals_and_the_pair_is_exact() {
        let (problem, (a, b)) = noisy_problem(5, 9, |i| Matrix2::new(0.7 + 0.1 * i as f64, 0.0, 0.3, 1.4));
        let cameras = problem.cameras.clone();
        let mut rng = Rng::new(10);
        let sim = Similarity::of_cameras(&cameras);
        let truth = plucker::transform(&sim.matrix(), &plucker::from_points(&a, &b));
        let residuals = problem.views(&sim);
        let cost = fractional_residual::cost(&residuals, &truth);
        let chart = TwoViewChart::new(&problem, &sim, &residuals, &truth, 4.0 * cost).expect("a pair");
        assert!(chart.line(&Vector4::zeros()).normalize().dot(&truth.normalize()).abs() > 1.0 - 1e-10);
        // The clearance is CENTRE_CLEARANCE times the local line's distance from each centre.
        let cams: Vec<Matrix3x4<f64>> = cameras.iter().map(|p| sim.camera(p)).collect();
        let (p0, d0) = plucker::to_point_direction(&truth).unwrap();
        for (p, c) in cams.iter().zip(&chart.clearance) {
            let centre = views::centre(p);
            let dist = (centre - p0).cross(&d0).norm();
            let det = p.fixed_view::<3, 3>(0, 0).determinant().abs();
            assert!(
                (c / det - CENTRE_CLEARANCE * dist).abs() < 1e-9 * dist,
                "{} vs {}",
                c / det,
                CENTRE_CLEARANCE * dist
            );
        }
        assert!(chart.is_clear(&truth));
        assert_eq!(chart.clearance(&[-1e-6; 4], &[1e-6; 4]), Clearance::Clear);
        for _ in 0..50 {
            let w = Vector4::from_fn(|_, _| rng.normal() * 0.5);
            let l = chart.line(&w);
            for (v, form) in chart.views.iter().enumerate() {
                let direct = residuals[v].residual(&l);
                let via_forms = form.residual(&w);
                assert!(
                    (direct - via_forms).norm() < 1e-7 * (1.0 + direct.norm()),
                    "view {v}: {direct} vs {via_forms}"
                );
            }
        }
    }
}
