//! The constrained estimator (25) by sequential quadratic programming.
//!
//! Unknowns: the free coordinates `u` (so `q = q(u)`, linear: the base
//! stretch and nodes 1…N) and the load parameters `F`. The objective is
//! quadratic in `(u, F)`, only the equilibrium `Q(F, q, P) = 0` (17) is
//! nonlinear. Each iteration solves, with clarabel,
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
//! as the reduced method's. The QP data are rescaled so that clarabel's
//! absolute tolerances act as relative ones (the QP is homogeneous in its
//! right-hand sides), and the returned `du` is recomputed from `dF` with the
//! banded factorization of `K`, so the linearized equilibrium holds to
//! round-off. Globalization: backtracking on the ℓ1 merit function
//! `φ = J + μ |Q|₁`, `μ` above the largest equality multiplier.
//! When no bound is active in a QP's solution, the step is polished: `dF` is
//! recomputed exactly on that active set (the equality-constrained QP, solved
//! through the banded factorization of `K` and an `n_ob × n_ob` Cholesky);
//! clarabel alone resolves the weakly penalized directions (the slopes `w'`)
//! only to about 1e-5 of `|F|`.
//! After convergence the shape is re-solved at the final `F` (a few Newton
//! steps) so the estimate is an exact equilibrium.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus,
    SupportedConeT, ZeroConeT,
};

use crate::assembly::Robot;
use crate::element::{hermite, Element};
use crate::error::{Error, Result};
use crate::loads::Loads;

use super::{
    dot, norm2, run_step, Backend, BoundFrame, Core, Estimate, EstimateReport, Estimator,
    EstimatorSettings, LoadModel, ObsOp, Observation, Solved,
};

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
/// assert!(e.report.converged);
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
    last_lu: Option<crate::banded::BandedLu>,
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
        Ok(SqpEstimator {
            core,
            g_free,
            h_upper,
            last_lu: None,
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

    /// One QP: returns `(du, dF, λ_eq)`.
    #[allow(clippy::too_many_arguments)]
    fn qp(
        &mut self,
        op: &ObsOp,
        q: &[f64],
        f: &[f64],
        e: &[f64],
        r: &[f64],
        alpha: f64,
    ) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>, bool)> {
        let bounds = self.bound_rows(q)?;
        let core = &mut self.core;
        let nfree = core.robot.n_free();
        let nq = core.robot.n_q();
        let nf = core.n_f;
        let n = nfree + nf;
        let (nd, d) = (E::NODE_DOFS, E::DIM);
        // objective
        let mut pt: std::collections::BTreeMap<(usize, usize), f64> = Default::default();
        let mut c = vec![0.0; n];
        for i in 0..op.n() {
            let ma = core.robot.restrict(&op.dense_row(i, nq, nd, d))?;
            let nz: Vec<(usize, f64)> = ma
                .iter()
                .copied()
                .enumerate()
                .filter(|(_, v)| *v != 0.0)
                .collect();
            for &(a, va) in &nz {
                c[a] += 2.0 * op.wt[i] * e[i] * va;
                for &(b, vb) in &nz {
                    if a <= b {
                        *pt.entry((a, b)).or_insert(0.0) += 2.0 * op.wt[i] * va * vb;
                    }
                }
            }
        }
        let hf = core.penalty_grad(f)?;
        for (k, v) in hf.iter().enumerate() {
            c[nfree + k] = 2.0 * alpha * v;
        }
        for &(i, j, v) in &self.h_upper {
            *pt.entry((nfree + i, nfree + j)).or_insert(0.0) += 2.0 * alpha * v;
        }
        let pmax = pt.values().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
        // constraints
        core.robot.tangent_into(q, &core.known, &mut core.kmat)?;
        let kmat = core.kmat.clone();
        let lu = kmat.clone().factor_scaled(0.0, "tangent stiffness")?;
        let mut b_eq: Vec<f64> = r.iter().map(|v| -v).collect();
        let mut ineq: Vec<(Vec<(usize, f64)>, f64)> = Vec::new();
        for (coeffs, lo, hi) in &bounds {
            let val: f64 = coeffs.iter().map(|(k, v)| v * f[*k]).sum();
            if let Some(lo) = lo {
                ineq.push((
                    coeffs.iter().map(|(k, v)| (nfree + k, -v)).collect(),
                    val - lo,
                ));
            }
            if let Some(hi) = hi {
                ineq.push((
                    coeffs.iter().map(|(k, v)| (nfree + k, *v)).collect(),
                    hi - val,
                ));
            }
        }
        // scaling: objective by 1/pmax, unknowns by γ
        let cmax = c.iter().fold(0.0f64, |m, v| m.max(v.abs())) / pmax;
        let bmax = b_eq.iter().fold(0.0f64, |m, v| m.max(v.abs()));
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
        for (row, (coeffs, _)) in ineq.iter().enumerate() {
            for &(k, v) in coeffs {
                ri.push(m_eq + row);
                ci.push(k);
                vi.push(v);
            }
        }
        let m = m_eq + ineq.len();
        let a_mat = CscMatrix::new_from_triplets(m, n, ri, ci, vi);
        b_eq.iter_mut().for_each(|v| *v /= gamma);
        let mut b = b_eq;
        b.extend(ineq.iter().map(|(_, h)| h / gamma));
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
            return Err(Error::NonFinite {
                context: format!("SQP subproblem: clarabel status {:?}", sol.status),
            });
        }
        let mut du: Vec<f64> = sol.x[..nfree].iter().map(|v| v * gamma).collect();
        let mut df: Vec<f64> = sol.x[nfree..].iter().map(|v| v * gamma).collect();
        // polish on the active set (as OSQP does): with no bound active the
        // QP is the equality-constrained one, whose exact solution is the
        // Gauss–Newton step from the feasibility-restored residual
        // e' = e + A M K⁻¹ Q. The interior-point solution is accurate to its
        // tolerances in the well-determined directions only: the penalty's
        // curvature along the slopes w' is ~1e-8 of the data term's.
        let active = sol.s[m_eq..]
            .iter()
            .zip(&sol.z[m_eq..])
            .any(|(s, z)| *s <= 1e-6 || *z > 1e-6 * s.max(1e-300));
        if !active {
            let mut w0 = r.to_vec();
            lu.solve_in_place(&mut w0)?;
            let dq0 = core.robot.expand_step(&w0)?;
            let e1: Vec<f64> = (0..op.n())
                .map(|i| e[i] + op.apply_row(i, &dq0, nd, d))
                .collect();
            let dv = core.derivs(&lu, op)?;
            let (step, _) = core.gn_step(&dv, op, &e1, f, alpha)?;
            if step.iter().all(|v| v.is_finite()) {
                df = step;
            }
        }
        let lambda: Vec<f64> = sol.z[..m_eq].iter().map(|v| v * gamma * pmax).collect();
        // polish: du from the linearized equilibrium, K du = Q + Mᵀ G dF
        let mut rhs = r.to_vec();
        for &(i, j, v) in &self.g_free {
            rhs[i] += v * df[j];
        }
        lu.solve_in_place(&mut rhs)?;
        if rhs.iter().all(|v| v.is_finite()) {
            du = rhs;
        }
        self.last_lu = Some(lu);
        Ok((du, df, lambda, c, active))
    }

    fn solve_one(&mut self, op: &ObsOp, f0: Vec<f64>, q0: Vec<f64>, alpha: f64) -> Result<Solved> {
        let settings = self.core.settings.clone();
        let mut f = f0;
        let mut q = q0;
        let n_ob = op.n() as f64;
        let mut iterations = 0;
        let mut mu = 0.0f64;
        let mut cause = None;
        let mut converged = false;
        let mut prev_dec = f64::INFINITY;
        loop {
            let (wr, pen, e) = self.core.objective(op, &q, &f, alpha)?;
            let obj = wr + pen;
            let r = self.core.residual(&q, &f)?;
            let dead = self.core.dead_with(&f)?;
            let load = norm2(&self.core.robot.restrict(&dead)?).max(1e-12);
            let rn = norm2(&r);
            if iterations >= settings.max_iterations {
                cause = Some("iteration limit".to_string());
                break;
            }
            let (mut du, mut df, lambda, c, active) = match self.qp(op, &q, &f, &e, &r, alpha) {
                Ok(s) => s,
                Err(err) => {
                    cause = Some(err.to_string());
                    break;
                }
            };
            iterations += 1;
            let mut d = du.clone();
            d.extend_from_slice(&df);
            // model decrease of the objective
            let dec = (-dot(&c, &d)).max(0.0);
            // trust region on the predicted marker motion
            let dq_pred = self.core.robot.expand_step(&du)?;
            let moved = (0..op.n())
                .map(|i| op.apply_row(i, &dq_pred, E::NODE_DOFS, E::DIM).abs())
                .fold(0.0f64, f64::max);
            if moved > settings.max_observation_jump_m && moved.is_finite() {
                let s = settings.max_observation_jump_m / moved;
                du.iter_mut()
                    .chain(df.iter_mut())
                    .chain(d.iter_mut())
                    .for_each(|v| *v *= s);
            }
            let lin = dot(&c, &d);
            let scale = obj.max(n_ob);
            // feasible: |Q| relative to the applied loads, or at the round-off
            // floor ε |K|max |q|∞ √n (which grows with the element count)
            let qmax = q.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            let floor = 0.1
                * f64::EPSILON
                * self.core.kmat.max_abs()
                * qmax
                * (self.core.robot.n_free() as f64).sqrt();
            let feasible = rn <= (1e-9 * load).max(floor);
            // with a bound active the step is clarabel's, accurate to its
            // tolerances only: a predicted decrease of 1e-9 then ends it
            let tol = if active {
                settings.tolerance.max(1e-9)
            } else {
                settings.tolerance
            };
            if feasible && (dec <= tol * scale || (dec <= 1e-13 * scale && dec > 0.9 * prev_dec)) {
                converged = true;
                break;
            }
            prev_dec = if feasible { dec } else { f64::INFINITY };
            let lmax = lambda.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            mu = mu.max(1.5 * lmax + 1e-12);
            let r1: f64 = r.iter().map(|v| v.abs()).sum();
            let phi = obj + mu * r1;
            let slope = lin - mu * r1;
            let dq = self.core.robot.expand_step(&du)?;
            let mut t = 1.0;
            let mut accepted = false;
            // second-order correction (against the Maratos effect): the
            // trial shape is pulled back onto the equilibrium manifold by
            // one step u += K⁻¹ Q(q_t, F_t) with the factorization at q
            for _ in 0..30 {
                let mut qt: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a + t * b).collect();
                let ft: Vec<f64> = f.iter().zip(&df).map(|(a, b)| a + t * b).collect();
                let mut rt = self.core.residual(&qt, &ft)?;
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
                        let rc = self.core.residual(&qc, &ft)?;
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
                let (wr_t, pen_t, _) = self.core.objective(op, &qt, &ft, alpha)?;
                let phi_t = wr_t + pen_t + mu * rt.iter().map(|v| v.abs()).sum::<f64>();
                let small = dec <= 1e-8 * scale && rn <= 1e-6 * load;
                // near the round-off floor μ|Q|₁ is noise: a trial that stays
                // feasible to 10× the tolerance and decreases J is accepted
                let feasible_t = norm2(&rt) <= 10.0 * (1e-9 * load).max(floor);
                let descends = wr_t + pen_t <= obj + 1e-4 * t * lin.min(0.0);
                if phi_t <= phi + 1e-4 * t * slope.min(0.0) || small || (feasible_t && descends) {
                    q = qt;
                    f = ft;
                    accepted = true;
                    break;
                }
                t *= 0.5;
            }
            if !accepted {
                converged = dec <= 1e-10 * scale && rn <= 1e-6 * load;
                if !converged {
                    cause = Some("merit line search failed".to_string());
                }
                break;
            }
        }
        // exact equilibrium at the final F, derivatives and covariance there
        let eq = self.core.equilibrium(&f, &q)?;
        let (wr, pen, e) = self.core.objective(op, &eq.q, &f, alpha)?;
        let dv = self.core.derivs(&eq.lu, op)?;
        let g = self.core.gradient(&dv, op, &e, &f, alpha)?;
        let (_, l) = self.core.gn_step(&dv, op, &e, &f, alpha)?;
        Ok(Solved {
            f,
            q: eq.q,
            derivs: dv,
            cov_factor: l,
            e,
            report: EstimateReport {
                backend: Backend::Sqp,
                converged,
                iterations,
                sub_steps: 1,
                objective: wr + pen,
                weighted_residual: wr,
                n_observations: op.n(),
                gradient_norm: norm2(&g),
                equilibrium_residual_n: eq.residual_n,
                alpha,
                wall_time_s: 0.0,
                cause,
            },
        })
    }
}

crate::estimate::impl_estimator!(SqpEstimator, Backend::Sqp);
