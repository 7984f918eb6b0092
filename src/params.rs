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
pub const GRAVITY_M_PER_S2: [f64; 2] = [0.0, -9.81];

/// Pressures of the built-in default scene (Pa): the first section's upper
/// chamber at 60 kPa lifts the robot against its weight, the second
/// section's lower chamber at 30 kPa curls the tip back down.
pub const DEFAULT_PRESSURES_PA: [f64; 4] = [60.0e3, 0.0, 0.0, 30.0e3];
