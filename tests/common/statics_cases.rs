//! The static solver's globalization cases (shared by `tests/statics_scaling.rs`
//! and `benches/statics_scaling.rs`): every exudyn reference case plus four
//! hard loads of the kind users apply, each as a scene with `n` elements.
#![allow(dead_code, clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use serde_json::{Value, json};
use softrod::scene::Scene;

/// Bending stiffness of the two-section robot (N·m²).
const EI: f64 = 0.025;
/// Its length (m).
const L: f64 = 0.24;

/// The exudyn reference cases (`reference/exudyn_<case>.json`).
pub const EXUDYN: [&str; 12] = [
    "uniform_small",
    "uniform_large",
    "linear_small",
    "linear_large",
    "gaussian_small",
    "gaussian_large",
    "tip_force_small",
    "tip_force_large",
    "tip_moment_small",
    "tip_moment_large",
    "self_weight_moment_small",
    "self_weight_moment_large",
];

/// The hard cases: their names, in table order.
pub const HARD: [&str; 6] = [
    "mid_force_vs_moment",
    "buckled_column",
    "lateral_column",
    "tip_mass_column",
    "full_circle",
    "estimator_bench",
];

/// Two 0.12 m sections (EA 300 N, EI 0.025 N·m²) of `n/2` and `n − n/2`
/// elements, massless unless `mass` (kg/m), the base at `angle` (rad).
fn scene(n: usize, mass: f64, angle: f64, gravity: bool, loads: Value) -> Scene {
    let section = |k: usize| {
        json!({"length_m": 0.12, "ea_n": 300.0, "ei_nm2": EI,
        "mass_per_length_kg_per_m": mass, "elements": k})
    };
    let text = json!({
        "robot": {"sections": [section(n / 2), section(n - n / 2)]},
        "base": {"position_m": [0.0, 0.0], "angle_rad": angle},
        "gravity_m_per_s2": if gravity { json!([0.0, -9.81]) } else { json!([0.0, 0.0]) },
        "loads": loads,
    });
    let s: Scene = serde_json::from_value(text).unwrap();
    s.validate().unwrap();
    s
}

/// The exudyn reference case `name` (its sections, base and loads) at `n`
/// elements.
pub fn exudyn(name: &str, n: usize) -> Scene {
    let path = format!(
        "{}/reference/exudyn_{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let r: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let p = &r["params"];
    let mut s = scene(n, 0.0, 0.0, false, p["loads"].clone());
    s.base = serde_json::from_value(p["base"].clone()).unwrap();
    for (sec, spec) in s
        .robot
        .sections
        .iter_mut()
        .zip(p["sections"].as_array().unwrap())
    {
        sec.ea_n = spec["ea_n"].as_f64().unwrap();
        sec.ei_nm2 = spec["ei_nm2"].as_f64().unwrap();
        sec.length_m = spec["length_m"].as_f64().unwrap();
    }
    s.validate().unwrap();
    s
}

/// The hard case `name` at `n` elements:
/// - `mid_force_vs_moment`: 2 N down at mid-length against a 0.1 N·m
///   counter-clockwise tip moment (`P L²/EI ≈ 4.6`);
/// - `buckled_column`: base pointing up (tilted 0.01 rad), a uniform weight
///   with `q L³/EI = 12` (buckling starts at 7.84): it falls over;
/// - `lateral_column`: base pointing straight up, the same weight and a
///   0.01 N lateral tip force toward +x ([`lateral_column`]);
/// - `tip_mass_column`: the same column with a 20 g tip mass, tilted
///   0.01 rad toward +x ([`tip_mass_column`]);
/// - `full_circle`: a tip moment `2π EI/L` that rolls the rod into a circle;
/// - `estimator_bench`: the two-section robot with its weight and the
///   default pressures plus the estimator bench's unknown loads (a 20 g tip
///   mass and 0.5 N/m down).
pub fn hard(name: &str, n: usize) -> Scene {
    match name {
        "mid_force_vs_moment" => scene(
            n,
            0.0,
            0.0,
            false,
            json!([{"type": "point_force", "s_m": L / 2.0, "force_n": [0.0, -2.0]},
                   {"type": "tip_moment", "moment_nm": 0.1}]),
        ),
        "buckled_column" => {
            let q = 12.0 * EI / L.powi(3);
            scene(
                n,
                0.0,
                std::f64::consts::FRAC_PI_2 - 0.01,
                false,
                json!([{"type": "distributed", "profile": "uniform", "w_n_per_m": [0.0, -q]}]),
            )
        }
        "lateral_column" => lateral_column(n, 0.01),
        "tip_mass_column" => tip_mass_column(n, 0.01),
        "full_circle" => scene(
            n,
            0.0,
            0.0,
            false,
            json!([{"type": "tip_moment", "moment_nm": 2.0 * std::f64::consts::PI * EI / L}]),
        ),
        "estimator_bench" => {
            let mut s = Scene::two_section();
            s.robot.sections[0].elements = n / 2;
            s.robot.sections[1].elements = n - n / 2;
            s.markers.clear();
            s.loads = serde_json::from_value(json!([
                {"type": "tip_mass", "mass_kg": 0.02},
                {"type": "distributed", "profile": "uniform", "w_n_per_m": [0.0, -0.5]}
            ]))
            .unwrap();
            s.validate().unwrap();
            s
        }
        other => panic!("unknown case {other}"),
    }
}

/// The column standing straight up beyond its buckling load
/// (`q L³/EI = 12`, the weight uniform along it) with a lateral tip force
/// `lateral_n` (N) toward +x, at `n` elements: the branch connected to the
/// unloaded state leans with the force.
pub fn lateral_column(n: usize, lateral_n: f64) -> Scene {
    let q = 12.0 * EI / L.powi(3);
    scene(
        n,
        0.0,
        std::f64::consts::FRAC_PI_2,
        false,
        json!([{"type": "distributed", "profile": "uniform", "w_n_per_m": [0.0, -q]},
               {"type": "point_force", "s_m": L, "force_n": [lateral_n, 0.0]}]),
    )
}

/// The column of [`lateral_column`] (`q L³/EI = 12`, no lateral force)
/// with a 20 g tip mass (under gravity), the base tilted by `tilt_rad`
/// toward +x, at `n` elements: beyond buckling, leaning with the tilt.
pub fn tip_mass_column(n: usize, tilt_rad: f64) -> Scene {
    let q = 12.0 * EI / L.powi(3);
    scene(
        n,
        0.0,
        std::f64::consts::FRAC_PI_2 - tilt_rad,
        true,
        json!([{"type": "distributed", "profile": "uniform", "w_n_per_m": [0.0, -q]},
               {"type": "tip_mass", "mass_kg": 0.02}]),
    )
}

/// Every case: `(name, scene)` at `n` elements.
pub fn all(n: usize) -> Vec<(String, Scene)> {
    EXUDYN
        .iter()
        .map(|c| (format!("exudyn_{c}"), exudyn(c, n)))
        .chain(HARD.iter().map(|c| (c.to_string(), hard(c, n))))
        .collect()
}
