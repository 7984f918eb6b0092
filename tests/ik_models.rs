//! The one inverse kinematics on a model other than the clamped robot: the
//! parallel robot's platform under a force on it
//! ([`InverseKinematics::for_model`]). Its pressure sensitivities (43) on
//! a structure (the applied force of unit pressures through the rigid
//! joints' map) against central differences of cold equilibria, and its
//! solutions checked by a solve that does not go through it (the
//! parallel robot's own globalized solve from the straight reference).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::control::{IkSettings, InverseKinematics};
use softrod::estimate::LoadModel;
use softrod::parallel::{ParallelRobot, ParallelSpec};
use softrod::sensitivity::Sensitivity;
use softrod::site::Site;
use softrod::statics::Tracker;
use softrod::structure::{Actuated, Assembled, Structure};

const PLATFORM: Site = Site::Body { body: 0 };

/// The parallel robot at 2 elements per section (legs of the full 3-D
/// element, as the tracking runs' model) and the
/// centre pressures of the tracking runs (chamber 0 of every first
/// section at 40 kPa) with 5 kPa more in every chamber (inside the bounds
/// by more than a difference step).
fn robot() -> (ParallelRobot<softrod::element::Ancf3d>, Vec<f64>) {
    let spec = ParallelSpec {
        elements_per_section: 2,
        ..ParallelSpec::default()
    };
    let p = softrod::control::parallel::centre_pressures(&spec);
    let p = p.iter().map(|v| v + 5e3).collect();
    (spec.build_full().unwrap(), p)
}

/// The parallel controller's settings of the inverse kinematics: the
/// pressures' weight 1e-4, the null-space damping 1e-2, ended at the
/// tolerance (0.1 µm).
fn settings() -> IkSettings {
    IkSettings {
        pressure_weight: 1e-4,
        null_space_damping: 1e-2,
        stop_when_reached: true,
        ..IkSettings::default()
    }
}

fn ik_of(
    robot: &ParallelRobot<softrod::element::Ancf3d>,
    p: &[f64],
) -> InverseKinematics<Structure<softrod::element::Ancf3d>> {
    let known = robot.loads(p, [0.0; 3], [0.0; 3]).unwrap();
    InverseKinematics::for_model(
        robot.structure().clone(),
        known,
        settings(),
        PLATFORM,
        LoadModel::AtSite { site: PLATFORM },
    )
    .unwrap()
}

/// The platform's centre (m) where the parallel robot's own solver puts it
/// under pressures `p` and a platform force `f`, from the reference.
fn platform_by_own_solve(
    robot: &ParallelRobot<softrod::element::Ancf3d>,
    p: &[f64],
    f: [f64; 3],
) -> [f64; 3] {
    let eq = robot
        .solve(&robot.loads(p, f, [0.0; 3]).unwrap(), None)
        .unwrap();
    let pose = robot.platform_pose(eq.q.as_slice()).unwrap();
    [pose[0], pose[1], pose[2]]
}

#[test]
fn structure_pressure_sensitivities_match_central_differences() {
    let (robot, p) = robot();
    let s = robot.structure();
    let loads = robot.loads(&p, [0.0, 0.0, -0.05], [0.0; 3]).unwrap();
    let mut tracker = Tracker::new(s.clone(), loads.clone(), Default::default()).unwrap();
    let load = LoadModel::AtSite { site: PLATFORM };
    let q0 = robot.solve(&loads, None).unwrap().q;
    let eq = tracker.solve(&load, &[0.0; 3], q0.as_slice()).unwrap();
    let dqdp = Sensitivity::at(s, eq.u.as_slice(), &eq.factors)
        .unwrap()
        .dq_dp(eq.q.as_slice())
        .unwrap();
    assert_eq!(dqdp.shape(), (Assembled::n_q(s), p.len()));
    let x0 = s.body_coordinates(0).unwrap().start;
    let h = 50.0; // Pa, of a 0–100 kPa range
    let mut worst = 0.0f64;
    let mut scale = 0.0f64;
    for k in [0, 1, 3, 7, 12, 17] {
        let mut pp = p.clone();
        pp[k] += h;
        let plus = platform_by_own_solve(&robot, &pp, [0.0, 0.0, -0.05]);
        pp[k] -= 2.0 * h;
        let minus = platform_by_own_solve(&robot, &pp, [0.0, 0.0, -0.05]);
        for i in 0..3 {
            let fd = (plus[i] - minus[i]) / (2.0 * h);
            worst = worst.max((fd - dqdp[(x0 + i, k)]).abs());
            scale = scale.max(fd.abs());
        }
    }
    println!("dx/dP: worst |analytic - central| {worst:.3e} m/Pa of {scale:.3e}");
    assert!(scale > 1e-8, "the pressures move the platform");
    assert!(worst <= 1e-4 * scale, "{worst:e} of {scale:e}");
}

#[test]
fn platform_jacobian_of_the_one_inverse_kinematics_matches_central_differences() {
    let (robot, p) = robot();
    let mut ik = ik_of(&robot, &p);
    let f = [0.0, 0.0, -0.05];
    let (q, _) = ik.forward(&p, &f, None).unwrap();
    let jac = ik.jacobian(q.as_slice(), &p, &f).unwrap();
    assert_eq!(jac.shape(), (3, 18));
    let h = 50.0;
    let mut worst = 0.0f64;
    let mut scale = 0.0f64;
    for k in 0..18 {
        let mut pp = p.clone();
        pp[k] += h;
        let plus = platform_by_own_solve(&robot, &pp, f);
        pp[k] -= 2.0 * h;
        let minus = platform_by_own_solve(&robot, &pp, f);
        for i in 0..3 {
            let fd = (plus[i] - minus[i]) / (2.0 * h);
            worst = worst.max((fd - jac[(i, k)]).abs());
            scale = scale.max(fd.abs());
        }
    }
    println!("J = dx/dP: worst |analytic - central| {worst:.3e} of {scale:.3e}");
    assert!(worst <= 1e-4 * scale, "{worst:e} of {scale:e}");
}

#[test]
fn parallel_targets_are_reached_as_the_robots_own_solve_confirms() {
    let (robot, p) = robot();
    let mut ik = ik_of(&robot, &p);
    assert_eq!(ik.n_load_params(), 3);
    let weight = [0.0, 0.0, -0.1 * 9.81];
    let (_, c) = ik.forward(&p, &weight, None).unwrap();
    // the tracking runs' circle (2.5 mm about the centre, 100 g payload) at
    // 8 points, warm from one target to the next, and a target far outside
    // the workspace
    for k in 0..8 {
        let a = std::f64::consts::TAU * k as f64 / 8.0;
        let target = [c[0] + 2.5e-3 * a.cos(), c[1] + 2.5e-3 * a.sin(), c[2]];
        let sol = ik.solve(&target, &weight).unwrap();
        assert!(sol.status.is_reached(), "target {k}: {:?}", sol.status);
        let bounds = robot.structure().pressure_bounds();
        for (v, (lo, hi)) in sol.pressures_pa.iter().zip(&bounds) {
            assert!(lo <= v && v <= hi);
        }
        let x = platform_by_own_solve(&robot, sol.pressures_pa.as_slice(), weight);
        let err = (0..3)
            .map(|i| (x[i] - target[i]).powi(2))
            .sum::<f64>()
            .sqrt();
        assert!(
            err <= 1e-6,
            "target {k}: the robot's own solve is {err:e} m away"
        );
    }
    let far = [c[0] + 0.5, c[1], c[2]];
    let sol = ik.solve(&far, &weight).unwrap();
    assert!(!sol.status.is_reached(), "{:?}", sol.status);
    assert!(sol.status.error_m() > 0.1);
}

#[test]
fn bad_inputs_of_the_model_inverse_kinematics_are_refused_by_name() {
    let (robot, p) = robot();
    let known = robot.loads(&p, [0.0; 3], [0.0; 3]).unwrap();
    let s = robot.structure().clone();
    let e = InverseKinematics::for_model(
        s.clone(),
        known.clone(),
        IkSettings::default(),
        Site::Body { body: 4 },
        LoadModel::AtSite { site: PLATFORM },
    )
    .unwrap_err();
    assert_eq!(e.field(), Some("effector.body"), "{e}");
    // the distributed field lives on the clamped robot's rod: a structure
    // has none, refused here (it used to fail only at the first solve)
    let e = InverseKinematics::for_model(
        s.clone(),
        known.clone(),
        IkSettings::default(),
        PLATFORM,
        LoadModel::Distributed,
    )
    .unwrap_err();
    assert_eq!(e.field(), Some("load_model"), "{e}");
    assert!(matches!(e, softrod::Error::InvalidParameter { .. }), "{e}");
    let mut ik = ik_of(&robot, &p);
    let e = ik.solve(&[0.0, 0.0], &[0.0; 3]).unwrap_err();
    assert_eq!(e.field(), Some("x_d"), "{e}");
    let e = ik.solve(&[0.0, 0.0, 0.2], &[0.0; 2]).unwrap_err();
    assert_eq!(e.field(), Some("f_hat"), "{e}");
    let e = ik.solve(&[0.0, 0.0, 0.2], &[f64::NAN; 3]).unwrap_err();
    assert_eq!(e.field(), Some("f_hat[0]"), "{e}");
    let e = ik
        .solve_starting_at(&[0.0, 0.0, 0.2], &[0.0; 3], &[0.0; 5])
        .unwrap_err();
    assert_eq!(e.field(), Some("pressures_pa"), "{e}");
}
