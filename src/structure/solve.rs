//! Newton's method on a structure's equilibrium (17) in its free
//! coordinates, `R(u) = 0`, with `K_u du = R` per iteration, equal load
//! steps and a backtracking line search on the total potential.
//!
//! The linear solve is one function, [`solve_tangent`] (a dense LU of the
//! assembled entries); a sparse factorization with its symbolic analysis
//! reused across iterations replaces it without touching the rest.

use serde::{Deserialize, Serialize};

use super::{Structure, StructureLoads, Triplets};
use crate::element::Element;
use crate::error::{check_len, Error, Result};

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
}

impl Default for NewtonSettings {
    fn default() -> Self {
        NewtonSettings {
            max_iterations: 50,
            tolerance: 1e-10,
            load_steps: 1,
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

/// How [`solve_equilibrium`] ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NewtonStatus {
    /// `‖R‖∞ ≤ tolerance · scale` at the full load.
    Converged {
        /// Newton iterations over all load steps.
        iterations: usize,
    },
    /// A load step used up its iterations.
    IterationLimit {
        /// The load factor of the step that did not converge.
        load_factor: f64,
    },
    /// No step length in the line search lowered the potential or the
    /// residual.
    LineSearchFailed {
        /// The load factor of the step that stalled.
        load_factor: f64,
    },
}

/// The outcome of [`solve_equilibrium`]: the last iterate and its status
/// (not converged is not an error: the caller decides).
#[derive(Debug, Clone, PartialEq)]
pub struct StructureEquilibrium {
    /// Free coordinates.
    pub u: Vec<f64>,
    /// All coordinates, `φ(u)`.
    pub q: Vec<f64>,
    /// How the solve ended.
    pub status: NewtonStatus,
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
        matches!(self.status, NewtonStatus::Converged { .. })
    }
}

/// Solves `K du = r` for the assembled tangent `k` (entries summed into a
/// dense matrix, LU with partial pivoting).
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
    let singular = |index: usize| Error::Singular {
        context: "structure tangent (dense LU)".into(),
        index,
        pivot: 0.0,
        scale: 0.0,
    };
    let x = k
        .to_dense()
        .lu()
        .solve(&nalgebra::DVector::from_column_slice(r))
        .ok_or_else(|| singular(0))?;
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        return Err(singular(i));
    }
    Ok(x.as_slice().to_vec())
}

fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

/// Newton's method on `R(u) = 0` from `u0` (default: the straight
/// reference, [`Structure::reference_free_coordinates`]), in
/// `settings.load_steps` equal load steps.
///
/// # Errors
/// The errors of [`NewtonSettings::validate`], [`Structure::dead_force`]
/// and [`solve_tangent`]; [`Error::DimensionMismatch`] for a `u0` of the
/// wrong size; [`Error::NonFinite`] if an iterate stops being finite.
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
pub fn solve_equilibrium<E: Element>(
    structure: &Structure<E>,
    loads: &StructureLoads,
    u0: Option<&[f64]>,
    settings: &NewtonSettings,
) -> Result<StructureEquilibrium> {
    settings.validate()?;
    structure.validate_loads(loads)?;
    let mut u = match u0 {
        Some(u0) => {
            check_len("u0", structure.n_free(), u0.len())?;
            u0.to_vec()
        }
        None => structure.reference_free_coordinates().to_vec(),
    };
    let n = structure.n_free();
    let mut r = vec![0.0; n];
    let mut k = Triplets::new(n);
    let mut iterations = 0;
    let mut floor = 0.0;
    let steps = settings.load_steps;
    for step in 1..=steps {
        let factor = step as f64 / steps as f64;
        let scaled = if steps == 1 {
            loads.clone()
        } else {
            loads.scaled(factor)
        };
        let dead = structure.dead_force(&scaled)?;
        let mut applied = vec![0.0; n];
        structure.dof_map().restrict_into(&u, &dead, &mut applied)?;
        structure.residual_and_tangent_into(&u, &dead, &scaled, &mut r, &mut k)?;
        let scale = norm_inf(&applied).max(norm_inf(&r));
        let target = settings.tolerance * scale;
        let mut converged = false;
        for _ in 0..settings.max_iterations {
            if norm_inf(&r) <= target {
                converged = true;
                break;
            }
            floor = 10.0 * f64::EPSILON * k.max_abs() * norm_inf(&u);
            let at_floor = norm_inf(&r) <= floor;
            iterations += 1;
            let du = solve_tangent(&k, &r)?;
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
                let dpi = structure.potential_change(&u, &trial, &dead, &scaled)?;
                let rt = structure.residual(&trial, &dead, &scaled)?;
                if dpi <= -1e-4 * alpha * slope.max(0.0) || norm_inf(&rt) < r0 {
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
                    structure.residual_and_tangent_into(&u, &dead, &scaled, &mut r, &mut k)?;
                }
                converged = true;
                break;
            }
            let Some(next) = accepted else {
                return finish(
                    structure,
                    u,
                    &r,
                    floor,
                    iterations,
                    NewtonStatus::LineSearchFailed {
                        load_factor: factor,
                    },
                );
            };
            u = next;
            structure.residual_and_tangent_into(&u, &dead, &scaled, &mut r, &mut k)?;
        }
        if !converged && norm_inf(&r) > target {
            return finish(
                structure,
                u,
                &r,
                floor,
                iterations,
                NewtonStatus::IterationLimit {
                    load_factor: factor,
                },
            );
        }
    }
    finish(
        structure,
        u,
        &r,
        floor,
        iterations,
        NewtonStatus::Converged { iterations },
    )
}

fn finish<E: Element>(
    structure: &Structure<E>,
    u: Vec<f64>,
    r: &[f64],
    floor: f64,
    iterations: usize,
    status: NewtonStatus,
) -> Result<StructureEquilibrium> {
    let q = structure.configuration(&u)?;
    Ok(StructureEquilibrium {
        u,
        q,
        status,
        residual_n: norm_inf(r),
        residual_floor_n: floor,
        iterations,
    })
}
