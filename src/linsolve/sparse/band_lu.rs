//! A band LU with partial pivoting (row interchanges, as LAPACK's `gbtrf`)
//! in the dofs' own order: the solve of a band pattern's matrix that is not
//! positive definite (a robot's tangent far from equilibrium or at a
//! saddle), in place of faer's general simplicial LU.
//!
//! Measured (callgrind, `examples/peer_times.rs`, uniform_large at 16
//! elements): faer's LU of the 68 × 68 tangent of half-bandwidth 7 and its
//! workspace took about a fifth of the whole static solve (two per solve,
//! ~250 k instructions each); the band elimination is `n b (2b + 1)`
//! multiply-adds.

use std::sync::Arc;

use super::band::Band;
use super::{Numeric, SparseFactors, SparseSolver};
use crate::linsolve::{FactorOptions, Inertia, LinsolveError, SymmetricMatrix, pivot_tolerance};

/// The factors `P A = L U` of a band matrix of half-bandwidth `b`: `U` of
/// upper bandwidth `2b` (the fill of the interchanges), `L` unit lower of
/// bandwidth `b`, the interchange of each step.
#[derive(Debug, Clone)]
pub(super) struct BandLu {
    n: usize,
    b: usize,
    /// Row `k` of `U`: columns `k − b ..= k + 2b` (width `3b + 1`; the
    /// part left of `k` is workspace, zero at the end).
    u: Vec<f64>,
    /// The multipliers of step `k`: rows `k + 1 ..= k + b` (`b` each).
    l: Vec<f64>,
    /// The row interchanged with row `k` at step `k`.
    swap: Vec<usize>,
}

impl Band {
    /// The LU of `D (A + μ D⁻²) D`… precisely: of the matrix with entries
    /// `d_i d_j a_ij + μ δ_ij` (the Jacobi-scaled, shifted matrix the other
    /// paths factor), with partial pivoting; `Err(Singular)` at a pivot not
    /// above `n ε` times its row's largest scaled entry. `Ok` with the
    /// factors and the smallest such ratio.
    pub(super) fn lu(
        &self,
        matrix: &SymmetricMatrix,
        d: &[f64],
        shift: f64,
    ) -> Result<(BandLu, f64), LinsolveError> {
        let (n, b) = (d.len(), self.b());
        let w = 3 * b + 1;
        let mut u = vec![0.0; n * w];
        // row i, column j at i * w + (j + b − i)
        for (&v, (i, j)) in matrix.values().iter().zip(self.entries()) {
            let s = v * d[i] * d[j];
            u[i * w + (j + b - i)] = s;
            if i != j {
                u[j * w + (i + b - j)] = s;
            }
        }
        for i in 0..n {
            u[i * w + b] += shift;
        }
        let rowmax: Vec<f64> = u
            .chunks_exact(w)
            .map(|r| r.iter().fold(0.0f64, |m, v| m.max(v.abs())))
            .collect();
        // the original row now in row i
        let mut origin: Vec<usize> = (0..n).collect();
        let mut l = vec![0.0; n * b];
        let mut swap = vec![0; n];
        let rel = pivot_tolerance(n);
        let mut min_ratio = f64::INFINITY;
        for k in 0..n {
            let last = (k + b).min(n - 1);
            // the pivot: the largest |a_ik| over rows k ..= k + b
            let mut p = k;
            let mut best = u[k * w + b].abs();
            for i in k + 1..=last {
                let v = u[i * w + (k + b - i)].abs();
                if v > best {
                    (p, best) = (i, v);
                }
            }
            swap[k] = p;
            if p != k {
                // columns k ..= k + 2b of both rows (inside both windows)
                for j in k..=(k + 2 * b).min(n - 1) {
                    u.swap(k * w + (j + b - k), p * w + (j + b - p));
                }
                origin.swap(k, p);
            }
            let pivot = u[k * w + b];
            let scale = rowmax[origin[k]];
            if !super::exceeds(pivot.abs(), rel * scale) {
                return Err(LinsolveError::Singular {
                    index: origin[k],
                    pivot,
                    scale,
                });
            }
            min_ratio = min_ratio.min(pivot.abs() / scale);
            let top = (k + 2 * b).min(n - 1);
            for i in k + 1..=last {
                let m = u[i * w + (k + b - i)] / pivot;
                l[k * b + (i - k - 1)] = m;
                u[i * w + (k + b - i)] = 0.0;
                if m != 0.0 && top > k {
                    // row i −= m × row k over the columns k + 1 ..= top
                    let (head, tail) = u.split_at_mut(i * w);
                    let pivot_row = &head[k * w + b + 1..=k * w + top + b - k];
                    let row = &mut tail[k + 1 + b - i..=top + b - i];
                    for (a, c) in row.iter_mut().zip(pivot_row) {
                        *a -= m * c;
                    }
                }
            }
        }
        Ok((BandLu { n, b, u, l, swap }, min_ratio))
    }
}

impl Band {
    /// A matrix the band `L D Lᵀ` did not find positive definite: its
    /// inertia from the band `L D Lᵀ` carried through negative pivots
    /// (natural order, no pivoting: Sylvester's law holds for any
    /// symmetric order, as for the general path's fill-reducing one) and,
    /// when it has a negative eigenvalue, its band LU. `Ok(None)` when
    /// this does not decide (a pivot not clearly nonzero, i.e. not above
    /// `n ε` times its row's largest scaled entry, the general path's
    /// test; or no negative pivot): the general path then does.
    ///
    /// # Errors
    /// [`LinsolveError::NotPositiveDefinite`] (the first negative pivot)
    /// when `options` require a positive definite matrix; the band LU's.
    pub(super) fn indefinite(
        &self,
        matrix: &SymmetricMatrix,
        d: &[f64],
        options: FactorOptions,
    ) -> Result<Option<(BandLu, Inertia, f64)>, LinsolveError> {
        let (n, b) = (d.len(), self.b());
        let w = b + 1;
        // lower band: row i holds columns i − b ..= i at i w + (j + b − i)
        let mut l = vec![0.0; n * w];
        for (&v, (i, j)) in matrix.values().iter().zip(self.entries()) {
            let (hi, lo) = (i.max(j), i.min(j));
            l[hi * w + lo + b - hi] = v * d[i] * d[j];
        }
        let mut rowmax = vec![0.0f64; n];
        for i in 0..n {
            l[i * w + b] += options.shift;
            for t in b.saturating_sub(i)..=b {
                let (j, a) = (i + t - b, l[i * w + t].abs());
                rowmax[i] = rowmax[i].max(a);
                rowmax[j] = rowmax[j].max(a);
            }
        }
        let rel = pivot_tolerance(n);
        let mut pivots = vec![0.0; n];
        // v[k − lo] = L_ik D_k along row i
        let mut v = vec![0.0; w];
        let mut first_negative = None;
        for i in 0..n {
            let lo = i.saturating_sub(b);
            for j in lo..i {
                let mut s = l[i * w + j + b - i];
                for k in lo.max(j.saturating_sub(b))..j {
                    s -= v[k - lo] * l[j * w + k + b - j];
                }
                v[j - lo] = s;
                l[i * w + j + b - i] = s / pivots[j];
            }
            let mut s = l[i * w + b];
            for k in lo..i {
                s -= v[k - lo] * l[i * w + k + b - i];
            }
            if !super::exceeds(s.abs(), rel * rowmax[i]) {
                return Ok(None);
            }
            if s < 0.0 && first_negative.is_none() {
                first_negative = Some((i, s));
            }
            pivots[i] = s;
        }
        let Some((index, pivot)) = first_negative else {
            return Ok(None);
        };
        if options.require_positive_definite {
            return Err(LinsolveError::NotPositiveDefinite { index, pivot });
        }
        let negative = pivots.iter().filter(|p| **p < 0.0).count();
        let inertia = Inertia {
            positive: n - negative,
            negative,
        };
        let (f, min_pivot) = self.lu(matrix, d, options.shift)?;
        Ok(Some((f, inertia, min_pivot)))
    }
}

impl SparseSolver {
    /// The factors of a band path: `numeric` in the natural order, scaled
    /// by `d`.
    pub(super) fn band_factors(
        &self,
        numeric: Numeric,
        d: &Arc<Vec<f64>>,
        inertia: Option<Inertia>,
        min_pivot: f64,
    ) -> SparseFactors {
        SparseFactors {
            n: d.len(),
            symbolic: self.symbolic.clone(),
            perm: self.perm.clone(),
            numeric,
            scaling: d.clone(),
            inertia,
            min_pivot,
        }
    }
}

impl BandLu {
    /// Solves `A x = rhs` in place (the matrix the factors are of).
    pub(super) fn solve_in_place(&self, x: &mut [f64]) {
        let (n, b) = (self.n, self.b);
        let w = 3 * b + 1;
        if x.len() != n {
            return;
        }
        // L y = P rhs
        for k in 0..n {
            let p = self.swap[k];
            if p != k {
                x.swap(k, p);
            }
            let xk = x[k];
            for t in 0..b.min(n - 1 - k) {
                x[k + 1 + t] -= self.l[k * b + t] * xk;
            }
        }
        // U x = y
        for k in (0..n).rev() {
            let row = &self.u[k * w..(k + 1) * w];
            let top = (k + 2 * b).min(n - 1);
            let s: f64 = row[b + 1..=top + b - k]
                .iter()
                .zip(&x[k + 1..=top])
                .map(|(a, c)| a * c)
                .sum();
            x[k] = (x[k] - s) / row[b];
        }
    }
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use crate::linsolve::{
        CholeskyKind, FactorMethod, FactorOptions, Factorization, LinsolveError, SparseSettings,
        SparseSolver, SymmetricMatrix, SymmetricPattern, TangentSolver,
    };

    /// A chain of `elements` random symmetric (indefinite) element blocks
    /// of `2 dofs` coordinates, plus `diag` on the diagonal.
    fn chain(elements: usize, dofs: usize, diag: f64, seed: u64) -> SymmetricMatrix {
        super::super::band::tests::chain_with(elements, dofs, diag, seed, |rand, m| {
            let mut h = vec![0.0; m * m];
            for a in 0..m {
                for b in a..m {
                    // rows of very different scales, as a cable's tangent
                    let v = rand() * 10f64.powi(((a + b) % 5) as i32);
                    h[a * m + b] = v;
                    h[b * m + a] = v;
                }
            }
            h
        })
    }

    fn general(p: &Arc<SymmetricPattern>) -> SparseSolver {
        let s = SparseSettings {
            cholesky: CholeskyKind::Llt,
            ..SparseSettings::default()
        };
        SparseSolver::with_settings(p, s).unwrap()
    }

    #[test]
    fn band_lu_solves_what_the_general_lu_solves() {
        for (elements, dofs, seed) in [(3, 4, 1), (16, 4, 2), (40, 4, 3), (5, 6, 4), (20, 3, 5)] {
            let k = chain(elements, dofs, 0.0, seed);
            let p = k.pattern().clone();
            let mut band = SparseSolver::analyze(&p).unwrap();
            for shift in [0.0, 1e-3] {
                let options = FactorOptions {
                    shift,
                    ..FactorOptions::default()
                };
                let fb = band.factor(&k, options).unwrap();
                let fo = general(&p).factor(&k, options).unwrap();
                assert_eq!(fb.method(), FactorMethod::Lu, "{elements} x {dofs}");
                assert_eq!(fo.method(), FactorMethod::Lu);
                assert_eq!(fb.inertia(), fo.inertia());
                assert!(fb.inertia().is_some_and(|i| i.negative > 0));
                // the band inertia refuses what is not positive definite
                let definite = FactorOptions {
                    require_positive_definite: true,
                    ..options
                };
                let e = band.factor(&k, definite).unwrap_err();
                assert!(
                    matches!(e, LinsolveError::NotPositiveDefinite { .. }),
                    "{e:?}"
                );
                let n = k.n();
                let (rhs, xb, xo, scale) =
                    super::super::band::tests::two_column_solves(&fb, &fo, n);
                for (a, b) in xb.iter().zip(&xo) {
                    assert!((a - b).abs() <= 1e-9 * scale, "{a} vs {b}");
                }
                // and it is the solution: the residual of the unshifted
                // matrix is small when there is no shift
                if shift == 0.0 {
                    let mut y = vec![0.0; n];
                    k.mul_vec_into(&xb[..n], &mut y).unwrap();
                    let r = y
                        .iter()
                        .zip(&rhs[..n])
                        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                    assert!(r <= 1e-9 * scale.max(1.0), "residual {r}");
                }
            }
        }
    }

    #[test]
    fn band_lu_refuses_a_singular_matrix() {
        // a chain whose last node's coordinates are not coupled at all:
        // a zero row and column
        let mut k = chain(4, 4, 0.0, 9);
        let n = k.n();
        let p = k.pattern().clone();
        let cols: Vec<(usize, usize)> = (0..n)
            .flat_map(|i| (0..n).map(move |j| (i, j)))
            .filter(|&(i, j)| i >= n - 4 || j >= n - 4)
            .collect();
        for (i, j) in cols {
            if let Some(slot) = p.position(i, j) {
                k.values_mut()[slot] = 0.0;
            }
        }
        let mut band = SparseSolver::analyze(&p).unwrap();
        let e = band.factor(&k, FactorOptions::default()).unwrap_err();
        assert!(matches!(e, LinsolveError::Singular { .. }), "{e:?}");
        let e = general(&p)
            .factor(&k, FactorOptions::default())
            .unwrap_err();
        assert!(matches!(e, LinsolveError::Singular { .. }), "{e:?}");
    }
}
