//! The grasp scene file of `softrod grasp`: the object, where it is put,
//! and optionally the gripper, the settings, the noise seed and the
//! strategy. [`GraspScene::from_json`] parses and checks it (every check
//! [`run_trial`] makes before it simulates), naming the field as written.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::grasp::gripper::GripperSpec;
use crate::grasp::object::GraspObject;
use crate::grasp::trial::{
    GraspSettings, Placement, Strategy, TrialOutcome, check_trial, run_trial,
};

/// A grasp scene file (JSON): `{"object": {...}, "placement": {...}}`,
/// optional `gripper`, `settings`, `seed` (default 1) and `strategy`.
///
/// # Example
/// ```
/// let s = softrod::grasp::scene::GraspScene::from_json(r#"{"object": {"name": "apple",
///   "shape": {"shape": "circle", "radius_m": 0.035}, "mass_kg": 0.15, "mu": 0.5}}"#)?;
/// assert_eq!(s.seed, 1);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GraspScene {
    /// The object on the table.
    pub object: GraspObject,
    /// Where it is put (default centred, unrotated).
    #[serde(default)]
    pub placement: Placement,
    /// The gripper (default [`GripperSpec::default`]).
    #[serde(default)]
    pub gripper: GripperSpec,
    /// The trial's settings (default [`GraspSettings::default`]).
    #[serde(default)]
    pub settings: GraspSettings,
    /// Seed of the marker noise (default 1).
    #[serde(default = "default_seed")]
    pub seed: u64,
    /// The strategy (default: the caller's choice, else adaptive).
    #[serde(default)]
    pub strategy: Option<Strategy>,
}

fn default_seed() -> u64 {
    1
}

impl GraspScene {
    /// Parses and checks a grasp scene: malformed JSON, unknown fields and
    /// wrong types by their path, then [`check_trial`]'s checks.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`object.mu`,
    /// `placement.offset_m`, `settings.control_rate_hz`, `seed`, …;
    /// `(file)` when the JSON itself is broken).
    ///
    /// # Example
    /// ```
    /// use softrod::grasp::scene::GraspScene;
    /// let e = GraspScene::from_json(r#"{"object": {"name": "x", "shape": {"shape": "circle",
    ///   "radius_m": 0.02}, "mass_kg": 0.1, "mu": -0.5}}"#).unwrap_err();
    /// assert_eq!(e.field(), Some("object.mu"), "{e}");
    /// let e = GraspScene::from_json(r#"{"object": {"name": "x", "shape": {"shape": "circle",
    ///   "radius_m": 0.02}, "mass_kg": 0.1, "mu": 0.5}, "seed": -1}"#).unwrap_err();
    /// assert_eq!(e.field(), Some("seed"), "{e}");
    /// ```
    pub fn from_json(text: &str) -> Result<GraspScene> {
        let s: GraspScene = crate::scene::json::parse(text)
            .map_err(|e| Error::invalid(e.name(), "as written", e.message))?;
        check_trial(&s.gripper, &s.object, &s.placement, &s.settings)?;
        Ok(s)
    }

    /// Runs the scene's trial with `strategy` (default: the scene's, else
    /// [`Strategy::Adaptive`]).
    ///
    /// # Errors
    /// As [`run_trial`].
    ///
    /// # Example
    /// ```no_run
    /// let text = std::fs::read_to_string("examples/grasp_apple.json")?;
    /// let out = softrod::grasp::scene::GraspScene::from_json(&text)?.run(None)?;
    /// println!("{}", out.success);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn run(&self, strategy: Option<Strategy>) -> Result<TrialOutcome> {
        run_trial(
            &self.gripper,
            &self.object,
            self.placement,
            strategy.or(self.strategy).unwrap_or(Strategy::Adaptive),
            &self.settings,
            self.seed,
        )
    }
}
