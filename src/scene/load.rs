//! The known loads of a scene: forces, moments, weights, in 2-D or 3-D.

use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{
    check_all_finite, check_finite, check_index, check_len, check_positive, Error, Result,
};
use crate::loads::{FollowerLoad, LineLoad, Loads, NodeMoment, PointForce, PointMoment};

/// A known load of a scene (dead, world axes, SI). Vectors have as many
/// components as the scene's element has dimensions (2 for `planar_cable`,
/// 3 for `spatial_cable`); a moment is one number in 2-D and a 3-vector in 3-D.
///
/// # Example
/// ```
/// use softrod::scene::{MomentNm, SceneLoad};
/// let l: SceneLoad = serde_json::from_str(
///     r#"{"type": "tip_moment", "moment_nm": [0, 0.01, 0]}"#).unwrap();
/// assert_eq!(l, SceneLoad::TipMoment { moment_nm: MomentNm::Vector(vec![0.0, 0.01, 0.0]) });
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum SceneLoad {
    /// A distributed load with a profile (`uniform`, `linear`, `gaussian`,
    /// `tabulated`).
    Distributed(LineLoad),
    /// A force at the tip (N).
    TipForce {
        /// Force (N).
        force_n: Vec<f64>,
    },
    /// A force at arc coordinate `s_m` (N).
    PointForce {
        /// Arc coordinate (m).
        s_m: f64,
        /// Force (N).
        force_n: Vec<f64>,
    },
    /// A moment at the tip node (N·m).
    TipMoment {
        /// Moment (N·m; in 2-D one number, counter-clockwise positive; in
        /// 3-D a vector in world axes).
        moment_nm: MomentNm,
    },
    /// A moment at a node (N·m).
    NodeMoment {
        /// Node index (1 ..= number of elements).
        node: usize,
        /// Moment (N·m, as for `tip_moment`).
        moment_nm: MomentNm,
    },
    /// A concentrated moment at arc coordinate `s_m` (N·m), anywhere on the
    /// robot beyond the clamped base (between nodes it acts on the
    /// element's two nodes through the interpolated tangent; see
    /// [`crate::loads::PointMoment`]).
    Moment {
        /// Arc coordinate (m, > 0).
        s_m: f64,
        /// Moment (N·m, as for `tip_moment`).
        moment_nm: MomentNm,
    },
    /// An extra uniform weight (kg/m) under its own gravity vector.
    SelfWeight {
        /// Mass per length (kg/m).
        mass_per_length_kg_per_m: f64,
        /// Gravity (m/s²).
        gravity_m_per_s2: Vec<f64>,
    },
    /// A pressure normal to the deformed backbone (N/m, planar scenes):
    /// `pressure_n_per_m`, optionally on `[s_start_m, s_end_m]` only; see
    /// [`crate::loads::FollowerLoad`].
    Follower(FollowerLoad),
    /// A mass hanging at the tip (kg), under the scene's gravity.
    TipMass {
        /// Mass (kg).
        mass_kg: f64,
    },
}

impl SceneLoad {
    /// Adds this load, the scene's `loads[i]`, to `loads` in the code's
    /// terms ([`Loads`]): the one conversion from a scene's loads, which
    /// [`super::Scene::loads`] runs for each. A tip load acts at the arc
    /// coordinate `length_m` or the last of `n_nodes` nodes; a tip mass
    /// under `gravity` (m/s²), which must have `dim` components.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `loads[i]....` for a non-positive
    /// tip mass or a negative extra weight; [`Error::DimensionMismatch`]
    /// for a gravity vector of the wrong size.
    pub(crate) fn resolve_into(
        &self,
        i: usize,
        dim: usize,
        length_m: f64,
        n_nodes: usize,
        gravity: &[f64],
        loads: &mut Loads,
    ) -> Result<()> {
        let (total, d) = (length_m, dim);
        match self {
            SceneLoad::Distributed(p) => loads.line_loads.push(p.clone()),
            SceneLoad::Follower(f) => loads.follower_loads.push(f.clone()),
            SceneLoad::TipForce { force_n } => loads.point_forces.push(PointForce {
                s_m: total,
                force_n: force_n.clone(),
            }),
            SceneLoad::PointForce { s_m, force_n } => loads.point_forces.push(PointForce {
                s_m: *s_m,
                force_n: force_n.clone(),
            }),
            SceneLoad::TipMoment { moment_nm } => loads.node_moments.push(NodeMoment {
                node: n_nodes - 1,
                moment_nm: moment_nm.components(),
            }),
            SceneLoad::NodeMoment { node, moment_nm } => loads.node_moments.push(NodeMoment {
                node: *node,
                moment_nm: moment_nm.components(),
            }),
            SceneLoad::Moment { s_m, moment_nm } => loads.point_moments.push(PointMoment {
                s_m: *s_m,
                moment_nm: moment_nm.components(),
            }),
            SceneLoad::SelfWeight {
                mass_per_length_kg_per_m: m,
                gravity_m_per_s2: g,
            } => {
                if !(m.is_finite() && *m >= 0.0) {
                    return Err(Error::invalid(
                        format!("loads[{i}].mass_per_length_kg_per_m"),
                        m,
                        "must be finite and >= 0",
                    ));
                }
                check_len(&format!("loads[{i}].gravity_m_per_s2"), d, g.len())?;
                loads.line_loads.push(LineLoad::Uniform {
                    w_n_per_m: g.iter().map(|g| m * g).collect(),
                })
            }
            SceneLoad::TipMass { mass_kg } => {
                check_positive(&format!("loads[{i}].mass_kg"), *mass_kg)?;
                check_len("gravity_m_per_s2", d, gravity.len())?;
                loads.point_forces.push(PointForce {
                    s_m: total,
                    force_n: gravity.iter().map(|g| mass_kg * g).collect(),
                })
            }
        }
        Ok(())
    }
}

/// A concentrated moment in a scene file (N·m): a number in a planar scene,
/// an array of three numbers (world axes) in a spatial one.
///
/// # Example
/// ```
/// use softrod::scene::MomentNm;
/// let planar: MomentNm = serde_json::from_str("0.01").unwrap();
/// assert_eq!(planar.components(), vec![0.01]);
/// let spatial: MomentNm = serde_json::from_str("[0, 0, 0.01]").unwrap();
/// assert_eq!(spatial.components(), vec![0.0, 0.0, 0.01]);
/// assert_eq!(serde_json::to_string(&planar).unwrap(), "0.01");
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum MomentNm {
    /// One number (N·m): the planar moment.
    Scalar(f64),
    /// Components in world axes (N·m): the spatial moment.
    Vector(Vec<f64>),
}

impl MomentNm {
    /// The moment's components (one for [`MomentNm::Scalar`]).
    pub fn components(&self) -> Vec<f64> {
        match self {
            MomentNm::Scalar(m) => vec![*m],
            MomentNm::Vector(v) => v.clone(),
        }
    }

    /// Checks that the moment has `dim` finite components; `name` is its field.
    fn validate(&self, name: &str, dim: usize) -> Result<()> {
        match (self, dim) {
            (MomentNm::Scalar(_), 1) => {}
            (MomentNm::Scalar(_), _) => {
                return Err(Error::invalid(
                    name,
                    "a number",
                    format!(
                        "a moment in this scene is an array of {dim} numbers (N·m, world axes)"
                    ),
                ))
            }
            (MomentNm::Vector(v), 1) => {
                return Err(Error::invalid(
                    name,
                    format!("{v:?}"),
                    "a moment in a planar scene is one number (N·m, counter-clockwise positive)",
                ))
            }
            (MomentNm::Vector(v), _) => check_len(name, dim, v.len())?,
        }
        match self {
            MomentNm::Scalar(m) => check_finite(name, *m),
            MomentNm::Vector(v) => check_all_finite(name, v),
        }
    }
}

impl From<f64> for MomentNm {
    fn from(m: f64) -> Self {
        MomentNm::Scalar(m)
    }
}

impl<'de> Deserialize<'de> for MomentNm {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = MomentNm;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("`moment_nm` as a number (planar) or an array of 3 numbers (spatial)")
            }
            fn visit_f64<Er: serde::de::Error>(self, v: f64) -> std::result::Result<MomentNm, Er> {
                Ok(MomentNm::Scalar(v))
            }
            fn visit_i64<Er: serde::de::Error>(self, v: i64) -> std::result::Result<MomentNm, Er> {
                Ok(MomentNm::Scalar(v as f64))
            }
            fn visit_u64<Er: serde::de::Error>(self, v: u64) -> std::result::Result<MomentNm, Er> {
                Ok(MomentNm::Scalar(v as f64))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> std::result::Result<MomentNm, A::Error> {
                use serde::de::Error as _;
                // (a tagged load loses the path below `loads[i]`: name the field)
                let mut v = Vec::new();
                while let Some(x) = seq
                    .next_element::<f64>()
                    .map_err(|e| A::Error::custom(format!("moment_nm[{}]: {e}", v.len())))?
                {
                    if v.len() >= 3 {
                        return Err(A::Error::custom(
                            "moment_nm: more than 3 components (N·m, world axes)",
                        ));
                    }
                    v.push(x);
                }
                Ok(MomentNm::Vector(v))
            }
        }
        d.deserialize_any(V)
    }
}

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
fn check_load_scale<E: Element>(robot: &Robot<E>, load: &SceneLoad, gravity: &[f64]) -> Result<()> {
    let l = robot.length();
    let ei = robot
        .rod()
        .sections()
        .iter()
        .fold(0.0f64, |m, s| m.max(s.ei_nm2));
    let (force, line, moment) = (ei / (l * l), ei / (l * l * l), ei / l);
    let g = gravity.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    match load {
        SceneLoad::Distributed(p) => match p {
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
        SceneLoad::TipForce { force_n } | SceneLoad::PointForce { force_n, .. } => {
            check_scale("force_n", force_n, force, "N", true)
        }
        SceneLoad::TipMoment { moment_nm }
        | SceneLoad::NodeMoment { moment_nm, .. }
        | SceneLoad::Moment { moment_nm, .. } => match moment_nm {
            MomentNm::Scalar(m) => check_scale("moment_nm", &[*m], moment, "N·m", false),
            MomentNm::Vector(v) => check_scale("moment_nm", v, moment, "N·m", true),
        },
        SceneLoad::SelfWeight {
            mass_per_length_kg_per_m: m,
            gravity_m_per_s2: gl,
        } => {
            let gl = gl.iter().fold(0.0f64, |a, v| a.max(v.abs()));
            check_scale("gravity_m_per_s2", &[gl], line, "N/m", false)?;
            check_scale("mass_per_length_kg_per_m", &[m * gl], line, "N/m", false)
        }
        SceneLoad::TipMass { mass_kg } => check_scale("mass_kg", &[mass_kg * g], force, "N", false),
        SceneLoad::Follower(f) => check_scale(
            "pressure_n_per_m",
            &[f.pressure_n_per_m],
            line,
            "N/m",
            false,
        ),
    }
}

/// Checks one scene load against the robot, naming its fields as in the
/// scene file (the caller prefixes `loads[i].`); `gravity` is the scene's.
pub(super) fn validate_scene_load<E: Element>(
    robot: &Robot<E>,
    load: &SceneLoad,
    gravity: &[f64],
) -> Result<()> {
    validate_scene_load_values(robot, load)?;
    check_load_scale(robot, load, gravity)
}

/// The value checks of [`validate_scene_load`] (sizes, finiteness, places).
fn validate_scene_load_values<E: Element>(robot: &Robot<E>, load: &SceneLoad) -> Result<()> {
    let d = E::DIM;
    let vector = |name: &str, v: &[f64]| -> Result<()> {
        check_len(name, d, v.len())?;
        check_all_finite(name, v)
    };
    match load {
        SceneLoad::Distributed(l) => {
            l.validate("", d)?;
            l.check_on_robot("", robot.length())?;
            match l {
                // a bump centred off the robot acts only through its tail:
                // almost surely a typo (a length in mm, the wrong section)
                LineLoad::Gaussian { center_m, .. } => {
                    robot.locate("center_m", *center_m).map(|_| ())
                }
                _ => Ok(()),
            }
        }
        SceneLoad::TipForce { force_n } => vector("force_n", force_n),
        SceneLoad::PointForce { s_m, force_n } => {
            vector("force_n", force_n)?;
            robot.locate("s_m", *s_m).map(|_| ())
        }
        SceneLoad::TipMoment { moment_nm } => moment_nm.validate("moment_nm", E::MOMENT_DIM),
        SceneLoad::NodeMoment { node, moment_nm } => {
            moment_nm.validate("moment_nm", E::MOMENT_DIM)?;
            check_index("node", *node, robot.n_nodes())?;
            if *node == 0 {
                return Err(Error::invalid(
                    "node",
                    0,
                    "the clamped base takes no moment: must be a free node, >= 1",
                ));
            }
            Ok(())
        }
        SceneLoad::Moment { s_m, moment_nm } => {
            moment_nm.validate("moment_nm", E::MOMENT_DIM)?;
            robot.locate("s_m", *s_m)?;
            if *s_m <= 0.0 {
                return Err(Error::invalid(
                    "s_m",
                    s_m,
                    "the clamped base takes no moment: must be > 0",
                ));
            }
            Ok(())
        }
        SceneLoad::SelfWeight {
            mass_per_length_kg_per_m: m,
            gravity_m_per_s2: g,
        } => {
            if !(m.is_finite() && *m >= 0.0) {
                return Err(Error::invalid(
                    "mass_per_length_kg_per_m",
                    m,
                    "must be finite and >= 0",
                ));
            }
            vector("gravity_m_per_s2", g)
        }
        SceneLoad::TipMass { mass_kg } => check_positive("mass_kg", *mass_kg),
        SceneLoad::Follower(f) => {
            if d != 2 {
                return Err(Error::invalid(
                    "type",
                    "\"follower\"",
                    "a pressure normal to the backbone needs a planar scene (planar_cable)",
                ));
            }
            f.validate("", robot.length())
        }
    }
}
