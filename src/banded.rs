//! Banded matrices and their LU factorization with partial pivoting.
//!
//! The tangent stiffness of a cable is block-tridiagonal in the nodes: with
//! `b` coordinates per node it is banded with `kl = ku = 2b - 1`. Factoring
//! and solving cost `O(n kl (kl + ku))`, linear in the number of elements.
//! Partial pivoting keeps the factorization usable when the tangent is
//! indefinite (compression, buckling, iterates far from equilibrium).

use crate::error::{check_len, Error, Result};

/// The most numbers [`BandedMatrix::try_zeros`] stores (2³⁰, 8 GiB).
pub const MAX_ENTRIES: usize = 1 << 30;

/// A square banded matrix with `kl` sub- and `ku` super-diagonals.
///
/// Storage is row-major with room for the fill-in of pivoting: row `i` holds
/// columns `i - kl ..= i + ku + kl`.
///
/// # Example
/// ```
/// use softrod::banded::BandedMatrix;
/// let mut a = BandedMatrix::zeros(3, 1, 1);
/// for i in 0..3 { a.add(i, i, 2.0); }
/// a.add(0, 1, -1.0); a.add(1, 0, -1.0); a.add(1, 2, -1.0); a.add(2, 1, -1.0);
/// let lu = a.clone().factor("example").unwrap();
/// let mut x = vec![1.0, 0.0, 1.0];
/// lu.solve_in_place(&mut x).unwrap();
/// assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 1.0).abs() < 1e-14);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct BandedMatrix {
    n: usize,
    kl: usize,
    ku: usize,
    width: usize,
    data: Vec<f64>,
}

impl BandedMatrix {
    /// An `n × n` zero matrix with bandwidths `kl`, `ku`.
    ///
    /// # Panics
    /// Like `Vec::with_capacity`, if the storage `n (2 kl + ku + 1)` overflows
    /// `usize` (an allocation failure aborts). [`BandedMatrix::try_zeros`]
    /// returns an error instead; the library calls this only with sizes
    /// bounded by [`crate::assembly::MAX_ELEMENTS`].
    pub fn zeros(n: usize, kl: usize, ku: usize) -> Self {
        let width = kl.saturating_mul(2).saturating_add(ku).saturating_add(1);
        BandedMatrix {
            n,
            kl,
            ku,
            width,
            data: vec![0.0; n.saturating_mul(width)],
        }
    }

    /// As [`BandedMatrix::zeros`], refusing sizes above [`MAX_ENTRIES`]
    /// stored numbers before allocating.
    ///
    /// # Errors
    /// [`Error::TooLarge`] (field `n`) if `n (2 kl + ku + 1)` exceeds
    /// [`MAX_ENTRIES`] or overflows.
    ///
    /// # Example
    /// ```
    /// use softrod::{banded::BandedMatrix, Error};
    /// assert!(BandedMatrix::try_zeros(10, 1, 1).is_ok());
    /// let err = BandedMatrix::try_zeros(usize::MAX, 7, 7).unwrap_err();
    /// assert!(matches!(err, Error::TooLarge { ref name, .. } if name == "n"));
    /// ```
    pub fn try_zeros(n: usize, kl: usize, ku: usize) -> Result<Self> {
        let entries = kl
            .checked_mul(2)
            .and_then(|w| w.checked_add(ku))
            .and_then(|w| w.checked_add(1))
            .and_then(|w| w.checked_mul(n));
        match entries {
            Some(e) if e <= MAX_ENTRIES => Ok(Self::zeros(n, kl, ku)),
            _ => Err(Error::TooLarge {
                name: "n".into(),
                value: n,
                max: MAX_ENTRIES / (2 * kl.min(MAX_ENTRIES) + ku.min(MAX_ENTRIES) + 1),
            }),
        }
    }

    /// Order of the matrix.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Sets every entry to zero (keeps the allocation).
    pub fn fill_zero(&mut self) {
        self.data.iter_mut().for_each(|v| *v = 0.0);
    }

    /// Whether `(i, j)` lies in the band.
    pub fn in_band(&self, i: usize, j: usize) -> bool {
        i < self.n && j < self.n && j + self.kl >= i && j <= i + self.ku
    }

    #[inline]
    fn idx(&self, i: usize, j: usize) -> usize {
        i * self.width + (j + self.kl - i)
    }

    /// Entry `(i, j)` (zero outside the band).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        if self.in_band(i, j) {
            self.data[self.idx(i, j)]
        } else {
            0.0
        }
    }

    /// Adds `v` to entry `(i, j)`. Entries outside the band are ignored
    /// (assembly code guarantees the band); [`BandedMatrix::try_add`] reports them.
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        if self.in_band(i, j) {
            let k = self.idx(i, j);
            if let Some(a) = self.data.get_mut(k) {
                *a += v;
            }
        }
    }

    /// Adds the dense `size × size` block `block` (row-major) at rows and
    /// columns `off .. off + size`. The block must lie in the band.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if the block is not `size²` long or does
    /// not fit in the band.
    pub fn add_block(&mut self, off: usize, size: usize, block: &[f64]) -> Result<()> {
        crate::error::check_len("block", size * size, block.len())?;
        if size == 0 {
            return Ok(());
        }
        if off + size > self.n || size - 1 > self.kl.min(self.ku) {
            return Err(Error::DimensionMismatch {
                name: "block (outside the band)".into(),
                expected: self.kl.min(self.ku) + 1,
                got: size,
            });
        }
        for r in 0..size {
            let i = off + r;
            let start = self.idx(i, off);
            for (d, v) in self.data[start..start + size]
                .iter_mut()
                .zip(&block[r * size..(r + 1) * size])
            {
                *d += v;
            }
        }
        Ok(())
    }

    /// Adds `v` to entry `(i, j)`, which must lie in the band.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] (field `i` or `j`) for an index `>= n`,
    /// [`Error::InvalidParameter`] (field `j`) for an entry outside the band.
    ///
    /// # Example
    /// ```
    /// let mut a = softrod::banded::BandedMatrix::zeros(3, 1, 1);
    /// a.try_add(0, 1, 2.0).unwrap();
    /// assert!(a.try_add(0, 2, 1.0).is_err());
    /// ```
    pub fn try_add(&mut self, i: usize, j: usize, v: f64) -> Result<()> {
        crate::error::check_index("i", i, self.n)?;
        crate::error::check_index("j", j, self.n)?;
        if !self.in_band(i, j) {
            return Err(Error::invalid(
                "j",
                j,
                format!(
                    "row {i} of the band holds columns {}..={}",
                    i.saturating_sub(self.kl),
                    (i + self.ku).min(self.n - 1)
                ),
            ));
        }
        self.add(i, j, v);
        Ok(())
    }

    /// `y = A x`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `x` does not have `n` entries.
    pub fn mul_vec(&self, x: &[f64]) -> Result<Vec<f64>> {
        check_len("x", self.n, x.len())?;
        let mut y = vec![0.0; self.n];
        for (i, yi) in y.iter_mut().enumerate() {
            let lo = i.saturating_sub(self.kl);
            let hi = (i + self.ku + 1).min(self.n);
            *yi = (lo..hi).map(|j| self.data[self.idx(i, j)] * x[j]).sum();
        }
        Ok(y)
    }

    /// Replaces `A` by `D A D` with `D = diag(d)` (symmetric scaling).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `d` does not have `n` entries.
    pub fn scale_symmetric(&mut self, d: &[f64]) -> Result<()> {
        check_len("d", self.n, d.len())?;
        for i in 0..self.n {
            let lo = i.saturating_sub(self.kl);
            let hi = (i + self.ku + 1).min(self.n);
            for j in lo..hi {
                let k = self.idx(i, j);
                self.data[k] *= d[i] * d[j];
            }
        }
        Ok(())
    }

    /// Largest absolute entry.
    pub fn max_abs(&self) -> f64 {
        self.data.iter().fold(0.0f64, |m, v| m.max(v.abs()))
    }

    /// LU factorization with partial pivoting, in place.
    ///
    /// The singularity test is row-relative: a pivot is refused when it is
    /// below `n ε` times the largest original entry of its row (stiffness
    /// matrices of fine cables span many orders of magnitude between rows).
    ///
    /// # Errors
    /// [`Error::Singular`] when a pivot is zero or below `n ε max|row|`;
    /// [`Error::NonFinite`] when the matrix holds a NaN or infinity.
    pub fn factor(mut self, context: &str) -> Result<BandedLu> {
        let (n, kl, ku) = (self.n, self.kl, self.ku);
        let scale = self.max_abs();
        if !scale.is_finite() || self.data.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                context: context.to_string(),
            });
        }
        let rel = (n.max(1) as f64) * f64::EPSILON;
        let mut rowmax: Vec<f64> = self
            .data
            .chunks(self.width)
            .map(|r| r.iter().fold(0.0f64, |m, v| m.max(v.abs())))
            .collect();
        let mut piv = vec![0usize; n];
        let mut min_pivot = f64::INFINITY;
        let mut negative = 0usize;
        for k in 0..n {
            let last_row = (k + kl).min(n - 1);
            let mut p = k;
            let mut best = self.data[self.idx(k, k)].abs();
            for i in k + 1..=last_row {
                let v = self.data[self.idx(i, k)].abs();
                if v > best {
                    best = v;
                    p = i;
                }
            }
            if best <= rel * rowmax[p] || best == 0.0 {
                return Err(Error::Singular {
                    context: context.to_string(),
                    index: k,
                    pivot: best,
                    scale: rowmax[p],
                });
            }
            piv[k] = p;
            rowmax.swap(k, p);
            let last_col = (k + ku + kl).min(n - 1);
            if p != k {
                for j in k..=last_col {
                    let a = self.idx(k, j);
                    let b = self.idx(p, j);
                    self.data.swap(a, b);
                }
            }
            let pivot = self.data[self.idx(k, k)];
            min_pivot = min_pivot.min(pivot.abs() / rowmax[k]);
            if pivot < 0.0 {
                negative += 1;
            }
            let width = self.width;
            let len = last_col - k; // entries right of the pivot in row k
            let row_k = self.idx(k, k);
            for i in k + 1..=last_row {
                let ik = self.idx(i, k);
                let l = self.data[ik] / pivot;
                self.data[ik] = l;
                if l != 0.0 {
                    // rows i > k lie after row k in storage: split to borrow both
                    let (head, tail) = self.data.split_at_mut(ik + 1);
                    let src = &head[row_k + 1..row_k + 1 + len];
                    let dst = &mut tail[..len];
                    for (d, s) in dst.iter_mut().zip(src) {
                        *d -= l * s;
                    }
                }
                debug_assert!(ik + 1 + len <= (i + 1) * width);
            }
        }
        Ok(BandedLu {
            lu: self,
            piv,
            min_pivot,
            negative_pivots: negative,
            scaling: None,
        })
    }

    /// LU factorization of the Jacobi-scaled, shifted matrix
    /// `D A D + shift·I`, `D = diag(|a_ii|^-1/2)`; the returned factors solve
    /// `(A + shift·diag|a_ii|) x = b`. Scaling makes the factorization of
    /// stiffness matrices whose rows span many orders of magnitude accurate.
    ///
    /// # Errors
    /// As [`BandedMatrix::factor`].
    pub fn factor_scaled(mut self, shift: f64, context: &str) -> Result<BandedLu> {
        let d: Vec<f64> = (0..self.n)
            .map(|i| {
                let a = self.data[self.idx(i, i)].abs();
                if a > 0.0 && a.is_finite() {
                    1.0 / a.sqrt()
                } else {
                    1.0
                }
            })
            .collect();
        self.scale_symmetric(&d)?;
        if shift != 0.0 {
            for i in 0..self.n {
                let k = self.idx(i, i);
                self.data[k] += shift;
            }
        }
        let mut lu = self.factor(context)?;
        lu.scaling = Some(d);
        Ok(lu)
    }
}

/// The LU factors of a [`BandedMatrix`].
#[derive(Debug, Clone)]
pub struct BandedLu {
    lu: BandedMatrix,
    piv: Vec<usize>,
    min_pivot: f64,
    negative_pivots: usize,
    scaling: Option<Vec<f64>>,
}

impl BandedLu {
    /// Order of the factored matrix.
    pub fn n(&self) -> usize {
        self.lu.n
    }

    /// Solves `A x = b` in place (`b` has `n` entries).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] (field `b`) if `b` does not have `n` entries.
    #[allow(clippy::needless_range_loop)]
    pub fn solve_in_place(&self, b: &mut [f64]) -> Result<()> {
        check_len("b", self.lu.n, b.len())?;
        if let Some(d) = &self.scaling {
            b.iter_mut().zip(d).for_each(|(x, d)| *x *= d);
        }
        let (n, kl, ku) = (self.lu.n, self.lu.kl, self.lu.ku);
        let m = self.lu.width;
        for k in 0..n {
            let p = self.piv[k];
            if p != k {
                b.swap(k, p);
            }
            let bk = b[k];
            if bk != 0.0 {
                for i in k + 1..=(k + kl).min(n - 1) {
                    b[i] -= self.lu.data[self.lu.idx(i, k)] * bk;
                }
            }
        }
        for i in (0..n).rev() {
            let row = i * m + kl; // index of (i, i)
            let last = (i + ku + kl).min(n - 1);
            let coeffs = &self.lu.data[row + 1..row + 1 + (last - i)];
            let s: f64 = coeffs
                .iter()
                .zip(&b[i + 1..=last])
                .map(|(a, x)| a * x)
                .sum();
            b[i] = (b[i] - s) / self.lu.data[row];
        }
        if let Some(d) = &self.scaling {
            b.iter_mut().zip(d).for_each(|(x, d)| *x *= d);
        }
        Ok(())
    }

    /// Smallest ratio of a pivot to the largest original entry of its row: a
    /// cheap indicator of ill-conditioning (small means nearly singular).
    pub fn pivot_ratio(&self) -> f64 {
        self.min_pivot
    }

    /// Number of negative pivots. For a symmetric matrix factored without
    /// row interchanges it equals the number of negative eigenvalues; with
    /// interchanges it is only an indicator.
    pub fn negative_pivots(&self) -> usize {
        self.negative_pivots
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lcg(seed: &mut u64) -> f64 {
        *seed = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((*seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    }

    #[test]
    fn solves_random_banded_systems_to_small_residual() {
        let mut seed = 7u64;
        for &(n, kl, ku) in &[
            (1, 0, 0),
            (5, 1, 1),
            (40, 7, 7),
            (84, 7, 7),
            (403, 7, 7),
            (50, 3, 5),
            (30, 11, 11),
        ] {
            let mut a = BandedMatrix::zeros(n, kl, ku);
            for i in 0..n {
                for j in i.saturating_sub(kl)..(i + ku + 1).min(n) {
                    // indefinite, with small diagonals: pivoting is needed
                    a.add(i, j, lcg(&mut seed) + if i == j { 0.01 } else { 0.0 });
                }
            }
            let x_true: Vec<f64> = (0..n).map(|_| lcg(&mut seed)).collect();
            let b = a.mul_vec(&x_true).unwrap();
            let mut x = b.clone();
            let lu = a.clone().factor("test").unwrap();
            lu.solve_in_place(&mut x).unwrap();
            let r = a.mul_vec(&x).unwrap();
            let res = r
                .iter()
                .zip(&b)
                .map(|(p, q)| (p - q).abs())
                .fold(0.0, f64::max);
            let bn = b.iter().map(|v| v.abs()).fold(0.0, f64::max);
            assert!(res <= 1e-10 * bn.max(1.0), "n={n}: residual {res}");
        }
    }

    #[test]
    fn matches_a_dense_solve() {
        let mut seed = 11u64;
        let n = 24;
        let mut a = BandedMatrix::zeros(n, 3, 3);
        let mut dense = nalgebra::DMatrix::<f64>::zeros(n, n);
        for i in 0..n {
            for j in i.saturating_sub(3)..(i + 4).min(n) {
                let v = lcg(&mut seed);
                a.add(i, j, v);
                dense[(i, j)] = v;
            }
        }
        let b: Vec<f64> = (0..n).map(|_| lcg(&mut seed)).collect();
        let xd = dense
            .lu()
            .solve(&nalgebra::DVector::from_vec(b.clone()))
            .unwrap();
        let mut x = b;
        a.factor("test").unwrap().solve_in_place(&mut x).unwrap();
        for i in 0..n {
            assert!((x[i] - xd[i]).abs() < 1e-9 * (1.0 + xd[i].abs()));
        }
    }

    #[test]
    fn scaled_factorization_solves_badly_scaled_systems() {
        // rows scaled over 12 decades: A = S B S with B well conditioned
        let mut seed = 3u64;
        let n = 60;
        let mut a = BandedMatrix::zeros(n, 3, 3);
        let sc: Vec<f64> = (0..n).map(|i| 10f64.powi((i % 4) as i32 * 4 - 6)).collect();
        for i in 0..n {
            for j in i.saturating_sub(3)..(i + 4).min(n) {
                let b = if i == j { 4.0 } else { 0.3 * lcg(&mut seed) };
                a.add(i, j, sc[i] * b * sc[j]);
            }
        }
        let x_true: Vec<f64> = (0..n).map(|i| lcg(&mut seed) / sc[i]).collect();
        let b = a.mul_vec(&x_true).unwrap();
        let mut x = b.clone();
        a.clone()
            .factor_scaled(0.0, "test")
            .unwrap()
            .solve_in_place(&mut x)
            .unwrap();
        for i in 0..n {
            assert!(
                (x[i] - x_true[i]).abs() <= 1e-10 * x_true[i].abs().max(1e-300) + 1e-12 / sc[i],
                "{i}"
            );
        }
    }

    #[test]
    fn singular_matrix_is_reported_with_its_pivot() {
        let mut a = BandedMatrix::zeros(3, 1, 1);
        a.add(0, 0, 1.0);
        a.add(1, 1, 1.0);
        match a.factor("K") {
            Err(Error::Singular { index, context, .. }) => {
                assert_eq!(index, 2);
                assert_eq!(context, "K");
            }
            other => panic!("expected Singular, got {other:?}"),
        }
        let mut nan = BandedMatrix::zeros(2, 1, 1);
        nan.add(0, 0, f64::NAN);
        assert!(matches!(nan.factor("K"), Err(Error::NonFinite { .. })));
    }
}
