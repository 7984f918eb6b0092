//! The soft parallel robot (params::parallel, full 3-D legs, 4 elements per
//! section: 3 × 9 nodes of 12 coordinates and the platform, 331 free
//! coordinates):
//! - `parallel/static_solve/actuated`: a static solve from the straight
//!   reference with chamber 0 of every leg's first section at 40 kPa and a
//!   100 g payload;
//! - `parallel/payload_step/actuated`: one payload estimation (32)–(35)
//!   from the unloaded equilibrium to a platform displaced by a 100 g
//!   payload (Newton on the payload force with warm static solves);
//! - the same static solve with spatial-cable legs (the cheaper model the
//!   torsion test rules out) for the price of the section frames;
//! - `parallel/warm_solve/actuated`: the tracking loop's static solve
//!   (`parallel::warm`): from the equilibrium, chamber 0 of leg 0 up by
//!   1 kPa, chord steps with the kept factors;
//! - `parallel/track_step/ff_updater`: one control instant of the tracking
//!   loop (estimator, updater, inverse kinematics) with the controller's
//!   model of 2 elements per section, from a settled state (the loop's
//!   clone outside the measured time).
//!
//! Measured (2026-12-03, shared 2-core machine, medians): static solve
//! 33.0 ms with full 3-D legs, 1.14 ms with spatial-cable legs; a payload
//! step 53.3 ms; the warm solve 0.77 ms; one control instant 5.8 ms.
//!
//! Run: `cargo bench --bench parallel`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use softrod::control::parallel::{TrackSettings, controller};
use softrod::estimate::Backend;
use softrod::parallel::ParallelSpec;
use softrod::parallel::payload::fig8_configurations;
use softrod::plant::MarkerFrame;

fn bench(c: &mut Criterion) {
    let spec = ParallelSpec::default();
    let full = spec.build_full().unwrap();
    let cable = spec.build_cable().unwrap();
    let p = fig8_configurations(&spec)[1].as_slice().to_vec();
    let payload = [0.0, 0.0, -0.981];
    let loads = full.loads(&p, payload, [0.0; 3]).unwrap();
    let cable_loads = cable.loads(&p, payload, [0.0; 3]).unwrap();
    let free = full
        .solve(&full.loads(&p, [0.0; 3], [0.0; 3]).unwrap(), None)
        .unwrap();
    let loaded = full.solve(&loads, Some(free.q.as_slice())).unwrap();
    let x = full.platform_pose(loaded.q.as_slice()).unwrap();
    let mut g = c.benchmark_group("parallel");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    g.bench_function("static_solve/actuated", |b| {
        b.iter(|| black_box(full.solve(&loads, None).unwrap()))
    });
    g.bench_function("static_solve_cable/actuated", |b| {
        b.iter(|| black_box(cable.solve(&cable_loads, None).unwrap()))
    });
    g.bench_function("payload_step/actuated", |b| {
        b.iter(|| {
            black_box(
                full.estimate_payload(&p, [x[0], x[1], x[2]], 5e-5, Backend::Newton)
                    .unwrap(),
            )
        })
    });
    let mut warm = softrod::parallel::warm::WarmStatics::new(full.clone()).unwrap();
    warm.factor_at(
        free.u.as_slice(),
        &full.loads(&p, [0.0; 3], [0.0; 3]).unwrap(),
    )
    .unwrap();
    let mut p1 = p.clone();
    p1[0] += 1e3;
    let nudged = full.loads(&p1, [0.0; 3], [0.0; 3]).unwrap();
    g.bench_function("warm_solve/actuated", |b| {
        b.iter(|| black_box(warm.clone().solve(&nudged, free.u.as_slice()).unwrap()))
    });
    let model = ParallelSpec {
        elements_per_section: 2,
        ..ParallelSpec::default()
    }
    .build_full()
    .unwrap();
    let eq = model
        .solve(
            &model.loads(&p, [0.0, 0.0, -0.981], [0.0; 3]).unwrap(),
            None,
        )
        .unwrap();
    let x = model.platform_pose(eq.q.as_slice()).unwrap();
    let mut ctl = controller(model, &TrackSettings::default(), &p).unwrap();
    let target = vec![x[0], x[1], x[2]];
    let frame = MarkerFrame {
        time_s: 0.0,
        positions_m: vec![target.clone()],
    };
    for _ in 0..30 {
        ctl.control_step(&frame, &target, &target).unwrap();
    }
    let next = [x[0] + 1e-4, x[1], x[2]];
    g.bench_function("track_step/ff_updater", |b| {
        // the clone outside the measured time: one control instant alone
        b.iter_batched(
            || ctl.clone(),
            |mut c| black_box(c.control_step(&frame, &target, &next).unwrap()),
            criterion::BatchSize::SmallInput,
        )
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
