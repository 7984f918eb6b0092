//! Predictor–corrector continuation in the load, the static solver's
//! globalization.
//!
//! The path `H(u, λ) = R(u; λ loads) − (1 − λ) R(u_0; no loads) = 0` goes
//! from the start point (exact at `λ = 0`; a cold solve starts from the
//! unloaded reference, where the offset vanishes) to the full load at
//! `λ = 1`. Each load step predicts along the path's tangent
//! `du/dλ = K⁻¹ ∂H/∂λ` (the loads enter linearly:
//! `∂H/∂λ = R(u; 1) − R(u; 0) + R(u_0; 0)`; `K` from the factors the last
//! corrector iteration left, no extra factorization), with a second-order
//! term from the change of the tangent over the last step, and corrects
//! with plain Newton iterations (17). The step length follows two measured
//! quantities: the rotation the predictor makes (at most
//! [`PREDICTOR_ROTATION`] rad on any node slope) and the corrector's first
//! contraction `θ` (the next step is `√(θ_target/θ)` times this one, between
//! a quarter and twice; a corrector that does not contract cuts the step).
//! The path is followed on its stable side: a step from a stable point
//! (positive definite tangent) that lands on an unstable one (a negative
//! `L D Lᵀ` pivot of the corrector's last tangent) stepped over a
//! bifurcation, such as a column's buckling load, where the straight column
//! goes on as a saddle while the stable path bends away. The saddle is left
//! at that load along its direction of most negative curvature by a descent
//! Newton run ([`super::stability`]), toward the side the path's tangent at
//! its last stable point leans to (the branch connected to the unloaded
//! state; reported as a [`StaticWarning::Bifurcation`]), and the path goes
//! on from the stable equilibrium it reaches; only if that fails is the step
//! halved. (Measured
//! on a column under `q L³/EI = 12`: halving until the path bends onto the
//! stable branch took 22 load steps, 100–110 iterations at every mesh; the
//! escape at the saddle 2 steps, 41 iterations at 8 elements, 45 at 32.)
//!
//! Why not natural continuation with a line search on the potential (the
//! solver before): on a fine mesh the first Newton step of a large rotation
//! stretches the node slopes `r'`; the line search accepts it because the
//! potential drops while the residual grows by three orders of magnitude,
//! and the iterates wander (measured: 385 iterations for a tip moment
//! bending the rod by 110° at 512 elements, no convergence of a full circle
//! at 2000). Why not a trust region on the potential: it shares that
//! acceptance test. The predictor moves along the path instead, the plain
//! corrector either contracts or the step is cut, and the iteration count
//! follows the rotation of the solution more than the mesh (the README's
//! iteration table). What still grows with the mesh: a concentrated moment
//! acts on one node slope, whose stretch is held only by `EA L_e` (soft on
//! a fine mesh), so near the loaded node the corrector contracts slowly.

use super::StaticSolver;
use super::newton::{Target, Work};
use crate::error::Result;
use crate::linsolve::{AutoFactors, FactorOptions, Factorization, LinsolveError, TangentSolver};
use crate::numeric::norm2;
use crate::outcome::{NonFiniteAt, StaticStatus, StaticWarning};
use crate::structure::{Model, ModelLoads};

/// Largest rotation of a node slope a predictor may make (rad).
pub(super) const PREDICTOR_ROTATION: f64 = 1.0;
/// A load step is solved once the corrector's error estimate (its last
/// step times its contraction) is below this (rad). Measured: 1e-4 left
/// stiff axial errors that made the next corrector contract slowly on fine
/// meshes (tip force at 512 elements: 42 iterations; at 1e-9: 14).
const CORRECTOR_TOLERANCE: f64 = 1e-9;
/// After [`LENIENT`] iterations, a corrector whose step does not shrink by
/// this factor has left the path's neighbourhood: the load step is cut.
const CONTRACTION: f64 = 0.9;
/// The corrector's first iterations may grow (a predictor off the path by
/// a stiff stretch first relaxes it), as long as no step turns a slope by
/// more than [`PREDICTOR_ROTATION`].
const LENIENT: usize = 3;
/// The corrector's first contraction the step length aims at.
const TARGET_CONTRACTION: f64 = 0.5;
/// Corrector iterations per load step before it is cut.
const CORRECTOR_ITERATIONS: usize = 8;

/// What a continuation ended with.
pub(super) struct PathEnd {
    /// Reached `λ = 1` (the caller polishes) or why not.
    pub status: Option<StaticStatus>,
    /// Load steps taken.
    pub load_steps: usize,
    /// The critical points passed, and how each branch was chosen
    /// ([`StaticWarning::Bifurcation`]).
    pub warnings: Vec<StaticWarning>,
}

/// A continuation's state along its path.
struct Path<M: Model> {
    /// `R(u_0; no loads)`: the homotopy's offset at `λ = 0`.
    r0: Vec<f64>,
    /// The loads at `λ = 0` and `n_q` zeros (no dead forces).
    unloaded: M::Loads,
    zero_dead: Vec<f64>,
    /// The load factor of the path's last point.
    lambda: f64,
    /// The next load step.
    delta: f64,
    /// The factors of the last corrector's tangent (the next path
    /// tangent's, no extra factorization).
    factors: Option<AutoFactors>,
    /// The path's tangent `du/dλ` at its last point, and the rotation per
    /// unit `λ` it makes.
    tangent: Option<(Vec<f64>, f64)>,
    /// The tangent at the point before and the load step between them.
    previous_tangent: Option<(Vec<f64>, f64)>,
    load_steps: usize,
    /// Whether the path's last point was a stable equilibrium.
    stable: bool,
    warnings: Vec<StaticWarning>,
    /// Residual buffers of the path tangent.
    r1: Vec<f64>,
    rz: Vec<f64>,
}

impl<M: Model> Path<M> {
    /// The continuation's end with `status` (`None`: `λ = 1` reached).
    fn end(self, status: Option<StaticStatus>) -> PathEnd {
        PathEnd {
            status,
            load_steps: self.load_steps,
            warnings: self.warnings,
        }
    }
}

/// What a load step ended with ([`StaticSolver::path_step`]).
enum Step {
    /// On to the next load step (taken, or cut).
    Next,
    /// `λ = 1` reached.
    Reached,
    /// The path ends with this status.
    Stop(StaticStatus),
}

impl StaticSolver {
    /// Follows the path from `u` (the start, `w.q = φ(u)`) to `λ = 1`; on
    /// success `u` is near the full load's equilibrium (the caller
    /// polishes it with [`StaticSolver::newton`]). Conservative loads only:
    /// the caller sends non-conservative ones to the homotopy, so every
    /// tangent here is a potential's and its inertia tells stability. Each
    /// load step in its phases: the path tangent ([`Self::path_tangent`]),
    /// the predictor ([`Self::predict`]), the corrector
    /// ([`Self::corrector`]), the step taken or cut ([`Self::path_step`],
    /// which leaves a saddle the step landed on, [`Self::leave_saddle`]).
    pub(super) fn continuation<M: Model>(
        &self,
        model: &M,
        dead: &[f64],
        loads: &M::Loads,
        u: &mut [f64],
        w: &mut Work<'_>,
        scale: f64,
    ) -> Result<PathEnd> {
        let n = model.n_free();
        let nq = model.n_q();
        let zero_dead = vec![0.0; nq];
        let unloaded = loads.scaled(0.0);
        let mut r0 = vec![0.0; n];
        model.residual_into(u, &w.q, &zero_dead, &unloaded, &mut r0)?;
        let mut path = Path::<M> {
            r0,
            unloaded,
            zero_dead,
            lambda: 0.0,
            delta: 1.0,
            factors: None,
            tangent: None,
            previous_tangent: None,
            load_steps: 0,
            stable: false,
            warnings: Vec::new(),
            r1: vec![0.0; n],
            rz: vec![0.0; n],
        };
        let mut dq = vec![0.0; nq];
        let (mut u_try, mut q_try) = (u.to_vec(), w.q.clone());
        loop {
            if w.iterations >= self.settings.max_total_iterations {
                let status = StaticStatus::IterationLimit {
                    iterations: w.iterations,
                };
                return Ok(path.end(Some(status)));
            }
            if path.tangent.is_none()
                && let Some(status) =
                    self.path_tangent(model, dead, loads, u, w, &mut path, &mut dq)?
            {
                return Ok(path.end(Some(status)));
            }
            let target = self.predict(model, u, w, &mut path, &mut dq, &mut u_try, &mut q_try)?;
            let off: Vec<f64> = path.r0.iter().map(|v| (1.0 - target) * v).collect();
            let dead_t: Vec<f64> = dead.iter().map(|v| target * v).collect();
            let loads_t = loads.scaled(target);
            let tgt = Target::<M> {
                dead: &dead_t,
                loads: &loads_t,
                offset: &off,
                strict: false,
                descent: false,
                definite_only: false,
                full: false,
            };
            let corrected = self.corrector(model, &tgt, &mut u_try, &mut q_try, w)?;
            let trial = (&mut u_try[..], &mut q_try[..]);
            match self.path_step(
                model, &tgt, target, corrected, u, trial, w, &mut path, scale,
            )? {
                Step::Next => {}
                Step::Reached => return Ok(path.end(None)),
                Step::Stop(status) => return Ok(path.end(Some(status))),
            }
        }
    }

    /// The path's tangent at `(u, λ)` into `path.tangent`:
    /// `dH/dλ = R(u; 1) − R(u; 0) + r0` solved with the last corrector's
    /// factors, or with the tangent factored here (a new path start: its
    /// definiteness says whether the path starts on its stable side).
    /// `Some(status)` when it cannot be had.
    #[allow(clippy::too_many_arguments)]
    fn path_tangent<M: Model>(
        &self,
        model: &M,
        dead: &[f64],
        loads: &M::Loads,
        u: &[f64],
        w: &mut Work<'_>,
        path: &mut Path<M>,
        dq: &mut [f64],
    ) -> Result<Option<StaticStatus>> {
        let f = match path.factors.take() {
            Some(f) => f,
            None => {
                let dead_l: Vec<f64> = dead.iter().map(|v| path.lambda * v).collect();
                let loads_l = loads.scaled(path.lambda);
                model.tangent_into(u, &w.q, &dead_l, &loads_l, &mut w.k)?;
                w.iterations += 1;
                match factor(w) {
                    Ok(f) => {
                        // the path is followed on its stable side when it
                        // starts there
                        path.stable = f.is_positive_definite();
                        f
                    }
                    Err(status) => return Ok(Some(status)),
                }
            }
        };
        model.residual_into(u, &w.q, dead, loads, &mut path.r1)?;
        model.residual_into(u, &w.q, &path.zero_dead, &path.unloaded, &mut path.rz)?;
        let mut t: Vec<f64> = (path.r1.iter())
            .zip(&path.rz)
            .zip(&path.r0)
            .map(|((a, b), c)| a - b + c)
            .collect();
        f.solve_in_place(&mut t)?;
        if !t.iter().all(|v| v.is_finite()) {
            return Ok(Some(StaticStatus::NonFinite {
                at: NonFiniteAt::Tangent,
            }));
        }
        model.step_into(u, &t, dq)?;
        let rate = step_size(model, dq);
        path.tangent = Some((t, rate));
        Ok(None)
    }

    /// The predictor: the next load factor (the step bounded by the
    /// rotation the predictor makes), returned, and the predicted point in
    /// `u_try`, `q_try`: along the path tangent, second order when the last
    /// step's tangent is known (the tangent's change over that step
    /// estimates d²u/dλ², a turning slope's inward pull, which a straight
    /// predictor misses).
    #[allow(clippy::too_many_arguments)]
    fn predict<M: Model>(
        &self,
        model: &M,
        u: &[f64],
        w: &Work<'_>,
        path: &mut Path<M>,
        dq: &mut [f64],
        u_try: &mut [f64],
        q_try: &mut [f64],
    ) -> Result<f64> {
        let (t, rate) = match path.tangent.as_ref() {
            Some((t, rate)) => (t, *rate),
            // (set by the caller before)
            None => return Ok(path.lambda),
        };
        if rate * path.delta > PREDICTOR_ROTATION {
            path.delta = PREDICTOR_ROTATION / rate;
        }
        let target = (path.lambda + path.delta).min(1.0);
        let h = target - path.lambda;
        let mut step: Vec<f64> = t.clone();
        if let Some((t_prev, dl)) = path.previous_tangent.as_ref() {
            step.iter_mut()
                .zip(t.iter().zip(t_prev))
                .for_each(|(s, (a, b))| *s += 0.5 * h * (a - b) / dl);
        }
        model.step_into(u, &step, dq)?;
        model.advance_into(u, &w.q, &step, dq, h, u_try, q_try)?;
        Ok(target)
    }

    /// The load step to `target` after its corrector: taken (the path
    /// moves to the corrected point `trial`, the next step from the
    /// corrector's contraction), or, from a stable point to an unstable one
    /// (a bifurcation stepped over: a column's buckling load, where the
    /// straight column goes on as a saddle while the path bends away), the
    /// saddle left for the stable branch ([`Self::leave_saddle`]), or cut.
    #[allow(clippy::too_many_arguments)]
    fn path_step<M: Model>(
        &self,
        model: &M,
        tgt: &Target<'_, M>,
        target: f64,
        corrected: Corrected,
        u: &mut [f64],
        (u_try, q_try): (&mut [f64], &mut [f64]),
        w: &mut Work<'_>,
        path: &mut Path<M>,
        scale: f64,
    ) -> Result<Step> {
        let h = target - path.lambda;
        match corrected {
            Corrected::Done { factors: f, .. } if path.stable && !f.is_positive_definite() => {
                if self.leave_saddle(model, tgt, target, u, (u_try, q_try), w, path, scale)? {
                    return Ok(if path.lambda >= 1.0 {
                        Step::Reached
                    } else {
                        Step::Next
                    });
                }
                u_try.copy_from_slice(u);
                q_try.copy_from_slice(&w.q);
                path.delta = 0.5 * h;
                if path.delta < self.settings.min_load_step {
                    return Ok(Step::Stop(StaticStatus::LoadStepTooSmall {
                        load_fraction: path.lambda,
                    }));
                }
                Ok(Step::Next)
            }
            Corrected::Done {
                factors: f,
                contraction,
            } => {
                path.stable = f.is_positive_definite();
                path.load_steps += 1;
                path.lambda = target;
                u.copy_from_slice(u_try);
                w.q.copy_from_slice(q_try);
                if path.lambda >= 1.0 {
                    return Ok(Step::Reached);
                }
                path.factors = Some(*f);
                path.previous_tangent = path.tangent.take().map(|(t, _)| (t, h));
                path.delta = h * step_factor(contraction);
                Ok(Step::Next)
            }
            Corrected::Failed(Some(status), _) => Ok(Step::Stop(status)),
            Corrected::Failed(None, contraction) => {
                u_try.copy_from_slice(u);
                q_try.copy_from_slice(&w.q);
                path.delta = h * step_factor(contraction).min(0.5);
                if path.delta < self.settings.min_load_step {
                    return Ok(Step::Stop(StaticStatus::LoadStepTooSmall {
                        load_fraction: path.lambda,
                    }));
                }
                Ok(Step::Next)
            }
        }
    }

    /// Leaves the saddle `trial` the load step to `target` landed on, at
    /// that load, for the stable branch ([`super::stability`]), toward the
    /// side the path's tangent at its last stable point leans to (a
    /// bifurcation warning says how the side was chosen). Only from the
    /// unloaded start, whose homotopy offset is nil (the escape's descent
    /// knows no offset). `true`: the path moved to the stable equilibrium
    /// found (`u`, `w.q`, `trial` set to it, `λ = target`); `false`: `u`,
    /// `w.q` as they were.
    #[allow(clippy::too_many_arguments)]
    fn leave_saddle<M: Model>(
        &self,
        model: &M,
        tgt: &Target<'_, M>,
        target: f64,
        u: &mut [f64],
        (u_try, q_try): (&mut [f64], &mut [f64]),
        w: &mut Work<'_>,
        path: &mut Path<M>,
        scale: f64,
    ) -> Result<bool> {
        if norm2(&path.r0) > self.settings.residual_tolerance * scale {
            return Ok(false);
        }
        let mut u_s = u_try.to_vec();
        let saved_q = std::mem::replace(&mut w.q, q_try.to_vec());
        // the path's tangent at its last stable point tells the side it
        // leans to
        let lean = path.tangent.as_ref().map(|(t, _)| t.as_slice());
        let st = self.stabilize(
            model,
            tgt.dead,
            tgt.loads,
            &mut u_s,
            w,
            scale,
            StaticStatus::Converged(crate::outcome::StaticCriterion::Residual),
            lean,
        )?;
        if !(st.status.is_converged() && st.inertia.is_some_and(|i| i.negative == 0)) {
            w.q = saved_q;
            return Ok(false);
        }
        if let Some(branch) = st.branch {
            path.warnings.push(StaticWarning::Bifurcation {
                from_load_fraction: path.lambda,
                to_load_fraction: target,
                branch,
            });
        }
        path.stable = true;
        path.load_steps += 1;
        path.lambda = target;
        u.copy_from_slice(&u_s);
        q_try.copy_from_slice(&w.q);
        u_try.copy_from_slice(u);
        path.tangent = None;
        path.previous_tangent = None;
        Ok(true)
    }

    /// Plain Newton iterations on `R(u) − offset = 0` from the predicted
    /// `u` (`q = φ(u)`), which must contract.
    fn corrector<M: Model>(
        &self,
        model: &M,
        t: &Target<'_, M>,
        u: &mut [f64],
        q: &mut [f64],
        w: &mut Work<'_>,
    ) -> Result<Corrected> {
        let mut du = vec![0.0; model.n_free()];
        let mut dq = vec![0.0; model.n_q()];
        let mut u_next = u.to_vec();
        let mut q_next = q.to_vec();
        let mut previous = f64::INFINITY;
        let mut first_contraction = 0.0;
        for k in 0..CORRECTOR_ITERATIONS {
            if w.iterations >= self.settings.max_total_iterations {
                return Ok(Corrected::Failed(
                    Some(StaticStatus::IterationLimit {
                        iterations: w.iterations,
                    }),
                    1.0,
                ));
            }
            model.residual_and_tangent_into(u, q, t.dead, t.loads, &mut w.r, &mut w.k)?;
            w.r.iter_mut().zip(t.offset).for_each(|(a, b)| *a -= b);
            if !norm2(&w.r).is_finite() {
                return Ok(Corrected::Failed(None, 1.0));
            }
            w.iterations += 1;
            let f = match factor(w) {
                Ok(f) => f,
                Err(StaticStatus::SingularTangent) => return Ok(Corrected::Failed(None, 1.0)),
                Err(status) => return Ok(Corrected::Failed(Some(status), 1.0)),
            };
            du.copy_from_slice(&w.r);
            f.solve_in_place(&mut du)?;
            model.step_into(u, &du, &mut dq)?;
            let size = step_size(model, &dq);
            let contracting = if k < LENIENT {
                size <= PREDICTOR_ROTATION
            } else {
                size <= CONTRACTION * previous
            };
            if !(size.is_finite() && contracting) {
                let theta = if k == 0 { 1.0 } else { size / previous };
                return Ok(Corrected::Failed(None, theta));
            }
            model.advance_into(u, q, &du, &dq, 1.0, &mut u_next, &mut q_next)?;
            u.copy_from_slice(&u_next);
            q.copy_from_slice(&q_next);
            w.last_step = dq.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            // Newton's error after this step is about θ × its size
            let theta = if k == 0 { 1.0 } else { size / previous };
            if k == 1 {
                first_contraction = theta;
            }
            if size * theta <= CORRECTOR_TOLERANCE || size <= f64::EPSILON {
                return Ok(Corrected::Done {
                    factors: Box::new(f),
                    contraction: first_contraction,
                });
            }
            previous = size;
        }
        Ok(Corrected::Failed(None, 1.0))
    }
}

/// The next load step over this one, from the corrector's first
/// contraction `θ`: the predictor's error grows with the step squared, and
/// Newton's first contraction with it, so `√(θ_target / θ)`, between a
/// quarter and twice.
fn step_factor(theta: f64) -> f64 {
    (TARGET_CONTRACTION / theta.max(1e-12))
        .sqrt()
        .clamp(0.25, 2.0)
}

/// A corrector's outcome.
enum Corrected {
    /// Converged; the factors of its last tangent and the contraction of
    /// its first two steps (0 if one step sufficed).
    Done {
        factors: Box<AutoFactors>,
        contraction: f64,
    },
    /// Did not contract (`None`: cut the step; the contraction seen, 1 if
    /// none) or met a hard failure.
    Failed(Option<StaticStatus>, f64),
}

/// The size of a step `dq` over all coordinates: its rotation
/// ([`Stepping::step_rotation`](crate::structure::Stepping::step_rotation); a position change over the length counted
/// too would weigh the slopes' own change `1/L` times).
fn step_size<M: Model>(model: &M, dq: &[f64]) -> f64 {
    model.step_rotation(dq)
}

/// Factors `w.k`, with a growing diagonal shift if it is singular.
fn factor(w: &mut Work<'_>) -> std::result::Result<AutoFactors, StaticStatus> {
    for mu in [0.0, 1e-10, 1e-8] {
        let options = FactorOptions {
            shift: mu,
            ..FactorOptions::default()
        };
        match w.solver.factor(&w.k, options) {
            Ok(f) => return Ok(f),
            Err(LinsolveError::Singular { .. }) => continue,
            Err(LinsolveError::NonFinite { .. }) => {
                return Err(StaticStatus::NonFinite {
                    at: NonFiniteAt::Tangent,
                });
            }
            Err(_) => return Err(StaticStatus::SingularTangent),
        }
    }
    Err(StaticStatus::SingularTangent)
}
