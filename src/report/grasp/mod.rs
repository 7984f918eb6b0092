//! The grasp's report part: Table I in simulation (the nine objects of
//! [`crate::report::grasp::table`], five seeded placements each, both strategies;
//! quick: the plastic bottle once) and one grasp sequence per strategy
//! (finger shapes over time, the object at the start and at the end, the
//! contact forces after the lift), on the red apple's first placement
//! (quick: the bottle's). `grasp.png`, `grasp.svg`, `grasp.json`,
//! `grasp.md` (the success table).

use std::path::PathBuf;

use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;

use crate::contact::Obstacle;
use crate::error::Result;
use crate::grasp::gripper::GripperSpec;
use crate::grasp::object::GraspObject;
use crate::report::{ReportOptions, write_json};

pub mod table;

use crate::grasp::trial::{GraspSettings, Strategy, TrialOutcome};
use table::{TableRow, run_table, table_objects};

/// Index of the red apple in [`table_objects`] (the full report's sequence).
const SEQUENCE_OBJECT: usize = 5;
/// Index of the plastic bottle (the quick report's only object).
const QUICK_OBJECT: usize = 3;
/// The table's seed.
const SEED: u64 = 1;

/// What the part measured.
#[derive(Debug, Clone, Serialize)]
pub struct GraspReport {
    /// Successes per object and strategy.
    pub rows: Vec<TableRow>,
    /// The largest holding mass of an adaptive trial (kg).
    pub max_holding_mass_kg: f64,
    /// The drawn sequences: the first try of the sequence object, adaptive
    /// then open loop.
    pub sequences: Vec<TrialOutcome>,
    /// The objects (sizes, masses, friction).
    pub objects: Vec<GraspObject>,
}

impl GraspReport {
    /// The success table as Markdown.
    pub fn markdown(&self) -> String {
        let mut s = String::from("| object | adaptive | open loop |\n|---|---|---|\n");
        let (mut ta, mut to, mut na, mut no) = (0, 0, 0, 0);
        for pair in self.rows.chunks(2) {
            if let [a, o] = pair {
                s.push_str(&format!(
                    "| {} | {}/{} | {}/{} |\n",
                    a.object, a.successes, a.tries, o.successes, o.tries
                ));
                (ta, na, to, no) = (
                    ta + a.successes,
                    na + a.tries,
                    to + o.successes,
                    no + o.tries,
                );
            }
        }
        s.push_str(&format!("| total | {ta}/{na} | {to}/{no} |\n"));
        s.push_str(&format!(
            "\nLargest holding mass of an adaptive grasp: {:.3} kg.\n",
            self.max_holding_mass_kg
        ));
        s
    }
}

/// Runs the table (module docs) and writes the figure, the JSON and the
/// Markdown table into `opts.out_dir`.
///
/// # Errors
/// Bad input of the built-in objects (none); [`crate::Error::Io`] for a
/// file that cannot be written. A failed trial is an outcome, not an error.
pub fn run(opts: &ReportOptions) -> Result<(GraspReport, Vec<PathBuf>)> {
    let all = table_objects();
    let (objects, tries, seq) = if opts.quick {
        (vec![all[QUICK_OBJECT].clone()], 1, 0)
    } else {
        (all, 5, SEQUENCE_OBJECT)
    };
    let strategies = [Strategy::Adaptive, Strategy::OpenLoop];
    let pb = crate::report::progress(objects.len() * tries * 2, opts.quiet, "grasp");
    let mut sequences = Vec::new();
    let mut k = 0usize;
    let rows = run_table(
        &GripperSpec::default(),
        &objects,
        &strategies,
        tries,
        &GraspSettings::default(),
        SEED,
        |o| {
            // outcomes arrive per object, per strategy, per try
            if k / (2 * tries) == seq && k.is_multiple_of(tries) {
                sequences.push(o.clone());
            }
            k += 1;
            pb.inc(1);
        },
    )?;
    pb.finish_and_clear();
    let max_holding_mass_kg = rows
        .iter()
        .filter(|r| r.strategy == Strategy::Adaptive)
        .flat_map(|r| r.holding_mass_kg.iter().copied())
        .fold(0.0, f64::max);
    let report = GraspReport {
        rows,
        max_holding_mass_kg,
        sequences,
        objects,
    };
    let dir = &opts.out_dir;
    let json = dir.join("grasp.json");
    write_json(&json, &report)?;
    let md = dir.join("grasp.md");
    crate::report::atomic::write_atomic(&md, report.markdown().as_bytes())?;
    let mut files = vec![json, md];
    files.extend(crate::report::plot::both(
        dir,
        "grasp",
        (1500, 520),
        |a| draw(a, &report),
        |a| draw(a, &report),
    )?);
    Ok((report, files))
}

/// The outline of an obstacle as a closed polyline (m).
fn outline(o: &Obstacle, shift: [f64; 2]) -> Vec<(f64, f64)> {
    let mut pts: Vec<(f64, f64)> = match o {
        Obstacle::Circle { center_m, radius_m } => (0..=64)
            .map(|k| {
                let a = std::f64::consts::TAU * k as f64 / 64.0;
                (
                    center_m[0] + radius_m * a.cos(),
                    center_m[1] + radius_m * a.sin(),
                )
            })
            .collect(),
        Obstacle::Capsule {
            start_m,
            end_m,
            radius_m,
        } => {
            let d = [end_m[0] - start_m[0], end_m[1] - start_m[1]];
            let a0 = d[1].atan2(d[0]) - std::f64::consts::FRAC_PI_2;
            let arc = |c: [f64; 2], from: f64| {
                (0..=32).map(move |k| {
                    let a = from + std::f64::consts::PI * k as f64 / 32.0;
                    (c[0] + radius_m * a.cos(), c[1] + radius_m * a.sin())
                })
            };
            arc(*end_m, a0)
                .chain(arc(*start_m, a0 + std::f64::consts::PI))
                .collect()
        }
        Obstacle::Polygon { vertices_m } => vertices_m.iter().map(|v| (v[0], v[1])).collect(),
    };
    if let Some(&f) = pts.first() {
        pts.push(f);
    }
    pts.iter()
        .map(|(x, y)| (x + shift[0], y + shift[1]))
        .collect()
}

const ADAPTIVE: RGBColor = RGBColor(31, 119, 180);
const OPEN: RGBColor = RGBColor(214, 39, 40);

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    r: &GraspReport,
) -> std::result::Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| format!("{x:?}");
    root.fill(&WHITE).map_err(e)?;
    let panels = root.split_evenly((1, 3));
    for (panel, out) in panels.iter().zip(&r.sequences) {
        let verdict = match (&out.failure, out.success) {
            (_, true) => format!("held, slip {:.1} mm", out.slip_m * 1e3),
            (Some(f), false) => format!("failed: {}", failure_name(f)),
            (None, false) => "failed".into(),
        };
        let mut c = ChartBuilder::on(panel)
            .caption(
                format!("{} on the {}: {verdict}", out.strategy.name(), out.object),
                ("sans-serif", 17),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(-0.075..0.075, -0.14..0.01)
            .map_err(e)?;
        c.configure_mesh()
            .x_desc("x (m)")
            .y_desc("y (m), palm at 0")
            .draw()
            .map_err(e)?;
        // the object at the start (dashed grey) and at the end (filled)
        let start = outline(&out.outline, [0.0, 0.0]);
        c.draw_series(LineSeries::new(start, BLACK.mix(0.35).stroke_width(1)))
            .map_err(e)?;
        // the start outline moved as a rigid body to the final pose
        let (c0, c1) = (out.pose.position_m, out.final_pose.position_m);
        let (s, co) = (out.final_pose.angle_rad - out.pose.angle_rad).sin_cos();
        let end: Vec<(f64, f64)> = outline(&out.outline, [0.0, 0.0])
            .into_iter()
            .map(|(x, y)| {
                let (dx, dy) = (x - c0[0], y - c0[1]);
                (c1[0] + co * dx - s * dy, c1[1] + s * dx + co * dy)
            })
            .collect();
        c.draw_series(std::iter::once(Polygon::new(
            end.clone(),
            RGBColor(250, 200, 120).mix(0.6).filled(),
        )))
        .map_err(e)?;
        c.draw_series(LineSeries::new(end, BLACK.stroke_width(1)))
            .map_err(e)?;
        // finger shapes: six frames over the sequence, light to dark
        let n = out.frames.len();
        let picks: Vec<usize> = if n == 0 {
            Vec::new()
        } else {
            (0..6).map(|k| k * (n - 1) / 5).collect()
        };
        for (j, &i) in picks.iter().enumerate() {
            let f = &out.frames[i];
            let t = 0.25 + 0.75 * j as f64 / 5.0;
            let colour = crate::report::plot::viridis(1.0 - t);
            let width = if j == 5 { 3 } else { 1 };
            for line in &f.centreline_m {
                c.draw_series(LineSeries::new(
                    line.iter().map(|p| (p[0], p[1])),
                    colour.stroke_width(width),
                ))
                .map_err(e)?;
            }
        }
        // contact forces after the lift: arrows along the push, 10 mm per N
        if let Some(f) = out.frames.last() {
            for ct in &f.contacts {
                let l = 0.01 * ct.force_n;
                let from = (
                    ct.point_m[0] - l * ct.normal[0],
                    ct.point_m[1] - l * ct.normal[1],
                );
                let to = (ct.point_m[0], ct.point_m[1]);
                let colour = if out.strategy == Strategy::Adaptive {
                    ADAPTIVE
                } else {
                    OPEN
                };
                c.draw_series(LineSeries::new([from, to], colour.stroke_width(3)))
                    .map_err(e)?;
                c.draw_series(std::iter::once(Circle::new(to, 3, colour.filled())))
                    .map_err(e)?;
            }
        }
    }
    // success per object
    let n_obj = r.rows.len() / 2;
    let tries = r.rows.first().map_or(1, |x| x.tries).max(1);
    let mut c = ChartBuilder::on(&panels[2])
        .caption(
            format!(
                "successes out of {tries} (largest holding mass {:.0} g)",
                r.max_holding_mass_kg * 1e3
            ),
            ("sans-serif", 17),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(110)
        .build_cartesian_2d(0.0..tries as f64 + 0.5, 0.0..n_obj.max(1) as f64)
        .map_err(e)?;
    let names: Vec<String> = r.rows.iter().step_by(2).map(|x| x.object.clone()).collect();
    c.configure_mesh()
        .disable_y_mesh()
        .y_labels(n_obj.max(1) * 2 + 1)
        .y_label_formatter(&|y| {
            let k = y.floor() as usize;
            if (y - k as f64 - 0.5).abs() < 0.01 {
                names
                    .get(n_obj - 1 - k.min(n_obj - 1))
                    .cloned()
                    .unwrap_or_default()
            } else {
                String::new()
            }
        })
        .x_desc("successful tries")
        .draw()
        .map_err(e)?;
    for (k, pair) in r.rows.chunks(2).enumerate() {
        let y = (n_obj - 1 - k) as f64;
        for (j, row) in pair.iter().enumerate() {
            let colour = if row.strategy == Strategy::Adaptive {
                ADAPTIVE
            } else {
                OPEN
            };
            let (y0, y1) = (y + 0.1 + 0.4 * j as f64, y + 0.45 + 0.4 * j as f64);
            c.draw_series(std::iter::once(Rectangle::new(
                [(0.0, y0), (row.successes as f64, y1)],
                colour.filled(),
            )))
            .map_err(e)?;
        }
    }
    c.draw_series(std::iter::once(Rectangle::new(
        [(0.0, 0.0), (0.0, 0.0)],
        ADAPTIVE.filled(),
    )))
    .map_err(e)?
    .label("adaptive")
    .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], ADAPTIVE.filled()));
    c.draw_series(std::iter::once(Rectangle::new(
        [(0.0, 0.0), (0.0, 0.0)],
        OPEN.filled(),
    )))
    .map_err(e)?
    .label("open loop")
    .legend(|(x, y)| Rectangle::new([(x, y - 5), (x + 12, y + 5)], OPEN.filled()));
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::LowerRight)
        .draw()
        .map_err(e)?;
    Ok(())
}

fn failure_name(f: &crate::grasp::trial::Failure) -> String {
    use crate::grasp::trial::Failure;
    match f {
        Failure::Slips { slip_m, .. } => format!("slips {:.0} mm", slip_m * 1e3),
        Failure::Dropped { .. } => "dropped".into(),
        Failure::Missed { side } => format!("{side:?} finger missed"),
        Failure::PlantSolve { status, .. } => format!("plant solve ({status})"),
        Failure::ObjectMotion { .. } => "object motion".into(),
        Failure::Controller { .. } => "controller".into(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outlines_close() {
        let c = Obstacle::Circle {
            center_m: [0.0, 0.0],
            radius_m: 0.01,
        };
        let o = outline(&c, [0.0, -0.1]);
        assert_eq!(o.first(), o.last());
        assert!(
            o.iter()
                .all(|p| ((p.0).hypot(p.1 + 0.1) - 0.01).abs() < 1e-12)
        );
    }
}
