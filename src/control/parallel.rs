//! Tracking a platform trajectory under an unknown hanging mass (Sec. IV
//! on the parallel robot): feedforward only versus feedforward with the
//! parameter updater (31).
//!
//! ```text
//! platform marker → estimator F̄ (32)–(35) → updater (31) F̂ → f_IK(x_d, F̂) → 18 pressures → plant
//! ```
//!
//! The loop is the planar robot's, [`ClosedLoop::for_model`] on the robot's
//! structure ([`controller`]), its plant a [`ParallelPlant`]: the updater
//! [`ParameterUpdater`](super::ParameterUpdater), the one estimator ([`NewtonEstimator`](crate::estimate::NewtonEstimator)) and the
//! one inverse kinematics ([`InverseKinematics::for_model`](super::InverseKinematics::for_model)), the end
//! effector and the one marker at the platform's centre, `F̂` a force
//! there; its samples are the planar robot's tracking records
//! ([`super::track::TrackSample`]):
//!
//! - the load is the force `F ∈ R³` at the platform's centre (the payload
//!   model (32)–(35), [`LoadModel::AtSite`]): `F̄` is the force that puts
//!   the model's platform at the measured position under the commanded
//!   pressures (the estimate of one marker at the platform's site, `α` =
//!   [`PAYLOAD_ALPHA`]: three coordinates for three unknowns, an exact fit;
//!   the estimator's marker σ is the controller's tolerance, which sets
//!   only where its iteration stops: at a step of a tenth of it); an
//!   estimate that does not converge keeps the last good `F̄`
//!   ([`EstimateFlag::KeptLast`](super::EstimateFlag::KeptLast));
//! - `f_IK(x_d, F̂)`: the pressures (within their bounds) putting the
//!   model's platform at `x_d` under `F̂`, by the inverse kinematics'
//!   Gauss–Newton on the pressures scaled by their range with the Jacobian
//!   `J = ∂x/∂P` (43), the redundancy (18 pressures, 3 coordinates)
//!   resolved towards the least `Σ (P/range)²` with the weight
//!   `μ = 10⁻⁴` ([`IkSettings::pressure_weight`]), each step the exact box
//!   QP with a damping `λ = 10⁻²` of the step
//!   ([`IkSettings::null_space_damping`]): in the null space of `J` a step
//!   moves 1 % of the way to the least pressures (a full null-space move
//!   changes the pressures by tens of kPa, whose nonlinearity the next
//!   iterations must undo: measured, 10–20 iterations per instant instead
//!   of 1–3), in the range of `J` it is Gauss–Newton's;
//! - feedforward only: `F̂ = 0` (the model's own weights only).
//!
//! Every equilibrium, the estimator's and the inverse kinematics', is a warm
//! chord solve with kept factors, which the two trackers hand to each other
//! (the chord strategy of [`crate::parallel::warm`],
//! [`ClosedLoop::with_corrector`]), which is what makes a control step cost
//! milliseconds instead of a cold solve's 0.1 s.
//!
//! The plant is another [`ParallelRobot`] ([`ParallelPlant`]): finer mesh
//! and the stiffness and gain errors of
//! [`crate::parallel::payload::plant_spec`], the mass hung from the
//! platform's centre, solved statically at every control instant (a
//! quasi-static plant: the platform is taken to settle within a control
//! interval; the robot's dynamics are not modelled here), its marker read
//! with Gaussian noise of σ per coordinate, one frame per instant.
//!
//! With model error the estimator's `F̄` is not the payload alone (the
//! virtual payload of [`crate::control::VirtualPayload`]); for tracking
//! that does not matter: at a steady state `F̂ = F̄`, the model puts the
//! platform at `x_d` under `F̂` (inverse kinematics) and at the measurement
//! under `F̄` (estimator), so the measured platform is at `x_d`: the
//! updater acts as an integral action on the position through the model.

use serde::Serialize;

use super::track::{TrackSample, track_samples};
use super::{ClosedLoop, ControllerKind, IkSettings, LoopSettings, Trajectory};
use crate::element::{Ancf3d, Element};
use crate::error::{Result, check_all_finite, check_len};
use crate::estimate::{EstimatorSettings, LoadModel, PAYLOAD_ALPHA};
use crate::parallel::warm::{WarmCounts, chord_strategy};
use crate::parallel::{ParallelRobot, ParallelSpec};
use crate::plant::ParallelPlant;
use crate::site::Site;
use crate::structure::Structure;

/// Weight of the scaled pressures' norm against the position error
/// ([`IkSettings::pressure_weight`]).
const MU: f64 = 1e-4;
/// Damping of the pressure step ([`IkSettings::null_space_damping`]): a
/// step changes the pressures little in the null space of `J` (the pull
/// towards the least pressures is `μ/(μ + λ)` = 1 % of the way per
/// iteration), fully in its range.
const LAMBDA: f64 = 1e-2;
/// Inverse-kinematics iterations per control instant, at most.
const IK_ITERATIONS: usize = 20;
/// The platform's centre: the end effector, the marker and where `F̂` acts.
const PLATFORM: Site = Site::Body { body: 0 };
/// Gauss–Newton iterations of the estimator per control instant, at most.
const ESTIMATOR_ITERATIONS: usize = 8;

mod settings;
pub use settings::{MAX_PARALLEL_TRACK_STEPS, TrackSettings};

/// The controller of one robot model (see the [module
/// documentation](self)): the closed loop on its structure at the start
/// pressures `p0_pa` (and `F̂ = 0`), the rate, controller, gains and
/// inverse kinematics' tolerance of `settings`.
///
/// # Errors
/// As [`ClosedLoop::for_model`] and [`ParallelRobot::loads`];
/// [`crate::Error::DimensionMismatch`] (`pressures_pa`) for a wrong count.
///
/// # Example
/// ```
/// use softrod::control::parallel::{TrackSettings, centre_pressures, controller};
/// use softrod::plant::{ParallelPlant, Plant};
/// let mut spec = softrod::parallel::ParallelSpec::default();
/// spec.elements_per_section = 1;
/// let p = centre_pressures(&spec);
/// let mut lp = controller(spec.build_full()?, &TrackSettings::default(), p.as_slice())?;
/// let mut plant = ParallelPlant::new(spec.build_full()?, 0.05, 0.0, 1)?;
/// plant.command(p.as_slice())?;
/// let frame = plant.advance(0.1)?;
/// let x = frame.positions_m[0].clone();
/// let s = lp.control_step(&frame, &x, &x)?;
/// assert!(s.ik.is_reached() && s.f_bar_resultant_n[2] < 0.0); // the payload's weight
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn controller<E: Element + 'static>(
    model: ParallelRobot<E>,
    settings: &TrackSettings,
    p0_pa: &[f64],
) -> Result<ClosedLoop<Structure<E>>> {
    check_len("pressures_pa", model.spec().n_pressures(), p0_pa.len())?;
    let tolerance_m = settings.tolerance();
    let known = model.loads(p0_pa, [0.0; 3], [0.0; 3])?;
    let loop_settings = LoopSettings {
        control_rate_hz: settings.control_rate_hz,
        controller: settings.controller,
        gains: settings.gains,
        ik: IkSettings {
            max_iterations: IK_ITERATIONS,
            tolerance_m,
            pressure_weight: MU,
            null_space_damping: LAMBDA,
            stop_when_reached: true,
            ..IkSettings::default()
        },
        estimator: EstimatorSettings {
            load_model: LoadModel::AtSite { site: PLATFORM },
            alpha: Some(PAYLOAD_ALPHA),
            noise_sigma_m: tolerance_m,
            max_iterations: ESTIMATOR_ITERATIONS,
            ..EstimatorSettings::default()
        },
        abort_error_m: None,
    };
    // the chord steps' answer without the residual there: each step at most
    // half the last, the last below 1.2e-11 m, bound the answer's distance
    // from the equilibrium by that step; the residual would cost about 5 %
    // more per control instant (criterion, `parallel/track_step`)
    let chord = chord_strategy(model.spec(), false);
    ClosedLoop::for_model(
        model.structure().clone(),
        known,
        &[PLATFORM],
        PLATFORM,
        loop_settings,
    )?
    .with_corrector(chord)
}

/// The summary of a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackSummary {
    /// Which controller ran.
    pub controller: ControllerKind,
    /// Samples in all.
    pub samples: usize,
    /// Errors are scored from this time on (s).
    pub score_from_s: f64,
    /// Mean tracking error from then on (m).
    pub mean_error_m: f64,
    /// Largest tracking error from then on (m).
    pub max_error_m: f64,
    /// Median wall time of a controller step (s).
    pub median_step_time_s: f64,
    /// Instants whose inverse kinematics ended farther than its tolerance.
    pub ik_not_reached: usize,
    /// The hung mass (kg).
    pub payload_kg: f64,
    /// The static solves of the controller's model and what they cost.
    pub model_solves: WarmCounts,
    /// The plant's static solves.
    pub plant_solves: WarmCounts,
    /// The longest controller step (s).
    pub max_step_time_s: f64,
}

/// A tracking run: its summary and samples.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackRun {
    /// The summary.
    pub summary: TrackSummary,
    /// One per control instant.
    pub samples: Vec<TrackSample>,
}

/// The trajectory of a run: a horizontal circle of `settings.radius_m`
/// about the model's platform under the centre pressures, starting from
/// rest after the hold (the built-in circle's smooth start).
///
/// # Errors
/// As [`Trajectory::new`].
fn circle(centre: [f64; 3], s: &TrackSettings) -> Result<Trajectory> {
    let planar = Trajectory::circle(
        nalgebra::Vector2::new(centre[0], centre[1]),
        s.radius_m,
        s.period_s,
        s.duration_s,
        s.hold_s,
    )?;
    let points = planar
        .points_m
        .iter()
        .map(|p| vec![p[0], p[1], centre[2]])
        .collect();
    Trajectory::from_rows(planar.times_s.clone(), points)
}

/// The centre pressures of a run: chamber 0 of every leg's first section
/// at 40 kPa (the second configuration of the Fig. 8 experiment): the
/// legs bent, the pressures inside their bounds.
///
/// # Example
/// ```
/// let spec = softrod::parallel::ParallelSpec::default();
/// let p = softrod::control::parallel::centre_pressures(&spec);
/// assert_eq!((p[0], p.len()), (40e3, spec.n_pressures()));
/// ```
pub fn centre_pressures(spec: &ParallelSpec) -> nalgebra::DVector<f64> {
    crate::parallel::payload::fig8_configurations(spec)
        .get(1)
        .cloned()
        .unwrap_or_else(|| nalgebra::DVector::zeros(0))
}

/// Tracks the circle of `settings` with the robot of `spec` as the
/// controller's model (at `settings.model_elements_per_section`) against the
/// plant [`crate::parallel::payload::plant_spec`] of it carrying
/// `settings.payload_kg`, legs of the full 3-D element in both. The circle
/// is about the model's platform at the pressures `centre_pa` (Pa; empty:
/// [`centre_pressures`]), where the first command starts.
///
/// # Errors
/// As [`TrackSettings::validate`] and [`ParallelSpec::validate`];
/// [`Error::DimensionMismatch`](crate::Error::DimensionMismatch) (`pressures_pa`) for a wrong count; the
/// static solves' errors.
///
/// # Example
/// See `tests/parallel_track.rs` and `examples/parallel_track.rs`.
pub fn run_track(
    spec: &ParallelSpec,
    centre_pa: &[f64],
    settings: &TrackSettings,
) -> Result<TrackRun> {
    run_track_observed(spec, centre_pa, settings, &mut |_, _| {})
}

/// [`run_track`], calling `on_sample(done, total)` after each control
/// instant (a progress bar: `total` is the run's number of instants).
///
/// # Errors
/// As [`run_track`].
///
/// # Example
/// ```no_run
/// use softrod::control::parallel::{run_track_observed, TrackSettings};
/// let spec = softrod::parallel::ParallelSpec::default();
/// let mut last = 0;
/// let run = run_track_observed(&spec, &[], &TrackSettings::default(), &mut |done, _| last = done)?;
/// assert_eq!(last, run.samples.len());
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn run_track_observed(
    spec: &ParallelSpec,
    centre_pa: &[f64],
    settings: &TrackSettings,
    on_sample: &mut dyn FnMut(usize, usize),
) -> Result<TrackRun> {
    settings.validate()?;
    spec.validate()?;
    let mut model_spec = spec.clone();
    model_spec.elements_per_section = settings.model_elements_per_section;
    let model: ParallelRobot<Ancf3d> = model_spec.build_full()?;
    let plant = crate::parallel::payload::plant_spec(spec).build_full()?;
    let dt = 1.0 / settings.control_rate_hz;
    let p_c = if centre_pa.is_empty() {
        centre_pressures(spec).data.into()
    } else {
        check_len("pressures_pa", spec.n_pressures(), centre_pa.len())?;
        check_all_finite("pressures_pa", centre_pa)?;
        centre_pa.to_vec()
    };
    let centre_eq = model.solve(&model.loads(&p_c, [0.0; 3], [0.0; 3])?, None)?;
    let c = model.platform_pose(centre_eq.q.as_slice())?;
    let trajectory = circle([c[0], c[1], c[2]], settings)?;
    let mut lp = controller(model, settings, &p_c)?;
    let mut plant = ParallelPlant::new(
        plant,
        settings.payload_kg,
        settings.noise_sigma_m,
        settings.seed,
    )?;
    let t0 = trajectory.times_s.first().copied().unwrap_or(0.0);
    let n = ((trajectory.end_s() - t0) / dt).floor() as usize;
    let mut done = 0;
    let series = lp.run(&mut plant, &trajectory, |p: &ParallelPlant<Ancf3d>| {
        done += 1;
        on_sample(done, n);
        p.true_platform_m()
    })?;
    let samples = track_samples(&series, |_| settings.payload_kg);
    let mut summary = summarize(settings, &samples);
    summary.model_solves = lp.counts();
    summary.plant_solves = plant.counts();
    Ok(TrackRun { summary, samples })
}

fn summarize(settings: &TrackSettings, samples: &[TrackSample]) -> TrackSummary {
    let scored: Vec<f64> = samples
        .iter()
        .filter(|s| s.time_s >= settings.score_from_s)
        .map(|s| s.error_m)
        .collect();
    let mean = if scored.is_empty() {
        0.0
    } else {
        scored.iter().sum::<f64>() / scored.len() as f64
    };
    let mut times: Vec<f64> = samples.iter().map(|s| s.step_time_s).collect();
    times.sort_by(f64::total_cmp);
    TrackSummary {
        controller: settings.controller,
        samples: samples.len(),
        score_from_s: settings.score_from_s,
        mean_error_m: mean,
        max_error_m: scored.iter().fold(0.0, |m: f64, v| m.max(*v)),
        median_step_time_s: times.get(times.len() / 2).copied().unwrap_or(0.0),
        ik_not_reached: samples
            .iter()
            .filter(|s| s.ik.error_m() > settings.ik_tolerance_m)
            .count(),
        payload_kg: settings.payload_kg,
        model_solves: WarmCounts::default(),
        plant_solves: WarmCounts::default(),
        max_step_time_s: times.last().copied().unwrap_or(0.0),
    }
}
