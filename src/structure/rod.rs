//! A rod: a chain of cable elements in its own coordinates, without its
//! boundary. Its sections (stiffness, weight, discretization, chambers), its
//! elastic energy, self-weight and known loads, the distributed-load matrix
//! `J_QF = B = ∫ Sᵀ S dX` (22), (23), (26), and the pneumatic actuation as
//! end torques of each section (18), `W_A = Σ_s M_s · (θ_end(s) − θ_start(s))`,
//! `M_s = G_s P`.
//!
//! Layout: node-major, `q = [q_0; q_1; …; q_N]`, `NODE_DOFS` numbers per
//! node, node 0 at the rod's start. What holds the rod (a clamp, a joint to
//! a rigid body) is not the rod's business: a [`crate::assembly::Robot`] is
//! a rod clamped at its start, a [`super::Structure`] places several rods
//! and rigid bodies by its [`super::DofMap`].

use crate::element::{ArcPoint, Element};
use crate::error::{
    check_all_finite, check_at_most, check_finite, check_index, check_len, check_positive, Error,
    Result,
};
use crate::linsolve::BandedMatrix;
use crate::loads::{outside, Loads};
use crate::quadrature::GaussRule;

pub use super::section::{Chamber, Section};

mod arc_loads;

/// The largest number of elements a robot (or all rods of a structure) may
/// have; larger requests are refused before anything is allocated.
pub const MAX_ELEMENTS: usize = 200_000;
/// Largest element dof count any element type has (full 3-D ANCF: 24).
pub(crate) const MAX_EDOF: usize = 24;

/// Longest section a rod may have (m). Far beyond any soft robot; a length
/// above it is a unit mistake or a value that can only overflow.
pub const MAX_SECTION_LENGTH_M: f64 = 1e6;

/// Largest ratio of the longest to the shortest section of a rod. The
/// tolerances on arc positions are relative to the rod's length; beyond this
/// ratio they cannot tell positions on the shortest section apart.
pub const MAX_SECTION_LENGTH_RATIO: f64 = 1e6;

/// Refuses a section longer than [`MAX_SECTION_LENGTH_M`] and sections whose
/// lengths differ by more than [`MAX_SECTION_LENGTH_RATIO`], naming the
/// longest (lengths already checked finite and positive).
fn check_section_lengths(path: &str, sections: &[Section]) -> Result<()> {
    let (mut long, mut short) = (0, 0);
    for (i, s) in sections.iter().enumerate() {
        if s.length_m > sections[long].length_m {
            long = i;
        }
        if s.length_m < sections[short].length_m {
            short = i;
        }
    }
    let Some(l) = sections.get(long).map(|s| s.length_m) else {
        return Ok(());
    };
    let name = format!("{path}.sections[{long}].length_m");
    if l > MAX_SECTION_LENGTH_M {
        return Err(Error::invalid(
            name,
            l,
            format!("must be at most {MAX_SECTION_LENGTH_M:e} m (lengths are in m)"),
        ));
    }
    let shortest = sections[short].length_m;
    if l > MAX_SECTION_LENGTH_RATIO * shortest {
        // name the one farther from the metre scale; mention the other
        let (bad, other) = if l.ln().abs() >= shortest.ln().abs() {
            (long, short)
        } else {
            (short, long)
        };
        return Err(Error::invalid(
            format!("{path}.sections[{bad}].length_m"),
            sections[bad].length_m,
            format!(
                "differs from `{path}.sections[{other}].length_m` = {:e} m by more than a factor \
                 {MAX_SECTION_LENGTH_RATIO:e}: arc positions on the shorter section cannot be resolved",
                sections[other].length_m
            ),
        ));
    }
    Ok(())
}

/// A flattened chamber: section index, gain, bounds.
#[derive(Debug, Clone)]
pub(crate) struct ChamberRef {
    pub(crate) section: usize,
    pub(crate) gain: Vec<f64>,
    pub(crate) min: f64,
    pub(crate) max: f64,
}

/// A chain of elements of type `E` along one backbone, in its own
/// coordinates (node-major, node 0 at the start).
///
/// # Example
/// ```
/// use softrod::assembly::Section;
/// use softrod::element::PlanarCable;
/// use softrod::structure::Rod;
/// let mut s = Section::uniform(0.2, 300.0, 0.025, 4);
/// s.mass_per_length_kg_per_m = 0.1;
/// let rod = Rod::new(&[s], &[0.0, -9.81], 5, 5, "rod", |s, le, ax, be| {
///     PlanarCable::with_rules(le, s.ea_n, s.ei_nm2, s.rest_curvature_per_m, ax, be)
/// }).unwrap();
/// assert_eq!((rod.n_nodes(), rod.n_q()), (5, 20));
/// // the self-weight's generalized forces add up to the weight
/// let fy: f64 = rod.gravity_force().iter().skip(1).step_by(4).sum();
/// assert!((fy + 0.1 * 0.2 * 9.81).abs() < 1e-15);
/// ```
#[derive(Debug, Clone)]
pub struct Rod<E: Element> {
    sections: Vec<Section>,
    gravity: Vec<f64>,
    elements: Vec<E>,
    node_s: Vec<f64>,
    section_nodes: Vec<(usize, usize)>,
    gravity_force: Vec<f64>,
    chambers: Vec<ChamberRef>,
    gram: BandedMatrix,
    /// Each element's `∫ s_k s_l dX` (4 × 4 over the node slots), the
    /// blocks `gram` is assembled from (applied element by element).
    elem_gram: Vec<[[f64; 4]; 4]>,
    line_rule: GaussRule,
}

impl<E: Element> Rod<E> {
    /// The checks of [`Rod::new`] that bound what it allocates: at least one
    /// section, an element type the assembly can hold, at most
    /// [`MAX_ELEMENTS`] elements. Returns the number of elements.
    pub(crate) fn check_layout(sections: &[Section], path: &str) -> Result<usize> {
        let d = E::DIM;
        let nd = E::NODE_DOFS;
        if sections.is_empty() {
            return Err(Error::invalid(
                format!("{path}.sections"),
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
        for (i, s) in sections.iter().enumerate() {
            // `total <= MAX_ELEMENTS` here, so the subtraction cannot underflow
            check_at_most(
                &format!("{path}.sections[{i}].elements"),
                s.elements,
                MAX_ELEMENTS - total,
            )?;
            total += s.elements;
        }
        Ok(total)
    }

    /// All checks of [`Rod::new`], without building anything: returns the
    /// number of elements.
    pub(crate) fn check_sections(
        sections: &[Section],
        gravity_m_per_s2: &[f64],
        axial_gauss_points: usize,
        bending_gauss_points: usize,
        path: &str,
    ) -> Result<usize> {
        let d = E::DIM;
        let total = Self::check_layout(sections, path)?;
        check_len("gravity_m_per_s2", d, gravity_m_per_s2.len())?;
        check_all_finite("gravity_m_per_s2", gravity_m_per_s2)?;
        for (name, n) in [
            (format!("{path}.axial_gauss_points"), axial_gauss_points),
            (format!("{path}.bending_gauss_points"), bending_gauss_points),
        ] {
            if n == 0 {
                return Err(Error::invalid(name, n, "must be >= 1"));
            }
            check_at_most(&name, n, crate::quadrature::MAX_POINTS)?;
        }
        for (i, s) in sections.iter().enumerate() {
            let p = |f: &str| format!("{path}.sections[{i}].{f}");
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
                let pc = |f: &str| format!("{path}.sections[{i}].chambers[{c}].{f}");
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
                        format!(
                            "must be >= `{}` = {}: one of the two is wrong",
                            pc("pressure_min_pa"),
                            ch.pressure_min_pa
                        ),
                    ));
                }
            }
        }
        check_section_lengths(path, sections)?;
        Ok(total)
    }

    /// Validates the sections and builds the rod; `make` builds one element
    /// of a section from `(section, element length, axial points, bending
    /// points)`. Field names start with `path` (`robot` gives
    /// `robot.sections[1].ei_nm2`); gravity is `gravity_m_per_s2` (m/s²).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field at fault for no
    /// sections, zero elements, non-positive lengths or stiffnesses,
    /// negative mass, non-finite numbers, inverted pressure bounds, Gauss
    /// rules of no points, or an element type whose constants do not fit;
    /// [`Error::TooLarge`] for more than [`MAX_ELEMENTS`] elements or Gauss
    /// rules above [`crate::quadrature::MAX_POINTS`] points (both refused
    /// before anything proportional is allocated);
    /// [`Error::DimensionMismatch`] for vectors of the wrong size. Errors of
    /// `make` come back with the section's path prefixed to the field name.
    pub fn new(
        sections: &[Section],
        gravity_m_per_s2: &[f64],
        axial_gauss_points: usize,
        bending_gauss_points: usize,
        path: &str,
        make: impl Fn(&Section, f64, usize, usize) -> Result<E>,
    ) -> Result<Self> {
        let nd = E::NODE_DOFS;
        let total = Self::check_sections(
            sections,
            gravity_m_per_s2,
            axial_gauss_points,
            bending_gauss_points,
            path,
        )?;
        let chambers: Vec<ChamberRef> = sections
            .iter()
            .enumerate()
            .flat_map(|(i, s)| {
                s.chambers.iter().map(move |ch| ChamberRef {
                    section: i,
                    gain: ch.gain_nm_per_pa.clone(),
                    min: ch.pressure_min_pa,
                    max: ch.pressure_max_pa,
                })
            })
            .collect();
        // elements and nodes
        let mut elements = Vec::with_capacity(total);
        let mut node_s = Vec::with_capacity(total + 1);
        let mut section_nodes = Vec::with_capacity(sections.len());
        node_s.push(0.0);
        let mut s0 = 0.0;
        for (i, sec) in sections.iter().enumerate() {
            let le = sec.length_m / sec.elements as f64;
            let start = node_s.len() - 1;
            let proto = make(sec, le, axial_gauss_points, bending_gauss_points)
                .map_err(|e| e.with_prefix(&format!("{path}.sections[{i}].")))?;
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
        let n_q = node_s.len() * nd;
        let kb = 2 * nd - 1;
        let line_rule = GaussRule::new(5)?;
        let mut rod = Rod {
            sections: sections.to_vec(),
            gravity: gravity_m_per_s2.to_vec(),
            elements,
            node_s,
            section_nodes,
            gravity_force: vec![0.0; n_q],
            chambers,
            gram: BandedMatrix::zeros(n_q, kb, kb),
            elem_gram: Vec::new(),
            line_rule,
        };
        rod.assemble_gram();
        // self-weight: uniform line load m g per section
        let mut gravity = vec![0.0; n_q];
        for (e, el) in rod.elements.iter().enumerate() {
            let m = rod.sections[rod.section_of_element(e)].mass_per_length_kg_per_m;
            if m == 0.0 {
                continue;
            }
            let w: Vec<f64> = rod.gravity.iter().map(|g| m * g).collect();
            for (xi, wt) in rod.line_rule.iter() {
                add_shape_force(
                    el,
                    xi,
                    &w,
                    wt * el.length(),
                    &mut gravity[e * nd..(e + 2) * nd],
                );
            }
        }
        rod.gravity_force = gravity;
        Ok(rod)
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
                        self.gram
                            .add(e * nd + slot::<E>(k) + i, e * nd + slot::<E>(l) + i, *mkl);
                    }
                }
            }
            blocks.push(m);
        }
        self.elem_gram = blocks;
    }
    /// `J_QF F = ∫ Sᵀ S dX F` ([`Rod::load_gram`] times `f`) into `out`,
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
                    let v: f64 = (0..4).map(|l| m[k][l] * f[e * nd + slot::<E>(l) + i]).sum();
                    out[e * nd + slot::<E>(k) + i] += v;
                }
            }
        }
        Ok(())
    }
    /// As [`Rod::apply_load_gram_into`], into a new vector.
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
    /// The sections, start to end.
    pub fn sections(&self) -> &[Section] {
        &self.sections
    }
    /// Gravity (m/s²).
    pub fn gravity(&self) -> &[f64] {
        &self.gravity
    }
    /// The chambers, flattened in section order.
    pub(crate) fn chamber_refs(&self) -> &[ChamberRef] {
        &self.chambers
    }

    /// The stress-free straight configuration from the start node at
    /// `position` (m) along the unit tangent `direction` (exact equilibrium
    /// without loads, actuation and rest curvature). Entries missing from
    /// `position` or `direction` count as 0.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::element::PlanarCable;
    /// use softrod::structure::Rod;
    /// let rod = Rod::new(&[Section::uniform(0.2, 300.0, 0.025, 4)], &[0.0, 0.0], 5, 5, "rod",
    ///     |s, le, ax, be| PlanarCable::with_rules(le, s.ea_n, s.ei_nm2, 0.0, ax, be)).unwrap();
    /// let q = rod.straight_configuration(&[1.0, 0.0], &[0.0, 1.0]);
    /// assert_eq!(&q[16..], &[1.0, 0.2, 0.0, 1.0]);
    /// assert!(rod.elastic_energy(&q).unwrap() < 1e-20);
    /// ```
    pub fn straight_configuration(&self, position: &[f64], direction: &[f64]) -> Vec<f64> {
        let d = E::DIM;
        let nd = E::NODE_DOFS;
        let mut q = Vec::with_capacity(self.n_q());
        let at = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(0.0);
        let dir: Vec<f64> = (0..d).map(|i| at(direction, i)).collect();
        for &s in &self.node_s {
            let p: Vec<f64> = (0..d).map(|i| at(position, i) + s * dir[i]).collect();
            let node = E::straight_node(&p, &dir);
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
        // the Hermite slots by offset (as ArcPoint::value_into for a cable)
        let base = p.element * E::NODE_DOFS;
        Ok((0..E::DIM)
            .map(|i| {
                (0..4)
                    .map(|k| p.values[k] * q[base + slot::<E>(k) + i])
                    .sum()
            })
            .collect())
    }

    /// The element, `ξ` and Hermite weights at arc coordinate `s` (m): the
    /// interpolation of any cable field (`q`, `F`) there, by
    /// [`ArcPoint::value_into`] and [`ArcPoint::slope_into`].
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `name` if `s` is not on the rod.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::element::PlanarCable;
    /// use softrod::structure::Rod;
    /// let rod = Rod::new(&[Section::uniform(0.2, 300.0, 0.025, 4)], &[0.0, 0.0], 5, 5, "rod",
    ///     |s, le, ax, be| PlanarCable::with_rules(le, s.ea_n, s.ei_nm2, 0.0, ax, be)).unwrap();
    /// let q = rod.straight_configuration(&[0.0, 0.0], &[1.0, 0.0]);
    /// let mut r = [0.0; 2];
    /// rod.arc_point("s_m", 0.13).unwrap().value_into(&q, &mut r).unwrap();
    /// assert!((r[0] - 0.13).abs() < 1e-15);
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
    /// for non-finite values, points off the rod and pressures outside their
    /// bounds; [`Error::IndexOutOfRange`] for moments beyond the last node.
    pub fn validate_loads(&self, loads: &Loads) -> Result<()> {
        self.validate_all_loads(loads, false)
    }

    /// [`Rod::validate_loads`] for a rod of a [`super::Structure`],
    /// refusing moments at node 0 if `clamped_start` (a clamp takes them:
    /// they are a user's mistake). A structure does not assemble moments at
    /// arc positions yet: `point_moments` are refused, not ignored.
    pub(crate) fn validate_loads_with(&self, loads: &Loads, clamped_start: bool) -> Result<()> {
        self.validate_all_loads(loads, clamped_start)?;
        if !loads.point_moments.is_empty() {
            return Err(Error::invalid(
                "point_moments",
                format!("{} moments", loads.point_moments.len()),
                "moments at arc positions are assembled on a robot only, not yet in a structure: \
                 use node_moments",
            ));
        }
        Ok(())
    }

    /// [`Rod::validate_loads`] for the rod of a clamped
    /// [`crate::assembly::Robot`]: moments at the base refused.
    pub(crate) fn validate_robot_loads(&self, loads: &Loads) -> Result<()> {
        self.validate_all_loads(loads, true)
    }

    fn validate_all_loads(&self, loads: &Loads, clamped_start: bool) -> Result<()> {
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
            l.check_on_robot(&format!("line_loads[{i}]"), self.length())?;
        }
        for (i, p) in loads.point_forces.iter().enumerate() {
            check_len(&format!("point_forces[{i}].force_n"), d, p.force_n.len())?;
            check_all_finite(&format!("point_forces[{i}].force_n"), &p.force_n)?;
            self.locate(&format!("point_forces[{i}].s_m"), p.s_m)?;
        }
        for (i, m) in loads.node_moments.iter().enumerate() {
            check_all_finite(&format!("node_moments[{i}].moment_nm"), &m.moment_nm)?;
            if clamped_start && m.node == 0 {
                return Err(Error::invalid(
                    format!("node_moments[{i}].node"),
                    m.node,
                    "the clamped base takes no moment: must be a free node, >= 1",
                ));
            }
        }
        self.validate_point_moments(loads, clamped_start)
    }
    /// The checks of [`Rod::validate_loads`] that indexing depends on (the
    /// pressure count, the nodes and sizes of the moments), without the
    /// value checks: the solver evaluates scaled loads whose pressures may
    /// lie outside their bounds.
    pub(crate) fn check_load_structure(&self, loads: &Loads) -> Result<()> {
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
        self.check_point_moment_structure(loads)
    }
    /// The dead (configuration-independent) generalized forces over all
    /// coordinates: self-weight, line loads, point forces and `J_QF F` (N).
    ///
    /// # Errors
    /// As [`Rod::validate_loads`]; [`Error::NonFinite`] if the forces
    /// overflow.
    pub fn dead_force(&self, loads: &Loads) -> Result<Vec<f64>> {
        self.validate_loads(loads)?;
        let nd = E::NODE_DOFS;
        let mut f = self.gravity_force.clone();
        for l in &loads.line_loads {
            self.add_line_load(l, &mut f);
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
        let mut m = vec![vec![0.0; E::MOMENT_DIM]; self.sections.len()];
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
    pub(crate) fn for_each_node_moment(
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
    /// The elastic energy of every element at `q` into `out` (J; one entry
    /// per element), for [`crate::assembly::Robot::potential_change_from`].
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
    /// Node positions `r_i` (m), one `DIM` vector per node of `q` (a
    /// trailing partial node is ignored, so this never panics).
    pub fn node_positions(&self, q: &[f64]) -> Vec<Vec<f64>> {
        let nd = E::NODE_DOFS;
        q.chunks_exact(nd)
            .map(|c| c.iter().take(E::DIM).copied().collect())
            .collect()
    }
}

/// Offset in the element coordinates of the centreline's Hermite slot `k`
/// (`r_1, r_1', r_2, r_2'`): node `k / 2`, position or first gradient. For
/// a cable (`NODE_DOFS = 2 DIM`) this is `k · DIM`; the full 3-D element
/// has further gradients after `r'` in each node.
fn slot<E: Element>(k: usize) -> usize {
    (k / 2) * E::NODE_DOFS + (k % 2) * E::DIM
}

/// Adds `scale · S(ξ)ᵀ f` into the element vector `out` (the centreline's
/// Hermite slots).
fn add_shape_force<E: Element>(el: &E, xi: f64, f: &[f64], scale: f64, out: &mut [f64]) {
    let d = E::DIM;
    let s = el.shape(xi);
    for k in 0..4 {
        for i in 0..d {
            out[slot::<E>(k) + i] += scale * s[k] * f[i];
        }
    }
}
