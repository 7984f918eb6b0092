//! Static solver benches on the paper's two-section robot (elements split
//! `n/2 + (n − n/2)` between the sections) under its weight and the default
//! pressures:
//! - `newton_step/<n>`: one Newton step (assembly of residual and tangent,
//!   the library's sparse `L D Lᵀ`, analyzed once, solve) at the
//!   equilibrium, 10 to 2000 elements;
//! - `static_solve_cold/<n>`: a whole solve from the arc configuration,
//!   5 to 2000 elements;
//! - `static_solve_warm/<n>`: a whole solve from the previous equilibrium
//!   after a 0.5 kPa pressure change (a control step), 5 to 2000 elements;
//!
//! Run: `cargo bench --bench statics -- --warm-up-time 1 --measurement-time 3`
//! (filter by group: `cargo bench --bench statics -- static_solve_warm`),
//! then `python3 benches/table.py` for the README tables, or
//! `python3 benches/fit_exponent.py GROUP 100` for one group's fit.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use softrod::assembly::Robot;
use softrod::element::PlanarCable;
use softrod::linsolve::{AutoSolver, FactorOptions, Factorization, SymmetricMatrix, TangentSolver};
use softrod::loads::Loads;
use softrod::params;
use softrod::statics::StaticSolver;

/// The paper's two-section robot with `n` elements in all, under its weight
/// and the default pressures, at its equilibrium.
fn robot(n: usize) -> (Robot<PlanarCable>, Loads, Vec<f64>) {
    let mut scene = softrod::scene::Scene::two_section();
    scene.robot.sections[0].elements = n / 2;
    scene.robot.sections[1].elements = n - n / 2;
    let robot = scene.robot().unwrap();
    assert_eq!(robot.elements().len(), n);
    let mut loads = scene.loads().unwrap();
    loads.pressures_pa = params::DEFAULT_PRESSURES_PA.to_vec();
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    (robot, loads, eq.q.data.into())
}

fn newton_step(c: &mut Criterion) {
    // `cargo bench --bench statics -- newton_step`
    let mut group = c.benchmark_group("newton_step");
    for &n in &[10usize, 20, 50, 100, 200, 500, 1000, 2000] {
        let (robot, loads, q) = robot(n);
        let dead = robot.dead_force(&loads).unwrap();
        let mut r = vec![0.0; robot.n_free()];
        let mut k = SymmetricMatrix::zeros(robot.tangent_pattern().clone());
        let mut solver = AutoSolver::analyze(robot.tangent_pattern()).unwrap();
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                robot
                    .residual_and_tangent_into(
                        black_box(&q),
                        dead.as_slice(),
                        &loads,
                        &mut r,
                        &mut k,
                    )
                    .unwrap();
                let f = solver.factor(&k, FactorOptions::default()).unwrap();
                f.solve_in_place(&mut r).unwrap();
                black_box(&r);
            })
        });
    }
    group.finish();
}

fn static_solve(c: &mut Criterion) {
    // cold: from the arc configuration; warm: from the previous equilibrium
    // after a 0.5 kPa pressure change (a control step).
    // `cargo bench --bench statics -- static_solve_cold`
    let mut cold = c.benchmark_group("static_solve_cold");
    for &n in &[5usize, 6, 20, 100, 500, 2000] {
        let (robot, loads, _) = robot(n);
        let solver = StaticSolver::default();
        cold.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| solver.solve(&robot, black_box(&loads), None).unwrap())
        });
    }
    cold.finish();
    // `cargo bench --bench statics -- static_solve_warm`
    let mut warm = c.benchmark_group("static_solve_warm");
    for &n in &[5usize, 6, 20, 100, 500, 2000] {
        let (robot, loads, q) = robot(n);
        let solver = StaticSolver::default();
        let mut nudged = loads.clone();
        nudged.pressures_pa[0] += 500.0;
        warm.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| solver.solve(&robot, black_box(&nudged), Some(&q)).unwrap())
        });
    }
    warm.finish();
}

criterion_group!(benches, newton_step, static_solve);
criterion_main!(benches);
