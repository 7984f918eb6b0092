//! softrod's in-process times for `validation/bench_peers.py`, as JSON on
//! standard output.
//!
//! `cargo run --release --features report --example peer_times [REPO_ROOT [CASE [ELEMENTS]]]`
//!
//! With `CASE` (and optionally `ELEMENTS`), only the forward solves of that
//! case (at that size) are timed and printed, no estimates: one cell to
//! profile, e.g. `valgrind --tool=callgrind
//! ./target/release/examples/peer_times . uniform_small 16`.
//!
//! - `forward`: the cold static solve (`StaticSolver::solve` from the
//!   straight rod) of every exudyn cantilever reference case
//!   (`reference/exudyn_<case>.json`: its sections, clamp of all four base
//!   coordinates, 3 bending Gauss points, its loads) at 4–128 elements:
//!   the same discretization exudyn's `SolveStatic` is timed on.
//! - `estimate`: the problem (25) on three of the report's references (20
//!   elements, 5 markers at `L k / 5` read off exudyn's 128-element shape
//!   with 0.01 mm seeded noise, no known loads, the distributed unknown
//!   load): `α` by the estimator's default rule (once; the evidence), then the first
//!   estimate at that `α` by both backends from a fresh estimator (the time
//!   a peer is compared with), with the data a peer needs to pose the same
//!   problem (markers, `σ`, `α`) and softrod's answer to compare with.
//!
//! Each time is the median of repeated runs (at least 3, until 0.3 s;
//! exactly `PEER_TIMES_RUNS` runs when that variable is set).
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::time::Instant;

use serde_json::{Value, json};
use softrod::assembly::Clamp;
use softrod::estimate::{Backend, EstimatorSettings};
use softrod::loads::Loads;
use softrod::report::reference::Reference;
use softrod::report::sweep;
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

/// The exudyn reference cases: the one list the static solver's tests and
/// benches use.
#[path = "../tests/common/statics_cases.rs"]
mod statics_cases;
use statics_cases::EXUDYN as CASES;

const ELEMENTS: [usize; 6] = [4, 8, 16, 32, 64, 128];
const ESTIMATE_REFERENCES: [&str; 3] = [
    "exudyn_family_uniform_1",
    "exudyn_uniform_large",
    "exudyn_gaussian_large",
];

/// Median wall time (s) of `run`, repeated at least 3 times and until 0.3 s
/// (exactly `PEER_TIMES_RUNS` times when that is set: a fixed count for
/// callgrind).
fn median_time(mut run: impl FnMut()) -> (f64, usize) {
    let fixed: Option<usize> = std::env::var("PEER_TIMES_RUNS")
        .ok()
        .and_then(|v| v.parse().ok());
    let mut times = Vec::new();
    let start = Instant::now();
    while match fixed {
        Some(k) => times.len() < k,
        None => times.len() < 3 || (start.elapsed().as_secs_f64() < 0.3 && times.len() < 1000),
    } {
        let t = Instant::now();
        run();
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    (
        times.get(times.len() / 2).copied().unwrap_or(0.0),
        times.len(),
    )
}

/// A scene with the reference's sections, base and loads (as
/// `tests/references.rs` builds it).
fn scene(r: &Value, elements: usize) -> Scene {
    let p = &r["params"];
    let sections = p["sections"].as_array().unwrap();
    let mut text = json!({
        "robot": {
            "sections": sections.iter().map(|s| json!({
                "length_m": s["length_m"], "ea_n": s["ea_n"], "ei_nm2": s["ei_nm2"],
                "elements": elements / sections.len(),
            })).collect::<Vec<_>>(),
            "bending_gauss_points": 3,
        },
        "base": p["base"],
        "gravity_m_per_s2": [0.0, 0.0],
    });
    text["loads"] = p["loads"].clone();
    let mut s: Scene = serde_json::from_value(text).unwrap();
    s.base.clamp = Clamp::Full;
    s.validate().unwrap();
    s
}

fn forward(root: &str, only_case: Option<&str>, only_n: Option<usize>) -> Vec<Value> {
    let mut out = Vec::new();
    for case in CASES {
        if only_case.is_some_and(|c| c != case) {
            continue;
        }
        let path = format!("{root}/reference/exudyn_{case}.json");
        let r: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
        for n in ELEMENTS {
            if only_n.is_some_and(|m| m != n) {
                continue;
            }
            let s = scene(&r, n);
            let robot = s.robot().unwrap();
            let loads = s.loads().unwrap();
            let solver = StaticSolver::default();
            let first = solver.solve(&robot, &loads, None);
            let (converged, iterations, tip) = match &first {
                Ok(eq) => (
                    eq.report.status.is_converged(),
                    eq.report.iterations,
                    eq.q.as_slice()[eq.q.len() - 4..eq.q.len() - 2].to_vec(),
                ),
                Err(_) => (false, 0, vec![]),
            };
            let (median_s, runs) = median_time(|| {
                let _ = std::hint::black_box(solver.solve(&robot, &loads, None));
            });
            out.push(json!({
                "case": case, "elements": n, "converged": converged,
                "newton_iterations": iterations, "tip_m": tip,
                "median_s": median_s, "runs": runs,
            }));
        }
    }
    out
}

fn estimate() -> Vec<Value> {
    let sigma = 1e-5;
    let n = 20;
    let mut out = Vec::new();
    for name in ESTIMATE_REFERENCES {
        let r = Reference::embedded(name).unwrap();
        let robot = sweep::model_robot(&r, n).unwrap();
        let arcs = sweep::marker_arcs(r.length_m, 5);
        let obs = sweep::observe(&r, arcs.as_slice(), sigma, 7);
        let base = EstimatorSettings {
            noise_sigma_m: sigma,
            ..EstimatorSettings::default()
        };
        let alpha = {
            let mut est = softrod::estimate::EstimatorSettings {
                backend: Backend::Newton,
                ..base.clone()
            }
            .build_for(&robot, &Loads::default())
            .unwrap();
            est.step(&obs).unwrap().report.alpha
        };
        let settings = EstimatorSettings {
            alpha: Some(alpha),
            ..base
        };
        let mut backends = serde_json::Map::new();
        for backend in [Backend::Newton, Backend::Sqp] {
            let build = || {
                softrod::estimate::EstimatorSettings {
                    backend,
                    ..settings.clone()
                }
                .build_for(&robot, &Loads::default())
                .unwrap()
            };
            let e = build().step(&obs).unwrap();
            let (median_s, runs) = median_time(|| {
                let mut est = build();
                let _ = std::hint::black_box(est.step(&obs));
            });
            backends.insert(
                backend.name().into(),
                json!({
                    "median_s": median_s, "runs": runs,
                    "converged": e.report.status.is_converged(),
                    "iterations": e.report.iterations,
                    "objective": e.report.objective,
                    "f": e.f.as_slice(), "q": e.q.as_slice(),
                }),
            );
        }
        out.push(json!({
            "reference": name,
            "sections": r.sections.iter().map(|s| json!({
                "length_m": s.length_m, "ea_n": s.ea_n, "ei_nm2": s.ei_nm2,
            })).collect::<Vec<_>>(),
            "elements": n,
            "clamp": "all four base coordinates",
            "bending_gauss_points": 3,
            "axial_gauss_points": 5,
            "markers": obs.markers.iter().map(|m| json!({
                "s_m": m.s_m, "position_m": m.position_m,
            })).collect::<Vec<_>>(),
            "noise_sigma_m": sigma,
            "alpha": alpha,
            "penalty": "alpha * F^T B F, B = int S^T S dX (the distributed load field)",
            "backends": backends,
        }));
    }
    out
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let root = args.get(1).map_or(".", String::as_str);
    let only_case = args.get(2).map(String::as_str);
    let only_n = args
        .get(3)
        .map(|n| n.parse::<usize>().expect("ELEMENTS: a number"));
    let doc = if only_case.is_some() {
        json!({
            "generator": "examples/peer_times.rs",
            "softrod": env!("CARGO_PKG_VERSION"),
            "forward": forward(root, only_case, only_n),
        })
    } else {
        json!({
            "generator": "examples/peer_times.rs",
            "softrod": env!("CARGO_PKG_VERSION"),
            "forward": forward(root, None, None),
            "estimate": estimate(),
        })
    };
    println!("{}", serde_json::to_string_pretty(&doc).unwrap());
}
