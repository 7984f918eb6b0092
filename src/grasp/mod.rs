//! The adaptive pinch grasp (Sec. VI, (45)–(52)): a two-finger gripper,
//! rigid objects that can slip, and two grasp strategies.
//!
//! - [`friction`]: whether contact forces inside the Coulomb cones balance an
//!   object's weight (a second-order cone program, clarabel).
//! - [`gripper`]: the two mirrored two-segment fingers (dimensions in
//!   [`crate::params::gripper`]), per finger and as one structure.
//! - [`object`]: the objects (circle, ellipse, rectangle, rounded polygon)
//!   with mass and friction, their outlines and their circle covers.
//! - [`plant`]: the gripper as the "real robot" (not the model), with exact
//!   contact against the object and the table.
//! - [`strategy`]: the contact pose (46)–(49) with a signed angle, the
//!   Jacobian (50), the bounded least-squares step of (51)/(52).
//! - `rest` (internal): the object on the table as a planar rigid body
//!   under gravity, the table's friction and the fingers' pushes.
//! - `slip` (internal): the lifted object as a planar rigid body that
//!   settles in the fingers (Gauss's principle of least constraint).
//! - [`trial`]: one quasi-static grasp trial and its success criterion.
//! - [`scene`]: the grasp scene file of `softrod grasp`, parsed and checked.

pub mod friction;
pub mod gripper;
pub mod object;
pub mod plant;
mod rest;
pub mod scene;
mod slip;
pub mod strategy;
pub mod trial;

#[cfg(test)]
mod fixtures;
