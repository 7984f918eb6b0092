//! Payload-mass estimation from the end-effector position (Sec. IV, Fig. 8):
//! the concentrated-load model (32)–(35).
//!
//! A mass hangs at one node of the model (the "stressed point" of (32)).
//! The unknown load is reduced to the force `F` there (`DIM` numbers), whose
//! generalized force is `A_xᵀ F` (34); the equilibrium (35)
//! `Q_E(q) + Q_A(q, P) + A_xᵀ F = 0` together with "the end effector is at
//! the measured `x̄`" (32) fixes `(q, F)`: as many unknowns as equations.
//! The solve is Newton on `F` with `q` eliminated by the equilibrium (each
//! iterate `q(F)` solved warm by an [`EquilibriumTracker`]) and the Jacobian
//! `∂x/∂F = S(X_e) ∂q/∂F` from (28) with `G = A_xᵀ`, backtracking on
//! `|x(F) − x̄|`.
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
use crate::estimate::LoadModel;
use crate::loads::Loads;
use crate::sensitivity::Sensitivity;
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
    /// Newton iterations per solve (default 50).
    pub max_iterations: usize,
    /// The end effector counts as matched within this distance (m, default 1e-9).
    pub tolerance_m: f64,
    /// Largest change of `|F|` in one Newton step (N, default 0.5).
    pub max_step_n: f64,
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
            tolerance_m: 1e-9,
            max_step_n: 0.5,
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
    /// [`Error::InvalidParameter`] naming the field (`mass.tolerance_m`, …).
    pub fn validate(&self) -> Result<()> {
        if self.max_iterations == 0 {
            return Err(Error::invalid("mass.max_iterations", 0, "must be >= 1"));
        }
        for (name, v) in [
            ("mass.tolerance_m", self.tolerance_m),
            ("mass.max_step_n", self.max_step_n),
            ("mass.scale", self.scale),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(name, v, "must be finite and > 0"));
            }
        }
        self.statics.validate("mass.statics")
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
    /// Newton iterations.
    pub iterations: usize,
    /// Whether the iteration ended on a step below the tolerance (a
    /// stationary point of the distance) rather than on its limit or a
    /// failed line search.
    pub converged: bool,
}

impl MassEstimate {
    /// [`MassEstimate::force_n`] as a vector (N).
    ///
    /// # Example
    /// ```
    /// let e = softrod::control::MassEstimate {
    ///     mass_kg: 0.05, force_n: vec![0.0, -0.49], target_m: vec![0.2, 0.0],
    ///     model_unloaded_m: vec![0.2, 0.001], pressures_pa: vec![0.0; 4],
    ///     residual_m: 0.0, iterations: 3, converged: true,
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
pub struct MassEstimator<E: Element> {
    tracker: EquilibriumTracker<E>,
    known: Loads,
    load: LoadModel,
    effector_s_m: f64,
    gravity_m_per_s2: Vec<f64>,
    settings: MassSettings,
    warm: Option<Vec<f64>>,
    ik: InverseKinematics<E>,
}

impl<E: Element> MassEstimator<E> {
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
        let tracker = EquilibriumTracker::new(robot, known.clone(), settings.statics.clone())?;
        Ok(MassEstimator {
            tracker,
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
    /// `pressures_pa`: `(F, x, iterations)`. Gauss–Newton on the parameters
    /// `θ` of `F = B θ` (`B = g`: one parameter, the mass; `B = I`: the
    /// force), backtracking on `|x(F) − x̄|`, until a step moves the end
    /// effector by less than the tolerance. The closest iterate is returned
    /// if it stalls (the caller compares `x` with the target).
    ///
    /// # Errors
    /// As [`MassEstimator::jacobian`].
    ///
    /// # Example
    /// See [`MassEstimator::forward`].
    pub fn force_for(
        &mut self,
        pressures_pa: &[f64],
        target_m: &[f64],
    ) -> Result<(DVector<f64>, DVector<f64>, usize, bool)> {
        let (f, x, iterations, converged) = self.force_for_raw(pressures_pa, target_m)?;
        Ok((
            DVector::from_vec(f),
            DVector::from_vec(x),
            iterations,
            converged,
        ))
    }

    /// [`MassEstimator::force_for`] as plain vectors.
    fn force_for_raw(
        &mut self,
        pressures_pa: &[f64],
        target_m: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>, usize, bool)> {
        let d = E::DIM;
        check_len("target_m", d, target_m.len())?;
        check_all_finite("target_m", target_m)?;
        let dist = |x: &[f64]| -> f64 {
            x.iter()
                .zip(target_m)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt()
        };
        // F = B θ
        let b: Vec<Vec<f64>> = match self.settings.force {
            MassForce::Gravity => self.gravity_m_per_s2.iter().map(|g| vec![*g]).collect(),
            MassForce::Free => (0..d)
                .map(|r| (0..d).map(|c| if r == c { 1.0 } else { 0.0 }).collect())
                .collect(),
        };
        let np = b[0].len();
        let force = |th: &[f64]| -> Vec<f64> {
            b.iter()
                .map(|row| row.iter().zip(th).map(|(a, t)| a * t).sum())
                .collect()
        };
        let mut theta = vec![0.0; np];
        let mut f = force(&theta);
        let (_, mut x) = self.forward_raw(pressures_pa, &f)?;
        let mut r = dist(&x);
        let mut iterations = 0;
        let mut converged = r <= self.settings.tolerance_m;
        while iterations < self.settings.max_iterations && !converged {
            iterations += 1;
            let jf = self.jacobian(pressures_pa, &f)?;
            // J_θ = J_F B (DIM × np); normal equations J_θᵀ J_θ dθ = J_θᵀ (x̄ − x)
            let jt: Vec<Vec<f64>> = (0..d)
                .map(|row| {
                    (0..np)
                        .map(|c| (0..d).map(|k| jf[(row, k)] * b[k][c]).sum())
                        .collect()
                })
                .collect();
            let res: Vec<f64> = target_m.iter().zip(&x).map(|(a, b)| a - b).collect();
            let normal: Vec<Vec<f64>> = (0..np)
                .map(|i| {
                    (0..np)
                        .map(|j| (0..d).map(|k| jt[k][i] * jt[k][j]).sum())
                        .collect()
                })
                .collect();
            let rhs: Vec<f64> = (0..np)
                .map(|i| (0..d).map(|k| jt[k][i] * res[k]).sum())
                .collect();
            let mut step = solve_small(&normal, &rhs)?;
            // the predicted motion of the end effector
            let moved = (0..d)
                .map(|k| (0..np).map(|c| jt[k][c] * step[c]).sum::<f64>().powi(2))
                .sum::<f64>()
                .sqrt();
            if moved <= self.settings.tolerance_m {
                converged = true;
                break;
            }
            let fstep = force(&step);
            let norm = fstep.iter().map(|v| v * v).sum::<f64>().sqrt();
            if norm > self.settings.max_step_n {
                let sc = self.settings.max_step_n / norm;
                step.iter_mut().for_each(|v| *v *= sc);
            }
            // backtracking on the distance
            let mut t = 1.0;
            let mut accepted = false;
            let warm = self.warm.clone();
            for _ in 0..20 {
                let trial: Vec<f64> = theta.iter().zip(&step).map(|(a, s)| a + t * s).collect();
                let ft = force(&trial);
                if let Ok((_, xt)) = self.forward_raw(pressures_pa, &ft) {
                    let rt = dist(&xt);
                    if rt < r {
                        theta = trial;
                        f = ft;
                        x = xt;
                        r = rt;
                        accepted = true;
                        converged = r <= self.settings.tolerance_m;
                        break;
                    }
                }
                self.warm.clone_from(&warm);
                t *= 0.5;
            }
            if !accepted {
                break;
            }
        }
        Ok((f, x, iterations, converged))
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
        let (force_n, x, iterations, converged) = self.force_for_raw(pressures_pa, &target_m)?;
        let g2: f64 = self.gravity_m_per_s2.iter().map(|g| g * g).sum();
        let mass_kg = force_n
            .iter()
            .zip(&self.gravity_m_per_s2)
            .map(|(f, g)| f * g)
            .sum::<f64>()
            / g2
            * self.settings.scale;
        let residual_m = x
            .iter()
            .zip(&target_m)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            .sqrt();
        Ok(MassEstimate {
            mass_kg,
            force_n,
            target_m,
            model_unloaded_m,
            pressures_pa: pressures_pa.to_vec(),
            converged,
            residual_m,
            iterations,
        })
    }
}

impl<E: Element> MassEstimator<E> {
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

/// `A x = b` for a small dense `A` (rows), by LU with partial pivoting.
fn solve_small(a: &[Vec<f64>], b: &[f64]) -> Result<Vec<f64>> {
    let n = b.len();
    let m = nalgebra::DMatrix::from_fn(n, n, |r, c| a[r][c]);
    let scale = m.amax();
    let x = m
        .lu()
        .solve(&nalgebra::DVector::from_column_slice(b))
        .ok_or(Error::Singular {
            context: "mass estimation: dx/dF (the end effector does not move with the load)".into(),
            index: 0,
            pivot: 0.0,
            scale,
        })?;
    Ok(x.iter().copied().collect())
}
