// `softrod avoid SCENE [--out FILE] [--baseline]`: obstacle avoidance by
// touch against the simulated plant (the paper's Fig. 9).

use std::path::PathBuf;

use anyhow::{Context, Result};

use softrod::touch::{AvoidScene, AvoidStatus};

use super::output::{AvoidRecord, CommandName, GoalNotMet, Header, Outcome, SceneKind};
use super::write_json;

/// Runs the avoidance of the scene file `scene`, writes the run as JSON
/// (`out` or standard output) and a summary on standard error; fails when
/// the goal is not reached.
pub(super) fn avoid(scene: PathBuf, out: Option<PathBuf>, baseline: bool) -> Result<()> {
    let text = std::fs::read_to_string(&scene)
        .with_context(|| format!("cannot read {}", scene.display()))?;
    let mut s = AvoidScene::from_json(&text)?;
    if baseline {
        s.avoid.touch_feedback = false;
    }
    let run = s.run()?;
    // an avoidance scene has no name: its file's stem
    let name = scene
        .file_stem()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let record = AvoidRecord {
        header: Header::new(
            CommandName::Avoid,
            &name,
            SceneKind::Avoid,
            Outcome::from_ok(run.status.is_reached()),
        ),
        run,
    };
    write_json(&record, out.as_ref())?;
    let run = &record.run;
    for t in &run.touched {
        eprintln!(
            "softrod: touched at {:.2} s: s = {:.4} m, obstacle point ({:.4}, {:.4}) m, force ({:.4}, {:.4}) N",
            t.time_s, t.s_m, t.point_m[0], t.point_m[1], t.force_n[0], t.force_n[1]
        );
    }
    match run.status {
        AvoidStatus::Reached { time_s } => {
            eprintln!(
                "softrod: goal reached at {time_s:.2} s, final error {:.3} mm; largest contact force {:.4} N before localization, {:.4} N after",
                run.final_error_m * 1e3,
                run.max_force_before_n,
                run.max_force_after_n
            );
            Ok(())
        }
        AvoidStatus::NotReached { distance_m } => Err(GoalNotMet(format!(
            "goal not reached: the end effector ended {:.2} mm from it (largest contact force {:.4} N)",
            distance_m * 1e3,
            run.max_force_before_n.max(run.max_force_after_n)
        ))
        .into()),
        AvoidStatus::GoalUnreachable { distance_m } => Err(GoalNotMet(format!(
            "goal unreachable: outside the robot's workspace (the closest pose is {:.2} mm away); not run",
            distance_m * 1e3
        ))
        .into()),
    }
}
