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
mod sweep;

pub use avoid::{
    calibrate_on_free_plant, check_obstacles, run_avoidance, AvoidRun, AvoidSample, AvoidSettings,
    AvoidStatus, TouchedPoint,
};
pub use calibrate::{calibrate, Calibration, FreeFrame};
pub use field::{field_gradient, repulsive, FieldParams};
pub use peak::{peak_contact, PeakContact};
pub use point_search::{locate_point_force, marker_offset, PointContact, PointSearchSettings};
pub use response::MarkerResponse;
pub use robot::{five_section_scene, marker_arcs, ROD_RADIUS_M, SECTIONS, SECTION_LENGTH_M};
pub use scene::AvoidScene;
pub use sweep::{run_localization, LocalizationCase, LocalizationResult, PROBE_RADIUS_M};
