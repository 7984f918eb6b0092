// `softrod estimate` on a recorded stream: the markers file's two forms
// (one observation, or frames of a recording) and the per-frame output.

use std::path::Path;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use softrod::estimate::Observation;
use softrod::outcome::EstimateStatus;

use super::EstimateOut;

/// A markers file: `{"markers": [...]}`, one observation, or
/// `{"frames": [{"t_s": ..., "markers": [...]}, ...]}`, a recorded stream.
pub(super) enum Markers {
    Single(Observation),
    Stream(Vec<Frame>),
}

/// One frame of a recorded stream.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct Frame {
    /// Time of the frame (s).
    pub(super) t_s: f64,
    /// The markers seen at `t_s` (as in a single-observation file).
    pub(super) markers: Vec<softrod::estimate::MarkerObservation>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StreamFile {
    /// What the recording is (free text, not read).
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<String>,
    frames: Vec<Frame>,
}

impl Markers {
    /// The observations in order, with the frame times (`None` for a
    /// single observation).
    pub(super) fn observations(self) -> Vec<(Option<f64>, Observation)> {
        match self {
            Markers::Single(o) => vec![(None, o)],
            Markers::Stream(frames) => frames
                .into_iter()
                .map(|f| (Some(f.t_s), Observation { markers: f.markers }))
                .collect(),
        }
    }

    /// The first observation (a refinement's).
    pub(super) fn first(&self) -> Option<Observation> {
        match self {
            Markers::Single(o) => Some(o.clone()),
            Markers::Stream(frames) => frames.first().map(|f| Observation {
                markers: f.markers.clone(),
            }),
        }
    }
}

/// Reads a markers file of either form; an error names the field by its
/// path in the file (`frames[2].markers[0].position_m`, ...).
pub(super) fn read(path: &Path) -> Result<Markers> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let bad = |e: &dyn std::fmt::Display| format!("{}: not a markers file: {e}", path.display());
    let value: serde_json::Value = serde_json::from_str(&text).with_context(|| bad(&"not JSON"))?;
    if value.get("frames").is_none() {
        return serde_json::from_str(&text)
            .map(Markers::Single)
            .with_context(|| bad(&"expected {\"markers\": [...]} or {\"frames\": [...]}"));
    }
    let file: StreamFile = serde_path_to_error::deserialize(value).map_err(|e| {
        let at = e.path().to_string();
        anyhow::anyhow!("{}", bad(&format_args!("at `{at}`: {}", e.inner())))
    })?;
    if file.frames.is_empty() {
        anyhow::bail!("{}", bad(&"`frames` is empty"));
    }
    let mut last = f64::NEG_INFINITY;
    for (i, f) in file.frames.iter().enumerate() {
        if !f.t_s.is_finite() || f.t_s < last {
            anyhow::bail!(
                "{}",
                bad(&format_args!(
                    "`frames[{i}].t_s` = {}: times must be finite and non-decreasing",
                    f.t_s
                ))
            );
        }
        last = f.t_s;
    }
    Ok(Markers::Stream(file.frames))
}

/// One frame's estimate in the output of a stream.
#[derive(Serialize)]
pub(super) struct FrameOut {
    /// Time of the frame (s).
    pub(super) t_s: f64,
    /// How its estimate ended (also in `estimate.report.status`).
    pub(super) status: EstimateStatus,
    pub(super) estimate: EstimateOut,
}

/// The result of `softrod estimate` on a recorded stream: one record per
/// frame, the estimator kept warm from frame to frame.
#[derive(Serialize)]
pub(super) struct StreamOut {
    pub(super) scene: String,
    pub(super) backend: String,
    pub(super) observation: String,
    pub(super) n_frames: usize,
    /// Frames whose estimate did not converge (their index).
    pub(super) not_converged: Vec<usize>,
    pub(super) frames: Vec<FrameOut>,
}

impl StreamOut {
    /// The stream's records from the per-frame estimates (in order).
    pub(super) fn new(observation: String, frames: Vec<(f64, EstimateOut)>) -> Self {
        let (scene, backend) = frames
            .first()
            .map(|(_, e)| (e.scene.clone(), e.backend.clone()))
            .unwrap_or_default();
        let frames: Vec<FrameOut> = frames
            .into_iter()
            .map(|(t_s, estimate)| FrameOut {
                t_s,
                status: estimate.report.status,
                estimate,
            })
            .collect();
        StreamOut {
            scene,
            backend,
            observation,
            n_frames: frames.len(),
            not_converged: frames
                .iter()
                .enumerate()
                .filter(|(_, f)| !f.status.is_converged())
                .map(|(i, _)| i)
                .collect(),
            frames,
        }
    }

    /// One line per frame on standard error: its time and status.
    pub(super) fn summarize(&self) {
        for (i, f) in self.frames.iter().enumerate() {
            eprintln!(
                "softrod: frame {i} (t = {} s): {}, weighted residual {:.4e} for {} components, alpha {:.3e}",
                f.t_s,
                f.status,
                f.estimate.report.weighted_residual,
                f.estimate.report.n_observations,
                f.estimate.report.alpha
            );
        }
    }
}
