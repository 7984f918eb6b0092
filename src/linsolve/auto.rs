//! The solver the library uses for every tangent, chosen by a [`SolverKind`]
//! in the settings. Today that is faer's sparse `L D Lᵀ` ([`SparseSolver`])
//! for every structure: a banded `L D Lᵀ` for single chains was measured
//! against it on the warm estimator step and the warm static solve (20, 200
//! and 2000 elements) and was nowhere 1.5 times faster end to end (at most
//! 1.2–1.25), so it was removed (README, "Performance").

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::{
    FactorMethod, FactorOptions, Factorization, Inertia, LinsolveError, SparseFactors,
    SparseSolver, SymmetricMatrix, SymmetricPattern, TangentSolver,
};

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
#[non_exhaustive]
pub enum SolverKind {
    /// The library's choice for the pattern (the default): today always
    /// [`SolverKind::Sparse`].
    #[default]
    Auto,
    /// [`SparseSolver`] with its default settings.
    Sparse,
}

/// The solver a [`SolverKind`] names, analyzed on a pattern: today always
/// [`SparseSolver`] (the enum leaves room for others).
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use softrod::linsolve::*;
/// // a chain closed into a ring (any pattern will do)
/// let mut els: Vec<[usize; 2]> = (0..99).map(|e| [e, e + 1]).collect();
/// els.push([99, 0]);
/// let p = Arc::new(SymmetricPattern::from_elements(100, &els)?);
/// let mut k = SymmetricMatrix::zeros(p.clone());
/// for e in 0..els.len() {
///     k.add_element(e, &[1.0, -1.0, -1.0, 1.0])?;
/// }
/// k.add(0, 0, 1.0)?;
/// let mut solver = AutoSolver::analyze(&p)?;
/// assert_eq!(solver.kind(), SolverKind::Sparse);
/// let mut x = vec![1.0; 100];
/// solver.factor(&k, FactorOptions::default())?.solve_in_place(&mut x)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum AutoSolver {
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
        match kind {
            SolverKind::Auto | SolverKind::Sparse => {
                Ok(AutoSolver::Sparse(SparseSolver::analyze(pattern)?))
            }
        }
    }

    /// The solver in use (never [`SolverKind::Auto`]).
    pub fn kind(&self) -> SolverKind {
        match self {
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
            AutoSolver::Sparse(s) => s.pattern(),
        }
    }

    fn factor(
        &mut self,
        matrix: &SymmetricMatrix,
        options: FactorOptions,
    ) -> Result<AutoFactors, LinsolveError> {
        Ok(match self {
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
/// assert!(matches!(f, AutoFactors::Sparse(_)) && f.is_positive_definite());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
#[non_exhaustive]
pub enum AutoFactors {
    /// Of the sparse solver.
    Sparse(SparseFactors),
}

impl Factorization for AutoFactors {
    fn n(&self) -> usize {
        match self {
            AutoFactors::Sparse(f) => f.n(),
        }
    }

    fn method(&self) -> FactorMethod {
        match self {
            AutoFactors::Sparse(f) => f.method(),
        }
    }

    fn inertia(&self) -> Option<Inertia> {
        match self {
            AutoFactors::Sparse(f) => f.inertia(),
        }
    }

    fn pivot_ratio(&self) -> f64 {
        match self {
            AutoFactors::Sparse(f) => f.pivot_ratio(),
        }
    }

    fn solve_in_place(&self, b: &mut [f64]) -> Result<(), LinsolveError> {
        match self {
            AutoFactors::Sparse(f) => f.solve_in_place(b),
        }
    }

    fn solve_columns_in_place(&self, b: &mut [f64], nrhs: usize) -> Result<(), LinsolveError> {
        match self {
            AutoFactors::Sparse(f) => f.solve_columns_in_place(b, nrhs),
        }
    }
}
