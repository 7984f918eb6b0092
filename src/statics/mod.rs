//! Static equilibrium: Newton's method on `Q(F, q, P) = 0` (17), the one
//! equilibrium solver of every model: a clamped [`Robot`](crate::assembly::Robot), a multi-body
//! [`crate::structure::Structure`], any [`Model`] model, iterated in its
//! free coordinates `u` with `q = φ(u)` (the equilibrium is
//! `R(u) = T(u)ᵀ Q(φ(u)) = 0`).
//!
//! Globalization: a quick plain Newton run from the start point (for a cold
//! solve of a fine mesh given up at the first tangent that is not positive
//! definite, before any pivoted LU of it); for a cold
//! solve of a fine mesh (64 elements or more), then a start from the
//! equilibrium of a 16-element mesh of the same model interpolated onto the
//! fine one (mesh sequencing, `sequence.rs`: the iteration count no longer
//! grows with the mesh); then a predictor–corrector continuation in the
//! load (`continuation.rs`); as the last resort, a backtracking line search that accepts a decrease of the
//! total potential or of `|R|²` (the Newton direction always descends the
//! latter, whatever the tangent's definiteness), a cap on the rotation of
//! the node slopes (and rigid bodies) per step, and, when the full problem
//! fails from the start point, a homotopy `R(u) − (1 − λ) R(u_0) = 0` from
//! `λ = 0` (where the start point is exact) to `λ = 1` with adaptive steps.
//!
//! Convergence is scale-aware. The residual test is relative to the applied
//! generalized forces, but never asks for less than the round-off floor
//! `ε |K|_max |q|_∞ max(1, 0.05 √n)`, which grows with the element count (a fixed
//! relative tolerance of 1e-10 is unreachable at 32+ elements). A full Newton
//! step below `increment_tolerance × L` also ends the solve, when the residual
//! is within [`INCREMENT_RESIDUAL_MULTIPLE`] times the tolerance or floor. The
//! report's status shows which test ended it (or why it failed), with the
//! tolerance and the floor ([`residual_floor`]); before a converged status is
//! returned its test is checked again on the answer's own residual
//! ([`StaticStatus::Unverified`] when it does not hold: a stiff section beside
//! a soft one can put the floor, set by the stiff rows, above the whole load).
//! An answer with negative eigenvalues carries [`StaticWarning::Unstable`].
//!
//! Stability: the answer's tangent is factored once more and the signs of
//! its `L D Lᵀ` pivots give its inertia ([`StaticReport::negative_eigenvalues`]);
//! a saddle (a column standing straight beyond its buckling load) is left
//! along its direction of negative curvature by a descent Newton run, so the
//! answer is a stable equilibrium whenever one is found.
//!
//! Branches: a cold solve follows the branch connected to the unloaded state
//! along the load path. Its quick full-load attempt is kept only when every
//! tangent it met was positive definite (the `L D Lᵀ` succeeded: no extra
//! factorization), otherwise the load path decides; a load step that lands
//! on a saddle left a critical point behind, and the saddle is left toward
//! the side the path leaned to before it (its tangent at the last stable
//! point projected on the direction of negative curvature: a lateral load,
//! a tilt). The report names the choice ([`StaticWarning::Bifurcation`]
//! with a [`BranchChoice`]), ambiguous when the path leans to neither side
//! (a symmetric load).
//!
//! [`EquilibriumTracker`] (in [`tracker`]) solves the same equilibrium at a
//! sequence of nearby loads, warm, reusing factorizations: what an estimator
//! or a controller needs; it falls back to [`StaticSolver`].

use std::sync::Arc;

use nalgebra::DVector;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_at_most, check_len, check_positive, named};
use crate::linsolve::{AutoSolver, SolverKind, TangentSolver};
pub use crate::outcome::{
    BranchChoice, NonFiniteAt, StaticCriterion, StaticReport, StaticStatus, StaticWarning,
};
use crate::structure::Model;

mod continuation;
mod newton;
pub use newton::INCREMENT_RESIDUAL_MULTIPLE;
mod sequence;
mod stability;
pub mod tracker;

pub use tracker::{
    EquilibriumTracker, FactoredTangent, LinearLoad, TrackedEquilibrium, Tracker, WarmCounts,
    WarmPath, WarmStatus, WarmStrategy,
};

/// Settings of the static solver; every field has a documented default.
///
/// # Example
/// ```
/// let s = softrod::statics::StaticSettings { residual_tolerance: 1e-12, ..Default::default() };
/// s.validate("").unwrap();
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StaticSettings {
    /// Newton iterations per load step (default 30).
    pub max_iterations: usize,
    /// Newton iterations in all, over every load step (default 2000).
    pub max_total_iterations: usize,
    /// Residual tolerance relative to the norm of the applied generalized
    /// forces (default 1e-10).
    pub residual_tolerance: f64,
    /// A full Newton step shorter than this times the robot length ends the
    /// solve (default 1e-12).
    pub increment_tolerance: f64,
    /// Largest change of a node slope `r'` in one Newton step, roughly the
    /// rotation in rad (default 0.5).
    pub max_step_rotation: f64,
    /// Smallest homotopy step before giving up (default 1e-4).
    pub min_load_step: f64,
    /// The linear solver of the tangent (default [`SolverKind::Auto`]: the
    /// band kernels where the tangent's pattern is a narrow band, as every
    /// robot's chain is, faer's sparse `L D Lᵀ` otherwise; each with a
    /// pivoted LU for indefinite tangents). [`SolverKind::Sparse`] never
    /// takes the band path, [`SolverKind::Band`] refuses a model whose
    /// pattern is not a narrow band ([`Error::InvalidParameter`] naming
    /// `linear_solver`). See [`crate::linsolve::sparse::BandPath`].
    pub linear_solver: SolverKind,
}

impl Default for StaticSettings {
    fn default() -> Self {
        StaticSettings {
            max_iterations: 30,
            max_total_iterations: 2000,
            residual_tolerance: 1e-10,
            increment_tolerance: 1e-12,
            max_step_rotation: 0.5,
            min_load_step: 1e-4,
            linear_solver: SolverKind::Auto,
        }
    }
}

impl StaticSettings {
    /// Checks every field: iteration counts in `1..=MAX_ITERATIONS`
    /// (`max_total_iterations >= max_iterations`), tolerances and the
    /// smallest load step in `(0, 1)`, `max_step_rotation` finite and positive.
    /// `path` is where the caller keeps these settings (e.g.
    /// `"solver.static"` in a scene, `"loop.ik.statics"` in the closed
    /// loop's settings): the errors name `path.field`, or the bare field for
    /// an empty `path`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field; [`Error::TooLarge`] for
    /// an iteration count above [`MAX_ITERATIONS`].
    ///
    /// # Example
    /// ```
    /// use softrod::statics::StaticSettings;
    /// let s = StaticSettings { max_iterations: 0, ..Default::default() };
    /// let e = s.validate("loop.ik.statics").unwrap_err();
    /// assert!(e.to_string().contains("loop.ik.statics.max_iterations"));
    /// assert!(s.validate("").unwrap_err().to_string().contains("max_iterations"));
    /// ```
    pub fn validate(&self, path: &str) -> Result<()> {
        let f = |name: &str| {
            if path.is_empty() {
                name.to_string()
            } else {
                format!("{path}.{name}")
            }
        };
        // (the field names are formatted only for an error: this runs on
        // every solve)
        if self.max_iterations == 0 {
            return Err(Error::invalid(f("max_iterations"), 0, "must be >= 1"));
        }
        for (name, v) in [
            ("max_iterations", self.max_iterations),
            ("max_total_iterations", self.max_total_iterations),
        ] {
            named(|n| check_at_most(n, v, MAX_ITERATIONS), || f(name))?;
        }
        if self.max_total_iterations < self.max_iterations {
            return Err(Error::invalid(
                f("max_total_iterations"),
                self.max_total_iterations,
                format!("must be >= {}", f("max_iterations")),
            ));
        }
        for (name, v) in [
            ("residual_tolerance", self.residual_tolerance),
            ("increment_tolerance", self.increment_tolerance),
            ("max_step_rotation", self.max_step_rotation),
            ("min_load_step", self.min_load_step),
        ] {
            named(|n| check_positive(n, v), || f(name))?;
        }
        for (name, v) in [
            ("residual_tolerance", self.residual_tolerance),
            ("increment_tolerance", self.increment_tolerance),
            ("min_load_step", self.min_load_step),
        ] {
            // a relative tolerance of 1 or more accepts any configuration
            if v >= 1.0 {
                return Err(Error::invalid(f(name), v, "must be < 1"));
            }
        }
        Ok(())
    }
}

/// The largest iteration budget [`StaticSettings`] accept: it bounds the
/// time a solve may take.
pub const MAX_ITERATIONS: usize = 100_000;

/// A converged equilibrium.
///
/// # Example
/// ```
/// use softrod::{scene::Scene, structure::Assembled, statics::StaticSolver};
/// let scene = Scene::two_section();
/// let robot = scene.robot()?;
/// let eq = StaticSolver::default().solve(&robot, &scene.loads()?, None)?;
/// // q = φ(u): the clamped base node, then the free nodes as they are
/// assert_eq!((eq.q.len(), eq.u.len()), (robot.n_q(), Assembled::n_free(&robot)));
/// assert_eq!(eq.q.rows(4, robot.n_q() - 4), eq.u.rows(robot.n_base_free(), robot.n_q() - 4));
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Equilibrium {
    /// All coordinates, base node included (`φ(u)`); a function taking
    /// coordinates borrows them as `eq.q.as_slice()`.
    pub q: DVector<f64>,
    /// The free coordinates (a robot: its base stretch, then nodes 1 … N;
    /// a structure: block by block, see [`crate::structure::DofMap`]).
    pub u: DVector<f64>,
    /// What the solver did.
    pub report: StaticReport,
}

/// Newton solver for the static equilibrium of a [`Robot`](crate::assembly::Robot) or any other
/// [`Model`] model (see [`StaticSolver::solve`] for a structure).
///
/// # Example
/// ```
/// use softrod::{assembly::{RobotSpec, Section}, loads::{Loads, PointForce}, statics::StaticSolver};
/// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]).build_planar().unwrap();
/// let loads = Loads { point_forces: vec![PointForce { s_m: 0.24, force_n: vec![0.0, -0.01] }], ..Loads::default() };
/// let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
/// let tip_y = eq.q[robot.n_q() - 3];
/// // linear theory: P L³ / (3 EI)
/// assert!((tip_y + 0.01 * 0.24f64.powi(3) / (3.0 * 0.025)).abs() < 1e-6);
/// ```
#[derive(Debug, Clone, Default)]
pub struct StaticSolver {
    /// Settings.
    pub settings: StaticSettings,
}

impl StaticSolver {
    /// A solver with the given settings.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if the settings are invalid.
    ///
    /// # Example
    /// ```
    /// use softrod::statics::{StaticSettings, StaticSolver};
    /// assert!(StaticSolver::new(StaticSettings { max_iterations: 0, ..Default::default() }).is_err());
    /// ```
    pub fn new(settings: StaticSettings) -> Result<Self> {
        settings.validate("")?;
        Ok(StaticSolver { settings })
    }

    /// Solves the equilibrium `R(u) = 0` of `model` (a [`Robot`](crate::assembly::Robot), a
    /// [`crate::structure::Structure`], any [`Model`] model) for the
    /// given loads, in its free coordinates `u` with `q = φ(u)`, starting
    /// from `q0` (all `n_q` coordinates, taken to the map by
    /// [`Stepping::free_coordinates_of`](crate::structure::Stepping::free_coordinates_of): a robot's clamp resets its base
    /// position and direction) or, cold, from
    /// [`SolverHints::start_free_coordinates`](crate::structure::SolverHints::start_free_coordinates) (a robot: the arcs of its
    /// actuation, [`Robot::arc_configuration`](crate::assembly::Robot::arc_configuration)).
    ///
    /// # Errors
    /// [`Error::NotConverged`] with the report when no equilibrium is found
    /// within the budget; the errors of [`Assembled::validate_loads`](crate::structure::Assembled::validate_loads) for
    /// bad loads; [`Error::DimensionMismatch`] or
    /// [`Error::InvalidParameter`] for a bad `q0`; the settings' errors
    /// ([`StaticSettings::validate`]).
    ///
    /// # Example
    /// A structure: two clamped legs whose tips hold a 50 g platform, pushed
    /// sideways; at equilibrium both legs lean the same way.
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::statics::StaticSolver;
    /// use softrod::structure::{BodyLoad, JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureLoads, StructureSpec};
    /// let leg = |x: f64| RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 6)], nalgebra::Vector2::new(x, 0.0), nalgebra::Vector2::new(0.0, 1.0));
    /// let joint = |rod| JointSpec::RodToBody { rod, end: RodEnd::End, body: 0, point_m: None, direction: None };
    /// let s = StructureSpec::new(
    ///     vec![leg(-0.05), leg(0.05)],
    ///     vec![RigidBodySpec { mass_kg: 0.05, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![joint(0), joint(1)],
    /// ).build_planar()?;
    /// let loads = StructureLoads {
    ///     bodies: vec![BodyLoad { body: 0, force_n: vec![0.1, 0.0], moment_nm: vec![0.0] }],
    ///     ..StructureLoads::default()
    /// };
    /// let eq = StaticSolver::default().solve(&s, &loads, None)?;
    /// assert!(eq.report.status.is_converged());
    /// let x = s.body_free_coordinates(0)?.start;
    /// assert!(eq.u[x] > 0.0);
    /// // warm: from the equilibrium, a little more force
    /// let more = StructureLoads { bodies: vec![BodyLoad { body: 0, force_n: vec![0.11, 0.0], moment_nm: vec![0.0] }], ..loads };
    /// let warm = StaticSolver::default().solve(&s, &more, Some(eq.q.as_slice()))?;
    /// assert!(warm.u[x] > eq.u[x]);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn solve<M: Model>(
        &self,
        model: &M,
        loads: &M::Loads,
        q0: Option<&[f64]>,
    ) -> Result<Equilibrium> {
        self.settings.validate("")?;
        let pattern = model.tangent_pattern()?;
        let mut solver = AutoSolver::with_kind(&pattern, self.settings.linear_solver)?;
        let u = self.start(model, loads, q0)?;
        self.run(model, loads, u, q0.is_none(), &mut solver)
    }

    /// [`StaticSolver::solve`] with a linear solver analyzed before on the
    /// model's [`Assembled::tangent_pattern`](crate::structure::Assembled::tangent_pattern) (a robot's
    /// [`Robot::tangent_pattern`](crate::assembly::Robot::tangent_pattern)): a caller that solves one model many
    /// times analyzes its pattern once (`settings.linear_solver` is then not
    /// read).
    ///
    /// # Errors
    /// As [`StaticSolver::solve`]; [`Error::InvalidParameter`] (field
    /// `solver`) for a solver analyzed on another pattern.
    ///
    /// # Example
    /// ```
    /// use softrod::linsolve::{AutoSolver, SolverKind};
    /// use softrod::statics::StaticSolver;
    /// let scene = softrod::scene::Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let mut solver = AutoSolver::with_kind(robot.tangent_pattern(), SolverKind::Sparse)?;
    /// let eq = StaticSolver::default().solve_with(&robot, &loads, None, &mut solver)?;
    /// assert!(eq.report.status.is_converged());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn solve_with<M: Model>(
        &self,
        model: &M,
        loads: &M::Loads,
        q0: Option<&[f64]>,
        solver: &mut AutoSolver,
    ) -> Result<Equilibrium> {
        self.settings.validate("")?;
        let pattern = solver.pattern();
        let expected = model.tangent_pattern()?;
        if !(Arc::ptr_eq(pattern, &expected) || **pattern == *expected) {
            return Err(Error::invalid(
                "solver",
                pattern.n(),
                "analyzed on another pattern than the model's tangent",
            ));
        }
        let u = self.start(model, loads, q0)?;
        self.run(model, loads, u, q0.is_none(), solver)
    }

    /// The start point in free coordinates: `q0` taken to the map, or the
    /// model's cold start.
    fn start<M: Model>(&self, model: &M, loads: &M::Loads, q0: Option<&[f64]>) -> Result<Vec<f64>> {
        match q0 {
            Some(q0) => {
                check_len("q0", model.n_q(), q0.len())?;
                crate::error::check_all_finite("q0", q0)?;
                model.free_coordinates_of(q0).map(|u| u.data.into())
            }
            None => model.start_free_coordinates(loads).map(|u| u.data.into()),
        }
    }
}

/// The round-off floor of the equilibrium residual `|Q|_2` (N) at a
/// configuration whose largest coordinate is `q_max_abs` (m), with a tangent
/// stiffness whose largest entry is `k_max_abs` over `n_free` free
/// coordinates: `ε |K|_max |q|_∞ · max(1, 0.05 √n_free)`. Below it the
/// residual cannot certify more digits; the static solver stops there (after
/// one more Newton step) and the SQP estimator calls an iterate feasible
/// there.
///
/// # Example
/// ```
/// let floor = softrod::statics::residual_floor(1e4, 0.24, 84);
/// assert!((floor - f64::EPSILON * 1e4 * 0.24).abs() < 1e-25);
/// ```
pub fn residual_floor(k_max_abs: f64, q_max_abs: f64, n_free: usize) -> f64 {
    f64::EPSILON * k_max_abs * q_max_abs * (FLOOR_SQRT_N * (n_free as f64).sqrt()).max(1.0)
}

/// The floor's growth with the number of free coordinates,
/// `max(1, FLOOR_SQRT_N √n_free)`.
/// Calibrated by running Newton far past convergence: on a cantilever under a
/// uniform load (8 to 2048 elements) the residual stagnates at 0.05 to 0.47
/// times `ε |K|_max |q|_∞` (0.22 at 8 elements, 0.08 at 32, 0.13 at 128,
/// 0.25 at 512, 0.45 at 2048); on the default two-section scene at 2000
/// elements at about 1.3 times. The envelope puts the floor 2 to 5 times above
/// the stagnation level at every size. (An earlier `0.02 √n` fell below it on
/// small meshes: a 14-element solve ended at 1.15 times that floor.) The
/// solver takes one more Newton step when it reaches the floor, so a
/// conservative floor costs no accuracy.
const FLOOR_SQRT_N: f64 = 0.05;

/// `v`, or `f64::MAX` in place of an infinity or NaN: every number of a
/// report is finite.
fn finite_or_max(v: f64) -> f64 {
    if v.is_finite() { v } else { f64::MAX }
}

#[cfg(test)]
mod tests;
