//! Sites (`softrod::site`): one addressing of points for every model.
//!
//! - The clamped robot and the one-rod structure built from the same
//!   sections give the same rows for every site, and so the same markers.
//! - A rigid body's site is its pose's position (the parallel robot's
//!   platform centre).
//! - The parallel robot's payload is a force at its platform's site.
//! - A force at a site of the parallel robot (a structure whose map
//!   `q = φ(u)` is not linear) has the sensitivity `∂q/∂F` (28) of central
//!   finite differences of re-solved equilibria, and its platform block is
//!   the platform's compliance computed by a dense LU of the tangent
//!   (`ParallelRobot::platform_compliance`, another code path).
//! - On the robot, a force at the node's site is the concentrated load at
//!   the node, bit for bit, through the estimator.
//! - The one-rod structure estimates the robot's tip force through the same
//!   estimator: the same optimum, force to 1e-9 and shape to 1e-10 of the robot's,
//!   by either backend (the robot's cold newton estimate takes the sqp far
//!   start, the structure's the reduced iteration alone).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use nalgebra::{DMatrix, Vector2};
use softrod::assembly::{RobotSpec, Section};
use softrod::estimate::{
    Backend, BoundFrame, Estimator, EstimatorSettings, LoadBound, LoadModel, NewtonEstimator,
};
use softrod::loads::{Loads, PointForce};
use softrod::observe::{MarkerObservation, Observation, ObservationOperator};
use softrod::scene::Scene;
use softrod::sensitivity::Sensitivity;
use softrod::site::{Site, Sites};
use softrod::statics::{LinearLoad, StaticSettings, StaticSolver, Tracker};
use softrod::structure::{RodSpec, Stepping, StructureLoads, StructureSpec};

fn sections() -> Vec<Section> {
    vec![
        Section::uniform(0.12, 300.0, 0.025, 4),
        Section::uniform(0.12, 200.0, 0.012, 5),
    ]
}

#[test]
fn the_one_rod_structure_has_the_robots_sites() {
    let robot = RobotSpec::new(sections()).build_planar().unwrap();
    let rod = RodSpec::clamped(sections(), Vector2::zeros(), Vector2::new(1.0, 0.0));
    let structure = StructureSpec::new(vec![rod], vec![], vec![])
        .build_planar()
        .unwrap();
    assert_eq!(Sites::dim(&robot), 2);
    assert_eq!(structure.n_q(), robot.n_q());
    for s_m in [0.0, 0.03, 0.12, 0.1700001, 0.24] {
        let site = Site::Rod { rod: 0, s_m };
        assert_eq!(
            robot.site_rows("m", &site).unwrap(),
            structure.site_rows("m", &site).unwrap(),
            "s = {s_m}"
        );
    }
    for node in [0, 4, 9] {
        assert_eq!(
            robot.node_arc_m("m", 0, node).unwrap(),
            structure.node_arc_m("m", 0, node).unwrap()
        );
    }
    // a bent shape: the same markers from both
    let q: Vec<f64> = robot
        .reference_configuration()
        .iter()
        .enumerate()
        .map(|(i, v)| v + 1e-3 * ((i as f64) * 0.7).sin())
        .collect();
    let sites: Vec<Site> = [0.05, 0.2, 0.24]
        .map(|s_m| Site::Rod { rod: 0, s_m })
        .to_vec();
    // (the two builds place interior nodes to the last bit differently:
    // 1e-15 m here)
    let a = Observation::of_sites(&robot, &q, &sites).unwrap();
    let b = Observation::of_sites(&structure, &q, &sites).unwrap();
    for (ma, mb) in a.markers.iter().zip(&b.markers) {
        assert_eq!((ma.s_m, ma.rod, ma.body), (mb.s_m, mb.rod, mb.body));
        for (x, y) in ma.position_m.iter().zip(&mb.position_m) {
            assert!((x - y).abs() <= 1e-14 * 0.24, "{x} vs {y}");
        }
    }
    // and the node markers of `of_nodes` are those of the nodes' sites
    let n = Observation::of_nodes(&robot, &q, &[4, 9]).unwrap();
    assert_eq!(n.markers[1].position_m, q[36..38].to_vec());
    // refusals name the field
    let e = robot
        .site_rows("m", &Site::Rod { rod: 1, s_m: 0.1 })
        .unwrap_err();
    assert_eq!(e.field(), Some("m.rod"));
    let e = structure
        .site_rows("m", &Site::Rod { rod: 0, s_m: 0.3 })
        .unwrap_err();
    assert_eq!(e.field(), Some("m.s_m"));
    let e = robot.site_rows("m", &Site::Body { body: 0 }).unwrap_err();
    assert_eq!(e.field(), Some("m.body"));
}

#[test]
fn a_body_site_is_the_pose_position_and_a_marker_there_has_no_tangent() {
    let robot = softrod::parallel::ParallelSpec::default()
        .build_cable()
        .unwrap();
    let loads = robot.loads(&[], [0.02, 0.0, -0.05], [0.0; 3]).unwrap();
    let eq = robot.solve(&loads, None).unwrap();
    let s = robot.structure();
    let p = s
        .site_rows("m", &Site::Body { body: 0 })
        .unwrap()
        .position_at(eq.q.as_slice());
    let pose = robot.platform_pose(eq.q.as_slice()).unwrap();
    assert_eq!(p, pose.as_slice()[..3].to_vec());
    let mut obs = Observation::of_sites(s, eq.q.as_slice(), &[Site::Body { body: 0 }]).unwrap();
    assert_eq!(obs.markers[0].body, Some(0));
    assert_eq!(
        ObservationOperator::new(s, &obs, 1e-5, 1e-3).unwrap().len(),
        3
    );
    obs.markers[0].tangent = Some(vec![0.0, 0.0, 1.0]);
    let e = ObservationOperator::new(s, &obs, 1e-5, 1e-3).unwrap_err();
    assert_eq!(e.field(), Some("observation.markers[0].tangent"));
    // a marker with a body and a node names itself
    let m: MarkerObservation =
        serde_json::from_str(r#"{"body": 0, "node": 3, "position_m": [0, 0, 0]}"#).unwrap();
    let e = ObservationOperator::new(s, &Observation { markers: vec![m] }, 1e-5, 1e-3).unwrap_err();
    assert_eq!(e.field(), Some("observation.markers[0]"));
}

#[test]
fn a_force_at_the_platform_has_the_sensitivity_of_resolved_equilibria() {
    let robot = softrod::parallel::ParallelSpec::default()
        .build_cable()
        .unwrap();
    let s = robot.structure();
    let known = robot.loads(&[], [0.0, 0.0, -0.2], [0.0; 3]).unwrap();
    let load = LoadModel::AtSite {
        site: Site::Body { body: 0 },
    };
    assert_eq!(load.n_params(s), 3);
    let mut tracker = Tracker::new(s.clone(), known.clone(), Default::default()).unwrap();
    let f0 = [0.01, -0.02, 0.0];
    let start = robot.solve(&known, None).unwrap();
    let eq = tracker.solve(&load, &f0, start.q.as_slice()).unwrap();
    assert!(eq.status.is_converged());
    let dq_df = Sensitivity::at(s, eq.u.as_slice(), &eq.factors)
        .unwrap()
        .dq_df(&load)
        .unwrap();
    let tight = StaticSolver::new(StaticSettings {
        residual_tolerance: 1e-13,
        ..StaticSettings::default()
    })
    .unwrap();
    let h = 1e-4;
    let mut fd = DMatrix::zeros(s.n_q(), 3);
    for j in 0..3 {
        let mut col = vec![0.0; s.n_q()];
        for sign in [1.0, -1.0] {
            let mut f = f0;
            f[j] += sign * h;
            let loads = load.add_to(s, &known, &f);
            let q = tight.solve(s, &loads, Some(eq.q.as_slice())).unwrap().q;
            col.iter_mut()
                .zip(q.iter())
                .for_each(|(c, v)| *c += sign * v / (2.0 * h));
        }
        fd.column_mut(j).copy_from_slice(&col);
    }
    let scale = dq_df.amax();
    assert!(scale > 0.0);
    let err = (&dq_df - &fd).amax() / scale;
    assert!(err < 1e-5, "dq/dF against finite differences: {err:e}");
    // the platform block: the compliance by a dense LU of the tangent
    let c = robot
        .platform_compliance(
            &softrod::statics::Equilibrium {
                q: eq.q.clone(),
                u: eq.u.clone(),
                report: start.report.clone(),
            },
            &load.add_to(s, &known, &f0),
        )
        .unwrap();
    let x = s.body_coordinates(0).unwrap().start;
    let block = dq_df.view((x, 0), (3, 3)).into_owned();
    let err = (&block - c).amax() / c.amax();
    assert!(err < 1e-9, "platform compliance: {err:e}");
}

#[test]
fn a_force_at_a_nodes_site_is_the_concentrated_load_at_the_node() {
    let scene = Scene::two_section();
    let (robot, known) = (scene.robot().unwrap(), scene.loads().unwrap());
    let node = 20;
    let s_m = robot.node_arc()[node];
    let truth = LoadModel::Concentrated { node };
    let loads = truth.add_to(&robot, &known, &[0.01, -0.03]);
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[5, 10, 15, 20]).unwrap();
    let run = |load_model| {
        let settings = EstimatorSettings {
            load_model,
            alpha: Some(1e-6),
            ..EstimatorSettings::default()
        };
        let mut est = NewtonEstimator::new(&robot, &known, &settings).unwrap();
        est.step(&obs).unwrap()
    };
    let a = run(truth);
    let b = run(LoadModel::AtSite {
        site: Site::Rod { rod: 0, s_m },
    });
    assert!(a.report.status.is_converged());
    assert_eq!(a.f, b.f);
    assert_eq!(a.q, b.q);
    assert!((a.f[1] + 0.03).abs() < 1e-4, "{}", a.f);
    // the clamp does not move: a force there is refused up front
    let settings = EstimatorSettings {
        load_model: LoadModel::AtSite {
            site: Site::Rod { rod: 0, s_m: 0.0 },
        },
        ..EstimatorSettings::default()
    };
    let e = NewtonEstimator::new(&robot, &known, &settings).unwrap_err();
    assert_eq!(e.field(), Some("estimator.load_model"));
}

/// The parallel robot's payload (32)–(35) through the one estimator: a
/// force at the platform's site, from the platform marker, equals the
/// truth (a 10 g payload solved by the static solver), and its reported standard
/// deviations are those of the closed form `σ (C⁻¹ C⁻ᵀ)` of an exactly
/// determined linear estimate (`C` the compliance by a dense LU).
#[test]
fn the_parallel_payload_is_a_force_at_the_platform_site() {
    let robot = softrod::parallel::ParallelSpec::default()
        .build_full()
        .unwrap();
    let s = robot.structure();
    let known = robot.loads(&[], [0.0; 3], [0.0; 3]).unwrap();
    let truth = [0.0, 0.0, -0.0981];
    let loaded = robot
        .solve(&robot.loads(&[], truth, [0.0; 3]).unwrap(), None)
        .unwrap();
    let platform = Site::Body { body: 0 };
    let obs = Observation::of_sites(s, loaded.q.as_slice(), &[platform]).unwrap();
    let sigma = 1e-5;
    let settings = EstimatorSettings {
        load_model: LoadModel::AtSite { site: platform },
        alpha: Some(1e-12),
        noise_sigma_m: sigma,
        ..EstimatorSettings::default()
    };
    let mut est = NewtonEstimator::new(s, &known, &settings).unwrap();
    let e = est.step(&obs).unwrap();
    assert!(e.report.status.is_converged(), "{}", e.report);
    for k in 0..3 {
        assert!((e.f[k] - truth[k]).abs() < 1e-6, "{} vs {truth:?}", e.f);
    }
    let start = robot.solve(&known, None).unwrap();
    // the parallel robot's own entry point is this estimate
    let x = robot.platform_pose(loaded.q.as_slice()).unwrap();
    let p = robot
        .estimate_payload(
            &[],
            x.fixed_rows::<3>(0).into_owned(),
            sigma,
            Backend::Newton,
        )
        .unwrap();
    assert!(p.status.is_converged());
    assert!((p.force_n - nalgebra::Vector3::from_column_slice(e.f.as_slice())).amax() < 1e-9);
    assert!((p.mass_kg - 0.01).abs() < 1e-6, "{}", p.mass_kg);
    // σ of an exactly determined estimate: σ C⁻¹ row norms
    let eq = softrod::statics::Equilibrium {
        q: e.q.clone(),
        u: s.free_coordinates_of(e.q.as_slice()).unwrap(),
        report: start.report.clone(),
    };
    let c = robot
        .platform_compliance(&eq, &robot.loads(&[], truth, [0.0; 3]).unwrap())
        .unwrap();
    let ci = c.try_inverse().unwrap();
    let closed = (ci * ci.transpose()) * (sigma * sigma);
    let std = e.std_f();
    for k in 0..3 {
        let want = closed[(k, k)].sqrt();
        assert!(
            (std[k] - want).abs() < 0.02 * want,
            "σ_F[{k}] = {} against {want}",
            std[k]
        );
    }
}

/// The robot of `sections()` and the one-rod structure built from the same
/// sections, and markers at a third, two thirds and the tip of the robot's
/// equilibrium under a tip force of (0.01, −0.03) N and its weight.
fn robot_and_one_rod_structure_observed() -> (
    softrod::assembly::Robot<softrod::element::PlanarCable>,
    softrod::structure::Structure<softrod::element::PlanarCable>,
    Observation,
) {
    let robot = RobotSpec::new(sections()).build_planar().unwrap();
    let rod = RodSpec::clamped(sections(), Vector2::zeros(), Vector2::new(1.0, 0.0));
    let mut spec = StructureSpec::new(vec![rod], vec![], vec![]);
    spec.gravity_m_per_s2 = robot.spec().gravity_m_per_s2.clone();
    let structure = spec.build_planar().unwrap();
    let truth = Loads {
        point_forces: vec![PointForce {
            s_m: 0.24,
            force_n: vec![0.01, -0.03],
        }],
        ..Loads::default()
    };
    let eq = StaticSolver::default().solve(&robot, &truth, None).unwrap();
    let sites: Vec<Site> = [0.08, 0.16, 0.24]
        .map(|s_m| Site::Rod { rod: 0, s_m })
        .to_vec();
    let obs = Observation::of_sites(&robot, eq.q.as_slice(), &sites).unwrap();
    (robot, structure, obs)
}

/// The same estimate through the robot and through the one-rod structure
/// built from the same sections (a tip force of (0.01, −0.03) N under
/// weight, markers at a third, two thirds and the tip), iterated to the
/// optimum: force equal to 1e-9 and shape to 1e-10 relative, so the
/// estimator's generic path finds the robot's answer.
#[test]
fn the_one_rod_structure_estimates_the_robots_load() {
    let (robot, structure, obs) = robot_and_one_rod_structure_observed();
    let settings = EstimatorSettings {
        load_model: LoadModel::AtSite {
            site: Site::Rod { rod: 0, s_m: 0.24 },
        },
        alpha: Some(1e-6),
        // to the optimum, not to a tenth of its standard deviation: the
        // robot's cold estimate takes the far start, the structure's not
        statistical_tolerance: 0.0,
        ..EstimatorSettings::default()
    };
    let a = NewtonEstimator::new(&robot, &Loads::default(), &settings)
        .unwrap()
        .step(&obs)
        .unwrap();
    let known = StructureLoads {
        rods: vec![Loads::default()],
        ..StructureLoads::default()
    };
    let b = NewtonEstimator::new(&structure, &known, &settings)
        .unwrap()
        .step(&obs)
        .unwrap();
    assert!(a.report.status.is_converged(), "{}", a.report);
    let df = (&a.f - &b.f).amax() / a.f.amax();
    let dq = (&a.q - &b.q).amax() / 0.24;
    println!("one-rod structure vs robot: force {df:.1e}, shape {dq:.1e} (relative)");
    println!("robot: {}\nstructure: {}", a.report, b.report);
    assert!(b.report.status.is_converged(), "{}", b.report);
    assert!((a.f[1] + 0.03).abs() < 1e-4, "{}", a.f);
    // measured: force 2.7e-10, shape 1.1e-11 (the two stop at the tight
    // test's predicted decrease, 1e-15 of the objective's scale, at
    // different iterates)
    assert!(df < 1e-9 && dq < 1e-10, "{df:.1e} {dq:.1e}");
}

/// The sqp backend on a structure: the one-rod structure's estimate of the
/// robot's tip force (as above) by sqp is the robot's by sqp, with bounds
/// too (the tip force's y component bounded above by −0.031 N, active: the
/// bound's answer differs from the unbounded one).
#[test]
fn the_one_rod_structure_estimates_the_robots_load_by_sqp() {
    let (robot, structure, obs) = robot_and_one_rod_structure_observed();
    let obs = obs.with_noise(1e-4, 7);
    let known = StructureLoads {
        rods: vec![Loads::default()],
        ..StructureLoads::default()
    };
    let tip = Site::Rod { rod: 0, s_m: 0.24 };
    let bound = LoadBound {
        s_m: 0.24,
        frame: BoundFrame::World,
        direction: vec![0.0, 1.0],
        min_n_per_m: None,
        max_n_per_m: Some(-0.031),
    };
    let mut forces = Vec::new();
    for bounds in [vec![], vec![bound]] {
        let settings = EstimatorSettings {
            backend: Backend::Sqp,
            load_model: LoadModel::AtSite { site: tip },
            alpha: Some(1e-6),
            noise_sigma_m: 1e-4,
            statistical_tolerance: 0.0,
            bounds,
            ..EstimatorSettings::default()
        };
        let a = settings
            .build_for(&robot, &Loads::default())
            .unwrap()
            .step(&obs)
            .unwrap();
        let b = settings
            .build_for(&structure, &known)
            .unwrap()
            .step(&obs)
            .unwrap();
        assert!(a.report.status.is_converged(), "{}", a.report);
        assert!(b.report.status.is_converged(), "{}", b.report);
        let df = (&a.f - &b.f).amax() / a.f.amax();
        let dq = (&a.q - &b.q).amax() / 0.24;
        let dc = (a.covariance_f() - b.covariance_f()).amax() / a.covariance_f().amax();
        println!(
            "sqp, {} bounds: one-rod structure vs robot: force {df:.1e}, shape {dq:.1e}, covariance {dc:.1e}",
            settings.bounds.len()
        );
        assert!(
            df < 1e-8 && dq < 1e-9 && dc < 1e-6,
            "{df:.1e} {dq:.1e} {dc:.1e}"
        );
        forces.push(a.f.clone());
    }
    // the bound is active: F_y at its limit, the unbounded F_y above it
    assert!(forces[0][1] > -0.031 + 1e-4, "{}", forces[0]);
    assert!((forces[1][1] + 0.031).abs() < 1e-9, "{}", forces[1]);
}

/// The parallel robot's payload by both backends: the same estimate (force
/// and covariance), and with a bound the sqp backend's constrained least
/// squares. The platform is pushed up (a force against gravity, which no
/// payload makes); bounded to `F·ĝ ≥ 0` (a payload pulls along gravity),
/// the estimate is the least-squares force perpendicular to `g`, checked
/// against the platform compliance `C` (a dense LU of the tangent, another
/// code path): `F⊥ = argmin |C F⊥ − d|` over the plane `F·ĝ = 0`.
#[test]
fn the_parallel_payload_by_either_backend() {
    let robot = softrod::parallel::ParallelSpec::default()
        .build_cable()
        .unwrap();
    let s = robot.structure();
    let known = robot.loads(&[], [0.0; 3], [0.0; 3]).unwrap();
    let free = robot.solve(&known, None).unwrap();
    let x0 = robot.platform_pose(free.q.as_slice()).unwrap();
    // a 10 g payload: both backends give the same estimate
    let loaded = robot
        .solve(
            &robot.loads(&[], [0.0, 0.0, -0.0981], [0.0; 3]).unwrap(),
            None,
        )
        .unwrap();
    let x = robot.platform_pose(loaded.q.as_slice()).unwrap();
    let target = x.fixed_rows::<3>(0).into_owned();
    let n = robot
        .estimate_payload(&[], target, 5e-5, Backend::Newton)
        .unwrap();
    let q = robot
        .estimate_payload(&[], target, 5e-5, Backend::Sqp)
        .unwrap();
    println!("payload: newton {n:?}\n         sqp {q:?}");
    assert!(n.status.is_converged() && q.status.is_converged());
    assert!((n.force_n - q.force_n).amax() < 1e-9 * n.force_n.amax());
    assert!((n.std_n - q.std_n).amax() < 1e-6 * n.std_n.amax());
    assert!((q.mass_kg - 0.01).abs() < 1e-6, "{}", q.mass_kg);
    // pushed up and sideways by (0.02, 0, 0.05) N: bounded to F·ĝ ≥ 0
    let c = robot.platform_compliance(&free, &known).unwrap();
    let push = nalgebra::Vector3::new(0.02, 0.0, 0.05);
    let d = c * push;
    let target = x0.fixed_rows::<3>(0).into_owned() + d;
    let platform = Site::Body { body: 0 };
    let settings = EstimatorSettings {
        backend: Backend::Sqp,
        load_model: LoadModel::AtSite { site: platform },
        alpha: Some(1e-12),
        statistical_tolerance: 0.0,
        bounds: vec![LoadBound {
            s_m: 0.0,
            frame: BoundFrame::World,
            direction: vec![0.0, 0.0, -1.0],
            min_n_per_m: Some(0.0),
            max_n_per_m: None,
        }],
        ..EstimatorSettings::default()
    };
    let obs = Observation {
        markers: vec![MarkerObservation::at_site(
            &platform,
            target.as_slice().to_vec(),
        )],
    };
    let e = settings.build_for(s, &known).unwrap().step(&obs).unwrap();
    assert!(e.report.status.is_converged(), "{}", e.report);
    // the constrained least squares on the compliance: F = (a, b, 0)
    let c2 = c.fixed_columns::<2>(0).into_owned();
    let ab = (c2.transpose() * c2).try_inverse().unwrap() * c2.transpose() * d;
    let want = nalgebra::Vector3::new(ab[0], ab[1], 0.0);
    let got = nalgebra::Vector3::from_column_slice(e.f.as_slice());
    println!("bounded payload: {got:?} against {want:?} (unbounded: {push:?})");
    assert!(
        got[2].abs() < 1e-9,
        "F_z = {} must be at its bound 0",
        got[2]
    );
    assert!(
        (got - want).amax() < 1e-3 * want.amax(),
        "{got:?} vs {want:?}"
    );
    // and the newton backend refuses bounds
    let newton = EstimatorSettings {
        backend: Backend::Newton,
        ..settings
    };
    assert!(newton.build_for(s, &known).is_err());
}
