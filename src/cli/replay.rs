// `softrod estimate` on a recorded stream: the markers file
// (`softrod::scene::markers::MarkersFile`, one observation or frames of a
// recording) and the record of the stream.

use std::path::Path;

use anyhow::Result;

use softrod::scene::Scene;
use softrod::scene::markers::MarkersFile;

use super::output::{
    CommandName, EstimateBody, FrameRecord, Header, Outcome, SceneKind, StreamRecord, StreamStatus,
};

/// Reads a markers file of either form; an error names the field by its
/// path in the file (`frames[2].markers[0].position_m`, ...).
pub(super) fn read(path: &Path) -> Result<MarkersFile> {
    MarkersFile::from_file(path).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

/// The record of a stream from the per-frame estimates (in order).
pub(super) fn stream_record(scene: &Scene, frames: Vec<(f64, EstimateBody)>) -> StreamRecord {
    let (backend, observation) = frames
        .first()
        .map(|(_, e)| (e.backend, e.observation.clone()))
        .unwrap_or((super::output::BackendName::Newton, String::new()));
    let frames: Vec<FrameRecord> = frames
        .into_iter()
        .map(|(t_s, estimate)| FrameRecord {
            t_s,
            status: estimate.status,
            estimate,
        })
        .collect();
    let not_converged: Vec<usize> = frames
        .iter()
        .enumerate()
        .filter(|(_, f)| !f.status.is_converged())
        .map(|(i, _)| i)
        .collect();
    let ok = not_converged.is_empty();
    StreamRecord {
        header: Header::new(
            CommandName::Estimate,
            &scene.name,
            SceneKind::of(scene),
            Outcome::from_ok(ok),
        ),
        status: if ok {
            StreamStatus::AllConverged
        } else {
            StreamStatus::NotAllConverged
        },
        backend,
        observation,
        n_frames: frames.len(),
        not_converged,
        frames,
    }
}

/// One line per frame on standard error: its time and status.
pub(super) fn summarize(record: &StreamRecord) {
    for (i, f) in record.frames.iter().enumerate() {
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
