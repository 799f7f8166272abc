//! The reprojection cost of a rig's pose: the sum over its cameras of each camera's own cost
//! ([`ReprojectionCost::exact`]: points and segments in that camera's pixels, through its lens,
//! weighted by their noise) at the camera's pose `sensor_from_world = sensor_from_rig ∘ rig_from_world`.
//!
//! Its tangent is the rig's `(ω, δt)`: `exp(ω) R`, `t + δt` ([`crate::pose::PoseResult::covariance`]),
//! rig frame. Camera `k`'s pose `(R_k R, R_k t + t_k)` then moves by `exp(R_k ω) R_k R` and
//! `R_k δt`, so its residuals' Jacobian in the rig's tangent is its own times
//! `B_k = diag(R_k, R_k)`: the gradient is `Σ B_kᵀ g_k` and the Gauss-Newton matrix `Σ B_kᵀ H_k B_k`.

use super::ObservingCameras;
use crate::camera_pose::Pose;
use crate::error::Result;
use crate::optim::{trust_region, Linearization, Objective, Summary, TrustRegionOptions};
use crate::pose::refinement::PoseCost;
use crate::pose::reprojection::{covariance_from_information, retract, ReprojectionCost};
use crate::pose::Correspondences;
use crate::rig::{tangent_map, Rig};
use nalgebra::{SMatrix, SVector};

/// One camera's share of a rig's observations: its correspondences, in the order of the input, and
/// the input's rows they came from.
#[derive(Debug, Clone)]
pub(crate) struct CameraShare {
    pub camera: usize,
    pub corr: Correspondences,
    pub points: Vec<usize>,
    pub lines: Vec<usize>,
}

/// The observations of a rig split by the camera that saw them (the data of
/// [`RigReprojectionCost`], which borrows them).
#[derive(Debug, Clone)]
pub struct RigObservations {
    pub(crate) shares: Vec<CameraShare>,
    n_points: usize,
    n_lines: usize,
}

impl RigObservations {
    /// `corr` split by `cameras`, checked against `rig` ([`ObservingCameras::check`]).
    pub fn new(rig: &Rig, corr: &Correspondences, cameras: &ObservingCameras) -> Result<RigObservations> {
        cameras.check(rig, corr)?;
        let shares = cameras
            .used(rig, corr)
            .into_iter()
            .map(|k| {
                let points: Vec<bool> = (0..corr.n_points()).map(|i| cameras.point(i) == k).collect();
                let lines: Vec<bool> = (0..corr.n_lines()).map(|j| cameras.line(j) == k).collect();
                let rows = |mask: &[bool]| (0..mask.len()).filter(|&i| mask[i]).collect();
                CameraShare {
                    camera: k,
                    corr: crate::pose::robust::scoring::subset(corr, &points, &lines),
                    points: rows(&points),
                    lines: rows(&lines),
                }
            })
            .collect();
        Ok(RigObservations {
            shares,
            n_points: corr.n_points(),
            n_lines: corr.n_lines(),
        })
    }
}

/// The reprojection cost of a rig's observations at `rig_from_world` (module docs), with its
/// Jacobian in the rig's tangent `(ω, t)`.
pub struct RigReprojectionCost<'a> {
    rig: &'a Rig,
    /// Per camera with observations: its share and its cost.
    costs: Vec<(&'a CameraShare, ReprojectionCost<'a>)>,
    n_points: usize,
    n_lines: usize,
}

impl<'a> RigReprojectionCost<'a> {
    /// The cost of `observations` (split from one rig's correspondences) seen by `rig`.
    pub fn new(rig: &'a Rig, observations: &'a RigObservations) -> Result<Self> {
        let costs = observations
            .shares
            .iter()
            .map(|share| {
                Ok((
                    share,
                    ReprojectionCost::exact(&rig.cameras()[share.camera], &share.corr)?,
                ))
            })
            .collect::<Result<_>>()?;
        Ok(RigReprojectionCost {
            rig,
            costs,
            n_points: observations.n_points,
            n_lines: observations.n_lines,
        })
    }

    /// Number of scalar residuals: two per point and two per segment.
    pub fn residual_count(&self) -> usize {
        2 * (self.n_points + self.n_lines)
    }

    /// Per-correspondence reprojection errors in their camera's pixels (whitened units with noise),
    /// in the order of the input: the point distance for points, then the RMS of the two endpoint
    /// distances for segments (as [`ReprojectionCost::errors`]).
    pub fn errors(&self, pose: &Pose) -> Vec<f64> {
        let mut errors = vec![f64::NAN; self.n_points + self.n_lines];
        for (share, cost) in &self.costs {
            let own = cost.errors(&self.rig.sensor_from_world(share.camera, pose));
            let rows = share
                .points
                .iter()
                .copied()
                .chain(share.lines.iter().map(|j| self.n_points + j));
            for (row, e) in rows.zip(own) {
                errors[row] = e;
            }
        }
        errors
    }

    /// The covariance of `rig_from_world` at `pose`, 6x6 in the rig's tangent `(ω, t)`: `σ² (JᵀJ)⁻¹`
    /// for pixel noise `sigma_px` (whitened units with noise); `None` when `JᵀJ` is singular (the
    /// observations do not fix the pose).
    pub fn covariance(&self, pose: &Pose, sigma_px: f64) -> Option<SMatrix<f64, 6, 6>> {
        covariance_from_information(&self.linearize(pose).gauss_newton, sigma_px)
    }
}

impl Objective<6> for RigReprojectionCost<'_> {
    type Point = Pose;

    fn cost(&self, pose: &Pose) -> f64 {
        self.costs
            .iter()
            .map(|(share, cost)| cost.cost(&self.rig.sensor_from_world(share.camera, pose)))
            .sum()
    }

    fn linearize(&self, pose: &Pose) -> Linearization<6> {
        let mut total = Linearization::zero();
        for (share, cost) in &self.costs {
            let own = cost.linearize(&self.rig.sensor_from_world(share.camera, pose));
            total.add_mapped(&own, &tangent_map(&self.rig.sensor_from_rig()[share.camera].rotation));
        }
        total
    }

    fn retract(&self, pose: &Pose, d: &SVector<f64, 6>) -> Pose {
        retract(pose, d)
    }
}

impl PoseCost for RigReprojectionCost<'_> {
    fn residual_count(&self) -> usize {
        RigReprojectionCost::residual_count(self)
    }

    fn cost_below(&self, pose: &Pose, bound: f64) -> Option<f64> {
        let mut sum = 0.0;
        for (share, cost) in &self.costs {
            sum += cost.cost_below(&self.rig.sensor_from_world(share.camera, pose), bound - sum)?;
        }
        (sum < bound).then_some(sum)
    }

    fn points_behind(&self, pose: &Pose) -> usize {
        self.costs
            .iter()
            .map(|(share, cost)| cost.points_behind(&self.rig.sensor_from_world(share.camera, pose)))
            .sum()
    }
}

/// Minimises the rig's reprojection cost of `observations` from `initial` (`rig_from_world`) with the
/// trust region of section 4.1 and `options`; the pose reached and the solver's summary (costs
/// `½ Σ r²`).
pub fn refine(
    rig: &Rig,
    observations: &RigObservations,
    initial: &Pose,
    options: &TrustRegionOptions,
) -> Result<(Pose, Summary)> {
    let cost = RigReprojectionCost::new(rig, observations)?;
    Ok(trust_region::minimize(&cost, *initial, options))
}
