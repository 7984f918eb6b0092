//! The stiffness of the follower loads ([`crate::loads::FollowerLoad`]).
//!
//! A follower load's generalized force is `Q = C q`, `C` constant and not
//! symmetric, so its stiffness `−C` is not symmetric either. The tangent
//! the static solver factors ([`Robot::tangent_into`]) is symmetric: it
//! holds the symmetric part `−(C + Cᵀ)/2`. The rest, `−(C − Cᵀ)/2`, lives at
//! the two ends of each loaded piece only (integration by parts:
//! `C − Cᵀ = p [Sᵀ J S]` there), is of the size `p` (N/m) against a
//! bending stiffness `EI/L³`, and is left to the Newton iteration: with
//! follower loads the iteration converges linearly at a rate of about
//! `p L³ / EI` instead of quadratically. [`Robot::follower_stiffness`] gives
//! the full matrix.

use super::Robot;
use crate::element::Element;
use crate::error::Result;
use crate::loads::Loads;
use crate::structure::rod::MAX_EDOF;

/// `(m + mᵀ)/2` of a row-major 8 × 8 matrix.
pub(super) fn symmetric_part(m: &[f64; 64]) -> [f64; 64] {
    let mut s = [0.0; 64];
    for i in 0..8 {
        for j in 0..8 {
            s[i * 8 + j] = 0.5 * (m[i * 8 + j] + m[j * 8 + i]);
        }
    }
    s
}

impl<E: Element> Robot<E> {
    /// The full stiffness `−∂Q/∂u` of the follower loads of `loads` over
    /// the free coordinates (`n_free × n_free`, dense, not symmetric; it
    /// does not depend on the configuration). [`Robot::tangent_into`] holds
    /// its symmetric part; this minus its transpose, halved, is what the
    /// symmetric tangent leaves out.
    ///
    /// # Errors
    /// As [`Robot::validate_loads`].
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::loads::{FollowerLoad, Loads};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 4)]).build_planar()?;
    /// let loads = Loads { follower_loads: vec![FollowerLoad { pressure_n_per_m: 2.0,
    ///     s_start_m: None, s_end_m: None }], ..Loads::default() };
    /// let k = robot.follower_stiffness(&loads)?;
    /// let skew = (&k - k.transpose()) * 0.5;
    /// // the antisymmetric part is p/2 J at the tip's position only
    /// let n = robot.n_free();
    /// assert!((skew[(n - 4, n - 3)] - 1.0).abs() < 1e-12);
    /// assert!(skew.iter().map(|v| v.abs()).sum::<f64>() - 2.0 < 1e-12);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn follower_stiffness(&self, loads: &Loads) -> Result<nalgebra::DMatrix<f64>> {
        self.validate_loads(loads)?;
        let nd = E::NODE_DOFS;
        let edof = 2 * nd;
        let mut k = nalgebra::DMatrix::zeros(self.n_free(), self.n_free());
        self.rod.for_each_follower_element(loads, |e, m| {
            let dofs: Vec<usize> = (e * nd..e * nd + edof.min(MAX_EDOF)).collect();
            self.dofs.add_stiffness(&[], &dofs, m, -1.0, &mut k)
        })?;
        Ok(k)
    }
}
