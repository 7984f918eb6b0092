//! Obstacles in the simulated plant's world: with them, the plant's
//! quasi-static equilibrium is the contact equilibrium (the minimum of the
//! potential energy subject to non-penetration, [`ContactSolver`]), and the
//! contact forces are part of the plant's truth (for scoring only: a
//! controller feels them through the markers).
//!
//! A contact solve that does not reach a non-penetrating equilibrium is
//! never taken as the plant's shape: [`crate::plant::Plant::advance`] then
//! returns [`Error::ContactNotConverged`] with the solver's report and the
//! plant keeps its previous shape.

use crate::assembly::Robot;
use crate::contact::{ContactForce, ContactSettings, ContactSolver, Obstacles};
use crate::element::PlanarCable;
use crate::error::{Error, Result};
use crate::loads::Loads;
use crate::outcome::{ContactReport, ContactStatus};
use crate::statics::StaticSolver;

/// Clearance beyond which a step is solved without the contact solver (m).
const FREE_MARGIN_M: f64 = 1e-3;

use super::SimulatedPlant;

/// The plant's obstacles, its contact solver and the last contact solve.
///
/// # Example
/// ```
/// use softrod::contact::{Obstacle, Obstacles};
/// use softrod::plant::{Plant, PlantSettings, SimulatedPlant};
/// // the five-section robot hangs from its base along −y; a disk beside it
/// let scene = softrod::touch::five_section_scene(4);
/// let walls = Obstacles::new(vec![Obstacle::Circle { center_m: [0.1, -0.3], radius_m: 0.02 }], 0.01)?;
/// let mut plant = SimulatedPlant::new(&scene, &[0.186, 0.372], PlantSettings::default())?
///     .with_obstacles(walls)?;
/// plant.advance(0.05)?;
/// let c = plant.contact().unwrap();
/// assert!(c.report().unwrap().status.is_converged() && c.report().unwrap().min_gap_m >= -1e-9);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct PlantContact {
    obstacles: Obstacles,
    solver: ContactSolver,
    report: Option<ContactReport>,
    contacts: Vec<ContactForce>,
}

impl PlantContact {
    /// The obstacles with the contact solver of `settings`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for invalid settings.
    pub fn new(obstacles: Obstacles, settings: ContactSettings) -> Result<Self> {
        Ok(PlantContact {
            obstacles,
            solver: ContactSolver::new(settings)?,
            report: None,
            contacts: Vec::new(),
        })
    }

    /// The obstacles.
    pub fn obstacles(&self) -> &Obstacles {
        &self.obstacles
    }

    /// The report of the last contact solve (`None` before the first).
    pub fn report(&self) -> Option<&ContactReport> {
        self.report.as_ref()
    }

    /// The active contacts of the last converged solve, base to tip.
    pub fn contacts(&self) -> &[ContactForce] {
        &self.contacts
    }

    /// Sum of the magnitudes of the active contact forces (N).
    pub fn total_force_n(&self) -> f64 {
        self.contacts.iter().map(|c| c.force_n).sum()
    }

    /// The contact equilibrium of `robot` under `loads`, warm from `q`;
    /// the new shape only if the solve converged.
    ///
    /// # Errors
    /// [`Error::ContactNotConverged`] with the report when it did not; the
    /// solver's input errors.
    pub(super) fn solve(
        &mut self,
        robot: &Robot<PlanarCable>,
        loads: &Loads,
        q: &[f64],
    ) -> Result<Vec<f64>> {
        // Far from every obstacle the contact equilibrium is the free one:
        // taken when no gap is closer than twice the largest node motion
        // of the step plus 1 mm (nothing can have been passed through).
        if let Ok(eq) = StaticSolver::default().solve(robot, loads, Some(q)) {
            let moved =
                eq.q.as_slice()
                    .chunks(4)
                    .zip(q.chunks(4))
                    .map(|(a, b)| (a[0] - b[0]).hypot(a[1] - b[1]))
                    .fold(0.0, f64::max);
            let min_gap = self
                .obstacles
                .gaps(robot, eq.q.as_slice())?
                .iter()
                .map(|g| g.gap_m)
                .fold(f64::INFINITY, f64::min);
            if min_gap > 2.0 * moved + FREE_MARGIN_M {
                self.report = Some(ContactReport {
                    status: ContactStatus::Converged,
                    min_gap_m: if min_gap.is_finite() {
                        min_gap
                    } else {
                        f64::MAX
                    },
                    residual_norm_n: eq.report.residual_norm_n,
                    residual_tolerance_n: eq.report.residual_tolerance_n,
                    ..ContactReport::default()
                });
                self.contacts.clear();
                return Ok(eq.q.data.into());
            }
        }
        let sol = self.solver.solve(robot, loads, &self.obstacles, Some(q))?;
        let converged = sol.is_converged();
        self.report = Some(sol.report.clone());
        if !converged {
            return Err(Error::ContactNotConverged {
                report: Box::new(sol.report),
            });
        }
        self.contacts = sol.contacts;
        Ok(sol.q.data.into())
    }
}

impl SimulatedPlant {
    /// The plant with rigid obstacles in its world (gaps measured from the
    /// rod's surface, its radius in `obstacles`), the default contact
    /// settings. The current shape is re-solved among them (from the shape
    /// of the actuation alone, so an obstacle in the way is met, not
    /// tunnelled).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `obstacles[i]` for an obstacle
    /// overlapping the plant's base or reference configuration;
    /// [`Error::ContactNotConverged`] if the first contact solve fails.
    pub fn with_obstacles(self, obstacles: Obstacles) -> Result<Self> {
        self.with_contact(PlantContact::new(obstacles, ContactSettings::default())?)
    }

    /// As [`SimulatedPlant::with_obstacles`] with a prepared [`PlantContact`].
    ///
    /// # Errors
    /// As [`SimulatedPlant::with_obstacles`].
    pub fn with_contact(mut self, mut contact: PlantContact) -> Result<Self> {
        contact.obstacles.check_robot(&self.robot)?;
        let mut base = self.base_loads.clone();
        base.pressures_pa.clone_from(&self.actual_pa);
        let loads =
            self.settings
                .payloads
                .loads_at(self.time_s, &self.scene.gravity_m_per_s2, &base);
        let start = self.robot.reference_configuration();
        self.q = contact.solve(&self.robot, &loads, start.as_slice())?;
        self.contact = Some(contact);
        Ok(self)
    }

    /// The plant's obstacles and last contact solve (`None` without
    /// obstacles). For scoring only.
    pub fn contact(&self) -> Option<&PlantContact> {
        self.contact.as_ref()
    }

    /// The true shape now (all coordinates). For scoring only.
    pub fn true_q(&self) -> &[f64] {
        &self.q
    }
}
