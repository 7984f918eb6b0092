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
mod replay;
mod track;

use std::path::PathBuf;

mod parallel;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use serde::Serialize;

use softrod::assembly::{Robot, ValidityWarning};
use softrod::element::{Element, PlanarCable};
use softrod::estimate::{Backend, Estimate, EstimateReport, MarkerObservation, Observation};
use softrod::loads::{LineLoad, PointForce};
use softrod::refine::{Quantity, Refinement};
use softrod::scene::{Scene, SceneRobot};
use softrod::statics::{StaticReport, StaticSolver};

/// Shape and force estimation for slender soft robots (ANCF cable model).
///
/// Without a subcommand, runs the built-in two-section robot and prints a summary.
#[derive(Parser, Debug)]
#[command(name = "softrod", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

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
    /// the estimator kept warm, written as {"frames": [{"t_s", "status", "estimate"}, ...]}.
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

/// One node of a result.
#[derive(Serialize)]
struct NodeOut {
    /// Undeformed arc coordinate (m).
    s_m: f64,
    /// Position (m).
    position_m: Vec<f64>,
    /// Slope r' (dimensionless; its norm is 1 + axial strain).
    slope: Vec<f64>,
    /// Planar: the tangent's angle from the x axis (rad), unwrapped along
    /// the backbone (a full circle ends at 2π).
    #[serde(skip_serializing_if = "Option::is_none")]
    angle_rad: Option<f64>,
}

/// Fills in the planar robot's unwrapped node angles; returns the tip's.
fn fill_angles(
    robot: &Robot<PlanarCable>,
    q: &[f64],
    nodes: &mut [NodeOut],
) -> Result<Option<f64>> {
    let angles = robot.node_angles(q)?;
    for (n, a) in nodes.iter_mut().zip(&angles) {
        n.angle_rad = Some(*a);
    }
    Ok(angles.as_slice().last().copied())
}

/// The result of `softrod solve`.
#[derive(Serialize)]
struct SolveOut {
    scene: String,
    pressures_pa: Vec<f64>,
    nodes: Vec<NodeOut>,
    tip_position_m: Vec<f64>,
    /// Planar: the tip tangent's angle from the x axis (rad).
    #[serde(skip_serializing_if = "Option::is_none")]
    tip_angle_rad: Option<f64>,
    /// Spatial: the unit tangent at the tip.
    #[serde(skip_serializing_if = "Option::is_none")]
    tip_direction: Option<Vec<f64>>,
    /// Spatial: the angle between the tip tangent and the base tangent (rad).
    #[serde(skip_serializing_if = "Option::is_none")]
    tip_angle_from_base_rad: Option<f64>,
    report: StaticReport,
    /// The configuration (not written).
    #[serde(skip)]
    q: Vec<f64>,
    /// Where the result leaves the model's validity (also on stderr).
    warnings: Vec<ValidityWarning>,
    /// How the counts of "elements": "auto" sections were chosen.
    #[serde(skip_serializing_if = "Option::is_none")]
    refinement: Option<Refinement>,
}

/// The nodes of configuration `q`: arc coordinate, position and slope.
fn node_outs<E: Element>(robot: &Robot<E>, q: &[f64]) -> Vec<NodeOut> {
    let (d, nd) = (E::DIM, E::NODE_DOFS);
    robot
        .node_arc()
        .iter()
        .enumerate()
        .map(|(i, &s)| NodeOut {
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
) -> SolveOut {
    let tip = &q[q.len() - E::NODE_DOFS..];
    SolveOut {
        scene: scene.name.clone(),
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
) -> Result<SolveOut> {
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

fn solve(scene: &Scene, pressures: Option<Vec<f64>>) -> Result<SolveOut> {
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

/// One sample of the estimated load.
#[derive(Serialize)]
struct LoadSample {
    /// Undeformed arc coordinate (m).
    s: f64,
    /// Load per undeformed length, world axes (N/m).
    w: Vec<f64>,
}

/// Resultant of the estimated load.
#[derive(Serialize)]
struct ResultantOut {
    /// Force (N), world axes.
    force_n: Vec<f64>,
    /// Standard deviation of each force component for the stated marker noise (N).
    force_std_n: Vec<f64>,
    /// Moment about the base position, in the estimated shape (N·m).
    moment_nm: Vec<f64>,
}

/// The result of `softrod estimate`.
#[derive(Serialize)]
struct EstimateOut {
    scene: String,
    backend: String,
    /// Where the observation came from.
    observation: String,
    /// The known chamber pressures (Pa) the estimate is for.
    pressures_pa: Vec<f64>,
    /// Node coordinates of the estimated shape (m).
    nodes: Vec<NodeOut>,
    /// The estimated distributed load on an evenly spaced grid of `load_grid_points` arc coordinates.
    load: Vec<LoadSample>,
    load_grid_points: usize,
    /// The raw load parameters F (N/m, N/m², node-major [w, w']; or the force, N).
    load_parameters: Vec<f64>,
    resultant: ResultantOut,
    /// Marker residuals A q - y (m), in observation order.
    marker_residuals_m: Vec<f64>,
    /// Standard deviation of the estimated marker-space shape (m), per observed component.
    marker_std_m: Vec<f64>,
    /// Largest standard deviation of a load parameter (N/m or N).
    max_load_parameter_std: f64,
    /// The marker noise the covariances are stated for (m).
    noise_sigma_m: f64,
    /// Load directions the markers determine (the evidence's effective
    /// number of parameters; null if it could not be computed).
    determined_directions: f64,
    /// Fewer than 0.5 load directions determined: the markers barely see
    /// the load, `force_std_n` is a prior's width, not knowledge (also on stderr).
    weakly_informed: bool,
    report: EstimateReport,
    /// The estimated configuration (not written).
    #[serde(skip)]
    q: Vec<f64>,
    /// Where the estimated shape leaves the model's validity (also on stderr).
    warnings: Vec<ValidityWarning>,
    /// How the counts of "elements": "auto" sections were chosen.
    #[serde(skip_serializing_if = "Option::is_none")]
    refinement: Option<Refinement>,
}

const LOAD_GRID: usize = 49;

fn estimate_out<E: Element>(
    scene: &Scene,
    robot: &Robot<E>,
    pressures_pa: Vec<f64>,
    e: &Estimate,
    observation: String,
) -> EstimateOut {
    let nodes = node_outs(robot, e.q.as_slice());
    let d = e.resultant_force_n.len();
    let m = e.marker_residuals.len();
    EstimateOut {
        scene: scene.name.clone(),
        backend: e.report.backend.name().to_string(),
        observation,
        pressures_pa,
        nodes,
        load: e
            .sample_load(LOAD_GRID)
            .into_iter()
            .map(|(s, w)| LoadSample {
                s,
                w: w.as_slice().to_vec(),
            })
            .collect(),
        load_grid_points: LOAD_GRID,
        load_parameters: e.f.as_slice().to_vec(),
        resultant: ResultantOut {
            force_n: e.resultant_force_n.as_slice().to_vec(),
            force_std_n: (0..d)
                .map(|a| e.resultant_force_cov()[(a, a)].max(0.0).sqrt())
                .collect(),
            moment_nm: e.resultant_moment_nm.as_slice().to_vec(),
        },
        marker_residuals_m: e.marker_residuals.as_slice().to_vec(),
        marker_std_m: (0..m)
            .map(|i| e.marker_cov()[(i, i)].max(0.0).sqrt())
            .collect(),
        max_load_parameter_std: e.std_f().iter().copied().fold(0.0, f64::max),
        noise_sigma_m: e.noise_sigma_m,
        determined_directions: e.determined_directions(),
        weakly_informed: e.weakly_informed(),
        report: e.report.clone(),
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
    markers: Option<(&PathBuf, replay::Markers)>,
) -> Result<Vec<(Option<f64>, EstimateOut)>> {
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
    markers: Option<(&PathBuf, replay::Markers)>,
) -> Result<Vec<(Option<f64>, EstimateOut)>> {
    let known = scene.loads()?;
    let mut settings = scene.estimator_settings()?;
    if let Some(b) = backend {
        settings.backend = b;
    }
    let (observations, source) = match markers {
        Some((path, m)) => (m.observations(), format!("markers file {}", path.display())),
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
            estimate_out(scene, &robot, pressures.clone(), &e, source.clone()),
        ));
    }
    Ok(outs)
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
            let stream = matches!(file, Some(replay::Markers::Stream(_)));
            let mut outs = estimate(
                &scene,
                backend.map(Backend::from),
                markers.as_ref().zip(file),
            )?;
            if stream {
                let source = outs
                    .first()
                    .map(|(_, o)| o.observation.clone())
                    .unwrap_or_default();
                let frames = outs
                    .into_iter()
                    .map(|(t, mut o)| {
                        o.refinement.clone_from(&refinement);
                        (t.unwrap_or(0.0), o)
                    })
                    .collect();
                let result = replay::StreamOut::new(source, frames);
                result.summarize();
                write_json(&result, out.as_ref())?;
                if let Some(&i) = result.not_converged.first() {
                    anyhow::bail!(
                        "{} of {} frames did not converge (the first: frames[{i}], {}); every frame's record is written with its status",
                        result.not_converged.len(),
                        result.n_frames,
                        result.frames[i].status
                    );
                }
                return Ok(());
            }
            let Some((_, mut result)) = outs.pop() else {
                anyhow::bail!("no observation to estimate from");
            };
            result.refinement = refinement;
            if markers.is_none() {
                eprintln!("softrod: no markers file: {}", result.observation);
            }
            warn_all(&result.warnings);
            if result.weakly_informed && result.report.status.is_converged() {
                eprintln!(
                    "softrod: warning: the markers determine {:.3} load directions (fewer than {}): they barely see the load; the estimate stays near zero and `force_std_n` is the width of a prior fitted to markers that show no load, not knowledge of the load",
                    result.determined_directions,
                    softrod::estimate::WEAKLY_INFORMED_DIRECTIONS
                );
            }
            write_json(&result, out.as_ref())?;
            // the last iterate is written (its report says how it ended); the
            // exit status says that it is not an estimate
            let status = result.report.status;
            if status == softrod::outcome::EstimateStatus::NoInformation {
                anyhow::bail!(
                    "{status}; the result written is the prior (zero load, the prior's standard deviations), not an estimate"
                );
            }
            if !status.is_converged() {
                anyhow::bail!(
                    "estimation did not converge: {status}; the result written is the last iterate"
                );
            }
            Ok(())
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
                q.backend.name(), q.elements, q.markers, q.median_step_s * 1e3, q.backbone_rms_m * 1e3, q.load_rel_l2 * 100.0, q.force_rel * 100.0
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
