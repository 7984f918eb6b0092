//! The known loads of a rod that act at arc positions between nodes:
//! concentrated moments ([`crate::loads::PointMoment`]), through the
//! virtual node of [`crate::loads::point_moment`]; and line loads with
//! breakpoints (a [`crate::loads::LineLoad::Tabulated`]), integrated piece
//! by piece.

use super::{MAX_EDOF, Rod, add_shape_force};
use crate::element::{ArcPoint, Element};
use crate::error::{Error, Result, check_all_finite, check_len};
use crate::loads::point_moment::{
    add_point_moment_work, has_cable_layout, point_moment_work_between,
};
use crate::loads::{LineLoad, Loads, outside};

impl<E: Element> Rod<E> {
    /// Adds the generalized forces `∫ Sᵀ w dX` of the line load `l` into
    /// `f` (all of the rod's coordinates). Each element is integrated by the
    /// 5-point Gauss rule (exact to degree 9), split at the profile's
    /// breakpoints inside it: a piecewise-linear table times a cubic shape
    /// function is a quartic on each piece, integrated exactly.
    pub(super) fn add_line_load(&self, l: &LineLoad, f: &mut [f64]) {
        let nd = E::NODE_DOFS;
        let total = self.length();
        let cuts = l.breakpoints();
        // the load per length at a quadrature point (validated: E::DIM
        // components, at most 3)
        let mut w = [0.0; 3];
        let w = &mut w[..E::DIM.min(3)];
        for (e, el) in self.elements.iter().enumerate() {
            let le = el.length();
            let x0 = self.node_s[e];
            let Some(out) = f.get_mut(e * nd..(e + 2) * nd) else {
                return;
            };
            if cuts.is_empty() {
                for (xi, wt) in self.line_rule.iter() {
                    l.at_into(x0 + xi * le, total, w);
                    add_shape_force(el, xi, w, wt * le, out);
                }
                continue;
            }
            let x1 = x0 + le;
            let inner = cuts.iter().copied().filter(|&c| c > x0 && c < x1);
            let mut a = x0;
            for b in inner.chain(std::iter::once(x1)) {
                let h = b - a;
                for (xi, wt) in self.line_rule.iter() {
                    let x = a + xi * h;
                    l.at_into(x, total, w);
                    add_shape_force(el, (x - x0) / le, w, wt * h, out);
                }
                a = b;
            }
        }
    }

    /// The point of the moment `i` at `s` (m), or the error naming
    /// `point_moments[i].s_m`.
    fn point_moment_at(&self, i: usize, s: f64) -> Result<ArcPoint> {
        ArcPoint::locate(self.node_arc(), s)
            .ok_or_else(|| outside(&format!("point_moments[{i}].s_m"), s, self.length()))
    }

    /// Value checks of the moments at arc positions: finite components, on
    /// the rod, and beyond the start if it is clamped.
    pub(super) fn validate_point_moments(&self, loads: &Loads, clamped_start: bool) -> Result<()> {
        for (i, m) in loads.point_moments.iter().enumerate() {
            crate::error::named(
                |n| check_all_finite(n, &m.moment_nm),
                || format!("point_moments[{i}].moment_nm"),
            )?;
            self.point_moment_at(i, m.s_m)?;
            if clamped_start && m.s_m <= 0.0 {
                return Err(Error::invalid(
                    format!("point_moments[{i}].s_m"),
                    m.s_m,
                    "the clamped base takes no moment: must be > 0",
                ));
            }
        }
        Ok(())
    }

    /// The checks the assembly of the moments at arc positions depends on:
    /// a cable's node layout and `MOMENT_DIM` components each.
    pub(super) fn check_point_moment_structure(&self, loads: &Loads) -> Result<()> {
        if loads.point_moments.is_empty() {
            return Ok(());
        }
        if !has_cable_layout::<E>() {
            return Err(Error::invalid(
                "point_moments",
                format!("DIM = {}, NODE_DOFS = {}", E::DIM, E::NODE_DOFS),
                "a moment at an arc position needs a cable element (nodes [r, r'])",
            ));
        }
        for (i, m) in loads.point_moments.iter().enumerate() {
            if m.moment_nm.len() != E::MOMENT_DIM {
                check_len(
                    &format!("point_moments[{i}].moment_nm"),
                    E::MOMENT_DIM,
                    m.moment_nm.len(),
                )?;
            }
        }
        Ok(())
    }

    /// Calls `f(e, grad, hess)` for every moment at an arc position: `e` the
    /// element holding it, `grad` and `hess` (row-major; empty unless
    /// `hessian`) the derivatives of its work `M · θ(s)` with respect to
    /// the element's `2 NODE_DOFS` coordinates, at the rod configuration
    /// `q` (`n_q` numbers) with rotations measured from the node
    /// `reference`. `loads` must have passed `check_load_structure`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a moment off the rod, and what `f`
    /// returns.
    pub(crate) fn for_each_point_moment(
        &self,
        reference: &[f64],
        q: &[f64],
        loads: &Loads,
        hessian: bool,
        mut f: impl FnMut(usize, &[f64], &[f64]) -> Result<()>,
    ) -> Result<()> {
        if loads.point_moments.is_empty() {
            return Ok(());
        }
        check_len("q", self.n_q(), q.len())?;
        let n = 2 * E::NODE_DOFS;
        let mut g = [0.0; MAX_EDOF];
        let mut h = [0.0; MAX_EDOF * MAX_EDOF];
        let nh = if hessian { n * n } else { 0 };
        for (i, m) in loads.point_moments.iter().enumerate() {
            let p = self.point_moment_at(i, m.s_m)?;
            let (g, h) = (&mut g[..n], &mut h[..nh]);
            g.fill(0.0);
            h.fill(0.0);
            add_point_moment_work::<E>(
                &p,
                reference,
                q,
                &m.moment_nm,
                g,
                hessian.then_some(&mut *h),
            );
            f(p.element, g, h)?;
        }
        Ok(())
    }

    /// The work of the moments at arc positions while the rod moves from
    /// `from` to `to` (J; rotations below π), measured from `reference`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for configurations of the wrong size,
    /// [`Error::InvalidParameter`] for a moment off the rod.
    pub(crate) fn point_moment_work_between(
        &self,
        reference: &[f64],
        from: &[f64],
        to: &[f64],
        loads: &Loads,
    ) -> Result<f64> {
        if loads.point_moments.is_empty() {
            return Ok(0.0);
        }
        check_len("q", self.n_q(), from.len())?;
        check_len("q", self.n_q(), to.len())?;
        let mut w = 0.0;
        for (i, m) in loads.point_moments.iter().enumerate() {
            let p = self.point_moment_at(i, m.s_m)?;
            w += point_moment_work_between::<E>(&p, reference, from, to, &m.moment_nm);
        }
        Ok(w)
    }
}
