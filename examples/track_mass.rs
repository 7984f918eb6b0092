//! Payload-mass estimation against the simulated plant (the paper's Fig. 8):
//! a mass of 0-200 g at the tip of the two-section robot in three
//! configurations, read off the end effector's displacement with the
//! concentrated-load model (32)-(35) (see `softrod::control::MassEstimator`).
//!
//! Run: `cargo run --release --features cli --example track_mass` (prints the table for the
//! matched and the relative reference, calibrated and raw).
//!
//! Measured (seed 1, calibration 150 g straight with seed 99, 10 frames per
//! state; mean absolute error over 0, 20, ..., 200 g): matched reference
//! 0.24 / 0.91 / 1.29 g (straight / S / curled) with the scale 1.140, raw
//! (scale 1) 12.5 / 13.1 / 13.4 g, the plant's EI +15 % (masses come out
//! 1/1.15 light). The relative reference at the commanded pressures:
//! 0.20 / 0.69 / 20.2 g (curled fails: the plant, 10 % weaker in actuation,
//! is less curled than the model, and the compliance differs there).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::control::{MassReference, WeighingExperiment};
use softrod::scene::Scene;

fn main() -> softrod::Result<()> {
    for reference in [MassReference::Matched, MassReference::Relative] {
        let mut e = WeighingExperiment::paper_like(Scene::two_section());
        e.settings.reference = reference;
        let t = e.run()?;
        println!(
            "reference {reference:?}, scale {:.4} (150 g weighing, straight)",
            t.scale
        );
        println!("| configuration | mean abs error (g) | raw (scale 1) (g) | estimates (g) |");
        println!("|---|---|---|---|");
        for (c, conf) in t.configurations.iter().enumerate() {
            let est: Vec<String> = t
                .rows
                .iter()
                .filter(|r| r.configuration == c)
                .map(|r| format!("{:.1}", r.estimated_kg * 1e3))
                .collect();
            println!(
                "| {} | {:.2} | {:.2} | {} |",
                conf.name,
                t.mean_abs_error_kg(c, false) * 1e3,
                t.mean_abs_error_kg(c, true) * 1e3,
                est.join(" ")
            );
        }
    }
    Ok(())
}
