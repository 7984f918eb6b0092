//! `softrod grasp`: one trial from a scene file; bad scenes name the field.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "common/cli.rs"]
mod cli;
use cli::softrod as run;

#[test]
fn grasp_writes_the_outcome_and_rejects_bad_objects() {
    let dir = std::env::temp_dir().join(format!("softrod_grasp_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("out.json");
    let (code, _, err) = run(&[
        "grasp",
        "examples/grasp_apple.json",
        "--strategy",
        "open_loop",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["strategy"], "open_loop");
    assert!(v["success"].is_boolean() && v["frames"].as_array().unwrap().len() > 10);
    let bad = dir.join("bad.json");
    std::fs::write(
        &bad,
        r#"{"object": {"name": "x", "shape": {"shape": "circle", "radius_m": 0.02}, "mass_kg": 0.1, "mu": -0.5}}"#,
    )
    .unwrap();
    let (code, _, err) = run(&["grasp", bad.to_str().unwrap()]);
    assert_ne!(code, 0);
    assert!(err.contains("object.mu"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
}
