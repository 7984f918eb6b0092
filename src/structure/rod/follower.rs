//! The follower loads of a planar rod ([`crate::loads::FollowerLoad`]):
//! their checks, their generalized force `Q = C q` element by element, its
//! stiffness, and its work along a straight path.

use super::Rod;
use crate::element::{Element, hermite};
use crate::error::{Error, Result};
use crate::loads::Loads;
use crate::loads::follower::shape_slope_gram;

/// Element coordinates of a planar cable (2 nodes × `[x, y, x', y']`).
const EDOF: usize = 8;

impl<E: Element> Rod<E> {
    /// Value checks of the follower loads (pressure finite, interval on
    /// the rod and not empty).
    pub(super) fn validate_followers(&self, loads: &Loads) -> Result<()> {
        for (i, f) in loads.follower_loads.iter().enumerate() {
            crate::error::named(
                |n| f.validate(n, self.length()),
                || format!("follower_loads[{i}]"),
            )?;
        }
        Ok(())
    }

    /// The check the assembly of follower loads depends on: a planar cable.
    pub(super) fn check_follower_structure(&self, loads: &Loads) -> Result<()> {
        if loads.follower_loads.is_empty() || (E::DIM == 2 && E::NODE_DOFS == 4) {
            return Ok(());
        }
        Err(Error::invalid(
            "follower_loads",
            format!("{} loads", loads.follower_loads.len()),
            "a pressure normal to the backbone needs a planar robot (planar_cable): in 3-D \
             the normal is not defined by the backbone alone",
        ))
    }

    /// Calls `f(e, m)` for every element a follower load touches, with
    /// `m = ∂Q_e/∂q_e` (8 × 8, row-major, not symmetric): the element's
    /// generalized force is `Q_e = m q_e` and its stiffness `−m`. `loads`
    /// must have passed [`Rod::check_load_structure`]; nothing is called
    /// for a rod that is not a planar cable.
    pub(crate) fn for_each_follower_element(
        &self,
        loads: &Loads,
        mut f: impl FnMut(usize, &[f64; EDOF * EDOF]) -> Result<()>,
    ) -> Result<()> {
        if loads.follower_loads.is_empty() || E::DIM != 2 || E::NODE_DOFS != 4 {
            return Ok(());
        }
        let total = self.length();
        let mut m = [0.0; EDOF * EDOF];
        for (e, el) in self.elements.iter().enumerate() {
            let le = el.length();
            let (x0, x1) = (self.node_s[e], self.node_s[e] + le);
            m.fill(0.0);
            let mut touched = false;
            for load in &loads.follower_loads {
                let (a, b) = load.interval(total);
                let (lo, hi) = (a.max(x0) - x0, b.min(x1) - x0);
                if hi <= lo {
                    continue;
                }
                touched = true;
                let p = load.pressure_n_per_m;
                let c = shape_slope_gram(
                    |xi| {
                        let (s, d1, _) = hermite(xi, le);
                        (s, d1)
                    },
                    &self.line_rule,
                    le,
                    lo,
                    hi,
                );
                // Q[k, x] = −p Σ_l C_kl q[l, y], Q[k, y] = p Σ_l C_kl q[l, x]
                for (k, ck) in c.iter().enumerate() {
                    for (l, ckl) in ck.iter().enumerate() {
                        m[(2 * k) * EDOF + 2 * l + 1] -= p * ckl;
                        m[(2 * k + 1) * EDOF + 2 * l] += p * ckl;
                    }
                }
            }
            if touched {
                f(e, &m)?;
            }
        }
        Ok(())
    }

    /// The work of the follower loads while the rod moves along the
    /// straight path from `from` to `to` (J): `Q` is linear in `q`, so the
    /// trapezoid `½ (Q(from) + Q(to)) · (to − from)` is exact. (A follower
    /// load has no potential: the work depends on the path.)
    pub(crate) fn follower_work_between(
        &self,
        from: &[f64],
        to: &[f64],
        loads: &Loads,
    ) -> Result<f64> {
        let mut w = 0.0;
        self.for_each_follower_element(loads, |e, m| {
            let (Some(a), Some(b)) = (from.get(4 * e..4 * e + EDOF), to.get(4 * e..4 * e + EDOF))
            else {
                return Ok(());
            };
            for i in 0..EDOF {
                let qi: f64 = (0..EDOF).map(|j| m[i * EDOF + j] * (a[j] + b[j])).sum();
                w += 0.5 * qi * (b[i] - a[i]);
            }
            Ok(())
        })?;
        Ok(w)
    }
}
