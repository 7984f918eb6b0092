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

use nalgebra::DMatrix;

use crate::element::Element;
use crate::error::{Result, check_len};
use crate::linsolve::BandedMatrix;
use crate::quadrature::GaussRule;

pub use super::section::{Chamber, Section};

mod arc_loads;
mod build;
mod follower;
mod forces;
mod geometry;

/// The largest number of elements a robot (or all rods of a structure) may
/// have; larger requests are refused before anything is allocated, with an
/// error naming the field and this limit. It is the one element limit of
/// every entry point: a scene (and `softrod` on the command line), a
/// [`crate::assembly::RobotSpec`], a structure, and so the static solver and
/// the estimator, which only take built robots. 2048 is the largest mesh
/// the static solver and the estimator are measured on (cold solves of the
/// reference cases and hard loads up to 2000 elements,
/// `benches/statics_scaling.rs`; the estimator's warm step up to 2000). Above
/// it nothing is known to converge in a bounded time (an estimate at 10 000
/// elements failed its line search after 20 s, one at 150 000 did not end),
/// so larger meshes are refused up front rather than left to hang. (A
/// section that fits alone but not with the sections before it is refused
/// with the room left, `MAX_ELEMENTS` minus those sections' elements.)
///
/// # Example
/// ```
/// use softrod::assembly::{RobotSpec, Section, MAX_ELEMENTS};
/// let too_many = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, MAX_ELEMENTS + 1)]);
/// let e = too_many.build_planar().unwrap_err();
/// assert!(e.to_string().contains(&MAX_ELEMENTS.to_string()));
/// ```
pub const MAX_ELEMENTS: usize = 2048;
/// Largest element dof count any element type has (full 3-D ANCF: 24).
pub(crate) const MAX_EDOF: usize = 24;

/// Longest section a rod may have (m). Far beyond any soft robot; a length
/// above it is a unit mistake or a value that can only overflow.
pub const MAX_SECTION_LENGTH_M: f64 = 1e6;

/// Largest ratio of the longest to the shortest section of a rod. The
/// tolerances on arc positions are relative to the rod's length; beyond this
/// ratio they cannot tell positions on the shortest section apart.
pub const MAX_SECTION_LENGTH_RATIO: f64 = 1e6;

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
    /// Elastic energy `U_E(q)` (J).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`](crate::Error::DimensionMismatch) if `q` has the wrong size.
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
    /// [`Error::DimensionMismatch`](crate::Error::DimensionMismatch) if `q` or `out` has the wrong size.
    pub fn element_energies_into(&self, q: &[f64], out: &mut [f64]) -> Result<()> {
        let nd = E::NODE_DOFS;
        check_len("q", self.n_q(), q.len())?;
        check_len("energies", self.elements.len(), out.len())?;
        for ((e, el), u) in self.elements.iter().enumerate().zip(out.iter_mut()) {
            *u = el.energy(&q[e * nd..(e + 2) * nd]);
        }
        Ok(())
    }
    /// Node positions `r_i` (m): a `DIM × nodes` matrix, column `i` the
    /// position of node `i` of `q` (a trailing partial node is ignored, so
    /// this never panics); as [`crate::assembly::Robot::node_positions`].
    pub fn node_positions(&self, q: &[f64]) -> DMatrix<f64> {
        let nd = E::NODE_DOFS;
        let nodes = q.len() / nd;
        DMatrix::from_fn(E::DIM, nodes, |i, n| q[n * nd + i])
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
