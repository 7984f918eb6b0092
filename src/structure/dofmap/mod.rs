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

use super::rigid::PlanarAttachment;
use crate::error::{check_all_finite, check_index, check_len, Error, Result};
use crate::loads::force_field::StiffnessSink;

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
}

impl BlockRule {
    /// Number of coordinates of the block.
    pub fn len(&self) -> usize {
        match self {
            BlockRule::Free { len } => *len,
            BlockRule::Affine { offset, .. } => offset.len(),
            BlockRule::PlanarRigidEnd { .. } => 4,
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
            BlockRule::PlanarRigidEnd { .. } => 1,
        }
    }
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
                    check_all_finite(&p(".attachment.point_m"), &attachment.point_m)?;
                    check_all_finite(&p(".attachment.direction"), &attachment.direction)?;
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
            if let BlockRule::PlanarRigidEnd { body_block, .. } = b.rule {
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
                    if let Some(&c) = t.get(k) {
                        if c != 0.0 {
                            out[n] = (b.u0 + j, c);
                            n += 1;
                        }
                    }
                }
                n
            }
            BlockRule::PlanarRigidEnd { attachment, .. } => {
                let (pose, s) = self.pose(b, u);
                let row = attachment
                    .jacobian(pose, s)
                    .get(k)
                    .copied()
                    .unwrap_or([0.0; 4]);
                let cols = [b.pose_u, b.pose_u + 1, b.pose_u + 2, b.u0];
                let mut n = 0;
                for (&c, &v) in cols.iter().zip(&row) {
                    if v != 0.0 {
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
            }
        }
        Ok(())
    }

    /// `q = φ(u)`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `u` has the wrong size.
    pub fn configuration(&self, u: &[f64]) -> Result<Vec<f64>> {
        let mut q = vec![0.0; self.n_q];
        self.configuration_into(u, &mut q)?;
        Ok(q)
    }

    /// The free coordinates of a configuration `q` over all coordinates:
    /// the `u` with `φ(u) = q` when `q` lies on the map, else its nearest
    /// reach block by block (free blocks copied; an affine block's free
    /// directions by least squares, its prescribed part kept; a rigid end's
    /// stretch `σ = (R(θ) d)·r' − 1` at its body's pose from `q`).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `q` has the wrong size;
    /// [`Error::InvalidParameter`] for affine directions that are linearly
    /// dependent.
    ///
    /// # Example
    /// ```
    /// use softrod::structure::{BlockRule, DofMap};
    /// let map = DofMap::new(vec![
    ///     BlockRule::Affine { offset: vec![0.0, 0.0, 1.0, 0.0], directions: vec![vec![0.0, 0.0, 1.0, 0.0]] },
    ///     BlockRule::Free { len: 4 },
    /// ]).unwrap();
    /// let u = vec![0.5, 0.1, 0.0, 1.0, 0.0];
    /// let q = map.configuration(&u).unwrap();
    /// assert_eq!(map.free_coordinates_of(&q).unwrap(), u);
    /// ```
    pub fn free_coordinates_of(&self, q: &[f64]) -> Result<Vec<f64>> {
        check_len("q", self.n_q, q.len())?;
        let mut u = vec![0.0; self.n_u];
        for &(q0, u0, len) in &self.runs {
            u[u0..u0 + len].copy_from_slice(&q[q0..q0 + len]);
        }
        for b in self.constrained.iter().filter_map(|&i| self.blocks.get(i)) {
            let qb = &q[b.q0..b.q0 + b.len];
            match &b.rule {
                BlockRule::Free { len } => u[b.u0..b.u0 + len].copy_from_slice(qb),
                BlockRule::Affine { offset, directions } => {
                    // normal equations of min |offset + Σ t_k u_k − q_b|
                    let m = directions.len();
                    if m == 0 {
                        continue;
                    }
                    let gram = nalgebra::DMatrix::from_fn(m, m, |i, j| {
                        directions[i]
                            .iter()
                            .zip(&directions[j])
                            .map(|(a, c)| a * c)
                            .sum::<f64>()
                    });
                    let rhs = nalgebra::DVector::from_fn(m, |i, _| {
                        directions[i]
                            .iter()
                            .zip(qb.iter().zip(offset))
                            .map(|(t, (x, o))| t * (x - o))
                            .sum::<f64>()
                    });
                    let x = gram.cholesky().map(|c| c.solve(&rhs)).ok_or_else(|| {
                        Error::invalid(
                            "dof_map.directions",
                            m,
                            "linearly dependent free directions",
                        )
                    })?;
                    u[b.u0..b.u0 + m].copy_from_slice(x.as_slice());
                }
                BlockRule::PlanarRigidEnd { .. } => {}
            }
        }
        // rigid ends after every pose is known
        for b in self.constrained.iter().filter_map(|&i| self.blocks.get(i)) {
            if let BlockRule::PlanarRigidEnd { attachment, .. } = &b.rule {
                let theta = u.get(b.pose_u + 2).copied().unwrap_or(0.0);
                let e = super::rigid::rotate(theta, attachment.direction);
                let slope = &q[b.q0 + 2..b.q0 + 4];
                u[b.u0] = e[0] * slope[0] + e[1] * slope[1] - 1.0;
            }
        }
        Ok(u)
    }

    /// A step of the free coordinates mapped to all coordinates,
    /// `dq = T(u) du`, into `dq`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `du` or `dq` (or, for a nonlinear
    /// map, `u`) has the wrong size.
    ///
    /// # Example
    /// ```
    /// use softrod::structure::{BlockRule, DofMap};
    /// let map = DofMap::new(vec![
    ///     BlockRule::Affine { offset: vec![0.0, 0.0, 1.0, 0.0], directions: vec![vec![0.0, 0.0, 1.0, 0.0]] },
    ///     BlockRule::Free { len: 4 },
    /// ]).unwrap();
    /// // a stretch step moves only the base slope; a linear map reads no `u`
    /// let mut dq = vec![0.0; 8];
    /// map.expand_into(&[], &[0.5, 0.0, 0.0, 0.0, 0.0], &mut dq).unwrap();
    /// assert_eq!(dq, vec![0.0, 0.0, 0.5, 0.0, 0.0, 0.0, 0.0, 0.0]);
    /// ```
    pub fn expand_into(&self, u: &[f64], du: &[f64], dq: &mut [f64]) -> Result<()> {
        self.check_u(u)?;
        check_len("du", self.n_u, du.len())?;
        check_len("dq", self.n_q, dq.len())?;
        for &(q0, u0, len) in &self.runs {
            dq[q0..q0 + len].copy_from_slice(&du[u0..u0 + len]);
        }
        for b in self.constrained.iter().filter_map(|&i| self.blocks.get(i)) {
            let len = b.len;
            let qb = &mut dq[b.q0..b.q0 + len];
            match &b.rule {
                BlockRule::Free { .. } => qb.copy_from_slice(&du[b.u0..b.u0 + len]),
                BlockRule::Affine { directions, .. } => {
                    qb.iter_mut().for_each(|v| *v = 0.0);
                    for (j, t) in directions.iter().enumerate() {
                        for (x, tk) in qb.iter_mut().zip(t) {
                            *x += tk * du[b.u0 + j];
                        }
                    }
                }
                BlockRule::PlanarRigidEnd { attachment, .. } => {
                    let (pose, s) = self.pose(b, u);
                    let jac = attachment.jacobian(pose, s);
                    let cols = [b.pose_u, b.pose_u + 1, b.pose_u + 2, b.u0];
                    for (x, row) in qb.iter_mut().zip(&jac) {
                        *x = row.iter().zip(&cols).map(|(c, &j)| c * du[j]).sum();
                    }
                }
            }
        }
        Ok(())
    }

    /// A generalized force over all coordinates restricted to the free
    /// coordinates, `T(u)ᵀ f` (the work-conjugate of [`DofMap::expand_into`]),
    /// into `out`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `f` or `out` (or, for a nonlinear
    /// map, `u`) has the wrong size.
    ///
    /// # Example
    /// ```
    /// use softrod::structure::{BlockRule, DofMap};
    /// let map = DofMap::new(vec![
    ///     BlockRule::Affine { offset: vec![0.0, 0.0, 1.0, 0.0], directions: vec![vec![0.0, 0.0, 1.0, 0.0]] },
    ///     BlockRule::Free { len: 4 },
    /// ]).unwrap();
    /// // a force on the clamped position does no work; on its slope, along the stretch
    /// let f = [7.0, 7.0, 2.0, 9.0, 1.0, 2.0, 3.0, 4.0];
    /// let mut out = vec![0.0; 5];
    /// map.restrict_into(&[], &f, &mut out).unwrap();
    /// assert_eq!(out, vec![2.0, 1.0, 2.0, 3.0, 4.0]);
    /// ```
    pub fn restrict_into(&self, u: &[f64], f: &[f64], out: &mut [f64]) -> Result<()> {
        self.check_u(u)?;
        check_len("f", self.n_q, f.len())?;
        check_len("u", self.n_u, out.len())?;
        // blocks own disjoint free coordinates except rigid ends, which add
        // to their body's pose: write owned entries first, then add
        for &(q0, u0, len) in &self.runs {
            out[u0..u0 + len].copy_from_slice(&f[q0..q0 + len]);
        }
        for b in self.constrained.iter().filter_map(|&i| self.blocks.get(i)) {
            let len = b.len;
            let fb = &f[b.q0..b.q0 + len];
            match &b.rule {
                BlockRule::Free { .. } => out[b.u0..b.u0 + len].copy_from_slice(fb),
                BlockRule::Affine { directions, .. } => {
                    for (j, t) in directions.iter().enumerate() {
                        out[b.u0 + j] = t.iter().zip(fb).map(|(a, b)| a * b).sum();
                    }
                }
                BlockRule::PlanarRigidEnd { .. } => out[b.u0] = 0.0,
            }
        }
        for b in self.constrained.iter().filter_map(|&i| self.blocks.get(i)) {
            if let BlockRule::PlanarRigidEnd { attachment, .. } = &b.rule {
                let (pose, s) = self.pose(b, u);
                let jac = attachment.jacobian(pose, s);
                let cols = [b.pose_u, b.pose_u + 1, b.pose_u + 2, b.u0];
                for (row, fi) in jac.iter().zip(&f[b.q0..b.q0 + 4]) {
                    for (c, &j) in row.iter().zip(&cols) {
                        out[j] += c * fi;
                    }
                }
            }
        }
        Ok(())
    }

    /// Adds `sign · Tᵀ g` into the free-coordinate vector `out`, for a vector
    /// `g` over the coordinates `dofs` (at most [`MAX_DOFS`]): the scatter of
    /// an element's or a node's generalized force.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for sizes that do not fit,
    /// [`Error::IndexOutOfRange`] for a coordinate `>= n_q`.
    ///
    /// # Example
    /// ```
    /// use softrod::structure::{BlockRule, DofMap};
    /// let map = DofMap::new(vec![
    ///     BlockRule::Affine { offset: vec![0.0, 0.0, 1.0, 0.0], directions: vec![vec![0.0, 0.0, 1.0, 0.0]] },
    ///     BlockRule::Free { len: 4 },
    /// ]).unwrap();
    /// let mut out = vec![0.0; 5];
    /// map.add_force(&[], &[2, 4], &[3.0, 1.0], -1.0, &mut out).unwrap();
    /// assert_eq!(out, vec![-3.0, -1.0, 0.0, 0.0, 0.0]);
    /// ```
    pub fn add_force(
        &self,
        u: &[f64],
        dofs: &[usize],
        g: &[f64],
        sign: f64,
        out: &mut [f64],
    ) -> Result<()> {
        self.check_u(u)?;
        check_len("g", dofs.len(), g.len())?;
        check_len("out", self.n_u, out.len())?;
        let mut t = [(0usize, 0.0f64); MAX_TERMS];
        for (&qi, gk) in dofs.iter().zip(g) {
            check_index("dofs", qi, self.n_q)?;
            let n = self.row_at(qi, u, &mut t);
            for &(j, c) in &t[..n] {
                out[j] += sign * c * gk;
            }
        }
        Ok(())
    }

    /// Adds `sign · Tᵀ H T` into `sink`, for a matrix `h` (row-major,
    /// `dofs.len()²`) over the coordinates `dofs` (at most [`MAX_DOFS`]): the
    /// scatter of an element's stiffness.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for sizes that do not fit,
    /// [`Error::IndexOutOfRange`] for a coordinate `>= n_q`.
    ///
    /// # Example
    /// ```
    /// use softrod::structure::{BlockRule, DofMap, Triplets};
    /// let map = DofMap::new(vec![
    ///     BlockRule::Affine { offset: vec![0.0, 0.0, 1.0, 0.0], directions: vec![vec![0.0, 0.0, 1.0, 0.0]] },
    ///     BlockRule::Free { len: 4 },
    /// ]).unwrap();
    /// // a 2 × 2 matrix over the base slope x and node 1's x
    /// let mut k = Triplets::new(map.n_u());
    /// map.add_stiffness(&[], &[2, 4], &[2.0, -1.0, -1.0, 2.0], 1.0, &mut k).unwrap();
    /// let k = k.to_dense();
    /// assert_eq!((k[(0, 0)], k[(0, 1)], k[(1, 1)]), (2.0, -1.0, 2.0));
    /// ```
    pub fn add_stiffness<S: StiffnessSink + ?Sized>(
        &self,
        u: &[f64],
        dofs: &[usize],
        h: &[f64],
        sign: f64,
        sink: &mut S,
    ) -> Result<()> {
        self.check_u(u)?;
        let size = dofs.len();
        if size > MAX_DOFS {
            check_len("dofs", MAX_DOFS, size)?;
        }
        check_len("h", size * size, h.len())?;
        let mut rows = [[(0usize, 0.0f64); MAX_TERMS]; MAX_DOFS];
        let mut counts = [0usize; MAX_DOFS];
        for ((&qi, r), n) in dofs.iter().zip(rows.iter_mut()).zip(counts.iter_mut()) {
            check_index("dofs", qi, self.n_q)?;
            *n = self.row_at(qi, u, r);
        }
        for a in 0..size {
            for b in 0..size {
                for &(i, ci) in &rows[a][..counts[a]] {
                    for &(j, cj) in &rows[b][..counts[b]] {
                        sink.add(i, j, sign * ci * cj * h[a * size + b]);
                    }
                }
            }
        }
        Ok(())
    }

    /// Adds `value · T_iᵀ T_j` into `sink` (`T_i` row `i` of `T(u)`): one
    /// entry of a stiffness over all coordinates, mapped to the free ones
    /// (how a force field's stiffness reaches the tangent).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a nonlinear map and a `u` of the
    /// wrong size, [`Error::IndexOutOfRange`] for a coordinate `>= n_q`.
    pub fn add_stiffness_entry<S: StiffnessSink + ?Sized>(
        &self,
        u: &[f64],
        i: usize,
        j: usize,
        value: f64,
        sink: &mut S,
    ) -> Result<()> {
        self.check_u(u)?;
        check_index("i", i, self.n_q)?;
        check_index("j", j, self.n_q)?;
        let mut ri = [(0usize, 0.0f64); MAX_TERMS];
        let mut rj = [(0usize, 0.0f64); MAX_TERMS];
        let ni = self.row_at(i, u, &mut ri);
        let nj = self.row_at(j, u, &mut rj);
        for &(a, ca) in &ri[..ni] {
            for &(b, cb) in &rj[..nj] {
                sink.add(a, b, ca * cb * value);
            }
        }
        Ok(())
    }

    /// Adds `Σ_i g_i ∂²φ_i/∂u²` into `sink` for a vector `g` over all
    /// coordinates: with `g = ∂Π/∂q` the gradient of the total potential,
    /// the term of the tangent `K_u = Tᵀ K T + Σ_i g_i ∂²φ_i/∂u²` that a
    /// nonlinear map adds (nothing for a linear map).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `u` or `g` has the wrong size.
    ///
    /// # Example
    /// ```
    /// use softrod::structure::{rigid::PlanarAttachment, BlockRule, DofMap};
    /// // a node on a free planar body: a force g on the node's position
    /// // stiffens the body's turn by −g·n (n = R(θ) p)
    /// let map = DofMap::new(vec![
    ///     BlockRule::PlanarRigidEnd { body_block: 1,
    ///         attachment: PlanarAttachment { point_m: [0.1, 0.0], direction: [0.0, 1.0] } },
    ///     BlockRule::Free { len: 3 },
    /// ]).unwrap();
    /// let u = [0.0, 0.0, 0.0, 0.0]; // stretch, x, y, θ
    /// let g = [-2.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0];
    /// let mut k = nalgebra::DMatrix::zeros(4, 4);
    /// map.add_geometric_stiffness(&u, &g, &mut k).unwrap();
    /// assert!((k[(3, 3)] - 0.2).abs() < 1e-15);
    /// ```
    pub fn add_geometric_stiffness<S: StiffnessSink + ?Sized>(
        &self,
        u: &[f64],
        g: &[f64],
        sink: &mut S,
    ) -> Result<()> {
        if self.linear {
            return Ok(());
        }
        check_len("u", self.n_u, u.len())?;
        check_len("g", self.n_q, g.len())?;
        for b in &self.blocks {
            if let BlockRule::PlanarRigidEnd { attachment, .. } = &b.rule {
                let (pose, s) = self.pose(b, u);
                let gb = [g[b.q0], g[b.q0 + 1], g[b.q0 + 2], g[b.q0 + 3]];
                let c = attachment.curvature(pose, s, gb);
                let th = b.pose_u + 2;
                sink.add(th, th, c[0][0]);
                sink.add(th, b.u0, c[0][1]);
                sink.add(b.u0, th, c[1][0]);
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests;
