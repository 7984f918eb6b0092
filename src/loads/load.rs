//! [`Load`]: one known load, as a scene file states it and as code adds it
//! to the [`Loads`] of a solve. Its checks against a robot
//! ([`Load::validate`]) and [`Loads::add`] live with the robot
//! (`assembly`), so that this module needs none of it.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_all_finite, check_finite, check_len, check_positive};

use super::{FollowerLoad, LineLoad, Loads, NodeMoment, PointForce, PointMoment};

/// One known load, in code and in a scene file alike: a scene's `loads`
/// list deserializes into `Vec<Load>`, and code adds the same loads to a
/// [`Loads`] with [`Loads::add`] (a tip load at the robot's tip, a tip mass
/// under the robot's gravity). Dead, world axes, SI. Vectors have as many
/// components as the element has dimensions (2 for `planar_cable`, 3 for
/// `spatial_cable`); a moment is one number in 2-D and a 3-vector in 3-D.
///
/// # Example
/// ```
/// use softrod::loads::{Load, Loads, MomentNm};
/// let l: Load = serde_json::from_str(
///     r#"{"type": "tip_moment", "moment_nm": [0, 0.01, 0]}"#).unwrap();
/// assert_eq!(l, Load::TipMoment { moment_nm: MomentNm::Vector(vec![0.0, 0.01, 0.0]) });
/// // in code: a 20 g tip mass and an extra weight, on a planar robot
/// let robot = softrod::scene::Scene::two_section().robot()?;
/// let mut loads = Loads { pressures_pa: vec![0.0; 4], ..Loads::default() };
/// loads.add(&robot, &Load::TipMass { mass_kg: 0.02 })?;
/// loads.add(&robot, &Load::SelfWeight { mass_per_length_kg_per_m: 0.01, gravity_m_per_s2: vec![0.0, -9.81] })?;
/// assert_eq!(loads.point_forces[0].s_m, robot.length());
/// assert!((loads.point_forces[0].force_n[1] + 0.02 * 9.81).abs() < 1e-15);
/// assert_eq!(loads.add(&robot, &Load::TipMass { mass_kg: -1.0 }).unwrap_err().field(), Some("mass_kg"));
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Load {
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
    /// [`PointMoment`]).
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
    /// [`FollowerLoad`].
    Follower(FollowerLoad),
    /// A mass hanging at the tip (kg), under the scene's gravity.
    TipMass {
        /// Mass (kg).
        mass_kg: f64,
    },
}

impl Load {
    /// The checks of [`Load::validate`] that need no robot: sizes (`dim`
    /// components, a moment `moment_dim`), finite values and signs. Errors
    /// name the load's own fields.
    pub(crate) fn check_values(&self, dim: usize, moment_dim: usize) -> Result<()> {
        let vector = |name: &str, v: &[f64]| -> Result<()> {
            check_len(name, dim, v.len())?;
            check_all_finite(name, v)
        };
        match self {
            Load::Distributed(l) => l.validate("", dim),
            Load::TipForce { force_n } | Load::PointForce { force_n, .. } => {
                vector("force_n", force_n)
            }
            Load::TipMoment { moment_nm }
            | Load::NodeMoment { moment_nm, .. }
            | Load::Moment { moment_nm, .. } => moment_nm.validate("moment_nm", moment_dim),
            Load::SelfWeight {
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
            Load::TipMass { mass_kg } => check_positive("mass_kg", *mass_kg),
            Load::Follower(f) => {
                if dim != 2 {
                    return Err(Error::invalid(
                        "type",
                        "\"follower\"",
                        "a pressure normal to the backbone needs a planar scene (planar_cable)",
                    ));
                }
                check_finite("pressure_n_per_m", f.pressure_n_per_m)
            }
        }
    }

    /// Adds this load to `loads` in the solver's terms: a tip load acts at
    /// the arc coordinate `length_m` or the last of `n_nodes` nodes; a tip
    /// mass under `gravity` (m/s²), which must have `dim` components. The
    /// load's values are checked by the callers ([`Load::validate`],
    /// [`Load::check_values`]).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a `gravity` of the wrong size.
    pub(crate) fn resolve_into(
        &self,
        dim: usize,
        length_m: f64,
        n_nodes: usize,
        gravity: &[f64],
        loads: &mut Loads,
    ) -> Result<()> {
        let (total, d) = (length_m, dim);
        match self {
            Load::Distributed(p) => loads.line_loads.push(p.clone()),
            Load::Follower(f) => loads.follower_loads.push(f.clone()),
            Load::TipForce { force_n } => loads.point_forces.push(PointForce {
                s_m: total,
                force_n: force_n.clone(),
            }),
            Load::PointForce { s_m, force_n } => loads.point_forces.push(PointForce {
                s_m: *s_m,
                force_n: force_n.clone(),
            }),
            Load::TipMoment { moment_nm } => loads.node_moments.push(NodeMoment {
                node: n_nodes - 1,
                moment_nm: moment_nm.components(),
            }),
            Load::NodeMoment { node, moment_nm } => loads.node_moments.push(NodeMoment {
                node: *node,
                moment_nm: moment_nm.components(),
            }),
            Load::Moment { s_m, moment_nm } => loads.point_moments.push(PointMoment {
                s_m: *s_m,
                moment_nm: moment_nm.components(),
            }),
            Load::SelfWeight {
                mass_per_length_kg_per_m: m,
                gravity_m_per_s2: g,
            } => loads.line_loads.push(LineLoad::Uniform {
                w_n_per_m: g.iter().map(|g| m * g).collect(),
            }),
            Load::TipMass { mass_kg } => {
                // the robot's (or scene's) gravity, not a field of the load
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

/// A concentrated moment of a [`Load`] (N·m): a number on a planar robot,
/// an array of three numbers (world axes) on a spatial one.
///
/// # Example
/// ```
/// use softrod::loads::MomentNm;
/// let planar: MomentNm = serde_json::from_str("0.01").unwrap();
/// assert_eq!(planar, MomentNm::Scalar(0.01));
/// let spatial: MomentNm = serde_json::from_str("[0, 0, 0.01]").unwrap();
/// assert_eq!(spatial.vector::<3>()?, nalgebra::Vector3::new(0.0, 0.0, 0.01));
/// assert!(planar.vector::<3>().is_err());
/// assert_eq!(serde_json::to_string(&planar).unwrap(), "0.01");
/// # Ok::<(), softrod::Error>(())
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
    pub(crate) fn components(&self) -> Vec<f64> {
        match self {
            MomentNm::Scalar(m) => vec![*m],
            MomentNm::Vector(v) => v.clone(),
        }
    }

    /// Checks that the moment has `dim` finite components; `name` is its field.
    pub(crate) fn validate(&self, name: &str, dim: usize) -> Result<()> {
        match (self, dim) {
            (MomentNm::Scalar(_), 1) => {}
            (MomentNm::Scalar(_), _) => {
                return Err(Error::invalid(
                    name,
                    "a number",
                    format!(
                        "a moment in this scene is an array of {dim} numbers (N·m, world axes)"
                    ),
                ));
            }
            (MomentNm::Vector(v), 1) => {
                return Err(Error::invalid(
                    name,
                    format!("{v:?}"),
                    "a moment in a planar scene is one number (N·m, counter-clockwise positive)",
                ));
            }
            (MomentNm::Vector(v), _) => check_len(name, dim, v.len())?,
        }
        match self {
            MomentNm::Scalar(m) => check_finite(name, *m),
            MomentNm::Vector(v) => check_all_finite(name, v),
        }
    }
}

impl MomentNm {
    /// The moment as a `D`-vector (N·m; `D = 1` for a planar moment, 3 for
    /// a spatial one).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `moment_nm` if it has another
    /// number of components.
    ///
    /// # Example
    /// See [`MomentNm`].
    pub fn vector<const D: usize>(&self) -> Result<nalgebra::SVector<f64, D>> {
        let c = self.components();
        check_len("moment_nm", D, c.len())?;
        Ok(nalgebra::SVector::from_column_slice(&c))
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
