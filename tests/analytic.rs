//! Analytic verification of the static model (issue "Foundation", point 5).
//!
//! Each test states its tolerance and why. All use a clamped cantilever along
//! +x with the paper's stiffnesses (EI = 0.025 N·m², EA = 300 N, L = 0.24 m).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::assembly::{Robot, RobotSpec, Section};
use softrod::element::PlanarCable;
use softrod::loads::{LineLoad, Loads, NodeMoment, PointForce};
use softrod::statics::StaticSolver;

const L: f64 = 0.24;
const EI: f64 = 0.025;
const EA: f64 = 300.0;

fn cantilever(elements: usize) -> Robot<PlanarCable> {
    let mut spec = RobotSpec::new(vec![Section::uniform(L, EA, EI, elements)]);
    spec.gravity_m_per_s2 = vec![0.0, 0.0];
    spec.build_planar().unwrap()
}

fn tip(robot: &Robot<PlanarCable>, loads: &Loads) -> [f64; 4] {
    let eq = StaticSolver::default().solve(robot, loads, None).unwrap();
    assert!(eq.report.status.is_converged());
    let n = eq.q.len();
    [eq.q[n - 4], eq.q[n - 3], eq.q[n - 2], eq.q[n - 1]]
}

/// A tip moment bends the cantilever into a circular arc of curvature
/// `M/EI` (no axial force, so no stretch): tip at `(sin(κL)/κ, (1 − cos κL)/κ)`.
/// Here a quarter circle. The cubic Hermite interpolation cannot represent an
/// arc exactly, so the tip error must fall with refinement; the observed order
/// (log2 of successive error ratios) must be at least 3.5 (cubic
/// interpolation of a smooth curve: O(h⁴) in positions), and at 32 elements
/// the error must be below 1e-7 L.
#[test]
fn tip_moment_gives_a_circular_arc_with_fourth_order_convergence() {
    let kappa = std::f64::consts::FRAC_PI_2 / L;
    let m = EI * kappa;
    let exact = [(kappa * L).sin() / kappa, (1.0 - (kappa * L).cos()) / kappa];
    let mut errors = Vec::new();
    for &n in &[2usize, 4, 8, 16, 32] {
        let robot = cantilever(n);
        let loads = Loads {
            node_moments: vec![NodeMoment {
                node: n,
                moment_nm: vec![m],
            }],
            ..Loads::default()
        };
        let t = tip(&robot, &loads);
        let err = ((t[0] - exact[0]).powi(2) + (t[1] - exact[1]).powi(2)).sqrt();
        // the tip slope turns by exactly κL = 90° in the exact solution
        let angle_err = (t[3].atan2(t[2]) - kappa * L).abs();
        println!("n = {n}: tip error {err:.3e} m, tip angle error {angle_err:.3e} rad");
        assert!(
            angle_err < 1e-2 / (n * n) as f64,
            "n = {n}: tip angle error {angle_err}"
        );
        errors.push((n, err));
    }
    let orders: Vec<f64> = errors
        .windows(2)
        .map(|w| (w[0].1 / w[1].1).log2())
        .collect();
    println!("tip-moment arc: errors {errors:?}, observed orders {orders:?}");
    for o in &orders[1..] {
        assert!(*o >= 3.5, "observed order {o} (errors {errors:?})");
    }
    assert!(errors[4].1 < 1e-7 * L, "{errors:?}");
}

/// Small-deflection uniform load: Euler–Bernoulli gives `w L⁴ / (8 EI)`.
/// The load makes the deflection 1e-4 L, so geometric nonlinearity changes it
/// by O((δ/L)²) ≈ 1e-8 relative; Hermite elements with a consistent load
/// vector are nodally exact for a uniform load. Bound: 0.1 % (the issue's),
/// and we also check the far tighter 1e-5 that the argument above predicts.
#[test]
fn uniform_load_small_deflection_matches_wl4_over_8ei() {
    let w = 1e-4 * L * 8.0 * EI / L.powi(4); // δ = 1e-4 L
    let robot = cantilever(8);
    let loads = Loads {
        line_loads: vec![LineLoad::Uniform {
            w_n_per_m: vec![0.0, -w],
        }],
        ..Loads::default()
    };
    let t = tip(&robot, &loads);
    let exact = w * L.powi(4) / (8.0 * EI);
    let rel = (-t[1] - exact).abs() / exact;
    println!(
        "uniform load: tip deflection {:.6e} m vs {exact:.6e} m, relative error {rel:.2e}",
        -t[1]
    );
    assert!(rel < 1e-3);
    assert!(rel < 1e-5);
}

/// Tip force in the linear range: `P L³ / (3 EI)`. Same argument and bounds
/// as the uniform load (Hermite elements are nodally exact for point loads).
#[test]
fn tip_force_small_deflection_matches_pl3_over_3ei() {
    let p = 1e-4 * L * 3.0 * EI / L.powi(3);
    let robot = cantilever(4);
    let loads = Loads {
        point_forces: vec![PointForce {
            s_m: L,
            force_n: vec![0.0, -p],
        }],
        ..Loads::default()
    };
    let t = tip(&robot, &loads);
    let exact = p * L.powi(3) / (3.0 * EI);
    let rel = (-t[1] - exact).abs() / exact;
    println!(
        "tip force: tip deflection {:.6e} m vs {exact:.6e} m, relative error {rel:.2e}",
        -t[1]
    );
    assert!(rel < 1e-3);
    assert!(rel < 1e-5);
}

/// An axial tip force stretches the cantilever by `P L / EA`. The model's
/// axial strain `|r'| − 1` makes the axial force exactly `EA ε`, so the result
/// is exact up to round-off even for a large stretch (here 10 %): bound 1e-9
/// relative.
#[test]
fn axial_tip_force_stretches_by_pl_over_ea() {
    for &p in &[0.3, 30.0] {
        let robot = cantilever(6);
        let loads = Loads {
            point_forces: vec![PointForce {
                s_m: L,
                force_n: vec![p, 0.0],
            }],
            ..Loads::default()
        };
        let t = tip(&robot, &loads);
        let exact = p * L / EA;
        let rel = ((t[0] - L) - exact).abs() / exact;
        println!(
            "axial force {p} N: stretch {:.6e} m vs {exact:.6e} m, relative error {rel:.2e}",
            t[0] - L
        );
        assert!(rel < 1e-9);
        assert!(t[1].abs() < 1e-12);
    }
}
