//! The report's charts (plotters, PNG and SVG from one drawing function).
//!
//! Text on a PNG needs a font: DejaVu Sans (`DejaVuSans.ttf`, bundled in this
//! directory with its license `LICENSE_DEJAVU`: Bitstream Vera license plus
//! public-domain DejaVu changes) is registered as "sans-serif" once.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use crate::error::{Error, Result};
use crate::estimate::Backend;

use super::layout::{self, LayoutIssue, Recorder};
use super::pareto::{LabelledPoint, ParetoPoint, ParetoReport};
use super::stability::{MapSpec, StabilityReport};
use super::sweep::FailureCause;

const FONT: &str = "sans-serif";

/// Registers the bundled font (once).
///
/// # Errors
/// [`Error::Io`] if the bundled font cannot be parsed (it can).
pub(crate) fn register_font() -> Result<()> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font(FONT, FontStyle::Normal, include_bytes!("DejaVuSans.ttf"))
            .is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::Io {
            path: "src/report/DejaVuSans.ttf".into(),
            message: "the bundled font could not be registered".into(),
        })
    }
}

pub(super) fn ms<E: std::fmt::Debug>(e: E) -> String {
    format!("{e:?}")
}

/// Draws with `draw` through the layout [`Recorder`]: the drawing's
/// result and what the layout check found (see [`super::layout`]).
pub(super) fn draw_recorded<DB: DrawingBackend>(
    backend: DB,
    draw: impl FnOnce(&DrawingArea<Recorder<DB>, Shift>) -> std::result::Result<(), String>,
) -> (std::result::Result<(), String>, Vec<LayoutIssue>) {
    let size = backend.get_size();
    layout::recorded(size, || {
        let root = Recorder(backend).into_drawing_area();
        draw(&root)?;
        root.present().map_err(ms)
    })
}

/// Each layout issue of the chart at `path` as a warning on standard error
/// (and kept for the report's summary).
pub(super) fn warn_layout(path: &Path, issues: &[LayoutIssue]) {
    layout::keep_chart_issues(path, issues);
    for i in issues {
        eprintln!("softrod: warning: chart {}: layout: {i}", path.display());
    }
}

/// A PNG drawing function through the layout recorder.
pub(super) type PngArea<'a> = DrawingArea<Recorder<BitMapBackend<'a>>, Shift>;
/// An SVG drawing function through the layout recorder.
pub(super) type SvgArea<'a> = DrawingArea<Recorder<SVGBackend<'a>>, Shift>;

/// Draws with `draw` into `<dir>/<stem>.png` and `<dir>/<stem>.svg`; the
/// PNG's drawing is layout-checked, its issues warned on standard error
/// and returned.
pub(super) fn both_checked(
    dir: &Path,
    stem: &str,
    size: (u32, u32),
    draw_png: impl Fn(&PngArea) -> std::result::Result<(), String>,
    draw_svg: impl Fn(&SvgArea) -> std::result::Result<(), String>,
) -> Result<(Vec<PathBuf>, Vec<LayoutIssue>)> {
    register_font()?;
    let png = dir.join(format!("{stem}.png"));
    let svg = dir.join(format!("{stem}.svg"));
    let mut issues = Vec::new();
    // drawn into temporary files, renamed when whole (atomic output)
    super::atomic::with_temp(&png, |tmp| {
        let (r, found) = draw_recorded(BitMapBackend::new(tmp, size), &draw_png);
        issues = found;
        r.map_err(|m| super::io_error(&png, m))
    })?;
    super::atomic::with_temp(&svg, |tmp| {
        // the same drawing: not recorded again
        let root = Recorder(SVGBackend::new(tmp, size)).into_drawing_area();
        draw_svg(&root).map_err(|m| super::io_error(&svg, m))?;
        root.present().map_err(|e| super::io_error(&svg, ms(e)))
    })?;
    warn_layout(&png, &issues);
    Ok((vec![png, svg], issues))
}

/// [`both_checked`] without its issues (warned on standard error).
pub(super) fn both(
    dir: &Path,
    stem: &str,
    size: (u32, u32),
    draw_png: impl Fn(&PngArea) -> std::result::Result<(), String>,
    draw_svg: impl Fn(&SvgArea) -> std::result::Result<(), String>,
) -> Result<Vec<PathBuf>> {
    Ok(both_checked(dir, stem, size, draw_png, draw_svg)?.0)
}

fn backend_colour(b: Backend) -> RGBColor {
    match b {
        Backend::Newton => RGBColor(31, 119, 180),
        Backend::Sqp => RGBColor(214, 39, 40),
    }
}

/// One metric panel of the Pareto chart.
struct Metric {
    title: &'static str,
    axis: &'static str,
    scale: f64,
    get: fn(&ParetoPoint) -> f64,
    extra: fn(&LabelledPoint) -> f64,
    front: fn(&ParetoPoint) -> bool,
}

const METRICS: [Metric; 3] = [
    Metric {
        title: "(a) backbone",
        axis: "backbone RMS error (mm)",
        scale: 1e3,
        get: |p| p.backbone_rms_m,
        extra: |p| p.backbone_rms_m,
        front: |p| p.front_backbone,
    },
    Metric {
        title: "(b) load field",
        axis: "load error ‖w − w_ref‖ / ‖w_ref‖ (%)",
        scale: 100.0,
        get: |p| p.load_rel_l2,
        extra: |p| p.load_rel_l2,
        front: |p| p.front_load,
    },
    Metric {
        title: "(c) resultant force",
        axis: "resultant force error (%)",
        scale: 100.0,
        get: |p| p.force_rel,
        extra: |p| p.force_rel,
        front: |p| p.front_force,
    },
];

fn log_range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(a, b), v| (a.min(v), b.max(v)));
    if !(lo.is_finite() && hi > 0.0) {
        return (0.1, 10.0);
    }
    let lo = 10f64.powf((lo.log10() - 0.15).floor());
    let hi = 10f64.powf((hi.log10() + 0.15).ceil());
    (lo, hi.max(lo * 10.0))
}

fn pareto_draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    report: &ParetoReport,
    extra: &[LabelledPoint],
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(ms)?;
    let (title_area, body) = root.split_vertically(50);
    title_area
        .draw(&Text::new(
            format!(
                "Speed against accuracy: estimators on exudyn 128-element references ({}), {} markers noise σ = {} mm",
                report.grid.references.join(", "),
                "equally spaced",
                report.grid.noise_m * 1e3
            ),
            (20, 15),
            (FONT, 20).into_font(),
        ))
        .map_err(ms)?;
    let (panels_area, legend_area) = body.split_vertically(body.dim_in_pixel().1 - 70);
    let panels = panels_area.split_evenly((1, 3));
    let pts: Vec<&ParetoPoint> = report.points.iter().filter(|p| p.converged).collect();
    let (x0, x1) = log_range(
        pts.iter()
            .map(|p| p.median_step_s * 1e3)
            .chain(extra.iter().map(|e| e.median_step_s * 1e3)),
    );
    let marker_counts = &report.grid.markers;
    for (metric, area) in METRICS.iter().zip(panels.iter()) {
        let (y0, y1) = log_range(
            pts.iter()
                .map(|p| (metric.get)(p) * metric.scale)
                .chain(extra.iter().map(|e| (metric.extra)(e) * metric.scale)),
        );
        let mut chart = ChartBuilder::on(area)
            .caption(metric.title, (FONT, 18))
            .margin(12)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())
            .map_err(ms)?;
        chart
            .configure_mesh()
            .x_desc("median time per warm estimate (ms)")
            .y_desc(metric.axis)
            .axis_desc_style((FONT, 15))
            .label_style((FONT, 13))
            .x_label_formatter(&|v| fmt_tick(*v))
            .y_label_formatter(&|v| fmt_tick(*v))
            .light_line_style(RGBColor(235, 235, 235))
            .draw()
            .map_err(ms)?;
        layout::data_in(chart.plotting_area());
        // labels go where they cover no other label and stay in the axes
        let mut labels = Labels::new(chart.plotting_area().get_pixel_range());
        // the front: a staircase through its members, fastest first
        let mut front: Vec<&&ParetoPoint> = pts.iter().filter(|p| (metric.front)(p)).collect();
        front.sort_by(|a, b| a.median_step_s.total_cmp(&b.median_step_s));
        let mut stairs = Vec::new();
        for (i, p) in front.iter().enumerate() {
            let xy = (p.median_step_s * 1e3, (metric.get)(p) * metric.scale);
            if i > 0 {
                stairs.push((
                    xy.0,
                    stairs.last().map(|s: &(f64, f64)| s.1).unwrap_or(xy.1),
                ));
            }
            stairs.push(xy);
        }
        chart
            .draw_series(LineSeries::new(stairs, BLACK.stroke_width(1)))
            .map_err(ms)?;
        chart
            .draw_series(front.iter().map(|p| {
                Circle::new(
                    (p.median_step_s * 1e3, (metric.get)(p) * metric.scale),
                    9,
                    BLACK.stroke_width(2),
                )
            }))
            .map_err(ms)?;
        for p in &pts {
            let xy = (p.median_step_s * 1e3, (metric.get)(p) * metric.scale);
            let c = backend_colour(p.backend);
            let k = marker_counts
                .iter()
                .position(|m| *m == p.markers)
                .unwrap_or(0);
            let st = c.filled();
            let at = EmptyElement::at(xy);
            match k % 4 {
                0 => chart
                    .draw_series(std::iter::once(at + Circle::new((0, 0), 5, st)))
                    .map(|_| ()),
                1 => chart
                    .draw_series(std::iter::once(at + TriangleMarker::new((0, 0), 7, st)))
                    .map(|_| ()),
                2 => chart
                    .draw_series(std::iter::once(at + Rectangle::new([(-5, -5), (5, 5)], st)))
                    .map(|_| ()),
                _ => chart
                    .draw_series(std::iter::once(
                        at + Polygon::new(vec![(0, -7), (6, 0), (0, 7), (-6, 0)], st),
                    ))
                    .map(|_| ()),
            }
            .map_err(ms)?;
            let text = format!("{}", p.elements);
            if let Some((dx, dy, pos)) = labels.place(area, &text, 13, chart.backend_coord(&xy)) {
                chart
                    .draw_series(std::iter::once(
                        EmptyElement::at(xy)
                            + Text::new(text, (dx, dy), (FONT, 13).into_font().color(&c).pos(pos)),
                    ))
                    .map_err(ms)?;
            }
        }
        for e in extra {
            let xy = (e.median_step_s * 1e3, (metric.extra)(e) * metric.scale);
            if xy.0.is_finite() && xy.1.is_finite() && xy.0 > 0.0 && xy.1 > 0.0 {
                chart
                    .draw_series(std::iter::once(Cross::new(
                        xy,
                        9,
                        RGBColor(0, 150, 0).stroke_width(3),
                    )))
                    .map_err(ms)?;
                let at = chart.backend_coord(&xy);
                if let Some((dx, dy, pos)) = labels.place(area, &e.label, 14, at) {
                    chart
                        .draw_series(std::iter::once(
                            EmptyElement::at(xy)
                                + Text::new(
                                    e.label.clone(),
                                    (dx, dy),
                                    (FONT, 14).into_font().color(&RGBColor(0, 120, 0)).pos(pos),
                                ),
                        ))
                        .map_err(ms)?;
                }
            }
        }
        layout::annotations();
    }
    pareto_legend(&legend_area, marker_counts, !extra.is_empty())
}

/// The legend rows under the Pareto panels: items placed one after the
/// other by their measured widths, a new row when one would leave the
/// canvas.
fn pareto_legend<'a, DB: DrawingBackend + 'a>(
    area: &DrawingArea<DB, Shift>,
    marker_counts: &[usize],
    marked: bool,
) -> std::result::Result<(), String> {
    let style = |c: &RGBColor| (FONT, 15).into_font().color(c);
    let width = area.dim_in_pixel().0 as i32;
    let (mut x, mut y) = (30, 18);
    // one item: its glyph drawn by `glyph` at (x, y) and its text after it
    let mut item = |text: &str,
                    colour: RGBColor,
                    glyph: &dyn Fn((i32, i32)) -> DynElement<'a, DB, (i32, i32)>|
     -> std::result::Result<(), String> {
        let w = area
            .estimate_text_size(text, &style(&colour))
            .map_err(ms)?
            .0 as i32;
        if x + 26 + w > width - 10 {
            x = 30;
            y += 28;
        }
        area.draw(&glyph((x + 8, y))).map_err(ms)?;
        area.draw(&Text::new(
            text.to_string(),
            (x + 24, y - 9),
            style(&colour),
        ))
        .map_err(ms)?;
        x += 24 + w + 36;
        Ok(())
    };
    for b in [Backend::Newton, Backend::Sqp] {
        let c = backend_colour(b);
        item(&format!("backend {}", b.name()), BLACK, &|(x, y)| {
            Rectangle::new([(x - 8, y - 6), (x + 12, y + 6)], c.filled()).into_dyn()
        })?;
    }
    for (k, m) in marker_counts.iter().enumerate() {
        item(&format!("{m} markers"), BLACK, &|xy| {
            shape_px(k, xy, RGBColor(90, 90, 90))
        })?;
    }
    item(
        "Pareto front (faster or more accurate than every other)",
        BLACK,
        &|xy| Circle::new(xy, 9, BLACK.stroke_width(2)).into_dyn(),
    )?;
    item(
        "number next to a point: elements of the model (where there is room)",
        RGBColor(80, 80, 80),
        &|xy| EmptyElement::at(xy).into_dyn(),
    )?;
    if marked {
        item("elements: \"auto\" (marked points)", BLACK, &|xy| {
            Cross::new(xy, 9, RGBColor(0, 150, 0).stroke_width(3)).into_dyn()
        })?;
    }
    Ok(())
}

/// Labels placed next to their points where they cover no other label and
/// stay inside the plotting area (pixels).
struct Labels {
    area: (std::ops::Range<i32>, std::ops::Range<i32>),
    placed: Vec<(i32, i32, i32, i32)>,
}

impl Labels {
    fn new(area: (std::ops::Range<i32>, std::ops::Range<i32>)) -> Self {
        Labels {
            area,
            placed: Vec::new(),
        }
    }

    /// Where `text` (font size `size`) goes next to the point at pixel
    /// `at`: the offset and anchor of the first free spot (right above,
    /// right below, left above, left below), or `None`.
    fn place<DB: DrawingBackend>(
        &mut self,
        canvas: &DrawingArea<DB, Shift>,
        text: &str,
        size: u32,
        at: (i32, i32),
    ) -> Option<(i32, i32, Pos)> {
        let (w, h) = canvas
            .estimate_text_size(text, &TextStyle::from((FONT, size).into_font()))
            .ok()?;
        let (w, h) = (w as i32, h as i32 + 2);
        // (dx, dy, to the right, below)
        // clear of the point's glyph (up to 9 px)
        let spots = [
            (8, -5, true, false),
            (8, 5, true, true),
            (-8, -5, false, false),
            (-8, 5, false, true),
        ];
        for (dx, dy, right, below) in spots {
            let x0 = if right { at.0 + dx } else { at.0 + dx - w };
            let y0 = if below { at.1 + dy } else { at.1 + dy - h };
            let b = (x0, y0, x0 + w, y0 + h);
            let inside = b.0 >= self.area.0.start
                && b.2 < self.area.0.end
                && b.1 >= self.area.1.start
                && b.3 < self.area.1.end;
            let free = self
                .placed
                .iter()
                .all(|p| b.2 <= p.0 || p.2 <= b.0 || b.3 <= p.1 || p.3 <= b.1);
            if inside && free {
                self.placed.push(b);
                let hp = if right { HPos::Left } else { HPos::Right };
                let vp = if below { VPos::Top } else { VPos::Bottom };
                return Some((dx, dy, Pos::new(hp, vp)));
            }
        }
        None
    }
}

/// The same glyph at a pixel position (legend).
fn shape_px<'a, DB: DrawingBackend + 'a>(
    k: usize,
    xy: (i32, i32),
    c: RGBColor,
) -> DynElement<'a, DB, (i32, i32)> {
    let st = c.filled();
    match k % 4 {
        0 => (EmptyElement::at(xy) + Circle::new((0, 0), 5, st)).into_dyn(),
        1 => (EmptyElement::at(xy) + TriangleMarker::new((0, 0), 7, st)).into_dyn(),
        2 => (EmptyElement::at(xy) + Rectangle::new([(-5, -5), (5, 5)], st)).into_dyn(),
        _ => (EmptyElement::at(xy) + Polygon::new(vec![(0, -7), (6, 0), (0, 7), (-6, 0)], st))
            .into_dyn(),
    }
}

pub(super) fn fmt_tick(v: f64) -> String {
    if (1.0..1e4).contains(&v) {
        format!("{}", (v * 1e3).round() / 1e3)
    } else if (0.01..1.0).contains(&v) {
        format!("{}", (v * 1e4).round() / 1e4)
    } else {
        format!("{v:.0e}")
    }
}

/// Writes `pareto.png` and `pareto.svg`.
///
/// # Errors
/// [`Error::Io`] when a file cannot be written.
pub(crate) fn pareto_chart(
    report: &ParetoReport,
    extra: &[LabelledPoint],
    dir: &Path,
) -> Result<Vec<PathBuf>> {
    both(
        dir,
        "pareto",
        (1950, 720),
        |a| pareto_draw(a, report, extra),
        |a| pareto_draw(a, report, extra),
    )
}

/// A perceptually ordered colour map (viridis anchors, linear between), `t` in [0, 1].
pub(crate) fn viridis(t: f64) -> RGBColor {
    const A: [(u8, u8, u8); 6] = [
        (68, 1, 84),
        (65, 68, 135),
        (42, 120, 142),
        (34, 168, 132),
        (122, 209, 81),
        (253, 231, 37),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (A.len() - 1) as f64;
    let i = (x.floor() as usize).min(A.len() - 2);
    let f = x - i as f64;
    let m = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    RGBColor(
        m(A[i].0, A[i + 1].0),
        m(A[i].1, A[i + 1].1),
        m(A[i].2, A[i + 1].2),
    )
}

fn stability_draw<DB: DrawingBackend>(
    root: &DrawingArea<DB, Shift>,
    report: &StabilityReport,
    map: &MapSpec,
) -> std::result::Result<(), String> {
    root.fill(&WHITE).map_err(ms)?;
    let (title_area, body) = root.split_vertically(50);
    title_area
        .draw(&Text::new(
            format!("Stability: {} × {}", map.x.title(), map.y.title()),
            (20, 6),
            (FONT, 20).into_font(),
        ))
        .map_err(ms)?;
    title_area
        .draw(&Text::new(
            "colour and upper number: backbone RMS error against exudyn (mm); lower number: load error ‖w − w_ref‖/‖w_ref‖ (%); grey: failed, with the cause",
            (20, 30),
            (FONT, 14).into_font().color(&RGBColor(60, 60, 60)),
        ))
        .map_err(ms)?;
    let (main, bar) = body.split_horizontally(body.dim_in_pixel().0 - 130);
    let panels = main.split_evenly((1, report.backends.len().max(1)));
    // one colour scale for both backends
    let vals: Vec<f64> = report
        .cells
        .iter()
        .filter(|c| c.map == map.name)
        .filter_map(|c| c.outcome.errors.map(|e| e.backbone_rms_m * 1e3))
        .filter(|v| v.is_finite() && *v > 0.0)
        .collect();
    let (lo, hi) = log_range(vals.iter().copied());
    for (b, area) in report.backends.iter().zip(panels.iter()) {
        backend_panel(area, report, map, *b, (lo, hi))?;
    }
    colour_bar(&bar, (lo, hi))
}

/// Where `v` lies on the logarithmic colour scale `[lo, hi]` (0 to 1).
fn log_t(v: f64, (lo, hi): (f64, f64)) -> f64 {
    (v.log10() - lo.log10()) / (hi.log10() - lo.log10())
}

/// One backend's panel of a stability map: a cell per grid point, its
/// colour and numbers (or its failure's cause) on the scale `[lo, hi]` (mm).
fn backend_panel<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    report: &StabilityReport,
    map: &MapSpec,
    b: Backend,
    scale: (f64, f64),
) -> std::result::Result<(), String> {
    let t_of = |v: f64| log_t(v, scale);
    let nx = map.x_values.len() as i32;
    let ny = map.y_values.len() as i32;
    let mut chart = ChartBuilder::on(area)
        .caption(format!("backend {}", b.name()), (FONT, 18))
        .margin(12)
        .x_label_area_size(50)
        .y_label_area_size(70)
        .build_cartesian_2d((0..nx - 1).into_segmented(), (0..ny - 1).into_segmented())
        .map_err(ms)?;
    let xl = |v: &SegmentValue<i32>| match v {
        SegmentValue::CenterOf(i) if *i >= 0 && *i < nx => map.x.label(map.x_values[*i as usize]),
        _ => String::new(),
    };
    let yl = |v: &SegmentValue<i32>| match v {
        SegmentValue::CenterOf(i) if *i >= 0 && *i < ny => map.y.label(map.y_values[*i as usize]),
        _ => String::new(),
    };
    chart
        .configure_mesh()
        .disable_mesh()
        .x_labels(nx as usize + 1)
        .y_labels(ny as usize + 1)
        .x_desc(map.x.title())
        .y_desc(map.y.title())
        .axis_desc_style((FONT, 16))
        .label_style((FONT, 14))
        .x_label_formatter(&xl)
        .y_label_formatter(&yl)
        .draw()
        .map_err(ms)?;
    for c in report.cells_of(&map.name, b) {
        let (ix, iy) = (c.index.0 as i32, c.index.1 as i32);
        let rect = [
            (SegmentValue::Exact(ix), SegmentValue::Exact(iy)),
            (SegmentValue::Exact(ix + 1), SegmentValue::Exact(iy + 1)),
        ];
        let centre = (SegmentValue::CenterOf(ix), SegmentValue::CenterOf(iy));
        let (fill, text, tc) = match (c.outcome.is_converged(), c.outcome.errors) {
            (true, Some(e)) => {
                let t = t_of(e.backbone_rms_m * 1e3);
                let tc = if t > 0.55 { BLACK } else { WHITE };
                (
                    viridis(t),
                    format!(
                        "{}\n{:.0}%",
                        fmt_mm(e.backbone_rms_m * 1e3),
                        e.load_rel_l2 * 100.0
                    ),
                    tc,
                )
            }
            _ => (
                RGBColor(200, 200, 200),
                c.outcome
                    .cause()
                    .unwrap_or(FailureCause::Other)
                    .code()
                    .to_string(),
                RGBColor(150, 0, 0),
            ),
        };
        chart
            .draw_series(std::iter::once(Rectangle::new(rect.clone(), fill.filled())))
            .map_err(ms)?;
        chart
            .draw_series(std::iter::once(Rectangle::new(rect, WHITE.stroke_width(1))))
            .map_err(ms)?;
        let lines: Vec<&str> = text.lines().collect();
        for (k, line) in lines.iter().enumerate() {
            let dy = (k as i32 * 2 - (lines.len() as i32 - 1)) * 8;
            chart
                .draw_series(std::iter::once(
                    EmptyElement::at(centre.clone())
                        + Text::new(
                            line.to_string(),
                            (0, dy),
                            (FONT, 13)
                                .into_font()
                                .color(&tc)
                                .pos(Pos::new(HPos::Center, VPos::Center)),
                        ),
                ))
                .map_err(ms)?;
        }
    }
    Ok(())
}

/// The colour bar of the scale `[lo, hi]` (mm) beside the panels.
fn colour_bar<DB: DrawingBackend>(
    bar: &DrawingArea<DB, Shift>,
    (lo, hi): (f64, f64),
) -> std::result::Result<(), String> {
    let t_of = |v: f64| log_t(v, (lo, hi));
    let (_, h) = bar.dim_in_pixel();
    let (top, bottom) = (70i32, h as i32 - 70);
    let x0 = 20i32;
    let steps = 100;
    for k in 0..steps {
        let t0 = k as f64 / steps as f64;
        let y_a = bottom - ((bottom - top) as f64 * t0) as i32;
        let y_b = bottom - ((bottom - top) as f64 * (t0 + 1.0 / steps as f64)) as i32;
        bar.draw(&Rectangle::new(
            [(x0, y_b), (x0 + 25, y_a)],
            viridis(t0).filled(),
        ))
        .map_err(ms)?;
    }
    let mut d = lo;
    while d <= hi * 1.0001 {
        let t = t_of(d);
        let y = bottom - ((bottom - top) as f64 * t) as i32;
        bar.draw(&PathElement::new(vec![(x0 + 25, y), (x0 + 31, y)], BLACK))
            .map_err(ms)?;
        bar.draw(&Text::new(
            fmt_tick(d),
            (x0 + 34, y - 7),
            (FONT, 13).into_font(),
        ))
        .map_err(ms)?;
        d *= 10.0;
    }
    bar.draw(&Text::new(
        "RMS (mm)",
        (x0 - 10, top - 30),
        (FONT, 14).into_font(),
    ))
    .map_err(ms)?;
    Ok(())
}

fn fmt_mm(v: f64) -> String {
    if v >= 10.0 {
        format!("{v:.0}")
    } else if v >= 1.0 {
        format!("{v:.1}")
    } else if v >= 0.01 {
        format!("{v:.2}")
    } else {
        format!("{v:.0e}")
    }
}

/// Writes `stability_<map>.png` and `.svg`.
///
/// # Errors
/// [`Error::Io`] when a file cannot be written.
pub(crate) fn stability_map(
    report: &StabilityReport,
    map: &MapSpec,
    dir: &Path,
) -> Result<Vec<PathBuf>> {
    let nx = map.x_values.len() as u32;
    let width = (2 * (70 + 95 * nx.max(2)) + 200).max(1100);
    both(
        dir,
        &format!("stability_{}", map.name),
        (width, 640),
        |a| stability_draw(a, report, map),
        |a| stability_draw(a, report, map),
    )
}
