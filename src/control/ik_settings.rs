//! The inverse kinematics' settings and the status of a solve (see
//! [`InverseKinematics`](super::InverseKinematics)).

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::statics::StaticSettings;

/// Settings of [`InverseKinematics`](super::InverseKinematics); every field has a documented default.
///
/// # Example
/// ```
/// softrod::control::IkSettings::default().validate()?;
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IkSettings {
    /// Newton iterations per solve (default 40).
    pub max_iterations: usize,
    /// The end effector counts as reached within this distance (m, default 1e-7).
    pub tolerance_m: f64,
    /// Largest change of a scaled pressure `P / range` in one step (default 0.25).
    pub max_step: f64,
    /// Static solver of the equilibria `q(P)`.
    pub statics: StaticSettings,
    /// Newton iterations in all (over every load step) of the static solve
    /// of one line-search trial that the warm corrector did not finish
    /// (default 150; at most `statics.max_total_iterations` is used). A
    /// trial the static solver does not reach within it is rejected, as one that does not lower
    /// the merit is, and the step is halved: a trial that needs a long
    /// homotopy crosses a fold of the equilibria (a heavily loaded robot
    /// snapping over) or is too long. Measured on the failure sweep's
    /// cases: converging trials take at most 135 iterations (2 × the
    /// robot's weight at the tip), failing ones 550–990 (5 ×), which made
    /// one control step cost up to 10 s.
    pub trial_max_total_iterations: usize,
    /// Static Newton iterations one [`InverseKinematics::solve`](super::InverseKinematics::solve) may spend
    /// in all: its equilibria, line-search trials and restarts (default
    /// 20 000). When they are spent the solve ends with the closest pose
    /// found so far and [`IkStatus::IterationLimit`], so one control step
    /// has a bounded cost whatever the load.
    pub max_static_iterations: usize,
    /// Weight `μ` of the scaled pressures' norm `½ μ |P̂|²` against the
    /// position error `½ |x_d − x|² / ℓ²`, ℓ = 0.1 mm (default 1e-2): the
    /// redundancy rule, least `Σ P̂²` (dimensionless, ≥ 0, at most 1e6).
    pub pressure_weight: f64,
    /// A damping `λ` of every step (dimensionless, added to the diagonal of
    /// the step's Hessian in scaled pressures, default 0, ≥ 0, at most
    /// 1e6): a step then moves only `μ/(μ + λ)` of the way to the least
    /// pressures in the null space of the Jacobian (the parallel robot's 18
    /// pressures for 3 coordinates: there a full null-space move changes
    /// the pressures by tens of kPa, whose nonlinearity the next iterations
    /// must undo), fully in its range.
    pub null_space_damping: f64,
    /// End a solve as soon as the end effector is within `tolerance_m`
    /// (default `false`: the iterations go on until no step lowers the
    /// merit, which settles the pressures on the least `Σ P̂²` of the
    /// redundancy rule). With a [`IkSettings::null_space_damping`] the
    /// null-space moves are slow by design, so a controller that only needs
    /// the position stops here (the parallel robot's: 1–3 iterations per
    /// control instant instead of the iteration limit).
    pub stop_when_reached: bool,
}

impl Default for IkSettings {
    fn default() -> Self {
        IkSettings {
            max_iterations: 40,
            tolerance_m: 1e-7,
            max_step: 0.25,
            statics: StaticSettings::default(),
            trial_max_total_iterations: 150,
            max_static_iterations: 20_000,
            pressure_weight: 1e-2,
            null_space_damping: 0.0,
            stop_when_reached: false,
        }
    }
}

impl IkSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`ik.tolerance_m`, …).
    pub fn validate(&self) -> Result<()> {
        if self.max_iterations == 0 {
            return Err(Error::invalid("ik.max_iterations", 0, "must be >= 1"));
        }
        if self.max_static_iterations == 0 {
            return Err(Error::invalid(
                "ik.max_static_iterations",
                0,
                "must be >= 1",
            ));
        }
        if self.trial_max_total_iterations == 0 {
            return Err(Error::invalid(
                "ik.trial_max_total_iterations",
                0,
                "must be >= 1",
            ));
        }
        for (name, v) in [
            ("ik.tolerance_m", self.tolerance_m),
            ("ik.max_step", self.max_step),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(name, v, "must be finite and > 0"));
            }
        }
        for (name, v) in [
            ("ik.pressure_weight", self.pressure_weight),
            ("ik.null_space_damping", self.null_space_damping),
        ] {
            if !(v.is_finite() && (0.0..=1e6).contains(&v)) {
                return Err(Error::invalid(name, v, "must lie in [0, 1e6]"));
            }
        }
        self.statics.validate("ik.statics")
    }
}

/// How an inverse-kinematics solve ended.
///
/// # Example
/// ```
/// let s = softrod::control::IkStatus::Reached { error_m: 1e-9 };
/// assert!(s.is_reached());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum IkStatus {
    /// The end effector is at the target within the tolerance.
    Reached {
        /// Remaining distance (m).
        error_m: f64,
    },
    /// The target cannot be reached within the pressure bounds: the solution
    /// is the closest reachable pose found.
    Unreachable {
        /// Distance from the closest pose to the target (m).
        distance_m: f64,
    },
    /// The iteration limit came first.
    IterationLimit {
        /// Remaining distance (m).
        error_m: f64,
    },
    /// Not solved: in a closed loop, the inverse kinematics found no
    /// equilibrium this instant or the plant failed before it ran (the
    /// sample's status says which); the last command is held.
    NotSolved,
}

impl IkStatus {
    /// Whether the target was reached.
    pub fn is_reached(&self) -> bool {
        matches!(self, IkStatus::Reached { .. })
    }

    /// The remaining distance to the target (m; infinite when not solved).
    pub fn error_m(&self) -> f64 {
        match *self {
            IkStatus::Reached { error_m } | IkStatus::IterationLimit { error_m } => error_m,
            IkStatus::Unreachable { distance_m } => distance_m,
            IkStatus::NotSolved => f64::INFINITY,
        }
    }
}

/// Which bound a chamber's pressure sits on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PressureBound {
    /// Strictly inside its bounds.
    Inside,
    /// Exactly at `P_min`.
    Min,
    /// Exactly at `P_max`.
    Max,
}
