//! The command line fails with a non-zero exit and exactly one line on
//! stderr, `softrod: error: ...`, for every bad invocation: no usage block,
//! no panic message, no backtrace (issue "Hardening", point 1).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::process::Command;

fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn temp_file(name: &str, text: &str) -> String {
    let path = std::env::temp_dir().join(format!("softrod-cli-{}-{name}", std::process::id()));
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn every_bad_invocation_is_one_line_and_a_non_zero_exit() {
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/two_section.json");
    let malformed = temp_file(
        "malformed.json",
        r#"{"robot": {"sections": [{"length_m": 0.1,"#,
    );
    let huge = temp_file(
        "huge.json",
        r#"{"robot": {"sections": [{"length_m": 0.1, "ea_n": 1, "ei_nm2": 1, "elements": 1000000000}]}}"#,
    );
    let cases: Vec<(&str, Vec<&str>, &str)> = vec![
        (
            "unknown flag",
            vec!["--bogus"],
            "unexpected argument '--bogus'",
        ),
        (
            "unknown subcommand",
            vec!["estimate-everything"],
            "unrecognized subcommand",
        ),
        ("missing scene", vec!["solve"], "<SCENE>"),
        (
            "missing file",
            vec!["solve", "/nonexistent/scene.json"],
            "cannot read /nonexistent/scene.json",
        ),
        (
            "malformed scene",
            vec!["solve", &malformed],
            "EOF while parsing",
        ),
        (
            "absurd element count",
            vec!["solve", &huge],
            "robot.sections[0].elements",
        ),
        (
            "NaN pressure",
            vec!["solve", example, "--pressures", "0,NaN,0,0"],
            "pressures_pa[1]",
        ),
        (
            "pressure out of bounds",
            vec!["solve", example, "--pressures", "0,0,0,1e9"],
            "pressures_pa[3]",
        ),
        (
            "too few pressures",
            vec!["solve", example, "--pressures", "1,2"],
            "pressures_pa",
        ),
        (
            "pressure not a number",
            vec!["solve", example, "--pressures", "1,two,3,4"],
            "two",
        ),
        (
            "unwritable output",
            vec!["solve", example, "--out", "/nonexistent/dir/out.json"],
            "cannot write /nonexistent/dir/out.json",
        ),
    ];
    for (what, args, needle) in cases {
        let (code, _, stderr) = run(&args);
        assert_ne!(code, 0, "{what}: exit 0");
        let lines: Vec<&str> = stderr.lines().collect();
        assert_eq!(lines.len(), 1, "{what}: stderr is not one line:\n{stderr}");
        assert!(lines[0].starts_with("softrod: error: "), "{what}: {stderr}");
        assert!(
            lines[0].contains(needle),
            "{what}: `{needle}` not in {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{what}: {stderr}");
        println!("{what:25} exit {code}: {}", lines[0]);
    }
}

/// `--pressures` takes negatives and spaces, in `solve` and in `estimate`,
/// and the pressures given are the ones the result is for.
#[test]
fn pressures_take_negatives_spaces_and_reach_estimate() {
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/two_section.json");
    for args in [
        vec!["solve", example, "--pressures", "5e3, 10e3 0,0"],
        vec!["solve", example, "--pressures=5e3,10e3,0,0"],
        vec!["estimate", example, "--pressures", "5e3 10e3 0 0"],
    ] {
        let (code, stdout, stderr) = run(&args);
        assert_eq!(code, 0, "{args:?}: {stderr}");
        let out: serde_json::Value = serde_json::from_str(&stdout).unwrap();
        let p: Vec<f64> = serde_json::from_value(out["pressures_pa"].clone()).unwrap();
        assert_eq!(p, vec![5e3, 10e3, 0.0, 0.0], "{args:?}");
    }
    // a negative pressure is read as a number (not as a flag) and checked
    // against the chamber's bounds, which this scene's chambers put at 0
    let mut messages = Vec::new();
    for sub in ["solve", "estimate"] {
        let (code, _, stderr) = run(&[sub, example, "--pressures", "-5e3, 0 0 0"]);
        assert_ne!(code, 0);
        assert!(
            stderr.contains("`pressures_pa[0]` = -5000: must lie in [0, 100000] Pa"),
            "{sub}: {stderr}"
        );
        messages.push(stderr);
    }
    // one wording for both subcommands (the bounds' fields named)
    assert_eq!(messages[0], messages[1]);
    assert!(messages[0].contains("pressure_min_pa"), "{}", messages[0]);
}

/// A solve that converges outside the model's validity (a −1e4 N tip force
/// pushes the 0.24 m robot back through its clamp) says so: a warning in the
/// JSON and one line per warning on stderr; a valid solve has none.
#[test]
fn a_result_outside_the_model_s_validity_carries_warnings() {
    let text = include_str!("../examples/two_section.json");
    let mut scene: serde_json::Value = serde_json::from_str(text).unwrap();
    scene["loads"] = serde_json::json!([{"type": "tip_force", "force_n": [-1e4, 0.0]}]);
    let path = temp_file("through_clamp.json", &scene.to_string());
    let (code, stdout, stderr) = run(&["solve", &path]);
    assert_eq!(code, 0, "{stderr}");
    let out: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    let kinds: Vec<&str> = out["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w["kind"].as_str().unwrap())
        .collect();
    assert_eq!(
        kinds,
        ["axial_strain", "behind_clamp"],
        "{}",
        out["warnings"]
    );
    // flipped through the clamp, the rod is stretched to x = −8 m (≈ 4600 %)
    assert!(out["warnings"][0]["strain"].as_f64().unwrap() > 10.0);
    assert_eq!(
        stderr
            .lines()
            .filter(|l| l.starts_with("softrod: warning: "))
            .count(),
        // the two validity warnings and the stability warning (the rod
        // flipped through the clamp is a saddle)
        3,
        "{stderr}"
    );
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/two_section.json");
    let (_, stdout, _) = run(&["solve", example]);
    let out: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(out["warnings"], serde_json::json!([]));
}

#[test]
fn help_version_and_a_good_solve_exit_zero() {
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/two_section.json");
    for args in [vec!["--help"], vec!["--version"], vec!["solve", example]] {
        let (code, stdout, stderr) = run(&args);
        assert_eq!(code, 0, "{args:?}: {stderr}");
        assert!(
            !stdout.is_empty() && stderr.is_empty(),
            "{args:?}: {stderr}"
        );
    }
}

/// The JSON reports carry a typed status (`{"converged": "<test>"}` or a
/// failure variant with its data), and an estimate that stops short is
/// written, with its status, under a non-zero exit and one line on stderr.
#[test]
fn json_reports_carry_a_typed_status() {
    let example = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/two_section.json");
    let (code, stdout, stderr) = run(&["solve", example]);
    assert_eq!(code, 0, "{stderr}");
    let out: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert!(
        out["report"]["status"]["converged"].is_string(),
        "{}",
        out["report"]
    );
    let (code, stdout, stderr) = run(&["estimate", example]);
    assert_eq!(code, 0, "{stderr}");
    let out: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert!(
        out["report"]["status"]["converged"].is_string(),
        "{}",
        out["report"]
    );
    // one Gauss-Newton step at a small alpha: the last iterate is written
    let mut scene: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(example).unwrap()).unwrap();
    scene["solver"]["estimator"] =
        serde_json::json!({"alpha": 1e-2, "max_iterations": 1, "statistical_tolerance": 0.0});
    let path = temp_file("one_iteration.json", &scene.to_string());
    let (code, stdout, stderr) = run(&["estimate", &path]);
    // exit code 2: the run finished, its record is written, the goal not met
    assert_eq!(code, 2, "{stdout}");
    let errors: Vec<&str> = stderr
        .lines()
        .filter(|l| l.starts_with("softrod: goal not met:"))
        .collect();
    assert_eq!(errors.len(), 1, "{stderr}");
    assert!(errors[0].contains("did not converge"), "{stderr}");
    let out: serde_json::Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(
        out["report"]["status"],
        serde_json::json!({"iteration_limit": {"iterations": 1}}),
        "{}",
        out["report"]
    );
    assert_eq!(out["status"], out["report"]["status"]);
    assert_eq!(out["outcome"], "goal_not_met");
}
