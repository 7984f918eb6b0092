//! What the estimators need of a model: its equilibrium ([`Model`](crate::structure::Model)),
//! its points ([`Sites`]), and where a distributed field lives. The clamped
//! [`Robot`] and every [`Structure`] (the parallel robot, the gripper's
//! fingers) are estimation models: a force at a site is estimated on both;
//! the distributed field (8) on the robot's rod.

use nalgebra::DVector;

use crate::assembly::Robot;
use crate::element::Element;
use crate::loads::{Loads, PointForce};
use crate::site::{Site, Sites};
use crate::structure::{BodyLoad, DofMap, Model, Rod, Structure, StructureLoads};

/// A model the estimators run on.
///
/// # Example
/// ```
/// use softrod::estimate::EstimationModel;
/// let robot = softrod::scene::Scene::two_section().robot()?;
/// assert!(robot.field_rod().is_some());
/// let parallel = softrod::parallel::ParallelSpec::default().build_cable()?;
/// assert!(parallel.structure().field_rod().is_none());
/// # Ok::<(), softrod::Error>(())
/// ```
pub trait EstimationModel:
    Model<Loads: Clone + Default + PartialEq + std::fmt::Debug + Send + Sync>
    + Sites
    + 'static
    + Clone
    + std::fmt::Debug
    + Send
    + Sync
{
    /// The element of the model's rods.
    type Element: Element;

    /// Whether a cold estimate of the newton backend may take the far
    /// start (the sqp backend's full-space iterations, see
    /// [`crate::estimate::NewtonEstimator`]) when the trust region cuts its
    /// step: the clamped robot's large deflections need it. Default
    /// `true`; the structures' `false`: on the parallel robot's payload
    /// (`examples/parallel_estimate.json`) it took one iteration more and
    /// 6 % more instructions for the same estimate (to 1e-12).
    const FAR_START: bool = true;

    /// The rod whose coordinates carry the distributed field `w = S F` (8),
    /// if the model has one: the clamped robot's rod, whose coordinates are
    /// the first of `q`.
    fn field_rod(&self) -> Option<&Rod<Self::Element>>;

    /// The straight reference configuration `q` (the cold start).
    fn reference_q(&self) -> DVector<f64>;

    /// The loads `known` with a force `force_n` at `site` added.
    fn with_point_force(&self, known: &Self::Loads, site: &Site, force_n: &[f64]) -> Self::Loads;

    /// The loads `known` with the distributed field `f` added (NaN, and so
    /// refused by the loads' check, on a model without a field rod).
    fn with_distributed(&self, known: &Self::Loads, f: &[f64]) -> Self::Loads;

    /// The largest change of a position coordinate in the step `dq` (m):
    /// the nodes' positions and the bodies' (slopes and angles left out).
    fn max_position_change(&self, dq: &[f64]) -> f64;

    /// The map `q = φ(u)` from the free coordinates to all coordinates
    /// (whether it is linear decides what the sqp backend may keep
    /// constant).
    fn dof_map(&self) -> &DofMap;
}

impl<E: Element + 'static> EstimationModel for Robot<E> {
    type Element = E;

    fn field_rod(&self) -> Option<&Rod<E>> {
        Some(self.rod())
    }

    fn dof_map(&self) -> &DofMap {
        Robot::dof_map(self)
    }

    fn reference_q(&self) -> DVector<f64> {
        self.reference_configuration()
    }

    fn with_point_force(&self, known: &Loads, site: &Site, force_n: &[f64]) -> Loads {
        let mut loads = known.clone();
        let s_m = match *site {
            Site::Rod { rod: 0, s_m } => s_m,
            // refused by the loads' check (a point off the robot)
            _ => f64::NAN,
        };
        loads.point_forces.push(PointForce {
            s_m,
            force_n: force_n.to_vec(),
        });
        loads
    }

    fn with_distributed(&self, known: &Loads, f: &[f64]) -> Loads {
        let mut loads = known.clone();
        if loads.distributed_f.is_empty() {
            loads.distributed_f = f.to_vec();
        } else {
            loads
                .distributed_f
                .iter_mut()
                .zip(f)
                .for_each(|(a, b)| *a += b);
        }
        loads
    }

    fn max_position_change(&self, dq: &[f64]) -> f64 {
        let nd = E::NODE_DOFS;
        dq.iter()
            .enumerate()
            .filter(|(i, _)| i % nd < E::DIM)
            .fold(0.0f64, |m, (_, v)| m.max(v.abs()))
    }
}

impl<E: Element + 'static> EstimationModel for Structure<E> {
    type Element = E;

    const FAR_START: bool = false;

    fn field_rod(&self) -> Option<&Rod<E>> {
        None
    }

    fn dof_map(&self) -> &DofMap {
        Structure::dof_map(self)
    }

    fn reference_q(&self) -> DVector<f64> {
        self.configuration(self.reference_free_coordinates())
            .unwrap_or_else(|_| DVector::from_element(self.n_q(), f64::NAN))
    }

    fn with_point_force(
        &self,
        known: &StructureLoads,
        site: &Site,
        force_n: &[f64],
    ) -> StructureLoads {
        let mut loads = known.clone();
        match *site {
            Site::Body { body } => loads.bodies.push(BodyLoad {
                body,
                force_n: force_n.to_vec(),
                moment_nm: vec![0.0; E::MOMENT_DIM],
            }),
            Site::Rod { rod, s_m } => {
                if loads.rods.len() <= rod {
                    loads.rods.resize(rod + 1, Loads::default());
                }
                loads.rods[rod].point_forces.push(PointForce {
                    s_m,
                    force_n: force_n.to_vec(),
                });
            }
        }
        loads
    }

    fn with_distributed(&self, known: &StructureLoads, _f: &[f64]) -> StructureLoads {
        let mut loads = known.clone();
        loads.bodies.push(BodyLoad {
            body: 0,
            force_n: vec![f64::NAN; E::DIM],
            moment_nm: vec![0.0; E::MOMENT_DIM],
        });
        loads
    }

    fn max_position_change(&self, dq: &[f64]) -> f64 {
        let nd = E::NODE_DOFS;
        let rods = self.n_rod_nodes() * nd;
        let mut m = dq
            .iter()
            .take(rods)
            .enumerate()
            .filter(|(i, _)| i % nd < E::DIM)
            .fold(0.0f64, |m, (_, v)| m.max(v.abs()));
        for b in 0..self.spec().rigid_bodies.len() {
            if let Ok(r) = self.body_coordinates(b) {
                for v in dq
                    .get(r.start..(r.start + E::DIM).min(r.end))
                    .unwrap_or(&[])
                {
                    m = m.max(v.abs());
                }
            }
        }
        m
    }
}
