//! The one element limit ([`softrod::assembly::MAX_ELEMENTS`]): every entry
//! point refuses a larger mesh up front, with an error naming the field and
//! the limit, instead of a solve or an estimate that runs for minutes (an
//! estimate at 10 000 elements failed its line search after 20 s, one at
//! 150 000 never ended, before the limit was lowered to where the solvers
//! are measured). And the static solver's settings name their fields with
//! the path the user wrote them at, however deeply they are nested.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::time::{Duration, Instant};

use serde_json::json;
use softrod::Error;
use softrod::assembly::{MAX_ELEMENTS, RobotSpec, Section};
use softrod::control::{LoopSettings, MassSettings};
use softrod::estimate::EstimatorSettings;
use softrod::parallel::ParallelSpec;
use softrod::scene::Scene;
use softrod::scene::parallel::ParallelScene;
use softrod::statics::{StaticSettings, StaticSolver};
use softrod::structure::{RodSpec, StructureSpec};

fn scene(elements: [usize; 2]) -> serde_json::Value {
    let section =
        |k: usize| json!({"length_m": 0.12, "ea_n": 300.0, "ei_nm2": 0.025, "elements": k});
    json!({"robot": {"sections": [section(elements[0]), section(elements[1])]}})
}

fn refused(e: Error, field: &str, max: usize) {
    let text = e.to_string();
    match e {
        Error::TooLarge { name, max: m, .. } => {
            assert_eq!((name.as_str(), m), (field, max), "{text}");
            assert!(text.contains(&max.to_string()), "{text}");
        }
        other => panic!("not TooLarge: {other}"),
    }
}

#[test]
fn ten_thousand_elements_are_refused_by_every_entry_point() {
    // a scene (what `softrod solve` and `softrod estimate` read)
    let s: Scene = serde_json::from_value(scene([5000, 5000])).unwrap();
    refused(
        s.validate().unwrap_err(),
        "robot.sections[0].elements",
        MAX_ELEMENTS,
    );
    refused(
        s.robot().unwrap_err(),
        "robot.sections[0].elements",
        MAX_ELEMENTS,
    );
    // a robot specification (the estimator and the solvers take built robots)
    let spec = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 10_000)]);
    refused(
        spec.build_planar().unwrap_err(),
        "robot.sections[0].elements",
        MAX_ELEMENTS,
    );
    // sections that fit alone but not together: the room left
    let s: Scene = serde_json::from_value(scene([1500, 1500])).unwrap();
    refused(
        s.validate().unwrap_err(),
        "robot.sections[1].elements",
        MAX_ELEMENTS - 1500,
    );
}

#[test]
fn the_limit_itself_is_accepted() {
    let s: Scene =
        serde_json::from_value(scene([MAX_ELEMENTS / 2, MAX_ELEMENTS - MAX_ELEMENTS / 2])).unwrap();
    s.validate().unwrap();
    assert_eq!(s.robot().unwrap().n_elements(), MAX_ELEMENTS);
}

/// The 3-D elements (a scene's `spatial_cable` and `ancf3d` robots, a spatial
/// robot specification), a structure, and the parallel robot, in code and as
/// a scene: 10 000 elements are refused before anything of that size is
/// built, naming the field the user wrote and the limit.
#[test]
fn ten_thousand_elements_are_refused_in_3d_structures_and_parallel_robots() {
    let t = Instant::now();
    for element in ["spatial_cable", "ancf3d"] {
        let mut v = scene([5000, 5000]);
        v["robot"]["element"] = json!(element);
        v["base"] =
            json!({"position_m": [0.0, 0.0, 0.0], "angle_rad": 0.0, "direction": [1.0, 0.0, 0.0]});
        v["gravity_m_per_s2"] = json!([0.0, 0.0, -9.81]);
        let s: Scene = serde_json::from_value(v).unwrap();
        refused(
            s.validate().unwrap_err(),
            "robot.sections[0].elements",
            MAX_ELEMENTS,
        );
        refused(
            s.build().unwrap_err(),
            "robot.sections[0].elements",
            MAX_ELEMENTS,
        );
    }
    let spatial = RobotSpec::spatial(vec![Section::uniform(0.24, 300.0, 0.025, 10_000)]);
    refused(
        spatial.build_spatial().unwrap_err(),
        "robot.sections[0].elements",
        MAX_ELEMENTS,
    );
    // a structure: the count over all rods
    let rod = |k: usize| {
        RodSpec::clamped(
            vec![Section::uniform(0.2, 300.0, 0.02, k)],
            nalgebra::Vector2::new(0.0, 0.0),
            nalgebra::Vector2::new(0.0, 1.0),
        )
    };
    let spec = StructureSpec::new(vec![rod(5000), rod(5000)], vec![], vec![]);
    refused(
        spec.build_planar().unwrap_err(),
        "structure.rods[0].sections[0].elements",
        MAX_ELEMENTS,
    );
    // the parallel robot: its own fields (`parallel.…`), not the structure
    // it lays out, and never the legs laid out first (a billion legs)
    let parallel = |f: &dyn Fn(&mut ParallelSpec)| {
        let mut p = ParallelSpec::default();
        f(&mut p);
        p
    };
    let (legs, sections) = (
        ParallelSpec::default().legs,
        ParallelSpec::default().sections_per_leg,
    );
    let p = parallel(&|p| p.elements_per_section = 10_000 / (legs * sections) + 1);
    refused(
        p.validate().unwrap_err(),
        "parallel.elements_per_section",
        MAX_ELEMENTS / (legs * sections),
    );
    refused(
        p.build_full().unwrap_err(),
        "parallel.elements_per_section",
        MAX_ELEMENTS / (legs * sections),
    );
    refused(
        p.build_cable().unwrap_err(),
        "parallel.elements_per_section",
        MAX_ELEMENTS / (legs * sections),
    );
    let p = parallel(&|p| p.legs = 1_000_000_000);
    refused(p.build_full().unwrap_err(), "parallel.legs", MAX_ELEMENTS);
    let p = parallel(&|p| p.sections_per_leg = 10_000);
    refused(
        p.validate().unwrap_err(),
        "parallel.sections_per_leg",
        MAX_ELEMENTS / legs,
    );
    let mut v = json!({"parallel": serde_json::to_value(ParallelSpec::default()).unwrap()});
    v["parallel"]["elements_per_section"] = json!(10_000);
    refused(
        ParallelScene::from_json(&v.to_string()).unwrap_err(),
        "parallel.elements_per_section",
        MAX_ELEMENTS / (legs * sections),
    );
    // refused up front: nothing of 10 000 elements was assembled
    assert!(t.elapsed() < Duration::from_secs(5), "{:?}", t.elapsed());
}

/// The command line: `softrod solve` and `softrod estimate` of a
/// 10 000-element scene end at once with one line naming the field and the
/// limit (no estimate is attempted).
#[cfg(feature = "cli")]
#[test]
fn the_command_line_refuses_ten_thousand_elements_naming_the_limit() {
    let dir = std::env::temp_dir().join(format!("softrod-limits-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("huge.json");
    std::fs::write(&path, scene([5000, 5000]).to_string()).unwrap();
    let markers = dir.join("markers.json");
    std::fs::write(
        &markers,
        json!({"markers": [{"s_m": 0.24, "position_m": [0.2, -0.05]}]}).to_string(),
    )
    .unwrap();
    let path = path.to_string_lossy().into_owned();
    let markers = markers.to_string_lossy().into_owned();
    for args in [
        vec!["solve", &path],
        vec!["estimate", &path, "--markers", &markers],
    ] {
        let t = Instant::now();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_softrod"))
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}: {stderr}");
        assert!(
            stderr.contains("robot.sections[0].elements")
                && stderr.contains(&MAX_ELEMENTS.to_string()),
            "{args:?}: {stderr}"
        );
        assert_eq!(stderr.trim().lines().count(), 1, "{args:?}: {stderr}");
        assert!(
            t.elapsed() < Duration::from_secs(5),
            "{args:?}: {:?}",
            t.elapsed()
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Static settings nested in other settings name their fields with the
/// whole path: a scene's `solver.static.…` and `solver.estimator.statics.…`,
/// the closed loop's `loop.ik.statics.…` and `loop.estimator.statics.…`,
/// the mass estimator's `mass.statics.…`; on their own, the bare field.
#[test]
fn nested_static_settings_name_the_whole_path() {
    let bad = StaticSettings {
        max_iterations: 0,
        ..StaticSettings::default()
    };
    let field = |e: Error| e.field().map(str::to_string);
    let mut l = LoopSettings::default();
    l.ik.statics = bad.clone();
    assert_eq!(
        field(l.validate().unwrap_err()).as_deref(),
        Some("loop.ik.statics.max_iterations")
    );
    let mut l = LoopSettings::default();
    l.estimator.statics.residual_tolerance = 2.0;
    assert_eq!(
        field(l.validate().unwrap_err()).as_deref(),
        Some("loop.estimator.statics.residual_tolerance")
    );
    let m = MassSettings {
        statics: StaticSettings {
            max_step_rotation: f64::NAN,
            ..StaticSettings::default()
        },
        ..MassSettings::default()
    };
    assert_eq!(
        field(m.validate().unwrap_err()).as_deref(),
        Some("mass.statics.max_step_rotation")
    );
    let e = EstimatorSettings {
        statics: StaticSettings {
            max_total_iterations: 1,
            max_iterations: 2,
            ..StaticSettings::default()
        },
        ..EstimatorSettings::default()
    };
    let err = e.validate().unwrap_err();
    assert!(
        err.to_string().contains("estimator.statics.max_iterations"),
        "{err}"
    );
    assert_eq!(
        field(err).as_deref(),
        Some("estimator.statics.max_total_iterations")
    );
    // a scene, as written in its file
    let mut v = scene([4, 4]);
    v["solver"] = json!({"static": {"min_load_step": 0.0}});
    let s: Scene = serde_json::from_value(v.clone()).unwrap();
    assert_eq!(
        field(s.validate().unwrap_err()).as_deref(),
        Some("solver.static.min_load_step")
    );
    v["solver"] = json!({"estimator": {"statics": {"max_iterations": 200_000}}});
    let s: Scene = serde_json::from_value(v).unwrap();
    assert_eq!(
        field(s.validate().unwrap_err()).as_deref(),
        Some("solver.estimator.statics.max_iterations")
    );
    // on their own: the bare field, from the settings and from the solver
    assert_eq!(
        field(bad.validate("").unwrap_err()).as_deref(),
        Some("max_iterations")
    );
    assert_eq!(
        field(StaticSolver::new(bad).unwrap_err()).as_deref(),
        Some("max_iterations")
    );
}
