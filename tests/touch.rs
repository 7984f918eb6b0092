//! Touch: the plant among obstacles (never a penetrating shape as
//! converged), the markers' response to a point force against finite
//! differences, the calibration against the plant's known factors, and
//! contact localization against the plant's own contact forces (the plant
//! is not the model: finer mesh, EI +15 %, gain −10 %, EA −5 %, marker
//! noise σ = 0.05 mm).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use nalgebra::Vector2;
use softrod::Error;
use softrod::contact::{ContactSettings, Obstacle, Obstacles};
use softrod::loads::PointForce;
use softrod::plant::{Plant, PlantContact, PlantSettings, SimulatedPlant};
#[cfg(feature = "report")]
use softrod::report::touch::{LocalizationCase, run_localization};
use softrod::statics::StaticSolver;
use softrod::touch::{
    FreeFrame, MarkerResponse, ROD_RADIUS_M, calibrate, five_section_scene, marker_arcs,
};

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
    let mut free =
        SimulatedPlant::new(&scene, marker_arcs(6).as_slice(), PlantSettings::default()).unwrap();
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
    let arcs = arcs.as_slice();
    let mut plant = SimulatedPlant::new(&scene, arcs, PlantSettings::default())
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
    let mut free = SimulatedPlant::new(&scene, arcs, PlantSettings::default()).unwrap();
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
    let arcs = arcs.as_slice();
    let starved = ContactSettings {
        max_iterations: 1,
        max_newton_iterations: 1,
        ..ContactSettings::default()
    };
    // hanging straight, far from the disk: solved without the contact solver
    let mut plant = SimulatedPlant::new(&scene, arcs, PlantSettings::default())
        .unwrap()
        .with_contact(PlantContact::new(disk(), starved).unwrap())
        .unwrap();
    // bending onto the disk, one SQP iteration cannot reach the contact
    // equilibrium: an error with the solver's status, and no shape taken
    plant.command(&bent()).unwrap();
    let mut err = None;
    for _ in 0..10 {
        let before = plant.true_q().to_vec();
        if let Err(e) = plant.advance(0.05) {
            assert_eq!(plant.true_q(), &before[..]);
            err = Some(e);
            break;
        }
    }
    let Some(Error::ContactNotConverged { report }) = err else {
        panic!("{err:?}")
    };
    assert!(!report.status.is_converged(), "{report}");
}

#[test]
fn obstacle_overlapping_the_plant_is_refused_by_field() {
    let scene = five_section_scene(4);
    let plant =
        SimulatedPlant::new(&scene, marker_arcs(6).as_slice(), PlantSettings::default()).unwrap();
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
    let arcs = arcs.as_slice();
    let resp = MarkerResponse::new(&robot, &loads, q.as_slice(), arcs).unwrap();
    let markers = |q: &[f64]| -> Vec<f64> {
        arcs.iter()
            .flat_map(|&s| robot.position_at(q, s).unwrap().data.as_vec().clone())
            .collect()
    };
    let y0 = markers(q.as_slice());
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
                markers(
                    solver
                        .solve(&robot, &l, Some(q.as_slice()))
                        .unwrap()
                        .q
                        .as_slice(),
                )
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
    let arcs = arcs.as_slice();
    let mut plant = SimulatedPlant::new(&scene, arcs, PlantSettings::default()).unwrap();
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
    let c = calibrate(&scene, arcs, &frames).unwrap();
    // the plant: EI x 1.15, gain x 0.90 (and a finer mesh, EA x 0.95, noise)
    assert!((c.ei_factor / 1.15 - 1.0).abs() < 0.03, "{c:?}");
    assert!((c.gain_factor / 0.90 - 1.0).abs() < 0.03, "{c:?}");
    assert!(c.rms_after_m < 0.2 * c.rms_before_m, "{c:?}");
}

#[test]
#[cfg(feature = "report")]
fn point_search_locates_contacts_within_5_mm_with_six_markers() {
    // the last: a weak contact near the tip (8 mN; 16 mm off with 5 frames
    // averaged instead of the default 20)
    for (s, depth, seed) in [
        (0.2, 0.01, 1),
        (0.3, 0.01, 2),
        (0.4, 0.01, 3),
        (0.45, 0.005, 1),
    ] {
        let r = run_localization(
            &LocalizationCase::new(s, depth, 6, seed),
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

#[test]
fn repulsive_gradient_is_the_exact_gradient_of_38_not_the_printed_39() {
    use softrod::touch::{FieldParams, repulsive};
    let p = FieldParams::default();
    let obs = Vector2::new(0.01, -0.02);
    let h = 1e-7;
    for x in [[0.05, 0.0], [0.02, -0.05], [-0.03, 0.01], [0.011, -0.019]] {
        let x = Vector2::from(x);
        let (_, g) = repulsive(&p, x, obs);
        let d = (x[0] - obs[0]).hypot(x[1] - obs[1]);
        for k in 0..2 {
            let (mut a, mut b) = (x, x);
            a[k] += h;
            b[k] -= h;
            let fd = (repulsive(&p, a, obs).0 - repulsive(&p, b, obs).0) / (2.0 * h);
            assert!(
                (fd - g[k]).abs() <= 1e-6 * g[k].abs().max(1e-3),
                "x {x:?} k {k}: {fd} vs {}",
                g[k]
            );
            // the paper's (39): α (1/Q0 − 1/d) (x − x_obs) / d^{3/2}
            let printed = p.alpha_r * (1.0 / p.q0_m - 1.0 / d) * (x[k] - obs[k]) / d.powf(1.5);
            assert!(
                (printed - g[k]).abs() > 0.1 * g[k].abs(),
                "x {x:?}: (39) agrees?"
            );
        }
    }
}

#[test]
fn field_gradient_in_the_shape_matches_finite_differences() {
    use softrod::touch::{FieldParams, field_gradient};
    let scene = five_section_scene(4);
    let (robot, mut loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    loads.pressures_pa = bent();
    let q = StaticSolver::default()
        .solve(&robot, &loads, None)
        .unwrap()
        .q;
    let p = FieldParams::default();
    let goal = Vector2::new(0.15, -0.40);
    // two obstacle points within Q0 of several elements
    let obs = [Vector2::new(0.09, -0.33), Vector2::new(0.02, -0.2)];
    let (_, g) = field_gradient(&robot, q.as_slice(), &p, goal, &obs).unwrap();
    let h = 1e-7;
    let scale = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    assert!(scale > 1.0);
    // every free coordinate (the base node is clamped)
    for i in 4..q.len() {
        let (mut a, mut b) = (q.clone(), q.clone());
        a[i] += h;
        b[i] -= h;
        let fd = (field_gradient(&robot, a.as_slice(), &p, goal, &obs)
            .unwrap()
            .0
            - field_gradient(&robot, b.as_slice(), &p, goal, &obs)
                .unwrap()
                .0)
            / (2.0 * h);
        assert!((fd - g[i]).abs() < 1e-5 * scale, "q[{i}]: {fd} vs {}", g[i]);
    }
}

/// The calibration, the plant among one disk, the avoidance run.
fn avoid(
    center: [f64; 2],
    goal: [f64; 2],
    feedback: bool,
    duration_s: f64,
) -> softrod::Result<softrod::touch::AvoidRun> {
    use softrod::touch::{AvoidSettings, calibrate_on_free_plant, run_avoidance};
    let scene = five_section_scene(4);
    let arcs = marker_arcs(6);
    let arcs = arcs.as_slice();
    let cal = calibrate_on_free_plant(&scene, arcs, &PlantSettings::default())?;
    let obstacles = Obstacles::new(
        vec![Obstacle::Circle {
            center_m: center,
            radius_m: 0.01,
        }],
        ROD_RADIUS_M,
    )?;
    let mut plant =
        SimulatedPlant::new(&scene, arcs, PlantSettings::default())?.with_obstacles(obstacles)?;
    let settings = AvoidSettings {
        duration_s,
        touch_feedback: feedback,
        ..AvoidSettings::default()
    };
    run_avoidance(&scene, &cal, arcs, &mut plant, goal.into(), &settings)
}

#[test]
fn avoidance_by_touch_reaches_the_goal_the_baseline_pushes_into_the_obstacle() {
    let (disk, goal) = ([0.08, -0.465], [0.15, -0.40]);
    let run = avoid(disk, goal, true, 70.0).unwrap();
    println!(
        "touch: {:?}, final {:.2} mm, force before {:.4} N, after {:.4} N, touched {:?}",
        run.status,
        run.final_error_m * 1e3,
        run.max_force_before_n,
        run.max_force_after_n,
        run.touched
    );
    assert!(run.status.is_reached(), "{:?}", run.status);
    assert!(run.final_error_m <= 2e-3);
    // localized near the disk's surface (radius 10 mm)
    let t = &run.touched[0];
    let d = (t.point_m[0] - disk[0]).hypot(t.point_m[1] - disk[1]);
    assert!((d - 0.01).abs() < 5e-3, "{t:?}");
    // the contact force never grows after localization
    assert!(run.max_force_before_n > 0.0);
    assert!(
        run.max_force_after_n <= run.max_force_before_n * 1.05,
        "{run:?}"
    );
    assert!(run.final_force_n <= 1e-9);
    // the baseline meets the disk at about 13 s and pushes on (0.46 N by 70 s)
    let base = avoid(disk, goal, false, 70.0).unwrap();
    println!(
        "baseline: {:?}, final {:.2} mm, force max {:.4} N",
        base.status,
        base.final_error_m * 1e3,
        base.max_force_before_n
    );
    assert!(!base.status.is_reached());
    assert!(base.max_force_before_n > 20.0 * run.max_force_before_n);
    // it stalls: still pressing at the end, the end effector ~107 mm short
    assert!(base.final_force_n > 0.3, "{}", base.final_force_n);
    assert!(base.final_error_m > 0.05, "{}", base.final_error_m);
}

#[test]
fn avoidance_bad_input_is_typed_and_an_unreachable_goal_says_so() {
    use softrod::touch::AvoidStatus;
    // a goal no pressure reaches: a status, not a run
    let run = avoid([0.08, -0.465], [0.0, 0.5], true, 1.0).unwrap();
    assert!(
        matches!(run.status, AvoidStatus::GoalUnreachable { distance_m } if distance_m > 0.5),
        "{:?}",
        run.status
    );
    assert!(run.samples.is_empty());
    let err = avoid([0.08, -0.465], [f64::NAN, 0.0], true, 1.0).unwrap_err();
    assert_eq!(err.field(), Some("goal_m"));
    // obstacles: radius <= 0, NaN, non-convex polygon, overlapping the base
    let bad = [
        (
            Obstacle::Circle {
                center_m: [0.1, 0.0],
                radius_m: 0.0,
            },
            "obstacles[0].radius_m",
        ),
        (
            Obstacle::Capsule {
                start_m: [0.1, f64::NAN],
                end_m: [0.2, 0.0],
                radius_m: 0.01,
            },
            "obstacles[0].start_m",
        ),
        (
            Obstacle::Polygon {
                vertices_m: vec![[0.1, 0.0], [0.2, 0.0], [0.12, 0.02], [0.2, 0.1], [0.1, 0.1]],
            },
            "obstacles[0].vertices_m",
        ),
    ];
    for (o, field) in bad {
        let err = Obstacles::new(vec![o], ROD_RADIUS_M).unwrap_err();
        assert_eq!(err.field(), Some(field), "{err}");
    }
    let base = Obstacles::new(
        vec![Obstacle::Circle {
            center_m: [0.0, 0.005],
            radius_m: 0.01,
        }],
        ROD_RADIUS_M,
    )
    .unwrap();
    let plant = SimulatedPlant::new(
        &five_section_scene(4),
        marker_arcs(6).as_slice(),
        PlantSettings::default(),
    )
    .unwrap();
    let err = plant.with_obstacles(base).unwrap_err();
    assert_eq!(err.field(), Some("obstacles[0]"));
    assert!(err.to_string().contains("base"), "{err}");
}
