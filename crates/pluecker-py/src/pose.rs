//! `estimate_pose`: keyword options → `PoseOptions`, arrays → `Correspondences`, the solve with the
//! GIL released.

use crate::camera::PyCamera;
use crate::convert::{points, rotation, seconds_arg, segments, vector};
use crate::errors::{invalid_argument, shape_error, solve};
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

fn iteration_cap(name: &str, value: i64) -> PyResult<usize> {
    if value < 1 {
        return Err(invalid_argument(name, format!("must be at least 1, got {value}")));
    }
    Ok(value as usize)
}

/// The options, from the keyword arguments of `estimate_pose`.
#[allow(clippy::too_many_arguments)]
fn options(
    method: &str,
    penalty: f64,
    normalize: bool,
    refine: bool,
    initial_pose: Option<&Bound<'_, PyTuple>>,
    max_iterations: i64,
    refine_max_iterations: i64,
) -> PyResult<PoseOptions> {
    let mut opts = PoseOptions {
        method: Method::parse(method).map_err(crate::errors::to_py_err)?,
        lambda: penalty,
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
    let cap = iteration_cap("max_iterations", max_iterations)?;
    opts.trust_region.stopping.max_iterations = cap;
    opts.levenberg_marquardt.stopping.max_iterations = cap;
    opts.newton.max_iterations = cap;
    opts.refinement.stopping.max_iterations = iteration_cap("refine_max_iterations", refine_max_iterations)?;
    Ok(opts)
}

/// The keyword arguments of the robust estimator, as given.
pub struct RobustArgs {
    pub robust: bool,
    pub point_threshold: f64,
    pub line_threshold: f64,
    pub confidence: f64,
    pub max_ransac_iterations: i64,
    pub time_budget: Option<f64>,
    pub seed: i64,
    pub min_inliers: i64,
    pub min_inlier_ratio: f64,
    pub sprt: bool,
}

impl RobustArgs {
    /// The options, checked whether or not `robust` is set (a bad value is an error either way);
    /// `None` when not robust.
    fn options(&self) -> PyResult<Option<RansacOptions>> {
        let budget = self.time_budget.map(|s| seconds_arg("time_budget", s)).transpose()?;
        if self.seed < 0 {
            return Err(invalid_argument("seed", format!("must be ≥ 0, got {}", self.seed)));
        }
        if self.min_inliers < 3 {
            return Err(invalid_argument(
                "min_inliers",
                format!("must be at least 3, got {}", self.min_inliers),
            ));
        }
        let opts = RansacOptions {
            point_threshold: self.point_threshold,
            line_threshold: self.line_threshold,
            confidence: self.confidence,
            max_iterations: iteration_cap("max_ransac_iterations", self.max_ransac_iterations)?,
            time_budget: budget,
            seed: self.seed as u64,
            min_inliers: self.min_inliers as usize,
            min_inlier_ratio: self.min_inlier_ratio,
            sprt: self.sprt,
            ..RansacOptions::default()
        };
        opts.validate().map_err(crate::errors::to_py_err)?;
        Ok(self.robust.then_some(opts))
    }
}

/// Estimates the pose `x_cam = R X_world + t` from point and/or line correspondences, optionally
/// robustly (LO-RANSAC), with its covariance.
#[pyfunction]
#[pyo3(signature = (
    camera, points2d = None, points3d = None, lines2d = None, lines3d = None, method = "trust-region", *,
    penalty = 50.0, normalize = true, refine = true, initial_pose = None, max_iterations = 200,
    refine_max_iterations = 50, robust = false, point_threshold = 4.0, line_threshold = 4.0,
    confidence = 0.9999, max_ransac_iterations = 100_000, time_budget = None, seed = 0, min_inliers = 6,
    min_inlier_ratio = 0.1, sprt = true, sigma_px = None, certify = false, certify_gap = 1e-3, ambiguity_threshold = 9.0
))]
#[allow(clippy::too_many_arguments)]
pub fn estimate_pose(
    py: Python<'_>,
    camera: &Bound<'_, PyCamera>,
    points2d: Option<&Bound<'_, PyAny>>,
    points3d: Option<&Bound<'_, PyAny>>,
    lines2d: Option<&Bound<'_, PyAny>>,
    lines3d: Option<&Bound<'_, PyAny>>,
    method: &str,
    penalty: f64,
    normalize: bool,
    refine: bool,
    initial_pose: Option<&Bound<'_, PyTuple>>,
    max_iterations: i64,
    refine_max_iterations: i64,
    robust: bool,
    point_threshold: f64,
    line_threshold: f64,
    confidence: f64,
    max_ransac_iterations: i64,
    time_budget: Option<f64>,
    seed: i64,
    min_inliers: i64,
    min_inlier_ratio: f64,
    sprt: bool,
    sigma_px: Option<f64>,
    certify: bool,
    certify_gap: f64,
    ambiguity_threshold: f64,
) -> PyResult<PyPoseResult> {
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
    opts.sigma_px = sigma_px;
    opts.ambiguity_threshold = ambiguity_threshold;
    let certificate = pluecker::pose::CertificateOptions {
        gap: certify_gap,
        ..Default::default()
    };
    certificate.validate().map_err(crate::errors::to_py_err)?;
    opts.certify = certify.then_some(certificate);
    let corr = correspondences(points2d, points3d, lines2d, lines3d)?;
    let result = solve(py, move || {
        pluecker::estimate_pose(&camera, &corr, &opts).map_err(|e| match e {
            // The core calls the paper's λ `lambda`; Python calls it `penalty`.
            Error::InvalidOption { name, reason } if name == "lambda" => Error::InvalidOption {
                name: "penalty".into(),
                reason,
            },
            e => e,
        })
    })?;
    Ok(PyPoseResult::wrap(result))
}
