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
//!   [`Loads`](crate::loads::Loads), apart from `F`.
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
//! # Choosing `α`: the discrepancy principle
//!
//! Leave `alpha` unset and the first observation picks `α` so that the
//! weighted residual equals `n_ob` (Morozov's discrepancy principle): with
//! whitened weights that is the expected value of the residual of the true
//! shape under the stated noise. A smaller residual would fit the noise (an
//! `n_q`-parameter load explains any 10 numbers exactly and amplifies noise
//! into large forces: Fig. 3); a larger one throws information away. The
//! weighted residual grows monotonically with `α`, so a bisection in `log α`
//! finds it. The chosen `α` is kept for the following (streaming) steps.
//!
//! # Backends
//!
//! - [`NewtonEstimator`] ("newton"): the paper's reduced method (27)–(30),
//!   `q = q(F)` by the static solve, Gauss–Newton steps on `F`.
//! - [`SqpEstimator`] ("sqp"): (25) as a sequence of QPs in `(du, dF)` with
//!   the linearized equilibrium as equality constraints, solved by clarabel;
//!   it also takes bounds on `w` ([`LoadBound`]).
//!
//! Both solve the same problem and agree at convergence.
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
//! let obs = Observation::at_nodes(&robot, &eq.q, &[4, 8, 12, 16, 20]);
//! let settings = EstimatorSettings { alpha: Some(1.0), ..EstimatorSettings::default() };
//! let mut est = Backend::Newton.build(robot, loads, settings)?;
//! let e = est.step(&obs)?;
//! assert!(e.report.status.is_converged());
//! // nothing but the known loads acts: the estimated load is small
//! assert!(e.resultant_force_n.iter().all(|f| f.abs() < 1e-3));
//! # Ok::<(), softrod::Error>(())
//! ```

// Dense index loops read like the equations here.
#![allow(clippy::needless_range_loop, clippy::type_complexity)]

pub mod newton;
pub mod sqp;

pub use newton::NewtonEstimator;
pub use sqp::SqpEstimator;

use std::time::Instant;

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::element::{hermite, Element, PlanarCable};
use crate::error::{check_all_finite, check_len, check_positive, Error, Result};
use crate::linsolve::{BandedLu, BandedMatrix};
use crate::loads::{Loads, PointForce};
use crate::statics::{StaticSettings, StaticSolver};

pub use crate::outcome::{EstimateCriterion, EstimateStatus};

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
    /// Builds the estimator of this backend for a planar robot with known
    /// loads `known` (self-weight comes from the robot; pressures, known
    /// line loads, point forces and moments from `known`).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for invalid settings (or bounds given to
    /// the Newton backend); the errors of [`Robot::validate_loads`].
    ///
    /// # Example
    /// See the [module documentation](self).
    pub fn build(
        self,
        robot: Robot<PlanarCable>,
        known: Loads,
        settings: EstimatorSettings,
    ) -> Result<Box<dyn Estimator>> {
        Ok(match self {
            Backend::Newton => Box::new(NewtonEstimator::new(robot, known, settings)?),
            Backend::Sqp => Box::new(SqpEstimator::new(robot, known, settings)?),
        })
    }

    /// The backend's name as on the command line ("newton" or "sqp").
    pub fn name(self) -> &'static str {
        match self {
            Backend::Newton => "newton",
            Backend::Sqp => "sqp",
        }
    }
}

/// How the unknown load is parameterized.
///
/// # Example
/// ```
/// let m: softrod::estimate::LoadModel =
///     serde_json::from_str(r#"{"kind": "concentrated", "node": 20}"#).unwrap();
/// assert_eq!(m, softrod::estimate::LoadModel::Concentrated { node: 20 });
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
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
    /// Lower bound of `d · w` (N/m), if any.
    #[serde(default)]
    pub min_n_per_m: Option<f64>,
    /// Upper bound of `d · w` (N/m), if any.
    #[serde(default)]
    pub max_n_per_m: Option<f64>,
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
    /// (default): chosen on the first observation by the discrepancy principle.
    pub alpha: Option<f64>,
    /// Standard deviation of each marker position component (m); the default
    /// weights are `1/σ²` and the covariances are stated for this noise
    /// (default 1e-5 m = 0.01 mm).
    pub noise_sigma_m: f64,
    /// Standard deviation of each observed tangent component (dimensionless,
    /// default 1e-3).
    pub tangent_sigma: f64,
    /// Outer iterations per observation (default 100).
    pub max_iterations: usize,
    /// Convergence: the predicted decrease of the objective below
    /// `tolerance × max(objective, n_ob)` (default 1e-15; a round-off floor
    /// also ends it). The Newton backend also stops after a step whose
    /// predicted successor decrease, `dec²/dec_prev`, is below `1e-3 ×` that
    /// (taken without confirming it by another linearization).
    pub tolerance: f64,
    /// Largest marker jump (m) between successive observations handled in
    /// one go; larger jumps are split into a sequence of intermediate
    /// observations; also the trust radius of one step's predicted node motion
    /// (default 0.02 m).
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
            noise_sigma_m: 1e-5,
            tangent_sigma: 1e-3,
            max_iterations: 100,
            tolerance: 1e-15,
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
            if let (Some(lo), Some(hi)) = (b.min_n_per_m, b.max_n_per_m) {
                if lo > hi {
                    return Err(Error::invalid(
                        p("max_n_per_m"),
                        hi,
                        "must be >= min_n_per_m",
                    ));
                }
            }
        }
        self.statics.validate()
    }
}

/// One marker measurement.
///
/// # Example
/// ```
/// let m = softrod::estimate::MarkerObservation::at_node(20, vec![0.2, 0.05]);
/// assert_eq!(m.node, Some(20));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MarkerObservation {
    /// Node index, or
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub node: Option<usize>,
    /// undeformed arc coordinate (m): exactly one of the two.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub s_m: Option<f64>,
    /// Measured position (m, world axes).
    pub position_m: Vec<f64>,
    /// Measured tangent `r'` (dimensionless), if observed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangent: Option<Vec<f64>>,
    /// Weights of the position components (1/m²); default `1/σ²`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_weight: Option<Vec<f64>>,
    /// Weights of the tangent components (dimensionless); default `1/σ_t²`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangent_weight: Option<Vec<f64>>,
}

impl MarkerObservation {
    /// A position-only marker at a node with default weights.
    pub fn at_node(node: usize, position_m: Vec<f64>) -> Self {
        MarkerObservation {
            node: Some(node),
            s_m: None,
            position_m,
            tangent: None,
            position_weight: None,
            tangent_weight: None,
        }
    }

    /// A position-only marker at arc coordinate `s_m` with default weights.
    pub fn at_arc(s_m: f64, position_m: Vec<f64>) -> Self {
        MarkerObservation {
            node: None,
            s_m: Some(s_m),
            position_m,
            tangent: None,
            position_weight: None,
            tangent_weight: None,
        }
    }
}

/// One observation: the markers measured at one instant. This is also the
/// format of a markers file (`softrod estimate --markers FILE`):
/// `{"markers": [{"node": 4, "position_m": [0.05, 0.01]}, {"s_m": 0.24,
/// "position_m": [...], "tangent": [...]}, ...]}`.
///
/// # Example
/// ```
/// let o: softrod::estimate::Observation = serde_json::from_str(
///     r#"{"markers": [{"node": 20, "position_m": [0.2, 0.05]}]}"#).unwrap();
/// assert_eq!(o.n_components(), 2);
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Observation {
    /// The markers.
    pub markers: Vec<MarkerObservation>,
}

impl Observation {
    /// The exact positions of the configuration `q` at the given nodes (a
    /// noise-free synthetic observation); nodes beyond `q` are skipped.
    pub fn at_nodes<E: Element>(_robot: &Robot<E>, q: &[f64], nodes: &[usize]) -> Self {
        let nd = E::NODE_DOFS;
        let d = E::DIM;
        Observation {
            markers: nodes
                .iter()
                .filter(|&&n| (n + 1) * nd <= q.len())
                .map(|&n| MarkerObservation::at_node(n, q[n * nd..n * nd + d].to_vec()))
                .collect(),
        }
    }

    /// Number of observed scalar components `n_ob`.
    pub fn n_components(&self) -> usize {
        self.markers
            .iter()
            .map(|m| m.position_m.len() + m.tangent.as_ref().map_or(0, |t| t.len()))
            .sum()
    }

    /// Adds seeded Gaussian noise of standard deviation `sigma_m` to every
    /// position component (a deterministic generator: the same seed gives the
    /// same noise).
    pub fn with_noise(mut self, sigma_m: f64, seed: u64) -> Self {
        let mut rng = Gaussian::new(seed);
        for m in &mut self.markers {
            for p in &mut m.position_m {
                *p += sigma_m * rng.sample();
            }
        }
        self
    }
}

/// A small deterministic normal generator (SplitMix64 + Box–Muller), for
/// synthetic observations.
#[derive(Debug, Clone)]
pub struct Gaussian {
    state: u64,
    spare: Option<f64>,
}

impl Gaussian {
    /// A generator with seed `seed`.
    pub fn new(seed: u64) -> Self {
        Gaussian {
            state: seed ^ 0x9E37_79B9_7F4A_7C15,
            spare: None,
        }
    }
    fn uniform(&mut self) -> f64 {
        self.state = self.state.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.state;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        ((z >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }
    /// One standard normal sample.
    pub fn sample(&mut self) -> f64 {
        if let Some(s) = self.spare.take() {
            return s;
        }
        let (u, v) = (self.uniform(), self.uniform());
        let r = (-2.0 * u.ln()).sqrt();
        let t = 2.0 * std::f64::consts::PI * v;
        self.spare = Some(r * t.sin());
        r * t.cos()
    }
}

/// What an estimation did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EstimateReport {
    /// The backend that ran.
    pub backend: Backend,
    /// How the estimation ended (of the intermediate observation that
    /// stopped it, if one did).
    pub status: EstimateStatus,
    /// Outer iterations (Gauss–Newton steps or QPs), summed over the
    /// intermediate observations.
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
        )
    }
}

/// The result of one estimation.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// All coordinates of the estimated shape (m, dimensionless slopes).
    pub q: Vec<f64>,
    /// The load parameters `F` (distributed: `n_q` entries, N/m and N/m²;
    /// concentrated: the force, N).
    pub f: Vec<f64>,
    /// The parameterization of `f`.
    pub load_model: LoadModel,
    /// Resultant force of the estimated load, `∫ w dX` or the force (N).
    pub resultant_force_n: Vec<f64>,
    /// Moment of the estimated load about the base position in the
    /// estimated (deformed) shape, `∫ (r − r_0) × w dX` (N·m).
    pub resultant_moment_nm: Vec<f64>,
    /// Covariance of the resultant force for the stated marker noise (N², row-major).
    pub resultant_force_cov: Vec<f64>,
    /// Marker residuals `A q − y` in observation order (m; tangents dimensionless).
    pub marker_residuals: Vec<f64>,
    /// Covariance factor `L` (`n_F × n_ob`, row-major): `Cov(F) = L Lᵀ`, see
    /// [`Estimate::covariance_f`]. Like the other covariances it is taken at
    /// the last linearization (see [`EstimateReport::gradient_norm`]; after
    /// an unconfirmed last step the two points differ by that step, whose
    /// predicted decrease is below `1e-3 tolerance`: the covariances then
    /// differ by about the square root of that, relatively).
    pub cov_factor: Vec<f64>,
    /// Covariance of the estimated marker-space shape `A q` (`n_ob × n_ob`,
    /// row-major; m²).
    pub marker_cov: Vec<f64>,
    /// The stated marker noise the covariances are for (m).
    pub noise_sigma_m: f64,
    /// What the estimator did.
    pub report: EstimateReport,
    node_s: Vec<f64>,
    dim: usize,
    n_ob: usize,
}

impl Estimate {
    /// The estimated load per undeformed length at arc coordinate `s` (N/m,
    /// world axes), `w(s) = S(s) F` (8). Zero for a concentrated load
    /// (see [`Estimate::f`]) and outside the robot.
    pub fn load_at(&self, s: f64) -> Vec<f64> {
        let d = self.dim;
        let mut w = vec![0.0; d];
        if self.load_model != LoadModel::Distributed || self.node_s.len() < 2 {
            return w;
        }
        let total = self.node_s[self.node_s.len() - 1];
        if !(s >= -1e-12 * total && s <= total * (1.0 + 1e-12)) {
            return w;
        }
        let n_el = self.node_s.len() - 1;
        let e = self
            .node_s
            .partition_point(|&x| x <= s)
            .saturating_sub(1)
            .min(n_el - 1);
        let le = self.node_s[e + 1] - self.node_s[e];
        let xi = ((s - self.node_s[e]) / le).clamp(0.0, 1.0);
        let (sh, _, _) = hermite(xi, le);
        let nd = 2 * d;
        for (k, sk) in sh.iter().enumerate() {
            for (i, wi) in w.iter_mut().enumerate() {
                *wi += sk * self.f[e * nd + k * d + i];
            }
        }
        w
    }

    /// `w` sampled at `n` evenly spaced arc coordinates from base to tip:
    /// `(s (m), w (N/m))`.
    pub fn sample_load(&self, n: usize) -> Vec<(f64, Vec<f64>)> {
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

    /// `Cov(F) = L Lᵀ` (`n_F × n_F`, row-major) for the stated marker noise:
    /// the covariance of the Gauss–Newton-linearized estimator,
    /// `F̂ ≈ (JᵀWJ + αH)⁻¹ JᵀW y`, with `J` the marker Jacobian `∂(Aq)/∂F`
    /// and `Cov(y) = σ² I`.
    pub fn covariance_f(&self) -> Vec<f64> {
        let n = self.f.len();
        let m = self.n_ob;
        let l = &self.cov_factor;
        let mut c = vec![0.0; n * n];
        for i in 0..n {
            for j in i..n {
                let v: f64 = (0..m).map(|k| l[i * m + k] * l[j * m + k]).sum();
                c[i * n + j] = v;
                c[j * n + i] = v;
            }
        }
        c
    }

    /// Standard deviations of the entries of `F` (square roots of the
    /// diagonal of [`Estimate::covariance_f`]).
    pub fn std_f(&self) -> Vec<f64> {
        let m = self.n_ob;
        (0..self.f.len())
            .map(|i| {
                self.cov_factor[i * m..(i + 1) * m]
                    .iter()
                    .map(|v| v * v)
                    .sum::<f64>()
                    .sqrt()
            })
            .collect()
    }

    /// Node positions of the estimated shape (m).
    pub fn node_positions(&self) -> Vec<Vec<f64>> {
        self.q
            .chunks(2 * self.dim)
            .map(|c| c[..self.dim].to_vec())
            .collect()
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
    /// let obs = Observation::at_nodes(&robot, &eq.q, &[4, 8, 12, 16, 20]);
    /// // one Gauss-Newton step is not enough at a small alpha
    /// let settings = EstimatorSettings { alpha: Some(1e-2), max_iterations: 1, ..Default::default() };
    /// let mut est = Backend::Newton.build(robot, loads, settings)?;
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

/// Implements [`Estimator`] for a backend type with a `core` field and a
/// `solve_one` method (the two backends differ only in those).
macro_rules! impl_estimator {
    ($ty:ident, $backend:expr) => {
        impl<E: Element + 'static> Estimator for $ty<E> {
            fn step(&mut self, observation: &Observation) -> Result<Estimate> {
                run_step(
                    self,
                    observation,
                    $backend,
                    |s| &mut s.core,
                    Self::solve_one,
                )
            }

            fn backend(&self) -> Backend {
                $backend
            }

            fn alpha(&self) -> Option<f64> {
                self.core.alpha
            }

            fn reset(&mut self) {
                self.core.warm = None;
                self.core.lu_cache = None;
                self.core.eq_state = None;
                self.core.derivs_cache = None;
                self.core.alpha = self.core.settings.alpha;
            }
        }
    };
}
pub(crate) use impl_estimator;

/// An estimator: one observation in, one estimate out, keeping its warm
/// start (the last `F*` and shape) between calls.
///
/// # Example
/// See the [module documentation](self).
pub trait Estimator {
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
}

// ---------------------------------------------------------------------------
// The shared core: observation operator, equilibrium, Jacobians.

/// One observed scalar: `Σ_k w_k q_e[k·DIM + comp]`, element `e`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct ObsRow {
    pub e: usize,
    pub w: [f64; 4],
    pub comp: usize,
}

/// The observation operator `A`, the measurements `y`, the weights `W`.
#[derive(Debug, Clone)]
pub(crate) struct ObsOp {
    pub rows: Vec<ObsRow>,
    pub y: Vec<f64>,
    pub wt: Vec<f64>,
}

impl ObsOp {
    pub fn n(&self) -> usize {
        self.rows.len()
    }
    /// `A q` (one row).
    pub fn apply_row(&self, i: usize, q: &[f64], nd: usize, d: usize) -> f64 {
        let r = &self.rows[i];
        (0..4).map(|k| r.w[k] * q[r.e * nd + k * d + r.comp]).sum()
    }
    /// `A q − y`.
    pub fn residual(&self, q: &[f64], nd: usize, d: usize) -> Vec<f64> {
        (0..self.n())
            .map(|i| self.apply_row(i, q, nd, d) - self.y[i])
            .collect()
    }
    /// `eᵀ W e`.
    pub fn weighted(&self, e: &[f64]) -> f64 {
        e.iter().zip(&self.wt).map(|(e, w)| w * e * e).sum()
    }
    /// Row `i` as a dense vector over all `n_q` coordinates.
    pub fn dense_row(&self, i: usize, nq: usize, nd: usize, d: usize) -> Vec<f64> {
        let r = &self.rows[i];
        let mut a = vec![0.0; nq];
        for k in 0..4 {
            a[r.e * nd + k * d + r.comp] += r.w[k];
        }
        a
    }
    /// The same operator with measurements `y`.
    pub fn with_y(&self, y: Vec<f64>) -> Self {
        ObsOp {
            rows: self.rows.clone(),
            y,
            wt: self.wt.clone(),
        }
    }
}

/// The state a backend keeps between steps.
#[derive(Debug, Clone)]
pub(crate) struct Warm {
    pub f: Vec<f64>,
    pub q: Vec<f64>,
    pub y: Vec<f64>,
}

/// What the backends share: the robot, the known loads, the load model.
#[derive(Debug, Clone)]
pub(crate) struct Core<E: Element> {
    pub robot: Robot<E>,
    pub known: Loads,
    /// Dead force of the known loads (n_q).
    pub dead_known: Vec<f64>,
    pub settings: EstimatorSettings,
    pub n_f: usize,
    pub kmat: BandedMatrix,
    pub alpha: Option<f64>,
    pub warm: Option<Warm>,
    /// The last factorization of `K` and the shape it was taken at.
    pub lu_cache: Option<(Vec<f64>, BandedLu)>,
    /// The last solved equilibrium: its load, shape and residual.
    pub eq_state: Option<EqState>,
    /// The derivatives at the last converged estimate's shape for its
    /// observation rows: a warm step's first iteration starts there.
    pub derivs_cache: Option<(Vec<f64>, Vec<ObsRow>, Derivs)>,
}

/// A solved equilibrium [`Core::equilibrium_opt`] remembers: asked again at
/// the same `(F, q)` it returns at once, and a trial load `F'` from the same
/// shape starts from `Q(q, F') = Q(q, F) + Mᵀ G (F' − F)` (the unknown load
/// enters linearly) instead of a new residual evaluation.
#[derive(Debug, Clone)]
pub(crate) struct EqState {
    f: Vec<f64>,
    q: Vec<f64>,
    r: Vec<f64>,
    residual_n: f64,
}

/// The solved equilibrium at some `F`: configuration and the factored tangent.
pub(crate) struct Equil {
    pub q: Vec<f64>,
    pub lu: BandedLu,
    pub residual_n: f64,
}

/// The Cholesky factor of a Gauss–Newton system ([`Core::gn_solve`]).
pub(crate) struct GnFactor(SmallCholesky);

/// `A = L Lᵀ` of a small dense symmetric positive definite matrix
/// (row-major `L`; the Gauss–Newton systems are `n_ob × n_ob` or
/// `n_F × n_F` with a concentrated load).
pub(crate) struct SmallCholesky {
    m: usize,
    l: Vec<f64>,
}

impl SmallCholesky {
    /// The factor of `a` (row-major `m × m`, symmetric), with a diagonal
    /// jitter of 1e-14 … 1e-10 of the largest diagonal entry if the plain
    /// factorization fails (nearly redundant markers); `None` if that does
    /// not help either.
    fn jittered(a: Vec<f64>, m: usize) -> Option<Self> {
        let dmax = (0..m).fold(0.0f64, |x, i| x.max(a[i * m + i].abs()));
        for jitter in [0.0, 1e-14, 1e-12, 1e-10] {
            let mut l = a.clone();
            for i in 0..m {
                l[i * m + i] += jitter * dmax;
            }
            if Self::factor_in_place(&mut l, m) {
                return Some(SmallCholesky { m, l });
            }
        }
        None
    }

    /// Cholesky in place (lower triangle; the upper is zeroed). False if a
    /// pivot is not positive or not finite.
    fn factor_in_place(l: &mut [f64], m: usize) -> bool {
        for j in 0..m {
            let mut d = l[j * m + j];
            for k in 0..j {
                d -= l[j * m + k] * l[j * m + k];
            }
            if !(d > 0.0 && d.is_finite()) {
                return false;
            }
            let d = d.sqrt();
            l[j * m + j] = d;
            for i in j + 1..m {
                let mut s = l[i * m + j];
                for k in 0..j {
                    s -= l[i * m + k] * l[j * m + k];
                }
                l[i * m + j] = s / d;
                l[j * m + i] = 0.0;
            }
        }
        true
    }

    /// Solves `A x = b` in place.
    fn solve(&self, b: &mut [f64]) {
        let (m, l) = (self.m, &self.l);
        for i in 0..m {
            let mut s = b[i];
            for k in 0..i {
                s -= l[i * m + k] * b[k];
            }
            b[i] = s / l[i * m + i];
        }
        for i in (0..m).rev() {
            let mut s = b[i];
            for k in i + 1..m {
                s -= l[k * m + i] * b[k];
            }
            b[i] = s / l[i * m + i];
        }
    }

    /// `A⁻¹` (row-major).
    fn inverse(&self) -> Vec<f64> {
        let m = self.m;
        let mut inv = vec![0.0; m * m];
        let mut col = vec![0.0; m];
        for j in 0..m {
            col.iter_mut()
                .enumerate()
                .for_each(|(i, v)| *v = f64::from(u8::from(i == j)));
            self.solve(&mut col);
            for i in 0..m {
                inv[i * m + j] = col[i];
            }
        }
        inv
    }
}

/// Derivatives at an equilibrium for an observation.
#[derive(Debug, Clone)]
pub(crate) struct Derivs {
    /// Adjoint fields `z_i = M K⁻¹ Mᵀ a_iᵀ` (n_ob × n_q, row i = z_i).
    pub z: Vec<Vec<f64>>,
    /// Marker Jacobian rows `J_i = Gᵀ z_i` (n_ob × n_F).
    pub jm: Vec<Vec<f64>>,
}

impl<E: Element> Core<E> {
    pub fn new(robot: Robot<E>, known: Loads, settings: EstimatorSettings) -> Result<Self> {
        settings.validate()?;
        let dead_known = robot.dead_force(&known)?;
        let n_f = match settings.load_model {
            LoadModel::Distributed => robot.n_q(),
            LoadModel::Concentrated { node } => {
                if node == 0 || node >= robot.n_nodes() {
                    return Err(Error::invalid(
                        "estimator.load_model.node",
                        node,
                        format!("must be a free node, 1..={}", robot.n_nodes() - 1),
                    ));
                }
                E::DIM
            }
        };
        for (i, b) in settings.bounds.iter().enumerate() {
            check_len(
                &format!("estimator.bounds[{i}].direction"),
                E::DIM,
                b.direction.len(),
            )?;
            if settings.load_model == LoadModel::Distributed {
                robot.locate(&format!("estimator.bounds[{i}].s_m"), b.s_m)?;
            }
        }
        let nd = E::NODE_DOFS;
        Ok(Core {
            alpha: settings.alpha,
            kmat: BandedMatrix::zeros(robot.n_free(), 2 * nd - 1, 2 * nd - 1),
            robot,
            known,
            dead_known,
            settings,
            n_f,
            warm: None,
            lu_cache: None,
            eq_state: None,
            derivs_cache: None,
        })
    }

    /// Builds the observation operator.
    pub fn obs_op(&self, obs: &Observation) -> Result<ObsOp> {
        let d = E::DIM;
        let robot = &self.robot;
        let mut op = ObsOp {
            rows: Vec::new(),
            y: Vec::new(),
            wt: Vec::new(),
        };
        if obs.markers.is_empty() {
            return Err(Error::invalid(
                "observation.markers",
                "[]",
                "needs at least one marker",
            ));
        }
        let pw = 1.0 / (self.settings.noise_sigma_m * self.settings.noise_sigma_m);
        let tw = 1.0 / (self.settings.tangent_sigma * self.settings.tangent_sigma);
        let mut seen: Vec<f64> = Vec::with_capacity(obs.markers.len());
        for (i, m) in obs.markers.iter().enumerate() {
            let name = |f: &str| format!("observation.markers[{i}].{f}");
            let s = match (m.node, m.s_m) {
                (Some(n), None) => {
                    crate::error::check_index(&name("node"), n, robot.n_nodes())?;
                    robot.node_arc()[n]
                }
                (None, Some(s)) => s,
                _ => {
                    return Err(Error::invalid(
                        format!("observation.markers[{i}]"),
                        "",
                        "give exactly one of `node` and `s_m`",
                    ))
                }
            };
            let (e, xi) = robot.locate(&name("s_m"), s)?;
            if seen
                .iter()
                .any(|t: &f64| (t - s).abs() <= 1e-9 * robot.length())
            {
                return Err(Error::invalid(
                    format!("observation.markers[{i}]"),
                    s,
                    "duplicates another marker's position",
                ));
            }
            seen.push(s);
            let le = robot.elements()[e].length();
            let (sh, dsh, _) = hermite(xi, le);
            check_len(&name("position_m"), d, m.position_m.len())?;
            check_all_finite(&name("position_m"), &m.position_m)?;
            let weights = |w: &Option<Vec<f64>>, field: &str, default: f64| -> Result<Vec<f64>> {
                match w {
                    None => Ok(vec![default; d]),
                    Some(w) => {
                        check_len(&name(field), d, w.len())?;
                        for (k, v) in w.iter().enumerate() {
                            check_positive(&format!("{}[{k}]", name(field)), *v)?;
                        }
                        Ok(w.clone())
                    }
                }
            };
            let wp = weights(&m.position_weight, "position_weight", pw)?;
            for c in 0..d {
                op.rows.push(ObsRow { e, w: sh, comp: c });
                op.y.push(m.position_m[c]);
                op.wt.push(wp[c]);
            }
            if let Some(t) = &m.tangent {
                check_len(&name("tangent"), d, t.len())?;
                check_all_finite(&name("tangent"), t)?;
                let wtan = weights(&m.tangent_weight, "tangent_weight", tw)?;
                for c in 0..d {
                    op.rows.push(ObsRow { e, w: dsh, comp: c });
                    op.y.push(t[c]);
                    op.wt.push(wtan[c]);
                }
            }
        }
        Ok(op)
    }

    /// `G F` over all coordinates (N).
    pub fn gen_force(&self, f: &[f64]) -> Result<Vec<f64>> {
        match self.settings.load_model {
            LoadModel::Distributed => self.robot.apply_load_gram(f),
            LoadModel::Concentrated { node } => {
                let nd = E::NODE_DOFS;
                let mut g = vec![0.0; self.robot.n_q()];
                g[node * nd..node * nd + E::DIM].copy_from_slice(f);
                Ok(g)
            }
        }
    }

    /// `Gᵀ v` (`v` over all coordinates).
    pub fn gen_force_t(&self, v: &[f64]) -> Result<Vec<f64>> {
        match self.settings.load_model {
            LoadModel::Distributed => self.robot.apply_load_gram(v),
            LoadModel::Concentrated { node } => {
                let nd = E::NODE_DOFS;
                Ok(v[node * nd..node * nd + E::DIM].to_vec())
            }
        }
    }

    /// `H F`.
    pub fn penalty_grad(&self, f: &[f64]) -> Result<Vec<f64>> {
        match self.settings.load_model {
            LoadModel::Distributed => self.robot.apply_load_gram(f),
            LoadModel::Concentrated { .. } => Ok(f.to_vec()),
        }
    }

    /// `Fᵀ H F`.
    pub fn penalty(&self, f: &[f64]) -> Result<f64> {
        Ok(self
            .penalty_grad(f)?
            .iter()
            .zip(f)
            .map(|(a, b)| a * b)
            .sum())
    }

    /// The dead force with the unknown load `F` (n_q).
    pub fn dead_with(&self, f: &[f64]) -> Result<Vec<f64>> {
        let mut dead = self.gen_force(f)?;
        dead.iter_mut()
            .zip(&self.dead_known)
            .for_each(|(a, b)| *a += b);
        Ok(dead)
    }

    /// The known loads plus the unknown load `F`, as [`Loads`].
    pub fn loads_with(&self, f: &[f64]) -> Loads {
        let mut loads = self.known.clone();
        match self.settings.load_model {
            LoadModel::Distributed => {
                if loads.distributed_f.is_empty() {
                    loads.distributed_f = f.to_vec();
                } else {
                    loads
                        .distributed_f
                        .iter_mut()
                        .zip(f)
                        .for_each(|(a, b)| *a += b);
                }
            }
            LoadModel::Concentrated { node } => loads.point_forces.push(PointForce {
                s_m: self.robot.node_arc()[node],
                force_n: f.to_vec(),
            }),
        }
        loads
    }

    /// Factors the tangent at `q`: `L D Lᵀ` of the Jacobi-scaled tangent
    /// (it is symmetric, and positive definite near a stable equilibrium),
    /// the pivoted LU if it is not positive definite.
    pub fn factor(&mut self, q: &[f64]) -> Result<BandedLu> {
        self.robot.tangent_into(q, &self.known, &mut self.kmat)?;
        debug_assert!(self.kmat.is_symmetric());
        self.kmat.factor_scaled_symmetric(0.0, "tangent stiffness")
    }

    /// The residual `Q` over the free coordinates at `(q, F)`.
    pub fn residual(&self, q: &[f64], f: &[f64]) -> Result<Vec<f64>> {
        let dead = self.dead_with(f)?;
        self.robot.residual(q, &dead, &self.known)
    }

    /// One plain Newton (or, with old factors, chord) step at `q` with the
    /// factors `lu` for the residual `r` at `q` (computed by the caller):
    /// the step is applied unless it is not finite, longer than a quarter
    /// of the robot, or not shorter than `limit` (m). Returns the step's
    /// size (m) if applied. `du` (`n_free`) and `dq` (`n_q`) are scratch.
    #[allow(clippy::too_many_arguments)]
    fn plain_step(
        &self,
        q: &mut [f64],
        lu: &BandedLu,
        r: &[f64],
        du: &mut [f64],
        dq: &mut [f64],
        limit: f64,
    ) -> Result<Option<f64>> {
        du.copy_from_slice(r);
        lu.solve_in_place(du)?;
        let step = du.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if !step.is_finite() || step > 0.25 * self.robot.length() || step > limit {
            return Ok(None);
        }
        self.robot.expand_step_into(du, dq)?;
        q.iter_mut().zip(dq.iter()).for_each(|(a, b)| *a += b);
        Ok(Some(step))
    }

    /// Solves the equilibrium at `F` from `q0`: a few plain Newton steps
    /// (fast for warm starts), else the globalized [`StaticSolver`].
    pub fn equilibrium(&mut self, f: &[f64], q0: &[f64]) -> Result<Equil> {
        self.equilibrium_opt(f, q0, true)
    }

    /// As [`Core::equilibrium`]; without `fallback` a failure of the plain
    /// Newton steps is an error at once (cheap, for line-search trials).
    ///
    /// Warm starts take chord (modified Newton) steps with the cached
    /// factorization: a few residuals, then one fresh factorization at the
    /// solution for exact derivatives (kept for the next call). Each
    /// converged solve ends with a step below `1e-10 L`.
    pub fn equilibrium_opt(&mut self, f: &[f64], q0: &[f64], fallback: bool) -> Result<Equil> {
        // asked again at the last solution (a warm start): nothing to solve.
        // The cached factors may be those of a point up to 1e-8 L away (a
        // last Gauss–Newton step keeps them, see Core::equilibrium_chord):
        // the derivatives they give differ by about 1e-7 relative, which the
        // next Gauss–Newton step absorbs.
        if let (Some(st), Some((q_lu, lu))) = (&self.eq_state, &self.lu_cache) {
            let near = q_lu
                .iter()
                .zip(q0)
                .all(|(a, b)| (a - b).abs() <= 1e-8 * self.robot.length());
            if st.f == f && st.q == q0 && near {
                return Ok(Equil {
                    q: q0.to_vec(),
                    lu: lu.clone(),
                    residual_n: st.residual_n,
                });
            }
        }
        let dead = self.dead_with(f)?;
        let n = self.robot.n_free();
        let len = self.robot.length();
        let mut r = vec![0.0; n];
        let mut du = vec![0.0; n];
        let mut dq = vec![0.0; self.robot.n_q()];
        // the residual at q0 from the remembered one, if q0 is its shape
        let known_residual = self.residual_from_state(f, q0, &mut r)?;
        if let Some((q_lu, lu)) = self.lu_cache.take() {
            let mut q = q0.to_vec();
            let mut prev = f64::INFINITY;
            let mut done = false;
            let mut moved = false;
            for it in 0..12 {
                if it > 0 || !known_residual {
                    self.robot.residual_into(&q, &dead, &self.known, &mut r)?;
                }
                let Some(step) = self.plain_step(&mut q, &lu, &r, &mut du, &mut dq, 0.5 * prev)?
                else {
                    break;
                };
                prev = step;
                if step <= 1e-10 * len {
                    done = true;
                    break;
                }
                moved = true;
            }
            if done {
                // the cached factors are exact if q has not left their point
                let same = !moved && q_lu.iter().zip(q0).all(|(a, b)| a == b);
                let lu = if same {
                    self.robot.residual_into(&q, &dead, &self.known, &mut r)?;
                    lu
                } else {
                    // fresh factors at the solution, with its residual
                    self.robot.residual_and_tangent_into(
                        &q,
                        &dead,
                        &self.known,
                        &mut r,
                        &mut self.kmat,
                    )?;
                    self.kmat
                        .factor_scaled_symmetric(0.0, "tangent stiffness")?
                };
                return Ok(self.solved(f, q, lu, r));
            }
            self.lu_cache = Some((q_lu, lu));
        }
        let mut q = q0.to_vec();
        let mut prev = f64::INFINITY;
        for _ in 0..12 {
            // Newton: residual and tangent at q in one pass
            self.robot
                .residual_and_tangent_into(&q, &dead, &self.known, &mut r, &mut self.kmat)?;
            let lu = match self.kmat.factor_scaled_symmetric(0.0, "tangent stiffness") {
                Ok(lu) => lu,
                Err(_) => break,
            };
            let Some(step) = self.plain_step(&mut q, &lu, &r, &mut du, &mut dq, 0.9 * prev)? else {
                break;
            };
            prev = step;
            if step <= 1e-10 * len {
                self.robot.residual_into(&q, &dead, &self.known, &mut r)?;
                return Ok(self.solved(f, q, lu, r));
            }
        }
        if !fallback {
            return Err(Error::NonFinite {
                context: "plain Newton steps of the equilibrium did not converge".into(),
            });
        }
        // fallback: the globalized static solver
        let solver = StaticSolver::new(self.settings.statics.clone())?;
        let loads = self.loads_with(f);
        let eq = solver.solve(&self.robot, &loads, Some(q0))?;
        self.robot
            .residual_and_tangent_into(&eq.q, &dead, &self.known, &mut r, &mut self.kmat)?;
        let lu = self
            .kmat
            .factor_scaled_symmetric(0.0, "tangent stiffness")?;
        let mut out = self.solved(f, eq.q, lu, r);
        out.residual_n = eq.report.residual_norm_n;
        Ok(out)
    }

    /// The equilibrium at `F` from `q0` by chord steps with the cached
    /// factorization only, keeping that factorization (no refactorization
    /// at the solution): for a last, tiny Gauss–Newton step. `None` (and no
    /// change) if there is no cached factorization or the steps do not
    /// converge below `1e-10 L`; else the shape and its residual norm.
    pub fn equilibrium_chord(&mut self, f: &[f64], q0: &[f64]) -> Result<Option<(Vec<f64>, f64)>> {
        let Some((q_lu, lu)) = self.lu_cache.take() else {
            return Ok(None);
        };
        let dead = self.dead_with(f)?;
        let n = self.robot.n_free();
        let len = self.robot.length();
        let mut r = vec![0.0; n];
        let mut du = vec![0.0; n];
        let mut dq = vec![0.0; self.robot.n_q()];
        let known_residual = self.residual_from_state(f, q0, &mut r)?;
        let mut q = q0.to_vec();
        let mut prev = f64::INFINITY;
        let mut done = false;
        for it in 0..12 {
            if it > 0 || !known_residual {
                self.robot.residual_into(&q, &dead, &self.known, &mut r)?;
            }
            let Some(step) = self.plain_step(&mut q, &lu, &r, &mut du, &mut dq, 0.5 * prev)? else {
                break;
            };
            prev = step;
            if step <= 1e-10 * len {
                done = true;
                break;
            }
        }
        self.lu_cache = Some((q_lu, lu));
        if !done {
            return Ok(None);
        }
        self.robot.residual_into(&q, &dead, &self.known, &mut r)?;
        let residual_n = norm2(&r);
        self.eq_state = Some(EqState {
            f: f.to_vec(),
            q: q.clone(),
            r,
            residual_n,
        });
        Ok(Some((q, residual_n)))
    }

    /// `Q(q0, F)` into `r` from the remembered equilibrium if `q0` is its
    /// shape (`Q(q, F) = Q(q, F_s) + Mᵀ G (F − F_s)`); false otherwise.
    fn residual_from_state(&self, f: &[f64], q0: &[f64], r: &mut [f64]) -> Result<bool> {
        match &self.eq_state {
            Some(st) if st.q == q0 && st.f.len() == f.len() => {
                let df: Vec<f64> = f.iter().zip(&st.f).map(|(a, b)| a - b).collect();
                let gdf = self.gen_force(&df)?;
                self.robot.restrict_into(&gdf, r)?;
                r.iter_mut().zip(&st.r).for_each(|(a, b)| *a += b);
                Ok(true)
            }
            _ => Ok(false),
        }
    }

    /// Records a solved equilibrium (`r` its residual, `lu` the factors
    /// at `q`) in the caches and returns it.
    fn solved(&mut self, f: &[f64], q: Vec<f64>, lu: BandedLu, r: Vec<f64>) -> Equil {
        let residual_n = norm2(&r);
        self.lu_cache = Some((q.clone(), lu.clone()));
        self.eq_state = Some(EqState {
            f: f.to_vec(),
            q: q.clone(),
            r,
            residual_n,
        });
        Equil { q, lu, residual_n }
    }

    /// Adjoint fields and the marker Jacobian at an equilibrium (28): row
    /// `i` of `∂(Aq)/∂F` is `Gᵀ M K⁻¹ Mᵀ a_iᵀ` (K symmetric). The `n_ob`
    /// adjoint systems share one factorization and one sweep over it.
    pub fn derivs(&self, lu: &BandedLu, op: &ObsOp) -> Result<Derivs> {
        let nq = self.robot.n_q();
        let nfree = self.robot.n_free();
        let (nd, d) = (E::NODE_DOFS, E::DIM);
        let m = op.n();
        // right-hand sides Mᵀ a_iᵀ, row-major n_free × m
        let mut b = vec![0.0; nfree * m];
        let mut u = vec![0.0; nfree];
        for (i, row) in op.rows.iter().enumerate() {
            if row.e == 0 {
                // touches the base node: restrict through the clamp
                let ai = op.dense_row(i, nq, nd, d);
                self.robot.restrict_into(&ai, &mut u)?;
                for (k, v) in u.iter().enumerate() {
                    b[k * m + i] = *v;
                }
            } else {
                let nb = self.robot.n_base_free();
                for k in 0..4 {
                    let gi = row.e * nd + k * d + row.comp;
                    b[(nb + gi - nd) * m + i] += row.w[k];
                }
            }
        }
        lu.solve_many_in_place(&mut b, m)?;
        let mut z = Vec::with_capacity(m);
        let mut jm = Vec::with_capacity(m);
        for i in 0..m {
            for (k, uk) in u.iter_mut().enumerate() {
                *uk = b[k * m + i];
            }
            let mut zi = vec![0.0; nq];
            self.robot.expand_step_into(&u, &mut zi)?;
            jm.push(self.gen_force_t(&zi)?);
            z.push(zi);
        }
        Ok(Derivs { z, jm })
    }

    /// The derivatives at `q` for `op`'s rows: the cached ones if they were
    /// taken at this very shape for the same rows, else [`Core::derivs`].
    pub fn derivs_at(&mut self, q: &[f64], lu: &BandedLu, op: &ObsOp) -> Result<Derivs> {
        if let Some((qc, rows, dv)) = self.derivs_cache.take() {
            if qc == q && rows == op.rows {
                return Ok(dv);
            }
        }
        self.derivs(lu, op)
    }

    /// Remembers the derivatives at a converged estimate (see
    /// [`Core::derivs_at`]).
    pub fn keep_derivs(&mut self, q: &[f64], op: &ObsOp, dv: &Derivs) {
        self.derivs_cache = Some((q.to_vec(), op.rows.clone(), dv.clone()));
    }

    /// The objective parts at `(q, F)`: `(eᵀWe, α FᵀHF, e)`.
    pub fn objective(
        &self,
        op: &ObsOp,
        q: &[f64],
        f: &[f64],
        alpha: f64,
    ) -> Result<(f64, f64, Vec<f64>)> {
        let e = op.residual(q, E::NODE_DOFS, E::DIM);
        Ok((op.weighted(&e), alpha * self.penalty(f)?, e))
    }

    /// Reduced gradient (29): `2 (Jᵀ W e + α H F)`.
    pub fn gradient(
        &self,
        dv: &Derivs,
        op: &ObsOp,
        e: &[f64],
        f: &[f64],
        alpha: f64,
    ) -> Result<Vec<f64>> {
        let mut g: Vec<f64> = self
            .penalty_grad(f)?
            .iter()
            .map(|v| 2.0 * alpha * v)
            .collect();
        for (i, ji) in dv.jm.iter().enumerate() {
            let c = 2.0 * op.wt[i] * e[i];
            g.iter_mut().zip(ji).for_each(|(a, b)| *a += c * b);
        }
        Ok(g)
    }

    /// The Gauss–Newton step (30) for `F`: solves `(JᵀWJ + αH) dF = −(JᵀWe + αHF)`.
    /// Distributed loads use the representer form `F + dF = Σ_i z_i c_i`,
    /// `(α W⁻¹ + Zᵀ B Z) c = J F − e` (an `n_ob × n_ob` Cholesky, no `n_q³`
    /// work); concentrated loads solve the small `n_F × n_F` system. Also
    /// returns the covariance factor `L = σ (JᵀWJ + αH)⁻¹ JᵀW` (n_F × n_ob).
    pub fn gn_step(
        &self,
        dv: &Derivs,
        op: &ObsOp,
        e: &[f64],
        f: &[f64],
        alpha: f64,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let (step, fac) = self.gn_solve(dv, op, e, f, alpha)?;
        let l = self.cov_factor(dv, op, &fac);
        Ok((step, l))
    }

    /// The step of [`Core::gn_step`] and the Cholesky factor of its system
    /// (for [`Core::cov_factor`]), without the covariance factor: an
    /// iteration needs only the step.
    pub fn gn_solve(
        &self,
        dv: &Derivs,
        op: &ObsOp,
        e: &[f64],
        f: &[f64],
        alpha: f64,
    ) -> Result<(Vec<f64>, GnFactor)> {
        let m = op.n();
        let nf = self.n_f;
        let not_spd = || Error::NotPositiveDefinite {
            context: "the Gauss-Newton matrix of the estimator".into(),
        };
        match self.settings.load_model {
            LoadModel::Distributed => {
                // S = Zᵀ B Z + α W⁻¹ (symmetric: the upper triangle, mirrored)
                let mut s = vec![0.0; m * m];
                for i in 0..m {
                    for j in i..m {
                        let v = dot(&dv.z[i], &dv.jm[j]);
                        s[i * m + j] = v;
                        s[j * m + i] = v;
                    }
                    s[i * m + i] += alpha / op.wt[i];
                }
                let chol = SmallCholesky::jittered(s, m).ok_or_else(not_spd)?;
                let mut c: Vec<f64> = (0..m).map(|i| dot(&dv.jm[i], f) - e[i]).collect();
                chol.solve(&mut c);
                let mut step: Vec<f64> = f.iter().map(|v| -v).collect();
                for (zi, ci) in dv.z.iter().zip(&c) {
                    step.iter_mut().zip(zi).for_each(|(a, b)| *a += ci * b);
                }
                Ok((step, GnFactor(chol)))
            }
            LoadModel::Concentrated { .. } => {
                let mut n = vec![0.0; nf * nf];
                for a in 0..nf {
                    for b in 0..nf {
                        n[a * nf + b] = (0..m)
                            .map(|i| op.wt[i] * dv.jm[i][a] * dv.jm[i][b])
                            .sum::<f64>()
                            + if a == b { alpha } else { 0.0 };
                    }
                }
                let chol = SmallCholesky::jittered(n, nf).ok_or_else(not_spd)?;
                let mut step: Vec<f64> = (0..nf)
                    .map(|a| {
                        -(0..m).map(|i| op.wt[i] * dv.jm[i][a] * e[i]).sum::<f64>() - alpha * f[a]
                    })
                    .collect();
                chol.solve(&mut step);
                Ok((step, GnFactor(chol)))
            }
        }
    }

    /// The covariance factor `L = σ (JᵀWJ + αH)⁻¹ JᵀW` (`n_F × n_ob`,
    /// row-major) from the factor of [`Core::gn_solve`] at the same
    /// derivatives: `σ Z S⁻¹` for the distributed load, `σ N⁻¹ JᵀW` for a
    /// concentrated one (`O(n_F n_ob²)`).
    pub fn cov_factor(&self, dv: &Derivs, op: &ObsOp, fac: &GnFactor) -> Vec<f64> {
        let m = op.n();
        let nf = self.n_f;
        let sigma = self.settings.noise_sigma_m;
        let inv = fac.0.inverse();
        let mut l = vec![0.0; nf * m];
        match self.settings.load_model {
            LoadModel::Distributed => {
                // column j of L = σ Σ_i S⁻¹[i, j] z_i (contiguous axpys,
                // into Lᵀ), then transposed
                let mut lt = vec![0.0; m * nf];
                for (j, ltj) in lt.chunks_exact_mut(nf).enumerate() {
                    for (i, zi) in dv.z.iter().enumerate() {
                        let c = sigma * inv[i * m + j];
                        ltj.iter_mut().zip(zi).for_each(|(v, z)| *v += c * z);
                    }
                }
                for (k, lk) in l.chunks_exact_mut(m).enumerate() {
                    for (j, v) in lk.iter_mut().enumerate() {
                        *v = lt[j * nf + k];
                    }
                }
            }
            LoadModel::Concentrated { .. } => {
                for a in 0..nf {
                    for j in 0..m {
                        l[a * m + j] = sigma
                            * (0..nf).map(|b| inv[a * nf + b] * dv.jm[j][b]).sum::<f64>()
                            * op.wt[j];
                    }
                }
            }
        }
        l
    }

    /// Assembles the [`Estimate`] at a converged `(q, F)`.
    #[allow(clippy::too_many_arguments)]
    pub fn finish(
        &self,
        q: Vec<f64>,
        f: Vec<f64>,
        op: &ObsOp,
        dv: &Derivs,
        cov_factor: Vec<f64>,
        e: Vec<f64>,
        report: EstimateReport,
    ) -> Result<Estimate> {
        let d = E::DIM;
        let m = op.n();
        let nf = self.n_f;
        // resultant force weights: c_i = ∫ (row i of w) dX, and moment
        let (resultant_force_n, resultant_moment_nm, fw) = self.resultants(&q, &f)?;
        // Lᵀ (n_ob × n_F): its rows are contiguous for the products below
        let mut lt = vec![0.0; m * nf];
        for (k, lk) in cov_factor.chunks_exact(m).enumerate() {
            for (j, v) in lk.iter().enumerate() {
                lt[j * nf + k] = *v;
            }
        }
        // Cov(resultant) = (C L)(C L)ᵀ with C the d × n_F map F → ∫w
        let mut cl = vec![0.0; d * m];
        for a in 0..d {
            for j in 0..m {
                cl[a * m + j] = dot(&fw[a * nf..(a + 1) * nf], &lt[j * nf..(j + 1) * nf]);
            }
        }
        let mut resultant_force_cov = vec![0.0; d * d];
        for a in 0..d {
            for b in 0..d {
                resultant_force_cov[a * d + b] =
                    dot(&cl[a * m..(a + 1) * m], &cl[b * m..(b + 1) * m]);
            }
        }
        // marker-space shape covariance: (J L)(J L)ᵀ
        let mut jl = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                jl[i * m + j] = dot(&dv.jm[i], &lt[j * nf..(j + 1) * nf]);
            }
        }
        let mut marker_cov = vec![0.0; m * m];
        for i in 0..m {
            for j in 0..m {
                marker_cov[i * m + j] = dot(&jl[i * m..(i + 1) * m], &jl[j * m..(j + 1) * m]);
            }
        }
        Ok(Estimate {
            q,
            f,
            load_model: self.settings.load_model,
            resultant_force_n,
            resultant_moment_nm,
            resultant_force_cov,
            marker_residuals: e,
            cov_factor,
            marker_cov,
            noise_sigma_m: self.settings.noise_sigma_m,
            report,
            node_s: self.robot.node_arc().to_vec(),
            dim: d,
            n_ob: m,
        })
    }

    /// Resultant force and moment (about the base position, in the shape
    /// `q`) of the load `F`, and the `DIM × n_F` map `F → ∫ w dX`.
    #[allow(clippy::type_complexity)]
    pub fn resultants(&self, q: &[f64], f: &[f64]) -> Result<(Vec<f64>, Vec<f64>, Vec<f64>)> {
        let d = E::DIM;
        let nd = E::NODE_DOFS;
        let nf = self.n_f;
        let r0 = &q[..d];
        let mut force = vec![0.0; d];
        let mut moment = vec![0.0; if d == 2 { 1 } else { 3 }];
        let mut fw = vec![0.0; d * nf];
        match self.settings.load_model {
            LoadModel::Concentrated { node } => {
                force.copy_from_slice(f);
                let r: Vec<f64> = (0..d).map(|i| q[node * nd + i] - r0[i]).collect();
                moment = cross(&r, f);
                for a in 0..d {
                    fw[a * nf + a] = 1.0;
                }
            }
            LoadModel::Distributed => {
                const MAX_DIM: usize = 3;
                let rule = crate::quadrature::GaussRule::new(5)?;
                // the shape functions at the rule's points (elements of a
                // section share a length: recomputed only when it changes)
                let mut le_prev = f64::NAN;
                let mut shapes = [[0.0; 4]; 5];
                for (e, el) in self.robot.elements().iter().enumerate() {
                    let le = el.length();
                    if le != le_prev {
                        for (sh, (xi, _)) in shapes.iter_mut().zip(rule.iter()) {
                            *sh = el.shape(xi);
                        }
                        le_prev = le;
                    }
                    for (sh, (_, wt)) in shapes.iter().zip(rule.iter()) {
                        let mut w = [0.0; MAX_DIM];
                        let mut r = [0.0; MAX_DIM];
                        for (k, sk) in sh.iter().enumerate() {
                            for i in 0..d.min(MAX_DIM) {
                                w[i] += sk * f[e * nd + k * d + i];
                                r[i] += sk * q[e * nd + k * d + i];
                                fw[i * nf + e * nd + k * d + i] += wt * le * sk;
                            }
                        }
                        for i in 0..d.min(MAX_DIM) {
                            force[i] += wt * le * w[i];
                            r[i] -= r0[i];
                        }
                        if d == 2 {
                            moment[0] += wt * le * (r[0] * w[1] - r[1] * w[0]);
                        } else {
                            let mm = cross(&r[..d], &w[..d]);
                            moment
                                .iter_mut()
                                .zip(mm)
                                .for_each(|(a, b)| *a += wt * le * b);
                        }
                    }
                }
            }
        }
        Ok((force, moment, fw))
    }

    /// Intermediate measurement vectors from the previous observation to `y`
    /// when the jump exceeds `max_observation_jump_m` (positions only count).
    pub fn sub_targets(&self, op: &ObsOp, q_start: &[f64]) -> Vec<Vec<f64>> {
        // from the last observation, or (first step) from the markers of
        // the starting shape
        let predicted: Vec<f64>;
        let prev = match &self.warm {
            Some(w) if w.y.len() == op.y.len() => &w.y,
            _ => {
                predicted = (0..op.n())
                    .map(|i| op.apply_row(i, q_start, E::NODE_DOFS, E::DIM))
                    .collect();
                &predicted
            }
        };
        let jump =
            op.y.iter()
                .zip(prev)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        let n = (jump / self.settings.max_observation_jump_m)
            .ceil()
            .max(1.0);
        let n = if n.is_finite() {
            (n as usize).min(1000)
        } else {
            1
        };
        (1..=n)
            .map(|k| {
                let t = k as f64 / n as f64;
                prev.iter()
                    .zip(&op.y)
                    .map(|(a, b)| a + t * (b - a))
                    .collect()
            })
            .collect()
    }

    /// The starting point of a step: the warm state, else zero load and the
    /// shape of the known loads.
    pub fn start(&mut self) -> Result<(Vec<f64>, Vec<f64>)> {
        if let Some(w) = &self.warm {
            return Ok((w.f.clone(), w.q.clone()));
        }
        let f = vec![0.0; self.n_f];
        let solver = StaticSolver::new(self.settings.statics.clone())?;
        let eq = solver.solve(&self.robot, &self.known, None)?;
        Ok((f, eq.q))
    }

    /// Chooses `α` by the discrepancy principle: `weighted_residual(α) =
    /// n_ob`, with `solve(α)` returning the weighted residual of the estimate
    /// at `α`. The residual grows with `α`: from `α = 100` the bracket is
    /// widened by factors of 10, then bisected in `log10 α` to 0.02.
    pub fn discrepancy_alpha(
        n_ob: usize,
        mut solve: impl FnMut(f64) -> Result<f64>,
    ) -> Result<f64> {
        let target = n_ob as f64;
        let (lo_lim, hi_lim) = (-14.0f64, 14.0f64);
        // start where the reduced problem is well conditioned (with whitened
        // weights α = 100 is a strong regularization) and move by decades:
        // each solve starts from the previous one (continuation)
        let mut a = 2.0f64;
        let mut r = solve(100.0)?;
        let (mut lo, mut hi);
        if r > target {
            hi = a;
            while r > target && a > lo_lim {
                hi = a;
                a -= 1.0;
                r = solve(10f64.powf(a))?;
            }
            if r > target {
                return Ok(10f64.powf(a));
            }
            lo = a;
        } else {
            lo = a;
            while r <= target && a < hi_lim {
                lo = a;
                a += 1.0;
                r = solve(10f64.powf(a))?;
            }
            if r <= target {
                return Ok(10f64.powf(a));
            }
            hi = a;
        }
        while hi - lo > 0.02 {
            let mid = 0.5 * (lo + hi);
            if solve(10f64.powf(mid))? > target {
                hi = mid;
            } else {
                lo = mid;
            }
        }
        Ok(10f64.powf(0.5 * (lo + hi)))
    }
}

/// The factor (≤ 1) that keeps the predicted marker motion `max_i |J_i dF|`
/// within `cap` (m): a trust region against Gauss–Newton overshoots far from
/// the solution (loads under which the statics barely converge).
pub(crate) fn step_cap(jm: &[Vec<f64>], step: &[f64], cap: f64) -> f64 {
    let pred = jm.iter().map(|j| dot(j, step).abs()).fold(0.0f64, f64::max);
    if pred > cap && pred.is_finite() {
        cap / pred
    } else {
        1.0
    }
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

pub(crate) fn norm2(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

pub(crate) fn dot(a: &[f64], b: &[f64]) -> f64 {
    crate::linsolve::banded::dot(a, b)
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
/// let f = direct_solution(&robot, &loads, &eq.q)?;
/// assert!(f.iter().all(|v| v.abs() < 1e-3));
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn direct_solution<E: Element>(robot: &Robot<E>, known: &Loads, q: &[f64]) -> Result<Vec<f64>> {
    let dead = robot.dead_force(known)?;
    let r = robot.residual(q, &dead, known)?; // Q without F
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
    Ok(f.iter().copied().collect())
}

/// One solve of a continuation path in `α` (the discrepancy search, the
/// cold start at a small `α`): from `(f0, q0)` at `alpha`; a converged solve
/// becomes the next start. Its weighted residual, or `None` when the solve
/// failed.
fn path_solve<S>(
    core_of: &mut S,
    op: &ObsOp,
    alpha: f64,
    f0: &mut Vec<f64>,
    q0: &mut Vec<f64>,
    solve_one: fn(&mut S, &ObsOp, Vec<f64>, Vec<f64>, f64) -> Result<Solved>,
) -> Option<f64> {
    let s = solve_one(core_of, op, f0.clone(), q0.clone(), alpha).ok()?;
    if s.report.status.is_converged() {
        *f0 = s.f;
        *q0 = s.q;
    }
    Some(s.report.weighted_residual)
}

/// Where the cold start of the `newton` backend at a given small `α` begins
/// its continuation (m/N² with whitened weights; the discrepancy search
/// starts there too).
pub const ALPHA_CONTINUATION_START: f64 = 100.0;

/// The cold start of the reduced Gauss–Newton method at a small fixed `α`:
/// from the unloaded start, the Gauss–Newton iteration on a nearly
/// unregularized problem takes many short line-search steps, or stalls (the
/// stability map's "line search failed" at α ≤ 1 m/N² before this). The
/// solution is instead followed from [`ALPHA_CONTINUATION_START`] down by
/// decades to `α`, each solve starting from the last converged one (the path
/// the discrepancy search takes); the last one becomes the warm start of the
/// solve at `α`. A solve of the path that fails or does not converge is
/// skipped (the next one starts from the last converged point), so the
/// result at `α` is the same minimizer, reached from a closer start.
fn alpha_continuation<E: Element, S>(
    core_of: &mut S,
    op: &ObsOp,
    alpha: f64,
    get_core: fn(&mut S) -> &mut Core<E>,
    solve_one: fn(&mut S, &ObsOp, Vec<f64>, Vec<f64>, f64) -> Result<Solved>,
) -> Result<()> {
    let (mut f0, mut q0) = get_core(core_of).start()?;
    let mut b = ALPHA_CONTINUATION_START;
    while b > 1.5 * alpha {
        path_solve(core_of, op, b, &mut f0, &mut q0, solve_one);
        b /= 10.0;
    }
    get_core(core_of).warm = Some(Warm {
        f: f0,
        q: q0,
        y: op.y.clone(),
    });
    Ok(())
}

/// Runs one observation through a sequence of intermediate targets and the
/// backend's `solve_one`, shared by both backends.
pub(crate) fn run_step<E: Element, S>(
    core_of: &mut S,
    observation: &Observation,
    backend: Backend,
    get_core: fn(&mut S) -> &mut Core<E>,
    solve_one: fn(&mut S, &ObsOp, Vec<f64>, Vec<f64>, f64) -> Result<Solved>,
) -> Result<Estimate> {
    let start = Instant::now();
    let op = get_core(core_of).obs_op(observation)?;
    let alpha = match get_core(core_of).alpha {
        Some(a) => {
            if backend == Backend::Newton
                && get_core(core_of).warm.is_none()
                && a < ALPHA_CONTINUATION_START
            {
                alpha_continuation(core_of, &op, a, get_core, solve_one)?;
            }
            a
        }
        None => {
            // continuation in α: each solve starts from the last converged one
            let (mut f0, mut q0) = get_core(core_of).start()?;
            let n_ob = op.n();
            let a = Core::<E>::discrepancy_alpha(n_ob, |a| {
                // a failure (at an extreme α) counts as a perfect fit: the
                // search then moves to larger α
                Ok(path_solve(core_of, &op, a, &mut f0, &mut q0, solve_one).unwrap_or(0.0))
            })?;
            let core = get_core(core_of);
            core.alpha = Some(a);
            // the last solve of the search is close: start from it
            core.warm = Some(Warm {
                f: f0,
                q: q0,
                y: op.y.clone(),
            });
            a
        }
    };
    let (_, q_start) = get_core(core_of).start()?;
    let targets = get_core(core_of).sub_targets(&op, &q_start);
    let n_sub = targets.len();
    let mut iterations = 0;
    let mut last: Option<Solved> = None;
    for y in targets {
        let (f0, q0) = match &last {
            Some(s) => (s.f.clone(), s.q.clone()),
            None => get_core(core_of).start()?,
        };
        let sub = op.with_y(y);
        let s = solve_one(core_of, &sub, f0, q0, alpha)?;
        iterations += s.report.iterations;
        if !s.report.status.is_converged() {
            // the last iterate, with its status (the warm start stays at the
            // last converged estimate); its objective and marker residuals
            // against the observation itself, not the intermediate one
            let core = get_core(core_of);
            let (wr, pen, e) = core.objective(&op, &s.q, &s.f, alpha)?;
            let mut report = s.report;
            report.iterations = iterations;
            report.sub_steps = n_sub;
            report.backend = backend;
            report.objective = wr + pen;
            report.weighted_residual = wr;
            report.wall_time_s = start.elapsed().as_secs_f64();
            return core.finish(s.q, s.f, &op, &s.derivs, s.cov_factor, e, report);
        }
        last = Some(s);
    }
    let s = last.ok_or_else(|| Error::NonFinite {
        context: "estimator produced no step".into(),
    })?;
    let core = get_core(core_of);
    core.warm = Some(Warm {
        f: s.f.clone(),
        q: s.q.clone(),
        y: op.y.clone(),
    });
    let mut report = s.report;
    report.iterations = iterations;
    report.sub_steps = n_sub;
    report.backend = backend;
    report.wall_time_s = start.elapsed().as_secs_f64();
    core.finish(s.q, s.f, &op, &s.derivs, s.cov_factor, s.e, report)
}

/// One converged solve of a backend.
pub(crate) struct Solved {
    pub f: Vec<f64>,
    pub q: Vec<f64>,
    pub derivs: Derivs,
    pub cov_factor: Vec<f64>,
    pub e: Vec<f64>,
    pub report: EstimateReport,
}
