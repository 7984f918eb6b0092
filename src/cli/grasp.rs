// `softrod grasp SCENE [--strategy adaptive|open-loop] [--out FILE]`: one
// simulated grasp trial (the two-finger gripper, an object on a table), its
// outcome as JSON.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use serde::Deserialize;

use softrod::grasp::gripper::GripperSpec;
use softrod::grasp::object::GraspObject;
use softrod::grasp::trial::{run_trial, GraspSettings, Placement, Strategy};

/// The grasp scene file: the object, where it is put, and optionally the
/// gripper, the settings and the noise seed.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GraspScene {
    object: GraspObject,
    #[serde(default)]
    placement: Placement,
    #[serde(default)]
    gripper: GripperSpec,
    #[serde(default)]
    settings: GraspSettings,
    #[serde(default = "default_seed")]
    seed: u64,
    #[serde(default)]
    strategy: Option<Strategy>,
}

fn default_seed() -> u64 {
    1
}

/// The strategy on the command line.
#[derive(Debug, Clone, Copy, clap::ValueEnum)]
pub enum StrategyArg {
    /// (45)–(52) with the estimator.
    Adaptive,
    /// Proximal segments to a predetermined pressure.
    OpenLoop,
}

fn read_scene(path: &Path) -> Result<GraspScene> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("cannot read the grasp scene {}", path.display()))?;
    let de = &mut serde_json::Deserializer::from_str(&text);
    serde_path_to_error::deserialize(de).map_err(|e| {
        anyhow::anyhow!(
            "invalid grasp scene {}: at `{}`: {}",
            path.display(),
            e.path(),
            e.inner()
        )
    })
}

/// Runs one trial and writes its outcome (JSON) to `out` or standard output.
pub fn run(scene: PathBuf, strategy: Option<StrategyArg>, out: Option<PathBuf>) -> Result<()> {
    let s = read_scene(&scene)?;
    let strategy = match strategy {
        Some(StrategyArg::Adaptive) => Strategy::Adaptive,
        Some(StrategyArg::OpenLoop) => Strategy::OpenLoop,
        None => s.strategy.unwrap_or(Strategy::Adaptive),
    };
    let outcome = run_trial(
        &s.gripper,
        &s.object,
        s.placement,
        strategy,
        &s.settings,
        s.seed,
    )?;
    eprintln!(
        "softrod: grasp of {} ({}): {}{}",
        outcome.object,
        strategy.name(),
        if outcome.success { "held" } else { "failed" },
        outcome
            .failure
            .as_ref()
            .map(|f| format!(", {f:?}"))
            .unwrap_or_default()
    );
    let text = serde_json::to_string_pretty(&outcome)?;
    match out {
        Some(path) => std::fs::write(&path, text + "\n")
            .with_context(|| format!("cannot write {}", path.display())),
        None => {
            outln!("{text}");
            Ok(())
        }
    }
}
