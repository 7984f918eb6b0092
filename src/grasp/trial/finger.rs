//! One finger's adaptive controller in a grasp trial: estimator, virtual
//! payload, contact detection and the laws (51)/(52).

use super::*;

/// Estimates averaged for contact detection and localization.
const AVERAGED_ESTIMATES: usize = 3;

/// The adaptive controller of one finger.
pub(super) struct FingerController {
    pub(super) side: Side,
    pub(super) model: Robot<PlanarCable>,
    pub(super) estimator: Box<dyn Estimator>,
    pub(super) vp: VirtualPayload,
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
}

impl FingerController {
    pub(super) fn new(
        gripper: &GripperSpec,
        side: Side,
        noise_m: f64,
        alpha: f64,
        vp: Option<VirtualPayload>,
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
            calibrating: vp.is_none(),
            recent: Vec::new(),
            vp: vp.unwrap_or_else(|| VirtualPayload::new(3)),
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
    pub(super) fn resultant_and_peak(&self, r: &[f64]) -> Result<(f64, f64)> {
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
        Ok((fx.hypot(fy), peak))
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
        let dt = 1.0 / s.control_rate_hz;
        self.estimator.set_known_loads(Loads {
            pressures_pa: self.pressures.clone(),
            ..Loads::default()
        })?;
        let est = self.estimator.step(&state.markers)?;
        if !est.f.iter().chain(&est.q).all(|v| v.is_finite()) {
            return Ok(Some(Failure::Controller {
                message: "the estimate is not finite".into(),
            }));
        }
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
        let (res, peak) = self.resultant_and_peak(&r)?;
        let s_c = match self.phase {
            Phase::Approach if self.calibrating => {
                self.vp.record(&self.pressures, est.f.as_slice())?;
                self.length
            }
            // only on a full window: the first estimates alone carry the
            // marker noise (measured: a resultant of 0.30 N on the second
            // estimate of a finger 50 mm from the red apple, a false contact
            // that turned the finger outward to its pressure bound)
            Phase::Approach
                if self.recent.len() == AVERAGED_ESTIMATES && res > s.contact_threshold_n =>
            {
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

/// The virtual payload of each finger: the approach law run on the plant
/// with nothing in the way (no object, no table), the estimates recorded
/// against the pressures until the fingertips reach the centreline.
pub(super) fn calibrate(
    gripper: &GripperSpec,
    settings: &GraspSettings,
    seed: u64,
) -> std::result::Result<[VirtualPayload; 2], Stop> {
    let mut plant = GripperPlant::new(
        gripper,
        &settings.plant,
        Vec::new(),
        None,
        &settings.markers_s_m,
        seed.wrapping_add(0x5EED),
    )?;
    let noise = settings.plant.marker_noise_m;
    let mut ctrl = [
        FingerController::new(gripper, Side::Left, noise, settings.estimator_alpha, None)?,
        FingerController::new(gripper, Side::Right, noise, settings.estimator_alpha, None)?,
    ];
    let zero = vec![0.0; FINGER_PRESSURES];
    let mut p = [zero.clone(), zero];
    let n = (settings.max_time_s * settings.control_rate_hz).ceil() as usize;
    for _ in 0..n {
        let state = plant.solve([&p[0], &p[1]])?.states()?;
        let mut done = false;
        for (c, st) in ctrl.iter_mut().zip(&state) {
            match c.step(st, settings) {
                Ok(None) => {}
                Ok(Some(_)) => done = true,
                Err(e) => {
                    return Err(Failure::Controller {
                        message: format!("virtual payload run: {e}"),
                    }
                    .into())
                }
            }
        }
        if done {
            break;
        }
        p = [ctrl[0].pressures.clone(), ctrl[1].pressures.clone()];
    }
    let [a, b] = ctrl;
    Ok([a.vp, b.vp])
}
