//! Non-linear least-squares solvers sharing one problem interface ([`problem::Objective`]):
//! the paper's trust region (Hebden or Moré-Sorensen steps), Levenberg-Marquardt and Newton.

pub mod levenberg_marquardt;
pub mod newton;
pub mod problem;
pub mod subproblem;
pub mod trust_region;

pub use problem::{Linearization, Objective, StoppingCriteria, Summary, Termination};
pub use trust_region::{Subproblem, TrustRegionOptions};
