//! [`Sites`] of a structure: rod points through each rod's node block,
//! rigid bodies through their pose block.

use super::Structure;
use crate::element::Element;
use crate::error::{Result, check_index};
use crate::site::{Site, SiteRows, Sites, block_position_rows, rod_node_arc, rod_rows};

impl<E: Element> Sites for Structure<E> {
    fn dim(&self) -> usize {
        E::DIM
    }

    fn node_arc_m(&self, field: &str, rod: usize, node: usize) -> Result<f64> {
        check_index(&format!("{field}.rod"), rod, self.rods.len())?;
        rod_node_arc(&self.rods[rod], field, node)
    }

    fn node_coordinates_of(
        &self,
        field: &str,
        rod: usize,
        node: usize,
    ) -> Result<std::ops::Range<usize>> {
        check_index(&format!("{field}.rod"), rod, self.rods.len())?;
        check_index(field, node, self.rods[rod].n_nodes())?;
        let n = (self.rod_node0[rod] + node) * E::NODE_DOFS;
        Ok(n..n + E::NODE_DOFS)
    }

    fn site_rows(&self, field: &str, site: &Site) -> Result<SiteRows> {
        match *site {
            Site::Rod { rod, s_m } => {
                check_index(&format!("{field}.rod"), rod, self.rods.len())?;
                let offset = self.rod_node0[rod] * E::NODE_DOFS;
                rod_rows(&self.rods[rod], offset, field, s_m)
            }
            Site::Body { body } => {
                check_index(&format!("{field}.body"), body, self.spec.rigid_bodies.len())?;
                let range = self.body_coordinates(body)?;
                Ok(block_position_rows(range, E::DIM))
            }
        }
    }
}
