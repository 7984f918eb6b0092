//! Bad inputs: scene numbers: non-finite (scenes and API), non-positive, markers (rows of the table of `tests/bad_inputs.rs`).

use super::*;

#[allow(clippy::too_many_lines, unused_variables)]
pub(super) fn cases() -> Vec<Case> {
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
            move || {
                scene_load(Load::TipMoment {
                    moment_nm: inf.into(),
                })
            },
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
    ]
}
