//! The constant matrices of the load over the free coordinates, `Mᵀ G`
//! and `H` (the sqp backend's linearized equilibrium and penalty), as
//! triplets, probed instead of formed column by column.

use crate::element::NodeKinematics;
use crate::error::Result;

use super::problem::Problem;
use super::{EstimationModel, LoadModel};

/// Sparse entries `(row, column, value)`, sorted by column then row.
pub(crate) type Triplets = Vec<(usize, usize, f64)>;

impl<M: EstimationModel> Problem<M> {
    /// The matrices of the load over the free coordinates at `u` (constant
    /// where the map `q = φ(u)` is linear), as triplets sorted by column
    /// then row: `(i, j, (Mᵀ G)_ij)` (nonzero
    /// entries) and the upper triangle of `H`, `(i, j, H_ij)` with `i ≤ j`.
    ///
    /// Column `j` is `Mᵀ G e_j`. For the distributed load (`G = H = B`,
    /// coupling the coordinates of a node with those of its neighbours)
    /// over a linear node-by-node map (each block of the map within one
    /// node: `Mᵀ` acts node by node) the columns of the same coordinate of
    /// every third node have disjoint supports and are probed together:
    /// `3 NODE_DOFS` products instead of `n_F` (the entries are the same
    /// numbers: one nonzero per element and row enters each sum). Any other
    /// load or map: column by column.
    pub(crate) fn load_triplets(&self, u: &[f64]) -> Result<(Triplets, Triplets)> {
        let nf = self.n_f();
        let mut g_free = Vec::new();
        let mut h_upper = Vec::new();
        if let Some(node_of_free) = self.free_nodes() {
            let nd = M::Element::NODE_DOFS;
            let n_nodes = self.robot().n_q() / nd;
            // the probed node (≡ c mod 3) next to node m, if any
            let source = |m: usize, c: usize| -> Option<usize> {
                (m.saturating_sub(1)..=(m + 1).min(n_nodes - 1)).find(|k| k % 3 == c)
            };
            for c in 0..3 {
                for k in 0..nd {
                    let mut probe = vec![0.0; nf];
                    for m in (c..n_nodes).step_by(3) {
                        probe[m * nd + k] = 1.0;
                    }
                    let col = self.restrict(u, &self.gen_force(&probe)?)?;
                    for (i, v) in col.iter().enumerate() {
                        if *v != 0.0
                            && let Some(m) = source(node_of_free[i], c)
                        {
                            g_free.push((i, m * nd + k, *v));
                        }
                    }
                    let hcol = self.penalty_grad(&probe)?;
                    for (i, v) in hcol.iter().enumerate() {
                        if *v != 0.0
                            && let Some(m) = source(i / nd, c)
                        {
                            let j = m * nd + k;
                            if i <= j {
                                h_upper.push((i, j, *v));
                            }
                        }
                    }
                }
            }
            let by_column =
                |a: &(usize, usize, f64), b: &(usize, usize, f64)| (a.1, a.0).cmp(&(b.1, b.0));
            g_free.sort_unstable_by(by_column);
            h_upper.sort_unstable_by(by_column);
            return Ok((g_free, h_upper));
        }
        self.load_triplets_by_columns(u)
    }

    /// [`Problem::load_triplets`] column by column (`n_F` products).
    fn load_triplets_by_columns(&self, u: &[f64]) -> Result<(Triplets, Triplets)> {
        let nf = self.n_f();
        let mut g_free = Vec::new();
        let mut h_upper = Vec::new();
        for j in 0..nf {
            let mut ej = vec![0.0; nf];
            ej[j] = 1.0;
            let col = self.restrict(u, &self.gen_force(&ej)?)?;
            for (i, v) in col.iter().enumerate() {
                if *v != 0.0 {
                    g_free.push((i, j, *v));
                }
            }
            let hcol = self.penalty_grad(&ej)?;
            for (i, v) in hcol.iter().enumerate().take(j + 1) {
                if *v != 0.0 {
                    h_upper.push((i, j, *v));
                }
            }
        }
        Ok((g_free, h_upper))
    }

    /// For the distributed load over a linear map whose blocks each lie
    /// within one node (see [`Problem::load_triplets`]): the node of each
    /// free coordinate; `None` otherwise.
    fn free_nodes(&self) -> Option<Vec<usize>> {
        let nd = M::Element::NODE_DOFS;
        let robot = self.robot();
        let map = EstimationModel::dof_map(robot);
        if self.load() != LoadModel::Distributed
            || !map.is_linear()
            || !robot.n_q().is_multiple_of(nd)
        {
            return None;
        }
        let mut node = vec![usize::MAX; robot.n_free()];
        for b in 0..map.n_blocks() {
            let (q, u) = (map.coordinates(b)?, map.free(b)?);
            if q.is_empty() || q.start / nd != (q.end - 1) / nd {
                return None;
            }
            for i in u {
                *node.get_mut(i)? = q.start / nd;
            }
        }
        node.iter().all(|m| *m != usize::MAX).then_some(node)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use crate::assembly::{Base, Clamp, Robot, RobotSpec, Section};
    use crate::element::Element;
    use crate::estimate::EstimatorSettings;
    use crate::loads::Loads;
    use crate::structure::Assembled;

    /// `load_triplets` against `load_triplets_by_columns` on `robot`,
    /// for both load models.
    fn check<E: Element>(robot: &Robot<E>, what: &str) {
        let n = robot.n_elements();
        for load_model in [LoadModel::Distributed, LoadModel::Concentrated { node: n }] {
            let settings = EstimatorSettings {
                load_model,
                ..EstimatorSettings::default()
            };
            let p = Problem::new(robot.clone(), Loads::default(), settings).unwrap();
            assert_eq!(
                p.free_nodes().is_some(),
                load_model == LoadModel::Distributed,
                "{what} {n} {load_model:?}"
            );
            let u = robot.reference_free_coordinates();
            let fast = p.load_triplets(u.as_slice()).unwrap();
            let slow = p.load_triplets_by_columns(u.as_slice()).unwrap();
            assert!(!fast.0.is_empty() && !fast.1.is_empty());
            assert_eq!(fast, slow, "{what} {n} elements {load_model:?}");
        }
    }

    /// The probed triplets of `Mᵀ G` and `H` are the column-by-column ones,
    /// number for number and in the same order, for the distributed load
    /// under both clamps, planar and spatial, at several mesh sizes (a
    /// coloring that let two columns share a row would sum them: a wrong
    /// entry); the concentrated load takes the column path.
    #[test]
    fn probed_load_triplets_are_the_columns() {
        for clamp in [Clamp::Full, Clamp::PositionAndDirection] {
            for n in [1, 2, 3, 4, 7, 20] {
                let mut spec = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, n)]);
                spec.base = Base {
                    clamp,
                    ..Base::default()
                };
                check(&spec.build_planar().unwrap(), &format!("planar {clamp:?}"));
                spec.base.position_m = vec![0.0; 3];
                spec.gravity_m_per_s2 = vec![0.0; 3];
                check(
                    &spec.build_spatial().unwrap(),
                    &format!("spatial {clamp:?}"),
                );
            }
        }
    }
}
