//! Triangulation of a point from two or more views (Josephson & Kahl 2008, sections 2.1, 3, 4).
//!
//! The estimate minimises eq. 19, `Σᵢ ‖Lᵢ rᵢ(X)‖²`, the reprojection error of eq. 15 whitened by the
//! observation covariances (eq. 18; squared pixels without covariances), over points in front of
//! every camera (`λ > 0` in eq. 1). The three [`Method`]s:
//! - `linear`: the DLT with conditioning (`linear`);
//! - `local`: the trust region of [`crate::optim`] on eq. 19 from the linear point
//!   (`cost`); when that start is behind a camera (or at infinity), from the best point
//!   in front of every camera on one of the back-projected rays instead;
//! - `optimal`: the local solution, certified by the convexity test of
//!   `certificate` when it passes, else by branch and bound
//!   (`global`; the relaxation of each fraction is the secant envelope by default,
//!   eqs. 21-22 on request), which may also return a better point than the local one.
//!
//! **Statuses of `optimal`.** `Success` when certified (the gap closed, whatever the local stage's
//! termination); `GapNotClosed` at the node cap or when the search set could not be boxed;
//! `NumericalFailure` when a conic solve of the initial box failed (no certificate);
//! `BehindCamera`/`AtInfinity`
//! when no start in front of every camera was found or when the infimum over the points in front
//! is not reached at a finite point (below). The certificate's relative gap is
//! `(cost − lower_bound) / max(cost, 1e-12)`: a cost at the rounding level (exact data) counts as
//! certified by the trivial bound 0. The bound covers every point in front of the cameras.
//!
//! The DLT cannot see that a point lies behind the cameras; the other methods search in front of
//! every camera only. When the observations are best explained behind the cameras (the rays diverge
//! in front) or by parallel rays, the infimum over the points in front is approached only at
//! infinity and the minimisation runs off towards it. Then (`infinity`: a point at
//! infinity costs no more than the estimate) `local` and `optimal` report `BehindCamera` with the DLT
//! point when that point is behind a camera and cheaper than every point at infinity, else
//! `AtInfinity` with a NaN point and the cost at infinity — never a far point as a success.
//! `optimal` checks this after branch and bound (whose search set includes the points at infinity),
//! `local` when it stopped on its iteration cap or more than 1000 camera spreads away.
//!
//! Degenerate input is an error: fewer than two views, mismatched lengths, NaN/inf, a singular
//! camera, a covariance that is not positive definite, or cameras sharing one centre (no parallax).
//! A solve that runs but fails reports it in [`Report::status`].

pub(crate) mod batch;
pub(crate) mod certificate;
pub(crate) mod chart;
pub(crate) mod cost;
pub(crate) mod global;
pub(crate) mod infinity;
pub(crate) mod lens;
pub(crate) mod linear;
pub(crate) mod robust;

pub use batch::{triangulate_points, DensePointTracks, LinearPoints, PointTracks, SparsePointTracks};

/// The stages of the point solvers that the integration tests check directly; not part of the
/// user-facing API.
#[doc(hidden)]
pub mod testing {
    pub use super::certificate::{convexity_test, ConvexityCertificate};
    pub use super::cost::{in_front, point_cost, point_views, PointView};
    pub use super::global::{global_point, GlobalPoint, GlobalSettings, GlobalStatus, Relaxation};
    pub use super::lens::{exact_cost, lens_certificate, LensBound, LensBoundFailure, LensView};
}

use self::certificate::convexity_test;
use self::chart::{Chart, ChartKind};
use self::cost::{in_front, point_cost, point_views, PointObjective, PointView};
use self::global::{global_point, GlobalSettings, GlobalStatus, DEFAULT_RELAXATION};
use self::infinity::best_at_infinity;
use self::lens::LensView;
use self::linear::{frame_of_cameras, linear_point, LinearPoint, WorldFrame};
use super::uncertainty::covariance_of_information3;
use super::views::{baseline, centre, depth_normalized, validate_cameras, Cameras, View};
use super::{Certificate, CertificateKind, CostKind, Method, Report, Status, TriangulationOptions};
use crate::certificate::Primitive;
use crate::covariance::whitenings;
use crate::error::{Error, Result};
use crate::global::relative_gap;
use crate::optim::{trust_region, Termination};
use nalgebra::{Matrix2, Matrix3, Matrix3x4, Vector2, Vector3};
use std::time::Instant;

/// Centres closer than this, relative to their distance from the origin (at least 1), coincide.
const SAME_CENTRE: f64 = 1e-10;
/// Depths tried along each back-projected ray for a start in front of the cameras: log-spaced from
/// `10^-2` camera spreads to the given maximum.
const RAY_DEPTHS: usize = 33;
/// The farthest start of the local method, in camera spreads (parallax ~ 1e-6 rad).
const FARTHEST_START: f64 = 1e6;
/// The farthest chart origin of branch and bound, in camera spreads (parallax ~ 1e-3 rad), where
/// the Gauss-Newton Hessian is still well conditioned.
const FARTHEST_ORIGIN: f64 = 1e3;

/// A triangulated point.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PointTriangulation {
    /// The point, world coordinates (NaN when the status is [`Status::AtInfinity`]).
    pub point: Vector3<f64>,
    /// The first-order 3x3 covariance of `point` (world units², [`super::uncertainty`]): `(JᵀJ)⁻¹`
    /// with `J` the Jacobian of the whitened residuals of eq. 18 at `point` (1 px isotropic noise per
    /// view without covariances). Computed for every method and status whenever `point` is finite;
    /// `None` when it is not, or when `JᵀJ` is numerically singular (a point at or near infinity).
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows::option"))]
    pub covariance: Option<Matrix3<f64>>,
    /// What the method did: status, cost of eq. 19, certificate, iterations, time.
    #[cfg_attr(feature = "serde", serde(flatten))]
    pub report: Report,
    /// With [`TriangulationOptions::outlier_threshold`], one flag per view of the track (in its
    /// order): the observations the point was solved from (`robust`). `None` otherwise.
    pub inliers: Option<Vec<bool>>,
}

/// Triangulates one point seen by `cameras` at the pixels `observations` (one per camera), with
/// optional 2x2 pixel covariances (one per view; identity when `None`).
///
/// With [`Cameras::Projections`] (3x4, world → pixels, any positive scale; in front means
/// `(P X̃)₃ > 0`, `views`) the cost is eq. 19. With [`Cameras::Views`] (each a camera, pinhole or any
/// of COLMAP's models, and its pose) the observations are the images' own (distorted) pixels, the
/// cost is the reprojection error in those pixels through the exact projection, and `optimal`
/// certifies it with `lens::lens_certificate` (interval bounds of the lenses' Jacobians); with pinhole
/// cameras only it is the problem of their matrices `K [R | t]`.
///
/// Errors: [`Error::TooFewCorrespondences`] for fewer than 2 views, [`Error::Shape`] for mismatched
/// lengths, [`Error::NonFinite`] naming the argument and row, [`Error::SingularCamera`],
/// [`Error::Degenerate`] for a covariance that is not positive definite, cameras with one common
/// centre, or (views) an observation whose pixel has no preimage inside its lens's fold,
/// [`Error::InvalidOption`] for bad options.
///
/// Through a COLMAP camera model (here SIMPLE_RADIAL), from the raw, distorted pixels: the point
/// minimises the reprojection error in each image's own pixels.
/// ```
/// use pluecker::nalgebra::{Matrix3, Vector3};
/// use pluecker::camera::{Camera, CameraModel};
/// use pluecker::triangulation::{point::triangulate_point, TriangulationOptions, View};
/// use pluecker::Pose;
/// let lens = Camera::new(CameraModel::SimpleRadial, &[800.0, 320.0, 240.0, -0.1]).unwrap();
/// let views = [
///     View::new(lens.clone(), Pose::new(Matrix3::identity(), Vector3::zeros())),
///     View::new(lens.clone(), Pose::new(Matrix3::identity(), Vector3::new(-1.0, 0.0, 0.0))),
/// ];
/// let x = Vector3::new(0.3, -0.2, 5.0);
/// let pixels: Vec<_> = views.iter().map(|v| lens.project(&(v.pose.rotation * x + v.pose.translation))).collect();
/// let result = triangulate_point(&views, &pixels, None, &TriangulationOptions::default()).unwrap();
/// assert!((result.point - x).norm() < 1e-6);
/// assert!(result.report.certified());
/// ```
pub fn triangulate_point<'a>(
    cameras: impl Into<Cameras<'a>>,
    observations: &[Vector2<f64>],
    covariances: Option<&[Matrix2<f64>]>,
    opts: &TriangulationOptions,
) -> Result<PointTriangulation> {
    match cameras.into() {
        Cameras::Projections(projections) => point_of_projections(projections, observations, covariances, opts),
        Cameras::Views(views) => point_of_views(views, observations, covariances, opts),
    }
}

/// [`triangulate_point`] with 3x4 projections.
fn point_of_projections(
    projections: &[Matrix3x4<f64>],
    observations: &[Vector2<f64>],
    covariances: Option<&[Matrix2<f64>]>,
    opts: &TriangulationOptions,
) -> Result<PointTriangulation> {
    let started = Instant::now();
    let whitening = checked_track(projections, "cameras", observations, covariances, opts)?;
    let normalized: Vec<Matrix3x4<f64>> = projections.iter().map(depth_normalized).collect();
    let views = point_views(&normalized, observations, &whitening);
    Ok(solve_track_views(
        views.as_slice(),
        &frame_of_cameras(projections),
        opts,
        started,
    ))
}

/// [`triangulate_point`] with views.
fn point_of_views(
    views: &[View],
    observations: &[Vector2<f64>],
    covariances: Option<&[Matrix2<f64>]>,
    opts: &TriangulationOptions,
) -> Result<PointTriangulation> {
    let started = Instant::now();
    let cameras: Vec<Matrix3x4<f64>> = views.iter().map(View::projection).collect();
    let whitening = checked_track(&cameras, "views", observations, covariances, opts)?;
    let lens_views: Vec<LensView> = views
        .iter()
        .zip(observations)
        .zip(&whitening)
        .map(|((v, x), l)| LensView::new(v, *x, *l))
        .collect();
    lens::solve_lens_track(&lens_views, &frame_of_cameras(&cameras), opts, started)
}

/// The checks of one track's input (errors of [`triangulate_point`]; `what` names the cameras), and
/// its whitening factors.
fn checked_track(
    cameras: &[Matrix3x4<f64>],
    what: &str,
    observations: &[Vector2<f64>],
    covariances: Option<&[Matrix2<f64>]>,
    opts: &TriangulationOptions,
) -> Result<Vec<Matrix2<f64>>> {
    opts.validate()?;
    check_track(cameras, observations, opts.method)?;
    validate_cameras(cameras, what)?;
    if let Some(row) = observations.iter().position(|x| !(x.x.is_finite() && x.y.is_finite())) {
        return Err(Error::NonFinite {
            what: "observations".into(),
            index: row,
        });
    }
    let whitening = whitenings(covariances, cameras.len(), "covariances")?;
    check_parallax(cameras, what)?;
    Ok(whitening)
}

/// [`solve_views`] on the track's first-order views, or its robust form when
/// `opts.outlier_threshold` is set (whose decisions use each view's own residual).
pub(crate) fn solve_track_views<T: robust::RobustTrack + ?Sized>(
    track: &T,
    frame: &WorldFrame,
    opts: &TriangulationOptions,
    started: Instant,
) -> PointTriangulation {
    match opts.outlier_threshold {
        None => solve_views(track.first_order(), frame, opts, started),
        Some(tau) => robust::solve_views_robust(track, frame, opts, tau, started),
    }
}

/// At least two views and one observation per camera.
pub(crate) fn check_track(cameras: &[Matrix3x4<f64>], observations: &[Vector2<f64>], method: Method) -> Result<()> {
    if cameras.len() < 2 {
        return Err(Error::TooFewCorrespondences {
            method: method.as_str().into(),
            required: "2 views of the point".into(),
            actual: format!("{} view(s)", cameras.len()),
        });
    }
    if observations.len() != cameras.len() {
        return Err(Error::Shape {
            what: "observations".into(),
            expected: format!("{} points (one per camera)", cameras.len()),
            actual: format!("{}", observations.len()),
        });
    }
    Ok(())
}

/// [`Error::Degenerate`] when every camera has the same centre (no parallax).
pub(crate) fn check_parallax(cameras: &[Matrix3x4<f64>], what: &str) -> Result<()> {
    let scale = cameras.iter().map(|p| centre(p).norm()).fold(1.0, f64::max);
    if baseline(cameras) <= SAME_CENTRE * scale {
        return Err(Error::Degenerate {
            what: format!("{what}: all camera centres coincide (no parallax)"),
        });
    }
    Ok(())
}

/// The chosen method on prepared views (checked input); `started` times the whole call.
pub(crate) fn solve_views(
    views: &[PointView],
    frame: &WorldFrame,
    opts: &TriangulationOptions,
    started: Instant,
) -> PointTriangulation {
    let linear = linear_point(views, frame);
    let mut report = Report::new(opts.method, CostKind::Reprojection);
    let finish = |point: Vector3<f64>, mut report: Report| {
        let covariance = point_covariance(views, &point);
        report.test_residuals(2 * views.len(), 3);
        report.time_seconds = started.elapsed().as_secs_f64();
        PointTriangulation {
            point,
            covariance,
            report,
            inliers: None,
        }
    };
    if opts.method == Method::Linear {
        return match linear {
            LinearPoint::Finite(x) => {
                report.cost = point_cost(views, &x);
                report.status = if in_front(views, &x) {
                    Status::Success
                } else {
                    Status::BehindCamera
                };
                finish(x, report)
            }
            LinearPoint::AtInfinity(_) => {
                report.status = Status::AtInfinity;
                finish(Vector3::repeat(f64::NAN), report)
            }
        };
    }
    let Some((x, termination, iterations)) = local_solution(views, frame, linear, opts) else {
        report.status = Status::AtInfinity;
        return finish(Vector3::repeat(f64::NAN), report);
    };
    report.cost = point_cost(views, &x);
    report.iterations = iterations;
    report.termination = termination;
    report.status = match termination {
        Termination::NonFiniteCost | Termination::SingularHessian => Status::NumericalFailure,
        _ if !in_front(views, &x) => Status::BehindCamera,
        Termination::MaxIterations => Status::NotConverged,
        _ => Status::Success,
    };
    if matches!(report.status, Status::NumericalFailure | Status::BehindCamera) {
        return finish(x, report);
    }
    let settle = |u: Unreached, mut report: Report| {
        report.set_status(u.status);
        report.cost = u.cost;
        finish(u.point, report)
    };
    if opts.method == Method::Local {
        // A local minimisation that ran off towards infinity: say where its infimum lies.
        let far = (x - frame.centre).norm() > FARTHEST_ORIGIN * frame.scale;
        if report.status == Status::NotConverged || far {
            if let Some(u) = unreached(views, frame, &x, report.cost, linear, opts) {
                return settle(u, report);
            }
        }
        return finish(x, report);
    }
    if let LinearPoint::AtInfinity(_) = linear {
        // Parallel rays: when the point at infinity fits at least as well as the best finite point
        // found, eq. 19 has no finite minimiser worth reporting (branch and bound would only chase
        // it outwards).
        if let Some(u) = unreached(views, frame, &x, report.cost, linear, opts) {
            return settle(u, report);
        }
    }
    let (x, status, certificate, cost) = certify(views, frame, x, report.cost, linear, opts);
    report.status = status;
    // A search that proved nothing (it failed before its first bound) leaves no certificate.
    report.certificate = (!certificate.raw_lower_bound.is_nan()).then_some(certificate);
    report.cost = cost;
    if certificate.kind == CertificateKind::BranchAndBound && matches!(status, Status::Success | Status::GapNotClosed) {
        // Branch and bound searches the closure of the points in front, infinity included: its best
        // finite point may be a far point on the way there (module docs of `infinity`).
        if let Some(u) = unreached(views, frame, &x, cost, linear, opts) {
            report.certificate = certificate_when_unreached(&certificate, &u);
            return settle(u, report);
        }
    }
    finish(x, report)
}

/// The certificate of branch and bound once [`unreached`] has spoken: never certified; for a point
/// at infinity the lower bound (valid over the points in front, infinity included) and the gap to
/// the cost there are kept; a point behind a camera is outside the searched set, so nothing is
/// (`None`).
fn certificate_when_unreached(certificate: &Certificate, u: &Unreached) -> Option<Certificate> {
    (u.status == Status::AtInfinity && !certificate.raw_lower_bound.is_nan()).then(|| {
        let lower_bound = certificate.lower_bound.min(u.cost);
        Certificate::new(
            certificate.kind,
            certificate.primitive,
            lower_bound,
            certificate.raw_lower_bound,
            relative_gap(u.cost, lower_bound),
            false,
        )
        .with_effort(certificate.nodes, certificate.solver_iterations)
    })
}

/// The outcome of a solve whose infimum over points in front of every camera is not reached at a
/// finite point ([`unreached`]).
struct Unreached {
    point: Vector3<f64>,
    status: Status,
    cost: f64,
}

/// `Some` when a point at infinity in front of every camera costs no more than the finite estimate
/// `x` of cost `cost` (module docs of [`self::infinity`]). Then the data are best explained
/// behind a camera — status [`Status::BehindCamera`] with the DLT point, when that point is finite,
/// behind a camera and cheaper than the best point at infinity — or else at infinity — status
/// [`Status::AtInfinity`], a NaN point and the cost there. The best direction is searched from `x`
/// seen from the cameras' centroid and from the DLT's direction when the DLT is at infinity.
fn unreached(
    views: &[PointView],
    frame: &WorldFrame,
    x: &Vector3<f64>,
    cost: f64,
    linear: LinearPoint,
    opts: &TriangulationOptions,
) -> Option<Unreached> {
    let mut starts = vec![x - frame.centre];
    if let LinearPoint::AtInfinity(d) = linear {
        starts.push(d);
    }
    let (_, at_infinity) = best_at_infinity(views, &starts, &opts.local)?;
    if at_infinity > cost {
        return None;
    }
    Some(match linear {
        LinearPoint::Finite(p) if !in_front(views, &p) && point_cost(views, &p) < at_infinity => Unreached {
            point: p,
            status: Status::BehindCamera,
            cost: point_cost(views, &p),
        },
        _ => Unreached {
            point: Vector3::repeat(f64::NAN),
            status: Status::AtInfinity,
            cost: at_infinity,
        },
    })
}

/// The local minimum of eq. 19 from the linear point, or from a start in front of the cameras when
/// that one is behind a camera, at infinity, or ends behind one. `None` when no start exists.
pub(crate) fn local_solution(
    views: &[PointView],
    frame: &WorldFrame,
    linear: LinearPoint,
    opts: &TriangulationOptions,
) -> Option<(Vector3<f64>, Termination, usize)> {
    let objective = PointObjective { views };
    let run = |x0: Vector3<f64>| {
        let (x, summary) = trust_region::minimize(&objective, x0, &opts.local);
        (x, summary.termination, summary.iterations)
    };
    let from_linear = match linear {
        LinearPoint::Finite(x) => Some(run(x)),
        LinearPoint::AtInfinity(_) => None,
    };
    if from_linear.as_ref().is_some_and(|r| in_front(views, &r.0)) {
        return from_linear;
    }
    match ray_start(views, frame, FARTHEST_START).map(run) {
        Some(r) if in_front(views, &r.0) => Some(r),
        other => from_linear.or(other),
    }
}

/// The cheapest point in front of every camera among log-spaced depths along each view's
/// back-projected ray (the ray of view `i` solves `Aᵢ X = −Wᵢ[:, 3]`), up to `farthest` camera spreads.
fn ray_start(views: &[PointView], frame: &WorldFrame, farthest: f64) -> Option<Vector3<f64>> {
    let mut best: Option<(f64, Vector3<f64>)> = None;
    for v in views {
        let a = v.a();
        let direction = a.row(0).transpose().cross(&a.row(1).transpose());
        let c = v.c();
        if !(c.dot(&direction).abs() > 1e-12 * direction.norm()) {
            continue;
        }
        // A point on the ray (least norm), then the point at depth z: x0 + (z − z(x0))/(c·d) d.
        let Some(x0) = (a * a.transpose())
            .try_inverse()
            .map(|g| -(a.transpose() * (g * v.w.column(3))))
        else {
            continue;
        };
        let z0 = v.depth(&x0);
        for k in 0..RAY_DEPTHS {
            let span = farthest.log10() + 2.0;
            let z = frame.scale * 10f64.powf(-2.0 + span * k as f64 / (RAY_DEPTHS - 1) as f64);
            let x = x0 + direction * ((z - z0) / c.dot(&direction));
            if in_front(views, &x) {
                let cost = point_cost(views, &x);
                if best.map_or(true, |b| cost < b.0) {
                    best = Some((cost, x));
                }
            }
        }
    }
    best.map(|b| b.1)
}

/// The certificate of a local solution in front of every camera: the convexity test, then branch
/// and bound. Returns the (possibly improved) point, its status, the certificate and its cost.
fn certify(
    views: &[PointView],
    frame: &WorldFrame,
    x: Vector3<f64>,
    cost: f64,
    linear: LinearPoint,
    opts: &TriangulationOptions,
) -> (Vector3<f64>, Status, Certificate, f64) {
    // Relative to max(cost, CERTIFICATE_COST_FLOOR) (`relative_gap`): exact data (cost at the rounding level) is
    // certified by the trivial bound, which a relative gap could never show.
    let test = convexity_test(views, &x);
    if let Some(certificate) = test
        .passed
        .then(|| {
            Certificate::of_convexity_test(Primitive::Point, cost, test.lower_bound, opts.certify.max_relative_gap)
        })
        .flatten()
    {
        return (x, Status::Success, certificate, cost);
    }
    // Chart origins when the local solution itself cannot be one (it ran off towards infinity).
    let mut origins: Vec<Vector3<f64>> = Vec::new();
    if Chart::new(views, &x, ChartKind::MeanDepth).is_none() {
        if let LinearPoint::Finite(p) = linear {
            if in_front(views, &p) {
                origins.push(p);
            }
        }
        origins.extend(ray_start(views, frame, FARTHEST_ORIGIN));
    }
    let settings = GlobalSettings {
        max_relative_gap: opts.certify.max_relative_gap,
        max_nodes: opts.conic_max_nodes(),
        local: opts.local,
        relaxation: DEFAULT_RELAXATION,
    };
    let g = global_point(views, &x, cost, &origins, &settings);
    // Both bounds hold over every point in front of the cameras: the better one, before
    // and after the cap at the cost.
    let raw_lower_bound = if test.passed {
        g.raw_lower_bound.max(test.lower_bound)
    } else {
        g.raw_lower_bound
    };
    let lower_bound = if test.passed {
        g.lower_bound.max(test.lower_bound)
    } else {
        g.lower_bound
    }
    .min(g.cost);
    let gap = relative_gap(g.cost, lower_bound);
    let certified = g.status == GlobalStatus::Converged && gap <= opts.certify.max_relative_gap;
    // Success exactly when certified: branch and bound's own stopping rule measures the gap against
    // its incumbent, which may differ from `gap` in the last digits.
    let status = match g.status {
        GlobalStatus::Converged if certified => Status::Success,
        GlobalStatus::Converged | GlobalStatus::NodeLimit | GlobalStatus::Unbounded => Status::GapNotClosed,
        GlobalStatus::Stopped(reason) => Status::stopped(reason),
        GlobalStatus::Failed => Status::NumericalFailure,
    };
    let certificate = Certificate::new(
        CertificateKind::BranchAndBound,
        Primitive::Point,
        lower_bound,
        raw_lower_bound,
        gap,
        certified,
    )
    .with_effort(g.nodes, g.solver_iterations);
    (g.point, status, certificate, g.cost)
}

/// The 3x3 covariance of a point `x` (world units²) seen in `views` ([`super::uncertainty`]): `(Σ BᵢᵀBᵢ)⁻¹` with
/// `Bᵢ = (Aᵢ − rᵢcᵢᵀ)/zᵢ` the Jacobian of the whitened residual of eqs. 15-18
/// ([`PointView::residual_and_information`]).
pub(crate) fn point_covariance(views: &[PointView], x: &Vector3<f64>) -> Option<Matrix3<f64>> {
    if !x.iter().all(|v| v.is_finite()) {
        return None;
    }
    let information = views
        .iter()
        .fold(Matrix3::zeros(), |h, v| h + v.residual_and_information(x).1);
    covariance_of_information3(&information)
}
