//! `softrod solve`, `softrod estimate` and `softrod track` on a
//! soft-parallel-robot scene (a scene file whose top-level object has a
//! `parallel` key).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use softrod::parallel::payload::PayloadEstimate;
use softrod::scene::parallel::{ParallelScene, ParallelSolution, PlatformMarkers};

use super::output::{
    CommandName, ControllerName, Header, Outcome, ParallelEstimateRecord, ParallelSolveRecord,
    ParallelSolveStatus, PoseRecord, SceneKind, TrackRecord, TrackStatus,
};

/// The scene at `path` if it is a parallel-robot scene.
pub(super) fn read(path: &Path) -> Result<Option<ParallelScene>> {
    // a file too large (or unreadable) is the ordinary scene reader's to refuse
    match std::fs::metadata(path) {
        Ok(m) if m.len() <= softrod::scene::MAX_SCENE_BYTES as u64 => {}
        _ => return Ok(None),
    }
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    if !ParallelScene::is_parallel(&text) {
        return Ok(None);
    }
    Ok(Some(ParallelScene::from_json(&text)?))
}

/// `softrod solve` on a parallel scene (`pressures` override the scene's).
pub(super) fn solve(
    mut scene: ParallelScene,
    pressures: Option<Vec<f64>>,
    out: Option<&PathBuf>,
) -> Result<()> {
    if let Some(p) = pressures {
        scene.pressures_pa = p;
        scene.validate()?;
    }
    let solution = scene.solve()?;
    super::write_json(
        &ParallelSolveRecord {
            header: Header::new(
                CommandName::Solve,
                &scene.name,
                SceneKind::Parallel,
                Outcome::Success,
            ),
            status: ParallelSolveStatus::Converged,
            element: scene.element.into(),
            pressures_pa: scene.pressures_pa.clone(),
            platform_pose: PoseRecord::from_six(&solution.platform_pose),
            legs_m: solution.legs_m,
            iterations: solution.iterations,
        },
        out,
    )
}

/// `softrod estimate` on a parallel scene: the payload at the platform
/// from the platform marker (a markers file `{"unloaded_m": [..],
/// "loaded_m": [..]}`; without one, the scene solved without and with a
/// 100 g payload, exact).
pub(super) fn estimate(
    mut scene: ParallelScene,
    markers: Option<&PathBuf>,
    pressures: Option<Vec<f64>>,
    backend: Option<softrod::estimate::Backend>,
    out: Option<&PathBuf>,
) -> Result<()> {
    if let Some(b) = backend {
        scene.backend = b;
    }
    if let Some(p) = pressures {
        scene.pressures_pa = p;
        scene.validate()?;
    }
    let (m, source) = match markers {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            let m = PlatformMarkers::from_json(&text, &scene)
                .with_context(|| format!("{}: not a platform markers file", path.display()))?;
            (m, format!("markers file {}", path.display()))
        }
        None => {
            let free = scene.solve()?;
            let mut loaded = scene.clone();
            let g = &scene.parallel.gravity_m_per_s2;
            loaded.platform_force_n = g.iter().map(|v| 0.1 * v).collect();
            let with = loaded.solve()?;
            let p =
                |s: &ParallelSolution| [s.platform_pose[0], s.platform_pose[1], s.platform_pose[2]];
            (
                PlatformMarkers {
                    unloaded_m: p(&free),
                    loaded_m: p(&with),
                },
                "synthesized: the scene solved without and with a 100 g payload (exact); the estimate should be 0.1 kg".to_string(),
            )
        }
    };
    if markers.is_none() {
        eprintln!("softrod: no markers file: {source}");
    }
    let e: PayloadEstimate = scene.estimate(m.unloaded_m, m.loaded_m)?;
    let converged = e.status.is_converged();
    super::write_json(
        &ParallelEstimateRecord {
            header: Header::new(
                CommandName::Estimate,
                &scene.name,
                SceneKind::Parallel,
                Outcome::from_ok(converged),
            ),
            status: Some(e.status),
            backend: scene.backend.into(),
            element: scene.element.into(),
            observation: source,
            force_n: e.force_n.into(),
            force_std_n: Some(e.std_n.into()),
            mass_kg: e.mass_kg,
            mass_std_kg: Some(e.std_kg),
            iterations: e.iterations,
            residual_m: e.residual_m,
        },
        out,
    )?;
    if !converged {
        return Err(super::GoalNotMet(format!(
            "the payload estimate did not converge: {}; the result written is the last iterate",
            e.status
        ))
        .into());
    }
    Ok(())
}

/// `softrod track` on a parallel scene: the circle about the platform at
/// the scene's pressures (the default centre without), the run's settings
/// from the trajectory file (`softrod::control::parallel::TrackSettings`,
/// every field optional), the controller overridden by `--controller`.
pub(super) fn track(
    scene: ParallelScene,
    settings: Option<&PathBuf>,
    payload_file: bool,
    controller: Option<softrod::control::ControllerKind>,
    out: Option<&PathBuf>,
) -> Result<()> {
    use softrod::control::parallel as track;
    use softrod::parallel::LegElement;
    if payload_file {
        anyhow::bail!(
            "--payload: a parallel-robot run hangs one mass, the trajectory file's `payload_kg`"
        );
    }
    if scene.element != LegElement::Ancf3d {
        anyhow::bail!(
            "element: tracking on the parallel robot needs the full 3-D element (\"ancf3d\"); \
             the spatial cable misses the platform's twist"
        );
    }
    if !(scene.platform_force_n.is_empty() && scene.platform_moment_nm.is_empty()) {
        anyhow::bail!(
            "platform_force_n: a tracking scene carries no known platform load (the unknown \
             mass is the trajectory file's `payload_kg`)"
        );
    }
    let mut settings: track::TrackSettings = match settings {
        Some(path) => {
            let text = std::fs::read_to_string(path)
                .with_context(|| format!("cannot read {}", path.display()))?;
            track::TrackSettings::from_json(&text)
                .with_context(|| format!("{}: not a parallel tracking file", path.display()))?
        }
        None => track::TrackSettings::default(),
    };
    if let Some(c) = controller {
        settings.controller = c;
    }
    let bar = softrod::report::progress(0, false, "track");
    let run = track::run_track_observed(
        &scene.parallel,
        &scene.pressures_pa,
        &settings,
        &mut |done, total| {
            bar.set_length(total as u64);
            bar.set_position(done as u64);
        },
    );
    bar.finish_and_clear();
    let run = run?;
    let s = &run.summary;
    let controller = ControllerName::from(s.controller);
    eprintln!(
        "softrod: track (parallel robot): {}, {} samples; from {} s: mean error {:.4} mm, \
         max {:.4} mm; median step {:.1} ms; IK not reached {}",
        controller.name(),
        s.samples,
        s.score_from_s,
        s.mean_error_m * 1e3,
        s.max_error_m * 1e3,
        s.median_step_time_s * 1e3,
        s.ik_not_reached
    );
    super::write_json(
        &TrackRecord {
            header: Header::new(
                CommandName::Track,
                &scene.name,
                SceneKind::Parallel,
                Outcome::Success,
            ),
            status: TrackStatus::Completed,
            controller,
            run,
        },
        out,
    )
}
