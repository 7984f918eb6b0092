//! The chart layout check: every chart the project draws goes through a
//! recording backend (`Recorder`, crate-internal) that notes where each text
//! lands (its box, measured with the font plotters draws it with) and,
//! between `data_in` and `annotations`, every data mark of a chart's
//! plotting area. A
//! [`LayoutIssue`] is a text outside the canvas, two texts that overlap, or
//! a data mark outside its axes.
//!
//! plotters clamps a series' vertices to its plotting area (a point beyond
//! the range is drawn on the border); what can leave the axes is what is
//! drawn in pixels from a point (a label, a glyph) or a wide stroke's
//! polygon (its miter joins), and these are what the data check sees.
//!
//! The chart code says where data starts: after a chart's mesh (axes, ticks
//! and their labels) is drawn, `layout::data_in(&chart.plotting_area())`;
//! before its legend or labels that may leave the axes on purpose,
//! `layout::annotations()`. What is drawn outside such a span is checked for
//! its text only.

use std::cell::RefCell;
use std::fmt;

use plotters::coord::CoordTranslate;
use plotters::prelude::DrawingArea;
use plotters_backend::text_anchor::{HPos, VPos};
use plotters_backend::{
    BackendColor, BackendCoord, BackendStyle, BackendTextStyle, DrawingBackend, DrawingErrorKind,
};
use serde::Serialize;

/// A box in pixels: `[x0, x1) × [y0, y1)`, `y` down.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct PixelBox {
    /// Left edge (px).
    pub x0: i32,
    /// Top edge (px).
    pub y0: i32,
    /// Right edge (px, exclusive).
    pub x1: i32,
    /// Bottom edge (px, exclusive).
    pub y1: i32,
}

impl PixelBox {
    /// The overlap of two boxes in pixels along x and y (0 if apart).
    fn overlap(&self, o: &PixelBox) -> (i32, i32) {
        (
            (self.x1.min(o.x1) - self.x0.max(o.x0)).max(0),
            (self.y1.min(o.y1) - self.y0.max(o.y0)).max(0),
        )
    }

    /// Whether the point lies within the box grown by `tol` pixels.
    fn holds(&self, p: BackendCoord, tol: i32) -> bool {
        p.0 >= self.x0 - tol && p.0 < self.x1 + tol && p.1 >= self.y0 - tol && p.1 < self.y1 + tol
    }

    /// Whether `o` lies within the box grown by `tol` pixels.
    fn contains(&self, o: &PixelBox, tol: i32) -> bool {
        o.x0 >= self.x0 - tol
            && o.y0 >= self.y0 - tol
            && o.x1 <= self.x1 + tol
            && o.y1 <= self.y1 + tol
    }
}

impl fmt::Display for PixelBox {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "[{}..{}]×[{}..{}] px",
            self.x0, self.x1, self.y0, self.y1
        )
    }
}

/// What the layout check found wrong with a chart.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum LayoutIssue {
    /// A text (partly) outside the canvas.
    TextOutsideCanvas {
        /// The text.
        text: String,
        /// Where it was drawn.
        at: PixelBox,
        /// The canvas (px).
        canvas: (u32, u32),
    },
    /// Two texts that overlap (by more than a pixel each way).
    TextOverlap {
        /// The first text drawn.
        first: String,
        /// Its box.
        first_at: PixelBox,
        /// The second.
        second: String,
        /// Its box.
        second_at: PixelBox,
    },
    /// A data mark (a line's vertex, a marker's centre, a band's corner)
    /// outside the plotting area it was drawn in.
    DataOutsideAxes {
        /// The plotting area (px).
        area: PixelBox,
        /// The mark (px).
        at: (i32, i32),
        /// Marks of this area outside it (this one is the first).
        count: usize,
    },
}

impl fmt::Display for LayoutIssue {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LayoutIssue::TextOutsideCanvas { text, at, canvas } => write!(
                f,
                "text \"{text}\" at {at} leaves the {}×{} canvas",
                canvas.0, canvas.1
            ),
            LayoutIssue::TextOverlap {
                first,
                first_at,
                second,
                second_at,
            } => write!(
                f,
                "text \"{first}\" at {first_at} overlaps \"{second}\" at {second_at}"
            ),
            LayoutIssue::DataOutsideAxes { area, at, count } => write!(
                f,
                "{count} data marks outside their axes {area}, the first at ({}, {}) px",
                at.0, at.1
            ),
        }
    }
}

/// What a drawing put where (the recorder's notes).
#[derive(Debug, Default)]
struct Log {
    canvas: (u32, u32),
    texts: Vec<(String, PixelBox)>,
    areas: Vec<(PixelBox, Vec<BackendCoord>)>,
    /// The area data marks go to now.
    current: Option<usize>,
}

thread_local! {
    static LOG: RefCell<Option<Log>> = const { RefCell::new(None) };
    /// Every checked chart's issues since the last [`take_chart_issues`].
    static CHARTS: RefCell<Vec<ChartIssue>> = const { RefCell::new(Vec::new()) };
}

/// A layout issue of a chart file.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChartIssue {
    /// The chart.
    pub chart: std::path::PathBuf,
    /// What is wrong with it.
    pub issue: LayoutIssue,
}

/// Keeps the issues of the chart `chart` for [`take_chart_issues`].
pub(crate) fn keep_chart_issues(chart: &std::path::Path, issues: &[LayoutIssue]) {
    CHARTS.with(|c| {
        c.borrow_mut().extend(issues.iter().map(|i| ChartIssue {
            chart: chart.to_path_buf(),
            issue: i.clone(),
        }))
    });
}

/// The issues kept on this thread since the last call (the report's
/// charts; [`super::ReportSummary::layout`]).
pub(crate) fn take_chart_issues() -> Vec<ChartIssue> {
    CHARTS.with(|c| std::mem::take(&mut *c.borrow_mut()))
}

/// Marks drawn from now on (on this thread) are data of `area`'s plotting
/// area, until the next [`data_in`] or [`annotations`].
pub(crate) fn data_in<DB: DrawingBackend, CT: CoordTranslate>(area: &DrawingArea<DB, CT>) {
    let (x, y) = area.get_pixel_range();
    let b = PixelBox {
        x0: x.start,
        x1: x.end,
        y0: y.start,
        y1: y.end,
    };
    LOG.with(|l| {
        if let Some(log) = l.borrow_mut().as_mut() {
            log.areas.push((b, Vec::new()));
            log.current = Some(log.areas.len() - 1);
        }
    });
}

/// Marks drawn from now on are not data (a legend, a label).
pub(crate) fn annotations() {
    LOG.with(|l| {
        if let Some(log) = l.borrow_mut().as_mut() {
            log.current = None;
        }
    });
}

fn note_marks(points: impl IntoIterator<Item = BackendCoord>) {
    LOG.with(|l| {
        if let Some(log) = l.borrow_mut().as_mut()
            && let Some(i) = log.current
        {
            log.areas[i].1.extend(points);
        }
    });
}

/// A text's box; a text drawn as data (a point's label) is also data: its
/// corners must lie within the axes.
fn note_text(text: &str, at: PixelBox) {
    LOG.with(|l| {
        if let Some(log) = l.borrow_mut().as_mut() {
            log.texts.push((text.to_string(), at));
            if let Some(i) = log.current {
                log.areas[i]
                    .1
                    .extend([(at.x0, at.y0), (at.x1 - 1, at.y1 - 1)]);
            }
        }
    });
}

/// Runs `draw` with the notes of every [`Recorder`] on this thread kept,
/// then checks them: `draw`'s result and what the check found.
pub(crate) fn recorded<T>(canvas: (u32, u32), draw: impl FnOnce() -> T) -> (T, Vec<LayoutIssue>) {
    LOG.with(|l| {
        *l.borrow_mut() = Some(Log {
            canvas,
            ..Log::default()
        })
    });
    let out = draw();
    let log = LOG.with(|l| l.borrow_mut().take()).unwrap_or_default();
    (out, check(&log))
}

/// The check of one drawing's notes.
fn check(log: &Log) -> Vec<LayoutIssue> {
    let canvas = PixelBox {
        x0: 0,
        y0: 0,
        x1: log.canvas.0 as i32,
        y1: log.canvas.1 as i32,
    };
    let mut issues = Vec::new();
    for (text, at) in &log.texts {
        if !canvas.contains(at, 0) {
            issues.push(LayoutIssue::TextOutsideCanvas {
                text: text.clone(),
                at: *at,
                canvas: log.canvas,
            });
        }
    }
    for (i, (a, ab)) in log.texts.iter().enumerate() {
        for (b, bb) in &log.texts[i + 1..] {
            if a == b && ab == bb {
                // the same text drawn twice on itself (plotters draws a
                // log axis's end tick twice): one label to the eye
                continue;
            }
            let (ox, oy) = ab.overlap(bb);
            if ox > 1 && oy > 1 {
                issues.push(LayoutIssue::TextOverlap {
                    first: a.clone(),
                    first_at: *ab,
                    second: b.clone(),
                    second_at: *bb,
                });
            }
        }
    }
    for (area, marks) in &log.areas {
        // a line of width w ends within its area; one pixel of rounding
        let outside: Vec<&BackendCoord> = marks.iter().filter(|p| !area.holds(**p, 1)).collect();
        if let Some(first) = outside.first() {
            issues.push(LayoutIssue::DataOutsideAxes {
                area: *area,
                at: **first,
                count: outside.len(),
            });
        }
    }
    issues
}

/// The box `text` covers when drawn at `pos` in `style` (as plotters'
/// default `draw_text` places it: the layout box moved by the anchor, then
/// turned by the style's transform about `pos`).
fn text_box<S: BackendTextStyle>(text: &str, style: &S, pos: BackendCoord) -> Option<PixelBox> {
    let ((min_x, min_y), (max_x, max_y)) = style.layout_box(text).ok()?;
    let (w, h) = (max_x - min_x, max_y - min_y);
    let dx = match style.anchor().h_pos {
        HPos::Left => 0,
        HPos::Right => -w,
        HPos::Center => -w / 2,
    };
    let dy = match style.anchor().v_pos {
        VPos::Top => 0,
        VPos::Center => -h / 2,
        VPos::Bottom => -h,
    };
    let t = style.transform();
    let corners =
        [(dx, dy), (dx + w, dy), (dx, dy + h), (dx + w, dy + h)].map(|(x, y)| t.transform(x, y));
    let (x0, x1) = (
        corners.iter().map(|c| c.0).min()?,
        corners.iter().map(|c| c.0).max()?,
    );
    let (y0, y1) = (
        corners.iter().map(|c| c.1).min()?,
        corners.iter().map(|c| c.1).max()?,
    );
    Some(PixelBox {
        x0: pos.0 + x0,
        x1: pos.0 + x1,
        y0: pos.1 + y0,
        y1: pos.1 + y1,
    })
}

/// A drawing backend that draws with `DB` and notes what it drew for the
/// layout check (only inside [`recorded`]).
pub(crate) struct Recorder<DB>(pub(crate) DB);

impl<DB: DrawingBackend> DrawingBackend for Recorder<DB> {
    type ErrorType = DB::ErrorType;

    fn get_size(&self) -> (u32, u32) {
        self.0.get_size()
    }

    fn ensure_prepared(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.ensure_prepared()
    }

    fn present(&mut self) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.present()
    }

    fn draw_pixel(
        &mut self,
        point: BackendCoord,
        color: BackendColor,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.draw_pixel(point, color)
    }

    fn draw_line<S: BackendStyle>(
        &mut self,
        from: BackendCoord,
        to: BackendCoord,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        note_marks([from, to]);
        self.0.draw_line(from, to, style)
    }

    fn draw_rect<S: BackendStyle>(
        &mut self,
        upper_left: BackendCoord,
        bottom_right: BackendCoord,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        note_marks([upper_left, bottom_right]);
        self.0.draw_rect(upper_left, bottom_right, style, fill)
    }

    fn draw_path<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        path: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let p: Vec<BackendCoord> = path.into_iter().collect();
        if style.stroke_width() > 1 {
            // a wide line is drawn as this polygon (its miter joins can
            // reach far past the path's vertices, e.g. at a 180° turn)
            note_marks(plotters_backend::rasterizer::polygonize(
                &p,
                style.stroke_width(),
            ));
        } else {
            note_marks(p.iter().copied());
        }
        self.0.draw_path(p, style)
    }

    fn draw_circle<S: BackendStyle>(
        &mut self,
        center: BackendCoord,
        radius: u32,
        style: &S,
        fill: bool,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        note_marks([center]);
        self.0.draw_circle(center, radius, style, fill)
    }

    fn fill_polygon<S: BackendStyle, I: IntoIterator<Item = BackendCoord>>(
        &mut self,
        vert: I,
        style: &S,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        let v: Vec<BackendCoord> = vert.into_iter().collect();
        note_marks(v.iter().copied());
        self.0.fill_polygon(v, style)
    }

    fn draw_text<TStyle: BackendTextStyle>(
        &mut self,
        text: &str,
        style: &TStyle,
        pos: BackendCoord,
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        if style.color().alpha > 0.0
            && !text.trim().is_empty()
            && let Some(b) = text_box(text, style, pos)
        {
            note_text(text, b);
        }
        self.0.draw_text(text, style, pos)
    }

    fn estimate_text_size<TStyle: BackendTextStyle>(
        &self,
        text: &str,
        style: &TStyle,
    ) -> Result<(u32, u32), DrawingErrorKind<Self::ErrorType>> {
        self.0.estimate_text_size(text, style)
    }

    fn blit_bitmap(
        &mut self,
        pos: BackendCoord,
        size: (u32, u32),
        src: &[u8],
    ) -> Result<(), DrawingErrorKind<Self::ErrorType>> {
        self.0.blit_bitmap(pos, size, src)
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
mod tests {
    use super::{LayoutIssue, Recorder, annotations, data_in, recorded, text_box};
    use plotters::coord::Shift;
    use plotters::prelude::*;

    /// Draws into an in-memory bitmap through the recorder.
    fn issues_of(
        size: (u32, u32),
        draw: impl FnOnce(&DrawingArea<Recorder<BitMapBackend>, Shift>),
    ) -> Vec<LayoutIssue> {
        super::super::plot::register_font().unwrap();
        let mut buf = vec![0u8; (size.0 * size.1 * 3) as usize];
        recorded(size, || {
            let root = Recorder(BitMapBackend::with_buffer(&mut buf, size)).into_drawing_area();
            draw(&root);
            root.present().unwrap();
        })
        .1
    }

    // the checker sees each kind of fault it is for, and passes a clean chart
    #[test]
    fn finds_text_off_canvas_overlaps_and_data_outside_axes() {
        // a font looked up before the bundled one is registered stays unavailable
        super::super::plot::register_font().unwrap();
        let font = ("sans-serif", 20).into_font();
        let found = issues_of((300, 200), |root| {
            root.fill(&WHITE).unwrap();
            root.draw(&Text::new("inside", (10, 10), font.clone()))
                .unwrap();
            root.draw(&Text::new("clipped on the right", (250, 60), font.clone()))
                .unwrap();
            root.draw(&Text::new("one", (10, 120), font.clone()))
                .unwrap();
            root.draw(&Text::new("two", (20, 125), font.clone()))
                .unwrap();
        });
        assert_eq!(found.len(), 2, "{found:?}");
        assert!(
            matches!(&found[0], LayoutIssue::TextOutsideCanvas { text, .. } if text == "clipped on the right")
        );
        assert!(
            matches!(&found[1], LayoutIssue::TextOverlap { first, second, .. } if first == "one" && second == "two")
        );

        // a point's label drawn as data at x: inside the axes, or running
        // out of them (plotters clamps a series' vertices to its plotting
        // area, so what leaves the axes is what is drawn in pixels from a
        // point: a label, a glyph, a wide stroke's join)
        let chart_with = |x: f64| {
            issues_of((400, 300), |root| {
                root.fill(&WHITE).unwrap();
                let mut c = ChartBuilder::on(root)
                    .margin(10)
                    .x_label_area_size(30)
                    .y_label_area_size(40)
                    .build_cartesian_2d(0.0..1.0, 0.0..1.0)
                    .unwrap();
                c.configure_mesh()
                    .label_style(("sans-serif", 12))
                    .draw()
                    .unwrap();
                data_in(c.plotting_area());
                c.draw_series(LineSeries::new([(0.0, 0.0), (0.5, 0.9), (1.0, 0.2)], BLUE))
                    .unwrap();
                c.draw_series(std::iter::once(Text::new(
                    "a point's label",
                    (x, 0.5),
                    ("sans-serif", 14),
                )))
                .unwrap();
                annotations();
            })
        };
        assert_eq!(chart_with(0.1), vec![]);
        let out = chart_with(0.9);
        assert!(
            out.iter()
                .any(|i| matches!(i, LayoutIssue::DataOutsideAxes { count: 1, .. })),
            "{out:?}"
        );
    }

    // a y-axis title turned by 90° is measured turned: tall and narrow
    #[test]
    fn turned_text_is_measured_turned() {
        super::super::plot::register_font().unwrap();
        let style: TextStyle = ("sans-serif", 20)
            .into_font()
            .transform(FontTransform::Rotate270)
            .into();
        let flat: TextStyle = ("sans-serif", 20).into_font().into();
        let b = text_box("a long axis title", &style, (100, 100)).unwrap();
        let f = text_box("a long axis title", &flat, (100, 100)).unwrap();
        assert_eq!((b.x1 - b.x0, b.y1 - b.y0), (f.y1 - f.y0, f.x1 - f.x0));
        assert!(b.y1 - b.y0 > 3 * (b.x1 - b.x0));
    }
}
