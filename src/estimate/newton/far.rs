//! The far start of a cold reduced solve: the sqp backend's full-space
//! iterations over `(q, F)` (see the [module documentation](super)).

use crate::error::Result;
use crate::observe::ObservationOperator;
use crate::statics::tracker::FactoredTangent;

use super::super::EstimationModel;
use super::super::driver::{Method, Solved};
use super::super::problem::{Derivs, Problem};
use super::super::sqp::SqpEstimator;

/// The full-space iterations over `(q, F)` a far start runs on a model (the
/// sqp backend's, on the clamped robot; a model without them has no far
/// start and its reduced iteration backtracks on its own).
pub trait FullSpaceSolve<M: EstimationModel>: std::fmt::Debug + Send + Sync {
    /// One solve from `(f0, q0)` at `alpha` for `op`.
    fn solve_one(
        &mut self,
        op: &ObservationOperator,
        f0: Vec<f64>,
        q0: Vec<f64>,
        alpha: f64,
    ) -> Result<Solved>;
    /// The last QP's factored tangent and derivatives, if taken at `q`.
    fn take_final_qp(
        &mut self,
        q: &[f64],
        op: &ObservationOperator,
    ) -> Option<(FactoredTangent, Derivs)>;
    /// A copy (the estimator is `Clone`).
    fn boxed_clone(&self) -> Box<dyn FullSpaceSolve<M>>;
}

/// The full-space iterations of a far start, once made.
#[derive(Debug)]
pub(crate) struct FullSpaceBox<M: EstimationModel>(pub(crate) Box<dyn FullSpaceSolve<M>>);

impl<M: EstimationModel> Clone for FullSpaceBox<M> {
    fn clone(&self) -> Self {
        FullSpaceBox(self.0.boxed_clone())
    }
}

impl<M: EstimationModel> FullSpaceSolve<M> for SqpEstimator<M> {
    fn solve_one(
        &mut self,
        op: &ObservationOperator,
        f0: Vec<f64>,
        q0: Vec<f64>,
        alpha: f64,
    ) -> Result<Solved> {
        Method::solve_one(self, op, f0, q0, alpha)
    }

    fn take_final_qp(
        &mut self,
        q: &[f64],
        op: &ObservationOperator,
    ) -> Option<(FactoredTangent, Derivs)> {
        SqpEstimator::take_final_qp(self, q, op)
    }

    fn boxed_clone(&self) -> Box<dyn FullSpaceSolve<M>> {
        Box::new(self.clone())
    }
}

/// The sqp backend's full-space iterations over a copy of `problem`.
pub(crate) fn sqp_full_space<M: EstimationModel>(
    problem: &Problem<M>,
) -> Option<Box<dyn FullSpaceSolve<M>>> {
    let sqp = SqpEstimator::over(problem.clone()).ok()?;
    Some(Box::new(sqp))
}

/// The full-space iterations of a far start: from `(f, q)`, an
/// equilibrium, the estimate at `alpha` for `op` by the sqp backend's
/// iterations over `(q, F)`, whose iterates need not be equilibria; made
/// over a copy of the problem (its analyzed linear solver, its unloaded
/// start) the first time it is needed, kept in `inner`. Its converged
/// estimate, an equilibrium, with the iterations it took and its last
/// QP's factored tangent and derivatives when taken there (the reduced
/// iteration resumes from them without a factorization or adjoint solves),
/// if it converged below the objective `obj` at `(f, q)`; `None` otherwise
/// (the reduced iteration then backtracks on its own).
///
/// It is taken as soon as the trust region cuts a step of a cold solve,
/// without trying the reduced step's equilibrium first: that trial (chord
/// and plain Newton steps from the linearized prediction) failed on every
/// large deflection measured and cost factorizations of its own.
///
/// Why: far from the solution (the first estimate of a large deflection,
/// from the unloaded shape) a step of the reduced method needs the
/// equilibrium at every trial load. A full trust-region step (2 cm of
/// predicted node motion) leaves its linearized prediction off the
/// equilibrium by second-order terms (1.9 N on the 0.24 m exudyn cable
/// under 3 × its self-weight) from which plain Newton steps diverge, so
/// the line search halved down to 1/16 of the step, 1–2 mm of motion, and
/// each accepted trial converged a static solve of 4–6 factorizations: 19
/// iterations and 213 factorizations where the full-space iterations,
/// which restore the equilibrium in the same linear solve as the step,
/// take 7 iterations of one factorization each.
pub(super) fn full_space<M: EstimationModel>(
    inner: &mut Option<FullSpaceBox<M>>,
    core: &Problem<M>,
    op: &ObservationOperator,
    f: &[f64],
    q: &[f64],
    alpha: f64,
    obj: f64,
) -> Option<FullSpace> {
    if inner.is_none() {
        // the same problem (its analysis, its unloaded start)
        *inner = Some(FullSpaceBox(M::full_space(core)?));
    }
    let sqp = &mut inner.as_mut()?.0;
    let s = sqp.solve_one(op, f.to_vec(), q.to_vec(), alpha).ok()?;
    if !(s.report.status.is_converged() && s.report.objective < obj) {
        return None;
    }
    let last = sqp.take_final_qp(&s.q, op);
    Some((s.f, s.q, s.report.iterations, last))
}

/// A converged run of the full-space iterations: the load, the shape, the
/// iterations, and the last QP's factored tangent and derivatives when they
/// were taken at that shape.
type FullSpace = (
    Vec<f64>,
    Vec<f64>,
    usize,
    Option<(crate::statics::tracker::FactoredTangent, Derivs)>,
);
