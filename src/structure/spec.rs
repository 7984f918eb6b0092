//! What a structure is made of, as written in a scene: rods with their end
//! supports, rigid bodies, joints, and the loads on the bodies.
//!
//! The checks here run before anything that grows with an element count is
//! allocated; every error names its field (`structure.joints[1].body`).

use nalgebra::{SVector, Vector3};
use serde::{Deserialize, Serialize};

use super::rigid::{Attachment, PlanarAttachment, resolve_spatial, rotate, rotate_back};
use super::rod::{MAX_ELEMENTS, Rod};
use super::section::Section;
use crate::element::{DEFAULT_GAUSS_POINTS, Element};
use crate::error::{Error, Result, check_all_finite, check_at_most, check_index, check_len};
use crate::loads::Loads;

/// What the base clamp prescribes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Clamp {
    /// Position and direction of the base; the axial strain at the base is
    /// free (the physical clamp; default).
    #[default]
    PositionAndDirection,
    /// Position and the whole slope vector `r_0' = t_0` (the literal reading
    /// of a clamp `r_0' = t_0`, and exudyn's cantilevers that fix all four base coordinates):
    /// forbids axial strain at the base, a boundary layer one element long.
    Full,
}

/// How one end of a rod is held, besides joints: free or clamped to the
/// ground where the rod's straight reference puts it.
///
/// # Example
/// ```
/// use softrod::structure::{Clamp, EndSupport};
/// let s: EndSupport = serde_json::from_str(r#"{"kind": "clamped"}"#).unwrap();
/// assert_eq!(s, EndSupport::Clamped { clamp: Clamp::PositionAndDirection });
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum EndSupport {
    /// Free (or held by a joint).
    #[default]
    Free,
    /// Clamped to the ground.
    Clamped {
        /// What the clamp prescribes.
        #[serde(default)]
        clamp: Clamp,
    },
}

/// One rod: its sections from start to end, its straight reference (start
/// point and direction) and its end supports.
///
/// # Example
/// ```
/// use softrod::assembly::Section;
/// use softrod::structure::{EndSupport, RodSpec};
/// let leg = RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.05, 0.0), nalgebra::Vector2::new(0.0, 1.0));
/// assert!(matches!(leg.start, EndSupport::Clamped { .. }));
/// assert_eq!(leg.end, EndSupport::Free);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RodSpec {
    /// Sections from the start to the end.
    pub sections: Vec<Section>,
    /// Start point of the straight reference (m).
    pub start_m: Vec<f64>,
    /// Direction of the straight reference (any non-zero length; normalized).
    pub direction: Vec<f64>,
    /// Support of the start (node 0).
    #[serde(default)]
    pub start: EndSupport,
    /// Support of the end (last node).
    #[serde(default)]
    pub end: EndSupport,
}

impl RodSpec {
    /// A rod clamped at its start (`start_m` in m, `direction`: `Vector2`s for
    /// a planar rod, `Vector3`s for a spatial one), free at its end ([`RodSpec`]).
    pub fn clamped<const D: usize>(
        sections: Vec<Section>,
        start_m: SVector<f64, D>,
        direction: SVector<f64, D>,
    ) -> Self {
        RodSpec {
            sections,
            start_m: start_m.as_slice().to_vec(),
            direction: direction.as_slice().to_vec(),
            start: EndSupport::Clamped {
                clamp: Clamp::PositionAndDirection,
            },
            end: EndSupport::Free,
        }
    }

    /// Total undeformed length (m).
    pub fn length(&self) -> f64 {
        self.sections.iter().map(|s| s.length_m).sum()
    }

    /// The start point of the straight reference as a point of dimension
    /// `D` (m).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `start_m` if it does not have `D`
    /// entries.
    ///
    /// # Example
    /// ```
    /// use softrod::{assembly::Section, structure::RodSpec};
    /// let leg = RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.05, 0.0), nalgebra::Vector2::new(0.0, 2.0));
    /// assert_eq!(leg.start_point::<2>()?, nalgebra::Vector2::new(0.05, 0.0));
    /// assert_eq!(leg.unit_direction::<2>()?, nalgebra::Vector2::y());
    /// assert!(leg.start_point::<3>().is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn start_point<const D: usize>(&self) -> Result<SVector<f64, D>> {
        crate::numeric::fixed("start_m", &self.start_m)
    }

    /// The unit direction of the straight reference in `D` dimensions.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `direction` if it does not have
    /// `D` entries; [`Error::InvalidParameter`] if it is zero or not finite.
    ///
    /// # Example
    /// See [`RodSpec::start_point`].
    pub fn unit_direction<const D: usize>(&self) -> Result<SVector<f64, D>> {
        let d: SVector<f64, D> = crate::numeric::fixed("direction", &self.direction)?;
        let n = d.norm();
        if !(n > 0.0 && n.is_finite()) {
            return Err(Error::invalid(
                "direction",
                format!("{:?}", self.direction),
                "must be a non-zero vector of finite length",
            ));
        }
        Ok(d / n)
    }
}

/// A rigid body: its mass and its pose in the reference configuration. The
/// position is the body's reference point and centre of mass.
///
/// # Example
/// ```
/// let platform = softrod::structure::RigidBodySpec { mass_kg: 0.05, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] };
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigidBodySpec {
    /// Mass (kg); zero is a massless connector (it must then be joined).
    pub mass_kg: f64,
    /// Position of the reference point (centre of mass) (m).
    pub position_m: Vec<f64>,
    /// Orientation (rad): the angle from the world axes in 2-D (one
    /// number); a rotation vector in 3-D (three).
    pub orientation_rad: Vec<f64>,
}

impl RigidBodySpec {
    /// The reference point as a point of dimension `D` (m).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `position_m` if it does not have
    /// `D` entries.
    ///
    /// # Example
    /// ```
    /// let platform = softrod::structure::RigidBodySpec { mass_kg: 0.05, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] };
    /// assert_eq!(platform.position::<2>()?, nalgebra::Vector2::new(0.0, 0.2));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn position<const D: usize>(&self) -> Result<SVector<f64, D>> {
        crate::numeric::fixed("position_m", &self.position_m)
    }

    /// The orientation of a spatial body as a rotation vector (rad).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `orientation_rad` if it does not
    /// have three entries (a planar body has one angle: read the field).
    ///
    /// # Example
    /// ```
    /// let b = softrod::structure::RigidBodySpec { mass_kg: 0.05, position_m: vec![0.0; 3], orientation_rad: vec![0.0, 0.0, 0.1] };
    /// assert!((b.rotation_vector()?.z - 0.1).abs() < 1e-15);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn rotation_vector(&self) -> Result<Vector3<f64>> {
        crate::numeric::fixed("orientation_rad", &self.orientation_rad)
    }
}

/// Which end of a rod.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RodEnd {
    /// Node 0.
    Start,
    /// The last node.
    End,
}

/// A joint.
///
/// # Example
/// ```
/// use softrod::structure::{JointSpec, RodEnd};
/// let j: JointSpec = serde_json::from_str(
///     r#"{"kind": "rod_to_body", "rod": 1, "end": "end", "body": 0}"#).unwrap();
/// assert!(matches!(j, JointSpec::RodToBody { rod: 1, end: RodEnd::End, body: 0, .. }));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum JointSpec {
    /// A rod end rigidly fixed to a rigid body: the end's position and
    /// tangent direction follow the body (its stretch stays free).
    RodToBody {
        /// The rod.
        rod: usize,
        /// Which end.
        end: RodEnd,
        /// The rigid body.
        body: usize,
        /// The joint's point in the body frame (m); by default where the
        /// rod's straight reference puts the end. If given, it must agree
        /// with the reference (to 1e-6 of the rod's length).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        point_m: Option<Vec<f64>>,
        /// The rod's tangent at the joint in the body frame; by default the
        /// reference's. If given, it must agree with the reference (1e-6).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        direction: Option<Vec<f64>>,
    },
    /// A rigid body fixed to the ground in its reference pose.
    BodyToGround {
        /// The rigid body.
        body: usize,
    },
}

/// A dead load on a rigid body at its reference point (world axes).
///
/// # Example
/// ```
/// let push = softrod::structure::BodyLoad { body: 0, force_n: vec![1e-3, 0.0], moment_nm: vec![] };
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodyLoad {
    /// The rigid body.
    pub body: usize,
    /// Force (N); empty for none.
    #[serde(default)]
    pub force_n: Vec<f64>,
    /// Moment (N·m; one number in 2-D); empty for none.
    #[serde(default)]
    pub moment_nm: Vec<f64>,
}

impl BodyLoad {
    /// The force as a vector of dimension `D` (N; zero if none is given).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `force_n` if it has neither 0 nor
    /// `D` entries.
    ///
    /// # Example
    /// ```
    /// let push = softrod::structure::BodyLoad { body: 0, force_n: vec![1e-3, 0.0], moment_nm: vec![] };
    /// assert_eq!(push.force::<2>()?, nalgebra::Vector2::new(1e-3, 0.0));
    /// assert_eq!(push.moment::<1>()?[0], 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn force<const D: usize>(&self) -> Result<SVector<f64, D>> {
        if self.force_n.is_empty() {
            return Ok(SVector::zeros());
        }
        crate::numeric::fixed("force_n", &self.force_n)
    }

    /// The moment with `M` components (N·m; 1 in 2-D, 3 in 3-D; zero if
    /// none is given).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `moment_nm` if it has neither 0
    /// nor `M` entries.
    ///
    /// # Example
    /// See [`BodyLoad::force`].
    pub fn moment<const M: usize>(&self) -> Result<SVector<f64, M>> {
        if self.moment_nm.is_empty() {
            return Ok(SVector::zeros());
        }
        crate::numeric::fixed("moment_nm", &self.moment_nm)
    }
}

/// Everything that loads a structure in one static solve besides weight.
///
/// # Example
/// ```
/// use softrod::structure::{BodyLoad, StructureLoads};
/// let loads = StructureLoads { bodies: vec![BodyLoad { body: 0, force_n: vec![0.0, -0.1], moment_nm: vec![] }], ..Default::default() };
/// assert_eq!(loads.scaled(0.5).bodies[0].force_n[1], -0.05);
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StructureLoads {
    /// The loads of every rod, in rod order; empty for none on any rod.
    #[serde(default)]
    pub rods: Vec<Loads>,
    /// Loads on rigid bodies.
    #[serde(default)]
    pub bodies: Vec<BodyLoad>,
}

impl StructureLoads {
    /// Multiplies every load and pressure by `factor` (weights stay).
    pub fn scaled(&self, factor: f64) -> StructureLoads {
        let sc = |v: &[f64]| v.iter().map(|x| x * factor).collect::<Vec<_>>();
        StructureLoads {
            rods: self.rods.iter().map(|l| l.scaled(factor)).collect(),
            bodies: self
                .bodies
                .iter()
                .map(|b| BodyLoad {
                    body: b.body,
                    force_n: sc(&b.force_n),
                    moment_nm: sc(&b.moment_nm),
                })
                .collect(),
        }
    }
}

/// A structure: rods, rigid bodies and joints, under gravity.
///
/// # Example
/// ```
/// use softrod::assembly::Section;
/// use softrod::structure::{JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureSpec};
/// // two legs clamped at x = ±0.05 m, their tips joined to a platform
/// let leg = |x: f64| RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(x, 0.0), nalgebra::Vector2::new(0.0, 1.0));
/// let joint = |rod| JointSpec::RodToBody { rod, end: RodEnd::End, body: 0, point_m: None, direction: None };
/// let spec = StructureSpec::new(
///     vec![leg(-0.05), leg(0.05)],
///     vec![RigidBodySpec { mass_kg: 0.01, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
///     vec![joint(0), joint(1)],
/// );
/// let s = spec.build_planar().unwrap();
/// assert_eq!(s.n_q(), 2 * 5 * 4 + 3);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StructureSpec {
    /// The rods.
    pub rods: Vec<RodSpec>,
    /// The rigid bodies.
    #[serde(default)]
    pub rigid_bodies: Vec<RigidBodySpec>,
    /// The joints.
    #[serde(default)]
    pub joints: Vec<JointSpec>,
    /// Gravity (m/s²).
    #[serde(default = "default_gravity")]
    pub gravity_m_per_s2: Vec<f64>,
    /// Gauss points of the axial-strain integral.
    #[serde(default = "default_gauss")]
    pub axial_gauss_points: usize,
    /// Gauss points of the bending integral.
    #[serde(default = "default_gauss")]
    pub bending_gauss_points: usize,
}

/// Gravity a spec gets when it states none (m/s²; shared by the robot's spec).
pub(crate) fn default_gravity() -> Vec<f64> {
    vec![0.0, -9.81]
}
/// Gauss points of either integral when a spec states none.
pub(crate) fn default_gauss() -> usize {
    DEFAULT_GAUSS_POINTS
}

/// A joint of a rod end to a rigid body, checked and resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ResolvedJoint {
    /// Index in `joints`.
    pub(crate) joint: usize,
    pub(crate) rod: usize,
    pub(crate) end: RodEnd,
    pub(crate) body: usize,
    pub(crate) attachment: Attachment,
}

/// The outcome of [`StructureSpec::check`]: what the builder needs.
#[derive(Debug, Clone)]
pub(crate) struct Checked {
    /// Unit reference direction of every rod.
    pub(crate) directions: Vec<Vec<f64>>,
    /// The rod-to-body joints.
    pub(crate) joints: Vec<ResolvedJoint>,
    /// Whether each body is fixed to the ground.
    pub(crate) grounded: Vec<bool>,
}

/// Relative tolerance of a given joint point or direction against the
/// rods' straight reference.
const JOINT_TOLERANCE: f64 = 1e-6;

impl StructureSpec {
    /// A spec with gravity `[0, -9.81]` and 5-point rules.
    pub fn new(
        rods: Vec<RodSpec>,
        rigid_bodies: Vec<RigidBodySpec>,
        joints: Vec<JointSpec>,
    ) -> Self {
        StructureSpec {
            rods,
            rigid_bodies,
            joints,
            gravity_m_per_s2: default_gravity(),
            axial_gauss_points: DEFAULT_GAUSS_POINTS,
            bending_gauss_points: DEFAULT_GAUSS_POINTS,
        }
    }

    /// Gravity as a vector of dimension `D` (m/s²).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `gravity_m_per_s2` if it does not
    /// have `D` entries.
    ///
    /// # Example
    /// ```
    /// let spec = softrod::structure::StructureSpec::new(vec![], vec![], vec![]);
    /// assert_eq!(spec.gravity::<2>()?, nalgebra::Vector2::new(0.0, -9.81));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn gravity<const D: usize>(&self) -> Result<SVector<f64, D>> {
        crate::numeric::fixed("gravity_m_per_s2", &self.gravity_m_per_s2)
    }

    /// Builds the planar structure.
    ///
    /// # Errors
    /// See [`super::Structure::new`].
    pub fn build_planar(&self) -> Result<super::Structure<crate::element::PlanarCable>> {
        super::Structure::new(self.clone(), super::section::planar_element)
    }

    /// Every check of a structure for elements of type `E`, in this order:
    /// gravity and Gauss rules, the element count, each rod's sections and
    /// reference, the rigid bodies, the joints (indices, an end joined
    /// twice or both clamped and joined, a body fixed twice, points and
    /// directions against the reference), a rigid body with no mass and no
    /// joint, and a part of the structure that floats (no clamp and no body
    /// fixed to the ground). Allocates only in proportion to the numbers of
    /// rods, bodies and joints.
    pub(crate) fn check<E: Element>(&self) -> Result<Checked> {
        let d = E::DIM;
        if self.rods.is_empty() {
            return Err(Error::invalid(
                "structure.rods",
                "[]",
                "a structure needs at least one rod",
            ));
        }
        check_len("structure.gravity_m_per_s2", d, self.gravity_m_per_s2.len())?;
        check_all_finite("structure.gravity_m_per_s2", &self.gravity_m_per_s2)?;
        for (name, n) in [
            ("structure.axial_gauss_points", self.axial_gauss_points),
            ("structure.bending_gauss_points", self.bending_gauss_points),
        ] {
            if n == 0 {
                return Err(Error::invalid(name, n, "must be >= 1"));
            }
            check_at_most(name, n, crate::quadrature::MAX_POINTS)?;
        }
        // the element count of all rods together, before anything else
        let mut total = 0usize;
        for (i, r) in self.rods.iter().enumerate() {
            for (k, s) in r.sections.iter().enumerate() {
                check_at_most(
                    &format!("structure.rods[{i}].sections[{k}].elements"),
                    s.elements,
                    MAX_ELEMENTS - total,
                )?;
                total += s.elements;
            }
        }
        let mut directions = Vec::with_capacity(self.rods.len());
        for (i, r) in self.rods.iter().enumerate() {
            let path = format!("structure.rods[{i}]");
            Rod::<E>::check_sections(
                &r.sections,
                &self.gravity_m_per_s2,
                self.axial_gauss_points,
                self.bending_gauss_points,
                &path,
            )?;
            check_len(&format!("{path}.start_m"), d, r.start_m.len())?;
            check_all_finite(&format!("{path}.start_m"), &r.start_m)?;
            directions.push(unit(&format!("{path}.direction"), &r.direction, d)?);
        }
        let planar_cable = d == 2 && E::NODE_DOFS == 4;
        let spatial = d == 3 && (E::NODE_DOFS == 6 || E::NODE_DOFS == 12);
        if !self.rigid_bodies.is_empty() && !planar_cable && !spatial {
            return Err(Error::invalid(
                "structure.rigid_bodies",
                format!("{} bodies", self.rigid_bodies.len()),
                "rigid bodies are implemented for the planar cable, the spatial cable and the full 3-D element",
            ));
        }
        // the pose's rotation: an angle in 2-D, a rotation vector in 3-D
        let n_rot = if d == 2 { 1 } else { 3 };
        for (b, body) in self.rigid_bodies.iter().enumerate() {
            let p = |f: &str| format!("structure.rigid_bodies[{b}].{f}");
            if !(body.mass_kg.is_finite() && body.mass_kg >= 0.0) {
                return Err(Error::invalid(
                    p("mass_kg"),
                    body.mass_kg,
                    "must be finite and >= 0",
                ));
            }
            check_len(&p("position_m"), d, body.position_m.len())?;
            check_all_finite(&p("position_m"), &body.position_m)?;
            check_len(&p("orientation_rad"), n_rot, body.orientation_rad.len())?;
            check_all_finite(&p("orientation_rad"), &body.orientation_rad)?;
        }
        let (joints, grounded, joined_bodies) = self.check_joints(&directions, E::NODE_DOFS)?;
        for (b, body) in self.rigid_bodies.iter().enumerate() {
            if body.mass_kg == 0.0 && !joined_bodies[b] {
                return Err(Error::invalid(
                    format!("structure.rigid_bodies[{b}].mass_kg"),
                    0,
                    "a rigid body with no mass and no joint is undetermined: give it a mass or join it",
                ));
            }
        }
        self.check_grounded(&joints, &grounded)?;
        Ok(Checked {
            directions,
            joints,
            grounded,
        })
    }

    /// The joints: indices, ends joined twice, bodies fixed twice, points
    /// and directions. Returns the rod-to-body joints, which bodies are
    /// fixed to the ground and which bodies some joint names.
    #[allow(clippy::type_complexity)]
    fn check_joints(
        &self,
        directions: &[Vec<f64>],
        node_dofs: usize,
    ) -> Result<(Vec<ResolvedJoint>, Vec<bool>, Vec<bool>)> {
        let (n_rods, n_bodies) = (self.rods.len(), self.rigid_bodies.len());
        // which joint holds each rod end (2 per rod), which fixes each body
        let mut end_joint: Vec<Option<usize>> = vec![None; 2 * n_rods];
        let mut ground_joint: Vec<Option<usize>> = vec![None; n_bodies];
        let mut joined = vec![false; n_bodies];
        let mut resolved = Vec::new();
        for (j, joint) in self.joints.iter().enumerate() {
            let p = |f: &str| format!("structure.joints[{j}].{f}");
            match joint {
                JointSpec::BodyToGround { body } => {
                    check_index(&p("body"), *body, n_bodies)?;
                    if let Some(first) = ground_joint[*body] {
                        return Err(Error::invalid(
                            p("body"),
                            body,
                            format!(
                                "rigid body {body} is already fixed to the ground by joints[{first}]"
                            ),
                        ));
                    }
                    ground_joint[*body] = Some(j);
                    joined[*body] = true;
                }
                JointSpec::RodToBody {
                    rod,
                    end,
                    body,
                    point_m,
                    direction,
                } => {
                    check_index(&p("rod"), *rod, n_rods)?;
                    check_index(&p("body"), *body, n_bodies)?;
                    let slot = 2 * rod + usize::from(*end == RodEnd::End);
                    if let Some(first) = end_joint[slot] {
                        return Err(Error::invalid(
                            p("end"),
                            format!("{end:?}"),
                            format!("this end of rod {rod} is already joined by joints[{first}]"),
                        ));
                    }
                    let r = &self.rods[*rod];
                    let support = match end {
                        RodEnd::Start => r.start,
                        RodEnd::End => r.end,
                    };
                    if support != EndSupport::Free {
                        return Err(Error::invalid(
                            p("end"),
                            format!("{end:?}"),
                            format!(
                                "this end of rod {rod} is clamped: an end is clamped or joined, not both"
                            ),
                        ));
                    }
                    end_joint[slot] = Some(j);
                    joined[*body] = true;
                    let attachment = if node_dofs == 4 {
                        Attachment::Planar(self.attachment(
                            j,
                            *rod,
                            *end,
                            *body,
                            &directions[*rod],
                            point_m,
                            direction,
                        )?)
                    } else {
                        let (r, b, dir) = (
                            &self.rods[*rod],
                            &self.rigid_bodies[*body],
                            &directions[*rod],
                        );
                        let s = if *end == RodEnd::Start {
                            0.0
                        } else {
                            r.length()
                        };
                        let v3 = |v: &[f64]| [v[0], v[1], v[2]];
                        let end_m: [f64; 3] = std::array::from_fn(|i| r.start_m[i] + s * dir[i]);
                        Attachment::Spatial(resolve_spatial(
                            &p(""),
                            end_m,
                            v3(dir),
                            v3(&b.position_m),
                            v3(&b.orientation_rad),
                            point_m,
                            direction,
                            r.length(),
                            JOINT_TOLERANCE,
                            node_dofs,
                        )?)
                    };
                    resolved.push(ResolvedJoint {
                        joint: j,
                        rod: *rod,
                        end: *end,
                        body: *body,
                        attachment,
                    });
                }
            }
        }
        let grounded = ground_joint.iter().map(Option::is_some).collect();
        Ok((resolved, grounded, joined))
    }

    /// The body-frame point and direction of a rod-to-body joint: given
    /// ones are checked against the rods' straight reference, missing ones
    /// are taken from it.
    #[allow(clippy::too_many_arguments)]
    fn attachment(
        &self,
        j: usize,
        rod: usize,
        end: RodEnd,
        body: usize,
        dir: &[f64],
        point_m: &Option<Vec<f64>>,
        direction: &Option<Vec<f64>>,
    ) -> Result<PlanarAttachment> {
        let p = |f: &str| format!("structure.joints[{j}].{f}");
        let r = &self.rods[rod];
        let b = &self.rigid_bodies[body];
        let s = match end {
            RodEnd::Start => 0.0,
            RodEnd::End => r.length(),
        };
        let end_pos = [r.start_m[0] + s * dir[0], r.start_m[1] + s * dir[1]];
        let th = b.orientation_rad[0];
        let x = [b.position_m[0], b.position_m[1]];
        let reference_point = rotate_back(th, [end_pos[0] - x[0], end_pos[1] - x[1]]);
        let reference_dir = rotate_back(th, [dir[0], dir[1]]);
        let point = match point_m {
            None => reference_point,
            Some(v) => {
                check_len(&p("point_m"), 2, v.len())?;
                check_all_finite(&p("point_m"), v)?;
                let w = rotate(th, [v[0], v[1]]);
                let gap = ((x[0] + w[0] - end_pos[0]).powi(2) + (x[1] + w[1] - end_pos[1]).powi(2))
                    .sqrt();
                if gap.is_nan() || gap > JOINT_TOLERANCE * r.length() {
                    return Err(Error::invalid(
                        p("point_m"),
                        format!("{v:?}"),
                        format!(
                            "puts the joint {gap:.3e} m from the end of rod {rod} in the reference \
                             (its end is at {reference_point:?} in the body frame)"
                        ),
                    ));
                }
                [v[0], v[1]]
            }
        };
        let direction = match direction {
            None => reference_dir,
            Some(v) => {
                let u = unit(&p("direction"), v, 2)?;
                let off =
                    ((u[0] - reference_dir[0]).powi(2) + (u[1] - reference_dir[1]).powi(2)).sqrt();
                if off.is_nan() || off > JOINT_TOLERANCE {
                    return Err(Error::invalid(
                        p("direction"),
                        format!("{v:?}"),
                        format!(
                            "differs from rod {rod}'s direction {reference_dir:?} (body frame) in the reference"
                        ),
                    ));
                }
                [u[0], u[1]]
            }
        };
        Ok(PlanarAttachment {
            point_m: point.into(),
            direction: direction.into(),
        })
    }

    /// Every connected part of the structure (rods and bodies linked by
    /// joints) must reach the ground: a clamp or a body fixed to it.
    fn check_grounded(&self, joints: &[ResolvedJoint], grounded: &[bool]) -> Result<()> {
        let n_rods = self.rods.len();
        let n = n_rods + self.rigid_bodies.len();
        let mut parent: Vec<usize> = (0..n).collect();
        fn root(parent: &mut [usize], mut i: usize) -> usize {
            while parent[i] != i {
                parent[i] = parent[parent[i]];
                i = parent[i];
            }
            i
        }
        for j in joints {
            let (a, b) = (root(&mut parent, j.rod), root(&mut parent, n_rods + j.body));
            parent[a] = b;
        }
        let mut held = vec![false; n];
        for (i, r) in self.rods.iter().enumerate() {
            if r.start != EndSupport::Free || r.end != EndSupport::Free {
                let k = root(&mut parent, i);
                held[k] = true;
            }
        }
        for (b, &g) in grounded.iter().enumerate() {
            if g {
                let k = root(&mut parent, n_rods + b);
                held[k] = true;
            }
        }
        for i in 0..n {
            let k = root(&mut parent, i);
            if !held[k] {
                let name = if i < n_rods {
                    format!("structure.rods[{i}]")
                } else {
                    format!("structure.rigid_bodies[{}]", i - n_rods)
                };
                return Err(Error::invalid(
                    name,
                    "floating",
                    "its part of the structure has no ground connection (no clamped rod end and no body_to_ground joint)",
                ));
            }
        }
        Ok(())
    }
}

/// `v / |v|` after checking its length and values.
fn unit(name: &str, v: &[f64], d: usize) -> Result<Vec<f64>> {
    check_len(name, d, v.len())?;
    check_all_finite(name, v)?;
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
    if !(n > 0.0 && n.is_finite()) {
        return Err(Error::invalid(
            name,
            format!("{v:?}"),
            "must be a non-zero direction",
        ));
    }
    Ok(v.iter().map(|x| x / n).collect())
}
