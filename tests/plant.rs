//! The simulated plant is not the controller's model: every difference the
//! plant promises is checked here, and its payload schedule and regulator
//! lag against closed forms.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::plant::{Payload, PayloadKind, PayloadSchedule, Plant, PlantSettings, SimulatedPlant};
use softrod::scene::Scene;

fn marker_arcs(scene: &Scene) -> Vec<f64> {
    let robot = scene.robot().unwrap();
    scene
        .markers
        .iter()
        .map(|m| robot.node_arc()[m.node.unwrap()])
        .collect()
}

#[test]
fn plant_differs_from_the_controller_model_in_every_respect() {
    let scene = Scene::two_section();
    let model = scene.robot().unwrap();
    let settings = PlantSettings {
        payloads: PayloadSchedule::tip_mass(0.02, model.length()),
        ..PlantSettings::default()
    };
    let mut plant = SimulatedPlant::new(&scene, &marker_arcs(&scene), settings).unwrap();
    let ps = plant.scene().clone();
    // finer mesh: at least twice the controller's in every section
    for (a, b) in ps.robot.sections.iter().zip(&scene.robot.sections) {
        assert!(
            a.elements >= 2 * b.elements,
            "{} vs {}",
            a.elements,
            b.elements
        );
        // parameter errors: EI +15 %, EA -5 %, actuation gain -10 %
        assert!((a.ei_nm2 / b.ei_nm2 - 1.15).abs() < 1e-12);
        assert!((a.ea_n / b.ea_n - 0.95).abs() < 1e-12);
        for (ca, cb) in a.chambers.iter().zip(&b.chambers) {
            for (ga, gb) in ca.gain_nm_per_pa.iter().zip(&cb.gain_nm_per_pa) {
                assert!((ga / gb - 0.90).abs() < 1e-12);
            }
        }
    }
    assert!(plant.robot().n_elements() >= 2 * model.n_elements());
    // a payload the controller is not told about
    assert!(plant.settings().payloads.mass_at(0.0, model.length()) > 0.0);
    assert!(scene.loads.is_empty());
    // marker noise: the frame is not the truth, and differs frame to frame
    let f1 = plant.advance(0.01).unwrap();
    let truth = plant.true_markers_m().unwrap();
    let dev: Vec<f64> = f1
        .positions_m
        .iter()
        .flatten()
        .zip(truth.iter().flatten())
        .map(|(a, b)| a - b)
        .collect();
    assert!(
        dev.iter().all(|d| *d != 0.0 && d.abs() < 5.0 * 5e-5),
        "{dev:?}"
    );
    let f2 = plant.advance(0.01).unwrap();
    assert_ne!(f1.positions_m, f2.positions_m);
    // the regulator lags: after a step of the command, the pressure is behind
    plant.command(&[0.0, 50e3, 0.0, 0.0]).unwrap();
    plant.advance(0.02).unwrap();
    let p = plant.actual_pressures_pa().to_vec();
    let scene_p = &scene.pressures_pa;
    let decay = (-1.0f64).exp(); // dt / tau = 0.02 / 0.02
    for c in 0..4 {
        let cmd = [0.0, 50e3, 0.0, 0.0][c];
        let expected = cmd + (scene_p[c] - cmd) * decay;
        assert!(
            (p[c] - expected).abs() < 1e-9 * 1e5,
            "chamber {c}: {} vs {expected}",
            p[c]
        );
    }
    // quasi-static equilibrium of the plant's own model differs from the
    // controller's at the same pressures
    let ctrl_tip = softrod::statics::StaticSolver::default()
        .solve(&model, &scene.loads().unwrap(), None)
        .unwrap()
        .q;
    let ctrl_tip = model
        .position_at(ctrl_tip.as_slice(), model.length())
        .unwrap();
    let plant0 =
        SimulatedPlant::new(&scene, &marker_arcs(&scene), PlantSettings::default()).unwrap();
    let plant_tip = plant0.true_tip_m().unwrap();
    let d = ((ctrl_tip[0] - plant_tip[0]).powi(2) + (ctrl_tip[1] - plant_tip[1]).powi(2)).sqrt();
    assert!(d > 1e-3, "plant and model tips differ by only {d} m");
}

#[test]
fn identical_settings_reproduce_the_model_only_when_every_difference_is_removed() {
    // with every difference switched off the plant is the model on a finer
    // mesh: tips agree to the discretization error (a check that the
    // differences above are the plant's doing, not an artefact)
    let scene = Scene::two_section();
    let model = scene.robot().unwrap();
    let same = PlantSettings {
        ei_factor: 1.0,
        gain_factor: 1.0,
        ea_factor: 1.0,
        noise_sigma_m: 0.0,
        regulator_time_constant_s: 0.0,
        ..PlantSettings::default()
    };
    let plant = SimulatedPlant::new(&scene, &marker_arcs(&scene), same).unwrap();
    let q = softrod::statics::StaticSolver::default()
        .solve(&model, &scene.loads().unwrap(), None)
        .unwrap()
        .q;
    let tip = model.position_at(q.as_slice(), model.length()).unwrap();
    let pt = plant.true_tip_m().unwrap();
    assert!(
        (tip[0] - pt[0]).abs() < 1e-5 && (tip[1] - pt[1]).abs() < 1e-5,
        "{tip:?} vs {pt:?}"
    );
}

#[test]
fn payload_schedule_in_time() {
    let g = [0.0, -9.81];
    let base = softrod::loads::Loads::default();
    let s = PayloadSchedule {
        payloads: vec![
            Payload {
                kind: PayloadKind::PointMass {
                    mass_kg: 0.01,
                    s_m: 0.24,
                },
                start_s: 0.0,
                end_s: None,
            },
            Payload {
                kind: PayloadKind::Distributed {
                    mass_per_length_kg_per_m: 0.05,
                },
                start_s: 1.0,
                end_s: Some(2.0),
            },
            Payload {
                kind: PayloadKind::Sliding {
                    mass_kg: 0.02,
                    from_s_m: 0.1,
                    to_s_m: 0.2,
                    speed_m_per_s: 0.05,
                },
                start_s: 0.5,
                end_s: None,
            },
        ],
    };
    s.validate(0.24).unwrap();
    // mixed: the distributed mass acts only in [1, 2)
    assert!((s.mass_at(0.2, 0.24) - 0.01).abs() < 1e-15);
    assert!((s.mass_at(1.5, 0.24) - (0.01 + 0.05 * 0.24 + 0.02)).abs() < 1e-15);
    assert!((s.mass_at(2.0, 0.24) - 0.03).abs() < 1e-15);
    // sliding: at 0.05 m/s from 0.1 m, 1 s after its start it is at 0.15 m; it stops at 0.2 m
    let l = s.loads_at(1.5, &g, &base);
    let slide = l
        .point_forces
        .iter()
        .find(|p| (p.force_n[1] + 0.02 * 9.81).abs() < 1e-15)
        .unwrap();
    assert!((slide.s_m - 0.15).abs() < 1e-12);
    let l = s.loads_at(10.0, &g, &base);
    let slide = l
        .point_forces
        .iter()
        .find(|p| (p.force_n[1] + 0.02 * 9.81).abs() < 1e-15)
        .unwrap();
    assert!((slide.s_m - 0.2).abs() < 1e-12);
}

#[test]
fn bad_payloads_and_commands_name_the_field() {
    let scene = Scene::two_section();
    let arcs = marker_arcs(&scene);
    let bad = |kind: PayloadKind, start_s: f64, end_s: Option<f64>| {
        let settings = PlantSettings {
            payloads: PayloadSchedule {
                payloads: vec![Payload {
                    kind,
                    start_s,
                    end_s,
                }],
            },
            ..PlantSettings::default()
        };
        SimulatedPlant::new(&scene, &arcs, settings)
            .unwrap_err()
            .field()
            .map(str::to_owned)
    };
    let pm = |m: f64| PayloadKind::PointMass {
        mass_kg: m,
        s_m: 0.2,
    };
    assert_eq!(
        bad(pm(-0.01), 0.0, None).as_deref(),
        Some("plant.payloads[0].mass_kg")
    );
    assert_eq!(
        bad(pm(f64::NAN), 0.0, None).as_deref(),
        Some("plant.payloads[0].mass_kg")
    );
    assert_eq!(
        bad(pm(0.01), 2.0, Some(1.0)).as_deref(),
        Some("plant.payloads[0].end_s")
    );
    assert_eq!(
        bad(pm(0.01), -1.0, None).as_deref(),
        Some("plant.payloads[0].start_s")
    );
    assert_eq!(
        bad(
            PayloadKind::PointMass {
                mass_kg: 0.01,
                s_m: 0.5
            },
            0.0,
            None
        )
        .as_deref(),
        Some("plant.payloads[0].s_m")
    );
    assert_eq!(
        bad(
            PayloadKind::Sliding {
                mass_kg: 0.01,
                from_s_m: 0.1,
                to_s_m: 0.2,
                speed_m_per_s: 0.0
            },
            0.0,
            None
        )
        .as_deref(),
        Some("plant.payloads[0].speed_m_per_s")
    );
    let mut plant = SimulatedPlant::new(&scene, &arcs, PlantSettings::default()).unwrap();
    let e = plant.command(&[0.0, 2e5, 0.0, 0.0]).unwrap_err();
    assert_eq!(e.field(), Some("pressures_pa[1]"));
    let e = plant.command(&[0.0, f64::NAN, 0.0, 0.0]).unwrap_err();
    assert!(e.field().unwrap().starts_with("pressures_pa"));
    assert_eq!(plant.advance(0.0).unwrap_err().field(), Some("dt_s"));
    assert_eq!(plant.advance(-1.0).unwrap_err().field(), Some("dt_s"));
    let e = SimulatedPlant::new(
        &scene,
        &arcs,
        PlantSettings {
            mesh_factor: 0,
            ..Default::default()
        },
    )
    .unwrap_err();
    assert_eq!(e.field(), Some("plant.mesh_factor"));
    let e = SimulatedPlant::new(&scene, &[0.3], PlantSettings::default()).unwrap_err();
    assert_eq!(e.field(), Some("markers[0].s_m"));
}
