//! The `L D Lᵀ` factorization of a symmetric band matrix without pivoting,
//! in compact lower-band storage, with kernels unrolled for the cable's
//! bandwidths (7 in the plane, 11 in space).

use super::factors::{BandedLu, Kind};
use super::{axpy_neg, dot, BandedMatrix};
use crate::linsolve::Inertia;

/// Why an `L D Lᵀ` factorization stopped.
#[derive(Debug)]
pub(super) enum LdltFailure {
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
pub(super) struct Ldlt {
    pub(super) n: usize,
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
    pub(super) fn new(
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
        Self::factor_band(n, kb, ld, rowmax, require_pd)
    }

    /// Factors the lower band `ld` (compact storage, filled) in place; the
    /// pivot of row `i` is tested against `rowmax[i]`.
    fn factor_band(
        n: usize,
        kb: usize,
        mut ld: Vec<f64>,
        rowmax: Vec<f64>,
        require_pd: bool,
    ) -> std::result::Result<Self, LdltFailure> {
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

    pub(super) fn into_factors(self, scaling: Option<Vec<f64>>) -> BandedLu {
        BandedLu {
            min_pivot: self.min_pivot,
            negative_pivots: self.negative,
            inertia: Some(self.inertia()),
            kind: Kind::Ldlt(self),
            scaling,
        }
    }

    /// The inertia: the signs of the pivots (Sylvester's law of inertia).
    pub(super) fn inertia(&self) -> Inertia {
        Inertia {
            positive: self.n - self.negative,
            negative: self.negative,
        }
    }

    /// Solves `L D Lᵀ X = B` for `r` right-hand sides stored column after
    /// column (`b[c n + i]`).
    pub(super) fn solve_columns(&self, b: &mut [f64], r: usize) {
        let n = self.n;
        if r == 1 {
            self.solve(b, 1);
            return;
        }
        if self.kb == 7 || self.kb == 11 {
            // groups of four columns, gathered into rows of four
            let mut scratch = vec![[0.0; 4]; n];
            let mut c0 = 0;
            while c0 < r {
                let g = (r - c0).min(4);
                let cols = &mut b[c0 * n..(c0 + g) * n];
                for (i, x) in scratch.iter_mut().enumerate() {
                    for c in 0..4 {
                        x[c] = if c < g { cols[c * n + i] } else { 0.0 };
                    }
                }
                if self.kb == 7 {
                    ldlt_solve_group::<7, 8>(&self.ld, n, &mut scratch);
                } else {
                    ldlt_solve_group::<11, 12>(&self.ld, n, &mut scratch);
                }
                for (i, x) in scratch.iter().enumerate() {
                    for (c, v) in x.iter().take(g).enumerate() {
                        cols[c * n + i] = *v;
                    }
                }
                c0 += g;
            }
            return;
        }
        let mut rows = vec![0.0; n * r];
        for (c, col) in b.chunks_exact(n).enumerate() {
            for (i, v) in col.iter().enumerate() {
                rows[i * r + c] = *v;
            }
        }
        self.solve(&mut rows, r);
        for (c, col) in b.chunks_exact_mut(n).enumerate() {
            for (i, v) in col.iter_mut().enumerate() {
                *v = rows[i * r + c];
            }
        }
    }

    /// Solves `L D Lᵀ x = b` for `r` right-hand sides stored row-major
    /// (`b[i r + c]`, entry `i` of right-hand side `c`).
    pub(super) fn solve(&self, b: &mut [f64], r: usize) {
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
