// `softrod track`: the closed loop against a simulated plant (see
// `softrod::control::run_track` for the files).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use softrod::control::{
    CircleSpec, ControllerKind, TrackFile, TrajectorySpec, payloads_from_json, run_track,
};
use softrod::scene::Scene;

use super::output::{
    CommandName, ControllerName, GoalNotMet, Header, Outcome, SceneKind, TrackRecord, TrackStatus,
};

/// `--controller`, spelled as in the JSON (`ff_updater`; the older
/// `ff+updater` is accepted too).
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub(super) enum ControllerArg {
    /// Feedforward only.
    Ff,
    /// Feedforward with the updater (31).
    #[value(name = "ff_updater", alias = "ff+updater")]
    FfUpdater,
}

/// The largest trajectory or payload file read (64 MiB).
const MAX_FILE_BYTES: u64 = 64 << 20;

fn read(path: &Path) -> Result<String> {
    let size = std::fs::metadata(path)
        .with_context(|| format!("cannot read {}", path.display()))?
        .len();
    if size > MAX_FILE_BYTES {
        anyhow::bail!(
            "{} is {size} bytes: at most {MAX_FILE_BYTES}",
            path.display()
        );
    }
    std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))
}

/// The default run: a 5 mm circle about the model's end effector at the
/// scene's pressures, 15 s per turn, after a 3 s hold.
fn default_file() -> TrackFile {
    TrackFile {
        trajectory: TrajectorySpec::Circle(CircleSpec {
            center_m: None,
            radius_m: 0.005,
            period_s: 15.0,
            duration_s: 15.0,
            hold_s: 3.0,
        }),
        loop_settings: Default::default(),
        plant: Default::default(),
        score_from_s: None,
    }
}

pub(super) fn run(
    scene: PathBuf,
    trajectory: Option<PathBuf>,
    payload: Option<PathBuf>,
    controller: Option<ControllerArg>,
    out: Option<PathBuf>,
) -> Result<()> {
    // a parallel-robot scene: its settings and plant (softrod::control::parallel)
    if let Some(ps) = super::parallel::read(&scene)? {
        let kind = controller.map(|c| match c {
            ControllerArg::Ff => ControllerKind::Ff,
            ControllerArg::FfUpdater => ControllerKind::FfUpdater,
        });
        return super::parallel::track(
            ps,
            trajectory.as_ref(),
            payload.is_some(),
            kind,
            out.as_ref(),
        );
    }
    let scene = Scene::from_file(&scene)?;
    let file = match &trajectory {
        Some(p) => TrackFile::from_json(&read(p)?).with_context(|| p.display().to_string())?,
        None => default_file(),
    };
    let payloads = match &payload {
        Some(p) => Some(payloads_from_json(&read(p)?).with_context(|| p.display().to_string())?),
        None => None,
    };
    let controller = controller.map(|c| match c {
        ControllerArg::Ff => ControllerKind::Ff,
        ControllerArg::FfUpdater => ControllerKind::FfUpdater,
    });
    let run = run_track(&scene, &file, payloads.as_ref(), controller)?;
    let s = &run.summary;
    let controller = ControllerName::from(s.controller);
    eprintln!(
        "softrod: track: {} at {} Hz, {} samples; from {} s: mean error {:.4} mm, max {:.4} mm; \
         median step {:.3} ms; IK not reached {}, pressures saturated {}, estimator kept last {}",
        controller.name(),
        s.control_rate_hz,
        s.samples,
        s.score_from_s,
        s.mean_error_m * 1e3,
        s.max_error_m * 1e3,
        s.median_step_time_s * 1e3,
        s.ik_not_reached,
        s.pressure_saturated,
        s.estimator_kept_last
    );
    let status = match (s.plant_failed_at_s, s.aborted_at_s) {
        (Some(at_s), _) => TrackStatus::PlantFailed { at_s },
        (None, Some(at_s)) => TrackStatus::Aborted { at_s },
        (None, None) => TrackStatus::Completed,
    };
    let ok = matches!(status, TrackStatus::Completed);
    super::write_json(
        &TrackRecord {
            header: Header::new(
                CommandName::Track,
                &scene.name,
                SceneKind::of(&scene),
                Outcome::from_ok(ok),
            ),
            status,
            controller,
            run,
        },
        out.as_ref(),
    )?;
    if !ok {
        return Err(GoalNotMet(format!(
            "the run stopped early ({}); the samples up to then are written",
            match status {
                TrackStatus::PlantFailed { at_s } =>
                    format!("the plant's equilibrium failed at {at_s} s"),
                TrackStatus::Aborted { at_s } =>
                    format!("the watchdog (loop.abort_error_m) stopped it at {at_s} s"),
                TrackStatus::Completed => String::new(),
            }
        ))
        .into());
    }
    Ok(())
}
