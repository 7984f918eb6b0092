//! The estimators' cost, counted instead of timed: tangent factorizations
//! and solved right-hand sides per warm step
//! (`EstimateReport::linear_work`), on the streaming benches' scenario
//! (`benches/estimate.rs`: the two-section robot, an unknown 20 g tip mass
//! plus 0.5 N/m, markers at `L k / m`, 0.01 mm seeded noise, `α = 31`,
//! the default statistical stopping test at 0.1 standard deviations).
//!
//! One exact linearization at 5 markers is one factorization and the 10
//! adjoint solves; the bounds below are what the methods measured when
//! written (README, "Performance"): a regression that brings back a second
//! linearization per warm step (or one SQP iteration per element count)
//! fails here.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::assembly::Robot;
use softrod::element::PlanarCable;
use softrod::estimate::{Backend, EstimatorSettings, MarkerObservation, Observation};
use softrod::linsolve::LinearWork;
use softrod::loads::{LineLoad, Loads, PointForce};
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

/// The benches' robot with `n` elements, its known loads and `frames` noisy
/// observations of `m` markers on the true shape.
fn case(n: usize, m: usize, frames: u64) -> (Robot<PlanarCable>, Loads, Vec<Observation>) {
    let mut scene = Scene::two_section();
    scene.robot.sections[0].elements = n / 2;
    scene.robot.sections[1].elements = n - n / 2;
    let robot = scene.robot().unwrap();
    let known = scene.loads().unwrap();
    let truth_at = |k: f64| {
        let mut truth = known.clone();
        truth.point_forces.push(PointForce {
            s_m: robot.length(),
            force_n: vec![0.0, -0.02 * 9.81 * k],
        });
        truth.line_loads.push(LineLoad::Uniform {
            w_n_per_m: vec![0.0, -0.5 * k],
        });
        truth
    };
    let solver = StaticSolver::default();
    let mut q = solver.solve(&robot, &known, None).unwrap().q;
    for k in 1..=8 {
        q = solver
            .solve(&robot, &truth_at(f64::from(k) / 8.0), Some(q.as_slice()))
            .unwrap()
            .q;
    }
    let markers: Vec<MarkerObservation> = (1..=m)
        .map(|k| {
            let s = robot.length() * k as f64 / m as f64;
            MarkerObservation::at_arc(s, robot.position_at(q.as_slice(), s).unwrap().data.into())
        })
        .collect();
    let frames = (0..frames)
        .map(|k| {
            Observation {
                markers: markers.clone(),
            }
            .with_noise(1e-5, k)
        })
        .collect();
    (robot, known, frames)
}

/// The work of each warm step (after a first step on frame 0), every step
/// converged.
fn warm_work(backend: Backend, n: usize, frames: u64) -> Vec<(LinearWork, usize)> {
    let (robot, known, obs) = case(n, 5, frames);
    let settings = EstimatorSettings {
        alpha: Some(31.0),
        ..EstimatorSettings::default()
    };
    let mut est = softrod::estimate::EstimatorSettings {
        backend,
        ..settings
    }
    .build_for(&robot, &known)
    .unwrap();
    est.step(&obs[0]).unwrap().converged().unwrap();
    obs[1..]
        .iter()
        .map(|o| {
            let e = est.step(o).unwrap().converged().unwrap();
            (e.report.linear_work, e.report.iterations)
        })
        .collect()
}

/// A warm `newton` step at 20 elements, 5 markers: one Gauss–Newton step
/// from the derivatives cached at the last estimate, its equilibrium by
/// chord steps from the linearized prediction, one factorization and the
/// 10 adjoint solves at the new point, which the statistical test accepts.
#[test]
fn warm_newton_step_is_one_linearization() {
    let work = warm_work(Backend::Newton, 20, 12);
    println!("newton: {work:?}");
    for (w, it) in &work {
        assert_eq!(w.factorizations, 1, "{work:?}");
        assert!(w.solves <= 17, "{work:?}");
        assert_eq!(*it, 1, "{work:?}");
    }
}

/// A warm `sqp` step: the first QP at the last estimate reuses the
/// factored tangent and derivatives kept there, the second (at the new
/// point) factors once and ends within the noise.
#[test]
fn warm_sqp_step_is_one_linearization() {
    let work = warm_work(Backend::Sqp, 20, 12);
    println!("sqp: {work:?}");
    for (w, it) in &work {
        assert_eq!(w.factorizations, 1, "{work:?}");
        assert!(w.solves <= 20, "{work:?}");
        assert!(*it <= 2, "{work:?}");
    }
}

/// The warm step's work does not grow with the mesh (`sqp`'s iteration
/// count grew with the element count against a round-off test, its cost
/// exponent was 1.34 over 100–2000 elements; a final chord step that
/// missed at fine meshes cost it a second linearization): the same counts
/// at 100 and 800 elements, for both backends.
#[test]
fn warm_work_does_not_grow_with_the_mesh() {
    for backend in [Backend::Newton, Backend::Sqp] {
        let max = |n: usize| {
            let w = warm_work(backend, n, 5);
            println!("{} {n} el: {w:?}", backend.name());
            w.iter().fold((0, 0), |(f, i), (w, it)| {
                (f.max(w.factorizations), i.max(*it))
            })
        };
        let (coarse, fine) = (max(100), max(800));
        assert!(
            fine.0 <= coarse.0 && fine.1 <= coarse.1,
            "{}: (factorizations, iterations) {coarse:?} at 100 el, {fine:?} at 800",
            backend.name()
        );
        assert!(fine.0 <= 1 && fine.1 <= 2, "{}: {fine:?}", backend.name());
    }
}
