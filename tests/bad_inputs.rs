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

use std::time::{Duration, Instant};

use serde_json::{json, Value};
use softrod::assembly::{RobotSpec, Section, MAX_ELEMENTS};
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
use softrod::Error;

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

#[allow(clippy::too_many_lines)]
fn cases() -> Vec<Case> {
    use Kind::*;
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    vec![
        // --- non-finite numbers, every numeric field of a scene ---
        case(
            "NaN section length",
            move || scene(|s| s.robot.sections[0].length_m = nan),
            Invalid,
            "robot.sections[0].length_m",
        ),
        case(
            "infinite EA",
            move || scene(|s| s.robot.sections[1].ea_n = inf),
            Invalid,
            "robot.sections[1].ea_n",
        ),
        case(
            "-inf EI",
            move || scene(|s| s.robot.sections[0].ei_nm2 = -inf),
            Invalid,
            "robot.sections[0].ei_nm2",
        ),
        case(
            "NaN mass per length",
            move || scene(|s| s.robot.sections[1].mass_per_length_kg_per_m = nan),
            Invalid,
            "robot.sections[1].mass_per_length_kg_per_m",
        ),
        case(
            "NaN rest curvature",
            move || scene(|s| s.robot.sections[0].rest_curvature_per_m = nan),
            Invalid,
            "robot.sections[0].rest_curvature_per_m",
        ),
        case(
            "infinite chamber gain",
            move || scene(|s| s.robot.sections[0].chambers[1].gain_nm_per_pa[0] = inf),
            Invalid,
            "robot.sections[0].chambers[1].gain_nm_per_pa[0]",
        ),
        case(
            "NaN pressure lower bound",
            move || scene(|s| s.robot.sections[1].chambers[0].pressure_min_pa = nan),
            Invalid,
            "robot.sections[1].chambers[0].pressure_min_pa",
        ),
        case(
            "infinite pressure upper bound",
            move || scene(|s| s.robot.sections[1].chambers[1].pressure_max_pa = inf),
            Invalid,
            "robot.sections[1].chambers[1].pressure_max_pa",
        ),
        case(
            "NaN base position",
            move || scene(|s| s.base.position_m[1] = nan),
            Invalid,
            "base.position_m[1]",
        ),
        case(
            "infinite base angle",
            move || scene(|s| s.base.angle_rad = inf),
            Invalid,
            "base.angle_rad",
        ),
        case(
            "NaN gravity",
            move || scene(|s| s.gravity_m_per_s2[0] = nan),
            Invalid,
            "gravity_m_per_s2[0]",
        ),
        case(
            "NaN pressure",
            move || scene(|s| s.pressures_pa[2] = nan),
            Invalid,
            "pressures_pa[2]",
        ),
        case(
            "NaN tip force",
            move || {
                scene_load(Load::TipForce {
                    force_n: vec![nan, 0.0],
                })
            },
            Invalid,
            "loads[0].force_n[0]",
        ),
        case(
            "NaN point-force position",
            move || {
                scene_load(Load::PointForce {
                    s_m: nan,
                    force_n: vec![0.0, 1.0],
                })
            },
            Invalid,
            "loads[0].s_m",
        ),
        case(
            "infinite tip moment",
            move || scene_load(Load::TipMoment { moment_nm: inf.into() }),
            Invalid,
            "loads[0].moment_nm",
        ),
        case(
            "infinite node moment",
            move || {
                scene_load(Load::NodeMoment {
                    node: 3,
                    moment_nm: (-inf).into(),
                })
            },
            Invalid,
            "loads[0].moment_nm",
        ),
        case(
            "NaN Gaussian centre",
            move || {
                scene_load(Load::Distributed(LineLoad::Gaussian {
                    amplitude_n_per_m: vec![0.0, 1.0],
                    center_m: nan,
                    width_m: 0.01,
                }))
            },
            Invalid,
            "loads[0].center_m",
        ),
        case(
            "infinite uniform load",
            move || {
                scene_load(Load::Distributed(LineLoad::Uniform {
                    w_n_per_m: vec![0.0, inf],
                }))
            },
            Invalid,
            "loads[0].w_n_per_m[1]",
        ),
        case(
            "NaN linear load",
            move || {
                scene_load(Load::Distributed(LineLoad::Linear {
                    w_start_n_per_m: vec![nan, 0.0],
                    w_end_n_per_m: vec![0.0, 0.0],
                }))
            },
            Invalid,
            "loads[0].w_start_n_per_m[0]",
        ),
        case(
            "infinite moment at an arc position",
            move || {
                scene_load(Load::Moment {
                    s_m: 0.1,
                    moment_nm: inf.into(),
                })
            },
            Invalid,
            "loads[0].moment_nm",
        ),
        case(
            "moment at the clamped base",
            move || {
                scene_load(Load::Moment {
                    s_m: 0.0,
                    moment_nm: 0.01.into(),
                })
            },
            Invalid,
            "loads[0].s_m",
        ),
        case(
            "moment off the robot",
            move || {
                scene_load(Load::Moment {
                    s_m: 0.25,
                    moment_nm: 0.01.into(),
                })
            },
            Invalid,
            "loads[0].s_m",
        ),
        case(
            "table with arc positions out of order",
            move || {
                scene_load(Load::Distributed(LineLoad::Tabulated {
                    s_m: vec![0.0, 0.2, 0.1],
                    w_n_per_m: vec![vec![0.0, 1.0]; 3],
                }))
            },
            Invalid,
            "loads[0].s_m[2]",
        ),
        case(
            "table reaching beyond the tip",
            move || {
                scene_load(Load::Distributed(LineLoad::Tabulated {
                    s_m: vec![0.0, 0.1, 0.3],
                    w_n_per_m: vec![vec![0.0, 1.0]; 3],
                }))
            },
            Invalid,
            "loads[0].s_m[2]",
        ),
        case(
            "NaN table value",
            move || {
                scene_load(Load::Distributed(LineLoad::Tabulated {
                    s_m: vec![0.0, 0.1],
                    w_n_per_m: vec![vec![0.0, 1.0], vec![nan, 0.0]],
                }))
            },
            Invalid,
            "loads[0].w_n_per_m[1][0]",
        ),
        case(
            "table of one entry",
            move || {
                scene_load(Load::Distributed(LineLoad::Tabulated {
                    s_m: vec![0.1],
                    w_n_per_m: vec![vec![0.0, 1.0]],
                }))
            },
            Invalid,
            "loads[0].s_m",
        ),
        case(
            "table value of the wrong size",
            move || {
                scene_load(Load::Distributed(LineLoad::Tabulated {
                    s_m: vec![0.0, 0.1],
                    w_n_per_m: vec![vec![0.0, 1.0], vec![0.0, 1.0, 2.0]],
                }))
            },
            Dim,
            "loads[0].w_n_per_m[1]",
        ),
        case(
            "NaN extra-weight gravity",
            move || {
                scene_load(Load::SelfWeight {
                    mass_per_length_kg_per_m: 0.1,
                    gravity_m_per_s2: vec![0.0, nan],
                })
            },
            Invalid,
            "loads[0].gravity_m_per_s2[1]",
        ),
        case(
            "NaN extra weight",
            move || {
                scene_load(Load::SelfWeight {
                    mass_per_length_kg_per_m: nan,
                    gravity_m_per_s2: vec![0.0, -9.81],
                })
            },
            Invalid,
            "loads[0].mass_per_length_kg_per_m",
        ),
        case(
            "NaN tip mass",
            move || scene_load(Load::TipMass { mass_kg: nan }),
            Invalid,
            "loads[0].mass_kg",
        ),
        case(
            "NaN marker position",
            move || {
                scene(|s| {
                    s.markers = vec![Marker {
                        node: None,
                        s_m: Some(nan),
                        tangent: false,
                    }]
                })
            },
            Invalid,
            "markers[0].s_m",
        ),
        case(
            "NaN residual tolerance",
            move || settings(|t| t.residual_tolerance = nan),
            Invalid,
            "solver.static.residual_tolerance",
        ),
        case(
            "infinite max step rotation",
            move || settings(|t| t.max_step_rotation = inf),
            Invalid,
            "solver.static.max_step_rotation",
        ),
        // --- non-finite numbers through the API ---
        case(
            "NaN in q0",
            move || {
                let mut q: Vec<f64> = Scene::two_section()
                    .robot()
                    .unwrap()
                    .reference_configuration()
                    .data
                    .into();
                q[5] = nan;
                solve(default_loads(), Some(q))
            },
            Invalid,
            "q0[5]",
        ),
        case(
            "infinite point force (API)",
            move || {
                solve(
                    Loads {
                        point_forces: vec![PointForce {
                            s_m: 0.1,
                            force_n: vec![0.0, -inf],
                        }],
                        ..default_loads()
                    },
                    None,
                )
            },
            Invalid,
            "point_forces[0].force_n[1]",
        ),
        case(
            "NaN distributed-load parameter",
            move || {
                solve(
                    Loads {
                        distributed_f: {
                            let mut f = vec![0.0; 84];
                            f[3] = nan;
                            f
                        },
                        ..default_loads()
                    },
                    None,
                )
            },
            Invalid,
            "distributed_f[3]",
        ),
        case(
            "NaN node moment (API)",
            move || {
                solve(
                    Loads {
                        node_moments: vec![NodeMoment {
                            node: 20,
                            moment_nm: vec![nan],
                        }],
                        ..default_loads()
                    },
                    None,
                )
            },
            Invalid,
            "node_moments[0].moment_nm[0]",
        ),
        case(
            "NaN element length",
            move || PlanarCable::new(nan, 300.0, 0.025).map(|_| ()),
            Invalid,
            "length_m",
        ),
        // --- non-positive stiffness, length, element count; negative mass ---
        case(
            "zero EA",
            move || scene(|s| s.robot.sections[0].ea_n = 0.0),
            Invalid,
            "robot.sections[0].ea_n",
        ),
        case(
            "negative EI",
            move || scene(|s| s.robot.sections[1].ei_nm2 = -0.025),
            Invalid,
            "robot.sections[1].ei_nm2",
        ),
        case(
            "zero length",
            move || scene(|s| s.robot.sections[0].length_m = 0.0),
            Invalid,
            "robot.sections[0].length_m",
        ),
        case(
            "negative length",
            move || scene(|s| s.robot.sections[1].length_m = -0.12),
            Invalid,
            "robot.sections[1].length_m",
        ),
        case(
            "section with zero elements",
            move || scene(|s| s.robot.sections[1].elements = 0),
            Invalid,
            "robot.sections[1].elements",
        ),
        case(
            "negative mass per length",
            move || scene(|s| s.robot.sections[0].mass_per_length_kg_per_m = -0.15),
            Invalid,
            "robot.sections[0].mass_per_length_kg_per_m",
        ),
        case(
            "negative extra weight",
            move || {
                scene_load(Load::SelfWeight {
                    mass_per_length_kg_per_m: -1.0,
                    gravity_m_per_s2: vec![0.0, -9.81],
                })
            },
            Invalid,
            "loads[0].mass_per_length_kg_per_m",
        ),
        case(
            "zero tip mass",
            move || scene_load(Load::TipMass { mass_kg: 0.0 }),
            Invalid,
            "loads[0].mass_kg",
        ),
        case(
            "zero Gaussian width",
            move || {
                scene_load(Load::Distributed(LineLoad::Gaussian {
                    amplitude_n_per_m: vec![0.0, 1.0],
                    center_m: 0.1,
                    width_m: 0.0,
                }))
            },
            Invalid,
            "loads[0].width_m",
        ),
        case(
            "element length underflows to zero",
            move || {
                scene(|s| {
                    s.robot.sections[0].length_m = 1e-320;
                    s.robot.sections[0].elements = 100
                })
            },
            Invalid,
            "robot.sections[0].length_m",
        ),
        case(
            "empty robot",
            move || scene(|s| s.robot.sections.clear()),
            Invalid,
            "robot.sections",
        ),
        case(
            "empty robot (JSON)",
            move || json(|v| v["robot"]["sections"] = json!([])),
            Invalid,
            "robot.sections",
        ),
        // --- markers ---
        case(
            "marker node beyond the tip",
            move || scene(|s| s.markers[4].node = Some(21)),
            Index,
            "markers[4].node",
        ),
        case(
            "marker arc beyond the tip",
            move || {
                scene(|s| {
                    s.markers = vec![Marker {
                        node: None,
                        s_m: Some(0.3),
                        tangent: false,
                    }]
                })
            },
            Invalid,
            "markers[0].s_m",
        ),
        case(
            "marker arc before the base",
            move || {
                scene(|s| {
                    s.markers = vec![Marker {
                        node: None,
                        s_m: Some(-0.01),
                        tangent: false,
                    }]
                })
            },
            Invalid,
            "markers[0].s_m",
        ),
        case(
            "duplicated marker (node and arc)",
            move || {
                scene(|s| {
                    s.markers = vec![
                        Marker {
                            node: Some(4),
                            s_m: None,
                            tangent: false,
                        },
                        Marker {
                            node: None,
                            s_m: Some(0.048),
                            tangent: true,
                        },
                    ]
                })
            },
            Invalid,
            "markers[1]",
        ),
        case(
            "duplicated marker (same node)",
            move || scene(|s| s.markers[3].node = Some(4)),
            Invalid,
            "markers[3]",
        ),
        case(
            "marker with node and arc",
            move || scene(|s| s.markers[0].s_m = Some(0.01)),
            Invalid,
            "markers[0]",
        ),
        case(
            "marker with neither",
            move || scene(|s| s.markers[2].node = None),
            Invalid,
            "markers[2]",
        ),
        // --- pressures ---
        case(
            "pressure above its bound",
            move || scene(|s| s.pressures_pa[0] = 1e6),
            Invalid,
            "pressures_pa[0]",
        ),
        case(
            "pressure below its bound",
            move || scene(|s| s.pressures_pa[1] = -1.0),
            Invalid,
            "pressures_pa[1]",
        ),
        case(
            "too few pressures",
            move || scene(|s| s.pressures_pa.pop().map(|_| ()).unwrap_or(())),
            Dim,
            "pressures_pa",
        ),
        case(
            "too many pressures (API)",
            move || {
                solve(
                    Loads {
                        pressures_pa: vec![0.0; 5],
                        ..Loads::default()
                    },
                    None,
                )
            },
            Dim,
            "pressures_pa",
        ),
        case(
            "inverted pressure bounds",
            move || scene(|s| s.robot.sections[0].chambers[0].pressure_min_pa = 2e5),
            Invalid,
            "robot.sections[0].chambers[0].pressure_max_pa",
        ),
        // --- mismatched dimensions ---
        case(
            "3-entry base position",
            move || scene(|s| s.base.position_m.push(0.0)),
            Dim,
            "base.position_m",
        ),
        case(
            "3-entry gravity",
            move || scene(|s| s.gravity_m_per_s2 = vec![0.0, -9.81, 0.0]),
            Dim,
            "gravity_m_per_s2",
        ),
        case(
            "3-entry tip force",
            move || {
                scene_load(Load::TipForce {
                    force_n: vec![0.0, 1.0, 0.0],
                })
            },
            Dim,
            "loads[0].force_n",
        ),
        case(
            "1-entry linear load",
            move || {
                scene_load(Load::Distributed(LineLoad::Linear {
                    w_start_n_per_m: vec![0.0, 0.0],
                    w_end_n_per_m: vec![1.0],
                }))
            },
            Dim,
            "loads[0].w_end_n_per_m",
        ),
        case(
            "3-entry extra-weight gravity",
            move || {
                scene_load(Load::SelfWeight {
                    mass_per_length_kg_per_m: 0.1,
                    gravity_m_per_s2: vec![0.0, -9.81, 0.0],
                })
            },
            Dim,
            "loads[0].gravity_m_per_s2",
        ),
        case(
            "2-entry chamber gain",
            move || scene(|s| s.robot.sections[1].chambers[0].gain_nm_per_pa.push(1e-6)),
            Dim,
            "robot.sections[1].chambers[0].gain_nm_per_pa",
        ),
        case(
            "q0 of the wrong length",
            move || solve(default_loads(), Some(vec![0.0; 80])),
            Dim,
            "q0",
        ),
        case(
            "distributed-load parameters of the wrong length",
            move || {
                solve(
                    Loads {
                        distributed_f: vec![0.0; 83],
                        ..default_loads()
                    },
                    None,
                )
            },
            Dim,
            "distributed_f",
        ),
        case(
            "2-entry moment (API)",
            move || {
                solve(
                    Loads {
                        node_moments: vec![NodeMoment {
                            node: 3,
                            moment_nm: vec![0.0, 1.0],
                        }],
                        ..default_loads()
                    },
                    None,
                )
            },
            Dim,
            "node_moments[0].moment_nm",
        ),
        case(
            "node moment at the clamped base",
            move || {
                scene_load(Load::NodeMoment {
                    node: 0,
                    moment_nm: 0.1.into(),
                })
            },
            Invalid,
            "loads[0].node",
        ),
        case(
            "node moment beyond the tip",
            move || {
                scene_load(Load::NodeMoment {
                    node: 99,
                    moment_nm: 0.1.into(),
                })
            },
            Index,
            "loads[0].node",
        ),
        case(
            "node moment beyond the tip (API)",
            move || {
                solve(
                    Loads {
                        node_moments: vec![NodeMoment {
                            node: 21,
                            moment_nm: vec![0.1],
                        }],
                        ..default_loads()
                    },
                    None,
                )
            },
            Index,
            "node_moments[0].node",
        ),
        case(
            "point force beyond the tip",
            move || {
                scene_load(Load::PointForce {
                    s_m: 0.25,
                    force_n: vec![0.0, 1.0],
                })
            },
            Invalid,
            "loads[0].s_m",
        ),
        // --- low-level API with wrong sizes ---
        case(
            "sparse solve with a short right-hand side",
            || {
                let p = std::sync::Arc::new(SymmetricPattern::from_elements(3, &[vec![0, 1, 2]])?);
                let mut k = SymmetricMatrix::zeros(p.clone());
                for i in 0..3 {
                    k.add(i, i, 1.0)?;
                }
                let f = AutoSolver::analyze(&p)?.factor(&k, FactorOptions::default())?;
                Ok(f.solve_in_place(&mut [1.0, 2.0])?)
            },
            Dim,
            "b",
        ),
        case(
            "banded entry outside the band",
            || BandedMatrix::zeros(5, 1, 1).try_add(0, 3, 1.0),
            Invalid,
            "j",
        ),
        case(
            "banded entry beyond the matrix",
            || BandedMatrix::zeros(5, 1, 1).try_add(5, 5, 1.0),
            Index,
            "i",
        ),
        case(
            "position_at with a short q",
            || {
                let r = Scene::two_section().robot()?;
                r.position_at(&[0.0; 8], 0.1).map(|_| ())
            },
            Dim,
            "q",
        ),
        case(
            "position_at off the robot",
            || {
                let r = Scene::two_section().robot()?;
                r.position_at(r.reference_configuration().as_slice(), 1.0).map(|_| ())
            },
            Invalid,
            "s_m",
        ),
        case(
            "residual_into with a short output",
            || {
                let r = Scene::two_section().robot()?;
                let q = r.reference_configuration();
                r.residual_into(q.as_slice(), &vec![0.0; r.n_q()], &default_loads(), &mut [0.0; 3])
            },
            Dim,
            "residual",
        ),
        case(
            "residual with a moment beyond the tip",
            || {
                let r = Scene::two_section().robot()?;
                let q = r.reference_configuration();
                let l = Loads {
                    node_moments: vec![NodeMoment {
                        node: 50,
                        moment_nm: vec![1.0],
                    }],
                    ..default_loads()
                };
                r.residual(q.as_slice(), &vec![0.0; r.n_q()], &l).map(|_| ())
            },
            Index,
            "node_moments[0].node",
        ),
        case(
            "tangent with an empty moment",
            || {
                let r = Scene::two_section().robot()?;
                let q = r.reference_configuration();
                let l = Loads {
                    node_moments: vec![NodeMoment {
                        node: 5,
                        moment_nm: vec![],
                    }],
                    ..default_loads()
                };
                r.tangent_into(q.as_slice(), &l, &mut BandedMatrix::zeros(1, 0, 0))
            },
            Dim,
            "node_moments[0].moment_nm",
        ),
        case(
            "expand_step with a long step",
            || {
                let r = Scene::two_section().robot()?;
                r.expand_step(&vec![0.0; r.n_free() + 1]).map(|_| ())
            },
            Dim,
            "du",
        ),
        // --- absurd sizes, refused before allocating ---
        case(
            "10^9 elements",
            move || scene(|s| s.robot.sections[0].elements = 1_000_000_000),
            TooLarge,
            "robot.sections[0].elements",
        ),
        case(
            "usize::MAX elements",
            move || scene(|s| s.robot.sections[1].elements = usize::MAX),
            TooLarge,
            "robot.sections[1].elements",
        ),
        case(
            "elements too many only in sum",
            move || {
                scene(|s| {
                    s.robot.sections[0].elements = MAX_ELEMENTS / 2 + 1;
                    s.robot.sections[1].elements = MAX_ELEMENTS / 2 + 1
                })
            },
            TooLarge,
            "robot.sections[1].elements",
        ),
        case(
            "10^9 elements (JSON)",
            move || json(|v| v["robot"]["sections"][0]["elements"] = json!(1_000_000_000u64)),
            TooLarge,
            "robot.sections[0].elements",
        ),
        case(
            "10^6 axial Gauss points",
            move || scene(|s| s.robot.axial_gauss_points = 1_000_000),
            TooLarge,
            "robot.axial_gauss_points",
        ),
        case(
            "zero bending Gauss points",
            move || scene(|s| s.robot.bending_gauss_points = 0),
            Invalid,
            "robot.bending_gauss_points",
        ),
        case(
            "Gauss rule of usize::MAX points",
            || GaussRule::new(usize::MAX).map(|_| ()),
            TooLarge,
            "gauss_points",
        ),
        case(
            "element rule of 33 points",
            || PlanarCable::with_rules(0.1, 1.0, 1.0, 0.0, 33, 3).map(|_| ()),
            TooLarge,
            "axial_gauss_points",
        ),
        case(
            "banded matrix of usize::MAX rows",
            || BandedMatrix::try_zeros(usize::MAX, 7, 7).map(|_| ()),
            TooLarge,
            "n",
        ),
        case(
            "robot spec of 10^12 elements",
            || {
                RobotSpec::new(vec![Section::uniform(1.0, 1.0, 1.0, 1_000_000_000_000)])
                    .build_planar()
                    .map(|_| ())
            },
            TooLarge,
            "robot.sections[0].elements",
        ),
        // --- static settings out of range ---
        case(
            "zero iterations",
            move || settings(|t| t.max_iterations = 0),
            Invalid,
            "solver.static.max_iterations",
        ),
        case(
            "10^9 total iterations",
            move || settings(|t| t.max_total_iterations = 1_000_000_000),
            TooLarge,
            "solver.static.max_total_iterations",
        ),
        case(
            "total budget below the per-step budget",
            move || settings(|t| t.max_total_iterations = 10),
            Invalid,
            "solver.static.max_total_iterations",
        ),
        case(
            "zero residual tolerance",
            move || settings(|t| t.residual_tolerance = 0.0),
            Invalid,
            "solver.static.residual_tolerance",
        ),
        case(
            "residual tolerance of 2",
            move || settings(|t| t.residual_tolerance = 2.0),
            Invalid,
            "solver.static.residual_tolerance",
        ),
        case(
            "increment tolerance of 1",
            move || settings(|t| t.increment_tolerance = 1.0),
            Invalid,
            "solver.static.increment_tolerance",
        ),
        case(
            "negative max step rotation",
            move || settings(|t| t.max_step_rotation = -0.5),
            Invalid,
            "solver.static.max_step_rotation",
        ),
        case(
            "min load step of 1.5",
            move || settings(|t| t.min_load_step = 1.5),
            Invalid,
            "solver.static.min_load_step",
        ),
        case(
            "NaN increment tolerance (API)",
            || {
                StaticSolver::new(StaticSettings {
                    increment_tolerance: f64::NAN,
                    ..Default::default()
                })
                .map(|_| ())
            },
            Invalid,
            "increment_tolerance",
        ),
        // --- malformed JSON, unknown and missing fields, wrong types ---
        case(
            "truncated JSON",
            || Scene::from_json(r#"{"robot": {"sections": [{"length_m": 0.1"#).map(|_| ()),
            Parse,
            "EOF while parsing",
        ),
        case(
            "not JSON",
            || Scene::from_json("robot = 1").map(|_| ()),
            Parse,
            "line 1 column 1",
        ),
        case(
            "empty file",
            || Scene::from_json("").map(|_| ()),
            Parse,
            "EOF",
        ),
        case(
            "unknown field in a section",
            move || json(|v| v["robot"]["sections"][0]["colour"] = json!(3)),
            Parse,
            "robot.sections[0].colour: unknown field `colour`",
        ),
        case(
            "unknown top-level field",
            move || json(|v| v["pressure"] = json!([1])),
            Parse,
            "unknown field `pressure`",
        ),
        case(
            "unknown field in a load",
            move || {
                json(|v| {
                    v["loads"] = json!([{"type": "tip_force", "force_n": [0, 1], "torque": 2}])
                })
            },
            Parse,
            "unknown field `torque`",
        ),
        case(
            "unknown load type",
            move || json(|v| v["loads"] = json!([{"type": "laser", "power": 2}])),
            Parse,
            "unknown variant `laser`",
        ),
        case(
            "unknown solver setting",
            move || json(|v| v["solver"]["static"]["tolerance"] = json!(1e-9)),
            Parse,
            "solver.static.tolerance: unknown field `tolerance`",
        ),
        case(
            "unknown element family",
            move || json(|v| v["robot"]["element"] = json!("beam3d")),
            Parse,
            "robot.element: unknown variant `beam3d`",
        ),
        case(
            "missing EI",
            move || {
                json(|v| {
                    v["robot"]["sections"][1]
                        .as_object_mut()
                        .unwrap()
                        .remove("ei_nm2");
                })
            },
            Parse,
            "missing field `ei_nm2`",
        ),
        case(
            "missing robot",
            move || {
                json(|v| {
                    v.as_object_mut().unwrap().remove("robot");
                })
            },
            Parse,
            "missing field `robot`",
        ),
        case(
            "missing load field",
            move || json(|v| v["loads"] = json!([{"type": "point_force", "force_n": [0, 1]}])),
            Parse,
            "missing field `s_m`",
        ),
        case(
            "negative element count",
            move || json(|v| v["robot"]["sections"][0]["elements"] = json!(-3)),
            Parse,
            "robot.sections[0].elements: invalid value",
        ),
        case(
            "fractional element count",
            move || json(|v| v["robot"]["sections"][1]["elements"] = json!(2.5)),
            Parse,
            "robot.sections[1].elements",
        ),
        case(
            "element count neither a number nor auto",
            move || json(|v| v["robot"]["sections"][0]["elements"] = json!("many")),
            Parse,
            "robot.sections[0].elements: invalid value: string \"many\", expected a positive integer or \"auto\"",
        ),
        case(
            "auto without a refinement",
            move || {
                json(|v| v["robot"]["sections"][1]["elements"] = json!("auto"))
            },
            Invalid,
            "refinement",
        ),
        case(
            "refinement without an auto section",
            move || {
                json(|v| {
                    v["refinement"] = json!({"quantity": "tip_position", "tolerance_m": 1e-5})
                })
            },
            Invalid,
            "refinement",
        ),
        case(
            "zero tolerance",
            move || auto_json(|v| v["refinement"]["tolerance_m"] = json!(0.0)),
            Invalid,
            "refinement.tolerance_m",
        ),
        case(
            "negative tolerance",
            move || {
                auto_json(|v| {
                    v["refinement"] = json!({"quantity": "load_resultant", "tolerance_n": -1e-3})
                })
            },
            Invalid,
            "refinement.tolerance_n",
        ),
        case(
            "NaN tolerance",
            move || {
                auto_scene(|s| {
                    s.refinement = Some(RefinementTarget::TipPosition {
                        tolerance_m: nan,
                        max_elements: 100,
                    })
                })
            },
            Invalid,
            "refinement.tolerance_m",
        ),
        case(
            "max_elements below the smallest mesh",
            move || auto_json(|v| v["refinement"]["max_elements"] = json!(1)),
            Invalid,
            "refinement.max_elements",
        ),
        case(
            "max_elements above the limit",
            move || auto_json(|v| v["refinement"]["max_elements"] = json!(MAX_ELEMENTS + 1)),
            TooLarge,
            "refinement.max_elements",
        ),
        case(
            "unknown refinement quantity",
            move || auto_json(|v| v["refinement"]["quantity"] = json!("tip_angle")),
            Parse,
            "unknown variant `tip_angle`",
        ),
        case(
            "tolerance in the wrong unit",
            move || {
                auto_json(|v| {
                    v["refinement"] = json!({"quantity": "tip_position", "tolerance_n": 1e-3})
                })
            },
            Parse,
            "tolerance_n",
        ),
        case(
            "refinement without a tolerance",
            move || auto_json(|v| v["refinement"] = json!({"quantity": "tip_position"})),
            Parse,
            "missing field `tolerance_m`",
        ),
        case(
            "marker by node with auto",
            move || auto_json(|v| v["markers"][2] = json!({"node": 4})),
            Invalid,
            "markers[2].node",
        ),
        case(
            "node moment with auto",
            move || {
                auto_json(|v| v["loads"] = json!([{"type": "node_moment", "node": 3, "moment_nm": 0.01}]))
            },
            Invalid,
            "loads[0].node",
        ),
        case(
            "concentrated load model by node with auto",
            move || {
                auto_json(|v| {
                    v["solver"]["estimator"] = json!({"load_model": {"kind": "concentrated", "node": 20}})
                })
            },
            Invalid,
            "solver.estimator.load_model.node",
        ),
        case(
            "unknown load stated twice",
            move || {
                json(|v| {
                    v["unknown_load"] = json!({"acts_at": "point", "s_m": 0.24});
                    v["solver"]["estimator"] = json!({"load_model": {"kind": "concentrated", "node": 20}});
                })
            },
            Invalid,
            "unknown_load",
        ),
        case(
            "unknown point load off the robot",
            move || auto_json(|v| v["unknown_load"] = json!({"acts_at": "point", "s_m": 0.3})),
            Invalid,
            "unknown_load.s_m",
        ),
        case(
            "unknown point load at the clamped base",
            move || json(|v| v["unknown_load"] = json!({"acts_at": "point", "s_m": 0.0})),
            Invalid,
            "unknown_load.s_m",
        ),
        case(
            "unknown point load between nodes of a fixed mesh",
            move || json(|v| v["unknown_load"] = json!({"acts_at": "point", "s_m": 0.13})),
            Invalid,
            "unknown_load.s_m",
        ),
        case(
            "unknown point load no mesh within max_elements puts a node at",
            move || {
                auto_json(|v| {
                    v["unknown_load"] = json!({"acts_at": "point", "s_m": 0.1234567891});
                    v["refinement"]["max_elements"] = json!(50);
                })
            },
            Invalid,
            "unknown_load.s_m",
        ),
        case(
            "unknown load kind",
            move || json(|v| v["unknown_load"] = json!({"acts_at": "line"})),
            Parse,
            "unknown variant `line`",
        ),
        case(
            "string for a number",
            move || json(|v| v["robot"]["sections"][0]["ea_n"] = json!("300")),
            Parse,
            "robot.sections[0].ea_n: invalid type",
        ),
        case(
            "number out of range",
            || {
                Scene::from_json(r#"{"robot": {"sections": [{"length_m": 1e999, "ea_n": 1, "ei_nm2": 1, "elements": 2}]}}"#).map(|_| ())
            },
            Parse,
            "robot.sections[0].length_m",
        ),
        case(
            "null for a vector",
            move || json(|v| v["gravity_m_per_s2"] = Value::Null),
            Parse,
            "gravity_m_per_s2: invalid type: null",
        ),
        case(
            "unreadable file",
            || Scene::from_file(std::path::Path::new("/nonexistent/scene.json")).map(|_| ()),
            Parse,
            "cannot read /nonexistent/scene.json",
        ),
        // --- the estimator's inputs ---
        case(
            "alpha = 0 (fewer observations than load parameters)",
            || estimate(Backend::Newton, |s| s.alpha = Some(0.0), |_| {}),
            Invalid,
            "estimator.alpha",
        ),
        case(
            "negative alpha",
            || estimate(Backend::Sqp, |s| s.alpha = Some(-1.0), |_| {}),
            Invalid,
            "estimator.alpha",
        ),
        case(
            "NaN alpha",
            || estimate(Backend::Newton, |s| s.alpha = Some(f64::NAN), |_| {}),
            Invalid,
            "estimator.alpha",
        ),
        case(
            "zero marker noise",
            || estimate(Backend::Newton, |s| s.noise_sigma_m = 0.0, |_| {}),
            Invalid,
            "estimator.noise_sigma_m",
        ),
        case(
            "zero estimator iterations",
            || estimate(Backend::Sqp, |s| s.max_iterations = 0, |_| {}),
            Invalid,
            "estimator.max_iterations",
        ),
        case(
            "zero position weight",
            || {
                estimate(
                    Backend::Newton,
                    |_| {},
                    |o| o.markers[1].position_weight = Some(vec![1.0, 0.0]),
                )
            },
            Invalid,
            "observation.markers[1].position_weight[1]",
        ),
        case(
            "negative position weight",
            || {
                estimate(
                    Backend::Sqp,
                    |_| {},
                    |o| o.markers[0].position_weight = Some(vec![-1.0, 1.0]),
                )
            },
            Invalid,
            "observation.markers[0].position_weight[0]",
        ),
        case(
            "NaN observed position",
            || {
                estimate(
                    Backend::Newton,
                    |_| {},
                    |o| o.markers[2].position_m[0] = f64::NAN,
                )
            },
            Invalid,
            "observation.markers[2].position_m[0]",
        ),
        case(
            "3-D position for a planar robot",
            || {
                estimate(
                    Backend::Newton,
                    |_| {},
                    |o| o.markers[0].position_m.push(0.0),
                )
            },
            Dim,
            "observation.markers[0].position_m",
        ),
        case(
            "2-D position for a spatial robot",
            || estimate_spatial(|_| {}, |o| o.markers[0].position_m.truncate(2)),
            Dim,
            "observation.markers[0].position_m",
        ),
        case(
            "2-D tangent for a spatial robot",
            || estimate_spatial(|_| {}, |o| o.markers[3].tangent = Some(vec![1.0, 0.0])),
            Dim,
            "observation.markers[3].tangent",
        ),
        case(
            "local-frame load bound on a spatial robot",
            || {
                estimate_spatial(
                    |s| {
                        s.bounds = vec![LoadBound {
                            s_m: 0.12,
                            frame: BoundFrame::Local,
                            direction: vec![0.0, 1.0, 0.0],
                            min_n_per_m: Some(0.0),
                            max_n_per_m: None,
                        }]
                    },
                    |_| {},
                )
            },
            Invalid,
            "estimator.bounds[0].frame",
        ),
        case(
            "2-D load bound direction on a spatial robot",
            || {
                estimate_spatial(
                    |s| {
                        s.bounds = vec![LoadBound {
                            s_m: 0.12,
                            frame: BoundFrame::World,
                            direction: vec![0.0, 1.0],
                            min_n_per_m: Some(0.0),
                            max_n_per_m: None,
                        }]
                    },
                    |_| {},
                )
            },
            Dim,
            "estimator.bounds[0].direction",
        ),
        case(
            "observed marker beyond the tip (node)",
            || estimate(Backend::Newton, |_| {}, |o| o.markers[4].node = Some(21)),
            Index,
            "observation.markers[4].node",
        ),
        case(
            "observed marker beyond the tip (arc)",
            || {
                estimate(
                    Backend::Sqp,
                    |_| {},
                    |o| o.markers[4] = MarkerObservation::at_arc(0.3, nalgebra::Vector2::new(0.3, 0.0)),
                )
            },
            Invalid,
            "observation.markers[4].s_m",
        ),
        case(
            "duplicated observed marker",
            || estimate(Backend::Newton, |_| {}, |o| o.markers[1].node = Some(4)),
            Invalid,
            "observation.markers[1]",
        ),
        case(
            "empty observation",
            || estimate(Backend::Newton, |_| {}, |o| o.markers.clear()),
            Invalid,
            "observation.markers",
        ),
        case(
            "zero bound direction",
            || {
                estimate(
                    Backend::Sqp,
                    |s| {
                        s.bounds = vec![LoadBound {
                            s_m: 0.1,
                            frame: BoundFrame::World,
                            direction: vec![0.0, 0.0],
                            min_n_per_m: Some(0.0),
                            max_n_per_m: None,
                        }]
                    },
                    |_| {},
                )
            },
            Invalid,
            "estimator.bounds[0].direction",
        ),
        // --- structures: rods, rigid bodies, joints ---
        case(
            "structure without rods",
            || structure(|s| s.rods.clear()),
            Invalid,
            "structure.rods",
        ),
        case(
            "joint naming a missing body",
            || {
                structure(|s| {
                    if let JointSpec::RodToBody { body, .. } = &mut s.joints[1] {
                        *body = 3;
                    }
                })
            },
            Index,
            "structure.joints[1].body",
        ),
        case(
            "joint naming a missing rod",
            || {
                structure(|s| {
                    if let JointSpec::RodToBody { rod, .. } = &mut s.joints[0] {
                        *rod = 7;
                    }
                })
            },
            Index,
            "structure.joints[0].rod",
        ),
        case(
            "rod end joined twice",
            || structure(|s| s.joints.push(s.joints[1].clone())),
            Invalid,
            "structure.joints[2].end",
        ),
        case(
            "clamped rod end also joined",
            || {
                structure(|s| {
                    s.joints.push(JointSpec::RodToBody {
                        rod: 0,
                        end: RodEnd::Start,
                        body: 0,
                        point_m: None,
                        direction: None,
                    })
                })
            },
            Invalid,
            "structure.joints[2].end",
        ),
        case(
            "rigid body fixed to the ground twice",
            || {
                structure(|s| {
                    s.joints.push(JointSpec::BodyToGround { body: 0 });
                    s.joints.push(JointSpec::BodyToGround { body: 0 });
                })
            },
            Invalid,
            "structure.joints[3].body",
        ),
        case(
            "rigid body with no mass and no joint",
            || {
                structure(|s| {
                    s.rigid_bodies.push(RigidBodySpec {
                        mass_kg: 0.0,
                        position_m: vec![1.0, 1.0],
                        orientation_rad: vec![0.0],
                    })
                })
            },
            Invalid,
            "structure.rigid_bodies[1].mass_kg",
        ),
        case(
            "floating structure: no rod end clamped",
            || {
                structure(|s| {
                    for r in &mut s.rods {
                        r.start = EndSupport::Free;
                    }
                })
            },
            Invalid,
            "structure.rods[0]",
        ),
        case(
            "floating rigid body with a mass and no joint",
            || {
                structure(|s| {
                    s.rigid_bodies.push(RigidBodySpec {
                        mass_kg: 0.1,
                        position_m: vec![1.0, 1.0],
                        orientation_rad: vec![0.0],
                    })
                })
            },
            Invalid,
            "structure.rigid_bodies[1]",
        ),
        case(
            "structure with more elements than the limit, over all rods",
            || structure(|s| s.rods[1].sections[0].elements = MAX_ELEMENTS),
            TooLarge,
            "structure.rods[1].sections[0].elements",
        ),
        case(
            "joint point off the rod's end",
            || {
                structure(|s| {
                    if let JointSpec::RodToBody { point_m, .. } = &mut s.joints[0] {
                        *point_m = Some(vec![-0.05, 0.01]);
                    }
                })
            },
            Invalid,
            "structure.joints[0].point_m",
        ),
        case(
            "zero joint direction",
            || {
                structure(|s| {
                    if let JointSpec::RodToBody { direction, .. } = &mut s.joints[1] {
                        *direction = Some(vec![0.0, 0.0]);
                    }
                })
            },
            Invalid,
            "structure.joints[1].direction",
        ),
        case(
            "NaN rigid body mass",
            move || structure(|s| s.rigid_bodies[0].mass_kg = nan),
            Invalid,
            "structure.rigid_bodies[0].mass_kg",
        ),
        case(
            "rigid body orientation of the wrong size",
            || structure(|s| s.rigid_bodies[0].orientation_rad = vec![0.0, 0.0, 0.0]),
            Dim,
            "structure.rigid_bodies[0].orientation_rad",
        ),
        case(
            "zero rod direction",
            || structure(|s| s.rods[0].direction = vec![0.0, 0.0]),
            Invalid,
            "structure.rods[0].direction",
        ),
        case(
            "negative EI in a structure's rod",
            || structure(|s| s.rods[1].sections[0].ei_nm2 = -1.0),
            Invalid,
            "structure.rods[1].sections[0].ei_nm2",
        ),
        case(
            "load on a missing rigid body",
            || {
                structure_loads(StructureLoads {
                    bodies: vec![BodyLoad {
                        body: 2,
                        force_n: vec![0.0, 1.0],
                        moment_nm: vec![],
                    }],
                    ..StructureLoads::default()
                })
            },
            Index,
            "loads.bodies[0].body",
        ),
        case(
            "loads for one rod of two",
            || {
                structure_loads(StructureLoads {
                    rods: vec![Loads::default()],
                    ..StructureLoads::default()
                })
            },
            Dim,
            "loads.rods",
        ),
        case(
            "moment at a clamped rod start",
            || {
                structure_loads(StructureLoads {
                    rods: vec![
                        Loads {
                            node_moments: vec![NodeMoment {
                                node: 0,
                                moment_nm: vec![0.1],
                            }],
                            ..Loads::default()
                        },
                        Loads::default(),
                    ],
                    ..StructureLoads::default()
                })
            },
            Invalid,
            "loads.rods[0].node_moments[0].node",
        ),
        case(
            "unknown estimator setting",
            || json(|v| v["solver"]["estimator"] = json!({"backend": "newton", "beta": 1.0})),
            Parse,
            "beta",
        ),
        case(
            "unknown element",
            || json(|v| v["robot"]["element"] = json!("full_ancf")),
            Parse,
            "robot.element",
        ),
        case(
            "2-D tip force in a spatial scene",
            || spatial_json(|v| v["loads"][0]["force_n"] = json!([0.0, 1.0])),
            Dim,
            "loads[0].force_n",
        ),
        case(
            "3-D tip force in a planar scene",
            || json(|v| v["loads"] = json!([{"type": "tip_force", "force_n": [0.0, 1.0, 0.0]}])),
            Dim,
            "loads[0].force_n",
        ),
        case(
            "2-D base position in a spatial scene",
            || spatial_json(|v| v["base"]["position_m"] = json!([0.0, 0.0])),
            Dim,
            "base.position_m",
        ),
        case(
            "3-D base position in a planar scene",
            || json(|v| v["base"]["position_m"] = json!([0.0, 0.0, 0.0])),
            Dim,
            "base.position_m",
        ),
        case(
            "2-D base direction in a spatial scene",
            || spatial_json(|v| v["base"]["direction"] = json!([1.0, 0.0])),
            Dim,
            "base.direction",
        ),
        case(
            "zero base direction in a spatial scene",
            || spatial_json(|v| v["base"]["direction"] = json!([0.0, 0.0, 0.0])),
            Invalid,
            "base.direction",
        ),
        case(
            "2-D gravity in a spatial scene",
            || spatial_json(|v| v["gravity_m_per_s2"] = json!([0.0, -9.81])),
            Dim,
            "gravity_m_per_s2",
        ),
        case(
            "null gravity in a spatial scene",
            || spatial_json(|v| v["gravity_m_per_s2"] = Value::Null),
            Parse,
            "gravity_m_per_s2: invalid type: null",
        ),
        case(
            "2-D distributed load in a spatial scene",
            || {
                spatial_json(|v| {
                    v["loads"] = json!([{"type": "distributed", "profile": "uniform", "w_n_per_m": [0.0, 1.0]}])
                })
            },
            Dim,
            "loads[0].w_n_per_m",
        ),
        case(
            "scalar tip moment in a spatial scene",
            || spatial_json(|v| v["loads"] = json!([{"type": "tip_moment", "moment_nm": 0.01}])),
            Invalid,
            "loads[0].moment_nm",
        ),
        case(
            "2-D node moment in a spatial scene",
            || {
                spatial_json(|v| {
                    v["loads"] = json!([{"type": "node_moment", "node": 3, "moment_nm": [0.0, 0.01]}])
                })
            },
            Dim,
            "loads[0].moment_nm",
        ),
        case(
            "non-numeric moment component",
            || spatial_json(|v| v["loads"] = json!([{"type": "tip_moment", "moment_nm": [0.0, "x", 0.0]}])),
            Parse,
            "loads[0]: moment_nm[1]",
        ),
        case(
            "four-component moment",
            || spatial_json(|v| v["loads"] = json!([{"type": "tip_moment", "moment_nm": [0.0, 0.0, 0.0, 1.0]}])),
            Parse,
            "loads[0]: moment_nm",
        ),
        case(
            "vector tip moment in a planar scene",
            || json(|v| v["loads"] = json!([{"type": "tip_moment", "moment_nm": [0.0, 0.0, 0.01]}])),
            Invalid,
            "loads[0].moment_nm",
        ),
        case(
            "2-D self-weight gravity in a spatial scene",
            || {
                spatial_json(|v| {
                    v["loads"] = json!([{"type": "self_weight", "mass_per_length_kg_per_m": 0.1, "gravity_m_per_s2": [0.0, -9.81]}])
                })
            },
            Dim,
            "loads[0].gravity_m_per_s2",
        ),
        case(
            "1-D chamber gain in a spatial scene",
            || {
                spatial_json(|v| {
                    v["robot"]["sections"][0]["chambers"] = json!([{"gain_nm_per_pa": [3e-6], "pressure_min_pa": 0.0, "pressure_max_pa": 1e5}]);
                    v["pressures_pa"] = json!([0.0]);
                })
            },
            Dim,
            "robot.sections[0].chambers[0].gain_nm_per_pa",
        ),
        case(
            "rest curvature in a spatial scene",
            || spatial_json(|v| v["robot"]["sections"][1]["rest_curvature_per_m"] = json!(2.0)),
            Invalid,
            "robot.sections[1].rest_curvature_per_m",
        ),
        case(
            "auto elements in a spatial scene",
            || {
                spatial_json(|v| {
                    v["robot"]["sections"][0]["elements"] = json!("auto");
                    v["refinement"] = json!({"quantity": "tip_position", "tolerance_m": 1e-5});
                })
            },
            Invalid,
            "robot.sections[0].elements",
        ),
    ]
}

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
    q.iter().all(|v| v.is_finite())
        && [
            r.residual_norm_n,
            r.residual_tolerance_n,
            r.residual_floor_n,
            r.load_scale_n,
            r.increment_norm_m,
            r.wall_time_s,
        ]
        .iter()
        .all(|v| v.is_finite())
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
