//! A tracking run as the command line describes it (`softrod track`): a
//! scene (the controller's model), a trajectory file (the path, the loop's
//! and the plant's settings) and a payload schedule, run against a
//! [`SimulatedPlant`] built from the scene with the plant's differences.
//!
//! The trajectory file (JSON; every field but `trajectory` optional):
//!
//! ```json
//! {
//!   "trajectory": {"kind": "circle", "center_m": [0.1911, 0.1203], "radius_m": 0.005,
//!                  "period_s": 15.0, "duration_s": 15.0, "hold_s": 3.0},
//!   "loop": {"control_rate_hz": 30.0, "controller": "ff_updater",
//!            "gains": {"k_p_per_s": 4.0, "k_i_per_s2": 4.0}},
//!   "plant": {"ei_factor": 1.15, "gain_factor": 0.9, "noise_sigma_m": 5e-5},
//!   "score_from_s": 3.0
//! }
//! ```
//!
//! Trajectory kinds: `circle`, `figure_eight` (`size_m`), `line`
//! (`from_m`, `to_m`), `samples` (`times_s`, `points_m`) and `pressures`
//! (`times_s`, `pressures_pa`: the path is the model's unloaded end
//! effector under that pressure schedule). A `circle` or `figure_eight`
//! without `center_m` is centred on the model's end effector at the
//! scene's pressures. The payload file is a [`PayloadSchedule`]
//! (`{"payloads": [...]}`), replacing the plant's.
//!
//! Every check names the field as written in its file
//! (`trajectory.radius_m`, `loop.gains.k_p_per_s`, `payloads[1].end_s`,
//! `trajectory.pressures_pa[3][1]`, …).

use nalgebra::DVector;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_all_finite, check_len};
use crate::plant::{PayloadSchedule, PlantSettings, SimulatedPlant};
use crate::scene::Scene;

use super::{
    ClosedLoop, ControllerKind, EstimateFlag, IkStatus, LoopSettings, StepStatus, TimeSeries,
    Trajectory,
};
use super::{IkSettings, InverseKinematics};

mod spec;
pub use spec::{CircleSpec, FigureEightSpec, LineSpec, PressuresSpec, SamplesSpec, TrajectorySpec};

/// A trajectory file (see the [module documentation](crate::control)); read it with
/// [`TrackFile::from_json`], which names the path of a bad field.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackFile {
    /// The desired path.
    pub trajectory: TrajectorySpec,
    /// The loop (default [`LoopSettings::default`]).
    #[serde(rename = "loop", default)]
    pub loop_settings: LoopSettings,
    /// The plant's differences from the scene (default
    /// [`PlantSettings::default`]).
    #[serde(default)]
    pub plant: PlantSettings,
    /// Errors are scored from this time on (s; default the trajectory's
    /// hold, else 2.7 s, the updater's 2 % settling time).
    #[serde(default)]
    pub score_from_s: Option<f64>,
}

/// A trajectory file with the trajectory not yet parsed.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TrackFileRaw {
    trajectory: serde_json::Value,
    #[serde(rename = "loop", default)]
    loop_settings: LoopSettings,
    #[serde(default)]
    plant: PlantSettings,
    #[serde(default)]
    score_from_s: Option<f64>,
}

impl TrackFile {
    /// Parses a trajectory file.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for malformed JSON, unknown fields or
    /// wrong types, naming the field's path (`(file)` when the JSON itself
    /// is broken).
    ///
    /// # Example
    /// ```
    /// let f = softrod::control::TrackFile::from_json(r#"{"trajectory": {"kind": "circle", "radius_m": 0.005, "period_s": 15, "duration_s": 15}}"#)?;
    /// assert_eq!(f.loop_settings.control_rate_hz, 30.0);
    /// let e = softrod::control::TrackFile::from_json(r#"{"trajectory": {"kind": "circle", "radius_m": "big"}}"#).unwrap_err();
    /// assert_eq!(e.field(), Some("trajectory.radius_m"), "{e}");
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn from_json(text: &str) -> Result<Self> {
        let raw: TrackFileRaw = parse_json(text)?;
        Ok(TrackFile {
            trajectory: TrajectorySpec::from_value(raw.trajectory)?,
            loop_settings: raw.loop_settings,
            plant: raw.plant,
            score_from_s: raw.score_from_s,
        })
    }
}

/// Parses JSON with the path of a bad field in the message.
pub(crate) fn parse_json<T: serde::de::DeserializeOwned>(text: &str) -> Result<T> {
    crate::scene::json::parse(text).map_err(|e| Error::invalid(e.name(), "as written", e.message))
}

/// Parses a payload file (`{"payloads": [...]}`).
///
/// # Errors
/// As [`TrackFile::from_json`].
///
/// # Example
/// ```
/// let p = softrod::control::payloads_from_json(r#"{"payloads": [{"kind": "point_mass", "mass_kg": 0.02, "s_m": 0.24}]}"#)?;
/// assert_eq!(p.payloads.len(), 1);
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn payloads_from_json(text: &str) -> Result<PayloadSchedule> {
    parse_json(text)
}

/// One sample of a tracking run, as written.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackSample {
    /// Time (s).
    pub time_s: f64,
    /// Desired end effector (m).
    pub desired_m: Vec<f64>,
    /// The plant's true end effector (m).
    pub actual_m: Vec<f64>,
    /// The end-effector marker as measured (m).
    pub measured_m: Vec<f64>,
    /// `|actual − desired|` (m).
    pub error_m: f64,
    /// The payload mass acting on the plant (kg; the controller is not told).
    pub payload_kg: f64,
    /// Resultant of the load the feedforward uses, `F̂` (N; payload plus
    /// the virtual payload of the model's errors).
    pub estimated_load_n: Vec<f64>,
    /// Resultant of the estimator's `F̄` this frame (N).
    pub estimator_load_n: Vec<f64>,
    /// Pressures commanded for the next interval (Pa).
    pub pressures_pa: Vec<f64>,
    /// Wall time of estimation + updater + inverse kinematics (s).
    pub step_time_s: f64,
    /// How the inverse kinematics ended.
    pub ik: IkStatus,
    /// The estimator this frame (`kept_last`: it failed, the last good
    /// estimate was used).
    pub estimate: EstimateFlag,
    /// How the step ended (`ok`, `ik_failed`: last command held,
    /// `plant_failed`: the plant's equilibrium failed and the run stopped).
    pub status: StepStatus,
}

impl TrackSample {
    /// [`TrackSample::desired_m`] as a vector (m).
    ///
    /// # Example
    /// ```
    /// use softrod::control::{EstimateFlag, IkStatus, StepStatus, TrackSample};
    /// let s = TrackSample {
    ///     time_s: 1.0, desired_m: vec![0.2, 0.05], actual_m: vec![0.2, 0.0498],
    ///     measured_m: vec![0.2, 0.0497], error_m: 2e-4, payload_kg: 0.0,
    ///     estimated_load_n: vec![0.0, -0.1], estimator_load_n: vec![0.0, -0.12],
    ///     pressures_pa: vec![0.0; 4], step_time_s: 0.0, ik: IkStatus::NotSolved,
    ///     estimate: EstimateFlag::NotRun, status: StepStatus::Ok,
    /// };
    /// assert!(((s.actual() - s.desired()).norm() - s.error_m).abs() < 1e-15);
    /// assert_eq!(s.measured(), nalgebra::dvector![0.2, 0.0497]);
    /// assert_eq!(s.estimated_load(), nalgebra::dvector![0.0, -0.1]);
    /// assert_eq!(s.estimator_load(), nalgebra::dvector![0.0, -0.12]);
    /// ```
    pub fn desired(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.desired_m)
    }

    /// [`TrackSample::actual_m`] as a vector (m).
    ///
    /// # Example
    /// See [`TrackSample::desired`].
    pub fn actual(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.actual_m)
    }

    /// [`TrackSample::measured_m`] as a vector (m).
    ///
    /// # Example
    /// See [`TrackSample::desired`].
    pub fn measured(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.measured_m)
    }

    /// [`TrackSample::estimated_load_n`] as a vector (N).
    ///
    /// # Example
    /// See [`TrackSample::desired`].
    pub fn estimated_load(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.estimated_load_n)
    }

    /// [`TrackSample::estimator_load_n`] as a vector (N).
    ///
    /// # Example
    /// See [`TrackSample::desired`].
    pub fn estimator_load(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.estimator_load_n)
    }
}

/// The summary of a tracking run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackSummary {
    /// The controller.
    pub controller: ControllerKind,
    /// Control rate (Hz).
    pub control_rate_hz: f64,
    /// Samples.
    pub samples: usize,
    /// Scoring starts here (s).
    pub score_from_s: f64,
    /// Mean tracking error from `score_from_s` on (m).
    pub mean_error_m: f64,
    /// Maximum tracking error from `score_from_s` on (m).
    pub max_error_m: f64,
    /// Median step time (s).
    pub median_step_time_s: f64,
    /// Samples whose inverse kinematics did not reach its target.
    pub ik_not_reached: usize,
    /// Samples whose pressures sat on a bound.
    pub pressure_saturated: usize,
    /// Frames whose estimator failed (last good estimate kept).
    pub estimator_kept_last: usize,
    /// Steps whose inverse kinematics found no equilibrium (last command
    /// held).
    pub ik_failed: usize,
    /// The time the plant's equilibrium failed and the run stopped (s), or
    /// `None`.
    pub plant_failed_at_s: Option<f64>,
    /// The time the watchdog (`loop.abort_error_m`) stopped the run (s), or
    /// `None`.
    pub aborted_at_s: Option<f64>,
    /// The plant (its differences from the model, payloads included).
    pub plant: PlantSettings,
}

/// A finished tracking run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackRun {
    /// The summary.
    pub summary: TrackSummary,
    /// One sample per control instant.
    pub samples: Vec<TrackSample>,
}

/// Checks a point: `DIM` finite coordinates within the robot's reach.
fn check_point(field: &str, p: &[f64], base: &[f64], length: f64) -> Result<()> {
    check_len(field, base.len(), p.len())?;
    check_all_finite(field, p)?;
    let d = p
        .iter()
        .zip(base)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt();
    if d > length {
        return Err(Error::invalid(
            field,
            format!("{p:?}"),
            format!("out of reach: {d:.4} m from the base, the robot is {length:.4} m long"),
        ));
    }
    Ok(())
}

fn check_positive(field: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(field, v, "must be finite and > 0"))
    }
}

/// Builds the desired trajectory of `spec` for the model of `scene`.
///
/// # Errors
/// [`Error::InvalidParameter`] naming the field (`trajectory.radius_m`,
/// `trajectory.points_m[4]`, `trajectory.pressures_pa[2][0]`, …): not
/// finite, of the wrong size, out of reach (farther from the base than the
/// robot is long, or, checked by the inverse kinematics on 8 points of the
/// path, more than 0.5 mm from any pose within the pressure bounds), an
/// empty trajectory, times going backwards, pressures outside the bounds.
pub fn build_trajectory(scene: &Scene, spec: &TrajectorySpec) -> Result<Trajectory> {
    let robot = scene.robot()?;
    let loads = scene.loads()?;
    let base = robot.position_at(robot.reference_configuration().as_slice(), 0.0)?;
    let length = robot.length();
    let mut ik = InverseKinematics::new(robot.clone(), loads.clone(), IkSettings::default())?;
    let zeros = vec![0.0; robot.n_q()];
    let center = |c: &Option<Vec<f64>>, ik: &mut InverseKinematics<_>| -> Result<Vec<f64>> {
        match c {
            Some(c) => {
                check_point("trajectory.center_m", c, base.as_slice(), length)?;
                Ok(c.clone())
            }
            None => Ok(ik.forward(&loads.pressures_pa, &zeros, None)?.1.data.into()),
        }
    };
    let arr = |v: &[f64]| nalgebra::Vector2::new(v[0], v.get(1).copied().unwrap_or(0.0));
    // (the trajectory, the field a point out of reach is blamed on, the
    // other field that places the path, named in the message)
    let (traj, blame, with) = match spec {
        TrajectorySpec::Circle(CircleSpec {
            center_m,
            radius_m,
            period_s,
            duration_s,
            hold_s,
        }) => {
            check_positive("trajectory.radius_m", *radius_m)?;
            let c = center(center_m, &mut ik)?;
            (
                Trajectory::circle(arr(&c), *radius_m, *period_s, *duration_s, *hold_s)?,
                "trajectory.radius_m".to_string(),
                center_m.as_ref().map(|_| "trajectory.center_m"),
            )
        }
        TrajectorySpec::FigureEight(FigureEightSpec {
            center_m,
            size_m,
            period_s,
            duration_s,
            hold_s,
        }) => {
            check_positive("trajectory.size_m", *size_m)?;
            let c = center(center_m, &mut ik)?;
            (
                Trajectory::figure_eight(arr(&c), *size_m, *period_s, *duration_s, *hold_s)?,
                "trajectory.size_m".to_string(),
                center_m.as_ref().map(|_| "trajectory.center_m"),
            )
        }
        TrajectorySpec::Line(LineSpec {
            from_m,
            to_m,
            period_s,
            duration_s,
            hold_s,
        }) => {
            check_point("trajectory.from_m", from_m, base.as_slice(), length)?;
            check_point("trajectory.to_m", to_m, base.as_slice(), length)?;
            (
                Trajectory::line(arr(from_m), arr(to_m), *period_s, *duration_s, *hold_s)?,
                "trajectory.to_m".to_string(),
                Some("trajectory.from_m"),
            )
        }
        TrajectorySpec::Samples(SamplesSpec { times_s, points_m }) => {
            let t = Trajectory::from_rows(times_s.clone(), points_m.clone())?;
            for (i, p) in points_m.iter().enumerate() {
                check_point(
                    &format!("trajectory.points_m[{i}]"),
                    p,
                    base.as_slice(),
                    length,
                )?;
            }
            (t, "trajectory.points_m".to_string(), None)
        }
        TrajectorySpec::Pressures(PressuresSpec {
            times_s,
            pressures_pa,
        }) => {
            if pressures_pa.len() != times_s.len() || times_s.is_empty() {
                return Err(Error::invalid(
                    "trajectory.pressures_pa",
                    pressures_pa.len(),
                    format!(
                        "must have one pressure set per time ({}), at least one",
                        times_s.len()
                    ),
                ));
            }
            let bounds = robot.pressure_bounds();
            let mut points = Vec::with_capacity(times_s.len());
            for (i, p) in pressures_pa.iter().enumerate() {
                let field = format!("trajectory.pressures_pa[{i}]");
                check_len(&field, bounds.len(), p.len())?;
                for (j, (v, (lo, hi))) in p.iter().zip(&bounds).enumerate() {
                    if !(v.is_finite() && *v >= *lo && *v <= *hi) {
                        return Err(Error::invalid(
                            format!("{field}[{j}]"),
                            v,
                            format!("must lie within the chamber's bounds [{lo}, {hi}] Pa"),
                        ));
                    }
                }
                points.push(ik.forward(p, &zeros, None)?.1.data.into());
            }
            (
                Trajectory::from_rows(times_s.clone(), points)?,
                "trajectory.pressures_pa".to_string(),
                None,
            )
        }
    };
    // reach: the distance from the base at every sample, the inverse
    // kinematics at 8 points
    for (i, p) in traj.points_m.iter().enumerate() {
        check_point(&blame, p, base.as_slice(), length).map_err(|e| match e {
            Error::InvalidParameter {
                name,
                value,
                reason,
            } => Error::InvalidParameter {
                name,
                value,
                reason: format!(
                    "{reason} (the path's point {i}, at {} s){}",
                    traj.times_s[i],
                    placed_by(with)
                ),
            },
            other => other,
        })?;
    }
    let n = traj.points_m.len();
    let m = 8.min(n);
    for k in 0..m {
        let i = if m > 1 { k * (n - 1) / (m - 1) } else { 0 };
        let sol = ik.solve(&traj.points_m[i], &zeros).map_err(|e| {
            Error::invalid(
                blame.clone(),
                format!("{:?}", traj.points_m[i]),
                format!(
                    "out of reach at {} s: the inverse kinematics found no pose ({e}){}",
                    traj.times_s[i],
                    placed_by(with)
                ),
            )
        })?;
        if !sol.status.is_reached() && sol.status.error_m() > 5e-4 {
            return Err(Error::invalid(
                blame,
                format!("{:?}", traj.points_m[i]),
                format!(
                    "out of reach at {} s: the closest pose within the pressure bounds is {:.2} mm away{}",
                    traj.times_s[i],
                    sol.status.error_m() * 1e3,
                    placed_by(with)
                ),
            ));
        }
    }
    Ok(traj)
}

/// The note of a reach error on a path that another field places too.
fn placed_by(with: Option<&str>) -> String {
    with.map(|w| format!("; the path is placed by `{w}` too"))
        .unwrap_or_default()
}

/// Checks the file's settings with the paths of the file.
fn validate_file(file: &TrackFile, payloads: &PayloadSchedule, length_m: f64) -> Result<()> {
    file.loop_settings.validate()?;
    file.plant.validate()?;
    if let Some(t) = file.score_from_s
        && !(t.is_finite() && t >= 0.0)
    {
        return Err(Error::invalid("score_from_s", t, "must be finite and >= 0"));
    }
    payloads.validate(length_m)
}

/// Checks a trajectory file (and a payload schedule replacing the plant's,
/// if given) against `scene` as [`run_track`] does before it runs: the
/// settings, the payloads and the trajectory (every point within reach),
/// without running the loop. A refusal names the field as written in the
/// file.
///
/// # Errors
/// As [`run_track`]'s checks.
///
/// # Example
/// ```
/// use softrod::control::{check_track, TrackFile};
/// let scene = softrod::scene::Scene::two_section();
/// let file = TrackFile::from_json(r#"{"trajectory": {"kind": "circle", "radius_m": 0.005, "period_s": 15, "duration_s": 15},
///   "loop": {"control_rate_hz": -30}}"#)?;
/// let e = check_track(&scene, &file, None).unwrap_err();
/// assert_eq!(e.field(), Some("loop.control_rate_hz"), "{e}");
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn check_track(
    scene: &Scene,
    file: &TrackFile,
    payloads: Option<&PayloadSchedule>,
) -> Result<Trajectory> {
    let length = scene.robot()?.length();
    validate_file(file, payloads.unwrap_or(&file.plant.payloads), length)?;
    let trajectory = build_trajectory(scene, &file.trajectory)?;
    let rate = file.loop_settings.control_rate_hz;
    let steps = trajectory.end_s() * rate;
    if steps > MAX_TRACK_STEPS as f64 {
        return Err(Error::invalid(
            "loop.control_rate_hz",
            rate,
            format!(
                "with the trajectory's {} s, {steps:.3e} control steps: at most {MAX_TRACK_STEPS} \
                 (an hour at the default 30 Hz; each step is a plant solve, an estimate and an \
                 inverse kinematics)",
                trajectory.end_s()
            ),
        ));
    }
    Ok(trajectory)
}

/// The most control steps a run of [`run_track`] takes (`control_rate_hz`
/// × the trajectory's end time): 3600 s at the default 30 Hz. At the
/// measured 0.13–0.45 ms per step that is under a minute; 3600 s at 10 kHz
/// (3.6e7 steps, hours) was accepted before.
pub const MAX_TRACK_STEPS: usize = 108_000;

/// Runs `file` on `scene` with `payloads` (replacing the plant's, if
/// given) and the controller `controller` (replacing the file's, if given).
///
/// # Errors
/// The checks of [`build_trajectory`] and of the settings, naming the
/// field as written (`loop.control_rate_hz`, `loop.gains.k_p_per_s`,
/// `plant.ei_factor`, `payloads[0].mass_kg`, …); [`Error::InvalidParameter`]
/// (field `markers`) for a scene without markers; the plant's and the
/// inverse kinematics' errors at the start (no equilibrium to start from).
/// After the start nothing is an error: an estimator failure, an inverse
/// kinematics without equilibrium and a plant whose equilibrium fails are
/// rows of the time series that say so (the last one ends the run, the
/// summary's `plant_failed_at_s`).
pub fn run_track(
    scene: &Scene,
    file: &TrackFile,
    payloads: Option<&PayloadSchedule>,
    controller: Option<ControllerKind>,
) -> Result<TrackRun> {
    let robot = scene.robot()?;
    let length = robot.length();
    let trajectory = check_track(scene, file, payloads)?;
    let payloads = payloads.unwrap_or(&file.plant.payloads).clone();
    let arcs: Vec<f64> = scene
        .markers
        .iter()
        .enumerate()
        .map(|(i, m)| match (m.node, m.s_m) {
            (Some(n), _) => robot
                .node_arc()
                .get(n)
                .copied()
                .ok_or_else(|| Error::invalid(format!("markers[{i}].node"), n, "no such node")),
            (None, Some(s)) => Ok(s),
            (None, None) => Err(Error::invalid(
                format!("markers[{i}]"),
                "{}",
                "give a node or s_m",
            )),
        })
        .collect::<Result<_>>()?;
    if arcs.is_empty() {
        return Err(Error::invalid(
            "markers",
            "[]",
            "the estimator of the loop needs the scene's markers",
        ));
    }
    let mut settings = file.loop_settings.clone();
    if let Some(c) = controller {
        settings.controller = c;
    }
    let plant_settings = PlantSettings {
        payloads: payloads.clone(),
        ..file.plant.clone()
    };
    let mut plant = SimulatedPlant::new(scene, &arcs, plant_settings.clone())?;
    let mut lp = ClosedLoop::new(robot, scene.loads()?, &arcs, settings.clone())?;
    let series = lp.run(&mut plant, &trajectory, |p| p.true_tip_m().ok())?;
    let score_from_s = file.score_from_s.unwrap_or(match &file.trajectory {
        TrajectorySpec::Samples(_) | TrajectorySpec::Pressures(_) => 2.7,
        t => t.hold_s().max(0.0),
    });
    let (mean_error_m, max_error_m) = series.mean_max_after(score_from_s);
    let mut steps: Vec<f64> = series.samples.iter().map(|s| s.step_time_s).collect();
    steps.sort_by(f64::total_cmp);
    let bounds = scene.robot()?.pressure_bounds();
    let samples = track_samples(&series, |t| payloads.mass_at(t, length));
    let summary = TrackSummary {
        controller: settings.controller,
        control_rate_hz: settings.control_rate_hz,
        samples: samples.len(),
        score_from_s,
        mean_error_m,
        max_error_m,
        median_step_time_s: steps.get(steps.len() / 2).copied().unwrap_or(0.0),
        ik_not_reached: samples.iter().filter(|s| !s.ik.is_reached()).count(),
        pressure_saturated: samples
            .iter()
            .filter(|s| {
                s.pressures_pa
                    .iter()
                    .zip(&bounds)
                    .any(|(p, (lo, hi))| (p - hi).abs() < 1e-9 * (hi - lo) && hi > lo && *p > *lo)
            })
            .count(),
        estimator_kept_last: samples
            .iter()
            .filter(|s| matches!(s.estimate, EstimateFlag::KeptLast { .. }))
            .count(),
        ik_failed: samples
            .iter()
            .filter(|s| matches!(s.status, StepStatus::IkFailed { .. }))
            .count(),
        plant_failed_at_s: series.plant_failed_at_s(),
        aborted_at_s: series
            .samples
            .last()
            .filter(|s| matches!(s.status, StepStatus::Aborted { .. }))
            .map(|s| s.time_s),
        plant: plant_settings,
    };
    Ok(TrackRun { summary, samples })
}

/// The rows of a run's time series as tracking samples: the true end
/// effector (the measured one where the plant gave none) and its distance
/// from the target, the hung mass `payload_kg(t)` on the plant, the loads'
/// resultants.
pub(crate) fn track_samples(
    series: &TimeSeries,
    payload_kg: impl Fn(f64) -> f64,
) -> Vec<TrackSample> {
    series
        .samples
        .iter()
        .map(|s| {
            let actual = s
                .true_tip_m
                .clone()
                .unwrap_or_else(|| s.measured_tip_m.clone());
            let error_m = actual
                .iter()
                .zip(&s.desired_m)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt();
            TrackSample {
                time_s: s.time_s,
                desired_m: s.desired_m.clone(),
                actual_m: actual,
                measured_m: s.measured_tip_m.clone(),
                error_m,
                payload_kg: payload_kg(s.time_s),
                estimated_load_n: s.f_hat_resultant_n.clone(),
                estimator_load_n: s.f_bar_resultant_n.clone(),
                pressures_pa: s.pressures_pa.clone(),
                step_time_s: s.step_time_s,
                ik: s.ik,
                estimate: s.estimate,
                status: s.status.clone(),
            }
        })
        .collect()
}
