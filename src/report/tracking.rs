//! The closed loop's figures (Fig. 6 and Fig. 8 against the simulated
//! plant): trajectory tracking of the two-section robot, feedforward only
//! against feedforward + updater, per trajectory and payload; and the
//! payload-mass estimation in three configurations.
//!
//! Outputs: `tracking.{png,svg,json}` ((a) desired and tracked paths with a
//! 20 g tip mass, (b) the error over time on the circle with a 20 g tip
//! mass, (c) mean error per payload, both controllers) and
//! `tracking_mass.{png,svg,json}` (estimated against hung mass, three
//! configurations). Every run is guarded (its own thread, `catch_unwind`,
//! the report's per-case time cap, as [`super::sweep::run_guarded`] does for
//! the estimator cases): a failure, a panic or an overrun is a row with its
//! message, never a crash or a hang.

use std::path::{Path, PathBuf};
use std::time::Instant;

use plotters::coord::Shift;
use plotters::prelude::*;
use serde::{Deserialize, Serialize};

use crate::control::{
    CircleSpec, ControllerKind, FigureEightSpec, LineSpec, MassTable, TrackFile, TrackRun,
    TrajectorySpec, WeighingExperiment, run_track,
};
use crate::error::Result;
use crate::plant::{Payload, PayloadKind, PayloadSchedule};
use crate::scene::Scene;

use super::ReportOptions;
use super::plot::{both, ms};

const FONT: &str = "sans-serif";
/// The centre of the example trajectories: the model's end effector at
/// (45, 0, 45, 0) kPa (m).
const CENTER_M: [f64; 2] = [0.1911, 0.1203];

/// One tracking run of the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrackingRow {
    /// Trajectory name.
    pub trajectory: String,
    /// Payload condition.
    pub payload: String,
    /// Controller.
    pub controller: ControllerKind,
    /// Mean error after the hold (m), `None` if the run failed.
    pub mean_error_m: Option<f64>,
    /// Maximum error after the hold (m).
    pub max_error_m: Option<f64>,
    /// Median step time (s).
    pub median_step_time_s: Option<f64>,
    /// Samples whose inverse kinematics did not reach its target.
    pub ik_not_reached: usize,
    /// Frames whose estimator failed (last good estimate kept).
    pub estimator_kept_last: usize,
    /// The failure, if the run failed.
    pub failure: Option<String>,
}

/// The report part's results.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrackingReport {
    /// One row per trajectory × payload × controller.
    pub rows: Vec<TrackingRow>,
    /// The weighings.
    pub mass: Option<MassTable>,
    /// Wall time (s).
    pub wall_time_s: f64,
    /// Plotted series (not written to JSON): (trajectory, payload,
    /// controller) → run.
    #[serde(skip)]
    pub runs: Vec<(String, String, ControllerKind, TrackRun)>,
}

/// The trajectories of the report (`quick`: a short circle).
pub fn trajectories(quick: bool) -> Vec<(String, TrajectorySpec)> {
    let c = Some(CENTER_M.to_vec());
    let hold = 3.0;
    let d = |full: f64| if quick { 3.0 } else { full };
    let mut t = vec![(
        "circle r 5 mm, 15 s".to_string(),
        TrajectorySpec::Circle(CircleSpec {
            center_m: c.clone(),
            radius_m: 0.005,
            period_s: 15.0,
            duration_s: d(15.0),
            hold_s: hold,
        }),
    )];
    if !quick {
        t.push((
            "figure-eight 10 mm, 20 s".into(),
            TrajectorySpec::FigureEight(FigureEightSpec {
                center_m: c,
                size_m: 0.005,
                period_s: 20.0,
                duration_s: 20.0,
                hold_s: hold,
            }),
        ));
        t.push((
            "line 11 mm, 15 s".into(),
            TrajectorySpec::Line(LineSpec {
                from_m: vec![CENTER_M[0] - 0.004, CENTER_M[1] - 0.004],
                to_m: vec![CENTER_M[0] + 0.004, CENTER_M[1] + 0.004],
                period_s: 15.0,
                duration_s: 15.0,
                hold_s: hold,
            }),
        ));
    }
    t
}

/// The payload conditions (`quick`: none and a 20 g tip mass).
pub fn payloads(quick: bool) -> Vec<(String, PayloadSchedule)> {
    let at = |kind, start_s| Payload {
        kind,
        start_s,
        end_s: None,
    };
    let point = |m, s| PayloadKind::PointMass { mass_kg: m, s_m: s };
    let mut p = vec![
        ("none".to_string(), PayloadSchedule::none()),
        ("tip 20 g".into(), PayloadSchedule::tip_mass(0.02, 0.24)),
    ];
    if !quick {
        p.push((
            "distributed 0.1 kg/m".into(),
            PayloadSchedule {
                payloads: vec![at(
                    PayloadKind::Distributed {
                        mass_per_length_kg_per_m: 0.1,
                    },
                    0.0,
                )],
            },
        ));
        p.push((
            "mixed 10 g + 10 g + 0.05 kg/m".into(),
            PayloadSchedule {
                payloads: vec![
                    at(point(0.01, 0.12), 0.0),
                    at(point(0.01, 0.24), 0.0),
                    at(
                        PayloadKind::Distributed {
                            mass_per_length_kg_per_m: 0.05,
                        },
                        0.0,
                    ),
                ],
            },
        ));
        p.push((
            "15 g on at 8 s, sliding".into(),
            PayloadSchedule {
                payloads: vec![at(
                    PayloadKind::Sliding {
                        mass_kg: 0.015,
                        from_s_m: 0.12,
                        to_s_m: 0.24,
                        speed_m_per_s: 0.005,
                    },
                    8.0,
                )],
            },
        ));
    }
    p
}

/// The scene of the report: the two-section robot at (45, 0, 45, 0) kPa.
pub fn scene() -> Scene {
    let mut s = Scene::two_section();
    s.pressures_pa = vec![45e3, 0.0, 45e3, 0.0];
    s
}

/// Runs every tracking case and the weighings.
///
/// # Errors
/// None in practice: a failing case is a row with its failure.
pub fn run(opts: &ReportOptions) -> Result<TrackingReport> {
    let start = Instant::now();
    let scene = scene();
    let trajs = trajectories(opts.quick);
    let pays = payloads(opts.quick);
    let n = trajs.len() * pays.len() * 2;
    let pb = super::progress(n + 1, opts.quiet, "tracking");
    let mut rows = Vec::new();
    let mut runs = Vec::new();
    for (tname, spec) in &trajs {
        for (pname, schedule) in &pays {
            for controller in [ControllerKind::Ff, ControllerKind::FfUpdater] {
                let file = TrackFile {
                    trajectory: spec.clone(),
                    loop_settings: Default::default(),
                    plant: Default::default(),
                    score_from_s: None,
                };
                let outcome = guarded(opts.case_cap, {
                    let scene = scene.clone();
                    let schedule = schedule.clone();
                    move || run_track(&scene, &file, Some(&schedule), Some(controller))
                });
                let row = match outcome {
                    Ok(Ok(r)) => {
                        let s = &r.summary;
                        let row = TrackingRow {
                            trajectory: tname.clone(),
                            payload: pname.clone(),
                            controller,
                            mean_error_m: Some(s.mean_error_m),
                            max_error_m: Some(s.max_error_m),
                            median_step_time_s: Some(s.median_step_time_s),
                            ik_not_reached: s.ik_not_reached,
                            estimator_kept_last: s.estimator_kept_last,
                            failure: None,
                        };
                        runs.push((tname.clone(), pname.clone(), controller, r));
                        row
                    }
                    Ok(Err(e)) => failed(tname, pname, controller, e.to_string()),
                    Err(e) => failed(tname, pname, controller, e),
                };
                rows.push(row);
                pb.inc(1);
            }
        }
    }
    let mut exp = WeighingExperiment::paper_like(Scene::two_section());
    if opts.quick {
        exp.masses_kg = vec![0.0, 0.1, 0.2];
        exp.frames = 3;
    }
    let mass = guarded(opts.case_cap, move || exp.run())
        .ok()
        .and_then(|r| r.ok());
    pb.finish_and_clear();
    Ok(TrackingReport {
        rows,
        mass,
        wall_time_s: start.elapsed().as_secs_f64(),
        runs,
    })
}

/// Runs `f` on its own thread under `catch_unwind`, waiting at most `cap`:
/// a panic or an overrun is an `Err` with what happened (an overrunning
/// thread is left to finish its bounded work; its result is dropped).
pub(crate) fn guarded<T: Send + 'static>(
    cap: std::time::Duration,
    f: impl FnOnce() -> T + Send + 'static,
) -> std::result::Result<T, String> {
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::Builder::new()
        .name("softrod-report-track".into())
        .spawn(move || {
            let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
            let _ = tx.send(r);
        })
        .map_err(|e| format!("cannot start a thread: {e}"))?;
    match rx.recv_timeout(cap) {
        Ok(Ok(v)) => Ok(v),
        Ok(Err(p)) => Err(format!(
            "panic: {}",
            p.downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| p.downcast_ref::<String>().cloned())
                .unwrap_or_default()
        )),
        Err(_) => Err(format!("timeout: over {} s", cap.as_secs_f64())),
    }
}

fn failed(t: &str, p: &str, controller: ControllerKind, failure: String) -> TrackingRow {
    TrackingRow {
        trajectory: t.into(),
        payload: p.into(),
        controller,
        mean_error_m: None,
        max_error_m: None,
        median_step_time_s: None,
        ik_not_reached: 0,
        estimator_kept_last: 0,
        failure: Some(failure),
    }
}

const COLOURS: [RGBColor; 5] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
    RGBColor(148, 103, 189),
    RGBColor(255, 127, 14),
];

fn range(v: impl Iterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(x), b.max(x))
        });
    if lo.is_finite() && hi > lo {
        (lo - pad * (hi - lo), hi + pad * (hi - lo))
    } else {
        (0.0, 1.0)
    }
}

fn log_range(v: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = v
        .filter(|x| x.is_finite() && *x > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
    if !(lo.is_finite() && hi > 0.0) {
        return (1e-3, 1.0);
    }
    (
        10f64.powf(lo.log10().floor()),
        10f64.powf(hi.log10().ceil()).max(lo * 10.0),
    )
}

fn tracking_draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    r: &TrackingReport,
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(ms)?;
    let (title, body) = root.split_vertically(45);
    title
        .draw(&Text::new(
            "Trajectory tracking against the simulated plant (finer mesh, EI +15 %, gain -10 %, EA -5 %, 0.05 mm noise, 20 ms lag), 30 Hz",
            (20, 12),
            (FONT, 19).into_font(),
        ))
        .map_err(ms)?;
    let panels = body.split_evenly((1, 3));
    paths_draw(&panels[0], r)?;
    error_draw(&panels[1], r)?;
    means_draw(&panels[2], r)
}

/// Panel (a) of the tracking chart: the paths with the 20 g tip mass and
/// the updater.
fn paths_draw<DB: DrawingBackend>(
    panel: &DrawingArea<DB, Shift>,
    r: &TrackingReport,
) -> std::result::Result<(), String> {
    // (a) paths, 20 g tip mass, with the updater
    let tip: Vec<&(String, String, ControllerKind, TrackRun)> = r
        .runs
        .iter()
        .filter(|(_, p, c, _)| p == "tip 20 g" && *c == ControllerKind::FfUpdater)
        .collect();
    let xs = tip
        .iter()
        .flat_map(|(_, _, _, run)| run.samples.iter().map(|s| s.desired_m[0] * 1e3));
    let ys = tip
        .iter()
        .flat_map(|(_, _, _, run)| run.samples.iter().map(|s| s.desired_m[1] * 1e3));
    let (x0, x1) = range(xs, 0.1);
    let (y0, y1) = range(ys, 0.1);
    let mut chart = ChartBuilder::on(panel)
        .caption(
            "(a) paths, 20 g tip mass: desired (black), FF + updater",
            (FONT, 16),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(ms)?;
    chart
        .configure_mesh()
        .x_desc("x (mm)")
        .y_desc("y (mm)")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 14))
        .draw()
        .map_err(ms)?;
    for (k, (t, _, _, run)) in tip.iter().enumerate() {
        let c = COLOURS[k % COLOURS.len()];
        chart
            .draw_series(LineSeries::new(
                run.samples
                    .iter()
                    .map(|s| (s.desired_m[0] * 1e3, s.desired_m[1] * 1e3)),
                BLACK.stroke_width(1),
            ))
            .map_err(ms)?;
        chart
            .draw_series(LineSeries::new(
                run.samples
                    .iter()
                    .filter(|s| s.time_s >= run.summary.score_from_s)
                    .map(|s| (s.actual_m[0] * 1e3, s.actual_m[1] * 1e3)),
                c.stroke_width(2),
            ))
            .map_err(ms)?
            .label(t.clone())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], c.stroke_width(2)));
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 12))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(ms)?;
    Ok(())
}

/// Panel (b): the error over time of the first trajectory with the 20 g
/// tip mass, both controllers.
fn error_draw<DB: DrawingBackend>(
    panel: &DrawingArea<DB, Shift>,
    r: &TrackingReport,
) -> std::result::Result<(), String> {
    // (b) error over time, the first trajectory with the 20 g tip mass
    let first = r.runs.first().map(|x| x.0.clone()).unwrap_or_default();
    let series: Vec<&(String, String, ControllerKind, TrackRun)> = r
        .runs
        .iter()
        .filter(|(t, p, _, _)| *t == first && p == "tip 20 g")
        .collect();
    let (e0, e1) = log_range(
        series
            .iter()
            .flat_map(|(_, _, _, run)| run.samples.iter().map(|s| s.error_m * 1e3)),
    );
    let t1 = series
        .iter()
        .flat_map(|(_, _, _, run)| run.samples.last().map(|s| s.time_s))
        .fold(1.0f64, f64::max);
    let mut chart = ChartBuilder::on(panel)
        .caption(
            format!("(b) error over time: {first}, 20 g tip mass"),
            (FONT, 16),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(0.0..t1, (e0..e1).log_scale())
        .map_err(ms)?;
    chart
        .configure_mesh()
        .x_desc("time (s)")
        .y_desc("|tip − desired| (mm)")
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 14))
        .draw()
        .map_err(ms)?;
    for (_, _, c, run) in &series {
        let colour = if *c == ControllerKind::Ff {
            COLOURS[1]
        } else {
            COLOURS[0]
        };
        chart
            .draw_series(LineSeries::new(
                run.samples
                    .iter()
                    .filter(|s| s.error_m > 0.0)
                    .map(|s| (s.time_s, s.error_m * 1e3)),
                colour.stroke_width(2),
            ))
            .map_err(ms)?
            .label(match c {
                ControllerKind::Ff => "feedforward only",
                ControllerKind::FfUpdater => "feedforward + updater",
            })
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], colour.stroke_width(2))
            });
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 12))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(ms)?;
    Ok(())
}

/// Panel (c): the mean error after the hold per payload, trajectory and
/// controller.
fn means_draw<DB: DrawingBackend>(
    panel: &DrawingArea<DB, Shift>,
    r: &TrackingReport,
) -> std::result::Result<(), String> {
    // (c) mean error per payload
    let pays: Vec<String> = {
        let mut v: Vec<String> = Vec::new();
        for row in &r.rows {
            if !v.contains(&row.payload) {
                v.push(row.payload.clone());
            }
        }
        v
    };
    let trajs: Vec<String> = {
        let mut v: Vec<String> = Vec::new();
        for row in &r.rows {
            if !v.contains(&row.trajectory) {
                v.push(row.trajectory.clone());
            }
        }
        v
    };
    let (m0, m1) = log_range(
        r.rows
            .iter()
            .filter_map(|x| x.mean_error_m.map(|e| e * 1e3)),
    );
    let mut chart = ChartBuilder::on(panel)
        .caption(
            "(c) mean error after the 3 s hold: FF (open) vs FF + updater (filled)",
            (FONT, 16),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(-0.5..(pays.len() as f64 - 0.5), (m0..m1).log_scale())
        .map_err(ms)?;
    chart
        .configure_mesh()
        .x_desc(
            "payload: ".to_string()
                + &pays
                    .iter()
                    .enumerate()
                    .map(|(i, p)| format!("{i} {p}"))
                    .collect::<Vec<_>>()
                    .join(", "),
        )
        .y_desc("mean error (mm)")
        .x_labels(pays.len())
        .x_label_formatter(&|v| format!("{}", v.round()))
        .label_style((FONT, 12))
        .axis_desc_style((FONT, 11))
        .draw()
        .map_err(ms)?;
    for (k, t) in trajs.iter().enumerate() {
        let c = COLOURS[k % COLOURS.len()];
        let dx = (k as f64 - (trajs.len() as f64 - 1.0) / 2.0) * 0.15;
        for row in r.rows.iter().filter(|x| &x.trajectory == t) {
            let Some(e) = row.mean_error_m else { continue };
            let Some(i) = pays.iter().position(|p| *p == row.payload) else {
                continue;
            };
            let xy = (i as f64 + dx, e * 1e3);
            let style = if row.controller == ControllerKind::Ff {
                c.stroke_width(2)
            } else {
                c.filled()
            };
            chart
                .draw_series(std::iter::once(Circle::new(xy, 6, style)))
                .map_err(ms)?;
        }
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(ms)?
            .label(t.clone())
            .legend(move |(x, y)| Circle::new((x + 8, y), 5, c.filled()));
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 12))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::MiddleRight)
        .draw()
        .map_err(ms)?;
    Ok(())
}

fn mass_draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    t: &MassTable,
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(ms)?;
    let top = t
        .rows
        .iter()
        .map(|r| r.true_kg.max(r.estimated_kg))
        .fold(0.0f64, f64::max)
        * 1e3
        * 1.08;
    let mut chart = ChartBuilder::on(root)
        .caption(
            format!(
                "Payload mass from the end effector (32)-(35), plant != model; scale {:.3} from one 150 g weighing",
                t.scale
            ),
            (FONT, 16),
        )
        .margin(15)
        .x_label_area_size(45)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..top.max(1.0), 0.0..top.max(1.0))
        .map_err(ms)?;
    chart
        .configure_mesh()
        .x_desc("hung mass (g)")
        .y_desc("estimated mass (g)")
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 15))
        .draw()
        .map_err(ms)?;
    chart
        .draw_series(LineSeries::new(
            vec![(0.0, 0.0), (top, top)],
            BLACK.stroke_width(1),
        ))
        .map_err(ms)?;
    for (c, conf) in t.configurations.iter().enumerate() {
        let colour = COLOURS[c % COLOURS.len()];
        chart
            .draw_series(
                t.rows.iter().filter(|r| r.configuration == c).map(|r| {
                    Circle::new((r.true_kg * 1e3, r.estimated_kg * 1e3), 5, colour.filled())
                }),
            )
            .map_err(ms)?
            .label(format!(
                "{}: mean |error| {:.2} g (raw {:.2} g)",
                conf.name,
                t.mean_abs_error_kg(c, false) * 1e3,
                t.mean_abs_error_kg(c, true) * 1e3
            ))
            .legend(move |(x, y)| Circle::new((x + 8, y), 5, colour.filled()));
    }
    chart
        .configure_series_labels()
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(ms)?;
    Ok(())
}

impl TrackingReport {
    /// Writes `tracking.{png,svg,json}` and `tracking_mass.{png,svg,json}`.
    ///
    /// # Errors
    /// [`crate::Error::Io`] when a file cannot be written.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let mut files = both(
            dir,
            "tracking",
            (1950, 680),
            |a| tracking_draw(a, self),
            |a| tracking_draw(a, self),
        )?;
        let json = dir.join("tracking.json");
        super::write_json(&json, self)?;
        files.push(json);
        if let Some(m) = &self.mass {
            files.extend(both(
                dir,
                "tracking_mass",
                (900, 760),
                |a| mass_draw(a, m),
                |a| mass_draw(a, m),
            )?);
            let json = dir.join("tracking_mass.json");
            super::write_json(&json, m)?;
            files.push(json);
        }
        Ok(files)
    }
}

#[cfg(test)]
#[allow(clippy::panic, clippy::unwrap_used)]
mod tests {
    use std::time::Duration;

    #[test]
    fn guard_turns_a_panic_and_an_overrun_into_failures() {
        let cap = Duration::from_millis(200);
        assert_eq!(super::guarded(cap, || 3).unwrap(), 3);
        // (a panic's backtrace may take a while to print: a long cap)
        let e = super::guarded(Duration::from_secs(30), || -> i32 { panic!("boom") }).unwrap_err();
        assert!(e.starts_with("panic: boom"), "{e}");
        let e = super::guarded(Duration::from_millis(20), || {
            std::thread::sleep(Duration::from_millis(300));
        })
        .unwrap_err();
        assert!(e.starts_with("timeout"), "{e}");
    }
}
