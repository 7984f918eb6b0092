//! Obstacle avoidance by touch (the paper's Fig. 9) on the five-section
//! robot, the plant not the model (twice the mesh, EI +15 %, gain −10 %,
//! EA −5 %, σ = 0.05 mm, regulator lag 20 ms), 20 Hz, the paper's field
//! parameters: obstacle placements × goals, with touch feedback and the
//! baseline without it.
//!
//! Run: `cargo run --release --example avoid_fig9 [OUT.json]` (prints the
//! table; writes every run as JSON if a path is given).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::contact::{Obstacle, Obstacles};
use softrod::plant::{PlantSettings, SimulatedPlant};
use softrod::touch::{
    calibrate_on_free_plant, five_section_scene, marker_arcs, run_avoidance, AvoidSettings,
    AvoidStatus, ROD_RADIUS_M,
};

/// Disks (centre, radius; m) in the path the robot's lower part sweeps.
pub const PLACEMENTS: [([f64; 2], f64); 5] = [
    ([0.08, -0.465], 0.01),
    ([0.10, -0.455], 0.01),
    ([0.06, -0.475], 0.015),
    ([0.12, -0.45], 0.01),
    ([0.09, -0.48], 0.02),
];

/// Goals of the end effector (m).
pub const GOALS: [[f64; 2]; 2] = [[0.15, -0.40], [0.12, -0.36]];

fn main() -> softrod::Result<()> {
    let out = std::env::args().nth(1);
    let scene = five_section_scene(4);
    let arcs = marker_arcs(6);
    let ps = PlantSettings::default();
    let cal = calibrate_on_free_plant(&scene, &arcs, &ps)?;
    println!(
        "calibration: EI x {:.4}, gain x {:.4} (plant: 1.15, 0.90); marker rms {:.3} -> {:.3} mm",
        cal.ei_factor,
        cal.gain_factor,
        cal.rms_before_m * 1e3,
        cal.rms_after_m * 1e3
    );
    println!("obstacle (m)              goal (m)        | touch: status      final(mm) f_before(N) f_after(N) touches | baseline: status final(mm) f_max(N) f_end(N)");
    let mut runs = Vec::new();
    for (c, r) in PLACEMENTS {
        for goal in GOALS {
            let mut res = Vec::new();
            for feedback in [true, false] {
                let obstacles = Obstacles::new(
                    vec![Obstacle::Circle {
                        center_m: c,
                        radius_m: r,
                    }],
                    ROD_RADIUS_M,
                )?;
                let mut plant =
                    SimulatedPlant::new(&scene, &arcs, ps.clone())?.with_obstacles(obstacles)?;
                let settings = AvoidSettings {
                    duration_s: 120.0,
                    touch_feedback: feedback,
                    ..AvoidSettings::default()
                };
                let run = run_avoidance(&scene, &cal, &arcs, &mut plant, goal, &settings);
                res.push(run);
            }
            let status = |s: &AvoidStatus| match s {
                AvoidStatus::Reached { time_s } => format!("reached {time_s:5.1} s"),
                AvoidStatus::NotReached { .. } => "not reached    ".into(),
                AvoidStatus::GoalUnreachable { .. } => "unreachable    ".into(),
            };
            let line = match (&res[0], &res[1]) {
                (Ok(a), Ok(b)) => format!(
                    "{} {:9.2} {:11.4} {:10.4} {:7} | {} {:9.2} {:8.4} {:8.4}",
                    status(&a.status),
                    a.final_error_m * 1e3,
                    a.max_force_before_n,
                    a.max_force_after_n,
                    a.touched.len(),
                    status(&b.status),
                    b.final_error_m * 1e3,
                    b.max_force_before_n,
                    b.final_force_n
                ),
                (a, b) => format!("error: {:?} / {:?}", a.as_ref().err(), b.as_ref().err()),
            };
            println!(
                "({:.3}, {:.3}) r {:.3}  ({:.3}, {:.3}) | {line}",
                c[0], c[1], r, goal[0], goal[1]
            );
            runs.push(res.into_iter().filter_map(|r| r.ok()).collect::<Vec<_>>());
        }
    }
    if let Some(path) = out {
        std::fs::write(&path, serde_json::to_string(&runs).unwrap()).unwrap();
        println!("wrote {path}");
    }
    Ok(())
}
