//! Contact localization sweep on the five-section robot (5 × 93 mm), the
//! plant not the model (twice the mesh, EI +15 %, gain −10 %, EA −5 %,
//! σ = 0.05 mm, 20 frames averaged by default): contact positions × loads (how far the
//! disk reaches into the contact-free shape) × marker counts, both methods:
//! the paper's peak of the estimated load minus the virtual payload, and the
//! point-force search on the calibrated model.
//!
//! Run: `cargo run --release --features cli --example avoid_localization [OUT.json [FRAMES [MARKERS…]]]
//! [--alpha=evidence|discrepancy]` (prints the table; writes every case as
//! JSON if a path is given; FRAMES marker frames averaged per measurement,
//! default 20; marker counts, default 4 6 11; the estimators' α rule,
//! default `softrod::touch::ALPHA_RULE`).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::plant::PlantSettings;
use softrod::report::touch::{LocalizationCase, run_localization};

fn main() {
    let mut alpha_rule = softrod::touch::ALPHA_RULE;
    let args: Vec<String> = std::env::args()
        .filter(|a| match a.strip_prefix("--alpha=") {
            Some(v) => {
                alpha_rule = serde_json::from_str(&format!("\"{v}\"")).expect("an α rule");
                false
            }
            None => true,
        })
        .collect();
    let out = args.get(1).filter(|a| a.as_str() != "-").cloned();
    let frames: usize = args
        .get(2)
        .map_or(20, |a| a.parse().expect("FRAMES: a count"));
    let counts: Vec<usize> = if args.len() > 3 {
        args[3..]
            .iter()
            .map(|a| a.parse().expect("MARKERS: a count"))
            .collect()
    } else {
        vec![4, 6, 11]
    };
    println!("{frames} frames averaged per measurement, α rule {alpha_rule:?}");
    let mut results = Vec::new();
    println!(
        "markers  s_c(m)  depth(mm)  true_s(m)  |f|(N)  | peak: err(mm) ferr(N) | point: err(mm) ferr(N)"
    );
    for &n_markers in &counts {
        let mut worst = (0.0f64, 0.0f64);
        let mut sum = (0.0, 0.0);
        let mut count = 0;
        for s in [0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45] {
            for depth in [0.005, 0.01, 0.02] {
                let case = LocalizationCase {
                    frames,
                    alpha_rule,
                    ..LocalizationCase::new(s, depth, n_markers, 1)
                };
                match run_localization(&case, 4, &PlantSettings::default()) {
                    Ok(r) => {
                        let (a, b) = r.location_errors_m();
                        let (fa, fb) = r.force_errors_n();
                        let f = r.true_force_n[0].hypot(r.true_force_n[1]);
                        println!(
                            "{n_markers:7}  {s:6.3}  {:9.0}  {:9.4}  {f:6.4}  | {:13.1} {fa:7.4} | {:14.1} {fb:7.4}",
                            depth * 1e3,
                            r.true_s_m,
                            a * 1e3,
                            b * 1e3
                        );
                        worst = (worst.0.max(a), worst.1.max(b));
                        sum = (sum.0 + a, sum.1 + b);
                        count += 1;
                        results.push(r);
                    }
                    Err(e) => println!("{n_markers:7}  {s:6.3}  {:9.0}  skipped: {e}", depth * 1e3),
                }
            }
        }
        println!(
            "{n_markers} markers, {count} cases: peak mean {:.1} mm, max {:.1} mm; point mean {:.1} mm, max {:.1} mm",
            sum.0 / count as f64 * 1e3,
            worst.0 * 1e3,
            sum.1 / count as f64 * 1e3,
            worst.1 * 1e3
        );
    }
    if let Some(path) = out {
        std::fs::write(&path, serde_json::to_string_pretty(&results).unwrap()).unwrap();
        println!("wrote {path}");
    }
}
