//! Linear solvers for the tangent stiffness, behind one trait.
//!
//! A Newton method solves `K du = r` with a new `K` at every iteration but
//! the same sparsity: the pattern is analyzed once ([`TangentSolver::analyze`]),
//! each tangent is factored numerically ([`TangentSolver::factor`]), and the
//! factors solve one or many right-hand sides in place
//! ([`Factorization::solve_in_place`], [`Factorization::solve_columns_in_place`]:
//! the estimator's adjoint systems share one factorization).
//!
//! The assembler does not know the solver: it writes element blocks into a
//! [`SymmetricMatrix`] on a [`SymmetricPattern`] built from the element
//! connectivity (each element's global dofs), through scatter maps computed
//! with the pattern.
//!
//! Every solver factors the Jacobi-scaled, optionally shifted matrix
//! `D K D + μ I`, `D = diag(|k_ii|^-1/2)` (the rows of a fine cable's
//! tangent span many orders of magnitude), by `L D Lᵀ` or Cholesky when it
//! is positive definite. A tangent that is not (compression, buckling, an
//! iterate far from equilibrium) is refactored with pivoting (LU) unless
//! [`FactorOptions::require_positive_definite`] asks for the error instead;
//! the factors report the tangent's [`Inertia`] (Sylvester's law: the signs
//! of the `L D Lᵀ` pivots are those of the eigenvalues) whenever an `L D Lᵀ`
//! exists, so a Newton method can see that its tangent is indefinite.
//! Failures are data: [`LinsolveError`].
//!
//! Implementations:
//! - [`SparseSolver`]: any pattern. faer's `L D Lᵀ` (or Cholesky) after a
//!   fill-reducing ordering whose symbolic analysis all factorizations
//!   share, and faer's pivoted LU; and the *band path*: where the pattern
//!   is a narrow band in the dofs' own order (a chain numbered node by
//!   node, i.e. every robot's tangent; [`sparse::BandPath`] says when
//!   exactly), band kernels in that order replace faer: a band `L D Lᵀ`
//!   for a positive definite matrix, its inertia and a band LU with
//!   partial pivoting for an indefinite one. They were kept because they
//!   measured faster than faer on the small tangents of the static solves
//!   (README, "Performance").
//! - [`AutoSolver`]: the [`SparseSolver`] a [`SolverKind`] names: the band
//!   path where the pattern is a narrow band (`Auto`, the default), never
//!   (`Sparse`), or required (`Band`).
//!
//! [`BandedMatrix`] is plain band storage (the load Gram matrix, a tangent
//! target for element tests); nothing factors it.
//!
//! # Example
//! ```
//! use std::sync::Arc;
//! use softrod::linsolve::{
//!     Factorization, FactorOptions, SparseSolver, SymmetricMatrix, SymmetricPattern, TangentSolver,
//! };
//! // a chain of five springs, fixed at one end: dofs 0..5
//! let elements: Vec<Vec<usize>> = (0..4).map(|e| vec![e, e + 1]).collect();
//! let pattern = Arc::new(SymmetricPattern::from_elements(5, &elements)?);
//! let mut solver = SparseSolver::analyze(&pattern)?;
//! let mut k = SymmetricMatrix::zeros(pattern);
//! k.add(0, 0, 1.0)?; // the spring to the ground
//! for e in 0..4 {
//!     k.add_element(e, &[1.0, -1.0, -1.0, 1.0])?;
//! }
//! let f = solver.factor(&k, FactorOptions::default())?;
//! assert!(f.is_positive_definite());
//! let mut u = vec![0.0, 0.0, 0.0, 0.0, 1.0]; // unit force at the free end
//! f.solve_in_place(&mut u)?;
//! assert!((u[4] - 5.0).abs() < 1e-12); // five unit springs in series
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::sync::Arc;

mod auto;
pub mod banded;
mod pattern;
pub mod sparse;
mod work;

pub use auto::{AutoFactors, AutoSolver, SolverKind};
pub use banded::BandedMatrix;
pub use pattern::{MAX_ELEMENT_DOFS, SymmetricMatrix, SymmetricPattern};
pub use sparse::{CholeskyKind, SparseFactors, SparseSettings, SparseSolver};
pub use work::LinearWork;

/// Why a factorization or a solve failed. Indices are rows (dofs) of the
/// matrix as given, not of a reordering.
///
/// # Example
/// ```
/// use softrod::linsolve::LinsolveError;
/// let e = LinsolveError::NotPositiveDefinite { index: 3, pivot: -0.5 };
/// assert!(e.to_string().contains("row 3"));
/// ```
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LinsolveError {
    /// The (scaled, shifted) matrix is not positive definite and
    /// [`FactorOptions::require_positive_definite`] was set: the first
    /// pivot that is not clearly positive, in elimination order.
    #[error("not positive definite: pivot {pivot:e} at row {index}")]
    NotPositiveDefinite {
        /// Row of the pivot.
        index: usize,
        /// The pivot of the Jacobi-scaled matrix (its diagonal is 1 + shift).
        pivot: f64,
    },
    /// No usable pivot: the matrix is singular to working precision (a pivot
    /// below `n ε` times the largest entry of its row of the scaled matrix).
    #[error("singular matrix: pivot {pivot:e} at row {index} (its row's scale {scale:e})")]
    Singular {
        /// Row (or, for a pivoted LU, column) of the pivot.
        index: usize,
        /// The pivot's value (scaled matrix).
        pivot: f64,
        /// The largest absolute entry of its row (scaled matrix).
        scale: f64,
    },
    /// The matrix holds a NaN or an infinity (the first such entry).
    #[error("non-finite matrix entry at ({row}, {col})")]
    NonFinite {
        /// Row of the entry.
        row: usize,
        /// Column of the entry.
        col: usize,
    },
    /// A vector has the wrong length.
    #[error("dimension mismatch in `{name}`: expected {expected}, got {got}")]
    DimensionMismatch {
        /// Which argument.
        name: &'static str,
        /// The length expected.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// The matrix lives on another pattern than the one the solver analyzed.
    #[error("the matrix's sparsity pattern is not the one the solver analyzed")]
    PatternMismatch,
    /// A factor option is out of range.
    #[error("invalid factor option `{name}` = {value}: {reason}")]
    InvalidOption {
        /// The option.
        name: &'static str,
        /// Its value.
        value: f64,
        /// The valid range.
        reason: &'static str,
    },
    /// The factors or their workspace would exceed what can be stored.
    #[error("{what} is too large: {entries} entries, at most {max}")]
    TooLarge {
        /// What was to be stored.
        what: &'static str,
        /// The entries it needs.
        entries: usize,
        /// The most accepted.
        max: usize,
    },
    /// An allocation for the factors or a workspace failed.
    #[error("out of memory in the linear solver")]
    OutOfMemory,
    /// The band path was required ([`sparse::BandPath::Required`]) of a
    /// pattern that is not a narrow band: its band in the dofs' own order
    /// stores more than twice the entries of the fill-reduced sparse factor.
    #[error(
        "the pattern is not a narrow band: half-bandwidth {half_bandwidth}, \
         {band_entries} band entries against {factor_entries} of the sparse factor"
    )]
    NotBanded {
        /// The half-bandwidth `b` in the dofs' own order.
        half_bandwidth: usize,
        /// The band's storage `n (b + 1)` (`usize::MAX` if it overflows).
        band_entries: usize,
        /// The entries of faer's factor after its fill-reducing ordering.
        factor_entries: usize,
    },
}

impl From<LinsolveError> for crate::Error {
    /// Maps each failure onto the crate's error kind that carries its data:
    /// a pivot that is not positive where positive definiteness was required
    /// to [`crate::Error::NonPositivePivot`] (its row and value), a singular
    /// matrix to [`crate::Error::Singular`] (row, pivot, scale), a
    /// non-finite entry to [`crate::Error::NonFinite`] (naming it), sizes
    /// to [`crate::Error::DimensionMismatch`] / [`crate::Error::TooLarge`],
    /// a failed allocation to [`crate::Error::OutOfMemory`], and the
    /// caller's mistakes (another pattern, a bad option, the band path
    /// required of a pattern that is not banded) to
    /// [`crate::Error::InvalidParameter`].
    ///
    /// # Example
    /// ```
    /// use softrod::{linsolve::LinsolveError, Error};
    /// let e: Error = LinsolveError::NotPositiveDefinite { index: 3, pivot: -0.5 }.into();
    /// assert!(matches!(e, Error::NonPositivePivot { index: 3, pivot: -0.5, .. }));
    /// ```
    fn from(e: LinsolveError) -> Self {
        use crate::Error;
        match e {
            LinsolveError::NotPositiveDefinite { index, pivot } => Error::NonPositivePivot {
                context: "linear solve".into(),
                index,
                pivot,
            },
            LinsolveError::Singular {
                index,
                pivot,
                scale,
            } => Error::Singular {
                context: "linear solve".into(),
                index,
                pivot,
                scale,
            },
            LinsolveError::NonFinite { row, col } => Error::NonFinite {
                context: format!("linear solve: matrix entry ({row}, {col})"),
            },
            LinsolveError::DimensionMismatch {
                name,
                expected,
                got,
            } => Error::DimensionMismatch {
                name: name.into(),
                expected,
                got,
            },
            LinsolveError::TooLarge { what, entries, max } => Error::TooLarge {
                name: what.into(),
                value: entries,
                max,
            },
            LinsolveError::PatternMismatch => Error::invalid(
                "matrix",
                "another sparsity pattern",
                "must be on the pattern the solver analyzed",
            ),
            LinsolveError::InvalidOption {
                name,
                value,
                reason,
            } => Error::invalid(name, value, reason),
            LinsolveError::OutOfMemory => Error::OutOfMemory {
                context: "linear solve".into(),
            },
            e @ LinsolveError::NotBanded { .. } => {
                Error::invalid("linear_solver", "band", e.to_string())
            }
        }
    }
}

/// How one matrix is factored.
///
/// # Example
/// ```
/// use softrod::linsolve::FactorOptions;
/// let o = FactorOptions { shift: 1e-6, ..FactorOptions::default() };
/// assert!(!o.require_positive_definite);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FactorOptions {
    /// Diagonal shift `μ >= 0` of the Jacobi-scaled matrix: the factors solve
    /// `(K + μ diag|k_ii|) x = b` (a Levenberg–Marquardt-like shift a Newton
    /// method raises when the tangent is not positive definite). Default 0.
    pub shift: f64,
    /// Refuse a matrix that is not positive definite
    /// ([`LinsolveError::NotPositiveDefinite`]) instead of refactoring it
    /// with pivoting: cheap when the caller only wants a descent direction.
    /// Default `false`.
    pub require_positive_definite: bool,
}

impl Default for FactorOptions {
    fn default() -> Self {
        FactorOptions {
            shift: 0.0,
            require_positive_definite: false,
        }
    }
}

impl FactorOptions {
    /// Checks the shift.
    ///
    /// # Errors
    /// [`LinsolveError::InvalidOption`] for a negative or non-finite shift.
    ///
    /// # Example
    /// ```
    /// use softrod::linsolve::FactorOptions;
    /// assert!(FactorOptions { shift: -1.0, ..Default::default() }.validate().is_err());
    /// ```
    pub fn validate(&self) -> Result<(), LinsolveError> {
        if !(self.shift.is_finite() && self.shift >= 0.0) {
            return Err(LinsolveError::InvalidOption {
                name: "shift",
                value: self.shift,
                reason: "must be finite and >= 0",
            });
        }
        Ok(())
    }
}

/// Which factorization solves: Cholesky `L Lᵀ`, `L D Lᵀ` (both without
/// pivoting, after a fill-reducing ordering), or LU with partial pivoting.
///
/// # Example
/// ```
/// use softrod::linsolve::FactorMethod;
/// assert_ne!(FactorMethod::Ldlt, FactorMethod::Lu);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FactorMethod {
    /// Cholesky `L Lᵀ` (positive definite).
    Llt,
    /// `L D Lᵀ` without pivoting.
    Ldlt,
    /// LU with partial pivoting (indefinite or nearly singular tangents).
    Lu,
}

/// The inertia of a symmetric matrix: how many eigenvalues are positive and
/// negative (a factored matrix has no zero eigenvalue to working precision).
///
/// # Example
/// ```
/// use softrod::linsolve::Inertia;
/// let i = Inertia { positive: 5, negative: 1 };
/// assert!(!i.is_positive_definite());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Inertia {
    /// Number of positive eigenvalues.
    pub positive: usize,
    /// Number of negative eigenvalues.
    pub negative: usize,
}

impl Inertia {
    /// Whether every eigenvalue is positive.
    pub fn is_positive_definite(&self) -> bool {
        self.negative == 0
    }
}

/// The factors of one matrix: they solve `K x = b` for one or many `b`.
///
/// `Clone` is cheap relative to a factorization (the symbolic part is
/// shared); a Newton method may keep old factors for chord steps.
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use softrod::linsolve::*;
/// let p = Arc::new(SymmetricPattern::from_elements(2, [[0, 1]])?);
/// let mut k = SymmetricMatrix::zeros(p.clone());
/// k.add_element(0, &[2.0, 1.0, 1.0, 2.0])?;
/// let f = SparseSolver::analyze(&p)?.factor(&k, FactorOptions::default())?;
/// // two right-hand sides, column after column
/// let mut b = vec![3.0, 3.0, 1.0, -1.0];
/// f.solve_columns_in_place(&mut b, 2)?;
/// assert!(b.iter().zip([1.0, 1.0, 1.0, -1.0]).all(|(x, y)| (x - y).abs() < 1e-14));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub trait Factorization: Clone + std::fmt::Debug + Send + Sync {
    /// Order of the factored matrix.
    fn n(&self) -> usize;

    /// Which factorization solves.
    fn method(&self) -> FactorMethod;

    /// The inertia of the factored (shifted) matrix when an `L D Lᵀ` or
    /// Cholesky factorization of it exists, `None` when only the pivoted
    /// LU was possible.
    fn inertia(&self) -> Option<Inertia>;

    /// Whether the factored (shifted) matrix is known to be positive
    /// definite.
    fn is_positive_definite(&self) -> bool {
        self.inertia().is_some_and(|i| i.is_positive_definite())
    }

    /// Smallest ratio of a pivot to the largest entry of its row (scaled
    /// matrix): small means nearly singular.
    fn pivot_ratio(&self) -> f64;

    /// Solves `K x = b` in place.
    ///
    /// # Errors
    /// [`LinsolveError::DimensionMismatch`] if `b` does not have `n` entries;
    /// [`LinsolveError::OutOfMemory`] if the workspace cannot be allocated.
    fn solve_in_place(&self, b: &mut [f64]) -> Result<(), LinsolveError>;

    /// Solves `K X = B` in place for `nrhs` right-hand sides stored column
    /// after column (`b[c n + i]` is entry `i` of right-hand side `c`), in
    /// one sweep over the factors.
    ///
    /// # Errors
    /// [`LinsolveError::DimensionMismatch`] if `b` does not have
    /// `n · nrhs` entries; [`LinsolveError::OutOfMemory`] as above.
    fn solve_columns_in_place(&self, b: &mut [f64], nrhs: usize) -> Result<(), LinsolveError>;
}

/// A linear solver for symmetric tangents: analyzes a sparsity pattern
/// once, then factors any number of matrices on it.
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use softrod::linsolve::*;
/// fn solve<S: TangentSolver>(k: &SymmetricMatrix, b: &mut [f64]) -> Result<(), LinsolveError> {
///     let mut solver = S::analyze(k.pattern())?;
///     solver.factor(k, FactorOptions::default())?.solve_in_place(b)
/// }
/// let p = Arc::new(SymmetricPattern::from_elements(2, [[0, 1]])?);
/// let mut k = SymmetricMatrix::zeros(p);
/// k.add_element(0, &[2.0, 1.0, 1.0, 2.0])?;
/// let (mut x, mut y) = (vec![3.0, 3.0], vec![3.0, 3.0]);
/// solve::<SparseSolver>(&k, &mut x)?;
/// solve::<AutoSolver>(&k, &mut y)?;
/// assert!((x[0] - 1.0).abs() < 1e-14 && (y[1] - 1.0).abs() < 1e-14);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub trait TangentSolver {
    /// The factors [`TangentSolver::factor`] returns.
    type Factors: Factorization;

    /// Analyzes `pattern` (orderings, symbolic factorization, storage).
    ///
    /// # Errors
    /// [`LinsolveError::TooLarge`] or [`LinsolveError::OutOfMemory`] when
    /// the factors of this pattern cannot be stored.
    fn analyze(pattern: &Arc<SymmetricPattern>) -> Result<Self, LinsolveError>
    where
        Self: Sized;

    /// The pattern this solver was analyzed for.
    fn pattern(&self) -> &Arc<SymmetricPattern>;

    /// Factors the Jacobi-scaled, shifted `matrix` (see the module docs):
    /// `L Lᵀ` or `L D Lᵀ` when positive definite, else (unless
    /// `options.require_positive_definite`) a pivoted LU, with the inertia
    /// from an `L D Lᵀ` when one exists.
    ///
    /// # Errors
    /// [`LinsolveError::PatternMismatch`] for a matrix on another pattern;
    /// [`LinsolveError::InvalidOption`] for a bad shift;
    /// [`LinsolveError::NonFinite`] for a NaN or infinite entry;
    /// [`LinsolveError::NotPositiveDefinite`] (only when required);
    /// [`LinsolveError::Singular`] when no pivot is usable;
    /// [`LinsolveError::OutOfMemory`].
    fn factor(
        &mut self,
        matrix: &SymmetricMatrix,
        options: FactorOptions,
    ) -> Result<Self::Factors, LinsolveError>;
}

/// The checks every [`TangentSolver::factor`] starts with (finiteness is
/// checked while the values are read).
fn check_factor_input(
    pattern: &Arc<SymmetricPattern>,
    matrix: &SymmetricMatrix,
    options: &FactorOptions,
) -> Result<(), LinsolveError> {
    if !(Arc::ptr_eq(pattern, matrix.pattern()) || **pattern == **matrix.pattern()) {
        return Err(LinsolveError::PatternMismatch);
    }
    options.validate()
}

/// The length check of the solves.
fn check_rhs(name: &'static str, expected: usize, got: usize) -> Result<(), LinsolveError> {
    if expected == got {
        Ok(())
    } else {
        Err(LinsolveError::DimensionMismatch {
            name,
            expected,
            got,
        })
    }
}

/// The pivot threshold relative to a row's scale: `n ε`.
fn pivot_tolerance(n: usize) -> f64 {
    (n.max(1) as f64) * f64::EPSILON
}

#[cfg(test)]
mod tests;
