//! `softrod plot RESULT.json` (issue 37, point 2): a picture of the records
//! of `solve` and `estimate` (planar, spatial, 3-D), of a parallel robot's
//! `solve`, each through the layout check (no text off the canvas or over
//! another, no data outside its axes); the fields the picture reads are
//! checked against the estimator itself; unknown records and formats are
//! refused naming what was read.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};

use serde_json::Value;
use softrod::report::result_plot::plot_result;
use softrod::scene::Scene;
use softrod::scene::markers::MarkersFile;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

#[path = "common/cli.rs"]
mod cli;
use cli::softrod as run3;

/// Exit code and standard error.
fn run(args: &[&str]) -> (i32, String) {
    let (code, _, stderr) = run3(args);
    (code, stderr)
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("softrod-plot-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn record(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Draws `json` as PNG and SVG through the library and checks the files
/// and the layout; returns the panels.
fn plot_both(json: &Path, want_record: &str) -> Vec<String> {
    let mut panels = None;
    for ext in ["png", "svg"] {
        let out = json.with_extension(ext);
        let s = plot_result(json, Some(&out)).unwrap();
        assert_eq!(s.record, want_record);
        assert!(s.layout.is_empty(), "{}: {:#?}", out.display(), s.layout);
        let bytes = std::fs::read(&out).unwrap();
        match ext {
            "png" => assert_eq!(&bytes[1..4], b"PNG"),
            _ => assert!(String::from_utf8_lossy(&bytes).contains("<svg")),
        }
        panels = Some(s.panels);
    }
    panels.unwrap()
}

#[test]
fn every_robot_record_is_drawn_with_a_clean_layout() {
    let d = dir("kinds");
    let cases: [(&[&str], &str, &[&str]); 5] = [
        (
            &["solve", "examples/two_section.json"],
            "solve planar_cable",
            &["x–y"],
        ),
        (
            &["estimate", "examples/two_section.json"],
            "estimate planar_cable",
            &["x–y", "load", "residuals"],
        ),
        (
            &["solve", "examples/spatial_cantilever.json"],
            "solve spatial_cable",
            &["x–y", "x–z", "y–z"],
        ),
        (
            &[
                "estimate",
                "examples/ancf3d_cantilever.json",
                "--markers",
                "examples/ancf3d_cantilever_markers.json",
            ],
            "estimate ancf3d",
            &["x–y", "x–z", "y–z", "load", "residuals"],
        ),
        (
            &["solve", "examples/parallel_robot.json"],
            "solve parallel",
            &["x–y", "x–z", "y–z"],
        ),
    ];
    for (k, (args, kind, panels)) in cases.iter().enumerate() {
        let json = d.join(format!("{k}.json"));
        let mut a: Vec<&str> = args.to_vec();
        let out = json.to_str().unwrap();
        a.extend(["--out", out]);
        let (code, err) = run(&a);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert_eq!(plot_both(&json, kind), *panels, "{args:?}");
    }
    // the command line: the default output next to the record
    let json = d.join("0.json");
    let _ = std::fs::remove_file(d.join("0.png"));
    let (code, said, err) = run3(&["plot", json.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    assert!(said.contains("solve planar_cable: x–y"), "{said}");
    assert!(d.join("0.png").exists());
    assert!(!err.contains("layout"), "{err}");
}

// the markers and the load band the picture draws, against the estimator
// run here on the same observation: fitted − measured is the record's own
// residual, and at a node the band is the load parameter's 1σ (there
// w(s_i) = F_i, (8))
#[test]
fn the_drawn_fields_are_the_estimators() {
    let d = dir("fields");
    let synth = d.join("synth.json");
    let (code, err) = run(&[
        "estimate",
        "examples/two_section.json",
        "--out",
        synth.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let r = record(&synth);
    let markers = r["markers"].as_array().unwrap();
    assert_eq!(markers.len(), 5);
    let residuals: Vec<f64> = r["marker_residuals_m"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    for (i, m) in markers.iter().enumerate() {
        for a in 0..2 {
            let fit = m["fitted_position_m"][a].as_f64().unwrap();
            let meas = m["measured_position_m"][a].as_f64().unwrap();
            assert!(
                ((fit - meas) - residuals[2 * i + a]).abs() < 1e-12,
                "marker {i} axis {a}"
            );
        }
    }
    // the same observation as a markers file, estimated here and by the CLI
    let file = serde_json::json!({
        "markers": markers.iter().map(|m| serde_json::json!({
            "node": m["node"], "position_m": m["measured_position_m"]
        })).collect::<Vec<_>>()
    });
    let mpath = d.join("markers.json");
    std::fs::write(&mpath, file.to_string()).unwrap();
    let out = d.join("est.json");
    let (code, err) = run(&[
        "estimate",
        "examples/two_section.json",
        "--markers",
        mpath.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let r = record(&out);
    let scene = Scene::from_file(Path::new(&format!("{ROOT}/examples/two_section.json"))).unwrap();
    let robot = scene.robot().unwrap();
    let obs = MarkersFile::from_file(&mpath).unwrap().observations();
    let e = scene
        .estimator_settings()
        .unwrap()
        .build_for(&robot, &scene.loads().unwrap())
        .unwrap()
        .step(&obs[0].1)
        .unwrap();
    let std_f = e.std_f();
    let node_s = robot.node_arc();
    let mut checked = 0;
    for sample in r["load"].as_array().unwrap() {
        let s = sample["s"].as_f64().unwrap();
        let Some(i) = node_s.iter().position(|x| (x - s).abs() < 1e-12) else {
            continue;
        };
        for a in 0..2 {
            let band = sample["w_std"][a].as_f64().unwrap();
            let want = std_f[i * 4 + a];
            assert!(
                (band - want).abs() <= 1e-9 * want.abs().max(1e-30),
                "node {i} axis {a}: {band} vs {want}"
            );
            // the base node carries no load: there the band is zero too
            assert_eq!(want > 0.0, i > 0, "node {i}");
        }
        checked += 1;
    }
    assert!(checked >= 4, "{checked} grid points on nodes");
}

#[test]
fn records_without_a_picture_are_refused_naming_what_was_read() {
    let d = dir("refused");
    let track = d.join("track.json");
    std::fs::write(
        &track,
        r#"{"format_version": "1", "command": "track", "scene": "x", "scene_kind": "planar_cable"}"#,
    )
    .unwrap();
    let (code, err) = run(&["plot", track.to_str().unwrap()]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains("command `track`") && err.contains("scene_kind `planar_cable`"),
        "{err}"
    );
    let other = d.join("other.json");
    std::fs::write(&other, r#"{"nodes": []}"#).unwrap();
    let e = plot_result(&other, None).unwrap_err();
    assert!(
        matches!(&e, softrod::Error::UnsupportedRecord { format_version, .. } if format_version == "(none)"),
        "{e}"
    );
    // a solve record whose nodes are not numbers: the field is named
    let bad = d.join("bad.json");
    std::fs::write(
        &bad,
        r#"{"format_version": "1", "command": "solve", "scene": "x", "scene_kind": "planar_cable", "nodes": [{"position_m": ["a", 0]}]}"#,
    )
    .unwrap();
    let e = plot_result(&bad, None).unwrap_err();
    assert!(e.to_string().contains("nodes[0].position_m"), "{e}");
    let e = plot_result(&bad, Some(Path::new("x.jpg"))).unwrap_err();
    assert_eq!(e.field(), Some("out"), "{e}");
}
