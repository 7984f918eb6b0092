//! The far start of a cold reduced solve: the sqp backend's full-space
//! iterations over `(q, F)` (see the [module documentation](super)).

use crate::observe::ObservationOperator;

use super::super::EstimationModel;
use super::super::driver::Method;
use super::super::problem::{Derivs, Problem};
use super::super::sqp::SqpEstimator;

/// The full-space iterations of a far start: from `(f, q)`, an
/// equilibrium, the estimate at `alpha` for `op` by the sqp backend's
/// iterations over `(q, F)`, whose iterates need not be equilibria; made
/// over a copy of the problem (its analyzed linear solver, its unloaded
/// start) the first time it is needed, kept in `inner`. Its converged
/// estimate, an equilibrium, with the iterations it took and its last
/// QP's factored tangent and derivatives when taken there (the reduced
/// iteration resumes from them without a factorization or adjoint solves),
/// if it converged below the objective `obj` at `(f, q)`; `None` otherwise
/// (the reduced iteration then backtracks on its own), and always on a
/// model without it ([`EstimationModel::FAR_START`]).
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
    inner: &mut Option<Box<SqpEstimator<M>>>,
    core: &Problem<M>,
    op: &ObservationOperator,
    f: &[f64],
    q: &[f64],
    alpha: f64,
    obj: f64,
) -> Option<FullSpace> {
    if !M::FAR_START {
        return None;
    }
    if inner.is_none() {
        // the same problem (its analysis, its unloaded start)
        *inner = Some(Box::new(SqpEstimator::over(core.clone()).ok()?));
    }
    let sqp = inner.as_mut()?;
    let s = Method::solve_one(sqp.as_mut(), op, f.to_vec(), q.to_vec(), alpha).ok()?;
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
