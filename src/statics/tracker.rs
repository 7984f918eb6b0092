//! Equilibria at a sequence of nearby loads: the static solver's warm
//! tracker.
//!
//! An estimator (or a controller) asks for the equilibrium `Q(F, q, P) = 0`
//! (17) at many loads `F` close to each other, each from a nearby shape. The
//! load enters linearly, `Q_F = G F` ([`LinearLoad`]). The tracker keeps the
//! last factorization of the tangent `K` and the last solved state, so that
//!
//! - asked again at the same `(F, q)`, it answers at once;
//! - from the shape of its last solution, the residual at a new `F'` is
//!   `Q(q, F') = Q(q, F) + Mᵀ G (F' − F)`, with no new residual evaluation;
//! - it first takes chord (modified Newton) steps with the kept factors, then
//!   plain Newton steps, and only then falls back to the globalized
//!   [`StaticSolver`] (line search, homotopy).
//!
//! Every converged solve ends with a step below `1e-10 L` (or, in chord
//! steps, with one after which the contraction so far predicts less than
//! that to go) and returns the factors of `K` at its solution (fresh, unless the solution did not move
//! from the point the kept factors belong to), which the sensitivities
//! ([`crate::sensitivity`]) of that equilibrium use.
//!
//! The tangent is factored by an [`AutoSolver`] of the kind
//! [`StaticSettings::linear_solver`] asks for, analyzed once on the
//! robot's tangent pattern when the tracker is made: every later
//! factorization (chord, Newton, fallback, [`EquilibriumTracker::factor_tangent`])
//! reuses that analysis.

use nalgebra::DVector;

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{check_len, Result};
use crate::linsolve::{
    AutoFactors, AutoSolver, FactorOptions, Factorization, SymmetricMatrix, TangentSolver,
};
use crate::loads::Loads;
use crate::numeric::norm2;

use super::{StaticSettings, StaticSolver};

/// A load linear in a parameter vector `F`: its generalized force over all
/// coordinates is `G F` with a constant `G` (the distributed field (8) with
/// `G = J_QF` (22), (23), a concentrated force (32)–(35), …).
///
/// # Example
/// A force on node 20's `y` coordinate:
/// ```
/// use softrod::{assembly::Robot, element::Element, loads::{Loads, PointForce}};
/// use softrod::statics::LinearLoad;
/// use nalgebra::DVector;
/// struct TipY;
/// impl<E: Element> LinearLoad<E> for TipY {
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
pub trait LinearLoad<E: Element> {
    /// Number of parameters `n_F`.
    fn n_params(&self, robot: &Robot<E>) -> usize;
    /// `G F` over all `n_q` coordinates (N).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `f` has the wrong length.
    fn force(&self, robot: &Robot<E>, f: &[f64]) -> Result<DVector<f64>>;
    /// `Gᵀ v` for `v` over all `n_q` coordinates.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `v` has the wrong length.
    fn force_transpose(&self, robot: &Robot<E>, v: &[f64]) -> Result<DVector<f64>>;
    /// The loads `known` with `F` added, for the globalized static solver.
    fn add_to(&self, robot: &Robot<E>, known: &Loads, f: &[f64]) -> Loads;
}

/// A solved equilibrium of the tracker: the shape, the factored tangent at
/// it and its residual.
///
/// # Example
/// See [`EquilibriumTracker`] and [`crate::sensitivity`].
#[derive(Debug, Clone)]
pub struct TrackedEquilibrium {
    /// All coordinates (m, dimensionless slopes).
    pub q: DVector<f64>,
    /// The factors of the tangent `K` at `q` (see the [module
    /// documentation](self) for the one exception).
    pub factors: AutoFactors,
    /// `|Q|_2` at `q` (N).
    pub residual_n: f64,
}

/// A tangent stiffness `K` over the free coordinates and its factors, as
/// one call of [`EquilibriumTracker::factor_tangent`] made them: whoever
/// needs `K` itself (its entries for a QP, its largest entry for a
/// round-off floor) takes it from here, next to the factors of the same
/// matrix.
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
    /// `K = −∂Q/∂q` over the free coordinates (N/m and N per unit slope).
    pub matrix: SymmetricMatrix,
    /// Its factors.
    pub factors: AutoFactors,
}

/// The last solved state: its load, shape and residual.
#[derive(Debug, Clone)]
struct State {
    f: Vec<f64>,
    q: Vec<f64>,
    r: Vec<f64>,
    residual_n: f64,
}

/// Equilibria of a robot under known loads plus a [`LinearLoad`] at a
/// sequence of nearby parameters (see the [module documentation](self)).
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
#[derive(Debug, Clone)]
pub struct EquilibriumTracker<E: Element> {
    robot: Robot<E>,
    known: Loads,
    /// Dead force of the known loads (`n_q`).
    dead_known: DVector<f64>,
    solver: StaticSolver,
    /// The linear solver, analyzed once on the robot's tangent pattern.
    linear: AutoSolver,
    /// Tangent buffer.
    kmat: SymmetricMatrix,
    /// The last factorization of `K` and the shape it was taken at.
    factors: Option<(Vec<f64>, AutoFactors)>,
    /// The last solved equilibrium.
    state: Option<State>,
}

impl<E: Element> EquilibriumTracker<E> {
    /// A tracker for `robot` under the known loads `known`; `settings` are
    /// those of the globalized fallback solve, and
    /// [`StaticSettings::linear_solver`] picks the linear solver of every
    /// factorization (its pattern analyzed here, once).
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for invalid settings; the errors of
    /// [`Robot::dead_force`]; [`crate::Error::TooLarge`] if the tangent's
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
    pub fn new(robot: Robot<E>, known: Loads, settings: StaticSettings) -> Result<Self> {
        let linear = AutoSolver::with_kind(robot.tangent_pattern(), settings.linear_solver)?;
        let solver = StaticSolver::new(settings)?;
        let dead_known = robot.dead_force(&known)?;
        Ok(EquilibriumTracker {
            kmat: SymmetricMatrix::zeros(robot.tangent_pattern().clone()),
            linear,
            robot,
            known,
            dead_known,
            solver,
            factors: None,
            state: None,
        })
    }

    /// The robot.
    pub fn robot(&self) -> &Robot<E> {
        &self.robot
    }

    /// The known loads.
    pub fn known(&self) -> &Loads {
        &self.known
    }

    /// The settings of the fallback solve.
    pub fn settings(&self) -> &StaticSettings {
        &self.solver.settings
    }

    /// The linear solver in use ([`SolverKind::Auto`] resolved at
    /// [`EquilibriumTracker::new`]).
    ///
    /// [`SolverKind::Auto`]: crate::linsolve::SolverKind::Auto
    pub fn solver_kind(&self) -> crate::linsolve::SolverKind {
        self.linear.kind()
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
    pub fn dead_with<L: LinearLoad<E>>(&self, load: &L, f: &[f64]) -> Result<DVector<f64>> {
        let mut dead = load.force(&self.robot, f)?;
        check_len("G F", self.dead_known.len(), dead.len())?;
        dead += &self.dead_known;
        Ok(dead)
    }

    /// The residual `Q` over the free coordinates at `(q, F)` (N).
    ///
    /// # Errors
    /// As [`LinearLoad::force`] and [`Robot::residual`].
    ///
    /// # Example
    /// See [`EquilibriumTracker::dead_with`].
    pub fn residual<L: LinearLoad<E>>(
        &self,
        load: &L,
        q: &[f64],
        f: &[f64],
    ) -> Result<DVector<f64>> {
        let dead = self.dead_with(load, f)?;
        self.robot.residual(q, dead.as_slice(), &self.known)
    }

    /// The tangent `K = −∂Q/∂q` at `q` over the free coordinates and its
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
        let mut matrix = SymmetricMatrix::zeros(self.robot.tangent_pattern().clone());
        self.robot.tangent_into(q, &self.known, &mut matrix)?;
        let factors = self.linear.factor(&matrix, FactorOptions::default())?;
        Ok(FactoredTangent { matrix, factors })
    }

    /// Keeps `factors`, taken at `q`, for the chord steps of the next solve.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `q` or the factors do not fit
    /// the robot.
    pub fn keep_factors(&mut self, q: &[f64], factors: AutoFactors) -> Result<()> {
        check_len("q", self.robot.n_q(), q.len())?;
        check_len("factors", self.robot.n_free(), factors.n())?;
        self.factors = Some((q.to_vec(), factors));
        Ok(())
    }

    /// Forgets the kept factors and the last solution.
    pub fn forget(&mut self) {
        self.factors = None;
        self.state = None;
    }

    /// Replaces the known loads (for example the pressures a controller
    /// commanded): the robot, the settings and the linear solver's analysis
    /// stay; the kept factors and the last equilibrium, which were taken
    /// under the old loads, are dropped.
    ///
    /// # Errors
    /// As [`Robot::validate_loads`] and [`Robot::dead_force`]; on an error
    /// the tracker is unchanged.
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
    pub fn set_known(&mut self, known: Loads) -> Result<()> {
        self.robot.validate_loads(&known)?;
        let dead_known = self.robot.dead_force(&known)?;
        self.known = known;
        self.dead_known = dead_known;
        self.forget();
        Ok(())
    }

    /// The equilibrium at `F` from `q0`: chord steps with the kept factors,
    /// then plain Newton steps, then the globalized [`StaticSolver`].
    ///
    /// # Errors
    /// [`crate::Error::NotConverged`] if the globalized solve fails too; the
    /// errors of [`EquilibriumTracker::residual`] and of the factorization.
    pub fn solve<L: LinearLoad<E>>(
        &mut self,
        load: &L,
        f: &[f64],
        q0: &[f64],
    ) -> Result<TrackedEquilibrium> {
        match self.solve_opt(load, f, q0, true)? {
            Some(eq) => Ok(eq),
            // unreachable: with the fallback a failure is an error
            None => self.fallback(load, f, q0),
        }
    }

    /// As [`EquilibriumTracker::solve`] without the globalized fallback:
    /// `None` when the chord and plain Newton steps do not converge (cheap,
    /// for the trials of a line search).
    ///
    /// # Errors
    /// As [`EquilibriumTracker::solve`].
    pub fn try_solve<L: LinearLoad<E>>(
        &mut self,
        load: &L,
        f: &[f64],
        q0: &[f64],
    ) -> Result<Option<TrackedEquilibrium>> {
        self.solve_opt(load, f, q0, false)
    }

    /// The equilibrium at `F` from `q0` by chord steps with the kept factors
    /// only, keeping them (no factorization at the solution): for a last,
    /// tiny step. `None` (and no change) if no factors are kept or the steps
    /// do not converge below `1e-10 L`; else the shape and its `|Q|_2` (N).
    ///
    /// # Errors
    /// As [`EquilibriumTracker::residual`].
    pub fn solve_chord<L: LinearLoad<E>>(
        &mut self,
        load: &L,
        f: &[f64],
        q0: &[f64],
    ) -> Result<Option<(DVector<f64>, f64)>> {
        let Some((q_lu, lu)) = self.factors.take() else {
            return Ok(None);
        };
        let dead = self.dead_with(load, f)?;
        let n = self.robot.n_free();
        let len = self.robot.length();
        let mut r = vec![0.0; n];
        let mut du = vec![0.0; n];
        let mut dq = vec![0.0; self.robot.n_q()];
        let known_residual = self.residual_from_state(load, f, q0, &mut r)?;
        let mut q = q0.to_vec();
        let mut prev = f64::INFINITY;
        let mut path = 0.0;
        let mut done = false;
        for it in 0..12 {
            if it > 0 || !known_residual {
                self.robot
                    .residual_into(&q, dead.as_slice(), &self.known, &mut r)?;
            }
            let Some(step) = self.plain_step(&mut q, &lu, &r, &mut du, &mut dq, 0.5 * prev)? else {
                break;
            };
            path += step;
            let converged = chord_converged(step, prev, path, len);
            prev = step;
            if converged {
                done = true;
                break;
            }
        }
        self.factors = Some((q_lu, lu));
        if !done {
            return Ok(None);
        }
        self.robot
            .residual_into(&q, dead.as_slice(), &self.known, &mut r)?;
        let residual_n = norm2(&r);
        self.state = Some(State {
            f: f.to_vec(),
            q: q.clone(),
            r,
            residual_n,
        });
        Ok(Some((DVector::from_vec(q), residual_n)))
    }

    /// One plain Newton (or, with old factors, chord) step at `q` with the
    /// factors `lu` for the residual `r` at `q` (computed by the caller):
    /// the step is applied unless it is not finite, longer than a quarter
    /// of the robot, or not shorter than `limit` (m). Returns the step's
    /// size (m) if applied. `du` (`n_free`) and `dq` (`n_q`) are scratch.
    fn plain_step(
        &self,
        q: &mut [f64],
        lu: &AutoFactors,
        r: &[f64],
        du: &mut [f64],
        dq: &mut [f64],
        limit: f64,
    ) -> Result<Option<f64>> {
        du.copy_from_slice(r);
        lu.solve_in_place(du)?;
        let step = du.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !step.is_finite() || step > 0.25 * self.robot.length() || step > limit {
            return Ok(None);
        }
        self.robot.expand_step_into(du, dq)?;
        q.iter_mut().zip(dq.iter()).for_each(|(a, b)| *a += b);
        Ok(Some(step))
    }

    /// The solve; without `fallback` a failure of the chord and plain Newton
    /// steps is `None`.
    ///
    /// Warm starts take chord (modified Newton) steps with the kept
    /// factorization: a few residuals, then one fresh factorization at the
    /// solution for exact derivatives (kept for the next call).
    fn solve_opt<L: LinearLoad<E>>(
        &mut self,
        load: &L,
        f: &[f64],
        q0: &[f64],
        fallback: bool,
    ) -> Result<Option<TrackedEquilibrium>> {
        // asked again at the last solution (a warm start): nothing to solve.
        // The kept factors may be those of a point up to 1e-8 L away (a
        // chord solve keeps them, see solve_chord): the derivatives they give
        // differ by about 1e-7 relative, which the next Gauss–Newton step of
        // an estimator absorbs.
        if let (Some(st), Some((q_lu, lu))) = (&self.state, &self.factors) {
            let near = q_lu
                .iter()
                .zip(q0)
                .all(|(a, b)| (a - b).abs() <= 1e-8 * self.robot.length());
            if st.f == f && st.q == q0 && near {
                return Ok(Some(TrackedEquilibrium {
                    q: DVector::from_column_slice(q0),
                    factors: lu.clone(),
                    residual_n: st.residual_n,
                }));
            }
        }
        let dead = self.dead_with(load, f)?;
        let n = self.robot.n_free();
        let len = self.robot.length();
        let mut r = vec![0.0; n];
        let mut du = vec![0.0; n];
        let mut dq = vec![0.0; self.robot.n_q()];
        // the residual at q0 from the remembered one, if q0 is its shape
        let known_residual = self.residual_from_state(load, f, q0, &mut r)?;
        if let Some((q_lu, lu)) = self.factors.take() {
            let mut q = q0.to_vec();
            let mut prev = f64::INFINITY;
            let mut path = 0.0;
            let mut done = false;
            let mut moved = false;
            for it in 0..12 {
                if it > 0 || !known_residual {
                    self.robot
                        .residual_into(&q, dead.as_slice(), &self.known, &mut r)?;
                }
                let Some(step) = self.plain_step(&mut q, &lu, &r, &mut du, &mut dq, 0.5 * prev)?
                else {
                    break;
                };
                path += step;
                let converged = chord_converged(step, prev, path, len);
                moved |= step > 1e-10 * len;
                prev = step;
                if converged {
                    done = true;
                    break;
                }
            }
            if done {
                // the kept factors are exact if q has not left their point
                let same = !moved && q_lu.iter().zip(q0).all(|(a, b)| a == b);
                let lu = if same {
                    self.robot
                        .residual_into(&q, dead.as_slice(), &self.known, &mut r)?;
                    lu
                } else {
                    // fresh factors at the solution, with its residual
                    self.robot.residual_and_tangent_into(
                        &q,
                        dead.as_slice(),
                        &self.known,
                        &mut r,
                        &mut self.kmat,
                    )?;
                    self.linear.factor(&self.kmat, FactorOptions::default())?
                };
                return Ok(Some(self.solved(f, q, lu, r)));
            }
            self.factors = Some((q_lu, lu));
        }
        let mut q = q0.to_vec();
        let mut prev = f64::INFINITY;
        for _ in 0..12 {
            // Newton: residual and tangent at q in one pass
            self.robot.residual_and_tangent_into(
                &q,
                dead.as_slice(),
                &self.known,
                &mut r,
                &mut self.kmat,
            )?;
            let lu = match self.linear.factor(&self.kmat, FactorOptions::default()) {
                Ok(lu) => lu,
                Err(_) => break,
            };
            let Some(step) = self.plain_step(&mut q, &lu, &r, &mut du, &mut dq, 0.9 * prev)? else {
                break;
            };
            prev = step;
            if step <= 1e-10 * len {
                self.robot
                    .residual_into(&q, dead.as_slice(), &self.known, &mut r)?;
                return Ok(Some(self.solved(f, q, lu, r)));
            }
        }
        if !fallback {
            return Ok(None);
        }
        self.fallback(load, f, q0).map(Some)
    }

    /// The globalized [`StaticSolver`] from `q0`, its solution factored and
    /// kept.
    fn fallback<L: LinearLoad<E>>(
        &mut self,
        load: &L,
        f: &[f64],
        q0: &[f64],
    ) -> Result<TrackedEquilibrium> {
        let dead = self.dead_with(load, f)?;
        let mut r = vec![0.0; self.robot.n_free()];
        let loads = load.add_to(&self.robot, &self.known, f);
        let eq = self
            .solver
            .solve_with(&self.robot, &loads, Some(q0), &mut self.linear)?;
        self.robot.residual_and_tangent_into(
            eq.q.as_slice(),
            dead.as_slice(),
            &self.known,
            &mut r,
            &mut self.kmat,
        )?;
        let lu = self.linear.factor(&self.kmat, FactorOptions::default())?;
        let mut out = self.solved(f, eq.q.data.into(), lu, r);
        out.residual_n = eq.report.residual_norm_n;
        Ok(out)
    }

    /// `Q(q0, F)` into `r` from the remembered equilibrium if `q0` is its
    /// shape (`Q(q, F) = Q(q, F_s) + Mᵀ G (F − F_s)`); false otherwise.
    fn residual_from_state<L: LinearLoad<E>>(
        &self,
        load: &L,
        f: &[f64],
        q0: &[f64],
        r: &mut [f64],
    ) -> Result<bool> {
        match &self.state {
            Some(st) if st.q == q0 && st.f.len() == f.len() => {
                let df: Vec<f64> = f.iter().zip(&st.f).map(|(a, b)| a - b).collect();
                let gdf = load.force(&self.robot, &df)?;
                self.robot.restrict_into(gdf.as_slice(), r)?;
                r.iter_mut().zip(&st.r).for_each(|(a, b)| *a += b);
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    /// Records a solved equilibrium (`r` its residual, `lu` the factors at
    /// `q`) and returns it.
    fn solved(
        &mut self,
        f: &[f64],
        q: Vec<f64>,
        lu: AutoFactors,
        r: Vec<f64>,
    ) -> TrackedEquilibrium {
        let residual_n = norm2(&r);
        self.factors = Some((q.clone(), lu.clone()));
        self.state = Some(State {
            f: f.to_vec(),
            q: q.clone(),
            r,
            residual_n,
        });
        TrackedEquilibrium {
            q: DVector::from_vec(q),
            factors: lu,
            residual_n,
        }
    }
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
mod tests {
    use super::chord_converged;

    /// Chord steps contracting at a constant rate `ρ` from an error of
    /// `7e-4 L` (a short path: its length is not what is tested here): the test stops where the distance left is below
    /// `1e-10 L` (never above it), for `ρ` up to 1/2, and at ρ = 0.1 one
    /// step before the step itself falls below the bound (what it saves);
    /// a first step, or a slower contraction, stops only below the bound.
    #[test]
    fn chord_steps_stop_where_the_contraction_predicts_the_bound() {
        let len = 0.24;
        let tol = 1e-10 * len;
        for rho in [0.01, 0.1, 0.3, 0.5] {
            let mut err: f64 = 7e-4 * len;
            let mut prev = f64::INFINITY;
            let mut steps = 0;
            loop {
                let step = err * (1.0 - rho);
                err *= rho;
                steps += 1;
                if chord_converged(step, prev, 0.0, len) {
                    break;
                }
                prev = step;
                assert!(steps < 100);
            }
            assert!(err <= tol * (1.0 + 1e-12), "rho {rho}: {err:e} left");
            // the plain test would take the step after, below the bound
            let plain = (1..100)
                .find(|&k| 7e-4 * len * rho.powi(k - 1) * (1.0 - rho) <= tol)
                .unwrap_or(100);
            if rho == 0.1 {
                assert_eq!(steps + 1, plain, "rho {rho}");
            }
            assert!(steps <= plain);
        }
        // a first step is taken on its own size only
        assert!(!chord_converged(2.0 * tol, f64::INFINITY, 0.0, len));
        assert!(chord_converged(0.5 * tol, f64::INFINITY, 0.0, len));
        // a contraction slower than 1/2 is not trusted
        assert!(!chord_converged(1.1 * tol, 1.9 * tol, 0.0, len));
        assert!(chord_converged(1.1 * tol, 40.0 * tol, 0.0, len));
        // nor one along a path longer than 1e-4 L (far from the solution)
        assert!(!chord_converged(1.1 * tol, 40.0 * tol, 2e-4 * len, len));
    }
}
