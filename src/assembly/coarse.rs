//! Mesh sequencing: a coarser mesh of the same robot, its loads carried
//! over, and the interpolation of a coarse configuration onto the fine mesh.
//!
//! A cold static solve of a fine mesh starts from the equilibrium of a
//! coarse one ([`COARSE_ELEMENTS`] elements), interpolated node by node with
//! the cable's own Hermite shape functions: the load path (its continuation
//! steps, the bifurcations it avoids) is followed where it is cheap and
//! does not depend on the mesh, and the fine mesh only corrects the
//! discretization error, a few Newton steps whatever its size.

use std::sync::Arc;

use nalgebra::DVector;

use super::Robot;
use crate::element::{ArcPoint, Element};
use crate::error::{Error, Result, check_len};
use crate::loads::{Loads, PointMoment};
use crate::structure::section::Section;

/// Elements (over all sections) of the coarse mesh a cold solve of a fine
/// mesh starts from. Measured on the static-scaling cases: 16 puts the
/// interpolated start within a few full Newton steps of the fine
/// equilibrium at every size up to 2000 elements.
pub const COARSE_ELEMENTS: usize = 16;

/// A robot is solved on a coarse mesh first when it has at least this many
/// times [`COARSE_ELEMENTS`] elements.
pub const SEQUENCING_RATIO: usize = 4;

/// The function that builds one element of a section from `(section,
/// element length, axial points, bending points)`.
type Make<E> = dyn Fn(&Section, f64, usize, usize) -> Result<E> + Send + Sync;

/// What [`Robot::new`] was given to build its elements, kept to build a
/// coarser mesh of the same robot.
#[derive(Clone)]
pub(super) struct ElementMaker<E>(Arc<Make<E>>);

impl<E> ElementMaker<E> {
    pub(super) fn new(
        make: impl Fn(&Section, f64, usize, usize) -> Result<E> + Send + Sync + 'static,
    ) -> Self {
        ElementMaker(Arc::new(make))
    }

    /// One element of `section`.
    pub(super) fn build(&self, section: &Section, le: f64, ax: usize, be: usize) -> Result<E> {
        (self.0)(section, le, ax, be)
    }
}

impl<E> std::fmt::Debug for ElementMaker<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("ElementMaker")
    }
}

impl<E: Element> Robot<E> {
    /// The same robot on a coarse mesh (about 16 elements,
    /// each section keeping its share, at least one), with `loads` carried
    /// over: the distributed-load parameters interpolated to the coarse
    /// nodes, a moment at a node turned into the same moment at that node's
    /// arc coordinate; the rest is given by arc coordinate or per chamber
    /// and stays. `None` for a robot below 4 ×
    /// 16 elements or whose nodes are not `[r, r']` (the
    /// cables; not the full 3-D element).
    ///
    /// # Errors
    /// The errors of [`Robot::new`] on the coarse spec and of
    /// [`Robot::validate_loads`].
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::loads::Loads;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.12, 300.0, 0.025, 100),
    ///     Section::uniform(0.12, 300.0, 0.025, 300)]).build_planar()?;
    /// let (coarse, _) = robot.coarsened(&Loads::default())?.unwrap();
    /// assert_eq!((coarse.spec().sections[0].elements, coarse.spec().sections[1].elements), (4, 12));
    /// assert!(coarse.coarsened(&Loads::default())?.is_none());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn coarsened(&self, loads: &Loads) -> Result<Option<(Robot<E>, Loads)>> {
        let n = self.n_elements();
        if E::NODE_DOFS != 2 * E::DIM || n < SEQUENCING_RATIO * COARSE_ELEMENTS {
            return Ok(None);
        }
        self.validate_loads(loads)?;
        let coarse = self.coarse_robot(|| {
            let mut spec = self.spec.clone();
            for s in &mut spec.sections {
                s.elements = (s.elements * COARSE_ELEMENTS).div_ceil(n).max(1);
            }
            Robot::with_maker(spec, self.make.clone())
        })?;
        let mut carried = loads.clone();
        if !loads.distributed_f.is_empty() {
            carried.distributed_f = self.interpolate_to(&loads.distributed_f, coarse.node_arc())?;
        }
        let arcs = self.node_arc();
        for m in &loads.node_moments {
            let s_m = *arcs
                .get(m.node)
                .ok_or_else(|| Error::invalid("node_moments.node", m.node, "beyond the tip"))?;
            carried.point_moments.push(PointMoment {
                s_m,
                moment_nm: m.moment_nm.clone(),
            });
        }
        carried.node_moments.clear();
        Ok(Some((coarse, carried)))
    }

    /// The free coordinates on this robot's mesh of the configuration
    /// `q_coarse` of `coarse` (the same robot on another mesh, e.g.
    /// [`Robot::coarsened`]): every node takes the position and slope of the
    /// coarse cable at its arc coordinate (Hermite interpolation), the clamp
    /// its base.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `q_coarse` is not `coarse`'s size or
    /// the nodes are not `[r, r']`; [`Error::InvalidParameter`] if the two
    /// robots do not have the same length.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::Assembled;
    /// let fine = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 64)]).build_planar()?;
    /// let coarse = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 16)]).build_planar()?;
    /// let u = fine.prolong_from(&coarse, coarse.reference_configuration().as_slice())?;
    /// let straight = fine.reference_free_coordinates();
    /// // a straight line is a cubic: interpolated to round-off
    /// assert!(u.iter().zip(&straight).all(|(a, b)| (a - b).abs() < 1e-14));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn prolong_from(&self, coarse: &Robot<E>, q_coarse: &[f64]) -> Result<DVector<f64>> {
        check_len("q_coarse", coarse.n_q(), q_coarse.len())?;
        if (coarse.length() - self.length()).abs() > 1e-12 * self.length() {
            return Err(Error::invalid(
                "coarse",
                coarse.length(),
                "not the same robot: another length",
            ));
        }
        let q = coarse.interpolate_to(q_coarse, self.node_arc())?;
        crate::structure::Stepping::free_coordinates_of(self, &q)
    }

    /// A cable field (`[v, v']` per node, node-major) of this mesh at the
    /// arc coordinates `arcs`, node-major again.
    fn interpolate_to(&self, field: &[f64], arcs: &[f64]) -> Result<Vec<f64>> {
        let d = E::DIM;
        let nd = E::NODE_DOFS;
        if nd != 2 * d {
            return Err(Error::DimensionMismatch {
                name: "node coordinates [r, r']".into(),
                expected: 2 * d,
                got: nd,
            });
        }
        check_len("field", self.n_q(), field.len())?;
        let length = self.length();
        let mut out = vec![0.0; arcs.len() * nd];
        for (node, &s) in out.chunks_exact_mut(nd).zip(arcs) {
            let p = ArcPoint::locate(self.node_arc(), s.clamp(0.0, length))
                .ok_or_else(|| Error::invalid("s_m", s, "not on the robot"))?;
            let (value, slope) = node.split_at_mut(d);
            p.value_into(field, value)?;
            p.slope_into(field, slope)?;
        }
        Ok(out)
    }
}
