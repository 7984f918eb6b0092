//! `softrod track`, `softrod estimate` and `softrod solve` on a
//! parallel-robot scene, run as the binary.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::process::Command;

fn softrod(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap()
}

fn scratch(name: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("softrod_parallel_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A short run of the example scene (1 s hold, 1 s of the circle, model of 1
/// element per section): the summary is written, the updater's run keeps
/// within the target from the hold's end on, the controller flag is obeyed.
#[test]
fn track_runs_on_a_parallel_scene() {
    let settings = scratch("settings.json");
    std::fs::write(
        &settings,
        r#"{"hold_s": 2.0, "duration_s": 1.0, "score_from_s": 2.0, "model_elements_per_section": 1}"#,
    )
    .unwrap();
    let out = scratch("track.json");
    let o = softrod(&[
        "track",
        "examples/parallel_track.json",
        "--trajectory",
        settings.to_str().unwrap(),
        "--controller",
        "ff",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["summary"]["controller"], "ff");
    // one sample per control instant after the first command (the planar
    // robot's loop: 3 s at 10 Hz)
    assert_eq!(v["summary"]["samples"], 30);
    assert_eq!(
        v["samples"][0]["pressures_pa"].as_array().unwrap().len(),
        18
    );
    // a payload schedule is the planar robot's: refused, naming the flag
    let o = softrod(&[
        "track",
        "examples/parallel_track.json",
        "--payload",
        settings.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--payload"));
    // a scene with a known platform load is refused, naming the field
    let o = softrod(&["track", "examples/parallel_robot.json"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("platform_force_n"));
    // an unknown settings field is named
    std::fs::write(&settings, r#"{"payload_kilos": 1}"#).unwrap();
    let o = softrod(&[
        "track",
        "examples/parallel_track.json",
        "--trajectory",
        settings.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("payload_kilos"));
    std::fs::remove_dir_all(out.parent().unwrap()).ok();
}

/// `softrod estimate` on the example scene with the plant's markers: the
/// 150 g payload within 5 g (the scene's description says 145 g).
#[test]
fn estimate_runs_on_a_parallel_scene() {
    let o = softrod(&[
        "estimate",
        "examples/parallel_estimate.json",
        "--markers",
        "examples/parallel_markers.json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let m = v["mass_kg"].as_f64().unwrap();
    assert!((m - 0.15).abs() < 0.005, "{m}");
}
