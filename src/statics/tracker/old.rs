//! The estimators' tracker as it was before the one generic tracker (kept
//! for the comparison of old and new in `super::tests` only).
#![allow(dead_code, missing_docs, clippy::all)]

use nalgebra::DVector;

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{check_len, Result};
use crate::linsolve::{
    AutoFactors, AutoSolver, FactorOptions, Factorization, SymmetricMatrix, TangentSolver,
};
use crate::loads::Loads;
use crate::numeric::norm2;

use super::chord_converged;
use super::LinearLoad;
use crate::statics::{StaticSettings, StaticSolver};

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
/// ```ignore
/// use softrod::linsolve::Factorization;
/// use softrod::{scene::Scene, statics::EquilibriumTracker};
/// let scene = Scene::two_section();
/// let mut tracker = EquilibriumTracker::new(scene.robot()?, scene.loads()?, Default::default())?;
/// let q = tracker.robot().reference_configuration().as_slice().to_vec();
/// let t = tracker.factor_tangent(&q)?;
/// assert!(t.factors.is_positive_definite()); // the straight robot is stable
/// assert_eq!(t.matrix.n(), t.factors.n());
/// # Ok::<(), softrod::Error>(())
/// ```ignore
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
/// ```ignore
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
/// ```ignore
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
    /// ```ignore
    /// use softrod::linsolve::SolverKind;
    /// use softrod::{scene::Scene, statics::{EquilibriumTracker, StaticSettings}};
    /// let scene = Scene::two_section();
    /// let settings = StaticSettings { linear_solver: SolverKind::Sparse, ..Default::default() };
    /// let tracker = EquilibriumTracker::new(scene.robot()?, scene.loads()?, settings)?;
    /// assert_eq!(tracker.solver_kind(), SolverKind::Sparse);
    /// # Ok::<(), softrod::Error>(())
    /// ```ignore
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
    /// ```ignore
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
    /// ```ignore
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
    /// ```ignore
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
    /// ```ignore
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
