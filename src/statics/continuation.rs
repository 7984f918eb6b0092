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
//! Newton run ([`super::stability`]) and the path goes on from the stable
//! equilibrium it reaches; only if that fails is the step halved. (Measured
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

use super::newton::{Target, Work};
use super::StaticSolver;
use crate::error::Result;
use crate::linsolve::{AutoFactors, FactorOptions, Factorization, LinsolveError, TangentSolver};
use crate::numeric::norm2;
use crate::outcome::{NonFiniteAt, StaticStatus};
use crate::structure::Assembled;

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
}

impl StaticSolver {
    /// Follows the path from `u` (the start, `w.q = φ(u)`) to `λ = 1`; on
    /// success `u` is near the full load's equilibrium (the caller
    /// polishes it with [`StaticSolver::newton`]). Conservative loads only:
    /// the caller sends non-conservative ones to the homotopy, so every
    /// tangent here is a potential's and its inertia tells stability.
    pub(super) fn continuation<M: Assembled>(
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
        let unloaded = model.scaled_loads(loads, 0.0);
        let mut r0 = vec![0.0; n];
        model.residual_into(u, &w.q, &zero_dead, &unloaded, &mut r0)?;
        let mut lambda = 0.0;
        let mut delta: f64 = 1.0;
        let mut factors: Option<AutoFactors> = None;
        let mut tangent: Option<(Vec<f64>, f64)> = None;
        let mut previous_tangent: Option<(Vec<f64>, f64)> = None;
        let mut load_steps = 0;
        // whether the path's last point was a stable equilibrium
        let mut stable = false;
        let (mut r1, mut rz) = (vec![0.0; n], vec![0.0; n]);
        let mut dq = vec![0.0; nq];
        let (mut u_try, mut q_try) = (u.to_vec(), w.q.clone());
        loop {
            if w.iterations >= self.settings.max_total_iterations {
                return Ok(PathEnd {
                    status: Some(StaticStatus::IterationLimit {
                        iterations: w.iterations,
                    }),
                    load_steps,
                });
            }
            // the path's tangent at (u, λ): dH/dλ = R(u; 1) − R(u; 0) + r0
            if tangent.is_none() {
                let f = match factors.take() {
                    Some(f) => f,
                    None => {
                        let dead_l: Vec<f64> = dead.iter().map(|v| lambda * v).collect();
                        let loads_l = model.scaled_loads(loads, lambda);
                        model.tangent_into(u, &w.q, &dead_l, &loads_l, &mut w.k)?;
                        w.iterations += 1;
                        match factor(w) {
                            Ok(f) => {
                                // the path is followed on its stable side
                                // when it starts there
                                stable = f.is_positive_definite();
                                f
                            }
                            Err(status) => {
                                return Ok(PathEnd {
                                    status: Some(status),
                                    load_steps,
                                })
                            }
                        }
                    }
                };
                model.residual_into(u, &w.q, dead, loads, &mut r1)?;
                model.residual_into(u, &w.q, &zero_dead, &unloaded, &mut rz)?;
                let mut t: Vec<f64> = r1
                    .iter()
                    .zip(&rz)
                    .zip(&r0)
                    .map(|((a, b), c)| a - b + c)
                    .collect();
                f.solve_in_place(&mut t)?;
                if !t.iter().all(|v| v.is_finite()) {
                    return Ok(PathEnd {
                        status: Some(StaticStatus::NonFinite {
                            at: NonFiniteAt::Tangent,
                        }),
                        load_steps,
                    });
                }
                model.step_into(u, &t, &mut dq)?;
                let rate = step_size(model, &dq);
                tangent = Some((t, rate));
            }
            let Some((t, rate)) = tangent.as_ref() else {
                continue;
            };
            // the predictor's rotation bounds the step
            if rate * delta > PREDICTOR_ROTATION {
                delta = PREDICTOR_ROTATION / rate;
            }
            let target = (lambda + delta).min(1.0);
            let h = target - lambda;
            // second order when the last step's tangent is known: the
            // tangent's change over that step estimates d²u/dλ² (a turning
            // slope's inward pull, which a straight predictor misses)
            let mut step: Vec<f64> = t.clone();
            if let Some((t_prev, dl)) = previous_tangent.as_ref() {
                step.iter_mut()
                    .zip(t.iter().zip(t_prev))
                    .for_each(|(s, (a, b))| *s += 0.5 * h * (a - b) / dl);
            }
            model.step_into(u, &step, &mut dq)?;
            model.advance_into(u, &w.q, &step, &dq, h, &mut u_try, &mut q_try)?;
            let off: Vec<f64> = r0.iter().map(|v| (1.0 - target) * v).collect();
            let dead_t: Vec<f64> = dead.iter().map(|v| target * v).collect();
            let loads_t = model.scaled_loads(loads, target);
            let tgt = Target::<M> {
                dead: &dead_t,
                loads: &loads_t,
                offset: &off,
                strict: false,
                descent: false,
                definite_only: false,
                full: false,
            };
            match self.corrector(model, &tgt, &mut u_try, &mut q_try, w)? {
                // a step from a stable point to an unstable one stepped over
                // a bifurcation (a column's buckling load: the straight
                // column goes on as a saddle, the path bends away): shorter
                Corrected::Done { factors: f, .. } if stable && !f.is_positive_definite() => {
                    // leave the saddle at this load for the stable branch
                    // (from the unloaded start, whose homotopy offset is nil:
                    // the escape's descent knows no offset)
                    if norm2(&r0) <= self.settings.residual_tolerance * scale {
                        let mut u_s = u_try.clone();
                        let saved_q = std::mem::replace(&mut w.q, q_try.clone());
                        let (st, inertia) = self.stabilize(
                            model,
                            &dead_t,
                            &loads_t,
                            &mut u_s,
                            w,
                            scale,
                            StaticStatus::Converged(crate::outcome::StaticCriterion::Residual),
                        )?;
                        if st.is_converged() && inertia.is_some_and(|i| i.negative == 0) {
                            stable = true;
                            load_steps += 1;
                            lambda = target;
                            u.copy_from_slice(&u_s);
                            q_try.copy_from_slice(&w.q);
                            u_try.copy_from_slice(u);
                            if lambda >= 1.0 {
                                return Ok(PathEnd {
                                    status: None,
                                    load_steps,
                                });
                            }
                            tangent = None;
                            previous_tangent = None;
                            continue;
                        }
                        w.q = saved_q;
                    }
                    u_try.copy_from_slice(u);
                    q_try.copy_from_slice(&w.q);
                    delta = 0.5 * h;
                    if delta < self.settings.min_load_step {
                        return Ok(PathEnd {
                            status: Some(StaticStatus::LoadStepTooSmall {
                                load_fraction: lambda,
                            }),
                            load_steps,
                        });
                    }
                }
                Corrected::Done {
                    factors: f,
                    contraction,
                } => {
                    stable = f.is_positive_definite();
                    load_steps += 1;
                    lambda = target;
                    u.copy_from_slice(&u_try);
                    w.q.copy_from_slice(&q_try);
                    if lambda >= 1.0 {
                        return Ok(PathEnd {
                            status: None,
                            load_steps,
                        });
                    }
                    factors = Some(*f);
                    previous_tangent = tangent.take().map(|(t, _)| (t, h));
                    delta = h * step_factor(contraction);
                }
                Corrected::Failed(Some(status), _) => {
                    return Ok(PathEnd {
                        status: Some(status),
                        load_steps,
                    })
                }
                Corrected::Failed(None, contraction) => {
                    u_try.copy_from_slice(u);
                    q_try.copy_from_slice(&w.q);
                    delta = h * step_factor(contraction).min(0.5);
                    if delta < self.settings.min_load_step {
                        return Ok(PathEnd {
                            status: Some(StaticStatus::LoadStepTooSmall {
                                load_fraction: lambda,
                            }),
                            load_steps,
                        });
                    }
                }
            }
        }
    }

    /// Plain Newton iterations on `R(u) − offset = 0` from the predicted
    /// `u` (`q = φ(u)`), which must contract.
    fn corrector<M: Assembled>(
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
/// ([`Assembled::step_rotation`]; a position change over the length counted
/// too would weigh the slopes' own change `1/L` times).
fn step_size<M: Assembled>(model: &M, dq: &[f64]) -> f64 {
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
                })
            }
            Err(_) => return Err(StaticStatus::SingularTangent),
        }
    }
    Err(StaticStatus::SingularTangent)
}
