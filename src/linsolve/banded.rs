//! Banded matrices: the storage of the load Gram matrix `∫ Sᵀ S dX` and a
//! tangent target for element-level tests.
//!
//! A cable's matrices are block-tridiagonal in the nodes: with `b`
//! coordinates per node they are banded with `kl = ku = 2b - 1`. Tangents
//! are factored by [`crate::linsolve::TangentSolver`] (faer's sparse
//! `L D Lᵀ`); the banded factorizations were removed after measurement (they
//! were at most 1.25x faster end to end, see the README's Performance).

use crate::error::{Error, Result, check_len};

/// The most numbers [`BandedMatrix::try_zeros`] stores (2³⁰, 8 GiB).
pub const MAX_ENTRIES: usize = 1 << 30;

/// A square banded matrix with `kl` sub- and `ku` super-diagonals.
///
/// Storage is row-major with room for the fill-in of pivoting: row `i` holds
/// columns `i - kl ..= i + ku + kl`.
///
/// # Example
/// ```
/// use softrod::linsolve::BandedMatrix;
/// let mut a = BandedMatrix::zeros(3, 1, 1);
/// for i in 0..3 { a.add(i, i, 2.0); }
/// a.add(0, 1, -1.0); a.add(1, 0, -1.0); a.add(1, 2, -1.0); a.add(2, 1, -1.0);
/// assert_eq!(a.mul_vec(&[1.0, 1.0, 1.0]).unwrap(), vec![1.0, 0.0, 1.0]);
/// assert!(a.is_symmetric());
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
    /// use softrod::{linsolve::BandedMatrix, Error};
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
        // only the band: the fill-in room right of it is written by the LU
        // factorization alone, which consumes its matrix, so it is zero
        let (kl, ku, w) = (self.kl, self.ku, self.width);
        for row in self.data.chunks_exact_mut(w) {
            row[..kl + ku + 1].iter_mut().for_each(|v| *v = 0.0);
        }
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
    /// let mut a = softrod::linsolve::BandedMatrix::zeros(3, 1, 1);
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
        let mut y = vec![0.0; self.n];
        self.mul_vec_into(x, &mut y)?;
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
        let (kl, ku, w) = (self.kl, self.ku, self.width);
        self.data
            .chunks_exact(w)
            .flat_map(|row| &row[..kl + ku + 1])
            .fold(0.0f64, |m, v| m.max(v.abs()))
    }

    /// Whether every entry of the band equals its mirror image (exactly;
    /// `kl` must equal `ku`).
    pub fn is_symmetric(&self) -> bool {
        if self.kl != self.ku {
            return false;
        }
        let (n, kb, w) = (self.n, self.kl, self.width);
        for i in 0..n {
            let row = i * w + kb; // (i, i)
            let last = (i + kb).min(n.saturating_sub(1));
            for j in i + 1..=last {
                // (i, j) against (j, i)
                if self.data[row + (j - i)] != self.data[j * w + kb - (j - i)] {
                    return false;
                }
            }
        }
        true
    }
    /// `y = A x` into `y` (no allocation).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `x` or `y` does not have `n` entries.
    pub fn mul_vec_into(&self, x: &[f64], y: &mut [f64]) -> Result<()> {
        check_len("x", self.n, x.len())?;
        check_len("y", self.n, y.len())?;
        let (n, kl, ku, w) = (self.n, self.kl, self.ku, self.width);
        for (i, yi) in y.iter_mut().enumerate() {
            let lo = i.saturating_sub(kl);
            let hi = (i + ku + 1).min(n);
            let start = i * w + (lo + kl - i);
            *yi = dot(&self.data[start..start + (hi - lo)], &x[lo..hi]);
        }
        Ok(())
    }

    /// Sub-diagonals `kl`.
    pub fn kl(&self) -> usize {
        self.kl
    }

    /// Super-diagonals `ku`.
    pub fn ku(&self) -> usize {
        self.ku
    }

    /// Adds the dense symmetric `size × size` block `block` (row-major) at
    /// rows and columns `off .. off + size`, without checks: the caller
    /// guarantees `off + size <= n` and `size <= min(kl, ku) + 1`.
    #[inline]
    pub(crate) fn add_block_unchecked(&mut self, off: usize, size: usize, block: &[f64]) {
        let w = self.width;
        for (r, brow) in block.chunks_exact(size).take(size).enumerate() {
            let start = (off + r) * w + self.kl - r;
            for (d, v) in self.data[start..start + size].iter_mut().zip(brow) {
                *d += v;
            }
        }
    }
}

/// `Σ a_i b_i` over the common length, in four independent partial sums
/// (the compiler keeps them in registers and may vectorize).
#[inline]
pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut s = [0.0f64; 4];
    let mut ca = a.chunks_exact(4);
    let mut cb = b.chunks_exact(4);
    for (x, y) in (&mut ca).zip(&mut cb) {
        s[0] += x[0] * y[0];
        s[1] += x[1] * y[1];
        s[2] += x[2] * y[2];
        s[3] += x[3] * y[3];
    }
    let mut t = (s[0] + s[2]) + (s[1] + s[3]);
    for (x, y) in ca.remainder().iter().zip(cb.remainder()) {
        t += x * y;
    }
    t
}

#[cfg(test)]
mod tests;
