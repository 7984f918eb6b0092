// The command line (the binary's `softrod_cli` module; subcommands of wave 2 live in their own files here).

/// `println!` that ends the program quietly (exit 0) when standard output
/// is closed, e.g. `softrod | head`, like a Unix tool on SIGPIPE.
macro_rules! outln {
    ($($t:tt)*) => {{
        use std::io::Write as _;
        if writeln!(std::io::stdout(), $($t)*).is_err() {
            std::process::exit(0);
        }
    }};
}

mod atomic;
mod avoid;
mod demo;
pub mod output;
mod replay;
mod track;

use std::path::PathBuf;

mod parallel;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use serde::Serialize;

use output::{
    CommandName, EstimateBody, EstimateRecord, GoalNotMet, Header, LoadSample, MarkerFitRecord,
    NodeRecord, Outcome, PointForceRecord, ResultantRecord, SceneKind, SolveRecord,
};
use softrod::assembly::{Robot, ValidityWarning};
use softrod::element::{Element, PlanarCable};
use softrod::estimate::{Backend, Estimate, MarkerObservation, Observation};
use softrod::refine::{Quantity, Refinement};
use softrod::scene::markers::MarkersFile;
use softrod::scene::{Scene, SceneRobot};
use softrod::statics::{StaticReport, StaticSolver};

/// Shape and force estimation for slender soft robots (ANCF cable model).
///
/// Without a subcommand, runs the built-in two-section robot and prints a summary.
#[derive(Parser, Debug)]
#[command(name = "softrod", version, about, after_help = EXIT_CODES)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

/// The exit codes (also in the README).
const EXIT_CODES: &str = "\
Output: every subcommand's JSON record carries \"format_version\" (now \"1\"), \"command\", \"scene\", \"scene_kind\", \"outcome\" and a typed \"status\"; its JSON Schema is written by `softrod schema --out DIR` (committed under schema/).

Exit codes:
  0  success (\"outcome\": \"success\")
  1  error: bad input, or no answer found (nothing written; the message names the field or the failed solve)
  2  goal not met: the run finished and wrote its record (\"outcome\": \"goal_not_met\") but an estimate did not converge, a goal was missed, a grasp did not hold or a tracking run stopped early";

#[derive(Subcommand, Debug)]
enum Command {
    /// Obstacle avoidance by touch (Fig. 9): the five-section robot moves to
    /// the scene's goal among obstacles it is not told about, localizes each
    /// contact from its markers and steers around it. Writes the run as
    /// JSON; fails if the goal is not reached or is outside the workspace.
    Avoid {
        /// Avoidance scene (JSON: obstacles, goal_m, optional plant/avoid settings).
        scene: PathBuf,
        /// Output file (default: standard output).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Run the baseline: the same controller without touch feedback.
        #[arg(long)]
        baseline: bool,
    },
    /// Solve the static equilibrium of a scene and write the result as JSON.
    Solve {
        /// Scene file (JSON).
        scene: PathBuf,
        /// Chamber pressures in Pa, separated by commas and/or spaces, e.g.
        /// `--pressures 20e3,-5e3` or `--pressures "20e3, -5e3"` (overrides the scene's).
        #[arg(long, value_parser = parse_pressures, allow_hyphen_values = true)]
        pressures: Option<PressuresArg>,
        /// Output file (default: standard output).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Estimate shape and distributed load from marker positions (Sec. III)
    /// and write the result as JSON.
    ///
    /// The markers file is JSON: {"markers": [{"node": 4, "position_m": [x, y]},
    /// {"s_m": 0.24, "position_m": [x, y], "tangent": [tx, ty]}, ...]} (positions in m,
    /// world axes; [x, y, z] and [tx, ty, tz] in a "spatial_cable" or "ancf3d" scene; optional
    /// "position_weight"/"tangent_weight" per component), or a recorded stream
    /// {"frames": [{"t_s": 0.0, "markers": [...]}, ...]}: one estimate per frame,
    /// the estimator kept warm, written as {"frames": [{"t_s", "status", "estimate"}, ...]};
    /// either may hold a "description" (free text, not read).
    /// Without it, the observation is synthesized: the scene is solved forward
    /// with its own loads and seeded 0.01 mm noise is added at the scene's markers.
    Estimate {
        /// Scene file (JSON); its loads and pressures are the known loads.
        scene: PathBuf,
        /// Backend (default: the scene's `solver.estimator.backend`).
        #[arg(long, value_enum)]
        backend: Option<BackendArg>,
        /// Markers file (JSON, see above).
        #[arg(long)]
        markers: Option<PathBuf>,
        /// Chamber pressures in Pa of the known actuation, separated by commas
        /// and/or spaces (overrides the scene's; as in `solve`).
        #[arg(long, value_parser = parse_pressures, allow_hyphen_values = true)]
        pressures: Option<PressuresArg>,
        /// Output file (default: standard output).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Track a trajectory in closed loop against a simulated plant that is
    /// not the scene's model (finer mesh, parameter errors, noise, lag,
    /// payloads the controller is not told about) and write the time series
    /// and a summary as JSON. The trajectory file (JSON) gives the path
    /// (circle, figure_eight, line, samples, pressures), the loop's and the
    /// plant's settings; the payload file a schedule {"payloads": [...]}.
    /// Without a trajectory file: a 5 mm circle about the end effector at
    /// the scene's pressures. A parallel-robot scene tracks a horizontal
    /// platform circle instead; its trajectory file holds the run's
    /// settings (softrod::control::parallel::TrackSettings).
    Track {
        /// Scene file (JSON): the controller's model and the markers.
        scene: PathBuf,
        /// Trajectory file (JSON).
        #[arg(long)]
        trajectory: Option<PathBuf>,
        /// Payload schedule (JSON), replacing the trajectory file's plant payloads.
        #[arg(long)]
        payload: Option<PathBuf>,
        /// Controller (default: the trajectory file's, else ff+updater).
        #[arg(long, value_enum)]
        controller: Option<track::ControllerArg>,
        /// Output file (default: standard output).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Speed against accuracy (Pareto chart) and the stability map of the
    /// estimators, against exudyn references: writes pareto.{png,svg,json},
    /// stability_*.{png,svg}, stability.json and stability.md.
    Report {
        /// Output directory (the committed figures of the README were made
        /// with `--out validation/figures`).
        #[arg(long, default_value = "target/report")]
        out: PathBuf,
        /// A tiny sweep (seconds) instead of the full one (minutes).
        #[arg(long)]
        quick: bool,
        /// One part only.
        #[arg(long, value_enum)]
        only: Option<PartArg>,
        /// No progress bar.
        #[arg(long)]
        quiet: bool,
    },
    /// Draw a result: the record written by `solve` or `estimate` (a robot
    /// scene: the backbone, the markers measured and fitted, the estimated
    /// load along the backbone with its ±1σ band, the marker residuals),
    /// by `solve` on a parallel robot (legs and platform) or by `avoid`
    /// (the shapes, the goal, the obstacle points learnt by touch and the
    /// contact forces). One x–y view for a planar robot, three orthogonal
    /// views (x–y, x–z, y–z) in 3-D. A record of another kind is refused
    /// (exit code 1) with what was read.
    Plot {
        /// The result record (JSON, format_version "1").
        record: PathBuf,
        /// The picture: a .png or .svg file (default: the record's path
        /// with the extension .png).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Write the JSON Schema of every output record (the files committed
    /// under schema/): `solve`, `solve_parallel`, `estimate`,
    /// `estimate_stream`, `estimate_parallel`, `track`, `avoid`, `grasp`.
    Schema {
        /// Directory to write `<name>.schema.json` into (default: print
        /// them all as one JSON object to standard output).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// One simulated grasp (two-finger gripper, an object on a table) and
    /// its outcome as JSON. The scene file is JSON: {"object": {"name": ...,
    /// "shape": {"shape": "circle", "radius_m": 0.03}, "mass_kg": 0.1, "mu": 0.5},
    /// "placement": {"offset_m": 0.0, "angle_rad": 0.0}} (optional: "gripper",
    /// "settings", "seed", "strategy").
    Grasp {
        /// Grasp scene file (JSON, see above).
        scene: PathBuf,
        /// Strategy (default: the scene's, else adaptive).
        #[arg(long, value_enum)]
        strategy: Option<grasp::StrategyArg>,
        /// Output file (default: standard output).
        #[arg(long)]
        out: Option<PathBuf>,
    },
}

mod grasp;

/// Chamber pressures from the command line, in Pa.
#[derive(Clone, Debug)]
struct PressuresArg(Vec<f64>);

/// `--pressures`: numbers separated by commas and/or whitespace; negatives
/// allowed (a chamber under vacuum).
fn parse_pressures(text: &str) -> std::result::Result<PressuresArg, String> {
    let mut out = Vec::new();
    for (i, item) in text
        .split(|c: char| c == ',' || c.is_whitespace())
        .filter(|t| !t.is_empty())
        .enumerate()
    {
        // non-finite values parse and are refused by the scene's own check,
        // which names `pressures_pa[i]`
        let p: f64 = item
            .parse()
            .map_err(|_| format!("pressure {i} (`{item}`) is not a number in Pa"))?;
        out.push(p);
    }
    if out.is_empty() {
        return Err("no pressures given".into());
    }
    Ok(PressuresArg(out))
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum PartArg {
    Pareto,
    Stability,
    Spatial,
    Tracking,
    Touch,
    Loop,
    Grasp,
    Coverage,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum BackendArg {
    Newton,
    Sqp,
}

impl From<BackendArg> for Backend {
    fn from(b: BackendArg) -> Self {
        match b {
            BackendArg::Newton => Backend::Newton,
            BackendArg::Sqp => Backend::Sqp,
        }
    }
}

/// Fills in the planar robot's unwrapped node angles; returns the tip's.
fn fill_angles(
    robot: &Robot<PlanarCable>,
    q: &[f64],
    nodes: &mut [NodeRecord],
) -> Result<Option<f64>> {
    let angles = robot.node_angles(q)?;
    for (n, a) in nodes.iter_mut().zip(&angles) {
        n.angle_rad = Some(*a);
    }
    Ok(angles.as_slice().last().copied())
}

/// The nodes of configuration `q`: arc coordinate, position and slope.
fn node_outs<E: Element>(robot: &Robot<E>, q: &[f64]) -> Vec<NodeRecord> {
    let (d, nd) = (E::DIM, E::NODE_DOFS);
    robot
        .node_arc()
        .iter()
        .enumerate()
        .map(|(i, &s)| NodeRecord {
            s_m: s,
            position_m: q[i * nd..i * nd + d].to_vec(),
            slope: q[i * nd + d..i * nd + 2 * d].to_vec(),
            angle_rad: None,
        })
        .collect()
}

fn solve_out<E: Element>(
    scene: &Scene,
    robot: &Robot<E>,
    pressures: Vec<f64>,
    q: &[f64],
    report: StaticReport,
) -> SolveRecord {
    let tip = &q[q.len() - E::NODE_DOFS..];
    SolveRecord {
        header: Header::new(
            CommandName::Solve,
            &scene.name,
            SceneKind::of(scene),
            Outcome::from_ok(report.status.is_converged()),
        ),
        status: report.status,
        pressures_pa: pressures,
        tip_position_m: tip[..E::DIM].to_vec(),
        tip_angle_rad: None,
        tip_direction: None,
        tip_angle_from_base_rad: None,
        nodes: node_outs(robot, q),
        report,
        q: q.to_vec(),
        warnings: robot.validity(q).unwrap_or_default(),
        refinement: None,
    }
}

/// The static equilibrium of the scene's robot under its loads.
fn solve_with<E: Element>(
    scene: &Scene,
    robot: &Robot<E>,
    pressures: Option<Vec<f64>>,
) -> Result<SolveRecord> {
    let mut loads = scene.loads()?;
    if let Some(p) = pressures {
        loads.pressures_pa = p;
    }
    let solver = StaticSolver::new(scene.solver.statics.clone())?;
    let eq = solver.solve(robot, &loads, None)?;
    Ok(solve_out(
        scene,
        robot,
        loads.pressures_pa.clone(),
        eq.q.as_slice(),
        eq.report,
    ))
}

fn solve(scene: &Scene, pressures: Option<Vec<f64>>) -> Result<SolveRecord> {
    match scene.build()? {
        SceneRobot::Planar(robot) => {
            let mut out = solve_with(scene, &robot, pressures)?;
            out.tip_angle_rad = fill_angles(&robot, &out.q, &mut out.nodes)?;
            Ok(out)
        }
        SceneRobot::Full(robot) => {
            let mut out = solve_with(scene, &robot, pressures)?;
            out.tip_direction = out.nodes.last().map(|n| {
                let l = n.slope.iter().map(|x| x * x).sum::<f64>().sqrt();
                n.slope.iter().map(|x| x / l).collect()
            });
            Ok(out)
        }
        SceneRobot::Spatial(robot) => {
            let mut out = solve_with(scene, &robot, pressures)?;
            let unit = |v: &[f64]| {
                let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
                v.iter().map(|x| x / n).collect::<Vec<f64>>()
            };
            let base = unit(&robot.base_node()[3..6]);
            if let Some(tip) = out.nodes.last().map(|n| unit(&n.slope)) {
                let cos = base.iter().zip(&tip).map(|(a, b)| a * b).sum::<f64>();
                out.tip_angle_from_base_rad = Some(cos.clamp(-1.0, 1.0).acos());
                out.tip_direction = Some(tip);
            }
            Ok(out)
        }
    }
}

fn write_json<T: Serialize>(value: &T, out: Option<&PathBuf>) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    match out {
        Some(path) => atomic::write_atomic(path, (text + "\n").as_bytes()),
        None => {
            use std::io::Write;
            let mut stdout = std::io::stdout().lock();
            writeln!(stdout, "{text}")
                .and_then(|()| stdout.flush())
                .context("cannot write to standard output")
        }
    }
}

const LOAD_GRID: usize = 49;

/// Each marker of `obs`: where it was measured and where the estimated
/// shape `q` puts it (a marker on a body, or one that cannot be placed, is
/// left out: the residuals keep it).
fn marker_fits<E: Element>(robot: &Robot<E>, q: &[f64], obs: &Observation) -> Vec<MarkerFitRecord> {
    obs.markers
        .iter()
        .filter_map(|m| {
            let s = match (m.node, m.s_m) {
                (Some(n), _) => *robot.node_arc().get(n)?,
                (None, Some(s)) => s,
                _ => return None,
            };
            let fitted = robot.position_at(q, s).ok()?;
            Some(MarkerFitRecord {
                s_m: s,
                node: m.node,
                measured_position_m: m.position_m.clone(),
                fitted_position_m: fitted.as_slice().to_vec(),
            })
        })
        .collect()
}

/// The 1σ of `w(s)` per component from the noise covariance factor `L` of
/// the load parameters, `sqrt(diag(S L Lᵀ Sᵀ))` (`w = S(s) F`, (8)): `S`
/// applied to each column of `L`. `None` for a concentrated load.
fn load_std<E: Element>(e: &Estimate, s: f64) -> Option<Vec<f64>> {
    if e.load_model != softrod::estimate::LoadModel::Distributed {
        return None;
    }
    let l = e.cov_factor();
    let p = softrod::element::ArcPoint::locate(e.node_arc(), s)?;
    let mut var = vec![0.0; E::DIM];
    let mut col = vec![0.0; E::DIM];
    let n = l.nrows();
    for j in 0..l.ncols() {
        // DMatrix storage is column-major: column j is one slice
        p.node_value_into(&l.as_slice()[j * n..(j + 1) * n], E::NODE_DOFS, &mut col)
            .ok()?;
        var.iter_mut().zip(&col).for_each(|(v, c)| *v += c * c);
    }
    Some(var.into_iter().map(f64::sqrt).collect())
}

fn estimate_out<E: Element>(
    robot: &Robot<E>,
    pressures_pa: Vec<f64>,
    e: &Estimate,
    obs: &Observation,
    observation: String,
) -> EstimateBody {
    let nodes = node_outs(robot, e.q.as_slice());
    let d = e.resultant_force_n.len();
    let cov = e.resultant_force_cov();
    EstimateBody {
        status: e.report.status,
        backend: e.report.backend.into(),
        observation,
        pressures_pa,
        nodes,
        load: e
            .sample_load(LOAD_GRID)
            .into_iter()
            .map(|(s, w)| LoadSample {
                s,
                w: w.as_slice().to_vec(),
                w_std: load_std::<E>(e, s),
            })
            .collect(),
        load_grid_points: LOAD_GRID,
        load_parameters: e.f.as_slice().to_vec(),
        point_force: match e.load_model {
            softrod::estimate::LoadModel::Concentrated { node } => {
                robot.node_arc().get(node).map(|&s| PointForceRecord {
                    node,
                    s_m: s,
                    position_m: e.q.as_slice()[node * E::NODE_DOFS..node * E::NODE_DOFS + E::DIM]
                        .to_vec(),
                })
            }
            _ => None,
        },
        resultant: ResultantRecord {
            force_n: e.resultant_force_n.as_slice().to_vec(),
            force_std_n: (0..d).map(|a| cov[(a, a)].max(0.0).sqrt()).collect(),
            force_cov_n2: (0..d)
                .map(|a| (0..d).map(|b| cov[(a, b)]).collect())
                .collect(),
            moment_nm: e.resultant_moment_nm.as_slice().to_vec(),
        },
        marker_residuals_m: e.marker_residuals.as_slice().to_vec(),
        markers: marker_fits(robot, e.q.as_slice(), obs),
        marker_std_m: e.marker_std().as_slice().to_vec(),
        max_load_parameter_std: e.std_f().iter().copied().fold(0.0, f64::max),
        noise_sigma_m: e.noise_sigma_m,
        determined_directions: e.determined_directions(),
        resultant_prior_fraction: e.resultant_prior_fraction(),
        weakly_informed: e.weakly_informed(),
        weakly_informed_reason: e.weak_information(),
        report: (&e.report).into(),
        q: e.q.as_slice().to_vec(),
        warnings: robot.validity(e.q.as_slice()).unwrap_or_default(),
        refinement: None,
    }
}

/// The scene's markers read off the configuration `q` (exact).
fn observe<E: Element>(scene: &Scene, robot: &Robot<E>, q: &[f64]) -> Result<Observation> {
    let mut markers = Vec::new();
    for m in &scene.markers {
        let s = match (m.node, m.s_m) {
            (Some(n), _) => robot.node_arc()[n],
            (None, Some(s)) => s,
            _ => anyhow::bail!("a marker needs `node` or `s_m`"),
        };
        let point = robot.arc_point("marker", s)?;
        let p = robot.position_at(q, s)?;
        let mut mo = match m.node {
            Some(n) => MarkerObservation::at_node(n, p),
            None => MarkerObservation::at_arc(s, p),
        };
        if m.tangent {
            let mut t = vec![0.0; E::DIM];
            point.node_slope_into(q, E::NODE_DOFS, &mut t)?;
            mo.tangent = Some(t);
        }
        markers.push(mo);
    }
    Ok(Observation { markers })
}

/// The estimates of `softrod estimate`: one per observation of the markers
/// file (one, or every frame of a recorded stream, the estimator kept
/// warm), or of the synthesized observation without one; each with the
/// frame's time (`None` for a single observation).
fn estimate(
    scene: &Scene,
    backend: Option<Backend>,
    markers: Option<(&PathBuf, MarkersFile)>,
) -> Result<Vec<(Option<f64>, EstimateBody)>> {
    match scene.build()? {
        SceneRobot::Planar(robot) => {
            let mut outs = estimate_with(scene, robot.clone(), backend, markers)?;
            for (_, out) in &mut outs {
                fill_angles(&robot, &out.q, &mut out.nodes)?;
            }
            Ok(outs)
        }
        SceneRobot::Spatial(robot) => estimate_with(scene, robot, backend, markers),
        SceneRobot::Full(robot) => estimate_with(scene, robot, backend, markers),
    }
}

/// [`estimate`] on the scene's robot of element `E`.
fn estimate_with<E: Element + 'static>(
    scene: &Scene,
    robot: Robot<E>,
    backend: Option<Backend>,
    markers: Option<(&PathBuf, MarkersFile)>,
) -> Result<Vec<(Option<f64>, EstimateBody)>> {
    let known = scene.loads()?;
    let mut settings = scene.estimator_settings()?;
    if let Some(b) = backend {
        settings.backend = b;
    }
    let (observations, source) = match markers {
        Some((path, m)) => {
            m.check_work(robot.n_elements())
                .with_context(|| path.display().to_string())?;
            (m.observations(), format!("markers file {}", path.display()))
        }
        None => {
            let solver = StaticSolver::new(scene.solver.statics.clone())?;
            let eq = solver.solve(&robot, &known, None)?;
            let obs = observe(scene, &robot, eq.q.as_slice())?.with_noise(1e-5, 1);
            (vec![(None, obs)], "synthesized: the scene solved forward with its own loads, seeded 0.01 mm noise added to the marker positions (seed 1); the estimated load should be near zero".to_string())
        }
    };
    let pressures = known.pressures_pa.clone();
    let mut est = settings.build_for(&robot, &known)?;
    let mut outs = Vec::with_capacity(observations.len());
    for (i, (t_s, obs)) in observations.into_iter().enumerate() {
        let e = est.step(&obs).with_context(|| match t_s {
            Some(t) => format!("frames[{i}] (t_s = {t})"),
            None => "the markers".to_string(),
        })?;
        outs.push((
            t_s,
            estimate_out(&robot, pressures.clone(), &e, &obs, source.clone()),
        ));
    }
    Ok(outs)
}

/// Writes the record of one estimate (its warnings on standard error); a
/// record whose estimate did not converge is written and then reported as
/// [`GoalNotMet`].
fn write_estimate(
    scene: &Scene,
    body: EstimateBody,
    synthesized: bool,
    out: Option<&PathBuf>,
) -> Result<()> {
    if synthesized {
        eprintln!("softrod: no markers file: {}", body.observation);
    }
    warn_all(&body.warnings);
    let status = body.status;
    if let Some(why) = &body.weakly_informed_reason
        && status.is_converged()
    {
        eprintln!("softrod: warning: {why}");
    }
    let record = EstimateRecord {
        header: Header::new(
            CommandName::Estimate,
            &scene.name,
            SceneKind::of(scene),
            Outcome::from_ok(status.is_converged()),
        ),
        body,
    };
    write_json(&record, out)?;
    // the last iterate is written (its status says how it ended); the exit
    // code says that it is not an estimate
    if status == softrod::outcome::EstimateStatus::NoInformation {
        return Err(GoalNotMet(format!(
            "{status}; the result written is the prior (zero load, the prior's standard deviations), not an estimate"
        ))
        .into());
    }
    if !status.is_converged() {
        return Err(GoalNotMet(format!(
            "estimation did not converge: {status}; the result written is the last iterate"
        ))
        .into());
    }
    Ok(())
}

/// Resolves "elements": "auto" sections by refinement (the observation for a
/// `load_resultant` target) and says on stderr what was chosen.
fn refine(scene: Scene, observation: Option<&Observation>) -> Result<(Scene, Option<Refinement>)> {
    if !scene.has_auto_elements() {
        return Ok((scene, None));
    }
    let quantity = scene.refinement.as_ref().map(Quantity::of);
    let observation = match quantity {
        Some(Quantity::LoadResultant) => Some(observation.context("a load_resultant refinement fits the estimator to marker positions: give `softrod estimate SCENE --markers FILE`")?),
        _ => None,
    };
    let r = softrod::refine::auto_elements(&scene, observation)?;
    eprintln!(
        "softrod: elements \"auto\": chose {:?} elements per section ({} in all) for {} within {:e} {}: estimated error {:.2e} ± {:.1e} {} (observed order {:.2}, {} meshes tried)",
        r.elements,
        r.total_elements,
        r.quantity.name(),
        r.tolerance,
        r.quantity.unit(),
        r.estimated_error,
        r.error_margin,
        r.quantity.unit(),
        r.observed_order,
        r.history.len()
    );
    Ok((r.scene.clone(), Some(r)))
}

/// Each warning as one line on standard error.
fn warn_all(warnings: &[ValidityWarning]) {
    for w in warnings {
        eprintln!("softrod: warning: {w}");
    }
}

/// Runs the command line.
pub fn run() -> Result<()> {
    let cli = parse_args()?;
    match cli.command {
        None => demo::default_run(),
        Some(Command::Avoid {
            scene,
            out,
            baseline,
        }) => avoid::avoid(scene, out, baseline),
        Some(Command::Solve {
            scene,
            pressures,
            out,
        }) => {
            let pressures = pressures.map(|p| p.0);
            if let Some(ps) = parallel::read(&scene)? {
                return parallel::solve(ps, pressures, out.as_ref());
            }
            let mut scene = Scene::from_file(&scene)?;
            if let Some(p) = &pressures {
                // the pressures the result is for (and the refinement
                // solves with), checked like the scene's own: the same
                // message as `estimate`'s
                scene.pressures_pa = p.clone();
                scene.validate()?;
            }
            let (scene, refinement) = refine(scene, None)?;
            let mut result = solve(&scene, pressures)?;
            result.refinement = refinement;
            warn_all(&result.warnings);
            result
                .report
                .warnings
                .iter()
                .for_each(|w| eprintln!("softrod: warning: {w}"));
            write_json(&result, out.as_ref())
        }
        Some(Command::Estimate {
            scene,
            backend,
            markers,
            pressures,
            out,
        }) => {
            if let Some(ps) = parallel::read(&scene)? {
                return parallel::estimate(
                    ps,
                    markers.as_ref(),
                    pressures.map(|p| p.0),
                    backend.map(Backend::from),
                    out.as_ref(),
                );
            }
            let mut scene = Scene::from_file(&scene)?;
            if let Some(p) = pressures {
                // the known actuation the estimate is for; checked like the scene's own
                scene.pressures_pa = p.0;
                scene.validate()?;
            }
            if let Some(b) = backend {
                // the refinement estimates with the backend the result is for
                scene.solver.estimator.backend = b.into();
            }
            let file = markers.as_ref().map(|p| replay::read(p)).transpose()?;
            let observation = match (&file, scene.has_auto_elements()) {
                (Some(m), true) => m.first(),
                _ => None,
            };
            let (scene, refinement) = refine(scene, observation.as_ref())?;
            let stream = file.as_ref().is_some_and(MarkersFile::is_stream);
            let mut outs = estimate(
                &scene,
                backend.map(Backend::from),
                markers.as_ref().zip(file),
            )?;
            if stream {
                let frames = outs
                    .into_iter()
                    .map(|(t, mut o)| {
                        o.refinement.clone_from(&refinement);
                        (t.unwrap_or(0.0), o)
                    })
                    .collect();
                let result = replay::stream_record(&scene, frames);
                replay::summarize(&result);
                write_json(&result, out.as_ref())?;
                if let Some(&i) = result.not_converged.first() {
                    return Err(GoalNotMet(format!(
                        "{} of {} frames did not converge (the first: frames[{i}], {}); every frame's record is written with its status",
                        result.not_converged.len(),
                        result.n_frames,
                        result.frames[i].status
                    ))
                    .into());
                }
                return Ok(());
            }
            let Some((_, mut body)) = outs.pop() else {
                anyhow::bail!("no observation to estimate from");
            };
            body.refinement = refinement;
            write_estimate(&scene, body, markers.is_none(), out.as_ref())
        }
        Some(Command::Track {
            scene,
            trajectory,
            payload,
            controller,
            out,
        }) => track::run(scene, trajectory, payload, controller, out),
        Some(Command::Report {
            out,
            quick,
            only,
            quiet,
        }) => report(out, quick, only, quiet),
        Some(Command::Grasp {
            scene,
            strategy,
            out,
        }) => grasp::run(scene, strategy, out),
        Some(Command::Schema { out }) => schema(out),
        Some(Command::Plot { record, out }) => {
            let summary = softrod::report::plot_result(&record, out.as_deref())?;
            outln!(
                "wrote {} ({}: {})",
                summary.path.display(),
                summary.record,
                summary.panels.join(", ")
            );
            Ok(())
        }
    }
}

/// `softrod schema`: the output records' schemas, into `out` (one file
/// each, written atomically) or to standard output.
fn schema(out: Option<PathBuf>) -> Result<()> {
    let schemas = output::schemas();
    match out {
        Some(dir) => {
            std::fs::create_dir_all(&dir)
                .with_context(|| format!("cannot create {}", dir.display()))?;
            for (name, s) in &schemas {
                let path = dir.join(format!("{name}.schema.json"));
                let text = serde_json::to_string_pretty(s)? + "\n";
                atomic::write_atomic(&path, text.as_bytes())?;
                eprintln!("softrod: wrote {}", path.display());
            }
            Ok(())
        }
        None => {
            let all: serde_json::Map<String, serde_json::Value> = schemas
                .into_iter()
                .map(|(n, s)| (n.to_string(), s.to_value()))
                .collect();
            write_json(&all, None)
        }
    }
}

fn report(out: PathBuf, quick: bool, only: Option<PartArg>, quiet: bool) -> Result<()> {
    use softrod::report::{self, Part, ReportOptions};
    let only = only.map(|p| match p {
        PartArg::Pareto => Part::Pareto,
        PartArg::Stability => Part::Stability,
        PartArg::Spatial => Part::Spatial,
        PartArg::Tracking => Part::Tracking,
        PartArg::Touch => Part::Touch,
        PartArg::Loop => Part::Loop,
        PartArg::Grasp => Part::Grasp,
        PartArg::Coverage => Part::Coverage,
    });
    let opts = ReportOptions {
        quick,
        only,
        quiet,
        ..ReportOptions::new(out)
    };
    let summary = report::run(&opts, &[])?;
    if let Some(p) = &summary.pareto {
        outln!(
            "Pareto: {} configurations ({} cases) in {:.1} s; backbone-RMS front (fastest first):",
            p.points.len(),
            p.cases.len(),
            p.wall_time_s
        );
        for q in p.front_backbone() {
            outln!(
                "  {:<6} {:3} elements {:2} markers: {:8.3} ms, backbone {:.4} mm, load {:.1} %, force {:.1} %",
                q.backend.name(),
                q.elements,
                q.markers,
                q.median_step_s * 1e3,
                q.backbone_rms_m * 1e3,
                q.load_rel_l2 * 100.0,
                q.force_rel * 100.0
            );
        }
    }
    if let Some(s) = &summary.stability {
        let failed = s.cells.iter().filter(|c| !c.outcome.is_converged()).count();
        outln!(
            "Stability: {} cases in {:.1} s, {} failed, {} panics",
            s.cells.len(),
            s.wall_time_s,
            failed,
            s.panics
        );
    }
    if let Some(t) = &summary.tracking {
        let failed = t.rows.iter().filter(|r| r.failure.is_some()).count();
        outln!(
            "Tracking: {} runs in {:.1} s, {} failed",
            t.rows.len(),
            t.wall_time_s,
            failed
        );
    }
    outln!(
        "wrote {} files in {:.1} s:",
        summary.files.len(),
        summary.wall_time_s
    );
    for f in &summary.files {
        outln!("  {}", f.display());
    }
    Ok(())
}

/// Parses the arguments. `--help` and `--version` print and exit 0; a usage
/// error becomes a one-line error (clap's own message, without the usage
/// block) so that `main` reports it like every other error.
fn parse_args() -> Result<Cli> {
    match Cli::try_parse() {
        Ok(cli) => Ok(cli),
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => {
            let text = e.to_string();
            let head = text
                .split("\n\nUsage:")
                .next()
                .unwrap_or_default()
                .split("\n\nFor more information")
                .next()
                .unwrap_or_default();
            let line = head.split_whitespace().collect::<Vec<_>>().join(" ");
            Err(anyhow::anyhow!(
                "{} (see `softrod --help`)",
                line.trim_start_matches("error: ")
            ))
        }
    }
}
