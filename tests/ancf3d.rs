//! The full 3-D ANCF element (`Ancf3d`, 12 coordinates per node) on a
//! clamped rod through the crate's robot assembly and static solver,
//! against closed forms: axial `PL/EA`, tip load `PL³/3EI` in both bending
//! planes (different stiffnesses), self-weight `wL⁴/8EI`, twist `TL/GJ`
//! (large), and a tip moment rolling the rod into a circular arc of
//! curvature `M/EI` in both planes. Each converged answer within `1e-5 L`
//! (or `1e-5 rad`), with the observed orders printed (`--nocapture`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::assembly::{Robot, RobotSpec, Section};
use softrod::element::{Ancf3d, Ancf3dStiffness, Element, NodeKinematics};
use softrod::loads::{Loads, NodeMoment, PointForce};
use softrod::statics::StaticSolver;

const L: f64 = 0.24;
const EA: f64 = 300.0;
/// Bending about the section's Y axis (deflection along z).
const EI_Y: f64 = 0.025;
/// Bending about the section's Z axis (deflection along y): different, so
/// a mix-up of the planes shows.
const EI_Z: f64 = 0.04;
const GJ: f64 = 0.019;
const ND: usize = 12;

fn stiffness() -> Ancf3dStiffness {
    let mut s = Ancf3dStiffness::isotropic(EA, EI_Y, GJ);
    s.ei_z_nm2 = EI_Z;
    s
}

/// A rod of length `L` along +x from the origin, `n` elements, no gravity
/// unless `mass_kg_per_m` is given (then g = 9.81 m/s² along −z).
fn robot(n: usize, mass_kg_per_m: f64) -> Robot<Ancf3d> {
    let mut sec = Section::uniform(L, EA, EI_Y, n);
    sec.mass_per_length_kg_per_m = mass_kg_per_m;
    let mut spec = RobotSpec::spatial(vec![sec]);
    if mass_kg_per_m == 0.0 {
        spec.gravity_m_per_s2 = vec![0.0; 3];
    }
    Robot::new(spec, |_, le, ax, be| {
        Ancf3d::with_stiffness(le, stiffness(), ax.max(be))
    })
    .unwrap()
}

fn solve(robot: &Robot<Ancf3d>, loads: &Loads) -> Vec<f64> {
    let eq = StaticSolver::default().solve(robot, loads, None).unwrap();
    assert!(eq.report.status.is_converged());
    eq.q.data.into()
}

fn tip(q: &[f64]) -> &[f64] {
    &q[q.len() - ND..]
}

fn tip_force(f: [f64; 3]) -> Loads {
    Loads {
        point_forces: vec![PointForce {
            s_m: L,
            force_n: f.to_vec(),
        }],
        ..Loads::default()
    }
}

fn tip_moment(n: usize, m: [f64; 3]) -> Loads {
    Loads {
        node_moments: vec![NodeMoment {
            node: n,
            moment_nm: m.to_vec(),
        }],
        ..Loads::default()
    }
}

/// Observed orders `log2(e_n / e_2n)` of errors on meshes doubling.
fn orders(errors: &[f64]) -> Vec<f64> {
    errors.windows(2).map(|w| (w[0] / w[1]).log2()).collect()
}

fn print_table(case: &str, meshes: &[usize], errors: &[f64]) {
    let o = orders(errors);
    for (i, (n, e)) in meshes.iter().zip(errors).enumerate() {
        let order = if i == 0 {
            String::new()
        } else {
            format!("{:.2}", o[i - 1])
        };
        println!("{case:<28} {n:>4} elements  error {e:.3e}  order {order}");
    }
}

#[test]
fn the_robot_holds_twelve_coordinates_per_node_and_a_stress_free_reference() {
    let r = robot(4, 0.0);
    assert_eq!(Ancf3d::NODE_DOFS, 12);
    assert_eq!((r.n_q(), r.n_free(), r.n_base_free()), (60, 49, 1));
    let q = r.reference_configuration();
    assert!(r.elastic_energy(q.as_slice()).unwrap() < 1e-24);
    // the robot's centreline interpolation reads the Hermite slots of 12-coordinate nodes
    let mut p = [0.0; 3];
    p.copy_from_slice(r.position_at(q.as_slice(), 0.1).unwrap().as_slice());
    assert!((p[0] - 0.1).abs() < 1e-15 && p[1] == 0.0 && p[2] == 0.0);
    // straight nodes: r_X along x, r_Y = e_y, r_Z = e_z
    assert_eq!(
        &q.as_slice()[ND..2 * ND],
        &[0.06, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
    );
}

#[test]
fn axial_tip_force_stretches_by_pl_over_ea() {
    let p = 3.0;
    for n in [1, 4, 16] {
        let q = solve(&robot(n, 0.0), &tip_force([p, 0.0, 0.0]));
        let err = (tip(&q)[0] - L * (1.0 + p / EA)).abs();
        println!("axial PL/EA                  {n:>4} elements  error {err:.3e}");
        assert!(err < 1e-5 * L, "{n}: {err}");
        // nothing bends or twists
        assert!(tip(&q)[1].abs() < 1e-14 && tip(&q)[2].abs() < 1e-14);
    }
}

#[test]
fn tip_load_deflects_by_pl3_over_3ei_in_both_bending_planes() {
    // δ/L = 1e-3: the geometric nonlinearity is ~1e-9 L
    for (axis, ei) in [(1, EI_Z), (2, EI_Y)] {
        let p = 3.0 * ei * 1e-3 / (L * L);
        let mut f = [0.0; 3];
        f[axis] = -p;
        for n in [1, 2, 8] {
            let r = robot(n, 0.0);
            let q = solve(&r, &tip_force(f));
            let d = p * L.powi(3) / (3.0 * ei);
            let err = (tip(&q)[axis] + d).abs();
            println!("tip load PL³/3EI, axis {axis}      {n:>4} elements  error {err:.3e}");
            assert!(err < 1e-5 * L, "axis {axis}, {n}: {err}");
            // the other plane stays at rest, and the tip slope is PL²/2EI
            assert!(tip(&q)[3 - axis].abs() < 1e-14);
            let slope = tip(&q)[3 + axis] / tip(&q)[3];
            assert!((slope + p * L * L / (2.0 * ei)).abs() < 1e-5, "{slope}");
            let phi = Ancf3d::node_rotation(r.base_node(), tip(&q));
            assert!(phi[0].abs() < 1e-14, "no twist: {phi:?}");
        }
    }
}

#[test]
fn self_weight_deflects_by_wl4_over_8ei() {
    // the self-weight goes through the centreline's Hermite slots of every element
    let m = 0.01;
    let w = m * 9.81;
    let d = w * L.powi(4) / (8.0 * EI_Y);
    for n in [2, 8] {
        let q = solve(&robot(n, m), &Loads::default());
        let err = (tip(&q)[2] + d).abs();
        println!("self-weight wL⁴/8EI          {n:>4} elements  error {err:.3e}");
        assert!(err < 1e-5 * L, "{n}: {err}");
    }
}

#[test]
fn tip_torque_twists_by_tl_over_gj() {
    // a large twist: 1.5 rad (a straight rod under a torque twists
    // uniformly, exactly TL/GJ at any angle)
    let psi = 1.5;
    let t = psi * GJ / L;
    let meshes = [2, 4, 8, 16];
    let mut errors = Vec::new();
    for n in meshes {
        let r = robot(n, 0.0);
        let q = solve(&r, &tip_moment(n, [t, 0.0, 0.0]));
        let phi = Ancf3d::node_rotation(r.base_node(), tip(&q));
        errors.push((phi[0] - psi).abs());
        // the centreline stays straight and unstretched
        assert!((tip(&q)[0] - L).abs() < 1e-9 && tip(&q)[1].abs() < 1e-12);
        assert!(phi[1].abs() < 1e-12 && phi[2].abs() < 1e-12);
    }
    print_table("twist TL/GJ (1.5 rad)", &meshes, &errors);
    assert!(errors[meshes.len() - 1] < 1e-5, "{errors:?}");
    // observed: h⁴ (the linearly interpolated section gradients of a
    // uniformly twisted rod err by O(Δ³) in the twist rate, Δ the twist per element)
    for o in orders(&errors[..errors.len() - 1]) {
        assert!(o > 3.5, "{errors:?}");
    }
}

/// The arc of curvature `k` along x, bending towards `axis` (1: y, 2: z):
/// the point at arc length `s`.
fn arc(k: f64, s: f64, axis: usize) -> [f64; 3] {
    let mut p = [(k * s).sin() / k, 0.0, 0.0];
    p[axis] = (1.0 - (k * s).cos()) / k;
    p
}

#[test]
fn tip_moment_rolls_the_rod_into_a_circular_arc_in_both_planes() {
    // an arc of 2.5 rad (the work of a moment is a potential of the tip
    // frame only below a half turn)
    let theta = 2.5;
    let meshes = [4, 8, 16, 32];
    for (axis, ei, m_axis, sign) in [(1, EI_Z, 2, 1.0), (2, EI_Y, 1, -1.0)] {
        let m = theta * ei / L;
        let k = m / ei;
        let mut moment = [0.0; 3];
        moment[m_axis] = sign * m;
        let (mut errors, mut turn_errors) = (Vec::new(), Vec::new());
        for n in meshes {
            let r = robot(n, 0.0);
            let q = solve(&r, &tip_moment(n, moment));
            // every node on the arc, and the tip turned by θ
            let mut err = 0.0f64;
            for (i, s) in r.node_arc().iter().enumerate() {
                let a = arc(k, *s, axis);
                for c in 0..3 {
                    err = err.max((q[i * ND + c] - a[c]).abs());
                }
            }
            let phi = Ancf3d::node_rotation(r.base_node(), tip(&q));
            assert!(
                phi[3 - m_axis].abs() < 1e-12 && phi[0].abs() < 1e-12,
                "{phi:?}"
            );
            errors.push(err);
            turn_errors.push((phi[m_axis] - sign * theta).abs());
        }
        print_table(&format!("tip moment, arc towards {axis}"), &meshes, &errors);
        print_table(
            &format!("tip moment, tip turn ({axis})"),
            &meshes,
            &turn_errors,
        );
        assert!(errors[meshes.len() - 1] < 1e-5 * L, "{errors:?}");
        assert!(turn_errors[meshes.len() - 1] < 1e-5, "{turn_errors:?}");
        for o in orders(&errors).into_iter().chain(orders(&turn_errors)) {
            assert!(o > 3.5, "{errors:?} {turn_errors:?}");
        }
    }
}

#[test]
fn the_element_energy_of_the_arc_is_the_bending_energy() {
    // a consistency check of what the solver minimizes: the exact arc's
    // nodes (frame following the tangent) store ½ EI k² L up to the
    // interpolation error
    let (n, k) = (32, 2.0);
    let r = robot(n, 0.0);
    let mut q = Vec::new();
    for s in r.node_arc() {
        let p = arc(k, *s, 1);
        let (c, sn) = ((k * s).cos(), (k * s).sin());
        q.extend(p);
        q.extend([c, sn, 0.0, -sn, c, 0.0, 0.0, 0.0, 1.0]);
    }
    let u = r.elastic_energy(&q).unwrap();
    let exact = 0.5 * EI_Z * k * k * L;
    assert!((u - exact).abs() < 1e-6 * exact, "{u} vs {exact}");
    assert!(r.elements()[0].length() > 0.0);
}
