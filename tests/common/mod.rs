//! Fixtures shared by the integration tests (`mod common;` in each file).
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use serde_json::Value;

/// The committed reference `reference/<name>.json` (written by a
/// `validation/` script from a code we did not write).
pub fn reference(name: &str) -> Value {
    let path = format!("{}/reference/{name}.json", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"))
}

use softrod::assembly::Section;
use softrod::structure::{JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureSpec};

/// Leg length of [`two_legs`] (m).
pub const LEG_L: f64 = 0.2;
/// Half spacing of [`two_legs`]' legs (m).
pub const LEG_RHO: f64 = 0.05;
/// Bending stiffness of [`two_legs`]' legs (N·m², the paper's simulated robot).
pub const LEG_EI: f64 = 0.02;
/// Axial stiffness of [`two_legs`]' legs (N).
pub const LEG_EA: f64 = 300.0;

/// Two vertical legs of `n` elements at x = ±ρ, clamped at y = 0, tips fixed
/// to a platform at (0, L) of mass `mass_kg`; gravity `[0, −9.81]` or none.
pub fn two_legs(n: usize, mass_kg: f64, gravity: bool) -> StructureSpec {
    let leg = |x: f64| {
        RodSpec::clamped(
            vec![Section::uniform(LEG_L, LEG_EA, LEG_EI, n)],
            nalgebra::Vector2::new(x, 0.0),
            nalgebra::Vector2::new(0.0, 1.0),
        )
    };
    let joint = |rod| JointSpec::RodToBody {
        rod,
        end: RodEnd::End,
        body: 0,
        point_m: None,
        direction: None,
    };
    let mut spec = StructureSpec::new(
        vec![leg(-LEG_RHO), leg(LEG_RHO)],
        vec![RigidBodySpec {
            mass_kg,
            position_m: vec![0.0, LEG_L],
            orientation_rad: vec![0.0],
        }],
        vec![joint(0), joint(1)],
    );
    if !gravity {
        spec.gravity_m_per_s2 = vec![0.0, 0.0];
    }
    spec
}

/// Seeded pseudo-random numbers in [-1, 1) (Knuth's MMIX LCG).
pub fn lcg(seed: u64, n: usize) -> Vec<f64> {
    let mut s = seed;
    (0..n)
        .map(|_| {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            2.0 * ((s >> 11) as f64 / (1u64 << 53) as f64) - 1.0
        })
        .collect()
}
