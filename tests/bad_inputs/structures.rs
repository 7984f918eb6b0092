//! Bad inputs: structures: rods, rigid bodies, joints (rows of the table of `tests/bad_inputs.rs`).

use super::*;

#[allow(clippy::too_many_lines, unused_variables)]
pub(super) fn cases() -> Vec<Case> {
    use Kind::*;
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    vec![
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
                    v["loads"] =
                        json!([{"type": "node_moment", "node": 3, "moment_nm": [0.0, 0.01]}])
                })
            },
            Dim,
            "loads[0].moment_nm",
        ),
        case(
            "non-numeric moment component",
            || {
                spatial_json(|v| {
                    v["loads"] = json!([{"type": "tip_moment", "moment_nm": [0.0, "x", 0.0]}])
                })
            },
            Parse,
            "loads[0].moment_nm[1]",
        ),
        case(
            "four-component moment",
            || {
                spatial_json(|v| {
                    v["loads"] = json!([{"type": "tip_moment", "moment_nm": [0.0, 0.0, 0.0, 1.0]}])
                })
            },
            Parse,
            "loads[0].moment_nm",
        ),
        case(
            "vector tip moment in a planar scene",
            || {
                json(|v| {
                    v["loads"] = json!([{"type": "tip_moment", "moment_nm": [0.0, 0.0, 0.01]}])
                })
            },
            Invalid,
            "loads[0].moment_nm",
        ),
        case(
            "2-D self-weight gravity in a spatial scene",
            || {
                spatial_json(
                    |v| v["loads"] = json!([{"type": "self_weight", "mass_per_length_kg_per_m": 0.1, "gravity_m_per_s2": [0.0, -9.81]}]),
                )
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
