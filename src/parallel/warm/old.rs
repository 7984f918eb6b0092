//! The parallel robot's warm solver as it was before the one generic
//! tracker (kept for the comparison of old and new only).
#![allow(dead_code, missing_docs, clippy::all)]

use nalgebra::{DMatrix, DVector, SMatrix};

use crate::element::Element;
use crate::error::{check_len, Error, Result};
use crate::linsolve::{
    AutoFactors, AutoSolver, FactorOptions, Factorization, SymmetricMatrix, TangentSolver,
};
use crate::parallel::ParallelRobot;
use crate::statics::StaticSolver;
use crate::structure::{Assembled, StructureLoads};

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

/// Counts of what the warm solves cost.
///
/// # Example
/// ```ignore
/// let c = softrod::parallel::warm::WarmCounts::default();
/// assert_eq!(c.factorizations, 0);
/// ```ignore
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct WarmCounts {
    /// Solves asked for.
    pub solves: usize,
    /// Residual evaluations (chord steps).
    pub residuals: usize,
    /// Tangent assemblies and factorizations.
    pub factorizations: usize,
    /// Solves that fell back to the globalized [`StaticSolver`].
    pub fallbacks: usize,
}

/// Warm static solves of one [`ParallelRobot`] (see the [module
/// documentation](self)).
///
/// # Example
/// ```ignore
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
/// ```ignore
#[derive(Debug, Clone)]
pub struct WarmStatics<E: Element> {
    robot: ParallelRobot<E>,
    solver: AutoSolver,
    k: SymmetricMatrix,
    factors: Option<AutoFactors>,
    counts: WarmCounts,
    /// A chord solve ends with a step below this (m or unit slope).
    step_tolerance: f64,
}

impl<E: Element> WarmStatics<E> {
    /// The warm solver of `robot` (its tangent pattern analyzed once).
    ///
    /// # Errors
    /// As [`AutoSolver::with_kind`] for a pattern too large to factor.
    pub fn new(robot: ParallelRobot<E>) -> Result<Self> {
        let pattern = Assembled::tangent_pattern(robot.structure())?;
        let solver = AutoSolver::with_kind(&pattern, crate::linsolve::SolverKind::Auto)?;
        let step_tolerance = 1e-11 * robot.spec().leg_length_m.max(1e-3) / 0.1;
        Ok(WarmStatics {
            robot,
            solver,
            k: SymmetricMatrix::zeros(pattern),
            factors: None,
            counts: WarmCounts::default(),
            step_tolerance,
        })
    }

    /// The robot.
    pub fn robot(&self) -> &ParallelRobot<E> {
        &self.robot
    }

    /// What the solves cost so far.
    pub fn counts(&self) -> WarmCounts {
        self.counts
    }

    /// Assembles and factors the tangent at `u` under `loads`, kept for the
    /// next chord steps and sensitivities.
    ///
    /// # Errors
    /// Sizes as [`crate::structure::Structure::residual`]; a tangent that
    /// cannot be factored.
    pub fn factor_at(&mut self, u: &[f64], loads: &StructureLoads) -> Result<()> {
        let s = self.robot.structure();
        let dead: Vec<f64> = s.dead_force(loads)?.data.into();
        let q: Vec<f64> = s.configuration(u)?.data.into();
        s.tangent_into(u, &q, &dead, loads, &mut self.k)?;
        self.factors = Some(self.solver.factor(&self.k, FactorOptions::default())?);
        self.counts.factorizations += 1;
        Ok(())
    }

    /// The equilibrium's free coordinates `u` under `loads`, from `u0` (a
    /// nearby equilibrium, typically the last one).
    ///
    /// # Errors
    /// Sizes as [`crate::structure::Structure::residual`]; the errors of
    /// [`StaticSolver::solve`] when the fallback fails too.
    pub fn solve(&mut self, loads: &StructureLoads, u0: &[f64]) -> Result<DVector<f64>> {
        let s = self.robot.structure();
        check_len("u0", s.n_free(), u0.len())?;
        self.counts.solves += 1;
        let dead: Vec<f64> = s.dead_force(loads)?.data.into();
        let (n, nq) = (s.n_free(), s.n_q());
        let mut u = u0.to_vec();
        let mut q: Vec<f64> = s.configuration(&u)?.data.into();
        let (mut r, mut du, mut dq) = (vec![0.0; n], vec![0.0; n], vec![0.0; nq]);
        let (mut u1, mut q1) = (u.clone(), q.clone());
        let mut last = f64::INFINITY;
        let mut refactors = 0;
        if self.factors.is_none() {
            self.factor_at(&u, loads)?;
            refactors += 1;
        }
        for _ in 0..MAX_CHORD_STEPS * 3 {
            let s = self.robot.structure();
            s.residual_into(&u, &q, &dead, loads, &mut r)?;
            self.counts.residuals += 1;
            du.copy_from_slice(&r);
            let Some(f) = &self.factors else { break };
            f.solve_in_place(&mut du)?;
            let step = du.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if !step.is_finite() {
                break;
            }
            if step > 0.5 * last {
                // not contracting: a Newton step from here, at most twice
                if refactors >= 3 {
                    break;
                }
                self.factor_at(&u, loads)?;
                refactors += 1;
                last = f64::INFINITY;
                continue;
            }
            let s = self.robot.structure();
            s.step_into(&u, &du, &mut dq)?;
            s.advance_into(&u, &q, &du, &dq, 1.0, &mut u1, &mut q1)?;
            std::mem::swap(&mut u, &mut u1);
            std::mem::swap(&mut q, &mut q1);
            if step <= self.step_tolerance {
                return Ok(DVector::from_vec(u));
            }
            last = step;
        }
        self.counts.fallbacks += 1;
        let s = self.robot.structure();
        let q0: Vec<f64> = s.configuration(u0)?.data.into();
        let eq = StaticSolver::default().solve_with(s, loads, Some(&q0), &mut self.solver)?;
        self.factor_at(eq.u.as_slice(), loads)?;
        Ok(eq.u)
    }

    /// `W = K⁻¹ A_xᵀ` (three columns of `n_free`, column-major) and the
    /// compliance `C = A_x W` with the kept factors.
    fn compliance_columns(&self) -> Result<(Vec<f64>, SMatrix<f64, 3, 3>)> {
        let Some(f) = &self.factors else {
            return Err(Error::invalid(
                "warm",
                "unfactored",
                "factor a tangent (a solve or factor_at) before the sensitivities",
            ));
        };
        let n = self.robot.structure().n_free();
        let x0 = self.robot.platform_free_start()?;
        let mut w = vec![0.0; 3 * n];
        for j in 0..3 {
            w[j * n + x0 + j] = 1.0;
        }
        f.solve_columns_in_place(&mut w, 3)?;
        let c = SMatrix::<f64, 3, 3>::from_fn(|i, j| w[j * n + x0 + i]);
        Ok((w, c))
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
    /// ```ignore
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
    /// ```ignore
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
