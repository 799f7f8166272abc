//! Non-linear least-squares solvers sharing one problem interface ([`problem::Objective`]):
//! the paper's trust region (Hebden or Moré-Sorensen steps), Levenberg-Marquardt and Newton.

pub(crate) mod levenberg_marquardt;
pub(crate) mod newton;
pub(crate) mod problem;
pub(crate) mod subproblem;
pub(crate) mod trust_region;

pub use levenberg_marquardt::LevenbergMarquardtOptions;
pub use problem::{Linearization, Objective, StoppingCriteria, Summary, Termination};
pub use trust_region::{Subproblem, TrustRegionOptions};

// Written and read by name with the `serde` feature.
crate::names::serde_by_name!(Termination, Subproblem);
