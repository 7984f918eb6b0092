//! One case of a sweep: an estimator on markers sampled from a reference
//! shape, run under guard, reduced to an [`Outcome`].
//!
//! A case never panics and never hangs: the estimator runs on its own thread
//! under [`std::panic::catch_unwind`] with a wall-clock cap, its iteration
//! budgets bounded by [`EstimatorSettings`]; an error, a panic or a timeout is
//! recorded as an outcome with a [`FailureCause`], computed from the typed
//! status or error (never from a message).

use std::sync::{Arc, mpsc};
use std::time::{Duration, Instant};

use clarabel::solver::SolverStatus;
use serde::{Deserialize, Serialize};

use crate::assembly::{Base, Clamp, Robot, RobotSpec, Section};
use crate::element::PlanarCable;
use crate::error::{Error, Result};
use crate::estimate::{
    Backend, Estimate, EstimateStatus, EstimatorSettings, MarkerObservation, Observation,
};
use crate::loads::Loads;
use crate::statics::StaticStatus;

use super::reference::Reference;

/// Why a case failed: the categories of the stability map.
///
/// # Example
/// ```
/// use softrod::report::sweep::FailureCause;
/// let err = softrod::Error::InvalidParameter {
///     name: "markers".into(), value: "0".into(), reason: "needs at least one marker".into() };
/// assert_eq!(FailureCause::classify(&err), FailureCause::InvalidInput);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FailureCause {
    /// The iterates left the finite numbers, or the equilibrium solve
    /// diverged (non-finite values, the homotopy stalled, plain Newton steps
    /// of the equilibrium failed).
    Divergence,
    /// The tangent stiffness had a vanishing pivot.
    SingularTangent,
    /// A matrix the method factors was not positive definite or the QP solver
    /// stopped on numerical trouble: the problem is too ill-conditioned.
    IllConditioning,
    /// The iteration budget ran out.
    IterationLimit,
    /// The SQP subproblem was infeasible.
    QpInfeasible,
    /// The line search found no acceptable step.
    LineSearchFailed,
    /// The library refused the input (e.g. no markers, a non-finite position).
    InvalidInput,
    /// The case exceeded its wall-clock cap.
    Timeout,
    /// The code panicked (a bug: the report's tests assert this never happens).
    Panic,
    /// Anything else.
    Other,
}

impl FailureCause {
    /// All categories, in table order.
    pub(crate) const ALL: [FailureCause; 10] = [
        FailureCause::Divergence,
        FailureCause::SingularTangent,
        FailureCause::IllConditioning,
        FailureCause::IterationLimit,
        FailureCause::QpInfeasible,
        FailureCause::LineSearchFailed,
        FailureCause::InvalidInput,
        FailureCause::Timeout,
        FailureCause::Panic,
        FailureCause::Other,
    ];

    /// A readable name ("iteration limit").
    pub fn label(self) -> &'static str {
        match self {
            FailureCause::Divergence => "divergence / non-finite",
            FailureCause::SingularTangent => "singular tangent",
            FailureCause::IllConditioning => "ill-conditioning",
            FailureCause::IterationLimit => "iteration limit",
            FailureCause::QpInfeasible => "QP infeasible",
            FailureCause::LineSearchFailed => "line search failed",
            FailureCause::InvalidInput => "invalid input",
            FailureCause::Timeout => "timeout",
            FailureCause::Panic => "panic",
            FailureCause::Other => "other",
        }
    }

    /// A two- or three-letter code for a heat-map cell ("IT").
    pub fn code(self) -> &'static str {
        match self {
            FailureCause::Divergence => "DIV",
            FailureCause::SingularTangent => "SNG",
            FailureCause::IllConditioning => "ILL",
            FailureCause::IterationLimit => "IT",
            FailureCause::QpInfeasible => "QPI",
            FailureCause::LineSearchFailed => "LS",
            FailureCause::InvalidInput => "INV",
            FailureCause::Timeout => "TO",
            FailureCause::Panic => "PAN",
            FailureCause::Other => "OTH",
        }
    }

    /// The category of an error of the library.
    pub fn classify(err: &Error) -> FailureCause {
        match err {
            Error::InvalidParameter { .. }
            | Error::TooLarge { .. }
            | Error::IndexOutOfRange { .. }
            | Error::DimensionMismatch { .. }
            | Error::Scene { .. } => FailureCause::InvalidInput,
            Error::Singular { .. } => FailureCause::SingularTangent,
            Error::NotPositiveDefinite { .. } | Error::NonPositivePivot { .. } => {
                FailureCause::IllConditioning
            }
            Error::NotConverged { report } => Self::of_statics(&report.status),
            Error::EstimateNotConverged { status, .. } => Self::of_estimate(status),
            Error::NonFinite { .. } => FailureCause::Divergence,
            Error::Io { .. } => FailureCause::Other,
            #[allow(unreachable_patterns)]
            _ => FailureCause::Other,
        }
    }

    /// The category of a static solve that did not converge.
    ///
    /// # Example
    /// ```
    /// use softrod::report::sweep::FailureCause;
    /// use softrod::statics::StaticStatus;
    /// let s = StaticStatus::LoadStepTooSmall { load_fraction: 0.5 };
    /// assert_eq!(FailureCause::of_statics(&s), FailureCause::Divergence);
    /// ```
    pub fn of_statics(status: &StaticStatus) -> FailureCause {
        match status {
            StaticStatus::IterationLimit { .. } => FailureCause::IterationLimit,
            StaticStatus::SingularTangent => FailureCause::SingularTangent,
            StaticStatus::LineSearchFailed => FailureCause::LineSearchFailed,
            StaticStatus::NonFinite { .. } | StaticStatus::LoadStepTooSmall { .. } => {
                FailureCause::Divergence
            }
            StaticStatus::Converged(_) | StaticStatus::Unverified { .. } => FailureCause::Other,
        }
    }

    /// The category of an estimation that did not converge.
    ///
    /// # Example
    /// ```
    /// use clarabel::solver::SolverStatus;
    /// use softrod::{estimate::EstimateStatus, report::sweep::FailureCause};
    /// let s = EstimateStatus::QpNotSolved(SolverStatus::PrimalInfeasible);
    /// assert_eq!(FailureCause::of_estimate(&s), FailureCause::QpInfeasible);
    /// ```
    pub fn of_estimate(status: &EstimateStatus) -> FailureCause {
        match status {
            EstimateStatus::IterationLimit { .. } => FailureCause::IterationLimit,
            EstimateStatus::LineSearchFailed => FailureCause::LineSearchFailed,
            EstimateStatus::QpNotSolved(s) => match s {
                SolverStatus::PrimalInfeasible
                | SolverStatus::DualInfeasible
                | SolverStatus::AlmostPrimalInfeasible
                | SolverStatus::AlmostDualInfeasible => FailureCause::QpInfeasible,
                SolverStatus::MaxIterations => FailureCause::IterationLimit,
                _ => FailureCause::IllConditioning,
            },
            EstimateStatus::SingularTangent => FailureCause::SingularTangent,
            EstimateStatus::NotPositiveDefinite => FailureCause::IllConditioning,
            EstimateStatus::NonFinite { .. } => FailureCause::Divergence,
            EstimateStatus::Converged(_)
            | EstimateStatus::NoInformation
            | EstimateStatus::MisfitBeyondNoise { .. } => FailureCause::Other,
        }
    }
}

/// Everything that defines one case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseSpec {
    /// The estimator backend.
    pub backend: Backend,
    /// The reference (truth) the markers come from.
    #[serde(serialize_with = "ser_reference_name")]
    pub reference: Arc<Reference>,
    /// Elements of the estimator's model (split evenly over the sections).
    pub elements: usize,
    /// Position markers, equally spaced at `s = L j / markers`, `j = 1..=markers`.
    pub markers: usize,
    /// Standard deviation of the seeded Gaussian noise on each marker
    /// coordinate (m); 0: exact markers.
    pub noise_m: f64,
    /// The noise the estimator is told (m, `noise_sigma_m`): the true noise,
    /// but at least 0.01 mm (the settings need σ > 0).
    pub declared_noise_m: f64,
    /// Fixed `α` (m/N²), or `None` for the discrepancy principle.
    pub alpha: Option<f64>,
    /// Largest marker displacement (m) between the previous frame and the
    /// measured one (see [`run_case`]).
    pub jump_m: f64,
    /// Warm frames after the first (noisy re-measurements of the same shape,
    /// each timed); 0: the measured frame only.
    pub warm_frames: usize,
    /// Seed of the noise.
    pub seed: u64,
    /// Iteration budget of the estimator per observation.
    pub max_iterations: usize,
}

fn ser_reference_name<S: serde::Serializer>(
    r: &Arc<Reference>,
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    s.serialize_str(&r.name)
}

/// Errors of an estimate against the reference.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CaseErrors {
    /// RMS distance between the estimated and the reference backbone over
    /// `BACKBONE_POINTS` evenly spaced arc coordinates (m).
    pub backbone_rms_m: f64,
    /// Relative L2 error of the load field, `‖w − w_ref‖ / ‖w_ref‖` over
    /// `LOAD_POINTS` arc coordinates.
    pub load_rel_l2: f64,
    /// Relative error of the resultant force, `|R − R_ref| / |R_ref|`.
    pub force_rel: f64,
}

/// Arc points of the backbone RMS.
pub(crate) const BACKBONE_POINTS: usize = 241;
/// Arc points of the load error.
pub(crate) const LOAD_POINTS: usize = 481;

/// The step of a case at which it failed.
///
/// # Example
/// ```
/// use softrod::report::sweep::Stage;
/// assert_eq!(Stage::WarmFrame(3).to_string(), "warm frame 3");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// Building the model or the estimator.
    Setup,
    /// The first (cold) frame.
    FirstFrame,
    /// The previous frame of a jump.
    PreviousFrame,
    /// The measured frame.
    MeasuredFrame,
    /// The `k`-th warm frame after it.
    WarmFrame(usize),
    /// Not known (a panic or a timeout of the guarded case).
    Unknown,
}

impl std::fmt::Display for Stage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Stage::Setup => write!(f, "setup"),
            Stage::FirstFrame => write!(f, "first frame"),
            Stage::PreviousFrame => write!(f, "previous frame"),
            Stage::MeasuredFrame => write!(f, "measured frame"),
            Stage::WarmFrame(k) => write!(f, "warm frame {k}"),
            Stage::Unknown => write!(f, "unknown"),
        }
    }
}

/// Why a case failed.
///
/// # Example
/// ```
/// use softrod::report::sweep::{CaseFailure, FailureCause, Stage};
/// let f = CaseFailure { cause: FailureCause::Timeout, estimator: None, at: Stage::Unknown,
///                       message: "no result within 60 s".into() };
/// assert_eq!(serde_json::to_value(&f).unwrap()["at"], "unknown");
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CaseFailure {
    /// The category.
    pub cause: FailureCause,
    /// The estimator's status, when it returned an estimate that did not
    /// converge.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimator: Option<EstimateStatus>,
    /// Where.
    pub at: Stage,
    /// The error message or the failed report, for people.
    pub message: String,
}

/// How a case ended.
///
/// # Example
/// ```
/// use softrod::report::sweep::CaseStatus;
/// assert!(CaseStatus::Converged.is_converged());
/// assert_eq!(serde_json::to_string(&CaseStatus::Converged).unwrap(), "\"converged\"");
/// ```
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum CaseStatus {
    /// Every step converged.
    Converged,
    /// A step failed.
    Failed(CaseFailure),
}

impl CaseStatus {
    /// Whether every step converged.
    pub fn is_converged(&self) -> bool {
        matches!(self, CaseStatus::Converged)
    }
}

/// The result of one case.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Outcome {
    /// What ran.
    pub spec: CaseSpec,
    /// How it ended.
    pub status: CaseStatus,
    /// Outer iterations of the measured frame's step (or of the failed one).
    pub iterations: usize,
    /// The `α` in use at the end (m/N²), if chosen.
    pub alpha_used: Option<f64>,
    /// Errors against the reference: of the measured frame, or the mean over
    /// the warm frames when there are any; `None` when the case failed.
    pub errors: Option<CaseErrors>,
    /// Median wall time of the warm steps (s), if any ran.
    pub median_step_s: Option<f64>,
    /// Wall time of each warm step (s), in order.
    pub warm_step_s: Vec<f64>,
    /// Wall time of the measured frame's step (s).
    pub step_s: Option<f64>,
    /// Wall time of the whole case (s).
    pub total_s: f64,
}

impl Outcome {
    fn failed(spec: CaseSpec, failure: CaseFailure, total_s: f64) -> Self {
        Outcome {
            spec,
            status: CaseStatus::Failed(failure),
            iterations: 0,
            alpha_used: None,
            errors: None,
            median_step_s: None,
            warm_step_s: Vec::new(),
            step_s: None,
            total_s,
        }
    }

    /// Whether every step converged.
    pub fn is_converged(&self) -> bool {
        self.status.is_converged()
    }

    /// The failure, if the case failed.
    pub fn failure(&self) -> Option<&CaseFailure> {
        match &self.status {
            CaseStatus::Converged => None,
            CaseStatus::Failed(f) => Some(f),
        }
    }

    /// The category of the failure, if the case failed.
    pub fn cause(&self) -> Option<FailureCause> {
        self.failure().map(|f| f.cause)
    }
}

/// A failed step: the failure without its stage, and the iterations taken.
struct StepFailure {
    cause: FailureCause,
    estimator: Option<EstimateStatus>,
    message: String,
    iterations: usize,
}

impl StepFailure {
    fn of_error(err: &Error) -> Self {
        StepFailure {
            cause: FailureCause::classify(err),
            estimator: match err {
                Error::EstimateNotConverged { status, .. } => Some(*status),
                _ => None,
            },
            message: err.to_string(),
            iterations: 0,
        }
    }

    fn at(self, at: Stage) -> CaseFailure {
        CaseFailure {
            cause: self.cause,
            estimator: self.estimator,
            at,
            message: self.message,
        }
    }
}

/// The estimator's model of the reference robot: its sections (weightless,
/// no chambers) with `elements` elements in all, exudyn's clamp (all four
/// base coordinates) and bending rule (3 Gauss points).
///
/// # Errors
/// [`Error::InvalidParameter`] when `elements` is not a positive multiple
/// of the number of sections; the errors of [`RobotSpec::build_planar`].
pub fn model_robot(reference: &Reference, elements: usize) -> Result<Robot<PlanarCable>> {
    let ns = reference.sections.len();
    if elements == 0 || !elements.is_multiple_of(ns) {
        return Err(Error::invalid(
            "elements",
            elements,
            format!("must be a positive multiple of the {ns} sections"),
        ));
    }
    let sections = reference
        .sections
        .iter()
        .map(|s| Section::uniform(s.length_m, s.ea_n, s.ei_nm2, elements / ns))
        .collect();
    let mut spec = RobotSpec::new(sections);
    spec.base = Base {
        clamp: Clamp::Full,
        ..Base::default()
    };
    spec.bending_gauss_points = 3;
    spec.build_planar()
}

/// Arc coordinates of `n` equally spaced markers, `L j / n`, `j = 1..=n` (m).
///
/// # Example
/// ```
/// let s = softrod::report::sweep::marker_arcs(0.24, 4);
/// assert_eq!(s, nalgebra::dvector![0.06, 0.12, 0.18, 0.24]);
/// ```
pub fn marker_arcs(length_m: f64, n: usize) -> nalgebra::DVector<f64> {
    nalgebra::DVector::from_fn(n, |i, _| length_m * (i + 1) as f64 / n as f64)
}

/// The markers of the reference at `arcs`, with seeded noise `sigma` (m).
pub fn observe(reference: &Reference, arcs: &[f64], sigma: f64, seed: u64) -> Observation {
    let obs = Observation {
        markers: arcs
            .iter()
            .map(|&s| MarkerObservation::at_arc(s, reference.position_at(s)))
            .collect(),
    };
    if sigma > 0.0 {
        obs.with_noise(sigma, seed)
    } else {
        obs
    }
}

/// The previous frame of a jump: every marker moved towards its rest position
/// `(s, 0)` on the straight robot (or beyond it), so that the largest marker
/// displacement from `current` is `jump_m`. Blends the measured markers with
/// the unloaded robot's, `y_prev = y + λ (y_rest − y)`.
pub(crate) fn previous_frame(current: &Observation, jump_m: f64) -> Observation {
    let rest = |m: &MarkerObservation| [m.s_m.unwrap_or(0.0), 0.0];
    let dmax = current
        .markers
        .iter()
        .map(|m| {
            let r = rest(m);
            (m.position_m[0] - r[0]).hypot(m.position_m[1] - r[1])
        })
        .fold(0.0f64, f64::max);
    let lambda = if dmax > 0.0 { jump_m / dmax } else { 0.0 };
    Observation {
        markers: current
            .markers
            .iter()
            .map(|m| {
                let r = rest(m);
                let p = nalgebra::Vector2::new(
                    m.position_m[0] + lambda * (r[0] - m.position_m[0]),
                    m.position_m[1] + lambda * (r[1] - m.position_m[1]),
                );
                MarkerObservation::at_arc(m.s_m.unwrap_or(0.0), p)
            })
            .collect(),
    }
}

/// Errors of `e` (estimated on `robot`) against `reference`.
///
/// # Errors
/// [`Error::NonFinite`] when the estimate is not finite.
pub(crate) fn case_errors(
    robot: &Robot<PlanarCable>,
    e: &Estimate,
    reference: &Reference,
) -> Result<CaseErrors> {
    let l = reference.length_m;
    let mut sum = 0.0;
    for i in 0..BACKBONE_POINTS {
        let s = l * i as f64 / (BACKBONE_POINTS - 1) as f64;
        let p = robot.position_at(e.q.as_slice(), s)?;
        let t = reference.position_at(s);
        sum += (p[0] - t[0]).powi(2) + (p[1] - t[1]).powi(2);
    }
    let backbone_rms_m = (sum / BACKBONE_POINTS as f64).sqrt();
    let (mut num, mut den) = (0.0, 0.0);
    for i in 0..LOAD_POINTS {
        let s = l * i as f64 / (LOAD_POINTS - 1) as f64;
        let w = e.load_at(s);
        let t = reference.load_at(s);
        num += (w[0] - t[0]).powi(2) + (w[1] - t[1]).powi(2);
        den += t[0] * t[0] + t[1] * t[1];
    }
    let load_rel_l2 = (num / den.max(f64::MIN_POSITIVE)).sqrt();
    let r = reference.resultant_force_n();
    let f = &e.resultant_force_n;
    let force_rel = (f[0] - r[0]).hypot(f[1] - r[1]) / r[0].hypot(r[1]).max(f64::MIN_POSITIVE);
    let errors = CaseErrors {
        backbone_rms_m,
        load_rel_l2,
        force_rel,
    };
    if [backbone_rms_m, load_rel_l2, force_rel]
        .iter()
        .all(|v| v.is_finite())
    {
        Ok(errors)
    } else {
        Err(Error::NonFinite {
            context: "estimate compared with the reference".into(),
        })
    }
}

/// Runs one case (unguarded: see [`run_guarded`]).
///
/// The estimator first takes a noisy measurement of the shape (cold start;
/// `α` is chosen there when not fixed, so that α comes from a physical
/// frame), then, for a jump, the previous frame: the markers moved back by
/// `jump_m` (`previous_frame`). Then the measured frame (seed `seed`),
/// reached from the previous one: its outcome and errors are recorded. Then
/// `warm_frames` more noisy re-measurements, timed.
pub fn run_case(spec: &CaseSpec) -> Outcome {
    let start = Instant::now();
    let reference = &spec.reference;
    let elapsed = || start.elapsed().as_secs_f64();
    let fail = |f: StepFailure, at: Stage| Outcome {
        iterations: f.iterations,
        ..Outcome::failed(spec.clone(), f.at(at), elapsed())
    };
    let robot = match model_robot(reference, spec.elements) {
        Ok(r) => r,
        Err(e) => return fail(StepFailure::of_error(&e), Stage::Setup),
    };
    let settings = EstimatorSettings {
        backend: spec.backend,
        alpha: spec.alpha,
        // the Pareto chart and the stability map (and the README's tables
        // of them) are for α by the discrepancy principle
        alpha_rule: crate::estimate::AlphaRule::Discrepancy,
        noise_sigma_m: spec.declared_noise_m,
        max_iterations: spec.max_iterations,
        // converged to round-off (the default stops within 0.1 of a
        // standard deviation): the chart compares the backends, which then
        // agree to 1e-6
        statistical_tolerance: 0.0,
        ..EstimatorSettings::default()
    };
    let mut est = match settings.build_for(&robot, &Loads::default()) {
        Ok(e) => e,
        Err(e) => return fail(StepFailure::of_error(&e), Stage::Setup),
    };
    let arcs = marker_arcs(reference.length_m, spec.markers);
    let arcs = arcs.as_slice();
    let measured = observe(reference, arcs, spec.noise_m, spec.seed);
    let first = observe(
        reference,
        arcs,
        spec.noise_m,
        spec.seed.wrapping_add(1_000_003),
    );
    let previous = (spec.jump_m > 0.0).then(|| previous_frame(&measured, spec.jump_m));
    let step = |est: &mut Box<dyn crate::estimate::Estimator>,
                o: &Observation|
     -> std::result::Result<(Estimate, f64), StepFailure> {
        let t = Instant::now();
        match est.step(o) {
            Ok(e) => {
                let dt = t.elapsed().as_secs_f64();
                if !e.report.status.is_converged() {
                    Err(StepFailure {
                        cause: FailureCause::of_estimate(&e.report.status),
                        estimator: Some(e.report.status),
                        message: e.report.to_string(),
                        iterations: e.report.iterations,
                    })
                } else if e.q.iter().chain(&e.f).any(|v| !v.is_finite()) {
                    Err(StepFailure {
                        cause: FailureCause::Divergence,
                        estimator: None,
                        message: "non-finite estimate".into(),
                        iterations: e.report.iterations,
                    })
                } else {
                    Ok((e, dt))
                }
            }
            Err(err) => Err(StepFailure::of_error(&err)),
        }
    };
    if let Err(f) = step(&mut est, &first) {
        return fail(f, Stage::FirstFrame);
    }
    if let Some(previous) = &previous
        && let Err(f) = step(&mut est, previous)
    {
        return Outcome {
            alpha_used: est.alpha(),
            ..fail(f, Stage::PreviousFrame)
        };
    }
    let (e, dt) = match step(&mut est, &measured) {
        Ok(x) => x,
        Err(f) => {
            return Outcome {
                alpha_used: est.alpha(),
                ..fail(f, Stage::MeasuredFrame)
            };
        }
    };
    let iterations = e.report.iterations;
    let first = match case_errors(&robot, &e, reference) {
        Ok(x) => x,
        Err(err) => return fail(StepFailure::of_error(&err), Stage::MeasuredFrame),
    };
    let mut errs = Vec::new();
    let mut times = Vec::new();
    for k in 0..spec.warm_frames {
        let o = observe(
            reference,
            arcs,
            spec.noise_m,
            spec.seed.wrapping_add(1 + k as u64),
        );
        match step(&mut est, &o) {
            Ok((e, dt)) => {
                times.push(dt);
                match case_errors(&robot, &e, reference) {
                    Ok(x) => errs.push(x),
                    Err(err) => return fail(StepFailure::of_error(&err), Stage::WarmFrame(k)),
                }
            }
            Err(f) => return fail(f, Stage::WarmFrame(k)),
        }
    }
    let errors = if errs.is_empty() {
        first
    } else {
        let n = errs.len() as f64;
        CaseErrors {
            backbone_rms_m: errs.iter().map(|x| x.backbone_rms_m).sum::<f64>() / n,
            load_rel_l2: errs.iter().map(|x| x.load_rel_l2).sum::<f64>() / n,
            force_rel: errs.iter().map(|x| x.force_rel).sum::<f64>() / n,
        }
    };
    Outcome {
        spec: spec.clone(),
        status: CaseStatus::Converged,
        iterations,
        alpha_used: est.alpha(),
        errors: Some(errors),
        median_step_s: median(&mut times.clone()),
        warm_step_s: times,
        step_s: Some(dt),
        total_s: elapsed(),
    }
}

/// The median of `v` (sorted in place), `None` when empty.
pub fn median(v: &mut [f64]) -> Option<f64> {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some(0.5 * (v[n / 2 - 1] + v[n / 2])),
    }
}

/// Runs [`run_case`] on its own thread under `catch_unwind`, waiting at most
/// `cap`: a panic becomes [`FailureCause::Panic`], an overrun
/// [`FailureCause::Timeout`] (the thread is left to finish its bounded
/// iterations in the background; its result is discarded).
pub fn run_guarded(spec: &CaseSpec, cap: Duration) -> Outcome {
    run_guarded_with(spec, cap, run_case)
}

/// [`run_guarded`] with another case function (for tests of the guard).
pub fn run_guarded_with(spec: &CaseSpec, cap: Duration, f: fn(&CaseSpec) -> Outcome) -> Outcome {
    let start = Instant::now();
    let (tx, rx) = mpsc::channel();
    let s = spec.clone();
    let spawned = std::thread::Builder::new()
        .name("softrod-report-case".into())
        .spawn(move || {
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| f(&s)));
            // the receiver may have given up (timeout): nothing to do then
            let _ = tx.send(r);
        });
    let guard_failure = |cause, message, at| CaseFailure {
        cause,
        estimator: None,
        at,
        message,
    };
    if let Err(e) = spawned {
        return Outcome::failed(
            spec.clone(),
            guard_failure(
                FailureCause::Other,
                format!("cannot start a thread: {e}"),
                Stage::Setup,
            ),
            0.0,
        );
    }
    match rx.recv_timeout(cap) {
        Ok(Ok(o)) => o,
        Ok(Err(payload)) => {
            let msg = payload
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "panic".to_string());
            Outcome::failed(
                spec.clone(),
                guard_failure(FailureCause::Panic, msg, Stage::Unknown),
                start.elapsed().as_secs_f64(),
            )
        }
        Err(_) => Outcome::failed(
            spec.clone(),
            guard_failure(
                FailureCause::Timeout,
                format!("no result within {:.0} s", cap.as_secs_f64()),
                Stage::Unknown,
            ),
            start.elapsed().as_secs_f64(),
        ),
    }
}
