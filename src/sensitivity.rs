//! Sensitivities of an equilibrium: how the shape and what is observed of it
//! move with the load and the pressures, by linear and adjoint solves with
//! one factorization of the tangent.
//!
//! At an equilibrium `Q(F, q, P) = 0` (17) with the tangent `K = −∂Q/∂q` over
//! the free coordinates `u` (`q = q(u)`, `dq = M du`, see
//! [`Robot::expand_step`]), a change of the generalized force `dQ` moves the
//! shape by `dq = M K⁻¹ Mᵀ dQ`. So
//!
//! - (28) `∂q/∂F = M K⁻¹ Mᵀ G` for a load `Q_F = G F` ([`LinearLoad`]):
//!   [`Sensitivity::dq_df`];
//! - (43) `∂q/∂P = −(∂Q/∂q)⁻¹ ∂Q/∂P = M K⁻¹ ∂Q/∂P` for the chamber
//!   pressures: [`Sensitivity::dq_dp`];
//! - an output `y_i = c_i · q` (a marker coordinate of the estimator's `A`
//!   (25), the end-effector pose of a controller (50)) has
//!   `∂y_i/∂F = (Gᵀ z_i)ᵀ` and `∂y_i/∂P = (∂Q/∂Pᵀ u_i)ᵀ` with the adjoint
//!   fields `u_i = K⁻¹ Mᵀ c_i`, `z_i = M u_i` (`K` is symmetric): one solve
//!   per output instead of one per parameter ([`Sensitivity::adjoints`],
//!   [`Sensitivity::load_gradients`], [`Sensitivity::pressure_gradients`]).
//!
//! The estimator's marker Jacobian (28)–(30) and a controller's (43), (50)
//! are this one machinery.
//!
//! A [`Sensitivity`] is made from the robot and any factors of its tangent
//! at the equilibrium ([`Factorization`]: those an
//! [`EquilibriumTracker`](crate::statics::EquilibriumTracker) returns, or
//! one's own from a [`TangentSolver`](crate::linsolve::TangentSolver));
//! many right-hand sides are solved in one sweep over the factors
//! ([`Factorization::solve_columns_in_place`]).
//!
//! # Example
//! ```
//! use softrod::{estimate::LoadModel, scene::Scene, sensitivity::Sensitivity, statics::EquilibriumTracker};
//! let scene = Scene::two_section();
//! let robot = scene.robot()?;
//! let n = robot.n_q();
//! let mut tracker = EquilibriumTracker::new(robot, scene.loads()?, Default::default())?;
//! let load = LoadModel::Concentrated { node: 20 };
//! let q0 = tracker.robot().arc_configuration(&scene.pressures_pa);
//! let eq = tracker.solve(&load, &[0.0, 0.0], q0.as_slice())?;
//! let s = Sensitivity::new(tracker.robot(), &eq.factors)?;
//! // (28): an upward tip force moves the tip up
//! let dq_df = s.dq_df(&load)?;
//! assert!(dq_df[(n - 3, 1)] > 0.0);
//! // the same number by an adjoint solve for the output "tip y"
//! let adj = s.adjoints([&[(n - 3, 1.0)][..]])?;
//! let grad = s.load_gradients(&load, &adj)?;
//! assert!((grad[(1, 0)] - dq_df[(n - 3, 1)]).abs() < 1e-12 * grad[(1, 0)].abs());
//! # Ok::<(), softrod::Error>(())
//! ```
//!
//! The same from factors made by hand: the tangent assembled on the robot's
//! pattern and factored by a solver of one's choice.
//! ```
//! use softrod::linsolve::{AutoSolver, FactorOptions, SolverKind, SymmetricMatrix, TangentSolver};
//! use softrod::{scene::Scene, sensitivity::Sensitivity, statics::StaticSolver};
//! let scene = Scene::two_section();
//! let (robot, loads) = (scene.robot()?, scene.loads()?);
//! let eq = StaticSolver::default().solve(&robot, &loads, None)?;
//! let mut k = SymmetricMatrix::zeros(robot.tangent_pattern().clone());
//! robot.tangent_into(eq.q.as_slice(), &loads, &mut k)?;
//! let mut solver = AutoSolver::with_kind(robot.tangent_pattern(), SolverKind::Sparse)?;
//! let factors = solver.factor(&k, FactorOptions::default())?;
//! let s = Sensitivity::new(&robot, &factors)?;
//! // (43): raising a chamber's pressure moves the shape
//! let dq_dp = s.dq_dp(eq.q.as_slice())?;
//! assert_eq!(dq_dp.shape(), (robot.n_q(), robot.n_pressures()));
//! assert!(dq_dp.amax() > 0.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use nalgebra::{DMatrix, DVector};

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{Error, Result, check_len};
use crate::linsolve::{AutoFactors, Factorization};
use crate::statics::LinearLoad;
use crate::structure::{Actuated, Model};

/// The sensitivities of one equilibrium of `robot`, from the factors `F` of
/// its tangent `K` there (as [`crate::statics::EquilibriumTracker`] returns
/// them: [`AutoFactors`], the default; any [`Factorization`] will do).
///
/// # Example
/// See the [module documentation](self).
#[derive(Debug)]
pub struct Sensitivity<'a, M: Model, F: Factorization = AutoFactors> {
    robot: &'a M,
    /// The free coordinates of the equilibrium (the map's Jacobian `T(u)`
    /// is taken there; the clamped robot's map is linear).
    u: &'a [f64],
    factors: &'a F,
}

impl<M: Model, F: Factorization> Clone for Sensitivity<'_, M, F> {
    fn clone(&self) -> Self {
        *self
    }
}

impl<M: Model, F: Factorization> Copy for Sensitivity<'_, M, F> {}

/// Adjoint fields of `m` outputs `y_i = c_i · q`, column `i` each.
///
/// # Example
/// See the [module documentation](self).
#[derive(Debug, Clone, PartialEq)]
pub struct Adjoints {
    /// `u_i = K⁻¹ Mᵀ c_i` over the free coordinates (`n_free × m`).
    pub free: DMatrix<f64>,
    /// `z_i = M u_i` over all coordinates (`n_q × m`).
    pub full: DMatrix<f64>,
}

impl<'a, E: Element, F: Factorization> Sensitivity<'a, Robot<E>, F> {
    /// The sensitivities of the clamped robot at an equilibrium whose
    /// tangent's factors (over the free coordinates) are `factors` (its map
    /// `q = φ(u)` is linear: [`Sensitivity::at`] without the point).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if the factors are not `n_free` square.
    ///
    /// # Example
    /// See the [module documentation](self).
    pub fn new(robot: &'a Robot<E>, factors: &'a F) -> Result<Self> {
        check_len("factors", robot.n_free(), factors.n())?;
        Ok(Sensitivity {
            robot,
            u: &[],
            factors,
        })
    }
}

impl<'a, M: Model, F: Factorization> Sensitivity<'a, M, F> {
    /// The sensitivities of any model at the equilibrium of free
    /// coordinates `u` whose tangent's factors are `factors`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `u` is not `n_free` long or the
    /// factors are not `n_free` square.
    ///
    /// # Example
    /// The parallel robot's platform moving under a force on it:
    /// ```
    /// use softrod::{estimate::LoadModel, sensitivity::Sensitivity, site::Site, statics::Tracker};
    /// let robot = softrod::parallel::ParallelSpec::default().build_cable()?;
    /// let s = robot.structure();
    /// let loads = robot.loads(&[], [0.0; 3], [0.0; 3])?;
    /// let mut tracker = Tracker::new(s.clone(), loads, Default::default())?;
    /// let load = LoadModel::AtSite { site: Site::Body { body: 0 } };
    /// let q0 = s.configuration(s.reference_free_coordinates())?;
    /// let eq = tracker.solve(&load, &[0.0; 3], q0.as_slice())?;
    /// let dq_df = Sensitivity::at(s, eq.u.as_slice(), &eq.factors)?.dq_df(&load)?;
    /// // a downward force moves the platform down
    /// let z = s.body_coordinates(0)?.start + 2;
    /// assert!(dq_df[(z, 2)] > 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn at(model: &'a M, u: &'a [f64], factors: &'a F) -> Result<Self> {
        check_len("u", model.n_free(), u.len())?;
        check_len("factors", model.n_free(), factors.n())?;
        Ok(Sensitivity {
            robot: model,
            u,
            factors,
        })
    }

    /// The shape's response `dq = M K⁻¹ Mᵀ g` to a change `g` of the
    /// generalized force over all `n_q` coordinates (N).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `g` is not `n_q` long.
    ///
    /// # Example
    /// ```
    /// use softrod::{estimate::LoadModel, scene::Scene, sensitivity::Sensitivity, statics::EquilibriumTracker};
    /// let scene = Scene::two_section();
    /// let robot = scene.robot()?;
    /// let n = robot.n_q();
    /// let mut tracker = EquilibriumTracker::new(robot, scene.loads()?, Default::default())?;
    /// let load = LoadModel::Concentrated { node: 20 };
    /// let q0 = tracker.robot().arc_configuration(&scene.pressures_pa);
    /// let eq = tracker.solve(&load, &[0.0, 0.0], q0.as_slice())?;
    /// let mut g = nalgebra::DVector::zeros(n);
    /// g[n - 3] = -1e-3; // 1 mN down at the tip
    /// let dq: nalgebra::DVector<f64> =
    ///     Sensitivity::new(tracker.robot(), &eq.factors)?.response(g.as_slice())?;
    /// assert!(dq[n - 3] < 0.0); // the tip moves down
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn response(&self, g: &[f64]) -> Result<DVector<f64>> {
        check_len("g", self.robot.n_q(), g.len())?;
        let mut du = vec![0.0; self.robot.n_free()];
        self.robot.restrict_into(self.u, g, &mut du)?;
        self.factors.solve_in_place(&mut du)?;
        let mut dq = DVector::zeros(self.robot.n_q());
        self.robot.step_into(self.u, &du, dq.as_mut_slice())?;
        Ok(dq)
    }

    /// (28) `∂q/∂F = M K⁻¹ Mᵀ G` (`n_q × n_F`) for the load `load`: one
    /// solve per parameter, sharing the factorization.
    ///
    /// # Errors
    /// The errors of [`LinearLoad::force`].
    pub fn dq_df<L: LinearLoad<M>>(&self, load: &L) -> Result<DMatrix<f64>> {
        let nf = load.n_params(self.robot);
        let nfree = self.robot.n_free();
        let mut b = vec![0.0; nfree * nf];
        let mut ej = vec![0.0; nf];
        for (j, col) in b.chunks_exact_mut(nfree.max(1)).enumerate() {
            ej.iter_mut()
                .enumerate()
                .for_each(|(k, v)| *v = f64::from(u8::from(k == j)));
            let g = load.force(self.robot, &ej)?;
            self.robot.restrict_into(self.u, g.as_slice(), col)?;
        }
        self.expand_columns(b, nf)
    }

    /// The adjoint fields of the outputs `rows` (each sparse over all `n_q`
    /// coordinates: `(index, coefficient)`), one solve each, in one sweep
    /// over the factors.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for an index beyond `n_q`.
    pub fn adjoints<'r>(
        &self,
        rows: impl IntoIterator<Item = &'r [(usize, f64)]>,
    ) -> Result<Adjoints> {
        let nq = self.robot.n_q();
        let nfree = self.robot.n_free();
        let rows: Vec<&[(usize, f64)]> = rows.into_iter().collect();
        let m = rows.len();
        // right-hand sides Mᵀ c_i, column i each (n_free × m, column-major)
        let mut free = DMatrix::zeros(nfree, m);
        let mut c = vec![0.0; nq];
        for (row, col) in rows
            .iter()
            .zip(free.as_mut_slice().chunks_exact_mut(nfree.max(1)))
        {
            for &(j, w) in row.iter() {
                crate::error::check_index("output row index", j, nq)?;
                c[j] += w;
            }
            self.robot.restrict_into(self.u, &c, col)?;
            for &(j, _) in row.iter() {
                c[j] = 0.0;
            }
        }
        self.factors
            .solve_columns_in_place(free.as_mut_slice(), m)?;
        let mut full = DMatrix::zeros(nq, m);
        for (fi, zi) in free
            .as_slice()
            .chunks_exact(nfree.max(1))
            .zip(full.as_mut_slice().chunks_exact_mut(nq.max(1)))
        {
            self.robot.step_into(self.u, fi, zi)?;
        }
        Ok(Adjoints { free, full })
    }

    /// The gradients `∇_F y_i = Gᵀ z_i` of the outputs of `adjoints` with
    /// respect to the load parameters, column `i` each (`n_F × m`: the
    /// transpose of `∂y/∂F`).
    ///
    /// # Errors
    /// The errors of [`LinearLoad::force_transpose`].
    pub fn load_gradients<L: LinearLoad<M>>(
        &self,
        load: &L,
        adjoints: &Adjoints,
    ) -> Result<DMatrix<f64>> {
        let nf = load.n_params(self.robot);
        let m = adjoints.full.ncols();
        let mut out = DMatrix::zeros(nf, m);
        for (zi, gi) in adjoints
            .full
            .column_iter()
            .zip(out.as_mut_slice().chunks_exact_mut(nf.max(1)))
        {
            let g = load.force_transpose(self.robot, zi.as_slice())?;
            check_len("G^T z", nf, g.len())?;
            gi.copy_from_slice(g.as_slice());
        }
        Ok(out)
    }

    /// Solves `K X = B` for the `ncols` columns of `b` (column-major
    /// `n_free × ncols`) and expands each to all coordinates (`n_q × ncols`).
    fn expand_columns(&self, mut b: Vec<f64>, ncols: usize) -> Result<DMatrix<f64>> {
        let nfree = self.robot.n_free();
        let nq = self.robot.n_q();
        if b.len() != nfree * ncols {
            return Err(Error::DimensionMismatch {
                name: "right-hand sides".into(),
                expected: nfree * ncols,
                got: b.len(),
            });
        }
        self.factors.solve_columns_in_place(&mut b, ncols)?;
        let mut out = DMatrix::zeros(nq, ncols);
        for (u, col) in b
            .chunks_exact(nfree.max(1))
            .zip(out.as_mut_slice().chunks_exact_mut(nq.max(1)))
        {
            self.robot.step_into(self.u, u, col)?;
        }
        Ok(out)
    }
}

impl<'a, M: Actuated, F: Factorization> Sensitivity<'a, M, F> {
    /// (43) `∂q/∂P = −(∂Q/∂q)⁻¹ ∂Q/∂P` (`n_q × n_pressures`, m/Pa) at the
    /// equilibrium `q` of these factors.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `q` is not `n_q` long.
    pub fn dq_dp(&self, q: &[f64]) -> Result<DMatrix<f64>> {
        let jac = self.robot.pressure_jacobian_free(self.u, q)?;
        let np = jac.ncols();
        // n_free × n_p, its columns one after the other
        self.expand_columns(jac.data.into(), np)
    }

    /// The gradients `∇_P y_i = (∂Q/∂P)ᵀ u_i` of the outputs of `adjoints`
    /// with respect to the pressures at the equilibrium `q`, column `i` each
    /// (`n_pressures × m`, per Pa).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `q` is not `n_q` long or `adjoints`
    /// do not fit the robot.
    pub fn pressure_gradients(&self, q: &[f64], adjoints: &Adjoints) -> Result<DMatrix<f64>> {
        let nfree = self.robot.n_free();
        check_len("adjoints", nfree, adjoints.free.nrows())?;
        let jac = self.robot.pressure_jacobian_free(self.u, q)?;
        Ok(jac.tr_mul(&adjoints.free))
    }
}
