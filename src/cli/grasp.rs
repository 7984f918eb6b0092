// `softrod grasp SCENE [--strategy adaptive|open_loop] [--out FILE]`: one
// simulated grasp trial (the two-finger gripper, an object on a table), its
// outcome as JSON.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};

use softrod::grasp::scene::GraspScene;
use softrod::grasp::trial::Strategy;

use super::output::{
    CommandName, GoalNotMet, GraspRecord, GraspStatus, Header, Outcome, SceneKind,
};

/// The strategy on the command line.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum StrategyArg {
    /// (45)–(52) with the estimator.
    Adaptive,
    /// Proximal segments to a predetermined pressure (`open-loop` is
    /// accepted too).
    #[value(name = "open_loop", alias = "open-loop")]
    OpenLoop,
}

fn read_scene(path: &Path) -> Result<GraspScene> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the grasp scene {}", path.display()))?;
    GraspScene::from_json(&text).with_context(|| format!("invalid grasp scene {}", path.display()))
}

/// Runs one trial and writes its outcome (JSON) to `out` or standard output.
pub fn run(scene: PathBuf, strategy: Option<StrategyArg>, out: Option<PathBuf>) -> Result<()> {
    let s = read_scene(&scene)?;
    let strategy = strategy.map(|s| match s {
        StrategyArg::Adaptive => Strategy::Adaptive,
        StrategyArg::OpenLoop => Strategy::OpenLoop,
    });
    let outcome = s.run(strategy)?;
    let strategy = outcome.strategy;
    eprintln!(
        "softrod: grasp of {} ({}): {}{}",
        outcome.object,
        strategy.name(),
        if outcome.success { "held" } else { "failed" },
        outcome
            .failure
            .as_ref()
            .map(|f| format!(", {}", super::output::json_text(f)))
            .unwrap_or_default()
    );
    let held = outcome.success;
    let record = GraspRecord {
        header: Header::new(
            CommandName::Grasp,
            &outcome.object,
            SceneKind::Grasp,
            Outcome::from_ok(held),
        ),
        status: if held {
            GraspStatus::Held
        } else {
            GraspStatus::Failed
        },
        trial: outcome,
    };
    super::write_json(&record, out.as_ref())?;
    if !held {
        return Err(GoalNotMet(format!(
            "the grasp of {} did not hold{}; its record is written",
            record.trial.object,
            record
                .trial
                .failure
                .as_ref()
                .map(|f| format!(" ({})", super::output::json_text(f)))
                .unwrap_or_default()
        ))
        .into());
    }
    Ok(())
}
