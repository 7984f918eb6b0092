//! Tracking a platform circle under an unknown 100 g mass on the soft
//! parallel robot: feedforward only versus feedforward + updater (31),
//! plant ≠ model (finer mesh, EI +15 %, GJ +10 %, EA +2 %, gain −10 %,
//! σ = 0.05 mm on the platform marker).
//!
//! Run: `cargo run --release --features cli --example parallel_track [-- <duration_s> [<model elements per section> [<radius_mm>]]]`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use softrod::control::ControllerKind;
use softrod::control::parallel::{TrackSettings, run_track};
use softrod::parallel::ParallelSpec;

fn main() -> Result<(), softrod::Error> {
    let duration: f64 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(20.0);
    let elements: usize = std::env::args()
        .nth(2)
        .and_then(|a| a.parse().ok())
        .unwrap_or(TrackSettings::default().model_elements_per_section);
    let spec = ParallelSpec::default();
    println!(
        "| controller | mean error (mm) | max error (mm) | IK not reached | median step (ms) |"
    );
    println!("|---|---|---|---|---|");
    for kind in [ControllerKind::Ff, ControllerKind::FfUpdater] {
        let settings = TrackSettings {
            controller: kind,
            duration_s: duration,
            model_elements_per_section: elements,
            radius_m: std::env::args()
                .nth(3)
                .and_then(|a| a.parse::<f64>().ok())
                .map_or(TrackSettings::default().radius_m, |r| r * 1e-3),
            ..TrackSettings::default()
        };
        let t = std::time::Instant::now();
        let run = run_track(&spec, &[], &settings)?;
        let s = &run.summary;
        println!(
            "| {:?} | {:.4} | {:.4} | {} | {:.1} |  ({} samples, from {} s, {:.1} s wall)",
            kind,
            s.mean_error_m * 1e3,
            s.max_error_m * 1e3,
            s.ik_not_reached,
            s.median_step_time_s * 1e3,
            s.samples,
            s.score_from_s,
            t.elapsed().as_secs_f64()
        );
        let ik_max = run
            .samples
            .iter()
            .fold(0.0f64, |m, s| m.max(s.ik.error_m()));
        println!(
            "   max step {:.1} ms; model {:?}; plant {:?}",
            s.max_step_time_s * 1e3,
            s.model_solves,
            s.plant_solves
        );
        for smp in run
            .samples
            .iter()
            .filter(|x| x.step_time_s > 0.2 || x.ik.error_m() > 1e-6)
        {
            println!(
                "   t {:.1}: step {:.0} ms, IK error {:.2e} m",
                smp.time_s,
                smp.step_time_s * 1e3,
                smp.ik.error_m()
            );
        }
        println!("   IK: largest remaining distance {ik_max:.3e} m");
        if let Some(last) = run.samples.last() {
            println!(
                "   last F̂ {:?} N, F̄ {:?} N",
                last.estimated_load_n, last.estimator_load_n
            );
        }
    }
    Ok(())
}
