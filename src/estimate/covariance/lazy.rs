//! The covariances of an estimate formed on request: what they are formed
//! from ([`CovarianceInputs`]) and the cells that keep them once formed
//! ([`LazyCovariances`]).

use std::sync::{Arc, OnceLock};

use nalgebra::DMatrix;

use super::super::LoadModel;
use super::super::gn_form::GnForm;
use super::super::problem::{Derivs, GnFactor};
use super::{
    MarkerPart, cov_factor, largest_relative_variance, noise_cov, posterior,
    posterior_alpha_marginal, prior_resultant,
};

/// What the covariances of an estimate are formed from: the derivatives
/// and the Gauss–Newton factor of its last linearization, with what the
/// formulas need besides. An [`Estimate`](super::super::Estimate) keeps them and forms its
/// covariances when first asked ([`LazyCovariances`]): a stream of
/// estimates that reads no covariance pays for none.
#[derive(Debug, Clone)]
pub(crate) struct CovarianceInputs {
    /// The load model.
    pub(crate) load: LoadModel,
    /// The form of its Gauss–Newton systems ([`super::super::gn_form`]).
    pub(crate) form: GnForm,
    /// Coordinates per node (the first `DIM` of them the position).
    pub(crate) nd: usize,
    /// Load slots per node that carry a load (`2 DIM`): the rows of `L`
    /// beyond them in each node's are zero, like those entries of `F`.
    pub(crate) used_slots: usize,
    /// The stated marker noise (m).
    pub(crate) sigma: f64,
    /// The map `C: F → ∫ w dX` (row-major `DIM × n_F`).
    pub(crate) fw: Vec<f64>,
    /// The derivatives of the last linearization.
    pub(crate) dv: Derivs,
    /// The diagonal of `W`.
    pub(crate) weights: Vec<f64>,
    /// The `α` of the estimate.
    pub(crate) alpha: f64,
    /// When `α` is the evidence's and the markers see the load: the
    /// estimate `F̂` and its penalty `F̂ᵀ H F̂` (the covariances are then
    /// averaged over `α`, [`posterior_alpha_marginal`]).
    pub(crate) evidence: Option<(Vec<f64>, f64)>,
    /// When the markers see the load: the objective `Φ` and the penalty
    /// `F̂ᵀ H F̂` at the estimate, for the evidence's `γ`
    /// ([`LazyCovariances::determined_directions`]; `None`: `γ` = 0).
    pub(crate) gamma: Option<(f64, f64)>,
    /// The Gauss–Newton system's factor at `dv`, if at hand.
    pub(crate) gn: Option<GnFactor>,
}

impl CovarianceInputs {
    /// The covariance factor `L` (`n_F × n_ob`; NaN if the Gauss–Newton
    /// matrix cannot be factored, which an estimate whose step solved that
    /// system never meets).
    fn factor(&self) -> DMatrix<f64> {
        let (nf, m) = (self.dv.jt.nrows(), self.weights.len());
        let Some(mut l) = cov_factor(
            &self.form,
            self.sigma,
            &self.dv,
            &self.weights,
            self.alpha,
            self.gn.as_ref(),
        ) else {
            return DMatrix::from_element(nf, m, f64::NAN);
        };
        if self.load == LoadModel::Distributed && self.nd > self.used_slots {
            for i in 0..l.nrows() {
                if i % self.nd >= self.used_slots {
                    l.row_mut(i).fill(0.0);
                }
            }
        }
        l
    }

    /// `Cov(resultant force)` (`DIM × DIM`) and `Cov(A q)` (`n_ob ×
    /// n_ob`): the posterior's ([`posterior`], averaged over `α` when it is
    /// the evidence's), or, when its matrix cannot be factored, the spread
    /// the noise alone causes, from the covariance factor `l()`. Of
    /// `Cov(A q)` the `markers` part (row-major when full).
    fn posterior(
        &self,
        markers: MarkerPart,
        l: impl FnOnce() -> DMatrix<f64>,
    ) -> (DMatrix<f64>, Vec<f64>) {
        let (load, nd, fw, dv, w, alpha) = (
            &self.form,
            self.nd,
            &self.fw[..],
            &self.dv,
            &self.weights[..],
            self.alpha,
        );
        let gn = self.gn.as_ref();
        let d = fw.len().checked_div(dv.jt.nrows()).unwrap_or(0);
        let typed = |(r, mk): (Vec<f64>, Vec<f64>)| (DMatrix::from_row_slice(d, d, &r), mk);
        if let Some((f, pen)) = &self.evidence {
            let c = posterior_alpha_marginal(load, nd, fw, dv, w, alpha, f, *pen, gn, markers);
            if let Some(c) = c {
                return typed(c);
            }
        }
        if let Some(c) = posterior(load, nd, fw, dv, w, alpha, gn, markers) {
            return typed(c);
        }
        typed(noise_cov(&l(), fw, dv, markers))
    }
}

/// The covariances of an [`Estimate`](super::super::Estimate), formed from its
/// [`CovarianceInputs`] on the first request and kept. Two are equal when
/// their covariances are (comparing forms both).
#[derive(Debug, Clone)]
pub(crate) struct LazyCovariances {
    inputs: Arc<CovarianceInputs>,
    factor: OnceLock<DMatrix<f64>>,
    posterior: OnceLock<(DMatrix<f64>, DMatrix<f64>)>,
    /// The resultant's posterior covariance when asked for alone (without
    /// `Cov(A q)`, whose work grows as `n_ob²`).
    resultant: OnceLock<DMatrix<f64>>,
    /// The variances of `A q` when asked for alone (the diagonal of
    /// `Cov(A q)` without the rest).
    marker_variances: OnceLock<Vec<f64>>,
    gamma: OnceLock<f64>,
    prior_fraction: OnceLock<(f64, Vec<f64>)>,
}

impl LazyCovariances {
    /// Covariances to be formed from `inputs`.
    pub(crate) fn new(inputs: CovarianceInputs) -> Self {
        LazyCovariances {
            inputs: Arc::new(inputs),
            factor: OnceLock::new(),
            posterior: OnceLock::new(),
            resultant: OnceLock::new(),
            marker_variances: OnceLock::new(),
            gamma: OnceLock::new(),
            prior_fraction: OnceLock::new(),
        }
    }

    /// How many load directions the markers determine at the estimate's
    /// `α`: the evidence's effective number of parameters `γ` (0 when the
    /// markers see nothing of the load, `NaN` if it cannot be formed).
    pub(crate) fn determined_directions(&self) -> f64 {
        *self.gamma.get_or_init(|| {
            let i = &self.inputs;
            match i.gamma {
                Some((objective, pen)) => super::super::evidence::evidence(
                    &i.form, &i.dv, &i.weights, objective, pen, i.alpha,
                )
                .map_or(f64::NAN, |ev| ev.gamma),
                None => 0.0,
            }
        })
    }

    /// The largest fraction of the resultant's prior variance the markers
    /// leave in any direction at the estimate's `α`: the largest
    /// eigenvalue of `P⁻¹ Σ`, `P = C (αH)⁻¹ Cᵀ` the prior's covariance of
    /// the resultant ([`prior_resultant`]) and `Σ` the posterior's at the
    /// same `α` ([`posterior`], not averaged over `α`), in `(0, 1]`, and
    /// that direction (unit, world axes); 1 when the markers see nothing of
    /// the load (no direction), `NaN` if it cannot be formed.
    pub(crate) fn resultant_prior_fraction(&self) -> &(f64, Vec<f64>) {
        self.prior_fraction.get_or_init(|| {
            let i = &self.inputs;
            if i.gamma.is_none() {
                return (1.0, Vec::new());
            }
            let nf = i.dv.jt.nrows();
            let d = i.fw.len().checked_div(nf).unwrap_or(0);
            let prior = prior_resultant(&i.form, i.nd, &i.fw, nf, i.alpha);
            let post = posterior(
                &i.form,
                i.nd,
                &i.fw,
                &i.dv,
                &i.weights,
                i.alpha,
                i.gn.as_ref(),
                MarkerPart::None,
            );
            match (prior, post) {
                (Some(p), Some((s, _))) => largest_relative_variance(
                    DMatrix::from_row_slice(d, d, &p),
                    &DMatrix::from_row_slice(d, d, &s),
                )
                .map_or((f64::NAN, Vec::new()), |(r, u)| (r, u.as_slice().to_vec())),
                _ => (f64::NAN, Vec::new()),
            }
        })
    }

    /// The covariance factor `L`.
    pub(super) fn factor(&self) -> &DMatrix<f64> {
        self.factor.get_or_init(|| self.inputs.factor())
    }

    /// The posterior covariances of the resultant force and of `A q`.
    pub(super) fn posterior(&self) -> &(DMatrix<f64>, DMatrix<f64>) {
        self.posterior.get_or_init(|| {
            let m = self.inputs.weights.len();
            let (r, mk) = self
                .inputs
                .posterior(MarkerPart::Full, || self.factor().clone());
            let mk = if mk.len() == m * m {
                DMatrix::from_row_slice(m, m, &mk)
            } else {
                DMatrix::from_element(m, m, f64::NAN)
            };
            (r, mk)
        })
    }

    /// The posterior covariance of the resultant force: from
    /// [`LazyCovariances::posterior`] if formed, else alone (the same
    /// numbers, without `Cov(A q)`).
    pub(super) fn resultant(&self) -> &DMatrix<f64> {
        if let Some(p) = self.posterior.get() {
            return &p.0;
        }
        self.resultant.get_or_init(|| {
            self.inputs
                .posterior(MarkerPart::None, || self.factor().clone())
                .0
        })
    }

    /// The posterior variances of `A q` (the diagonal of `Cov(A q)`): from
    /// [`LazyCovariances::posterior`] if formed, else alone (the same
    /// numbers, without the `n_ob²` matrix).
    pub(super) fn marker_variances(&self) -> Vec<f64> {
        if let Some(p) = self.posterior.get() {
            return p.1.diagonal().as_slice().to_vec();
        }
        self.marker_variances
            .get_or_init(|| {
                let m = self.inputs.weights.len();
                let (_, v) = self
                    .inputs
                    .posterior(MarkerPart::Diagonal, || self.factor().clone());
                if v.len() == m { v } else { vec![f64::NAN; m] }
            })
            .clone()
    }
}

impl PartialEq for LazyCovariances {
    fn eq(&self, other: &Self) -> bool {
        self.factor() == other.factor() && self.posterior() == other.posterior()
    }
}
