//! Structures: rods, rigid bodies and joints, assembled by connectivity.
//!
//! A model is a set of bodies — ANCF rods (each end clamped to the ground,
//! free, or joined to a rigid body) and rigid bodies (a platform, a grasped
//! object) — and joints (a rod end rigidly fixed to a rigid body at a point
//! and direction; a rigid body fixed to the ground). A single clamped chain
//! ([`crate::assembly::Robot`]) is one case.
//!
//! - [`spec`]: the input ([`StructureSpec`], [`StructureLoads`]) and its checks.
//! - [`rod`], [`section`]: one chain of elements in its own coordinates.
//! - [`rigid`]: where a rod end fixed to a planar rigid body sits.
//! - [`dofmap`]: all coordinates `q` (the rods' nodes, the bodies' poses)
//!   from the free coordinates `u`, `q = φ(u)`, block by block; the clamp is
//!   an affine block, `q = T u + q̄`.
//! - [`Structure`]: rods, bodies and the map built from a spec; each
//!   element knows its nodes and so its coordinates, and the assembler
//!   (`assemble`) adds element by element through the map: residual
//!   `R(u) = T(u)ᵀ Q(φ(u))` of the equilibrium (17) and tangent
//!   `K_u = Tᵀ K T + Σ_i g_i ∂²φ_i/∂u²` as a [`Triplets`] list.
//! - [`model`]: what an equilibrium solver needs of a model, by concept:
//!   its equilibrium ([`Assembled`], ten methods), how a solver steps in
//!   its free coordinates ([`Stepping`]), shortcuts with defaults
//!   ([`SolverHints`]), mesh sequencing ([`MeshSequencing`]) and the load
//!   set's scaling ([`ModelLoads`]); [`Model`] is all of them, implemented
//!   by the structure and the clamped robot. The solver is
//!   [`crate::statics::StaticSolver`], one for every model.

pub mod actuation;
mod assemble;
pub mod dofmap;
pub mod model;
pub mod rigid;
pub mod rod;
pub mod section;
mod sites;
pub mod spec;
mod strategy;
mod triplets;

use std::ops::Range;
use std::sync::Arc;

pub use actuation::Actuated;
pub use assemble::JointReaction;
pub use dofmap::{BlockRule, DofMap};
pub use model::{Assembled, Model, ModelLoads};
pub use rod::Rod;
pub use section::{Chamber, RestCurvatureProfile, Section};
pub use spec::{
    BodyLoad, Clamp, EndSupport, JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureLoads,
    StructureSpec,
};
pub use strategy::{MeshSequencing, SolverHints, Stepping};
pub use triplets::Triplets;

use crate::element::Element;
use crate::error::{Result, check_index};
use crate::loads::force_field::ForceField;
use rigid::Attachment;
use spec::ResolvedJoint;

/// One element of a structure: its two nodes (global node numbers) and where
/// it comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct ElementRef {
    nodes: [usize; 2],
    rod: usize,
    local: usize,
}

/// A structure built from a [`StructureSpec`]: its rods, the connectivity of
/// their elements, the rigid bodies and the map `q = φ(u)`.
///
/// Coordinates `q`: every rod's nodes, rod after rod (`NODE_DOFS` per node,
/// node-major), then every rigid body's pose (`x, y, θ` in 2-D). Free
/// coordinates `u`: block by block in the same order (see [`DofMap`]).
///
/// # Example
/// ```
/// use softrod::assembly::Section;
/// use softrod::structure::{RodSpec, StructureSpec};
/// let spec = StructureSpec::new(
///     vec![RodSpec::clamped(vec![Section::uniform(0.24, 300.0, 0.025, 8)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(1.0, 0.0))],
///     vec![], vec![]);
/// let s = spec.build_planar().unwrap();
/// // one clamped rod is the single chain: base stretch + nodes 1 … 8
/// assert_eq!((s.n_q(), s.n_free()), (36, 33));
/// ```
#[derive(Debug, Clone)]
pub struct Structure<E: Element> {
    spec: StructureSpec,
    rods: Vec<Rod<E>>,
    /// Global number of each rod's node 0.
    rod_node0: Vec<usize>,
    /// Each rod's start node in the straight reference: node rotations (the
    /// work of moments) are measured from its tangent.
    rod_reference: Vec<Vec<f64>>,
    n_rod_nodes: usize,
    connectivity: Vec<ElementRef>,
    /// The rod-to-body joints, with the global node of the joined end.
    joints: Vec<(ResolvedJoint, usize)>,
    dofs: DofMap,
    u_reference: Vec<f64>,
    fields: Vec<Arc<dyn ForceField>>,
}

impl<E: Element> Structure<E> {
    /// Checks `spec` and builds the structure; `make` builds one element of
    /// a section from `(section, element length, axial points, bending
    /// points)`.
    ///
    /// # Errors
    /// Every check names its field (`structure.rods[1].sections[0].ei_nm2`,
    /// `structure.joints[2].body`, …): [`crate::Error::InvalidParameter`] for
    /// bad numbers, a rod end joined twice (or clamped and joined), a body
    /// fixed to the ground twice, a joint point or direction off the rods'
    /// reference, a rigid body with no mass and no joint, a part of the
    /// structure with no ground connection, or rigid bodies with a
    /// non-planar element; [`crate::Error::IndexOutOfRange`] for a joint
    /// naming a missing rod or body; [`crate::Error::DimensionMismatch`] for
    /// vectors of the wrong size; [`crate::Error::TooLarge`] for more than
    /// [`rod::MAX_ELEMENTS`] elements in all. All before anything that grows
    /// with an element count is allocated.
    pub fn new(
        spec: StructureSpec,
        make: impl Fn(&Section, f64, usize, usize) -> Result<E>,
    ) -> Result<Self> {
        let d = E::DIM;
        let nd = E::NODE_DOFS;
        let checked = spec.check::<E>()?;
        let mut rods = Vec::with_capacity(spec.rods.len());
        let mut rod_node0 = Vec::with_capacity(spec.rods.len());
        let mut rod_reference = Vec::with_capacity(spec.rods.len());
        let mut connectivity = Vec::new();
        let mut q_ref = Vec::new();
        let mut n_nodes = 0usize;
        for (i, r) in spec.rods.iter().enumerate() {
            let rod = Rod::new(
                &r.sections,
                &spec.gravity_m_per_s2,
                spec.axial_gauss_points,
                spec.bending_gauss_points,
                &format!("structure.rods[{i}]"),
                &make,
            )?;
            rod_node0.push(n_nodes);
            for e in 0..rod.n_elements() {
                connectivity.push(ElementRef {
                    nodes: [n_nodes + e, n_nodes + e + 1],
                    rod: i,
                    local: e,
                });
            }
            let straight = rod.straight_configuration(&r.start_m, &checked.directions[i]);
            rod_reference.push(straight.as_slice()[..nd].to_vec());
            q_ref.extend(straight.iter());
            n_nodes += rod.n_nodes();
            rods.push(rod);
        }
        for b in &spec.rigid_bodies {
            q_ref.extend_from_slice(&b.position_m);
            q_ref.extend_from_slice(&b.orientation_rad);
        }
        // one block per rod node, then one per body
        let joint_at = |rod: usize, end: RodEnd| {
            checked
                .joints
                .iter()
                .find(|j| j.rod == rod && j.end == end)
                .copied()
        };
        let mut blocks = Vec::with_capacity(n_nodes + spec.rigid_bodies.len());
        let mut joints = Vec::with_capacity(checked.joints.len());
        for (i, (r, rod)) in spec.rods.iter().zip(&rods).enumerate() {
            let last = rod.n_nodes() - 1;
            for k in 0..rod.n_nodes() {
                let node = rod_node0[i] + k;
                let (support, end) = if k == 0 {
                    (r.start, RodEnd::Start)
                } else {
                    (r.end, RodEnd::End)
                };
                let rule = if k != 0 && k != last {
                    BlockRule::Free { len: nd }
                } else if let EndSupport::Clamped { clamp } = support {
                    clamp_rule::<E>(q_ref[node * nd..(node + 1) * nd].to_vec(), clamp)
                } else if let Some(j) = joint_at(i, end) {
                    joints.push((j, node));
                    let b = &spec.rigid_bodies[j.body];
                    let mut pose = b.position_m.clone();
                    pose.extend_from_slice(&b.orientation_rad);
                    let body_block = n_nodes + j.body;
                    match (j.attachment, checked.grounded[j.body]) {
                        // a joint to a fixed body is a clamp where the body holds the end
                        (Attachment::Planar(a), true) => clamp_rule::<E>(
                            a.node([pose[0], pose[1], pose[2]], 0.0).to_vec(),
                            Clamp::PositionAndDirection,
                        ),
                        (Attachment::Spatial(a), true) => {
                            let node = a.node(std::array::from_fn(|k| pose[k]), 0.0);
                            clamp_rule::<E>(node[..nd].to_vec(), Clamp::PositionAndDirection)
                        }
                        (Attachment::Planar(attachment), false) => BlockRule::PlanarRigidEnd {
                            body_block,
                            attachment,
                        },
                        (Attachment::Spatial(attachment), false) => BlockRule::SpatialRigidEnd {
                            body_block,
                            attachment,
                        },
                    }
                } else {
                    BlockRule::Free { len: nd }
                };
                blocks.push(rule);
            }
        }
        for (b, body) in spec.rigid_bodies.iter().enumerate() {
            blocks.push(if checked.grounded[b] {
                let mut pose = body.position_m.clone();
                pose.extend_from_slice(&body.orientation_rad);
                BlockRule::Affine {
                    offset: pose,
                    directions: Vec::new(),
                }
            } else {
                BlockRule::Free {
                    len: d + body.orientation_rad.len(),
                }
            });
        }
        let dofs = DofMap::new(blocks)?;
        // free coordinates of the straight reference: free blocks copy it,
        // stretches are zero
        let mut u_reference = vec![0.0; dofs.n_u()];
        for b in 0..dofs.n_blocks() {
            if let (Some(BlockRule::Free { .. }), Some(qr), Some(ur)) =
                (dofs.rule(b), dofs.coordinates(b), dofs.free(b))
            {
                u_reference[ur].copy_from_slice(&q_ref[qr]);
            }
        }
        Ok(Structure {
            spec,
            rods,
            rod_node0,
            rod_reference,
            n_rod_nodes: n_nodes,
            connectivity,
            joints,
            dofs,
            u_reference,
            fields: Vec::new(),
        })
    }

    /// The structure's definition.
    pub fn spec(&self) -> &StructureSpec {
        &self.spec
    }
    /// The rods, in their own coordinates.
    pub fn rods(&self) -> &[Rod<E>] {
        &self.rods
    }
    /// The map from free coordinates to all coordinates.
    pub fn dof_map(&self) -> &DofMap {
        &self.dofs
    }
    /// Number of coordinates `n_q`.
    pub fn n_q(&self) -> usize {
        self.dofs.n_q()
    }
    /// Number of free coordinates `n_u`.
    pub fn n_free(&self) -> usize {
        self.dofs.n_u()
    }
    /// Number of elements of all rods.
    pub fn n_elements(&self) -> usize {
        self.connectivity.len()
    }
    /// Number of rod nodes of all rods.
    pub fn n_rod_nodes(&self) -> usize {
        self.n_rod_nodes
    }

    /// The global node numbers of element `e` (its coordinates are the
    /// nodes' `NODE_DOFS` each, node `n` at `n · NODE_DOFS`).
    ///
    /// # Errors
    /// [`crate::Error::IndexOutOfRange`] for `e >= n_elements`.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::structure::{JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureSpec};
    /// let spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(0.0, 1.0))],
    ///     vec![RigidBodySpec { mass_kg: 0.1, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![JointSpec::RodToBody { rod: 0, end: RodEnd::End, body: 0, point_m: None, direction: None }],
    /// );
    /// let s = spec.build_planar().unwrap();
    /// assert_eq!(s.element_nodes(3).unwrap(), [3, 4]);
    /// ```
    pub fn element_nodes(&self, e: usize) -> Result<[usize; 2]> {
        check_index("element", e, self.connectivity.len())?;
        Ok(self.connectivity[e].nodes)
    }

    /// The coordinates (indices into `q`) of node `node` of rod `rod`.
    ///
    /// # Errors
    /// [`crate::Error::IndexOutOfRange`] for a rod or node that does not exist.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::structure::{JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureSpec};
    /// let spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(0.0, 1.0))],
    ///     vec![RigidBodySpec { mass_kg: 0.1, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![JointSpec::RodToBody { rod: 0, end: RodEnd::End, body: 0, point_m: None, direction: None }],
    /// );
    /// let s = spec.build_planar().unwrap();
    /// assert_eq!(s.node_coordinates(0, 4).unwrap(), 16..20);
    /// assert!(s.node_coordinates(1, 0).is_err());
    /// ```
    pub fn node_coordinates(&self, rod: usize, node: usize) -> Result<Range<usize>> {
        check_index("rod", rod, self.rods.len())?;
        check_index("node", node, self.rods[rod].n_nodes())?;
        let n = (self.rod_node0[rod] + node) * E::NODE_DOFS;
        Ok(n..n + E::NODE_DOFS)
    }

    /// The coordinates (indices into `q`) of rigid body `body`'s pose.
    ///
    /// # Errors
    /// [`crate::Error::IndexOutOfRange`] for a body that does not exist.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::structure::{JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureSpec};
    /// let spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(0.0, 1.0))],
    ///     vec![RigidBodySpec { mass_kg: 0.1, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![JointSpec::RodToBody { rod: 0, end: RodEnd::End, body: 0, point_m: None, direction: None }],
    /// );
    /// let s = spec.build_planar().unwrap();
    /// // after the rod's 5 nodes: x, y, θ
    /// assert_eq!(s.body_coordinates(0).unwrap(), 20..23);
    /// ```
    pub fn body_coordinates(&self, body: usize) -> Result<Range<usize>> {
        check_index("body", body, self.spec.rigid_bodies.len())?;
        self.dofs
            .coordinates(self.n_rod_nodes + body)
            .ok_or_else(|| crate::Error::invalid("body", body, "has no block"))
    }

    /// The free coordinates of rigid body `body`'s pose (empty if it is
    /// fixed to the ground).
    ///
    /// # Errors
    /// [`crate::Error::IndexOutOfRange`] for a body that does not exist.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::structure::{JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureSpec};
    /// let spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(0.0, 1.0))],
    ///     vec![RigidBodySpec { mass_kg: 0.1, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![JointSpec::RodToBody { rod: 0, end: RodEnd::End, body: 0, point_m: None, direction: None }],
    /// );
    /// let s = spec.build_planar().unwrap();
    /// // base stretch, nodes 1 … 3, the joint's stretch, then the pose
    /// assert_eq!(s.body_free_coordinates(0).unwrap(), 14..17);
    /// ```
    pub fn body_free_coordinates(&self, body: usize) -> Result<Range<usize>> {
        check_index("body", body, self.spec.rigid_bodies.len())?;
        let b = self.n_rod_nodes + body;
        Ok(match self.dofs.rule(b) {
            Some(BlockRule::Free { .. }) => self.dofs.free(b).unwrap_or(0..0),
            _ => 0..0,
        })
    }

    /// The free coordinates of the straight reference: every rod straight
    /// as its spec says, every body at its pose, every stretch zero.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::structure::{JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureSpec};
    /// let spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(0.0, 1.0))],
    ///     vec![RigidBodySpec { mass_kg: 0.1, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![JointSpec::RodToBody { rod: 0, end: RodEnd::End, body: 0, point_m: None, direction: None }],
    /// );
    /// let s = spec.build_planar().unwrap();
    /// let q = s.configuration(s.reference_free_coordinates()).unwrap();
    /// // the joined tip sits where the body says: (0, 0.2), pointing up
    /// assert!((q[17] - 0.2).abs() < 1e-15 && (q[19] - 1.0).abs() < 1e-15);
    /// ```
    pub fn reference_free_coordinates(&self) -> &[f64] {
        &self.u_reference
    }

    /// `q = φ(u)` ([`DofMap::configuration`]).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `u` has the wrong size.
    pub fn configuration(&self, u: &[f64]) -> Result<nalgebra::DVector<f64>> {
        self.dofs.configuration(u)
    }

    /// Adds a configuration-dependent force (a spring, a contact) over the
    /// structure's coordinates `q`.
    ///
    /// # Errors
    /// The field's [`ForceField::check`] against `n_q`.
    ///
    /// # Example
    /// ```
    /// use std::sync::Arc;
    /// use softrod::loads::force_field::PointSpring;
    /// use softrod::assembly::Section;
    /// use softrod::structure::{JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureSpec};
    /// let spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(0.0, 1.0))],
    ///     vec![RigidBodySpec { mass_kg: 0.1, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![JointSpec::RodToBody { rod: 0, end: RodEnd::End, body: 0, point_m: None, direction: None }],
    /// );
    /// let mut s = spec.build_planar().unwrap();
    /// let pose = s.body_coordinates(0).unwrap();
    /// let spring = PointSpring::new([pose.start, pose.start + 1], nalgebra::Vector2::new(0.0, 0.3), 5.0, 0.0).unwrap();
    /// s.add_force_field(Arc::new(spring)).unwrap();
    /// let outside = PointSpring::new([99, 100], nalgebra::Vector2::zeros(), 5.0, 0.0).unwrap();
    /// assert!(s.add_force_field(Arc::new(outside)).is_err());
    /// ```
    pub fn add_force_field(&mut self, field: Arc<dyn ForceField>) -> Result<()> {
        field.check(self.n_q())?;
        self.fields.push(field);
        Ok(())
    }
}

/// The affine block of a clamp at the node `offset`: position and direction
/// fixed, the stretch free unless the clamp is [`Clamp::Full`].
fn clamp_rule<E: Element>(offset: Vec<f64>, clamp: Clamp) -> BlockRule {
    let directions = match clamp {
        Clamp::PositionAndDirection => {
            crate::element::direction_list(&E::clamp_free_directions(&offset))
        }
        Clamp::Full => Vec::new(),
    };
    BlockRule::Affine { offset, directions }
}
