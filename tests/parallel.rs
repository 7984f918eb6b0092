//! The soft parallel robot: closed forms (each identical leg carries W/3
//! of an axial load; the platform's twist under a torque about the
//! vertical axis, with and without torsion) and the measurement that
//! decides between spatial-cable and full 3-D legs.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::parallel::{ParallelRobot, ParallelSpec};

/// Three vertical legs (platform radius = base radius), no weight.
fn vertical() -> ParallelSpec {
    let mut spec = ParallelSpec::default();
    spec.platform_radius_m = spec.base_radius_m;
    spec.platform_disc_radius_m = spec.base_radius_m;
    spec.gravity_m_per_s2 = vec![0.0; 3];
    spec.mass_per_length_kg_per_m = 0.0;
    spec.platform_mass_kg = 0.0;
    spec
}

fn twist<E: softrod::element::Element>(robot: &ParallelRobot<E>, torque_nm: f64) -> [f64; 6] {
    let loads = robot.loads(&[], [0.0; 3], [0.0, 0.0, torque_nm]).unwrap();
    let eq = robot.solve(&loads, None).unwrap();
    robot.platform_pose(eq.q.as_slice()).unwrap().into()
}

/// An axial load W on the platform's centre: each of the three identical
/// legs carries W/3 (by the joint reactions, 1e-9 relative), and the
/// platform sinks by `W L / (3 EA)` (small load: 1e-6 relative).
#[test]
fn each_leg_carries_a_third_of_an_axial_load() {
    let spec = vertical();
    let w = 0.5;
    let robot = spec.build_full().unwrap();
    let loads = robot.loads(&[], [0.0, 0.0, -w], [0.0; 3]).unwrap();
    let eq = robot.solve(&loads, None).unwrap();
    let s = robot.structure();
    let reactions = s
        .joint_reactions(
            eq.u.as_slice(),
            s.dead_force(&loads).unwrap().as_slice(),
            &loads,
        )
        .unwrap();
    assert_eq!(reactions.len(), 3);
    for r in &reactions {
        // what the leg exerts on the platform: W/3 upwards
        let rel = (r.force_n[2] - w / 3.0).abs() / (w / 3.0);
        println!(
            "leg {}: axial force {:.12} N (W/3 = {:.12}), rel {rel:.1e}",
            r.joint,
            r.force_n[2],
            w / 3.0
        );
        assert!(rel < 1e-9, "leg {}: {rel:e}", r.joint);
        assert!(r.force_n[0].abs() < 1e-9 * w && r.force_n[1].abs() < 1e-9 * w);
    }
    let dz =
        robot.platform_pose(eq.q.as_slice()).unwrap()[2] - spec.platform_reference_m().unwrap()[2];
    let closed = -w * spec.leg_length_m / (3.0 * spec.ea_n);
    let rel = (dz / closed - 1.0).abs();
    println!("platform drop {dz:.9e} m, W L/(3 EA) = {closed:.9e} m, rel {rel:.1e}");
    assert!(rel < 1e-6, "drop: {rel:e}");
}

/// A torque T about the vertical axis turns the platform by
/// `T / (3 (12 EI ρ²/L³ + GJ/L))` with full 3-D legs (each bends as a
/// clamped–guided beam and twists) and by `T / (3 · 12 EI ρ²/L³)` with
/// spatial-cable legs (no torsional stiffness), each within 1e-6 relative
/// at a small torque (1 mN·m: rotations of 4e-4 rad, the closed forms'
/// small-rotation error is of that order squared).
#[test]
fn platform_twist_under_a_torque_matches_both_closed_forms() {
    let spec = vertical();
    let (l, rho, ei, gj) = (
        spec.leg_length_m,
        spec.base_radius_m,
        spec.ei_nm2,
        spec.gj_nm2,
    );
    let t = 1e-3;
    let bending = 12.0 * ei * rho * rho / l.powi(3);
    let with_torsion = t / (3.0 * (bending + gj / l));
    let without = t / (3.0 * bending);
    let full = twist(&spec.build_full().unwrap(), t);
    let cable = twist(&spec.build_cable().unwrap(), t);
    let (ef, ec) = (full[5] / with_torsion - 1.0, cable[5] / without - 1.0);
    println!(
        "twist: full {:.9e} rad (closed {with_torsion:.9e}, rel {ef:.1e}); cable {:.9e} rad (closed {without:.9e}, rel {ec:.1e})",
        full[5], cable[5]
    );
    assert!(ef.abs() < 1e-6 && ec.abs() < 1e-6);
    // the twist is about z only, the platform stays put
    for v in [full, cable] {
        assert!(v[3].abs() < 1e-12 && v[4].abs() < 1e-12);
        assert!(v[0].abs() < 1e-9 && v[1].abs() < 1e-9);
    }
    // the two models differ by the torsion's share, GJ/L against 12 EI ρ²/L³
    assert!(cable[5] / full[5] - 1.0 > 0.2);
}

/// The decision: the default robot (inclined legs, weight, actuated) with
/// full 3-D legs and with spatial-cable legs. Under a vertical payload or a
/// lateral force with the chambers vented the two agree to 1e-5 mm (the
/// legs do not twist); with the chambers pressurized (the legs lean into a
/// twisted shape) and under a torque they differ by more than the marker
/// noise (σ = 0.05 mm): the scene needs the full element.
#[test]
fn the_actuated_robot_needs_section_frames() {
    let spec = ParallelSpec::default();
    let full = spec.build_full().unwrap();
    let cable = spec.build_cable().unwrap();
    let mut p = vec![0.0; spec.n_pressures()];
    for leg in 0..spec.legs {
        p[leg * 6] = 60e3; // section 1, chamber 0
        p[leg * 6 + 4] = 30e3; // section 2, chamber 1
    }
    type Case<'a> = (&'a str, &'a [f64], [f64; 3], [f64; 3]);
    let cases: [Case; 4] = [
        (
            "payload 200 g, vented",
            &[],
            [0.0, 0.0, -0.2 * 9.81],
            [0.0; 3],
        ),
        ("lateral 0.2 N, vented", &[], [0.2, 0.0, 0.0], [0.0; 3]),
        ("torque 5 mN·m, vented", &[], [0.0; 3], [0.0, 0.0, 5e-3]),
        (
            "payload 200 g, actuated",
            &p,
            [0.0, 0.0, -0.2 * 9.81],
            [0.0; 3],
        ),
    ];
    let mut gaps = Vec::new();
    for (name, pr, f, m) in cases {
        let ef = full.solve(&full.loads(pr, f, m).unwrap(), None).unwrap();
        let ec = cable.solve(&cable.loads(pr, f, m).unwrap(), None).unwrap();
        let (a, b) = (
            full.platform_pose(ef.q.as_slice()).unwrap(),
            cable.platform_pose(ec.q.as_slice()).unwrap(),
        );
        let dx = (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
        println!(
            "{name}: |x_full − x_cable| = {:.3e} mm, twist full {:.4e} rad, cable {:.4e} rad",
            dx * 1e3,
            a[5],
            b[5]
        );
        gaps.push((dx, a[5], b[5]));
    }
    assert!(gaps[0].0 < 1e-8 && gaps[1].0 < 1e-8);
    // torque: 30 % more twist without torsion (GJ/L against 12 EI ρ²/L³ of inclined legs)
    assert!(gaps[2].2 / gaps[2].1 > 1.25);
    // actuated: the platform positions differ by more than 2 σ
    assert!(gaps[3].0 > 2.0 * 0.05e-3, "{:e}", gaps[3].0);
}
