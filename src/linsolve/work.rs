//! Counts of the linear solvers' work on the calling thread: how many
//! tangents were factored and how many right-hand sides were solved. The
//! estimators report the difference over a step
//! ([`crate::estimate::EstimateReport::linear_work`]), so tests can hold a
//! method to its cost without timing it.

use std::cell::Cell;

use serde::{Deserialize, Serialize};

thread_local! {
    static FACTORIZATIONS: Cell<usize> = const { Cell::new(0) };
    static SOLVES: Cell<usize> = const { Cell::new(0) };
}

/// Factorizations and solved right-hand sides, counted on one thread.
///
/// # Example
/// ```
/// use std::sync::Arc;
/// use softrod::linsolve::*;
/// let p = Arc::new(SymmetricPattern::from_elements(2, [[0, 1]])?);
/// let mut k = SymmetricMatrix::zeros(p.clone());
/// k.add_element(0, &[2.0, 1.0, 1.0, 2.0])?;
/// let before = LinearWork::now();
/// let f = AutoSolver::analyze(&p)?.factor(&k, FactorOptions::default())?;
/// let mut b = vec![1.0; 2 * 3];
/// f.solve_columns_in_place(&mut b, 3)?;
/// let done = LinearWork::now().since(before);
/// assert_eq!(done, LinearWork { factorizations: 1, solves: 3 });
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct LinearWork {
    /// Numeric factorizations of a tangent (an `L D Lᵀ` and its pivoted LU
    /// fallback count as one).
    pub factorizations: usize,
    /// Right-hand sides solved with some factors (a solve of `k` columns
    /// counts `k`).
    pub solves: usize,
}

impl LinearWork {
    /// The counts of this thread since it started.
    pub fn now() -> Self {
        LinearWork {
            factorizations: FACTORIZATIONS.try_with(Cell::get).unwrap_or(0),
            solves: SOLVES.try_with(Cell::get).unwrap_or(0),
        }
    }

    /// The work done between `earlier` and `self` (both of
    /// [`LinearWork::now`] on the same thread).
    pub fn since(self, earlier: LinearWork) -> Self {
        LinearWork {
            factorizations: self.factorizations.saturating_sub(earlier.factorizations),
            solves: self.solves.saturating_sub(earlier.solves),
        }
    }
}

/// Counts one factorization.
pub(crate) fn count_factorization() {
    let _ = FACTORIZATIONS.try_with(|c| c.set(c.get().wrapping_add(1)));
}

/// Counts `k` solved right-hand sides.
pub(crate) fn count_solves(k: usize) {
    let _ = SOLVES.try_with(|c| c.set(c.get().wrapping_add(k)));
}
