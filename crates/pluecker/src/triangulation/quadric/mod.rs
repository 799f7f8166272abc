//! Triangulation of a quadric (an ellipsoid) from its outline conics in three or more views
//! (Josephson & Kahl 2008, sections 2.3, 3, 4).
//!
//! The estimate minimises eq. 19, `Σᵢ ‖Lᵢ rᵢ(L)‖²`, over dual quadrics `L` (eq. 10), with `rᵢ` the
//! 5-entry residual of the observed image ellipse (eq. 17 with the normalisation of
//! `residual`) and `Lᵢ` the whitening of its 5x5 covariance (eq. 18; identity without
//! covariances — then the shape entries, in px², dominate: pass covariances from
//! [`super::fitting::fit_conic`]). The three [`Method`]s:
//! - `linear`: Lemma 2.1 stacked over the views with the unknown scales eliminated — each view gives
//!   the 5 equations `N_i L̃ = 0` that say `P_C L̃` is proportional to the observed dual conic
//!   (the numerators of eq. 17) — rows scaled per view by the ellipse's size (pixels² and pixels to
//!   units), solved for the least singular vector in a conditioned world frame, twice (the second
//!   time in a frame centred on the first estimate); then made a proper quadric: the nearest real
//!   ellipsoid (negative eigenvalues of its shape matrix clamped to 0, see [`nearest_ellipsoid`]);
//! - `local`: the trust region of [`crate::optim`] from the linear ellipsoid over its centre, rotation
//!   and signed semi-axes `s` with `L = H diag(s₁², s₂², s₃², −1) Hᵀ` (`H = [R c; 0 1]`): every
//!   iterate is a real ellipsoid (flat when a semi-axis reaches 0), so the result is always proper;
//!   A run that ends flat is tried again from a thin ellipsoid when the cost decreases with the
//!   zero semi-axis (a flat start is a stationary point of the signed semi-axes, see `unflattened`);
//! - `optimal`: the local ellipsoid, certified by the convexity test of `certificate` (every
//!   ellipsoid that no principal plane cuts), or, when the test cannot decide, by branch and bound
//!   (section 4, `optimal`, over an a-priori box).
//!
//! Degenerate input is an error: fewer than 3 views (two views leave a one-parameter family of
//! quadrics tangent to both viewing cones), mismatched lengths, NaN/inf, a singular camera, a conic
//! that is not a real ellipse (named by index), a covariance that is not positive definite, or
//! cameras sharing one centre. An estimate whose centre is behind a camera, or that crosses a
//! camera's principal plane, has status [`Status::BehindCamera`].

pub(crate) mod batch;
pub(crate) mod certificate;
pub(crate) mod optimal;
pub(crate) mod residual;

pub use batch::{triangulate_quadrics, DenseQuadricTracks, QuadricTracks, SparseQuadricTracks};

/// The stages of the quadric solver that the integration tests check directly; not part of the
/// user-facing API.
#[doc(hidden)]
pub mod testing {
    pub use super::residual::ConicFrame;
}

use self::optimal::optimal_quadric;
use self::residual::{quadric_view, ConicFrame};
use super::conditioning::{check_views, Similarity};
use super::fitting::fit_conic;
use super::fractional_residual::{self, FractionalResidual};
use super::uncertainty::{covariance_of_information, QuadricCovariance};
use super::views::{Cameras, View};
use super::{parse_observations, CostKind, Method, Report, Status, TriangulationOptions};
use crate::covariance::whitenings;
use crate::error::{Error, Result};
use crate::geometry::quadric::{
    centre_shape, centre_shape_tangent, dual_of_centre_shape, sym4_to_vec, vec_to_sym4, CentreShape, Ellipsoid,
};
use crate::optim::{trust_region, Linearization, Objective, Summary};
use nalgebra::{Matrix3, Matrix3x4, Matrix4, Rotation3, SMatrix, SVector, Vector2, Vector3};
use std::time::Instant;

/// A 5x5 covariance of a conic residual.
pub type Matrix5 = SMatrix<f64, 5, 5>;

/// A triangulated ellipsoid.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct QuadricTriangulation {
    /// The dual quadric `L` of eq. 10 (world frame), normalised so that `L₄₄ = −1`.
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows"))]
    pub dual: Matrix4<f64>,
    /// The point quadric `C = L⁻¹` of eq. 9, `None` for a flat ellipsoid (a disc).
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows::option"))]
    pub primal: Option<Matrix4<f64>>,
    /// Centre, world units.
    pub centre: Vector3<f64>,
    /// Semi-axis lengths in decreasing order, world units (a zero means a flat ellipsoid).
    pub semi_axes: Vector3<f64>,
    /// Unit axes as columns, in the order of `semi_axes`.
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows"))]
    pub axes: Matrix3<f64>,
    /// The first-order 9x9 covariance of the ellipsoid in the [`crate::geometry::CentreShape`]
    /// chart `(c₁, c₂, c₃, S₁₁, S₁₂, S₁₃, S₂₂, S₂₃, S₃₃)`: centre (world units) and upper triangle of
    /// the shape matrix `S = axes diag(semi_axes²) axesᵀ` (world units²), so that `dual` is
    /// `[S − c cᵀ, −c; −cᵀ, −1]`. `(JᵀJ)⁻¹` with `J` the Jacobian of the whitened residuals of eq. 18
    /// ([`super::uncertainty`]; identity residual covariances when none are given). Computed for every
    /// method and status with a finite estimate; `None` when `JᵀJ` is numerically singular. For a flat
    /// estimate it ignores the constraint `S ⪰ 0` (see [`super::uncertainty`]).
    pub covariance: Option<QuadricCovariance>,
    /// What the method did: status, cost of eq. 19, certificate, iterations, time.
    #[cfg_attr(feature = "serde", serde(flatten))]
    pub report: Report,
}

/// The checked observations of one quadric.
pub(crate) struct QuadricProblem {
    pub cameras: Vec<Matrix3x4<f64>>,
    pub frames: Vec<ConicFrame>,
    pub whitenings: Vec<Matrix5>,
}

impl QuadricProblem {
    /// The whitened residuals of every view in the conditioned frame `sim` (eqs. 14, 17-18).
    pub fn views(&self, sim: &Similarity) -> Vec<FractionalResidual<5, 10>> {
        self.cameras
            .iter()
            .zip(&self.frames)
            .zip(&self.whitenings)
            .map(|((p, f), w)| quadric_view(&sim.camera(p), f, w))
            .collect()
    }

    /// Eq. 19 at a world dual quadric.
    pub fn cost(&self, dual: &Matrix4<f64>) -> f64 {
        fractional_residual::cost(&self.views(&Similarity::identity()), &sym4_to_vec(dual))
    }

    /// The conditioned frame of an ellipsoid: origin at its centre, unit its largest semi-axis (at
    /// least 1e-3 of the distance to the nearest camera).
    pub(crate) fn frame_of(&self, e: &Ellipsoid) -> Similarity {
        let nearest = self
            .cameras
            .iter()
            .map(|p| (super::views::centre(p) - e.centre).norm())
            .fold(f64::INFINITY, f64::min);
        Similarity::around(e.centre, e.semi_axes.max().max(1e-3 * nearest))
    }
}

/// The dual quadric transformed by the similarity: `H L Hᵀ`.
pub(crate) fn transform_dual(sim_matrix: &Matrix4<f64>, dual: &Matrix4<f64>) -> Matrix4<f64> {
    sim_matrix * dual * sim_matrix.transpose()
}

/// The refusal of views through a distorting lens ([`triangulate_quadric`]): [`Error::InvalidOption`] naming `cameras` and the
/// first view whose camera distorts (`cameras[j]`, the camera of `views[j]`, as the Python
/// `cameras=` argument names it).
#[doc(hidden)]
pub fn refuse_distortion(views: &[View]) -> Result<()> {
    let distorting = views
        .iter()
        .enumerate()
        .find_map(|(j, v)| v.camera.distortion().filter(|l| l.distorts()).map(|l| (j, l)));
    match distorting {
        None => Ok(()),
        Some((j, lens)) => Err(Error::InvalidOption {
            name: "cameras".into(),
            reason: format!(
                "cameras[{j}] ({}) has distortion, through which the outline of a quadric is not a conic; \
                 fit the conics to undistorted points (Camera::undistort) and give the pinhole part",
                lens.model().as_str()
            ),
        }),
    }
}

/// The observed outlines of one ellipsoid, one per camera.
#[derive(Debug, Clone, Copy)]
pub enum QuadricObservations<'a> {
    /// Primal image conics (eq. 8, pixels, any scale and sign; each must be a real ellipse), with
    /// optional 5x5 covariances of the conic residuals (one per view, e.g. from
    /// [`super::fitting::fit_conic`]; identity when `None`).
    Conics(&'a [Matrix3<f64>], Option<&'a [Matrix5]>),
    /// Edge points of each outline (pixels, i.i.d. Gaussian noise of `sigma` px per coordinate, the
    /// `f64`): per view, [`fit_conic`] gives the conic and its covariance. Errors name the view index
    /// (`points[i]`).
    EdgePoints(&'a [Vec<Vector2<f64>>], f64),
}

impl<'a> From<&'a [Matrix3<f64>]> for QuadricObservations<'a> {
    fn from(conics: &'a [Matrix3<f64>]) -> Self {
        QuadricObservations::Conics(conics, None)
    }
}

impl<'a> From<&'a Vec<Matrix3<f64>>> for QuadricObservations<'a> {
    fn from(conics: &'a Vec<Matrix3<f64>>) -> Self {
        QuadricObservations::Conics(conics, None)
    }
}

impl<'a, const N: usize> From<&'a [Matrix3<f64>; N]> for QuadricObservations<'a> {
    fn from(conics: &'a [Matrix3<f64>; N]) -> Self {
        QuadricObservations::Conics(conics, None)
    }
}

/// Triangulates one ellipsoid seen by `cameras` as `observations` (its outline conics, or edge points
/// of them, one per camera).
///
/// With [`Cameras::Projections`] (3x4, world → pixels, any positive scale; in front means
/// `(P X̃)₃ > 0`, `views`) the cameras are used as given. With [`Cameras::Views`] (a pinhole or any of
/// COLMAP's models, and a pose): the outline of a quadric seen through a lens with distortion is not a
/// conic (eq. 8 holds for the pinhole projection only), so a view whose camera distorts
/// ([`crate::camera::Camera::distorts`]) is refused with [`Error::InvalidOption`] naming it;
/// pinholes and lenses whose distortion is the identity are solved with their `K [R | t]`.
///
/// Errors: [`Error::TooFewCorrespondences`] for fewer than 3 views, [`Error::Shape`] for mismatched
/// lengths, [`Error::NonFinite`] naming the argument and row, [`Error::SingularCamera`],
/// [`Error::Degenerate`] (a conic that is not an ellipse, too few or degenerate edge points, a
/// covariance that is not positive definite, cameras with one centre), [`Error::InvalidOption`].
pub fn triangulate_quadric<'a>(
    cameras: impl Into<Cameras<'a>>,
    observations: impl Into<QuadricObservations<'a>>,
    opts: &TriangulationOptions,
) -> Result<QuadricTriangulation> {
    let of_views: Vec<Matrix3x4<f64>>;
    let projections = match cameras.into() {
        Cameras::Projections(projections) => projections,
        Cameras::Views(views) => {
            refuse_distortion(views)?;
            of_views = views.iter().map(View::projection).collect();
            &of_views
        }
    };
    match observations.into() {
        QuadricObservations::Conics(conics, covariances) => {
            quadric_of_projections(projections, conics, covariances, opts)
        }
        QuadricObservations::EdgePoints(points, sigma) => quadric_of_points(projections, points, sigma, opts),
    }
}

/// [`triangulate_quadric`] of conics seen by projections.
pub(crate) fn quadric_of_projections(
    projections: &[Matrix3x4<f64>],
    conics: &[Matrix3<f64>],
    covariances: Option<&[Matrix5]>,
    opts: &TriangulationOptions,
) -> Result<QuadricTriangulation> {
    let started = Instant::now();
    opts.validate()?;
    opts.reject_outlier_threshold("quadrics")?;
    check_views(projections, conics.len(), 3, "conics", opts.method)?;
    let frames = parse_observations(conics, "conics", "is not a real ellipse", ConicFrame::of_conic)?;
    let problem = QuadricProblem {
        cameras: projections.to_vec(),
        frames,
        whitenings: whitenings(covariances, projections.len(), "covariances")?,
    };
    let mut report = Report::new(opts.method, CostKind::ConicResidual);
    let Some(linear) = linear_quadric(&problem) else {
        report.status = Status::NumericalFailure;
        report.time_seconds = started.elapsed().as_secs_f64();
        let nan = Ellipsoid {
            centre: Vector3::repeat(f64::NAN),
            axes: Matrix3::repeat(f64::NAN),
            semi_axes: Vector3::repeat(f64::NAN),
        };
        return Ok(finish(&problem, &nan, report));
    };
    report.cost = problem.cost(&linear.dual());
    let estimate = match opts.method {
        Method::Linear => linear,
        Method::Local => {
            let (e, local) = local_quadric(&problem, &linear, opts);
            report = local;
            e
        }
        Method::Optimal => {
            let (e, local) = local_quadric(&problem, &linear, opts);
            let (best, optimal) = optimal_quadric(&problem, &e, &local, opts);
            report = optimal;
            best
        }
    };
    let mut result = finish(&problem, &estimate, report);
    result.report.time_seconds = started.elapsed().as_secs_f64();
    Ok(result)
}

/// The result record of an ellipsoid; sets [`Status::BehindCamera`] when it is not entirely in front
/// of every camera (module docs).
fn finish(problem: &QuadricProblem, e: &Ellipsoid, mut report: Report) -> QuadricTriangulation {
    report.test_residuals(5 * problem.cameras.len(), 9);
    let dual = e.dual();
    let in_front = problem.cameras.iter().all(|p| {
        let p = super::views::depth_normalized(p);
        let row = p.row(2).transpose();
        (p * e.centre.push(1.0)).z > 0.0 && row.dot(&(dual * row)) < 0.0
    });
    if !in_front && e.centre.iter().all(|v| v.is_finite()) {
        report.set_status(Status::BehindCamera);
    }
    QuadricTriangulation {
        dual,
        primal: e.primal(),
        centre: e.centre,
        semi_axes: e.semi_axes,
        axes: e.axes,
        covariance: quadric_covariance(problem, e),
        report,
    }
}

/// [`triangulate_quadric`] from edge points seen by projections.
fn quadric_of_points(
    projections: &[Matrix3x4<f64>],
    points: &[Vec<Vector2<f64>>],
    sigma: f64,
    opts: &TriangulationOptions,
) -> Result<QuadricTriangulation> {
    let mut conics = Vec::with_capacity(points.len());
    let mut covariances = Vec::with_capacity(points.len());
    for (i, pts) in points.iter().enumerate() {
        let fit = fit_conic(pts, sigma).map_err(|e| match e {
            Error::Degenerate { what } => Error::Degenerate {
                what: format!("points[{i}]: {what}"),
            },
            Error::NonFinite { index, .. } => Error::NonFinite {
                what: format!("points[{i}]"),
                index,
            },
            other => other,
        })?;
        conics.push(fit.conic);
        covariances.push(fit.covariance);
    }
    quadric_of_projections(projections, &conics, Some(&covariances), opts)
}

/// The nearest real ellipsoid of a dual quadric of any scale and sign: normalised so that
/// `L₄₄ = −1`, the centre read from its last column and the negative eigenvalues of its shape
/// matrix `R diag(s²) Rᵀ` clamped to 0. `None` when `L₄₄ = 0` or no eigenvalue is positive.
pub fn nearest_ellipsoid(dual: &Matrix4<f64>) -> Option<Ellipsoid> {
    let q44 = dual[(3, 3)];
    if !(q44.abs() > 0.0) || !dual.iter().all(|v| v.is_finite()) {
        return None;
    }
    let q = dual / -q44;
    let centre: Vector3<f64> = -q.fixed_view::<3, 1>(0, 3).into_owned();
    let top: Matrix3<f64> = q.fixed_view::<3, 3>(0, 0).into_owned();
    let shape = top + centre * centre.transpose();
    let eig = (0.5 * (shape + shape.transpose())).symmetric_eigen();
    if !(eig.eigenvalues.max() > 0.0) {
        return None;
    }
    let clamped =
        eig.eigenvectors * Matrix3::from_diagonal(&eig.eigenvalues.map(|v| v.max(0.0))) * eig.eigenvectors.transpose();
    let mut rebuilt = Matrix4::zeros();
    rebuilt
        .fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&(clamped - centre * centre.transpose()));
    rebuilt.fixed_view_mut::<3, 1>(0, 3).copy_from(&(-centre));
    rebuilt.fixed_view_mut::<1, 3>(3, 0).copy_from(&(-centre.transpose()));
    rebuilt[(3, 3)] = -1.0;
    Ellipsoid::from_dual(&rebuilt)
}

/// One pass of the linear method (module docs) in the frame `sim`: the world dual quadric.
fn linear_pass(problem: &QuadricProblem, sim: &Similarity) -> Option<Matrix4<f64>> {
    let mut normal = SMatrix::<f64, 10, 10>::zeros();
    for (p, frame) in problem.cameras.iter().zip(&problem.frames) {
        // Rows scaled by the ellipse's size: px² for the shape entries, px for the centre entries.
        let shape = self::residual::observed_shape(frame);
        let size = shape.trace().abs().sqrt().max(f64::MIN_POSITIVE);
        let w = Matrix5::from_diagonal(
            &(SVector::<f64, 5>::from_column_slice(&[1.0, 1.0, 1.0, size, size]) / (size * size)),
        );
        let view = quadric_view(&sim.camera(p), frame, &w);
        for r in 0..5 {
            let row = view.numerator.row(r);
            let norm2 = row.norm_squared();
            if norm2 > 0.0 {
                normal += row.transpose() * row / norm2.sqrt();
            }
        }
    }
    let eig = normal.symmetric_eigen();
    let q = eig.eigenvectors.column(eig.eigenvalues.imin()).into_owned();
    let inverse = sim.inverse_matrix();
    Some(transform_dual(&inverse, &vec_to_sym4(&q))).filter(|d| d.iter().all(|v| v.is_finite()))
}

/// The linear method (module docs): `None` when no real ellipsoid comes out.
pub(crate) fn linear_quadric(problem: &QuadricProblem) -> Option<Ellipsoid> {
    let first = nearest_ellipsoid(&linear_pass(problem, &Similarity::of_cameras(&problem.cameras))?)?;
    let second = linear_pass(problem, &problem.frame_of(&first)).and_then(|d| nearest_ellipsoid(&d));
    Some(second.unwrap_or(first))
}

/// An ellipsoid with signed semi-axes: the point of the local method's search space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct EllipsoidPoint {
    pub centre: Vector3<f64>,
    pub rotation: Matrix3<f64>,
    pub s: Vector3<f64>,
}

impl EllipsoidPoint {
    pub fn of(e: &Ellipsoid) -> EllipsoidPoint {
        EllipsoidPoint {
            centre: e.centre,
            rotation: e.axes,
            s: e.semi_axes,
        }
    }

    fn h(&self) -> Matrix4<f64> {
        let mut h = Matrix4::identity();
        h.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.rotation);
        h.fixed_view_mut::<3, 1>(0, 3).copy_from(&self.centre);
        h
    }

    /// `L = H diag(s², −1) Hᵀ`.
    pub fn dual(&self) -> Matrix4<f64> {
        let d = Matrix4::from_diagonal(&self.s.map(|v| v * v).push(-1.0));
        let h = self.h();
        h * d * h.transpose()
    }

    /// `∂L̃/∂δ` (10x9) for `δ = (δc, ω, δs)` with `c ← c + δc`, `R ← R exp([ω]ₓ)`, `s ← s + δs`.
    pub fn tangent(&self) -> SMatrix<f64, 10, 9> {
        let h = self.h();
        let d = Matrix4::from_diagonal(&self.s.map(|v| v * v).push(-1.0));
        let mut t = SMatrix::<f64, 10, 9>::zeros();
        for k in 0..3 {
            let e = Vector3::ith(k, 1.0);
            let mut dh = Matrix4::zeros();
            dh.fixed_view_mut::<3, 1>(0, 3).copy_from(&e);
            t.set_column(k, &sym4_to_vec(&(dh * d * h.transpose() + h * d * dh.transpose())));
            let mut dr = Matrix4::zeros();
            dr.fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&(self.rotation * e.cross_matrix()));
            t.set_column(3 + k, &sym4_to_vec(&(dr * d * h.transpose() + h * d * dr.transpose())));
            let mut ds = Matrix4::zeros();
            ds[(k, k)] = 2.0 * self.s[k];
            t.set_column(6 + k, &sym4_to_vec(&(h * ds * h.transpose())));
        }
        t
    }

    pub(crate) fn retract(&self, d: &SVector<f64, 9>) -> EllipsoidPoint {
        let r = Rotation3::new(Vector3::new(d[3], d[4], d[5]));
        EllipsoidPoint {
            centre: self.centre + Vector3::new(d[0], d[1], d[2]),
            rotation: self.rotation * r.matrix(),
            s: self.s + Vector3::new(d[6], d[7], d[8]),
        }
    }

    /// The ellipsoid (semi-axes `|s|`, sorted) in the world, from a point in the frame `sim`.
    pub fn to_world(self, sim: &Similarity) -> Option<Ellipsoid> {
        Ellipsoid::from_dual(&transform_dual(&sim.inverse_matrix(), &self.dual()))
    }
}

/// Eq. 19 over [`EllipsoidPoint`]s, in a conditioned frame.
pub(crate) struct QuadricObjective<'a> {
    pub views: &'a [FractionalResidual<5, 10>],
}

impl Objective<9> for QuadricObjective<'_> {
    type Point = EllipsoidPoint;

    fn cost(&self, x: &EllipsoidPoint) -> f64 {
        0.5 * fractional_residual::cost(self.views, &sym4_to_vec(&x.dual()))
    }

    fn linearize(&self, x: &EllipsoidPoint) -> Linearization<9> {
        fractional_residual::linearize(self.views, &sym4_to_vec(&x.dual()), &x.tangent())
    }

    fn retract(&self, x: &EllipsoidPoint, d: &SVector<f64, 9>) -> EllipsoidPoint {
        x.retract(d)
    }
}

/// The local method from `start` (world): the minimised ellipsoid and its report.
pub(crate) fn local_quadric(
    problem: &QuadricProblem,
    start: &Ellipsoid,
    opts: &TriangulationOptions,
) -> (Ellipsoid, Report) {
    let sim = problem.frame_of(start);
    let views = problem.views(&sim);
    let x0 = EllipsoidPoint::of(&Ellipsoid::from_dual(&transform_dual(&sim.matrix(), &start.dual())).unwrap_or(*start));
    let objective = QuadricObjective { views: &views };
    let (mut x, mut summary) = trust_region::minimize(&objective, x0, &opts.local);
    // At most one escape per semi-axis.
    for _ in 0..3 {
        let Some(thin) = unflattened(&views, &x) else {
            break;
        };
        let (y, again) = trust_region::minimize(&objective, thin, &opts.local);
        if !(again.final_cost < summary.final_cost) {
            break;
        }
        x = y;
        summary = Summary {
            iterations: summary.iterations + again.iterations,
            evaluations: summary.evaluations + again.evaluations,
            initial_cost: summary.initial_cost,
            ..again
        };
    }
    let world = x.to_world(&sim).unwrap_or(*start);
    (world, Report::of_local(&summary, CostKind::ConicResidual))
}

/// Semi-axes at most this fraction of the largest count as zero for [`unflattened`].
const FLAT: f64 = 1e-6;

/// A flat ellipsoid (a semi-axis at 0) is a stationary point of the cost over [`EllipsoidPoint`]s
/// whatever the data say, the cost depending on `s²` only: the local method started flat (the linear
/// method clamps a negative eigenvalue of the shape to 0) stays flat even where a thin ellipsoid fits
/// better. When the cost decreases with `s_k²` at a zero `s_k`, the start of a second run:
/// `s_k² = −f'/f''`, the Gauss-Newton step along `s_k²` (tangent `∂L/∂(s_k²) = hₖhₖᵀ`, `hₖ` the
/// `k`-th column of `H`). `None` when no semi-axis is zero or none should grow.
fn unflattened(views: &[FractionalResidual<5, 10>], x: &EllipsoidPoint) -> Option<EllipsoidPoint> {
    let largest = x.s.abs().max();
    let z = sym4_to_vec(&x.dual());
    (0..3).filter(|&k| x.s[k].abs() <= FLAT * largest).find_map(|k| {
        let column = x.h().column(k).into_owned();
        let tangent = SMatrix::<f64, 10, 1>::from_column_slice(sym4_to_vec(&(column * column.transpose())).as_slice());
        let lin = fractional_residual::linearize(views, &z, &tangent);
        let (slope, curvature) = (lin.gradient[0], lin.gauss_newton[(0, 0)]);
        (slope < 0.0 && curvature > 0.0).then(|| {
            let mut thin = *x;
            thin.s[k] = (-slope / curvature).sqrt();
            thin
        })
    })
}

/// The 9x9 covariance of an ellipsoid in the [`CentreShape`] chart ([`super::uncertainty`]), computed in the
/// frame of [`QuadricProblem::frame_of`] (origin at the centre, unit the largest semi-axis) and
/// scaled back: centre entries by that unit, shape entries by its square.
pub(crate) fn quadric_covariance(problem: &QuadricProblem, e: &Ellipsoid) -> Option<QuadricCovariance> {
    let dual = e.dual();
    if !dual.iter().all(|v| v.is_finite()) {
        return None;
    }
    let sim = problem.frame_of(e);
    let framed: CentreShape = centre_shape(&transform_dual(&sim.matrix(), &dual))?;
    let views = problem.views(&sim);
    let tangent = centre_shape_tangent(&Vector3::new(framed[0], framed[1], framed[2]));
    let info =
        fractional_residual::linearize(&views, &sym4_to_vec(&dual_of_centre_shape(&framed)), &tangent).gauss_newton;
    let framed_cov = covariance_of_information(&info)?;
    let unit = 1.0 / sim.scale;
    let d = CentreShape::from_fn(|k, _| if k < 3 { unit } else { unit * unit });
    Some(QuadricCovariance::from_diagonal(&d) * framed_cov * QuadricCovariance::from_diagonal(&d))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::problem::testing::gradient_error;
    use crate::triangulation::scenes::quadric_scene;

    #[test]
    fn tangent_matches_central_differences_and_the_objective_gradient_is_right() {
        let scene = quadric_scene(4, 0.8, 3);
        let x = EllipsoidPoint {
            centre: Vector3::new(0.1, -0.2, 0.05),
            rotation: Rotation3::new(Vector3::new(0.3, 0.1, -0.2)).into_inner(),
            s: Vector3::new(0.4, 0.3, 0.2),
        };
        let t = x.tangent();
        for k in 0..9 {
            let mut d = SVector::<f64, 9>::zeros();
            d[k] = 1e-6;
            let fd = (sym4_to_vec(&x.retract(&d).dual()) - sym4_to_vec(&x.retract(&-d).dual())) / 2e-6;
            assert!((fd - t.column(k)).norm() < 1e-8, "column {k}");
        }
        let frames: Vec<ConicFrame> = scene
            .outlines
            .iter()
            .map(|e| ConicFrame::of_conic(&e.primal()).unwrap())
            .collect();
        let problem = QuadricProblem {
            cameras: scene.cameras.clone(),
            frames,
            whitenings: vec![Matrix5::identity() * 0.1; 4],
        };
        let views = problem.views(&Similarity::identity());
        assert!(gradient_error(&QuadricObjective { views: &views }, &x, 1e-6) < 1e-5);
    }

    #[test]
    fn a_thin_ellipsoid_is_found_from_a_flat_start() {
        // Started flat, the local method would stay flat (the cost depends on s² only); the escape
        // of `unflattened` finds the thin ellipsoid of the exact outlines.
        let scene = quadric_scene(4, 0.8, 3);
        let thin = Ellipsoid {
            semi_axes: Vector3::new(0.4, 0.3, 0.03),
            ..scene.ellipsoid
        };
        let frames: Vec<ConicFrame> = scene
            .cameras
            .iter()
            .map(|p| {
                ConicFrame::of_conic(
                    &crate::geometry::quadric::project_dual(p, &thin.dual())
                        .try_inverse()
                        .unwrap(),
                )
                .unwrap()
            })
            .collect();
        let problem = QuadricProblem {
            cameras: scene.cameras.clone(),
            frames,
            whitenings: vec![Matrix5::identity(); 4],
        };
        let flat = Ellipsoid {
            semi_axes: Vector3::new(0.4, 0.3, 0.0),
            ..thin
        };
        let (e, report) = local_quadric(&problem, &flat, &TriangulationOptions::default());
        assert!((e.semi_axes - thin.semi_axes).norm() < 1e-6, "{:?}", e.semi_axes);
        assert!(report.cost < 1e-10, "{}", report.cost);
    }

    #[test]
    fn nearest_ellipsoid_keeps_ellipsoids_and_clamps_the_rest() {
        let e = Ellipsoid {
            centre: Vector3::new(1.0, 2.0, 3.0),
            axes: Matrix3::identity(),
            semi_axes: Vector3::new(3.0, 2.0, 1.0),
        };
        let back = nearest_ellipsoid(&(e.dual() * 2.5)).unwrap();
        assert!((back.semi_axes - e.semi_axes).norm() < 1e-12 && (back.centre - e.centre).norm() < 1e-12);
        // A hyperboloid of one sheet: the negative axis is clamped to a flat ellipsoid.
        let mut d = e.dual();
        d[(2, 2)] -= 2.0; // shape eigenvalue 1 → −1 on the third axis
        let flat = nearest_ellipsoid(&d).unwrap();
        assert!(flat.semi_axes.z == 0.0 && (flat.semi_axes.x - 3.0).abs() < 1e-12);
        assert!(nearest_ellipsoid(&Matrix4::from_diagonal(&nalgebra::Vector4::new(-1.0, -1.0, -1.0, -1.0))).is_none());
    }
}
