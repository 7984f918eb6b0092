//! Where the closed loop fails: a coarse grid over the tip payload (0–5 ×
//! the robot's own weight), the plant's `EI` error (−30 … +30 %), the
//! marker noise (0–0.5 mm) and the control rate (5–60 Hz), each case run by
//! [`crate::report::loop_failure::run_case`] (its verdict and cause are documented
//! there). Outputs `loop_failure.{png,svg,json}`: a failure map, one panel
//! per noise × rate, payload across and `EI` error up, each cell coloured by
//! its cause and labelled with its mean error (mm); a `*` marks the
//! payload × `EI` cells whose plant cannot reach the path at all
//! ([`crate::report::loop_failure::plant_reach_m`], 20 points of the scored path).

use std::path::{Path, PathBuf};
use std::time::Instant;

use plotters::coord::Shift;
use plotters::prelude::*;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::Result;

use crate::report::ReportOptions;
use crate::report::plot::{both, ms};
use crate::report::tracking::guarded;

mod grid;

pub use grid::{
    FailureSettings, LoopCase, LoopCause, LoopOutcome, LoopVerdict, case_file, plant_reach_m,
    robot_mass_kg, run_case,
};

const FONT: &str = "sans-serif";

/// The grid's axes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailureGrid {
    /// Tip payload in robot weights.
    pub payload_weights: Vec<f64>,
    /// The plant's `EI` error.
    pub ei_error: Vec<f64>,
    /// Marker noise (m).
    pub noise_sigma_m: Vec<f64>,
    /// Control rate (Hz).
    pub control_rate_hz: Vec<f64>,
}

impl FailureGrid {
    /// The report's grid (`quick`: 2 × 2 × 1 × 2, and the run scores 1 s
    /// of motion instead of 6).
    pub fn new(quick: bool) -> Self {
        if quick {
            FailureGrid {
                payload_weights: vec![0.0, 5.0],
                // +30 % at 5 Hz is a measured marginal case of the full grid
                // (mean 0.51–0.80 mm, "estimate inaccurate"): the quick grid
                // keeps to cases the full grid converges on
                ei_error: vec![-0.3, 0.15],
                noise_sigma_m: vec![1e-4],
                control_rate_hz: vec![5.0, 60.0],
            }
        } else {
            FailureGrid {
                payload_weights: vec![0.0, 0.5, 1.0, 2.0, 5.0],
                ei_error: vec![-0.3, -0.15, 0.0, 0.15, 0.3],
                noise_sigma_m: vec![0.0, 1e-4, 5e-4],
                control_rate_hz: vec![5.0, 15.0, 30.0, 60.0],
            }
        }
    }

    /// Every case (seed 1).
    pub fn cases(&self) -> Vec<LoopCase> {
        let mut v = Vec::new();
        for &noise in &self.noise_sigma_m {
            for &rate in &self.control_rate_hz {
                for &e in &self.ei_error {
                    for &p in &self.payload_weights {
                        v.push(LoopCase {
                            payload_weights: p,
                            ei_error: e,
                            noise_sigma_m: noise,
                            control_rate_hz: rate,
                            seed: 1,
                        });
                    }
                }
            }
        }
        v
    }
}

/// One case: its outcome, or what stopped it (a panic or the report's time
/// cap, neither expected).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailureRow {
    /// The case.
    pub case: LoopCase,
    /// Its outcome.
    pub outcome: Option<LoopOutcome>,
    /// An error, panic or overrun.
    pub failure: Option<String>,
    /// Wall time of the case (s).
    pub wall_time_s: f64,
}

/// How close the plant itself gets to the scored path (see
/// [`plant_reach_m`]) for one payload and `EI` error.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReachRow {
    /// Tip payload in robot weights.
    pub payload_weights: f64,
    /// The plant's `EI` error.
    pub ei_error: f64,
    /// The largest distance of the plant's closest pose to the path (m),
    /// or `None` if it could not be computed.
    pub reach_m: Option<f64>,
    /// Why not, if not.
    pub failure: Option<String>,
}

/// A plant farther than this from the path cannot follow it (m: ten times
/// the inverse kinematics' default tolerance).
pub const UNREACHABLE_M: f64 = 1e-6;

/// The part's results.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct LoopFailureReport {
    /// The grid.
    pub grid: FailureGrid,
    /// How cases were run and judged.
    pub settings: FailureSettings,
    /// The robot's mass (kg): one "weight" of payload.
    pub robot_mass_kg: f64,
    /// One row per case.
    pub rows: Vec<FailureRow>,
    /// The plant's own reach per payload × `EI` error.
    pub plant_reach: Vec<ReachRow>,
    /// Cases per cause whose plant cannot reach the path
    /// ([`UNREACHABLE_M`]).
    pub counts_plant_unreachable: Vec<(LoopCause, usize)>,
    /// Cases per cause.
    pub counts: Vec<(LoopCause, usize)>,
    /// Wall time (s).
    pub wall_time_s: f64,
}

/// Runs the grid (in parallel; each case under the report's guard).
///
/// # Errors
/// None in practice: a failing case is a row.
pub fn run(opts: &ReportOptions) -> Result<LoopFailureReport> {
    let start = Instant::now();
    let scene = crate::report::tracking::scene();
    let grid = FailureGrid::new(opts.quick);
    let mut settings = FailureSettings::default();
    if opts.quick {
        settings.duration_s = 1.0;
    }
    let cases = grid.cases();
    let pb = crate::report::progress(cases.len(), opts.quiet, "loop fails");
    let rows: Vec<FailureRow> = cases
        .par_iter()
        .map(|case| {
            let t = Instant::now();
            let (scene, settings, c) = (scene.clone(), settings.clone(), *case);
            let r = guarded(opts.case_cap, move || run_case(&scene, &c, &settings));
            let (outcome, failure) = match r {
                Ok(Ok(o)) => (Some(o), None),
                Ok(Err(e)) => (None, Some(e.to_string())),
                Err(e) => (None, Some(e)),
            };
            pb.inc(1);
            FailureRow {
                case: *case,
                outcome,
                failure,
                wall_time_s: t.elapsed().as_secs_f64(),
            }
        })
        .collect();
    pb.finish_and_clear();
    let mut pairs = Vec::new();
    for &p in &grid.payload_weights {
        for &e in &grid.ei_error {
            pairs.push((p, e));
        }
    }
    let plant_reach: Vec<ReachRow> = pairs
        .par_iter()
        .map(|&(p, e)| {
            let case = LoopCase {
                payload_weights: p,
                ei_error: e,
                noise_sigma_m: 0.0,
                control_rate_hz: 30.0,
                seed: 1,
            };
            let (scene, settings) = (scene.clone(), settings.clone());
            let r = guarded(opts.case_cap, move || {
                plant_reach_m(&scene, &case, &settings, 20)
            });
            let (reach_m, failure) = match r {
                Ok(Ok(d)) => (Some(d), None),
                Ok(Err(e)) => (None, Some(e.to_string())),
                Err(e) => (None, Some(e)),
            };
            ReachRow {
                payload_weights: p,
                ei_error: e,
                reach_m,
                failure,
            }
        })
        .collect();
    let unreachable = |c: &LoopCase| {
        plant_reach.iter().any(|r| {
            r.payload_weights == c.payload_weights
                && r.ei_error == c.ei_error
                && r.reach_m.is_some_and(|d| d > UNREACHABLE_M)
        })
    };
    let counts_plant_unreachable = LoopCause::ALL
        .iter()
        .map(|c| {
            (
                *c,
                rows.iter()
                    .filter(|r| {
                        unreachable(&r.case) && r.outcome.as_ref().is_some_and(|o| o.cause == *c)
                    })
                    .count(),
            )
        })
        .filter(|(_, n)| *n > 0)
        .collect();
    let counts = LoopCause::ALL
        .iter()
        .map(|c| {
            (
                *c,
                rows.iter()
                    .filter(|r| r.outcome.as_ref().is_some_and(|o| o.cause == *c))
                    .count(),
            )
        })
        .filter(|(_, n)| *n > 0)
        .collect();
    Ok(LoopFailureReport {
        grid,
        robot_mass_kg: crate::report::loop_failure::robot_mass_kg(&scene),
        settings,
        rows,
        plant_reach,
        counts_plant_unreachable,
        counts,
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}

fn cause_colour(c: Option<LoopCause>) -> RGBColor {
    match c {
        Some(LoopCause::None) => RGBColor(120, 200, 120),
        Some(LoopCause::PlantFailure) => RGBColor(90, 90, 90),
        Some(LoopCause::IkUnreachable) => RGBColor(214, 39, 40),
        Some(LoopCause::PressureSaturation) => RGBColor(255, 127, 14),
        Some(LoopCause::EstimatorFailure) => RGBColor(148, 103, 189),
        Some(LoopCause::UpdaterInstability) => RGBColor(31, 119, 180),
        Some(LoopCause::EstimateInaccurate) => RGBColor(230, 210, 90),
        Some(LoopCause::StartFailed) => RGBColor(140, 86, 75),
        Some(LoopCause::Watchdog) => RGBColor(60, 20, 20),
        None => RGBColor(255, 255, 255),
    }
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    r: &LoopFailureReport,
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(ms)?;
    let (title, rest) = root.split_vertically(40);
    title
        .draw(&Text::new(
            format!(
                "Where the closed loop fails (FF + updater, circle 5 mm after a 3 s hold, no watchdog; converged: mean error <= {:.1} mm). Payload x robot weight ({:.0} g) across, plant EI error up; cell: mean error (mm)",
                r.settings.converged_mean_m * 1e3,
                r.robot_mass_kg * 1e3
            ),
            (15, 12),
            (FONT, 15).into_font(),
        ))
        .map_err(ms)?;
    let (body, legend) = rest.split_vertically(rest.dim_in_pixel().1.saturating_sub(40));
    let g = &r.grid;
    let panels = body.split_evenly((g.noise_sigma_m.len(), g.control_rate_hz.len()));
    let np = g.payload_weights.len();
    let ne = g.ei_error.len();
    for (ni, noise) in g.noise_sigma_m.iter().enumerate() {
        for (ri, rate) in g.control_rate_hz.iter().enumerate() {
            let panel = &panels[ni * g.control_rate_hz.len() + ri];
            let mut chart = ChartBuilder::on(panel)
                .caption(
                    format!("noise {:.2} mm, {rate} Hz", noise * 1e3),
                    (FONT, 13),
                )
                .margin(6)
                .x_label_area_size(22)
                .y_label_area_size(38)
                .build_cartesian_2d(-0.5..(np as f64 - 0.5), -0.5..(ne as f64 - 0.5))
                .map_err(ms)?;
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(np)
                .y_labels(ne)
                .x_label_formatter(&|v| {
                    let i = v.round() as usize;
                    g.payload_weights
                        .get(i)
                        .map(|p| format!("{p}x"))
                        .unwrap_or_default()
                })
                .y_label_formatter(&|v| {
                    let i = v.round() as usize;
                    g.ei_error
                        .get(i)
                        .map(|e| format!("{:+.0}%", e * 100.0))
                        .unwrap_or_default()
                })
                .label_style((FONT, 10))
                .draw()
                .map_err(ms)?;
            for row in r
                .rows
                .iter()
                .filter(|x| x.case.noise_sigma_m == *noise && x.case.control_rate_hz == *rate)
            {
                let (Some(i), Some(j)) = (
                    g.payload_weights
                        .iter()
                        .position(|p| *p == row.case.payload_weights),
                    g.ei_error.iter().position(|e| *e == row.case.ei_error),
                ) else {
                    continue;
                };
                let (x, y) = (i as f64, j as f64);
                let cause = row.outcome.as_ref().map(|o| o.cause);
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(x - 0.48, y - 0.48), (x + 0.48, y + 0.48)],
                        cause_colour(cause).filled(),
                    )))
                    .map_err(ms)?;
                let mut label = match row.outcome.as_ref().and_then(|o| o.mean_error_m) {
                    Some(e) if e < 0.01 => format!("{:.2}", e * 1e3),
                    Some(e) => format!("{:.0}", e * 1e3),
                    None => "-".into(),
                };
                if r.plant_unreachable(&row.case) {
                    label.push('*');
                }
                let colour = if matches!(cause, Some(LoopCause::Watchdog)) {
                    WHITE
                } else {
                    BLACK
                };
                chart
                    .draw_series(std::iter::once(Text::new(
                        label,
                        (x - 0.3, y + 0.15),
                        (FONT, 10).into_font().color(&colour),
                    )))
                    .map_err(ms)?;
            }
        }
    }
    // legend: the causes present
    let mut x = 15;
    for (c, n) in &r.counts {
        legend
            .draw(&Rectangle::new(
                [(x, 10), (x + 16, 26)],
                cause_colour(Some(*c)).filled(),
            ))
            .map_err(ms)?;
        let text = format!("{} ({n})", c.label());
        legend
            .draw(&Text::new(
                text.clone(),
                (x + 20, 12),
                (FONT, 13).into_font(),
            ))
            .map_err(ms)?;
        x += 30 + 8 * text.len() as i32;
    }
    legend
        .draw(&Text::new(
            "* the plant itself cannot reach the path with this payload",
            (x, 12),
            (FONT, 13).into_font(),
        ))
        .map_err(ms)?;
    Ok(())
}

impl LoopFailureReport {
    /// Whether the plant of `case` cannot reach the path (its payload and
    /// `EI` error's [`ReachRow`] farther than [`UNREACHABLE_M`]).
    pub fn plant_unreachable(&self, case: &LoopCase) -> bool {
        self.plant_reach.iter().any(|r| {
            r.payload_weights == case.payload_weights
                && r.ei_error == case.ei_error
                && r.reach_m.is_some_and(|d| d > UNREACHABLE_M)
        })
    }

    /// Cases that converged.
    pub fn converged(&self) -> usize {
        self.rows
            .iter()
            .filter(|r| {
                r.outcome
                    .as_ref()
                    .is_some_and(|o| o.verdict == LoopVerdict::Converged)
            })
            .count()
    }

    /// Writes `loop_failure.{png,svg,json}`.
    ///
    /// # Errors
    /// [`crate::Error::Io`] when a file cannot be written.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let mut files = both(
            dir,
            "loop_failure",
            (1500, 900),
            |a| draw(a, self),
            |a| draw(a, self),
        )?;
        let json = dir.join("loop_failure.json");
        crate::report::write_json(&json, self)?;
        files.push(json);
        Ok(files)
    }
}
