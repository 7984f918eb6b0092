//! The stability of the static solver's answer: a column clamped pointing
//! up under its own weight beyond its buckling load (`q L³/EI = 12`, the
//! straight column buckles at 7.837) has a straight equilibrium, a saddle of
//! the potential, and a bent, stable one. The solver must return the bent
//! one, report it stable, and its tangent must be positive definite
//! (checked here by a dense eigen-decomposition, not by the solver's own
//! `L D Lᵀ`); its tip must sit where the extensible elastica puts it
//! (`reference/elastica_heavy_column.json`, shooting by
//! `validation/elastica_heavy_column.py`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "common/statics_cases.rs"]
mod cases;
mod common;

use nalgebra::{DMatrix, SymmetricEigen};
use softrod::linsolve::SymmetricMatrix;
use softrod::statics::StaticSolver;

/// The smallest eigenvalue of the robot's tangent at `q`, over the largest
/// diagonal entry (dense, by nalgebra's symmetric eigen-decomposition).
fn smallest_relative_eigenvalue(
    robot: &softrod::assembly::Robot<softrod::element::PlanarCable>,
    q: &[f64],
    loads: &softrod::loads::Loads,
) -> f64 {
    let mut k = SymmetricMatrix::zeros(robot.tangent_pattern().clone());
    robot.tangent_into(q, loads, &mut k).unwrap();
    let n = k.n();
    let dense = DMatrix::from_fn(n, n, |i, j| k.get(i, j));
    let scale = (0..n).fold(0.0f64, |m, i| m.max(dense[(i, i)].abs()));
    let eig = SymmetricEigen::new(dense);
    eig.eigenvalues.iter().fold(f64::INFINITY, |m, v| m.min(*v)) / scale
}

#[test]
fn the_column_buckles() {
    let reference = common::reference("elastica_heavy_column");
    let tip_ref: Vec<f64> = reference["values"]["tip_position_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    // the mesh's discretization error of the tip (measured: 9.4e-5 m at 8
    // elements, 3.6e-7 at 32, 1.4e-9 at 128), with a margin
    for (n, bound) in [(8, 2e-4), (32, 1e-6), (128, 1e-8)] {
        let scene = cases::hard("buckled_column", n);
        let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
        let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
        let r = &eq.report;
        assert!(r.status.is_converged(), "{n}: {r}");
        assert_eq!(r.negative_eigenvalues, Some(0), "{n}: {r}");
        assert!(r.is_stable());
        let lowest = smallest_relative_eigenvalue(&robot, eq.q.as_slice(), &loads);
        assert!(
            lowest > 0.0,
            "{n}: the tangent's smallest eigenvalue {lowest:e}"
        );
        let k = eq.q.len() - 4;
        let (dx, dy) = (eq.q[k] - tip_ref[0], eq.q[k + 1] - tip_ref[1]);
        assert!(
            dx.abs() < bound && dy.abs() < bound,
            "{n}: tip ({}, {}) m, the elastica's ({}, {}) m",
            eq.q[k],
            eq.q[k + 1],
            tip_ref[0],
            tip_ref[1]
        );
    }
}

/// The same column below its buckling load (`q L³/EI = 6`) stands nearly
/// straight: stable, no escape needed, no load step cut.
#[test]
fn below_buckling_the_column_stands() {
    let mut scene = cases::hard("buckled_column", 32);
    scene.loads = serde_json::from_value(serde_json::json!([{"type": "distributed",
        "profile": "uniform", "w_n_per_m": [0.0, -6.0 * 0.025 / 0.24f64.powi(3)]}]))
    .unwrap();
    let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    assert!(eq.report.is_stable(), "{}", eq.report);
    let k = eq.q.len() - 4;
    // leaning towards the tilt, but far less than the buckled column
    assert!(eq.q[k] > 0.0 && eq.q[k] < 0.05, "tip x {}", eq.q[k]);
    assert!(smallest_relative_eigenvalue(&robot, eq.q.as_slice(), &loads) > 0.0);
}

/// A perfect column (no tilt) beyond its buckling load: the load path
/// stays straight, so the solver ends on the saddle and must leave it along
/// its negative curvature (either side is right by symmetry).
#[test]
fn a_perfect_column_leaves_the_saddle() {
    let mut scene = cases::hard("buckled_column", 8);
    scene.base.angle_rad = std::f64::consts::FRAC_PI_2;
    let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    assert!(eq.report.is_stable(), "{}", eq.report);
    assert!(smallest_relative_eigenvalue(&robot, eq.q.as_slice(), &loads) > 0.0);
    let k = eq.q.len() - 4;
    // the tilted column's tip is 0.204 m to the side; without the tilt the
    // bent column is nearly as far (the 0.01 rad tilt moves it little)
    assert!(eq.q[k].abs() > 0.15, "tip x {} m: {}", eq.q[k], eq.report);
}

/// A perfect column under ten times its Euler load (a compressive tip
/// force, `P = 10 π² EI / (4 L²)`, 16 elements): the straight equilibrium
/// has two negative eigenvalues; whenever the solver returns an unstable
/// answer the report carries the stability warning, which its text prints;
/// a stable answer carries none. (Before issue 33: no warning, the only
/// trace a count in `negative_eigenvalues`. Until the escape's plain-Newton
/// finish, the solver returned this saddle, 2 negative eigenvalues; now it
/// reaches the stable bent column, and says the side was ambiguous: the
/// load is symmetric.)
#[test]
fn an_unstable_answer_carries_a_warning() {
    use softrod::statics::StaticWarning;
    let mut scene = cases::hard("buckled_column", 16);
    scene.base.angle_rad = std::f64::consts::FRAC_PI_2;
    let p = 10.0 * std::f64::consts::PI.powi(2) * 0.025 / (4.0 * 0.24f64.powi(2));
    scene.loads = serde_json::from_value(serde_json::json!([
        {"type": "tip_force", "force_n": [0.0, -p]}
    ]))
    .unwrap();
    let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    let r = &eq.report;
    let negative = r.negative_eigenvalues.unwrap();
    // checked independently: the dense eigenvalues agree on the sign
    let lowest = smallest_relative_eigenvalue(&robot, eq.q.as_slice(), &loads);
    assert_eq!(negative > 0, lowest < 0.0, "{lowest:e}: {r}");
    if negative > 0 {
        assert_eq!(
            r.warnings,
            vec![StaticWarning::Unstable {
                negative_eigenvalues: negative
            }]
        );
        assert!(
            r.to_string().contains("warning: unstable equilibrium"),
            "{r}"
        );
        let json = serde_json::to_string(r).unwrap();
        assert!(json.contains("\"warnings\":[{\"unstable\""), "{json}");
    } else {
        assert_eq!(
            r.warnings,
            vec![StaticWarning::Bifurcation {
                from_load_fraction: 1.0,
                to_load_fraction: 1.0,
                branch: softrod::statics::BranchChoice::Symmetric,
            }],
            "{r}"
        );
    }
    // what the solver returns today
    assert_eq!(negative, 0, "{r}");
    // a stable answer: no stability warning (the tilted column's report
    // names the bifurcation it passed, `tests/statics_branch.rs`)
    let stable = cases::hard("buckled_column", 16);
    let (robot, loads) = (stable.robot().unwrap(), stable.loads().unwrap());
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    assert!(
        eq.report.is_stable()
            && !(eq.report.warnings.iter()).any(|w| matches!(w, StaticWarning::Unstable { .. })),
        "{}",
        eq.report
    );
}
