//! The factors of the sparse solver: the numeric factorization and its
//! solves (permuted, scaled, one sweep for many right-hand sides).

use std::sync::Arc;

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::perm::PermRef;
use faer::sparse::linalg::cholesky::simplicial::{SimplicialLdltRef, SimplicialLltRef};
use faer::sparse::linalg::cholesky::{LdltRef, LltRef, SymbolicCholesky, SymbolicCholeskyRaw};
use faer::sparse::linalg::lu::simplicial::{
    SimplicialLu, solve_in_place_scratch as lu_solve_scratch,
};
use faer::{Conj, MatMut, Par};

use super::Permuted;
use super::band::BandFactors;
use super::band_lu::BandLu;
use crate::linsolve::{FactorMethod, Factorization, Inertia, LinsolveError, check_rhs};

/// The numeric factors.
#[derive(Debug, Clone)]
pub(super) enum Numeric {
    /// The band `L D Lᵀ` in the natural order (`scaling` then in the
    /// natural order too).
    Band(BandFactors),
    /// The band LU with partial pivoting, natural order (`band_lu.rs`).
    BandLu(BandLu),
    Llt(Vec<f64>),
    Ldlt(Vec<f64>),
    Lu {
        lu: SimplicialLu<usize, f64>,
        row_fwd: Vec<usize>,
        row_inv: Vec<usize>,
    },
}

/// The factors `SparseSolver` returns (see [`Factorization`]).
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
    pub(super) n: usize,
    pub(super) symbolic: Arc<SymbolicCholesky<usize>>,
    pub(super) perm: Arc<Permuted>,
    pub(super) numeric: Numeric,
    /// The Jacobi scaling in the permuted order.
    pub(super) scaling: Arc<Vec<f64>>,
    pub(super) inertia: Option<Inertia>,
    pub(super) min_pivot: f64,
}

impl SparseFactors {
    /// Whether the band kernels factored the matrix (the band path of
    /// [`crate::linsolve::sparse`]: band `L D Lᵀ` or band LU in the dofs'
    /// own order), not faer.
    ///
    /// # Example
    /// ```
    /// use std::sync::Arc;
    /// use softrod::linsolve::*;
    /// let p = Arc::new(SymmetricPattern::from_elements(2, [[0, 1]])?);
    /// let mut k = SymmetricMatrix::zeros(p.clone());
    /// k.add_element(0, &[2.0, 1.0, 1.0, 2.0])?;
    /// let band = AutoSolver::with_kind(&p, SolverKind::Auto)?.factor(&k, FactorOptions::default())?;
    /// let faer = AutoSolver::with_kind(&p, SolverKind::Sparse)?.factor(&k, FactorOptions::default())?;
    /// assert!(band.is_banded() && !faer.is_banded());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn is_banded(&self) -> bool {
        matches!(self.numeric, Numeric::Band(_) | Numeric::BandLu(_))
    }

    /// The solve for `k >= 1` column-major right-hand sides (sizes checked):
    /// permuted and scaled into a workspace (kept per thread, so repeated
    /// solves do not allocate), solved there, back.
    fn solve_cols(&self, b: &mut [f64], k: usize) -> Result<(), LinsolveError> {
        thread_local! {
            static SCRATCH: std::cell::RefCell<Vec<f64>> = const { std::cell::RefCell::new(Vec::new()) };
        }
        let kept = SCRATCH.try_with(|cell| match cell.try_borrow_mut() {
            Ok(mut x) => Some(self.solve_cols_with(b, k, &mut x)),
            Err(_) => None,
        });
        match kept {
            Ok(Some(result)) => result,
            _ => self.solve_cols_with(b, k, &mut Vec::new()),
        }
    }

    /// [`SparseFactors::solve_cols`] with the workspace `x`.
    fn solve_cols_with(
        &self,
        b: &mut [f64],
        k: usize,
        x: &mut Vec<f64>,
    ) -> Result<(), LinsolveError> {
        let n = self.n;
        if let Numeric::Band(_) | Numeric::BandLu(_) = &self.numeric {
            // natural order: no permutation, no workspace
            for bc in b.chunks_exact_mut(n) {
                bc.iter_mut()
                    .zip(self.scaling.iter())
                    .for_each(|(v, d)| *v *= d);
                match &self.numeric {
                    Numeric::Band(f) => f.solve_in_place(bc),
                    Numeric::BandLu(f) => f.solve_in_place(bc),
                    _ => {}
                }
                bc.iter_mut()
                    .zip(self.scaling.iter())
                    .for_each(|(v, d)| *v *= d);
            }
            return Ok(());
        }
        let fwd = &self.perm.fwd;
        x.clear();
        x.try_reserve(n * k)
            .map_err(|_| LinsolveError::OutOfMemory)?;
        for bc in b.chunks_exact(n) {
            x.extend(fwd.iter().zip(self.scaling.iter()).map(|(&i, d)| bc[i] * d));
        }
        let rhs = MatMut::from_column_major_slice_mut(&mut x[..], n, k);
        match (&self.numeric, self.symbolic.raw()) {
            // solved above, in the natural order
            (Numeric::Band(_) | Numeric::BandLu(_), _) => {}
            // the simplicial factors solve in place without a workspace
            (Numeric::Llt(values), SymbolicCholeskyRaw::Simplicial(s)) => {
                SimplicialLltRef::new(s, values).solve_in_place_with_conj(
                    Conj::No,
                    rhs,
                    Par::Seq,
                    MemStack::new(&mut []),
                );
            }
            (Numeric::Ldlt(values), SymbolicCholeskyRaw::Simplicial(s)) => {
                SimplicialLdltRef::new(s, values).solve_in_place_with_conj(
                    Conj::No,
                    rhs,
                    Par::Seq,
                    MemStack::new(&mut []),
                );
            }
            (Numeric::Llt(values), _) => {
                let req = self.symbolic.solve_in_place_scratch::<f64>(k, Par::Seq);
                let mut mem = MemBuffer::try_new(req).map_err(|_| LinsolveError::OutOfMemory)?;
                LltRef::new(&self.symbolic, values).solve_in_place_with_conj(
                    Conj::No,
                    rhs,
                    Par::Seq,
                    MemStack::new(&mut mem),
                );
            }
            (Numeric::Ldlt(values), _) => {
                let req = self.symbolic.solve_in_place_scratch::<f64>(k, Par::Seq);
                let mut mem = MemBuffer::try_new(req).map_err(|_| LinsolveError::OutOfMemory)?;
                LdltRef::new(&self.symbolic, values).solve_in_place_with_conj(
                    Conj::No,
                    rhs,
                    Par::Seq,
                    MemStack::new(&mut mem),
                );
            }
            (
                Numeric::Lu {
                    lu,
                    row_fwd,
                    row_inv,
                },
                _,
            ) => {
                let req = lu_solve_scratch::<usize, f64>(n, k, Par::Seq);
                let mut mem = MemBuffer::try_new(req).map_err(|_| LinsolveError::OutOfMemory)?;
                let id = &self.perm.identity;
                let row_perm = PermRef::new_checked(row_fwd, row_inv, n);
                let col_perm = PermRef::new_checked(id, id, n);
                lu.solve_in_place_with_conj(
                    row_perm,
                    col_perm,
                    Conj::No,
                    rhs,
                    Par::Seq,
                    MemStack::new(&mut mem),
                );
            }
        }
        for (xc, bc) in x.chunks_exact(n).zip(b.chunks_exact_mut(n)) {
            for ((xi, &i), d) in xc.iter().zip(fwd).zip(self.scaling.iter()) {
                bc[i] = xi * d;
            }
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
            Numeric::Ldlt(_) | Numeric::Band(_) => FactorMethod::Ldlt,
            Numeric::Lu { .. } | Numeric::BandLu(_) => FactorMethod::Lu,
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
        super::super::work::count_solves(nrhs);
        self.solve_cols(b, nrhs)
    }
}
