//! A trial's closing and lift on the plant (the module docs of
//! [`crate::grasp::trial`]).

use super::*;

/// What a trial's simulation needs besides the plant.
pub(super) struct Scene<'a> {
    pub(super) gripper: &'a GripperSpec,
    pub(super) object: &'a GraspObject,
    pub(super) settings: &'a GraspSettings,
    pub(super) strategy: Strategy,
    pub(super) seed: u64,
    /// The table top (m).
    pub(super) table_y: f64,
}

/// Largest steps of the object on the table when it is set down.
const REST_STEPS_START: usize = 400;
/// Largest steps of the object on the table per control interval (when the
/// fingers' pushes move it).
const REST_STEPS_PER_INTERVAL: usize = 20;

impl Scene<'_> {
    /// The table as the plant's obstacle when the palm has come down by
    /// `descent` (m): the contact solver takes no obstacle that overlaps
    /// the straight fingers, so a table risen to their tips is left out
    /// (the tips have risen above it).
    fn plant_table(&self, descent: f64) -> Option<Obstacle> {
        (descent < self.settings.table_clearance_m - 5e-4).then(|| table_at(self.table_y + descent))
    }

    /// Solves the fingers at `pressures` with the object on the table
    /// (palm come down by `descent`), the object moving on it until it
    /// rests (`crate::grasp::rest`, at most `max_steps` steps); `pose` is
    /// the object's pose, updated. The fingers' states at the last pose.
    fn rest(
        &self,
        plant: &mut GripperPlant,
        pose: &mut Pose,
        pressures: [&[f64]; 2],
        descent: f64,
        max_steps: usize,
    ) -> std::result::Result<[FingerState; 2], Stop> {
        let r = self.gripper.finger_radius_m;
        let table = TableTop {
            top_m: self.table_y + descent,
            mu: self.settings.table_mu,
        };
        let mut last = None;
        let rested = rest_on_table(
            self.object,
            *pose,
            &table,
            self.gripper.gravity_m_per_s2,
            self.settings.slip_step_m,
            max_steps,
            |p: &Pose| -> std::result::Result<Vec<FrictionContact>, Stop> {
                plant.set_workspace(self.object.contact_cover(p)?, self.plant_table(descent));
                let states = plant.solve(pressures)?.states()?;
                let contacts = friction_contacts(self.object, p, &states, r);
                last = Some(states);
                Ok(contacts)
            },
        )?;
        *pose = rested.pose;
        if let Some(message) = rested.failed {
            return Err(Failure::ObjectMotion { message }.into());
        }
        last.ok_or_else(|| Stop::Bad(Error::invalid("rest", "none", "no plant solve")))
    }
}

/// The closing and the lift (module docs); a failed trial stops with its
/// cause, which the caller records.
pub(super) fn simulate(
    scene: &Scene<'_>,
    plant: &mut GripperPlant,
    out: &mut TrialOutcome,
) -> std::result::Result<(), Stop> {
    let Scene {
        gripper,
        object,
        settings,
        strategy,
        seed,
        ..
    } = *scene;
    let r = gripper.finger_radius_m;
    let dt = 1.0 / settings.control_rate_hz;
    let mut descent = 0.0;
    let zero = vec![0.0; FINGER_PRESSURES];
    // the object is set down at its placement and comes to rest
    let mut state = scene.rest(
        plant,
        &mut out.final_pose,
        [&zero, &zero],
        0.0,
        REST_STEPS_START,
    )?;
    // the object's steps on the table per control interval
    let pushed = if settings.push_object_on_table {
        REST_STEPS_PER_INTERVAL
    } else {
        0
    };
    // the palm may come down until the object's top is this close
    let max_descent = (-object.bounds(&out.final_pose)[3] - settings.palm_clearance_m).max(0.0);
    let mut pressures = [zero.clone(), zero.clone()];
    let mut phases = [Phase::Ramp; 2];
    let mut poses = [None; 2];
    match strategy {
        Strategy::OpenLoop => {
            let p_ol = match settings.open_loop_pressure_pa {
                Some(p) => p.min(gripper.pressure_max_pa),
                None => meeting_pressure_pa(gripper)?,
            };
            let n = (settings.open_loop_ramp_s / dt).ceil() as usize + 10;
            for k in 1..=n {
                let p = (k as f64 * dt / settings.open_loop_ramp_s).min(1.0) * p_ol;
                let cmd = vec![p, 0.0, 0.0, 0.0];
                pressures = [cmd.clone(), cmd];
                state = scene.rest(
                    plant,
                    &mut out.final_pose,
                    [&pressures[0], &pressures[1]],
                    0.0,
                    pushed,
                )?;
                out.push_frame(k as f64 * dt, phases, &pressures, &state, r, poses);
            }
        }
        Strategy::Adaptive => {
            let noise = settings.plant.marker_noise_m;
            let [cal_left, cal_right] = calibrate(gripper, settings, seed)?;
            let mut ctrl = [
                FingerController::new(
                    gripper,
                    Side::Left,
                    noise,
                    settings.estimator_alpha,
                    Some(cal_left),
                )?,
                FingerController::new(
                    gripper,
                    Side::Right,
                    noise,
                    settings.estimator_alpha,
                    Some(cal_right),
                )?,
            ];
            let n = (settings.max_time_s / dt).ceil() as usize;
            for k in 1..=n {
                for (c, st) in ctrl.iter_mut().zip(&state) {
                    let failure = c.step(st, settings).map_err(|e| Failure::Controller {
                        message: e.to_string(),
                    })?;
                    if let Some(f) = failure {
                        return Err(f.into());
                    }
                }
                phases = [ctrl[0].phase, ctrl[1].phase];
                poses = [ctrl[0].pose, ctrl[1].pose];
                if phases.iter().all(|p| *p == Phase::Hold) {
                    break;
                }
                pressures = [ctrl[0].pressures.clone(), ctrl[1].pressures.clone()];
                // while a finger approaches, the arm lowers the palm by its
                // estimated fingertip rise (module docs)
                if phases.contains(&Phase::Approach) {
                    let rise = ctrl
                        .iter()
                        .filter(|c| c.phase == Phase::Approach)
                        .filter_map(|c| c.pose)
                        .map(|p| p[1] + gripper.finger_length_m())
                        .fold(f64::INFINITY, f64::min);
                    let target = (rise - 0.001).clamp(0.0, max_descent);
                    if target > descent {
                        // in the palm's frame the table and the object rise
                        out.final_pose.position_m[1] += target - descent;
                        descent = target;
                    }
                }
                state = scene.rest(
                    plant,
                    &mut out.final_pose,
                    [&pressures[0], &pressures[1]],
                    descent,
                    pushed,
                )?;
                out.push_frame(k as f64 * dt, phases, &pressures, &state, r, poses);
            }
            // how far the estimated contact point is from the true one
            let mut worst: Option<f64> = None;
            for (c, st) in ctrl.iter().zip(&state) {
                if let (Some(p), false) = (c.pose, st.object_contacts.is_empty()) {
                    let e = st
                        .object_contacts
                        .iter()
                        .map(|t| (t.point_m[0] - p[0]).hypot(t.point_m[1] - p[1]))
                        .fold(f64::INFINITY, f64::min);
                    worst = Some(worst.map_or(e, |w: f64| w.max(e)));
                }
            }
            out.contact_estimate_error_m = worst;
        }
    }
    // the lift: the table no longer carries the object; while the contacts
    // cannot carry it, it moves as a rigid body (module docs, `slip`)
    let t_end = out.frames.last().map_or(0.0, |f| f.time_s) + dt;
    let max_steps = (2.0 * gripper.finger_length_m() / settings.slip_step_m).ceil() as usize;
    let mut k = 0;
    let settled = settle(
        object,
        out.final_pose,
        gripper.gravity_m_per_s2,
        settings.slip_step_m,
        max_steps,
        |pose: &Pose, before: [Option<Touch>; 2]| -> std::result::Result<Grip, Stop> {
            out.final_pose = *pose;
            plant.set_workspace(object.contact_cover(pose)?, None);
            let lifted = plant.solve([&pressures[0], &pressures[1]])?.states()?;
            out.push_frame(t_end + k as f64 * dt, phases, &pressures, &lifted, r, poses);
            k += 1;
            let grip = lifted_grip(plant, object, pose, &lifted, r, before)?;
            Ok(grip)
        },
    )?;
    out.final_pose = settled.pose;
    out.slip_m = settled.slip_m;
    let w0 = settled.first.weight_factor;
    out.holding_mass_kg = settled.first.holding_mass_kg(object.mass_kg);
    out.success = settled.holds && out.slip_m <= settings.max_slip_m;
    out.failure = match (settled.holds, out.success) {
        (_, true) => None,
        (true, false) => Some(Failure::Slips {
            weight_factor: w0,
            slip_m: out.slip_m,
        }),
        (false, _) => Some(Failure::Dropped {
            weight_factor: w0,
            slip_m: out.slip_m,
        }),
    };
    out.hold = Some(settled.first);
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::panic)]
    use super::*;
    use crate::contact::faults::NO_POLISH;
    use crate::grasp::object::Shape;

    #[test]
    fn a_failed_plant_solve_is_a_failed_trial_with_its_cause() {
        // the contact solves' polish made to fail (the fault the contact
        // module's tests inject): the first solve with a finger on the disc
        // does not converge, and the trial ends failed with the plant's
        // status, never as a success
        let disc = GraspObject {
            name: "disc".into(),
            shape: Shape::Circle { radius_m: 0.03 },
            mass_kg: 0.1,
            mu: 0.5,
        };
        NO_POLISH.with(|f| f.set(true));
        let out = run_trial(
            &GripperSpec::default(),
            &disc,
            Placement::default(),
            Strategy::OpenLoop,
            &GraspSettings::default(),
            1,
        );
        NO_POLISH.with(|f| f.set(false));
        let out = out.unwrap();
        assert!(!out.success);
        assert!(
            matches!(&out.failure, Some(Failure::PlantSolve { status, .. }) if !status.is_converged()),
            "{:?}",
            out.failure
        );
    }
}
