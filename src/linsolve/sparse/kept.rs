//! The symbolic analyses a thread made last, kept for the solvers analyzed
//! after them on the same sparsity pattern.

use std::cell::RefCell;
use std::sync::Arc;

use faer::sparse::linalg::cholesky::SymbolicCholesky;

use super::{Permuted, SparseSettings};
use crate::linsolve::SymmetricPattern;

/// How many symbolic analyses each thread keeps ([`super::SparseSolver::with_settings`]).
const ANALYSES_KEPT: usize = 8;

/// One symbolic analysis kept for reuse: the pattern it was made of, its
/// settings and its products.
pub(super) struct Analysis {
    pub(super) pattern: Arc<SymmetricPattern>,
    pub(super) settings: SparseSettings,
    pub(super) symbolic: Arc<SymbolicCholesky<usize>>,
    pub(super) perm: Arc<Permuted>,
}

thread_local! {
    /// The analyses made last on this thread, most recent first: the
    /// analysis depends only on the pattern (the mesh) and the settings, and
    /// a solver analyzed per solve (a cold static solve, a fresh estimator)
    /// then costs no more than a lookup. The first entries of a pattern of
    /// 1 000 elements cost as much as its first factorizations.
    static ANALYSES: RefCell<Vec<Analysis>> = const { RefCell::new(Vec::new()) };
}

/// The kept analysis of `pattern` (the same one or an equal sparsity
/// structure) with `settings`, if any, moved to the front.
pub(super) fn kept_analysis(
    pattern: &Arc<SymmetricPattern>,
    settings: SparseSettings,
) -> Option<(Arc<SymbolicCholesky<usize>>, Arc<Permuted>)> {
    ANALYSES
        .try_with(|cell| {
            let mut kept = cell.try_borrow_mut().ok()?;
            let at = kept.iter().position(|a| {
                a.settings == settings
                    && (Arc::ptr_eq(&a.pattern, pattern)
                        || (a.pattern.n() == pattern.n()
                            && a.pattern.col_ptr() == pattern.col_ptr()
                            && a.pattern.row_idx() == pattern.row_idx()))
            })?;
            let a = kept.remove(at);
            let found = (a.symbolic.clone(), a.perm.clone());
            kept.insert(0, a);
            Some(found)
        })
        .ok()
        .flatten()
}

/// Keeps an analysis (dropping the least recently used past
/// [`ANALYSES_KEPT`]).
pub(super) fn keep_analysis(analysis: Analysis) {
    let _ = ANALYSES.try_with(|cell| {
        if let Ok(mut kept) = cell.try_borrow_mut() {
            kept.insert(0, analysis);
            kept.truncate(ANALYSES_KEPT);
        }
    });
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use std::sync::Arc;

    use crate::linsolve::{SparseSolver, SymmetricPattern, TangentSolver};

    fn chain(n: usize) -> Arc<SymmetricPattern> {
        let els: Vec<[usize; 2]> = (0..n - 1).map(|e| [e, e + 1]).collect();
        Arc::new(SymmetricPattern::from_elements(n, &els).unwrap())
    }

    /// A second solver of the same pattern, and of an equal pattern built
    /// anew (a coarse mesh rebuilt per solve), shares the first one's
    /// analysis; another pattern gets its own.
    #[test]
    fn an_equal_pattern_reuses_the_analysis_and_another_does_not() {
        let (p, q, other) = (chain(50), chain(50), chain(51));
        let a = SparseSolver::analyze(&p).unwrap();
        let b = SparseSolver::analyze(&p).unwrap();
        let c = SparseSolver::analyze(&q).unwrap();
        let d = SparseSolver::analyze(&other).unwrap();
        assert!(Arc::ptr_eq(&a.symbolic, &b.symbolic) && Arc::ptr_eq(&a.perm, &b.perm));
        assert!(Arc::ptr_eq(&a.symbolic, &c.symbolic));
        assert!(
            Arc::ptr_eq(c.pattern(), &q),
            "the solver keeps its caller's pattern"
        );
        assert!(!Arc::ptr_eq(&a.symbolic, &d.symbolic));
        assert_eq!(d.pattern().n(), 51);
    }

    /// Only the last `ANALYSES_KEPT` patterns are kept.
    #[test]
    fn the_least_recently_used_analysis_is_dropped() {
        let first = chain(30);
        let a = SparseSolver::analyze(&first).unwrap();
        for n in 31..31 + super::ANALYSES_KEPT {
            SparseSolver::analyze(&chain(n)).unwrap();
        }
        let again = SparseSolver::analyze(&first).unwrap();
        assert!(!Arc::ptr_eq(&a.symbolic, &again.symbolic));
    }
}
