//! What an equilibrium solver needs of a model, in its free coordinates:
//! the one trait both the clamped robot (`crate::assembly::Robot`, its impl
//! there) and a
//! multi-body [`Structure`] implement.
//!
//! A model has free coordinates `u` and all coordinates `q = φ(u)` (a
//! linear clamp map for the robot, rigid ends for a structure); its
//! equilibrium (17) is `R(u) = T(u)ᵀ Q(φ(u)) = 0` with the tangent
//! `K_u = −∂R/∂u` assembled on a sparsity pattern fixed by the model's
//! connectivity, and `R = −∂Π/∂u` for the total potential `Π`, the merit
//! function of a line search.

use std::sync::Arc;

use nalgebra::DVector;

use super::{Structure, StructureLoads, Triplets};
use crate::element::Element;
use crate::error::{check_len, Error, Result};
use crate::linsolve::{SymmetricMatrix, SymmetricPattern};

/// A model whose equilibrium a static solver finds in the free coordinates
/// `u`, with `q = φ(u)`.
///
/// Every method that takes `u` and `q` expects `q = φ(u)` (the solver
/// computes it once per iterate with [`Assembled::configuration_into`]); a
/// model reads whichever is cheaper for it.
///
/// # Example
/// ```
/// use softrod::assembly::{RobotSpec, Section};
/// use softrod::linsolve::SymmetricMatrix;
/// use softrod::loads::Loads;
/// use softrod::structure::Assembled;
/// fn residual_norm<M: Assembled>(m: &M, loads: &M::Loads) -> softrod::Result<f64> {
///     let u = m.reference_free_coordinates();
///     let mut q = vec![0.0; m.n_q()];
///     m.configuration_into(u.as_slice(), &mut q)?;
///     let dead = m.dead_force(loads)?;
///     let mut r = vec![0.0; m.n_free()];
///     let mut k = SymmetricMatrix::zeros(m.tangent_pattern()?);
///     m.residual_and_tangent_into(u.as_slice(), &q, dead.as_slice(), loads, &mut r, &mut k)?;
///     Ok(r.iter().fold(0.0f64, |a, v| a.max(v.abs())))
/// }
/// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
/// // straight under its own weight: not in equilibrium
/// assert!(residual_norm(&robot, &Loads::default())? > 0.0);
/// # Ok::<(), softrod::Error>(())
/// ```
pub trait Assembled {
    /// The model's loads.
    type Loads: Clone;

    /// Number of free coordinates `n_u`.
    fn n_free(&self) -> usize;

    /// Number of coordinates `n_q`.
    fn n_q(&self) -> usize;

    /// `q = φ(u)` into `q`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    fn configuration_into(&self, u: &[f64], q: &mut [f64]) -> Result<()>;

    /// The free coordinates of the straight, unstressed reference (where a
    /// solve starts by default).
    fn reference_free_coordinates(&self) -> DVector<f64>;

    /// Checks that `loads` fit the model.
    ///
    /// # Errors
    /// A typed error naming the field at fault.
    fn validate_loads(&self, loads: &Self::Loads) -> Result<()>;

    /// The dead forces over all coordinates (N): self-weight and the known
    /// configuration-independent loads.
    ///
    /// # Errors
    /// As the model's load checks.
    fn dead_force(&self, loads: &Self::Loads) -> Result<DVector<f64>>;

    /// `loads` scaled by `factor` (a load step).
    fn scaled_loads(&self, loads: &Self::Loads, factor: f64) -> Self::Loads;

    /// `T(u)ᵀ f` for a force `f` over all coordinates into `out` (the dead
    /// force seen by the free coordinates: the scale of a residual).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    fn restrict_into(&self, u: &[f64], f: &[f64], out: &mut [f64]) -> Result<()>;

    /// The residual `R(u)` (N) into `out`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    fn residual_into(
        &self,
        u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &Self::Loads,
        out: &mut [f64],
    ) -> Result<()>;

    /// The residual into `out` and the tangent `K_u = −∂R/∂u` into `k`
    /// (put on [`Assembled::tangent_pattern`] if it is on another).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    fn residual_and_tangent_into(
        &self,
        u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &Self::Loads,
        out: &mut [f64],
        k: &mut SymmetricMatrix,
    ) -> Result<()>;

    /// `Π(to) − Π(from)` (J).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    #[allow(clippy::too_many_arguments)]
    fn potential_change(
        &self,
        from_u: &[f64],
        from_q: &[f64],
        to_u: &[f64],
        to_q: &[f64],
        dead: &[f64],
        loads: &Self::Loads,
    ) -> Result<f64>;

    /// The sparsity pattern of the tangent over the free coordinates (what a
    /// solver analyzes once).
    ///
    /// # Errors
    /// [`Error::TooLarge`] if it cannot be stored.
    fn tangent_pattern(&self) -> Result<Arc<SymmetricPattern>>;

    /// The free coordinates of a start configuration `q` over all
    /// coordinates: the `u` whose `φ(u)` is `q` when `q` lies on the map,
    /// else the map's nearest (the clamp keeps its prescribed base and
    /// takes the stretch along its free direction; a rigid end takes its
    /// body's pose and the stretch along the joint's direction).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a `q` of the wrong size.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let u = robot.reference_free_coordinates();
    /// let mut q = vec![0.0; robot.n_q()];
    /// robot.configuration_into(u.as_slice(), &mut q)?;
    /// assert_eq!(robot.free_coordinates_of(&q)?, u);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn free_coordinates_of(&self, q: &[f64]) -> Result<DVector<f64>>;

    /// Where a solve without a start point starts: the straight reference
    /// ([`Assembled::reference_free_coordinates`]) unless the model knows a
    /// closer guess for `loads` (the robot: the arcs of its actuation).
    ///
    /// # Errors
    /// As [`Assembled::validate_loads`].
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// // without actuation the arcs are straight: the reference
    /// let u = robot.start_free_coordinates(&softrod::loads::Loads::default())?;
    /// assert_eq!(u, robot.reference_free_coordinates());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn start_free_coordinates(&self, loads: &Self::Loads) -> Result<DVector<f64>> {
        self.validate_loads(loads)?;
        Ok(self.reference_free_coordinates())
    }

    /// The applied generalized forces over the free coordinates into `out`
    /// (N): `T(u)ᵀ` of the dead forces plus the actuation and the
    /// concentrated moments at `q` (not the elastic or force-field terms).
    /// Their norm is the scale of a relative residual tolerance.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let loads = softrod::loads::Loads::default();
    /// let (u, q) = (robot.reference_free_coordinates().as_slice().to_vec(), robot.reference_configuration().as_slice().to_vec());
    /// let dead = robot.dead_force(&loads)?;
    /// let mut f = vec![0.0; robot.n_free()];
    /// robot.applied_force_into(&u, &q, dead.as_slice(), &loads, &mut f)?;
    /// // a weightless robot without loads: nothing applied
    /// assert!(f.iter().all(|v| *v == 0.0));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn applied_force_into(
        &self,
        u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &Self::Loads,
        out: &mut [f64],
    ) -> Result<()>;

    /// The tangent alone into `k` (the residual is not needed). By default
    /// [`Assembled::residual_and_tangent_into`] with the residual dropped.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let loads = softrod::loads::Loads::default();
    /// let (u, q) = (robot.reference_free_coordinates().as_slice().to_vec(), robot.reference_configuration().as_slice().to_vec());
    /// let dead = robot.dead_force(&loads)?;
    /// let mut k = softrod::linsolve::SymmetricMatrix::zeros(Assembled::tangent_pattern(&robot)?);
    /// Assembled::tangent_into(&robot, &u, &q, dead.as_slice(), &loads, &mut k)?;
    /// assert!(k.get(1, 1) > 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn tangent_into(
        &self,
        u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &Self::Loads,
        k: &mut SymmetricMatrix,
    ) -> Result<()> {
        let mut r = vec![0.0; self.n_free()];
        self.residual_and_tangent_into(u, q, dead, loads, &mut r, k)
    }

    /// A step `du` of the free coordinates mapped to all coordinates,
    /// `dq = T(u) du`, into `dq`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// // a step of the base stretch turns into a step of the base slope
    /// let mut du = vec![0.0; robot.n_free()];
    /// du[0] = 0.01;
    /// let mut dq = vec![0.0; robot.n_q()];
    /// robot.step_into(robot.reference_free_coordinates().as_slice(), &du, &mut dq)?;
    /// assert_eq!(dq[2], 0.01);
    /// assert_eq!(robot.step_rotation(&dq), 0.01);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn step_into(&self, u: &[f64], du: &[f64], dq: &mut [f64]) -> Result<()>;

    /// The point `u + s du` into `u_to` and its configuration into `q_to`,
    /// for a step `du` with `dq = T(u) du` ([`Assembled::step_into`]) from
    /// `u` with `q = φ(u)`. By default `q_to = φ(u + s du)`; a model whose
    /// map is affine may move along the step instead, `q_to = q + s dq` (the
    /// same point up to round-off).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let (u, q) = (robot.reference_free_coordinates().as_slice().to_vec(), robot.reference_configuration().as_slice().to_vec());
    /// let mut du = vec![0.0; robot.n_free()];
    /// du[2] = 0.01; // node 1's y
    /// let mut dq = vec![0.0; robot.n_q()];
    /// robot.step_into(&u, &du, &mut dq)?;
    /// let (mut u1, mut q1) = (u.clone(), q.clone());
    /// robot.advance_into(&u, &q, &du, &dq, 0.5, &mut u1, &mut q1)?;
    /// assert_eq!(q1[5], 0.005);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    #[allow(clippy::too_many_arguments)]
    fn advance_into(
        &self,
        u: &[f64],
        q: &[f64],
        du: &[f64],
        dq: &[f64],
        s: f64,
        u_to: &mut [f64],
        q_to: &mut [f64],
    ) -> Result<()> {
        let _ = (q, dq);
        check_len("u", self.n_free(), u.len())?;
        check_len("du", self.n_free(), du.len())?;
        check_len("u", self.n_free(), u_to.len())?;
        for ((v, a), b) in u_to.iter_mut().zip(u).zip(du) {
            *v = a + s * b;
        }
        self.configuration_into(u_to, q_to)
    }

    /// The largest rotation a step `dq` over all coordinates makes (rad,
    /// roughly): the largest change of a rod node's slope `r'` (unit length
    /// at rest) or of a rigid body's angle. A solver caps it per step.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// // node 2's slope turns by 0.1, its position moves by 0.3 m
    /// let mut dq = vec![0.0; robot.n_q()];
    /// dq[8] = 0.3;
    /// dq[11] = 0.1;
    /// assert_eq!(robot.step_rotation(&dq), 0.1);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn step_rotation(&self, dq: &[f64]) -> f64;

    /// A length of the model (m): the scale of a step tolerance (the
    /// robot's length, the total length of a structure's rods).
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// assert_eq!(robot.length_m(), 0.2);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn length_m(&self) -> f64;

    /// Energies at `q` that [`Assembled::potential_change_from`] may reuse
    /// into `out` (a line search tries several steps from one point; the
    /// robot keeps its element energies). By default none.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a `q` of the wrong size.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let mut e = Vec::new();
    /// robot.energies_into(robot.reference_configuration().as_slice(), &mut e)?;
    /// // one per element, nothing stored at rest (up to round-off)
    /// assert!(e.len() == 4 && e.iter().all(|v| v.abs() < 1e-20));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn energies_into(&self, q: &[f64], out: &mut Vec<f64>) -> Result<()> {
        let _ = q;
        out.clear();
        Ok(())
    }

    /// Whether `loads` derive from a potential (default: yes). A follower
    /// load does not: the symmetric tangent the solvers factor is then not
    /// the stability of the equilibrium, and the static solver neither
    /// checks nor reports it.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::loads::{FollowerLoad, Loads};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// assert!(robot.conservative(&Loads::default()));
    /// let f = FollowerLoad { pressure_n_per_m: -1.0, s_start_m: None, s_end_m: None };
    /// assert!(!robot.conservative(&Loads { follower_loads: vec![f], ..Loads::default() }));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn conservative(&self, loads: &Self::Loads) -> bool {
        let _ = loads;
        true
    }

    /// Mesh sequencing: a coarser model of the same body with `loads`
    /// carried over, whose equilibrium ([`Assembled::prolong`] onto this
    /// model) starts a cold static solve; `None`, the default, when the
    /// model has none (a robot: [`crate::assembly::Robot::coarsened`]).
    ///
    /// # Errors
    /// As [`Assembled::validate_loads`] and the model's construction.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]).build_planar()?;
    /// // coarse enough already
    /// assert!(robot.coarse_model(&softrod::loads::Loads::default())?.is_none());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn coarse_model(&self, loads: &Self::Loads) -> Result<Option<(Self, Self::Loads)>>
    where
        Self: Sized,
    {
        let _ = loads;
        Ok(None)
    }

    /// The free coordinates of this model interpolating the configuration
    /// `q_coarse` of `coarse` (from [`Assembled::coarse_model`]).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (field `coarse`) for a model without
    /// a coarse one (the default); a robot's as
    /// [`crate::assembly::Robot::prolong_from`].
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 64)]).build_planar()?;
    /// let (coarse, _) = robot.coarse_model(&softrod::loads::Loads::default())?.unwrap();
    /// let u = robot.prolong(&coarse, coarse.reference_configuration().as_slice())?;
    /// let straight = robot.reference_free_coordinates();
    /// assert!(u.iter().zip(straight.iter()).all(|(a, b)| (a - b).abs() < 1e-14));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn prolong(&self, coarse: &Self, q_coarse: &[f64]) -> Result<DVector<f64>>
    where
        Self: Sized,
    {
        let _ = (coarse, q_coarse);
        Err(Error::invalid(
            "coarse",
            "a model",
            "this model has no coarse mesh",
        ))
    }

    /// [`Assembled::potential_change`] given what
    /// [`Assembled::energies_into`] wrote at `from`. By default the
    /// energies are not read.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let loads = softrod::loads::Loads::default();
    /// let (u, q) = (robot.reference_free_coordinates().as_slice().to_vec(), robot.reference_configuration().as_slice().to_vec());
    /// let dead = robot.dead_force(&loads)?;
    /// let (mut u1, mut q1) = (u.clone(), q.clone());
    /// u1[2] += 1e-3;
    /// q1[5] += 1e-3; // node 1 lifted: bending stores energy
    /// let mut e = Vec::new();
    /// robot.energies_into(&q, &mut e)?;
    /// let d = Assembled::potential_change_from(&robot, &u, &q, &e, &u1, &q1, dead.as_slice(), &loads)?;
    /// assert!(d > 0.0 && d == Assembled::potential_change(&robot, &u, &q, &u1, &q1, dead.as_slice(), &loads)?);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    #[allow(clippy::too_many_arguments)]
    fn potential_change_from(
        &self,
        from_u: &[f64],
        from_q: &[f64],
        from_energies: &[f64],
        to_u: &[f64],
        to_q: &[f64],
        dead: &[f64],
        loads: &Self::Loads,
    ) -> Result<f64> {
        let _ = from_energies;
        self.potential_change(from_u, from_q, to_u, to_q, dead, loads)
    }
}

impl<E: Element> Assembled for Structure<E> {
    type Loads = StructureLoads;

    fn n_free(&self) -> usize {
        Structure::n_free(self)
    }

    fn n_q(&self) -> usize {
        Structure::n_q(self)
    }

    fn configuration_into(&self, u: &[f64], q: &mut [f64]) -> Result<()> {
        self.dof_map().configuration_into(u, q)
    }

    fn reference_free_coordinates(&self) -> DVector<f64> {
        DVector::from_column_slice(Structure::reference_free_coordinates(self))
    }

    fn validate_loads(&self, loads: &StructureLoads) -> Result<()> {
        Structure::validate_loads(self, loads)
    }

    fn dead_force(&self, loads: &StructureLoads) -> Result<DVector<f64>> {
        Structure::dead_force(self, loads)
    }

    fn scaled_loads(&self, loads: &StructureLoads, factor: f64) -> StructureLoads {
        loads.scaled(factor)
    }

    fn restrict_into(&self, u: &[f64], f: &[f64], out: &mut [f64]) -> Result<()> {
        self.dof_map().restrict_into(u, f, out)
    }

    fn residual_into(
        &self,
        u: &[f64],
        _q: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
        out: &mut [f64],
    ) -> Result<()> {
        check_len("residual", Structure::n_free(self), out.len())?;
        out.copy_from_slice(Structure::residual(self, u, dead, loads)?.as_slice());
        Ok(())
    }

    fn residual_and_tangent_into(
        &self,
        u: &[f64],
        _q: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
        out: &mut [f64],
        k: &mut SymmetricMatrix,
    ) -> Result<()> {
        let mut t = Triplets::new(Structure::n_free(self));
        Structure::residual_and_tangent_into(self, u, dead, loads, out, &mut t)?;
        let pattern = if k.n() == t.n() {
            k.pattern().clone()
        } else {
            Assembled::tangent_pattern(self)?
        };
        symmetric_from_triplets(&t, &pattern, k)
    }

    fn potential_change(
        &self,
        from_u: &[f64],
        _from_q: &[f64],
        to_u: &[f64],
        _to_q: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
    ) -> Result<f64> {
        Structure::potential_change(self, from_u, to_u, dead, loads)
    }

    /// The entries the assembly writes at the reference (each element's,
    /// each joined block's, each force field's coordinates through the map,
    /// whatever their values): the pattern of every tangent of this
    /// structure.
    fn free_coordinates_of(&self, q: &[f64]) -> Result<DVector<f64>> {
        self.dof_map().free_coordinates_of(q)
    }

    fn applied_force_into(
        &self,
        u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &StructureLoads,
        out: &mut [f64],
    ) -> Result<()> {
        Structure::applied_force_into(self, u, q, dead, loads, out)
    }

    fn step_into(&self, u: &[f64], du: &[f64], dq: &mut [f64]) -> Result<()> {
        self.dof_map().expand_into(u, du, dq)
    }

    fn step_rotation(&self, dq: &[f64]) -> f64 {
        let (nd, d) = (E::NODE_DOFS, E::DIM);
        let nodes = self.n_rod_nodes() * nd;
        let slopes = dq
            .get(..nodes)
            .unwrap_or(&[])
            .chunks(nd)
            .flat_map(|node| node.get(d..2 * d).unwrap_or(&[]))
            .fold(0.0f64, |m, v| m.max(v.abs()));
        // the bodies' angles: a planar pose is (x, y, θ), a 3-D one (x, ψ)
        let angles = (0..self.spec().rigid_bodies.len())
            .filter_map(|b| self.body_coordinates(b).ok())
            .filter_map(|r| match r.len() {
                3 => dq.get(r.start + 2..r.start + 3),
                6 => dq.get(r.start + 3..r.start + 6),
                _ => None,
            })
            .flatten()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        slopes.max(angles)
    }

    fn length_m(&self) -> f64 {
        self.rods().iter().map(|r| r.length()).sum()
    }

    fn tangent_pattern(&self) -> Result<Arc<SymmetricPattern>> {
        let u = Structure::reference_free_coordinates(self);
        let loads = StructureLoads::default();
        let dead = vec![0.0; Structure::n_q(self)];
        let mut r = vec![0.0; Structure::n_free(self)];
        let mut t = Triplets::new(Structure::n_free(self));
        Structure::residual_and_tangent_into(self, u, &dead, &loads, &mut r, &mut t)?;
        Ok(Arc::new(pattern_of(&t)?))
    }
}

/// The symmetric pattern holding every entry of `t` (and its mirror).
pub(crate) fn pattern_of(t: &Triplets) -> Result<SymmetricPattern> {
    let mut pairs: Vec<[usize; 2]> = t
        .entries()
        .iter()
        .filter(|e| e.0 != e.1)
        .map(|&(i, j, _)| [i.min(j), i.max(j)])
        .collect();
    pairs.sort_unstable();
    pairs.dedup();
    SymmetricPattern::from_elements(t.n(), &pairs)
}

/// `k = (T + Tᵀ)/2` for the entries `t` (the symmetric part: a tangent
/// that is symmetric up to round-off), on `pattern`.
///
/// # Errors
/// [`Error::InvalidParameter`] (field `tangent`) for an entry outside the
/// pattern (a force field whose coupling changes with the configuration).
pub(crate) fn symmetric_from_triplets(
    t: &Triplets,
    pattern: &Arc<SymmetricPattern>,
    k: &mut SymmetricMatrix,
) -> Result<()> {
    if Arc::ptr_eq(k.pattern(), pattern) {
        k.fill_zero();
    } else {
        *k = SymmetricMatrix::zeros(pattern.clone());
    }
    for &(i, j, v) in t.entries() {
        let w = if i == j { v } else { 0.5 * v };
        if !k.add_if_present(i, j, w) {
            return Err(Error::invalid(
                "tangent",
                format!("({i}, {j})"),
                "entry outside the structure's tangent pattern",
            ));
        }
    }
    Ok(())
}
