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
            nalgebra::Vector2::new(0.0, 0.0),
            nalgebra::Vector2::new(0.0, 1.0),
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

/// The quick attempt of a cold solve that has the coarse mesh's start
/// behind it gives up at the first tangent that is not positive definite,
/// after one factorization and before any step (no shifted retries, no
/// pivoted LU of the fine tangent): 2 N at mid-length against a 0.1 N·m
/// tip moment on 128 elements, whose tangent at the straight start is
/// indefinite. Without the flag the same iteration solves with the
/// pivoted LU of that tangent.
#[test]
fn a_definite_only_attempt_gives_up_at_an_indefinite_tangent() {
    use super::newton::{Target, Work};
    use crate::linsolve::{AutoSolver, LinearWork, SymmetricMatrix};
    use crate::structure::{Assembled, MeshSequencing, SolverHints};
    let scene: crate::scene::Scene = serde_json::from_value(serde_json::json!({
        "robot": {"sections": [
            {"length_m": 0.12, "ea_n": 300.0, "ei_nm2": 0.025, "elements": 64},
            {"length_m": 0.12, "ea_n": 300.0, "ei_nm2": 0.025, "elements": 64}]},
        "gravity_m_per_s2": [0.0, 0.0],
        "loads": [{"type": "point_force", "s_m": 0.12, "force_n": [0.0, -2.0]},
                  {"type": "tip_moment", "moment_nm": 0.1}],
    }))
    .unwrap();
    let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    assert!(robot.coarse_model(&loads).unwrap().is_some());
    let dead: Vec<f64> = crate::structure::Assembled::dead_force(&robot, &loads)
        .unwrap()
        .data
        .into();
    let zero = vec![0.0; robot.n_free()];
    let attempt = |definite_only: bool| {
        let mut solver = AutoSolver::with_kind(robot.tangent_pattern(), SolverKind::Auto).unwrap();
        let mut u: Vec<f64> = robot.start_free_coordinates(&loads).unwrap().data.into();
        let mut w = Work {
            k: SymmetricMatrix::zeros(robot.tangent_pattern().clone()),
            solver: &mut solver,
            r: vec![0.0; robot.n_free()],
            q: vec![0.0; robot.n_q()],
            iterations: 0,
            floor: 0.0,
            last_step: 0.0,
            definite: false,
            settled: false,
        };
        robot.configuration_into(&u, &mut w.q).unwrap();
        let target = Target::<crate::assembly::Robot<crate::element::PlanarCable>> {
            dead: &dead,
            loads: &loads,
            offset: &zero,
            strict: true,
            descent: false,
            definite_only,
            full: true,
        };
        let quick = StaticSolver {
            settings: StaticSettings {
                max_iterations: 1,
                ..StaticSettings::default()
            },
        };
        let before = LinearWork::now();
        let status = quick.newton(&robot, &target, &mut u, &mut w, 2.0).unwrap();
        let moved = u != robot.start_free_coordinates(&loads).unwrap().as_slice();
        let work = LinearWork::now().since(before);
        (status, w.iterations, w.definite, moved, work)
    };
    // the tangent at the straight start is indefinite (the plain attempt
    // factors it by LU and solves for a direction, then gives up at the
    // shortened step)
    let (_, iterations, definite, _, work) = attempt(false);
    assert_eq!((iterations, definite), (1, false));
    assert!(work.factorizations >= 1 && work.solves >= 1, "{work:?}");
    let (status, iterations, definite, moved, work) = attempt(true);
    assert_eq!(status, StaticStatus::LineSearchFailed);
    assert_eq!((iterations, definite, moved), (1, false, false));
    assert_eq!((work.factorizations, work.solves), (1, 0));
}

/// `|R|₂` at the answer `eq` of `model` under `loads`, evaluated afresh:
/// what the report's `residual_norm_n` must equal bit for bit.
fn residual_norm_at<M: Model>(model: &M, eq: &Equilibrium, loads: &M::Loads) -> f64 {
    let dead = model.dead_force(loads).unwrap();
    let mut r = vec![0.0; model.n_free()];
    model
        .residual_into(
            eq.u.as_slice(),
            eq.q.as_slice(),
            dead.as_slice(),
            loads,
            &mut r,
        )
        .unwrap();
    crate::numeric::norm2(&r)
}

/// A small load (a 1e-3 N·m tip moment on 16 elements) converges in plain
/// Newton to the round-off floor; the answer's stability is read off the
/// last Newton factorization (made at a point that had met the floor), so
/// the solve factors once per iteration and no more, and reports the
/// inertia and the residual a fresh factorization and evaluation at the
/// answer give.
#[test]
fn a_small_load_reads_its_stability_off_the_last_newton_factorization() {
    use crate::linsolve::{AutoSolver, Factorization, LinearWork, SymmetricMatrix};
    let scene: crate::scene::Scene = serde_json::from_value(serde_json::json!({
        "robot": {"sections": [
            {"length_m": 0.24, "ea_n": 300.0, "ei_nm2": 0.025, "elements": 16}]},
        "gravity_m_per_s2": [0.0, 0.0],
        "loads": [{"type": "tip_moment", "moment_nm": 1e-3}],
    }))
    .unwrap();
    let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    let before = LinearWork::now();
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    let work = LinearWork::now().since(before);
    assert_eq!(
        eq.report.status,
        StaticStatus::Converged(StaticCriterion::RoundOffFloor),
        "{}",
        eq.report
    );
    assert_eq!(work.factorizations, eq.report.iterations, "{}", eq.report);
    // what a factorization at the answer says
    let mut k = SymmetricMatrix::zeros(robot.tangent_pattern().clone());
    let dead = crate::structure::Assembled::dead_force(&robot, &loads).unwrap();
    crate::structure::SolverHints::tangent_into(
        &robot,
        eq.u.as_slice(),
        eq.q.as_slice(),
        dead.as_slice(),
        &loads,
        &mut k,
    )
    .unwrap();
    let mut solver = AutoSolver::with_kind(robot.tangent_pattern(), SolverKind::Auto).unwrap();
    let f = solver.factor(&k, Default::default()).unwrap();
    assert_eq!(
        eq.report.negative_eigenvalues,
        f.inertia().map(|i| i.negative)
    );
    assert_eq!(eq.report.negative_eigenvalues, Some(0));
    assert_eq!(
        eq.report.residual_norm_n,
        residual_norm_at(&robot, &eq, &loads)
    );
}

/// The report's residual is the residual at the answer, bit for bit,
/// whichever path reached it: a small load converged by the residual test
/// (its residual kept from the last Newton run), a large one through the
/// continuation, a column standing beyond buckling (the saddle left for
/// the stable branch: `u` moves after the last full Newton run), and a
/// structure.
#[test]
fn the_reported_residual_is_the_residual_at_the_answer() {
    let scene = |elements: usize, loads: serde_json::Value, base_angle: f64| {
        let s: crate::scene::Scene = serde_json::from_value(serde_json::json!({
            "robot": {"sections": [
                {"length_m": 0.24, "ea_n": 300.0, "ei_nm2": 0.025, "elements": elements}]},
            "base": {"position_m": [0.0, 0.0], "angle_rad": base_angle},
            "gravity_m_per_s2": [0.0, 0.0],
            "loads": loads,
        }))
        .unwrap();
        (s.robot().unwrap(), s.loads().unwrap())
    };
    let uniform = |q: f64| serde_json::json!([{"type": "distributed", "profile": "uniform", "w_n_per_m": [0.0, q]}]);
    let column = uniform(-12.0 * 0.025 / 0.24f64.powi(3));
    let mut criteria = Vec::new();
    for (n, loads, angle) in [
        (4, uniform(-0.01), 0.0),
        (16, uniform(-0.01), 0.0),
        (8, uniform(-20.0), 0.0),
        (8, column, std::f64::consts::FRAC_PI_2 + 0.01),
    ] {
        let (robot, loads) = scene(n, loads, angle);
        let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
        assert_eq!(
            eq.report.residual_norm_n,
            residual_norm_at(&robot, &eq, &loads),
            "{n}: {}",
            eq.report
        );
        assert_eq!(eq.report.negative_eigenvalues, Some(0), "{}", eq.report);
        criteria.push(eq.report.status);
    }
    // the paths above include one that ends on the residual test
    assert!(criteria.contains(&StaticStatus::Converged(StaticCriterion::Residual)));
    let (s, loads) = leg_and_body();
    let eq = StaticSolver::default().solve(&s, &loads, None).unwrap();
    assert_eq!(eq.report.residual_norm_n, residual_norm_at(&s, &eq, &loads));
}
