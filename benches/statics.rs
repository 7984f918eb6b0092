//! Static solver benches: the cost of one Newton step (assembly of residual
//! and tangent, banded LU, solve) from 10 to 2000 elements, and whole solves.
//!
//! Run: `cargo bench --bench statics` then `python3 benches/fit_exponent.py GROUP`
//! for GROUP in `newton_step`, `static_solve_cold`, `static_solve_warm`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use softrod::assembly::Robot;
use softrod::banded::BandedMatrix;
use softrod::element::PlanarCable;
use softrod::loads::Loads;
use softrod::params;
use softrod::statics::StaticSolver;

/// The paper's two-section robot with `n` elements in all, under its weight
/// and the default pressures, at its equilibrium.
fn robot(n: usize) -> (Robot<PlanarCable>, Loads, Vec<f64>) {
    let mut scene = softrod::scene::Scene::two_section();
    for s in &mut scene.robot.sections {
        s.elements = n.div_ceil(2);
    }
    let robot = scene.robot().unwrap();
    let mut loads = scene.loads().unwrap();
    loads.pressures_pa = params::DEFAULT_PRESSURES_PA.to_vec();
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    (robot, loads, eq.q)
}

fn newton_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("newton_step");
    for &n in &[10usize, 20, 50, 100, 200, 500, 1000, 2000] {
        let (robot, loads, q) = robot(n);
        let dead = robot.dead_force(&loads).unwrap();
        let mut r = vec![0.0; robot.n_free()];
        let mut k = BandedMatrix::zeros(robot.n_free(), 7, 7);
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                robot
                    .residual_into(black_box(&q), &dead, &loads, &mut r)
                    .unwrap();
                robot.tangent_into(black_box(&q), &loads, &mut k).unwrap();
                let lu = k.clone().factor_scaled(0.0, "K").unwrap();
                lu.solve_in_place(&mut r).unwrap();
                black_box(&r);
            })
        });
    }
    group.finish();
}

fn static_solve(c: &mut Criterion) {
    // cold: from the arc configuration; warm: from the previous equilibrium
    // after a 0.5 kPa pressure change (a control step).
    let mut cold = c.benchmark_group("static_solve_cold");
    for &n in &[6usize, 20, 100, 500, 2000] {
        let (robot, loads, _) = robot(n);
        let solver = StaticSolver::default();
        cold.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| solver.solve(&robot, black_box(&loads), None).unwrap())
        });
    }
    cold.finish();
    let mut warm = c.benchmark_group("static_solve_warm");
    for &n in &[6usize, 20, 100, 500, 2000] {
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
