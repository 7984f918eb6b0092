//! A band `L D Lᵀ` in the dofs' own order, for the patterns that are band
//! matrices with little fill (a chain numbered node by node: a robot's
//! tangent, half-bandwidth `2 NODE_DOFS − 1`).
//!
//! For a positive definite matrix it is what faer's simplicial `L D Lᵀ`
//! computes (no pivoting either), without the per-row elimination-tree
//! reach and the permutation: measured on a 4-element robot (callgrind,
//! `examples/peer_times.rs`' small loads), faer's numeric factorization
//! took about a quarter of a whole static solve. A matrix that is not
//! positive definite goes on to the general path (faer's `L D Lᵀ` for the
//! inertia and its pivoted LU), which this module does not replace.

use crate::linsolve::{LinsolveError, SymmetricMatrix, SymmetricPattern, pivot_tolerance};

/// A pattern's band layout (built once, at analysis).
#[derive(Debug)]
pub(super) struct Band {
    /// The half-bandwidth `b`: `a_ij = 0` for `|i − j| > b`.
    b: usize,
    /// For each stored slot of the pattern (upper triangle, column by
    /// column): its place in the band storage, its row and its column.
    slots: Vec<(usize, usize, usize)>,
}

/// The largest `n (b + 1)` (band storage) kept on the band path, relative
/// to the entries of faer's factor with its fill-reducing ordering: the
/// band's work grows as `n b²`, the general factor's with its fill.
const MAX_BAND_FILL: usize = 2;

/// Below this size a dense band of any width is cheap (`n³/6` flops).
const SMALL: usize = 32;

impl Band {
    /// The band layout of `pattern`, if its band in the natural order has
    /// no more than [`MAX_BAND_FILL`] times `factor_entries` entries (or
    /// the pattern is small).
    ///
    /// # Errors
    /// [`LinsolveError::NotBanded`] (its band and `factor_entries`)
    /// otherwise.
    pub(super) fn of(
        pattern: &SymmetricPattern,
        factor_entries: usize,
    ) -> Result<Band, LinsolveError> {
        let n = pattern.n();
        let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
        let mut b = 0;
        for j in 0..n {
            for &i in &ri[cp[j]..cp[j + 1]] {
                b = b.max(j.abs_diff(i));
            }
        }
        let storage = n.checked_mul(b + 1);
        let narrow = storage.is_some_and(|s| s <= MAX_BAND_FILL.saturating_mul(factor_entries));
        if n > SMALL && !narrow {
            return Err(LinsolveError::NotBanded {
                half_bandwidth: b,
                band_entries: storage.unwrap_or(usize::MAX),
                factor_entries,
            });
        }
        let mut slots = Vec::with_capacity(ri.len());
        for j in 0..n {
            for &i in &ri[cp[j]..cp[j + 1]] {
                let (lo, hi) = (i.min(j), i.max(j));
                // row `hi`, column `lo` of the lower band
                slots.push(((hi + 1) * b + lo, i, j));
            }
        }
        Ok(Band { b, slots })
    }

    /// The half-bandwidth.
    pub(super) fn b(&self) -> usize {
        self.b
    }

    /// The row and column of each stored entry of the pattern, in the
    /// order of its values.
    pub(super) fn entries(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.slots.iter().map(|&(_, i, j)| (i, j))
    }

    /// Factors `d_i d_j k_ij + μ δ_ij` (`d` the Jacobi scaling in the
    /// natural order). `Ok(Ok((factors, smallest pivot ratio)))` when every
    /// pivot exceeds `n ε` times its diagonal entry (the general path's
    /// test of positive definiteness), `Ok(Err((row, pivot)))` at the first
    /// that does not.
    ///
    /// # Errors
    /// [`LinsolveError::NonFinite`] for a matrix entry that is not finite.
    pub(super) fn factor(
        &self,
        matrix: &SymmetricMatrix,
        d: &[f64],
        shift: f64,
    ) -> Result<Banded, LinsolveError> {
        let values = matrix.values();
        let mut bad = 0.0f64;
        for &v in values {
            #[allow(clippy::eq_op)]
            {
                bad += v - v;
            }
        }
        if bad.is_nan() {
            matrix.check_finite()?;
        }
        let (n, b) = (d.len(), self.b);
        let w = b + 1;
        // `b` rows of zeros (pivot 1) before the matrix's, so that every
        // row eliminates the same `b` columns before its diagonal
        let mut l = vec![0.0; (n + b) * w];
        for (&v, &(at, i, j)) in values.iter().zip(&self.slots) {
            l[at + b * w] = v * d[i] * d[j];
        }
        let mut pivots = vec![1.0; n + b];
        // fixed widths for the elements' bands (planar cable 7, spatial 11
        // and 23): loops the compiler unrolls; any other width by slices
        let done = match b {
            7 => factor_rows(l.as_chunks_mut::<8>().0, &mut pivots, shift),
            11 => factor_rows(l.as_chunks_mut::<12>().0, &mut pivots, shift),
            23 => factor_rows(l.as_chunks_mut::<24>().0, &mut pivots, shift),
            _ => factor_rows(
                &mut l.chunks_exact_mut(w).collect::<Vec<_>>(),
                &mut pivots,
                shift,
            ),
        };
        Ok(done.map(|min_ratio| (BandFactors { b, l, pivots }, min_ratio)))
    }
}

/// The band `L D Lᵀ` in place on `rows` (`b + 1` entries each, the first
/// `b` rows zero, `pivots` 1 there): row `r` holds the entries of columns
/// `r − b … r`, overwritten by `L` (unit diagonal) and its pivot in
/// `pivots[r]`. The smallest ratio of a pivot to its diagonal entry, or
/// the first row (of the matrix) whose pivot does not exceed `n ε` times it.
fn factor_rows<R: AsRef<[f64]> + AsMut<[f64]>>(
    rows: &mut [R],
    pivots: &mut [f64],
    shift: f64,
) -> Result<f64, (usize, f64)> {
    let Some(w) = rows.first().map(|r| r.as_ref().len()) else {
        return Ok(f64::INFINITY);
    };
    let b = w - 1;
    let n = rows.len() - b;
    let rel = pivot_tolerance(n);
    let mut min_ratio = f64::INFINITY;
    // `v[t] = L_ij D_j`, `j = i − b + t`, along row i
    let mut v_stack = [0.0f64; 32];
    let mut v_heap = Vec::new();
    let v: &mut [f64] = if w <= v_stack.len() {
        &mut v_stack[..w]
    } else {
        v_heap.resize(w, 0.0);
        &mut v_heap
    };
    for r in b..rows.len() {
        let (before, rest) = rows.split_at_mut(r);
        let Some(row) = rest.first_mut() else { break };
        let row = row.as_mut();
        for t in 0..b {
            // row j = i − b + t is stored at r − b + t; its column
            // i − b + t' at t' + b − t
            let row_j = before[r - b + t].as_ref();
            let mut s = row[t];
            for tp in 0..t {
                s -= v[tp] * row_j[tp + b - t];
            }
            v[t] = s;
            row[t] = s / pivots[r - b + t];
        }
        let scale = row[b] + shift;
        let mut s = scale;
        for tp in 0..b {
            s -= v[tp] * row[tp];
        }
        if !super::exceeds(s, rel * scale.abs()) {
            return Err((r - b, s));
        }
        min_ratio = min_ratio.min(s / scale.abs());
        pivots[r] = s;
        row[b] = 1.0;
    }
    Ok(min_ratio)
}

/// A band factorization: the factors and the smallest pivot ratio, or the
/// first row whose pivot is not clearly positive and that pivot.
pub(super) type Banded = Result<(BandFactors, f64), (usize, f64)>;

/// The factors of a band `L D Lᵀ` (unit lower `L` by rows, `D` its pivots).
#[derive(Debug, Clone)]
pub(super) struct BandFactors {
    b: usize,
    /// Row `i` holds `L_ik`, `k = i − b … i`, at `(i + b) (b + 1) + k + b − i`
    /// (after `b` rows of zeros).
    l: Vec<f64>,
    /// `D`, after `b` ones.
    pivots: Vec<f64>,
}

impl BandFactors {
    /// Solves `L D Lᵀ x = y` in place (`x` the natural order, scaled).
    pub(super) fn solve_in_place(&self, x: &mut [f64]) {
        // fixed widths for the elements' bands (see `Band::factor`): the
        // same arithmetic in the same order, unrolled
        let done = match self.b {
            7 => self.solve_fixed::<8>(x),
            11 => self.solve_fixed::<12>(x),
            _ => false,
        };
        if !done {
            self.solve_any(x);
        }
    }

    /// [`BandFactors::solve_in_place`] for the width `W = b + 1`; `false`
    /// (nothing done) if the factors are not of that width or `x` is
    /// shorter than the band.
    fn solve_fixed<const W: usize>(&self, x: &mut [f64]) -> bool {
        let b = W - 1;
        let Some(l) = self.l.get(b * W..) else {
            return false;
        };
        let (rows, _) = l.as_chunks::<W>();
        let n = x.len();
        if self.b != b || rows.len() != n || n < b {
            return false;
        }
        for (i, row) in rows.iter().enumerate() {
            let s = if i >= b {
                let y = &x[i - b..i];
                let mut s = row[0] * y[0];
                for t in 1..b {
                    s += row[t] * y[t];
                }
                s
            } else {
                let mut s = -0.0;
                for (t, y) in x[..i].iter().enumerate() {
                    s += row[t + b - i] * y;
                }
                s
            };
            x[i] -= s;
        }
        for (xi, d) in x.iter_mut().zip(self.pivots.iter().skip(b)) {
            *xi /= d;
        }
        for (i, row) in rows.iter().enumerate().rev() {
            let xi = x[i];
            if i >= b {
                let y = &mut x[i - b..i];
                for t in 0..b {
                    y[t] -= row[t] * xi;
                }
            } else {
                for (t, y) in x[..i].iter_mut().enumerate() {
                    *y -= row[t + b - i] * xi;
                }
            }
        }
        true
    }

    /// [`BandFactors::solve_in_place`] for any width.
    fn solve_any(&self, x: &mut [f64]) {
        let b = self.b;
        let w = b + 1;
        let l = self.l.get(b * w..).unwrap_or(&[]);
        for (i, row) in l.chunks_exact(w).enumerate() {
            let lo = i.saturating_sub(b);
            let (done, rest) = x.split_at_mut(i);
            let s: f64 = row[lo + b - i..b]
                .iter()
                .zip(&done[lo..])
                .map(|(l, y)| l * y)
                .sum();
            if let Some(xi) = rest.first_mut() {
                *xi -= s;
            }
        }
        for (xi, d) in x.iter_mut().zip(self.pivots.iter().skip(b)) {
            *xi /= d;
        }
        for (i, row) in l.chunks_exact(w).enumerate().rev() {
            let lo = i.saturating_sub(b);
            let (head, rest) = x.split_at_mut(i);
            let xi = rest.first().copied().unwrap_or(0.0);
            for (y, l) in head[lo..].iter_mut().zip(&row[lo + b - i..b]) {
                *y -= l * xi;
            }
        }
    }
}

#[cfg(test)]
pub(super) mod tests {
    use std::sync::Arc;

    use crate::linsolve::{
        CholeskyKind, FactorMethod, FactorOptions, Factorization, Inertia, SparseSettings,
        SparseSolver, SymmetricMatrix, SymmetricPattern, TangentSolver,
    };

    /// A chain of `elements` elements between nodes of `dofs` coordinates,
    /// each element block `block(rand, 2 dofs)` (row-major, symmetric;
    /// `rand` draws seeded numbers in `[−0.5, 0.5)`), plus `diag` on the
    /// diagonal of the whole matrix. Also the band LU's tests' matrices.
    pub(in crate::linsolve::sparse) fn chain_with(
        elements: usize,
        dofs: usize,
        diag: f64,
        seed: u64,
        mut block: impl FnMut(&mut dyn FnMut() -> f64, usize) -> Vec<f64>,
    ) -> SymmetricMatrix {
        let n = (elements + 1) * dofs;
        let els: Vec<Vec<usize>> = (0..elements)
            .map(|e| (e * dofs..(e + 2) * dofs).collect())
            .collect();
        let p = Arc::new(SymmetricPattern::from_elements(n, &els).unwrap());
        let mut k = SymmetricMatrix::zeros(p);
        let mut rng = crate::rng::Lcg::new(seed);
        let mut rand = || rng.centered();
        for e in 0..elements {
            k.add_element(e, &block(&mut rand, 2 * dofs)).unwrap();
        }
        for i in 0..n {
            k.add(i, i, diag).unwrap();
        }
        k
    }

    /// Two right-hand sides for an `n × n` matrix (fixed integers in
    /// `[−5, 5]`, column after column) solved by both factorizations:
    /// `(rhs, x_a, x_b, max |x_b|)`, what the band paths' tests compare.
    pub(in crate::linsolve::sparse) fn two_column_solves(
        a: &impl Factorization,
        b: &impl Factorization,
        n: usize,
    ) -> (Vec<f64>, Vec<f64>, Vec<f64>, f64) {
        let rhs: Vec<f64> = (0..2 * n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
        let (mut xa, mut xb) = (rhs.clone(), rhs.clone());
        a.solve_columns_in_place(&mut xa, 2).unwrap();
        b.solve_columns_in_place(&mut xb, 2).unwrap();
        let scale = xb.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        (rhs, xa, xb, scale)
    }

    /// [`chain_with`] of blocks `Gᵀ G + 0.1 I` (seed 7): positive definite
    /// for `diag` ≥ 0.
    fn chain(elements: usize, dofs: usize, diag: f64) -> SymmetricMatrix {
        chain_with(elements, dofs, diag, 7, |rand, m| {
            let g: Vec<f64> = (0..m * m).map(|_| rand()).collect();
            let mut h = vec![0.0; m * m];
            for a in 0..m {
                for b in 0..m {
                    h[a * m + b] = (0..m).map(|c| g[c * m + a] * g[c * m + b]).sum::<f64>()
                        + if a == b { 0.1 } else { 0.0 };
                }
            }
            h
        })
    }

    /// The band path (`L D Lᵀ`, the default) against the general one
    /// (Cholesky with faer's ordering, which never takes it): the same
    /// solution to round-off, the same inertia, the smallest pivot ratio
    /// of the same size; at every width the band path has (7: the planar
    /// cable, 11 and 23: the spatial ones, 5: any other) and on both sides
    /// of the small-size rule (n ≤ 32 always, larger by fill).
    #[test]
    fn fixed_width_solves_equal_the_general_solve_bit_for_bit() {
        use super::Band;
        // half-bandwidths 7 (4 dofs a node) and 11 (6), short and long
        for (elements, dofs) in [(1, 4), (2, 4), (30, 4), (1, 6), (12, 6)] {
            let k = chain(elements, dofs, 0.0);
            let n = k.n();
            let band = Band::of(k.pattern(), usize::MAX / 4).unwrap();
            let d: Vec<f64> = (0..n).map(|i| 1.0 + 0.01 * i as f64).collect();
            let (f, _) = band.factor(&k, &d, 0.0).unwrap().unwrap();
            assert_eq!(f.b, 2 * dofs - 1);
            let rhs: Vec<f64> = (0..n).map(|i| ((i * 37) % 11) as f64 - 5.0).collect();
            let (mut a, mut b) = (rhs.clone(), rhs);
            f.solve_in_place(&mut a);
            f.solve_any(&mut b);
            assert_eq!(a, b, "{elements} x {dofs}");
            assert!(a.iter().all(|v| v.is_finite()));
        }
    }

    #[test]
    fn band_factors_agree_with_the_general_path() {
        for (elements, dofs) in [(3, 4), (40, 4), (5, 6), (30, 12), (50, 3)] {
            let k = chain(elements, dofs, 0.0);
            let p = k.pattern().clone();
            let mut band = SparseSolver::analyze(&p).unwrap();
            let general = SparseSettings {
                cholesky: CholeskyKind::Llt,
                ..SparseSettings::default()
            };
            let mut other = SparseSolver::with_settings(&p, general).unwrap();
            let fb = band.factor(&k, FactorOptions::default()).unwrap();
            let fo = other.factor(&k, FactorOptions::default()).unwrap();
            assert_eq!(fb.method(), FactorMethod::Ldlt);
            assert_eq!(fo.method(), FactorMethod::Llt);
            assert_eq!(fb.inertia(), fo.inertia());
            let n = k.n();
            let (rhs, xb, xo, scale) = two_column_solves(&fb, &fo, n);
            let diff = xb
                .iter()
                .zip(&xo)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(
                diff <= 1e-9 * scale,
                "{elements}×{dofs}: {diff:e} of {scale:e}"
            );
            // K x = b to round-off
            let mut kx = vec![0.0; n];
            k.mul_vec_into(&xb[..n], &mut kx).unwrap();
            let res = kx
                .iter()
                .zip(&rhs)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(
                res <= 1e-9 * 5.0 * (n as f64),
                "{elements}×{dofs}: residual {res:e}"
            );
            let ratio = fb.pivot_ratio() / fo.pivot_ratio();
            assert!(ratio > 0.0 && ratio.is_finite(), "{ratio}");
        }
    }

    /// A matrix that is not positive definite leaves the band path: the
    /// general path's pivoted LU with the inertia of its `L D Lᵀ`, and a
    /// typed refusal naming a row when positive definiteness is required;
    /// a shift that makes it definite is factored on the band again.
    #[test]
    fn an_indefinite_band_matrix_goes_on_to_the_general_path() {
        let k = chain(6, 4, -2.0);
        let p = k.pattern().clone();
        let mut s = SparseSolver::analyze(&p).unwrap();
        let f = s.factor(&k, FactorOptions::default()).unwrap();
        assert_eq!(f.method(), FactorMethod::Lu);
        let inertia = f.inertia().unwrap();
        assert!(inertia.negative > 0 && inertia.positive + inertia.negative == k.n());
        let strict = FactorOptions {
            require_positive_definite: true,
            ..FactorOptions::default()
        };
        match s.factor(&k, strict) {
            Err(crate::linsolve::LinsolveError::NotPositiveDefinite { index, pivot }) => {
                assert!(index < k.n() && pivot < 1e-6, "{index} {pivot}");
            }
            other => panic!("expected NotPositiveDefinite, got {:?}", other.is_ok()),
        }
        let shifted = FactorOptions {
            shift: 1e3,
            ..FactorOptions::default()
        };
        let f = s.factor(&k, shifted).unwrap();
        assert_eq!(f.method(), FactorMethod::Ldlt);
        assert_eq!(
            f.inertia(),
            Some(Inertia {
                positive: k.n(),
                negative: 0
            })
        );
    }
}
