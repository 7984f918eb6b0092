//! The stability map: where each estimator fails, and why.
//!
//! Five parameters, swept in pairs (the others at their defaults): marker
//! noise × load magnitude, marker count × the jump between successive
//! observations, `α` × marker noise. The truth is exudyn's family of
//! cantilevers under a uniform load of `k` times the robot's self-weight
//! (`reference/exudyn_family_uniform_*.json`, `k` = 0.1 … 20). Every case
//! records converged or not, the failure cause, iterations and errors
//! ([`Outcome`]); cases run in parallel (rayon), each under guard.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::estimate::Backend;

use super::reference::{FAMILY_FACTORS, Reference, family_name};
use super::sweep::{CaseSpec, FailureCause, Outcome, run_guarded};
use super::{Machine, ReportOptions, plot, progress, write_json};

/// A swept parameter.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Param {
    /// Marker noise σ (m).
    Noise,
    /// Load magnitude: `k` times the robot's self-weight (0.15 kg/m × g).
    Load,
    /// Number of position markers.
    Markers,
    /// Largest marker displacement between the previous and the measured frame (m).
    Jump,
    /// The regularization weight `α` (m/N²); 0 stands for the discrepancy principle.
    Alpha,
}

impl Param {
    /// Axis title with units.
    pub(crate) fn title(self) -> &'static str {
        match self {
            Param::Noise => "marker noise σ (mm)",
            Param::Load => "load (× self-weight)",
            Param::Markers => "markers",
            Param::Jump => "jump between frames (mm)",
            Param::Alpha => "α (m/N²)",
        }
    }

    /// A value as an axis label.
    pub fn label(self, v: f64) -> String {
        match self {
            Param::Noise | Param::Jump => format!("{}", round_sig(v * 1e3)),
            Param::Load => format!("{}", round_sig(v)),
            Param::Markers => format!("{v:.0}"),
            Param::Alpha if v == 0.0 => "auto".into(),
            Param::Alpha => format!("1e{:.0}", v.log10()),
        }
    }
}

fn round_sig(v: f64) -> f64 {
    (v * 1e6).round() / 1e6
}

/// Parameter values of a case.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Marker noise (m).
    pub noise_m: f64,
    /// Load factor `k` (× self-weight).
    pub load_factor: f64,
    /// Markers.
    pub markers: usize,
    /// Jump (m).
    pub jump_m: f64,
    /// `α` (m/N²), 0: discrepancy principle.
    pub alpha: f64,
}

impl Params {
    /// The defaults of the parameters not swept by a map: 0.1 mm noise, 3×
    /// self-weight (tip deflection 68 mm), 5 markers, no jump, α by the
    /// discrepancy principle.
    pub(crate) const DEFAULT: Params = Params {
        noise_m: 1e-4,
        load_factor: 3.0,
        markers: 5,
        jump_m: 0.0,
        alpha: 0.0,
    };

    /// The value of one parameter.
    pub fn get(&self, p: Param) -> f64 {
        match p {
            Param::Noise => self.noise_m,
            Param::Load => self.load_factor,
            Param::Markers => self.markers as f64,
            Param::Jump => self.jump_m,
            Param::Alpha => self.alpha,
        }
    }

    /// With one parameter set.
    pub fn with(mut self, p: Param, v: f64) -> Params {
        match p {
            Param::Noise => self.noise_m = v,
            Param::Load => self.load_factor = v,
            Param::Markers => self.markers = v.round().max(0.0) as usize,
            Param::Jump => self.jump_m = v,
            Param::Alpha => self.alpha = v,
        }
        self
    }
}

/// One heat map: two parameters and their values.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MapSpec {
    /// File-name tag (`stability_<name>.png`).
    pub name: String,
    /// Horizontal parameter.
    pub x: Param,
    /// Its values.
    pub x_values: Vec<f64>,
    /// Vertical parameter.
    pub y: Param,
    /// Its values.
    pub y_values: Vec<f64>,
}

/// The maps of the full (`quick = false`) or the test sweep.
pub fn maps(quick: bool) -> Vec<MapSpec> {
    let m = |name: &str, x, xv: &[f64], y, yv: &[f64]| MapSpec {
        name: name.into(),
        x,
        x_values: xv.to_vec(),
        y,
        y_values: yv.to_vec(),
    };
    if quick {
        vec![
            m(
                "noise_load",
                Param::Noise,
                &[0.0, 2e-3],
                Param::Load,
                &[0.1, 20.0],
            ),
            m(
                "markers_jump",
                Param::Markers,
                &[1.0, 5.0],
                Param::Jump,
                &[0.0, 0.05],
            ),
            m(
                "alpha_noise",
                Param::Alpha,
                &[0.0, 1e-8],
                Param::Noise,
                &[0.0, 2e-3],
            ),
        ]
    } else {
        let noise = [0.0, 5e-5, 2e-4, 5e-4, 1e-3, 2e-3];
        vec![
            m(
                "noise_load",
                Param::Noise,
                &noise,
                Param::Load,
                &FAMILY_FACTORS,
            ),
            m(
                "markers_jump",
                Param::Markers,
                &[1.0, 2.0, 3.0, 5.0, 8.0, 11.0],
                Param::Jump,
                &[0.0, 0.005, 0.01, 0.02, 0.035, 0.05],
            ),
            m(
                "alpha_noise",
                Param::Alpha,
                &[0.0, 1e-8, 1e-6, 1e-4, 1e-2, 1.0, 1e2, 1e4],
                Param::Noise,
                &noise,
            ),
        ]
    }
}

/// Elements of the estimator's model in the stability sweep (the paper's 2 × 10).
pub const ELEMENTS: usize = 20;
/// Iteration budget of the estimator per observation.
pub const MAX_ITERATIONS: usize = 100;

/// One cell of a map.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cell {
    /// The map.
    pub map: String,
    /// Indices of the cell (x, y).
    pub index: (usize, usize),
    /// The parameters.
    pub params: Params,
    /// What happened.
    pub outcome: Outcome,
}

/// The result of the sweep.
#[derive(Debug, Clone, Serialize)]
pub struct StabilityReport {
    /// What this is.
    pub description: String,
    /// The truth.
    pub truth: String,
    /// Parameters not swept by a map.
    pub defaults: Params,
    /// The maps.
    pub maps: Vec<MapSpec>,
    /// Backends.
    pub backends: Vec<Backend>,
    /// Every case.
    pub cells: Vec<Cell>,
    /// Panics among the outcomes (must be 0).
    pub panics: usize,
    /// The machine.
    pub machine: Machine,
    /// Wall time of the sweep (s).
    pub wall_time_s: f64,
}

/// Runs the sweep.
///
/// # Errors
/// [`crate::Error::Io`] when an embedded reference is malformed or missing.
pub fn run(opts: &ReportOptions) -> Result<StabilityReport> {
    let start = std::time::Instant::now();
    let maps = maps(opts.quick);
    let backends = vec![Backend::Newton, Backend::Sqp];
    let mut family: BTreeMap<String, Arc<Reference>> = BTreeMap::new();
    for k in FAMILY_FACTORS {
        let n = family_name(k);
        family.insert(n.clone(), Arc::new(Reference::embedded(&n)?));
    }
    let mut jobs = Vec::new();
    for map in &maps {
        for (iy, &yv) in map.y_values.iter().enumerate() {
            for (ix, &xv) in map.x_values.iter().enumerate() {
                let p = Params::DEFAULT.with(map.x, xv).with(map.y, yv);
                let name = family_name(p.load_factor);
                let reference = family.get(&name).cloned().ok_or_else(|| crate::Error::Io {
                    path: format!("reference/{name}.json"),
                    message: "no embedded reference for this load factor".into(),
                })?;
                for &backend in &backends {
                    jobs.push((map.name.clone(), (ix, iy), p, backend, reference.clone()));
                }
            }
        }
    }
    let mut machine = Machine::detect();
    let pb = progress(jobs.len(), opts.quiet, "stability");
    let cells: Vec<Cell> = jobs
        .par_iter()
        .map(|(map, index, p, backend, reference)| {
            let spec = CaseSpec {
                backend: *backend,
                reference: reference.clone(),
                elements: ELEMENTS,
                markers: p.markers,
                noise_m: p.noise_m,
                declared_noise_m: p.noise_m.max(1e-5),
                alpha: (p.alpha > 0.0).then_some(p.alpha),
                jump_m: p.jump_m,
                warm_frames: 0,
                seed: 11,
                max_iterations: MAX_ITERATIONS,
            };
            let outcome = run_guarded(&spec, opts.case_cap);
            pb.inc(1);
            Cell {
                map: map.clone(),
                index: *index,
                params: *p,
                outcome,
            }
        })
        .collect();
    pb.finish_and_clear();
    machine.sample_load();
    let panics = cells
        .iter()
        .filter(|c| c.outcome.cause() == Some(FailureCause::Panic))
        .count();
    Ok(StabilityReport {
        description: "Stability of the estimators: pairs of parameters swept with the others at their \
                      defaults; each case takes a first noisy frame of the true shape (cold start, α \
                      chosen there unless fixed), for a jump a previous frame (the markers moved back \
                      towards the straight robot by the jump), then the measured frame, whose outcome \
                      and errors are recorded. The \
                      estimator's model has 20 elements (2 sections × 10), exudyn's clamp; σ declared \
                      to the estimator = the true noise, at least 0.01 mm."
            .into(),
        truth: "exudyn ObjectANCFCable2D, 128 elements, uniform load k × 0.15 kg/m × 9.81 m/s² \
                (reference/exudyn_family_uniform_*.json by validation/exudyn_load_family.py). Not \
                computed by softrod."
            .into(),
        defaults: Params::DEFAULT,
        maps,
        backends,
        cells,
        panics,
        machine,
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}

impl StabilityReport {
    /// The cells of one map for one backend.
    pub(crate) fn cells_of(&self, map: &str, backend: Backend) -> Vec<&Cell> {
        self.cells
            .iter()
            .filter(|c| c.map == map && c.outcome.spec.backend == backend)
            .collect()
    }

    /// The Markdown table "where each method fails, and why".
    pub fn markdown(&self) -> String {
        let mut s = String::new();
        s.push_str("| backend | map | converged | failures by cause | where it fails | worst converged backbone RMS | slowest case |\n");
        s.push_str("|---|---|---|---|---|---|---|\n");
        for &b in &self.backends {
            for map in &self.maps {
                let cells = self.cells_of(&map.name, b);
                let ok = cells.iter().filter(|c| c.outcome.is_converged()).count();
                let mut by: BTreeMap<FailureCause, Vec<String>> = BTreeMap::new();
                for c in cells.iter().filter(|c| !c.outcome.is_converged()) {
                    let cause = c.outcome.cause().unwrap_or(FailureCause::Other);
                    by.entry(cause).or_default().push(format!(
                        "{} {}, {} {}",
                        short(map.x),
                        map.x.label(c.params.get(map.x)),
                        short(map.y),
                        map.y.label(c.params.get(map.y))
                    ));
                }
                let causes = if by.is_empty() {
                    "—".to_string()
                } else {
                    by.iter()
                        .map(|(c, v)| format!("{} × {}", v.len(), c.label()))
                        .collect::<Vec<_>>()
                        .join("; ")
                };
                let wherestr = if by.is_empty() {
                    "—".to_string()
                } else {
                    by.iter()
                        .map(|(c, v)| {
                            let more = if v.len() > 12 {
                                format!(" (+{} more)", v.len() - 12)
                            } else {
                                String::new()
                            };
                            format!(
                                "{}: {}{}",
                                c.code(),
                                v.iter().take(12).cloned().collect::<Vec<_>>().join("; "),
                                more
                            )
                        })
                        .collect::<Vec<_>>()
                        .join("<br>")
                };
                let worst = cells
                    .iter()
                    .filter_map(|c| c.outcome.errors.map(|e| (e.backbone_rms_m, c)))
                    .max_by(|a, b| a.0.total_cmp(&b.0))
                    .map(|(e, c)| {
                        format!(
                            "{:.3} mm ({} {}, {} {})",
                            e * 1e3,
                            short(map.x),
                            map.x.label(c.params.get(map.x)),
                            short(map.y),
                            map.y.label(c.params.get(map.y))
                        )
                    })
                    .unwrap_or_else(|| "—".into());
                let slowest = cells
                    .iter()
                    .map(|c| c.outcome.total_s)
                    .fold(0.0f64, f64::max);
                s.push_str(&format!(
                    "| {} | {} × {} | {}/{} | {} | {} | {} | {:.2} s |\n",
                    b.name(),
                    map.x.title(),
                    map.y.title(),
                    ok,
                    cells.len(),
                    causes,
                    wherestr,
                    worst,
                    slowest
                ));
            }
        }
        s.push_str(&format!(
            "\nCodes: {}. Panics: {}. Defaults of the parameters a map does not sweep: noise {} mm, load {}× self-weight, {} markers, jump {} mm, α auto (discrepancy principle); model: {} elements.\n",
            FailureCause::ALL
                .iter()
                .map(|c| format!("{} = {}", c.code(), c.label()))
                .collect::<Vec<_>>()
                .join(", "),
            self.panics,
            Params::DEFAULT.noise_m * 1e3,
            Params::DEFAULT.load_factor,
            Params::DEFAULT.markers,
            Params::DEFAULT.jump_m * 1e3,
            ELEMENTS
        ));
        s
    }

    /// Writes `stability.json`, `stability.md` and the heat maps into `dir`.
    ///
    /// # Errors
    /// [`crate::Error::Io`] when a file cannot be written.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let json = dir.join("stability.json");
        write_json(&json, self)?;
        let md = dir.join("stability.md");
        let text = format!(
            "# Where each method fails, and why\n\nGenerated by `softrod report` ({} cases, {:.0} s). Truth: {}\n\n{}",
            self.cells.len(),
            self.wall_time_s,
            self.truth,
            self.markdown()
        );
        super::atomic::write_atomic(&md, text.as_bytes())?;
        let mut files = vec![json, md];
        for map in &self.maps {
            files.extend(plot::stability_map(self, map, dir)?);
        }
        Ok(files)
    }
}

fn short(p: Param) -> &'static str {
    match p {
        Param::Noise => "noise (mm)",
        Param::Load => "load ×",
        Param::Markers => "markers",
        Param::Jump => "jump (mm)",
        Param::Alpha => "α",
    }
}
