//! The estimator's cost in the number of markers (issue 33, "bounded
//! work"): the benches' streaming scenario (`tests/common/streaming.rs`:
//! the two-section robot at 20 elements, an unknown 20 g tip mass plus
//! 0.5 N/m, markers at `L k / m`, 0.01 mm seeded noise) observed by
//! `m ∈ {10, 100, 1 000, 10 000}` markers.
//!
//! Groups (criterion ids are `GROUP/BACKEND/<m>mk`):
//! - `estimate_markers_warm`: one streaming step of a warm estimator with
//!   `α = 31` given (the step of a stream);
//! - `estimate_markers_first`: the first step of a fresh estimator with
//!   `α` by the evidence (the `α` search, about 15–20 estimates), and the
//!   resultant's posterior covariance.
//!
//! Run (a few minutes; one sample is seconds at 10 000 markers):
//! `cargo bench -j 1 --bench estimate_markers`; the README table:
//! `python3 benches/markers_table.py`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::time::Duration;

#[path = "../tests/common/streaming.rs"]
mod streaming;

use criterion::{BatchSize, BenchmarkId, Criterion, criterion_group, criterion_main};
use softrod::estimate::{Backend, EstimatorSettings};

const ELEMENTS: usize = 20;
const MARKERS: [usize; 4] = [10, 100, 1000, 10_000];
const BACKENDS: [Backend; 2] = [Backend::Newton, Backend::Sqp];

fn settings(backend: Backend, alpha: Option<f64>) -> EstimatorSettings {
    EstimatorSettings {
        backend,
        alpha,
        ..EstimatorSettings::default()
    }
}

fn warm(c: &mut Criterion) {
    let mut group = c.benchmark_group("estimate_markers_warm");
    for m in MARKERS {
        let (robot, known, frames) = streaming::streaming_case(ELEMENTS, m, 8);
        for backend in BACKENDS {
            let mut est = settings(backend, Some(31.0))
                .build_for(&robot, &known)
                .unwrap();
            est.step(&frames[0]).unwrap().converged().unwrap();
            let mut k = 0;
            group.bench_function(BenchmarkId::new(backend.name(), format!("{m}mk")), |b| {
                b.iter(|| {
                    k = k % (frames.len() - 1) + 1;
                    let e = est.step(black_box(&frames[k])).unwrap();
                    assert!(e.report.status.is_converged(), "{:?}", e.report.status);
                    e
                })
            });
        }
    }
    group.finish();
}

fn first(c: &mut Criterion) {
    let mut group = c.benchmark_group("estimate_markers_first");
    for m in MARKERS {
        let (robot, known, frames) = streaming::streaming_case(ELEMENTS, m, 1);
        for backend in BACKENDS {
            group.bench_function(BenchmarkId::new(backend.name(), format!("{m}mk")), |b| {
                b.iter_batched(
                    || settings(backend, None).build_for(&robot, &known).unwrap(),
                    |mut est| {
                        let e = est.step(black_box(&frames[0])).unwrap();
                        assert!(e.report.status.is_converged(), "{:?}", e.report.status);
                        black_box(e.resultant_force_cov().clone())
                    },
                    BatchSize::PerIteration,
                )
            });
        }
    }
    group.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    targets = warm, first
}
criterion_main!(benches);
