//! The gripper as the "real robot": not the controller's model.
//!
//! Each finger is a finer mesh with a stiffer bending stiffness and a
//! weaker actuation than the model (defaults: twice the elements, EI +15 %,
//! gain −10 %), solved with exact frictionless contact
//! ([`crate::contact::ContactSolver`]) against the object and the table;
//! its markers carry Gaussian noise (default 0.05 mm). In each contact
//! solve the object is a fixed obstacle; between solves the trial moves it
//! ([`GripperPlant::set_workspace`]): while the fingers close it rests on
//! the table, after the lift it is a planar rigid body (position and
//! rotation) that the trial steps, pose by pose, while the friction check
//! ([`crate::grasp::friction::hold_check`]) says the contact forces cannot
//! balance its weight (Gauss's least constraint inside the friction
//! cones): it may slide, turn in the pinch, or drop.

use nalgebra::{DVector, Vector2};
use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::contact::{ContactForce, ContactSolver, Obstacle, Obstacles};
use crate::element::PlanarCable;
use crate::error::{Error, Result};
use crate::grasp::gripper::{GripperSpec, Side};
use crate::loads::Loads;
use crate::observe::{MarkerObservation, Observation};
use crate::outcome::ContactStatus;

/// How the plant differs from the model; every field has a documented default.
///
/// # Example
/// ```
/// let s = softrod::grasp::plant::GripperPlantSettings::default();
/// assert_eq!((s.mesh_factor, s.ei_factor, s.gain_factor), (2, 1.15, 0.9));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GripperPlantSettings {
    /// Elements per model element (default 2).
    pub mesh_factor: usize,
    /// Bending stiffness factor (default 1.15).
    pub ei_factor: f64,
    /// Actuation gain factor (default 0.9).
    pub gain_factor: f64,
    /// Marker noise, standard deviation per component (m; default 5e-5).
    pub marker_noise_m: f64,
}

impl Default for GripperPlantSettings {
    fn default() -> Self {
        GripperPlantSettings {
            mesh_factor: 2,
            ei_factor: 1.15,
            gain_factor: 0.9,
            marker_noise_m: 5e-5,
        }
    }
}

impl GripperPlantSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`plant.<field>`).
    pub fn validate(&self) -> Result<()> {
        if self.mesh_factor == 0 || self.mesh_factor > 16 {
            return Err(Error::invalid(
                "plant.mesh_factor",
                self.mesh_factor,
                "must be in 1..=16",
            ));
        }
        for (n, v) in [
            ("ei_factor", self.ei_factor),
            ("gain_factor", self.gain_factor),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(
                    format!("plant.{n}"),
                    v,
                    "must be finite and > 0",
                ));
            }
        }
        if !(self.marker_noise_m.is_finite() && self.marker_noise_m >= 0.0) {
            return Err(Error::invalid(
                "plant.marker_noise_m",
                self.marker_noise_m,
                "must be finite and >= 0",
            ));
        }
        Ok(())
    }
}

/// One finger's state after a plant solve.
#[derive(Debug, Clone, PartialEq)]
pub struct FingerState {
    /// The plant's coordinates.
    pub q: DVector<f64>,
    /// Contacts with the object.
    pub object_contacts: Vec<ContactForce>,
    /// Contacts with the table, if it is there.
    pub table_contacts: Vec<ContactForce>,
    /// The noisy marker observation.
    pub markers: Observation,
    /// Centreline points at the plant's nodes (m), for drawings.
    pub centreline_m: Vec<Vector2<f64>>,
}

/// The result of one plant solve: both fingers, or why it failed.
#[derive(Debug, Clone, PartialEq)]
pub enum PlantStep {
    /// Both contact solves converged.
    Solved(Box<[FingerState; 2]>),
    /// A contact solve did not converge: which finger and the solver's status.
    Failed {
        /// The finger.
        side: Side,
        /// The contact solver's status (never [`ContactStatus::Converged`]).
        status: ContactStatus,
    },
}

/// The simulated gripper with an object (and a table) in its workspace.
#[derive(Debug, Clone)]
pub struct GripperPlant {
    fingers: [Robot<PlanarCable>; 2],
    object: Vec<Obstacle>,
    table: Option<Obstacle>,
    radius_m: f64,
    markers_s_m: Vec<f64>,
    noise_m: f64,
    seed: u64,
    step: u64,
    warm: [Option<Vec<f64>>; 2],
    /// Whether each finger touched anything at the last solve.
    touching: [bool; 2],
    solver: ContactSolver,
}

impl GripperPlant {
    /// The plant of `gripper` (perturbed by `settings`) around `object`
    /// (its circle cover, [`crate::grasp::object::GraspObject::contact_cover`];
    /// empty: the payload-free run of the virtual payload), with a table
    /// (an obstacle, or `None`); markers at the arc
    /// coordinates `markers_s_m` of each finger, noise seeded by `seed`.
    ///
    /// # Errors
    /// [`GripperPlantSettings::validate`], [`GripperSpec::validate`]; an
    /// obstacle overlapping a straight finger ([`Obstacles::check_robot`],
    /// field `obstacles[i]`).
    pub fn new(
        gripper: &GripperSpec,
        settings: &GripperPlantSettings,
        object: Vec<Obstacle>,
        table: Option<Obstacle>,
        markers_s_m: &[f64],
        seed: u64,
    ) -> Result<Self> {
        settings.validate()?;
        gripper.validate()?;
        let build = |side| {
            gripper
                .finger_spec(
                    side,
                    settings.ei_factor,
                    settings.gain_factor,
                    settings.mesh_factor,
                )
                .build_planar()
        };
        let fingers = [build(Side::Left)?, build(Side::Right)?];
        let plant = GripperPlant {
            fingers,
            object,
            table,
            radius_m: gripper.finger_radius_m,
            markers_s_m: markers_s_m.to_vec(),
            noise_m: settings.marker_noise_m,
            seed,
            step: 0,
            warm: [None, None],
            touching: [false, false],
            solver: ContactSolver::default(),
        };
        let obs = plant.obstacles()?;
        for f in &plant.fingers {
            obs.check_robot(f)?;
            for (i, &s) in markers_s_m.iter().enumerate() {
                f.locate(&format!("markers_s_m[{i}]"), s)?;
            }
        }
        Ok(plant)
    }

    fn obstacles(&self) -> Result<Obstacles> {
        let mut v: Vec<Obstacle> = self.object.clone();
        v.extend(self.table.clone());
        Obstacles::new(v, self.radius_m)
    }

    /// Removes the table (the gripper has lifted the object off it).
    pub fn remove_table(&mut self) {
        self.table = None;
    }

    /// Moves the workspace: the object's new circle cover and the table (or
    /// none). The palm frame is the plant's frame, so a palm that moves
    /// down is a workspace that moves up, and an object that slips is a
    /// new cover. The next solve starts warm from the last shapes.
    pub fn set_workspace(&mut self, object: Vec<Obstacle>, table: Option<Obstacle>) {
        self.object = object;
        self.table = table;
    }

    /// The plant's finger robots (left, right).
    pub fn fingers(&self) -> &[Robot<PlanarCable>; 2] {
        &self.fingers
    }

    /// Solves both fingers at their pressures (Pa, four each), warm from
    /// the last solve.
    ///
    /// # Errors
    /// Bad input only (pressures of the wrong count or outside the
    /// chambers' bounds). A contact solve that does not converge is
    /// [`PlantStep::Failed`].
    pub fn solve(&mut self, pressures_pa: [&[f64]; 2]) -> Result<PlantStep> {
        let obstacles = self.obstacles()?;
        let mut out = Vec::with_capacity(2);
        for (k, side) in [Side::Left, Side::Right].into_iter().enumerate() {
            let robot = &self.fingers[k];
            for (j, (p, (lo, hi))) in pressures_pa[k]
                .iter()
                .zip(robot.pressure_bounds())
                .enumerate()
            {
                if !(p.is_finite() && *p >= lo - 1e-9 && *p <= hi + 1e-9) {
                    return Err(Error::invalid(
                        format!("pressures_pa[{j}]"),
                        p,
                        "outside the chamber's bounds",
                    ));
                }
            }
            let loads = Loads {
                pressures_pa: pressures_pa[k].to_vec(),
                ..Loads::default()
            };
            // the solve without obstacles first: if every gap (object and
            // table) at that equilibrium is open it is the contact solution
            // too, and the contact solver never sees an obstacle the finger
            // does not touch (measured: the table polygon alone made solves
            // of a finger far from it fail with LineSearchFailed). Only for
            // a finger that touched nothing at the last solve: a pressed
            // finger's free equilibrium may lie wholly beyond a thin object
            // (measured: after the lift a finger pressing the 3 mm ruler
            // passed through it, all gaps open on its far side)
            let free_obstacles = Obstacles::new(Vec::new(), self.radius_m)?;
            let n_obj = self.object.len();
            let mut free = None;
            if !self.touching[k] {
                let sol =
                    self.solver
                        .solve(robot, &loads, &free_obstacles, self.warm[k].as_deref())?;
                if sol.is_converged()
                    && obstacles
                        .gaps(robot, sol.q.as_slice())?
                        .iter()
                        .all(|g| g.gap_m > 0.0)
                {
                    free = Some(sol);
                }
            }
            let mut sol = match free {
                Some(sol) => sol,
                None => self
                    .solver
                    .solve(robot, &loads, &obstacles, self.warm[k].as_deref())?,
            };
            if !sol.is_converged() && self.warm[k].is_some() {
                // once more from the straight finger
                sol = self.solver.solve(robot, &loads, &obstacles, None)?;
            }
            if !sol.is_converged() {
                self.warm[k] = None;
                return Ok(PlantStep::Failed {
                    side,
                    status: sol.report.status,
                });
            }
            let mut markers = Vec::with_capacity(self.markers_s_m.len());
            for &s in &self.markers_s_m {
                markers.push(MarkerObservation::at_arc(
                    s,
                    robot.position_at(sol.q.as_slice(), s)?,
                ));
            }
            let seed = self
                .seed
                .wrapping_mul(1_000_003)
                .wrapping_add(2 * self.step + k as u64);
            let markers = Observation { markers }.with_noise(self.noise_m, seed);
            let centreline_m = robot
                .node_positions(sol.q.as_slice())
                .column_iter()
                .map(|p| Vector2::new(p[0], p[1]))
                .collect();
            let (object_contacts, table_contacts) = sol
                .contacts
                .iter()
                .cloned()
                .partition(|c| c.obstacle < n_obj);
            self.warm[k] = Some(sol.q.as_slice().to_vec());
            self.touching[k] = !sol.contacts.is_empty();
            out.push(FingerState {
                q: sol.q.clone(),
                object_contacts,
                table_contacts,
                markers,
                centreline_m,
            });
        }
        self.step += 1;
        match <[FingerState; 2]>::try_from(out) {
            Ok(f) => Ok(PlantStep::Solved(Box::new(f))),
            Err(_) => Err(Error::invalid("plant", "fingers", "expected two")),
        }
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
    use crate::assembly::{Robot, RobotSpec, Section};
    use crate::contact::faults::{NO_COMPLEMENTARITY, NO_POLISH};
    use crate::contact::{ContactSolver, Obstacle, Obstacles};
    use crate::element::PlanarCable;
    use crate::grasp::gripper::{GripperSpec, Side};
    use crate::loads::{Loads, PointForce};
    use crate::outcome::ContactStatus;

    /// A dumped solve: its name, the finger, the loads, the obstacles, the
    /// warm start.
    type Dumped = (String, Robot<PlanarCable>, Loads, Obstacles, Vec<f64>);

    /// The plant solves dumped from the simulated Table I
    /// (tests/contact_plant_cases.json): the finger, its pressures, the
    /// obstacles, the warm start; each finger has left the object.
    fn dumped() -> Vec<Dumped> {
        let doc: serde_json::Value =
            serde_json::from_str(include_str!("../../tests/contact_plant_cases.json")).unwrap();
        doc["cases"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| {
                let side = if c["side"] == "left" {
                    Side::Left
                } else {
                    Side::Right
                };
                let robot = GripperSpec::default()
                    .finger_spec(side, 1.15, 0.9, 2)
                    .build_planar()
                    .unwrap();
                let obstacles: Vec<Obstacle> =
                    serde_json::from_value(c["obstacles"].clone()).unwrap();
                let obstacles =
                    Obstacles::new(obstacles, c["rod_radius_m"].as_f64().unwrap()).unwrap();
                let loads = Loads {
                    pressures_pa: serde_json::from_value(c["pressures_pa"].clone()).unwrap(),
                    ..Loads::default()
                };
                let warm = serde_json::from_value(c["warm_q"].clone()).unwrap();
                (c["case"].to_string(), robot, loads, obstacles, warm)
            })
            .collect()
    }

    #[test]
    fn a_stopped_sqp_whose_active_set_holds_open_gaps_polishes_its_closed_contacts() {
        // Every QP multiplier counted, also of the gaps the step leaves
        // open (the fault that the complementarity test in the QP mends):
        // the SQP stops at the released finger's free equilibrium with its
        // ~50 open gaps all "active", and the polish of that set diverges.
        // Measured before the fallback to the closed contacts (tape
        // measure, open loop, try 4, plant step 83): 200 SQP + 11 640
        // Newton iterations in 43 s, IterationLimit, then LineSearchFailed
        // cold. Now the polish of its closed contacts (none) converges.
        NO_COMPLEMENTARITY.with(|f| f.set(true));
        let solver = ContactSolver::default();
        for (name, robot, loads, obstacles, warm) in dumped() {
            let none = Obstacles::new(Vec::new(), obstacles.rod_radius_m()).unwrap();
            let free = solver.solve(&robot, &loads, &none, Some(&warm)).unwrap();
            assert!(free.is_converged(), "{name}: {}", free.report);
            for (how, q0) in [("warm", Some(warm.as_slice())), ("cold", None)] {
                let sol = solver.solve(&robot, &loads, &obstacles, q0).unwrap();
                assert!(sol.is_converged(), "{name} ({how}): {}", sol.report);
                assert!(
                    sol.report.sqp_iterations <= 30,
                    "{name} ({how}): {}",
                    sol.report
                );
                assert!(
                    sol.contacts.is_empty(),
                    "{name} ({how}): {:?}",
                    sol.contacts
                );
                let d = (&sol.q - &free.q).amax();
                assert!(d < 1e-9, "{name} ({how}): {d:e}");
            }
        }
        NO_COMPLEMENTARITY.with(|f| f.set(false));
    }

    #[test]
    fn a_solve_whose_polish_cannot_converge_stops_stalled_at_once() {
        // a propped cantilever (the contact module's example) whose polish
        // is made to fail: the SQP reaches the solution, its steps fall to
        // round-off, and the solve ends Stalled within a few iterations
        // instead of repeating the same QP and polish up to the limit
        NO_POLISH.with(|f| f.set(true));
        let mut spec = RobotSpec::new(vec![Section::uniform(1.0, 1e4, 1.0, 8)]);
        spec.gravity_m_per_s2 = vec![0.0, 0.0];
        let robot = spec.build_planar().unwrap();
        let obstacles = Obstacles::new(
            vec![Obstacle::Circle {
                center_m: [0.5, -0.001],
                radius_m: 0.001,
            }],
            0.0,
        )
        .unwrap();
        let loads = Loads {
            point_forces: vec![PointForce {
                s_m: 1.0,
                force_n: vec![0.0, -1e-5],
            }],
            ..Loads::default()
        };
        let sol = ContactSolver::default()
            .solve(&robot, &loads, &obstacles, None)
            .unwrap();
        NO_POLISH.with(|f| f.set(false));
        assert!(
            matches!(sol.report.status, ContactStatus::Stalled { .. }),
            "{}",
            sol.report
        );
        assert!(sol.report.sqp_iterations <= 20, "{}", sol.report);
        // the same solve with its polish converges
        let ok = ContactSolver::default()
            .solve(&robot, &loads, &obstacles, None)
            .unwrap();
        assert!(ok.is_converged(), "{}", ok.report);
    }
}
