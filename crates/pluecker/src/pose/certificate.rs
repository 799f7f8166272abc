//! Certification of the pose: a proved lower bound on the reprojection cost over every pose that keeps
//! the object points in front of the camera.

use super::correspondences::Correspondences;
use super::reprojection::Pose;
use crate::camera::Camera;
use crate::error::{Error, Result};

/// Options of the certificate. Every field has a documented default.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CertificateOptions {
    /// Relative gap `(cost − lower_bound) / cost` at or below which the answer is certified. Default
    /// `1e-3` (as triangulation).
    pub gap: f64,
    /// Cap on the rotation cells examined by the search. Default `20_000`.
    pub max_nodes: usize,
}

impl Default for CertificateOptions {
    fn default() -> Self {
        CertificateOptions { gap: 1e-3, max_nodes: 20_000 }
    }
}

impl CertificateOptions {
    /// Checks the ranges stated on each field.
    pub fn validate(&self) -> Result<()> {
        if !(self.gap.is_finite() && self.gap > 0.0 && self.gap < 1.0) {
            return Err(Error::InvalidOption {
                name: "certify_gap".into(),
                reason: format!("must be in (0, 1), got {}", self.gap),
            });
        }
        if self.max_nodes < 1 {
            return Err(Error::InvalidOption {
                name: "certify_max_nodes".into(),
                reason: "must be at least 1".into(),
            });
        }
        Ok(())
    }
}

/// How the answer was certified, or why it was not.
#[derive(Debug, Clone, PartialEq)]
pub enum Certificate {
    /// [`super::PoseOptions::certify`] was `None`.
    NotRequested,
    /// Proved by the sublevel-set test after examining `nodes` rotation cells.
    SublevelSet {
        /// Rotation cells examined.
        nodes: usize,
    },
    /// Not proved; the reason.
    NotProved(String),
}

impl Certificate {
    /// `"not_requested"`, `"sublevel_set"` or `"not_proved"`.
    pub fn as_str(&self) -> &'static str {
        match self {
            Certificate::NotRequested => "not_requested",
            Certificate::SublevelSet { .. } => "sublevel_set",
            Certificate::NotProved(_) => "not_proved",
        }
    }

    /// A sentence for reports.
    pub fn message(&self) -> String {
        match self {
            Certificate::NotRequested => "not requested (certify=False)".into(),
            Certificate::SublevelSet { nodes } => format!("proved by the sublevel-set test ({nodes} rotation cells)"),
            Certificate::NotProved(why) => why.clone(),
        }
    }
}

/// The certificate stage's outcome.
#[derive(Debug, Clone, PartialEq)]
pub struct Certification {
    pub certified: bool,
    pub lower_bound: f64,
    pub gap: f64,
    pub certificate: Certificate,
}

impl Certification {
    /// No certificate, for `reason`.
    pub fn none(certificate: Certificate) -> Self {
        Certification {
            certified: false,
            lower_bound: f64::NAN,
            gap: f64::NAN,
            certificate,
        }
    }
}

/// Certifies `pose` (conditioned frame of `corr`), a local minimum of cost `cost` = `½ Σ r²`.
pub fn certify(camera: &Camera, corr: &Correspondences, pose: &Pose, cost: f64, options: &CertificateOptions) -> Certification {
    let _ = (camera, corr, pose, cost, options);
    Certification::none(Certificate::NotProved("not implemented".into()))
}
