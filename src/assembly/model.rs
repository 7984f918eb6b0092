//! [`Assembled`] for the clamped robot: the equilibrium solvers see a
//! [`Robot`] through the same trait as a multi-body structure.

use std::sync::Arc;

use super::Robot;
use crate::element::Element;
use crate::error::Result;
use crate::linsolve::{SymmetricMatrix, SymmetricPattern};
use crate::loads::Loads;
use crate::structure::Assembled;

impl<E: Element> Assembled for Robot<E> {
    type Loads = Loads;

    fn n_free(&self) -> usize {
        Robot::n_free(self)
    }

    fn n_q(&self) -> usize {
        Robot::n_q(self)
    }

    fn configuration_into(&self, u: &[f64], q: &mut [f64]) -> Result<()> {
        self.dof_map().configuration_into(u, q)
    }

    fn reference_free_coordinates(&self) -> Vec<f64> {
        // the clamp's free directions at zero, the nodes where they lie
        let q = self.reference_configuration();
        let mut u = vec![0.0; self.n_base_free()];
        u.extend_from_slice(q.get(E::NODE_DOFS..).unwrap_or(&[]));
        u
    }

    fn validate_loads(&self, loads: &Loads) -> Result<()> {
        Robot::validate_loads(self, loads)
    }

    fn dead_force(&self, loads: &Loads) -> Result<Vec<f64>> {
        Robot::dead_force(self, loads)
    }

    fn scaled_loads(&self, loads: &Loads, factor: f64) -> Loads {
        loads.scaled(factor)
    }

    fn restrict_into(&self, _u: &[f64], f: &[f64], out: &mut [f64]) -> Result<()> {
        Robot::restrict_into(self, f, out)
    }

    fn residual_into(
        &self,
        _u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &Loads,
        out: &mut [f64],
    ) -> Result<()> {
        Robot::residual_into(self, q, dead, loads, out)
    }

    fn residual_and_tangent_into(
        &self,
        _u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &Loads,
        out: &mut [f64],
        k: &mut SymmetricMatrix,
    ) -> Result<()> {
        Robot::residual_and_tangent_into(self, q, dead, loads, out, k)
    }

    fn potential_change(
        &self,
        _from_u: &[f64],
        from_q: &[f64],
        _to_u: &[f64],
        to_q: &[f64],
        dead: &[f64],
        loads: &Loads,
    ) -> Result<f64> {
        Robot::potential_change(self, from_q, to_q, dead, loads)
    }

    fn tangent_pattern(&self) -> Result<Arc<SymmetricPattern>> {
        Ok(Robot::tangent_pattern(self).clone())
    }
}
