//! Structures: rods, rigid bodies and joints, assembled by connectivity.
//!
//! A model is a set of bodies — ANCF rods (each end clamped to the ground,
//! free, or joined to a rigid body), rigid bodies (a platform, a grasped
//! object) — and joints (a rod end rigidly fixed to a rigid body at a point
//! and direction; a rigid body fixed to the ground). All coordinates `q` (the
//! rods' nodes, the bodies' poses) follow the free coordinates `u` through a
//! [`DofMap`], `q = φ(u)`: the clamp of a single chain is one affine block of
//! it, `q = T u + q̄`.

pub mod dofmap;
pub mod rigid;
pub mod rod;
pub mod section;
mod spec;
mod triplets;

pub use dofmap::{BlockRule, DofMap};
pub use rod::Rod;
pub use spec::Clamp;
pub use triplets::Triplets;
