//! Linear-solver benches: factor + solve of the real tangent stiffness of
//! the two-section robot at its equilibrium under the scene's loads (a
//! loaded, positive definite tangent), 20, 200 and 2000 elements, for
//! faer's sparse solver in its settings (the banded solver these were
//! compared with was removed: README, "Performance"):
//!
//! - `sparse_ldlt`, `sparse_llt`: faer with the AMD ordering, the symbolic
//!   analysis done once and reused; `sparse_ldlt_natural`: the chain's own
//!   order;
//! - `sparse_lu`: faer's simplicial LU (the sparse fallback) after the
//!   `L D Lᵀ` that finds the inertia, forced by an indefinite copy of the
//!   tangent (one diagonal entry negated);
//! - `*_10rhs`: the same factorization, then 10 right-hand sides in one
//!   sweep (the estimator's adjoint solves for 5 markers × 2 components);
//! - `sparse_analyze`: the one-off symbolic analysis, for scale.
//!
//! Run: `cargo bench --bench linsolve -- --warm-up-time 1 --measurement-time 3`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::hint::black_box;
use std::sync::Arc;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use softrod::assembly::{Robot, RobotSpec};
use softrod::element::PlanarCable;
use softrod::linsolve::sparse::Ordering;
use softrod::linsolve::{
    BandedMatrix, CholeskyKind, FactorMethod, FactorOptions, Factorization, SparseSettings,
    SparseSolver, SymmetricMatrix, SymmetricPattern, TangentSolver,
};
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

const SIZES: [usize; 3] = [20, 200, 2000];
const NRHS: usize = 10;

/// The two-section robot with `n` elements in all (the scene's
/// `RobotSpec`, sections refined), its tangent at the equilibrium under the scene's
/// loads as a band matrix and on the connectivity pattern.
fn setup(n: usize) -> (BandedMatrix, SymmetricMatrix) {
    let scene = Scene::two_section();
    let mut spec: RobotSpec = scene.robot().unwrap().spec().clone();
    for sec in &mut spec.sections {
        sec.elements = n / 2;
    }
    let robot: Robot<PlanarCable> = spec.build_planar().unwrap();
    assert_eq!(robot.elements().len(), n);
    let loads = scene.loads().unwrap();
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    let nf = robot.n_free();
    let mut k = BandedMatrix::zeros(nf, 7, 7);
    robot.tangent_into(eq.q.as_slice(), &loads, &mut k).unwrap();
    // the connectivity in free coordinates: element 0 couples the base's
    // free directions with node 1, element e >= 1 nodes e and e + 1
    let nb = robot.n_base_free();
    let elements: Vec<Vec<usize>> = (0..n)
        .map(|e| {
            if e == 0 {
                (0..nb + 4).collect()
            } else {
                (nb + 4 * (e - 1)..nb + 4 * (e + 1)).collect()
            }
        })
        .collect();
    let pattern = Arc::new(SymmetricPattern::from_elements(nf, &elements).unwrap());
    let mut ks = SymmetricMatrix::zeros(pattern);
    let entries: Vec<(usize, usize)> = ks.iter_upper().map(|(i, j, _)| (i, j)).collect();
    for (i, j) in entries {
        ks.add(i, j, k.get(i, j)).unwrap();
    }
    // the pattern holds the whole assembled tangent
    let back = ks.to_banded().unwrap();
    for i in 0..nf {
        for j in i.saturating_sub(7)..(i + 8).min(nf) {
            assert_eq!(
                back.get(i, j),
                k.get(i, j),
                "({i}, {j}) outside the pattern"
            );
        }
    }
    (k, ks)
}

fn rhs(n: usize, m: usize) -> Vec<f64> {
    (0..n * m)
        .map(|i| ((i * 7919) % 101) as f64 - 50.0)
        .collect()
}

/// Benches `factor` + one solve and `factor` + 10 solves of a solver.
fn bench_solver<S: TangentSolver>(
    group: &mut criterion::BenchmarkGroup<'_, criterion::measurement::WallTime>,
    name: &str,
    n: usize,
    solver: &mut S,
    k: &SymmetricMatrix,
    method: FactorMethod,
) {
    let nf = k.n();
    let f = solver.factor(k, FactorOptions::default()).unwrap();
    assert_eq!(f.method(), method, "{name}");
    let (b1, b10) = (rhs(nf, 1), rhs(nf, NRHS));
    let (mut x1, mut x10) = (b1.clone(), b10.clone());
    group.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
        b.iter(|| {
            let f = solver
                .factor(black_box(k), FactorOptions::default())
                .unwrap();
            x1.copy_from_slice(&b1);
            f.solve_in_place(&mut x1).unwrap();
        })
    });
    group.bench_with_input(
        BenchmarkId::new(format!("{name}_{NRHS}rhs"), n),
        &n,
        |b, _| {
            b.iter(|| {
                let f = solver
                    .factor(black_box(k), FactorOptions::default())
                    .unwrap();
                x10.copy_from_slice(&b10);
                f.solve_columns_in_place(&mut x10, NRHS).unwrap();
            })
        },
    );
}

fn linsolve(c: &mut Criterion) {
    let mut group = c.benchmark_group("linsolve");
    for n in SIZES {
        let (_, ks) = setup(n);
        let nf = ks.n();
        let p = ks.pattern().clone();

        for (name, settings, method) in [
            ("sparse_ldlt", SparseSettings::default(), FactorMethod::Ldlt),
            (
                "sparse_llt",
                SparseSettings {
                    cholesky: CholeskyKind::Llt,
                    ..SparseSettings::default()
                },
                FactorMethod::Llt,
            ),
            (
                "sparse_ldlt_natural",
                SparseSettings {
                    ordering: Ordering::Natural,
                    ..SparseSettings::default()
                },
                FactorMethod::Ldlt,
            ),
        ] {
            let mut s = SparseSolver::with_settings(&p, settings).unwrap();
            bench_solver(&mut group, name, n, &mut s, &ks, method);
        }
        // the sparse LU fallback: an indefinite copy (one diagonal entry
        // negated: a rank-one change, exactly one negative eigenvalue)
        let mut k_ind = ks.clone();
        let d = p.diagonal_slots()[nf / 2];
        k_ind.values_mut()[d] = -ks.values()[d];
        let mut s = SparseSolver::analyze(&p).unwrap();
        let f = s.factor(&k_ind, FactorOptions::default()).unwrap();
        assert_eq!(f.inertia().map(|i| i.negative), Some(1));
        bench_solver(&mut group, "sparse_lu", n, &mut s, &k_ind, FactorMethod::Lu);
        group.bench_with_input(BenchmarkId::new("sparse_analyze", n), &n, |b, _| {
            b.iter(|| black_box(SparseSolver::analyze(black_box(&p)).unwrap()))
        });
    }
    group.finish();
}

criterion_group!(benches, linsolve);
criterion_main!(benches);
