//! Planar rigid-body kinematics of a cable end fixed to a rigid body.
//!
//! A rigid body's pose in 2-D is `(x, y, θ)`: the position of its reference
//! point (its centre of mass) and its rotation. A cable node `[r, r']` fixed
//! to the body at the body-frame point `p` with the body-frame direction `d`
//! (unit) follows the pose and one stretch coordinate `σ`:
//!
//! `r = x + R(θ) p`, `r' = (1 + σ) R(θ) d`, `R(θ) = [[cos θ, −sin θ], [sin θ, cos θ]]`.
//!
//! The joint fixes where the section sits and which way it points, not how
//! much it is stretched (the same reason a clamp leaves the base stretch
//! free: the axial strain `|r'| − 1` of the element at the joint is the
//! element's, not the joint's). With `n = R p`, `e = R d` and `J` the
//! quarter turn `[[0, −1], [1, 0]]` (so `∂R/∂θ = J R`):
//!
//! - first derivatives: `∂r/∂x = I`, `∂r/∂θ = J n`, `∂r'/∂θ = (1 + σ) J e`,
//!   `∂r'/∂σ = e`;
//! - second derivatives (the only non-zero ones): `∂²r/∂θ² = −n`,
//!   `∂²r'/∂θ² = −(1 + σ) e`, `∂²r'/∂θ∂σ = J e`.
//!
//! Contracted with a vector `g` over the node's four coordinates (the
//! gradient of the potential there), the second derivative gives the
//! geometric stiffness of the joint:
//! `Σ_i g_i ∂²φ_i/∂θ² = −g_r·n − (1 + σ) g_r'·e` and
//! `Σ_i g_i ∂²φ_i/∂θ∂σ = g_r'·(J e)`.
//!
//! A rod end fixed to a body that is itself fixed to the ground has a
//! constant pose: its map is affine in `σ`, exactly a clamp.
//!
//! The 3-D counterpart (a pose `(x, ψ)` with a rotation vector, rod ends
//! of the spatial cable and of the full 3-D element) is in
//! [`SpatialAttachment`].

mod spatial;

use nalgebra::Vector2;

pub(crate) use spatial::resolve_spatial;
pub use spatial::{
    SPATIAL_END_COLUMNS, SpatialAttachment, rotate_3d, rotate_back_3d, rotation_vector_of,
};

/// `R(θ) v` for the planar rotation by `theta` (rad).
pub(crate) fn rotate(theta: f64, v: [f64; 2]) -> [f64; 2] {
    let (s, c) = theta.sin_cos();
    [c * v[0] - s * v[1], s * v[0] + c * v[1]]
}

/// `Rᵀ(θ) v`: world components to body components.
pub(crate) fn rotate_back(theta: f64, v: [f64; 2]) -> [f64; 2] {
    let (s, c) = theta.sin_cos();
    [c * v[0] + s * v[1], -s * v[0] + c * v[1]]
}

/// The quarter turn `J v = (−v_y, v_x)`.
fn quarter(v: [f64; 2]) -> [f64; 2] {
    [-v[1], v[0]]
}

/// A cable end fixed to a planar rigid body: the body-frame point `p` (m)
/// and unit direction `d` of the joint (a [`BlockRule::PlanarRigidEnd`]).
///
/// # Example
/// ```
/// use nalgebra::Vector2;
/// use softrod::structure::{rigid::PlanarAttachment, BlockRule, DofMap};
/// // a body pose (x, y, θ) and a cable node fixed to it 5 cm along its x axis
/// let a = PlanarAttachment { point_m: Vector2::new(0.05, 0.0), direction: Vector2::y() };
/// let map = DofMap::new(vec![
///     BlockRule::Free { len: 3 },
///     BlockRule::PlanarRigidEnd { body_block: 0, attachment: a },
/// ])?;
/// // the pose's three coordinates and the joint's stretch are free
/// assert_eq!(map.n_u(), 4);
/// # Ok::<(), softrod::Error>(())
/// ```
///
/// [`BlockRule::PlanarRigidEnd`]: crate::structure::BlockRule::PlanarRigidEnd
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanarAttachment {
    /// The joint's point in the body frame (m).
    pub point_m: Vector2<f64>,
    /// The rod's tangent direction at the joint in the body frame (unit).
    pub direction: Vector2<f64>,
}

impl PlanarAttachment {
    /// The cable node `[r, r']` for the body pose `(x, y, θ)` (m, m, rad) and
    /// the stretch `σ`: `r = x + R(θ) p`, `r' = (1 + σ) R(θ) d`.
    pub(crate) fn node(&self, pose: [f64; 3], stretch: f64) -> [f64; 4] {
        let n = rotate(pose[2], self.point_m.into());
        let e = rotate(pose[2], self.direction.into());
        let l = 1.0 + stretch;
        [pose[0] + n[0], pose[1] + n[1], l * e[0], l * e[1]]
    }

    /// The Jacobian of [`PlanarAttachment::node`] with respect to
    /// `(x, y, θ, σ)`: row `i` is `∂node_i/∂(x, y, θ, σ)`.
    pub(crate) fn jacobian(&self, pose: [f64; 3], stretch: f64) -> [[f64; 4]; 4] {
        let jn = quarter(rotate(pose[2], self.point_m.into()));
        let e = rotate(pose[2], self.direction.into());
        let je = quarter(e);
        let l = 1.0 + stretch;
        [
            [1.0, 0.0, jn[0], 0.0],
            [0.0, 1.0, jn[1], 0.0],
            [0.0, 0.0, l * je[0], e[0]],
            [0.0, 0.0, l * je[1], e[1]],
        ]
    }

    /// `Σ_i g_i ∂²node_i/∂(θ, σ)²` for a vector `g` over the node's four
    /// coordinates: `[[h_θθ, h_θσ], [h_θσ, 0]]` (the second derivatives in
    /// `x`, `y` vanish).
    pub(crate) fn curvature(&self, pose: [f64; 3], stretch: f64, g: [f64; 4]) -> [[f64; 2]; 2] {
        let n = rotate(pose[2], self.point_m.into());
        let e = rotate(pose[2], self.direction.into());
        let je = quarter(e);
        let l = 1.0 + stretch;
        let h_tt = -(g[0] * n[0] + g[1] * n[1]) - l * (g[2] * e[0] + g[3] * e[1]);
        let h_ts = g[2] * je[0] + g[3] * je[1];
        [[h_tt, h_ts], [h_ts, 0.0]]
    }

    /// The wrench about the body's reference point of a generalized force
    /// `f` on the node's four coordinates (`Jᵀ f` restricted to the pose):
    /// force `f_r` (N) and moment `n × f_r + (1 + σ) e × f_r'` (N·m).
    pub(crate) fn wrench(&self, pose: [f64; 3], stretch: f64, f: [f64; 4]) -> [f64; 3] {
        let jac = self.jacobian(pose, stretch);
        let mut w = [0.0; 3];
        for (k, wk) in w.iter_mut().enumerate() {
            *wk = (0..4).map(|i| jac[i][k] * f[i]).sum();
        }
        w
    }
}

/// Where a rod end sits on a rigid body: planar or in 3-D.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Attachment {
    /// A planar cable node on a planar body.
    Planar(PlanarAttachment),
    /// A spatial-cable or full 3-D node on a 3-D body.
    Spatial(SpatialAttachment),
}

#[cfg(test)]
pub(crate) use spatial::frame_of_columns;

#[cfg(test)]
mod tests {
    use super::*;

    const A: PlanarAttachment = PlanarAttachment {
        point_m: Vector2::new(0.07, -0.03),
        direction: Vector2::new(0.6, 0.8),
    };

    fn node(v: [f64; 4]) -> [f64; 4] {
        A.node([v[0], v[1], v[2]], v[3])
    }

    #[test]
    fn a_turned_body_carries_its_end() {
        let a = PlanarAttachment {
            point_m: Vector2::new(0.05, 0.0),
            direction: Vector2::new(0.0, 1.0),
        };
        // a body at (0, 0.2) turned by 90°: the end sits at (0, 0.25), pointing along −x
        let node = a.node([0.0, 0.2, std::f64::consts::FRAC_PI_2], 0.0);
        assert!((node[1] - 0.25).abs() < 1e-15 && (node[2] + 1.0).abs() < 1e-15);
        let v = rotate(std::f64::consts::FRAC_PI_2, [1.0, 0.0]);
        assert!(v[0].abs() < 1e-15 && (v[1] - 1.0).abs() < 1e-15);
        let v = rotate_back(0.3, rotate(0.3, [0.2, -0.7]));
        assert!((v[0] - 0.2).abs() < 1e-15 && (v[1] + 0.7).abs() < 1e-15);
    }

    /// Jacobian and contracted second derivative against central
    /// differences at a turned, stretched pose.
    #[test]
    fn jacobian_and_curvature_match_finite_differences() {
        let v = [0.1, -0.2, 0.9, 0.03];
        let g = [0.3, -1.1, 0.7, 0.25];
        let jac = A.jacobian([v[0], v[1], v[2]], v[3]);
        let h = 1e-6;
        let mut worst_j = 0.0f64;
        for k in 0..4 {
            let (mut vp, mut vm) = (v, v);
            vp[k] += h;
            vm[k] -= h;
            let (np, nm) = (node(vp), node(vm));
            for i in 0..4 {
                let fd = (np[i] - nm[i]) / (2.0 * h);
                worst_j = worst_j.max((fd - jac[i][k]).abs());
            }
        }
        assert!(worst_j < 1e-9, "Jacobian: {worst_j:e}");
        // d/du_k (Σ_i g_i ∂φ_i/∂u_l) over (θ, σ) and zero in x, y
        let full = |v: [f64; 4]| {
            let j = A.jacobian([v[0], v[1], v[2]], v[3]);
            let mut c = [0.0; 4];
            for (l, cl) in c.iter_mut().enumerate() {
                *cl = (0..4).map(|i| g[i] * j[i][l]).sum();
            }
            c
        };
        let curv = A.curvature([v[0], v[1], v[2]], v[3], g);
        let mut worst_h = 0.0f64;
        for k in 0..4 {
            let (mut vp, mut vm) = (v, v);
            vp[k] += h;
            vm[k] -= h;
            let (cp, cm) = (full(vp), full(vm));
            for l in 0..4 {
                let fd = (cp[l] - cm[l]) / (2.0 * h);
                let an = if k >= 2 && l >= 2 {
                    curv[k - 2][l - 2]
                } else {
                    0.0
                };
                worst_h = worst_h.max((fd - an).abs());
            }
        }
        println!("attachment FD: Jacobian {worst_j:.1e}, second derivative {worst_h:.1e}");
        assert!(worst_h < 1e-9, "second derivative: {worst_h:e}");
    }

    #[test]
    fn wrench_is_force_and_moment_about_the_reference_point() {
        // a pure force on r at the point: moment n × f
        let pose = [0.0, 0.0, 0.0];
        let w = A.wrench(pose, 0.0, [0.0, 2.0, 0.0, 0.0]);
        assert!((w[0]).abs() < 1e-15 && (w[1] - 2.0).abs() < 1e-15);
        assert!((w[2] - 0.07 * 2.0).abs() < 1e-15);
    }
}
