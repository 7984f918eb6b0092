use super::*;
use crate::rng::Lcg;

/// The straight node as a plain vector (the tests splice nodes).
fn straight_node(position: &[f64], direction: &[f64]) -> Vec<f64> {
    Ancf3d::straight_node(position, direction).data.into()
}

/// A bent, twisted, stretched, slightly sheared element of length `le`.
fn deformed(le: f64, seed: u64) -> Vec<f64> {
    let mut rng = Lcg::new(seed);
    let mut qe = straight_node(&[0.0; 3], &[1.0, 0.0, 0.0]);
    qe.extend(straight_node(&[le, 0.0, 0.0], &[1.0, 0.0, 0.0]));
    // rotate node 2 by 0.4 rad about an oblique axis, move it, perturb all
    let (c, sn) = (0.4f64.cos(), 0.4f64.sin());
    let n = [0.3, 0.5, 0.81];
    let nn: f64 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    let n = n.map(|x: f64| x / nn.sqrt());
    for k in 0..3 {
        let v = [qe[15 + 3 * k], qe[16 + 3 * k], qe[17 + 3 * k]];
        let nv = jet::cross(&n, &v);
        let d = n[0] * v[0] + n[1] * v[1] + n[2] * v[2];
        for i in 0..3 {
            qe[15 + 3 * k + i] = v[i] * c + nv[i] * sn + n[i] * d * (1.0 - c);
        }
    }
    qe[13] += 0.2 * le;
    qe[14] -= 0.1 * le;
    for v in qe.iter_mut() {
        *v += 0.03 * rng.symmetric();
    }
    qe
}

fn elements() -> Vec<Ancf3d> {
    let mut aniso = Ancf3dStiffness::isotropic(300.0, 0.025, 0.019);
    aniso.ei_z_nm2 = 0.06;
    aniso.shear_penalty_n = 500.0;
    vec![
        Ancf3d::new(0.1, 300.0, 0.025, 0.019).unwrap(),
        Ancf3d::with_stiffness(0.1, aniso, 4).unwrap(),
    ]
}

#[test]
fn shape_functions_are_the_corrected_eq_5() {
    let le = 0.3;
    // s2 is the Hermite slope function: s2(0) = s2(L) = 0, s2'(0) = 1, s2'(L) = 0
    let h = 1e-6;
    let s2 = |x: f64| Ancf3d::shape_functions(x, 0.0, 0.0, le)[1];
    assert!(s2(0.0).abs() < 1e-15 && s2(le).abs() < 1e-15);
    assert!(((s2(h) - s2(0.0)) / h - 1.0).abs() < 1e-5);
    assert!(((s2(le) - s2(le - h)) / h).abs() < 1e-5);
    // the misprinted 2X³/L² would give s2(L) = L
    // an affine field r = A X + c is reproduced at every material point
    let a = [[1.1, 0.2, -0.3], [0.1, 0.9, 0.4], [-0.2, 0.3, 1.2]];
    let c = [0.5, -0.1, 0.2];
    let field = |x: [f64; 3]| [0, 1, 2].map(|i| c[i] + (0..3).map(|j| a[i][j] * x[j]).sum::<f64>());
    let mut qe = Vec::new();
    for xn in [0.0, le] {
        qe.extend(field([xn, 0.0, 0.0]));
        for j in 0..3 {
            qe.extend(a.map(|row| row[j]));
        }
    }
    let e = Ancf3d::new(le, 1.0, 1.0, 1.0).unwrap();
    for (xi, y, z) in [(0.0, 0.0, 0.0), (0.3, 0.02, -0.01), (1.0, -0.05, 0.03)] {
        let p = e.material_point(&qe, xi, y, z);
        let r = field([xi * le, y, z]);
        for i in 0..3 {
            assert!((p[i] - r[i]).abs() < 1e-14, "{xi} {y} {z}: {p:?} vs {r:?}");
        }
    }
}

#[test]
fn gradient_matches_finite_differences_of_the_energy() {
    for (n, e) in elements().iter().enumerate() {
        let qe = deformed(e.length(), 7 + n as u64);
        let mut g = vec![0.0; ED];
        e.add_energy_gradient(&qe, &mut g);
        let gmax = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        assert!(gmax > 1.0, "a deformed element has forces: {gmax}");
        for i in 0..ED {
            let h = 1e-6;
            let (mut qp, mut qm) = (qe.clone(), qe.clone());
            qp[i] += h;
            qm[i] -= h;
            let fd = (e.energy(&qp) - e.energy(&qm)) / (2.0 * h);
            assert!(
                (g[i] - fd).abs() < 1e-6 * gmax,
                "element {n}, coordinate {i}: {} vs {fd}",
                g[i]
            );
        }
    }
}

#[test]
fn hessian_matches_finite_differences_of_the_gradient() {
    for (n, e) in elements().iter().enumerate() {
        let qe = deformed(e.length(), 11 + n as u64);
        let mut hs = vec![0.0; ED * ED];
        e.add_energy_hessian(&qe, &mut hs);
        let (mut g2, mut h2) = (vec![0.0; ED], vec![0.0; ED * ED]);
        e.add_energy_gradient_and_hessian(&qe, &mut g2, &mut h2);
        let mut g = vec![0.0; ED];
        e.add_energy_gradient(&qe, &mut g);
        let hmax = hs.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        for i in 0..ED {
            assert!((g[i] - g2[i]).abs() < 1e-12 * (1.0 + g[i].abs()));
            let h = 1e-6;
            let (mut qp, mut qm) = (qe.clone(), qe.clone());
            qp[i] += h;
            qm[i] -= h;
            let (mut gp, mut gm) = (vec![0.0; ED], vec![0.0; ED]);
            e.add_energy_gradient(&qp, &mut gp);
            e.add_energy_gradient(&qm, &mut gm);
            for j in 0..ED {
                let fd = (gp[j] - gm[j]) / (2.0 * h);
                let k = hs[j * ED + i];
                assert!(
                    (k - fd).abs() < 1e-6 * hmax,
                    "element {n}, ({j}, {i}): {k} vs {fd}"
                );
                assert!((k - hs[i * ED + j]).abs() < 1e-9 * hmax, "symmetric");
                assert!((k - h2[j * ED + i]).abs() < 1e-12 * hmax);
            }
        }
    }
}

/// `Q v + c` on positions, `Q v` on gradients.
fn move_rigidly(qe: &[f64], rot: &[[f64; 3]; 3], shift: [f64; 3]) -> Vec<f64> {
    let mut out = qe.to_vec();
    for (b, chunk) in qe.chunks(3).enumerate() {
        for i in 0..3 {
            let mut v: f64 = (0..3).map(|j| rot[i][j] * chunk[j]).sum();
            if b % 4 == 0 {
                v += shift[i];
            }
            out[3 * b + i] = v;
        }
    }
    out
}

fn rotation(axis: [f64; 3], angle: f64) -> [[f64; 3]; 3] {
    let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
    let k = axis.map(|x| x / n);
    let (c, s) = (angle.cos(), angle.sin());
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let skew = match (i, j) {
                (0, 1) => -k[2],
                (0, 2) => k[1],
                (1, 0) => k[2],
                (1, 2) => -k[0],
                (2, 0) => -k[1],
                (2, 1) => k[0],
                _ => 0.0,
            };
            r[i][j] = if i == j { c } else { 0.0 } + s * skew + (1.0 - c) * k[i] * k[j];
        }
    }
    r
}

#[test]
fn energy_and_forces_are_invariant_under_rigid_motions() {
    for e in elements() {
        let qe = deformed(e.length(), 3);
        let u = e.energy(&qe);
        assert!(u > 1e-3, "a deformed element stores energy: {u}");
        let mut g = vec![0.0; ED];
        e.add_energy_gradient(&qe, &mut g);
        for (axis, angle, shift) in [
            ([0.0, 0.0, 1.0], 2.0, [1.0, -2.0, 0.5]),
            ([1.0, 1.0, -0.3], -2.9, [0.0, 0.3, 0.0]),
            ([0.2, -1.0, 0.1], 0.7, [-5.0, 0.0, 3.0]),
        ] {
            let rot = rotation(axis, angle);
            let moved = move_rigidly(&qe, &rot, shift);
            assert!((e.energy(&moved) - u).abs() < 1e-12 * u);
            // forces rotate with the body: g(Q q + c) = Q g(q)
            let mut gm = vec![0.0; ED];
            e.add_energy_gradient(&moved, &mut gm);
            let expect = move_rigidly(&g, &rot, [0.0; 3]);
            for i in 0..ED {
                assert!((gm[i] - expect[i]).abs() < 1e-10 * (1.0 + g[i].abs()));
            }
        }
        // a rigid motion of the stress-free element costs nothing
        let mut straight = straight_node(&[0.0; 3], &[1.0, 0.0, 0.0]);
        straight.extend(straight_node(&[e.length(), 0.0, 0.0], &[1.0, 0.0, 0.0]));
        let moved = move_rigidly(&straight, &rotation([1.0, 2.0, 3.0], 1.3), [1.0, 1.0, 1.0]);
        assert!(e.energy(&moved).abs() < 1e-20);
        let mut gm = vec![0.0; ED];
        e.add_energy_gradient(&moved, &mut gm);
        assert!(gm.iter().all(|v| v.abs() < 1e-12));
    }
}

#[test]
fn pure_twist_and_pure_bending_have_their_closed_form_energies() {
    let (le, gj, ei) = (0.2, 0.019, 0.025);
    let e = Ancf3d::new(le, 300.0, ei, gj).unwrap();
    // twist ψ at node 2 about x: τ = ψ/L in the limit of small ψ
    let psi: f64 = 1e-3;
    let mut qe = straight_node(&[0.0; 3], &[1.0, 0.0, 0.0]);
    qe.extend(straight_node(&[le, 0.0, 0.0], &[1.0, 0.0, 0.0]));
    let (c, s) = (psi.cos(), psi.sin());
    qe[18..24].copy_from_slice(&[0.0, c, s, 0.0, -s, c]);
    let u = 0.5 * gj * (psi / le).powi(2) * le;
    assert!(
        (e.energy(&qe) - u).abs() < 1e-6 * u,
        "{} vs {u}",
        e.energy(&qe)
    );
    let [_, _, _, tau] = e.strains(&qe, 0.5);
    assert!((tau - psi / le).abs() < 1e-6 * psi / le);
    // a parabola y = k X²/2 in the xy-plane, frame following the tangent:
    // κ_Z ≈ k (bending about the section's Z axis), no twist
    let k = 1e-3;
    let mut qb = straight_node(&[0.0; 3], &[1.0, 0.0, 0.0]);
    qb.extend(straight_node(
        &[le, 0.5 * k * le * le, 0.0],
        &[1.0, k * le, 0.0],
    ));
    let [_, ky, kz, tau] = e.strains(&qb, 0.5);
    assert!(
        ky.abs() < 1e-12 && tau.abs() < 1e-12 && (kz - k).abs() < 1e-8,
        "{ky} {kz} {tau}"
    );
}

#[test]
fn moment_work_derivatives_match_finite_differences() {
    let reference = straight_node(&[0.0; 3], &[0.0, 0.6, 0.8]);
    let qe = deformed(0.1, 5);
    let node = qe[ND..].to_vec();
    let m = [0.3, -0.2, 0.5];
    let (mut g, mut h) = (vec![0.0; ND], vec![0.0; ND * ND]);
    Ancf3d::add_moment_work(&reference, &node, &m, &mut g, &mut h);
    let w = |n: &[f64]| {
        let phi = Ancf3d::node_rotation(reference.as_slice(), n);
        m[0] * phi[0] + m[1] * phi[1] + m[2] * phi[2]
    };
    let hstep = 1e-6;
    for i in 0..ND {
        let (mut np, mut nm) = (node.clone(), node.clone());
        np[i] += hstep;
        nm[i] -= hstep;
        let fd = (w(&np) - w(&nm)) / (2.0 * hstep);
        assert!((g[i] - fd).abs() < 1e-7, "{i}: {} vs {fd}", g[i]);
        assert!(
            (Ancf3d::moment_work_between(&reference, &nm, &np, &m) - (w(&np) - w(&nm))).abs()
                < 1e-15
        );
        let (mut gp, mut gm) = (vec![0.0; ND], vec![0.0; ND]);
        let mut scratch = vec![0.0; ND * ND];
        Ancf3d::add_moment_work(&reference, &np, &m, &mut gp, &mut scratch);
        Ancf3d::add_moment_work(&reference, &nm, &m, &mut gm, &mut scratch);
        for j in 0..ND {
            let fd = (gp[j] - gm[j]) / (2.0 * hstep);
            assert!(
                (h[j * ND + i] - fd).abs() < 1e-6,
                "({j}, {i}): {} vs {fd}",
                h[j * ND + i]
            );
        }
    }
    // the positions do no work
    assert!(g[..3].iter().all(|v| *v == 0.0));
}

#[test]
fn node_rotation_is_the_rotation_of_the_section_frame() {
    let reference = straight_node(&[0.0; 3], &[1.0, 0.0, 0.0]);
    for (axis, angle) in [
        ([1.0, 0.0, 0.0], 1.2),
        ([0.3, -0.4, 0.5], 2.5),
        ([0.0, 0.0, 1.0], 1e-9),
    ] {
        let rot = rotation(axis, angle);
        let node = move_rigidly(&reference, &rot, [0.0; 3]);
        let phi = Ancf3d::node_rotation(reference.as_slice(), &node);
        let n = (axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]).sqrt();
        for i in 0..3 {
            assert!((phi[i] - angle * axis[i] / n).abs() < 1e-12, "{phi:?}");
        }
        // a stretched tangent and a scaled section do not rotate the node
        let mut scaled = node.clone();
        scaled[3..].iter_mut().for_each(|v| *v *= 1.3);
        let phi2 = Ancf3d::node_rotation(reference.as_slice(), &scaled);
        assert!((0..3).all(|i| (phi[i] - phi2[i]).abs() < 1e-12));
    }
}

#[test]
fn straight_nodes_carry_orthonormal_right_handed_frames() {
    for d in [
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [-1.0, 1e-12, 0.0],
        [0.0, 0.0, 2.0],
        [0.3, -0.4, 0.2],
    ] {
        let node = straight_node(&[1.0, 2.0, 3.0], &d);
        assert_eq!(&node[..6], &[1.0, 2.0, 3.0, d[0], d[1], d[2]]);
        let f = frame_of(&node).unwrap();
        for i in 0..3 {
            for j in 0..3 {
                let dij: f64 = (0..3).map(|k| f[i][k] * f[j][k]).sum();
                assert!(
                    (dij - if i == j { 1.0 } else { 0.0 }).abs() < 1e-12,
                    "{d:?}"
                );
            }
        }
        let t = jet::cross(&f[1], &f[2]);
        assert!(
            (0..3).all(|k| (t[k] - f[0][k]).abs() < 1e-12),
            "right-handed"
        );
        // the stored section gradients are the frame itself
        assert!((0..3).all(|k| (node[6 + k] - f[1][k]).abs() < 1e-12));
        assert_eq!(Ancf3d::clamp_free_directions(&node).ncols(), 1);
    }
    assert!(straight_node(&[0.0; 3], &[0.0; 3])[0].is_nan());
    assert!(Ancf3d::node_tangent(&[0.0; ND])[0].is_nan());
    assert!(Ancf3d::clamp_free_directions(&[0.0; ND]).is_empty());
}

#[test]
fn wrong_sizes_give_nan_and_add_nothing() {
    let e = Ancf3d::new(0.1, 1.0, 1.0, 1.0).unwrap();
    assert!(e.energy(&[0.0; 12]).is_nan());
    let mut g = vec![0.0; 12];
    e.add_energy_gradient(&[1.0; 24], &mut g);
    assert!(g.iter().all(|v| *v == 0.0));
    assert!(e.strains(&[0.0; 23], 0.5)[0].is_nan());
    assert!(e.material_point(&[0.0; 3], 0.5, 0.0, 0.0)[0].is_nan());
    let node = straight_node(&[0.0; 3], &[1.0, 0.0, 0.0]);
    assert!(Ancf3d::node_rotation(&node, &node[..6])[0].is_nan());
    assert!(Ancf3d::moment_work_between(&node, &node, &node, &[1.0]).is_nan());
    let (mut g, mut h) = (vec![0.0; 12], vec![0.0; 144]);
    Ancf3d::add_moment_work(&node, &node, &[1.0, 0.0], &mut g, &mut h);
    assert!(g.iter().chain(&h).all(|v| *v == 0.0));
    for (field, bad) in [
        ("length_m", Ancf3d::new(0.0, 1.0, 1.0, 1.0)),
        ("gj_nm2", Ancf3d::new(0.1, 1.0, 1.0, f64::NAN)),
    ] {
        assert!(bad.unwrap_err().to_string().contains(field));
    }
    let s = Ancf3dStiffness::isotropic(1.0, 1.0, 1.0);
    assert!(
        Ancf3d::with_stiffness(0.1, s, 0)
            .unwrap_err()
            .to_string()
            .contains("gauss_points")
    );
}
