//! The static solver's globalization across meshes: every exudyn reference
//! case and four hard loads (a 2 N mid-length force against a tip moment, a
//! post-buckled column, a tip moment rolling the rod into a full circle, the
//! estimator bench's loads; `tests/common/statics_cases.rs`) solved cold at
//! 8, 32, 128 and 512 elements. Each converges within a Newton-iteration
//! budget that does not depend on the mesh, and the total over the cases
//! does not grow with it (a fine mesh starts from a coarse mesh's
//! equilibrium: `src/statics/sequence.rs`). The timing over 8 to 2000
//! elements is `benches/statics_scaling.rs`; the README has its iteration
//! table.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "common/statics_cases.rs"]
mod cases;
mod common;

use softrod::assembly::Robot;
use softrod::element::PlanarCable;
use softrod::loads::{Loads, NodeMoment};
use softrod::statics::StaticSolver;

/// Total Newton iterations (every load step's, the coarse mesh's included)
/// one cold solve may take (measured at most 51: the post-buckled column).
const BUDGET: usize = 60;

/// The total over the cases at 512 elements over the total at 8 (measured
/// 263 / 201 = 1.31; 272 / 201 = 1.35 at 2000 elements in the bench).
const GROWTH: f64 = 1.5;

#[test]
fn cold_solves_converge_within_a_mesh_independent_budget() {
    let solver = StaticSolver::default();
    let mut failures = Vec::new();
    let mut totals = Vec::new();
    for n in [8, 32, 128, 512] {
        let mut total = 0;
        for (name, scene) in cases::all(n) {
            let robot = scene.robot().unwrap();
            let loads = scene.loads().unwrap();
            match solver.solve(&robot, &loads, None) {
                Ok(eq) => {
                    total += eq.report.iterations;
                    if eq.report.iterations > BUDGET {
                        failures.push(format!("{name}/{n}: {} iterations", eq.report.iterations));
                    }
                    if eq.report.negative_eigenvalues != Some(0) {
                        failures.push(format!("{name}/{n}: not stable: {}", eq.report));
                    }
                }
                Err(e) => failures.push(format!("{name}/{n}: {e}")),
            }
        }
        totals.push((n, total));
    }
    assert!(failures.is_empty(), "{failures:#?}");
    let (first, last) = (totals[0].1 as f64, totals[totals.len() - 1].1 as f64);
    assert!(
        last <= GROWTH * first,
        "the totals grow with the mesh: {totals:?}"
    );
}

/// The coarse start: the full circle's 16-element equilibrium, interpolated
/// onto 128 elements, is within the coarse discretization error of the
/// fine equilibrium, and the fine mesh then takes only a few Newton
/// iterations.
#[test]
fn a_fine_mesh_starts_from_the_coarse_equilibrium() {
    let scene = cases::hard("full_circle", 128);
    let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    let solver = StaticSolver::default();
    let fine = solver.solve(&robot, &loads, None).unwrap();
    let (coarse, coarse_loads) = robot.coarsened(&loads).unwrap().unwrap();
    assert_eq!(coarse.n_elements(), 16);
    let c = solver.solve(&coarse, &coarse_loads, None).unwrap();
    let u = robot.prolong_from(&coarse, c.q.as_slice()).unwrap();
    let gap = u
        .iter()
        .zip(&fine.u)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    // the circle's discretization error at 16 elements (measured 1.4e-3 on
    // the slopes)
    assert!(gap > 0.0 && gap < 3e-3, "gap {gap:e}");
    let on_fine = fine.report.iterations - c.report.iterations;
    assert!(on_fine <= 6, "{on_fine} iterations on the fine mesh");
}

/// A moment at a node of the fine mesh reaches the coarse mesh as the same
/// moment at that node's arc coordinate, and the distributed-load
/// parameters as the same field (a uniform one stays uniform).
#[test]
fn the_coarse_mesh_carries_the_loads_over() {
    let scene = cases::hard("estimator_bench", 128);
    let robot: Robot<PlanarCable> = scene.robot().unwrap();
    // a uniform field w = (0, −2) N/m as distributed-load parameters
    let mut f = vec![0.0; robot.n_q()];
    f.chunks_mut(4).for_each(|c| c[1] = -2.0);
    let loads = Loads {
        distributed_f: f,
        node_moments: vec![NodeMoment {
            node: 64,
            moment_nm: vec![0.05],
        }],
        ..scene.loads().unwrap()
    };
    assert!(loads.point_moments.is_empty());
    let (coarse, carried) = robot.coarsened(&loads).unwrap().unwrap();
    assert!(carried.node_moments.is_empty());
    assert_eq!(carried.point_moments.len(), 1);
    assert!((carried.point_moments[0].s_m - robot.node_arc()[64]).abs() < 1e-15);
    assert_eq!(carried.distributed_f.len(), coarse.n_q());
    assert!(carried.distributed_f.chunks(4).all(|c| c[0].abs() < 1e-12
        && (c[1] + 2.0).abs() < 1e-12
        && c[2].abs() < 1e-12
        && c[3].abs() < 1e-12));
}

/// The full circle: the tip comes back to the base (the inextensible
/// circle closes; the rod's stretch under a pure moment is nil) and the
/// tip slope points along +x again.
#[test]
fn the_full_circle_closes() {
    for n in [8, 32] {
        let scene = cases::hard("full_circle", n);
        let robot = scene.robot().unwrap();
        let eq = StaticSolver::default()
            .solve(&robot, &scene.loads().unwrap(), None)
            .unwrap();
        let q = &eq.q;
        let k = q.len() - 4;
        let gap = (q[k].powi(2) + q[k + 1].powi(2)).sqrt();
        // discretization error of the circle: 2e-4 m at 8 elements, 1e-6 at 32
        let bound = if n == 8 { 5e-4 } else { 5e-6 };
        assert!(gap < bound, "{n}: the tip is {gap:e} m from the base");
        assert!(
            q[k + 2] > 0.99 && q[k + 3].abs() < 1e-2,
            "{n}: tip slope {:?}",
            &q.as_slice()[k + 2..]
        );
    }
}
