//! `softrod avoid` on bad scene files: one line on stderr naming the field
//! the user wrote and a non-zero exit; a goal outside the workspace exits
//! non-zero with a status that says so, without running.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::process::Command;

fn avoid(name: &str, scene: &str) -> (i32, String) {
    let path = std::env::temp_dir().join(format!("softrod-avoid-{}-{name}", std::process::id()));
    std::fs::write(&path, scene).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_softrod"))
        .arg("avoid")
        .arg(&path)
        .output()
        .unwrap();
    std::fs::remove_file(&path).ok();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_avoidance_scenes_name_the_field_and_an_unreachable_goal_says_so() {
    let cases = [
        (
            "negative radius",
            r#"{"obstacles": [{"shape": "circle", "center_m": [0.08, -0.465], "radius_m": -0.01}], "goal_m": [0.15, -0.4]}"#,
            "obstacles[0].radius_m",
        ),
        (
            "non-convex polygon",
            r#"{"obstacles": [{"shape": "polygon", "vertices_m": [[0.1, -0.3], [0.2, -0.3], [0.12, -0.28], [0.2, -0.2], [0.1, -0.2]]}], "goal_m": [0.15, -0.4]}"#,
            "obstacles[0].vertices_m",
        ),
        (
            "overlapping the robot",
            r#"{"obstacles": [{"shape": "circle", "center_m": [0.0, -0.2], "radius_m": 0.01}], "goal_m": [0.15, -0.4]}"#,
            "obstacles[0]",
        ),
        (
            "goal outside the workspace",
            r#"{"obstacles": [{"shape": "circle", "center_m": [0.08, -0.465], "radius_m": 0.01}], "goal_m": [0.0, 0.5]}"#,
            "goal unreachable",
        ),
    ];
    for (what, scene, expect) in cases {
        let (code, stderr) = avoid(&what.replace(' ', "_"), scene);
        assert_ne!(code, 0, "{what}: {stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{what}: {stderr}");
        assert!(stderr.contains(expect), "{what}: {stderr}");
        assert!(!stderr.contains("panicked"), "{what}: {stderr}");
    }
}
