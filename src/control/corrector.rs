//! The inverse kinematics' corrector as it was before the one generic
//! tracker (kept for the comparison of old and new only).
#![allow(dead_code, missing_docs, clippy::all)]

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::Result;
use crate::linsolve::{
    AutoFactors, AutoSolver, FactorOptions, Factorization, SymmetricMatrix, TangentSolver,
};
use crate::loads::Loads;
use crate::numeric::norm2;
use crate::statics::StaticSettings;
use crate::structure::Assembled;

/// Newton steps the corrector takes at most (a warm start from the
/// sensitivities' prediction converges in one or two: measured on the
/// tracking bench's loop).
pub(crate) const MAX_STEPS: usize = 6;

/// A corrected equilibrium.
#[derive(Debug, Clone)]
pub(crate) struct Corrected {
    /// All coordinates.
    pub(crate) q: Vec<f64>,
    /// The factors of the tangent at `q` (positive definite).
    pub(crate) factors: AutoFactors,
}

/// The equilibrium of `robot` under `loads` from `q0`, or `None` when the
/// corrector gives up (see the module documentation); with the Newton
/// steps taken (at least 1: the static solver's count of the work).
pub(crate) fn correct<E: Element>(
    robot: &Robot<E>,
    loads: &Loads,
    q0: &[f64],
    settings: &StaticSettings,
    linear: &mut AutoSolver,
) -> (Option<Corrected>, usize) {
    let mut steps = 0;
    let out = attempt(robot, loads, q0, settings, linear, &mut steps)
        .ok()
        .flatten();
    (out, steps.max(1))
}

fn attempt<E: Element>(
    robot: &Robot<E>,
    loads: &Loads,
    q0: &[f64],
    settings: &StaticSettings,
    linear: &mut AutoSolver,
    steps: &mut usize,
) -> Result<Option<Corrected>> {
    let (n, nq) = (robot.n_free(), robot.n_q());
    let dead: Vec<f64> = robot.dead_force(loads)?.data.into();
    let mut u: Vec<f64> = robot.free_coordinates_of(q0)?.data.into();
    let mut q = vec![0.0; nq];
    robot.configuration_into(&u, &mut q)?;
    let mut r = vec![0.0; n];
    robot.applied_force_into(&u, &q, &dead, loads, &mut r)?;
    let tol = settings.residual_tolerance * norm2(&r);
    if !tol.is_finite() {
        return Ok(None);
    }
    let mut k = SymmetricMatrix::zeros(robot.tangent_pattern().clone());
    let (mut du, mut dq) = (vec![0.0; n], vec![0.0; nq]);
    let (mut u_next, mut q_next) = (u.clone(), q.clone());
    let mut previous = f64::INFINITY;
    loop {
        Robot::residual_and_tangent_into(robot, &q, &dead, loads, &mut r, &mut k)?;
        let rn = norm2(&r);
        if !(rn.is_finite() && rn < previous) {
            return Ok(None);
        }
        let factors = match linear.factor(&k, FactorOptions::default()) {
            Ok(f) if f.is_positive_definite() => f,
            _ => return Ok(None),
        };
        if rn <= tol {
            return Ok(Some(Corrected { q, factors }));
        }
        if *steps >= MAX_STEPS {
            return Ok(None);
        }
        *steps += 1;
        du.copy_from_slice(&r);
        factors.solve_in_place(&mut du)?;
        robot.step_into(&u, &du, &mut dq)?;
        let rotation = robot.step_rotation(&dq);
        if rotation.is_nan() || rotation > settings.max_step_rotation {
            return Ok(None);
        }
        robot.advance_into(&u, &q, &du, &dq, 1.0, &mut u_next, &mut q_next)?;
        std::mem::swap(&mut u, &mut u_next);
        std::mem::swap(&mut q, &mut q_next);
        previous = rn;
    }
}
