//! Bad inputs: malformed JSON, unknown and missing fields, wrong types; the estimator's inputs (rows of the table of `tests/bad_inputs.rs`).

use super::*;

#[allow(clippy::too_many_lines, unused_variables)]
pub(super) fn cases() -> Vec<Case> {
    use Kind::*;
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    vec![
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
            move || json(|v| v["robot"]["sections"][1]["elements"] = json!("auto")),
            Invalid,
            "refinement",
        ),
        case(
            "refinement without an auto section",
            move || {
                json(|v| v["refinement"] = json!({"quantity": "tip_position", "tolerance_m": 1e-5}))
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
                auto_json(|v| {
                    v["loads"] = json!([{"type": "node_moment", "node": 3, "moment_nm": 0.01}])
                })
            },
            Invalid,
            "loads[0].node",
        ),
        case(
            "concentrated load model by node with auto",
            move || {
                auto_json(|v| {
                    v["solver"]["estimator"] =
                        json!({"load_model": {"kind": "concentrated", "node": 20}})
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
                    v["solver"]["estimator"] =
                        json!({"load_model": {"kind": "concentrated", "node": 20}});
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
                    |o| {
                        o.markers[4] =
                            MarkerObservation::at_arc(0.3, nalgebra::Vector2::new(0.3, 0.0))
                    },
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
    ]
}
