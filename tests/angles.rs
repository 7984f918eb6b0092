//! Tangent angles unwrapped along the backbone: a rod rolled into a full
//! circle reports 2π at its tip (not the `atan2` value near 0), in the
//! library and in `softrod solve`'s output.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::f64::consts::TAU;
use std::process::Command;

use softrod::assembly::{RobotSpec, Section};
use softrod::loads::{Loads, NodeMoment};
use softrod::statics::StaticSolver;

/// Closed form: a tip moment M on a cantilever bends it into an arc of
/// curvature M/EI, the tangent angle growing linearly, θ(s) = M s / EI.
#[test]
fn node_angles_follow_the_closed_form_past_pi() {
    let (l, ei, n) = (0.24, 0.025, 48);
    let robot = RobotSpec::new(vec![Section::uniform(l, 300.0, ei, n)])
        .build_planar()
        .unwrap();
    for turns in [0.75, 1.0, 1.25] {
        let m = turns * TAU * ei / l;
        let loads = Loads {
            node_moments: vec![NodeMoment {
                node: n,
                moment_nm: vec![m],
            }],
            ..Loads::default()
        };
        let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
        let angles = robot.node_angles(eq.q.as_slice()).unwrap();
        for (a, s) in angles.iter().zip(robot.node_arc()) {
            // the mesh's discretization error (1e-6 to 1e-5 rad at 48 elements) is what is left
            assert!(
                (a - m * s / ei).abs() < 5e-5,
                "{turns} turns: θ({s}) = {a}, closed form {}",
                m * s / ei
            );
        }
        // between nodes too
        let s = 0.7 * l;
        let a = robot.angle_at(eq.q.as_slice(), s).unwrap();
        assert!(
            (a - m * s / ei).abs() < 5e-5,
            "{turns} turns: θ({s}) = {a}, closed form {}",
            m * s / ei
        );
    }
}

#[test]
fn softrod_solve_reports_the_unwrapped_tip_angle() {
    let mut scene: serde_json::Value =
        serde_json::from_str(include_str!("../examples/two_section.json")).unwrap();
    let (l, ei) = (0.24, 0.025);
    scene["loads"] = serde_json::json!([{"type": "tip_moment", "moment_nm": TAU * ei / l}]);
    scene["pressures_pa"] = serde_json::json!([0, 0, 0, 0]);
    scene["gravity_m_per_s2"] = serde_json::json!([0, 0]);
    let path = std::env::temp_dir().join(format!("softrod-angles-{}.json", std::process::id()));
    std::fs::write(&path, scene.to_string()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_softrod"))
        .arg("solve")
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let tip = v["tip_angle_rad"].as_f64().unwrap();
    // 20 elements: 1.5e-4 rad discretization error (atan2 alone would give about 0)
    assert!((tip - TAU).abs() < 1e-3, "tip angle {tip}");
    let nodes: Vec<f64> = v["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|n| n["angle_rad"].as_f64().unwrap())
        .collect();
    assert!(nodes.windows(2).all(|w| w[1] > w[0]), "{nodes:?}");
}
