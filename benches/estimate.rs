//! Estimation benches: one warm streaming step (a new noisy frame of the
//! same scene) per backend on the two-section robot (20 elements, 5
//! markers, unknown 20 g tip mass + 0.5 N/m uniform load, alpha fixed at the
//! value the discrepancy principle picks there), for 20 and 80 elements.
//!
//! Run: `cargo bench --bench estimate`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use softrod::estimate::{Backend, EstimatorSettings, Observation};
use softrod::loads::{LineLoad, PointForce};
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

fn warm_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("estimate_warm_step");
    for &n in &[20usize, 80] {
        let mut scene = Scene::two_section();
        for s in &mut scene.robot.sections {
            s.elements = n / 2;
        }
        let robot = scene.robot().unwrap();
        let known = scene.loads().unwrap();
        let mut truth = known.clone();
        truth.point_forces.push(PointForce {
            s_m: robot.length(),
            force_n: vec![0.0, -0.02 * 9.81],
        });
        truth.line_loads.push(LineLoad::Uniform {
            w_n_per_m: vec![0.0, -0.5],
        });
        let eq = StaticSolver::default().solve(&robot, &truth, None).unwrap();
        let nodes: Vec<usize> = (1..=5).map(|k| k * n / 5).collect();
        let frames: Vec<Observation> = (0..64)
            .map(|k| Observation::at_nodes(&robot, &eq.q, &nodes).with_noise(1e-5, k))
            .collect();
        for backend in [Backend::Newton, Backend::Sqp] {
            let settings = EstimatorSettings {
                alpha: Some(31.0),
                ..EstimatorSettings::default()
            };
            let mut est = backend
                .build(robot.clone(), known.clone(), settings)
                .unwrap();
            est.step(&frames[0]).unwrap();
            let mut k = 0;
            group.bench_with_input(BenchmarkId::new(backend.name(), n), &n, |b, _| {
                b.iter(|| {
                    k = (k + 1) % frames.len();
                    black_box(est.step(black_box(&frames[k])).unwrap());
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, warm_step);
criterion_main!(benches);
