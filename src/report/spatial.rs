//! The soft parallel robot's report part: the simulated Fig. 8 (payload
//! mass estimated from the platform marker against the hung mass, three
//! configurations, plant ≠ model) and a view of the robot in two
//! projections (side `x–z`, top `x–y`) in the three configurations with a
//! 200 g payload. `spatial.png`, `spatial.svg`, `spatial.json`.

use std::path::PathBuf;

use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Serialize;

use super::{ReportOptions, write_json};
use crate::error::Result;
use crate::parallel::ParallelSpec;
use crate::parallel::payload::{
    FIG8_FRAMES, MassTrial, Measurement, fig8_configurations, mass_experiment, plant_spec,
};
use crate::scene::parallel::ParallelSolution;

/// What the part measured.
#[derive(Debug, Clone, Serialize)]
pub struct SpatialReport {
    /// Every trial: configuration, hung mass, estimate (kg).
    pub trials: Vec<(usize, f64, f64)>,
    /// Mean absolute error per configuration (g).
    pub mean_error_g: Vec<f64>,
    /// Frames averaged per pose, marker noise per frame (m).
    pub frames: usize,
    /// Marker noise per frame (m).
    pub sigma_m: f64,
    /// The model's robot in each configuration with a 200 g payload.
    pub shapes: Vec<ParallelSolution>,
}

const COLOURS: [RGBColor; 3] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
];

/// Runs the experiment (masses every 25 g, quick: every 100 g) and writes
/// the chart and the JSON into `opts.out_dir`.
///
/// # Errors
/// As [`mass_experiment`]; [`crate::Error::Io`] for a file that cannot be
/// written.
pub fn run(opts: &ReportOptions) -> Result<(SpatialReport, Vec<PathBuf>)> {
    let spec = ParallelSpec::default();
    let model = spec.build_full()?;
    let plant = plant_spec(&spec).build_full()?;
    let configs = fig8_configurations(&spec);
    let step = if opts.quick { 4 } else { 1 };
    let masses: Vec<f64> = (0..=8).step_by(step).map(|k| 0.025 * k as f64).collect();
    let m = Measurement {
        sigma_m: 0.05e-3,
        frames: FIG8_FRAMES,
        seed: 3,
    };
    // the mass experiment, then the shape of each configuration
    let pb = super::progress(1 + configs.len(), opts.quiet, "spatial");
    pb.set_message("payload mass (Fig. 8)");
    let trials: Vec<MassTrial> = mass_experiment(&model, &plant, &configs, &masses, m)?;
    pb.inc(1);
    pb.set_message("shapes with 200 g");
    let mean_error_g = (0..configs.len())
        .map(|c| {
            let e: Vec<f64> = trials
                .iter()
                .filter(|t| t.configuration == c)
                .map(|t| t.error_kg().abs() * 1e3)
                .collect();
            e.iter().sum::<f64>() / e.len().max(1) as f64
        })
        .collect();
    let mut shapes = Vec::with_capacity(configs.len());
    for p in &configs {
        let scene = crate::scene::parallel::ParallelScene {
            name: String::new(),
            description: String::new(),
            element: crate::parallel::LegElement::Ancf3d,
            parallel: spec.clone(),
            pressures_pa: p.as_slice().to_vec(),
            platform_force_n: vec![0.0, 0.0, -0.2 * 9.81],
            platform_moment_nm: Vec::new(),
            marker_sigma_m: 0.05e-3,
            backend: Default::default(),
        };
        shapes.push(scene.solve()?);
        pb.inc(1);
    }
    pb.finish_and_clear();
    let report = SpatialReport {
        trials: trials
            .iter()
            .map(|t| (t.configuration, t.mass_kg, t.estimate_kg))
            .collect(),
        mean_error_g,
        frames: m.frames,
        sigma_m: m.sigma_m,
        shapes,
    };
    let dir = &opts.out_dir;
    let json = dir.join("spatial.json");
    write_json(&json, &report)?;
    let mut files = vec![json];
    files.extend(super::plot::both(
        dir,
        "spatial",
        (1500, 520),
        |a| draw(a, &report),
        |a| draw(a, &report),
    )?);
    Ok((report, files))
}

fn draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    r: &SpatialReport,
) -> std::result::Result<(), String> {
    let e = |x: DrawingAreaErrorKind<DB::ErrorType>| format!("{x:?}");
    root.fill(&WHITE).map_err(e)?;
    let panels = root.split_evenly((1, 3));
    // (a) estimated against hung mass
    let mut c = ChartBuilder::on(&panels[0])
        .caption("payload from the platform marker", ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(50)
        .build_cartesian_2d(-10.0..220.0, -10.0..220.0)
        .map_err(e)?;
    c.configure_mesh()
        .x_desc("hung mass (g)")
        .y_desc("estimated mass (g)")
        .draw()
        .map_err(e)?;
    super::layout::data_in(c.plotting_area());
    c.draw_series(LineSeries::new(
        [(0.0, 0.0), (210.0, 210.0)],
        BLACK.mix(0.4),
    ))
    .map_err(e)?;
    for (k, colour) in COLOURS.iter().enumerate() {
        let pts: Vec<(f64, f64)> = r
            .trials
            .iter()
            .filter(|t| t.0 == k)
            .map(|t| (t.1 * 1e3, t.2 * 1e3))
            .collect();
        let mean = r.mean_error_g.get(k).copied().unwrap_or(f64::NAN);
        c.draw_series(pts.iter().map(|&p| Circle::new(p, 5, colour.filled())))
            .map_err(e)?
            .label(format!("configuration {} (mean error {mean:.1} g)", k + 1))
            .legend(move |(x, y)| Circle::new((x, y), 5, colour.filled()));
    }
    super::layout::annotations();
    c.configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .position(SeriesLabelPosition::UpperLeft)
        .draw()
        .map_err(e)?;
    // (b) side view x–z and (c) top view x–y of the robot with 200 g
    for (panel, (title, axis)) in panels[1..].iter().zip([
        ("side view (x–z), 200 g payload", 2usize),
        ("top view (x–y)", 1usize),
    ]) {
        // the axes hold every leg (they once were fixed, and a leg left them)
        let span = |k: usize| {
            let (lo, hi) = r
                .shapes
                .iter()
                .flat_map(|s| s.legs_m.iter().flatten().map(move |p| p[k]))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
                    (a.min(v), b.max(v))
                });
            if lo.is_finite() {
                let pad = 0.08 * (hi - lo).max(1e-3);
                (lo - pad, hi + pad)
            } else {
                (-0.1, 0.1)
            }
        };
        let ((xlo, xhi), (ylo, yhi)) = (span(0), span(axis));
        let mut c = ChartBuilder::on(panel)
            .caption(title, ("sans-serif", 20))
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(xlo..xhi, ylo..yhi)
            .map_err(e)?;
        c.configure_mesh()
            .x_desc("x (m)")
            .y_desc(if axis == 2 { "z (m)" } else { "y (m)" })
            .draw()
            .map_err(e)?;
        super::layout::data_in(c.plotting_area());
        for (k, s) in r.shapes.iter().enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            for leg in &s.legs_m {
                c.draw_series(LineSeries::new(
                    leg.iter().map(|p| (p[0], p[axis])),
                    colour.stroke_width(2),
                ))
                .map_err(e)?;
            }
            // the platform: the legs' ends joined, edge by edge (a wide
            // polyline's miter join at the 180° turn of a platform seen
            // edge-on spikes out of the axes)
            let ends: Vec<(f64, f64)> = s
                .legs_m
                .iter()
                .filter_map(|l| l.last().map(|p| (p[0], p[axis])))
                .collect();
            let n = ends.len();
            c.draw_series((0..n).map(|i| {
                PathElement::new(vec![ends[i], ends[(i + 1) % n]], colour.stroke_width(4))
            }))
            .map_err(e)?;
        }
        super::layout::annotations();
    }
    Ok(())
}
