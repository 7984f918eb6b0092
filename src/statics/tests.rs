//! The one static solver on both kinds of model and with both linear
//! solvers (these replace the tests of the former `structure::solve`).

#![allow(clippy::unwrap_used, clippy::panic)]

use super::*;
use crate::structure::{
    BodyLoad, JointSpec, RigidBodySpec, RodEnd, RodSpec, Section, StructureLoads, StructureSpec,
};

/// The paper's two-section robot (weight, pressures, a tip force, a
/// moment) with each linear-solver kind at a tolerance of 1e-12: each
/// reaches the default solve's equilibrium to 1e-10 of the largest
/// coordinate.
#[test]
fn every_solver_kind_reaches_the_same_equilibrium() {
    let scene = crate::scene::Scene::two_section();
    let robot = scene.robot().unwrap();
    let loads = scene.loads().unwrap();
    let reference = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    let scale = reference.q.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for kind in [SolverKind::Auto, SolverKind::Sparse] {
        let settings = StaticSettings {
            linear_solver: kind,
            residual_tolerance: 1e-12,
            ..StaticSettings::default()
        };
        let eq = StaticSolver::new(settings)
            .unwrap()
            .solve(&robot, &loads, None)
            .unwrap();
        assert!(eq.report.status.is_converged(), "{kind:?}: {}", eq.report);
        let diff =
            eq.q.iter()
                .zip(&reference.q)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff <= 1e-10 * scale, "{kind:?}: {diff:e} of {scale:e}");
    }
}

/// A clamped leg holding a 50 g body, pushed sideways.
fn leg_and_body() -> (
    crate::structure::Structure<crate::element::PlanarCable>,
    StructureLoads,
) {
    let spec = StructureSpec::new(
        vec![RodSpec::clamped(
            vec![Section::uniform(0.2, 300.0, 0.02, 6)],
            vec![0.0, 0.0],
            vec![0.0, 1.0],
        )],
        vec![RigidBodySpec {
            mass_kg: 0.05,
            position_m: vec![0.0, 0.2],
            orientation_rad: vec![0.0],
        }],
        vec![JointSpec::RodToBody {
            rod: 0,
            end: RodEnd::End,
            body: 0,
            point_m: None,
            direction: None,
        }],
    );
    let loads = StructureLoads {
        bodies: vec![BodyLoad {
            body: 0,
            force_n: vec![0.05, 0.0],
            moment_nm: vec![1e-3],
        }],
        ..StructureLoads::default()
    };
    (spec.build_planar().unwrap(), loads)
}

/// The statuses are the same for a robot and a structure: a converged solve
/// names its test; one that runs out of its budget says so with the
/// iterations spent, as an error carrying the report.
#[test]
fn statuses_are_the_same_for_robots_and_structures() {
    let scene = crate::scene::Scene::two_section();
    let robot = scene.robot().unwrap();
    let loads = scene.loads().unwrap();
    let (s, sloads) = leg_and_body();
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    assert!(matches!(eq.report.status, StaticStatus::Converged(_)));
    let eq = StaticSolver::default().solve(&s, &sloads, None).unwrap();
    assert!(matches!(eq.report.status, StaticStatus::Converged(_)));
    let tight = StaticSolver::new(StaticSettings {
        max_iterations: 1,
        max_total_iterations: 1,
        ..StaticSettings::default()
    })
    .unwrap();
    for outcome in [
        tight.solve(&robot, &loads, None).map(|_| ()),
        tight.solve(&s, &sloads, None).map(|_| ()),
    ] {
        match outcome {
            Err(Error::NotConverged { report }) => {
                assert_eq!(
                    report.status,
                    StaticStatus::IterationLimit { iterations: 1 }
                );
                assert_eq!(report.iterations, 1);
            }
            other => panic!("expected the budget to stop the solve: {other:?}"),
        }
    }
}

/// A structure's solve started at its own equilibrium (given as all
/// coordinates `q`) is back at the same free coordinates and converges at
/// once; `solve_with` refuses a linear solver of another pattern.
#[test]
fn a_structure_restarts_from_its_configuration() {
    let (s, loads) = leg_and_body();
    let eq = StaticSolver::default().solve(&s, &loads, None).unwrap();
    let u = s.dof_map().free_coordinates_of(eq.q.as_slice()).unwrap();
    let du = u
        .iter()
        .zip(&eq.u)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(du < 1e-15, "{du}");
    let warm = StaticSolver::default()
        .solve(&s, &loads, Some(eq.q.as_slice()))
        .unwrap();
    assert!(warm.report.iterations <= 1, "{}", warm.report);
    // a start of the wrong size or not finite is refused, naming `q0`
    match StaticSolver::default().solve(&s, &loads, Some(eq.u.as_slice())) {
        Err(Error::DimensionMismatch { name, .. }) => assert_eq!(name, "q0"),
        other => panic!("{other:?}"),
    }
    let mut bad = eq.q.clone();
    bad[3] = f64::NAN;
    match StaticSolver::default().solve(&s, &loads, Some(bad.as_slice())) {
        Err(e) => assert_eq!(e.field(), Some("q0[3]"), "{e:?}"),
        Ok(_) => panic!("a NaN start was accepted"),
    }
    let robot = crate::scene::Scene::two_section().robot().unwrap();
    let mut other = AutoSolver::analyze(robot.tangent_pattern()).unwrap();
    match StaticSolver::default().solve_with(&s, &loads, None, &mut other) {
        Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, "solver"),
        other => panic!("{other:?}"),
    }
}
