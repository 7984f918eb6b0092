//! Parallel-robot scenes: the example files solve and estimate, and bad
//! input gives typed errors naming the field (a leg joined off the
//! platform, legs of zero length, a platform with no mass and no legs,
//! wrong pressure counts).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::scene::parallel::ParallelScene;

fn example(name: &str) -> String {
    std::fs::read_to_string(format!("{}/examples/{name}", env!("CARGO_MANIFEST_DIR"))).unwrap()
}

fn with(edit: impl Fn(&mut serde_json::Value)) -> softrod::Error {
    let mut v: serde_json::Value = serde_json::from_str(&example("parallel_robot.json")).unwrap();
    edit(&mut v);
    ParallelScene::from_json(&v.to_string()).unwrap_err()
}

#[test]
fn example_scenes_solve_and_estimate() {
    let robot = ParallelScene::from_json(&example("parallel_robot.json")).unwrap();
    let s = robot.solve().unwrap();
    assert_eq!((s.legs_m.len(), s.legs_m[0].len()), (3, 9));
    // the legs end on the platform: its centre is 40 mm from each leg's end
    for leg in &s.legs_m {
        let e = leg.last().unwrap();
        let d = ((e[0] - s.platform_pose[0]).powi(2)
            + (e[1] - s.platform_pose[1]).powi(2)
            + (e[2] - s.platform_pose[2]).powi(2))
        .sqrt();
        assert!((d - 0.04).abs() < 1e-12, "{d}");
    }
    // the twist scene: spatial-cable legs turn by the closed form's inclined-leg value
    let twist = ParallelScene::from_json(&example("parallel_twist.json"))
        .unwrap()
        .solve()
        .unwrap();
    assert!(twist.platform_pose[5] > 3.5e-3 && twist.platform_pose[5] < 4.0e-3);
    // the markers of a plant with a 150 g payload: within 5 g
    let est = ParallelScene::from_json(&example("parallel_estimate.json")).unwrap();
    let m: serde_json::Value = serde_json::from_str(&example("parallel_markers.json")).unwrap();
    let v3 = |k: &str| {
        let a = m[k].as_array().unwrap();
        [0, 1, 2].map(|i| a[i].as_f64().unwrap())
    };
    let e = est.estimate(v3("unloaded_m"), v3("loaded_m")).unwrap();
    println!(
        "estimated payload {:.2} g (150 g hung from the plant)",
        e.mass_kg * 1e3
    );
    assert!((e.mass_kg - 0.15).abs() < 0.005);
}

#[test]
fn bad_input_is_refused_with_the_field() {
    // a leg joined off the platform
    let e = with(|v| v["parallel"]["platform_radius_m"] = 0.07.into());
    assert_eq!(e.field(), Some("parallel.platform_radius_m"), "{e}");
    // legs of zero length
    let e = with(|v| v["parallel"]["leg_length_m"] = 0.0.into());
    assert_eq!(e.field(), Some("parallel.leg_length_m"), "{e}");
    // legs too short to reach the platform
    let e = with(|v| v["parallel"]["leg_length_m"] = 0.01.into());
    assert_eq!(e.field(), Some("parallel.leg_length_m"), "{e}");
    // a platform with no mass and no legs
    let e = with(|v| {
        v["parallel"]["legs"] = 0.into();
        v["parallel"]["platform_mass_kg"] = 0.0.into();
        v["pressures_pa"] = serde_json::json!([]);
    });
    assert_eq!(e.field(), Some("parallel.legs"), "{e}");
    assert!(e.to_string().contains("no mass and no legs"), "{e}");
    // pressures of the wrong count, a platform force of 2 numbers
    let e = with(|v| v["pressures_pa"] = serde_json::json!([1.0, 2.0]));
    assert_eq!(e.field(), Some("pressures_pa"), "{e}");
    let e = with(|v| v["platform_force_n"] = serde_json::json!([0.0, 1.0]));
    assert_eq!(e.field(), Some("platform_force_n"), "{e}");
    // unknown fields name their path
    let e = with(|v| v["parallel"]["leg_lenght_m"] = 0.1.into());
    assert!(e.to_string().contains("leg_lenght_m"), "{e}");
}

/// `"element": "ancf3d"` in a scene: one leg twisted by a tip moment about
/// its axis turns by `T L / GJ` (GJ = EI/1.5), within 1e-6 relative; a
/// singular section frame in the rest configuration (a zero direction) is
/// refused naming `base.direction`.
#[test]
fn ancf3d_scene_twists_by_tl_over_gj_and_refuses_a_singular_frame() {
    use softrod::element::{Ancf3d, NodeKinematics};
    use softrod::scene::{Scene, SceneRobot};
    use softrod::statics::StaticSolver;
    let scene = Scene::from_json(&example("parallel_leg_ancf3d.json")).unwrap();
    let SceneRobot::Full(robot) = scene.build().unwrap() else {
        panic!("an ancf3d scene builds full 3-D elements");
    };
    let eq = StaticSolver::default()
        .solve(&robot, &scene.loads().unwrap(), None)
        .unwrap();
    let tip = &eq.q.as_slice()[eq.q.len() - 12..];
    let phi = Ancf3d::node_rotation(robot.base_node(), tip);
    let closed = 1e-3 * 0.12 / (0.025 / 1.5);
    let rel = (phi[2].abs() / closed - 1.0).abs();
    println!(
        "ancf3d scene twist {:.9e} rad, T L/GJ {closed:.9e}, rel {rel:.1e}",
        phi[2]
    );
    assert!(rel < 1e-6);
    let mut v: serde_json::Value =
        serde_json::from_str(&example("parallel_leg_ancf3d.json")).unwrap();
    v["base"]["direction"] = serde_json::json!([0.0, 0.0, 0.0]);
    let e = Scene::from_json(&v.to_string())
        .and_then(|s| s.build().map(|_| ()))
        .unwrap_err();
    assert_eq!(e.field(), Some("base.direction"), "{e}");
}
