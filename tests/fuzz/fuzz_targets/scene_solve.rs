//! Fuzz target: arbitrary bytes as a scene file, then everything the CLI
//! does with it (parse, validate, build, solve, read markers back).
//!
//! The library must never panic and never return a non-finite number from a
//! successful solve. Inputs are capped so the fuzzer spends its time on
//! parsing and validation, not on huge valid solves; the library itself
//! must refuse absurd sizes (that is tested in tests/bad_inputs.rs).
#![no_main]

use libfuzzer_sys::fuzz_target;
use softrod::scene::Scene;
use softrod::statics::{StaticCriterion, StaticSolver};

/// Largest input (bytes).
const MAX_INPUT: usize = 16 * 1024;
/// Largest element count solved.
const MAX_ELEMENTS: usize = 500;
/// Largest iteration budget solved.
const MAX_ITERATIONS: usize = 400;

fuzz_target!(|data: &[u8]| {
    if data.len() > MAX_INPUT {
        return;
    }
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let scene = match Scene::from_json(text) {
        Ok(s) => s,
        Err(e) => {
            // errors must render
            let _ = e.to_string();
            return;
        }
    };
    let total: usize = scene
        .robot
        .sections
        .iter()
        .fold(0usize, |a, s| a.saturating_add(s.elements));
    if total > MAX_ELEMENTS || scene.solver.statics.max_total_iterations > MAX_ITERATIONS {
        return;
    }
    let Ok(robot) = scene.robot() else {
        return;
    };
    let Ok(loads) = scene.loads() else {
        return;
    };
    let Ok(solver) = StaticSolver::new(scene.solver.statics.clone()) else {
        return;
    };
    match solver.solve(&robot, &loads, None) {
        Ok(eq) => {
            assert!(eq.q.iter().all(|v| v.is_finite()), "non-finite q");
            let r = &eq.report;
            for v in [
                r.residual_norm_n,
                r.residual_tolerance_n,
                r.residual_floor_n,
                r.load_scale_n,
                r.increment_norm_m,
                r.wall_time_s,
            ] {
                assert!(v.is_finite(), "non-finite report: {r}");
            }
            // a returned solution is an equilibrium: the residual, recomputed
            // through the public API, is within the reported bound (the
            // increment criterion is trusted only at a tight tolerance)
            if let Ok(dead) = robot.dead_force(&loads) {
                let res = robot
                    .residual(&eq.q, &dead, &loads)
                    .map(|r| r.iter().map(|x| x * x).sum::<f64>().sqrt());
                let bound = r.residual_tolerance_n.max(r.residual_floor_n);
                let by_increment = r.status.criterion() == Some(StaticCriterion::Increment);
                if let Ok(res) = res {
                    assert!(
                        res <= bound * (1.0 + 1e-6)
                            || (by_increment && scene.solver.statics.increment_tolerance > 1e-10),
                        "|Q| = {res:e} above {bound:e} at a returned solution: {r}"
                    );
                }
            }
            for m in &scene.markers {
                if let Some(s) = m.s_m {
                    let p = robot.position_at(&eq.q, s);
                    assert!(p.is_ok(), "validated marker off the robot");
                }
            }
            let _ = robot.node_positions(&eq.q);
            let _ = robot.elastic_energy(&eq.q);
            // a warm start from the solution must also be fine
            let _ = solver.solve(&robot, &loads, Some(&eq.q));
        }
        Err(e) => {
            let _ = e.to_string();
        }
    }
});
