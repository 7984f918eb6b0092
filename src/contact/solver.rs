//! The contact solver: SQP with clarabel QPs, then Newton on the KKT system
//! of the active contacts.

use std::time::Instant;

use clarabel::solver::SolverStatus;
use nalgebra::{DMatrix, DVector, Vector2};
use serde::{Deserialize, Serialize};

pub use super::settings::ContactSettings;

use super::qp::solve_qp;
use super::start::cold_start;
use super::{Gap, Obstacles};
use crate::assembly::Robot;
use crate::element::PlanarCable;
use crate::error::{Result, check_all_finite, check_len};
use crate::linsolve::BandedMatrix;
use crate::loads::Loads;
use crate::numeric::norm2;
use crate::outcome::{ContactReport, ContactStatus, NonFiniteAt};
use crate::statics::residual_floor;

/// An active contact of a solution.
///
/// # Example
/// ```
/// use softrod::assembly::{RobotSpec, Section};
/// use softrod::contact::{ContactSolver, Obstacle, Obstacles};
/// use softrod::loads::{Loads, PointForce};
/// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 12)]).build_planar()?;
/// // a disk 3 cm below the rod's middle, rod radius 5 mm
/// let obstacles = Obstacles::new(vec![Obstacle::Circle { center_m: [0.12, -0.045], radius_m: 0.01 }], 0.005)?;
/// let loads = Loads { point_forces: vec![PointForce { s_m: 0.24, force_n: vec![0.0, -1.0] }], ..Loads::default() };
/// let sol = ContactSolver::default().solve(&robot, &loads, &obstacles, None)?;
/// let c = &sol.contacts[0];
/// assert!(c.obstacle == 0 && c.force_n > 0.0 && c.gap_m.abs() < 1e-9);
/// // the force on the rod pushes it away from the disk: up
/// assert!(c.normal[1] > 0.0);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactForce {
    /// Index of the obstacle.
    pub obstacle: usize,
    /// Undeformed arc coordinate of the contact point (m).
    pub s_m: f64,
    /// The centreline point in contact (m); the obstacle's surface is
    /// `rod_radius_m + gap_m` from it along `−normal`.
    pub point_m: [f64; 2],
    /// Outward normal of the obstacle: the direction of the force on the rod.
    pub normal: [f64; 2],
    /// Magnitude of the contact force on the rod (N, `>= 0`).
    pub force_n: f64,
    /// The gap there (m; zero to the tolerance).
    pub gap_m: f64,
}

impl ContactForce {
    /// The centreline point in contact (m), typed.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::contact::ContactForce;
    /// let c = ContactForce { obstacle: 0, s_m: 0.1, point_m: [0.1, -0.02], normal: [0.0, 1.0], force_n: 0.5, gap_m: 0.0 };
    /// assert_eq!(c.point(), Vector2::new(0.1, -0.02));
    /// ```
    pub fn point(&self) -> Vector2<f64> {
        Vector2::from(self.point_m)
    }

    /// The obstacle's outward unit normal: the direction of the force on the
    /// rod, typed.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::contact::ContactForce;
    /// let c = ContactForce { obstacle: 0, s_m: 0.1, point_m: [0.1, -0.02], normal: [0.0, 1.0], force_n: 0.5, gap_m: 0.0 };
    /// assert_eq!(c.direction(), Vector2::new(0.0, 1.0));
    /// ```
    pub fn direction(&self) -> Vector2<f64> {
        Vector2::from(self.normal)
    }

    /// The contact force on the rod (N): `force_n` along the normal.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::contact::ContactForce;
    /// let c = ContactForce { obstacle: 0, s_m: 0.1, point_m: [0.1, -0.02], normal: [0.0, 1.0], force_n: 0.5, gap_m: 0.0 };
    /// assert_eq!(c.force(), Vector2::new(0.0, 0.5));
    /// ```
    pub fn force(&self) -> Vector2<f64> {
        self.force_n * self.direction()
    }
}

/// The result of a contact solve: the last iterate, its contacts and the
/// report. Only a [`ContactStatus::Converged`] status certifies the shape.
///
/// # Example
/// ```
/// use softrod::assembly::{RobotSpec, Section};
/// use softrod::contact::{ContactSolver, Obstacle, Obstacles};
/// use softrod::loads::{Loads, PointForce};
/// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 12)]).build_planar()?;
/// // a disk 3 cm below the rod's middle, rod radius 5 mm
/// let obstacles = Obstacles::new(vec![Obstacle::Circle { center_m: [0.12, -0.045], radius_m: 0.01 }], 0.005)?;
/// let loads = Loads { point_forces: vec![PointForce { s_m: 0.24, force_n: vec![0.0, -1.0] }], ..Loads::default() };
/// let sol = ContactSolver::default().solve(&robot, &loads, &obstacles, None)?;
/// assert!(sol.is_converged() && sol.report.min_gap_m >= -1e-10);
/// assert_eq!(sol.q.len(), robot.n_q());
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ContactSolution {
    /// All coordinates, base node included.
    pub q: DVector<f64>,
    /// Every contact with a force, base to tip.
    pub contacts: Vec<ContactForce>,
    /// What the solver did.
    pub report: ContactReport,
}

impl ContactSolution {
    /// Whether the solve converged to a non-penetrating equilibrium.
    pub fn is_converged(&self) -> bool {
        self.report.status.is_converged()
    }
}

/// The contact solver (see the module docs).
///
/// Cost: the KKT systems are dense (`O(n³)` in the free coordinates), meant
/// for robots of up to a few hundred elements.
///
/// # Example
/// ```
/// use softrod::assembly::{RobotSpec, Section};
/// use softrod::contact::{ContactSolver, Obstacle, Obstacles};
/// use softrod::loads::{Loads, PointForce};
/// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 12)]).build_planar()?;
/// // a disk 3 cm below the rod's middle, rod radius 5 mm
/// let obstacles = Obstacles::new(vec![Obstacle::Circle { center_m: [0.12, -0.045], radius_m: 0.01 }], 0.005)?;
/// let loads = Loads { point_forces: vec![PointForce { s_m: 0.24, force_n: vec![0.0, -1.0] }], ..Loads::default() };
/// let sol = ContactSolver::default().solve(&robot, &loads, &obstacles, None)?;
/// assert!(sol.is_converged());
/// println!("{}", sol.report);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, Default)]
pub struct ContactSolver {
    /// Settings.
    pub settings: ContactSettings,
}

/// Smallest force of an active contact in an SQP step, relative to the
/// largest: above the QP's multipliers of open gaps (measured up to 2e-8 at
/// a fingertip near several circles; taken as active they over-constrained
/// the point and the polish's KKT system was singular). A second test, in
/// `qp::solve_qp`, drops the multiplier of every gap the step leaves
/// open, which this ratio cannot do when no gap carries a force.
const ACTIVE_FORCE_RATIO: f64 = 1e-6;

/// SQP steps at round-off, each after a failed polish, before a solve
/// ends [`ContactStatus::Stalled`].
const MAX_STALLS: usize = 3;

/// One active contact during the solve: its obstacle, where it is, its force.
#[derive(Debug, Clone, Copy)]
struct Active {
    obstacle: usize,
    s: f64,
    lambda: f64,
}

/// The map of one element's 8 coordinates into the free coordinates.
pub(super) struct ElementMap {
    /// For element 0: the base node's coordinates per free base direction.
    base_cols: Vec<Vec<f64>>,
    nbf: usize,
}

impl ElementMap {
    pub(super) fn new(robot: &Robot<PlanarCable>) -> Result<Self> {
        let nbf = robot.n_base_free();
        let mut base_cols = Vec::with_capacity(nbf);
        for j in 0..nbf {
            let mut u = vec![0.0; robot.n_free()];
            u[j] = 1.0;
            base_cols.push(robot.expand_step(&u)?.as_slice()[..4].to_vec());
        }
        Ok(ElementMap { base_cols, nbf })
    }
    /// The trust region of one SQP step per free coordinate: `position_m`
    /// for a node position (or a base freedom that moves one), `slope`
    /// for a node slope.
    fn step_bounds(&self, n: usize, position_m: f64, slope: f64) -> Vec<f64> {
        (0..n)
            .map(|j| {
                let moves_position = if j < self.nbf {
                    self.base_cols[j][..2].iter().any(|c| *c != 0.0)
                } else {
                    (j - self.nbf) % 4 < 2
                };
                if moves_position { position_m } else { slope }
            })
            .collect()
    }
    /// `(u index, coefficient)` pairs of element coordinate `a` of element `e`.
    fn of(&self, e: usize, a: usize) -> Vec<(usize, f64)> {
        let qi = 4 * e + a;
        if qi >= 4 {
            vec![(qi - 4 + self.nbf, 1.0)]
        } else {
            self.base_cols
                .iter()
                .enumerate()
                .filter(|(_, c)| c[qi] != 0.0)
                .map(|(j, c)| (j, c[qi]))
                .collect()
        }
    }
    pub(super) fn gradient(&self, g: &Gap, n: usize) -> Vec<f64> {
        let mut out = vec![0.0; n];
        for a in 0..8 {
            for (u, c) in self.of(g.element, a) {
                out[u] += c * g.gradient[a];
            }
        }
        out
    }
    pub(super) fn add_hessian(&self, g: &Gap, scale: f64, h: &mut DMatrix<f64>) {
        for a in 0..8 {
            for (ua, ca) in self.of(g.element, a) {
                for b in 0..8 {
                    for (ub, cb) in self.of(g.element, b) {
                        h[(ua, ub)] += scale * ca * cb * g.hessian[(a, b)];
                    }
                }
            }
        }
    }
}

/// Everything fixed during one solve.
struct Ctx<'a> {
    robot: &'a Robot<PlanarCable>,
    loads: &'a Loads,
    obstacles: &'a Obstacles,
    dead: Vec<f64>,
    map: ElementMap,
    n: usize,
    /// Norm of the applied generalized forces (N).
    scale: f64,
}

impl Ctx<'_> {
    fn residual(&self, q: &[f64]) -> Result<Vec<f64>> {
        Ok(self.robot.residual(q, &self.dead, self.loads)?.data.into())
    }
    fn tangent(&self, q: &[f64]) -> Result<DMatrix<f64>> {
        let hb = 7;
        let mut band = BandedMatrix::zeros(self.n, hb, hb);
        self.robot.tangent_into(q, self.loads, &mut band)?;
        let mut k = DMatrix::zeros(self.n, self.n);
        for i in 0..self.n {
            for j in i.saturating_sub(hb)..(i + hb + 1).min(self.n) {
                k[(i, j)] = band.get(i, j);
            }
        }
        Ok(k)
    }
    fn expand(&self, du: &[f64]) -> Result<Vec<f64>> {
        Ok(self.robot.expand_step(du)?.data.into())
    }
    /// The tolerance of the KKT residual at `q` with tangent `k` (N).
    fn tolerance(&self, q: &[f64], k: &DMatrix<f64>, rel: f64) -> f64 {
        let kmax = k.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let qmax = q.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        (rel * self.scale).max(4.0 * residual_floor(kmax, qmax, self.n))
    }
    /// Total penetration `Σ max(0, −g)` (m) and the smallest gap.
    fn penetration(&self, q: &[f64]) -> Result<(f64, f64)> {
        let gaps = self.obstacles.gaps(self.robot, q)?;
        let pen = gaps.iter().map(|g| (-g.gap_m).max(0.0)).sum();
        let min = gaps.iter().map(|g| g.gap_m).fold(f64::MAX, f64::min);
        Ok((pen, min))
    }
    /// The largest change of a node slope in `dq`.
    fn slope_change(&self, dq: &[f64]) -> f64 {
        dq.chunks(4)
            .flat_map(|c| c[2..].iter())
            .fold(0.0f64, |m, v| m.max(v.abs()))
    }
}

/// The gap of `gaps` that continues the active contact `a`: the same
/// obstacle, nearest in arc, not taken already.
fn continue_gap(gaps: &[Gap], a: &Active, taken: &[usize]) -> Option<usize> {
    gaps.iter()
        .enumerate()
        .filter(|(i, g)| g.obstacle == a.obstacle && !taken.contains(i))
        .min_by(|(_, x), (_, y)| (x.s_m - a.s).abs().total_cmp(&(y.s_m - a.s).abs()))
        .map(|(i, _)| i)
}

impl ContactSolver {
    /// A solver with the given settings.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`](crate::Error::InvalidParameter) if the settings are invalid.
    ///
    /// # Example
    /// ```
    /// use softrod::contact::{ContactSettings, ContactSolver};
    /// let bad = ContactSettings { penetration_tolerance_m: 1e-6, ..Default::default() };
    /// assert_eq!(ContactSolver::new(bad).unwrap_err().field(), Some("penetration_tolerance_m"));
    /// ```
    pub fn new(settings: ContactSettings) -> Result<Self> {
        settings.validate()?;
        Ok(ContactSolver { settings })
    }

    /// The equilibrium of `robot` under `loads` among `obstacles`, from `q0`
    /// (all `n_q` coordinates) or, cold, from the shapes of the actuation
    /// alone ([`Robot::arc_configuration`]) followed as the pressures grow
    /// from zero up to the last one that touches no obstacle (so a start is
    /// never beyond a thin obstacle that the loading path meets). The SQP's
    /// steps are bounded and their linearized gaps keep them on the near
    /// side of every obstacle, so the solve follows the loading from the
    /// start: an obstacle the free equilibrium would pass through is met,
    /// not tunnelled.
    ///
    /// # Errors
    /// Bad input only: the settings ([`ContactSettings::validate`]), the
    /// loads ([`Robot::validate_loads`]), an obstacle overlapping the
    /// robot's base or reference configuration
    /// ([`Obstacles::check_robot`]), a `q0` of the wrong size or not finite.
    /// A solve that fails returns its last iterate with the status that
    /// says why.
    pub fn solve(
        &self,
        robot: &Robot<PlanarCable>,
        loads: &Loads,
        obstacles: &Obstacles,
        q0: Option<&[f64]>,
    ) -> Result<ContactSolution> {
        let start = Instant::now();
        self.settings.validate()?;
        obstacles.check_robot(robot)?;
        let dead: Vec<f64> = robot.dead_force(loads)?.data.into();
        let n = robot.n_free();
        let mut applied: Vec<f64> = robot.restrict(&dead)?.data.into();
        let mut m = vec![0.0; n];
        robot.moment_force_into(robot.reference_configuration().as_slice(), loads, &mut m)?;
        applied.iter_mut().zip(&m).for_each(|(a, b)| *a += b);
        let ctx = Ctx {
            robot,
            loads,
            obstacles,
            dead,
            map: ElementMap::new(robot)?,
            n,
            scale: norm2(&applied),
        };
        let mut report = ContactReport::default();
        let mut q = match q0 {
            Some(q0) => {
                check_len("q0", robot.n_q(), q0.len())?;
                check_all_finite("q0", q0)?;
                self.with_clamp(robot, q0)?
            }
            // not the free equilibrium nor the actuation's shape, even if
            // they do not penetrate: they may lie beyond an obstacle the
            // loading path meets
            None => cold_start(robot, &loads.pressures_pa, obstacles)?,
        };
        let (status, active) = self.sqp(&ctx, &mut q, &mut report)?;
        report.status = status;
        let (_, min) = ctx.penetration(&q)?;
        report.min_gap_m = if min.is_finite() { min } else { f64::MAX };
        // never a penetrating shape as converged
        if report.status.is_converged()
            && (min.is_nan() || min < -self.settings.penetration_tolerance_m)
        {
            report.status = ContactStatus::Infeasible {
                penetration_m: -min,
            };
        }
        let gaps = obstacles.gaps(robot, &q)?;
        let mut contacts = Vec::new();
        let mut taken = Vec::new();
        for a in active.iter().filter(|a| a.lambda > 0.0) {
            if let Some(i) = continue_gap(&gaps, a, &taken) {
                taken.push(i);
                let g = &gaps[i];
                contacts.push(ContactForce {
                    obstacle: g.obstacle,
                    s_m: g.s_m,
                    point_m: g.point_m.into(),
                    normal: g.normal.into(),
                    force_n: a.lambda,
                    gap_m: g.gap_m,
                });
            }
        }
        contacts.sort_by(|a, b| a.s_m.total_cmp(&b.s_m));
        report.wall_time_s = start.elapsed().as_secs_f64();
        Ok(ContactSolution {
            q: DVector::from_vec(q),
            contacts,
            report,
        })
    }

    /// `q0` with the clamp's base position and direction reset (its
    /// stretch kept).
    fn with_clamp(&self, robot: &Robot<PlanarCable>, q0: &[f64]) -> Result<Vec<f64>> {
        let base = robot.base_node();
        let mut u = vec![0.0; robot.n_free()];
        let nbf = robot.n_base_free();
        for j in 0..nbf {
            let mut e = vec![0.0; robot.n_free()];
            e[j] = 1.0;
            let col = robot.expand_step(&e)?;
            let num: f64 = (0..4).map(|i| col[i] * (q0[i] - base[i])).sum();
            let den: f64 = (0..4).map(|i| col[i] * col[i]).sum();
            if den > 0.0 {
                u[j] = num / den;
            }
        }
        let dq = robot.expand_step(&u)?;
        let mut q = q0.to_vec();
        for i in 0..4 {
            q[i] = base[i] + dq[i];
        }
        Ok(q)
    }

    /// SQP iterations from `q` (updated in place), then the polish.
    fn sqp(
        &self,
        ctx: &Ctx<'_>,
        q: &mut Vec<f64>,
        report: &mut ContactReport,
    ) -> Result<(ContactStatus, Vec<Active>)> {
        let n = ctx.n;
        let l = ctx.robot.length();
        let mut active: Vec<Active> = Vec::new();
        let mut prev_set: Vec<usize> = Vec::new();
        let mut nu = 0.0f64;
        let mut stalls = 0;
        // The QP's step is bounded (a rotation of `max_step_rotation` moves
        // no point further than that times the length): an unbounded step
        // far from the solution reaches through the linearization of a far
        // obstacle, whose constraint then binds a meaningless step and
        // leaves clarabel without progress.
        let rot = self.settings.max_step_rotation;
        let bounds = ctx.map.step_bounds(n, rot * l, rot);
        for it in 0..self.settings.max_iterations {
            report.sqp_iterations = it + 1;
            let gaps = ctx.obstacles.gaps(ctx.robot, q)?;
            let r = ctx.residual(q)?;
            let mut h = ctx.tangent(q)?;
            if !(norm2(&r).is_finite() && h.iter().all(|v| v.is_finite())) {
                return Ok((
                    ContactStatus::NonFinite {
                        at: NonFiniteAt::Residual,
                    },
                    active,
                ));
            }
            // the Lagrangian's Hessian with the last forces
            let mut taken = Vec::new();
            for a in &active {
                if let Some(i) = continue_gap(&gaps, a, &taken) {
                    taken.push(i);
                    ctx.map.add_hessian(&gaps[i], -a.lambda, &mut h);
                }
            }
            let grads: Vec<Vec<f64>> = gaps.iter().map(|g| ctx.map.gradient(g, n)).collect();
            let (du, lambda) = match solve_qp(&h, &r, &gaps, &grads, &bounds) {
                Ok(x) => x,
                Err(status) => {
                    let pen = gaps.iter().map(|g| (-g.gap_m).max(0.0)).fold(0.0, f64::max);
                    return Ok((
                        match status {
                            SolverStatus::PrimalInfeasible
                            | SolverStatus::AlmostPrimalInfeasible => {
                                ContactStatus::Infeasible { penetration_m: pen }
                            }
                            other => ContactStatus::QpFailed { status: other },
                        },
                        active,
                    ));
                }
            };
            let lmax = lambda.iter().fold(0.0f64, |m, v| m.max(*v));
            let is_active = |lam: f64| lam > ACTIVE_FORCE_RATIO * lmax.max(1e-300);
            active = gaps
                .iter()
                .zip(&lambda)
                .filter(|(_, lam)| is_active(**lam))
                .map(|(g, lam)| Active {
                    obstacle: g.obstacle,
                    s: g.s_m,
                    lambda: *lam,
                })
                .collect();
            let set: Vec<usize> = active.iter().map(|a| a.obstacle).collect();
            let dq = ctx.expand(&du)?;
            let step = dq.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            // polish once the step is small or the active set settled
            let polished = step <= 1e-6 * l || (set == prev_set && step <= 1e-2 * l);
            if polished && let Some((qp, act)) = self.try_polish(ctx, q, &active, report)? {
                *q = qp;
                return Ok((ContactStatus::Converged, act));
            }
            prev_set = set;
            // line search on Π + ν Σ max(0, −g)
            nu = nu.max(2.0 * lmax);
            let pen0: f64 = gaps.iter().map(|g| (-g.gap_m).max(0.0)).sum();
            let slope: f64 = -r.iter().zip(&du).map(|(a, b)| a * b).sum::<f64>() - nu * pen0;
            let sc = ctx.slope_change(&dq);
            let mut t = if sc > self.settings.max_step_rotation {
                self.settings.max_step_rotation / sc
            } else {
                1.0
            };
            let mut accepted = false;
            let mut trial = q.clone();
            for _ in 0..40 {
                for ((x, a), b) in trial.iter_mut().zip(q.iter()).zip(&dq) {
                    *x = a + t * b;
                }
                let dpi = ctx
                    .robot
                    .potential_change(q, &trial, &ctx.dead, ctx.loads)?;
                let (pen, _) = ctx.penetration(&trial)?;
                let dphi = dpi + nu * (pen - pen0);
                if dphi.is_finite() && dphi <= 1e-4 * t * slope.min(0.0) {
                    accepted = true;
                    break;
                }
                t *= 0.5;
            }
            if !accepted {
                if !polished && let Some((qp, act)) = self.try_polish(ctx, q, &active, report)? {
                    *q = qp;
                    return Ok((ContactStatus::Converged, act));
                }
                return Ok((ContactStatus::LineSearchFailed, active));
            }
            q.copy_from_slice(&trial);
            if step * t <= 1e-13 * l {
                if !polished && let Some((qp, act)) = self.try_polish(ctx, q, &active, report)? {
                    *q = qp;
                    return Ok((ContactStatus::Converged, act));
                }
                // the iterate no longer moves and its polish failed: more
                // iterations repeat the same QP and the same polish
                // (measured: a released finger whose 52 open gaps all kept
                // a multiplier ran 200 SQP + 11 640 Newton iterations, 43 s,
                // to IterationLimit)
                stalls += 1;
                if stalls >= MAX_STALLS {
                    return Ok((
                        ContactStatus::Stalled {
                            active_contacts: active.len(),
                        },
                        active,
                    ));
                }
            } else {
                stalls = 0;
            }
        }
        Ok((
            ContactStatus::IterationLimit {
                iterations: self.settings.max_iterations,
            },
            active,
        ))
    }

    /// The polish from `q` with the SQP's active set; if it fails, once more
    /// with only the contacts of that set whose gap is closed (below
    /// `1e-6 L`): where the SQP has stopped, an open gap carries no force,
    /// and a multiplier the QP left on it would over-constrain the KKT
    /// system. The solution's coordinates and active set, if either passes.
    fn try_polish(
        &self,
        ctx: &Ctx<'_>,
        q: &[f64],
        active: &[Active],
        report: &mut ContactReport,
    ) -> Result<Option<(Vec<f64>, Vec<Active>)>> {
        let mut trial = q.to_vec();
        let mut act = active.to_vec();
        if self.polish(ctx, &mut trial, &mut act, report)? {
            return Ok(Some((trial, act)));
        }
        let gaps = ctx.obstacles.gaps(ctx.robot, q)?;
        let closed_m = 1e-6 * ctx.robot.length();
        let mut taken = Vec::new();
        let mut closed = Vec::new();
        for a in active {
            if let Some(i) = continue_gap(&gaps, a, &taken) {
                taken.push(i);
                if gaps[i].gap_m <= closed_m {
                    closed.push(*a);
                }
            }
        }
        if closed.len() == active.len() {
            return Ok(None);
        }
        let mut trial = q.to_vec();
        if self.polish(ctx, &mut trial, &mut closed, report)? {
            return Ok(Some((trial, closed)));
        }
        Ok(None)
    }

    /// Newton's method on the KKT system of the active set `act` from `q`:
    /// `−Q − Gᵀλ = 0`, `g_A = 0`, then the checks (every force pushes, no
    /// other gap below the penetration tolerance), changing the set while
    /// they fail. `true` with `q` and `act` at the solution.
    fn polish(
        &self,
        ctx: &Ctx<'_>,
        q: &mut [f64],
        act: &mut Vec<Active>,
        report: &mut ContactReport,
    ) -> Result<bool> {
        if polish_disabled() {
            return Ok(false);
        }
        let n = ctx.n;
        let l = ctx.robot.length();
        let gtol = 1e-14 * l.max(q.iter().fold(0.0f64, |m, v| m.max(v.abs())));
        for _ in 0..self.settings.max_active_set_changes {
            let mut converged = false;
            let mut last = (f64::INFINITY, f64::INFINITY);
            for _ in 0..self.settings.max_newton_iterations {
                let gaps = ctx.obstacles.gaps(ctx.robot, q)?;
                let mut idx = Vec::with_capacity(act.len());
                for a in act.iter() {
                    match continue_gap(&gaps, a, &idx) {
                        Some(i) => idx.push(i),
                        None => return Ok(false),
                    }
                }
                for (a, &i) in act.iter_mut().zip(&idx) {
                    a.s = gaps[i].s_m;
                }
                let r = ctx.residual(q)?;
                let k = ctx.tangent(q)?;
                let mut hl = k.clone();
                let mut f: Vec<f64> = r.iter().map(|v| -v).collect();
                let grads: Vec<Vec<f64>> =
                    idx.iter().map(|&i| ctx.map.gradient(&gaps[i], n)).collect();
                for (a, (&i, gr)) in act.iter().zip(idx.iter().zip(&grads)) {
                    ctx.map.add_hessian(&gaps[i], -a.lambda, &mut hl);
                    f.iter_mut().zip(gr).for_each(|(x, g)| *x -= a.lambda * g);
                }
                let fnorm = norm2(&f);
                let cmax = idx.iter().map(|&i| gaps[i].gap_m.abs()).fold(0.0, f64::max);
                let tol = ctx.tolerance(q, &k, self.settings.residual_tolerance);
                report.residual_norm_n = fnorm;
                report.residual_tolerance_n = tol;
                if !(fnorm.is_finite() && cmax.is_finite()) {
                    return Ok(false);
                }
                if fnorm <= tol && cmax <= gtol {
                    converged = true;
                    break;
                }
                // stagnation at round-off after the tolerances are met loosely
                if fnorm >= 0.5 * last.0
                    && cmax >= 0.5 * last.1
                    && fnorm <= 10.0 * tol
                    && cmax <= 1e3 * gtol
                {
                    converged = true;
                    break;
                }
                last = (fnorm, cmax);
                let m = act.len();
                let mut kkt = DMatrix::zeros(n + m, n + m);
                kkt.view_mut((0, 0), (n, n)).copy_from(&hl);
                let mut rhs = DVector::zeros(n + m);
                for i in 0..n {
                    rhs[i] = -f[i];
                }
                for (j, (gr, &i)) in grads.iter().zip(&idx).enumerate() {
                    for (c, v) in gr.iter().enumerate() {
                        kkt[(c, n + j)] = -v;
                        kkt[(n + j, c)] = -v;
                    }
                    rhs[n + j] = gaps[i].gap_m;
                }
                let Some(x) = kkt.lu().solve(&rhs) else {
                    return Ok(false);
                };
                if !x.iter().all(|v| v.is_finite()) {
                    return Ok(false);
                }
                report.newton_iterations += 1;
                let du: Vec<f64> = x.iter().take(n).copied().collect();
                let dq = ctx.expand(&du)?;
                let sc = ctx.slope_change(&dq);
                let t = if sc > self.settings.max_step_rotation {
                    self.settings.max_step_rotation / sc
                } else {
                    1.0
                };
                q.iter_mut().zip(&dq).for_each(|(a, b)| *a += t * b);
                for (j, a) in act.iter_mut().enumerate() {
                    a.lambda += t * x[n + j];
                }
            }
            if !converged {
                return Ok(false);
            }
            // every force pushes
            let lmax = act.iter().fold(0.0f64, |m, a| m.max(a.lambda.abs()));
            if let Some((j, a)) = act
                .iter()
                .enumerate()
                .min_by(|x, y| x.1.lambda.total_cmp(&y.1.lambda))
                && a.lambda < -1e-9 * lmax.max(ctx.scale)
            {
                act.remove(j);
                continue;
            }
            // no other gap is closed
            let gaps = ctx.obstacles.gaps(ctx.robot, q)?;
            let mut idx = Vec::new();
            for a in act.iter() {
                if let Some(i) = continue_gap(&gaps, a, &idx) {
                    idx.push(i);
                }
            }
            let worst = gaps
                .iter()
                .enumerate()
                .filter(|(i, _)| !idx.contains(i))
                .min_by(|x, y| x.1.gap_m.total_cmp(&y.1.gap_m));
            match worst {
                Some((_, g)) if g.gap_m < -self.settings.penetration_tolerance_m => {
                    act.push(Active {
                        obstacle: g.obstacle,
                        s: g.s_m,
                        lambda: 0.0,
                    });
                }
                _ => {
                    act.iter_mut().for_each(|a| a.lambda = a.lambda.max(0.0));
                    return Ok(true);
                }
            }
        }
        Ok(false)
    }
}

#[cfg(test)]
fn polish_disabled() -> bool {
    super::faults::NO_POLISH.with(|f| f.get())
}

#[cfg(not(test))]
fn polish_disabled() -> bool {
    false
}
