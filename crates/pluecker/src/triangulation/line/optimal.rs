//! Branch and bound for lines (Josephson & Kahl 2008, sections 4.1-4.3.2).
//!
//! **Parametrisation** (eq. 23). In a frame chosen per line — `z` axis along the local line, the
//! planes `z = 0` and `z = 1` crossing it at two points `Ŷ`, `X̂` in front of every camera near its
//! point closest to the cameras (see `plane_frame`) — a line through `X = (x₁, x₂, 1)` and
//! `Y = (y₁, y₂, 0)` has the Plücker coordinates
//! `𝓛 = (x₁y₂ − x₂y₁, −y₁, x₁ − y₁, −y₂, y₂ − x₂, 1)`. The local line is `x = y = 0`, so no line
//! near it is parallel to the planes `z = 0, 1` (the paper switches frames for such lines; here the
//! frame follows the line).
//!
//! **Domain.** Branch and bound searches the lines whose points `X`, `Y` satisfy the eq. 27 strips in
//! every view, `|l̂ᵢᵀ Pᵢ X̃| ≤ γᵢ depthᵢ(X)` (the projection lies within `γᵢ` px of the observed line,
//! in front of the camera) and `depthᵢ(X) ≤ z_max`, and whose whitened residual is at most `γ` in every
//! view (`‖Lᵢ rᵢ‖ ≤ γ`, with the denominator of eq. 17 positive). `γ` is `sqrt(local cost)`: every
//! line cheaper than the local line satisfies it. The strip widths `γᵢ` are derived from `γ`: an image line `ℓ` with
//! `‖Lᵢ rᵢ(ℓ)‖ ≤ γ` passes within `(γ/D) ‖Lᵢ⁻ᵀ (u − oᵢ)‖` px of the observed line at the pixel `u`
//! (see [`super::residual`]); `γᵢ` is [`STRIP_MARGIN`] times that width at the images of the
//! local line's points `X̂`, `Ŷ`, and `z_max` is [`DEPTH_FACTOR`] times their largest depth. The
//! certificate is a certificate over this domain: a line within `γ` whose points `X`, `Y` project far
//! from the images of `X̂`, `Ŷ` along the observed line (where the strips of whitened width are wider
//! than `γᵢ`) is outside it. The initial box is the bounding box of the strips on each plane (eq. 27,
//! solved exactly as 2-D polygons).
//!
//! **Bound** (sections 4.1.1-4.1.2). Over a box of `(x₁, x₂, y₁, y₂)` one SOCP: the monomials
//! `w₁ = x₁y₂`, `w₂ = x₂y₁` lifted with their McCormick envelopes (eqs. 24-25, [`crate::global::monomial`]),
//! so that `𝓛` is affine in `(x, y, w)`; per view the numerator cone `‖Aᵢ𝓛‖² ≤ tᵢ gᵢ` (eq. 21), the
//! domain cone `‖Aᵢ𝓛‖ ≤ γ gᵢ` and the fraction envelope of eq. 22 over `tᵢ ∈ [0, γ² Gᵢᵁ]`,
//! `gᵢ ∈ [Gᵢᴸ, Gᵢᵁ]` (interval bounds of the denominator over the box); a view whose denominator
//! interval reaches 0 contributes 0 (a valid bound: its term is non-negative). The bound is the
//! solver-tolerance-proof dual bound of [`crate::global::socp`]. Branching splits the four line
//! parameters (section 4.2), the widest at the relaxed minimiser; each node's relaxed minimiser starts
//! a short local minimisation whose cost is an upper bound (section 5).

use super::residual::LINE_FRAME_DISTANCE;
use super::{LineObjective, LineProblem};
use crate::certificate::Primitive;
use crate::geometry::plucker::{self, OrthonormalLine};
use crate::global::branch_and_bound::{branch_and_bound, Bound, BoundingOracle, BranchAndBoundOptions, Region};
use crate::global::envelopes::add_quadratic_over_linear;
use crate::global::monomial::{add_mccormick, product_bounds, Interval};
use crate::global::socp::{Affine, Socp, SocpStatus};
use crate::optim::{trust_region, TrustRegionOptions};
use crate::triangulation::certificate::{certificate_of, minimum, optimal_start, solve_fraction_relaxation};
use crate::triangulation::conditioning::Similarity;
use crate::triangulation::fractional_residual::{self, FractionalResidual};
use crate::triangulation::{CertificateKind, Report, Status, TriangulationOptions};
use nalgebra::{Matrix3, Matrix4, Vector2, Vector3, Vector4, Vector6};
use std::ops::{Add, Sub};

/// Factor between the eq. 27 strip widths and the width implied by `γ` at the local line's points.
pub const STRIP_MARGIN: f64 = 2.0;
/// `z_max` as a multiple of the largest depth of the local line's points `X̂`, `Ŷ`.
pub const DEPTH_FACTOR: f64 = 100.0;
/// Rounds of bound tightening at the root (stopping early when a round shrinks the box's volume by
/// less than 10 %).
const MAX_TIGHTENING_ROUNDS: usize = 6;
/// Trust-region iterations of the local step from each node's relaxed minimiser.
const NODE_LOCAL_ITERATIONS: usize = 10;
/// Half-width of the square clipped by the strips (frame units; the local line is at the origin).
const FAR: f64 = 1e6;

/// Eq. 23: the Plücker coordinates of the line through `(x₁, x₂, 1)` and `(y₁, y₂, 0)`.
pub(crate) fn eq23(x: &Vector2<f64>, y: &Vector2<f64>) -> Vector6<f64> {
    Vector6::new(x[0] * y[1] - x[1] * y[0], -y[0], x[0] - y[0], -y[1], y[1] - x[1], 1.0)
}

/// The frame of the module docs for a world line: `Y` (`z = 0`) and `X` (`z = 1`) are the points
/// `t_c ∓ h` along the line from its foot ([`LineProblem::foot`]), inside the interval of the line
/// in front of every camera: `t_c` is 0 clamped into the middle half of that interval (or `ρ/4` from
/// a finite end of a half-infinite one) and `h = min(ρ/20, half the distance from t_c to the nearest
/// end)`; the frame's unit is `2h`. `None` when the line is at infinity in world coordinates (so far
/// from the origin, relative to its own length scale, that its direction is lost).
fn plane_frame(problem: &LineProblem, world_line: &Vector6<f64>) -> Option<Similarity> {
    let (foot, rho) = problem.foot(world_line);
    let (_, d) = plucker::to_point_direction(world_line)?;
    // depth_i(foot + t d) = a_i + b_i t > 0 for every camera.
    let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
    for p in &problem.cameras {
        let p = crate::triangulation::views::depth_normalized(p);
        let (a, b) = ((p * foot.push(1.0)).z, (p * d.push(0.0)).z);
        if b > 0.0 {
            lo = lo.max(-a / b);
        } else if b < 0.0 {
            hi = hi.min(-a / b);
        }
    }
    let (inner_lo, inner_hi) = match (lo.is_finite(), hi.is_finite()) {
        (true, true) => (lo + 0.25 * (hi - lo), hi - 0.25 * (hi - lo)),
        (true, false) => (lo + 0.25 * rho, f64::INFINITY),
        (false, true) => (f64::NEG_INFINITY, hi - 0.25 * rho),
        (false, false) => (f64::NEG_INFINITY, f64::INFINITY),
    };
    let centre = if inner_lo <= inner_hi {
        0.0f64.clamp(inner_lo, inner_hi)
    } else {
        0.5 * (lo + hi)
    };
    let room = (centre - lo).min(hi - centre);
    let h = (0.05 * rho).min(0.5 * room).max(f64::MIN_POSITIVE);
    let e1 = if d.x.abs() < 0.9 {
        d.cross(&Vector3::x())
    } else {
        d.cross(&Vector3::y())
    }
    .normalize();
    let e2 = d.cross(&e1);
    Some(Similarity {
        rotation: Matrix3::from_rows(&[e1.transpose(), e2.transpose(), d.transpose()]),
        ..Similarity::around(foot + d * (centre - h), 2.0 * h)
    })
}

/// A half-plane `a·v ≤ b` of one of the planes `z = 0, 1`.
type HalfPlane = (Vector2<f64>, f64);

/// The eq. 27 constraints of view `p` (depth-normalised, frame) with observed unit-normal line `l`
/// and strip half-width `gamma` on the plane `z = h`, as `a·v ≤ b` in `v = (v₁, v₂)`.
fn strip(p: &nalgebra::Matrix3x4<f64>, l: &Vector3<f64>, gamma: f64, z_max: f64, h: f64) -> [HalfPlane; 3] {
    // u = M v + m with M the first two columns of P and m = h p₃ + p₄; w·u ≤ c becomes Mᵀw·v ≤ c − w·m.
    let m2 = p.fixed_view::<3, 2>(0, 0).into_owned();
    let m0: Vector3<f64> = p.column(2) * h + p.column(3);
    let row = |w: Vector3<f64>, c: f64| -> HalfPlane { (m2.transpose() * w, c - w.dot(&m0)) };
    let depth = Vector3::z();
    [
        row(l - depth * gamma, 0.0),
        row(-l - depth * gamma, 0.0),
        row(depth, z_max),
    ]
}

/// The bounding box of a convex polygon given as half-planes, by clipping the square `[−FAR, FAR]²`;
/// `None` when empty.
fn clip_bounds(halfplanes: &[HalfPlane]) -> Option<(Vector2<f64>, Vector2<f64>)> {
    let mut poly = vec![
        Vector2::new(-FAR, -FAR),
        Vector2::new(FAR, -FAR),
        Vector2::new(FAR, FAR),
        Vector2::new(-FAR, FAR),
    ];
    for (a, b) in halfplanes {
        let scale = a.norm().max(b.abs()).max(f64::MIN_POSITIVE);
        let (a, b) = (a / scale, b / scale);
        let mut next = Vec::with_capacity(poly.len() + 1);
        for k in 0..poly.len() {
            let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
            let (fp, fq) = (a.dot(&p) - b, a.dot(&q) - b);
            if fp <= 0.0 {
                next.push(p);
            }
            if (fp < 0.0 && fq > 0.0) || (fp > 0.0 && fq < 0.0) {
                next.push(p + (q - p) * (fp / (fp - fq)));
            }
        }
        poly = next;
        if poly.is_empty() {
            return None;
        }
    }
    let lo = poly.iter().fold(Vector2::repeat(f64::INFINITY), |m, p| m.inf(p));
    let hi = poly.iter().fold(Vector2::repeat(f64::NEG_INFINITY), |m, p| m.sup(p));
    Some((lo, hi))
}

/// The bound oracle of the module docs.
struct LineOracle<'a> {
    views: &'a [FractionalResidual<2, 6>],
    /// The branching coordinates `z`: `p = (x₁, x₂, y₁, y₂) = T z` (see [`branching_map`]).
    t: Matrix4<f64>,
    /// Eq. 27 half-planes on `z = 1` (for `x`) and `z = 0` (for `y`).
    x_strips: Vec<HalfPlane>,
    y_strips: Vec<HalfPlane>,
    gamma: f64,
    /// Bounds of every denominator over the root box (from [`LineOracle::tighten`]).
    g_bounds: Vec<Interval>,
    /// The cost of the local line: lines that cost more cannot improve on it (the cut of
    /// [`LineOracle::relaxation`]).
    incumbent: f64,
    local: TrustRegionOptions,
}

/// The convex relaxation of the domain over one region, without an objective.
struct Relaxation {
    p: Socp,
    /// Program variables `z₁ … z₄` (the branching coordinates).
    vars: [usize; 4],
    /// Per view: the numerator `Aᵢ𝓛` (2 affine entries), the denominator `gᵢ = cᵢ𝓛`, its interval,
    /// and the variable `tᵢ ≥ ‖Aᵢ𝓛‖²/gᵢ` (eq. 21).
    views: Vec<([Affine; 2], Affine, Interval, usize)>,
}

impl LineOracle<'_> {
    /// A short local minimisation from `(x, y)`: the frame line and its cost.
    fn local_step(&self, x: &Vector2<f64>, y: &Vector2<f64>) -> Option<(f64, Vector6<f64>)> {
        let start = OrthonormalLine::from_plucker(&eq23(x, y))?;
        let objective = LineObjective { views: self.views };
        let (line, summary) = trust_region::minimize(&objective, start, &self.local);
        summary
            .final_cost
            .is_finite()
            .then(|| (2.0 * summary.final_cost, line.to_plucker()))
    }

    /// The box, McCormick envelopes (eqs. 24-25), domain cones and eq. 27 strips over `region`;
    /// `None` when a denominator is non-positive on the whole region (no line of the domain).
    fn relaxation(&self, region: &Region) -> Option<Relaxation> {
        let mut p = Socp::new();
        let vars: [usize; 4] = std::array::from_fn(|k| p.add_variable(region.lower[k], region.upper[k]));
        for (k, &v) in vars.iter().enumerate() {
            p.less_eq(&Affine::constant(region.lower[k]), &Affine::var(v));
            p.less_eq(&Affine::var(v), &Affine::constant(region.upper[k]));
        }
        // An affine form r·z of the branching variables, and its exact range over the region.
        let form = |r: &[f64]| {
            r.iter()
                .zip(&vars)
                .fold(Affine::constant(0.0), |acc, (&c, &v)| acc.plus(&Affine::term(v, c)))
        };
        let range = |r: &[f64]| {
            (0..4).fold(Interval::new(0.0, 0.0), |acc, k| {
                acc.add(Interval::new(region.lower[k], region.upper[k]).scale(r[k]))
            })
        };
        let rows: [Vec<f64>; 4] = std::array::from_fn(|k| self.t.row(k).iter().copied().collect());
        let (x1, x2, y1, y2) = (&rows[0], &rows[1], &rows[2], &rows[3]);
        let w1 = add_mccormick(&mut p, &form(x1), range(x1), &form(y2), range(y2));
        let w2 = add_mccormick(&mut p, &form(x2), range(x2), &form(y1), range(y1));
        let monomials = product_bounds(range(x1), range(y2)).sub(product_bounds(range(x2), range(y1)));
        // Eq. 23: 𝓛 = E z + (w₁ − w₂) e₁ + e₆, with E the linear part in z.
        let linear: [Vec<f64>; 6] = [
            vec![0.0; 4],
            y1.iter().map(|v| -v).collect(),
            x1.iter().zip(y1).map(|(a, b)| a - b).collect(),
            y2.iter().map(|v| -v).collect(),
            y2.iter().zip(x2).map(|(a, b)| a - b).collect(),
            vec![0.0; 4],
        ];
        // c·𝓛 as an affine expression and its interval (exact in z, McCormick range for w₁ − w₂).
        let combine = |c: &[f64]| {
            let r: Vec<f64> = (0..4).map(|k| (0..6).map(|i| c[i] * linear[i][k]).sum()).collect();
            let e = form(&r)
                .plus(&Affine::var(w1).minus(&Affine::var(w2)).scaled(c[0]))
                .shifted(c[5]);
            let i = range(&r).add(monomials.scale(c[0])).add(Interval::new(c[5], c[5]));
            (e, i)
        };
        let mut views = Vec::with_capacity(self.views.len());
        for (view, root) in self.views.iter().zip(&self.g_bounds) {
            let c: Vec<f64> = view.denominator.iter().copied().collect();
            let (g, interval) = combine(&c);
            let g_range = Interval::new(interval.lo.max(root.lo), interval.hi.min(root.hi));
            if g_range.hi <= 0.0 || g_range.hi < g_range.lo {
                return None;
            }
            let a: [Affine; 2] =
                std::array::from_fn(|r| combine(&view.numerator.row(r).iter().copied().collect::<Vec<_>>()).0);
            p.second_order(g.clone().scaled(self.gamma), &a);
            let t = p.add_variable(0.0, self.gamma.powi(2).min(self.incumbent) * g_range.hi);
            add_quadratic_over_linear(&mut p, &a, &g, &Affine::var(t));
            views.push((a, g, g_range, t));
        }
        // The cut Σ tᵢ/Gᵢᵁ ≤ incumbent: ‖rᵢ‖² = tᵢ/gᵢ ≥ tᵢ/Gᵢᵁ at tᵢ = ‖Aᵢ𝓛‖²/gᵢ, so every line
        // cheaper than the incumbent satisfies it.
        let cut = views.iter().fold(Affine::constant(0.0), |acc, (_, _, g_range, t)| {
            acc.plus(&Affine::term(*t, 1.0 / g_range.hi))
        });
        p.less_eq(&cut, &Affine::constant(self.incumbent));
        for (strips, (i, j)) in [(&self.x_strips, (0, 1)), (&self.y_strips, (2, 3))] {
            for (a, b) in strips.iter() {
                let r: Vec<f64> = (0..4).map(|k| a.x * rows[i][k] + a.y * rows[j][k]).collect();
                p.less_eq(&form(&r), &Affine::constant(*b));
            }
        }
        Some(Relaxation { p, vars, views })
    }

    /// Optimisation-based bound tightening of the root: the least and greatest value of each line
    /// parameter, then of each denominator, over the relaxation (valid bounds by the dual bound of
    /// [`crate::global::socp`]). `None` when the relaxation is infeasible (an empty domain); also
    /// returns the solver iterations spent.
    fn tighten(&mut self, region: &Region) -> (Option<Region>, usize) {
        let mut iterations = 0;
        let mut region = region.clone();
        let mut extreme = |relax: &Relaxation, e: Affine| {
            let (value, spent) = minimum(&relax.p, e);
            iterations += spent;
            value
        };
        for _ in 0..MAX_TIGHTENING_ROUNDS {
            let before: f64 = (0..4).map(|k| region.width(k)).product();
            let Some(relax) = self.relaxation(&region) else {
                return (None, 0);
            };
            for k in 0..4 {
                let var = Affine::var(relax.vars[k]);
                let Some(lo) = extreme(&relax, var.clone()) else {
                    return (None, 0);
                };
                let Some(hi) = extreme(&relax, var.scaled(-1.0)) else {
                    return (None, 0);
                };
                region.lower[k] = lo.map_or(region.lower[k], |v| v.max(region.lower[k]));
                region.upper[k] = hi.map_or(region.upper[k], |v| (-v).min(region.upper[k]));
                if region.lower[k] > region.upper[k] {
                    return (None, 0);
                }
            }
            if (0..4).map(|k| region.width(k)).product::<f64>() > 0.9 * before {
                break;
            }
        }
        let Some(relax) = self.relaxation(&region) else {
            return (None, 0);
        };
        for (i, (_, g, _, _)) in relax.views.iter().enumerate() {
            let Some(lo) = extreme(&relax, g.clone()) else {
                return (None, 0);
            };
            let Some(hi) = extreme(&relax, g.clone().scaled(-1.0)) else {
                return (None, 0);
            };
            let old = self.g_bounds[i];
            self.g_bounds[i] = Interval::new(
                lo.map_or(old.lo, |v| v.max(old.lo)),
                hi.map_or(old.hi, |v| (-v).min(old.hi)),
            );
        }
        (Some(region), iterations)
    }
}

impl BoundingOracle for LineOracle<'_> {
    type Candidate = Vector6<f64>;
    type Inherited = ();

    fn bound(&mut self, region: &Region) -> Bound<Vector6<f64>> {
        let Some(Relaxation { mut p, vars, views }) = self.relaxation(region) else {
            return Bound::Empty { solver_iterations: 0 };
        };
        let terms = views.iter().map(|(_, g, range, t)| (*t, g, range.lo, range.hi));
        let s = solve_fraction_relaxation(&mut p, terms, self.gamma.powi(2).min(self.incumbent));
        match s.status {
            SocpStatus::Infeasible => Bound::Empty {
                solver_iterations: s.iterations,
            },
            SocpStatus::Solved => {
                let minimizer: Vec<f64> = vars
                    .iter()
                    .enumerate()
                    .map(|(k, &j)| s.x[j].clamp(region.lower[k], region.upper[k]))
                    .collect();
                let p = self.t * Vector4::from_column_slice(&minimizer);
                let (x, y) = (Vector2::new(p[0], p[1]), Vector2::new(p[2], p[3]));
                Bound::Bounded {
                    lower: s.lower_bound.max(0.0),
                    relaxed_minimizer: Some(minimizer),
                    candidate: self.local_step(&x, &y),
                    solver_iterations: s.iterations,
                }
            }
            _ => Bound::Failed {
                solver_iterations: s.iterations,
            },
        }
    }
}

/// `T` with `p = (x₁, x₂, y₁, y₂) = T z` whitening the Gauss-Newton Hessian `H` of eq. 19 in `p` at
/// the local line `p = 0` (`H = L Lᵀ`, `T = L⁻ᵀ`, so that `pᵀ H p = ‖z‖²`): near the optimum the
/// cost's level sets are balls in `z`, which axis-aligned boxes cover without waste. The identity
/// when `H` is singular.
fn branching_map(views: &[FractionalResidual<2, 6>]) -> Matrix4<f64> {
    let reference = eq23(&Vector2::zeros(), &Vector2::zeros());
    // ∂𝓛/∂p of eq. 23 at p = 0.
    let mut dl = nalgebra::SMatrix::<f64, 6, 4>::zeros();
    dl[(2, 0)] = 1.0;
    dl[(4, 1)] = -1.0;
    dl[(1, 2)] = -1.0;
    dl[(2, 2)] = -1.0;
    dl[(3, 3)] = -1.0;
    dl[(4, 3)] = 1.0;
    let h = fractional_residual::linearize(views, &reference, &dl).gauss_newton;
    match h.cholesky() {
        Some(c) => c
            .l()
            .try_inverse()
            .map(|l| l.transpose())
            .unwrap_or_else(Matrix4::identity),
        None => Matrix4::identity(),
    }
}

/// The optimal method from the local line `local` (world) with report `local_report`: the best
/// world line found and the report with its certificate (module docs).
pub(crate) fn optimal_line(
    problem: &LineProblem,
    local: &Vector6<f64>,
    local_report: &Report,
    opts: &TriangulationOptions,
) -> (Vector6<f64>, Report) {
    let mut report = match optimal_start(local_report, Primitive::Line) {
        Ok(report) => report,
        Err(certified) => return (*local, certified),
    };
    let cost = local_report.cost;
    let gamma = cost.sqrt();
    let Some(sim) = plane_frame(problem, local) else {
        // No frame for eq. 23, so no search: the local line, uncertified (the caller turns a line
        // at infinity into the same error as for `local`).
        report.set_status(Status::NumericalFailure);
        return (*local, report);
    };
    let h = sim.matrix();
    let frame_local = plucker::transform(&h, local);
    let reference = eq23(&Vector2::zeros(), &Vector2::zeros());
    let views: Vec<FractionalResidual<2, 6>> = problem.views(&sim).iter().map(|v| v.oriented(&reference)).collect();
    // Eq. 27 strips on z = 1 (X) and z = 0 (Y).
    let cameras: Vec<nalgebra::Matrix3x4<f64>> = problem.cameras.iter().map(|p| sim.camera(p)).collect();
    let points = [Vector4::new(0.0, 0.0, 1.0, 1.0), Vector4::new(0.0, 0.0, 0.0, 1.0)];
    let z_max = DEPTH_FACTOR
        * cameras
            .iter()
            .flat_map(|p| points.iter().map(move |x| (p * x).z))
            .fold(0.0, f64::max);
    let (mut x_strips, mut y_strips) = (Vec::new(), Vec::new());
    for ((p, frame), w) in cameras.iter().zip(&problem.frames).zip(&problem.whitenings) {
        let w_inv_t = w.try_inverse().unwrap_or_else(nalgebra::Matrix2::zeros).transpose();
        let width = points
            .iter()
            .map(|x| {
                let u = p * x;
                gamma / LINE_FRAME_DISTANCE * (w_inv_t * (u.xy() / u.z - frame.origin)).norm()
            })
            .fold(0.0, f64::max);
        let l = frame.line();
        x_strips.extend(strip(p, &l, STRIP_MARGIN * width, z_max, 1.0));
        y_strips.extend(strip(p, &l, STRIP_MARGIN * width, z_max, 0.0));
    }
    // The strips and the cones hold the local line: a domain found empty is a numerical artefact,
    // which proves nothing.
    let (Some((xlo, xhi)), Some((ylo, yhi))) = (clip_bounds(&x_strips), clip_bounds(&y_strips)) else {
        report.set_status(Status::NumericalFailure);
        return (*local, report);
    };
    // The strips' box in p = (x, y), then its bounding box in the branching coordinates z = T⁻¹ p.
    let (p_lo, p_hi) = (
        Vector4::new(xlo.x, xlo.y, ylo.x, ylo.y),
        Vector4::new(xhi.x, xhi.y, yhi.x, yhi.y),
    );
    let t = branching_map(&views);
    let t_inv = t.try_inverse().unwrap_or_else(Matrix4::identity);
    let z_range = |k: usize| {
        (0..4).fold(Interval::new(0.0, 0.0), |acc, j| {
            acc.add(Interval::new(p_lo[j], p_hi[j]).scale(t_inv[(k, j)]))
        })
    };
    let root = Region::new(
        (0..4).map(|k| z_range(k).lo).collect::<Vec<f64>>(),
        (0..4).map(|k| z_range(k).hi).collect::<Vec<f64>>(),
    );
    if !(0..4).all(|k| root.lower[k].is_finite() && root.upper[k].is_finite()) {
        // The strips overflowed (a cost or whitening beyond double precision): no box to search.
        report.set_status(Status::NumericalFailure);
        return (*local, report);
    }
    let mut node_local = opts.local;
    node_local.stopping.max_iterations = NODE_LOCAL_ITERATIONS;
    let g_bounds = vec![Interval::new(f64::NEG_INFINITY, f64::INFINITY); views.len()];
    let frame_cost = fractional_residual::cost(&views, &frame_local);
    let incumbent = frame_cost * (1.0 + 1e-9);
    let mut oracle = LineOracle {
        views: &views,
        t,
        x_strips,
        y_strips,
        gamma,
        g_bounds,
        incumbent,
        local: node_local,
    };
    let (root, tightening_iterations) = oracle.tighten(&root);
    let Some(root) = root else {
        report.set_status(Status::NumericalFailure);
        return (*local, report);
    };
    let bb_opts = BranchAndBoundOptions {
        max_relative_gap: opts.certify.max_relative_gap,
        max_nodes: opts.conic_max_nodes(),
        trivial_lower_bound: 0.0,
    };
    let mut result = branch_and_bound(&mut oracle, root, Some((frame_cost, frame_local)), &bb_opts);
    result.solver_iterations += tightening_iterations;
    let (best_cost, best) = result.best.unwrap_or((frame_cost, frame_local));
    let world = plucker::transform(&sim.inverse_matrix(), &best);
    report.cost = best_cost;
    let (status, certificate) = certificate_of(
        &result,
        best_cost,
        opts.certify.max_relative_gap,
        CertificateKind::BranchAndBound,
        Primitive::Line,
    );
    (report.status, report.certificate) = (status, certificate);
    (world, report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::synthetic::triangulation_scene;

    #[test]
    fn the_plane_frame_is_the_documented_one() {
        // Lines through a scene point, recomputed from the doc comment of `plane_frame`: the interval
        // of `t` in front of every camera, `t_c` = 0 clamped into its middle half, `h = min(ρ/20, half
        // the room to the nearest end)`, origin at `t_c − h` along the line, unit `2h`.
        let mut rng = crate::rng::Rng::new(31);
        let mut checked = 0;
        for seed in 0..20u64 {
            let scene = triangulation_scene(4, 0.5, seed);
            let problem = LineProblem {
                cameras: scene.cameras.clone(),
                frames: vec![],
                whitenings: vec![],
            };
            let line = plucker::from_point_direction(&scene.point, &rng.unit_vector3());
            let Some(sim) = plane_frame(&problem, &line) else {
                continue;
            };
            let (foot, rho) = problem.foot(&line);
            let (_, d) = plucker::to_point_direction(&line).unwrap();
            let (mut lo, mut hi) = (f64::NEG_INFINITY, f64::INFINITY);
            for p in &problem.cameras {
                let p = p / p.fixed_view::<1, 3>(2, 0).norm() * p.fixed_view::<3, 3>(0, 0).determinant().signum();
                let (a, b) = ((p * foot.push(1.0)).z, (p * d.push(0.0)).z);
                if b > 0.0 {
                    lo = lo.max(-a / b);
                } else if b < 0.0 {
                    hi = hi.min(-a / b);
                }
            }
            let (inner_lo, inner_hi) = match (lo.is_finite(), hi.is_finite()) {
                (true, true) => (0.75 * lo + 0.25 * hi, 0.25 * lo + 0.75 * hi),
                (true, false) => (lo + 0.25 * rho, f64::INFINITY),
                (false, true) => (f64::NEG_INFINITY, hi - 0.25 * rho),
                (false, false) => (f64::NEG_INFINITY, f64::INFINITY),
            };
            let t_c = 0.0f64.max(inner_lo).min(inner_hi);
            let h = (rho / 20.0).min(0.5 * (t_c - lo).min(hi - t_c));
            let origin = foot + d * (t_c - h);
            assert!(
                (sim.scale * 2.0 * h - 1.0).abs() < 1e-12,
                "seed {seed}: unit {} vs {}",
                1.0 / sim.scale,
                2.0 * h
            );
            assert!(
                (sim.origin - origin).norm() <= 1e-12 * (1.0 + origin.norm()),
                "seed {seed}"
            );
            checked += 1;
        }
        assert!(checked >= 15, "{checked}");
    }
}
