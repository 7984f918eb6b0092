//! The factors of a band matrix ([`BandedLu`]): a pivoted LU or `L D Lᵀ`,
//! and their solves for one or many right-hand sides.

use super::ldlt::Ldlt;
use super::{axpy_neg, dot, BandedMatrix};
use crate::error::{check_len, Result};
use crate::linsolve::{check_rhs, FactorMethod, Factorization, Inertia, LinsolveError};

/// Which factorization a [`BandedLu`] holds.
#[derive(Debug, Clone)]
pub(super) enum Kind {
    /// Pivoted LU in the matrix's own storage.
    Lu { lu: BandedMatrix, piv: Vec<usize> },
    /// `L D Lᵀ` of a symmetric matrix.
    Ldlt(Ldlt),
}

/// The factors of a [`BandedMatrix`]: a pivoted LU
/// ([`BandedMatrix::factor`]) or, for symmetric matrices, `L D Lᵀ`
/// ([`BandedMatrix::factor_ldlt`], and [`BandedMatrix::factor_scaled`] when
/// the matrix is symmetric positive definite). Both solve `A x = b`.
#[derive(Debug, Clone)]
pub struct BandedLu {
    pub(super) kind: Kind,
    pub(super) min_pivot: f64,
    pub(super) negative_pivots: usize,
    pub(super) scaling: Option<Vec<f64>>,
    /// The inertia, when an `L D Lᵀ` of the (scaled, shifted) matrix
    /// exists: from the factors themselves, or from the `L D Lᵀ` a
    /// [`super::BandedSolver`] took before its LU.
    pub(super) inertia: Option<Inertia>,
}

impl BandedLu {
    /// Order of the factored matrix.
    pub fn n(&self) -> usize {
        match &self.kind {
            Kind::Lu { lu, .. } => lu.n,
            Kind::Ldlt(f) => f.n,
        }
    }

    /// Whether the factors are `L D Lᵀ` (symmetric, no pivoting) rather
    /// than a pivoted LU.
    pub fn is_ldlt(&self) -> bool {
        matches!(self.kind, Kind::Ldlt(_))
    }

    /// Solves `A x = b` in place (`b` has `n` entries).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] (field `b`) if `b` does not have `n` entries.
    pub fn solve_in_place(&self, b: &mut [f64]) -> Result<()> {
        check_len("b", self.n(), b.len())?;
        self.solve_rows(b, 1);
        Ok(())
    }

    /// Solves `A X = B` in place for `nrhs` right-hand sides at once, `b`
    /// row-major `n × nrhs` (`b[i·nrhs + c]` is entry `i` of right-hand side
    /// `c`): one sweep over the factors for all of them.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] (field `b`) if `b` does not have
    /// `n · nrhs` entries.
    ///
    /// # Example
    /// ```
    /// use softrod::linsolve::BandedMatrix;
    /// let mut a = BandedMatrix::zeros(2, 1, 1);
    /// a.add(0, 0, 2.0); a.add(1, 1, 4.0);
    /// let f = a.factor("example").unwrap();
    /// let mut b = vec![2.0, 4.0, 8.0, 4.0]; // columns (2, 8) and (4, 4)
    /// f.solve_many_in_place(&mut b, 2).unwrap();
    /// assert_eq!(b, vec![1.0, 2.0, 2.0, 1.0]);
    /// ```
    pub fn solve_many_in_place(&self, b: &mut [f64], nrhs: usize) -> Result<()> {
        check_len("b", self.n().saturating_mul(nrhs), b.len())?;
        if nrhs > 0 {
            self.solve_rows(b, nrhs);
        }
        Ok(())
    }

    /// The solve for `r >= 1` row-major right-hand sides (sizes checked).
    fn solve_rows(&self, b: &mut [f64], r: usize) {
        let scale = |b: &mut [f64]| {
            if let Some(d) = &self.scaling {
                if r == 1 {
                    b.iter_mut().zip(d).for_each(|(x, di)| *x *= di);
                } else {
                    for (row, di) in b.chunks_exact_mut(r).zip(d) {
                        row.iter_mut().for_each(|x| *x *= di);
                    }
                }
            }
        };
        scale(b);
        match &self.kind {
            Kind::Ldlt(f) => f.solve(b, r),
            Kind::Lu { lu, piv } => lu_solve(lu, piv, b, r),
        }
        scale(b);
    }

    /// The solve for `r >= 1` right-hand sides stored column after column
    /// (sizes checked).
    fn solve_columns(&self, b: &mut [f64], r: usize) {
        let n = self.n();
        let scale = |b: &mut [f64]| {
            if let Some(d) = &self.scaling {
                for col in b.chunks_exact_mut(n.max(1)) {
                    col.iter_mut().zip(d).for_each(|(x, di)| *x *= di);
                }
            }
        };
        scale(b);
        match &self.kind {
            Kind::Ldlt(f) => f.solve_columns(b, r),
            Kind::Lu { lu, piv } => {
                if r == 1 {
                    lu_solve(lu, piv, b, 1);
                } else {
                    let mut rows = vec![0.0; n * r];
                    for (c, col) in b.chunks_exact(n).enumerate() {
                        for (i, v) in col.iter().enumerate() {
                            rows[i * r + c] = *v;
                        }
                    }
                    lu_solve(lu, piv, &mut rows, r);
                    for (c, col) in b.chunks_exact_mut(n).enumerate() {
                        for (i, v) in col.iter_mut().enumerate() {
                            *v = rows[i * r + c];
                        }
                    }
                }
            }
        }
        scale(b);
    }

    /// Smallest ratio of a pivot to the largest original entry of its row: a
    /// cheap indicator of ill-conditioning (small means nearly singular).
    pub fn pivot_ratio(&self) -> f64 {
        self.min_pivot
    }

    /// Number of negative pivots. For a symmetric matrix factored without
    /// row interchanges (always for `L D Lᵀ`) it equals the number of
    /// negative eigenvalues; with interchanges it is only an indicator.
    pub fn negative_pivots(&self) -> usize {
        self.negative_pivots
    }
}

impl Factorization for BandedLu {
    fn n(&self) -> usize {
        BandedLu::n(self)
    }

    fn method(&self) -> FactorMethod {
        match self.kind {
            Kind::Ldlt(_) => FactorMethod::Ldlt,
            Kind::Lu { .. } => FactorMethod::Lu,
        }
    }

    fn inertia(&self) -> Option<Inertia> {
        self.inertia
    }

    fn pivot_ratio(&self) -> f64 {
        self.min_pivot
    }

    fn solve_in_place(&self, b: &mut [f64]) -> std::result::Result<(), LinsolveError> {
        check_rhs("b", self.n(), b.len())?;
        self.solve_rows(b, 1);
        Ok(())
    }

    fn solve_columns_in_place(
        &self,
        b: &mut [f64],
        nrhs: usize,
    ) -> std::result::Result<(), LinsolveError> {
        check_rhs("b", self.n().saturating_mul(nrhs), b.len())?;
        if nrhs > 0 && self.n() > 0 {
            self.solve_columns(b, nrhs);
        }
        Ok(())
    }
}

/// Forward and back substitution with pivoted LU factors for `r`
/// row-major right-hand sides.
fn lu_solve(lu: &BandedMatrix, piv: &[usize], b: &mut [f64], r: usize) {
    let (n, kl, ku, w) = (lu.n, lu.kl, lu.ku, lu.width);
    if r == 1 {
        for k in 0..n {
            let p = piv[k];
            if p != k {
                b.swap(k, p);
            }
            let bk = b[k];
            if bk != 0.0 {
                let last = (k + kl).min(n - 1);
                // column k below the diagonal: rows k+1..=last, stride w - 1
                for (off, i) in (k + 1..=last).enumerate() {
                    let idx = i * w + kl - 1 - off; // (i, k) = i w + k + kl − i
                    b[i] -= lu.data[idx] * bk;
                }
            }
        }
        for i in (0..n).rev() {
            let row = i * w + kl; // (i, i)
            let last = (i + ku + kl).min(n - 1);
            let s = dot(&lu.data[row + 1..row + 1 + (last - i)], &b[i + 1..=last]);
            b[i] = (b[i] - s) / lu.data[row];
        }
        return;
    }
    for k in 0..n {
        let p = piv[k];
        if p != k {
            for c in 0..r {
                b.swap(k * r + c, p * r + c);
            }
        }
        let last = (k + kl).min(n - 1);
        let (head, tail) = b.split_at_mut((k + 1) * r);
        let bk = &head[k * r..];
        for i in k + 1..=last {
            let l = lu.data[i * w + k + kl - i];
            if l != 0.0 {
                let off = (i - k - 1) * r;
                axpy_neg(l, bk, &mut tail[off..off + r]);
            }
        }
    }
    for i in (0..n).rev() {
        let row = i * w + kl;
        let last = (i + ku + kl).min(n - 1);
        let (head, tail) = b.split_at_mut((i + 1) * r);
        let bi = &mut head[i * r..];
        for j in i + 1..=last {
            let u = lu.data[row + (j - i)];
            if u != 0.0 {
                let off = (j - i - 1) * r;
                axpy_neg(u, &tail[off..off + r], bi);
            }
        }
        let dinv = 1.0 / lu.data[row];
        bi.iter_mut().for_each(|v| *v *= dinv);
    }
}
