//! `α` by the evidence (beyond the paper): the regularization weight that
//! maximizes the marginal likelihood of the observation.
//!
//! # The model behind the penalty
//!
//! The objective (25) with whitened weights is `−2 log` of a posterior:
//! the markers `y = A q(F) + n` with Gaussian noise `n ~ N(0, W⁻¹)` and the
//! penalty (26) as a Gaussian prior `F ~ N(0, (α H)⁻¹)` (for the
//! distributed field a prior on `w(X)` with `E ∫ wᵀw dX = n_F / α`). `α` is
//! then the prior's precision, and the observation itself says how large it
//! is: the evidence `p(y | α) = ∫ p(y | F) p(F | α) dF`, linearized at the
//! estimate `F̂` (Laplace; `J = ∂(Aq)/∂F` there), is
//!
//! ```text
//! −2 log p(y | α) = Φ(α) + log det S − m log α + m log 2π        (distributed)
//! −2 log p(y | α) = Φ(α) + log det N − d log α − log det W + m log 2π   (concentrated)
//! ```
//!
//! with `Φ` the minimal objective, `m = n_ob`, `S = α W⁻¹ + Zᵀ B Z` the
//! Gauss–Newton system of the representer form, `N = JᵀWJ + α I`, `d = n_F`.
//! The distributed load observed by more components than it has parameters
//! (the primal form, [`super::gn_form`]) takes the second line with
//! `N = JᵀWJ + α B` and `− log det B` added: by Sylvester's determinant
//! identity `det(I_m + W J B⁻¹ Jᵀ/α) = det(I_n + B⁻¹ JᵀWJ/α)`, so
//! `log det S − m log α = log det N − d log α − log det B − log det W`,
//! and `γ = d − α tr(N⁻¹ B)`. No `m × m` matrix then.
//! Its derivative in `log α` at a fixed linearization (the minimizer `F̂`
//! moves with `α`, but `Φ` is stationary in `F`) is
//!
//! ```text
//! d(−2 log p)/d log α = α F̂ᵀ H F̂ − γ,
//! γ = m − α tr(S⁻¹ W⁻¹)   or   γ = d − α tr(N⁻¹),
//! ```
//!
//! `γ` being the number of load directions the markers determine (MacKay's
//! effective number of parameters). The evidence is largest where the
//! penalty of the estimate equals `γ`: [`evidence_alpha`] finds that root by
//! the discrepancy search's bracketing and bisection in `log α`.
//!
//! Under this model the reported covariances are the posterior's
//! (`(JᵀWJ + αH)⁻¹`, see `covariance`): they hold the spread the noise
//! causes and the bias the penalty puts in, as far as the prior describes
//! the load. The evidence is also a likelihood of `ln α`: its width,
//! `σ² = 2 / (d²(−2 log p)/d(ln α)²)`, is how well the observation knows
//! `α`, and the reported covariances average the posterior over it and add
//! how far the estimate moves with `α` (`covariance::posterior_alpha_marginal`).
//! Without that the intervals were too narrow where the markers barely see
//! the load (a large `α`): 89 % of smooth loads covered instead of 92.5 %.

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::observe::ObservationOperator;

use super::driver::{ALPHA_CONTINUATION_START, Method, Warm};
use super::gn_form::{GnForm, count_dense, jittered_cholesky, primal_system};
use super::problem::{Derivs, Problem, columns};

/// How `α` is chosen when the settings leave it unset.
///
/// # Example
/// ```
/// let r: softrod::estimate::AlphaRule = serde_json::from_str("\"discrepancy\"").unwrap();
/// assert_eq!(r, softrod::estimate::AlphaRule::Discrepancy);
/// assert_eq!(softrod::estimate::AlphaRule::default(), softrod::estimate::AlphaRule::Evidence);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum AlphaRule {
    /// The largest marginal likelihood of the observation (default): the
    /// posterior standard deviations then cover the truth at about their
    /// nominal rate (see the crate's README, "Uncertainty").
    #[default]
    Evidence,
    /// Morozov's discrepancy principle: the weighted residual equals the
    /// number of observed components.
    Discrepancy,
}

impl AlphaRule {
    /// The rule as the settings spell it (`alpha_rule`).
    ///
    /// # Example
    /// ```
    /// assert_eq!(softrod::estimate::AlphaRule::Evidence.name(), "evidence");
    /// assert_eq!(softrod::estimate::AlphaRule::Discrepancy.name(), "discrepancy");
    /// // the spelling of the settings' JSON
    /// assert_eq!(serde_json::to_string(&softrod::estimate::AlphaRule::Discrepancy).unwrap(), "\"discrepancy\"");
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            AlphaRule::Evidence => "evidence",
            AlphaRule::Discrepancy => "discrepancy",
        }
    }
}

/// The evidence of an estimate and its derivative in `log α`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Evidence {
    /// `−2 log p(y | α)` (dimensionless).
    pub minus_two_log: f64,
    /// `d(−2 log p(y | α)) / d log α` at the fixed linearization.
    pub slope: f64,
    /// The effective number of determined parameters `γ`.
    pub gamma: f64,
}

/// The evidence at an estimate: derivatives `dv` (marker Jacobian `Jᵀ` and
/// adjoint fields `Z`), weights `w`, the objective `phi`, the penalty
/// `pen = Fᵀ H F`, at `alpha`, in the Gauss–Newton system's form `form`.
/// `None` if the Gauss–Newton matrix is not positive definite.
pub(crate) fn evidence(
    form: &GnForm,
    dv: &Derivs,
    w: &[f64],
    phi: f64,
    pen: f64,
    alpha: f64,
) -> Option<Evidence> {
    let m = w.len();
    let ln2pi = (2.0 * std::f64::consts::PI).ln();
    let (logdet, trace, count, extra) = match form {
        GnForm::Representer => {
            // S = Zᵀ B Z + α W⁻¹ (B z_j = J_j)
            count_dense(m * m * dv.jt.nrows() + m * m * m);
            let mut s = dv.z.tr_mul(&dv.jt);
            s = (&s + s.transpose()) * 0.5;
            for i in 0..m {
                s[(i, i)] += alpha / w[i];
            }
            let chol = jittered_cholesky(s)?;
            let inv = chol.inverse();
            let tr: f64 = (0..m).map(|i| inv[(i, i)] / w[i]).sum();
            (log_det(&chol), tr, m as f64, 0.0)
        }
        GnForm::Primal(h) => {
            // N = Jᵀ W J + α H, tr(N⁻¹ H)
            let d = dv.jt.nrows();
            let chol = primal_system(&dv.jt, w, alpha, h)?;
            let inv = chol.inverse();
            count_dense(d * d * d);
            let tr: f64 = inv.iter().zip(h.h.iter()).map(|(a, b)| a * b).sum();
            let logdet_w: f64 = w.iter().map(|v| v.ln()).sum();
            (log_det(&chol), tr, d as f64, -logdet_w - h.log_det)
        }
    };
    let gamma = count - alpha * trace;
    Some(Evidence {
        minus_two_log: phi + logdet - count * alpha.ln() + extra + m as f64 * ln2pi,
        slope: alpha * pen - gamma,
        gamma,
    })
}

/// `log det A` from its Cholesky factor.
fn log_det(c: &nalgebra::Cholesky<f64, nalgebra::Dyn>) -> f64 {
    2.0 * c.l_dirty().diagonal().iter().map(|v| v.ln()).sum::<f64>()
}

/// Whether the markers see the load at all: some entry of the marker
/// Jacobian is not zero. Markers only at the clamped base (positions or
/// tangents) give a zero Jacobian: the estimate is then the prior's.
pub(crate) fn informative(dv: &Derivs) -> bool {
    columns(&dv.jt).any(|c| c.iter().any(|v| *v != 0.0))
}

/// The root of the evidence's slope in `log10 α` from the values
/// `slope(log10 α)`: bracketed from `log10 α = 2` by decades (at most to
/// ±14), then bisected to 0.02. A positive slope means a smaller `α` is
/// more likely. `Ok(None)` from `slope` (a failed solve, an uninformative
/// observation) counts as a negative slope: the search moves to larger
/// `α`, the stronger regularization.
pub(crate) fn evidence_root(mut slope: impl FnMut(f64) -> Result<Option<f64>>) -> Result<f64> {
    let (lo_lim, hi_lim) = (-14.0f64, 14.0f64);
    let mut g = |a: f64| -> Result<f64> { Ok(slope(a)?.unwrap_or(-1.0)) };
    let mut a = ALPHA_CONTINUATION_START.log10();
    let mut v = g(a)?;
    let (mut lo, mut hi);
    if v > 0.0 {
        hi = a;
        while v > 0.0 && a > lo_lim {
            hi = a;
            a -= 1.0;
            v = g(a)?;
        }
        if v > 0.0 {
            return Ok(10f64.powf(a));
        }
        lo = a;
    } else {
        lo = a;
        while v <= 0.0 && a < hi_lim {
            lo = a;
            a += 1.0;
            v = g(a)?;
        }
        if v <= 0.0 {
            return Ok(10f64.powf(a));
        }
        hi = a;
    }
    while hi - lo > 0.02 {
        let mid = 0.5 * (lo + hi);
        if g(mid)? > 0.0 {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok(10f64.powf(0.5 * (lo + hi)))
}

/// `α` by the largest evidence for the observation `op`, each solve
/// starting from the last converged one (continuation in `α`); also the
/// warm start it leaves (the last converged solve of the search). An
/// observation the markers cannot see (see [`informative`]) has a flat
/// evidence: `α` stays at [`ALPHA_CONTINUATION_START`].
pub(crate) fn evidence_alpha<Mo: super::EstimationModel, Me: Method<Mo>>(
    method: &mut Me,
    op: &ObservationOperator,
    search: &mut super::AlphaSearch,
) -> Result<(f64, Warm)> {
    let (mut f0, mut q0) = method.stream().start()?;
    let mut blind = false;
    let a = evidence_root(|log_a| {
        if blind {
            return Ok(None);
        }
        let alpha = 10f64.powf(log_a);
        search.solves += 1;
        let Ok(s) = method.solve_one(op, f0.clone(), q0.clone(), alpha) else {
            return Ok(None);
        };
        search.iterations += s.report.iterations;
        if !informative(&s.derivs) {
            blind = true;
            return Ok(None);
        }
        let problem: &Problem<Mo> = &method.stream().problem;
        let pen = problem.penalty(&s.f)?;
        let ev = evidence(
            &problem.gn_form(op.len())?,
            &s.derivs,
            op.weights(),
            s.report.objective,
            pen,
            alpha,
        );
        if s.report.status.is_converged() {
            f0 = s.f;
            q0 = s.q;
        }
        Ok(ev.map(|e| e.slope))
    })?;
    let a = if blind { ALPHA_CONTINUATION_START } else { a };
    Ok((
        a,
        Warm {
            f: f0,
            q: q0,
            y: op.measurements().to_vec(),
        },
    ))
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::*;
    use crate::estimate::LoadModel;
    use crate::estimate::gn_form::PenaltyMatrix;
    use nalgebra::DMatrix;

    /// A load model and whether its system is solved in the primal form.
    type Case = (LoadModel, bool);

    /// Seeded numbers in [-1, 1).
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

    /// A linear problem `y = J F + n`: `B` symmetric positive definite
    /// (`n_f × n_f`), `Z` (`n_f × m`), `J = Zᵀ B`; weights `w`.
    struct Linear {
        b: DMatrix<f64>,
        z: DMatrix<f64>,
        w: Vec<f64>,
        y: Vec<f64>,
    }

    fn linear(nf: usize, m: usize, seed: u64) -> Linear {
        let r = DMatrix::from_vec(nf, nf, lcg(seed, nf * nf));
        let b = &r * r.transpose() + DMatrix::identity(nf, nf) * 0.5;
        let z = DMatrix::from_vec(nf, m, lcg(seed + 1, nf * m));
        let w: Vec<f64> = lcg(seed + 2, m).iter().map(|v| 2.0 + v).collect();
        let y = lcg(seed + 3, m).iter().map(|v| 3.0 * v).collect();
        Linear { b, z, w, y }
    }

    impl Linear {
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
        /// The minimizer of `(JF − y)ᵀW(JF − y) + α FᵀHF` and the
        /// evidence there, by dense linear algebra.
        fn form(&self, (load, primal): Case) -> GnForm {
            if primal {
                GnForm::Primal(std::sync::Arc::new(
                    PenaltyMatrix::new(self.h(load)).unwrap(),
                ))
            } else {
                GnForm::Representer
            }
        }
        fn at(&self, case: Case, alpha: f64) -> (Evidence, f64) {
            let load = case.0;
            let jt = self.jt(load);
            let h = self.h(load);
            let wm = DMatrix::from_diagonal(&nalgebra::DVector::from_column_slice(&self.w));
            let y = nalgebra::DVector::from_column_slice(&self.y);
            let n = &jt * &wm * jt.transpose() + &h * alpha;
            let f = n.clone().cholesky().unwrap().solve(&(&jt * &wm * &y));
            let e = jt.transpose() * &f - &y;
            let pen = (f.transpose() * &h * &f)[(0, 0)];
            let phi = (e.transpose() * &wm * &e)[(0, 0)] + alpha * pen;
            let dv = Derivs {
                z: self.z.clone(),
                jt,
            };
            let form = self.form(case);
            (evidence(&form, &dv, &self.w, phi, pen, alpha).unwrap(), pen)
        }
        /// `−2 log N(y; 0, W⁻¹ + J (αH)⁻¹ Jᵀ)`, directly.
        fn direct(&self, (load, _): Case, alpha: f64) -> f64 {
            let jt = self.jt(load);
            let hinv = self.h(load).try_inverse().unwrap() / alpha;
            let winv = DMatrix::from_diagonal(&nalgebra::DVector::from_iterator(
                self.w.len(),
                self.w.iter().map(|v| 1.0 / v),
            ));
            let c = winv + jt.transpose() * hinv * &jt;
            let y = nalgebra::DVector::from_column_slice(&self.y);
            let chol = c.cholesky().unwrap();
            let m = self.y.len() as f64;
            (y.transpose() * chol.solve(&y))[(0, 0)]
                + log_det(&chol)
                + m * (2.0 * std::f64::consts::PI).ln()
        }
    }

    /// The distributed load in both forms, the concentrated one (primal).
    const MODELS: [Case; 3] = [
        (LoadModel::Distributed, false),
        (LoadModel::Distributed, true),
        (LoadModel::Concentrated { node: 1 }, true),
    ];

    /// The evidence equals the Gaussian marginal likelihood written out
    /// (`y ~ N(0, W⁻¹ + J (αH)⁻¹ Jᵀ)`), for both load models and both
    /// forms of the distributed load's system, with fewer and with more
    /// observed components than parameters.
    /// Bound 1e-9 relative (a missing `log α` term is off by O(m)).
    #[test]
    fn evidence_is_the_marginal_likelihood() {
        for load in MODELS {
            for p in [linear(7, 4, 11), linear(5, 9, 12)] {
                for alpha in [1e-3, 0.1, 3.0, 100.0] {
                    let (ev, _) = p.at(load, alpha);
                    let direct = p.direct(load, alpha);
                    let err = (ev.minus_two_log - direct).abs() / direct.abs().max(1.0);
                    assert!(
                        err < 1e-9,
                        "{load:?} alpha {alpha}: {} vs {direct}",
                        ev.minus_two_log
                    );
                }
            }
        }
    }

    /// The slope `d(−2 log p)/d log α = α FᵀHF − γ` equals central finite
    /// differences of the evidence (each side re-minimized), for both load
    /// models (the distributed one in both forms) over five decades. Bound 1e-6 relative to `max(|slope|, 1)`
    /// (a wrong sign or a missing trace term is off by O(1)).
    #[test]
    fn evidence_slope_matches_finite_differences() {
        for load in MODELS {
            let p = linear(9, 5, 3);
            for alpha in [1e-3, 1e-2, 0.3, 5.0, 80.0] {
                let (ev, _) = p.at(load, alpha);
                let h: f64 = 1e-5;
                let up = p.at(load, alpha * h.exp()).0.minus_two_log;
                let dn = p.at(load, alpha * (-h).exp()).0.minus_two_log;
                let fd = (up - dn) / (2.0 * h);
                let err = (ev.slope - fd).abs() / ev.slope.abs().max(1.0);
                assert!(
                    err < 1e-6,
                    "{load:?} alpha {alpha}: {} vs fd {fd}",
                    ev.slope
                );
                assert!(ev.gamma > 0.0 && ev.gamma < 5.0 + 1e-12);
            }
        }
    }

    /// The root search finds the zero of a monotone slope to 0.02 decades
    /// from either side, and stops at the limits when there is none.
    #[test]
    fn evidence_root_brackets_and_bisects() {
        for root in [-7.3, -0.4, 2.0, 5.55] {
            let a = evidence_root(|x| Ok(Some(x - root))).unwrap();
            assert!((a.log10() - root).abs() <= 0.011, "{root}: {}", a.log10());
        }
        assert_eq!(evidence_root(|_| Ok(Some(1.0))).unwrap(), 1e-14);
        assert_eq!(evidence_root(|_| Ok(None)).unwrap(), 1e14);
    }

    /// With a zero Jacobian the observation is not informative.
    #[test]
    fn zero_jacobian_is_uninformative() {
        let p = linear(4, 2, 5);
        let dv = Derivs {
            z: DMatrix::zeros(4, 2),
            jt: DMatrix::zeros(4, 2),
        };
        assert!(!informative(&dv));
        let dv = Derivs {
            z: p.z.clone(),
            jt: p.jt(LoadModel::Distributed),
        };
        assert!(informative(&dv));
    }
}
