//! The two places the controller reaches into the sensitivity and
//! estimator machinery; kept here, small, so that a change of how those are
//! constructed touches one function each.

use nalgebra::DMatrix;

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::Result;
use crate::estimate::{Backend, Estimator, EstimatorSettings, NewtonEstimator, SqpEstimator};
use crate::linsolve::{AutoSolver, FactorOptions, SolverKind, SymmetricMatrix, TangentSolver};
use crate::loads::Loads;
use crate::sensitivity::Sensitivity;
use crate::structure::Actuated;

/// (43) `∂q/∂P = −(∂Q/∂q)⁻¹ ∂Q/∂P` (`n_q × n_pressures`, m/Pa) at the
/// equilibrium `q` of `model` under `loads` (whose pressures and load field
/// enter the tangent).
pub(crate) fn dq_dp<M: Actuated>(model: &M, loads: &M::Loads, q: &[f64]) -> Result<DMatrix<f64>> {
    let mut solver = AutoSolver::with_kind(&model.tangent_pattern()?, SolverKind::Auto)?;
    let u = model.free_coordinates_of(q)?;
    let dead = model.dead_force(loads)?;
    let mut k = SymmetricMatrix::zeros(model.tangent_pattern()?);
    model.tangent_into(u.as_slice(), q, dead.as_slice(), loads, &mut k)?;
    let factors = solver.factor(&k, FactorOptions::default())?;
    Sensitivity::at(model, u.as_slice(), &factors)?.dq_dp(q)
}

/// The loop's estimator: a concrete backend (not a `Box<dyn Estimator>`)
/// so that a loop, warm start included, can be cloned: a benchmark restores
/// the same state for every measured step, a sweep branches one settled loop.
#[derive(Debug, Clone)]
pub(crate) enum LoopEstimator<E: Element> {
    /// The reduced Gauss–Newton backend.
    Newton(Box<NewtonEstimator<Robot<E>>>),
    /// The SQP backend.
    Sqp(Box<SqpEstimator<Robot<E>>>),
}

impl<E: Element + 'static> LoopEstimator<E> {
    /// The estimator as the trait object.
    pub(crate) fn as_dyn(&mut self) -> &mut dyn Estimator {
        match self {
            LoopEstimator::Newton(e) => e.as_mut(),
            LoopEstimator::Sqp(e) => e.as_mut(),
        }
    }
}

/// The estimator of `settings.backend` for `robot` under the known loads
/// `known` at the chamber pressures `pressures_pa`.
///
/// The loop builds it once and replaces its known pressures each step with
/// [`Estimator::set_known_loads`], keeping the warm start `(F, q)` and `α`.
pub(crate) fn estimator_at<E: Element + 'static>(
    robot: &Robot<E>,
    known: &Loads,
    pressures_pa: &[f64],
    settings: &EstimatorSettings,
) -> Result<LoopEstimator<E>> {
    let mut loads = known.clone();
    loads.pressures_pa = pressures_pa.to_vec();
    Ok(match settings.backend {
        Backend::Newton => {
            LoopEstimator::Newton(Box::new(NewtonEstimator::new(robot, &loads, settings)?))
        }
        Backend::Sqp => LoopEstimator::Sqp(Box::new(SqpEstimator::new(robot, &loads, settings)?)),
    })
}
