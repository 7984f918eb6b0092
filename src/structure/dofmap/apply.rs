//! The scatter side of the map: `u` from `q`, `T du`, `Tᵀ f`, `Tᵀ H T`
//! and the second-derivative term of the tangent.

use super::{BlockRule, DofMap, MAX_DOFS, MAX_TERMS};
use crate::error::{Error, Result, check_index, check_len};
use crate::loads::force_field::StiffnessSink;

impl DofMap {
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
    /// assert_eq!(map.free_coordinates_of(q.as_slice()).unwrap().as_slice(), &u[..]);
    /// ```
    pub fn free_coordinates_of(&self, q: &[f64]) -> Result<nalgebra::DVector<f64>> {
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
                BlockRule::PlanarRigidEnd { .. } | BlockRule::SpatialRigidEnd { .. } => {}
            }
        }
        // rigid ends after every pose is known
        for b in self.constrained.iter().filter_map(|&i| self.blocks.get(i)) {
            match &b.rule {
                BlockRule::PlanarRigidEnd { attachment, .. } => {
                    let theta = u.get(b.pose_u + 2).copied().unwrap_or(0.0);
                    let e = crate::structure::rigid::rotate(theta, attachment.direction.into());
                    let slope = &q[b.q0 + 2..b.q0 + 4];
                    u[b.u0] = e[0] * slope[0] + e[1] * slope[1] - 1.0;
                }
                BlockRule::SpatialRigidEnd { attachment, .. } => {
                    let psi: [f64; 3] =
                        std::array::from_fn(|k| u.get(b.pose_u + 3 + k).copied().unwrap_or(0.0));
                    u[b.u0] = attachment.stretch_of(psi, &q[b.q0..b.q0 + b.len]);
                }
                _ => {}
            }
        }
        Ok(nalgebra::DVector::from_vec(u))
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
                BlockRule::PlanarRigidEnd { .. } | BlockRule::SpatialRigidEnd { .. } => {
                    if let Some(end) = self.end_jacobian(b, u) {
                        let cols = &end.cols[..end.n_cols];
                        for (x, row) in qb.iter_mut().zip(&end.jac) {
                            *x = row.iter().zip(cols).map(|(c, &j)| c * du[j]).sum();
                        }
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
                BlockRule::PlanarRigidEnd { .. } | BlockRule::SpatialRigidEnd { .. } => {
                    out[b.u0] = 0.0
                }
            }
        }
        for b in self.constrained.iter().filter_map(|&i| self.blocks.get(i)) {
            if let Some(end) = self.end_jacobian(b, u) {
                let cols = &end.cols[..end.n_cols];
                for (row, fi) in end.jac.iter().zip(&f[b.q0..b.q0 + b.len]) {
                    for (c, &j) in row.iter().zip(cols) {
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
    ///         attachment: PlanarAttachment { point_m: nalgebra::Vector2::new(0.1, 0.0), direction: nalgebra::Vector2::y() } },
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
            match &b.rule {
                BlockRule::PlanarRigidEnd { attachment, .. } => {
                    let (pose, s) = self.pose(b, u);
                    let gb = [g[b.q0], g[b.q0 + 1], g[b.q0 + 2], g[b.q0 + 3]];
                    let c = attachment.curvature(pose, s, gb);
                    let th = b.pose_u + 2;
                    sink.add(th, th, c[0][0]);
                    sink.add(th, b.u0, c[0][1]);
                    sink.add(b.u0, th, c[1][0]);
                }
                BlockRule::SpatialRigidEnd { attachment, .. } => {
                    let (pose, s) = self.pose_3d(b, u);
                    let c = attachment.curvature(pose, s, &g[b.q0..b.q0 + b.len]);
                    let cols = [b.pose_u + 3, b.pose_u + 4, b.pose_u + 5, b.u0];
                    for (row, &i) in c.iter().zip(&cols) {
                        for (v, &j) in row.iter().zip(&cols) {
                            sink.add(i, j, *v);
                        }
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }
}
