//! An avoidance scene file: the robot, its obstacles (unknown to the
//! controller, in the plant's world only), the goal, the plant's
//! differences and the controller's settings.
//!
//! ```json
//! {
//!   "obstacles": [{"shape": "circle", "center_m": [0.08, -0.465], "radius_m": 0.01}],
//!   "goal_m": [0.15, -0.40],
//!   "avoid": {"duration_s": 70.0}
//! }
//! ```
//!
//! Every other field has a default: the paper's five-section robot
//! ([`five_section_scene`]), six markers, the rod radius
//! [`ROD_RADIUS_M`], the default plant differences and avoidance settings.

use serde::{Deserialize, Serialize};

use crate::contact::{Obstacle, Obstacles};
use crate::error::{Error, Result};
use crate::plant::{PlantSettings, SimulatedPlant};

use super::{
    AvoidRun, AvoidSettings, ROD_RADIUS_M, calibrate_on_free_plant, five_section_scene,
    marker_arcs, run_avoidance,
};

/// An avoidance scene (see the [module documentation](crate::touch)).
///
/// # Example
/// ```
/// let s = softrod::touch::AvoidScene::from_json(
///     r#"{"obstacles": [{"shape": "circle", "center_m": [0.08, -0.465], "radius_m": -0.01}], "goal_m": [0.15, -0.4]}"#);
/// assert_eq!(s.unwrap_err().field(), Some("obstacles[0].radius_m"));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AvoidScene {
    /// Obstacles in the plant's world (m).
    pub obstacles: Vec<Obstacle>,
    /// Radius of the robot's body (m, default [`ROD_RADIUS_M`]).
    #[serde(default = "default_rod_radius")]
    pub rod_radius_m: f64,
    /// The end effector's goal (m).
    pub goal_m: [f64; 2],
    /// Number of markers, evenly spaced from base to tip (default 6).
    #[serde(default = "default_markers")]
    pub markers: usize,
    /// How the plant differs from the model (default [`PlantSettings`]).
    #[serde(default)]
    pub plant: PlantSettings,
    /// The controller (default [`AvoidSettings`]).
    #[serde(default)]
    pub avoid: AvoidSettings,
}

fn default_rod_radius() -> f64 {
    ROD_RADIUS_M
}

fn default_markers() -> usize {
    6
}

impl AvoidScene {
    /// Parses and validates a scene.
    ///
    /// # Errors
    /// [`Error::Scene`] for malformed JSON, unknown fields or wrong types
    /// (the message starts with the field's path);
    /// [`Error::InvalidParameter`] naming the field for invalid values: an
    /// obstacle's (`obstacles[i].radius_m`, `…center_m`, a non-convex
    /// `…vertices_m`), one overlapping the robot's base or straight
    /// reference configuration (`obstacles[i]`), `goal_m` not finite,
    /// `markers` below 2 or above 64, the plant's and the controller's
    /// settings (`plant.*`, `avoid.*`, `field.*`).
    pub fn from_json(text: &str) -> Result<Self> {
        let scene: AvoidScene = crate::scene::json::parse(text).map_err(|e| Error::Scene {
            message: e.located(),
        })?;
        scene.validate()?;
        Ok(scene)
    }

    /// Checks every field (see [`AvoidScene::from_json`]).
    ///
    /// # Errors
    /// As [`AvoidScene::from_json`].
    pub fn validate(&self) -> Result<()> {
        let obstacles = self.checked_obstacles()?;
        if !self.goal_m.iter().all(|v| v.is_finite()) {
            return Err(Error::invalid(
                "goal_m",
                format!("{:?}", self.goal_m),
                "must be finite",
            ));
        }
        if !(2..=64).contains(&self.markers) {
            return Err(Error::invalid(
                "markers",
                self.markers,
                "must be in 2 ..= 64",
            ));
        }
        self.plant.validate()?;
        self.avoid.validate()?;
        obstacles.check_robot(&five_section_scene(self.avoid.model_elements).robot()?)
    }

    fn checked_obstacles(&self) -> Result<Obstacles> {
        Obstacles::new(self.obstacles.clone(), self.rod_radius_m)
    }

    /// Calibrates the model on an obstacle-free copy of the plant, then runs
    /// the avoidance ([`run_avoidance`]).
    ///
    /// # Errors
    /// As [`AvoidScene::validate`] and [`run_avoidance`].
    pub fn run(&self) -> Result<AvoidRun> {
        self.validate()?;
        let scene = five_section_scene(self.avoid.model_elements);
        let arcs = marker_arcs(self.markers);
        let arcs = arcs.as_slice();
        let cal = calibrate_on_free_plant(&scene, arcs, &self.plant)?;
        let mut plant = SimulatedPlant::new(&scene, arcs, self.plant.clone())?
            .with_obstacles(self.checked_obstacles()?)?;
        run_avoidance(&scene, &cal, arcs, &mut plant, self.goal(), &self.avoid)
    }

    /// [`AvoidScene::goal_m`] as a vector (m).
    ///
    /// # Example
    /// ```
    /// let s = softrod::touch::AvoidScene::from_json(r#"{"obstacles": [], "goal_m": [0.15, -0.4]}"#)?;
    /// assert_eq!(s.goal(), nalgebra::Vector2::new(0.15, -0.4));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn goal(&self) -> nalgebra::Vector2<f64> {
        nalgebra::Vector2::from(self.goal_m)
    }
}
