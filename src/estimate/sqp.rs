//! The constrained estimator (25) by sequential quadratic programming.
//!
//! Unknowns: the free coordinates `u` (so `q = q(u)`, linear: the base
//! stretch and nodes 1…N) and the load parameters `F`. The objective is
//! quadratic in `(u, F)`, only the equilibrium `Q(F, q, P) = 0` (17) is
//! nonlinear. Each iteration takes a full-space step `(du, dF)` from the QP
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
//!   interior-point method: block elimination with the banded LU of `K`
//!   (`du = K⁻¹ (Q + Mᵀ G dF)`) leaves for `dF` the Gauss–Newton system of
//!   the reduced problem at the linearized residual `e' = e + A M K⁻¹ Q`,
//!   solved in the representer form (an `n_ob × n_ob` Cholesky, see
//!   `Core::gn_step`). One tangent factorization per iteration; the
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
//!   `du` is always recomputed from `dF` with the banded factorization of
//!   `K`, so the linearized equilibrium holds to round-off. (Clarabel alone
//!   resolves the weakly penalized directions, the slopes `w'`, only to
//!   about 1e-5 of `|F|`; the exact solve does not have that limit.)
//!
//! Globalization: backtracking on the ℓ1 merit function `φ = J + μ |Q|₁`,
//! `μ` above the largest equality multiplier, each trial pulled back onto
//! the equilibrium manifold by chord steps (a second-order correction).
//! Convergence is judged on feasibility and on the predicted decrease along
//! the manifold, `−g̃ᵀ dF` with `g̃` the reduced gradient (29) at the
//! feasibility-restored residual `e'` (for a step of clarabel's: `−cᵀ d`,
//! to 1e-9), and on the bounds holding at the current `F` (in the local
//! frame they move with the shape).
//! After convergence the shape is re-solved at the final `F` (a chord step
//! with the last factorization, or a few Newton steps) so the estimate is
//! an exact equilibrium.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
    SupportedConeT, ZeroConeT,
};

use crate::assembly::Robot;
use crate::element::{hermite, Element};
use crate::error::{Error, Result};
use crate::linsolve::BandedLu;
use crate::loads::Loads;

use super::{
    dot, norm2, run_step, Backend, BoundFrame, Core, Derivs, Estimate, EstimateCriterion,
    EstimateReport, EstimateStatus, Estimator, EstimatorSettings, LoadModel, ObsOp, Observation,
    Solved,
};
use crate::outcome::NonFiniteAt;

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
/// use softrod::estimate::{Estimator, EstimatorSettings, SqpEstimator, Observation};
/// use softrod::{scene::Scene, statics::StaticSolver};
/// let scene = Scene::two_section();
/// let (robot, loads) = (scene.robot()?, scene.loads()?);
/// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
/// let obs = Observation::at_nodes(&robot, &eq.q, &[4, 8, 12, 16, 20]);
/// let settings = EstimatorSettings { alpha: Some(1.0), ..EstimatorSettings::default() };
/// let mut est = SqpEstimator::new(robot, loads, settings)?;
/// let e = est.step(&obs)?;
/// assert!(e.report.status.is_converged());
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct SqpEstimator<E: Element> {
    core: Core<E>,
    /// Triplets `(free row, F column, value)` of `Mᵀ G` (constant).
    g_free: Vec<(usize, usize, f64)>,
    /// Upper-triangle triplets of `H` (constant).
    h_upper: Vec<(usize, usize, f64)>,
    /// The factored tangent of the last QP (for the second-order correction).
    last_lu: Option<BandedLu>,
    /// The factored load Gram matrix `B` (distributed load with bounds).
    gram_lu: Option<BandedLu>,
    /// The bounds active in the last QP's solution (indices into the rows
    /// of [`SqpEstimator::inequalities`]): the first guess for the next QP
    /// (`None` before the first: clarabel then finds one).
    active_set: Option<Vec<usize>>,
}

impl<E: Element> SqpEstimator<E> {
    /// An estimator for `robot` under the known loads `known`.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for invalid settings or bounds; the
    /// errors of [`Robot::validate_loads`].
    pub fn new(robot: Robot<E>, known: Loads, settings: EstimatorSettings) -> Result<Self> {
        let core = Core::new(robot, known, settings)?;
        let nq = core.robot.n_q();
        let nf = core.n_f;
        let mut g_free = Vec::new();
        let mut h_upper = Vec::new();
        for j in 0..nf {
            let mut ej = vec![0.0; nf];
            ej[j] = 1.0;
            let col = core.robot.restrict(&core.gen_force(&ej)?)?;
            for (i, v) in col.iter().enumerate() {
                if *v != 0.0 {
                    g_free.push((i, j, *v));
                }
            }
            let hcol = core.penalty_grad(&ej)?;
            for (i, v) in hcol.iter().enumerate().take(j + 1) {
                if *v != 0.0 {
                    h_upper.push((i, j, *v));
                }
            }
        }
        let _ = nq;
        let gram_lu = match core.settings.load_model {
            LoadModel::Distributed if !core.settings.bounds.is_empty() => Some(
                core.robot
                    .load_gram()
                    .clone()
                    .factor_scaled(0.0, "load Gram matrix")?,
            ),
            _ => None,
        };
        Ok(SqpEstimator {
            core,
            g_free,
            h_upper,
            last_lu: None,
            gram_lu,
            active_set: None,
        })
    }

    /// The robot.
    pub fn robot(&self) -> &Robot<E> {
        &self.core.robot
    }

    /// Rows `(coefficients over F, lo, hi)` of the load bounds at shape `q`.
    #[allow(clippy::type_complexity)]
    fn bound_rows(&self, q: &[f64]) -> Result<Vec<(Vec<(usize, f64)>, Option<f64>, Option<f64>)>> {
        let d = E::DIM;
        let nd = E::NODE_DOFS;
        let mut rows = Vec::new();
        for b in &self.core.settings.bounds {
            let (e, xi) = match self.core.settings.load_model {
                LoadModel::Distributed => self.core.robot.locate("bound.s_m", b.s_m)?,
                LoadModel::Concentrated { node } => {
                    if node == 0 {
                        (0, 0.0)
                    } else {
                        (node - 1, 1.0)
                    }
                }
            };
            let le = self.core.robot.elements()[e].length();
            let (sh, dsh, _) = hermite(xi, le);
            // world direction
            let dir: Vec<f64> = match b.frame {
                BoundFrame::World => b.direction.clone(),
                BoundFrame::Local => {
                    let mut t = vec![0.0; d];
                    for (k, dk) in dsh.iter().enumerate() {
                        for (i, ti) in t.iter_mut().enumerate() {
                            *ti += dk * q[e * nd + k * d + i];
                        }
                    }
                    let n = norm2(&t).max(1e-300);
                    t.iter_mut().for_each(|v| *v /= n);
                    if d == 2 {
                        let nrm = [-t[1], t[0]];
                        (0..2)
                            .map(|i| b.direction[0] * t[i] + b.direction[1] * nrm[i])
                            .collect()
                    } else {
                        // 3-D: tangent component only is frame-invariant; use world for the rest
                        b.direction.clone()
                    }
                }
            };
            let coeffs: Vec<(usize, f64)> = match self.core.settings.load_model {
                LoadModel::Distributed => {
                    let mut c = Vec::new();
                    for (k, sk) in sh.iter().enumerate() {
                        for (i, di) in dir.iter().enumerate() {
                            if sk * di != 0.0 {
                                c.push((e * nd + k * d + i, sk * di));
                            }
                        }
                    }
                    c
                }
                LoadModel::Concentrated { .. } => dir.iter().copied().enumerate().collect(),
            };
            rows.push((coeffs, b.min_n_per_m, b.max_n_per_m));
        }
        Ok(rows)
    }

    /// One QP at `(q, F)` with the tangent factored there: the step
    /// `(du, dF)`, the largest equality multiplier, the objective's linear
    /// term `c` and whether a bound is active. Without bounds the QP is the
    /// equality-constrained one, solved exactly through the banded
    /// factorization of `K` ([`SqpEstimator::equality_qp`]); with bounds
    /// [`SqpEstimator::bounded_qp`].
    fn qp(
        &mut self,
        op: &ObsOp,
        q: &[f64],
        f: &[f64],
        e: &[f64],
        r: &[f64],
        alpha: f64,
    ) -> std::result::Result<QpStep, QpError> {
        let lu = self.core.factor(q)?;
        let c = self.linear_term(op, f, e, alpha)?;
        let step = if self.core.settings.bounds.is_empty() {
            self.equality_qp(&lu, op, f, e, r, alpha, c)?
        } else {
            self.bounded_qp(&lu, op, q, f, e, r, alpha, c)?
        };
        self.core.lu_cache = Some((q.to_vec(), lu.clone()));
        self.last_lu = Some(lu);
        Ok(step)
    }

    /// The QP objective's linear term `c = 2 [Mᵀ AᵀW e; α H F]`.
    fn linear_term(&self, op: &ObsOp, f: &[f64], e: &[f64], alpha: f64) -> Result<Vec<f64>> {
        let core = &self.core;
        let (nd, d) = (E::NODE_DOFS, E::DIM);
        let mut wa = vec![0.0; core.robot.n_q()];
        for (i, row) in op.rows.iter().enumerate() {
            for k in 0..4 {
                wa[row.e * nd + k * d + row.comp] += 2.0 * op.wt[i] * e[i] * row.w[k];
            }
        }
        let mut c = core.robot.restrict(&wa)?;
        c.extend(core.penalty_grad(f)?.iter().map(|v| 2.0 * alpha * v));
        Ok(c)
    }

    /// The equality-constrained QP (no bounds), exactly: its KKT system
    /// `[P, A_eqᵀ; A_eq, 0]` is solved by block elimination with the banded
    /// LU of `K` (`du = K⁻¹ (Q + Mᵀ G dF)`) and, for `dF`, the Gauss–Newton
    /// system of the reduced problem at the linearized residual
    /// `e' = e + A M K⁻¹ Q` ([`Core::gn_step`]: an `n_ob × n_ob` Cholesky in
    /// the representer form). The equality multipliers follow from the `du`
    /// rows of the KKT system, `K λ = 2 Mᵀ AᵀW (e + A M du)`.
    #[allow(clippy::too_many_arguments)]
    fn equality_qp(
        &mut self,
        lu: &BandedLu,
        op: &ObsOp,
        f: &[f64],
        e: &[f64],
        r: &[f64],
        alpha: f64,
        c: Vec<f64>,
    ) -> Result<QpStep> {
        let Unconstrained { dv, df0: df, g1, l } = self.unconstrained(lu, op, f, e, r, alpha)?;
        let dec_opt = (-dot(&g1, &df)).max(0.0);
        let du = self.du_from(lu, r, &df)?;
        let lambda_max = self.lambda_max(&dv, op, e, &du)?;
        Ok(QpStep {
            du,
            df,
            lambda_max,
            c,
            active: false,
            exact: true,
            bound_violation: 0.0,
            dec_opt: Some(dec_opt),
            derivs: Some((dv, l)),
        })
    }

    /// The QP's solution without bounds, by block elimination: the
    /// restored residual `e' = e + A M K⁻¹ Q`, the derivatives at `q`, the
    /// Gauss–Newton load step there and the reduced gradient at `e'`.
    fn unconstrained(
        &self,
        lu: &BandedLu,
        op: &ObsOp,
        f: &[f64],
        e: &[f64],
        r: &[f64],
        alpha: f64,
    ) -> Result<Unconstrained> {
        let core = &self.core;
        let (nd, d) = (E::NODE_DOFS, E::DIM);
        let mut w0 = r.to_vec();
        lu.solve_in_place(&mut w0)?;
        let dq0 = core.robot.expand_step(&w0)?;
        let e1: Vec<f64> = (0..op.n())
            .map(|i| e[i] + op.apply_row(i, &dq0, nd, d))
            .collect();
        let dv = core.derivs(lu, op)?;
        let (df0, l) = core.gn_step(&dv, op, &e1, f, alpha)?;
        let g1 = core.gradient(&dv, op, &e1, f, alpha)?;
        Ok(Unconstrained { dv, df0, g1, l })
    }

    /// `du` from the linearized equilibrium, `K du = Q + Mᵀ G dF`.
    fn du_from(&self, lu: &BandedLu, r: &[f64], df: &[f64]) -> Result<Vec<f64>> {
        let mut rhs = r.to_vec();
        for &(i, j, v) in &self.g_free {
            rhs[i] += v * df[j];
        }
        lu.solve_in_place(&mut rhs)?;
        Ok(rhs)
    }

    /// The bounds as rows `a · dF ≤ h` over the load step at `(q, F)`.
    fn inequalities(&self, q: &[f64], f: &[f64]) -> Result<Vec<Ineq>> {
        let mut ineq = Vec::new();
        for (coeffs, lo, hi) in self.bound_rows(q)? {
            let val: f64 = coeffs.iter().map(|(k, v)| v * f[*k]).sum();
            if let Some(lo) = lo {
                ineq.push(Ineq {
                    a: coeffs.iter().map(|(k, v)| (*k, -v)).collect(),
                    h: val - lo,
                });
            }
            if let Some(hi) = hi {
                ineq.push(Ineq {
                    a: coeffs.clone(),
                    h: hi - val,
                });
            }
        }
        Ok(ineq)
    }

    /// The QP with bounds. The bounds act on `F` only, so on a known active
    /// set the QP is equality-constrained and solved exactly through the
    /// reduced Gauss–Newton system ([`Reduced`]): the unconstrained step
    /// `dF₀` corrected by the active rows' multipliers. An active set is
    /// accepted only with its optimality certificate (every inactive bound
    /// holds, every active multiplier has the right sign; the QP is convex,
    /// so these KKT conditions are sufficient). Tried in turn: the active
    /// set of the last QP, none (`dF₀` itself), and the one clarabel's
    /// interior-point solution identifies; if that too fails the
    /// certificate, clarabel's step is taken as it is.
    #[allow(clippy::too_many_arguments)]
    fn bounded_qp(
        &mut self,
        lu: &BandedLu,
        op: &ObsOp,
        q: &[f64],
        f: &[f64],
        e: &[f64],
        r: &[f64],
        alpha: f64,
        c: Vec<f64>,
    ) -> std::result::Result<QpStep, QpError> {
        let ineq = self.inequalities(q, f)?;
        let core = &self.core;
        let Unconstrained { dv, df0, g1, l } = self.unconstrained(lu, op, f, e, r, alpha)?;
        let reduced = Reduced::new(core, self.gram_lu.as_ref(), &dv, op, alpha);
        let solve_from = |start: &[usize]| -> Option<(Vec<f64>, Vec<usize>)> {
            active_set_solve(reduced.as_ref()?, &ineq, f, &df0, start)
        };
        let warm = self.active_set.as_deref().and_then(solve_from);
        let (df, act, exact) = match warm {
            Some((df, act)) => (df, act, true),
            None => {
                let (df_ip, act) = self.clarabel_df(op, r, alpha, &c, &ineq)?;
                match solve_from(&act) {
                    Some((df, act)) => (df, act, true),
                    None => (df_ip, act, false),
                }
            }
        };
        // the bounds at the current F (they move with the shape in the
        // local frame): the largest violation relative to the row's scale
        let bound_violation = ineq
            .iter()
            .map(|ie| {
                let size: f64 = ie.a.iter().map(|(j, v)| (v * f[*j]).abs()).sum();
                -ie.h / (size + ie.h.abs()).max(1e-300)
            })
            .fold(0.0f64, f64::max);
        let dec_opt = exact.then(|| (-dot(&g1, &df)).max(0.0));
        self.active_set = Some(act.clone());
        let du = self.du_from(lu, r, &df)?;
        let lambda_max = self.lambda_max(&dv, op, e, &du)?;
        Ok(QpStep {
            du,
            df,
            lambda_max,
            c,
            active: !act.is_empty(),
            exact,
            bound_violation,
            dec_opt,
            derivs: Some((dv, l)),
        })
    }

    /// The largest equality multiplier, from the `du` rows of the KKT
    /// system (the bounds do not involve `u`):
    /// `λ = 2 Σ_i w_i ẽ_i K⁻¹ Mᵀ a_iᵀ`, `ẽ = e + A M du`.
    fn lambda_max(&self, dv: &Derivs, op: &ObsOp, e: &[f64], du: &[f64]) -> Result<f64> {
        let (nd, d) = (E::NODE_DOFS, E::DIM);
        let dq = self.core.robot.expand_step(du)?;
        let mut lam = vec![0.0; self.core.robot.n_q()];
        for (i, zi) in dv.z.iter().enumerate() {
            let s = 2.0 * op.wt[i] * (e[i] + op.apply_row(i, &dq, nd, d));
            lam.iter_mut().zip(zi).for_each(|(a, b)| *a += s * b);
        }
        Ok(lam.iter().fold(0.0f64, |m, v| m.max(v.abs())))
    }

    /// The full-space QP with bounds by clarabel's interior-point method:
    /// its load step and the bounds active in its solution.
    fn clarabel_df(
        &self,
        op: &ObsOp,
        r: &[f64],
        alpha: f64,
        c: &[f64],
        ineq: &[Ineq],
    ) -> std::result::Result<(Vec<f64>, Vec<usize>), QpError> {
        let core = &self.core;
        let nfree = core.robot.n_free();
        let nq = core.robot.n_q();
        let nf = core.n_f;
        let n = nfree + nf;
        let (nd, d) = (E::NODE_DOFS, E::DIM);
        // objective
        let mut pt: std::collections::BTreeMap<(usize, usize), f64> = Default::default();
        for i in 0..op.n() {
            let ma = core.robot.restrict(&op.dense_row(i, nq, nd, d))?;
            let nz: Vec<(usize, f64)> = ma
                .iter()
                .copied()
                .enumerate()
                .filter(|(_, v)| *v != 0.0)
                .collect();
            for &(a, va) in &nz {
                for &(b, vb) in &nz {
                    if a <= b {
                        *pt.entry((a, b)).or_insert(0.0) += 2.0 * op.wt[i] * va * vb;
                    }
                }
            }
        }
        for &(i, j, v) in &self.h_upper {
            *pt.entry((nfree + i, nfree + j)).or_insert(0.0) += 2.0 * alpha * v;
        }
        let pmax = pt.values().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
        // scaling: objective by 1/pmax, unknowns by γ
        let cmax = c.iter().fold(0.0f64, |m, v| m.max(v.abs())) / pmax;
        let bmax = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let gamma = cmax.max(bmax).max(1e-300);
        let (mut ri, mut ci, mut vi) = (Vec::new(), Vec::new(), Vec::new());
        for ((a, b), v) in &pt {
            ri.push(*a);
            ci.push(*b);
            vi.push(v / pmax);
        }
        let p_mat = CscMatrix::new_from_triplets(n, n, ri, ci, vi);
        let c_s: Vec<f64> = c.iter().map(|v| v / (pmax * gamma)).collect();
        let (mut ri, mut ci, mut vi) = (Vec::new(), Vec::new(), Vec::new());
        let kmat = &core.kmat;
        for i in 0..nfree {
            let lo = i.saturating_sub(2 * nd - 1);
            let hi = (i + 2 * nd).min(nfree);
            for j in lo..hi {
                let v = kmat.get(i, j);
                if v != 0.0 {
                    ri.push(i);
                    ci.push(j);
                    vi.push(-v);
                }
            }
        }
        for &(i, j, v) in &self.g_free {
            ri.push(i);
            ci.push(nfree + j);
            vi.push(v);
        }
        let m_eq = nfree;
        for (row, ie) in ineq.iter().enumerate() {
            for &(k, v) in &ie.a {
                ri.push(m_eq + row);
                ci.push(nfree + k);
                vi.push(v);
            }
        }
        let m = m_eq + ineq.len();
        let a_mat = CscMatrix::new_from_triplets(m, n, ri, ci, vi);
        let mut b: Vec<f64> = r.iter().map(|v| -v / gamma).collect();
        b.extend(ineq.iter().map(|ie| ie.h / gamma));
        let mut cones: Vec<SupportedConeT<f64>> = vec![ZeroConeT(m_eq)];
        if !ineq.is_empty() {
            cones.push(NonnegativeConeT(ineq.len()));
        }
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .tol_gap_abs(1e-10)
            .tol_gap_rel(1e-10)
            .tol_feas(1e-10)
            .max_iter(200)
            .build()
            .map_err(|e| Error::invalid("clarabel settings", format!("{e:?}"), "internal"))?;
        let mut solver = DefaultSolver::new(&p_mat, &c_s, &a_mat, &b, &cones, settings)
            .map_err(|e| Error::invalid("clarabel problem", format!("{e:?}"), "internal"))?;
        solver.solve();
        let sol = &solver.solution;
        if !matches!(
            sol.status,
            SolverStatus::Solved | SolverStatus::AlmostSolved
        ) {
            return Err(QpError::Clarabel(sol.status));
        }
        let df: Vec<f64> = sol.x[nfree..].iter().map(|v| v * gamma).collect();
        let act: Vec<usize> = sol.s[m_eq..]
            .iter()
            .zip(&sol.z[m_eq..])
            .enumerate()
            .filter(|(_, (s, z))| **s <= 1e-6 || **z > 1e-6 * s.max(1e-300))
            .map(|(k, _)| k)
            .collect();
        Ok((df, act))
    }

    #[allow(clippy::too_many_lines)]
    fn solve_one(&mut self, op: &ObsOp, f0: Vec<f64>, q0: Vec<f64>, alpha: f64) -> Result<Solved> {
        let settings = self.core.settings.clone();
        let (nd, d) = (E::NODE_DOFS, E::DIM);
        let len = self.core.robot.length();
        let mut f = f0;
        let mut q = q0;
        let n_ob = op.n() as f64;
        let mut iterations = 0;
        let mut mu = 0.0f64;
        // set where the loop ends
        let status;
        let mut prev_dec = f64::INFINITY;
        // the state at (q, F): dead force, residual Q, objective parts; an
        // accepted line-search trial hands its own on to the next iteration
        let mut dead = self.core.dead_with(&f)?;
        let mut r = self.core.residual(&q, &f)?;
        let (mut wr, mut pen, mut e) = self.core.objective(op, &q, &f, alpha)?;
        // derivatives and covariance factor of the last QP, taken at q
        let mut at_q: Option<(Derivs, Vec<f64>)> = None;
        loop {
            let obj = wr + pen;
            let load = norm2(&self.core.robot.restrict(&dead)?).max(1e-12);
            let rn = norm2(&r);
            if iterations >= settings.max_iterations {
                status = EstimateStatus::IterationLimit { iterations };
                break;
            }
            let QpStep {
                mut du,
                mut df,
                lambda_max: lmax,
                c,
                active,
                exact,
                bound_violation,
                dec_opt,
                derivs,
            } = match self.qp(op, &q, &f, &e, &r, alpha) {
                Ok(s) => s,
                Err(err) => {
                    status = err.status()?;
                    break;
                }
            };
            at_q = derivs;
            iterations += 1;
            let mut dm = du.clone();
            dm.extend_from_slice(&df);
            // model decrease of the objective
            let dec = (-dot(&c, &dm)).max(0.0);
            // trust region on the predicted marker motion
            let mut dq = self.core.robot.expand_step(&du)?;
            let moved = (0..op.n())
                .map(|i| op.apply_row(i, &dq, nd, d).abs())
                .fold(0.0f64, f64::max);
            if moved > settings.max_observation_jump_m && moved.is_finite() {
                let s = settings.max_observation_jump_m / moved;
                du.iter_mut()
                    .chain(df.iter_mut())
                    .chain(dm.iter_mut())
                    .chain(dq.iter_mut())
                    .for_each(|v| *v *= s);
            }
            let lin = dot(&c, &dm);
            let scale = obj.max(n_ob);
            // feasible: |Q| relative to the applied loads, or at the round-off
            // floor ε |K|max |q|∞ √n (which grows with the element count)
            let qmax = q.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let floor = 0.1
                * f64::EPSILON
                * self.core.kmat.max_abs()
                * qmax
                * (self.core.robot.n_free() as f64).sqrt();
            let feasible = rn <= (1e-9 * load).max(floor) && bound_violation <= 1e-9;
            // with a bound active the step is clarabel's, accurate to its
            // tolerances only: a predicted decrease of 1e-9 then ends it
            let tol = if active && !exact {
                settings.tolerance.max(1e-9)
            } else {
                settings.tolerance
            };
            // convergence is judged on the decrease along the manifold
            let dec_c = dec_opt.unwrap_or(dec);
            if feasible {
                let criterion = if dec_c <= tol * scale {
                    Some(EstimateCriterion::PredictedDecrease)
                } else if dec_c <= 1e-13 * scale && dec_c > 0.9 * prev_dec {
                    Some(EstimateCriterion::RoundOffFloor)
                } else {
                    None
                };
                if let Some(c) = criterion {
                    status = EstimateStatus::Converged(c);
                    break;
                }
            }
            prev_dec = if feasible { dec_c } else { f64::INFINITY };
            mu = mu.max(1.5 * lmax + 1e-12);
            let r1: f64 = r.iter().map(|v| v.abs()).sum();
            let phi = obj + mu * r1;
            let slope = lin - mu * r1;
            let mut t = 1.0;
            let mut accepted = false;
            // second-order correction (against the Maratos effect): the
            // trial shape is pulled back onto the equilibrium manifold by
            // chord steps u += K⁻¹ Q(q_t, F_t) with the factorization at q
            for _ in 0..30 {
                let mut qt: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a + t * b).collect();
                let ft: Vec<f64> = f.iter().zip(&df).map(|(a, b)| a + t * b).collect();
                let dead_t = self.core.dead_with(&ft)?;
                let mut rt = self.core.robot.residual(&qt, &dead_t, &self.core.known)?;
                if let Some(lu) = &self.last_lu {
                    // up to four chord steps while the residual shrinks
                    let mut rn_t = norm2(&rt);
                    for _ in 0..4 {
                        let mut du_c = rt.clone();
                        lu.solve_in_place(&mut du_c)?;
                        if !du_c.iter().all(|v| v.is_finite()) {
                            break;
                        }
                        let corr = self.core.robot.expand_step(&du_c)?;
                        let qc: Vec<f64> = qt.iter().zip(&corr).map(|(a, b)| a + b).collect();
                        let rc = self.core.robot.residual(&qc, &dead_t, &self.core.known)?;
                        let rn_c = norm2(&rc);
                        if rn_c.is_nan() || rn_c >= rn_t {
                            break;
                        }
                        qt = qc;
                        rt = rc;
                        rn_t = rn_c;
                        if rn_t <= 1e-10 * load {
                            break;
                        }
                    }
                }
                let (wr_t, pen_t, e_t) = self.core.objective(op, &qt, &ft, alpha)?;
                let phi_t = wr_t + pen_t + mu * rt.iter().map(|v| v.abs()).sum::<f64>();
                let small = dec <= 1e-8 * scale && rn <= 1e-6 * load;
                // near the round-off floor μ|Q|₁ is noise: a trial that stays
                // feasible to 10× the tolerance and decreases J is accepted
                let feasible_t = norm2(&rt) <= 10.0 * (1e-9 * load).max(floor);
                let descends = wr_t + pen_t <= obj + 1e-4 * t * lin.min(0.0);
                if phi_t <= phi + 1e-4 * t * slope.min(0.0) || small || (feasible_t && descends) {
                    q = qt;
                    f = ft;
                    dead = dead_t;
                    r = rt;
                    (wr, pen, e) = (wr_t, pen_t, e_t);
                    at_q = None;
                    accepted = true;
                    break;
                }
                t *= 0.5;
            }
            if !accepted {
                status = if dec <= 1e-10 * scale && rn <= 1e-6 * load {
                    EstimateStatus::Converged(EstimateCriterion::NegligibleDecrease)
                } else {
                    EstimateStatus::LineSearchFailed
                };
                break;
            }
        }
        // exact equilibrium at the final F, derivatives and covariance
        // there: at a feasible point one chord step with the last QP's
        // factorization (taken at q) does it, and that QP's derivatives are
        // exact; otherwise the equilibrium is re-solved and re-factored
        let mut finish = None;
        if let (Some((dv, l)), Some(lu)) = (at_q.take(), &self.last_lu) {
            let mut w = r.clone();
            lu.solve_in_place(&mut w)?;
            let step = w.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if step <= 1e-10 * len {
                let dq = self.core.robot.expand_step(&w)?;
                q.iter_mut().zip(&dq).for_each(|(a, b)| *a += b);
                let residual_n = norm2(&self.core.robot.residual(&q, &dead, &self.core.known)?);
                finish = Some((q.clone(), dv, l, residual_n));
            }
        }
        let (q, dv, l, residual_n) = match finish {
            Some(x) => x,
            None => {
                let eq = self.core.equilibrium(&f, &q)?;
                let dv = self.core.derivs(&eq.lu, op)?;
                let e = op.residual(&eq.q, nd, d);
                let (_, l) = self.core.gn_step(&dv, op, &e, &f, alpha)?;
                (eq.q, dv, l, eq.residual_n)
            }
        };
        let (wr, pen, e) = self.core.objective(op, &q, &f, alpha)?;
        let g = self.core.gradient(&dv, op, &e, &f, alpha)?;
        Ok(Solved {
            f,
            q,
            derivs: dv,
            cov_factor: l,
            e,
            report: EstimateReport {
                backend: Backend::Sqp,
                status,
                iterations,
                sub_steps: 1,
                objective: wr + pen,
                weighted_residual: wr,
                n_observations: op.n(),
                gradient_norm: norm2(&g),
                equilibrium_residual_n: residual_n,
                alpha,
                wall_time_s: 0.0,
            },
        })
    }
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
    derivs: Option<(Derivs, Vec<f64>)>,
}

/// The equality-constrained QP's parts (see [`SqpEstimator::unconstrained`]).
struct Unconstrained {
    /// Adjoint fields and marker Jacobian at `q`.
    dv: Derivs,
    /// The Gauss–Newton load step at the restored residual.
    df0: Vec<f64>,
    /// The reduced gradient (29) at the restored residual.
    g1: Vec<f64>,
    /// The covariance factor at `q`.
    l: Vec<f64>,
}

/// One bound row `a · dF ≤ h` (`a` sparse over the load parameters).
struct Ineq {
    a: Vec<(usize, f64)>,
    h: f64,
}

/// The QP's load step by active-set iterations from the rows `start`: each
/// solves the equality-constrained QP on the current set, drops the row
/// with the most negative multiplier or else adds the most violated
/// inactive bound, and stops when neither exists: then every inactive
/// bound holds (to 1e-9 of its row's scale) and no active multiplier is
/// negative (beyond 1e-9 of the largest), the KKT conditions of the convex
/// QP, so the step is its solution. `None` if that takes more than
/// `2 n_rows + 8` solves or a solve fails (dependent active rows).
fn active_set_solve(
    red: &Reduced<'_>,
    ineq: &[Ineq],
    f: &[f64],
    df0: &[f64],
    start: &[usize],
) -> Option<(Vec<f64>, Vec<usize>)> {
    let mut act: Vec<usize> = start.iter().copied().filter(|&k| k < ineq.len()).collect();
    act.sort_unstable();
    act.dedup();
    for _ in 0..2 * ineq.len() + 8 {
        let (df, nu) = if act.is_empty() {
            (df0.to_vec(), Vec::new())
        } else {
            red.solve_on(&act, ineq, df0)?
        };
        if !df.iter().chain(&nu).all(|v| v.is_finite()) {
            return None;
        }
        let numax = nu.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let (i_min, nu_min) =
            nu.iter()
                .copied()
                .enumerate()
                .fold(
                    (0, f64::INFINITY),
                    |m, (i, v)| if v < m.1 { (i, v) } else { m },
                );
        if nu_min < -1e-9 * numax {
            act.remove(i_min);
            continue;
        }
        let (k_max, viol_max) = ineq
            .iter()
            .enumerate()
            .filter(|(k, _)| act.binary_search(k).is_err())
            .map(|(k, ie)| {
                let lhs: f64 = ie.a.iter().map(|(j, v)| v * df[*j]).sum();
                let size: f64 =
                    ie.a.iter()
                        .map(|(j, v)| v.abs() * (f[*j].abs() + df[*j].abs()))
                        .sum();
                (k, (lhs - ie.h) / (size + ie.h.abs()).max(1e-300))
            })
            .fold(
                (0, f64::NEG_INFINITY),
                |m, (k, v)| if v > m.1 { (k, v) } else { m },
            );
        if viol_max > 1e-9 {
            if let Err(pos) = act.binary_search(&k_max) {
                act.insert(pos, k_max);
            }
            continue;
        }
        return Some((df, act));
    }
    None
}

/// The reduced Gauss–Newton Hessian `N = Jᵀ W J + α H` at one
/// linearization, applied as `N⁻¹`: for the distributed load
/// (`J = Z B`, `H = B`) by Woodbury,
/// `N⁻¹ = α⁻¹ (B⁻¹ − Zᵀ S⁻¹ Z)`, `S = α W⁻¹ + Z B Zᵀ` (`n_ob × n_ob`);
/// for a concentrated load `N` itself (`DIM × DIM`).
struct Reduced<'a> {
    z: &'a [Vec<f64>],
    chol: nalgebra::Cholesky<f64, nalgebra::Dyn>,
    gram_lu: Option<&'a BandedLu>,
    alpha: f64,
}

impl<'a> Reduced<'a> {
    fn new<E: Element>(
        core: &Core<E>,
        gram_lu: Option<&'a BandedLu>,
        dv: &'a Derivs,
        op: &ObsOp,
        alpha: f64,
    ) -> Option<Self> {
        let m = op.n();
        let mat = match core.settings.load_model {
            LoadModel::Distributed => {
                gram_lu?;
                nalgebra::DMatrix::from_fn(m, m, |i, j| {
                    0.5 * (dot(&dv.z[i], &dv.jm[j]) + dot(&dv.z[j], &dv.jm[i]))
                        + if i == j { alpha / op.wt[i] } else { 0.0 }
                })
            }
            LoadModel::Concentrated { .. } => {
                let nf = core.n_f;
                nalgebra::DMatrix::from_fn(nf, nf, |a, b| {
                    (0..m)
                        .map(|i| op.wt[i] * dv.jm[i][a] * dv.jm[i][b])
                        .sum::<f64>()
                        + if a == b { alpha } else { 0.0 }
                })
            }
        };
        Some(Reduced {
            z: &dv.z,
            chol: mat.cholesky()?,
            gram_lu,
            alpha,
        })
    }

    /// `N⁻¹ a` for a sparse `a` over the load parameters (`n_f` long).
    fn n_inv(&self, a: &[(usize, f64)], nf: usize) -> Option<Vec<f64>> {
        let mut x = vec![0.0; nf];
        for &(j, v) in a {
            x[j] += v;
        }
        match self.gram_lu {
            Some(lu) => {
                let t = nalgebra::DVector::from_fn(self.z.len(), |i, _| {
                    a.iter().map(|(j, v)| v * self.z[i][*j]).sum::<f64>()
                });
                let s = self.chol.solve(&t);
                lu.solve_in_place(&mut x).ok()?;
                for (zi, si) in self.z.iter().zip(s.iter()) {
                    x.iter_mut().zip(zi).for_each(|(a, b)| *a -= si * b);
                }
                x.iter_mut().for_each(|v| *v /= self.alpha);
                Some(x)
            }
            None => {
                let v = self.chol.solve(&nalgebra::DVector::from_vec(x));
                Some(v.iter().copied().collect())
            }
        }
    }

    /// The step with the rows `act` held at equality, `a_k · dF = h_k`:
    /// `dF = dF₀ − Σ_k ν_k N⁻¹ a_k`, `(C N⁻¹ Cᵀ) ν = C dF₀ − h`; also `ν`
    /// (the rows' multipliers, up to a positive factor).
    fn solve_on(&self, act: &[usize], ineq: &[Ineq], df0: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let nf = df0.len();
        let y: Vec<Vec<f64>> = act
            .iter()
            .map(|&k| self.n_inv(&ineq.get(k)?.a, nf))
            .collect::<Option<_>>()?;
        let rowdot =
            |k: usize, v: &[f64]| -> f64 { ineq[k].a.iter().map(|(j, c)| c * v[*j]).sum() };
        let na = act.len();
        let mmat = nalgebra::DMatrix::from_fn(na, na, |i, j| {
            0.5 * (rowdot(act[i], &y[j]) + rowdot(act[j], &y[i]))
        });
        let rhs = nalgebra::DVector::from_fn(na, |i, _| rowdot(act[i], df0) - ineq[act[i]].h);
        let nu = mmat.cholesky()?.solve(&rhs);
        let mut df = df0.to_vec();
        for (yk, nk) in y.iter().zip(nu.iter()) {
            df.iter_mut().zip(yk).for_each(|(a, b)| *a -= nk * b);
        }
        Some((df, nu.iter().copied().collect()))
    }
}

crate::estimate::impl_estimator!(SqpEstimator, Backend::Sqp);

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::element::{NodeKinematics, PlanarCable};
    use crate::loads::LineLoad;
    use crate::scene::Scene;
    use crate::statics::StaticSolver;

    /// The bounded QP's exact solution by active-set iterations: from the
    /// empty set and from the set clarabel's interior-point solution
    /// identifies it reaches the same step (the QP is strictly convex in
    /// `dF`), with bounds active, every bound held, and a reduced objective
    /// `(e' + J dF)ᵀ W (e' + J dF) + α (F + dF)ᵀ H (F + dF)` not above that of
    /// clarabel's step (an independent solver of the same QP). A wrong
    /// active set or a wrong multiplier sign gives a higher objective or a
    /// violated bound.
    #[test]
    fn active_set_step_solves_the_bounded_qp() {
        let mut scene = Scene::two_section();
        for s in &mut scene.robot.sections {
            s.elements = 10;
        }
        let robot = scene.robot().unwrap();
        let known = scene.loads().unwrap();
        let mut truth = known.clone();
        truth.line_loads.push(LineLoad::Gaussian {
            amplitude_n_per_m: vec![0.0, -20.0],
            center_m: 0.16,
            width_m: 0.01,
        });
        let eq = StaticSolver::default().solve(&robot, &truth, None).unwrap();
        let obs = Observation::at_nodes(&robot, &eq.q, &[4, 8, 12, 16, 20]).with_noise(1e-5, 3);
        let bounds = (0..=24)
            .map(|i| super::super::LoadBound {
                s_m: 0.01 * f64::from(i),
                frame: BoundFrame::World,
                direction: vec![0.0, 1.0],
                min_n_per_m: None,
                max_n_per_m: Some(0.0),
            })
            .collect();
        let alpha = 10.0;
        let settings = EstimatorSettings {
            alpha: Some(alpha),
            bounds,
            ..EstimatorSettings::default()
        };
        let mut est = SqpEstimator::new(robot, known, settings).unwrap();
        let op = est.core.obs_op(&obs).unwrap();
        let (f, q) = est.core.start().unwrap();
        let (_, _, e) = est.core.objective(&op, &q, &f, alpha).unwrap();
        let r = est.core.residual(&q, &f).unwrap();
        let lu = est.core.factor(&q).unwrap();
        let c = est.linear_term(&op, &f, &e, alpha).unwrap();
        let ineq = est.inequalities(&q, &f).unwrap();
        let un = est.unconstrained(&lu, &op, &f, &e, &r, alpha).unwrap();
        let (nd, d) = (PlanarCable::NODE_DOFS, PlanarCable::DIM);
        let mut w0 = r.clone();
        lu.solve_in_place(&mut w0).unwrap();
        let dq0 = est.core.robot.expand_step(&w0).unwrap();
        let e1: Vec<f64> = (0..op.n())
            .map(|i| e[i] + op.apply_row(i, &dq0, nd, d))
            .collect();
        let reduced_objective = |df: &[f64]| {
            let wr: f64 = (0..op.n())
                .map(|i| op.wt[i] * (e1[i] + dot(&un.dv.jm[i], df)).powi(2))
                .sum();
            let ft: Vec<f64> = f.iter().zip(df).map(|(a, b)| a + b).collect();
            wr + alpha * est.core.penalty(&ft).unwrap()
        };
        let red = Reduced::new(&est.core, est.gram_lu.as_ref(), &un.dv, &op, alpha).unwrap();
        let (df_ip, act_ip) = est.clarabel_df(&op, &r, alpha, &c, &ineq).unwrap();
        let (df_a, act_a) = active_set_solve(&red, &ineq, &f, &un.df0, &[]).unwrap();
        let (df_b, act_b) = active_set_solve(&red, &ineq, &f, &un.df0, &act_ip).unwrap();
        assert!(!act_a.is_empty(), "the test needs active bounds");
        assert_eq!(act_a, act_b);
        let nrm = norm2(&df_a);
        let diff: Vec<f64> = df_a.iter().zip(&df_b).map(|(a, b)| a - b).collect();
        assert!(norm2(&diff) <= 1e-9 * nrm, "{}", norm2(&diff) / nrm);
        // every bound holds: w_y(s_j; F + dF) <= 0
        let worst = ineq
            .iter()
            .map(|ie| ie.a.iter().map(|(j, v)| v * df_a[*j]).sum::<f64>() - ie.h)
            .fold(f64::MIN, f64::max);
        assert!(worst <= 1e-9, "bound violated by {worst}");
        let (phi_a, phi_ip, phi_0) = (
            reduced_objective(&df_a),
            reduced_objective(&df_ip),
            reduced_objective(&un.df0),
        );
        eprintln!(
            "active {act_a:?} (clarabel {act_ip:?}); objective exact {phi_a:.12e}, clarabel {phi_ip:.12e}, unbounded {phi_0:.12e}"
        );
        assert!(phi_a <= phi_ip * (1.0 + 1e-9), "{phi_a} > {phi_ip}");
        assert!(phi_a > phi_0, "the bounds must cost something");
    }
}
