//! The sparse solver (faer): `L D Lᵀ` or Cholesky with a fill-reducing
//! ordering whose symbolic analysis every factorization reuses, and a
//! sparse LU with partial pivoting for tangents that are not positive
//! definite.
//!
//! All faer calls run sequentially (`Par::Seq` is passed to each of them,
//! so the process-wide setting is left to the application): the tangents
//! of slender structures are too small for threads to pay.

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::linalg::cholesky::llt::factor::{LltError, LltRegularization};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLdltRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LdltRef, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::lu::simplicial::{
    factorize_simplicial_numeric_lu, factorize_simplicial_numeric_lu_scratch,
    solve_in_place_scratch as lu_solve_scratch, SimplicialLu,
};
use faer::sparse::linalg::LuError;
use faer::sparse::{FaerError, SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

use super::{
    check_factor_input, check_rhs, pivot_tolerance, FactorMethod, FactorOptions, Factorization,
    Inertia, LinsolveError, SymmetricMatrix, SymmetricPattern, TangentSolver,
};

/// The symmetric factorization [`SparseSolver`] tries first.
///
/// # Example
/// ```
/// use softrod::linsolve::CholeskyKind;
/// assert_eq!(CholeskyKind::default(), CholeskyKind::Ldlt);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CholeskyKind {
    /// `L D Lᵀ`: as fast as Cholesky, and its pivots give the inertia
    /// whatever the definiteness (the default).
    #[default]
    Ldlt,
    /// Cholesky `L Lᵀ`; a tangent that is not positive definite is then
    /// refactored by `L D Lᵀ` for its inertia before the LU.
    Llt,
}

/// The fill-reducing ordering of [`SparseSolver`].
///
/// # Example
/// ```
/// use softrod::linsolve::sparse::Ordering;
/// assert_eq!(Ordering::default(), Ordering::Amd);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Ordering {
    /// Approximate minimum degree (the default).
    #[default]
    Amd,
    /// The dofs' own order (a chain numbered node by node has no fill
    /// outside its band in it).
    Natural,
}

/// Settings of [`SparseSolver`].
///
/// # Example
/// ```
/// use softrod::linsolve::{CholeskyKind, SparseSettings};
/// let s = SparseSettings { cholesky: CholeskyKind::Llt, ..SparseSettings::default() };
/// assert_eq!(s.ordering, softrod::linsolve::sparse::Ordering::Amd);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SparseSettings {
    /// The factorization tried first. Default [`CholeskyKind::Ldlt`].
    pub cholesky: CholeskyKind,
    /// The fill-reducing ordering. Default [`Ordering::Amd`].
    pub ordering: Ordering,
}

/// The full (both triangles) pattern the LU factors, the column ordering
/// it uses, and where each of its entries comes from in the upper triangle.
#[derive(Debug)]
struct LuPattern {
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    from_upper: Vec<usize>,
    col_fwd: Vec<usize>,
    col_inv: Vec<usize>,
}

/// The faer sparse solver behind [`TangentSolver`], for any pattern.
///
/// [`TangentSolver::analyze`] computes the fill-reducing ordering and the
/// symbolic factorization once; [`TangentSolver::factor`] scales and
/// shifts the matrix (see [`crate::linsolve`]) and factors it numerically
/// with that symbolic structure: `L D Lᵀ` (or Cholesky, see
/// [`SparseSettings`]) when positive definite, else faer's simplicial LU
/// with partial pivoting, in the same column ordering.
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use softrod::linsolve::*;
/// // two chains of springs joined at a shared dof 0 (not banded in this numbering)
/// let elements = vec![vec![0, 1], vec![1, 2], vec![0, 3], vec![3, 4]];
/// let p = Arc::new(SymmetricPattern::from_elements(5, &elements)?);
/// let mut k = SymmetricMatrix::zeros(p.clone());
/// for e in 0..4 {
///     k.add_element(e, &[1.0, -1.0, -1.0, 1.0])?;
/// }
/// k.add(0, 0, 1.0)?;
/// let mut solver = SparseSolver::analyze(&p)?;
/// let f = solver.factor(&k, FactorOptions::default())?;
/// assert_eq!(f.inertia(), Some(Inertia { positive: 5, negative: 0 }));
/// let mut x = vec![0.0, 0.0, 1.0, 0.0, 0.0];
/// f.solve_in_place(&mut x)?;
/// assert!((x[2] - 3.0).abs() < 1e-12 && (x[4] - 1.0).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct SparseSolver {
    pattern: Arc<SymmetricPattern>,
    settings: SparseSettings,
    symbolic: Arc<SymbolicCholesky<usize>>,
    lu: Arc<LuPattern>,
    scaled: Vec<f64>,
    rowmax: Vec<f64>,
}

impl SparseSolver {
    /// Analyzes `pattern` with the given settings.
    ///
    /// # Errors
    /// [`LinsolveError::TooLarge`] or [`LinsolveError::OutOfMemory`] when
    /// faer cannot index or allocate the symbolic factorization.
    ///
    /// # Example
    /// ```
    /// use std::sync::Arc;
    /// use softrod::linsolve::{sparse::Ordering, SparseSettings, SparseSolver, SymmetricPattern};
    /// let p = Arc::new(SymmetricPattern::from_elements(3, [[0, 1], [1, 2]])?);
    /// let s = SparseSolver::with_settings(&p, SparseSettings { ordering: Ordering::Natural, ..Default::default() })?;
    /// assert!(s.factor_entries() >= 5);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_settings(
        pattern: &Arc<SymmetricPattern>,
        settings: SparseSettings,
    ) -> Result<Self, LinsolveError> {
        let n = pattern.n();
        let a =
            SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
        let ordering = match settings.ordering {
            Ordering::Amd => SymmetricOrdering::Amd,
            Ordering::Natural => SymmetricOrdering::Identity,
        };
        let symbolic = factorize_symbolic_cholesky(
            a,
            Side::Upper,
            ordering,
            CholeskySymbolicParams::default(),
        )
        .map_err(faer_error)?;
        let (col_fwd, col_inv) = match symbolic.perm() {
            Some(p) => (p.arrays().0.to_vec(), p.arrays().1.to_vec()),
            None => ((0..n).collect(), (0..n).collect()),
        };
        let lu = full_pattern(pattern, col_fwd, col_inv);
        Ok(SparseSolver {
            pattern: pattern.clone(),
            settings,
            symbolic: Arc::new(symbolic),
            lu: Arc::new(lu),
            scaled: Vec::new(),
            rowmax: Vec::new(),
        })
    }

    /// The settings.
    pub fn settings(&self) -> SparseSettings {
        self.settings
    }

    /// Number of stored entries of the Cholesky factor `L` (a measure of
    /// the fill the ordering leaves).
    pub fn factor_entries(&self) -> usize {
        self.symbolic.len_val()
    }

    /// Whether faer chose its supernodal (blocked) factorization for this
    /// pattern rather than the simplicial one.
    pub fn is_supernodal(&self) -> bool {
        matches!(self.symbolic.raw(), SymbolicCholeskyRaw::Supernodal(_))
    }

    /// The numeric `L Lᵀ` (`llt`) or `L D Lᵀ` of the scaled matrix with the
    /// shared symbolic structure; on success its pivots (`D`, or `L_kk²`)
    /// in elimination order.
    fn cholesky(&self, llt: bool) -> Result<CholeskyOutcome, LinsolveError> {
        let n = self.pattern.n();
        let sym = &self.symbolic;
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(
                n,
                n,
                self.pattern.col_ptr(),
                None,
                self.pattern.row_idx(),
            ),
            &self.scaled[..],
        );
        let mut values = try_zeros(sym.len_val())?;
        let req = if llt {
            sym.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
        } else {
            sym.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default())
        };
        let mut mem = MemBuffer::try_new(req).map_err(|_| LinsolveError::OutOfMemory)?;
        let stack = MemStack::new(&mut mem);
        let failed_at = if llt {
            match sym.factorize_numeric_llt(
                &mut values,
                a,
                Side::Upper,
                LltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            ) {
                Ok(_) => None,
                Err(LltError::NonPositivePivot { index }) => Some(index),
            }
        } else {
            match sym.factorize_numeric_ldlt(
                &mut values,
                a,
                Side::Upper,
                LdltRegularization::default(),
                Par::Seq,
                stack,
                Default::default(),
            ) {
                Ok(_) => None,
                Err(LdltError::ZeroPivot { index }) => Some(index),
            }
        };
        if let Some(index) = failed_at {
            // faer counts the simplicial pivot from 1, the supernodal from 0
            let k = match sym.raw() {
                SymbolicCholeskyRaw::Simplicial(_) => index.saturating_sub(1),
                SymbolicCholeskyRaw::Supernodal(_) => index,
            };
            return Ok(CholeskyOutcome::Failed {
                index: self.lu.col_fwd.get(k).copied().unwrap_or(0),
            });
        }
        let mut pivots = Vec::with_capacity(n);
        match sym.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                pivots.extend(s.col_ptr()[..n].iter().map(|&p| values[p]));
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let f = SupernodalLdltRef::new(s, &values);
                for sn in 0..s.n_supernodes() {
                    let block = f.supernode(sn).val();
                    pivots.extend((0..block.ncols()).map(|c| block[(c, c)]));
                }
            }
        }
        if llt {
            pivots.iter_mut().for_each(|l| *l *= *l);
        }
        Ok(CholeskyOutcome::Done { values, pivots })
    }

    /// Classifies the pivots `d` (elimination order) of an `L D Lᵀ` or
    /// `L Lᵀ`: the first that is not clearly positive (original row and
    /// value), whether every pivot is clearly nonzero, the smallest ratio.
    fn classify(&self, pivots: &[f64]) -> PivotClass {
        let rel = pivot_tolerance(self.pattern.n());
        let mut class = PivotClass {
            first_not_positive: None,
            all_nonzero: true,
            negative: 0,
            min_ratio: f64::INFINITY,
        };
        for (k, &d) in pivots.iter().enumerate() {
            let row = self.lu.col_fwd[k];
            let scale = self.rowmax[row];
            if !exceeds(d, rel * scale) && class.first_not_positive.is_none() {
                class.first_not_positive = Some((row, d));
            }
            if !exceeds(d.abs(), rel * scale) {
                class.all_nonzero = false;
            }
            if d < 0.0 {
                class.negative += 1;
            }
            class.min_ratio = class.min_ratio.min(d.abs() / scale);
        }
        class
    }

    /// The pivoted LU of the scaled matrix.
    fn lu(&self) -> Result<(Numeric, f64), LinsolveError> {
        let n = self.pattern.n();
        let lp = &self.lu;
        let full_values: Vec<f64> = lp.from_upper.iter().map(|&k| self.scaled[k]).collect();
        let a = SparseColMatRef::new(
            SymbolicSparseColMatRef::new_checked(n, n, &lp.col_ptr, None, &lp.row_idx),
            &full_values[..],
        );
        let mut lu = SimplicialLu::new();
        let mut row_fwd = vec![0usize; n];
        let mut row_inv = vec![0usize; n];
        let mut mem =
            MemBuffer::try_new(factorize_simplicial_numeric_lu_scratch::<usize, f64>(n, n))
                .map_err(|_| LinsolveError::OutOfMemory)?;
        let col_perm = PermRef::new_checked(&lp.col_fwd, &lp.col_inv, n);
        match factorize_simplicial_numeric_lu(
            &mut row_fwd,
            &mut row_inv,
            &mut lu,
            a,
            col_perm,
            MemStack::new(&mut mem),
        ) {
            Ok(()) => {}
            Err(LuError::SymbolicSingular { index }) => {
                return Err(LinsolveError::Singular {
                    index: lp.col_fwd.get(index).copied().unwrap_or(0),
                    pivot: 0.0,
                    scale: 0.0,
                })
            }
            Err(LuError::Generic(e)) => return Err(faer_error(e)),
        }
        // the pivots: U's diagonal, against the pivot row's scale
        let rel = pivot_tolerance(n);
        let mut min_ratio = f64::INFINITY;
        {
            let u = lu.u_factor_unsorted();
            for (j, &row) in row_fwd.iter().enumerate() {
                let pivot = u
                    .row_idx_of_col_raw(j)
                    .iter()
                    .zip(u.val_of_col(j))
                    .find(|(&i, _)| i == j)
                    .map_or(0.0, |(_, v)| *v);
                let scale = self.rowmax[row];
                if !exceeds(pivot.abs(), rel * scale) {
                    return Err(LinsolveError::Singular {
                        index: lp.col_fwd[j],
                        pivot,
                        scale,
                    });
                }
                min_ratio = min_ratio.min(pivot.abs() / scale);
            }
        }
        Ok((
            Numeric::Lu {
                lu,
                row_fwd,
                row_inv,
                pattern: self.lu.clone(),
            },
            min_ratio,
        ))
    }
}

/// What a numeric `L Lᵀ` / `L D Lᵀ` gave.
enum CholeskyOutcome {
    /// faer stopped at a pivot (zero, non-finite, or for `L Lᵀ` not positive).
    Failed { index: usize },
    /// The factor values and the pivots in elimination order.
    Done { values: Vec<f64>, pivots: Vec<f64> },
}

/// The pivots of an `L D Lᵀ` / `L Lᵀ` judged.
struct PivotClass {
    first_not_positive: Option<(usize, f64)>,
    all_nonzero: bool,
    negative: usize,
    min_ratio: f64,
}

impl TangentSolver for SparseSolver {
    type Factors = SparseFactors;

    fn analyze(pattern: &Arc<SymmetricPattern>) -> Result<Self, LinsolveError> {
        Self::with_settings(pattern, SparseSettings::default())
    }

    fn pattern(&self) -> &Arc<SymmetricPattern> {
        &self.pattern
    }

    fn factor(
        &mut self,
        matrix: &SymmetricMatrix,
        options: FactorOptions,
    ) -> Result<SparseFactors, LinsolveError> {
        check_factor_input(&self.pattern, matrix, &options)?;
        let n = matrix.n();
        let d = matrix.jacobi_scaling();
        matrix.scaled_into(&d, options.shift, &mut self.scaled, &mut self.rowmax);
        let factors = |numeric, inertia, min_pivot| SparseFactors {
            n,
            symbolic: self.symbolic.clone(),
            numeric,
            scaling: d.clone(),
            inertia,
            min_pivot,
        };
        let llt_first = self.settings.cholesky == CholeskyKind::Llt;
        let mut outcome = self.cholesky(llt_first)?;
        if llt_first {
            if let CholeskyOutcome::Done { values, pivots } = &outcome {
                let class = self.classify(pivots);
                if class.first_not_positive.is_none() {
                    let inertia = Inertia {
                        positive: n,
                        negative: 0,
                    };
                    return Ok(factors(
                        Numeric::Llt(values.clone()),
                        Some(inertia),
                        class.min_ratio,
                    ));
                }
            }
            // not positive definite: L D Lᵀ for the pivot and the inertia
            outcome = self.cholesky(false)?;
        }
        let inertia = match outcome {
            CholeskyOutcome::Done { values, pivots } => {
                let class = self.classify(&pivots);
                match class.first_not_positive {
                    None => {
                        let inertia = Inertia {
                            positive: n,
                            negative: 0,
                        };
                        return Ok(factors(
                            Numeric::Ldlt(values),
                            Some(inertia),
                            class.min_ratio,
                        ));
                    }
                    Some((index, pivot)) if options.require_positive_definite => {
                        return Err(LinsolveError::NotPositiveDefinite { index, pivot });
                    }
                    Some(_) => class.all_nonzero.then_some(Inertia {
                        positive: n - class.negative,
                        negative: class.negative,
                    }),
                }
            }
            CholeskyOutcome::Failed { index } => {
                if options.require_positive_definite {
                    return Err(LinsolveError::NotPositiveDefinite { index, pivot: 0.0 });
                }
                None
            }
        };
        let (numeric, min_pivot) = self.lu()?;
        Ok(factors(numeric, inertia, min_pivot))
    }
}

/// The numeric factors.
#[derive(Debug, Clone)]
enum Numeric {
    Llt(Vec<f64>),
    Ldlt(Vec<f64>),
    Lu {
        lu: SimplicialLu<usize, f64>,
        row_fwd: Vec<usize>,
        row_inv: Vec<usize>,
        pattern: Arc<LuPattern>,
    },
}

/// The factors [`SparseSolver`] returns (see [`Factorization`]).
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use softrod::linsolve::*;
/// let p = Arc::new(SymmetricPattern::from_elements(2, [[0, 1]])?);
/// let mut k = SymmetricMatrix::zeros(p.clone());
/// k.add_element(0, &[1.0, 2.0, 2.0, 1.0])?; // eigenvalues 3 and −1
/// let f: SparseFactors = SparseSolver::analyze(&p)?.factor(&k, FactorOptions::default())?;
/// assert_eq!(f.method(), FactorMethod::Lu);
/// assert_eq!(f.inertia(), Some(Inertia { positive: 1, negative: 1 }));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct SparseFactors {
    n: usize,
    symbolic: Arc<SymbolicCholesky<usize>>,
    numeric: Numeric,
    scaling: Vec<f64>,
    inertia: Option<Inertia>,
    min_pivot: f64,
}

impl SparseFactors {
    /// The solve for `k >= 1` column-major right-hand sides (sizes checked).
    fn solve_cols(&self, b: &mut [f64], k: usize) -> Result<(), LinsolveError> {
        let n = self.n;
        for col in b.chunks_exact_mut(n) {
            col.iter_mut().zip(&self.scaling).for_each(|(x, d)| *x *= d);
        }
        let req = match &self.numeric {
            Numeric::Llt(_) | Numeric::Ldlt(_) => {
                self.symbolic.solve_in_place_scratch::<f64>(k, Par::Seq)
            }
            Numeric::Lu { .. } => lu_solve_scratch::<usize, f64>(n, k, Par::Seq),
        };
        let mut mem =
            MemBuffer::try_new(StackReq::any_of(&[req])).map_err(|_| LinsolveError::OutOfMemory)?;
        let stack = MemStack::new(&mut mem);
        let rhs = MatMut::from_column_major_slice_mut(b, n, k);
        match &self.numeric {
            Numeric::Llt(values) => {
                LltRef::new(&self.symbolic, values).solve_in_place_with_conj(
                    Conj::No,
                    rhs,
                    Par::Seq,
                    stack,
                );
            }
            Numeric::Ldlt(values) => {
                LdltRef::new(&self.symbolic, values).solve_in_place_with_conj(
                    Conj::No,
                    rhs,
                    Par::Seq,
                    stack,
                );
            }
            Numeric::Lu {
                lu,
                row_fwd,
                row_inv,
                pattern,
            } => {
                let row_perm = PermRef::new_checked(row_fwd, row_inv, n);
                let col_perm = PermRef::new_checked(&pattern.col_fwd, &pattern.col_inv, n);
                lu.solve_in_place_with_conj(row_perm, col_perm, Conj::No, rhs, Par::Seq, stack);
            }
        }
        for col in b.chunks_exact_mut(n) {
            col.iter_mut().zip(&self.scaling).for_each(|(x, d)| *x *= d);
        }
        Ok(())
    }
}

impl Factorization for SparseFactors {
    fn n(&self) -> usize {
        self.n
    }

    fn method(&self) -> FactorMethod {
        match self.numeric {
            Numeric::Llt(_) => FactorMethod::Llt,
            Numeric::Ldlt(_) => FactorMethod::Ldlt,
            Numeric::Lu { .. } => FactorMethod::Lu,
        }
    }

    fn inertia(&self) -> Option<Inertia> {
        self.inertia
    }

    fn pivot_ratio(&self) -> f64 {
        self.min_pivot
    }

    fn solve_in_place(&self, b: &mut [f64]) -> Result<(), LinsolveError> {
        self.solve_columns_in_place(b, 1)
    }

    fn solve_columns_in_place(&self, b: &mut [f64], nrhs: usize) -> Result<(), LinsolveError> {
        check_rhs("b", self.n.saturating_mul(nrhs), b.len())?;
        if nrhs == 0 || self.n == 0 {
            return Ok(());
        }
        self.solve_cols(b, nrhs)
    }
}

#[allow(clippy::needless_range_loop)] // CSC loops read clearer indexed
/// The full pattern of the LU from the upper triangle: column `j` holds
/// the upper column `j` (rows `<= j`) followed by row `j` of the upper
/// triangle (rows `> j`), both sorted.
fn full_pattern(p: &SymmetricPattern, col_fwd: Vec<usize>, col_inv: Vec<usize>) -> LuPattern {
    let n = p.n();
    let (cp, ri) = (p.col_ptr(), p.row_idx());
    let mut count = vec![0usize; n];
    for j in 0..n {
        count[j] += cp[j + 1] - cp[j];
        for &i in &ri[cp[j]..cp[j + 1]] {
            if i != j {
                count[i] += 1;
            }
        }
    }
    let mut col_ptr = vec![0usize; n + 1];
    for j in 0..n {
        col_ptr[j + 1] = col_ptr[j] + count[j];
    }
    let nnz = col_ptr[n];
    let mut row_idx = vec![0usize; nnz];
    let mut from_upper = vec![0usize; nnz];
    let mut next = col_ptr[..n].to_vec();
    // upper parts first (rows <= j), then the mirrored entries in
    // increasing column order, which are rows > j of column i
    for j in 0..n {
        for k in cp[j]..cp[j + 1] {
            let at = next[j];
            row_idx[at] = ri[k];
            from_upper[at] = k;
            next[j] += 1;
        }
    }
    for j in 0..n {
        for k in cp[j]..cp[j + 1] {
            let i = ri[k];
            if i != j {
                let at = next[i];
                row_idx[at] = j;
                from_upper[at] = k;
                next[i] += 1;
            }
        }
    }
    LuPattern {
        col_ptr,
        row_idx,
        from_upper,
        col_fwd,
        col_inv,
    }
}

/// `x > t`, false for a NaN.
fn exceeds(x: f64, t: f64) -> bool {
    x > t
}

/// A zeroed vector, refusing instead of aborting when it cannot be allocated.
fn try_zeros(len: usize) -> Result<Vec<f64>, LinsolveError> {
    let mut v = Vec::new();
    v.try_reserve_exact(len)
        .map_err(|_| LinsolveError::OutOfMemory)?;
    v.resize(len, 0.0);
    Ok(v)
}

/// faer's non-numeric errors.
fn faer_error(e: FaerError) -> LinsolveError {
    match e {
        FaerError::IndexOverflow => LinsolveError::TooLarge {
            what: "sparse factor",
            entries: usize::MAX,
            max: isize::MAX as usize,
        },
        _ => LinsolveError::OutOfMemory,
    }
}
