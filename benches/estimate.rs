//! Estimation benches on the paper's two-section robot: the unknown load is
//! a 20 g tip mass plus a 0.5 N/m uniform load, the markers are spread
//! evenly along the robot (at arc lengths `k L / m`, `k = 1..=m`), each
//! frame is the true shape plus 0.01 mm noise, and `α = 31` (the value the
//! discrepancy principle picks at 20 elements and 5 markers).
//!
//! Groups (criterion ids are `GROUP/BACKEND/PARAMETER`):
//! - `estimate_warm_step/BACKEND/<n>el_<m>mk`: one streaming step (a new
//!   noisy frame of the same scene) of a warm estimator, for elements
//!   `n ∈ {5, 10, 20, 40, 80, 160}` × markers `m ∈ {2, 3, 5, 8, 11}`.
//! - `estimate_cold_step/BACKEND/<n>el_<m>mk`: the first step of a fresh
//!   estimator with `α` given (static solve of the known loads, then the
//!   estimate), same grid.
//! - `estimate_alpha_search/BACKEND/20el_5mk`: the first step of a fresh
//!   estimator without `α` (the discrepancy-principle search), once.
//! - `estimate_warm_scaling/BACKEND/<n>`: the warm step with 5 markers for
//!   `n ∈ {100, 200, 500, 1000, 2000}`, for the log–log fit exponent.
//! - `estimate_warm_step_bounded/sqp/<n>el_5mk`: the sqp warm step with one
//!   load bound (`w_y ≥ −0.3 N/m` at mid-length, active at the solution), 20
//!   and 80 elements.
//!
//! - `estimate_vs_linearization/{linearization,newton,sqp}/20el_5mk`: the
//!   README's scenario in one group, so the ratios come from one run: one
//!   exact linearization at the warm estimate (residual, tangent, its
//!   `L D Lᵀ` factorization and the 10 adjoint solves of the 5 markers)
//!   and the warm step of each backend with the statistical stopping test
//!   at 0.1 of a standard deviation (`statistical_tolerance: 0.1`).
//! - `estimate_first/BACKEND/<load>`: the first step of a fresh estimator
//!   without `α` (the discrepancy-principle search) at 20 elements and 5
//!   markers on loads of the tests and of the report (two separated
//!   bumps, a uniform load plus a tip force, the Gaussian bump, the benches'
//!   tip mass plus uniform load).
//!
//! Run everything (a few minutes; short warm-up and measurement times are
//! set below, the command line overrides them):
//! `cargo bench --bench estimate`
//! Filter by a regular expression on the id, e.g. only the sqp warm steps:
//! `cargo bench --bench estimate -- 'estimate_warm_step/sqp'`
//! Tables for the README: `python3 benches/table.py`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::time::Duration;

#[path = "../tests/common/streaming.rs"]
mod streaming;

use criterion::{BatchSize, BenchmarkId, Criterion, criterion_group, criterion_main};
use softrod::assembly::Robot;
use softrod::element::PlanarCable;
use softrod::estimate::{
    Backend, BoundFrame, Estimate, Estimator, EstimatorSettings, LoadBound, MarkerObservation,
    Observation,
};
use softrod::linsolve::{AutoSolver, FactorOptions, Factorization, SymmetricMatrix, TangentSolver};
use softrod::loads::{LineLoad, Loads, PointForce};
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

const ELEMENTS: [usize; 6] = [5, 10, 20, 40, 80, 160];
const MARKERS: [usize; 5] = [2, 3, 5, 8, 11];
const SCALING: [usize; 5] = [100, 200, 500, 1000, 2000];
const ALPHA: f64 = 31.0;
const BACKENDS: [Backend; 2] = [Backend::Newton, Backend::Sqp];

/// The scene with `n` elements in all, its known loads and 64 noisy frames
/// of `m` markers on the true equilibrium.
struct Case {
    robot: Robot<PlanarCable>,
    known: Loads,
    frames: Vec<Observation>,
}

fn case(n: usize, m: usize) -> Case {
    let (robot, known, frames) = streaming::streaming_case(n, m, 64);
    Case {
        robot,
        known,
        frames,
    }
}

fn settings() -> EstimatorSettings {
    EstimatorSettings {
        alpha: Some(ALPHA),
        ..EstimatorSettings::default()
    }
}

/// A warm estimator (its first step taken on frame 0). If that first step
/// does not converge (the Newton backend's cold start can fail at 160
/// elements), the estimator is led there through 16 observations
/// interpolated from the markers of the known loads' equilibrium; if that
/// fails too, the estimator is returned with the error (the benchmark then
/// times steps that do not converge, and says so).
fn warm(c: &Case, backend: Backend, settings: EstimatorSettings) -> Warm {
    let mut est = softrod::estimate::EstimatorSettings {
        backend,
        ..settings
    }
    .build_for(&c.robot, &c.known)
    .unwrap();
    if est.step(&c.frames[0]).and_then(Estimate::converged).is_ok() {
        return (est, None);
    }
    est.reset();
    let q0 = StaticSolver::default()
        .solve(&c.robot, &c.known, None)
        .unwrap()
        .q;
    let target = &c.frames[0].markers;
    for k in 1..=16 {
        let t = f64::from(k) / 16.0;
        let markers = target
            .iter()
            .map(|mk| {
                let s = mk.s_m.unwrap();
                let p0 = c.robot.position_at(q0.as_slice(), s).unwrap();
                let p = p0
                    .iter()
                    .zip(&mk.position_m)
                    .map(|(a, b)| a + t * (b - a))
                    .collect::<Vec<f64>>();
                MarkerObservation::at_arc(s, nalgebra::DVector::from_vec(p))
            })
            .collect();
        if let Err(e) = est
            .step(&Observation { markers })
            .and_then(Estimate::converged)
        {
            return (est, Some(format!("no warm start: {e}")));
        }
    }
    let failed = est
        .step(&c.frames[0])
        .and_then(Estimate::converged)
        .err()
        .map(|e| format!("no warm start: {e}"));
    (est, failed)
}

/// An estimator and, if it could not be warmed, why.
type Warm = (Box<dyn Estimator>, Option<String>);

/// Benchmarks one warm step per iteration, cycling through the frames.
/// The case is built only if the id passes criterion's filter. A step that
/// does not converge is timed all the same (the time to the answer) and
/// counted: then a `not_converged` file next to criterion's results says
/// how many (`benches/table.py` marks those medians).
fn bench_warm(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    (name, backend, param): (&str, Backend, String),
    make: impl Fn() -> (Case, Warm),
) {
    let dir = marker_dir(name, backend, &param);
    let _ = std::fs::remove_file(dir.join("not_converged"));
    let mut state: Option<(Case, Warm)> = None;
    let (mut k, mut steps, mut failed) = (0, 0usize, 0usize);
    group.bench_function(BenchmarkId::new(backend.name(), &param), |b| {
        let (c, (est, cold)) = state.get_or_insert_with(&make);
        b.iter(|| {
            k = (k + 1) % c.frames.len();
            let ok = black_box(est.step(black_box(&c.frames[k])))
                .is_ok_and(|e| e.report.status.is_converged());
            steps += 1;
            failed += usize::from(!ok);
        });
        if failed > 0 {
            let why = cold.as_deref().unwrap_or("");
            let msg = format!("{failed} of {steps} warm steps did not converge {why}\n");
            eprintln!("{name}/{}/{param}: {msg}", backend.name());
            let _ = std::fs::create_dir_all(&dir);
            let _ = std::fs::write(dir.join("not_converged"), msg);
        }
    });
}

/// Where criterion keeps the results of `group/backend/param`.
fn marker_dir(group: &str, backend: Backend, param: &str) -> std::path::PathBuf {
    std::path::Path::new("target/criterion")
        .join(group)
        .join(backend.name())
        .join(param)
}

fn warm_step(c: &mut Criterion) {
    // `cargo bench --bench estimate -- 'estimate_warm_step/'`
    let mut group = c.benchmark_group("estimate_warm_step");
    for n in ELEMENTS {
        for m in MARKERS {
            for backend in BACKENDS {
                let id = ("estimate_warm_step", backend, format!("{n}el_{m}mk"));
                bench_warm(&mut group, id, || {
                    let c = case(n, m);
                    let w = warm(&c, backend, settings());
                    (c, w)
                });
            }
        }
    }
    group.finish();
}

fn cold_step(c: &mut Criterion) {
    // `cargo bench --bench estimate -- 'estimate_cold_step/'`
    let mut group = c.benchmark_group("estimate_cold_step");
    for n in ELEMENTS {
        for m in MARKERS {
            for backend in BACKENDS {
                let param = format!("{n}el_{m}mk");
                let id = BenchmarkId::new(backend.name(), &param);
                let mut state: Option<Case> = None;
                group.bench_function(id, |b| {
                    let c = state.get_or_insert_with(|| {
                        let c = case(n, m);
                        note_failure("estimate_cold_step", backend, &param, &c, settings());
                        c
                    });
                    b.iter_batched(
                        || {
                            softrod::estimate::EstimatorSettings {
                                backend,
                                ..settings()
                            }
                            .build_for(&c.robot, &c.known)
                            .unwrap()
                        },
                        // the time to the answer, an estimate or a
                        // non-convergence (marked by `note_failure`)
                        |mut est| {
                            black_box(
                                est.step(black_box(&c.frames[1]))
                                    .is_ok_and(|e| e.report.status.is_converged()),
                            )
                        },
                        BatchSize::SmallInput,
                    )
                });
            }
        }
    }
    group.finish();
}

/// Runs the cold step once; if it does not converge, says so on stderr and
/// leaves a `not_converged` file next to criterion's results for the id
/// (`benches/table.py` marks those medians).
fn note_failure(group: &str, backend: Backend, param: &str, c: &Case, settings: EstimatorSettings) {
    let dir = marker_dir(group, backend, param);
    let marker = dir.join("not_converged");
    let _ = std::fs::remove_file(&marker);
    let mut est = softrod::estimate::EstimatorSettings {
        backend,
        ..settings
    }
    .build_for(&c.robot, &c.known)
    .unwrap();
    if let Err(e) = est.step(&c.frames[1]).and_then(Estimate::converged) {
        eprintln!("{group}/{}/{param}: {e}", backend.name());
        let _ = std::fs::create_dir_all(&dir);
        let _ = std::fs::write(&marker, format!("{e}\n"));
    }
}

fn alpha_search(c: &mut Criterion) {
    // `cargo bench --bench estimate -- 'estimate_alpha_search/'`
    let mut group = c.benchmark_group("estimate_alpha_search");
    for backend in BACKENDS {
        let id = BenchmarkId::new(backend.name(), "20el_5mk");
        let mut state: Option<Case> = None;
        group.bench_function(id, |b| {
            let c = state.get_or_insert_with(|| case(20, 5));
            b.iter_batched(
                || {
                    let s = EstimatorSettings {
                        alpha: None,
                        ..EstimatorSettings::default()
                    };
                    softrod::estimate::EstimatorSettings { backend, ..s }
                        .build_for(&c.robot, &c.known)
                        .unwrap()
                },
                |mut est| {
                    black_box(
                        est.step(black_box(&c.frames[1]))
                            .is_ok_and(|e| e.report.status.is_converged()),
                    )
                },
                BatchSize::SmallInput,
            )
        });
    }
    group.finish();
}

fn warm_scaling(c: &mut Criterion) {
    // `cargo bench --bench estimate -- 'estimate_warm_scaling/'`
    let mut group = c.benchmark_group("estimate_warm_scaling");
    for n in SCALING {
        for backend in BACKENDS {
            let id = ("estimate_warm_scaling", backend, n.to_string());
            bench_warm(&mut group, id, || {
                let c = case(n, 5);
                let w = warm(&c, backend, settings());
                (c, w)
            });
        }
    }
    group.finish();
}

fn warm_step_bounded(c: &mut Criterion) {
    // `cargo bench --bench estimate -- 'estimate_warm_step_bounded/'`
    let mut group = c.benchmark_group("estimate_warm_step_bounded");
    for n in [20usize, 80] {
        let id = (
            "estimate_warm_step_bounded",
            Backend::Sqp,
            format!("{n}el_5mk"),
        );
        bench_warm(&mut group, id, || {
            let c = case(n, 5);
            let s_m = 0.5 * c.robot.length();
            let bound = LoadBound {
                s_m,
                frame: BoundFrame::World,
                direction: vec![0.0, 1.0],
                min_n_per_m: Some(-0.3),
                max_n_per_m: None,
            };
            let s = EstimatorSettings {
                bounds: vec![bound],
                ..settings()
            };
            let mut est = softrod::estimate::EstimatorSettings {
                backend: Backend::Sqp,
                ..s
            }
            .build_for(&c.robot, &c.known)
            .unwrap();
            let e = est.step(&c.frames[0]).unwrap();
            // the bound must be active, else this measures the free case
            let w = e.load_at(s_m)[1];
            assert!((w + 0.3).abs() < 1e-6, "bound not active: w_y = {w}");
            (c, (est, None))
        });
    }
    group.finish();
}

fn vs_linearization(c: &mut Criterion) {
    // `cargo bench --bench estimate -- 'estimate_vs_linearization/'`
    let mut group = c.benchmark_group("estimate_vs_linearization");
    let param = "20el_5mk".to_string();
    let mut state: Option<(Case, Vec<f64>)> = None;
    group.bench_function(BenchmarkId::new("linearization", &param), |b| {
        let (c, q) = state.get_or_insert_with(|| {
            let c = case(20, 5);
            let mut est = softrod::estimate::EstimatorSettings {
                backend: Backend::Newton,
                ..settings()
            }
            .build_for(&c.robot, &c.known)
            .unwrap();
            let q = est.step(&c.frames[0]).unwrap().q;
            (c, q.as_slice().to_vec())
        });
        let robot = &c.robot;
        let dead = robot.dead_force(&c.known).unwrap();
        let nf = robot.n_free();
        let mut r = vec![0.0; nf];
        let mut k = SymmetricMatrix::zeros(robot.tangent_pattern().clone());
        let mut solver = AutoSolver::analyze(robot.tangent_pattern()).unwrap();
        // the adjoint right-hand sides of the 5 markers (at nodes 4, 8, …, 20)
        let n_rhs = 10;
        let mut b0 = vec![0.0; nf * n_rhs];
        for mk in 0..5 {
            let node = 4 * (mk + 1);
            for comp in 0..2 {
                b0[(2 * mk + comp) * nf + robot.n_base_free() + (node - 1) * 4 + comp] = 1.0;
            }
        }
        let mut bm = b0.clone();
        b.iter(|| {
            robot
                .residual_into(black_box(q), dead.as_slice(), &c.known, &mut r)
                .unwrap();
            robot.tangent_into(black_box(q), &c.known, &mut k).unwrap();
            let f = solver.factor(&k, FactorOptions::default()).unwrap();
            bm.copy_from_slice(&b0);
            f.solve_columns_in_place(black_box(&mut bm), n_rhs).unwrap();
        })
    });
    for backend in BACKENDS {
        let id = ("estimate_vs_linearization", backend, param.clone());
        bench_warm(&mut group, id, || {
            let c = case(20, 5);
            let s = EstimatorSettings {
                statistical_tolerance: 0.1,
                ..settings()
            };
            let w = warm(&c, backend, s);
            (c, w)
        });
    }
    group.finish();
}

/// The loads of `first_estimate`: `(name, line loads, tip force (N))`.
fn first_loads() -> Vec<(&'static str, Vec<LineLoad>, f64)> {
    let bump = |a: f64, c: f64| LineLoad::Gaussian {
        amplitude_n_per_m: vec![0.0, a],
        center_m: c,
        width_m: 0.01,
    };
    let uniform = |w: f64| LineLoad::Uniform {
        w_n_per_m: vec![0.0, w],
    };
    vec![
        ("two_bumps", vec![bump(-10.0, 0.06), bump(10.0, 0.18)], 0.0),
        ("uniform_tip", vec![uniform(-1.0)], -0.2),
        ("gaussian", vec![bump(-20.0, 0.16)], 0.0),
        ("tip_mass_uniform", vec![uniform(-0.5)], -0.02 * 9.81),
    ]
}

fn first_estimate(c: &mut Criterion) {
    // `cargo bench --bench estimate -- 'estimate_first/'`
    let mut group = c.benchmark_group("estimate_first");
    for (name, lines, tip) in first_loads() {
        for backend in BACKENDS {
            let id = BenchmarkId::new(backend.name(), name);
            let mut state: Option<(Robot<PlanarCable>, Loads, Observation)> = None;
            group.bench_function(id, |b| {
                let (robot, known, obs) = state.get_or_insert_with(|| {
                    let mut scene = Scene::two_section();
                    scene.robot.sections[0].elements = 10;
                    scene.robot.sections[1].elements = 10;
                    let robot = scene.robot().unwrap();
                    let known = scene.loads().unwrap();
                    let mut truth = known.clone();
                    truth.line_loads.extend(lines.iter().cloned());
                    if tip != 0.0 {
                        truth.point_forces.push(PointForce {
                            s_m: robot.length(),
                            force_n: vec![0.0, tip],
                        });
                    }
                    let solver = StaticSolver::default();
                    let q = solver.solve(&robot, &truth, None).unwrap().q;
                    let markers = (1..=5)
                        .map(|k| {
                            let s = robot.length() * f64::from(k) / 5.0;
                            MarkerObservation::at_arc(
                                s,
                                robot.position_at(q.as_slice(), s).unwrap(),
                            )
                        })
                        .collect();
                    let obs = Observation { markers }.with_noise(1e-5, 7);
                    (robot, known, obs)
                });
                b.iter_batched(
                    || {
                        let s = EstimatorSettings {
                            alpha: None,
                            ..EstimatorSettings::default()
                        };
                        softrod::estimate::EstimatorSettings { backend, ..s }
                            .build_for(robot, known)
                            .unwrap()
                    },
                    |mut est| {
                        black_box(
                            est.step(black_box(&*obs))
                                .is_ok_and(|e| e.report.status.is_converged()),
                        )
                    },
                    BatchSize::SmallInput,
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
        .measurement_time(Duration::from_secs(1));
    targets = vs_linearization, first_estimate, warm_step, warm_step_bounded, warm_scaling, cold_step, alpha_search
}
criterion_main!(benches);
