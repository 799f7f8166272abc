//! What a reported cost measures: one vocabulary for the stages of a pose and for every triangulated
//! primitive, so that two costs are compared only when they are of one kind.
//!
//! A certificate ([`crate::Certificate`]) always bounds the cost its result reports, of the kind that
//! result names: a bound proved on one kind is never attached to a cost of another.

/// What a cost measures (`PoseDetails.stages[].cost_kind`, `TriangulationReport.cost_kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
pub enum CostKind {
    /// The pose paper's algebraic cost (eqs. 13-15, 22 as `½ΣΦ²`, normalised units).
    Algebraic,
    /// `Σ r²` over the reprojection residuals in the observed pixels, whitened by the given covariances
    /// (squared pixels without): for a point its pixel error, for an image segment the distances of its
    /// two endpoints to the image of the line (the curved image through a lens with distortion; the
    /// Mahalanobis distance with covariances). The pose's refinement and certificate; triangulated
    /// points (Josephson & Kahl's eq. 19 for a point is this cost); lines from segments seen through a
    /// lens that distorts.
    Reprojection,
    /// The robust loop's truncated reprojection cost `Σ min(eᵢ², τᵢ²)` (squared pixels).
    Msac,
    /// Josephson & Kahl's eq. 19 on the residual of an image line (eq. 17 in the line's own frame,
    /// section 3.1: the line's angle and offset), whitened by the residual's covariance (eq. 18):
    /// lines from homogeneous image lines, and from segments seen by pinhole cameras (or lenses that do
    /// not distort), whose residual covariance comes from the endpoints' noise. For segments it agrees
    /// with [`CostKind::Reprojection`] to first order at the observed lines, not beyond: at a line
    /// whose image passes at signed distances `x`, `y` from the endpoints, each view's term is their
    /// reprojection cost times a factor that is 1 at the observed line (`docs/triangulation.md`).
    LineResidual,
    /// Josephson & Kahl's eq. 19 on the residual of an image conic (eq. 17, five entries of the conic
    /// normalised as in section 3.1), whitened by its covariance (eq. 18): quadrics.
    ConicResidual,
}

impl CostKind {
    /// snake_case name for reports, JSON and Python.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }
}

// Written and read by name with the `serde` feature.
crate::names::serde_by_name!(CostKind);
