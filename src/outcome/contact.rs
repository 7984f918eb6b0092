//! The contact solver's status and report.

use clarabel::solver::SolverStatus;
use serde::{Deserialize, Serialize};

use super::NonFiniteAt;

/// How a contact solve ended.
///
/// Only [`ContactStatus::Converged`] certifies the shape: equilibrium with
/// the contact forces, every force pushing (non-negative), and no gap below
/// `−penetration_tolerance_m`. Every other variant comes with the last
/// iterate, which may penetrate.
///
/// # Example
/// ```
/// use softrod::outcome::ContactStatus;
/// assert!(ContactStatus::Converged.is_converged());
/// let s = ContactStatus::Infeasible { penetration_m: 2e-3 };
/// assert!(!s.is_converged());
/// assert_eq!(serde_json::to_string(&s).unwrap(), r#"{"infeasible":{"penetration_m":0.002}}"#);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum ContactStatus {
    /// Equilibrium with contact: the KKT conditions hold to the
    /// tolerances.
    Converged,
    /// The linearized non-penetration constraints admit no step: no
    /// feasible point was found from the start.
    Infeasible {
        /// The deepest penetration at the last iterate (m, positive).
        penetration_m: f64,
    },
    /// A QP subproblem failed for another reason: clarabel's status.
    QpFailed {
        /// Clarabel's status.
        #[serde(with = "super::estimate::solver_status")]
        #[cfg_attr(feature = "schema", schemars(with = "String"))]
        status: SolverStatus,
    },
    /// The SQP iteration budget ran out.
    IterationLimit {
        /// SQP iterations taken.
        iterations: usize,
    },
    /// No step along the SQP direction decreased the merit function
    /// (potential plus a penalty on penetration).
    LineSearchFailed,
    /// The SQP iterate stopped moving (its steps at round-off), but
    /// Newton's method on the KKT system of its active set, and of the
    /// closed contacts among them, did not reach a solution that passes
    /// the checks: the solve stops there instead of spending its iteration
    /// budget on the same point.
    Stalled {
        /// Contacts in the SQP's active set.
        active_contacts: usize,
    },
    /// A number that is not finite appeared.
    NonFinite {
        /// Where.
        at: NonFiniteAt,
    },
}

impl ContactStatus {
    /// Whether the solve converged to a non-penetrating equilibrium.
    pub fn is_converged(&self) -> bool {
        matches!(self, ContactStatus::Converged)
    }
}

impl std::fmt::Display for ContactStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ContactStatus::Converged => write!(f, "converged"),
            ContactStatus::Infeasible { penetration_m } => {
                write!(f, "infeasible (penetration {penetration_m:.3e} m)")
            }
            ContactStatus::QpFailed { status } => write!(f, "QP failed ({status:?})"),
            ContactStatus::IterationLimit { iterations } => {
                write!(f, "iteration limit ({iterations} iterations)")
            }
            ContactStatus::LineSearchFailed => write!(f, "line search failed"),
            ContactStatus::Stalled { active_contacts } => write!(
                f,
                "stalled (the SQP stopped; the polish of its {active_contacts} contacts failed)"
            ),
            ContactStatus::NonFinite { at } => write!(f, "non-finite {}", at.name()),
        }
    }
}

/// What a contact solve did.
///
/// # Example
/// ```
/// use softrod::outcome::{ContactReport, ContactStatus};
/// let r = ContactReport { status: ContactStatus::Converged, ..ContactReport::default() };
/// assert!(r.status.is_converged());
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactReport {
    /// How the solve ended.
    pub status: ContactStatus,
    /// SQP iterations (clarabel QPs).
    pub sqp_iterations: usize,
    /// Newton iterations on the KKT system of the final active set.
    pub newton_iterations: usize,
    /// `|Q + Gᵀλ|_2` at the end: the equilibrium residual with the contact
    /// forces (N).
    pub residual_norm_n: f64,
    /// The tolerance it was held to (N).
    pub residual_tolerance_n: f64,
    /// The smallest gap over all obstacles (m; negative: penetration).
    pub min_gap_m: f64,
    /// Wall time (s).
    pub wall_time_s: f64,
}

impl Default for ContactReport {
    fn default() -> Self {
        ContactReport {
            status: ContactStatus::IterationLimit { iterations: 0 },
            sqp_iterations: 0,
            newton_iterations: 0,
            residual_norm_n: 0.0,
            residual_tolerance_n: 0.0,
            min_gap_m: f64::MAX,
            wall_time_s: 0.0,
        }
    }
}

impl std::fmt::Display for ContactReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}; {} SQP + {} Newton iterations, |Q + Gᵀλ| = {:.3e} N (tolerance {:.3e} N), smallest gap {:.3e} m",
            self.status,
            self.sqp_iterations,
            self.newton_iterations,
            self.residual_norm_n,
            self.residual_tolerance_n,
            self.min_gap_m
        )
    }
}
