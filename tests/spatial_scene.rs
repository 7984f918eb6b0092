//! A spatial scene (`"element": "spatial_cable"`) through the command line:
//! `softrod solve examples/spatial_cantilever.json` against exudyn's 3-D
//! ANCF cable (`reference/exudyn_spatial_tip_force_oblique_large.json`, the
//! same robot, load, Gauss rules and clamp).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use std::process::Command;

use common::reference;
use serde_json::Value;

const EXAMPLE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/examples/spatial_cantilever.json"
);

/// Runs `softrod ARGS` and parses its standard output as JSON.
fn softrod_json(args: &[&str]) -> Value {
    let out = Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args(args)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "softrod {args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn vector(v: &Value) -> Vec<f64> {
    serde_json::from_value(v.clone()).unwrap()
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// The example is exudyn's oblique large-deflection case at 16 elements:
/// the same discretized energy, so every node agrees to the solvers'
/// tolerances (the bound of `tests/spatial_cable.rs`, 1e-9 m), and the
/// printed tip direction is exudyn's tip tangent (1e-9).
#[test]
fn solve_of_the_spatial_example_matches_exudyn_node_by_node() {
    let ex = reference("exudyn_spatial_tip_force_oblique_large");
    let force = vector(&ex["params"]["loads"][0]["force_n"]);
    let scene: Value = serde_json::from_str(&std::fs::read_to_string(EXAMPLE).unwrap()).unwrap();
    assert_eq!(scene["robot"]["element"], "spatial_cable");
    assert_eq!(vector(&scene["loads"][0]["force_n"]), force);
    let run = ex["values"]["runs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["elements"] == 16)
        .unwrap();
    let out = softrod_json(&["solve", EXAMPLE]);
    assert_eq!(out["report"]["converged"], true);
    let nodes = out["nodes"].as_array().unwrap();
    let reference: Vec<Vec<f64>> = serde_json::from_value(run["nodes"].clone()).unwrap();
    assert_eq!(nodes.len(), 17);
    assert_eq!(reference.len(), 17);
    let mut worst = 0.0f64;
    for (n, r) in nodes.iter().zip(&reference) {
        let p = vector(&n["position_m"]);
        assert_eq!(p.len(), 3);
        assert_eq!(vector(&n["slope"]).len(), 3);
        worst = worst.max(dist(&p, &r[..3]));
    }
    let tip = vector(&out["tip_position_m"]);
    let tip_err = dist(&tip, &vector(&run["tip_position_m"]));
    let dir_err = dist(&vector(&out["tip_direction"]), &vector(&run["tip_tangent"]));
    println!("nodes vs exudyn (16 elements): max {worst:.2e} m; tip {tip_err:.2e} m; tip direction {dir_err:.2e}");
    assert!(worst <= 1e-9, "{worst} m");
    assert!(tip_err <= 1e-9, "{tip_err} m");
    assert!(dir_err <= 1e-9, "{dir_err}");
    // the tip is far out of the base's plane: a 3-D result, not a planar one
    assert!(tip[2] < -0.1, "{tip:?}");
    assert!(out.get("tip_angle_rad").is_none());
    let angle = out["tip_angle_from_base_rad"].as_f64().unwrap();
    assert!((angle - run["tip_tangent"][0].as_f64().unwrap().acos()).abs() <= 1e-9);
}
