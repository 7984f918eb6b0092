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
//! # Example
//! ```
//! use softrod::{estimate::LoadModel, scene::Scene, sensitivity::Sensitivity, statics::EquilibriumTracker};
//! let scene = Scene::two_section();
//! let robot = scene.robot()?;
//! let n = robot.n_q();
//! let mut tracker = EquilibriumTracker::new(robot, scene.loads()?, Default::default())?;
//! let load = LoadModel::Concentrated { node: 20 };
//! let q0 = tracker.robot().arc_configuration(&scene.pressures_pa);
//! let eq = tracker.solve(&load, &[0.0, 0.0], &q0)?;
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

use nalgebra::DMatrix;

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{check_len, Error, Result};
use crate::linsolve::BandedLu;
use crate::statics::LinearLoad;

/// The sensitivities of one equilibrium of `robot`, from the factors of its
/// tangent `K` there (as [`crate::statics::EquilibriumTracker`] returns them).
///
/// # Example
/// See the [module documentation](self).
#[derive(Debug, Clone, Copy)]
pub struct Sensitivity<'a, E: Element> {
    robot: &'a Robot<E>,
    factors: &'a BandedLu,
}

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

impl<'a, E: Element> Sensitivity<'a, E> {
    /// The sensitivities at an equilibrium whose tangent's factors are
    /// `factors`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if the factors are not `n_free` square.
    pub fn new(robot: &'a Robot<E>, factors: &'a BandedLu) -> Result<Self> {
        check_len("factors", robot.n_free(), factors.n())?;
        Ok(Sensitivity { robot, factors })
    }

    /// The shape's response `dq = M K⁻¹ Mᵀ g` to a change `g` of the
    /// generalized force over all `n_q` coordinates (N).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `g` is not `n_q` long.
    pub fn response(&self, g: &[f64]) -> Result<Vec<f64>> {
        let mut du = self.robot.restrict(g)?;
        self.factors.solve_in_place(&mut du)?;
        self.robot.expand_step(&du)
    }

    /// (28) `∂q/∂F = M K⁻¹ Mᵀ G` (`n_q × n_F`) for the load `load`: one
    /// solve per parameter, sharing the factorization.
    ///
    /// # Errors
    /// The errors of [`LinearLoad::force`].
    pub fn dq_df<L: LinearLoad<E>>(&self, load: &L) -> Result<DMatrix<f64>> {
        let nf = load.n_params(self.robot);
        let nfree = self.robot.n_free();
        let mut b = vec![0.0; nfree * nf];
        let mut ej = vec![0.0; nf];
        let mut u = vec![0.0; nfree];
        for j in 0..nf {
            ej.iter_mut()
                .enumerate()
                .for_each(|(k, v)| *v = f64::from(u8::from(k == j)));
            self.robot
                .restrict_into(&load.force(self.robot, &ej)?, &mut u)?;
            for (k, v) in u.iter().enumerate() {
                b[k * nf + j] = *v;
            }
        }
        self.expand_columns(b, nf)
    }

    /// (43) `∂q/∂P = −(∂Q/∂q)⁻¹ ∂Q/∂P` (`n_q × n_pressures`, m/Pa) at the
    /// equilibrium `q` of these factors.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `q` is not `n_q` long.
    pub fn dq_dp(&self, q: &[f64]) -> Result<DMatrix<f64>> {
        let np = self.robot.n_pressures();
        self.expand_columns(self.robot.pressure_jacobian(q)?, np)
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
        // right-hand sides Mᵀ c_i, row-major n_free × m
        let mut b = vec![0.0; nfree * m];
        let mut c = vec![0.0; nq];
        let mut u = vec![0.0; nfree];
        for (i, row) in rows.iter().enumerate() {
            for &(j, w) in row.iter() {
                crate::error::check_index("output row index", j, nq)?;
                c[j] += w;
            }
            self.robot.restrict_into(&c, &mut u)?;
            for (k, v) in u.iter().enumerate() {
                if *v != 0.0 {
                    b[k * m + i] = *v;
                }
            }
            for &(j, _) in row.iter() {
                c[j] = 0.0;
            }
        }
        self.factors.solve_many_in_place(&mut b, m)?;
        let mut free = DMatrix::zeros(nfree, m);
        let mut full = DMatrix::zeros(nq, m);
        for (i, (fi, zi)) in free
            .as_mut_slice()
            .chunks_exact_mut(nfree.max(1))
            .zip(full.as_mut_slice().chunks_exact_mut(nq.max(1)))
            .enumerate()
        {
            for (k, v) in fi.iter_mut().enumerate() {
                *v = b[k * m + i];
            }
            self.robot.expand_step_into(fi, zi)?;
        }
        Ok(Adjoints { free, full })
    }

    /// The gradients `∇_F y_i = Gᵀ z_i` of the outputs of `adjoints` with
    /// respect to the load parameters, column `i` each (`n_F × m`: the
    /// transpose of `∂y/∂F`).
    ///
    /// # Errors
    /// The errors of [`LinearLoad::force_transpose`].
    pub fn load_gradients<L: LinearLoad<E>>(
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
            gi.copy_from_slice(&g);
        }
        Ok(out)
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
        let np = self.robot.n_pressures();
        let jac = DMatrix::from_row_slice(nfree, np, &self.robot.pressure_jacobian(q)?);
        Ok(jac.tr_mul(&adjoints.free))
    }

    /// Solves `K X = B` for the `ncols` columns of `b` (row-major
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
        self.factors.solve_many_in_place(&mut b, ncols)?;
        let mut out = DMatrix::zeros(nq, ncols);
        let mut u = vec![0.0; nfree];
        for (j, col) in out.as_mut_slice().chunks_exact_mut(nq.max(1)).enumerate() {
            for (k, v) in u.iter_mut().enumerate() {
                *v = b[k * ncols + j];
            }
            self.robot.expand_step_into(&u, col)?;
        }
        Ok(out)
    }
}
