//! Warm static solves of the parallel robot for a controller: many
//! equilibria at nearby pressures and platform forces, each from the last.
//!
//! Why: a static solve of the full-leg robot from its straight reference
//! takes 4–5 Newton iterations, and two thirds of each iteration is the
//! assembly of the tangent (the 24-coordinate element's Hessian at every
//! Gauss point); the residual alone costs about a thirtieth of it and the
//! sparse factorization of the 264 × 264 tangent less than the assembly.
//! Measured (4 elements per section, 264 free coordinates, the machine
//! shared by several builds, so the times are noisy): cold
//! solve ≈ 90 ms in 5 iterations, warm from a nearby equilibrium 3
//! iterations ≈ 75 ms, one residual ≈ 0.5 ms, one residual and tangent
//! ≈ 14 ms.
//!
//! So [`WarmStatics`] runs the one warm [`Tracker`] with
//! [`WarmStrategy::ChordRefactor`]: it keeps the factors of the last
//! tangent and takes chord (modified Newton) steps `u ← u + K₀⁻¹ R(u)` with
//! them, each a residual and a back-substitution; it refactors at the
//! current point when the steps stop shrinking by half, and falls back to
//! the globalized [`crate::statics::StaticSolver`] when the chord
//! iteration fails. What is this robot's own here: the same factors give
//! the platform's sensitivities ([`WarmStatics::sensitivities`]): its
//! compliance `C = A_x K⁻¹ A_xᵀ` (32)–(35) and its pressure Jacobian
//! `J = A_x K⁻¹ ∂R/∂P` (43), from three solves with `A_xᵀ` (K is
//! symmetric), at the tangent of the last factorization (a quasi-Newton
//! Jacobian for the controller's iterations, whose residuals are exact).

use nalgebra::{DMatrix, DVector, SMatrix};

use super::ParallelRobot;
use crate::element::Element;
use crate::error::{Error, Result, check_len};
use crate::linsolve::{AutoFactors, Factorization};
use crate::statics::{StaticSettings, Tracker, WarmStrategy};
use crate::structure::{Structure, StructureLoads};

pub use crate::statics::WarmCounts;

/// Chord steps per solve before the solve refactors (at most twice) and
/// then falls back.
const MAX_CHORD_STEPS: usize = 12;

/// The platform's sensitivities at an equilibrium.
///
/// # Example
/// See [`WarmStatics::sensitivities`].
#[derive(Debug, Clone, PartialEq)]
pub struct PlatformSensitivities {
    /// `∂x/∂F`: the platform's compliance to a force at its centre (m/N).
    pub compliance_m_per_n: SMatrix<f64, 3, 3>,
    /// `∂x/∂P`: 3 × (number of pressures) (m/Pa).
    pub jacobian_m_per_pa: DMatrix<f64>,
}

/// Warm static solves of one [`ParallelRobot`] (see the [module
/// documentation](self)).
///
/// # Example
/// ```
/// use softrod::parallel::{warm::WarmStatics, ParallelSpec};
/// let mut spec = ParallelSpec::default();
/// spec.elements_per_section = 2;
/// let robot = spec.build_full()?;
/// let mut warm = WarmStatics::new(robot.clone())?;
/// let loads = robot.loads(&[], [0.0, 0.0, -0.5], [0.0; 3])?;
/// let eq = robot.solve(&loads, None)?;
/// // from the equilibrium, a little more load: chord steps, the same answer
/// let more = robot.loads(&[], [0.0, 0.0, -0.51], [0.0; 3])?;
/// let u = warm.solve(&more, eq.u.as_slice())?;
/// let exact = robot.solve(&more, Some(eq.q.as_slice()))?;
/// let d = u.iter().zip(&exact.u).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
/// assert!(d < 1e-9, "{d}");
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct WarmStatics<E: Element> {
    robot: ParallelRobot<E>,
    tracker: Tracker<Structure<E>>,
}

/// The warm strategy of the parallel robot's loop (see
/// [`WarmStatics::new`]): chord steps with kept factors, at most 3
/// factorizations and `3 ×` [`MAX_CHORD_STEPS`] residuals per solve, a step
/// tolerance of `1e-11` times the leg length over 0.1 m; with `confirm`
/// the residual at the answer is evaluated for its status.
pub(crate) fn chord_strategy(spec: &crate::parallel::ParallelSpec, confirm: bool) -> WarmStrategy {
    WarmStrategy::ChordRefactor {
        max_factorizations: 3,
        max_residuals: MAX_CHORD_STEPS * 3,
        step_tolerance_m: 1e-11 * spec.leg_length_m.max(1e-3) / 0.1,
        confirm,
    }
}

/// `W = K⁻¹ A_xᵀ` (three columns of `n_free`, column-major) and the
/// platform's compliance `C = A_x W` (m/N) of `robot` with the factors of
/// a tangent `K`.
///
/// # Errors
/// The factors' solve errors (factors that do not fit the robot).
fn compliance_columns<E: Element>(
    robot: &ParallelRobot<E>,
    factors: &AutoFactors,
) -> Result<(Vec<f64>, SMatrix<f64, 3, 3>)> {
    let n = robot.structure().n_free();
    let x0 = robot.platform_free_start()?;
    let mut w = vec![0.0; 3 * n];
    for j in 0..3 {
        w[j * n + x0 + j] = 1.0;
    }
    factors.solve_columns_in_place(&mut w, 3)?;
    let c = SMatrix::<f64, 3, 3>::from_fn(|i, j| w[j * n + x0 + i]);
    Ok((w, c))
}

impl<E: Element> WarmStatics<E> {
    /// The warm solver of `robot` (its tangent pattern analyzed once): the
    /// tracker's [`WarmStrategy::ChordRefactor`] with at most 3
    /// factorizations and 36 residuals per solve, a step tolerance of
    /// `1e-11` times the leg length over 0.1 m, the answer's residual not
    /// evaluated (a residual per solve saved; its status is then
    /// [`crate::statics::WarmStatus::Unconfirmed`]), the fallback the
    /// default [`crate::statics::StaticSolver`].
    ///
    /// # Errors
    /// As [`Tracker::new`] for a pattern too large to factor.
    pub fn new(robot: ParallelRobot<E>) -> Result<Self> {
        let strategy = chord_strategy(robot.spec(), false);
        let tracker = Tracker::new(
            robot.structure().clone(),
            StructureLoads::default(),
            StaticSettings::default(),
        )?
        .with_strategy(strategy)?;
        Ok(WarmStatics { robot, tracker })
    }

    /// The robot.
    pub fn robot(&self) -> &ParallelRobot<E> {
        &self.robot
    }

    /// What the solves cost so far.
    pub fn counts(&self) -> WarmCounts {
        self.tracker.counts()
    }

    /// The tracker the solves run on.
    pub fn tracker(&self) -> &Tracker<Structure<E>> {
        &self.tracker
    }

    /// Assembles and factors the tangent at `u` under `loads`, kept for the
    /// next chord steps and sensitivities.
    ///
    /// # Errors
    /// Sizes as [`crate::structure::Structure::residual`]; a tangent that
    /// cannot be factored.
    pub fn factor_at(&mut self, u: &[f64], loads: &StructureLoads) -> Result<()> {
        self.tracker.set_loads(loads.clone())?;
        self.tracker.factor_at_free(u)
    }

    /// The equilibrium's free coordinates `u` under `loads`, from `u0` (a
    /// nearby equilibrium, typically the last one).
    ///
    /// # Errors
    /// Sizes as [`crate::structure::Structure::residual`]; the errors of
    /// [`crate::statics::StaticSolver::solve`] when the fallback fails too.
    pub fn solve(&mut self, loads: &StructureLoads, u0: &[f64]) -> Result<DVector<f64>> {
        check_len("u0", self.robot.structure().n_free(), u0.len())?;
        self.tracker.set_loads(loads.clone())?;
        Ok(self.tracker.solve_free(u0)?.u)
    }

    /// The kept factors, or the error of sensitivities asked too early.
    fn factors(&self) -> Result<&AutoFactors> {
        self.tracker.kept_factors().ok_or_else(|| {
            Error::invalid(
                "warm",
                "unfactored",
                "factor a tangent (a solve or factor_at) before the sensitivities",
            )
        })
    }

    /// `W = K⁻¹ A_xᵀ` (three columns of `n_free`, column-major) and the
    /// compliance `C = A_x W` with the kept factors.
    fn compliance_columns(&self) -> Result<(Vec<f64>, SMatrix<f64, 3, 3>)> {
        compliance_columns(&self.robot, self.factors()?)
    }

    /// The platform's compliance `C = A_x K⁻¹ A_xᵀ` (m/N) with the kept
    /// factors (the first half of [`WarmStatics::sensitivities`]).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (`warm`) when nothing is factored yet.
    pub fn compliance(&self) -> Result<SMatrix<f64, 3, 3>> {
        Ok(self.compliance_columns()?.1)
    }

    /// The platform's compliance and pressure Jacobian with the kept
    /// factors (see the [module documentation](self)); the generalized
    /// forces of the pressures are evaluated exactly at `u`.
    ///
    /// # Errors
    /// Sizes as [`crate::structure::Structure::residual`];
    /// [`Error::InvalidParameter`] (`warm`) when nothing is factored yet.
    ///
    /// # Example
    /// ```
    /// use softrod::parallel::{warm::WarmStatics, ParallelSpec};
    /// let mut spec = ParallelSpec::default();
    /// spec.elements_per_section = 2;
    /// let robot = spec.build_full()?;
    /// let loads = robot.loads(&[], [0.0; 3], [0.0; 3])?;
    /// let eq = robot.solve(&loads, None)?;
    /// let mut warm = WarmStatics::new(robot.clone())?;
    /// warm.factor_at(eq.u.as_slice(), &loads)?;
    /// let s = warm.sensitivities(eq.u.as_slice())?;
    /// assert_eq!(s.jacobian_m_per_pa.shape(), (3, 18));
    /// // the same compliance as the payload estimation's dense one
    /// let c = robot.platform_compliance(&eq, &loads)?;
    /// assert!((s.compliance_m_per_n[(2, 2)] - c[(2, 2)]).abs() < 1e-9 * c[(2, 2)]);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn sensitivities(&self, u: &[f64]) -> Result<PlatformSensitivities> {
        let s = self.robot.structure();
        let n = s.n_free();
        check_len("u", n, u.len())?;
        let (w, c) = self.compliance_columns()?;
        // ∂R/∂P_k: the pressures' generalized force is linear in P
        let np = self.robot.spec().n_pressures();
        let q: Vec<f64> = s.configuration(u)?.data.into();
        let zero_dead = vec![0.0; s.n_q()];
        let mut jac = DMatrix::zeros(3, np);
        let mut p = vec![0.0; np];
        let mut g = vec![0.0; n];
        for k in 0..np {
            p.iter_mut().for_each(|v| *v = 0.0);
            p[k] = 1.0;
            let loads = self.robot.loads(&p, [0.0; 3], [0.0; 3])?;
            s.applied_force_into(u, &q, &zero_dead, &loads, &mut g)?;
            for i in 0..3 {
                jac[(i, k)] = (0..n).map(|a| w[i * n + a] * g[a]).sum();
            }
        }
        Ok(PlatformSensitivities {
            compliance_m_per_n: c,
            jacobian_m_per_pa: jac,
        })
    }
}
