//! One finger's adaptive controller in a grasp trial: estimator, virtual
//! payload, contact detection and the laws (51)/(52).

use super::*;
use crate::estimate::Estimate;
use nalgebra::{Matrix2, Vector2};

/// Estimates averaged for contact detection and localization.
const AVERAGED_ESTIMATES: usize = 3;

/// What the payload-free run measured for one finger: the virtual payload
/// (the mean estimate of `frames` marker frames at each recorded pressure)
/// and the covariance of one estimate's resultant about that mean (N²;
/// the marker noise seen through the estimator, measured from the
/// frames' scatter at each pressure: the configuration is the same, only
/// the noise differs).
#[derive(Debug, Clone)]
pub(super) struct FingerCalibration {
    pub(super) vp: VirtualPayload,
    pub(super) resultant_cov_n2: Matrix2<f64>,
    pub(super) frames: usize,
}

/// The adaptive controller of one finger.
pub(super) struct FingerController {
    pub(super) side: Side,
    pub(super) model: Robot<PlanarCable>,
    pub(super) estimator: Box<dyn Estimator>,
    pub(super) vp: VirtualPayload,
    /// The measured covariance of one estimate's resultant (calibrated
    /// controllers; zero while calibrating).
    pub(super) resultant_cov_n2: Matrix2<f64>,
    /// Marker frames averaged per record of the virtual payload.
    pub(super) calibration_frames: usize,
    /// While calibrating: the scatter `Σ (r − r̄)(r − r̄)ᵀ` of the frames'
    /// resultants about their mean at each pressure, and its degrees of freedom.
    scatter: (Matrix2<f64>, usize),
    pub(super) phase: Phase,
    pub(super) pressures: Vec<f64>,
    pub(super) pose: Option<[f64; 3]>,
    pub(super) length: f64,
    pub(super) radius: f64,
    pub(super) max_pa: f64,
    /// The payload-free run: record the virtual payload, never detect.
    pub(super) calibrating: bool,
    /// The last estimates minus the virtual payload (averaged for detection
    /// and localization: one estimate carries the marker noise).
    pub(super) recent: Vec<Vec<f64>>,
    /// The largest averaged resultant (N) on a full window while
    /// approaching (not calibrating): the margin of the detection.
    pub(super) largest_approach_residual_n: f64,
}

impl FingerController {
    pub(super) fn new(
        gripper: &GripperSpec,
        side: Side,
        noise_m: f64,
        alpha: f64,
        calibration: Option<FingerCalibration>,
    ) -> Result<Self> {
        let model = gripper.finger(side)?;
        let settings = EstimatorSettings {
            noise_sigma_m: noise_m.max(1e-6),
            alpha: Some(alpha),
            ..EstimatorSettings::default()
        };
        let known = Loads {
            pressures_pa: vec![0.0; FINGER_PRESSURES],
            ..Loads::default()
        };
        let estimator = settings.build_for(&model, &known)?;
        Ok(FingerController {
            side,
            model,
            estimator,
            calibrating: calibration.is_none(),
            recent: Vec::new(),
            largest_approach_residual_n: 0.0,
            resultant_cov_n2: calibration
                .as_ref()
                .map_or_else(Matrix2::zeros, |c| c.resultant_cov_n2),
            calibration_frames: calibration.as_ref().map_or(1, |c| c.frames),
            scatter: (Matrix2::zeros(), 0),
            vp: match calibration {
                Some(c) => c.vp,
                None => VirtualPayload::new(3)?,
            },
            phase: Phase::Approach,
            pressures: vec![0.0; FINGER_PRESSURES],
            pose: None,
            length: gripper.finger_length_m(),
            radius: gripper.finger_radius_m,
            max_pa: gripper.pressure_max_pa,
        })
    }

    /// Resultant (N) of a load field and where it peaks: the
    /// magnitude-weighted mean arc coordinate of the nodes at more than half
    /// the largest nodal magnitude (the largest node alone jumps by a node
    /// spacing between steps).
    pub(super) fn resultant_and_peak(&self, r: &[f64]) -> Result<(Vector2<f64>, f64)> {
        let g = self.model.apply_load_gram(r)?;
        let fx: f64 = g.iter().step_by(4).sum();
        let fy: f64 = g.iter().skip(1).step_by(4).sum();
        let arcs = self.model.node_arc();
        let mags: Vec<f64> = (0..arcs.len())
            .map(|i| r[4 * i].hypot(r[4 * i + 1]))
            .collect();
        let top = mags.iter().skip(1).copied().fold(0.0, f64::max);
        let (mut ws, mut w) = (0.0, 0.0);
        for (m, s) in mags.iter().zip(arcs).skip(1) {
            if *m >= 0.5 * top && top > 0.0 {
                ws += m * s;
                w += m;
            }
        }
        let peak = if w > 0.0 { ws / w } else { self.length };
        Ok((Vector2::new(fx, fy), peak))
    }

    /// Whether the averaged resultant `r` (estimates minus the virtual
    /// payload) is beyond the noise: `d² = rᵀ C⁻¹ r` above the χ²₂ quantile
    /// `−2 ln p` of the false-alarm probability `p` per control instant, with
    /// `C` the covariance of the mean of [`AVERAGED_ESTIMATES`] estimates
    /// minus the mean of `calibration_frames` (the virtual payload's record).
    fn significant(&self, r: &Vector2<f64>, s: &GraspSettings) -> bool {
        let scale = 1.0 / self.recent.len() as f64 + 1.0 / self.calibration_frames as f64;
        let c = self.resultant_cov_n2 * scale;
        // a covariance not measured (singular) gives no test: the threshold alone
        match c.try_inverse() {
            Some(ci) if c.determinant() > 0.0 => {
                (r.transpose() * ci * r)[(0, 0)] > -2.0 * s.contact_false_alarm_probability.ln()
            }
            _ => true,
        }
    }

    /// What the payload-free run measured (see [`FingerCalibration`]);
    /// `None` if the scatter has no degrees of freedom (one frame per record).
    fn calibration(self) -> Option<FingerCalibration> {
        let (scatter, dof) = self.scatter;
        (dof > 0).then(|| FingerCalibration {
            vp: self.vp,
            resultant_cov_n2: scatter / dof as f64,
            frames: self.calibration_frames,
        })
    }

    /// The estimate from one marker frame at the current pressures; `None`
    /// if it is not finite.
    fn estimate(&mut self, state: &FingerState) -> Result<Option<Estimate>> {
        self.estimator.set_known_loads(Loads {
            pressures_pa: self.pressures.clone(),
            ..Loads::default()
        })?;
        let est = self.estimator.step(&state.markers)?;
        Ok(est
            .f
            .iter()
            .chain(&est.q)
            .all(|v| v.is_finite())
            .then_some(est))
    }

    /// One control instant: the markers in, the new pressures (or a failure).
    pub(super) fn step(
        &mut self,
        state: &FingerState,
        s: &GraspSettings,
    ) -> Result<Option<Failure>> {
        if self.phase == Phase::Hold {
            return Ok(None);
        }
        match self.estimate(state)? {
            Some(est) => self.act(&est, s),
            None => Ok(Some(Failure::Controller {
                message: "the estimate is not finite".into(),
            })),
        }
    }

    /// One control instant of the payload-free run: the estimates of the
    /// frames `states` (one configuration, fresh marker noise each) are
    /// averaged into one record of the virtual payload at the current
    /// pressures, then the approach law steps on the last estimate.
    fn calibration_step(
        &mut self,
        states: &[&FingerState],
        s: &GraspSettings,
    ) -> Result<Option<Failure>> {
        let mut last = None;
        let mut mean: Vec<f64> = Vec::new();
        let mut resultants = Vec::with_capacity(states.len());
        for st in states {
            let Some(est) = self.estimate(st)? else {
                return Ok(Some(Failure::Controller {
                    message: "the estimate is not finite".into(),
                }));
            };
            if mean.is_empty() {
                mean = vec![0.0; est.f.len()];
            }
            mean.iter_mut()
                .zip(est.f.iter())
                .for_each(|(m, f)| *m += f / states.len() as f64);
            resultants.push(self.resultant_and_peak(est.f.as_slice())?.0);
            last = Some(est);
        }
        let Some(est) = last else {
            return Ok(None);
        };
        let centre = resultants.iter().sum::<Vector2<f64>>() / resultants.len() as f64;
        for r in &resultants {
            self.scatter.0 += (r - centre) * (r - centre).transpose();
        }
        self.scatter.1 += resultants.len() - 1;
        self.vp.record(&self.pressures, &mean)?;
        self.act(&est, s)
    }

    /// Contact detection and the laws (51)/(52) on the estimate `est`.
    fn act(&mut self, est: &Estimate, s: &GraspSettings) -> Result<Option<Failure>> {
        let dt = 1.0 / s.control_rate_hz;
        let r: Vec<f64> = if self.vp.is_empty() {
            vec![0.0; est.f.len()]
        } else {
            self.vp
                .subtract(&self.pressures, est.f.as_slice())?
                .data
                .into()
        };
        self.recent.push(r);
        if self.recent.len() > AVERAGED_ESTIMATES {
            self.recent.remove(0);
        }
        let mut r = vec![0.0; est.f.len()];
        for x in &self.recent {
            r.iter_mut()
                .zip(x)
                .for_each(|(a, b)| *a += b / self.recent.len() as f64);
        }
        let (resultant, peak) = self.resultant_and_peak(&r)?;
        let res = resultant.norm();
        let full = self.recent.len() == AVERAGED_ESTIMATES;
        let significant = full && !self.calibrating && self.significant(&resultant, s);
        if self.phase == Phase::Approach && !self.calibrating && full {
            self.largest_approach_residual_n = self.largest_approach_residual_n.max(res);
        }
        let s_c = match self.phase {
            Phase::Approach if self.calibrating => self.length,
            // only on a full window: the first estimates alone carry the
            // marker noise (measured: a resultant of 0.30 N on the second
            // estimate of a finger 50 mm from the red apple, a false contact
            // that turned the finger outward to its pressure bound)
            Phase::Approach if significant && res > s.contact_threshold_n => {
                self.phase = Phase::Squeeze;
                peak
            }
            Phase::Approach => self.length,
            _ => peak,
        };
        let loads = Loads {
            pressures_pa: self.pressures.clone(),
            distributed_f: est.f.as_slice().to_vec(),
            ..Loads::default()
        };
        let pose = contact_pose(&self.model, est.q.as_slice(), s_c)?;
        self.pose = Some(pose.into());
        let inward = self.side.inward();
        let near_bound = self
            .pressures
            .iter()
            .any(|p| *p >= (1.0 - s.bound_margin) * self.max_pa);
        // missed: the fingertip's surface is past the centreline by more
        // than `miss_overshoot_m` (a thin object placed off the centreline
        // is touched only there) or a pressure is near its bound
        let past = inward * pose[0] + self.radius - s.miss_overshoot_m;
        if self.phase == Phase::Approach && (past >= 0.0 || near_bound) {
            return Ok(Some(Failure::Missed { side: self.side }));
        }
        if self.phase == Phase::Squeeze && near_bound {
            self.phase = Phase::Align;
        }
        if self.phase == Phase::Align && pose[2].abs() < s.theta_tolerance_rad {
            self.phase = Phase::Hold;
            return Ok(None);
        }
        let turn = -s.u2_rad_per_s * pose[2].signum() * f64::from(u8::from(pose[2] != 0.0));
        // (52) also while the finger is turned by more than the band: the
        // contact blocks the motion (51) asks for, and its push turns the finger
        let squaring = self.phase == Phase::Squeeze && pose[2].abs() > s.theta_band_rad;
        let xdot = if self.phase == Phase::Align || squaring {
            nalgebra::Vector3::new(0.0, 0.0, turn)
        } else {
            nalgebra::Vector3::new(inward * s.u1_m_per_s, 0.0, turn)
        };
        let j = contact_jacobian(&self.model, est.q.as_slice(), &loads, s_c)?;
        let dp = bounded_step(
            &j,
            &xdot,
            dt,
            &self.pressures,
            &self.model.pressure_bounds(),
            self.length,
        )?;
        self.pressures
            .iter_mut()
            .zip(&dp)
            .for_each(|(p, d)| *p += d);
        Ok(None)
    }
}

/// A payload-free run of both fingers: the approach law on the plant with
/// nothing in the way (no object, no table), until a finger misses (its
/// fingertip passes the centreline) or, with a virtual payload given, a
/// finger detects a contact (there is none: a false detection).
pub(super) struct FreeRun {
    /// Each finger's calibration (recorded, or the one given).
    pub(super) calibration: [Option<FingerCalibration>; 2],
    /// Which fingers detected a contact (only with a given virtual payload;
    /// read by the false-detection tests).
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) detected: [bool; 2],
    /// Each finger's largest averaged resultant (N) while approaching.
    #[cfg_attr(not(test), allow(dead_code))]
    pub(super) largest_residual_n: [f64; 2],
}

/// Runs the payload-free approach (see [`FreeRun`]); without `vp` it is the
/// calibration: each control instant's `frames` marker frames are
/// estimated and their mean recorded as the virtual payload at the
/// pressures.
pub(super) fn free_run(
    gripper: &GripperSpec,
    settings: &GraspSettings,
    seed: u64,
    calibration: Option<[FingerCalibration; 2]>,
    frames: usize,
) -> std::result::Result<FreeRun, Stop> {
    let mut plant = GripperPlant::new(
        gripper,
        &settings.plant,
        Vec::new(),
        None,
        &settings.markers_s_m,
        seed,
    )?;
    let noise = settings.plant.marker_noise_m;
    let [vl, vr] = match calibration {
        Some([l, r]) => [Some(l), Some(r)],
        None => [None, None],
    };
    let mut ctrl = [
        FingerController::new(gripper, Side::Left, noise, settings.estimator_alpha, vl)?,
        FingerController::new(gripper, Side::Right, noise, settings.estimator_alpha, vr)?,
    ];
    let calibrating = ctrl[0].calibrating;
    let frames = if calibrating { frames.max(1) } else { 1 };
    for c in ctrl.iter_mut() {
        c.calibration_frames = frames;
    }
    let zero = vec![0.0; FINGER_PRESSURES];
    let mut p = [zero.clone(), zero];
    let n = (settings.max_time_s * settings.control_rate_hz).ceil() as usize;
    for _ in 0..n {
        let mut states = Vec::with_capacity(frames);
        for _ in 0..frames {
            states.push(plant.solve([&p[0], &p[1]])?.states()?);
        }
        let mut done = false;
        for (i, c) in ctrl.iter_mut().enumerate() {
            let step = if calibrating {
                let mine: Vec<&FingerState> = states.iter().map(|st| &st[i]).collect();
                c.calibration_step(&mine, settings)
            } else {
                c.step(&states[0][i], settings)
            };
            match step {
                Ok(None) => done |= c.phase != Phase::Approach,
                Ok(Some(_)) => done = true,
                Err(e) => {
                    return Err(Failure::Controller {
                        message: format!("payload-free run: {e}"),
                    }
                    .into());
                }
            }
        }
        if done {
            break;
        }
        p = [ctrl[0].pressures.clone(), ctrl[1].pressures.clone()];
    }
    let [a, b] = ctrl;
    Ok(FreeRun {
        detected: [a.phase != Phase::Approach, b.phase != Phase::Approach],
        largest_residual_n: [a.largest_approach_residual_n, b.largest_approach_residual_n],
        calibration: [a.calibration(), b.calibration()],
    })
}

/// Each finger's calibration: the payload-free run (see [`free_run`])
/// recording the mean of `settings.calibration_frames` estimates against
/// the pressures until the fingertips reach the centreline, and the
/// estimates' noise.
pub(super) fn calibrate(
    gripper: &GripperSpec,
    settings: &GraspSettings,
    seed: u64,
) -> std::result::Result<[FingerCalibration; 2], Stop> {
    let run = free_run(
        gripper,
        settings,
        seed.wrapping_add(0x5EED),
        None,
        settings.calibration_frames,
    )?;
    match run.calibration {
        [Some(l), Some(r)] => Ok([l, r]),
        _ => Err(Stop::Bad(Error::invalid(
            "settings.calibration_frames",
            settings.calibration_frames,
            "needs at least 2 frames to measure the noise",
        ))),
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::panic)]
    use super::*;

    /// Calibrates on seed `seed`, then runs the payload-free approach again
    /// on other marker noise with that calibration: which fingers detect a
    /// contact (there is none), and their largest averaged resultant.
    fn false_detections(s: &GraspSettings, seed: u64) -> ([bool; 2], [f64; 2]) {
        let g = GripperSpec::default();
        let run = |cal, seed, frames| match free_run(&g, s, seed, cal, frames) {
            Ok(r) => r,
            Err(Stop::Bad(e)) => panic!("{e}"),
            Err(Stop::Fail(f)) => panic!("{f:?}"),
        };
        let [Some(l), Some(r)] = run(None, seed, s.calibration_frames).calibration else {
            panic!("no calibration")
        };
        let free = run(Some([l, r]), seed + 1000, 1);
        (free.detected, free.largest_residual_n)
    }

    #[test]
    fn a_payload_free_finger_detects_no_contact() {
        // nothing touches the fingers: the estimates minus the virtual
        // payload are noise. With the force threshold alone (no significance
        // test: p → 1) noise crossed 0.25 N in 2 of 20 fingers over these
        // seeds (5 of 20 with one calibration frame per pressure; measured);
        // beyond the measured noise (p = 1e-4 per control instant) none does
        let s = GraspSettings::default();
        let threshold_only = GraspSettings {
            contact_false_alarm_probability: 1.0 - 1e-12,
            ..s.clone()
        };
        let (mut with_test, mut without, mut largest) = (0, 0, 0.0_f64);
        for seed in 0..SEEDS {
            let (d, r) = false_detections(&s, seed);
            with_test += d.iter().filter(|d| **d).count();
            largest = largest.max(r[0]).max(r[1]);
            let (d, _) = false_detections(&threshold_only, seed);
            without += d.iter().filter(|d| **d).count();
        }
        assert_eq!(with_test, 0, "false detections with the significance test");
        // the test is what holds them off: the force threshold alone is crossed
        assert!(
            without > 0 && largest > s.contact_threshold_n,
            "{without} {largest}"
        );
    }

    /// Seeds of the payload-free runs.
    const SEEDS: u64 = 10;

    #[test]
    fn the_measured_noise_is_the_scatter_of_the_frames() {
        // the calibration's covariance of one estimate's resultant: positive
        // definite and of the size the estimate's noise has (measured σ
        // 0.064 N across the finger at 0.05 mm marker noise)
        let s = GraspSettings::default();
        let g = GripperSpec::default();
        let Ok(FreeRun {
            calibration: [Some(l), Some(r)],
            ..
        }) = free_run(&g, &s, 7, None, s.calibration_frames)
        else {
            panic!("no calibration")
        };
        for c in [l.resultant_cov_n2, r.resultant_cov_n2] {
            assert!(c[(0, 0)] > 0.0 && c.determinant() > 0.0, "{c}");
            let sx = c[(0, 0)].sqrt();
            assert!((0.02..0.2).contains(&sx), "{sx}");
        }
    }
}
