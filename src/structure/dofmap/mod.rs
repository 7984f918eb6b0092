//! The map from free coordinates `u` to all coordinates `q`: `q = φ(u)`,
//! with Jacobian `T(u) = ∂φ/∂u`.
//!
//! All coordinates of a model (every rod node `[r, r']`, every rigid body's
//! pose) are cut into *blocks*; each block follows the free coordinates by
//! one [`BlockRule`]:
//!
//! - [`BlockRule::Free`]: the block's coordinates are free coordinates.
//! - [`BlockRule::Affine`]: `q_b = q̄_b + Σ_k t_k u_k`, a fixed offset plus
//!   free directions. The clamp is one: the base position and direction are
//!   prescribed (`q̄`), the stretch along the tangent is free (one direction
//!   `t`); with no direction the block is fixed.
//! - [`BlockRule::PlanarRigidEnd`]: a cable node fixed to a rigid body whose
//!   pose is a free block, `r = x_b + R(θ) p`, `r' = (1 + σ) R(θ) d`, with
//!   one new free coordinate, the stretch `σ` (see [`super::rigid`]). It is
//!   nonlinear in `θ`.
//! - [`BlockRule::SpatialRigidEnd`]: its 3-D counterpart, a spatial-cable
//!   node `[r, r']` or a full 3-D node `[r, r_X, r_Y, r_Z]` fixed to a body
//!   whose pose `(x, ψ)` (position, rotation vector) is a free block of 6:
//!   `r = x + R(ψ) p`, `r_X = (1 + σ) R(ψ) d`, `r_Y = R(ψ) a₂`,
//!   `r_Z = R(ψ) a₃` (see [`super::rigid::SpatialAttachment`]).
//!
//! Free coordinates are numbered block by block in block order: the free
//! coordinates of a single clamped chain are its base stretch and then the
//! coordinates of nodes 1 … N, as always.
//!
//! Where every block is linear, `q = T u + q̄` with a constant `T`. With a
//! rigid end, the equilibrium (17) in `u` is `R(u) = T(u)ᵀ Q(φ(u)) = 0` and
//! its tangent `K_u = −∂R/∂u = Tᵀ K T + Σ_i g_i ∂²φ_i/∂u²`, `K = −∂Q/∂q` and
//! `g = −Q = ∂Π/∂q` the gradient of the total potential:
//! [`DofMap::add_stiffness`] adds the first term element by element,
//! [`DofMap::add_geometric_stiffness`] the second.

use std::ops::Range;

use super::rigid::{PlanarAttachment, SPATIAL_END_COLUMNS, SpatialAttachment};
use crate::error::{Error, Result, check_all_finite, check_index, check_len};

/// The largest block (a node of the full 3-D ANCF element: 12 coordinates).
pub const MAX_BLOCK: usize = 12;
/// The most free coordinates one coordinate may depend on.
const MAX_TERMS: usize = 6;
/// The most coordinates one call of [`DofMap::add_force`] or
/// [`DofMap::add_stiffness`] may touch (an element of two 12-coordinate nodes).
pub const MAX_DOFS: usize = 24;

/// How a block of coordinates follows the free coordinates.
///
/// # Example
/// ```
/// use softrod::structure::BlockRule;
/// // a planar clamp at the origin along x: position and direction fixed, stretch free
/// let clamp = BlockRule::Affine {
///     offset: vec![0.0, 0.0, 1.0, 0.0],
///     directions: vec![vec![0.0, 0.0, 1.0, 0.0]],
/// };
/// assert_eq!(clamp.len(), 4);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub enum BlockRule {
    /// `len` free coordinates.
    Free {
        /// Number of coordinates.
        len: usize,
    },
    /// `q_b = offset + Σ_k directions[k] u_k`: each direction is a new free
    /// coordinate; no direction fixes the block.
    Affine {
        /// The prescribed part `q̄_b`.
        offset: Vec<f64>,
        /// The free directions `t_k` (each as long as `offset`).
        directions: Vec<Vec<f64>>,
    },
    /// A planar cable node `[r, r']` fixed to the rigid body whose pose
    /// `(x, y, θ)` is the [`BlockRule::Free`] block `body_block` (of length
    /// 3): `r = x + R(θ) p`, `r' = (1 + σ) R(θ) d`, `σ` a new free coordinate.
    PlanarRigidEnd {
        /// The block holding the body's pose.
        body_block: usize,
        /// Where and in which direction the node sits on the body.
        attachment: PlanarAttachment,
    },
    /// A spatial-cable (6) or full 3-D (12 coordinates) node fixed to the
    /// rigid body whose pose `(x, ψ)` is the [`BlockRule::Free`] block
    /// `body_block` (of length 6): `σ` a new free coordinate.
    SpatialRigidEnd {
        /// The block holding the body's pose.
        body_block: usize,
        /// Where the node sits on the body and its section frame there.
        attachment: SpatialAttachment,
    },
}

impl BlockRule {
    /// Number of coordinates of the block.
    pub fn len(&self) -> usize {
        match self {
            BlockRule::Free { len } => *len,
            BlockRule::Affine { offset, .. } => offset.len(),
            BlockRule::PlanarRigidEnd { .. } => 4,
            BlockRule::SpatialRigidEnd { attachment, .. } => attachment.node_dofs,
        }
    }

    /// Whether the block has no coordinates.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of free coordinates the block adds.
    pub fn n_free(&self) -> usize {
        match self {
            BlockRule::Free { len } => *len,
            BlockRule::Affine { directions, .. } => directions.len(),
            BlockRule::PlanarRigidEnd { .. } | BlockRule::SpatialRigidEnd { .. } => 1,
        }
    }
}

/// A rigid end's free coordinates (`cols[..n_cols]`) and the Jacobian of
/// its node with respect to them (rows past the node's length zero).
struct EndJacobian {
    cols: [usize; SPATIAL_END_COLUMNS],
    n_cols: usize,
    jac: [[f64; SPATIAL_END_COLUMNS]; MAX_BLOCK],
}

/// One block with its place in `q` and `u`.
#[derive(Debug, Clone, PartialEq)]
struct Block {
    /// First coordinate.
    q0: usize,
    /// Number of coordinates.
    len: usize,
    /// First free coordinate the block adds.
    u0: usize,
    /// First free coordinate of the body pose (rigid ends only).
    pose_u: usize,
    rule: BlockRule,
}

/// The constraint map `q = φ(u)` of a model, block by block.
///
/// # Example
/// ```
/// use softrod::structure::{BlockRule, DofMap};
/// // a clamped planar chain of two elements: node 0 clamped, nodes 1 and 2 free
/// let map = DofMap::new(vec![
///     BlockRule::Affine { offset: vec![0.0, 0.0, 1.0, 0.0], directions: vec![vec![0.0, 0.0, 1.0, 0.0]] },
///     BlockRule::Free { len: 4 },
///     BlockRule::Free { len: 4 },
/// ]).unwrap();
/// assert_eq!((map.n_q(), map.n_u()), (12, 9));
/// let mut u = vec![0.0; 9];
/// u[0] = 0.01; // base stretch
/// let q = map.configuration(&u).unwrap();
/// assert_eq!(q[2], 1.01);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct DofMap {
    blocks: Vec<Block>,
    /// The leading run of blocks of equal length: `(length, count)` (the
    /// nodes of the rods), where the block of a coordinate is a division.
    uniform: (usize, usize),
    /// Maximal runs of free blocks that follow each other in both `q` and
    /// `u`: `(q0, u0, len)`, copied as one slice.
    runs: Vec<(usize, usize, usize)>,
    /// The blocks that are not free.
    constrained: Vec<usize>,
    n_q: usize,
    n_u: usize,
    linear: bool,
}

impl DofMap {
    /// Numbers the blocks' coordinates and free coordinates in order.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (field `dof_map.blocks[i]…`) for an empty
    /// or too long block, a direction of the wrong length, more than 6
    /// directions, non-finite numbers, or a rigid end whose body block is not
    /// a free block of 3 coordinates;
    /// [`Error::IndexOutOfRange`] for a body block that does not exist.
    pub fn new(rules: Vec<BlockRule>) -> Result<Self> {
        let n_blocks = rules.len();
        for (i, rule) in rules.iter().enumerate() {
            let p = |f: &str| format!("dof_map.blocks[{i}]{f}");
            let len = rule.len();
            if len == 0 || len > MAX_BLOCK {
                return Err(Error::invalid(
                    p(""),
                    format!("{len} coordinates"),
                    format!("a block has 1 to {MAX_BLOCK} coordinates"),
                ));
            }
            match rule {
                BlockRule::Free { .. } => {}
                BlockRule::Affine { offset, directions } => {
                    check_all_finite(&p(".offset"), offset)?;
                    if directions.len() > MAX_TERMS {
                        return Err(Error::invalid(
                            p(".directions"),
                            directions.len(),
                            format!("at most {MAX_TERMS} free directions"),
                        ));
                    }
                    for (k, t) in directions.iter().enumerate() {
                        let name = p(&format!(".directions[{k}]"));
                        check_len(&name, len, t.len())?;
                        check_all_finite(&name, t)?;
                    }
                }
                BlockRule::PlanarRigidEnd {
                    body_block,
                    attachment,
                } => {
                    check_index(&p(".body_block"), *body_block, n_blocks)?;
                    if !matches!(rules[*body_block], BlockRule::Free { len: 3 }) {
                        return Err(Error::invalid(
                            p(".body_block"),
                            body_block,
                            "must be a free block of 3 coordinates (x, y, θ)",
                        ));
                    }
                    check_all_finite(&p(".attachment.point_m"), attachment.point_m.as_slice())?;
                    check_all_finite(&p(".attachment.direction"), attachment.direction.as_slice())?;
                }
                BlockRule::SpatialRigidEnd {
                    body_block,
                    attachment,
                } => {
                    check_index(&p(".body_block"), *body_block, n_blocks)?;
                    if !matches!(rules[*body_block], BlockRule::Free { len: 6 }) {
                        return Err(Error::invalid(
                            p(".body_block"),
                            body_block,
                            "must be a free block of 6 coordinates (x, y, z, ψ)",
                        ));
                    }
                    attachment
                        .check()
                        .map_err(|e| e.with_prefix(&p(".attachment.")))?;
                }
            }
        }
        let mut blocks = Vec::with_capacity(n_blocks);
        let (mut q0, mut u0) = (0usize, 0usize);
        for rule in rules {
            let (len, nf) = (rule.len(), rule.n_free());
            blocks.push(Block {
                q0,
                len,
                u0,
                pose_u: 0,
                rule,
            });
            q0 += len;
            u0 += nf;
        }
        // resolve the body poses of the rigid ends
        let starts: Vec<usize> = blocks.iter().map(|b| b.u0).collect();
        let mut linear = true;
        for b in &mut blocks {
            if let BlockRule::PlanarRigidEnd { body_block, .. }
            | BlockRule::SpatialRigidEnd { body_block, .. } = b.rule
            {
                b.pose_u = starts[body_block];
                linear = false;
            }
        }
        let first = blocks.first().map_or(1, |b| b.len);
        let run = blocks.iter().take_while(|b| b.len == first).count();
        let mut runs: Vec<(usize, usize, usize)> = Vec::new();
        let mut constrained = Vec::new();
        for (i, b) in blocks.iter().enumerate() {
            if !matches!(b.rule, BlockRule::Free { .. }) {
                constrained.push(i);
                continue;
            }
            match runs.last_mut() {
                Some((q0, u0, len)) if *q0 + *len == b.q0 && *u0 + *len == b.u0 => *len += b.len,
                _ => runs.push((b.q0, b.u0, b.len)),
            }
        }
        Ok(DofMap {
            blocks,
            uniform: (first, run),
            runs,
            constrained,
            n_q: q0,
            n_u: u0,
            linear,
        })
    }

    /// Number of coordinates `n_q`.
    pub fn n_q(&self) -> usize {
        self.n_q
    }
    /// Number of free coordinates `n_u`.
    pub fn n_u(&self) -> usize {
        self.n_u
    }
    /// Number of blocks.
    pub fn n_blocks(&self) -> usize {
        self.blocks.len()
    }
    /// Whether `φ` is affine (`q = T u + q̄`, `T` constant): no rigid ends.
    /// The methods of a linear map do not read `u` (an empty slice will do).
    pub fn is_linear(&self) -> bool {
        self.linear
    }
    /// The rule of block `b`.
    pub fn rule(&self, b: usize) -> Option<&BlockRule> {
        self.blocks.get(b).map(|x| &x.rule)
    }
    /// The coordinates of block `b` (a range of `q` indices).
    pub fn coordinates(&self, b: usize) -> Option<Range<usize>> {
        self.blocks.get(b).map(|x| x.q0..x.q0 + x.len)
    }
    /// The free coordinates block `b` adds (a range of `u` indices: its own
    /// coordinates, its free directions, or a rigid end's stretch).
    pub fn free(&self, b: usize) -> Option<Range<usize>> {
        self.blocks.get(b).map(|x| x.u0..x.u0 + x.rule.n_free())
    }

    /// If the coordinates `q_start .. q_start + len` are free coordinates
    /// that follow each other in `u`, the first of them.
    ///
    /// # Example
    /// ```
    /// use softrod::structure::{BlockRule, DofMap};
    /// let map = DofMap::new(vec![
    ///     BlockRule::Affine { offset: vec![0.0, 0.0, 1.0, 0.0], directions: vec![vec![0.0, 0.0, 1.0, 0.0]] },
    ///     BlockRule::Free { len: 4 },
    /// ]).unwrap();
    /// assert_eq!(map.contiguous_free(4, 4), Some(1)); // node 1: u[1..5]
    /// assert_eq!(map.contiguous_free(0, 8), None); // the clamped node is not free
    /// ```
    pub fn contiguous_free(&self, q_start: usize, len: usize) -> Option<usize> {
        let first = self.block_at(q_start)?;
        let b = &self.blocks[first];
        let BlockRule::Free { .. } = b.rule else {
            return None;
        };
        let u_start = b.u0 + (q_start - b.q0);
        let mut i = first;
        // every block up to the end of the range must be free and in step
        while let Some(x) = self.blocks.get(i) {
            if x.q0 >= q_start + len {
                break;
            }
            match x.rule {
                BlockRule::Free { .. } if x.u0 + q_start == u_start + x.q0 => {}
                _ => return None,
            }
            i += 1;
        }
        (q_start + len <= self.n_q).then_some(u_start)
    }

    /// The block holding coordinate `qi`.
    fn block_at(&self, qi: usize) -> Option<usize> {
        let (len, run) = self.uniform;
        if qi < len * run {
            return Some(qi / len);
        }
        let i = run + self.blocks[run..].partition_point(|b| b.q0 + b.len <= qi);
        (i < self.blocks.len()).then_some(i)
    }

    fn check_u(&self, u: &[f64]) -> Result<()> {
        if self.linear {
            Ok(())
        } else {
            check_len("u", self.n_u, u.len())
        }
    }

    /// The pose and stretch of a rigid end.
    fn pose(&self, b: &Block, u: &[f64]) -> ([f64; 3], f64) {
        let get = |i: usize| u.get(i).copied().unwrap_or(f64::NAN);
        (
            [get(b.pose_u), get(b.pose_u + 1), get(b.pose_u + 2)],
            get(b.u0),
        )
    }

    /// The pose `(x, ψ)` and stretch of a spatial rigid end.
    fn pose_3d(&self, b: &Block, u: &[f64]) -> ([f64; 6], f64) {
        let get = |i: usize| u.get(i).copied().unwrap_or(f64::NAN);
        (std::array::from_fn(|k| get(b.pose_u + k)), get(b.u0))
    }

    /// A rigid end's Jacobian at `u`: the free coordinates it depends on
    /// (the body's pose, then its stretch) and `∂node/∂(those)` (`None` for
    /// another rule).
    fn end_jacobian(&self, b: &Block, u: &[f64]) -> Option<EndJacobian> {
        let mut out = EndJacobian {
            cols: [0; SPATIAL_END_COLUMNS],
            n_cols: 0,
            jac: [[0.0; SPATIAL_END_COLUMNS]; MAX_BLOCK],
        };
        match &b.rule {
            BlockRule::PlanarRigidEnd { attachment, .. } => {
                let (pose, s) = self.pose(b, u);
                let j = attachment.jacobian(pose, s);
                out.cols[..4].copy_from_slice(&[b.pose_u, b.pose_u + 1, b.pose_u + 2, b.u0]);
                out.n_cols = 4;
                for (row, jr) in out.jac.iter_mut().zip(&j) {
                    row[..4].copy_from_slice(jr);
                }
            }
            BlockRule::SpatialRigidEnd { attachment, .. } => {
                let (pose, s) = self.pose_3d(b, u);
                out.jac = attachment.jacobian(pose, s);
                for (k, c) in out.cols[..6].iter_mut().enumerate() {
                    *c = b.pose_u + k;
                }
                out.cols[6] = b.u0;
                out.n_cols = SPATIAL_END_COLUMNS;
            }
            _ => return None,
        }
        Some(out)
    }

    /// Row `k` of `T` within block `b` (`∂q_{q0+k}/∂u`) into `out`; returns
    /// the number of terms.
    fn row(&self, b: &Block, k: usize, u: &[f64], out: &mut [(usize, f64); MAX_TERMS]) -> usize {
        match &b.rule {
            BlockRule::Free { .. } => {
                out[0] = (b.u0 + k, 1.0);
                1
            }
            BlockRule::Affine { directions, .. } => {
                let mut n = 0;
                for (j, t) in directions.iter().enumerate() {
                    if let Some(&c) = t.get(k)
                        && c != 0.0
                    {
                        out[n] = (b.u0 + j, c);
                        n += 1;
                    }
                }
                n
            }
            BlockRule::PlanarRigidEnd { .. } | BlockRule::SpatialRigidEnd { .. } => {
                let Some(end) = self.end_jacobian(b, u) else {
                    return 0;
                };
                let Some(row) = end.jac.get(k) else {
                    return 0;
                };
                // a spatial end keeps its structural terms (the rotation's,
                // and the stretch's on `r_X`) also where they vanish (at
                // ψ = 0): the tangent's pattern is taken at the reference
                let spatial = end.n_cols == SPATIAL_END_COLUMNS;
                let mut n = 0;
                for (l, (&c, &v)) in end.cols[..end.n_cols].iter().zip(row).enumerate() {
                    let structural =
                        spatial && ((3..6).contains(&l) || (l == 6 && (3..6).contains(&k)));
                    if (v != 0.0 || structural) && n < MAX_TERMS {
                        out[n] = (c, v);
                        n += 1;
                    }
                }
                n
            }
        }
    }

    /// Row of `T` for coordinate `qi` (no terms for an index off the end).
    fn row_at(&self, qi: usize, u: &[f64], out: &mut [(usize, f64); MAX_TERMS]) -> usize {
        match self.block_at(qi) {
            Some(b) => {
                let b = &self.blocks[b];
                self.row(b, qi - b.q0, u, out)
            }
            None => 0,
        }
    }

    /// `q = φ(u)` into `q` (`n_q` entries).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `u` or `q` has the wrong size.
    pub fn configuration_into(&self, u: &[f64], q: &mut [f64]) -> Result<()> {
        check_len("u", self.n_u, u.len())?;
        check_len("q", self.n_q, q.len())?;
        for &(q0, u0, len) in &self.runs {
            q[q0..q0 + len].copy_from_slice(&u[u0..u0 + len]);
        }
        for b in self.constrained.iter().filter_map(|&i| self.blocks.get(i)) {
            let len = b.len;
            let qb = &mut q[b.q0..b.q0 + len];
            match &b.rule {
                BlockRule::Free { .. } => qb.copy_from_slice(&u[b.u0..b.u0 + len]),
                BlockRule::Affine { offset, directions } => {
                    qb.copy_from_slice(offset);
                    for (j, t) in directions.iter().enumerate() {
                        for (x, tk) in qb.iter_mut().zip(t) {
                            *x += tk * u[b.u0 + j];
                        }
                    }
                }
                BlockRule::PlanarRigidEnd { attachment, .. } => {
                    let (pose, s) = self.pose(b, u);
                    qb.copy_from_slice(&attachment.node(pose, s));
                }
                BlockRule::SpatialRigidEnd { attachment, .. } => {
                    let (pose, s) = self.pose_3d(b, u);
                    qb.copy_from_slice(&attachment.node(pose, s)[..len]);
                }
            }
        }
        Ok(())
    }

    /// `q = φ(u)`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `u` has the wrong size.
    pub fn configuration(&self, u: &[f64]) -> Result<nalgebra::DVector<f64>> {
        self.configuration_vec(u).map(nalgebra::DVector::from_vec)
    }

    /// As [`DofMap::configuration`], as a plain vector (the assembly's
    /// scratch).
    pub(crate) fn configuration_vec(&self, u: &[f64]) -> Result<Vec<f64>> {
        let mut q = vec![0.0; self.n_q];
        self.configuration_into(u, &mut q)?;
        Ok(q)
    }
}

mod apply;
#[cfg(test)]
mod tests;
