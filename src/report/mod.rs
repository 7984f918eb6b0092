//! `softrod report`: the speed–accuracy (Pareto) chart and the stability map
//! of the estimators, the closed loop's figures and the parallel robot's.
//!
//! - [`pareto`]: backend × element count × marker count against exudyn's
//!   128-element solutions ([`reference`](mod@reference)); error (backbone RMS, load error)
//!   against the median time per warm estimate; the Pareto front marked.
//! - [`auto_point`]: where `"elements": "auto"` lands on the Pareto chart.
//! - [`tracking`]: the closed loop against the simulated plant (tracking
//!   and payload-mass figures, `tracking*.{png,svg,json}`).
//! - [`loop_pareto`], [`loop_failure`]: the closed loop's speed against
//!   accuracy over model size and backend, and where it fails
//!   (`loop_{pareto,failure}.{png,svg,json}`).
//! - [`spatial`]: the soft parallel robot's payload estimation and two
//!   projections of its shape (`spatial.{png,svg,json}`).
//! - [`grasp`]: Table I in simulation and one grasp sequence per strategy
//!   (`grasp.{png,svg,json,md}`).
//! - [`coverage`]: how often the true resultant force lies in the
//!   estimate's reported 95 % region (`coverage.{png,svg,json}`).
//! - [`stability`]: marker noise, load magnitude, marker count, the jump
//!   between successive observations and `α`, per backend: converged or
//!   not, the failure cause ([`sweep::FailureCause`]), iterations, errors;
//!   heat maps and a Markdown table of where each method fails and why.
//!
//! Every case runs under guard ([`sweep::run_guarded`]): a failure, a panic or
//! an overrun is a recorded outcome, never a crash or a hang. Outputs (in the
//! output directory): `pareto.{png,svg,json}`, `stability_<map>.{png,svg}`,
//! `stability.json`, `stability.md`.
//!
//! # Example
//! ```no_run
//! use softrod::report::{run, ReportOptions};
//! let opts = ReportOptions { quick: true, ..ReportOptions::new("target/report") };
//! let summary = run(&opts, &[])?;
//! println!("{} files written", summary.files.len());
//! # Ok::<(), softrod::Error>(())
//! ```

pub mod atomic;
pub mod auto_point;
pub mod coverage;
pub mod grasp;
pub mod layout;
pub mod loop_failure;
pub mod loop_pareto;
pub mod pareto;
pub mod plot;
pub mod reference;
pub mod result_plot;
pub mod spatial;
pub mod stability;
pub mod sweep;
pub mod touch;
pub mod tracking;

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

pub use pareto::{LabelledPoint, ParetoReport};
pub use result_plot::{PlotSummary, plot_result};
pub use stability::StabilityReport;

/// Which part of the report runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Part {
    /// The Pareto chart only.
    Pareto,
    /// The stability map only.
    Stability,
    /// The soft parallel robot only (payload estimation, two projections).
    Spatial,
    /// The closed loop's tracking and mass-estimation figures only.
    Tracking,
    /// Contact localization and avoidance by touch ([`touch`](mod@touch)).
    Touch,
    /// The closed loop's speed against accuracy and its failure map only.
    Loop,
    /// The grasp's success table and sequences only.
    Grasp,
    /// The coverage of the reported uncertainty only.
    Coverage,
}

/// Options of a report run.
#[derive(Debug, Clone, PartialEq)]
pub struct ReportOptions {
    /// Output directory (created if absent).
    pub out_dir: PathBuf,
    /// A tiny sweep (seconds; what the tests run) instead of the full one.
    pub quick: bool,
    /// One part only (default: both).
    pub only: Option<Part>,
    /// No progress bar (it is also hidden when standard error is not a terminal).
    pub quiet: bool,
    /// Wall-clock cap of one case (a case over it is recorded as a timeout).
    pub case_cap: Duration,
}

impl ReportOptions {
    /// Both parts, the full sweep, a progress bar, a 60 s cap per case.
    pub fn new(out_dir: impl Into<PathBuf>) -> Self {
        ReportOptions {
            out_dir: out_dir.into(),
            quick: false,
            only: None,
            quiet: false,
            case_cap: Duration::from_secs(60),
        }
    }
}

/// What a report run produced.
#[derive(Debug, Clone)]
pub struct ReportSummary {
    /// The Pareto sweep, if it ran.
    pub pareto: Option<ParetoReport>,
    /// The stability sweep, if it ran.
    pub stability: Option<StabilityReport>,
    /// The closed loop's figures, if they ran.
    pub tracking: Option<tracking::TrackingReport>,
    /// The files written.
    pub files: Vec<PathBuf>,
    /// What the layout check ([`layout`](mod@layout)) found in the charts
    /// written: empty when no text leaves its canvas or covers another and
    /// no data mark leaves its axes.
    pub layout: Vec<layout::ChartIssue>,
    /// Wall time of the whole run (s).
    pub wall_time_s: f64,
}

/// The machine a report ran on (timings are only comparable within one run).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Machine {
    /// CPU model (from `/proc/cpuinfo`, if readable).
    pub cpu: String,
    /// Logical CPUs available to the process.
    pub cpus: usize,
    /// 1-minute load average at the start and the end of the sweep (Linux).
    pub load_average: Vec<f64>,
    /// `softrod` version.
    pub softrod_version: String,
    /// Build profile ("release" or "debug").
    pub profile: String,
}

impl Machine {
    /// Reads what it can about this machine.
    pub(crate) fn detect() -> Machine {
        let cpu = std::fs::read_to_string("/proc/cpuinfo")
            .ok()
            .and_then(|t| {
                t.lines()
                    .find(|l| l.starts_with("model name"))
                    .and_then(|l| l.split(':').nth(1))
                    .map(|s| s.trim().to_string())
            })
            .unwrap_or_else(|| "unknown".to_string());
        Machine {
            cpu,
            cpus: std::thread::available_parallelism()
                .map(|n| n.get())
                .unwrap_or(1),
            load_average: load_average().into_iter().collect(),
            softrod_version: env!("CARGO_PKG_VERSION").to_string(),
            profile: if cfg!(debug_assertions) {
                "debug"
            } else {
                "release"
            }
            .to_string(),
        }
    }

    /// Appends the current load average (call at the end of a sweep).
    pub fn sample_load(&mut self) {
        self.load_average.extend(load_average());
    }
}

fn load_average() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|t| t.split_whitespace().next().and_then(|v| v.parse().ok()))
}

/// The progress bar of every run longer than a few seconds (the report's
/// parts, `softrod track` on a parallel robot): on standard error, `what`
/// before it, `len` steps (`set_length` when it is known later); hidden
/// when `quiet` or when standard error is not a terminal (a log file, a
/// pipe, a test).
///
/// # Example
/// ```
/// let bar = softrod::report::progress(10, false, "sweep");
/// for _ in 0..10 {
///     bar.inc(1);
/// }
/// bar.finish_and_clear();
/// ```
pub fn progress(len: usize, quiet: bool, what: &str) -> indicatif::ProgressBar {
    if quiet || !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let pb = indicatif::ProgressBar::new(len as u64);
    let style = indicatif::ProgressStyle::with_template(
        "{prefix:>10} [{bar:40}] {pos}/{len}, {elapsed} elapsed, ~{eta} left {msg}",
    )
    .map(|s| s.progress_chars("=> "))
    .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar());
    pb.set_style(style);
    pb.set_prefix(what.to_string());
    pb
}

/// Writes `value` as pretty JSON to `path` (atomically).
pub(crate) fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value).map_err(|e| io_error(path, e))?;
    atomic::write_atomic(path, (text + "\n").as_bytes())
}

/// [`Error::Io`] for `path`.
pub(crate) fn io_error(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Io {
        path: path.display().to_string(),
        message: e.to_string(),
    }
}

/// Runs the report: the sweeps, the charts, the JSON and Markdown files.
/// `extra` are additional labelled points for the Pareto chart (e.g. where
/// `elements: "auto"` lands).
///
/// # Errors
/// [`Error::Io`] when the output directory or a file cannot be written.
/// A failing case is not an error: it is an outcome in the report.
pub fn run(opts: &ReportOptions, extra: &[LabelledPoint]) -> Result<ReportSummary> {
    let start = Instant::now();
    let _ = layout::take_chart_issues();
    std::fs::create_dir_all(&opts.out_dir).map_err(|e| io_error(&opts.out_dir, e))?;
    let mut files = Vec::new();
    let pareto = if matches!(opts.only, None | Some(Part::Pareto)) {
        let mut r = pareto::run(opts)?;
        let pb = progress(1, opts.quiet, "auto");
        pb.set_message("elements: \"auto\" on the Pareto references");
        let (auto, notes) = auto_point::auto_points(opts, &r.grid)?;
        pb.finish_and_clear();
        r.auto_points = auto;
        r.auto_notes = notes;
        let marked: Vec<LabelledPoint> = extra.iter().chain(&r.auto_points).cloned().collect();
        files.extend(r.write(&opts.out_dir, &marked)?);
        Some(r)
    } else {
        None
    };
    if matches!(opts.only, None | Some(Part::Spatial)) {
        files.extend(spatial::run(opts)?.1);
    }
    let stability = if matches!(opts.only, None | Some(Part::Stability)) {
        let r = stability::run(opts)?;
        files.extend(r.write(&opts.out_dir)?);
        Some(r)
    } else {
        None
    };
    if matches!(opts.only, None | Some(Part::Touch)) {
        files.extend(touch::run(opts)?.1);
    }
    if matches!(opts.only, None | Some(Part::Coverage)) {
        files.extend(coverage::run(opts)?.1);
    }
    let tracking = if matches!(opts.only, None | Some(Part::Tracking)) {
        let r = tracking::run(opts)?;
        files.extend(r.write(&opts.out_dir)?);
        Some(r)
    } else {
        None
    };
    if matches!(opts.only, None | Some(Part::Loop)) {
        files.extend(loop_pareto::run(opts)?.write(&opts.out_dir)?);
        files.extend(loop_failure::run(opts)?.write(&opts.out_dir)?);
    }
    if matches!(opts.only, None | Some(Part::Grasp)) {
        files.extend(grasp::run(opts)?.1);
    }
    Ok(ReportSummary {
        pareto,
        stability,
        tracking,
        files,
        layout: layout::take_chart_issues(),
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}
