//! The first estimate (a fresh estimator, `α` chosen by the default rule,
//! the evidence) of both backends on every load of the estimator tests and
//! of the report's sweep, at 20 elements and 5 markers: wall time (median
//! of `REPEATS` runs; the two backends' runs alternate, so a shared
//! machine's load falls on both alike), the tangent factorizations counted
//! ([`softrod::linsolve::LinearWork`], independent of the load), iterations,
//! the `α` found and the ratio of the two backends' times.
//!
//! `cargo run --release --features cli --example first_estimate [REPEATS [FILTER]]`
//! (`FILTER`: only the loads whose name contains it)
//!
//! Loads on the two-section robot (its known pressures; the truth solved on
//! a mesh twice as fine, 5 markers at `L k / 5` with 0.01 mm seeded noise):
//! the tests' uniform, linear and Gaussian loads, two separated bumps, a
//! uniform load plus a tip force, a tip force alone, the benches' tip mass
//! plus uniform load. On the report's references (exudyn's cable, markers
//! read off its solution): the large Gaussian bump and uniform load and the
//! uniform family `k × self-weight`.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use std::time::Instant;

use softrod::assembly::Robot;
use softrod::element::PlanarCable;
use softrod::estimate::{Backend, EstimatorSettings, MarkerObservation, Observation};
use softrod::loads::{LineLoad, Loads, PointForce};
use softrod::report::reference::{self, Reference};
use softrod::report::sweep;
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

/// A load case: the estimator's robot and known loads, the observation.
struct Case {
    name: String,
    robot: Robot<PlanarCable>,
    known: Loads,
    obs: Observation,
}

fn two_section(n: usize) -> (Robot<PlanarCable>, Loads) {
    let mut scene = Scene::two_section();
    scene.robot.sections[0].elements = n / 2;
    scene.robot.sections[1].elements = n - n / 2;
    (scene.robot().unwrap(), scene.loads().unwrap())
}

fn scene_case(name: &str, lines: Vec<LineLoad>, points: Vec<PointForce>) -> Case {
    let (fine, known) = two_section(40);
    let (robot, _) = two_section(20);
    let mut truth = known.clone();
    truth.line_loads.extend(lines);
    truth.point_forces.extend(points);
    // the truth's shape, the load added in steps from the known shape
    let solver = StaticSolver::default();
    let mut q = solver.solve(&fine, &known, None).unwrap().q;
    let steps = 8;
    for k in 1..=steps {
        let t = f64::from(k) / f64::from(steps);
        let mut l = known.clone();
        l.line_loads.extend(
            truth
                .line_loads
                .iter()
                .skip(known.line_loads.len())
                .map(|x| scale_line(x, t)),
        );
        l.point_forces.extend(
            truth
                .point_forces
                .iter()
                .skip(known.point_forces.len())
                .map(|p| PointForce {
                    s_m: p.s_m,
                    force_n: p.force_n.iter().map(|v| v * t).collect(),
                }),
        );
        q = solver.solve(&fine, &l, Some(q.as_slice())).unwrap().q;
    }
    let markers = sweep::marker_arcs(robot.length(), 5)
        .iter()
        .map(|&s| MarkerObservation::at_arc(s, fine.position_at(q.as_slice(), s).unwrap()))
        .collect();
    Case {
        name: name.into(),
        robot,
        known,
        obs: Observation { markers }.with_noise(1e-5, 7),
    }
}

fn scale_line(l: &LineLoad, t: f64) -> LineLoad {
    let s = |v: &Vec<f64>| v.iter().map(|x| x * t).collect::<Vec<f64>>();
    match l {
        LineLoad::Uniform { w_n_per_m } => LineLoad::Uniform {
            w_n_per_m: s(w_n_per_m),
        },
        LineLoad::Linear {
            w_start_n_per_m,
            w_end_n_per_m,
        } => LineLoad::Linear {
            w_start_n_per_m: s(w_start_n_per_m),
            w_end_n_per_m: s(w_end_n_per_m),
        },
        LineLoad::Gaussian {
            amplitude_n_per_m,
            center_m,
            width_m,
        } => LineLoad::Gaussian {
            amplitude_n_per_m: s(amplitude_n_per_m),
            center_m: *center_m,
            width_m: *width_m,
        },
        other => other.clone(),
    }
}

fn reference_case(name: &str) -> Case {
    let r = Reference::embedded(name).unwrap();
    let robot = sweep::model_robot(&r, 20).unwrap();
    let obs = sweep::observe(&r, sweep::marker_arcs(r.length_m, 5).as_slice(), 1e-5, 7);
    Case {
        name: name.into(),
        robot,
        known: Loads::default(),
        obs,
    }
}

fn gaussian(a: f64, c: f64, w: f64) -> LineLoad {
    LineLoad::Gaussian {
        amplitude_n_per_m: vec![0.0, a],
        center_m: c,
        width_m: w,
    }
}

fn cases() -> Vec<Case> {
    let uniform = |w: f64| LineLoad::Uniform {
        w_n_per_m: vec![0.0, w],
    };
    let tip = |f: f64| PointForce {
        s_m: 0.24,
        force_n: vec![0.0, f],
    };
    let mut v = vec![
        scene_case("uniform 1 N/m", vec![uniform(-1.0)], vec![]),
        scene_case(
            "linear to (0.5, -2) N/m",
            vec![LineLoad::Linear {
                w_start_n_per_m: vec![0.0, 0.0],
                w_end_n_per_m: vec![0.5, -2.0],
            }],
            vec![],
        ),
        scene_case(
            "gaussian -20 N/m at 0.16 m",
            vec![gaussian(-20.0, 0.16, 0.01)],
            vec![],
        ),
        scene_case(
            "two bumps (0.06 m, 0.18 m)",
            vec![gaussian(-10.0, 0.06, 0.01), gaussian(10.0, 0.18, 0.01)],
            vec![],
        ),
        scene_case(
            "uniform 1 N/m + tip 0.2 N",
            vec![uniform(-1.0)],
            vec![tip(-0.2)],
        ),
        scene_case("tip force 0.2 N", vec![], vec![tip(-0.2)]),
        scene_case(
            "bench: 20 g tip + 0.5 N/m",
            vec![uniform(-0.5)],
            vec![tip(-0.02 * 9.81)],
        ),
    ];
    for name in ["exudyn_gaussian_large", "exudyn_uniform_large"] {
        v.push(reference_case(name));
    }
    for k in reference::FAMILY_FACTORS {
        v.push(reference_case(&reference::family_name(k)));
    }
    v
}

/// One backend's runs on a case: the wall times (s) and the last run's
/// estimate.
struct Runs {
    times: Vec<f64>,
    last: Option<softrod::Result<softrod::estimate::Estimate>>,
}

impl Runs {
    /// The median and the fastest run (s).
    fn median_min(&mut self) -> (f64, f64) {
        self.times.sort_by(f64::total_cmp);
        (self.times[self.times.len() / 2], self.times[0])
    }
}

fn main() {
    let repeats: usize = std::env::args()
        .nth(1)
        .map(|a| a.parse().unwrap())
        .unwrap_or(5);
    let filter = std::env::args().nth(2).unwrap_or_default();
    println!(
        "{:<34} {:>10} {:>5} {:>6} {:>9} {:>10} {:>5} {:>6} {:>9} {:>7} {:>7} {:>7}",
        "load",
        "newton ms",
        "fact",
        "it",
        "alpha",
        "sqp ms",
        "fact",
        "it",
        "alpha",
        "ratio",
        "min-r",
        "f-ratio"
    );
    let backends = [Backend::Newton, Backend::Sqp];
    let (mut worst, mut worst_min, mut worst_work) = (0.0f64, 0.0f64, 0.0f64);
    for c in cases().into_iter().filter(|c| c.name.contains(&filter)) {
        let mut runs: Vec<Runs> = backends
            .iter()
            .map(|_| Runs {
                times: Vec::new(),
                last: None,
            })
            .collect();
        for _ in 0..repeats {
            for (backend, r) in backends.iter().zip(runs.iter_mut()) {
                let settings = EstimatorSettings::default();
                let mut est = softrod::estimate::EstimatorSettings {
                    backend: *backend,
                    ..settings
                }
                .build_for(&c.robot, &c.known)
                .unwrap();
                let t = Instant::now();
                let e = est.step(&c.obs);
                r.times.push(t.elapsed().as_secs_f64());
                r.last = Some(e);
            }
        }
        let mut fastest = [0.0; 2];
        let row: Vec<(f64, usize, usize, f64, bool)> = runs
            .iter_mut()
            .zip(fastest.iter_mut())
            .map(|(r, fast)| {
                let (med, min) = r.median_min();
                *fast = min;
                match r.last.take().unwrap() {
                    Ok(e) => (
                        med,
                        e.report.linear_work.factorizations,
                        e.report.iterations,
                        e.report.alpha,
                        e.report.status.is_converged(),
                    ),
                    Err(_) => (med, 0, 0, f64::NAN, false),
                }
            })
            .collect();
        let ratio = row[0].0 / row[1].0;
        let ratio_min = fastest[0] / fastest[1];
        worst_min = worst_min.max(ratio_min.max(1.0 / ratio_min));
        let work = row[0].1 as f64 / row[1].1.max(1) as f64;
        worst = worst.max(ratio.max(1.0 / ratio));
        worst_work = worst_work.max(work.max(1.0 / work));
        let mark = |ok: bool| if ok { "" } else { "!" };
        println!(
            "{:<34} {:>9.3}{} {:>5} {:>6} {:>9.3e} {:>9.3}{} {:>5} {:>6} {:>9.3e} {:>7.2} {:>7.2} {:>7.2}",
            c.name,
            row[0].0 * 1e3,
            mark(row[0].4),
            row[0].1,
            row[0].2,
            row[0].3,
            row[1].0 * 1e3,
            mark(row[1].4),
            row[1].1,
            row[1].2,
            row[1].3,
            ratio,
            ratio_min,
            work,
        );
    }
    println!(
        "largest ratio either way: median time {worst:.2}, fastest run {worst_min:.2}, \
         factorizations {worst_work:.2}"
    );
}
