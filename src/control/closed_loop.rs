//! The closed loop of Fig. 6(b): at every control instant `t_k`
//!
//! 1. the plant's markers at `t_k` (the only thing read from it);
//! 2. the estimator's load `F̄` with the pressures commanded over the last
//!    interval (warm `α`); on an estimator failure the last good `F̄` is kept
//!    and the sample says so;
//! 3. the updater (31) moves `F̂` towards `F̄` (feedforward only: `F̂ = 0`);
//! 4. `f_IK(x_d(t_{k+1}), F̂)` gives the pressures for the next interval;
//! 5. the plant advances to `t_{k+1}` under them.
//!
//! Every instant is a row of the time series with its [`StepStatus`]: an
//! inverse kinematics that finds no equilibrium holds the last command and
//! the loop goes on; a plant whose own equilibrium fails ends the run with a
//! last row saying so (its state is then unknown). Neither is an error of
//! [`ClosedLoop::run`].

use std::time::Instant;

use nalgebra::{DVector, Dim, RawStorage, Vector};
use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::element::{Element, NodeKinematics};
use crate::error::{Error, Result, check_len};
use crate::estimate::{EstimateStatus, EstimationModel, EstimatorSettings, LoadModel};
use crate::loads::Loads;
use crate::plant::Plant;
use crate::site::Site;
use crate::statics::WarmStrategy;
use crate::structure::Actuated;

use super::{IkSettings, IkStatus, InverseKinematics, ParameterUpdater, Trajectory, adapter};
use super::{UpdaterGains, VirtualPayload};

/// The highest control rate accepted (Hz).
const MAX_RATE_HZ: f64 = 10_000.0;

/// Which controller runs.
///
/// # Example
/// ```
/// let c: softrod::control::ControllerKind = serde_json::from_str("\"ff_updater\"").unwrap();
/// assert_eq!(c, softrod::control::ControllerKind::FfUpdater);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ControllerKind {
    /// Feedforward only: `f_IK(x_d, 0)`, the model's own load only.
    Ff,
    /// Feedforward with the estimated load through the updater (31).
    #[default]
    FfUpdater,
}

/// Settings of the loop; every field has a documented default.
///
/// # Example
/// ```
/// let s = softrod::control::LoopSettings { control_rate_hz: 0.0, ..Default::default() };
/// assert_eq!(s.validate().unwrap_err().field(), Some("loop.control_rate_hz"));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct LoopSettings {
    /// Control rate (Hz, in (0, 10 000]; default 30, the paper's).
    pub control_rate_hz: f64,
    /// The controller (default feedforward + updater).
    pub controller: ControllerKind,
    /// Gains of the updater (31).
    pub gains: UpdaterGains,
    /// Inverse kinematics.
    pub ik: IkSettings,
    /// The estimator (its `alpha`, if unset, is chosen on the first frame
    /// and kept).
    pub estimator: EstimatorSettings,
    /// Watchdog: [`ClosedLoop::run`] stops with a row of status
    /// [`StepStatus::Aborted`] when the measured end effector is farther
    /// than this from its target (m, > 0; default `None`, never). A robot
    /// that far off is not being tracked, and every estimate from a frame
    /// that far from the model's prediction costs many fallback solves.
    #[serde(default)]
    pub abort_error_m: Option<f64>,
}

impl Default for LoopSettings {
    fn default() -> Self {
        LoopSettings {
            control_rate_hz: 30.0,
            controller: ControllerKind::FfUpdater,
            gains: UpdaterGains::default(),
            ik: IkSettings::default(),
            estimator: EstimatorSettings {
                noise_sigma_m: 5e-5,
                // not the crate's default (the evidence): measured on the
                // tracking table (3 paths x 5 payloads, `examples/track_fig6.rs`
                // `[evidence]`), the discrepancy rule keeps every mean error
                // after the hold at or below 0.3 mm (0.055-0.298 mm), the
                // evidence rule does not (0.065-0.329 mm: 0.306 and 0.329 mm
                // with the sliding mass); its smaller alpha follows the noise
                alpha_rule: crate::estimate::AlphaRule::Discrepancy,
                ..EstimatorSettings::default()
            },
            abort_error_m: None,
        }
    }
}

impl LoopSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field as written in a
    /// trajectory file (`loop.control_rate_hz`, `loop.gains.k_p_per_s`,
    /// `loop.ik.max_iterations`, `loop.estimator.…`).
    pub fn validate(&self) -> Result<()> {
        let r = self.control_rate_hz;
        if !(r.is_finite() && r > 0.0 && r <= MAX_RATE_HZ) {
            return Err(Error::invalid(
                "loop.control_rate_hz",
                r,
                format!("must be > 0 and at most {MAX_RATE_HZ} Hz"),
            ));
        }
        self.gains.validate_at("loop.gains.")?;
        if let Some(a) = self.abort_error_m
            && !(a.is_finite() && a > 0.0)
        {
            return Err(Error::invalid(
                "loop.abort_error_m",
                a,
                "must be finite and > 0",
            ));
        }
        self.ik.validate().map_err(|e| e.with_prefix("loop."))?;
        self.estimator
            .validate()
            .map_err(|e| e.with_prefix("loop."))
    }
}

/// What the estimator gave at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "estimate", rename_all = "snake_case")]
pub enum EstimateFlag {
    /// Not run (feedforward only).
    NotRun,
    /// A converged estimate was used.
    Converged,
    /// The estimator stopped short (its status) or failed: the last good
    /// estimate was kept.
    KeptLast {
        /// The estimator's status, `None` if it returned an error.
        status: Option<EstimateStatus>,
    },
}

/// How one control instant ended.
///
/// # Example
/// ```
/// use softrod::control::StepStatus;
/// assert!(StepStatus::Ok.is_ok());
/// let s = StepStatus::PlantFailed { message: "no equilibrium".into() };
/// assert_eq!(serde_json::to_string(&s)?, r#"{"plant_failed":{"message":"no equilibrium"}}"#);
/// # Ok::<(), serde_json::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StepStatus {
    /// Every part of the step ran.
    Ok,
    /// The inverse kinematics found no equilibrium: the last command is held
    /// and the loop goes on.
    IkFailed {
        /// The solver's error.
        message: String,
    },
    /// The plant's own equilibrium failed over the interval ending here: the
    /// run stops with this row (the tip shown is the plant's last good one).
    PlantFailed {
        /// The plant's error.
        message: String,
    },
    /// The watchdog ([`LoopSettings::abort_error_m`]) stopped the run: the
    /// measured end effector was this far from its target (m).
    Aborted {
        /// Distance of the measured end effector from the target (m).
        error_m: f64,
    },
}

impl StepStatus {
    /// Whether the step ran without a failure.
    pub fn is_ok(&self) -> bool {
        matches!(self, StepStatus::Ok)
    }

    /// Whether the row's tip is the plant's at that time (not after a
    /// plant failure).
    pub fn tip_known(&self) -> bool {
        !matches!(self, StepStatus::PlantFailed { .. })
    }

    /// Whether the row ended the run (plant failure or watchdog).
    pub fn ends_run(&self) -> bool {
        matches!(
            self,
            StepStatus::PlantFailed { .. } | StepStatus::Aborted { .. }
        )
    }
}

/// One instant of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoopSample {
    /// Time (s).
    pub time_s: f64,
    /// Desired end-effector position at this time (m).
    pub desired_m: Vec<f64>,
    /// The tip marker as measured (m).
    pub measured_tip_m: Vec<f64>,
    /// The true tip, if the caller's inspection supplied it (m).
    pub true_tip_m: Option<Vec<f64>>,
    /// The estimator's load `F̄` (the distributed field of (8), `n_q`
    /// entries; zeros when not run), after subtracting the virtual payload
    /// if one is set.
    pub f_bar: Vec<f64>,
    /// Resultant of `F̄` (N).
    pub f_bar_resultant_n: Vec<f64>,
    /// Resultant of the updater's load `F̂` used by the feedforward (N).
    pub f_hat_resultant_n: Vec<f64>,
    /// Pressures commanded for the next interval (Pa).
    pub pressures_pa: Vec<f64>,
    /// How the inverse kinematics ended.
    pub ik: IkStatus,
    /// What the estimator gave.
    pub estimate: EstimateFlag,
    /// Wall time of estimation + updater + inverse kinematics (s).
    pub step_time_s: f64,
    /// How the step ended.
    pub status: StepStatus,
}

impl LoopSample {
    /// [`LoopSample::desired_m`] as a vector (m).
    ///
    /// # Example
    /// ```
    /// use softrod::control::{EstimateFlag, IkStatus, LoopSample, StepStatus};
    /// let s = LoopSample {
    ///     time_s: 0.1, desired_m: vec![0.2, 0.05], measured_tip_m: vec![0.2, 0.049],
    ///     true_tip_m: Some(vec![0.2, 0.0495]), f_bar: vec![0.0; 12],
    ///     f_bar_resultant_n: vec![0.0, -0.1], f_hat_resultant_n: vec![0.0, -0.09],
    ///     pressures_pa: vec![1e4, 0.0, 0.0, 2e4], ik: IkStatus::NotSolved,
    ///     estimate: EstimateFlag::NotRun, step_time_s: 0.0, status: StepStatus::Ok,
    /// };
    /// assert_eq!(s.desired(), nalgebra::dvector![0.2, 0.05]);
    /// assert_eq!(s.measured_tip(), nalgebra::dvector![0.2, 0.049]);
    /// assert_eq!(s.true_tip(), Some(nalgebra::dvector![0.2, 0.0495]));
    /// assert_eq!(s.f_bar_resultant(), nalgebra::dvector![0.0, -0.1]);
    /// assert_eq!(s.f_hat_resultant(), nalgebra::dvector![0.0, -0.09]);
    /// assert_eq!(s.pressures()[3], 2e4);
    /// ```
    pub fn desired(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.desired_m)
    }

    /// [`LoopSample::measured_tip_m`] as a vector (m).
    ///
    /// # Example
    /// See [`LoopSample::desired`].
    pub fn measured_tip(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.measured_tip_m)
    }

    /// [`LoopSample::true_tip_m`] as a vector (m), if known.
    ///
    /// # Example
    /// See [`LoopSample::desired`].
    pub fn true_tip(&self) -> Option<DVector<f64>> {
        self.true_tip_m.as_deref().map(DVector::from_column_slice)
    }

    /// [`LoopSample::f_bar_resultant_n`] as a vector (N).
    ///
    /// # Example
    /// See [`LoopSample::desired`].
    pub fn f_bar_resultant(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.f_bar_resultant_n)
    }

    /// [`LoopSample::f_hat_resultant_n`] as a vector (N).
    ///
    /// # Example
    /// See [`LoopSample::desired`].
    pub fn f_hat_resultant(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.f_hat_resultant_n)
    }

    /// [`LoopSample::pressures_pa`] as a vector (Pa).
    ///
    /// # Example
    /// See [`LoopSample::desired`].
    pub fn pressures(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.pressures_pa)
    }
}

/// The samples of a run.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct TimeSeries {
    /// One per control instant.
    pub samples: Vec<LoopSample>,
}

impl TimeSeries {
    /// The time the plant failed and the run stopped (s), if it did.
    pub fn plant_failed_at_s(&self) -> Option<f64> {
        self.samples
            .last()
            .filter(|s| matches!(s.status, StepStatus::PlantFailed { .. }))
            .map(|s| s.time_s)
    }

    /// Tracking errors `|tip − x_d|` (m) from `from_s` on, of the true tip
    /// where known, else of the measured one; a row whose plant failed is
    /// left out (its tip is not known). One entry per row, in time order.
    ///
    /// # Example
    /// ```
    /// use softrod::control::TimeSeries;
    /// let ts = TimeSeries::default();
    /// assert_eq!(ts.errors_after(0.0).len(), 0);
    /// assert_eq!(ts.mean_max_after(0.0), (0.0, 0.0));
    /// ```
    pub fn errors_after(&self, from_s: f64) -> DVector<f64> {
        let e: Vec<f64> = self
            .samples
            .iter()
            .filter(|s| s.time_s >= from_s)
            .filter(|s| s.status.tip_known())
            .map(|s| {
                let tip = s.true_tip_m.as_ref().unwrap_or(&s.measured_tip_m);
                tip.iter()
                    .zip(&s.desired_m)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        DVector::from_vec(e)
    }

    /// Mean and maximum tracking error from `from_s` on (m); zeros if no sample.
    pub fn mean_max_after(&self, from_s: f64) -> (f64, f64) {
        let e = self.errors_after(from_s);
        if e.is_empty() {
            return (0.0, 0.0);
        }
        let mean = e.iter().sum::<f64>() / e.len() as f64;
        (mean, e.iter().fold(0.0f64, |m, v| m.max(*v)))
    }
}

/// A controller of one robot model (see the [module documentation](crate::control)).
///
/// # Example
/// Hold the two-section robot's tip at a point for 1 s at the default
/// 30 Hz (feedforward + updater) against a simulated plant that is not the
/// model ([`PlantSettings::default`](crate::plant::PlantSettings): EI
/// +15 %, chamber gain −10 %, a finer mesh, marker noise and lag) carrying
/// a 10 g tip mass the controller is not told about: the tip error peaks
/// near 6 mm and the updater takes it below 0.5 mm within 3 s. The plant's
/// true tip scores the run; the controller sees its markers only. (A
/// trajectory: `examples/track_fig6.rs`.)
/// ```
/// use softrod::control::{ClosedLoop, LoopSettings, Trajectory};
/// use softrod::plant::{PayloadSchedule, PlantSettings, SimulatedPlant};
/// use softrod::scene::Scene;
/// let scene = Scene::two_section();
/// let robot = scene.robot()?;
/// let arcs: Vec<f64> = scene.markers.iter().filter_map(|m| m.node).map(|n| robot.node_arc()[n]).collect();
/// let plant_settings = PlantSettings { payloads: PayloadSchedule::tip_mass(0.01, 0.24), ..PlantSettings::default() };
/// let mut plant = SimulatedPlant::new(&scene, &arcs, plant_settings)?;
/// let hold = Trajectory::new(&[0.0, 4.0], &[nalgebra::Vector2::new(0.21, 0.095); 2])?;
/// let mut lp = ClosedLoop::new(robot, scene.loads()?, &arcs, LoopSettings::default())?;
/// let ts = lp.run(&mut plant, &hold, |p| p.true_tip_m().ok())?;
/// assert_eq!(ts.samples.len(), 120);
/// assert!(ts.samples.iter().all(|s| s.ik.is_reached()));
/// // the payload pulls the tip 6 mm off before the updater has learnt it
/// let (_, peak_m) = ts.mean_max_after(0.5);
/// let (mean_m, _) = ts.mean_max_after(3.0); // over the last second
/// assert!(peak_m > 3e-3 && mean_m < 0.5e-3, "{peak_m} m, then {mean_m} m");
/// # Ok::<(), softrod::Error>(())
/// ```
///
/// A clone carries the whole state (updater, warm estimator, warm inverse
/// kinematics, last good estimate, last command): two clones fed the same
/// frames give the same commands.
#[derive(Debug, Clone)]
pub struct ClosedLoop<M: Actuated + EstimationModel> {
    model: M,
    known: M::Loads,
    /// Where the frames' markers are, in their order.
    markers: Vec<Site>,
    settings: LoopSettings,
    ik: InverseKinematics<M>,
    updater: ParameterUpdater,
    last_good: Option<Vec<f64>>,
    commanded_pa: Vec<f64>,
    virtual_payload: Option<VirtualPayload>,
    /// The estimator, built on the first frame and kept warm after (its
    /// known pressures replaced each step).
    estimator: Option<adapter::LoopEstimator<M>>,
    /// The warm strategy of the estimator's equilibria, when not its own
    /// ([`ClosedLoop::with_corrector`]): the estimator's and the inverse
    /// kinematics' trackers then hand their kept factors to each other.
    corrector: Option<WarmStrategy>,
}

impl<E: Element + 'static> ClosedLoop<Robot<E>> {
    /// A controller for the model `model` under the known loads `known`
    /// (its pressures are the command before the first step), observing
    /// markers at the arc coordinates `marker_s_m` (m; the last one should
    /// be the end effector's).
    ///
    /// # Errors
    /// As [`LoopSettings::validate`], [`InverseKinematics::new`];
    /// [`Error::InvalidParameter`] (field `markers`) for no markers.
    pub fn new(
        model: Robot<E>,
        known: Loads,
        marker_s_m: &[f64],
        settings: LoopSettings,
    ) -> Result<Self> {
        settings.validate()?;
        if marker_s_m.is_empty() {
            return Err(Error::invalid("markers", "[]", "the loop needs markers"));
        }
        for (i, &s) in marker_s_m.iter().enumerate() {
            model.locate(&format!("markers[{i}].s_m"), s)?;
        }
        let tip = Site::Rod {
            rod: 0,
            s_m: model.length(),
        };
        let markers: Vec<Site> = marker_s_m
            .iter()
            .map(|&s_m| Site::Rod { rod: 0, s_m })
            .collect();
        ClosedLoop::for_model(model, known, &markers, tip, settings)
    }
}

impl<M: Actuated + EstimationModel> ClosedLoop<M> {
    /// A controller for any model (a structure of rods and bodies: the
    /// parallel robot with the platform's centre for its end effector)
    /// under the known loads `known` (its pressures are the command before
    /// the first step), observing markers at the sites `markers` (a frame's
    /// positions in their order), moving the site `effector` along the
    /// trajectory; the estimator's load model
    /// ([`EstimatorSettings::load_model`]) is the load the inverse
    /// kinematics feeds forward.
    ///
    /// # Errors
    /// As [`LoopSettings::validate`] and [`InverseKinematics::for_model`];
    /// [`Error::InvalidParameter`] (field `markers`) for no markers or a
    /// site the model does not have (`markers[i]`).
    ///
    /// # Example
    /// The parallel robot's platform, observed by one marker at its centre:
    /// ```
    /// use softrod::control::{ClosedLoop, LoopSettings};
    /// use softrod::{estimate::LoadModel, site::Site};
    /// let mut spec = softrod::parallel::ParallelSpec::default();
    /// spec.elements_per_section = 1;
    /// let robot = spec.build_cable()?;
    /// let platform = Site::Body { body: 0 };
    /// let known = robot.loads(&vec![0.0; 18], [0.0; 3], [0.0; 3])?;
    /// let mut settings = LoopSettings::default();
    /// settings.estimator.load_model = LoadModel::AtSite { site: platform };
    /// let lp = ClosedLoop::for_model(robot.structure().clone(), known, &[platform], platform, settings)?;
    /// assert_eq!(lp.f_hat().len(), 3); // a force at the platform's centre
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn for_model(
        model: M,
        known: M::Loads,
        markers: &[Site],
        effector: Site,
        settings: LoopSettings,
    ) -> Result<Self> {
        settings.validate()?;
        if markers.is_empty() {
            return Err(Error::invalid("markers", "[]", "the loop needs markers"));
        }
        for (i, site) in markers.iter().enumerate() {
            model.site_rows(&format!("markers[{i}]"), site)?;
        }
        let ik = InverseKinematics::for_model(
            model.clone(),
            known.clone(),
            settings.ik.clone(),
            effector,
            settings.estimator.load_model,
        )?;
        let updater = ParameterUpdater::new(
            ik.n_load_params(),
            settings.gains,
            1.0 / settings.control_rate_hz,
        )?;
        let mut commanded_pa = model.pressures_of(&known);
        if commanded_pa.is_empty() {
            commanded_pa = vec![0.0; model.pressure_bounds().len()];
        }
        Ok(ClosedLoop {
            model,
            known,
            markers: markers.to_vec(),
            settings,
            ik,
            updater,
            last_good: None,
            commanded_pa,
            virtual_payload: None,
            estimator: None,
            corrector: None,
        })
    }

    /// The loop with another warm strategy for every equilibrium of its
    /// model, the inverse kinematics' and the estimator's (by default each
    /// its own: [`InverseKinematics::with_corrector`],
    /// [`crate::estimate::NewtonEstimator::with_corrector`]); the two
    /// trackers then hand their kept factors to each other, so one
    /// factorization serves both (a model whose tangent costs far more
    /// than its chord steps: the parallel robot's full 3-D legs).
    ///
    /// # Errors
    /// As [`WarmStrategy::validate`].
    pub fn with_corrector(mut self, strategy: WarmStrategy) -> Result<Self> {
        self.ik = self.ik.with_corrector(strategy)?;
        self.corrector = Some(strategy);
        Ok(self)
    }

    /// Subtracts `vp` (keyed by the desired end-effector position) from every
    /// estimate before the updater: the loop then feeds forward the real
    /// payload only.
    pub fn with_virtual_payload(mut self, vp: VirtualPayload) -> Self {
        self.virtual_payload = Some(vp);
        self
    }

    /// The settings (the estimator's `alpha` is set once chosen).
    pub fn settings(&self) -> &LoopSettings {
        &self.settings
    }

    /// The control interval (s).
    pub fn dt_s(&self) -> f64 {
        1.0 / self.settings.control_rate_hz
    }

    /// The updater's current `F̂`.
    pub fn f_hat(&self) -> &[f64] {
        self.updater.estimate()
    }

    /// Resultant `∫ w dX` of a distributed load field `f` on the model (N,
    /// `DIM` components; NaN for a field of the wrong length).
    ///
    /// # Example
    /// A uniform 1 N/m downwards on the 0.24 m robot:
    /// ```
    /// use softrod::control::{ClosedLoop, LoopSettings};
    /// use softrod::scene::Scene;
    /// let scene = Scene::two_section();
    /// let robot = scene.robot()?;
    /// let n = robot.n_q();
    /// let lp = ClosedLoop::new(robot, scene.loads()?, &[0.24], LoopSettings::default())?;
    /// // the field of (8) holding w = (0, -1) N/m at every node (value rows)
    /// let f: Vec<f64> = (0..n).map(|i| if i % 4 == 1 { -1.0 } else { 0.0 }).collect();
    /// let r = lp.resultant(&f);
    /// assert!(r[0].abs() < 1e-12 && (r[1] + 0.24).abs() < 1e-12, "{r}");
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn resultant(&self, f: &[f64]) -> DVector<f64> {
        let d = M::Element::DIM;
        let nan = || DVector::from_element(d, f64::NAN);
        match self.settings.estimator.load_model {
            LoadModel::Distributed => {
                let Some(Ok(g)) = self.model.field_rod().map(|r| r.apply_load_gram(f)) else {
                    return nan();
                };
                // the generalized force's position rows sum to ∫ w dX
                let nd = M::Element::NODE_DOFS;
                DVector::from_iterator(d, (0..d).map(|k| g.iter().skip(k).step_by(nd).sum()))
            }
            // a force at a site: its basis times the parameters
            site => match site.force_basis(d) {
                Ok(Some(b)) if b.ncols() == f.len() => b * DVector::from_column_slice(f),
                _ => nan(),
            },
        }
    }

    /// The estimator's `F̄` from the markers of `frame`; `(F̄, flag)` with
    /// the last good one kept on a failure (zeros before any).
    fn estimate(&mut self, frame: &crate::plant::MarkerFrame) -> (Vec<f64>, EstimateFlag) {
        let keep = |s: &Self, status| {
            let f = s
                .last_good
                .clone()
                .unwrap_or_else(|| vec![0.0; s.ik.n_load_params()]);
            (f, EstimateFlag::KeptLast { status })
        };
        let obs = match frame.observation_at(&self.markers) {
            Ok(o) => o,
            Err(_) => return keep(self, None),
        };
        // built once, then warm: only the commanded pressures change
        let ready = match self.estimator.as_mut() {
            Some(e) => e
                .as_dyn()
                .set_known_loads(self.model.with_pressures(&self.known, &self.commanded_pa)),
            None => adapter::estimator_at(
                &self.model,
                &self.known,
                &self.commanded_pa,
                &self.settings.estimator,
                self.corrector,
            )
            .map(|e| self.estimator = Some(e)),
        };
        // with one corrector for both, the inverse kinematics factored last
        // near this command: its factors start the estimator's chord steps
        if self.corrector.is_some()
            && let Some(e) = self.estimator.as_mut()
        {
            e.tracker_mut().keep_from(self.ik.tracker_mut());
        }
        let est = ready.and_then(|()| match self.estimator.as_mut() {
            Some(e) => {
                let e = e.as_dyn();
                let r = e.step(&obs);
                if self.settings.estimator.alpha.is_none() {
                    self.settings.estimator.alpha = e.alpha();
                }
                r
            }
            None => Err(Error::invalid("estimator", "none", "not built")),
        });
        // and the estimator's last factors the next inverse kinematics'
        if self.corrector.is_some()
            && let Some(e) = self.estimator.as_mut()
        {
            self.ik.tracker_mut().keep_from(e.tracker_mut());
        }
        match est {
            Ok(e) if e.report.status.is_converged() && e.f.iter().all(|v| v.is_finite()) => {
                self.last_good = Some(e.f.as_slice().to_vec());
                (e.f.as_slice().to_vec(), EstimateFlag::Converged)
            }
            Ok(e) => keep(self, Some(e.report.status)),
            Err(_) => keep(self, None),
        }
    }

    /// One control instant: the markers `frame` (taken at the time whose
    /// desired position is `x_now`) in, the pressures for the interval
    /// ending at `x_next` out (in the sample, and kept as the command the
    /// next estimate assumes). The caller sends them to the plant.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for targets of the wrong dimension and
    /// [`Error::InvalidParameter`] for non-finite ones. An estimator failure
    /// is not an error (the sample's `estimate` says so), nor is an inverse
    /// kinematics that finds no equilibrium (the last command is held, the
    /// sample's `status` is [`StepStatus::IkFailed`]).
    pub fn control_step(
        &mut self,
        frame: &crate::plant::MarkerFrame,
        x_now: &[f64],
        x_next: &[f64],
    ) -> Result<LoopSample> {
        check_len("x_d", M::Element::DIM, x_now.len())?;
        check_len("x_d", M::Element::DIM, x_next.len())?;
        crate::error::check_all_finite("x_d", x_now)?;
        crate::error::check_all_finite("x_d", x_next)?;
        let start = Instant::now();
        let zeros = vec![0.0; self.ik.n_load_params()];
        let (f_bar, flag, f_hat) = match self.settings.controller {
            ControllerKind::Ff => (zeros.clone(), EstimateFlag::NotRun, zeros),
            ControllerKind::FfUpdater => {
                let (mut f_bar, flag) = self.estimate(frame);
                if let Some(vp) = &self.virtual_payload
                    && let Ok(f) = vp.subtract(x_now, &f_bar)
                {
                    f_bar = f.data.into();
                }
                let f_hat = self.updater.step(&f_bar)?.to_vec();
                (f_bar, flag, f_hat)
            }
        };
        let (pressures_pa, ik, status) = match self.ik.solve(x_next, &f_hat) {
            Ok(sol) => (sol.pressures_pa.data.into(), sol.status, StepStatus::Ok),
            Err(e) => (
                self.commanded_pa.clone(),
                IkStatus::NotSolved,
                StepStatus::IkFailed {
                    message: e.to_string(),
                },
            ),
        };
        let step_time_s = start.elapsed().as_secs_f64();
        self.commanded_pa.clone_from(&pressures_pa);
        Ok(LoopSample {
            time_s: frame.time_s,
            desired_m: x_now.to_vec(),
            measured_tip_m: frame.positions_m.last().cloned().unwrap_or_default(),
            true_tip_m: None,
            f_bar_resultant_n: self.resultant(&f_bar).data.into(),
            f_bar,
            f_hat_resultant_n: self.resultant(&f_hat).data.into(),
            pressures_pa,
            ik,
            estimate: flag,
            step_time_s,
            status,
        })
    }

    /// What the loop's static solves cost so far: the inverse
    /// kinematics' and the estimator's.
    ///
    /// # Example
    /// See [`crate::control::parallel::run_track`].
    pub fn counts(&self) -> crate::statics::WarmCounts {
        let est = self
            .estimator
            .as_ref()
            .map(adapter::LoopEstimator::counts)
            .unwrap_or_default();
        self.ik.counts() + est
    }

    /// The pressures last commanded (Pa).
    pub fn commanded_pa(&self) -> &[f64] {
        &self.commanded_pa
    }

    /// Runs the loop on `plant` along `trajectory`, from its start to its
    /// end at the control rate; `inspect` is called on the plant after
    /// every frame and may return the true tip for scoring (any nalgebra
    /// vector of the robot's dimension, e.g. [`SimulatedPlant::true_tip_m`](crate::plant::SimulatedPlant::true_tip_m)'s
    /// `Vector2`; it must not feed the controller).
    ///
    /// A plant failure over an interval ends the run with a last row of
    /// status [`StepStatus::PlantFailed`]; an inverse kinematics that finds
    /// no equilibrium is a row of status [`StepStatus::IkFailed`] (the last
    /// command held) and the run goes on. The run takes a fixed number of
    /// steps, each of bounded iterations: it cannot hang.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for an invalid trajectory (naming its
    /// field), one of another dimension than the robot, or one shorter than
    /// one control interval (`trajectory.times_s`); the plant's refusal of
    /// the first command (pressures outside its bounds); the inverse
    /// kinematics' errors at the start point (no equilibrium to start from).
    pub fn run<P: Plant, D: Dim, S: RawStorage<f64, D>>(
        &mut self,
        plant: &mut P,
        trajectory: &Trajectory,
        mut inspect: impl FnMut(&P) -> Option<Vector<f64, D, S>>,
    ) -> Result<TimeSeries> {
        let mut inspect = |p: &P| inspect(p).map(|v| v.iter().copied().collect::<Vec<f64>>());
        trajectory.validate()?;
        check_len("trajectory.points_m[0]", M::Element::DIM, trajectory.dim())?;
        check_len(
            "plant pressures",
            self.model.pressure_bounds().len(),
            plant.n_pressures(),
        )?;
        let dt = self.dt_s();
        let t0 = trajectory.times_s[0];
        let n = ((trajectory.end_s() - t0) / dt).floor().min(1e7) as usize;
        if n == 0 {
            return Err(Error::invalid(
                "trajectory.times_s",
                format!("[{t0}, {}]", trajectory.end_s()),
                format!(
                    "the trajectory lasts {} s, less than one control interval ({dt} s at {} Hz)",
                    trajectory.end_s() - t0,
                    self.settings.control_rate_hz
                ),
            ));
        }
        let zeros = vec![0.0; self.ik.n_load_params()];
        // the first command: the start point, nothing estimated yet
        let first = self.ik.solve(trajectory.at(t0).as_slice(), &zeros)?;
        self.commanded_pa = first.pressures_pa.data.into();
        plant.command(&self.commanded_pa)?;
        let mut series = TimeSeries::default();
        let mut last_tip_m: Vec<f64> = Vec::new();
        for k in 1..=n {
            let t = t0 + k as f64 * dt;
            let frame = match plant.advance(dt) {
                Ok(f) => f,
                Err(e) => {
                    let zeros_d = vec![0.0; M::Element::DIM];
                    let last = series.samples.last();
                    series.samples.push(LoopSample {
                        time_s: t,
                        desired_m: trajectory.at(t).data.into(),
                        measured_tip_m: last_tip_m.clone(),
                        true_tip_m: inspect(plant),
                        f_bar: zeros.clone(),
                        f_bar_resultant_n: last
                            .map_or(zeros_d.clone(), |s| s.f_bar_resultant_n.clone()),
                        f_hat_resultant_n: last.map_or(zeros_d, |s| s.f_hat_resultant_n.clone()),
                        pressures_pa: self.commanded_pa.clone(),
                        ik: IkStatus::NotSolved,
                        estimate: EstimateFlag::NotRun,
                        step_time_s: 0.0,
                        status: StepStatus::PlantFailed {
                            message: e.to_string(),
                        },
                    });
                    break;
                }
            };
            let true_tip_m = inspect(plant);
            if let (Some(limit), Some(tip)) =
                (self.settings.abort_error_m, frame.positions_m.last())
            {
                let x = trajectory.at(t);
                let e = tip
                    .iter()
                    .zip(&x)
                    .map(|(a, b)| (a - b).powi(2))
                    .sum::<f64>()
                    .sqrt();
                // A NaN distance aborts the run too.
                if e.is_nan() || e > limit {
                    let zeros_d = vec![0.0; M::Element::DIM];
                    let last = series.samples.last();
                    series.samples.push(LoopSample {
                        time_s: t,
                        desired_m: x.data.into(),
                        measured_tip_m: tip.clone(),
                        true_tip_m,
                        f_bar: zeros.clone(),
                        f_bar_resultant_n: last
                            .map_or(zeros_d.clone(), |s| s.f_bar_resultant_n.clone()),
                        f_hat_resultant_n: last.map_or(zeros_d, |s| s.f_hat_resultant_n.clone()),
                        pressures_pa: self.commanded_pa.clone(),
                        ik: IkStatus::NotSolved,
                        estimate: EstimateFlag::NotRun,
                        step_time_s: 0.0,
                        status: StepStatus::Aborted { error_m: e },
                    });
                    break;
                }
            }
            let mut sample = self.control_step(
                &frame,
                trajectory.at(t).as_slice(),
                trajectory.at(t + dt).as_slice(),
            )?;
            sample.time_s = t;
            sample.true_tip_m = true_tip_m;
            last_tip_m.clone_from(&sample.measured_tip_m);
            plant.command(&self.commanded_pa)?;
            series.samples.push(sample);
        }
        Ok(series)
    }
}
