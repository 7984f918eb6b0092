use super::*;
use crate::element::PlanarCable;
use crate::rng::Lcg;

/// A large deformation of an element of length `le`: the second node off
/// the first one's tangent, slopes turned by up to about 60° and stretched
/// by up to ±20 %.
fn deformed(seed: u64, le: f64) -> [f64; 12] {
    let mut r = Lcg::new(seed.wrapping_add(17));
    let mut q = [0.0; 12];
    for (i, v) in q.iter_mut().enumerate() {
        *v = match i {
            0..=2 => 0.1 * le * r.centered(),
            3 => 1.0 + 0.4 * r.centered(),
            4 | 5 => 1.2 * r.centered(),
            6 => le * (1.0 + 0.3 * r.centered()),
            7 | 8 => 0.6 * le * r.centered(),
            9 => 0.9 + 0.4 * r.centered(),
            _ => 1.2 * r.centered(),
        };
    }
    q
}

/// A random rotation matrix (from a random unit quaternion).
fn rotation(seed: u64) -> [[f64; 3]; 3] {
    let mut r = Lcg::new(seed);
    let q = [r.centered(), r.centered(), r.centered(), r.centered()];
    let n = q.iter().map(|v| v * v).sum::<f64>().sqrt();
    let [w, x, y, z] = q.map(|v| v / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

fn rotate(r: &[[f64; 3]; 3], v: &[f64]) -> [f64; 3] {
    [0, 1, 2].map(|i| r[i][0] * v[0] + r[i][1] * v[1] + r[i][2] * v[2])
}

fn max_abs(v: &[f64]) -> f64 {
    v.iter().fold(0.0f64, |m, x| m.max(x.abs()))
}

#[test]
fn gradient_matches_finite_differences() {
    for seed in 0..20 {
        let le = 0.05 + 0.01 * seed as f64;
        let (na, nb) = if seed % 2 == 0 { (5, 3) } else { (4, 4) };
        let e = SpatialCable::with_rules(le, 300.0, 0.025, na, nb).unwrap();
        let q = deformed(seed, le);
        let mut g = [0.0; 12];
        e.add_energy_gradient(&q, &mut g);
        let scale = max_abs(&g);
        assert!(scale > 0.0);
        for i in 0..12 {
            let h = 1e-6 * (1.0 + q[i].abs());
            let (mut qp, mut qm) = (q, q);
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
        let (na, nb) = if seed % 2 == 0 { (5, 5) } else { (5, 3) };
        let e = SpatialCable::with_rules(le, 300.0, 0.025, na, nb).unwrap();
        let q = deformed(seed + 100, le);
        let mut h = [0.0; 144];
        e.add_energy_hessian(&q, &mut h);
        let scale = max_abs(&h);
        for j in 0..12 {
            let d = 1e-6 * (1.0 + q[j].abs());
            let (mut qp, mut qm) = (q, q);
            qp[j] += d;
            qm[j] -= d;
            let (mut gp, mut gm) = ([0.0; 12], [0.0; 12]);
            e.add_energy_gradient(&qp, &mut gp);
            e.add_energy_gradient(&qm, &mut gm);
            for i in 0..12 {
                let fd = (gp[i] - gm[i]) / (2.0 * d);
                assert!(
                    (fd - h[i * 12 + j]).abs() <= 1e-6 * scale,
                    "seed {seed} ({i},{j}): {fd} vs {}",
                    h[i * 12 + j]
                );
                assert!((h[i * 12 + j] - h[j * 12 + i]).abs() <= 1e-12 * scale);
            }
        }
    }
}

#[test]
fn energy_is_invariant_under_rigid_motions_and_the_gradient_rotates() {
    let le = 0.08;
    let e = SpatialCable::with_rules(le, 300.0, 0.025, 5, 3).unwrap();
    for seed in 0..20 {
        let q = deformed(seed + 300, le);
        let rot = rotation(seed + 1000);
        let mut shift = Lcg::new(seed + 2000);
        let t = [shift.centered(), shift.centered(), shift.centered()];
        // positions rotate and translate, slopes rotate
        let mut qr = [0.0; 12];
        for k in 0..4 {
            let v = rotate(&rot, &q[3 * k..3 * k + 3]);
            for i in 0..3 {
                qr[3 * k + i] = v[i] + if k % 2 == 0 { t[i] } else { 0.0 };
            }
        }
        let (u, ur) = (e.energy(&q), e.energy(&qr));
        assert!(u > 1e-3, "a large deformation stores energy: {u}");
        assert!((u - ur).abs() <= 1e-12 * u, "seed {seed}: {u} vs {ur}");
        let (mut g, mut gr) = ([0.0; 12], [0.0; 12]);
        e.add_energy_gradient(&q, &mut g);
        e.add_energy_gradient(&qr, &mut gr);
        let scale = max_abs(&g);
        for k in 0..4 {
            let v = rotate(&rot, &g[3 * k..3 * k + 3]);
            for i in 0..3 {
                assert!(
                    (v[i] - gr[3 * k + i]).abs() <= 1e-12 * scale,
                    "seed {seed} slot {k}: {v:?} vs {:?}",
                    &gr[3 * k..3 * k + 3]
                );
            }
        }
        // and the forces of a rigid translation sum to zero
        for i in 0..3 {
            assert!((g[i] + g[6 + i]).abs() <= 1e-12 * scale);
        }
    }
}

#[test]
fn rigid_motions_of_the_straight_element_store_no_energy() {
    let le = 0.12;
    let e = SpatialCable::new(le, 300.0, 0.025).unwrap();
    for seed in 0..16 {
        let rot = rotation(seed + 50);
        let t = rotate(&rot, &[1.0, 0.0, 0.0]);
        let p = [0.3 * seed as f64, -0.1, 0.2];
        let q = [
            p[0],
            p[1],
            p[2],
            t[0],
            t[1],
            t[2],
            p[0] + le * t[0],
            p[1] + le * t[1],
            p[2] + le * t[2],
            t[0],
            t[1],
            t[2],
        ];
        assert!(e.energy(&q).abs() < 1e-20);
        let mut g = [0.0; 12];
        e.add_energy_gradient(&q, &mut g);
        assert!(g.iter().all(|v| v.abs() < 1e-12), "{g:?}");
    }
}

#[test]
fn a_planar_configuration_reproduces_the_planar_cable() {
    for seed in 0..20 {
        let le = 0.04 + 0.01 * seed as f64;
        let (na, nb) = if seed % 2 == 0 { (5, 3) } else { (5, 5) };
        let planar = PlanarCable::with_rules(le, 300.0, 0.025, 0.0, na, nb).unwrap();
        let spatial = SpatialCable::with_rules(le, 300.0, 0.025, na, nb).unwrap();
        let q3 = deformed(seed + 500, le);
        // the xy-plane: drop z
        let mut q2 = [0.0; 8];
        let mut q3p = [0.0; 12];
        for k in 0..4 {
            q2[2 * k] = q3[3 * k];
            q2[2 * k + 1] = q3[3 * k + 1];
            q3p[3 * k] = q3[3 * k];
            q3p[3 * k + 1] = q3[3 * k + 1];
        }
        let (u2, u3) = (planar.energy(&q2), spatial.energy(&q3p));
        assert!((u2 - u3).abs() <= 1e-12 * u2, "seed {seed}: {u2} vs {u3}");
        let (mut g2, mut g3) = ([0.0; 8], [0.0; 12]);
        planar.add_energy_gradient(&q2, &mut g2);
        spatial.add_energy_gradient(&q3p, &mut g3);
        let scale = max_abs(&g2);
        for k in 0..4 {
            for i in 0..2 {
                let (a, b) = (g2[2 * k + i], g3[3 * k + i]);
                assert!((a - b).abs() <= 1e-12 * scale, "seed {seed}: {a} vs {b}");
            }
            assert_eq!(g3[3 * k + 2], 0.0, "no force out of the plane");
        }
        // the in-plane block of the tangent, too
        let (mut h2, mut h3) = ([0.0; 64], [0.0; 144]);
        planar.add_energy_hessian(&q2, &mut h2);
        spatial.add_energy_hessian(&q3p, &mut h3);
        let scale = max_abs(&h2);
        for r in 0..8 {
            for c in 0..8 {
                let (r3, c3) = (3 * (r / 2) + r % 2, 3 * (c / 2) + c % 2);
                let (a, b) = (h2[r * 8 + c], h3[r3 * 12 + c3]);
                assert!(
                    (a - b).abs() <= 1e-12 * scale,
                    "seed {seed} ({r},{c}): {a} vs {b}"
                );
            }
        }
    }
}

#[test]
fn fused_gradient_and_hessian_equal_the_separate_kernels() {
    for (seed, (na, nb)) in [(5usize, 5usize), (5, 3), (2, 7)].into_iter().enumerate() {
        let le = 0.07;
        let e = SpatialCable::with_rules(le, 300.0, 0.025, na, nb).unwrap();
        let q = deformed(seed as u64 + 40, le);
        let (mut g1, mut h1) = ([0.0; 12], [0.0; 144]);
        e.add_energy_gradient(&q, &mut g1);
        e.add_energy_hessian(&q, &mut h1);
        let (mut g2, mut h2) = ([0.0; 12], [0.0; 144]);
        e.add_energy_gradient_and_hessian(&q, &mut g2, &mut h2);
        assert_eq!(g1, g2);
        assert_eq!(h1, h2);
        // wrong sizes add nothing and give NaN, never a panic
        let mut g3 = [0.0; 12];
        e.add_energy_gradient_and_hessian(&q[..11], &mut g3, &mut h2);
        e.add_energy_gradient(&q[..11], &mut g3);
        assert_eq!(g3, [0.0; 12]);
        assert!(e.energy(&q[..8]).is_nan());
        assert!(e.strains(&q[..8], 0.5).0.is_nan());
    }
}

#[test]
fn coinciding_rules_give_the_energy_of_separate_integrals() {
    let le = 0.09;
    let (ea, ei) = (300.0, 0.025);
    let e = SpatialCable::with_rules(le, ea, ei, 5, 5).unwrap();
    let q = deformed(77, le);
    let rule = crate::quadrature::GaussRule::new(5).unwrap();
    let mut u = 0.0;
    for (xi, w) in rule.iter() {
        let (eps, k) = e.strains(&q, xi);
        u += 0.5 * w * le * (ea * eps * eps + ei * (k[0] * k[0] + k[1] * k[1] + k[2] * k[2]));
    }
    assert!((e.energy(&q) - u).abs() <= 1e-14 * u.abs());
}

#[test]
fn curvature_of_an_arc_in_a_tilted_plane_is_its_binormal_over_the_radius() {
    // an arc of radius R in the plane spanned by rot·e_x, rot·e_y: the
    // Hermite interpolant of a short piece has κ ≈ (1/R) rot·e_z
    let (le, radius) = (0.01, 0.5);
    let e = SpatialCable::new(le, 1.0, 1.0).unwrap();
    let rot = rotation(7);
    let th = le / radius;
    let node = |a: f64| {
        let p = rotate(&rot, &[radius * a.sin(), radius * (1.0 - a.cos()), 0.0]);
        let t = rotate(&rot, &[a.cos(), a.sin(), 0.0]);
        [p[0], p[1], p[2], t[0], t[1], t[2]]
    };
    let mut q = [0.0; 12];
    q[..6].copy_from_slice(&node(0.0));
    q[6..].copy_from_slice(&node(th));
    let (eps, k) = e.strains(&q, 0.5);
    let b = rotate(&rot, &[0.0, 0.0, 1.0]);
    assert!(eps.abs() < 1e-8, "{eps}");
    for i in 0..3 {
        assert!((k[i] - b[i] / radius).abs() < 5e-5 / radius, "{k:?} {b:?}");
    }
}

#[test]
fn rotation_factor_series_and_closed_form_agree() {
    // h(c) = θ / sin θ, its derivatives by central differences of the closed form
    for c in [0.999, 0.9, 0.6, 0.5 + 1e-12, 0.5 - 1e-12, 0.2, -0.5, -0.9] {
        let (h, h1, h2) = rotation_factor(c);
        let th = f64::acos(c);
        assert!((h - th / th.sin()).abs() <= 1e-14 * h, "{c}");
        let d = 1e-5;
        let (hp, h1p, _) = rotation_factor(c + d);
        let (hm, h1m, _) = rotation_factor(c - d);
        assert!(
            ((hp - hm) / (2.0 * d) - h1).abs() <= 1e-8 * h1.abs().max(1.0),
            "{c}"
        );
        assert!(
            ((h1p - h1m) / (2.0 * d) - h2).abs() <= 1e-7 * h2.abs().max(1.0),
            "{c}"
        );
    }
    // the two branches meet at 1 − c = 0.5 to round-off, values and derivatives
    let (a, b) = (rotation_factor(0.5 + 1e-15), rotation_factor(0.5 - 1e-15));
    assert!((a.0 - b.0).abs() < 1e-14 && (a.1 - b.1).abs() < 1e-13 && (a.2 - b.2).abs() < 1e-12);
    let (h, h1, h2) = rotation_factor(1.0);
    assert!(h == 1.0 && (h1 + 1.0 / 3.0).abs() < 1e-16 && (h2 - 4.0 / 15.0).abs() < 1e-16);
}

/// Node coordinates with the slope `u`.
fn node_with_slope(u: [f64; 3]) -> [f64; 6] {
    [0.1, -0.2, 0.3, u[0], u[1], u[2]]
}

#[test]
fn moment_work_derivatives_match_finite_differences() {
    let reference = node_with_slope([0.6, 0.0, 0.8]);
    let m = [0.7, -0.3, 0.45];
    let work = |n: &[f64; 6]| {
        let phi = SpatialCable::node_rotation(&reference, n);
        m[0] * phi[0] + m[1] * phi[1] + m[2] * phi[2]
    };
    // small turns (the series branch), large ones (the closed form), stretch
    let slopes = [
        [0.6, 0.0, 0.8],
        [0.61, 0.01, 0.79],
        [0.7, 0.2, 0.6],
        [1.1, -0.4, 0.3],
        [0.0, 1.3, 0.0],
        [-0.5, 0.5, -0.3],
    ];
    for u in slopes {
        let node = node_with_slope(u);
        let (mut g, mut h) = ([0.0; 6], [0.0; 36]);
        SpatialCable::add_moment_work(&reference, &node, &m, &mut g, &mut h);
        let (gs, hs) = (max_abs(&g).max(1e-3), max_abs(&h).max(1e-3));
        assert!(g[..3].iter().all(|v| *v == 0.0), "positions do no work");
        for j in 0..6 {
            let d = 1e-6;
            let (mut p, mut q) = (node, node);
            p[j] += d;
            q[j] -= d;
            let fd = (work(&p) - work(&q)) / (2.0 * d);
            assert!((fd - g[j]).abs() < 1e-8 * gs, "{u:?} {j}: {fd} vs {}", g[j]);
            let (mut gp, mut gm, mut scratch) = ([0.0; 6], [0.0; 6], [0.0; 36]);
            SpatialCable::add_moment_work(&reference, &p, &m, &mut gp, &mut scratch);
            SpatialCable::add_moment_work(&reference, &q, &m, &mut gm, &mut scratch);
            for i in 0..6 {
                let fd = (gp[i] - gm[i]) / (2.0 * d);
                assert!((fd - h[i * 6 + j]).abs() < 1e-7 * hs, "{u:?} ({i},{j})");
                assert!((h[i * 6 + j] - h[j * 6 + i]).abs() <= 1e-14 * hs);
            }
        }
        // the work between two nodes is the difference of the works
        let from = node_with_slope([0.7, 0.2, 0.6]);
        let w = SpatialCable::moment_work_between(&reference, &from, &node, &m);
        assert!((w - (work(&node) - work(&from))).abs() < 1e-15);
    }
}

#[test]
fn in_plane_moment_work_is_the_planar_angle_times_the_moment() {
    let r2 = [0.0, 0.0, 0.8, 0.6];
    let r3 = [0.0, 0.0, 0.0, 0.8, 0.6, 0.0];
    for k in 0..12 {
        let th = -2.9 + 0.5 * k as f64;
        let (x, y) = (1.2 * th.cos(), 1.2 * th.sin());
        let n2 = [0.0, 0.0, x, y];
        let n3 = [0.0, 0.0, 0.0, x, y, 0.0];
        let phi = SpatialCable::node_rotation(&r3, &n3);
        let theta = PlanarCable::node_rotation(&r2, &n2)[0];
        assert!(phi[0].abs() < 1e-15 && phi[1].abs() < 1e-15);
        assert!((phi[2] - theta).abs() < 1e-14, "{phi:?} vs {theta}");
        let m = 0.3;
        let (mut g2, mut h2) = ([0.0; 4], [0.0; 16]);
        let (mut g3, mut h3) = ([0.0; 6], [0.0; 36]);
        PlanarCable::add_moment_work(&r2, &n2, &[m], &mut g2, &mut h2);
        SpatialCable::add_moment_work(&r3, &n3, &[0.0, 0.0, m], &mut g3, &mut h3);
        for (i, i3) in [(2, 3), (3, 4)] {
            assert!((g2[i] - g3[i3]).abs() < 1e-14, "{k}: {g2:?} {g3:?}");
            // (θ from the reference reaches 3.04 rad: h' loses digits near π)
            for (j, j3) in [(2, 3), (3, 4)] {
                let (a, b) = (h2[i * 4 + j], h3[i3 * 6 + j3]);
                assert!((a - b).abs() < 1e-11 * max_abs(&h2), "{k}: {a} vs {b}");
            }
        }
        assert!(g3[5].abs() < 1e-15);
    }
}

#[test]
fn a_moment_along_the_reference_tangent_does_no_work() {
    let reference = node_with_slope([0.0, 0.0, 2.0]);
    for u in [[0.3, 0.1, 1.0], [1.0, -0.4, 0.2], [0.0, 0.0, 0.5]] {
        let node = node_with_slope(u);
        let (mut g, mut h) = ([0.0; 6], [0.0; 36]);
        SpatialCable::add_moment_work(&reference, &node, &[0.0, 0.0, 5.0], &mut g, &mut h);
        assert!(g.iter().chain(&h).all(|v| *v == 0.0));
        let phi = SpatialCable::node_rotation(&reference, &node);
        assert!(phi[2] == 0.0);
    }
}

#[test]
fn node_kinematics_of_bad_slices_are_nan_or_empty() {
    let n = [0.0; 5];
    assert!(
        SpatialCable::straight_node(&[0.0; 2], &[1.0, 0.0, 0.0])
            .iter()
            .all(|v| v.is_nan())
    );
    assert!(SpatialCable::node_tangent(&n).iter().all(|v| v.is_nan()));
    assert!(SpatialCable::clamp_free_directions(&n).is_empty());
    let good = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0];
    assert!(
        SpatialCable::node_rotation(&good, &[0.0; 6])
            .iter()
            .all(|v| v.is_nan())
    );
    assert!(SpatialCable::moment_work_between(&good, &good, &good, &[1.0]).is_nan());
    let (mut g, mut h) = ([0.0; 6], [0.0; 36]);
    SpatialCable::add_moment_work(&good, &good, &[1.0, 2.0], &mut g, &mut h);
    SpatialCable::add_moment_work(&good, &good, &[1.0, 2.0, 3.0], &mut g[..5], &mut h);
    assert!(g.iter().chain(&h).all(|v| *v == 0.0));
    assert_eq!(
        SpatialCable::clamp_free_directions(&[0.0, 0.0, 0.0, 0.0, 2.0, 0.0]),
        nalgebra::DMatrix::from_column_slice(6, 1, &[0.0, 0.0, 0.0, 0.0, 1.0, 0.0])
    );
}
