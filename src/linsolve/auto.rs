//! A solver chosen at run time: the banded one for single chains (a narrow
//! band: about twice as fast as faer's sparse factorization there), the
//! sparse one for everything else.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::{
    BandedLu, BandedSolver, FactorMethod, FactorOptions, Factorization, Inertia, LinsolveError,
    SparseFactors, SparseSolver, SymmetricMatrix, SymmetricPattern, TangentSolver,
};

/// The widest band [`SolverKind::Auto`] gives to the banded solver: a
/// single chain of two-node elements with up to 8 dofs per node (the
/// planar cable has bandwidth 7, the spatial one 11).
pub const AUTO_MAX_BANDWIDTH: usize = 15;

/// Which solver an [`AutoSolver`] uses.
///
/// # Example
/// ```
/// use softrod::linsolve::SolverKind;
/// let k: SolverKind = serde_json::from_str(r#""sparse""#).unwrap();
/// assert_eq!(k, SolverKind::Sparse);
/// assert_eq!(SolverKind::default(), SolverKind::Auto);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SolverKind {
    /// Banded when the pattern's bandwidth is at most
    /// [`AUTO_MAX_BANDWIDTH`], sparse otherwise (the default).
    #[default]
    Auto,
    /// Always [`BandedSolver`] (any pattern; a wide one costs `n × bandwidth`
    /// storage).
    Banded,
    /// Always [`SparseSolver`] with its default settings.
    Sparse,
}

/// [`BandedSolver`] or [`SparseSolver`], chosen by a [`SolverKind`] when the
/// pattern is analyzed.
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use softrod::linsolve::*;
/// // a chain: banded; the same chain closed into a ring: sparse
/// let chain: Vec<[usize; 2]> = (0..99).map(|e| [e, e + 1]).collect();
/// let mut ring = chain.clone();
/// ring.push([99, 0]);
/// for (els, kind) in [(chain, SolverKind::Banded), (ring, SolverKind::Sparse)] {
///     let p = Arc::new(SymmetricPattern::from_elements(100, &els)?);
///     let mut k = SymmetricMatrix::zeros(p.clone());
///     for e in 0..els.len() {
///         k.add_element(e, &[1.0, -1.0, -1.0, 1.0])?;
///     }
///     k.add(0, 0, 1.0)?;
///     let mut solver = AutoSolver::analyze(&p)?;
///     assert_eq!(solver.kind(), kind);
///     let mut x = vec![1.0; 100];
///     solver.factor(&k, FactorOptions::default())?.solve_in_place(&mut x)?;
/// }
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub enum AutoSolver {
    /// The banded solver.
    Banded(BandedSolver),
    /// The sparse solver.
    Sparse(SparseSolver),
}

impl AutoSolver {
    /// Analyzes `pattern` with the solver `kind` asks for.
    ///
    /// # Errors
    /// As [`TangentSolver::analyze`] of the chosen solver.
    ///
    /// # Example
    /// ```
    /// use std::sync::Arc;
    /// use softrod::linsolve::{AutoSolver, SolverKind, SymmetricPattern};
    /// let p = Arc::new(SymmetricPattern::from_elements(3, [[0, 1], [1, 2]])?);
    /// let s = AutoSolver::with_kind(&p, SolverKind::Sparse)?;
    /// assert_eq!(s.kind(), SolverKind::Sparse);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_kind(
        pattern: &Arc<SymmetricPattern>,
        kind: SolverKind,
    ) -> Result<Self, LinsolveError> {
        let banded = match kind {
            SolverKind::Auto => pattern.bandwidth() <= AUTO_MAX_BANDWIDTH,
            SolverKind::Banded => true,
            SolverKind::Sparse => false,
        };
        Ok(if banded {
            AutoSolver::Banded(BandedSolver::analyze(pattern)?)
        } else {
            AutoSolver::Sparse(SparseSolver::analyze(pattern)?)
        })
    }

    /// The solver in use ([`SolverKind::Banded`] or [`SolverKind::Sparse`]).
    pub fn kind(&self) -> SolverKind {
        match self {
            AutoSolver::Banded(_) => SolverKind::Banded,
            AutoSolver::Sparse(_) => SolverKind::Sparse,
        }
    }
}

impl TangentSolver for AutoSolver {
    type Factors = AutoFactors;

    fn analyze(pattern: &Arc<SymmetricPattern>) -> Result<Self, LinsolveError> {
        Self::with_kind(pattern, SolverKind::Auto)
    }

    fn pattern(&self) -> &Arc<SymmetricPattern> {
        match self {
            AutoSolver::Banded(s) => s.pattern(),
            AutoSolver::Sparse(s) => s.pattern(),
        }
    }

    fn factor(
        &mut self,
        matrix: &SymmetricMatrix,
        options: FactorOptions,
    ) -> Result<AutoFactors, LinsolveError> {
        Ok(match self {
            AutoSolver::Banded(s) => AutoFactors::Banded(s.factor(matrix, options)?),
            AutoSolver::Sparse(s) => AutoFactors::Sparse(s.factor(matrix, options)?),
        })
    }
}

/// The factors of an [`AutoSolver`].
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use softrod::linsolve::*;
/// let p = Arc::new(SymmetricPattern::from_elements(2, [[0, 1]])?);
/// let mut k = SymmetricMatrix::zeros(p.clone());
/// k.add_element(0, &[2.0, 1.0, 1.0, 2.0])?;
/// let f: AutoFactors = AutoSolver::analyze(&p)?.factor(&k, FactorOptions::default())?;
/// assert!(matches!(f, AutoFactors::Banded(_)) && f.is_positive_definite());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub enum AutoFactors {
    /// Of the banded solver.
    Banded(BandedLu),
    /// Of the sparse solver.
    Sparse(SparseFactors),
}

impl Factorization for AutoFactors {
    fn n(&self) -> usize {
        match self {
            AutoFactors::Banded(f) => Factorization::n(f),
            AutoFactors::Sparse(f) => f.n(),
        }
    }

    fn method(&self) -> FactorMethod {
        match self {
            AutoFactors::Banded(f) => f.method(),
            AutoFactors::Sparse(f) => f.method(),
        }
    }

    fn inertia(&self) -> Option<Inertia> {
        match self {
            AutoFactors::Banded(f) => f.inertia(),
            AutoFactors::Sparse(f) => f.inertia(),
        }
    }

    fn pivot_ratio(&self) -> f64 {
        match self {
            AutoFactors::Banded(f) => Factorization::pivot_ratio(f),
            AutoFactors::Sparse(f) => f.pivot_ratio(),
        }
    }

    fn solve_in_place(&self, b: &mut [f64]) -> Result<(), LinsolveError> {
        match self {
            AutoFactors::Banded(f) => Factorization::solve_in_place(f, b),
            AutoFactors::Sparse(f) => f.solve_in_place(b),
        }
    }

    fn solve_columns_in_place(&self, b: &mut [f64], nrhs: usize) -> Result<(), LinsolveError> {
        match self {
            AutoFactors::Banded(f) => f.solve_columns_in_place(b, nrhs),
            AutoFactors::Sparse(f) => f.solve_columns_in_place(b, nrhs),
        }
    }
}
