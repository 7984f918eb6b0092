//! Table I in simulation: the paper's nine objects, five seeded tries each
//! with a randomized placement, both strategies.
//!
//! The objects are sections in the gripper's plane (the object lying
//! across it), sizes, masses and friction coefficients chosen from
//! real-world values (silicone fingers against the object's surface):
//!
//! | object | section | size | mass | μ |
//! |---|---|---|---|---|
//! | ruler | rectangle, standing on edge | 3 × 30 mm | 20 g | 0.5 (plastic) |
//! | marking pen | circle | Ø 18 mm | 15 g | 0.4 (smooth plastic) |
//! | green apple | circle | Ø 70 mm | 150 g | 0.5 (waxy skin) |
//! | plastic bottle | circle | Ø 65 mm | 30 g (empty) | 0.35 (PET) |
//! | tangerine | ellipse | 60 × 50 mm | 90 g | 0.7 (peel) |
//! | red apple | circle | Ø 75 mm | 200 g | 0.5 (waxy skin) |
//! | mouse | rounded rectangle | 60 × 38 mm, corners r 12 mm | 90 g | 0.5 (ABS) |
//! | tape measure | rounded square | 65 × 65 mm, corners r 8 mm | 200 g | 0.5 (rubberized ABS) |
//! | walnut | circle | Ø 32 mm | 10 g | 0.6 (rough shell) |
//!
//! Placement: the object's centre offset uniformly within ±6 mm of the
//! centreline and turned uniformly within ±0.15 rad, from a SplitMix64
//! generator seeded per object and try; both strategies see the same
//! placements. The object is set down so and comes to rest on the table
//! ([`crate::grasp::trial`]): a circle's turn does not matter, the ruler
//! (turns up to 0.079 rad, below the 0.1 rad at which it would fall over)
//! and the tangerine come back upright, the mouse and the tape measure tip
//! onto a face; the offset stays (it shifts by the tipping, a few mm).

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::grasp::gripper::GripperSpec;
use crate::grasp::object::{GraspObject, Shape};
use crate::grasp::trial::{Failure, GraspSettings, Placement, Strategy, TrialOutcome, run_trial};
use crate::rng::SplitMix64;

/// Largest placement offset (m).
pub const MAX_OFFSET_M: f64 = 0.006;
/// Largest placement turn (rad).
pub const MAX_TURN_RAD: f64 = 0.15;

fn circle(name: &str, d_mm: f64, g: f64, mu: f64) -> GraspObject {
    GraspObject {
        name: name.into(),
        shape: Shape::Circle {
            radius_m: 0.5e-3 * d_mm,
        },
        mass_kg: 1e-3 * g,
        mu,
    }
}

fn rounded_rect(name: &str, w_mm: f64, h_mm: f64, r_mm: f64, g: f64, mu: f64) -> GraspObject {
    let (a, b) = (0.5e-3 * w_mm - 1e-3 * r_mm, 0.5e-3 * h_mm - 1e-3 * r_mm);
    GraspObject {
        name: name.into(),
        shape: Shape::RoundedPolygon {
            vertices_m: vec![[-a, -b], [a, -b], [a, b], [-a, b]],
            corner_radius_m: 1e-3 * r_mm,
        },
        mass_kg: 1e-3 * g,
        mu,
    }
}

/// The nine objects of Table I (module docs).
///
/// # Example
/// ```
/// let objects = softrod::report::grasp::table::table_objects();
/// assert_eq!(objects.len(), 9);
/// assert!(objects.iter().all(|o| o.validate("object").is_ok()));
/// ```
pub fn table_objects() -> Vec<GraspObject> {
    vec![
        GraspObject {
            name: "ruler".into(),
            shape: Shape::Rectangle {
                size_m: [0.003, 0.03],
            },
            mass_kg: 0.02,
            mu: 0.5,
        },
        circle("marking pen", 18.0, 15.0, 0.4),
        circle("green apple", 70.0, 150.0, 0.5),
        circle("plastic bottle", 65.0, 30.0, 0.35),
        GraspObject {
            name: "tangerine".into(),
            shape: Shape::Ellipse {
                semi_axes_m: [0.03, 0.025],
            },
            mass_kg: 0.09,
            mu: 0.7,
        },
        circle("red apple", 75.0, 200.0, 0.5),
        rounded_rect("mouse", 60.0, 38.0, 12.0, 90.0, 0.5),
        rounded_rect("tape measure", 65.0, 65.0, 8.0, 200.0, 0.5),
        circle("walnut", 32.0, 10.0, 0.6),
    ]
}

/// The placement of try `k` of object `i` under `seed`.
///
/// # Example
/// ```
/// use softrod::report::grasp::table::{placement, MAX_OFFSET_M};
/// let p = placement(7, 2, 3);
/// assert_eq!(p, placement(7, 2, 3));
/// assert!(p.offset_m.abs() <= MAX_OFFSET_M);
/// ```
pub fn placement(seed: u64, object: usize, try_index: usize) -> Placement {
    let mut rng = SplitMix64::new(
        seed.wrapping_mul(0x2545_F491_4F6C_DD1D)
            .wrapping_add((object as u64) << 32 | try_index as u64),
    );
    Placement {
        offset_m: MAX_OFFSET_M * rng.symmetric(),
        angle_rad: MAX_TURN_RAD * rng.symmetric(),
    }
}

/// One row of the table: an object's tries with one strategy.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TableRow {
    /// The object.
    pub object: String,
    /// The strategy.
    pub strategy: Strategy,
    /// Successful tries.
    pub successes: usize,
    /// Tries.
    pub tries: usize,
    /// Each try's failure (`None`: success).
    pub failures: Vec<Option<Failure>>,
    /// Each try's holding mass (kg).
    pub holding_mass_kg: Vec<f64>,
}

/// Runs `tries` seeded tries of each object with each strategy; `each`
/// sees every outcome (for figures), in order.
///
/// # Errors
/// Bad input only (see [`run_trial`]).
///
/// # Example
/// ```no_run
/// use softrod::grasp::{gripper::GripperSpec, trial::{GraspSettings, Strategy}};
/// use softrod::report::grasp::table::{run_table, table_objects};
/// let rows = run_table(&GripperSpec::default(), &table_objects(), &[Strategy::Adaptive], 5, &GraspSettings::default(), 1, |_| {})?;
/// for r in rows { println!("{} {}/{}", r.object, r.successes, r.tries); }
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn run_table(
    gripper: &GripperSpec,
    objects: &[GraspObject],
    strategies: &[Strategy],
    tries: usize,
    settings: &GraspSettings,
    seed: u64,
    mut each: impl FnMut(&TrialOutcome),
) -> Result<Vec<TableRow>> {
    let mut rows = Vec::new();
    for (i, o) in objects.iter().enumerate() {
        for &strategy in strategies {
            rows.push(run_row(
                gripper, o, i, strategy, tries, settings, seed, &mut each,
            )?);
        }
    }
    Ok(rows)
}

/// One row of [`run_table`]: `tries` seeded tries of `object`, which is
/// number `index` of the table (the placements are keyed by it), with one
/// strategy. A subset of the table reruns exactly by its indices.
///
/// # Errors
/// Bad input only (see [`run_trial`]).
///
/// # Example
/// ```no_run
/// use softrod::grasp::{gripper::GripperSpec, trial::{GraspSettings, Strategy}};
/// use softrod::report::grasp::table::{run_row, table_objects};
/// let mouse = &table_objects()[6];
/// let row = run_row(&GripperSpec::default(), mouse, 6, Strategy::Adaptive, 5, &GraspSettings::default(), 1, |_| {})?;
/// println!("{}/{}", row.successes, row.tries);
/// # Ok::<(), softrod::Error>(())
/// ```
#[allow(clippy::too_many_arguments)]
pub fn run_row(
    gripper: &GripperSpec,
    object: &GraspObject,
    index: usize,
    strategy: Strategy,
    tries: usize,
    settings: &GraspSettings,
    seed: u64,
    mut each: impl FnMut(&TrialOutcome),
) -> Result<TableRow> {
    let mut row = TableRow {
        object: object.name.clone(),
        strategy,
        successes: 0,
        tries,
        failures: Vec::new(),
        holding_mass_kg: Vec::new(),
    };
    for k in 0..tries {
        let p = placement(seed, index, k);
        let out = run_trial(
            gripper,
            object,
            p,
            strategy,
            settings,
            seed ^ ((index * 100 + k) as u64),
        )?;
        row.successes += usize::from(out.success);
        row.failures.push(out.failure.clone());
        row.holding_mass_kg.push(out.holding_mass_kg);
        each(&out);
    }
    Ok(row)
}
