//! The settings of a parallel-robot tracking run, as its file writes them.

use serde::{Deserialize, Serialize};

use super::super::{ControllerKind, UpdaterGains};
use crate::error::{Error, Result};

/// The settings of a tracking run; every field has a default.
///
/// # Example
/// ```
/// let s: softrod::control::parallel::TrackSettings = serde_json::from_str(r#"{"payload_kg": 0.05}"#)?;
/// assert_eq!(s.control_rate_hz, 10.0);
/// s.validate()?;
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TrackSettings {
    /// The controller (default feedforward + updater).
    pub controller: ControllerKind,
    /// Control rate (Hz, default 10; the plant is quasi-static).
    pub control_rate_hz: f64,
    /// Updater gains (31) (default `K_P = K_I = 4`).
    pub gains: UpdaterGains,
    /// The unknown mass hung from the platform's centre (kg, default 0.1).
    pub payload_kg: f64,
    /// Marker noise per coordinate and frame (m, default 0.05 mm).
    pub noise_sigma_m: f64,
    /// Seed of the noise (default 1).
    pub seed: u64,
    /// Elements per section of the controller's model (default 2: the
    /// model's 4 of `params::parallel` cost twice as much per step; the
    /// coarser mesh is one more model error the loop absorbs).
    pub model_elements_per_section: usize,
    /// Radius of the horizontal circle (m, default 2.5 mm: at 4 mm the
    /// model needs chambers at their 100 kPa bound over part of the circle
    /// once the updater's load is in, measured: 37 of 231 instants
    /// unreachable).
    pub radius_m: f64,
    /// Time per turn (s, default 20).
    pub period_s: f64,
    /// Duration of the circle (s, default 20: one turn).
    pub duration_s: f64,
    /// Hold at the start point before the circle (s, default 3).
    pub hold_s: f64,
    /// Errors are scored from this time on (s, default 3: the end of the
    /// hold, by when the updater has settled to 2 %).
    pub score_from_s: f64,
    /// The inverse kinematics counts a target reached within this (m,
    /// default 1 µm, 1/200 of the tracking target).
    pub ik_tolerance_m: f64,
}

impl Default for TrackSettings {
    fn default() -> Self {
        TrackSettings {
            controller: ControllerKind::FfUpdater,
            control_rate_hz: 10.0,
            gains: UpdaterGains::default(),
            payload_kg: 0.1,
            noise_sigma_m: 0.05e-3,
            seed: 1,
            model_elements_per_section: 2,
            radius_m: 2.5e-3,
            period_s: 20.0,
            duration_s: 20.0,
            hold_s: 3.0,
            score_from_s: 3.0,
            ik_tolerance_m: 1e-6,
        }
    }
}

impl TrackSettings {
    /// Parses and checks a parallel tracking file (the `--trajectory` file
    /// of `softrod track` on a parallel-robot scene; every field optional).
    /// A refusal names the field as written in the file (`control_rate_hz`,
    /// `gains.k_p_per_s`), not [`TrackSettings::validate`]'s `track.` and
    /// `updater.` names.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for malformed JSON, unknown fields,
    /// wrong types and the checks of [`TrackSettings::validate`].
    ///
    /// # Example
    /// ```
    /// use softrod::control::parallel::TrackSettings;
    /// let s = TrackSettings::from_json(r#"{"payload_kg": 0.05}"#)?;
    /// assert_eq!(s.control_rate_hz, 10.0);
    /// let e = TrackSettings::from_json(r#"{"gains": {"k_p_per_s": -1}}"#).unwrap_err();
    /// assert_eq!(e.field(), Some("gains.k_p_per_s"), "{e}");
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn from_json(text: &str) -> Result<Self> {
        let s: TrackSettings = super::super::track::parse_json(text)?;
        s.validate().map_err(|e| match e {
            Error::InvalidParameter {
                name,
                value,
                reason,
            } => Error::InvalidParameter {
                name: match name.strip_prefix("track.") {
                    Some(n) => n.to_string(),
                    None => name.replacen("updater.", "gains.", 1),
                },
                value,
                reason,
            },
            e => e,
        })?;
        Ok(s)
    }

    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`track.control_rate_hz`,
    /// `track.payload_kg`, …, `updater.k_p_per_s`).
    pub fn validate(&self) -> Result<()> {
        let f = |n: &str| format!("track.{n}");
        for (name, v) in [
            ("control_rate_hz", self.control_rate_hz),
            ("period_s", self.period_s),
            ("ik_tolerance_m", self.ik_tolerance_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(f(name), v, "must be finite and > 0"));
            }
        }
        if self.control_rate_hz > 1000.0 {
            return Err(Error::invalid(
                f("control_rate_hz"),
                self.control_rate_hz,
                "at most 1000 Hz",
            ));
        }
        for (name, v) in [
            ("payload_kg", self.payload_kg),
            ("noise_sigma_m", self.noise_sigma_m),
            ("radius_m", self.radius_m),
            ("duration_s", self.duration_s),
            ("hold_s", self.hold_s),
            ("score_from_s", self.score_from_s),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(f(name), v, "must be finite and >= 0"));
            }
        }
        if self.duration_s + self.hold_s > 600.0 {
            // the larger of the two is blamed, the other named
            let (name, v, other) = if self.hold_s > self.duration_s {
                ("hold_s", self.hold_s, "duration_s")
            } else {
                ("duration_s", self.duration_s, "hold_s")
            };
            return Err(Error::invalid(
                f(name),
                v,
                format!("with `{other}` at most 600 s in all"),
            ));
        }
        let steps = (self.duration_s + self.hold_s) * self.control_rate_hz;
        if steps > MAX_PARALLEL_TRACK_STEPS as f64 {
            return Err(Error::invalid(
                f("control_rate_hz"),
                self.control_rate_hz,
                format!(
                    "with `duration_s` + `hold_s` = {} s, {steps:.3e} control steps: at most \
                     {MAX_PARALLEL_TRACK_STEPS}",
                    self.duration_s + self.hold_s
                ),
            ));
        }
        if self.model_elements_per_section == 0 {
            return Err(Error::invalid(
                f("model_elements_per_section"),
                0,
                "must be >= 1",
            ));
        }
        self.gains.validate()
    }
}

/// The most control steps of a parallel-robot tracking run, `control_rate_hz`
/// times `duration_s` plus `hold_s`: 600 s at the default 10 Hz, about 2.4
/// min of computation at the measured 24 ms per step (600 s at 1 kHz, 6e5
/// steps or about 4 h, was accepted before).
pub const MAX_PARALLEL_TRACK_STEPS: usize = 6_000;

impl TrackSettings {
    pub(super) fn tolerance(&self) -> f64 {
        self.ik_tolerance_m
    }
}
