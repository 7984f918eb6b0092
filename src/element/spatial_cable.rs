//! The spatial ANCF cable (3-D, 6 coordinates per node, `q_i = [r_i, r_i']`):
//! the cubic Hermite centreline (14), (16) of the planar cable in space, with
//! the energy (19) `U_E = ½ ∫ (EA ε² + EI |κ|²) dX`, `ε = |r'| − 1` and the
//! curvature vector `κ = r' × r'' / (r'·r')`.
//!
//! Bending is isotropic (one EI for both bending planes) and the cable has no
//! torsion and no section frame: there is no rest curvature (a rest
//! curvature vector would need a frame to say in which plane the rest shape
//! bends), and a moment along the tangent does no work.
//!
//! # Derivatives per Gauss point
//! With `a = r'`, `b = r''`, `d = a·a`, `c = a × b`, `κ = c/d` and the skew
//! matrix `[v]ₓ w = v × w`, the Jacobian of `κ` with respect to `z = (a, b)` is
//! `J_a = −([b]ₓ + 2 κ aᵀ)/d`, `J_b = [a]ₓ/d`, so the bending energy density
//! `½ EI |κ|²` has the gradient `EI Jᵀ κ = EI ((b × κ − 2|κ|² a)/d, (κ × a)/d)`
//! and the Hessian `EI (Jᵀ J + Σ_i κ_i ∇²κ_i)`, where
//! `Σ_i κ_i ∇²κ_i` has the blocks
//! `aa: −2 (v_a aᵀ + a v_aᵀ)/d² + |κ|² (8 a aᵀ/d² − 2 I/d)`,
//! `ab: −[κ]ₓ/d − 2 a v_bᵀ/d²`, `ba` its transpose, `bb: 0`, with
//! `v_a = b × κ`, `v_b = κ × a` (`c` is bilinear in `(a, b)`; `Σ_i κ_i ∂²c_i/∂a∂b = −[κ]ₓ`).
//! The axial density `½ EA ε²` gives `EA ε a/|a|` and
//! `EA/|a| (a aᵀ/|a|² + ε I)`. The element maps `z = T q_e`,
//! `T = [s' ⊗ I₃; s'' ⊗ I₃]`.
//!
//! # A moment on a node
//! A node's rotation is the smallest rotation that takes the reference
//! tangent `t0` to the node's tangent `t = r'/|r'|`: the rotation vector
//! `φ = θ n`, `cos θ = t0·t`, `n = t0 × t / |t0 × t|`, and a constant moment
//! `M` does the work `W = M · φ`. This is a potential (the static solver's
//! line search and symmetric tangent need one; the virtual work `M · (t × δt)`
//! of a dead moment is not integrable in 3-D), it reduces to the planar
//! `M θ` for rotations in a plane (`θ` below π), and to `M · (t0 × t)` for
//! small rotations. The component of `M` along `t0` does no work at all: `φ`
//! is perpendicular to `t0` (the cable has no torsion). Written
//! `W = h(c) μ·t` with `c = t0·t`, `μ = M × t0` and
//! `h(c) = θ/sin θ = arccos(c)/√(1 − c²)` (a series in `1 − c` near
//! `θ = 0`, where the closed form is 0/0); `W` is singular at `θ = π`
//! (the tangent turned back onto `−t0`), where the work is not finite.

use super::DEFAULT_GAUSS_POINTS;
use super::{Element, GaussPoint, NodeKinematics, check_cable, gauss_points, hermite};
use crate::error::Result;
use nalgebra::{DMatrix, DVector, Vector3};

/// Spatial ANCF cable element (3-D, 6 coordinates per node,
/// `q_i = [x, y, z, x', y', z']`).
///
/// # Example
/// ```
/// use softrod::element::{Element, SpatialCable};
/// let e = SpatialCable::new(0.1, 300.0, 0.025)?;
/// // a straight, unstretched element along z: no energy
/// let qe = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.1, 0.0, 0.0, 1.0];
/// assert!(e.energy(&qe).abs() < 1e-18);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct SpatialCable {
    le: f64,
    ea: f64,
    ei: f64,
    /// The Gauss points of both integrals (as the planar cable's).
    points: Vec<GaussPoint>,
}

type V3 = [f64; 3];

#[inline]
fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// `[v]ₓ`, the matrix of `w ↦ v × w`.
#[inline]
fn skew(v: V3) -> [V3; 3] {
    [[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]]
}

impl SpatialCable {
    /// A spatial cable element of length `le` (m), axial stiffness `ea` (N)
    /// and bending stiffness `ei` (N·m², both planes), with 5-point rules for
    /// both integrals.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] if a value is not finite and
    /// positive (named `length_m`, `ea_n`, `ei_nm2`).
    ///
    /// # Example
    /// ```
    /// let e = softrod::element::SpatialCable::new(0.1, 300.0, 0.025)?;
    /// assert_eq!(e.ei(), 0.025);
    /// assert!(softrod::element::SpatialCable::new(0.1, -1.0, 0.025).is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn new(le: f64, ea: f64, ei: f64) -> Result<Self> {
        Self::with_rules(le, ea, ei, DEFAULT_GAUSS_POINTS, DEFAULT_GAUSS_POINTS)
    }

    /// As [`SpatialCable::new`], with the numbers of Gauss points of the
    /// axial and the bending integrals.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for non-positive or non-finite
    /// `le`, `ea`, `ei`, or a rule of 0 points; [`crate::Error::TooLarge`]
    /// for a rule above [`crate::quadrature::MAX_POINTS`] points.
    ///
    /// # Example
    /// ```
    /// // exudyn's ObjectANCFCable rules: 5 points axial, 3 bending
    /// let e = softrod::element::SpatialCable::with_rules(0.1, 300.0, 0.025, 5, 3)?;
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn with_rules(
        le: f64,
        ea: f64,
        ei: f64,
        axial_points: usize,
        bending_points: usize,
    ) -> Result<Self> {
        check_cable(le, ea, ei)?;
        let points = gauss_points(le, ea, ei, axial_points, bending_points)?;
        Ok(SpatialCable { le, ea, ei, points })
    }

    /// Axial strain `ε = |r'| − 1` and curvature vector
    /// `κ = r' × r'' / (r'·r')` (1/m) at `ξ`.
    ///
    /// A `qe` without exactly 12 entries gives NaN.
    ///
    /// # Example
    /// ```
    /// let e = softrod::element::SpatialCable::new(1.0, 1.0, 1.0)?;
    /// let qe = [0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 0.0, 0.0, 2.0, 0.0];
    /// let (eps, kappa) = e.strains(&qe, 0.5);
    /// assert!((eps - 1.0).abs() < 1e-14 && kappa.iter().all(|k| k.abs() < 1e-14));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn strains(&self, qe: &[f64], xi: f64) -> (f64, Vector3<f64>) {
        let Ok(qe) = <&[f64; 12]>::try_from(qe) else {
            return (f64::NAN, Vector3::repeat(f64::NAN));
        };
        let (_, d1, d2) = hermite(xi, self.le);
        let (a, b) = derivs(qe, &d1, &d2);
        let d = dot(a, a);
        let c = cross(a, b);
        (d.sqrt() - 1.0, Vector3::new(c[0] / d, c[1] / d, c[2] / d))
    }

    /// Axial stiffness EA (N).
    pub fn ea(&self) -> f64 {
        self.ea
    }

    /// Bending stiffness EI (N·m²).
    pub fn ei(&self) -> f64 {
        self.ei
    }

    /// Gradient of the energy density at a Gauss point with respect to
    /// `z = (a, b) = (r', r'')`, weights included.
    #[inline]
    fn point_gradient(gp: &GaussPoint, a: V3, b: V3) -> [f64; 6] {
        let mut gz = [0.0; 6];
        if gp.ca != 0.0 {
            // dU/da = EA ε a/|a|
            let n = dot(a, a).sqrt();
            let f = gp.ca * (n - 1.0) / n;
            for i in 0..3 {
                gz[i] = f * a[i];
            }
        }
        if gp.cb != 0.0 {
            let id = 1.0 / dot(a, a);
            let c = cross(a, b);
            let k = [c[0] * id, c[1] * id, c[2] * id];
            let kk = dot(k, k);
            let va = cross(b, k);
            let vb = cross(k, a);
            let f = gp.cb * id;
            for i in 0..3 {
                gz[i] += f * (va[i] - 2.0 * kk * a[i]);
                gz[3 + i] += f * vb[i];
            }
        }
        gz
    }

    /// Gradient and Hessian (6 × 6) of the energy density at a Gauss point
    /// with respect to `z = (a, b)`, weights included (module docs).
    #[inline]
    #[allow(clippy::needless_range_loop)]
    fn point_derivatives(gp: &GaussPoint, a: V3, b: V3) -> ([f64; 6], [[f64; 6]; 6]) {
        let gz = Self::point_gradient(gp, a, b);
        let mut hz = [[0.0; 6]; 6];
        if gp.ca != 0.0 {
            let n = dot(a, a).sqrt();
            let inv_n = 1.0 / n;
            let eps = n - 1.0;
            let c = gp.ca * inv_n;
            let w = inv_n * inv_n;
            for i in 0..3 {
                for j in 0..3 {
                    hz[i][j] = c * a[i] * a[j] * w;
                }
                hz[i][i] += c * eps;
            }
        }
        if gp.cb != 0.0 {
            let id = 1.0 / dot(a, a);
            let id2 = id * id;
            let c = cross(a, b);
            let k = [c[0] * id, c[1] * id, c[2] * id];
            let kk = dot(k, k);
            let va = cross(b, k);
            let vb = cross(k, a);
            // J = [J_a | J_b], 3 × 6
            let (sb, sa, sk) = (skew(b), skew(a), skew(k));
            let mut jac = [[0.0; 6]; 3];
            for r in 0..3 {
                for j in 0..3 {
                    jac[r][j] = -(sb[r][j] + 2.0 * k[r] * a[j]) * id;
                    jac[r][3 + j] = sa[r][j] * id;
                }
            }
            let cb = gp.cb;
            for i in 0..6 {
                for j in 0..6 {
                    let jtj = jac[0][i] * jac[0][j] + jac[1][i] * jac[1][j] + jac[2][i] * jac[2][j];
                    hz[i][j] += cb * jtj;
                }
            }
            for i in 0..3 {
                for j in 0..3 {
                    // aa block
                    let mut s =
                        -2.0 * (va[i] * a[j] + a[i] * va[j]) * id2 + 8.0 * kk * a[i] * a[j] * id2;
                    if i == j {
                        s -= 2.0 * kk * id;
                    }
                    hz[i][j] += cb * s;
                    // ab block and its transpose
                    let ab = -sk[i][j] * id - 2.0 * a[i] * vb[j] * id2;
                    hz[i][3 + j] += cb * ab;
                    hz[3 + j][i] += cb * ab;
                }
            }
        }
        (gz, hz)
    }
}

/// `r'` and `r''` at a Gauss point.
#[inline]
fn derivs(qe: &[f64; 12], d1: &[f64; 4], d2: &[f64; 4]) -> (V3, V3) {
    let mut a = [0.0; 3];
    let mut b = [0.0; 3];
    for k in 0..4 {
        for i in 0..3 {
            a[i] += d1[k] * qe[3 * k + i];
            b[i] += d2[k] * qe[3 * k + i];
        }
    }
    (a, b)
}

/// Adds `Tᵀ g_z` to the element gradient, `T = [d1 ⊗ I₃; d2 ⊗ I₃]`.
#[inline]
fn scatter_gradient(gp: &GaussPoint, gz: &[f64; 6], grad: &mut [f64; 12]) {
    for k in 0..4 {
        for i in 0..3 {
            grad[3 * k + i] += gp.d1[k] * gz[i] + gp.d2[k] * gz[3 + i];
        }
    }
}

/// Adds the upper triangle of `Tᵀ H_z T` to `h` (row-major 12 × 12).
#[inline]
#[allow(clippy::needless_range_loop)]
fn accumulate_hessian(gp: &GaussPoint, hz: &[[f64; 6]; 6], h: &mut [f64; 144]) {
    let (d1, d2) = (&gp.d1, &gp.d2);
    // V = H_z T: column (l, j) = d1_l H_z[:, j] + d2_l H_z[:, 3 + j]
    let mut v = [[0.0; 12]; 6];
    for r in 0..6 {
        for l in 0..4 {
            for j in 0..3 {
                v[r][3 * l + j] = d1[l] * hz[r][j] + d2[l] * hz[r][3 + j];
            }
        }
    }
    // Tᵀ V: row (k, i) = d1_k V[i] + d2_k V[3 + i], upper triangle
    for k in 0..4 {
        for i in 0..3 {
            let row = 3 * k + i;
            let (p, q) = (d1[k], d2[k]);
            for col in row..12 {
                h[row * 12 + col] += p * v[i][col] + q * v[3 + i][col];
            }
        }
    }
}

/// Adds the symmetric matrix whose upper triangle `h` holds into `hess`.
#[inline]
fn mirror_into(h: &[f64; 144], hess: &mut [f64; 144]) {
    for r in 0..12 {
        for c in 0..12 {
            hess[r * 12 + c] += if c >= r { h[r * 12 + c] } else { h[c * 12 + r] };
        }
    }
}

impl Element for SpatialCable {
    fn length(&self) -> f64 {
        self.le
    }

    fn energy(&self, qe: &[f64]) -> f64 {
        let Ok(qe) = <&[f64; 12]>::try_from(qe) else {
            return f64::NAN;
        };
        let mut u = 0.0;
        for gp in &self.points {
            let (a, b) = derivs(qe, &gp.d1, &gp.d2);
            let aa = dot(a, a);
            if gp.ca != 0.0 {
                let eps = aa.sqrt() - 1.0;
                u += 0.5 * gp.ca * eps * eps;
            }
            if gp.cb != 0.0 {
                let c = cross(a, b);
                u += 0.5 * gp.cb * dot(c, c) / (aa * aa);
            }
        }
        u
    }

    fn add_energy_gradient(&self, qe: &[f64], grad: &mut [f64]) {
        let (Ok(qe), Ok(grad)) = (<&[f64; 12]>::try_from(qe), <&mut [f64; 12]>::try_from(grad))
        else {
            return;
        };
        for gp in &self.points {
            let (a, b) = derivs(qe, &gp.d1, &gp.d2);
            let gz = Self::point_gradient(gp, a, b);
            scatter_gradient(gp, &gz, grad);
        }
    }

    fn add_energy_hessian(&self, qe: &[f64], hess: &mut [f64]) {
        let (Ok(qe), Ok(hess)) = (
            <&[f64; 12]>::try_from(qe),
            <&mut [f64; 144]>::try_from(hess),
        ) else {
            return;
        };
        let mut h = [0.0; 144];
        for gp in &self.points {
            let (a, b) = derivs(qe, &gp.d1, &gp.d2);
            let (_, hz) = Self::point_derivatives(gp, a, b);
            accumulate_hessian(gp, &hz, &mut h);
        }
        mirror_into(&h, hess);
    }

    fn add_energy_gradient_and_hessian(&self, qe: &[f64], grad: &mut [f64], hess: &mut [f64]) {
        let (Ok(qe), Ok(grad), Ok(hess)) = (
            <&[f64; 12]>::try_from(qe),
            <&mut [f64; 12]>::try_from(grad),
            <&mut [f64; 144]>::try_from(hess),
        ) else {
            return;
        };
        let mut h = [0.0; 144];
        for gp in &self.points {
            let (a, b) = derivs(qe, &gp.d1, &gp.d2);
            let (gz, hz) = Self::point_derivatives(gp, a, b);
            scatter_gradient(gp, &gz, grad);
            accumulate_hessian(gp, &hz, &mut h);
        }
        mirror_into(&h, hess);
    }

    fn shape(&self, xi: f64) -> [f64; 4] {
        hermite(xi, self.le).0
    }
}

/// `h(c) = arccos(c)/√(1 − c²) = θ/sin θ` and its first two derivatives with
/// respect to `c`. Near `c = 1` the closed forms are 0/0: there the series
/// `h = Σ a_n x^n`, `x = 1 − c`, `a_0 = 1`, `a_n = n a_{n−1}/(2n + 1)` (from
/// `(1 − c²) h' = c h − 1`), which converges like `(x/2)^n`. Shared with
/// the full 3-D element's frame rotation.
pub(crate) fn rotation_factor(c: f64) -> (f64, f64, f64) {
    let x = 1.0 - c;
    if x < 0.5 {
        // 48 terms: (1/4)^48 is far below round-off, also for h''
        let (mut a, mut h, mut hx, mut hxx) = (1.0, 1.0, 0.0, 0.0);
        let (mut p0, mut p1) = (0.0, 1.0); // x^(n−2), x^(n−1)
        for n in 1..=48 {
            let nf = n as f64;
            a *= nf / (2.0 * nf + 1.0);
            let pn = p1 * x;
            h += a * pn;
            hx += nf * a * p1;
            if n >= 2 {
                hxx += nf * (nf - 1.0) * a * p0;
            }
            p0 = p1;
            p1 = pn;
        }
        return (h, -hx, hxx);
    }
    let s2 = x * (2.0 - x); // 1 − c², without cancellation
    let h = c.clamp(-1.0, 1.0).acos() / s2.sqrt();
    let h1 = (c * h - 1.0) / s2;
    let h2 = (h + 3.0 * c * h1) / s2;
    (h, h1, h2)
}

/// The unit vector along `v` and `|v|`; `None` for a zero or non-finite `v`.
fn unit(v: V3) -> Option<(V3, f64)> {
    let n = dot(v, v).sqrt();
    (n > 0.0 && n.is_finite()).then(|| ([v[0] / n, v[1] / n, v[2] / n], n))
}

/// The slope `r'` of a 6-coordinate node.
fn slope(node: &[f64]) -> Option<V3> {
    match node {
        [_, _, _, x, y, z] => Some([*x, *y, *z]),
        _ => None,
    }
}

/// `M · φ(t0 → t)` for the unit tangents `t0`, `t` (module docs).
fn rotation_vector(t0: V3, t: V3) -> V3 {
    let (h, _, _) = rotation_factor(dot(t0, t));
    let n = cross(t0, t);
    [h * n[0], h * n[1], h * n[2]]
}

/// The node's rotation is the rotation vector of the smallest rotation from
/// the reference tangent to the node's tangent; a moment `M` (N·m, world
/// axes) does the work `M · φ`, and its component along the reference
/// tangent none (see the module docs of `spatial_cable`).
impl NodeKinematics for SpatialCable {
    const DIM: usize = 3;
    const NODE_DOFS: usize = 6;
    const MOMENT_DIM: usize = 3;

    fn straight_node(position: &[f64], direction: &[f64]) -> DVector<f64> {
        DVector::from_vec({
            match (position, direction) {
                ([x, y, z], [dx, dy, dz]) => vec![*x, *y, *z, *dx, *dy, *dz],
                _ => vec![f64::NAN; 6],
            }
        })
    }

    fn node_tangent(node: &[f64]) -> DVector<f64> {
        DVector::from_vec({
            match slope(node).and_then(unit) {
                Some((t, _)) => t.to_vec(),
                None => vec![f64::NAN; 3],
            }
        })
    }

    fn node_rotation(reference: &[f64], node: &[f64]) -> DVector<f64> {
        DVector::from_vec({
            match (slope(reference).and_then(unit), slope(node).and_then(unit)) {
                (Some((t0, _)), Some((t, _))) => rotation_vector(t0, t).to_vec(),
                _ => vec![f64::NAN; 3],
            }
        })
    }

    #[allow(clippy::needless_range_loop)]
    fn add_moment_work(
        reference: &[f64],
        node: &[f64],
        moment: &[f64],
        grad: &mut [f64],
        hess: &mut [f64],
    ) {
        let (Some((t0, _)), Some((t, rho)), &[m0, m1, m2], Some(grad), Some(hess)) = (
            slope(reference).and_then(unit),
            slope(node).and_then(unit),
            moment,
            grad.get_mut(..6),
            hess.get_mut(..36),
        ) else {
            return;
        };
        // W(u) = F(u/|u|), F(t) = h(t0·t) μ·t, μ = M × t0
        let mu = cross([m0, m1, m2], t0);
        let (h, h1, h2) = rotation_factor(dot(t0, t));
        let p = dot(mu, t);
        // ∇F = h' P t0 + h μ, ∇²F = h'' P t0 t0ᵀ + h' (t0 μᵀ + μ t0ᵀ)
        let gt = [
            h1 * p * t0[0] + h * mu[0],
            h1 * p * t0[1] + h * mu[1],
            h1 * p * t0[2] + h * mu[2],
        ];
        let mut ht = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                ht[i][j] = h2 * p * t0[i] * t0[j] + h1 * (t0[i] * mu[j] + mu[i] * t0[j]);
            }
        }
        // the chain rule through t = u/|u|, ∂t/∂u = Π/ρ, Π = I − t tᵀ:
        // ∇W = Π ∇F/ρ,
        // ∇²W = [Π ∇²F Π − (g⊥ tᵀ + t g⊥ᵀ) − (t·∇F) Π]/ρ², g⊥ = Π ∇F
        let gtt = dot(t, gt);
        let gp = [gt[0] - gtt * t[0], gt[1] - gtt * t[1], gt[2] - gtt * t[2]];
        let mut pi = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                pi[i][j] = if i == j { 1.0 } else { 0.0 } - t[i] * t[j];
            }
        }
        // Π ∇²F Π
        let mut hp = [[0.0; 3]; 3];
        for i in 0..3 {
            for j in 0..3 {
                hp[i][j] = (0..3).map(|k| ht[i][k] * pi[k][j]).sum();
            }
        }
        let ir = 1.0 / rho;
        let ir2 = ir * ir;
        for i in 0..3 {
            grad[3 + i] += gp[i] * ir;
            for j in 0..3 {
                let php: f64 = (0..3).map(|k| pi[i][k] * hp[k][j]).sum();
                hess[(3 + i) * 6 + 3 + j] +=
                    (php - gp[i] * t[j] - t[i] * gp[j] - gtt * pi[i][j]) * ir2;
            }
        }
    }

    fn clamp_free_directions(node: &[f64]) -> DMatrix<f64> {
        super::direction_columns(Self::NODE_DOFS, {
            match slope(node).and_then(unit) {
                Some((t, _)) => vec![vec![0.0, 0.0, 0.0, t[0], t[1], t[2]]],
                None => Vec::new(),
            }
        })
    }

    fn moment_work_between(reference: &[f64], from: &[f64], to: &[f64], moment: &[f64]) -> f64 {
        let (Some((t0, _)), Some((ta, _)), Some((tb, _)), &[m0, m1, m2]) = (
            slope(reference).and_then(unit),
            slope(from).and_then(unit),
            slope(to).and_then(unit),
            moment,
        ) else {
            return f64::NAN;
        };
        let m = [m0, m1, m2];
        dot(m, rotation_vector(t0, tb)) - dot(m, rotation_vector(t0, ta))
    }
}

#[cfg(test)]
mod tests;
