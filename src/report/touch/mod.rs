//! The touch report part: contact localization error against the contact's
//! arc position for both methods (the paper's peak of the estimated load
//! minus the virtual payload, and the point-force search), six markers,
//! σ = 0.05 mm, the plant not the model; and one obstacle-avoidance run by
//! touch (the paper's Fig. 9): the true shapes over time, the obstacle, the
//! contact points learnt by touch, the goal and the end effector's path;
//! and the avoidance table (obstacle placements × goals, by touch and the
//! baseline without it: final error of every run).
//! `touch.png`, `touch.svg`, `touch.json`.

use std::path::PathBuf;

use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;

use crate::contact::{Obstacle, Obstacles};
use crate::error::Result;
use crate::plant::{PlantSettings, SimulatedPlant};
use crate::report::plot::{both, ms};
use crate::report::{ReportOptions, write_json};
use crate::touch::{
    AvoidRun, AvoidSettings, AvoidStatus, ROD_RADIUS_M, calibrate_on_free_plant,
    five_section_scene, marker_arcs, run_avoidance,
};

mod sweep;
mod table;

pub use sweep::{LocalizationCase, LocalizationResult, PROBE_RADIUS_M, run_localization};
pub use table::{AvoidRow, AvoidSummary, FIG9_GOALS, FIG9_PLACEMENTS, avoidance_table};

/// The avoidance run's disk (centre, radius; m) and goal (m).
pub(crate) const AVOID_DISK: ([f64; 2], f64) = ([0.08, -0.465], 0.01);
/// The avoidance run's goal (m).
pub(crate) const AVOID_GOAL: nalgebra::Vector2<f64> = nalgebra::Vector2::new(0.15, -0.40);

/// What the part measured.
#[derive(Debug, Clone, Serialize)]
pub struct TouchReport {
    /// Every localization case (a case the plant cannot make is left out).
    pub localization: Vec<LocalizationResult>,
    /// Mean and largest location error of the peak method (m).
    pub peak_mean_max_m: (f64, f64),
    /// Mean and largest location error of the point search (m).
    pub point_mean_max_m: (f64, f64),
    /// The obstacle of the avoidance run: centre and radius (m).
    pub disk_m: ([f64; 2], f64),
    /// The avoidance run (touch feedback on).
    pub avoidance: AvoidRun,
    /// Length of each run of the table (s).
    pub table_duration_s: f64,
    /// The avoidance table: every placement × goal by touch and the
    /// baseline (quick: the first placement and goal only).
    pub table: Vec<AvoidRow>,
}

impl TouchReport {
    /// [`TouchReport::disk_m`] with its centre as a vector: `(centre, radius)` (m).
    ///
    /// # Example
    /// ```no_run
    /// let opts = softrod::report::ReportOptions { quick: true, ..softrod::report::ReportOptions::new("target/report") };
    /// let (report, _files) = softrod::report::touch::run(&opts)?;
    /// let (centre, radius) = report.disk();
    /// assert!(radius > 0.0 && centre.y < 0.0);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn disk(&self) -> (nalgebra::Vector2<f64>, f64) {
        (nalgebra::Vector2::from(self.disk_m.0), self.disk_m.1)
    }
}

/// Runs the sweep (contact at 0.15 … 0.45 m, intrusion 5 and 10 mm; quick:
/// 0.2, 0.3, 0.4 m at 10 mm), the avoidance run (70 s) and the avoidance
/// table ([`FIG9_PLACEMENTS`] × [`FIG9_GOALS`], 120 s per run; quick: the
/// first of each, 70 s), writes the chart and the JSON into `opts.out_dir`.
///
/// # Errors
/// The avoidance run's errors; [`crate::Error::Io`] for a file that cannot
/// be written. A localization case that fails is left out.
pub fn run(opts: &ReportOptions) -> Result<(TouchReport, Vec<PathBuf>)> {
    let (positions, depths): (Vec<f64>, Vec<f64>) = if opts.quick {
        (vec![0.2, 0.3, 0.4], vec![0.01])
    } else {
        (
            (0..7).map(|k| 0.15 + 0.05 * k as f64).collect(),
            vec![0.005, 0.01],
        )
    };
    // localization cases, the calibration, the avoidance run, the table
    let pb = super::progress(positions.len() * depths.len() + 3, opts.quiet, "touch");
    pb.set_message("contact localization");
    let mut localization = Vec::new();
    for &s in &positions {
        for &d in &depths {
            pb.inc(1);
            if let Ok(r) = run_localization(
                &LocalizationCase::new(s, d, 6, 1),
                4,
                &PlantSettings::default(),
            ) {
                localization.push(r);
            }
        }
    }
    let stats = |f: &dyn Fn(&LocalizationResult) -> f64| {
        let n = localization.len().max(1) as f64;
        (
            localization.iter().map(f).sum::<f64>() / n,
            localization.iter().map(f).fold(0.0, f64::max),
        )
    };
    let peak_mean_max_m = stats(&|r| r.location_errors_m().0);
    let point_mean_max_m = stats(&|r| r.location_errors_m().1);
    let scene = five_section_scene(4);
    let arcs = marker_arcs(6);
    let arcs = arcs.as_slice();
    let ps = PlantSettings::default();
    pb.set_message("calibration on the free plant");
    let cal = calibrate_on_free_plant(&scene, arcs, &ps)?;
    pb.inc(1);
    let (c, radius) = AVOID_DISK;
    let obstacles = Obstacles::new(
        vec![Obstacle::Circle {
            center_m: c,
            radius_m: radius,
        }],
        ROD_RADIUS_M,
    )?;
    let mut plant = SimulatedPlant::new(&scene, arcs, ps)?.with_obstacles(obstacles)?;
    let settings = AvoidSettings {
        duration_s: 70.0,
        shape_interval_s: 5.0,
        ..AvoidSettings::default()
    };
    pb.set_message("avoidance by touch (Fig. 9)");
    let avoidance = run_avoidance(&scene, &cal, arcs, &mut plant, AVOID_GOAL, &settings)?;
    pb.inc(1);
    let (placements, goals, table_duration_s) = if opts.quick {
        (&FIG9_PLACEMENTS[..1], &FIG9_GOALS[..1], 70.0)
    } else {
        (&FIG9_PLACEMENTS[..], &FIG9_GOALS[..], 120.0)
    };
    pb.set_message("avoidance table");
    let table = avoidance_table(
        placements,
        goals,
        &PlantSettings::default(),
        &AvoidSettings {
            duration_s: table_duration_s,
            ..AvoidSettings::default()
        },
    )?;
    pb.finish_and_clear();
    let report = TouchReport {
        localization,
        peak_mean_max_m,
        point_mean_max_m,
        disk_m: AVOID_DISK,
        avoidance,
        table_duration_s,
        table,
    };
    let json = opts.out_dir.join("touch.json");
    write_json(&json, &report)?;
    let mut files = vec![json];
    files.extend(both(
        &opts.out_dir,
        "touch",
        (2100, 700),
        |root| draw(root, &report),
        |root| draw(root, &report),
    )?);
    Ok((report, files))
}

const PEAK: RGBColor = RGBColor(214, 39, 40);
const POINT: RGBColor = RGBColor(31, 119, 180);

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    r: &TouchReport,
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(ms)?;
    let panels = root.split_evenly((1, 3));
    // (a) location error against the contact's arc position
    let ymax = r
        .localization
        .iter()
        .map(|x| x.location_errors_m().0.max(x.location_errors_m().1) * 1e3)
        .fold(10.0, f64::max)
        * 1.1;
    let mut c = ChartBuilder::on(&panels[0])
        .caption(
            "contact localization, 6 markers, σ 0.05 mm",
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(0.1..0.5, 0.0..ymax)
        .map_err(ms)?;
    c.configure_mesh()
        .x_desc("contact arc position s (m)")
        .y_desc("location error (mm)")
        .draw()
        .map_err(ms)?;
    c.draw_series(LineSeries::new(
        [(0.1, 5.0), (0.5, 5.0)],
        BLACK.mix(0.4).stroke_width(1),
    ))
    .map_err(ms)?
    .label("5 mm target")
    .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLACK.mix(0.4)));
    for (name, colour, idx, (mean, max)) in [
        ("peak of the load (paper)", PEAK, 0, r.peak_mean_max_m),
        ("point-force search", POINT, 1, r.point_mean_max_m),
    ] {
        let pts: Vec<(f64, f64)> = r
            .localization
            .iter()
            .map(|x| {
                let e = x.location_errors_m();
                (x.true_s_m, if idx == 0 { e.0 } else { e.1 } * 1e3)
            })
            .collect();
        c.draw_series(pts.iter().map(|&p| Circle::new(p, 5, colour.filled())))
            .map_err(ms)?
            .label(format!(
                "{name}: mean {:.1} mm, max {:.1} mm",
                mean * 1e3,
                max * 1e3
            ))
            .legend(move |(x, y)| Circle::new((x, y), 5, colour.filled()));
    }
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(ms)?;
    // (b) the avoidance run
    let a = &r.avoidance;
    let mut c = ChartBuilder::on(&panels[1])
        .caption(
            match a.status {
                AvoidStatus::Reached { time_s } => {
                    format!("avoidance by touch: goal reached at {time_s:.1} s")
                }
                _ => "avoidance by touch: goal not reached".to_string(),
            },
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(-0.16..0.40, -0.52..0.02)
        .map_err(ms)?;
    c.configure_mesh()
        .x_desc("x (m)")
        .y_desc("y (m)")
        .draw()
        .map_err(ms)?;
    let n = a.shapes.len().max(2) as f64;
    for (k, (t, nodes)) in a.shapes.iter().enumerate() {
        let shade = 0.2 + 0.8 * k as f64 / (n - 1.0);
        let colour = RGBColor(
            (200.0 * (1.0 - shade)) as u8,
            (200.0 * (1.0 - shade)) as u8,
            (200.0 * (1.0 - shade) + 55.0 * shade) as u8,
        );
        let s = c
            .draw_series(LineSeries::new(
                nodes.iter().map(|p| (p[0], p[1])),
                colour.stroke_width(2),
            ))
            .map_err(ms)?;
        if k + 1 == a.shapes.len() {
            s.label(format!("true shape every 5 s (last {t:.0} s)"))
                .legend(move |(x, y)| PathElement::new([(x, y), (x + 16, y)], colour));
        }
    }
    // the obstacle and the robot's reach of it (its radius)
    let (centre, radius) = r.disk_m;
    let ring = |rad: f64| -> Vec<(f64, f64)> {
        (0..=64)
            .map(|i| {
                let th = i as f64 / 64.0 * std::f64::consts::TAU;
                (centre[0] + rad * th.cos(), centre[1] + rad * th.sin())
            })
            .collect()
    };
    c.draw_series(std::iter::once(Polygon::new(ring(radius), BLACK.mix(0.5))))
        .map_err(ms)?
        .label("obstacle (unknown to the controller)")
        .legend(|(x, y)| Circle::new((x, y), 5, BLACK.mix(0.5).filled()));
    let path: Vec<(f64, f64)> = a
        .samples
        .iter()
        .map(|s| (s.tip_true_m[0], s.tip_true_m[1]))
        .collect();
    c.draw_series(LineSeries::new(path, RGBColor(44, 160, 44).stroke_width(1)))
        .map_err(ms)?
        .label("end effector")
        .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], RGBColor(44, 160, 44)));
    c.draw_series(
        a.touched
            .iter()
            .map(|p| Cross::new((p.point_m[0], p.point_m[1]), 7, PEAK.stroke_width(3))),
    )
    .map_err(ms)?
    .label("contact localized by touch")
    .legend(|(x, y)| Cross::new((x, y), 6, PEAK.stroke_width(3)));
    c.draw_series(std::iter::once(TriangleMarker::new(
        (a.goal_m[0], a.goal_m[1]),
        8,
        POINT.filled(),
    )))
    .map_err(ms)?
    .label("goal")
    .legend(|(x, y)| TriangleMarker::new((x, y), 6, POINT.filled()));
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(ms)?;
    draw_table(&panels[2], r)
}

/// (c) the avoidance table: final error of every placement × goal, by
/// touch and the baseline.
fn draw_table<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    r: &TouchReport,
) -> std::result::Result<(), String> {
    let n = r.table.len().max(1) as f64;
    let reached = r
        .table
        .iter()
        .filter(|x| x.touch.status.is_reached())
        .count();
    let base = r
        .table
        .iter()
        .filter(|x| x.baseline.status.is_reached())
        .count();
    let mut c = ChartBuilder::on(area)
        .caption(
            format!(
                "avoidance table: by touch {reached}/{}, baseline {base}/{} reached",
                r.table.len(),
                r.table.len()
            ),
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(0.5..n + 0.5, (0.01..2000.0).log_scale())
        .map_err(ms)?;
    c.configure_mesh()
        .x_desc("placement × goal (row of touch.json's table)")
        .y_desc("final end-effector error (mm)")
        .x_labels(r.table.len().max(2))
        .draw()
        .map_err(ms)?;
    c.draw_series(LineSeries::new(
        [(0.5, 2.0), (n + 0.5, 2.0)],
        BLACK.mix(0.4).stroke_width(1),
    ))
    .map_err(ms)?
    .label("2 mm: reached")
    .legend(|(x, y)| PathElement::new([(x, y), (x + 16, y)], BLACK.mix(0.4)));
    let clip = |v: f64| v.clamp(0.011, 1999.0);
    c.draw_series(r.table.iter().enumerate().map(|(i, x)| {
        Circle::new(
            ((i + 1) as f64, clip(x.touch.final_error_m * 1e3)),
            6,
            POINT.filled(),
        )
    }))
    .map_err(ms)?
    .label(format!("by touch ({} s runs)", r.table_duration_s))
    .legend(|(x, y)| Circle::new((x, y), 5, POINT.filled()));
    c.draw_series(r.table.iter().enumerate().map(|(i, x)| {
        TriangleMarker::new(
            ((i + 1) as f64, clip(x.baseline.final_error_m * 1e3)),
            7,
            PEAK.filled(),
        )
    }))
    .map_err(ms)?
    .label("baseline (no touch feedback)")
    .legend(|(x, y)| TriangleMarker::new((x, y), 5, PEAK.filled()));
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::MiddleLeft)
        .draw()
        .map_err(ms)?;
    Ok(())
}
