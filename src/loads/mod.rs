//! Known loads: line loads given by a profile, point forces, concentrated
//! moments, the pressures of the actuation, and the unknown distributed load
//! field `w(X) = S(X) F` (8), (16).
//!
//! [`Load`] is one known load as a scene file states it (`tip_force`,
//! `tip_mass`, `self_weight`, `tip_moment`, `moment` at an arc position, a
//! `distributed` profile including a table, a `follower` pressure, …): a
//! scene's `loads` deserialize into it, and code adds the same values to
//! the [`Loads`] of a solve with [`Loads::add`] (or builds them from a
//! list with [`Loads::from_loads`]); both check a load as a scene does
//! ([`Load::validate`]). [`Loads`] holds them as the solver uses them (a tip load at the tip's arc position, a mass as its
//! weight). Rest curvature is a property of a section, not a load
//! ([`crate::assembly::Section`]).
//!
//! Every load here is dead (fixed in world axes) except the
//! [`FollowerLoad`], a pressure normal to the deformed backbone. Self-weight comes from
//! the sections' mass per length and the scene's gravity, not from here.
//! Forces that depend on the configuration (a spring holding a point, later
//! contact) are [`force_field::ForceField`]s: energy, force and stiffness at
//! `q`.

pub mod follower;
pub mod force_field;
mod load;
pub(crate) mod point_moment;

use nalgebra::{DVector, SVector};
use serde::{Deserialize, Serialize};

pub use follower::FollowerLoad;
pub use load::{Load, MomentNm};

use crate::error::{Error, Result, check_all_finite, check_finite, check_positive};

/// A known distributed load along the backbone (N/m, world axes), as a
/// function of the undeformed arc coordinate `X` (m).
///
/// # Example
/// ```
/// use softrod::loads::LineLoad;
/// let w = LineLoad::Linear { w_start_n_per_m: vec![0.0, 0.0], w_end_n_per_m: vec![0.0, -2.0] };
/// assert_eq!(w.at(0.5, 1.0), nalgebra::dvector![0.0, -1.0]);
/// // a table: -2 N/m at 0.1 m falling linearly to 0 at 0.2 m, nothing elsewhere
/// let t = LineLoad::Tabulated { s_m: vec![0.1, 0.2], w_n_per_m: vec![vec![0.0, -2.0], vec![0.0, 0.0]] };
/// assert!((t.at(0.15, 0.24)[1] + 1.0).abs() < 1e-15);
/// assert_eq!(t.at(0.05, 0.24), nalgebra::dvector![0.0, 0.0]);
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
    /// A table: load per length `w_n_per_m[k]` at arc coordinate `s_m[k]`,
    /// linear in `X` between neighbouring entries and zero outside
    /// `[s_m[0], s_m[last]]` (a table that covers the whole robot starts
    /// at 0 and ends at its length). At least two entries, `s_m` strictly
    /// increasing and on the robot. Its generalized forces are integrated
    /// exactly (each element is split at the table's arc positions).
    Tabulated {
        /// Arc coordinates of the entries (m, strictly increasing).
        s_m: Vec<f64>,
        /// Load per length at each entry (N/m, one vector per entry).
        w_n_per_m: Vec<Vec<f64>>,
    },
}

impl LineLoad {
    /// The load per length at arc coordinate `x` on a robot of length
    /// `total` (N/m, world axes, as many components as the profile's vectors).
    ///
    /// # Example
    /// See [`LineLoad`].
    pub fn at(&self, x: f64, total: f64) -> nalgebra::DVector<f64> {
        let mut w = nalgebra::DVector::zeros(self.dim());
        self.at_into(x, total, w.as_mut_slice());
        w
    }

    /// The number of components of the profile's vectors (a table without
    /// entries: 0).
    fn dim(&self) -> usize {
        match self {
            LineLoad::Uniform { w_n_per_m } => w_n_per_m.len(),
            LineLoad::Linear {
                w_start_n_per_m, ..
            } => w_start_n_per_m.len(),
            LineLoad::Gaussian {
                amplitude_n_per_m, ..
            } => amplitude_n_per_m.len(),
            LineLoad::Tabulated { w_n_per_m, .. } => w_n_per_m.first().map_or(0, Vec::len),
        }
    }

    /// [`LineLoad::at`] into `out` (its first components; the assembly's
    /// quadrature calls it at every point, without allocating).
    pub(crate) fn at_into(&self, x: f64, total: f64, out: &mut [f64]) {
        let lerp = |out: &mut [f64], a: &[f64], b: &[f64], t: f64| {
            for ((o, a), b) in out.iter_mut().zip(a).zip(b) {
                *o = a + t * (b - a);
            }
        };
        match self {
            LineLoad::Uniform { w_n_per_m } => {
                out.iter_mut().zip(w_n_per_m).for_each(|(o, w)| *o = *w);
            }
            LineLoad::Linear {
                w_start_n_per_m: a,
                w_end_n_per_m: b,
            } => lerp(out, a, b, x / total),
            LineLoad::Gaussian {
                amplitude_n_per_m,
                center_m,
                width_m,
            } => {
                let g = (-(x - center_m).powi(2) / (2.0 * width_m * width_m)).exp();
                out.iter_mut()
                    .zip(amplitude_n_per_m)
                    .for_each(|(o, a)| *o = a * g);
            }
            LineLoad::Tabulated { s_m, w_n_per_m } => {
                // the entry at or before x; none before the first or after the last
                let k = s_m.partition_point(|&s| s <= x);
                let (Some(k), Some(&last)) = (k.checked_sub(1), s_m.last()) else {
                    out.fill(0.0);
                    return;
                };
                let Some(a) = w_n_per_m.get(k).filter(|_| x <= last) else {
                    out.fill(0.0);
                    return;
                };
                match (s_m.get(k + 1), w_n_per_m.get(k + 1)) {
                    (Some(s1), Some(b)) => lerp(out, a, b, (x - s_m[k]) / (s1 - s_m[k])),
                    _ => out.iter_mut().zip(a).for_each(|(o, w)| *o = *w),
                }
            }
        }
    }

    /// The arc coordinates where the load's profile has a kink or a jump
    /// (m): a table's entries; none for the smooth profiles.
    pub fn breakpoints(&self) -> &[f64] {
        match self {
            LineLoad::Tabulated { s_m, .. } => s_m,
            _ => &[],
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
            LineLoad::Tabulated { s_m, w_n_per_m } => {
                if s_m.len() < 2 {
                    return Err(Error::invalid(
                        path("s_m"),
                        format!("{s_m:?}"),
                        "a table needs at least two entries",
                    ));
                }
                crate::error::check_len(&path("w_n_per_m"), s_m.len(), w_n_per_m.len())?;
                for (k, s) in s_m.iter().enumerate() {
                    let n = path(&format!("s_m[{k}]"));
                    check_finite(&n, *s)?;
                    if k > 0 && *s <= s_m[k - 1] {
                        return Err(Error::invalid(
                            n,
                            s,
                            format!("must be greater than the entry before, {} m", s_m[k - 1]),
                        ));
                    }
                }
                for (k, w) in w_n_per_m.iter().enumerate() {
                    vec(&format!("w_n_per_m[{k}]"), w)?;
                }
                Ok(())
            }
        }
    }

    /// Checks that a table's arc positions lie on a robot of length
    /// `total` (m); errors name `name.s_m[k]` (or `s_m[k]`). Other profiles
    /// pass.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for an arc position off `[0, total]`
    /// (beyond a relative `1e-12`).
    ///
    /// # Example
    /// ```
    /// use softrod::loads::LineLoad;
    /// let t = LineLoad::Tabulated { s_m: vec![0.0, 0.3], w_n_per_m: vec![vec![0.0, 1.0]; 2] };
    /// assert_eq!(t.check_on_robot("line_loads[0]", 0.24).unwrap_err().field(), Some("line_loads[0].s_m[1]"));
    /// ```
    pub fn check_on_robot(&self, name: &str, total: f64) -> Result<()> {
        let tol = 1e-12 * total;
        for (k, s) in self.breakpoints().iter().enumerate() {
            if !(*s >= -tol && *s <= total + tol) {
                let field = if name.is_empty() {
                    format!("s_m[{k}]")
                } else {
                    format!("{name}.s_m[{k}]")
                };
                return Err(outside(&field, *s, total));
            }
        }
        Ok(())
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

impl PointForce {
    /// A force `force_n` (N, world axes; two components on a planar robot,
    /// three on a spatial one) at the arc coordinate `s_m` (m).
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::loads::PointForce;
    /// let tip = PointForce::new(0.24, Vector2::new(0.0, -0.1));
    /// assert_eq!(tip, PointForce { s_m: 0.24, force_n: vec![0.0, -0.1] });
    /// assert_eq!(tip.force::<2>()?, Vector2::new(0.0, -0.1));
    /// assert!(tip.force::<3>().is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn new<const D: usize>(s_m: f64, force_n: SVector<f64, D>) -> Self {
        PointForce {
            s_m,
            force_n: force_n.as_slice().to_vec(),
        }
    }

    /// The force as a `D`-vector (N, world axes).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `force_n` if it has another number
    /// of components.
    ///
    /// # Example
    /// See [`PointForce::new`].
    pub fn force<const D: usize>(&self) -> Result<SVector<f64, D>> {
        crate::numeric::fixed("force_n", &self.force_n)
    }
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

impl NodeMoment {
    /// A moment `moment_nm` (N·m; one component on a planar robot, three in
    /// world axes on a spatial one) at node `node`.
    ///
    /// # Example
    /// ```
    /// use nalgebra::{Vector1, Vector3};
    /// use softrod::loads::NodeMoment;
    /// let m = NodeMoment::new(20, Vector1::new(0.01));
    /// assert_eq!(m, NodeMoment { node: 20, moment_nm: vec![0.01] });
    /// assert_eq!(m.moment::<1>()?.x, 0.01);
    /// assert!(NodeMoment::new(3, Vector3::z()).moment::<1>().is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn new<const D: usize>(node: usize, moment_nm: SVector<f64, D>) -> Self {
        NodeMoment {
            node,
            moment_nm: moment_nm.as_slice().to_vec(),
        }
    }

    /// The moment as a `D`-vector (N·m; `D = 1` planar, 3 spatial).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `moment_nm` if it has another
    /// number of components.
    ///
    /// # Example
    /// See [`NodeMoment::new`].
    pub fn moment<const D: usize>(&self) -> Result<SVector<f64, D>> {
        crate::numeric::fixed("moment_nm", &self.moment_nm)
    }
}

/// A dead concentrated moment at an arc position of the backbone.
///
/// It does the work `W = M · θ(s)`, `θ(s)` the rotation of the backbone's
/// tangent at `s` from the clamp's direction (in 2-D the angle of `r'(s)`,
/// in 3-D the rotation vector of the smallest rotation; a cable has no
/// torsion, so a component along the reference tangent does no work). At a
/// node this is the same load as a [`NodeMoment`] there; between nodes the
/// tangent `r'(s)` is interpolated by the cubic Hermite functions, so the
/// moment acts on the element's two nodes. On a clamped robot it must lie
/// beyond the base (`s_m > 0`). Accuracy: the bending moment jumps at `s`;
/// with a node there the equilibrium converges as fast as for a moment at
/// a node (fourth order in the element length), inside an element at first
/// order (the cubic cannot follow the jump of curvature inside it).
///
/// # Example
/// ```
/// use softrod::loads::{Loads, PointMoment};
/// let loads = Loads { point_moments: vec![PointMoment { s_m: 0.1, moment_nm: vec![0.01] }],
///     ..Loads::default() };
/// assert_eq!(loads.scaled(2.0).point_moments[0].moment_nm, vec![0.02]);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PointMoment {
    /// Undeformed arc coordinate of the point (m, 0 at the base).
    pub s_m: f64,
    /// Moment (N·m; one component in 2-D, counter-clockwise positive; three
    /// in world axes in 3-D).
    pub moment_nm: Vec<f64>,
}

impl PointMoment {
    /// A moment `moment_nm` (N·m; one component on a planar robot, three in
    /// world axes on a spatial one) at the arc coordinate `s_m` (m).
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector3;
    /// use softrod::loads::PointMoment;
    /// let m = PointMoment::new(0.1, Vector3::new(0.0, 0.0, 0.01));
    /// assert_eq!(m.moment_nm, vec![0.0, 0.0, 0.01]);
    /// assert_eq!(m.moment::<3>()?, Vector3::new(0.0, 0.0, 0.01));
    /// assert!(m.moment::<1>().is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn new<const D: usize>(s_m: f64, moment_nm: SVector<f64, D>) -> Self {
        PointMoment {
            s_m,
            moment_nm: moment_nm.as_slice().to_vec(),
        }
    }

    /// The moment as a `D`-vector (N·m; `D = 1` planar, 3 spatial).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `moment_nm` if it has another
    /// number of components.
    ///
    /// # Example
    /// See [`PointMoment::new`].
    pub fn moment<const D: usize>(&self) -> Result<SVector<f64, D>> {
        crate::numeric::fixed("moment_nm", &self.moment_nm)
    }
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
    /// Known concentrated moments at arc positions.
    #[serde(default)]
    pub point_moments: Vec<PointMoment>,
    /// Pressures normal to the deformed backbone (planar robots; not dead:
    /// they turn with the rod).
    #[serde(default)]
    pub follower_loads: Vec<FollowerLoad>,
}

impl Loads {
    /// [`Loads::pressures_pa`] as a vector (Pa).
    ///
    /// # Example
    /// ```
    /// let loads = softrod::loads::Loads { pressures_pa: vec![20e3, 0.0], ..Default::default() };
    /// assert_eq!(loads.pressures(), nalgebra::dvector![20e3, 0.0]);
    /// assert_eq!(loads.distributed().len(), 0); // no distributed field
    /// ```
    pub fn pressures(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.pressures_pa)
    }

    /// [`Loads::distributed_f`] as a vector (`n_q` parameters of the
    /// distributed load field, or empty).
    ///
    /// # Example
    /// See [`Loads::pressures`].
    pub fn distributed(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.distributed_f)
    }

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
                    LineLoad::Tabulated { s_m, w_n_per_m } => LineLoad::Tabulated {
                        s_m: s_m.clone(),
                        w_n_per_m: w_n_per_m.iter().map(|w| sc(w)).collect(),
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
            point_moments: self
                .point_moments
                .iter()
                .map(|m| PointMoment {
                    s_m: m.s_m,
                    moment_nm: sc(&m.moment_nm),
                })
                .collect(),
            follower_loads: self
                .follower_loads
                .iter()
                .map(|f| FollowerLoad {
                    pressure_n_per_m: f.pressure_n_per_m * factor,
                    ..f.clone()
                })
                .collect(),
        }
    }
}

/// Error for a point outside the robot.
pub(crate) fn outside(name: &str, s: f64, total: f64) -> Error {
    Error::invalid(name, s, format!("must lie on the robot, in [0, {total}] m"))
}
