//! What a solver needs of a model beyond its equilibrium ([`Assembled`]):
//! moving in the free coordinates ([`Stepping`]), optional shortcuts a model
//! may know ([`SolverHints`], every method with a default), and mesh
//! sequencing ([`MeshSequencing`], none by default). [`Model`] is all of
//! them: what the static solver and everything above it take.

use nalgebra::DVector;

use super::Assembled;
#[cfg(doc)]
use super::Model;
use crate::error::{Error, Result, check_len};
use crate::linsolve::SymmetricMatrix;

/// How a solver moves in the free coordinates `u` of a model with `q = φ(u)`:
/// the map's inverse, its tangent `T(u) = ∂φ/∂u` and transpose, and the
/// scales of a step (a rotation and a length).
pub trait Stepping: Assembled {
    /// The free coordinates of a start configuration `q` over all
    /// coordinates: the `u` whose `φ(u)` is `q` when `q` lies on the map,
    /// else the map's nearest (the clamp keeps its prescribed base and
    /// takes the stretch along its free direction; a rigid end takes its
    /// body's pose and the stretch along the joint's direction).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a `q` of the wrong size.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, Stepping};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let u = robot.reference_free_coordinates();
    /// let mut q = vec![0.0; robot.n_q()];
    /// robot.configuration_into(u.as_slice(), &mut q)?;
    /// assert_eq!(robot.free_coordinates_of(&q)?, u);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn free_coordinates_of(&self, q: &[f64]) -> Result<DVector<f64>>;

    /// `T(u)ᵀ f` for a force `f` over all coordinates into `out` (the dead
    /// force seen by the free coordinates: the scale of a residual).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    fn restrict_into(&self, u: &[f64], f: &[f64], out: &mut [f64]) -> Result<()>;

    /// A step `du` of the free coordinates mapped to all coordinates,
    /// `dq = T(u) du`, into `dq`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, Stepping};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// // a step of the base stretch turns into a step of the base slope
    /// let mut du = vec![0.0; robot.n_free()];
    /// du[0] = 0.01;
    /// let mut dq = vec![0.0; robot.n_q()];
    /// robot.step_into(robot.reference_free_coordinates().as_slice(), &du, &mut dq)?;
    /// assert_eq!(dq[2], 0.01);
    /// assert_eq!(robot.step_rotation(&dq), 0.01);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn step_into(&self, u: &[f64], du: &[f64], dq: &mut [f64]) -> Result<()>;

    /// The point `u + s du` into `u_to` and its configuration into `q_to`,
    /// for a step `du` with `dq = T(u) du` ([`Stepping::step_into`]) from
    /// `u` with `q = φ(u)`. By default `q_to = φ(u + s du)`; a model whose
    /// map is affine may move along the step instead, `q_to = q + s dq` (the
    /// same point up to round-off).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, Stepping};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let (u, q) = (robot.reference_free_coordinates().as_slice().to_vec(), robot.reference_configuration().as_slice().to_vec());
    /// let mut du = vec![0.0; robot.n_free()];
    /// du[2] = 0.01; // node 1's y
    /// let mut dq = vec![0.0; robot.n_q()];
    /// robot.step_into(&u, &du, &mut dq)?;
    /// let (mut u1, mut q1) = (u.clone(), q.clone());
    /// robot.advance_into(&u, &q, &du, &dq, 0.5, &mut u1, &mut q1)?;
    /// assert_eq!(q1[5], 0.005);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    #[allow(clippy::too_many_arguments)]
    fn advance_into(
        &self,
        u: &[f64],
        q: &[f64],
        du: &[f64],
        dq: &[f64],
        s: f64,
        u_to: &mut [f64],
        q_to: &mut [f64],
    ) -> Result<()> {
        let _ = (q, dq);
        check_len("u", self.n_free(), u.len())?;
        check_len("du", self.n_free(), du.len())?;
        check_len("u", self.n_free(), u_to.len())?;
        for ((v, a), b) in u_to.iter_mut().zip(u).zip(du) {
            *v = a + s * b;
        }
        self.configuration_into(u_to, q_to)
    }

    /// The largest rotation a step `dq` over all coordinates makes (rad,
    /// roughly): the largest change of a rod node's slope `r'` (unit length
    /// at rest) or of a rigid body's angle. A solver caps it per step.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, Stepping};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// // node 2's slope turns by 0.1, its position moves by 0.3 m
    /// let mut dq = vec![0.0; robot.n_q()];
    /// dq[8] = 0.3;
    /// dq[11] = 0.1;
    /// assert_eq!(robot.step_rotation(&dq), 0.1);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn step_rotation(&self, dq: &[f64]) -> f64;

    /// A length of the model (m): the scale of a step tolerance (the
    /// robot's length, the total length of a structure's rods).
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, Stepping};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// assert_eq!(robot.length_m(), 0.2);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn length_m(&self) -> f64;
}

/// Shortcuts a model may know for its solver, each with a default that is
/// correct for every model: a start closer than the reference, the applied
/// force that scales a residual tolerance, the tangent alone, and energies a
/// line search may reuse.
pub trait SolverHints: Stepping {
    /// Where a solve without a start point starts: the straight reference
    /// ([`Assembled::reference_free_coordinates`]) unless the model knows a
    /// closer guess for `loads` (the robot: the arcs of its actuation).
    ///
    /// # Errors
    /// As [`Assembled::validate_loads`].
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, SolverHints};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// // without actuation the arcs are straight: the reference
    /// let u = robot.start_free_coordinates(&softrod::loads::Loads::default())?;
    /// assert_eq!(u, robot.reference_free_coordinates());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn start_free_coordinates(&self, loads: &Self::Loads) -> Result<DVector<f64>> {
        self.validate_loads(loads)?;
        Ok(self.reference_free_coordinates())
    }

    /// The applied generalized forces over the free coordinates into `out`
    /// (N): `T(u)ᵀ` of the dead forces plus the actuation and the
    /// concentrated moments at `q` (not the elastic or force-field terms).
    /// Their norm is the scale of a relative residual tolerance.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, SolverHints};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let loads = softrod::loads::Loads::default();
    /// let (u, q) = (robot.reference_free_coordinates().as_slice().to_vec(), robot.reference_configuration().as_slice().to_vec());
    /// let dead = robot.dead_force(&loads)?;
    /// let mut f = vec![0.0; robot.n_free()];
    /// robot.applied_force_into(&u, &q, dead.as_slice(), &loads, &mut f)?;
    /// // a weightless robot without loads: nothing applied
    /// assert!(f.iter().all(|v| *v == 0.0));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn applied_force_into(
        &self,
        u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &Self::Loads,
        out: &mut [f64],
    ) -> Result<()>;

    /// The tangent alone into `k` (the residual is not needed). By default
    /// [`Assembled::residual_and_tangent_into`] with the residual dropped.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, SolverHints};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let loads = softrod::loads::Loads::default();
    /// let (u, q) = (robot.reference_free_coordinates().as_slice().to_vec(), robot.reference_configuration().as_slice().to_vec());
    /// let dead = robot.dead_force(&loads)?;
    /// let mut k = softrod::linsolve::SymmetricMatrix::zeros(Assembled::tangent_pattern(&robot)?);
    /// SolverHints::tangent_into(&robot, &u, &q, dead.as_slice(), &loads, &mut k)?;
    /// assert!(k.get(1, 1) > 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn tangent_into(
        &self,
        u: &[f64],
        q: &[f64],
        dead: &[f64],
        loads: &Self::Loads,
        k: &mut SymmetricMatrix,
    ) -> Result<()> {
        let mut r = vec![0.0; self.n_free()];
        self.residual_and_tangent_into(u, q, dead, loads, &mut r, k)
    }

    /// Energies at `q` that [`SolverHints::potential_change_from`] may reuse
    /// into `out` (a line search tries several steps from one point; the
    /// robot keeps its element energies). By default none.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a `q` of the wrong size.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, SolverHints};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let mut e = Vec::new();
    /// robot.energies_into(robot.reference_configuration().as_slice(), &mut e)?;
    /// // one per element, nothing stored at rest (up to round-off)
    /// assert!(e.len() == 4 && e.iter().all(|v| v.abs() < 1e-20));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn energies_into(&self, q: &[f64], out: &mut Vec<f64>) -> Result<()> {
        let _ = q;
        out.clear();
        Ok(())
    }

    /// [`Assembled::potential_change`] given what
    /// [`SolverHints::energies_into`] wrote at `from`. By default the
    /// energies are not read.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, SolverHints};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
    /// let loads = softrod::loads::Loads::default();
    /// let (u, q) = (robot.reference_free_coordinates().as_slice().to_vec(), robot.reference_configuration().as_slice().to_vec());
    /// let dead = robot.dead_force(&loads)?;
    /// let (mut u1, mut q1) = (u.clone(), q.clone());
    /// u1[2] += 1e-3;
    /// q1[5] += 1e-3; // node 1 lifted: bending stores energy
    /// let mut e = Vec::new();
    /// robot.energies_into(&q, &mut e)?;
    /// let d = SolverHints::potential_change_from(&robot, &u, &q, &e, &u1, &q1, dead.as_slice(), &loads)?;
    /// assert!(d > 0.0 && d == Assembled::potential_change(&robot, &u, &q, &u1, &q1, dead.as_slice(), &loads)?);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    #[allow(clippy::too_many_arguments)]
    fn potential_change_from(
        &self,
        from_u: &[f64],
        from_q: &[f64],
        from_energies: &[f64],
        to_u: &[f64],
        to_q: &[f64],
        dead: &[f64],
        loads: &Self::Loads,
    ) -> Result<f64> {
        let _ = from_energies;
        self.potential_change(from_u, from_q, to_u, to_q, dead, loads)
    }
}

/// Mesh sequencing: a coarser model of the same body whose equilibrium
/// starts a cold solve of this one. By default a model has none.
pub trait MeshSequencing: Assembled {
    /// Mesh sequencing: a coarser model of the same body with `loads`
    /// carried over, whose equilibrium ([`MeshSequencing::prolong`] onto this
    /// model) starts a cold static solve; `None`, the default, when the
    /// model has none (a robot: [`crate::assembly::Robot::coarsened`]).
    ///
    /// # Errors
    /// As [`Assembled::validate_loads`] and the model's construction.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, MeshSequencing};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]).build_planar()?;
    /// // coarse enough already
    /// assert!(robot.coarse_model(&softrod::loads::Loads::default())?.is_none());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn coarse_model(&self, loads: &Self::Loads) -> Result<Option<(Self, Self::Loads)>>
    where
        Self: Sized,
    {
        let _ = loads;
        Ok(None)
    }

    /// The free coordinates of this model interpolating the configuration
    /// `q_coarse` of `coarse` (from [`MeshSequencing::coarse_model`]).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (field `coarse`) for a model without
    /// a coarse one (the default); a robot's as
    /// [`crate::assembly::Robot::prolong_from`].
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::structure::{Assembled, MeshSequencing};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 64)]).build_planar()?;
    /// let (coarse, _) = robot.coarse_model(&softrod::loads::Loads::default())?.unwrap();
    /// let u = robot.prolong(&coarse, coarse.reference_configuration().as_slice())?;
    /// let straight = robot.reference_free_coordinates();
    /// assert!(u.iter().zip(straight.iter()).all(|(a, b)| (a - b).abs() < 1e-14));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    fn prolong(&self, coarse: &Self, q_coarse: &[f64]) -> Result<DVector<f64>>
    where
        Self: Sized,
    {
        let _ = (coarse, q_coarse);
        Err(Error::invalid(
            "coarse",
            "a model",
            "this model has no coarse mesh",
        ))
    }
}
