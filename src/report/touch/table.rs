//! The avoidance table of the paper's Fig. 9: obstacle placements × goals,
//! each run with touch feedback and without it (the baseline), the plant
//! not the model.
//!
//! Placement rule: a disk counts as a placement only if the baseline's path
//! to every goal meets it (the plant's contact force is positive at some
//! instant of the baseline run); a disk the baseline passes by blocks
//! nothing and proves nothing. [`AvoidRow::baseline_met_obstacle`] says
//! whether a row obeys the rule.

use std::time::Instant;

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::contact::{Obstacle, Obstacles};
use crate::error::Result;
use crate::plant::{PlantSettings, SimulatedPlant};

use crate::touch::{
    AvoidRun, AvoidSettings, AvoidStatus, ROD_RADIUS_M, calibrate_on_free_plant,
    five_section_scene, marker_arcs, run_avoidance,
};

/// The obstacle placements of the table: disks (centre, radius; m) that
/// the baseline's path to both [`FIG9_GOALS`] meets.
///
/// # Example
/// ```
/// let (center, radius) = softrod::report::touch::FIG9_PLACEMENTS[0];
/// assert_eq!((center, radius), (nalgebra::Vector2::new(0.08, -0.465), 0.01));
/// ```
pub const FIG9_PLACEMENTS: [(Vector2<f64>, f64); 5] = [
    (Vector2::new(0.08, -0.465), 0.01),
    (Vector2::new(0.10, -0.455), 0.01),
    (Vector2::new(0.06, -0.475), 0.015),
    (Vector2::new(0.12, -0.45), 0.01),
    (Vector2::new(0.09, -0.48), 0.02),
];

/// The goals of the end effector (m).
///
/// # Example
/// ```
/// assert_eq!(softrod::report::touch::FIG9_GOALS[1], nalgebra::Vector2::new(0.12, -0.36));
/// ```
pub const FIG9_GOALS: [Vector2<f64>; 2] = [Vector2::new(0.15, -0.40), Vector2::new(0.12, -0.36)];

/// What one run did, without its samples.
///
/// # Example
/// ```
/// use softrod::report::touch::AvoidSummary;
/// let s = AvoidSummary::default();
/// assert_eq!((s.touches, s.first_contact_s), (0, None));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AvoidSummary {
    /// How it ended.
    pub status: AvoidStatus,
    /// When the goal was reached for good (s of simulated time).
    pub reached_s: Option<f64>,
    /// Final distance of the true end effector from the goal (m).
    pub final_error_m: f64,
    /// Closest approach of the true end effector to the goal (m).
    pub closest_m: f64,
    /// Wall-clock time of the run (s; machine-dependent, for orientation).
    pub wall_s: f64,
    /// Largest plant contact force before the first localization (N; the
    /// whole run's for the baseline).
    pub max_force_before_n: f64,
    /// Largest plant contact force after it (N).
    pub max_force_after_n: f64,
    /// Plant contact force at the end (N).
    pub final_force_n: f64,
    /// Contacts localized by touch.
    pub touches: usize,
    /// First and last instants with a plant contact force above 1 mN (s).
    pub first_contact_s: Option<f64>,
    /// See `first_contact_s`.
    pub last_contact_s: Option<f64>,
    /// The true end effector at the end (m).
    pub final_tip_m: [f64; 2],
    /// Chamber pressures at a bound at the end.
    pub pressures_at_bounds: usize,
}

impl AvoidSummary {
    /// [`AvoidSummary::final_tip_m`] as a vector (m).
    ///
    /// # Example
    /// ```
    /// let s = softrod::report::touch::AvoidSummary { final_tip_m: [0.15, -0.4], ..Default::default() };
    /// assert_eq!(s.final_tip(), nalgebra::Vector2::new(0.15, -0.4));
    /// ```
    pub fn final_tip(&self) -> Vector2<f64> {
        Vector2::from(self.final_tip_m)
    }
}

impl Default for AvoidSummary {
    fn default() -> Self {
        AvoidSummary {
            status: AvoidStatus::NotReached {
                distance_m: f64::NAN,
            },
            reached_s: None,
            final_error_m: f64::NAN,
            closest_m: f64::NAN,
            wall_s: 0.0,
            max_force_before_n: 0.0,
            max_force_after_n: 0.0,
            final_force_n: 0.0,
            touches: 0,
            first_contact_s: None,
            last_contact_s: None,
            final_tip_m: [f64::NAN; 2],
            pressures_at_bounds: 0,
        }
    }
}

impl AvoidSummary {
    /// The summary of `run`, which took `wall_s`, the chambers' bounds
    /// `bounds` (Pa).
    pub fn of(run: &AvoidRun, wall_s: f64, bounds: &[(f64, f64)]) -> Self {
        let g = run.goal();
        let dist = |t: [f64; 2]| (Vector2::from(t) - g).norm();
        let touching = |s: &&crate::touch::AvoidSample| s.contact_force_n > 1e-3;
        let last = run.samples.last();
        AvoidSummary {
            status: run.status,
            reached_s: match run.status {
                AvoidStatus::Reached { time_s } => Some(time_s),
                _ => None,
            },
            final_error_m: run.final_error_m,
            closest_m: run
                .samples
                .iter()
                .map(|s| dist(s.tip_true_m))
                .fold(f64::NAN, f64::min),
            wall_s,
            max_force_before_n: run.max_force_before_n,
            max_force_after_n: run.max_force_after_n,
            final_force_n: run.final_force_n,
            touches: run.touched.len(),
            first_contact_s: run.samples.iter().find(touching).map(|s| s.time_s),
            last_contact_s: run.samples.iter().rev().find(touching).map(|s| s.time_s),
            final_tip_m: last.map_or([f64::NAN; 2], |s| s.tip_true_m),
            pressures_at_bounds: last.map_or(0, |s| {
                s.pressures_pa
                    .iter()
                    .zip(bounds)
                    .filter(|(p, (lo, hi))| {
                        let tol = 1e-6 * (hi - lo);
                        **p <= lo + tol || **p >= hi - tol
                    })
                    .count()
            }),
        }
    }
}

/// One placement and goal: the run by touch and the baseline.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AvoidRow {
    /// The disk's centre (m).
    pub center_m: [f64; 2],
    /// The disk's radius (m).
    pub radius_m: f64,
    /// The goal (m).
    pub goal_m: [f64; 2],
    /// With touch feedback.
    pub touch: AvoidSummary,
    /// Without it.
    pub baseline: AvoidSummary,
}

impl AvoidRow {
    /// [`AvoidRow::center_m`] as a vector (m).
    ///
    /// # Example
    /// ```
    /// use softrod::report::touch::{AvoidRow, AvoidSummary};
    /// let row = AvoidRow { center_m: [0.08, -0.465], radius_m: 0.01, goal_m: [0.15, -0.4],
    ///     touch: AvoidSummary::default(), baseline: AvoidSummary::default() };
    /// assert_eq!(row.center(), nalgebra::Vector2::new(0.08, -0.465));
    /// assert_eq!(row.goal(), nalgebra::Vector2::new(0.15, -0.4));
    /// ```
    pub fn center(&self) -> Vector2<f64> {
        Vector2::from(self.center_m)
    }

    /// [`AvoidRow::goal_m`] as a vector (m).
    ///
    /// # Example
    /// See [`AvoidRow::center`].
    pub fn goal(&self) -> Vector2<f64> {
        Vector2::from(self.goal_m)
    }

    /// Whether the baseline met the obstacle (the placement rule).
    pub fn baseline_met_obstacle(&self) -> bool {
        self.baseline.max_force_before_n > 1e-3
    }
}

/// Runs every placement × goal with touch feedback and without it on the
/// five-section robot (6 markers; the model calibrated on the obstacle-free
/// plant once), each run `settings` with `touch_feedback` set per run.
///
/// # Example
/// ```
/// use softrod::report::touch::{avoidance_table, FIG9_GOALS, FIG9_PLACEMENTS};
/// use softrod::touch::AvoidSettings;
/// // one placement and goal, 0.5 s of each run (the table's runs take 120 s)
/// let settings = AvoidSettings { duration_s: 0.5, ..AvoidSettings::default() };
/// let rows = avoidance_table(&FIG9_PLACEMENTS[..1], &FIG9_GOALS[..1],
///     &softrod::plant::PlantSettings::default(), &settings)?;
/// assert_eq!(rows.len(), 1);
/// assert!(!rows[0].baseline.status.is_reached() && !rows[0].baseline_met_obstacle());
/// # Ok::<(), softrod::Error>(())
/// ```
///
/// # Errors
/// As [`calibrate_on_free_plant`], [`Obstacles::new`] and
/// [`run_avoidance`].
pub fn avoidance_table(
    placements: &[(Vector2<f64>, f64)],
    goals: &[Vector2<f64>],
    plant: &PlantSettings,
    settings: &AvoidSettings,
) -> Result<Vec<AvoidRow>> {
    let scene = five_section_scene(settings.model_elements);
    let arcs = marker_arcs(6);
    let arcs = arcs.as_slice();
    let cal = calibrate_on_free_plant(&scene, arcs, plant)?;
    let bounds = scene.robot()?.pressure_bounds();
    let mut rows = Vec::new();
    for &(center_m, radius_m) in placements {
        for &goal_m in goals {
            let summary = |feedback: bool| -> Result<AvoidSummary> {
                let obstacles = Obstacles::new(
                    vec![Obstacle::Circle {
                        center_m: center_m.into(),
                        radius_m,
                    }],
                    ROD_RADIUS_M,
                )?;
                let mut p =
                    SimulatedPlant::new(&scene, arcs, plant.clone())?.with_obstacles(obstacles)?;
                let s = AvoidSettings {
                    touch_feedback: feedback,
                    ..settings.clone()
                };
                let start = Instant::now();
                let run = run_avoidance(&scene, &cal, arcs, &mut p, goal_m, &s)?;
                Ok(AvoidSummary::of(
                    &run,
                    start.elapsed().as_secs_f64(),
                    &bounds,
                ))
            };
            let touch = summary(true)?;
            let baseline = summary(false)?;
            rows.push(AvoidRow {
                center_m: center_m.into(),
                radius_m,
                goal_m: goal_m.into(),
                touch,
                baseline,
            });
        }
    }
    Ok(rows)
}
