//! Static solver: robustness across element counts, warm starts, and failure
//! as a reported outcome.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::Error;
use softrod::loads::{Loads, PointForce};
use softrod::scene::Scene;
use softrod::statics::{StaticSettings, StaticSolver, StaticStatus};

fn scene(elements_per_section: usize) -> Scene {
    let mut s = Scene::two_section();
    for sec in &mut s.robot.sections {
        sec.elements = elements_per_section;
    }
    s
}

/// The default scene (weight + 60/30 kPa) converges cold from 10 to 2000
/// elements in a handful of iterations, and the tip converges with
/// refinement (differences between successive meshes shrink).
#[test]
fn default_scene_converges_cold_from_10_to_2000_elements() {
    let mut tips = Vec::new();
    for &n in &[5usize, 10, 25, 50, 100, 250, 1000] {
        let s = scene(n);
        let robot = s.robot().unwrap();
        let eq = StaticSolver::default()
            .solve(&robot, &s.loads().unwrap(), None)
            .unwrap();
        assert!(
            eq.report.status.is_converged() && eq.report.iterations <= 8,
            "{n}: {}",
            eq.report
        );
        assert!(
            eq.report.residual_norm_n
                <= eq
                    .report
                    .residual_tolerance_n
                    .max(eq.report.residual_floor_n)
                    * 1.0001
        );
        let k = eq.q.len();
        tips.push((eq.q[k - 4], eq.q[k - 3]));
    }
    let d: Vec<f64> = tips
        .windows(2)
        .map(|w| ((w[0].0 - w[1].0).powi(2) + (w[0].1 - w[1].1).powi(2)).sqrt())
        .collect();
    println!("tip differences between successive meshes: {d:?}");
    assert!(d[0] < 1e-4 && d[d.len() - 1] < 1e-9, "{d:?}");
}

/// A warm start at the solution needs no iteration; a small change needs few.
#[test]
fn warm_start_is_cheap() {
    let s = scene(10);
    let robot = s.robot().unwrap();
    let loads = s.loads().unwrap();
    let solver = StaticSolver::default();
    let eq = solver.solve(&robot, &loads, None).unwrap();
    let again = solver.solve(&robot, &loads, Some(eq.q.as_slice())).unwrap();
    assert_eq!(again.report.iterations, 0);
    let mut nudged = loads.clone();
    nudged.pressures_pa[0] += 500.0;
    let warm = solver
        .solve(&robot, &nudged, Some(eq.q.as_slice()))
        .unwrap();
    assert!(warm.report.iterations <= 3, "{}", warm.report);
}

/// A budget too small to converge is an error carrying the report, not a
/// silent result.
#[test]
fn non_convergence_is_an_error_with_its_report() {
    let s = scene(10);
    let robot = s.robot().unwrap();
    let loads = Loads {
        pressures_pa: vec![0.0; 4],
        point_forces: vec![PointForce {
            s_m: 0.24,
            force_n: vec![0.0, -5.0],
        }],
        ..Loads::default()
    };
    let settings = StaticSettings {
        max_iterations: 2,
        max_total_iterations: 4,
        ..Default::default()
    };
    match StaticSolver::new(settings)
        .unwrap()
        .solve(&robot, &loads, None)
    {
        Err(Error::NotConverged { report }) => {
            assert!(!report.status.is_converged());
            assert!(
                matches!(report.status, StaticStatus::IterationLimit { .. }),
                "{report}"
            );
            assert!(report.iterations <= 4 && report.residual_norm_n.is_finite());
        }
        other => panic!("expected NotConverged, got {other:?}"),
    }
}
