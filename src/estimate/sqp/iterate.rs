//! The SQP iteration of one solve, by phase (see the [module
//! documentation](super) for the method): the QP at the point, the trust
//! region on its step, the convergence tests, the line search on the merit
//! function with its second-order correction, and the exact equilibrium
//! at the final load. [`SqpEstimator::iterate`] strings them together.

use crate::error::Result;
use crate::linsolve::{AutoFactors, Factorization};
use crate::numeric::{dot, max_abs, norm2};
use crate::observe::ObservationOperator;
use crate::statics::residual_floor;
use crate::statics::tracker::{FactoredTangent, chord_converged};

use super::super::driver::Solved;
use super::super::problem::{Derivs, GnFactor};
use super::super::{Backend, EstimateCriterion, EstimateReport, EstimateStatus, EstimationModel};
use super::{SqpEstimator, WarmQp, trust};

/// A point of the iteration: `(q, F)` (not necessarily an equilibrium)
/// with the free coordinates `u` of `q = φ(u)`, the dead force there, the
/// residual `Q` and the objective's parts. An accepted line-search trial
/// hands its own on to the next iteration.
struct Point {
    u: Vec<f64>,
    q: Vec<f64>,
    f: Vec<f64>,
    dead: Vec<f64>,
    r: Vec<f64>,
    wr: f64,
    pen: f64,
    e: Vec<f64>,
}

/// The QP's step within the trust region: `dF`, `(du, dF)` together (`dm`), the
/// predicted motion of the coordinates `dq`, whether the radius cut it,
/// and the model decrease `dec = −cᵀ d` before the cut.
struct TrialStep {
    df: Vec<f64>,
    dm: Vec<f64>,
    dq: nalgebra::DVector<f64>,
    cut: bool,
    dec: f64,
}

/// The merit function's data for the line search: `φ = J + μ |Q|₁` at the
/// point, its slope along the step, the step's model slope `lin = cᵀ d`
/// and the point's `|Q|_2` and applied-load scale.
struct Merit {
    mu: f64,
    phi: f64,
    slope: f64,
    lin: f64,
    rn: f64,
    load: f64,
    floor: f64,
    scale: f64,
    dec: f64,
}

/// The constant data of one solve.
struct Solve<'a> {
    op: &'a ObservationOperator,
    alpha: f64,
    len: f64,
    n_free: usize,
    n_ob: f64,
}

impl<M: EstimationModel> SqpEstimator<M> {
    /// The SQP solve from `(f0, q0)` at `alpha` for `op`: QPs until the
    /// convergence tests hold at a feasible point, the budget runs out, a
    /// QP or the line search fails; then the exact equilibrium at the
    /// final `F` and the solve's report.
    pub(super) fn iterate(
        &mut self,
        op: &ObservationOperator,
        f0: Vec<f64>,
        q0: Vec<f64>,
        alpha: f64,
    ) -> Result<Solved> {
        let settings = self.stream.problem.settings().clone();
        let robot = self.stream.problem.robot();
        let sv = Solve {
            op,
            alpha,
            len: robot.length_m(),
            n_free: robot.n_free(),
            n_ob: op.len() as f64,
        };
        let mut p = self.point(&sv, q0, f0)?;
        let mut iterations = 0;
        let mut mu = 0.0f64;
        let mut prev_dec = f64::INFINITY;
        // derivatives and Gauss–Newton factor of the last QP, taken at q
        let mut at_q: Option<(Derivs, GnFactor)> = None;
        // the factored tangent of the last QP (the second-order correction,
        // the final chord step)
        let mut last: Option<FactoredTangent> = None;
        // the trust radius on the predicted marker motion (m)
        let mut radius = settings.max_observation_jump_m;
        let status = loop {
            let obj = p.wr + p.pen;
            let load = norm2(self.stream.problem.restrict(&p.u, &p.dead)?.as_slice()).max(1e-12);
            let rn = norm2(&p.r);
            if iterations >= settings.max_iterations {
                break EstimateStatus::IterationLimit { iterations };
            }
            let (qp, tangent) = match self.qp(op, &p.u, &p.q, &p.f, &p.e, &p.r, alpha) {
                Ok(s) => s,
                Err(err) => break err.status()?,
            };
            at_q = qp.derivs;
            let lu = &last.insert(tangent).factors;
            iterations += 1;
            let step = self.trust_cut(op, &p.u, qp.du, qp.df, &qp.c, radius)?;
            let scale = obj.max(sv.n_ob);
            // feasible: |Q| relative to the applied loads, or at the round-off
            // floor ε |K|max |q|∞ √n (which grows with the element count)
            let floor = residual_floor(qp.tangent_max_abs, max_abs(&p.q), sv.n_free);
            let feasible = rn <= (1e-9 * load).max(floor) && qp.bound_violation <= 1e-9;
            // with a bound active the step is clarabel's, accurate to its
            // tolerances only: a predicted decrease of 1e-9 then ends it
            let tol = if qp.active && !qp.exact {
                settings.tolerance.max(1e-9)
            } else {
                settings.tolerance
            };
            // convergence is judged on the decrease along the manifold
            // (−g̃ᵀdF = 2 dFᵀ N dF at the QP's solution: the statistical test
            // is on half of it, as the Newton backend's)
            let dec_c = qp.dec_opt.unwrap_or(step.dec);
            if feasible {
                let kappa = settings.statistical_tolerance;
                if let Some(c) = converged(dec_c, tol, kappa, scale, prev_dec) {
                    break EstimateStatus::Converged(c);
                }
            }
            prev_dec = if feasible { dec_c } else { f64::INFINITY };
            mu = mu.max(1.5 * qp.lambda_max + 1e-12);
            let lin = dot(&qp.c, &step.dm);
            let r1: f64 = p.r.iter().map(|v| v.abs()).sum();
            let merit = Merit {
                mu,
                phi: obj + mu * r1,
                slope: lin - mu * r1,
                lin,
                rn,
                load,
                floor,
                scale,
                dec: step.dec,
            };
            match self.line_search(&sv, &mut p, lu, &step, &merit)? {
                Some(t) => {
                    at_q = None;
                    let start = settings.max_observation_jump_m;
                    radius = trust::next_radius(radius, t, step.cut, start, sv.len);
                }
                None => {
                    break if step.dec <= 1e-10 * scale && rn <= 1e-6 * load {
                        EstimateStatus::Converged(EstimateCriterion::NegligibleDecrease)
                    } else {
                        EstimateStatus::LineSearchFailed
                    };
                }
            }
        };
        self.answer(&sv, p, at_q, last, status, iterations)
    }

    /// The point `(q, F)`: its free coordinates, dead force, residual and
    /// objective.
    fn point(&self, sv: &Solve<'_>, q: Vec<f64>, f: Vec<f64>) -> Result<Point> {
        let problem = &self.stream.problem;
        let u = problem.robot().free_coordinates_of(&q)?.data.into();
        let dead = problem.dead_with(&f)?;
        let r = problem.residual(&q, &f)?;
        let (wr, pen, e) = problem.objective(sv.op, &q, &f, sv.alpha)?;
        Ok(Point {
            u,
            q,
            f,
            dead,
            r,
            wr,
            pen,
            e,
        })
    }

    /// The trust region on the QP step's predicted marker motion: the step
    /// `(du, dF)` at `u` scaled to move no marker by more than `radius`,
    /// with the model decrease `−cᵀ d` of the step before the cut.
    fn trust_cut(
        &self,
        op: &ObservationOperator,
        u: &[f64],
        mut du: Vec<f64>,
        mut df: Vec<f64>,
        c: &[f64],
        radius: f64,
    ) -> Result<TrialStep> {
        let mut dm = du.clone();
        dm.extend_from_slice(&df);
        // model decrease of the objective
        let dec = (-dot(c, &dm)).max(0.0);
        let mut dq = self.stream.problem.expand(u, &du)?;
        let moved = op
            .rows()
            .iter()
            .map(|row| row.apply(dq.as_slice()).abs())
            .fold(0.0f64, f64::max);
        let cut = moved > radius && moved.is_finite();
        if cut {
            let s = radius / moved;
            du.iter_mut()
                .chain(df.iter_mut())
                .chain(dm.iter_mut())
                .chain(dq.iter_mut())
                .for_each(|v| *v *= s);
        }
        Ok(TrialStep {
            df,
            dm,
            dq,
            cut,
            dec,
        })
    }

    /// Backtracking on the ℓ1 merit function from the point `p` along the
    /// step, each trial pulled back onto the equilibrium manifold by chord
    /// steps with the QP's factorization `lu` (the second-order
    /// correction, against the Maratos effect). On acceptance `p` becomes
    /// the trial and the fraction `t` of the step taken is returned;
    /// `None` if no trial of 30 halvings is accepted.
    fn line_search(
        &self,
        sv: &Solve<'_>,
        p: &mut Point,
        lu: &AutoFactors,
        step: &TrialStep,
        m: &Merit,
    ) -> Result<Option<f64>> {
        let obj = p.wr + p.pen;
        let mut t = 1.0;
        let robot = self.stream.problem.robot();
        let du = &step.dm[..robot.n_free()];
        let (mut ut, mut qt) = (p.u.clone(), p.q.clone());
        for _ in 0..30 {
            robot.advance_into(&p.u, &p.q, du, step.dq.as_slice(), t, &mut ut, &mut qt)?;
            let ft: Vec<f64> = p.f.iter().zip(&step.df).map(|(a, b)| a + t * b).collect();
            let problem = &self.stream.problem;
            let dead_t = problem.dead_with(&ft)?;
            let (ut, qt, rt) = self.corrected(ut.clone(), qt.clone(), &dead_t, lu, m.load)?;
            let (wr_t, pen_t, e_t) = problem.objective(sv.op, &qt, &ft, sv.alpha)?;
            let phi_t = wr_t + pen_t + m.mu * rt.iter().map(|v| v.abs()).sum::<f64>();
            let small = m.dec <= 1e-8 * m.scale && m.rn <= 1e-6 * m.load;
            // near the round-off floor μ|Q|₁ is noise: a trial that stays
            // feasible to 10× the tolerance and decreases J is accepted
            let feasible_t = norm2(rt.as_slice()) <= 10.0 * (1e-9 * m.load).max(m.floor);
            let descends = wr_t + pen_t <= obj + 1e-4 * t * m.lin.min(0.0);
            if m.phi_t_accepts(phi_t, t) || small || (feasible_t && descends) {
                *p = Point {
                    u: ut,
                    q: qt,
                    f: ft,
                    dead: dead_t,
                    r: rt,
                    wr: wr_t,
                    pen: pen_t,
                    e: e_t,
                };
                return Ok(Some(t));
            }
            t *= 0.5;
        }
        Ok(None)
    }

    /// The second-order correction of a trial shape `qt = φ(ut)` under the
    /// dead force `dead_t`: up to four chord steps `u += K⁻¹ Q(q_t, F_t)`
    /// with the factorization `lu` while the residual shrinks (to `1e-10`
    /// of the applied load `load`). The corrected point and its residual.
    #[allow(clippy::type_complexity)]
    fn corrected(
        &self,
        mut ut: Vec<f64>,
        mut qt: Vec<f64>,
        dead_t: &[f64],
        lu: &AutoFactors,
        load: f64,
    ) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
        let problem = &self.stream.problem;
        let robot = problem.robot();
        let (mut uc, mut qc) = (ut.clone(), qt.clone());
        let mut rt = problem.residual_under(&ut, &qt, dead_t)?;
        let mut rn_t = norm2(rt.as_slice());
        for _ in 0..4 {
            let mut du_c = rt.clone();
            lu.solve_in_place(&mut du_c)?;
            if !du_c.iter().all(|v| v.is_finite()) {
                break;
            }
            let corr = problem.expand(&ut, du_c.as_slice())?;
            robot.advance_into(&ut, &qt, &du_c, corr.as_slice(), 1.0, &mut uc, &mut qc)?;
            let rc = problem.residual_under(&uc, &qc, dead_t)?;
            let rn_c = norm2(rc.as_slice());
            if rn_c.is_nan() || rn_c >= rn_t {
                break;
            }
            std::mem::swap(&mut ut, &mut uc);
            std::mem::swap(&mut qt, &mut qc);
            rt = rc;
            rn_t = rn_c;
            if rn_t <= 1e-10 * load {
                break;
            }
        }
        Ok((ut, qt, rt))
    }

    /// The answer at the last point: its exact equilibrium at the final
    /// `F` (see [`SqpEstimator::final_chord`], else re-solved and
    /// re-factored), the derivatives and covariance factor there, and the
    /// report with `status`.
    fn answer(
        &mut self,
        sv: &Solve<'_>,
        p: Point,
        at_q: Option<(Derivs, GnFactor)>,
        last: Option<FactoredTangent>,
        status: EstimateStatus,
        iterations: usize,
    ) -> Result<Solved> {
        let (op, alpha) = (sv.op, sv.alpha);
        let finish = match (at_q, last) {
            (Some(at), Some(tangent)) => self.final_chord(sv, &p, at, tangent)?,
            _ => None,
        };
        let f = p.f;
        let (q, dv, gn, residual_n) = match finish {
            Some(x) => x,
            None => {
                self.warm_qp = None;
                let problem = &mut self.stream.problem;
                let eq = problem.equilibrium(&f, &p.q)?;
                let dv = problem.derivs(eq.q.as_slice(), &eq.factors, op)?;
                let e = op.residual(eq.q.as_slice());
                let (_, gn) = problem.gn_solve(&dv, op, &e, &f, alpha)?;
                (eq.q.data.into(), dv, Some(gn), eq.residual_n)
            }
        };
        let problem = &self.stream.problem;
        let (wr, pen, e) = problem.objective(op, &q, &f, alpha)?;
        let g = problem.gradient(&dv, op, &e, &f, alpha)?;
        Ok(Solved {
            f,
            q,
            derivs: dv,
            gn,
            e,
            report: EstimateReport {
                backend: Backend::Sqp,
                status,
                iterations,
                sub_steps: 1,
                objective: wr + pen,
                weighted_residual: wr,
                n_observations: op.len(),
                gradient_norm: norm2(&g),
                equilibrium_residual_n: residual_n,
                alpha,
                wall_time_s: 0.0,
                linear_work: Default::default(),
                far_start: None,
                alpha_search: None,
            },
        })
    }

    /// The exact equilibrium at the final `F` by chord steps from the last
    /// point with the last QP's factorization (taken there): at a feasible
    /// point a few do it, and while they move the shape by no more than
    /// 1e-6 L that QP's derivatives stay exact to about 1e-6 relative
    /// (they serve the covariances, the reported gradient norm and the
    /// next warm step's first QP, not the estimate itself). The shape, the
    /// derivatives, the factor and `|Q|_2`, with the QP kept for the next
    /// warm step; `None` (and no QP kept) when the steps do not converge
    /// (the caller re-solves). (One chord step of 1e-10 L at most, as
    /// before, missed at fine meshes, where the feasibility test's
    /// round-off floor is larger: the shape then moves by 1e-8 m at 800
    /// elements, and the re-solve cost a second linearization per warm
    /// step.)
    #[allow(clippy::type_complexity)]
    fn final_chord(
        &mut self,
        sv: &Solve<'_>,
        p: &Point,
        (dv, fac): (Derivs, GnFactor),
        tangent: FactoredTangent,
    ) -> Result<Option<(Vec<f64>, Derivs, Option<GnFactor>, f64)>> {
        let len = sv.len;
        let lu = &tangent.factors;
        let problem = &self.stream.problem;
        let robot = problem.robot();
        let (mut uc, mut qc) = (p.u.clone(), p.q.clone());
        let (mut u1, mut q1) = (uc.clone(), qc.clone());
        let mut rc = p.r.clone();
        let mut moved = 0.0;
        let mut prev = f64::INFINITY;
        let mut done = false;
        for _ in 0..4 {
            let mut w = rc.clone();
            lu.solve_in_place(&mut w)?;
            let step = w.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            moved += step;
            if !step.is_finite() || moved > 1e-6 * len {
                break;
            }
            let dq = problem.expand(&uc, &w)?;
            robot.advance_into(&uc, &qc, &w, dq.as_slice(), 1.0, &mut u1, &mut q1)?;
            std::mem::swap(&mut uc, &mut u1);
            std::mem::swap(&mut qc, &mut q1);
            rc = problem.residual_under(&uc, &qc, &p.dead)?;
            // below 1e-10 L, or predicted so by the contraction so far
            if chord_converged(step, prev, moved, len) {
                done = true;
                break;
            }
            prev = step;
        }
        if !done {
            self.warm_qp = None;
            return Ok(None);
        }
        let residual_n = norm2(&rc);
        self.warm_qp = Some(WarmQp {
            q: qc.clone(),
            rows: sv.op.rows().to_vec(),
            tangent,
            dv: dv.clone(),
        });
        Ok(Some((qc, dv, Some(fac), residual_n)))
    }
}

/// The convergence tests of a feasible point on the predicted decrease
/// along the manifold `dec` (`scale = max(J, n_ob)`): below `tol × scale`;
/// half of it below `κ²` (the statistical test, as the Newton backend's);
/// at the round-off floor (below `1e-13 scale` and no longer shrinking).
fn converged(
    dec: f64,
    tol: f64,
    kappa: f64,
    scale: f64,
    prev_dec: f64,
) -> Option<EstimateCriterion> {
    if dec <= tol * scale {
        Some(EstimateCriterion::PredictedDecrease)
    } else if 0.5 * dec <= kappa.powi(2) {
        Some(EstimateCriterion::WithinNoise)
    } else if dec <= 1e-13 * scale && dec > 0.9 * prev_dec {
        Some(EstimateCriterion::RoundOffFloor)
    } else {
        None
    }
}

impl Merit {
    /// The Armijo test on the merit function for a trial at `t`.
    fn phi_t_accepts(&self, phi_t: f64, t: f64) -> bool {
        phi_t <= self.phi + 1e-4 * t * self.slope.min(0.0)
    }
}
