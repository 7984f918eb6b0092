//! Covariances of the estimate for the stated marker noise (beyond the
//! paper): the Gauss–Newton-linearized estimator
//! `F̂ ≈ (JᵀWJ + αH)⁻¹ JᵀW y` with `Cov(y) = σ² I` has
//! `Cov(F) = L Lᵀ`, `L = σ (JᵀWJ + αH)⁻¹ JᵀW` (`n_F × n_ob`), taken at the
//! last linearization (the Gauss–Newton Hessian (30)).

use nalgebra::DMatrix;

use crate::element::Element;
use crate::observe::ObservationOperator;

use super::problem::{weighted_columns, Derivs, GnFactor, Problem};
use super::{Estimate, LoadModel};

/// The covariance factor `L = σ (JᵀWJ + αH)⁻¹ JᵀW` (`n_F × n_ob`,
/// row-major) from the factor of [`Problem::gn_solve`] at the same
/// derivatives: `σ Z S⁻¹` for the distributed load (the representer form,
/// `S = α W⁻¹ + Zᵀ B Z`), `σ N⁻¹ JᵀW` for a concentrated one.
pub(crate) fn cov_factor<E: Element>(
    problem: &Problem<E>,
    dv: &Derivs,
    op: &ObservationOperator,
    fac: &GnFactor,
) -> Vec<f64> {
    let sigma = problem.settings().noise_sigma_m;
    let l = match problem.load() {
        // σ Z S⁻¹: the small inverse, then one product
        LoadModel::Distributed => &dv.z * (fac.0.inverse() * sigma),
        LoadModel::Concentrated { .. } => {
            fac.0.solve(&weighted_columns(&dv.jt, op.weights())) * sigma
        }
    };
    row_major(&l)
}

/// `Cov(resultant force)` (`DIM × DIM`) and `Cov(A q)` (`n_ob × n_ob`),
/// both row-major, from the covariance factor `L` (row-major `n_F × n_ob`),
/// the map `C: F → ∫ w dX` (row-major `DIM × n_F`) and the marker
/// Jacobian: `(C L)(C L)ᵀ` and `(J L)(J L)ᵀ`.
pub(crate) fn resultant_and_marker_cov(
    cov_factor: &[f64],
    fw: &[f64],
    dv: &Derivs,
) -> (Vec<f64>, Vec<f64>) {
    let nf = dv.jt.nrows();
    let m = dv.jt.ncols();
    let d = fw.len().checked_div(nf).unwrap_or(0);
    let lt = DMatrix::from_column_slice(m, nf, cov_factor);
    // (C L)ᵀ = Lᵀ Cᵀ, Cᵀ column-major is C row-major
    let cl_t = &lt * DMatrix::from_column_slice(nf, d, fw);
    // (J L)ᵀ = Lᵀ Jᵀ
    let jl_t = &lt * &dv.jt;
    (
        row_major(&cl_t.tr_mul(&cl_t)),
        row_major(&jl_t.tr_mul(&jl_t)),
    )
}

/// The entries of `a` row by row.
fn row_major(a: &DMatrix<f64>) -> Vec<f64> {
    a.transpose().as_slice().to_vec()
}

impl Estimate {
    /// `Cov(F) = L Lᵀ` (`n_F × n_F`, row-major) for the stated marker noise:
    /// the covariance of the Gauss–Newton-linearized estimator,
    /// `F̂ ≈ (JᵀWJ + αH)⁻¹ JᵀW y`, with `J` the marker Jacobian `∂(Aq)/∂F`
    /// and `Cov(y) = σ² I`.
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{Backend, EstimatorSettings, LoadModel, Observation};
    /// use softrod::{scene::Scene, statics::StaticSolver};
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let obs = Observation::at_nodes(&robot, &eq.q, &[10, 20]);
    /// let settings = EstimatorSettings {
    ///     load_model: LoadModel::Concentrated { node: 20 }, alpha: Some(1.0), ..Default::default()
    /// };
    /// let e = Backend::Newton.build(robot, loads, settings)?.step(&obs)?;
    /// let c = e.covariance_f();
    /// assert_eq!(c.len(), 4);
    /// assert!((c[0].sqrt() - e.std_f()[0]).abs() <= 1e-12 * c[0].sqrt() && c[1] == c[2]);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn covariance_f(&self) -> Vec<f64> {
        let lt = self.cov_factor_t();
        row_major(&lt.tr_mul(&lt))
    }

    /// Standard deviations of the entries of `F` (square roots of the
    /// diagonal of [`Estimate::covariance_f`]).
    ///
    /// # Example
    /// See [`Estimate::covariance_f`].
    pub fn std_f(&self) -> Vec<f64> {
        self.cov_factor_t()
            .column_iter()
            .map(|c| c.norm())
            .collect()
    }

    /// `Lᵀ` (`n_ob × n_F`).
    fn cov_factor_t(&self) -> DMatrix<f64> {
        DMatrix::from_column_slice(self.n_ob, self.f.len(), &self.cov_factor)
    }
}
