//! Obstacle avoidance by touch (the paper's Sec. V, Fig. 9): the robot
//! descends the potential field (36)–(44) towards a goal; an obstacle it
//! was not told about stops it; the contact is localized from the markers
//! ([`locate_point_force`]) and its point joins the repulsive field, and
//! the robot goes around it to the goal.
//!
//! At every control instant (20 Hz by default):
//!
//! 1. the plant's (noisy) markers;
//! 2. the shape `q̂` and load `F̂` by the estimator on the calibrated model
//!    with the commanded pressures (the feedback of every position below);
//! 3. with touch feedback: the point-force search on the same markers; a
//!    force that explains them far better than none (the drop of the
//!    misfit over the assumed noise, `Δχ²`, above a threshold, and at least
//!    `min_force_n`), found at three successive instants within 2 cm,
//!    localizes a contact; the obstacle's point `x_obs` is the rod's surface
//!    there, `r̂(ŝ) − ρ f̂/|f̂|` (the force on the rod points away from the
//!    obstacle), and joins the repulsive field (replacing a known point
//!    within 2 cm);
//! 4. `∂U_t/∂P = ∂U_t/∂q ∂q/∂P` (41), (43) at `(q̂, F̂)`; a pressure at its
//!    bound whose step would cross it is frozen; `β` from (44) so the end
//!    effector moves at `v_d`; `P ← P − β ∂U_t/∂P Δt` (40).
//!
//! Without touch feedback (the baseline) step 3 is skipped: the field has
//! no repulsion and the robot pushes into the obstacle.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::contact::Obstacles;
use crate::control::{IkSettings, IkStatus, InverseKinematics};
use crate::element::PlanarCable;
use crate::error::{Error, Result, check_len, check_positive};
use crate::estimate::{AlphaRule, Estimator, EstimatorSettings};
use crate::loads::Loads;
use crate::plant::{Plant, PlantSettings, SimulatedPlant};
use crate::scene::Scene;

use super::response::dq_dp;
use super::{
    Calibration, FieldParams, FreeFrame, PointSearchSettings, calibrate, field_gradient,
    locate_point_force,
};

/// Settings of an avoidance run; every field has a documented default.
///
/// # Example
/// ```
/// let s = softrod::touch::AvoidSettings::default();
/// assert_eq!((s.control_rate_hz, s.touch_feedback), (20.0, true));
/// s.validate()?;
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct AvoidSettings {
    /// The field's parameters (the paper's by default).
    pub field: FieldParams,
    /// Control rate (Hz, default 20, the paper's).
    pub control_rate_hz: f64,
    /// Length of the run (s, default 60).
    pub duration_s: f64,
    /// Whether contacts are localized and added to the field (default
    /// true; false: the baseline).
    pub touch_feedback: bool,
    /// Drop of the markers' misfit over the noise, `Δχ²`, that counts as a
    /// contact (default 200).
    pub detection_chi2: f64,
    /// Smallest force that counts as a contact (N, default 0.005).
    pub min_force_n: f64,
    /// The goal counts as reached within this distance (m, default 0.002).
    pub goal_tolerance_m: f64,
    /// Marker noise the controller assumes (m, default 5e-5).
    pub noise_sigma_m: f64,
    /// Elements per section of the controller's model (default 4).
    pub model_elements: usize,
    /// Shapes kept for the figure every this many seconds (default 1).
    pub shape_interval_s: f64,
    /// How the estimator chooses its regularization `α` (default
    /// [`ALPHA_RULE`](super::ALPHA_RULE), the touch default, with its
    /// reason there).
    pub alpha_rule: AlphaRule,
}

impl Default for AvoidSettings {
    fn default() -> Self {
        AvoidSettings {
            field: FieldParams::default(),
            control_rate_hz: 20.0,
            duration_s: 60.0,
            touch_feedback: true,
            detection_chi2: 200.0,
            min_force_n: 0.005,
            goal_tolerance_m: 0.002,
            noise_sigma_m: 5e-5,
            model_elements: 4,
            shape_interval_s: 1.0,
            alpha_rule: super::ALPHA_RULE,
        }
    }
}

/// The most control steps an avoidance run takes (`duration_s` ×
/// `control_rate_hz`): ten minutes at the paper's 20 Hz, about 50 s of
/// computation at the measured ≈ 3.9 ms per step (1e6 steps, ≈ 65 min, were
/// accepted before).
pub const MAX_AVOID_STEPS: usize = 12_000;

impl AvoidSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`avoid.control_rate_hz`, …).
    pub fn validate(&self) -> Result<()> {
        self.field.validate()?;
        for (name, v) in [
            ("avoid.control_rate_hz", self.control_rate_hz),
            ("avoid.duration_s", self.duration_s),
            ("avoid.detection_chi2", self.detection_chi2),
            ("avoid.min_force_n", self.min_force_n),
            ("avoid.goal_tolerance_m", self.goal_tolerance_m),
            ("avoid.noise_sigma_m", self.noise_sigma_m),
            ("avoid.shape_interval_s", self.shape_interval_s),
        ] {
            check_positive(name, v)?;
        }
        let steps = self.duration_s * self.control_rate_hz;
        if steps > MAX_AVOID_STEPS as f64 {
            return Err(Error::invalid(
                "avoid.duration_s",
                self.duration_s,
                format!(
                    "with `avoid.control_rate_hz` = {} Hz, {steps:.3e} control steps: at most \
                     {MAX_AVOID_STEPS}",
                    self.control_rate_hz
                ),
            ));
        }
        if self.model_elements == 0 || self.model_elements > 64 {
            return Err(Error::invalid(
                "avoid.model_elements",
                self.model_elements,
                "must be in 1 ..= 64",
            ));
        }
        Ok(())
    }
}

/// How a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum AvoidStatus {
    /// The end effector reached the goal and stayed within the tolerance
    /// to the end of the run.
    Reached {
        /// When it entered the tolerance for good (s).
        time_s: f64,
    },
    /// The run ended away from the goal.
    NotReached {
        /// Final distance of the true end effector from the goal (m).
        distance_m: f64,
    },
    /// The goal lies outside the controller's workspace (its inverse
    /// kinematics without obstacles ends this far from it): not run.
    GoalUnreachable {
        /// Closest distance the model reaches (m).
        distance_m: f64,
    },
}

impl AvoidStatus {
    /// Whether the goal was reached.
    pub fn is_reached(&self) -> bool {
        matches!(self, AvoidStatus::Reached { .. })
    }
}

/// An obstacle point learnt by touch.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TouchedPoint {
    /// When it was (last) localized (s).
    pub time_s: f64,
    /// Arc coordinate of the contact (m).
    pub s_m: f64,
    /// The obstacle's point in the field (m).
    pub point_m: [f64; 2],
    /// The estimated contact force on the robot (N).
    pub force_n: [f64; 2],
}

impl TouchedPoint {
    /// [`TouchedPoint::point_m`] as a vector (m).
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// let p = softrod::touch::TouchedPoint { time_s: 3.0, s_m: 0.4, point_m: [0.1, -0.45],
    ///     force_n: [0.0, 0.03] };
    /// assert_eq!((p.point(), p.force()), (Vector2::new(0.1, -0.45), Vector2::new(0.0, 0.03)));
    /// ```
    pub fn point(&self) -> Vector2<f64> {
        Vector2::from(self.point_m)
    }

    /// [`TouchedPoint::force_n`] as a vector (N).
    ///
    /// # Example
    /// See [`TouchedPoint::point`].
    pub fn force(&self) -> Vector2<f64> {
        Vector2::from(self.force_n)
    }
}

/// One control instant.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AvoidSample {
    /// Time (s).
    pub time_s: f64,
    /// True end effector (m, for scoring).
    pub tip_true_m: [f64; 2],
    /// Estimated end effector (m).
    pub tip_estimated_m: [f64; 2],
    /// Sum of the plant's contact forces (N, for scoring).
    pub contact_force_n: f64,
    /// Obstacle points known to the field.
    pub known_points: usize,
    /// The point search's `Δχ²` (0 without touch feedback).
    pub touch_chi2: f64,
    /// Commanded pressures for the next interval (Pa).
    pub pressures_pa: Vec<f64>,
}

impl AvoidSample {
    /// [`AvoidSample::tip_true_m`] as a vector (m).
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// let s = softrod::touch::AvoidSample { time_s: 0.05, tip_true_m: [0.1, -0.4],
    ///     tip_estimated_m: [0.1, -0.401], contact_force_n: 0.0, known_points: 0,
    ///     touch_chi2: 0.0, pressures_pa: vec![0.0; 10] };
    /// assert_eq!(s.tip_true(), Vector2::new(0.1, -0.4));
    /// assert!((s.tip_estimated() - s.tip_true()).norm() < 1.1e-3);
    /// ```
    pub fn tip_true(&self) -> Vector2<f64> {
        Vector2::from(self.tip_true_m)
    }

    /// [`AvoidSample::tip_estimated_m`] as a vector (m).
    ///
    /// # Example
    /// See [`AvoidSample::tip_true`].
    pub fn tip_estimated(&self) -> Vector2<f64> {
        Vector2::from(self.tip_estimated_m)
    }
}

/// A whole run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AvoidRun {
    /// How it ended.
    pub status: AvoidStatus,
    /// The goal (m).
    pub goal_m: [f64; 2],
    /// Final distance of the true end effector from the goal (m).
    pub final_error_m: f64,
    /// Largest plant contact force before the first localization (N).
    pub max_force_before_n: f64,
    /// Largest plant contact force after it (N; 0 without one).
    pub max_force_after_n: f64,
    /// Plant contact force at the end (N).
    pub final_force_n: f64,
    /// The model calibration used.
    pub calibration: Calibration,
    /// Obstacle points learnt by touch.
    pub touched: Vec<TouchedPoint>,
    /// Every control instant.
    pub samples: Vec<AvoidSample>,
    /// True shapes (node positions, m) every `shape_interval_s`: `(t, nodes)`.
    pub shapes: Vec<(f64, Vec<[f64; 2]>)>,
}

impl AvoidRun {
    /// [`AvoidRun::goal_m`] as a vector (m).
    ///
    /// # Example
    /// See [`run_avoidance`].
    pub fn goal(&self) -> Vector2<f64> {
        Vector2::from(self.goal_m)
    }

    /// The shape kept at index `i` of [`AvoidRun::shapes`]: its time (s) and
    /// node positions as vectors (m); `None` past the last one.
    ///
    /// # Example
    /// See [`run_avoidance`].
    pub fn shape(&self, i: usize) -> Option<(f64, Vec<Vector2<f64>>)> {
        self.shapes
            .get(i)
            .map(|(t, nodes)| (*t, nodes.iter().map(|&p| Vector2::from(p)).collect()))
    }
}

/// Calibrates the nominal scene on an obstacle-free copy of the plant:
/// frames at three pressure patterns (every first chamber at 20 kPa, every
/// second one, and half of the first), 0.5 s each.
///
/// # Errors
/// As [`calibrate`] and the plant's.
pub fn calibrate_on_free_plant(
    nominal: &Scene,
    marker_s_m: &[f64],
    plant: &PlantSettings,
) -> Result<Calibration> {
    let mut free = SimulatedPlant::new(nominal, marker_s_m, plant.clone())?;
    let np = free.n_pressures();
    let mut a = vec![0.0; np];
    a.iter_mut().step_by(2).for_each(|p| *p = 20e3);
    let mut b = a.clone();
    b.rotate_right(1);
    let half: Vec<f64> = a.iter().map(|p| 0.5 * p).collect();
    let mut frames = Vec::new();
    for p in [a, b, half] {
        free.command(&p)?;
        for _ in 0..9 {
            free.advance(0.05)?;
        }
        frames.push(FreeFrame {
            markers_m: free.advance(0.05)?.positions_m,
            pressures_pa: p,
        });
    }
    calibrate(nominal, marker_s_m, &frames)
}

/// Runs the avoidance on `plant` (obstacles in its world, unknown to the
/// controller) from its present state, towards `goal_m`, the controller's
/// model the nominal scene `nominal` with `settings.model_elements` per
/// section, calibrated by `calibration`, observing markers at
/// `marker_s_m` (see the [module documentation](crate::touch)).
///
/// # Errors
/// [`Error::InvalidParameter`] for invalid settings or a non-finite goal
/// (`goal_m`); the plant's errors (a contact solve that does not converge);
/// the model's static solve failing.
///
/// # Example
/// Half a second towards a goal below the hanging robot, with no obstacle:
/// ```
/// use nalgebra::Vector2;
/// use softrod::plant::{PlantSettings, SimulatedPlant};
/// use softrod::touch::{calibrate_on_free_plant, five_section_scene, marker_arcs, run_avoidance, AvoidSettings};
/// let scene = five_section_scene(4);
/// let arcs = marker_arcs(6);
/// let cal = calibrate_on_free_plant(&scene, arcs.as_slice(), &PlantSettings::default())?;
/// let mut plant = SimulatedPlant::new(&scene, arcs.as_slice(), PlantSettings::default())?;
/// let settings = AvoidSettings { duration_s: 0.5, ..AvoidSettings::default() };
/// let goal = Vector2::new(0.12, -0.4);
/// let run = run_avoidance(&scene, &cal, arcs.as_slice(), &mut plant, goal, &settings)?;
/// assert_eq!((run.goal(), run.samples.len()), (goal, 10));
/// let (t, nodes) = run.shape(0).unwrap();
/// assert!(t > 0.0 && nodes.len() > 2);
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn run_avoidance(
    nominal: &Scene,
    calibration: &Calibration,
    marker_s_m: &[f64],
    plant: &mut SimulatedPlant,
    goal_m: Vector2<f64>,
    settings: &AvoidSettings,
) -> Result<AvoidRun> {
    settings.validate()?;
    if !goal_m.iter().all(|v| v.is_finite()) {
        return Err(Error::invalid(
            "goal_m",
            format!("[{}, {}]", goal_m.x, goal_m.y),
            "must be finite",
        ));
    }
    let mut scene = calibration.apply(nominal);
    for s in &mut scene.robot.sections {
        s.elements = settings.model_elements;
    }
    let model = scene.robot()?;
    check_len("plant pressures", model.n_pressures(), plant.n_pressures())?;
    let bounds = model.pressure_bounds();
    let base_loads = scene.loads()?;
    let mut run = AvoidRun {
        status: AvoidStatus::NotReached {
            distance_m: f64::NAN,
        },
        goal_m: goal_m.into(),
        final_error_m: f64::NAN,
        max_force_before_n: 0.0,
        max_force_after_n: 0.0,
        final_force_n: 0.0,
        calibration: *calibration,
        touched: Vec::new(),
        samples: Vec::new(),
        shapes: Vec::new(),
    };
    // an unreachable goal is said so, not chased
    let mut ik = InverseKinematics::new(model.clone(), base_loads.clone(), IkSettings::default())?;
    if let IkStatus::Unreachable { distance_m } =
        ik.solve(goal_m.as_slice(), &vec![0.0; model.n_q()])?.status
        && distance_m > settings.goal_tolerance_m
    {
        run.status = AvoidStatus::GoalUnreachable { distance_m };
        return Ok(run);
    }
    let dt = 1.0 / settings.control_rate_hz;
    let steps = (settings.duration_s * settings.control_rate_hz).round() as usize;
    let mut p: Vec<f64> = plant_pressures(plant);
    let es = EstimatorSettings {
        noise_sigma_m: settings.noise_sigma_m,
        alpha_rule: settings.alpha_rule,
        ..EstimatorSettings::default()
    };
    let mut known = base_loads.clone();
    known.pressures_pa.clone_from(&p);
    let mut est: Box<dyn Estimator> = es.build_for(&model, &known)?;
    let search = PointSearchSettings {
        grid_step_m: 1e-3,
        passes: 1,
        normal_only: true,
    };
    let mut touch = Touch {
        search,
        sigma2: settings.noise_sigma_m * settings.noise_sigma_m,
        detection_chi2: settings.detection_chi2,
        min_force_n: settings.min_force_n,
        pending: Vec::new(),
        points: Vec::new(),
    };
    let mut next_shape = 0.0;
    let tip_s = model.length();
    for k in 1..=steps {
        plant.command(&p)?;
        let frame = plant.advance(dt)?;
        let t = k as f64 * dt;
        let force_now = plant.contact().map_or(0.0, |c| c.total_force_n());
        if run.touched.is_empty() {
            run.max_force_before_n = run.max_force_before_n.max(force_now);
        } else {
            run.max_force_after_n = run.max_force_after_n.max(force_now);
        }
        if t + 1e-9 >= next_shape {
            let q = plant.true_q();
            run.shapes
                .push((t, q.chunks(4).map(|c| [c[0], c[1]]).collect()));
            next_shape += settings.shape_interval_s;
        }
        // 2. the estimate with the pressures commanded over the interval
        let mut known = base_loads.clone();
        known.pressures_pa.clone_from(&p);
        est.set_known_loads(known.clone())?;
        let e = est.step(&frame.observation(marker_s_m)?)?;
        let (q_hat, f_hat) = (e.q.clone(), e.f.clone());
        // 3. touch
        let chi2_now = if settings.touch_feedback {
            let markers = super::planar_points("markers", &frame.positions_m)?;
            touch.step(
                &model,
                &known,
                marker_s_m,
                &markers,
                q_hat.as_slice(),
                t,
                &mut run.touched,
            )?
        } else {
            0.0
        };
        // 4. the field's gradient in the pressures, frozen at the bounds, β (44)
        let mut loads = base_loads.clone();
        loads.pressures_pa.clone_from(&p);
        loads.distributed_f = f_hat.as_slice().to_vec();
        let step = FieldStep {
            model: &model,
            loads: &loads,
            q_hat: q_hat.as_slice(),
            bounds: &bounds,
            goal_m,
            points: &touch.points,
        };
        step.descend(&settings.field, dt, &mut p)?;
        let tip = plant.true_tip_m()?;
        let tip_hat = model.position_at(q_hat.as_slice(), tip_s)?;
        run.samples.push(AvoidSample {
            time_s: t,
            tip_true_m: [tip[0], tip[1]],
            tip_estimated_m: [tip_hat[0], tip_hat[1]],
            contact_force_n: force_now,
            known_points: touch.points.len(),
            touch_chi2: chi2_now,
            pressures_pa: p.clone(),
        });
    }
    finish(&mut run, goal_m, settings.goal_tolerance_m);
    Ok(run)
}

/// What the touch feedback keeps between instants: the point search's
/// settings, the detection thresholds, the candidates of the current
/// contact (a point is learnt once three consecutive instants agree on it
/// within 2 cm) and the obstacle points learnt.
struct Touch {
    search: PointSearchSettings,
    /// σ² of the markers (m²).
    sigma2: f64,
    detection_chi2: f64,
    min_force_n: f64,
    pending: Vec<TouchedPoint>,
    points: Vec<Vector2<f64>>,
}

impl Touch {
    /// One instant: the point force that best explains the markers (its
    /// χ² against no force), and where it is strong enough, a candidate
    /// contact point on the rod's surface (`q_hat` the estimated shape);
    /// a point confirmed by three candidates is learnt (pushed to
    /// `touched`). Returns the χ².
    #[allow(clippy::too_many_arguments)]
    fn step(
        &mut self,
        model: &Robot<PlanarCable>,
        known: &Loads,
        marker_s_m: &[f64],
        markers: &[Vector2<f64>],
        q_hat: &[f64],
        t: f64,
        touched: &mut Vec<TouchedPoint>,
    ) -> Result<f64> {
        let c = locate_point_force(model, known, marker_s_m, markers, &[], &self.search)?;
        let chi2 = (c.misfit_free_m2 - c.misfit_m2) / self.sigma2;
        let f = c.force_n[0].hypot(c.force_n[1]);
        if !(chi2 > self.detection_chi2 && f > self.min_force_n) {
            self.pending.clear();
            return Ok(chi2);
        }
        let r = model.position_at(q_hat, c.s_m)?;
        let rho = super::ROD_RADIUS_M;
        let point = [r[0] - rho * c.force_n[0] / f, r[1] - rho * c.force_n[1] / f];
        let cand = TouchedPoint {
            time_s: t,
            s_m: c.s_m,
            point_m: point,
            force_n: c.force_n,
        };
        let near = |a: Vector2<f64>, b: Vector2<f64>| (a - b).norm() < 0.02;
        self.pending.retain(|x| near(x.point(), cand.point()));
        self.pending.push(cand.clone());
        if self.pending.len() >= 3 {
            match self.points.iter().position(|x| near(*x, cand.point())) {
                Some(i) => self.points[i] = cand.point(),
                None => self.points.push(cand.point()),
            }
            touched.push(cand);
            self.pending.clear();
        }
        Ok(chi2)
    }
}

/// One descent step of the pressures on the potential field (44) at the
/// estimated shape.
struct FieldStep<'a> {
    model: &'a Robot<PlanarCable>,
    /// The loads of the estimate: the commanded pressures and the
    /// estimated field `F̂`.
    loads: &'a Loads,
    q_hat: &'a [f64],
    bounds: &'a [(f64, f64)],
    goal_m: Vector2<f64>,
    points: &'a [Vector2<f64>],
}

impl FieldStep<'_> {
    /// The field's gradient in the pressures through (43), frozen where a
    /// pressure sits at a bound and points out, scaled by `β` so that the
    /// end effector moves at the field's `v_d`, applied over `dt_s` to `p`
    /// (clamped to the bounds).
    fn descend(&self, field: &FieldParams, dt_s: f64, p: &mut [f64]) -> Result<()> {
        let model = self.model;
        let nq = model.n_q();
        let (_, g_q) = field_gradient(model, self.q_hat, field, self.goal_m, self.points)?;
        let jac = dq_dp(model, self.loads, self.q_hat)?;
        let np = p.len();
        let mut g_p: Vec<f64> = (0..np)
            .map(|j| (0..nq).map(|i| g_q[i] * jac[(i, j)]).sum())
            .collect();
        for (j, (lo, hi)) in self.bounds.iter().enumerate() {
            let tol = 1e-9 * (hi - lo);
            if (p[j] <= lo + tol && g_p[j] > 0.0) || (p[j] >= hi - tol && g_p[j] < 0.0) {
                g_p[j] = 0.0;
            }
        }
        // ∂x_e/∂P ∂U/∂P: the end effector is the last node's position
        let v: Vec<f64> = (0..2)
            .map(|d| (0..np).map(|j| jac[(nq - 4 + d, j)] * g_p[j]).sum())
            .collect();
        let speed = v[0].hypot(v[1]);
        if speed > 0.0 && speed.is_finite() {
            let beta = field.v_d_m_per_s / speed;
            for (j, (lo, hi)) in self.bounds.iter().enumerate() {
                p[j] = (p[j] - beta * g_p[j] * dt_s).clamp(*lo, *hi);
            }
        }
        Ok(())
    }
}

/// The run's end: the final error and force, and its status (reached at
/// the first instant from which the tip stays within `tolerance_m` of the
/// goal, else not reached with the last distance).
fn finish(run: &mut AvoidRun, goal_m: Vector2<f64>, tolerance_m: f64) {
    let err = |s: &AvoidSample| (s.tip_true() - goal_m).norm();
    let last = run.samples.last().map_or(f64::NAN, err);
    run.final_error_m = last;
    run.final_force_n = run.samples.last().map_or(0.0, |s| s.contact_force_n);
    run.status = match run
        .samples
        .iter()
        .rposition(|s| err(s).is_nan() || err(s) > tolerance_m)
    {
        None => AvoidStatus::Reached { time_s: 0.0 },
        Some(i) if i + 1 < run.samples.len() => AvoidStatus::Reached {
            time_s: run.samples[i + 1].time_s,
        },
        Some(_) => AvoidStatus::NotReached { distance_m: last },
    };
}

/// The plant's chamber pressures now (the command it holds).
fn plant_pressures(plant: &SimulatedPlant) -> Vec<f64> {
    plant.actual_pressures_pa().to_vec()
}

/// The obstacles of a plant, checked against the model too (for a scene
/// file: an obstacle overlapping the reference configuration or the base
/// is named by its field path).
///
/// # Errors
/// [`Error::InvalidParameter`] naming `obstacles[i]`.
pub fn check_obstacles(nominal: &Scene, obstacles: &Obstacles) -> Result<()> {
    obstacles.check_robot(&nominal.robot()?)
}
