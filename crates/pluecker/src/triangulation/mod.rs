//! Triangulation: the 3-D point, line or quadric seen by several known cameras (Josephson & Kahl 2008).
//!
//! Every primitive is estimated by minimising the covariance-weighted reprojection cost of eq. 19,
//! `Σᵢ ‖Lᵢ rᵢ‖²`, with `rᵢ` the residual of eq. 17 in view `i` (2 entries for points and lines, 5 for
//! conics) and `Lᵢ` the Cholesky factor of the inverse covariance of that observation (eq. 18; the
//! identity when no covariance is given, so that the cost of a point is its squared pixel error).
//! Lines from segments seen through a lens that distorts minimise the segments' reprojection cost
//! instead (`line::lens`); every result says which cost it reports ([`Report::cost_kind`]).
//! Three methods ([`Method`]): a linear (DLT-style) solution, a local minimisation from it, and the
//! globally optimal answer of branch and bound (section 4) whose [`Certificate`] carries a lower
//! bound on the cost of every 3-D primitive. The paper bounds its initial search domain with a
//! user-given largest reprojection error `γ` (sections 4.3.1-4.3.2); here every search takes
//! `γ = ε₀ = √(cost of the local solution)`, which every primitive at least as cheap satisfies in
//! each view, so no primitive that could improve on the estimate is left out and there is no option
//! for it.
//!
//! Conventions: cameras are 3x4 matrices `P` that map world points straight to pixels,
//! `λ (u, v, 1)ᵀ = P (X, 1)ᵀ` with `λ > 0` in front of the camera (eq. 1) for the matrix as given, so
//! any positive scale but not any sign (`views`: `fx < 0` and left-handed worlds are fine); costs
//! are in squared (whitened) pixels, without the ½ of the least-squares solvers in [`crate::optim`].
//! A report's certificate is `None` when no bound was computed (methods `linear` and `local`, a
//! refused input); when a search ran, it is `Some`, and `certified` is true only with
//! [`Status::Success`] ([`Report::set_status`]): a requested certificate that does not close its
//! gap turns success into [`Status::GapNotClosed`], and any other failure status keeps precedence.

pub(crate) mod certificate;
pub(crate) mod conditioning;
pub mod fitting;
pub(crate) mod fractional_residual;
pub mod line;
pub mod point;
pub mod quadric;
pub mod scenes;
pub(crate) mod tracks;
pub mod uncertainty;
pub(crate) mod views;

pub use tracks::{Csr, TrackCameras};
pub use views::{Cameras, View};

/// The batches that hand each track's result to the caller as it finishes, with that track's output
/// row, instead of collecting them (the Python bindings write them straight into preallocated
/// columns); not part of the user-facing API, whose batches are [`point::triangulate_points`],
/// [`line::triangulate_lines`] and [`quadric::triangulate_quadrics`].
#[doc(hidden)]
pub mod streaming {
    pub use super::line::batch::lines_into;
    pub use super::point::batch::{linear_points_into, points_into, LinearTrack};
    pub use super::quadric::batch::quadrics_into;
}

/// Helpers the Python bindings and the integration tests call directly; not part of the user-facing
/// API.
#[doc(hidden)]
pub mod testing {
    pub use super::quadric::certificate::convexity_bound_at as quadric_convexity_bound;
    pub use super::views::{baseline, centre, depth, depth_normalized};
    pub use crate::covariance::whitening;
}

use crate::error::{Error, Result};
use crate::optim::{Summary, TrustRegionOptions};

/// The three estimators of every primitive.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
pub enum Method {
    /// Algebraic least squares on the projection equations (DLT), with Hartley normalisation.
    Linear,
    /// Minimisation of the weighted cost of eq. 19 from the linear solution. Not certified.
    Local,
    /// Certified global minimum of eq. 19: a cheap sufficient test first, branch and bound
    /// (section 4) when the test cannot decide. The default.
    Optimal,
}

impl Method {
    /// Every method, in the order above.
    pub const ALL: &'static [Method] = <Method as strum::VariantArray>::VARIANTS;

    /// The name used by Python and the command line.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }

    /// Parses [`Method::as_str`] names.
    pub fn parse(name: &str) -> Result<Method> {
        crate::names::parse("method", "triangulation method", name)
    }
}

/// The lower bound of the optimal method for lines.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
pub enum LineBound {
    /// Interval Taylor bounds over the chart of the line's images in two views
    /// (`line::taylor_search`; certificate kind `taylor_branch_and_bound`, domain: every line but
    /// those within 1 % of the local line's distance from a camera centre). The
    /// default. When no pair of views charts every cheaper line (a line near an epipolar plane of
    /// every pair), [`LineBound::Relaxation`] is used instead.
    Taylor,
    /// The paper's SOCP relaxation of eqs. 21-27 (`line::optimal`; kind `branch_and_bound`, domain:
    /// the eq. 27 strips).
    Relaxation,
}

impl LineBound {
    /// Every bound, in the order above.
    pub const ALL: &'static [LineBound] = <LineBound as strum::VariantArray>::VARIANTS;

    /// The name used by Python and the command line.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }

    /// Parses [`LineBound::as_str`] names.
    pub fn parse(name: &str) -> Result<LineBound> {
        crate::names::parse("line_bound", "line bound", name)
    }
}

/// The lower bound of the optimal method for quadrics.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, strum::IntoStaticStr, strum::EnumString, strum::VariantArray)]
#[strum(serialize_all = "snake_case")]
pub enum QuadricBound {
    /// The convexity test of `quadric::certificate` (kind `convexity_test`, domain: every ellipsoid
    /// that no camera's principal plane cuts), then the paper's relaxation when the test cannot
    /// decide. The default.
    Convexity,
    /// The paper's SOCP relaxation of eqs. 21-22, 26 only (`quadric::optimal`; kind
    /// `branch_and_bound`, domain: an a-priori box).
    Relaxation,
}

impl QuadricBound {
    /// Every bound, in the order above.
    pub const ALL: &'static [QuadricBound] = <QuadricBound as strum::VariantArray>::VARIANTS;

    /// The name used by Python and the command line.
    pub fn as_str(&self) -> &'static str {
        self.into()
    }

    /// Parses [`QuadricBound::as_str`] names.
    pub fn parse(name: &str) -> Result<QuadricBound> {
        crate::names::parse("quadric_bound", "quadric bound", name)
    }
}

/// Options of every triangulation function; each field has a documented default.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[non_exhaustive]
pub struct TriangulationOptions {
    /// Estimator. Default [`Method::Optimal`].
    pub method: Method,
    /// The certificate of method `optimal`: its gap, and a node cap overriding each search's own
    /// (branch and bound with conic relaxations for points, quadrics and [`LineBound::Relaxation`]:
    /// [`CONIC_MAX_NODES`]; the Taylor bound of lines: [`line::taylor_search::MAX_NODES`]). Beyond the
    /// cap the status is [`Status::GapNotClosed`]. Default [`CertifyOptions::default`] (gap `1e-3`,
    /// the paper stopped at 10 %; each search's own cap).
    pub certify: CertifyOptions,
    /// Points and lines: reject outlier observations of a track (`point::robust`, `line::robust`).
    /// A view is an inlier when its whitened residual (pixels without covariances) is at most this;
    /// the result carries the inlier mask and is solved on the inliers only. Default `None`: every
    /// observation is used. Quadrics reject it with [`Error::InvalidOption`].
    pub outlier_threshold: Option<f64>,
    /// The lower bound of the line certificate ([`LineBound`]). Default [`LineBound::Taylor`].
    pub line_bound: LineBound,
    /// The lower bound of the quadric certificate ([`QuadricBound`]). Default
    /// [`QuadricBound::Convexity`].
    pub quadric_bound: QuadricBound,
    /// Settings of the local minimisation (method `local`, and the upper bounds of `optimal`).
    /// Default: the trust region of section 4.1 with 100 iterations and a step tolerance of 1e-10.
    pub local: TrustRegionOptions,
}

impl Default for TriangulationOptions {
    fn default() -> Self {
        let mut local = TrustRegionOptions::default();
        local.stopping.max_iterations = 100;
        local.stopping.step_tolerance = 1e-10;
        TriangulationOptions {
            method: Method::Optimal,
            certify: CertifyOptions::default(),
            outlier_threshold: None,
            line_bound: LineBound::Taylor,
            quadric_bound: QuadricBound::Convexity,
            local,
        }
    }
}

/// The node cap of the branch and bounds with conic relaxations (points, quadrics and
/// [`LineBound::Relaxation`]) when [`CertifyOptions::max_nodes`] is `None`: each node solves a conic
/// program (about a millisecond).
pub const CONIC_MAX_NODES: usize = 2_000;

impl TriangulationOptions {
    /// The node cap of a branch and bound with conic relaxations ([`CONIC_MAX_NODES`] unless
    /// `certify.max_nodes` says otherwise).
    pub(crate) fn conic_max_nodes(&self) -> usize {
        self.certify.max_nodes_or(CONIC_MAX_NODES)
    }

    /// Checks the numeric options.
    pub fn validate(&self) -> Result<()> {
        let bad = |name: &str, reason: &str| {
            Err(Error::InvalidOption {
                name: name.into(),
                reason: reason.into(),
            })
        };
        // A relative gap is (upper − lower) / upper ≤ 1 whenever the lower bound is ≥ 0, so a threshold
        // of 1 or more would certify without any bound: `validate` keeps it in (0, 1).
        self.certify.validate("certify")?;
        if let Some(tau) = self.outlier_threshold {
            if !(tau.is_finite() && tau > 0.0) {
                return bad(
                    "outlier_threshold",
                    "must be a positive finite number of (whitened) pixels",
                );
            }
        }
        Ok(())
    }

    /// [`Error::InvalidOption`] when `outlier_threshold` is set for `what` (quadrics), which have no
    /// robust form yet: a silently ignored threshold would keep the outliers.
    pub fn reject_outlier_threshold(&self, what: &str) -> Result<()> {
        match self.outlier_threshold {
            None => Ok(()),
            Some(_) => Err(Error::InvalidOption {
                name: "outlier_threshold".into(),
                reason: format!("applies to points and lines; {what} have no robust triangulation yet"),
            }),
        }
    }
}

#[doc(no_inline)]
pub use crate::certificate::{Certificate, CertificateKind, CertifyOptions, Primitive};
#[doc(no_inline)]
pub use crate::cost_kind::CostKind;
#[doc(no_inline)]
pub use crate::status::Status;

/// What one triangulation did: the crate's one [`crate::Report`] with the triangulation [`Method`].
pub type Report = crate::report::Report<Method>;

impl Report {
    /// The report of a local minimisation of a cost of kind `cost_kind` that ended as `summary` says
    /// (`summary.final_cost` is the solvers' `½ Σ`, so the cost is twice it).
    pub(crate) fn of_local(summary: &Summary, cost_kind: CostKind) -> Report {
        Report {
            status: if summary.termination.converged() {
                Status::Success
            } else {
                Status::NotConverged
            },
            cost: 2.0 * summary.final_cost,
            iterations: summary.iterations,
            termination: summary.termination,
            ..Report::new(Method::Local, cost_kind)
        }
    }
}

/// Parses one observation per view (image line, conic, ...) with `parse`, checking finiteness first:
/// [`Error::NonFinite`] names `what` and the row; a row `parse` rejects is [`Error::Degenerate`] with
/// `what[i] <why>`.
pub(crate) fn parse_observations<T, F>(
    rows: &[T],
    what: &str,
    why: &str,
    parse: impl Fn(&T) -> Option<F>,
) -> Result<Vec<F>>
where
    for<'a> &'a T: IntoIterator<Item = &'a f64>,
{
    rows.iter()
        .enumerate()
        .map(|(i, row)| {
            if !row.into_iter().all(|v| v.is_finite()) {
                return Err(Error::NonFinite {
                    what: what.into(),
                    index: i,
                });
            }
            parse(row).ok_or_else(|| Error::Degenerate {
                what: format!("{what}[{i}] {why}"),
            })
        })
        .collect()
}

// Written and read by name with the `serde` feature.
crate::names::serde_by_name!(Method, LineBound, QuadricBound);
