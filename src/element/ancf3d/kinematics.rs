//! The strain measures of the full 3-D element, written once over a
//! [`Scalar`] (value, gradient or Hessian from the same code).
//!
//! At a point of the centreline the element gives `a = r_X`, `b = r_XX`
//! (from the cubic Hermite part of (5)), the section gradients `d2 = r_Y`,
//! `d3 = r_Z` (linear along the element) and their rates `d2' = ∂r_Y/∂X`,
//! `d3' = ∂r_Z/∂X`: the 18 numbers `z = [a, b, d2, d2', d3, d3']`.
//!
//! - stretch `λ = |a|`, axial strain `ε = λ − 1`, tangent `t = a/λ`;
//! - curvature vector `κ = a × b / λ² = t × t'` (the cable's, per undeformed
//!   length);
//! - section frame `(t, e2, e3)`: `m = d2 − (d2·t) t − t × d3`,
//!   `e2 = m/|m|`, `e3 = t × e2`. With `p2, p3` the projections of `d2, d3`
//!   on the plane normal to `t`, `m = p2 − t × p3` and `e2` is the first
//!   column of the rotation of the polar decomposition of `[p2 p3]` in that
//!   plane: where the section is unsheared (`d2, d3 ⊥ t`),
//!   `[r_X r_Y r_Z] = R U` with `R = [t e2 e3]`;
//! - bending curvatures `κ_Y = κ·e2`, `κ_Z = κ·e3`;
//! - twist `τ = e2'·e3 = m'·(t × m)/|m|²`, the rate of the frame's rotation
//!   about `t`, with `t' = (b − (t·b) t)/λ` and
//!   `m' = d2' − (d2'·t + d2·t') t − (d2·t) t' − t' × d3 − t × d3'`.
//!
//! At a node: the shear `γ_2 = t·d2`, `γ_3 = t·d3` and the Green strain of
//! the section `E_ij = (d_i·d_j − δ_ij)/2`, `i, j ∈ {2, 3}`, and the
//! rotation vector of the node's frame from a reference frame.

use super::jet::{Scalar, Vec3, axpy, cross, dot, mul3, sub3};
use crate::element::spatial_cable::rotation_factor;

/// The stiffnesses a density is weighted with (weights of the Gauss point
/// included by the caller).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LineStiffness {
    pub ea: f64,
    pub ei_y: f64,
    pub ei_z: f64,
    pub gj: f64,
}

/// `(λ, t)` of `a`.
#[inline]
fn stretch<T: Scalar>(a: &Vec3<T>) -> (T, Vec3<T>) {
    let lam = dot(a, a).sqrt();
    let il = lam.recip();
    (lam, mul3(il, a))
}

/// `m = d2 − (d2·t) t − t × d3` (module docs).
#[inline]
fn section_vector<T: Scalar>(t: &Vec3<T>, d2: &Vec3<T>, d3: &Vec3<T>) -> Vec3<T> {
    let p = axpy(-dot(d2, t), t, d2);
    sub3(&p, &cross(t, d3))
}

/// Axial strain, curvatures `(κ_Y, κ_Z)` and twist at a centreline point
/// from `z = [a, b, d2, d2', d3, d3']`.
#[inline]
pub(crate) fn strains<T: Scalar>(z: &[T; 18]) -> (T, T, T, T) {
    let a = [z[0], z[1], z[2]];
    let b = [z[3], z[4], z[5]];
    let d2 = [z[6], z[7], z[8]];
    let d2p = [z[9], z[10], z[11]];
    let d3 = [z[12], z[13], z[14]];
    let d3p = [z[15], z[16], z[17]];
    let (lam, t) = stretch(&a);
    let il = lam.recip();
    let eps = lam - T::cst(1.0);
    // κ = t × t' with t' = (b − (t·b) t)/λ
    let tp = mul3(il, &axpy(-dot(&t, &b), &t, &b));
    let kappa = cross(&t, &tp);
    let m = section_vector(&t, &d2, &d3);
    let d2t = dot(&d2, &t);
    let mut mp = axpy(-(dot(&d2p, &t) + dot(&d2, &tp)), &t, &d2p);
    mp = axpy(-d2t, &tp, &mp);
    mp = sub3(&mp, &cross(&tp, &d3));
    mp = sub3(&mp, &cross(&t, &d3p));
    let tm = cross(&t, &m);
    let mm = dot(&m, &m);
    let imm = mm.recip();
    let tau = dot(&mp, &tm) * imm;
    let inv_m = imm.sqrt();
    let ky = dot(&kappa, &m) * inv_m;
    let kz = dot(&kappa, &tm) * inv_m;
    (eps, ky, kz, tau)
}

/// The energy density `½ (EA ε² + EI_Y κ_Y² + EI_Z κ_Z² + GJ τ²)` at a
/// centreline point. With `EI_Y = EI_Z` the bending term is `½ EI |κ|²`
/// (`κ ⊥ t`), which does not need the frame.
#[inline]
pub(crate) fn line_density<T: Scalar>(z: &[T; 18], k: &LineStiffness) -> T {
    let (eps, ky, kz, tau) = strains(z);
    let mut u = (eps * eps).scale(k.ea) + (tau * tau).scale(k.gj);
    if k.ei_y == k.ei_z {
        let a = [z[0], z[1], z[2]];
        let b = [z[3], z[4], z[5]];
        let c = cross(&a, &b);
        let aa = dot(&a, &a);
        u = u + (dot(&c, &c) * (aa * aa).recip()).scale(k.ei_y);
    } else {
        u = u + (ky * ky).scale(k.ei_y) + (kz * kz).scale(k.ei_z);
    }
    u.scale(0.5)
}

/// The penalty density `½ k_s (γ_2² + γ_3²) + ½ k_c (E_22² + E_33² + 2 E_23²)`
/// at a node from `n = [a, d2, d3]` (module docs).
#[inline]
pub(crate) fn node_penalty<T: Scalar>(n: &[T; 9], k_shear: f64, k_section: f64) -> T {
    let a = [n[0], n[1], n[2]];
    let d2 = [n[3], n[4], n[5]];
    let d3 = [n[6], n[7], n[8]];
    let (_, t) = stretch(&a);
    let g2 = dot(&t, &d2);
    let g3 = dot(&t, &d3);
    let one = T::cst(1.0);
    let e22 = (dot(&d2, &d2) - one).scale(0.5);
    let e33 = (dot(&d3, &d3) - one).scale(0.5);
    let e23 = dot(&d2, &d3).scale(0.5);
    let shear = (g2 * g2 + g3 * g3).scale(k_shear);
    let section = (e22 * e22 + e33 * e33 + (e23 * e23).scale(2.0)).scale(k_section);
    (shear + section).scale(0.5)
}

/// The section frame `[t, e2, e3]` (columns) of a node from `n = [a, d2, d3]`.
#[inline]
pub(crate) fn node_frame<T: Scalar>(n: &[T; 9]) -> [Vec3<T>; 3] {
    let a = [n[0], n[1], n[2]];
    let d2 = [n[3], n[4], n[5]];
    let d3 = [n[6], n[7], n[8]];
    let (_, t) = stretch(&a);
    let m = section_vector(&t, &d2, &d3);
    let e2 = mul3(dot(&m, &m).sqrt().recip(), &m);
    let e3 = cross(&t, &e2);
    [t, e2, e3]
}

/// The rotation vector `φ` of `Q = R R0ᵀ` (world axes), `R` the frame of
/// the node `n = [a, d2, d3]`, `R0` the columns `reference`: with
/// `w = Σ_k r0_k × r_k = 2 sin θ ν` and `cos θ = (tr Q − 1)/2 = (Σ_k r0_k·r_k − 1)/2`,
/// `φ = θ ν = ½ h(cos θ) w` (singular at `θ = π`).
pub(crate) fn rotation_vector<T: Scalar>(reference: &[[f64; 3]; 3], n: &[T; 9]) -> Vec3<T> {
    let frame = node_frame(n);
    let mut w = [T::cst(0.0); 3];
    let mut tr = T::cst(0.0);
    for (r0, r) in reference.iter().zip(&frame) {
        let r0 = [T::cst(r0[0]), T::cst(r0[1]), T::cst(r0[2])];
        let c = cross(&r0, r);
        w = [w[0] + c[0], w[1] + c[1], w[2] + c[2]];
        tr = tr + dot(&r0, r);
    }
    let c = (tr - T::cst(1.0)).scale(0.5);
    let (h, h1, h2) = rotation_factor(c.value());
    let h = c.map(h, h1, h2).scale(0.5);
    mul3(h, &w)
}
