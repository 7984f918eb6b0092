//! Every bad input is refused with a typed error that names the field at
//! fault (issue "Hardening", points 1–3 and the fuzzing regressions).
//!
//! One table: each row builds a bad input, runs the public call a user
//! would make, and states the exact error variant and field name expected.
//! Scenes start from the paper's two-section robot (`Scene::two_section`, 20
//! elements, 21 nodes, 4 chambers) and change one thing. JSON cannot express
//! NaN or infinity, so non-finite numbers are put into the parsed `Scene`
//! and checked with `Scene::validate`, exactly what `Scene::from_json` runs.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;
#[path = "common/scene_checks.rs"]
mod scene_checks;

use std::time::{Duration, Instant};

use serde_json::{Value, json};
use softrod::Error;
use softrod::assembly::{MAX_ELEMENTS, RobotSpec, Section};
use softrod::element::{PlanarCable, SpatialCable};
use softrod::estimate::{
    Backend, BoundFrame, EstimatorSettings, LoadBound, MarkerObservation, Observation,
};
use softrod::linsolve::{
    AutoSolver, BandedMatrix, FactorOptions, Factorization, SymmetricMatrix, SymmetricPattern,
    TangentSolver,
};
use softrod::loads::Load;
use softrod::loads::{LineLoad, Loads, NodeMoment, PointForce};
use softrod::quadrature::GaussRule;
use softrod::scene::{Marker, RefinementTarget, Scene};
use softrod::statics::{StaticSettings, StaticSolver, StaticStatus};
use softrod::structure::{
    BodyLoad, EndSupport, JointSpec, RigidBodySpec, RodEnd, StructureLoads, StructureSpec,
};

/// The error variant a case must produce.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Invalid,
    Dim,
    TooLarge,
    Index,
    /// `Error::Scene`: the field is checked as a substring of the message.
    Parse,
    NonFinite,
}

fn kind_of(e: &Error) -> Option<Kind> {
    Some(match e {
        Error::InvalidParameter { .. } => Kind::Invalid,
        Error::DimensionMismatch { .. } => Kind::Dim,
        Error::TooLarge { .. } => Kind::TooLarge,
        Error::IndexOutOfRange { .. } => Kind::Index,
        Error::Scene { .. } => Kind::Parse,
        Error::NonFinite { .. } => Kind::NonFinite,
        _ => return None,
    })
}

/// Builds an estimator for the two-section robot (settings changed by
/// `fs`) and takes one step on an observation of its straight configuration
/// at nodes 4, 8, 12, 16, 20 (changed by `fo`).
fn estimate(
    backend: Backend,
    fs: impl FnOnce(&mut EstimatorSettings),
    fo: impl FnOnce(&mut Observation),
) -> Result<(), Error> {
    let scene = Scene::two_section();
    let robot = scene.robot()?;
    let q = robot.reference_configuration();
    let mut settings = EstimatorSettings::default();
    fs(&mut settings);
    let mut obs = Observation {
        markers: [4usize, 8, 12, 16, 20]
            .iter()
            .map(|&n| {
                MarkerObservation::at_node(
                    n,
                    nalgebra::Vector2::from_column_slice(&q.as_slice()[4 * n..4 * n + 2]),
                )
            })
            .collect(),
    };
    fo(&mut obs);
    let mut est = softrod::estimate::EstimatorSettings {
        backend,
        ..settings
    }
    .build_for(&robot, &scene.loads()?)?;
    est.step(&obs).map(|_| ())
}

/// Validates the two-section scene after `f` changed it.
fn scene(f: impl FnOnce(&mut Scene)) -> Result<(), Error> {
    let mut s = Scene::two_section();
    f(&mut s);
    s.validate()
}

/// Validates the two-section scene with one load.
fn scene_load(load: Load) -> Result<(), Error> {
    scene(|s| s.loads = vec![load])
}

/// Parses `examples/two_section.json` after `f` changed its JSON value.
fn json(f: impl FnOnce(&mut Value)) -> Result<(), Error> {
    let mut v: Value = serde_json::from_str(include_str!("../examples/two_section.json")).unwrap();
    f(&mut v);
    Scene::from_json(&v.to_string()).map(|_| ())
}

/// Parses `examples/auto_tip.json` (the two-section robot with
/// `"elements": "auto"`, markers by arc coordinate and a `tip_position`
/// refinement) after `f` changed its JSON value.
fn auto_json(f: impl FnOnce(&mut Value)) -> Result<(), Error> {
    let mut v: Value = serde_json::from_str(include_str!("../examples/auto_tip.json")).unwrap();
    f(&mut v);
    Scene::from_json(&v.to_string()).map(|_| ())
}

/// Parses `examples/spatial_cantilever.json` (a spatial cable scene) after
/// `f` changed its JSON value.
fn spatial_json(f: impl FnOnce(&mut Value)) -> Result<(), Error> {
    let mut v: Value =
        serde_json::from_str(include_str!("../examples/spatial_cantilever.json")).unwrap();
    f(&mut v);
    Scene::from_json(&v.to_string()).map(|_| ())
}

/// Builds an SQP estimator for the spatial example
/// (`examples/spatial_cantilever.json`, 16 elements), its settings changed by
/// `fs`, and takes one step on markers at nodes 4, 8, 12, 16 of its straight
/// configuration (changed by `fo`).
fn estimate_spatial(
    fs: impl FnOnce(&mut EstimatorSettings),
    fo: impl FnOnce(&mut Observation),
) -> Result<(), Error> {
    let scene = Scene::from_json(include_str!("../examples/spatial_cantilever.json"))?;
    let robot = scene.robot_as::<SpatialCable>()?;
    let q = robot.reference_configuration();
    let mut settings = EstimatorSettings {
        backend: Backend::Sqp,
        ..EstimatorSettings::default()
    };
    fs(&mut settings);
    let mut obs = Observation {
        markers: [4usize, 8, 12, 16]
            .iter()
            .map(|&n| {
                MarkerObservation::at_node(
                    n,
                    nalgebra::Vector3::from_column_slice(&q.as_slice()[6 * n..6 * n + 3]),
                )
            })
            .collect(),
    };
    fo(&mut obs);
    let mut est = settings.build_for(&robot, &scene.loads()?)?;
    est.step(&obs).map(|_| ())
}

/// Validates `examples/auto_tip.json` after `f` changed the parsed scene.
fn auto_scene(f: impl FnOnce(&mut Scene)) -> Result<(), Error> {
    let mut s = Scene::from_json(include_str!("../examples/auto_tip.json")).unwrap();
    f(&mut s);
    s.validate()
}

/// Solves the two-section scene with `loads` from `q0`.
fn solve(loads: Loads, q0: Option<Vec<f64>>) -> Result<(), Error> {
    let s = Scene::two_section();
    let robot = s.robot().unwrap();
    StaticSolver::default()
        .solve(&robot, &loads, q0.as_deref())
        .map(|_| ())
}

fn default_loads() -> Loads {
    Scene::two_section().loads().unwrap()
}

fn settings(f: impl FnOnce(&mut StaticSettings)) -> Result<(), Error> {
    scene(|s| f(&mut s.solver.statics))
}

/// Two legs clamped at x = ±0.05 m whose tips are fixed to a 50 g
/// platform, after `f` changed the spec; built as a planar structure.
fn structure(f: impl FnOnce(&mut StructureSpec)) -> Result<(), Error> {
    let mut spec = two_legs();
    f(&mut spec);
    spec.build_planar().map(|_| ())
}

/// The two-leg platform of `tests/structure.rs` (4 elements a leg, 50 g).
fn two_legs() -> StructureSpec {
    common::two_legs(4, 0.05, true)
}

/// The dead forces of the two-leg platform under `loads`.
fn structure_loads(loads: StructureLoads) -> Result<(), Error> {
    two_legs().build_planar()?.dead_force(&loads).map(|_| ())
}

type Case = (
    &'static str,
    Box<dyn Fn() -> Result<(), Error>>,
    Kind,
    &'static str,
);

fn case(
    what: &'static str,
    run: impl Fn() -> Result<(), Error> + 'static,
    kind: Kind,
    field: &'static str,
) -> Case {
    (what, Box::new(run), kind, field)
}

/// Every row of the table, by subject (one file each under `tests/bad_inputs/`).
fn cases() -> Vec<Case> {
    [
        scene_values::cases(),
        sizes::cases(),
        files_estimator::cases(),
        structures::cases(),
    ]
    .into_iter()
    .flatten()
    .collect()
}

#[path = "bad_inputs/files_estimator.rs"]
mod files_estimator;
#[path = "bad_inputs/scene_values.rs"]
mod scene_values;
#[path = "bad_inputs/sizes.rs"]
mod sizes;
#[path = "bad_inputs/structures.rs"]
mod structures;

/// The table: every case fails with its variant and names its field. All
/// failures are collected, so one run shows every wrong row.
#[test]
fn every_bad_input_is_refused_with_its_variant_and_field() {
    let table = cases();
    assert!(table.len() >= 30, "{} cases", table.len());
    let mut wrong = Vec::new();
    for (what, run, kind, field) in &table {
        let start = Instant::now();
        let outcome = run();
        let took = start.elapsed();
        match outcome {
            Ok(()) => wrong.push(format!("{what}: accepted")),
            Err(e) => {
                let got = kind_of(&e);
                let named = match &e {
                    Error::Scene { message } => message.contains(field),
                    Error::NonFinite { context } => context.contains(field),
                    other => other.field() == Some(*field),
                };
                println!("{what:50} -> {e}");
                if got != Some(*kind) || !named {
                    wrong.push(format!(
                        "{what}: expected {kind:?} naming `{field}`, got {e:?}"
                    ));
                }
            }
        }
        // refused before any work proportional to the request
        if took > Duration::from_secs(1) {
            wrong.push(format!("{what}: took {took:?}"));
        }
    }
    println!("{} cases", table.len());
    assert!(
        wrong.is_empty(),
        "{} wrong rows:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}

/// Zero mass per length is a weightless robot, not an error: it solves (to
/// the pure-actuation arc) like any other.
#[test]
fn zero_mass_is_a_weightless_robot_that_solves() {
    let mut s = Scene::two_section();
    for sec in &mut s.robot.sections {
        sec.mass_per_length_kg_per_m = 0.0;
    }
    s.validate().unwrap();
    let robot = s.robot().unwrap();
    let eq = StaticSolver::default()
        .solve(&robot, &s.loads().unwrap(), None)
        .unwrap();
    assert!(eq.report.status.is_converged());
    assert!(eq.q.iter().all(|v| v.is_finite()));
    assert!(robot.gravity_force().iter().all(|v| *v == 0.0));
}

/// Every number a solve returns: the coordinates and the report's floats.
fn all_finite(q: &[f64], r: &softrod::statics::StaticReport) -> bool {
    q.iter().all(|v| v.is_finite()) && scene_checks::report_is_finite(r)
}

/// Loads far beyond what the model can carry and contradictory or
/// degenerate inputs end within the iteration budget and a few seconds,
/// either with a converged, finite, in-tolerance equilibrium or with
/// `NotConverged` carrying a finite report and its cause. No NaN leaves.
#[test]
fn divergent_and_ill_posed_solves_end_with_a_report_in_bounded_time() {
    let s = Scene::two_section();
    let robot = s.robot().unwrap();
    let base = s.loads().unwrap();
    let l = robot.length();
    let ei = 0.025;
    let turns = |n: f64| ei * 2.0 * std::f64::consts::PI * n / l;
    let tip_force = |f: Vec<f64>| Loads {
        point_forces: vec![PointForce { s_m: l, force_n: f }],
        ..base.clone()
    };
    let tip_moment = |m: f64| Loads {
        node_moments: vec![NodeMoment {
            node: 20,
            moment_nm: vec![m],
        }],
        ..base.clone()
    };
    let far = robot
        .reference_configuration()
        .iter()
        .map(|v| v * 1e150 + 1e150)
        .collect::<Vec<_>>();
    let cases: Vec<(&str, Loads, Option<Vec<f64>>)> = vec![
        ("tip force 1e6 N down", tip_force(vec![0.0, -1e6]), None),
        (
            "tip force 1e6 N backwards (compression)",
            tip_force(vec![-1e6, 0.0]),
            None,
        ),
        ("tip force 1e300 N", tip_force(vec![1e300, -1e300]), None),
        ("tip moment of 10 turns", tip_moment(turns(10.0)), None),
        ("tip moment of 1000 turns", tip_moment(turns(1000.0)), None),
        ("tip moment 1e300 N m", tip_moment(1e300), None),
        // a huge tip moment against a huge opposite moment one node before:
        // a kink the cable cannot take
        (
            "opposed moments of 50 turns",
            Loads {
                node_moments: vec![
                    NodeMoment {
                        node: 19,
                        moment_nm: vec![-turns(50.0)],
                    },
                    NodeMoment {
                        node: 20,
                        moment_nm: vec![turns(50.0)],
                    },
                ],
                ..base.clone()
            },
            None,
        ),
        (
            "uniform load 1e5 N/m",
            Loads {
                line_loads: vec![LineLoad::Uniform {
                    w_n_per_m: vec![0.0, -1e5],
                }],
                ..base.clone()
            },
            None,
        ),
        (
            "Gaussian load narrower than round-off",
            Loads {
                line_loads: vec![LineLoad::Gaussian {
                    amplitude_n_per_m: vec![0.0, 1.0],
                    center_m: 0.12,
                    width_m: 1e-200,
                }],
                ..base.clone()
            },
            None,
        ),
        ("start 1e150 m away", base.clone(), Some(far)),
        (
            "start with every coordinate zero",
            base.clone(),
            Some(vec![0.0; robot.n_q()]),
        ),
    ];
    let solver = StaticSolver::default();
    let budget = solver.settings.max_total_iterations;
    for (what, loads, q0) in cases {
        let start = Instant::now();
        let outcome = solver.solve(&robot, &loads, q0.as_deref());
        let took = start.elapsed();
        assert!(took < Duration::from_secs(5), "{what}: took {took:?}");
        match outcome {
            Ok(eq) => {
                let r = &eq.report;
                println!("{what:45} -> converged: {r}");
                assert!(all_finite(eq.q.as_slice(), r), "{what}: non-finite result");
                assert!(r.iterations <= budget, "{what}: {r}");
                assert!(
                    r.residual_norm_n <= 1.0001 * r.residual_tolerance_n.max(r.residual_floor_n)
                        || r.status.criterion()
                            == Some(softrod::statics::StaticCriterion::Increment),
                    "{what}: {r}"
                );
            }
            Err(Error::NotConverged { report }) => {
                println!("{what:45} -> {report}");
                assert!(!report.status.is_converged(), "{what}: {report}");
                assert!(report.iterations <= budget, "{what}: {report}");
                assert!(all_finite(&[], &report), "{what}: {report:?}");
            }
            Err(Error::NonFinite { context }) => {
                // loads whose generalized forces overflow are refused up front
                println!("{what:45} -> non-finite {context}");
            }
            Err(other) => panic!("{what}: unexpected {other:?}"),
        }
    }
}

/// With a small budget a divergent solve stops at the budget.
#[test]
fn a_small_budget_bounds_the_iterations_of_a_divergent_solve() {
    let s = Scene::two_section();
    let robot = s.robot().unwrap();
    let loads = Loads {
        point_forces: vec![PointForce {
            s_m: robot.length(),
            force_n: vec![-1e6, 1e6],
        }],
        ..s.loads().unwrap()
    };
    let settings = StaticSettings {
        max_iterations: 10,
        max_total_iterations: 25,
        ..Default::default()
    };
    match StaticSolver::new(settings)
        .unwrap()
        .solve(&robot, &loads, None)
    {
        Err(Error::NotConverged { report }) => {
            assert_eq!(
                report.status,
                StaticStatus::IterationLimit { iterations: 25 },
                "{report}"
            );
            assert!(!report.status.is_converged(), "{report}");
            assert_eq!(report.iterations, 25, "{report}");
            assert!(all_finite(&[], &report));
        }
        other => panic!("expected the iteration budget to stop the solve, got {other:?}"),
    }
}

/// The load checks run on every solve and format a field's name only when
/// it is at fault: the second entry of each list is named with its index
/// and field, as the first would be.
#[test]
fn the_load_checks_name_the_entry_at_fault_by_its_index() {
    use softrod::loads::{FollowerLoad, PointMoment};
    let robot = Scene::two_section().robot().unwrap();
    let with = |f: &dyn Fn(&mut Loads)| {
        let mut l = default_loads();
        f(&mut l);
        l
    };
    let force = |s_m: f64, force_n: Vec<f64>| PointForce { s_m, force_n };
    let forces = |bad: PointForce| vec![force(0.1, vec![0.0, -0.01]), bad];
    let uniform = |w: Vec<f64>| LineLoad::Uniform { w_n_per_m: w };
    let node = |node: usize, m: f64| NodeMoment {
        node,
        moment_nm: vec![m],
    };
    let point = |m: f64| PointMoment {
        s_m: 0.1,
        moment_nm: vec![m],
    };
    let follower = |p: f64| FollowerLoad {
        pressure_n_per_m: p,
        s_start_m: None,
        s_end_m: None,
    };
    let table = LineLoad::Tabulated {
        s_m: vec![0.0, 9.0],
        w_n_per_m: vec![vec![0.0, 0.0], vec![0.0, -0.1]],
    };
    let rows: Vec<(Loads, Kind, &str)> = vec![
        (
            with(&|l| l.point_forces = forces(force(0.1, vec![0.0, f64::NAN]))),
            Kind::Invalid,
            "point_forces[1].force_n[1]",
        ),
        (
            with(&|l| l.point_forces = forces(force(0.1, vec![0.0]))),
            Kind::Dim,
            "point_forces[1].force_n",
        ),
        (
            with(&|l| l.point_forces = forces(force(5.0, vec![0.0, -0.01]))),
            Kind::Invalid,
            "point_forces[1].s_m",
        ),
        (
            with(&|l| l.line_loads = vec![uniform(vec![0.0, -0.1]), uniform(vec![0.0; 3])]),
            Kind::Dim,
            "line_loads[1].w_n_per_m",
        ),
        (
            with(&|l| l.line_loads = vec![uniform(vec![0.0, -0.1]), table.clone()]),
            Kind::Invalid,
            "line_loads[1].s_m[1]",
        ),
        (
            with(&|l| l.node_moments = vec![node(3, 0.01), node(4, f64::INFINITY)]),
            Kind::Invalid,
            "node_moments[1].moment_nm[0]",
        ),
        (
            with(&|l| l.point_moments = vec![point(0.01), point(f64::NAN)]),
            Kind::Invalid,
            "point_moments[1].moment_nm[0]",
        ),
        (
            with(&|l| l.follower_loads = vec![follower(0.1), follower(f64::NAN)]),
            Kind::Invalid,
            "follower_loads[1].pressure_n_per_m",
        ),
    ];
    for (loads, kind, field) in rows {
        let e = robot.validate_loads(&loads).unwrap_err();
        assert_eq!(
            (kind_of(&e), e.field()),
            (Some(kind), Some(field)),
            "{field}: {e}"
        );
        // the solver's own check says the same
        let e = StaticSolver::default()
            .solve(&robot, &loads, None)
            .unwrap_err();
        assert_eq!(e.field(), Some(field), "{field}: {e}");
    }
}
