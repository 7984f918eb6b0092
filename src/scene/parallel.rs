//! A soft parallel robot as a scene file: the robot's numbers (the
//! `parallel` object, [`ParallelSpec`]), the legs' element, the chamber
//! pressures and the loads on the platform.
//!
//! ```json
//! { "name": "parallel", "element": "ancf3d",
//!   "parallel": { "base_radius_m": 0.06, "platform_radius_m": 0.04, "leg_length_m": 0.12,
//!                 "sections_per_leg": 2, "elements_per_section": 4, "ea_n": 300, "ei_nm2": 0.025,
//!                 "gj_nm2": 0.0167, "mass_per_length_kg_per_m": 0.15, "platform_mass_kg": 0.05,
//!                 "gain_nm_per_pa": 3e-6 },
//!   "pressures_pa": [], "platform_force_n": [0, 0, -0.98], "platform_moment_nm": [0, 0, 0] }
//! ```
//!
//! A file is a parallel-robot scene when its top-level object has a
//! `parallel` key ([`ParallelScene::is_parallel`]); `softrod solve` and
//! `softrod estimate` then take this path.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::element::Element;
use crate::error::{Error, Result, check_all_finite, check_len};
use crate::estimate::Backend;
use crate::parallel::payload::PayloadEstimate;
use crate::parallel::{LegElement, ParallelRobot, ParallelSpec};
use crate::statics::Equilibrium;

fn ancf3d() -> LegElement {
    LegElement::Ancf3d
}

/// A parallel-robot scene.
///
/// # Example
/// ```
/// use softrod::scene::parallel::ParallelScene;
/// let s = ParallelScene::from_json(r#"{"parallel": {"base_radius_m": 0.06, "platform_radius_m": 0.04,
///   "leg_length_m": 0.12, "sections_per_leg": 2, "elements_per_section": 2, "ea_n": 300,
///   "ei_nm2": 0.025, "gj_nm2": 0.0167, "platform_mass_kg": 0.05, "gain_nm_per_pa": 3e-6}}"#)?;
/// let out = s.solve()?;
/// assert!(out.platform_pose[2] < -0.11);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParallelScene {
    /// Name.
    #[serde(default)]
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The legs' element (default `ancf3d`: the parallel robot needs the
    /// section frames, see `tests/parallel.rs`).
    #[serde(default = "ancf3d")]
    pub element: LegElement,
    /// The robot's numbers.
    pub parallel: ParallelSpec,
    /// Chamber pressures (Pa): none, or legs × sections × 3.
    #[serde(default)]
    pub pressures_pa: Vec<f64>,
    /// A known force on the platform's centre (N, world axes; empty for none).
    #[serde(default)]
    pub platform_force_n: Vec<f64>,
    /// A known moment on the platform (N·m, world axes; empty for none).
    #[serde(default)]
    pub platform_moment_nm: Vec<f64>,
    /// The noise of one platform-marker coordinate (m, in `(0, 1e-3]`;
    /// default 0.05 mm): the estimate's standard deviations (its target, a
    /// difference of two measurements, has `√2` times this).
    #[serde(default = "default_marker_sigma")]
    pub marker_sigma_m: f64,
    /// The estimator's backend for the payload estimate (default
    /// `newton`; `softrod estimate --backend` overrides it).
    #[serde(default)]
    pub backend: Backend,
}

/// The default [`ParallelScene::marker_sigma_m`]: 0.05 mm.
fn default_marker_sigma() -> f64 {
    0.05e-3
}

/// The largest [`ParallelScene::marker_sigma_m`] (m).
pub const MAX_MARKER_SIGMA_M: f64 = 1e-3;

/// What a solve of a parallel scene gives (written to JSON; typed by
/// [`ParallelSolution::platform_position`],
/// [`ParallelSolution::platform_rotation`] and [`ParallelSolution::leg`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ParallelSolution {
    /// The platform's pose: position of its centre (m), rotation vector (rad).
    pub platform_pose: [f64; 6],
    /// Every leg's node positions (m), base to platform.
    pub legs_m: Vec<Vec<[f64; 3]>>,
    /// Newton iterations.
    pub iterations: usize,
}

impl ParallelSolution {
    /// The position of the platform's centre (m).
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector3;
    /// use softrod::scene::parallel::ParallelSolution;
    /// let s = ParallelSolution {
    ///     platform_pose: [0.0, 0.0, -0.11, 0.0, 0.0, 0.01],
    ///     legs_m: vec![vec![[0.06, 0.0, 0.0], [0.04, 0.0, -0.11]]],
    ///     iterations: 4,
    /// };
    /// assert_eq!(s.platform_position(), Vector3::new(0.0, 0.0, -0.11));
    /// assert_eq!(s.platform_rotation(), Vector3::new(0.0, 0.0, 0.01));
    /// assert_eq!(s.leg(0).unwrap()[1], Vector3::new(0.04, 0.0, -0.11));
    /// assert!(s.leg(1).is_none());
    /// ```
    pub fn platform_position(&self) -> Vector3<f64> {
        Vector3::from_column_slice(&self.platform_pose[..3])
    }

    /// The platform's rotation vector (rad).
    ///
    /// # Example
    /// See [`ParallelSolution::platform_position`].
    pub fn platform_rotation(&self) -> Vector3<f64> {
        Vector3::from_column_slice(&self.platform_pose[3..])
    }

    /// Leg `i`'s node positions (m), base to platform; `None` past the last
    /// leg.
    ///
    /// # Example
    /// See [`ParallelSolution::platform_position`].
    pub fn leg(&self, i: usize) -> Option<Vec<Vector3<f64>>> {
        self.legs_m
            .get(i)
            .map(|nodes| nodes.iter().map(|p| Vector3::from(*p)).collect())
    }
}

impl ParallelScene {
    /// The known force on the platform's centre as a 3-D vector (N, world
    /// axes; zero if none is given).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `platform_force_n` if it has
    /// neither 0 nor 3 entries.
    ///
    /// # Example
    /// ```
    /// let s: softrod::scene::parallel::ParallelScene = serde_json::from_str(r#"{"parallel": {"base_radius_m": 0.05,
    ///   "platform_radius_m": 0.03, "leg_length_m": 0.12, "sections_per_leg": 2, "elements_per_section": 2,
    ///   "ea_n": 300, "ei_nm2": 0.025, "gj_nm2": 0.0167, "platform_mass_kg": 0.05, "gain_nm_per_pa": 3e-6},
    ///   "platform_force_n": [0, 0, -0.1]}"#)?;
    /// assert_eq!(s.platform_force()?.z, -0.1);
    /// assert_eq!(s.platform_moment()?, nalgebra::Vector3::zeros());
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn platform_force(&self) -> Result<nalgebra::Vector3<f64>> {
        if self.platform_force_n.is_empty() {
            return Ok(nalgebra::Vector3::zeros());
        }
        crate::numeric::fixed("platform_force_n", &self.platform_force_n)
    }

    /// The known moment on the platform as a 3-D vector (N·m, world axes;
    /// zero if none is given).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `platform_moment_nm` if it has
    /// neither 0 nor 3 entries.
    ///
    /// # Example
    /// See [`ParallelScene::platform_force`].
    pub fn platform_moment(&self) -> Result<nalgebra::Vector3<f64>> {
        if self.platform_moment_nm.is_empty() {
            return Ok(nalgebra::Vector3::zeros());
        }
        crate::numeric::fixed("platform_moment_nm", &self.platform_moment_nm)
    }

    /// Whether a scene text is a parallel-robot scene (its top-level object
    /// has a `parallel` key); malformed JSON is not.
    ///
    /// # Example
    /// ```
    /// use softrod::scene::parallel::ParallelScene;
    /// assert!(ParallelScene::is_parallel(r#"{"parallel": {}}"#));
    /// assert!(!ParallelScene::is_parallel(r#"{"robot": {}}"#));
    /// ```
    pub fn is_parallel(text: &str) -> bool {
        serde_json::from_str::<serde_json::Value>(text)
            .ok()
            .and_then(|v| v.as_object().map(|o| o.contains_key("parallel")))
            .unwrap_or(false)
    }

    /// Parses and validates a parallel scene.
    ///
    /// # Errors
    /// [`Error::Scene`] for malformed JSON, unknown or missing fields (the
    /// message starts with the field's path); the errors of
    /// [`ParallelScene::validate`].
    pub fn from_json(text: &str) -> Result<Self> {
        let s: ParallelScene = super::json::parse(text).map_err(|e| Error::Scene {
            message: e.located(),
        })?;
        s.validate()?;
        Ok(s)
    }

    /// Checks the scene: [`ParallelSpec::validate`] (fields `parallel.…`),
    /// the pressure count and the platform's loads.
    ///
    /// # Errors
    /// A typed error naming the field.
    ///
    /// # Example
    /// ```
    /// use softrod::scene::parallel::ParallelScene;
    /// let e = ParallelScene::from_json(r#"{"parallel": {"base_radius_m": 0.06, "platform_radius_m": 0.04,
    ///   "leg_length_m": 0.12, "sections_per_leg": 2, "elements_per_section": 2, "ea_n": 300,
    ///   "ei_nm2": 0.025, "gj_nm2": 0.0167, "platform_mass_kg": 0.05, "gain_nm_per_pa": 3e-6},
    ///   "platform_force_n": [0, 1]}"#).unwrap_err();
    /// assert_eq!(e.field(), Some("platform_force_n"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        self.parallel.validate()?;
        if !self.pressures_pa.is_empty() {
            check_len(
                "pressures_pa",
                self.parallel.n_pressures(),
                self.pressures_pa.len(),
            )?;
        }
        check_all_finite("pressures_pa", &self.pressures_pa)?;
        for (name, v) in [
            ("platform_force_n", &self.platform_force_n),
            ("platform_moment_nm", &self.platform_moment_nm),
        ] {
            if !v.is_empty() {
                check_len(name, 3, v.len())?;
            }
            check_all_finite(name, v)?;
        }
        crate::error::check_positive("marker_sigma_m", self.marker_sigma_m)?;
        if self.marker_sigma_m > MAX_MARKER_SIGMA_M {
            return Err(Error::invalid(
                "marker_sigma_m",
                self.marker_sigma_m,
                format!("must be at most {MAX_MARKER_SIGMA_M} m (a motion-capture marker's noise)"),
            ));
        }
        Ok(())
    }

    /// The noise of the estimate's target (m): two measurements of
    /// [`ParallelScene::marker_sigma_m`] each.
    fn noise_sigma_m(&self) -> f64 {
        self.marker_sigma_m * std::f64::consts::SQRT_2
    }

    fn vec3(v: &[f64]) -> [f64; 3] {
        match v {
            [a, b, c] => [*a, *b, *c],
            _ => [0.0; 3],
        }
    }

    /// The static equilibrium of the scene.
    ///
    /// # Errors
    /// As [`ParallelScene::validate`] and [`ParallelRobot::solve`].
    pub fn solve(&self) -> Result<ParallelSolution> {
        self.validate()?;
        match self.element {
            LegElement::Ancf3d => self.solve_with(&self.parallel.build_full()?),
            LegElement::SpatialCable => self.solve_with(&self.parallel.build_cable()?),
        }
    }

    fn loads_of<E: Element>(
        &self,
        robot: &ParallelRobot<E>,
        extra_n: [f64; 3],
    ) -> Result<crate::structure::StructureLoads> {
        let f = Self::vec3(&self.platform_force_n);
        robot.loads(
            &self.pressures_pa,
            [0, 1, 2].map(|i| f[i] + extra_n[i]),
            Self::vec3(&self.platform_moment_nm),
        )
    }

    fn solve_with<E: Element>(&self, robot: &ParallelRobot<E>) -> Result<ParallelSolution> {
        let eq = robot.solve(&self.loads_of(robot, [0.0; 3])?, None)?;
        solution(robot, &eq)
    }

    /// The payload force at the platform (32)–(35) from two measured
    /// platform positions (m): unloaded and loaded, under the scene's
    /// pressures and known loads (the relative displacement is applied to
    /// the model's unloaded platform).
    ///
    /// # Errors
    /// As [`ParallelScene::solve`] and
    /// [`ParallelRobot::estimate_payload`].
    pub fn estimate(
        &self,
        unloaded_m: impl Into<Vector3<f64>>,
        loaded_m: impl Into<Vector3<f64>>,
    ) -> Result<PayloadEstimate> {
        let unloaded_m: [f64; 3] = unloaded_m.into().into();
        let loaded_m: [f64; 3] = loaded_m.into().into();
        self.validate()?;
        PlatformMarkers {
            unloaded_m,
            loaded_m,
        }
        .check(self)?;
        match self.element {
            LegElement::Ancf3d => {
                self.estimate_with(&self.parallel.build_full()?, unloaded_m, loaded_m)
            }
            LegElement::SpatialCable => {
                self.estimate_with(&self.parallel.build_cable()?, unloaded_m, loaded_m)
            }
        }
    }

    fn estimate_with<E: Element>(
        &self,
        robot: &ParallelRobot<E>,
        unloaded_m: [f64; 3],
        loaded_m: [f64; 3],
    ) -> Result<PayloadEstimate> {
        if !self.platform_force_n.is_empty() {
            return Err(Error::invalid(
                "platform_force_n",
                format!("{:?}", self.platform_force_n),
                "the estimated payload is the platform's force: leave it out of the scene",
            ));
        }
        let free = robot.solve(&self.loads_of(robot, [0.0; 3])?, None)?;
        let x = robot.platform_pose(free.q.as_slice())?;
        let target = [0, 1, 2].map(|i| x[i] + loaded_m[i] - unloaded_m[i]);
        robot.estimate_payload(
            &self.pressures_pa,
            target,
            self.noise_sigma_m(),
            self.backend,
        )
    }
}

fn solution<E: Element>(robot: &ParallelRobot<E>, eq: &Equilibrium) -> Result<ParallelSolution> {
    let s = robot.structure();
    let mut legs = Vec::with_capacity(s.rods().len());
    for (i, rod) in s.rods().iter().enumerate() {
        let mut nodes = Vec::with_capacity(rod.n_nodes());
        for k in 0..rod.n_nodes() {
            let r = s.node_coordinates(i, k)?;
            nodes.push([eq.q[r.start], eq.q[r.start + 1], eq.q[r.start + 2]]);
        }
        legs.push(nodes);
    }
    Ok(ParallelSolution {
        platform_pose: robot.platform_pose(eq.q.as_slice())?.into(),
        legs_m: legs,
        iterations: eq.report.iterations,
    })
}

/// The markers file of a parallel estimate (`softrod estimate SCENE
/// --markers FILE` on a parallel scene): the platform marker unloaded and
/// loaded (m, world axes). Only their difference is used; it is applied to
/// the model's unloaded platform.
///
/// # Example
/// ```
/// use softrod::scene::parallel::{ParallelScene, PlatformMarkers};
/// let scene = ParallelScene::from_json(&std::fs::read_to_string("examples/parallel_estimate.json")?)?;
/// let m = PlatformMarkers::from_json(r#"{"unloaded_m": [0, 0, -0.118], "loaded_m": [0, 0, -0.1182]}"#, &scene)?;
/// assert!((m.loaded() - m.unloaded()).norm() < 1e-3);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlatformMarkers {
    /// The platform marker without the payload (m).
    pub unloaded_m: [f64; 3],
    /// The platform marker with the payload (m).
    pub loaded_m: [f64; 3],
}

impl PlatformMarkers {
    /// Parses a platform markers file and checks it against `scene`
    /// (see [`PlatformMarkers::check`]); a refusal names the field as
    /// written (`loaded_m[2]`; `(file)` when the JSON itself is broken).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field.
    ///
    /// # Example
    /// ```
    /// use softrod::scene::parallel::{ParallelScene, PlatformMarkers};
    /// let scene = ParallelScene::from_json(&std::fs::read_to_string("examples/parallel_estimate.json")?)?;
    /// let e = PlatformMarkers::from_json(r#"{"unloaded_m": [0, 0, -0.118], "loaded_m": [0, 0]}"#, &scene).unwrap_err();
    /// assert_eq!(e.field(), Some("loaded_m"), "{e}");
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn from_json(text: &str, scene: &ParallelScene) -> Result<PlatformMarkers> {
        let m: PlatformMarkers = super::json::parse(text)
            .map_err(|e| Error::invalid(e.name(), "as written", e.message))?;
        m.check(scene)?;
        Ok(m)
    }

    /// Checks the markers: every coordinate finite and within 1e12 leg
    /// lengths of the origin, and the loaded marker within one leg length
    /// of the unloaded one (a payload cannot move the platform further).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `unloaded_m[i]` or `loaded_m[i]`.
    ///
    /// # Example
    /// ```
    /// use softrod::scene::parallel::{ParallelScene, PlatformMarkers};
    /// let scene = ParallelScene::from_json(&std::fs::read_to_string("examples/parallel_estimate.json")?)?;
    /// let m = PlatformMarkers { unloaded_m: [0.0, 0.0, -0.118], loaded_m: [0.0, 0.0, -1.0] };
    /// assert_eq!(m.check(&scene).unwrap_err().field(), Some("loaded_m[2]"));
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn check(&self, scene: &ParallelScene) -> Result<()> {
        let leg = scene.parallel.leg_length_m;
        for (name, p) in [
            ("unloaded_m", &self.unloaded_m),
            ("loaded_m", &self.loaded_m),
        ] {
            check_all_finite(name, p)?;
            if let Some(i) = p.iter().position(|v| v.abs() > 1e12 * leg) {
                return Err(Error::invalid(
                    format!("{name}[{i}]"),
                    p[i],
                    format!("is more than 1e12 leg lengths ({leg} m) from the origin"),
                ));
            }
        }
        if let Some(i) = (0..3).find(|&i| (self.loaded_m[i] - self.unloaded_m[i]).abs() > leg) {
            return Err(Error::invalid(
                format!("loaded_m[{i}]"),
                self.loaded_m[i],
                format!(
                    "is {:.4e} m from `unloaded_m[{i}]` = {}: a payload moves the platform by less than a leg's length ({leg} m)",
                    self.loaded_m[i] - self.unloaded_m[i],
                    self.unloaded_m[i]
                ),
            ));
        }
        Ok(())
    }

    /// The unloaded marker (m).
    ///
    /// # Example
    /// ```
    /// let m = softrod::scene::parallel::PlatformMarkers { unloaded_m: [0.0, 0.0, -0.1], loaded_m: [0.0, 0.0, -0.11] };
    /// assert_eq!(m.unloaded().z, -0.1);
    /// ```
    pub fn unloaded(&self) -> nalgebra::Vector3<f64> {
        self.unloaded_m.into()
    }

    /// The loaded marker (m).
    ///
    /// # Example
    /// ```
    /// let m = softrod::scene::parallel::PlatformMarkers { unloaded_m: [0.0, 0.0, -0.1], loaded_m: [0.0, 0.0, -0.11] };
    /// assert_eq!(m.loaded().z, -0.11);
    /// ```
    pub fn loaded(&self) -> nalgebra::Vector3<f64> {
        self.loaded_m.into()
    }
}
