//! The values the paper leaves open, in one place, with their reasons.
//!
//! What the paper gives: sections of 120 mm, EI =
//! 0.025 N·m² (Sec. IV), EA = 300 N (the simulated robot of Fig. 3), five
//! markers, control at 30 Hz. Everything else a simulation needs is chosen
//! here and used everywhere (the built-in scene, `examples/two_section.json`,
//! tests and benches).

/// Section length of the two-section robot (m). Paper, Sec. IV.
pub const SECTION_LENGTH_M: f64 = 0.12;

/// Bending stiffness EI (N·m²). Paper, Sec. IV (identified by static tests).
pub const EI_NM2: f64 = 0.025;

/// Axial stiffness EA (N). Paper, Fig. 3 (the simulated robot); Sec. IV does
/// not give it, and the two robots are built alike.
pub const EA_N: f64 = 300.0;

/// Mass per length (kg/m). Not in the paper. Each section is two PVC tubes of
/// 18 mm outer diameter (about 1 mm wall, 1.4 g/cm³: 0.075 kg/m each) with
/// steel wires and printed connectors: 0.15 kg/m. The robot then sags by
/// about 24 mm (10 % of its length) under its own weight when horizontal,
/// a clearly nonlinear but not extreme case.
pub const MASS_PER_LENGTH_KG_PER_M: f64 = 0.15;

/// Torque per chamber pressure (N·m/Pa). Not in the paper. Chosen so that the
/// upper pressure bound bends one free section by about 80°
/// (`M = EI θ / L = 0.025 × 1.4 / 0.12 ≈ 0.3 N·m` at 100 kPa).
pub const ACTUATION_GAIN_NM_PER_PA: f64 = 3.0e-6;

/// Chamber pressure bounds (Pa): gauge pressure, vented to full. Not in the
/// paper; 100 kPa is a common limit for PVC-tube actuators.
pub const PRESSURE_MIN_PA: f64 = 0.0;
/// Upper chamber pressure bound (Pa).
pub const PRESSURE_MAX_PA: f64 = 100.0e3;

/// Elements per section of the default scene: 10 per section (20 in all,
/// as in Fig. 4 of the paper).
pub const ELEMENTS_PER_SECTION: usize = 10;

/// Gravity (m/s²), the base horizontal so that the weight bends the robot.
///
/// # Example
/// ```
/// let g = softrod::params::GRAVITY_M_PER_S2;
/// assert_eq!(g, nalgebra::Vector2::new(0.0, -9.81));
/// assert_eq!(g.norm(), 9.81);
/// ```
pub const GRAVITY_M_PER_S2: nalgebra::Vector2<f64> = nalgebra::Vector2::new(0.0, -9.81);

/// Pressures of the built-in default scene (Pa): the first section's upper
/// chamber at 60 kPa lifts the robot against its weight, the second
/// section's lower chamber at 30 kPa curls the tip back down.
pub const DEFAULT_PRESSURES_PA: [f64; 4] = [60.0e3, 0.0, 0.0, 30.0e3];

/// The soft parallel robot (Figs. 7–8 of the paper, its ref. \[48\]): three
/// pneumatic legs from a base circle to a rigid platform. The paper gives
/// none of its numbers; they are chosen here, with their reasons.
pub mod parallel {
    /// Number of legs (the paper's robot has three).
    pub const LEGS: usize = 3;

    /// Radius of the circle the legs are clamped on (m). The legs are
    /// hung from a base plate above (the weights of Fig. 8 hang from the
    /// platform below); 60 mm leaves room for three actuators of about
    /// 20 mm diameter with their fittings.
    pub const BASE_RADIUS_M: f64 = 0.06;

    /// Radius of the circle the legs are joined to the platform on (m).
    /// Smaller than the base's, so the legs lean inwards by
    /// `asin(0.02 / 0.12) ≈ 9.6°` (the closed-form tests use equal radii,
    /// vertical legs).
    pub const PLATFORM_RADIUS_M: f64 = 0.04;

    /// Radius of the platform itself (m): a printed disc of 100 mm diameter;
    /// the legs' joints must lie on it.
    pub const PLATFORM_DISC_RADIUS_M: f64 = 0.05;

    /// Leg length (m): one of the paper's 120 mm sections long, made of two
    /// pneumatic sections of 60 mm.
    pub const LEG_LENGTH_M: f64 = 0.12;

    /// Pneumatic sections per leg, each with three chambers at 120°.
    pub const SECTIONS_PER_LEG: usize = 2;

    /// Elements per section of the model.
    pub const ELEMENTS_PER_SECTION: usize = 4;

    /// Bending stiffness EI (N·m²): the paper's identified value for its
    /// actuators (Sec. IV), both section axes.
    pub const EI_NM2: f64 = 0.025;

    /// Axial stiffness EA (N): the paper's simulated robot (Fig. 3).
    pub const EA_N: f64 = 300.0;

    /// Torsional stiffness GJ (N·m²): an isotropic, incompressible
    /// elastomer section (ν = 0.5, `J = 2I` for a round section) has
    /// `GJ = EI/(1 + ν) = EI/1.5`.
    pub const GJ_NM2: f64 = EI_NM2 / 1.5;

    /// Mass per length of a leg (kg/m), as the manipulator's sections.
    pub const MASS_PER_LENGTH_KG_PER_M: f64 = 0.15;

    /// Platform mass (kg): a printed disc of about 100 mm diameter, 5 mm thick.
    pub const PLATFORM_MASS_KG: f64 = 0.05;

    /// Torque per chamber pressure (N·m/Pa), as the manipulator's: 100 kPa
    /// bends a free 60 mm section by about 40°.
    pub const GAIN_NM_PER_PA: f64 = 3.0e-6;
}

/// The two-finger gripper of Sec. VI (Fig. 10(a)). The paper's text gives
/// no dimensions (only the drawing); these are chosen, with their reasons:
///
/// - Each finger: two equal pneumatic segments of 50 mm (the drawing shows
///   two segments of about equal length; a 100 mm finger reaches objects
///   from a walnut, about 30 mm, to a bottle, about 65 mm, as in Fig. 10(c)).
/// - Finger bases 110 mm apart, fingers 16 mm thick (rod radius 8 mm): the
///   straight fingers leave a 94 mm opening, wider than the largest object
///   of Table I (an apple of about 75 mm) with room for its placement error.
/// - Each segment has two chambers (one on each side of the strain-limiting
///   layer), so it bends either way: four pressures per finger, which makes
///   the Jacobian (50) 3 × 4.
pub mod gripper {
    /// Length of each of a finger's two segments (m).
    pub const SEGMENT_LENGTH_M: f64 = 0.05;
    /// Distance between the two finger bases (m), symmetric about x = 0.
    pub const BASE_SPACING_M: f64 = 0.11;
    /// Half the finger's thickness (m): contact is measured from the
    /// centreline offset by it.
    pub const FINGER_RADIUS_M: f64 = 0.008;
    /// Bending stiffness of a finger (N·m²). A silicone finger with a
    /// strain-limiting layer is much softer than the PVC robot of Sec. IV:
    /// chosen so that a free segment bends by about 95° at the upper
    /// pressure (`θ = M L / EI = 0.4 × 0.05 / 0.012 ≈ 1.67 rad`), as the
    /// fingers of Fig. 10(a) curl.
    pub const EI_NM2: f64 = 0.012;
    /// Axial stiffness (N): the strain-limiting layer prevents elongation;
    /// as the robot's.
    pub const EA_N: f64 = 300.0;
    /// Mass per length (kg/m): a 16 × 20 mm silicone section, about half of
    /// it chambers (1.1 g/cm³): about 0.18 kg/m.
    pub const MASS_PER_LENGTH_KG_PER_M: f64 = 0.18;
    /// Torque per chamber pressure (N·m/Pa): a chamber face of about
    /// 25 × 20 mm (the finger's width by a chamber's height) at about 8 mm
    /// from the strain-limiting layer (`5e-4 m² × 0.008 m = 4e-6`), 0.4 N·m
    /// at the upper bound. Measured in the simulated Table I: half of this
    /// (with half the stiffness, the same free shapes) squeezed about 1.7 N
    /// per finger and held at most 0.20 kg, the red apple (0.2 kg) slipped;
    /// this value holds about 0.45 kg, the paper's gripper about 0.4 kg.
    pub const ACTUATION_GAIN_NM_PER_PA: f64 = 4.0e-6;
    /// Upper chamber pressure (Pa), as the robot's.
    pub const PRESSURE_MAX_PA: f64 = 100.0e3;
    /// Elements per segment of the controller's model (the plant uses more).
    pub const ELEMENTS_PER_SEGMENT: usize = 4;
}
