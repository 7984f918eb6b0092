//! Model no more than a scene needs: the element counts of
//! `"elements": "auto"` sections, chosen by refinement with an a-posteriori
//! error estimate on a named quantity.
//!
//! # The scene
//!
//! ```json
//! "robot": {"sections": [{"length_m": 0.24, "ea_n": 300, "ei_nm2": 0.025, "elements": "auto"}]},
//! "refinement": {"quantity": "tip_position", "tolerance_m": 1e-5, "max_elements": 2000}
//! ```
//!
//! The quantity is one of
//! - `tip_position` (`tolerance_m`): the tip position of the scene's static
//!   equilibrium under its own loads and pressures;
//! - `load_resultant` (`tolerance_n`): the resultant force of the unknown
//!   load the estimator fits to an observation (the marker positions, given
//!   to [`auto_elements`]; `softrod estimate --markers FILE` on the command
//!   line), with the scene's estimator settings and load model
//!   ([`Scene::estimator_settings`]), except that the estimator converges
//!   to the tight test alone (`statistical_tolerance` 0: the meshes'
//!   exact optima are compared, not estimates stopped within the noise). The markers must be given by arc
//!   coordinate `s_m`: a node index means another point on every mesh.
//!
//! The error of a vector quantity is the Euclidean norm of its error.
//!
//! # The candidate meshes
//!
//! Sections with a fixed count keep it. The auto sections get counts in
//! proportion to their length, at least one each: base counts
//! `c_i = max(1, round(L_i / L_shortest))`, and the candidate of scale
//! `t = 1, 2, 3, …` has `t c_i` elements in auto section `i` ([`Ladder`]).
//! When the scene states that the unknown load acts at a point
//! (`UnknownLoad::Point`) inside an auto section, that section's base count
//! is rounded up to a multiple of the smallest `k` for which a uniform
//! `k`-element mesh of the section has a node there, so every candidate keeps
//! a node at the point, where the estimator puts the concentrated force.
//!
//! # The error estimate
//!
//! The scale is doubled, `t = 1, 2, 4, …`, and the quantity `Q_t` computed
//! at each. With `d_t = |Q_t − Q_{t/2}|`, three successive levels give the
//! observed order `p = log2(d_{t/2} / d_t)`: not assumed (the planar
//! cable's tip converges at order 4 with the default clamp, at order 3 with
//! the full clamp), only bounded: the estimate is trusted when `p ≥`
//! [`MIN_ORDER`] (the differences at least halve), and `p` is capped at
//! [`MAX_ORDER`] (a smaller `p` gives a larger, more cautious estimate).
//! Differences all below [`SETTLED_FRACTION`] of the tolerance are also
//! trusted, with `p = MIN_ORDER` (a quantity the mesh represents exactly
//! converges at round-off, with no order to observe). Richardson's
//! extrapolation from the two finest levels,
//!
//! ```text
//! Q_R = Q_t + (Q_t − Q_{t/2}) / (2^p − 1),
//! ```
//!
//! estimates the converged value, and `e_s = |Q_s − Q_R|` the error of any
//! mesh `s` (for the level below the finest, `d_t 2^p / (2^p − 1)`). The
//! estimate comes with a margin `m`, a bound on how far `Q_R` may be off: the
//! larger of the finest level's own estimated error `|Q_t − Q_R| =
//! d_t / (2^p − 1)` and the distance from `Q_R` of the same extrapolation one
//! level coarser (from `Q_{t/4}`, `Q_{t/2}`), which is large while the
//! levels are not yet asymptotic. The true error then lies in `e_s ± m` (the
//! bracket the tests check against references). In the asymptotic range `m`
//! is a few per cent of `e_s` for the meshes chosen. The tolerance is met by
//! the estimate `e_s`; ask for a smaller tolerance to have it met by the
//! bracket's upper end. The
//! doubling stops at the first level whose estimate meets the tolerance (so
//! the finest solve is one level finer than the mesh chosen). Then a
//! bisection over the scales between the last failing level and the first
//! passing one, each probe compared with the same `Q_R`, finds the smallest
//! scale that passes, assuming the error falls with the scale between the
//! two (true in the asymptotic range the order check asks for). A probe
//! whose solve fails counts as failing.
//!
//! If the next doubling would exceed `max_elements` (all elements, fixed
//! sections included), the refinement stops with
//! [`Error::RefinementNotConverged`] and the history of the meshes tried.
//!
//! # Example
//! ```
//! use softrod::{refine::auto_elements, scene::Scene};
//! let scene = Scene::from_json(r#"{
//!     "robot": {"sections": [{"length_m": 0.24, "ea_n": 300, "ei_nm2": 0.025, "elements": "auto"}]},
//!     "gravity_m_per_s2": [0, 0],
//!     "loads": [{"type": "tip_moment", "moment_nm": 0.1636}],
//!     "refinement": {"quantity": "tip_position", "tolerance_m": 1e-6}}"#)?;
//! let r = auto_elements(&scene, None)?;
//! assert!(r.estimated_error <= 1e-6);
//! assert_eq!(r.scene.robot()?.n_elements(), r.total_elements);
//! println!("{} elements, estimated error {:.1e} m", r.total_elements, r.estimated_error);
//! # Ok::<(), softrod::Error>(())
//! ```

use std::time::Instant;

use nalgebra::SVector;
use serde::Serialize;

use crate::element::{NodeKinematics, PlanarCable};
use crate::error::{Error, Result};
use crate::estimate::{EstimatorSettings, Observation};
pub use crate::scene::Ladder;
use crate::scene::{RefinementTarget, Scene};
use crate::statics::StaticSolver;

pub use crate::outcome::{Phase, Quantity, RefinementFailure, RefinementStop, Trial, TrialFailure};

/// The smallest observed order of convergence the error estimate trusts.
pub const MIN_ORDER: f64 = 1.0;
/// The largest order the error estimate uses (a larger observed one is
/// capped: the estimate then errs on the large side).
pub const MAX_ORDER: f64 = 8.0;
/// Successive differences below this fraction of the tolerance end the
/// doubling whatever their ratio (the quantity has settled at round-off).
pub const SETTLED_FRACTION: f64 = 1.0 / 16.0;

impl Quantity {
    /// The quantity a target names.
    ///
    /// # Example
    /// ```
    /// use softrod::{refine::Quantity, scene::RefinementTarget};
    /// let t = RefinementTarget::TipPosition { tolerance_m: 1e-6, max_elements: 100 };
    /// assert_eq!(Quantity::of(&t), Quantity::TipPosition);
    /// ```
    pub fn of(target: &RefinementTarget) -> Self {
        match target {
            RefinementTarget::TipPosition { .. } => Quantity::TipPosition,
            RefinementTarget::LoadResultant { .. } => Quantity::LoadResultant,
        }
    }
}

/// The outcome of [`auto_elements`].
#[derive(Debug, Clone, PartialEq, Serialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct Refinement {
    /// The quantity controlled.
    pub quantity: Quantity,
    /// Its tolerance (m or N).
    pub tolerance: f64,
    /// The chosen elements per section (fixed sections unchanged).
    pub elements: Vec<usize>,
    /// The chosen elements in all.
    pub total_elements: usize,
    /// The quantity on the chosen mesh (m or N).
    pub value: Vec<f64>,
    /// Estimated error of `value` (m or N; see the [module
    /// documentation](self)); at most `tolerance`.
    pub estimated_error: f64,
    /// The margin of every estimate (m or N): the true error lies within
    /// `estimated_error ± error_margin` when the extrapolated value is off by
    /// less than the finest mesh is.
    pub error_margin: f64,
    /// The order used by the extrapolation: observed, within
    /// [[`MIN_ORDER`], [`MAX_ORDER`]].
    pub observed_order: f64,
    /// The Richardson-extrapolated value `Q_R` (m or N).
    pub extrapolated: Vec<f64>,
    /// Every mesh tried, in order.
    pub history: Vec<Trial>,
    /// The scene with the chosen counts (auto resolved, `refinement`
    /// dropped): build the robot, solve or estimate with it.
    #[serde(skip)]
    pub scene: Scene,
}

impl Refinement {
    /// [`Refinement::value`] as a `D`-vector (m or N).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `value` if it does not have `D`
    /// components.
    ///
    /// # Example
    /// ```
    /// use softrod::{refine::auto_elements, scene::Scene};
    /// let scene = Scene::from_json(r#"{
    ///     "robot": {"sections": [{"length_m": 0.24, "ea_n": 300, "ei_nm2": 0.025, "elements": "auto"}]},
    ///     "gravity_m_per_s2": [0, 0],
    ///     "loads": [{"type": "tip_moment", "moment_nm": 0.1636}],
    ///     "refinement": {"quantity": "tip_position", "tolerance_m": 1e-4}}"#)?;
    /// let r = auto_elements(&scene, None)?;
    /// let tip: nalgebra::Vector2<f64> = r.value_vector::<2>()?;
    /// assert!((tip - r.extrapolated_vector::<2>()?).norm() <= r.estimated_error + r.error_margin);
    /// assert_eq!(r.history.last().map(|t| t.value_vector::<2>().is_ok()), Some(true));
    /// assert!(r.value_vector::<3>().is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn value_vector<const D: usize>(&self) -> Result<SVector<f64, D>> {
        crate::error::check_len("value", D, self.value.len())?;
        Ok(SVector::from_column_slice(&self.value))
    }

    /// [`Refinement::extrapolated`] as a `D`-vector (m or N).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `extrapolated` if it does not
    /// have `D` components.
    ///
    /// # Example
    /// See [`Refinement::value_vector`].
    pub fn extrapolated_vector<const D: usize>(&self) -> Result<SVector<f64, D>> {
        crate::error::check_len("extrapolated", D, self.extrapolated.len())?;
        Ok(SVector::from_column_slice(&self.extrapolated))
    }
}

// The trial record lives in `outcome` (which imports no error type); its
// typed accessor lives here, beside the refinement that makes it.
impl Trial {
    /// [`Trial::value`] as a `D`-vector (m or N), `None` when the mesh
    /// failed.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `value` if it does not
    /// have `D` components.
    ///
    /// # Example
    /// See [`Refinement::value_vector`].
    pub fn value_vector<const D: usize>(&self) -> Result<Option<SVector<f64, D>>> {
        self.value
            .as_ref()
            .map(|v| {
                crate::error::check_len("value", D, v.len())?;
                Ok(SVector::from_column_slice(v))
            })
            .transpose()
    }
}

/// Chooses the element counts of a scene's `"elements": "auto"` sections:
/// the smallest candidate mesh whose estimated error on the scene's
/// `refinement` quantity meets its tolerance (see the
/// [module documentation](self) for the candidates and the estimate).
/// `observation` is the marker positions a `load_resultant` refinement fits
/// (markers by `s_m`); a `tip_position` refinement takes none.
///
/// # Errors
/// The errors of [`Scene::validate`]; [`Error::InvalidParameter`] naming
/// `refinement` when the scene has no auto section, `observation` when it is
/// missing (or given to a `tip_position` refinement), or
/// `observation.markers[i].node` for a marker given by node;
/// [`Error::RefinementNotConverged`] with the history when the tolerance is
/// not reached within `max_elements`; the errors of the solves other than
/// non-convergence (a mesh whose solve does not converge counts as failing).
///
/// # Example
/// See the [module documentation](self).
pub fn auto_elements(scene: &Scene, observation: Option<&Observation>) -> Result<Refinement> {
    scene.validate()?;
    let Some(target) = scene.refinement else {
        return Err(Error::invalid(
            "refinement",
            "none",
            "the scene has no section with \"elements\": \"auto\"",
        ));
    };
    let quantity = Quantity::of(&target);
    let observation = match (quantity, observation) {
        (Quantity::TipPosition, None) => None,
        (Quantity::TipPosition, Some(_)) => {
            return Err(Error::invalid(
                "observation",
                "given",
                "a tip_position refinement solves the scene's statics and uses no observation",
            ));
        }
        (Quantity::LoadResultant, None) => {
            return Err(Error::invalid(
                "observation",
                "none",
                "a load_resultant refinement fits the estimator to an observation: give the \
                 marker positions",
            ));
        }
        (Quantity::LoadResultant, Some(o)) => {
            if let Some((i, m)) = o.markers.iter().enumerate().find(|(_, m)| m.node.is_some()) {
                return Err(Error::invalid(
                    format!("observation.markers[{i}].node"),
                    m.node.unwrap_or_default(),
                    "a node index means another point on every mesh: give the marker's s_m",
                ));
            }
            Some(o)
        }
    };
    let mut run = Run {
        scene,
        ladder: Ladder::new(scene)?,
        quantity,
        observation,
        history: Vec::new(),
    };
    let tol = target.tolerance();
    let max = target.max_elements();

    // doubling: t = 1, 2, 4, … until the level below the finest passes
    let mut levels: Vec<usize> = Vec::new();
    let mut scale = 1usize;
    let (order, extrapolated, margin) = loop {
        let total = run.ladder.total_elements(scale);
        if total > max || scale == usize::MAX {
            let stop = RefinementStop::MeshLimit {
                next_elements: total,
                max_elements: max,
                last_change: levels.last().and_then(|&i| run.history[i].change),
            };
            return Err(run.failure(&target, stop));
        }
        let i = run.trial(scale, Phase::Doubling)?;
        if let Some(&prev) = levels.last() {
            run.history[i].change = distance(&run.history[prev].value, &run.history[i].value);
        }
        levels.push(i);
        if let [.., z, a, b] = levels[..] {
            let h = &run.history;
            if let (Some(d1), Some(d2), Some(q0), Some(q1), Some(q2)) = (
                h[a].change,
                h[b].change,
                &h[z].value,
                &h[a].value,
                &h[b].value,
            ) {
                let observed = (d1 / d2).log2();
                let settled = d1.max(d2) <= SETTLED_FRACTION * tol;
                if observed >= MIN_ORDER || settled {
                    let p = if observed.is_nan() {
                        MIN_ORDER
                    } else {
                        observed.clamp(MIN_ORDER, MAX_ORDER)
                    };
                    let gain = p.exp2();
                    if d2 * gain / (gain - 1.0) <= tol {
                        let q_r = extrapolate(q1, q2, gain);
                        // how far Q_R may be off: no further than the finest
                        // level, nor than the extrapolation one level coarser
                        let coarser = extrapolate(q0, q1, gain);
                        let margin = (d2 / (gain - 1.0))
                            .max(distance(&Some(coarser), &Some(q_r.clone())).unwrap_or(0.0));
                        break (p, q_r, margin);
                    }
                }
            }
        }
        scale = scale.saturating_mul(2);
    };
    let estimate = |value: &Option<Vec<f64>>| distance(value, &Some(extrapolated.clone()));
    for t in &mut run.history {
        t.estimated_error = estimate(&t.value);
    }

    // bisection between the last failing and the first passing scale
    let passes = |t: &Trial| t.estimated_error.is_some_and(|e| e <= tol);
    let mut hi = run
        .history
        .iter()
        .filter(|t| passes(t))
        .map(|t| t.scale)
        .min()
        .unwrap_or(scale);
    let mut lo = run
        .history
        .iter()
        .map(|t| t.scale)
        .filter(|&s| s < hi)
        .max()
        .unwrap_or(0);
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        let i = run.trial(mid, Phase::Search)?;
        let t = &mut run.history[i];
        t.estimated_error = estimate(&t.value);
        if passes(t) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let chosen = run
        .history
        .iter()
        .find(|t| t.scale == hi && passes(t))
        .cloned()
        .ok_or_else(|| Error::NonFinite {
            context: "refinement: the chosen mesh has no estimate".into(),
        })?;
    Ok(Refinement {
        quantity,
        tolerance: tol,
        total_elements: chosen.total_elements,
        value: chosen.value.clone().unwrap_or_default(),
        estimated_error: chosen.estimated_error.unwrap_or(f64::NAN),
        error_margin: margin,
        observed_order: order,
        extrapolated,
        scene: scene.with_elements(&chosen.elements)?,
        elements: chosen.elements,
        history: run.history,
    })
}

/// Richardson's extrapolation `fine + (fine − coarse) / (gain − 1)` of two
/// levels whose error falls by `gain = 2^p` from one to the next.
fn extrapolate(coarse: &[f64], fine: &[f64], gain: f64) -> Vec<f64> {
    fine.iter()
        .zip(coarse)
        .map(|(f, c)| f + (f - c) / (gain - 1.0))
        .collect()
}

/// `|a − b|`, when both are known.
fn distance(a: &Option<Vec<f64>>, b: &Option<Vec<f64>>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) => Some(
            a.iter()
                .zip(b)
                .map(|(x, y)| (x - y) * (x - y))
                .sum::<f64>()
                .sqrt(),
        ),
        _ => None,
    }
}

/// The state of one refinement.
struct Run<'a> {
    scene: &'a Scene,
    ladder: Ladder,
    quantity: Quantity,
    observation: Option<&'a Observation>,
    history: Vec<Trial>,
}

impl Run<'_> {
    /// Computes the quantity at scale `t`, records the trial and returns
    /// its index in the history.
    fn trial(&mut self, t: usize, phase: Phase) -> Result<usize> {
        let elements = self.ladder.elements(t);
        let scene = self.scene.with_elements(&elements)?;
        let start = Instant::now();
        let outcome = match self.quantity {
            Quantity::TipPosition => tip_position(&scene),
            Quantity::LoadResultant => match self.observation {
                Some(o) => load_resultant(&scene, o),
                None => Err(Error::invalid("observation", "none", "required")),
            },
        };
        let (value, failure) = match outcome {
            Ok(Ok(v)) if v.iter().all(|x| x.is_finite()) => (Some(v), None),
            Ok(Ok(_)) => (None, Some(TrialFailure::NonFinite)),
            Ok(Err(f)) => (None, Some(f)),
            Err(Error::NotConverged { report }) => {
                (None, Some(TrialFailure::Statics(report.status)))
            }
            Err(Error::EstimateNotConverged { status, .. }) => {
                (None, Some(TrialFailure::Estimate(status)))
            }
            Err(Error::Singular { .. }) => (None, Some(TrialFailure::Singular)),
            Err(Error::NotPositiveDefinite { .. } | Error::NonPositivePivot { .. }) => {
                (None, Some(TrialFailure::NotPositiveDefinite))
            }
            Err(Error::NonFinite { .. }) => (None, Some(TrialFailure::NonFinite)),
            Err(e) => return Err(e),
        };
        self.history.push(Trial {
            scale: t,
            total_elements: elements.iter().fold(0usize, |a, &n| a.saturating_add(n)),
            elements,
            phase,
            value,
            change: None,
            estimated_error: None,
            failure,
            wall_time_s: start.elapsed().as_secs_f64(),
        });
        Ok(self.history.len() - 1)
    }

    fn failure(self, target: &RefinementTarget, stop: RefinementStop) -> Error {
        Error::RefinementNotConverged {
            report: Box::new(RefinementFailure {
                quantity: Quantity::of(target),
                tolerance: target.tolerance(),
                stop,
                history: self.history,
            }),
        }
    }
}

/// The tip position of the scene's static equilibrium (m).
fn tip_position(scene: &Scene) -> Result<std::result::Result<Vec<f64>, TrialFailure>> {
    let robot = scene.robot()?;
    let loads = scene.loads()?;
    let eq = StaticSolver::new(scene.solver.statics.clone())?.solve(&robot, &loads, None)?;
    let nd = PlanarCable::NODE_DOFS;
    let tip = eq.q.len().saturating_sub(nd);
    Ok(Ok(eq.q.as_slice()[tip..tip + PlanarCable::DIM].to_vec()))
}

/// The resultant force of the unknown load estimated from `observation`
/// (N), or the status of an estimation that did not converge.
fn load_resultant(
    scene: &Scene,
    observation: &Observation,
) -> Result<std::result::Result<Vec<f64>, TrialFailure>> {
    let robot = scene.robot()?;
    let known = scene.loads()?;
    // the refinement compares the exact optima of successive meshes: an
    // estimate stopped within the noise (the statistical test) would put its
    // stopping error, up to a tenth of a standard deviation, into the
    // mesh-to-mesh differences, so the tight test alone decides here
    let settings = EstimatorSettings {
        statistical_tolerance: 0.0,
        ..scene.estimator_settings()?
    };
    let mut estimator = settings.build_for(&robot, &known)?;
    let e = estimator.step(observation)?;
    Ok(if e.report.status.is_converged() {
        Ok(e.resultant_force_n.as_slice().to_vec())
    } else {
        Err(TrialFailure::Estimate(e.report.status))
    })
}
