//! [`Model`](crate::structure::Model) for the clamped robot: the equilibrium solvers see a
//! [`Robot`] through the same trait as a multi-body structure.

use std::sync::Arc;

use nalgebra::{DMatrix, DVector};

use super::Robot;
use crate::element::Element;
use crate::error::{Result, check_len};
use crate::linsolve::{SymmetricMatrix, SymmetricPattern};
use crate::loads::Loads;
use crate::structure::{Actuated, Assembled, MeshSequencing, ModelLoads, SolverHints, Stepping};

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

    fn reference_free_coordinates(&self) -> DVector<f64> {
        // the clamp's free directions at zero, the nodes where they lie
        let q = self.reference_configuration();
        let mut u = vec![0.0; self.n_base_free()];
        u.extend_from_slice(q.as_slice().get(E::NODE_DOFS..).unwrap_or(&[]));
        DVector::from_vec(u)
    }

    fn validate_loads(&self, loads: &Loads) -> Result<()> {
        Robot::validate_loads(self, loads)
    }

    fn dead_force(&self, loads: &Loads) -> Result<DVector<f64>> {
        Robot::dead_force(self, loads)
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

impl<E: Element> Stepping for Robot<E> {
    /// The clamp resets the base position and direction and keeps the
    /// stretch along its free direction; nodes 1 … N are taken as given.
    fn free_coordinates_of(&self, q: &[f64]) -> Result<DVector<f64>> {
        let nd = E::NODE_DOFS;
        check_len("q0", self.n_q(), q.len())?;
        let mut d = vec![0.0; self.n_q()];
        d[..nd]
            .iter_mut()
            .zip(q.iter().zip(self.base_node()))
            .for_each(|(d, (a, b))| *d = a - b);
        let stretch = self.restrict(&d)?;
        let nb = self.n_base_free();
        let mut u = Vec::with_capacity(self.n_free());
        u.extend_from_slice(&stretch.as_slice()[..nb]);
        u.extend_from_slice(&q[nd..]);
        Ok(DVector::from_vec(u))
    }

    fn restrict_into(&self, _u: &[f64], f: &[f64], out: &mut [f64]) -> Result<()> {
        Robot::restrict_into(self, f, out)
    }

    fn step_into(&self, _u: &[f64], du: &[f64], dq: &mut [f64]) -> Result<()> {
        self.expand_step_into(du, dq)
    }

    /// The clamp is affine: `q + s dq` (the arithmetic of the robot's
    /// solver since wave 1).
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
        check_len("u", self.n_free(), u.len())?;
        check_len("du", self.n_free(), du.len())?;
        check_len("u", self.n_free(), u_to.len())?;
        check_len("q", self.n_q(), q.len())?;
        check_len("dq", self.n_q(), dq.len())?;
        check_len("q", self.n_q(), q_to.len())?;
        for ((v, a), b) in u_to.iter_mut().zip(u).zip(du) {
            *v = a + s * b;
        }
        for ((v, a), b) in q_to.iter_mut().zip(q).zip(dq) {
            *v = a + s * b;
        }
        Ok(())
    }

    fn step_rotation(&self, dq: &[f64]) -> f64 {
        let (nd, d) = (E::NODE_DOFS, E::DIM);
        dq.chunks(nd)
            .flat_map(|node| node.get(d..2 * d).unwrap_or(&[]))
            .fold(0.0f64, |m, v| m.max(v.abs()))
    }

    fn length_m(&self) -> f64 {
        self.length()
    }
}

/// The chambers in section order; `∂R/∂P` by [`Robot::pressure_jacobian`]
/// (the clamp's map is linear: no `u`).
impl<E: Element> Actuated for Robot<E> {
    fn pressure_bounds(&self) -> Vec<(f64, f64)> {
        Robot::pressure_bounds(self)
    }

    fn pressures_of(&self, loads: &Loads) -> Vec<f64> {
        loads.pressures_pa.clone()
    }

    fn with_pressures(&self, known: &Loads, p: &[f64]) -> Loads {
        let mut loads = known.clone();
        loads.pressures_pa = p.to_vec();
        loads
    }

    fn pressure_jacobian_free(&self, _u: &[f64], q: &[f64]) -> Result<DMatrix<f64>> {
        self.pressure_jacobian(q)
    }
}

impl<E: Element> SolverHints for Robot<E> {
    /// The arcs of the actuation ([`Robot::arc_configuration`]).
    fn start_free_coordinates(&self, loads: &Loads) -> Result<DVector<f64>> {
        self.validate_loads(loads)?;
        // no pressure (or only zeros): the arcs of no actuation, kept by the
        // robot (the same numbers: a zero pressure adds a zero torque)
        if loads.pressures_pa.iter().all(|p| *p == 0.0)
            && let Some(u) = self.unactuated_start()
        {
            return Ok(u.clone());
        }
        self.free_coordinates_of(self.arc_configuration(&loads.pressures_pa).as_slice())
    }

    fn applied_force_into(
        &self,
        _u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &Loads,
        out: &mut [f64],
    ) -> Result<()> {
        Robot::restrict_into(self, dead, out)?;
        let mut m = vec![0.0; self.n_free()];
        self.moment_force_into(q, loads, &mut m)?;
        out.iter_mut().zip(&m).for_each(|(a, b)| *a += b);
        Ok(())
    }

    /// The robot's tangent does not depend on the dead forces.
    fn tangent_into(
        &self,
        _u: &[f64],
        q: &[f64],
        _dead: &[f64],
        loads: &Loads,
        k: &mut SymmetricMatrix,
    ) -> Result<()> {
        Robot::tangent_into(self, q, loads, k)
    }

    /// The element energies ([`Robot::element_energies_into`]).
    fn energies_into(&self, q: &[f64], out: &mut Vec<f64>) -> Result<()> {
        out.resize(self.n_elements(), 0.0);
        self.element_energies_into(q, out)
    }

    fn potential_change_from(
        &self,
        _from_u: &[f64],
        from_q: &[f64],
        from_energies: &[f64],
        _to_u: &[f64],
        to_q: &[f64],
        dead: &[f64],
        loads: &Loads,
    ) -> Result<f64> {
        Robot::potential_change_from(self, from_q, from_energies, to_q, dead, loads)
    }
}

impl<E: Element> MeshSequencing for Robot<E> {
    fn coarse_model(&self, loads: &Loads) -> Result<Option<(Self, Loads)>> {
        self.coarsened(loads)
    }

    fn prolong(&self, coarse: &Self, q_coarse: &[f64]) -> Result<DVector<f64>> {
        self.prolong_from(coarse, q_coarse)
    }
}

impl ModelLoads for Loads {
    fn scaled(&self, factor: f64) -> Loads {
        Loads::scaled(self, factor)
    }

    /// A follower load does not derive from a potential.
    fn conservative(&self) -> bool {
        self.follower_loads.is_empty()
    }
}
