//! The estimators' status.

use clarabel::solver::SolverStatus;
use serde::{Deserialize, Serialize};

use super::NonFiniteAt;

/// Which test ended a converged estimation (the predicted decrease `dec` of
/// the objective along the step, `scale = max(objective, n_ob)`).
///
/// # Example
/// ```
/// use softrod::outcome::{EstimateCriterion, EstimateStatus};
/// let s = EstimateStatus::Converged(EstimateCriterion::PredictedDecrease);
/// assert_eq!(serde_json::to_string(&s).unwrap(), r#"{"converged":"predicted_decrease"}"#);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum EstimateCriterion {
    /// `dec <= tolerance × scale` (for the SQP backend at a feasible point,
    /// the decrease along the equilibrium manifold).
    PredictedDecrease,
    /// `dec` at the round-off floor: below `1e-13 scale` and no longer
    /// shrinking.
    RoundOffFloor,
    /// The statistical test: the next Gauss–Newton step would move the
    /// estimate by less than `statistical_tolerance` of its own standard
    /// deviation (`dec ≤ κ²`, see
    /// [`EstimatorSettings::statistical_tolerance`](crate::estimate::EstimatorSettings::statistical_tolerance)).
    WithinNoise,
    /// Newton backend: the decrease predicted after the step
    /// (`dec²/dec_prev`, quadratic convergence) was far below the tolerance,
    /// so the step was taken without a further linearization to confirm it.
    UnconfirmedLastStep,
    /// Newton backend: the step makes no first-order change of the
    /// objective (zero slope) and its predicted decrease is not a number.
    Stationary,
    /// The line search found no decrease, but the predicted decrease was
    /// already negligible (below `1e-6 scale` for the Newton backend, `1e-10
    /// scale` at a feasible point for the SQP backend): round-off hides it.
    NegligibleDecrease,
}

impl EstimateCriterion {
    /// The test in words.
    pub fn name(self) -> &'static str {
        match self {
            EstimateCriterion::PredictedDecrease => "predicted decrease",
            EstimateCriterion::RoundOffFloor => "round-off floor",
            EstimateCriterion::WithinNoise => "within the noise",
            EstimateCriterion::UnconfirmedLastStep => "unconfirmed last step",
            EstimateCriterion::Stationary => "stationary point",
            EstimateCriterion::NegligibleDecrease => "negligible decrease",
        }
    }
}

/// How an estimation ended.
///
/// `Converged` means both that the iteration stopped by the test it names
/// and that the answer passed the fit test: its weighted misfit at its own
/// equilibrium within the 0.999 quantile of χ²(`n_ob`) (see
/// [`FIT_QUANTILE`](crate::estimate::FIT_QUANTILE)). An iteration that
/// stopped but whose answer fails the fit test ends as
/// [`EstimateStatus::MisfitBeyondNoise`].
///
/// An estimator that stops short still returns its last iterate (an
/// equilibrium) with one of the other variants: see
/// [`Estimator::step`](crate::estimate::Estimator::step).
///
/// # Example
/// ```
/// use softrod::outcome::EstimateStatus;
/// use clarabel::solver::SolverStatus;
/// let s = EstimateStatus::QpNotSolved(SolverStatus::PrimalInfeasible);
/// assert!(!s.is_converged());
/// assert_eq!(serde_json::to_string(&s).unwrap(), r#"{"qp_not_solved":"PrimalInfeasible"}"#);
/// let back: EstimateStatus = serde_json::from_str(r#"{"qp_not_solved":"PrimalInfeasible"}"#).unwrap();
/// assert_eq!(back, s);
/// let m = EstimateStatus::MisfitBeyondNoise {
///     stopped_by: softrod::outcome::EstimateCriterion::WithinNoise,
///     weighted_residual: 2.1e6,
///     quantile: 37.7,
/// };
/// assert!(!m.is_converged());
/// assert_eq!(
///     serde_json::to_string(&m).unwrap(),
///     r#"{"misfit_beyond_noise":{"stopped_by":"within_noise","weighted_residual":2100000.0,"quantile":37.7}}"#
/// );
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum EstimateStatus {
    /// Converged; the test that ended it (and the answer passed the fit
    /// test).
    Converged(EstimateCriterion),
    /// The iteration stopped (by `stopped_by`), but the answer does not
    /// explain the markers to their noise: its weighted misfit
    /// `(Aq − y)ᵀW(Aq − y)` exceeds the χ² quantile for the observed
    /// components (an unmodelled effect, a wrong noise level, or a penalty
    /// that holds the load back). Not converged.
    MisfitBeyondNoise {
        /// The test that stopped the iteration.
        stopped_by: EstimateCriterion,
        /// The weighted misfit at the answer (dimensionless with whitened
        /// weights).
        weighted_residual: f64,
        /// The χ² quantile it exceeds
        /// ([`FIT_QUANTILE`](crate::estimate::FIT_QUANTILE) for `n_ob`
        /// degrees of freedom).
        quantile: f64,
    },
    /// The outer iteration budget (`max_iterations`) ran out.
    IterationLimit {
        /// Outer iterations of the solve that stopped.
        iterations: usize,
    },
    /// The line search (Armijo on the objective, or on the SQP merit
    /// function) found no acceptable step.
    LineSearchFailed,
    /// An SQP subproblem was not solved: clarabel's status (infeasible, as
    /// with contradictory bounds, a numerical error, its iteration limit…).
    QpNotSolved(
        #[serde(with = "solver_status")]
        #[cfg_attr(feature = "schema", schemars(with = "String"))]
        SolverStatus,
    ),
    /// An SQP subproblem's tangent stiffness had a vanishing pivot.
    SingularTangent,
    /// An SQP subproblem's Gauss–Newton matrix was not positive definite.
    NotPositiveDefinite,
    /// A number that is not finite appeared in an SQP subproblem.
    NonFinite {
        /// Where.
        at: NonFiniteAt,
    },
    /// The markers do not see the load (every one at the clamped base:
    /// positions and tangents there do not move): the estimate is the
    /// penalty's prior, zero load, with the prior's spread, not knowledge.
    NoInformation,
}

impl EstimateStatus {
    /// Whether the estimation converged.
    pub fn is_converged(&self) -> bool {
        matches!(self, EstimateStatus::Converged(_))
    }

    /// The test that ended a converged estimation.
    pub fn criterion(&self) -> Option<EstimateCriterion> {
        match self {
            EstimateStatus::Converged(c) => Some(*c),
            _ => None,
        }
    }
}

impl std::fmt::Display for EstimateStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EstimateStatus::Converged(c) => write!(f, "converged ({})", c.name()),
            EstimateStatus::MisfitBeyondNoise {
                stopped_by,
                weighted_residual,
                quantile,
            } => write!(
                f,
                "misfit beyond the noise: weighted residual {weighted_residual:.4e} above the chi-square quantile {quantile:.4e} (stopped by {})",
                stopped_by.name()
            ),
            EstimateStatus::IterationLimit { iterations } => {
                write!(f, "iteration limit ({iterations} iterations)")
            }
            EstimateStatus::LineSearchFailed => write!(f, "line search failed"),
            EstimateStatus::QpNotSolved(s) => {
                write!(f, "QP subproblem not solved (clarabel: {s:?})")
            }
            EstimateStatus::SingularTangent => write!(f, "singular tangent in a QP subproblem"),
            EstimateStatus::NotPositiveDefinite => {
                write!(
                    f,
                    "Gauss-Newton matrix not positive definite in a QP subproblem"
                )
            }
            EstimateStatus::NonFinite { at } => {
                write!(f, "non-finite {} in a QP subproblem", at.name())
            }
            EstimateStatus::NoInformation => write!(
                f,
                "no information: the markers do not see the load (all at the clamped base)"
            ),
        }
    }
}

/// clarabel's `SolverStatus` as its variant name (it has no serde support).
pub(super) mod solver_status {
    use clarabel::solver::SolverStatus;
    use serde::{Deserialize, Deserializer, Serializer};

    const ALL: [SolverStatus; 12] = [
        SolverStatus::Unsolved,
        SolverStatus::Solved,
        SolverStatus::PrimalInfeasible,
        SolverStatus::DualInfeasible,
        SolverStatus::AlmostSolved,
        SolverStatus::AlmostPrimalInfeasible,
        SolverStatus::AlmostDualInfeasible,
        SolverStatus::MaxIterations,
        SolverStatus::MaxTime,
        SolverStatus::NumericalError,
        SolverStatus::InsufficientProgress,
        SolverStatus::CallbackTerminated,
    ];

    pub fn serialize<S: Serializer>(s: &SolverStatus, ser: S) -> Result<S::Ok, S::Error> {
        ser.collect_str(&format_args!("{s:?}"))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(de: D) -> Result<SolverStatus, D::Error> {
        let name = String::deserialize(de)?;
        ALL.into_iter()
            .find(|s| format!("{s:?}") == name)
            .ok_or_else(|| serde::de::Error::custom(format!("unknown clarabel status `{name}`")))
    }
}
