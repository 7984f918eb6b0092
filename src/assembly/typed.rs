//! The robot's typed conveniences: the allocating counterparts of its
//! `_into` kernels, returning nalgebra vectors and matrices (coordinate
//! vectors as `DVector`, positions and torques as `DMatrix` columns or
//! fixed-size points).

use nalgebra::{DMatrix, DVector, SVector};

use super::Robot;
use crate::element::Element;
use crate::error::{Result, check_len};
use crate::loads::Loads;
use crate::structure::rod::MAX_EDOF;

impl<E: Element> Robot<E> {
    /// As [`Robot::apply_load_gram_into`], into a new vector.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `f` does not have `n_q` entries.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)]).build_planar().unwrap();
    /// let f: Vec<f64> = (0..robot.n_q()).map(|i| (i % 5) as f64).collect();
    /// let a = robot.apply_load_gram(&f).unwrap();
    /// let b = robot.load_gram().mul_vec(&f).unwrap();
    /// assert!(a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-15));
    /// ```
    pub fn apply_load_gram(&self, f: &[f64]) -> Result<DVector<f64>> {
        self.rod.apply_load_gram(f)
    }

    /// Maps a step `du` of the free coordinates to the step of all `n_q`
    /// coordinates, `dq = T du` ([`crate::structure::DofMap::expand_into`]).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `du` has the wrong size.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 4)]).build_planar()?;
    /// let du = nalgebra::DVector::from_element(robot.n_free(), 1.0);
    /// let dq = robot.expand_step(du.as_slice())?;
    /// assert_eq!(dq.len(), robot.n_q());
    /// // the base position and direction do not move; its stretch does
    /// assert_eq!((dq[0], dq[1]), (0.0, 0.0));
    /// assert_eq!(dq.rows(4, robot.n_q() - 4), du.rows(1, robot.n_free() - 1));
    /// // the work-conjugate: (T du) · f = du · (Tᵀ f)
    /// let f = nalgebra::DVector::from_fn(robot.n_q(), |i, _| i as f64);
    /// assert!((dq.dot(&f) - du.dot(&robot.restrict(f.as_slice())?)).abs() < 1e-12);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn expand_step(&self, du: &[f64]) -> Result<DVector<f64>> {
        check_len("du", self.n_free(), du.len())?;
        let mut dq = DVector::zeros(self.n_q());
        self.dofs.expand_into(&[], du, dq.as_mut_slice())?;
        Ok(dq)
    }

    /// Restricts a generalized force over all `n_q` coordinates to the free
    /// coordinates, `Tᵀ f` (the work-conjugate of [`Robot::expand_step`];
    /// [`crate::structure::DofMap::restrict_into`]).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `f` has the wrong size.
    ///
    /// # Example
    /// See [`Robot::expand_step`].
    pub fn restrict(&self, f: &[f64]) -> Result<DVector<f64>> {
        check_len("f", self.n_q(), f.len())?;
        let mut u = DVector::zeros(self.n_free());
        self.dofs.restrict_into(&[], f, u.as_mut_slice())?;
        Ok(u)
    }

    /// Position `r(s)` of the backbone at arc coordinate `s` (m): a vector
    /// of the element's dimension (`E::DIM`: 2 planar, 3 spatial), the
    /// interpolated counterpart of a column of [`Robot::node_positions`]
    /// (a dynamic vector for the reason given there). As a fixed-size type:
    /// [`Robot::position_at_fixed`], or for a planar robot
    /// [`crate::shape::Shape::position_at`].
    ///
    /// # Errors
    /// [`crate::Error::InvalidParameter`] if `s` is off the robot,
    /// [`crate::Error::DimensionMismatch`] if `q` does not have `n_q` entries.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 4)]).build_planar()?;
    /// let q = robot.reference_configuration();
    /// let p = robot.position_at(q.as_slice(), 0.1)?;
    /// assert!((p - nalgebra::dvector![0.1, 0.0]).norm() < 1e-14);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn position_at(&self, q: &[f64], s: f64) -> Result<DVector<f64>> {
        self.rod.position_at(q, s)
    }

    /// [`Robot::position_at`] as a fixed-size point of dimension `D`
    /// (`robot.position_at_fixed::<2>(&q, s)` for a planar robot).
    ///
    /// # Errors
    /// As [`Robot::position_at`]; [`crate::Error::DimensionMismatch`] if
    /// `D` is not the robot's dimension.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 4)]).build_planar()?;
    /// let q = robot.reference_configuration();
    /// let p: nalgebra::Vector2<f64> = robot.position_at_fixed(q.as_slice(), 0.1)?;
    /// assert!((p - nalgebra::Vector2::new(0.1, 0.0)).norm() < 1e-14);
    /// assert!(robot.position_at_fixed::<3>(q.as_slice(), 0.1).is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn position_at_fixed<const D: usize>(&self, q: &[f64], s: f64) -> Result<SVector<f64, D>> {
        check_len("position dimension", E::DIM, D)?;
        let p = self.rod.position_at(q, s)?;
        Ok(SVector::from_column_slice(p.as_slice()))
    }

    /// The dead (configuration-independent) generalized forces over all
    /// coordinates: self-weight, line loads, point forces and `J_QF F` (N).
    ///
    /// # Errors
    /// As [`Robot::validate_loads`]; [`crate::Error::NonFinite`] if the forces
    /// overflow.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// use softrod::loads::{Loads, PointForce};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 4)]).build_planar()?;
    /// let loads = Loads { point_forces: vec![PointForce { s_m: 0.24, force_n: vec![0.0, -0.01] }], ..Loads::default() };
    /// let dead = robot.dead_force(&loads)?;
    /// // the tip force sits on the tip node's position coordinates
    /// assert!((dead[robot.n_q() - 3] + 0.01).abs() < 1e-15);
    /// // at the straight reference the residual is the dead force, restricted
    /// let q = robot.reference_configuration();
    /// let r = robot.residual(q.as_slice(), dead.as_slice(), &loads)?;
    /// assert!((r - robot.restrict(dead.as_slice())?).norm() < 1e-12);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn dead_force(&self, loads: &Loads) -> Result<DVector<f64>> {
        self.validate_loads(loads)?;
        self.rod.dead_force(loads)
    }

    /// The section torques `M_s = Σ_c G_c P_c` (N·m): a `MOMENT_DIM ×
    /// n_sections` matrix, column `s` the torque of section `s` (pressures
    /// beyond [`Robot::n_pressures`] are ignored, missing ones count as 0).
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{Chamber, RobotSpec, Section};
    /// let mut section = Section::uniform(0.24, 300.0, 0.025, 4);
    /// section.chambers = vec![Chamber { gain_nm_per_pa: vec![1e-6], pressure_min_pa: -1e5, pressure_max_pa: 1e5 }];
    /// let robot = RobotSpec::new(vec![section]).build_planar()?;
    /// let m = robot.section_torques(&[2e4]);
    /// assert_eq!(m.shape(), (1, 1));
    /// assert!((m[(0, 0)] - 0.02).abs() < 1e-15);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn section_torques(&self, pressures: &[f64]) -> DMatrix<f64> {
        self.rod.section_torques(pressures)
    }

    /// Generalized force `Q(q)` over the free coordinates (17): the dead
    /// forces `dead` (from [`Robot::dead_force`]), minus the elastic gradient,
    /// plus the actuation and the concentrated moments `∂W/∂q`.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] for wrong sizes.
    ///
    /// # Example
    /// See [`Robot::dead_force`].
    pub fn residual(&self, q: &[f64], dead: &[f64], loads: &Loads) -> Result<DVector<f64>> {
        let mut out = DVector::zeros(self.n_free());
        self.residual_into(q, dead, loads, out.as_mut_slice())?;
        Ok(out)
    }

    /// `∂Q/∂P` over the free coordinates: column `c` is the generalized force
    /// of chamber `c` per pascal, `G_c · ∂(θ_end − θ_start)/∂q` (an
    /// `n_free × n_pressures` matrix).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `q` has the wrong size.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{Chamber, RobotSpec, Section};
    /// let mut section = Section::uniform(0.24, 300.0, 0.025, 4);
    /// section.chambers = vec![Chamber { gain_nm_per_pa: vec![1e-6], pressure_min_pa: -1e5, pressure_max_pa: 1e5 }];
    /// let robot = RobotSpec::new(vec![section]).build_planar()?;
    /// let j = robot.pressure_jacobian(robot.reference_configuration().as_slice())?;
    /// assert_eq!(j.shape(), (robot.n_free(), 1));
    /// // straight and unloaded: a pressure bends, so its force is a moment at the tip
    /// assert!(j.column(0).norm() > 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn pressure_jacobian(&self, q: &[f64]) -> Result<DMatrix<f64>> {
        let nd = E::NODE_DOFS;
        check_len("q", self.n_q(), q.len())?;
        let np = self.n_pressures();
        let mut jac = DMatrix::zeros(self.n_free(), np);
        let mut scratch = [0.0; MAX_EDOF * MAX_EDOF];
        let mut col = vec![0.0; self.n_free()];
        for (c, ch) in self.rod.chamber_refs().iter().enumerate() {
            col.iter_mut().for_each(|v| *v = 0.0);
            let (a, b) = self.rod.section_nodes()[ch.section];
            for (node, sign) in [(b, 1.0), (a, -1.0)] {
                let m: Vec<f64> = ch.gain.iter().map(|g| sign * g).collect();
                let mut g = [0.0; MAX_EDOF];
                E::add_moment_work(
                    &self.base_node,
                    &q[node * nd..(node + 1) * nd],
                    &m,
                    &mut g[..nd],
                    &mut scratch[..nd * nd],
                );
                self.scatter_force(node * nd, &g[..nd], 1.0, &mut col)?;
            }
            jac.column_mut(c).copy_from_slice(&col);
        }
        Ok(jac)
    }

    /// Node positions `r_i` (m): a `DIM × nodes` matrix, column `i` the
    /// position of node `i` of `q` (a trailing partial node is ignored, so
    /// this never panics).
    ///
    /// A matrix, not a list of fixed-size points: the dimension is the
    /// element's (`E::DIM`), which a generic robot cannot name as a type;
    /// a matrix keeps this infallible for every element and gives the rows
    /// (all x, all y) as well as the columns. For a planar robot,
    /// [`crate::shape::Shape::node_positions`] gives `Point2`s and
    /// [`Robot::position_at`] a fixed-size point anywhere.
    ///
    /// # Example
    /// ```
    /// use softrod::assembly::{RobotSpec, Section};
    /// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 4)]).build_planar()?;
    /// let r = robot.node_positions(robot.reference_configuration().as_slice());
    /// assert_eq!(r.shape(), (2, 5));
    /// assert!((r.column(4) - nalgebra::Vector2::new(0.24, 0.0)).norm() < 1e-15);
    /// assert!(r.row(1).iter().all(|y| *y == 0.0));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn node_positions(&self, q: &[f64]) -> DMatrix<f64> {
        self.rod.node_positions(q)
    }
}
