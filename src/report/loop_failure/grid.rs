//! Where the closed loop fails: one tracking run per case of a grid over the
//! payload (in units of the robot's own weight), the plant's bending
//! stiffness error, the marker noise and the control rate, each classified
//! as converged or diverged with the cause.
//!
//! A case is [`run_track`] on the scene's robot with a tip mass of
//! `payload_weights ×` the robot's weight, the plant's `EI` off by
//! `ei_error` (its other differences at their defaults: twice the mesh,
//! actuation gain −10 %, `EA` −5 %, 20 ms regulator lag), marker noise
//! `noise_sigma_m` (the estimator told the same σ, as a user who knows the
//! camera would), at `control_rate_hz`, feedforward + updater.
//!
//! Every part of a run has an iteration limit (the estimator, the inverse
//! kinematics, the plant's static solve) and the run a fixed number of
//! steps, so a case ends without any wall-clock guard; a plant failure ends
//! it early with a row saying so. The verdict:
//!
//! - **converged**: the run reached its end, the mean error over the
//!   scoring window (after the hold) is at most
//!   [`FailureSettings::converged_mean_m`] and the mean over its last third
//!   at most twice that;
//! - **diverged** otherwise, with the first cause that holds, in this
//!   order: the plant failed ([`LoopCause::PlantFailure`]); the inverse
//!   kinematics did not reach its target in at least
//!   [`FailureSettings::flag_fraction`] of the window's steps
//!   ([`LoopCause::IkUnreachable`]); a chamber sat at its upper bound that
//!   often ([`LoopCause::PressureSaturation`]); the estimator failed that
//!   often ([`LoopCause::EstimatorFailure`]); the error grew (the last
//!   third's mean over twice the first third's) or the fed-forward load
//!   swung from step to step by more than its own mean change
//!   ([`LoopCause::UpdaterInstability`]); else the estimator converged
//!   every frame but its load was off ([`LoopCause::EstimateInaccurate`]).
//!   A run that could not start is [`LoopCause::StartFailed`].
//!
//! The sweep runs without the loop's watchdog
//! ([`FailureSettings::abort_error_m`] `None`): a watchdog stop would hide
//! the cause (2 × the robot's weight at the tip puts the tip more than
//! 100 mm off at the first frame, before any step is scored), and no run
//! needs it to end. A case stopped by a watchdog set there is
//! [`LoopCause::Watchdog`]. [`plant_reach_m`] checks an "IK unreachable"
//! against the plant itself: how close the plant, with the true payload and
//! no model error, can get to the scored path within the pressure bounds.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::plant::{PayloadSchedule, PlantSettings, SimulatedPlant};
use crate::scene::Scene;

use crate::control::{
    CircleSpec, ControllerKind, EstimateFlag, IkSettings, IkStatus, InverseKinematics,
    LoopSettings, StepStatus, TrackFile, TrackRun, TrajectorySpec, build_trajectory, run_track,
};

/// One case of the sweep.
///
/// # Example
/// ```
/// let c = softrod::report::loop_failure::LoopCase::nominal();
/// assert_eq!((c.payload_weights, c.ei_error, c.control_rate_hz), (0.0, 0.15, 30.0));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LoopCase {
    /// Tip mass in units of the robot's own weight (≥ 0).
    pub payload_weights: f64,
    /// The plant's bending stiffness error: its `EI` is `(1 + ei_error)` ×
    /// the model's (> −1).
    pub ei_error: f64,
    /// Marker noise, standard deviation per component (m, ≥ 0).
    pub noise_sigma_m: f64,
    /// Control rate (Hz).
    pub control_rate_hz: f64,
    /// Seed of the plant's noise.
    pub seed: u64,
}

impl LoopCase {
    /// The tracking figure's conditions: no payload, `EI` +15 %, 0.05 mm
    /// noise, 30 Hz, seed 1.
    pub fn nominal() -> Self {
        LoopCase {
            payload_weights: 0.0,
            ei_error: 0.15,
            noise_sigma_m: 5e-5,
            control_rate_hz: 30.0,
            seed: 1,
        }
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field.
    pub fn validate(&self) -> Result<()> {
        if !(self.payload_weights.is_finite() && self.payload_weights >= 0.0) {
            return Err(Error::invalid(
                "case.payload_weights",
                self.payload_weights,
                "must be finite and >= 0",
            ));
        }
        if !(self.ei_error.is_finite() && self.ei_error > -1.0) {
            return Err(Error::invalid(
                "case.ei_error",
                self.ei_error,
                "must be finite and > -1",
            ));
        }
        if !(self.noise_sigma_m.is_finite() && self.noise_sigma_m >= 0.0) {
            return Err(Error::invalid(
                "case.noise_sigma_m",
                self.noise_sigma_m,
                "must be finite and >= 0",
            ));
        }
        Ok(())
    }
}

/// How a case is run and judged; every field has a documented default.
///
/// # Example
/// ```
/// let s = softrod::report::loop_failure::FailureSettings::default();
/// assert_eq!((s.hold_s, s.duration_s, s.converged_mean_m), (3.0, 6.0, 5e-4));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FailureSettings {
    /// The circle's centre (m; default (0.1911, 0.1203), the model's end
    /// effector at (45, 0, 45, 0) kPa; typed: [`FailureSettings::center`]).
    pub center_m: [f64; 2],
    /// The circle's radius (m, default 5 mm).
    pub radius_m: f64,
    /// One turn (s, default 15).
    pub period_s: f64,
    /// Hold at the start point, not scored (s, default 3: the updater's 2 %
    /// settling time is 2.70 s).
    pub hold_s: f64,
    /// Motion after the hold, scored (s, default 6).
    pub duration_s: f64,
    /// A case converged if its mean error after the hold is at most this
    /// (m, default 0.5 mm).
    pub converged_mean_m: f64,
    /// A flag (IK not reached, saturation, estimator failure) is a cause
    /// when it holds in at least this fraction of the scored steps (default
    /// 0.1).
    pub flag_fraction: f64,
    /// The loop's watchdog ([`LoopSettings::abort_error_m`], m; default
    /// `None`, off). The sweep runs without it: every run is bounded by its
    /// iteration limits and its fixed number of steps, and a watchdog stop
    /// hides the cause (with 2× the robot's weight at the tip the tip is
    /// more than 100 mm off at the first frame, before any step is scored).
    /// A case stopped by a watchdog set here is [`LoopCause::Watchdog`].
    #[serde(default)]
    pub abort_error_m: Option<f64>,
}

impl Default for FailureSettings {
    fn default() -> Self {
        FailureSettings {
            center_m: [0.1911, 0.1203],
            radius_m: 0.005,
            period_s: 15.0,
            hold_s: 3.0,
            duration_s: 6.0,
            converged_mean_m: 5e-4,
            flag_fraction: 0.1,
            abort_error_m: None,
        }
    }
}

impl FailureSettings {
    /// The circle's centre (m), typed.
    ///
    /// # Example
    /// ```
    /// let s = softrod::report::loop_failure::FailureSettings::default();
    /// assert_eq!(s.center(), nalgebra::Vector2::new(0.1911, 0.1203));
    /// ```
    pub fn center(&self) -> nalgebra::Vector2<f64> {
        self.center_m.into()
    }
}

/// Converged or not.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoopVerdict {
    /// See [`run_case`](crate::report::loop_failure::run_case).
    Converged,
    /// See [`run_case`](crate::report::loop_failure::run_case).
    Diverged,
}

/// Why a case diverged (see [`run_case`](crate::report::loop_failure::run_case) for the
/// order in which they are tested).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoopCause {
    /// Converged: no cause.
    None,
    /// The plant's own equilibrium failed; the run stopped.
    PlantFailure,
    /// The inverse kinematics did not reach its targets within the bounds.
    IkUnreachable,
    /// A chamber sat at its upper pressure bound.
    PressureSaturation,
    /// The estimator failed (last good estimate kept) in many frames.
    EstimatorFailure,
    /// The error grew or the fed-forward load swung from step to step.
    UpdaterInstability,
    /// The estimator converged but its load was off (noise): the error
    /// stayed above the threshold without growing.
    EstimateInaccurate,
    /// The run could not start (no equilibrium or no pose at the start).
    StartFailed,
    /// The watchdog stopped the run: the tip was more than
    /// [`FailureSettings::abort_error_m`] off its target.
    Watchdog,
}

impl LoopCause {
    /// A short label (charts).
    pub fn label(&self) -> &'static str {
        match self {
            LoopCause::None => "converged",
            LoopCause::PlantFailure => "plant failure",
            LoopCause::IkUnreachable => "IK unreachable",
            LoopCause::PressureSaturation => "pressure saturation",
            LoopCause::EstimatorFailure => "estimator failure",
            LoopCause::UpdaterInstability => "updater instability",
            LoopCause::EstimateInaccurate => "estimate inaccurate",
            LoopCause::StartFailed => "start failed",
            LoopCause::Watchdog => "watchdog",
        }
    }

    /// Every cause, in the order of the module documentation.
    pub const ALL: [LoopCause; 9] = [
        LoopCause::None,
        LoopCause::PlantFailure,
        LoopCause::IkUnreachable,
        LoopCause::PressureSaturation,
        LoopCause::EstimatorFailure,
        LoopCause::UpdaterInstability,
        LoopCause::EstimateInaccurate,
        LoopCause::StartFailed,
        LoopCause::Watchdog,
    ];
}

/// One case's result.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoopOutcome {
    /// The case.
    pub case: LoopCase,
    /// Converged or diverged.
    pub verdict: LoopVerdict,
    /// Why it diverged ([`LoopCause::None`] if it converged).
    pub cause: LoopCause,
    /// Mean tracking error after the hold (m; `None` if no step was scored:
    /// it could not start or stopped during the hold).
    pub mean_error_m: Option<f64>,
    /// Maximum tracking error after the hold (m).
    pub max_error_m: Option<f64>,
    /// Scored steps.
    pub scored_steps: usize,
    /// Scored steps whose inverse kinematics did not reach its target.
    pub ik_not_reached: usize,
    /// Scored steps with a chamber at its upper bound.
    pub saturated: usize,
    /// Scored frames whose estimator failed.
    pub estimator_failed: usize,
    /// When the plant failed (s), if it did.
    pub plant_failed_at_s: Option<f64>,
    /// The error that stopped the run from starting, if any.
    pub message: Option<String>,
}

/// The robot's own weight's mass (kg): `Σ mass per length × length`.
pub fn robot_mass_kg(scene: &Scene) -> f64 {
    scene
        .robot
        .sections
        .iter()
        .map(|s| s.mass_per_length_kg_per_m * s.length_m)
        .sum()
}

/// The trajectory file of `case` under `settings` (see [`run_case`](crate::report::loop_failure::run_case)).
///
/// # Errors
/// As [`LoopCase::validate`].
pub fn case_file(scene: &Scene, case: &LoopCase, settings: &FailureSettings) -> Result<TrackFile> {
    case.validate()?;
    let length: f64 = scene.robot.sections.iter().map(|s| s.length_m).sum();
    let mut loop_settings = LoopSettings {
        control_rate_hz: case.control_rate_hz,
        controller: ControllerKind::FfUpdater,
        abort_error_m: settings.abort_error_m,
        ..Default::default()
    };
    if case.noise_sigma_m > 0.0 {
        loop_settings.estimator.noise_sigma_m = case.noise_sigma_m;
    }
    Ok(TrackFile {
        trajectory: TrajectorySpec::Circle(CircleSpec {
            center_m: Some(settings.center_m.to_vec()),
            radius_m: settings.radius_m,
            period_s: settings.period_s,
            duration_s: settings.duration_s,
            hold_s: settings.hold_s,
        }),
        loop_settings,
        plant: PlantSettings {
            ei_factor: 1.0 + case.ei_error,
            noise_sigma_m: case.noise_sigma_m,
            seed: case.seed,
            payloads: PayloadSchedule::tip_mass(
                case.payload_weights * robot_mass_kg(scene),
                length,
            ),
            ..Default::default()
        },
        score_from_s: Some(settings.hold_s),
    })
}

/// How close the plant itself can get to the scored path of `case` (m): the
/// largest, over `points` instants evenly spread over the scored window, of
/// the distance of the closest pose within the pressure bounds, found by
/// [`InverseKinematics`] on the plant's own robot (its mesh and parameter
/// errors) carrying the case's true payload. Zero (below the inverse
/// kinematics' tolerance) when the plant can follow the path: a loop that
/// then reports "IK unreachable" failed by its estimate, not by the
/// physics.
///
/// # Errors
/// As [`LoopCase::validate`]; [`Error::InvalidParameter`] (field `points`)
/// for fewer than 1; the plant's and the inverse kinematics' errors.
///
/// # Example
/// ```
/// use softrod::report::loop_failure::{plant_reach_m, FailureSettings, LoopCase};
/// let mut scene = softrod::scene::Scene::two_section();
/// scene.pressures_pa = vec![45e3, 0.0, 45e3, 0.0];
/// let d = plant_reach_m(&scene, &LoopCase::nominal(), &FailureSettings::default(), 2)?;
/// assert!(d < 1e-6);
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn plant_reach_m(
    scene: &Scene,
    case: &LoopCase,
    settings: &FailureSettings,
    points: usize,
) -> Result<f64> {
    if points == 0 {
        return Err(Error::invalid("points", 0, "must be >= 1"));
    }
    let file = case_file(scene, case, settings)?;
    let trajectory = build_trajectory(scene, &file.trajectory)?;
    let length: f64 = scene.robot.sections.iter().map(|s| s.length_m).sum();
    let plant = SimulatedPlant::new(scene, &[length], file.plant.clone())?;
    let own = plant.scene();
    let known = file
        .plant
        .payloads
        .loads_at(settings.hold_s, &own.gravity_m_per_s2, &own.loads()?);
    let robot = plant.robot().clone();
    let zero = vec![0.0; robot.n_q()];
    let mut ik = InverseKinematics::new(robot, known, IkSettings::default())?;
    let mut worst = 0.0f64;
    for k in 0..points {
        let frac = if points == 1 {
            0.0
        } else {
            k as f64 / (points - 1) as f64
        };
        let x = trajectory.at(settings.hold_s + frac * settings.duration_s);
        let sol = ik.solve(x.as_slice(), &zero)?;
        worst = worst.max(sol.status.error_m());
    }
    Ok(worst)
}

/// Runs one case and judges it.
///
/// # Errors
/// [`Error::InvalidParameter`] for an invalid case or settings (naming the
/// field). A run that fails to start is an outcome
/// ([`LoopCause::StartFailed`]), not an error.
///
/// # Example
/// See `tests/control_failure.rs`; `softrod report --only loop` runs the grid.
pub fn run_case(scene: &Scene, case: &LoopCase, settings: &FailureSettings) -> Result<LoopOutcome> {
    let file = case_file(scene, case, settings)?;
    file.loop_settings.validate()?;
    if !(settings.converged_mean_m.is_finite() && settings.converged_mean_m > 0.0) {
        return Err(Error::invalid(
            "converged_mean_m",
            settings.converged_mean_m,
            "must be finite and > 0",
        ));
    }
    if !(settings.flag_fraction.is_finite()
        && settings.flag_fraction > 0.0
        && settings.flag_fraction <= 1.0)
    {
        return Err(Error::invalid(
            "flag_fraction",
            settings.flag_fraction,
            "must be in (0, 1]",
        ));
    }
    match run_track(scene, &file, None, None) {
        Ok(run) => Ok(judge(scene, *case, settings, &run)),
        Err(e) => {
            // the settings were checked: what remains is the start
            if matches!(&e, Error::InvalidParameter { name, .. } if name.starts_with("case.")) {
                return Err(e);
            }
            Ok(LoopOutcome {
                case: *case,
                verdict: LoopVerdict::Diverged,
                cause: LoopCause::StartFailed,
                mean_error_m: None,
                max_error_m: None,
                scored_steps: 0,
                ik_not_reached: 0,
                saturated: 0,
                estimator_failed: 0,
                plant_failed_at_s: None,
                message: Some(e.to_string()),
            })
        }
    }
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// The verdict and cause of a finished run (see [`run_case`](crate::report::loop_failure::run_case)).
fn judge(scene: &Scene, case: LoopCase, settings: &FailureSettings, run: &TrackRun) -> LoopOutcome {
    let from = run.summary.score_from_s;
    let scored: Vec<_> = run
        .samples
        .iter()
        .filter(|s| s.time_s >= from && s.status.tip_known())
        .collect();
    let n = scored.len();
    let upper: Vec<f64> = scene
        .robot
        .sections
        .iter()
        .flat_map(|s| s.chambers.iter().map(|c| c.pressure_max_pa))
        .collect();
    let ik_not_reached = scored
        .iter()
        .filter(|s| !matches!(s.ik, IkStatus::Reached { .. }))
        .count();
    let saturated = scored
        .iter()
        .filter(|s| {
            s.pressures_pa
                .iter()
                .zip(&upper)
                .any(|(p, hi)| *p >= hi * (1.0 - 1e-9))
        })
        .count();
    let estimator_failed = scored
        .iter()
        .filter(|s| matches!(s.estimate, EstimateFlag::KeptLast { .. }))
        .count();
    let errors: Vec<f64> = scored.iter().map(|s| s.error_m).collect();
    let third = (n / 3).max(1);
    let first = mean(&errors[..third.min(n)]);
    let last = mean(&errors[n.saturating_sub(third)..]);
    let mean_error = mean(&errors);
    let max_error = errors.iter().fold(0.0f64, |m, v| m.max(*v));
    let plant_failed_at_s = run.summary.plant_failed_at_s;
    let aborted = run
        .samples
        .last()
        .is_some_and(|s| matches!(s.status, StepStatus::Aborted { .. }));
    let converged = plant_failed_at_s.is_none()
        && !aborted
        && n > 0
        && mean_error <= settings.converged_mean_m
        && last <= 2.0 * settings.converged_mean_m;
    // the fed-forward load: mean |ΔF̂| against the mean |F̂_k+1 − F̂_k−1|/2
    // (a smooth sequence has them equal; a sequence that flips every step
    // has the first much larger)
    let fhat: Vec<&Vec<f64>> = scored.iter().map(|s| &s.estimated_load_n).collect();
    let dist = |a: &[f64], b: &[f64]| -> f64 {
        a.iter()
            .zip(b)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let step1 = mean(
        &fhat
            .windows(2)
            .map(|w| dist(w[0], w[1]))
            .collect::<Vec<_>>(),
    );
    let step2 = mean(
        &fhat
            .windows(3)
            .map(|w| 0.5 * dist(w[0], w[2]))
            .collect::<Vec<_>>(),
    );
    let flag = |count: usize| n > 0 && count as f64 >= settings.flag_fraction * n as f64;
    let cause = if converged {
        LoopCause::None
    } else if plant_failed_at_s.is_some() {
        LoopCause::PlantFailure
    } else if aborted {
        LoopCause::Watchdog
    } else if flag(ik_not_reached) {
        LoopCause::IkUnreachable
    } else if flag(saturated) {
        LoopCause::PressureSaturation
    } else if flag(estimator_failed) {
        LoopCause::EstimatorFailure
    } else if last > 2.0 * first || step1 > 2.0 * step2.max(1e-12) {
        LoopCause::UpdaterInstability
    } else {
        LoopCause::EstimateInaccurate
    };
    LoopOutcome {
        case,
        verdict: if converged {
            LoopVerdict::Converged
        } else {
            LoopVerdict::Diverged
        },
        cause,
        mean_error_m: (n > 0).then_some(mean_error),
        max_error_m: (n > 0).then_some(max_error),
        scored_steps: n,
        ik_not_reached,
        saturated,
        estimator_failed,
        plant_failed_at_s,
        message: None,
    }
}
