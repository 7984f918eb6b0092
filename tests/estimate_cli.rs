//! `softrod estimate` replays a recorded stream (issue 33, point 2): a
//! markers file `{"frames": [{"t_s": ..., "markers": [...]}, ...]}`, one
//! estimate per frame with the estimator kept warm, one record per frame
//! with its status. The committed example
//! `examples/two_section_payload_frames.json` is the robot at rest, then a
//! 20 g tip payload, observed on a plant that is not the estimator's model
//! (four times the elements); [`the_committed_stream_is_the_plants`]
//! regenerates it and checks the file against it.
#![cfg(feature = "cli")]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use serde_json::Value;
use softrod::estimate::MarkerObservation;
use softrod::loads::PointForce;
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

const EXAMPLE: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/examples/two_section_payload_frames.json"
);
const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/two_section.json");
/// The payload (N) at the tip from the second frame on.
const PAYLOAD_N: [f64; 2] = [0.0, -0.02 * 9.81];
/// Frame times (s); the payload acts from the second.
const TIMES_S: [f64; 4] = [0.0, 0.1, 0.2, 0.3];

#[path = "common/cli.rs"]
mod cli;
use cli::softrod as run;

/// The stream the example holds: `examples/two_section.json`'s robot at
/// four times its elements under its loads (at rest), then with the
/// payload, five markers at `k L / 5`, 0.01 mm seeded noise (seed = frame).
fn plant_stream() -> Value {
    let mut scene = Scene::from_json(&std::fs::read_to_string(SCENE).unwrap()).unwrap();
    for s in &mut scene.robot.sections {
        s.elements *= 4;
    }
    let robot = scene.robot().unwrap();
    let known = scene.loads().unwrap();
    let mut loaded = known.clone();
    loaded.point_forces.push(PointForce {
        s_m: robot.length(),
        force_n: PAYLOAD_N.to_vec(),
    });
    let solver = StaticSolver::default();
    let rest = solver.solve(&robot, &known, None).unwrap().q;
    let load = solver
        .solve(&robot, &loaded, Some(rest.as_slice()))
        .unwrap()
        .q;
    let frames: Vec<Value> = TIMES_S
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            let q = if k == 0 { &rest } else { &load };
            let markers: Vec<MarkerObservation> = (1..=5)
                .map(|m| {
                    let s = robot.length() * f64::from(m) / 5.0;
                    MarkerObservation::at_arc(s, robot.position_at(q.as_slice(), s).unwrap())
                })
                .collect();
            let obs = softrod::estimate::Observation { markers }.with_noise(1e-5, k as u64);
            serde_json::json!({"t_s": t, "markers": obs.markers})
        })
        .collect();
    serde_json::json!({
        "description": "examples/two_section.json observed on a plant of 4x its elements: at rest at t = 0, a 20 g tip payload from t = 0.1 s; five markers at k L/5, 0.01 mm seeded noise (seed = frame index). Written by tests/estimate_cli.rs (SOFTROD_WRITE_EXAMPLES=1).",
        "frames": frames
    })
}

/// The committed example is the plant's stream (positions to 1e-12 m):
/// rewritten with `SOFTROD_WRITE_EXAMPLES=1`.
#[test]
fn the_committed_stream_is_the_plants() {
    let want = plant_stream();
    if std::env::var_os("SOFTROD_WRITE_EXAMPLES").is_some() {
        std::fs::write(EXAMPLE, serde_json::to_string_pretty(&want).unwrap() + "\n").unwrap();
    }
    let got: Value = serde_json::from_str(&std::fs::read_to_string(EXAMPLE).unwrap()).unwrap();
    let frames = |v: &Value| v["frames"].as_array().unwrap().clone();
    assert_eq!(frames(&got).len(), TIMES_S.len());
    for (g, w) in frames(&got).iter().zip(frames(&want)) {
        assert_eq!(g["t_s"], w["t_s"]);
        for (gm, wm) in g["markers"]
            .as_array()
            .unwrap()
            .iter()
            .zip(w["markers"].as_array().unwrap())
        {
            assert_eq!(gm["s_m"], wm["s_m"]);
            for (a, b) in gm["position_m"]
                .as_array()
                .unwrap()
                .iter()
                .zip(wm["position_m"].as_array().unwrap())
            {
                assert!((a.as_f64().unwrap() - b.as_f64().unwrap()).abs() <= 1e-12);
            }
        }
    }
}

/// The replay: exit 0, one record per frame with its time and a converged
/// status, the estimator warm from the second frame on (no α search
/// there unless the fit fails), and the resultant within
/// `max(4 σ_reported, 10 % |F|, 5 mN)` of the truth: zero at rest, the
/// payload after (the plant is a finer mesh than the model). Before this
/// the file was refused ("not a markers file").
#[test]
fn estimate_replays_a_recorded_stream() {
    for backend in ["newton", "sqp"] {
        let (code, out, err) = run(&[
            "estimate",
            SCENE,
            "--markers",
            EXAMPLE,
            "--backend",
            backend,
        ]);
        assert_eq!(code, 0, "{backend}: {err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        let frames = v["frames"].as_array().unwrap();
        assert_eq!(v["n_frames"], TIMES_S.len());
        assert_eq!(frames.len(), TIMES_S.len());
        assert_eq!(v["not_converged"].as_array().unwrap().len(), 0);
        assert_eq!(
            err.lines().filter(|l| l.contains("frame ")).count(),
            TIMES_S.len(),
            "{err}"
        );
        for (k, f) in frames.iter().enumerate() {
            assert_eq!(f["t_s"].as_f64().unwrap(), TIMES_S[k]);
            assert!(
                f["status"].get("converged").is_some(),
                "{backend} frame {k}: {}",
                f["status"]
            );
            assert_eq!(f["status"], f["estimate"]["report"]["status"]);
            let truth = if k == 0 { [0.0; 2] } else { PAYLOAD_N };
            let size = (truth[0].powi(2) + truth[1].powi(2)).sqrt();
            let res = &f["estimate"]["resultant"];
            for a in 0..2 {
                let got = res["force_n"][a].as_f64().unwrap();
                let sd = res["force_std_n"][a].as_f64().unwrap();
                let tol = (4.0 * sd).max(0.1 * size).max(5e-3);
                assert!(
                    (got - truth[a]).abs() <= tol,
                    "{backend} frame {k}: force[{a}] {got} vs {} (tol {tol})",
                    truth[a]
                );
            }
        }
    }
}

/// A malformed frame is refused with its path in the file; an empty
/// stream and decreasing times are refused; a single-observation file
/// still gives one record (not a stream).
#[test]
fn stream_files_are_checked_and_single_files_still_work() {
    let dir = std::env::temp_dir();
    let write = |name: &str, text: &str| {
        let p = dir.join(format!(
            "softrod-estimate-cli-{}-{name}",
            std::process::id()
        ));
        std::fs::write(&p, text).unwrap();
        p.to_string_lossy().into_owned()
    };
    let bad = write(
        "bad.json",
        r#"{"frames": [{"t_s": 0, "markers": [{"s_m": 0.24, "position_m": [0.2, 0.0]}]},
                       {"t_s": 1, "markers": [{"s_m": 0.24, "position": [0.2, 0.0]}]}]}"#,
    );
    let (code, _, err) = run(&["estimate", SCENE, "--markers", &bad]);
    assert_ne!(code, 0);
    assert!(err.contains("frames[1].markers[0]"), "{err}");
    let empty = write("empty.json", r#"{"frames": []}"#);
    let (code, _, err) = run(&["estimate", SCENE, "--markers", &empty]);
    assert!(code != 0 && err.contains("empty"), "{err}");
    let back = write(
        "back.json",
        r#"{"frames": [{"t_s": 1, "markers": [{"s_m": 0.24, "position_m": [0.2, 0.0]}]},
                       {"t_s": 0, "markers": [{"s_m": 0.24, "position_m": [0.2, 0.0]}]}]}"#,
    );
    let (code, _, err) = run(&["estimate", SCENE, "--markers", &back]);
    assert!(code != 0 && err.contains("frames[1].t_s"), "{err}");
    // the first frame alone, as a single observation
    let v: Value = serde_json::from_str(&std::fs::read_to_string(EXAMPLE).unwrap()).unwrap();
    let single = write(
        "single.json",
        &serde_json::json!({"markers": v["frames"][0]["markers"]}).to_string(),
    );
    let (code, out, err) = run(&["estimate", SCENE, "--markers", &single]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert!(v.get("frames").is_none() && v["report"]["status"].get("converged").is_some());
}
