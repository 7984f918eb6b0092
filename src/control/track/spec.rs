//! The desired path as a trajectory file writes it (`"trajectory"`): one
//! struct per `"kind"`, read with the path of a bad field.

use nalgebra::DVector;
use serde::{Deserialize, Serialize};

use super::parse_json;
use crate::error::{Error, Result};

/// A desired path as written in a trajectory file (`"kind"` names the
/// variant; its fields sit beside it).
///
/// # Example
/// ```
/// let f = softrod::control::TrackFile::from_json(
///     r#"{"trajectory": {"kind": "line", "from_m": [0.18, 0.11], "to_m": [0.19, 0.12], "period_s": 10, "duration_s": 10}}"#)?;
/// assert!(matches!(f.trajectory, softrod::control::TrajectorySpec::Line(_)));
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum TrajectorySpec {
    /// [`Trajectory::circle`](crate::control::Trajectory::circle).
    Circle(CircleSpec),
    /// [`Trajectory::figure_eight`](crate::control::Trajectory::figure_eight).
    FigureEight(FigureEightSpec),
    /// [`Trajectory::line`](crate::control::Trajectory::line).
    Line(LineSpec),
    /// Positions at times, linear in between.
    Samples(SamplesSpec),
    /// A pressure schedule: the path is the model's unloaded end effector
    /// under it.
    Pressures(PressuresSpec),
}

/// `"kind": "circle"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CircleSpec {
    /// Centre (m; default the model's end effector at the scene's pressures).
    #[serde(default)]
    pub center_m: Option<Vec<f64>>,
    /// Radius (m, > 0).
    pub radius_m: f64,
    /// One turn (s).
    pub period_s: f64,
    /// Duration of the motion (s).
    pub duration_s: f64,
    /// Hold at the start point first (s, default 3).
    #[serde(default = "default_hold")]
    pub hold_s: f64,
}

/// `"kind": "figure_eight"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FigureEightSpec {
    /// Centre (m; default as for a circle).
    #[serde(default)]
    pub center_m: Option<Vec<f64>>,
    /// Half-width (m, > 0).
    pub size_m: f64,
    /// One figure (s).
    pub period_s: f64,
    /// Duration of the motion (s).
    pub duration_s: f64,
    /// Hold at the start point first (s, default 3).
    #[serde(default = "default_hold")]
    pub hold_s: f64,
}

/// `"kind": "line"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LineSpec {
    /// One end (m).
    pub from_m: Vec<f64>,
    /// The other end (m).
    pub to_m: Vec<f64>,
    /// One return trip (s).
    pub period_s: f64,
    /// Duration of the motion (s).
    pub duration_s: f64,
    /// Hold at the start point first (s, default 3).
    #[serde(default = "default_hold")]
    pub hold_s: f64,
}

/// `"kind": "samples"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SamplesSpec {
    /// Times (s), increasing.
    pub times_s: Vec<f64>,
    /// Positions (m).
    pub points_m: Vec<Vec<f64>>,
}

/// `"kind": "pressures"`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressuresSpec {
    /// Times (s), increasing.
    pub times_s: Vec<f64>,
    /// Chamber pressures per time (Pa), within the chambers' bounds.
    pub pressures_pa: Vec<Vec<f64>>,
}

impl CircleSpec {
    /// The centre (m) as a vector, if the file gives one.
    ///
    /// ```
    /// use softrod::control::CircleSpec;
    /// let c = CircleSpec { center_m: Some(vec![0.19, 0.12]), radius_m: 0.005,
    ///                      period_s: 15.0, duration_s: 15.0, hold_s: 3.0 };
    /// assert_eq!(c.center().unwrap()[1], 0.12);
    /// ```
    pub fn center(&self) -> Option<DVector<f64>> {
        self.center_m.as_deref().map(DVector::from_column_slice)
    }
}

impl FigureEightSpec {
    /// The centre (m) as a vector, if the file gives one.
    ///
    /// ```
    /// use softrod::control::FigureEightSpec;
    /// let c = FigureEightSpec { center_m: None, size_m: 0.01,
    ///                           period_s: 15.0, duration_s: 15.0, hold_s: 3.0 };
    /// assert!(c.center().is_none());
    /// ```
    pub fn center(&self) -> Option<DVector<f64>> {
        self.center_m.as_deref().map(DVector::from_column_slice)
    }
}

impl LineSpec {
    /// The first end (`from_m`, m) as a vector.
    ///
    /// ```
    /// use softrod::control::LineSpec;
    /// let l = LineSpec { from_m: vec![0.18, 0.12], to_m: vec![0.20, 0.12],
    ///                    period_s: 10.0, duration_s: 10.0, hold_s: 3.0 };
    /// assert_eq!((l.end() - l.start()).norm(), 0.020000000000000018);
    /// ```
    pub fn start(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.from_m)
    }

    /// The other end (`to_m`, m) as a vector.
    ///
    /// ```
    /// use softrod::control::LineSpec;
    /// let l = LineSpec { from_m: vec![0.18, 0.12], to_m: vec![0.20, 0.13],
    ///                    period_s: 10.0, duration_s: 10.0, hold_s: 3.0 };
    /// assert_eq!(l.end()[1], 0.13);
    /// ```
    pub fn end(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.to_m)
    }
}

impl SamplesSpec {
    /// Sample `i`'s position (m) as a vector; `None` past the last sample.
    ///
    /// ```
    /// use softrod::control::SamplesSpec;
    /// let s = SamplesSpec { times_s: vec![0.0, 1.0],
    ///                       points_m: vec![vec![0.19, 0.12], vec![0.19, 0.13]] };
    /// assert_eq!(s.point(1).unwrap()[1], 0.13);
    /// assert!(s.point(2).is_none());
    /// ```
    pub fn point(&self, i: usize) -> Option<DVector<f64>> {
        self.points_m.get(i).map(|p| DVector::from_column_slice(p))
    }
}

impl PressuresSpec {
    /// The chamber pressures (Pa) at time `times_s[i]`; `None` past the
    /// last time.
    ///
    /// ```
    /// use softrod::control::PressuresSpec;
    /// let p = PressuresSpec { times_s: vec![0.0], pressures_pa: vec![vec![5e4, 0.0]] };
    /// assert_eq!(p.pressures(0).unwrap()[0], 5e4);
    /// ```
    pub fn pressures(&self, i: usize) -> Option<DVector<f64>> {
        self.pressures_pa
            .get(i)
            .map(|p| DVector::from_column_slice(p))
    }
}

impl TrajectorySpec {
    /// The hold at the start (s; 0 for samples and pressure schedules).
    pub fn hold_s(&self) -> f64 {
        match self {
            TrajectorySpec::Circle(c) => c.hold_s,
            TrajectorySpec::FigureEight(c) => c.hold_s,
            TrajectorySpec::Line(c) => c.hold_s,
            _ => 0.0,
        }
    }

    /// Parses `{"kind": ..., fields}` with the path of a bad field (an
    /// internally tagged enum hides it from the parser's path).
    pub(super) fn from_value(v: serde_json::Value) -> Result<Self> {
        let kind = v
            .get("kind")
            .and_then(|k| k.as_str())
            .ok_or_else(|| {
                Error::invalid(
                    "trajectory.kind",
                    "missing",
                    "one of circle, figure_eight, line, samples, pressures",
                )
            })?
            .to_string();
        let mut v = v;
        if let Some(o) = v.as_object_mut() {
            o.remove("kind");
        }
        let text = v.to_string();
        let p = |e: Error| e.with_prefix("trajectory.");
        Ok(match kind.as_str() {
            "circle" => TrajectorySpec::Circle(parse_json(&text).map_err(p)?),
            "figure_eight" => TrajectorySpec::FigureEight(parse_json(&text).map_err(p)?),
            "line" => TrajectorySpec::Line(parse_json(&text).map_err(p)?),
            "samples" => TrajectorySpec::Samples(parse_json(&text).map_err(p)?),
            "pressures" => TrajectorySpec::Pressures(parse_json(&text).map_err(p)?),
            other => {
                return Err(Error::invalid(
                    "trajectory.kind",
                    other,
                    "one of circle, figure_eight, line, samples, pressures",
                ));
            }
        })
    }
}

fn default_hold() -> f64 {
    3.0
}
