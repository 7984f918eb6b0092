//! The two forms of the Gauss–Newton system (30) and which one a
//! linearization is solved in, so that the work is linear in the markers.
//!
//! With `m = n_ob` observed components and `n_F` load parameters the same
//! system has two forms:
//!
//! - **primal**: `N = Jᵀ W J + α H` (`n_F × n_F`), formed by accumulating
//!   the weighted marker rows, `O(m n_F² + n_F³)`;
//! - **representer** (distributed load, `J = Zᵀ B`, `H = B`):
//!   `S = α W⁻¹ + Zᵀ B Z` (`m × m`), `O(m² n_F + m³)`, no `n_F³` work.
//!
//! They are the same linear algebra (Woodbury; Sylvester for the
//! determinants, see [`super::evidence`]). The problem takes the smaller:
//! the representer form while `m ≤ n_F` (few markers on a fine mesh, as
//! before), the primal one beyond (many markers), so a step's dense work is
//! `O(min(m, n_F)² max(m, n_F))`, linear in `m` at a given mesh. A
//! concentrated force (`n_F = DIM`, `H = I`) is always primal. Nothing of
//! size `m × m` is formed in the primal form.
//!
//! The dense work is counted (flops of forming and factoring the systems,
//! per thread) so tests hold the estimator to its cost without timing it.

use std::cell::Cell;
use std::sync::Arc;

use nalgebra::{Cholesky, DMatrix, Dyn};

thread_local! {
    static DENSE_FLOPS: Cell<u64> = const { Cell::new(0) };
}

/// Counts `flops` of dense work in the estimator's systems.
pub(crate) fn count_dense(flops: usize) {
    let _ = DENSE_FLOPS.try_with(|c| c.set(c.get().wrapping_add(flops as u64)));
}

/// The dense work of this thread since it started (flops counted by
/// [`count_dense`]).
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) fn dense_work() -> u64 {
    DENSE_FLOPS.try_with(Cell::get).unwrap_or(0)
}

/// The dense penalty matrix `H` (`n_F × n_F`, symmetric positive definite)
/// of the primal form and `log det H`.
#[derive(Debug, Clone)]
pub(crate) struct PenaltyMatrix {
    /// `H`.
    pub(crate) h: DMatrix<f64>,
    /// `log det H`.
    pub(crate) log_det: f64,
}

impl PenaltyMatrix {
    /// `H` and its log-determinant; `None` unless it is positive definite
    /// (the full 3-D element's load Gram matrix is singular on the node
    /// numbers no load is made of: that load stays in the representer form).
    pub(crate) fn new(h: DMatrix<f64>) -> Option<Self> {
        let chol = h.clone().cholesky()?;
        let log_det = 2.0
            * chol
                .l_dirty()
                .diagonal()
                .iter()
                .map(|v| v.ln())
                .sum::<f64>();
        log_det.is_finite().then_some(PenaltyMatrix { h, log_det })
    }
}

/// The form a Gauss–Newton system is solved in (see the module docs).
#[derive(Debug, Clone)]
pub(crate) enum GnForm {
    /// `S = α W⁻¹ + Zᵀ B Z` (`n_ob × n_ob`), the distributed load.
    Representer,
    /// `N = Jᵀ W J + α H` (`n_F × n_F`) with the dense `H`.
    Primal(Arc<PenaltyMatrix>),
}

/// The factor of `N = Jᵀ W J + α H` from the marker Jacobian transposed
/// `jt` (`Jᵀ`, one column per observed component) and weights `w`: the weighted marker rows accumulated into the
/// `n_F × n_F` matrix (one product), then a Cholesky factorization with the
/// jitter of [`jittered_cholesky`]. `None` if it cannot be factored.
pub(crate) fn primal_system(
    jt: &DMatrix<f64>,
    w: &[f64],
    alpha: f64,
    h: &PenaltyMatrix,
) -> Option<Cholesky<f64, Dyn>> {
    let (nf, m) = jt.shape();
    let mut n = weighted_columns(jt, w) * jt.transpose();
    n.zip_apply(&h.h, |a, b| *a += alpha * b);
    count_dense(m * nf * nf + nf * nf * nf / 3);
    jittered_cholesky(n)
}

/// `J W`: the columns of `jt` scaled by the weights.
pub(crate) fn weighted_columns(jt: &DMatrix<f64>, w: &[f64]) -> DMatrix<f64> {
    let mut jw = jt.clone();
    for (mut col, wi) in jw.column_iter_mut().zip(w) {
        col *= *wi;
    }
    jw
}

/// `A = L Lᵀ` of a small dense symmetric matrix (only its lower triangle is
/// read), with a diagonal jitter of 1e-14 … 1e-10 of the largest diagonal
/// entry if the plain factorization fails (nearly redundant markers);
/// `None` if that does not help either.
pub(crate) fn jittered_cholesky(a: DMatrix<f64>) -> Option<Cholesky<f64, Dyn>> {
    let m = a.nrows();
    let dmax = (0..m).fold(0.0f64, |x, i| x.max(a[(i, i)].abs()));
    for jitter in [0.0, 1e-14, 1e-12, 1e-10] {
        let mut l = a.clone();
        for i in 0..m {
            l[(i, i)] += jitter * dmax;
        }
        if let Some(c) = l.cholesky()
            && c.l_dirty().diagonal().iter().all(|v| v.is_finite())
        {
            return Some(c);
        }
    }
    None
}
