//! A line seen through lenses with distortion: the exact cost of its segments in the images' own
//! pixels, and its local minimisation (Josephson & Kahl 2008, sections 2.2 and 3, with the pinhole
//! projection replaced by the lens's).
//!
//! **Cost.** View `i` has a camera ([`Camera`]: `u = K D(n)`, `n = (x/z, y/z)`,
//! `x_cam = Rᵢ X + tᵢ`), an observed segment with (distorted) endpoints `eᵢ₁`, `eᵢ₂` and their 2x2
//! covariances `Cᵢₖ` (pixels²; the identity when none are given). A 3-D line `𝓛` (Plücker coordinates,
//! eq. 3) has in view `i` the normalised image line `lᵢ = P_𝓛 𝓛` (eqs. 6-7 for the camera `[Rᵢ | tᵢ]`),
//! whose image in the pixels is the curve `K D(ℓᵢ)`. Each endpoint's residual `rᵢₖ(𝓛)` is its signed
//! Mahalanobis distance to that curve ([`crate::camera::curved_line`]), and the cost is
//! `F(𝓛) = Σᵢ Σₖ rᵢₖ²`, the reprojection error of the segments through the exact projection: the
//! statistically optimal cost for Gaussian noise of the endpoints across the line. Without distortion
//! it is the squared distance of the endpoints to the projected line (Table 2's error).
//!
//! **Stages.** The first stages are those of [`super`] on the first-order problem: each endpoint
//! undistorted into the pixels of its lens's pinhole part with covariance `J⁻¹ C J⁻ᵀ`
//! ([`Camera::undistort_with_covariance`]), each segment's line and the covariance of its residual
//! (eq. 18) by [`line_from_endpoints`]. With `optimal`, they run `local` and, as for points, also
//! `optimal` (whose global search may find another basin), the cheaper exact cost kept. `refine`
//! then minimises `F` itself over the orthonormal representation of Bartoli & Sturm (the 4-parameter
//! update of `super::LineObjective`, in the same conditioned frame). Its gradient: by the envelope
//! theorem `∂rᵢₖ/∂lᵢ` is the derivative at the nearest point `q*` of the curve moved with the line
//! ([`crate::camera::curved_line::EndpointResidual::line_gradient`]), and `∂lᵢ/∂𝓛 = P_𝓛`.
//!
//! **No certificate.** No proof of a lower bound of `F` exists yet through a distorting lens (the
//! Taylor and relaxation bounds of [`super`] bound eq. 19 of the first-order problem, another cost).
//! So the result is never certified there: `local` reports `success`, `optimal` reports
//! `gap_not_closed` (no bound) after the same refinement; a first-order bound is never attached to
//! `F`. When no camera distorts (pinholes, or lenses whose distortion is the identity:
//! [`Camera::distorts`]) the first-order problem is the pinhole problem of
//! [`super::triangulate_line`] of [`super::LineObservations::Segments`] (eq. 19 with each segment's line and the covariance of its
//! residual from the endpoints' covariances), and its answer is returned as it is: its cost is eq. 19
//! ([`crate::CostKind::LineResidual`]),
//! not `F`, and its certificate is the one of [`super`].

use super::{finish, line_of_projections, LineProblem, LineTriangulation, LinesAndCovariances};
use crate::camera::curved_line::{endpoint_residual, pinhole_endpoint_residual};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::geometry::plucker::{self, LineChart, OrthonormalLine, PluckerCamera};
use crate::optim::{trust_region, Linearization, Objective, Summary, Termination, TrustRegionOptions};
use crate::triangulation::conditioning::Similarity;
use crate::triangulation::fitting::line_from_endpoints;
use crate::triangulation::line::residual::LineFrame;
use crate::triangulation::point::robust::reselect_at_optimum;
use crate::triangulation::uncertainty::covariance_of_information;
use crate::triangulation::views::View;
use crate::triangulation::{CostKind, Method, Status, TriangulationOptions};
use nalgebra::{Matrix2, Matrix2x3, Matrix3x4, Matrix4, SMatrix, SVector, Vector2, Vector3, Vector6};

/// One segment observed through a camera: the camera, its pose, the observed (distorted) endpoints
/// and their covariances, with the endpoints' first-order form (module docs).
#[derive(Debug, Clone, Copy)]
pub struct LensSegment<'a> {
    /// The camera.
    pub camera: &'a Camera,
    /// `[R | t]`, world to camera.
    pub pose: Matrix3x4<f64>,
    /// The observed endpoints, pixels.
    pub endpoints: [Vector2<f64>; 2],
    /// Their covariances, pixels².
    pub covariances: [Matrix2<f64>; 2],
    /// The endpoints undistorted into the pixels of the pinhole part, and their first-order covariances.
    undistorted: [(Vector2<f64>, Matrix2<f64>); 2],
    /// The normalised coordinates of the undistorted endpoints, where the searches along the curve start.
    starts: [Vector2<f64>; 2],
}

impl<'a> LensSegment<'a> {
    /// Segment `index` (named in errors as `segments[index]`) seen in `view`. Errors:
    /// [`Error::Degenerate`] for an endpoint outside the invertible region of the lens, or where the
    /// distortion is singular.
    pub fn new(
        view: &'a View,
        endpoints: [Vector2<f64>; 2],
        covariances: [Matrix2<f64>; 2],
        index: usize,
    ) -> Result<LensSegment<'a>> {
        let k = view.camera.intrinsics();
        let k_inverse = k.matrix().try_inverse().ok_or_else(|| Error::SingularCamera {
            what: format!("views[{index}]: K is singular"),
        })?;
        let mut undistorted = [(Vector2::zeros(), Matrix2::zeros()); 2];
        for end in 0..2 {
            undistorted[end] = match view.camera.distortion() {
                Some(lens) => {
                    let (ubar, cov) = lens
                        .undistort_with_covariance(&endpoints[end], &covariances[end], index)
                        .map_err(|e| match e {
                            Error::Degenerate { what } => Error::Degenerate {
                                what: format!("lines[{index}]: endpoint {end}: {what}"),
                            },
                            other => other,
                        })?;
                    let cov = cov.ok_or_else(|| Error::Degenerate {
                        what: format!("lines[{index}]: endpoint {end}: the distortion is singular there"),
                    })?;
                    (ubar, cov)
                }
                None => (endpoints[end], covariances[end]),
            };
        }
        let start = |u: &Vector2<f64>| (k_inverse * Vector3::new(u.x, u.y, 1.0)).xy();
        let mut rt = Matrix3x4::zeros();
        rt.fixed_view_mut::<3, 3>(0, 0).copy_from(&view.pose.rotation);
        rt.set_column(3, &view.pose.translation);
        Ok(LensSegment {
            camera: &view.camera,
            pose: rt,
            endpoints,
            covariances,
            undistorted,
            starts: [start(&undistorted[0].0), start(&undistorted[1].0)],
        })
    }

    /// The first-order observation: the image line through the undistorted endpoints (pixels of the
    /// pinhole part) and the covariance of its residual ([`line_from_endpoints`]).
    pub(crate) fn first_order(&self, index: usize) -> Result<(Vector3<f64>, Matrix2<f64>)> {
        let [(a, ca), (b, cb)] = self.undistorted;
        let fit = line_from_endpoints(&a, &b, &ca, &cb).map_err(|e| match e {
            Error::Degenerate { what } if what.contains("zero-length") => Error::Degenerate {
                what: format!("lines[{index}] has zero length"),
            },
            Error::Degenerate { .. } | Error::NonFinite { .. } => Error::Degenerate {
                what: format!("lines[{index}]: no line through its undistorted endpoints"),
            },
            other => other,
        })?;
        Ok((fit.line, fit.covariance))
    }

    /// The two endpoint residuals `rₖ` of the normalised image line `l` (module docs) and `∂r/∂l`;
    /// `None` where `l` has no image (the 3-D line passes through the camera centre).
    pub fn residuals(&self, l: &Vector3<f64>) -> Option<(Vector2<f64>, Matrix2x3<f64>)> {
        let mut r = Vector2::zeros();
        let mut j = Matrix2x3::zeros();
        for k in 0..2 {
            let (rk, jk) = match self.camera.distortion() {
                Some(lens) => {
                    let fit = endpoint_residual(lens, l, &self.starts[k], &self.endpoints[k], &self.covariances[k])?;
                    (fit.residual, fit.line_gradient(lens, l))
                }
                None => {
                    let k_inverse = self.camera.intrinsics().matrix().try_inverse()?;
                    pinhole_endpoint_residual(&k_inverse, l, &self.endpoints[k], &self.covariances[k])?
                }
            };
            r[k] = rk;
            j.set_row(k, &jk);
        }
        Some((r, j))
    }

    /// `r₁² + r₂²` of the world line `world_line`, `∞` where it has no image.
    pub fn squared_residual(&self, world_line: &Vector6<f64>) -> f64 {
        let l = plucker::camera(&self.pose) * world_line;
        self.residuals(&l).map_or(f64::INFINITY, |(r, _)| r.norm_squared())
    }
}

/// `F(𝓛) = Σ rᵢₖ²` (module docs) of the world line `world_line`, `∞` where a view has no image of it.
pub fn exact_cost(segments: &[LensSegment], world_line: &Vector6<f64>) -> f64 {
    segments.iter().map(|s| s.squared_residual(world_line)).sum()
}

/// `J = ∂r/∂δ` (2x4) of a segment at the line `l = P_𝓛 𝓛` moved by `∂𝓛/∂δ = tangent`.
fn segment_jacobian(
    segment: &LensSegment,
    camera: &PluckerCamera,
    line: &Vector6<f64>,
    tangent: &SMatrix<f64, 6, 4>,
) -> Option<(Vector2<f64>, SMatrix<f64, 2, 4>)> {
    let (r, dr_dl) = segment.residuals(&(camera * line))?;
    Some((r, dr_dl * camera * tangent))
}

/// The Plücker cameras of `segments` in the conditioned frame `sim` (`[R | t] H⁻¹`).
fn framed_cameras(segments: &[LensSegment], sim: &Similarity) -> Vec<PluckerCamera> {
    segments.iter().map(|s| plucker::camera(&sim.camera(&s.pose))).collect()
}

/// `½ F` over the orthonormal representation, in a conditioned frame.
struct ExactLineObjective<'a, 'b> {
    segments: &'a [LensSegment<'b>],
    cameras: Vec<PluckerCamera>,
}

impl Objective<4> for ExactLineObjective<'_, '_> {
    type Point = OrthonormalLine;

    fn cost(&self, x: &OrthonormalLine) -> f64 {
        let line = x.to_plucker();
        0.5 * self
            .segments
            .iter()
            .zip(&self.cameras)
            .map(|(s, p)| {
                s.residuals(&(p * line))
                    .map_or(f64::INFINITY, |(r, _)| r.norm_squared())
            })
            .sum::<f64>()
    }

    fn linearize(&self, x: &OrthonormalLine) -> Linearization<4> {
        let (line, tangent) = (x.to_plucker(), x.tangent());
        let mut lin = Linearization::zero();
        for (s, p) in self.segments.iter().zip(&self.cameras) {
            let Some((r, j)) = segment_jacobian(s, p, &line, &tangent) else {
                lin.cost = f64::INFINITY;
                return lin;
            };
            lin.add(&r, &j);
        }
        lin
    }

    fn retract(&self, x: &OrthonormalLine, d: &SVector<f64, 4>) -> OrthonormalLine {
        x.retract(d)
    }
}

/// The local minimum of `F` from the world line `start` by the trust region of [`crate::optim`], in
/// the conditioned frame of the local method ([`LineProblem::frame_around`] of `problem`, the
/// first-order problem of the same views). Returns the world line and the solver's summary.
pub(crate) fn refine(
    problem: &LineProblem,
    segments: &[LensSegment],
    start: &Vector6<f64>,
    opts: &TrustRegionOptions,
) -> Option<(Vector6<f64>, Summary)> {
    let sim = problem.frame_around(start);
    let objective = ExactLineObjective {
        segments,
        cameras: framed_cameras(segments, &sim),
    };
    let x0 = OrthonormalLine::from_plucker(&plucker::transform(&sim.matrix(), start))?;
    let (x, summary) = trust_region::minimize(&objective, x0, opts);
    Some((plucker::transform(&sim.inverse_matrix(), &x.to_plucker()), summary))
}

/// The 4x4 covariance in `chart` of the exact residuals' Jacobian, `(JᵀJ)⁻¹`
/// ([`super::chart_covariance`]).
fn exact_covariance(problem: &LineProblem, segments: &[LensSegment], chart: &LineChart) -> Option<Matrix4<f64>> {
    super::chart_covariance(problem, chart, |sim, framed| {
        let (line, tangent) = (framed.line(&nalgebra::Vector4::zeros()), framed.tangent());
        let mut information = Matrix4::zeros();
        for (s, p) in segments.iter().zip(framed_cameras(segments, sim)) {
            let (_, j) = segment_jacobian(s, &p, &line, &tangent)?;
            information += j.transpose() * j;
        }
        covariance_of_information(&information)
    })
}

/// The first-order problem of `segments`: their lines and the covariances of their residuals.
fn first_order(segments: &[LensSegment]) -> Result<LinesAndCovariances> {
    let (mut lines, mut covariances) = (Vec::new(), Vec::new());
    for (i, s) in segments.iter().enumerate() {
        let (line, covariance) = s.first_order(i)?;
        lines.push(line);
        covariances.push(covariance);
    }
    Ok((lines, covariances))
}

/// One line seen through `segments` (checked), by the stages of the module docs; `cameras` are the
/// views' `K [R | t]`.
pub(crate) fn solve_lens_segments(
    cameras: &[Matrix3x4<f64>],
    segments: &[LensSegment],
    opts: &TriangulationOptions,
) -> Result<LineTriangulation> {
    let (lines, covariances) = first_order(segments)?;
    let distorts = segments
        .iter()
        .any(|s| s.camera.distortion().is_some_and(Camera::distorts));
    if !distorts {
        return line_of_projections(cameras, &lines, Some(&covariances), opts);
    }
    let through = |first_opts: &TriangulationOptions| -> Result<LineTriangulation> {
        let mut result = line_of_projections(cameras, &lines, Some(&covariances), first_opts)?;
        result.report.method = opts.method;
        through_lenses(&mut result, cameras, &lines, &covariances, segments, opts)?;
        Ok(result)
    };
    if opts.method != Method::Optimal {
        return through(opts);
    }
    let local = through(&TriangulationOptions {
        method: Method::Local,
        ..opts.clone()
    })?;
    // The first-order branch and bound may find another basin; its first-order certificate is
    // dropped (it bounds another cost). An error of that search keeps the local answer.
    match through(opts) {
        Ok(searched) if searched.report.cost < local.report.cost || !local.report.cost.is_finite() => Ok(searched),
        _ => Ok(local),
    }
}

/// The exact stage (module docs): `result` was solved from the first-order lines `lines` (with
/// residual covariances `covariances`) of `segments` (all of them, or its inliers). Its line is
/// refined on `F` over the segments it used; its cost, covariance and status become those of `F`,
/// and it carries no certificate.
fn through_lenses(
    result: &mut LineTriangulation,
    cameras: &[Matrix3x4<f64>],
    lines: &[Vector3<f64>],
    covariances: &[Matrix2<f64>],
    segments: &[LensSegment],
    opts: &TriangulationOptions,
) -> Result<()> {
    let pick = |flags: &[bool]| -> (LineProblem, Vec<LensSegment>) {
        let keep: Vec<usize> = (0..segments.len()).filter(|&i| flags[i]).collect();
        let problem = LineProblem {
            cameras: keep.iter().map(|&i| cameras[i]).collect(),
            frames: keep
                .iter()
                .map(|&i| LineFrame::of_line(&lines[i]).expect("a checked line"))
                .collect(),
            whitenings: keep
                .iter()
                .map(|&i| {
                    crate::covariance::whitening(&covariances[i], "covariances", i).expect("a checked covariance")
                })
                .collect(),
        };
        (problem, keep.iter().map(|&i| segments[i]).collect())
    };
    let all = vec![true; segments.len()];
    let (mut problem, mut used) = pick(result.inliers.as_deref().unwrap_or(&all));
    let start = *result.plucker.coordinates();
    let start_cost = exact_cost(&used, &start);
    let report = &mut result.report;
    report.certificate = None;
    let refinable = matches!(
        report.status,
        Status::Success | Status::GapNotClosed | Status::NotConverged
    ) && opts.method != Method::Linear
        && start_cost.is_finite();
    let mut line = start;
    if refinable {
        let Some((mut x, mut summary)) = refine(&problem, &used, &start, &opts.local) else {
            return Err(Error::Degenerate {
                what: "the estimated line lies at infinity".into(),
            });
        };
        if let (Some(tau), Some(flags)) = (opts.outlier_threshold, result.inliers.as_mut()) {
            // The inliers are those within τ at the exact optimum, re-solved while they change (as
            // the first-order robust stage does).
            x = reselect_at_optimum(
                flags,
                x,
                tau,
                &mut summary,
                |j, x| segments[j].squared_residual(x),
                |flags, x| {
                    (problem, used) = pick(flags);
                    refine(&problem, &used, x, &opts.local)
                },
            );
        }
        line = x;
        report.iterations += summary.iterations;
        report.termination = summary.termination;
        report.status = match summary.termination {
            Termination::NonFiniteCost | Termination::SingularHessian => Status::NumericalFailure,
            Termination::MaxIterations => Status::NotConverged,
            _ if opts.method == Method::Optimal => Status::GapNotClosed,
            _ => Status::Success,
        };
    } else if report.status == Status::Success && opts.method == Method::Optimal {
        report.status = Status::GapNotClosed;
    }
    let mut record = finish(&problem, &line, result.report.clone())?;
    record.report.cost = exact_cost(&used, record.plucker.coordinates());
    record.report.cost_kind = CostKind::Reprojection;
    if !record.report.cost.is_finite()
        && matches!(
            record.report.status,
            Status::Success | Status::GapNotClosed | Status::NotConverged
        )
    {
        // The exact cost overflowed (covariances near the smallest doubles) or a view has no image
        // of the line: nothing says this line is good.
        record.report.status = Status::NumericalFailure;
    }
    record.covariance = exact_covariance(&problem, &used, &record.chart);
    record.inliers = result.inliers.take();
    *result = record;
    Ok(())
}
