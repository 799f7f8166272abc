//! One status for every estimate, pose or triangulated primitive: whether the answer can be used,
//! and if not why. Each estimator's docs say which variants it returns.

use crate::error::Error;
use crate::interrupt::StopReason;

/// Whether an estimate can be used, and if not why.
#[derive(Debug, Clone, Copy, PartialEq, Eq, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
#[non_exhaustive]
pub enum Status {
    /// The method finished: every stage converged (pose: every object point in front of the camera);
    /// with a certificate requested, it holds within the gap.
    Success,
    /// A certificate was requested and does not hold within the gap: the search hit its node cap,
    /// or no bound exists for these data (the certificate, if any, holds the bound reached). The
    /// estimate is the best found.
    GapNotClosed,
    /// A stage stopped on its iteration cap; the estimate is the last iterate.
    NotConverged,
    /// Pose: some object points or line endpoints are behind the camera at the returned pose
    /// (robust: of the inliers), or the data are explained better by a pose with every point behind
    /// the camera. Triangulation: the estimate lies behind (or on the principal plane of) at least
    /// one camera.
    BehindCamera,
    /// Pose: another local minimum of the reprojection error with every object point in front
    /// explains the data nearly as well (`PoseOptions::ambiguity_threshold`); every stage converged.
    Ambiguous,
    /// Triangulation: the estimate is a point at infinity: parallel rays, or every point in front of
    /// the cameras costs more than a point at infinity. No finite point is returned.
    AtInfinity,
    /// The solver failed numerically (a singular system, a non-finite cost, a conic solver failure).
    NumericalFailure,
    /// Robust estimation: too few observations or correspondences agree on one answer (pose: fewer
    /// than the required inliers; triangulation: fewer than two views of the track).
    TooFewInliers,
    /// Robust pose: no sample gave a pose in front of the camera (every sample degenerate, or no
    /// minimal solver for this mix of data). The pose is NaN.
    NoHypothesis,
    /// The call was stopped ([`crate::interrupt`]: Ctrl-C, a failed progress callback) before the
    /// solve ended: the estimate and lower bound are those reached, uncertified. In a batch, a track
    /// not started when the stop came is rejected with the same status and no estimate.
    Interrupted,
    /// Like [`Status::Interrupted`], stopped because the call's time budget ran out.
    TimeBudget,
    /// A batch track (or a distributed query) rejected before any solve: fewer views than the
    /// primitive needs ([`Error::TooFewCorrespondences`]).
    TooFewViews,
    /// Rejected: a NaN or infinite input value ([`Error::NonFinite`]).
    NonFinite,
    /// Rejected: the data cannot determine the estimate, e.g. a zero-length segment
    /// ([`Error::Degenerate`]).
    Degenerate,
    /// Rejected: a camera that cannot be inverted ([`Error::SingularCamera`]).
    SingularCamera,
    /// Rejected: an input of the wrong shape or naming something that does not exist, e.g. an image id
    /// that is not among the cameras ([`Error::Shape`]).
    InvalidInput,
    /// Rejected: an option outside its documented range ([`Error::InvalidOption`]).
    InvalidOption,
}

impl Status {
    /// snake_case name for reports, JSON and Python.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }

    /// The status of a solve stopped for `reason`.
    pub fn stopped(reason: StopReason) -> Status {
        match reason {
            StopReason::Requested => Status::Interrupted,
            StopReason::TimeBudget => Status::TimeBudget,
        }
    }

    /// The status of a problem rejected with `err` before any solve (one bad track of a batch, one
    /// bad query of a distributed job): the error's kind, named.
    pub fn rejected(err: &Error) -> Status {
        match err {
            Error::TooFewCorrespondences { .. } => Status::TooFewViews,
            Error::NonFinite { .. } => Status::NonFinite,
            Error::Degenerate { .. } => Status::Degenerate,
            Error::SingularCamera { .. } => Status::SingularCamera,
            Error::Shape { .. } => Status::InvalidInput,
            Error::InvalidOption { .. } => Status::InvalidOption,
            Error::Interrupted { reason } => Status::stopped(*reason),
        }
    }
}

// Written and read by name with the `serde` feature.
crate::names::serde_by_name!(Status);
