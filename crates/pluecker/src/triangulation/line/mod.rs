//! Triangulation of a 3-D line from its images in two or more views (Josephson & Kahl 2008,
//! sections 2.2, 3, 4).
//!
//! The estimate minimises eq. 19, `Σᵢ ‖Lᵢ rᵢ(𝓛)‖²`, over 3-D lines `𝓛` (Plücker coordinates, eq. 3,
//! satisfying eq. 4), with `rᵢ` the residual of the observed image line `lᵢ` (eq. 17 with the
//! normalisation of section 3.1, see `residual`) and `Lᵢ` the whitening of its 2x2
//! covariance (eq. 18; identity without covariances). The three [`Method`]s:
//! - `linear`: the line common to the back-projected planes `πᵢ = Pᵢᵀ lᵢ` in the least-squares sense
//!   (conditioned world frame, planes scaled to unit normals): the two right singular vectors `A`, `B`
//!   of the least singular values of the stacked `πᵢᵀ` span it, and `𝓛 = A∧B` (eq. 2) satisfies
//!   eq. 4 by construction (it is the rank-2 approximation, so no separate correction is needed);
//! - `local`: the trust region of [`crate::optim`] on eq. 19 from the linear line, moving the line in
//!   the orthonormal representation of Bartoli & Sturm ([`OrthonormalLine`]): a minimal 4-parameter
//!   update that keeps eq. 4 exactly;
//! - `optimal`: the local line, then branch and bound: by default with interval Taylor bounds over
//!   the two-view chart (`taylor_search`, `two_view_chart`), whose certificate covers
//!   every line; or with the paper's SOCP relaxation (section 4, `optimal`), selected by
//!   [`TriangulationOptions::line_bound`] and used when the chart has no pair of views.
//!
//! Degenerate input is an error: fewer than 2 views, mismatched lengths, NaN/inf, a singular camera,
//! an image line with zero normal, a covariance that is not positive definite, cameras sharing one
//! centre, or back-projected planes that all coincide (the 3-D line lies in an epipolar plane of every
//! pair of views, so its images do not determine it). Lines have no cheirality test: every line not
//! parallel to an image plane crosses that camera's principal plane, so [`super::Status::BehindCamera`] is
//! never reported for lines.

pub(crate) mod batch;
pub(crate) mod lens;
pub(crate) mod optimal;
pub(crate) mod residual;
pub(crate) mod robust;
pub(crate) mod taylor_search;
pub(crate) mod two_view_chart;

pub use batch::{triangulate_lines, DenseLineTracks, ImageLines, LineTracks, SparseLineTracks, SparseSegmentTracks};
pub use taylor_search::MAX_NODES as TAYLOR_MAX_NODES;

/// The stages of the line solvers that the integration tests check directly; not part of the
/// user-facing API.
#[doc(hidden)]
pub mod testing {
    pub use super::lens::{exact_cost, LensSegment};
    pub use super::residual::{endpoint_distances, LineFrame};
}

use self::lens::LensSegment;
use self::optimal::optimal_line;
use self::residual::{line_view, LineFrame};
use self::taylor_search::optimal_line_taylor;
use super::conditioning::{check_views, Similarity};
use super::fitting::line_from_segment;
use super::fractional_residual::{self, FractionalResidual};
use super::uncertainty::covariance_of_information;
use super::views::{Cameras, View};
use super::{parse_observations, CostKind, LineBound, Method, Report, TriangulationOptions};
use crate::covariance::{whitening, whitenings};
use crate::error::{Error, Result};
use crate::geometry::plucker::{self, LineChart, OrthonormalLine, PluckerLine};
use crate::optim::{trust_region, Linearization, Objective};
use nalgebra::{Matrix2, Matrix3x4, Matrix4, SVector, Vector2, Vector3, Vector4, Vector6};
use std::time::Instant;

/// Ratio of the second to the largest eigenvalue of `Σ πᵢπᵢᵀ` below which the back-projected planes
/// count as one plane (eigenvalues are squared singular values: 1e-18 is a 1e-9 relative spread).
const COINCIDENT_PLANES: f64 = 1e-18;

/// A triangulated 3-D line.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct LineTriangulation {
    /// The line in the world frame: Plücker coordinates (eq. 3), unit norm, satisfying eq. 4.
    pub plucker: PluckerLine,
    /// The point of the line closest to the world origin, world units.
    pub point: Vector3<f64>,
    /// Unit direction of the line, world frame (the direction `d` of [`plucker::direction_moment`]).
    pub direction: Vector3<f64>,
    /// The chart of [`Self::covariance`]: pivot `point`, direction `direction` and the axes `e₁`, `e₂`
    /// of [`LineChart`].
    pub chart: LineChart,
    /// The first-order 4x4 covariance of the line in `chart`, `(α₁, α₂, t₁, t₂)`: tilts of the
    /// direction towards `e₁`, `e₂` (dimensionless) and the crossing point of the plane through
    /// `point` normal to `direction` along `e₁`, `e₂` (world units); `(JᵀJ)⁻¹` with `J` the Jacobian
    /// of the whitened residuals of eq. 18 ([`super::uncertainty`]; identity residual covariances
    /// when none are given). Computed for every method and status; `None` when `JᵀJ` is numerically
    /// singular (a line nearly in an epipolar plane of every pair of views). Map it with
    /// [`LineChart::plucker_covariance`] or [`LineChart::point_direction_covariance`].
    #[cfg_attr(feature = "serde", serde(with = "crate::matrix_rows::option"))]
    pub covariance: Option<Matrix4<f64>>,
    /// What the method did: status, cost of eq. 19, certificate, iterations, time.
    #[cfg_attr(feature = "serde", serde(flatten))]
    pub report: Report,
    /// With [`TriangulationOptions::outlier_threshold`], one flag per view of the track (in its
    /// order): the observations the line was solved from (`robust`). `None` otherwise.
    pub inliers: Option<Vec<bool>>,
}

/// The checked observations of one line.
pub(crate) struct LineProblem {
    pub cameras: Vec<Matrix3x4<f64>>,
    pub frames: Vec<LineFrame>,
    pub whitenings: Vec<Matrix2<f64>>,
}

impl LineProblem {
    /// The whitened residuals of every view in the conditioned frame `sim` (eqs. 6-7, 17-18).
    pub fn views(&self, sim: &Similarity) -> Vec<FractionalResidual<2, 6>> {
        self.cameras
            .iter()
            .zip(&self.frames)
            .zip(&self.whitenings)
            .map(|((p, f), w)| line_view(&sim.camera(p), f, w))
            .collect()
    }

    /// Eq. 19 at a world line.
    pub fn cost(&self, world_line: &Vector6<f64>) -> f64 {
        fractional_residual::cost(&self.views(&Similarity::identity()), world_line)
    }

    /// The point of a world line closest to the centroid of the camera centres, and the distance `ρ`
    /// between them (at least the RMS spread of the centres).
    pub fn foot(&self, world_line: &Vector6<f64>) -> (Vector3<f64>, f64) {
        let spread = Similarity::of_cameras(&self.cameras);
        let Some((p, d)) = plucker::to_point_direction(world_line) else {
            return (spread.origin, 1.0 / spread.scale);
        };
        let foot = p + d * d.dot(&(spread.origin - p));
        (foot, (foot - spread.origin).norm().max(1.0 / spread.scale))
    }

    /// The conditioned frame of the local method: unit `ρ` ([`Self::foot`]) and origin `ρ` away from
    /// the line (towards the cameras), so that the line has `φ = π/4` in the orthonormal
    /// representation, far from its singular charts `φ = 0` (a line through the origin, where one
    /// direction of motion is lost) and `φ = π/2`.
    pub(crate) fn frame_around(&self, world_line: &Vector6<f64>) -> Similarity {
        let (foot, rho) = self.foot(world_line);
        let Some((_, d)) = plucker::to_point_direction(world_line) else {
            return Similarity::of_cameras(&self.cameras);
        };
        let towards = Similarity::of_cameras(&self.cameras).origin - foot;
        let mut side = towards - d * d.dot(&towards);
        if side.norm() <= 1e-6 * rho {
            side = if d.x.abs() < 0.9 {
                d.cross(&Vector3::x())
            } else {
                d.cross(&Vector3::y())
            };
        }
        Similarity::around(foot + side.normalize() * rho, rho)
    }
}

/// The observed images of one 3-D line, one per camera.
#[derive(Debug, Clone, Copy)]
pub enum LineObservations<'a> {
    /// Homogeneous image lines `l` (pixels, any scale and sign: `l·(u, v, 1) = 0`), with optional 2x2
    /// covariances of the line residuals (one per view, e.g. from [`super::fitting::fit_line`];
    /// identity when `None`). With [`Cameras::Projections`] only.
    Lines(&'a [Vector3<f64>], Option<&'a [Matrix2<f64>]>),
    /// Image segments (pixel endpoints) whose endpoints have i.i.d. Gaussian noise of `sigma` px per
    /// coordinate (the `f64`). With projections each segment gives its line and covariance by
    /// [`lines_from_segments`]; with views this is [`LineObservations::SegmentEndpoints`] with
    /// endpoint covariances `σ² I`.
    Segments(&'a [[Vector2<f64>; 2]], f64),
    /// Image segments whose endpoints are the images' own (distorted) pixels, with optional 2x2
    /// covariances of each endpoint (identity when `None`). With [`Cameras::Views`] only.
    SegmentEndpoints(&'a [[Vector2<f64>; 2]], Option<&'a [[Matrix2<f64>; 2]]>),
}

impl<'a> From<&'a [Vector3<f64>]> for LineObservations<'a> {
    fn from(lines: &'a [Vector3<f64>]) -> Self {
        LineObservations::Lines(lines, None)
    }
}

impl<'a> From<&'a Vec<Vector3<f64>>> for LineObservations<'a> {
    fn from(lines: &'a Vec<Vector3<f64>>) -> Self {
        LineObservations::Lines(lines, None)
    }
}

impl<'a, const N: usize> From<&'a [Vector3<f64>; N]> for LineObservations<'a> {
    fn from(lines: &'a [Vector3<f64>; N]) -> Self {
        LineObservations::Lines(lines, None)
    }
}

/// Triangulates one 3-D line seen by `cameras` as `observations` (image lines or segments, one per
/// camera).
///
/// With [`Cameras::Projections`] (3x4, world → pixels, any positive scale; in front means
/// `(P X̃)₃ > 0`, `views`) the cost is eq. 19 on the line residuals. With [`Cameras::Views`] (each a
/// camera, pinhole or any of COLMAP's models, and its pose) the observations are segments whose
/// endpoints are the images' own (distorted) pixels: through a distorting lens the cost is the
/// segments' reprojection error through the exact projection, the Mahalanobis distances of the
/// endpoints to the line's curved images, minimised by the local method; it is never certified there
/// (`lens`: `optimal` reports `gap_not_closed`). When no camera distorts this is the problem of the
/// views' `K [R | t]` on the segments' lines and covariances
/// ([`crate::triangulation::fitting::line_from_endpoints`]).
///
/// Errors: [`Error::TooFewCorrespondences`] for fewer than 2 views, [`Error::Shape`] for mismatched
/// lengths, [`Error::NonFinite`] naming the argument and row, [`Error::SingularCamera`],
/// [`Error::Degenerate`] (a line with zero normal, a segment of zero length or with an endpoint outside
/// its lens's invertible region, a covariance that is not positive definite, cameras with one centre, a
/// line in an epipolar plane of every view pair), [`Error::InvalidOption`] (bad options, a bad
/// `sigma`, homogeneous lines with views or endpoint covariances with projections).
pub fn triangulate_line<'a>(
    cameras: impl Into<Cameras<'a>>,
    observations: impl Into<LineObservations<'a>>,
    opts: &TriangulationOptions,
) -> Result<LineTriangulation> {
    match (cameras.into(), observations.into()) {
        (Cameras::Projections(projections), LineObservations::Lines(lines, covariances)) => {
            line_of_projections(projections, lines, covariances, opts)
        }
        (Cameras::Projections(projections), LineObservations::Segments(segments, sigma)) => {
            let (lines, covariances) = lines_from_segments(segments, sigma)?;
            line_of_projections(projections, &lines, Some(&covariances), opts)
        }
        (Cameras::Views(views), LineObservations::SegmentEndpoints(segments, covariances)) => {
            line_of_segment_views(views, segments, covariances, opts)
        }
        (Cameras::Views(views), LineObservations::Segments(segments, sigma)) => {
            batch::check_sigma(&ImageLines::Segments { endpoints: &[], sigma })?;
            let covariances = vec![[Matrix2::identity() * (sigma * sigma); 2]; segments.len()];
            line_of_segment_views(views, segments, Some(&covariances), opts)
        }
        (Cameras::Views(_), LineObservations::Lines(..)) => Err(Error::InvalidOption {
            name: "lines".into(),
            reason: "with views the image lines are segments (a line's image through a lens is a curve, \
                     not a homogeneous line)"
                .into(),
        }),
        (Cameras::Projections(_), LineObservations::SegmentEndpoints(..)) => Err(Error::InvalidOption {
            name: "covariances".into(),
            reason: "endpoint covariances apply to segments seen through views; with projections give the \
                     segments' noise sigma or the lines' covariances"
                .into(),
        }),
    }
}

/// [`triangulate_line`] of homogeneous image lines seen by projections.
pub(crate) fn line_of_projections(
    projections: &[Matrix3x4<f64>],
    lines: &[Vector3<f64>],
    covariances: Option<&[Matrix2<f64>]>,
    opts: &TriangulationOptions,
) -> Result<LineTriangulation> {
    let started = Instant::now();
    opts.validate()?;
    check_views(projections, lines.len(), 2, "lines", opts.method)?;
    let frames = parse_observations(
        lines,
        "lines",
        "has a zero normal (the line at infinity)",
        LineFrame::of_line,
    )?;
    let problem = LineProblem {
        cameras: projections.to_vec(),
        frames,
        whitenings: whitenings(covariances, projections.len(), "covariances")?,
    };
    let mut result = match opts.outlier_threshold {
        None => triangulate_line_views(&problem, opts)?,
        Some(tau) => robust::triangulate_line_robust(&problem, opts, tau)?,
    };
    result.report.time_seconds = started.elapsed().as_secs_f64();
    Ok(result)
}

/// The chosen method on checked observations (every view of `problem`).
pub(crate) fn triangulate_line_views(problem: &LineProblem, opts: &TriangulationOptions) -> Result<LineTriangulation> {
    let linear = linear_line(problem)?;
    let mut report = Report {
        cost: problem.cost(&linear),
        ..Report::new(opts.method, CostKind::LineResidual)
    };
    let estimate = match opts.method {
        Method::Linear => linear,
        Method::Local => {
            let (line, local) = local_line(problem, &linear, opts);
            report = Report {
                method: Method::Local,
                ..local
            };
            line
        }
        Method::Optimal => {
            let (line, local) = local_line(problem, &linear, opts);
            let taylor = match opts.line_bound {
                LineBound::Taylor => optimal_line_taylor(problem, &line, &local, opts),
                LineBound::Relaxation => None,
            };
            let (best, optimal) = taylor.unwrap_or_else(|| optimal_line(problem, &line, &local, opts));
            report = optimal;
            best
        }
    };
    finish(problem, &estimate, report)
}

/// The result record of a world line (unit norm, point and direction) and its covariance.
fn finish(problem: &LineProblem, line: &Vector6<f64>, mut report: Report) -> Result<LineTriangulation> {
    report.test_residuals(2 * problem.cameras.len(), 4);
    let plucker = PluckerLine::new(&plucker::nearest_line(line))?;
    let at_infinity = || Error::Degenerate {
        what: "the estimated line lies at infinity".into(),
    };
    let (point, direction) = plucker.point_direction().ok_or_else(at_infinity)?;
    let chart = LineChart::new(&point, &direction).ok_or_else(at_infinity)?;
    Ok(LineTriangulation {
        plucker,
        point,
        direction,
        chart,
        covariance: line_covariance(problem, &chart),
        report,
        inliers: None,
    })
}

/// Image lines (homogeneous, one per segment) and the 2x2 covariances of their residuals.
pub type LinesAndCovariances = (Vec<Vector3<f64>>, Vec<Matrix2<f64>>);

/// The image lines and residual covariances of image segments (pixel endpoints, i.i.d. Gaussian
/// noise of `sigma` px per coordinate): [`line_from_segment`] on each (see [`super::fitting`]).
/// `lines` are the image lines given as segments; errors name `lines[i]`, the argument of the
/// triangulation functions (and of the Python package) the segments come in.
pub fn lines_from_segments(lines: &[[Vector2<f64>; 2]], sigma: f64) -> Result<LinesAndCovariances> {
    let mut homogeneous = Vec::with_capacity(lines.len());
    let mut covariances = Vec::with_capacity(lines.len());
    for (i, s) in lines.iter().enumerate() {
        if !s.iter().all(|p| p.x.is_finite() && p.y.is_finite()) {
            return Err(Error::NonFinite {
                what: "lines".into(),
                index: i,
            });
        }
        let fit = line_from_segment(&s[0], &s[1], sigma).map_err(|e| match e {
            Error::Degenerate { what } if what.contains("zero-length") => Error::Degenerate {
                what: format!("lines[{i}] has zero length"),
            },
            other => other,
        })?;
        if whitening(&fit.covariance, "lines", i).is_err() {
            return Err(Error::Degenerate {
                what: format!(
                    "lines[{i}]: the covariance of its line is numerically singular (a segment far shorter than its distance from the image origin)"
                ),
            });
        }
        homogeneous.push(fit.line);
        covariances.push(fit.covariance);
    }
    Ok((homogeneous, covariances))
}

/// [`triangulate_line`] of segments seen through views, with optional endpoint covariances (errors
/// name `lines`, `covariances` and `projections`).
pub(crate) fn line_of_segment_views(
    views: &[View],
    lines: &[[Vector2<f64>; 2]],
    covariances: Option<&[[Matrix2<f64>; 2]]>,
    opts: &TriangulationOptions,
) -> Result<LineTriangulation> {
    let started = Instant::now();
    opts.validate()?;
    let cameras: Vec<Matrix3x4<f64>> = views.iter().map(View::projection).collect();
    check_views(&cameras, lines.len(), 2, "lines", opts.method)?;
    if let Some(c) = covariances {
        if c.len() != views.len() {
            return Err(Error::Shape {
                what: "covariances".into(),
                expected: format!("{} (one pair of endpoint covariances per view)", views.len()),
                actual: c.len().to_string(),
            });
        }
    }
    let identity = [Matrix2::identity(); 2];
    let mut observed = Vec::with_capacity(views.len());
    for (i, (view, s)) in views.iter().zip(lines).enumerate() {
        if !s.iter().all(|p| p.x.is_finite() && p.y.is_finite()) {
            return Err(Error::NonFinite {
                what: "lines".into(),
                index: i,
            });
        }
        let pair = covariances.map_or(identity, |c| c[i]);
        for c in &pair {
            // A named error for a covariance that is not finite or not positive definite.
            whitening(c, "covariances", i)?;
        }
        observed.push(LensSegment::new(view, *s, pair, i)?);
    }
    let mut result = lens::solve_lens_segments(&cameras, &observed, opts)?;
    result.report.time_seconds = started.elapsed().as_secs_f64();
    Ok(result)
}

/// The linear method (module docs), as a world line.
pub(crate) fn linear_line(problem: &LineProblem) -> Result<Vector6<f64>> {
    let sim = Similarity::of_cameras(&problem.cameras);
    let mut gram = Matrix4::zeros();
    for (p, f) in problem.cameras.iter().zip(&problem.frames) {
        let plane: Vector4<f64> = sim.camera(p).transpose() * f.line();
        let norm = plane.xyz().norm();
        if norm > 0.0 {
            gram += plane * plane.transpose() / (norm * norm);
        }
    }
    let eig = gram.symmetric_eigen();
    let mut order = [0usize, 1, 2, 3];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    if !(eig.eigenvalues[order[1]] > COINCIDENT_PLANES * eig.eigenvalues[order[0]]) {
        return Err(Error::Degenerate {
            what:
                "lines: the back-projected planes coincide (the line lies in an epipolar plane of every pair of views)"
                    .into(),
        });
    }
    let a: Vector4<f64> = eig.eigenvectors.column(order[2]).into_owned();
    let b: Vector4<f64> = eig.eigenvectors.column(order[3]).into_owned();
    let conditioned = plucker::from_homogeneous_points(&a, &b);
    if plucker::to_point_direction(&conditioned).is_none() {
        return Err(Error::Degenerate {
            what: "lines: the back-projected planes meet at infinity".into(),
        });
    }
    Ok(plucker::transform(&sim.inverse_matrix(), &conditioned))
}

/// Eq. 19 over the orthonormal representation (module docs), in a conditioned frame.
pub(crate) struct LineObjective<'a> {
    pub views: &'a [FractionalResidual<2, 6>],
}

impl Objective<4> for LineObjective<'_> {
    type Point = OrthonormalLine;

    fn cost(&self, x: &OrthonormalLine) -> f64 {
        0.5 * fractional_residual::cost(self.views, &x.to_plucker())
    }

    fn linearize(&self, x: &OrthonormalLine) -> Linearization<4> {
        fractional_residual::linearize(self.views, &x.to_plucker(), &x.tangent())
    }

    fn retract(&self, x: &OrthonormalLine, d: &SVector<f64, 4>) -> OrthonormalLine {
        x.retract(d)
    }
}

/// The local method from `start` (a world line): the minimised world line and its report.
pub(crate) fn local_line(
    problem: &LineProblem,
    start: &Vector6<f64>,
    opts: &TriangulationOptions,
) -> (Vector6<f64>, Report) {
    let sim = problem.frame_around(start);
    let views = problem.views(&sim);
    let h = sim.matrix();
    let objective = LineObjective { views: &views };
    let x0 = OrthonormalLine::from_plucker(&plucker::transform(&h, start)).expect("a finite line");
    let (x, summary) = trust_region::minimize(&objective, x0, &opts.local);
    let world = plucker::transform(&sim.inverse_matrix(), &x.to_plucker());
    (world, Report::of_local(&summary, CostKind::LineResidual))
}

/// The 4x4 covariance of a line in `chart` (pivoted anywhere on the line; [`super::uncertainty`]). Computed in
/// the chart pivoted at the point of the line closest to the centroid of the camera centres, in a
/// frame whose unit is its distance `ρ` from them ([`LineProblem::foot`]), then moved to `chart`'s
/// pivot exactly: from `δ' = (α, t')` there, `δ = (α, ρ t' − s α)` with `s` the signed distance
/// along the line from `chart`'s pivot to that point ([`LineChart::repivot`]).
pub(crate) fn line_covariance(problem: &LineProblem, chart: &LineChart) -> Option<Matrix4<f64>> {
    chart_covariance(problem, chart, |sim, framed| {
        let views = problem.views(sim);
        let info =
            fractional_residual::linearize(&views, &framed.line(&Vector4::zeros()), &framed.tangent()).gauss_newton;
        covariance_of_information(&info)
    })
}

/// The repivoting of [`line_covariance`] for any residuals: `framed_covariance(sim, framed)` is the
/// covariance in the chart `framed` (pivot at the origin of the frame `sim`, unit `ρ`), moved here to
/// `chart`'s pivot and world units.
pub(crate) fn chart_covariance(
    problem: &LineProblem,
    chart: &LineChart,
    framed_covariance: impl Fn(&Similarity, &LineChart) -> Option<Matrix4<f64>>,
) -> Option<Matrix4<f64>> {
    let world_line = chart.line(&Vector4::zeros());
    if !world_line.iter().all(|v| v.is_finite()) {
        return None;
    }
    let (foot, rho) = problem.foot(&world_line);
    let near = chart.repivot(&foot);
    let sim = Similarity::around(near.pivot, rho);
    // The frame only translates and scales: the pivot is its origin, the axes are unchanged.
    let framed = LineChart {
        pivot: Vector3::zeros(),
        ..near
    };
    let framed_cov = framed_covariance(&sim, &framed)?;
    let s = chart.direction.dot(&(near.pivot - chart.pivot));
    let mut m = Matrix4::identity();
    m[(2, 2)] = rho;
    m[(3, 3)] = rho;
    m[(2, 0)] = -s;
    m[(3, 1)] = -s;
    Some(m * framed_cov * m.transpose())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optim::problem::testing::gradient_error;
    use crate::rng::Rng;

    pub(crate) fn ring_cameras(n: usize, rng: &mut Rng) -> Vec<Matrix3x4<f64>> {
        // Cameras on a circle of radius 4 around the origin, looking at it.
        let k = nalgebra::Matrix3::new(800.0, 0.0, 320.0, 0.0, 800.0, 240.0, 0.0, 0.0, 1.0);
        (0..n)
            .map(|i| {
                let angle = 0.6 * i as f64 / n.max(1) as f64 + 0.05 * rng.normal();
                let c = Vector3::new(4.0 * angle.sin(), 0.3 * rng.normal(), -4.0 * angle.cos());
                let z = (-c).normalize();
                let x = Vector3::y().cross(&z).normalize();
                let y = z.cross(&x);
                let r = nalgebra::Matrix3::from_rows(&[x.transpose(), y.transpose(), z.transpose()]);
                let mut rt = Matrix3x4::zeros();
                rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&r);
                rt.set_column(3, &(-r * c));
                k * rt
            })
            .collect()
    }

    /// `n` ring cameras (seed `seed`), the images of the line through `a = (0.2, −0.3, 0.1)` and
    /// `b = (−0.3, 0.4, −0.2)` with small random errors, and view `i`'s whitening `whitening(i)`.
    pub(crate) fn noisy_problem(
        n: usize,
        seed: u64,
        whitening: impl Fn(usize) -> Matrix2<f64>,
    ) -> (LineProblem, (Vector3<f64>, Vector3<f64>)) {
        let mut rng = Rng::new(seed);
        let cameras = ring_cameras(n, &mut rng);
        let (a, b) = (Vector3::new(0.2, -0.3, 0.1), Vector3::new(-0.3, 0.4, -0.2));
        let frames = cameras
            .iter()
            .map(|p| {
                let l = (p * a.push(1.0)).cross(&(p * b.push(1.0)))
                    + Vector3::new(rng.normal(), rng.normal(), rng.normal() * 300.0) * 1e-3;
                LineFrame::of_line(&l).unwrap()
            })
            .collect();
        let problem = LineProblem {
            cameras,
            frames,
            whitenings: (0..n).map(whitening).collect(),
        };
        (problem, (a, b))
    }

    #[test]
    fn objective_gradient_matches_central_differences() {
        let (problem, (a, b)) = noisy_problem(4, 61, |_| Matrix2::new(0.7, 0.0, 0.3, 1.4));
        let views = problem.views(&Similarity::identity());
        let objective = LineObjective { views: &views };
        let x = OrthonormalLine::from_plucker(&plucker::from_points(&a, &(b + Vector3::new(0.01, 0.0, 0.02)))).unwrap();
        assert!(gradient_error(&objective, &x, 1e-6) < 1e-5);
    }
}
