//! Kernel benches: the pieces a static Newton step and an estimator step
//! are made of, on the two-section robot at its equilibrium under the
//! scene's loads, for 20, 200 and 2000 elements:
//!
//! - `element_hessian`: one element's energy Hessian (8 × 8);
//! - `residual`, `tangent`, `residual_and_tangent`: the assembled
//!   generalized force and tangent stiffness (`Robot::residual_into`,
//!   `Robot::tangent_into`, both in one pass);
//! - `factor_ldlt`, `factor_lu`: the Jacobi-scaled tangent by the library's
//!   solver (faer's sparse `L D Lᵀ`, analysis done once), and, for a
//!   tangent shifted to be indefinite, by its pivoted LU fallback;
//! - `solve`: one right-hand side with the `L D Lᵀ` factors;
//! - `adjoint_solves`: the 10 right-hand sides of the marker Jacobian
//!   (5 markers × 2 components) in one sweep;
//! - `marker_jacobian`: `NewtonEstimator::markers_and_jacobian` at the
//!   estimate (equilibrium check, factorization, adjoint solves, `Gᵀ z`).
//!
//! Run: `cargo bench --bench kernels` (then `python3 benches/fit_exponent.py
//! kernels/GROUP` for a scaling exponent).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use softrod::assembly::Robot;
use softrod::element::{Element, PlanarCable};
use softrod::estimate::{EstimatorSettings, NewtonEstimator, Observation};
use softrod::linsolve::{
    AutoSolver, FactorMethod, FactorOptions, Factorization, SymmetricMatrix, TangentSolver,
};
use softrod::loads::Loads;
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

const SIZES: [usize; 3] = [20, 200, 2000];

/// The two-section robot with `n` elements in all at its equilibrium under
/// the scene's loads.
fn setup(n: usize) -> (Robot<PlanarCable>, Loads, Vec<f64>) {
    let mut scene = Scene::two_section();
    for s in &mut scene.robot.sections {
        s.elements = n / 2;
    }
    let robot = scene.robot().unwrap();
    let loads = scene.loads().unwrap();
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    (robot, loads, eq.q.data.into())
}

fn kernels(c: &mut Criterion) {
    let mut group = c.benchmark_group("kernels");
    for n in SIZES {
        let (robot, loads, q) = setup(n);
        let dead = robot.dead_force(&loads).unwrap();
        let nf = robot.n_free();
        let mut r = vec![0.0; nf];
        let mut k = SymmetricMatrix::zeros(robot.tangent_pattern().clone());
        if n == SIZES[0] {
            let el = &robot.elements()[n / 2];
            let qe = &q[4 * (n / 2)..4 * (n / 2) + 8];
            let mut h = [0.0; 64];
            group.bench_function("element_hessian", |b| {
                b.iter(|| {
                    h.fill(0.0);
                    el.add_energy_hessian(black_box(qe), &mut h);
                    black_box(&h);
                })
            });
        }
        group.bench_with_input(BenchmarkId::new("residual", n), &n, |b, _| {
            b.iter(|| {
                robot
                    .residual_into(black_box(&q), dead.as_slice(), &loads, &mut r)
                    .unwrap()
            })
        });
        group.bench_with_input(BenchmarkId::new("tangent", n), &n, |b, _| {
            b.iter(|| robot.tangent_into(black_box(&q), &loads, &mut k).unwrap())
        });
        group.bench_with_input(BenchmarkId::new("residual_and_tangent", n), &n, |b, _| {
            b.iter(|| {
                robot
                    .residual_and_tangent_into(
                        black_box(&q),
                        dead.as_slice(),
                        &loads,
                        &mut r,
                        &mut k,
                    )
                    .unwrap()
            })
        });
        robot.tangent_into(&q, &loads, &mut k).unwrap();
        let mut solver = AutoSolver::analyze(robot.tangent_pattern()).unwrap();
        // the LU path: the tangent shifted by −2 |k_ii| is indefinite
        let mut k_lu = k.clone();
        for i in 0..nf {
            let v = k_lu.get(i, i);
            k_lu.add(i, i, -2.0 * v.abs()).unwrap();
        }
        let f_lu = solver.factor(&k_lu, FactorOptions::default()).unwrap();
        assert_eq!(f_lu.method(), FactorMethod::Lu);
        group.bench_with_input(BenchmarkId::new("factor_lu", n), &n, |b, _| {
            b.iter(|| black_box(solver.factor(&k_lu, FactorOptions::default()).unwrap()))
        });
        group.bench_with_input(BenchmarkId::new("factor_ldlt", n), &n, |b, _| {
            b.iter(|| black_box(solver.factor(&k, FactorOptions::default()).unwrap()))
        });
        let f = solver.factor(&k, FactorOptions::default()).unwrap();
        assert_eq!(f.method(), FactorMethod::Ldlt);
        let rhs: Vec<f64> = (0..nf).map(|i| ((i * 7919) % 101) as f64 - 50.0).collect();
        let mut x = rhs.clone();
        group.bench_with_input(BenchmarkId::new("solve", n), &n, |b, _| {
            b.iter(|| {
                x.copy_from_slice(&rhs);
                f.solve_in_place(black_box(&mut x)).unwrap();
            })
        });
        // the marker Jacobian's right-hand sides: M^T a_i for 5 markers x 2
        let nodes: Vec<usize> = (1..=5).map(|m| m * n / 5).collect();
        let m = 2 * nodes.len();
        let mut b0 = vec![0.0; nf * m];
        for (c, node) in nodes.iter().enumerate() {
            for comp in 0..2 {
                // node >= 1: free coordinate (node − 1)·4 + comp + 1;
                // right-hand side 2 c + comp, column after column
                b0[(2 * c + comp) * nf + robot.n_base_free() + (node - 1) * 4 + comp] = 1.0;
            }
        }
        let mut bm = b0.clone();
        group.bench_with_input(BenchmarkId::new("adjoint_solves", n), &n, |b, _| {
            b.iter(|| {
                bm.copy_from_slice(&b0);
                f.solve_columns_in_place(black_box(&mut bm), m).unwrap();
            })
        });
        let obs = Observation::of_nodes(&robot, &q, &nodes)
            .unwrap()
            .with_noise(1e-5, 3);
        let settings = EstimatorSettings {
            alpha: Some(31.0),
            ..EstimatorSettings::default()
        };
        let mut est = NewtonEstimator::new(&robot, &loads, &settings).unwrap();
        let e = softrod::estimate::Estimator::step(&mut est, &obs).unwrap();
        group.bench_with_input(BenchmarkId::new("marker_jacobian", n), &n, |b, _| {
            b.iter(|| black_box(est.markers_and_jacobian(&obs, e.f.as_slice()).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(benches, kernels);
criterion_main!(benches);
