//! What a trial records (frames, contact forces) and how it stops: a
//! failed plant solve or controller step is the trial's failure.

use super::*;

pub(super) fn contact_records(fingers: &[FingerState; 2], radius: f64) -> Vec<ContactRecord> {
    let mut out = Vec::new();
    for (f, side) in fingers.iter().zip([Side::Left, Side::Right]) {
        for c in &f.object_contacts {
            let d = radius + c.gap_m;
            out.push(ContactRecord {
                side,
                point_m: [
                    c.point_m[0] - d * c.normal[0],
                    c.point_m[1] - d * c.normal[1],
                ],
                normal: [-c.normal[0], -c.normal[1]],
                force_n: c.force_n,
            });
        }
    }
    out
}

pub(super) fn frame(
    time_s: f64,
    phases: [Phase; 2],
    pressures: [&[f64]; 2],
    fingers: &[FingerState; 2],
    radius: f64,
    poses: [Option<[f64; 3]>; 2],
    object: Pose,
) -> Frame {
    Frame {
        time_s,
        phases,
        pressures_pa: [pressures[0].to_vec(), pressures[1].to_vec()],
        centreline_m: [0, 1].map(|i| fingers[i].centreline_m.iter().map(|p| [p.x, p.y]).collect()),
        contacts: contact_records(fingers, radius),
        contact_pose: poses,
        object_position_m: object.position_m,
        object_angle_rad: object.angle_rad,
    }
}

/// Why a trial stops early: bad input (an error) or a failed trial (its
/// cause, recorded in the outcome).
pub(super) enum Stop {
    /// Bad input.
    Bad(Error),
    /// The trial failed.
    Fail(Failure),
}

impl From<Error> for Stop {
    fn from(e: Error) -> Self {
        Stop::Bad(e)
    }
}

impl From<Failure> for Stop {
    fn from(f: Failure) -> Self {
        Stop::Fail(f)
    }
}

impl PlantStep {
    /// Both fingers' states, or the trial's failure: a contact solve that
    /// did not converge.
    pub(super) fn states(self) -> std::result::Result<[FingerState; 2], Failure> {
        match self {
            PlantStep::Solved(s) => Ok(*s),
            PlantStep::Failed { side, status } => Err(Failure::PlantSolve { side, status }),
        }
    }
}

impl TrialOutcome {
    /// Records the state after a control interval.
    pub(super) fn push_frame(
        &mut self,
        time_s: f64,
        phases: [Phase; 2],
        pressures: &[Vec<f64>; 2],
        fingers: &[FingerState; 2],
        radius: f64,
        poses: [Option<[f64; 3]>; 2],
    ) {
        let f = frame(
            time_s,
            phases,
            [&pressures[0], &pressures[1]],
            fingers,
            radius,
            poses,
            self.final_pose,
        );
        self.frames.push(f);
    }
}
