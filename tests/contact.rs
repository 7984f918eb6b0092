//! Contact against references not computed with softrod: the propped
//! cantilever's closed form and the elastica on a point obstacle by
//! shooting, exudyn's penalty contact (validation/contact_*.py write
//! reference/contact_*.json).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use common::reference;
use softrod::assembly::{RobotSpec, Section};
use softrod::contact::{ContactSolution, ContactSolver, Obstacle, Obstacles};
use softrod::element::PlanarCable;
use softrod::loads::{Loads, PointForce};

fn robot(p: &serde_json::Value, elements: usize) -> softrod::assembly::Robot<PlanarCable> {
    let f = |k: &str| p[k].as_f64().unwrap();
    let mut spec = RobotSpec::new(vec![Section::uniform(
        f("length_m"),
        f("ea_n"),
        f("ei_nm2"),
        elements,
    )]);
    spec.gravity_m_per_s2 = vec![0.0, 0.0];
    spec.build_planar().unwrap()
}

fn tip_load(l: f64, force: [f64; 2]) -> Loads {
    Loads {
        point_forces: vec![PointForce {
            s_m: l,
            force_n: force.to_vec(),
        }],
        ..Loads::default()
    }
}

fn check_solution(sol: &ContactSolution) {
    assert!(sol.is_converged(), "{}", sol.report);
    assert!(sol.report.min_gap_m >= -1e-9, "{}", sol.report);
    assert!(sol.report.residual_norm_n <= sol.report.residual_tolerance_n);
}

#[test]
fn propped_cantilever_reaction_matches_the_closed_form() {
    let doc = reference("contact_propped_cantilever");
    let p = &doc["params"];
    let l = p["length_m"].as_f64().unwrap();
    let load = p["tip_load_n"].as_f64().unwrap();
    let rho = p["support_radius_m"].as_f64().unwrap();
    for s in doc["values"]["supports"].as_array().unwrap() {
        let a = s["a_m"].as_f64().unwrap();
        let r_ref = s["reaction_n"].as_f64().unwrap();
        // the support touches the straight rod's underside at x = a
        let obstacles = Obstacles::new(
            vec![Obstacle::Circle {
                center_m: [a, -rho],
                radius_m: rho,
            }],
            0.0,
        )
        .unwrap();
        // meshes with a node at the support: Hermite cubics are exact for the
        // linear beam between point loads, so every mesh gives the limit
        for n in [4, 8, 16] {
            let robot = robot(p, n);
            let mut per_load = Vec::new();
            // the linear limit: the tip deflects about 1e-5 L at the reference
            // load, so the geometric nonlinearity changes R/P by about 1e-10;
            // R/P at a tenth of the load agrees
            for scale in [1.0, 0.1] {
                let sol = ContactSolver::default()
                    .solve(&robot, &tip_load(l, [0.0, -scale * load]), &obstacles, None)
                    .unwrap();
                check_solution(&sol);
                assert_eq!(sol.contacts.len(), 1, "{:?}", sol.contacts);
                let c = &sol.contacts[0];
                assert!((c.s_m - a).abs() < 1e-6, "contact at {} for a = {a}", c.s_m);
                per_load.push(c.force_n / (scale * load));
                let rel = (c.force_n / (scale * r_ref) - 1.0).abs();
                println!(
                    "a = {a}, {n} elements, P = {:.1e} N: R = {:.12e} N (closed form {:.12e}), relative error {rel:.2e}",
                    scale * load,
                    c.force_n,
                    scale * r_ref
                );
                assert!(rel < 1e-6, "relative error {rel:e}");
            }
            assert!(
                (per_load[0] / per_load[1] - 1.0).abs() < 1e-8,
                "{per_load:?}"
            );
        }
    }
}

#[test]
fn elastica_on_a_point_obstacle_matches_shooting() {
    for name in ["contact_elastica_down", "contact_elastica_oblique"] {
        let doc = reference(name);
        let p = &doc["params"];
        let v = &doc["values"];
        let l = p["length_m"].as_f64().unwrap();
        let o = &p["obstacle"];
        let c = o["center_m"].as_array().unwrap();
        let obstacles = Obstacles::new(
            vec![Obstacle::Circle {
                center_m: [c[0].as_f64().unwrap(), c[1].as_f64().unwrap()],
                radius_m: o["radius_m"].as_f64().unwrap(),
            }],
            0.0,
        )
        .unwrap();
        let f = p["tip_load_n"].as_array().unwrap();
        let loads = tip_load(l, [f[0].as_f64().unwrap(), f[1].as_f64().unwrap()]);
        let r_ref = v["reaction_n"].as_f64().unwrap();
        let s_ref = v["contact_s_m"].as_f64().unwrap();
        let mut last = None;
        for n in [16, 32, 64, 128] {
            let robot = robot(p, n);
            let sol = ContactSolver::default()
                .solve(&robot, &loads, &obstacles, None)
                .unwrap();
            check_solution(&sol);
            assert_eq!(sol.contacts.len(), 1, "{:?}", sol.contacts);
            let k = &sol.contacts[0];
            let (er, es) = ((k.force_n / r_ref - 1.0).abs(), (k.s_m / s_ref - 1.0).abs());
            println!(
                "{name}, {n} elements: R = {:.10e} N (shooting {r_ref:.10e}), s = {:.10} m (shooting {s_ref:.10}); relative errors {er:.2e}, {es:.2e}; {}",
                k.force_n, k.s_m, sol.report
            );
            last = Some((er, es));
        }
        let (er, es) = last.unwrap();
        assert!(er < 1e-5 && es < 1e-5, "{name}: {er:e} {es:e}");
    }
}

#[test]
fn exudyn_penalty_contact_tends_to_the_exact_force() {
    let doc = reference("contact_exudyn_penalty");
    let p = &doc["params"];
    let l = p["length_m"].as_f64().unwrap();
    let o = &p["obstacle"];
    let c = o["center_m"].as_array().unwrap();
    let obstacles = Obstacles::new(
        vec![Obstacle::Circle {
            center_m: [c[0].as_f64().unwrap(), c[1].as_f64().unwrap()],
            radius_m: o["radius_m"].as_f64().unwrap(),
        }],
        0.0,
    )
    .unwrap();
    let f = p["tip_load_n"].as_array().unwrap();
    let loads = tip_load(l, [f[0].as_f64().unwrap(), f[1].as_f64().unwrap()]);
    // the same mesh as exudyn's
    let robot = robot(p, p["elements"].as_u64().unwrap() as usize);
    let sol = ContactSolver::default()
        .solve(&robot, &loads, &obstacles, None)
        .unwrap();
    check_solution(&sol);
    assert_eq!(sol.contacts.len(), 1);
    let exact = &sol.contacts[0];
    let fx = [
        exact.force_n * exact.normal[0],
        exact.force_n * exact.normal[1],
    ];
    println!("softrod: R = {:.10e} N, force {fx:?} N", exact.force_n);
    let mut errors = Vec::new();
    for run in doc["values"]["runs"].as_array().unwrap() {
        assert!(run["converged"].as_bool().unwrap());
        let k = run["contact_stiffness_n_per_m"].as_f64().unwrap();
        let r = run["reaction_n"].as_f64().unwrap();
        let v = run["contact_force_n"].as_array().unwrap();
        let dir =
            (v[0].as_f64().unwrap() - fx[0]).hypot(v[1].as_f64().unwrap() - fx[1]) / exact.force_n;
        let rel = (r / exact.force_n - 1.0).abs();
        println!(
            "k = {k:.0e} N/m: exudyn R = {r:.10e} N, relative difference {rel:.2e} (k × difference {:.2}), force vector {dir:.2e}",
            k * rel
        );
        errors.push((k, rel, dir));
    }
    // the penalty's bias is O(1/k): visible at small k, shrinking tenfold
    // per decade, until exudyn's own discretization of the gap (straight
    // segments, 12 per element: chords within ~1e-6 m of the cubic) is
    // reached at a few 1e-5 in magnitude; the direction of a segment's
    // normal differs from the cubic's by up to κ h / 2 (h = 2.6 mm), a few
    // 1e-4 here
    let (k0, e0, _) = errors[0];
    let (_, e1, _) = errors[1];
    assert!(k0 == 1e2 && e0 > 1e-2 && e1 < e0 / 5.0, "{errors:?}");
    for &(k, e, _) in &errors {
        assert!(e <= 10.0 / k + 5e-5, "k = {k}: {e}");
    }
    for &(_, e, d) in &errors[errors.len() - 2..] {
        assert!(e < 5e-5 && d < 5e-4, "{errors:?}");
    }
}

#[test]
fn propped_cantilever_with_the_support_inside_an_element_converges_in_the_mesh() {
    let doc = reference("contact_propped_cantilever");
    let p = &doc["params"];
    let l = p["length_m"].as_f64().unwrap();
    let load = p["tip_load_n"].as_f64().unwrap();
    let rho = p["support_radius_m"].as_f64().unwrap();
    // a = 0.3 m: inside an element for 8, 16, 32, 64 elements (nodes at k/n)
    let a = 0.3;
    let r_ref = load * (3.0 * l - a) / (2.0 * a);
    let obstacles = Obstacles::new(
        vec![Obstacle::Circle {
            center_m: [a, -rho],
            radius_m: rho,
        }],
        0.0,
    )
    .unwrap();
    let mut errors = Vec::new();
    for n in [8, 16, 32, 64] {
        let robot = robot(p, n);
        let sol = ContactSolver::default()
            .solve(&robot, &tip_load(l, [0.0, -load]), &obstacles, None)
            .unwrap();
        check_solution(&sol);
        let c = &sol.contacts[0];
        let rel = (c.force_n / r_ref - 1.0).abs();
        println!(
            "a = {a} (inside an element), {n} elements: R = {:.12e} N, closed form {r_ref:.12e} N, relative error {rel:.2e}, contact at s = {:.9} m",
            c.force_n, c.s_m
        );
        errors.push(rel);
    }
    assert!(errors[3] < 1e-6, "{errors:?}");
}

/// The equilibrium with the contact forces as dead point forces: the
/// multipliers are forces if the robot is then in equilibrium without the
/// obstacles.
fn contact_forces_balance(
    robot: &softrod::assembly::Robot<PlanarCable>,
    loads: &Loads,
    sol: &ContactSolution,
) -> f64 {
    let mut with = loads.clone();
    for c in &sol.contacts {
        with.point_forces.push(PointForce {
            s_m: c.s_m,
            force_n: vec![c.force_n * c.normal[0], c.force_n * c.normal[1]],
        });
    }
    let dead = robot.dead_force(&with).unwrap();
    let r = robot
        .residual(sol.q.as_slice(), dead.as_slice(), &with)
        .unwrap();
    let scale = robot
        .restrict(dead.as_slice())
        .unwrap()
        .iter()
        .map(|v| v * v)
        .sum::<f64>()
        .sqrt();
    r.iter().map(|v| v * v).sum::<f64>().sqrt() / scale
}

#[test]
fn a_robot_sagging_onto_a_capsule_and_a_polygon_balances_its_contact_forces() {
    // the 0.24 m robot of the examples under its weight and a tip load,
    // rod radius 8 mm, a capsule under its middle and a wedge under its tip
    let mut spec = RobotSpec::new(vec![Section {
        mass_per_length_kg_per_m: 0.2,
        ..Section::uniform(0.24, 300.0, 0.025, 16)
    }]);
    spec.gravity_m_per_s2 = vec![0.0, -9.81];
    let robot = spec.build_planar().unwrap();
    let obstacles = Obstacles::new(
        vec![
            Obstacle::Capsule {
                start_m: [0.08, -0.03],
                end_m: [0.14, -0.025],
                radius_m: 0.01,
            },
            Obstacle::Polygon {
                vertices_m: vec![[0.18, -0.08], [0.26, -0.08], [0.22, -0.03]],
            },
        ],
        0.008,
    )
    .unwrap();
    let loads = tip_load(0.24, [0.0, -1.0]);
    let sol = ContactSolver::default()
        .solve(&robot, &loads, &obstacles, None)
        .unwrap();
    check_solution(&sol);
    println!("{}", sol.report);
    for c in &sol.contacts {
        println!("{c:?}");
        assert!(c.force_n > 0.0 && c.gap_m.abs() <= 1e-9);
    }
    let touched: Vec<usize> = sol.contacts.iter().map(|c| c.obstacle).collect();
    assert!(touched.contains(&0) && touched.contains(&1), "{touched:?}");
    let balance = contact_forces_balance(&robot, &loads, &sol);
    println!("equilibrium with the contact forces as point loads: relative residual {balance:.2e}");
    assert!(balance < 1e-8, "{balance:e}");
    // every gap along the rod is closed or open, none negative, on a fine
    // sampling independent of the gap search
    for k in 0..=2400 {
        let s = 0.24 * k as f64 / 2400.0;
        let r = robot.position_at(sol.q.as_slice(), s).unwrap();
        for o in obstacles.obstacles() {
            let d = o
                .signed_distance(nalgebra::Vector2::new(r[0], r[1]))
                .distance_m
                - 0.008;
            assert!(d >= -1e-9, "penetration {d:e} at s = {s}");
        }
    }
}

#[test]
fn a_start_pinched_between_two_obstacles_is_infeasible() {
    // two overlapping disks either side of a straight rod turned up by 0.8
    // rad, both 1 cm into it at the same point: the linearized gaps ask
    // for a step both ways
    let mut spec = RobotSpec::new(vec![Section::uniform(0.3, 300.0, 0.02, 6)]);
    spec.gravity_m_per_s2 = vec![0.0, 0.0];
    let robot = spec.build_planar().unwrap();
    let (t, nrm) = (
        [0.8f64.cos(), 0.8f64.sin()],
        [-(0.8f64.sin()), 0.8f64.cos()],
    );
    let p = [0.2 * t[0], 0.2 * t[1]];
    let obstacles = Obstacles::new(
        vec![
            Obstacle::Circle {
                center_m: [p[0] + 0.03 * nrm[0], p[1] + 0.03 * nrm[1]],
                radius_m: 0.04,
            },
            Obstacle::Circle {
                center_m: [p[0] - 0.03 * nrm[0], p[1] - 0.03 * nrm[1]],
                radius_m: 0.04,
            },
        ],
        0.0,
    )
    .unwrap();
    let q0: Vec<f64> = robot
        .node_arc()
        .iter()
        .flat_map(|&s| [s * t[0], s * t[1], t[0], t[1]])
        .collect();
    let sol = ContactSolver::default()
        .solve(&robot, &Loads::default(), &obstacles, Some(&q0))
        .unwrap();
    println!("{}", sol.report);
    assert!(
        matches!(sol.report.status, softrod::outcome::ContactStatus::Infeasible { penetration_m } if penetration_m > 0.009),
        "{}",
        sol.report
    );
    assert!(!sol.is_converged() && sol.report.min_gap_m < -0.009);
}

#[test]
fn an_actuated_robot_bending_into_a_disk_stops_on_it() {
    // the two-section robot of the examples, pressurized, with a disk placed
    // across its free equilibrium (but clear of the straight robot)
    let scene = softrod::scene::Scene::two_section();
    let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    let free = softrod::statics::StaticSolver::default()
        .solve(&robot, &loads, None)
        .unwrap();
    let l = robot.length();
    let s = 0.8 * l;
    let r = robot.position_at(free.q.as_slice(), s).unwrap();
    // 1 cm radius, its centre 5 mm inside the free shape's side, off the x axis
    let base_y = robot.base_node()[1];
    assert!((r[1] - base_y).abs() > 0.03, "{r:?}");
    let obstacles = Obstacles::new(
        vec![Obstacle::Circle {
            center_m: [r[0], r[1]],
            radius_m: 0.01,
        }],
        0.004,
    )
    .unwrap();
    let sol = ContactSolver::default()
        .solve(&robot, &loads, &obstacles, None)
        .unwrap();
    println!("{}", sol.report);
    for c in &sol.contacts {
        println!("{c:?}");
    }
    check_solution(&sol);
    assert!(!sol.contacts.is_empty());
    let balance = contact_forces_balance(&robot, &loads, &sol);
    println!("relative residual with the contact forces as point loads {balance:.2e}");
    assert!(balance < 1e-8, "{balance:e}");
}

#[test]
fn a_solve_from_afar_with_a_far_obstacle_equals_the_free_solve() {
    // the pressurized two-section robot on the plant's finer mesh, solved
    // from its straight reference configuration, a disk 0.1 m from its free
    // shape: no contact, so the contact solve is the free equilibrium.
    // (Unbounded SQP steps made the far disk's linearized gap bind and
    // clarabel stop with InsufficientProgress.)
    let scene = softrod::scene::Scene::two_section();
    let plant = softrod::plant::SimulatedPlant::new(
        &scene,
        &[0.12, 0.24],
        softrod::plant::PlantSettings::default(),
    )
    .unwrap();
    let (robot, loads) = (plant.robot().clone(), scene.loads().unwrap());
    let free = softrod::statics::StaticSolver::default()
        .solve(&robot, &loads, None)
        .unwrap();
    let obstacles = Obstacles::new(
        vec![Obstacle::Circle {
            center_m: [0.2, 0.2],
            radius_m: 0.02,
        }],
        0.005,
    )
    .unwrap();
    let min = obstacles
        .gaps(&robot, free.q.as_slice())
        .unwrap()
        .iter()
        .map(|g| g.gap_m)
        .fold(f64::INFINITY, f64::min);
    assert!((min - 0.1).abs() < 0.005, "{min}");
    let sol = ContactSolver::default()
        .solve(
            &robot,
            &loads,
            &obstacles,
            Some(robot.reference_configuration().as_slice()),
        )
        .unwrap();
    println!("{}", sol.report);
    assert!(sol.is_converged(), "{}", sol.report);
    assert!(sol.contacts.is_empty());
    let d = sol
        .q
        .iter()
        .zip(&free.q)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(d < 1e-9, "{d:e}");
}

#[test]
fn a_fingertip_pressed_against_a_column_of_small_circles_converges() {
    // the right finger of the gripper's plant pressing its tip against a
    // ruler's circle cover (37 circles of 1.5 mm, 0.75 mm apart): the
    // fingertip is near several circles at once, and the interior-point
    // QP gives the open ones multipliers of up to 2e-8 of the contact's.
    // Taken as active they over-constrained the tip point and the solve
    // ended with LineSearchFailed (measured before the fix).
    use softrod::grasp::gripper::{GripperSpec, Side};
    let robot = GripperSpec::default()
        .finger_spec(Side::Right, 1.15, 0.9, 2)
        .build_planar()
        .unwrap();
    let y0 = -0.093_813_949_742_768_8;
    let circles: Vec<Obstacle> = (0..37)
        .map(|k| Obstacle::Circle {
            center_m: [0.0035, y0 + 0.00075 * k as f64],
            radius_m: 0.0015,
        })
        .collect();
    let obstacles = Obstacles::new(circles, 0.008).unwrap();
    let loads = Loads {
        pressures_pa: vec![68_601.311_472_840_68, 0.0, 0.0, 65_037.856_817_770_71],
        ..Loads::default()
    };
    let sol = ContactSolver::default()
        .solve(&robot, &loads, &obstacles, None)
        .unwrap();
    check_solution(&sol);
    assert!(sol.report.min_gap_m >= -1e-10, "{}", sol.report);
    // one contact, at the tip, pushing the finger outward (+x)
    assert_eq!(sol.contacts.len(), 1, "{:?}", sol.contacts);
    let c = &sol.contacts[0];
    assert!((c.s_m - robot.length()).abs() < 1e-12 && c.force_n > 0.0);
    assert!(c.normal[0] > 0.9, "{:?}", c.normal);
    assert!(contact_forces_balance(&robot, &loads, &sol) < 1e-8);
}
