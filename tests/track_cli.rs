//! `softrod track`: a run with the example files writes the time series and
//! the summary; every bad input is one error line naming the field as
//! written in its file.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

fn ex(name: &str) -> String {
    format!("{}/examples/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[path = "common/cli.rs"]
mod cli;
use cli::softrod as run;

fn temp_file(name: &str, text: &str) -> String {
    let path = std::env::temp_dir().join(format!("softrod-track-{}-{name}", std::process::id()));
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn track_writes_the_time_series_and_the_updater_beats_feedforward() {
    let scene = ex("track_scene.json");
    let out = std::env::temp_dir().join(format!("softrod-track-{}-out.json", std::process::id()));
    let out = out.to_string_lossy().into_owned();
    let mut means = vec![];
    for controller in ["ff", "ff_updater"] {
        let (code, _, err) = run(&[
            "track",
            &scene,
            "--trajectory",
            &ex("trajectory_circle.json"),
            "--payload",
            &ex("payload_tip.json"),
            "--controller",
            controller,
            "--out",
            &out,
        ]);
        assert_eq!(code, 0, "{err}");
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        let samples = v["samples"].as_array().unwrap();
        assert_eq!(samples.len(), 540); // 18 s at 30 Hz
        let s = &samples[300];
        for key in [
            "time_s",
            "desired_m",
            "actual_m",
            "measured_m",
            "error_m",
            "payload_kg",
            "estimated_load_n",
            "pressures_pa",
            "step_time_s",
            "ik",
            "estimate",
        ] {
            assert!(!s[key].is_null(), "sample without {key}: {s}");
        }
        assert_eq!(s["payload_kg"].as_f64().unwrap(), 0.02);
        let summary = &v["summary"];
        assert_eq!(summary["samples"].as_u64().unwrap(), 540);
        assert_eq!(summary["plant"]["ei_factor"].as_f64().unwrap(), 1.15);
        means.push(summary["mean_error_m"].as_f64().unwrap());
        if controller == "ff_updater" {
            assert_eq!(s["estimate"]["estimate"], "converged");
            assert_eq!(s["estimated_load_n"].as_array().unwrap().len(), 2);
        }
    }
    println!("mean error: ff {} m, ff_updater {} m", means[0], means[1]);
    assert!(means[0] > 5e-3, "feedforward {}", means[0]);
    assert!(means[1] < 0.3e-3, "with the updater {}", means[1]);
}

#[test]
fn bad_track_input_names_the_field() {
    let scene = ex("track_scene.json");
    let traj = |t: &str| format!(r#"{{"trajectory": {t}}}"#);
    let circle =
        r#"{"kind": "circle", "radius_m": 0.005, "period_s": 15, "duration_s": 1, "hold_s": 0}"#;
    let cases: Vec<(&str, String, Option<String>, &str)> = vec![
        (
            "NaN point",
            traj(r#"{"kind": "samples", "times_s": [0, 1], "points_m": [[0.19, 0.12], [null, 0.12]]}"#),
            None,
            "trajectory.points_m[1][0]",
        ),
        (
            "out of reach",
            traj(r#"{"kind": "samples", "times_s": [0, 1], "points_m": [[0.19, 0.12], [0.5, 0.0]]}"#),
            None,
            "trajectory.points_m[1]",
        ),
        (
            "out of reach inside the length (the bounds)",
            traj(r#"{"kind": "samples", "times_s": [0, 1], "points_m": [[0.19, 0.12], [0.03, 0.01]]}"#),
            None,
            "trajectory.points_m",
        ),
        (
            "circle out of reach",
            traj(r#"{"kind": "circle", "radius_m": 0.2, "period_s": 15, "duration_s": 15}"#),
            None,
            "trajectory.radius_m",
        ),
        (
            "negative radius",
            traj(r#"{"kind": "circle", "radius_m": -0.005, "period_s": 15, "duration_s": 15}"#),
            None,
            "trajectory.radius_m",
        ),
        (
            "empty trajectory",
            traj(r#"{"kind": "samples", "times_s": [], "points_m": []}"#),
            None,
            "trajectory.times_s",
        ),
        (
            "time going backwards",
            traj(r#"{"kind": "samples", "times_s": [0, 2, 1], "points_m": [[0.19, 0.12], [0.19, 0.12], [0.19, 0.12]]}"#),
            None,
            "trajectory.times_s[2]",
        ),
        (
            "control rate 0",
            format!(r#"{{"trajectory": {circle}, "loop": {{"control_rate_hz": 0}}}}"#),
            None,
            "loop.control_rate_hz",
        ),
        (
            "control rate above 10 kHz",
            format!(r#"{{"trajectory": {circle}, "loop": {{"control_rate_hz": 20000}}}}"#),
            None,
            "loop.control_rate_hz",
        ),
        (
            "gain 0",
            format!(r#"{{"trajectory": {circle}, "loop": {{"gains": {{"k_p_per_s": 0}}}}}}"#),
            None,
            "loop.gains.k_p_per_s",
        ),
        (
            "negative integral gain",
            format!(r#"{{"trajectory": {circle}, "loop": {{"gains": {{"k_i_per_s2": -4}}}}}}"#),
            None,
            "loop.gains.k_i_per_s2",
        ),
        (
            "pressure schedule outside the bounds",
            traj(r#"{"kind": "pressures", "times_s": [0, 1], "pressures_pa": [[45e3, 0, 45e3, 0], [150e3, 0, 45e3, 0]]}"#),
            None,
            "trajectory.pressures_pa[1][0]",
        ),
        (
            "negative payload mass",
            traj(circle),
            Some(r#"{"payloads": [{"kind": "point_mass", "mass_kg": -0.02, "s_m": 0.24}]}"#.into()),
            "payloads[0].mass_kg",
        ),
        (
            "payload time going backwards",
            traj(circle),
            Some(r#"{"payloads": [{"kind": "point_mass", "mass_kg": 0.02, "s_m": 0.24, "start_s": 2, "end_s": 1}]}"#.into()),
            "payloads[0].end_s",
        ),
        (
            "unknown payload field",
            traj(circle),
            Some(r#"{"payloads": [{"kind": "point_mass", "mass_kg": 0.02, "s_m": 0.24, "colour": 1}]}"#.into()),
            "payloads[0]",
        ),
        (
            "trajectory shorter than one control interval",
            traj(r#"{"kind": "circle", "radius_m": 0.005, "period_s": 15, "duration_s": 0, "hold_s": 0}"#),
            None,
            "trajectory.times_s",
        ),
        (
            "negative duration",
            traj(r#"{"kind": "line", "from_m": [0.19, 0.12], "to_m": [0.195, 0.125], "period_s": 15, "duration_s": -1}"#),
            None,
            "trajectory.duration_s",
        ),
        (
            "period 0",
            traj(r#"{"kind": "figure_eight", "size_m": 0.005, "period_s": 0, "duration_s": 15}"#),
            None,
            "trajectory.period_s",
        ),
        (
            "NaN centre (null)",
            traj(r#"{"kind": "circle", "center_m": [null, 0.12], "radius_m": 0.005, "period_s": 15, "duration_s": 15}"#),
            None,
            "trajectory.center_m[0]",
        ),
        (
            "watchdog 0",
            format!(r#"{{"trajectory": {circle}, "loop": {{"abort_error_m": 0}}}}"#),
            None,
            "loop.abort_error_m",
        ),
        (
            "negative distributed payload",
            traj(circle),
            Some(r#"{"payloads": [{"kind": "distributed", "mass_per_length_kg_per_m": -0.1}]}"#.into()),
            "payloads[0].mass_per_length_kg_per_m",
        ),
        (
            "payload starting before 0",
            traj(circle),
            Some(r#"{"payloads": [{"kind": "point_mass", "mass_kg": 0.02, "s_m": 0.24, "start_s": -1}]}"#.into()),
            "payloads[0].start_s",
        ),
        (
            "sliding speed 0",
            traj(circle),
            Some(r#"{"payloads": [{"kind": "sliding", "mass_kg": 0.02, "from_s_m": 0.1, "to_s_m": 0.24, "speed_m_per_s": 0}]}"#.into()),
            "payloads[0].speed_m_per_s",
        ),
        (
            "plant factor",
            format!(r#"{{"trajectory": {circle}, "plant": {{"ei_factor": -1}}}}"#),
            None,
            "plant.ei_factor",
        ),
    ];
    for (i, (what, t, p, field)) in cases.iter().enumerate() {
        let tf = temp_file(&format!("t{i}.json"), t);
        let mut args = vec!["track", scene.as_str(), "--trajectory", tf.as_str()];
        let pf;
        if let Some(p) = p {
            pf = temp_file(&format!("p{i}.json"), p);
            args.extend(["--payload", pf.as_str()]);
        }
        let (code, out, err) = run(&args);
        assert_eq!(code, 1, "{what}: {err}");
        assert!(out.is_empty(), "{what}: wrote {out}");
        assert_eq!(err.lines().count(), 1, "{what}: {err}");
        assert!(
            err.starts_with("softrod: error:") && err.contains(&format!("`{field}")),
            "{what}: expected the field `{field}`: {err}"
        );
    }
}
