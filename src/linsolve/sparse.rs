//! The sparse solver (faer): `L D Lᵀ` or Cholesky with a fill-reducing
//! ordering whose symbolic analysis every factorization reuses, and a
//! sparse LU with partial pivoting for tangents that are not positive
//! definite.
//!
//! The band path ([`BandPath`]): a pattern whose band in the dofs' own
//! order is narrow (a chain numbered node by node: every robot's tangent)
//! is factored by band kernels in that order instead: a band `L D Lᵀ`
//! (`band.rs`) when the matrix is positive definite, else the band
//! `L D Lᵀ`'s inertia and a band LU with partial pivoting (`band_lu.rs`).
//! Only an indefinite matrix with a pivot too small for the band `L D Lᵀ`'s
//! inertia still goes to faer's `L D Lᵀ` (for the inertia), and then to the
//! band LU.
//!
//! All faer calls run sequentially (`Par::Seq` is passed to each of them,
//! so the process-wide setting is left to the application): the tangents
//! of slender structures are too small for threads to pay.

use std::sync::{Arc, OnceLock};

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::ldlt::factor::{LdltError, LdltRegularization};
use faer::linalg::cholesky::llt::factor::{LltError, LltRegularization};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::supernodal::SupernodalLdltRef;
use faer::sparse::linalg::cholesky::{
    CholeskySymbolicParams, SymbolicCholesky, SymbolicCholeskyRaw, SymmetricOrdering,
    factorize_symbolic_cholesky,
};
use faer::sparse::linalg::lu::simplicial::{
    SimplicialLu, factorize_simplicial_numeric_lu, factorize_simplicial_numeric_lu_scratch,
};
use faer::sparse::linalg::{LuError, amd};
use faer::sparse::{FaerError, SparseColMatRef, SymbolicSparseColMat, SymbolicSparseColMatRef};
use faer::{Par, Side};

use super::{
    FactorOptions, Inertia, LinsolveError, SymmetricMatrix, SymmetricPattern, TangentSolver,
    check_factor_input, pivot_tolerance,
};

mod band;
mod band_lu;
mod factors;
mod kept;
use band::Band;
use factors::Numeric;
pub use factors::SparseFactors;
use kept::{Analysis, keep_analysis, kept_analysis};

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

/// When [`SparseSolver`] factors by its band kernels (the band path of the
/// module docs) rather than by faer.
///
/// A pattern is a *narrow band* when its band in the dofs' own order
/// (`n (b + 1)` entries, `b` the half-bandwidth) stores at most twice the
/// entries of faer's factor after its fill-reducing ordering, or when it has
/// at most 32 rows: the band kernels' work grows as `n b²`, faer's with its
/// fill. A chain numbered node by node (a robot's tangent, `b = 2 × node
/// dofs − 1`) is one; a structure whose joints couple distant dofs may not be.
///
/// # Example
/// ```
/// use softrod::linsolve::{sparse::BandPath, SparseSettings};
/// assert_eq!(SparseSettings::default().band, BandPath::WhereNarrow);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum BandPath {
    /// The band path for a narrow band and the [`CholeskyKind::Ldlt`]
    /// setting, faer's factorizations otherwise (the default).
    #[default]
    WhereNarrow,
    /// faer's factorizations for every pattern.
    Never,
    /// The band path whatever [`SparseSettings::cholesky`] says; the
    /// analysis of a pattern that is not a narrow band is refused
    /// ([`LinsolveError::NotBanded`]).
    Required,
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
    /// When the band kernels factor instead of faer. Default
    /// [`BandPath::WhereNarrow`].
    pub band: BandPath,
}

/// The matrix as faer factors it: symmetrically permuted by the
/// fill-reducing ordering once, at analysis, so that each factorization
/// writes the scaled values straight into the permuted storage (no copy
/// of the matrix per factorization) and faer factors it in its own order.
#[derive(Debug)]
struct Permuted {
    /// Ordering: permuted index `k` is row `fwd[k]` of the given matrix.
    fwd: Vec<usize>,
    /// The triangle faer's factorization reads: upper for the simplicial
    /// factors, lower for the supernodal ones.
    side: Side,
    /// That triangle of the permuted matrix, compressed columns, sorted
    /// (checked once, here).
    tri: SymbolicSparseColMat<usize>,
    /// For each stored entry, its slot in the given pattern's values.
    src: Vec<usize>,
    /// Position of each (permuted) diagonal entry in the stored values.
    diag: Vec<usize>,
    /// The identity permutation (the LU's column order: already permuted).
    identity: Vec<usize>,
    /// The full permuted matrix (both triangles) the LU factors, and for
    /// each of its entries the stored entry it copies: built when an LU of
    /// this pattern is first needed, then shared by every solver of it.
    full: OnceLock<(SymbolicSparseColMat<usize>, Vec<usize>)>,
    /// The band kernels in the natural order, tried first: for a narrow
    /// band pattern as [`SparseSettings::band`] says (see `band.rs`).
    band: Option<Band>,
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
    perm: Arc<Permuted>,
    /// Scratch of one factorization: the scaled, shifted, permuted values.
    scaled: Vec<f64>,
    /// Scratch: the pivots of the last `L D Lᵀ` / `L Lᵀ` (elimination order).
    pivots: Vec<f64>,
    /// faer's workspace of the numeric factorizations, allocated at the
    /// first one and reused by all later ones.
    workspace: Workspace,
}

/// A faer workspace kept across calls (a clone starts without one).
#[derive(Default)]
struct Workspace(Option<MemBuffer>);

impl Clone for Workspace {
    fn clone(&self) -> Self {
        Workspace(None)
    }
}

impl std::fmt::Debug for Workspace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Workspace")
    }
}

impl Workspace {
    /// The workspace, allocated for `req` when there is none yet.
    fn stack(&mut self, req: StackReq) -> Result<&mut MemStack, LinsolveError> {
        if self.0.is_none() {
            self.0 = Some(MemBuffer::try_new(req).map_err(|_| LinsolveError::OutOfMemory)?);
        }
        match &mut self.0 {
            Some(mem) => Ok(MemStack::new(mem)),
            None => Err(LinsolveError::OutOfMemory),
        }
    }
}

impl SparseSolver {
    /// Analyzes `pattern` with the given settings.
    ///
    /// # Errors
    /// [`LinsolveError::TooLarge`] or [`LinsolveError::OutOfMemory`] when
    /// faer cannot index or allocate the symbolic factorization;
    /// [`LinsolveError::NotBanded`] for [`BandPath::Required`] and a pattern
    /// that is not a narrow band.
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
        let (symbolic, perm) = match kept_analysis(pattern, settings) {
            Some(found) => found,
            None => {
                let (symbolic, perm) = Self::symbolic_analysis(pattern, settings)?;
                let (symbolic, perm) = (Arc::new(symbolic), Arc::new(perm));
                keep_analysis(Analysis {
                    pattern: pattern.clone(),
                    settings,
                    symbolic: symbolic.clone(),
                    perm: perm.clone(),
                });
                (symbolic, perm)
            }
        };
        Ok(SparseSolver {
            pattern: pattern.clone(),
            settings,
            symbolic,
            perm,
            scaled: Vec::new(),
            pivots: Vec::with_capacity(pattern.n()),
            workspace: Workspace::default(),
        })
    }

    /// The fill-reducing ordering of `pattern` and the symbolic
    /// factorization of the permuted matrix (what [`Self::with_settings`]
    /// keeps per thread).
    fn symbolic_analysis(
        pattern: &SymmetricPattern,
        settings: SparseSettings,
    ) -> Result<(SymbolicCholesky<usize>, Permuted), LinsolveError> {
        let n = pattern.n();
        let a =
            SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
        let params = CholeskySymbolicParams::default();
        let (fwd, inv) = match settings.ordering {
            Ordering::Amd => {
                let (mut fwd, mut inv) = (vec![0usize; n], vec![0usize; n]);
                let mut mem =
                    MemBuffer::try_new(amd::order_scratch::<usize>(n, pattern.nnz_upper()))
                        .map_err(|_| LinsolveError::OutOfMemory)?;
                amd::order(
                    &mut fwd,
                    &mut inv,
                    a,
                    params.amd_params,
                    MemStack::new(&mut mem),
                )
                .map_err(faer_error)?;
                (fwd, inv)
            }
            Ordering::Natural => ((0..n).collect(), (0..n).collect()),
        };
        // the permuted upper triangle, and the symbolic factorization of it
        // in its own order
        let (up_ptr, up_idx, up_src) = permuted_triangle(pattern, &inv, Side::Upper);
        let a = SymbolicSparseColMatRef::new_checked(n, n, &up_ptr, None, &up_idx);
        let symbolic =
            factorize_symbolic_cholesky(a, Side::Upper, SymmetricOrdering::Identity, params)
                .map_err(faer_error)?;
        let side = match symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(_) => Side::Upper,
            SymbolicCholeskyRaw::Supernodal(_) => Side::Lower,
        };
        let (col_ptr, row_idx, src) = match side {
            Side::Upper => (up_ptr, up_idx, up_src),
            Side::Lower => permuted_triangle(pattern, &inv, Side::Lower),
        };
        let diag = (0..n)
            .map(|c| {
                let (a, b) = (col_ptr[c], col_ptr[c + 1]);
                // sorted rows: the diagonal is last (upper) or first (lower)
                match side {
                    Side::Upper => b.saturating_sub(1),
                    Side::Lower => a,
                }
            })
            .collect();
        let tri = SymbolicSparseColMat::new_checked(n, n, col_ptr, None, row_idx);
        let band = match (settings.band, settings.cholesky) {
            (BandPath::WhereNarrow, CholeskyKind::Ldlt) => {
                Band::of(pattern, symbolic.len_val()).ok()
            }
            (BandPath::WhereNarrow, CholeskyKind::Llt) | (BandPath::Never, _) => None,
            (BandPath::Required, _) => Some(Band::of(pattern, symbolic.len_val())?),
        };
        Ok((
            symbolic,
            Permuted {
                fwd,
                side,
                tri,
                src,
                diag,
                identity: (0..n).collect(),
                full: OnceLock::new(),
                band,
            },
        ))
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

    /// The half-bandwidth of the band path when this solver takes it (see
    /// [`BandPath`]), `None` when every matrix is factored by faer.
    ///
    /// # Example
    /// ```
    /// use std::sync::Arc;
    /// use softrod::linsolve::{sparse::BandPath, SparseSettings, SparseSolver, SymmetricPattern, TangentSolver};
    /// let p = Arc::new(SymmetricPattern::from_elements(3, [[0, 1], [1, 2]])?);
    /// assert_eq!(SparseSolver::analyze(&p)?.band_half_width(), Some(1));
    /// let never = SparseSettings { band: BandPath::Never, ..Default::default() };
    /// assert_eq!(SparseSolver::with_settings(&p, never)?.band_half_width(), None);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn band_half_width(&self) -> Option<usize> {
        self.perm.band.as_ref().map(Band::b)
    }

    /// The numeric `L Lᵀ` (`llt`) or `L D Lᵀ` of the scaled matrix with the
    /// shared symbolic structure; on success its pivots (`D`, or `L_kk²`)
    /// in elimination order are left in `self.pivots`.
    fn cholesky(&mut self, llt: bool) -> Result<CholeskyOutcome, LinsolveError> {
        let sym = &self.symbolic;
        let pm = &self.perm;
        let a = SparseColMatRef::new(pm.tri.as_ref(), &self.scaled[..]);
        let mut values = try_zeros(sym.len_val())?;
        // one workspace for both factorizations
        let req = sym
            .factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default())
            .or(sym.factorize_numeric_ldlt_scratch::<f64>(Par::Seq, Default::default()));
        let stack = self.workspace.stack(req)?;
        let failed_at = if llt {
            match sym.factorize_numeric_llt(
                &mut values,
                a,
                pm.side,
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
                pm.side,
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
                index: pm.fwd.get(k).copied().unwrap_or(0),
            });
        }
        let pivots = &mut self.pivots;
        pivots.clear();
        match sym.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                pivots.extend(s.col_ptr()[..s.nrows()].iter().map(|&p| values[p]));
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
        Ok(CholeskyOutcome::Done { values })
    }

    /// Whether the pivots `d` (elimination order, `self.pivots`) of an
    /// `L D Lᵀ` or `L Lᵀ` are all clearly positive: above `n ε` times their row's diagonal
    /// in the scaled matrix (a positive definite matrix has no larger
    /// entry). `Ok` with the smallest such ratio, else the first pivot
    /// that is not (its original row and value).
    fn positive_definite(&self) -> Result<f64, (usize, f64)> {
        let rel = pivot_tolerance(self.pattern.n());
        let mut min_ratio = f64::INFINITY;
        for ((&d, &at), &row) in self.pivots.iter().zip(&self.perm.diag).zip(&self.perm.fwd) {
            let scale = self.scaled[at].abs();
            if !exceeds(d, rel * scale) {
                return Err((row, d));
            }
            min_ratio = min_ratio.min(d / scale);
        }
        Ok(min_ratio)
    }

    /// The largest absolute entry of each row of the scaled, permuted
    /// matrix (the scale of the pivot tests of indefinite matrices).
    fn row_scales(&self) -> Vec<f64> {
        let tri = self.perm.tri.as_ref();
        let mut rowmax = vec![0.0f64; tri.ncols()];
        for c in 0..tri.ncols() {
            for (&r, v) in tri
                .row_idx_of_col_raw(c)
                .iter()
                .zip(&self.scaled[tri.col_range(c)])
            {
                rowmax[r] = rowmax[r].max(v.abs());
                rowmax[c] = rowmax[c].max(v.abs());
            }
        }
        rowmax
    }

    /// The inertia from the pivots of an `L D Lᵀ` (`self.pivots`), if every pivot is
    /// clearly nonzero (above `n ε` times its row's largest entry).
    fn inertia_of(&self, rowmax: &[f64]) -> Option<Inertia> {
        let pivots = &self.pivots;
        let rel = pivot_tolerance(self.pattern.n());
        let nonzero = pivots
            .iter()
            .zip(rowmax)
            .all(|(d, m)| exceeds(d.abs(), rel * m));
        let negative = pivots.iter().filter(|d| **d < 0.0).count();
        nonzero.then_some(Inertia {
            positive: pivots.len() - negative,
            negative,
        })
    }

    /// The pivoted LU of the scaled, permuted matrix (its columns already
    /// in the fill-reducing order).
    fn lu(&mut self, rowmax: &[f64]) -> Result<(Numeric, f64), LinsolveError> {
        let n = self.pattern.n();
        let pm = &self.perm;
        let full = pm.full.get_or_init(|| {
            let tri = pm.tri.as_ref();
            let (ptr, rows, src) = full_pattern(n, tri.col_ptr(), tri.row_idx());
            (
                SymbolicSparseColMat::new_checked(n, n, ptr, None, rows),
                src,
            )
        });
        let full_values: Vec<f64> = full.1.iter().map(|&k| self.scaled[k]).collect();
        let a = SparseColMatRef::new(full.0.as_ref(), &full_values[..]);
        let mut lu = SimplicialLu::new();
        let mut row_fwd = vec![0usize; n];
        let mut row_inv = vec![0usize; n];
        let mut mem =
            MemBuffer::try_new(factorize_simplicial_numeric_lu_scratch::<usize, f64>(n, n))
                .map_err(|_| LinsolveError::OutOfMemory)?;
        let col_perm = PermRef::new_checked(&pm.identity, &pm.identity, n);
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
                    index: pm.fwd.get(index).copied().unwrap_or(0),
                    pivot: 0.0,
                    scale: 0.0,
                });
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
                    .find(|&(&i, _)| i == j)
                    .map_or(0.0, |(_, v)| *v);
                let scale = rowmax[row];
                if !exceeds(pivot.abs(), rel * scale) {
                    return Err(LinsolveError::Singular {
                        index: pm.fwd[j],
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
            },
            min_ratio,
        ))
    }

    /// The scaled, shifted values `d_i d_j k_ij + μ δ_ij` into the permuted
    /// storage.
    ///
    /// # Errors
    /// [`LinsolveError::NonFinite`] naming the first entry that is not
    /// finite.
    fn scale_and_permute(
        &mut self,
        matrix: &SymmetricMatrix,
        d_perm: &[f64],
        shift: f64,
    ) -> Result<(), LinsolveError> {
        let pm = &self.perm;
        let tri = pm.tri.as_ref();
        let values = matrix.values();
        self.scaled.clear();
        self.scaled.resize(pm.src.len(), 0.0);
        // v − v is 0 for finite v, NaN for NaN and ±∞
        let mut bad = 0.0f64;
        for (c, &dc) in d_perm.iter().enumerate() {
            let range = tri.col_range(c);
            for ((out, &k), &r) in self.scaled[range.clone()]
                .iter_mut()
                .zip(&pm.src[range.clone()])
                .zip(tri.row_idx_of_col_raw(c))
            {
                let v = values[k];
                #[allow(clippy::eq_op)]
                {
                    bad += v - v;
                }
                *out = v * d_perm[r] * dc;
            }
        }
        for &at in &pm.diag {
            self.scaled[at] += shift;
        }
        if bad.is_nan() {
            matrix.check_finite()?;
        }
        Ok(())
    }
}

/// What a numeric `L Lᵀ` / `L D Lᵀ` gave.
enum CholeskyOutcome {
    /// faer stopped at a pivot (zero, non-finite, or for `L Lᵀ` not positive).
    Failed { index: usize },
    /// The factor values (the pivots are in `SparseSolver::pivots`).
    Done { values: Vec<f64> },
    /// An `L D Lᵀ` that exists but is not positive definite (its pivots in
    /// `SparseSolver::pivots`).
    Indefinite,
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
        super::work::count_factorization();
        let n = matrix.n();
        // the Jacobi scaling |k_ii|^-1/2 (1 for a zero or non-finite
        // diagonal)
        let (values, diag) = (matrix.values(), self.pattern.diagonal_slots());
        let jacobi = |i: usize| {
            let a = values[diag[i]].abs();
            if a > 0.0 && a.is_finite() {
                1.0 / a.sqrt()
            } else {
                1.0
            }
        };
        let all_positive = Some(Inertia {
            positive: n,
            negative: 0,
        });
        // the natural order's scaling, for the band paths
        let d_band: Option<Arc<Vec<f64>>> = self
            .perm
            .band
            .as_ref()
            .map(|_| Arc::new((0..n).map(jacobi).collect()));
        if let (Some(band), Some(d)) = (&self.perm.band, &d_band) {
            // a positive definite band matrix: its band L D Lᵀ in the
            // natural order; anything else goes on to the general path
            if let Ok((f, ratio)) = band.factor(matrix, d, options.shift)? {
                return Ok(self.band_factors(Numeric::Band(f), d, all_positive, ratio));
            }
            // (a pivot the natural order leaves below the test may pass in
            // the fill-reducing order: the general path decides, so that
            // the band path never refuses what the general path factors);
            // an indefinite one: its band inertia and LU (band_lu.rs)
            if let Some((f, inertia, ratio)) = band.indefinite(matrix, d, options)? {
                return Ok(self.band_factors(Numeric::BandLu(f), d, Some(inertia), ratio));
            }
        }
        // in the permuted order
        let d_perm: Vec<f64> = self.perm.fwd.iter().map(|&i| jacobi(i)).collect();
        self.scale_and_permute(matrix, &d_perm, options.shift)?;
        let d_perm = Arc::new(d_perm);
        let (symbolic, perm) = (self.symbolic.clone(), self.perm.clone());
        let factors = |numeric, inertia, min_pivot| SparseFactors {
            n,
            symbolic: symbolic.clone(),
            perm: perm.clone(),
            numeric,
            scaling: d_perm.clone(),
            inertia,
            min_pivot,
        };
        let llt_first = self.settings.cholesky == CholeskyKind::Llt;
        let mut outcome = self.cholesky(llt_first)?;
        if llt_first {
            if let CholeskyOutcome::Done { values } = outcome
                && let Ok(ratio) = self.positive_definite()
            {
                return Ok(factors(Numeric::Llt(values), all_positive, ratio));
            }
            // not positive definite: L D Lᵀ for the pivot and the inertia
            outcome = self.cholesky(false)?;
        }
        if let CholeskyOutcome::Done { values } = outcome {
            match self.positive_definite() {
                Ok(ratio) => return Ok(factors(Numeric::Ldlt(values), all_positive, ratio)),
                Err((index, pivot)) if options.require_positive_definite => {
                    return Err(LinsolveError::NotPositiveDefinite { index, pivot });
                }
                Err(_) => outcome = CholeskyOutcome::Indefinite,
            }
        }
        // not positive definite: the row scales of the pivot tests, the
        // inertia if the L D Lᵀ exists, and the pivoted LU
        let rowmax = self.row_scales();
        let inertia = match outcome {
            CholeskyOutcome::Done { .. } | CholeskyOutcome::Indefinite => self.inertia_of(&rowmax),
            CholeskyOutcome::Failed { index } => {
                if options.require_positive_definite {
                    return Err(LinsolveError::NotPositiveDefinite { index, pivot: 0.0 });
                }
                None
            }
        };
        let Some((band, d)) = self.perm.band.as_ref().zip(d_band) else {
            let (numeric, min_pivot) = self.lu(&rowmax)?;
            return Ok(factors(numeric, inertia, min_pivot));
        };
        // a band pattern: the band LU in the natural order (band_lu.rs)
        let (f, min_pivot) = band.lu(matrix, &d, options.shift)?;
        Ok(self.band_factors(Numeric::BandLu(f), &d, inertia, min_pivot))
    }
}

/// One triangle of the symmetrically permuted pattern (`inv[i]` the new
/// index of row `i`): column pointers, sorted row indices, and for each
/// stored entry its slot in `p`'s values.
fn permuted_triangle(
    p: &SymmetricPattern,
    inv: &[usize],
    side: Side,
) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let n = p.n();
    let (cp, ri) = (p.col_ptr(), p.row_idx());
    // (column, row, slot) in the permuted numbering
    let mut entries: Vec<(usize, usize, usize)> = Vec::with_capacity(ri.len());
    for j in 0..n {
        for (k, &i) in ri.iter().enumerate().take(cp[j + 1]).skip(cp[j]) {
            let (a, b) = (inv[i], inv[j]);
            let (lo, hi) = (a.min(b), a.max(b));
            entries.push(match side {
                Side::Upper => (hi, lo, k),
                Side::Lower => (lo, hi, k),
            });
        }
    }
    entries.sort_unstable();
    compress(n, &entries)
}

/// The full pattern (both triangles) of a symmetric matrix stored as one
/// triangle (`col_ptr`, `row_idx`): its column pointers, sorted row
/// indices, and for each entry the stored entry it copies.
fn full_pattern(
    n: usize,
    col_ptr: &[usize],
    row_idx: &[usize],
) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let mut entries: Vec<(usize, usize, usize)> = Vec::with_capacity(2 * row_idx.len());
    for c in 0..n {
        for (k, &r) in row_idx
            .iter()
            .enumerate()
            .take(col_ptr[c + 1])
            .skip(col_ptr[c])
        {
            entries.push((c, r, k));
            if r != c {
                entries.push((r, c, k));
            }
        }
    }
    entries.sort_unstable();
    compress(n, &entries)
}

/// Compressed columns from sorted `(column, row, source)` triples.
fn compress(n: usize, entries: &[(usize, usize, usize)]) -> (Vec<usize>, Vec<usize>, Vec<usize>) {
    let mut ptr = vec![0usize; n + 1];
    for &(c, _, _) in entries {
        ptr[c + 1] += 1;
    }
    for c in 0..n {
        ptr[c + 1] += ptr[c];
    }
    let rows = entries.iter().map(|e| e.1).collect();
    let src = entries.iter().map(|e| e.2).collect();
    (ptr, rows, src)
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
