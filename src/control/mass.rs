//! Payload-mass estimation from the end-effector position (Sec. IV, Fig. 8):
//! the concentrated-load model (32)–(35).
//!
//! A mass hangs at one node of the model (the "stressed point" of (32)).
//! The unknown load is reduced to the force `F` there (`DIM` numbers), whose
//! generalized force is `A_xᵀ F` (34); the equilibrium (35)
//! `Q_E(q) + Q_A(q, P) + A_xᵀ F = 0` together with "the end effector is at
//! the measured `x̄`" (32) fixes `(q, F)`: as many unknowns as equations.
//! This is the estimate of a force at a site by the one estimator of every
//! model ([`NewtonEstimator`] with [`LoadModel::AtSite`], or with
//! [`LoadModel::Along`] for the weight alone, one unknown along gravity),
//! from one marker at the end effector, with the vanishing penalty
//! [`PAYLOAD_ALPHA`]: its status (the fit test against
//! [`MassSettings::noise_sigma_m`]) and its covariance come with it. The
//! forward map `x(F)` and its Jacobian `∂x/∂F = S(X_e) ∂q/∂F` ((28) with
//! `G = A_xᵀ`) stay available to check the answer
//! ([`MassEstimator::forward`], [`MassEstimator::jacobian`]).
//!
//! # Relative displacement (the virtual payload idea)
//! The model is not the robot: its unloaded end effector is not where the
//! robot's is, and the force that explains the difference (a virtual
//! payload, Fig. 5) would count as mass. So, as the paper does, only the
//! displacement caused by loading is used: the target is the model's own
//! unloaded end effector at the same pressures plus the measured
//! displacement, `x̄ = x_model(P, F = 0) + (x_loaded − x_unloaded)`, and the
//! mass is the component of `F` along gravity, `m = F · g / |g|²`.
//! [`MassReference::Absolute`] (the loaded position as measured) is kept for
//! comparison.

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::element::Element;
use crate::error::{Error, Result, check_all_finite, check_len};
use crate::estimate::{
    Estimate, EstimateStatus, Estimator, EstimatorSettings, LoadModel, NewtonEstimator,
    PAYLOAD_ALPHA,
};
use crate::loads::Loads;
use crate::observe::{MarkerObservation, Observation};
use crate::sensitivity::Sensitivity;
use crate::site::Site;
use crate::statics::{EquilibriumTracker, StaticSettings};

use super::{IkSettings, InverseKinematics};

/// What the target of the solve is (see the [module documentation](crate::control)).
///
/// # Example
/// ```
/// let r: softrod::control::MassReference = serde_json::from_str("\"relative\"").unwrap();
/// assert_eq!(r, softrod::control::MassReference::Relative);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MassReference {
    /// The model's unloaded end effector plus the measured displacement
    /// (default; the paper's choice).
    #[default]
    Relative,
    /// The loaded end effector as measured (the virtual payload counts as
    /// mass).
    Absolute,
    /// As `Relative`, but at the model pressures that put the model's
    /// unloaded end effector where the robot's was measured (found by the
    /// inverse kinematics started at the commanded pressures, minimum `Σ P²`
    /// rule), instead of at the commanded ones: the model's configuration then matches the robot's, so an
    /// actuation error does not change the compliance the mass is read
    /// with.
    Matched,
}

/// Which force the mass may exert at its node.
///
/// # Example
/// ```
/// let f: softrod::control::MassForce = serde_json::from_str("\"gravity\"").unwrap();
/// assert_eq!(f, softrod::control::MassForce::Gravity);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MassForce {
    /// Its weight: `F = m g`, one unknown (the mass) fitted to the `DIM`
    /// measured coordinates by least squares (default: a hanging mass
    /// pulls along gravity, and the fit does not turn a model error along
    /// the stiff axial direction into a large sideways force).
    #[default]
    Gravity,
    /// Any force `F` (`DIM` unknowns, as many as measured coordinates;
    /// the paper's `F ∈ R³`): the mass is its component along gravity.
    Free,
}

/// Settings of [`MassEstimator`]; every field has a documented default.
///
/// # Example
/// ```
/// softrod::control::MassSettings::default().validate()?;
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MassSettings {
    /// Outer iterations of the estimator per estimate (default 50).
    pub max_iterations: usize,
    /// The standard deviation of each coordinate of the measured
    /// displacement (m, default 1e-5): the mass's standard deviation and
    /// the fit test of the estimate are stated for it.
    pub noise_sigma_m: f64,
    /// Which target (default relative).
    pub reference: MassReference,
    /// Which force (default the weight).
    pub force: MassForce,
    /// Factor on the estimated mass (default 1): a stiffness error of the
    /// model scales every displacement, so one weighing of a known mass
    /// ([`MassEstimator::calibrate`]) fixes it for all configurations.
    pub scale: f64,
    /// Static solver of the equilibria `q(F)`.
    pub statics: StaticSettings,
}

impl Default for MassSettings {
    fn default() -> Self {
        MassSettings {
            max_iterations: 50,
            noise_sigma_m: 1e-5,
            reference: MassReference::Relative,
            force: MassForce::Gravity,
            scale: 1.0,
            statics: StaticSettings::default(),
        }
    }
}

impl MassSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`mass.noise_sigma_m`, …).
    pub fn validate(&self) -> Result<()> {
        if self.max_iterations == 0 {
            return Err(Error::invalid("mass.max_iterations", 0, "must be >= 1"));
        }
        for (name, v) in [
            ("mass.noise_sigma_m", self.noise_sigma_m),
            ("mass.scale", self.scale),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(name, v, "must be finite and > 0"));
            }
        }
        self.statics.validate("mass.statics")
    }

    /// The estimator's settings of a mass hanging at `site` under gravity
    /// `gravity_m_per_s2` (`DIM` components): the force at the site
    /// ([`LoadModel::AtSite`]) or its weight along gravity
    /// ([`LoadModel::Along`]), the vanishing penalty [`PAYLOAD_ALPHA`], run
    /// to its optimum (no statistical stop).
    fn estimator(&self, site: Site, gravity_m_per_s2: &[f64]) -> EstimatorSettings {
        let mut direction = [0.0; 3];
        direction[..gravity_m_per_s2.len()].copy_from_slice(gravity_m_per_s2);
        EstimatorSettings {
            load_model: match self.force {
                MassForce::Gravity => LoadModel::Along { site, direction },
                MassForce::Free => LoadModel::AtSite { site },
            },
            alpha: Some(PAYLOAD_ALPHA),
            noise_sigma_m: self.noise_sigma_m,
            max_iterations: self.max_iterations,
            statistical_tolerance: 0.0,
            statics: self.statics.clone(),
            ..EstimatorSettings::default()
        }
    }
}

/// The result of [`MassEstimator::estimate`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MassEstimate {
    /// The estimated mass `F · g / |g|²` (kg; negative if the load pulls
    /// against gravity).
    pub mass_kg: f64,
    /// The force `F` at the load node (N).
    pub force_n: Vec<f64>,
    /// The end-effector position the model was solved for (m).
    pub target_m: Vec<f64>,
    /// The model's unloaded end effector at the pressures used (m).
    pub model_unloaded_m: Vec<f64>,
    /// The model pressures the mass was read at (Pa): the commanded ones,
    /// or for [`MassReference::Matched`] those of the inverse kinematics.
    pub pressures_pa: Vec<f64>,
    /// Remaining distance between the model's end effector and the target
    /// (m): for [`MassForce::Gravity`] the part of the displacement a weight
    /// at the node cannot explain.
    pub residual_m: f64,
    /// Iterations of the estimator.
    pub iterations: usize,
    /// Whether the estimator's iteration ended on its stopping test (a
    /// stationary point of the misfit) rather than on its limit or a
    /// failed line search: `status` converged, or a misfit beyond the
    /// noise (for [`MassForce::Gravity`], a displacement a weight at the
    /// point cannot explain to [`MassSettings::noise_sigma_m`]; its size is
    /// `residual_m`).
    pub converged: bool,
    /// The estimator's status, its fit test under
    /// [`MassSettings::noise_sigma_m`] included.
    pub status: EstimateStatus,
    /// The mass's standard deviation (kg) under
    /// [`MassSettings::noise_sigma_m`], the scale applied.
    pub std_kg: f64,
}

impl MassEstimate {
    /// [`MassEstimate::force_n`] as a vector (N).
    ///
    /// # Example
    /// ```
    /// let e = softrod::control::MassEstimate {
    ///     mass_kg: 0.05, force_n: vec![0.0, -0.49], target_m: vec![0.2, 0.0],
    ///     model_unloaded_m: vec![0.2, 0.001], pressures_pa: vec![0.0; 4],
    ///     residual_m: 0.0, iterations: 3, converged: true, std_kg: 1e-4,
    ///     status: softrod::estimate::EstimateStatus::Converged(softrod::estimate::EstimateCriterion::WithinNoise),
    /// };
    /// assert_eq!(e.force(), nalgebra::dvector![0.0, -0.49]);
    /// assert_eq!(e.target(), nalgebra::dvector![0.2, 0.0]);
    /// assert_eq!(e.model_unloaded(), nalgebra::dvector![0.2, 0.001]);
    /// ```
    pub fn force(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.force_n)
    }

    /// [`MassEstimate::target_m`] as a vector (m).
    ///
    /// # Example
    /// See [`MassEstimate::force`].
    pub fn target(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.target_m)
    }

    /// [`MassEstimate::model_unloaded_m`] as a vector (m).
    ///
    /// # Example
    /// See [`MassEstimate::force`].
    pub fn model_unloaded(&self) -> DVector<f64> {
        DVector::from_column_slice(&self.model_unloaded_m)
    }
}

/// The concentrated-load mass estimator of one robot model (see the
/// [module documentation](crate::control)).
///
/// # Example
/// A 50 g mass at the tip of the model itself, recovered from the tip
/// displacement it causes:
/// ```
/// use softrod::control::{MassEstimator, MassSettings};
/// use softrod::{loads::PointForce, scene::Scene, statics::StaticSolver};
/// let scene = Scene::two_section();
/// let (robot, loads) = (scene.robot()?, scene.loads()?);
/// let mut est = MassEstimator::new(robot.clone(), loads.clone(), 0.24, &scene.gravity_m_per_s2, MassSettings::default())?;
/// let unloaded = robot.position_at(StaticSolver::default().solve(&robot, &loads, None)?.q.as_slice(), 0.24)?;
/// let mut heavy = loads.clone();
/// heavy.point_forces.push(PointForce { s_m: 0.24, force_n: vec![0.0, -0.05 * 9.81] });
/// let loaded = robot.position_at(StaticSolver::default().solve(&robot, &heavy, None)?.q.as_slice(), 0.24)?;
/// let m = est.estimate(&loads.pressures_pa, unloaded.as_slice(), loaded.as_slice())?;
/// assert!((m.mass_kg - 0.05).abs() < 1e-6, "{}", m.mass_kg);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct MassEstimator<E: Element + 'static> {
    /// The forward map's warm equilibria ([`MassEstimator::forward`]).
    tracker: EquilibriumTracker<E>,
    /// The estimate of the force at the load point (32)–(35): the one
    /// estimator of every model, with the load model of
    /// [`MassSettings::force`].
    estimator: NewtonEstimator<Robot<E>>,
    /// The pressures the estimator's known loads carry (Pa).
    estimator_pressures_pa: Vec<f64>,
    /// `F = basis θ` of the estimator's load model (`DIM × n_params`).
    basis: DMatrix<f64>,
    known: Loads,
    load: LoadModel,
    effector_s_m: f64,
    gravity_m_per_s2: Vec<f64>,
    settings: MassSettings,
    warm: Option<Vec<f64>>,
    ik: InverseKinematics<Robot<E>>,
}

/// The estimator's answer to one target (see [`MassEstimator::force_for`]).
struct Fit {
    force_n: Vec<f64>,
    x_m: Vec<f64>,
    estimate: Estimate,
}

impl Fit {
    /// Whether the iteration ended on its stopping test (converged, or a
    /// misfit beyond the noise at a stationary point).
    fn stopped_on_test(&self) -> bool {
        matches!(
            self.estimate.report.status,
            EstimateStatus::Converged(_) | EstimateStatus::MisfitBeyondNoise { .. }
        )
    }
}

impl<E: Element + 'static> MassEstimator<E> {
    /// An estimator for a mass hanging at the node at arc coordinate
    /// `load_s_m` of `robot` (m; a node must lie there) under the known
    /// loads `known` (their pressures are replaced per estimate), gravity
    /// `gravity_m_per_s2`, the end effector at the tip.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field: invalid settings,
    /// `mass.load_s_m` off the robot or not at a node, `gravity_m_per_s2`
    /// zero or not finite; the errors of [`Robot::validate_loads`].
    pub fn new(
        robot: Robot<E>,
        known: Loads,
        load_s_m: f64,
        gravity_m_per_s2: &[f64],
        settings: MassSettings,
    ) -> Result<Self> {
        settings.validate()?;
        check_len("gravity_m_per_s2", E::DIM, gravity_m_per_s2.len())?;
        check_all_finite("gravity_m_per_s2", gravity_m_per_s2)?;
        if gravity_m_per_s2.iter().all(|g| *g == 0.0) {
            return Err(Error::invalid(
                "gravity_m_per_s2",
                "0",
                "a mass is read off its weight: gravity must not be zero",
            ));
        }
        robot.locate("mass.load_s_m", load_s_m)?;
        let arc = robot.node_arc();
        let tol = 1e-9 * robot.length();
        let node = arc
            .iter()
            .position(|s| (s - load_s_m).abs() <= tol)
            .ok_or_else(|| {
                Error::invalid(
                    "mass.load_s_m",
                    load_s_m,
                    "no node of the model lies there: (32) puts a node at the stressed point",
                )
            })?;
        if node == 0 {
            return Err(Error::invalid(
                "mass.load_s_m",
                load_s_m,
                "a mass at the clamped base does not move the robot",
            ));
        }
        let effector_s_m = robot.length();
        let ik_settings = IkSettings {
            statics: settings.statics.clone(),
            ..IkSettings::default()
        };
        let ik = InverseKinematics::new(robot.clone(), known.clone(), ik_settings)?;
        let site = Site::Rod {
            rod: 0,
            s_m: arc[node],
        };
        let estimator_settings = settings.estimator(site, gravity_m_per_s2);
        let basis = estimator_settings
            .load_model
            .force_basis(E::DIM)?
            .unwrap_or_default();
        let estimator = NewtonEstimator::new(&robot, &known, &estimator_settings)?;
        let tracker = EquilibriumTracker::new(robot, known.clone(), settings.statics.clone())?;
        Ok(MassEstimator {
            tracker,
            estimator,
            estimator_pressures_pa: known.pressures_pa.clone(),
            basis,
            known,
            load: LoadModel::Concentrated { node },
            effector_s_m,
            gravity_m_per_s2: gravity_m_per_s2.to_vec(),
            settings,
            warm: None,
            ik,
        })
    }

    /// The robot.
    pub fn robot(&self) -> &Robot<E> {
        self.tracker.robot()
    }

    /// Sets the chamber pressures of the model (Pa).
    fn set_pressures(&mut self, pressures_pa: &[f64]) -> Result<()> {
        if self.tracker.known().pressures_pa != pressures_pa {
            let mut known = self.known.clone();
            known.pressures_pa = pressures_pa.to_vec();
            self.tracker.set_known(known)?;
            self.warm = None;
        }
        Ok(())
    }

    /// The model's equilibrium at pressures `pressures_pa` with the force
    /// `force_n` at the load node: its shape `q` and end effector (m, `DIM`
    /// components).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for pressures outside their bounds or not
    /// finite; the static solver's errors (no equilibrium found).
    ///
    /// # Example
    /// A downward force at the tip lowers the end effector, by `∂x/∂F F` to
    /// first order:
    /// ```
    /// use softrod::control::{MassEstimator, MassSettings};
    /// use softrod::scene::Scene;
    /// let scene = Scene::two_section();
    /// let (robot, loads) = (scene.robot()?, scene.loads()?);
    /// let p = loads.pressures_pa.clone();
    /// let mut est = MassEstimator::new(robot, loads, 0.24, &scene.gravity_m_per_s2, MassSettings::default())?;
    /// let (_, x0) = est.forward(&p, &[0.0, 0.0])?;
    /// let (_, x1) = est.forward(&p, &[0.0, -1e-3])?;
    /// let j = est.jacobian(&p, &[0.0, 0.0])?; // 2 × 2, m/N
    /// let predicted = &x0 + &j * nalgebra::dvector![0.0, -1e-3];
    /// assert!(x1[1] < x0[1] && (&x1 - predicted).norm() < 1e-2 * (&x1 - &x0).norm());
    /// // the force that puts the end effector back where the load moved it
    /// let (f, _, _, converged) = est.force_for(&p, x0.as_slice())?;
    /// assert!(converged && f.norm() < 1e-9);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn forward(
        &mut self,
        pressures_pa: &[f64],
        force_n: &[f64],
    ) -> Result<(DVector<f64>, DVector<f64>)> {
        let (q, x) = self.forward_raw(pressures_pa, force_n)?;
        Ok((DVector::from_vec(q), DVector::from_vec(x)))
    }

    /// [`MassEstimator::forward`] as plain vectors (the Newton loop's).
    fn forward_raw(
        &mut self,
        pressures_pa: &[f64],
        force_n: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        check_len("force_n", E::DIM, force_n.len())?;
        check_all_finite("force_n", force_n)?;
        self.set_pressures(pressures_pa)?;
        let q0 = match &self.warm {
            Some(q) => q.clone(),
            None => self
                .tracker
                .robot()
                .arc_configuration(pressures_pa)
                .data
                .into(),
        };
        let eq = self.tracker.solve(&self.load, force_n, &q0)?;
        let x = self
            .tracker
            .robot()
            .position_at(eq.q.as_slice(), self.effector_s_m)?;
        self.warm = Some(eq.q.as_slice().to_vec());
        Ok((eq.q.data.into(), x.data.into()))
    }

    /// `∂x/∂F` (`DIM × DIM`, m/N): how the end effector moves with the force
    /// at the load node, at the equilibrium of `pressures_pa` and `force_n`
    /// ((28) with `G = A_xᵀ` (34)).
    ///
    /// # Errors
    /// As [`MassEstimator::forward`]; [`Error::Singular`] if the tangent
    /// cannot be factored.
    ///
    /// # Example
    /// See [`MassEstimator::forward`].
    pub fn jacobian(&mut self, pressures_pa: &[f64], force_n: &[f64]) -> Result<DMatrix<f64>> {
        let (q, _) = self.forward_raw(pressures_pa, force_n)?;
        let eq = self.tracker.solve(&self.load, force_n, &q)?;
        let robot = self.tracker.robot();
        let dq_df = Sensitivity::new(robot, &eq.factors)?.dq_df(&self.load)?;
        let point = robot.arc_point("effector", self.effector_s_m)?;
        let d = E::DIM;
        let mut jac = DMatrix::zeros(d, d);
        let mut out = vec![0.0; d];
        for (c, col) in dq_df.column_iter().enumerate() {
            point.value_into(col.as_slice(), &mut out)?;
            for (r, v) in out.iter().enumerate() {
                jac[(r, c)] = *v;
            }
        }
        Ok(jac)
    }

    /// The force at the load node putting the model's end effector at (or,
    /// for [`MassForce::Gravity`], closest to) `target_m` under
    /// `pressures_pa`: `(F, x, iterations, converged)`, `converged` as
    /// [`MassEstimate::converged`]. The estimate (32)–(35) of the force at
    /// the node ([`LoadModel::AtSite`], or its weight along gravity,
    /// [`LoadModel::Along`]) from one marker at the end effector, by the
    /// estimator of every model ([`NewtonEstimator`], kept warm from one
    /// call to the next at the same pressures).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] or [`Error::InvalidParameter`]
    /// (`target_m`) for a target of the wrong size or not finite; as
    /// [`crate::estimate::Estimator::step`].
    ///
    /// # Example
    /// See [`MassEstimator::forward`].
    pub fn force_for(
        &mut self,
        pressures_pa: &[f64],
        target_m: &[f64],
    ) -> Result<(DVector<f64>, DVector<f64>, usize, bool)> {
        let fit = self.fit(pressures_pa, target_m)?;
        let converged = fit.stopped_on_test();
        Ok((
            DVector::from_vec(fit.force_n),
            DVector::from_vec(fit.x_m),
            fit.estimate.report.iterations,
            converged,
        ))
    }

    /// The estimate of the force at the load node from the end effector
    /// at `target_m`.
    fn fit(&mut self, pressures_pa: &[f64], target_m: &[f64]) -> Result<Fit> {
        check_len("target_m", E::DIM, target_m.len())?;
        check_all_finite("target_m", target_m)?;
        if self.estimator_pressures_pa != pressures_pa {
            let mut known = self.known.clone();
            known.pressures_pa = pressures_pa.to_vec();
            self.estimator.set_known_loads(known)?;
            // another configuration: a cold start (its far start), not the
            // last configuration's shape
            self.estimator.reset();
            self.estimator_pressures_pa = pressures_pa.to_vec();
        }
        let observation = Observation {
            markers: vec![MarkerObservation::at_arc(
                self.effector_s_m,
                DVector::from_column_slice(target_m),
            )],
        };
        let estimate = self.estimator.step(&observation)?;
        let force_n: Vec<f64> = (&self.basis * &estimate.f).data.into();
        let x_m = self
            .tracker
            .robot()
            .position_at(estimate.q.as_slice(), self.effector_s_m)?
            .data
            .into();
        Ok(Fit {
            force_n,
            x_m,
            estimate,
        })
    }

    /// The mass hanging at the load node from the end effector measured
    /// before (`unloaded_m`) and after (`loaded_m`) it was hung, at the
    /// chamber pressures `pressures_pa` (see the [module
    /// documentation](crate::control) for the two references).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `unloaded_m` / `loaded_m` for
    /// non-finite positions; [`Error::DimensionMismatch`]; as
    /// [`MassEstimator::force_for`].
    pub fn estimate(
        &mut self,
        pressures_pa: &[f64],
        unloaded_m: &[f64],
        loaded_m: &[f64],
    ) -> Result<MassEstimate> {
        let d = E::DIM;
        check_len("unloaded_m", d, unloaded_m.len())?;
        check_len("loaded_m", d, loaded_m.len())?;
        check_all_finite("unloaded_m", unloaded_m)?;
        check_all_finite("loaded_m", loaded_m)?;
        let pressures_pa = match self.settings.reference {
            MassReference::Matched => {
                let zeros = vec![0.0; self.ik.robot().n_q()];
                self.ik
                    .solve_starting_at(unloaded_m, &zeros, pressures_pa)?
                    .pressures_pa
                    .data
                    .into()
            }
            _ => pressures_pa.to_vec(),
        };
        let pressures_pa = &pressures_pa[..];
        let (_, model_unloaded_m) = self.forward_raw(pressures_pa, &vec![0.0; d])?;
        let target_m: Vec<f64> = match self.settings.reference {
            MassReference::Relative | MassReference::Matched => model_unloaded_m
                .iter()
                .zip(loaded_m.iter().zip(unloaded_m))
                .map(|(m, (l, u))| m + (l - u))
                .collect(),
            MassReference::Absolute => loaded_m.to_vec(),
        };
        let fit = self.fit(pressures_pa, &target_m)?;
        let converged = fit.stopped_on_test();
        let g2: f64 = self.gravity_m_per_s2.iter().map(|g| g * g).sum();
        // m = gᵀ F / |g|² = cᵀ θ with c = basisᵀ g / |g|²
        let g = DVector::from_column_slice(&self.gravity_m_per_s2);
        let c = self.basis.tr_mul(&g) / g2 * self.settings.scale;
        let mass_kg = c.dot(&fit.estimate.f);
        let std_kg = (c.transpose() * fit.estimate.covariance_f() * &c)[(0, 0)]
            .max(0.0)
            .sqrt();
        let residual_m = fit
            .x_m
            .iter()
            .zip(&target_m)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        Ok(MassEstimate {
            mass_kg,
            force_n: fit.force_n,
            target_m,
            model_unloaded_m,
            pressures_pa: pressures_pa.to_vec(),
            converged,
            status: fit.estimate.report.status,
            std_kg,
            residual_m,
            iterations: fit.estimate.report.iterations,
        })
    }
}

impl<E: Element + 'static> MassEstimator<E> {
    /// The factor on the estimated mass in use.
    pub fn scale(&self) -> f64 {
        self.settings.scale
    }

    /// Calibrates [`MassSettings::scale`] with one weighing of a known mass
    /// `known_kg` (> 0) at `pressures_pa` (the end effector measured
    /// unloaded and loaded); returns the new scale. Later estimates, in any
    /// configuration, use it.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (field `known_kg`) for a mass ≤ 0 or not
    /// finite, (field `loaded_m`) if the raw estimate is not positive or the
    /// solve did not converge; as [`MassEstimator::estimate`].
    pub fn calibrate(
        &mut self,
        pressures_pa: &[f64],
        unloaded_m: &[f64],
        loaded_m: &[f64],
        known_kg: f64,
    ) -> Result<f64> {
        if !(known_kg.is_finite() && known_kg > 0.0) {
            return Err(Error::invalid(
                "known_kg",
                known_kg,
                "must be finite and > 0",
            ));
        }
        let old = self.settings.scale;
        self.settings.scale = 1.0;
        let e = self.estimate(pressures_pa, unloaded_m, loaded_m);
        self.settings.scale = old;
        let e = e?;
        if !(e.converged && e.mass_kg > 0.0) {
            return Err(Error::invalid(
                "loaded_m",
                format!("{loaded_m:?}"),
                format!(
                    "the calibration weighing gives {} kg (converged: {}): no scale from it",
                    e.mass_kg, e.converged
                ),
            ));
        }
        self.settings.scale = known_kg / e.mass_kg;
        Ok(self.settings.scale)
    }
}
