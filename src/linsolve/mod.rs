//! Linear solvers for the tangent stiffness.
//!
//! [`banded`]: band matrices and their `L D Lᵀ` and pivoted LU factorizations.
pub mod banded;

pub use banded::{BandedLu, BandedMatrix};
