//! Assembly of a multi-section robot from cable elements: the dof layout, the
//! elastic forces and the tangent stiffness, self-weight, known loads, the
//! distributed-load matrix `J_QF = B = ∫ Sᵀ S dX` (22), (23), (26), and the
//! pneumatic actuation as end torques of each section, `Q_A = ∂W_A/∂q` (18),
//! `W_A = Σ_s M_s · (θ_end(s) − θ_start(s))`, `M_s = G_s P`.
//!
//! Layout: node-major, `q = [q_0; q_1; …; q_N]`, `NODE_DOFS` numbers per node.
//! Node 0 is the clamped base. A clamp fixes the base position and the base
//! direction but not the axial strain there: MODEL.md §2 prescribes `r_0'`,
//! but prescribing `|r_0'| = 1` forbids stretch at the base and makes an
//! axial tip force stretch a 6-element cantilever 2 % too little (exudyn's
//! cantilevers likewise constrain only x, y and y' of the base). So the
//! unknowns of a static solve, the *free coordinates* `u`, are the base
//! stretch `b` (with `r_0' = (1 + b) t_0`) followed by `q_1 … q_N`;
//! [`Robot::expand_step`] and [`Robot::restrict`] map between `u` and `q`. Equilibrium (17) is `Q(F, q, P) = 0` with
//! `Q = Q_F + Q_E + Q_A` and the tangent stiffness is `K = −∂Q/∂q`.

use serde::{Deserialize, Serialize};

use crate::element::{ArcPoint, Element, PlanarCable, SpatialCable, DEFAULT_GAUSS_POINTS};
use crate::error::{
    check_all_finite, check_at_most, check_finite, check_index, check_len, check_positive, Error,
    Result,
};
use crate::linsolve::BandedMatrix;
use crate::loads::{outside, Loads};
use crate::quadrature::GaussRule;

/// The largest number of elements a robot may have; larger requests are
/// refused before anything is allocated.
pub const MAX_ELEMENTS: usize = 200_000;
/// Largest element dof count any element type has (full 3-D ANCF: 24).
const MAX_EDOF: usize = 24;

/// One pneumatic chamber: its torque per pressure and its pressure bounds.
///
/// # Example
/// ```
/// let c = softrod::assembly::Chamber { gain_nm_per_pa: vec![3e-6], pressure_min_pa: 0.0, pressure_max_pa: 100e3 };
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Chamber {
    /// Column of the calibration matrix `G`: torque on the section per unit
    /// pressure (N·m/Pa; one component in 2-D, positive bends counter-clockwise;
    /// three in 3-D, world axes: a spatial cable has no section frame, and
    /// the torque works through the rotation of the section's end tangents
    /// from the base direction, see [`crate::element::SpatialCable`]).
    pub gain_nm_per_pa: Vec<f64>,
    /// Lower pressure bound (Pa).
    pub pressure_min_pa: f64,
    /// Upper pressure bound (Pa).
    pub pressure_max_pa: f64,
}

/// One section of the robot: a uniform piece with its own stiffness, weight,
/// discretization and chambers.
///
/// In JSON, `"elements"` is a positive integer or `"auto"`; `"auto"` sets
/// [`Section::auto_elements`] (and `elements` to 0), and a number clears it.
///
/// # Example
/// ```
/// use softrod::assembly::Section;
/// let s = Section::uniform(0.12, 300.0, 0.025, 10);
/// assert_eq!(s.elements, 10);
/// let auto: Section = serde_json::from_str(
///     r#"{"length_m": 0.12, "ea_n": 300, "ei_nm2": 0.025, "elements": "auto"}"#).unwrap();
/// assert!(auto.auto_elements);
/// assert!(serde_json::to_string(&auto).unwrap().contains(r#""elements":"auto""#));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "SectionJson", into = "SectionJson")]
pub struct Section {
    /// Undeformed length (m).
    pub length_m: f64,
    /// Axial stiffness EA (N).
    pub ea_n: f64,
    /// Bending stiffness EI (N·m²).
    pub ei_nm2: f64,
    /// Mass per undeformed length (kg/m); zero is a weightless section.
    #[serde(default)]
    pub mass_per_length_kg_per_m: f64,
    /// Number of elements.
    pub elements: usize,
    /// Whether the scene asked for `"elements": "auto"`: the count is then
    /// chosen by [`crate::refine::auto_elements`], and `elements` is not
    /// used until the refinement fills it in. A scene refuses to build a
    /// robot from such a section ([`crate::scene::Scene::robot`]); a
    /// [`RobotSpec`] ignores the flag and builds with `elements`.
    pub auto_elements: bool,
    /// Rest curvature `κ0` (1/m).
    pub rest_curvature_per_m: f64,
    /// Pneumatic chambers acting on this section.
    pub chambers: Vec<Chamber>,
}

/// A section's element count as written in JSON: a number or `"auto"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ElementCount {
    Fixed(usize),
    Auto,
}

impl Serialize for ElementCount {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            ElementCount::Fixed(n) => s.serialize_u64(*n as u64),
            ElementCount::Auto => s.serialize_str("auto"),
        }
    }
}

impl<'de> Deserialize<'de> for ElementCount {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = ElementCount;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(r#"a positive integer or "auto""#)
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> std::result::Result<Self::Value, E> {
                usize::try_from(v)
                    .map(ElementCount::Fixed)
                    .map_err(|_| E::invalid_value(serde::de::Unexpected::Unsigned(v), &self))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<Self::Value, E> {
                u64::try_from(v)
                    .map_err(|_| E::invalid_value(serde::de::Unexpected::Signed(v), &self))
                    .and_then(|v| self.visit_u64(v))
            }
            fn visit_str<E: serde::de::Error>(
                self,
                v: &str,
            ) -> std::result::Result<Self::Value, E> {
                if v == "auto" {
                    Ok(ElementCount::Auto)
                } else {
                    Err(E::invalid_value(serde::de::Unexpected::Str(v), &self))
                }
            }
        }
        d.deserialize_any(Visitor)
    }
}

/// The JSON form of [`Section`].
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SectionJson {
    length_m: f64,
    ea_n: f64,
    ei_nm2: f64,
    #[serde(default)]
    mass_per_length_kg_per_m: f64,
    elements: ElementCount,
    #[serde(default)]
    rest_curvature_per_m: f64,
    #[serde(default)]
    chambers: Vec<Chamber>,
}

impl From<SectionJson> for Section {
    fn from(j: SectionJson) -> Self {
        let (elements, auto_elements) = match j.elements {
            ElementCount::Fixed(n) => (n, false),
            ElementCount::Auto => (0, true),
        };
        Section {
            length_m: j.length_m,
            ea_n: j.ea_n,
            ei_nm2: j.ei_nm2,
            mass_per_length_kg_per_m: j.mass_per_length_kg_per_m,
            elements,
            auto_elements,
            rest_curvature_per_m: j.rest_curvature_per_m,
            chambers: j.chambers,
        }
    }
}

impl From<Section> for SectionJson {
    fn from(s: Section) -> Self {
        SectionJson {
            length_m: s.length_m,
            ea_n: s.ea_n,
            ei_nm2: s.ei_nm2,
            mass_per_length_kg_per_m: s.mass_per_length_kg_per_m,
            elements: if s.auto_elements {
                ElementCount::Auto
            } else {
                ElementCount::Fixed(s.elements)
            },
            rest_curvature_per_m: s.rest_curvature_per_m,
            chambers: s.chambers,
        }
    }
}

impl Section {
    /// A weightless section with no chambers and no rest curvature.
    pub fn uniform(length_m: f64, ea_n: f64, ei_nm2: f64, elements: usize) -> Self {
        Section {
            length_m,
            ea_n,
            ei_nm2,
            mass_per_length_kg_per_m: 0.0,
            elements,
            auto_elements: false,
            rest_curvature_per_m: 0.0,
            chambers: Vec::new(),
        }
    }
}

/// What the base clamp prescribes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Clamp {
    /// Position and direction of the base; the axial strain at the base is
    /// free (the physical clamp; default).
    #[default]
    PositionAndDirection,
    /// Position and the whole slope vector `r_0' = t_0` (MODEL.md's literal
    /// reading, and exudyn's cantilevers that fix all four base coordinates):
    /// forbids axial strain at the base, a boundary layer one element long.
    Full,
}

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

fn default_gravity() -> Vec<f64> {
    vec![0.0, -9.81]
}
fn default_gauss() -> usize {
    DEFAULT_GAUSS_POINTS
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
        Robot::new(self.clone(), |s, le, ax, be| {
            PlanarCable::with_rules(le, s.ea_n, s.ei_nm2, s.rest_curvature_per_m, ax, be)
        })
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

    /// Total number of elements (saturating).
    pub fn total_elements(&self) -> usize {
        self.sections
            .iter()
            .fold(0usize, |a, s| a.saturating_add(s.elements))
    }
}

/// A flattened chamber: section index, gain, bounds.
#[derive(Debug, Clone)]
struct ChamberRef {
    section: usize,
    gain: Vec<f64>,
    min: f64,
    max: f64,
}

/// A robot assembled from elements of type `E`.
#[derive(Debug, Clone)]
pub struct Robot<E: Element> {
    spec: RobotSpec,
    elements: Vec<E>,
    node_s: Vec<f64>,
    section_nodes: Vec<(usize, usize)>,
    base_node: Vec<f64>,
    base_free: Vec<Vec<f64>>,
    gravity_force: Vec<f64>,
    chambers: Vec<ChamberRef>,
    gram: BandedMatrix,
    /// Each element's `∫ s_k s_l dX` (4 × 4 over the node slots), the
    /// blocks `gram` is assembled from (applied element by element).
    elem_gram: Vec<[[f64; 4]; 4]>,
    line_rule: GaussRule,
}

impl<E: Element> Robot<E> {
    /// Validates `spec` and assembles the robot; `make` builds one element of
    /// a section from `(section, element length, axial points, bending points)`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field at fault
    /// (`robot.sections[i].ei_nm2`, …) for empty robots, zero elements,
    /// non-positive lengths or stiffnesses, negative mass, non-finite
    /// numbers, inverted pressure bounds, or an element type whose constants
    /// do not fit the assembly; [`Error::TooLarge`] for more than
    /// [`MAX_ELEMENTS`] elements or Gauss rules above
    /// [`crate::quadrature::MAX_POINTS`] points (both refused before anything
    /// proportional is allocated); [`Error::DimensionMismatch`] for vectors
    /// of the wrong size. Errors of `make` are returned with the section's
    /// path prefixed to the field name.
    pub fn new(
        spec: RobotSpec,
        make: impl Fn(&Section, f64, usize, usize) -> Result<E>,
    ) -> Result<Self> {
        let d = E::DIM;
        let nd = E::NODE_DOFS;
        if spec.sections.is_empty() {
            return Err(Error::invalid(
                "robot.sections",
                "[]",
                "a robot needs at least one section",
            ));
        }
        // the assembly's fixed-size scratch buffers and node layout
        if d == 0 || E::MOMENT_DIM == 0 || nd < 2 * d || 2 * nd > MAX_EDOF {
            return Err(Error::invalid(
                "element",
                format!("DIM = {d}, NODE_DOFS = {nd}"),
                format!("needs 2 DIM <= NODE_DOFS <= {}", MAX_EDOF / 2),
            ));
        }
        let mut total = 0usize;
        for (i, s) in spec.sections.iter().enumerate() {
            // `total <= MAX_ELEMENTS` here, so the subtraction cannot underflow
            check_at_most(
                &format!("robot.sections[{i}].elements"),
                s.elements,
                MAX_ELEMENTS - total,
            )?;
            total += s.elements;
        }
        check_len("base.position_m", d, spec.base.position_m.len())?;
        check_all_finite("base.position_m", &spec.base.position_m)?;
        check_finite("base.angle_rad", spec.base.angle_rad)?;
        check_len("gravity_m_per_s2", d, spec.gravity_m_per_s2.len())?;
        check_all_finite("gravity_m_per_s2", &spec.gravity_m_per_s2)?;
        for (name, n) in [
            ("robot.axial_gauss_points", spec.axial_gauss_points),
            ("robot.bending_gauss_points", spec.bending_gauss_points),
        ] {
            if n == 0 {
                return Err(Error::invalid(name, n, "must be >= 1"));
            }
            check_at_most(name, n, crate::quadrature::MAX_POINTS)?;
        }
        let mut chambers = Vec::new();
        for (i, s) in spec.sections.iter().enumerate() {
            let p = |f: &str| format!("robot.sections[{i}].{f}");
            check_positive(&p("length_m"), s.length_m)?;
            check_positive(&p("ea_n"), s.ea_n)?;
            check_positive(&p("ei_nm2"), s.ei_nm2)?;
            if !(s.mass_per_length_kg_per_m.is_finite() && s.mass_per_length_kg_per_m >= 0.0) {
                return Err(Error::invalid(
                    p("mass_per_length_kg_per_m"),
                    s.mass_per_length_kg_per_m,
                    "must be finite and >= 0",
                ));
            }
            if s.elements == 0 {
                return Err(Error::invalid(
                    p("elements"),
                    0,
                    "a section needs at least one element",
                ));
            }
            check_finite(&p("rest_curvature_per_m"), s.rest_curvature_per_m)?;
            for (c, ch) in s.chambers.iter().enumerate() {
                let pc = |f: &str| format!("robot.sections[{i}].chambers[{c}].{f}");
                check_len(
                    &pc("gain_nm_per_pa"),
                    E::MOMENT_DIM,
                    ch.gain_nm_per_pa.len(),
                )?;
                check_all_finite(&pc("gain_nm_per_pa"), &ch.gain_nm_per_pa)?;
                check_finite(&pc("pressure_min_pa"), ch.pressure_min_pa)?;
                check_finite(&pc("pressure_max_pa"), ch.pressure_max_pa)?;
                if ch.pressure_min_pa > ch.pressure_max_pa {
                    return Err(Error::invalid(
                        pc("pressure_max_pa"),
                        ch.pressure_max_pa,
                        format!("must be >= pressure_min_pa = {}", ch.pressure_min_pa),
                    ));
                }
                chambers.push(ChamberRef {
                    section: i,
                    gain: ch.gain_nm_per_pa.clone(),
                    min: ch.pressure_min_pa,
                    max: ch.pressure_max_pa,
                });
            }
        }
        // elements and nodes
        let mut elements = Vec::with_capacity(total);
        let mut node_s = Vec::with_capacity(total + 1);
        let mut section_nodes = Vec::with_capacity(spec.sections.len());
        node_s.push(0.0);
        let mut s0 = 0.0;
        for (i, sec) in spec.sections.iter().enumerate() {
            let le = sec.length_m / sec.elements as f64;
            let start = node_s.len() - 1;
            let proto = make(sec, le, spec.axial_gauss_points, spec.bending_gauss_points)
                .map_err(|e| e.with_prefix(&format!("robot.sections[{i}].")))?;
            for k in 0..sec.elements {
                elements.push(proto.clone());
                node_s.push(if k + 1 == sec.elements {
                    s0 + sec.length_m
                } else {
                    s0 + (k + 1) as f64 * le
                });
            }
            s0 += sec.length_m;
            section_nodes.push((start, node_s.len() - 1));
        }
        let dir = base_direction(&spec.base, d)?;
        let base_node = E::straight_node(&spec.base.position_m, &dir);
        check_len("element straight_node", nd, base_node.len())?;
        let base_free = match spec.base.clamp {
            Clamp::PositionAndDirection => E::clamp_free_directions(&base_node),
            Clamp::Full => Vec::new(),
        };
        for t in &base_free {
            check_len("element clamp_free_directions", nd, t.len())?;
        }
        let n_q = node_s.len() * nd;
        let kb = 2 * nd - 1;
        let line_rule = GaussRule::new(5)?;
        let mut robot = Robot {
            spec,
            elements,
            node_s,
            section_nodes,
            base_node,
            base_free,
            gravity_force: vec![0.0; n_q],
            chambers,
            gram: BandedMatrix::zeros(n_q, kb, kb),
            elem_gram: Vec::new(),
            line_rule,
        };
        robot.assemble_gram();
        // self-weight: uniform line load m g per section
        let mut gravity = vec![0.0; n_q];
        for (e, el) in robot.elements.iter().enumerate() {
            let m = robot.spec.sections[robot.section_of_element(e)].mass_per_length_kg_per_m;
            if m == 0.0 {
                continue;
            }
            let w: Vec<f64> = robot.spec.gravity_m_per_s2.iter().map(|g| m * g).collect();
            for (xi, wt) in robot.line_rule.iter() {
                add_shape_force(
                    el,
                    xi,
                    &w,
                    wt * el.length(),
                    &mut gravity[e * nd..(e + 2) * nd],
                );
            }
        }
        robot.gravity_force = gravity;
        Ok(robot)
    }

    fn assemble_gram(&mut self) {
        let nd = E::NODE_DOFS;
        let d = E::DIM;
        let rule = GaussRule::new(4).unwrap_or_else(|_| self.line_rule.clone());
        let mut blocks = Vec::with_capacity(self.elements.len());
        for (e, el) in self.elements.iter().enumerate() {
            let le = el.length();
            let mut m = [[0.0; 4]; 4];
            for (xi, w) in rule.iter() {
                let s = el.shape(xi);
                for k in 0..4 {
                    for l in 0..4 {
                        m[k][l] += w * le * s[k] * s[l];
                    }
                }
            }
            // S = [s_1 I, s_2 I, s_3 I, s_4 I]; component k of q_e block = s_k
            for (k, mk) in m.iter().enumerate() {
                for (l, mkl) in mk.iter().enumerate() {
                    for i in 0..d {
                        self.gram.add(e * nd + k * d + i, e * nd + l * d + i, *mkl);
                    }
                }
            }
            blocks.push(m);
        }
        self.elem_gram = blocks;
    }

    /// `J_QF F = ∫ Sᵀ S dX F` ([`Robot::load_gram`] times `f`) into `out`,
    /// element by element (`O(n)`, no allocation); the same map as
    /// `load_gram().mul_vec(f)` up to round-off.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `f` or `out` does not have `n_q` entries.
    pub fn apply_load_gram_into(&self, f: &[f64], out: &mut [f64]) -> Result<()> {
        check_len("f", self.n_q(), f.len())?;
        check_len("out", self.n_q(), out.len())?;
        let nd = E::NODE_DOFS;
        let d = E::DIM;
        out.iter_mut().for_each(|v| *v = 0.0);
        if d == 2 && nd == 4 {
            // the planar cable: pairs of components, unrolled
            for (e, m) in self.elem_gram.iter().enumerate() {
                let Ok(fe) = <&[f64; 8]>::try_from(&f[e * 4..e * 4 + 8]) else {
                    continue;
                };
                let Ok(oe) = <&mut [f64; 8]>::try_from(&mut out[e * 4..e * 4 + 8]) else {
                    continue;
                };
                for k in 0..4 {
                    let (mut x, mut y) = (0.0, 0.0);
                    for l in 0..4 {
                        x += m[k][l] * fe[2 * l];
                        y += m[k][l] * fe[2 * l + 1];
                    }
                    oe[2 * k] += x;
                    oe[2 * k + 1] += y;
                }
            }
            return Ok(());
        }
        for (e, m) in self.elem_gram.iter().enumerate() {
            for k in 0..4 {
                for i in 0..d {
                    let v: f64 = (0..4).map(|l| m[k][l] * f[e * nd + l * d + i]).sum();
                    out[e * nd + k * d + i] += v;
                }
            }
        }
        Ok(())
    }

    /// As [`Robot::apply_load_gram_into`], into a new vector.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `f` does not have `n_q` entries.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]).build_planar().unwrap();
    /// let f: Vec<f64> = (0..robot.n_q()).map(|i| (i % 5) as f64).collect();
    /// let a = robot.apply_load_gram(&f).unwrap();
    /// let b = robot.load_gram().mul_vec(&f).unwrap();
    /// assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-15));
    /// ```
    pub fn apply_load_gram(&self, f: &[f64]) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.n_q()];
        self.apply_load_gram_into(f, &mut out)?;
        Ok(out)
    }

    /// The robot's definition.
    pub fn spec(&self) -> &RobotSpec {
        &self.spec
    }
    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.elements.len()
    }
    /// Number of nodes (elements + 1).
    pub fn n_nodes(&self) -> usize {
        self.node_s.len()
    }
    /// Number of coordinates `n_q`, base node included.
    pub fn n_q(&self) -> usize {
        self.node_s.len() * E::NODE_DOFS
    }
    /// Number of free coordinates: the base's free directions (its stretch)
    /// and the coordinates of nodes 1 … N.
    pub fn n_free(&self) -> usize {
        self.base_free.len() + self.n_q() - E::NODE_DOFS
    }

    /// Number of free coordinates at the clamped base (1 for a cable with
    /// [`Clamp::PositionAndDirection`], 0 with [`Clamp::Full`]).
    pub fn n_base_free(&self) -> usize {
        self.base_free.len()
    }

    /// As [`Robot::dof_map`] into a fixed buffer; returns the count.
    fn dof_map_into(&self, gi: usize, out: &mut [(usize, f64); MAX_EDOF]) -> usize {
        let nd = E::NODE_DOFS;
        let nb = self.base_free.len();
        if gi >= nd {
            out[0] = (nb + gi - nd, 1.0);
            return 1;
        }
        let mut n = 0;
        for (j, t) in self.base_free.iter().enumerate() {
            if t[gi] != 0.0 && n < MAX_EDOF {
                out[n] = (j, t[gi]);
                n += 1;
            }
        }
        n
    }

    /// The free coordinates that a global coordinate `gi` depends on, with
    /// coefficients: `dq[gi] = Σ coef · du[index]`.
    fn dof_map(&self, gi: usize, out: &mut Vec<(usize, f64)>) {
        out.clear();
        let nd = E::NODE_DOFS;
        let nb = self.base_free.len();
        if gi >= nd {
            out.push((nb + gi - nd, 1.0));
        } else {
            for (j, t) in self.base_free.iter().enumerate() {
                if t[gi] != 0.0 {
                    out.push((j, t[gi]));
                }
            }
        }
    }

    /// Maps a step `du` of the free coordinates to the step of all `n_q`
    /// coordinates, `dq = M du`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `du` has the wrong size.
    pub fn expand_step(&self, du: &[f64]) -> Result<Vec<f64>> {
        check_len("du", self.n_free(), du.len())?;
        let nd = E::NODE_DOFS;
        let nb = self.base_free.len();
        let mut dq = vec![0.0; self.n_q()];
        for (j, t) in self.base_free.iter().enumerate() {
            for k in 0..nd {
                dq[k] += t[k] * du[j];
            }
        }
        dq[nd..].copy_from_slice(&du[nb..]);
        Ok(dq)
    }

    /// As [`Robot::expand_step`], into `dq` (`n_q` entries; no allocation).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `du` or `dq` has the wrong size.
    pub fn expand_step_into(&self, du: &[f64], dq: &mut [f64]) -> Result<()> {
        check_len("du", self.n_free(), du.len())?;
        check_len("dq", self.n_q(), dq.len())?;
        let nd = E::NODE_DOFS;
        let nb = self.base_free.len();
        dq[..nd].iter_mut().for_each(|v| *v = 0.0);
        for (j, t) in self.base_free.iter().enumerate() {
            for k in 0..nd {
                dq[k] += t[k] * du[j];
            }
        }
        dq[nd..].copy_from_slice(&du[nb..]);
        Ok(())
    }

    /// As [`Robot::restrict`], into `u` (`n_free` entries; no allocation).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `f` or `u` has the wrong size.
    pub fn restrict_into(&self, f: &[f64], u: &mut [f64]) -> Result<()> {
        check_len("f", self.n_q(), f.len())?;
        check_len("u", self.n_free(), u.len())?;
        let nd = E::NODE_DOFS;
        let nb = self.base_free.len();
        for (j, t) in self.base_free.iter().enumerate() {
            u[j] = t.iter().zip(&f[..nd]).map(|(a, b)| a * b).sum();
        }
        u[nb..].copy_from_slice(&f[nd..]);
        Ok(())
    }

    /// Restricts a generalized force over all `n_q` coordinates to the free
    /// coordinates, `Mᵀ f` (the work-conjugate of [`Robot::expand_step`]).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `f` has the wrong size.
    pub fn restrict(&self, f: &[f64]) -> Result<Vec<f64>> {
        check_len("f", self.n_q(), f.len())?;
        let nd = E::NODE_DOFS;
        let mut u = Vec::with_capacity(self.n_free());
        for t in &self.base_free {
            u.push(t.iter().zip(&f[..nd]).map(|(a, b)| a * b).sum());
        }
        u.extend_from_slice(&f[nd..]);
        Ok(u)
    }
    /// Undeformed arc coordinate of every node (m).
    pub fn node_arc(&self) -> &[f64] {
        &self.node_s
    }
    /// Total undeformed length (m).
    pub fn length(&self) -> f64 {
        self.node_s.last().copied().unwrap_or(0.0)
    }
    /// The elements, base to tip.
    pub fn elements(&self) -> &[E] {
        &self.elements
    }
    /// First and last node of every section.
    pub fn section_nodes(&self) -> &[(usize, usize)] {
        &self.section_nodes
    }
    /// Number of chambers (pressures).
    pub fn n_pressures(&self) -> usize {
        self.chambers.len()
    }
    /// `(min, max)` bounds of every pressure (Pa).
    pub fn pressure_bounds(&self) -> Vec<(f64, f64)> {
        self.chambers.iter().map(|c| (c.min, c.max)).collect()
    }

    /// Index of the section that holds element `e`; an `e` beyond the last
    /// element gives the last section (never panics: a robot has at least
    /// one section).
    pub fn section_of_element(&self, e: usize) -> usize {
        self.section_nodes
            .iter()
            .position(|&(_, end)| e < end)
            .unwrap_or(self.section_nodes.len().saturating_sub(1))
    }

    /// The clamped base node's coordinates.
    pub fn base_node(&self) -> &[f64] {
        &self.base_node
    }

    /// The stress-free straight configuration along the base direction
    /// (exact equilibrium without loads, actuation and rest curvature).
    pub fn reference_configuration(&self) -> Vec<f64> {
        let d = E::DIM;
        let nd = E::NODE_DOFS;
        let mut q = Vec::with_capacity(self.n_q());
        let dir: Vec<f64> = self.base_node[d..2 * d].to_vec();
        for &s in &self.node_s {
            let p: Vec<f64> = (0..d).map(|i| self.base_node[i] + s * dir[i]).collect();
            let node = E::straight_node(&p, &dir);
            q.extend(node.iter().take(nd));
        }
        q
    }

    /// The configuration the section torques of `pressures` (plus rest
    /// curvature) would give without any other load: each section a circular
    /// arc of curvature `κ_s = M_s / EI_s + κ0_s`, inextensible (planar
    /// robots; a spatial robot gets the straight configuration). The static
    /// solver starts cold solves here: it is exact for pure actuation and
    /// much closer to equilibrium than the straight line.
    pub fn arc_configuration(&self, pressures: &[f64]) -> Vec<f64> {
        if E::DIM != 2 || E::MOMENT_DIM != 1 {
            return self.reference_configuration();
        }
        let nd = E::NODE_DOFS;
        let torques = self.section_torques(pressures);
        let mut q = Vec::with_capacity(self.n_q());
        let th0 = match self.spec.base.direction {
            None => self.spec.base.angle_rad,
            Some(_) => self.base_node[3].atan2(self.base_node[2]),
        };
        let (mut x, mut y, mut th) = (self.base_node[0], self.base_node[1], th0);
        let mut s_prev = 0.0;
        for (i, &s) in self.node_s.iter().enumerate() {
            if i > 0 {
                let sec = self.section_of_element(i - 1);
                let spec = &self.spec.sections[sec];
                let k = torques[sec].first().copied().unwrap_or(0.0) / spec.ei_nm2
                    + spec.rest_curvature_per_m;
                let ds = s - s_prev;
                let dth = k * ds;
                if dth.abs() < 1e-9 {
                    x += ds * (th + 0.5 * dth).cos();
                    y += ds * (th + 0.5 * dth).sin();
                } else {
                    x += ((th + dth).sin() - th.sin()) / k;
                    y += (th.cos() - (th + dth).cos()) / k;
                }
                th += dth;
            }
            s_prev = s;
            let node = E::straight_node(&[x, y], &[th.cos(), th.sin()]);
            q.extend(node.iter().take(nd));
        }
        q
    }

    /// Element holding arc coordinate `s` and the local coordinate `ξ` in it.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if `s` is not on the robot.
    pub fn locate(&self, name: &str, s: f64) -> Result<(usize, f64)> {
        let total = self.length();
        let tol = 1e-12 * total;
        if !s.is_finite() || s < -tol || s > total + tol {
            return Err(outside(name, s, total));
        }
        let n = self.elements.len();
        // first node with arc > s
        let e = self
            .node_s
            .partition_point(|&x| x <= s)
            .saturating_sub(1)
            .min(n - 1);
        let xi = ((s - self.node_s[e]) / self.elements[e].length()).clamp(0.0, 1.0);
        Ok((e, xi))
    }

    /// Position `r(s)` of the backbone at arc coordinate `s` (m).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] if `s` is off the robot,
    /// [`Error::DimensionMismatch`] if `q` does not have `n_q` entries.
    pub fn position_at(&self, q: &[f64], s: f64) -> Result<Vec<f64>> {
        check_len("q", self.n_q(), q.len())?;
        let p = self.arc_point("s_m", s)?;
        let mut r = vec![0.0; E::DIM];
        p.value_into(q, &mut r)?;
        Ok(r)
    }

    /// The element, `ξ` and Hermite weights at arc coordinate `s` (m): the
    /// interpolation of any cable field (`q`, `F`) there, by
    /// [`ArcPoint::value_into`] and [`ArcPoint::slope_into`].
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `name` if `s` is not on the robot.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]).build_planar()?;
    /// let p = robot.arc_point("marker.s_m", 0.1)?;
    /// let mut t = [0.0; 2];
    /// p.slope_into(&robot.reference_configuration(), &mut t)?;
    /// assert!((t[0] - 1.0).abs() < 1e-14 && t[1].abs() < 1e-14);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn arc_point(&self, name: &str, s: f64) -> Result<ArcPoint> {
        let (e, xi) = self.locate(name, s)?;
        Ok(ArcPoint::new(e, xi, self.elements[e].length()))
    }

    /// The matrix `∫ Sᵀ S dX` over the whole robot (`n_q × n_q`, banded): the
    /// map `J_QF` from load parameters `F` to generalized forces (23) and the
    /// penalty matrix `B` of (26).
    pub fn load_gram(&self) -> &BandedMatrix {
        &self.gram
    }

    /// Generalized self-weight over all coordinates (N).
    pub fn gravity_force(&self) -> &[f64] {
        &self.gravity_force
    }

    /// Checks that `loads` fit this robot.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes, [`Error::InvalidParameter`]
    /// for non-finite values, points off the robot, moments at the clamped
    /// base, and pressures outside their bounds; [`Error::IndexOutOfRange`]
    /// for moments beyond the tip node.
    pub fn validate_loads(&self, loads: &Loads) -> Result<()> {
        let d = E::DIM;
        self.check_load_structure(loads)?;
        check_all_finite("pressures_pa", &loads.pressures_pa)?;
        for (i, (p, c)) in loads.pressures_pa.iter().zip(&self.chambers).enumerate() {
            if *p < c.min || *p > c.max {
                return Err(Error::invalid(
                    format!("pressures_pa[{i}]"),
                    p,
                    format!("must lie in [{}, {}] Pa", c.min, c.max),
                ));
            }
        }
        if !loads.distributed_f.is_empty() {
            check_len("distributed_f", self.n_q(), loads.distributed_f.len())?;
            check_all_finite("distributed_f", &loads.distributed_f)?;
        }
        for (i, l) in loads.line_loads.iter().enumerate() {
            l.validate(&format!("line_loads[{i}]"), d)?;
        }
        for (i, p) in loads.point_forces.iter().enumerate() {
            check_len(&format!("point_forces[{i}].force_n"), d, p.force_n.len())?;
            check_all_finite(&format!("point_forces[{i}].force_n"), &p.force_n)?;
            self.locate(&format!("point_forces[{i}].s_m"), p.s_m)?;
        }
        for (i, m) in loads.node_moments.iter().enumerate() {
            check_all_finite(&format!("node_moments[{i}].moment_nm"), &m.moment_nm)?;
            if m.node == 0 {
                return Err(Error::invalid(
                    format!("node_moments[{i}].node"),
                    m.node,
                    "the clamped base takes no moment: must be a free node, >= 1",
                ));
            }
        }
        Ok(())
    }

    /// The checks of [`Robot::validate_loads`] that indexing depends on (the
    /// pressure count, the nodes and sizes of the moments), without the
    /// value checks: the solver evaluates scaled loads whose pressures may
    /// lie outside their bounds.
    fn check_load_structure(&self, loads: &Loads) -> Result<()> {
        check_len("pressures_pa", self.n_pressures(), loads.pressures_pa.len())?;
        // (names are formatted only for an error: this runs on every
        // residual and tangent)
        for (i, m) in loads.node_moments.iter().enumerate() {
            if m.moment_nm.len() != E::MOMENT_DIM {
                check_len(
                    &format!("node_moments[{i}].moment_nm"),
                    E::MOMENT_DIM,
                    m.moment_nm.len(),
                )?;
            }
            if m.node >= self.n_nodes() {
                check_index(&format!("node_moments[{i}].node"), m.node, self.n_nodes())?;
            }
        }
        Ok(())
    }

    /// The dead (configuration-independent) generalized forces over all
    /// coordinates: self-weight, line loads, point forces and `J_QF F` (N).
    ///
    /// # Errors
    /// As [`Robot::validate_loads`]; [`Error::NonFinite`] if the forces
    /// overflow.
    pub fn dead_force(&self, loads: &Loads) -> Result<Vec<f64>> {
        self.validate_loads(loads)?;
        let nd = E::NODE_DOFS;
        let mut f = self.gravity_force.clone();
        let total = self.length();
        for l in &loads.line_loads {
            for (e, el) in self.elements.iter().enumerate() {
                let le = el.length();
                for (xi, wt) in self.line_rule.iter() {
                    let w = l.at(self.node_s[e] + xi * le, total);
                    add_shape_force(el, xi, &w, wt * le, &mut f[e * nd..(e + 2) * nd]);
                }
            }
        }
        for p in &loads.point_forces {
            let (e, xi) = self.locate("s_m", p.s_m)?;
            add_shape_force(
                &self.elements[e],
                xi,
                &p.force_n,
                1.0,
                &mut f[e * nd..(e + 2) * nd],
            );
        }
        if !loads.distributed_f.is_empty() {
            let jf = self.apply_load_gram(&loads.distributed_f)?;
            f.iter_mut().zip(jf).for_each(|(a, b)| *a += b);
        }
        // finite inputs can still overflow (huge loads, a Gaussian narrower
        // than the floating-point range resolves)
        if f.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                context: "dead forces (loads too large or too narrow)".into(),
            });
        }
        Ok(f)
    }

    /// The section torques `M_s = Σ_c G_c P_c` (N·m), one `MOMENT_DIM` vector per section.
    pub fn section_torques(&self, pressures: &[f64]) -> Vec<Vec<f64>> {
        let mut m = vec![vec![0.0; E::MOMENT_DIM]; self.spec.sections.len()];
        for (c, p) in self.chambers.iter().zip(pressures) {
            for (mi, g) in m[c.section].iter_mut().zip(&c.gain) {
                *mi += g * p;
            }
        }
        m
    }

    /// Calls `f(node, moment)` for the node moments of the actuation (each
    /// section's torque at its last node, its opposite at its first, in
    /// section order) and then the known concentrated moments, without
    /// allocating. `loads` must have passed `check_load_structure`.
    fn for_each_node_moment(
        &self,
        loads: &Loads,
        mut f: impl FnMut(usize, &[f64]) -> Result<()>,
    ) -> Result<()> {
        const MAX_MOMENT_DIM: usize = 3;
        let md = E::MOMENT_DIM.min(MAX_MOMENT_DIM);
        if !loads.pressures_pa.is_empty() {
            for (s, &(a, b)) in self.section_nodes.iter().enumerate() {
                // M_s = Σ_c G_c P_c over the section's chambers, in order
                let mut m = [0.0; MAX_MOMENT_DIM];
                for (c, p) in self.chambers.iter().zip(&loads.pressures_pa) {
                    if c.section == s {
                        for (mi, g) in m.iter_mut().zip(&c.gain) {
                            *mi += g * p;
                        }
                    }
                }
                if m[..md].iter().all(|v| *v == 0.0) {
                    continue;
                }
                f(b, &m[..md])?;
                let neg = m.map(|v| -v);
                f(a, &neg[..md])?;
            }
        }
        for nm in &loads.node_moments {
            f(nm.node, &nm.moment_nm)?;
        }
        Ok(())
    }

    /// Generalized force `Q(q)` over the free coordinates (17): the dead
    /// forces `dead` (from [`Robot::dead_force`]), minus the elastic gradient,
    /// plus the actuation and the concentrated moments `∂W/∂q`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    pub fn residual(&self, q: &[f64], dead: &[f64], loads: &Loads) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.n_free()];
        self.residual_into(q, dead, loads, &mut out)?;
        Ok(out)
    }

    /// As [`Robot::residual`], into `out` (`n_free` entries).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    pub fn residual_into(
        &self,
        q: &[f64],
        dead: &[f64],
        loads: &Loads,
        out: &mut [f64],
    ) -> Result<()> {
        check_len("q", self.n_q(), q.len())?;
        check_len("dead force", self.n_q(), dead.len())?;
        check_len("residual", self.n_free(), out.len())?;
        self.check_load_structure(loads)?;
        self.assemble(q, Some((dead, out)), None, loads)
    }

    /// Tangent stiffness `K = −∂Q/∂q` over the free coordinates, banded with
    /// `kl = ku = 2 NODE_DOFS − 1`, written into `k` (resized if needed).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    pub fn tangent_into(&self, q: &[f64], loads: &Loads, k: &mut BandedMatrix) -> Result<()> {
        check_len("q", self.n_q(), q.len())?;
        self.check_load_structure(loads)?;
        self.assemble(q, None, Some(k), loads)
    }

    /// [`Robot::residual_into`] and [`Robot::tangent_into`] at the same `q`
    /// in one pass over the elements (a Newton step needs both).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    pub fn residual_and_tangent_into(
        &self,
        q: &[f64],
        dead: &[f64],
        loads: &Loads,
        out: &mut [f64],
        k: &mut BandedMatrix,
    ) -> Result<()> {
        check_len("q", self.n_q(), q.len())?;
        check_len("dead force", self.n_q(), dead.len())?;
        check_len("residual", self.n_free(), out.len())?;
        self.check_load_structure(loads)?;
        self.assemble(q, Some((dead, out)), Some(k), loads)
    }

    /// The assembly loop behind the residual and the tangent (sizes and
    /// load structure checked by the callers). Interior elements add their
    /// gradient and Hessian at a plain offset; the first element's base
    /// node maps through the clamp's free directions.
    fn assemble(
        &self,
        q: &[f64],
        mut residual: Option<(&[f64], &mut [f64])>,
        mut k: Option<&mut BandedMatrix>,
        loads: &Loads,
    ) -> Result<()> {
        let nd = E::NODE_DOFS;
        let nb = self.base_free.len();
        let edof = 2 * nd;
        if let Some((dead, out)) = residual.as_mut() {
            for (j, t) in self.base_free.iter().enumerate() {
                out[j] = t.iter().zip(&dead[..nd]).map(|(a, b)| a * b).sum();
            }
            out[nb..].copy_from_slice(&dead[nd..]);
        }
        if let Some(k) = k.as_mut() {
            let kb = 2 * nd - 1;
            if k.n() != self.n_free() || k.kl() != kb || k.ku() != kb {
                **k = BandedMatrix::zeros(self.n_free(), kb, kb);
            } else {
                k.fill_zero();
            }
        }
        let mut g = [0.0; MAX_EDOF];
        let mut h = vec![0.0; if k.is_some() { edof * edof } else { 0 }];
        for (e, el) in self.elements.iter().enumerate() {
            let qe = &q[e * nd..(e + 2) * nd];
            let g = &mut g[..edof];
            let h = &mut h[..];
            g.fill(0.0);
            match (residual.is_some(), k.is_some()) {
                (true, true) => {
                    h.fill(0.0);
                    el.add_energy_gradient_and_hessian(qe, g, h);
                }
                (true, false) => el.add_energy_gradient(qe, g),
                (false, true) => {
                    h.fill(0.0);
                    el.add_energy_hessian(qe, h);
                }
                (false, false) => {}
            }
            if e > 0 {
                // interior elements: a plain shift
                let off = e * nd - nd + nb;
                if let Some((_, out)) = residual.as_mut() {
                    for (o, gk) in out[off..off + edof].iter_mut().zip(g.iter()) {
                        *o -= gk;
                    }
                }
                if let Some(k) = k.as_mut() {
                    // off + edof <= n_free and edof - 1 <= kb: in the band
                    k.add_block_unchecked(off, edof, h);
                }
                continue;
            }
            if let Some((_, out)) = residual.as_mut() {
                self.scatter_force(0, g, -1.0, out);
            }
            if let Some(k) = k.as_mut() {
                self.scatter_stiffness(0, edof, h, 1.0, k);
            }
        }
        let mut mg = [0.0; MAX_EDOF];
        let mut mh = Vec::new();
        self.for_each_node_moment(loads, |node, m| {
            let mg = &mut mg[..nd];
            mh.resize(nd * nd, 0.0);
            let mh = &mut mh[..];
            mg.fill(0.0);
            mh.fill(0.0);
            E::add_moment_work(&self.base_node, &q[node * nd..(node + 1) * nd], m, mg, mh);
            if let Some((_, out)) = residual.as_mut() {
                self.scatter_force(node * nd, mg, 1.0, out);
            }
            if let Some(k) = k.as_mut() {
                self.scatter_stiffness(node * nd, nd, mh, -1.0, k);
            }
            Ok(())
        })
    }

    /// Adds `sign · Mᵀ g` for a vector `g` over the global coordinates
    /// `start ..` into the free-coordinate vector `out`.
    fn scatter_force(&self, start: usize, g: &[f64], sign: f64, out: &mut [f64]) {
        let nd = E::NODE_DOFS;
        let nb = self.base_free.len();
        for (k, gk) in g.iter().enumerate() {
            let gi = start + k;
            if gi >= nd {
                out[nb + gi - nd] += sign * gk;
            } else {
                for (j, t) in self.base_free.iter().enumerate() {
                    out[j] += sign * t[gi] * gk;
                }
            }
        }
    }

    /// Adds `sign · Mᵀ H M` for a `size × size` matrix `h` over the global
    /// coordinates `start ..` into the banded free-coordinate matrix `k`.
    fn scatter_stiffness(
        &self,
        start: usize,
        size: usize,
        h: &[f64],
        sign: f64,
        k: &mut BandedMatrix,
    ) {
        // at most NODE_DOFS base-free directions map one coordinate
        let mut mi = [(0usize, 0.0f64); MAX_EDOF];
        let mut mj = [(0usize, 0.0f64); MAX_EDOF];
        for a in 0..size {
            let na = self.dof_map_into(start + a, &mut mi);
            for b in 0..size {
                let nb = self.dof_map_into(start + b, &mut mj);
                for &(i, ci) in &mi[..na] {
                    for &(j, cj) in &mj[..nb] {
                        k.add(i, j, sign * ci * cj * h[a * size + b]);
                    }
                }
            }
        }
    }

    /// `∂Q/∂P` over the free coordinates: column `c` is the generalized force
    /// of chamber `c` per pascal, `G_c · ∂(θ_end − θ_start)/∂q` (row-major,
    /// `n_free × n_pressures`).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `q` has the wrong size.
    pub fn pressure_jacobian(&self, q: &[f64]) -> Result<Vec<f64>> {
        let nd = E::NODE_DOFS;
        check_len("q", self.n_q(), q.len())?;
        let np = self.n_pressures();
        let mut jac = vec![0.0; self.n_free() * np];
        let mut scratch = [0.0; MAX_EDOF * MAX_EDOF];
        let mut map = Vec::new();
        for (c, ch) in self.chambers.iter().enumerate() {
            let (a, b) = self.section_nodes[ch.section];
            for (node, sign) in [(b, 1.0), (a, -1.0)] {
                let m: Vec<f64> = ch.gain.iter().map(|g| sign * g).collect();
                let mut g = [0.0; MAX_EDOF];
                E::add_moment_work(
                    &self.base_node,
                    &q[node * nd..(node + 1) * nd],
                    &m,
                    &mut g[..nd],
                    &mut scratch[..nd * nd],
                );
                for (k, gk) in g[..nd].iter().enumerate() {
                    self.dof_map(node * nd + k, &mut map);
                    for &(i, ci) in &map {
                        jac[i * np + c] += ci * gk;
                    }
                }
            }
        }
        Ok(jac)
    }

    /// Elastic energy `U_E(q)` (J).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `q` has the wrong size.
    pub fn elastic_energy(&self, q: &[f64]) -> Result<f64> {
        let nd = E::NODE_DOFS;
        check_len("q", self.n_q(), q.len())?;
        Ok(self
            .elements
            .iter()
            .enumerate()
            .map(|(e, el)| el.energy(&q[e * nd..(e + 2) * nd]))
            .sum())
    }

    /// Change of the total potential `Π = U_E − W` from `from` to `to` (J):
    /// elastic energy, minus the work of the dead forces `dead` and of the
    /// actuation and concentrated moments. `Q = −∂Π/∂q`, so this is the merit
    /// function of the static solver's line search.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    pub fn potential_change(
        &self,
        from: &[f64],
        to: &[f64],
        dead: &[f64],
        loads: &Loads,
    ) -> Result<f64> {
        let nd = E::NODE_DOFS;
        check_len("q", self.n_q(), from.len())?;
        check_len("q", self.n_q(), to.len())?;
        check_len("dead force", self.n_q(), dead.len())?;
        self.check_load_structure(loads)?;
        let mut d = 0.0;
        for (e, el) in self.elements.iter().enumerate() {
            let r = e * nd..(e + 2) * nd;
            d += el.energy(&to[r.clone()]) - el.energy(&from[r]);
        }
        for i in nd..self.n_q() {
            d -= dead[i] * (to[i] - from[i]);
        }
        self.for_each_node_moment(loads, |node, m| {
            let r = node * nd..(node + 1) * nd;
            d -= E::moment_work_between(&self.base_node, &from[r.clone()], &to[r], m);
            Ok(())
        })?;
        Ok(d)
    }

    /// The elastic energy of every element at `q` into `out` (J; one entry
    /// per element), for [`Robot::potential_change_from`].
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `q` or `out` has the wrong size.
    pub fn element_energies_into(&self, q: &[f64], out: &mut [f64]) -> Result<()> {
        let nd = E::NODE_DOFS;
        check_len("q", self.n_q(), q.len())?;
        check_len("energies", self.elements.len(), out.len())?;
        for ((e, el), u) in self.elements.iter().enumerate().zip(out.iter_mut()) {
            *u = el.energy(&q[e * nd..(e + 2) * nd]);
        }
        Ok(())
    }

    /// [`Robot::potential_change`] with the element energies at `from`
    /// given ([`Robot::element_energies_into`]): a line search evaluates
    /// many trials from one point. The same arithmetic, term by term.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    pub fn potential_change_from(
        &self,
        from: &[f64],
        from_energies: &[f64],
        to: &[f64],
        dead: &[f64],
        loads: &Loads,
    ) -> Result<f64> {
        let nd = E::NODE_DOFS;
        check_len("q", self.n_q(), from.len())?;
        check_len("q", self.n_q(), to.len())?;
        check_len("energies", self.elements.len(), from_energies.len())?;
        check_len("dead force", self.n_q(), dead.len())?;
        self.check_load_structure(loads)?;
        let mut d = 0.0;
        for ((e, el), u0) in self.elements.iter().enumerate().zip(from_energies) {
            d += el.energy(&to[e * nd..(e + 2) * nd]) - u0;
        }
        for i in nd..self.n_q() {
            d -= dead[i] * (to[i] - from[i]);
        }
        self.for_each_node_moment(loads, |node, m| {
            let r = node * nd..(node + 1) * nd;
            d -= E::moment_work_between(&self.base_node, &from[r.clone()], &to[r], m);
            Ok(())
        })?;
        Ok(d)
    }

    /// The generalized force of the actuation and the concentrated moments,
    /// `∂W/∂q` over the free coordinates, into `out` (`n_free`; O(number of
    /// moments) besides clearing `out`).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    pub fn moment_force_into(&self, q: &[f64], loads: &Loads, out: &mut [f64]) -> Result<()> {
        let nd = E::NODE_DOFS;
        check_len("q", self.n_q(), q.len())?;
        check_len("out", self.n_free(), out.len())?;
        self.check_load_structure(loads)?;
        out.iter_mut().for_each(|v| *v = 0.0);
        let mut mg = [0.0; MAX_EDOF];
        let mut mh = vec![0.0; nd * nd];
        self.for_each_node_moment(loads, |node, m| {
            let mg = &mut mg[..nd];
            mg.fill(0.0);
            E::add_moment_work(
                &self.base_node,
                &q[node * nd..(node + 1) * nd],
                m,
                mg,
                &mut mh,
            );
            self.scatter_force(node * nd, mg, 1.0, out);
            Ok(())
        })
    }

    /// Node positions `r_i` (m), one `DIM` vector per node of `q` (a
    /// trailing partial node is ignored, so this never panics).
    pub fn node_positions(&self, q: &[f64]) -> Vec<Vec<f64>> {
        let nd = E::NODE_DOFS;
        q.chunks_exact(nd)
            .map(|c| c.iter().take(E::DIM).copied().collect())
            .collect()
    }
}

/// The unit base tangent of `base` in `d` dimensions (see [`Base`]).
fn base_direction(base: &Base, d: usize) -> Result<Vec<f64>> {
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

/// Adds `scale · S(ξ)ᵀ f` into the element vector `out` (cable layout).
fn add_shape_force<E: Element>(el: &E, xi: f64, f: &[f64], scale: f64, out: &mut [f64]) {
    let d = E::DIM;
    let s = el.shape(xi);
    for k in 0..4 {
        for i in 0..d {
            out[k * d + i] += scale * s[k] * f[i];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn robot(n: usize) -> Robot<PlanarCable> {
        let mut s1 = Section::uniform(0.12, 300.0, 0.025, n);
        s1.mass_per_length_kg_per_m = 0.15;
        s1.chambers = vec![Chamber {
            gain_nm_per_pa: vec![3e-6],
            pressure_min_pa: 0.0,
            pressure_max_pa: 1e5,
        }];
        let mut s2 = s1.clone();
        s2.ei_nm2 = 0.02;
        RobotSpec::new(vec![s1, s2]).build_planar().unwrap()
    }

    fn perturbed(r: &Robot<PlanarCable>, seed: u64) -> Vec<f64> {
        let mut q = r.reference_configuration();
        let mut s = seed;
        q[2] *= 1.003; // a stretched base
        for v in q.iter_mut().skip(4) {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            *v += 0.02 * (((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5);
        }
        q
    }

    /// The assembled tangent equals the central-difference Jacobian of
    /// `−Q` along every free coordinate (step 1e-7), to 1e-6 of its largest entry.
    fn assert_tangent_is_the_fd_jacobian(
        r: &Robot<PlanarCable>,
        q: &[f64],
        dead: &[f64],
        loads: &Loads,
    ) {
        let mut k = BandedMatrix::zeros(1, 0, 0);
        r.tangent_into(q, loads, &mut k).unwrap();
        let scale = k.max_abs();
        let h = 1e-7;
        for j in 0..r.n_free() {
            let mut du = vec![0.0; r.n_free()];
            du[j] = h;
            let dq = r.expand_step(&du).unwrap();
            let qp: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a + b).collect();
            let qm: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a - b).collect();
            let rp = r.residual(&qp, dead, loads).unwrap();
            let rm = r.residual(&qm, dead, loads).unwrap();
            for i in 0..r.n_free() {
                let fd = -(rp[i] - rm[i]) / (2.0 * h);
                assert!(
                    (fd - k.get(i, j)).abs() < 1e-6 * scale,
                    "({i},{j}) {fd} vs {}",
                    k.get(i, j)
                );
            }
        }
    }

    #[test]
    fn full_clamp_has_no_free_base_coordinate_and_a_consistent_tangent() {
        let mut spec = robot(2).spec().clone();
        spec.base.clamp = Clamp::Full;
        let r = spec.build_planar().unwrap();
        assert_eq!(r.n_base_free(), 0);
        assert_eq!(r.n_free(), r.n_q() - 4);
        let loads = Loads {
            pressures_pa: vec![3e4, 1e4],
            ..Loads::default()
        };
        let dead = r.dead_force(&loads).unwrap();
        assert_tangent_is_the_fd_jacobian(&r, &perturbed(&r, 9), &dead, &loads);
    }

    #[test]
    fn tangent_is_the_finite_difference_jacobian_of_the_residual() {
        let r = robot(3);
        let loads = Loads {
            pressures_pa: vec![4e4, 2e4],
            node_moments: vec![crate::loads::NodeMoment {
                node: 4,
                moment_nm: vec![0.01],
            }],
            ..Loads::default()
        };
        let dead = r.dead_force(&loads).unwrap();
        assert_tangent_is_the_fd_jacobian(&r, &perturbed(&r, 3), &dead, &loads);
    }

    #[test]
    fn pressure_jacobian_matches_finite_differences() {
        let r = robot(2);
        let q = perturbed(&r, 5);
        let jac = r.pressure_jacobian(&q).unwrap();
        let base = Loads {
            pressures_pa: vec![1e4, 1e4],
            ..Loads::default()
        };
        let dead = r.dead_force(&base).unwrap();
        for c in 0..2 {
            let mut lp = base.clone();
            let mut lm = base.clone();
            lp.pressures_pa[c] += 100.0;
            lm.pressures_pa[c] -= 100.0;
            let rp = r.residual(&q, &dead, &lp).unwrap();
            let rm = r.residual(&q, &dead, &lm).unwrap();
            for i in 0..r.n_free() {
                let fd = (rp[i] - rm[i]) / 200.0;
                assert!((fd - jac[i * 2 + c]).abs() < 1e-9, "{i} {c}");
            }
        }
    }

    #[test]
    fn gram_integrates_products_of_fields() {
        // F describing w = (1, 2) uniform: F_i = [1, 2, 0, 0]; q = straight line
        // r = (s, 0); then q·J F = ∫ r·w ds = ∫ s ds = L²/2.
        let r = robot(4);
        let n = r.n_nodes();
        let f: Vec<f64> = (0..n).flat_map(|_| [1.0, 2.0, 0.0, 0.0]).collect();
        let q = r.reference_configuration();
        let jf = r.load_gram().mul_vec(&f).unwrap();
        let work: f64 = q.iter().zip(&jf).map(|(a, b)| a * b).sum();
        let l = r.length();
        assert!((work - l * l / 2.0).abs() < 1e-14);
        // total force of a uniform load = w L in each component
        let fx: f64 = (0..n).map(|i| jf[4 * i]).sum();
        let fy: f64 = (0..n).map(|i| jf[4 * i + 1]).sum();
        assert!((fx - l).abs() < 1e-14 && (fy - 2.0 * l).abs() < 1e-14);
    }

    #[test]
    fn self_weight_sums_to_the_weight() {
        let r = robot(5);
        let g = r.gravity_force();
        let fy: f64 = (0..r.n_nodes()).map(|i| g[4 * i + 1]).sum();
        assert!((fy - (-9.81 * 0.15 * 0.24)).abs() < 1e-14);
    }

    #[test]
    fn locate_finds_the_element() {
        let r = robot(2);
        assert_eq!(r.locate("s", 0.0).unwrap(), (0, 0.0));
        let (e, xi) = r.locate("s", 0.24).unwrap();
        assert_eq!(e, 3);
        assert!((xi - 1.0).abs() < 1e-12);
        let (e, xi) = r.locate("s", 0.09).unwrap();
        assert_eq!(e, 1);
        assert!((xi - 0.5).abs() < 1e-12);
        assert!(r.locate("s", 0.3).is_err());
    }

    #[test]
    fn fused_and_cached_kernels_equal_the_plain_ones() {
        let r = robot(3);
        let loads = Loads {
            pressures_pa: vec![4e4, 2e4],
            node_moments: vec![crate::loads::NodeMoment {
                node: 4,
                moment_nm: vec![0.01],
            }],
            ..Loads::default()
        };
        let dead = r.dead_force(&loads).unwrap();
        let q = perturbed(&r, 11);
        // residual and tangent in one pass: bit for bit the separate ones
        let (mut r1, mut r2) = (vec![0.0; r.n_free()], vec![0.0; r.n_free()]);
        let mut k1 = BandedMatrix::zeros(1, 0, 0);
        let mut k2 = BandedMatrix::zeros(1, 0, 0);
        r.residual_into(&q, &dead, &loads, &mut r1).unwrap();
        r.tangent_into(&q, &loads, &mut k1).unwrap();
        r.residual_and_tangent_into(&q, &dead, &loads, &mut r2, &mut k2)
            .unwrap();
        assert_eq!(r1, r2);
        assert_eq!(k1, k2);
        assert!(k1.is_symmetric());
        // the element-wise Gram product against the banded one
        let f: Vec<f64> = (0..r.n_q()).map(|i| (i as f64 * 0.37).sin()).collect();
        let a = r.apply_load_gram(&f).unwrap();
        let b = r.load_gram().mul_vec(&f).unwrap();
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() <= 1e-15 * (1.0 + y.abs()));
        }
        // the potential change from cached energies: the same number
        let to = perturbed(&r, 12);
        let mut u = vec![0.0; r.n_elements()];
        r.element_energies_into(&q, &mut u).unwrap();
        assert_eq!(
            r.potential_change(&q, &to, &dead, &loads).unwrap(),
            r.potential_change_from(&q, &u, &to, &dead, &loads).unwrap()
        );
        // the moment force: residual with and without the moments
        let mut m = vec![0.0; r.n_free()];
        r.moment_force_into(&q, &loads, &mut m).unwrap();
        let zero = vec![0.0; r.n_q()];
        let none = Loads {
            pressures_pa: vec![0.0, 0.0],
            ..Loads::default()
        };
        let (mut with, mut without) = (vec![0.0; r.n_free()], vec![0.0; r.n_free()]);
        r.residual_into(&q, &zero, &loads, &mut with).unwrap();
        r.residual_into(&q, &zero, &none, &mut without).unwrap();
        let scale = m.iter().fold(0.0f64, |x, v| x.max(v.abs()));
        assert!(scale > 0.0);
        for ((a, b), c) in m.iter().zip(&with).zip(&without) {
            assert!((a - (b - c)).abs() <= 1e-9 * scale);
        }
        // and the allocation-free maps equal the allocating ones
        let du: Vec<f64> = (0..r.n_free()).map(|i| i as f64).collect();
        let mut dq = vec![0.0; r.n_q()];
        r.expand_step_into(&du, &mut dq).unwrap();
        assert_eq!(dq, r.expand_step(&du).unwrap());
        let mut uu = vec![0.0; r.n_free()];
        r.restrict_into(&f, &mut uu).unwrap();
        assert_eq!(uu, r.restrict(&f).unwrap());
    }
}
