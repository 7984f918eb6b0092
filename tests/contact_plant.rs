//! The gripper plant's contact solves that failed in the simulated Table I
//! (tests/contact_plant_cases.json: the finger, its pressures, the
//! obstacles and the warm start of each, dumped from the trial): every
//! one converges, from its warm start and cold, to the equilibrium that a
//! solve without obstacles confirms independently.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::assembly::Robot;
use softrod::contact::{ContactSolution, ContactSolver, Obstacle, Obstacles};
use softrod::element::PlanarCable;
use softrod::grasp::gripper::{GripperSpec, Side};
use softrod::loads::Loads;

struct Case {
    name: String,
    robot: Robot<PlanarCable>,
    loads: Loads,
    obstacles: Obstacles,
    warm: Vec<f64>,
}

fn cases() -> Vec<Case> {
    let doc: serde_json::Value =
        serde_json::from_str(include_str!("contact_plant_cases.json")).unwrap();
    doc["cases"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let side = match c["side"].as_str().unwrap() {
                "left" => Side::Left,
                _ => Side::Right,
            };
            // the plant's finger: EI +15 %, gain −10 %, twice the mesh
            let robot = GripperSpec::default()
                .finger_spec(side, 1.15, 0.9, 2)
                .build_planar()
                .unwrap();
            let obstacles: Vec<Obstacle> = serde_json::from_value(c["obstacles"].clone()).unwrap();
            let obstacles = Obstacles::new(obstacles, c["rod_radius_m"].as_f64().unwrap()).unwrap();
            let loads = Loads {
                pressures_pa: serde_json::from_value(c["pressures_pa"].clone()).unwrap(),
                ..Loads::default()
            };
            Case {
                name: c["case"].as_str().unwrap().to_string(),
                robot,
                loads,
                obstacles,
                warm: serde_json::from_value(c["warm_q"].clone()).unwrap(),
            }
        })
        .collect()
}

fn check(case: &Case, sol: &ContactSolution, how: &str) {
    let name = &case.name;
    assert!(sol.is_converged(), "{name} ({how}): {}", sol.report);
    assert!(
        sol.report.min_gap_m >= -1e-10,
        "{name} ({how}): {}",
        sol.report
    );
    assert!(
        sol.report.residual_norm_n <= sol.report.residual_tolerance_n,
        "{name} ({how}): {}",
        sol.report
    );
}

#[test]
fn plant_solves_released_from_the_object_converge_to_the_free_equilibrium() {
    // In each case the finger leaves the object (its equilibrium without
    // obstacles has every gap open), but the interior-point QP gave every
    // open gap a multiplier of ~1e-14 N, all of them "active" under a
    // threshold relative to the largest: the polish then solved a KKT
    // system with dozens of constraints at the fingertip, diverged, and the
    // solve ended with LineSearchFailed, from the warm start and cold
    // (measured before the fix: residual up to 1.7e16 N after 301–1020
    // Newton iterations).
    let solver = ContactSolver::default();
    let none = Obstacles::new(Vec::new(), 0.008).unwrap();
    let cases = cases();
    assert_eq!(cases.len(), 4);
    for case in &cases {
        let free = solver
            .solve(&case.robot, &case.loads, &none, Some(&case.warm))
            .unwrap();
        assert!(free.is_converged(), "{}: {}", case.name, free.report);
        let open = case
            .obstacles
            .gaps(&case.robot, free.q.as_slice())
            .unwrap()
            .iter()
            .map(|g| g.gap_m)
            .fold(f64::INFINITY, f64::min);
        assert!(open > 1e-5, "{}: {open:e}", case.name);
        for (how, q0) in [("warm", Some(case.warm.as_slice())), ("cold", None)] {
            let sol = solver
                .solve(&case.robot, &case.loads, &case.obstacles, q0)
                .unwrap();
            check(case, &sol, how);
            assert!(
                sol.contacts.is_empty(),
                "{} ({how}): {:?}",
                case.name,
                sol.contacts
            );
            let d = sol
                .q
                .iter()
                .zip(&free.q)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(d < 1e-9, "{} ({how}): {d:e}", case.name);
        }
    }
}
