//! Models driven by chamber pressures: what the inverse kinematics and the
//! pressure sensitivities (43) need of a model beyond its equilibrium.
//!
//! The pressures of a model are one vector: the clamped robot's chambers in
//! section order; a [`Structure`]'s rod after rod, each in its section
//! order (the parallel robot's leg-major order). A chamber's pressure acts
//! through the moments of (17), which turn with the rod, so `Q(q, P)` is
//! linear in `P` at a fixed shape and its derivative is the applied force
//! of unit pressures.

use nalgebra::DMatrix;

use super::{Model, Structure, StructureLoads};
use crate::element::Element;
use crate::error::{Result, check_len};
use crate::loads::Loads;

/// A model whose chambers' pressures are inputs.
///
/// # Example
/// ```
/// use softrod::structure::Actuated;
/// let robot = softrod::scene::Scene::two_section().robot()?;
/// assert_eq!(Actuated::pressure_bounds(&robot).len(), 4);
/// let parallel = softrod::parallel::ParallelSpec::default().build_cable()?;
/// let s = parallel.structure();
/// assert_eq!(s.pressure_bounds().len(), parallel.spec().n_pressures());
/// let loads = s.with_pressures(&Default::default(), &vec![1e3; 18]);
/// assert_eq!(s.pressures_of(&loads), vec![1e3; 18]);
/// # Ok::<(), softrod::Error>(())
/// ```
pub trait Actuated: Model<Loads: Default> {
    /// The `(min, max)` bounds of every pressure (Pa), in the model's order.
    fn pressure_bounds(&self) -> Vec<(f64, f64)>;

    /// The pressures of `loads` (Pa; empty where the loads set none).
    fn pressures_of(&self, loads: &Self::Loads) -> Vec<f64>;

    /// The loads `known` with the pressures `p` (Pa, the model's order,
    /// [`Actuated::pressure_bounds`]'s length) in place of theirs; a `p` of
    /// another length gives loads that [`crate::structure::Assembled::validate_loads`] refuses.
    fn with_pressures(&self, known: &Self::Loads, p: &[f64]) -> Self::Loads;

    /// `∂R/∂P` (N/Pa over the free coordinates, `n_free × n_pressures`)
    /// at the configuration `u`, `q = φ(u)`: the applied force of each unit
    /// pressure, restricted by `T(u)ᵀ` (the right-hand sides of (43)).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] for wrong sizes.
    fn pressure_jacobian_free(&self, u: &[f64], q: &[f64]) -> Result<DMatrix<f64>> {
        let np = self.pressure_bounds().len();
        let n = self.n_free();
        check_len("q", self.n_q(), q.len())?;
        let zero_dead = vec![0.0; self.n_q()];
        let mut jac = DMatrix::zeros(n, np);
        let mut p = vec![0.0; np];
        for k in 0..np {
            p.iter_mut()
                .enumerate()
                .for_each(|(i, v)| *v = f64::from(u8::from(i == k)));
            let loads = self.with_pressures(&Default::default(), &p);
            self.applied_force_into(u, q, &zero_dead, &loads, jac.column_mut(k).as_mut_slice())?;
        }
        Ok(jac)
    }
}

impl<E: Element> Actuated for Structure<E> {
    fn pressure_bounds(&self) -> Vec<(f64, f64)> {
        self.rods()
            .iter()
            .flat_map(|r| r.pressure_bounds())
            .collect()
    }

    fn pressures_of(&self, loads: &StructureLoads) -> Vec<f64> {
        let mut p = Vec::new();
        for (i, rod) in self.rods().iter().enumerate() {
            match loads.rods.get(i) {
                Some(l) if l.pressures_pa.len() == rod.n_pressures() => {
                    p.extend_from_slice(&l.pressures_pa)
                }
                // a rod without pressures: none of the model's either
                _ if rod.n_pressures() > 0 => return Vec::new(),
                _ => {}
            }
        }
        p
    }

    /// A `p` of the wrong length goes whole to rod 0, whose loads' check
    /// then refuses it.
    fn with_pressures(&self, known: &StructureLoads, p: &[f64]) -> StructureLoads {
        let mut loads = known.clone();
        if loads.rods.len() < self.rods().len() {
            loads.rods.resize(self.rods().len(), Loads::default());
        }
        let total: usize = self.rods().iter().map(|r| r.n_pressures()).sum();
        if p.len() != total {
            if let Some(l) = loads.rods.first_mut() {
                l.pressures_pa = p.to_vec();
            }
            return loads;
        }
        let mut rest = p;
        for (rod, l) in self.rods().iter().zip(loads.rods.iter_mut()) {
            let (mine, tail) = rest.split_at(rod.n_pressures());
            l.pressures_pa = mine.to_vec();
            rest = tail;
        }
        loads
    }
}
