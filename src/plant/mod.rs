//! The robot a controller acts on: a [`Plant`] takes pressures, advances
//! time and returns marker positions — nothing else leaves it.
//!
//! [`SimulatedPlant`] stands in for the real robot. It is built from its own
//! copy of the scene and is deliberately *not* the controller's model:
//!
//! - a finer mesh ([`PlantSettings::mesh_factor`] × the elements of every
//!   section, default 2);
//! - parameter errors: bending stiffness `EI × 1.15`, actuation gain
//!   `× 0.90`, axial stiffness `EA × 0.95` (defaults);
//! - payloads the controller is not told about, on a schedule in time
//!   ([`PayloadSchedule`]: none, point or tip masses, a distributed mass,
//!   several at once, one put on mid-run, one sliding along the backbone);
//! - seeded Gaussian marker noise (default σ = 0.05 mm per component);
//! - a first-order pressure regulator: the chamber pressure follows the
//!   command by `τ dP/dt = P_cmd − P` with `τ` = 0.02 s by default (the
//!   order of the step response of a proportional pneumatic regulator),
//!   integrated exactly over each interval for a command held constant;
//! - quasi-static equilibrium (17) at the end of every interval, solved by
//!   [`StaticSolver`] warm-started from the previous shape, or, with
//!   obstacles in the plant's world ([`SimulatedPlant::with_obstacles`]),
//!   by the exact contact solver ([`crate::contact`]).
//!
//! The truth (the shape without noise) is available on [`SimulatedPlant`]
//! itself for scoring a run; a controller only ever holds a `&mut dyn Plant`
//! or a generic `P: Plant`.

mod obstacles;
mod parallel;
mod payload;

pub use obstacles::PlantContact;
pub use parallel::ParallelPlant;
pub use payload::{Payload, PayloadKind, PayloadSchedule};

use nalgebra::{DVector, Vector2};
use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::element::PlanarCable;
use crate::error::{Error, Result, check_all_finite, check_len};
use crate::linsolve::AutoSolver;
use crate::loads::Loads;
use crate::observe::{MarkerObservation, Observation};
use crate::scene::Scene;
use crate::site::Site;
use crate::statics::StaticSolver;

/// Marker positions at one instant.
///
/// # Example
/// ```
/// let f = softrod::plant::MarkerFrame { time_s: 0.0, positions_m: vec![vec![0.24, 0.0]] };
/// assert_eq!(f.positions_m.len(), 1);
/// assert_eq!(f.position(0), Some(nalgebra::dvector![0.24, 0.0]));
/// assert_eq!(f.position(1), None);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MarkerFrame {
    /// Time of the frame (s).
    pub time_s: f64,
    /// One position per marker (m), in the order the plant was given them.
    pub positions_m: Vec<Vec<f64>>,
}

impl MarkerFrame {
    /// Marker `i`'s position as a vector (m), `None` past the last marker.
    ///
    /// # Example
    /// See [`MarkerFrame`].
    pub fn position(&self, i: usize) -> Option<DVector<f64>> {
        self.positions_m
            .get(i)
            .map(|p| DVector::from_column_slice(p))
    }

    /// The frame as an [`Observation`] of markers at the arc coordinates
    /// `s_m` (one per marker, m).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `s_m` does not have one entry per marker.
    pub fn observation(&self, s_m: &[f64]) -> Result<Observation> {
        check_len("marker arc coordinates", self.positions_m.len(), s_m.len())?;
        let sites: Vec<Site> = s_m.iter().map(|&s_m| Site::Rod { rod: 0, s_m }).collect();
        self.observation_at(&sites)
    }

    /// The frame as an observation of markers at the sites `sites` (one
    /// per position, in order: the rods' arc coordinates or a body's
    /// reference point, [`MarkerObservation::at_site`]).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] when the counts differ.
    ///
    /// # Example
    /// ```
    /// use softrod::{plant::MarkerFrame, site::Site};
    /// let f = MarkerFrame { time_s: 0.0, positions_m: vec![vec![0.0, 0.0, 0.3]] };
    /// let obs = f.observation_at(&[Site::Body { body: 0 }])?;
    /// assert_eq!(obs.markers[0].body, Some(0));
    /// assert!(f.observation_at(&[]).is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn observation_at(&self, sites: &[Site]) -> Result<Observation> {
        check_len("marker sites", self.positions_m.len(), sites.len())?;
        Ok(Observation {
            markers: self
                .positions_m
                .iter()
                .zip(sites)
                .map(|(p, site)| MarkerObservation::at_site(site, p.clone()))
                .collect(),
        })
    }
}

/// A robot under control: pressures in, marker positions out.
///
/// # Example
/// ```
/// use softrod::plant::{Plant, PlantSettings, SimulatedPlant};
/// let scene = softrod::scene::Scene::two_section();
/// let mut plant = SimulatedPlant::new(&scene, &[0.12, 0.24], PlantSettings::default())?;
/// plant.command(&[20e3, 0.0, 0.0, 0.0])?;
/// let frame = plant.advance(1.0 / 30.0)?;
/// assert_eq!(frame.positions_m.len(), 2);
/// # Ok::<(), softrod::Error>(())
/// ```
pub trait Plant {
    /// Number of chambers.
    fn n_pressures(&self) -> usize;
    /// Sets the commanded chamber pressures (Pa), held until the next command.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (field `pressures_pa[i]`) for a pressure
    /// outside the chamber's bounds or not finite;
    /// [`Error::DimensionMismatch`] for the wrong count.
    fn command(&mut self, pressures_pa: &[f64]) -> Result<()>;
    /// Advances time by `dt_s` (s) and returns the markers at the new time.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (field `dt_s`) for `dt_s ≤ 0` or not
    /// finite; the plant's own failures (a static solve that does not
    /// converge).
    fn advance(&mut self, dt_s: f64) -> Result<MarkerFrame>;
    /// The current time (s).
    fn time_s(&self) -> f64;
}

/// How a [`SimulatedPlant`] differs from the nominal scene; every field has a
/// documented default.
///
/// # Example
/// ```
/// let s = softrod::plant::PlantSettings::default();
/// assert_eq!((s.mesh_factor, s.ei_factor, s.gain_factor, s.ea_factor), (2, 1.15, 0.9, 0.95));
/// s.validate()?;
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PlantSettings {
    /// Elements per section: this many times the nominal scene's (default 2).
    pub mesh_factor: usize,
    /// Factor on every section's `EI` (default 1.15).
    pub ei_factor: f64,
    /// Factor on every chamber's actuation gain (default 0.90).
    pub gain_factor: f64,
    /// Factor on every section's `EA` (default 0.95).
    pub ea_factor: f64,
    /// Marker noise, standard deviation per component (m, default 5e-5).
    pub noise_sigma_m: f64,
    /// Seed of the marker noise (default 1).
    pub seed: u64,
    /// Time constant of the first-order pressure regulator (s, default 0.02;
    /// 0 = no lag).
    pub regulator_time_constant_s: f64,
    /// The payloads (default none).
    pub payloads: PayloadSchedule,
}

impl Default for PlantSettings {
    fn default() -> Self {
        PlantSettings {
            mesh_factor: 2,
            ei_factor: 1.15,
            gain_factor: 0.90,
            ea_factor: 0.95,
            noise_sigma_m: 5e-5,
            seed: 1,
            regulator_time_constant_s: 0.02,
            payloads: PayloadSchedule::none(),
        }
    }
}

/// The range of the plant's model-error factors (`ei_factor`,
/// `gain_factor`, `ea_factor`): a plant 100 times stiffer or softer than
/// its model is no model error; far beyond, the plant's stiffnesses
/// overflow (and were refused under the scene's field names).
pub const MODEL_FACTOR_RANGE: (f64, f64) = (1e-2, 1e2);

/// The largest marker noise of the simulated plant (m): 1 mm, twenty times
/// the default and ten times a motion-capture system's (at `1e308` the
/// markers read 1e307 m; at 1 cm the loop lost the 0.24 m robot in 4
/// samples).
pub const MAX_NOISE_SIGMA_M: f64 = 1e-3;

/// The largest time constant of the pressure regulator (s): one hour.
pub const MAX_REGULATOR_TIME_CONSTANT_S: f64 = 3600.0;

impl PlantSettings {
    /// Checks every field (the payloads are checked against the robot by
    /// [`SimulatedPlant::new`]).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field: `mesh_factor` outside
    /// 1 ..= 64, a factor outside [`MODEL_FACTOR_RANGE`], a noise above
    /// [`MAX_NOISE_SIGMA_M`], a regulator slower than
    /// [`MAX_REGULATOR_TIME_CONSTANT_S`], anything negative or not finite.
    pub fn validate(&self) -> Result<()> {
        if self.mesh_factor == 0 || self.mesh_factor > 64 {
            return Err(Error::invalid(
                "plant.mesh_factor",
                self.mesh_factor,
                "must be in 1 ..= 64",
            ));
        }
        let (lo, hi) = MODEL_FACTOR_RANGE;
        for (name, v) in [
            ("plant.ei_factor", self.ei_factor),
            ("plant.gain_factor", self.gain_factor),
            ("plant.ea_factor", self.ea_factor),
        ] {
            if !(v.is_finite() && (lo..=hi).contains(&v)) {
                return Err(Error::invalid(
                    name,
                    v,
                    format!("must lie in [{lo}, {hi}]: a factor on the model's value"),
                ));
            }
        }
        for (name, v, max) in [
            ("plant.noise_sigma_m", self.noise_sigma_m, MAX_NOISE_SIGMA_M),
            (
                "plant.regulator_time_constant_s",
                self.regulator_time_constant_s,
                MAX_REGULATOR_TIME_CONSTANT_S,
            ),
        ] {
            if !(v.is_finite() && v >= 0.0 && v <= max) {
                return Err(Error::invalid(
                    name,
                    v,
                    format!("must be >= 0 and at most {max:e}"),
                ));
            }
        }
        Ok(())
    }
}

/// A simulated robot that is not the controller's model (see the [module
/// documentation](self)).
///
/// # Example
/// See [`Plant`].
#[derive(Debug, Clone)]
pub struct SimulatedPlant {
    scene: Scene,
    robot: Robot<PlanarCable>,
    settings: PlantSettings,
    marker_s_m: Vec<f64>,
    base_loads: Loads,
    solver: StaticSolver,
    linear: AutoSolver,
    time_s: f64,
    commanded_pa: Vec<f64>,
    actual_pa: Vec<f64>,
    q: Vec<f64>,
    noise_draws: u64,
    /// Obstacles in the plant's world (see [`SimulatedPlant::with_obstacles`]).
    contact: Option<PlantContact>,
}

impl SimulatedPlant {
    /// The plant of the nominal scene `nominal` with the differences of
    /// `settings`, observed by markers at the arc coordinates `marker_s_m`
    /// (m), starting at rest in equilibrium at the scene's pressures.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field for invalid settings,
    /// payloads or marker coordinates; the errors of [`Scene::robot`] and of
    /// the static solve.
    pub fn new(nominal: &Scene, marker_s_m: &[f64], settings: PlantSettings) -> Result<Self> {
        settings.validate()?;
        let mut scene = nominal.clone();
        scene.name = format!("{} (plant)", nominal.name);
        for s in &mut scene.robot.sections {
            s.elements = s.elements.saturating_mul(settings.mesh_factor);
            s.ei_nm2 *= settings.ei_factor;
            s.ea_n *= settings.ea_factor;
            for c in &mut s.chambers {
                c.gain_nm_per_pa
                    .iter_mut()
                    .for_each(|g| *g *= settings.gain_factor);
            }
        }
        let robot = scene.robot()?;
        let length = robot.length();
        settings
            .payloads
            .validate(length)
            .map_err(|e| e.with_prefix("plant."))?;
        for (i, &s) in marker_s_m.iter().enumerate() {
            if !(s.is_finite() && (0.0..=length).contains(&s)) {
                return Err(Error::invalid(
                    format!("markers[{i}].s_m"),
                    s,
                    format!("must lie on the robot, in [0, {length}] m"),
                ));
            }
        }
        let base_loads = scene.loads()?;
        let pressures = base_loads.pressures_pa.clone();
        let solver = StaticSolver::new(scene.solver.statics.clone())?;
        let mut linear =
            AutoSolver::with_kind(robot.tangent_pattern(), solver.settings.linear_solver)?;
        let loads0 = settings
            .payloads
            .loads_at(0.0, &scene.gravity_m_per_s2, &base_loads);
        let q = solver
            .solve_with(&robot, &loads0, None, &mut linear)?
            .q
            .data
            .into();
        Ok(SimulatedPlant {
            scene,
            robot,
            settings,
            marker_s_m: marker_s_m.to_vec(),
            base_loads,
            solver,
            linear,
            time_s: 0.0,
            commanded_pa: pressures.clone(),
            actual_pa: pressures,
            q,
            noise_draws: 0,
            contact: None,
        })
    }

    /// The plant's own scene (finer mesh, parameter errors applied).
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The plant's robot.
    pub fn robot(&self) -> &Robot<PlanarCable> {
        &self.robot
    }

    /// The settings the plant was built with.
    pub fn settings(&self) -> &PlantSettings {
        &self.settings
    }

    /// The pressures in the chambers now, behind the command by the
    /// regulator's lag (Pa). For scoring only.
    pub fn actual_pressures_pa(&self) -> &[f64] {
        &self.actual_pa
    }

    /// The true (noise-free) marker positions now (m), one per marker. For
    /// scoring only: a controller sees [`Plant::advance`]'s noisy frame.
    ///
    /// # Errors
    /// As [`Robot::position_at`].
    ///
    /// # Example
    /// ```
    /// use softrod::plant::{PlantSettings, SimulatedPlant};
    /// let scene = softrod::scene::Scene::two_section();
    /// let plant = SimulatedPlant::new(&scene, &[0.12, 0.24], PlantSettings::default())?;
    /// let m = plant.true_markers_m()?;
    /// assert_eq!(m.len(), 2);
    /// assert!((m[1] - plant.true_tip_m()?).norm() < 1e-15);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn true_markers_m(&self) -> Result<Vec<Vector2<f64>>> {
        self.marker_s_m
            .iter()
            .map(|&s| self.robot.position_at_fixed::<2>(&self.q, s))
            .collect()
    }

    /// The true (noise-free) tip position now (m). For scoring only.
    ///
    /// # Errors
    /// As [`Robot::position_at`].
    ///
    /// # Example
    /// See [`SimulatedPlant::true_markers_m`].
    pub fn true_tip_m(&self) -> Result<Vector2<f64>> {
        self.robot
            .position_at_fixed::<2>(&self.q, self.robot.length())
    }
}

/// Checks a command against the chambers' `bounds` (Pa): one finite
/// pressure per chamber within its bounds.
fn check_command(bounds: &[(f64, f64)], pressures_pa: &[f64]) -> Result<()> {
    check_len("pressures_pa", bounds.len(), pressures_pa.len())?;
    check_all_finite("pressures_pa", pressures_pa)?;
    for (i, (p, &(lo, hi))) in pressures_pa.iter().zip(bounds).enumerate() {
        if *p < lo || *p > hi {
            return Err(Error::invalid(
                format!("pressures_pa[{i}]"),
                p,
                format!("must lie within the chamber's bounds [{lo}, {hi}] Pa"),
            ));
        }
    }
    Ok(())
}

impl Plant for SimulatedPlant {
    fn n_pressures(&self) -> usize {
        self.robot.n_pressures()
    }

    fn command(&mut self, pressures_pa: &[f64]) -> Result<()> {
        check_command(&self.robot.pressure_bounds(), pressures_pa)?;
        self.commanded_pa.copy_from_slice(pressures_pa);
        Ok(())
    }

    fn advance(&mut self, dt_s: f64) -> Result<MarkerFrame> {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(Error::invalid("dt_s", dt_s, "must be finite and > 0"));
        }
        // τ dP/dt = P_cmd − P, exact for a command held over the interval
        let tau = self.settings.regulator_time_constant_s;
        let decay = if tau > 0.0 { (-dt_s / tau).exp() } else { 0.0 };
        for (a, c) in self.actual_pa.iter_mut().zip(&self.commanded_pa) {
            *a = c + (*a - c) * decay;
        }
        self.time_s += dt_s;
        let mut base = self.base_loads.clone();
        base.pressures_pa.clone_from(&self.actual_pa);
        let loads =
            self.settings
                .payloads
                .loads_at(self.time_s, &self.scene.gravity_m_per_s2, &base);
        self.q = match self.contact.as_mut() {
            Some(c) => c.solve(&self.robot, &loads, &self.q)?,
            None => self
                .solver
                .solve_with(&self.robot, &loads, Some(&self.q), &mut self.linear)?
                .q
                .data
                .into(),
        };
        let truth = self.true_markers_m()?;
        let obs = Observation {
            markers: truth
                .into_iter()
                .map(|p| MarkerObservation::at_arc(0.0, p))
                .collect(),
        };
        // a fresh seed per frame: the seed and the frame count
        self.noise_draws = self.noise_draws.wrapping_add(1);
        let seed = self
            .settings
            .seed
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .wrapping_add(self.noise_draws);
        let noisy = obs.with_noise(self.settings.noise_sigma_m, seed);
        Ok(MarkerFrame {
            time_s: self.time_s,
            positions_m: noisy.markers.into_iter().map(|m| m.position_m).collect(),
        })
    }

    fn time_s(&self) -> f64 {
        self.time_s
    }
}
