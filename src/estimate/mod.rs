//! Motion–force estimation (Sec. III): from a few marker positions, the shape
//! `q` and the unknown external load `F` of the robot.
//!
//! # The problem (25)
//!
//! ```text
//! min_{q,F}  (A q − y)ᵀ W (A q − y) + α Fᵀ H F    s.t.  Q(F, q, P) = 0   (17)
//! ```
//!
//! - `A q` are the observed quantities: marker positions `r(X_m) = S(X_m) q`
//!   (16) at nodes or at arc coordinates, optionally tangents `r'(X_m)`;
//!   `y` the measurements, `W` diagonal weights ([`Observation`]).
//! - The unknown load enters the equilibrium as `Q_F = G F` ([`LoadModel`]):
//!   the distributed field `w(X) = S(X) F` (8) with `G = J_QF = B = ∫ Sᵀ S dX`
//!   (22), (23), or a concentrated force at a node (32)–(35) with `G = A_xᵀ`.
//!   Known loads (self-weight, a known tip mass, pressures) stay in
//!   [`Loads`], apart from `F`.
//! - The penalty (26) is `H = B` for the distributed field (`α ∫ wᵀ w dX`)
//!   and `H = I` for a concentrated force (`α |F|²`).
//!
//! # Weights and the units of `α`
//!
//! Weights are noise-whitened by default: `W = I / σ²` for positions with
//! `σ = noise_sigma_m` (so a weighted residual `(Aq − y)ᵀW(Aq − y)` of about
//! `n_ob`, the number of observed components, means "fits to the noise") and
//! `I / σ_t²` for tangents. The objective is then dimensionless, so `α` has
//! the units of `1 / (Fᵀ H F)`: m/N² for the distributed field
//! (`∫ wᵀw dX` is in N²/m), 1/N² for a concentrated force. Defaults then do not
//! depend on the robot's size or on units. (With raw SI weights `W = I` the
//! objective is in m², and a sensible `α` for the paper's robot is around
//! 1e-10–1e-8 m³/N².)
//!
//! # Choosing `α`, and what the standard deviations mean
//!
//! Leave `alpha` unset and the first observation picks it ([`AlphaRule`]);
//! the chosen `α` is kept for the following (streaming) steps.
//!
//! - `evidence` (default): read the penalty as a Gaussian prior on the load,
//!   `F ~ N(0, (αH)⁻¹)`, and the weights as the noise, `n ~ N(0, W⁻¹)`;
//!   `α` is the prior precision the observation makes most likely (the
//!   largest marginal likelihood, linearized at the estimate). The reported
//!   covariances ([`Estimate::resultant_force_cov`],
//!   [`Estimate::marker_cov`]) are that model's posterior, `(JᵀWJ + αH)⁻¹`:
//!   the spread of the noise *and* the bias the penalty puts in. Their 95 %
//!   intervals cover the true resultant at about their nominal rate for
//!   smooth loads (measured by `softrod report --only coverage`; the
//!   README's "Uncertainty" table).
//! - `discrepancy`: Morozov's principle, the weighted residual equals
//!   `n_ob`, the expected value of the residual of the true shape under the
//!   stated noise. The weighted residual grows monotonically with `α`, so a
//!   bisection in `log α` finds it.
//!
//! Markers that do not see the load (all at the clamped base) give the
//! status [`EstimateStatus::NoInformation`]: the estimate is the prior's.
//!
//! # Backends
//!
//! - [`NewtonEstimator`] ("newton"): the paper's reduced method (27)–(30),
//!   `q = q(F)` by the static solve, Gauss–Newton steps on `F`.
//! - [`SqpEstimator`] ("sqp"): (25) as a sequence of QPs in `(du, dF)` with
//!   the linearized equilibrium as equality constraints, solved by clarabel;
//!   it also takes bounds on the load ([`LoadBound`]).
//!
//! Both run on every [`EstimationModel`] (the clamped robot, every
//! structure), solve the same problem and agree at convergence.
//!
//! # Example
//! ```
//! use softrod::estimate::{Backend, EstimatorSettings, Observation};
//! use softrod::{scene::Scene, statics::StaticSolver};
//! let scene = Scene::two_section();
//! let robot = scene.robot()?;
//! let loads = scene.loads()?;
//! // the "measurement": the solved shape at the five marker nodes
//! let eq = StaticSolver::default().solve(&robot, &loads, None)?;
//! let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[4, 8, 12, 16, 20])?;
//! let settings = EstimatorSettings { alpha: Some(1.0), ..EstimatorSettings::default() };
//! let mut est = settings.build_for(&robot, &loads)?; // the backend settings.backend names
//! let e = est.step(&obs)?;
//! assert!(e.report.status.is_converged());
//! // nothing but the known loads acts: the estimated load is small
//! assert!(e.resultant_force_n.iter().all(|f| f.abs() < 1e-3));
//! # Ok::<(), softrod::Error>(())
//! ```

//!
//! # Layout
//!
//! - `problem`: the problem (25) and what it computes at a point: the load
//!   model, the objective, the marker Jacobian (28), the gradient (29) and
//!   the Gauss–Newton step (30); the direct solution (24).
//! - `triplets`: the constant matrices of the load over the free
//!   coordinates (the sqp backend's), probed.
//! - `covariance`: the covariances of an estimate.
//! - `evidence`: `α` by the evidence.
//! - `driver`: the stream of observations, `α` by the discrepancy principle,
//!   the incremental observations of a large jump.
//! - [`newton`], [`sqp`]: the two methods over the problem.
//!
//! Observations and their operator `A` are [`crate::observe`]'s; the
//! equilibrium `q(F)` is solved by the static solver's warm tracker
//! ([`crate::statics::EquilibriumTracker`]), the marker Jacobian by the
//! adjoint solves of [`crate::sensitivity`].

mod covariance;
mod driver;
mod evidence;
mod fit;
mod gn_form;
mod load_model;
mod model;
pub mod newton;
mod problem;
pub mod sqp;
mod triplets;

pub use driver::ALPHA_CONTINUATION_START;
pub use evidence::AlphaRule;
pub use fit::{FIT_QUANTILE, chi2_quantile};
pub use model::EstimationModel;
pub use newton::NewtonEstimator;
pub use problem::direct_solution;
pub use sqp::SqpEstimator;

pub use crate::observe::{MarkerObservation, Observation};
pub use crate::outcome::{EstimateCriterion, EstimateStatus};

use nalgebra::{DMatrix, DVector, SVector};
use serde::{Deserialize, Serialize};

use crate::element::ArcPoint;
use crate::error::{Error, Result, check_all_finite, check_positive};
use crate::loads::Loads;
use crate::statics::StaticSettings;

/// Which estimator runs.
///
/// # Example
/// ```
/// let b: softrod::estimate::Backend = serde_json::from_str("\"sqp\"").unwrap();
/// assert_eq!(b, softrod::estimate::Backend::Sqp);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Backend {
    /// The reduced Gauss–Newton method (27)–(30): [`NewtonEstimator`].
    #[default]
    Newton,
    /// Sequential quadratic programming on (25) with clarabel: [`SqpEstimator`].
    Sqp,
}

impl Backend {
    /// The backend's name as on the command line ("newton" or "sqp").
    pub fn name(self) -> &'static str {
        match self {
            Backend::Newton => "newton",
            Backend::Sqp => "sqp",
        }
    }
}

/// The regularization weight of the payload estimates
/// ([`crate::parallel::ParallelRobot::estimate_payload`],
/// [`crate::control::MassEstimator`]): `α |F|²` against the whitened
/// misfit, so small that the estimate of a force at a site from one marker
/// there is the exactly determined (or least-squares) one (`α |F|²` ≈
/// 1e-14 for a 100 g payload).
///
/// # Example
/// ```
/// assert!(softrod::estimate::PAYLOAD_ALPHA < 1e-9);
/// ```
pub const PAYLOAD_ALPHA: f64 = 1e-12;

/// How the unknown load is parameterized.
///
/// # Example
/// ```
/// let m: softrod::estimate::LoadModel =
///     serde_json::from_str(r#"{"kind": "concentrated", "node": 20}"#).unwrap();
/// assert_eq!(m, softrod::estimate::LoadModel::Concentrated { node: 20 });
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum LoadModel {
    /// The distributed field `w(X) = S(X) F` (8): `F` has `n_q` entries,
    /// `[w_i, w_i']` per node (N/m, N/m²), every node including the base.
    #[default]
    Distributed,
    /// A force `F` (N, `DIM` entries) at a node (32)–(35).
    Concentrated {
        /// The node (1 ..= number of elements; the base carries no load).
        node: usize,
    },
    /// A force `F` (N, `DIM` entries) at a site of any model (32)–(35):
    /// a rod point, or a rigid body's reference point (the parallel
    /// robot's payload at its platform's centre, `{"kind": "body",
    /// "body": 0}`). `Concentrated { node }` is this at the node's site.
    AtSite {
        /// Where the force acts.
        site: crate::site::Site,
    },
    /// A force of unknown magnitude along a known direction at a site:
    /// one parameter, the force's component along the unit direction (N).
    /// A hanging mass pulls along gravity (`direction` = g), so its weight
    /// is one unknown fitted to the measured coordinates by least squares,
    /// and a model error along a stiff direction is not read as a force
    /// there.
    Along {
        /// Where the force acts.
        site: crate::site::Site,
        /// The force's direction (world axes; any length > 0, used as the
        /// unit vector; a planar model's third component must be 0).
        direction: [f64; 3],
    },
}

impl LoadModel {
    /// Whether the load is a force at one point (`DIM` parameters, the
    /// penalty `α |F|²`).
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::LoadModel;
    /// assert!(LoadModel::Concentrated { node: 3 }.is_concentrated());
    /// assert!(!LoadModel::Distributed.is_concentrated());
    /// ```
    pub fn is_concentrated(&self) -> bool {
        !matches!(self, LoadModel::Distributed)
    }

    /// The `DIM × n_params` map from a concentrated load's parameters to
    /// its force at the site (`None` for the distributed field): the
    /// identity for a force, the unit direction's column for
    /// [`LoadModel::Along`] (whose direction must be finite and not zero,
    /// with no component beyond `dim`).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `estimator.load_model.direction`.
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::LoadModel;
    /// use softrod::site::Site;
    /// let weight = LoadModel::Along { site: Site::Rod { rod: 0, s_m: 0.24 }, direction: [0.0, -9.81, 0.0] };
    /// let b = weight.force_basis(2)?.unwrap();
    /// assert_eq!((b.nrows(), b.ncols()), (2, 1));
    /// assert!((b[(1, 0)] + 1.0).abs() < 1e-15);
    /// assert_eq!(LoadModel::Concentrated { node: 3 }.force_basis(2)?.unwrap(), nalgebra::DMatrix::identity(2, 2));
    /// for bad in [[0.0; 3], [0.0, -9.81, 1.0], [f64::NAN, 1.0, 0.0]] {
    ///     let e = LoadModel::Along { site: Site::Body { body: 0 }, direction: bad }.force_basis(2).unwrap_err();
    ///     assert_eq!(e.field(), Some("estimator.load_model.direction"));
    /// }
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn force_basis(&self, dim: usize) -> Result<Option<DMatrix<f64>>> {
        match *self {
            LoadModel::Distributed => Ok(None),
            LoadModel::Concentrated { .. } | LoadModel::AtSite { .. } => {
                Ok(Some(DMatrix::identity(dim, dim)))
            }
            LoadModel::Along { direction, .. } => {
                let bad = |why: &str| {
                    Error::invalid(
                        "estimator.load_model.direction",
                        format!("{direction:?}"),
                        why.to_string(),
                    )
                };
                if direction.iter().any(|v| !v.is_finite()) {
                    return Err(bad("must be finite"));
                }
                if direction[dim.min(3)..].iter().any(|v| *v != 0.0) {
                    return Err(bad("a planar model's direction has no third component"));
                }
                let norm = direction[..dim.min(3)]
                    .iter()
                    .map(|v| v * v)
                    .sum::<f64>()
                    .sqrt();
                if !(norm > 0.0 && norm.is_finite()) {
                    return Err(bad("must not be zero"));
                }
                Ok(Some(DMatrix::from_iterator(
                    dim,
                    1,
                    direction[..dim.min(3)].iter().map(|v| v / norm),
                )))
            }
        }
    }
}

/// The frame in which a [`LoadBound`] reads the load.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum BoundFrame {
    /// World axes `(x, y)`.
    #[default]
    World,
    /// The robot's local frame at the point: `(tangent, normal)`, the normal
    /// the tangent turned by +90°. The frame is taken at the current iterate
    /// (lagged, not differentiated); at convergence it is the estimate's.
    Local,
}

/// A linear inequality on the estimated load at one point:
/// `min ≤ d · w(s) ≤ max`, `d` in the axes of `frame` (SQP backend only).
/// For a concentrated load, `w(s)` reads the force (N) and `s_m` is ignored.
///
/// # Example
/// A contact that can only push the robot along its local normal:
/// ```
/// use softrod::estimate::{BoundFrame, LoadBound};
/// let b = LoadBound { s_m: 0.16, frame: BoundFrame::Local, direction: vec![0.0, 1.0],
///                     min_n_per_m: Some(0.0), max_n_per_m: None };
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadBound {
    /// Undeformed arc coordinate (m).
    pub s_m: f64,
    /// Axes of `direction`.
    #[serde(default)]
    pub frame: BoundFrame,
    /// Direction `d` (`DIM` entries, need not be unit).
    pub direction: Vec<f64>,
    /// Lower bound of `d · w` (N/m; N for a force at a node or a site), if
    /// any.
    #[serde(default)]
    pub min_n_per_m: Option<f64>,
    /// Upper bound of `d · w` (N/m; N for a force at a node or a site), if
    /// any.
    #[serde(default)]
    pub max_n_per_m: Option<f64>,
}

impl LoadBound {
    /// [`LoadBound::direction`] as a `D`-vector (`D` the robot's dimension).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `direction` if it has another
    /// number of components.
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{BoundFrame, LoadBound};
    /// let b = LoadBound { s_m: 0.16, frame: BoundFrame::Local, direction: vec![0.0, 1.0],
    ///                     min_n_per_m: Some(0.0), max_n_per_m: None };
    /// assert_eq!(b.direction_vector::<2>()?, nalgebra::Vector2::y());
    /// assert!(b.direction_vector::<3>().is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn direction_vector<const D: usize>(&self) -> Result<nalgebra::SVector<f64, D>> {
        crate::numeric::fixed("direction", &self.direction)
    }
}

/// Settings of the estimators; every field has a documented default. They
/// serialize, so a scene can carry them (`solver.estimator`).
///
/// # Example
/// ```
/// let s: softrod::estimate::EstimatorSettings =
///     serde_json::from_str(r#"{"backend": "sqp", "alpha": 1e-2, "noise_sigma_m": 5e-5}"#).unwrap();
/// s.validate().unwrap();
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct EstimatorSettings {
    /// Backend (default `newton`).
    pub backend: Backend,
    /// Parameterization of the unknown load (default `distributed`).
    pub load_model: LoadModel,
    /// Regularization weight `α` (units: see the module docs; m/N² for the
    /// distributed field with the default whitened weights). `None`
    /// (default): chosen on the first observation by `alpha_rule`.
    pub alpha: Option<f64>,
    /// How an unset `alpha` is chosen (default: the largest evidence).
    pub alpha_rule: AlphaRule,
    /// Standard deviation of each marker position component (m); the default
    /// weights are `1/σ²` and the covariances are stated for this noise
    /// (default 1e-5 m = 0.01 mm).
    pub noise_sigma_m: f64,
    /// Standard deviation of each observed tangent component (dimensionless,
    /// default 1e-3).
    pub tangent_sigma: f64,
    /// Outer iterations per observation (default 100; at most
    /// [`MAX_ESTIMATOR_ITERATIONS`]: each is a linearization, a static
    /// solve or a QP).
    pub max_iterations: usize,
    /// Convergence, tight: the predicted decrease of the objective below
    /// `tolerance × max(objective, n_ob)` (default 1e-15; a round-off floor
    /// also ends it). The Newton backend also stops after a step whose
    /// predicted successor decrease, `dec²/dec_prev`, is below `1e-3 ×` the
    /// threshold (taken without confirming it by another linearization).
    pub tolerance: f64,
    /// Convergence, statistical (default 0.1; 0 turns it off and leaves
    /// `tolerance` alone to decide): the estimation also
    /// stops when the next
    /// Gauss–Newton step `dF`, taken with the exact derivatives at the
    /// current estimate, would move it by less than this fraction `κ` of its
    /// own standard deviation. The test is on the step's predicted decrease
    /// `dec = dFᵀ N dF ≤ κ²` (`N = JᵀWJ + αH`, the Gauss–Newton Hessian (30)
    /// over 2, the posterior precision of `F` for the stated noise). Then
    /// every linear function `aᵀF` of the load moves by at most `κ` times its
    /// posterior standard deviation `√(aᵀN⁻¹a)`, and the predicted markers
    /// by at most `κ σ` together (`|J dF|_W ≤ κ`): no observation can tell
    /// the answer from the exact optimum. The error the early stop adds to
    /// the estimate's own (noise-driven) error grows that by a factor of at
    /// most `√(1 + κ²)`: 0.5 % at κ = 0.1. For two estimates to agree to
    /// round-off (comparisons between backends), leave it at 0.
    pub statistical_tolerance: f64,
    /// Largest marker jump (m) between successive observations handled in
    /// one go; larger jumps are split into a sequence of intermediate
    /// observations (a stream's first observation, which has none before
    /// it, is taken in one go); also the trust radius of one step's
    /// predicted node motion (the sqp backend's starting radius, which
    /// grows while its full steps hold) (default 0.02 m).
    pub max_observation_jump_m: f64,
    /// Inequalities on the load (SQP backend only; default none).
    pub bounds: Vec<LoadBound>,
    /// Static solver settings for the fallback solves.
    pub statics: StaticSettings,
}

impl Default for EstimatorSettings {
    fn default() -> Self {
        EstimatorSettings {
            backend: Backend::Newton,
            load_model: LoadModel::Distributed,
            alpha: None,
            alpha_rule: AlphaRule::Evidence,
            noise_sigma_m: 1e-5,
            tangent_sigma: 1e-3,
            max_iterations: 100,
            tolerance: 1e-15,
            statistical_tolerance: 0.1,
            max_observation_jump_m: 0.02,
            bounds: Vec::new(),
            statics: StaticSettings::default(),
        }
    }
}

impl EstimatorSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field.
    pub fn validate(&self) -> Result<()> {
        if let Some(a) = self.alpha {
            if a == 0.0 {
                return Err(Error::invalid(
                    "estimator.alpha",
                    a,
                    "must be > 0: with alpha = 0 the markers do not determine the load \
                     (a distributed load has n_q parameters, more than the observed \
                     components); give a small alpha, or none for the discrepancy principle",
                ));
            }
            check_positive("estimator.alpha", a)?;
        }
        check_positive("estimator.noise_sigma_m", self.noise_sigma_m)?;
        check_positive("estimator.tangent_sigma", self.tangent_sigma)?;
        check_positive("estimator.tolerance", self.tolerance)?;
        crate::error::check_finite(
            "estimator.statistical_tolerance",
            self.statistical_tolerance,
        )?;
        if self.statistical_tolerance < 0.0 {
            return Err(Error::invalid(
                "estimator.statistical_tolerance",
                self.statistical_tolerance,
                "must be >= 0 (0 turns the statistical test off)",
            ));
        }
        check_positive(
            "estimator.max_observation_jump_m",
            self.max_observation_jump_m,
        )?;
        if self.max_iterations == 0 {
            return Err(Error::invalid(
                "estimator.max_iterations",
                0,
                "must be >= 1",
            ));
        }
        crate::error::check_at_most(
            "estimator.max_iterations",
            self.max_iterations,
            MAX_ESTIMATOR_ITERATIONS,
        )?;
        for (i, b) in self.bounds.iter().enumerate() {
            let p = |f: &str| format!("estimator.bounds[{i}].{f}");
            crate::error::check_finite(&p("s_m"), b.s_m)?;
            check_all_finite(&p("direction"), &b.direction)?;
            if b.direction.iter().all(|d| *d == 0.0) {
                return Err(Error::invalid(p("direction"), "0", "must not be zero"));
            }
            for v in [b.min_n_per_m, b.max_n_per_m].into_iter().flatten() {
                crate::error::check_finite(&p("min_n_per_m/max_n_per_m"), v)?;
            }
            if let (Some(lo), Some(hi)) = (b.min_n_per_m, b.max_n_per_m)
                && lo > hi
            {
                return Err(Error::invalid(
                    p("max_n_per_m"),
                    hi,
                    "must be >= min_n_per_m",
                ));
            }
        }
        self.statics.validate("estimator.statics")
    }
}

/// The largest [`EstimatorSettings::max_iterations`] accepted: it bounds
/// the work of one estimate (an iteration of the newton backend is a
/// static solve, of the sqp backend a QP).
pub const MAX_ESTIMATOR_ITERATIONS: usize = 10_000;

/// What an estimation did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateReport {
    /// The backend that ran.
    pub backend: Backend,
    /// How the estimation ended (of the intermediate observation that
    /// stopped it, if one did).
    pub status: EstimateStatus,
    /// Outer iterations (Gauss–Newton steps or QPs) of the solves at the
    /// chosen `α`, summed over the intermediate observations (and, for the
    /// Newton backend, the full-space iterations of a far start its solve
    /// took, see [`EstimateReport::far_start`]). The solves of an `α`
    /// search are counted in [`EstimateReport::alpha_search`]: after one,
    /// the solve at the chosen `α` starts from the search's last and may
    /// take 0 iterations.
    pub iterations: usize,
    /// Intermediate observations used (1: the observation was taken directly).
    pub sub_steps: usize,
    /// Final objective `(Aq − y)ᵀW(Aq − y) + α FᵀHF` (dimensionless with
    /// whitened weights).
    pub objective: f64,
    /// Final weighted residual `(Aq − y)ᵀW(Aq − y)`.
    pub weighted_residual: f64,
    /// Number of observed components `n_ob`.
    pub n_observations: usize,
    /// Norm of the reduced gradient (29) of the objective with respect to
    /// `F` at the last linearization: the estimate itself, or, when the
    /// Newton backend took its last step unconfirmed (the decrease predicted
    /// after it far below the tolerance, see [`NewtonEstimator`]), the
    /// iterate before that step.
    pub gradient_norm: f64,
    /// Final equilibrium residual `|Q|_2` (N).
    pub equilibrium_residual_n: f64,
    /// The regularization weight used.
    pub alpha: f64,
    /// Wall time of the step (s).
    pub wall_time_s: f64,
    /// Tangent factorizations and solved right-hand sides of the step
    /// (the `α` choice of a first step included): its cost, counted
    /// instead of timed.
    #[serde(default)]
    pub linear_work: crate::linsolve::LinearWork,
    /// The Newton backend's far start in this step, if a solve took it
    /// (see [`FarStart`]); `None` for the sqp backend and for a step that
    /// did not need it.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub far_start: Option<FarStart>,
    /// The choice of `α` this step made, if it made one (see
    /// [`AlphaSearch`]): its solves and their iterations are not in
    /// [`EstimateReport::iterations`], which counts the solves at the chosen
    /// `α` only; `None` when `α` was given or chosen on an earlier step.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub alpha_search: Option<AlphaSearch>,
}

/// The Newton backend's far start in one step: while a stream has no
/// estimate yet, a reduced solve whose step the trust region cuts (or that
/// starts from zero load) continues with the sqp backend's full-space
/// iterations over `(q, F)`, and the reduced iteration resumes at their
/// equilibrium (see [`NewtonEstimator`]). Counted over every solve of the
/// step, the `α` search's included.
///
/// # Example
/// ```
/// use softrod::estimate::{Backend, EstimatorSettings, Observation};
/// use softrod::loads::PointForce;
/// use softrod::{scene::Scene, statics::StaticSolver};
/// let scene = Scene::two_section();
/// let (robot, mut loads) = (scene.robot()?, scene.loads()?);
/// let known = loads.clone();
/// loads.point_forces.push(PointForce { s_m: 0.24, force_n: vec![0.0, -0.3] });
/// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
/// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[5, 10, 15, 20])?.with_noise(1e-5, 1);
/// let settings = EstimatorSettings { alpha: Some(1e-2), ..Default::default() };
/// let e = settings.build_for(&robot, &known)?.step(&obs)?;
/// // a cold estimate from zero load takes the far start at once
/// let far = e.report.far_start.expect("far start");
/// assert!(far.solves >= 1 && far.iterations >= 1 && far.iterations <= e.report.iterations);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct FarStart {
    /// Solves of the step that took it.
    pub solves: usize,
    /// Full-space iterations (QPs) those solves took, in all (when
    /// `answer`, the returned solve's are part of
    /// [`EstimateReport::iterations`]).
    pub iterations: usize,
    /// Solves through it that did not converge and were repeated without
    /// it.
    pub repeated_without: usize,
    /// Whether the solve of the returned estimate went through it.
    pub answer: bool,
}

/// The search for `α` in one step, when the step chose it: a stream's
/// first observation with `alpha` unset, or a later frame whose answer at
/// the earlier `α` failed the fit test (then chosen again). The search
/// solves the estimation problem at a sequence of `α` (each solve starting
/// from the last converged one); the solve at the chosen `α` then starts
/// from the search's last, and may need no iteration of its own.
///
/// # Example
/// ```
/// use softrod::estimate::{AlphaRule, EstimatorSettings, Observation};
/// use softrod::loads::PointForce;
/// use softrod::{scene::Scene, statics::StaticSolver};
/// let scene = Scene::two_section();
/// let (robot, mut loads) = (scene.robot()?, scene.loads()?);
/// let known = loads.clone();
/// loads.point_forces.push(PointForce { s_m: 0.24, force_n: vec![0.0, -0.3] });
/// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
/// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[5, 10, 15, 20])?.with_noise(1e-5, 1);
/// let mut est = EstimatorSettings::default().build_for(&robot, &known)?;
/// // the first observation chooses α by the default rule
/// let search = est.step(&obs)?.report.alpha_search.expect("an α search");
/// assert_eq!(search.rule, AlphaRule::Evidence);
/// assert!(search.solves >= 2 && search.iterations >= 1);
/// // the next frame keeps that α: no search
/// assert!(est.step(&obs)?.report.alpha_search.is_none());
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct AlphaSearch {
    /// The rule that chose `α` (the settings' `alpha_rule`).
    pub rule: AlphaRule,
    /// Solves of the estimation problem the search ran (one per `α` tried).
    pub solves: usize,
    /// Outer iterations of those solves that returned, in all, counted as
    /// [`EstimateReport::iterations`] counts a solve's (Gauss–Newton steps
    /// or QPs; a Newton far start's full-space iterations included).
    pub iterations: usize,
}

impl std::fmt::Display for EstimateReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} ({}); {} iterations, objective {:.6e} (weighted residual {:.4e} for {} components), |grad| {:.3e}, alpha {:.3e}, {:.1} us",
            self.status,
            self.backend.name(),
            self.iterations,
            self.objective,
            self.weighted_residual,
            self.n_observations,
            self.gradient_norm,
            self.alpha,
            self.wall_time_s * 1e6,
        )?;
        if let Some(a) = &self.alpha_search {
            write!(
                f,
                "; alpha chosen by the {} rule: {} solve(s), {} iterations",
                a.rule.name(),
                a.solves,
                a.iterations
            )?;
        }
        if let Some(fs) = &self.far_start {
            write!(
                f,
                "; far start: {} solve(s), {} full-space iterations{}",
                fs.solves,
                fs.iterations,
                if fs.answer {
                    ", the answer's included"
                } else {
                    ""
                }
            )?;
        }
        Ok(())
    }
}

/// The result of one estimation.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// All coordinates of the estimated shape (m, dimensionless slopes).
    pub q: DVector<f64>,
    /// The load parameters `F` (distributed: `n_q` entries laid out like
    /// the node coordinates, `[w, w']` first in each node's, N/m and N/m²,
    /// the full 3-D element's `r_Y, r_Z` slots zero; concentrated: the
    /// force, N).
    pub f: DVector<f64>,
    /// The parameterization of `f`.
    pub load_model: LoadModel,
    /// Resultant force of the estimated load, `∫ w dX` or the force (N).
    pub resultant_force_n: DVector<f64>,
    /// Moment of the estimated load about the base position in the
    /// estimated (deformed) shape, `∫ (r − r_0) × w dX` (N·m).
    pub resultant_moment_nm: DVector<f64>,
    /// Marker residuals `A q − y` in observation order (m; tangents dimensionless).
    pub marker_residuals: DVector<f64>,
    /// The stated marker noise the covariances are for (m).
    pub noise_sigma_m: f64,
    /// What the estimator did.
    pub report: EstimateReport,
    node_s: Vec<f64>,
    dim: usize,
    node_dofs: usize,
    /// The covariances ([`Estimate::resultant_force_cov`],
    /// [`Estimate::marker_cov`], [`Estimate::cov_factor`]), formed on
    /// request.
    cov: covariance::LazyCovariances,
}

/// Fewer determined load directions than this
/// ([`Estimate::determined_directions`]) make an estimate weakly informed
/// ([`Estimate::weakly_informed`]).
pub const WEAKLY_INFORMED_DIRECTIONS: f64 = 0.5;

/// A larger fraction of the resultant's prior variance left by the markers
/// in some direction than this ([`Estimate::resultant_prior_fraction`])
/// makes an estimate weakly informed ([`Estimate::weakly_informed`]): the
/// markers then remove less than a fifth of what the prior allows.
pub const WEAKLY_INFORMED_PRIOR_FRACTION: f64 = 0.8;

/// Why an estimate is weakly informed ([`Estimate::weak_information`]):
/// its reported resultant standard deviations are then (mostly) the width
/// of a prior the evidence fitted to what the markers see, not knowledge
/// of the load.
///
/// # Example
/// ```
/// use softrod::estimate::WeakInformation;
/// let w = WeakInformation::ResultantFromPrior { prior_fraction: 0.93, direction: vec![0.0, 1.0] };
/// assert_eq!(serde_json::to_value(&w).unwrap()["reason"], "resultant_from_prior");
/// assert!(w.to_string().contains("93 %") && w.to_string().contains("(0.00, 1.00)"));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(tag = "reason", rename_all = "snake_case")]
#[non_exhaustive]
pub enum WeakInformation {
    /// The markers barely see the load: fewer than
    /// [`WEAKLY_INFORMED_DIRECTIONS`] load directions determined.
    FewDirections {
        /// [`Estimate::determined_directions`].
        directions: f64,
    },
    /// The markers see the load but not (some direction of) its
    /// resultant: they leave more than [`WEAKLY_INFORMED_PRIOR_FRACTION`]
    /// of the resultant's prior variance. The load the markers cannot see
    /// (near the clamp, or alternating along the arc so that its effects
    /// cancel) then sets the resultant, and the prior the evidence fitted
    /// to the visible load says how large it is.
    ResultantFromPrior {
        /// [`Estimate::resultant_prior_fraction`].
        prior_fraction: f64,
        /// The direction of the resultant it is for (unit, world axes;
        /// empty when the markers see nothing of the load).
        direction: Vec<f64>,
    },
}

impl std::fmt::Display for WeakInformation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            WeakInformation::FewDirections { directions } => write!(
                f,
                "the markers determine {directions:.3} load directions (fewer than {WEAKLY_INFORMED_DIRECTIONS}): they barely see the load; the estimate stays near zero and `force_std_n` is the width of a prior fitted to markers that show no load, not knowledge of the load"
            ),
            WeakInformation::ResultantFromPrior {
                prior_fraction,
                direction,
            } => write!(
                f,
                "the markers leave {:.0} % of the resultant's prior variance in the direction ({}) (more than {:.0} %): they do not see that part of the resultant, and `force_std_n` there is the width of a prior fitted to the load they see, not knowledge of the resultant",
                100.0 * prior_fraction,
                direction
                    .iter()
                    .map(|v| format!("{v:.2}"))
                    .collect::<Vec<_>>()
                    .join(", "),
                100.0 * WEAKLY_INFORMED_PRIOR_FRACTION
            ),
        }
    }
}

impl Estimate {
    /// Whether the reported resultant σ is (mostly) a prior's width rather
    /// than knowledge of the load: [`Estimate::weak_information`] gives a
    /// reason. The estimate is then close to the prior's (zero load) in the
    /// directions the markers do not determine, and its standard
    /// deviations are the width of a prior the evidence fitted to what the
    /// markers show: they say that these markers cannot tell that part of
    /// the load from zero, not that it is known to be zero. (Markers that
    /// see nothing at all end as [`EstimateStatus::NoInformation`].)
    ///
    /// # Example
    /// A tip marker that moves less than its noise under any load the
    /// prior allows:
    /// ```
    /// use softrod::estimate::{EstimatorSettings, Observation};
    /// use softrod::{scene::Scene, statics::StaticSolver};
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[20])?;
    /// let settings = EstimatorSettings { noise_sigma_m: 1e-5, ..Default::default() };
    /// let e = settings.build_for(&robot, &loads)?.step(&obs.with_noise(1e-5, 1))?;
    /// println!("{} directions, weakly informed: {}", e.determined_directions(), e.weakly_informed());
    /// assert_eq!(e.weakly_informed(), e.weak_information().is_some());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn weakly_informed(&self) -> bool {
        self.weak_information().is_some()
    }

    /// Why the estimate is weakly informed ([`Estimate::weakly_informed`]),
    /// or `None`: fewer than [`WEAKLY_INFORMED_DIRECTIONS`] load directions
    /// determined ([`WeakInformation::FewDirections`]), else more than
    /// [`WEAKLY_INFORMED_PRIOR_FRACTION`] of the resultant's prior variance
    /// left in some direction ([`WeakInformation::ResultantFromPrior`]).
    ///
    /// # Example
    /// See [`Estimate::resultant_prior_fraction`].
    pub fn weak_information(&self) -> Option<WeakInformation> {
        let directions = self.determined_directions();
        if directions < WEAKLY_INFORMED_DIRECTIONS {
            return Some(WeakInformation::FewDirections { directions });
        }
        let (prior_fraction, direction) = self.cov.resultant_prior_fraction();
        (*prior_fraction > WEAKLY_INFORMED_PRIOR_FRACTION).then(|| {
            WeakInformation::ResultantFromPrior {
                prior_fraction: *prior_fraction,
                direction: direction.clone(),
            }
        })
    }

    /// How much of the resultant the markers leave to the prior: the
    /// largest ratio, over directions `u`, of the resultant's posterior
    /// variance to its prior variance at the estimate's `α`, `uᵀ Σ u / uᵀ P
    /// u` with `P = C (αH)⁻¹ Cᵀ` and `Σ = C (JᵀWJ + αH)⁻¹ Cᵀ` (`C` the map
    /// to the resultant; `Σ` at the one `α`, not averaged over it like
    /// [`Estimate::resultant_force_cov`]). Between 0 (the markers fix the
    /// resultant) and 1 (they say nothing of it in some direction; also
    /// when they see nothing of the load); `NaN` if it cannot be formed.
    /// Formed on the first request, like the covariances.
    ///
    /// # Example
    /// Five markers of a robot bent by a tip force see the resultant; one
    /// marker 3 mm from the clamp does not:
    /// ```
    /// use softrod::estimate::{EstimatorSettings, Observation, WeakInformation};
    /// use softrod::loads::PointForce;
    /// use softrod::{scene::Scene, statics::StaticSolver};
    /// let scene = Scene::two_section();
    /// let (robot, known) = (scene.robot()?, scene.loads()?);
    /// let mut loads = known.clone();
    /// loads.point_forces.push(PointForce { s_m: 0.24, force_n: vec![0.0, -0.1] });
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let settings = EstimatorSettings { noise_sigma_m: 1e-5, ..Default::default() };
    /// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[4, 8, 12, 16, 20])?;
    /// let e = settings.build_for(&robot, &known)?.step(&obs.with_noise(1e-5, 1))?;
    /// assert!(e.resultant_prior_fraction() < 0.5 && e.weak_information().is_none());
    /// let near = Observation::of_nodes(&robot, eq.q.as_slice(), &[1])?;
    /// let e = settings.build_for(&robot, &known)?.step(&near.with_noise(1e-5, 1))?;
    /// assert!(e.weakly_informed());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn resultant_prior_fraction(&self) -> f64 {
        self.cov.resultant_prior_fraction().0
    }

    /// How many load directions the markers determine at the chosen `α`:
    /// the evidence's effective number of parameters `γ` (see
    /// [`AlphaRule`]; between 0, markers that see nothing of the load, and
    /// the number of observed components; `NaN` if it could not be
    /// computed). Formed on the first request, like the covariances. See
    /// [`Estimate::weakly_informed`].
    ///
    /// ```
    /// use softrod::estimate::{EstimatorSettings, Observation};
    /// use softrod::{scene::Scene, statics::StaticSolver};
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[5, 10, 15, 20])?;
    /// let settings = EstimatorSettings { noise_sigma_m: 1e-4, ..Default::default() };
    /// let e = settings.build_for(&robot, &loads)?.step(&obs.with_noise(1e-4, 1))?;
    /// assert!(e.determined_directions() >= 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn determined_directions(&self) -> f64 {
        self.cov.determined_directions()
    }

    /// The estimated load per undeformed length at arc coordinate `s` (N/m,
    /// world axes, `DIM` entries), `w(s) = S(s) F` (8). Zero for a
    /// concentrated load (see [`Estimate::f`]) and outside the robot; see
    /// [`Estimate::load_vector_at`] for a fixed-size vector that refuses an
    /// arc position off the robot.
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{EstimatorSettings, Observation};
    /// use softrod::{scene::Scene, statics::StaticSolver};
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[10, 20])?.with_noise(1e-5, 1);
    /// let e = EstimatorSettings::default().build_for(&robot, &loads)?.step(&obs)?;
    /// let w: nalgebra::DVector<f64> = e.load_at(0.12);
    /// assert_eq!(w.len(), 2);
    /// assert_eq!(e.load_at(1.0).norm(), 0.0); // off the robot
    /// let samples = e.sample_load(5);
    /// assert_eq!((samples.len(), samples[4].0), (5, 0.24));
    /// let nodes = e.node_positions::<2>()?;
    /// assert_eq!(nodes.len(), robot.n_nodes());
    /// assert!((nodes[20] - eq.shape(&robot)?.tip_pose()?.position_m.coords).norm() < 1e-3);
    /// assert!(e.node_positions::<3>().is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn load_at(&self, s: f64) -> DVector<f64> {
        let d = self.dim;
        let mut w = DVector::zeros(d);
        if self.load_model != LoadModel::Distributed || self.node_s.len() < 2 {
            return w;
        }
        // w(s) = S(s) F (8): the cable field F at the point (laid out like
        // the node coordinates: [w, w'] first in each node's numbers)
        if let Some(p) = ArcPoint::locate(&self.node_s, s)
            && p.node_value_into(self.f.as_slice(), self.node_dofs, w.as_mut_slice())
                .is_err()
        {
            w.iter_mut().for_each(|v| *v = f64::NAN);
        }
        w
    }

    /// `w` sampled at `n` evenly spaced arc coordinates from base to tip:
    /// `(s (m), w (N/m))`.
    ///
    /// # Example
    /// See [`Estimate::load_at`].
    pub fn sample_load(&self, n: usize) -> Vec<(f64, DVector<f64>)> {
        let total = self.node_s.last().copied().unwrap_or(0.0);
        (0..n)
            .map(|i| {
                let s = if n > 1 {
                    total * i as f64 / (n - 1) as f64
                } else {
                    0.0
                };
                (s, self.load_at(s))
            })
            .collect()
    }

    /// Node positions of the estimated shape (m) as `D`-vectors.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `q` if the robot has another
    /// dimension than `D`.
    ///
    /// # Example
    /// See [`Estimate::load_at`].
    pub fn node_positions<const D: usize>(&self) -> Result<Vec<SVector<f64, D>>> {
        crate::error::check_len("q", D, self.dim)?;
        Ok(self
            .q
            .as_slice()
            .chunks(self.node_dofs.max(1))
            .map(|c| SVector::from_fn(|i, _| c.get(i).copied().unwrap_or(0.0)))
            .collect())
    }

    /// Undeformed arc coordinates of the nodes (m).
    pub fn node_arc(&self) -> &[f64] {
        &self.node_s
    }

    /// The estimate if it converged, else [`Error::EstimateNotConverged`]
    /// with its status: for callers to whom a last iterate is no answer.
    ///
    /// # Errors
    /// [`Error::EstimateNotConverged`] when `report.status` is not converged.
    ///
    /// # Example
    /// ```
    /// use softrod::estimate::{Backend, EstimatorSettings, Observation};
    /// use softrod::{scene::Scene, statics::StaticSolver, Error};
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let eq = StaticSolver::default().solve(&robot, &loads, None)?;
    /// let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[4, 8, 12, 16, 20])?;
    /// // one Gauss-Newton step is not enough at a small alpha
    /// let settings = EstimatorSettings { alpha: Some(1e-2), max_iterations: 1, ..Default::default() };
    /// let mut est = settings.build_for(&robot, &loads)?;
    /// let e = est.step(&obs.with_noise(1e-4, 3))?;
    /// assert!(!e.report.status.is_converged()); // the last iterate, with its status
    /// assert!(matches!(e.converged(), Err(Error::EstimateNotConverged { .. })));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn converged(self) -> Result<Self> {
        if self.report.status.is_converged() {
            Ok(self)
        } else {
            Err(Error::EstimateNotConverged {
                status: self.report.status,
                iterations: self.report.iterations,
            })
        }
    }
}

/// An estimator: one observation in, one estimate out, keeping its warm
/// start (the last `F*` and shape) between calls.
///
/// # Example
/// See the [module documentation](self).
pub trait Estimator<L = Loads> {
    /// Estimates shape and load from `observation`, warm-started from the
    /// previous step. A large jump from the previous observation is taken
    /// through intermediate observations (`max_observation_jump_m`).
    ///
    /// # Outcome
    /// `Ok` whenever the estimator has an iterate to give: its
    /// `report.status` says whether it converged. One that stopped short
    /// (the iteration limit, a failed line search, an SQP subproblem clarabel
    /// did not solve) returns its last iterate, an equilibrium `(q, F)` of
    /// the model, with its covariances, because a control loop needs the last
    /// good estimate; the estimator's warm start stays at the last converged
    /// estimate. The caller decides: [`Estimate::converged`] turns a
    /// non-converged estimate into [`Error::EstimateNotConverged`].
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] / [`Error::DimensionMismatch`] for a
    /// malformed observation; when a computation breaks down before there is
    /// an iterate to return: [`Error::NotConverged`] (a static solve the
    /// estimator needs fails), [`Error::Singular`],
    /// [`Error::NotPositiveDefinite`] (the Newton backend's Gauss–Newton
    /// matrix), [`Error::NonFinite`].
    fn step(&mut self, observation: &Observation) -> Result<Estimate>;
    /// The backend.
    fn backend(&self) -> Backend;
    /// The regularization weight in use (`None` until chosen).
    fn alpha(&self) -> Option<f64>;
    /// Forgets the warm start (and an automatically chosen `α`).
    fn reset(&mut self);
    /// Replaces the known loads (a controller's commanded pressures, a
    /// payload it was told about), keeping the warm start `(F, q)` and `α`:
    /// the next step starts from the last estimate, re-solved under the new
    /// loads, instead of from scratch.
    ///
    /// # Errors
    /// As [`crate::assembly::Robot::validate_loads`]; on an error the estimator is unchanged.
    fn set_known_loads(&mut self, known: L) -> Result<()>;
}

// (last: the public-API snapshot reads a file up to its first test item)
#[cfg(test)]
mod gn_tests;
#[cfg(test)]
mod marker_work_tests;
