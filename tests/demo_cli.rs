//! The demo (`softrod` without a subcommand, issue 37 point 4) tells the
//! truth about what it ran. Its estimate is made from the committed
//! `examples/two_section_payload_markers.json`: the markers of a plant
//! that is not the estimator's model (`examples/two_section.json` at four
//! times its elements, `softrod::plant::SimulatedPlant` without parameter
//! errors) carrying a payload the estimator is not told about (a 20 g tip
//! mass and a uniform −0.5 N/m), seeded noise σ = 0.01 mm.
//! [`the_committed_markers_are_the_plants`] regenerates the file and checks
//! it; [`the_demo_s_commands_rerun_what_it_prints`] runs the commands the
//! demo prints and checks that they give what it printed, and that the
//! truth lies within a few σ of the estimate.
#![cfg(feature = "cli")]
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use serde_json::Value;
use softrod::plant::{Payload, PayloadKind, PayloadSchedule, Plant, PlantSettings, SimulatedPlant};
use softrod::scene::Scene;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");
const MARKERS: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/examples/two_section_payload_markers.json"
);
const SCENE: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/examples/two_section.json");
/// The payload: a tip mass (kg) and a uniform line load along gravity (N/m).
const TIP_MASS_KG: f64 = 0.02;
const UNIFORM_N_PER_M: f64 = 0.5;
const GRAVITY_M_PER_S2: f64 = 9.81;
const SIGMA_M: f64 = 1e-5;
/// The demo's command prefix.
const RUN: &str = "cargo run --release --features cli --";

#[path = "common/cli.rs"]
mod cli;
use cli::softrod;

/// The plant: the scene at four times its elements, no parameter errors,
/// no regulator lag, the payload from the start, noise σ (seed 1),
/// observed at the arc coordinates `s_m`.
fn plant(scene: &Scene, s_m: &[f64]) -> SimulatedPlant {
    let length = scene.robot().unwrap().length();
    let payload = |kind| Payload {
        kind,
        start_s: 0.0,
        end_s: None,
    };
    let settings = PlantSettings {
        mesh_factor: 4,
        ei_factor: 1.0,
        gain_factor: 1.0,
        ea_factor: 1.0,
        noise_sigma_m: SIGMA_M,
        seed: 1,
        regulator_time_constant_s: 0.0,
        payloads: PayloadSchedule {
            payloads: vec![
                payload(PayloadKind::PointMass {
                    mass_kg: TIP_MASS_KG,
                    s_m: length,
                }),
                payload(PayloadKind::Distributed {
                    mass_per_length_kg_per_m: UNIFORM_N_PER_M / GRAVITY_M_PER_S2,
                }),
            ],
        },
    };
    SimulatedPlant::new(scene, s_m, settings).unwrap()
}

fn scene() -> Scene {
    Scene::from_json(&std::fs::read_to_string(SCENE).unwrap()).unwrap()
}

/// The markers file: the scene's five markers (their arc coordinates on the
/// model) read on the plant in equilibrium with the payload, one frame of
/// the plant's own noisy observation.
fn plant_markers() -> Value {
    let scene = scene();
    let robot = scene.robot().unwrap();
    let s_m: Vec<f64> = scene
        .markers
        .iter()
        .map(|m| robot.node_arc()[m.node.unwrap()])
        .collect();
    assert_eq!(s_m.len(), 5);
    let mut plant = plant(&scene, &s_m);
    plant.command(&scene.pressures_pa).unwrap();
    let obs = plant.advance(0.1).unwrap().observation(&s_m).unwrap();
    serde_json::json!({
        "description": "examples/two_section.json's five markers (s = k L/5) on a plant of 4x its elements (softrod::plant::SimulatedPlant, no parameter errors) carrying a 20 g tip mass and a uniform -0.5 N/m; seeded noise 0.01 mm. Written by tests/demo_cli.rs (SOFTROD_WRITE_EXAMPLES=1).",
        "markers": obs.markers
    })
}

/// The committed file is the plant's markers (positions to 1e-12 m):
/// rewritten with `SOFTROD_WRITE_EXAMPLES=1`. The plant's noise is the
/// stated σ: the file is σ from the noise-free markers in RMS (within a
/// factor of 2, ten numbers).
#[test]
fn the_committed_markers_are_the_plants() {
    let want = plant_markers();
    if std::env::var_os("SOFTROD_WRITE_EXAMPLES").is_some() {
        std::fs::write(MARKERS, serde_json::to_string_pretty(&want).unwrap() + "\n").unwrap();
    }
    let got: Value = serde_json::from_str(&std::fs::read_to_string(MARKERS).unwrap()).unwrap();
    assert_eq!(got["description"], want["description"]);
    let markers = |v: &Value| v["markers"].as_array().unwrap().clone();
    assert_eq!(markers(&got).len(), markers(&want).len());
    for (g, w) in markers(&got).iter().zip(markers(&want)) {
        assert_eq!(g["s_m"], w["s_m"]);
        let (g, w) = (&g["position_m"], &w["position_m"]);
        assert_eq!(g.as_array().unwrap().len(), 2);
        for a in 0..2 {
            let (x, y) = (g[a].as_f64().unwrap(), w[a].as_f64().unwrap());
            assert!((x - y).abs() <= 1e-12, "{x} vs {y}");
        }
    }
    // the noise: against the noise-free plant
    let s_m: Vec<f64> = markers(&got)
        .iter()
        .map(|m| m["s_m"].as_f64().unwrap())
        .collect();
    let truth = plant(&scene(), &s_m).true_markers_m().unwrap();
    let sq: f64 = markers(&got)
        .iter()
        .zip(&truth)
        .map(|(m, t)| {
            (0..2)
                .map(|a| (m["position_m"][a].as_f64().unwrap() - t[a]).powi(2))
                .sum::<f64>()
        })
        .sum();
    let rms = (sq / 10.0).sqrt();
    assert!(
        rms > 0.5 * SIGMA_M && rms < 2.0 * SIGMA_M,
        "noise RMS {rms:e} m"
    );
}

/// The numbers of `text` (a sign, digits, a point, an exponent).
fn numbers(text: &str) -> Vec<f64> {
    text.split(|c: char| !(c.is_ascii_digit() || "+-.e".contains(c)))
        .filter_map(|t| t.parse().ok())
        .collect()
}

/// The text between `from` and the next `to` in `line`.
fn between<'a>(line: &'a str, from: &str, to: &str) -> &'a str {
    let start = line
        .find(from)
        .unwrap_or_else(|| panic!("no `{from}` in {line}"))
        + from.len();
    let end = line[start..].find(to).unwrap() + start;
    &line[start..end]
}

/// The demo's estimate: for each backend, its printed resultant and the
/// counts of its α search and iterations equal those of the record the
/// printed command writes (to the printed precision), the rule printed is
/// the record's, and the truth the demo prints (the payload of the
/// markers file) lies within 3σ of the estimate.
#[test]
fn the_demo_s_commands_rerun_what_it_prints() {
    let (code, out, err) = softrod(&[]);
    assert_eq!(code, 0, "{err}");
    assert!(
        !out.contains("`softrod "),
        "a command that cargo run does not install:\n{out}"
    );
    let lines: Vec<&str> = out.lines().collect();
    let truth_line = lines
        .iter()
        .find(|l| l.trim_start().starts_with("truth:"))
        .unwrap();
    let truth = numbers(between(truth_line, "resultant (", ")"));
    let want = [
        0.0,
        -UNIFORM_N_PER_M * 0.24 - TIP_MASS_KG * GRAVITY_M_PER_S2,
    ];
    for a in 0..2 {
        assert!(
            (truth[a] - want[a]).abs() <= 0.5e-4,
            "{truth:?} vs {want:?}"
        );
    }
    let mut checked = 0;
    for backend in ["newton", "sqp"] {
        let at = lines
            .iter()
            .position(|l| l.trim_start().starts_with(&format!("{backend} ")))
            .unwrap_or_else(|| panic!("no {backend} line:\n{out}"));
        let printed = numbers(between(lines[at], "resultant (", ")"));
        assert_eq!(printed.len(), 4, "{}", lines[at]);
        assert!(lines[at].contains("± 1 sigma"), "{}", lines[at]);
        let block = &lines[at..(at + 5).min(lines.len())];
        let alpha = block.iter().find(|l| l.contains("alpha_rule")).unwrap();
        let rerun = block.iter().find(|l| l.contains("rerun:")).unwrap();
        let cmd = rerun.split("rerun: ").nth(1).unwrap();
        let args: Vec<&str> = cmd
            .strip_prefix(RUN)
            .unwrap_or_else(|| panic!("not a cargo run command: {cmd}"))
            .split_whitespace()
            .collect();
        assert!(args.contains(&"--markers") && args.contains(&backend));
        let (code, _, err) = softrod(&args);
        assert_eq!(code, 0, "`{cmd}`: {err}");
        let file = args[args.iter().position(|a| *a == "--out").unwrap() + 1];
        let record: Value =
            serde_json::from_str(&std::fs::read_to_string(format!("{ROOT}/{file}")).unwrap())
                .unwrap();
        let res = &record["resultant"];
        for a in 0..2 {
            let f = res["force_n"][a].as_f64().unwrap();
            let sd = res["force_std_n"][a].as_f64().unwrap();
            assert!(
                (f - printed[2 * a]).abs() <= 0.5e-4 + 1e-12,
                "{backend}: force[{a}] {f} vs printed {}",
                printed[2 * a]
            );
            assert!(
                (sd - printed[2 * a + 1]).abs() <= 0.5e-4 + 1e-12,
                "{backend}: std[{a}] {sd} vs printed {}",
                printed[2 * a + 1]
            );
            assert!(
                (f - want[a]).abs() <= 3.0 * sd,
                "{backend}: force[{a}] {f} ± {sd}, truth {}",
                want[a]
            );
        }
        // the α rule and the counts printed are the record's
        let report = &record["report"];
        let search = &report["alpha_search"];
        assert!(
            alpha.contains(&format!("alpha_rule {}", search["rule"])),
            "{alpha} vs {search}"
        );
        let counts = numbers(between(alpha, "a search of ", " at the chosen"));
        assert_eq!(
            counts,
            vec![
                search["solves"].as_f64().unwrap(),
                search["iterations"].as_f64().unwrap(),
                report["iterations"].as_f64().unwrap()
            ],
            "{alpha}"
        );
        assert!(search["solves"].as_u64().unwrap() >= 2);
        checked += 1;
    }
    assert_eq!(checked, 2);
}
