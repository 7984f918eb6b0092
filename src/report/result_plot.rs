//! A picture of one result: what `softrod plot RESULT.json` draws from the
//! JSON record of `softrod solve`, `softrod estimate` or `softrod avoid`
//! (format version "1", the schemas under `schema/`).
//!
//! - A robot scene's `solve`: the backbone (its nodes), in the `x–y` plane
//!   for a planar robot, in three orthogonal views (`x–y`, `x–z`, `y–z`)
//!   for a spatial or 3-D one.
//! - Its `estimate` (one observation, or the last frame of a stream): the
//!   estimated backbone with the markers measured (rings) and fitted
//!   (dots), the estimated load `w(s)` along the backbone with its ±1σ band
//!   (`load[].w_std`: the spread under the stated marker noise), and each
//!   marker's residual against the noise σ.
//! - A parallel robot's `solve`: the legs and the platform in three views.
//! - An `avoid` run: the robot's shapes over the run, the goal, the
//!   obstacle points learnt by touch and the estimated contact forces.
//!
//! PNG or SVG by the output's extension. Every picture goes through the
//! layout check ([`super::layout`]); what it finds is in
//! [`PlotSummary::layout`] (and warned on standard error).
//!
//! # Example
//! ```no_run
//! let summary = softrod::report::result_plot::plot_result(
//!     "target/estimate.json".as_ref(),
//!     Some("target/estimate.png".as_ref()),
//! )?;
//! assert!(summary.layout.is_empty());
//! # Ok::<(), softrod::Error>(())
//! ```

use std::path::{Path, PathBuf};

use plotters::coord::Shift;
use plotters::prelude::*;
use serde::Deserialize;

use super::layout::{self, LayoutIssue};
use super::plot::{draw_recorded, ms, register_font, warn_layout};
use crate::error::{Error, Result};

const FONT: &str = "sans-serif";
const SHAPE: RGBColor = RGBColor(31, 119, 180);
const MEASURED: RGBColor = RGBColor(214, 39, 40);
const FITTED: RGBColor = RGBColor(20, 20, 20);
const COMPONENTS: [RGBColor; 3] = [
    RGBColor(31, 119, 180),
    RGBColor(214, 39, 40),
    RGBColor(44, 160, 44),
];
const LOAD: RGBColor = RGBColor(148, 103, 189);
const AXES: [&str; 3] = ["x", "y", "z"];

/// What [`plot_result`] drew.
#[derive(Debug, Clone)]
pub struct PlotSummary {
    /// The file written.
    pub path: PathBuf,
    /// What was read: `"<command> <scene_kind>"`, e.g. `"estimate planar_cable"`.
    pub record: String,
    /// The panels drawn, e.g. `["x–y", "load", "residuals"]`.
    pub panels: Vec<String>,
    /// What the layout check found (empty: no text off the canvas or over
    /// another, no data outside its axes).
    pub layout: Vec<LayoutIssue>,
}

/// Draws the record in the file `record` into `out` (default: the record's
/// path with the extension `.png`).
///
/// # Errors
/// - [`Error::Io`] if the record cannot be read, is not JSON or has a
///   field of the wrong shape (the message names the field), or `out`
///   cannot be written;
/// - [`Error::UnsupportedRecord`] for a record that is not a format-1
///   softrod record or whose kind has no picture (it names what was read);
/// - [`Error::InvalidParameter`] named `out` for an extension other than
///   `.png` or `.svg`.
///
/// # Example
/// See the [module](self).
pub fn plot_result(record: &Path, out: Option<&Path>) -> Result<PlotSummary> {
    let text = std::fs::read_to_string(record).map_err(|e| super::io_error(record, e))?;
    let value: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| super::io_error(record, format!("not JSON: {e}")))?;
    let out = out
        .map(Path::to_path_buf)
        .unwrap_or_else(|| record.with_extension("png"));
    plot_record(&value, &record.display().to_string(), &out)
}

/// Draws the record `value` (read from `source`, for the messages) into
/// `out`.
///
/// # Errors
/// As [`plot_result`].
///
/// # Example
/// See the [module](self).
pub fn plot_record(value: &serde_json::Value, source: &str, out: &Path) -> Result<PlotSummary> {
    let format = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let svg = match format.as_deref() {
        Some("png") => false,
        Some("svg") => true,
        _ => {
            return Err(Error::InvalidParameter {
                name: "out".into(),
                value: out.display().to_string(),
                reason: "the picture is a .png or an .svg file".into(),
            });
        }
    };
    let picture = Picture::read(value, source)?;
    let size = picture.size();
    register_font()?;
    let mut issues = Vec::new();
    super::atomic::with_temp(out, |tmp| {
        let (r, found) = if svg {
            draw_recorded(SVGBackend::new(tmp, size), |a| picture.draw(a))
        } else {
            draw_recorded(BitMapBackend::new(tmp, size), |a| picture.draw(a))
        };
        issues = found;
        r.map_err(|m| super::io_error(out, m))
    })?;
    warn_layout(out, &issues);
    Ok(PlotSummary {
        path: out.to_path_buf(),
        record: picture.record.clone(),
        panels: picture.panels(),
        layout: issues,
    })
}

// ---- the records, as far as a picture reads them ------------------------

#[derive(Deserialize)]
struct Head {
    format_version: Option<String>,
    command: Option<String>,
    scene: Option<String>,
    scene_kind: Option<String>,
    outcome: Option<String>,
    status: Option<serde_json::Value>,
}

#[derive(Deserialize)]
struct NodeIn {
    position_m: Vec<f64>,
}

#[derive(Deserialize)]
struct LoadIn {
    s: f64,
    w: Vec<f64>,
    #[serde(default)]
    w_std: Option<Vec<f64>>,
}

#[derive(Deserialize)]
struct MarkerIn {
    s_m: f64,
    measured_position_m: Vec<f64>,
    fitted_position_m: Vec<f64>,
}

#[derive(Deserialize)]
struct PointForceIn {
    node: usize,
    s_m: f64,
    position_m: Vec<f64>,
}

#[derive(Deserialize)]
struct ResultantIn {
    force_n: Vec<f64>,
    force_std_n: Vec<f64>,
}

/// A robot scene's solve or estimate (an estimate's fields optional).
#[derive(Deserialize)]
struct RobotIn {
    nodes: Vec<NodeIn>,
    #[serde(default)]
    load: Vec<LoadIn>,
    #[serde(default)]
    markers: Vec<MarkerIn>,
    #[serde(default)]
    resultant: Option<ResultantIn>,
    #[serde(default)]
    point_force: Option<PointForceIn>,
    #[serde(default)]
    noise_sigma_m: Option<f64>,
}

#[derive(Deserialize)]
struct StreamFrameIn {
    t_s: f64,
    estimate: serde_json::Value,
}

#[derive(Deserialize)]
struct StreamIn {
    frames: Vec<StreamFrameIn>,
}

#[derive(Deserialize)]
struct ParallelIn {
    legs_m: Vec<Vec<[f64; 3]>>,
}

#[derive(Deserialize)]
struct TouchedIn {
    point_m: [f64; 2],
    force_n: [f64; 2],
}

#[derive(Deserialize)]
struct AvoidIn {
    goal_m: [f64; 2],
    touched: Vec<TouchedIn>,
    shapes: Vec<(f64, Vec<[f64; 2]>)>,
}

/// `T` from `value`, a malformed field named by its path.
fn field<T: serde::de::DeserializeOwned>(value: &serde_json::Value, source: &str) -> Result<T> {
    serde_path_to_error::deserialize(value).map_err(|e| Error::Io {
        path: source.to_string(),
        message: format!("field `{}`: {}", e.path(), e.inner()),
    })
}

// ---- what is drawn ------------------------------------------------------

/// A marker: measured and fitted position (m).
struct Marker {
    s_m: f64,
    measured: Vec<f64>,
    fitted: Vec<f64>,
}

/// One sample of the load: `s` (m), `w` (N/m), its 1σ (N/m) if known.
struct Sample {
    s: f64,
    w: Vec<f64>,
    std: Option<Vec<f64>>,
}

/// An estimated point force: its node, arc coordinate (m), point (m),
/// force and 1σ (N).
struct PointForce {
    node: usize,
    s_m: f64,
    at: Vec<f64>,
    force: Vec<f64>,
    std: Vec<f64>,
}

/// The estimate's part of a robot picture.
struct EstimatePart {
    markers: Vec<Marker>,
    load: Vec<Sample>,
    point: Option<PointForce>,
    noise_sigma_m: Option<f64>,
}

enum Body {
    /// Polylines in world axes (a backbone, the legs), `dim` axes each.
    Shape {
        dim: usize,
        lines: Vec<Vec<Vec<f64>>>,
        /// Close the lines' ends into a ring (the parallel platform).
        ring: bool,
        estimate: Option<EstimatePart>,
    },
    Avoid(AvoidIn),
}

struct Picture {
    /// `"<command> <scene_kind>"`.
    record: String,
    /// Title lines.
    title: Vec<String>,
    body: Body,
}

/// What a record's header says, for messages.
fn described(h: &Head) -> (String, String, String) {
    let or_none = |v: &Option<String>| v.clone().unwrap_or_else(|| "(none)".into());
    (
        or_none(&h.format_version),
        or_none(&h.command),
        or_none(&h.scene_kind),
    )
}

impl Picture {
    fn read(value: &serde_json::Value, source: &str) -> Result<Picture> {
        let head: Head = field(value, source)?;
        let (version, command, kind) = described(&head);
        let unsupported = || Error::UnsupportedRecord {
            path: source.to_string(),
            format_version: version.clone(),
            command: command.clone(),
            scene_kind: kind.clone(),
        };
        if head.format_version.as_deref() != Some("1") {
            return Err(unsupported());
        }
        let status = head
            .status
            .as_ref()
            .map(|s| serde_json::to_string(s).unwrap_or_default())
            .unwrap_or_default();
        let mut title = vec![format!(
            "softrod {command}: {} ({kind}), outcome {}, status {status}",
            head.scene.as_deref().unwrap_or(""),
            head.outcome.as_deref().unwrap_or("(none)")
        )];
        let dim = match kind.as_str() {
            "planar_cable" => 2,
            "spatial_cable" | "ancf3d" => 3,
            _ => 0,
        };
        let body = match (command.as_str(), kind.as_str()) {
            ("solve", _) if dim > 0 => {
                let r: RobotIn = field(value, source)?;
                robot_body(dim, r, false, &mut title)?
            }
            ("estimate", _) if dim > 0 && value.get("frames").is_some() => {
                let s: StreamIn = field(value, source)?;
                let n = s.frames.len();
                let Some(last) = s.frames.last() else {
                    return Err(Error::Io {
                        path: source.into(),
                        message: "field `frames`: a stream of no frames has no picture".into(),
                    });
                };
                title.push(format!("the last of {n} frames, t = {} s", last.t_s));
                let r: RobotIn = field(&last.estimate, source)?;
                robot_body(dim, r, true, &mut title)?
            }
            ("estimate", _) if dim > 0 => {
                let r: RobotIn = field(value, source)?;
                robot_body(dim, r, true, &mut title)?
            }
            ("solve", "parallel") => {
                let p: ParallelIn = field(value, source)?;
                Body::Shape {
                    dim: 3,
                    lines: p
                        .legs_m
                        .into_iter()
                        .map(|l| l.into_iter().map(|p| p.to_vec()).collect())
                        .collect(),
                    ring: true,
                    estimate: None,
                }
            }
            ("avoid", "avoid") => {
                let a: AvoidIn = field(value, source)?;
                title.push(format!(
                    "{} shapes over the run (grey; the last blue), {} obstacle points learnt by touch with their estimated contact force",
                    a.shapes.len(),
                    a.touched.len()
                ));
                Body::Avoid(a)
            }
            _ => return Err(unsupported()),
        };
        Ok(Picture {
            record: format!("{command} {kind}"),
            title,
            body,
        })
    }

    fn views(&self) -> Vec<(usize, usize)> {
        match &self.body {
            Body::Shape { dim: 2, .. } | Body::Avoid(_) => vec![(0, 1)],
            Body::Shape { .. } => vec![(0, 1), (0, 2), (1, 2)],
        }
    }

    fn has_estimate(&self) -> bool {
        matches!(
            &self.body,
            Body::Shape {
                estimate: Some(_),
                ..
            }
        )
    }

    fn panels(&self) -> Vec<String> {
        let mut p: Vec<String> = self
            .views()
            .iter()
            .map(|(a, b)| format!("{}–{}", AXES[*a], AXES[*b]))
            .collect();
        if self.has_estimate() {
            p.push("load".into());
            p.push("residuals".into());
        }
        p
    }

    /// Canvas (px): 600 px a panel, 3-D estimates on two rows.
    fn size(&self) -> (u32, u32) {
        let views = self.views().len() as u32;
        let head = 40 + 22 * self.title.len() as u32;
        match (views, self.has_estimate()) {
            (1, false) => (760, 640 + head),
            (1, true) => (1800, 600 + head),
            (_, false) => (1800, 600 + head),
            (_, true) => (1800, 1150 + head),
        }
    }

    fn draw<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
    ) -> std::result::Result<(), String> {
        root.fill(&WHITE).map_err(ms)?;
        let head = 20 + 22 * self.title.len() as u32;
        let (top, body) = root.split_vertically(head);
        for (i, line) in self.title.iter().enumerate() {
            let size = if i == 0 { 18 } else { 15 };
            top.draw(&Text::new(
                line.clone(),
                (16, 10 + 22 * i as i32),
                (FONT, size).into_font(),
            ))
            .map_err(ms)?;
        }
        let views = self.views();
        match &self.body {
            Body::Avoid(a) => draw_avoid(&body, a),
            Body::Shape {
                lines,
                ring,
                estimate,
                ..
            } => {
                let (view_row, rest) = match (views.len(), estimate) {
                    (1, Some(_)) => (body.clone(), None),
                    (_, Some(_)) => {
                        let h = body.dim_in_pixel().1;
                        let (a, b) = body.split_vertically(h / 2);
                        (a, Some(b))
                    }
                    _ => (body.clone(), None),
                };
                let columns = if views.len() == 1 && estimate.is_some() {
                    3
                } else {
                    views.len()
                };
                let cells = view_row.split_evenly((1, columns));
                for (cell, view) in cells.iter().zip(&views) {
                    draw_view(cell, *view, lines, *ring, estimate.as_ref())?;
                }
                if let Some(e) = estimate {
                    let (load_cell, residual_cell) = match &rest {
                        Some(r) => {
                            let c = r.split_evenly((1, 2));
                            (c[0].clone(), c[1].clone())
                        }
                        None => (cells[1].clone(), cells[2].clone()),
                    };
                    match &e.point {
                        Some(p) => draw_point_force(&load_cell, p)?,
                        None => draw_load(&load_cell, e)?,
                    }
                    draw_residuals(&residual_cell, e)?;
                }
                Ok(())
            }
        }
    }
}

/// A robot record's body; an estimate's parts and the resultant's line.
fn robot_body(dim: usize, r: RobotIn, estimate: bool, title: &mut Vec<String>) -> Result<Body> {
    let line: Vec<Vec<f64>> = r.nodes.iter().map(|n| n.position_m.clone()).collect();
    if let Some(res) = &r.resultant {
        let parts: Vec<String> = res
            .force_n
            .iter()
            .zip(&res.force_std_n)
            .zip(AXES)
            .map(|((f, s), a)| format!("F{a} = {} ± {} N", sig3(*f), sig3(*s)))
            .collect();
        title.push(format!(
            "resultant of the estimated load: {} (±: 1σ for the stated marker noise)",
            parts.join(", ")
        ));
    }
    let estimate = estimate.then(|| EstimatePart {
        markers: r
            .markers
            .into_iter()
            .map(|m| Marker {
                s_m: m.s_m,
                measured: m.measured_position_m,
                fitted: m.fitted_position_m,
            })
            .collect(),
        load: r
            .load
            .into_iter()
            .map(|l| Sample {
                s: l.s,
                w: l.w,
                std: l.w_std,
            })
            .collect(),
        noise_sigma_m: r.noise_sigma_m,
        point: r
            .point_force
            .zip(r.resultant.as_ref())
            .map(|(p, res)| PointForce {
                node: p.node,
                s_m: p.s_m,
                at: p.position_m,
                force: res.force_n.clone(),
                std: res.force_std_n.clone(),
            }),
    });
    Ok(Body::Shape {
        dim,
        lines: vec![line],
        ring: false,
        estimate,
    })
}

/// The legend of `chart`'s labelled series at `position`, in the one style
/// of these pictures; what it draws is an annotation for the layout check
/// (it may lie over the data, not outside the canvas or over other text).
fn draw_legend<'a, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> std::result::Result<(), String> {
    layout::annotations();
    chart
        .configure_series_labels()
        .label_font((FONT, 13))
        .background_style(WHITE.mix(0.85))
        .border_style(RGBColor(160, 160, 160))
        .position(position)
        .draw()
        .map_err(ms)
}

/// `[lo, hi]` of `values`, padded by `pad` of the span (a span of zero:
/// `±1e-3` about the value; nothing: `[-1, 1]`).
fn padded(values: impl Iterator<Item = f64>, pad: f64) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    let span = hi - lo;
    if span <= 1e-12 * lo.abs().max(hi.abs()).max(1e-300) {
        let d = 1e-3f64.max(lo.abs() * 0.1);
        return (lo - d, hi + d);
    }
    (lo - pad * span, hi + pad * span)
}

/// Ranges with equal scale on both axes for a plot area of `px` pixels.
fn equal_aspect(x: (f64, f64), y: (f64, f64), px: (u32, u32)) -> ((f64, f64), (f64, f64)) {
    let (w, h) = (px.0.max(1) as f64, px.1.max(1) as f64);
    let per_px = ((x.1 - x.0) / w).max((y.1 - y.0) / h);
    let grow = |r: (f64, f64), n: f64| {
        let c = 0.5 * (r.0 + r.1);
        (c - 0.5 * per_px * n, c + 0.5 * per_px * n)
    };
    (grow(x, w), grow(y, h))
}

/// Tick labels of an axis spanning `range`, in units of `scale` (1e3: m
/// shown in mm): as many decimals as a tenth of the span needs, no `-0`.
fn ticks(range: (f64, f64), scale: f64) -> impl Fn(&f64) -> String {
    let step = ((range.1 - range.0) * scale / 10.0).abs();
    let decimals = if step > 0.0 && step.is_finite() {
        (-step.log10().floor()).clamp(0.0, 9.0) as usize
    } else {
        0
    };
    move |v: &f64| {
        let t = format!("{:.*}", decimals, v * scale);
        match t.strip_prefix('-') {
            Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
            _ => t,
        }
    }
}

/// `v` with three significant digits (`1.23e-5` outside 0.001..10⁴).
fn sig3(v: f64) -> String {
    let a = v.abs();
    if a == 0.0 || !a.is_finite() {
        format!("{v}")
    } else if (1e-3..1e4).contains(&a) {
        let d = (2.0 - a.log10().floor()).max(0.0) as usize;
        format!("{v:.d$}")
    } else {
        format!("{v:.2e}")
    }
}

/// One view `(a, b)` of the lines (and the markers) with equal axes.
fn draw_view<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    (a, b): (usize, usize),
    lines: &[Vec<Vec<f64>>],
    ring: bool,
    estimate: Option<&EstimatePart>,
) -> std::result::Result<(), String> {
    let at = |p: &Vec<f64>| {
        (
            p.get(a).copied().unwrap_or(0.0),
            p.get(b).copied().unwrap_or(0.0),
        )
    };
    let mut points: Vec<(f64, f64)> = lines.iter().flatten().map(at).collect();
    let arrow = estimate.and_then(|e| e.point.as_ref()).and_then(|p| {
        // the force's direction, a quarter of the backbone's extent in
        // this view long
        let extent = [a, b]
            .iter()
            .map(|&k| {
                let (lo, hi) = padded(
                    lines.iter().flatten().filter_map(|q| q.get(k).copied()),
                    0.0,
                );
                hi - lo
            })
            .fold(0.0, f64::max);
        let norm = p.force.iter().map(|f| f * f).sum::<f64>().sqrt();
        (norm > 0.0).then(|| {
            let k = 0.25 * extent / norm;
            let tip: Vec<f64> = p.at.iter().zip(&p.force).map(|(x, f)| x + k * f).collect();
            (at(&p.at), at(&tip))
        })
    });
    if let Some(e) = estimate {
        points.extend(e.markers.iter().map(|m| at(&m.measured)));
    }
    points.extend(arrow.iter().flat_map(|(a, b)| [*a, *b]));
    let (x, y) = (
        padded(points.iter().map(|p| p.0), 0.08),
        padded(points.iter().map(|p| p.1), 0.08),
    );
    let (w, h) = area.dim_in_pixel();
    let (margin, xl, yl, caption) = (12u32, 45u32, 70u32, 30u32);
    let plot_px = (
        w.saturating_sub(2 * margin + yl),
        h.saturating_sub(2 * margin + xl + caption),
    );
    let (x, y) = equal_aspect(x, y, plot_px);
    let (fx, fy) = (ticks(x, 1e3), ticks(y, 1e3));
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!("{}–{} view (equal axes)", AXES[a], AXES[b]),
            (FONT, 18),
        )
        .margin(margin)
        .x_label_area_size(xl)
        .y_label_area_size(yl)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(ms)?;
    chart
        .configure_mesh()
        .x_desc(format!("{} (mm)", AXES[a]))
        .y_desc(format!("{} (mm)", AXES[b]))
        .axis_desc_style((FONT, 15))
        .label_style((FONT, 13))
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(ms)?;
    layout::data_in(chart.plotting_area());
    for (k, line) in lines.iter().enumerate() {
        let s = chart
            .draw_series(LineSeries::new(line.iter().map(at), SHAPE.stroke_width(3)))
            .map_err(ms)?;
        if k == 0 {
            s.label(if ring { "legs" } else { "backbone" })
                .legend(|(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], SHAPE.stroke_width(3))
                });
        }
    }
    if ring {
        // each edge on its own: a wide polyline's miter join at a turn of
        // 180° (a platform seen edge-on) would spike out of the axes
        let ends: Vec<(f64, f64)> = lines.iter().filter_map(|l| l.last().map(at)).collect();
        let n = ends.len();
        chart
            .draw_series(
                (0..n).map(|i| {
                    PathElement::new(vec![ends[i], ends[(i + 1) % n]], BLACK.stroke_width(2))
                }),
            )
            .map_err(ms)?
            .label("platform")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.stroke_width(2)));
    }
    if let Some(e) = estimate.filter(|e| !e.markers.is_empty()) {
        chart
            .draw_series(
                e.markers
                    .iter()
                    .map(|m| Circle::new(at(&m.measured), 7, MEASURED.stroke_width(2))),
            )
            .map_err(ms)?
            .label("marker, measured")
            .legend(|(x, y)| Circle::new((x + 10, y), 7, MEASURED.stroke_width(2)));
        chart
            .draw_series(
                e.markers
                    .iter()
                    .map(|m| Circle::new(at(&m.fitted), 3, FITTED.filled())),
            )
            .map_err(ms)?
            .label("marker, fitted (the estimated shape)")
            .legend(|(x, y)| Circle::new((x + 10, y), 3, FITTED.filled()));
    }
    if let Some((from, to)) = arrow {
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![from, to],
                LOAD.stroke_width(3),
            )))
            .map_err(ms)?
            .label("estimated point force (direction; its size in the load panel)")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], LOAD.stroke_width(3)));
        chart
            .draw_series(std::iter::once(Circle::new(to, 4, LOAD.filled())))
            .map_err(ms)?;
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}

/// An estimated point force: one bar per component with its ±1σ.
fn draw_point_force<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    p: &PointForce,
) -> std::result::Result<(), String> {
    let n = p.force.len();
    let sd = |k: usize| p.std.get(k).copied().unwrap_or(0.0);
    let (y0, y1) = padded(
        (0..n).flat_map(|k| [p.force[k] - sd(k), p.force[k] + sd(k), 0.0]),
        0.15,
    );
    let fy = ticks((y0, y1), 1.0);
    let mut chart = ChartBuilder::on(area)
        .caption(
            format!(
                "estimated point force at node {} (s = {} mm), ±1σ",
                p.node,
                sig3(p.s_m * 1e3)
            ),
            (FONT, 18),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d((0..n as i32 - 1).into_segmented(), y0..y1)
        .map_err(ms)?;
    let xl = |v: &SegmentValue<i32>| match v {
        SegmentValue::CenterOf(i) if (*i as usize) < n => format!("F{}", AXES[*i as usize]),
        _ => String::new(),
    };
    chart
        .configure_mesh()
        .disable_x_mesh()
        .x_labels(n + 1)
        .x_label_formatter(&xl)
        .y_label_formatter(&fy)
        .x_desc("component (world axes)")
        .y_desc("force (N)")
        .axis_desc_style((FONT, 15))
        .label_style((FONT, 13))
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(ms)?;
    layout::data_in(chart.plotting_area());
    for k in 0..n {
        let i = k as i32;
        let f = p.force[k];
        chart
            .draw_series(std::iter::once(Rectangle::new(
                [
                    (SegmentValue::Exact(i), 0.0),
                    (SegmentValue::Exact(i + 1), f),
                ],
                COMPONENTS[k % 3].mix(0.7).filled(),
            )))
            .map_err(ms)?;
        // the ±1σ bar: a vertical line with a cap at each end
        let c = SegmentValue::CenterOf(i);
        chart
            .draw_series(std::iter::once(PathElement::new(
                vec![(c.clone(), f - sd(k)), (c.clone(), f + sd(k))],
                BLACK.stroke_width(2),
            )))
            .map_err(ms)?;
        for end in [f - sd(k), f + sd(k)] {
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at((c.clone(), end))
                        + PathElement::new(vec![(-8, 0), (8, 0)], BLACK.stroke_width(2)),
                ))
                .map_err(ms)?;
        }
    }
    layout::annotations();
    Ok(())
}

/// The estimated load `w(s)` per component with its ±1σ band.
fn draw_load<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    e: &EstimatePart,
) -> std::result::Result<(), String> {
    let dim = e.load.first().map(|l| l.w.len()).unwrap_or(0);
    let band = |l: &Sample, k: usize, sign: f64| {
        l.w[k]
            + sign
                * l.std
                    .as_ref()
                    .and_then(|s| s.get(k))
                    .copied()
                    .unwrap_or(0.0)
    };
    let (s0, s1) = padded(e.load.iter().map(|l| l.s), 0.0);
    let (y0, y1) = padded(
        e.load
            .iter()
            .flat_map(|l| (0..dim).flat_map(move |k| [band(l, k, -1.0), band(l, k, 1.0)])),
        0.1,
    );
    let has_std = e.load.iter().any(|l| l.std.is_some());
    let (fs, fy) = (ticks((s0, s1), 1e3), ticks((y0, y1), 1.0));
    let mut chart = ChartBuilder::on(area)
        .caption(
            if has_std {
                "estimated load along the backbone (band: ±1σ of the marker noise)"
            } else {
                "estimated load along the backbone (no σ in this record)"
            },
            (FONT, 18),
        )
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(s0..s1, y0..y1)
        .map_err(ms)?;
    chart
        .configure_mesh()
        .x_desc("arc coordinate s (mm)")
        .y_desc("load per length w (N/m)")
        .axis_desc_style((FONT, 15))
        .label_style((FONT, 13))
        .x_label_formatter(&fs)
        .y_label_formatter(&fy)
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(ms)?;
    layout::data_in(chart.plotting_area());
    for (k, colour) in COMPONENTS.iter().enumerate().take(dim) {
        if has_std {
            let upper = e.load.iter().map(|l| (l.s, band(l, k, 1.0)));
            let lower = e.load.iter().rev().map(|l| (l.s, band(l, k, -1.0)));
            chart
                .draw_series(std::iter::once(Polygon::new(
                    upper.chain(lower).collect::<Vec<_>>(),
                    colour.mix(0.2).filled(),
                )))
                .map_err(ms)?;
        }
        let c = *colour;
        chart
            .draw_series(LineSeries::new(
                e.load.iter().map(|l| (l.s, l.w[k])),
                c.stroke_width(2),
            ))
            .map_err(ms)?
            .label(format!("w{}", AXES[k]))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
}

/// Each marker's residual `|measured − fitted|` (µm) against its arc
/// coordinate, with the stated noise σ.
fn draw_residuals<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    e: &EstimatePart,
) -> std::result::Result<(), String> {
    let r: Vec<(f64, f64)> = e
        .markers
        .iter()
        .map(|m| {
            let d2: f64 = m
                .measured
                .iter()
                .zip(&m.fitted)
                .map(|(a, b)| (a - b) * (a - b))
                .sum();
            (m.s_m, d2.sqrt() * 1e6)
        })
        .collect();
    let sigma_um = e.noise_sigma_m.map(|s| s * 1e6);
    let (_, top) = padded(r.iter().map(|p| p.1).chain(sigma_um).chain([0.0]), 0.15);
    let (s0, s1) = padded(
        e.load.iter().map(|l| l.s).chain(r.iter().map(|p| p.0)),
        0.05,
    );
    let (fs, fy) = (ticks((s0, s1), 1e3), ticks((0.0, top), 1.0));
    let mut chart = ChartBuilder::on(area)
        .caption("marker residuals |measured − fitted|", (FONT, 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(s0..s1, 0.0..top)
        .map_err(ms)?;
    chart
        .configure_mesh()
        .x_desc("arc coordinate s (mm)")
        .y_desc("residual (µm)")
        .axis_desc_style((FONT, 15))
        .label_style((FONT, 13))
        .x_label_formatter(&fs)
        .y_label_formatter(&fy)
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(ms)?;
    layout::data_in(chart.plotting_area());
    for &(s, v) in &r {
        chart
            .draw_series(LineSeries::new(
                [(s, 0.0), (s, v)],
                MEASURED.stroke_width(2),
            ))
            .map_err(ms)?;
    }
    chart
        .draw_series(r.iter().map(|&p| Circle::new(p, 5, MEASURED.filled())))
        .map_err(ms)?
        .label("a marker's residual")
        .legend(|(x, y)| Circle::new((x + 10, y), 5, MEASURED.filled()));
    if let Some(sig) = sigma_um {
        chart
            .draw_series(LineSeries::new(
                [(s0, sig), (s1, sig)],
                BLACK.mix(0.6).stroke_width(1),
            ))
            .map_err(ms)?
            .label(format!("stated marker noise σ = {} µm", sig3(sig)))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], BLACK.mix(0.6)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperRight)
}

/// An avoidance run: its shapes, the goal, the touched points and their
/// estimated contact forces (arrows; the scale in the legend).
fn draw_avoid<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    a: &AvoidIn,
) -> std::result::Result<(), String> {
    let pts: Vec<(f64, f64)> = a
        .shapes
        .iter()
        .flat_map(|(_, s)| s.iter().map(|p| (p[0], p[1])))
        .chain(std::iter::once((a.goal_m[0], a.goal_m[1])))
        .chain(a.touched.iter().map(|t| (t.point_m[0], t.point_m[1])))
        .collect();
    // force arrows: the largest force a fifth of the shapes' extent
    let x = padded(pts.iter().map(|p| p.0), 0.0);
    let fmax = a
        .touched
        .iter()
        .map(|t| t.force_n[0].hypot(t.force_n[1]))
        .fold(0.0, f64::max);
    let m_per_n = if fmax > 0.0 {
        0.2 * (x.1 - x.0) / fmax
    } else {
        0.0
    };
    let tips = a.touched.iter().map(|t| {
        (
            t.point_m[0] + m_per_n * t.force_n[0],
            t.point_m[1] + m_per_n * t.force_n[1],
        )
    });
    let pts: Vec<(f64, f64)> = pts.iter().copied().chain(tips).collect();
    let (x, y) = (
        padded(pts.iter().map(|p| p.0), 0.12),
        padded(pts.iter().map(|p| p.1), 0.12),
    );
    let (w, h) = area.dim_in_pixel();
    let (x, y) = equal_aspect(x, y, (w.saturating_sub(106), h.saturating_sub(111)));
    let (fx, fy) = (ticks(x, 1e3), ticks(y, 1e3));
    let mut chart = ChartBuilder::on(area)
        .caption("x–y view (equal axes)", (FONT, 18))
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x.0..x.1, y.0..y.1)
        .map_err(ms)?;
    chart
        .configure_mesh()
        .x_desc("x (mm)")
        .y_desc("y (mm)")
        .axis_desc_style((FONT, 15))
        .label_style((FONT, 13))
        .x_label_formatter(&fx)
        .y_label_formatter(&fy)
        .light_line_style(RGBColor(235, 235, 235))
        .draw()
        .map_err(ms)?;
    layout::data_in(chart.plotting_area());
    let n = a.shapes.len();
    for (i, (_, s)) in a.shapes.iter().enumerate() {
        let last = i + 1 == n;
        let style = if last {
            SHAPE.stroke_width(3)
        } else {
            RGBColor(190, 190, 190).stroke_width(1)
        };
        let series = chart
            .draw_series(LineSeries::new(s.iter().map(|p| (p[0], p[1])), style))
            .map_err(ms)?;
        if last {
            series.label("the last shape").legend(|(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], SHAPE.stroke_width(3))
            });
        }
    }
    chart
        .draw_series(std::iter::once(Cross::new(
            (a.goal_m[0], a.goal_m[1]),
            9,
            RGBColor(0, 150, 0).stroke_width(3),
        )))
        .map_err(ms)?
        .label("goal")
        .legend(|(x, y)| Cross::new((x + 10, y), 6, RGBColor(0, 150, 0).stroke_width(3)));
    if !a.touched.is_empty() {
        chart
            .draw_series(
                a.touched
                    .iter()
                    .map(|t| Circle::new((t.point_m[0], t.point_m[1]), 6, MEASURED.filled())),
            )
            .map_err(ms)?
            .label("obstacle point learnt by touch")
            .legend(|(x, y)| Circle::new((x + 10, y), 6, MEASURED.filled()));
        chart
            .draw_series(a.touched.iter().map(|t| {
                let p = (t.point_m[0], t.point_m[1]);
                PathElement::new(
                    vec![
                        p,
                        (p.0 + m_per_n * t.force_n[0], p.1 + m_per_n * t.force_n[1]),
                    ],
                    FITTED.stroke_width(2),
                )
            }))
            .map_err(ms)?
            .label(format!(
                "estimated contact force on the robot ({:.0} mm per N)",
                m_per_n * 1e3
            ))
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], FITTED.stroke_width(2)));
    }
    draw_legend(&mut chart, SeriesLabelPosition::UpperLeft)
}
