//! What a structure is made of, as written in a scene: rods with their end
//! supports, rigid bodies and joints, and the loads on the bodies.

use serde::{Deserialize, Serialize};

/// What the base clamp prescribes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Clamp {
    /// Position and direction of the base; the axial strain at the base is
    /// free (the physical clamp; default).
    #[default]
    PositionAndDirection,
    /// Position and the whole slope vector `r_0' = t_0` (MODEL.md's literal
    /// reading, and exudyn's cantilevers that fix all four base coordinates):
    /// forbids axial strain at the base, a boundary layer one element long.
    Full,
}
