//! The full 3-D ANCF element (eqs. (1)–(9)): 12 coordinates per node,
//! `q_i = [r_i, r_iX, r_iY, r_iZ]` (7), 24 per element, and a structural
//! (rod) elastic energy with axial strain, two bending curvatures and
//! torsion read from the section frame.
//!
//! # Interpolation (5), (6)
//! `r(X, Y, Z) = S(X, Y, Z) q_e` with the eight functions of (5), `ξ = X/L_e`:
//!
//! `s1 = 1 − 3ξ² + 2ξ³`, `s2 = L_e (ξ − 2ξ² + ξ³)`, `s3 = Y (1 − ξ)`,
//! `s4 = Z (1 − ξ)`, `s5 = 3ξ² − 2ξ³`, `s6 = L_e (ξ³ − ξ²)`, `s7 = Y ξ`,
//! `s8 = Z ξ`.
//!
//! The paper prints `s2` with `2X³/L_e²`; the coefficients (2) it derives
//! from give `X³/L_e²` (and only then is `s2` the slope function of the
//! cubic Hermite set, `s2'(L_e) = 0`): the code uses the latter. On the
//! centreline (`Y = Z = 0`) the position is the spatial cable's cubic
//! Hermite curve; the section gradients `r_Y`, `r_Z` are linear in `X`.
//!
//! # Elastic energy
//! The paper leaves the energy of this element to its ref. [48]. Here it is
//! the energy of a Kirchhoff rod with a section frame:
//!
//! `U_E = ∫ ½ (EA ε² + EI_Y κ_Y² + EI_Z κ_Z² + GJ τ²) dX
//!        + Σ_nodes (L_e/2) ½ (k_s (γ_2² + γ_3²) + k_c (E_22² + E_33² + 2 E_23²))`
//!
//! with the measures of the `kinematics` module: `ε = |r_X| − 1`;
//! the curvature vector `κ = r_X × r_XX / |r_X|²` of the centreline (the
//! cable's), split into `κ_Y = κ·e2`, `κ_Z = κ·e3` along the section frame;
//! the twist `τ = e2'·e3` of that frame; the frame `R = [t e2 e3]` the
//! rotation of the polar decomposition of `[r_X r_Y r_Z] = R U` taken with
//! the tangent `t = r_X/|r_X|` as first axis (the in-plane polar rotation of
//! the section gradients projected normal to `t`). The second line is a
//! penalty, integrated by the two-point Lobatto (trapezoid) rule, i.e. at
//! the nodes, on the shear `γ_k = t·r_k` and the Green strain of the
//! section `E_ij = (r_i·r_j − δ_ij)/2` (`i, j ∈ {Y, Z}`).
//!
//! Why this form:
//! - It is the rod theory the soft robots are modelled with everywhere
//!   else in the crate (the cables' `EA ε² + EI |κ|²`, eq. (19)) plus the
//!   torsion the section frame makes possible, with the stiffnesses an
//!   engineer measures (EA, EI about both section axes, GJ). A continuum
//!   (Saint-Venant–Kirchhoff) energy of this element is reported in the
//!   ANCF literature to lock in bending and through Poisson's effect, and it
//!   asks for section integrals nobody measures on a pneumatic actuator.
//! - Bending is read from the cubic centreline, not from the derivative of
//!   the linearly interpolated section gradients: the element bends exactly
//!   like the spatial cable (a cubic is represented exactly, no shear
//!   locking: there is no shear strain in the bending energy).
//! - The physical energy depends on `r_Y`, `r_Z` only through the frame,
//!   and the frame is unchanged when a multiple of `t` is added to `r_Y` or
//!   `r_Z`: the shear penalty acts on directions the physical energy does not
//!   see, so its value does not change the solution. It is applied only at
//!   the nodes, where the linear `r_Y`, `r_Z` can meet it exactly (applied at
//!   interior Gauss points it would force the linear section gradients to
//!   follow the quadratic `r_X` and lock). The section penalty keeps
//!   `[r_Y r_Z]` orthonormal at the nodes; only the twist stresses it
//!   (the frame is invariant to a common scaling of `r_Y, r_Z`, not to a
//!   change of their shape); with the default `k_c = EA` the closed-form
//!   twist `TL/GJ` of 1.5 rad is met to 2e-6 rad at 16 elements, converging
//!   at fourth order (tests/ancf3d.rs).
//! - Rigid motions: every measure is built from dot and cross products of
//!   the gradients, so the energy is invariant under any rotation and
//!   translation (a test).
//!
//! What it does not do: shear deformation (Kirchhoff rod, the slender
//! limit of Simo–Reissner), rest curvature or twist, warping, Poisson's
//! effect. The section gradients are linear along the element and a twisted
//! section is not: the uniform twist is met only in the limit, observed at
//! fourth order in the element length (tests/ancf3d.rs).
//!
//! # Derivatives
//! The densities are written once over a scalar type and evaluated with
//! forward-mode dual numbers (value + gradient) and second-order jets
//! (value + gradient + Hessian) over the 18 centreline quantities of a
//! Gauss point (9 at a node): the exact analytic derivatives by the chain
//! rule, without hand-expanded third derivatives of the polar frame. The
//! element then maps them linearly, `z = T q_e`.
//!
//! # A moment on a node
//! The node's rotation is the rotation vector `φ` of `R R0ᵀ`, `R` the
//! node's section frame, `R0` the reference node's; a moment `M` (world
//! axes) does the work `W = M · φ`, a potential (rotations below π). It is
//! the planar `M θ` for rotations about a fixed axis (the twist of a
//! straight rod, a rod rolled in a plane), and `M · (rotation)` for small
//! rotations. Unlike the cable, a moment along the tangent does work.

pub(crate) mod jet;
mod kinematics;

use jet::{Dual, Jet, Scalar};
use kinematics::{LineStiffness, line_density, node_frame, node_penalty, rotation_vector, strains};
use nalgebra::{DMatrix, DVector, Vector3};

use super::{DEFAULT_GAUSS_POINTS, Element, NodeKinematics, hermite};
use crate::error::{Error, Result, check_positive};
use crate::quadrature::GaussRule;

/// Coordinates per node.
const ND: usize = 12;
/// Coordinates per element.
const ED: usize = 24;
/// Centreline quantities per Gauss point.
const NZ: usize = 18;
/// Gradient coordinates of a node (`r_X, r_Y, r_Z`).
const NG: usize = 9;

/// Stiffnesses of a section of the full 3-D element.
///
/// # Example
/// ```
/// let s = softrod::element::Ancf3dStiffness::isotropic(300.0, 0.025, 0.019);
/// assert_eq!((s.ei_y_nm2, s.ei_z_nm2, s.shear_penalty_n), (0.025, 0.025, 300.0));
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ancf3dStiffness {
    /// Axial stiffness EA (N).
    pub ea_n: f64,
    /// Bending stiffness about the section's Y axis (curvature along `e2`), N·m².
    pub ei_y_nm2: f64,
    /// Bending stiffness about the section's Z axis (curvature along `e3`), N·m².
    pub ei_z_nm2: f64,
    /// Torsional stiffness GJ (N·m²).
    pub gj_nm2: f64,
    /// Penalty stiffness `k_s` on the shear `t·r_Y`, `t·r_Z` at the nodes (N).
    pub shear_penalty_n: f64,
    /// Penalty stiffness `k_c` on the Green strain of the section at the nodes (N).
    pub section_penalty_n: f64,
}

impl Ancf3dStiffness {
    /// Equal bending stiffness `ei_nm2` in both planes; both penalties equal
    /// to the axial stiffness `ea_n` (the section as stiff in its plane as
    /// along the rod: a Poisson-free section).
    pub fn isotropic(ea_n: f64, ei_nm2: f64, gj_nm2: f64) -> Self {
        Ancf3dStiffness {
            ea_n,
            ei_y_nm2: ei_nm2,
            ei_z_nm2: ei_nm2,
            gj_nm2,
            shear_penalty_n: ea_n,
            section_penalty_n: ea_n,
        }
    }

    /// Checks that every stiffness is finite and positive.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`ea_n`, `ei_y_nm2`, …).
    ///
    /// # Example
    /// ```
    /// let mut s = softrod::element::Ancf3dStiffness::isotropic(300.0, 0.025, 0.019);
    /// s.gj_nm2 = -1.0;
    /// assert!(s.validate().unwrap_err().to_string().contains("gj_nm2"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("ea_n", self.ea_n),
            ("ei_y_nm2", self.ei_y_nm2),
            ("ei_z_nm2", self.ei_z_nm2),
            ("gj_nm2", self.gj_nm2),
            ("shear_penalty_n", self.shear_penalty_n),
            ("section_penalty_n", self.section_penalty_n),
        ] {
            check_positive(name, v)?;
        }
        Ok(())
    }
}

/// One row of `z = T q_e`: up to four coordinates and their weights.
#[derive(Debug, Clone, Copy, Default)]
struct Row {
    idx: [usize; 4],
    coef: [f64; 4],
    n: usize,
}

/// A Gauss point: its weight times `L_e` and the map `z = T q_e`.
#[derive(Debug, Clone)]
struct Point {
    w: f64,
    rows: [Row; NZ],
}

impl Point {
    fn new(xi: f64, w: f64, le: f64) -> Self {
        let (_, d1, d2) = hermite(xi, le);
        let mut rows = [Row::default(); NZ];
        // Hermite slots of the centreline: r1, r1X, r2, r2X
        let slots = [0, 3, ND, ND + 3];
        for i in 0..3 {
            let idx = slots.map(|s| s + i);
            rows[i] = Row {
                idx,
                coef: d1,
                n: 4,
            };
            rows[3 + i] = Row {
                idx,
                coef: d2,
                n: 4,
            };
            for (k, base) in [(6, 6), (12, 9)] {
                let idx = [base + i, ND + base + i, 0, 0];
                rows[k + i] = Row {
                    idx,
                    coef: [1.0 - xi, xi, 0.0, 0.0],
                    n: 2,
                };
                rows[k + 3 + i] = Row {
                    idx,
                    coef: [-1.0 / le, 1.0 / le, 0.0, 0.0],
                    n: 2,
                };
            }
        }
        Point { w: w * le, rows }
    }

    #[inline]
    fn z(&self, qe: &[f64; ED]) -> [f64; NZ] {
        self.rows
            .map(|r| (0..r.n).map(|k| r.coef[k] * qe[r.idx[k]]).sum())
    }
}

/// The full 3-D ANCF element (module docs): 12 coordinates per node,
/// `q_i = [x, y, z, r_X, r_Y, r_Z]`, a Kirchhoff rod with a section frame.
///
/// # Example
/// ```
/// use softrod::element::{Ancf3d, Element, NodeKinematics};
/// let e = Ancf3d::new(0.1, 300.0, 0.025, 0.019)?;
/// // a straight stress-free element along x: no energy
/// let mut qe = Ancf3d::straight_node(&[0.0; 3], &[1.0, 0.0, 0.0]).as_slice().to_vec();
/// qe.extend(Ancf3d::straight_node(&[0.1, 0.0, 0.0], &[1.0, 0.0, 0.0]).iter());
/// assert!(e.energy(&qe).abs() < 1e-20);
/// // twisted by 0.01 rad about x at node 2: U = ½ GJ τ² L_e, τ = 0.1 rad/m
/// let (c, s) = (0.01f64.cos(), 0.01f64.sin());
/// qe[18..24].copy_from_slice(&[0.0, c, s, 0.0, -s, c]);
/// assert!((e.energy(&qe) - 0.5 * 0.019 * 0.01 * 0.1).abs() < 1e-9);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct Ancf3d {
    le: f64,
    stiffness: Ancf3dStiffness,
    line: LineStiffness,
    points: Vec<Point>,
}

impl Ancf3d {
    /// An element of length `le` (m) with the isotropic stiffnesses `ea`
    /// (N), `ei` (N·m², both planes) and `gj` (N·m²)
    /// ([`Ancf3dStiffness::isotropic`]), 5 Gauss points.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a value that is not finite and
    /// positive (`length_m`, `ea_n`, `ei_y_nm2`, `gj_nm2`, …).
    ///
    /// # Example
    /// ```
    /// assert!(softrod::element::Ancf3d::new(0.1, 300.0, 0.025, 0.0).is_err());
    /// ```
    pub fn new(le: f64, ea: f64, ei: f64, gj: f64) -> Result<Self> {
        Self::with_stiffness(
            le,
            Ancf3dStiffness::isotropic(ea, ei, gj),
            DEFAULT_GAUSS_POINTS,
        )
    }

    /// An element of length `le` (m) with `stiffness` and a Gauss rule of
    /// `gauss_points` points for the line integral.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a non-positive or non-finite length
    /// or stiffness (named as the field) or a rule of 0 points
    /// (`gauss_points`); [`Error::TooLarge`] above
    /// [`crate::quadrature::MAX_POINTS`] points.
    ///
    /// # Example
    /// ```
    /// use softrod::element::{Ancf3d, Ancf3dStiffness};
    /// let mut s = Ancf3dStiffness::isotropic(300.0, 0.025, 0.019);
    /// s.ei_z_nm2 = 0.05;
    /// let e = Ancf3d::with_stiffness(0.1, s, 4)?;
    /// assert_eq!(e.stiffness().ei_z_nm2, 0.05);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn with_stiffness(
        le: f64,
        stiffness: Ancf3dStiffness,
        gauss_points: usize,
    ) -> Result<Self> {
        check_positive("length_m", le)?;
        if !(1.0 / (le * le)).is_finite() {
            return Err(Error::invalid(
                "length_m",
                le,
                "element too short: 1/L_e² overflows",
            ));
        }
        stiffness.validate()?;
        if gauss_points == 0 {
            return Err(Error::invalid("gauss_points", 0, "must be >= 1"));
        }
        let rule = GaussRule::new(gauss_points)?;
        let points = rule.iter().map(|(xi, w)| Point::new(xi, w, le)).collect();
        Ok(Ancf3d {
            le,
            stiffness,
            line: LineStiffness {
                ea: stiffness.ea_n,
                ei_y: stiffness.ei_y_nm2,
                ei_z: stiffness.ei_z_nm2,
                gj: stiffness.gj_nm2,
            },
            points,
        })
    }

    /// The element's stiffnesses.
    pub fn stiffness(&self) -> &Ancf3dStiffness {
        &self.stiffness
    }

    /// The eight shape functions (5) at the material point `(X, Y, Z)`
    /// (m) of an element of length `le` (m), `s2` as corrected in the
    /// module docs.
    ///
    /// # Example
    /// ```
    /// let s = softrod::element::Ancf3d::shape_functions(0.05, 0.01, 0.0, 0.1);
    /// assert!((s[0] + s[4] - 1.0).abs() < 1e-15); // s1 + s5 = 1
    /// assert!((s[2] + s[6] - 0.01).abs() < 1e-15); // s3 + s7 = Y
    /// ```
    pub fn shape_functions(x: f64, y: f64, z: f64, le: f64) -> [f64; 8] {
        let xi = x / le;
        let (h, _, _) = hermite(xi, le);
        [
            h[0],
            h[1],
            y * (1.0 - xi),
            z * (1.0 - xi),
            h[2],
            h[3],
            y * xi,
            z * xi,
        ]
    }

    /// The position `r(X, Y, Z) = S q_e` (6) of the material point at
    /// `ξ = X/L_e` and section coordinates `y_m`, `z_m` (m). A `qe` without
    /// exactly 24 entries gives NaN.
    ///
    /// # Example
    /// ```
    /// use softrod::element::{Ancf3d, NodeKinematics};
    /// let e = softrod::element::Ancf3d::new(0.1, 300.0, 0.025, 0.019)?;
    /// let mut qe = Ancf3d::straight_node(&[0.0; 3], &[0.0, 0.0, 1.0]).as_slice().to_vec();
    /// qe.extend(Ancf3d::straight_node(&[0.0, 0.0, 0.1], &[0.0, 0.0, 1.0]).iter());
    /// let p = e.material_point(&qe, 0.5, 0.01, 0.0);
    /// assert!((p - nalgebra::Vector3::new(0.0, 0.01, 0.05)).norm() < 1e-15);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn material_point(&self, qe: &[f64], xi: f64, y_m: f64, z_m: f64) -> Vector3<f64> {
        let Ok(qe) = <&[f64; ED]>::try_from(qe) else {
            return Vector3::repeat(f64::NAN);
        };
        let s = Self::shape_functions(xi * self.le, y_m, z_m, self.le);
        let mut r = [0.0; 3];
        for (k, sk) in s.iter().enumerate() {
            for (i, ri) in r.iter_mut().enumerate() {
                *ri += sk * qe[3 * k + i];
            }
        }
        Vector3::from(r)
    }

    /// Axial strain `ε`, bending curvatures `κ_Y`, `κ_Z` (1/m) and twist
    /// `τ` (rad/m) at `ξ` (module docs). A `qe` without exactly 24 entries
    /// gives NaN.
    ///
    /// # Example
    /// ```
    /// use softrod::element::{Ancf3d, NodeKinematics};
    /// let e = Ancf3d::new(1.0, 1.0, 1.0, 1.0)?;
    /// let mut qe = Ancf3d::straight_node(&[0.0; 3], &[1.0, 0.0, 0.0]).as_slice().to_vec();
    /// qe.extend(Ancf3d::straight_node(&[1.0, 0.0, 0.0], &[1.0, 0.0, 0.0]).iter());
    /// let [eps, ky, kz, tau] = e.strains(&qe, 0.3);
    /// assert!(eps.abs() < 1e-15 && ky.abs() < 1e-15 && kz.abs() < 1e-15 && tau.abs() < 1e-15);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn strains(&self, qe: &[f64], xi: f64) -> [f64; 4] {
        let Ok(qe) = <&[f64; ED]>::try_from(qe) else {
            return [f64::NAN; 4];
        };
        let z = Point::new(xi, 1.0, self.le).z(qe);
        let (e, ky, kz, t) = strains(&z);
        [e, ky, kz, t]
    }

    /// The gradient coordinates `[r_X, r_Y, r_Z]` of end `k` (0 or 1).
    #[inline]
    fn node_gradients(qe: &[f64; ED], k: usize) -> [f64; NG] {
        let mut n = [0.0; NG];
        n.copy_from_slice(&qe[ND * k + 3..ND * k + ND]);
        n
    }

    fn penalty<T: Scalar>(&self, n: &[T; NG]) -> T {
        node_penalty(
            n,
            self.stiffness.shear_penalty_n,
            self.stiffness.section_penalty_n,
        )
        .scale(0.5 * self.le)
    }

    fn gradient_into(&self, qe: &[f64; ED], grad: &mut [f64; ED]) {
        for p in &self.points {
            let z = p.z(qe);
            let zd: [Dual<NZ>; NZ] = std::array::from_fn(|r| Dual::var(z[r], r));
            let u = line_density(&zd, &self.line);
            for (row, g) in p.rows.iter().zip(&u.g) {
                for k in 0..row.n {
                    grad[row.idx[k]] += p.w * row.coef[k] * g;
                }
            }
        }
        for k in 0..2 {
            let n = Self::node_gradients(qe, k);
            let nd: [Dual<NG>; NG] = std::array::from_fn(|r| Dual::var(n[r], r));
            let u = self.penalty(&nd);
            for (i, g) in u.g.iter().enumerate() {
                grad[ND * k + 3 + i] += g;
            }
        }
    }

    /// Adds the gradient (if `grad`) and the Hessian into `hess`.
    fn derivatives_into(
        &self,
        qe: &[f64; ED],
        mut grad: Option<&mut [f64; ED]>,
        hess: &mut [f64; ED * ED],
    ) {
        for p in &self.points {
            let z = p.z(qe);
            let zj: [Jet<NZ>; NZ] = std::array::from_fn(|r| Jet::var(z[r], r));
            let u = line_density(&zj, &self.line);
            if let Some(grad) = grad.as_deref_mut() {
                for (row, g) in p.rows.iter().zip(&u.g) {
                    for k in 0..row.n {
                        grad[row.idx[k]] += p.w * row.coef[k] * g;
                    }
                }
            }
            for (r1, row1) in p.rows.iter().enumerate() {
                for (r2, row2) in p.rows.iter().enumerate() {
                    let h = p.w * u.h[r1][r2];
                    if h == 0.0 {
                        continue;
                    }
                    for k1 in 0..row1.n {
                        let hk = h * row1.coef[k1];
                        let base = row1.idx[k1] * ED;
                        for k2 in 0..row2.n {
                            hess[base + row2.idx[k2]] += hk * row2.coef[k2];
                        }
                    }
                }
            }
        }
        for k in 0..2 {
            let n = Self::node_gradients(qe, k);
            let nj: [Jet<NG>; NG] = std::array::from_fn(|r| Jet::var(n[r], r));
            let u = self.penalty(&nj);
            let off = ND * k + 3;
            for i in 0..NG {
                if let Some(grad) = grad.as_deref_mut() {
                    grad[off + i] += u.g[i];
                }
                for j in 0..NG {
                    hess[(off + i) * ED + off + j] += u.h[i][j];
                }
            }
        }
    }
}

impl Element for Ancf3d {
    fn length(&self) -> f64 {
        self.le
    }

    fn energy(&self, qe: &[f64]) -> f64 {
        let Ok(qe) = <&[f64; ED]>::try_from(qe) else {
            return f64::NAN;
        };
        let mut u = 0.0;
        for p in &self.points {
            u += p.w * line_density(&p.z(qe), &self.line);
        }
        for k in 0..2 {
            u += self.penalty(&Self::node_gradients(qe, k));
        }
        u
    }

    fn add_energy_gradient(&self, qe: &[f64], grad: &mut [f64]) {
        let (Ok(qe), Ok(grad)) = (<&[f64; ED]>::try_from(qe), <&mut [f64; ED]>::try_from(grad))
        else {
            return;
        };
        self.gradient_into(qe, grad);
    }

    fn add_energy_hessian(&self, qe: &[f64], hess: &mut [f64]) {
        let (Ok(qe), Ok(hess)) = (
            <&[f64; ED]>::try_from(qe),
            <&mut [f64; ED * ED]>::try_from(hess),
        ) else {
            return;
        };
        self.derivatives_into(qe, None, hess);
    }

    fn add_energy_gradient_and_hessian(&self, qe: &[f64], grad: &mut [f64], hess: &mut [f64]) {
        let (Ok(qe), Ok(grad), Ok(hess)) = (
            <&[f64; ED]>::try_from(qe),
            <&mut [f64; ED]>::try_from(grad),
            <&mut [f64; ED * ED]>::try_from(hess),
        ) else {
            return;
        };
        self.derivatives_into(qe, Some(grad), hess);
    }

    /// The centreline's weights: the cubic Hermite functions `s1, s2, s5,
    /// s6` of (5) on the slots `r_1, r_1X, r_2, r_2X` (`s3, s4, s7, s8`
    /// vanish at `Y = Z = 0`).
    fn shape(&self, xi: f64) -> [f64; 4] {
        hermite(xi, self.le).0
    }
}

/// The gradient coordinates `[r_X, r_Y, r_Z]` of a 12-coordinate node.
fn gradients(node: &[f64]) -> Option<[f64; NG]> {
    let g = node.get(3..ND).filter(|_| node.len() == ND)?;
    let mut n = [0.0; NG];
    n.copy_from_slice(g);
    n.iter().all(|v| v.is_finite()).then_some(n)
}

/// The section frame of a node, `None` if it is singular (a zero or
/// non-finite tangent or section vector).
fn frame_of(node: &[f64]) -> Option<[[f64; 3]; 3]> {
    let f = node_frame(&gradients(node)?);
    f.iter().flatten().all(|v| v.is_finite()).then_some(f)
}

/// The right-handed orthonormal frame `[t, e2, e3]` of a stress-free node
/// along the unit tangent `t`: `e_y, e_z` carried by the smallest rotation
/// from `e_x` to `t` (near `t = −e_x`, where that rotation is undefined,
/// `e2` is `−e_y` made normal to `t`).
fn straight_frame(t: [f64; 3]) -> [[f64; 3]; 3] {
    let c = t[0];
    if 1.0 + c < 1e-9 {
        // near −e_x: −e_y made normal to t, then e3 = t × e2
        let p = [t[1] * t[0], t[1] * t[1] - 1.0, t[1] * t[2]];
        let n = jet::dot(&p, &p).sqrt();
        let e2 = p.map(|x| x / n);
        return [t, e2, jet::cross(&t, &e2)];
    }
    // R = I + [v]ₓ + [v]ₓ²/(1 + c), v = e_x × t
    let v = [0.0, -t[2], t[1]];
    let rot = |u: [f64; 3]| {
        let vu = jet::cross(&v, &u);
        let vvu = jet::cross(&v, &vu);
        [0, 1, 2].map(|i| u[i] + vu[i] + vvu[i] / (1.0 + c))
    };
    [t, rot([0.0, 1.0, 0.0]), rot([0.0, 0.0, 1.0])]
}

/// A node's rotation is the rotation vector of its section frame relative to
/// the reference node's; a moment `M` (N·m, world axes) does the work
/// `M · φ` (module docs).
impl NodeKinematics for Ancf3d {
    const DIM: usize = 3;
    const NODE_DOFS: usize = ND;
    const MOMENT_DIM: usize = 3;

    /// `[position, direction, e2, e3]`: `r_X` is `direction` as given, the
    /// section gradients the unit axes `straight_frame` carries along the
    /// unit direction (NaN for a zero or non-finite direction).
    fn straight_node(position: &[f64], direction: &[f64]) -> DVector<f64> {
        DVector::from_vec({
            let ([x, y, z], [dx, dy, dz]) = (position, direction) else {
                return DVector::from_vec(vec![f64::NAN; ND]);
            };
            let n = (dx * dx + dy * dy + dz * dz).sqrt();
            if !(n > 0.0 && n.is_finite()) {
                return DVector::from_vec(vec![f64::NAN; ND]);
            }
            let [_, e2, e3] = straight_frame([dx / n, dy / n, dz / n]);
            let mut q = vec![*x, *y, *z, *dx, *dy, *dz];
            q.extend_from_slice(&e2);
            q.extend_from_slice(&e3);
            q
        })
    }

    fn node_tangent(node: &[f64]) -> DVector<f64> {
        DVector::from_vec({
            match frame_of(node) {
                Some([t, _, _]) => t.to_vec(),
                None => vec![f64::NAN; 3],
            }
        })
    }

    fn node_rotation(reference: &[f64], node: &[f64]) -> DVector<f64> {
        DVector::from_vec({
            match (frame_of(reference), gradients(node)) {
                (Some(r0), Some(n)) => rotation_vector(&r0, &n).to_vec(),
                _ => vec![f64::NAN; 3],
            }
        })
    }

    fn add_moment_work(
        reference: &[f64],
        node: &[f64],
        moment: &[f64],
        grad: &mut [f64],
        hess: &mut [f64],
    ) {
        let (Some(r0), Some(n), &[m0, m1, m2], Some(grad), Some(hess)) = (
            frame_of(reference),
            gradients(node),
            moment,
            grad.get_mut(..ND),
            hess.get_mut(..ND * ND),
        ) else {
            return;
        };
        let nj: [Jet<NG>; NG] = std::array::from_fn(|r| Jet::var(n[r], r));
        let phi = rotation_vector(&r0, &nj);
        let w = phi[0].scale(m0) + phi[1].scale(m1) + phi[2].scale(m2);
        for i in 0..NG {
            grad[3 + i] += w.g[i];
            for j in 0..NG {
                hess[(3 + i) * ND + 3 + j] += w.h[i][j];
            }
        }
    }

    /// The stretch along the tangent: `r_X` scaled, the frame kept.
    fn clamp_free_directions(node: &[f64]) -> DMatrix<f64> {
        super::direction_columns(Self::NODE_DOFS, {
            match frame_of(node) {
                Some([t, _, _]) => {
                    let mut d = vec![0.0; ND];
                    d[3..6].copy_from_slice(&t);
                    vec![d]
                }
                None => Vec::new(),
            }
        })
    }

    fn moment_work_between(reference: &[f64], from: &[f64], to: &[f64], moment: &[f64]) -> f64 {
        let (Some(r0), Some(a), Some(b), &[m0, m1, m2]) =
            (frame_of(reference), gradients(from), gradients(to), moment)
        else {
            return f64::NAN;
        };
        let (pa, pb) = (rotation_vector(&r0, &a), rotation_vector(&r0, &b));
        m0 * (pb[0] - pa[0]) + m1 * (pb[1] - pa[1]) + m2 * (pb[2] - pa[2])
    }
}

#[cfg(test)]
mod tests;
