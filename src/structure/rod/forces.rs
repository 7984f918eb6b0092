//! The known loads of a rod: their checks, the dead generalized forces,
//! the load Gram matrix `J_QF` applied to a load vector (23), and the node
//! moments of the actuation (18).

use nalgebra::{DMatrix, DVector};

use super::{Rod, add_shape_force, slot};
use crate::element::Element;
use crate::error::{Error, Result, check_all_finite, check_index, check_len, named};
use crate::loads::Loads;

impl<E: Element> Rod<E> {
    /// `J_QF F = ∫ Sᵀ S dX F` ([`Rod::load_gram`] times `f`) into `out`,
    /// element by element (`O(n)`, no allocation); the same map as
    /// `load_gram().mul_vec(f)` up to round-off.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `f` or `out` does not have `n_q` entries.
    pub fn apply_load_gram_into(&self, f: &[f64], out: &mut [f64]) -> Result<()> {
        check_len("f", self.n_q(), f.len())?;
        check_len("out", self.n_q(), out.len())?;
        let nd = E::NODE_DOFS;
        let d = E::DIM;
        out.iter_mut().for_each(|v| *v = 0.0);
        if d == 2 && nd == 4 {
            // the planar cable: pairs of components, unrolled
            for (e, m) in self.elem_gram.iter().enumerate() {
                let Ok(fe) = <&[f64; 8]>::try_from(&f[e * 4..e * 4 + 8]) else {
                    continue;
                };
                let Ok(oe) = <&mut [f64; 8]>::try_from(&mut out[e * 4..e * 4 + 8]) else {
                    continue;
                };
                for k in 0..4 {
                    let (mut x, mut y) = (0.0, 0.0);
                    for l in 0..4 {
                        x += m[k][l] * fe[2 * l];
                        y += m[k][l] * fe[2 * l + 1];
                    }
                    oe[2 * k] += x;
                    oe[2 * k + 1] += y;
                }
            }
            return Ok(());
        }
        for (e, m) in self.elem_gram.iter().enumerate() {
            for k in 0..4 {
                for i in 0..d {
                    let v: f64 = (0..4).map(|l| m[k][l] * f[e * nd + slot::<E>(l) + i]).sum();
                    out[e * nd + slot::<E>(k) + i] += v;
                }
            }
        }
        Ok(())
    }
    /// As [`Rod::apply_load_gram_into`], into a new vector.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `f` does not have `n_q` entries.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]).build_planar().unwrap();
    /// let f: Vec<f64> = (0..robot.n_q()).map(|i| (i % 5) as f64).collect();
    /// let a = robot.apply_load_gram(&f).unwrap();
    /// let b = robot.load_gram().mul_vec(&f).unwrap();
    /// assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-15));
    /// ```
    pub fn apply_load_gram(&self, f: &[f64]) -> Result<DVector<f64>> {
        let mut out = DVector::zeros(self.n_q());
        self.apply_load_gram_into(f, out.as_mut_slice())?;
        Ok(out)
    }
    /// Checks that `loads` fit this robot.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes, [`Error::InvalidParameter`]
    /// for non-finite values, points off the rod and pressures outside their
    /// bounds; [`Error::IndexOutOfRange`] for moments beyond the last node.
    pub fn validate_loads(&self, loads: &Loads) -> Result<()> {
        self.validate_all_loads(loads, false)
    }

    /// [`Rod::validate_loads`] for a rod of a [`super::Structure`],
    /// refusing moments at node 0 if `clamped_start` (a clamp takes them:
    /// they are a user's mistake). A structure does not assemble moments at
    /// arc positions yet: `point_moments` are refused, not ignored.
    pub(crate) fn validate_loads_with(&self, loads: &Loads, clamped_start: bool) -> Result<()> {
        self.validate_all_loads(loads, clamped_start)?;
        if !loads.follower_loads.is_empty() {
            return Err(Error::invalid(
                "follower_loads",
                format!("{} loads", loads.follower_loads.len()),
                "follower loads are assembled on a robot only, not yet in a structure",
            ));
        }
        if !loads.point_moments.is_empty() {
            return Err(Error::invalid(
                "point_moments",
                format!("{} moments", loads.point_moments.len()),
                "moments at arc positions are assembled on a robot only, not yet in a structure: \
                 use node_moments",
            ));
        }
        Ok(())
    }

    /// [`Rod::validate_loads`] for the rod of a clamped
    /// [`crate::assembly::Robot`]: moments at the base refused.
    pub(crate) fn validate_robot_loads(&self, loads: &Loads) -> Result<()> {
        self.validate_all_loads(loads, true)
    }

    fn validate_all_loads(&self, loads: &Loads, clamped_start: bool) -> Result<()> {
        let d = E::DIM;
        self.check_load_structure(loads)?;
        check_all_finite("pressures_pa", &loads.pressures_pa)?;
        for (i, (p, c)) in loads.pressures_pa.iter().zip(&self.chambers).enumerate() {
            if *p < c.min || *p > c.max {
                return Err(Error::invalid(
                    format!("pressures_pa[{i}]"),
                    p,
                    format!("must lie in [{}, {}] Pa", c.min, c.max),
                ));
            }
        }
        if !loads.distributed_f.is_empty() {
            check_len("distributed_f", self.n_q(), loads.distributed_f.len())?;
            check_all_finite("distributed_f", &loads.distributed_f)?;
        }
        for (i, l) in loads.line_loads.iter().enumerate() {
            let name = || format!("line_loads[{i}]");
            named(|n| l.validate(n, d), name)?;
            named(|n| l.check_on_robot(n, self.length()), name)?;
        }
        for (i, p) in loads.point_forces.iter().enumerate() {
            named(
                |n| {
                    check_len(n, d, p.force_n.len())?;
                    check_all_finite(n, &p.force_n)
                },
                || format!("point_forces[{i}].force_n"),
            )?;
            named(
                |n| self.locate(n, p.s_m),
                || format!("point_forces[{i}].s_m"),
            )?;
        }
        for (i, m) in loads.node_moments.iter().enumerate() {
            named(
                |n| check_all_finite(n, &m.moment_nm),
                || format!("node_moments[{i}].moment_nm"),
            )?;
            if clamped_start && m.node == 0 {
                return Err(Error::invalid(
                    format!("node_moments[{i}].node"),
                    m.node,
                    "the clamped base takes no moment: must be a free node, >= 1",
                ));
            }
        }
        self.validate_point_moments(loads, clamped_start)?;
        self.validate_followers(loads)
    }
    /// The checks of [`Rod::validate_loads`] that indexing depends on (the
    /// pressure count, the nodes and sizes of the moments), without the
    /// value checks: the solver evaluates scaled loads whose pressures may
    /// lie outside their bounds.
    pub(crate) fn check_load_structure(&self, loads: &Loads) -> Result<()> {
        check_len("pressures_pa", self.n_pressures(), loads.pressures_pa.len())?;
        // (names are formatted only for an error: this runs on every
        // residual and tangent)
        for (i, m) in loads.node_moments.iter().enumerate() {
            if m.moment_nm.len() != E::MOMENT_DIM {
                check_len(
                    &format!("node_moments[{i}].moment_nm"),
                    E::MOMENT_DIM,
                    m.moment_nm.len(),
                )?;
            }
            if m.node >= self.n_nodes() {
                check_index(&format!("node_moments[{i}].node"), m.node, self.n_nodes())?;
            }
        }
        self.check_point_moment_structure(loads)?;
        self.check_follower_structure(loads)
    }
    /// The dead (configuration-independent) generalized forces over all
    /// coordinates: self-weight, line loads, point forces and `J_QF F` (N).
    ///
    /// # Errors
    /// As [`Rod::validate_loads`]; [`Error::NonFinite`] if the forces
    /// overflow.
    pub fn dead_force(&self, loads: &Loads) -> Result<DVector<f64>> {
        self.validate_loads(loads)?;
        let nd = E::NODE_DOFS;
        let mut f = self.gravity_force.clone();
        for l in &loads.line_loads {
            self.add_line_load(l, &mut f);
        }
        for p in &loads.point_forces {
            let (e, xi) = self.locate("s_m", p.s_m)?;
            add_shape_force(
                &self.elements[e],
                xi,
                &p.force_n,
                1.0,
                &mut f[e * nd..(e + 2) * nd],
            );
        }
        if !loads.distributed_f.is_empty() {
            let jf = self.apply_load_gram(&loads.distributed_f)?;
            f.iter_mut().zip(jf.iter()).for_each(|(a, b)| *a += b);
        }
        // finite inputs can still overflow (huge loads, a Gaussian narrower
        // than the floating-point range resolves)
        if f.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                context: "dead forces (loads too large or too narrow)".into(),
            });
        }
        Ok(DVector::from_vec(f))
    }
    /// The section torques `M_s = Σ_c G_c P_c` (N·m): a `MOMENT_DIM ×
    /// n_sections` matrix, column `s` the torque of section `s` (pressures
    /// beyond the chambers are ignored, missing ones count as 0).
    pub fn section_torques(&self, pressures: &[f64]) -> DMatrix<f64> {
        let mut m = DMatrix::zeros(E::MOMENT_DIM, self.sections.len());
        for (c, p) in self.chambers.iter().zip(pressures) {
            for (mi, g) in m.column_mut(c.section).iter_mut().zip(&c.gain) {
                *mi += g * p;
            }
        }
        m
    }
    /// Calls `f(node, moment)` for the node moments of the actuation (each
    /// section's torque at its last node, its opposite at its first, in
    /// section order) and then the known concentrated moments, without
    /// allocating. `loads` must have passed `check_load_structure`.
    pub(crate) fn for_each_node_moment(
        &self,
        loads: &Loads,
        mut f: impl FnMut(usize, &[f64]) -> Result<()>,
    ) -> Result<()> {
        const MAX_MOMENT_DIM: usize = 3;
        let md = E::MOMENT_DIM.min(MAX_MOMENT_DIM);
        if !loads.pressures_pa.is_empty() {
            for (s, &(a, b)) in self.section_nodes.iter().enumerate() {
                // M_s = Σ_c G_c P_c over the section's chambers, in order
                let mut m = [0.0; MAX_MOMENT_DIM];
                for (c, p) in self.chambers.iter().zip(&loads.pressures_pa) {
                    if c.section == s {
                        for (mi, g) in m.iter_mut().zip(&c.gain) {
                            *mi += g * p;
                        }
                    }
                }
                if m[..md].iter().all(|v| *v == 0.0) {
                    continue;
                }
                f(b, &m[..md])?;
                let neg = m.map(|v| -v);
                f(a, &neg[..md])?;
            }
        }
        for nm in &loads.node_moments {
            f(nm.node, &nm.moment_nm)?;
        }
        Ok(())
    }
}
