//! The solver the library uses for every tangent, chosen by a [`SolverKind`]
//! in the settings ([`crate::statics::StaticSettings::linear_solver`]).
//!
//! Every kind is the [`SparseSolver`]; the kind says whether it takes its
//! band path (see [`crate::linsolve::sparse::BandPath`]): band kernels in
//! the dofs' own order where the pattern is a narrow band (a robot's chain,
//! the default `Auto`), faer's fill-reducing sparse factorizations always
//! (`Sparse`), or the band kernels required (`Band`, refused for a pattern
//! that is not a narrow band). They solve the same systems to round-off.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::sparse::BandPath;
use super::{
    FactorOptions, LinsolveError, SparseFactors, SparseSettings, SparseSolver, SymmetricMatrix,
    SymmetricPattern, TangentSolver,
};

/// Which factorization an [`AutoSolver`] uses.
///
/// # Example
/// ```
/// use softrod::linsolve::SolverKind;
/// let k: SolverKind = serde_json::from_str(r#""band""#).unwrap();
/// assert_eq!(k, SolverKind::Band);
/// assert_eq!(SolverKind::default(), SolverKind::Auto);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum SolverKind {
    /// The band kernels where the pattern is a narrow band (every robot's
    /// chain), faer's sparse factorizations otherwise (the default):
    /// [`BandPath::WhereNarrow`].
    #[default]
    Auto,
    /// faer's sparse `L D Lᵀ` after a fill-reducing ordering (pivoted LU for
    /// an indefinite matrix) for every pattern, never the band kernels:
    /// [`BandPath::Never`].
    Sparse,
    /// The band kernels in the dofs' own order (`L D Lᵀ`, band LU for an
    /// indefinite matrix); a pattern that is not a narrow band is refused:
    /// [`BandPath::Required`].
    Band,
}

impl SolverKind {
    /// The [`SparseSolver`] settings of this kind.
    ///
    /// # Example
    /// ```
    /// use softrod::linsolve::{sparse::BandPath, SolverKind};
    /// assert_eq!(SolverKind::Sparse.sparse_settings().band, BandPath::Never);
    /// ```
    pub fn sparse_settings(self) -> SparseSettings {
        let band = match self {
            SolverKind::Auto => BandPath::WhereNarrow,
            SolverKind::Sparse => BandPath::Never,
            SolverKind::Band => BandPath::Required,
        };
        SparseSettings {
            band,
            ..SparseSettings::default()
        }
    }
}

/// The solver a [`SolverKind`] names, analyzed on a pattern: a
/// [`SparseSolver`] with [`SolverKind::sparse_settings`].
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use softrod::linsolve::*;
/// // a chain closed into a ring: the band of 0–99 spans every row
/// let mut els: Vec<[usize; 2]> = (0..99).map(|e| [e, e + 1]).collect();
/// els.push([99, 0]);
/// let p = Arc::new(SymmetricPattern::from_elements(100, &els)?);
/// let mut k = SymmetricMatrix::zeros(p.clone());
/// for e in 0..els.len() {
///     k.add_element(e, &[1.0, -1.0, -1.0, 1.0])?;
/// }
/// k.add(0, 0, 1.0)?;
/// let mut solver = AutoSolver::analyze(&p)?;
/// assert_eq!(solver.kind(), SolverKind::Sparse); // not a narrow band
/// assert!(matches!(
///     AutoSolver::with_kind(&p, SolverKind::Band),
///     Err(LinsolveError::NotBanded { half_bandwidth: 99, .. })
/// ));
/// let mut x = vec![1.0; 100];
/// solver.factor(&k, FactorOptions::default())?.solve_in_place(&mut x)?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone)]
pub struct AutoSolver {
    solver: SparseSolver,
}

impl AutoSolver {
    /// Analyzes `pattern` with the solver `kind` asks for.
    ///
    /// # Errors
    /// As [`SparseSolver::with_settings`]: [`LinsolveError::NotBanded`] for
    /// [`SolverKind::Band`] and a pattern that is not a narrow band.
    ///
    /// # Example
    /// ```
    /// use std::sync::Arc;
    /// use softrod::linsolve::{AutoSolver, SolverKind, SymmetricPattern};
    /// let p = Arc::new(SymmetricPattern::from_elements(3, [[0, 1], [1, 2]])?);
    /// assert_eq!(AutoSolver::with_kind(&p, SolverKind::Auto)?.kind(), SolverKind::Band);
    /// assert_eq!(AutoSolver::with_kind(&p, SolverKind::Sparse)?.kind(), SolverKind::Sparse);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn with_kind(
        pattern: &Arc<SymmetricPattern>,
        kind: SolverKind,
    ) -> Result<Self, LinsolveError> {
        Ok(AutoSolver {
            solver: SparseSolver::with_settings(pattern, kind.sparse_settings())?,
        })
    }

    /// The path this solver takes (never [`SolverKind::Auto`]):
    /// [`SolverKind::Band`] when it factors by the band kernels,
    /// [`SolverKind::Sparse`] when by faer.
    pub fn kind(&self) -> SolverKind {
        match self.solver.band_half_width() {
            Some(_) => SolverKind::Band,
            None => SolverKind::Sparse,
        }
    }

    /// The sparse solver behind it.
    pub fn sparse(&self) -> &SparseSolver {
        &self.solver
    }
}

impl TangentSolver for AutoSolver {
    type Factors = AutoFactors;

    fn analyze(pattern: &Arc<SymmetricPattern>) -> Result<Self, LinsolveError> {
        Self::with_kind(pattern, SolverKind::Auto)
    }

    fn pattern(&self) -> &Arc<SymmetricPattern> {
        self.solver.pattern()
    }

    fn factor(
        &mut self,
        matrix: &SymmetricMatrix,
        options: FactorOptions,
    ) -> Result<AutoFactors, LinsolveError> {
        self.solver.factor(matrix, options)
    }
}

/// The factors of an [`AutoSolver`]: those of its [`SparseSolver`].
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use softrod::linsolve::*;
/// let p = Arc::new(SymmetricPattern::from_elements(2, [[0, 1]])?);
/// let mut k = SymmetricMatrix::zeros(p.clone());
/// k.add_element(0, &[2.0, 1.0, 1.0, 2.0])?;
/// let f: AutoFactors = AutoSolver::analyze(&p)?.factor(&k, FactorOptions::default())?;
/// assert!(f.is_banded() && f.is_positive_definite());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub type AutoFactors = SparseFactors;
