//! Touch: the plant among obstacles (never a penetrating shape as
//! converged), the markers' response to a point force against finite
//! differences, the calibration against the plant's known factors, and
//! contact localization against the plant's own contact forces (the plant
//! is not the model: finer mesh, EI +15 %, gain −10 %, EA −5 %, marker
//! noise σ = 0.05 mm).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::contact::{ContactSettings, Obstacle, Obstacles};
use softrod::loads::PointForce;
use softrod::plant::{Plant, PlantContact, PlantSettings, SimulatedPlant};
use softrod::statics::StaticSolver;
use softrod::touch::{
    calibrate, five_section_scene, marker_arcs, run_localization, FreeFrame, LocalizationCase,
    MarkerResponse, ROD_RADIUS_M,
};
use softrod::Error;

fn bent() -> Vec<f64> {
    let mut p = vec![0.0; 10];
    p.iter_mut().step_by(2).for_each(|x| *x = 20e3);
    p
}

/// A disk on the inside of the bend at s = 0.3 m, reaching 10 mm into the
/// contact-free shape.
fn disk() -> Obstacles {
    // the plant's contact-free shape at the bend: the point and normal at s = 0.3 m
    let scene = five_section_scene(4);
    let mut free = SimulatedPlant::new(&scene, &marker_arcs(6), PlantSettings::default()).unwrap();
    free.command(&bent()).unwrap();
    for _ in 0..10 {
        free.advance(0.05).unwrap();
    }
    let q = free.true_q().to_vec();
    let r = free.robot().position_at(&q, 0.3).unwrap();
    let mut t = [0.0; 2];
    free.robot()
        .arc_point("s", 0.3)
        .unwrap()
        .slope_into(&q, &mut t)
        .unwrap();
    let tn = t[0].hypot(t[1]);
    let reach = 0.02 + ROD_RADIUS_M - 0.01;
    let c = [r[0] - t[1] / tn * reach, r[1] + t[0] / tn * reach];
    Obstacles::new(
        vec![Obstacle::Circle {
            center_m: c,
            radius_m: 0.02,
        }],
        ROD_RADIUS_M,
    )
    .unwrap()
}

#[test]
fn plant_among_obstacles_touches_without_penetrating() {
    let scene = five_section_scene(4);
    let arcs = marker_arcs(6);
    let mut plant = SimulatedPlant::new(&scene, &arcs, PlantSettings::default())
        .unwrap()
        .with_obstacles(disk())
        .unwrap();
    // straight, hanging: the disk is not touched
    assert!(plant.contact().unwrap().contacts().is_empty());
    plant.command(&bent()).unwrap();
    for _ in 0..10 {
        plant.advance(0.05).unwrap();
    }
    let c = plant.contact().unwrap();
    let report = c.report().unwrap();
    assert!(report.status.is_converged(), "{report}");
    assert!(report.min_gap_m >= -1e-9, "{report}");
    assert_eq!(c.contacts().len(), 1, "{:?}", c.contacts());
    let k = &c.contacts()[0];
    assert!((k.s_m - 0.3).abs() < 0.01 && k.force_n > 0.01, "{k:?}");
    // the contact force holds the plant away from its free shape: without
    // the disk the same pressures bend it further
    let mut free = SimulatedPlant::new(&scene, &arcs, PlantSettings::default()).unwrap();
    free.command(&bent()).unwrap();
    for _ in 0..10 {
        free.advance(0.05).unwrap();
    }
    let (a, b) = (plant.true_tip_m().unwrap(), free.true_tip_m().unwrap());
    assert!((a[0] - b[0]).hypot(a[1] - b[1]) > 5e-3, "{a:?} {b:?}");
}

#[test]
fn plant_contact_that_does_not_converge_is_an_error_not_a_shape() {
    let scene = five_section_scene(4);
    let arcs = marker_arcs(6);
    let starved = ContactSettings {
        max_iterations: 1,
        max_newton_iterations: 1,
        ..ContactSettings::default()
    };
    // one SQP iteration cannot bend the robot onto the disk: refused with
    // the solver's status, no shape taken
    let err = SimulatedPlant::new(&scene, &arcs, PlantSettings::default())
        .unwrap()
        .with_contact(PlantContact::new(disk(), starved).unwrap())
        .unwrap_err();
    let Error::ContactNotConverged { report } = err else {
        panic!("{err}")
    };
    assert!(!report.status.is_converged(), "{report}");
}

#[test]
fn obstacle_overlapping_the_plant_is_refused_by_field() {
    let scene = five_section_scene(4);
    let plant = SimulatedPlant::new(&scene, &marker_arcs(6), PlantSettings::default()).unwrap();
    let on_robot = Obstacles::new(
        vec![
            Obstacle::Circle {
                center_m: [0.3, 0.0],
                radius_m: 0.01,
            },
            Obstacle::Circle {
                center_m: [0.0, -0.2],
                radius_m: 0.01,
            },
        ],
        ROD_RADIUS_M,
    )
    .unwrap();
    let err = plant.with_obstacles(on_robot).unwrap_err();
    assert_eq!(err.field(), Some("obstacles[1]"), "{err}");
}

#[test]
fn marker_response_matches_finite_differences() {
    let scene = five_section_scene(4);
    let (robot, mut loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    loads.pressures_pa = bent();
    let solver = StaticSolver::default();
    let q = solver.solve(&robot, &loads, None).unwrap().q;
    let arcs = marker_arcs(6);
    let resp = MarkerResponse::new(&robot, &loads, &q, &arcs).unwrap();
    let markers = |q: &[f64]| -> Vec<f64> {
        arcs.iter()
            .flat_map(|&s| robot.position_at(q, s).unwrap())
            .collect()
    };
    let y0 = markers(&q);
    let h = 1e-5;
    for s in [0.05, 0.2171, 0.3, 0.465] {
        let g = resp.at(s).unwrap();
        for d in 0..2 {
            let side = |sign: f64| {
                let mut l = loads.clone();
                let mut f = [0.0; 2];
                f[d] = sign * h;
                l.point_forces.push(PointForce {
                    s_m: s,
                    force_n: f.to_vec(),
                });
                markers(&solver.solve(&robot, &l, Some(&q)).unwrap().q)
            };
            let (a, b) = (side(1.0), side(-1.0));
            let scale = g.column(d).amax();
            assert!(scale > 1e-5, "s {s}: {scale}");
            for i in 0..y0.len() {
                let fd = (a[i] - b[i]) / (2.0 * h);
                assert!(
                    (fd - g[(i, d)]).abs() < 1e-6 * scale,
                    "s {s} d {d} row {i}: {fd} vs {}",
                    g[(i, d)]
                );
            }
        }
    }
}

#[test]
fn calibration_recovers_the_plants_stiffness_and_gain() {
    let scene = five_section_scene(4);
    let arcs = marker_arcs(6);
    let mut plant = SimulatedPlant::new(&scene, &arcs, PlantSettings::default()).unwrap();
    let p = bent();
    let mut other = p.clone();
    other.rotate_right(1);
    let mut frames = Vec::new();
    for pr in [p, other] {
        plant.command(&pr).unwrap();
        for _ in 0..10 {
            plant.advance(0.05).unwrap();
        }
        frames.push(FreeFrame {
            pressures_pa: pr,
            markers_m: plant.advance(0.05).unwrap().positions_m,
        });
    }
    let c = calibrate(&scene, &arcs, &frames).unwrap();
    // the plant: EI x 1.15, gain x 0.90 (and a finer mesh, EA x 0.95, noise)
    assert!((c.ei_factor / 1.15 - 1.0).abs() < 0.03, "{c:?}");
    assert!((c.gain_factor / 0.90 - 1.0).abs() < 0.03, "{c:?}");
    assert!(c.rms_after_m < 0.2 * c.rms_before_m, "{c:?}");
}

#[test]
fn point_search_locates_contacts_within_5_mm_with_six_markers() {
    for (s, seed) in [(0.2, 1), (0.3, 2), (0.4, 3)] {
        let r = run_localization(
            &LocalizationCase::new(s, 0.01, 6, seed),
            4,
            &PlantSettings::default(),
        )
        .unwrap();
        let (peak, point) = r.location_errors_m();
        let (_, force) = r.force_errors_n();
        let f = r.true_force_n[0].hypot(r.true_force_n[1]);
        println!(
            "s {s}: true {:.4} m, {f:.4} N; peak error {:.1} mm, point error {:.1} mm, force error {:.1} %",
            r.true_s_m,
            peak * 1e3,
            point * 1e3,
            100.0 * force / f
        );
        assert!(point <= 5e-3, "{r:?}");
        assert!(force <= 0.05 * f, "{r:?}");
    }
}
