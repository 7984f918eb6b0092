//! The two-finger soft gripper (Fig. 10(a)): two fingers hanging from a
//! palm, mirrored about the gripper's centreline `x = 0`, each two pneumatic
//! segments with a chamber on each side (bending inward or outward).
//!
//! Coordinates: the palm at `y = 0`, finger bases at `(∓ spacing/2, 0)`,
//! fingers pointing down (`−y`), gravity `−y`. The left finger (`x < 0`)
//! bends inward counter-clockwise; the right one is its mirror image, so
//! the same pressures give mirrored shapes. Each finger's pressures are
//! `[proximal inward, proximal outward, distal inward, distal outward]`.
//!
//! The two fingers form one [`Structure`] (two clamped rods); with the
//! grasped object held in place by the contact solve, the fingers are
//! coupled only through the object, so the plant solves each finger as its
//! own clamped chain ([`GripperSpec::finger`]) against the object.

use serde::{Deserialize, Serialize};

use crate::assembly::{Base, Chamber, Robot, RobotSpec, Section};
use crate::element::PlanarCable;
use crate::error::{Error, Result};
use crate::params::gripper as p;
use crate::structure::{RodSpec, Structure, StructureSpec};

/// Which finger.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// The finger at `x < 0`.
    Left,
    /// The finger at `x > 0`, the left one mirrored.
    Right,
}

impl Side {
    /// `+1` for the left finger, `−1` for the right: the sign of "inward" in
    /// x and of an inward (counter-clockwise for the left) rotation.
    pub fn inward(self) -> f64 {
        match self {
            Side::Left => 1.0,
            Side::Right => -1.0,
        }
    }
}

/// The gripper's dimensions and material; defaults from
/// [`crate::params::gripper`].
///
/// # Example
/// ```
/// use softrod::grasp::gripper::{GripperSpec, Side};
/// let g = GripperSpec::default();
/// let left = g.finger(Side::Left)?;
/// assert_eq!((left.n_pressures(), left.n_elements()), (4, 8));
/// assert!((g.opening_m() - 0.094).abs() < 1e-12);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GripperSpec {
    /// Length of each segment (m).
    pub segment_length_m: f64,
    /// Distance between the finger bases (m).
    pub base_spacing_m: f64,
    /// Half the finger thickness (m).
    pub finger_radius_m: f64,
    /// Bending stiffness (N·m²).
    pub ei_nm2: f64,
    /// Axial stiffness (N).
    pub ea_n: f64,
    /// Mass per length (kg/m).
    pub mass_per_length_kg_per_m: f64,
    /// Torque per chamber pressure (N·m/Pa).
    pub gain_nm_per_pa: f64,
    /// Upper chamber pressure (Pa); the lower one is 0.
    pub pressure_max_pa: f64,
    /// Elements per segment.
    pub elements_per_segment: usize,
    /// Gravity (m/s²).
    pub gravity_m_per_s2: [f64; 2],
}

impl Default for GripperSpec {
    fn default() -> Self {
        GripperSpec {
            segment_length_m: p::SEGMENT_LENGTH_M,
            base_spacing_m: p::BASE_SPACING_M,
            finger_radius_m: p::FINGER_RADIUS_M,
            ei_nm2: p::EI_NM2,
            ea_n: p::EA_N,
            mass_per_length_kg_per_m: p::MASS_PER_LENGTH_KG_PER_M,
            gain_nm_per_pa: p::ACTUATION_GAIN_NM_PER_PA,
            pressure_max_pa: p::PRESSURE_MAX_PA,
            elements_per_segment: p::ELEMENTS_PER_SEGMENT,
            gravity_m_per_s2: crate::params::GRAVITY_M_PER_S2.into(),
        }
    }
}

/// Pressures per finger.
pub const FINGER_PRESSURES: usize = 4;

impl GripperSpec {
    /// Checks every field (positive and finite; the fingers must not touch
    /// each other when straight).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`gripper.<field>`).
    pub fn validate(&self) -> Result<()> {
        for (name, v) in [
            ("segment_length_m", self.segment_length_m),
            ("base_spacing_m", self.base_spacing_m),
            ("finger_radius_m", self.finger_radius_m),
            ("ei_nm2", self.ei_nm2),
            ("ea_n", self.ea_n),
            ("gain_nm_per_pa", self.gain_nm_per_pa),
            ("pressure_max_pa", self.pressure_max_pa),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(
                    format!("gripper.{name}"),
                    v,
                    "must be finite and > 0",
                ));
            }
        }
        if !(self.mass_per_length_kg_per_m.is_finite() && self.mass_per_length_kg_per_m >= 0.0) {
            return Err(Error::invalid(
                "gripper.mass_per_length_kg_per_m",
                self.mass_per_length_kg_per_m,
                "must be finite and >= 0",
            ));
        }
        if self.elements_per_segment == 0 {
            return Err(Error::invalid(
                "gripper.elements_per_segment",
                0,
                "must be >= 1",
            ));
        }
        if self.opening_m() <= 0.0 {
            return Err(Error::invalid(
                "gripper.base_spacing_m",
                self.base_spacing_m,
                "the straight fingers overlap (spacing <= 2 finger_radius_m)",
            ));
        }
        crate::error::check_all_finite("gripper.gravity_m_per_s2", &self.gravity_m_per_s2)
    }

    /// The gap between the straight fingers' surfaces (m): the widest
    /// object the gripper takes.
    pub fn opening_m(&self) -> f64 {
        self.base_spacing_m - 2.0 * self.finger_radius_m
    }

    /// A finger's length (m).
    pub fn finger_length_m(&self) -> f64 {
        2.0 * self.segment_length_m
    }

    /// The base point of a finger (m).
    ///
    /// # Example
    /// ```
    /// use softrod::grasp::gripper::{GripperSpec, Side};
    /// let g = GripperSpec::default();
    /// assert_eq!(g.base_m(Side::Left), nalgebra::Vector2::new(-0.5 * g.base_spacing_m, 0.0));
    /// ```
    pub fn base_m(&self, side: Side) -> nalgebra::Vector2<f64> {
        nalgebra::Vector2::new(-side.inward() * 0.5 * self.base_spacing_m, 0.0)
    }

    /// Gravity in the palm's frame as a vector (m/s²; the field
    /// `gravity_m_per_s2`).
    ///
    /// # Example
    /// ```
    /// let g = softrod::grasp::gripper::GripperSpec::default();
    /// assert_eq!(g.gravity().y, g.gravity_m_per_s2[1]);
    /// ```
    pub fn gravity(&self) -> nalgebra::Vector2<f64> {
        self.gravity_m_per_s2.into()
    }

    /// The sections of one finger, with stiffness and gain scaled and the
    /// mesh refined by the given factors (1, 1, 1 for the model; a plant
    /// uses others).
    pub fn finger_sections(
        &self,
        side: Side,
        ei_factor: f64,
        gain_factor: f64,
        mesh_factor: usize,
    ) -> Vec<Section> {
        let g = side.inward() * self.gain_nm_per_pa * gain_factor;
        let chamber = |gain: f64| Chamber {
            gain_nm_per_pa: vec![gain],
            pressure_min_pa: 0.0,
            pressure_max_pa: self.pressure_max_pa,
        };
        (0..2)
            .map(|_| {
                let mut s = Section::uniform(
                    self.segment_length_m,
                    self.ea_n,
                    self.ei_nm2 * ei_factor,
                    self.elements_per_segment * mesh_factor.max(1),
                );
                s.mass_per_length_kg_per_m = self.mass_per_length_kg_per_m;
                s.chambers = vec![chamber(g), chamber(-g)];
                s
            })
            .collect()
    }

    /// The robot spec of one finger (see [`GripperSpec::finger_sections`]).
    pub fn finger_spec(
        &self,
        side: Side,
        ei_factor: f64,
        gain_factor: f64,
        mesh_factor: usize,
    ) -> RobotSpec {
        let mut spec =
            RobotSpec::new(self.finger_sections(side, ei_factor, gain_factor, mesh_factor));
        spec.base = Base {
            position_m: self.base_m(side).as_slice().to_vec(),
            angle_rad: -std::f64::consts::FRAC_PI_2,
            direction: Some(vec![0.0, -1.0]),
            ..Base::default()
        };
        spec.gravity_m_per_s2 = self.gravity_m_per_s2.to_vec();
        spec
    }

    /// One finger of the controller's model, a clamped chain.
    ///
    /// # Errors
    /// [`GripperSpec::validate`]; [`Robot::new`].
    pub fn finger(&self, side: Side) -> Result<Robot<PlanarCable>> {
        self.validate()?;
        self.finger_spec(side, 1.0, 1.0, 1).build_planar()
    }

    /// Both fingers as one structure: two rods clamped at the palm, rod 0
    /// the left finger, rod 1 the right one; the pressures of
    /// [`crate::structure::StructureLoads`] per rod as for
    /// [`GripperSpec::finger`].
    ///
    /// # Errors
    /// [`GripperSpec::validate`]; [`Structure::new`].
    ///
    /// # Example
    /// ```
    /// let s = softrod::grasp::gripper::GripperSpec::default().structure()?;
    /// assert_eq!((s.rods().len(), s.n_elements()), (2, 16));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn structure(&self) -> Result<Structure<PlanarCable>> {
        self.validate()?;
        let rod = |side| {
            RodSpec::clamped(
                self.finger_sections(side, 1.0, 1.0, 1),
                self.base_m(side),
                nalgebra::Vector2::new(0.0, -1.0),
            )
        };
        let mut spec = StructureSpec::new(vec![rod(Side::Left), rod(Side::Right)], vec![], vec![]);
        spec.gravity_m_per_s2 = self.gravity_m_per_s2.to_vec();
        spec.build_planar()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::loads::Loads;
    use crate::statics::StaticSolver;
    use crate::structure::StructureLoads;

    #[test]
    fn the_structure_is_two_mirrored_fingers() {
        let g = GripperSpec::default();
        let p = vec![60e3, 0.0, 20e3, 0.0];
        let loads = Loads {
            pressures_pa: p.clone(),
            ..Loads::default()
        };
        let solver = StaticSolver::default();
        let left = g.finger(Side::Left).unwrap();
        let right = g.finger(Side::Right).unwrap();
        let ql = solver.solve(&left, &loads, None).unwrap().q;
        let qr = solver.solve(&right, &loads, None).unwrap().q;
        let s = g.structure().unwrap();
        let sl = StructureLoads {
            rods: vec![loads.clone(), loads],
            ..Default::default()
        };
        let qs = solver.solve(&s, &sl, None).unwrap().q;
        assert_eq!(qs.len(), ql.len() + qr.len());
        for (a, b) in qs.iter().zip(ql.iter().chain(&qr)) {
            assert!((a - b).abs() < 1e-9, "{a} {b}");
        }
        // mirror: x ↦ −x, y, x' ↦ −x', y'
        for (k, (a, b)) in ql.iter().zip(&qr).enumerate() {
            let sign = if k % 2 == 0 { -1.0 } else { 1.0 };
            assert!((a - sign * b).abs() < 1e-9, "{k}: {a} {b}");
        }
        // inward: the left tip moves to +x, and the free-bending angle is M L / EI per segment
        let tip = left
            .position_at(ql.as_slice(), g.finger_length_m())
            .unwrap();
        assert!(tip[0] > g.base_m(Side::Left)[0] + 0.02, "{tip:?}");
    }

    #[test]
    fn a_free_segment_bends_by_ml_over_ei() {
        // weightless, proximal pressure only: the proximal segment is an arc of
        // angle M L / EI, the distal one straight along its end tangent
        let g = GripperSpec {
            mass_per_length_kg_per_m: 0.0,
            elements_per_segment: 8,
            ..GripperSpec::default()
        };
        let f = g.finger(Side::Right).unwrap();
        let p = 50e3;
        let loads = Loads {
            pressures_pa: vec![p, 0.0, 0.0, 0.0],
            ..Loads::default()
        };
        let q = StaticSolver::default().solve(&f, &loads, None).unwrap().q;
        let phi = g.gain_nm_per_pa * p * g.segment_length_m / g.ei_nm2;
        let angles = f.node_angles(q.as_slice()).unwrap();
        let mid = g.elements_per_segment;
        // right finger: inward is clockwise, from −π/2
        let turned = -(angles[mid] + std::f64::consts::FRAC_PI_2);
        assert!((turned - phi).abs() < 2e-3 * phi, "{turned} {phi}");
        assert!((angles[2 * mid] - angles[mid]).abs() < 1e-6);
    }

    #[test]
    fn bad_dimensions_name_the_field() {
        let g = GripperSpec {
            base_spacing_m: 0.01,
            ..GripperSpec::default()
        };
        assert_eq!(
            g.validate().unwrap_err().field(),
            Some("gripper.base_spacing_m")
        );
        let g = GripperSpec {
            ei_nm2: -1.0,
            ..GripperSpec::default()
        };
        assert_eq!(
            g.finger(Side::Left).unwrap_err().field(),
            Some("gripper.ei_nm2")
        );
    }
}
