//! Where the closed loop fails, on a few cases (the full grid is
//! `softrod report --only loop`): payload in robot weights, EI error,
//! marker noise, control rate; converged or diverged and why.
//!
//! Run: `cargo run --release --features cli --example track_failure [PAYLOAD EI_ERROR NOISE_M RATE_HZ]`
//! (no arguments: the corners of the report's grid).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::report::loop_failure::{FailureSettings, LoopCase, run_case};
use softrod::scene::Scene;

fn main() -> softrod::Result<()> {
    let mut scene = Scene::two_section();
    scene.pressures_pa = vec![45e3, 0.0, 45e3, 0.0];
    let args: Vec<f64> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("numbers"))
        .collect();
    let cases: Vec<LoopCase> = if args.len() == 4 {
        vec![LoopCase {
            payload_weights: args[0],
            ei_error: args[1],
            noise_sigma_m: args[2],
            control_rate_hz: args[3],
            seed: 1,
        }]
    } else {
        let mut v = vec![];
        for p in [0.0, 5.0] {
            for e in [-0.3, 0.3] {
                for n in [0.0, 5e-4] {
                    for r in [5.0, 60.0] {
                        v.push(LoopCase {
                            payload_weights: p,
                            ei_error: e,
                            noise_sigma_m: n,
                            control_rate_hz: r,
                            seed: 1,
                        });
                    }
                }
            }
        }
        v
    };
    let settings = FailureSettings::default();
    println!(
        "payload_W  EI_err  noise_mm  rate_Hz  verdict   cause                 mean_mm   max_mm  ik!  sat  est!  wall_s"
    );
    for c in &cases {
        let t = std::time::Instant::now();
        let o = run_case(&scene, c, &settings)?;
        println!(
            "{:9.2} {:7.2} {:9.3} {:8.1}  {:9} {:20} {:8.3} {:8.3} {:4} {:4} {:5} {:7.2} {}",
            c.payload_weights,
            c.ei_error,
            c.noise_sigma_m * 1e3,
            c.control_rate_hz,
            format!("{:?}", o.verdict),
            o.cause.label(),
            o.mean_error_m.unwrap_or(f64::NAN) * 1e3,
            o.max_error_m.unwrap_or(f64::NAN) * 1e3,
            o.ik_not_reached,
            o.saturated,
            o.estimator_failed,
            t.elapsed().as_secs_f64(),
            o.message.unwrap_or_default()
        );
    }
    Ok(())
}
