//! [`Report`]: what one solve did, the same in every result (a pose, a point, a line, a quadric), as
//! Clarabel's `Info` is: the method that ran, whether the answer can be used, its cost and what the
//! cost measures, the certificate of global optimality, the iterations and the time.

use crate::certificate::Certificate;
use crate::chi_square::ResidualTest;
use crate::cost_kind::CostKind;
use crate::optim::Termination;
use crate::status::Status;

/// What one solve did; `M` is the problem's method ([`crate::pose::Method`],
/// [`crate::triangulation::Method`]). Every result holds one as its `report` (Python shows its fields on
/// the result itself).
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Deserialize))]
pub struct Report<M> {
    /// The method that ran.
    pub method: M,
    /// Whether the answer can be used, and if not why. A certificate requested that does not hold
    /// turns [`Status::Success`] into [`Status::GapNotClosed`].
    pub status: Status,
    /// The cost at the answer, of kind `cost_kind`: the sum of squared whitened residuals (for a pose,
    /// `Σ r²` px² of the used correspondences in the observed pixels; for a triangulation eq. 19). NaN
    /// when the answer is not finite.
    pub cost: f64,
    /// What `cost` measures, and what the certificate bounds: [`CostKind::Reprojection`] for poses and
    /// points and for lines from segments through a lens that distorts, [`CostKind::LineResidual`]
    /// for other lines, [`CostKind::ConicResidual`] for quadrics.
    pub cost_kind: CostKind,
    /// Optimality evidence: `None` when no bound was computed (not requested, a method without one,
    /// an input refused before the search); `Some` with `certified == false` when a search ran and did
    /// not close the gap (or the status is not [`Status::Success`]).
    pub certificate: Option<Certificate>,
    /// Accepted iterations (summed over a pose's stages; 0 for a closed form).
    pub iterations: usize,
    /// Why the last iterative stage stopped ([`Termination::ClosedForm`] for a closed form).
    pub termination: Termination,
    /// Wall time of the call, seconds.
    pub time_seconds: f64,
    /// Degrees of freedom of `cost`: `m − p` for `m` whitened residuals and `p` fitted parameters; 0
    /// when not known. See [`Report::residual_test`].
    pub residual_dof: usize,
}

impl<M> Report<M> {
    /// The report a method starts from: status success, no cost yet (of kind `cost_kind`), no
    /// certificate, no iterations.
    pub fn new(method: M, cost_kind: CostKind) -> Report<M> {
        Report {
            method,
            status: Status::Success,
            cost: f64::NAN,
            cost_kind,
            certificate: None,
            iterations: 0,
            termination: Termination::ClosedForm,
            time_seconds: 0.0,
            residual_dof: 0,
        }
    }

    /// `status == Status::Success`: the answer can be used.
    pub fn success(&self) -> bool {
        self.status == Status::Success
    }

    /// Whether a certificate was computed and proves the answer globally optimal (within
    /// `certify.max_relative_gap`, over the certificate's domain).
    pub fn certified(&self) -> bool {
        self.certificate.is_some_and(|c| c.certified)
    }

    /// Sets [`Report::residual_dof`] for `residuals` whitened residuals and `parameters` fitted ones.
    pub(crate) fn test_residuals(&mut self, residuals: usize, parameters: usize) {
        self.residual_dof = residuals.saturating_sub(parameters);
    }

    /// The χ² test of `cost` against the given covariances ([`crate::chi_square`]; identity
    /// covariances mean 1 px) with [`Report::residual_dof`] degrees of freedom. `consistent == false`:
    /// the observations disagree beyond their stated noise (an outlier, a wrong camera, distortion, a
    /// covariance too small). `None` when the degrees of freedom are 0 or there is no cost. Computed
    /// on demand (about 0.1 µs), not in the solvers' hot loops.
    pub fn residual_test(&self) -> Option<ResidualTest> {
        ResidualTest::new(self.cost, self.residual_dof)
    }

    /// Sets the status; a status other than [`Status::Success`] withdraws the certificate's claim
    /// (`certified` is false), so that the two fields never disagree.
    pub fn set_status(&mut self, status: Status) {
        self.status = status;
        if status != Status::Success {
            if let Some(c) = self.certificate.as_mut() {
                c.certified = false;
            }
        }
    }
}

/// Written with the fields in their order, and after `status` and `certificate` the two answers a
/// reader looks for, `success` ([`Report::success`]) and `certified` ([`Report::certified`]); reading
/// takes the fields and skips those two. A result writes its report's fields beside its own (the JSON
/// of the command line, `to_dict()` in Python).
#[cfg(feature = "serde")]
impl<M: serde::Serialize> serde::Serialize for Report<M> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct;
        let mut report = serializer.serialize_struct("Report", 11)?;
        report.serialize_field("method", &self.method)?;
        report.serialize_field("status", &self.status)?;
        report.serialize_field("success", &self.success())?;
        report.serialize_field("cost", &self.cost)?;
        report.serialize_field("cost_kind", &self.cost_kind)?;
        report.serialize_field("certificate", &self.certificate)?;
        report.serialize_field("certified", &self.certified())?;
        report.serialize_field("iterations", &self.iterations)?;
        report.serialize_field("termination", &self.termination)?;
        report.serialize_field("time_seconds", &self.time_seconds)?;
        report.serialize_field("residual_dof", &self.residual_dof)?;
        report.end()
    }
}
