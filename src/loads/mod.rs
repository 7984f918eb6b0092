//! Known loads: line loads given by a profile, point forces, concentrated
//! moments, the pressures of the actuation, and the unknown distributed load
//! field `w(X) = S(X) F` (8), (16).
//!
//! Every load here is dead (fixed in world axes). Self-weight comes from
//! the sections' mass per length and the scene's gravity, not from here.
//! Forces that depend on the configuration (a spring holding a point, later
//! contact) are [`force_field::ForceField`]s: energy, force and stiffness at
//! `q`.

pub mod force_field;

use serde::{Deserialize, Serialize};

use crate::error::{check_all_finite, check_finite, check_positive, Error, Result};

/// A known distributed load along the backbone (N/m, world axes), as a
/// function of the undeformed arc coordinate `X` (m).
///
/// # Example
/// ```
/// use softrod::loads::LineLoad;
/// let w = LineLoad::Linear { w_start_n_per_m: vec![0.0, 0.0], w_end_n_per_m: vec![0.0, -2.0] };
/// assert_eq!(w.at(0.5, 1.0), vec![0.0, -1.0]);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "profile", rename_all = "snake_case", deny_unknown_fields)]
pub enum LineLoad {
    /// Constant `w` (N/m).
    Uniform {
        /// Load per undeformed length (N/m).
        w_n_per_m: Vec<f64>,
    },
    /// Linear in `X` from the base (`X = 0`) to the tip (`X = L`).
    Linear {
        /// Load per length at the base (N/m).
        w_start_n_per_m: Vec<f64>,
        /// Load per length at the tip (N/m).
        w_end_n_per_m: Vec<f64>,
    },
    /// A Gaussian bump `A exp(-(X - X0)² / (2 σ²))`, like a contact.
    Gaussian {
        /// Peak load per length `A` (N/m).
        amplitude_n_per_m: Vec<f64>,
        /// Centre `X0` (m).
        center_m: f64,
        /// Width `σ` (m).
        width_m: f64,
    },
}

impl LineLoad {
    /// The load per length at arc coordinate `x` on a robot of length `total` (N/m).
    pub fn at(&self, x: f64, total: f64) -> Vec<f64> {
        match self {
            LineLoad::Uniform { w_n_per_m } => w_n_per_m.clone(),
            LineLoad::Linear {
                w_start_n_per_m: a,
                w_end_n_per_m: b,
            } => {
                let t = x / total;
                a.iter().zip(b).map(|(a, b)| a + t * (b - a)).collect()
            }
            LineLoad::Gaussian {
                amplitude_n_per_m,
                center_m,
                width_m,
            } => {
                let g = (-(x - center_m).powi(2) / (2.0 * width_m * width_m)).exp();
                amplitude_n_per_m.iter().map(|a| a * g).collect()
            }
        }
    }

    /// Checks dimensions and values; errors name the field `name.field`, or
    /// just `field` when `name` is empty.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] when a vector does not have `dim` entries,
    /// [`Error::InvalidParameter`] for a non-finite value or a non-positive width.
    pub fn validate(&self, name: &str, dim: usize) -> Result<()> {
        let path = |field: &str| {
            if name.is_empty() {
                field.to_string()
            } else {
                format!("{name}.{field}")
            }
        };
        let vec = |field: &str, v: &[f64]| -> Result<()> {
            let n = path(field);
            crate::error::check_len(&n, dim, v.len())?;
            check_all_finite(&n, v)
        };
        match self {
            LineLoad::Uniform { w_n_per_m } => vec("w_n_per_m", w_n_per_m),
            LineLoad::Linear {
                w_start_n_per_m,
                w_end_n_per_m,
            } => {
                vec("w_start_n_per_m", w_start_n_per_m)?;
                vec("w_end_n_per_m", w_end_n_per_m)
            }
            LineLoad::Gaussian {
                amplitude_n_per_m,
                center_m,
                width_m,
            } => {
                vec("amplitude_n_per_m", amplitude_n_per_m)?;
                check_finite(&path("center_m"), *center_m)?;
                check_positive(&path("width_m"), *width_m)
            }
        }
    }
}

/// A dead force at a point of the backbone.
///
/// # Example
/// ```
/// let tip = softrod::loads::PointForce { s_m: 0.24, force_n: vec![0.0, -0.1] };
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointForce {
    /// Undeformed arc coordinate of the point (m, 0 at the base).
    pub s_m: f64,
    /// Force in world axes (N).
    pub force_n: Vec<f64>,
}

/// A concentrated moment at a node; it does the work `M · θ` (θ the node's
/// rotation, `atan2(r'_y, r'_x)` in 2-D).
///
/// # Example
/// ```
/// let m = softrod::loads::NodeMoment { node: 20, moment_nm: vec![0.01] };
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NodeMoment {
    /// Node index (0 is the clamped base).
    pub node: usize,
    /// Moment (N·m; one component in 2-D).
    pub moment_nm: Vec<f64>,
}

/// Everything that loads the robot in one static solve besides its weight.
///
/// # Example
/// ```
/// use softrod::loads::{Loads, PointForce};
/// let loads = Loads { pressures_pa: vec![20e3, 0.0, 0.0, 0.0],
///     point_forces: vec![PointForce { s_m: 0.24, force_n: vec![0.0, -0.05] }], ..Loads::default() };
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Loads {
    /// Chamber pressures (Pa), one per chamber in section order.
    #[serde(default)]
    pub pressures_pa: Vec<f64>,
    /// Parameters `F` of the distributed load field `w(X) = S(X) F`
    /// (`n_q` numbers, node-major `[w_i, w_i']`, N/m and N/m²), or empty.
    #[serde(default)]
    pub distributed_f: Vec<f64>,
    /// Known line loads.
    #[serde(default)]
    pub line_loads: Vec<LineLoad>,
    /// Known point forces.
    #[serde(default)]
    pub point_forces: Vec<PointForce>,
    /// Known concentrated moments at nodes.
    #[serde(default)]
    pub node_moments: Vec<NodeMoment>,
}

impl Loads {
    /// Multiplies every load and pressure by `factor`.
    pub fn scaled(&self, factor: f64) -> Loads {
        let sc = |v: &[f64]| v.iter().map(|x| x * factor).collect::<Vec<_>>();
        Loads {
            pressures_pa: sc(&self.pressures_pa),
            distributed_f: sc(&self.distributed_f),
            line_loads: self
                .line_loads
                .iter()
                .map(|l| match l {
                    LineLoad::Uniform { w_n_per_m } => LineLoad::Uniform {
                        w_n_per_m: sc(w_n_per_m),
                    },
                    LineLoad::Linear {
                        w_start_n_per_m,
                        w_end_n_per_m,
                    } => LineLoad::Linear {
                        w_start_n_per_m: sc(w_start_n_per_m),
                        w_end_n_per_m: sc(w_end_n_per_m),
                    },
                    LineLoad::Gaussian {
                        amplitude_n_per_m,
                        center_m,
                        width_m,
                    } => LineLoad::Gaussian {
                        amplitude_n_per_m: sc(amplitude_n_per_m),
                        center_m: *center_m,
                        width_m: *width_m,
                    },
                })
                .collect(),
            point_forces: self
                .point_forces
                .iter()
                .map(|p| PointForce {
                    s_m: p.s_m,
                    force_n: sc(&p.force_n),
                })
                .collect(),
            node_moments: self
                .node_moments
                .iter()
                .map(|m| NodeMoment {
                    node: m.node,
                    moment_nm: sc(&m.moment_nm),
                })
                .collect(),
        }
    }
}

/// Error for a point outside the robot.
pub(crate) fn outside(name: &str, s: f64, total: f64) -> Error {
    Error::invalid(name, s, format!("must lie on the robot, in [0, {total}] m"))
}
