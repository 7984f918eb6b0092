//! Newton's method on a model's equilibrium (17) in its free
//! coordinates, `R(u) = 0` with `q = φ(u)`, for any [`Assembled`] model (a
//! structure, the clamped robot): `K_u du = R` per iteration, equal load
//! steps and a backtracking line search on the total potential.
//!
//! The tangent is assembled on the model's sparsity pattern, analyzed once
//! per solve by an [`AutoSolver`] (banded or sparse, [`NewtonSettings::linear_solver`])
//! and factored numerically at every iteration.

use serde::{Deserialize, Serialize};

use super::model::{pattern_of, symmetric_from_triplets};
use super::{Assembled, Triplets};
use crate::error::{check_len, Error, Result};
use crate::linsolve::{
    AutoSolver, FactorOptions, Factorization, SolverKind, SymmetricMatrix, TangentSolver,
};
use crate::outcome::{StaticCriterion, StaticStatus};

/// Settings of [`solve_equilibrium`].
///
/// # Example
/// ```
/// let s = softrod::structure::solve::NewtonSettings::default();
/// assert_eq!((s.max_iterations, s.load_steps), (50, 1));
/// s.validate().unwrap();
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NewtonSettings {
    /// Largest number of Newton iterations per load step (default 50).
    pub max_iterations: usize,
    /// Converged when `‖R‖∞ ≤ tolerance · scale`, `scale` the larger of
    /// the restricted dead forces `‖Tᵀ f_dead‖∞` and the first residual
    /// (default 1e-10), or when a Newton step from the round-off floor
    /// `10 ε |K_u|_max |u|_∞` has been taken (a smaller residual cannot be
    /// certified, but that step still gains digits).
    pub tolerance: f64,
    /// Number of equal load steps: the loads scaled by `k / load_steps`
    /// (weights always whole) (default 1).
    pub load_steps: usize,
    /// The linear solver of the tangent (default [`SolverKind::Auto`]:
    /// banded for a single chain, sparse otherwise).
    #[serde(default)]
    pub linear_solver: SolverKind,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        NewtonSettings {
            max_iterations: 50,
            tolerance: 1e-10,
            load_steps: 1,
            linear_solver: SolverKind::Auto,
        }
    }
}

impl NewtonSettings {
    /// Checks the settings.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field for no iterations, a
    /// tolerance that is not finite and positive, or load steps outside
    /// `1 ..= 10000`.
    pub fn validate(&self) -> Result<()> {
        if self.max_iterations == 0 {
            return Err(Error::invalid("newton.max_iterations", 0, "must be >= 1"));
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return Err(Error::invalid(
                "newton.tolerance",
                self.tolerance,
                "must be finite and > 0",
            ));
        }
        if !(1..=10_000).contains(&self.load_steps) {
            return Err(Error::invalid(
                "newton.load_steps",
                self.load_steps,
                "must lie in 1 ..= 10000",
            ));
        }
        Ok(())
    }
}

/// The outcome of [`solve_equilibrium`]: the last iterate and its status
/// (not converged is not an error: the caller decides).
#[derive(Debug, Clone, PartialEq)]
pub struct StructureEquilibrium {
    /// Free coordinates.
    pub u: Vec<f64>,
    /// All coordinates, `φ(u)`.
    pub q: Vec<f64>,
    /// How the solve ended (the static solver's status: converged by the
    /// residual test or at the round-off floor, iteration limit of a load
    /// step, line search failed).
    pub status: StaticStatus,
    /// The load fraction of the last load step taken (1 when converged).
    pub load_fraction: f64,
    /// `‖R‖∞` at `u` (N).
    pub residual_n: f64,
    /// The round-off floor of `‖R‖∞` at the last tangent (N).
    pub residual_floor_n: f64,
    /// Newton iterations over all load steps.
    pub iterations: usize,
}

impl StructureEquilibrium {
    /// Whether the solve converged.
    pub fn converged(&self) -> bool {
        self.status.is_converged()
    }
}

/// Solves `K du = r` for the assembled tangent `k` (its symmetric part on
/// the pattern of its entries, factored by an [`AutoSolver`]: one solve; a
/// Newton method keeps its solver and factors on the same pattern).
///
/// # Errors
/// [`Error::DimensionMismatch`] if `r` does not have `k.n()` entries;
/// [`Error::Singular`] if the factorization fails or the solution is not
/// finite.
///
/// # Example
/// ```
/// use softrod::loads::force_field::StiffnessSink;
/// use softrod::structure::{solve::solve_tangent, Triplets};
/// let mut k = Triplets::new(2);
/// k.add(0, 0, 2.0);
/// k.add(1, 1, 4.0);
/// assert_eq!(solve_tangent(&k, &[2.0, 2.0]).unwrap(), vec![1.0, 0.5]);
/// ```
pub fn solve_tangent(k: &Triplets, r: &[f64]) -> Result<Vec<f64>> {
    check_len("r", k.n(), r.len())?;
    let pattern = std::sync::Arc::new(pattern_of(k)?);
    let mut m = SymmetricMatrix::zeros(pattern.clone());
    symmetric_from_triplets(k, &pattern, &mut m)?;
    let mut solver = AutoSolver::analyze(&pattern)?;
    factor_and_solve(&mut solver, &m, r)
}

/// Factors `k` with `solver` and solves `K x = r`.
fn factor_and_solve(solver: &mut AutoSolver, k: &SymmetricMatrix, r: &[f64]) -> Result<Vec<f64>> {
    let mut x = r.to_vec();
    solver
        .factor(k, FactorOptions::default())?
        .solve_in_place(&mut x)?;
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(Error::Singular {
            context: "tangent solve (non-finite step)".into(),
            index: i,
            pivot: 0.0,
            scale: 0.0,
        });
    }
    Ok(x)
}

fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// Newton's method on `R(u) = 0` from `u0` (default: the straight
/// reference, [`Assembled::reference_free_coordinates`]), in
/// `settings.load_steps` equal load steps.
///
/// # Errors
/// The errors of [`NewtonSettings::validate`], [`Assembled::dead_force`]
/// and the tangent's factorization; [`Error::DimensionMismatch`] for a `u0`
/// of the wrong size; [`Error::NonFinite`] if an iterate stops being finite.
///
/// # Example
/// ```
/// use softrod::assembly::Section;
/// use softrod::loads::{Loads, PointForce};
/// use softrod::structure::{solve::{solve_equilibrium, NewtonSettings}, RodSpec, StructureLoads, StructureSpec};
/// let mut spec = StructureSpec::new(vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)],
///     vec![0.0, 0.0], vec![1.0, 0.0])], vec![], vec![]);
/// spec.gravity_m_per_s2 = vec![0.0, 0.0];
/// let s = spec.build_planar().unwrap();
/// // a small tip force: the cantilever's P L³ / (3 EI)
/// let loads = StructureLoads { rods: vec![Loads { point_forces: vec![PointForce { s_m: 0.2, force_n: vec![0.0, -1e-4] }], ..Loads::default() }], ..Default::default() };
/// let eq = solve_equilibrium(&s, &loads, None, &NewtonSettings::default()).unwrap();
/// assert!(eq.converged());
/// let tip = eq.q[4 * 4 + 1];
/// assert!((tip + 1e-4 * 0.008 / (3.0 * 0.02)).abs() < 1e-3 * 1e-4 * 0.008 / 0.06);
/// ```
pub fn solve_equilibrium<M: Assembled>(
    structure: &M,
    loads: &M::Loads,
    u0: Option<&[f64]>,
    settings: &NewtonSettings,
) -> Result<StructureEquilibrium> {
    settings.validate()?;
    let pattern = structure.tangent_pattern()?;
    let mut solver = AutoSolver::with_kind(&pattern, settings.linear_solver)?;
    solve_equilibrium_with(structure, loads, u0, settings, &mut solver)
}

/// [`solve_equilibrium`] with a solver analyzed before, on the model's
/// [`Assembled::tangent_pattern`] (a caller that solves one model many
/// times analyzes once; `settings.linear_solver` is then not read).
///
/// # Errors
/// As [`solve_equilibrium`];
/// [`crate::Error::InvalidParameter`] (field `solver`) for a solver
/// analyzed on another pattern.
///
/// # Example
/// ```
/// use softrod::assembly::{RobotSpec, Section};
/// use softrod::linsolve::{AutoSolver, SolverKind};
/// use softrod::loads::Loads;
/// use softrod::structure::solve::{solve_equilibrium_with, NewtonSettings};
/// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 8)]).build_planar()?;
/// let mut solver = AutoSolver::with_kind(robot.tangent_pattern(), SolverKind::Sparse)?;
/// let settings = NewtonSettings::default();
/// let a = solve_equilibrium_with(&robot, &Loads::default(), None, &settings, &mut solver)?;
/// let mut light = Loads::default();
/// light.point_forces = vec![softrod::loads::PointForce { s_m: 0.2, force_n: vec![0.0, 1e-3] }];
/// let b = solve_equilibrium_with(&robot, &light, Some(&a.u), &settings, &mut solver)?;
/// assert!(a.converged() && b.converged() && b.q[b.q.len() - 3] > a.q[a.q.len() - 3]);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn solve_equilibrium_with<M: Assembled>(
    structure: &M,
    loads: &M::Loads,
    u0: Option<&[f64]>,
    settings: &NewtonSettings,
    solver: &mut AutoSolver,
) -> Result<StructureEquilibrium> {
    settings.validate()?;
    structure.validate_loads(loads)?;
    let mut u = match u0 {
        Some(u0) => {
            check_len("u0", structure.n_free(), u0.len())?;
            u0.to_vec()
        }
        None => structure.reference_free_coordinates(),
    };
    let n = structure.n_free();
    let pattern = solver.pattern().clone();
    if pattern.n() != n {
        return Err(Error::invalid(
            "solver",
            pattern.n(),
            "analyzed for another pattern than the model's tangent",
        ));
    }
    let mut r = vec![0.0; n];
    let mut k = SymmetricMatrix::zeros(pattern);
    let mut q = vec![0.0; structure.n_q()];
    let mut q_trial = q.clone();
    let mut r_trial = r.clone();
    let mut iterations = 0;
    let mut floor = 0.0;
    let mut criterion = StaticCriterion::Residual;
    let steps = settings.load_steps;
    for step in 1..=steps {
        let factor = step as f64 / steps as f64;
        let scaled = if steps == 1 {
            loads.clone()
        } else {
            structure.scaled_loads(loads, factor)
        };
        let dead = structure.dead_force(&scaled)?;
        let mut applied = vec![0.0; n];
        structure.restrict_into(&u, &dead, &mut applied)?;
        structure.configuration_into(&u, &mut q)?;
        structure.residual_and_tangent_into(&u, &q, &dead, &scaled, &mut r, &mut k)?;
        let scale = norm_inf(&applied).max(norm_inf(&r));
        let target = settings.tolerance * scale;
        let mut converged = false;
        for _ in 0..settings.max_iterations {
            if norm_inf(&r) <= target {
                converged = true;
                criterion = StaticCriterion::Residual;
                break;
            }
            floor = 10.0 * f64::EPSILON * k.max_abs() * norm_inf(&u);
            let at_floor = norm_inf(&r) <= floor;
            iterations += 1;
            let du = factor_and_solve(solver, &k, &r)?;
            // backtracking: accept a step that lowers the potential
            // (Armijo) or the residual
            let slope: f64 = r.iter().zip(&du).map(|(a, b)| a * b).sum();
            let r0 = norm_inf(&r);
            let mut alpha = 1.0;
            let mut accepted = None;
            for _ in 0..30 {
                let trial: Vec<f64> = u.iter().zip(&du).map(|(a, b)| a + alpha * b).collect();
                if trial.iter().any(|v| !v.is_finite()) {
                    return Err(Error::NonFinite {
                        context: "structure Newton iterate".into(),
                    });
                }
                structure.configuration_into(&trial, &mut q_trial)?;
                let dpi = structure.potential_change(&u, &q, &trial, &q_trial, &dead, &scaled)?;
                structure.residual_into(&trial, &q_trial, &dead, &scaled, &mut r_trial)?;
                if dpi <= -1e-4 * alpha * slope.max(0.0) || norm_inf(&r_trial) < r0 {
                    accepted = Some(trial);
                    break;
                }
                alpha *= 0.5;
            }
            if at_floor {
                // one step from the floor: keep it if it does not raise the
                // residual, and stop
                if let Some(next) = accepted {
                    u = next;
                    structure.configuration_into(&u, &mut q)?;
                    structure.residual_and_tangent_into(&u, &q, &dead, &scaled, &mut r, &mut k)?;
                }
                converged = true;
                criterion = StaticCriterion::RoundOffFloor;
                break;
            }
            let Some(next) = accepted else {
                return finish(
                    structure,
                    u,
                    &r,
                    floor,
                    iterations,
                    StaticStatus::LineSearchFailed,
                    factor,
                );
            };
            u = next;
            structure.configuration_into(&u, &mut q)?;
            structure.residual_and_tangent_into(&u, &q, &dead, &scaled, &mut r, &mut k)?;
        }
        if !converged && norm_inf(&r) > target {
            return finish(
                structure,
                u,
                &r,
                floor,
                iterations,
                StaticStatus::IterationLimit { iterations },
                factor,
            );
        }
    }
    finish(
        structure,
        u,
        &r,
        floor,
        iterations,
        StaticStatus::Converged(criterion),
        1.0,
    )
}

fn finish<M: Assembled>(
    structure: &M,
    u: Vec<f64>,
    r: &[f64],
    floor: f64,
    iterations: usize,
    status: StaticStatus,
    load_fraction: f64,
) -> Result<StructureEquilibrium> {
    let mut q = vec![0.0; structure.n_q()];
    structure.configuration_into(&u, &mut q)?;
    Ok(StructureEquilibrium {
        u,
        q,
        status,
        load_fraction,
        residual_n: norm_inf(r),
        residual_floor_n: floor,
        iterations,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The clamped robot, an [`Assembled`] model: Newton in its free
    /// coordinates with either linear solver reaches the static solver's
    /// equilibrium of the paper's two-section robot (weight, pressures, a
    /// tip force, a moment).
    #[test]
    fn the_robot_through_the_trait_reaches_the_static_equilibrium() {
        let scene = crate::scene::Scene::two_section();
        let robot = scene.robot().unwrap();
        let loads = scene.loads().unwrap();
        let reference = crate::statics::StaticSolver::default()
            .solve(&robot, &loads, None)
            .unwrap();
        let scale = reference.q.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for kind in [SolverKind::Auto, SolverKind::Sparse] {
            let settings = NewtonSettings {
                linear_solver: kind,
                tolerance: 1e-12,
                ..NewtonSettings::default()
            };
            let eq = solve_equilibrium(&robot, &loads, None, &settings).unwrap();
            assert!(eq.converged(), "{kind:?}: {:?}", eq.status);
            let diff =
                eq.q.iter()
                    .zip(&reference.q)
                    .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(diff <= 1e-10 * scale, "{kind:?}: {diff:e} of {scale:e}");
        }
    }

    /// The statuses are the static solver's: a converged solve names its
    /// test, a load step that runs out of iterations says so with the
    /// iterations spent and the load fraction it was at.
    #[test]
    fn statuses_are_the_static_solvers() {
        let scene = crate::scene::Scene::two_section();
        let robot = scene.robot().unwrap();
        let loads = scene.loads().unwrap();
        let eq = solve_equilibrium(&robot, &loads, None, &NewtonSettings::default()).unwrap();
        assert!(
            matches!(eq.status, StaticStatus::Converged(_)) && eq.load_fraction == 1.0,
            "{:?}",
            eq.status
        );
        let settings = NewtonSettings {
            max_iterations: 1,
            load_steps: 4,
            ..NewtonSettings::default()
        };
        let eq = solve_equilibrium(&robot, &loads, None, &settings).unwrap();
        assert!(!eq.converged());
        assert_eq!(eq.status, StaticStatus::IterationLimit { iterations: 1 });
        assert_eq!(eq.load_fraction, 0.25);
    }

    /// The one-shot solve of a list of entries: the symmetric part, on the
    /// entries' pattern.
    #[test]
    fn solve_tangent_solves_a_coupled_system() {
        use crate::loads::force_field::StiffnessSink;
        let mut k = Triplets::new(3);
        for (i, j, v) in [
            (0, 0, 4.0),
            (1, 1, 3.0),
            (2, 2, 2.0),
            (0, 2, 1.0),
            (2, 0, 1.0),
        ] {
            k.add(i, j, v);
        }
        let x = solve_tangent(&k, &[5.0, 3.0, 3.0]).unwrap();
        for (a, b) in x.iter().zip([1.0, 1.0, 1.0]) {
            assert!((a - b).abs() < 1e-14, "{x:?}");
        }
    }
}
