//! Where the closed loop fails (a small seeded version of the report's
//! grid, run as the report runs it: without the watchdog), and the rows
//! that end or interrupt a run: a plant whose equilibrium fails, the
//! watchdog set by hand; bad input of the loop and the sweep.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::control::{ClosedLoop, LoopSettings, StepStatus, Trajectory};
use softrod::plant::{MarkerFrame, Plant, PlantSettings, SimulatedPlant};
use softrod::report::loop_failure::{
    FailureSettings, LoopCase, LoopCause, LoopVerdict, plant_reach_m, run_case,
};
use softrod::scene::Scene;

fn scene() -> Scene {
    let mut s = Scene::two_section();
    s.pressures_pa = vec![45e3, 0.0, 45e3, 0.0];
    s
}

fn marker_arcs(scene: &Scene) -> Vec<f64> {
    let robot = scene.robot().unwrap();
    scene
        .markers
        .iter()
        .map(|m| robot.node_arc()[m.node.unwrap()])
        .collect()
}

#[test]
fn small_seeded_failure_grid_classifies_every_case() {
    let scene = scene();
    // 1 s of motion after the 3 s hold: the report runs 6 s
    let settings = FailureSettings {
        duration_s: 1.0,
        ..Default::default()
    };
    let case = |p: f64, e: f64, n: f64, r: f64| LoopCase {
        payload_weights: p,
        ei_error: e,
        noise_sigma_m: n,
        control_rate_hz: r,
        seed: 7,
    };
    let cases = [
        case(0.0, 0.15, 5e-5, 30.0),
        case(0.0, -0.3, 0.0, 5.0),
        case(1.0, 0.3, 1e-4, 15.0),
        case(5.0, -0.3, 5e-4, 60.0),
    ];
    let mut outcomes = vec![];
    for c in &cases {
        let o = run_case(&scene, c, &settings).unwrap();
        // the verdict and the cause agree; errors are finite when scored
        assert_eq!(
            o.verdict == LoopVerdict::Converged,
            o.cause == LoopCause::None,
            "{o:?}"
        );
        if let Some(e) = o.mean_error_m {
            assert!(e.is_finite() && e >= 0.0 && o.scored_steps > 0, "{o:?}");
            assert!(o.max_error_m.unwrap() >= e);
        }
        // the same seed gives the same outcome
        assert_eq!(run_case(&scene, c, &settings).unwrap(), o);
        outcomes.push(o);
    }
    // the tracking figure's conditions converge, within the target
    assert_eq!(
        outcomes[0].verdict,
        LoopVerdict::Converged,
        "{:?}",
        outcomes[0]
    );
    assert!(
        outcomes[0].mean_error_m.unwrap() < 0.3e-3,
        "{:?}",
        outcomes[0]
    );
    // a stiffness 30 % low at 5 Hz still converges
    assert_eq!(
        outcomes[1].verdict,
        LoopVerdict::Converged,
        "{:?}",
        outcomes[1]
    );
    // five times the robot's weight at the tip cannot be held: no watchdog
    // stops the run, it ends with its real cause, the inverse kinematics
    // at the pressure bounds every scored step
    let heavy = &outcomes[3];
    assert_eq!(heavy.verdict, LoopVerdict::Diverged);
    assert_eq!(heavy.cause, LoopCause::IkUnreachable, "{heavy:?}");
    assert_eq!(heavy.ik_not_reached, heavy.scored_steps, "{heavy:?}");
    assert!(heavy.mean_error_m.unwrap() > 0.1, "{heavy:?}");
    // and that cause is physical: the plant itself, with the true payload
    // and no model error, gets no closer to the path within the bounds than
    // the loop did; with the tracking figure's conditions it follows it
    let reach = plant_reach_m(&scene, &cases[3], &settings, 3).unwrap();
    assert!(reach > 0.1, "{reach}");
    assert!(
        heavy.max_error_m.unwrap() >= 0.95 * reach,
        "{heavy:?} {reach}"
    );
    assert!(plant_reach_m(&scene, &cases[0], &settings, 3).unwrap() < 1e-6);
    assert_eq!(
        plant_reach_m(&scene, &cases[0], &settings, 0)
            .unwrap_err()
            .field(),
        Some("points")
    );
}

/// A simulated plant whose equilibrium "fails" from frame `bad` on.
struct Failing {
    inner: SimulatedPlant,
    frame: usize,
    bad: usize,
}

impl Plant for Failing {
    fn n_pressures(&self) -> usize {
        self.inner.n_pressures()
    }
    fn command(&mut self, p: &[f64]) -> softrod::Result<()> {
        self.inner.command(p)
    }
    fn advance(&mut self, dt: f64) -> softrod::Result<MarkerFrame> {
        self.frame += 1;
        if self.frame >= self.bad {
            return Err(softrod::Error::InvalidParameter {
                name: "plant".into(),
                value: self.frame.to_string(),
                reason: "no equilibrium (simulated)".into(),
            });
        }
        self.inner.advance(dt)
    }
    fn time_s(&self) -> f64 {
        self.inner.time_s()
    }
}

#[test]
fn a_plant_failure_ends_the_run_with_a_row_and_the_watchdog_too() {
    let scene = scene();
    let robot = scene.robot().unwrap();
    let arcs = marker_arcs(&scene);
    let target = [0.1911, 0.1203];
    let traj = Trajectory::new(&[0.0, 2.0], &[nalgebra::Vector2::from(target); 2]).unwrap();
    let inner = SimulatedPlant::new(&scene, &arcs, PlantSettings::default()).unwrap();
    let mut plant = Failing {
        inner,
        frame: 0,
        bad: 31,
    };
    let mut lp = ClosedLoop::new(
        robot.clone(),
        scene.loads().unwrap(),
        &arcs,
        LoopSettings::default(),
    )
    .unwrap();
    let ts = lp
        .run(&mut plant, &traj, |p| p.inner.true_tip_m().ok())
        .unwrap();
    // 30 good rows, then the failure's row, then nothing
    assert_eq!(ts.samples.len(), 31);
    assert!(ts.samples[..30].iter().all(|s| s.status.is_ok()));
    let last = ts.samples.last().unwrap();
    let StepStatus::PlantFailed { message } = &last.status else {
        panic!("{:?}", last.status)
    };
    assert!(message.contains("no equilibrium (simulated)"), "{message}");
    assert!((ts.plant_failed_at_s().unwrap() - 31.0 / 30.0).abs() < 1e-9);
    // the failed row's tip is not scored
    assert_eq!(ts.errors_after(0.0).len(), 30);
    assert!(last.pressures_pa.iter().all(|p| p.is_finite()));
    // the watchdog: a limit no real tip meets stops at the first frame
    let mut plant = SimulatedPlant::new(&scene, &arcs, PlantSettings::default()).unwrap();
    let settings = LoopSettings {
        abort_error_m: Some(1e-9),
        ..Default::default()
    };
    let mut lp = ClosedLoop::new(robot, scene.loads().unwrap(), &arcs, settings).unwrap();
    let ts = lp
        .run(&mut plant, &traj, |_| None::<nalgebra::Vector2<f64>>)
        .unwrap();
    assert_eq!(ts.samples.len(), 1);
    assert!(
        matches!(ts.samples[0].status, StepStatus::Aborted { error_m } if error_m > 1e-9),
        "{:?}",
        ts.samples[0].status
    );
}

#[test]
fn loop_and_sweep_bad_input_names_the_field() {
    let field = |e: softrod::Error| {
        e.field()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("{e}"))
    };
    // the loop's settings name the path of a trajectory file
    let mut s = LoopSettings::default();
    s.gains.k_p_per_s = 0.0;
    assert_eq!(field(s.validate().unwrap_err()), "loop.gains.k_p_per_s");
    let mut s = LoopSettings::default();
    s.gains.k_i_per_s2 = f64::NAN;
    assert_eq!(field(s.validate().unwrap_err()), "loop.gains.k_i_per_s2");
    for a in [0.0, -1.0, f64::INFINITY] {
        let s = LoopSettings {
            abort_error_m: Some(a),
            ..Default::default()
        };
        assert_eq!(field(s.validate().unwrap_err()), "loop.abort_error_m");
    }
    let s = LoopSettings {
        ik: softrod::control::IkSettings {
            tolerance_m: -1.0,
            ..Default::default()
        },
        ..Default::default()
    };
    assert_eq!(field(s.validate().unwrap_err()), "loop.ik.tolerance_m");
    for (ik, name) in [
        (
            softrod::control::IkSettings {
                trial_max_total_iterations: 0,
                ..Default::default()
            },
            "loop.ik.trial_max_total_iterations",
        ),
        (
            softrod::control::IkSettings {
                max_static_iterations: 0,
                ..Default::default()
            },
            "loop.ik.max_static_iterations",
        ),
    ] {
        let s = LoopSettings {
            ik,
            ..Default::default()
        };
        assert_eq!(field(s.validate().unwrap_err()), name);
    }
    // a trajectory shorter than one control interval
    let scene = scene();
    let robot = scene.robot().unwrap();
    let arcs = marker_arcs(&scene);
    let mut plant = SimulatedPlant::new(&scene, &arcs, PlantSettings::default()).unwrap();
    let mut lp = ClosedLoop::new(
        robot,
        scene.loads().unwrap(),
        &arcs,
        LoopSettings::default(),
    )
    .unwrap();
    for traj in [
        Trajectory::new(&[0.0], &[nalgebra::Vector2::new(0.19, 0.12)]).unwrap(),
        Trajectory::new(&[0.0, 0.01], &[nalgebra::Vector2::new(0.19, 0.12); 2]).unwrap(),
    ] {
        assert_eq!(
            field(
                lp.run(&mut plant, &traj, |_| None::<nalgebra::Vector2<f64>>)
                    .unwrap_err()
            ),
            "trajectory.times_s"
        );
    }
    // the sweep's cases
    let settings = FailureSettings::default();
    for (c, name) in [
        (
            LoopCase {
                payload_weights: -1.0,
                ..LoopCase::nominal()
            },
            "case.payload_weights",
        ),
        (
            LoopCase {
                ei_error: -1.0,
                ..LoopCase::nominal()
            },
            "case.ei_error",
        ),
        (
            LoopCase {
                noise_sigma_m: f64::NAN,
                ..LoopCase::nominal()
            },
            "case.noise_sigma_m",
        ),
        (
            LoopCase {
                control_rate_hz: 0.0,
                ..LoopCase::nominal()
            },
            "loop.control_rate_hz",
        ),
        (
            LoopCase {
                control_rate_hz: 20e3,
                ..LoopCase::nominal()
            },
            "loop.control_rate_hz",
        ),
    ] {
        assert_eq!(field(run_case(&scene, &c, &settings).unwrap_err()), name);
    }
}
