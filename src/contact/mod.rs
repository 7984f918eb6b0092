//! Frictionless contact of a planar robot with rigid obstacles fixed in the
//! world (circles, capsules, convex polygons), exactly: the equilibrium is
//! the minimum of the total potential energy subject to non-penetration,
//!
//! `min Π(u)  subject to  g_j(u) ≥ 0`,
//!
//! `g_j` the gap between the rod's surface (its centreline offset by the rod
//! radius) and an obstacle, and the multipliers `λ_j ≥ 0` are the contact
//! forces (N), acting on the rod along the obstacle's outward normal. A
//! penalty would bias the force by `O(1/k)` and a barrier acts before
//! touching; here nothing acts until the gap closes and nothing penetrates.
//!
//! Gaps (`gap`): one per local minimum, along the rod, of the distance to
//! each obstacle, found exactly (the closest point of a cubic Hermite
//! element to a point is the root of a quintic; every real root in the
//! element is isolated), so there is no sampling density to choose: the
//! constraint follows the closest point as the rod slides, and a node shared
//! by two elements is one candidate (no duplicate constraints). Limitation:
//! point-wise gaps; a rod lying flat along a polygon's edge (a contact
//! spread over a segment) is represented by its local minima only.
//!
//! Solver ([`ContactSolver`]): SQP on the free coordinates; each QP (the
//! tangent stiffness, the linearized gaps) is solved by clarabel, whose
//! multipliers are the contact forces, with a line search on the potential
//! plus an exact penalty on penetration. Once the set of active contacts
//! settles, Newton's method on the KKT system of that set (the gaps'
//! Hessians included) polishes the solution to round-off, and the result is
//! accepted only if every force pushes and no gap is below
//! `−penetration_tolerance_m`.
//!
//! # Example
//! ```
//! use softrod::assembly::{RobotSpec, Section};
//! use softrod::contact::{ContactSolver, Obstacle, Obstacles};
//! use softrod::loads::{Loads, PointForce};
//! let mut spec = RobotSpec::new(vec![Section::uniform(1.0, 1e4, 1.0, 8)]);
//! spec.gravity_m_per_s2 = vec![0.0, 0.0];
//! let robot = spec.build_planar()?;
//! // a support touching the rod's underside at a = 0.5 m, a small tip load P
//! let obstacles = Obstacles::new(vec![Obstacle::Circle { center_m: [0.5, -0.001], radius_m: 0.001 }], 0.0)?;
//! let p = 1e-5;
//! let loads = Loads { point_forces: vec![PointForce { s_m: 1.0, force_n: vec![0.0, -p] }], ..Loads::default() };
//! let sol = ContactSolver::default().solve(&robot, &loads, &obstacles, None)?;
//! assert!(sol.report.status.is_converged());
//! // the propped cantilever: R = P (3L − a) / (2a)
//! assert!((sol.contacts[0].force_n / (p * 2.5) - 1.0).abs() < 1e-6);
//! # Ok::<(), softrod::Error>(())
//! ```

mod gap;
mod obstacle;
mod qp;
mod settings;
mod solver;
mod start;

pub use gap::Gap;
pub use obstacle::{MAX_OBSTACLE_EXTENT_M, Obstacle, SignedDistance};
pub use solver::{ContactForce, ContactSettings, ContactSolution, ContactSolver};

use crate::assembly::Robot;
use crate::element::{Element, PlanarCable};
use crate::error::{Error, Result, check_len};
use gap::{Cubic, element_candidates, gap_at, gap_value};

/// Validated obstacles and the rod radius the gaps are measured from.
///
/// # Example
/// ```
/// use softrod::contact::{Obstacle, Obstacles};
/// let bad = Obstacles::new(vec![Obstacle::Circle { center_m: [0.0, f64::NAN], radius_m: 0.1 }], 0.01);
/// assert_eq!(bad.unwrap_err().field(), Some("obstacles[0].center_m"));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Obstacles {
    obstacles: Vec<Obstacle>,
    rod_radius_m: f64,
}

impl Obstacles {
    /// Checks every obstacle ([`Obstacle::validate`], paths `obstacles[i]`)
    /// and the rod radius (finite, `>= 0`; 0 puts the contact on the
    /// centreline).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field.
    pub fn new(obstacles: Vec<Obstacle>, rod_radius_m: f64) -> Result<Self> {
        if !(rod_radius_m.is_finite() && rod_radius_m >= 0.0) {
            return Err(Error::invalid(
                "rod_radius_m",
                rod_radius_m,
                "must be finite and >= 0",
            ));
        }
        for (i, o) in obstacles.iter().enumerate() {
            o.validate(&format!("obstacles[{i}]"))?;
        }
        Ok(Obstacles {
            obstacles,
            rod_radius_m,
        })
    }

    /// The obstacles.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// The rod radius (m).
    pub fn rod_radius_m(&self) -> f64 {
        self.rod_radius_m
    }

    /// Checks the obstacles against a robot: none may overlap its base
    /// point or its reference (straight) configuration (touching is allowed:
    /// a gap down to `−1e-12 L`).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `obstacles[i]`.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::contact::{Obstacle, Obstacles};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let o = Obstacles::new(vec![Obstacle::Circle { center_m: [0.1, 0.0], radius_m: 0.01 }], 0.0)?;
    /// assert_eq!(o.check_robot(&robot).unwrap_err().field(), Some("obstacles[0]"));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn check_robot(&self, robot: &Robot<PlanarCable>) -> Result<()> {
        let tol = 1e-12 * robot.length();
        let base = robot.base_node();
        let base = [base[0], base[1]];
        for (i, o) in self.obstacles.iter().enumerate() {
            let g = o.signed_distance(nalgebra::Vector2::from(base)).distance_m - self.rod_radius_m;
            if g.is_nan() || g < -tol {
                return Err(Error::invalid(
                    format!("obstacles[{i}]"),
                    format!("{o:?}"),
                    format!("overlaps the robot's base (gap {g:e} m)"),
                ));
            }
        }
        let q = robot.reference_configuration();
        for g in self.gaps(robot, q.as_slice())? {
            if g.gap_m.is_nan() || g.gap_m < -tol {
                return Err(Error::invalid(
                    format!("obstacles[{}]", g.obstacle),
                    format!("{:?}", self.obstacles[g.obstacle]),
                    format!(
                        "overlaps the robot's reference configuration (gap {:e} m at s = {} m)",
                        g.gap_m, g.s_m
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Every gap of the configuration `q` (all `n_q` coordinates): for
    /// each obstacle, each local minimum along the rod of the distance from
    /// the rod's surface, with its derivatives (see [`Gap`]). Minima farther
    /// than the robot's length are left out (they cannot close in one
    /// step), and so is the clamped base point.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `q` does not have `n_q` entries.
    pub fn gaps(&self, robot: &Robot<PlanarCable>, q: &[f64]) -> Result<Vec<Gap>> {
        check_len("q", robot.n_q(), q.len())?;
        let screen = robot.length();
        let arcs = robot.node_arc();
        let n_el = robot.n_elements();
        let mut out = Vec::new();
        for (oi, o) in self.obstacles.iter().enumerate() {
            // (s, gap, element, ξ) in arc order, each node once
            let mut seq: Vec<(f64, f64, usize, f64)> = Vec::new();
            for (e, el) in robot.elements().iter().enumerate() {
                let qe = &q[4 * e..4 * e + 8];
                let le = el.length();
                let cubic = Cubic::new(qe, le);
                // the curve lies in the hull of its Bézier points, so within
                // `rad` of their mean; the distance is 1-Lipschitz
                let bez = [
                    [qe[0], qe[1]],
                    [qe[0] + le * qe[2] / 3.0, qe[1] + le * qe[3] / 3.0],
                    [qe[4] - le * qe[6] / 3.0, qe[5] - le * qe[7] / 3.0],
                    [qe[4], qe[5]],
                ];
                let mid = [
                    bez.iter().map(|p| p[0]).sum::<f64>() / 4.0,
                    bez.iter().map(|p| p[1]).sum::<f64>() / 4.0,
                ];
                let rad = bez
                    .iter()
                    .map(|p| ((p[0] - mid[0]).powi(2) + (p[1] - mid[1]).powi(2)).sqrt())
                    .fold(0.0, f64::max);
                let far = o.signed_distance(nalgebra::Vector2::from(mid)).distance_m
                    - rad
                    - self.rod_radius_m
                    > screen;
                let xs = if far {
                    vec![0.0, 1.0]
                } else {
                    element_candidates(&cubic, o)
                };
                for xi in xs {
                    if xi == 1.0 && e + 1 < n_el {
                        continue;
                    }
                    let g = gap_value(o, self.rod_radius_m, &cubic, xi);
                    seq.push((arcs[e] + xi * le, g, e, xi));
                }
            }
            let len = seq.len();
            for k in 1..len {
                let g = seq[k].1;
                let left = seq[k - 1].1 > g;
                let right = k + 1 == len || g <= seq[k + 1].1;
                if !(left && right) || g > screen {
                    continue;
                }
                let (s, _, e, xi) = seq[k];
                let el = &robot.elements()[e];
                let tip = k + 1 == len;
                out.push(gap_at(
                    oi,
                    o,
                    self.rod_radius_m,
                    e,
                    s,
                    &q[4 * e..4 * e + 8],
                    el.length(),
                    xi,
                    !tip,
                ));
            }
        }
        Ok(out)
    }
}

/// Faults the unit tests inject (per thread) to reach the paths a solve
/// takes when the QP's active set is wrong or the polish cannot converge.
#[cfg(test)]
pub(crate) mod faults {
    use std::cell::Cell;
    thread_local! {
        /// Every QP multiplier counts, even of a gap the step leaves open.
        pub(crate) static NO_COMPLEMENTARITY: Cell<bool> = const { Cell::new(false) };
        /// Every polish fails.
        pub(crate) static NO_POLISH: Cell<bool> = const { Cell::new(false) };
    }
}

#[cfg(test)]
mod tests;
