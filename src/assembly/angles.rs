//! Tangent angles of a planar robot, unwrapped along the backbone.
//!
//! `atan2` gives an angle in `(−π, π]`; a rod rolled into a full circle
//! turns by `2π`. The angle here is continuous in the arc coordinate: it
//! starts at the base tangent's `atan2` and follows the tangent through
//! every node and element midpoint, taking the turn between two samples in
//! `(−π, π]` (an element would have to turn by more than π between its end
//! and its midpoint to fool it).

use super::Robot;
use crate::element::PlanarCable;
use crate::error::{Result, check_len};

/// The wrapped difference `a − b` in `(−π, π]`.
fn turn(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    if d > std::f64::consts::PI {
        d - std::f64::consts::TAU
    } else {
        d
    }
}

impl Robot<PlanarCable> {
    /// The tangent angle from the x axis (rad) at every node of `q`,
    /// unwrapped along the backbone (a full circle ends at `2π`).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `q` does not have
    /// [`Robot::n_q`] entries.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::loads::{Loads, NodeMoment};
    /// use softrod::statics::StaticSolver;
    /// // a tip moment 2π EI / L rolls the rod into a full circle
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 32)]).build_planar()?;
    /// let m = std::f64::consts::TAU * 0.025 / 0.24;
    /// let loads = Loads { node_moments: vec![NodeMoment { node: 32, moment_nm: vec![m] }], ..Loads::default() };
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let angles = robot.node_angles(eq.q.as_slice())?;
    /// let tip = angles[angles.len() - 1];
    /// assert!((tip - std::f64::consts::TAU).abs() < 1e-4); // atan2 alone: about 0
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn node_angles(&self, q: &[f64]) -> Result<nalgebra::DVector<f64>> {
        check_len("q", self.n_q(), q.len())?;
        let slope_angle = |e: usize, xi: f64| -> Result<f64> {
            let arc = self.node_arc();
            let p = crate::element::ArcPoint::new(e, xi, arc[e + 1] - arc[e]);
            let mut t = [0.0; 2];
            p.slope_into(q, &mut t)?;
            Ok(t[1].atan2(t[0]))
        };
        let mut out = Vec::with_capacity(self.n_nodes());
        let mut angle = slope_angle(0, 0.0)?;
        out.push(angle);
        for e in 0..self.n_elements() {
            for xi in [0.5, 1.0] {
                let raw = slope_angle(e, xi)?;
                angle += turn(raw, angle);
            }
            out.push(angle);
        }
        Ok(nalgebra::DVector::from_vec(out))
    }

    /// The unwrapped tangent angle (rad) at arc coordinate `s_m` (m), as
    /// [`Robot::node_angles`] continued into the element holding `s_m`.
    ///
    /// # Errors
    /// As [`Robot::node_angles`]; [`crate::Error::InvalidParameter`] named
    /// `s_m` if it is off the robot.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.025, 4)]).build_planar()?;
    /// let q = robot.reference_configuration();
    /// assert_eq!(robot.angle_at(q.as_slice(), 0.13)?, 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn angle_at(&self, q: &[f64], s_m: f64) -> Result<f64> {
        let nodes = self.node_angles(q)?;
        let p = self.arc_point("s_m", s_m)?;
        let mut t = [0.0; 2];
        p.slope_into(q, &mut t)?;
        let start = nodes[p.element];
        // through the element's midpoint when s lies beyond it
        let mid = crate::element::ArcPoint::new(p.element, 0.5_f64.min(p.xi), p.length_m);
        let mut m = [0.0; 2];
        mid.slope_into(q, &mut m)?;
        let a_mid = start + turn(m[1].atan2(m[0]), start);
        Ok(a_mid + turn(t[1].atan2(t[0]), a_mid))
    }
}
