//! Static equilibrium: Newton's method on `Q(F, q, P) = 0` (17).
//!
//! Globalization: a backtracking line search on `|Q|²` (the Newton direction
//! always descends it, whatever the tangent's definiteness), a cap on the
//! rotation of the node slopes per step, and, when the full problem fails
//! from the start point, a homotopy `Q(q) − (1 − λ) Q(q_0) = 0` from `λ = 0`
//! (where the start point is exact) to `λ = 1` with adaptive steps.
//!
//! Convergence is scale-aware. The residual test is relative to the applied
//! generalized forces, but never asks for less than the round-off floor
//! `ε |K|_max |q|_∞ max(1, 0.05 √n)`, which grows with the element count (a fixed
//! relative tolerance of 1e-10 is unreachable at 32+ elements). A full Newton
//! step below `increment_tolerance × L` also ends the solve. The report's
//! status shows which test ended it (or why it failed), with the tolerance
//! and the floor ([`residual_floor`]).
//!
//! [`EquilibriumTracker`] (in [`tracker`]) solves the same equilibrium at a
//! sequence of nearby loads, warm, reusing factorizations: what an estimator
//! or a controller needs; it falls back to [`StaticSolver`].

use std::sync::Arc;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{check_len, Error, Result};
use crate::linsolve::{
    AutoSolver, FactorOptions, Factorization, LinsolveError, SolverKind, SymmetricMatrix,
    TangentSolver,
};
use crate::loads::Loads;
use crate::numeric::norm2;
pub use crate::outcome::{NonFiniteAt, StaticCriterion, StaticReport, StaticStatus};

pub mod tracker;

pub use tracker::{EquilibriumTracker, LinearLoad, TrackedEquilibrium};

/// Settings of the static solver; every field has a documented default.
///
/// # Example
/// ```
/// let s = softrod::statics::StaticSettings { residual_tolerance: 1e-12, ..Default::default() };
/// s.validate().unwrap();
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct StaticSettings {
    /// Newton iterations per load step (default 30).
    pub max_iterations: usize,
    /// Newton iterations in all, over every load step (default 2000).
    pub max_total_iterations: usize,
    /// Residual tolerance relative to the norm of the applied generalized
    /// forces (default 1e-10).
    pub residual_tolerance: f64,
    /// A full Newton step shorter than this times the robot length ends the
    /// solve (default 1e-12).
    pub increment_tolerance: f64,
    /// Largest change of a node slope `r'` in one Newton step, roughly the
    /// rotation in rad (default 0.5).
    pub max_step_rotation: f64,
    /// Smallest homotopy step before giving up (default 1e-4).
    pub min_load_step: f64,
    /// The linear solver of the tangent (default [`SolverKind::Auto`]: the
    /// banded one for the robot's single chain).
    pub linear_solver: SolverKind,
}

impl Default for StaticSettings {
    fn default() -> Self {
        StaticSettings {
            max_iterations: 30,
            max_total_iterations: 2000,
            residual_tolerance: 1e-10,
            increment_tolerance: 1e-12,
            max_step_rotation: 0.5,
            min_load_step: 1e-4,
            linear_solver: SolverKind::Auto,
        }
    }
}

impl StaticSettings {
    /// Checks every field: iteration counts in `1..=MAX_ITERATIONS`
    /// (`max_total_iterations >= max_iterations`), tolerances and the
    /// smallest load step in `(0, 1)`, `max_step_rotation` finite and positive.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field; [`Error::TooLarge`] for
    /// an iteration count above [`MAX_ITERATIONS`].
    pub fn validate(&self) -> Result<()> {
        if self.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", 0, "must be >= 1"));
        }
        crate::error::check_at_most("max_iterations", self.max_iterations, MAX_ITERATIONS)?;
        crate::error::check_at_most(
            "max_total_iterations",
            self.max_total_iterations,
            MAX_ITERATIONS,
        )?;
        if self.max_total_iterations < self.max_iterations {
            return Err(Error::invalid(
                "max_total_iterations",
                self.max_total_iterations,
                "must be >= max_iterations",
            ));
        }
        for (name, v) in [
            ("residual_tolerance", self.residual_tolerance),
            ("increment_tolerance", self.increment_tolerance),
            ("max_step_rotation", self.max_step_rotation),
            ("min_load_step", self.min_load_step),
        ] {
            crate::error::check_positive(name, v)?;
        }
        for (name, v) in [
            ("residual_tolerance", self.residual_tolerance),
            ("increment_tolerance", self.increment_tolerance),
            ("min_load_step", self.min_load_step),
        ] {
            // a relative tolerance of 1 or more accepts any configuration
            if v >= 1.0 {
                return Err(Error::invalid(name, v, "must be < 1"));
            }
        }
        Ok(())
    }
}

/// The largest iteration budget [`StaticSettings`] accept: it bounds the
/// time a solve may take.
pub const MAX_ITERATIONS: usize = 100_000;

/// A converged equilibrium.
#[derive(Debug, Clone, PartialEq)]
pub struct Equilibrium {
    /// All coordinates, base node included.
    pub q: Vec<f64>,
    /// What the solver did.
    pub report: StaticReport,
}

/// Newton solver for the static equilibrium of a [`Robot`].
///
/// # Example
/// ```
/// use softrod::{assembly::{RobotSpec, Section}, loads::{Loads, PointForce}, statics::StaticSolver};
/// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]).build_planar().unwrap();
/// let loads = Loads { point_forces: vec![PointForce { s_m: 0.24, force_n: vec![0.0, -0.01] }], ..Loads::default() };
/// let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
/// let tip_y = eq.q[robot.n_q() - 3];
/// // linear theory: P L³ / (3 EI)
/// assert!((tip_y + 0.01 * 0.24f64.powi(3) / (3.0 * 0.025)).abs() < 1e-6);
/// ```
#[derive(Debug, Clone, Default)]
pub struct StaticSolver {
    /// Settings.
    pub settings: StaticSettings,
}

struct Work<'a> {
    k: SymmetricMatrix,
    /// Analyzed on the robot's tangent pattern.
    solver: &'a mut AutoSolver,
    r: Vec<f64>,
    iterations: usize,
    floor: f64,
    last_step: f64,
}

impl StaticSolver {
    /// A solver with the given settings.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if the settings are invalid.
    pub fn new(settings: StaticSettings) -> Result<Self> {
        settings.validate()?;
        Ok(StaticSolver { settings })
    }

    /// Solves `Q(q) = 0` for the given loads, starting from `q0` (all `n_q`
    /// coordinates; the clamp resets its base position and direction) or,
    /// cold, from [`Robot::arc_configuration`].
    ///
    /// # Errors
    /// [`Error::NotConverged`] with the report when no equilibrium is found
    /// within the budget; the errors of [`Robot::validate_loads`] for bad
    /// loads; [`Error::DimensionMismatch`] or [`Error::InvalidParameter`] for
    /// a bad `q0`.
    pub fn solve<E: Element>(
        &self,
        robot: &Robot<E>,
        loads: &Loads,
        q0: Option<&[f64]>,
    ) -> Result<Equilibrium> {
        self.settings.validate()?;
        let mut solver =
            AutoSolver::with_kind(robot.tangent_pattern(), self.settings.linear_solver)?;
        self.solve_with(robot, loads, q0, &mut solver)
    }

    /// [`StaticSolver::solve`] with a linear solver analyzed before on
    /// [`Robot::tangent_pattern`]: a caller that solves one robot many times
    /// analyzes its pattern once (`settings.linear_solver` is then not read).
    ///
    /// # Errors
    /// As [`StaticSolver::solve`]; [`Error::InvalidParameter`] (field
    /// `solver`) for a solver analyzed on another pattern.
    ///
    /// # Example
    /// ```
    /// use softrod::linsolve::{AutoSolver, SolverKind};
    /// use softrod::statics::StaticSolver;
    /// let scene = softrod::scene::Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let mut solver = AutoSolver::with_kind(robot.tangent_pattern(), SolverKind::Sparse)?;
    /// let eq = StaticSolver::default().solve_with(&robot, &loads, None, &mut solver)?;
    /// assert!(eq.report.status.is_converged());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn solve_with<E: Element>(
        &self,
        robot: &Robot<E>,
        loads: &Loads,
        q0: Option<&[f64]>,
        solver: &mut AutoSolver,
    ) -> Result<Equilibrium> {
        self.settings.validate()?;
        let pattern = solver.pattern();
        if !(Arc::ptr_eq(pattern, robot.tangent_pattern())
            || **pattern == **robot.tangent_pattern())
        {
            return Err(Error::invalid(
                "solver",
                pattern.n(),
                "analyzed on another pattern than the robot's tangent",
            ));
        }
        let start = Instant::now();
        let nd = E::NODE_DOFS;
        let dead = robot.dead_force(loads)?;
        let mut q = match q0 {
            Some(q0) => {
                check_len("q0", robot.n_q(), q0.len())?;
                crate::error::check_all_finite("q0", q0)?;
                q0.to_vec()
            }
            None => robot.arc_configuration(&loads.pressures_pa),
        };
        // the clamp: base position and direction prescribed, stretch kept
        let mut base = robot.base_node().to_vec();
        let stretch = robot.restrict(&{
            let mut d = vec![0.0; robot.n_q()];
            d[..nd]
                .iter_mut()
                .zip(q.iter().zip(robot.base_node()))
                .for_each(|(d, (a, b))| *d = a - b);
            d
        })?;
        let free_dirs = robot.expand_step(&{
            let mut u = vec![0.0; robot.n_free()];
            u[..robot.n_base_free()].copy_from_slice(&stretch[..robot.n_base_free()]);
            u
        })?;
        base.iter_mut().zip(&free_dirs).for_each(|(b, d)| *b += d);
        q[..nd].copy_from_slice(&base);
        let n = robot.n_free();
        let mut w = Work {
            k: SymmetricMatrix::zeros(robot.tangent_pattern().clone()),
            solver,
            r: vec![0.0; n],
            iterations: 0,
            floor: 0.0,
            last_step: 0.0,
        };
        let scale = load_scale(robot, &dead, loads, &q)?;
        let offset = vec![0.0; n];
        let q_start = q.clone();
        let mut load_steps = 0;
        // loads so large that their norm overflows (or a start point where the
        // forces do): no tolerance can be stated, so no solve is attempted
        let mut status = if scale.is_finite() {
            self.newton(robot, &dead, loads, &offset, &mut q, &mut w, scale)?
        } else {
            StaticStatus::NonFinite {
                at: NonFiniteAt::Loads,
            }
        };
        if !status.is_converged() && scale.is_finite() {
            // Homotopy from the start point: R_λ(q) = Q(q; λ loads) − (1 − λ) Q(q_start; no loads).
            // At λ = 0 the start point is exact; the load-dependent part of the
            // tangent (the torques' Hessian) grows with λ, so iterates stay
            // near equilibria, where the tangent is positive definite.
            q.copy_from_slice(&q_start);
            let unloaded = loads.scaled(0.0);
            let zero_dead = vec![0.0; robot.n_q()];
            let mut r0 = vec![0.0; n];
            robot.residual_into(&q, &zero_dead, &unloaded, &mut r0)?;
            let mut lambda = 0.0;
            let mut step: f64 = 0.25;
            status = StaticStatus::LoadStepTooSmall { load_fraction: 0.0 };
            while w.iterations < self.settings.max_total_iterations {
                let target = (lambda + step).min(1.0);
                let off: Vec<f64> = r0.iter().map(|v| (1.0 - target) * v).collect();
                let dead_t: Vec<f64> = dead.iter().map(|v| target * v).collect();
                let loads_t = loads.scaled(target);
                let saved = q.clone();
                let before = w.iterations;
                let step_status =
                    self.newton(robot, &dead_t, &loads_t, &off, &mut q, &mut w, scale)?;
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
                    q = saved;
                    step *= 0.5;
                    if step < self.settings.min_load_step {
                        // a load step that ran out of iterations or found no
                        // descent: the homotopy stalled
                        status = match step_status {
                            StaticStatus::IterationLimit { .. }
                            | StaticStatus::LineSearchFailed => StaticStatus::LoadStepTooSmall {
                                load_fraction: lambda,
                            },
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
        }
        // final residual for the report
        robot.residual_into(&q, &dead, loads, &mut w.r)?;
        let res = norm2(&w.r);
        // no NaN leaves the library: a "converged" state with a non-finite
        // coordinate or residual is a failure
        if !(res.is_finite() && q.iter().all(|v| v.is_finite())) {
            status = StaticStatus::NonFinite {
                at: NonFiniteAt::Solution,
            };
        }
        let report = StaticReport {
            status,
            iterations: w.iterations,
            load_steps,
            residual_norm_n: finite_or_max(res),
            residual_tolerance_n: finite_or_max(self.settings.residual_tolerance * scale),
            residual_floor_n: finite_or_max(w.floor),
            load_scale_n: finite_or_max(scale),
            increment_norm_m: finite_or_max(w.last_step),
            wall_time_s: start.elapsed().as_secs_f64(),
        };
        if status.is_converged() {
            Ok(Equilibrium { q, report })
        } else {
            Err(Error::NotConverged {
                report: Box::new(report),
            })
        }
    }

    /// Newton iterations on `Q(q) − offset = 0` from `q` (updated in place).
    #[allow(clippy::too_many_arguments)]
    fn newton<E: Element>(
        &self,
        robot: &Robot<E>,
        dead: &[f64],
        loads: &Loads,
        offset: &[f64],
        q: &mut [f64],
        w: &mut Work<'_>,
        scale: f64,
    ) -> Result<StaticStatus> {
        let nd = E::NODE_DOFS;
        let d = E::DIM;
        let n = robot.n_free();
        let nq = robot.n_q();
        let tol = self.settings.residual_tolerance * scale;
        let xtol = self.settings.increment_tolerance * robot.length();
        let eval = |q: &[f64], r: &mut Vec<f64>| -> Result<f64> {
            robot.residual_into(q, dead, loads, r)?;
            r.iter_mut().zip(offset).for_each(|(a, b)| *a -= b);
            Ok(norm2(r))
        };
        let mut rn = eval(q, &mut w.r)?;
        let mut trial = q.to_vec();
        let mut r_trial = vec![0.0; n];
        let mut dq = vec![0.0; n];
        let mut energies = vec![0.0; robot.n_elements()];
        for _ in 0..self.settings.max_iterations {
            if !rn.is_finite() {
                return Ok(StaticStatus::NonFinite {
                    at: NonFiniteAt::Residual,
                });
            }
            if rn <= tol {
                return Ok(StaticStatus::Converged(StaticCriterion::Residual));
            }
            if w.iterations >= self.settings.max_total_iterations {
                return Ok(StaticStatus::IterationLimit {
                    iterations: w.iterations,
                });
            }
            robot.tangent_into(q, loads, &mut w.k)?;
            let qmax = q.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            w.floor = residual_floor(w.k.max_abs(), qmax, n);
            // At the round-off floor the residual cannot certify more digits,
            // but one more Newton step still can gain them (the floor does not
            // shrink with the load; stopping here left small-load solves 1e-11 m
            // short): take it, keep it unless it raises the residual, stop.
            let at_floor = rn <= w.floor;
            w.iterations += 1;
            // Newton direction; if it does not descend the potential (Q·dq <= 0,
            // an indefinite tangent far from equilibrium), shift the diagonal:
            // K + μ diag|K| with growing μ, until it does.
            // Jacobi-scaled factorization (the rows of a fine cable's tangent
            // span many orders of magnitude: bending ∝ L_e⁻³, axial on the
            // slopes ∝ L_e). If the direction does not descend the potential
            // (Q·dq <= 0: an indefinite tangent far from equilibrium), shift
            // the scaled diagonal with growing μ until it does.
            // (the tangent is symmetric: L D Lᵀ when positive definite, the
            // pivoted LU otherwise, neither consuming it)
            let mut found = false;
            for mu in [0.0, 1e-8, 1e-6, 1e-4, 1e-2, 1.0] {
                let options = FactorOptions {
                    shift: mu,
                    ..FactorOptions::default()
                };
                let lu = match w.solver.factor(&w.k, options) {
                    Ok(lu) => lu,
                    Err(LinsolveError::Singular { .. }) => continue,
                    Err(LinsolveError::NonFinite { .. }) => {
                        return Ok(StaticStatus::NonFinite {
                            at: NonFiniteAt::Tangent,
                        });
                    }
                    Err(e) => return Err(e.into()),
                };
                dq.copy_from_slice(&w.r);
                lu.solve_in_place(&mut dq)?;
                let slope: f64 = w.r.iter().zip(&dq).map(|(a, b)| a * b).sum();
                if slope > 0.0 && dq.iter().all(|v| v.is_finite()) {
                    found = true;
                    break;
                }
            }
            if !found {
                return Ok(StaticStatus::SingularTangent);
            }
            let dq_full = robot.expand_step(&dq)?;
            // cap the slope change
            let mut slope_change = 0.0f64;
            for node in 0..nq / nd {
                for i in d..2 * d {
                    slope_change = slope_change.max(dq_full[node * nd + i].abs());
                }
            }
            let mut t = if slope_change > self.settings.max_step_rotation {
                self.settings.max_step_rotation / slope_change
            } else {
                1.0
            };
            let step_inf = dq_full.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if at_floor {
                for ((v, a), b) in trial.iter_mut().zip(q.iter()).zip(&dq_full) {
                    *v = a + b;
                }
                let rt = eval(&trial, &mut r_trial)?;
                if rt.is_finite() && rt <= rn {
                    q.copy_from_slice(&trial);
                    std::mem::swap(&mut w.r, &mut r_trial);
                    w.last_step = step_inf;
                }
                return Ok(StaticStatus::Converged(StaticCriterion::RoundOffFloor));
            }
            // the element energies at q, once for all trials
            robot.element_energies_into(q, &mut energies)?;
            let offset_slope: f64 = offset.iter().zip(&dq).map(|(a, b)| a * b).sum();
            // Π decreases along dq when Q·dq > 0 (K positive along dq).
            let slope: f64 = w.r.iter().zip(&dq).map(|(a, b)| a * b).sum();
            let mut accepted = false;
            for _ in 0..30 {
                for ((v, a), b) in trial.iter_mut().zip(q.iter()).zip(&dq_full) {
                    *v = a + t * b;
                }
                let rt = eval(&trial, &mut r_trial)?;
                if rt.is_finite() {
                    let offset_work = t * offset_slope;
                    let dpi = robot.potential_change_from(q, &energies, &trial, dead, loads)?
                        + offset_work;
                    let energy_ok = dpi <= -1e-4 * t * slope;
                    let residual_ok = rt * rt <= (1.0 - 1e-4 * t) * rn * rn;
                    if energy_ok || residual_ok {
                        accepted = true;
                        break;
                    }
                }
                t *= 0.5;
            }
            if !accepted {
                // no decrease along the Newton direction: at the floor or stuck
                if step_inf <= xtol {
                    return Ok(StaticStatus::Converged(StaticCriterion::Increment));
                }
                return Ok(StaticStatus::LineSearchFailed);
            }
            q.copy_from_slice(&trial);
            std::mem::swap(&mut w.r, &mut r_trial);
            rn = norm2(&w.r);
            w.last_step = t * step_inf;
            if t == 1.0 && step_inf <= xtol {
                return Ok(StaticStatus::Converged(StaticCriterion::Increment));
            }
        }
        if rn <= tol.max(w.floor) {
            return Ok(StaticStatus::Converged(StaticCriterion::Residual));
        }
        Ok(StaticStatus::IterationLimit {
            iterations: w.iterations,
        })
    }
}

/// The round-off floor of the equilibrium residual `|Q|_2` (N) at a
/// configuration whose largest coordinate is `q_max_abs` (m), with a tangent
/// stiffness whose largest entry is `k_max_abs` over `n_free` free
/// coordinates: `ε |K|_max |q|_∞ · max(1, 0.05 √n_free)`. Below it the
/// residual cannot certify more digits; the static solver stops there (after
/// one more Newton step) and the SQP estimator calls an iterate feasible
/// there.
///
/// # Example
/// ```
/// let floor = softrod::statics::residual_floor(1e4, 0.24, 84);
/// assert!((floor - f64::EPSILON * 1e4 * 0.24).abs() < 1e-25);
/// ```
pub fn residual_floor(k_max_abs: f64, q_max_abs: f64, n_free: usize) -> f64 {
    f64::EPSILON * k_max_abs * q_max_abs * (FLOOR_SQRT_N * (n_free as f64).sqrt()).max(1.0)
}

/// The floor's growth with the number of free coordinates,
/// `max(1, FLOOR_SQRT_N √n_free)`.
/// Calibrated by running Newton far past convergence: on a cantilever under a
/// uniform load (8 to 2048 elements) the residual stagnates at 0.05 to 0.47
/// times `ε |K|_max |q|_∞` (0.22 at 8 elements, 0.08 at 32, 0.13 at 128,
/// 0.25 at 512, 0.45 at 2048); on the default two-section scene at 2000
/// elements at about 1.3 times. The envelope puts the floor 2 to 5 times above
/// the stagnation level at every size. (An earlier `0.02 √n` fell below it on
/// small meshes: a 14-element solve ended at 1.15 times that floor.) The
/// solver takes one more Newton step when it reaches the floor, so a
/// conservative floor costs no accuracy.
const FLOOR_SQRT_N: f64 = 0.05;

/// Norm of the applied generalized forces at `q`: dead loads plus actuation
/// and concentrated moments (N).
fn load_scale<E: Element>(robot: &Robot<E>, dead: &[f64], loads: &Loads, q: &[f64]) -> Result<f64> {
    let mut applied = robot.restrict(dead)?;
    // the moment terms (actuation and concentrated moments), directly
    let mut m = vec![0.0; robot.n_free()];
    robot.moment_force_into(q, loads, &mut m)?;
    applied.iter_mut().zip(&m).for_each(|(a, b)| *a += b);
    Ok(norm2(&applied))
}

/// `v`, or `f64::MAX` in place of an infinity or NaN: every number of a
/// report is finite.
fn finite_or_max(v: f64) -> f64 {
    if v.is_finite() {
        v
    } else {
        f64::MAX
    }
}
