//! What a robot computes once and keeps (shared by its clones, which are
//! the same robot: a [`Robot`] is never changed after it is built): the
//! coarse mesh a cold solve of a fine mesh starts from, the elements'
//! tangent stiffness at the straight reference configuration, where every
//! cold solve of an unactuated robot takes its first Newton step, and that
//! solve's start point.

use std::sync::{Arc, OnceLock};

use nalgebra::DVector;

use super::{Robot, TangentTarget};
use crate::element::Element;
use crate::error::Result;
use crate::linsolve::SymmetricMatrix;
use crate::structure::Stepping;

/// The robot's kept results (see the module documentation).
pub(super) struct RobotCache<E: Element> {
    /// The coarse mesh of [`Robot::coarsened`] (its loads are carried per
    /// call).
    pub(super) coarse: OnceLock<Robot<E>>,
    /// The elements' tangent at the reference configuration (`None` if it
    /// could not be formed).
    reference: OnceLock<Option<ReferenceTangent>>,
    /// The free coordinates of the arcs of no actuation (the cold start of
    /// every solve without pressures; `None` if they could not be formed).
    pub(super) unactuated_start: OnceLock<Option<DVector<f64>>>,
}

/// The elements' part of the tangent (no loads) at a configuration, on
/// the robot's tangent pattern.
struct ReferenceTangent {
    /// The configuration (all `n_q` coordinates).
    q: Vec<f64>,
    /// The values of the [`SymmetricMatrix`] on the robot's pattern.
    values: Vec<f64>,
}

impl<E: Element> Default for RobotCache<E> {
    fn default() -> Self {
        RobotCache {
            coarse: OnceLock::new(),
            reference: OnceLock::new(),
            unactuated_start: OnceLock::new(),
        }
    }
}

impl<E: Element> std::fmt::Debug for RobotCache<E> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("RobotCache")
    }
}

/// A fresh, empty cache for a new robot.
pub(super) fn new_cache<E: Element>() -> Arc<RobotCache<E>> {
    Arc::new(RobotCache::default())
}

impl<E: Element> Robot<E> {
    /// The elements' tangent stiffness (the values on
    /// [`Robot::tangent_pattern`], no load terms) if `q` is exactly the
    /// reference configuration, formed once per robot.
    pub(super) fn reference_element_tangent(&self, q: &[f64]) -> Option<&[f64]> {
        let kept = self.cache.reference.get_or_init(|| {
            let q = self.reference_configuration();
            let mut k = SymmetricMatrix::zeros(self.pattern.clone());
            k.reset(self.n_free(), 2 * E::NODE_DOFS - 1, &self.pattern);
            self.assemble_elements(q.as_slice(), None, Some(&mut k), false)
                .ok()?;
            Some(ReferenceTangent {
                q: q.data.into(),
                values: k.values().to_vec(),
            })
        });
        kept.as_ref()
            .filter(|r| r.q.as_slice() == q)
            .map(|r| r.values.as_slice())
    }

    /// The free coordinates of [`Robot::arc_configuration`] without
    /// pressures (the robot's rest curvature only), formed once per robot:
    /// the cold start of every solve of the unactuated robot.
    pub(super) fn unactuated_start(&self) -> Option<&DVector<f64>> {
        self.cache
            .unactuated_start
            .get_or_init(|| {
                let q = self.arc_configuration(&[]);
                Stepping::free_coordinates_of(self, q.as_slice()).ok()
            })
            .as_ref()
    }

    /// The coarse robot of [`Robot::coarsened`], built once.
    pub(super) fn coarse_robot(
        &self,
        build: impl FnOnce() -> Result<Robot<E>>,
    ) -> Result<Robot<E>> {
        if let Some(c) = self.cache.coarse.get() {
            return Ok(c.clone());
        }
        let c = build()?;
        let _ = self.cache.coarse.set(c.clone());
        Ok(c)
    }
}
