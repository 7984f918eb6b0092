//! The planar ANCF cable (2-D, 4 coordinates per node, `q_i = [r_i, r_i']`):
//! energy (19) with the scalar bending strain `κ = (r' × r'')_z / (r'·r')`, the
//! rate of the tangent angle per undeformed length, and an optional rest
//! curvature `κ0(X)`: constant, or any function of the arc coordinate
//! sampled at the bending Gauss points ([`PlanarCable::with_rest_curvature`]).

use super::DEFAULT_GAUSS_POINTS;
use super::{Element, GaussPoint, NodeKinematics, check_cable, gauss_points, hermite};
use crate::error::{Result, check_finite};
use nalgebra::{DMatrix, DVector};

/// Planar ANCF cable element (2-D, 4 coordinates per node).
///
/// # Example
/// ```
/// use softrod::element::{Element, PlanarCable};
/// let e = PlanarCable::new(0.1, 300.0, 0.025).unwrap();
/// // straight, unstretched element along x: no energy
/// let qe = [0.0, 0.0, 1.0, 0.0, 0.1, 0.0, 1.0, 0.0];
/// assert!(e.energy(&qe).abs() < 1e-18);
/// ```
#[derive(Debug, Clone)]
pub struct PlanarCable {
    le: f64,
    ea: f64,
    ei: f64,
    /// Rest curvature `κ0` (1/m) at each of `points` (0 at axial-only points).
    kappa0: Vec<f64>,
    /// The Gauss points of both integrals: one list when the two rules
    /// coincide (the default), else the axial points followed by the
    /// bending points. The kernels evaluate `r'`, `r''` once per point.
    points: Vec<GaussPoint>,
}

impl PlanarCable {
    /// A cable element of length `le` (m), axial stiffness `ea` (N) and bending
    /// stiffness `ei` (N·m²), with 5-point rules for both integrals and no rest
    /// curvature.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] if a value is not finite and positive.
    pub fn new(le: f64, ea: f64, ei: f64) -> Result<Self> {
        Self::with_rules(le, ea, ei, 0.0, DEFAULT_GAUSS_POINTS, DEFAULT_GAUSS_POINTS)
    }

    /// As [`PlanarCable::new`], with a rest curvature `kappa0` (1/m) and the
    /// numbers of Gauss points of the axial and the bending integrals.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] for non-positive or non-finite `le`, `ea`,
    /// `ei`, a non-finite `kappa0`, or a rule of 0 points; [`crate::Error::TooLarge`]
    /// for a rule above [`crate::quadrature::MAX_POINTS`] points.
    ///
    /// # Example
    /// ```
    /// // exudyn's ObjectANCFCable2D rules: 5 points axial, 3 bending
    /// let e = softrod::element::PlanarCable::with_rules(0.1, 300.0, 0.025, 0.0, 5, 3).unwrap();
    /// ```
    pub fn with_rules(
        le: f64,
        ea: f64,
        ei: f64,
        kappa0: f64,
        axial_points: usize,
        bending_points: usize,
    ) -> Result<Self> {
        check_finite("rest_curvature_per_m", kappa0)?;
        Self::with_rest_curvature(le, ea, ei, |_| kappa0, axial_points, bending_points)
    }

    /// As [`PlanarCable::with_rules`], with a rest curvature that varies
    /// along the element: `kappa0(x)` (1/m) at the local arc coordinate `x`
    /// (m, `0 ..= le` from the element's first node), evaluated at the
    /// bending Gauss points. The energy is then
    /// `½ ∫ EI (κ − κ0(X))² dX` by the bending rule: exact for the
    /// integrand's polynomial part, so a `κ0` with a kink inside an element
    /// is integrated only approximately (put a node at the kink).
    ///
    /// # Errors
    /// As [`PlanarCable::with_rules`]; [`crate::Error::InvalidParameter`]
    /// naming `rest_curvature_per_m` if `kappa0` gives a non-finite value.
    ///
    /// # Example
    /// ```
    /// use softrod::element::{Element, PlanarCable};
    /// // κ0 rising linearly from 1 to 2 1/m over a 0.1 m element
    /// let e = PlanarCable::with_rest_curvature(0.1, 300.0, 0.025, |x| 1.0 + 10.0 * x, 5, 5).unwrap();
    /// // the straight element stores the energy of bending it back: ½ EI ∫ κ0² dX
    /// let qe = [0.0, 0.0, 1.0, 0.0, 0.1, 0.0, 1.0, 0.0];
    /// let exact = 0.5 * 0.025 * (2.0f64.powi(3) - 1.0) / 3.0 * 0.1;
    /// assert!((e.energy(&qe) - exact).abs() < 1e-15);
    /// ```
    pub fn with_rest_curvature(
        le: f64,
        ea: f64,
        ei: f64,
        kappa0: impl Fn(f64) -> f64,
        axial_points: usize,
        bending_points: usize,
    ) -> Result<Self> {
        check_cable(le, ea, ei)?;
        let points = gauss_points(le, ea, ei, axial_points, bending_points)?;
        // the points' ξ, in the order `gauss_points` lists them
        let rule = |n| crate::quadrature::GaussRule::new(n);
        let (axial, bending) = (rule(axial_points)?, rule(bending_points)?);
        let xis: Vec<f64> = if axial == bending {
            axial.iter().map(|(xi, _)| xi).collect()
        } else {
            axial
                .iter()
                .chain(bending.iter())
                .map(|(xi, _)| xi)
                .collect()
        };
        let mut k0 = Vec::with_capacity(points.len());
        for (gp, xi) in points.iter().zip(xis) {
            let k = if gp.cb != 0.0 { kappa0(xi * le) } else { 0.0 };
            check_finite("rest_curvature_per_m", k)?;
            k0.push(k);
        }
        Ok(PlanarCable {
            le,
            ea,
            ei,
            kappa0: k0,
            points,
        })
    }

    /// Axial strain `ε` and bending strain `κ` at `ξ` (dimensionless, 1/m).
    ///
    /// # Example
    /// ```
    /// let e = softrod::element::PlanarCable::new(1.0, 1.0, 1.0).unwrap();
    /// let (eps, kappa) = e.strains(&[0.0, 0.0, 2.0, 0.0, 2.0, 0.0, 2.0, 0.0], 0.5);
    /// assert!((eps - 1.0).abs() < 1e-14 && kappa.abs() < 1e-14);
    /// ```
    ///
    /// A `qe` without exactly 8 entries gives `(NaN, NaN)`.
    pub fn strains(&self, qe: &[f64], xi: f64) -> (f64, f64) {
        let Ok(qe) = <&[f64; 8]>::try_from(qe) else {
            return (f64::NAN, f64::NAN);
        };
        let (_, d1, d2) = hermite(xi, self.le);
        let (a, b) = derivs(qe, &d1, &d2);
        let c = a[0] * b[1] - a[1] * b[0];
        (
            (a[0] * a[0] + a[1] * a[1]).sqrt() - 1.0,
            c / (a[0] * a[0] + a[1] * a[1]),
        )
    }

    /// Rotation angle of a node's section, `atan2(r'_y, r'_x)` (rad), from
    /// the node's coordinates `[x, y, x', y']`; NaN for another length.
    ///
    /// # Example
    /// ```
    /// use softrod::element::PlanarCable;
    /// let th = PlanarCable::node_angle(&[0.0, 0.0, 0.0, 2.0]);
    /// assert!((th - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    /// ```
    pub fn node_angle(node: &[f64]) -> f64 {
        match node {
            [_, _, x, y] => y.atan2(*x),
            _ => f64::NAN,
        }
    }

    /// Axial stiffness EA (N).
    pub fn ea(&self) -> f64 {
        self.ea
    }

    /// Bending stiffness EI (N·m²).
    pub fn ei(&self) -> f64 {
        self.ei
    }
}

/// `r'` and `r''` at a Gauss point.
#[inline]
fn derivs(qe: &[f64; 8], d1: &[f64; 4], d2: &[f64; 4]) -> ([f64; 2], [f64; 2]) {
    let mut a = [0.0; 2];
    let mut b = [0.0; 2];
    for k in 0..4 {
        a[0] += d1[k] * qe[2 * k];
        a[1] += d1[k] * qe[2 * k + 1];
        b[0] += d2[k] * qe[2 * k];
        b[1] += d2[k] * qe[2 * k + 1];
    }
    (a, b)
}

/// Bending strain `κ` and its gradient with respect to `z = (a, b)` (the
/// first two results of [`curvature`], without the Hessian).
#[inline]
fn curvature_gradient(a: [f64; 2], b: [f64; 2]) -> (f64, [f64; 4]) {
    // one division: the rest multiplies by 1/d
    let c = a[0] * b[1] - a[1] * b[0];
    let id = 1.0 / (a[0] * a[0] + a[1] * a[1]);
    let kappa = c * id;
    let k2 = 2.0 * kappa;
    (
        kappa,
        [
            (b[1] - k2 * a[0]) * id,
            (-b[0] - k2 * a[1]) * id,
            -a[1] * id,
            a[0] * id,
        ],
    )
}

/// Bending strain `κ = c/d` with `c = a × b`, `d = a·a`, and its first and
/// second derivatives with respect to `z = (a, b)`: returns `(κ, ∇κ, ∇²κ)`
/// (`κ` is linear in `b`: the `(b, b)` block of `∇²κ` is zero).
///
/// With `c_a = (b₁, −b₀)`, `c_b = (−a₁, a₀)`, `d_a = 2a`:
/// `κ_a = (c_a − κ d_a)/d`, `κ_b = c_b/d`,
/// `κ_aa = −(c_a d_aᵀ + d_a c_aᵀ)/d² − 2κ I/d + 2κ d_a d_aᵀ/d²`,
/// `κ_ab = C/d − d_a c_bᵀ/d²`, `C = [[0, 1], [−1, 0]]`.
#[inline]
#[allow(clippy::needless_range_loop)]
fn curvature(a: [f64; 2], b: [f64; 2]) -> (f64, [f64; 4], [[f64; 4]; 4]) {
    let c = a[0] * b[1] - a[1] * b[0];
    let id = 1.0 / (a[0] * a[0] + a[1] * a[1]);
    let kappa = c * id;
    let ca = [b[1], -b[0]];
    let cb = [-a[1], a[0]];
    let da = [2.0 * a[0], 2.0 * a[1]];
    let id2 = id * id;
    let mut g = [0.0; 4];
    for i in 0..2 {
        g[i] = (ca[i] - kappa * da[i]) * id;
        g[2 + i] = cb[i] * id;
    }
    let mut h = [[0.0; 4]; 4];
    // κ_aa
    for i in 0..2 {
        for j in 0..2 {
            let diag = if i == j { 2.0 * kappa * id } else { 0.0 };
            h[i][j] = (2.0 * kappa * da[i] * da[j] - (ca[i] * da[j] + da[i] * ca[j])) * id2 - diag;
        }
    }
    // κ_ab
    let cab = [[0.0, 1.0], [-1.0, 0.0]];
    for i in 0..2 {
        for j in 0..2 {
            let v = cab[i][j] * id - da[i] * cb[j] * id2;
            h[i][2 + j] = v;
            h[2 + j][i] = v;
        }
    }
    (kappa, g, h)
}

impl PlanarCable {
    /// Gradient of the energy density at a Gauss point with respect to
    /// `z = (a, b) = (r', r'')`, weights included.
    #[inline]
    fn point_gradient(&self, gp: &GaussPoint, k0: f64, a: [f64; 2], b: [f64; 2]) -> [f64; 4] {
        let mut gz = [0.0; 4];
        if gp.ca != 0.0 {
            // dU/da = EA ε a/|a|
            // (the same operations as point_derivatives: bit for bit)
            let n = (a[0] * a[0] + a[1] * a[1]).sqrt();
            let inv_n = 1.0 / n;
            let f = gp.ca * (n - 1.0) * inv_n;
            gz[0] = f * a[0];
            gz[1] = f * a[1];
        }
        if gp.cb != 0.0 {
            let (kappa, g) = curvature_gradient(a, b);
            let m = gp.cb * (kappa - k0);
            for (gi, v) in gz.iter_mut().zip(g) {
                *gi += m * v;
            }
        }
        gz
    }

    /// Gradient and Hessian (4 × 4) of the energy density at a Gauss point
    /// with respect to `z = (a, b)`, weights included.
    #[inline]
    #[allow(clippy::needless_range_loop)]
    fn point_derivatives(
        &self,
        gp: &GaussPoint,
        k0: f64,
        a: [f64; 2],
        b: [f64; 2],
    ) -> ([f64; 4], [[f64; 4]; 4]) {
        let mut gz = [0.0; 4];
        let mut hz = [[0.0; 4]; 4];
        if gp.ca != 0.0 {
            let aa = a[0] * a[0] + a[1] * a[1];
            let n = aa.sqrt();
            let inv_n = 1.0 / n;
            let eps = n - 1.0;
            let f = gp.ca * eps * inv_n;
            gz[0] = f * a[0];
            gz[1] = f * a[1];
            // EA [t tᵀ + ε (I − t tᵀ)/|a|] = EA/|a| [a aᵀ/|a|² + ε I]
            let c = gp.ca * inv_n;
            let w = inv_n * inv_n;
            hz[0][0] = c * (a[0] * a[0] * w + eps);
            hz[0][1] = c * (a[0] * a[1] * w);
            hz[1][0] = hz[0][1];
            hz[1][1] = c * (a[1] * a[1] * w + eps);
        }
        if gp.cb != 0.0 {
            let (kappa, g, hk) = curvature(a, b);
            let dk = kappa - k0;
            let c = gp.cb;
            let m = c * dk;
            for i in 0..4 {
                gz[i] += m * g[i];
                for j in i..4 {
                    hz[i][j] += c * (g[i] * g[j] + dk * hk[i][j]);
                }
            }
            for i in 1..4 {
                for j in 0..i {
                    hz[i][j] = hz[j][i];
                }
            }
        }
        (gz, hz)
    }
}

/// Adds `Tᵀ g_z` to the element gradient, `T = [d1 ⊗ I; d2 ⊗ I]`.
#[inline]
fn scatter_gradient(gp: &GaussPoint, gz: &[f64; 4], grad: &mut [f64; 8]) {
    for k in 0..4 {
        grad[2 * k] += gp.d1[k] * gz[0] + gp.d2[k] * gz[2];
        grad[2 * k + 1] += gp.d1[k] * gz[1] + gp.d2[k] * gz[3];
    }
}

/// The upper 2 × 2 blocks `(k, l)`, `k <= l`, of the element Hessian (node
/// vectors `q_k = r_0, r_0', r_1, r_1'`), in the order of [`BLOCKS`]; each
/// block row-major `[h00, h01, h10, h11]`.
type Blocks = [[f64; 4]; 10];

/// The `(k, l)` of each entry of [`Blocks`].
const BLOCKS: [(usize, usize); 10] = [
    (0, 0),
    (0, 1),
    (0, 2),
    (0, 3),
    (1, 1),
    (1, 2),
    (1, 3),
    (2, 2),
    (2, 3),
    (3, 3),
];

/// `acc += f · x` on a 2 × 2 block.
#[inline(always)]
fn axpy4(acc: &mut [f64; 4], f: f64, x: &[f64; 4]) {
    for (a, v) in acc.iter_mut().zip(x) {
        *a += f * v;
    }
}

/// Adds `Tᵀ H_z T` to the blocks (`T = [d1 ⊗ I; d2 ⊗ I]`): block `(k, l)`
/// gains `d1_k P_l + d2_k Q_l` with `P_l = d1_l H_aa + d2_l H_ab`,
/// `Q_l = d1_l H_ba + d2_l H_bb` (the columns of `H_z T`). An axial-only
/// point has the `(a, a)` block alone: `d1_k d1_l H_aa`.
#[inline]
fn accumulate_hessian(gp: &GaussPoint, hz: &[[f64; 4]; 4], h: &mut Blocks) {
    let (d1, d2) = (&gp.d1, &gp.d2);
    let haa = [hz[0][0], hz[0][1], hz[1][0], hz[1][1]];
    if gp.cb == 0.0 {
        for (blk, &(k, l)) in h.iter_mut().zip(&BLOCKS) {
            axpy4(blk, d1[k] * d1[l], &haa);
        }
        return;
    }
    let hab = [hz[0][2], hz[0][3], hz[1][2], hz[1][3]];
    let hba = [hz[2][0], hz[2][1], hz[3][0], hz[3][1]];
    let hbb = [hz[2][2], hz[2][3], hz[3][2], hz[3][3]];
    let mut p = [[0.0; 4]; 4];
    let mut q = [[0.0; 4]; 4];
    for l in 0..4 {
        for c in 0..4 {
            p[l][c] = d1[l] * haa[c] + d2[l] * hab[c];
            q[l][c] = d1[l] * hba[c] + d2[l] * hbb[c];
        }
    }
    for (blk, &(k, l)) in h.iter_mut().zip(&BLOCKS) {
        for c in 0..4 {
            blk[c] += d1[k] * p[l][c] + d2[k] * q[l][c];
        }
    }
}

/// Adds the symmetric 8 × 8 matrix whose upper blocks are `h` into `hess`
/// (row-major; block `(l, k)` below the diagonal is block `(k, l)`
/// transposed; a diagonal block is symmetrized).
#[inline]
fn mirror_into(h: &Blocks, hess: &mut [f64; 64]) {
    for (blk, &(k, l)) in h.iter().zip(&BLOCKS) {
        let (r, c) = (2 * k, 2 * l);
        if k == l {
            let off = 0.5 * (blk[1] + blk[2]);
            hess[r * 8 + c] += blk[0];
            hess[r * 8 + c + 1] += off;
            hess[(r + 1) * 8 + c] += off;
            hess[(r + 1) * 8 + c + 1] += blk[3];
            continue;
        }
        hess[r * 8 + c] += blk[0];
        hess[r * 8 + c + 1] += blk[1];
        hess[(r + 1) * 8 + c] += blk[2];
        hess[(r + 1) * 8 + c + 1] += blk[3];
        hess[c * 8 + r] += blk[0];
        hess[c * 8 + r + 1] += blk[2];
        hess[(c + 1) * 8 + r] += blk[1];
        hess[(c + 1) * 8 + r + 1] += blk[3];
    }
}

impl Element for PlanarCable {
    fn length(&self) -> f64 {
        self.le
    }

    fn energy(&self, qe: &[f64]) -> f64 {
        let Ok(qe) = <&[f64; 8]>::try_from(qe) else {
            return f64::NAN;
        };
        let mut u = 0.0;
        for (gp, k0) in self.points.iter().zip(&self.kappa0) {
            let (a, b) = derivs(qe, &gp.d1, &gp.d2);
            let aa = a[0] * a[0] + a[1] * a[1];
            if gp.ca != 0.0 {
                let eps = aa.sqrt() - 1.0;
                u += 0.5 * gp.ca * eps * eps;
            }
            if gp.cb != 0.0 {
                let k = (a[0] * b[1] - a[1] * b[0]) / aa - k0;
                u += 0.5 * gp.cb * k * k;
            }
        }
        u
    }

    fn add_energy_gradient(&self, qe: &[f64], grad: &mut [f64]) {
        let (Ok(qe), Ok(grad)) = (<&[f64; 8]>::try_from(qe), <&mut [f64; 8]>::try_from(grad))
        else {
            return;
        };
        for (gp, &k0) in self.points.iter().zip(&self.kappa0) {
            let (a, b) = derivs(qe, &gp.d1, &gp.d2);
            let gz = self.point_gradient(gp, k0, a, b);
            scatter_gradient(gp, &gz, grad);
        }
    }

    fn add_energy_hessian(&self, qe: &[f64], hess: &mut [f64]) {
        let (Ok(qe), Ok(hess)) = (<&[f64; 8]>::try_from(qe), <&mut [f64; 64]>::try_from(hess))
        else {
            return;
        };
        let mut h: Blocks = [[0.0; 4]; 10];
        for (gp, &k0) in self.points.iter().zip(&self.kappa0) {
            let (a, b) = derivs(qe, &gp.d1, &gp.d2);
            let (_, hz) = self.point_derivatives(gp, k0, a, b);
            accumulate_hessian(gp, &hz, &mut h);
        }
        mirror_into(&h, hess);
    }

    fn add_energy_gradient_and_hessian(&self, qe: &[f64], grad: &mut [f64], hess: &mut [f64]) {
        let (Ok(qe), Ok(grad), Ok(hess)) = (
            <&[f64; 8]>::try_from(qe),
            <&mut [f64; 8]>::try_from(grad),
            <&mut [f64; 64]>::try_from(hess),
        ) else {
            return;
        };
        let mut h: Blocks = [[0.0; 4]; 10];
        for (gp, &k0) in self.points.iter().zip(&self.kappa0) {
            let (a, b) = derivs(qe, &gp.d1, &gp.d2);
            let (gz, hz) = self.point_derivatives(gp, k0, a, b);
            scatter_gradient(gp, &gz, grad);
            accumulate_hessian(gp, &hz, &mut h);
        }
        mirror_into(&h, hess);
    }

    fn shape(&self, xi: f64) -> [f64; 4] {
        hermite(xi, self.le).0
    }
}

/// The node's rotation is the angle of its tangent, `θ = atan2(r'_y, r'_x)`;
/// a moment `M` (N·m, counter-clockwise positive) does the work `M θ`.
impl NodeKinematics for PlanarCable {
    const DIM: usize = 2;
    const NODE_DOFS: usize = 4;
    const MOMENT_DIM: usize = 1;

    fn straight_node(position: &[f64], direction: &[f64]) -> DVector<f64> {
        DVector::from_vec({
            match (position, direction) {
                ([x, y], [dx, dy]) => vec![*x, *y, *dx, *dy],
                _ => vec![f64::NAN; 4],
            }
        })
    }

    fn node_tangent(node: &[f64]) -> DVector<f64> {
        DVector::from_vec({
            match node {
                [_, _, x, y] => {
                    let n = (x * x + y * y).sqrt();
                    vec![x / n, y / n]
                }
                _ => vec![f64::NAN; 2],
            }
        })
    }

    fn node_rotation(reference: &[f64], node: &[f64]) -> DVector<f64> {
        DVector::from_vec({
            match (reference, node) {
                ([_, _, ax, ay], [_, _, bx, by]) => {
                    vec![(ax * by - ay * bx).atan2(ax * bx + ay * by)]
                }
                _ => vec![f64::NAN],
            }
        })
    }

    fn add_moment_work(
        _reference: &[f64],
        node: &[f64],
        moment: &[f64],
        grad: &mut [f64],
        hess: &mut [f64],
    ) {
        // θ = atan2(y, x) of the slope (x, y) = r' (the reference only shifts
        // θ by a constant); ∂θ = (-y, x)/ρ²,
        // ∂²θ = [[2xy, y² - x²], [y² - x², -2xy]]/ρ⁴.
        let (Some(&[x, y]), Some(&m), Some(grad), Some(hess)) = (
            node.get(2..4).and_then(|s| <&[f64; 2]>::try_from(s).ok()),
            moment.first(),
            grad.get_mut(..4),
            hess.get_mut(..16),
        ) else {
            return;
        };
        if node.len() != 4 || moment.len() != 1 {
            return;
        }
        let r2 = x * x + y * y;
        grad[2] += m * -y / r2;
        grad[3] += m * x / r2;
        let r4 = r2 * r2;
        let n = 4;
        hess[2 * n + 2] += m * 2.0 * x * y / r4;
        hess[2 * n + 3] += m * (y * y - x * x) / r4;
        hess[3 * n + 2] += m * (y * y - x * x) / r4;
        hess[3 * n + 3] += m * -2.0 * x * y / r4;
    }

    fn clamp_free_directions(node: &[f64]) -> DMatrix<f64> {
        super::direction_columns(Self::NODE_DOFS, {
            match node {
                [_, _, x, y] => {
                    let n = (x * x + y * y).sqrt();
                    vec![vec![0.0, 0.0, x / n, y / n]]
                }
                _ => Vec::new(),
            }
        })
    }

    fn moment_work_between(_reference: &[f64], from: &[f64], to: &[f64], moment: &[f64]) -> f64 {
        // the turn from `from` to `to` (no wrap-around below π)
        match (from, to, moment) {
            ([_, _, ax, ay], [_, _, bx, by], [m]) => {
                m * (ax * by - ay * bx).atan2(ax * bx + ay * by)
            }
            _ => f64::NAN,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quadrature::GaussRule;

    /// A deterministic pseudo-random deformed element.
    fn deformed(seed: u64, le: f64) -> [f64; 8] {
        let mut rng = crate::rng::Lcg::new(seed);
        rng.next_u64(); // (the first state is not drawn from)
        let mut rnd = || rng.centered();
        [
            0.1 * le * rnd(),
            0.1 * le * rnd(),
            1.0 + 0.3 * rnd(),
            0.5 * rnd(),
            le * (1.0 + 0.2 * rnd()),
            0.3 * le * rnd(),
            0.9 + 0.3 * rnd(),
            0.6 * rnd(),
        ]
    }

    #[test]
    fn gradient_matches_finite_differences() {
        for seed in 0..20 {
            let le = 0.05 + 0.01 * seed as f64;
            let e = PlanarCable::with_rules(le, 300.0, 0.025, 0.3 * seed as f64, 5, 3).unwrap();
            let q = deformed(seed, le);
            let mut g = [0.0; 8];
            e.add_energy_gradient(&q, &mut g);
            let scale = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for i in 0..8 {
                let h = 1e-6 * (1.0 + q[i].abs());
                let mut qp = q;
                let mut qm = q;
                qp[i] += h;
                qm[i] -= h;
                let fd = (e.energy(&qp) - e.energy(&qm)) / (2.0 * h);
                assert!(
                    (fd - g[i]).abs() <= 1e-6 * scale,
                    "seed {seed} i {i}: {fd} vs {}",
                    g[i]
                );
            }
        }
    }

    #[test]
    fn hessian_matches_finite_differences_and_is_symmetric() {
        for seed in 0..20 {
            let le = 0.05 + 0.01 * seed as f64;
            let e = PlanarCable::with_rules(le, 300.0, 0.025, -0.2 * seed as f64, 5, 5).unwrap();
            let q = deformed(seed + 100, le);
            let mut h = [0.0; 64];
            e.add_energy_hessian(&q, &mut h);
            let scale = h.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for j in 0..8 {
                let d = 1e-6 * (1.0 + q[j].abs());
                let mut qp = q;
                let mut qm = q;
                qp[j] += d;
                qm[j] -= d;
                let mut gp = [0.0; 8];
                let mut gm = [0.0; 8];
                e.add_energy_gradient(&qp, &mut gp);
                e.add_energy_gradient(&qm, &mut gm);
                for i in 0..8 {
                    let fd = (gp[i] - gm[i]) / (2.0 * d);
                    assert!(
                        (fd - h[i * 8 + j]).abs() <= 1e-6 * scale,
                        "seed {seed} ({i},{j}): {fd} vs {}",
                        h[i * 8 + j]
                    );
                    assert!((h[i * 8 + j] - h[j * 8 + i]).abs() <= 1e-12 * scale);
                }
            }
        }
    }

    #[test]
    fn curvature_gradient_is_the_first_part_of_curvature() {
        let (a, b) = ([0.9, 0.3], [-2.0, 5.0]);
        let (k1, g1) = curvature_gradient(a, b);
        let (k2, g2, _) = curvature(a, b);
        assert_eq!(k1, k2);
        for i in 0..4 {
            assert!((g1[i] - g2[i]).abs() <= 1e-15 * g2[i].abs().max(1.0));
        }
    }

    #[test]
    fn rigid_motions_of_the_straight_element_store_no_energy() {
        let le = 0.12;
        let e = PlanarCable::new(le, 300.0, 0.025).unwrap();
        for k in 0..16 {
            let th = k as f64 * 0.4;
            let (c, s) = (th.cos(), th.sin());
            let (tx, ty) = (0.3 * k as f64 - 1.0, 0.1 * k as f64);
            let q = [tx, ty, c, s, tx + le * c, ty + le * s, c, s];
            assert!(e.energy(&q).abs() < 1e-20);
            let mut g = [0.0; 8];
            e.add_energy_gradient(&q, &mut g);
            assert!(g.iter().all(|v| v.abs() < 1e-12), "{g:?}");
        }
    }

    #[test]
    fn moment_work_derivatives_match_finite_differences() {
        let node = [0.1, 0.2, 0.8, -0.6];
        let m = [0.7];
        let mut g = [0.0; 4];
        let mut h = [0.0; 16];
        PlanarCable::add_moment_work(&node, &node, &m, &mut g, &mut h);
        let work = |n: &[f64; 4]| m[0] * PlanarCable::node_angle(n);
        for j in 0..4 {
            let d = 1e-6;
            let mut p = node;
            let mut q = node;
            p[j] += d;
            q[j] -= d;
            assert!(((work(&p) - work(&q)) / (2.0 * d) - g[j]).abs() < 1e-8);
            let mut gp = [0.0; 4];
            let mut gm = [0.0; 4];
            let mut scratch = [0.0; 16];
            PlanarCable::add_moment_work(&node, &p, &m, &mut gp, &mut scratch);
            PlanarCable::add_moment_work(&node, &q, &m, &mut gm, &mut scratch);
            for i in 0..4 {
                assert!(((gp[i] - gm[i]) / (2.0 * d) - h[i * 4 + j]).abs() < 1e-7);
            }
        }
    }

    #[test]
    fn constant_curvature_is_measured_exactly_on_an_arc_like_element() {
        // slope rotating at rate k: the exact kappa at the nodes of a cubic
        // interpolant of an arc is close to k.
        let le = 0.01;
        let k = 2.0;
        let e = PlanarCable::new(le, 1.0, 1.0).unwrap();
        let th = k * le;
        let q = [
            0.0,
            0.0,
            1.0,
            0.0,
            th.sin() / k,
            (1.0 - th.cos()) / k,
            th.cos(),
            th.sin(),
        ];
        let (eps, kappa) = e.strains(&q, 0.5);
        assert!(
            eps.abs() < 1e-6 && (kappa - k).abs() < 1e-4,
            "{eps} {kappa}"
        );
    }

    #[test]
    fn fused_gradient_and_hessian_equal_the_separate_kernels() {
        for (seed, (na, nb)) in [(5usize, 5usize), (5, 3), (2, 7)].into_iter().enumerate() {
            let le = 0.07;
            let e = PlanarCable::with_rules(le, 300.0, 0.025, 0.4, na, nb).unwrap();
            let q = deformed(seed as u64 + 40, le);
            let (mut g1, mut h1) = ([0.0; 8], [0.0; 64]);
            e.add_energy_gradient(&q, &mut g1);
            e.add_energy_hessian(&q, &mut h1);
            let (mut g2, mut h2) = ([0.0; 8], [0.0; 64]);
            e.add_energy_gradient_and_hessian(&q, &mut g2, &mut h2);
            assert_eq!(g1, g2);
            assert_eq!(h1, h2);
            // wrong sizes add nothing
            let mut g3 = [0.0; 8];
            e.add_energy_gradient_and_hessian(&q[..7], &mut g3, &mut h2);
            assert_eq!(g3, [0.0; 8]);
        }
    }

    #[test]
    fn coinciding_rules_give_the_energy_of_separate_integrals() {
        // the merged 5/5 list against a 5/5 energy summed by hand
        let le = 0.09;
        let (ea, ei, k0) = (300.0, 0.025, 0.7);
        let e = PlanarCable::with_rules(le, ea, ei, k0, 5, 5).unwrap();
        let q = deformed(77, le);
        let rule = GaussRule::new(5).unwrap();
        let mut u = 0.0;
        for (xi, w) in rule.iter() {
            let (eps, kappa) = e.strains(&q, xi);
            u += 0.5 * w * le * (ea * eps * eps + ei * (kappa - k0) * (kappa - k0));
        }
        assert!((e.energy(&q) - u).abs() <= 1e-14 * u.abs());
    }
}
