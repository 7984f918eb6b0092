//! The equilibrium (17) of a structure in its free coordinates.
//!
//! With `Π(q)` the total potential (elastic energy, minus the work of the
//! dead loads, the actuation (18) and the concentrated moments, plus every
//! force field) and `g = ∂Π/∂q = −Q`, the residual over the free
//! coordinates is `R(u) = −T(u)ᵀ g(φ(u))` and the tangent
//! `K_u = −∂R/∂u = Tᵀ (∂²Π/∂q²) T + Σ_i g_i ∂²φ_i/∂u²`.
//!
//! Assembly is by connectivity: every element gathers its coordinates from
//! its two nodes, adds its gradient into `g` and its Hessian through the
//! rows of `T` of its coordinates (a shift where both nodes are free); the
//! second term of the tangent comes from the blocks of the map that are
//! nonlinear (rod ends on rigid bodies), once `g` is complete.

use nalgebra::DVector;

use super::rigid::Attachment;
use super::{BlockRule, Structure, StructureLoads, Triplets};
use crate::element::Element;
use crate::error::{Error, Result, check_all_finite, check_index, check_len};
use crate::loads::Loads;
use crate::loads::force_field::StiffnessSink;
use crate::structure::dofmap::DofMap;
use crate::structure::rod::MAX_EDOF;

/// What a rod end exerts on the rigid body it is joined to, about the
/// body's reference point (world axes): the body-pose part of `Tᵀ Q` at the
/// joined node, `Q` the node's generalized force (elastic, plus the loads
/// and moments applied at the node).
///
/// At equilibrium the reactions on a body and the body's own load (weight,
/// [`super::BodyLoad`]) sum to zero.
///
/// # Example
/// ```
/// use nalgebra::dvector;
/// let r = softrod::structure::JointReaction { joint: 0, body: 0, force_n: dvector![0.0, 0.1], moment_nm: dvector![0.0] };
/// assert_eq!(r.force_n.len(), 2);
/// assert_eq!(r.force::<2>()?, nalgebra::Vector2::new(0.0, 0.1));
/// assert_eq!(r.moment::<1>()?[0], 0.0);
/// assert!(r.force::<3>().is_err());
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct JointReaction {
    /// The joint (index in the spec's `joints`).
    pub joint: usize,
    /// The rigid body.
    pub body: usize,
    /// Force on the body (N; 2 or 3 components, the structure's
    /// dimension: a dynamic vector because a structure is generic over its
    /// element; [`JointReaction::force`] gives a fixed-size one).
    pub force_n: DVector<f64>,
    /// Moment on the body about its reference point (N·m; one number in 2-D,
    /// three in 3-D; [`JointReaction::moment`]).
    pub moment_nm: DVector<f64>,
}

impl JointReaction {
    /// The force as a fixed-size vector of dimension `D` (N).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `force_n` if the structure has
    /// another dimension.
    ///
    /// # Example
    /// See [`JointReaction`].
    pub fn force<const D: usize>(&self) -> Result<nalgebra::SVector<f64, D>> {
        crate::numeric::fixed("force_n", self.force_n.as_slice())
    }

    /// The moment as a fixed-size vector of `M` components (N·m; 1 in 2-D,
    /// 3 in 3-D).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `moment_nm` for another count.
    ///
    /// # Example
    /// See [`JointReaction`].
    pub fn moment<const M: usize>(&self) -> Result<nalgebra::SVector<f64, M>> {
        crate::numeric::fixed("moment_nm", self.moment_nm.as_slice())
    }
}

/// A sink that maps entries over all coordinates to the free coordinates.
struct Mapped<'a, S: ?Sized> {
    dofs: &'a DofMap,
    u: &'a [f64],
    sink: &'a mut S,
    error: Option<Error>,
}

impl<S: StiffnessSink + ?Sized> StiffnessSink for Mapped<'_, S> {
    fn add(&mut self, row: usize, col: usize, value: f64) {
        if let Err(e) = self
            .dofs
            .add_stiffness_entry(self.u, row, col, value, self.sink)
        {
            self.error.get_or_insert(e);
        }
    }
}

impl<E: Element> Structure<E> {
    /// The loads of rod `i`, if `loads` lists any.
    fn rod_loads<'a>(&self, loads: &'a StructureLoads, i: usize) -> Option<&'a Loads> {
        loads.rods.get(i)
    }

    /// Checks that `loads` fit this structure.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] (field `loads.rods`) unless there are no
    /// rod loads or one per rod; each rod's loads as
    /// [`super::Rod::validate_loads`] with the path `loads.rods[i].`
    /// prefixed (a moment at a clamped start is refused); for body loads,
    /// [`Error::IndexOutOfRange`] (`loads.bodies[k].body`),
    /// [`Error::DimensionMismatch`] and [`Error::InvalidParameter`] for
    /// wrong sizes and non-finite values.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::structure::{BodyLoad, RodSpec, StructureLoads, StructureSpec};
    /// let s = StructureSpec::new(vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)],
    ///     nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(1.0, 0.0))], vec![], vec![]).build_planar().unwrap();
    /// let bad = StructureLoads { bodies: vec![BodyLoad { body: 0, force_n: vec![], moment_nm: vec![] }], ..Default::default() };
    /// assert_eq!(s.validate_loads(&bad).unwrap_err().field(), Some("loads.bodies[0].body"));
    /// ```
    pub fn validate_loads(&self, loads: &StructureLoads) -> Result<()> {
        self.check_load_structure(loads)?;
        for (i, l) in loads.rods.iter().enumerate() {
            let clamped = matches!(self.spec.rods[i].start, super::EndSupport::Clamped { .. });
            self.rods[i]
                .validate_loads_with(l, clamped)
                .map_err(|e| e.with_prefix(&format!("loads.rods[{i}].")))?;
        }
        for (k, b) in loads.bodies.iter().enumerate() {
            check_all_finite(&format!("loads.bodies[{k}].force_n"), &b.force_n)?;
            check_all_finite(&format!("loads.bodies[{k}].moment_nm"), &b.moment_nm)?;
        }
        Ok(())
    }

    /// The checks that indexing depends on (sizes, indices), without the
    /// value checks: they run on every residual.
    fn check_load_structure(&self, loads: &StructureLoads) -> Result<()> {
        if !loads.rods.is_empty() {
            check_len("loads.rods", self.rods.len(), loads.rods.len())?;
        }
        for (i, (rod, l)) in self.rods.iter().zip(&loads.rods).enumerate() {
            rod.check_load_structure(l)
                .map_err(|e| e.with_prefix(&format!("loads.rods[{i}].")))?;
        }
        let n_bodies = self.spec.rigid_bodies.len();
        for (k, b) in loads.bodies.iter().enumerate() {
            if b.body >= n_bodies {
                check_index(&format!("loads.bodies[{k}].body"), b.body, n_bodies)?;
            }
            if !b.force_n.is_empty() && b.force_n.len() != E::DIM {
                check_len(
                    &format!("loads.bodies[{k}].force_n"),
                    E::DIM,
                    b.force_n.len(),
                )?;
            }
            if !b.moment_nm.is_empty() && b.moment_nm.len() != E::MOMENT_DIM {
                check_len(
                    &format!("loads.bodies[{k}].moment_nm"),
                    E::MOMENT_DIM,
                    b.moment_nm.len(),
                )?;
            }
        }
        Ok(())
    }

    /// The dead (configuration-independent) generalized forces over all
    /// coordinates: every rod's self-weight and loads ([`super::Rod::dead_force`]),
    /// every body's weight `m g` and its [`super::BodyLoad`]s (N, N·m).
    ///
    /// # Errors
    /// As [`Structure::validate_loads`]; [`Error::NonFinite`] if the forces
    /// overflow.
    pub fn dead_force(&self, loads: &StructureLoads) -> Result<DVector<f64>> {
        self.validate_loads(loads)?;
        let nd = E::NODE_DOFS;
        let mut f = DVector::zeros(self.n_q());
        for (i, rod) in self.rods.iter().enumerate() {
            let local = match self.rod_loads(loads, i) {
                Some(l) => rod.dead_force(l)?,
                None => DVector::from_column_slice(rod.gravity_force()),
            };
            let q0 = self.rod_node0[i] * nd;
            for (a, b) in f.as_mut_slice()[q0..q0 + local.len()]
                .iter_mut()
                .zip(local.iter())
            {
                *a += b;
            }
        }
        for (b, body) in self.spec.rigid_bodies.iter().enumerate() {
            let r = self.body_coordinates(b)?;
            for (k, g) in self.spec.gravity_m_per_s2.iter().enumerate() {
                f[r.start + k] += body.mass_kg * g;
            }
        }
        for l in &loads.bodies {
            let r = self.body_coordinates(l.body)?;
            for (k, v) in l.force_n.iter().enumerate() {
                f[r.start + k] += v;
            }
            for (k, v) in l.moment_nm.iter().enumerate() {
                f[r.start + E::DIM + k] += v;
            }
        }
        if f.iter().any(|v: &f64| !v.is_finite()) {
            return Err(Error::NonFinite {
                context: "dead forces of the structure (loads too large or too narrow)".into(),
            });
        }
        Ok(f)
    }

    /// Adds `sign · Tᵀ H T` for an element or node matrix over the
    /// coordinates `idx`: a plain shift where every node is a free block.
    fn scatter_stiffness(
        &self,
        u: &[f64],
        idx: &[usize],
        h: &[f64],
        sign: f64,
        k: &mut Triplets,
    ) -> Result<()> {
        let nd = E::NODE_DOFS;
        let n = idx.len();
        let mut free = [0usize; MAX_EDOF];
        let mut shift = n > 0 && n <= MAX_EDOF && n.is_multiple_of(nd);
        for (c, chunk) in idx.chunks(nd).enumerate() {
            if !shift {
                break;
            }
            match self.dofs.contiguous_free(chunk[0], nd) {
                Some(u0) => (0..nd).for_each(|a| free[c * nd + a] = u0 + a),
                None => shift = false,
            }
        }
        if !shift {
            return self.dofs.add_stiffness(u, idx, h, sign, k);
        }
        for a in 0..n {
            for b in 0..n {
                k.add(free[a], free[b], sign * h[a * n + b]);
            }
        }
        Ok(())
    }

    /// `g = ∂Π/∂q` at `q = φ(u)` (all coordinates), and, if `k` is given,
    /// `Tᵀ (∂²Π/∂q²) T` added into it. Sizes are checked by the callers.
    fn gradient(
        &self,
        u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
        mut k: Option<&mut Triplets>,
    ) -> Result<Vec<f64>> {
        let nd = E::NODE_DOFS;
        let edof = 2 * nd;
        let mut g = vec![0.0; self.n_q()];
        let mut ge = [0.0; MAX_EDOF];
        let mut qe = [0.0; MAX_EDOF];
        let mut idx = [0usize; MAX_EDOF];
        let mut he = vec![0.0; if k.is_some() { edof * edof } else { 0 }];
        for el in &self.connectivity {
            let element = &self.rods[el.rod].elements()[el.local];
            for (c, &node) in el.nodes.iter().enumerate() {
                for a in 0..nd {
                    idx[c * nd + a] = node * nd + a;
                    qe[c * nd + a] = q[node * nd + a];
                }
            }
            let ge = &mut ge[..edof];
            ge.fill(0.0);
            if let Some(k) = k.as_mut() {
                he.fill(0.0);
                element.add_energy_gradient_and_hessian(&qe[..edof], ge, &mut he);
                self.scatter_stiffness(u, &idx[..edof], &he, 1.0, k)?;
            } else {
                element.add_energy_gradient(&qe[..edof], ge);
            }
            for (i, v) in idx[..edof].iter().zip(ge.iter()) {
                g[*i] += v;
            }
        }
        for (gi, di) in g.iter_mut().zip(dead) {
            *gi -= di;
        }
        // actuation (18) and concentrated moments: Π −= M θ at their nodes
        let mut mg = [0.0; MAX_EDOF];
        let mut mh = vec![0.0; nd * nd];
        for (i, rod) in self.rods.iter().enumerate() {
            let Some(l) = self.rod_loads(loads, i) else {
                continue;
            };
            let node0 = self.rod_node0[i];
            let reference = &self.rod_reference[i];
            rod.for_each_node_moment(l, |node, m| {
                let start = (node0 + node) * nd;
                let mg = &mut mg[..nd];
                mg.fill(0.0);
                mh.fill(0.0);
                E::add_moment_work(reference, &q[start..start + nd], m, mg, &mut mh);
                for (gi, v) in g[start..start + nd].iter_mut().zip(mg.iter()) {
                    *gi -= v;
                }
                if let Some(k) = k.as_mut() {
                    let mut node_idx = [0usize; MAX_EDOF];
                    (0..nd).for_each(|a| node_idx[a] = start + a);
                    self.scatter_stiffness(u, &node_idx[..nd], &mh, -1.0, k)?;
                }
                Ok(())
            })?;
        }
        // force fields: Π += V
        if !self.fields.is_empty() {
            let mut f = vec![0.0; self.n_q()];
            for field in &self.fields {
                field.add_force(q, &mut f);
                if let Some(k) = k.as_mut() {
                    let mut sink = Mapped {
                        dofs: &self.dofs,
                        u,
                        sink: &mut **k,
                        error: None,
                    };
                    field.add_stiffness(q, &mut sink);
                    if let Some(e) = sink.error {
                        return Err(e);
                    }
                }
            }
            for (gi, fi) in g.iter_mut().zip(&f) {
                *gi -= fi;
            }
        }
        Ok(g)
    }

    fn check_sizes(&self, u: &[f64], dead: &[f64], loads: &StructureLoads) -> Result<()> {
        check_len("u", self.n_free(), u.len())?;
        check_len("dead force", self.n_q(), dead.len())?;
        self.check_load_structure(loads)
    }

    /// The residual `R(u) = T(u)ᵀ Q(φ(u))` of the equilibrium (17) over the
    /// free coordinates (N): dead forces `dead` (from
    /// [`Structure::dead_force`]), minus the elastic gradient, plus the
    /// actuation and moments, minus the gradient of every force field.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes, the structural errors
    /// of [`Structure::validate_loads`].
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::structure::{BodyLoad, JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureLoads, StructureSpec};
    /// let spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(0.0, 1.0))],
    ///     vec![RigidBodySpec { mass_kg: 0.1, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![JointSpec::RodToBody { rod: 0, end: RodEnd::End, body: 0, point_m: None, direction: None }],
    /// );
    /// let s = spec.build_planar().unwrap();
    /// let loads = StructureLoads::default();
    /// let dead = s.dead_force(&loads).unwrap();
    /// let u = s.reference_free_coordinates();
    /// // straight and unstressed: only the body's weight is unbalanced
    /// let r = s.residual(u, dead.as_slice(), &loads).unwrap();
    /// let y = s.body_free_coordinates(0).unwrap().start + 1;
    /// assert!((r[y] + 0.1 * 9.81).abs() < 1e-12);
    /// ```
    pub fn residual(
        &self,
        u: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
    ) -> Result<DVector<f64>> {
        self.check_sizes(u, dead, loads)?;
        let q = self.dofs.configuration_vec(u)?;
        let g = self.gradient(u, &q, dead, loads, None)?;
        let mut r = DVector::zeros(self.n_free());
        self.dofs.restrict_into(u, &g, r.as_mut_slice())?;
        Ok(-r)
    }

    /// The residual and the tangent `K_u = −∂R/∂u = Tᵀ K T + Σ_i g_i
    /// ∂²φ_i/∂u²` (`K = ∂²Π/∂q²`, `g = ∂Π/∂q`) at `u`, the tangent as a
    /// list of entries (`tangent` is reset to `n_free × n_free`). The
    /// tangent depends on the dead loads through the second term.
    ///
    /// # Errors
    /// As [`Structure::residual`].
    pub fn residual_and_tangent_into(
        &self,
        u: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
        residual: &mut [f64],
        tangent: &mut Triplets,
    ) -> Result<()> {
        self.check_sizes(u, dead, loads)?;
        check_len("residual", self.n_free(), residual.len())?;
        let q = self.dofs.configuration_vec(u)?;
        tangent.reset(self.n_free());
        let g = self.gradient(u, &q, dead, loads, Some(tangent))?;
        self.dofs.add_geometric_stiffness(u, &g, tangent)?;
        self.dofs.restrict_into(u, &g, residual)?;
        residual.iter_mut().for_each(|v| *v = -*v);
        Ok(())
    }

    /// As [`Structure::residual_and_tangent_into`], into new buffers.
    ///
    /// # Errors
    /// As [`Structure::residual`].
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::structure::{BodyLoad, JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureLoads, StructureSpec};
    /// let spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(0.0, 1.0))],
    ///     vec![RigidBodySpec { mass_kg: 0.1, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![JointSpec::RodToBody { rod: 0, end: RodEnd::End, body: 0, point_m: None, direction: None }],
    /// );
    /// let s = spec.build_planar().unwrap();
    /// let loads = StructureLoads::default();
    /// let dead = s.dead_force(&loads).unwrap();
    /// let u = s.reference_free_coordinates();
    /// let (r, k) = s.residual_and_tangent(u, dead.as_slice(), &loads).unwrap();
    /// let k = k.to_dense();
    /// assert_eq!(k.nrows(), s.n_free());
    /// assert!((k.clone() - k.transpose()).amax() < 1e-9 * k.amax());
    /// ```
    pub fn residual_and_tangent(
        &self,
        u: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
    ) -> Result<(DVector<f64>, Triplets)> {
        let mut r = DVector::zeros(self.n_free());
        let mut k = Triplets::new(self.n_free());
        self.residual_and_tangent_into(u, dead, loads, r.as_mut_slice(), &mut k)?;
        Ok((r, k))
    }

    /// Change of the total potential `Π` from the free coordinates `from`
    /// to `to` (J): elastic energy, minus the work of the dead forces, the
    /// actuation and the moments, plus the force fields' potentials.
    /// `R = −∂Π/∂u`: the merit of a line search.
    ///
    /// # Errors
    /// As [`Structure::residual`].
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::structure::{BodyLoad, JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureLoads, StructureSpec};
    /// let spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(0.0, 1.0))],
    ///     vec![RigidBodySpec { mass_kg: 0.1, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![JointSpec::RodToBody { rod: 0, end: RodEnd::End, body: 0, point_m: None, direction: None }],
    /// );
    /// let s = spec.build_planar().unwrap();
    /// let loads = StructureLoads::default();
    /// let dead = s.dead_force(&loads).unwrap();
    /// let u = s.reference_free_coordinates();
    /// // lowering the body by δ = 1 mm (its joined end with it) releases m g δ
    /// // ≈ 1 mJ and squeezes the rod's last element, whose end slopes stay
    /// // (strain −6 (δ/L_e) ξ (1 − ξ)): ½ EA L_e (6 δ/L_e)² / 30 = 3.6 mJ
    /// let mut down = u.to_vec();
    /// down[s.body_free_coordinates(0).unwrap().start + 1] -= 1e-3;
    /// let d = s.potential_change(u, &down, dead.as_slice(), &loads).unwrap();
    /// let expected = 0.5 * 300.0 * 0.05 * (6.0 * 1e-3 / 0.05f64).powi(2) / 30.0 - 0.1 * 9.81 * 1e-3;
    /// assert!((d - expected).abs() < 1e-12);
    /// ```
    pub fn potential_change(
        &self,
        from: &[f64],
        to: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
    ) -> Result<f64> {
        self.check_sizes(from, dead, loads)?;
        check_len("u", self.n_free(), to.len())?;
        let nd = E::NODE_DOFS;
        let (q0, q1) = (
            self.dofs.configuration_vec(from)?,
            self.dofs.configuration_vec(to)?,
        );
        let mut d = 0.0;
        let (mut a, mut b) = ([0.0; MAX_EDOF], [0.0; MAX_EDOF]);
        for el in &self.connectivity {
            let element = &self.rods[el.rod].elements()[el.local];
            for (c, &node) in el.nodes.iter().enumerate() {
                a[c * nd..(c + 1) * nd].copy_from_slice(&q0[node * nd..(node + 1) * nd]);
                b[c * nd..(c + 1) * nd].copy_from_slice(&q1[node * nd..(node + 1) * nd]);
            }
            d += element.energy(&b[..2 * nd]) - element.energy(&a[..2 * nd]);
        }
        for ((x0, x1), f) in q0.iter().zip(&q1).zip(dead) {
            d -= f * (x1 - x0);
        }
        for (i, rod) in self.rods.iter().enumerate() {
            let Some(l) = self.rod_loads(loads, i) else {
                continue;
            };
            let node0 = self.rod_node0[i];
            let reference = &self.rod_reference[i];
            rod.for_each_node_moment(l, |node, m| {
                let r = (node0 + node) * nd..(node0 + node + 1) * nd;
                d -= E::moment_work_between(reference, &q0[r.clone()], &q1[r], m);
                Ok(())
            })?;
        }
        for field in &self.fields {
            d += field.energy(&q1) - field.energy(&q0);
        }
        Ok(d)
    }

    /// The applied generalized forces over the free coordinates at `u`
    /// (`q = φ(u)`) into `out` (N): `T(u)ᵀ` of the dead forces `dead` plus
    /// the actuation and the concentrated moments, without the elastic and
    /// force-field terms. Its norm is the load scale of a static solve.
    ///
    /// # Errors
    /// As [`Structure::residual`]; [`Error::DimensionMismatch`] for a `q`
    /// or `out` of the wrong size.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::loads::{Loads, PointForce};
    /// use softrod::structure::{RodSpec, StructureLoads, StructureSpec};
    /// let mut spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(1.0, 0.0))],
    ///     vec![], vec![],
    /// );
    /// spec.gravity_m_per_s2 = vec![0.0, 0.0];
    /// let s = spec.build_planar().unwrap();
    /// let tip = Loads { point_forces: vec![PointForce { s_m: 0.2, force_n: vec![0.0, -0.5] }], ..Loads::default() };
    /// let loads = StructureLoads { rods: vec![tip], ..StructureLoads::default() };
    /// let dead = s.dead_force(&loads).unwrap();
    /// let u = s.reference_free_coordinates();
    /// let q = s.configuration(u).unwrap();
    /// let mut f = vec![0.0; s.n_free()];
    /// s.applied_force_into(u, q.as_slice(), dead.as_slice(), &loads, &mut f).unwrap();
    /// // the tip force on the tip node's y (free coordinate 1 + 3·4 + 1), nothing else
    /// assert_eq!(f[14], -0.5);
    /// assert_eq!(f.iter().map(|v| v.abs()).sum::<f64>(), 0.5);
    /// ```
    pub fn applied_force_into(
        &self,
        u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
        out: &mut [f64],
    ) -> Result<()> {
        self.check_sizes(u, dead, loads)?;
        check_len("q", self.n_q(), q.len())?;
        check_len("out", self.n_free(), out.len())?;
        let nd = E::NODE_DOFS;
        let mut f = dead.to_vec();
        let mut mg = [0.0; MAX_EDOF];
        let mut mh = vec![0.0; nd * nd];
        for (i, rod) in self.rods.iter().enumerate() {
            let Some(l) = self.rod_loads(loads, i) else {
                continue;
            };
            let node0 = self.rod_node0[i];
            let reference = &self.rod_reference[i];
            rod.for_each_node_moment(l, |node, m| {
                let start = (node0 + node) * nd;
                let mg = &mut mg[..nd];
                mg.fill(0.0);
                E::add_moment_work(reference, &q[start..start + nd], m, mg, &mut mh);
                for (fi, v) in f[start..start + nd].iter_mut().zip(mg.iter()) {
                    *fi += v;
                }
                Ok(())
            })?;
        }
        self.dofs.restrict_into(u, &f, out)
    }

    /// The generalized force `Q = −∂Π/∂q` over all coordinates at `φ(u)`
    /// (N, N·m): zero on free coordinates at equilibrium only through `Tᵀ`;
    /// on a clamped node its position entries are what the rod pushes on the
    /// clamp (minus the clamp's reaction).
    ///
    /// # Errors
    /// As [`Structure::residual`].
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::structure::{BodyLoad, JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureLoads, StructureSpec};
    /// let spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(0.0, 1.0))],
    ///     vec![RigidBodySpec { mass_kg: 0.1, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![JointSpec::RodToBody { rod: 0, end: RodEnd::End, body: 0, point_m: None, direction: None }],
    /// );
    /// let s = spec.build_planar().unwrap();
    /// let loads = StructureLoads::default();
    /// let dead = s.dead_force(&loads).unwrap();
    /// let u = s.reference_free_coordinates();
    /// // the straight reference: only the weight acts, on the body's y
    /// let f = s.generalized_force(u, dead.as_slice(), &loads).unwrap();
    /// let b = s.body_coordinates(0).unwrap();
    /// assert!((f[b.start + 1] + 0.1 * 9.81).abs() < 1e-12 && f[0].abs() < 1e-12);
    /// ```
    pub fn generalized_force(
        &self,
        u: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
    ) -> Result<DVector<f64>> {
        self.check_sizes(u, dead, loads)?;
        let q = self.dofs.configuration_vec(u)?;
        let g = self.gradient(u, &q, dead, loads, None)?;
        Ok(-DVector::from_vec(g))
    }

    /// The wrench every rod end exerts on the rigid body it is joined to
    /// (one [`JointReaction`] per rod-to-body joint, in joint order).
    ///
    /// # Errors
    /// As [`Structure::residual`].
    ///
    /// # Example
    /// ```
    /// use softrod::statics::StaticSolver;
    /// use softrod::assembly::Section;
    /// use softrod::structure::{BodyLoad, JointSpec, RigidBodySpec, RodEnd, RodSpec, StructureLoads, StructureSpec};
    /// let spec = StructureSpec::new(
    ///     vec![RodSpec::clamped(vec![Section::uniform(0.2, 300.0, 0.02, 4)], nalgebra::Vector2::new(0.0, 0.0), nalgebra::Vector2::new(0.0, 1.0))],
    ///     vec![RigidBodySpec { mass_kg: 0.1, position_m: vec![0.0, 0.2], orientation_rad: vec![0.0] }],
    ///     vec![JointSpec::RodToBody { rod: 0, end: RodEnd::End, body: 0, point_m: None, direction: None }],
    /// );
    /// let s = spec.build_planar().unwrap();
    /// let loads = StructureLoads::default();
    /// let dead = s.dead_force(&loads).unwrap();
    /// let u = s.reference_free_coordinates();
    /// let eq = StaticSolver::default().solve(&s, &loads, None).unwrap();
    /// let r = s.joint_reactions(eq.u.as_slice(), dead.as_slice(), &loads).unwrap();
    /// // the rod holds the body up: its reaction carries the weight
    /// assert!((r[0].force_n[1] - 0.1 * 9.81).abs() < 1e-9);
    /// ```
    pub fn joint_reactions(
        &self,
        u: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
    ) -> Result<Vec<JointReaction>> {
        self.check_sizes(u, dead, loads)?;
        let nd = E::NODE_DOFS;
        let q = self.dofs.configuration_vec(u)?;
        let g = self.gradient(u, &q, dead, loads, None)?;
        let mut out = Vec::with_capacity(self.joints.len());
        for (j, node) in &self.joints {
            let b = self.body_coordinates(j.body)?;
            let block = *node;
            let stretch = match (self.dofs.rule(block), self.dofs.free(block)) {
                (
                    Some(
                        BlockRule::PlanarRigidEnd { .. }
                        | BlockRule::SpatialRigidEnd { .. }
                        | BlockRule::Affine { .. },
                    ),
                    Some(r),
                ) if !r.is_empty() => u[r.start],
                _ => 0.0,
            };
            let s = node * nd;
            let f: Vec<f64> = g[s..s + nd].iter().map(|v| -v).collect();
            let (force_n, moment_nm) = match &j.attachment {
                Attachment::Planar(a) => {
                    let pose = [q[b.start], q[b.start + 1], q[b.start + 2]];
                    let w = a.wrench(pose, stretch, [f[0], f[1], f[2], f[3]]);
                    (vec![w[0], w[1]], vec![w[2]])
                }
                Attachment::Spatial(a) => {
                    let pose: [f64; 6] = std::array::from_fn(|k| q[b.start + k]);
                    let w = a.wrench(pose, stretch, &f);
                    (w[..3].to_vec(), w[3..].to_vec())
                }
            };
            out.push(JointReaction {
                joint: j.joint,
                body: j.body,
                force_n: DVector::from_vec(force_n),
                moment_nm: DVector::from_vec(moment_nm),
            });
        }
        Ok(out)
    }
}
