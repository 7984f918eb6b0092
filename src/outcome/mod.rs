//! How a solve ended: the status enums of the solvers, and the reports that
//! the crate's [`Error`](crate::Error) carries.
//!
//! Every solver report holds a `status` (Clarabel's `SolverStatus` and
//! argmin's `TerminationReason` are the model): converged, and by which
//! test, or stopped, and why, with the data that says it (the iteration
//! budget, clarabel's own status of a failed QP, where a non-finite number
//! appeared). No outcome is text: a caller matches on it, and
//! [`is_converged`](StaticStatus::is_converged) answers the common
//! question. Serialized (the command line's JSON), a status reads
//! `{"converged": "residual"}`, `{"iteration_limit": {"iterations": 30}}`,
//! `"line_search_failed"`.
//!
//! This module is plain data and depends on no solver, so the error type can
//! carry what a failed solve reports without a module cycle. The solvers
//! re-export what they report: [`crate::statics`] its [`StaticStatus`] and
//! [`StaticReport`], [`crate::estimate`] its [`EstimateStatus`],
//! [`crate::refine`] its [`Trial`] and [`RefinementFailure`].
//!
//! # Example
//! ```
//! use softrod::outcome::{StaticCriterion, StaticStatus};
//! let s = StaticStatus::Converged(StaticCriterion::Residual);
//! assert!(s.is_converged());
//! assert_eq!(serde_json::to_string(&s).unwrap(), r#"{"converged":"residual"}"#);
//! let s = StaticStatus::IterationLimit { iterations: 30 };
//! assert!(!s.is_converged());
//! assert_eq!(s.to_string(), "iteration limit (30 iterations)");
//! ```

mod contact;
mod estimate;
mod refine;
mod statics;

pub use contact::{ContactReport, ContactStatus};
pub use estimate::{EstimateCriterion, EstimateStatus};
pub use refine::{Phase, Quantity, RefinementFailure, RefinementStop, Trial, TrialFailure};
pub use statics::{BranchChoice, StaticCriterion, StaticReport, StaticStatus, StaticWarning};

use serde::{Deserialize, Serialize};

/// Where a number that is not finite (an infinity or a NaN) appeared.
///
/// # Example
/// ```
/// use softrod::outcome::{NonFiniteAt, StaticStatus};
/// let s = StaticStatus::NonFinite { at: NonFiniteAt::Residual };
/// assert_eq!(s.to_string(), "non-finite residual");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum NonFiniteAt {
    /// The applied generalized forces (loads whose norm overflows).
    Loads,
    /// The equilibrium residual `Q`.
    Residual,
    /// The tangent stiffness `K` or its factorization.
    Tangent,
    /// The final configuration.
    Solution,
}

impl NonFiniteAt {
    /// What it names, in words ("residual").
    pub fn name(self) -> &'static str {
        match self {
            NonFiniteAt::Loads => "applied loads",
            NonFiniteAt::Residual => "residual",
            NonFiniteAt::Tangent => "tangent stiffness",
            NonFiniteAt::Solution => "solution",
        }
    }
}
