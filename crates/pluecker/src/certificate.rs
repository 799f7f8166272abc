//! One certificate of global optimality for pose and triangulation: the options of every search
//! ([`CertifyOptions`]), the proved lower bound and relative gap ([`Certificate`]), how it was
//! proved ([`CertificateKind`]) and over which set ([`CertificateKind::domain`]).
//!
//! Costs are sums of squared (whitened) pixel residuals, `Σ r²`, for pose and triangulation alike.
//! The gap is `(cost − lower_bound) / max(cost, 1e-12)` ([`crate::global::relative_gap`]; `1e-12` is
//! [`crate::global::CERTIFICATE_COST_FLOOR`]).

/// Options of every certificate. Every field has a documented default.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct CertifyOptions {
    /// The answer is certified when `(cost − lower_bound) / max(cost, 1e-12) ≤ max_relative_gap`.
    /// Default `1e-3`.
    pub max_relative_gap: f64,
    /// Cap on the nodes (rotation cells, boxes) a search examines; `None` (the default): each
    /// search's own cap, stated in its docs (their nodes differ in cost by 100x).
    pub max_nodes: Option<usize>,
}

impl Default for CertifyOptions {
    fn default() -> Self {
        CertifyOptions {
            max_relative_gap: 1e-3,
            max_nodes: None,
        }
    }
}

impl CertifyOptions {
    /// The node cap of a search whose own default is `default`.
    pub fn max_nodes_or(&self, default: usize) -> usize {
        self.max_nodes.unwrap_or(default)
    }

    /// Checks the ranges stated on each field; `name` is the options' name in error messages
    /// (`"certify"`).
    pub fn validate(&self, name: &str) -> crate::error::Result<()> {
        if !(self.max_relative_gap.is_finite() && self.max_relative_gap > 0.0 && self.max_relative_gap < 1.0) {
            return Err(crate::error::Error::InvalidOption {
                name: format!("{name}.max_relative_gap"),
                reason: format!("must be in (0, 1), got {}", crate::error::number(self.max_relative_gap)),
            });
        }
        if self.max_nodes == Some(0) {
            return Err(crate::error::Error::InvalidOption {
                name: format!("{name}.max_nodes"),
                reason: "must be at least 1".into(),
            });
        }
        Ok(())
    }
}

/// How global optimality was established.
#[derive(Debug, Clone, Copy, PartialEq, Eq, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
pub enum CertificateKind {
    /// Not attempted (methods `linear` and `local`).
    None,
    /// A sufficient condition proved the local minimum global without branching.
    ConvexityTest,
    /// Branch and bound closed the gap (the SOCP relaxations of section 4).
    BranchAndBound,
    /// Lines: interval branch and bound with Taylor bounds over the two-view chart
    /// (`line::taylor_search`), whose domain is every line not within 1 % of
    /// the local line's distance from a camera centre.
    TaylorBranchAndBound,
    /// Points through lenses with distortion: the convexity test of the linearisation at the
    /// estimate, carried to the exact cost by interval bounds of the lenses' Jacobians
    /// (`point::lens`), whose domain is every point whose projections lie
    /// inside the disc where each lens is proved one-to-one.
    LensConvexityTest,
    /// Pose: the sublevel-set test (`pose::certificate`): a search over rotation cells that
    /// confines every pose as good as the estimate to a ball around it, then a bound on that ball.
    SublevelSet,
    /// Pose through a lens with distortion: the sublevel-set test on the whitened pinhole problem of
    /// the linearisation at the estimate, carried to the exact cost by interval bounds of the lens's
    /// Jacobian (`pose::certificate::lens`).
    LensSublevelSet,
}

impl CertificateKind {
    /// snake_case name for reports, JSON and Python.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }
}

/// What a certificate is about: a camera pose or a triangulated primitive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
pub enum Primitive {
    /// A camera pose (rotation and translation).
    Pose,
    /// A 3-D point.
    Point,
    /// A 3-D line.
    Line,
    /// A quadric (from its outlines, the conics).
    Quadric,
}

impl Primitive {
    /// snake_case name for reports, JSON and Python.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }
}

impl CertificateKind {
    /// The set of primitives over which a certificate of this kind bounds the cost of eq. 19 (each
    /// branch and bound's module docs give the details). A line or quadric certificate from branch and
    /// bound covers a search domain, not every primitive in front of the cameras.
    pub fn domain(&self, primitive: Primitive) -> &'static str {
        match (self, primitive) {
            (CertificateKind::None, _) => "none",
            (CertificateKind::LensSublevelSet, _) => {
                "every rotation and translation that keeps the object points and the segments' object \
                 endpoints in front of the camera, with every point's projection, and every point of a \
                 projected line that a segment endpoint's residual is measured to, inside the disc where the \
                 lens is proved one-to-one (the fold radius for radially symmetric lenses)"
            }
            (_, Primitive::Pose) | (CertificateKind::SublevelSet, _) => {
                "every rotation and translation that keeps the object points and the segments' object \
                 endpoints in front of the camera that saw them"
            }
            (CertificateKind::LensConvexityTest, _) => {
                "every point in front of every camera whose projection in each image lies inside the disc where \
                 its lens is proved one-to-one (the fold radius for radially symmetric lenses)"
            }
            (_, Primitive::Point) => "every point in front of every camera",
            (CertificateKind::ConvexityTest, Primitive::Line) => "every line (a cost at the zero bound)",
            (CertificateKind::ConvexityTest, Primitive::Quadric) => {
                "every ellipsoid, flat ones included, that no camera's principal plane cuts, in front of the \
                 cameras or behind them"
            }
            (CertificateKind::BranchAndBound, Primitive::Line) => {
                "lines whose points on two planes across the local line project within twice the eq. 27 strip \
                 widths of every observed line, at depths up to 100 times the local line's"
            }
            (CertificateKind::TaylorBranchAndBound, _) => {
                "every line at least 1/100 of the estimate's distance from each camera centre, in front of the \
                 cameras or not"
            }
            (CertificateKind::BranchAndBound, Primitive::Quadric) => {
                "quadrics centred within 10 times the largest camera distance of the local centre, with \
                 semi-axes up to that distance"
            }
        }
    }
}

/// The global-optimality evidence of an estimate.
#[derive(Debug, Clone, Copy)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize))]
pub struct Certificate {
    /// True when `relative_gap ≤ max_relative_gap` with a valid lower bound.
    pub certified: bool,
    /// A lower bound on the cost of eq. 19 over every admissible primitive, capped at the cost:
    /// `min(raw_lower_bound, cost)`. A result without a bound carries no certificate
    /// (`Option<Certificate>`).
    pub lower_bound: f64,
    /// The bound as the search or test proved it, before the cap at the cost (`+∞` when a search
    /// proved that its domain holds no admissible answer). A bound above the cost of an admissible
    /// answer would disprove the certificate: tests check it against independently computed costs.
    pub raw_lower_bound: f64,
    /// `(cost − lower_bound) / max(cost, 1e-12)`.
    pub relative_gap: f64,
    /// How the bound was obtained.
    pub kind: CertificateKind,
    /// What was estimated; with `kind` it sets the domain of the bound ([`Certificate::domain`]).
    pub primitive: Primitive,
    /// Branch-and-bound nodes whose bound was computed (0 for the convexity test).
    pub nodes: usize,
    /// Interior-point iterations of the conic solver, summed over nodes.
    pub solver_iterations: usize,
}

/// Field by field, with the NaN of "no raw bound" equal to itself (two certificates without a
/// bound are the same certificate).
impl PartialEq for Certificate {
    fn eq(&self, other: &Self) -> bool {
        let same_raw = self.raw_lower_bound == other.raw_lower_bound
            || (self.raw_lower_bound.is_nan() && other.raw_lower_bound.is_nan());
        same_raw
            && self.lower_bound == other.lower_bound
            && self.relative_gap == other.relative_gap
            && self.certified == other.certified
            && self.kind == other.kind
            && self.primitive == other.primitive
            && self.nodes == other.nodes
            && self.solver_iterations == other.solver_iterations
    }
}

impl Certificate {
    /// The one way a certificate is made: of `kind` about `primitive`, with the proved bound `raw_lower_bound`, the bound
    /// capped at the answer's cost `lower_bound`, their `relative_gap` and whether it closed
    /// (`certified`), and no search effort ([`Self::with_effort`] adds it). The fields' docs say what
    /// each must be; [`Self::of_bound`] computes the last three from the cost.
    pub(crate) fn new(
        kind: CertificateKind,
        primitive: Primitive,
        lower_bound: f64,
        raw_lower_bound: f64,
        relative_gap: f64,
        certified: bool,
    ) -> Certificate {
        Certificate {
            lower_bound,
            raw_lower_bound,
            relative_gap,
            certified,
            kind,
            primitive,
            nodes: 0,
            solver_iterations: 0,
        }
    }

    /// The certificate of `kind` about `primitive` of a proved bound `raw_lower_bound` on the cost `cost`: the bound
    /// capped at the cost (`min(raw_lower_bound, cost)`), its relative gap
    /// ([`crate::global::relative_gap`]), certified when that is at most `max_relative_gap`.
    pub(crate) fn of_bound(
        kind: CertificateKind,
        primitive: Primitive,
        cost: f64,
        raw_lower_bound: f64,
        max_relative_gap: f64,
    ) -> Certificate {
        let lower_bound = raw_lower_bound.min(cost);
        let relative_gap = crate::global::relative_gap(cost, lower_bound);
        Certificate::new(
            kind,
            primitive,
            lower_bound,
            raw_lower_bound,
            relative_gap,
            relative_gap <= max_relative_gap,
        )
    }

    /// The set of estimates over which `lower_bound` holds, in words ([`CertificateKind::domain`] of
    /// `kind` and `primitive`).
    pub fn domain(&self) -> &'static str {
        self.kind.domain(self.primitive)
    }

    /// The same certificate, with the branch-and-bound nodes whose bound was computed and the conic
    /// solver's iterations.
    pub(crate) fn with_effort(self, nodes: usize, solver_iterations: usize) -> Certificate {
        Certificate {
            nodes,
            solver_iterations,
            ..self
        }
    }

    /// The certificate about `primitive` of a convexity test whose (raw) lower bound on the cost is `raw_lower_bound`,
    /// when it closes the gap (`relative_gap(cost, min(raw_lower_bound, cost)) ≤ max_relative_gap`);
    /// `None` otherwise.
    pub(crate) fn of_convexity_test(
        primitive: Primitive,
        cost: f64,
        raw_lower_bound: f64,
        max_relative_gap: f64,
    ) -> Option<Certificate> {
        let certificate = Certificate::of_bound(
            CertificateKind::ConvexityTest,
            primitive,
            cost,
            raw_lower_bound,
            max_relative_gap,
        );
        certificate.certified.then_some(certificate)
    }
}

// Written and read by name with the `serde` feature.
crate::names::serde_by_name!(CertificateKind, Primitive);

/// Written with the fields in their order and, after `primitive`, its `domain` in words, so that the
/// JSON states what it proves; reading takes the fields and skips `domain`.
#[cfg(feature = "serde")]
impl serde::Serialize for Certificate {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut c = serializer.serialize_struct("Certificate", 9)?;
        c.serialize_field("certified", &self.certified)?;
        c.serialize_field("lower_bound", &self.lower_bound)?;
        c.serialize_field("raw_lower_bound", &self.raw_lower_bound)?;
        c.serialize_field("relative_gap", &self.relative_gap)?;
        c.serialize_field("kind", &self.kind)?;
        c.serialize_field("primitive", &self.primitive)?;
        c.serialize_field("domain", self.domain())?;
        c.serialize_field("nodes", &self.nodes)?;
        c.serialize_field("solver_iterations", &self.solver_iterations)?;
        c.end()
    }
}
