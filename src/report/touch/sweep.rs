//! One contact-localization experiment against the simulated plant, for
//! the sweep of contact positions, loads and marker counts: the plant (not
//! the model) bends into a disk placed at a chosen arc position and depth;
//! both localization methods see its noisy markers only.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::contact::{Obstacle, Obstacles};
use crate::error::{Error, Result};
use crate::estimate::{AlphaRule, Estimator, EstimatorSettings};
use crate::plant::{MarkerFrame, Plant, PlantSettings, SimulatedPlant};

use crate::touch::{
    FreeFrame, PointSearchSettings, ROD_RADIUS_M, calibrate, five_section_scene,
    locate_point_force, marker_arcs, marker_offset, peak_contact,
};

/// Radius of the disk the robot is pressed against in the sweep (m).
pub const PROBE_RADIUS_M: f64 = 0.02;

/// One localization experiment.
///
/// # Example
/// ```
/// let c = softrod::report::touch::LocalizationCase::new(0.3, 0.006, 6, 1);
/// assert_eq!((c.pressures_pa.len(), c.frames), (10, 20));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LocalizationCase {
    /// The chamber pressures (Pa), held.
    pub pressures_pa: Vec<f64>,
    /// Where the disk is put: the arc coordinate of the contact-free plant
    /// shape it is placed against (m).
    pub contact_s_m: f64,
    /// How far the disk reaches into the contact-free shape (m): the load.
    pub intrusion_m: f64,
    /// Number of markers, evenly spaced from base to tip.
    pub n_markers: usize,
    /// Seed of the marker noise.
    pub seed: u64,
    /// Marker frames averaged per measurement (at 20 Hz, the robot held
    /// still; default 20 = 1 s: with 5 the weak contacts near the tip,
    /// 8–17 mN, are located to 16 mm only, the noise's share of their
    /// small marker signal).
    pub frames: usize,
    /// How the estimators choose their regularization `α` (default
    /// [`ALPHA_RULE`](crate::touch::ALPHA_RULE), the touch default, with its
    /// reason there).
    #[serde(default = "touch_alpha_rule")]
    pub alpha_rule: AlphaRule,
}

fn touch_alpha_rule() -> AlphaRule {
    crate::touch::ALPHA_RULE
}

impl LocalizationCase {
    /// A case at the bend of the sweep (every section's first chamber at
    /// 20 kPa: the robot curls towards +x).
    pub fn new(contact_s_m: f64, intrusion_m: f64, n_markers: usize, seed: u64) -> Self {
        let mut pressures_pa = vec![0.0; 10];
        pressures_pa.iter_mut().step_by(2).for_each(|p| *p = 20e3);
        LocalizationCase {
            pressures_pa,
            contact_s_m,
            intrusion_m,
            n_markers,
            seed,
            frames: 20,
            alpha_rule: crate::touch::ALPHA_RULE,
        }
    }
}

/// The mean of `n` (≥ 1) frames at 20 Hz.
fn averaged(plant: &mut SimulatedPlant, n: usize) -> Result<MarkerFrame> {
    let n = n.max(1);
    let mut sum = plant.advance(0.05)?;
    for _ in 1..n {
        let f = plant.advance(0.05)?;
        sum.positions_m
            .iter_mut()
            .flatten()
            .zip(f.positions_m.iter().flatten())
            .for_each(|(a, b)| *a += b);
        sum.time_s = f.time_s;
    }
    sum.positions_m
        .iter_mut()
        .flatten()
        .for_each(|a| *a /= n as f64);
    Ok(sum)
}

/// What both methods found, and the truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LocalizationResult {
    /// The case.
    pub case: LocalizationCase,
    /// The plant's strongest contact: arc coordinate (m).
    pub true_s_m: f64,
    /// Its force on the robot (N).
    pub true_force_n: [f64; 2],
    /// The paper's method (peak of the load minus the virtual payload): arc
    /// coordinate (m) and force (the difference field's resultant, N).
    pub peak_s_m: f64,
    /// The paper's method's force (N).
    pub peak_force_n: [f64; 2],
    /// The point-force search: arc coordinate (m).
    pub point_s_m: f64,
    /// The point-force search: force (N).
    pub point_force_n: [f64; 2],
    /// The calibration the point search used.
    pub calibration: crate::touch::Calibration,
}

impl LocalizationResult {
    /// Location errors `|ŝ − s|` of the peak and point methods (m).
    pub fn location_errors_m(&self) -> (f64, f64) {
        (
            (self.peak_s_m - self.true_s_m).abs(),
            (self.point_s_m - self.true_s_m).abs(),
        )
    }

    /// Force errors `|f̂ − f|` of the peak and point methods (N).
    pub fn force_errors_n(&self) -> (f64, f64) {
        let e = |f: Vector2<f64>| (f - self.true_force()).norm();
        (e(self.peak_force()), e(self.point_force()))
    }

    /// [`LocalizationResult::true_force_n`] as a vector (N).
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::report::touch::{LocalizationCase, LocalizationResult};
    /// use softrod::touch::Calibration;
    /// let r = LocalizationResult { case: LocalizationCase::new(0.3, 0.006, 6, 1),
    ///     true_s_m: 0.3, true_force_n: [0.0, 0.02], peak_s_m: 0.31, peak_force_n: [0.0, 0.018],
    ///     point_s_m: 0.3, point_force_n: [0.001, 0.02],
    ///     calibration: Calibration { ei_factor: 1.0, gain_factor: 1.0, rms_before_m: 0.0, rms_after_m: 0.0 } };
    /// assert_eq!(r.true_force(), Vector2::new(0.0, 0.02));
    /// assert!((r.force_errors_n().0 - (r.peak_force() - r.true_force()).norm()).abs() < 1e-15);
    /// assert!((r.force_errors_n().1 - (r.point_force() - r.true_force()).norm()).abs() < 1e-15);
    /// ```
    pub fn true_force(&self) -> Vector2<f64> {
        Vector2::from(self.true_force_n)
    }

    /// [`LocalizationResult::peak_force_n`] as a vector (N).
    ///
    /// # Example
    /// See [`LocalizationResult::true_force`].
    pub fn peak_force(&self) -> Vector2<f64> {
        Vector2::from(self.peak_force_n)
    }

    /// [`LocalizationResult::point_force_n`] as a vector (N).
    ///
    /// # Example
    /// See [`LocalizationResult::true_force`].
    pub fn point_force(&self) -> Vector2<f64> {
        Vector2::from(self.point_force_n)
    }
}

/// Runs one case on the five-section robot (model: `model_elements` per
/// section; plant: `plant` with the case's seed and no regulator lag; the
/// default [`PlantSettings`] are the sweep's: EI +15 %, gain −10 %, EA
/// −5 %, twice the mesh, σ = 0.05 mm).
///
/// # Errors
/// [`Error::InvalidParameter`] if the disk would overlap the robot's
/// reference configuration or the plant makes no contact; the plant's,
/// the estimator's and the search's errors.
pub fn run_localization(
    case: &LocalizationCase,
    model_elements: usize,
    plant: &PlantSettings,
) -> Result<LocalizationResult> {
    let scene = five_section_scene(model_elements);
    let arcs = marker_arcs(case.n_markers);
    let arcs = arcs.as_slice();
    let settings = PlantSettings {
        regulator_time_constant_s: 0.0,
        seed: case.seed,
        ..plant.clone()
    };
    // the contact-free plant: calibration frames at the case's pressures and
    // two others, then the virtual payload's frame and the placement
    let mut free = SimulatedPlant::new(&scene, arcs, settings.clone())?;
    let mut frames = Vec::new();
    let mut other = case.pressures_pa.clone();
    other.rotate_right(1);
    let half: Vec<f64> = case.pressures_pa.iter().map(|p| 0.5 * p).collect();
    for p in [&other, &half, &case.pressures_pa] {
        free.command(p)?;
        frames.push(FreeFrame {
            pressures_pa: p.clone(),
            markers_m: averaged(&mut free, case.frames)?.positions_m,
        });
    }
    let calib = calibrate(&scene, arcs, &frames)?;
    let frame_free = MarkerFrame {
        time_s: free.time_s(),
        positions_m: frames[2].markers_m.clone(),
    };
    let probot = free.robot().clone();
    let qf = free.true_q().to_vec();
    let r = probot.position_at(&qf, case.contact_s_m)?;
    let mut t = [0.0; 2];
    probot
        .arc_point("contact_s_m", case.contact_s_m)?
        .slope_into(&qf, &mut t)?;
    let tn = t[0].hypot(t[1]);
    let n = [-t[1] / tn, t[0] / tn];
    let reach = PROBE_RADIUS_M + ROD_RADIUS_M - case.intrusion_m;
    let disk = Obstacle::Circle {
        center_m: [r[0] + n[0] * reach, r[1] + n[1] * reach],
        radius_m: PROBE_RADIUS_M,
    };
    let obstacles = Obstacles::new(vec![disk], ROD_RADIUS_M)?;
    let mut plant = SimulatedPlant::new(
        &scene,
        arcs,
        PlantSettings {
            seed: case.seed.wrapping_add(1000),
            ..settings
        },
    )?
    .with_obstacles(obstacles)?;
    plant.command(&case.pressures_pa)?;
    let frame = averaged(&mut plant, case.frames)?;
    let Some(truth) = plant.contact().and_then(|c| {
        c.contacts()
            .iter()
            .max_by(|a, b| a.force_n.total_cmp(&b.force_n))
            .cloned()
    }) else {
        return Err(Error::invalid(
            "intrusion_m",
            case.intrusion_m,
            "the plant makes no contact",
        ));
    };
    let es = EstimatorSettings {
        noise_sigma_m: settings.noise_sigma_m.max(1e-6),
        alpha_rule: case.alpha_rule,
        ..EstimatorSettings::default()
    };
    // the paper's method on the nominal model: the virtual payload (the
    // estimate of the contact-free frame; α chosen there and kept) absorbs
    // the model error
    let nominal = scene.robot()?;
    let mut known = scene.loads()?;
    known.pressures_pa.clone_from(&case.pressures_pa);
    let mut est: Box<dyn Estimator> = es.build_for(&nominal, &known)?;
    let vp = est.step(&frame_free.observation(arcs)?)?.converged()?;
    let e = est.step(&frame.observation(arcs)?)?.converged()?;
    let peak = peak_contact(&nominal, e.f.as_slice(), vp.f.as_slice())?;
    // the point search on the calibrated model, with its own virtual payload
    let model_scene = calib.apply(&scene);
    let model = model_scene.robot()?;
    let mut known = model_scene.loads()?;
    known.pressures_pa.clone_from(&case.pressures_pa);
    let mut est: Box<dyn Estimator> = es.build_for(&model, &known)?;
    let vp = est.step(&frame_free.observation(arcs)?)?.converged()?;
    let mut with_vp = known;
    with_vp.distributed_f = vp.f.as_slice().to_vec();
    let free_markers = crate::touch::planar_points("markers", &frame_free.positions_m)?;
    let offset = marker_offset(&model, &with_vp, arcs, &free_markers)?;
    let point = locate_point_force(
        &model,
        &with_vp,
        arcs,
        &crate::touch::planar_points("markers", &frame.positions_m)?,
        &offset,
        &PointSearchSettings::default(),
    )?;
    Ok(LocalizationResult {
        case: case.clone(),
        true_s_m: truth.s_m,
        true_force_n: [
            truth.force_n * truth.normal[0],
            truth.force_n * truth.normal[1],
        ],
        peak_s_m: peak.s_m,
        peak_force_n: peak.resultant_n,
        point_s_m: point.s_m,
        point_force_n: point.force_n,
        calibration: calib,
    })
}
