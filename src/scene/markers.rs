//! The markers file of `softrod estimate`: one observation
//! `{"markers": [...]}`, or a recorded stream
//! `{"frames": [{"t_s": 0.0, "markers": [...]}, ...]}` (one estimate per
//! frame, the estimator kept warm). Either may say what it holds in a
//! `"description"` (free text, not read).
//!
//! Read through the same parser as the scenes (an error names the field by
//! its path in the file: `frames[2].markers[0].position_m`) and held to the
//! documented limits: at most [`MAX_MARKERS`] markers per observation, at
//! most [`MAX_STREAM_FRAMES`] frames, frame times finite and
//! non-decreasing, and, against a robot, at most
//! [`MAX_MARKER_ELEMENT_PRODUCT`](super::ranges::MAX_MARKER_ELEMENT_PRODUCT)
//! markers × elements ([`MarkersFile::check_work`]).

use serde::Deserialize;

use super::ranges::MAX_MARKERS;
use crate::error::{Error, Result, check_at_most};
use crate::estimate::{MarkerObservation, Observation};

/// The most frames of a recorded stream: one warm estimate each (a few
/// milliseconds on the examples), so 100 000 frames, about 28 minutes of
/// 60 Hz motion capture, stay within minutes of work.
pub const MAX_STREAM_FRAMES: usize = 100_000;

/// One frame of a recorded stream.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MarkerFrame {
    /// Time of the frame (s).
    pub t_s: f64,
    /// The markers seen at `t_s` (as in a single-observation file).
    pub markers: Vec<MarkerObservation>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SingleFile {
    /// What the observation is (free text, not read).
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<String>,
    markers: Vec<MarkerObservation>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StreamFile {
    /// What the recording is (free text, not read).
    #[serde(default)]
    #[allow(dead_code)]
    description: Option<String>,
    frames: Vec<MarkerFrame>,
}

/// A markers file of either form.
///
/// # Example
/// ```
/// use softrod::scene::markers::MarkersFile;
/// let m = MarkersFile::from_json(r#"{"frames": [
///     {"t_s": 0.0, "markers": [{"node": 20, "position_m": [0.24, 0.0]}]},
///     {"t_s": 0.1, "markers": [{"node": 20, "position_m": [0.24, -0.01]}]}]}"#)?;
/// assert_eq!(m.observations().len(), 2);
/// // one observation, with a description (not read)
/// let one = MarkersFile::from_json(r#"{"description": "the tip at rest",
///     "markers": [{"node": 20, "position_m": [0.24, 0.0]}]}"#)?;
/// assert!(!one.is_stream() && one.observations()[0].1.markers.len() == 1);
/// let e = MarkersFile::from_json(r#"{"frames": [{"t_s": 0.0, "markers": [{"node": 20, "position": [0.24, 0.0]}]}]}"#)
///     .unwrap_err();
/// assert_eq!(e.field(), Some("frames[0].markers[0].position"), "{e}");
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub enum MarkersFile {
    /// `{"markers": [...]}`: one observation.
    Single(Observation),
    /// `{"frames": [...]}`: a recorded stream, in time order.
    Stream(Vec<MarkerFrame>),
}

impl MarkersFile {
    /// Parses and checks a markers file (the limits of the [module
    /// documentation](self)).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field at fault by its path in
    /// the file (`markers[0].position_m`, `frames[1].t_s`, `(file)` for
    /// text that is not JSON or neither form); [`Error::TooLarge`] naming
    /// `markers` or `frames[i].markers` beyond [`MAX_MARKERS`], or `frames`
    /// beyond [`MAX_STREAM_FRAMES`].
    pub fn from_json(text: &str) -> Result<MarkersFile> {
        let located = |e: super::json::ParseFailure| {
            Error::invalid(
                e.name(),
                "as written",
                format!(
                    "{} (a markers file is {{\"markers\": [...]}} or {{\"frames\": [{{\"t_s\": ..., \"markers\": [...]}}, ...]}})",
                    e.message
                ),
            )
        };
        let is_stream = serde_json::from_str::<serde_json::Value>(text)
            .ok()
            .is_some_and(|v| v.get("frames").is_some());
        let file = if is_stream {
            let file: StreamFile = super::json::parse(text).map_err(located)?;
            MarkersFile::Stream(file.frames)
        } else {
            let file: SingleFile = super::json::parse(text).map_err(located)?;
            MarkersFile::Single(Observation {
                markers: file.markers,
            })
        };
        file.check()?;
        Ok(file)
    }

    /// Reads a markers file (at most
    /// [`MAX_SCENE_BYTES`](super::MAX_SCENE_BYTES), refused before reading
    /// it); errors as [`MarkersFile::from_json`], the message prefixed with
    /// the file's path.
    ///
    /// # Errors
    /// [`Error::Scene`] if the file cannot be read; [`Error::TooLarge`] for
    /// a file above the size limit; as [`MarkersFile::from_json`].
    pub fn from_file(path: &std::path::Path) -> Result<MarkersFile> {
        let cannot_read = |e: std::io::Error| Error::Scene {
            message: format!("cannot read {}: {e}", path.display()),
        };
        let size = std::fs::metadata(path).map_err(cannot_read)?.len();
        check_at_most(
            &format!("size of {} (bytes)", path.display()),
            usize::try_from(size).unwrap_or(usize::MAX),
            super::MAX_SCENE_BYTES,
        )?;
        let text = std::fs::read_to_string(path).map_err(cannot_read)?;
        MarkersFile::from_json(&text)
    }

    /// The limits that need no robot.
    fn check(&self) -> Result<()> {
        match self {
            MarkersFile::Single(o) => check_at_most("markers", o.markers.len(), MAX_MARKERS),
            MarkersFile::Stream(frames) => {
                if frames.is_empty() {
                    return Err(Error::invalid(
                        "frames",
                        "[]",
                        "is empty: a stream needs at least one frame",
                    ));
                }
                check_at_most("frames", frames.len(), MAX_STREAM_FRAMES)?;
                let mut last = f64::NEG_INFINITY;
                for (i, f) in frames.iter().enumerate() {
                    if !f.t_s.is_finite() || f.t_s < last {
                        return Err(Error::invalid(
                            format!("frames[{i}].t_s"),
                            f.t_s,
                            "times must be finite and non-decreasing (s)",
                        ));
                    }
                    last = f.t_s;
                    check_at_most(
                        &format!("frames[{i}].markers"),
                        f.markers.len(),
                        MAX_MARKERS,
                    )?;
                }
                Ok(())
            }
        }
    }

    /// Refuses an estimate of more markers × `elements` than the documented
    /// budget ([`MAX_MARKER_ELEMENT_PRODUCT`](super::ranges::MAX_MARKER_ELEMENT_PRODUCT)),
    /// naming `markers` or `frames[i].markers`.
    ///
    /// # Errors
    /// [`Error::TooLarge`].
    ///
    /// # Example
    /// ```
    /// use softrod::scene::markers::MarkersFile;
    /// let m = MarkersFile::from_json(r#"{"markers": [{"node": 2, "position_m": [0.1, 0.0]},
    ///     {"node": 4, "position_m": [0.2, 0.0]}]}"#)?;
    /// assert!(m.check_work(10_000).is_ok());
    /// assert_eq!(m.check_work(10_001).unwrap_err().field(), Some("markers (× 10001 elements, the estimator's work per iteration)"));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn check_work(&self, elements: usize) -> Result<()> {
        match self {
            MarkersFile::Single(o) => {
                super::ranges::check_estimate_work("markers", o.markers.len(), elements)
            }
            MarkersFile::Stream(frames) => {
                for (i, f) in frames.iter().enumerate() {
                    super::ranges::check_estimate_work(
                        &format!("frames[{i}].markers"),
                        f.markers.len(),
                        elements,
                    )?;
                }
                Ok(())
            }
        }
    }

    /// Whether it is a recorded stream.
    pub fn is_stream(&self) -> bool {
        matches!(self, MarkersFile::Stream(_))
    }

    /// The observations in order, with the frame times (`None` for a
    /// single observation).
    pub fn observations(self) -> Vec<(Option<f64>, Observation)> {
        match self {
            MarkersFile::Single(o) => vec![(None, o)],
            MarkersFile::Stream(frames) => frames
                .into_iter()
                .map(|f| (Some(f.t_s), Observation { markers: f.markers }))
                .collect(),
        }
    }

    /// The first observation (a refinement's).
    pub fn first(&self) -> Option<Observation> {
        match self {
            MarkersFile::Single(o) => Some(o.clone()),
            MarkersFile::Stream(frames) => frames.first().map(|f| Observation {
                markers: f.markers.clone(),
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;

    fn frame(t: f64, n: usize) -> String {
        let m: Vec<String> = (0..n)
            .map(|i| {
                format!(
                    r#"{{"s_m": {}, "position_m": [0.1, 0.0]}}"#,
                    0.001 * i as f64
                )
            })
            .collect();
        format!(r#"{{"t_s": {t}, "markers": [{}]}}"#, m.join(","))
    }

    /// Every refusal names the field by its path in the file.
    #[test]
    fn refusals_name_their_field() {
        let field = |text: &str| {
            MarkersFile::from_json(text)
                .unwrap_err()
                .field()
                .map(str::to_string)
        };
        assert_eq!(
            field(r#"{"markers": [{"node": 2, "position_m": [0.1, "x"]}]}"#).as_deref(),
            Some("markers[0].position_m[1]")
        );
        assert_eq!(
            field(r#"{"markers": [{"node": 2, "position_m": [0.1, 0.0], "weight": 1}]}"#)
                .as_deref(),
            Some("markers[0].weight")
        );
        assert_eq!(
            field(&format!(r#"{{"frames": [{}, {{"t_s": 1, "markers": [{{"node": 2, "position_m": [0.1]}}], "x": 1}}]}}"#, frame(0.0, 1))).as_deref(),
            Some("frames[1].x")
        );
        assert_eq!(
            field(&format!(
                r#"{{"frames": [{}, {}]}}"#,
                frame(1.0, 1),
                frame(0.5, 1)
            ))
            .as_deref(),
            Some("frames[1].t_s")
        );
        assert_eq!(field(r#"{"frames": []}"#).as_deref(), Some("frames"));
        assert_eq!(field("not json").as_deref(), Some("(file)"));
        assert_eq!(field(r#"{"marker": []}"#).as_deref(), Some("marker"));
    }

    /// The documented limits: 250 markers per observation or frame.
    #[test]
    fn marker_limits_are_enforced_per_frame() {
        let ok = format!(r#"{{"frames": [{}]}}"#, frame(0.0, MAX_MARKERS));
        assert!(MarkersFile::from_json(&ok).is_ok());
        let over = format!(
            r#"{{"frames": [{}, {}]}}"#,
            frame(0.0, 1),
            frame(1.0, MAX_MARKERS + 1)
        );
        let e = MarkersFile::from_json(&over).unwrap_err();
        assert_eq!(e.field(), Some("frames[1].markers"), "{e}");
        let single = frame(0.0, MAX_MARKERS + 1).replacen(r#""t_s": 0, "#, "", 1);
        let e = MarkersFile::from_json(&single).unwrap_err();
        assert_eq!(e.field(), Some("markers"), "{e}");
        let m = MarkersFile::from_json(&format!(r#"{{"frames": [{}]}}"#, frame(0.0, 100))).unwrap();
        let e = m.check_work(201).unwrap_err();
        assert!(e.field().unwrap().starts_with("frames[0].markers"), "{e}");
        assert!(m.check_work(200).is_ok());
    }
}
