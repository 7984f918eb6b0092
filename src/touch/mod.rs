//! Touch: finding where an obstacle touches the robot from its markers
//! alone, and steering around it (the paper's Sec. V).
//!
//! - [`five_section_scene`]: the paper's five-section robot.
//! - [`peak_contact`]: the paper's localization, the peak of the estimated
//!   load minus the virtual payload.
//! - [`locate_point_force`]: a concentrated force at an unknown arc
//!   position, found by a 1-D search through the markers' response
//!   ([`MarkerResponse`]).

mod avoid;
mod calibrate;
mod field;
mod peak;
mod point_search;
mod response;
mod robot;
mod scene;

pub use avoid::{
    AvoidRun, AvoidSample, AvoidSettings, AvoidStatus, MAX_AVOID_STEPS, TouchedPoint,
    calibrate_on_free_plant, check_obstacles, run_avoidance,
};
pub use calibrate::{Calibration, FreeFrame, calibrate};
pub use field::{FieldParams, field_gradient, repulsive};
pub use peak::{PeakContact, peak_contact};
pub use point_search::{PointContact, PointSearchSettings, locate_point_force, marker_offset};
pub use response::MarkerResponse;
pub use robot::{ROD_RADIUS_M, SECTION_LENGTH_M, SECTIONS, five_section_scene, marker_arcs};
pub use scene::AvoidScene;

/// How touch's estimators choose their regularization `α` by default (the
/// avoidance's [`AvoidSettings::alpha_rule`] and the
/// localization study's `alpha_rule` (`report::touch::LocalizationCase`,
/// feature `report`)): the discrepancy principle.
///
/// Reason, measured with both rules (six markers, σ = 0.05 mm, the plant
/// not the model, 20 frames averaged; `cargo run --release --example
/// avoid_localization - 20 6 --alpha=evidence`): the paper's method, the
/// peak of the estimated load minus the virtual payload, depends on `α`
/// and is three times worse with the evidence rule (location error mean /
/// max 73 / 268 mm, force error up to 59 mN) than with the discrepancy
/// principle (21 / 68 mm, 27 mN): the evidence rule's smoother loads put
/// the difference's peak far from the contact. The point-force search
/// (0.2 / 0.6 mm) and the avoidance by touch (every placement × goal of
/// `report::touch::FIG9_PLACEMENTS` × `FIG9_GOALS` reached with both rules, final
/// errors 0.02–0.34 mm, `cargo run --release --example avoid_fig9 --
/// --alpha=evidence`) do not depend on the rule. One rule for both, the one
/// under which the paper's method is at its best, keeps the two methods'
/// comparison fair. (The baseline without touch feedback does depend on
/// it: with the evidence rule it slips off the disks sooner and reaches
/// the goals.)
///
/// # Example
/// ```
/// use softrod::estimate::AlphaRule;
/// assert_eq!(softrod::touch::ALPHA_RULE, AlphaRule::Discrepancy);
/// assert_eq!(softrod::touch::AvoidSettings::default().alpha_rule, AlphaRule::Discrepancy);
/// ```
pub const ALPHA_RULE: crate::estimate::AlphaRule = crate::estimate::AlphaRule::Discrepancy;

/// Planar marker positions (m) as vectors, each checked to have two
/// components; `name` is the field named in the error.
pub(crate) fn planar_points(
    name: &str,
    points: &[Vec<f64>],
) -> crate::Result<Vec<nalgebra::Vector2<f64>>> {
    points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            crate::error::check_len(&format!("{name}[{i}]"), 2, p.len())?;
            Ok(nalgebra::Vector2::new(p[0], p[1]))
        })
        .collect()
}
