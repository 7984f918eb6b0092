//! The one clarabel call: a convex cone program `min ½xᵀPx + qᵀx` subject
//! to `Ax + s = b`, `s ∈ K`, solved to stated tolerances, with its primal
//! `x`, slacks `s` and multipliers `z` (what the contact QP, the bounded
//! SQP subproblem and the grasp's friction programs read).

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

/// Clarabel's stopping tolerances (dimensionless, in the scaled program's
/// units): the absolute and relative duality gap and the feasibility.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Tolerances {
    pub gap_abs: f64,
    pub gap_rel: f64,
    pub feas: f64,
}

impl Tolerances {
    /// The same tolerance for the gaps and the feasibility.
    pub(crate) const fn all(tol: f64) -> Tolerances {
        Tolerances {
            gap_abs: tol,
            gap_rel: tol,
            feas: tol,
        }
    }
}

/// Clarabel's iteration limit for every program of the crate.
const MAX_ITERATIONS: u32 = 200;

/// A solved program: the primal `x`, the cone slacks `s` and the
/// multipliers `z` (one per constraint row), every entry finite.
#[derive(Debug, Clone)]
pub(crate) struct Solution {
    pub x: Vec<f64>,
    pub s: Vec<f64>,
    pub z: Vec<f64>,
}

/// Why a program has no solution: clarabel refused the settings or the
/// program's data (its message), or it stopped without one (its status; a
/// "solved" answer with a non-finite entry is `NumericalError`).
#[derive(Debug, Clone)]
pub(crate) enum Failure {
    Rejected(String),
    Status(SolverStatus),
}

impl Failure {
    /// Clarabel's status for the failure (`Unsolved` for a refused program).
    pub(crate) fn status(&self) -> SolverStatus {
        match self {
            Failure::Rejected(_) => SolverStatus::Unsolved,
            Failure::Status(s) => *s,
        }
    }
}

/// Solves `min ½xᵀPx + qᵀx` s.t. `b − Ax ∈ cones` (P upper triangular)
/// with clarabel to `tol`, at most 200 iterations. A status other than
/// `Solved` or `AlmostSolved`, or a non-finite entry of `x`, `s` or `z`, is
/// a [`Failure`].
pub(crate) fn solve(
    p: &CscMatrix<f64>,
    q: &[f64],
    a: &CscMatrix<f64>,
    b: &[f64],
    cones: &[SupportedConeT<f64>],
    tol: Tolerances,
) -> Result<Solution, Failure> {
    let settings = DefaultSettingsBuilder::default()
        .verbose(false)
        .tol_gap_abs(tol.gap_abs)
        .tol_gap_rel(tol.gap_rel)
        .tol_feas(tol.feas)
        .max_iter(MAX_ITERATIONS)
        .build()
        .map_err(|e| Failure::Rejected(format!("{e:?}")))?;
    let mut solver = DefaultSolver::new(p, q, a, b, cones, settings)
        .map_err(|e| Failure::Rejected(format!("{e:?}")))?;
    solver.solve();
    let sol = &solver.solution;
    if !matches!(
        sol.status,
        SolverStatus::Solved | SolverStatus::AlmostSolved
    ) {
        return Err(Failure::Status(sol.status));
    }
    if !sol
        .x
        .iter()
        .chain(&sol.s)
        .chain(&sol.z)
        .all(|v| v.is_finite())
    {
        return Err(Failure::Status(SolverStatus::NumericalError));
    }
    Ok(Solution {
        x: sol.x.clone(),
        s: sol.s.clone(),
        z: sol.z.clone(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use clarabel::solver::NonnegativeConeT;

    /// `min ½x² − x` s.t. `x ≤ 0.5`: the bound is active, `x = 0.5`, its
    /// multiplier `z = 0.5` (the gradient `x − 1` balanced), slack 0.
    #[test]
    fn a_bounded_scalar_program_has_its_closed_form() {
        let p = CscMatrix::new_from_triplets(1, 1, vec![0], vec![0], vec![1.0]);
        let a = CscMatrix::new_from_triplets(1, 1, vec![0], vec![0], vec![1.0]);
        let sol = solve(
            &p,
            &[-1.0],
            &a,
            &[0.5],
            &[NonnegativeConeT(1)],
            Tolerances::all(1e-10),
        )
        .unwrap();
        assert!((sol.x[0] - 0.5).abs() < 1e-8, "{:?}", sol);
        assert!((sol.z[0] - 0.5).abs() < 1e-8, "{:?}", sol);
        assert!(sol.s[0].abs() < 1e-8, "{:?}", sol);
    }

    /// `x ≤ −1` and `−x ≤ −1` (x ≥ 1) together: infeasible, a failure with
    /// clarabel's status, never a solution.
    #[test]
    fn an_infeasible_program_is_a_failure() {
        let p = CscMatrix::new_from_triplets(1, 1, vec![0], vec![0], vec![1.0]);
        let a = CscMatrix::new_from_triplets(2, 1, vec![0, 1], vec![0, 0], vec![1.0, -1.0]);
        let r = solve(
            &p,
            &[0.0],
            &a,
            &[-1.0, -1.0],
            &[NonnegativeConeT(2)],
            Tolerances::all(1e-10),
        );
        let status = r.unwrap_err().status();
        assert!(
            matches!(
                status,
                SolverStatus::PrimalInfeasible | SolverStatus::AlmostPrimalInfeasible
            ),
            "{status:?}"
        );
    }
}
