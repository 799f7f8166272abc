//! `estimate_pose`: keyword options → `PoseOptions`, arrays → `Correspondences`, the solve with the
//! GIL released.

use crate::camera::PyCamera;
use crate::convert::{optional_real, points, rotation, seconds_arg, segments, vector, Integer, Real};
use crate::errors::shape_error;
use crate::interrupt::{run_interruptible, with_partial};
use crate::result::PyPoseResult;
use nalgebra::{Matrix3, Vector3};
use pluecker::pose::{Correspondences, Method, PoseOptions, RansacOptions};
use pluecker::Error;
use pyo3::prelude::*;
use pyo3::types::PyTuple;

/// The four correspondence arrays, converted and checked (shapes, finiteness, matching counts).
pub fn correspondences(
    points2d: Option<&Bound<'_, PyAny>>,
    points3d: Option<&Bound<'_, PyAny>>,
    lines2d: Option<&Bound<'_, PyAny>>,
    lines3d: Option<&Bound<'_, PyAny>>,
) -> PyResult<Correspondences> {
    let c = Correspondences {
        points2d: points::<2>("points2d", points2d)?,
        points3d: points::<3>("points3d", points3d)?,
        lines2d: segments::<2>("lines2d", lines2d)?,
        lines3d: segments::<3>("lines3d", lines3d)?,
    };
    if c.points2d.len() != c.points3d.len() {
        let actual = format!("{} and {} rows", c.points2d.len(), c.points3d.len());
        return Err(shape_error("points2d / points3d", "the same number of rows", actual));
    }
    if c.lines2d.len() != c.lines3d.len() {
        let actual = format!("{} and {} segments", c.lines2d.len(), c.lines3d.len());
        return Err(shape_error("lines2d / lines3d", "the same number of segments", actual));
    }
    Ok(c)
}

/// A pose argument `(R, t)`: a rotation matrix and a `(3,)` translation.
pub fn pose_arg(
    r_name: &str,
    r: &Bound<'_, PyAny>,
    t_name: &str,
    t: &Bound<'_, PyAny>,
) -> PyResult<(Matrix3<f64>, Vector3<f64>)> {
    Ok((rotation(r_name, r)?, vector::<3>(t_name, t)?))
}

/// The options, from the keyword arguments of `estimate_pose`.
#[allow(clippy::too_many_arguments)]
fn options(
    method: &str,
    penalty: Real,
    normalize: bool,
    refine: bool,
    initial_pose: Option<&Bound<'_, PyTuple>>,
    max_iterations: Integer,
    refine_max_iterations: Integer,
) -> PyResult<PoseOptions> {
    let mut opts = PoseOptions {
        method: Method::parse(method).map_err(crate::errors::to_py_err)?,
        lambda: penalty.get("penalty")?,
        normalize,
        refine,
        ..PoseOptions::default()
    };
    if let Some(pair) = initial_pose {
        if pair.len() != 2 {
            let actual = format!("a tuple of length {}", pair.len());
            return Err(shape_error("initial_pose", "a tuple (R, t)", actual));
        }
        opts.initial_pose = Some(pose_arg(
            "initial_pose R",
            &pair.get_item(0)?,
            "initial_pose t",
            &pair.get_item(1)?,
        )?);
    }
    let cap = max_iterations.count("max_iterations", 1)?;
    opts.trust_region.stopping.max_iterations = cap;
    opts.levenberg_marquardt.stopping.max_iterations = cap;
    opts.newton.max_iterations = cap;
    opts.refinement.stopping.max_iterations = refine_max_iterations.count("refine_max_iterations", 1)?;
    Ok(opts)
}

/// The keyword arguments of the robust estimator, as given.
pub struct RobustArgs {
    pub robust: bool,
    pub point_threshold: Real,
    pub line_threshold: Real,
    pub confidence: Real,
    pub max_ransac_iterations: Integer,
    pub time_budget: Option<Real>,
    pub seed: Integer,
    pub min_inliers: Integer,
    pub min_inlier_ratio: Real,
    pub sprt: bool,
}

impl RobustArgs {
    /// The options, checked whether or not `robust` is set (a bad value is an error either way);
    /// `None` when not robust.
    fn options(&self) -> PyResult<Option<RansacOptions>> {
        let budget = optional_real("time_budget", self.time_budget)?
            .map(|s| seconds_arg("time_budget", s))
            .transpose()?;
        let opts = RansacOptions {
            point_threshold: self.point_threshold.get("point_threshold")?,
            line_threshold: self.line_threshold.get("line_threshold")?,
            confidence: self.confidence.get("confidence")?,
            max_iterations: self.max_ransac_iterations.count("max_ransac_iterations", 1)?,
            time_budget: budget,
            seed: self.seed.seed("seed")?,
            min_inliers: self.min_inliers.count("min_inliers", 3)?,
            min_inlier_ratio: self.min_inlier_ratio.get("min_inlier_ratio")?,
            sprt: self.sprt,
            ..RansacOptions::default()
        };
        opts.validate().map_err(crate::errors::to_py_err)?;
        Ok(self.robust.then_some(opts))
    }
}

/// Correspondences from which `estimate_pose` runs on a worker thread, so that Ctrl-C stops it
/// within about 0.1 s (fewer take milliseconds, and run on the calling thread).
const SHORT_POSE: usize = 1000;

/// Estimates the pose `x_cam = R X_world + t` from point and/or line correspondences, optionally
/// robustly (LO-RANSAC), with its covariance.
#[pyfunction]
#[pyo3(signature = (
    camera, points2d = None, points3d = None, lines2d = None, lines3d = None, method = "trust-region", *,
    penalty = Real::new(50.0), normalize = true, refine = true, initial_pose = None,
    max_iterations = Integer::new(200), refine_max_iterations = Integer::new(50), robust = false,
    point_threshold = Real::new(4.0), line_threshold = Real::new(4.0), confidence = Real::new(0.9999),
    max_ransac_iterations = Integer::new(100_000), time_budget = None, seed = Integer::new(0),
    min_inliers = Integer::new(6), min_inlier_ratio = Real::new(0.1), sprt = true, sigma_px = None,
    certify = false, certify_gap = Real::new(1e-3), ambiguity_threshold = Real::new(9.0)
), text_signature = "(camera, points2d=None, points3d=None, lines2d=None, lines3d=None, method='trust-region', *, penalty=50.0, normalize=True, refine=True, initial_pose=None, max_iterations=200, refine_max_iterations=50, robust=False, point_threshold=4.0, line_threshold=4.0, confidence=0.9999, max_ransac_iterations=100000, time_budget=None, seed=0, min_inliers=6, min_inlier_ratio=0.1, sprt=True, sigma_px=None, certify=False, certify_gap=0.001, ambiguity_threshold=9.0)")]
#[allow(clippy::too_many_arguments)]
pub fn estimate_pose(
    py: Python<'_>,
    camera: &Bound<'_, PyCamera>,
    points2d: Option<&Bound<'_, PyAny>>,
    points3d: Option<&Bound<'_, PyAny>>,
    lines2d: Option<&Bound<'_, PyAny>>,
    lines3d: Option<&Bound<'_, PyAny>>,
    method: &str,
    penalty: Real,
    normalize: bool,
    refine: bool,
    initial_pose: Option<&Bound<'_, PyTuple>>,
    max_iterations: Integer,
    refine_max_iterations: Integer,
    robust: bool,
    point_threshold: Real,
    line_threshold: Real,
    confidence: Real,
    max_ransac_iterations: Integer,
    time_budget: Option<Real>,
    seed: Integer,
    min_inliers: Integer,
    min_inlier_ratio: Real,
    sprt: bool,
    sigma_px: Option<Real>,
    certify: bool,
    certify_gap: Real,
    ambiguity_threshold: Real,
) -> PyResult<Py<PyPoseResult>> {
    let camera = camera.get().inner;
    let mut opts = options(
        method,
        penalty,
        normalize,
        refine,
        initial_pose,
        max_iterations,
        refine_max_iterations,
    )?;
    opts.robust = RobustArgs {
        robust,
        point_threshold,
        line_threshold,
        confidence,
        max_ransac_iterations,
        time_budget,
        seed,
        min_inliers,
        min_inlier_ratio,
        sprt,
    }
    .options()?;
    opts.sigma_px = optional_real("sigma_px", sigma_px)?;
    opts.ambiguity_threshold = ambiguity_threshold.get("ambiguity_threshold")?;
    let certificate = pluecker::pose::CertificateOptions {
        gap: certify_gap.get("certify_gap")?,
        ..Default::default()
    };
    certificate.validate().map_err(crate::errors::to_py_err)?;
    opts.certify = certify.then_some(certificate);
    let corr = correspondences(points2d, points3d, lines2d, lines3d)?;
    // A pose from fewer correspondences ends within milliseconds (see `interrupt::run_interruptible`).
    let short = corr.n_points() + corr.n_lines() < SHORT_POSE;
    let outcome = run_interruptible(py, None, None, short, move |_| {
        pluecker::estimate_pose(&camera, &corr, &opts).map_err(|e| match e {
            // The core calls the paper's λ `lambda`; Python calls it `penalty`.
            Error::InvalidOption { name, reason } if name == "lambda" => Error::InvalidOption {
                name: "penalty".into(),
                reason,
            },
            e => e,
        })
    })?;
    let result = Py::new(py, PyPoseResult::wrap(outcome.value))?;
    match outcome.pending {
        // Ctrl-C: the pose reached so far (RANSAC stopped with `ransac_stop == "interrupted"`).
        Some(e) => Err(with_partial(py, e, result.into_any())),
        None => Ok(result),
    }
}
