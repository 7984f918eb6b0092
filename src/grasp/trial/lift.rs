//! The fingers' grip on the object: what `grasp::rest` (on the table) and
//! `grasp::slip` (lifted) need from the plant at each pose of the object.

use super::*;

/// The fingers' contacts on `object` at `pose` for the friction programs:
/// each finger's push (its normal force) with the cone about the object's
/// own outline (not the cover's).
pub(super) fn friction_contacts(
    object: &GraspObject,
    pose: &Pose,
    fingers: &[FingerState; 2],
    r: f64,
) -> Vec<FrictionContact> {
    contact_records(fingers, r)
        .iter()
        .map(|c| {
            let n: [f64; 2] = object.surface_normal(pose, c.point_m.into()).into();
            FrictionContact {
                point_m: c.point_m,
                normal: [-n[0], -n[1]],
                max_normal_force_n: c.force_n,
            }
        })
        .collect()
}

/// The grip on the lifted object at `pose` (for `settle`): the friction
/// contacts with cones about the object's own outline (not the cover's),
/// each finger's strongest contact, and where each finger's material point
/// of the last touch is now (on the same side of its centreline).
pub(super) fn lifted_grip(
    plant: &GripperPlant,
    object: &GraspObject,
    pose: &Pose,
    lifted: &[FingerState; 2],
    r: f64,
    before: [Option<Touch>; 2],
) -> Result<Grip> {
    let contacts = friction_contacts(object, pose, lifted, r);
    // a finger's surface point at arc s on side σ: centreline + r σ ν
    let surface = |robot: &Robot<PlanarCable>, q: &[f64], s: f64, side: f64| -> Result<[f64; 2]> {
        let p = robot.position_at(q, s)?;
        let a = robot.angle_at(q, s)?;
        Ok([p[0] - r * side * a.sin(), p[1] + r * side * a.cos()])
    };
    let mut touches = [None, None];
    let mut followed_m = [None, None];
    for (i, (f, robot)) in lifted.iter().zip(plant.fingers()).enumerate() {
        if let Some(c) = f
            .object_contacts
            .iter()
            .max_by(|a, b| a.force_n.total_cmp(&b.force_n))
        {
            // the surface point faces the object: −normal from the centreline
            let a = robot.angle_at(f.q.as_slice(), c.s_m)?;
            let side = (-a.sin() * -c.normal[0] + a.cos() * -c.normal[1]).signum();
            let d = r + c.gap_m;
            touches[i] = Some(Touch {
                s_m: c.s_m,
                side,
                point_m: [
                    c.point_m[0] - d * c.normal[0],
                    c.point_m[1] - d * c.normal[1],
                ],
                finger_point_m: surface(robot, f.q.as_slice(), c.s_m, side)?,
                normal: [-c.normal[0], -c.normal[1]],
            });
        }
        if let Some(t) = before[i] {
            followed_m[i] = Some(surface(robot, f.q.as_slice(), t.s_m, t.side)?);
        }
    }
    Ok(Grip {
        contacts,
        both_fingers: lifted.iter().all(|f| !f.object_contacts.is_empty()),
        touches,
        followed_m,
    })
}
