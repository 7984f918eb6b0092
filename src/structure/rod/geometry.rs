//! Where things are on a rod: the straight configuration, arc positions
//! located in elements, positions along the backbone.

use nalgebra::DVector;

use super::{Rod, slot};
use crate::element::{ArcPoint, Element};
use crate::error::{Result, check_len};
use crate::loads::outside;

impl<E: Element> Rod<E> {
    /// The stress-free straight configuration from the start node at
    /// `position` (m) along the unit tangent `direction` (exact equilibrium
    /// without loads, actuation and rest curvature). Entries missing from
    /// `position` or `direction` count as 0.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::element::PlanarCable;
    /// use softrod::structure::Rod;
    /// let rod = Rod::new(&[Section::uniform(0.2, 300.0, 0.025, 4)], &[0.0, 0.0], 5, 5, "rod",
    ///     |s, le, ax, be| PlanarCable::with_rules(le, s.ea_n, s.ei_nm2, 0.0, ax, be)).unwrap();
    /// let q = rod.straight_configuration(&[1.0, 0.0], &[0.0, 1.0]);
    /// assert_eq!(q.as_slice()[16..], [1.0, 0.2, 0.0, 1.0]);
    /// assert!(rod.elastic_energy(q.as_slice()).unwrap() < 1e-20);
    /// ```
    pub fn straight_configuration(&self, position: &[f64], direction: &[f64]) -> DVector<f64> {
        let d = E::DIM;
        let nd = E::NODE_DOFS;
        let mut q = Vec::with_capacity(self.n_q());
        let at = |v: &[f64], i: usize| v.get(i).copied().unwrap_or(0.0);
        let dir: Vec<f64> = (0..d).map(|i| at(direction, i)).collect();
        for &s in &self.node_s {
            let p: Vec<f64> = (0..d).map(|i| at(position, i) + s * dir[i]).collect();
            let node = E::straight_node(&p, &dir);
            q.extend(node.iter().take(nd));
        }
        DVector::from_vec(q)
    }

    /// Element holding arc coordinate `s` and the local coordinate `ξ` in it.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`](crate::Error::InvalidParameter) if `s` is not on the robot.
    pub fn locate(&self, name: &str, s: f64) -> Result<(usize, f64)> {
        let total = self.length();
        let tol = 1e-12 * total;
        if !s.is_finite() || s < -tol || s > total + tol {
            return Err(outside(name, s, total));
        }
        let n = self.elements.len();
        // first node with arc > s
        let e = self
            .node_s
            .partition_point(|&x| x <= s)
            .saturating_sub(1)
            .min(n - 1);
        let xi = ((s - self.node_s[e]) / self.elements[e].length()).clamp(0.0, 1.0);
        Ok((e, xi))
    }
    /// Position `r(s)` of the backbone at arc coordinate `s` (m).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`](crate::Error::InvalidParameter) if `s` is off the robot,
    /// [`Error::DimensionMismatch`](crate::Error::DimensionMismatch) if `q` does not have `n_q` entries.
    pub fn position_at(&self, q: &[f64], s: f64) -> Result<DVector<f64>> {
        check_len("q", self.n_q(), q.len())?;
        let p = self.arc_point("s_m", s)?;
        // the Hermite slots by offset (as ArcPoint::value_into for a cable)
        let base = p.element * E::NODE_DOFS;
        Ok(DVector::from_fn(E::DIM, |i, _| {
            (0..4)
                .map(|k| p.values[k] * q[base + slot::<E>(k) + i])
                .sum()
        }))
    }

    /// The element, `ξ` and Hermite weights at arc coordinate `s` (m): the
    /// interpolation of any cable field (`q`, `F`) there, by
    /// [`ArcPoint::value_into`] and [`ArcPoint::slope_into`].
    ///
    /// # Errors
    /// [`Error::InvalidParameter`](crate::Error::InvalidParameter) named `name` if `s` is not on the rod.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::Section;
    /// use softrod::element::PlanarCable;
    /// use softrod::structure::Rod;
    /// let rod = Rod::new(&[Section::uniform(0.2, 300.0, 0.025, 4)], &[0.0, 0.0], 5, 5, "rod",
    ///     |s, le, ax, be| PlanarCable::with_rules(le, s.ea_n, s.ei_nm2, 0.0, ax, be)).unwrap();
    /// let q = rod.straight_configuration(&[0.0, 0.0], &[1.0, 0.0]);
    /// let mut r = [0.0; 2];
    /// rod.arc_point("s_m", 0.13).unwrap().value_into(q.as_slice(), &mut r).unwrap();
    /// assert!((r[0] - 0.13).abs() < 1e-15);
    /// ```
    pub fn arc_point(&self, name: &str, s: f64) -> Result<ArcPoint> {
        let (e, xi) = self.locate(name, s)?;
        Ok(ArcPoint::new(e, xi, self.elements[e].length()))
    }
}
