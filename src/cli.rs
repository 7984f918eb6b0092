// The command line (included by main.rs).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};
use serde::Serialize;

use softrod::assembly::Robot;
use softrod::element::{Element, PlanarCable};
use softrod::scene::Scene;
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
    /// Solve the static equilibrium of a scene and write the result as JSON.
    Solve {
        /// Scene file (JSON).
        scene: PathBuf,
        /// Chamber pressures in Pa, comma-separated (overrides the scene's).
        #[arg(long, value_delimiter = ',', allow_negative_numbers = true)]
        pressures: Option<Vec<f64>>,
        /// Output file (default: standard output).
        #[arg(long)]
        out: Option<PathBuf>,
    },
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
}

/// The result of `softrod solve`.
#[derive(Serialize)]
struct SolveOut {
    scene: String,
    pressures_pa: Vec<f64>,
    nodes: Vec<NodeOut>,
    tip_position_m: Vec<f64>,
    tip_angle_rad: f64,
    report: StaticReport,
}

fn solve_out(scene: &Scene, robot: &Robot<PlanarCable>, pressures: Vec<f64>, q: &[f64], report: StaticReport) -> SolveOut {
    let nd = PlanarCable::NODE_DOFS;
    let nodes: Vec<NodeOut> = robot
        .node_arc()
        .iter()
        .enumerate()
        .map(|(i, &s)| NodeOut { s_m: s, position_m: q[i * nd..i * nd + 2].to_vec(), slope: q[i * nd + 2..i * nd + 4].to_vec() })
        .collect();
    let tip = &q[q.len() - nd..];
    SolveOut {
        scene: scene.name.clone(),
        pressures_pa: pressures,
        tip_position_m: tip[..2].to_vec(),
        tip_angle_rad: PlanarCable::node_angle(tip),
        nodes,
        report,
    }
}

fn solve(scene: &Scene, pressures: Option<Vec<f64>>) -> Result<SolveOut> {
    let robot = scene.robot()?;
    let mut loads = scene.loads()?;
    if let Some(p) = pressures {
        loads.pressures_pa = p;
    }
    let solver = StaticSolver::new(scene.solver.statics.clone())?;
    let eq = solver.solve(&robot, &loads, None)?;
    Ok(solve_out(scene, &robot, loads.pressures_pa.clone(), &eq.q, eq.report))
}

fn write_json<T: Serialize>(value: &T, out: Option<&PathBuf>) -> Result<()> {
    let text = serde_json::to_string_pretty(value)?;
    match out {
        Some(path) => std::fs::write(path, text + "\n").with_context(|| format!("cannot write {}", path.display())),
        None => {
            use std::io::Write;
            let mut stdout = std::io::stdout().lock();
            writeln!(stdout, "{text}").and_then(|()| stdout.flush()).context("cannot write to standard output")
        }
    }
}

fn default_run() -> Result<()> {
    let scene = Scene::two_section();
    let robot = scene.robot()?;
    let out = solve(&scene, None)?;
    let spec = robot.spec();
    println!("softrod {} — built-in scene `{}`", env!("CARGO_PKG_VERSION"), scene.name);
    println!("  {}", scene.description);
    println!(
        "  {} sections, {} elements, {:.3} m, weight {:.3} N, pressures {:?} kPa",
        spec.sections.len(),
        robot.n_elements(),
        robot.length(),
        spec.sections.iter().map(|s| s.mass_per_length_kg_per_m * s.length_m * 9.81).sum::<f64>(),
        out.pressures_pa.iter().map(|p| p / 1e3).collect::<Vec<_>>()
    );
    println!("  equilibrium: {}", out.report);
    println!("  solve time: {:.1} µs", out.report.wall_time_s * 1e6);
    println!("  tip position: ({:+.4}, {:+.4}) m, tip angle {:+.2}°", out.tip_position_m[0], out.tip_position_m[1], out.tip_angle_rad.to_degrees());
    println!("  markers:");
    for m in &scene.markers {
        if let Some(n) = m.node {
            let p = &out.nodes[n].position_m;
            println!("    node {:2} (s = {:.3} m): ({:+.4}, {:+.4}) m", n, out.nodes[n].s_m, p[0], p[1]);
        }
    }
    println!("Run `softrod solve examples/two_section.json --out result.json` for the full result.");
    Ok(())
}

/// Runs the command line.
pub fn run() -> Result<()> {
    let cli = parse_args()?;
    match cli.command {
        None => default_run(),
        Some(Command::Solve { scene, pressures, out }) => {
            let scene = Scene::from_file(&scene)?;
            let result = solve(&scene, pressures)?;
            write_json(&result, out.as_ref())
        }
    }
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
            let head = text.split("\n\nUsage:").next().unwrap_or_default().split("\n\nFor more information").next().unwrap_or_default();
            let line = head.split_whitespace().collect::<Vec<_>>().join(" ");
            Err(anyhow::anyhow!("{} (see `softrod --help`)", line.trim_start_matches("error: ")))
        }
    }
}
