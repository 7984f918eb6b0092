//! A load added in code is checked as the same load in a scene file:
//! `Loads::add` and `Scene::validate` both use `Load::validate`, so a bad
//! load is refused by both, naming the same field (the scene's under
//! `loads[i].`) with the same message.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::loads::{FollowerLoad, LineLoad, Load, Loads, MomentNm};
use softrod::scene::Scene;

/// Bad loads for the two-section planar robot (0.24 m, 20 elements) and
/// the field each must be refused for.
fn bad_loads() -> Vec<(Load, &'static str)> {
    vec![
        (Load::TipMass { mass_kg: -0.02 }, "mass_kg"),
        (Load::TipMass { mass_kg: 0.0 }, "mass_kg"),
        (
            Load::TipForce {
                force_n: vec![0.0, -0.1, 0.0],
            },
            "force_n",
        ),
        (
            Load::TipForce {
                force_n: vec![f64::NAN, 0.0],
            },
            "force_n[0]",
        ),
        (
            Load::PointForce {
                s_m: 0.5,
                force_n: vec![0.0, -0.1],
            },
            "s_m",
        ),
        (
            Load::NodeMoment {
                node: 0,
                moment_nm: MomentNm::Scalar(0.01),
            },
            "node",
        ),
        (
            Load::NodeMoment {
                node: 10_000,
                moment_nm: MomentNm::Scalar(0.01),
            },
            "node",
        ),
        (
            Load::Moment {
                s_m: 0.0,
                moment_nm: MomentNm::Scalar(0.01),
            },
            "s_m",
        ),
        (
            Load::TipMoment {
                moment_nm: MomentNm::Vector(vec![0.0, 0.0, 0.01]),
            },
            "moment_nm",
        ),
        (
            Load::SelfWeight {
                mass_per_length_kg_per_m: -0.1,
                gravity_m_per_s2: vec![0.0, -9.81],
            },
            "mass_per_length_kg_per_m",
        ),
        (
            Load::SelfWeight {
                mass_per_length_kg_per_m: 0.1,
                gravity_m_per_s2: vec![-9.81],
            },
            "gravity_m_per_s2",
        ),
        (
            Load::Distributed(LineLoad::Gaussian {
                amplitude_n_per_m: vec![0.0, -1.0],
                center_m: 0.5,
                width_m: 0.01,
            }),
            "center_m",
        ),
        (
            Load::Distributed(LineLoad::Tabulated {
                s_m: vec![0.1, 0.3],
                w_n_per_m: vec![vec![0.0, -1.0]; 2],
            }),
            "s_m[1]",
        ),
        (
            Load::Follower(FollowerLoad {
                pressure_n_per_m: -1.0,
                s_start_m: Some(0.1),
                s_end_m: Some(0.5),
            }),
            "s_end_m",
        ),
    ]
}

#[test]
fn a_bad_load_in_code_is_refused_as_in_a_scene() {
    let base = Scene::two_section();
    let robot = base.robot().unwrap();
    for (load, field) in bad_loads() {
        // in code
        let mut loads = Loads {
            pressures_pa: vec![0.0; robot.n_pressures()],
            ..Loads::default()
        };
        let code = loads.add(&robot, &load).unwrap_err();
        assert_eq!(code.field(), Some(field), "{load:?}: {code}");
        assert_eq!(
            loads,
            Loads {
                pressures_pa: vec![0.0; robot.n_pressures()],
                ..Loads::default()
            },
            "{load:?}: a refused load must not be added"
        );
        // the same load as the scene's second load, after a good one
        let mut scene = base.clone();
        scene.loads = vec![Load::TipMass { mass_kg: 0.01 }, load.clone()];
        let in_scene = scene.validate().unwrap_err();
        let scene_field = format!("loads[1].{field}");
        assert_eq!(
            in_scene.field(),
            Some(scene_field.as_str()),
            "{load:?}: {in_scene}"
        );
        // the same message, the scene's under its path
        assert_eq!(
            in_scene.to_string(),
            code.to_string()
                .replacen(&format!("`{field}`"), &format!("`{scene_field}`"), 1),
            "{load:?}"
        );
        // and the same check by name
        let direct = load.validate(&robot, "loads[1]").unwrap_err();
        assert_eq!(direct.to_string(), in_scene.to_string());
    }
}

#[test]
fn a_good_load_passes_both() {
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let mut loads = scene.loads().unwrap();
    for load in &scene.loads {
        load.validate(&robot, "loads[0]").unwrap();
        loads.add(&robot, load).unwrap();
    }
    robot.validate_loads(&loads).unwrap();
}
