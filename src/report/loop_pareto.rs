//! The closed loop's speed against its accuracy: mean tracking error against
//! the median step time (estimation + updater + inverse kinematics) over
//! the controller's model size (3, 5, 10, 20, 40 elements over the two
//! sections) and the estimator's backend (Newton, SQP), all against one
//! plant that is none of the models: 80 elements (twice the largest model),
//! `EI` +15 %, actuation gain −10 %, `EA` −5 %, 0.05 mm marker noise, 20 ms
//! regulator lag, a 20 g tip mass the controller is not told about.
//!
//! The path is the tracking figure's circle (5 mm radius, 15 s per turn,
//! after a 3 s hold; scored after the hold); five markers at 48, 96, 144,
//! 192 and 240 mm. Outputs `loop_pareto.{png,svg,json}`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use plotters::coord::Shift;
use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use crate::control::{ClosedLoop, ControllerKind, LoopSettings, TrajectorySpec};
use crate::error::{Error, Result};
use crate::estimate::Backend;
use crate::plant::{PayloadSchedule, PlantSettings, SimulatedPlant};
use crate::scene::Scene;

use super::ReportOptions;
use super::plot::{both, ms};
use super::tracking::guarded;

const FONT: &str = "sans-serif";

/// The model sizes (elements over both sections).
pub const MODEL_ELEMENTS: [usize; 5] = [3, 5, 10, 20, 40];

/// Marker arc coordinates (m).
const MARKERS_M: [f64; 5] = [0.048, 0.096, 0.144, 0.192, 0.24];

/// One model size × backend.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LoopParetoRow {
    /// Elements of the controller's model (both sections).
    pub model_elements: usize,
    /// Estimator backend.
    pub backend: Backend,
    /// Mean tracking error after the hold (m), `None` if the run failed.
    pub mean_error_m: Option<f64>,
    /// Maximum tracking error after the hold (m).
    pub max_error_m: Option<f64>,
    /// Median step time (s).
    pub median_step_time_s: Option<f64>,
    /// Steps.
    pub steps: usize,
    /// Frames whose estimator failed (last good estimate kept).
    pub estimator_kept_last: usize,
    /// Steps whose status was not `ok`.
    pub not_ok: usize,
    /// The failure, if the run failed.
    pub failure: Option<String>,
}

/// The part's results.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LoopParetoReport {
    /// The plant's elements.
    pub plant_elements: usize,
    /// One row per model size × backend.
    pub rows: Vec<LoopParetoRow>,
    /// The machine.
    pub machine: super::Machine,
    /// Wall time (s).
    pub wall_time_s: f64,
}

/// The model of `elements` over the two sections of `base` (the first gets
/// the odd one).
fn model_scene(base: &Scene, elements: usize) -> Scene {
    let mut s = base.clone();
    let n = s.robot.sections.len().max(1);
    for (i, sec) in s.robot.sections.iter_mut().enumerate() {
        sec.elements = elements / n + usize::from(i < elements % n);
    }
    s
}

fn one(
    base: &Scene,
    elements: usize,
    backend: Backend,
    spec: &TrajectorySpec,
    hold_s: f64,
) -> Result<LoopParetoRow> {
    let model = model_scene(base, elements);
    let robot = model.robot()?;
    // the plant: 4 x the 20-element scene = 80 elements for every model
    let plant_settings = PlantSettings {
        mesh_factor: 4,
        payloads: PayloadSchedule::tip_mass(0.02, 0.24),
        ..Default::default()
    };
    let plant_base = model_scene(base, 20);
    let mut plant = SimulatedPlant::new(&plant_base, &MARKERS_M, plant_settings)?;
    let trajectory = crate::control::build_trajectory(base, spec)?;
    let mut settings = LoopSettings {
        controller: ControllerKind::FfUpdater,
        ..Default::default()
    };
    settings.estimator.backend = backend;
    let mut lp = ClosedLoop::new(robot, model.loads()?, &MARKERS_M, settings)?;
    let series = lp.run(&mut plant, &trajectory, |p| p.true_tip_m().ok())?;
    let (mean, max) = series.mean_max_after(hold_s);
    let mut steps: Vec<f64> = series.samples.iter().map(|s| s.step_time_s).collect();
    steps.sort_by(f64::total_cmp);
    Ok(LoopParetoRow {
        model_elements: elements,
        backend,
        mean_error_m: Some(mean),
        max_error_m: Some(max),
        median_step_time_s: steps.get(steps.len() / 2).copied(),
        steps: steps.len(),
        estimator_kept_last: series
            .samples
            .iter()
            .filter(|s| !matches!(s.estimate, crate::control::EstimateFlag::Converged))
            .count(),
        not_ok: series.samples.iter().filter(|s| !s.status.is_ok()).count(),
        failure: None,
    })
}

/// Runs every model size × backend (`quick`: 3 and 10 elements, Newton, a
/// 3 s circle).
///
/// # Errors
/// None in practice: a failing case is a row with its failure.
pub fn run(opts: &ReportOptions) -> Result<LoopParetoReport> {
    let start = Instant::now();
    let mut machine = super::Machine::detect();
    let base = super::tracking::scene();
    let (spec_name, spec) = super::tracking::trajectories(opts.quick)
        .into_iter()
        .next()
        .ok_or_else(|| Error::invalid("trajectory", "none", "the report has no trajectory"))?;
    let _ = spec_name;
    let hold = spec.hold_s();
    let sizes: Vec<usize> = if opts.quick {
        vec![3, 10]
    } else {
        MODEL_ELEMENTS.to_vec()
    };
    let backends: Vec<Backend> = if opts.quick {
        vec![Backend::Newton]
    } else {
        vec![Backend::Newton, Backend::Sqp]
    };
    let pb = super::progress(sizes.len() * backends.len(), opts.quiet, "loop speed");
    let mut rows = Vec::new();
    // one at a time: the step times are the measurement
    for &b in &backends {
        for &n in &sizes {
            pb.set_message(format!("{n} elements, {b:?}"));
            let (base, spec) = (base.clone(), spec.clone());
            let row = match guarded(opts.case_cap, move || one(&base, n, b, &spec, hold)) {
                Ok(Ok(r)) => r,
                Ok(Err(e)) => failed(n, b, e.to_string()),
                Err(e) => failed(n, b, e),
            };
            rows.push(row);
            pb.inc(1);
        }
    }
    pb.finish_and_clear();
    machine.sample_load();
    Ok(LoopParetoReport {
        plant_elements: 80,
        rows,
        machine,
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}

fn failed(n: usize, b: Backend, failure: String) -> LoopParetoRow {
    LoopParetoRow {
        model_elements: n,
        backend: b,
        mean_error_m: None,
        max_error_m: None,
        median_step_time_s: None,
        steps: 0,
        estimator_kept_last: 0,
        not_ok: 0,
        failure: Some(failure),
    }
}

fn log_range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && *x > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    if !(lo.is_finite() && hi > 0.0) {
        return (1e-3, 1.0);
    }
    (lo / 2.0, hi * 2.0)
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    r: &LoopParetoReport,
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(ms)?;
    let pts: Vec<(f64, f64)> = r
        .rows
        .iter()
        .filter_map(|x| Some((x.median_step_time_s? * 1e3, x.mean_error_m? * 1e3)))
        .collect();
    let (t0, t1) = log_range(pts.iter().map(|p| p.0));
    let (e0, e1) = log_range(pts.iter().map(|p| p.1));
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!(
                "Closed loop: speed against accuracy (model 3-40 elements, plant {} elements, EI +15 %, gain -10 %, EA -5 %, 20 g tip, 0.05 mm noise)",
                r.plant_elements
            ),
            (FONT, 15),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(65)
        .build_cartesian_2d((t0..t1).log_scale(), (e0..e1).log_scale())
        .map_err(ms)?;
    chart
        .configure_mesh()
        .x_desc("median step time: estimation + updater + IK (ms)")
        .y_desc("mean tracking error after the hold (mm)")
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        // rounded (a log axis's key points print as 0.30000000000000004)
        .x_label_formatter(&|v| super::plot::fmt_tick(*v))
        .y_label_formatter(&|v| super::plot::fmt_tick(*v))
        .draw()
        .map_err(ms)?;
    for (b, colour) in [
        (Backend::Newton, RGBColor(31, 119, 180)),
        (Backend::Sqp, RGBColor(214, 39, 40)),
    ] {
        let mut line: Vec<(f64, f64, usize)> = r
            .rows
            .iter()
            .filter(|x| x.backend == b)
            .filter_map(|x| {
                Some((
                    x.median_step_time_s? * 1e3,
                    x.mean_error_m? * 1e3,
                    x.model_elements,
                ))
            })
            .collect();
        if line.is_empty() {
            continue;
        }
        line.sort_by_key(|p| p.2);
        chart
            .draw_series(LineSeries::new(
                line.iter().map(|p| (p.0, p.1)),
                colour.stroke_width(2),
            ))
            .map_err(ms)?
            .label(format!("{b:?}"))
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(
                line.iter()
                    .map(|p| Circle::new((p.0, p.1), 5, colour.filled())),
            )
            .map_err(ms)?;
        chart
            .draw_series(line.iter().map(|p| {
                Text::new(
                    format!("{} el", p.2),
                    (p.0 * 1.04, p.1 * 1.08),
                    (FONT, 12).into_font().color(&colour),
                )
            }))
            .map_err(ms)?;
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(ms)?;
    Ok(())
}

impl LoopParetoReport {
    /// Writes `loop_pareto.{png,svg,json}`.
    ///
    /// # Errors
    /// [`crate::Error::Io`] when a file cannot be written.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let mut files = both(
            dir,
            "loop_pareto",
            (1100, 700),
            |a| draw(a, self),
            |a| draw(a, self),
        )?;
        let json = dir.join("loop_pareto.json");
        super::write_json(&json, self)?;
        files.push(json);
        Ok(files)
    }
}
