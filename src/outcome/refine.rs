//! The refinement's records: the meshes it tried and why it stopped.

use serde::{Deserialize, Serialize};

use super::{EstimateStatus, StaticStatus};

/// The quantity a refinement controls.
///
/// # Example
/// ```
/// use softrod::refine::Quantity;
/// assert_eq!((Quantity::TipPosition.name(), Quantity::TipPosition.unit()), ("tip_position", "m"));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum Quantity {
    /// The tip position of the static equilibrium (m).
    TipPosition,
    /// The resultant force of the estimated unknown load (N).
    LoadResultant,
}

impl Quantity {
    /// Its name in a scene (`tip_position`, `load_resultant`).
    pub fn name(self) -> &'static str {
        match self {
            Quantity::TipPosition => "tip_position",
            Quantity::LoadResultant => "load_resultant",
        }
    }

    /// Its SI unit (`m` or `N`).
    pub fn unit(self) -> &'static str {
        match self {
            Quantity::TipPosition => "m",
            Quantity::LoadResultant => "N",
        }
    }
}

/// Which stage of the refinement tried a mesh.
///
/// # Example
/// ```
/// let p: softrod::refine::Phase = serde_json::from_str("\"doubling\"").unwrap();
/// assert_eq!(p, softrod::refine::Phase::Doubling);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// The doubling of the scale, `1, 2, 4, …`.
    Doubling,
    /// The bisection between the last failing and the first passing level.
    Search,
}

/// Why the solve of one candidate mesh gave no value (the mesh then counts
/// as failing).
///
/// # Example
/// ```
/// use softrod::refine::TrialFailure;
/// use softrod::statics::StaticStatus;
/// let f = TrialFailure::Statics(StaticStatus::IterationLimit { iterations: 2000 });
/// assert_eq!(f.to_string(), "static solve: iteration limit (2000 iterations)");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum TrialFailure {
    /// The static solve did not converge.
    Statics(StaticStatus),
    /// The estimator did not converge.
    Estimate(EstimateStatus),
    /// A linear system had a vanishing pivot.
    Singular,
    /// A matrix that must be positive definite was not.
    NotPositiveDefinite,
    /// A computation, or the quantity itself, was not finite.
    NonFinite,
}

impl std::fmt::Display for TrialFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            TrialFailure::Statics(s) => write!(f, "static solve: {s}"),
            TrialFailure::Estimate(s) => write!(f, "estimation: {s}"),
            TrialFailure::Singular => write!(f, "singular matrix"),
            TrialFailure::NotPositiveDefinite => write!(f, "matrix not positive definite"),
            TrialFailure::NonFinite => write!(f, "non-finite value"),
        }
    }
}

/// One mesh the refinement tried.
///
/// # Example
/// See [`crate::refine::auto_elements`]: its result's `history`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Trial {
    /// The scale `t` of the candidate ([`crate::refine::Ladder::elements`]).
    pub scale: usize,
    /// Elements per section.
    pub elements: Vec<usize>,
    /// Elements in all.
    pub total_elements: usize,
    /// The stage that tried it.
    pub phase: Phase,
    /// The quantity on this mesh (m or N); `None` if the solve failed.
    pub value: Option<Vec<f64>>,
    /// `|Q_t − Q_{t/2}|`, the change from the previous doubling level (m or N).
    pub change: Option<f64>,
    /// The estimated error `|Q_t − Q_R|` (m or N), once the extrapolated
    /// value `Q_R` is known.
    pub estimated_error: Option<f64>,
    /// Why the solve failed, if it did.
    pub failure: Option<TrialFailure>,
    /// Wall time of the solve (s; information, not a measurement).
    pub wall_time_s: f64,
}

/// Why a refinement stopped short of its tolerance.
///
/// # Example
/// ```
/// use softrod::refine::RefinementStop;
/// let s = RefinementStop::MeshLimit { next_elements: 32, max_elements: 20, last_change: None };
/// assert_eq!(s.to_string(), "the next mesh, 32 elements, exceeds refinement.max_elements = 20");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RefinementStop {
    /// The next doubling would exceed `refinement.max_elements`.
    MeshLimit {
        /// Elements in all of the next mesh.
        next_elements: usize,
        /// The limit.
        max_elements: usize,
        /// The change between the last two doubling levels (m or N), if
        /// known.
        last_change: Option<f64>,
    },
}

impl std::fmt::Display for RefinementStop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RefinementStop::MeshLimit {
                next_elements,
                max_elements,
                last_change,
            } => {
                write!(
                    f,
                    "the next mesh, {next_elements} elements, exceeds refinement.max_elements = {max_elements}"
                )?;
                if let Some(c) = last_change {
                    write!(f, " (last change {c:.2e})")?;
                }
                Ok(())
            }
        }
    }
}

/// Why a refinement stopped short of its tolerance, with what it tried
/// (carried by [`Error::RefinementNotConverged`](crate::Error::RefinementNotConverged)).
///
/// # Example
/// See [`crate::refine::auto_elements`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RefinementFailure {
    /// The quantity controlled.
    pub quantity: Quantity,
    /// Its tolerance (m or N).
    pub tolerance: f64,
    /// Why it stopped.
    pub stop: RefinementStop,
    /// Every mesh tried, in order.
    pub history: Vec<Trial>,
}

impl std::fmt::Display for RefinementFailure {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let q = self.quantity;
        write!(
            f,
            "{} to {:e} {}: {}; meshes tried:",
            q.name(),
            self.tolerance,
            q.unit(),
            self.stop
        )?;
        for t in &self.history {
            match (&t.failure, t.change) {
                (Some(why), _) => write!(f, " {} elements (failed: {why});", t.total_elements)?,
                (None, Some(c)) => write!(
                    f,
                    " {} elements (change {c:.2e} {});",
                    t.total_elements,
                    q.unit()
                )?,
                (None, None) => write!(f, " {} elements;", t.total_elements)?,
            }
        }
        Ok(())
    }
}
