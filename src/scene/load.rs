//! The checks of a scene's known loads ([`Load`]) against its robot.

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{Error, Result};
use crate::loads::{LineLoad, Load, MomentNm};

/// How far beyond the scene's own scale a load may be: a force above
/// `MAX_LOAD_SCALE · EI / L²` (EI the stiffest section's, L the robot's
/// length; a line load `· EI / L³`, a moment `· EI / L`) can only
/// overflow the solve or describe a unit mistake, and is refused up front.
pub(crate) const MAX_LOAD_SCALE: f64 = 1e12;

/// Refuses a component of `values` beyond `MAX_LOAD_SCALE · scale`,
/// naming `name[k]` (or `name` for one number, `indexed` false).
fn check_scale(name: &str, values: &[f64], scale: f64, unit: &str, indexed: bool) -> Result<()> {
    let max = MAX_LOAD_SCALE * scale;
    for (k, v) in values.iter().enumerate() {
        if v.abs() > max {
            let field = if indexed {
                format!("{name}[{k}]")
            } else {
                name.to_string()
            };
            return Err(Error::invalid(
                field,
                v,
                format!(
                    "is more than {MAX_LOAD_SCALE:e} times the robot's own scale ({scale:.3e} {unit}, \
                     from its stiffness and length): it can only overflow (units are SI)"
                ),
            ));
        }
    }
    Ok(())
}

/// Checks that the magnitudes of a (finite, well-sized) load stay within
/// [`MAX_LOAD_SCALE`] of the robot's scale.
fn check_load_scale<E: Element>(robot: &Robot<E>, load: &Load, gravity: &[f64]) -> Result<()> {
    let l = robot.length();
    let ei = robot
        .rod()
        .sections()
        .iter()
        .fold(0.0f64, |m, s| m.max(s.ei_nm2));
    let (force, line, moment) = (ei / (l * l), ei / (l * l * l), ei / l);
    let g = gravity.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    match load {
        Load::Distributed(p) => match p {
            LineLoad::Uniform { w_n_per_m } => {
                check_scale("w_n_per_m", w_n_per_m, line, "N/m", true)
            }
            LineLoad::Linear {
                w_start_n_per_m,
                w_end_n_per_m,
            } => {
                check_scale("w_start_n_per_m", w_start_n_per_m, line, "N/m", true)?;
                check_scale("w_end_n_per_m", w_end_n_per_m, line, "N/m", true)
            }
            LineLoad::Gaussian {
                amplitude_n_per_m, ..
            } => check_scale("amplitude_n_per_m", amplitude_n_per_m, line, "N/m", true),
            LineLoad::Tabulated { w_n_per_m, .. } => {
                for (k, w) in w_n_per_m.iter().enumerate() {
                    check_scale(&format!("w_n_per_m[{k}]"), w, line, "N/m", true)?;
                }
                Ok(())
            }
        },
        Load::TipForce { force_n } | Load::PointForce { force_n, .. } => {
            check_scale("force_n", force_n, force, "N", true)
        }
        Load::TipMoment { moment_nm }
        | Load::NodeMoment { moment_nm, .. }
        | Load::Moment { moment_nm, .. } => match moment_nm {
            MomentNm::Scalar(m) => check_scale("moment_nm", &[*m], moment, "N·m", false),
            MomentNm::Vector(v) => check_scale("moment_nm", v, moment, "N·m", true),
        },
        Load::SelfWeight {
            mass_per_length_kg_per_m: m,
            gravity_m_per_s2: gl,
        } => {
            let gl = gl.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            check_scale("gravity_m_per_s2", &[gl], line, "N/m", false)?;
            check_scale("mass_per_length_kg_per_m", &[m * gl], line, "N/m", false)
        }
        Load::TipMass { mass_kg } => check_scale("mass_kg", &[mass_kg * g], force, "N", false),
        Load::Follower(f) => check_scale(
            "pressure_n_per_m",
            &[f.pressure_n_per_m],
            line,
            "N/m",
            false,
        ),
    }
}

/// Checks one scene load against the robot ([`Load::validate`], the same
/// check [`crate::loads::Loads::add`] makes) and its magnitudes against the
/// robot's scale, naming its fields as in the scene file (the caller
/// prefixes `loads[i].`); `gravity` is the scene's.
pub(super) fn validate_scene_load<E: Element>(
    robot: &Robot<E>,
    load: &Load,
    gravity: &[f64],
) -> Result<()> {
    load.validate(robot, "")?;
    check_load_scale(robot, load, gravity)
}
