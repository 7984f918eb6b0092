//! The reduced Gauss–Newton iteration (27)–(30) of one solve, by phase
//! (see the [module documentation](super) for the method): the objective
//! at the iterate, the linearization (derivatives (28), gradient (29), the
//! Gauss–Newton step (30)), the convergence tests, the trust region, the
//! unconfirmed last step, the far start and the Armijo line search.
//! [`Reduced::run`] strings them together.

use crate::error::Result;
use crate::linsolve::AutoFactors;
use crate::numeric::{dot, norm2};
use crate::observe::{ObsRow, ObservationOperator};
use crate::sensitivity::Sensitivity;
use crate::statics::TrackedEquilibrium;

use super::super::driver::Solved;
use super::super::problem::{Derivs, GnFactor, Problem, step_cap};
use super::super::{
    Backend, EstimateCriterion, EstimateReport, EstimateStatus, EstimationModel, EstimatorSettings,
};
use super::DerivsCache;
use super::far::full_space;

/// What a reduced solve works on: the estimator's problem and caches, the
/// observation and `α`.
pub(super) struct Reduced<'a, M: EstimationModel> {
    pub(super) core: &'a mut Problem<M>,
    /// The derivatives at the last converged estimate's shape (see
    /// `NewtonEstimator::derivs_cache`).
    pub(super) derivs_cache: &'a mut Option<DerivsCache>,
    /// The observation rows of `derivs_cache`.
    pub(super) cache_rows: &'a mut Vec<ObsRow>,
    /// The last estimate `F` and `H F` there.
    pub(super) hf_cache: &'a mut Option<(Vec<f64>, Vec<f64>)>,
    /// The full-space iterations of a far start.
    pub(super) inner: &'a mut Option<Box<super::super::sqp::SqpEstimator<M>>>,
    pub(super) op: &'a ObservationOperator,
    pub(super) alpha: f64,
    pub(super) settings: EstimatorSettings,
    /// The globalized static solves the line searches of this solve may
    /// still run (starts at [`LINE_SEARCH_FALLBACKS`]).
    pub(super) fallbacks_left: usize,
}

/// An iterate: an equilibrium `(q, F)` with the tangent's factors at `q`
/// and its residual `|Q|_2` (N).
pub(super) struct Iterate {
    pub(super) f: Vec<f64>,
    pub(super) q: Vec<f64>,
    lu: AutoFactors,
    res_n: f64,
}

impl Iterate {
    /// The iterate at load `f` and its equilibrium `eq`.
    pub(super) fn at(f: Vec<f64>, eq: TrackedEquilibrium) -> Self {
        Iterate {
            f,
            q: eq.q.data.into(),
            lu: eq.factors,
            res_n: eq.residual_n,
        }
    }
}

/// The objective's parts at an iterate: the weighted residual `eᵀWe`, the
/// penalty `α FᵀHF`, the marker residuals `e` and `H F` (for the gradient).
struct ObjectiveAt {
    wr: f64,
    pen: f64,
    e: Vec<f64>,
    hf: Vec<f64>,
}

impl ObjectiveAt {
    fn value(&self) -> f64 {
        self.wr + self.pen
    }
}

/// The linearization at an iterate: the derivatives, the gradient (29),
/// the Gauss–Newton step (30) with its system's factor, and the step's
/// predicted decrease `dec = −½ gᵀ dF`.
struct Linearization {
    dv: Derivs,
    g: Vec<f64>,
    step: Vec<f64>,
    fac: GnFactor,
    dec: f64,
}

/// The step within the trust region: the load step, the predicted motion
/// of the coordinates, the factor it was cut by and the slope `gᵀ dF`.
struct CappedStep {
    step: Vec<f64>,
    dq: Vec<f64>,
    cap: f64,
    slope: f64,
}

/// An accepted step: the new iterate and, when the line search formed it,
/// the objective there (which the next iteration starts from).
type Accepted = (Iterate, Option<ObjectiveAt>);

/// The globalized static solves (the tracker's fallback after its warm
/// iterations, each within `statics.max_total_iterations` Newton
/// iterations) that the line searches of one solve may run: one. A trial
/// that needs another ends the solve ([`Search::BudgetSpent`],
/// [`EstimateStatus::LineSearchFailed`]), so the line searches' globalized
/// work per solve is at most one static solve's budget.
///
/// Measured on the fuzz finding
/// `tests/fuzz/regressions/scene_estimate/newton_line_search_minutes` (16
/// elements, markers no equilibrium fits, default budgets): with a fallback
/// at every trial below `t = 0.01` (before) the estimate ran 137 s to
/// `iteration_limit` with 8.66 million factorizations, 8.63 million of them
/// in 3,966 globalized solves of its line searches (14 to 10,338
/// factorizations each); 299 of them converged, at steps `t` of 7e-9 to
/// 8e-3, and the estimate still ended with the objective at 2.1e7 for 8
/// observed components. With one per solve: 0.68 s, 39,192 factorizations,
/// `line_search_failed` (`tests/fuzz_findings.rs`). On the example scenes
/// (`examples/*` with their markers files, the payload stream) no line
/// search went below `t = 0.25`: none of their trials needs a fallback, and
/// their estimates are the same to the bit.
pub(super) const LINE_SEARCH_FALLBACKS: usize = 1;

/// How a line search ended.
enum Search {
    /// A trial was accepted (boxed: the other variants are empty).
    Accepted(Box<Accepted>),
    /// No trial of the 30 halvings was accepted.
    NoStep,
    /// A trial's warm static solve failed and the solve's line searches had
    /// run their [`LINE_SEARCH_FALLBACKS`] globalized solves.
    BudgetSpent,
}

impl<M: EstimationModel> Reduced<'_, M> {
    /// The solve from `(f0, q0)`: the iterations until a convergence test
    /// holds, the budget runs out or the line search fails; with `far`, a
    /// far start may replace the first linearization of a solve from zero
    /// load or a step the trust region cuts (`far` then holds the
    /// full-space iterations it took).
    pub(super) fn run(
        mut self,
        f0: Vec<f64>,
        q0: Vec<f64>,
        mut far: Option<&mut Option<usize>>,
    ) -> Result<Solved> {
        let eq = self.core.equilibrium(&f0, &q0)?;
        let mut it = Iterate::at(f0, eq);
        let n_ob = self.op.len() as f64;
        let mut iterations = 0;
        let mut prev_dec = f64::INFINITY;
        // the objective at the accepted trial point, which the next
        // iteration starts from
        let mut at_trial: Option<ObjectiveAt> = None;
        let mut eager = far.is_some() && it.f.iter().all(|v| *v == 0.0);
        loop {
            let at = self.objective_at(&it, at_trial.take())?;
            let obj = at.value();
            // a cold solve from zero load (a stream's first, from the
            // unloaded shape) takes the far start at once: its first
            // linearization would only measure how far the start is
            if eager {
                eager = false;
                if let Some(used) = far.take()
                    && let Some((next, its)) = self.far_start(&it, obj)?
                {
                    *used = Some(its);
                    iterations += its;
                    it = next;
                    continue;
                }
            }
            let lin = self.linearize(&it, &at)?;
            let scale = obj.max(n_ob);
            if let Some(criterion) = self.converged(&lin, scale, prev_dec) {
                return Ok(self.converged_at(it, at, lin, criterion, iterations));
            }
            if iterations >= self.settings.max_iterations {
                let status = EstimateStatus::IterationLimit { iterations };
                return Ok(self.stopped_at(it, at, lin, status, iterations));
            }
            let step = self.trust_region(&it, &lin)?;
            let last = self.is_last_step(&lin, &step, scale, prev_dec);
            iterations += 1;
            prev_dec = lin.dec;
            let lin = if last {
                match self.unconfirmed_last(&it, &at, lin, &step, iterations)? {
                    Ok(s) => return Ok(s),
                    Err(lin) => lin,
                }
            } else {
                lin
            };
            // a far start (the trust region cuts the step of a cold
            // solve): the full-space iterations take over (see
            // `full_space`), once per solve
            let mut accepted = None;
            if step.cap < 1.0
                && let Some(used) = far.take()
                && let Some((next, its)) = self.far_start(&it, obj)?
            {
                *used = Some(its);
                iterations += its;
                accepted = Some((next, None));
            }
            let search = match accepted {
                Some(a) => Search::Accepted(Box::new(a)),
                None => self.line_search(&it, obj, &lin, &step, scale)?,
            };
            let status = match search {
                Search::Accepted(accepted) => {
                    (it, at_trial) = *accepted;
                    continue;
                }
                Search::NoStep if lin.dec <= 1e-6 * scale => {
                    EstimateStatus::Converged(EstimateCriterion::NegligibleDecrease)
                }
                // no step, or the work the line searches may do spent:
                // never a convergence
                Search::NoStep | Search::BudgetSpent => EstimateStatus::LineSearchFailed,
            };
            return Ok(self.stopped_at(it, at, lin, status, iterations));
        }
    }

    /// The objective at the iterate: the line search's, when it formed it
    /// at this point; else at the last estimate's `F` with its cached
    /// `H F` (a warm step's first iteration); else formed.
    fn objective_at(&mut self, it: &Iterate, at_trial: Option<ObjectiveAt>) -> Result<ObjectiveAt> {
        let (core, op, alpha) = (&*self.core, self.op, self.alpha);
        Ok(match at_trial {
            Some(x) => x,
            None => match self.hf_cache.take() {
                Some((fc, hf)) if fc == it.f => {
                    let (wr, pen, e) =
                        core.objective_with_hf(op, it.q.as_slice(), &it.f, &hf, alpha);
                    ObjectiveAt { wr, pen, e, hf }
                }
                _ => {
                    let (wr, pen, e, hf) = core.objective_hf(op, it.q.as_slice(), &it.f, alpha)?;
                    ObjectiveAt { wr, pen, e, hf }
                }
            },
        })
    }

    /// The linearization at the iterate: the derivatives (cached at the
    /// last estimate's shape for a warm step, with the Gauss–Newton factor
    /// formed there for the same weights: the same numbers; else by the
    /// adjoint solves), the gradient (29) and the Gauss–Newton step (30)
    /// (the covariances are formed on request from its factor).
    fn linearize(&mut self, it: &Iterate, at: &ObjectiveAt) -> Result<Linearization> {
        let (core, op, alpha) = (&*self.core, self.op, self.alpha);
        let cached = match self.derivs_cache.take() {
            Some((qc, dv, gn)) if qc == it.q && self.cache_rows[..] == *op.rows() => {
                let gn = gn.and_then(|(w, fac)| (w[..] == *op.weights()).then_some(fac));
                Some((dv, gn))
            }
            _ => None,
        };
        let (dv, gn) = match cached {
            Some(x) => x,
            None => (core.derivs(&it.q, &it.lu, op)?, None),
        };
        let g = core.gradient_hf(&dv, op, &at.e, &at.hf, alpha)?;
        let (step, fac) = core.gn_solve_reusing(&dv, op, &at.e, &it.f, alpha, gn)?;
        let dec = -0.5 * dot(&g, &step);
        Ok(Linearization {
            dv,
            g,
            step,
            fac,
            dec,
        })
    }

    /// The convergence tests on the linearization (`scale = max(J, n_ob)`):
    /// the predicted decrease below `tolerance × scale`; the statistical
    /// test `dec = dFᵀ N dF ≤ κ²` (see
    /// [`EstimatorSettings::statistical_tolerance`]); the round-off floor
    /// (tiny and no longer shrinking); a stationary point.
    fn converged(
        &self,
        lin: &Linearization,
        scale: f64,
        prev_dec: f64,
    ) -> Option<EstimateCriterion> {
        let dec = lin.dec;
        let kappa2 = self.settings.statistical_tolerance.powi(2);
        let within_noise = dec <= kappa2;
        let floor = dec <= 1e-13 * scale && dec > 0.9 * prev_dec;
        if dec <= self.settings.tolerance * scale {
            Some(EstimateCriterion::PredictedDecrease)
        } else if within_noise {
            Some(EstimateCriterion::WithinNoise)
        } else if floor {
            Some(EstimateCriterion::RoundOffFloor)
        } else if !dec.is_finite() && dot(&lin.g, &lin.step) == 0.0 {
            Some(EstimateCriterion::Stationary)
        } else {
            None
        }
    }

    /// The report of the linearized iterate with `status`.
    fn report(
        &self,
        it: &Iterate,
        at: &ObjectiveAt,
        lin: &Linearization,
        status: EstimateStatus,
        iterations: usize,
    ) -> EstimateReport {
        EstimateReport {
            backend: Backend::Newton,
            status,
            iterations,
            sub_steps: 1,
            objective: at.value(),
            weighted_residual: at.wr,
            n_observations: self.op.len(),
            gradient_norm: norm2(&lin.g),
            equilibrium_residual_n: it.res_n,
            alpha: self.alpha,
            wall_time_s: 0.0,
            linear_work: Default::default(),
            far_start: None,
            alpha_search: None,
        }
    }

    /// A converged iterate: its derivatives, Gauss–Newton factor and `H F`
    /// cached (the next warm step starts there), and the solve.
    fn converged_at(
        self,
        it: Iterate,
        at: ObjectiveAt,
        lin: Linearization,
        criterion: EstimateCriterion,
        iterations: usize,
    ) -> Solved {
        let report = self.report(
            &it,
            &at,
            &lin,
            EstimateStatus::Converged(criterion),
            iterations,
        );
        let op = self.op;
        if self.cache_rows[..] != *op.rows() {
            *self.cache_rows = op.rows().to_vec();
        }
        *self.derivs_cache = Some((
            it.q.clone(),
            lin.dv.clone(),
            Some((op.weights().to_vec(), lin.fac.clone())),
        ));
        *self.hf_cache = Some((it.f.clone(), at.hf));
        Solved {
            f: it.f,
            q: it.q,
            derivs: lin.dv,
            gn: Some(lin.fac),
            e: at.e,
            report,
        }
    }

    /// The iterate as the solve's answer with a status that is not a
    /// convergence of the iteration (its budget, a failed line search) or
    /// the line search's negligible decrease.
    fn stopped_at(
        self,
        it: Iterate,
        at: ObjectiveAt,
        lin: Linearization,
        status: EstimateStatus,
        iterations: usize,
    ) -> Solved {
        let report = self.report(&it, &at, &lin, status, iterations);
        Solved {
            f: it.f,
            q: it.q,
            derivs: lin.dv,
            gn: Some(lin.fac),
            e: at.e,
            report,
        }
    }

    /// The trust region (after the convergence tests: a converged iterate
    /// takes no step): the predicted motion of every node,
    /// `M K⁻¹ Mᵀ G dF` (one more solve), within `max_observation_jump_m`.
    fn trust_region(&self, it: &Iterate, lin: &Linearization) -> Result<CappedStep> {
        let core = &*self.core;
        let jump = self.settings.max_observation_jump_m;
        let mut step = lin.step.clone();
        let u = core.robot().free_coordinates_of(&it.q)?;
        let mut dq: Vec<f64> = Sensitivity::at(core.robot(), u.as_slice(), &it.lu)?
            .response(&core.gen_force(&step)?)?
            .data
            .into();
        let moved = core.robot().max_position_change(&dq);
        let cap = if moved > jump && moved.is_finite() {
            jump / moved
        } else {
            step_cap(&lin.dv, &step, jump)
        };
        step.iter_mut().for_each(|v| *v *= cap);
        dq.iter_mut().for_each(|v| *v *= cap);
        let slope = dot(&lin.g, &step);
        Ok(CappedStep {
            step,
            dq,
            cap,
            slope,
        })
    }

    /// Whether this step is the last: the decrease predicted after it
    /// (convergence at least quadratic, `dec²/dec_prev`, with a margin of
    /// 1000) is far below the threshold the successor is held to
    /// (`max(tolerance × scale, κ²)`). The step is then taken without a
    /// further linearization to confirm it: the estimate is the iterate
    /// that confirmation would accept, and it saves a factorization, the
    /// adjoint solves and a Gauss–Newton system. The covariances and the
    /// gradient norm are this linearization's.
    fn is_last_step(
        &self,
        lin: &Linearization,
        step: &CappedStep,
        scale: f64,
        prev_dec: f64,
    ) -> bool {
        let dec = lin.dec;
        let kappa2 = self.settings.statistical_tolerance.powi(2);
        let threshold = (self.settings.tolerance * scale).max(kappa2);
        prev_dec.is_finite()
            && step.cap == 1.0
            && dec <= 1e-8 * scale
            && dec * dec <= 1e-3 * threshold * prev_dec
    }

    /// The unconfirmed last step: its equilibrium by chord steps with the
    /// kept factors (no factorization), the objective there; the
    /// linearization back if the chord steps do not converge (the iteration
    /// then goes on).
    fn unconfirmed_last(
        &mut self,
        it: &Iterate,
        at: &ObjectiveAt,
        lin: Linearization,
        step: &CappedStep,
        iterations: usize,
    ) -> Result<std::result::Result<Solved, Linearization>> {
        let ft: Vec<f64> = it.f.iter().zip(&step.step).map(|(a, b)| a + b).collect();
        let load = self.core.load();
        let Some((qt, res_t)) = self
            .core
            .tracker()
            .solve_chord(&load, &ft, it.q.as_slice())?
        else {
            return Ok(Err(lin));
        };
        let (wr_t, pen_t, e_t) = self
            .core
            .objective(self.op, qt.as_slice(), &ft, self.alpha)?;
        let mut rep = self.report(
            it,
            at,
            &lin,
            EstimateStatus::Converged(EstimateCriterion::UnconfirmedLastStep),
            iterations,
        );
        rep.objective = wr_t + pen_t;
        rep.weighted_residual = wr_t;
        rep.equilibrium_residual_n = res_t;
        Ok(Ok(Solved {
            f: ft,
            q: qt.data.into(),
            derivs: lin.dv,
            gn: Some(lin.fac),
            e: e_t,
            report: rep,
        }))
    }

    /// Armijo backtracking on the objective `obj` along the capped step;
    /// tiny predicted decreases take the full step (the objective's
    /// round-off would hide the decrease). [`Search::NoStep`] if no trial
    /// of 30 halvings is accepted; [`Search::BudgetSpent`] at a trial that
    /// needs a globalized static solve beyond [`LINE_SEARCH_FALLBACKS`].
    fn line_search(
        &mut self,
        it: &Iterate,
        obj: f64,
        lin: &Linearization,
        step: &CappedStep,
        scale: f64,
    ) -> Result<Search> {
        let (op, alpha) = (self.op, self.alpha);
        let core = &mut *self.core;
        let dec = lin.dec;
        let mut t = 1.0;
        for _ in 0..30 {
            let ft: Vec<f64> =
                it.f.iter()
                    .zip(&step.step)
                    .map(|(a, b)| a + t * b)
                    .collect();
            // the trial's equilibrium starts from the linearized
            // prediction q + t dq (a predictor–corrector step, as the
            // sqp backend's full-space step): the corrector's chord
            // steps then only remove the second-order error. From q
            // itself they had to cover the whole step and failed on
            // large ones, which fell through to the globalized static
            // solve (10–100× the cost of a first estimate).
            let qp: Vec<f64> = it.q.iter().zip(&step.dq).map(|(a, b)| a + t * b).collect();
            // a trial without the globalized fallback unless the step is
            // already short (and the solve's line searches have one left):
            // cheap
            let trial = if t < 0.01 && self.fallbacks_left > 0 {
                let before = core.tracker().counts().fallbacks;
                let eq = core.equilibrium(&ft, &qp).ok();
                if core.tracker().counts().fallbacks > before {
                    self.fallbacks_left -= 1;
                }
                eq
            } else {
                let load = core.load();
                let eq = core.tracker().try_solve(&load, &ft, &qp).ok().flatten();
                if eq.is_none() && t < 0.01 {
                    return Ok(Search::BudgetSpent);
                }
                eq
            };
            if let Some(eq) = trial {
                let (wr, pen, e, hf) = core.objective_hf(op, eq.q.as_slice(), &ft, alpha)?;
                if wr + pen <= obj + 1e-4 * t * step.slope || dec <= 1e-8 * scale {
                    return Ok(Search::Accepted(Box::new((
                        Iterate::at(ft, eq),
                        Some(ObjectiveAt { wr, pen, e, hf }),
                    ))));
                }
            }
            t *= 0.5;
        }
        Ok(Search::NoStep)
    }
}

impl<M: EstimationModel> Reduced<'_, M> {
    /// The far start from the iterate `it` (objective `obj`): the full-space
    /// iterations ([`full_space`]) and the equilibrium at their estimate,
    /// with the iterations they took; `None` if they did not converge below
    /// `obj` or the equilibrium failed. Their last factored tangent is kept in
    /// the tracker (the equilibrium there is then a chord step without a
    /// factorization) and their derivatives cached for the next iteration, at
    /// the equilibrium's shape when that stayed within `1e-10 L` of theirs
    /// (the tracker then returns the same factors, from which the derivatives
    /// are the same numbers).
    pub(super) fn far_start(&mut self, it: &Iterate, obj: f64) -> Result<Option<(Iterate, usize)>> {
        let (core, op) = (&mut *self.core, self.op);
        let Some((fs, qs, its, last)) =
            full_space(self.inner, core, op, &it.f, &it.q, self.alpha, obj)
        else {
            return Ok(None);
        };
        let mut cached = None;
        if let Some((tangent, dv)) = last {
            core.tracker().keep_factors(&qs, tangent.factors)?;
            cached = Some(dv);
        }
        let Ok(eq) = core.equilibrium(&fs, &qs) else {
            return Ok(None);
        };
        if let Some(dv) = cached {
            let tol = 1e-10 * core.robot().length_m();
            if eq.q.iter().zip(&qs).all(|(a, b)| (a - b).abs() <= tol) {
                *self.cache_rows = op.rows().to_vec();
                *self.derivs_cache = Some((eq.q.as_slice().to_vec(), dv, None));
            }
        }
        Ok(Some((Iterate::at(fs, eq), its)))
    }
}
