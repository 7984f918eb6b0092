//! Feedforward inverse kinematics `f_IK(x_d, F̂)` (Sec. IV): the pressures
//! `P` (within their bounds) and the shape `q` such that the equilibrium (17)
//! `Q(F̂, q, P) = 0` holds and the end effector sits at `x_d`.
//!
//! # Method
//! Newton–Raphson on the pair `(q, P)` with `q` eliminated by the
//! equilibrium: every iterate `q(P)` is solved (warm) by
//! [`StaticSolver`], and the end effector's Jacobian is
//! `J = ∂x/∂P = S(X_e) ∂q/∂P` with `∂q/∂P` from (43). One step solves the
//! bounded least-squares problem in the pressures scaled by their range,
//! `p̂ = P / (P_max − P_min)`:
//!
//! ```text
//! min_d  ½ |x_d − x − Ĵ d|² / ℓ²  +  ½ μ |p̂ + d|²    s.t.  p̂_min ≤ p̂ + d ≤ p̂_max,  |d|∞ ≤ Δ
//! ```
//!
//! exactly, by an active-set method (a pressure on its bound sits *on* it),
//! then backtracks on the same merit.
//!
//! # Redundancy rule: minimum Σ P̂²
//! The two-section robot has four chambers and two task coordinates: the
//! end effector depends on the section torques `M_s = G P` only, so the
//! pressures are free along the null space of `G` (raising both chambers of
//! a section together). The term `μ |p̂|²` picks the pressures of least
//! `Σ (P_i / range_i)²` (for equal ranges: least `Σ P²`): with the
//! antagonistic pairs of the paper's robot that is one active chamber per
//! section and bending direction, the other at zero — the least air and
//! the least wall load for the same pose. Weighted by `μ = 10⁻²` against the
//! position error in `ℓ = 0.1 mm`, it moves the reached position by about
//! `μ ℓ² |p̂| / |Ĵ|`, i.e. 1e-9 m on this robot.
//!
//! # Unreachable targets
//! A target outside the workspace (or beyond the bounds) ends at the closest
//! reachable pose the iteration finds (a stationary point of the merit, in
//! the bounds) with [`IkStatus::Unreachable`] and its distance: never a
//! silent clamp. A solve that does not reach its target from the warm
//! start (the workspace folds, so the distance has local minima) is
//! repeated from every chamber at its minimum or mid-range (`2ⁿ` starts for
//! `n ≤ 6` chambers) and the closest result kept — except when the last
//! solve already ended unreachable at a target within
//! [`RESTART_RADIUS_M`] of this one: its restarts found that closest pose,
//! and a loop following an unreachable path then costs one warm solve per
//! step instead of `2ⁿ + 1` cold ones.

use nalgebra::DMatrix;
use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{check_all_finite, check_len, Error, Result};
use crate::linsolve::AutoSolver;
use crate::loads::Loads;
use crate::statics::{StaticSettings, StaticSolver};

use super::{adapter, boxqp};

/// Settings of [`InverseKinematics`]; every field has a documented default.
///
/// # Example
/// ```
/// softrod::control::IkSettings::default().validate()?;
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct IkSettings {
    /// Newton iterations per solve (default 40).
    pub max_iterations: usize,
    /// The end effector counts as reached within this distance (m, default 1e-7).
    pub tolerance_m: f64,
    /// Largest change of a scaled pressure `P / range` in one step (default 0.25).
    pub max_step: f64,
    /// Static solver of the equilibria `q(P)`.
    pub statics: StaticSettings,
    /// Newton iterations in all (over every load step) of the static solve
    /// of one line-search trial (default 150; at most
    /// `statics.max_total_iterations` is used). A trial the warm solver
    /// does not reach within it is rejected, as one that does not lower
    /// the merit is, and the step is halved: a trial that needs a long
    /// homotopy crosses a fold of the equilibria (a heavily loaded robot
    /// snapping over) or is too long. Measured on the failure sweep's
    /// cases: converging trials take at most 135 iterations (2 × the
    /// robot's weight at the tip), failing ones 550–990 (5 ×), which made
    /// one control step cost up to 10 s.
    pub trial_max_total_iterations: usize,
    /// Static Newton iterations one [`InverseKinematics::solve`] may spend
    /// in all: its equilibria, line-search trials and restarts (default
    /// 20 000). When they are spent the solve ends with the closest pose
    /// found so far and [`IkStatus::IterationLimit`], so one control step
    /// has a bounded cost whatever the load.
    pub max_static_iterations: usize,
}

impl Default for IkSettings {
    fn default() -> Self {
        IkSettings {
            max_iterations: 40,
            tolerance_m: 1e-7,
            max_step: 0.25,
            statics: StaticSettings::default(),
            trial_max_total_iterations: 150,
            max_static_iterations: 20_000,
        }
    }
}

impl IkSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`ik.tolerance_m`, …).
    pub fn validate(&self) -> Result<()> {
        if self.max_iterations == 0 {
            return Err(Error::invalid("ik.max_iterations", 0, "must be >= 1"));
        }
        if self.max_static_iterations == 0 {
            return Err(Error::invalid(
                "ik.max_static_iterations",
                0,
                "must be >= 1",
            ));
        }
        if self.trial_max_total_iterations == 0 {
            return Err(Error::invalid(
                "ik.trial_max_total_iterations",
                0,
                "must be >= 1",
            ));
        }
        for (name, v) in [
            ("ik.tolerance_m", self.tolerance_m),
            ("ik.max_step", self.max_step),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(name, v, "must be finite and > 0"));
            }
        }
        self.statics.validate("ik.statics")
    }
}

/// How an inverse-kinematics solve ended.
///
/// # Example
/// ```
/// let s = softrod::control::IkStatus::Reached { error_m: 1e-9 };
/// assert!(s.is_reached());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum IkStatus {
    /// The end effector is at the target within the tolerance.
    Reached {
        /// Remaining distance (m).
        error_m: f64,
    },
    /// The target cannot be reached within the pressure bounds: the solution
    /// is the closest reachable pose found.
    Unreachable {
        /// Distance from the closest pose to the target (m).
        distance_m: f64,
    },
    /// The iteration limit came first.
    IterationLimit {
        /// Remaining distance (m).
        error_m: f64,
    },
    /// Not solved: in a closed loop, the inverse kinematics found no
    /// equilibrium this instant or the plant failed before it ran (the
    /// sample's status says which); the last command is held.
    NotSolved,
}

impl IkStatus {
    /// Whether the target was reached.
    pub fn is_reached(&self) -> bool {
        matches!(self, IkStatus::Reached { .. })
    }

    /// The remaining distance to the target (m; infinite when not solved).
    pub fn error_m(&self) -> f64 {
        match *self {
            IkStatus::Reached { error_m } | IkStatus::IterationLimit { error_m } => error_m,
            IkStatus::Unreachable { distance_m } => distance_m,
            IkStatus::NotSolved => f64::INFINITY,
        }
    }
}

/// Which bound a chamber's pressure sits on.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PressureBound {
    /// Strictly inside its bounds.
    Inside,
    /// Exactly at `P_min`.
    Min,
    /// Exactly at `P_max`.
    Max,
}

/// The result of [`InverseKinematics::solve`].
#[derive(Debug, Clone, PartialEq)]
pub struct IkSolution {
    /// Chamber pressures (Pa), within their bounds.
    pub pressures_pa: Vec<f64>,
    /// The equilibrium shape at those pressures (all coordinates).
    pub q: Vec<f64>,
    /// End-effector position (m).
    pub effector_m: Vec<f64>,
    /// How the solve ended.
    pub status: IkStatus,
    /// Newton iterations taken.
    pub iterations: usize,
    /// Where each pressure sits relative to its bounds.
    pub bounds: Vec<PressureBound>,
}

/// Feedforward inverse kinematics of one robot (see the [module
/// documentation](crate::control)). It keeps the last solution as the warm start of
/// the next.
///
/// # Example
/// ```
/// use softrod::{control::{InverseKinematics, IkSettings}, scene::Scene};
/// let scene = Scene::two_section();
/// let robot = scene.robot()?;
/// let n = robot.n_q();
/// let mut ik = InverseKinematics::new(robot, scene.loads()?, IkSettings::default())?;
/// let sol = ik.solve(&[0.20, 0.08], &vec![0.0; n])?;
/// assert!(sol.status.is_reached());
/// assert!((sol.effector_m[0] - 0.20).abs() < 1e-7 && (sol.effector_m[1] - 0.08).abs() < 1e-7);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct InverseKinematics<E: Element> {
    robot: Robot<E>,
    known: Loads,
    settings: IkSettings,
    solver: StaticSolver,
    /// The solver of the line search's trials (its total budget
    /// [`IkSettings::trial_max_total_iterations`]).
    trial_solver: StaticSolver,
    linear: AutoSolver,
    effector_s_m: f64,
    /// Scaled pressure bounds and the scale (range) of each chamber.
    lo: Vec<f64>,
    hi: Vec<f64>,
    range: Vec<f64>,
    warm: Option<(Vec<f64>, Vec<f64>)>,
    /// The target of the last solve, if it ended unreachable after its
    /// restarts.
    unreached_target: Option<Vec<f64>>,
    /// Static Newton iterations spent by the current solve.
    spent: usize,
}

/// A solve that does not reach its target skips the cold restarts when the
/// last solve ended unreachable at a target at most this far (m): 1 mm, what
/// a 5 Hz loop moves along the slowest paths a person would choose for this
/// robot in a fifth of a second is ten times less.
pub const RESTART_RADIUS_M: f64 = 1e-3;

/// Static Newton iterations a solve's result took (1 for an error without
/// a report).
fn spent(eq: &Result<crate::statics::Equilibrium>) -> usize {
    match eq {
        Ok(e) => e.report.iterations.max(1),
        Err(Error::NotConverged { report }) => report.iterations.max(1),
        Err(_) => 1,
    }
}

/// Line-search trials whose equilibrium the warm solver does not reach
/// after which one Newton run ends as stalled: such a trial marks a fold
/// of the equilibria (a heavily loaded robot snapping over) between the
/// iterate and the trial, and an iterate at the fold only ever accepts
/// ever shorter steps (measured: 5 × the robot's weight at the tip, steps
/// of 1e-4 of the pressure range after 9 failed trials each).
const FAILED_TRIALS: usize = 8;

/// Weight of the pressures' norm against the position error (see the
/// module documentation).
const MU: f64 = 1e-2;
/// Length scale of the position error (m).
const ELL_M: f64 = 1e-4;

impl<E: Element> InverseKinematics<E> {
    /// The inverse kinematics of `robot` under the known loads `known`
    /// (self-weight from the robot; the pressures in `known` are the first
    /// guess), the end effector at the tip.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for invalid settings, a robot without
    /// chambers, or a chamber whose bounds are equal; the errors of
    /// [`Robot::validate_loads`].
    pub fn new(robot: Robot<E>, known: Loads, settings: IkSettings) -> Result<Self> {
        settings.validate()?;
        robot.validate_loads(&known)?;
        let bounds = robot.pressure_bounds();
        if bounds.is_empty() {
            return Err(Error::invalid(
                "robot.sections[].chambers",
                0,
                "inverse kinematics needs at least one chamber",
            ));
        }
        let mut range = Vec::with_capacity(bounds.len());
        for (i, (lo, hi)) in bounds.iter().enumerate() {
            let r = hi - lo;
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::invalid(
                    format!("chambers[{i}].pressure_max_pa"),
                    hi,
                    "inverse kinematics needs P_max > P_min (finite)",
                ));
            }
            range.push(r);
        }
        let lo = bounds.iter().zip(&range).map(|((l, _), r)| l / r).collect();
        let hi = bounds.iter().zip(&range).map(|((_, h), r)| h / r).collect();
        let solver = StaticSolver::new(settings.statics.clone())?;
        let total = settings
            .trial_max_total_iterations
            .min(settings.statics.max_total_iterations);
        let trial_solver = StaticSolver::new(StaticSettings {
            max_iterations: settings.statics.max_iterations.min(total),
            max_total_iterations: total,
            ..settings.statics.clone()
        })?;
        let linear =
            AutoSolver::with_kind(robot.tangent_pattern(), settings.statics.linear_solver)?;
        Ok(InverseKinematics {
            effector_s_m: robot.length(),
            robot,
            known,
            settings,
            solver,
            trial_solver,
            linear,
            lo,
            hi,
            range,
            warm: None,
            unreached_target: None,
            spent: 0,
        })
    }

    /// The robot.
    pub fn robot(&self) -> &Robot<E> {
        &self.robot
    }

    /// Forgets the warm start.
    pub fn reset(&mut self) {
        self.warm = None;
        self.unreached_target = None;
    }

    /// The known loads with pressures `p` and the load field `f_hat`.
    fn loads(&self, p: &[f64], f_hat: &[f64]) -> Loads {
        let mut loads = self.known.clone();
        loads.pressures_pa = p.to_vec();
        loads.distributed_f = f_hat.to_vec();
        loads
    }

    /// The equilibrium at pressures `p` (Pa) and load field `f_hat` (the
    /// distributed `F` of (8), `n_q` entries), from `q0` or cold; its shape
    /// and end-effector position.
    ///
    /// # Errors
    /// The errors of [`StaticSolver::solve_with`] (bad loads, no equilibrium).
    pub fn forward(
        &mut self,
        p: &[f64],
        f_hat: &[f64],
        q0: Option<&[f64]>,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let loads = self.loads(p, f_hat);
        let eq = self
            .solver
            .solve_with(&self.robot, &loads, q0, &mut self.linear);
        self.spent += spent(&eq);
        let eq = eq?;
        let x = self.robot.position_at(eq.q.as_slice(), self.effector_s_m)?;
        Ok((eq.q.data.into(), x.data.into()))
    }

    /// As [`InverseKinematics::forward`] from `q0`, with the line-search
    /// trials' budget ([`IkSettings::trial_max_total_iterations`]).
    fn forward_trial(
        &mut self,
        p: &[f64],
        f_hat: &[f64],
        q0: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let loads = self.loads(p, f_hat);
        let eq = self
            .trial_solver
            .solve_with(&self.robot, &loads, Some(q0), &mut self.linear);
        self.spent += spent(&eq);
        let eq = eq?;
        let x = self.robot.position_at(eq.q.as_slice(), self.effector_s_m)?;
        Ok((eq.q.data.into(), x.data.into()))
    }

    /// (43) `∂q/∂P = −(∂Q/∂q)⁻¹ ∂Q/∂P` (`n_q × n_pressures`, m/Pa) at the
    /// equilibrium `q` of pressures `p` and load field `f_hat`.
    ///
    /// # Errors
    /// [`Error::Singular`] if the tangent cannot be factored; dimension errors.
    pub fn dq_dp(&self, q: &[f64], p: &[f64], f_hat: &[f64]) -> Result<DMatrix<f64>> {
        adapter::dq_dp(&self.robot, &self.loads(p, f_hat), q)
    }

    /// The end effector's Jacobian `∂x/∂P = S(X_e) ∂q/∂P` (43) at the
    /// equilibrium `q` of pressures `p` and load field `f_hat`
    /// (`DIM × n_pressures`, m/Pa).
    ///
    /// # Errors
    /// [`Error::Singular`] if the tangent cannot be factored; dimension errors.
    pub fn jacobian(&self, q: &[f64], p: &[f64], f_hat: &[f64]) -> Result<DMatrix<f64>> {
        let dqdp = self.dq_dp(q, p, f_hat)?;
        self.effector_columns(&dqdp)
    }

    /// As [`InverseKinematics::jacobian`], factoring with the solver's own
    /// linear solver, analyzed once at construction (the Newton loop's: a
    /// fresh solver would analyze the tangent's pattern at every iteration).
    fn jacobian_warm(&mut self, q: &[f64], p: &[f64], f_hat: &[f64]) -> Result<DMatrix<f64>> {
        let loads = self.loads(p, f_hat);
        let dqdp = adapter::dq_dp_with(&self.robot, &loads, q, &mut self.linear)?;
        self.effector_columns(&dqdp)
    }

    /// `S(X_e) ∂q/∂P`: the end effector's rows of the columns of `dqdp`.
    fn effector_columns(&self, dqdp: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        let point = self.robot.arc_point("effector", self.effector_s_m)?;
        let d = E::DIM;
        let mut jac = DMatrix::zeros(d, dqdp.ncols());
        let mut out = vec![0.0; d];
        for (c, col) in dqdp.column_iter().enumerate() {
            point.value_into(col.as_slice(), &mut out)?;
            for (r, v) in out.iter().enumerate() {
                jac[(r, c)] = *v;
            }
        }
        Ok(jac)
    }

    /// `f_IK(x_d, F̂)`: the pressures putting the end effector at `x_d`
    /// under the load field `f_hat` (`n_q` entries; zeros for none), warm
    /// from the last solve.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (field `x_d`) for a non-finite target,
    /// (field `f_hat`) for a non-finite load field;
    /// [`Error::DimensionMismatch`] for wrong sizes; the static solver's
    /// errors when no equilibrium is found. An unreachable target is not an
    /// error: see [`IkStatus::Unreachable`].
    pub fn solve(&mut self, x_d: &[f64], f_hat: &[f64]) -> Result<IkSolution> {
        let d = E::DIM;
        check_len("x_d", d, x_d.len())?;
        check_all_finite("x_d", x_d)?;
        check_len("f_hat", self.robot.n_q(), f_hat.len())?;
        check_all_finite("f_hat", f_hat)?;
        let np = self.range.len();
        let bounds = self.robot.pressure_bounds();
        self.spent = 0;
        let (p0, q0) = match self.warm.take() {
            Some((p, q)) => (p, Some(q)),
            None => {
                let p = if self.known.pressures_pa.len() == np {
                    // the known pressures are checked against the bounds
                    self.known.pressures_pa.clone()
                } else {
                    bounds.iter().map(|(lo, _)| *lo).collect()
                };
                (p, None)
            }
        };
        // the warm start; a static solve that fails from it is not the end:
        // the starts below are cold
        let near_unreached = self.unreached_target.take().is_some_and(|t| {
            t.iter()
                .zip(x_d)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt()
                <= RESTART_RADIUS_M
        });
        let (mut best, first_err) = match self.solve_from(x_d, f_hat, p0, q0) {
            Ok(s) if s.status.is_reached() => {
                self.warm = Some((s.pressures_pa.clone(), s.q.clone()));
                return Ok(s);
            }
            Ok(s) if near_unreached => {
                self.warm = Some((s.pressures_pa.clone(), s.q.clone()));
                self.unreached_target = Some(x_d.to_vec());
                return Ok(s);
            }
            Ok(s) => (Some(s), None),
            Err(e) => (None, Some(e)),
        };
        // not reached from the warm start: a local minimum of the distance
        // is possible (the workspace folds), so try every chamber at its
        // minimum or mid-range (2^n starts, n ≤ 6) and keep the closest
        let n_starts = if np <= 6 { 1usize << np } else { 2 };
        let mut iterations = best.as_ref().map_or(0, |b| b.iterations);
        for code in 0..n_starts {
            if self.spent >= self.settings.max_static_iterations {
                break;
            }
            let p: Vec<f64> = bounds
                .iter()
                .enumerate()
                .map(|(c, (lo, hi))| {
                    if (np <= 6 && code >> c & 1 == 1) || (np > 6 && code == 1) {
                        0.5 * (lo + hi)
                    } else {
                        *lo
                    }
                })
                .collect();
            let Ok(s) = self.solve_from(x_d, f_hat, p, None) else {
                continue;
            };
            iterations += s.iterations;
            if best
                .as_ref()
                .is_none_or(|b| s.status.error_m() < b.status.error_m())
            {
                let reached = s.status.is_reached();
                best = Some(s);
                if reached {
                    break;
                }
            }
        }
        let Some(mut best) = best else {
            return Err(first_err.unwrap_or_else(|| {
                Error::invalid(
                    "x_d",
                    format!("{x_d:?}"),
                    "no start of the inverse kinematics found an equilibrium",
                )
            }));
        };
        best.iterations = iterations;
        self.warm = Some((best.pressures_pa.clone(), best.q.clone()));
        if !best.status.is_reached() {
            self.unreached_target = Some(x_d.to_vec());
        }
        Ok(best)
    }

    /// As [`InverseKinematics::solve`], but starting from the pressures
    /// `p0_pa` (Pa, within their bounds) instead of the last solution: the
    /// solution nearest a known command where the workspace folds.
    ///
    /// # Errors
    /// As [`InverseKinematics::solve`]; [`Error::InvalidParameter`] (field
    /// `pressures_pa[i]`) for a start outside the bounds.
    pub fn solve_starting_at(
        &mut self,
        x_d: &[f64],
        f_hat: &[f64],
        p0_pa: &[f64],
    ) -> Result<IkSolution> {
        let mut loads = self.known.clone();
        loads.pressures_pa = p0_pa.to_vec();
        self.robot.validate_loads(&loads)?;
        check_len("f_hat", self.robot.n_q(), f_hat.len())?;
        check_all_finite("f_hat", f_hat)?;
        let (q0, _) = self.forward(p0_pa, f_hat, None)?;
        self.warm = Some((p0_pa.to_vec(), q0));
        self.unreached_target = None;
        self.solve(x_d, f_hat)
    }

    /// Newton from the pressures `p0` (and the shape `q0`, or cold).
    #[allow(non_snake_case)]
    fn solve_from(
        &mut self,
        x_d: &[f64],
        f_hat: &[f64],
        p0: Vec<f64>,
        q0: Option<Vec<f64>>,
    ) -> Result<IkSolution> {
        let d = E::DIM;
        let np = self.range.len();
        let mut P = p0;
        let (mut q, mut x) = self.forward(&P, f_hat, q0.as_deref())?;
        let merit = |x: &[f64], p: &[f64], range: &[f64]| -> f64 {
            let r2: f64 = x.iter().zip(x_d).map(|(a, b)| (b - a).powi(2)).sum();
            let p2: f64 = p.iter().zip(range).map(|(p, r)| (p / r).powi(2)).sum();
            0.5 * r2 / (ELL_M * ELL_M) + 0.5 * MU * p2
        };
        let mut phi = merit(&x, &P, &self.range);
        let bounds_pa = self.robot.pressure_bounds();
        let mut iterations = 0;
        let mut stalled = false;
        let mut damping = 0.0f64;
        let mut failed_trials = 0usize;
        while iterations < self.settings.max_iterations
            && self.spent < self.settings.max_static_iterations
        {
            iterations += 1;
            let J = self.jacobian_warm(&q, &P, f_hat)?;
            // scaled Jacobian Ĵ = J diag(range), residual r = x_d − x
            let Jh = DMatrix::from_fn(d, np, |r, c| J[(r, c)] * self.range[c]);
            let r: Vec<f64> = x_d.iter().zip(&x).map(|(a, b)| a - b).collect();
            let ph: Vec<f64> = P.iter().zip(&self.range).map(|(p, r)| p / r).collect();
            let w = 1.0 / (ELL_M * ELL_M);
            let mut H = Jh.transpose() * &Jh * w + DMatrix::identity(np, np) * MU;
            // Levenberg–Marquardt damping: the Gauss–Newton model leaves out
            // the curvature of x(P), which dominates far from the target
            let hmax = H.diagonal().amax();
            H += DMatrix::identity(np, np) * (damping * hmax);
            let g: Vec<f64> = (0..np)
                .map(|c| -w * (0..d).map(|k| Jh[(k, c)] * r[k]).sum::<f64>() + MU * ph[c])
                .collect();
            let step = self.settings.max_step;
            let lo: Vec<f64> = (0..np).map(|c| (self.lo[c] - ph[c]).max(-step)).collect();
            let hi: Vec<f64> = (0..np).map(|c| (self.hi[c] - ph[c]).min(step)).collect();
            let sol = boxqp::solve(&H, &g, &lo, &hi)?;
            let dec: f64 = -g.iter().zip(&sol.x).map(|(a, b)| a * b).sum::<f64>();
            let small = sol.x.iter().fold(0.0f64, |m, v| m.max(v.abs())) <= 1e-7;
            if small || dec <= 1e-10 * phi.max(1e-2) {
                stalled = true;
                break;
            }
            // backtracking on the merit (pressures at a bound stay on it for
            // a full step; shorter steps keep them inside)
            let mut t = 1.0;
            let mut accepted = false;
            for _ in 0..12 {
                let trial: Vec<f64> = (0..np)
                    .map(|c| {
                        let (lo_pa, hi_pa) = bounds_pa[c];
                        match (t == 1.0, sol.sides[c]) {
                            (true, boxqp::Side::Lower) => lo_pa,
                            (true, boxqp::Side::Upper) => hi_pa,
                            // inside by the QP's feasibility; the clamp only
                            // takes off round-off of the scaling
                            _ => ((ph[c] + t * sol.x[c]) * self.range[c]).clamp(lo_pa, hi_pa),
                        }
                    })
                    .collect();
                let ft = self.forward_trial(&trial, f_hat, &q);
                if ft.is_err() {
                    failed_trials += 1;
                }
                if let Ok((qt, xt)) = ft {
                    let phit = merit(&xt, &trial, &self.range);
                    if phit <= phi - 1e-4 * t * dec {
                        let ratio = (phi - phit) / dec.max(f64::MIN_POSITIVE);
                        damping = if t < 1.0 || ratio < 0.25 {
                            (4.0 * damping).max(1e-4)
                        } else if ratio > 0.75 {
                            if damping < 1e-10 {
                                0.0
                            } else {
                                damping / 4.0
                            }
                        } else {
                            damping
                        };
                        P = trial;
                        q = qt;
                        x = xt;
                        phi = phit;
                        accepted = true;
                        break;
                    }
                }
                t *= 0.5;
            }
            if failed_trials >= FAILED_TRIALS {
                // the iterate sits at a fold of the equilibria: the closest
                // pose on this branch
                stalled = true;
                break;
            }
            if !accepted && damping < 1.0 {
                // a shorter, more gradient-like step before giving up
                damping = (16.0 * damping).max(1e-3);
                continue;
            }
            if !accepted {
                stalled = true;
                break;
            }
        }
        let error_m = x
            .iter()
            .zip(x_d)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        let status = if error_m <= self.settings.tolerance_m {
            IkStatus::Reached { error_m }
        } else if stalled {
            IkStatus::Unreachable {
                distance_m: error_m,
            }
        } else {
            IkStatus::IterationLimit { error_m }
        };
        let bounds = P
            .iter()
            .zip(&bounds_pa)
            .map(|(p, (lo, hi))| {
                if p == lo {
                    PressureBound::Min
                } else if p == hi {
                    PressureBound::Max
                } else {
                    PressureBound::Inside
                }
            })
            .collect();
        Ok(IkSolution {
            pressures_pa: P,
            q,
            effector_m: x,
            status,
            iterations,
            bounds,
        })
    }
}
