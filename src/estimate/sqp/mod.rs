//! The constrained estimator (25) by sequential quadratic programming.
//!
//! Unknowns: the free coordinates `u` of any model (`q = φ(u)`: on the
//! clamped robot linear, the base stretch and nodes 1…N; on a structure
//! with rigid joints, such as the parallel robot, nonlinear in the bodies'
//! rotations) and the load parameters `F`. `M = ∂φ/∂u` below is taken at
//! the QP's point, and `Mᵀ G` is kept constant only where `φ` is linear.
//! On the clamped robot the objective is quadratic in `(u, F)` and only
//! the equilibrium `Q(F, q, P) = 0` (17) is nonlinear. Each iteration takes a full-space step `(du, dF)` from the QP
//!
//! ```text
//! min_{du, dF}  ½ dᵀ P d + cᵀ d
//!   P = 2 [Mᵀ AᵀWA M, 0; 0, α H],  c = 2 [Mᵀ AᵀW e; α H F]
//!   s.t.  −K du + Mᵀ G dF = −Q        (linearized equilibrium)
//!         lo ≤ d_j · w(s_j; F + dF) ≤ hi   (optional bounds on the load)
//! ```
//!
//! `P` holds the objective's Hessian only (no constraint curvature): a
//! Gauss–Newton SQP, whose fixed points are the KKT points of (25), the same
//! as the reduced method's. How the QP is solved:
//!
//! - **No bounds** (`EstimatorSettings::bounds` empty): the QP has equality
//!   constraints only, and its KKT system is solved directly, without an
//!   interior-point method: block elimination with the factors of `K`
//!   (`du = K⁻¹ (Q + Mᵀ G dF)`) leaves for `dF` the Gauss–Newton system of
//!   the reduced problem at the linearized residual `e' = e + A M K⁻¹ Q`,
//!   solved in the representer form (an `n_ob × n_ob` Cholesky, see
//!   the Gauss–Newton step (30)) up to `n_F` observed components, beyond in
//!   the `n_F × n_F` form accumulated over the marker rows (work linear in
//!   the markers; the QP's size does not grow with them). One tangent factorization per iteration; the
//!   equality multipliers follow from the `du` rows, `K λ = 2 Mᵀ AᵀW (e + A M du)`.
//! - **With bounds**: the bounds act on `F` only, so on a known active set
//!   the QP is again equality-constrained and solved exactly through the
//!   same reduced system (`N = Jᵀ W J + α H` applied by Woodbury, one
//!   `n_act × n_act` Cholesky for the active rows' multipliers).
//!   Active-set iterations (drop a negative multiplier, add the most
//!   violated bound) start from the last QP's active set and stop at the
//!   QP's KKT conditions, a certificate of optimality for this convex QP.
//!   Clarabel's interior-point method solves the QP when there is no
//!   active set yet (the first QP of an estimator) or when the warm-started
//!   iterations fail; its solution's active set then seeds the same exact
//!   solve, and only if that fails too is clarabel's step used as it is.
//!   For clarabel the QP data are rescaled so that its absolute tolerances
//!   act as relative ones (the QP is homogeneous in its right-hand sides);
//!   `du` is always recomputed from `dF` with the factorization of
//!   `K`, so the linearized equilibrium holds to round-off. (Clarabel alone
//!   resolves the weakly penalized directions, the slopes `w'`, only to
//!   about 1e-5 of `|F|`; the exact solve does not have that limit.)
//!
//! Globalization: backtracking on the ℓ1 merit function `φ = J + μ |Q|₁`,
//! `μ` above the largest equality multiplier, each trial pulled back onto
//! the equilibrium manifold by chord steps (a second-order correction),
//! within a trust region on the step's predicted marker motion. Its radius
//! starts at `max_observation_jump_m`, doubles after a full step it cut
//! (up to the robot's length) and shrinks with the step after a
//! backtracked one (never below the start): a first estimate of a large
//! deflection from the unloaded shape (18 cm of marker motion on the 24 cm
//! exudyn cable) then takes 8 QPs where a fixed 2 cm radius took 14, and
//! its stream's first observation is taken in one go instead of through
//! ten intermediate observations of 3–6 QPs each (39–48 QPs in all; see
//! `driver::run_step`).
//! Convergence is judged on feasibility and on the predicted decrease along
//! the manifold, `−g̃ᵀ dF` with `g̃` the reduced gradient (29) at the
//! feasibility-restored residual `e'` (for a step of clarabel's: `−cᵀ d`,
//! to 1e-9), and on the bounds holding at the current `F` (in the local
//! frame they move with the shape): below `tolerance × max(J, n_ob)`, or,
//! halved (`dFᵀ N dF`), below `κ²` (the statistical test of
//! `EstimatorSettings::statistical_tolerance`, as the Newton backend's). The
//! covariance factor is formed once, from the last QP's Gauss–Newton
//! factor.
//! After convergence the shape is re-solved at the final `F` (chord steps
//! with the last factorization, or a few Newton steps) so the estimate is
//! an exact equilibrium. The last QP's factored tangent and derivatives are
//! kept: the next warm step's first QP, at this estimate, starts from them,
//! so a warm step of a stream factors once (the second QP's tangent).

mod bounded;
mod iterate;
mod trust;

use clarabel::solver::SolverStatus;

use crate::element::NodeKinematics;
use crate::error::{Error, Result};
use crate::linsolve::SolverKind;
use crate::linsolve::{
    AutoFactors, AutoSolver, FactorOptions, Factorization, SymmetricMatrix, SymmetricPattern,
    TangentSolver,
};
use crate::numeric::{dot, max_abs};
use crate::observe::{ObsRow, ObservationOperator};
use crate::outcome::NonFiniteAt;
use crate::statics::tracker::FactoredTangent;

use super::driver::{Method, Solved, Stream, run_step};
use super::load_model::field_rod;
use super::problem::{Derivs, GnFactor, Problem, columns};
use super::{
    Backend, Estimate, EstimateStatus, EstimationModel, Estimator, EstimatorSettings, LoadModel,
    Observation,
};

/// Why an SQP subproblem was not solved: clarabel's status, or an error of
/// the linear algebra around it.
#[derive(Debug)]
enum QpError {
    /// Clarabel stopped without a solution.
    Clarabel(SolverStatus),
    /// Another error (a singular tangent, a Gauss–Newton matrix that is not
    /// positive definite, …).
    Other(Error),
}

impl From<Error> for QpError {
    fn from(e: Error) -> Self {
        QpError::Other(e)
    }
}

impl QpError {
    /// The estimator's status for a subproblem that failed this way; an
    /// error that says nothing about the subproblem is passed on.
    fn status(self) -> Result<EstimateStatus> {
        match self {
            QpError::Clarabel(s) => Ok(EstimateStatus::QpNotSolved(s)),
            QpError::Other(Error::Singular { .. }) => Ok(EstimateStatus::SingularTangent),
            QpError::Other(Error::NotPositiveDefinite { .. }) => {
                Ok(EstimateStatus::NotPositiveDefinite)
            }
            QpError::Other(Error::NonFinite { .. }) => Ok(EstimateStatus::NonFinite {
                at: NonFiniteAt::Tangent,
            }),
            QpError::Other(e) => Err(e),
        }
    }
}

/// The SQP estimator (backend "sqp").
///
/// # Example
/// ```
/// use softrod::estimate::{Backend, Estimator, EstimatorSettings, SqpEstimator, Observation};
/// use softrod::{scene::Scene, statics::StaticSolver};
/// let scene = Scene::two_section();
/// let (robot, loads) = (scene.robot()?, scene.loads()?);
/// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
/// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[4, 8, 12, 16, 20])?;
/// let settings = EstimatorSettings { backend: Backend::Sqp, alpha: Some(1.0), ..Default::default() };
/// let mut est = SqpEstimator::new(&robot, &loads, &settings)?;
/// let e = est.step(&obs)?;
/// assert!(e.report.status.is_converged());
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct SqpEstimator<M: EstimationModel> {
    stream: Stream<M>,
    /// Triplets `(free row, F column, value)` of `Mᵀ G` at the last QP's
    /// point (constant where the map `q = φ(u)` is linear).
    g_free: Vec<(usize, usize, f64)>,
    /// Whether `g_free` is constant (a linear map `q = φ(u)`: the clamped
    /// robot, a structure without rigid joints); else it is formed again
    /// at each QP's point.
    g_fixed: bool,
    /// Upper-triangle triplets of `H` (constant).
    h_upper: Vec<(usize, usize, f64)>,
    /// The factored load Gram matrix `B` (distributed load with bounds).
    gram_lu: Option<AutoFactors>,
    /// The bounds active in the last QP's solution (indices into the rows
    /// of the bounds' inequalities): the first guess for the next QP
    /// (`None` before the first: clarabel then finds one).
    active_set: Option<Vec<usize>>,
    /// The last QP's factored tangent and derivatives, taken at (within a
    /// final chord step of `1e-10 L` of) the last estimate's shape, for
    /// its observation rows: the first QP of the next warm step starts
    /// there instead of factoring again.
    warm_qp: Option<WarmQp>,
}

/// The kept last QP (see the `warm_qp` field of `SqpEstimator`).
#[derive(Debug, Clone)]
struct WarmQp {
    q: Vec<f64>,
    rows: Vec<ObsRow>,
    tangent: FactoredTangent,
    dv: Derivs,
}

impl<M: EstimationModel> SqpEstimator<M> {
    /// The warm tracker of the equilibria (a controller's inverse
    /// kinematics shares its kept factors, see
    /// [`super::NewtonEstimator`]'s).
    pub(crate) fn tracker_mut(&mut self) -> &mut crate::statics::Tracker<M> {
        self.stream.problem.tracker()
    }

    /// What the equilibria of the estimates so far cost.
    pub(crate) fn counts(&self) -> crate::statics::WarmCounts {
        self.stream.problem.tracker_ref().counts()
    }

    /// The estimation problem (tests set its Gauss–Newton form).
    #[cfg(test)]
    pub(crate) fn problem_mut(&mut self) -> &mut super::problem::Problem<M> {
        &mut self.stream.problem
    }

    /// An estimator for `robot` (the clamped robot or any structure) under
    /// the known loads `known` (both borrowed; the estimator keeps copies). `settings.backend` must be
    /// [`super::Backend::Sqp`]: the backend is chosen once, by the settings
    /// ([`EstimatorSettings::build_for`] builds the one they name).
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for invalid settings or bounds, or
    /// another backend (`estimator.backend`); the errors of
    /// [`crate::structure::Assembled::validate_loads`].
    ///
    /// # Example
    /// See [`SqpEstimator`].
    pub fn new(robot: &M, known: &M::Loads, settings: &EstimatorSettings) -> Result<Self> {
        if settings.backend != super::Backend::Sqp {
            return Err(crate::Error::invalid(
                "estimator.backend",
                settings.backend.name(),
                "SqpEstimator runs the sqp backend (build the one the settings name with EstimatorSettings::build_for)",
            ));
        }
        Self::over(Problem::new(
            robot.clone(),
            known.clone(),
            settings.clone(),
        )?)
    }

    /// The estimator over `problem` (its settings naming the sqp backend):
    /// the constant triplets of `Mᵀ G` and `H` and, for bounds on a
    /// distributed load, the factored load Gram matrix.
    pub(crate) fn over(problem: Problem<M>) -> Result<Self> {
        let u = problem.robot().reference_free_coordinates();
        let (g_free, h_upper) = problem.load_triplets(u.as_slice())?;
        let g_fixed = EstimationModel::dof_map(problem.robot()).is_linear();
        let gram_lu = match problem.load() {
            LoadModel::Distributed if !problem.settings().bounds.is_empty() => Some(gram_factors(
                problem.robot(),
                problem.settings().statics.linear_solver,
            )?),
            _ => None,
        };
        Ok(SqpEstimator {
            stream: Stream::new(problem),
            g_free,
            g_fixed,
            h_upper,
            gram_lu,
            active_set: None,
            warm_qp: None,
        })
    }

    /// The model.
    pub fn robot(&self) -> &M {
        self.stream.problem.robot()
    }

    /// The last QP's factored tangent and derivatives (kept for the next
    /// warm step), taken out, if they were taken at `q` for `op`'s rows.
    pub(crate) fn take_final_qp(
        &mut self,
        q: &[f64],
        op: &ObservationOperator,
    ) -> Option<(FactoredTangent, Derivs)> {
        let w = self.warm_qp.take()?;
        (w.q == q && w.rows == op.rows()).then_some((w.tangent, w.dv))
    }

    /// One QP at `(q, F)`: the tangent `K` assembled and factored at `q`,
    /// then the step `(du, dF)`, the largest equality multiplier, the
    /// objective's linear term `c` and whether a bound is active. Without
    /// bounds the QP is the equality-constrained one, solved exactly
    /// through the factorization of `K` ([`SqpEstimator::equality_qp`]);
    /// with bounds `bounded_qp` (whose clarabel matrix reads `K` itself).
    /// Returns the step and the factored tangent it was computed with (for
    /// the second-order correction); the tracker keeps the factors for its
    /// chord steps. `u`: the free coordinates of `q`.
    #[allow(clippy::too_many_arguments)]
    fn qp(
        &mut self,
        op: &ObservationOperator,
        u: &[f64],
        q: &[f64],
        f: &[f64],
        e: &[f64],
        r: &[f64],
        alpha: f64,
    ) -> std::result::Result<(QpStep, FactoredTangent), QpError> {
        // at the last estimate's shape (a warm step's first QP) its
        // factored tangent and derivatives are known
        let warm = self
            .warm_qp
            .take()
            .filter(|w| w.q == q && w.rows == op.rows());
        let (tangent, cached) = match warm {
            Some(w) => (w.tangent, Some(w.dv)),
            None => match self.stream.problem.unloaded_tangent(q) {
                // a cold start's first QP, at the unloaded shape
                Some(t) => (t, None),
                None => (self.stream.problem.factor_tangent(q)?, None),
            },
        };
        let (k, lu) = (&tangent.matrix, &tangent.factors);
        if !self.g_fixed {
            self.g_free = self.stream.problem.load_triplets(u)?.0;
        }
        let c = self.linear_term(op, u, f, e, alpha)?;
        let step = if self.stream.problem.settings().bounds.is_empty() {
            self.equality_qp(k, lu, op, u, f, e, r, alpha, c, cached)?
        } else {
            let (step, act) = self.bounded_qp(k, lu, op, u, q, f, e, r, alpha, c)?;
            self.active_set = Some(act);
            step
        };
        self.stream
            .problem
            .tracker()
            .keep_factors(q, tangent.factors.clone())?;
        Ok((step, tangent))
    }

    /// The QP objective's linear term `c = 2 [Mᵀ AᵀW e; α H F]` at `u`.
    fn linear_term(
        &self,
        op: &ObservationOperator,
        u: &[f64],
        f: &[f64],
        e: &[f64],
        alpha: f64,
    ) -> Result<Vec<f64>> {
        let problem = &self.stream.problem;
        let mut wa = vec![0.0; problem.robot().n_q()];
        for ((row, w), ei) in op.rows().iter().zip(op.weights()).zip(e) {
            for &(j, v) in row.entries() {
                wa[j] += 2.0 * w * ei * v;
            }
        }
        let mut c: Vec<f64> = problem.restrict(u, &wa)?.data.into();
        c.extend(problem.penalty_grad(f)?.iter().map(|v| 2.0 * alpha * v));
        Ok(c)
    }

    /// The equality-constrained QP (no bounds), exactly: its KKT system
    /// `[P, A_eqᵀ; A_eq, 0]` is solved by block elimination with the
    /// factors of `K` (`du = K⁻¹ (Q + Mᵀ G dF)`) and, for `dF`, the Gauss–Newton
    /// system of the reduced problem at the linearized residual
    /// `e' = e + A M K⁻¹ Q` (the Gauss–Newton step (30): an `n_ob × n_ob` Cholesky in
    /// the representer form). The equality multipliers follow from the `du`
    /// rows of the KKT system, `K λ = 2 Mᵀ AᵀW (e + A M du)`.
    #[allow(clippy::too_many_arguments)]
    fn equality_qp(
        &self,
        k: &SymmetricMatrix,
        lu: &AutoFactors,
        op: &ObservationOperator,
        u: &[f64],
        f: &[f64],
        e: &[f64],
        r: &[f64],
        alpha: f64,
        c: Vec<f64>,
        cached: Option<Derivs>,
    ) -> Result<QpStep> {
        let Unconstrained {
            dv,
            df0: df,
            g1,
            fac,
        } = self.unconstrained(lu, op, u, f, e, r, alpha, cached)?;
        let dec_opt = (-dot(&g1, &df)).max(0.0);
        let du = self.du_from(lu, r, &df)?;
        let lambda_max = self.lambda_max(&dv, op, u, e, &du)?;
        Ok(QpStep {
            du,
            df,
            lambda_max,
            c,
            active: false,
            exact: true,
            bound_violation: 0.0,
            dec_opt: Some(dec_opt),
            derivs: Some((dv, fac)),
            tangent_max_abs: k.max_abs(),
        })
    }

    /// The QP's solution without bounds, by block elimination: the
    /// restored residual `e' = e + A M K⁻¹ Q`, the derivatives at `q`, the
    /// Gauss–Newton load step there and the reduced gradient at `e'`.
    /// `u`: the free coordinates of `q`; `cached`: the derivatives at `q`,
    /// if known.
    #[allow(clippy::too_many_arguments)]
    fn unconstrained(
        &self,
        lu: &AutoFactors,
        op: &ObservationOperator,
        u: &[f64],
        f: &[f64],
        e: &[f64],
        r: &[f64],
        alpha: f64,
        cached: Option<Derivs>,
    ) -> Result<Unconstrained> {
        let problem = &self.stream.problem;
        let mut w0 = r.to_vec();
        lu.solve_in_place(&mut w0)?;
        let dq0 = problem.expand(u, &w0)?;
        let e1: Vec<f64> = e
            .iter()
            .zip(op.rows())
            .map(|(ei, row)| ei + row.apply(dq0.as_slice()))
            .collect();
        let dv = match cached {
            Some(dv) => dv,
            None => problem.derivs_at(u, lu, op)?,
        };
        let (df0, fac) = problem.gn_solve(&dv, op, &e1, f, alpha)?;
        let g1 = problem.gradient(&dv, op, &e1, f, alpha)?;
        Ok(Unconstrained { dv, df0, g1, fac })
    }

    /// `du` from the linearized equilibrium, `K du = Q + Mᵀ G dF`.
    fn du_from(&self, lu: &AutoFactors, r: &[f64], df: &[f64]) -> Result<Vec<f64>> {
        let mut rhs = r.to_vec();
        for &(i, j, v) in &self.g_free {
            rhs[i] += v * df[j];
        }
        lu.solve_in_place(&mut rhs)?;
        Ok(rhs)
    }

    /// The largest equality multiplier, from the `du` rows of the KKT
    /// system (the bounds do not involve `u`):
    /// `λ = 2 Σ_i w_i ẽ_i K⁻¹ Mᵀ a_iᵀ`, `ẽ = e + A M du`.
    fn lambda_max(
        &self,
        dv: &Derivs,
        op: &ObservationOperator,
        u: &[f64],
        e: &[f64],
        du: &[f64],
    ) -> Result<f64> {
        let problem = &self.stream.problem;
        let dq = problem.expand(u, du)?;
        let mut lam = vec![0.0; problem.robot().n_q()];
        for (((zi, row), w), ei) in columns(&dv.z).zip(op.rows()).zip(op.weights()).zip(e) {
            let s = 2.0 * w * (ei + row.apply(dq.as_slice()));
            lam.iter_mut().zip(zi).for_each(|(a, b)| *a += s * b);
        }
        Ok(max_abs(&lam))
    }
}

impl<M: EstimationModel> Method<M> for SqpEstimator<M> {
    const BACKEND: Backend = Backend::Sqp;

    fn stream(&mut self) -> &mut Stream<M> {
        &mut self.stream
    }

    fn solve_one(
        &mut self,
        op: &ObservationOperator,
        f0: Vec<f64>,
        q0: Vec<f64>,
        alpha: f64,
    ) -> Result<Solved> {
        self.iterate(op, f0, q0, alpha)
    }
}

/// The factors of the load Gram matrix `B = ∫ Sᵀ S dX` (22) over the
/// field rod's coordinates (the first of `q`): element `e` couples the
/// coordinates of its two nodes.
fn gram_factors<M: EstimationModel>(model: &M, kind: SolverKind) -> Result<AutoFactors> {
    let rod = field_rod(model)?;
    let nd = M::Element::NODE_DOFS;
    let elements = (0..rod.elements().len()).map(|e| (e * nd..(e + 2) * nd).collect::<Vec<_>>());
    let pattern = std::sync::Arc::new(SymmetricPattern::from_elements(rod.n_q(), elements)?);
    let gram = rod.load_gram();
    let mut b = SymmetricMatrix::zeros(pattern.clone());
    let slots: Vec<(usize, usize)> = b.iter_upper().map(|(i, j, _)| (i, j)).collect();
    for (i, j) in slots {
        b.add(i, j, gram.get(i, j))?;
    }
    let mut solver = AutoSolver::with_kind(&pattern, kind)?;
    Ok(solver.factor(&b, FactorOptions::default())?)
}

/// One SQP subproblem's solution.
struct QpStep {
    /// Step of the free coordinates (m).
    du: Vec<f64>,
    /// Step of the load parameters.
    df: Vec<f64>,
    /// The largest equality multiplier `|λ|∞` (for the merit weight).
    lambda_max: f64,
    /// The objective's linear term `c` over `(u, F)`.
    c: Vec<f64>,
    /// Whether a bound is active in the solution.
    active: bool,
    /// Whether the step solves the QP exactly (else it is clarabel's, to
    /// its tolerances).
    exact: bool,
    /// The largest violation of a bound at the current `F`, relative to
    /// the bounded quantity's scale (0 if all hold).
    bound_violation: f64,
    /// The predicted decrease along the constraint manifold,
    /// `−g̃ᵀ dF` with `g̃` the reduced gradient (29) at the
    /// feasibility-restored residual `e' = e + A M K⁻¹ Q`, when known
    /// (no bound active). Unlike `−cᵀ d` it carries no term linear in the
    /// equilibrium residual `Q`, so it reaches the round-off floor at once.
    dec_opt: Option<f64>,
    /// The derivatives at `q` and the covariance factor there, when the
    /// step computed them.
    derivs: Option<(Derivs, GnFactor)>,
    /// `|K|_max` of the QP's tangent (for the round-off floor of `|Q|`).
    tangent_max_abs: f64,
}

/// The equality-constrained QP's parts (see [`SqpEstimator::unconstrained`]).
struct Unconstrained {
    /// Adjoint fields and marker Jacobian at `q`.
    dv: Derivs,
    /// The Gauss–Newton load step at the restored residual.
    df0: Vec<f64>,
    /// The reduced gradient (29) at the restored residual.
    g1: Vec<f64>,
    /// The Gauss–Newton system's factor at `q` (the covariance factor is
    /// formed from it once, at the end).
    fac: GnFactor,
}

impl<M: EstimationModel> Estimator<M::Loads> for SqpEstimator<M> {
    fn step(&mut self, observation: &Observation) -> Result<Estimate> {
        run_step(self, observation)
    }

    fn backend(&self) -> Backend {
        Backend::Sqp
    }

    fn alpha(&self) -> Option<f64> {
        self.stream.alpha
    }

    fn reset(&mut self) {
        self.stream.reset();
        self.warm_qp = None;
    }

    fn set_known_loads(&mut self, known: M::Loads) -> Result<()> {
        self.stream.problem.set_known(known)?;
        self.warm_qp = None;
        Ok(())
    }
}
