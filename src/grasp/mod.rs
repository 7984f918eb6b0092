//! The adaptive pinch grasp (Sec. VI, (45)–(52)): a two-finger gripper,
//! rigid objects that can slip, and two grasp strategies.
//!
//! - [`friction`]: whether contact forces inside the Coulomb cones balance an
//!   object's weight (a second-order cone program, clarabel).
pub mod friction;
pub mod gripper;
pub mod object;
pub mod plant;
pub mod strategy;
pub mod table;
pub mod trial;
