//! Banded matrices, their `L D Lᵀ` factorization (symmetric) and their LU
//! factorization with partial pivoting.
//!
//! The tangent stiffness of a cable is block-tridiagonal in the nodes: with
//! `b` coordinates per node it is banded with `kl = ku = 2b - 1`. It is
//! symmetric, and positive definite near a stable equilibrium: there the
//! Jacobi-scaled `L D Lᵀ` without pivoting ([`BandedMatrix::factor_scaled`],
//! [`BandedMatrix::factor_scaled_symmetric`]) costs `O(n kl²/2)` and is
//! stable. Partial pivoting (`O(n kl (kl + ku))`) keeps the factorization
//! usable when the tangent is indefinite (compression, buckling, iterates
//! far from equilibrium): a symmetric matrix whose `L D Lᵀ` meets a pivot
//! that is not clearly positive is refactored that way. Both are linear in
//! the number of elements; [`BandedLu::solve_many_in_place`] solves several
//! right-hand sides in one sweep (the estimator's adjoint systems).

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
            kind: Kind::Lu { lu: self, piv },
            min_pivot,
            negative_pivots: negative,
            scaling: None,
        })
    }

    /// Factorization of the Jacobi-scaled, shifted matrix
    /// `D A D + shift·I`, `D = diag(|a_ii|^-1/2)`; the returned factors solve
    /// `(A + shift·diag|a_ii|) x = b`. Scaling makes the factorization of
    /// stiffness matrices whose rows span many orders of magnitude accurate.
    ///
    /// A symmetric matrix (every band entry equal to its mirror, as the
    /// assembled tangent stiffness is) whose scaled, shifted form is
    /// positive definite is factored as `L D Lᵀ` without pivoting
    /// ([`BandedMatrix::factor_scaled_symmetric`], a third of the work);
    /// anything else, and a symmetric matrix that turns out indefinite or
    /// nearly singular, by the pivoted LU of [`BandedMatrix::factor`]. Both
    /// solve the same system; the LU is the authority on singularity.
    ///
    /// # Errors
    /// As [`BandedMatrix::factor`].
    pub fn factor_scaled(self, shift: f64, context: &str) -> Result<BandedLu> {
        if self.is_symmetric() {
            return self.factor_scaled_symmetric(shift, context);
        }
        self.factor_scaled_lu(shift, context)
    }

    /// The pivoted-LU path of [`BandedMatrix::factor_scaled`], whatever the
    /// symmetry.
    fn factor_scaled_lu(mut self, shift: f64, context: &str) -> Result<BandedLu> {
        let d = self.jacobi_scaling();
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

    /// `|a_ii|^-1/2` (1 for a zero or non-finite diagonal).
    fn jacobi_scaling(&self) -> Vec<f64> {
        (0..self.n)
            .map(|i| {
                let a = self.data[self.idx(i, i)].abs();
                if a > 0.0 && a.is_finite() {
                    1.0 / a.sqrt()
                } else {
                    1.0
                }
            })
            .collect()
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

    /// As [`BandedMatrix::factor_scaled`] for a matrix known to be symmetric
    /// (only its lower band is read): the Jacobi-scaled, shifted matrix is
    /// factored as `L D Lᵀ` without pivoting when it is positive definite
    /// (every pivot above `n ε` times its row's largest entry); otherwise a
    /// copy is factored by the pivoted LU. Does not consume the matrix.
    ///
    /// # Errors
    /// As [`BandedMatrix::factor`] (raised by the LU fallback).
    pub fn factor_scaled_symmetric(&self, shift: f64, context: &str) -> Result<BandedLu> {
        let d = self.jacobi_scaling();
        match Ldlt::new(self, Some(&d), shift, true) {
            Ok(f) => Ok(f.into_factors(Some(d))),
            // not positive definite, nearly singular or non-finite: the
            // pivoted LU decides (and reports)
            Err(_) => self.clone().factor_scaled_lu(shift, context),
        }
    }

    /// `L D Lᵀ` factorization of a symmetric matrix (its lower band is
    /// read, `kl` sub-diagonals), without pivoting and without scaling. It
    /// exists for any matrix whose leading principal minors do not vanish,
    /// definite or not, and then the number of negative pivots is the
    /// number of negative eigenvalues (Sylvester's law of inertia). Without
    /// pivoting it is stable for positive definite matrices; for indefinite
    /// ones prefer [`BandedMatrix::factor`].
    ///
    /// # Errors
    /// [`Error::Singular`] when a pivot is zero or below `n ε` times the
    /// largest entry of its row; [`Error::NonFinite`] when the band holds a
    /// NaN or infinity.
    ///
    /// # Example
    /// ```
    /// use softrod::banded::BandedMatrix;
    /// let mut a = BandedMatrix::zeros(3, 1, 1);
    /// for i in 0..3 { a.add(i, i, 2.0); }
    /// for i in 0..2 { a.add(i, i + 1, -1.0); a.add(i + 1, i, -1.0); }
    /// let f = a.factor_ldlt("example").unwrap();
    /// assert_eq!(f.negative_pivots(), 0);
    /// let mut x = vec![1.0, 0.0, 1.0];
    /// f.solve_in_place(&mut x).unwrap();
    /// assert!((x[1] - 1.0).abs() < 1e-14);
    /// ```
    pub fn factor_ldlt(&self, context: &str) -> Result<BandedLu> {
        match Ldlt::new(self, None, 0.0, false) {
            Ok(f) => Ok(f.into_factors(None)),
            Err(LdltFailure::NonFinite) => Err(Error::NonFinite {
                context: context.to_string(),
            }),
            Err(LdltFailure::Pivot {
                index,
                pivot,
                scale,
            }) => Err(Error::Singular {
                context: context.to_string(),
                index,
                pivot,
                scale,
            }),
        }
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

/// `y -= c x` over the common length.
#[inline]
fn axpy_neg(c: f64, x: &[f64], y: &mut [f64]) {
    for (yi, xi) in y.iter_mut().zip(x) {
        *yi -= c * xi;
    }
}

/// Why an `L D Lᵀ` factorization stopped.
#[derive(Debug)]
enum LdltFailure {
    /// A NaN or infinity in the band.
    NonFinite,
    /// A pivot vanished (or, when positive definiteness is required, was
    /// not positive).
    Pivot {
        index: usize,
        pivot: f64,
        scale: f64,
    },
}

/// `L D Lᵀ` factors in compact lower-band storage: row `i` holds columns
/// `i − kb ..= i` at offsets `0 ..= kb` (`L` strictly below the diagonal,
/// `D` on it; entries left of column 0 are zero).
#[derive(Debug, Clone)]
struct Ldlt {
    n: usize,
    kb: usize,
    ld: Vec<f64>,
    min_pivot: f64,
    negative: usize,
}

impl Ldlt {
    /// Factors `S A S + shift I` (`S = diag(scale)`, or `I`) from the lower
    /// band of `a`. With `require_pd` a pivot must be positive and above
    /// `n ε` times its row's largest entry, else any pivot above that in
    /// magnitude is accepted.
    fn new(
        a: &BandedMatrix,
        scale: Option<&[f64]>,
        shift: f64,
        require_pd: bool,
    ) -> std::result::Result<Self, LdltFailure> {
        let (n, kb) = (a.n, a.kl);
        let w = kb + 1;
        let mut ld = vec![0.0; n * w];
        // the pivot test's scale: the largest entry of each row; when
        // positive definiteness is required, the diagonal (a positive
        // definite matrix has |a_ij| <= sqrt(a_ii a_jj), and the Jacobi-scaled
        // diagonal is 1 + shift), else the whole row of the original band
        let mut rowmax = vec![0.0f64; n];
        // NaN or infinity anywhere in the lower band makes this NaN
        let mut bad = 0.0f64;
        for i in 0..n {
            let lo = i.saturating_sub(kb);
            let src = i * a.width + (lo + a.kl - i);
            let dst = i * w + (lo + kb - i);
            let len = i - lo + 1;
            let row = &mut ld[dst..dst + len];
            row.copy_from_slice(&a.data[src..src + len]);
            if let Some(s) = scale {
                let si = s[i];
                for (v, sj) in row.iter_mut().zip(&s[lo..=i]) {
                    *v *= si * sj;
                }
            }
            row[len - 1] += shift;
            // v − v is 0 for finite v and NaN for NaN or ±∞
            #[allow(clippy::eq_op)]
            for v in row.iter() {
                bad += v - v;
            }
            rowmax[i] = if require_pd {
                row[len - 1].abs()
            } else {
                let hi = (i + a.ku + 1).min(n);
                let full = &a.data[src..src + (hi - lo)];
                let m = full.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                m.max((full[len - 1] + shift).abs())
            };
        }
        if bad.is_nan() {
            return Err(LdltFailure::NonFinite);
        }
        let rel = (n.max(1) as f64) * f64::EPSILON;
        let mut st = PivotStats {
            rowmax,
            rel,
            require_pd,
            min_pivot: f64::INFINITY,
            negative: 0,
        };
        // the first kb rows (a shorter band) generically; the interior rows
        // by a kernel unrolled for the bandwidth when it is a cable's
        let head = kb.min(n);
        ldlt_rows_generic(&mut ld, kb, 0..head, &mut st)?;
        match kb {
            7 => ldlt_rows_fixed::<7, 8>(&mut ld, head..n, &mut st)?,
            11 => ldlt_rows_fixed::<11, 12>(&mut ld, head..n, &mut st)?,
            _ => ldlt_rows_generic(&mut ld, kb, head..n, &mut st)?,
        }
        Ok(Ldlt {
            n,
            kb,
            ld,
            min_pivot: st.min_pivot,
            negative: st.negative,
        })
    }

    fn into_factors(self, scaling: Option<Vec<f64>>) -> BandedLu {
        BandedLu {
            min_pivot: self.min_pivot,
            negative_pivots: self.negative,
            kind: Kind::Ldlt(self),
            scaling,
        }
    }

    /// Solves `L D Lᵀ x = b` for `r` right-hand sides stored row-major
    /// (`b[i r + c]`, entry `i` of right-hand side `c`).
    fn solve(&self, b: &mut [f64], r: usize) {
        let (n, kb) = (self.n, self.kb);
        let w = kb + 1;
        if r == 1 {
            match kb {
                7 => ldlt_solve_one::<7, 8>(&self.ld, n, b),
                11 => ldlt_solve_one::<11, 12>(&self.ld, n, b),
                _ => {
                    for i in 0..n {
                        let lo = i.saturating_sub(kb);
                        let row = &self.ld[i * w + (lo + kb - i)..i * w + kb];
                        let s = dot(row, &b[lo..i]);
                        b[i] -= s;
                    }
                    for (x, row) in b.iter_mut().zip(self.ld.chunks_exact(w)) {
                        *x /= row[kb];
                    }
                    for j in (0..n).rev() {
                        let lo = j.saturating_sub(kb);
                        let row = &self.ld[j * w + (lo + kb - j)..j * w + kb];
                        let bj = b[j];
                        if bj != 0.0 {
                            axpy_neg(bj, row, &mut b[lo..j]);
                        }
                    }
                }
            }
            return;
        }
        if kb == 7 || kb == 11 {
            // groups of four right-hand sides, gathered into contiguous
            // rows of four: the kernels are unrolled over band and group
            let mut scratch = vec![[0.0; 4]; n];
            let mut c0 = 0;
            while c0 < r {
                let g = (r - c0).min(4);
                for (row, x) in b.chunks_exact(r).zip(scratch.iter_mut()) {
                    for c in 0..4 {
                        x[c] = if c < g { row[c0 + c] } else { 0.0 };
                    }
                }
                if kb == 7 {
                    ldlt_solve_group::<7, 8>(&self.ld, n, &mut scratch);
                } else {
                    ldlt_solve_group::<11, 12>(&self.ld, n, &mut scratch);
                }
                for (row, x) in b.chunks_exact_mut(r).zip(scratch.iter()) {
                    row[c0..c0 + g].copy_from_slice(&x[..g]);
                }
                c0 += g;
            }
            return;
        }
        for i in 0..n {
            let lo = i.saturating_sub(kb);
            let (head, tail) = b.split_at_mut(i * r);
            let bi = &mut tail[..r];
            for k in lo..i {
                let l = self.ld[i * w + (k + kb - i)];
                if l != 0.0 {
                    axpy_neg(l, &head[k * r..(k + 1) * r], bi);
                }
            }
        }
        for i in 0..n {
            let dinv = 1.0 / self.ld[i * w + kb];
            b[i * r..(i + 1) * r].iter_mut().for_each(|v| *v *= dinv);
        }
        for j in (0..n).rev() {
            let lo = j.saturating_sub(kb);
            let (head, tail) = b.split_at_mut(j * r);
            let bj = &tail[..r];
            for k in lo..j {
                let l = self.ld[j * w + (k + kb - j)];
                if l != 0.0 {
                    axpy_neg(l, bj, &mut head[k * r..(k + 1) * r]);
                }
            }
        }
    }
}

/// Pivot bookkeeping of an `L D Lᵀ` factorization.
struct PivotStats {
    rowmax: Vec<f64>,
    rel: f64,
    require_pd: bool,
    min_pivot: f64,
    negative: usize,
}

impl PivotStats {
    /// Accepts or refuses the pivot `d` of row `i`.
    #[inline]
    fn check(&mut self, i: usize, d: f64) -> std::result::Result<(), LdltFailure> {
        let scale = self.rowmax[i];
        let ok = if self.require_pd {
            d > self.rel * scale
        } else {
            d.abs() > self.rel * scale
        };
        if !ok || !d.is_finite() {
            return Err(LdltFailure::Pivot {
                index: i,
                pivot: d,
                scale,
            });
        }
        self.min_pivot = self.min_pivot.min(d.abs() / scale);
        if d < 0.0 {
            self.negative += 1;
        }
        Ok(())
    }
}

/// Rows `rows` of an `L D Lᵀ` factorization in compact lower-band storage
/// of bandwidth `kb` (any row, any bandwidth): a left-looking sweep, for
/// `j < i`: `u_j = a_ij − Σ_{k<j} u_k L_jk`, `L_ij = u_j / D_j`, then
/// `D_i = a_ii − Σ_k u_k L_ik`.
fn ldlt_rows_generic(
    ld: &mut [f64],
    kb: usize,
    rows: std::ops::Range<usize>,
    st: &mut PivotStats,
) -> std::result::Result<(), LdltFailure> {
    let w = kb + 1;
    let mut u = vec![0.0; kb];
    for i in rows {
        let lo = i.saturating_sub(kb);
        let m = i - lo; // entries left of the diagonal
        let (done, rest) = ld.split_at_mut(i * w);
        let row_i = &mut rest[..w];
        for jj in 0..m {
            let j = lo + jj;
            let row_j = &done[j * w..(j + 1) * w];
            // columns k = max(lo, j − kb) .. j of both rows
            let k0 = lo.max(j.saturating_sub(kb));
            let mut s = row_i[kb - m + jj];
            for (uk, ljk) in u[k0 - lo..jj].iter().zip(&row_j[k0 + kb - j..kb]) {
                s -= uk * ljk;
            }
            u[jj] = s;
            row_i[kb - m + jj] = s / row_j[kb];
        }
        let mut d = row_i[kb];
        for (uk, lik) in u[..m].iter().zip(&row_i[kb - m..kb]) {
            d -= uk * lik;
        }
        st.check(i, d)?;
        row_i[kb] = d;
    }
    Ok(())
}

/// As [`ldlt_rows_generic`] for rows with a full band (`i >= KB`) of the
/// bandwidth `KB` (`W = KB + 1`): fixed trip counts, unrolled by the
/// compiler. The same operations in the same order.
fn ldlt_rows_fixed<const KB: usize, const W: usize>(
    ld: &mut [f64],
    rows: std::ops::Range<usize>,
    st: &mut PivotStats,
) -> std::result::Result<(), LdltFailure> {
    debug_assert_eq!(W, KB + 1);
    for i in rows {
        let (done, rest) = ld.split_at_mut(i * W);
        let Ok(row_i) = <&mut [f64; W]>::try_from(&mut rest[..W]) else {
            continue;
        };
        // the KB rows above, i − KB .. i
        let prev = &done[(i - KB) * W..];
        let mut u = [0.0; KB];
        for jj in 0..KB {
            let Ok(row_j) = <&[f64; W]>::try_from(&prev[jj * W..(jj + 1) * W]) else {
                continue;
            };
            // row j = i − KB + jj holds column i − KB + kk at offset KB − jj + kk
            let mut s = row_i[jj];
            for kk in 0..jj {
                s -= u[kk] * row_j[KB - jj + kk];
            }
            u[jj] = s;
            row_i[jj] = s / row_j[KB];
        }
        let mut d = row_i[KB];
        for kk in 0..KB {
            d -= u[kk] * row_i[kk];
        }
        st.check(i, d)?;
        row_i[KB] = d;
    }
    Ok(())
}

/// Forward, diagonal and back substitution with `L D Lᵀ` factors for one
/// right-hand side; rows `i >= KB` by fixed-length loops.
#[allow(clippy::needless_range_loop)]
fn ldlt_solve_one<const KB: usize, const W: usize>(ld: &[f64], n: usize, b: &mut [f64]) {
    let head = KB.min(n);
    let (ld, b) = (&ld[..n * W], &mut b[..n]);
    // forward: y_i = b_i − Σ_k L_ik y_k
    for i in 1..head {
        let row = &ld[i * W..(i + 1) * W];
        let mut s = b[i];
        for (l, x) in row[KB - i..KB].iter().zip(&b[..i]) {
            s -= l * x;
        }
        b[i] = s;
    }
    for (i, row) in ld.chunks_exact(W).enumerate().skip(head) {
        let (Ok(row), Ok(x)) = (
            <&[f64; W]>::try_from(row),
            <&[f64; KB]>::try_from(&b[i - KB..i]),
        ) else {
            continue;
        };
        let mut s = b[i];
        for kk in 0..KB {
            s -= row[kk] * x[kk];
        }
        b[i] = s;
    }
    for (x, row) in b.iter_mut().zip(ld.chunks_exact(W)) {
        *x /= row[KB];
    }
    // back: x_k −= L_jk x_j for j descending
    for (j, row) in ld.chunks_exact(W).enumerate().skip(head).rev() {
        let (before, rest) = b.split_at_mut(j);
        let bj = rest[0];
        let (Ok(row), Ok(x)) = (
            <&[f64; W]>::try_from(row),
            <&mut [f64; KB]>::try_from(&mut before[j - KB..]),
        ) else {
            continue;
        };
        for kk in 0..KB {
            x[kk] -= row[kk] * bj;
        }
    }
    for j in (1..head).rev() {
        let row = &ld[j * W..(j + 1) * W];
        let (before, rest) = b.split_at_mut(j);
        let bj = rest[0];
        for (x, l) in before.iter_mut().zip(&row[KB - j..KB]) {
            *x -= l * bj;
        }
    }
}

/// As [`ldlt_solve_one`] for four right-hand sides at once, stored as
/// rows of four.
#[allow(clippy::needless_range_loop)]
fn ldlt_solve_group<const KB: usize, const W: usize>(ld: &[f64], n: usize, b: &mut [[f64; 4]]) {
    let head = KB.min(n);
    for i in 0..n {
        let lo = i.saturating_sub(KB);
        let row = &ld[i * W..(i + 1) * W];
        let (done, rest) = b.split_at_mut(i);
        let mut s = rest[0];
        if i >= head {
            let (Ok(row), Ok(x)) = (
                <&[f64; W]>::try_from(row),
                <&[[f64; 4]; KB]>::try_from(&done[lo..i]),
            ) else {
                continue;
            };
            for kk in 0..KB {
                let l = row[kk];
                for c in 0..4 {
                    s[c] -= l * x[kk][c];
                }
            }
        } else {
            for (l, x) in row[lo + KB - i..KB].iter().zip(&done[lo..i]) {
                for c in 0..4 {
                    s[c] -= l * x[c];
                }
            }
        }
        rest[0] = s;
    }
    for i in 0..n {
        let d = ld[i * W + KB];
        for c in 0..4 {
            b[i][c] /= d;
        }
    }
    for j in (0..n).rev() {
        let lo = j.saturating_sub(KB);
        let row = &ld[j * W..(j + 1) * W];
        let (before, rest) = b.split_at_mut(j);
        let bj = rest[0];
        if j >= head {
            let (Ok(row), Ok(x)) = (
                <&[f64; W]>::try_from(row),
                <&mut [[f64; 4]; KB]>::try_from(&mut before[lo..j]),
            ) else {
                continue;
            };
            for kk in 0..KB {
                let l = row[kk];
                for c in 0..4 {
                    x[kk][c] -= l * bj[c];
                }
            }
        } else {
            for (x, l) in before[lo..j].iter_mut().zip(&row[lo + KB - j..KB]) {
                for c in 0..4 {
                    x[c] -= l * bj[c];
                }
            }
        }
    }
}

/// Which factorization a [`BandedLu`] holds.
#[derive(Debug, Clone)]
enum Kind {
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
    kind: Kind,
    min_pivot: f64,
    negative_pivots: usize,
    scaling: Option<Vec<f64>>,
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
    /// [`Error::DimensionMismatch`] (field `b`) if `b` does not have `n` entries.
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
    /// [`Error::DimensionMismatch`] (field `b`) if `b` does not have
    /// `n · nrhs` entries.
    ///
    /// # Example
    /// ```
    /// use softrod::banded::BandedMatrix;
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

    /// A random symmetric band matrix: `B + Bᵀ` plus `diag` on the
    /// diagonal (positive definite for a large enough `diag`).
    fn random_symmetric(n: usize, kb: usize, diag: f64, seed: &mut u64) -> BandedMatrix {
        let mut a = BandedMatrix::zeros(n, kb, kb);
        for i in 0..n {
            for j in i.saturating_sub(kb)..i {
                let v = lcg(seed);
                a.add(i, j, v);
                a.add(j, i, v);
            }
            a.add(i, i, diag + lcg(seed));
        }
        a
    }

    fn dense_of(a: &BandedMatrix) -> nalgebra::DMatrix<f64> {
        let n = a.n();
        nalgebra::DMatrix::from_fn(n, n, |i, j| a.get(i, j))
    }

    fn max_rel_diff(x: &[f64], y: &[f64]) -> f64 {
        let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
        x.iter()
            .zip(y)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
            / scale
    }

    #[test]
    fn ldlt_matches_lu_and_dense_solves_on_spd_and_indefinite_bands() {
        let mut seed = 21u64;
        for &(n, kb, diag, spd) in &[
            (1, 0, 3.0, true),
            (6, 1, 3.0, true),
            (84, 7, 16.0, true),
            (403, 7, 16.0, true),
            (50, 3, 0.3, false),
            (84, 7, 0.5, false),
            (30, 11, 0.0, false),
        ] {
            let a = random_symmetric(n, kb, diag, &mut seed);
            assert!(a.is_symmetric());
            let dense = dense_of(&a);
            let eig = dense.clone().symmetric_eigenvalues();
            let neg = eig.iter().filter(|v| **v < 0.0).count();
            assert_eq!(
                neg == 0,
                spd,
                "n={n}: test matrix has {neg} negative eigenvalues"
            );
            let b: Vec<f64> = (0..n).map(|_| lcg(&mut seed)).collect();
            let xd: Vec<f64> = dense
                .clone()
                .lu()
                .solve(&nalgebra::DVector::from_vec(b.clone()))
                .unwrap()
                .iter()
                .copied()
                .collect();
            let ldlt = a.factor_ldlt("test").unwrap();
            assert!(ldlt.is_ldlt());
            // Sylvester: the pivots' signs are the eigenvalues' signs
            assert_eq!(ldlt.negative_pivots(), neg, "n={n}");
            let mut x = b.clone();
            ldlt.solve_in_place(&mut x).unwrap();
            assert!(max_rel_diff(&x, &xd) < 1e-9, "n={n}: ldlt vs dense");
            let mut xl = b.clone();
            a.clone()
                .factor("t")
                .unwrap()
                .solve_in_place(&mut xl)
                .unwrap();
            assert!(max_rel_diff(&x, &xl) < 1e-9, "n={n}: ldlt vs lu");
            // the scaled factorization takes LDLᵀ exactly when positive definite
            let scaled = a.clone().factor_scaled(0.0, "test").unwrap();
            assert_eq!(scaled.is_ldlt(), spd, "n={n}");
            let mut xs = b.clone();
            scaled.solve_in_place(&mut xs).unwrap();
            assert!(max_rel_diff(&xs, &xd) < 1e-9, "n={n}: scaled vs dense");
            let by_ref = a.factor_scaled_symmetric(0.0, "test").unwrap();
            assert_eq!(by_ref.is_ldlt(), spd);
        }
    }

    #[test]
    fn shifted_scaled_factors_solve_the_shifted_system() {
        // (A + μ diag|a_ii|) x = b, for the LDLᵀ and the LU path alike
        let mut seed = 5u64;
        for diag in [16.0, 0.2] {
            let a = random_symmetric(40, 7, diag, &mut seed);
            let mu = 0.3;
            let mut shifted = a.clone();
            for i in 0..40 {
                shifted.add(i, i, mu * a.get(i, i).abs());
            }
            let b: Vec<f64> = (0..40).map(|_| lcg(&mut seed)).collect();
            let mut x = b.clone();
            a.clone()
                .factor_scaled(mu, "t")
                .unwrap()
                .solve_in_place(&mut x)
                .unwrap();
            let r = shifted.mul_vec(&x).unwrap();
            assert!(max_rel_diff(&r, &b) < 1e-10, "diag {diag}");
        }
    }

    #[test]
    fn several_right_hand_sides_agree_with_one_at_a_time() {
        let mut seed = 9u64;
        let spd = random_symmetric(60, 7, 16.0, &mut seed);
        let mut general = BandedMatrix::zeros(60, 3, 5);
        for i in 0..60usize {
            for j in i.saturating_sub(3)..(i + 6).min(60) {
                general.add(i, j, lcg(&mut seed) + if i == j { 0.05 } else { 0.0 });
            }
        }
        let factors = [
            spd.factor_ldlt("t").unwrap(),
            spd.clone().factor_scaled(0.0, "t").unwrap(),
            general.clone().factor("t").unwrap(),
            general.clone().factor_scaled(0.0, "t").unwrap(),
        ];
        for f in &factors {
            for r in [1usize, 3, 10] {
                let cols: Vec<Vec<f64>> = (0..r)
                    .map(|_| (0..60).map(|_| lcg(&mut seed)).collect())
                    .collect();
                let mut b = vec![0.0; 60 * r];
                for i in 0..60 {
                    for c in 0..r {
                        b[i * r + c] = cols[c][i];
                    }
                }
                f.solve_many_in_place(&mut b, r).unwrap();
                for (c, col) in cols.iter().enumerate() {
                    let mut x = col.clone();
                    f.solve_in_place(&mut x).unwrap();
                    let xm: Vec<f64> = (0..60).map(|i| b[i * r + c]).collect();
                    assert!(max_rel_diff(&xm, &x) < 1e-13, "r {r} column {c}");
                }
            }
            assert!(matches!(
                f.solve_many_in_place(&mut [0.0; 7], 2),
                Err(Error::DimensionMismatch { .. })
            ));
        }
    }

    #[test]
    fn ldlt_reports_a_singular_matrix_with_its_pivot() {
        // [[1, 1], [1, 1]] ⊕ [2]: the second pivot vanishes
        let mut a = BandedMatrix::zeros(3, 1, 1);
        for (i, j, v) in [
            (0, 0, 1.0),
            (0, 1, 1.0),
            (1, 0, 1.0),
            (1, 1, 1.0),
            (2, 2, 2.0),
        ] {
            a.add(i, j, v);
        }
        match a.factor_ldlt("K") {
            Err(Error::Singular {
                index,
                context,
                pivot,
                scale,
            }) => {
                assert_eq!((index, context.as_str()), (1, "K"));
                assert!(pivot.abs() <= 1e-15 && scale == 1.0);
            }
            other => panic!("expected Singular, got {other:?}"),
        }
        // a zero leading pivot of an invertible matrix: LDLᵀ cannot, LU can
        let mut b = BandedMatrix::zeros(2, 1, 1);
        for (i, j, v) in [(0, 1, 1.0), (1, 0, 1.0), (1, 1, 1.0)] {
            b.add(i, j, v);
        }
        assert!(matches!(
            b.factor_ldlt("K"),
            Err(Error::Singular { index: 0, .. })
        ));
        let f = b.clone().factor_scaled(0.0, "K").unwrap();
        assert!(!f.is_ldlt());
        let mut x = vec![1.0, 2.0];
        f.solve_in_place(&mut x).unwrap();
        assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15);
        // the scaled path still reports a truly singular matrix (from the LU)
        assert!(matches!(
            a.factor_scaled(0.0, "K"),
            Err(Error::Singular { .. })
        ));
        let mut nan = BandedMatrix::zeros(2, 1, 1);
        nan.add(1, 0, f64::NAN);
        assert!(matches!(nan.factor_ldlt("K"), Err(Error::NonFinite { .. })));
        assert!(matches!(
            nan.factor_scaled(0.0, "K"),
            Err(Error::NonFinite { .. })
        ));
    }

    #[test]
    fn symmetry_is_detected_exactly() {
        let mut seed = 1u64;
        let mut a = random_symmetric(20, 3, 4.0, &mut seed);
        assert!(a.is_symmetric());
        a.add(7, 5, 1e-300);
        assert!(a.is_symmetric()); // below the entry's ulp: unchanged
        a.add(7, 5, 1e-3);
        assert!(!a.is_symmetric());
        assert!(!BandedMatrix::zeros(4, 1, 2).is_symmetric());
    }

    #[test]
    fn mul_vec_into_matches_the_dense_product() {
        let mut seed = 4u64;
        let mut a = BandedMatrix::zeros(30, 2, 4);
        for i in 0..30usize {
            for j in i.saturating_sub(2)..(i + 5).min(30) {
                a.add(i, j, lcg(&mut seed));
            }
        }
        let x: Vec<f64> = (0..30).map(|_| lcg(&mut seed)).collect();
        let yd = dense_of(&a) * nalgebra::DVector::from_vec(x.clone());
        let mut y = vec![0.0; 30];
        a.mul_vec_into(&x, &mut y).unwrap();
        for i in 0..30 {
            assert!((y[i] - yd[i]).abs() < 1e-14);
        }
        assert!(a.mul_vec_into(&x, &mut [0.0; 3]).is_err());
    }
}
