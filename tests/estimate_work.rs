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
//! fails here. Also the first estimate of a large deflection, whose cost
//! the two backends share within 1.5× (factorizations counted).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::assembly::{Base, Clamp, Robot, RobotSpec, Section};
use softrod::element::PlanarCable;
use softrod::estimate::{Backend, EstimatorSettings, MarkerObservation, Observation};
use softrod::linsolve::LinearWork;
use softrod::loads::{LineLoad, Loads};
use softrod::statics::StaticSolver;

#[path = "common/streaming.rs"]
mod streaming;
use streaming::streaming_case as case;

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

/// The 0.24 m cable of the report's references (two sections, EA 300 N,
/// EI 0.025 N·m², clamped base, no known loads) with `n` elements.
fn reference_cable(n: usize) -> Robot<PlanarCable> {
    let sections = (0..2)
        .map(|_| Section::uniform(0.12, 300.0, 0.025, n / 2))
        .collect();
    let mut spec = RobotSpec::new(sections);
    spec.base = Base {
        clamp: Clamp::Full,
        ..Base::default()
    };
    spec.bending_gauss_points = 3;
    spec.build_planar().unwrap()
}

/// The first estimate (`α` by the evidence, from the unloaded straight
/// shape) of a large deflection: the report's cable under a uniform load
/// of 3 × its self-weight, 4.41 N/m (tip 68 mm down, turned 0.39 rad),
/// observed by 5 markers, 20 elements. From the straight shape the
/// `newton` backend's reduced steps found no equilibrium at their full
/// trial step and crept by 1–2 mm per iteration: 221 factorizations
/// against `sqp`'s 15. Its far start now continues with the full-space
/// iterations; the two backends' factorizations are within 1.5× of each
/// other (measured 18 and 15).
#[test]
fn first_estimate_of_a_large_deflection_costs_both_backends_alike() {
    let fine = reference_cable(40);
    let mut truth = Loads::default();
    let mut q = StaticSolver::default()
        .solve(&fine, &truth, None)
        .unwrap()
        .q;
    for k in 1..=8 {
        truth.line_loads = vec![LineLoad::Uniform {
            w_n_per_m: vec![0.0, -4.4145 * f64::from(k) / 8.0],
        }];
        q = StaticSolver::default()
            .solve(&fine, &truth, Some(q.as_slice()))
            .unwrap()
            .q;
    }
    let markers = (1..=5)
        .map(|k| {
            let s = 0.24 * f64::from(k) / 5.0;
            MarkerObservation::at_arc(s, fine.position_at(q.as_slice(), s).unwrap())
        })
        .collect();
    let obs = Observation { markers }.with_noise(1e-5, 7);
    let work: Vec<usize> = [Backend::Newton, Backend::Sqp]
        .iter()
        .map(|b| {
            let mut est = EstimatorSettings {
                backend: *b,
                ..EstimatorSettings::default()
            }
            .build_for(&reference_cable(20), &Loads::default())
            .unwrap();
            let e = est.step(&obs).unwrap().converged().unwrap();
            println!("{}: {:?}", b.name(), e.report.linear_work);
            e.report.linear_work.factorizations
        })
        .collect();
    let (newton, sqp) = (work[0] as f64, work[1] as f64);
    assert!(
        newton <= 1.5 * sqp && sqp <= 1.5 * newton,
        "factorizations: newton {newton}, sqp {sqp}"
    );
}
