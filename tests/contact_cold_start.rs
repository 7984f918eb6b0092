//! Cold starts of the contact solver beside thin obstacles: a gripper
//! finger whose actuation alone would curl it past a 3–6 mm strip. The
//! solve from no start must end where the loading path ends (the pressure
//! ramped from zero in 40 warm-started steps), on the base's side of the
//! strip and pressing on it; before the cold start followed the actuation
//! path, it started from the full actuation's shape beyond the strip and
//! converged there, 65–80 mm from the ramp's equilibrium.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::assembly::Robot;
use softrod::contact::{ContactSolver, Obstacle, Obstacles};
use softrod::element::PlanarCable;
use softrod::grasp::gripper::{GripperSpec, Side};
use softrod::loads::Loads;

fn finger() -> (GripperSpec, Robot<PlanarCable>) {
    let g = GripperSpec::default();
    // the plant's finger: EI +15 %, gain −10 %, twice the mesh
    let robot = g
        .finger_spec(Side::Left, 1.15, 0.9, 2)
        .build_planar()
        .unwrap();
    (g, robot)
}

/// A vertical strip (capsule) `x_m` right of the left finger's base, from
/// `y_lo_m` to `y_hi_m`, of radius `radius_m`; the proximal chamber at
/// `fraction` of the largest pressure.
fn check(x_m: f64, y_lo_m: f64, y_hi_m: f64, radius_m: f64, fraction: f64) {
    let (g, robot) = finger();
    let x = g.base_m(Side::Left)[0] + x_m;
    let strip = Obstacle::Capsule {
        start_m: [x, y_lo_m],
        end_m: [x, y_hi_m],
        radius_m,
    };
    let obstacles = Obstacles::new(vec![strip], g.finger_radius_m).unwrap();
    let p = fraction * g.pressure_max_pa;
    let loads = |s: f64| Loads {
        pressures_pa: vec![s * p, 0.0, 0.0, 0.0],
        ..Loads::default()
    };
    let solver = ContactSolver::default();
    // the free finger curls past the strip: the obstacle is in its way
    let free = solver
        .solve(
            &robot,
            &loads(1.0),
            &Obstacles::new(vec![], g.finger_radius_m).unwrap(),
            None,
        )
        .unwrap();
    let tip = |q: &[f64]| robot.position_at(q, g.finger_length_m()).unwrap();
    assert!(tip(free.q.as_slice())[0] > x + radius_m + g.finger_radius_m);
    let cold = solver.solve(&robot, &loads(1.0), &obstacles, None).unwrap();
    let what =
        format!("strip at x {x_m}, y {y_lo_m}..{y_hi_m}, radius {radius_m}, {fraction} p_max");
    assert!(cold.is_converged(), "{what}: {}", cold.report);
    assert!(cold.report.min_gap_m >= -1e-10, "{what}: {}", cold.report);
    // on the base's side, pressed back by the strip
    assert!(!cold.contacts.is_empty(), "{what}: no contact");
    for c in &cold.contacts {
        assert!(
            c.force_n > 0.0 && c.normal[0] < 0.0 && c.point_m[0] < x,
            "{what}: {c:?}"
        );
    }
    // the loading path's end
    let mut q: Option<Vec<f64>> = None;
    for k in 1..=40 {
        let s = solver
            .solve(&robot, &loads(k as f64 / 40.0), &obstacles, q.as_deref())
            .unwrap();
        assert!(s.is_converged(), "{what}: ramp step {k}: {}", s.report);
        q = Some(s.q.as_slice().to_vec());
    }
    let ramp = q.unwrap();
    let d = cold
        .q
        .iter()
        .zip(&ramp)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(d < 1e-9, "{what}: cold start {d:e} m from the ramp's end");
}

#[test]
fn a_finger_curling_past_a_thin_strip_is_stopped_by_it_from_a_cold_start() {
    // a 3 mm strip, 20 mm tall, below the middle of the finger
    check(0.02, -0.08, -0.06, 0.0015, 1.0);
}

#[test]
fn a_finger_curling_past_a_short_strip_near_its_tip_is_stopped_by_it() {
    // a 6 mm strip, 10 mm tall, beside the fingertip, at 80 % pressure
    check(0.02, -0.105, -0.095, 0.003, 0.8);
}
