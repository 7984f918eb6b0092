//! The typed results of `softrod::shape` against closed forms and against
//! an independent computation: the clamp reaction from the global balance
//! of the external loads equals the one from the residual at the base node
//! (the first element's internal force there); a full circle's tip pose;
//! the estimate's typed views equal its raw fields.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use nalgebra::{Vector2, Vector4};
use softrod::Error;
use softrod::assembly::{RobotSpec, Section};
use softrod::element::Element;
use softrod::estimate::{Backend, EstimatorSettings, Observation};
use softrod::loads::{FollowerLoad, LineLoad, Loads, NodeMoment, PointForce, PointMoment};
use softrod::scene::Scene;
use softrod::statics::{StaticSettings, StaticSolver};

/// The clamp reaction (global balance of the external loads, in the
/// deformed shape) equals minus the generalized force on the base node at
/// equilibrium: its dead load minus the first element's elastic force
/// there, read as a force (position part) and a moment (`r'₀ × Q_r'`).
/// Line load, point force, moment at an arc position and a follower
/// pressure together; bound 1e-8 of the reaction's size (the equilibrium is
/// solved to 1e-13; a sign error or a missing load is O(1)).
#[test]
fn the_clamp_reaction_is_the_residual_at_the_base() {
    let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 8)])
        .build_planar()
        .unwrap();
    let loads = Loads {
        line_loads: vec![LineLoad::Uniform {
            w_n_per_m: vec![0.3, -1.5],
        }],
        point_forces: vec![PointForce {
            s_m: 0.2,
            force_n: vec![0.05, -0.08],
        }],
        point_moments: vec![PointMoment {
            s_m: 0.23,
            moment_nm: vec![0.004],
        }],
        node_moments: vec![NodeMoment {
            node: 5,
            moment_nm: vec![-0.002],
        }],
        follower_loads: vec![FollowerLoad {
            pressure_n_per_m: 0.4,
            s_start_m: Some(0.1),
            s_end_m: None,
        }],
        ..Loads::default()
    };
    let solver = StaticSolver::new(StaticSettings {
        residual_tolerance: 1e-13,
        ..StaticSettings::default()
    })
    .unwrap();
    let eq = solver.solve(&robot, &loads, None).unwrap();
    assert!(eq.report.status.is_converged());
    let shape = eq.shape(&robot).unwrap();
    let r = shape.clamp_reaction(&loads).unwrap();
    // the residual at the base node: dead load minus the elastic force of element 0
    let dead = robot.dead_force(&loads).unwrap();
    let mut g = vec![0.0; 8];
    robot.elements()[0].add_energy_gradient(&eq.q.as_slice()[..8], &mut g);
    let qb = Vector4::from_fn(|i, _| dead[i] - g[i]);
    let t0 = Vector2::new(eq.q[2], eq.q[3]);
    let force = -Vector2::new(qb[0], qb[1]);
    let moment = -t0.perp(&Vector2::new(qb[2], qb[3]));
    let scale = r.force_n.norm() + r.moment_nm.abs() / 0.24;
    assert!(
        (r.force_n - force).norm() <= 1e-8 * scale,
        "{:?} vs {force:?}",
        r.force_n
    );
    assert!(
        (r.moment_nm - moment).abs() <= 1e-8 * scale * 0.24,
        "{} vs {moment}",
        r.moment_nm
    );
    // and it is not trivially zero: the line load alone is 0.36 N down
    assert!(r.force_n.y > 0.3);
}

/// A tip moment `2π EI / L` rolls the rod into a full circle (closed form):
/// the tip pose's angle is 2π (unwrapped, not 0) and the tip is back at the
/// base; the pose at every arc position lies on the circle of radius
/// `L / 2π` through the base, by the element's interpolation (positions
/// between nodes too). Bounds from the 32-element mesh's error (the tip
/// angle 1e-4 as in `Robot::node_angles`' example, positions 1e-4 L).
#[test]
fn a_full_circle_has_its_tip_pose() {
    let (l, ei) = (0.24, 0.025);
    let robot = RobotSpec::new(vec![Section::uniform(l, 3e5, ei, 32)])
        .build_planar()
        .unwrap();
    let m = std::f64::consts::TAU * ei / l;
    let loads = Loads {
        node_moments: vec![NodeMoment {
            node: 32,
            moment_nm: vec![m],
        }],
        ..Loads::default()
    };
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    let shape = eq.shape(&robot).unwrap();
    let tip = shape.tip_pose().unwrap();
    assert!(
        (tip.angle_rad - std::f64::consts::TAU).abs() < 1e-4,
        "{tip:?}"
    );
    assert!(tip.position_m.coords.norm() < 1e-4 * l, "{tip:?}");
    let rho = l / std::f64::consts::TAU;
    let centre = Vector2::new(0.0, rho);
    for k in 0..=40 {
        // between the nodes (and at neither end)
        let s = l * (k as f64 + 0.37) / 41.0;
        let p = shape.pose_at(s).unwrap();
        assert!(
            ((p.position_m.coords - centre).norm() - rho).abs() < 1e-4 * l,
            "s {s}: {p:?}"
        );
        assert!((p.angle_rad - s / rho).abs() < 1e-3, "s {s}: {p:?}");
    }
    // the moment at the clamp balances the tip moment
    let r = shape.clamp_reaction(&loads).unwrap();
    assert!((r.moment_nm + m).abs() < 1e-9 * m && r.force_n.norm() < 1e-9);
    // off the robot: a typed error naming s_m
    match shape.position_at(l * 1.5) {
        Err(Error::InvalidParameter { name, .. }) => assert_eq!(name, "s_m"),
        other => panic!("{other:?}"),
    }
}

/// The typed views of an estimate are its raw fields; `build_for` borrows
/// and runs the backend the settings name.
#[test]
fn the_estimate_views_are_its_fields() {
    let scene = Scene::two_section();
    let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    let truth = Loads {
        point_forces: vec![PointForce {
            s_m: 0.24,
            force_n: vec![0.0, -0.05],
        }],
        ..loads.clone()
    };
    let eq = StaticSolver::default().solve(&robot, &truth, None).unwrap();
    let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[5, 10, 15, 20])
        .unwrap()
        .with_noise(1e-5, 4);
    for backend in [Backend::Newton, Backend::Sqp] {
        let settings = EstimatorSettings {
            backend,
            noise_sigma_m: 1e-5,
            ..EstimatorSettings::default()
        };
        let mut est = settings.build_for(&robot, &loads).unwrap();
        assert_eq!(est.backend(), backend);
        let e = est.step(&obs).unwrap();
        let f = e.resultant::<2>().unwrap();
        assert_eq!(f.as_slice(), e.resultant_force_n.as_slice());
        let c = e.resultant_cov::<2>().unwrap();
        assert_eq!(c[(0, 1)], e.resultant_force_cov()[1]);
        assert_eq!(c[(1, 0)], e.resultant_force_cov()[2]);
        assert_eq!(c[(1, 1)], e.resultant_force_cov()[3]);
        let mc = e.marker_cov().clone();
        assert_eq!(mc.shape(), (8, 8));
        assert_eq!(mc[(2, 5)], e.marker_cov()[2 * 8 + 5]);
        for s in [0.0, 0.05, 0.12, 0.2399, 0.24] {
            let w = e.load_vector_at::<2>(s).unwrap();
            assert_eq!(w.as_slice(), e.load_at(s).as_slice());
        }
        assert!(matches!(
            e.load_vector_at::<2>(0.3),
            Err(Error::InvalidParameter { .. })
        ));
        assert!(matches!(
            e.resultant::<3>(),
            Err(Error::DimensionMismatch { .. })
        ));
        // the estimated tip is the measured one, to the noise
        let tip = e.shape(&robot).unwrap().tip_pose().unwrap();
        let truth_tip = eq.shape(&robot).unwrap().tip_pose().unwrap();
        assert!((tip.position_m - truth_tip.position_m).norm() < 1e-4);
    }
}
