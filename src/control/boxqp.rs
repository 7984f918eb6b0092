//! A small strictly convex QP with box bounds, solved exactly by a primal
//! active-set method: `min ½ xᵀ H x + gᵀ x  s.t.  l ≤ x ≤ u`.
//!
//! Iterates stay feasible; a variable on its active set sits exactly on its
//! bound (assigned, never approached). Meant for a handful of variables (the
//! chamber pressures of an inverse-kinematics step).

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};

/// Where a variable of the solution sits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Side {
    Free,
    Lower,
    Upper,
}

/// The solution of [`solve`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct BoxQpSolution {
    pub(crate) x: Vec<f64>,
    pub(crate) sides: Vec<Side>,
}

/// Solves the box QP; `h` symmetric positive definite (`n × n`), `l ≤ u`.
///
/// # Errors
/// [`Error::NotPositiveDefinite`] if a reduced `H` cannot be factored;
/// [`Error::NonFinite`] if the active-set iterations do not end (a
/// degenerate problem).
pub(crate) fn solve(h: &DMatrix<f64>, g: &[f64], l: &[f64], u: &[f64]) -> Result<BoxQpSolution> {
    let n = g.len();
    let mut x: Vec<f64> = (0..n).map(|i| 0.0f64.clamp(l[i], u[i])).collect();
    let mut sides: Vec<Side> = (0..n)
        .map(|i| {
            if l[i] == u[i] || x[i] == l[i] && l[i] > 0.0 {
                Side::Lower
            } else if x[i] == u[i] && u[i] < 0.0 {
                Side::Upper
            } else {
                Side::Free
            }
        })
        .collect();
    let scale = h.amax().max(g.iter().fold(0.0f64, |m, v| m.max(v.abs())));
    for _ in 0..(20 * n + 50) {
        let free: Vec<usize> = (0..n).filter(|&i| sides[i] == Side::Free).collect();
        // minimizer over the free variables, the others fixed at their bounds
        let y = if free.is_empty() {
            Vec::new()
        } else {
            let m = free.len();
            let hff = DMatrix::from_fn(m, m, |a, b| h[(free[a], free[b])]);
            let rhs = DVector::from_fn(m, |a, _| {
                let i = free[a];
                -(g[i]
                    + (0..n)
                        .filter(|&j| sides[j] != Side::Free)
                        .map(|j| h[(i, j)] * x[j])
                        .sum::<f64>())
            });
            let chol = hff.cholesky().ok_or_else(|| Error::NotPositiveDefinite {
                context: "inverse-kinematics QP (free pressures)".into(),
            })?;
            chol.solve(&rhs).iter().copied().collect()
        };
        // the largest step towards it that stays feasible
        let mut alpha = 1.0f64;
        let mut blocking: Option<(usize, Side)> = None;
        for (a, &i) in free.iter().enumerate() {
            let d = y[a] - x[i];
            if d < 0.0 && y[a] < l[i] {
                let t = (l[i] - x[i]) / d;
                if t < alpha {
                    alpha = t;
                    blocking = Some((i, Side::Lower));
                }
            } else if d > 0.0 && y[a] > u[i] {
                let t = (u[i] - x[i]) / d;
                if t < alpha {
                    alpha = t;
                    blocking = Some((i, Side::Upper));
                }
            }
        }
        for (a, &i) in free.iter().enumerate() {
            x[i] += alpha.max(0.0) * (y[a] - x[i]);
            x[i] = x[i].clamp(l[i], u[i]);
        }
        if let Some((j, side)) = blocking {
            x[j] = if side == Side::Lower { l[j] } else { u[j] };
            sides[j] = side;
            continue;
        }
        // optimal over this active set: check the multipliers
        let grad: Vec<f64> = (0..n)
            .map(|i| g[i] + (0..n).map(|j| h[(i, j)] * x[j]).sum::<f64>())
            .collect();
        let mut worst: Option<(usize, f64)> = None;
        for i in 0..n {
            if l[i] == u[i] {
                continue;
            }
            let violation = match sides[i] {
                Side::Lower => -grad[i],
                Side::Upper => grad[i],
                Side::Free => 0.0,
            };
            if violation > 1e-13 * scale.max(f64::MIN_POSITIVE)
                && worst.is_none_or(|(_, v)| violation > v)
            {
                worst = Some((i, violation));
            }
        }
        match worst {
            None => return Ok(BoxQpSolution { x, sides }),
            Some((i, _)) => sides[i] = Side::Free,
        }
    }
    Err(Error::NonFinite {
        context: "inverse-kinematics QP: active-set iterations did not end".into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn objective(h: &DMatrix<f64>, g: &[f64], x: &[f64]) -> f64 {
        let xv = DVector::from_column_slice(x);
        0.5 * (xv.transpose() * h * &xv)[(0, 0)] + g.iter().zip(x).map(|(a, b)| a * b).sum::<f64>()
    }

    /// The reference: every assignment of each variable to free / lower /
    /// upper, the feasible one of least objective.
    fn brute_force(h: &DMatrix<f64>, g: &[f64], l: &[f64], u: &[f64]) -> Vec<f64> {
        let n = g.len();
        let mut best = (f64::INFINITY, vec![]);
        for code in 0..3usize.pow(n as u32) {
            let mut c = code;
            let mut x = vec![0.0; n];
            let mut free = vec![];
            for i in 0..n {
                match c % 3 {
                    0 => free.push(i),
                    1 => x[i] = l[i],
                    _ => x[i] = u[i],
                }
                c /= 3;
            }
            if !free.is_empty() {
                let m = free.len();
                let hff = DMatrix::from_fn(m, m, |a, b| h[(free[a], free[b])]);
                let rhs = DVector::from_fn(m, |a, _| {
                    let i = free[a];
                    -(g[i]
                        + (0..n)
                            .filter(|j| !free.contains(j))
                            .map(|j| h[(i, j)] * x[j])
                            .sum::<f64>())
                });
                let y = hff.cholesky().unwrap().solve(&rhs);
                for (a, &i) in free.iter().enumerate() {
                    x[i] = y[a];
                }
            }
            if (0..n).all(|i| x[i] >= l[i] - 1e-12 && x[i] <= u[i] + 1e-12) {
                let f = objective(h, g, &x);
                if f < best.0 {
                    best = (f, x);
                }
            }
        }
        best.1
    }

    #[test]
    fn matches_enumeration_of_active_sets_on_random_problems() {
        let mut rng = crate::rng::Lcg::new(12345);
        let mut rnd = || rng.symmetric();
        for n in [1usize, 2, 4, 6] {
            for _ in 0..40 {
                let a = DMatrix::from_fn(n + 2, n, |_, _| rnd());
                let h = a.transpose() * &a + DMatrix::identity(n, n) * 1e-3;
                let g: Vec<f64> = (0..n).map(|_| 3.0 * rnd()).collect();
                let l: Vec<f64> = (0..n).map(|_| -rnd().abs()).collect();
                let u: Vec<f64> = (0..n).map(|_| rnd().abs()).collect();
                let s = solve(&h, &g, &l, &u).unwrap();
                let r = brute_force(&h, &g, &l, &u);
                let (fs, fr) = (objective(&h, &g, &s.x), objective(&h, &g, &r));
                assert!(
                    (fs - fr).abs() <= 1e-10 * (1.0 + fr.abs()),
                    "n {n}: {fs} vs {fr}"
                );
                for i in 0..n {
                    assert!(s.x[i] >= l[i] && s.x[i] <= u[i]);
                    match s.sides[i] {
                        Side::Lower => assert_eq!(s.x[i], l[i]),
                        Side::Upper => assert_eq!(s.x[i], u[i]),
                        Side::Free => {}
                    }
                }
            }
        }
    }
}
