//! The static solver's Newton iterations and load homotopy, for any
//! [`Model`](crate::structure::Model) model, in its free coordinates `u` (`q = φ(u)`).
//!
//! Per iteration: the tangent `K_u` on the model's pattern, factored by the
//! caller's [`AutoSolver`] (analyzed once), the Newton direction
//! `K_u du = R` (17), a cap on the rotation of the step, and a
//! backtracking line search that accepts a decrease of the total
//! potential or of `|R|_2`. When the full load fails from the start point,
//! a homotopy `R(u; λ) − (1 − λ) R(u_0; 0) = 0` goes from `λ = 0` (where
//! the start point is exact) to `λ = 1` with adaptive steps.

use std::time::Instant;

use nalgebra::DVector;

use super::{Equilibrium, StaticSolver, finite_or_max, residual_floor};
use crate::error::{Error, Result};
use crate::linsolve::{
    AutoFactors, AutoSolver, FactorOptions, Factorization, Inertia, LinsolveError, SymmetricMatrix,
    TangentSolver,
};
use crate::numeric::norm2;
use crate::outcome::{NonFiniteAt, StaticCriterion, StaticReport, StaticStatus, StaticWarning};
use crate::structure::{Model, ModelLoads};

/// Iterations of the first, plain Newton attempt from the start point.
const QUICK_ITERATIONS: usize = 8;

/// Full Newton steps taken at most on the round-off floor.
const FLOOR_STEPS: usize = 3;

/// The increment test ends a solve only when the residual is also within
/// this multiple of the larger of the residual tolerance and the round-off
/// floor ([`StaticCriterion::Increment`]): a short step at a residual far
/// above both is a stalled iteration, not an equilibrium. (None of the
/// scaling cases of `benches/statics_scaling.rs` ends on the increment
/// test; the one regression case that did ended at 1.2 times the floor.)
///
/// # Example
/// ```
/// assert_eq!(softrod::statics::INCREMENT_RESIDUAL_MULTIPLE, 10.0);
/// ```
pub const INCREMENT_RESIDUAL_MULTIPLE: f64 = 10.0;

/// Whether the test `criterion` holds at a residual `|Q|_2 = residual` (N)
/// with the tolerance `tolerance` and the round-off floor `floor` (N): the
/// check every converged status passes on the returned answer.
fn criterion_holds(criterion: StaticCriterion, residual: f64, tolerance: f64, floor: f64) -> bool {
    match criterion {
        StaticCriterion::Residual => residual <= tolerance,
        StaticCriterion::RoundOffFloor => residual <= floor,
        StaticCriterion::Increment => {
            residual <= INCREMENT_RESIDUAL_MULTIPLE * tolerance.max(floor)
        }
    }
}

/// The diagonal shifts a descent run tries, smallest first, until the
/// shifted tangent is positive definite (a decade apart: the smallest
/// eigenvalue of a fine cable's Jacobi-scaled tangent is ~`(L_e/L)⁴`).
const DESCENT_SHIFTS: [f64; 19] = [
    0.0, 1e-16, 1e-15, 1e-14, 1e-13, 1e-12, 1e-11, 1e-10, 1e-9, 1e-8, 1e-7, 1e-6, 1e-5, 1e-4, 1e-3,
    1e-2, 1e-1, 1.0, 1e1,
];

/// The buffers and counters of one solve.
pub(super) struct Work<'a> {
    pub(super) k: SymmetricMatrix,
    /// Analyzed on the model's tangent pattern.
    pub(super) solver: &'a mut AutoSolver,
    /// The residual at the current iterate (offset subtracted).
    pub(super) r: Vec<f64>,
    /// `φ(u)` at the current iterate.
    pub(super) q: Vec<f64>,
    pub(super) iterations: usize,
    pub(super) floor: f64,
    pub(super) last_step: f64,
    /// Whether the last tangent [`StaticSolver::newton`] factored was
    /// positive definite.
    pub(super) definite: bool,
    /// Whether the last Newton run ended at an equilibrium of its target's
    /// full problem (`Target::full`) whose tangent it had factored, positive definite and
    /// unshifted, at a point that already met the convergence test to the
    /// round-off floor: the answer is that point plus one Newton step the
    /// residual cannot resolve, so the factorization gives its inertia (no
    /// factorization again for the stability test), and `r` is its
    /// residual. Read by [`StaticSolver::run`]'s stability test only.
    pub(super) settled: bool,
}

/// The loads of one Newton run: the dead forces, the model's loads and
/// the homotopy's offset.
pub(super) struct Target<'a, M: Model> {
    pub dead: &'a [f64],
    pub loads: &'a M::Loads,
    pub offset: &'a [f64],
    /// Only full Newton steps (the line search's first trial): a quick
    /// first attempt that gives up at the first step it would shorten.
    pub strict: bool,
    /// Descent only: positive definite (shifted) tangents, steps accepted
    /// only when they lower the potential (leaving a saddle, see
    /// [`super::stability`]).
    pub descent: bool,
    /// Give up at the first tangent that is not positive definite, before
    /// any pivoted LU of it (the quick attempt of a cold solve with the
    /// coarse mesh's start behind it, see [`StaticSolver::run`]).
    pub definite_only: bool,
    /// The problem itself (its dead forces and loads, no offset), not a
    /// homotopy's or continuation's intermediate one (see `Work::settled`).
    pub(super) full: bool,
}

/// The phase of a solve that produced its answer (or its last failure).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Phase {
    /// Plain Newton from the start point.
    Quick,
    /// Plain Newton from the coarse mesh's interpolated equilibrium.
    Sequenced,
    /// The predictor–corrector load continuation, then Newton.
    Continuation,
    /// Line-searched Newton from the start point.
    LineSearch,
    /// The globalized load homotopy from the start point.
    Homotopy,
}

/// What a phase of a solve ended with.
pub(super) struct PhaseEnd {
    /// The status of its last Newton run.
    pub(super) status: StaticStatus,
    /// Which phase.
    pub(super) phase: Phase,
    /// Load steps it took.
    pub(super) load_steps: usize,
    /// The critical points its load path passed, with the branch chosen at
    /// each ([`StaticWarning::Bifurcation`]).
    pub(super) warnings: Vec<StaticWarning>,
}

/// The fixed data of one solve: its loads as dead forces, its scale and
/// its start point.
pub(super) struct Problem<'a, M: Model> {
    pub(super) model: &'a M,
    pub(super) loads: &'a M::Loads,
    pub(super) dead: Vec<f64>,
    /// `n_free` zeros (the full problem's offset).
    pub(super) zero: Vec<f64>,
    /// `|applied forces|_2` at the start (N).
    pub(super) scale: f64,
    pub(super) u_start: Vec<f64>,
    pub(super) q_start: Vec<f64>,
}

impl<M: Model> Problem<'_, M> {
    /// The full problem as a Newton target.
    pub(super) fn full(&self, strict: bool, definite_only: bool) -> Target<'_, M> {
        Target {
            dead: &self.dead,
            loads: self.loads,
            offset: &self.zero,
            strict,
            descent: false,
            definite_only,
            full: true,
        }
    }

    /// `u`, `w.q` back at the start point.
    fn restart(&self, u: &mut [f64], w: &mut Work<'_>) {
        w.settled = false;
        u.copy_from_slice(&self.u_start);
        w.q.copy_from_slice(&self.q_start);
    }
}

impl StaticSolver {
    /// The solve behind [`StaticSolver::solve`] and
    /// [`StaticSolver::solve_with`]: `u` is the start (already checked),
    /// `solver` analyzed on the model's pattern. The phases in turn, each
    /// tried when the one before did not converge: [`Self::quick`],
    /// [`Self::sequenced`], [`Self::continued`], [`Self::line_searched`],
    /// [`Self::homotopy`]; then [`Self::finish`] (stability, the report).
    pub(super) fn run<M: Model>(
        &self,
        model: &M,
        loads: &M::Loads,
        mut u: Vec<f64>,
        cold: bool,
        solver: &mut AutoSolver,
    ) -> Result<Equilibrium> {
        let start = Instant::now();
        let n = model.n_free();
        let mut w = Work {
            k: SymmetricMatrix::zeros(solver.pattern().clone()),
            solver,
            r: vec![0.0; n],
            q: vec![0.0; model.n_q()],
            iterations: 0,
            floor: 0.0,
            last_step: 0.0,
            definite: false,
            settled: false,
        };
        let p = self.problem(model, loads, &u, &mut w)?;
        // loads so large that their norm overflows (or a start point where the
        // forces do): no tolerance can be stated, so no solve is attempted
        if !p.scale.is_finite() {
            let end = PhaseEnd {
                status: StaticStatus::NonFinite {
                    at: NonFiniteAt::Loads,
                },
                phase: Phase::Quick,
                load_steps: 0,
                warnings: Vec::new(),
            };
            return self.finish(&p, u, &mut w, end, start);
        }
        // a cold solve of a fine mesh has a coarse mesh of the same model
        // to start from (see `super::sequence`; `None` for a coarse mesh)
        let coarse = if cold {
            model.coarse_model(loads).ok().flatten()
        } else {
            None
        };
        let mut end = self.quick(&p, &mut u, &mut w, cold)?;
        if let (false, Some(coarse)) = (end.status.is_converged(), coarse) {
            end = self.sequenced(&p, coarse, &mut u, &mut w)?;
        }
        if !end.status.is_converged() {
            let steps = end.load_steps;
            end = self.continued(&p, &mut u, &mut w, cold)?;
            end.load_steps += steps;
        }
        if !end.status.is_converged() {
            let steps = end.load_steps;
            end = self.line_searched(&p, &mut u, &mut w)?;
            end.load_steps += steps;
        }
        if !end.status.is_converged() {
            let steps = end.load_steps;
            end = self.homotopy(&p, &mut u, &mut w)?;
            end.load_steps += steps;
        }
        self.finish(&p, u, &mut w, end, start)
    }

    /// The dead forces, the load scale and the start point of a solve from
    /// `u` (`w.q` set to `φ(u)`).
    fn problem<'a, M: Model>(
        &self,
        model: &'a M,
        loads: &'a M::Loads,
        u: &[f64],
        w: &mut Work<'_>,
    ) -> Result<Problem<'a, M>> {
        let dead: Vec<f64> = model.dead_force(loads)?.data.into();
        let n = model.n_free();
        model.configuration_into(u, &mut w.q)?;
        let scale = {
            let mut applied = vec![0.0; n];
            model.applied_force_into(u, &w.q, &dead, loads, &mut applied)?;
            norm2(&applied)
        };
        Ok(Problem {
            model,
            loads,
            dead,
            zero: vec![0.0; n],
            scale,
            u_start: u.to_vec(),
            q_start: w.q.clone(),
        })
    }

    /// First plain Newton from the start point (a warm start, a robot's
    /// arcs of its actuation), given up at the first step it would have to
    /// shorten; cold (`cold`), also at the first tangent that is not
    /// positive definite. A cold solve must follow the branch connected to
    /// the unloaded state along the load path, and a full-load Newton run
    /// that met an indefinite tangent may have crossed to another one
    /// (measured before: the upright column beyond buckling with a 0.01 N
    /// lateral tip force leaned against the force at 16 elements, its quick
    /// attempt converging through indefinite tangents); the load path
    /// (`continuation.rs`) then decides. It also saves work (measured,
    /// `benches/statics_scaling.rs`: such a quick attempt never converged on
    /// the scaling cases at 128 to 2000 elements, and its pivoted LU
    /// factorizations of the fine tangent, up to five in the first
    /// iteration with the diagonal shifts, cost more than the whole coarse
    /// solve; the tip moments and the mid-length force are indefinite at the
    /// straight start). Its answer is kept only at a stable equilibrium
    /// (plain Newton also finds the unstable ones, e.g. a column standing
    /// straight above its buckling load): otherwise the status is
    /// [`StaticStatus::LineSearchFailed`].
    fn quick<M: Model>(
        &self,
        p: &Problem<'_, M>,
        u: &mut [f64],
        w: &mut Work<'_>,
        cold: bool,
    ) -> Result<PhaseEnd> {
        let quick = StaticSolver {
            settings: super::StaticSettings {
                max_iterations: self.settings.max_iterations.min(QUICK_ITERATIONS),
                ..self.settings.clone()
            },
        };
        let status = quick.newton(p.model, &p.full(true, cold), u, w, p.scale)?;
        let stable = w.iterations == 0 || w.definite;
        Ok(PhaseEnd {
            status: if status.is_converged() && !stable {
                StaticStatus::LineSearchFailed
            } else {
                status
            },
            phase: Phase::Quick,
            load_steps: 0,
            warnings: Vec::new(),
        })
    }

    /// A cold solve of a fine mesh from the coarse mesh's equilibrium (see
    /// `super::sequence`), kept when plain Newton reaches a stable
    /// equilibrium from it (`u` is then that equilibrium; otherwise where
    /// Newton stopped, and the status [`StaticStatus::LineSearchFailed`]).
    fn sequenced<M: Model>(
        &self,
        p: &Problem<'_, M>,
        coarse: (M, M::Loads),
        u: &mut [f64],
        w: &mut Work<'_>,
    ) -> Result<PhaseEnd> {
        let start = self.coarse_start(p.model, coarse, self.settings.max_total_iterations)?;
        w.iterations += start.iterations;
        let mut status = StaticStatus::LineSearchFailed;
        if let Some(uc) = start.u {
            w.settled = false;
            u.copy_from_slice(&uc);
            p.model.configuration_into(u, &mut w.q)?;
            let before = w.iterations;
            let fine = self.fine_newton(p.model, &p.full(true, false), u, w, p.scale)?;
            if fine.is_converged() && (w.iterations == before || w.definite) {
                status = fine;
            }
        }
        Ok(PhaseEnd {
            status,
            phase: Phase::Sequenced,
            load_steps: start.load_steps,
            // the coarse solve's load path is this one's
            warnings: start.warnings,
        })
    }

    /// The predictor–corrector continuation from the start point (cold:
    /// from the unloaded reference, an exact equilibrium of no loads; an
    /// offset from another start point acts as a dead force on the node
    /// slopes, which stretches them on fine meshes), then Newton on the full
    /// problem. Non-conservative (follower) loads are not tried
    /// ([`StaticStatus::LineSearchFailed`]): their tangent is the symmetric
    /// part only, Newton converges linearly and the continuation's
    /// contraction test would halve every step; the globalized homotopy
    /// handles them.
    fn continued<M: Model>(
        &self,
        p: &Problem<'_, M>,
        u: &mut Vec<f64>,
        w: &mut Work<'_>,
        cold: bool,
    ) -> Result<PhaseEnd> {
        let (model, loads) = (p.model, p.loads);
        if !loads.conservative() {
            return Ok(PhaseEnd {
                status: StaticStatus::LineSearchFailed,
                phase: Phase::Continuation,
                load_steps: 0,
                warnings: Vec::new(),
            });
        }
        p.restart(u, w);
        if cold {
            *u = model.reference_free_coordinates().data.into();
            model.configuration_into(u, &mut w.q)?;
        }
        let end = self.continuation(model, &p.dead, loads, u, w, p.scale)?;
        w.settled = false;
        let status = match end.status {
            // near the full load's equilibrium: Newton to the tolerance
            None => self.newton(model, &p.full(false, false), u, w, p.scale)?,
            Some(status) => status,
        };
        Ok(PhaseEnd {
            status,
            phase: Phase::Continuation,
            load_steps: end.load_steps,
            warnings: end.warnings,
        })
    }

    /// Natural continuation's first step: line-searched Newton on the full
    /// problem from the start point (slower on fine meshes, but it reaches
    /// some equilibria the plain corrector cannot: see the module
    /// documentation).
    fn line_searched<M: Model>(
        &self,
        p: &Problem<'_, M>,
        u: &mut [f64],
        w: &mut Work<'_>,
    ) -> Result<PhaseEnd> {
        p.restart(u, w);
        let status = self.newton(p.model, &p.full(false, false), u, w, p.scale)?;
        Ok(PhaseEnd {
            status,
            phase: Phase::LineSearch,
            load_steps: 0,
            warnings: Vec::new(),
        })
    }

    /// The load homotopy from the start point, each load step globalized
    /// by the line search,
    /// `R_λ(u) = R(u; λ loads) − (1 − λ) R(u_start; no loads)`, with
    /// adaptive steps. Its last Newton run is on `λ = 1`, whose offset
    /// vanishes, but `w.r` may be an intermediate problem's residual when it
    /// fails (the report's residual is evaluated again).
    fn homotopy<M: Model>(
        &self,
        p: &Problem<'_, M>,
        u: &mut Vec<f64>,
        w: &mut Work<'_>,
    ) -> Result<PhaseEnd> {
        let model = p.model;
        p.restart(u, w);
        let unloaded = p.loads.scaled(0.0);
        let zero_dead = vec![0.0; model.n_q()];
        let mut r0 = vec![0.0; model.n_free()];
        model.residual_into(u, &w.q, &zero_dead, &unloaded, &mut r0)?;
        let mut lambda = 0.0;
        let mut step: f64 = 0.25;
        let mut load_steps = 0;
        let mut status = StaticStatus::LoadStepTooSmall { load_fraction: 0.0 };
        while w.iterations < self.settings.max_total_iterations {
            let target = (lambda + step).min(1.0);
            let off: Vec<f64> = r0.iter().map(|v| (1.0 - target) * v).collect();
            let dead_t: Vec<f64> = p.dead.iter().map(|v| target * v).collect();
            let loads_t = p.loads.scaled(target);
            let saved = (u.clone(), w.q.clone());
            let before = w.iterations;
            let t = Target::<M> {
                dead: &dead_t,
                loads: &loads_t,
                offset: &off,
                strict: false,
                descent: false,
                definite_only: false,
                full: false,
            };
            let step_status = self.newton(model, &t, u, w, p.scale)?;
            if step_status.is_converged() {
                load_steps += 1;
                lambda = target;
                if lambda >= 1.0 {
                    status = step_status;
                    break;
                }
                if w.iterations - before <= 6 {
                    step *= 2.0;
                }
            } else {
                (*u, w.q) = saved;
                step *= 0.5;
                if step < self.settings.min_load_step {
                    // a load step that ran out of iterations or found no
                    // descent: the homotopy stalled
                    status = match step_status {
                        StaticStatus::IterationLimit { .. } | StaticStatus::LineSearchFailed => {
                            StaticStatus::LoadStepTooSmall {
                                load_fraction: lambda,
                            }
                        }
                        other => other,
                    };
                    break;
                }
            }
        }
        if w.iterations >= self.settings.max_total_iterations && !status.is_converged() {
            status = StaticStatus::IterationLimit {
                iterations: w.iterations,
            };
        }
        Ok(PhaseEnd {
            status,
            phase: Phase::Homotopy,
            load_steps,
            warnings: Vec::new(),
        })
    }

    /// The answer's stability (a saddle, such as the straight column
    /// beyond buckling, is left for a stable equilibrium; see
    /// [`super::stability`]), its residual, the check that the test its
    /// status names holds on that residual, and the report.
    fn finish<M: Model>(
        &self,
        p: &Problem<'_, M>,
        mut u: Vec<f64>,
        w: &mut Work<'_>,
        mut end: PhaseEnd,
        start: Instant,
    ) -> Result<Equilibrium> {
        let (model, loads) = (p.model, p.loads);
        let mut status = end.status;
        // the answer's inertia goes into the report, read off the last
        // Newton factorization when it was made at an equilibrium to the
        // floor (see `Work::settled`: then `w.r` is the answer's residual too)
        let settled = status.is_converged() && w.settled && loads.conservative();
        // every Newton run leaves `w.r` the residual of its target at `u`;
        // the last one's target was the full problem (zero offset) unless
        // the homotopy ran: that residual is the report's while the
        // stability test leaves `u` where it is (bit for bit the same
        // evaluation; a residual less per solve)
        let homotopy = end.phase == Phase::Homotopy;
        let kept =
            (status.is_converged() && !settled && !homotopy).then(|| (u.clone(), w.r.clone()));
        let mut inertia = None;
        if settled {
            inertia = Some(Inertia {
                positive: model.n_free(),
                negative: 0,
            });
        } else if status.is_converged() {
            let st = self.stabilize(model, &p.dead, loads, &mut u, w, p.scale, status, None)?;
            (status, inertia) = (st.status, st.inertia);
            if let Some(branch) = st.branch {
                end.warnings.push(StaticWarning::Bifurcation {
                    from_load_fraction: 1.0,
                    to_load_fraction: 1.0,
                    branch,
                });
            }
        }
        if !settled {
            // final residual for the report
            match kept {
                Some((u_kept, r)) if u_kept == u => w.r = r,
                _ => model.residual_into(&u, &w.q, &p.dead, loads, &mut w.r)?,
            }
        }
        let res = norm2(&w.r);
        let tolerance = self.settings.residual_tolerance * p.scale;
        // no NaN leaves the library: a "converged" state with a non-finite
        // coordinate or residual is a failure
        if !(res.is_finite() && w.q.iter().all(|v| v.is_finite())) {
            status = StaticStatus::NonFinite {
                at: NonFiniteAt::Solution,
            };
        } else if let Some(criterion) = status.criterion() {
            // the test the status names, on the answer's own residual
            if !criterion_holds(criterion, res, tolerance, w.floor) {
                status = StaticStatus::Unverified { criterion };
            }
        }
        let report = StaticReport {
            status,
            iterations: w.iterations,
            load_steps: end.load_steps,
            residual_norm_n: finite_or_max(res),
            residual_tolerance_n: finite_or_max(tolerance),
            residual_floor_n: finite_or_max(w.floor),
            load_scale_n: finite_or_max(p.scale),
            increment_norm_m: finite_or_max(w.last_step),
            negative_eigenvalues: inertia.map(|i| i.negative),
            warnings: {
                let mut warnings = std::mem::take(&mut end.warnings);
                if let Some(i) = inertia.filter(|i| i.negative > 0) {
                    warnings.push(StaticWarning::Unstable {
                        negative_eigenvalues: i.negative,
                    });
                }
                warnings
            },
            wall_time_s: start.elapsed().as_secs_f64(),
        };
        if status.is_converged() {
            Ok(Equilibrium {
                q: DVector::from_vec(std::mem::take(&mut w.q)),
                u: DVector::from_vec(u),
                report,
            })
        } else {
            Err(Error::NotConverged {
                report: Box::new(report),
            })
        }
    }

    /// Newton iterations on `R(u) − offset = 0` from `u` (updated in place,
    /// `w.q = φ(u)` kept with it). Each iteration in its phases: the
    /// convergence and budget tests, the direction
    /// ([`Self::newton_direction`]: a chord step on the floor or the
    /// factored tangent), the rotation cap, a full step on the round-off
    /// floor ([`Self::floor_step`]) or the line search
    /// ([`Self::line_search`]), then the increment test.
    pub(super) fn newton<M: Model>(
        &self,
        model: &M,
        t: &Target<'_, M>,
        u: &mut [f64],
        w: &mut Work<'_>,
        scale: f64,
    ) -> Result<StaticStatus> {
        let n = model.n_free();
        let tol = self.settings.residual_tolerance * scale;
        let xtol = self.settings.increment_tolerance * model.length_m();
        w.settled = false;
        let rn = eval(model, t, u, &w.q, &mut w.r)?;
        let mut it = Iterate {
            rn,
            trial: u.to_vec(),
            q_trial: w.q.clone(),
            r_trial: vec![0.0; n],
            du: vec![0.0; n],
            dq: vec![0.0; model.n_q()],
            energies: Vec::new(),
            floor_steps: 0,
            floor_previous: f64::INFINITY,
            floor_lu: None,
        };
        for _ in 0..self.settings.max_iterations {
            if !it.rn.is_finite() {
                return Ok(StaticStatus::NonFinite {
                    at: NonFiniteAt::Residual,
                });
            }
            if it.rn <= tol {
                return Ok(StaticStatus::Converged(StaticCriterion::Residual));
            }
            if w.iterations >= self.settings.max_total_iterations {
                return Ok(StaticStatus::IterationLimit {
                    iterations: w.iterations,
                });
            }
            let at_floor = match self.newton_direction(model, t, u, w, &mut it)? {
                Direction::Found { at_floor } => at_floor,
                Direction::Stop(status) => return Ok(status),
            };
            model.step_into(u, &it.du, &mut it.dq)?;
            // cap the rotation of the step
            let rotation = model.step_rotation(&it.dq);
            let s = if rotation > self.settings.max_step_rotation {
                self.settings.max_step_rotation / rotation
            } else {
                1.0
            };
            let step_inf = it.dq.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if at_floor {
                match self.floor_step(model, t, u, w, &mut it, step_inf, xtol)? {
                    FloorStep::Continue => continue,
                    FloorStep::Converged => {
                        return Ok(StaticStatus::Converged(StaticCriterion::RoundOffFloor));
                    }
                    FloorStep::Ordinary => {}
                }
            }
            if t.strict && s < 1.0 {
                // only full steps: this one is capped
                return Ok(StaticStatus::LineSearchFailed);
            }
            // the increment test, with the residual within its multiple of
            // the tolerance or floor (see `INCREMENT_RESIDUAL_MULTIPLE`)
            let near = |rn: f64, floor: f64| rn <= INCREMENT_RESIDUAL_MULTIPLE * tol.max(floor);
            match self.line_search(model, t, u, w, &mut it, s)? {
                Search::Rejected => {
                    if t.strict {
                        // only full steps: this one is not accepted
                        return Ok(StaticStatus::LineSearchFailed);
                    }
                    // no decrease along the Newton direction: at the floor
                    // or stuck
                    if step_inf <= xtol && near(it.rn, w.floor) {
                        return Ok(StaticStatus::Converged(StaticCriterion::Increment));
                    }
                    return Ok(StaticStatus::LineSearchFailed);
                }
                Search::Accepted { s } => {
                    u.copy_from_slice(&it.trial);
                    std::mem::swap(&mut w.q, &mut it.q_trial);
                    std::mem::swap(&mut w.r, &mut it.r_trial);
                    it.rn = norm2(&w.r);
                    w.last_step = s * step_inf;
                    if s == 1.0 && step_inf <= xtol && near(it.rn, w.floor) {
                        return Ok(StaticStatus::Converged(StaticCriterion::Increment));
                    }
                }
            }
        }
        if it.rn <= tol {
            return Ok(StaticStatus::Converged(StaticCriterion::Residual));
        }
        if it.rn <= w.floor {
            return Ok(StaticStatus::Converged(StaticCriterion::RoundOffFloor));
        }
        Ok(StaticStatus::IterationLimit {
            iterations: w.iterations,
        })
    }

    /// The Newton direction of one iteration into `it.du` (one iteration
    /// counted). On the floor after a first step there: a chord step with
    /// that step's factorization (the tangent moves by round-off between
    /// points on the floor; a fresh one cost a tangent and a factorization
    /// per step, up to three steps at 2000 elements). Otherwise the tangent
    /// (and the round-off floor from it), factored Jacobi-scaled (the rows
    /// of a fine cable's tangent span many orders of magnitude: bending
    /// ∝ L_e⁻³, axial on the slopes ∝ L_e); if its direction does not
    /// descend the potential (R·du <= 0: an indefinite tangent far from
    /// equilibrium), the scaled diagonal is shifted with growing μ until it
    /// does. (The tangent is symmetric: L D Lᵀ when positive definite, the
    /// pivoted LU otherwise, neither consuming it.)
    fn newton_direction<M: Model>(
        &self,
        model: &M,
        t: &Target<'_, M>,
        u: &[f64],
        w: &mut Work<'_>,
        it: &mut Iterate,
    ) -> Result<Direction> {
        let chord = match (&it.floor_lu, it.floor_steps > 0 && it.rn <= w.floor) {
            (Some(f), true) => {
                it.du.copy_from_slice(&w.r);
                f.solve_in_place(&mut it.du)?;
                let slope: f64 = w.r.iter().zip(&it.du).map(|(a, b)| a * b).sum();
                slope > 0.0 && it.du.iter().all(|v| v.is_finite())
            }
            _ => false,
        };
        if !chord {
            model.tangent_into(u, &w.q, t.dead, t.loads, &mut w.k)?;
            let qmax = w.q.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            w.floor = residual_floor(w.k.max_abs(), qmax, model.n_free());
        }
        // At the round-off floor the residual cannot certify more digits,
        // but one more Newton step still can gain them (the floor does not
        // shrink with the load; stopping here left small-load solves 1e-11 m
        // short): take it, keep it unless it raises the residual, stop.
        let at_floor = it.rn <= w.floor;
        w.iterations += 1;
        if chord {
            return Ok(Direction::Found { at_floor });
        }
        let shifts: &[f64] = if t.descent {
            &DESCENT_SHIFTS
        } else if t.definite_only {
            &[0.0]
        } else {
            &[0.0, 1e-8, 1e-6, 1e-4, 1e-2, 1.0]
        };
        for &mu in shifts {
            let options = FactorOptions {
                shift: mu,
                require_positive_definite: t.descent || t.definite_only,
            };
            let lu = match w.solver.factor(&w.k, options) {
                Ok(lu) => lu,
                Err(LinsolveError::Singular { .. }) => continue,
                Err(LinsolveError::NotPositiveDefinite { .. }) if t.descent => continue,
                Err(LinsolveError::NotPositiveDefinite { .. }) if t.definite_only => {
                    return Ok(Direction::Stop(StaticStatus::LineSearchFailed));
                }
                Err(LinsolveError::NonFinite { .. }) => {
                    return Ok(Direction::Stop(StaticStatus::NonFinite {
                        at: NonFiniteAt::Tangent,
                    }));
                }
                Err(e) => return Err(e.into()),
            };
            w.definite = mu == 0.0 && lu.is_positive_definite();
            w.settled = t.full && at_floor && w.definite;
            it.du.copy_from_slice(&w.r);
            lu.solve_in_place(&mut it.du)?;
            let slope: f64 = w.r.iter().zip(&it.du).map(|(a, b)| a * b).sum();
            if slope > 0.0 && it.du.iter().all(|v| v.is_finite()) {
                if at_floor && mu == 0.0 {
                    it.floor_lu = Some(lu);
                }
                return Ok(Direction::Found { at_floor });
            }
        }
        Ok(Direction::Stop(StaticStatus::SingularTangent))
    }

    /// On the floor: a full Newton step along `it.du` (`it.dq`, of size
    /// `step_inf`), kept unless it leaves the floor (the first one: unless
    /// it lands above it).
    #[allow(clippy::too_many_arguments)]
    fn floor_step<M: Model>(
        &self,
        model: &M,
        t: &Target<'_, M>,
        u: &mut [f64],
        w: &mut Work<'_>,
        it: &mut Iterate,
        step_inf: f64,
        xtol: f64,
    ) -> Result<FloorStep> {
        model.advance_into(u, &w.q, &it.du, &it.dq, 1.0, &mut it.trial, &mut it.q_trial)?;
        let rt = eval(model, t, &it.trial, &it.q_trial, &mut it.r_trial)?;
        if !(it.floor_steps > 0 || rt <= w.floor) {
            // a first step that lands above the floor; the start was below
            // it only because the floor, set by the stiffest rows, is above
            // what the other rows carry (a stiff section beside a soft one):
            // an ordinary, line-searched step. Not an equilibrium to the
            // floor: its factorization tells nothing about the answer's
            // inertia.
            w.settled = false;
            return Ok(FloorStep::Ordinary);
        }
        // full Newton steps while they shrink (the residual cannot tell more
        // digits, the step size still can)
        let shrinking = it.floor_steps == 0 || step_inf <= 0.5 * it.floor_previous;
        // the first step is taken whenever it lands on the floor (below it
        // the residual cannot tell a good step from a bad one; a small load
        // on a fine mesh starts below it: left at the start point, 2000
        // elements under a 1e-3-scale load reported the straight rod); the
        // next ones unless they raise the residual above the floor
        let kept = it.floor_steps == 0 || rt <= it.rn.max(w.floor);
        if shrinking && rt.is_finite() && kept {
            u.copy_from_slice(&it.trial);
            std::mem::swap(&mut w.q, &mut it.q_trial);
            std::mem::swap(&mut w.r, &mut it.r_trial);
            w.last_step = step_inf;
            it.rn = rt;
            it.floor_steps += 1;
            it.floor_previous = step_inf;
            if step_inf > xtol && it.floor_steps < FLOOR_STEPS {
                return Ok(FloorStep::Continue);
            }
        }
        Ok(FloorStep::Converged)
    }

    /// The backtracking line search along `it.du` from the step length `s`
    /// (the rotation cap's): a trial is accepted when it lowers `|R|²`
    /// enough (not in a descent run) or the total potential `Π` (which
    /// decreases along `du` when `R·du > 0`); a strict target tries the
    /// full step only. The accepted trial is left in `it.trial`,
    /// `it.q_trial`, `it.r_trial`.
    fn line_search<M: Model>(
        &self,
        model: &M,
        t: &Target<'_, M>,
        u: &[f64],
        w: &Work<'_>,
        it: &mut Iterate,
        mut s: f64,
    ) -> Result<Search> {
        // the energies at u, once for all trials, when a trial first needs
        // them (a trial that lowers |R| enough needs none)
        let mut energies_at_u = false;
        let offset_slope: f64 = t.offset.iter().zip(&it.du).map(|(a, b)| a * b).sum();
        let slope: f64 = w.r.iter().zip(&it.du).map(|(a, b)| a * b).sum();
        let rn = it.rn;
        for _ in 0..30 {
            model.advance_into(u, &w.q, &it.du, &it.dq, s, &mut it.trial, &mut it.q_trial)?;
            let rt = eval(model, t, &it.trial, &it.q_trial, &mut it.r_trial)?;
            if rt.is_finite() {
                let residual_ok = !t.descent && rt * rt <= (1.0 - 1e-4 * s) * rn * rn;
                if residual_ok {
                    return Ok(Search::Accepted { s });
                }
                if !energies_at_u {
                    model.energies_into(&w.q, &mut it.energies)?;
                    energies_at_u = true;
                }
                let offset_work = s * offset_slope;
                let dpi = model.potential_change_from(
                    u,
                    &w.q,
                    &it.energies,
                    &it.trial,
                    &it.q_trial,
                    t.dead,
                    t.loads,
                )? + offset_work;
                if dpi <= -1e-4 * s * slope {
                    return Ok(Search::Accepted { s });
                }
            }
            if t.strict {
                // only full steps: this one is not accepted
                break;
            }
            s *= 0.5;
        }
        Ok(Search::Rejected)
    }
}

/// `|R(u) − offset|_2` of the target `t` at `u` (`q = φ(u)`), the residual
/// into `r`.
fn eval<M: Model>(
    model: &M,
    t: &Target<'_, M>,
    u: &[f64],
    q: &[f64],
    r: &mut [f64],
) -> Result<f64> {
    model.residual_into(u, q, t.dead, t.loads, r)?;
    r.iter_mut().zip(t.offset).for_each(|(a, b)| *a -= b);
    Ok(norm2(r))
}

/// The scratch state of one Newton run ([`StaticSolver::newton`]).
struct Iterate {
    /// `|R − offset|_2` at the current iterate.
    rn: f64,
    /// A trial point, its `φ` and its residual.
    trial: Vec<f64>,
    q_trial: Vec<f64>,
    r_trial: Vec<f64>,
    /// The Newton direction in free coordinates and in `q`.
    du: Vec<f64>,
    dq: Vec<f64>,
    /// The element energies at the current iterate (the line search's).
    energies: Vec<f64>,
    /// Full steps taken on the round-off floor, and the last one's size.
    floor_steps: usize,
    floor_previous: f64,
    /// The factorization of the first step on the round-off floor.
    floor_lu: Option<AutoFactors>,
}

/// The direction phase's outcome ([`StaticSolver::newton_direction`]).
enum Direction {
    /// In `Iterate::du`; `at_floor`: the iterate is on the round-off floor.
    Found { at_floor: bool },
    /// The run ends with this status.
    Stop(StaticStatus),
}

/// A full step on the round-off floor's outcome ([`StaticSolver::floor_step`]).
enum FloorStep {
    /// Kept; the full steps go on.
    Continue,
    /// The run ends on the floor.
    Converged,
    /// The first step landed above the floor: an ordinary, line-searched
    /// step instead.
    Ordinary,
}

/// The line search's outcome ([`StaticSolver::line_search`]).
enum Search {
    /// The trial at step length `s` (in `Iterate::trial`).
    Accepted { s: f64 },
    /// No trial lowered `|R|` or `Π` enough.
    Rejected,
}
