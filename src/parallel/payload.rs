//! The payload at the platform from the platform's position: the
//! concentrated-load estimation (32)–(35) of the paper, and the simulated
//! experiment of its Fig. 8 (masses hung from the platform, the mass
//! estimated from the platform marker's displacement).
//!
//! The unknown is the force `F ∈ R³` on the platform's centre, its
//! generalized force `Q_F = A_xᵀ F` (34) with `A_x` the rows of the
//! platform's position in `q` (32), the rows of its site
//! ([`crate::site::Site::Body`]); the equations are the equilibrium (35)
//! and the measured position `x̄ = A_x q` (32). This is the estimation of a
//! force at a site ([`crate::estimate::LoadModel::AtSite`]) by the one
//! estimator of every model, with a vanishing penalty (three force
//! components from the three coordinates of one marker): its reduced
//! Gauss–Newton steps are `ΔF = C⁻¹ (x̄ − A_x q(F))`, `C = A_x T K_u⁻¹ Tᵀ A_xᵀ`
//! the platform's compliance (3 × 3, [`ParallelRobot::platform_compliance`]),
//! and it reports the force's covariance `σ² C⁻¹ C⁻ᵀ` and its fit test.
//! The payload's mass is `m = F·g/|g|²`.
//!
//! Relative displacements (the paper's choice, "to reduce the influence of
//! the virtual payload"): the target is the model's unloaded platform
//! position plus the measured displacement between the unloaded and the
//! loaded robot, so an offset between model and robot that does not depend
//! on the payload cancels.

use nalgebra::{DVector, Matrix3, Vector3, Vector6};

use super::ParallelRobot;
use crate::element::Element;
use crate::error::{Error, Result, check_all_finite};
use crate::estimate::{Backend, EstimateStatus, EstimatorSettings, LoadModel};
use crate::observe::{MarkerObservation, Observation};
use crate::rng::Gaussian;
use crate::site::Site;
use crate::statics::Equilibrium;

pub use crate::estimate::PAYLOAD_ALPHA;

/// An estimated payload: the force at the platform's centre by the
/// estimator (either backend, with the force at the platform's site,
/// [`crate::estimate::LoadModel::AtSite`]).
///
/// # Example
/// ```
/// use nalgebra::Vector3;
/// use softrod::estimate::{EstimateCriterion, EstimateStatus};
/// let e = softrod::parallel::payload::PayloadEstimate {
///     force_n: Vector3::new(0.0, 0.0, -0.981), std_n: Vector3::new(0.01, 0.01, 0.003), mass_kg: 0.1,
///     std_kg: 0.0003, iterations: 3, residual_m: 1e-12,
///     status: EstimateStatus::Converged(EstimateCriterion::WithinNoise) };
/// assert_eq!(e.mass_kg, 0.1);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct PayloadEstimate {
    /// The force on the platform's centre (N, world axes).
    pub force_n: Vector3<f64>,
    /// Its standard deviations (N) under the marker noise given.
    pub std_n: Vector3<f64>,
    /// Its mass, `F·g/|g|²` (kg).
    pub mass_kg: f64,
    /// The mass's standard deviation (kg): that of `F·g/|g|²`.
    pub std_kg: f64,
    /// Iterations of the estimator.
    pub iterations: usize,
    /// The distance of the model's platform from the target at the end (m).
    pub residual_m: f64,
    /// The estimator's status (its fit test on the answer).
    pub status: EstimateStatus,
}

impl<E: Element> ParallelRobot<E> {
    /// The platform's compliance `C = ∂x/∂F` (m/N, 3 × 3) at the
    /// equilibrium `eq` under `loads` (from the tangent).
    ///
    /// # Errors
    /// [`Error::Singular`] for a singular tangent; sizes as
    /// [`crate::structure::Structure::residual_and_tangent`].
    ///
    /// # Example
    /// ```
    /// let robot = softrod::parallel::ParallelSpec::default().build_full()?;
    /// let loads = robot.loads(&[], [0.0; 3], [0.0; 3])?;
    /// let eq = robot.solve(&loads, None)?;
    /// let c = robot.platform_compliance(&eq, &loads)?;
    /// // the vertical compliance: about L/(3 EA) (the legs lean a little)
    /// assert!(c[(2, 2)] > 0.12 / 900.0 && c[(2, 2)] < 2.0 * 0.12 / 900.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn platform_compliance(
        &self,
        eq: &Equilibrium,
        loads: &crate::structure::StructureLoads,
    ) -> Result<Matrix3<f64>> {
        let s = &self.structure;
        let dead: Vec<f64> = s.dead_force(loads)?.data.into();
        let (_, k) = s.residual_and_tangent(eq.u.as_slice(), &dead, loads)?;
        let k = k.to_dense();
        let n = k.nrows();
        let x0 = self.platform_free_start()?;
        let lu = k.lu();
        let mut c = Matrix3::zeros();
        for j in 0..3 {
            let mut e = DVector::zeros(n);
            e[x0 + j] = 1.0;
            let col = lu.solve(&e).ok_or_else(|| Error::Singular {
                context: "the parallel robot's tangent (platform compliance)".into(),
                index: 0,
                pivot: 0.0,
                scale: 0.0,
            })?;
            for i in 0..3 {
                c[(i, j)] = col[x0 + i];
            }
        }
        Ok(c)
    }

    /// The payload force on the platform's centre that puts the platform
    /// at `target_m` under the chamber pressures `pressures_pa` (32)–(35):
    /// the estimate of a force at the platform's site from one marker
    /// there, with the marker noise `noise_sigma_m` (m) for its standard
    /// deviations, by the one estimator of every model and the backend
    /// `backend` (its warm tracker, its fit test, its covariance; both
    /// backends reach the same estimate). For bounds on the force, build
    /// the estimator on [`ParallelRobot::structure`] with
    /// [`EstimatorSettings::build_for`] and the sqp backend.
    ///
    /// # Errors
    /// As [`ParallelRobot::loads`]; [`Error::InvalidParameter`]
    /// (`target_m`) for a non-finite target; as
    /// [`crate::estimate::Estimator::step`].
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::Backend;
    /// let robot = softrod::parallel::ParallelSpec::default().build_full()?;
    /// // the platform where a 10 g payload puts it
    /// let loaded = robot.solve(&robot.loads(&[], [0.0, 0.0, -0.0981], [0.0; 3])?, None)?;
    /// let x = robot.platform_pose(loaded.q.as_slice())?;
    /// let target = x.fixed_rows::<3>(0).into_owned();
    /// let e = robot.estimate_payload(&[], target, 5e-5, Backend::Newton)?;
    /// assert!(e.status.is_converged());
    /// assert!((e.mass_kg - 0.01).abs() < 1e-6);
    /// // 0.05 mm of marker noise: grams of uncertainty (the compliance is 1.4e-4 m/N)
    /// assert!(e.std_kg > 1e-3 && e.std_kg < 0.1);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn estimate_payload(
        &self,
        pressures_pa: &[f64],
        target_m: impl Into<nalgebra::Vector3<f64>>,
        noise_sigma_m: f64,
        backend: Backend,
    ) -> Result<PayloadEstimate> {
        let target_m: [f64; 3] = target_m.into().into();
        check_all_finite("target_m", &target_m)?;
        let known = self.loads(pressures_pa, [0.0; 3], [0.0; 3])?;
        let platform = Site::Body { body: 0 };
        let settings = EstimatorSettings {
            backend,
            load_model: LoadModel::AtSite { site: platform },
            alpha: Some(PAYLOAD_ALPHA),
            noise_sigma_m,
            ..EstimatorSettings::default()
        };
        let mut estimator = settings.build_for(&self.structure, &known)?;
        let observation = Observation {
            markers: vec![MarkerObservation::at_site(&platform, target_m.to_vec())],
        };
        let e = estimator.step(&observation)?;
        let force_n = Vector3::from_iterator(e.f.iter().copied());
        let cov = e.covariance_f();
        let std_n = Vector3::from_fn(|k, _| cov[(k, k)].max(0.0).sqrt());
        let g = Vector3::from_column_slice(&self.spec.gravity_m_per_s2);
        let g2 = g.norm_squared();
        let (mass_kg, std_kg) = if g2 > 0.0 {
            let gm = g / g2;
            let c3 = cov.view((0, 0), (3, 3));
            (
                force_n.dot(&gm),
                (gm.transpose() * c3 * gm)[(0, 0)].max(0.0).sqrt(),
            )
        } else {
            (0.0, 0.0)
        };
        let x = self.platform_pose(e.q.as_slice())?;
        let residual_m = (0..3)
            .map(|i| (target_m[i] - x[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        Ok(PayloadEstimate {
            force_n,
            std_n,
            mass_kg,
            std_kg,
            iterations: e.report.iterations,
            residual_m,
            status: e.report.status,
        })
    }
}

/// What a simulated payload trial measures: the plant's platform marker,
/// unloaded and loaded, with noise.
///
/// # Example
/// ```
/// let t = softrod::parallel::payload::MassTrial { configuration: 0, mass_kg: 0.1, estimate_kg: 0.098 };
/// assert!((t.error_kg().abs() - 0.002).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MassTrial {
    /// Which pressure configuration.
    pub configuration: usize,
    /// The hung mass (kg).
    pub mass_kg: f64,
    /// Its estimate (kg).
    pub estimate_kg: f64,
}

impl MassTrial {
    /// `estimate − mass` (kg).
    pub fn error_kg(&self) -> f64 {
        self.estimate_kg - self.mass_kg
    }
}

/// The measurement of a trial: the marker noise and how many frames are
/// averaged per static pose.
///
/// # Example
/// ```
/// let m = softrod::parallel::payload::Measurement::default();
/// assert_eq!(m.sigma_m, 0.05e-3);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// Standard deviation of every marker coordinate per frame (m).
    pub sigma_m: f64,
    /// Frames averaged per static pose (a hung weight is still: the
    /// camera's frames of a second or so).
    pub frames: usize,
    /// Seed of the noise.
    pub seed: u64,
}

impl Default for Measurement {
    /// σ = 0.05 mm, one frame.
    fn default() -> Self {
        Measurement {
            sigma_m: 0.05e-3,
            frames: 1,
            seed: 1,
        }
    }
}

/// The experiment of Fig. 8: for every configuration (chamber pressures)
/// and every mass, the plant hangs the mass from the platform, the marker
/// measures the platform unloaded and loaded (noise, averaged frames), and
/// the model estimates the mass from the relative displacement.
///
/// # Errors
/// As [`ParallelRobot::solve`] and [`ParallelRobot::estimate_payload`].
///
/// # Example
/// ```
/// use softrod::parallel::{payload::{mass_experiment, Measurement}, ParallelSpec};
/// let model = ParallelSpec::default().build_full()?;
/// // a noise-free plant equal to the model recovers the mass
/// let m = Measurement { sigma_m: 0.0, ..Measurement::default() };
/// let trials = mass_experiment(&model, &model, &[nalgebra::DVector::zeros(0)], &[0.1], m)?;
/// assert!(trials[0].error_kg().abs() < 1e-9);
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn mass_experiment<E: Element, P: Element>(
    model: &ParallelRobot<E>,
    plant: &ParallelRobot<P>,
    configurations: &[DVector<f64>],
    masses_kg: &[f64],
    measurement: Measurement,
) -> Result<Vec<MassTrial>> {
    let mut noise = Gaussian::new(measurement.seed);
    let frames = measurement.frames.max(1);
    let mut measure = |x: Vector6<f64>| -> [f64; 3] {
        let mut m = [0.0; 3];
        for _ in 0..frames {
            for (mi, xi) in m.iter_mut().zip(&x) {
                *mi += xi + measurement.sigma_m * noise.sample();
            }
        }
        m.map(|v| v / frames as f64)
    };
    let g = &plant.spec.gravity_m_per_s2;
    let mut trials = Vec::with_capacity(configurations.len() * masses_kg.len());
    for (c, p) in configurations.iter().enumerate() {
        let p = p.as_slice();
        let plant_free = plant.solve(&plant.loads(p, [0.0; 3], [0.0; 3])?, None)?;
        let model_free = model.solve(&model.loads(p, [0.0; 3], [0.0; 3])?, None)?;
        let x_model = model.platform_pose(model_free.q.as_slice())?;
        for &m in masses_kg {
            let weight = [0, 1, 2].map(|i| m * g[i]);
            let loaded = plant.solve(
                &plant.loads(p, weight, [0.0; 3])?,
                Some(plant_free.q.as_slice()),
            )?;
            let before = measure(plant.platform_pose(plant_free.q.as_slice())?);
            let after = measure(plant.platform_pose(loaded.q.as_slice())?);
            let target = [0, 1, 2].map(|i| x_model[i] + after[i] - before[i]);
            let e = model.estimate_payload(
                p,
                target,
                measurement_sigma(&measurement),
                Backend::Newton,
            )?;
            if !e.status.is_converged() {
                return Err(Error::EstimateNotConverged {
                    status: e.status,
                    iterations: e.iterations,
                });
            }
            trials.push(MassTrial {
                configuration: c,
                mass_kg: m,
                estimate_kg: e.mass_kg,
            });
        }
    }
    Ok(trials)
}

/// The noise of a measured target (m): the model's unloaded platform plus
/// the difference of two platform measurements, each the mean of `frames`
/// frames of noise `sigma_m`, so `sigma_m √(2 / frames)`; a noise-free
/// measurement weighs as 1 nm (the estimator needs a positive noise).
fn measurement_sigma(m: &Measurement) -> f64 {
    (m.sigma_m * (2.0 / m.frames.max(1) as f64).sqrt()).max(1e-9)
}

/// The three configurations of the simulated Fig. 8 experiment (chamber
/// pressures, Pa): all chambers vented; chamber 0 of every leg's first
/// section at 40 kPa (the legs bend alike, the platform shifts and turns);
/// one chamber per leg at 50 kPa, a different one on each leg (the legs
/// bend apart).
///
/// # Example
/// ```
/// let spec = softrod::parallel::ParallelSpec::default();
/// let c = softrod::parallel::payload::fig8_configurations(&spec);
/// assert_eq!((c.len(), c[1].len()), (3, spec.n_pressures()));
/// assert_eq!(c[1][0], 40e3);
/// ```
pub fn fig8_configurations(spec: &super::ParallelSpec) -> Vec<DVector<f64>> {
    let n = spec.n_pressures();
    let per_leg = spec.sections_per_leg * super::CHAMBERS_PER_SECTION;
    let mut alike = vec![0.0; n];
    let mut apart = vec![0.0; n];
    for leg in 0..spec.legs {
        alike[leg * per_leg] = 40e3;
        // leg 0 section 1 chamber 0, leg 1 section 2 chamber 0, leg 2 section 1 chamber 1, …
        let k = (leg * super::CHAMBERS_PER_SECTION) % per_leg + leg / spec.sections_per_leg.max(1);
        apart[leg * per_leg + k % per_leg] = 50e3;
    }
    vec![
        DVector::zeros(n),
        DVector::from_vec(alike),
        DVector::from_vec(apart),
    ]
}

/// The "real robot" of the simulated experiments: the model's numbers off
/// by realistic amounts, on a finer mesh. EI +15 % and chamber gain −10 %
/// (the spec's example errors), GJ +10 % (torsion is not identified by a
/// bending test), EA +2 % (what a static loading test identifies the
/// vertical stiffness to: the platform's vertical compliance is mostly the
/// legs' axial one, and its error is the estimate's relative error), twice
/// the elements.
///
/// # Example
/// ```
/// let model = softrod::parallel::ParallelSpec::default();
/// let plant = softrod::parallel::payload::plant_spec(&model);
/// assert_eq!(plant.elements_per_section, 2 * model.elements_per_section);
/// ```
pub fn plant_spec(model: &super::ParallelSpec) -> super::ParallelSpec {
    let mut p = model.clone();
    p.ei_nm2 *= 1.15;
    p.gj_nm2 *= 1.10;
    p.ea_n *= 1.02;
    p.gain_nm_per_pa *= 0.9;
    p.elements_per_section *= 2;
    p
}

/// Frames averaged per static pose in the simulated experiment: 500, four
/// seconds of a 120 Hz camera. With σ = 0.05 mm per frame and one frame the
/// payload's 0.14–0.17 mm/N vertical compliance turns the noise of a
/// displacement (0.07 mm) into 30–50 g (measured, mean over 0–200 g); 500
/// frames take the noise to 3 µm.
pub const FIG8_FRAMES: usize = 500;
