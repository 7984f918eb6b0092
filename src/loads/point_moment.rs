//! The work of a concentrated moment at an arc position, through a
//! "virtual node".
//!
//! A moment `M` at the undeformed arc coordinate `s` does the work
//! `W = M · θ(v)`, `θ` the rotation of a node (the element's
//! [`NodeKinematics::node_rotation`]) evaluated at the virtual node
//! `v = [r(s), r'(s)]`. On a cable both halves are the cubic Hermite
//! interpolation (16) of the element's four slots,
//! `r(s) = Σ_k s_k(ξ) q_k`, `r'(s) = Σ_k s_k'(ξ) q_k`, so `v = A q_e` is
//! linear in the element coordinates and
//!
//! `∂W/∂q_e = Aᵀ ∂W/∂v`, `∂²W/∂q_e² = Aᵀ (∂²W/∂v²) A`,
//!
//! with the node kernel [`NodeKinematics::add_moment_work`] supplying the
//! derivatives in `v`. At a node (`ξ` = 0 or 1) `A` picks that node and the
//! load is exactly a moment at the node. The map needs a cable's node layout
//! (`NODE_DOFS = 2 DIM`, `[r, r']`); other layouts are refused
//! when the loads are validated.

use crate::element::{ArcPoint, NodeKinematics};

/// Largest node a virtual node can hold (a spatial cable's 6 coordinates,
/// with room for a 12-coordinate node).
const MAX_NODE: usize = 12;

/// Whether the element's node layout is a cable's `[r, r']`, the layout the
/// Hermite interpolation of [`ArcPoint`] fills.
pub(crate) fn has_cable_layout<E: NodeKinematics>() -> bool {
    E::NODE_DOFS == 2 * E::DIM && E::NODE_DOFS <= MAX_NODE
}

/// The virtual node `[r(s), r'(s)]` at `p` of the cable configuration `q`
/// (node-major, `2 DIM` numbers per node); `None` for another layout or a
/// `q` that ends before the element.
fn virtual_node<E: NodeKinematics>(p: &ArcPoint, q: &[f64]) -> Option<[f64; MAX_NODE]> {
    if !has_cable_layout::<E>() {
        return None;
    }
    let d = E::DIM;
    let mut v = [0.0; MAX_NODE];
    p.value_into(q, &mut v[..d]).ok()?;
    p.slope_into(q, &mut v[d..2 * d]).ok()?;
    Some(v)
}

/// Adds the gradient `∂W/∂q_e` (into `grad`, `2 NODE_DOFS` numbers) and, if
/// `hess` is given, the Hessian `∂²W/∂q_e²` (row-major, `(2 NODE_DOFS)²`)
/// of the work `W = M · θ(s)` of the moment `moment` at the point `p` of
/// the configuration `q` (all of the rod's coordinates), with respect to
/// the coordinates of the element `p.element`. `reference` is the node the
/// rotation is measured from. Adds nothing for another node layout, a short
/// `q` or short buffers.
pub(crate) fn add_point_moment_work<E: NodeKinematics>(
    p: &ArcPoint,
    reference: &[f64],
    q: &[f64],
    moment: &[f64],
    grad: &mut [f64],
    hess: Option<&mut [f64]>,
) {
    let nd = E::NODE_DOFS;
    let d = E::DIM;
    let n = 2 * nd;
    let Some(v) = virtual_node::<E>(p, q) else {
        return;
    };
    if grad.len() < n || hess.as_ref().is_some_and(|h| h.len() < n * n) {
        return;
    }
    let mut gv = [0.0; MAX_NODE];
    let mut hv = [0.0; MAX_NODE * MAX_NODE];
    E::add_moment_work(
        reference,
        &v[..nd],
        moment,
        &mut gv[..nd],
        &mut hv[..nd * nd],
    );
    let (a, b) = (p.values, p.slopes);
    // A: v_i = Σ_k a_k q_e[k d + i], v_{d+i} = Σ_k b_k q_e[k d + i]
    for k in 0..4 {
        for i in 0..d {
            grad[k * d + i] += a[k] * gv[i] + b[k] * gv[d + i];
        }
    }
    let Some(hess) = hess else {
        return;
    };
    for k in 0..4 {
        for i in 0..d {
            let row = (k * d + i) * n;
            for l in 0..4 {
                for j in 0..d {
                    let h = |x: usize, y: usize| hv[x * nd + y];
                    hess[row + l * d + j] += a[k] * a[l] * h(i, j)
                        + a[k] * b[l] * h(i, d + j)
                        + b[k] * a[l] * h(d + i, j)
                        + b[k] * b[l] * h(d + i, d + j);
                }
            }
        }
    }
}

/// The work `M · (θ(s; to) − θ(s; from))` of the constant moment `moment`
/// at the point `p` while the configuration moves from `from` to `to`
/// (rotations below π); NaN for another node layout or a short
/// configuration.
pub(crate) fn point_moment_work_between<E: NodeKinematics>(
    p: &ArcPoint,
    reference: &[f64],
    from: &[f64],
    to: &[f64],
    moment: &[f64],
) -> f64 {
    let nd = E::NODE_DOFS;
    match (virtual_node::<E>(p, from), virtual_node::<E>(p, to)) {
        (Some(a), Some(b)) => E::moment_work_between(reference, &a[..nd], &b[..nd], moment),
        _ => f64::NAN,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::element::{PlanarCable, SpatialCable};

    /// Central differences of the work (between) against the gradient, of
    /// the gradient against the Hessian, for both cables at interior points.
    fn check<E: NodeKinematics>(q: &[f64], reference: &[f64], moment: &[f64]) {
        let n = 2 * E::NODE_DOFS;
        for xi in [0.0, 0.3, 0.77, 1.0] {
            let p = ArcPoint::new(1, xi, 0.07);
            let mut g = vec![0.0; n];
            let mut hh = vec![0.0; n * n];
            add_point_moment_work::<E>(&p, reference, q, moment, &mut g, Some(&mut hh));
            let off = E::NODE_DOFS; // element 1 starts at node 1
            let h = 1e-6;
            let gs = g.iter().fold(1e-3f64, |m, v| m.max(v.abs()));
            let hs = hh.iter().fold(1e-3f64, |m, v| m.max(v.abs()));
            for c in 0..n {
                let (mut qp, mut qm) = (q.to_vec(), q.to_vec());
                qp[off + c] += h;
                qm[off + c] -= h;
                let fd =
                    point_moment_work_between::<E>(&p, reference, &qm, &qp, moment) / (2.0 * h);
                assert!(
                    (fd - g[c]).abs() < 1e-7 * gs,
                    "ξ {xi} grad {c}: {fd} vs {}",
                    g[c]
                );
                let (mut gp, mut gm) = (vec![0.0; n], vec![0.0; n]);
                add_point_moment_work::<E>(&p, reference, &qp, moment, &mut gp, None);
                add_point_moment_work::<E>(&p, reference, &qm, moment, &mut gm, None);
                for r in 0..n {
                    let fd = (gp[r] - gm[r]) / (2.0 * h);
                    assert!(
                        (fd - hh[r * n + c]).abs() < 1e-6 * hs,
                        "ξ {xi} hess ({r},{c}): {fd} vs {}",
                        hh[r * n + c]
                    );
                }
            }
        }
    }

    #[test]
    fn gradient_and_hessian_are_the_derivatives_of_the_work() {
        // three nodes of a bent, stretched planar cable
        let q2 = [
            0.0, 0.0, 1.0, 0.0, 0.07, 0.01, 0.9, 0.4, 0.12, 0.05, 0.5, 1.1,
        ];
        check::<PlanarCable>(&q2, &[0.0, 0.0, 1.0, 0.0], &[0.3]);
        let q3 = [
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.07, 0.01, -0.01, 0.9, 0.3, -0.2, 0.12, 0.04, 0.02, 0.6,
            0.7, 0.5,
        ];
        check::<SpatialCable>(&q3, &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0], &[0.1, -0.4, 0.25]);
    }

    #[test]
    fn at_a_node_it_is_the_node_moment() {
        let q = [
            0.0, 0.0, 1.0, 0.0, 0.07, 0.01, 0.9, 0.4, 0.12, 0.05, 0.5, 1.1,
        ];
        let reference = [0.0, 0.0, 1.0, 0.0];
        let m = [0.3];
        // ξ = 1 of element 0 and ξ = 0 of element 1: node 1
        for (e, xi, at) in [(0, 1.0, 4), (1, 0.0, 0)] {
            let p = ArcPoint::new(e, xi, 0.07);
            let mut g = [0.0; 8];
            let mut h = [0.0; 64];
            add_point_moment_work::<PlanarCable>(&p, &reference, &q, &m, &mut g, Some(&mut h));
            let (mut gn, mut hn) = ([0.0; 4], [0.0; 16]);
            PlanarCable::add_moment_work(&reference, &q[4..8], &m, &mut gn, &mut hn);
            for a in 0..4 {
                assert_eq!(g[at + a], gn[a]);
                for b in 0..4 {
                    assert_eq!(h[(at + a) * 8 + at + b], hn[a * 4 + b]);
                }
            }
            assert_eq!(
                g.iter().map(|v| v.abs()).sum::<f64>(),
                gn.iter().map(|v| v.abs()).sum::<f64>()
            );
        }
    }
}
