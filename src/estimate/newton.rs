//! The reduced Gauss–Newton estimator (27)–(30).
//!
//! `q = q(F)` by the static solve (warm-started from the previous iterate),
//! so the problem is unconstrained in `F`:
//! `J(F) = (A q(F) − y)ᵀ W (A q(F) − y) + α Fᵀ H F`.
//!
//! - Sensitivity (28): `∂u/∂F = K⁻¹ Mᵀ G` over the free coordinates `u`
//!   (`K = −∂Q/∂q` restricted with [`Robot::restrict`], `G = J_QF`). The
//!   marker Jacobian `J = A M K⁻¹ Mᵀ G` is formed row by row by adjoint
//!   solves, `z_i = M K⁻¹ Mᵀ a_iᵀ`, `J_i = Gᵀ z_i` (K is symmetric): `n_ob`
//!   solves with one factorization of `K` per iteration.
//! - Gradient (29): `g = 2 (Jᵀ W e + α H F)`, `e = A q − y`.
//! - Gauss–Newton Hessian (30): `2 (Jᵀ W J + α H)`. For the distributed
//!   load (`G = H = B`) the step is solved in the representer form
//!   `F + dF = Σ_i c_i z_i`, `(α W⁻¹ + Zᵀ B Z) c = J F − e`: a Cholesky of an
//!   `n_ob × n_ob` matrix, nothing of size `n_q³`.
//! - Globalization: Armijo backtracking on `J`, each trial a warm static solve
//!   from the linearized prediction `q + t M K⁻¹ Mᵀ G dF` (chord steps with
//!   the last factorization of `K`, then one fresh factorization at the
//!   solution, which the next iteration's adjoint solves use).
//! - Far starts of a cold estimate: when the trust region binds (the
//!   step's predicted node motion is cut to `max_observation_jump_m`),
//!   the reduced method would need many short steps, each a static solve of
//!   several factorizations (the first estimate of a large deflection from
//!   the unloaded shape). The solve then continues with the full-space
//!   iterations of the sqp backend over `(q, F)`, whose iterates need not
//!   be equilibria (one factorization each), and the reduced iteration
//!   resumes at their converged equilibrium, where it confirms convergence
//!   by its own test. Only while the stream has no estimate yet (a warm
//!   step never takes it), and a solve through it that does not converge
//!   is repeated without it: the result is never worse than the reduced
//!   iteration's alone.
//! - A warm step of a stream (a new frame near the last) typically takes
//!   one step from the cached derivatives at the last estimate, one
//!   factorization and one set of adjoint solves at the new point, which
//!   the statistical test accepts: about one exact linearization.
//! - Convergence: the predicted decrease `dec = −½ gᵀ dF = dFᵀ N dF`
//!   (`N = JᵀWJ + αH`) below `κ²`, `κ = statistical_tolerance` (the next
//!   step would move the estimate by less than `κ` of its own standard
//!   deviation, see [`EstimatorSettings::statistical_tolerance`]), or below
//!   `tolerance × max(J, n_ob)` (the tight test). Gauss–Newton converges here at least
//!   quadratically near the solution (the predicted decreases of a warm
//!   step run like 1e-1, 1e-6, 1e-13, 1e-18 relative), so when the decrease
//!   predicted after the current step, `dec²/dec_prev`, is below
//!   `1e-3 ×` the threshold, that step is the last: it is taken (its
//!   equilibrium by chord steps, without a new factorization) and the
//!   estimate returned without a further linearization to confirm it. It
//!   is the iterate the confirming iteration would accept; the gradient
//!   norm and the covariances are those of the linearization before the
//!   step.
//! - Warm start from the last `F*` and shape, with the derivatives there
//!   when they are known; a large jump of the markers is taken through
//!   intermediate observations.

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::Result;
use crate::linsolve::AutoFactors;
use crate::loads::Loads;
use crate::numeric::{dot, norm2};
use crate::observe::{ObsRow, ObservationOperator};
use crate::sensitivity::Sensitivity;
use nalgebra::{DMatrix, DVector};

use super::driver::{run_step, Method, Solved, Stream};
use super::problem::{step_cap, Derivs, GnFactor, Problem};
use super::sqp::SqpEstimator;
use super::{
    Backend, Estimate, EstimateCriterion, EstimateReport, EstimateStatus, Estimator,
    EstimatorSettings, Observation,
};

/// The derivatives at a shape `q` (first), with the Gauss–Newton factor
/// formed from them for the observation weights it holds, if any.
type DerivsCache = (Vec<f64>, Derivs, Option<(Vec<f64>, GnFactor)>);

/// The reduced Gauss–Newton estimator (backend "newton").
///
/// # Example
/// ```
/// use softrod::estimate::{Estimator, EstimatorSettings, NewtonEstimator, Observation};
/// use softrod::{scene::Scene, statics::StaticSolver};
/// let scene = Scene::two_section();
/// let (robot, loads) = (scene.robot()?, scene.loads()?);
/// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
/// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[4, 8, 12, 16, 20])?.with_noise(1e-5, 1);
/// let mut est = NewtonEstimator::new(&robot, &loads, &EstimatorSettings::default())?;
/// let e = est.step(&obs)?; // α by the discrepancy principle
/// assert!(e.report.status.is_converged());
/// let again = est.step(&obs)?; // warm: converges at once
/// assert!(again.report.iterations <= 2);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct NewtonEstimator<E: Element> {
    stream: Stream<E>,
    /// The derivatives at the last converged estimate's shape for the
    /// observation rows `cache_rows`: a warm step's first iteration starts
    /// there.
    derivs_cache: Option<DerivsCache>,
    /// The observation rows of `derivs_cache` (kept between steps: a
    /// stream's frames share them).
    cache_rows: Vec<ObsRow>,
    /// The last estimate `F` and `H F` there: a warm step's first
    /// objective starts at that `F`.
    hf_cache: Option<(Vec<f64>, Vec<f64>)>,
    /// The full-space iterations of a far start (made when first needed;
    /// see [`full_space`]).
    full_space: Option<Box<SqpEstimator<E>>>,
}

impl<E: Element> NewtonEstimator<E> {
    /// An estimator for `robot` under the known loads `known` (both
    /// borrowed; the estimator keeps copies). `settings.backend` must be
    /// [`super::Backend::Newton`]: the backend is chosen once, by the
    /// settings ([`EstimatorSettings::build_for`] builds the one they name).
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for invalid settings, another
    /// backend (`estimator.backend`) or bounds (bounds need the SQP
    /// backend); the errors of [`Robot::validate_loads`].
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{Backend, EstimatorSettings, NewtonEstimator};
    /// use softrod::scene::Scene;
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let est = NewtonEstimator::new(&robot, &loads, &EstimatorSettings::default())?;
    /// assert_eq!(est.robot().n_q(), robot.n_q());
    /// let sqp = EstimatorSettings { backend: Backend::Sqp, ..Default::default() };
    /// let err = NewtonEstimator::new(&robot, &loads, &sqp).unwrap_err();
    /// assert_eq!(err.field(), Some("estimator.backend"));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn new(robot: &Robot<E>, known: &Loads, settings: &EstimatorSettings) -> Result<Self> {
        if settings.backend != super::Backend::Newton {
            return Err(crate::Error::invalid(
                "estimator.backend",
                settings.backend.name(),
                "NewtonEstimator runs the newton backend (build the one the settings name with EstimatorSettings::build_for)",
            ));
        }
        if !settings.bounds.is_empty() {
            return Err(crate::Error::invalid(
                "estimator.bounds",
                settings.bounds.len(),
                "bounds on the load need the sqp backend",
            ));
        }
        Ok(NewtonEstimator {
            stream: Stream::new(Problem::new(
                robot.clone(),
                known.clone(),
                settings.clone(),
            )?),
            derivs_cache: None,
            cache_rows: Vec::new(),
            hf_cache: None,
            full_space: None,
        })
    }

    /// The robot.
    pub fn robot(&self) -> &Robot<E> {
        self.stream.problem.robot()
    }

    /// Objective `J(F)` and reduced gradient (29) at `F` for `observation`
    /// (static solve from the warm shape), for checks and for users who
    /// drive their own optimizer.
    ///
    /// # Errors
    /// As [`Estimator::step`].
    pub fn objective_and_gradient(
        &mut self,
        observation: &Observation,
        f: &[f64],
        alpha: f64,
    ) -> Result<(f64, DVector<f64>)> {
        let (q, lu, op) = self.equilibrium_at(observation, f)?;
        let problem = &self.stream.problem;
        let (wr, pen, e) = problem.objective(&op, &q, f, alpha)?;
        let dv = problem.derivs(&lu, &op)?;
        let g = problem.gradient(&dv, &op, &e, f, alpha)?;
        Ok((wr + pen, DVector::from_vec(g)))
    }

    /// The observed quantities `A q(F)` and the marker Jacobian
    /// `∂(A q)/∂F` (`n_ob × n_F`) at `F`.
    ///
    /// # Errors
    /// As [`Estimator::step`].
    pub fn markers_and_jacobian(
        &mut self,
        observation: &Observation,
        f: &[f64],
    ) -> Result<(DVector<f64>, DMatrix<f64>)> {
        let (q, lu, op) = self.equilibrium_at(observation, f)?;
        let dv = self.stream.problem.derivs(&lu, &op)?;
        Ok((DVector::from_vec(op.apply(&q)), dv.jt.transpose()))
    }

    /// The equilibrium at `F` from the warm shape, the tangent's factors
    /// there and the observation operator.
    fn equilibrium_at(
        &mut self,
        observation: &Observation,
        f: &[f64],
    ) -> Result<(Vec<f64>, AutoFactors, ObservationOperator)> {
        let op = self.stream.problem.operator(observation)?;
        crate::error::check_len("f", self.stream.problem.n_f(), f.len())?;
        let (_, q0) = self.stream.start()?;
        let problem = &mut self.stream.problem;
        let eq = problem.equilibrium(f, &q0)?;
        let lu = problem.factor_tangent(eq.q.as_slice())?.factors;
        Ok((eq.q.data.into(), lu, op))
    }
}

impl<E: Element> Method<E> for NewtonEstimator<E> {
    const BACKEND: Backend = Backend::Newton;

    fn stream(&mut self) -> &mut Stream<E> {
        &mut self.stream
    }

    fn solve_one(
        &mut self,
        op: &ObservationOperator,
        f0: Vec<f64>,
        q0: Vec<f64>,
        alpha: f64,
    ) -> Result<Solved> {
        // the far start only while the stream has no estimate (a cold
        // first estimate, its α search); a solve through it that ends
        // short of convergence is repeated without it
        // (a stream under a load its model cannot explain: a warm step
        // through the far start stalled in every frame of a closed loop)
        if self.stream.warm.is_some() {
            return self.solve_reduced(op, f0, q0, alpha, None);
        }
        let mut used = false;
        let r = self.solve_reduced(op, f0.clone(), q0.clone(), alpha, Some(&mut used));
        match r {
            Ok(s) if s.report.status.is_converged() || !used => Ok(s),
            Err(e) if !used => Err(e),
            _ => self.solve_reduced(op, f0, q0, alpha, None),
        }
    }
}

impl<E: Element> NewtonEstimator<E> {
    /// The reduced iteration from `(f0, q0)` at `alpha`; with `far`, a far
    /// start may continue with the full-space iterations (`far` is then
    /// set when it did).
    fn solve_reduced(
        &mut self,
        op: &ObservationOperator,
        f0: Vec<f64>,
        q0: Vec<f64>,
        alpha: f64,
        mut far: Option<&mut bool>,
    ) -> Result<Solved> {
        let NewtonEstimator {
            stream,
            derivs_cache,
            cache_rows,
            hf_cache,
            full_space: inner,
        } = self;
        let core = &mut stream.problem;
        let settings = core.settings().clone();
        let mut f = f0;
        let eq = core.equilibrium(&f, &q0)?;
        let (mut q, mut lu, mut res_n): (Vec<f64>, _, _) =
            (eq.q.data.into(), eq.factors, eq.residual_n);
        let n_ob = op.len() as f64;
        let kappa2 = settings.statistical_tolerance.powi(2);
        let mut iterations = 0;
        let mut prev_dec = f64::INFINITY;
        // the objective at the accepted trial point, which the next
        // iteration starts from
        let mut at_trial: Option<(f64, f64, Vec<f64>, Vec<f64>)> = None;
        let mut eager = far.is_some() && f.iter().all(|v| *v == 0.0);
        loop {
            // (with `H F`, for the gradient)
            let (wr, pen, e, hf) = match at_trial.take() {
                Some(x) => x,
                None => match hf_cache.take() {
                    Some((fc, hf)) if fc == f => {
                        let (wr, pen, e) = core.objective_with_hf(op, q.as_slice(), &f, &hf, alpha);
                        (wr, pen, e, hf)
                    }
                    _ => core.objective_hf(op, q.as_slice(), &f, alpha)?,
                },
            };
            let obj = wr + pen;
            // a cold solve from zero load (a stream's first, from the
            // unloaded shape) takes the far start at once: its first
            // linearization would only measure how far the start is
            if eager {
                eager = false;
                if let Some(used) = far.take() {
                    let fs = far_start(
                        inner,
                        derivs_cache,
                        cache_rows,
                        core,
                        op,
                        &f,
                        &q,
                        alpha,
                        obj,
                    )?;
                    if let Some((fs, eq, its)) = fs {
                        *used = true;
                        iterations += its;
                        f = fs;
                        q = eq.q.data.into();
                        lu = eq.factors;
                        res_n = eq.residual_n;
                        continue;
                    }
                }
            }
            // (a warm step starts where the last one converged: the
            // derivatives there are cached)
            // (with the Gauss–Newton factor formed there, for the same
            // weights: the same numbers)
            let cached = match derivs_cache.take() {
                Some((qc, dv, gn)) if qc == q && cache_rows[..] == *op.rows() => {
                    let gn = gn.and_then(|(w, fac)| (w[..] == *op.weights()).then_some(fac));
                    Some((dv, gn))
                }
                _ => None,
            };
            let (dv, gn) = match cached {
                Some(x) => x,
                None => (core.derivs(&lu, op)?, None),
            };
            let g = core.gradient_hf(&dv, op, &e, &hf, alpha)?;
            // the step (the covariances are formed on request, from `fac`)
            let (mut step, fac) = core.gn_solve_reusing(&dv, op, &e, &f, alpha, gn)?;
            let dec = -0.5 * dot(&g, &step);
            let scale = obj.max(n_ob);
            // the statistical test: dec = dFᵀ N dF ≤ κ² (see
            // EstimatorSettings::statistical_tolerance)
            let within_noise = dec <= kappa2;
            // the threshold the successor's predicted decrease is held to
            let threshold = (settings.tolerance * scale).max(kappa2);
            let report = |status: EstimateStatus, iterations: usize| EstimateReport {
                backend: Backend::Newton,
                status,
                iterations,
                sub_steps: 1,
                objective: obj,
                weighted_residual: wr,
                n_observations: op.len(),
                gradient_norm: norm2(&g),
                equilibrium_residual_n: res_n,
                alpha,
                wall_time_s: 0.0,
                linear_work: Default::default(),
            };
            // converged: predicted decrease below tolerance, or at the
            // round-off floor (tiny and no longer shrinking)
            let floor = dec <= 1e-13 * scale && dec > 0.9 * prev_dec;
            let criterion = if dec <= settings.tolerance * scale {
                Some(EstimateCriterion::PredictedDecrease)
            } else if within_noise {
                Some(EstimateCriterion::WithinNoise)
            } else if floor {
                Some(EstimateCriterion::RoundOffFloor)
            } else if !dec.is_finite() && dot(&g, &step) == 0.0 {
                Some(EstimateCriterion::Stationary)
            } else {
                None
            };
            if let Some(criterion) = criterion {
                if cache_rows[..] != *op.rows() {
                    *cache_rows = op.rows().to_vec();
                }
                *derivs_cache = Some((
                    q.clone(),
                    dv.clone(),
                    Some((op.weights().to_vec(), fac.clone())),
                ));
                *hf_cache = Some((f.clone(), hf));
                return Ok(Solved {
                    f,
                    q,
                    derivs: dv,
                    gn: Some(fac),
                    e,
                    report: report(EstimateStatus::Converged(criterion), iterations),
                });
            }
            if iterations >= settings.max_iterations {
                return Ok(Solved {
                    f,
                    q,
                    derivs: dv,
                    gn: Some(fac),
                    e,
                    report: report(EstimateStatus::IterationLimit { iterations }, iterations),
                });
            }
            // trust region (after the convergence tests: a converged
            // iterate takes no step): the predicted motion of every node,
            // M K⁻¹ Mᵀ G dF (one more solve), within max_observation_jump_m
            let mut dq: Vec<f64> = Sensitivity::new(core.robot(), &lu)?
                .response(&core.gen_force(&step)?)?
                .data
                .into();
            let nd = E::NODE_DOFS;
            let moved = dq
                .iter()
                .enumerate()
                .filter(|(i, _)| i % nd < E::DIM)
                .fold(0.0f64, |m, (_, v)| m.max(v.abs()));
            let cap = if moved > settings.max_observation_jump_m && moved.is_finite() {
                settings.max_observation_jump_m / moved
            } else {
                step_cap(&dv, &step, settings.max_observation_jump_m)
            };
            step.iter_mut().for_each(|v| *v *= cap);
            dq.iter_mut().for_each(|v| *v *= cap);
            let slope = dot(&g, &step);
            // The last step: when the decrease predicted after this step
            // (convergence at least quadratic, dec²/dec_prev, with a margin
            // of 1000) is far below the tolerance, the step is taken without
            // a further linearization to confirm it. The estimate is the
            // iterate that confirmation would accept; it saves a
            // factorization, the adjoint solves and a Gauss–Newton system.
            // The covariances and the gradient norm are this linearization's.
            let last = prev_dec.is_finite()
                && cap == 1.0
                && dec <= 1e-8 * scale
                && dec * dec <= 1e-3 * threshold * prev_dec;
            iterations += 1;
            prev_dec = dec;
            if last {
                let ft: Vec<f64> = f.iter().zip(&step).map(|(a, b)| a + b).collect();
                let load = core.load();
                if let Some((qt, res_t)) = core.tracker().solve_chord(&load, &ft, q.as_slice())? {
                    let (wr_t, pen_t, e_t) = core.objective(op, qt.as_slice(), &ft, alpha)?;
                    let mut rep = report(
                        EstimateStatus::Converged(EstimateCriterion::UnconfirmedLastStep),
                        iterations,
                    );
                    rep.objective = wr_t + pen_t;
                    rep.weighted_residual = wr_t;
                    rep.equilibrium_residual_n = res_t;
                    return Ok(Solved {
                        f: ft,
                        q: qt.data.into(),
                        derivs: dv,
                        gn: Some(fac),
                        e: e_t,
                        report: rep,
                    });
                }
            }
            // Armijo backtracking; tiny predicted decreases take the full
            // step (the objective's round-off would hide the decrease)
            let mut t = 1.0;
            let mut accepted = None;
            // a far start (the trust region cuts the step of a cold
            // solve): the full-space iterations take over (see
            // `full_space`), once per solve
            if cap < 1.0 {
                if let Some(used) = far.take() {
                    let fs = far_start(
                        inner,
                        derivs_cache,
                        cache_rows,
                        core,
                        op,
                        &f,
                        &q,
                        alpha,
                        obj,
                    )?;
                    if let Some((fs, eq, its)) = fs {
                        *used = true;
                        iterations += its;
                        accepted = Some((fs, eq, None));
                    }
                }
            }
            for _ in 0..30 {
                if accepted.is_some() {
                    break;
                }
                let ft: Vec<f64> = f.iter().zip(&step).map(|(a, b)| a + t * b).collect();
                // the trial's equilibrium starts from the linearized
                // prediction q + t dq (a predictor–corrector step, as the
                // sqp backend's full-space step): the corrector's chord
                // steps then only remove the second-order error. From q
                // itself they had to cover the whole step and failed on
                // large ones, which fell through to the globalized static
                // solve (10–100× the cost of a first estimate).
                let qp: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a + t * b).collect();
                // a trial without the globalized fallback unless the step is
                // already short: cheap
                let trial = if t < 0.01 {
                    core.equilibrium(&ft, &qp).ok()
                } else {
                    let load = core.load();
                    core.tracker().try_solve(&load, &ft, &qp).ok().flatten()
                };
                if let Some(eq) = trial {
                    let (wr_t, pen_t, e_t, hf_t) =
                        core.objective_hf(op, eq.q.as_slice(), &ft, alpha)?;
                    if wr_t + pen_t <= obj + 1e-4 * t * slope || dec <= 1e-8 * scale {
                        accepted = Some((ft, eq, Some((wr_t, pen_t, e_t, hf_t))));
                        break;
                    }
                }
                t *= 0.5;
            }
            match accepted {
                Some((ft, eq, objective)) => {
                    at_trial = objective;
                    f = ft;
                    q = eq.q.data.into();
                    lu = eq.factors;
                    res_n = eq.residual_n;
                }
                None => {
                    return Ok(Solved {
                        f,
                        q,
                        derivs: dv,
                        gn: Some(fac),
                        e,
                        report: report(
                            if dec <= 1e-6 * scale {
                                EstimateStatus::Converged(EstimateCriterion::NegligibleDecrease)
                            } else {
                                EstimateStatus::LineSearchFailed
                            },
                            iterations,
                        ),
                    });
                }
            }
        }
    }
}

impl<E: Element + 'static> Estimator for NewtonEstimator<E> {
    fn step(&mut self, observation: &Observation) -> Result<Estimate> {
        run_step(self, observation)
    }

    fn backend(&self) -> Backend {
        Backend::Newton
    }

    fn alpha(&self) -> Option<f64> {
        self.stream.alpha
    }

    fn reset(&mut self) {
        self.stream.reset();
        self.derivs_cache = None;
        self.hf_cache = None;
        self.full_space = None;
    }

    fn set_known_loads(&mut self, known: Loads) -> Result<()> {
        self.stream.problem.set_known(known)?;
        self.derivs_cache = None;
        self.full_space = None;
        Ok(())
    }
}

/// The far start from `(f, q)` (objective `obj`): the full-space
/// iterations ([`full_space`]) and the equilibrium at their estimate,
/// with the iterations they took; `None` if they did not converge below
/// `obj` or the equilibrium failed. Their last factored tangent is kept in
/// the tracker (the equilibrium there is then a chord step without a
/// factorization) and their derivatives cached for the next iteration, at
/// the equilibrium's shape when that stayed within `1e-10 L` of theirs
/// (the tracker then returns the same factors, from which the derivatives
/// are the same numbers).
#[allow(clippy::too_many_arguments)]
fn far_start<E: Element>(
    inner: &mut Option<Box<SqpEstimator<E>>>,
    derivs_cache: &mut Option<DerivsCache>,
    cache_rows: &mut Vec<ObsRow>,
    core: &mut Problem<E>,
    op: &ObservationOperator,
    f: &[f64],
    q: &[f64],
    alpha: f64,
    obj: f64,
) -> Result<Option<(Vec<f64>, crate::statics::TrackedEquilibrium, usize)>> {
    let Some((fs, qs, its, last)) = full_space(inner, core, op, f, q, alpha, obj) else {
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
        let tol = 1e-10 * core.robot().length();
        if eq.q.iter().zip(&qs).all(|(a, b)| (a - b).abs() <= tol) {
            *cache_rows = op.rows().to_vec();
            *derivs_cache = Some((eq.q.as_slice().to_vec(), dv, None));
        }
    }
    Ok(Some((fs, eq, its)))
}

/// The full-space iterations of a far start: from `(f, q)`, an
/// equilibrium, the estimate at `alpha` for `op` by the sqp backend's
/// iterations over `(q, F)`, whose iterates need not be equilibria; made
/// over a copy of the problem (its analyzed linear solver, its unloaded
/// start) the first time it is needed, kept in `inner`. Its converged
/// estimate, an equilibrium, with the iterations it took and its last
/// QP's factored tangent and derivatives when taken there (the reduced
/// iteration resumes from them without a factorization or adjoint solves),
/// if it converged below the objective `obj` at `(f, q)`; `None` otherwise
/// (the reduced iteration then backtracks on its own).
///
/// It is taken as soon as the trust region cuts a step of a cold solve,
/// without trying the reduced step's equilibrium first: that trial (chord
/// and plain Newton steps from the linearized prediction) failed on every
/// large deflection measured and cost factorizations of its own.
///
/// Why: far from the solution (the first estimate of a large deflection,
/// from the unloaded shape) a step of the reduced method needs the
/// equilibrium at every trial load. A full trust-region step (2 cm of
/// predicted node motion) leaves its linearized prediction off the
/// equilibrium by second-order terms (1.9 N on the 0.24 m exudyn cable
/// under 3 × its self-weight) from which plain Newton steps diverge, so
/// the line search halved down to 1/16 of the step, 1–2 mm of motion, and
/// each accepted trial converged a static solve of 4–6 factorizations: 19
/// iterations and 213 factorizations where the full-space iterations,
/// which restore the equilibrium in the same linear solve as the step,
/// take 7 iterations of one factorization each.
fn full_space<E: Element>(
    inner: &mut Option<Box<SqpEstimator<E>>>,
    core: &Problem<E>,
    op: &ObservationOperator,
    f: &[f64],
    q: &[f64],
    alpha: f64,
    obj: f64,
) -> Option<FullSpace> {
    if inner.is_none() {
        // the same problem (its analysis, its unloaded start)
        *inner = Some(Box::new(SqpEstimator::over(core.clone()).ok()?));
    }
    let sqp = inner.as_mut()?;
    let s = sqp.solve_one(op, f.to_vec(), q.to_vec(), alpha).ok()?;
    if !(s.report.status.is_converged() && s.report.objective < obj) {
        return None;
    }
    let last = sqp.take_final_qp(&s.q, op);
    Some((s.f, s.q, s.report.iterations, last))
}

/// A converged run of the full-space iterations: the load, the shape, the
/// iterations, and the last QP's factored tangent and derivatives when they
/// were taken at that shape.
type FullSpace = (
    Vec<f64>,
    Vec<f64>,
    usize,
    Option<(crate::statics::tracker::FactoredTangent, Derivs)>,
);

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use crate::assembly::{Base, Clamp, RobotSpec, Section};
    use crate::element::PlanarCable;
    use crate::loads::LineLoad;
    use crate::observe::MarkerObservation;
    use crate::statics::StaticSolver;

    /// 5 markers (0.01 mm noise) on the 0.24 m cable (20 elements, clamped)
    /// under a uniform load of `w` N/m, and the cable.
    fn frame(w: f64) -> (Robot<PlanarCable>, Observation) {
        let sections = (0..2)
            .map(|_| Section::uniform(0.12, 300.0, 0.025, 10))
            .collect();
        let mut spec = RobotSpec::new(sections);
        spec.base = Base {
            clamp: Clamp::Full,
            ..Base::default()
        };
        let robot = spec.build_planar().unwrap();
        let mut loads = Loads::default();
        let mut q = StaticSolver::default()
            .solve(&robot, &loads, None)
            .unwrap()
            .q;
        for k in 1..=8 {
            loads.line_loads = vec![LineLoad::Uniform {
                w_n_per_m: vec![0.0, w * f64::from(k) / 8.0],
            }];
            q = StaticSolver::default()
                .solve(&robot, &loads, Some(q.as_slice()))
                .unwrap()
                .q;
        }
        let markers = (1..=5)
            .map(|k| {
                let s = 0.24 * f64::from(k) / 5.0;
                let p = robot.position_at(q.as_slice(), s).unwrap();
                MarkerObservation::at_arc(s, p)
            })
            .collect();
        (robot, Observation { markers }.with_noise(1e-5, 3))
    }

    /// The far start serves the cold first estimate of a large deflection
    /// (3 × the cable's self-weight) and never a warm step, even one that
    /// jumps to a load three times larger: a stream whose frames its model
    /// cannot follow keeps the reduced iteration of the steps before.
    #[test]
    fn only_a_cold_estimate_takes_the_far_start() {
        let (robot, first) = frame(-4.4);
        let (_, far) = frame(-13.2);
        let mut est =
            NewtonEstimator::new(&robot, &Loads::default(), &EstimatorSettings::default()).unwrap();
        let e = est.step(&first).unwrap();
        assert!(e.report.status.is_converged(), "{}", e.report);
        assert!(
            est.full_space.is_some(),
            "the cold estimate took no far start"
        );
        est.full_space = None;
        let e = est.step(&far).unwrap();
        assert!(e.report.status.is_converged(), "{}", e.report);
        assert!(est.full_space.is_none(), "a warm step took the far start");
    }
}
