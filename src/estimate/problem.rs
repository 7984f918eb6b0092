//! The estimation problem (25) and what it computes at a point, apart from
//! the methods that search it (argmin's problem/solver split):
//!
//! - the unknown load `Q_F = G F` ([`LoadModel`] as a [`LinearLoad`]) and its
//!   penalty `α Fᵀ H F` (26);
//! - the equilibrium `q(F)` (17), through the static solver's warm tracker;
//! - the objective `(A q − y)ᵀ W (A q − y) + α Fᵀ H F` (25);
//! - the marker Jacobian `J = ∂(A q)/∂F` (28) by adjoint solves
//!   ([`crate::sensitivity`]);
//! - the reduced gradient (29) and the Gauss–Newton step (30);
//! - the resultants of a load, and the direct solution (24).
//!
//! [`super::newton`] and [`super::sqp`] are methods over it.

use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

use crate::assembly::Robot;
use crate::element::{Element, NodeKinematics};
use crate::error::{Error, Result, check_len};
use crate::linsolve::AutoFactors;
use crate::loads::Loads;
use crate::numeric::dot;
use crate::observe::{MAX_MARKER_SCALE, MarkerObservation, Observation, ObservationOperator};
use crate::sensitivity::Sensitivity;
use crate::statics::tracker::FactoredTangent;
use crate::statics::{LinearLoad, StaticSolver, TrackedEquilibrium, Tracker};
use crate::structure::ModelLoads;

use super::gn_form::{
    GnForm, PenaltyMatrix, count_dense, jittered_cholesky, primal_system, weighted_columns,
};
use super::load_model::field_rod;
use super::{BoundFrame, EstimationModel, EstimatorSettings, LoadModel};

/// The derivatives of the observation at an equilibrium.
#[derive(Debug, Clone)]
pub struct Derivs {
    /// Adjoint fields `z_i = M K⁻¹ Mᵀ a_iᵀ`, column `i` (`n_q × n_ob`).
    pub(crate) z: DMatrix<f64>,
    /// The marker Jacobian transposed (28): column `i` is `J_i = Gᵀ z_i`,
    /// the gradient of observed scalar `i` with respect to `F` (`n_F × n_ob`).
    pub(crate) jt: DMatrix<f64>,
}

/// The Cholesky factor of a Gauss–Newton system ([`Problem::gn_solve`]):
/// `S = α W⁻¹ + Zᵀ B Z` (`n_ob × n_ob`) for the distributed load in the
/// representer form (`n_ob ≤ n_F`), `N = Jᵀ W J + α H` (`n_F × n_F`) in
/// the primal form (a concentrated load, or a distributed one observed by
/// more components than it has parameters); with the `α` it was formed at
/// and, in the representer form, `Zᵀ B Z` itself (`None` in the primal
/// form): the posterior covariances at that `α` are formed from them
/// ([`super::covariance::posterior_cov`]) instead of again.
#[derive(Debug, Clone)]
pub struct GnFactor {
    /// The factor of `S` or `N`.
    pub chol: Cholesky<f64, Dyn>,
    /// `Zᵀ B Z` (the representer form; `None` in the primal form).
    pub gram: Option<DMatrix<f64>>,
    /// The `α` of the system.
    pub alpha: f64,
}

/// The estimation problem: the robot, its known loads and the load model,
/// with the equilibrium tracker that solves `q(F)`.
#[derive(Debug, Clone)]
pub struct Problem<M: EstimationModel> {
    tracker: Tracker<M>,
    settings: EstimatorSettings,
    n_f: usize,
    /// The last observation's markers and their operator: the next frame
    /// of the same markers reuses it ([`Problem::operator_of_frame`]).
    last_operator: Option<(Vec<MarkerObservation>, ObservationOperator)>,
    /// The shape of the known loads alone ([`Problem::unloaded_start`]),
    /// once solved, with the factored tangent there when it was formed.
    unloaded: Option<(Vec<f64>, Option<FactoredTangent>)>,
    /// The map `F → ∫ w dX` of the distributed load ([`Problem::resultants`]),
    /// once formed (it depends on the mesh alone).
    load_map: std::sync::OnceLock<Vec<f64>>,
    /// The dense penalty matrix of the primal form ([`Problem::gn_form`]),
    /// once formed; `None` inside when it is singular.
    penalty_matrix: std::sync::OnceLock<Option<std::sync::Arc<PenaltyMatrix>>>,
    /// The most observed components a distributed load is solved for in
    /// the representer form (default `n_F`; beyond it the primal form).
    representer_max: usize,
}

impl<M: EstimationModel> Problem<M> {
    /// The problem of `robot` under the known loads `known`.
    pub(crate) fn new(robot: M, known: M::Loads, settings: EstimatorSettings) -> Result<Self> {
        settings.validate()?;
        if let LoadModel::Concentrated { node } = settings.load_model {
            let nodes = robot.field_rod().map_or(0, |r| r.n_nodes());
            if node == 0 || node >= nodes {
                return Err(Error::invalid(
                    "estimator.load_model.node",
                    node,
                    format!("must be a free node, 1..={}", nodes.saturating_sub(1)),
                ));
            }
        }
        if !known.conservative() {
            // the sensitivities solve with the symmetric tangent: a follower
            // load's stiffness is not symmetric (assembly::Robot::follower_stiffness)
            return Err(Error::invalid(
                "follower_loads",
                "follower loads",
                "the estimator does not take follower loads among its known loads yet \
                 (its sensitivities assume a symmetric tangent); solve with them instead",
            ));
        }
        settings.load_model.force_basis(M::Element::DIM)?;
        let n_f = settings.load_model.n_params(&robot);
        super::load_model::check_site_moves(&settings.load_model, &robot)?;
        for (i, b) in settings.bounds.iter().enumerate() {
            check_len(
                &format!("estimator.bounds[{i}].direction"),
                M::Element::DIM,
                b.direction.len(),
            )?;
            if b.frame == BoundFrame::Local && M::Element::DIM != 2 {
                return Err(Error::invalid(
                    format!("estimator.bounds[{i}].frame"),
                    "local",
                    "the local frame (tangent, normal) is planar only: give the direction \
                     in world axes",
                ));
            }
            if settings.load_model == LoadModel::Distributed {
                field_rod(&robot)?.locate(&format!("estimator.bounds[{i}].s_m"), b.s_m)?;
            }
            if let LoadModel::AtSite { site } | LoadModel::Along { site, .. } = settings.load_model
                && b.frame == BoundFrame::Local
                && matches!(site, crate::site::Site::Body { .. })
            {
                return Err(Error::invalid(
                    format!("estimator.bounds[{i}].frame"),
                    "local",
                    "a rigid body's site has no tangent: give the direction in world axes",
                ));
            }
        }
        let tracker = Tracker::new(robot, known, settings.statics.clone())?;
        Ok(Problem {
            tracker,
            settings,
            n_f,
            last_operator: None,
            unloaded: None,
            load_map: std::sync::OnceLock::new(),
            penalty_matrix: std::sync::OnceLock::new(),
            representer_max: n_f,
        })
    }

    /// The robot.
    pub(crate) fn robot(&self) -> &M {
        self.tracker.model()
    }

    /// The equilibrium tracker.
    pub(crate) fn tracker(&mut self) -> &mut Tracker<M> {
        &mut self.tracker
    }

    /// The equilibrium tracker, to read.
    pub(crate) fn tracker_ref(&self) -> &Tracker<M> {
        &self.tracker
    }

    /// The known loads.
    pub(crate) fn known(&self) -> &M::Loads {
        self.tracker.known()
    }

    /// The settings.
    pub(crate) fn settings(&self) -> &EstimatorSettings {
        &self.settings
    }

    /// Number of load parameters `n_F`.
    pub(crate) fn n_f(&self) -> usize {
        self.n_f
    }

    /// The load model.
    pub(crate) fn load(&self) -> LoadModel {
        self.settings.load_model
    }

    /// The observation operator of `obs` with the settings' noise.
    pub(crate) fn operator(&self, obs: &Observation) -> Result<ObservationOperator> {
        ObservationOperator::new(
            self.robot(),
            obs,
            self.settings.noise_sigma_m,
            self.settings.tangent_sigma,
        )
    }

    /// [`Problem::operator`] for a frame of a stream: when `obs` has the
    /// markers of the last frame (the same nodes or arc positions, the same
    /// kinds and weights; only the measured values differ), the last
    /// operator with the new measurements, which pass the same checks
    /// (finite, not beyond [`MAX_MARKER_SCALE`] robot lengths, tangents of
    /// a length in `(0, MAX_MARKER_SCALE]`); otherwise, or when a value
    /// fails them, built anew (with its error naming the field), and kept.
    pub(crate) fn operator_of_frame(&mut self, obs: &Observation) -> Result<ObservationOperator> {
        if let Some((markers, op)) = &self.last_operator
            && let Some(y) =
                same_markers_values(markers, obs, self.robot().length_m(), M::Element::DIM)
            && let Ok(op) = op.with_measurements(y)
        {
            return Ok(op);
        }
        let op = self.operator(obs)?;
        self.last_operator = Some((obs.markers.clone(), op.clone()));
        Ok(op)
    }

    /// `G F` over all coordinates (N).
    pub(crate) fn gen_force(&self, f: &[f64]) -> Result<Vec<f64>> {
        Ok(self.load().force(self.robot(), f)?.data.into())
    }

    /// `H F`: the penalty (26) is `α Fᵀ H F`, `H = B` for the distributed
    /// field (`α ∫ wᵀ w dX`), `H = I` for a concentrated force.
    pub(crate) fn penalty_grad(&self, f: &[f64]) -> Result<Vec<f64>> {
        match self.load() {
            LoadModel::Distributed => Ok(field_rod(self.robot())?.apply_load_gram(f)?.data.into()),
            LoadModel::Concentrated { .. } | LoadModel::AtSite { .. } | LoadModel::Along { .. } => {
                Ok(f.to_vec())
            }
        }
    }

    /// `Fᵀ H F`.
    pub(crate) fn penalty(&self, f: &[f64]) -> Result<f64> {
        Ok(self
            .penalty_grad(f)?
            .iter()
            .zip(f)
            .map(|(a, b)| a * b)
            .sum())
    }

    /// The dead force with the unknown load `F` (`n_q`).
    pub(crate) fn dead_with(&self, f: &[f64]) -> Result<Vec<f64>> {
        Ok(self.tracker.dead_with(&self.load(), f)?.data.into())
    }

    /// The residual `Q` over the free coordinates at `(q, F)`.
    pub(crate) fn residual(&self, q: &[f64], f: &[f64]) -> Result<Vec<f64>> {
        Ok(self.tracker.residual(&self.load(), q, f)?.data.into())
    }

    /// The residual `Q` over the free coordinates at `q = φ(u)` under the
    /// dead force `dead` (the known loads' and the unknown load's).
    pub(crate) fn residual_under(&self, u: &[f64], q: &[f64], dead: &[f64]) -> Result<Vec<f64>> {
        let mut out = vec![0.0; self.robot().n_free()];
        self.robot()
            .residual_into(u, q, dead, self.known(), &mut out)?;
        Ok(out)
    }

    /// The equilibrium `q(F)` from `q0` (warm; the globalized static solve
    /// if needed).
    pub(crate) fn equilibrium(&mut self, f: &[f64], q0: &[f64]) -> Result<TrackedEquilibrium> {
        let load = self.load();
        self.tracker.solve(&load, f, q0)
    }

    /// The tangent at `q` and its factors, with the tracker's linear
    /// solver (see [`EquilibriumTracker::factor_tangent`]).
    pub(crate) fn factor_tangent(&mut self, q: &[f64]) -> Result<FactoredTangent> {
        self.tracker.factor_tangent(q)
    }

    /// The equilibrium and the free start: zero load and the shape of the
    /// known loads alone (solved once, then kept until the known loads
    /// change, [`Problem::set_known`]).
    ///
    /// Without known loads the static solver's cold start (the robot's
    /// reference shape) is that shape when its residual is at the round-off
    /// floor ([`crate::statics::residual_floor`]): taken as it is, its
    /// tangent factored once and kept for the first solve (the tracker's
    /// chord step and the sqp backend's first QP start from those factors)
    /// instead of a static solve (18 residuals on the unloaded exudyn cable
    /// at 20 elements: a tenth of a first estimate). Otherwise the static
    /// solve of the known loads.
    pub(crate) fn unloaded_start(&mut self) -> Result<(Vec<f64>, Vec<f64>)> {
        let f = vec![0.0; self.n_f];
        if let Some((q, _)) = &self.unloaded {
            return Ok((f, q.clone()));
        }
        if *self.known() == M::Loads::default() {
            let q: Vec<f64> = self.robot().reference_q().data.into();
            let r = self.residual(&q, &f)?;
            let t = self.tracker.factor_tangent(&q)?;
            let floor = crate::statics::residual_floor(
                t.matrix.max_abs(),
                crate::numeric::max_abs(&q),
                self.robot().n_free(),
            );
            if crate::numeric::norm2(&r) <= floor {
                self.tracker.keep_factors(&q, t.factors.clone())?;
                self.unloaded = Some((q.clone(), Some(t)));
                return Ok((f, q));
            }
        }
        let solver = StaticSolver::new(self.settings.statics.clone())?;
        let eq = solver.solve(self.robot(), self.tracker.known(), None)?;
        let q: Vec<f64> = eq.q.data.into();
        self.unloaded = Some((q.clone(), None));
        Ok((f, q))
    }

    /// The factored tangent at the unloaded start, if `q` is that shape and
    /// it was formed there ([`Problem::unloaded_start`]).
    pub(crate) fn unloaded_tangent(&self, q: &[f64]) -> Option<FactoredTangent> {
        match &self.unloaded {
            Some((qs, Some(t))) if qs == q => Some(t.clone()),
            _ => None,
        }
    }

    /// Replaces the known loads ([`EquilibriumTracker::set_known`]; with a
    /// chord strategy [`EquilibriumTracker::set_loads`], which keeps the
    /// factors) and forgets the shape of the old ones.
    pub(crate) fn set_known(&mut self, known: M::Loads) -> Result<()> {
        // a chord strategy's kept factors are a chord's, whose steps check
        // their own contraction and refactor where it fails: they stay
        // across the change (a controller's next command); otherwise they
        // are the tangent at a solution under the old loads and go
        if matches!(
            self.tracker.strategy(),
            crate::statics::WarmStrategy::ChordRefactor { .. }
        ) {
            self.tracker.set_loads(known)?;
        } else {
            self.tracker.set_known(known)?;
        }
        self.unloaded = None;
        Ok(())
    }

    /// The form the Gauss–Newton systems of `m` observed components are
    /// solved in ([`super::gn_form`]): the representer form for the
    /// distributed load while `m ≤ n_F` (or when its load Gram matrix is
    /// singular), the primal form otherwise.
    pub(crate) fn gn_form(&self, m: usize) -> Result<GnForm> {
        let primal = match self.load() {
            LoadModel::Distributed if m <= self.representer_max => None,
            _ => self.penalty_matrix()?,
        };
        Ok(primal.map_or(GnForm::Representer, GnForm::Primal))
    }

    /// Solves the distributed load in the representer form up to `m`
    /// observed components (default `n_F`): the tests compare the two
    /// forms on the same estimates.
    #[cfg(test)]
    pub(crate) fn set_representer_max(&mut self, m: usize) {
        self.representer_max = m;
    }

    /// The dense penalty matrix `H` and `log det H`: `B` of the distributed
    /// load (its columns `B e_j`, the numbers of [`Problem::penalty_grad`]),
    /// `I` for a concentrated force; formed at the first call and kept.
    /// `None` if `H` is not positive definite.
    fn penalty_matrix(&self) -> Result<Option<std::sync::Arc<PenaltyMatrix>>> {
        if let Some(h) = self.penalty_matrix.get() {
            return Ok(h.clone());
        }
        let nf = self.n_f;
        let h = match self.load() {
            LoadModel::Distributed => {
                let rod = field_rod(self.robot())?;
                let mut h = DMatrix::zeros(nf, nf);
                let mut e = vec![0.0; nf];
                for (j, col) in h.as_mut_slice().chunks_exact_mut(nf.max(1)).enumerate() {
                    e[j] = 1.0;
                    rod.apply_load_gram_into(&e, col)?;
                    e[j] = 0.0;
                }
                h
            }
            LoadModel::Concentrated { .. } | LoadModel::AtSite { .. } | LoadModel::Along { .. } => {
                DMatrix::identity(nf, nf)
            }
        };
        let h = PenaltyMatrix::new(h).map(std::sync::Arc::new);
        Ok(self.penalty_matrix.get_or_init(|| h).clone())
    }

    /// Adjoint fields and the marker Jacobian (28) at an equilibrium with
    /// the tangent's factors `lu`: row `i` of `∂(Aq)/∂F` is
    /// `Gᵀ M K⁻¹ Mᵀ a_iᵀ` (K symmetric), the `n_ob` adjoint systems in one
    /// sweep over the factors.
    pub(crate) fn derivs(
        &self,
        q: &[f64],
        lu: &AutoFactors,
        op: &ObservationOperator,
    ) -> Result<Derivs> {
        let u = self.robot().free_coordinates_of(q)?;
        self.derivs_of(Sensitivity::at(self.robot(), u.as_slice(), lu)?, op)
    }

    /// [`Problem::derivs`] at the free coordinates `u` of the equilibrium
    /// (the clamped robot's map is linear: its `u` is not read).
    pub(crate) fn derivs_at(
        &self,
        u: &[f64],
        lu: &AutoFactors,
        op: &ObservationOperator,
    ) -> Result<Derivs> {
        self.derivs_of(Sensitivity::at(self.robot(), u, lu)?, op)
    }

    /// `T(u)ᵀ f`: a force `f` over all coordinates as the free coordinates
    /// at `u` see it.
    pub(crate) fn restrict(&self, u: &[f64], f: &[f64]) -> Result<DVector<f64>> {
        let mut out = DVector::zeros(self.robot().n_free());
        self.robot().restrict_into(u, f, out.as_mut_slice())?;
        Ok(out)
    }

    /// `dq = T(u) du`: a step of the free coordinates at `u` over all
    /// coordinates.
    pub(crate) fn expand(&self, u: &[f64], du: &[f64]) -> Result<DVector<f64>> {
        let mut dq = DVector::zeros(self.robot().n_q());
        self.robot().step_into(u, du, dq.as_mut_slice())?;
        Ok(dq)
    }

    /// [`Problem::derivs`] from the sensitivities `s` of the equilibrium.
    fn derivs_of(&self, s: Sensitivity<'_, M>, op: &ObservationOperator) -> Result<Derivs> {
        let adj = s.adjoints(op.rows().iter().map(|r| r.entries()))?;
        let jt = match self.load() {
            // J_i = B z_i straight into the columns (the numbers of
            // `load_gradients`, without a vector per column)
            LoadModel::Distributed => {
                let rod = field_rod(self.robot())?;
                let (nq, m) = adj.full.shape();
                let mut jt = DMatrix::zeros(nq, m);
                for (z, out) in adj
                    .full
                    .as_slice()
                    .chunks_exact(nq.max(1))
                    .zip(jt.as_mut_slice().chunks_exact_mut(nq.max(1)))
                {
                    rod.apply_load_gram_into(z, out)?;
                }
                jt
            }
            LoadModel::Concentrated { .. } | LoadModel::AtSite { .. } | LoadModel::Along { .. } => {
                s.load_gradients(&self.load(), &adj)?
            }
        };
        Ok(Derivs { z: adj.full, jt })
    }

    /// The objective parts at `(q, F)`: `(eᵀWe, α FᵀHF, e)` (25).
    pub(crate) fn objective(
        &self,
        op: &ObservationOperator,
        q: &[f64],
        f: &[f64],
        alpha: f64,
    ) -> Result<(f64, f64, Vec<f64>)> {
        let (wr, pen, e, _) = self.objective_hf(op, q, f, alpha)?;
        Ok((wr, pen, e))
    }

    /// As [`Problem::objective`], with `H F` ([`Problem::penalty_grad`]),
    /// which the gradient at the same `F` takes
    /// ([`Problem::gradient_hf`]) instead of forming it again.
    pub(crate) fn objective_hf(
        &self,
        op: &ObservationOperator,
        q: &[f64],
        f: &[f64],
        alpha: f64,
    ) -> Result<(f64, f64, Vec<f64>, Vec<f64>)> {
        let hf = self.penalty_grad(f)?;
        let (wr, pen, e) = self.objective_with_hf(op, q, f, &hf, alpha);
        Ok((wr, pen, e, hf))
    }

    /// As [`Problem::objective`], with `H F` given (`hf`).
    pub(crate) fn objective_with_hf(
        &self,
        op: &ObservationOperator,
        q: &[f64],
        f: &[f64],
        hf: &[f64],
        alpha: f64,
    ) -> (f64, f64, Vec<f64>) {
        let e = op.residual(q);
        let pen: f64 = hf.iter().zip(f).map(|(a, b)| a * b).sum();
        (op.weighted(&e), alpha * pen, e)
    }

    /// Reduced gradient (29): `2 (Jᵀ W e + α H F)`.
    pub(crate) fn gradient(
        &self,
        dv: &Derivs,
        op: &ObservationOperator,
        e: &[f64],
        f: &[f64],
        alpha: f64,
    ) -> Result<Vec<f64>> {
        self.gradient_hf(dv, op, e, &self.penalty_grad(f)?, alpha)
    }

    /// As [`Problem::gradient`], with `H F` given (`hf`, `n_F`).
    pub(crate) fn gradient_hf(
        &self,
        dv: &Derivs,
        op: &ObservationOperator,
        e: &[f64],
        hf: &[f64],
        alpha: f64,
    ) -> Result<Vec<f64>> {
        check_len("hf", self.n_f, hf.len())?;
        let mut g: Vec<f64> = hf.iter().map(|v| 2.0 * alpha * v).collect();
        for ((ji, wi), ei) in columns(&dv.jt).zip(op.weights()).zip(e) {
            let c = 2.0 * wi * ei;
            g.iter_mut().zip(ji).for_each(|(a, b)| *a += c * b);
        }
        Ok(g)
    }

    /// The Gauss–Newton step (30): solves `(JᵀWJ + αH) dF = −(JᵀWe + αHF)`,
    /// and the Cholesky factor of its system, in the form of
    /// [`Problem::gn_form`]: the representer form `F + dF = Σ_i z_i c_i`,
    /// `(α W⁻¹ + Zᵀ B Z) c = J F − e` (an `n_ob × n_ob` Cholesky, no `n_q³`
    /// work) for a distributed load observed by at most `n_F` components;
    /// otherwise the `n_F × n_F` system itself, its matrix accumulated over
    /// the marker rows (work linear in the markers).
    pub(crate) fn gn_solve(
        &self,
        dv: &Derivs,
        op: &ObservationOperator,
        e: &[f64],
        f: &[f64],
        alpha: f64,
    ) -> Result<(Vec<f64>, GnFactor)> {
        self.gn_solve_reusing(dv, op, e, f, alpha, None)
    }

    /// As [`Problem::gn_solve`], with the factor `reuse` of the system when
    /// the caller has it: formed by `gn_solve` from the same `dv` and the
    /// same weights of `op` (a warm step's first iteration, at the last
    /// estimate's cached derivatives). It is used when its `α` is `alpha`
    /// and its form is this one (the same numbers: `S` or `N` depends on
    /// nothing else), formed anew otherwise.
    pub(crate) fn gn_solve_reusing(
        &self,
        dv: &Derivs,
        op: &ObservationOperator,
        e: &[f64],
        f: &[f64],
        alpha: f64,
        reuse: Option<GnFactor>,
    ) -> Result<(Vec<f64>, GnFactor)> {
        let w = op.weights();
        let not_spd = || Error::NotPositiveDefinite {
            context: "the Gauss-Newton matrix of the estimator".into(),
        };
        match self.gn_form(w.len())? {
            GnForm::Representer => {
                // S = Zᵀ B Z + α W⁻¹ (B z_j = J_j; symmetric: the upper
                // triangle by dot products of the contiguous columns,
                // mirrored)
                let m = w.len();
                let z: Vec<&[f64]> = columns(&dv.z).collect();
                let jt: Vec<&[f64]> = columns(&dv.jt).collect();
                let reuse = reuse.and_then(|fac| match fac.gram {
                    Some(k) if fac.alpha == alpha && k.nrows() == m => Some((fac.chol, k)),
                    _ => None,
                });
                let (chol, k) = match reuse {
                    Some(x) => x,
                    None => {
                        count_dense(m * m * self.n_f / 2 + m * m * m / 3);
                        let mut k = DMatrix::zeros(m, m);
                        for i in 0..m {
                            for j in i..m {
                                let v = dot(z[i], jt[j]);
                                k[(i, j)] = v;
                                k[(j, i)] = v;
                            }
                        }
                        let mut s = k.clone();
                        for i in 0..m {
                            s[(i, i)] += alpha / w[i];
                        }
                        (jittered_cholesky(s).ok_or_else(not_spd)?, k)
                    }
                };
                let mut c =
                    DVector::from_iterator(m, jt.iter().zip(e).map(|(j, ei)| dot(j, f) - ei));
                chol.solve_mut(&mut c);
                let mut step: Vec<f64> = f.iter().map(|v| -v).collect();
                for (zi, ci) in z.iter().zip(c.iter()) {
                    step.iter_mut().zip(*zi).for_each(|(a, b)| *a += ci * b);
                }
                Ok((
                    step,
                    GnFactor {
                        chol,
                        gram: Some(k),
                        alpha,
                    },
                ))
            }
            GnForm::Primal(h) => {
                // N = Jᵀ W J + α H accumulated over the marker rows
                let reuse = reuse.filter(|fac| {
                    fac.gram.is_none()
                        && fac.alpha == alpha
                        && fac.chol.l_dirty().nrows() == self.n_f
                });
                let chol = match reuse {
                    Some(fac) => fac.chol,
                    None => primal_system(&dv.jt, w, alpha, &h).ok_or_else(not_spd)?,
                };
                let hf = DVector::from_vec(self.penalty_grad(f)?);
                let mut step = -weighted_columns(&dv.jt, w) * DVector::from_column_slice(e);
                step -= hf * alpha;
                chol.solve_mut(&mut step);
                Ok((
                    step.as_slice().to_vec(),
                    GnFactor {
                        chol,
                        gram: None,
                        alpha,
                    },
                ))
            }
        }
    }

    /// Resultant force and moment (about the base position, in the shape
    /// `q`) of the load `F`, and the `DIM × n_F` map `F → ∫ w dX`
    /// (row-major). `hf` is `H F` ([`Problem::penalty_grad`]), which for
    /// the distributed load is `B F` (23): with `r = S q`, `w = S F` and
    /// `B = ∫ Sᵀ S dX = b ⊗ I` (the scalar shape functions' Gram matrix
    /// times the identity over the components), `∫ r_i w_j dX = Σ_a q_{a,i}
    /// (B F)_{a,j}` over the slots `a` (node positions and slopes), so the
    /// moment `∫ (r − r₀) × w dX` is `Σ_a q_a × (B F)_a − r₀ × ∫ w dX`, and
    /// the force `∫ w dX` the map times `F`.
    #[allow(clippy::type_complexity)]
    pub(crate) fn resultants(
        &self,
        q: &[f64],
        f: &[f64],
        hf: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
        let d = M::Element::DIM;
        let nf = self.n_f;
        let r0 = &q[..d];
        let mut force = vec![0.0; d];
        let mut moment = vec![0.0; M::Element::MOMENT_DIM];
        match self.load() {
            LoadModel::Concentrated { .. } | LoadModel::AtSite { .. } | LoadModel::Along { .. } => {
                // F = basis θ: fw is the basis, row-major
                let basis = self.load().force_basis(d)?.unwrap_or_default();
                check_len("f", basis.ncols(), f.len())?;
                let mut fw = vec![0.0; d * nf];
                for a in 0..d {
                    for j in 0..nf {
                        fw[a * nf + j] = basis[(a, j)];
                    }
                    force[a] = dot(&fw[a * nf..(a + 1) * nf], f);
                }
                let rows = self.load().site_rows(self.robot())?;
                let at = rows.map(|r| r.position_at(q)).unwrap_or_default();
                check_len("load_model.site", d, at.len())?;
                let r: Vec<f64> = (0..d).map(|i| at[i] - r0[i]).collect();
                moment = cross(&r, &force);
                Ok((force, moment, fw))
            }
            LoadModel::Distributed => {
                check_len("hf", nf, hf.len())?;
                check_len("f", nf, f.len())?;
                let fw = self.load_map()?;
                for (i, fi) in force.iter_mut().enumerate() {
                    *fi = dot(&fw[i * nf..(i + 1) * nf], f);
                }
                // Σ_a q_a × (B F)_a over the slots (DIM-vectors)
                for (qa, ba) in q[..nf].chunks_exact(d).zip(hf.chunks_exact(d)) {
                    if d == 2 {
                        moment[0] += qa[0] * ba[1] - qa[1] * ba[0];
                    } else {
                        moment[0] += qa[1] * ba[2] - qa[2] * ba[1];
                        moment[1] += qa[2] * ba[0] - qa[0] * ba[2];
                        moment[2] += qa[0] * ba[1] - qa[1] * ba[0];
                    }
                }
                moment
                    .iter_mut()
                    .zip(cross(r0, &force))
                    .for_each(|(m, c)| *m -= c);
                Ok((force, moment, fw.clone()))
            }
        }
    }

    /// The map `F → ∫ w dX` of the distributed load (`DIM × n_F`,
    /// row-major), formed by 5-point Gauss quadrature of the shape functions
    /// at the first call and kept.
    fn load_map(&self) -> Result<&Vec<f64>> {
        if let Some(m) = self.load_map.get() {
            return Ok(m);
        }
        let d = M::Element::DIM;
        let nd = M::Element::NODE_DOFS;
        let nf = self.n_f;
        let mut fw = vec![0.0; d * nf];
        let rule = crate::quadrature::GaussRule::new(5)?;
        for (e, el) in field_rod(self.robot())?.elements().iter().enumerate() {
            let le = el.length();
            for (xi, wt) in rule.iter() {
                for (k, sk) in el.shape(xi).iter().enumerate() {
                    // slot k: node e + k/2, its position (k even) or slope
                    // (k odd)
                    let base = (e + k / 2) * nd + (k % 2) * d;
                    for i in 0..d {
                        fw[i * nf + base + i] += wt * le * sk;
                    }
                }
            }
        }
        Ok(self.load_map.get_or_init(|| fw))
    }
}

/// The factor (≤ 1) that keeps the predicted marker motion `max_i |J_i dF|`
/// within `cap` (m): a trust region against Gauss–Newton overshoots far from
/// the solution (loads under which the statics barely converge).
pub(crate) fn step_cap(dv: &Derivs, step: &[f64], cap: f64) -> f64 {
    let pred = columns(&dv.jt)
        .map(|j| dot(j, step).abs())
        .fold(0.0f64, f64::max);
    if pred > cap && pred.is_finite() {
        cap / pred
    } else {
        1.0
    }
}

/// The columns of a matrix as contiguous slices (nalgebra stores by
/// column).
pub(crate) fn columns(a: &DMatrix<f64>) -> impl Iterator<Item = &[f64]> {
    a.as_slice().chunks_exact(a.nrows().max(1)).take(a.ncols())
}

/// The cross product: scalar (as a 1-vector) in 2-D, vector in 3-D.
fn cross(a: &[f64], b: &[f64]) -> Vec<f64> {
    if a.len() == 2 {
        vec![a[0] * b[1] - a[1] * b[0]]
    } else {
        vec![
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }
}

/// The direct solution (24) for the Fig. 3 comparison: the distributed load
/// `F` that makes the observed full state `q` an equilibrium,
/// `J_QF F = −(Q_E + Q_A + known dead forces)` over the free coordinates.
/// With a clamped base `J_QF` restricted to the free rows is not square
/// (`n_free × n_q`): this returns the minimum-norm least-squares solution
/// (normal equations of the free rows, an SVD pseudo-inverse). Only for
/// comparison: it amplifies marker errors into large forces.
///
/// # Errors
/// As [`Robot::dead_force`] and [`Robot::residual`].
///
/// # Example
/// ```
/// use softrod::{scene::Scene, statics::StaticSolver, estimate::direct_solution};
/// let scene = Scene::two_section();
/// let robot = scene.robot()?;
/// let loads = scene.loads()?;
/// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
/// let f: nalgebra::DVector<f64> = direct_solution(&robot, &loads, eq.q.as_slice())?;
/// assert!(f.iter().all(|v| v.abs() < 1e-3));
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn direct_solution<E: Element>(
    robot: &Robot<E>,
    known: &Loads,
    q: &[f64],
) -> Result<DVector<f64>> {
    let dead = robot.dead_force(known)?;
    let r = robot.residual(q, dead.as_slice(), known)?; // Q without F
    let nq = robot.n_q();
    let nfree = robot.n_free();
    let b = robot.load_gram();
    // free rows of J_QF: column j = restrict(B e_j)
    let mut j = DMatrix::zeros(nfree, nq);
    for c in 0..nq {
        let mut ej = vec![0.0; nq];
        ej[c] = 1.0;
        let col = robot.restrict(&b.mul_vec(&ej)?)?;
        for (i, v) in col.iter().enumerate() {
            j[(i, c)] = *v;
        }
    }
    let rhs = DVector::from_iterator(nfree, r.iter().map(|v| -v));
    let svd = j.svd(true, true);
    let f = svd.solve(&rhs, 1e-12).map_err(|m| Error::NonFinite {
        context: format!("direct solution (24): {m}"),
    })?;
    Ok(f)
}

/// The measurements of `obs` in the operator's order (each marker's
/// position, then its tangent if observed), if its markers are those of
/// `last` but for the measured values and every value passes the checks of
/// [`ObservationOperator::new`] (`dim` components, finite, positions within
/// [`MAX_MARKER_SCALE`] robot lengths `len`, tangents of a length in
/// `(0, MAX_MARKER_SCALE]`); `None` otherwise.
fn same_markers_values(
    last: &[MarkerObservation],
    obs: &Observation,
    len: f64,
    dim: usize,
) -> Option<Vec<f64>> {
    if last.len() != obs.markers.len() {
        return None;
    }
    let far = MAX_MARKER_SCALE * len;
    let mut y = Vec::with_capacity(last.len() * 2 * dim);
    for (a, b) in last.iter().zip(&obs.markers) {
        let same = a.rod == b.rod
            && a.node == b.node
            && a.s_m == b.s_m
            && a.body == b.body
            && a.tangent.is_some() == b.tangent.is_some()
            && a.position_weight == b.position_weight
            && a.tangent_weight == b.tangent_weight;
        let position_ok = b.position_m.len() == dim
            && b.position_m.iter().all(|v| v.is_finite() && v.abs() <= far);
        if !(same && position_ok) {
            return None;
        }
        y.extend_from_slice(&b.position_m);
        if let Some(t) = &b.tangent {
            let norm = t.iter().map(|v| v * v).sum::<f64>().sqrt();
            let ok = t.len() == dim
                && t.iter().all(|v| v.is_finite())
                && norm > 0.0
                && norm <= MAX_MARKER_SCALE;
            if !ok {
                return None;
            }
            y.extend_from_slice(t);
        }
    }
    Some(y)
}
