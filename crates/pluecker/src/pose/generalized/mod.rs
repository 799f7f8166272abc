//! The pose of a camera rig: the generalised absolute pose, `x_rig = R X_world + t`, from points and
//! segments seen by any of the rig's cameras ([`crate::Rig`], `x_sensor = R_k x_rig + t_k`).
//!
//! Every observation is a ray of the rig's frame that need not pass through one common centre (in
//! Plücker coordinates `(d, c × d)`, `c` its camera's centre): the cost is the reprojection error in
//! each camera's own pixels, through its own lens, points and segments as for one camera
//! ([`RigReprojectionCost`], the single camera's kernel per camera). [`estimate_rig_pose`] finds its
//! minimum:
//!
//! - observations all in one camera (a rig of one camera, or a frame where only one camera saw
//!   anything) are that camera's pose problem exactly: the single camera's pipeline
//!   ([`crate::pose::estimate_pose`]), with its global search, robust loop and certificate, and its pose
//!   moved into the rig's frame;
//! - otherwise the starts are the linear pose of the rays ([`linear_pose`], from six points off a
//!   plane), the minimal generalised poses of triples of correspondences (points and segments) spread
//!   over the cameras ([`crate::pose::minimal::solve_generalized`]), the single camera's answer for
//!   the camera that saw the most (with segments or fewer than six points), and the user's guess; each
//!   is refined with the trust region of section 4.1 (Phong & Horaud 1995) and the distinct minima
//!   compared as for one camera (the runner-up, the ambiguity test);
//! - with [`crate::pose::PoseOptions::ransac`], the one consensus loop (`crate::consensus`) draws
//!   triples of correspondences, solves them with the same minimal solvers, scores them by the
//!   truncated reprojection error in each camera's pixels and re-fits the best on its inliers.
//!
//! The certificate of global optimality (with [`crate::pose::PoseOptions::certify`]) is the single
//! camera's proof for observations in one camera; for several pinhole cameras it is the same
//! sublevel-set test over every camera's residuals, each point and segment in its own camera
//! (`crate::pose::certificate`'s `problem` module docs): a lower bound on the cost over every pose of
//! the rig that keeps the points in front of their cameras. Not for several cameras with lenses, nor
//! where no two points bound the depths: a requested certificate then leaves the status
//! [`crate::Status::GapNotClosed`] with the reason in `details.uncertified_reason`.

mod cost;
mod estimate;
mod linear;
mod problem;
mod robust;

pub use cost::{refine, RigObservations, RigReprojectionCost};
pub use estimate::estimate_rig_pose;
pub use linear::{linear_pose, rays, Ray};

use crate::error::{Error, Result};
use crate::pose::Correspondences;
use crate::rig::Rig;

/// Which camera of a rig saw each observation of a [`Correspondences`]: `point_cameras[i]` is the
/// index (in [`Rig::cameras`]) of the camera whose pixels `points2d[i]` are, `line_cameras[j]` that of
/// `lines2d[j]`. Empty vectors: every observation is camera 0's (for a rig of one camera).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ObservingCameras {
    /// One camera index per point.
    pub point_cameras: Vec<usize>,
    /// One camera index per segment.
    pub line_cameras: Vec<usize>,
}

impl ObservingCameras {
    /// The camera of point `i`.
    pub(crate) fn point(&self, i: usize) -> usize {
        self.point_cameras.get(i).copied().unwrap_or(0)
    }

    /// The camera of segment `j`.
    pub(crate) fn line(&self, j: usize) -> usize {
        self.line_cameras.get(j).copied().unwrap_or(0)
    }

    /// Checks one index per observation of `corr` (or none, for a rig of one camera), each a camera
    /// of `rig`: [`Error::Shape`] naming `point_cameras` / `line_cameras` and the row.
    pub fn check(&self, rig: &Rig, corr: &Correspondences) -> Result<()> {
        for (what, indices, rows) in [
            ("point_cameras", &self.point_cameras, corr.n_points()),
            ("line_cameras", &self.line_cameras, corr.n_lines()),
        ] {
            if indices.is_empty() && (rows == 0 || rig.len() == 1) {
                continue;
            }
            if indices.len() != rows {
                return Err(Error::Shape {
                    what: what.into(),
                    expected: format!("one camera index per observation ({rows})"),
                    actual: format!("{} indices", indices.len()),
                });
            }
            if let Some(i) = indices.iter().position(|&k| k >= rig.len()) {
                return Err(Error::Shape {
                    what: format!("{what}[{i}]"),
                    expected: format!("a camera index below {} (the rig's cameras)", rig.len()),
                    actual: indices[i].to_string(),
                });
            }
        }
        Ok(())
    }

    /// The cameras that saw at least one observation, in increasing order.
    pub(crate) fn used(&self, rig: &Rig, corr: &Correspondences) -> Vec<usize> {
        let mut seen = vec![false; rig.len()];
        for i in 0..corr.n_points() {
            seen[self.point(i)] = true;
        }
        for j in 0..corr.n_lines() {
            seen[self.line(j)] = true;
        }
        (0..rig.len()).filter(|&k| seen[k]).collect()
    }

    /// The observations of `corr` selected by the masks, with their cameras.
    pub(crate) fn subset(&self, points: &[bool], lines: &[bool]) -> ObservingCameras {
        ObservingCameras {
            point_cameras: (0..points.len())
                .filter(|&i| points[i])
                .map(|i| self.point(i))
                .collect(),
            line_cameras: (0..lines.len()).filter(|&j| lines[j]).map(|j| self.line(j)).collect(),
        }
    }
}

#[cfg(test)]
mod tests;
