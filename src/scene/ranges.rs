//! The physical range of the scene's fields that have no natural bound in
//! the model (angles, positions, gravity, pressures), and the bounds on the
//! work a scene may ask for (markers, and markers × elements for an
//! estimate). Checked by [`super::Scene::validate`], so every entry point
//! (the library's `Scene::from_json`, every CLI subcommand) refuses the
//! same values, naming the field as written in the file.
//!
//! The stiffnesses, lengths, masses and loads have their bounds where they
//! are checked (`crate::assembly`, `crate::loads`, `MAX_LOAD_SCALE`).

use crate::error::{Error, Result};

use super::Scene;

/// The largest `|base.angle_rad|` (rad): one turn either way. Every angle
/// has an equivalent there; far beyond, `θ + Δθ` rounds back to `θ` and the
/// cold start's arc collapsed (at `1e308` a "converged" shape had its 20
/// nodes behind the clamp). The angle is reduced to `(−π, π]` before use.
pub const MAX_BASE_ANGLE_RAD: f64 = std::f64::consts::TAU;

/// The largest base coordinate and marker-independent position (m): one
/// kilometre from the origin, where the robot's millimetres still have ten
/// significant digits.
pub const MAX_POSITION_M: f64 = 1e3;

/// The largest gravity component (m/s²): 100 g (a centrifuge, not a robot
/// arm; beyond it the self-weight dwarfs every stiffness of the model).
pub const MAX_GRAVITY_M_PER_S2: f64 = 981.0;

/// The largest chamber pressure bound and pressure, either sign (Pa):
/// 10 MPa = 100 bar, ten times what a pneumatic elastomer takes.
pub const MAX_PRESSURE_PA: f64 = 1e7;

/// The most markers a scene or a markers file may have: motion capture has
/// tens. The estimator's work is linear in the markers at a given mesh
/// (its Gauss–Newton systems in the `n_F × n_F` form beyond `n_F` observed
/// components; `benches/estimate_markers.rs`, README "Cost in the number
/// of markers": 20 elements, a first estimate with `α` by the evidence
/// 0.4–0.5 s at 1 000 markers, a warm step 13–18 ms). The command line's
/// `marker_std_m` comes from the markers' posterior covariance, an
/// `n_ob × n_ob` matrix (32 MB at 1 000 planar markers): that, not the
/// estimate, sets this bound.
pub const MAX_MARKERS: usize = 1_000;

/// The largest `markers × elements` of a scene's markers (the ones an
/// estimate or a tracking loop observes): 9 markers on the largest mesh
/// (2 048 elements), 250 on 80, 1 000 on 20 (the benches' case). A
/// linearization's dense work is `O(min(m, n_F)² max(m, n_F))` for `m`
/// observed components and `n_F ≈ 4 × elements` load parameters, so this
/// product bounds it up front.
pub const MAX_MARKER_ELEMENT_PRODUCT: usize = 20_000;

/// `|v| ≤ max` and finite, or the error naming `name`.
fn within(name: &str, v: f64, max: f64, unit: &str) -> Result<()> {
    if v.is_finite() && v.abs() <= max {
        Ok(())
    } else {
        Err(Error::invalid(
            name,
            v,
            format!("must lie in [-{max}, {max}] {unit}"),
        ))
    }
}

/// The angle `a` (rad, `|a| ≤ MAX_BASE_ANGLE_RAD`) in `(−π, π]`; unchanged
/// (bit for bit) when it already lies there.
pub(crate) fn reduce_angle(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    if a > -PI && a <= PI {
        return a;
    }
    let r = a.rem_euclid(TAU); // [0, 2π)
    if r > PI { r - TAU } else { r }
}

/// Checks the ranges of this module on `scene`.
pub(super) fn check(scene: &Scene) -> Result<()> {
    within(
        "base.angle_rad",
        scene.base.angle_rad,
        MAX_BASE_ANGLE_RAD,
        "rad (one turn either way)",
    )?;
    for (k, &x) in scene.base.position_m.iter().enumerate() {
        within(&format!("base.position_m[{k}]"), x, MAX_POSITION_M, "m")?;
    }
    for (k, &g) in scene.gravity_m_per_s2.iter().enumerate() {
        within(
            &format!("gravity_m_per_s2[{k}]"),
            g,
            MAX_GRAVITY_M_PER_S2,
            "m/s² (100 g)",
        )?;
    }
    for (i, s) in scene.robot.sections.iter().enumerate() {
        for (c, ch) in s.chambers.iter().enumerate() {
            let b = format!("robot.sections[{i}].chambers[{c}]");
            within(
                &format!("{b}.pressure_min_pa"),
                ch.pressure_min_pa,
                MAX_PRESSURE_PA,
                "Pa",
            )?;
            within(
                &format!("{b}.pressure_max_pa"),
                ch.pressure_max_pa,
                MAX_PRESSURE_PA,
                "Pa",
            )?;
        }
    }
    for (k, &p) in scene.pressures_pa.iter().enumerate() {
        within(&format!("pressures_pa[{k}]"), p, MAX_PRESSURE_PA, "Pa")?;
    }
    crate::error::check_at_most("markers", scene.markers.len(), MAX_MARKERS)
}

/// Refuses an estimate of `markers` markers on `elements` elements beyond
/// [`MAX_MARKER_ELEMENT_PRODUCT`], naming `field` (the markers' field).
///
/// # Errors
/// [`Error::TooLarge`] naming `field`.
pub(crate) fn check_estimate_work(field: &str, markers: usize, elements: usize) -> Result<()> {
    let max = MAX_MARKER_ELEMENT_PRODUCT / elements.max(1);
    if markers > max {
        return Err(Error::TooLarge {
            name: format!("{field} (× {elements} elements, the estimator's work per iteration)"),
            value: markers,
            max,
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn angles_reduce_into_one_turn_and_stay_bit_identical_inside() {
        for a in [0.0, -0.0, 1.0, -3.0, PI] {
            assert_eq!(reduce_angle(a).to_bits(), a.to_bits());
        }
        assert!((reduce_angle(1.5 * PI) + 0.5 * PI).abs() < 1e-15);
        assert!((reduce_angle(-1.5 * PI) - 0.5 * PI).abs() < 1e-15);
        assert!((reduce_angle(-PI) - PI).abs() < 1e-15);
        assert!((reduce_angle(2.0 * PI)).abs() < 1e-15);
    }
}
