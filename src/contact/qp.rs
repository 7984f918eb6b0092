//! The SQP's quadratic subproblem: the step and the contact forces of one
//! linearization, by clarabel.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{NonnegativeConeT, SolverStatus, SupportedConeT};

use crate::cone::{self, Tolerances};
use nalgebra::DMatrix;

use super::Gap;

/// The QP `min ½ duᵀ H du − Qᵀ du` subject to `g + G du >= 0` and
/// `|du_j| <= bounds_j` by clarabel, on Jacobi-scaled unknowns and
/// unit-norm constraint rows, `H` shifted to positive definite if
/// needed: the step and the multipliers of the gaps.
pub(super) fn solve_qp(
    h: &DMatrix<f64>,
    r: &[f64],
    gaps: &[Gap],
    grads: &[Vec<f64>],
    bounds: &[f64],
) -> std::result::Result<(Vec<f64>, Vec<f64>), SolverStatus> {
    let n = h.nrows();
    let d: Vec<f64> = (0..n)
        .map(|i| {
            let v = h[(i, i)].abs();
            if v > 0.0 && v.is_finite() {
                1.0 / v.sqrt()
            } else {
                1.0
            }
        })
        .collect();
    let mut p = DMatrix::from_fn(n, n, |i, j| d[i] * h[(i, j)] * d[j]);
    let p0 = p.clone();
    for mu in [0.0, 1e-10, 1e-8, 1e-6, 1e-4, 1e-2, 1.0, 10.0] {
        p = p0.clone();
        for i in 0..n {
            p[(i, i)] += mu;
        }
        if p.clone().cholesky().is_some() {
            break;
        }
    }
    let (mut ri, mut ci, mut vi) = (Vec::new(), Vec::new(), Vec::new());
    for j in 0..n {
        for i in 0..=j {
            let v = p[(i, j)];
            if v != 0.0 {
                ri.push(i);
                ci.push(j);
                vi.push(v);
            }
        }
    }
    let p_mat = CscMatrix::new_from_triplets(n, n, ri, ci, vi);
    let c: Vec<f64> = (0..n).map(|i| -d[i] * r[i]).collect();
    let m = gaps.len();
    // each gap's row scaled to unit norm in the scaled unknowns
    let rho: Vec<f64> = grads
        .iter()
        .map(|g| {
            let v = g
                .iter()
                .zip(&d)
                .map(|(a, b)| (a * b).powi(2))
                .sum::<f64>()
                .sqrt();
            if v > 0.0 && v.is_finite() { v } else { 1.0 }
        })
        .collect();
    let (mut ri, mut ci, mut vi) = (Vec::new(), Vec::new(), Vec::new());
    for (row, g) in grads.iter().enumerate() {
        for (j, v) in g.iter().enumerate() {
            if *v != 0.0 {
                ri.push(row);
                ci.push(j);
                vi.push(-v * d[j] / rho[row]);
            }
        }
    }
    let mut b: Vec<f64> = gaps.iter().zip(&rho).map(|(g, s)| g.gap_m / s).collect();
    // the trust region: ±du_j <= bounds_j
    for (j, (dj, bj)) in d.iter().zip(bounds).enumerate() {
        for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
            ri.push(m + 2 * j + k);
            ci.push(j);
            vi.push(sign * dj);
            b.push(*bj);
        }
    }
    let a_mat = CscMatrix::new_from_triplets(m + 2 * n, n, ri, ci, vi);
    let cones: Vec<SupportedConeT<f64>> = vec![NonnegativeConeT(m + 2 * n)];
    let sol = cone::solve(&p_mat, &c, &a_mat, &b, &cones, Tolerances::all(1e-12))
        .map_err(|f| f.status())?;
    let du: Vec<f64> = sol.x.iter().zip(&d).map(|(x, d)| x * d).collect();
    // complementarity: the multiplier of a gap the step leaves open (its
    // slack above its multiplier, both in the scaled problem's units) is
    // the interior point's residue, not a force. Measured: a finger
    // released from the object, every multiplier ~1e-14 N, all of them
    // "active" under the ratio to the largest; the polish's KKT system
    // with dozens of constraints at the fingertip diverged and the solve
    // ended with LineSearchFailed (4 trials of the simulated Table I)
    let lambda: Vec<f64> = sol.z[..m]
        .iter()
        .zip(&sol.s[..m])
        .zip(&rho)
        .map(|((z, sl), s)| {
            if z > sl || no_complementarity() {
                (z / s).max(0.0)
            } else {
                0.0
            }
        })
        .collect();
    if !du.iter().chain(&lambda).all(|v| v.is_finite()) {
        return Err(SolverStatus::NumericalError);
    }
    Ok((du, lambda))
}

#[cfg(test)]
fn no_complementarity() -> bool {
    super::faults::NO_COMPLEMENTARITY.with(|f| f.get())
}

#[cfg(not(test))]
fn no_complementarity() -> bool {
    false
}
