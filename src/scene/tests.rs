//! Unit tests of scene parsing.

use super::*;

#[test]
fn example_file_is_the_built_in_scene() {
    let text = include_str!("../../examples/two_section.json");
    assert_eq!(Scene::from_json(text).unwrap(), Scene::two_section());
}

#[test]
fn unknown_and_missing_fields_are_named() {
    let bad = r#"{"robot": {"sections": [{"length_m": 0.1, "ea_n": 1, "ei_nm2": 1, "elements": 2, "colour": 3}]}}"#;
    let msg = Scene::from_json(bad).unwrap_err().to_string();
    assert!(msg.contains("colour"), "{msg}");
    let missing = r#"{"robot": {"sections": [{"length_m": 0.1, "ea_n": 1, "elements": 2}]}}"#;
    let msg = Scene::from_json(missing).unwrap_err().to_string();
    assert!(msg.contains("ei_nm2"), "{msg}");
}

#[test]
fn nested_load_tags_parse() {
    let text = r#"{"robot": {"sections": [{"length_m": 0.2, "ea_n": 300, "ei_nm2": 0.02, "elements": 4}]},
        "loads": [{"type": "distributed", "profile": "gaussian", "amplitude_n_per_m": [0, -1], "center_m": 0.1, "width_m": 0.01},
                  {"type": "tip_moment", "moment_nm": 0.01}, {"type": "tip_mass", "mass_kg": 0.02}]}"#;
    let scene = Scene::from_json(text).unwrap();
    let loads = scene.loads().unwrap();
    assert_eq!(loads.line_loads.len(), 1);
    assert_eq!(loads.node_moments[0].node, 4);
    assert!((loads.point_forces[0].force_n[1] + 0.02 * 9.81).abs() < 1e-15);
    let bad = text.replace("\"width_m\"", "\"sigma\"");
    assert!(
        Scene::from_json(&bad)
            .unwrap_err()
            .to_string()
            .contains("sigma")
    );
}

#[test]
fn spatial_scene_defaults_and_vector_moments() {
    let text = r#"{"robot": {"element": "spatial_cable",
        "sections": [{"length_m": 0.24, "ea_n": 300, "ei_nm2": 0.025, "elements": 4}]},
        "loads": [{"type": "tip_moment", "moment_nm": [0, 0.01, 0]},
                  {"type": "tip_mass", "mass_kg": 0.02}]}"#;
    let scene = Scene::from_json(text).unwrap();
    assert_eq!(scene.gravity_m_per_s2, vec![0.0, 0.0, -9.81]);
    assert_eq!(scene.base.position_m, vec![0.0; 3]);
    assert_eq!(scene.base.direction, Some(vec![1.0, 0.0, 0.0]));
    let loads = scene.loads().unwrap();
    assert_eq!(loads.node_moments[0].node, 4);
    assert_eq!(loads.node_moments[0].moment_nm, vec![0.0, 0.01, 0.0]);
    assert!((loads.point_forces[0].force_n[2] + 0.02 * 9.81).abs() < 1e-15);
    assert!(matches!(scene.build().unwrap(), SceneRobot::Spatial(_)));
    // the planar path refuses it, naming the field
    let e = scene.robot().unwrap_err();
    assert_eq!(e.field(), Some("robot.element"));
    // written out and read back: the same scene (defaults made explicit)
    let json = serde_json::to_string(&scene).unwrap();
    assert_eq!(Scene::from_json(&json).unwrap(), scene);
}
