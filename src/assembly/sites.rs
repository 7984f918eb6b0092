//! [`Sites`] of the clamped robot: one rod (`rod: 0`), its coordinates
//! from the first of `q`, no rigid body.

use super::Robot;
use crate::element::Element;
use crate::error::{Result, check_index};
use crate::site::{Site, SiteRows, Sites, no_body, rod_node_arc, rod_rows};

impl<E: Element> Sites for Robot<E> {
    fn dim(&self) -> usize {
        E::DIM
    }

    fn node_arc_m(&self, field: &str, rod: usize, node: usize) -> Result<f64> {
        check_index(&format!("{field}.rod"), rod, 1)?;
        rod_node_arc(&self.rod, field, node)
    }

    fn node_coordinates_of(
        &self,
        field: &str,
        rod: usize,
        node: usize,
    ) -> Result<std::ops::Range<usize>> {
        check_index(&format!("{field}.rod"), rod, 1)?;
        check_index(field, node, self.n_nodes())?;
        Ok(node * E::NODE_DOFS..(node + 1) * E::NODE_DOFS)
    }

    fn site_rows(&self, field: &str, site: &Site) -> Result<SiteRows> {
        match *site {
            Site::Rod { rod, s_m } => {
                check_index(&format!("{field}.rod"), rod, 1)?;
                rod_rows(&self.rod, 0, field, s_m)
            }
            Site::Body { body } => Err(no_body(field, body)),
        }
    }
}
