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

use super::strategy::{MeshSequencing, SolverHints, Stepping};
use super::{Structure, StructureLoads, Triplets};
use crate::element::Element;
use crate::error::{Error, Result, check_len};
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
    /// The model's loads: a load set that can be scaled (a load step).
    type Loads: ModelLoads;

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
}

/// A model's load set: what a load step scales and whether it derives from a
/// potential.
///
/// # Example
/// ```
/// use softrod::loads::{FollowerLoad, Loads};
/// use softrod::structure::ModelLoads;
/// let loads = Loads { pressures_pa: vec![1e4], ..Loads::default() };
/// assert_eq!(ModelLoads::scaled(&loads, 0.5).pressures_pa, vec![5e3]);
/// assert!(loads.conservative());
/// let f = FollowerLoad { pressure_n_per_m: -1.0, s_start_m: None, s_end_m: None };
/// assert!(!Loads { follower_loads: vec![f], ..Loads::default() }.conservative());
/// ```
pub trait ModelLoads: Clone {
    /// The loads scaled by `factor` (a load step).
    fn scaled(&self, factor: f64) -> Self;

    /// Whether the loads derive from a potential (default: yes). A follower
    /// load does not: the symmetric tangent the solvers factor is then not
    /// the stability of the equilibrium, and the static solver neither
    /// checks nor reports it.
    fn conservative(&self) -> bool {
        true
    }
}

/// Everything a static solver and the layers above it (the warm tracker,
/// sensitivities, estimators) take of a model: its equilibrium
/// ([`Assembled`]), how to step in it ([`Stepping`]), its shortcuts
/// ([`SolverHints`]) and mesh sequencing ([`MeshSequencing`]). Implemented
/// for every type that implements those.
pub trait Model: SolverHints + MeshSequencing {}

impl<M: SolverHints + MeshSequencing> Model for M {}

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

impl<E: Element> Stepping for Structure<E> {
    fn free_coordinates_of(&self, q: &[f64]) -> Result<DVector<f64>> {
        self.dof_map().free_coordinates_of(q)
    }

    fn restrict_into(&self, u: &[f64], f: &[f64], out: &mut [f64]) -> Result<()> {
        self.dof_map().restrict_into(u, f, out)
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
}

/// The applied force: the dead forces, the actuation and the concentrated
/// moments through the joints' map.
impl<E: Element> SolverHints for Structure<E> {
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
}

/// No coarse mesh of a structure.
impl<E: Element> MeshSequencing for Structure<E> {}

impl ModelLoads for StructureLoads {
    fn scaled(&self, factor: f64) -> StructureLoads {
        StructureLoads::scaled(self, factor)
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
