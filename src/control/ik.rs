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
//! # Cost of a step
//! The equilibria of the Newton loop are warm: a line-search trial starts
//! from the last equilibrium moved to first order, `q + ∂q/∂P ΔP`, and the
//! first equilibrium of a solve whose load field changed from the last
//! solve's starts from the last one moved by its response to the change
//! (the load field the last solution holds for is kept with it: when it
//! is the same, that equilibrium is used as it is). A plain Newton
//! corrector takes them to the static solver's residual tolerance, and the
//! positive definite factors of the tangent at its answer (the static
//! solver's stability test) give the next Jacobian (43) by solves only;
//! the static solver, from the unpredicted start, takes over wherever the
//! corrector gives up. The closing iteration at a reached target (the
//! check that no null-space step lowers `Σ P̂²`) therefore costs solves,
//! not another factorization.
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

use nalgebra::{DMatrix, DVector};

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{Error, Result, check_all_finite, check_len};
use crate::linsolve::AutoFactors;
use crate::loads::Loads;
use crate::sensitivity::Sensitivity;
use crate::statics::{StaticSettings, StaticSolver, TrackedEquilibrium, Tracker, WarmStrategy};
use crate::structure::Stepping;

use super::ik_settings::{IkSettings, IkStatus, PressureBound};
use super::{adapter, boxqp};

/// The result of [`InverseKinematics::solve`].
///
/// # Example
/// ```
/// use softrod::{control::{InverseKinematics, IkSettings}, scene::Scene};
/// let scene = Scene::two_section();
/// let robot = scene.robot()?;
/// let (n, np) = (robot.n_q(), robot.n_pressures());
/// let mut ik = InverseKinematics::new(robot, scene.loads()?, IkSettings::default())?;
/// let sol = ik.solve(&[0.20, 0.08], &vec![0.0; n])?;
/// assert_eq!((sol.pressures_pa.len(), sol.q.len(), sol.effector_m.len()), (np, n, 2));
/// assert!((sol.effector_m - nalgebra::dvector![0.20, 0.08]).norm() < 1e-7);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct IkSolution {
    /// Chamber pressures (Pa), within their bounds.
    pub pressures_pa: DVector<f64>,
    /// The equilibrium shape at those pressures (all coordinates).
    pub q: DVector<f64>,
    /// End-effector position (m, `DIM` components).
    pub effector_m: DVector<f64>,
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
/// // the equilibrium at those pressures puts the end effector there
/// let (q, x) = ik.forward(sol.pressures_pa.as_slice(), &vec![0.0; n], None)?;
/// assert!((x - &sol.effector_m).norm() < 1e-9 && q.len() == n);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct InverseKinematics<E: Element> {
    /// The robot and the warm corrector of its equilibria (the one warm
    /// tracker, [`WarmStrategy::Newton`]), whose linear solver, analyzed
    /// once, also serves the static solves and the Jacobians.
    tracker: Tracker<Robot<E>>,
    known: Loads,
    settings: IkSettings,
    solver: StaticSolver,
    /// The solver of the line search's trials (its total budget
    /// [`IkSettings::trial_max_total_iterations`]).
    trial_solver: StaticSolver,
    effector_s_m: f64,
    /// Scaled pressure bounds and the scale (range) of each chamber.
    lo: Vec<f64>,
    hi: Vec<f64>,
    range: Vec<f64>,
    warm: Option<Held>,
    /// The target of the last solve, if it ended unreachable after its
    /// restarts.
    unreached_target: Option<Vec<f64>>,
    /// Static Newton iterations spent by the current solve.
    spent: usize,
}

/// An equilibrium the inverse kinematics holds: the last solution, the
/// warm start of the next solve.
#[derive(Debug, Clone)]
struct Held {
    /// Pressures (Pa).
    p: Vec<f64>,
    /// The equilibrium shape at `p` under `f_hat`.
    q: Vec<f64>,
    /// The load field `q` is the equilibrium of.
    f_hat: Vec<f64>,
    /// End-effector position at `q` (m).
    x: Vec<f64>,
    /// The factors of the tangent at `q` when the corrector made it.
    factors: Option<AutoFactors>,
}

/// Where a Newton run starts.
#[derive(Debug)]
enum Start {
    /// From the held equilibrium.
    Warm(Box<Held>),
    /// From these pressures (Pa), the equilibrium solved cold.
    Cold(Vec<f64>),
}

/// An equilibrium of the Newton loop: shape, end effector, and the factors
/// of its tangent when the corrector made it (`None`: the static solver).
type Eq = (Vec<f64>, Vec<f64>, Option<AutoFactors>);

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

/// Newton steps the corrector takes at most (a warm start from the
/// sensitivities' prediction converges in one or two: measured on the
/// tracking bench's loop).
const CORRECTOR_STEPS: usize = 6;

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
        let effector_s_m = robot.length();
        let tracker = Tracker::new(robot, known.clone(), settings.statics.clone())?.with_strategy(
            WarmStrategy::Newton {
                max_steps: CORRECTOR_STEPS,
            },
        )?;
        Ok(InverseKinematics {
            effector_s_m,
            tracker,
            known,
            settings,
            solver,
            trial_solver,
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
        self.tracker.robot()
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
    /// `q` and end-effector position (m, `DIM` components).
    ///
    /// # Errors
    /// The errors of [`StaticSolver::solve_with`] (bad loads, no equilibrium).
    ///
    /// # Example
    /// See [`InverseKinematics`].
    pub fn forward(
        &mut self,
        p: &[f64],
        f_hat: &[f64],
        q0: Option<&[f64]>,
    ) -> Result<(DVector<f64>, DVector<f64>)> {
        let (q, x) = self.forward_raw(p, f_hat, q0)?;
        Ok((DVector::from_vec(q), DVector::from_vec(x)))
    }

    /// [`InverseKinematics::forward`] as plain vectors (the Newton loop's).
    fn forward_raw(
        &mut self,
        p: &[f64],
        f_hat: &[f64],
        q0: Option<&[f64]>,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let loads = self.loads(p, f_hat);
        let eq = self.tracker.static_solve(&self.solver, &loads, q0);
        self.spent += spent(&eq);
        let eq = eq?;
        let x = self
            .robot()
            .position_at(eq.q.as_slice(), self.effector_s_m)?;
        Ok((eq.q.data.into(), x.data.into()))
    }

    /// The equilibrium at pressures `p` and load field `f_hat` near a
    /// known one: the corrector from `start` (a prediction), else the static
    /// solver from `fallback` (a line-search trial with the trials' budget,
    /// [`IkSettings::trial_max_total_iterations`]).
    fn equilibrium(
        &mut self,
        p: &[f64],
        f_hat: &[f64],
        start: &[f64],
        fallback: &[f64],
        trial: bool,
    ) -> Result<Eq> {
        let loads = self.loads(p, f_hat);
        let before = self.tracker.counts().steps;
        let corrected = self.correct(&loads, start);
        // the Newton steps taken (at least 1: the static solver's count)
        self.spent += (self.tracker.counts().steps - before).max(1);
        if let Some(c) = corrected {
            let x = self
                .robot()
                .position_at(c.q.as_slice(), self.effector_s_m)?;
            return Ok((c.q.data.into(), x.data.into(), Some(c.factors)));
        }
        let solver = if trial {
            &self.trial_solver
        } else {
            &self.solver
        };
        let eq = self.tracker.static_solve(solver, &loads, Some(fallback));
        self.spent += spent(&eq);
        let eq = eq?;
        let x = self
            .robot()
            .position_at(eq.q.as_slice(), self.effector_s_m)?;
        Ok((eq.q.data.into(), x.data.into(), None))
    }

    /// The corrector: the tracker's [`WarmStrategy::Newton`] from `start`
    /// under `loads` to the static solver's residual tolerance, with the
    /// positive definite factors of the tangent at its answer; `None`
    /// where it gives up (a hard solve, or an error: the static solver
    /// from the caller's start then reports it).
    fn correct(&mut self, loads: &Loads, start: &[f64]) -> Option<TrackedEquilibrium> {
        let u0 = self.robot().free_coordinates_of(start).ok()?;
        self.tracker.set_known(loads.clone()).ok()?;
        self.tracker.try_solve_free(u0.as_slice()).ok().flatten()
    }

    /// The first equilibrium of a Newton run: the held one as it is when
    /// its load field is `f_hat`, else corrected from it moved along its
    /// response to the change of load field, `M K⁻¹ Mᵀ J_QF ΔF̂` (the
    /// equilibrium's shift to first order); cold by the static solver.
    fn first_equilibrium(&mut self, f_hat: &[f64], start: Start) -> Result<(Vec<f64>, Eq)> {
        match start {
            Start::Cold(p) => {
                let (q, x) = self.forward_raw(&p, f_hat, None)?;
                Ok((p, (q, x, None)))
            }
            Start::Warm(h) if h.f_hat == f_hat => {
                let h = *h;
                Ok((h.p, (h.q, h.x, h.factors)))
            }
            Start::Warm(h) => {
                let predicted = match &h.factors {
                    Some(f) => {
                        let df: Vec<f64> = f_hat.iter().zip(&h.f_hat).map(|(a, b)| a - b).collect();
                        let g = self.robot().apply_load_gram(&df)?;
                        let dq = Sensitivity::new(self.robot(), f)?.response(g.as_slice())?;
                        h.q.iter().zip(dq.iter()).map(|(a, b)| a + b).collect()
                    }
                    None => h.q.clone(),
                };
                let eq = self.equilibrium(&h.p, f_hat, &predicted, &h.q, false)?;
                Ok((h.p, eq))
            }
        }
    }

    /// (43) `∂q/∂P = −(∂Q/∂q)⁻¹ ∂Q/∂P` (`n_q × n_pressures`, m/Pa) at the
    /// equilibrium `q` of pressures `p` and load field `f_hat`.
    ///
    /// # Errors
    /// [`Error::Singular`] if the tangent cannot be factored; dimension errors.
    pub fn dq_dp(&self, q: &[f64], p: &[f64], f_hat: &[f64]) -> Result<DMatrix<f64>> {
        adapter::dq_dp(self.robot(), &self.loads(p, f_hat), q)
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

    /// The Newton loop's `(∂x/∂P, ∂q/∂P)` at the equilibrium `q`: with the
    /// factors of its tangent when the corrector made it (solves only),
    /// else factoring with the inverse kinematics' own linear solver,
    /// analyzed once at construction.
    fn jacobian_warm(
        &mut self,
        q: &[f64],
        p: &[f64],
        f_hat: &[f64],
        factors: Option<&AutoFactors>,
    ) -> Result<(DMatrix<f64>, DMatrix<f64>)> {
        let dqdp = match factors {
            Some(f) => Sensitivity::new(self.robot(), f)?.dq_dp(q)?,
            None => {
                let loads = self.loads(p, f_hat);
                let (robot, linear) = self.tracker.model_and_linear();
                adapter::dq_dp_with(robot, &loads, q, linear)?
            }
        };
        Ok((self.effector_columns(&dqdp)?, dqdp))
    }

    /// `S(X_e) ∂q/∂P`: the end effector's rows of the columns of `dqdp`.
    fn effector_columns(&self, dqdp: &DMatrix<f64>) -> Result<DMatrix<f64>> {
        let point = self.robot().arc_point("effector", self.effector_s_m)?;
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
        check_len("f_hat", self.robot().n_q(), f_hat.len())?;
        check_all_finite("f_hat", f_hat)?;
        let np = self.range.len();
        let bounds = self.robot().pressure_bounds();
        self.spent = 0;
        let start = match self.warm.take() {
            Some(h) => Start::Warm(Box::new(h)),
            None => Start::Cold(if self.known.pressures_pa.len() == np {
                // the known pressures are checked against the bounds
                self.known.pressures_pa.clone()
            } else {
                bounds.iter().map(|(lo, _)| *lo).collect()
            }),
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
        let (mut best, first_err) = match self.solve_from(x_d, f_hat, start) {
            Ok((s, factors)) if s.status.is_reached() => {
                self.hold(&s, f_hat, factors);
                return Ok(s);
            }
            Ok((s, factors)) if near_unreached => {
                self.hold(&s, f_hat, factors);
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
        let mut iterations = best.as_ref().map_or(0, |b| b.0.iterations);
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
            let Ok(s) = self.solve_from(x_d, f_hat, Start::Cold(p)) else {
                continue;
            };
            iterations += s.0.iterations;
            if best
                .as_ref()
                .is_none_or(|b| s.0.status.error_m() < b.0.status.error_m())
            {
                let reached = s.0.status.is_reached();
                best = Some(s);
                if reached {
                    break;
                }
            }
        }
        let Some((mut best, factors)) = best else {
            return Err(first_err.unwrap_or_else(|| {
                Error::invalid(
                    "x_d",
                    format!("{x_d:?}"),
                    "no start of the inverse kinematics found an equilibrium",
                )
            }));
        };
        best.iterations = iterations;
        self.hold(&best, f_hat, factors);
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
        self.robot().validate_loads(&loads)?;
        check_len("f_hat", self.robot().n_q(), f_hat.len())?;
        check_all_finite("f_hat", f_hat)?;
        let (q, x) = self.forward_raw(p0_pa, f_hat, None)?;
        self.warm = Some(Held {
            p: p0_pa.to_vec(),
            q,
            f_hat: f_hat.to_vec(),
            x,
            factors: None,
        });
        self.unreached_target = None;
        self.solve(x_d, f_hat)
    }

    /// Keeps the solution `s` under the load field `f_hat` (and the factors
    /// of its tangent) as the next solve's warm start.
    fn hold(&mut self, s: &IkSolution, f_hat: &[f64], factors: Option<AutoFactors>) {
        self.warm = Some(Held {
            p: s.pressures_pa.as_slice().to_vec(),
            q: s.q.as_slice().to_vec(),
            f_hat: f_hat.to_vec(),
            x: s.effector_m.as_slice().to_vec(),
            factors,
        });
    }

    /// Newton from `start` (the held equilibrium, or cold at pressures);
    /// the solution and the factors of the tangent at its shape when the
    /// corrector made it.
    #[allow(non_snake_case)]
    fn solve_from(
        &mut self,
        x_d: &[f64],
        f_hat: &[f64],
        start: Start,
    ) -> Result<(IkSolution, Option<AutoFactors>)> {
        let d = E::DIM;
        let np = self.range.len();
        let (mut P, (mut q, mut x, mut factors)) = self.first_equilibrium(f_hat, start)?;
        let merit = |x: &[f64], p: &[f64], range: &[f64]| -> f64 {
            let r2: f64 = x.iter().zip(x_d).map(|(a, b)| (b - a).powi(2)).sum();
            let p2: f64 = p.iter().zip(range).map(|(p, r)| (p / r).powi(2)).sum();
            0.5 * r2 / (ELL_M * ELL_M) + 0.5 * MU * p2
        };
        let mut phi = merit(&x, &P, &self.range);
        let bounds_pa = self.robot().pressure_bounds();
        let mut iterations = 0;
        let mut stalled = false;
        let mut damping = 0.0f64;
        let mut failed_trials = 0usize;
        while iterations < self.settings.max_iterations
            && self.spent < self.settings.max_static_iterations
        {
            iterations += 1;
            let (J, dqdp) = self.jacobian_warm(&q, &P, f_hat, factors.as_ref())?;
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
                // the trial's equilibrium predicted to first order,
                // q + ∂q/∂P ΔP, corrected (the static solver from q if not)
                let dp = DVector::from_iterator(np, trial.iter().zip(&P).map(|(a, b)| a - b));
                let predicted: Vec<f64> = q
                    .iter()
                    .zip((&dqdp * dp).iter())
                    .map(|(a, b)| a + b)
                    .collect();
                let ft = self.equilibrium(&trial, f_hat, &predicted, &q, true);
                if ft.is_err() {
                    failed_trials += 1;
                }
                if let Ok((qt, xt, ft_factors)) = ft {
                    let phit = merit(&xt, &trial, &self.range);
                    if phit <= phi - 1e-4 * t * dec {
                        let ratio = (phi - phit) / dec.max(f64::MIN_POSITIVE);
                        damping = if t < 1.0 || ratio < 0.25 {
                            (4.0 * damping).max(1e-4)
                        } else if ratio > 0.75 {
                            if damping < 1e-10 { 0.0 } else { damping / 4.0 }
                        } else {
                            damping
                        };
                        P = trial;
                        q = qt;
                        x = xt;
                        factors = ft_factors;
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
        Ok((
            IkSolution {
                pressures_pa: DVector::from_vec(P),
                q: DVector::from_vec(q),
                effector_m: DVector::from_vec(x),
                status,
                iterations,
                bounds,
            },
            factors,
        ))
    }
}
