//! Covariances of the estimate (beyond the paper), taken at the last
//! linearization (the Gauss–Newton Hessian (30)):
//!
//! - the reported ones (resultant force, marker-space shape) are the
//!   posterior's, `Cov(F | y) = (JᵀWJ + αH)⁻¹`, of the model in which the
//!   penalty is a Gaussian prior (see [`super::evidence`]): noise spread
//!   plus the bias of the penalty; when `α` is the evidence's, averaged
//!   over `α`'s own uncertainty ([`posterior_alpha_marginal`]);
//! - the covariance factor `L = σ (JᵀWJ + αH)⁻¹ JᵀW` (`n_F × n_ob`) of
//!   the linearized estimator `F̂ ≈ (JᵀWJ + αH)⁻¹ JᵀW y` with `Cov(y) =
//!   σ² I`, `Cov(F̂) = L Lᵀ`, is the noise spread alone (no bias).

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

use super::Estimate;
use super::gn_form::{
    GnForm, PenaltyMatrix, count_dense, jittered_cholesky, primal_system, weighted_columns,
};
use super::problem::{Derivs, GnFactor};

mod lazy;
pub(crate) use lazy::{CovarianceInputs, LazyCovariances};

/// What of the marker-space covariance `Cov(A q)` a formula forms: nothing,
/// its diagonal (`n_ob` numbers, work linear in the markers in the primal
/// form) or all of it (`n_ob²` numbers, row-major).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum MarkerPart {
    /// Not formed (empty).
    None,
    /// The variances only.
    Diagonal,
    /// The whole matrix.
    Full,
}

impl MarkerPart {
    /// The numbers the part has for `m` observed components.
    fn len(self, m: usize) -> usize {
        match self {
            MarkerPart::None => 0,
            MarkerPart::Diagonal => m,
            MarkerPart::Full => m * m,
        }
    }

    /// The part of the symmetric `m × m` matrix `a`.
    fn of(self, a: &DMatrix<f64>) -> Vec<f64> {
        match self {
            MarkerPart::None => Vec::new(),
            MarkerPart::Diagonal => a.diagonal().as_slice().to_vec(),
            MarkerPart::Full => row_major(a),
        }
    }
}

/// The covariance factor `L = σ (JᵀWJ + αH)⁻¹ JᵀW` (`n_F × n_ob`), from
/// the Gauss–Newton system's factor at the same derivatives when it was
/// formed at `alpha` (else anew): `σ Z S⁻¹` in the representer form
/// (`S = α W⁻¹ + Zᵀ B Z`), `σ N⁻¹ JᵀW` in the primal form. `None` if that
/// system cannot be factored.
fn cov_factor(
    form: &GnForm,
    sigma: f64,
    dv: &Derivs,
    w: &[f64],
    alpha: f64,
    gn: Option<&GnFactor>,
) -> Option<DMatrix<f64>> {
    Some(match form {
        // σ Z S⁻¹: the small inverse, then one product
        GnForm::Representer => {
            let (_, chol) = representer_system(dv, w, alpha, gn)?;
            &dv.z * (chol.inverse() * sigma)
        }
        GnForm::Primal(h) => {
            primal_factor(dv, w, alpha, h, gn)?.solve(&weighted_columns(&dv.jt, w)) * sigma
        }
    })
}

/// `Zᵀ B Z` (symmetric) and the factor of `S = Zᵀ B Z + α W⁻¹` for the
/// distributed load: from `gn` when it was formed at `alpha`, else anew.
fn representer_system(
    dv: &Derivs,
    w: &[f64],
    alpha: f64,
    gn: Option<&GnFactor>,
) -> Option<(DMatrix<f64>, Cholesky<f64, Dyn>)> {
    if let Some(GnFactor {
        chol,
        gram: Some(k),
        alpha: a,
    }) = gn
        && *a == alpha
        && k.nrows() == w.len()
    {
        return Some((k.clone(), chol.clone()));
    }
    let m = w.len();
    count_dense(m * m * dv.jt.nrows() + m * m * m / 3);
    let k = dv.z.tr_mul(&dv.jt);
    let k = (&k + k.transpose()) * 0.5;
    let mut s = k.clone();
    for (i, wi) in w.iter().enumerate() {
        s[(i, i)] += alpha / wi;
    }
    Some((k, jittered_cholesky(s)?))
}

/// The factor of `N = Jᵀ W J + α H` (the primal form): from `gn` when it
/// was formed at `alpha`, else anew.
fn primal_factor(
    dv: &Derivs,
    w: &[f64],
    alpha: f64,
    h: &PenaltyMatrix,
    gn: Option<&GnFactor>,
) -> Option<Cholesky<f64, Dyn>> {
    if let Some(GnFactor {
        chol,
        gram: None,
        alpha: a,
    }) = gn
        && *a == alpha
        && chol.l_dirty().nrows() == dv.jt.nrows()
    {
        return Some(chol.clone());
    }
    primal_system(&dv.jt, w, alpha, h)
}

/// The posterior covariances of the resultant force (`DIM × DIM`) and of
/// the marker-space shape `A q` (`n_ob × n_ob`), both row-major, for the
/// linearized model with the penalty as prior (see [`super::evidence`]):
/// `Cov(F | y) = (JᵀWJ + αH)⁻¹`, the spread the noise causes plus the bias
/// the penalty puts in. With the map `C: F → ∫ w dX` (`fw`, row-major
/// `DIM × n_F`):
///
/// - representer form (distributed, `H = B`, `J = Zᵀ B`; no `n_q³` work):
///   `Cov(F | y) = (B⁻¹ − Z S⁻¹ Zᵀ)/α`, `S = α W⁻¹ + Zᵀ B Z`; since
///   `C = E_dᵀ B` (`E_d` the coordinates of a constant unit field),
///   `C B⁻¹ Cᵀ = C E_d` and `Cov(∫w) = (C E_d − (CZ) S⁻¹ (CZ)ᵀ)/α`,
///   `Cov(Aq) = Zᵀ B Z S⁻¹ W⁻¹`;
/// - primal form (concentrated, `H = I`, or distributed, `H = B`):
///   `Cov(F | y) = N⁻¹`, `N = JᵀWJ + αH`, `Cov(A q) = J N⁻¹ Jᵀ`.
///
/// `None` if the Gauss–Newton matrix is not positive definite. `form`:
/// the form of the system, `nd` coordinates per node (the first `DIM` of them the
/// position), `w` the weights; `gn`: the factor of the Gauss–Newton system
/// at the same derivatives, if at hand (used when formed at this `α`).
/// `markers`: what of `Cov(A q)` to form (all of it: `O(n_ob² n_F)` work
/// and `n_ob²` numbers; its diagonal in the primal form `|L⁻¹ j_i|²`,
/// `N = L Lᵀ`: `O(n_ob n_F²)` work and `n_ob` numbers).
#[allow(clippy::too_many_arguments)]
fn posterior(
    form: &GnForm,
    nd: usize,
    fw: &[f64],
    dv: &Derivs,
    w: &[f64],
    alpha: f64,
    gn: Option<&GnFactor>,
    markers: MarkerPart,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let m = w.len();
    let nf = dv.jt.nrows();
    let d = fw.len().checked_div(nf).unwrap_or(0);
    let c = DMatrix::from_row_slice(d, nf, fw);
    match form {
        GnForm::Representer => {
            let (k, chol) = representer_system(dv, w, alpha, gn)?;
            // C E_d: the columns of C at the position slots of component b
            let mut ce = DMatrix::zeros(d, d);
            for a in 0..d {
                for b in 0..d {
                    ce[(a, b)] = (0..nf / nd).map(|n| c[(a, n * nd + b)]).sum::<f64>();
                }
            }
            let cz = &c * &dv.z;
            let s_inv_czt = chol.solve(&cz.transpose());
            let r = (ce - &cz * s_inv_czt) / alpha;
            let r = (&r + r.transpose()) * 0.5;
            if markers == MarkerPart::None {
                return Some((row_major(&r), Vec::new()));
            }
            // Zᵀ B Z S⁻¹ W⁻¹ (the representer form serves up to n_F
            // observed components: m² is bounded by n_F²)
            let mut winv = DMatrix::zeros(m, m);
            for i in 0..m {
                winv[(i, i)] = 1.0 / w[i];
            }
            let mk = &k * chol.solve(&winv);
            let mk = (&mk + mk.transpose()) * 0.5;
            Some((row_major(&r), markers.of(&mk)))
        }
        GnForm::Primal(h) => {
            let chol = primal_factor(dv, w, alpha, h, gn)?;
            let ninv = chol.inverse();
            let r = &c * &ninv * c.transpose();
            let mk = match markers {
                MarkerPart::None => Vec::new(),
                MarkerPart::Full => row_major(&(dv.jt.transpose() * &ninv * &dv.jt)),
                // jᵢᵀ N⁻¹ jᵢ = |L⁻¹ jᵢ|², column by column
                MarkerPart::Diagonal => {
                    let x = chol.l().solve_lower_triangular(&dv.jt)?;
                    x.column_iter().map(|col| col.norm_squared()).collect()
                }
            };
            Some((row_major(&r), mk))
        }
    }
}

/// The prior covariance of the resultant force at `alpha` (`DIM × DIM`,
/// row-major): `C (αH)⁻¹ Cᵀ`, what the penalty read as a prior says of
/// the resultant before any marker. Representer form (`H = B`, `C = E_dᵀ
/// B`): `C E_d / α`, as in [`posterior`]; primal form: with the factor of
/// `H`. `nf` load parameters, `nd` coordinates per node. `None` if `H`
/// cannot be factored.
pub(crate) fn prior_resultant(
    form: &GnForm,
    nd: usize,
    fw: &[f64],
    nf: usize,
    alpha: f64,
) -> Option<Vec<f64>> {
    let d = fw.len().checked_div(nf).unwrap_or(0);
    let c = DMatrix::from_row_slice(d, nf, fw);
    let r = match form {
        GnForm::Representer => {
            let mut ce = DMatrix::zeros(d, d);
            for a in 0..d {
                for b in 0..d {
                    ce[(a, b)] = (0..nf / nd).map(|n| c[(a, n * nd + b)]).sum::<f64>();
                }
            }
            ce / alpha
        }
        GnForm::Primal(h) => {
            let chol = h.h.clone().cholesky()?;
            count_dense(nf * nf * nf / 3 + d * nf * nf);
            &c * chol.solve(&c.transpose()) / alpha
        }
    };
    Some(row_major(&((&r + r.transpose()) * 0.5)))
}

/// The largest eigenvalue of `P⁻¹ Σ` for symmetric `P` (positive definite)
/// and `Σ`, the largest ratio `uᵀ Σ u / uᵀ P u` over directions `u`, and
/// that `u` (unit length): from `M = L⁻¹ Σ L⁻ᵀ` (`P = L Lᵀ`), whose top
/// eigenvector `v` gives `u ∝ L⁻ᵀ v`. `None` unless `P` is positive
/// definite.
pub(crate) fn largest_relative_variance(
    p: DMatrix<f64>,
    sigma: &DMatrix<f64>,
) -> Option<(f64, DVector<f64>)> {
    let l = p.cholesky()?.l();
    let x = l.solve_lower_triangular(sigma)?;
    let m = l.solve_lower_triangular(&x.transpose())?;
    let eig = ((&m + m.transpose()) * 0.5).symmetric_eigen();
    let k = eig.eigenvalues.argmax().0;
    let u = l
        .transpose()
        .solve_upper_triangular(&eig.eigenvectors.column(k))?;
    let n = u.norm();
    Some((eig.eigenvalues[k], u / n))
}

/// The largest `σ` of `ln α` (one decade): where the evidence is flatter
/// than that, its curvature says little about where the truth's `α` is.
pub(crate) const SIGMA_LN_ALPHA_MAX: f64 = std::f64::consts::LN_10;

/// How uncertain the evidence leaves `α`, and how the estimate moves with
/// it, at a fixed linearization.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct AlphaSpread {
    /// Standard deviation of `ln α` under the evidence (Laplace):
    /// `σ² = 2 / (d²(−2 log p)/d(ln α)²)`, at most [`SIGMA_LN_ALPHA_MAX`].
    pub sigma_ln: f64,
    /// `d(C F̂)/d ln α`: how the resultant force moves with `α` (`DIM`).
    pub force: DVector<f64>,
    /// `d(J F̂)/d ln α`: how the predicted markers move with `α` (`n_ob`).
    pub marker: DVector<f64>,
}

/// The curvature `d²(−2 log p(y | α))/d(ln α)²` of the evidence of the
/// linearized model `y = J F + n`, `F ~ N(0, (αH)⁻¹)`, `n ~ N(0, W⁻¹)`, at
/// its minimizer `F̂` (with `u = J F̂`, `pen = F̂ᵀ H F̂`) and `K = J H⁻¹ Jᵀ`
/// (`n_ob × n_ob`). With `C = W⁻¹ + K/α` the marginal covariance of `y`,
/// `P = C⁻¹`, `T = P K/α` (so `γ = tr T`):
///
/// ```text
/// −2 log p = yᵀ P y + log det C + const
/// d/d ln α   = α pen − γ
/// d²/d ln α² = 2 uᵀ P u − α pen − tr(T²) + γ
/// ```
///
/// (`P y = W e`, `Jᵀ W e = α H F̂` and `u = K P y / α` express the data
/// through the estimate). `None` if `C` cannot be factored.
pub(crate) fn evidence_curvature(
    k: &DMatrix<f64>,
    w: &[f64],
    alpha: f64,
    u: &DVector<f64>,
    pen: f64,
) -> Option<f64> {
    let m = w.len();
    let mut c = k / alpha;
    for i in 0..m {
        c[(i, i)] += 1.0 / w[i];
    }
    let c = (&c + c.transpose()) * 0.5;
    let chol = jittered_cholesky(c)?;
    let t = chol.solve(&(k / alpha));
    let gamma = t.trace();
    let tt = (&t * &t).trace();
    let pu = chol.solve(u);
    Some(2.0 * u.dot(&pu) - alpha * pen - tt + gamma)
}

/// [`evidence_curvature`] in the primal form, without `m × m` matrices:
/// with `N = JᵀWJ + αH` (factor `chol`), Woodbury gives `P = W − W J N⁻¹
/// Jᵀ W` (so `uᵀ P u = uᵀ W u − aᵀ N⁻¹ a`, `a = Jᵀ W u`), and `T` has the
/// nonzero eigenvalues of `T' = N⁻¹ JᵀWJ = I − α N⁻¹ H`: `γ = tr T'`,
/// `tr(T²) = tr(T'²)`.
fn evidence_curvature_primal(
    dv: &Derivs,
    w: &[f64],
    alpha: f64,
    chol: &Cholesky<f64, Dyn>,
    h: &PenaltyMatrix,
    u: &DVector<f64>,
    pen: f64,
) -> f64 {
    let nf = dv.jt.nrows();
    let wu = DVector::from_iterator(u.len(), u.iter().zip(w).map(|(a, b)| a * b));
    let a = &dv.jt * &wu;
    let upu = u.dot(&wu) - a.dot(&chol.solve(&a));
    // T' = I − α N⁻¹ H
    let mut t = chol.solve(&h.h) * (-alpha);
    for i in 0..nf {
        t[(i, i)] += 1.0;
    }
    count_dense(nf * nf * nf);
    let gamma = t.trace();
    let tt: f64 = t.iter().zip(t.transpose().iter()).map(|(a, b)| a * b).sum();
    2.0 * upu - alpha * pen - tt + gamma
}

/// The [`AlphaSpread`] of the estimate `f` (penalty `pen = fᵀ H f`) at
/// `alpha`, in the system's form `form` (see [`posterior`] for `fw`, `dv`,
/// `w`). At a fixed linearization the minimizer moves as
/// `dF̂/d ln α = −N⁻¹ α H F̂` (`N = JᵀWJ + αH`): `−(F̂ − Z S⁻¹ J F̂)` in
/// the representer form, `−α N⁻¹ H F̂` in the primal form.
#[allow(clippy::too_many_arguments)]
pub(crate) fn alpha_spread(
    form: &GnForm,
    fw: &[f64],
    dv: &Derivs,
    w: &[f64],
    alpha: f64,
    f: &[f64],
    pen: f64,
    gn: Option<&GnFactor>,
) -> Option<AlphaSpread> {
    let m = w.len();
    let nf = dv.jt.nrows();
    if f.len() != nf || m != dv.jt.ncols() {
        return None;
    }
    let d = fw.len().checked_div(nf).unwrap_or(0);
    let cm = DMatrix::from_row_slice(d, nf, fw);
    let fv = DVector::from_column_slice(f);
    let u = dv.jt.tr_mul(&fv);
    let (curv, df) = match form {
        GnForm::Representer => {
            let (k, chol) = representer_system(dv, w, alpha, gn)?;
            let df = -(&fv - &dv.z * chol.solve(&u));
            (evidence_curvature(&k, w, alpha, &u, pen)?, df)
        }
        GnForm::Primal(h) => {
            let chol = primal_factor(dv, w, alpha, h, gn)?;
            let df = -chol.solve(&(&h.h * &fv)) * alpha;
            let curv = evidence_curvature_primal(dv, w, alpha, &chol, h, &u, pen);
            (curv, df)
        }
    };
    let sigma_ln = if curv > 2.0 / (SIGMA_LN_ALPHA_MAX * SIGMA_LN_ALPHA_MAX) {
        (2.0 / curv).sqrt()
    } else {
        SIGMA_LN_ALPHA_MAX
    };
    Some(AlphaSpread {
        sigma_ln,
        force: &cm * &df,
        marker: dv.jt.tr_mul(&df),
    })
}

/// The posterior covariances of [`posterior`] with `α` integrated out
/// under the evidence: `ln α ~ N(ln α̂, σ²)` ([`AlphaSpread`]), the
/// covariances averaged by the three-point Gauss–Hermite rule (`ln α̂`,
/// `ln α̂ ± √3 σ`, weights 2/3, 1/6, 1/6) and the spread of the estimate
/// itself added, `σ² g gᵀ` with `g = d(C F̂)/d ln α` (or `d(J F̂)/d ln α`).
/// That is the mean squared error about the reported estimate `F̂(α̂)`.
/// `markers` as in [`posterior`] (the parts are averaged entry by entry).
#[allow(clippy::too_many_arguments)]
pub(crate) fn posterior_alpha_marginal(
    form: &GnForm,
    nd: usize,
    fw: &[f64],
    dv: &Derivs,
    w: &[f64],
    alpha: f64,
    f: &[f64],
    pen: f64,
    gn: Option<&GnFactor>,
    markers: MarkerPart,
) -> Option<(Vec<f64>, Vec<f64>)> {
    let sp = alpha_spread(form, fw, dv, w, alpha, f, pen, gn)?;
    let h = 3f64.sqrt() * sp.sigma_ln;
    let d = sp.force.len();
    let m = sp.marker.len();
    let mut r = vec![0.0; d * d];
    let mut mk = vec![0.0; markers.len(m)];
    for (a, wt) in [
        (alpha, 2.0 / 3.0),
        (alpha * h.exp(), 1.0 / 6.0),
        (alpha * (-h).exp(), 1.0 / 6.0),
    ] {
        let (ri, mi) = posterior(form, nd, fw, dv, w, a, gn, markers)?;
        if ri.len() != r.len() || mi.len() != mk.len() {
            return None;
        }
        r.iter_mut().zip(&ri).for_each(|(x, y)| *x += wt * y);
        mk.iter_mut().zip(&mi).for_each(|(x, y)| *x += wt * y);
    }
    let s2 = sp.sigma_ln * sp.sigma_ln;
    for i in 0..d {
        for j in 0..d {
            r[i * d + j] += sp.force[i] * sp.force[j] * s2;
        }
    }
    match markers {
        MarkerPart::None => {}
        MarkerPart::Diagonal => {
            for (v, g) in mk.iter_mut().zip(sp.marker.iter()) {
                *v += g * g * s2;
            }
        }
        MarkerPart::Full => {
            for i in 0..m {
                for j in 0..m {
                    mk[i * m + j] += sp.marker[i] * sp.marker[j] * s2;
                }
            }
        }
    }
    Some((r, mk))
}

/// `Cov(resultant force)` (`DIM × DIM`) and `Cov(A q)` (`n_ob × n_ob`) of
/// the noise alone, from the covariance factor `L` (`n_F × n_ob`), the map
/// `C: F → ∫ w dX` (row-major `DIM × n_F`) and the marker Jacobian:
/// `(C L)(C L)ᵀ` (row-major) and the `markers` part of `(J L)(J L)ᵀ` (its
/// diagonal: the rows of `J L` squared, one row at a time).
fn noise_cov(
    l: &DMatrix<f64>,
    fw: &[f64],
    dv: &Derivs,
    markers: MarkerPart,
) -> (Vec<f64>, Vec<f64>) {
    let nf = dv.jt.nrows();
    let d = fw.len().checked_div(nf).unwrap_or(0);
    let cl = DMatrix::from_row_slice(d, nf, fw) * l;
    let r = row_major(&(&cl * cl.transpose()));
    let mk = match markers {
        MarkerPart::None => Vec::new(),
        // J L = Jtᵀ L
        MarkerPart::Full => {
            let jl = dv.jt.tr_mul(l);
            row_major(&(&jl * jl.transpose()))
        }
        MarkerPart::Diagonal => dv
            .jt
            .column_iter()
            .map(|j| (l.transpose() * j).norm_squared())
            .collect(),
    };
    (r, mk)
}

/// The entries of `a` row by row.
fn row_major(a: &DMatrix<f64>) -> Vec<f64> {
    a.transpose().as_slice().to_vec()
}

impl Estimate {
    /// `Cov(F) = L Lᵀ` (`n_F × n_F`) for the stated marker noise:
    /// the covariance of the Gauss–Newton-linearized estimator,
    /// `F̂ ≈ (JᵀWJ + αH)⁻¹ JᵀW y`, with `J` the marker Jacobian `∂(Aq)/∂F`
    /// and `Cov(y) = σ² I`.
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{EstimatorSettings, LoadModel, Observation};
    /// use softrod::{scene::Scene, statics::StaticSolver};
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[10, 20])?;
    /// let settings = EstimatorSettings {
    ///     load_model: LoadModel::Concentrated { node: 20 }, alpha: Some(1.0), ..Default::default()
    /// };
    /// let e = settings.build_for(&robot, &loads)?.step(&obs)?;
    /// let c: nalgebra::DMatrix<f64> = e.covariance_f();
    /// assert_eq!(c.shape(), (2, 2));
    /// assert!((c[(0, 0)].sqrt() - e.std_f()[0]).abs() <= 1e-12 * c[(0, 0)].sqrt());
    /// assert!((c[(0, 1)] - c[(1, 0)]).abs() <= 1e-14 * c.norm());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn covariance_f(&self) -> DMatrix<f64> {
        let l = self.cov_factor();
        l * l.transpose()
    }

    /// Standard deviations of the entries of `F` (square roots of the
    /// diagonal of [`Estimate::covariance_f`]).
    ///
    /// # Example
    /// See [`Estimate::covariance_f`].
    pub fn std_f(&self) -> DVector<f64> {
        let l = self.cov_factor();
        DVector::from_iterator(l.nrows(), l.row_iter().map(|r| r.norm()))
    }

    /// Posterior covariance of the resultant force (N², `DIM × DIM`): the
    /// spread of the stated marker noise plus the bias of the penalty, with
    /// the penalty read as a Gaussian prior (see [`super::AlphaRule`]); when
    /// `α` is the evidence's, averaged over `α`'s own uncertainty. Taken at
    /// the last linearization (see [`super::EstimateReport::gradient_norm`];
    /// after an unconfirmed last step the two points differ by that step,
    /// whose predicted decrease is below `1e-3 tolerance`: the covariances
    /// then differ by about the square root of that, relatively).
    ///
    /// Formed on the first call of this, [`Estimate::marker_cov`],
    /// [`Estimate::cov_factor`], [`Estimate::covariance_f`] or
    /// [`Estimate::std_f`] from the derivatives the estimate keeps, and
    /// kept: an estimator does not form covariances nobody reads (a
    /// stream of warm steps spends about a tenth of its time on them).
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{EstimatorSettings, Observation};
    /// use softrod::{scene::Scene, statics::StaticSolver};
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[10, 20])?.with_noise(1e-5, 1);
    /// let settings = EstimatorSettings { alpha: Some(1.0), ..Default::default() };
    /// let e = settings.build_for(&robot, &loads)?.step(&obs)?;
    /// let c: &nalgebra::DMatrix<f64> = e.resultant_force_cov();
    /// assert_eq!(c.shape(), (2, 2));
    /// assert!(c[(0, 0)] > 0.0 && c[(1, 1)] > 0.0);
    /// assert_eq!(c[(0, 1)], c[(1, 0)]);
    /// let m: &nalgebra::DMatrix<f64> = e.marker_cov();
    /// assert_eq!(m.shape(), (4, 4)); // two markers, two components each
    /// assert_eq!(e.cov_factor().shape(), (robot.n_q(), 4));
    /// // the marker noise (0.01 mm) bounds the posterior spread of the shape
    /// assert!(m[(3, 3)].sqrt() < 1e-5);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn resultant_force_cov(&self) -> &DMatrix<f64> {
        self.cov.resultant()
    }

    /// Posterior covariance of the estimated marker-space shape `A q`
    /// (`n_ob × n_ob`; m², tangents dimensionless), in observation order;
    /// formed on request like [`Estimate::resultant_force_cov`] (its work
    /// and size grow as `n_ob²`: the resultant's covariance alone does not
    /// form it).
    ///
    /// # Example
    /// See [`Estimate::resultant_force_cov`].
    pub fn marker_cov(&self) -> &DMatrix<f64> {
        &self.cov.posterior().1
    }

    /// Posterior standard deviations of the estimated marker-space shape
    /// `A q` (`n_ob`; m, tangents dimensionless), in observation order: the
    /// square roots of the diagonal of [`Estimate::marker_cov`], formed
    /// without it (`n_ob` numbers; in the primal form, the one of many
    /// markers, work linear in `n_ob`).
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{EstimatorSettings, Observation};
    /// use softrod::{scene::Scene, statics::StaticSolver};
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[10, 20])?.with_noise(1e-5, 1);
    /// let settings = EstimatorSettings { alpha: Some(1.0), ..Default::default() };
    /// let e = settings.build_for(&robot, &loads)?.step(&obs)?;
    /// let s = e.marker_std();
    /// assert_eq!(s.len(), 4);
    /// assert!((s[3] - e.marker_cov()[(3, 3)].sqrt()).abs() < 1e-12 * s[3]);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn marker_std(&self) -> DVector<f64> {
        let v = self.cov.marker_variances();
        DVector::from_iterator(v.len(), v.iter().map(|x| x.max(0.0).sqrt()))
    }

    /// Covariance factor `L` (`n_F × n_ob`) of the noise alone (no bias):
    /// `Cov(F̂) = L Lᵀ` ([`Estimate::covariance_f`]) for the linearized
    /// estimator `F̂ ≈ (JᵀWJ + αH)⁻¹ JᵀW y`, `L = σ (JᵀWJ + αH)⁻¹ JᵀW`;
    /// taken at the last linearization and formed on request like
    /// [`Estimate::resultant_force_cov`].
    ///
    /// # Example
    /// See [`Estimate::resultant_force_cov`].
    pub fn cov_factor(&self) -> &DMatrix<f64> {
        self.cov.factor()
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use crate::estimate::LoadModel;

    /// The primal form with the penalty matrix `h`.
    fn primal(h: DMatrix<f64>) -> GnForm {
        GnForm::Primal(std::sync::Arc::new(PenaltyMatrix::new(h).unwrap()))
    }

    fn lcg(seed: u64, n: usize) -> Vec<f64> {
        let mut s = seed;
        (0..n)
            .map(|_| {
                s = s
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                2.0 * ((s >> 11) as f64 / (1u64 << 53) as f64) - 1.0
            })
            .collect()
    }

    /// A random layout of 5 nodes × `nd` coordinates seen by `m` observed
    /// components, from the seeds `seed … seed + 4`: `B` symmetric positive
    /// definite, `Z`, weights in `[1, 3]`, a map `C` (row-major `2 × n_F`)
    /// and a load `F`.
    struct Layout {
        b: DMatrix<f64>,
        z: DMatrix<f64>,
        w: Vec<f64>,
        fw: Vec<f64>,
        f: Vec<f64>,
    }

    fn layout(nd: usize, m: usize, seed: u64) -> Layout {
        let nf = nd * 5;
        let r = DMatrix::from_vec(nf, nf, lcg(seed, nf * nf));
        Layout {
            b: &r * r.transpose() + DMatrix::identity(nf, nf),
            z: DMatrix::from_vec(nf, m, lcg(seed + 1, nf * m)),
            w: lcg(seed + 2, m).iter().map(|v| 2.0 + v).collect(),
            fw: lcg(seed + 3, 2 * nf),
            f: lcg(seed + 4, nf),
        }
    }

    /// The map `C = E_dᵀ B` to the resultant of the distributed load
    /// (`E_d` the coordinates of a constant unit field: 1 at the position
    /// slot of each component, `nd` coordinates per node), as a matrix and
    /// row-major.
    fn resultant_map(b: &DMatrix<f64>, nd: usize, d: usize) -> (DMatrix<f64>, Vec<f64>) {
        let nf = b.nrows();
        let mut e = DMatrix::zeros(nf, d);
        for n in 0..nf / nd {
            for a in 0..d {
                e[(n * nd + a, a)] = 1.0;
            }
        }
        let c = e.transpose() * b;
        let fw = c.transpose().as_slice().to_vec();
        (c, fw)
    }

    /// The representer forms of the posterior covariances equal the dense
    /// `(JᵀWJ + αH)⁻¹` mapped by `C` and `J`: a planar layout of 5 nodes ×
    /// 4 coordinates, `B` symmetric positive definite, `C = E_dᵀ B`, for
    /// both load models and both forms of the distributed load's system.
    /// Bound 1e-9 relative (a missing `1/α` or a transposed factor is off
    /// by O(1)).
    #[test]
    fn posterior_matches_the_dense_inverse() {
        let (nd, d, nodes, m) = (4, 2, 5, 3);
        let nf = nd * nodes;
        let r = DMatrix::from_vec(nf, nf, lcg(1, nf * nf));
        let b = &r * r.transpose() + DMatrix::identity(nf, nf);
        let z = DMatrix::from_vec(nf, m, lcg(2, nf * m));
        let w: Vec<f64> = lcg(3, m).iter().map(|v| 2.0 + v).collect();
        let wm = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&w));
        let alpha = 0.7;
        let close = |a: &[f64], b: &DMatrix<f64>| {
            let bt = b.transpose();
            let scale = b.iter().fold(0.0f64, |x, v| x.max(v.abs()));
            a.iter()
                .zip(bt.iter())
                .all(|(x, y)| (x - y).abs() <= 1e-9 * scale)
        };
        // distributed: H = B, J = Zᵀ B, C = E_dᵀ B
        let jt = &b * &z;
        let (c, fw) = resultant_map(&b, nd, d);
        let dv = Derivs {
            z: z.clone(),
            jt: jt.clone(),
        };
        let post = (&jt * &wm * jt.transpose() + &b * alpha)
            .try_inverse()
            .unwrap();
        for form in [GnForm::Representer, primal(b.clone())] {
            let (rc, mc) =
                posterior(&form, nd, &fw, &dv, &w, alpha, None, MarkerPart::Full).unwrap();
            assert!(close(&rc, &(&c * &post * c.transpose())), "{form:?}");
            assert!(close(&mc, &(jt.transpose() * &post * &jt)), "{form:?}");
        }
        // concentrated: H = I, C = I
        let jt = DMatrix::from_vec(d, m, lcg(4, d * m));
        let dv = Derivs {
            z: DMatrix::zeros(nf, m),
            jt: jt.clone(),
        };
        let fw = vec![1.0, 0.0, 0.0, 1.0];
        let eye = primal(DMatrix::identity(d, d));
        let (rc, mc) = posterior(&eye, nd, &fw, &dv, &w, alpha, None, MarkerPart::Full).unwrap();
        let post = (&jt * &wm * jt.transpose() + DMatrix::identity(d, d) * alpha)
            .try_inverse()
            .unwrap();
        assert!(close(&rc, &post));
        assert!(close(&mc, &(jt.transpose() * &post * &jt)));
    }

    /// The diagonal part of `Cov(A q)` (formed without the matrix) is the
    /// full matrix's diagonal, in both forms, averaged over `α`, and in the
    /// noise-only fallback; the resultant's part is the same numbers.
    /// Bound 1e-12 relative (a missing weight or a transposed factor is
    /// off by O(1)).
    #[test]
    fn the_marker_diagonal_is_the_full_covariances_diagonal() {
        let (nd, m) = (4, 7);
        let Layout { b, z, w, fw, f } = layout(nd, m, 21);
        let nf = b.nrows();
        let alpha = 0.7;
        let dv = Derivs {
            jt: &b * &z,
            z: z.clone(),
        };
        let diag_of = |full: &[f64]| (0..m).map(|i| full[i * m + i]).collect::<Vec<_>>();
        let close = |a: &[f64], b: &[f64]| {
            let scale = b.iter().fold(0.0f64, |x, v| x.max(v.abs()));
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-12 * scale)
        };
        for form in [GnForm::Representer, primal(b.clone())] {
            let (r_full, full) =
                posterior(&form, nd, &fw, &dv, &w, alpha, None, MarkerPart::Full).unwrap();
            let (r_diag, diag) =
                posterior(&form, nd, &fw, &dv, &w, alpha, None, MarkerPart::Diagonal).unwrap();
            assert!(close(&diag, &diag_of(&full)), "{form:?}");
            assert!(close(&r_diag, &r_full), "{form:?}");
            let (_, full) = posterior_alpha_marginal(
                &form,
                nd,
                &fw,
                &dv,
                &w,
                alpha,
                &f,
                0.3,
                None,
                MarkerPart::Full,
            )
            .unwrap();
            let (_, diag) = posterior_alpha_marginal(
                &form,
                nd,
                &fw,
                &dv,
                &w,
                alpha,
                &f,
                0.3,
                None,
                MarkerPart::Diagonal,
            )
            .unwrap();
            assert!(close(&diag, &diag_of(&full)), "α-averaged {form:?}");
        }
        let l = DMatrix::from_vec(nf, m, lcg(26, nf * m));
        let (r_full, full) = noise_cov(&l, &fw, &dv, MarkerPart::Full);
        let (r_diag, diag) = noise_cov(&l, &fw, &dv, MarkerPart::Diagonal);
        assert!(close(&diag, &diag_of(&full)) && close(&r_diag, &r_full));
        assert!(noise_cov(&l, &fw, &dv, MarkerPart::None).1.is_empty());
    }

    /// The posterior covariances from the Gauss–Newton system's factor at
    /// hand ([`GnFactor`]) equal those formed anew, for both load models,
    /// with and without the average over `α`; a factor formed at another
    /// `α` is not used. Bound 1e-12 relative (a factor of the wrong system
    /// is off by O(1)).
    #[test]
    fn posterior_from_the_factor_at_hand_equals_the_one_formed_anew() {
        let (nd, m) = (4, 3);
        let Layout { b, z, w, fw, f } = layout(nd, m, 11);
        let nf = b.nrows();
        let alpha = 0.7;
        let close = |a: &[f64], b: &[f64]| {
            let scale = b.iter().fold(0.0f64, |x, v| x.max(v.abs()));
            a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-12 * scale)
        };
        // distributed: S = Zᵀ B Z + α W⁻¹, as gn_solve forms it
        let dv = Derivs {
            jt: &b * &z,
            z: z.clone(),
        };
        let k = z.transpose() * &b * &z;
        let k = (&k + k.transpose()) * 0.5;
        let fac = |k: &DMatrix<f64>, a: f64| {
            let mut s = k.clone();
            for i in 0..m {
                s[(i, i)] += a / w[i];
            }
            GnFactor {
                chol: jittered_cholesky(s).unwrap(),
                gram: Some(k.clone()),
                alpha: a,
            }
        };
        let load = &GnForm::Representer;
        let gn = fac(&k, alpha);
        let fresh = posterior(load, nd, &fw, &dv, &w, alpha, None, MarkerPart::Full).unwrap();
        let reused = posterior(load, nd, &fw, &dv, &w, alpha, Some(&gn), MarkerPart::Full).unwrap();
        assert!(close(&reused.0, &fresh.0) && close(&reused.1, &fresh.1));
        let fresh = posterior_alpha_marginal(
            load,
            nd,
            &fw,
            &dv,
            &w,
            alpha,
            &f,
            0.3,
            None,
            MarkerPart::Full,
        )
        .unwrap();
        let reused = posterior_alpha_marginal(
            load,
            nd,
            &fw,
            &dv,
            &w,
            alpha,
            &f,
            0.3,
            Some(&gn),
            MarkerPart::Full,
        )
        .unwrap();
        assert!(close(&reused.0, &fresh.0) && close(&reused.1, &fresh.1));
        // a factor at another α is not used: a wrong gram there would show
        let wrong = fac(&(&k * 2.0), 2.0 * alpha);
        let other = posterior(
            load,
            nd,
            &fw,
            &dv,
            &w,
            alpha,
            Some(&wrong),
            MarkerPart::Full,
        )
        .unwrap();
        let fresh = posterior(load, nd, &fw, &dv, &w, alpha, None, MarkerPart::Full).unwrap();
        assert!(close(&other.0, &fresh.0) && close(&other.1, &fresh.1));
        // and a wrong factor at this α would: the test can fail
        let wrong = fac(&(&k * 2.0), alpha);
        let bad = posterior(
            load,
            nd,
            &fw,
            &dv,
            &w,
            alpha,
            Some(&wrong),
            MarkerPart::Full,
        )
        .unwrap();
        assert!(!close(&bad.1, &fresh.1));
        // concentrated: N = Jᵀ W J + α I
        let jt = DMatrix::from_vec(2, m, lcg(16, 2 * m));
        let dv = Derivs {
            z: DMatrix::zeros(nf, m),
            jt: jt.clone(),
        };
        let mut n = weighted_columns(&jt, &w) * jt.transpose();
        for i in 0..2 {
            n[(i, i)] += alpha;
        }
        let gn = GnFactor {
            chol: jittered_cholesky(n).unwrap(),
            gram: None,
            alpha,
        };
        let load = &primal(DMatrix::identity(2, 2));
        let fw = vec![1.0, 0.0, 0.0, 1.0];
        let fresh = posterior(load, nd, &fw, &dv, &w, alpha, None, MarkerPart::Full).unwrap();
        let reused = posterior(load, nd, &fw, &dv, &w, alpha, Some(&gn), MarkerPart::Full).unwrap();
        assert!(close(&reused.0, &fresh.0) && close(&reused.1, &fresh.1));
    }

    /// A linear problem with the minimizer `F̂(α)` in closed form: `B`
    /// (`nf × nf`, SPD), `Z`, `J = Zᵀ B` (distributed) or `J = Zᵀ`
    /// (concentrated), weights `w`, data `y`, a resultant map `C`.
    struct Lin {
        b: DMatrix<f64>,
        z: DMatrix<f64>,
        w: Vec<f64>,
        y: nalgebra::DVector<f64>,
        c: DMatrix<f64>,
    }

    impl Lin {
        fn new(nf: usize, m: usize, seed: u64) -> Lin {
            let r = DMatrix::from_vec(nf, nf, lcg(seed, nf * nf));
            Lin {
                b: &r * r.transpose() + DMatrix::identity(nf, nf) * 0.5,
                z: DMatrix::from_vec(nf, m, lcg(seed + 1, nf * m)),
                w: lcg(seed + 2, m).iter().map(|v| 2.0 + v).collect(),
                y: nalgebra::DVector::from_vec(lcg(seed + 3, m)) * 3.0,
                c: DMatrix::from_vec(2, nf, lcg(seed + 4, 2 * nf)),
            }
        }
        fn jt(&self, load: LoadModel) -> DMatrix<f64> {
            match load {
                LoadModel::Distributed => &self.b * &self.z,
                LoadModel::Concentrated { .. }
                | LoadModel::AtSite { .. }
                | LoadModel::Along { .. } => self.z.clone(),
            }
        }
        fn h(&self, load: LoadModel) -> DMatrix<f64> {
            match load {
                LoadModel::Distributed => self.b.clone(),
                LoadModel::Concentrated { .. }
                | LoadModel::AtSite { .. }
                | LoadModel::Along { .. } => DMatrix::identity(self.b.nrows(), self.b.nrows()),
            }
        }
        /// `F̂(α)` and `−2 log p(y | α)` (up to a constant), densely.
        fn at(&self, load: LoadModel, alpha: f64) -> (nalgebra::DVector<f64>, f64) {
            let jt = self.jt(load);
            let wm = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&self.w));
            let n = &jt * &wm * jt.transpose() + self.h(load) * alpha;
            let f = n.cholesky().unwrap().solve(&(&jt * &wm * &self.y));
            let winv = wm.try_inverse().unwrap();
            let cy = winv + jt.transpose() * self.h(load).try_inverse().unwrap() * &jt / alpha;
            let chol = cy.cholesky().unwrap();
            let ld = 2.0 * chol.l().diagonal().iter().map(|v| v.ln()).sum::<f64>();
            (f, (self.y.transpose() * chol.solve(&self.y))[(0, 0)] + ld)
        }
        fn k(&self, load: LoadModel) -> DMatrix<f64> {
            let jt = self.jt(load);
            jt.transpose() * self.h(load).try_inverse().unwrap() * jt
        }
    }

    /// A load model and whether its system is solved in the primal form.
    type Case = (LoadModel, bool);

    /// The distributed load in both forms, the concentrated one (primal).
    const MODELS: [Case; 3] = [
        (LoadModel::Distributed, false),
        (LoadModel::Distributed, true),
        (LoadModel::Concentrated { node: 1 }, true),
    ];

    impl Lin {
        fn form(&self, (load, is_primal): Case) -> GnForm {
            if is_primal {
                primal(self.h(load))
            } else {
                GnForm::Representer
            }
        }
        /// The evidence's curvature in the form of `case`.
        fn curvature(&self, case: Case, alpha: f64, u: &DVector<f64>, pen: f64) -> f64 {
            let load = case.0;
            match self.form(case) {
                GnForm::Representer => {
                    evidence_curvature(&self.k(load), &self.w, alpha, u, pen).unwrap()
                }
                GnForm::Primal(h) => {
                    let dv = Derivs {
                        z: self.z.clone(),
                        jt: self.jt(load),
                    };
                    let chol = primal_system(&dv.jt, &self.w, alpha, &h).unwrap();
                    evidence_curvature_primal(&dv, &self.w, alpha, &chol, &h, u, pen)
                }
            }
        }
    }

    /// The evidence's curvature in `ln α` equals central second differences
    /// of the evidence written out (each side re-minimized), for both load
    /// models (the distributed one in both forms), with fewer and with more
    /// observed components than parameters, over five decades. Bound 1e-5 relative to `max(|curv|, 1)`
    /// (a missing term, `2 uᵀPu` or `tr T²`, is off by O(1)).
    #[test]
    fn evidence_curvature_matches_finite_differences() {
        // with more components than parameters the written-out evidence
        // (`W⁻¹ + K/α`, `K` of rank `n_F`) loses digits as `α → 0`: its
        // second differences disagree between steps 1e-3 and 1e-4 at
        // `α = 1e-3`; there the two forms are compared with each other
        for (case, p, alphas) in MODELS.into_iter().flat_map(|c| {
            [
                (c, Lin::new(6, 4, 21), &[1e-3, 1e-2, 0.3, 5.0, 80.0][..]),
                (c, Lin::new(3, 7, 22), &[0.3, 5.0, 80.0][..]),
            ]
        }) {
            let load = case.0;
            for &alpha in alphas {
                let (f, _) = p.at(load, alpha);
                let u = p.jt(load).tr_mul(&f);
                let pen = (f.transpose() * p.h(load) * &f)[(0, 0)];
                let curv = p.curvature(case, alpha, &u, pen);
                let h: f64 = 1e-3;
                let up = p.at(load, alpha * h.exp()).1;
                let mid = p.at(load, alpha).1;
                let dn = p.at(load, alpha * (-h).exp()).1;
                let fd = (up - 2.0 * mid + dn) / (h * h);
                assert!(
                    (curv - fd).abs() <= 1e-5 * curv.abs().max(1.0),
                    "{case:?} alpha {alpha}: {curv} vs fd {fd}"
                );
            }
        }
        let p = Lin::new(3, 7, 22);
        let load = LoadModel::Distributed;
        for alpha in [1e-3, 1e-2, 0.3] {
            let (f, _) = p.at(load, alpha);
            let u = p.jt(load).tr_mul(&f);
            let pen = (f.transpose() * p.h(load) * &f)[(0, 0)];
            let rep = p.curvature((load, false), alpha, &u, pen);
            let pri = p.curvature((load, true), alpha, &u, pen);
            assert!(
                (rep - pri).abs() <= 1e-8 * rep.abs().max(1.0),
                "{alpha}: {rep} vs {pri}"
            );
        }
    }

    /// `d(C F̂)/d ln α` and `d(J F̂)/d ln α` of [`alpha_spread`] equal
    /// central differences of the re-minimized `F̂`, for both load models
    /// (the distributed one in both forms).
    /// Bound 1e-6 relative to the largest entry (a sign or a missing `α` is
    /// off by O(1)).
    #[test]
    fn estimate_slope_in_alpha_matches_finite_differences() {
        for case in MODELS {
            let load = case.0;
            let p = Lin::new(6, 4, 33);
            let fw: Vec<f64> = p.c.transpose().as_slice().to_vec();
            for alpha in [1e-2, 0.3, 5.0] {
                let (f, _) = p.at(load, alpha);
                let jt = p.jt(load);
                let dv = Derivs {
                    z: p.z.clone(),
                    jt: jt.clone(),
                };
                let pen = (f.transpose() * p.h(load) * &f)[(0, 0)];
                let form = p.form(case);
                let sp =
                    alpha_spread(&form, &fw, &dv, &p.w, alpha, f.as_slice(), pen, None).unwrap();
                let h: f64 = 1e-5;
                let df =
                    (p.at(load, alpha * h.exp()).0 - p.at(load, alpha * (-h).exp()).0) / (2.0 * h);
                let fd_force = &p.c * &df;
                let fd_marker = jt.tr_mul(&df);
                let scale = fd_force.amax().max(fd_marker.amax());
                assert!(
                    (&sp.force - &fd_force).amax() <= 1e-6 * scale,
                    "{case:?} {alpha}: {} vs {}",
                    sp.force,
                    fd_force
                );
                assert!(
                    (&sp.marker - &fd_marker).amax() <= 1e-6 * scale,
                    "{case:?} {alpha}"
                );
                assert!(sp.sigma_ln > 0.0 && sp.sigma_ln <= SIGMA_LN_ALPHA_MAX);
            }
        }
    }

    /// The prior covariance of the resultant equals the dense `C (αH)⁻¹
    /// Cᵀ` in both forms of the distributed load's system (`H = B`, `C =
    /// E_dᵀ B`) and for the concentrated force (`H = I`, `C = I`); the
    /// posterior at the same `α` is below it in every direction, and the
    /// largest ratio of the two with its direction equals the closed form
    /// of the 2 × 2 generalized eigenproblem `det(Σ − λ P) = 0`. Bound
    /// 1e-9 relative (a missing `1/α` is off by O(1)).
    #[test]
    fn prior_of_the_resultant_and_its_largest_ratio_match_the_dense_forms() {
        let (nd, d, nodes, m) = (4, 2, 5, 3);
        let nf = nd * nodes;
        let Layout { b, z, w, .. } = layout(nd, m, 31);
        let (c, fw) = resultant_map(&b, nd, d);
        let alpha = 0.7;
        let want = &c * b.clone().try_inverse().unwrap() * c.transpose() / alpha;
        let dv = Derivs {
            jt: &b * &z,
            z: z.clone(),
        };
        for form in [GnForm::Representer, primal(b.clone())] {
            let p =
                DMatrix::from_row_slice(d, d, &prior_resultant(&form, nd, &fw, nf, alpha).unwrap());
            assert!(
                (&p - &want).norm() <= 1e-9 * want.norm(),
                "{form:?}: {p} {want}"
            );
            let (post, _) =
                posterior(&form, nd, &fw, &dv, &w, alpha, None, MarkerPart::None).unwrap();
            let post = DMatrix::from_row_slice(d, d, &post);
            let (lam, u) = largest_relative_variance(p.clone(), &post).unwrap();
            // det(Σ − λ P) = 0: a λ² − b λ + c = 0
            let qa = p.determinant();
            let qb = post[(0, 0)] * p[(1, 1)] + post[(1, 1)] * p[(0, 0)]
                - 2.0 * post[(0, 1)] * p[(0, 1)];
            let qc = post.determinant();
            let top = (qb + (qb * qb - 4.0 * qa * qc).sqrt()) / (2.0 * qa);
            assert!(
                (lam - top).abs() <= 1e-9 * top && lam > 0.0 && lam < 1.0,
                "{lam} {top}"
            );
            // u is that direction: (Σ − λ P) u = 0, |u| = 1
            assert!(
                (&post * &u - &p * &u * lam).norm() <= 1e-9 * post.norm()
                    && (u.norm() - 1.0).abs() < 1e-12
            );
        }
        // concentrated: P = I / α
        let eye = primal(DMatrix::identity(d, d));
        let p = prior_resultant(&eye, nd, &[1.0, 0.0, 0.0, 1.0], d, alpha).unwrap();
        assert!(
            p.iter()
                .zip([1.0 / alpha, 0.0, 0.0, 1.0 / alpha])
                .all(|(x, y)| (x - y).abs() < 1e-15)
        );
    }
}
