//! The weighing experiment of Fig. 8 against a simulated plant: a mass is
//! hung at one point of the robot held at fixed pressures, the end
//! effector is measured before and after, and [`MassEstimator`] reads the
//! mass off the displacement.
//!
//! Every weighing is one [`SimulatedPlant`] (finer mesh, parameter errors,
//! marker noise, regulator lag; see [`PlantSettings`]) commanded to the
//! configuration's pressures; the mass is put on at `hang_s` and the end
//! effector averaged over `frames` frames before it (after the regulator
//! settled) and `frames` frames after the loaded robot settled. One
//! weighing of a known mass (its own noise seed) calibrates the estimator's
//! scale ([`MassEstimator::calibrate`]) for all configurations.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_len};
use crate::plant::{Payload, PayloadKind, PayloadSchedule, Plant, PlantSettings, SimulatedPlant};
use crate::scene::Scene;

use super::{MassEstimator, MassSettings};

/// The sampling rate of the weighings (Hz).
const RATE_HZ: f64 = 30.0;

/// One configuration: a name and its chamber pressures (Pa).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MassConfiguration {
    /// Name.
    pub name: String,
    /// Chamber pressures (Pa).
    pub pressures_pa: Vec<f64>,
}

/// The experiment; every field is documented with its unit.
///
/// # Example
/// ```
/// let e = softrod::control::WeighingExperiment::paper_like(softrod::scene::Scene::two_section());
/// assert_eq!(e.configurations.len(), 3);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct WeighingExperiment {
    /// The nominal scene (the estimator's model; the plant is built from it
    /// with `plant`'s differences).
    pub scene: Scene,
    /// How the plant differs from the model (its payloads are replaced).
    pub plant: PlantSettings,
    /// Where the mass hangs (m of undeformed arc; a node of the model).
    pub load_s_m: f64,
    /// The configurations.
    pub configurations: Vec<MassConfiguration>,
    /// The masses hung in each (kg).
    pub masses_kg: Vec<f64>,
    /// Frames averaged per state (unloaded, loaded).
    pub frames: usize,
    /// The calibration weighing: configuration index, known mass (kg),
    /// noise seed; `None`: no calibration (scale 1).
    pub calibration: Option<(usize, f64, u64)>,
    /// The estimator's settings.
    pub settings: MassSettings,
}

impl WeighingExperiment {
    /// The Fig. 8 experiment on `scene`'s robot: a mass of 0–200 g (steps of
    /// 20 g) at the tip; three configurations (straight, an S at
    /// (60, 0, 0, 30) kPa, curled up at (80, 0, 60, 0) kPa); ten frames per
    /// state; the default plant; calibration with 150 g in the first
    /// configuration (seed 99, not a seed of the weighings). The
    /// estimator's noise is that of a displacement of two means of ten
    /// frames of the plant's marker noise, `σ √(2/10)`.
    pub fn paper_like(scene: Scene) -> Self {
        let length: f64 = scene.robot.sections.iter().map(|s| s.length_m).sum();
        let plant = PlantSettings::default();
        let frames = 10;
        let noise_sigma_m = plant.noise_sigma_m * (2.0 / f64::from(frames)).sqrt();
        let configuration = |name: &str, p: [f64; 4]| MassConfiguration {
            name: name.into(),
            pressures_pa: p.to_vec(),
        };
        WeighingExperiment {
            scene,
            plant,
            load_s_m: length,
            configurations: vec![
                configuration("straight (0, 0, 0, 0) kPa", [0.0; 4]),
                configuration("S (60, 0, 0, 30) kPa", [60e3, 0.0, 0.0, 30e3]),
                configuration("curled (80, 0, 60, 0) kPa", [80e3, 0.0, 60e3, 0.0]),
            ],
            masses_kg: (0..=10).map(|k| 0.02 * f64::from(k)).collect(),
            frames: frames as usize,
            calibration: Some((0, 0.15, 99)),
            settings: MassSettings {
                reference: super::MassReference::Matched,
                noise_sigma_m,
                ..MassSettings::default()
            },
        }
    }
}

/// One weighing.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MassRow {
    /// Configuration index.
    pub configuration: usize,
    /// The mass hung (kg).
    pub true_kg: f64,
    /// The estimate (kg), with the calibrated scale.
    pub estimated_kg: f64,
    /// The estimate before scaling (kg).
    pub raw_kg: f64,
    /// The measured end effector, unloaded and loaded (m).
    pub unloaded_m: Vec<f64>,
    /// See `unloaded_m`.
    pub loaded_m: Vec<f64>,
    /// Whether the estimator's iteration converged
    /// ([`super::MassEstimate::converged`]).
    pub converged: bool,
    /// The estimate's standard deviation (kg, scaled) under the
    /// estimator's noise ([`MassSettings::noise_sigma_m`]).
    pub std_kg: f64,
}

impl MassRow {
    /// The measured displacement `loaded − unloaded` of the end effector (m).
    ///
    /// # Example
    /// ```
    /// let r = softrod::control::MassRow {
    ///     configuration: 0, true_kg: 0.1, estimated_kg: 0.1, raw_kg: 0.1,
    ///     unloaded_m: vec![0.24, 0.0], loaded_m: vec![0.239, -0.01], converged: true,
    ///     std_kg: 1e-3,
    /// };
    /// assert!((r.displacement() - nalgebra::dvector![-0.001, -0.01]).norm() < 1e-15);
    /// assert_eq!(r.loaded() - r.unloaded(), r.displacement());
    /// ```
    pub fn displacement(&self) -> nalgebra::DVector<f64> {
        nalgebra::DVector::from_iterator(
            self.loaded_m.len().min(self.unloaded_m.len()),
            self.loaded_m
                .iter()
                .zip(&self.unloaded_m)
                .map(|(l, u)| l - u),
        )
    }

    /// [`MassRow::unloaded_m`] as a vector (m).
    ///
    /// # Example
    /// See [`MassRow::displacement`].
    pub fn unloaded(&self) -> nalgebra::DVector<f64> {
        nalgebra::DVector::from_column_slice(&self.unloaded_m)
    }

    /// [`MassRow::loaded_m`] as a vector (m).
    ///
    /// # Example
    /// See [`MassRow::displacement`].
    pub fn loaded(&self) -> nalgebra::DVector<f64> {
        nalgebra::DVector::from_column_slice(&self.loaded_m)
    }
}

/// The result of [`WeighingExperiment::run`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MassTable {
    /// The configurations.
    pub configurations: Vec<MassConfiguration>,
    /// The scale from the calibration weighing (1 without).
    pub scale: f64,
    /// Every weighing.
    pub rows: Vec<MassRow>,
}

impl MassTable {
    /// Mean absolute error of configuration `c` (kg), calibrated
    /// (`raw = false`) or raw.
    pub fn mean_abs_error_kg(&self, c: usize, raw: bool) -> f64 {
        let e: Vec<f64> = self
            .rows
            .iter()
            .filter(|r| r.configuration == c)
            .map(|r| (if raw { r.raw_kg } else { r.estimated_kg } - r.true_kg).abs())
            .collect();
        e.iter().sum::<f64>() / e.len().max(1) as f64
    }
}

impl WeighingExperiment {
    /// The end effector averaged before and after a mass `mass_kg` is hung,
    /// at `pressures_pa`, on a plant with noise seed `seed` (m).
    ///
    /// # Errors
    /// The plant's errors (invalid settings, pressures outside their
    /// bounds, a static solve that fails).
    ///
    /// # Example
    /// ```
    /// use softrod::{control::WeighingExperiment, scene::Scene};
    /// let mut w = WeighingExperiment::paper_like(Scene::two_section());
    /// w.frames = 2;
    /// let (unloaded, loaded) = w.weigh(&[0.0; 4], 0.1, 7)?;
    /// assert!(loaded.y < unloaded.y - 1e-3, "{unloaded} {loaded}"); // 100 g pulls the tip down
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn weigh(
        &self,
        pressures_pa: &[f64],
        mass_kg: f64,
        seed: u64,
    ) -> Result<(Vector2<f64>, Vector2<f64>)> {
        let dt = 1.0 / RATE_HZ;
        let n = self.frames.max(1);
        // settle 10 frames, average n; hang; settle 10, average n
        let hang_s = (10 + n) as f64 * dt + 0.5 * dt;
        let settings = PlantSettings {
            seed,
            payloads: PayloadSchedule {
                payloads: vec![Payload {
                    kind: PayloadKind::PointMass {
                        mass_kg,
                        s_m: self.load_s_m,
                    },
                    start_s: hang_s,
                    end_s: None,
                }],
            },
            ..self.plant.clone()
        };
        let length: f64 = self.scene.robot.sections.iter().map(|s| s.length_m).sum();
        let mut plant = SimulatedPlant::new(&self.scene, &[length], settings)?;
        plant.command(pressures_pa)?;
        let average = |plant: &mut SimulatedPlant| -> Result<Vector2<f64>> {
            for _ in 0..10 {
                plant.advance(dt)?;
            }
            let mut sum = Vector2::zeros();
            for _ in 0..n {
                let f = plant.advance(dt)?;
                let x = f.positions_m.first().ok_or_else(|| {
                    Error::invalid("markers", "[]", "the plant returned no marker")
                })?;
                check_len("markers[0]", 2, x.len())?;
                sum += Vector2::new(x[0], x[1]);
            }
            Ok(sum / n as f64)
        };
        let unloaded = average(&mut plant)?;
        let loaded = average(&mut plant)?;
        Ok((unloaded, loaded))
    }

    /// Runs the calibration weighing (if any) and every weighing.
    ///
    /// # Errors
    /// As [`WeighingExperiment::weigh`], [`MassEstimator::new`],
    /// [`MassEstimator::calibrate`], [`MassEstimator::estimate`];
    /// [`Error::IndexOutOfRange`] for a calibration configuration that does
    /// not exist.
    pub fn run(&self) -> Result<MassTable> {
        let robot = self.scene.robot()?;
        let mut est = MassEstimator::new(
            robot,
            self.scene.loads()?,
            self.load_s_m,
            &self.scene.gravity_m_per_s2,
            self.settings.clone(),
        )?;
        if let Some((c, known, seed)) = self.calibration {
            crate::error::check_index("calibration.configuration", c, self.configurations.len())?;
            let p = &self.configurations[c].pressures_pa;
            let (u, l) = self.weigh(p, known, seed)?;
            est.calibrate(p, u.as_slice(), l.as_slice(), known)?;
        }
        let mut rows = Vec::new();
        for (c, conf) in self.configurations.iter().enumerate() {
            for &m in &self.masses_kg {
                let (u, l) = self.weigh(&conf.pressures_pa, m, self.plant.seed)?;
                let e = est.estimate(&conf.pressures_pa, u.as_slice(), l.as_slice())?;
                rows.push(MassRow {
                    configuration: c,
                    true_kg: m,
                    estimated_kg: e.mass_kg,
                    raw_kg: e.mass_kg / est.scale(),
                    unloaded_m: u.as_slice().to_vec(),
                    loaded_m: l.as_slice().to_vec(),
                    converged: e.converged,
                    std_kg: e.std_kg,
                });
            }
        }
        Ok(MassTable {
            configurations: self.configurations.clone(),
            scale: est.scale(),
            rows,
        })
    }
}
