// `softrod` without a subcommand: the solve of `examples/two_section.json`
// and an estimate from the markers of `examples/two_section_payload_markers.json`
// (both files embedded), each through the same code as the subcommand
// whose command line it prints, so that the command reruns what it shows.

use std::path::PathBuf;

use super::*;
use softrod::estimate::AlphaRule;

/// How the printed commands start: `cargo run` installs nothing.
const RUN: &str = "cargo run --release --features cli --";
/// The scene (relative to the crate's root, where the commands run).
const SCENE_PATH: &str = "examples/two_section.json";
const SCENE_JSON: &str = include_str!("../../examples/two_section.json");
/// The markers the estimate is made from: a plant of four times the
/// scene's elements carrying the payload below (written by
/// `tests/demo_cli.rs` with `SOFTROD_WRITE_EXAMPLES=1`).
const MARKERS_PATH: &str = "examples/two_section_payload_markers.json";
const MARKERS_JSON: &str = include_str!("../../examples/two_section_payload_markers.json");
/// The payload of the markers file (the estimator is not told about it):
/// a tip mass (kg) and a uniform line load (N/m); `tests/demo_cli.rs`
/// writes the file with the same numbers.
const TIP_MASS_KG: f64 = 0.02;
const UNIFORM_N_PER_M: [f64; 2] = [0.0, -0.5];
/// Re-estimates timed warm, each of the file's markers plus fresh noise.
const WARM_FRAMES: u64 = 50;

fn median_warm_step(
    est: &mut dyn softrod::estimate::Estimator,
    observations: &[Observation],
) -> Result<f64> {
    let mut times = Vec::with_capacity(observations.len());
    for o in observations {
        let t = std::time::Instant::now();
        est.step(o)?.converged()?;
        times.push(t.elapsed().as_secs_f64());
    }
    times.sort_by(f64::total_cmp);
    Ok(times.get(times.len() / 2).copied().unwrap_or(f64::NAN))
}

pub(super) fn default_run() -> Result<()> {
    let scene = Scene::from_json(SCENE_JSON)?;
    solve_summary(&scene)?;
    outln!();
    estimation_demo(&scene)?;
    outln!();
    outln!(
        "After `cargo install --path . --features cli`, `softrod` replaces `{RUN}` in these commands."
    );
    Ok(())
}

/// What an α rule is, in words.
fn rule_words(rule: AlphaRule) -> &'static str {
    match rule {
        AlphaRule::Evidence => "the largest evidence, the marginal likelihood of the markers",
        AlphaRule::Discrepancy => {
            "the discrepancy principle, weighted residual = observed components"
        }
    }
}

/// How `α` was set and what the estimate's iterations were, from its report.
fn alpha_and_iterations(r: &output::EstimateReportRecord, given: bool) -> String {
    let at_alpha = format!("{} iteration(s) at the chosen alpha", r.iterations);
    match (&r.alpha_search, given) {
        (Some(a), _) => format!(
            "alpha {:.3e} chosen by alpha_rule \"{}\" ({}): a search of {} solves, {} iterations in all, then {at_alpha}",
            r.alpha,
            a.rule.name(),
            rule_words(a.rule),
            a.solves,
            a.iterations
        ),
        (None, true) => format!(
            "alpha {:.3e} as given (solver.estimator.alpha), {} iteration(s)",
            r.alpha, r.iterations
        ),
        (None, false) => format!("alpha {:.3e} of an earlier step, {at_alpha}", r.alpha),
    }
}

/// The main job: an unknown payload on the two-section robot, estimated
/// from the committed markers file with the scene's estimator settings
/// (as `softrod estimate` does), by both backends.
fn estimation_demo(scene: &Scene) -> Result<()> {
    let robot = scene.robot()?;
    let known = scene.loads()?;
    let file = MarkersFile::from_json(MARKERS_JSON)?;
    let Some(observation) = file.first() else {
        anyhow::bail!("{MARKERS_PATH}: no observation");
    };
    let description: serde_json::Value = serde_json::from_str(MARKERS_JSON)?;
    let settings = scene.estimator_settings()?;
    let sigma = settings.noise_sigma_m;
    let length = robot.length();
    let truth = [
        UNIFORM_N_PER_M[0] * length,
        UNIFORM_N_PER_M[1] * length - 9.81 * TIP_MASS_KG,
    ];
    outln!(
        "Estimation (Sec. III): an unknown payload ({:.0} g tip mass + uniform {:+.2} N/m), not known to the estimator",
        TIP_MASS_KG * 1e3,
        UNIFORM_N_PER_M[1]
    );
    outln!(
        "  markers: {MARKERS_PATH}: {}",
        description["description"].as_str().unwrap_or("")
    );
    outln!(
        "  estimator: the scene's solver.estimator settings (as `estimate` uses them), marker noise sigma {:.2} mm",
        sigma * 1e3
    );
    outln!("  truth:  resultant ({:+.4}, {:+.4}) N", truth[0], truth[1]);
    let tip_marker = observation
        .markers
        .iter()
        .find(|m| m.s_m.is_some_and(|s| (s - length).abs() < 1e-12));
    for backend in [Backend::Newton, Backend::Sqp] {
        let path = PathBuf::from(MARKERS_PATH);
        let mut outs = estimate(scene, Some(backend), Some((&path, file.clone())))?;
        let Some((_, e)) = outs.pop() else {
            anyhow::bail!("no estimate");
        };
        let r = &e.resultant;
        let tip = e
            .nodes
            .last()
            .map(|n| n.position_m.clone())
            .unwrap_or_default();
        outln!(
            "  {:<6}  resultant ({:+.4} ± {:.4}, {:+.4} ± {:.4}) N (± 1 sigma), moment {:+.4} N·m about the base; {}",
            backend.name(),
            r.force_n[0],
            r.force_std_n[0],
            r.force_n[1],
            r.force_std_n[1],
            r.moment_nm[0],
            e.status
        );
        if let (Some(m), [x, y]) = (tip_marker, tip.as_slice()) {
            outln!(
                "          tip ({:+.5}, {:+.5}) m, {:.3} mm from the tip marker",
                x,
                y,
                (x - m.position_m[0]).hypot(y - m.position_m[1]) * 1e3
            );
        }
        outln!(
            "          {}; first estimate {:.1} ms",
            alpha_and_iterations(&e.report, settings.alpha.is_some()),
            e.report.wall_time_s * 1e3
        );
        // the estimator kept warm, timed on the file's markers with fresh
        // noise added (each frame a new draw)
        let mut est = softrod::estimate::EstimatorSettings {
            backend,
            ..settings.clone()
        }
        .build_for(&robot, &known)?;
        est.step(&observation)?.converged()?;
        let frames: Vec<Observation> = (0..WARM_FRAMES)
            .map(|k| observation.clone().with_noise(sigma, 100 + k))
            .collect();
        let t = median_warm_step(est.as_mut(), &frames)?;
        outln!(
            "          warm step: {:.1} µs (median of {WARM_FRAMES} re-estimates, each of these markers plus a fresh {:.2} mm noise draw)",
            t * 1e6,
            sigma * 1e3
        );
        outln!(
            "          rerun: {RUN} estimate {SCENE_PATH} --markers {MARKERS_PATH} --backend {} --out target/estimate_{}.json",
            backend.name(),
            backend.name()
        );
    }
    Ok(())
}

fn solve_summary(scene: &Scene) -> Result<()> {
    let robot = scene.robot()?;
    let out = solve(scene, None)?;
    let spec = robot.spec();
    outln!(
        "softrod {} — scene `{}` ({SCENE_PATH})",
        env!("CARGO_PKG_VERSION"),
        scene.name
    );
    outln!("  {}", scene.description);
    outln!(
        "  {} sections, {} elements, {:.3} m, weight {:.3} N, pressures {:?} kPa",
        spec.sections.len(),
        robot.n_elements(),
        robot.length(),
        spec.sections
            .iter()
            .map(|s| s.mass_per_length_kg_per_m * s.length_m * 9.81)
            .sum::<f64>(),
        out.pressures_pa.iter().map(|p| p / 1e3).collect::<Vec<_>>()
    );
    outln!("  equilibrium: {}", out.report);
    outln!("  solve time: {:.1} µs", out.report.wall_time_s * 1e6);
    outln!(
        "  tip position: ({:+.4}, {:+.4}) m, tip angle {:+.2}°",
        out.tip_position_m[0],
        out.tip_position_m[1],
        out.tip_angle_rad.unwrap_or(f64::NAN).to_degrees()
    );
    outln!("  markers:");
    for m in &scene.markers {
        if let Some(n) = m.node {
            let p = &out.nodes[n].position_m;
            outln!(
                "    node {:2} (s = {:.3} m): ({:+.4}, {:+.4}) m",
                n,
                out.nodes[n].s_m,
                p[0],
                p[1]
            );
        }
    }
    outln!("  rerun: {RUN} solve {SCENE_PATH} --out target/result.json");
    Ok(())
}
