//! What both estimators do around their method: the stream of
//! observations (warm starts), the choice of `α` by the discrepancy principle
//! and the continuation in `α`, the incremental observations of a large jump,
//! and the assembly of the [`Estimate`].

use std::time::Instant;

use nalgebra::DVector;

use crate::element::{Element, NodeKinematics};
use crate::error::{Error, Result};
use crate::linsolve::LinearWork;
use crate::observe::{Observation, ObservationOperator};

use super::covariance::{CovarianceInputs, LazyCovariances};
use super::problem::{Derivs, GnFactor, Problem};
use super::{AlphaRule, AlphaSearch, Backend, Estimate, EstimateReport, EstimationModel, FarStart};

/// Where the searches for `α` (the evidence's, the discrepancy principle's)
/// begin their continuation in `α` (m/N² with whitened weights).
pub const ALPHA_CONTINUATION_START: f64 = 100.0;

/// The state a backend keeps between steps: the last converged estimate and
/// the observation it fitted.
#[derive(Debug, Clone)]
pub(crate) struct Warm {
    pub(crate) f: Vec<f64>,
    pub(crate) q: Vec<f64>,
    pub(crate) y: Vec<f64>,
}

/// One solve of a backend at a fixed `α` and observation, converged or not
/// (its report's status says).
pub struct Solved {
    pub(crate) f: Vec<f64>,
    pub(crate) q: Vec<f64>,
    pub(crate) derivs: Derivs,
    /// The Gauss–Newton system's factor at `derivs` (the covariances are
    /// formed from it, on request), if at hand.
    pub(crate) gn: Option<GnFactor>,
    pub(crate) e: Vec<f64>,
    pub(crate) report: EstimateReport,
}

/// An estimator's state along a stream of observations: the problem, the
/// `α` in use and the warm start.
#[derive(Debug, Clone)]
pub(crate) struct Stream<M: EstimationModel> {
    pub(crate) problem: Problem<M>,
    pub(crate) alpha: Option<f64>,
    pub(crate) warm: Option<Warm>,
    /// The `α` search of the current step, if it ran one.
    pub(crate) alpha_search: Option<AlphaSearch>,
}

impl<M: EstimationModel> Stream<M> {
    /// A fresh stream over `problem` (`α` from its settings).
    pub(crate) fn new(problem: Problem<M>) -> Self {
        Stream {
            alpha: problem.settings().alpha,
            problem,
            warm: None,
            alpha_search: None,
        }
    }

    /// Forgets the warm start, the tracker's state and an automatically
    /// chosen `α`.
    pub(crate) fn reset(&mut self) {
        self.warm = None;
        self.problem.tracker().forget();
        self.alpha = self.problem.settings().alpha;
    }

    /// The starting point of a step: the warm state, else zero load and the
    /// shape of the known loads.
    pub(crate) fn start(&mut self) -> Result<(Vec<f64>, Vec<f64>)> {
        if let Some(w) = &self.warm {
            return Ok((w.f.clone(), w.q.clone()));
        }
        self.problem.unloaded_start()
    }

    /// Intermediate measurement vectors from the previous observation to `y`
    /// when the jump exceeds `max_observation_jump_m` (positions only count).
    fn sub_targets(&self, op: &ObservationOperator, q_start: &[f64]) -> Vec<Vec<f64>> {
        let y = op.measurements();
        // from the last observation, or (first step) from the markers of
        // the starting shape
        let predicted: Vec<f64>;
        let prev = match &self.warm {
            Some(w) if w.y.len() == y.len() => &w.y,
            _ => {
                predicted = op.apply(q_start);
                &predicted
            }
        };
        let jump = y
            .iter()
            .zip(prev)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let n = (jump / self.problem.settings().max_observation_jump_m)
            .ceil()
            .max(1.0);
        let n = if n.is_finite() {
            (n as usize).min(1000)
        } else {
            1
        };
        (1..=n)
            .map(|k| {
                let t = k as f64 / n as f64;
                prev.iter().zip(y).map(|(a, b)| a + t * (b - a)).collect()
            })
            .collect()
    }

    /// Assembles the [`Estimate`] at `(q, F)`; its covariances are formed
    /// from `dv` and `gn` when first asked for.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &self,
        q: Vec<f64>,
        f: Vec<f64>,
        op: &ObservationOperator,
        dv: Derivs,
        gn: Option<GnFactor>,
        e: Vec<f64>,
        report: EstimateReport,
    ) -> Result<Estimate> {
        let problem = &self.problem;
        let mut f = f;
        unused_load_slots_zeroed::<M::Element>(problem.load(), &mut f);
        // `H F̂`: the resultants' moment and the penalty `F̂ᵀ H F̂`
        let hf = problem.penalty_grad(&f)?;
        let (resultant_force_n, resultant_moment_nm, fw) = problem.resultants(&q, &f, &hf)?;
        let informative = super::evidence::informative(&dv);
        let mut report = report;
        if !informative {
            report.status = super::EstimateStatus::NoInformation;
        }
        let settings = problem.settings();
        let by_evidence = settings.alpha.is_none() && settings.alpha_rule == AlphaRule::Evidence;
        // the penalty `F̂ᵀ H F̂`, for the evidence's covariances and its γ
        let pen = if informative {
            Some(hf.iter().zip(&f).map(|(a, b)| a * b).sum())
        } else {
            None
        };
        let evidence = if by_evidence {
            pen.map(|pen| (f.clone(), pen))
        } else {
            None
        };
        let cov = LazyCovariances::new(CovarianceInputs {
            load: problem.load(),
            form: problem.gn_form(op.len())?,
            nd: M::Element::NODE_DOFS,
            used_slots: 2 * M::Element::DIM,
            sigma: settings.noise_sigma_m,
            fw,
            dv,
            weights: op.weights().to_vec(),
            alpha: report.alpha,
            evidence,
            // how many load directions the markers determine (the
            // evidence's γ), formed on request like the covariances
            gamma: pen.map(|pen| (report.objective, pen)),
            gn,
        });
        Ok(Estimate {
            q: DVector::from_vec(q),
            f: DVector::from_vec(f),
            load_model: problem.load(),
            resultant_force_n: DVector::from_vec(resultant_force_n),
            resultant_moment_nm: DVector::from_vec(resultant_moment_nm),
            marker_residuals: DVector::from_vec(e),
            noise_sigma_m: settings.noise_sigma_m,
            report,
            node_s: problem
                .robot()
                .field_rod()
                .map(|r| r.node_arc().to_vec())
                .unwrap_or_default(),
            dim: M::Element::DIM,
            node_dofs: M::Element::NODE_DOFS,
            cov,
        })
    }
}

/// A distributed load field is laid out like the node coordinates, its
/// `[w, w']` in the first `2 DIM` numbers of each node's; a node of the
/// full 3-D element holds `r_Y, r_Z` after them, numbers no load is made
/// of (`G F` and the penalty ignore them). The representer steps leave
/// values there that mean nothing: zeroed (and so are their rows of the
/// covariance factor, see [`CovarianceInputs::used_slots`]).
fn unused_load_slots_zeroed<E: Element>(load: super::LoadModel, f: &mut [f64]) {
    let (nd, d) = (E::NODE_DOFS, E::DIM);
    if load != super::LoadModel::Distributed || nd <= 2 * d {
        return;
    }
    for (i, v) in f.iter_mut().enumerate() {
        if i % nd >= 2 * d {
            *v = 0.0;
        }
    }
}

/// A method over the estimation problem: how one backend solves it at a
/// fixed `α` and observation from a start `(F, q)`.
pub(crate) trait Method<M: EstimationModel> {
    /// The backend.
    const BACKEND: Backend;
    /// The stream the method runs on.
    fn stream(&mut self) -> &mut Stream<M>;
    /// One solve from `(f0, q0)` at `alpha` for the observation `op`.
    fn solve_one(
        &mut self,
        op: &ObservationOperator,
        f0: Vec<f64>,
        q0: Vec<f64>,
        alpha: f64,
    ) -> Result<Solved>;
    /// The far starts of the solves since the last call (see
    /// [`FarStart`]), `None` if none took one; the log starts anew.
    fn take_far_start(&mut self) -> Option<FarStart> {
        None
    }
}

/// Chooses `α` by the discrepancy principle: `weighted_residual(α) =
/// n_ob`, with `solve(α)` returning the weighted residual of the estimate
/// at `α`. The residual grows with `α`: from `α = 100` the bracket is
/// widened by factors of 10, then bisected in `log10 α` to 0.02.
pub(crate) fn discrepancy_alpha(
    n_ob: usize,
    mut solve: impl FnMut(f64) -> Result<f64>,
) -> Result<f64> {
    let target = n_ob as f64;
    let (lo_lim, hi_lim) = (-14.0f64, 14.0f64);
    // start where the reduced problem is well conditioned (with whitened
    // weights α = 100 is a strong regularization) and move by decades:
    // each solve starts from the previous one (continuation)
    let mut a = 2.0f64;
    let mut r = solve(ALPHA_CONTINUATION_START)?;
    let (mut lo, mut hi);
    if r > target {
        hi = a;
        while r > target && a > lo_lim {
            hi = a;
            a -= 1.0;
            r = solve(10f64.powf(a))?;
        }
        if r > target {
            return Ok(10f64.powf(a));
        }
        lo = a;
    } else {
        lo = a;
        while r <= target && a < hi_lim {
            lo = a;
            a += 1.0;
            r = solve(10f64.powf(a))?;
        }
        if r <= target {
            return Ok(10f64.powf(a));
        }
        hi = a;
    }
    while hi - lo > 0.02 {
        let mid = 0.5 * (lo + hi);
        if solve(10f64.powf(mid))? > target {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok(10f64.powf(0.5 * (lo + hi)))
}

/// One solve of a continuation path in `α` (the discrepancy search): from `(f0, q0)` at `alpha`; a converged solve
/// becomes the next start. Its weighted residual, or `None` when the solve
/// failed.
fn path_solve<Mo: EstimationModel, Me: Method<Mo>>(
    method: &mut Me,
    op: &ObservationOperator,
    alpha: f64,
    (f0, q0): (&mut Vec<f64>, &mut Vec<f64>),
    search: &mut AlphaSearch,
) -> Option<f64> {
    search.solves += 1;
    let s = method.solve_one(op, f0.clone(), q0.clone(), alpha).ok()?;
    search.iterations += s.report.iterations;
    if s.report.status.is_converged() {
        *f0 = s.f;
        *q0 = s.q;
    }
    Some(s.report.weighted_residual)
}

/// Chooses `α` for the observation `op` by the settings' rule, each
/// solve of the search starting from the last converged one (continuation
/// in `α`, from the stream's start); keeps it in the stream with the warm
/// start the search leaves, and the search's count of solves and
/// iterations for the step's report.
fn choose_alpha<Mo: EstimationModel, Me: Method<Mo>>(
    method: &mut Me,
    op: &ObservationOperator,
) -> Result<f64> {
    let rule = method.stream().problem.settings().alpha_rule;
    let mut search = AlphaSearch {
        rule,
        ..AlphaSearch::default()
    };
    let (a, warm) = if rule == AlphaRule::Evidence {
        super::evidence::evidence_alpha(method, op, &mut search)?
    } else {
        let (mut f0, mut q0) = method.stream().start()?;
        let a = discrepancy_alpha(op.len(), |a| {
            // a failure (at an extreme α) counts as a perfect fit: the
            // search then moves to larger α
            Ok(path_solve(method, op, a, (&mut f0, &mut q0), &mut search).unwrap_or(0.0))
        })?;
        // the last solve of the search is close: start from it
        let warm = Warm {
            f: f0,
            q: q0,
            y: op.measurements().to_vec(),
        };
        (a, warm)
    };
    let stream = method.stream();
    stream.alpha = Some(a);
    stream.warm = Some(warm);
    stream.alpha_search = Some(search);
    Ok(a)
}

/// How the solves of one observation ended.
enum Targets {
    /// Every solve converged: the last one's, for the observation itself.
    Converged(Solved),
    /// A solve stopped short (of an intermediate observation, or of the
    /// observation itself): its last iterate.
    Stopped(Solved),
}

/// The solves of one observation at `alpha` with the iterations they took
/// and how many observations (intermediate ones and the observation
/// itself) were solved.
struct TargetsRun {
    outcome: Targets,
    iterations: usize,
    sub_steps: usize,
}

/// The observation `op` at `alpha`: a stream's first observation in one
/// go (there is no observation before it: the solve's own trust region,
/// which grows while its full steps hold, globalizes the way from the
/// unloaded shape); a later one's jump from the last split into
/// intermediate observations, each solved from the last; the first that
/// stops short ends the run.
fn solve_targets<Mo: EstimationModel, Me: Method<Mo>>(
    method: &mut Me,
    op: &ObservationOperator,
    alpha: f64,
) -> Result<TargetsRun> {
    let targets = if method.stream().warm.is_none() {
        vec![op.measurements().to_vec()]
    } else {
        let (_, q_start) = method.stream().start()?;
        method.stream().sub_targets(op, &q_start)
    };
    let n_sub = targets.len();
    let mut iterations = 0;
    let mut last: Option<Solved> = None;
    for (k, y) in targets.into_iter().enumerate() {
        let (f0, q0) = match &last {
            Some(s) => (s.f.clone(), s.q.clone()),
            None => method.stream().start()?,
        };
        // the last target is the observation itself
        let sub_op;
        let sub = if k + 1 == n_sub {
            op
        } else {
            sub_op = op.with_measurements(y)?;
            &sub_op
        };
        let s = method.solve_one(sub, f0, q0, alpha)?;
        iterations += s.report.iterations;
        if !s.report.status.is_converged() {
            return Ok(TargetsRun {
                outcome: Targets::Stopped(s),
                iterations,
                sub_steps: n_sub,
            });
        }
        last = Some(s);
    }
    let s = last.ok_or_else(|| Error::NonFinite {
        context: "estimator produced no step".into(),
    })?;
    Ok(TargetsRun {
        outcome: Targets::Converged(s),
        iterations,
        sub_steps: n_sub,
    })
}

/// The α revisit: a converged solve of a later frame at an `α` chosen
/// automatically on an earlier one whose answer fails the fit test (the
/// markers show a load the prior of that frame forbids, as a payload put
/// on a robot first seen at rest): `α` is chosen again on this frame, from
/// the answer, and the frame solved at the new `α`, which the stream keeps.
fn revisit_alpha<Mo: EstimationModel, Me: Method<Mo>>(
    method: &mut Me,
    op: &ObservationOperator,
    run: TargetsRun,
) -> Result<TargetsRun> {
    let Targets::Converged(s) = run.outcome else {
        return Ok(run);
    };
    method.stream().warm = Some(Warm {
        f: s.f,
        q: s.q,
        y: op.measurements().to_vec(),
    });
    let alpha = choose_alpha(method, op)?;
    let (f0, q0) = method.stream().start()?;
    let s = method.solve_one(op, f0, q0, alpha)?;
    let iterations = run.iterations + s.report.iterations;
    let outcome = if s.report.status.is_converged() {
        Targets::Converged(s)
    } else {
        Targets::Stopped(s)
    };
    Ok(TargetsRun {
        outcome,
        iterations,
        sub_steps: run.sub_steps,
    })
}

/// Whether a run converged with an answer that fails the fit test.
fn fails_fit(run: &TargetsRun) -> bool {
    match &run.outcome {
        Targets::Converged(s) => {
            super::fit::fit_test(s.report.weighted_residual, s.report.n_observations).is_err()
        }
        Targets::Stopped(_) => false,
    }
}

/// One observation through the backend's method: `α` chosen if not yet, a
/// large jump split into intermediate observations, each solved from the
/// last; `α` chosen again when it was chosen automatically on an earlier
/// frame and this frame's answer fails the fit test; the fit test on the
/// answer of a converged solve (a failure ends as
/// [`super::EstimateStatus::MisfitBeyondNoise`]); the estimate with its
/// covariances. A solve that stops short ends the step with its last
/// iterate and status (the warm start stays at the last estimate whose
/// solve converged, a fit failure's included: it is the problem's optimum
/// at this `α`).
pub(crate) fn run_step<Mo: EstimationModel, Me: Method<Mo>>(
    method: &mut Me,
    observation: &Observation,
) -> Result<Estimate> {
    let start = Instant::now();
    let work = LinearWork::now();
    let backend = Me::BACKEND;
    let op = method.stream().problem.operator_of_frame(observation)?;
    method.take_far_start();
    method.stream().alpha_search = None;
    let alpha_given = method.stream().problem.settings().alpha.is_some();
    // (an α not yet chosen is chosen on this frame: no revisit then)
    let chosen_now = method.stream().alpha.is_none();
    let alpha = match method.stream().alpha {
        Some(a) => a,
        None => choose_alpha(method, &op)?,
    };
    let mut run = solve_targets(method, &op, alpha)?;
    if !alpha_given && !chosen_now && fails_fit(&run) {
        run = revisit_alpha(method, &op, run)?;
    }
    let far_start = method.take_far_start();
    let alpha_search = method.stream().alpha_search.take();
    let finish_report = |mut report: EstimateReport| {
        report.iterations = run.iterations;
        report.sub_steps = run.sub_steps;
        report.backend = backend;
        report.far_start = far_start;
        report.alpha_search = alpha_search;
        report.wall_time_s = start.elapsed().as_secs_f64();
        report.linear_work = LinearWork::now().since(work);
        report
    };
    match run.outcome {
        Targets::Stopped(s) => {
            // the last iterate, with its status; its objective and marker
            // residuals against the observation itself, not the intermediate
            // one
            let stream = method.stream();
            let (wr, pen, e) = stream.problem.objective(&op, &s.q, &s.f, s.report.alpha)?;
            let mut report = s.report;
            report.objective = wr + pen;
            report.weighted_residual = wr;
            let report = finish_report(report);
            stream.finish(s.q, s.f, &op, s.derivs, s.gn, e, report)
        }
        Targets::Converged(s) => {
            let stream = method.stream();
            stream.warm = Some(Warm {
                f: s.f.clone(),
                q: s.q.clone(),
                y: op.measurements().to_vec(),
            });
            let mut report = finish_report(s.report);
            if let (Some(stopped_by), Err(quantile)) = (
                report.status.criterion(),
                super::fit::fit_test(report.weighted_residual, report.n_observations),
            ) {
                report.status = super::EstimateStatus::MisfitBeyondNoise {
                    stopped_by,
                    weighted_residual: report.weighted_residual,
                    quantile,
                };
            }
            stream.finish(s.q, s.f, &op, s.derivs, s.gn, s.e, report)
        }
    }
}
