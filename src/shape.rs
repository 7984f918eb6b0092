//! Typed results: the solved or estimated shape of a planar robot, its tip
//! pose and the reaction at its clamp, the estimated load and its
//! uncertainty, as nalgebra types.
//!
//! The solvers return coordinate vectors (`q`, `F`) as `Vec<f64>`; this
//! module reads them the way a user asks:
//!
//! - [`Shape`] (from [`Equilibrium::shape`] or [`Estimate::shape`]): node
//!   positions and unwrapped tangent angles, the position and angle at any
//!   arc position by the element's own (cubic Hermite) interpolation, the
//!   tip pose ([`Pose2`]) and the reaction at the clamp ([`Reaction2`]).
//! - On an [`Estimate`]: the resultant force as a fixed-size vector
//!   ([`Estimate::resultant`]), its covariance as a matrix
//!   ([`Estimate::resultant_cov`]), the estimated load as a function of arc
//!   position ([`Estimate::load_vector_at`]).
//! - [`EstimatorSettings::build_for`]: an estimator of the backend the
//!   settings name, from a borrowed robot and borrowed loads.
//!
//! All quantities SI: m, rad, N, N·m, N/m.
//!
//! # Example
//! ```
//! use softrod::{scene::Scene, statics::StaticSolver};
//! let scene = Scene::two_section();
//! let (robot, loads) = (scene.robot()?, scene.loads()?);
//! let eq = StaticSolver::default().solve(&robot, &loads, None)?;
//! let shape = eq.shape(&robot)?;
//! let tip = shape.tip_pose()?;
//! assert!((tip.position_m - shape.position_at(0.24)?).norm() < 1e-12);
//! // the clamp carries the robot's weight
//! let r = shape.clamp_reaction(&loads)?;
//! assert!(r.force_n.y > 0.0);
//! # Ok::<(), softrod::Error>(())
//! ```

use nalgebra::{DVector, Point2, SMatrix, SVector, Vector2};

use crate::assembly::Robot;
use crate::element::{NodeKinematics, PlanarCable};
use crate::error::{Error, Result, check_len};
use crate::estimate::{
    Backend, Estimate, EstimationModel, Estimator, EstimatorSettings, NewtonEstimator, SqpEstimator,
};
use crate::loads::Loads;
use crate::statics::Equilibrium;

/// A planar pose: a point and the unwrapped tangent angle there.
///
/// # Example
/// ```
/// use softrod::shape::Pose2;
/// let p = Pose2 { position_m: nalgebra::Point2::new(0.1, 0.0), angle_rad: std::f64::consts::FRAC_PI_2 };
/// assert!((p.tangent() - nalgebra::Vector2::y()).norm() < 1e-15);
/// assert!((p.isometry().translation.vector.x - 0.1).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose2 {
    /// Position (m, world axes).
    pub position_m: Point2<f64>,
    /// Tangent angle from the x axis (rad), unwrapped along the backbone
    /// (a rod rolled into a full circle ends at 2π, not 0).
    pub angle_rad: f64,
}

impl Pose2 {
    /// The unit tangent `(cos θ, sin θ)`.
    ///
    /// # Example
    /// See [`Pose2`].
    pub fn tangent(&self) -> Vector2<f64> {
        Vector2::new(self.angle_rad.cos(), self.angle_rad.sin())
    }

    /// The pose as an isometry (the angle taken modulo 2π).
    ///
    /// # Example
    /// See [`Pose2`].
    pub fn isometry(&self) -> nalgebra::Isometry2<f64> {
        nalgebra::Isometry2::new(self.position_m.coords, self.angle_rad)
    }
}

/// The force and moment the clamp exerts on a planar robot.
///
/// # Example
/// See [`Shape::clamp_reaction`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reaction2 {
    /// Force on the robot at its base (N, world axes).
    pub force_n: Vector2<f64>,
    /// Moment on the robot about its base point (N·m, counter-clockwise
    /// positive).
    pub moment_nm: f64,
}

/// A planar robot's configuration `q` read as a shape: borrowed from a
/// static solution ([`Equilibrium::shape`]) or an estimate
/// ([`Estimate::shape`]) together with its robot.
///
/// # Example
/// See the [module documentation](self).
#[derive(Debug, Clone, Copy)]
pub struct Shape<'a> {
    robot: &'a Robot<PlanarCable>,
    q: &'a [f64],
}

impl<'a> Shape<'a> {
    /// The shape of the coordinates `q` of `robot`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `q` if `q` does not have
    /// [`Robot::n_q`] entries.
    ///
    /// # Example
    /// ```
    /// use softrod::{assembly::{RobotSpec, Section}, shape::Shape};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.025, 4)]).build_planar()?;
    /// let q = robot.reference_configuration().as_slice().to_vec();
    /// let shape = Shape::new(&robot, &q)?;
    /// assert_eq!(shape.node_positions().len(), 5);
    /// assert!(Shape::new(&robot, &q[1..]).is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn new(robot: &'a Robot<PlanarCable>, q: &'a [f64]) -> Result<Self> {
        check_len("q", robot.n_q(), q.len())?;
        Ok(Shape { robot, q })
    }

    /// The coordinates `q` (m and dimensionless slopes, 4 per node).
    ///
    /// # Example
    /// ```
    /// use softrod::{assembly::{RobotSpec, Section}, shape::Shape};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.025, 4)]).build_planar()?;
    /// let q = robot.reference_configuration().as_slice().to_vec();
    /// assert_eq!(Shape::new(&robot, &q)?.coordinates().len(), robot.n_q());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn coordinates(&self) -> DVector<f64> {
        DVector::from_column_slice(self.q)
    }

    /// The node positions `r_i` (m).
    ///
    /// # Example
    /// ```
    /// use softrod::{assembly::{RobotSpec, Section}, shape::Shape};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.025, 4)]).build_planar()?;
    /// let q = robot.reference_configuration().as_slice().to_vec();
    /// let p = Shape::new(&robot, &q)?.node_positions();
    /// assert!((p[4].x - 0.2).abs() < 1e-15 && p[4].y == 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn node_positions(&self) -> Vec<Point2<f64>> {
        self.q
            .chunks_exact(PlanarCable::NODE_DOFS)
            .map(|c| Point2::new(c[0], c[1]))
            .collect()
    }

    /// The tangent angles at the nodes (rad), unwrapped along the backbone
    /// (see [`Robot::node_angles`]).
    ///
    /// # Errors
    /// As [`Robot::node_angles`] (not for a shape made by [`Shape::new`]).
    ///
    /// # Example
    /// ```
    /// use softrod::{assembly::{RobotSpec, Section}, shape::Shape};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.025, 4)]).build_planar()?;
    /// let q = robot.reference_configuration().as_slice().to_vec();
    /// assert_eq!(Shape::new(&robot, &q)?.node_angles()?.len(), 5);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn node_angles(&self) -> Result<DVector<f64>> {
        self.robot.node_angles(self.q)
    }

    /// The position `r(s)` at arc position `s_m` (m, undeformed), by the
    /// element's interpolation (16), not between the nodes.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `s_m` if it is off the robot.
    ///
    /// # Example
    /// ```
    /// use softrod::{assembly::{RobotSpec, Section}, shape::Shape};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.025, 4)]).build_planar()?;
    /// let q = robot.reference_configuration().as_slice().to_vec();
    /// let shape = Shape::new(&robot, &q)?;
    /// assert!((shape.position_at(0.13)?.x - 0.13).abs() < 1e-15);
    /// assert!(shape.position_at(0.3).is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn position_at(&self, s_m: f64) -> Result<Point2<f64>> {
        let p = self.robot.arc_point("s_m", s_m)?;
        let mut r = [0.0; 2];
        p.value_into(self.q, &mut r)?;
        Ok(Point2::new(r[0], r[1]))
    }

    /// The unwrapped tangent angle (rad) at arc position `s_m` (m), by the
    /// element's interpolation (see [`Robot::angle_at`]).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `s_m` if it is off the robot.
    ///
    /// # Example
    /// ```
    /// use softrod::{assembly::{RobotSpec, Section}, shape::Shape};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.025, 4)]).build_planar()?;
    /// let q = robot.reference_configuration().as_slice().to_vec();
    /// assert_eq!(Shape::new(&robot, &q)?.angle_at(0.07)?, 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn angle_at(&self, s_m: f64) -> Result<f64> {
        self.robot.angle_at(self.q, s_m)
    }

    /// The pose at arc position `s_m` (m): [`Shape::position_at`] and
    /// [`Shape::angle_at`].
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `s_m` if it is off the robot.
    ///
    /// # Example
    /// ```
    /// use softrod::{assembly::{RobotSpec, Section}, shape::Shape};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.025, 4)]).build_planar()?;
    /// let q = robot.reference_configuration().as_slice().to_vec();
    /// let p = Shape::new(&robot, &q)?.pose_at(0.1)?;
    /// assert!((p.position_m.x - 0.1).abs() < 1e-15 && p.angle_rad == 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn pose_at(&self, s_m: f64) -> Result<Pose2> {
        Ok(Pose2 {
            position_m: self.position_at(s_m)?,
            angle_rad: self.angle_at(s_m)?,
        })
    }

    /// The tip pose: position and unwrapped tangent angle of the last node.
    ///
    /// # Errors
    /// As [`Robot::node_angles`] (not for a shape made by [`Shape::new`]).
    ///
    /// # Example
    /// See the [module documentation](self).
    pub fn tip_pose(&self) -> Result<Pose2> {
        let angles = self.robot.node_angles(self.q)?;
        let tip = self.node_positions().last().copied();
        match (tip, angles.as_slice().last()) {
            (Some(position_m), Some(&angle_rad)) => Ok(Pose2 {
                position_m,
                angle_rad,
            }),
            _ => Err(Error::invalid("q", "no nodes", "the robot has no tip")),
        }
    }

    /// The force and moment the clamp exerts on the robot in this shape
    /// under the external `loads` (self-weight, line and point loads,
    /// moments, follower pressure; the chambers' actuation is internal to
    /// the robot and does not load the clamp): the opposite of the
    /// external loads' resultant and of their moment about the base point,
    /// taken in the deformed shape. It is the residual at the base: at an
    /// equilibrium the generalized forces of all other nodes vanish, so a
    /// rigid translation and rotation of the whole robot see only the base.
    /// Every external load enters through its generalized force `Q`: the
    /// force is `−Σ_i Q_r,i` and the moment `−Σ_i ((r_i − r_0) × Q_r,i +
    /// r'_i × Q_r',i)`, exact for the cable's interpolation.
    ///
    /// # Errors
    /// As [`Robot::validate_loads`].
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::loads::{Loads, PointForce};
    /// use softrod::statics::StaticSolver;
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]).build_planar()?;
    /// let loads = Loads { point_forces: vec![PointForce { s_m: 0.24, force_n: vec![0.0, -0.05] }], ..Loads::default() };
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let shape = eq.shape(&robot)?;
    /// let r = shape.clamp_reaction(&loads)?;
    /// let tip = shape.tip_pose()?.position_m;
    /// assert!((r.force_n - nalgebra::Vector2::new(0.0, 0.05)).norm() < 1e-12);
    /// assert!((r.moment_nm - 0.05 * tip.x).abs() < 1e-12); // −(r_tip × F)
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn clamp_reaction(&self, loads: &Loads) -> Result<Reaction2> {
        let nd = PlanarCable::NODE_DOFS;
        // the dead force holds no actuation; the chambers' moments (from
        // the pressures) are not among the known node moments
        let external = loads;
        let mut g = self.robot.dead_force(external)?;
        let q = self.q;
        self.robot
            .rod()
            .for_each_follower_element(external, |e, m| {
                let qe = &q[e * nd..(e + 2) * nd];
                for (k, row) in m.chunks_exact(qe.len()).enumerate() {
                    g[e * nd + k] += row.iter().zip(qe).map(|(a, b)| a * b).sum::<f64>();
                }
                Ok(())
            })?;
        let r0 = Vector2::new(q[0], q[1]);
        let (mut force, mut moment) = (Vector2::zeros(), 0.0);
        for (qi, gi) in q.chunks_exact(nd).zip(g.as_slice().chunks_exact(nd)) {
            let (fr, fs) = (Vector2::new(gi[0], gi[1]), Vector2::new(gi[2], gi[3]));
            let (r, t) = (Vector2::new(qi[0], qi[1]) - r0, Vector2::new(qi[2], qi[3]));
            force += fr;
            moment += r.perp(&fr) + t.perp(&fs);
        }
        // pure moments: their work M θ turns with a rigid rotation as M
        moment += external
            .node_moments
            .iter()
            .map(|m| m.moment_nm.first().copied().unwrap_or(0.0))
            .sum::<f64>();
        moment += external
            .point_moments
            .iter()
            .map(|m| m.moment_nm.first().copied().unwrap_or(0.0))
            .sum::<f64>();
        Ok(Reaction2 {
            force_n: -force,
            moment_nm: -moment,
        })
    }
}

impl Equilibrium {
    /// The solved configuration of `robot` as a [`Shape`].
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `q` if the solution is not one of
    /// `robot` (another number of coordinates).
    ///
    /// # Example
    /// See the [module documentation](self).
    pub fn shape<'a>(&'a self, robot: &'a Robot<PlanarCable>) -> Result<Shape<'a>> {
        Shape::new(robot, self.q.as_slice())
    }
}

impl Estimate {
    /// The estimated shape on `robot` (the estimator's robot) as a [`Shape`].
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `q` if the estimate is not one of
    /// `robot`.
    ///
    /// # Example
    /// See [`Estimate::resultant`].
    pub fn shape<'a>(&'a self, robot: &'a Robot<PlanarCable>) -> Result<Shape<'a>> {
        Shape::new(robot, self.q.as_slice())
    }

    /// The resultant force of the estimated load (N) as a `D`-vector
    /// (`D` = 2 for a planar robot, 3 for a spatial one).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `resultant_force_n` if the robot
    /// has another dimension than `D`.
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{EstimatorSettings, Observation};
    /// use softrod::{scene::Scene, statics::StaticSolver};
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[4, 8, 12, 16, 20])?.with_noise(1e-5, 1);
    /// let mut est = EstimatorSettings::default().build_for(&robot, &loads)?;
    /// let e = est.step(&obs)?;
    /// let f: nalgebra::Vector2<f64> = e.resultant::<2>()?;
    /// let cov: nalgebra::Matrix2<f64> = e.resultant_cov::<2>()?;
    /// assert!(cov.symmetric_eigenvalues().min() > 0.0);
    /// assert!(f.norm() < 0.05); // no unknown load acts
    /// assert!(e.resultant::<3>().is_err());
    /// let w = e.load_vector_at::<2>(0.12)?; // N/m at the middle
    /// assert!(w.norm().is_finite());
    /// assert!((e.shape(&robot)?.tip_pose()?.position_m.x - eq.shape(&robot)?.tip_pose()?.position_m.x).abs() < 1e-3);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn resultant<const D: usize>(&self) -> Result<SVector<f64, D>> {
        check_len("resultant_force_n", D, self.resultant_force_n.len())?;
        Ok(SVector::from_column_slice(
            self.resultant_force_n.as_slice(),
        ))
    }

    /// The covariance of [`Estimate::resultant`] (N²) as a `D × D` matrix
    /// (see [`Estimate::resultant_force_cov`] for what it holds).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `resultant_force_cov` if the
    /// robot has another dimension than `D`.
    ///
    /// # Example
    /// See [`Estimate::resultant`].
    pub fn resultant_cov<const D: usize>(&self) -> Result<SMatrix<f64, D, D>> {
        check_len(
            "resultant_force_cov",
            D * D,
            self.resultant_force_cov().len(),
        )?;
        Ok(SMatrix::from_fn(|i, j| self.resultant_force_cov()[(i, j)]))
    }

    /// The estimated load per undeformed length at arc position `s_m` (m)
    /// as a `D`-vector (N/m, world axes): `w(s) = S(s) F` (8) by the
    /// element's interpolation; zero for a concentrated unknown load.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `resultant_force_n` if the robot
    /// has another dimension than `D`; [`Error::InvalidParameter`] named
    /// `s_m` if it is off the robot.
    ///
    /// # Example
    /// See [`Estimate::resultant`]; as a function: `|s| e.load_vector_at::<2>(s)`.
    pub fn load_vector_at<const D: usize>(&self, s_m: f64) -> Result<SVector<f64, D>> {
        check_len("resultant_force_n", D, self.resultant_force_n.len())?;
        let length = self.node_arc().last().copied().unwrap_or(0.0);
        if !(s_m.is_finite() && (0.0..=length).contains(&s_m)) {
            return Err(Error::invalid(
                "s_m",
                s_m,
                format!("must lie on the robot, 0..={length} m"),
            ));
        }
        let w = self.load_at(s_m);
        if w.iter().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                context: format!("the estimated load at s_m = {s_m} m"),
            });
        }
        Ok(SVector::from_column_slice(w.as_slice()))
    }
}

impl EstimatorSettings {
    /// An estimator of the backend these settings name
    /// ([`EstimatorSettings::backend`]), for `robot` (the clamped robot or
    /// any structure: the parallel robot, the gripper's fingers) under the
    /// known loads `known` (both borrowed, cloned into the estimator): the
    /// backend is chosen once, in the settings.
    ///
    /// # Errors
    /// As [`NewtonEstimator::new`] and [`SqpEstimator::new`].
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{Backend, EstimatorSettings};
    /// use softrod::scene::Scene;
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let settings = EstimatorSettings { backend: Backend::Sqp, ..Default::default() };
    /// let est = settings.build_for(&robot, &loads)?;
    /// assert_eq!(est.backend(), Backend::Sqp);
    /// assert_eq!(robot.n_elements(), 20); // still ours
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn build_for<M: EstimationModel>(
        &self,
        robot: &M,
        known: &M::Loads,
    ) -> Result<Box<dyn Estimator<M::Loads>>> {
        Ok(match self.backend {
            Backend::Newton => Box::new(NewtonEstimator::new(robot, known, self)?),
            Backend::Sqp => Box::new(SqpEstimator::new(robot, known, self)?),
        })
    }
}
