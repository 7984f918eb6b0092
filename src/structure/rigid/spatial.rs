//! A rod end fixed to a rigid body in 3-D.
//!
//! A rigid body's pose in 3-D is `(x, ψ)`: the position `x` of its reference
//! point (its centre of mass) and its rotation vector `ψ` (rad), the
//! rotation `R(ψ) = exp([ψ]ₓ)` by the angle `|ψ|` about `ψ/|ψ|`
//! (Rodrigues: `R v = v + f₁ ψ × v + f₂ ψ × (ψ × v)`, `f₁ = sin θ/θ`,
//! `f₂ = (1 − cos θ)/θ²`, `θ = |ψ|`, both written as series in `θ²` so
//! that `ψ = 0` is regular).
//!
//! A rod node fixed to the body at the body-frame point `p`, with the
//! body-frame section frame `[d a₂ a₃]` (orthonormal, `d` the rod's
//! tangent), follows the pose and one stretch `σ`:
//!
//! - a spatial-cable node `[r, r']` (6 coordinates): `r = x + R p`,
//!   `r' = (1 + σ) R d`;
//! - a full 3-D node `[r, r_X, r_Y, r_Z]` (12 coordinates): the same, and
//!   `r_Y = R a₂`, `r_Z = R a₃`: the section frame is the body's, turned
//!   with it (what a rigid joint means), the stretch free as at a clamp.
//!
//! A spatial cable has no section frame: its joint fixes the tangent, and
//! a torque about the tangent reaches the body through nothing but the
//! other legs' bending. That is the difference the parallel robot measures.
//!
//! The Jacobian and the contracted second derivative
//! `Σ_i g_i ∂²node_i/∂(ψ, σ)²` are computed with second-order jets
//! (the exact derivatives by the chain rule); the second derivatives in `x`
//! vanish (the node is affine in `x`).

use nalgebra::{Matrix3, Vector3};

use crate::element::jet::{Jet, Scalar, cross};
use crate::error::{Error, Result};

/// Terms of the series of `f₁`, `f₂` (the terms fall like `θ^{2k}/(2k)!`:
/// below round-off for `θ < 2π` long before the last).
const SERIES_TERMS: usize = 40;

/// `f₁(s) = sin θ/θ`, `f₂(s) = (1 − cos θ)/θ²` with `s = θ²`, and their
/// first two derivatives in `s`: `(f, f', f'')` each.
fn rodrigues_factors(s: f64) -> ([f64; 3], [f64; 3]) {
    // f1 = Σ (−s)^k/(2k+1)!, f2 = Σ (−s)^k/(2k+2)!
    let (mut f1, mut f2) = ([0.0; 3], [0.0; 3]);
    let mut c1 = 1.0; // (−1)^k/(2k+1)!
    let mut c2 = 0.5; // (−1)^k/(2k+2)!
    let (mut p0, mut p1, mut p2) = (1.0, 0.0, 0.0); // s^k, s^(k−1), s^(k−2)
    for k in 0..SERIES_TERMS {
        let kf = k as f64;
        f1[0] += c1 * p0;
        f2[0] += c2 * p0;
        f1[1] += c1 * kf * p1;
        f2[1] += c2 * kf * p1;
        f1[2] += c1 * kf * (kf - 1.0) * p2;
        f2[2] += c2 * kf * (kf - 1.0) * p2;
        c1 /= -(2.0 * kf + 2.0) * (2.0 * kf + 3.0);
        c2 /= -(2.0 * kf + 3.0) * (2.0 * kf + 4.0);
        p2 = p1;
        p1 = p0;
        p0 *= s;
    }
    (f1, f2)
}

/// `R(ψ) v` over any scalar.
fn rotate_generic<T: Scalar>(psi: &[T; 3], v: [f64; 3]) -> [T; 3] {
    let s = psi[0] * psi[0] + psi[1] * psi[1] + psi[2] * psi[2];
    let (a, b) = rodrigues_factors(s.value());
    let f1 = s.map(a[0], a[1], a[2]);
    let f2 = s.map(b[0], b[1], b[2]);
    let vt = v.map(T::cst);
    let pv = cross(psi, &vt);
    let ppv = cross(psi, &pv);
    std::array::from_fn(|i| vt[i] + f1 * pv[i] + f2 * ppv[i])
}

/// `R(ψ) v` on arrays (the kernels' form of [`rotate_3d`]).
pub(crate) fn rot3(psi: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    rotate_generic(&psi, v)
}

/// `Rᵀ(ψ) v` on arrays (the kernels' form of [`rotate_back_3d`]).
pub(crate) fn rot3_back(psi: [f64; 3], v: [f64; 3]) -> [f64; 3] {
    rotate_generic(&psi.map(|x| -x), v)
}

/// `R(ψ) v`: the rotation by the rotation vector `psi` (rad) of `v`.
///
/// # Example
/// ```
/// use nalgebra::Vector3;
/// use softrod::structure::rigid::rotate_3d;
/// // a quarter turn about z takes x to y
/// let v = rotate_3d(Vector3::new(0.0, 0.0, std::f64::consts::FRAC_PI_2), Vector3::x());
/// assert!((v - Vector3::y()).norm() < 1e-15);
/// ```
pub fn rotate_3d(psi: Vector3<f64>, v: Vector3<f64>) -> Vector3<f64> {
    rot3(psi.into(), v.into()).into()
}

/// `Rᵀ(ψ) v = R(−ψ) v`: world components to body components.
///
/// # Example
/// ```
/// use nalgebra::Vector3;
/// use softrod::structure::rigid::{rotate_3d, rotate_back_3d};
/// let psi = Vector3::new(0.3, -0.2, 0.5);
/// let v = rotate_back_3d(psi, rotate_3d(psi, Vector3::new(0.2, -0.7, 0.1)));
/// assert!((v - Vector3::new(0.2, -0.7, 0.1)).norm() < 1e-15);
/// ```
pub fn rotate_back_3d(psi: Vector3<f64>, v: Vector3<f64>) -> Vector3<f64> {
    rot3_back(psi.into(), v.into()).into()
}

/// The rotation vector of a rotation matrix (the inverse of [`rotate_3d`]
/// for angles below π; the axis from the skew part, the angle from the
/// trace).
///
/// # Example
/// ```
/// use nalgebra::{Matrix3, Vector3};
/// use softrod::structure::rigid::{rotate_3d, rotation_vector_of};
/// let psi = Vector3::new(0.1, -0.4, 0.25);
/// let r = Matrix3::from_columns(&[Vector3::x(), Vector3::y(), Vector3::z()].map(|e| rotate_3d(psi, e)));
/// assert!((rotation_vector_of(&r) - psi).norm() < 1e-14);
/// ```
pub fn rotation_vector_of(r: &Matrix3<f64>) -> Vector3<f64> {
    rotvec_of(std::array::from_fn(|j| [r[(0, j)], r[(1, j)], r[(2, j)]])).into()
}

/// [`rotation_vector_of`] on the matrix's columns.
fn rotvec_of(cols: [[f64; 3]; 3]) -> [f64; 3] {
    // R[i][j] = cols[j][i]
    let r = |i: usize, j: usize| cols[j][i];
    let w = [r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1)];
    let sin2 = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt(); // 2 sin θ
    let cos = 0.5 * (r(0, 0) + r(1, 1) + r(2, 2) - 1.0);
    let theta = (0.5 * sin2).atan2(cos);
    let factor = if theta < 1e-8 { 0.5 } else { theta / sin2 };
    w.map(|x| factor * x)
}

/// A rod end fixed to a rigid body in 3-D: the body-frame point `p` (m) and
/// the body-frame section frame `[d, a₂, a₃]` (unit, right-handed), for a
/// node of `node_dofs` coordinates (6: spatial cable; 12: full 3-D element).
///
/// # Example
/// ```
/// use nalgebra::{Matrix3, Vector3};
/// use softrod::structure::rigid::SpatialAttachment;
/// // a rod end 5 cm along the body's x axis, its tangent along the body's −z
/// let frame = Matrix3::from_columns(&[-Vector3::z(), Vector3::y(), Vector3::x()]);
/// let a = SpatialAttachment::new(Vector3::new(0.05, 0.0, 0.0), frame, 12)?;
/// assert_eq!(a.frame.column(0), -Vector3::z());
/// // a left-handed frame is refused
/// let bad = Matrix3::from_columns(&[-Vector3::z(), Vector3::y(), -Vector3::x()]);
/// assert_eq!(SpatialAttachment::new(Vector3::zeros(), bad, 12).unwrap_err().field(), Some("frame"));
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpatialAttachment {
    /// The joint's point in the body frame (m).
    pub point_m: Vector3<f64>,
    /// The section frame at the joint in the body frame, by columns: the
    /// rod's tangent `d`, then the section axes `a₂`, `a₃`.
    pub frame: Matrix3<f64>,
    /// Coordinates of the joined node (6 or 12).
    pub node_dofs: usize,
}

/// Columns of a spatial rigid end's Jacobian: the pose `(x, ψ)` and `σ`.
pub const SPATIAL_END_COLUMNS: usize = 7;

impl SpatialAttachment {
    /// Checks the numbers: a finite point, an orthonormal right-handed
    /// frame (to 1e-9), 6 or 12 node coordinates.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `point_m`, `frame` or `node_dofs`.
    ///
    /// # Example
    /// See [`SpatialAttachment`].
    pub fn new(point_m: Vector3<f64>, frame: Matrix3<f64>, node_dofs: usize) -> Result<Self> {
        let a = SpatialAttachment {
            point_m,
            frame,
            node_dofs,
        };
        a.check()?;
        Ok(a)
    }

    /// The checks of [`SpatialAttachment::new`].
    ///
    /// # Errors
    /// As [`SpatialAttachment::new`].
    ///
    /// # Example
    /// ```
    /// use nalgebra::{Matrix3, Vector3};
    /// use softrod::structure::rigid::SpatialAttachment;
    /// let mut a = SpatialAttachment::new(Vector3::zeros(), Matrix3::identity(), 6)?;
    /// a.point_m.x = f64::NAN;
    /// assert_eq!(a.check().unwrap_err().field(), Some("point_m"));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn check(&self) -> Result<()> {
        if !self.point_m.iter().all(|v| v.is_finite()) {
            return Err(Error::invalid(
                "point_m",
                format!("{:?}", self.point_m),
                "must be finite",
            ));
        }
        if self.node_dofs != 6 && self.node_dofs != 12 {
            return Err(Error::invalid(
                "node_dofs",
                self.node_dofs,
                "a rigid end joins a 6-coordinate (spatial cable) or 12-coordinate (full 3-D) node",
            ));
        }
        let f = [self.axis(0), self.axis(1), self.axis(2)];
        let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        let mut off = 0.0f64;
        for i in 0..3 {
            for j in 0..3 {
                let want = if i == j { 1.0 } else { 0.0 };
                off = off.max((dot(&f[i], &f[j]) - want).abs());
            }
        }
        let c = cross(&f[0], &f[1]);
        off = off.max((0..3).map(|i| (c[i] - f[2][i]).abs()).fold(0.0, f64::max));
        if off.is_nan() || off > 1e-9 {
            return Err(Error::invalid(
                "frame",
                format!("{f:?}"),
                "must be orthonormal and right-handed (tangent, then the section axes)",
            ));
        }
        Ok(())
    }

    /// The body-frame point as an array.
    fn point(&self) -> [f64; 3] {
        self.point_m.into()
    }

    /// Column `k` of the section frame as an array.
    fn axis(&self, k: usize) -> [f64; 3] {
        [self.frame[(0, k)], self.frame[(1, k)], self.frame[(2, k)]]
    }

    /// The node and its derivatives in `(ψ, σ)` as jets.
    fn node_jet(&self, pose: [f64; 6], stretch: f64) -> [Jet<4>; 12] {
        let psi: [Jet<4>; 3] = std::array::from_fn(|i| Jet::var(pose[3 + i], i));
        let l = Jet::var(1.0 + stretch, 3);
        let n = rotate_generic(&psi, self.point());
        let e = rotate_generic(&psi, self.axis(0));
        let mut out = [Jet::cst(0.0); 12];
        for i in 0..3 {
            out[i] = n[i] + Jet::cst(pose[i]);
            out[3 + i] = l * e[i];
        }
        if self.node_dofs == 12 {
            let a2 = rotate_generic(&psi, self.axis(1));
            let a3 = rotate_generic(&psi, self.axis(2));
            out[6..9].copy_from_slice(&a2);
            out[9..12].copy_from_slice(&a3);
        }
        out
    }

    /// The node (`node_dofs` coordinates; the rest zero) for the body pose
    /// `(x, ψ)` (m, rad) and the stretch `σ`.
    pub(crate) fn node(&self, pose: [f64; 6], stretch: f64) -> [f64; 12] {
        let psi = [pose[3], pose[4], pose[5]];
        let n = rot3(psi, self.point());
        let e = rot3(psi, self.axis(0));
        let l = 1.0 + stretch;
        let mut out = [0.0; 12];
        for i in 0..3 {
            out[i] = pose[i] + n[i];
            out[3 + i] = l * e[i];
        }
        if self.node_dofs == 12 {
            let a2 = rot3(psi, self.axis(1));
            let a3 = rot3(psi, self.axis(2));
            out[6..9].copy_from_slice(&a2);
            out[9..12].copy_from_slice(&a3);
        }
        out
    }

    /// The Jacobian of [`SpatialAttachment::node`] with respect to
    /// `(x, ψ, σ)`: row `i` is `∂node_i/∂(x₁, x₂, x₃, ψ₁, ψ₂, ψ₃, σ)` (rows
    /// past `node_dofs` zero).
    pub(crate) fn jacobian(
        &self,
        pose: [f64; 6],
        stretch: f64,
    ) -> [[f64; SPATIAL_END_COLUMNS]; 12] {
        let jet = self.node_jet(pose, stretch);
        let mut jac = [[0.0; SPATIAL_END_COLUMNS]; 12];
        for (i, (row, j)) in jac.iter_mut().zip(&jet).enumerate().take(self.node_dofs) {
            if i < 3 {
                row[i] = 1.0;
            }
            row[3..].copy_from_slice(&j.g);
        }
        jac
    }

    /// `Σ_i g_i ∂²node_i/∂(ψ, σ)²` (4 × 4) for a vector `g` over the node's
    /// coordinates (the second derivatives in `x` vanish).
    pub(crate) fn curvature(&self, pose: [f64; 6], stretch: f64, g: &[f64]) -> [[f64; 4]; 4] {
        let jet = self.node_jet(pose, stretch);
        let mut c = [[0.0; 4]; 4];
        for (j, gi) in jet.iter().zip(g).take(self.node_dofs) {
            for (a, row) in c.iter_mut().enumerate() {
                for (b, x) in row.iter_mut().enumerate() {
                    *x += gi * j.h[a][b];
                }
            }
        }
        c
    }

    /// The wrench about the body's reference point of a generalized force
    /// `f` on the node's coordinates, in the pose's coordinates
    /// (`Jᵀ f` restricted to `(x, ψ)`): the force (N) and the moment
    /// conjugate to `ψ` (N·m; at `ψ = 0` the moment about the reference
    /// point in world axes).
    pub(crate) fn wrench(&self, pose: [f64; 6], stretch: f64, f: &[f64]) -> [f64; 6] {
        let jac = self.jacobian(pose, stretch);
        let mut w = [0.0; 6];
        for (k, wk) in w.iter_mut().enumerate() {
            *wk = jac
                .iter()
                .zip(f)
                .take(self.node_dofs)
                .map(|(row, fi)| row[k] * fi)
                .sum();
        }
        w
    }

    /// The stretch `σ = (R(ψ) d)·r' − 1` of a node `node` at the body's
    /// rotation `psi` (the nearest on the map; exact on it).
    pub(crate) fn stretch_of(&self, psi: [f64; 3], node: &[f64]) -> f64 {
        let e = rot3(psi, self.axis(0));
        match node.get(3..6) {
            Some(s) => e[0] * s[0] + e[1] * s[1] + e[2] * s[2] - 1.0,
            None => f64::NAN,
        }
    }
}

/// The attachment of a rod end to a body in the reference: the end of the
/// rod's straight reference at `end_m` with the unit tangent `dir`, the
/// body at `body_m` turned by `body_psi`; a given `point_m` or `direction`
/// (body frame) must agree with the reference (to `tol` of `length_m`, and
/// `tol`). The section axes are those a straight full 3-D rod carries
/// along `dir` (the element's `straight_node`), in the body frame. Errors
/// name `{path}point_m` / `{path}direction`.
/// The matrix whose columns are `cols`.
pub(crate) fn frame_of_columns(cols: [[f64; 3]; 3]) -> Matrix3<f64> {
    Matrix3::from_fn(|i, j| cols[j][i])
}

#[allow(clippy::too_many_arguments)]
pub(crate) fn resolve_spatial(
    path: &str,
    end_m: [f64; 3],
    dir: [f64; 3],
    body_m: [f64; 3],
    body_psi: [f64; 3],
    point_m: &Option<Vec<f64>>,
    direction: &Option<Vec<f64>>,
    length_m: f64,
    tol: f64,
    node_dofs: usize,
) -> Result<SpatialAttachment> {
    use crate::element::{Ancf3d, NodeKinematics};
    let rel = [
        end_m[0] - body_m[0],
        end_m[1] - body_m[1],
        end_m[2] - body_m[2],
    ];
    let reference_point = rot3_back(body_psi, rel);
    let node = Ancf3d::straight_node(&end_m, &dir);
    let axis = |k: usize| -> [f64; 3] {
        let v = [node[k], node[k + 1], node[k + 2]];
        rot3_back(body_psi, v)
    };
    let frame = [axis(3), axis(6), axis(9)];
    let point = match point_m {
        None => reference_point,
        Some(v) => {
            crate::error::check_len(&format!("{path}point_m"), 3, v.len())?;
            crate::error::check_all_finite(&format!("{path}point_m"), v)?;
            let gap = (0..3)
                .map(|i| (v[i] - reference_point[i]).powi(2))
                .sum::<f64>()
                .sqrt();
            if gap.is_nan() || gap > tol * length_m {
                return Err(Error::invalid(
                    format!("{path}point_m"),
                    format!("{v:?}"),
                    format!(
                        "puts the joint {gap:.3e} m from the rod's end in the reference \
                         (its end is at {reference_point:?} in the body frame)"
                    ),
                ));
            }
            [v[0], v[1], v[2]]
        }
    };
    if let Some(v) = direction {
        crate::error::check_len(&format!("{path}direction"), 3, v.len())?;
        crate::error::check_all_finite(&format!("{path}direction"), v)?;
        let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        let off = if n > 0.0 {
            (0..3)
                .map(|i| (v[i] / n - frame[0][i]).powi(2))
                .sum::<f64>()
                .sqrt()
        } else {
            f64::INFINITY
        };
        if off.is_nan() || off > tol {
            return Err(Error::invalid(
                format!("{path}direction"),
                format!("{v:?}"),
                format!(
                    "differs from the rod's direction {:?} (body frame) in the reference",
                    frame[0]
                ),
            ));
        }
    }
    SpatialAttachment::new(Vector3::from(point), frame_of_columns(frame), node_dofs)
        .map_err(|e| e.with_prefix(path))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn attachment(nd: usize) -> SpatialAttachment {
        // a tangent tilted off z with its section frame
        let d = [0.36, 0.48, 0.8];
        let a2 = [0.8, -0.6, 0.0];
        let a3 = cross(&d, &a2);
        SpatialAttachment::new(
            Vector3::new(0.07, -0.03, 0.02),
            frame_of_columns([d, a2, a3]),
            nd,
        )
        .unwrap()
    }

    /// Jacobian and contracted second derivative of both node kinds against
    /// central differences at a turned, stretched pose (and at ψ = 0, where
    /// the series matters most).
    #[test]
    fn jacobian_and_curvature_match_finite_differences() {
        for nd in [6, 12] {
            let a = attachment(nd);
            for pose in [
                [0.1, -0.2, 0.3, 0.4, -0.7, 0.9],
                [0.0, 0.0, 0.2, 0.0, 0.0, 0.0],
            ] {
                let v: Vec<f64> = pose.iter().copied().chain([0.03]).collect();
                let node = |v: &[f64]| a.node([v[0], v[1], v[2], v[3], v[4], v[5]], v[6]);
                let jac = a.jacobian(pose, v[6]);
                let h = 1e-6;
                let mut worst_j = 0.0f64;
                for k in 0..7 {
                    let (mut vp, mut vm) = (v.clone(), v.clone());
                    vp[k] += h;
                    vm[k] -= h;
                    let (np, nm) = (node(&vp), node(&vm));
                    for i in 0..12 {
                        let fd = (np[i] - nm[i]) / (2.0 * h);
                        worst_j = worst_j.max((fd - jac[i][k]).abs());
                    }
                }
                assert!(worst_j < 1e-9, "{nd}: Jacobian {worst_j:e}");
                let g: Vec<f64> = (0..nd).map(|i| ((i as f64) * 1.3 + 0.4).sin()).collect();
                let full = |v: &[f64]| {
                    let j = a.jacobian([v[0], v[1], v[2], v[3], v[4], v[5]], v[6]);
                    let mut c = [0.0; 7];
                    for (l, cl) in c.iter_mut().enumerate() {
                        *cl = (0..nd).map(|i| g[i] * j[i][l]).sum();
                    }
                    c
                };
                let curv = a.curvature(pose, v[6], &g);
                let mut worst_h = 0.0f64;
                for k in 0..7 {
                    let (mut vp, mut vm) = (v.clone(), v.clone());
                    vp[k] += h;
                    vm[k] -= h;
                    let (cp, cm) = (full(&vp), full(&vm));
                    for l in 0..7 {
                        let fd = (cp[l] - cm[l]) / (2.0 * h);
                        let an = if k >= 3 && l >= 3 {
                            curv[k - 3][l - 3]
                        } else {
                            0.0
                        };
                        worst_h = worst_h.max((fd - an).abs());
                    }
                }
                println!(
                    "spatial attachment {nd} FD: Jacobian {worst_j:.1e}, second derivative {worst_h:.1e}"
                );
                assert!(worst_h < 1e-8, "{nd}: second derivative {worst_h:e}");
                assert!(curv.iter().flatten().any(|x| x.abs() > 0.1));
            }
        }
    }

    /// Rodrigues against a rotation built by hand: a turn about a unit axis
    /// keeps the axis, turns a normal vector by the angle.
    #[test]
    fn rotation_is_the_rotation_about_the_vector() {
        let axis = [0.6, 0.0, 0.8];
        let angle = 2.5;
        let psi = axis.map(|x| x * angle);
        let r = rot3(psi, axis);
        assert!((0..3).all(|i| (r[i] - axis[i]).abs() < 1e-14));
        let n = [0.0, 1.0, 0.0];
        let rn = rot3(psi, n);
        let c = rn[1];
        assert!((c - angle.cos()).abs() < 1e-14);
        let w = cross(&axis, &n);
        let s: f64 = (0..3).map(|i| rn[i] * w[i]).sum();
        assert!((s - angle.sin()).abs() < 1e-14);
        let back =
            rotvec_of([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(|e| rot3(psi, e)));
        assert!((0..3).all(|i| (back[i] - psi[i]).abs() < 1e-12));
    }

    #[test]
    fn a_turned_body_carries_its_end() {
        let a = SpatialAttachment::new(
            Vector3::new(0.05, 0.0, 0.0),
            frame_of_columns([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]),
            12,
        )
        .unwrap();
        // the body at (0, 0, 0.2), turned by 90° about z: the end sits at (0, 0.05, 0.2)
        let node = a.node([0.0, 0.0, 0.2, 0.0, 0.0, std::f64::consts::FRAC_PI_2], 0.0);
        assert!((node[1] - 0.05).abs() < 1e-15 && (node[5] + 1.0).abs() < 1e-15);
        // and back: R^T R v = v
        let psi = [0.3, -0.2, 0.5];
        let v = rot3_back(psi, rot3(psi, [0.2, -0.7, 0.1]));
        assert!((v[0] - 0.2).abs() < 1e-15 && (v[1] + 0.7).abs() < 1e-15);
    }

    #[test]
    fn bad_frames_are_refused() {
        let e = SpatialAttachment::new(
            Vector3::zeros(),
            frame_of_columns([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]]),
            12,
        )
        .unwrap_err();
        assert_eq!(e.field(), Some("frame"));
        let e = SpatialAttachment::new(Vector3::zeros(), Matrix3::identity(), 4).unwrap_err();
        assert_eq!(e.field(), Some("node_dofs"));
    }
}
