//! Feedforward inverse kinematics `f_IK(x_d, F̂)` (Sec. IV): the pressures
//! `P` (within their bounds) and the shape `q` such that the equilibrium (17)
//! `Q(F̂, q, P) = 0` holds and the end effector sits at `x_d`.
//!
//! # Method
//! Newton–Raphson on the pair `(q, P)` with `q` eliminated by the
//! equilibrium: every iterate `q(P)` is solved (warm) by
//! [`StaticSolver`], and the end effector's Jacobian is
//! `J = ∂x/∂P = S(X_e) ∂q/∂P` with `∂q/∂P` from (43). One step solves the
//! bounded least-squares problem in the pressures scaled by their range,
//! `p̂ = P / (P_max − P_min)`:
//!
//! ```text
//! min_d  ½ |x_d − x − Ĵ d|² / ℓ²  +  ½ μ |p̂ + d|²    s.t.  p̂_min ≤ p̂ + d ≤ p̂_max,  |d|∞ ≤ Δ
//! ```
//!
//! exactly, by an active-set method (a pressure on its bound sits *on* it),
//! then backtracks on the same merit.
//!
//! # Cost of a step
//! The equilibria of the Newton loop are warm: a line-search trial starts
//! from the last equilibrium moved to first order, `q + ∂q/∂P ΔP`, and the
//! first equilibrium of a solve whose load field changed from the last
//! solve's starts from the last one moved by its response to the change
//! (the load field the last solution holds for is kept with it: when it
//! is the same, that equilibrium is used as it is). A plain Newton
//! corrector takes them to the static solver's residual tolerance, and the
//! positive definite factors of the tangent at its answer (the static
//! solver's stability test) give the next Jacobian (43) by solves only;
//! the static solver, from the unpredicted start, takes over wherever the
//! corrector gives up. The closing iteration at a reached target (the
//! check that no null-space step lowers `Σ P̂²`) therefore costs solves,
//! not another factorization. With a chord corrector
//! ([`InverseKinematics::with_corrector`], the parallel robot's) the
//! trials are chord steps with the kept factors, and each iteration's
//! Jacobian is one factorization at the iterate, kept for the next trials.
//!
//! # Redundancy rule: minimum Σ P̂²
//! The two-section robot has four chambers and two task coordinates: the
//! end effector depends on the section torques `M_s = G P` only, so the
//! pressures are free along the null space of `G` (raising both chambers of
//! a section together). The term `μ |p̂|²` picks the pressures of least
//! `Σ (P_i / range_i)²` (for equal ranges: least `Σ P²`): with the
//! antagonistic pairs of the paper's robot that is one active chamber per
//! section and bending direction, the other at zero — the least air and
//! the least wall load for the same pose. Weighted by `μ = 10⁻²`
//! ([`IkSettings::pressure_weight`]) against the position error in
//! `ℓ = 0.1 mm`, it moves the reached position by about `μ ℓ² |p̂| / |Ĵ|`,
//! i.e. 1e-9 m on this robot. Where the null space is large (the parallel
//! robot: 18 pressures, 3 coordinates), [`IkSettings::null_space_damping`]
//! `λ` adds `λ |d|²` to every step, which then moves `μ/(μ + λ)` of the way
//! towards the least pressures in the null space.
//!
//! # Models
//! The same loop serves every [`Actuated`] model: the end effector is a
//! [`Site`] (its position rows `A_x`, so `J = A_x ∂q/∂P`), the load field
//! `F̂` the parameters of a [`LoadModel`] (the distributed `F` of (8) on the
//! clamped robot, a force at the platform of the parallel robot), and the
//! equilibria and their factors come from the one warm [`Tracker`].
//!
//! # Unreachable targets
//! A target outside the workspace (or beyond the bounds) ends at the closest
//! reachable pose the iteration finds (a stationary point of the merit, in
//! the bounds) with [`IkStatus::Unreachable`] and its distance: never a
//! silent clamp. A solve that does not reach its target from the warm
//! start (the workspace folds, so the distance has local minima) is
//! repeated from every chamber at its minimum or mid-range (`2ⁿ` starts for
//! `n ≤ 6` chambers) and the closest result kept — except when the last
//! solve already ended unreachable at a target within
//! [`RESTART_RADIUS_M`] of this one: its restarts found that closest pose,
//! and a loop following an unreachable path then costs one warm solve per
//! step instead of `2ⁿ + 1` cold ones.

use nalgebra::{DMatrix, DVector};

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{Error, Result, check_all_finite, check_len};
use crate::estimate::{EstimationModel, LoadModel};
use crate::linsolve::AutoFactors;
use crate::loads::Loads;
use crate::sensitivity::Sensitivity;
use crate::site::{Site, SiteRows};
use crate::statics::{
    LinearLoad, StaticSettings, StaticSolver, TrackedEquilibrium, Tracker, WarmCounts, WarmPath,
    WarmStrategy,
};
use crate::structure::Actuated;

use super::ik_settings::{IkSettings, IkStatus, PressureBound};
use super::{adapter, boxqp};

/// The result of [`InverseKinematics::solve`].
///
/// # Example
/// ```
/// use softrod::{control::{InverseKinematics, IkSettings}, scene::Scene};
/// let scene = Scene::two_section();
/// let robot = scene.robot()?;
/// let (n, np) = (robot.n_q(), robot.n_pressures());
/// let mut ik = InverseKinematics::new(robot, scene.loads()?, IkSettings::default())?;
/// let sol = ik.solve(&[0.20, 0.08], &vec![0.0; n])?;
/// assert_eq!((sol.pressures_pa.len(), sol.q.len(), sol.effector_m.len()), (np, n, 2));
/// assert!((sol.effector_m - nalgebra::dvector![0.20, 0.08]).norm() < 1e-7);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct IkSolution {
    /// Chamber pressures (Pa), within their bounds.
    pub pressures_pa: DVector<f64>,
    /// The equilibrium shape at those pressures (all coordinates).
    pub q: DVector<f64>,
    /// End-effector position (m, `DIM` components).
    pub effector_m: DVector<f64>,
    /// How the solve ended.
    pub status: IkStatus,
    /// Newton iterations taken.
    pub iterations: usize,
    /// Where each pressure sits relative to its bounds.
    pub bounds: Vec<PressureBound>,
}

/// Feedforward inverse kinematics of one model (see the [module
/// documentation](crate::control)): the clamped robot with its end effector
/// at the tip under a distributed load field ([`InverseKinematics::new`]),
/// or any actuated model with an end-effector site and a load model
/// ([`InverseKinematics::for_model`]: the parallel robot's platform under a
/// force on it). It keeps the last solution as the warm start of the next.
///
/// # Example
/// ```
/// use softrod::{control::{InverseKinematics, IkSettings}, scene::Scene};
/// let scene = Scene::two_section();
/// let robot = scene.robot()?;
/// let n = robot.n_q();
/// let mut ik = InverseKinematics::new(robot, scene.loads()?, IkSettings::default())?;
/// let sol = ik.solve(&[0.20, 0.08], &vec![0.0; n])?;
/// assert!(sol.status.is_reached());
/// assert!((sol.effector_m[0] - 0.20).abs() < 1e-7 && (sol.effector_m[1] - 0.08).abs() < 1e-7);
/// // the equilibrium at those pressures puts the end effector there
/// let (q, x) = ik.forward(sol.pressures_pa.as_slice(), &vec![0.0; n], None)?;
/// assert!((x - &sol.effector_m).norm() < 1e-9 && q.len() == n);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct InverseKinematics<M: Actuated + EstimationModel> {
    /// The model and the warm corrector of its equilibria (the one warm
    /// tracker, [`WarmStrategy::Newton`]), whose linear solver, analyzed
    /// once, also serves the static solves and the Jacobians.
    tracker: Tracker<M>,
    known: M::Loads,
    /// What the load field `F̂` of a solve is: its parameters and how they
    /// enter the loads.
    load: LoadModel,
    /// The end effector's rows (its position is `A_x q`).
    effector: SiteRows,
    settings: IkSettings,
    solver: StaticSolver,
    /// The solver of the line search's trials (its total budget
    /// [`IkSettings::trial_max_total_iterations`]).
    trial_solver: StaticSolver,
    /// Scaled pressure bounds and the scale (range) of each chamber.
    lo: Vec<f64>,
    hi: Vec<f64>,
    range: Vec<f64>,
    warm: Option<Held>,
    /// The target of the last solve, if it ended unreachable after its
    /// restarts.
    unreached_target: Option<Vec<f64>>,
    /// Static Newton iterations spent by the current solve.
    spent: usize,
}

/// An equilibrium the inverse kinematics holds: the last solution, the
/// warm start of the next solve.
#[derive(Debug, Clone)]
struct Held {
    /// Pressures (Pa).
    p: Vec<f64>,
    /// The load field the equilibrium holds for.
    f_hat: Vec<f64>,
    /// The equilibrium at `p` under `f_hat`.
    eq: Eq,
}

/// Where a Newton run starts.
#[derive(Debug)]
enum Start {
    /// From the held equilibrium.
    Warm(Box<Held>),
    /// From these pressures (Pa), the equilibrium solved cold.
    Cold(Vec<f64>),
}

/// An equilibrium of the Newton loop.
#[derive(Debug, Clone)]
struct Eq {
    /// The shape (all coordinates).
    q: Vec<f64>,
    /// Its free coordinates.
    u: Vec<f64>,
    /// The end effector's position (m).
    x: Vec<f64>,
    /// The factors of its tangent when the corrector made it (`None`: the
    /// static solver).
    factors: Option<AutoFactors>,
}

/// A solve that does not reach its target skips the cold restarts when the
/// last solve ended unreachable at a target at most this far (m): 1 mm, what
/// a 5 Hz loop moves along the slowest paths a person would choose for this
/// robot in a fifth of a second is ten times less.
pub const RESTART_RADIUS_M: f64 = 1e-3;

/// Static Newton iterations a solve's result took (1 for an error without
/// a report).
fn spent(eq: &Result<crate::statics::Equilibrium>) -> usize {
    match eq {
        Ok(e) => e.report.iterations.max(1),
        Err(Error::NotConverged { report }) => report.iterations.max(1),
        Err(_) => 1,
    }
}

/// Line-search trials whose equilibrium the warm solver does not reach
/// after which one Newton run ends as stalled: such a trial marks a fold
/// of the equilibria (a heavily loaded robot snapping over) between the
/// iterate and the trial, and an iterate at the fold only ever accepts
/// ever shorter steps (measured: 5 × the robot's weight at the tip, steps
/// of 1e-4 of the pressure range after 9 failed trials each).
const FAILED_TRIALS: usize = 8;

/// Newton steps the corrector takes at most (a warm start from the
/// sensitivities' prediction converges in one or two: measured on the
/// tracking bench's loop).
const CORRECTOR_STEPS: usize = 6;

/// Length scale of the position error (m).
const ELL_M: f64 = 1e-4;

impl<E: Element + 'static> InverseKinematics<Robot<E>> {
    /// The inverse kinematics of `robot` under the known loads `known`
    /// (self-weight from the robot; the pressures in `known` are the first
    /// guess), the end effector at the tip, the load field `F̂` the
    /// distributed `F` of (8) (`n_q` entries).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for invalid settings, a robot without
    /// chambers, or a chamber whose bounds are equal; the errors of
    /// [`Robot::validate_loads`].
    pub fn new(robot: Robot<E>, known: Loads, settings: IkSettings) -> Result<Self> {
        let tip = Site::Rod {
            rod: 0,
            s_m: robot.length(),
        };
        Self::for_model(robot, known, settings, tip, LoadModel::Distributed)
    }

    /// The robot.
    pub fn robot(&self) -> &Robot<E> {
        self.tracker.robot()
    }
}

impl<M: Actuated + EstimationModel> InverseKinematics<M> {
    /// The inverse kinematics of `model` under the known loads `known`
    /// (the pressures in `known` are the first guess), the end effector at
    /// `effector`, the load field `F̂` of a solve the parameters of `load`
    /// ([`LinearLoad::n_params`] of them).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for invalid settings, a model without
    /// chambers, or a chamber whose bounds are equal; the errors of
    /// [`crate::structure::Assembled::validate_loads`] and of the effector's and the load's
    /// sites (named `effector` and `load_model`); [`Error::InvalidParameter`]
    /// named `load_model` for [`LoadModel::Distributed`] on a model without
    /// a field rod (a structure).
    ///
    /// # Example
    /// The parallel robot's platform moved 2 mm sideways under a 5 g
    /// payload:
    /// ```
    /// use softrod::{control::{InverseKinematics, IkSettings}, estimate::LoadModel, site::Site};
    /// let mut spec = softrod::parallel::ParallelSpec::default();
    /// spec.elements_per_section = 2;
    /// let robot = spec.build_cable()?;
    /// let s = robot.structure().clone();
    /// let platform = Site::Body { body: 0 };
    /// let known = robot.loads(&vec![0.0; 18], [0.0; 3], [0.0; 3])?;
    /// let mut ik = InverseKinematics::for_model(
    ///     s, known, IkSettings::default(), platform, LoadModel::AtSite { site: platform },
    /// )?;
    /// let weight = [0.0, 0.0, -0.005 * 9.81];
    /// let (_, x0) = ik.forward(&vec![0.0; 18], &weight, None)?;
    /// let target = [x0[0] + 2e-3, x0[1], x0[2]];
    /// let sol = ik.solve(&target, &weight)?;
    /// assert!(sol.status.is_reached(), "{:?}", sol.status);
    /// assert!((sol.effector_m[0] - target[0]).abs() < 1e-6);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn for_model(
        model: M,
        known: M::Loads,
        settings: IkSettings,
        effector: Site,
        load: LoadModel,
    ) -> Result<Self> {
        settings.validate()?;
        model.validate_loads(&known)?;
        let effector = model.site_rows("effector", &effector)?;
        load.check_defined_on(&model, "load_model")?;
        load.site_rows(&model)?;
        let bounds = model.pressure_bounds();
        if bounds.is_empty() {
            return Err(Error::invalid(
                "robot.sections[].chambers",
                0,
                "inverse kinematics needs at least one chamber",
            ));
        }
        let mut range = Vec::with_capacity(bounds.len());
        for (i, (lo, hi)) in bounds.iter().enumerate() {
            let r = hi - lo;
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::invalid(
                    format!("chambers[{i}].pressure_max_pa"),
                    hi,
                    "inverse kinematics needs P_max > P_min (finite)",
                ));
            }
            range.push(r);
        }
        let lo = bounds.iter().zip(&range).map(|((l, _), r)| l / r).collect();
        let hi = bounds.iter().zip(&range).map(|((_, h), r)| h / r).collect();
        let solver = StaticSolver::new(settings.statics.clone())?;
        let total = settings
            .trial_max_total_iterations
            .min(settings.statics.max_total_iterations);
        let trial_solver = StaticSolver::new(StaticSettings {
            max_iterations: settings.statics.max_iterations.min(total),
            max_total_iterations: total,
            ..settings.statics.clone()
        })?;
        let tracker = Tracker::new(model, known.clone(), settings.statics.clone())?.with_strategy(
            WarmStrategy::Newton {
                max_steps: CORRECTOR_STEPS,
            },
        )?;
        Ok(InverseKinematics {
            tracker,
            known,
            load,
            effector,
            settings,
            solver,
            trial_solver,
            lo,
            hi,
            range,
            warm: None,
            unreached_target: None,
            spent: 0,
        })
    }

    /// The same inverse kinematics with `strategy` as the warm corrector of
    /// its equilibria (default [`WarmStrategy::Newton`] of at most 6 steps,
    /// whose factors at the answer give the next Jacobian by solves only).
    /// With a chord strategy ([`WarmStrategy::ChordRefactor`]: the parallel
    /// robot's, whose 24-coordinate element makes a tangent costly) the
    /// Jacobian at an iterate is one factorization of its tangent, kept for
    /// the chord steps of the next trials.
    ///
    /// # Errors
    /// As [`WarmStrategy::validate`].
    ///
    /// # Example
    /// ```
    /// use softrod::{control::{InverseKinematics, IkSettings}, scene::Scene, statics::WarmStrategy};
    /// let scene = Scene::two_section();
    /// let robot = scene.robot()?;
    /// let n = robot.n_q();
    /// let chord = WarmStrategy::ChordRefactor {
    ///     max_factorizations: 3, max_residuals: 36, step_tolerance_m: 1e-11, confirm: true,
    /// };
    /// let mut ik = InverseKinematics::new(robot, scene.loads()?, IkSettings::default())?
    ///     .with_corrector(chord)?;
    /// let sol = ik.solve(&[0.20, 0.08], &vec![0.0; n])?;
    /// assert!(sol.status.is_reached());
    /// assert!(ik.counts().solves > 0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn with_corrector(mut self, strategy: WarmStrategy) -> Result<Self> {
        self.tracker = self.tracker.with_strategy(strategy)?;
        Ok(self)
    }

    /// The warm tracker of the equilibria, for a caller that solves the
    /// same model between the solves (a controller's estimator): its kept
    /// factors then serve both.
    pub(crate) fn tracker_mut(&mut self) -> &mut Tracker<M> {
        &mut self.tracker
    }

    /// The model.
    pub fn model(&self) -> &M {
        self.tracker.model()
    }

    /// What the warm corrector's equilibria cost so far (the globalized
    /// static solves of cold starts and of trials the corrector gave up on
    /// are not counted here: [`IkSolution::iterations`] and the solve's
    /// static budget bound them).
    pub fn counts(&self) -> WarmCounts {
        self.tracker.counts()
    }

    /// The number of parameters of a load field `F̂`.
    pub fn n_load_params(&self) -> usize {
        self.load.n_params(self.model())
    }

    /// Forgets the warm start.
    pub fn reset(&mut self) {
        self.warm = None;
        self.unreached_target = None;
    }

    /// The known loads with pressures `p` and the load field `f_hat` added.
    fn loads(&self, p: &[f64], f_hat: &[f64]) -> M::Loads {
        let model = self.model();
        self.load
            .add_to(model, &model.with_pressures(&self.known, p), f_hat)
    }

    /// The end effector's position (m) at `q`.
    fn effector_at(&self, q: &[f64]) -> Vec<f64> {
        self.effector.position_at(q)
    }

    /// The equilibrium at pressures `p` (Pa) and load field `f_hat` (the
    /// parameters of the load model: the distributed `F` of (8), `n_q`
    /// entries, on the robot), from `q0` or cold; its shape `q` and
    /// end-effector position (m, `DIM` components).
    ///
    /// # Errors
    /// The errors of [`StaticSolver::solve_with`] (bad loads, no equilibrium).
    ///
    /// # Example
    /// See [`InverseKinematics`].
    pub fn forward(
        &mut self,
        p: &[f64],
        f_hat: &[f64],
        q0: Option<&[f64]>,
    ) -> Result<(DVector<f64>, DVector<f64>)> {
        let eq = self.forward_raw(p, f_hat, q0)?;
        Ok((DVector::from_vec(eq.q), DVector::from_vec(eq.x)))
    }

    /// [`InverseKinematics::forward`] as plain vectors (the Newton loop's).
    fn forward_raw(&mut self, p: &[f64], f_hat: &[f64], q0: Option<&[f64]>) -> Result<Eq> {
        let loads = self.loads(p, f_hat);
        let eq = self.tracker.static_solve(&self.solver, &loads, q0);
        self.spent += spent(&eq);
        let eq = eq?;
        let x = self.effector_at(eq.q.as_slice());
        Ok(Eq {
            q: eq.q.data.into(),
            u: eq.u.data.into(),
            x,
            factors: None,
        })
    }

    /// The equilibrium at pressures `p` and load field `f_hat` near a
    /// known one: the corrector from `start` (a prediction), else the static
    /// solver from `fallback` (a line-search trial with the trials' budget,
    /// [`IkSettings::trial_max_total_iterations`]).
    fn equilibrium(
        &mut self,
        p: &[f64],
        f_hat: &[f64],
        start: &[f64],
        fallback: &[f64],
        trial: bool,
    ) -> Result<Eq> {
        let loads = self.loads(p, f_hat);
        let before = self.tracker.counts().steps;
        let corrected = self.correct(&loads, start);
        // the Newton steps taken (at least 1: the static solver's count)
        self.spent += (self.tracker.counts().steps - before).max(1);
        if let Some(c) = corrected {
            let x = self.effector_at(c.q.as_slice());
            // Newton's factors are those at the answer; a chord's are kept
            // from elsewhere
            let at_answer = c.path == WarmPath::Newton;
            return Ok(Eq {
                q: c.q.data.into(),
                u: c.u.data.into(),
                x,
                factors: at_answer.then_some(c.factors),
            });
        }
        let solver = if trial {
            &self.trial_solver
        } else {
            &self.solver
        };
        let eq = self.tracker.static_solve(solver, &loads, Some(fallback));
        self.spent += spent(&eq);
        let eq = eq?;
        let x = self.effector_at(eq.q.as_slice());
        Ok(Eq {
            q: eq.q.data.into(),
            u: eq.u.data.into(),
            x,
            factors: None,
        })
    }

    /// The corrector: the tracker's strategy ([`WarmStrategy::Newton`] by
    /// default) from `start` under `loads` to the static solver's residual
    /// tolerance (Newton's with the positive definite factors of the
    /// tangent at its answer); `None` where it gives up (a hard solve, or
    /// an error: the static solver from the caller's start then reports
    /// it). The tracker's kept factors stay (a chord strategy steps with
    /// them; Newton's does not read them).
    fn correct(&mut self, loads: &M::Loads, start: &[f64]) -> Option<TrackedEquilibrium> {
        let u0 = self.model().free_coordinates_of(start).ok()?;
        self.tracker.set_loads(loads.clone()).ok()?;
        self.tracker.try_solve_free(u0.as_slice()).ok().flatten()
    }

    /// The first equilibrium of a Newton run: the held one as it is when
    /// its load field is `f_hat`, else corrected from it moved along its
    /// response to the change of load field, `M K⁻¹ Mᵀ J_QF ΔF̂` (the
    /// equilibrium's shift to first order); cold by the static solver.
    fn first_equilibrium(&mut self, f_hat: &[f64], start: Start) -> Result<(Vec<f64>, Eq)> {
        match start {
            Start::Cold(p) => {
                let eq = self.forward_raw(&p, f_hat, None)?;
                Ok((p, eq))
            }
            Start::Warm(h) if h.f_hat == f_hat => {
                let h = *h;
                Ok((h.p, h.eq))
            }
            Start::Warm(h) => {
                let held = &h.eq;
                let predicted = match &held.factors {
                    Some(f) => {
                        let df: Vec<f64> = f_hat.iter().zip(&h.f_hat).map(|(a, b)| a - b).collect();
                        let model = self.model();
                        let g = self.load.force(model, &df)?;
                        let dq = Sensitivity::at(model, &held.u, f)?.response(g.as_slice())?;
                        held.q.iter().zip(dq.iter()).map(|(a, b)| a + b).collect()
                    }
                    None => held.q.clone(),
                };
                let eq = self.equilibrium(&h.p, f_hat, &predicted, &held.q, false)?;
                Ok((h.p, eq))
            }
        }
    }

    /// (43) `∂q/∂P = −(∂Q/∂q)⁻¹ ∂Q/∂P` (`n_q × n_pressures`, m/Pa) at the
    /// equilibrium `q` of pressures `p` and load field `f_hat`.
    ///
    /// # Errors
    /// [`Error::Singular`] if the tangent cannot be factored; dimension errors.
    pub fn dq_dp(&self, q: &[f64], p: &[f64], f_hat: &[f64]) -> Result<DMatrix<f64>> {
        adapter::dq_dp(self.model(), &self.loads(p, f_hat), q)
    }

    /// The end effector's Jacobian `∂x/∂P = S(X_e) ∂q/∂P` (43) at the
    /// equilibrium `q` of pressures `p` and load field `f_hat`
    /// (`DIM × n_pressures`, m/Pa).
    ///
    /// # Errors
    /// [`Error::Singular`] if the tangent cannot be factored; dimension errors.
    pub fn jacobian(&self, q: &[f64], p: &[f64], f_hat: &[f64]) -> Result<DMatrix<f64>> {
        let dqdp = self.dq_dp(q, p, f_hat)?;
        Ok(self.effector_columns(&dqdp))
    }

    /// The Newton loop's `(∂x/∂P, ∂q/∂P)` at the equilibrium `eq`: with the
    /// factors of its tangent when the corrector made it (solves only),
    /// else factoring its tangent with the tracker's linear solver
    /// (analyzed once at construction) and keeping the factors there for
    /// the next chord steps.
    fn jacobian_warm(
        &mut self,
        eq: &Eq,
        p: &[f64],
        f_hat: &[f64],
    ) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
        let dqdp = match &eq.factors {
            Some(f) => Sensitivity::at(self.model(), &eq.u, f)?.dq_dp(&eq.q)?,
            None => {
                self.tracker.set_loads(self.loads(p, f_hat))?;
                let tangent = self.tracker.factor_tangent(&eq.q)?;
                let dqdp = Sensitivity::at(self.model(), &eq.u, &tangent.factors)?.dq_dp(&eq.q)?;
                self.tracker.keep_factors(&eq.q, tangent.factors)?;
                dqdp
            }
        };
        Ok((self.effector_columns(&dqdp), dqdp))
    }

    /// `A_x ∂q/∂P`: the end effector's rows of the columns of `dqdp`.
    fn effector_columns(&self, dqdp: &DMatrix<f64>) -> DMatrix<f64> {
        let d = self.effector.position.len();
        let mut jac = DMatrix::zeros(d, dqdp.ncols());
        for (c, col) in dqdp.column_iter().enumerate() {
            for (r, v) in self
                .effector
                .position_at(col.as_slice())
                .into_iter()
                .enumerate()
            {
                jac[(r, c)] = v;
            }
        }
        jac
    }

    /// `f_IK(x_d, F̂)`: the pressures putting the end effector at `x_d`
    /// under the load field `f_hat` (`n_q` entries; zeros for none), warm
    /// from the last solve.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (field `x_d`) for a non-finite target,
    /// (field `f_hat`) for a non-finite load field;
    /// [`Error::DimensionMismatch`] for wrong sizes; the static solver's
    /// errors when no equilibrium is found. An unreachable target is not an
    /// error: see [`IkStatus::Unreachable`].
    pub fn solve(&mut self, x_d: &[f64], f_hat: &[f64]) -> Result<IkSolution> {
        check_len("x_d", self.effector.position.len(), x_d.len())?;
        check_all_finite("x_d", x_d)?;
        check_len("f_hat", self.n_load_params(), f_hat.len())?;
        check_all_finite("f_hat", f_hat)?;
        let np = self.range.len();
        let bounds = self.model().pressure_bounds();
        self.spent = 0;
        let start = match self.warm.take() {
            Some(h) => Start::Warm(Box::new(h)),
            None => Start::Cold({
                // the known pressures are checked against the bounds
                let known = self.model().pressures_of(&self.known);
                if known.len() == np {
                    known
                } else {
                    bounds.iter().map(|(lo, _)| *lo).collect()
                }
            }),
        };
        // the warm start; a static solve that fails from it is not the end:
        // the starts below are cold
        let near_unreached = self.unreached_target.take().is_some_and(|t| {
            t.iter()
                .zip(x_d)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt()
                <= RESTART_RADIUS_M
        });
        let (mut best, first_err) = match self.solve_from(x_d, f_hat, start) {
            Ok((s, eq)) if s.status.is_reached() => {
                self.hold(&s, f_hat, eq);
                return Ok(s);
            }
            Ok((s, eq)) if near_unreached => {
                self.hold(&s, f_hat, eq);
                self.unreached_target = Some(x_d.to_vec());
                return Ok(s);
            }
            Ok(s) => (Some(s), None),
            Err(e) => (None, Some(e)),
        };
        // not reached from the warm start: a local minimum of the distance
        // is possible (the workspace folds), so try every chamber at its
        // minimum or mid-range (2^n starts, n ≤ 6) and keep the closest
        let n_starts = if np <= 6 { 1usize << np } else { 2 };
        let mut iterations = best.as_ref().map_or(0, |b| b.0.iterations);
        for code in 0..n_starts {
            if self.spent >= self.settings.max_static_iterations {
                break;
            }
            let p: Vec<f64> = bounds
                .iter()
                .enumerate()
                .map(|(c, (lo, hi))| {
                    if (np <= 6 && code >> c & 1 == 1) || (np > 6 && code == 1) {
                        0.5 * (lo + hi)
                    } else {
                        *lo
                    }
                })
                .collect();
            let Ok(s) = self.solve_from(x_d, f_hat, Start::Cold(p)) else {
                continue;
            };
            iterations += s.0.iterations;
            if best
                .as_ref()
                .is_none_or(|b| s.0.status.error_m() < b.0.status.error_m())
            {
                let reached = s.0.status.is_reached();
                best = Some(s);
                if reached {
                    break;
                }
            }
        }
        let Some((mut best, eq)) = best else {
            return Err(first_err.unwrap_or_else(|| {
                Error::invalid(
                    "x_d",
                    format!("{x_d:?}"),
                    "no start of the inverse kinematics found an equilibrium",
                )
            }));
        };
        best.iterations = iterations;
        self.hold(&best, f_hat, eq);
        if !best.status.is_reached() {
            self.unreached_target = Some(x_d.to_vec());
        }
        Ok(best)
    }

    /// As [`InverseKinematics::solve`], but starting from the pressures
    /// `p0_pa` (Pa, within their bounds) instead of the last solution: the
    /// solution nearest a known command where the workspace folds.
    ///
    /// # Errors
    /// As [`InverseKinematics::solve`]; [`Error::InvalidParameter`] (field
    /// `pressures_pa[i]`) for a start outside the bounds.
    pub fn solve_starting_at(
        &mut self,
        x_d: &[f64],
        f_hat: &[f64],
        p0_pa: &[f64],
    ) -> Result<IkSolution> {
        check_len("pressures_pa", self.range.len(), p0_pa.len())?;
        let model = self.model();
        model.validate_loads(&model.with_pressures(&self.known, p0_pa))?;
        check_len("f_hat", self.n_load_params(), f_hat.len())?;
        check_all_finite("f_hat", f_hat)?;
        let eq = self.forward_raw(p0_pa, f_hat, None)?;
        self.warm = Some(Held {
            p: p0_pa.to_vec(),
            f_hat: f_hat.to_vec(),
            eq,
        });
        self.unreached_target = None;
        self.solve(x_d, f_hat)
    }

    /// Keeps the solution `s` under the load field `f_hat` (its
    /// equilibrium `eq`, with the factors of its tangent) as the next
    /// solve's warm start.
    fn hold(&mut self, s: &IkSolution, f_hat: &[f64], eq: Eq) {
        self.warm = Some(Held {
            p: s.pressures_pa.as_slice().to_vec(),
            f_hat: f_hat.to_vec(),
            eq,
        });
    }

    /// Newton from `start` (the held equilibrium, or cold at pressures);
    /// the solution and its equilibrium (with the factors of the tangent at
    /// its shape when the corrector made it).
    fn solve_from(&mut self, x_d: &[f64], f_hat: &[f64], start: Start) -> Result<(IkSolution, Eq)> {
        let (p, eq) = self.first_equilibrium(f_hat, start)?;
        let phi = self.merit(x_d, &eq.x, &p);
        let mut it = NewtonIterate {
            p,
            eq,
            phi,
            damping: 0.0,
        };
        let mut iterations = 0;
        let mut stalled = false;
        let mut failed_trials = 0usize;
        while iterations < self.settings.max_iterations
            && self.spent < self.settings.max_static_iterations
            && !(self.settings.stop_when_reached
                && distance(&it.eq.x, x_d) <= self.settings.tolerance_m)
        {
            iterations += 1;
            let Some(step) = self.newton_step(&it, x_d, f_hat)? else {
                stalled = true;
                break;
            };
            let accepted = self.backtrack(&mut it, &step, x_d, f_hat, &mut failed_trials);
            if failed_trials >= FAILED_TRIALS {
                // the iterate sits at a fold of the equilibria: the closest
                // pose on this branch
                stalled = true;
                break;
            }
            if !accepted && it.damping < 1.0 {
                // a shorter, more gradient-like step before giving up
                it.damping = (16.0 * it.damping).max(1e-3);
                continue;
            }
            if !accepted {
                stalled = true;
                break;
            }
        }
        Ok(self.solution(it, x_d, stalled, iterations))
    }

    /// The step of one Newton iteration at `it`: the bounded least-squares
    /// problem of the [module documentation](self) in the scaled pressures,
    /// solved exactly; `None` where it is too small to move (a stationary
    /// point of the merit in the bounds).
    #[allow(non_snake_case)]
    fn newton_step(
        &mut self,
        it: &NewtonIterate,
        x_d: &[f64],
        f_hat: &[f64],
    ) -> Result<Option<NewtonStep>> {
        let d = self.effector.position.len();
        let np = self.range.len();
        let (J, dqdp) = self.jacobian_warm(&it.eq, &it.p, f_hat)?;
        // scaled Jacobian Ĵ = J diag(range), residual r = x_d − x
        let Jh = DMatrix::from_fn(d, np, |r, c| J[(r, c)] * self.range[c]);
        let r: Vec<f64> = x_d.iter().zip(&it.eq.x).map(|(a, b)| a - b).collect();
        let ph: Vec<f64> = it.p.iter().zip(&self.range).map(|(p, r)| p / r).collect();
        let w = 1.0 / (ELL_M * ELL_M);
        let (mu, lambda) = (
            self.settings.pressure_weight,
            self.settings.null_space_damping,
        );
        let mut H = Jh.transpose() * &Jh * w + DMatrix::identity(np, np) * (mu + lambda);
        // Levenberg–Marquardt damping: the Gauss–Newton model leaves out
        // the curvature of x(P), which dominates far from the target
        let hmax = H.diagonal().amax();
        H += DMatrix::identity(np, np) * (it.damping * hmax);
        let g: Vec<f64> = (0..np)
            .map(|c| -w * (0..d).map(|k| Jh[(k, c)] * r[k]).sum::<f64>() + mu * ph[c])
            .collect();
        let step = self.settings.max_step;
        let lo: Vec<f64> = (0..np).map(|c| (self.lo[c] - ph[c]).max(-step)).collect();
        let hi: Vec<f64> = (0..np).map(|c| (self.hi[c] - ph[c]).min(step)).collect();
        let sol = boxqp::solve(&H, &g, &lo, &hi)?;
        let dec: f64 = -g.iter().zip(&sol.x).map(|(a, b)| a * b).sum::<f64>();
        let small = sol.x.iter().fold(0.0f64, |m, v| m.max(v.abs())) <= 1e-7;
        if small || dec <= 1e-10 * it.phi.max(1e-2) {
            return Ok(None);
        }
        Ok(Some(NewtonStep { sol, ph, dec, dqdp }))
    }

    /// Backtracking on the merit along `step` from `it` (pressures at a
    /// bound stay on it for a full step; shorter steps keep them inside);
    /// `it` moves to the accepted trial and its damping is adapted. Whether
    /// a trial was accepted; `failed_trials` counts the trials without an
    /// equilibrium.
    fn backtrack(
        &mut self,
        it: &mut NewtonIterate,
        step: &NewtonStep,
        x_d: &[f64],
        f_hat: &[f64],
        failed_trials: &mut usize,
    ) -> bool {
        let np = self.range.len();
        let bounds_pa = self.model().pressure_bounds();
        let mut t = 1.0;
        for _ in 0..12 {
            let trial: Vec<f64> = (0..np)
                .map(|c| {
                    let (lo_pa, hi_pa) = bounds_pa[c];
                    match (t == 1.0, step.sol.sides[c]) {
                        (true, boxqp::Side::Lower) => lo_pa,
                        (true, boxqp::Side::Upper) => hi_pa,
                        // inside by the QP's feasibility; the clamp only
                        // takes off round-off of the scaling
                        _ => ((step.ph[c] + t * step.sol.x[c]) * self.range[c]).clamp(lo_pa, hi_pa),
                    }
                })
                .collect();
            // the trial's equilibrium predicted to first order,
            // q + ∂q/∂P ΔP, corrected (the static solver from q if not)
            let dp = DVector::from_iterator(np, trial.iter().zip(&it.p).map(|(a, b)| a - b));
            let predicted: Vec<f64> = it
                .eq
                .q
                .iter()
                .zip((&step.dqdp * dp).iter())
                .map(|(a, b)| a + b)
                .collect();
            let q = it.eq.q.clone();
            match self.equilibrium(&trial, f_hat, &predicted, &q, true) {
                Err(_) => *failed_trials += 1,
                Ok(eq) => {
                    let phit = self.merit(x_d, &eq.x, &trial);
                    if phit <= it.phi - 1e-4 * t * step.dec {
                        let ratio = (it.phi - phit) / step.dec.max(f64::MIN_POSITIVE);
                        let damping = it.damping;
                        it.damping = if t < 1.0 || ratio < 0.25 {
                            (4.0 * damping).max(1e-4)
                        } else if ratio > 0.75 {
                            if damping < 1e-10 { 0.0 } else { damping / 4.0 }
                        } else {
                            damping
                        };
                        it.p = trial;
                        it.eq = eq;
                        it.phi = phit;
                        return true;
                    }
                }
            }
            t *= 0.5;
        }
        false
    }

    /// The merit of the Newton loop at the end-effector position `x` and the
    /// pressures `p`: `½ |x_d − x|² / ℓ² + ½ μ |P̂|²`.
    fn merit(&self, x_d: &[f64], x: &[f64], p: &[f64]) -> f64 {
        let r2: f64 = x.iter().zip(x_d).map(|(a, b)| (b - a).powi(2)).sum();
        let p2: f64 = p
            .iter()
            .zip(&self.range)
            .map(|(p, r)| (p / r).powi(2))
            .sum();
        0.5 * r2 / (ELL_M * ELL_M) + 0.5 * self.settings.pressure_weight * p2
    }

    /// The solution at the last iterate: its status from the distance to
    /// `x_d` (reached within the tolerance, else unreachable when the
    /// iteration stalled, else the iteration limit) and where each pressure
    /// sits relative to its bounds.
    fn solution(
        &self,
        it: NewtonIterate,
        x_d: &[f64],
        stalled: bool,
        iterations: usize,
    ) -> (IkSolution, Eq) {
        let error_m = distance(&it.eq.x, x_d);
        let status = if error_m <= self.settings.tolerance_m {
            IkStatus::Reached { error_m }
        } else if stalled {
            IkStatus::Unreachable {
                distance_m: error_m,
            }
        } else {
            IkStatus::IterationLimit { error_m }
        };
        let bounds =
            it.p.iter()
                .zip(&self.model().pressure_bounds())
                .map(|(p, (lo, hi))| {
                    if p == lo {
                        PressureBound::Min
                    } else if p == hi {
                        PressureBound::Max
                    } else {
                        PressureBound::Inside
                    }
                })
                .collect();
        (
            IkSolution {
                pressures_pa: DVector::from_vec(it.p),
                q: DVector::from_vec(it.eq.q.clone()),
                effector_m: DVector::from_vec(it.eq.x.clone()),
                status,
                iterations,
                bounds,
            },
            it.eq,
        )
    }
}

/// `|x − x_d|` (m).
fn distance(x: &[f64], x_d: &[f64]) -> f64 {
    x.iter()
        .zip(x_d)
        .map(|(a, b)| (a - b).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// The Newton loop's iterate: pressures, their equilibrium, merit and the
/// Levenberg–Marquardt damping.
#[derive(Debug)]
struct NewtonIterate {
    p: Vec<f64>,
    eq: Eq,
    phi: f64,
    damping: f64,
}

/// One Newton step: the box QP's solution in the scaled pressures, the
/// scaled pressures it starts from, the predicted decrease of the merit and
/// the sensitivities `∂q/∂P` at the iterate.
#[derive(Debug)]
struct NewtonStep {
    sol: boxqp::BoxQpSolution,
    ph: Vec<f64>,
    dec: f64,
    dqdp: DMatrix<f64>,
}
