//! Tracking a platform trajectory under an unknown hanging mass (Sec. IV
//! on the parallel robot): feedforward only versus feedforward with the
//! parameter updater (31).
//!
//! ```text
//! platform marker → estimator F̄ (32)–(35) → updater (31) F̂ → f_IK(x_d, F̂) → 18 pressures → plant
//! ```
//!
//! The pieces of [`crate::control`] and [`crate::estimate`] are used as
//! they are: the updater [`ParameterUpdater`], the one estimator
//! ([`NewtonEstimator`] on the robot's structure) and the one inverse
//! kinematics ([`InverseKinematics::for_model`] on it, the end effector at
//! the platform's centre, `F̂` a force there):
//!
//! - the load is the force `F ∈ R³` at the platform's centre (the payload
//!   model (32)–(35), [`LoadModel::AtSite`]): `F̄` is the force that puts
//!   the model's platform at the measured position under the commanded
//!   pressures (the estimate of one marker at the platform's site, `α` =
//!   [`PAYLOAD_ALPHA`]: three coordinates for three unknowns, an exact fit;
//!   the estimator's marker σ is the controller's tolerance, which sets
//!   only where its iteration stops: at a step of a tenth of it); an
//!   estimate that does not converge keeps the last good `F̄`
//!   ([`EstimateFlag::KeptLast`]);
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
//! chord solve with the kept factors of its tracker (the chord strategy of
//! [`crate::parallel::warm`], [`NewtonEstimator::with_corrector`]), which
//! is what makes a control step cost milliseconds instead of a cold
//! solve's 0.1 s.
//!
//! The plant is another [`ParallelRobot`]: finer mesh and the stiffness and
//! gain errors of [`crate::parallel::payload::plant_spec`], the mass hung from the
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

use nalgebra::Vector3;
use serde::Serialize;

use super::{
    ControllerKind, EstimateFlag, IkSettings, InverseKinematics, ParameterUpdater, Trajectory,
    UpdaterGains,
};
use crate::element::{Ancf3d, Element};
use crate::error::{Result, check_all_finite, check_len};
use crate::estimate::{
    Estimator, EstimatorSettings, LoadModel, NewtonEstimator, Observation, PAYLOAD_ALPHA,
};
use crate::observe::MarkerObservation;
use crate::parallel::warm::{WarmCounts, WarmStatics, chord_strategy};
use crate::parallel::{ParallelRobot, ParallelSpec};
use crate::rng::Gaussian;
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
/// The platform's centre: the end effector and where `F̂` acts.
const PLATFORM: Site = Site::Body { body: 0 };
/// Gauss–Newton iterations of the estimator per control instant, at most.
const ESTIMATOR_ITERATIONS: usize = 8;

mod settings;
pub use settings::{MAX_PARALLEL_TRACK_STEPS, TrackSettings};

/// The controller of one robot model: estimator, updater, inverse
/// kinematics, with their warm states (see the [module
/// documentation](self)).
#[derive(Debug, Clone)]
pub struct ParallelController<E: Element + 'static> {
    robot: ParallelRobot<E>,
    /// The inverse kinematics on the robot's structure (its warm tracker a
    /// chord strategy).
    ik: InverseKinematics<Structure<E>>,
    /// The estimator of the force at the platform's centre (its warm
    /// tracker a chord strategy), its known pressures the last command.
    estimator: NewtonEstimator<Structure<E>>,
    kind: ControllerKind,
    updater: ParameterUpdater,
    /// The last command.
    p: Vec<f64>,
    /// The estimator's last good force.
    f_bar: [f64; 3],
}

/// What a controller step did (written to JSON; the forces typed by
/// [`ControlStep::f_bar`] and [`ControlStep::f_hat`]).
///
/// # Example
/// ```
/// use nalgebra::Vector3;
/// use softrod::control::{EstimateFlag, parallel::ControlStep};
/// let s = ControlStep {
///     f_bar_n: [0.0, 0.0, -0.5],
///     f_hat_n: [0.0, 0.0, -0.4],
///     pressures_pa: vec![1e4; 9],
///     estimate: EstimateFlag::Converged,
///     ik_error_m: 1e-7,
///     ik_iterations: 2,
/// };
/// assert_eq!(s.f_bar(), Vector3::new(0.0, 0.0, -0.5));
/// assert_eq!(s.f_hat(), Vector3::new(0.0, 0.0, -0.4));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ControlStep {
    /// The estimator's force `F̄` (N; zeros for feedforward only).
    pub f_bar_n: [f64; 3],
    /// The updater's force `F̂` the feedforward used (N).
    pub f_hat_n: [f64; 3],
    /// The command (Pa).
    pub pressures_pa: Vec<f64>,
    /// What the estimator gave.
    pub estimate: EstimateFlag,
    /// Distance of the model's platform from the target at the command (m).
    pub ik_error_m: f64,
    /// Inverse-kinematics iterations.
    pub ik_iterations: usize,
}

impl ControlStep {
    /// The estimator's force `F̄` (N), typed.
    ///
    /// # Example
    /// ```
    /// use softrod::control::{EstimateFlag, parallel::ControlStep};
    /// let s = ControlStep { f_bar_n: [0.1, 0.0, -0.5], f_hat_n: [0.0; 3], pressures_pa: vec![], estimate: EstimateFlag::NotRun, ik_error_m: 0.0, ik_iterations: 0 };
    /// assert_eq!(s.f_bar().z, -0.5);
    /// ```
    pub fn f_bar(&self) -> Vector3<f64> {
        self.f_bar_n.into()
    }

    /// The updater's force `F̂` (N), typed.
    ///
    /// # Example
    /// ```
    /// use softrod::control::{EstimateFlag, parallel::ControlStep};
    /// let s = ControlStep { f_bar_n: [0.0; 3], f_hat_n: [0.1, 0.0, -0.4], pressures_pa: vec![], estimate: EstimateFlag::NotRun, ik_error_m: 0.0, ik_iterations: 0 };
    /// assert_eq!(s.f_hat().x, 0.1);
    /// ```
    pub fn f_hat(&self) -> Vector3<f64> {
        self.f_hat_n.into()
    }
}

impl<E: Element + 'static> ParallelController<E> {
    /// A controller of `model` starting at rest at the pressures `p0_pa`
    /// (and `F̂ = 0`), stepping every `dt_s`.
    ///
    /// # Errors
    /// As [`ParameterUpdater::new`], [`ParallelRobot::solve`] and
    /// [`InverseKinematics::for_model`] (a chamber whose bounds are
    /// equal); [`Error::DimensionMismatch`](crate::Error::DimensionMismatch) (`pressures_pa`) for a wrong
    /// count.
    pub fn new(
        model: ParallelRobot<E>,
        kind: ControllerKind,
        gains: UpdaterGains,
        dt_s: f64,
        p0_pa: &[f64],
        tolerance_m: f64,
    ) -> Result<Self> {
        let np = model.spec().n_pressures();
        check_len("pressures_pa", np, p0_pa.len())?;
        let settings = IkSettings {
            max_iterations: IK_ITERATIONS,
            tolerance_m,
            pressure_weight: MU,
            null_space_damping: LAMBDA,
            stop_when_reached: true,
            ..IkSettings::default()
        };
        let loads = model.loads(p0_pa, [0.0; 3], [0.0; 3])?;
        let mut ik = InverseKinematics::for_model(
            model.structure().clone(),
            loads.clone(),
            settings,
            PLATFORM,
            LoadModel::AtSite { site: PLATFORM },
        )?
        // the chord steps' answer without the residual there (the loop's old
        // warm solver's rule): each step at most half the last, the last
        // below 1.2e-11 m, bound the answer's distance from the equilibrium
        // by that step; the residual would cost 3 % more instructions per
        // tracking run (callgrind, 91 instants)
        .with_corrector(chord_strategy(model.spec(), false))?;
        let eq = model.solve(&loads, None)?;
        let tracker = ik.tracker_mut();
        tracker.set_loads(loads.clone())?;
        tracker.factor_at_free(eq.u.as_slice())?;
        let estimator = NewtonEstimator::new(
            model.structure(),
            &loads,
            &EstimatorSettings {
                load_model: LoadModel::AtSite { site: PLATFORM },
                alpha: Some(PAYLOAD_ALPHA),
                noise_sigma_m: tolerance_m,
                max_iterations: ESTIMATOR_ITERATIONS,
                ..EstimatorSettings::default()
            },
        )?
        .with_corrector(chord_strategy(model.spec(), true))?;
        Ok(ParallelController {
            robot: model,
            ik,
            estimator,
            kind,
            updater: ParameterUpdater::new(3, gains, dt_s)?,
            p: p0_pa.to_vec(),
            f_bar: [0.0; 3],
        })
    }

    /// The estimator: the force at the platform's centre that puts the
    /// model's platform at `measured` under the last command; the last good
    /// one kept when the estimate does not converge.
    fn estimate(&mut self, measured: [f64; 3]) -> Result<([f64; 3], EstimateFlag)> {
        let known = self.robot.loads(&self.p, [0.0; 3], [0.0; 3])?;
        self.estimator.set_known_loads(known)?;
        // the inverse kinematics factored last near this command: its
        // factors start the estimator's chord steps, and the estimator's
        // last ones the next inverse kinematics' (one tracker's factors, as
        // if the two shared it)
        self.estimator
            .tracker_mut()
            .keep_from(self.ik.tracker_mut());
        let observation = Observation {
            markers: vec![MarkerObservation::at_site(&PLATFORM, measured.to_vec())],
        };
        let flag = match self.estimator.step(&observation) {
            Ok(e) if e.report.status.is_converged() && e.f.iter().all(|v| v.is_finite()) => {
                self.f_bar = [e.f[0], e.f[1], e.f[2]];
                EstimateFlag::Converged
            }
            Ok(e) => EstimateFlag::KeptLast {
                status: Some(e.report.status),
            },
            Err(_) => EstimateFlag::KeptLast { status: None },
        };
        self.ik
            .tracker_mut()
            .keep_from(self.estimator.tracker_mut());
        Ok((self.f_bar, flag))
    }

    /// `f_IK(x_d, F̂)` warm from the last command, which it replaces;
    /// returns the remaining distance and the iterations.
    fn inverse_kinematics(&mut self, x_d: [f64; 3], f_hat: [f64; 3]) -> Result<(f64, usize)> {
        let sol = self.ik.solve(&x_d, &f_hat)?;
        self.p = sol.pressures_pa.data.into();
        Ok((sol.status.error_m(), sol.iterations))
    }

    /// What the controller's warm equilibria cost so far (the estimator's
    /// and the inverse kinematics').
    pub fn counts(&self) -> WarmCounts {
        self.ik.counts() + self.estimator.counts()
    }

    /// One control instant: the measured platform (m) in, the command for
    /// the next interval (towards `x_next`, the target at the next instant)
    /// out. The points are [`Vector3`]s (arrays convert).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`](crate::Error::InvalidParameter) for non-finite input; the errors of the
    /// static solves.
    pub fn step(
        &mut self,
        measured_m: impl Into<Vector3<f64>>,
        x_next_m: impl Into<Vector3<f64>>,
    ) -> Result<ControlStep> {
        let measured_m: [f64; 3] = measured_m.into().into();
        let x_next_m: [f64; 3] = x_next_m.into().into();
        check_all_finite("measured_m", &measured_m)?;
        check_all_finite("x_d", &x_next_m)?;
        let (f_bar, estimate, f_hat) = match self.kind {
            ControllerKind::Ff => ([0.0; 3], EstimateFlag::NotRun, [0.0; 3]),
            ControllerKind::FfUpdater => {
                let (f_bar, flag) = self.estimate(measured_m)?;
                let h = self.updater.step(&f_bar)?;
                (f_bar, flag, [h[0], h[1], h[2]])
            }
        };
        let (ik_error_m, ik_iterations) = self.inverse_kinematics(x_next_m, f_hat)?;
        Ok(ControlStep {
            f_bar_n: f_bar,
            f_hat_n: f_hat,
            pressures_pa: self.p.clone(),
            estimate,
            ik_error_m,
            ik_iterations,
        })
    }
}

/// One instant of a tracking run (written to JSON; the points typed by
/// [`TrackSample::desired`], [`TrackSample::actual`] and
/// [`TrackSample::measured`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrackSample {
    /// Time (s).
    pub time_s: f64,
    /// Desired platform position (m).
    pub desired_m: [f64; 3],
    /// The plant's platform (m).
    pub actual_m: [f64; 3],
    /// Its marker as measured (m).
    pub measured_m: [f64; 3],
    /// `|actual − desired|` (m).
    pub error_m: f64,
    /// What the controller did at this instant.
    pub control: ControlStep,
    /// Wall time of the controller's step (s).
    pub step_time_s: f64,
}

impl TrackSample {
    /// The desired platform position (m), typed.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector3;
    /// use softrod::control::{EstimateFlag, parallel::{ControlStep, TrackSample}};
    /// let control = ControlStep { f_bar_n: [0.0; 3], f_hat_n: [0.0; 3], pressures_pa: vec![], estimate: EstimateFlag::NotRun, ik_error_m: 0.0, ik_iterations: 0 };
    /// let s = TrackSample {
    ///     time_s: 0.1,
    ///     desired_m: [0.0, 0.01, 0.3],
    ///     actual_m: [0.0, 0.0, 0.3],
    ///     measured_m: [1e-5, 0.0, 0.3],
    ///     error_m: 0.01,
    ///     control,
    ///     step_time_s: 1e-3,
    /// };
    /// assert_eq!(s.desired(), Vector3::new(0.0, 0.01, 0.3));
    /// ```
    pub fn desired(&self) -> Vector3<f64> {
        self.desired_m.into()
    }

    /// The plant's platform position (m), typed.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector3;
    /// use softrod::control::{EstimateFlag, parallel::{ControlStep, TrackSample}};
    /// let control = ControlStep { f_bar_n: [0.0; 3], f_hat_n: [0.0; 3], pressures_pa: vec![], estimate: EstimateFlag::NotRun, ik_error_m: 0.0, ik_iterations: 0 };
    /// let s = TrackSample {
    ///     time_s: 0.1,
    ///     desired_m: [0.0, 0.01, 0.3],
    ///     actual_m: [0.0, 0.0, 0.3],
    ///     measured_m: [1e-5, 0.0, 0.3],
    ///     error_m: 0.01,
    ///     control,
    ///     step_time_s: 1e-3,
    /// };
    /// assert_eq!(s.actual(), Vector3::new(0.0, 0.0, 0.3));
    /// ```
    pub fn actual(&self) -> Vector3<f64> {
        self.actual_m.into()
    }

    /// The measured platform marker (m), typed.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector3;
    /// use softrod::control::{EstimateFlag, parallel::{ControlStep, TrackSample}};
    /// let control = ControlStep { f_bar_n: [0.0; 3], f_hat_n: [0.0; 3], pressures_pa: vec![], estimate: EstimateFlag::NotRun, ik_error_m: 0.0, ik_iterations: 0 };
    /// let s = TrackSample {
    ///     time_s: 0.1,
    ///     desired_m: [0.0, 0.01, 0.3],
    ///     actual_m: [0.0, 0.0, 0.3],
    ///     measured_m: [1e-5, 0.0, 0.3],
    ///     error_m: 0.01,
    ///     control,
    ///     step_time_s: 1e-3,
    /// };
    /// assert_eq!(s.measured(), Vector3::new(1e-5, 0.0, 0.3));
    /// ```
    pub fn measured(&self) -> Vector3<f64> {
        self.measured_m.into()
    }
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
    let x_at = |t: f64| -> [f64; 3] {
        let v = trajectory.at(t);
        [v[0], v[1], v[2]]
    };
    let mut ctl = ParallelController::new(
        model,
        settings.controller,
        settings.gains,
        dt,
        &p_c,
        settings.tolerance(),
    )?;
    // the first command: the start point without a load estimate
    let first = ctl.step_ff(x_at(0.0))?;
    let g = &plant.spec().gravity_m_per_s2;
    let weight = [0, 1, 2].map(|i| settings.payload_kg * g[i]);
    let plant_eq = plant.solve(&plant.loads(&first, weight, [0.0; 3])?, None)?;
    let mut plant_warm = WarmStatics::new(plant)?;
    let mut u_plant = plant_eq.u;
    let x0 = plant_warm.robot().platform_free_start()?;
    let mut noise = Gaussian::new(settings.seed);
    let n = (trajectory.end_s() / dt).floor() as usize + 1;
    let mut samples = Vec::with_capacity(n);
    for k in 0..n {
        let t = k as f64 * dt;
        let actual = [u_plant[x0], u_plant[x0 + 1], u_plant[x0 + 2]];
        let measured = actual.map(|v| v + settings.noise_sigma_m * noise.sample());
        let desired = x_at(t);
        let clock = std::time::Instant::now();
        let control = ctl.step(measured, x_at(t + dt))?;
        let step_time_s = clock.elapsed().as_secs_f64();
        let loads = plant_warm
            .robot()
            .loads(&control.pressures_pa, weight, [0.0; 3])?;
        u_plant = plant_warm.solve(&loads, u_plant.as_slice())?;
        let error_m = (0..3)
            .map(|i| (actual[i] - desired[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        samples.push(TrackSample {
            time_s: t,
            desired_m: desired,
            actual_m: actual,
            measured_m: measured,
            error_m,
            control,
            step_time_s,
        });
        on_sample(k + 1, n);
    }
    let mut summary = summarize(settings, &samples);
    summary.model_solves = ctl.counts();
    summary.plant_solves = plant_warm.counts();
    Ok(TrackRun { summary, samples })
}

impl<E: Element + 'static> ParallelController<E> {
    /// The feedforward command towards `x_d` with the updater's current
    /// `F̂`, without a new estimate (the first instant, before a frame).
    fn step_ff(&mut self, x_d: [f64; 3]) -> Result<Vec<f64>> {
        let e = self.updater.estimate();
        let f_hat = [e[0], e[1], e[2]];
        self.inverse_kinematics(x_d, f_hat)?;
        Ok(self.p.clone())
    }
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
            .filter(|s| s.control.ik_error_m > settings.ik_tolerance_m)
            .count(),
        payload_kg: settings.payload_kg,
        model_solves: WarmCounts::default(),
        plant_solves: WarmCounts::default(),
        max_step_time_s: times.last().copied().unwrap_or(0.0),
    }
}
