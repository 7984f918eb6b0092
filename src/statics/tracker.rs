//! Equilibria at a sequence of nearby loads: the static solver's warm
//! tracker, one for every model ([`Tracker`] over any [`Model`]: the
//! clamped [`Robot`] of the estimators, a [`crate::structure::Structure`]
//! such as the parallel robot, the robot of the inverse kinematics).
//!
//! An estimator (or a controller) asks for the equilibrium `R(u) = 0` (17)
//! at many loads close to each other, each from a nearby shape. The loads
//! are the tracker's known loads ([`Tracker::set_known`], or
//! [`Tracker::set_loads`] to keep the factors) plus, for an estimator, a
//! load linear in parameters `F`, `Q_F = G F` ([`LinearLoad`]). The tracker keeps the last factorization of the
//! tangent `K` and the last solved state, so that
//!
//! - asked again at the same `(F, q)`, it answers at once;
//! - from the shape of its last solution, the residual at a new `F'` is
//!   `R(q, F') = R(q, F) + Tᵀ G (F' − F)`, with no new residual evaluation;
//! - its warm iterations ([`WarmStrategy`]) take chord (modified Newton)
//!   steps with the kept factors, or plain Newton steps, before the
//!   globalized [`StaticSolver`] (line search, homotopy) as the fallback of
//!   [`Tracker::solve`] ([`Tracker::try_solve`] has none).
//!
//! The strategies (each what one caller measured fastest):
//!
//! - [`WarmStrategy::ChordThenNewton`] (the estimators'): chord steps, then
//!   plain Newton steps; it ends with a step below `1e-10 L` (or, in chord
//!   steps, with one after which the contraction so far predicts less than
//!   that to go) and factors the tangent at its solution (unless the
//!   solution did not move from the point the kept factors belong to):
//!   the sensitivities ([`crate::sensitivity`]) of that equilibrium use
//!   them;
//! - [`WarmStrategy::ChordRefactor`] (the parallel robot's, whose tangent
//!   costs thirty residuals): chord steps only, the tangent refactored
//!   where they stop halving, a few times per solve; its factors are those
//!   of the last factorization, not the solution's;
//! - [`WarmStrategy::Newton`] (the inverse kinematics' corrector): plain
//!   Newton from a predicted start, one residual and tangent per step,
//!   ending at the first iterate that passes the residual test with a
//!   positive definite tangent, whose factors it hands back.
//!
//! Every answer carries a [`WarmStatus`] set by the static solver's residual
//! test evaluated on the returned `q` (not by the step test that ended the
//! iteration), and the [`WarmPath`] that found it.
//!
//! The tangent is factored by an [`AutoSolver`] of the kind
//! [`StaticSettings::linear_solver`] asks for, analyzed once on the
//! model's tangent pattern when the tracker is made: every later
//! factorization (chord, Newton, fallback, [`Tracker::factor_tangent`])
//! reuses that analysis.

use nalgebra::DVector;
use serde::Serialize;

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{Error, Result, check_len};
use crate::linsolve::{
    AutoFactors, AutoSolver, FactorOptions, Factorization, SymmetricMatrix, TangentSolver,
};
use crate::numeric::{max_abs, norm2};
use crate::structure::Model;

use super::{Equilibrium, StaticSettings, StaticSolver, residual_floor};

/// A load linear in a parameter vector `F` on a model `M`: its generalized
/// force over all coordinates is `G F` with a constant `G` (the distributed
/// field (8) with `G = J_QF` (22), (23), a concentrated force at a site
/// (32)–(35), …). The [`Tracker`] solves with it, the
/// [`Sensitivity`](crate::sensitivity::Sensitivity) differentiates through
/// it, the estimators estimate its `F`.
///
/// # Example
/// A force on node 20's `y` coordinate of the clamped robot:
/// ```
/// use softrod::{assembly::Robot, element::Element, loads::{Loads, PointForce}};
/// use softrod::statics::LinearLoad;
/// use nalgebra::DVector;
/// struct TipY;
/// impl<E: Element> LinearLoad<Robot<E>> for TipY {
///     fn n_params(&self, _: &Robot<E>) -> usize { 1 }
///     fn force(&self, robot: &Robot<E>, f: &[f64]) -> softrod::Result<DVector<f64>> {
///         let mut g = DVector::zeros(robot.n_q());
///         g[20 * E::NODE_DOFS + 1] = f[0];
///         Ok(g)
///     }
///     fn force_transpose(&self, _: &Robot<E>, v: &[f64]) -> softrod::Result<DVector<f64>> {
///         Ok(DVector::from_element(1, v[20 * E::NODE_DOFS + 1]))
///     }
///     fn add_to(&self, robot: &Robot<E>, known: &Loads, f: &[f64]) -> Loads {
///         let mut loads = known.clone();
///         loads.point_forces.push(PointForce { s_m: robot.node_arc()[20], force_n: vec![0.0, f[0]] });
///         loads
///     }
/// }
/// let robot = softrod::scene::Scene::two_section().robot()?;
/// assert_eq!(LinearLoad::force(&TipY, &robot, &[2.0])?[81], 2.0);
/// # Ok::<(), softrod::Error>(())
/// ```
pub trait LinearLoad<M: Model> {
    /// Number of parameters `n_F`.
    fn n_params(&self, model: &M) -> usize;
    /// `G F` over all `n_q` coordinates (N).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `f` has the wrong length.
    fn force(&self, model: &M, f: &[f64]) -> Result<DVector<f64>>;
    /// `Gᵀ v` for `v` over all `n_q` coordinates.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `v` has the wrong length.
    fn force_transpose(&self, model: &M, v: &[f64]) -> Result<DVector<f64>>;
    /// The loads `known` with `F` added, for the globalized static solver.
    fn add_to(&self, model: &M, known: &M::Loads, f: &[f64]) -> M::Loads;
}

/// How a warm solve ended, by the static solver's residual test evaluated
/// on the returned `q`: `|R(q)|₂ ≤ max(tol, floor)` with
/// `tol = residual_tolerance · |applied forces|₂` at the solve's start (as
/// [`StaticSolver`] states its tolerance) and the round-off floor
/// [`residual_floor`] of the last factored tangent's `|K|max`.
///
/// # Example
/// ```
/// use softrod::statics::WarmStatus;
/// assert!(WarmStatus::Converged.is_converged());
/// assert!(!WarmStatus::Unconfirmed.is_converged());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[non_exhaustive]
pub enum WarmStatus {
    /// The residual test holds on the returned `q`.
    Converged,
    /// The iteration's step test ended it (a step below the step
    /// tolerance, or chord steps whose contraction predicts less than that
    /// left) but the residual at the returned `q` is above the residual
    /// test: an answer as close as the steps tell, which the residual does
    /// not certify.
    AboveResidualTest,
    /// The step test ended the iteration and the residual at the returned
    /// `q` was not evaluated ([`WarmStrategy::ChordRefactor`] with
    /// `confirm: false`, which saves a residual per solve); the reported
    /// residual is that of the iterate before the last step.
    Unconfirmed,
}

impl WarmStatus {
    /// Whether the residual test holds on the returned `q`.
    pub fn is_converged(&self) -> bool {
        matches!(self, WarmStatus::Converged)
    }
}

/// Which path of the tracker found an equilibrium.
///
/// # Example
/// ```
/// assert_ne!(softrod::statics::WarmPath::Chord, softrod::statics::WarmPath::Fallback);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[non_exhaustive]
pub enum WarmPath {
    /// Asked again at the last solution: answered from memory.
    Repeated,
    /// Chord steps with kept factors (refactored or not).
    Chord,
    /// Plain Newton steps.
    Newton,
    /// The globalized [`StaticSolver`].
    Fallback,
}

/// The warm iterations of a [`Tracker`] (see the [module
/// documentation](self)).
///
/// # Example
/// ```
/// use softrod::statics::WarmStrategy;
/// assert!(WarmStrategy::Newton { max_steps: 6 }.validate().is_ok());
/// assert!(WarmStrategy::Newton { max_steps: 0 }.validate().is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub enum WarmStrategy {
    /// Up to 12 chord steps with the kept factors, each applied only if it
    /// is shorter than half the last and than a quarter of the model's
    /// length; then, from the start again, up to 12 plain Newton steps,
    /// each shorter than 0.9 of the last; a step below `1e-10 L` (or chord
    /// steps whose contraction predicts that) ends
    /// it, and the tangent is factored at the solution.
    ChordThenNewton,
    /// Chord steps with the kept factors (factored at the start if none
    /// are kept); where a step does not halve the last, the tangent is
    /// refactored at the iterate, at most `max_factorizations` times per
    /// solve, up to `max_residuals` residuals; a step below
    /// `step_tolerance_m` ends it. The kept factors stay those of the last
    /// factorization. With `confirm`, the residual at the answer is
    /// evaluated for its status (one residual more per solve); without,
    /// the status is [`WarmStatus::Unconfirmed`].
    ChordRefactor {
        /// Factorizations per solve at most (the first included).
        max_factorizations: usize,
        /// Residual evaluations per solve at most.
        max_residuals: usize,
        /// A step (its largest entry, m or unit slope) below this ends the
        /// solve.
        step_tolerance_m: f64,
        /// Evaluate the residual at the answer.
        confirm: bool,
    },
    /// Plain Newton from the start, one residual and tangent per iterate:
    /// the first iterate whose residual passes the static solver's
    /// tolerance and whose tangent is positive definite is the answer; it
    /// gives up at a tangent that is not positive definite, a residual that
    /// does not shrink, a step turning a slope more than
    /// [`StaticSettings::max_step_rotation`], more than `max_steps` steps.
    Newton {
        /// Newton steps at most.
        max_steps: usize,
    },
}

impl WarmStrategy {
    /// Checks the strategy's numbers.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`max_factorizations`,
    /// `max_residuals`, `step_tolerance_m`, `max_steps`).
    pub fn validate(&self) -> Result<()> {
        match *self {
            WarmStrategy::ChordThenNewton => Ok(()),
            WarmStrategy::ChordRefactor {
                max_factorizations,
                max_residuals,
                step_tolerance_m,
                ..
            } => {
                if max_factorizations == 0 {
                    return Err(Error::invalid("max_factorizations", 0, "must be >= 1"));
                }
                if max_residuals == 0 {
                    return Err(Error::invalid("max_residuals", 0, "must be >= 1"));
                }
                crate::error::check_positive("step_tolerance_m", step_tolerance_m)
            }
            WarmStrategy::Newton { max_steps: 0 } => {
                Err(Error::invalid("max_steps", 0, "must be >= 1"))
            }
            WarmStrategy::Newton { .. } => Ok(()),
        }
    }
}

/// What the warm solves of a [`Tracker`] cost so far.
///
/// # Example
/// ```
/// let c = softrod::statics::WarmCounts::default();
/// assert_eq!(c.factorizations, 0);
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct WarmCounts {
    /// Solves asked for.
    pub solves: usize,
    /// Residual evaluations of the warm iterations (chord steps, the
    /// answer's; not the fallback's).
    pub residuals: usize,
    /// Tangent assemblies and factorizations (the fallback's own not
    /// counted, the one at its answer counted).
    pub factorizations: usize,
    /// Solves that fell back to the globalized [`StaticSolver`].
    pub fallbacks: usize,
    /// Chord and Newton steps applied.
    pub steps: usize,
}

/// The counts of two trackers together (a controller's estimator and
/// inverse kinematics).
///
/// # Example
/// ```
/// use softrod::statics::WarmCounts;
/// let a = WarmCounts { solves: 2, steps: 3, ..WarmCounts::default() };
/// assert_eq!((a + a).solves, 4);
/// ```
impl std::ops::Add for WarmCounts {
    type Output = WarmCounts;

    fn add(self, o: WarmCounts) -> WarmCounts {
        WarmCounts {
            solves: self.solves + o.solves,
            residuals: self.residuals + o.residuals,
            factorizations: self.factorizations + o.factorizations,
            fallbacks: self.fallbacks + o.fallbacks,
            steps: self.steps + o.steps,
        }
    }
}

/// A solved equilibrium of the tracker: the shape, the factored tangent,
/// its residual and how it was found.
///
/// # Example
/// See [`Tracker`] and [`crate::sensitivity`].
#[derive(Debug, Clone)]
pub struct TrackedEquilibrium {
    /// All coordinates (m, dimensionless slopes).
    pub q: DVector<f64>,
    /// The free coordinates of `q`.
    pub u: DVector<f64>,
    /// The factors of the tangent `K` at `q` (see the [module
    /// documentation](self): [`WarmStrategy::ChordRefactor`] keeps those
    /// of its last factorization; a solution that did not move from the
    /// kept factors' point, or Newton's last step below `1e-10 L`, keeps
    /// the factors of a point that close).
    pub factors: AutoFactors,
    /// `|R|_2` at `q` (N; see [`WarmStatus::Unconfirmed`]).
    pub residual_n: f64,
    /// The residual test on `q`.
    pub status: WarmStatus,
    /// The path that found it.
    pub path: WarmPath,
}

/// A tangent stiffness `K` over the free coordinates and its factors, as
/// one call of [`Tracker::factor_tangent`] made them: whoever needs `K`
/// itself (its entries for a QP, its largest entry for a round-off floor)
/// takes it from here, next to the factors of the same matrix.
///
/// # Example
/// ```
/// use softrod::linsolve::Factorization;
/// use softrod::{scene::Scene, statics::EquilibriumTracker};
/// let scene = Scene::two_section();
/// let mut tracker = EquilibriumTracker::new(scene.robot()?, scene.loads()?, Default::default())?;
/// let q = tracker.robot().reference_configuration().as_slice().to_vec();
/// let t = tracker.factor_tangent(&q)?;
/// assert!(t.factors.is_positive_definite()); // the straight robot is stable
/// assert_eq!(t.matrix.n(), t.factors.n());
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct FactoredTangent {
    /// `K = −∂R/∂u` over the free coordinates (N/m and N per unit slope).
    pub matrix: SymmetricMatrix,
    /// Its factors.
    pub factors: AutoFactors,
}

/// The kept factorization: the shape it was taken at, the factors and the
/// largest entry of the tangent (0 when unknown: factors kept from outside).
#[derive(Debug, Clone)]
struct Kept {
    q: Vec<f64>,
    factors: AutoFactors,
    k_max: f64,
}

/// The last solved state: its load, shape, residual and status.
#[derive(Debug, Clone)]
struct State {
    f: Vec<f64>,
    u: Vec<f64>,
    q: Vec<f64>,
    r: Vec<f64>,
    residual_n: f64,
    status: WarmStatus,
}

/// The iterate of a warm solve and its scratch: free coordinates `u`, all
/// coordinates `q = φ(u)`, the residual `r`, the step `du` (`dq = T du`)
/// and the next point `(u1, q1)`.
struct Iterate {
    u: Vec<f64>,
    q: Vec<f64>,
    r: Vec<f64>,
    du: Vec<f64>,
    dq: Vec<f64>,
    u1: Vec<f64>,
    q1: Vec<f64>,
}

impl Iterate {
    fn new(u: &[f64], q: &[f64]) -> Self {
        Iterate {
            u: u.to_vec(),
            q: q.to_vec(),
            r: vec![0.0; u.len()],
            du: vec![0.0; u.len()],
            dq: vec![0.0; q.len()],
            u1: u.to_vec(),
            q1: q.to_vec(),
        }
    }

    /// Back to the start `(u, q)`.
    fn restart(&mut self, u: &[f64], q: &[f64]) {
        self.u.copy_from_slice(u);
        self.q.copy_from_slice(q);
    }
}

/// One warm solve's target: the load parameters, the dead force with `G F`
/// and the residual test's tolerance.
struct Target<'a> {
    f: &'a [f64],
    dead: &'a [f64],
    tolerance_n: f64,
}

/// Equilibria of a model under known loads (plus a [`LinearLoad`]) at a
/// sequence of nearby loads (see the [module documentation](self)).
///
/// # Example
/// A structure (two legs holding a platform) pushed a little more each
/// time, warm from the last equilibrium:
/// ```
/// use softrod::assembly::Section;
/// use softrod::statics::{StaticSettings, Tracker, WarmPath};
/// use softrod::structure::{Assembled, BodyLoad, JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureLoads, StructureSpec};
/// let leg = |x: f64| RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(x, 0.0), nalgebra::Vector2::new(0.0, 1.0));
/// let joint = |rod| JointSpec::RodToBody { rod, end: RodEnd::End, body: 0, point_m: None, direction: None };
/// let s = StructureSpec::new(
///     vec![leg(-0.05), leg(0.05)],
///     vec![RigidBodySpec { mass_kg: 0.05, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
///     vec![joint(0), joint(1)],
/// ).build_planar()?;
/// let push = |fx: f64| StructureLoads { bodies: vec![BodyLoad { body: 0, force_n: vec![fx, 0.0], moment_nm: vec![0.0] }], ..StructureLoads::default() };
/// let mut tracker = Tracker::new(s.clone(), push(0.1), StaticSettings::default())?;
/// let u0 = s.reference_free_coordinates();
/// let first = tracker.solve_free(u0)?; // far from the start: the fallback
/// tracker.set_loads(push(0.11))?;
/// let next = tracker.solve_free(first.u.as_slice())?;
/// assert!(next.status.is_converged() && next.path != WarmPath::Fallback);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct Tracker<M: Model> {
    model: M,
    known: M::Loads,
    /// Dead force of the known loads (`n_q`).
    dead_known: DVector<f64>,
    solver: StaticSolver,
    /// The linear solver, analyzed once on the model's tangent pattern.
    linear: AutoSolver,
    /// Tangent buffer.
    kmat: SymmetricMatrix,
    /// The last factorization of `K` and the shape it was taken at.
    kept: Option<Kept>,
    /// The last solved equilibrium.
    state: Option<State>,
    strategy: WarmStrategy,
    counts: WarmCounts,
}

/// The warm tracker of a clamped robot (the estimators').
///
/// # Example
/// ```
/// use softrod::{estimate::LoadModel, scene::Scene, statics::{EquilibriumTracker, StaticSettings}};
/// let scene = Scene::two_section();
/// let robot = scene.robot()?;
/// let n = robot.n_q();
/// let mut tracker = EquilibriumTracker::new(robot, scene.loads()?, StaticSettings::default())?;
/// let load = LoadModel::Distributed;
/// let q0 = tracker.solve(&load, &vec![0.0; n], tracker.robot().arc_configuration(&[]).as_slice())?.q;
/// // a small uniform downward load: a warm solve from q0
/// let mut f = vec![0.0; n];
/// f.iter_mut().skip(1).step_by(4).for_each(|w| *w = -0.1);
/// let eq = tracker.solve(&load, &f, q0.as_slice())?;
/// assert!(eq.q[n - 3] < q0[n - 3] && eq.residual_n < 1e-8);
/// # Ok::<(), softrod::Error>(())
/// ```
pub type EquilibriumTracker<E> = Tracker<Robot<E>>;

impl<E: Element> Tracker<Robot<E>> {
    /// The robot.
    pub fn robot(&self) -> &Robot<E> {
        &self.model
    }
}

impl<M: Model> Tracker<M> {
    /// A tracker for `model` under the known loads `known`, with the
    /// estimators' [`WarmStrategy::ChordThenNewton`]; `settings` are those
    /// of the globalized fallback solve and of the residual test, and
    /// [`StaticSettings::linear_solver`] picks the linear solver of every
    /// factorization (its pattern analyzed here, once).
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for invalid settings; the errors of
    /// [`Assembled::dead_force`](crate::structure::Assembled::dead_force); [`crate::Error::TooLarge`] if the tangent's
    /// factors cannot be stored.
    ///
    /// # Example
    /// ```
    /// use softrod::linsolve::SolverKind;
    /// use softrod::{scene::Scene, statics::{EquilibriumTracker, StaticSettings}};
    /// let scene = Scene::two_section();
    /// let settings = StaticSettings { linear_solver: SolverKind::Sparse, ..Default::default() };
    /// let tracker = EquilibriumTracker::new(scene.robot()?, scene.loads()?, settings)?;
    /// assert_eq!(tracker.solver_kind(), SolverKind::Sparse);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn new(model: M, known: M::Loads, settings: StaticSettings) -> Result<Self> {
        let pattern = model.tangent_pattern()?;
        let linear = AutoSolver::with_kind(&pattern, settings.linear_solver)?;
        let solver = StaticSolver::new(settings)?;
        let dead_known = model.dead_force(&known)?;
        Ok(Tracker {
            kmat: SymmetricMatrix::zeros(pattern),
            linear,
            model,
            known,
            dead_known,
            solver,
            kept: None,
            state: None,
            strategy: WarmStrategy::ChordThenNewton,
            counts: WarmCounts::default(),
        })
    }

    /// The tracker with another warm strategy (the kept factors and state
    /// stay).
    ///
    /// # Errors
    /// As [`WarmStrategy::validate`].
    ///
    /// # Example
    /// ```
    /// use softrod::{scene::Scene, statics::{EquilibriumTracker, WarmStrategy}};
    /// let scene = Scene::two_section();
    /// let t = EquilibriumTracker::new(scene.robot()?, scene.loads()?, Default::default())?
    ///     .with_strategy(WarmStrategy::Newton { max_steps: 6 })?;
    /// assert_eq!(t.strategy(), WarmStrategy::Newton { max_steps: 6 });
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn with_strategy(mut self, strategy: WarmStrategy) -> Result<Self> {
        self.set_strategy(strategy)?;
        Ok(self)
    }

    /// Replaces the warm strategy in place ([`Tracker::with_strategy`]).
    pub(crate) fn set_strategy(&mut self, strategy: WarmStrategy) -> Result<()> {
        strategy.validate()?;
        self.strategy = strategy;
        Ok(())
    }

    /// The model.
    pub fn model(&self) -> &M {
        &self.model
    }

    /// The known loads.
    pub fn known(&self) -> &M::Loads {
        &self.known
    }

    /// The settings of the fallback solve and the residual test.
    pub fn settings(&self) -> &StaticSettings {
        &self.solver.settings
    }

    /// The warm strategy.
    pub fn strategy(&self) -> WarmStrategy {
        self.strategy
    }

    /// What the solves cost so far.
    pub fn counts(&self) -> WarmCounts {
        self.counts
    }

    /// The linear solver in use ([`SolverKind::Auto`] resolved at
    /// [`Tracker::new`]).
    ///
    /// [`SolverKind::Auto`]: crate::linsolve::SolverKind::Auto
    pub fn solver_kind(&self) -> crate::linsolve::SolverKind {
        self.linear.kind()
    }

    /// The kept factors, if any (those of the last solve's answer or
    /// factorization, see [`TrackedEquilibrium::factors`]).
    pub fn kept_factors(&self) -> Option<&AutoFactors> {
        self.kept.as_ref().map(|k| &k.factors)
    }

    /// Takes `other`'s kept factors (with their point and largest entry),
    /// if it has any: for two trackers of one model whose solves are near
    /// each other (a controller's estimator and inverse kinematics, at the
    /// same command), the factorization one made serves the other's chord
    /// steps, which check their own contraction.
    pub(crate) fn keep_from(&mut self, other: &Tracker<M>) {
        if let Some(k) = &other.kept {
            self.kept = Some(k.clone());
        }
    }

    /// The dead force of the known loads plus `G F` (`n_q`, N).
    ///
    /// # Errors
    /// As [`LinearLoad::force`]; [`crate::Error::DimensionMismatch`] if
    /// the load's force does not have `n_q` entries.
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::LoadModel;
    /// use softrod::{scene::Scene, statics::{EquilibriumTracker, StaticSettings}};
    /// let scene = Scene::two_section();
    /// let (robot, known) = (scene.robot()?, scene.loads()?);
    /// let dead_known = robot.dead_force(&known)?;
    /// let tracker = EquilibriumTracker::new(robot, known, StaticSettings::default())?;
    /// let f = vec![0.0; tracker.robot().n_q()];
    /// // F = 0: the known loads' dead force alone
    /// assert_eq!(tracker.dead_with(&LoadModel::Distributed, &f)?, dead_known);
    /// let q = tracker.robot().reference_configuration().as_slice().to_vec();
    /// let r = tracker.residual(&LoadModel::Distributed, q.as_slice(), &f)?;
    /// assert_eq!(r.len(), tracker.robot().n_free());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn dead_with<L: LinearLoad<M> + ?Sized>(
        &self,
        load: &L,
        f: &[f64],
    ) -> Result<DVector<f64>> {
        let mut dead = load.force(&self.model, f)?;
        check_len("G F", self.dead_known.len(), dead.len())?;
        dead += &self.dead_known;
        Ok(dead)
    }

    /// The residual `R` over the free coordinates at `(q, F)` (N).
    ///
    /// # Errors
    /// As [`LinearLoad::force`] and [`Assembled::residual_into`](crate::structure::Assembled::residual_into).
    ///
    /// # Example
    /// See [`Tracker::dead_with`].
    pub fn residual<L: LinearLoad<M>>(
        &self,
        load: &L,
        q: &[f64],
        f: &[f64],
    ) -> Result<DVector<f64>> {
        let dead = self.dead_with(load, f)?;
        let u = self.model.free_coordinates_of(q)?;
        let mut r = DVector::zeros(self.model.n_free());
        self.model.residual_into(
            u.as_slice(),
            q,
            dead.as_slice(),
            &self.known,
            r.as_mut_slice(),
        )?;
        Ok(r)
    }

    /// The tangent `K = −∂R/∂u` at `q` over the free coordinates and its
    /// factors (`L D Lᵀ` of the Jacobi-scaled tangent, which is symmetric
    /// and positive definite near a stable equilibrium; a pivoted LU if it
    /// is not positive definite), with the tracker's linear solver.
    ///
    /// # Errors
    /// [`crate::Error::Singular`] or [`crate::Error::NonFinite`] if the
    /// factorization fails; [`crate::Error::DimensionMismatch`] for a `q`
    /// of the wrong size.
    ///
    /// # Example
    /// See [`FactoredTangent`].
    pub fn factor_tangent(&mut self, q: &[f64]) -> Result<FactoredTangent> {
        let u = self.model.free_coordinates_of(q)?;
        let mut matrix = SymmetricMatrix::zeros(self.kmat.pattern().clone());
        self.model.tangent_into(
            u.as_slice(),
            q,
            self.dead_known.as_slice(),
            &self.known,
            &mut matrix,
        )?;
        let factors = self.linear.factor(&matrix, FactorOptions::default())?;
        self.counts.factorizations += 1;
        Ok(FactoredTangent { matrix, factors })
    }

    /// Factors the tangent at the free coordinates `u` under the known
    /// loads and keeps it for the next chord steps (and
    /// [`Tracker::kept_factors`]).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] for a `u` of the wrong size; the
    /// factorization's errors.
    pub fn factor_at_free(&mut self, u: &[f64]) -> Result<()> {
        check_len("u", self.model.n_free(), u.len())?;
        let mut q = vec![0.0; self.model.n_q()];
        self.model.configuration_into(u, &mut q)?;
        self.model.tangent_into(
            u,
            &q,
            self.dead_known.as_slice(),
            &self.known,
            &mut self.kmat,
        )?;
        self.refactor(q)
    }

    /// Keeps `factors`, taken at `q`, for the chord steps of the next solve.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `q` or the factors do not fit
    /// the model.
    pub fn keep_factors(&mut self, q: &[f64], factors: AutoFactors) -> Result<()> {
        check_len("q", self.model.n_q(), q.len())?;
        check_len("factors", self.model.n_free(), factors.n())?;
        self.kept = Some(Kept {
            q: q.to_vec(),
            factors,
            k_max: 0.0,
        });
        Ok(())
    }

    /// Forgets the kept factors and the last solution.
    pub fn forget(&mut self) {
        self.kept = None;
        self.state = None;
    }

    /// Replaces the known loads (for example the pressures a controller
    /// commanded): the model, the settings and the linear solver's analysis
    /// stay; the kept factors and the last equilibrium, which were taken
    /// under the old loads, are dropped.
    ///
    /// # Errors
    /// As [`Assembled::validate_loads`](crate::structure::Assembled::validate_loads) and [`Assembled::dead_force`](crate::structure::Assembled::dead_force); on
    /// an error the tracker is unchanged.
    ///
    /// # Example
    /// ```
    /// use softrod::{scene::Scene, statics::{EquilibriumTracker, StaticSettings}};
    /// let scene = Scene::two_section();
    /// let mut tracker = EquilibriumTracker::new(scene.robot()?, scene.loads()?, StaticSettings::default())?;
    /// let mut known = scene.loads()?;
    /// known.pressures_pa[0] += 1e3;
    /// tracker.set_known(known.clone())?;
    /// assert_eq!(tracker.known(), &known);
    /// known.pressures_pa[0] = f64::NAN;
    /// assert!(tracker.set_known(known).is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn set_known(&mut self, known: M::Loads) -> Result<()> {
        self.set_loads(known)?;
        self.kept = None;
        Ok(())
    }

    /// As [`Tracker::set_known`] but keeping the factors: the next solve's
    /// chord steps start with the tangent of the old loads (a controller's
    /// next command, a little different from the last).
    ///
    /// # Errors
    /// As [`Tracker::set_known`].
    pub fn set_loads(&mut self, known: M::Loads) -> Result<()> {
        self.model.validate_loads(&known)?;
        let dead_known = self.model.dead_force(&known)?;
        self.known = known;
        self.dead_known = dead_known;
        self.state = None;
        Ok(())
    }

    /// The static solve of `loads` by `solver` from `q0` (or cold) with
    /// the tracker's analyzed linear solver (the tracker's own state is
    /// not touched): for a caller that also needs globalized solves of
    /// its model.
    ///
    /// # Errors
    /// As [`StaticSolver::solve_with`].
    pub fn static_solve(
        &mut self,
        solver: &StaticSolver,
        loads: &M::Loads,
        q0: Option<&[f64]>,
    ) -> Result<Equilibrium> {
        solver.solve_with(&self.model, loads, q0, &mut self.linear)
    }

    /// The equilibrium at `F` from `q0` (all coordinates, taken as they
    /// are; their free coordinates by [`Stepping::free_coordinates_of`](crate::structure::Stepping::free_coordinates_of)):
    /// the warm iterations of the strategy, then the globalized
    /// [`StaticSolver`].
    ///
    /// # Errors
    /// [`crate::Error::NotConverged`] if the globalized solve fails too; the
    /// errors of [`Tracker::residual`] and of the factorization.
    pub fn solve<L: LinearLoad<M>>(
        &mut self,
        load: &L,
        f: &[f64],
        q0: &[f64],
    ) -> Result<TrackedEquilibrium> {
        let u0 = self.model.free_coordinates_of(q0)?;
        self.solve_from(Some(load), f, u0.as_slice(), q0, true)?
            .ok_or_else(unreachable_fallback)
    }

    /// As [`Tracker::solve`] without the globalized fallback: `None` when
    /// the warm iterations do not converge (cheap, for the trials of a
    /// line search).
    ///
    /// # Errors
    /// As [`Tracker::solve`].
    pub fn try_solve<L: LinearLoad<M>>(
        &mut self,
        load: &L,
        f: &[f64],
        q0: &[f64],
    ) -> Result<Option<TrackedEquilibrium>> {
        let u0 = self.model.free_coordinates_of(q0)?;
        self.solve_from(Some(load), f, u0.as_slice(), q0, false)
    }

    /// The equilibrium under the known loads alone from the free
    /// coordinates `u0` (`q0 = φ(u0)`): the warm iterations, then the
    /// globalized [`StaticSolver`].
    ///
    /// # Errors
    /// As [`Tracker::solve`]; [`crate::Error::DimensionMismatch`] for a
    /// `u0` of the wrong size.
    pub fn solve_free(&mut self, u0: &[f64]) -> Result<TrackedEquilibrium> {
        let q0 = self.configuration(u0)?;
        self.solve_from(None::<&dyn LinearLoad<M>>, &[], u0, &q0, true)?
            .ok_or_else(unreachable_fallback)
    }

    /// As [`Tracker::solve_free`] without the fallback: `None` when the
    /// warm iterations do not converge.
    ///
    /// # Errors
    /// As [`Tracker::solve_free`].
    pub fn try_solve_free(&mut self, u0: &[f64]) -> Result<Option<TrackedEquilibrium>> {
        let q0 = self.configuration(u0)?;
        self.solve_from(None::<&dyn LinearLoad<M>>, &[], u0, &q0, false)
    }

    /// The equilibrium at `F` from `q0` by chord steps with the kept factors
    /// only, keeping them (no factorization at the solution): for a last,
    /// tiny step. `None` (and no change) if no factors are kept or the steps
    /// do not converge below `1e-10 L`; else the shape and its `|R|_2` (N).
    ///
    /// # Errors
    /// As [`Tracker::residual`].
    pub fn solve_chord<L: LinearLoad<M>>(
        &mut self,
        load: &L,
        f: &[f64],
        q0: &[f64],
    ) -> Result<Option<(DVector<f64>, f64)>> {
        if self.kept.is_none() {
            return Ok(None);
        }
        self.counts.solves += 1;
        let u0 = self.model.free_coordinates_of(q0)?;
        let dead = self.dead_with(load, f)?;
        let target = self.target(f, dead.as_slice(), u0.as_slice(), q0)?;
        let mut it = Iterate::new(u0.as_slice(), q0);
        let known = self.residual_from_state(Some(load), f, q0, &mut it.r)?;
        let Some(kept) = self.kept.take() else {
            return Ok(None);
        };
        let end = self.chord(&target, &mut it, &kept.factors, known);
        let k_max = kept.k_max;
        self.kept = Some(kept);
        let Some(_) = end? else {
            return Ok(None);
        };
        self.eval_residual(&target, &mut it)?;
        let residual_n = norm2(&it.r);
        let status = self.status(&target, residual_n, k_max, &it.q);
        self.state = Some(State {
            f: f.to_vec(),
            u: it.u,
            q: it.q.clone(),
            r: it.r,
            residual_n,
            status,
        });
        Ok(Some((DVector::from_vec(it.q), residual_n)))
    }

    /// `φ(u)` (checked).
    fn configuration(&self, u: &[f64]) -> Result<Vec<f64>> {
        check_len("u0", self.model.n_free(), u.len())?;
        let mut q = vec![0.0; self.model.n_q()];
        self.model.configuration_into(u, &mut q)?;
        Ok(q)
    }

    /// The residual test's tolerance at the start `(u0, q0)` and the solve's
    /// target.
    fn target<'a>(
        &self,
        f: &'a [f64],
        dead: &'a [f64],
        u0: &[f64],
        q0: &[f64],
    ) -> Result<Target<'a>> {
        let mut applied = vec![0.0; self.model.n_free()];
        self.model
            .applied_force_into(u0, q0, dead, &self.known, &mut applied)?;
        Ok(Target {
            f,
            dead,
            tolerance_n: self.solver.settings.residual_tolerance * norm2(&applied),
        })
    }

    /// The residual test on `q` (see [`WarmStatus`]).
    fn status(&self, t: &Target<'_>, residual_n: f64, k_max: f64, q: &[f64]) -> WarmStatus {
        let floor = residual_floor(k_max, max_abs(q), self.model.n_free());
        if residual_n <= t.tolerance_n.max(floor) {
            WarmStatus::Converged
        } else {
            WarmStatus::AboveResidualTest
        }
    }

    /// The solve behind the public ones: the remembered answer if asked
    /// again, else the strategy's warm iterations, then (with `fallback`)
    /// the globalized solve.
    fn solve_from<L: LinearLoad<M> + ?Sized>(
        &mut self,
        load: Option<&L>,
        f: &[f64],
        u0: &[f64],
        q0: &[f64],
        fallback: bool,
    ) -> Result<Option<TrackedEquilibrium>> {
        self.counts.solves += 1;
        if let Some(eq) = self.repeated(f, q0) {
            return Ok(Some(eq));
        }
        let dead = match load {
            Some(l) => self.dead_with(l, f)?,
            None => self.dead_known.clone(),
        };
        let target = self.target(f, dead.as_slice(), u0, q0)?;
        let mut it = Iterate::new(u0, q0);
        // the residual at q0 from the remembered one, if q0 is its shape
        let known = self.residual_from_state(load, f, q0, &mut it.r)?;
        let found = match self.strategy {
            WarmStrategy::ChordThenNewton => self.chord_then_newton(&target, &mut it, known)?,
            WarmStrategy::ChordRefactor {
                max_factorizations,
                max_residuals,
                step_tolerance_m,
                confirm,
            } => self.chord_refactor(
                &target,
                &mut it,
                max_factorizations,
                max_residuals,
                step_tolerance_m,
                confirm,
            )?,
            WarmStrategy::Newton { max_steps } => self.newton_correct(&target, &mut it, max_steps),
        };
        if found.is_some() || !fallback {
            return Ok(found);
        }
        let loads = match load {
            Some(l) => l.add_to(&self.model, &self.known, f),
            None => self.known.clone(),
        };
        self.fallback(&target, &loads, q0).map(Some)
    }

    /// The last answer, if asked again at it (same `F`, `q0` its shape) and
    /// the kept factors are those of a point at most `1e-8 L` away.
    ///
    /// The kept factors may be those of a point up to 1e-8 L away (a
    /// chord solve keeps them, see [`Tracker::solve_chord`]): the
    /// derivatives they give differ by about 1e-7 relative, which the next
    /// Gauss–Newton step of an estimator absorbs.
    fn repeated(&self, f: &[f64], q0: &[f64]) -> Option<TrackedEquilibrium> {
        let (st, kept) = (self.state.as_ref()?, self.kept.as_ref()?);
        let len = self.model.length_m();
        let near = kept
            .q
            .iter()
            .zip(q0)
            .all(|(a, b)| (a - b).abs() <= 1e-8 * len);
        (st.f == f && st.q == q0 && near).then(|| TrackedEquilibrium {
            q: DVector::from_column_slice(q0),
            u: DVector::from_column_slice(&st.u),
            factors: kept.factors.clone(),
            residual_n: st.residual_n,
            status: st.status,
            path: WarmPath::Repeated,
        })
    }

    /// `R(q0, F)` into `r` from the remembered equilibrium if `q0` is its
    /// shape (`R(q, F) = R(q, F_s) + Tᵀ G (F − F_s)`); false otherwise.
    fn residual_from_state<L: LinearLoad<M> + ?Sized>(
        &self,
        load: Option<&L>,
        f: &[f64],
        q0: &[f64],
        r: &mut [f64],
    ) -> Result<bool> {
        match &self.state {
            Some(st) if st.q == q0 && st.f.len() == f.len() => {
                r.copy_from_slice(&st.r);
                if let Some(load) = load {
                    let df: Vec<f64> = f.iter().zip(&st.f).map(|(a, b)| a - b).collect();
                    let gdf = load.force(&self.model, &df)?;
                    self.model.restrict_into(&st.u, gdf.as_slice(), r)?;
                    r.iter_mut().zip(&st.r).for_each(|(a, b)| *a += b);
                }
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    /// `R` at the iterate into `it.r` (one residual counted).
    fn eval_residual(&mut self, t: &Target<'_>, it: &mut Iterate) -> Result<()> {
        self.counts.residuals += 1;
        self.model
            .residual_into(&it.u, &it.q, t.dead, &self.known, &mut it.r)
    }

    /// `R` into `it.r` and the tangent into the buffer at the iterate.
    fn eval_residual_and_tangent(&mut self, t: &Target<'_>, it: &mut Iterate) -> Result<()> {
        self.model.residual_and_tangent_into(
            &it.u,
            &it.q,
            t.dead,
            &self.known,
            &mut it.r,
            &mut self.kmat,
        )
    }

    /// Factors the tangent in the buffer (one factorization counted).
    fn factor_buffer(&mut self) -> Result<AutoFactors> {
        self.counts.factorizations += 1;
        Ok(self.linear.factor(&self.kmat, FactorOptions::default())?)
    }

    /// Factors the tangent in the buffer, taken at `q`, and keeps it.
    fn refactor(&mut self, q: Vec<f64>) -> Result<()> {
        let factors = self.factor_buffer()?;
        self.kept = Some(Kept {
            q,
            factors,
            k_max: self.kmat.max_abs(),
        });
        Ok(())
    }

    /// The direction `du = F⁻¹ r` at the iterate with the factors `lu`, and
    /// its size `|du|∞`.
    fn direction(lu: &AutoFactors, it: &mut Iterate) -> Result<f64> {
        it.du.copy_from_slice(&it.r);
        lu.solve_in_place(&mut it.du)?;
        Ok(it.du.iter().fold(0.0f64, |m, v| m.max(v.abs())))
    }

    /// Moves the iterate by its step `du` (`dq = T du` computed here unless
    /// `expanded`).
    fn advance(&mut self, it: &mut Iterate, expanded: bool) -> Result<()> {
        if !expanded {
            self.model.step_into(&it.u, &it.du, &mut it.dq)?;
        }
        self.model
            .advance_into(&it.u, &it.q, &it.du, &it.dq, 1.0, &mut it.u1, &mut it.q1)?;
        std::mem::swap(&mut it.u, &mut it.u1);
        std::mem::swap(&mut it.q, &mut it.q1);
        self.counts.steps += 1;
        Ok(())
    }

    /// One plain Newton (or, with old factors, chord) step at the iterate
    /// with the factors `lu` for its residual `it.r`: applied unless it is
    /// not finite, longer than a quarter of the model, or not shorter than
    /// `limit` (m). Returns the step's size (m) if applied.
    fn plain_step(
        &mut self,
        it: &mut Iterate,
        lu: &AutoFactors,
        limit: f64,
    ) -> Result<Option<f64>> {
        let step = Self::direction(lu, it)?;
        if !step.is_finite() || step > 0.25 * self.model.length_m() || step > limit {
            return Ok(None);
        }
        self.advance(it, false)?;
        Ok(Some(step))
    }

    /// Up to 12 chord steps with `lu` from the iterate (its residual known
    /// in `it.r` if `known`), each shorter than half the last, until
    /// [`chord_converged`]: whether a step moved the iterate by more than
    /// `1e-10 L`, or `None` if they stop contracting.
    fn chord(
        &mut self,
        t: &Target<'_>,
        it: &mut Iterate,
        lu: &AutoFactors,
        known: bool,
    ) -> Result<Option<bool>> {
        let len = self.model.length_m();
        let (mut prev, mut path, mut moved) = (f64::INFINITY, 0.0, false);
        for k in 0..12 {
            if k > 0 || !known {
                self.eval_residual(t, it)?;
            }
            let Some(step) = self.plain_step(it, lu, 0.5 * prev)? else {
                return Ok(None);
            };
            path += step;
            let converged = chord_converged(step, prev, path, len);
            moved |= step > 1e-10 * len;
            prev = step;
            if converged {
                return Ok(Some(moved));
            }
        }
        Ok(None)
    }

    /// [`WarmStrategy::ChordThenNewton`]: chord steps with the kept factors
    /// (a few residuals, then one fresh factorization at the solution for
    /// exact derivatives, kept for the next call), then plain Newton steps
    /// from the start.
    fn chord_then_newton(
        &mut self,
        t: &Target<'_>,
        it: &mut Iterate,
        known: bool,
    ) -> Result<Option<TrackedEquilibrium>> {
        let (u0, q0) = (it.u.clone(), it.q.clone());
        if let Some(kept) = self.kept.take() {
            if let Some(moved) = self.chord(t, it, &kept.factors, known)? {
                // the kept factors are exact if q has not left their point
                let (lu, k_max) = if !moved && kept.q == q0 {
                    self.eval_residual(t, it)?;
                    (kept.factors, kept.k_max)
                } else {
                    // fresh factors at the solution, with its residual
                    self.counts.residuals += 1;
                    self.eval_residual_and_tangent(t, it)?;
                    (self.factor_buffer()?, self.kmat.max_abs())
                };
                return Ok(Some(self.solved(t, it, lu, k_max, WarmPath::Chord)));
            }
            self.kept = Some(kept);
            it.restart(&u0, &q0);
        }
        let len = self.model.length_m();
        let mut prev = f64::INFINITY;
        for _ in 0..12 {
            // Newton: residual and tangent at the iterate in one pass
            self.eval_residual_and_tangent(t, it)?;
            let Ok(lu) = self.factor_buffer() else {
                break;
            };
            let Some(step) = self.plain_step(it, &lu, 0.9 * prev)? else {
                break;
            };
            prev = step;
            if step <= 1e-10 * len {
                self.eval_residual(t, it)?;
                let k_max = self.kmat.max_abs();
                return Ok(Some(self.solved(t, it, lu, k_max, WarmPath::Newton)));
            }
        }
        Ok(None)
    }

    /// [`WarmStrategy::ChordRefactor`].
    fn chord_refactor(
        &mut self,
        t: &Target<'_>,
        it: &mut Iterate,
        max_factorizations: usize,
        max_residuals: usize,
        step_tolerance_m: f64,
        confirm: bool,
    ) -> Result<Option<TrackedEquilibrium>> {
        let mut last = f64::INFINITY;
        let mut factorizations = 0;
        if self.kept.is_none() {
            self.eval_tangent(t, it)?;
            self.refactor(it.q.clone())?;
            factorizations += 1;
        }
        for _ in 0..max_residuals {
            self.eval_residual(t, it)?;
            let Some(kept) = &self.kept else { break };
            let step = Self::direction(&kept.factors, it)?;
            if !step.is_finite() {
                break;
            }
            if step > 0.5 * last {
                // not contracting: a Newton step from here
                if factorizations >= max_factorizations {
                    break;
                }
                self.eval_tangent(t, it)?;
                self.refactor(it.q.clone())?;
                factorizations += 1;
                last = f64::INFINITY;
                continue;
            }
            let previous_residual = norm2(&it.r);
            self.advance(it, false)?;
            if step <= step_tolerance_m {
                let Some(kept) = self.kept.take() else { break };
                let (residual_n, status) = if confirm {
                    self.eval_residual(t, it)?;
                    let rn = norm2(&it.r);
                    (rn, self.status(t, rn, kept.k_max, &it.q))
                } else {
                    (previous_residual, WarmStatus::Unconfirmed)
                };
                let eq = self.record(t, it, kept, residual_n, status, WarmPath::Chord);
                return Ok(Some(eq));
            }
            last = step;
        }
        Ok(None)
    }

    /// The tangent alone at the iterate into the buffer.
    fn eval_tangent(&mut self, t: &Target<'_>, it: &Iterate) -> Result<()> {
        self.model
            .tangent_into(&it.u, &it.q, t.dead, &self.known, &mut self.kmat)
    }

    /// [`WarmStrategy::Newton`]: `None` where it gives up (see there;
    /// errors of the evaluations give up too: the caller's globalized
    /// solve reports them).
    fn newton_correct(
        &mut self,
        t: &Target<'_>,
        it: &mut Iterate,
        max_steps: usize,
    ) -> Option<TrackedEquilibrium> {
        if !t.tolerance_n.is_finite() {
            return None;
        }
        let max_rotation = self.solver.settings.max_step_rotation;
        let mut steps = 0;
        let mut previous = f64::INFINITY;
        loop {
            self.counts.residuals += 1;
            self.eval_residual_and_tangent(t, it).ok()?;
            let rn = norm2(&it.r);
            if !(rn.is_finite() && rn < previous) {
                return None;
            }
            let factors = match self.factor_buffer() {
                Ok(f) if f.is_positive_definite() => f,
                _ => return None,
            };
            if rn <= t.tolerance_n {
                let k_max = self.kmat.max_abs();
                let kept = Kept {
                    q: Vec::new(),
                    factors,
                    k_max,
                };
                let status = self.status(t, rn, k_max, &it.q);
                return Some(self.record(t, it, kept, rn, status, WarmPath::Newton));
            }
            if steps >= max_steps {
                return None;
            }
            steps += 1;
            Self::direction(&factors, it).ok()?;
            self.model.step_into(&it.u, &it.du, &mut it.dq).ok()?;
            let rotation = self.model.step_rotation(&it.dq);
            if rotation.is_nan() || rotation > max_rotation {
                return None;
            }
            self.advance(it, true).ok()?;
            previous = rn;
        }
    }

    /// The globalized [`StaticSolver`] from `q0` under `loads`, its
    /// solution factored and kept.
    fn fallback(
        &mut self,
        t: &Target<'_>,
        loads: &M::Loads,
        q0: &[f64],
    ) -> Result<TrackedEquilibrium> {
        self.counts.fallbacks += 1;
        let eq = self
            .solver
            .solve_with(&self.model, loads, Some(q0), &mut self.linear)?;
        let mut it = Iterate::new(eq.u.as_slice(), eq.q.as_slice());
        self.eval_residual_and_tangent(t, &mut it)?;
        let lu = self.factor_buffer()?;
        let k_max = self.kmat.max_abs();
        let mut out = self.solved(t, &mut it, lu, k_max, WarmPath::Fallback);
        out.residual_n = eq.report.residual_norm_n;
        out.status = self.status(t, out.residual_n, k_max, eq.q.as_slice());
        if let Some(st) = &mut self.state {
            st.status = out.status;
        }
        Ok(out)
    }

    /// Records a solved equilibrium (`it.r` its residual, `lu` the factors
    /// at `it.q`, `k_max` the tangent's largest entry), its status by the
    /// residual test, and returns it.
    fn solved(
        &mut self,
        t: &Target<'_>,
        it: &mut Iterate,
        lu: AutoFactors,
        k_max: f64,
        path: WarmPath,
    ) -> TrackedEquilibrium {
        let residual_n = norm2(&it.r);
        let status = self.status(t, residual_n, k_max, &it.q);
        let kept = Kept {
            q: it.q.clone(),
            factors: lu,
            k_max,
        };
        self.record(t, it, kept, residual_n, status, path)
    }

    /// Keeps `kept` (with the Newton strategy, which does not use kept
    /// factors, only hands them back) and the state of the iterate, and
    /// returns the answer.
    fn record(
        &mut self,
        t: &Target<'_>,
        it: &mut Iterate,
        kept: Kept,
        residual_n: f64,
        status: WarmStatus,
        path: WarmPath,
    ) -> TrackedEquilibrium {
        let u = std::mem::take(&mut it.u);
        let q = std::mem::take(&mut it.q);
        let r = std::mem::take(&mut it.r);
        let factors = if let WarmStrategy::Newton { .. } = self.strategy {
            self.state = None;
            kept.factors
        } else {
            let factors = kept.factors.clone();
            self.kept = Some(kept);
            self.state = Some(State {
                f: t.f.to_vec(),
                u: u.clone(),
                q: q.clone(),
                r,
                residual_n,
                status,
            });
            factors
        };
        TrackedEquilibrium {
            q: DVector::from_vec(q),
            u: DVector::from_vec(u),
            factors,
            residual_n,
            status,
            path,
        }
    }
}

/// The error of a solve with the fallback that returned nothing (which
/// the fallback's own errors make impossible).
fn unreachable_fallback() -> Error {
    Error::invalid("tracker", "no answer", "the fallback solve returned none")
}

/// Whether chord steps have converged after a step of `step` (m) that
/// followed one of `prev` (m; infinite for the first), all of them
/// together `path` long (m, this one included), on a robot of length `len`
/// (m): the step itself is below `1e-10 len`, or, while the steps have
/// moved the shape by no more than `1e-4 len` (where the chord iteration
/// is linear: its contraction `ρ` is set by how far the kept factors' point
/// lies, and changes by about `1e-4` relative along so short a path; a
/// warm estimator step's steps move it by about `1e-5 len`, a far start's
/// by much more), the distance left to
/// the solution that the contraction so far predicts, `ρ step / (1 − ρ)`
/// with `ρ = step / prev ≤ 1/2`, is. The second saves the residual and the
/// solve that would only confirm a step below the bound (one in three or
/// four of a warm estimator step's).
pub(crate) fn chord_converged(step: f64, prev: f64, path: f64, len: f64) -> bool {
    let tol = 1e-10 * len;
    if step <= tol {
        return true;
    }
    if !prev.is_finite() || path > 1e-4 * len {
        return false;
    }
    let rho = step / prev;
    rho <= 0.5 && rho * step <= tol * (1.0 - rho)
}

#[cfg(test)]
mod tests;
