//! The two places the controller reaches into the sensitivity and
//! estimator machinery; kept here, small, so that a change of how those are
//! constructed touches one function each.

use nalgebra::DMatrix;

use crate::error::Result;
use crate::estimate::{
    Backend, EstimationModel, Estimator, EstimatorSettings, NewtonEstimator, SqpEstimator,
};
use crate::linsolve::{AutoSolver, FactorOptions, SolverKind, SymmetricMatrix, TangentSolver};
use crate::sensitivity::Sensitivity;
use crate::statics::{Tracker, WarmCounts, WarmStrategy};
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
pub(crate) enum LoopEstimator<M: EstimationModel> {
    /// The reduced Gauss–Newton backend.
    Newton(Box<NewtonEstimator<M>>),
    /// The SQP backend.
    Sqp(Box<SqpEstimator<M>>),
}

impl<M: EstimationModel> LoopEstimator<M> {
    /// The estimator as the trait object.
    pub(crate) fn as_dyn(&mut self) -> &mut dyn Estimator<M::Loads> {
        match self {
            LoopEstimator::Newton(e) => e.as_mut(),
            LoopEstimator::Sqp(e) => e.as_mut(),
        }
    }

    /// What its equilibria cost so far.
    pub(crate) fn counts(&self) -> WarmCounts {
        match self {
            LoopEstimator::Newton(e) => e.counts(),
            LoopEstimator::Sqp(e) => e.counts(),
        }
    }

    /// The warm tracker of its equilibria.
    pub(crate) fn tracker_mut(&mut self) -> &mut Tracker<M> {
        match self {
            LoopEstimator::Newton(e) => e.tracker_mut(),
            LoopEstimator::Sqp(e) => e.tracker_mut(),
        }
    }
}

/// The estimator of `settings.backend` for `model` under the known loads
/// `known` at the chamber pressures `pressures_pa`, its equilibria by the
/// warm strategy `corrector` (`None`: the estimator's own).
///
/// The loop builds it once and replaces its known pressures each step with
/// [`Estimator::set_known_loads`], keeping the warm start `(F, q)` and `α`.
pub(crate) fn estimator_at<M: Actuated + EstimationModel>(
    model: &M,
    known: &M::Loads,
    pressures_pa: &[f64],
    settings: &EstimatorSettings,
    corrector: Option<WarmStrategy>,
) -> Result<LoopEstimator<M>> {
    let loads = model.with_pressures(known, pressures_pa);
    let mut e = match settings.backend {
        Backend::Newton => {
            LoopEstimator::Newton(Box::new(NewtonEstimator::new(model, &loads, settings)?))
        }
        Backend::Sqp => LoopEstimator::Sqp(Box::new(SqpEstimator::new(model, &loads, settings)?)),
    };
    if let Some(strategy) = corrector {
        e.tracker_mut().set_strategy(strategy)?;
    }
    Ok(e)
}
