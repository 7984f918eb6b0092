//! Finite but absurd values (issue 33, "Finite absurd values accepted"):
//! each used to run to exit 0 with NaN or nonsense; each is now refused up
//! front, naming the field as written, and the largest accepted value runs
//! without a NaN.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use serde_json::Value;
use softrod::control::{TrackFile, check_track, run_track};
use softrod::scene::Scene;

const EXAMPLES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");

fn example(name: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(format!("{EXAMPLES}/{name}")).unwrap()).unwrap()
}

/// `examples/trajectory_circle.json`, shortened to 1 s (0.5 s hold), with `patch` applied.
fn trajectory(patch: impl Fn(&mut Value)) -> TrackFile {
    let mut t = example("trajectory_circle.json");
    t["trajectory"]["duration_s"] = 1.0.into();
    t["trajectory"]["hold_s"] = 0.5.into();
    patch(&mut t);
    TrackFile::from_json(&t.to_string()).unwrap()
}

fn track_scene() -> Scene {
    Scene::from_json(&example("track_scene.json").to_string()).unwrap()
}

/// No NaN anywhere in a run's JSON (serde writes NaN as `null`; the
/// optional fields that are legitimately `null` are the summary's).
fn assert_finite_run(run: &softrod::control::TrackRun) {
    let v = serde_json::to_value(run).unwrap();
    for (i, s) in v["samples"].as_array().unwrap().iter().enumerate() {
        for key in [
            "estimated_load_n",
            "estimator_load_n",
            "measured_m",
            "pressures_pa",
        ] {
            for x in s[key].as_array().unwrap() {
                assert!(
                    x.as_f64().is_some_and(f64::is_finite),
                    "sample {i}: {key} = {s}"
                );
            }
        }
    }
}

#[test]
fn updater_gains_beyond_their_range_are_refused_and_the_largest_runs_finite() {
    let scene = track_scene();
    // before: k_p = 1e308 ran to exit 0 with NaN loads in every sample
    for (field, v) in [
        ("k_p_per_s", 1e308),
        ("k_p_per_s", 1.1e4),
        ("k_i_per_s2", 1e9),
    ] {
        let file = trajectory(|t| t["loop"]["gains"][field] = v.into());
        let e = check_track(&scene, &file, None).unwrap_err();
        assert_eq!(
            e.field(),
            Some(format!("loop.gains.{field}").as_str()),
            "{e}"
        );
    }
    let file = trajectory(|t| {
        t["loop"]["gains"]["k_p_per_s"] = softrod::control::MAX_K_P_PER_S.into();
        t["loop"]["gains"]["k_i_per_s2"] = softrod::control::MAX_K_I_PER_S2.into();
    });
    assert_finite_run(&run_track(&scene, &file, None, None).unwrap());
}

#[test]
fn ik_weights_outside_their_range_are_refused_and_their_bounds_accepted() {
    let scene = track_scene();
    // the documented range of both is [0, 1e6] (`IkSettings`)
    for field in ["pressure_weight", "null_space_damping"] {
        for v in [-1e-300, -1.0, 1.000_001e6, 1e308] {
            let file = trajectory(|t| t["loop"]["ik"] = serde_json::json!({ field: v }));
            let e = check_track(&scene, &file, None).unwrap_err();
            assert_eq!(
                e.field(),
                Some(format!("loop.ik.{field}").as_str()),
                "{field} = {v}: {e}"
            );
        }
        for v in [0.0, 1e6] {
            let file = trajectory(|t| t["loop"]["ik"] = serde_json::json!({ field: v }));
            assert!(
                check_track(&scene, &file, None).is_ok(),
                "{field} = {v} refused"
            );
        }
    }
}

#[test]
fn plant_noise_and_factors_beyond_their_range_are_refused_naming_the_trajectory_field() {
    let scene = track_scene();
    // before: noise 1e308 ran to exit 0 with markers read at 1e307 m;
    // ea_factor 1e308 was refused as the scene's `robot.sections[0].ea_n`
    for (field, v) in [
        ("noise_sigma_m", 1e308),
        ("noise_sigma_m", 2e-3),
        ("ea_factor", 1e308),
        ("ei_factor", 1e-300),
        ("gain_factor", 1e9),
        ("regulator_time_constant_s", 1e9),
    ] {
        let file = trajectory(|t| t["plant"][field] = v.into());
        let e = check_track(&scene, &file, None).unwrap_err();
        assert_eq!(e.field(), Some(format!("plant.{field}").as_str()), "{e}");
    }
    let file = trajectory(|t| {
        t["plant"]["noise_sigma_m"] = softrod::plant::MAX_NOISE_SIGMA_M.into();
    });
    assert_finite_run(&run_track(&scene, &file, None, None).unwrap());
}

#[test]
fn a_base_angle_beyond_one_turn_is_refused_and_angles_are_reduced_before_use() {
    use softrod::scene::ranges::MAX_BASE_ANGLE_RAD;
    let base = example("two_section.json");
    let with_angle = |a: f64| {
        let mut v = base.clone();
        v["base"] = serde_json::json!({"position_m": [0.0, 0.0], "angle_rad": a});
        Scene::from_json(&v.to_string())
    };
    // before: 1e308 gave a "converged" shape with its 20 nodes behind the clamp
    for a in [1e308, -1e9, MAX_BASE_ANGLE_RAD * 1.0001] {
        let e = with_angle(a).unwrap_err();
        assert_eq!(e.field(), Some("base.angle_rad"), "{e}");
    }
    // an angle and its equivalent one turn away solve to the same shape
    let tip = |a: f64| {
        let scene = with_angle(a).unwrap();
        let robot = scene.robot().unwrap();
        let eq = softrod::statics::StaticSolver::default()
            .solve(&robot, &scene.loads().unwrap(), None)
            .unwrap();
        let n = eq.q.len();
        [eq.q[n - 4], eq.q[n - 3]]
    };
    let (a, b) = (tip(-4.0), tip(-4.0 + std::f64::consts::TAU));
    assert!(
        (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12,
        "{a:?} {b:?}"
    );
    let (a, b) = (tip(6.0), tip(6.0 - std::f64::consts::TAU));
    assert!(
        (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12,
        "{a:?} {b:?}"
    );
}

#[test]
fn positions_gravity_and_pressures_beyond_their_range_are_refused() {
    let base = example("two_section.json");
    for (path, v) in [
        (vec!["base", "position_m", "0"], 1e9),
        (vec!["gravity_m_per_s2", "1"], -1e9),
        (
            vec!["robot", "sections", "0", "chambers", "0", "pressure_max_pa"],
            1e9,
        ),
        (
            vec!["robot", "sections", "1", "chambers", "1", "pressure_min_pa"],
            -1e308,
        ),
        (vec!["pressures_pa", "2"], -1e9),
    ] {
        let mut doc = base.clone();
        if path[0] == "base" {
            doc["base"] = serde_json::json!({"position_m": [0.0, 0.0], "angle_rad": 0.0});
        }
        let mut cur = &mut doc;
        for p in &path {
            cur = match p.parse::<usize>() {
                Ok(i) => &mut cur[i],
                Err(_) => &mut cur[*p],
            };
        }
        *cur = v.into();
        let want = path
            .iter()
            .fold(String::new(), |acc, p| match p.parse::<usize>() {
                Ok(i) => format!("{acc}[{i}]"),
                Err(_) if acc.is_empty() => p.to_string(),
                Err(_) => format!("{acc}.{p}"),
            });
        let e = Scene::from_json(&doc.to_string()).unwrap_err();
        assert_eq!(e.field(), Some(want.as_str()), "{e}");
    }
}

#[test]
fn friction_outside_its_range_is_refused() {
    use softrod::grasp::scene::GraspScene;
    // before: a grasp with mu = 0 could end in `invalid parameter hold_check = InsufficientProgress`
    for mu in [0.0, 1e-3, 11.0, 1e308] {
        let mut g = example("grasp_apple.json");
        g["object"]["mu"] = mu.into();
        let e = GraspScene::from_json(&g.to_string()).unwrap_err();
        assert_eq!(e.field(), Some("object.mu"), "{e}");
    }
}

/// Bounded work (issue 33, "Unbounded work"): the runs that were accepted
/// for hours are refused up front, naming the field.
#[test]
fn runs_beyond_their_step_budget_are_refused_naming_the_field() {
    use softrod::control::parallel::TrackSettings;
    use softrod::touch::AvoidScene;
    let scene = track_scene();
    // `track`: 3600 s at 10 kHz (3.6e7 steps) was accepted
    let file = trajectory(|t| {
        t["trajectory"]["duration_s"] = 3590.0.into();
        t["trajectory"]["hold_s"] = 10.0.into();
        t["loop"]["control_rate_hz"] = 1e4.into();
    });
    let e = check_track(&scene, &file, None).unwrap_err();
    assert_eq!(e.field(), Some("loop.control_rate_hz"), "{e}");
    // the same hour at the default 30 Hz is within the budget
    let file = trajectory(|t| {
        t["trajectory"]["duration_s"] = 3590.0.into();
        t["trajectory"]["hold_s"] = 10.0.into();
    });
    assert!(check_track(&scene, &file, None).is_ok());
    // `avoid`: 1e6 steps (about 65 min) was accepted
    let mut a = example("avoid_disk.json");
    a["avoid"] = serde_json::json!({"duration_s": 5e4, "control_rate_hz": 20.0});
    let e = AvoidScene::from_json(&a.to_string()).unwrap_err();
    assert_eq!(e.field(), Some("avoid.duration_s"), "{e}");
    // parallel `track`: 600 s at 1 kHz (6e5 steps, about 4 h) was accepted
    let mut p = example("parallel_track_settings.json");
    p["duration_s"] = 590.0.into();
    p["hold_s"] = 10.0.into();
    p["control_rate_hz"] = 1000.0.into();
    let e = TrackSettings::from_json(&p.to_string()).unwrap_err();
    assert_eq!(e.field(), Some("control_rate_hz"), "{e}");
    // markers: beyond MAX_MARKERS, and beyond the markers × elements budget
    let base = example("two_section.json");
    let markers = |n: usize| {
        (0..n)
            .map(|i| serde_json::json!({"s_m": 0.24 * (i + 1) as f64 / n as f64}))
            .collect::<Vec<_>>()
    };
    let mut v = base.clone();
    v["markers"] = markers(softrod::scene::ranges::MAX_MARKERS + 1).into();
    let e = Scene::from_json(&v.to_string()).unwrap_err();
    assert!(e.field().is_some_and(|f| f.starts_with("markers")), "{e}");
    let mut v = base.clone();
    v["robot"]["sections"][0]["elements"] = 1000.into();
    v["markers"] = markers(30).into();
    let e = Scene::from_json(&v.to_string()).unwrap_err();
    assert!(e.field().is_some_and(|f| f.starts_with("markers")), "{e}");
    assert!(matches!(e, softrod::Error::TooLarge { .. }), "{e}");
    // the estimator's iterations: 1e18 was accepted (each a static solve)
    let mut v = base.clone();
    v["solver"]["estimator"] = serde_json::json!({"max_iterations": 1_000_000_000_000_000_000u64});
    let e = Scene::from_json(&v.to_string()).unwrap_err();
    assert_eq!(e.field(), Some("solver.estimator.max_iterations"), "{e}");
    let mut v = base.clone();
    v["solver"]["estimator"] =
        serde_json::json!({"max_iterations": softrod::estimate::MAX_ESTIMATOR_ITERATIONS});
    assert!(Scene::from_json(&v.to_string()).is_ok());
}
