//! The closed loop's step time against the warm estimator's, in one run
//! (machines differ day to day, so the target is a ratio: a control step at
//! most 3x the warm estimator step).
//!
//! Both on the two-section robot at 20 elements, five markers, frames from
//! the simulated plant (not the model) holding the tip near (0.21, 0.095) m
//! with a 20 g tip mass, 0.05 mm noise:
//! - `control_step/warm_estimator/20el_5mk`: one step of a Newton estimator
//!   built once (pressures fixed), the frames cycling;
//! - `control_step/ff_updater/20el_5mk`: one `ClosedLoop::control_step`
//!   (estimation + updater + inverse kinematics) on the same frames.
//!
//! - `control_step/ik_warm/20el`: the inverse kinematics alone, warm, on
//!   targets 0.05 mm apart.
//!
//! Measured (2026-11-30, shared 2-core machine): warm estimator 0.31 ms,
//! IK alone 0.36 ms, control step 5.2 ms (17x, over the 3x target): the
//! estimators take their pressures when built, so the loop builds one per
//! step and loses the warm start (see `control::adapter::estimator_at`).
//!
//! Run: `cargo bench --bench control`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use softrod::control::{ClosedLoop, IkSettings, InverseKinematics, LoopSettings};
use softrod::estimate::{Backend, EstimatorSettings};
use softrod::plant::{MarkerFrame, PayloadSchedule, Plant, PlantSettings, SimulatedPlant};
use softrod::scene::Scene;

fn bench(c: &mut Criterion) {
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let arcs: Vec<f64> = scene
        .markers
        .iter()
        .map(|m| robot.node_arc()[m.node.unwrap()])
        .collect();
    let target = [0.21, 0.095];
    // settle the loop on the plant, then record frames around the target
    let settings = PlantSettings {
        payloads: PayloadSchedule::tip_mass(0.02, 0.24),
        ..Default::default()
    };
    let mut plant = SimulatedPlant::new(&scene, &arcs, settings).unwrap();
    let mut lp = ClosedLoop::new(
        robot.clone(),
        scene.loads().unwrap(),
        &arcs,
        LoopSettings::default(),
    )
    .unwrap();
    let mut frames: Vec<MarkerFrame> = Vec::new();
    let mut last = Vec::new();
    for k in 0..150 {
        let f = plant.advance(1.0 / 30.0).unwrap();
        lp.control_step(&f, &target, &target).unwrap();
        plant.command(lp.commanded_pa()).unwrap();
        if k >= 120 {
            frames.push(f);
        }
        last = lp.commanded_pa().to_vec();
    }
    let alpha = lp.settings().estimator.alpha;
    let mut known = scene.loads().unwrap();
    known.pressures_pa = last;
    let est_settings = EstimatorSettings {
        alpha,
        noise_sigma_m: 5e-5,
        ..Default::default()
    };
    let mut est = Backend::Newton
        .build(robot.clone(), known, est_settings)
        .unwrap();
    let obs: Vec<_> = frames
        .iter()
        .map(|f| f.observation(&arcs).unwrap())
        .collect();
    est.step(&obs[0]).unwrap();
    let mut g = c.benchmark_group("control_step");
    g.warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(4));
    let mut i = 0;
    g.bench_function("warm_estimator/20el_5mk", |b| {
        b.iter(|| {
            i = (i + 1) % obs.len();
            black_box(est.step(&obs[i]).unwrap());
        })
    });
    let mut j = 0;
    g.bench_function("ff_updater/20el_5mk", |b| {
        b.iter(|| {
            j = (j + 1) % frames.len();
            black_box(lp.control_step(&frames[j], &target, &target).unwrap());
        })
    });
    // the inverse kinematics alone, warm, on targets 0.05 mm apart with
    // the loop's last F̂ (what a control step adds to the estimate)
    let f_hat = lp.f_hat().to_vec();
    let mut ik =
        InverseKinematics::new(robot.clone(), scene.loads().unwrap(), IkSettings::default())
            .unwrap();
    ik.solve(&target, &f_hat).unwrap();
    let mut flip = false;
    g.bench_function("ik_warm/20el", |b| {
        b.iter(|| {
            flip = !flip;
            let x = [target[0] + if flip { 5e-5 } else { 0.0 }, target[1]];
            black_box(ik.solve(&x, &f_hat).unwrap());
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
