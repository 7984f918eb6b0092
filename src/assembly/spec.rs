//! What defines a robot: its sections, the pose of its clamped base,
//! gravity and the Gauss rules.

use nalgebra::SVector;
use serde::{Deserialize, Serialize};

use super::{Clamp, Robot, Section};
use crate::element::{DEFAULT_GAUSS_POINTS, PlanarCable, SpatialCable};
use crate::error::{Error, Result, check_all_finite, check_len};
use crate::structure::spec::{default_gauss, default_gravity};

/// Pose of the clamped base.
///
/// The base tangent is `direction` when given (any non-zero length, `DIM`
/// components; the way to point a spatial robot anywhere), else
/// `(cos α, sin α)` in the plane, `(cos α, sin α, 0)` in space, `α = angle_rad`.
///
/// # Example
/// ```
/// let b = softrod::assembly::Base::default();
/// assert_eq!(b.position_m, vec![0.0, 0.0]);
/// // a spatial robot hanging down along -z
/// let down: softrod::assembly::Base = serde_json::from_str(
///     r#"{"position_m": [0, 0, 0], "angle_rad": 0, "direction": [0, 0, -1]}"#).unwrap();
/// assert_eq!(down.direction, Some(vec![0.0, 0.0, -1.0]));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Base {
    /// Base position (m).
    pub position_m: Vec<f64>,
    /// Angle of the base tangent from the x axis (rad); not used when
    /// `direction` is given.
    pub angle_rad: f64,
    /// Direction of the base tangent (dimensionless, normalized on use);
    /// `None`: from `angle_rad`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub direction: Option<Vec<f64>>,
    /// What the clamp prescribes (default `position_and_direction`).
    #[serde(default)]
    pub clamp: Clamp,
}

impl Base {
    /// The base position as a point of dimension `D` (m).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `base.position_m` if it does not
    /// have `D` entries.
    ///
    /// # Example
    /// ```
    /// let b = softrod::assembly::Base::default();
    /// assert_eq!(b.position::<2>()?, nalgebra::Vector2::zeros());
    /// assert!(b.position::<3>().is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn position<const D: usize>(&self) -> Result<SVector<f64, D>> {
        crate::numeric::fixed("base.position_m", &self.position_m)
    }

    /// The unit base tangent in `D` dimensions: `direction` normalized, or
    /// `(cos, sin)` of `angle_rad` (with `z = 0` in 3-D) without one.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `base.direction` if it does not
    /// have `D` entries; [`Error::InvalidParameter`] if it is zero or not
    /// finite.
    ///
    /// # Example
    /// ```
    /// let mut b = softrod::assembly::Base::default();
    /// b.angle_rad = std::f64::consts::FRAC_PI_2;
    /// assert!((b.unit_direction::<2>()? - nalgebra::Vector2::y()).norm() < 1e-15);
    /// b.direction = Some(vec![0.0, 0.0, -2.0]);
    /// assert_eq!(b.unit_direction::<3>()?, -nalgebra::Vector3::z());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn unit_direction<const D: usize>(&self) -> Result<SVector<f64, D>> {
        crate::numeric::fixed("base.direction", &base_direction(self, D)?)
    }
}

impl Default for Base {
    fn default() -> Self {
        Base {
            position_m: vec![0.0, 0.0],
            angle_rad: 0.0,
            direction: None,
            clamp: Clamp::default(),
        }
    }
}

/// Everything that defines a robot.
///
/// # Example
/// ```
/// use softrod::assembly::{RobotSpec, Section};
/// let spec = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]);
/// let robot = spec.build_planar().unwrap();
/// assert_eq!(robot.n_nodes(), 9);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// Sections from base to tip.
    pub sections: Vec<Section>,
    /// Pose of the clamped base.
    #[serde(default)]
    pub base: Base,
    /// Gravity (m/s²).
    #[serde(default = "default_gravity")]
    pub gravity_m_per_s2: Vec<f64>,
    /// Gauss points of the axial-strain integral.
    #[serde(default = "default_gauss")]
    pub axial_gauss_points: usize,
    /// Gauss points of the bending integral (3 matches exudyn's ANCFCable2D).
    #[serde(default = "default_gauss")]
    pub bending_gauss_points: usize,
}

impl RobotSpec {
    /// A spec with default base, gravity `[0, -9.81]` and 5-point rules.
    pub fn new(sections: Vec<Section>) -> Self {
        RobotSpec {
            sections,
            base: Base::default(),
            gravity_m_per_s2: default_gravity(),
            axial_gauss_points: DEFAULT_GAUSS_POINTS,
            bending_gauss_points: DEFAULT_GAUSS_POINTS,
        }
    }

    /// Builds the planar robot.
    ///
    /// # Errors
    /// See [`Robot::new`].
    pub fn build_planar(&self) -> Result<Robot<PlanarCable>> {
        Robot::new(self.clone(), crate::structure::section::planar_element)
    }

    /// A spatial spec: base at the origin pointing along +x, gravity
    /// `[0, 0, -9.81]`, 5-point rules.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::spatial(vec![Section::uniform(0.24, 300.0, 0.025, 8)]).build_spatial()?;
    /// assert_eq!(robot.n_q(), 9 * 6);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn spatial(sections: Vec<Section>) -> Self {
        RobotSpec {
            sections,
            base: Base {
                position_m: vec![0.0; 3],
                direction: Some(vec![1.0, 0.0, 0.0]),
                ..Base::default()
            },
            gravity_m_per_s2: vec![0.0, 0.0, -9.81],
            axial_gauss_points: DEFAULT_GAUSS_POINTS,
            bending_gauss_points: DEFAULT_GAUSS_POINTS,
        }
    }

    /// Builds the spatial robot (3-D vectors: base position, gravity,
    /// chamber gains and moments in world axes).
    ///
    /// # Errors
    /// See [`Robot::new`]; [`Error::InvalidParameter`] naming
    /// `robot.sections[i].rest_curvature_per_m` for a non-zero rest curvature
    /// (the spatial cable has none: it has no section frame to bend in).
    pub fn build_spatial(&self) -> Result<Robot<SpatialCable>> {
        Robot::new(self.clone(), |s, le, ax, be| {
            if s.rest_curvature_profile.is_some() {
                return Err(Error::invalid(
                    "rest_curvature_profile",
                    "a profile",
                    "the spatial cable has no rest curvature: leave it out",
                ));
            }
            if s.rest_curvature_per_m != 0.0 {
                return Err(Error::invalid(
                    "rest_curvature_per_m",
                    s.rest_curvature_per_m,
                    "the spatial cable has no rest curvature: must be 0",
                ));
            }
            SpatialCable::with_rules(le, s.ea_n, s.ei_nm2, ax, be)
        })
    }

    /// Gravity as a vector of dimension `D` (m/s²).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `gravity_m_per_s2` if it does not
    /// have `D` entries.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let spec = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]);
    /// assert_eq!(spec.gravity::<2>()?, nalgebra::Vector2::new(0.0, -9.81));
    /// assert!(spec.gravity::<3>().is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn gravity<const D: usize>(&self) -> Result<SVector<f64, D>> {
        crate::numeric::fixed("gravity_m_per_s2", &self.gravity_m_per_s2)
    }

    /// Total number of elements (saturating).
    pub fn total_elements(&self) -> usize {
        self.sections
            .iter()
            .fold(0usize, |a, s| a.saturating_add(s.elements))
    }
}

/// The unit base tangent of `base` in `d` dimensions (see [`Base`]).
pub(crate) fn base_direction(base: &Base, d: usize) -> Result<Vec<f64>> {
    let Some(v) = &base.direction else {
        let (c, s) = (base.angle_rad.cos(), base.angle_rad.sin());
        return Ok(if d == 2 { vec![c, s] } else { vec![c, s, 0.0] });
    };
    check_len("base.direction", d, v.len())?;
    check_all_finite("base.direction", v)?;
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !(n > 0.0 && n.is_finite()) {
        return Err(Error::invalid(
            "base.direction",
            format!("{v:?}"),
            "must be a non-zero vector of finite length",
        ));
    }
    Ok(v.iter().map(|x| x / n).collect())
}
