//! The speed–accuracy sweep: backend × element count × marker count, each
//! configuration estimated on markers sampled from exudyn's 128-element
//! solutions (the Gaussian bump and the uniform load, large deflection), with
//! seeded 0.01 mm noise; error against median time per warm estimate.
//!
//! Per configuration: a cold first step (α by the discrepancy principle), the
//! measured frame, then `warm_frames` noisy re-measurements of the same shape,
//! each step timed. The errors are the mean over the warm frames and the
//! reference cases; the time is the median of all warm steps. Cases run one
//! after another (no parallel timing).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::estimate::Backend;

use super::reference::Reference;
use super::sweep::{CaseSpec, Outcome, median, run_guarded};
use super::{Machine, ReportOptions, plot, progress, write_json};

/// An extra point for the Pareto chart (e.g. where `elements: "auto"` lands),
/// drawn as a labelled star; not part of the front computation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LabelledPoint {
    /// The label next to the point.
    pub label: String,
    /// Median time per estimate (s).
    pub median_step_s: f64,
    /// Backbone RMS error (m).
    pub backbone_rms_m: f64,
    /// Relative L2 error of the load field.
    pub load_rel_l2: f64,
    /// Relative error of the resultant force.
    pub force_rel: f64,
}

/// One configuration of the sweep, its errors pooled over the reference cases.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParetoPoint {
    /// Backend.
    pub backend: Backend,
    /// Elements of the estimator's model.
    pub elements: usize,
    /// Position markers.
    pub markers: usize,
    /// Whether every case of the configuration converged (only those are
    /// plotted and enter the fronts).
    pub converged: bool,
    /// Mean backbone RMS over the cases (m).
    pub backbone_rms_m: f64,
    /// Mean relative L2 error of the load field.
    pub load_rel_l2: f64,
    /// Mean relative error of the resultant force.
    pub force_rel: f64,
    /// Median time of all warm steps of the configuration (s).
    pub median_step_s: f64,
    /// On the front of (time, backbone RMS).
    pub front_backbone: bool,
    /// On the front of (time, load error).
    pub front_load: bool,
    /// On the front of (time, resultant force error).
    pub front_force: bool,
}

/// The grid of the sweep.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParetoGrid {
    /// Backends.
    pub backends: Vec<Backend>,
    /// Element counts of the estimator's model.
    pub elements: Vec<usize>,
    /// Marker counts.
    pub markers: Vec<usize>,
    /// The references (truth).
    pub references: Vec<String>,
    /// Marker noise (m).
    pub noise_m: f64,
    /// Timed warm frames per case.
    pub warm_frames: usize,
}

impl ParetoGrid {
    /// The sweep's case of one configuration on `reference`: the grid's
    /// noise (declared as it is), α by the discrepancy principle, no jump,
    /// the grid's warm frames, seed 7, 100 iterations.
    pub fn case(
        &self,
        backend: Backend,
        reference: Arc<Reference>,
        elements: usize,
        markers: usize,
    ) -> CaseSpec {
        CaseSpec {
            backend,
            reference,
            elements,
            markers,
            noise_m: self.noise_m,
            declared_noise_m: self.noise_m,
            alpha: None,
            jump_m: 0.0,
            warm_frames: self.warm_frames,
            seed: 7,
            max_iterations: 100,
        }
    }

    /// The full grid (`quick = false`, a few minutes) or the test grid.
    pub fn new(quick: bool) -> Self {
        if quick {
            ParetoGrid {
                backends: vec![Backend::Newton, Backend::Sqp],
                elements: vec![4, 8],
                markers: vec![3, 5],
                references: vec!["exudyn_uniform_large".into()],
                noise_m: 1e-5,
                warm_frames: 3,
            }
        } else {
            ParetoGrid {
                backends: vec![Backend::Newton, Backend::Sqp],
                elements: vec![2, 4, 8, 16, 32, 64],
                markers: vec![3, 5, 8, 11],
                references: vec![
                    "exudyn_uniform_large".into(),
                    "exudyn_gaussian_large".into(),
                ],
                noise_m: 1e-5,
                warm_frames: 9,
            }
        }
    }
}

/// The result of the sweep.
#[derive(Debug, Clone, Serialize)]
pub struct ParetoReport {
    /// What this is.
    pub description: String,
    /// The truth the errors are measured against.
    pub truth: String,
    /// The grid.
    pub grid: ParetoGrid,
    /// One point per configuration.
    pub points: Vec<ParetoPoint>,
    /// Every case (configuration × reference).
    pub cases: Vec<Outcome>,
    /// The machine (timings are comparable within one run only).
    pub machine: Machine,
    /// Wall time of the sweep (s).
    pub wall_time_s: f64,
    /// Where `"elements": "auto"` lands (see [`super::auto_point`]).
    pub auto_points: Vec<LabelledPoint>,
    /// Why a marker count has no auto point, if any.
    pub auto_notes: Vec<String>,
}

/// Which points are non-dominated when minimizing both coordinates (time,
/// error): `p` is dominated when some `q` is no worse in both and better in
/// one. Non-finite points are never on the front.
///
/// # Example
/// ```
/// let front = softrod::report::pareto::pareto_front(&[(1.0, 3.0), (2.0, 1.0), (2.0, 2.0)]);
/// assert_eq!(front, vec![true, true, false]);
/// ```
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    pareto_front_tol(points, 0.0)
}

/// [`pareto_front`] with errors that agree within the relative tolerance
/// `rel_tol` counted as equal: `q` dominates `p` when `q.0 ≤ p.0`,
/// `q.1 ≤ p.1 (1 + rel_tol)` and `q` is strictly better in one (`q.0 < p.0`
/// or `q.1 < p.1 (1 − rel_tol)`). Two backends that converge to the same
/// estimate then do not both sit on the front: the faster one does.
///
/// # Example
/// ```
/// use softrod::report::pareto::pareto_front_tol;
/// // the same error (to 1e-9) in twice the time: dominated
/// assert_eq!(pareto_front_tol(&[(1.0, 1.0), (2.0, 1.0 - 1e-9)], 1e-6), vec![true, false]);
/// ```
pub fn pareto_front_tol(points: &[(f64, f64)], rel_tol: f64) -> Vec<bool> {
    let finite = |p: &(f64, f64)| p.0.is_finite() && p.1.is_finite();
    points
        .iter()
        .map(|p| {
            finite(p)
                && !points.iter().any(|q| {
                    finite(q)
                        && q.0 <= p.0
                        && q.1 <= p.1 * (1.0 + rel_tol)
                        && (q.0 < p.0 || q.1 < p.1 * (1.0 - rel_tol))
                })
        })
        .collect()
}

/// Errors within this relative tolerance count as equal on the fronts of
/// the chart (the two backends solve the same problem and agree at
/// convergence to about 1e-9).
pub(crate) const FRONT_TOLERANCE: f64 = 1e-3;

/// Runs the sweep.
///
/// # Errors
/// [`crate::Error::Io`] when an embedded reference is malformed.
pub fn run(opts: &ReportOptions) -> Result<ParetoReport> {
    let start = std::time::Instant::now();
    let grid = ParetoGrid::new(opts.quick);
    let refs: Vec<Arc<Reference>> = grid
        .references
        .iter()
        .map(|n| Reference::embedded(n).map(Arc::new))
        .collect::<Result<_>>()?;
    let mut machine = Machine::detect();
    let mut specs = Vec::new();
    for &backend in &grid.backends {
        for &elements in &grid.elements {
            for &markers in &grid.markers {
                for r in &refs {
                    specs.push(grid.case(backend, r.clone(), elements, markers));
                }
            }
        }
    }
    let pb = progress(specs.len(), opts.quiet, "pareto");
    let mut cases = Vec::with_capacity(specs.len());
    for s in &specs {
        pb.set_message(format!(
            "{} {} el {} markers",
            s.backend.name(),
            s.elements,
            s.markers
        ));
        cases.push(run_guarded(s, opts.case_cap));
        pb.inc(1);
    }
    pb.finish_and_clear();
    machine.sample_load();
    let mut points = Vec::new();
    for &backend in &grid.backends {
        for &elements in &grid.elements {
            for &markers in &grid.markers {
                let mine: Vec<&Outcome> = cases
                    .iter()
                    .filter(|o| {
                        o.spec.backend == backend
                            && o.spec.elements == elements
                            && o.spec.markers == markers
                    })
                    .collect();
                let converged = !mine.is_empty() && mine.iter().all(|o| o.is_converged());
                let errs: Vec<_> = mine.iter().filter_map(|o| o.errors).collect();
                let n = errs.len().max(1) as f64;
                let mut times: Vec<f64> = mine
                    .iter()
                    .flat_map(|o| o.warm_step_s.iter().copied())
                    .collect();
                let mean = |f: fn(&super::sweep::CaseErrors) -> f64| {
                    if converged {
                        errs.iter().map(f).sum::<f64>() / n
                    } else {
                        f64::NAN
                    }
                };
                points.push(ParetoPoint {
                    backend,
                    elements,
                    markers,
                    converged,
                    backbone_rms_m: mean(|e| e.backbone_rms_m),
                    load_rel_l2: mean(|e| e.load_rel_l2),
                    force_rel: mean(|e| e.force_rel),
                    median_step_s: if converged {
                        median(&mut times).unwrap_or(f64::NAN)
                    } else {
                        f64::NAN
                    },
                    front_backbone: false,
                    front_load: false,
                    front_force: false,
                });
            }
        }
    }
    mark_fronts(&mut points);
    Ok(ParetoReport {
        description: "Speed against accuracy of the estimators: each configuration (backend, elements of \
                      the estimator's model, equally spaced position markers) estimates the unknown \
                      distributed load from markers sampled on the reference shapes with seeded noise; \
                      errors are the mean over the warm frames and the references, time the median wall \
                      time of the warm steps (in process, one case at a time)."
            .into(),
        truth: "exudyn ObjectANCFCable2D, 128 elements (reference/*.json by validation/exudyn_cantilever.py): \
                markers and backbone from exudyn's own cubic Hermite interpolation of its nodes; the load \
                is the one applied to exudyn (params.loads). Not computed by softrod."
            .into(),
        grid,
        points,
        cases,
        machine,
        wall_time_s: start.elapsed().as_secs_f64(),
        auto_points: Vec::new(),
        auto_notes: Vec::new(),
    })
}

/// Sets the `front_*` flags of the converged points.
pub(crate) fn mark_fronts(points: &mut [ParetoPoint]) {
    let pick = |f: fn(&ParetoPoint) -> f64, points: &[ParetoPoint]| -> Vec<bool> {
        let xy: Vec<(f64, f64)> = points
            .iter()
            .map(|p| {
                if p.converged {
                    (p.median_step_s, f(p))
                } else {
                    (f64::NAN, f64::NAN)
                }
            })
            .collect();
        pareto_front_tol(&xy, FRONT_TOLERANCE)
    };
    let b = pick(|p| p.backbone_rms_m, points);
    let l = pick(|p| p.load_rel_l2, points);
    let f = pick(|p| p.force_rel, points);
    for (i, p) in points.iter_mut().enumerate() {
        p.front_backbone = b[i];
        p.front_load = l[i];
        p.front_force = f[i];
    }
}

impl ParetoReport {
    /// Writes `pareto.json`, `pareto.png` and `pareto.svg` into `dir`.
    ///
    /// # Errors
    /// [`crate::Error::Io`] when a file cannot be written.
    pub fn write(&self, dir: &Path, extra: &[LabelledPoint]) -> Result<Vec<PathBuf>> {
        #[derive(Serialize)]
        struct Out<'a> {
            #[serde(flatten)]
            report: &'a ParetoReport,
            extra: &'a [LabelledPoint],
        }
        let json = dir.join("pareto.json");
        write_json(
            &json,
            &Out {
                report: self,
                extra,
            },
        )?;
        let mut files = vec![json];
        files.extend(plot::pareto_chart(self, extra, dir)?);
        Ok(files)
    }

    /// The configurations on the backbone-RMS front, fastest first.
    pub fn front_backbone(&self) -> Vec<&ParetoPoint> {
        let mut v: Vec<&ParetoPoint> = self.points.iter().filter(|p| p.front_backbone).collect();
        v.sort_by(|a, b| a.median_step_s.total_cmp(&b.median_step_s));
        v
    }
}
