//! The reduced Gauss–Newton estimator (27)–(30).
//!
//! `q = q(F)` by the static solve (warm-started from the previous iterate),
//! so the problem is unconstrained in `F`:
//! `J(F) = (A q(F) − y)ᵀ W (A q(F) − y) + α Fᵀ H F`.
//!
//! - Sensitivity (28): `∂u/∂F = K⁻¹ Mᵀ G` over the free coordinates `u`
//!   (`K = −∂Q/∂q` restricted with [`crate::assembly::Robot::restrict`], `G = J_QF`). The
//!   marker Jacobian `J = A M K⁻¹ Mᵀ G` is formed row by row by adjoint
//!   solves, `z_i = M K⁻¹ Mᵀ a_iᵀ`, `J_i = Gᵀ z_i` (K is symmetric): `n_ob`
//!   solves with one factorization of `K` per iteration.
//! - Gradient (29): `g = 2 (Jᵀ W e + α H F)`, `e = A q − y`.
//! - Gauss–Newton Hessian (30): `2 (Jᵀ W J + α H)`. For the distributed
//!   load (`G = H = B`) the step is solved in the representer form
//!   `F + dF = Σ_i c_i z_i`, `(α W⁻¹ + Zᵀ B Z) c = J F − e`: a Cholesky of an
//!   `n_ob × n_ob` matrix, nothing of size `n_q³`, while the observed
//!   components are at most `n_F`; beyond, `Jᵀ W J + α B` itself, accumulated
//!   over the marker rows (`n_F × n_F`): the work is linear in the markers
//!   (`estimate::gn_form`).
//! - Globalization: Armijo backtracking on `J`, each trial a warm static solve
//!   from the linearized prediction `q + t M K⁻¹ Mᵀ G dF` (chord steps with
//!   the last factorization of `K`, then one fresh factorization at the
//!   solution, which the next iteration's adjoint solves use). A trial
//!   below `t = 0.01` whose warm solve fails may run the globalized static
//!   solve, once per solve (`reduced::LINE_SEARCH_FALLBACKS`); a trial that
//!   needs another ends the solve as `line_search_failed`.
//! - Far starts of a cold estimate: when the trust region binds (the
//!   step's predicted node motion is cut to `max_observation_jump_m`),
//!   the reduced method would need many short steps, each a static solve of
//!   several factorizations (the first estimate of a large deflection from
//!   the unloaded shape). The solve then continues with the full-space
//!   iterations of the sqp backend over `(q, F)`, whose iterates need not
//!   be equilibria (one factorization each), and the reduced iteration
//!   resumes at their converged equilibrium, where it confirms convergence
//!   by its own test. Only while the stream has no estimate yet (a warm
//!   step never takes it), and a solve through it that does not converge
//!   is repeated without it: the result is never worse than the reduced
//!   iteration's alone.
//! - A warm step of a stream (a new frame near the last) typically takes
//!   one step from the cached derivatives at the last estimate, one
//!   factorization and one set of adjoint solves at the new point, which
//!   the statistical test accepts: about one exact linearization.
//! - Convergence: the predicted decrease `dec = −½ gᵀ dF = dFᵀ N dF`
//!   (`N = JᵀWJ + αH`) below `κ²`, `κ = statistical_tolerance` (the next
//!   step would move the estimate by less than `κ` of its own standard
//!   deviation, see [`EstimatorSettings::statistical_tolerance`]), or below
//!   `tolerance × max(J, n_ob)` (the tight test). Gauss–Newton converges here at least
//!   quadratically near the solution (the predicted decreases of a warm
//!   step run like 1e-1, 1e-6, 1e-13, 1e-18 relative), so when the decrease
//!   predicted after the current step, `dec²/dec_prev`, is below
//!   `1e-3 ×` the threshold, that step is the last: it is taken (its
//!   equilibrium by chord steps, without a new factorization) and the
//!   estimate returned without a further linearization to confirm it. It
//!   is the iterate the confirming iteration would accept; the gradient
//!   norm and the covariances are those of the linearization before the
//!   step.
//! - Warm start from the last `F*` and shape, with the derivatives there
//!   when they are known; a large jump of the markers is taken through
//!   intermediate observations.

pub(crate) mod far;
mod reduced;

use super::EstimationModel;
use crate::error::Result;
use crate::linsolve::AutoFactors;
use crate::observe::{ObsRow, ObservationOperator};
use crate::statics::{WarmCounts, WarmStrategy};
use nalgebra::{DMatrix, DVector};

use super::driver::{Method, Solved, Stream, run_step};
use super::problem::{Derivs, GnFactor, Problem};
use super::{Backend, Estimate, Estimator, EstimatorSettings, FarStart, Observation};

/// The derivatives at a shape `q` (first), with the Gauss–Newton factor
/// formed from them for the observation weights it holds, if any.
type DerivsCache = (Vec<f64>, Derivs, Option<(Vec<f64>, GnFactor)>);

/// The reduced Gauss–Newton estimator (backend "newton").
///
/// # Example
/// ```
/// use softrod::estimate::{Estimator, EstimatorSettings, NewtonEstimator, Observation};
/// use softrod::{scene::Scene, statics::StaticSolver};
/// let scene = Scene::two_section();
/// let (robot, loads) = (scene.robot()?, scene.loads()?);
/// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
/// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[4, 8, 12, 16, 20])?.with_noise(1e-5, 1);
/// let mut est = NewtonEstimator::new(&robot, &loads, &EstimatorSettings::default())?;
/// let e = est.step(&obs)?; // α by the discrepancy principle
/// assert!(e.report.status.is_converged());
/// let again = est.step(&obs)?; // warm: converges at once
/// assert!(again.report.iterations <= 2);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct NewtonEstimator<M: EstimationModel> {
    stream: Stream<M>,
    /// The derivatives at the last converged estimate's shape for the
    /// observation rows `cache_rows`: a warm step's first iteration starts
    /// there.
    derivs_cache: Option<DerivsCache>,
    /// The observation rows of `derivs_cache` (kept between steps: a
    /// stream's frames share them).
    cache_rows: Vec<ObsRow>,
    /// The last estimate `F` and `H F` there: a warm step's first
    /// objective starts at that `F`.
    hf_cache: Option<(Vec<f64>, Vec<f64>)>,
    /// The full-space iterations of a far start (made when first needed;
    /// see [`full_space`]).
    full_space: Option<Box<super::sqp::SqpEstimator<M>>>,
    /// The far starts of the solves since the driver last took the log.
    far_log: FarStart,
}

impl<M: EstimationModel> NewtonEstimator<M> {
    /// The estimation problem (tests set its Gauss–Newton form).
    #[cfg(test)]
    pub(crate) fn problem_mut(&mut self) -> &mut super::problem::Problem<M> {
        &mut self.stream.problem
    }

    /// An estimator for `robot` under the known loads `known` (both
    /// borrowed; the estimator keeps copies). `settings.backend` must be
    /// [`super::Backend::Newton`]: the backend is chosen once, by the
    /// settings ([`EstimatorSettings::build_for`] builds the one they name).
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for invalid settings, another
    /// backend (`estimator.backend`) or bounds (bounds need the SQP
    /// backend); the errors of [`Assembled::validate_loads`](crate::structure::Assembled::validate_loads).
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{Backend, EstimatorSettings, NewtonEstimator};
    /// use softrod::scene::Scene;
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let est = NewtonEstimator::new(&robot, &loads, &EstimatorSettings::default())?;
    /// assert_eq!(est.robot().n_q(), robot.n_q());
    /// let sqp = EstimatorSettings { backend: Backend::Sqp, ..Default::default() };
    /// let err = NewtonEstimator::new(&robot, &loads, &sqp).unwrap_err();
    /// assert_eq!(err.field(), Some("estimator.backend"));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn new(robot: &M, known: &M::Loads, settings: &EstimatorSettings) -> Result<Self> {
        if settings.backend != super::Backend::Newton {
            return Err(crate::Error::invalid(
                "estimator.backend",
                settings.backend.name(),
                "NewtonEstimator runs the newton backend (build the one the settings name with EstimatorSettings::build_for)",
            ));
        }
        if !settings.bounds.is_empty() {
            return Err(crate::Error::invalid(
                "estimator.bounds",
                settings.bounds.len(),
                "bounds on the load need the sqp backend",
            ));
        }
        Ok(NewtonEstimator {
            stream: Stream::new(Problem::new(
                robot.clone(),
                known.clone(),
                settings.clone(),
            )?),
            derivs_cache: None,
            cache_rows: Vec::new(),
            hf_cache: None,
            full_space: None,
            far_log: FarStart::default(),
        })
    }

    /// The robot.
    pub fn robot(&self) -> &M {
        self.stream.problem.robot()
    }

    /// The estimator with another warm strategy for the equilibria `q(F)`
    /// of its iterates (default [`WarmStrategy::ChordThenNewton`], which
    /// factors the tangent at every solution: each iteration's marker
    /// Jacobian (28) is then exact). With [`WarmStrategy::ChordRefactor`]
    /// the tangent is refactored only where the chord steps stop
    /// contracting: the Jacobian comes from the last factorization, an
    /// approximate Gauss–Newton whose iterates may be more, each far
    /// cheaper where a tangent costs much more than its chord steps (the
    /// full 3-D element of the parallel robot's legs, whose control loop
    /// uses it); the covariances are then those of that tangent too.
    ///
    /// # Errors
    /// As [`WarmStrategy::validate`].
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{Estimator, EstimatorSettings, NewtonEstimator, Observation};
    /// use softrod::{scene::Scene, statics::{StaticSolver, WarmStrategy}};
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[8, 16, 20])?.with_noise(1e-5, 1);
    /// let chord = WarmStrategy::ChordRefactor {
    ///     max_factorizations: 3, max_residuals: 36, step_tolerance_m: 1e-11, confirm: true,
    /// };
    /// let mut est = NewtonEstimator::new(&robot, &loads, &EstimatorSettings::default())?
    ///     .with_corrector(chord)?;
    /// assert!(est.step(&obs)?.report.status.is_converged());
    /// assert!(est.counts().solves > 0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn with_corrector(mut self, strategy: WarmStrategy) -> Result<Self> {
        self.stream.problem.tracker().set_strategy(strategy)?;
        Ok(self)
    }

    /// The warm tracker of the equilibria `q(F)`, for a caller that solves
    /// the same model near them (a controller's inverse kinematics: the
    /// two share their kept factors).
    pub(crate) fn tracker_mut(&mut self) -> &mut crate::statics::Tracker<M> {
        self.stream.problem.tracker()
    }

    /// What the equilibria `q(F)` of the estimates so far cost (the warm
    /// tracker's counts).
    pub fn counts(&self) -> WarmCounts {
        self.stream.problem.tracker_ref().counts()
    }

    /// Objective `J(F)` and reduced gradient (29) at `F` for `observation`
    /// (static solve from the warm shape), for checks and for users who
    /// drive their own optimizer.
    ///
    /// # Errors
    /// As [`Estimator::step`].
    pub fn objective_and_gradient(
        &mut self,
        observation: &Observation,
        f: &[f64],
        alpha: f64,
    ) -> Result<(f64, DVector<f64>)> {
        let (q, lu, op) = self.equilibrium_at(observation, f)?;
        let problem = &self.stream.problem;
        let (wr, pen, e) = problem.objective(&op, &q, f, alpha)?;
        let dv = problem.derivs(&q, &lu, &op)?;
        let g = problem.gradient(&dv, &op, &e, f, alpha)?;
        Ok((wr + pen, DVector::from_vec(g)))
    }

    /// The observed quantities `A q(F)` and the marker Jacobian
    /// `∂(A q)/∂F` (`n_ob × n_F`) at `F`.
    ///
    /// # Errors
    /// As [`Estimator::step`].
    pub fn markers_and_jacobian(
        &mut self,
        observation: &Observation,
        f: &[f64],
    ) -> Result<(DVector<f64>, DMatrix<f64>)> {
        let (q, lu, op) = self.equilibrium_at(observation, f)?;
        let dv = self.stream.problem.derivs(&q, &lu, &op)?;
        Ok((DVector::from_vec(op.apply(&q)), dv.jt.transpose()))
    }

    /// The equilibrium at `F` from the warm shape, the tangent's factors
    /// there and the observation operator.
    fn equilibrium_at(
        &mut self,
        observation: &Observation,
        f: &[f64],
    ) -> Result<(Vec<f64>, AutoFactors, ObservationOperator)> {
        let op = self.stream.problem.operator(observation)?;
        crate::error::check_len("f", self.stream.problem.n_f(), f.len())?;
        let (_, q0) = self.stream.start()?;
        let problem = &mut self.stream.problem;
        let eq = problem.equilibrium(f, &q0)?;
        let lu = problem.factor_tangent(eq.q.as_slice())?.factors;
        Ok((eq.q.data.into(), lu, op))
    }
}

impl<M: EstimationModel> Method<M> for NewtonEstimator<M> {
    const BACKEND: Backend = Backend::Newton;

    fn stream(&mut self) -> &mut Stream<M> {
        &mut self.stream
    }

    fn solve_one(
        &mut self,
        op: &ObservationOperator,
        f0: Vec<f64>,
        q0: Vec<f64>,
        alpha: f64,
    ) -> Result<Solved> {
        // the far start only while the stream has no estimate (a cold
        // first estimate, its α search); a solve through it that ends
        // short of convergence is repeated without it
        // (a stream under a load its model cannot explain: a warm step
        // through the far start stalled in every frame of a closed loop)
        if self.stream.warm.is_some() {
            self.far_log.answer = false;
            return self.solve_reduced(op, f0, q0, alpha, None);
        }
        let mut used = None;
        let r = self.solve_reduced(op, f0.clone(), q0.clone(), alpha, Some(&mut used));
        if let Some(its) = used {
            self.far_log.solves += 1;
            self.far_log.iterations += its;
        }
        self.far_log.answer = used.is_some();
        match r {
            Ok(s) if s.report.status.is_converged() || used.is_none() => Ok(s),
            Err(e) if used.is_none() => Err(e),
            _ => {
                self.far_log.repeated_without += 1;
                self.far_log.answer = false;
                self.solve_reduced(op, f0, q0, alpha, None)
            }
        }
    }

    fn take_far_start(&mut self) -> Option<FarStart> {
        let log = std::mem::take(&mut self.far_log);
        (log.solves > 0).then_some(log)
    }
}

impl<M: EstimationModel> NewtonEstimator<M> {
    /// The reduced iteration from `(f0, q0)` at `alpha`; with `far`, a far
    /// start may continue with the full-space iterations (`far` is then
    /// set to the iterations they took when it did). Its phases are
    /// [`reduced::Reduced`]'s.
    fn solve_reduced(
        &mut self,
        op: &ObservationOperator,
        f0: Vec<f64>,
        q0: Vec<f64>,
        alpha: f64,
        far: Option<&mut Option<usize>>,
    ) -> Result<Solved> {
        let NewtonEstimator {
            stream,
            derivs_cache,
            cache_rows,
            hf_cache,
            full_space,
            far_log: _,
        } = self;
        let core = &mut stream.problem;
        let settings = core.settings().clone();
        reduced::Reduced {
            core,
            derivs_cache,
            cache_rows,
            hf_cache,
            inner: full_space,
            op,
            alpha,
            settings,
            fallbacks_left: reduced::LINE_SEARCH_FALLBACKS,
        }
        .run(f0, q0, far)
    }
}

impl<M: EstimationModel> Estimator<M::Loads> for NewtonEstimator<M> {
    fn step(&mut self, observation: &Observation) -> Result<Estimate> {
        run_step(self, observation)
    }

    fn backend(&self) -> Backend {
        Backend::Newton
    }

    fn alpha(&self) -> Option<f64> {
        self.stream.alpha
    }

    fn reset(&mut self) {
        self.stream.reset();
        self.derivs_cache = None;
        self.hf_cache = None;
        self.full_space = None;
        self.far_log = FarStart::default();
    }

    fn set_known_loads(&mut self, known: M::Loads) -> Result<()> {
        self.stream.problem.set_known(known)?;
        self.derivs_cache = None;
        self.full_space = None;
        Ok(())
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use crate::assembly::{Base, Clamp, Robot, RobotSpec, Section};
    use crate::element::PlanarCable;
    use crate::loads::{LineLoad, Loads};
    use crate::observe::MarkerObservation;
    use crate::statics::StaticSolver;

    /// 5 markers (0.01 mm noise) on the 0.24 m cable (20 elements, clamped)
    /// under a uniform load of `w` N/m, and the cable.
    fn frame(w: f64) -> (Robot<PlanarCable>, Observation) {
        let sections = (0..2)
            .map(|_| Section::uniform(0.12, 300.0, 0.025, 10))
            .collect();
        let mut spec = RobotSpec::new(sections);
        spec.base = Base {
            clamp: Clamp::Full,
            ..Base::default()
        };
        let robot = spec.build_planar().unwrap();
        let mut loads = Loads::default();
        let mut q = StaticSolver::default()
            .solve(&robot, &loads, None)
            .unwrap()
            .q;
        for k in 1..=8 {
            loads.line_loads = vec![LineLoad::Uniform {
                w_n_per_m: vec![0.0, w * f64::from(k) / 8.0],
            }];
            q = StaticSolver::default()
                .solve(&robot, &loads, Some(q.as_slice()))
                .unwrap()
                .q;
        }
        let markers = (1..=5)
            .map(|k| {
                let s = 0.24 * f64::from(k) / 5.0;
                let p = robot.position_at(q.as_slice(), s).unwrap();
                MarkerObservation::at_arc(s, p)
            })
            .collect();
        (robot, Observation { markers }.with_noise(1e-5, 3))
    }

    /// The far start serves the cold first estimate of a large deflection
    /// (3 × the cable's self-weight) and never a warm step, even one that
    /// jumps to a load three times larger: a stream whose frames its model
    /// cannot follow keeps the reduced iteration of the steps before.
    #[test]
    fn only_a_cold_estimate_takes_the_far_start() {
        let (robot, first) = frame(-4.4);
        let (_, far) = frame(-13.2);
        let mut est =
            NewtonEstimator::new(&robot, &Loads::default(), &EstimatorSettings::default()).unwrap();
        let e = est.step(&first).unwrap();
        assert!(e.report.status.is_converged(), "{}", e.report);
        assert!(
            est.full_space.is_some(),
            "the cold estimate took no far start"
        );
        est.full_space = None;
        let e = est.step(&far).unwrap();
        assert!(e.report.status.is_converged(), "{}", e.report);
        assert!(est.full_space.is_none(), "a warm step took the far start");
    }
}
