//! A multi-section robot clamped at its base: one [`Rod`] (its sections,
//! elastic energy, self-weight, known loads, the distributed-load matrix
//! `J_QF = B = ∫ Sᵀ S dX` (22), (23), (26), and the pneumatic actuation as
//! end torques of each section, `Q_A = ∂W_A/∂q` (18)) held by a clamp; the
//! residual and the banded tangent stiffness over its free coordinates.
//!
//! Layout: node-major, `q = [q_0; q_1; …; q_N]`, `NODE_DOFS` numbers per node.
//! Node 0 is the clamped base. A clamp fixes the base position and the base
//! direction but not the axial strain there: the literal clamp prescribes `r_0'`,
//! but prescribing `|r_0'| = 1` forbids stretch at the base and makes an
//! axial tip force stretch a 6-element cantilever 2 % too little (exudyn's
//! cantilevers likewise constrain only x, y and y' of the base). So the
//! unknowns of a static solve, the *free coordinates* `u`, are the base
//! stretch `b` (with `r_0' = (1 + b) t_0`) followed by `q_1 … q_N`: the
//! robot is a structure of one rod clamped at its base, and its
//! [`DofMap`] (one affine block `q_0 = q̄_0 + b t`, then free blocks) maps
//! between `u` and `q` ([`Robot::expand_step`], [`Robot::restrict`]).
//! Equilibrium (17) is `Q(F, q, P) = 0` with `Q = Q_F + Q_E + Q_A` and the
//! tangent stiffness is `K = −∂Q/∂q`.

use std::sync::Arc;

use crate::element::{ArcPoint, Element};
use crate::error::{Result, check_all_finite, check_finite, check_len};
use crate::linsolve::{BandedMatrix, SymmetricMatrix, SymmetricPattern};
use crate::loads::Loads;
use crate::structure::rod::MAX_EDOF;
use crate::structure::{BlockRule, DofMap, Rod};

mod angles;
mod cache;
mod coarse;
mod configuration;
mod follower;
mod known_loads;
mod model;
mod sites;
mod spec;
mod tangent;
mod typed;
mod validity;

pub use crate::structure::Clamp;
pub use crate::structure::rod::MAX_ELEMENTS;
pub use crate::structure::section::{Chamber, RestCurvatureProfile, Section};
use spec::base_direction;
pub use spec::{Base, RobotSpec};
pub use tangent::TangentTarget;
pub use validity::{MAX_AXIAL_STRAIN, ValidityWarning};

/// A robot assembled from elements of type `E`.
#[derive(Debug, Clone)]
pub struct Robot<E: Element> {
    spec: RobotSpec,
    /// The chain: elements, sections, loads in its own coordinates.
    rod: Rod<E>,
    base_node: Vec<f64>,
    /// The map from the free coordinates to all coordinates: the clamped
    /// base node an affine block (its stretch free), nodes 1 … N free.
    dofs: DofMap,
    /// The tangent's sparsity over the free coordinates: element `e` of
    /// the pattern is the chain's element `e`.
    pattern: Arc<SymmetricPattern>,
    /// Builds one element of a section (what [`Robot::new`] was given): a
    /// coarser mesh of the same robot is built with it.
    make: coarse::ElementMaker<E>,
    /// The rows of the clamp's map `T` over the first element's
    /// coordinates `0 .. 2 NODE_DOFS`: `(local coordinate, free coordinate,
    /// coefficient)` for each nonzero (the map is affine, so `T` is
    /// constant). The first element scatters its force and stiffness
    /// through them instead of asking the map for each entry (measured:
    /// a tenth of a 4-element static solve went there).
    first_rows: Vec<(usize, usize, f64)>,
    /// What the robot computes once and keeps (`cache.rs`).
    cache: Arc<cache::RobotCache<E>>,
}

impl<E: Element> Robot<E> {
    /// Validates `spec` and assembles the robot; `make` builds one element of
    /// a section from `(section, element length, axial points, bending points)`.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] naming the field at fault
    /// (`robot.sections[i].ei_nm2`, …) for empty robots, zero elements,
    /// non-positive lengths or stiffnesses, negative mass, non-finite
    /// numbers, inverted pressure bounds, or an element type whose constants
    /// do not fit the assembly; [`crate::Error::TooLarge`] for more than
    /// [`MAX_ELEMENTS`] elements or Gauss rules above
    /// [`crate::quadrature::MAX_POINTS`] points (both refused before anything
    /// proportional is allocated); [`crate::Error::DimensionMismatch`] for vectors
    /// of the wrong size. Errors of `make` are returned with the section's
    /// path prefixed to the field name.
    pub fn new(
        spec: RobotSpec,
        make: impl Fn(&Section, f64, usize, usize) -> Result<E> + Send + Sync + 'static,
    ) -> Result<Self> {
        Self::with_maker(spec, coarse::ElementMaker::new(make))
    }

    /// [`Robot::new`] with the element builder already kept.
    fn with_maker(spec: RobotSpec, make: coarse::ElementMaker<E>) -> Result<Self> {
        let d = E::DIM;
        let nd = E::NODE_DOFS;
        Rod::<E>::check_layout(&spec.sections, "robot")?;
        check_len("base.position_m", d, spec.base.position_m.len())?;
        check_all_finite("base.position_m", &spec.base.position_m)?;
        check_finite("base.angle_rad", spec.base.angle_rad)?;
        check_len("gravity_m_per_s2", d, spec.gravity_m_per_s2.len())?;
        check_all_finite("gravity_m_per_s2", &spec.gravity_m_per_s2)?;
        let rod = Rod::new(
            &spec.sections,
            &spec.gravity_m_per_s2,
            spec.axial_gauss_points,
            spec.bending_gauss_points,
            "robot",
            |s: &Section, le, ax, be| make.build(s, le, ax, be),
        )?;
        let dir = base_direction(&spec.base, d)?;
        let base_node: Vec<f64> = E::straight_node(&spec.base.position_m, &dir).data.into();
        check_len("element straight_node", nd, base_node.len())?;
        let base_free = match spec.base.clamp {
            Clamp::PositionAndDirection => {
                crate::element::direction_list(&E::clamp_free_directions(&base_node))
            }
            Clamp::Full => Vec::new(),
        };
        for t in &base_free {
            check_len("element clamp_free_directions", nd, t.len())?;
        }
        let mut blocks = Vec::with_capacity(rod.n_nodes());
        blocks.push(BlockRule::Affine {
            offset: base_node.clone(),
            directions: base_free,
        });
        blocks.resize(rod.n_nodes(), BlockRule::Free { len: nd });
        let dofs = DofMap::new(blocks).map_err(|e| e.with_prefix("element clamp: "))?;
        let pattern = Arc::new(tangent_pattern(&dofs, rod.n_elements())?);
        let first_rows = first_rows(&dofs, 2 * nd)?;
        Ok(Robot {
            spec,
            rod,
            base_node,
            dofs,
            pattern,
            make,
            first_rows,
            cache: cache::new_cache(),
        })
    }

    /// The sparsity pattern of the tangent stiffness over the free
    /// coordinates, from the element connectivity (element `e` couples the
    /// free coordinates of nodes `e` and `e + 1`): built once with the
    /// robot, what a [`crate::linsolve::TangentSolver`] analyzes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let p = robot.tangent_pattern();
    /// assert_eq!((p.n(), p.n_elements(), p.bandwidth()), (robot.n_free(), 4, 7));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn tangent_pattern(&self) -> &Arc<SymmetricPattern> {
        &self.pattern
    }

    /// The chain: elements, sections and loads in the robot's coordinates.
    pub fn rod(&self) -> &Rod<E> {
        &self.rod
    }

    /// `J_QF F = ∫ Sᵀ S dX F` ([`Robot::load_gram`] times `f`) into `out`,
    /// element by element (`O(n)`, no allocation); the same map as
    /// `load_gram().mul_vec(f)` up to round-off.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `f` or `out` does not have `n_q` entries.
    pub fn apply_load_gram_into(&self, f: &[f64], out: &mut [f64]) -> Result<()> {
        self.rod.apply_load_gram_into(f, out)
    }

    /// The robot's definition.
    pub fn spec(&self) -> &RobotSpec {
        &self.spec
    }
    /// Number of elements.
    pub fn n_elements(&self) -> usize {
        self.rod.n_elements()
    }
    /// Number of nodes (elements + 1).
    pub fn n_nodes(&self) -> usize {
        self.rod.n_nodes()
    }
    /// Number of coordinates `n_q`, base node included.
    pub fn n_q(&self) -> usize {
        self.rod.n_q()
    }
    /// Number of free coordinates: the base's free directions (its stretch)
    /// and the coordinates of nodes 1 … N.
    pub fn n_free(&self) -> usize {
        self.dofs.n_u()
    }

    /// Number of free coordinates at the clamped base (1 for a cable with
    /// [`Clamp::PositionAndDirection`], 0 with [`Clamp::Full`]).
    pub fn n_base_free(&self) -> usize {
        self.dofs.free(0).map_or(0, |r| r.len())
    }

    /// The map from the free coordinates to all coordinates (one affine
    /// block for the clamped base, then one free block per node): the
    /// single chain as a structure.
    pub fn dof_map(&self) -> &DofMap {
        &self.dofs
    }

    /// As [`Robot::expand_step`], into `dq` (`n_q` entries; no allocation).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `du` or `dq` has the wrong size.
    pub fn expand_step_into(&self, du: &[f64], dq: &mut [f64]) -> Result<()> {
        self.dofs.expand_into(&[], du, dq)
    }

    /// As [`Robot::restrict`], into `u` (`n_free` entries; no allocation).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `f` or `u` has the wrong size.
    pub fn restrict_into(&self, f: &[f64], u: &mut [f64]) -> Result<()> {
        self.dofs.restrict_into(&[], f, u)
    }

    /// Undeformed arc coordinate of every node (m).
    pub fn node_arc(&self) -> &[f64] {
        self.rod.node_arc()
    }
    /// Total undeformed length (m).
    pub fn length(&self) -> f64 {
        self.rod.length()
    }
    /// The elements, base to tip.
    pub fn elements(&self) -> &[E] {
        self.rod.elements()
    }
    /// First and last node of every section.
    pub fn section_nodes(&self) -> &[(usize, usize)] {
        self.rod.section_nodes()
    }
    /// Number of chambers (pressures).
    pub fn n_pressures(&self) -> usize {
        self.rod.n_pressures()
    }
    /// `(min, max)` bounds of every pressure (Pa).
    pub fn pressure_bounds(&self) -> Vec<(f64, f64)> {
        self.rod.pressure_bounds()
    }

    /// Index of the section that holds element `e`; an `e` beyond the last
    /// element gives the last section (never panics: a robot has at least
    /// one section).
    pub fn section_of_element(&self, e: usize) -> usize {
        self.rod.section_of_element(e)
    }

    /// The clamped base node's coordinates.
    pub fn base_node(&self) -> &[f64] {
        &self.base_node
    }

    /// Element holding arc coordinate `s` and the local coordinate `ξ` in it.
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] if `s` is not on the robot.
    pub fn locate(&self, name: &str, s: f64) -> Result<(usize, f64)> {
        self.rod.locate(name, s)
    }

    /// The element, `ξ` and Hermite weights at arc coordinate `s` (m): the
    /// interpolation of any cable field (`q`, `F`) there, by
    /// [`ArcPoint::value_into`] and [`ArcPoint::slope_into`].
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] named `name` if `s` is not on the robot.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]).build_planar()?;
    /// let p = robot.arc_point("marker.s_m", 0.1)?;
    /// let mut t = [0.0; 2];
    /// p.slope_into(robot.reference_configuration().as_slice(), &mut t)?;
    /// assert!((t[0] - 1.0).abs() < 1e-14 && t[1].abs() < 1e-14);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn arc_point(&self, name: &str, s: f64) -> Result<ArcPoint> {
        self.rod.arc_point(name, s)
    }

    /// The matrix `∫ Sᵀ S dX` over the whole robot (`n_q × n_q`, banded): the
    /// map `J_QF` from load parameters `F` to generalized forces (23) and the
    /// penalty matrix `B` of (26).
    pub fn load_gram(&self) -> &BandedMatrix {
        self.rod.load_gram()
    }

    /// Generalized self-weight over all coordinates (N), a view of the
    /// robot's own vector.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 4)]).build_planar()?;
    /// let g = nalgebra::DVector::from_column_slice(robot.gravity_force());
    /// assert_eq!(g.len(), robot.n_q());
    /// assert!(g.iter().all(|v| v.is_finite()));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn gravity_force(&self) -> &[f64] {
        self.rod.gravity_force()
    }

    /// Checks that `loads` fit this robot.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] for wrong sizes, [`crate::Error::InvalidParameter`]
    /// for non-finite values, points off the robot, moments at the clamped
    /// base, and pressures outside their bounds; [`crate::Error::IndexOutOfRange`]
    /// for moments beyond the tip node.
    pub fn validate_loads(&self, loads: &Loads) -> Result<()> {
        self.rod.validate_robot_loads(loads)
    }

    /// As [`Robot::residual`], into `out` (`n_free` entries).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] for wrong sizes.
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
        self.rod.check_load_structure(loads)?;
        self.assemble::<SymmetricMatrix>(q, Some((dead, out)), None, loads)
    }

    /// Tangent stiffness `K = −∂Q/∂q` over the free coordinates (with
    /// follower loads its symmetric part: see [`Robot::follower_stiffness`]), written
    /// into `k`: a [`crate::linsolve::SymmetricMatrix`] on
    /// [`Robot::tangent_pattern`] (put on it if it is on another), or a band
    /// matrix with `kl = ku = 2 NODE_DOFS − 1` (resized if needed).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::linsolve::SymmetricMatrix;
    /// use softrod::loads::Loads;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let mut k = SymmetricMatrix::zeros(robot.tangent_pattern().clone());
    /// robot.tangent_into(robot.reference_configuration().as_slice(), &Loads::default(), &mut k)?;
    /// assert!(k.get(1, 1) > 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn tangent_into<K: TangentTarget>(
        &self,
        q: &[f64],
        loads: &Loads,
        k: &mut K,
    ) -> Result<()> {
        check_len("q", self.n_q(), q.len())?;
        self.rod.check_load_structure(loads)?;
        self.assemble(q, None, Some(k), loads)
    }

    /// [`Robot::residual_into`] and [`Robot::tangent_into`] at the same `q`
    /// in one pass over the elements (a Newton step needs both).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] for wrong sizes.
    pub fn residual_and_tangent_into<K: TangentTarget>(
        &self,
        q: &[f64],
        dead: &[f64],
        loads: &Loads,
        out: &mut [f64],
        k: &mut K,
    ) -> Result<()> {
        check_len("q", self.n_q(), q.len())?;
        check_len("dead force", self.n_q(), dead.len())?;
        check_len("residual", self.n_free(), out.len())?;
        self.rod.check_load_structure(loads)?;
        self.assemble(q, Some((dead, out)), Some(k), loads)
    }

    /// The assembly loop behind the residual and the tangent (sizes and
    /// load structure checked by the callers): the elements
    /// ([`Robot::assemble_elements`]), then the loads' terms.
    fn assemble<K: TangentTarget>(
        &self,
        q: &[f64],
        mut residual: Option<(&[f64], &mut [f64])>,
        mut k: Option<&mut K>,
        loads: &Loads,
    ) -> Result<()> {
        let nd = E::NODE_DOFS;
        let edof = 2 * nd;
        if let Some((dead, out)) = residual.as_mut() {
            self.dofs.restrict_into(&[], dead, out)?;
        }
        if let Some(k) = k.as_mut() {
            k.reset(self.n_free(), 2 * nd - 1, &self.pattern);
        }
        // the elements' tangent at the reference configuration is kept
        // (the first Newton step of every cold solve of an unactuated robot)
        let kept = match k.as_mut() {
            Some(k) => self
                .reference_element_tangent(q)
                .is_some_and(|values| k.add_values(values)),
            None => false,
        };
        self.assemble_elements(
            q,
            residual.as_mut().map(|(_, out)| &mut **out),
            k.as_deref_mut(),
            kept,
        )?;
        let mut mg = [0.0; MAX_EDOF];
        let mut mh = Vec::new();
        self.rod.for_each_node_moment(loads, |node, m| {
            let mg = &mut mg[..nd];
            mh.resize(nd * nd, 0.0);
            let mh = &mut mh[..];
            mg.fill(0.0);
            mh.fill(0.0);
            E::add_moment_work(&self.base_node, &q[node * nd..(node + 1) * nd], m, mg, mh);
            if let Some((_, out)) = residual.as_mut() {
                self.scatter_force(node * nd, mg, 1.0, out)?;
            }
            if let Some(k) = k.as_mut() {
                self.scatter_stiffness(node * nd, nd, mh, -1.0, &mut **k)?;
            }
            Ok(())
        })?;
        // moments at arc positions: on the two nodes of their element
        let hessian = k.is_some();
        self.rod
            .for_each_point_moment(&self.base_node, q, loads, hessian, |e, g, h| {
                if let Some((_, out)) = residual.as_mut() {
                    self.scatter_force(e * nd, g, 1.0, out)?;
                }
                if let Some(k) = k.as_mut() {
                    self.scatter_stiffness(e * nd, edof, h, -1.0, &mut **k)?;
                }
                Ok(())
            })?;
        // follower loads: Q_e = m q_e; the symmetric part of −m to the
        // tangent (see follower::follower_stiffness for the rest)
        self.rod.for_each_follower_element(loads, |e, m| {
            if let Some((_, out)) = residual.as_mut() {
                let qe = &q[e * nd..(e + 2) * nd];
                let g: Vec<f64> = m
                    .chunks_exact(qe.len())
                    .map(|row| row.iter().zip(qe).map(|(a, b)| a * b).sum())
                    .collect();
                self.scatter_force(e * nd, &g, 1.0, out)?;
            }
            if let Some(k) = k.as_mut() {
                let sym = follower::symmetric_part(m);
                self.scatter_stiffness(e * nd, edof, &sym, -1.0, &mut **k)?;
            }
            Ok(())
        })
    }

    /// The elements' part of the assembly: `−∇U` added to `residual` and
    /// `∇²U` to `k` (already reset), element by element; interior elements
    /// at a plain offset, the first element's base node through the
    /// clamp's free directions. With `skip_hessian` (`k` already holds the
    /// elements' tangent) only the gradients are formed.
    fn assemble_elements<K: TangentTarget>(
        &self,
        q: &[f64],
        mut residual: Option<&mut [f64]>,
        mut k: Option<&mut K>,
        skip_hessian: bool,
    ) -> Result<()> {
        let nd = E::NODE_DOFS;
        let edof = 2 * nd;
        if skip_hessian {
            k = None;
        }
        if residual.is_none() && k.is_none() {
            return Ok(());
        }
        let mut g = [0.0; MAX_EDOF];
        let mut h = vec![0.0; if k.is_some() { edof * edof } else { 0 }];
        for (e, el) in self.rod.elements().iter().enumerate() {
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
            if let Some(off) = self.dofs.contiguous_free(e * nd, edof) {
                // elements between free nodes: a plain shift
                if let Some(out) = residual.as_mut() {
                    for (o, gk) in out[off..off + edof].iter_mut().zip(g.iter()) {
                        *o -= gk;
                    }
                }
                if let Some(k) = k.as_mut() {
                    k.add_chain_block(e, off, edof, h)?;
                }
                continue;
            }
            if let Some(out) = residual.as_mut() {
                self.scatter_force(e * nd, g, -1.0, out)?;
            }
            if let Some(k) = k.as_mut() {
                self.scatter_stiffness(e * nd, edof, h, 1.0, &mut **k)?;
            }
        }
        Ok(())
    }

    /// Adds `sign · Tᵀ g` for a vector `g` over the coordinates
    /// `start .. start + g.len()` into the free-coordinate vector `out`.
    fn scatter_force(&self, start: usize, g: &[f64], sign: f64, out: &mut [f64]) -> Result<()> {
        if start == 0 && g.len() == 2 * E::NODE_DOFS {
            for &(a, i, c) in &self.first_rows {
                out[i] += sign * c * g[a];
            }
            return Ok(());
        }
        let dofs = range_dofs(start, g.len());
        self.dofs
            .add_force(&[], &dofs[..g.len().min(MAX_EDOF)], g, sign, out)
    }

    /// Adds `sign · Tᵀ H T` for a `size × size` matrix `h` over the
    /// coordinates `start .. start + size` into the banded free-coordinate
    /// matrix `k`.
    fn scatter_stiffness<K: TangentTarget>(
        &self,
        start: usize,
        size: usize,
        h: &[f64],
        sign: f64,
        k: &mut K,
    ) -> Result<()> {
        if start == 0 && size == 2 * E::NODE_DOFS {
            check_len("h", size * size, h.len())?;
            for &(a, i, ca) in &self.first_rows {
                for &(b, j, cb) in &self.first_rows {
                    k.add(i, j, sign * ca * cb * h[a * size + b]);
                }
            }
            return Ok(());
        }
        let dofs = range_dofs(start, size);
        self.dofs
            .add_stiffness(&[], &dofs[..size.min(MAX_EDOF)], h, sign, k)
    }

    /// Elastic energy `U_E(q)` (J).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `q` has the wrong size.
    pub fn elastic_energy(&self, q: &[f64]) -> Result<f64> {
        self.rod.elastic_energy(q)
    }

    /// Change of the total potential `Π = U_E − W` from `from` to `to` (J):
    /// elastic energy, minus the work of the dead forces `dead` and of the
    /// actuation and concentrated moments. `Q = −∂Π/∂q`, so this is the merit
    /// function of the static solver's line search.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] for wrong sizes.
    pub fn potential_change(
        &self,
        from: &[f64],
        to: &[f64],
        dead: &[f64],
        loads: &Loads,
    ) -> Result<f64> {
        // the line search's kernel with the energies at `from` taken here:
        // the same arithmetic, term by term
        check_len("q", self.n_q(), from.len())?;
        let mut from_energies = vec![0.0; self.rod.n_elements()];
        self.element_energies_into(from, &mut from_energies)?;
        self.potential_change_from(from, &from_energies, to, dead, loads)
    }

    /// The elastic energy of every element at `q` into `out` (J; one entry
    /// per element), for [`Robot::potential_change_from`].
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `q` or `out` has the wrong size.
    pub fn element_energies_into(&self, q: &[f64], out: &mut [f64]) -> Result<()> {
        self.rod.element_energies_into(q, out)
    }

    /// [`Robot::potential_change`] with the element energies at `from`
    /// given ([`Robot::element_energies_into`]): a line search evaluates
    /// many trials from one point. The same arithmetic, term by term.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] for wrong sizes.
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
        check_len("energies", self.rod.n_elements(), from_energies.len())?;
        check_len("dead force", self.n_q(), dead.len())?;
        self.rod.check_load_structure(loads)?;
        let mut d = 0.0;
        for ((e, el), u0) in self.rod.elements().iter().enumerate().zip(from_energies) {
            d += el.energy(&to[e * nd..(e + 2) * nd]) - u0;
        }
        for i in nd..self.n_q() {
            d -= dead[i] * (to[i] - from[i]);
        }
        self.rod.for_each_node_moment(loads, |node, m| {
            let r = node * nd..(node + 1) * nd;
            d -= E::moment_work_between(&self.base_node, &from[r.clone()], &to[r], m);
            Ok(())
        })?;
        d -= self
            .rod
            .point_moment_work_between(&self.base_node, from, to, loads)?;
        d -= self.rod.follower_work_between(from, to, loads)?;
        Ok(d)
    }

    /// The generalized force of the actuation and the concentrated moments,
    /// `∂W/∂q` over the free coordinates, into `out` (`n_free`; O(number of
    /// moments) besides clearing `out`).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] for wrong sizes.
    pub fn moment_force_into(&self, q: &[f64], loads: &Loads, out: &mut [f64]) -> Result<()> {
        let nd = E::NODE_DOFS;
        check_len("q", self.n_q(), q.len())?;
        check_len("out", self.n_free(), out.len())?;
        self.rod.check_load_structure(loads)?;
        out.iter_mut().for_each(|v| *v = 0.0);
        let mut mg = [0.0; MAX_EDOF];
        let mut mh = vec![0.0; nd * nd];
        self.rod.for_each_node_moment(loads, |node, m| {
            let mg = &mut mg[..nd];
            mg.fill(0.0);
            E::add_moment_work(
                &self.base_node,
                &q[node * nd..(node + 1) * nd],
                m,
                mg,
                &mut mh,
            );
            self.scatter_force(node * nd, mg, 1.0, out)
        })?;
        self.rod
            .for_each_point_moment(&self.base_node, q, loads, false, |e, g, _| {
                self.scatter_force(e * nd, g, 1.0, out)
            })
    }
}

/// The tangent pattern of a chain of `n_elements` two-node elements whose
/// node `i` is block `i` of `dofs`: element `e` couples the free
/// coordinates of blocks `e` and `e + 1`, in order.
fn tangent_pattern(dofs: &DofMap, n_elements: usize) -> Result<SymmetricPattern> {
    let mut elements = Vec::with_capacity(n_elements);
    for e in 0..n_elements {
        let (Some(a), Some(b)) = (dofs.free(e), dofs.free(e + 1)) else {
            return Err(crate::Error::IndexOutOfRange {
                name: "element nodes".into(),
                index: e + 1,
                len: dofs.n_blocks(),
            });
        };
        elements.push(a.chain(b).collect::<Vec<usize>>());
    }
    SymmetricPattern::from_elements(dofs.n_u(), &elements)
}

/// The nonzero rows of `T` over the coordinates `0 .. len` of an affine
/// map (see `Robot::first_rows`): `Tᵀ e_a` for each unit vector `e_a`.
fn first_rows(dofs: &DofMap, len: usize) -> Result<Vec<(usize, usize, f64)>> {
    let mut rows = Vec::new();
    let mut f = vec![0.0; dofs.n_q()];
    let mut t = vec![0.0; dofs.n_u()];
    for a in 0..len.min(f.len()) {
        f[a] = 1.0;
        t.fill(0.0);
        dofs.restrict_into(&[], &f, &mut t)?;
        f[a] = 0.0;
        rows.extend(
            t.iter()
                .enumerate()
                .filter(|(_, c)| **c != 0.0)
                .map(|(i, &c)| (a, i, c)),
        );
    }
    Ok(rows)
}

/// The coordinate indices `start .. start + len` (at most [`MAX_EDOF`]) in
/// a fixed buffer.
fn range_dofs(start: usize, len: usize) -> [usize; MAX_EDOF] {
    let mut d = [0usize; MAX_EDOF];
    for (k, x) in d.iter_mut().enumerate().take(len) {
        *x = start + k;
    }
    d
}

#[cfg(test)]
mod tests;
