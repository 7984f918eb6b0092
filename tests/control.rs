//! The controller: inverse kinematics (Jacobian and (43) by finite
//! differences, a target at a pressure bound, an unreachable target), the
//! updater (31) against its closed-form step response, a short closed loop
//! against a plant that is not the model, and bad input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::control::{
    ClosedLoop, ControllerKind, EstimateFlag, IkSettings, IkStatus, InverseKinematics,
    LoopSettings, ParameterUpdater, PressureBound, Trajectory, UpdaterGains,
};
use softrod::plant::{MarkerFrame, PayloadSchedule, Plant, PlantSettings, SimulatedPlant};
use softrod::scene::Scene;

fn setup() -> (
    Scene,
    InverseKinematics<softrod::assembly::Robot<softrod::element::PlanarCable>>,
) {
    let scene = Scene::two_section();
    let ik = InverseKinematics::new(
        scene.robot().unwrap(),
        scene.loads().unwrap(),
        IkSettings::default(),
    )
    .unwrap();
    (scene, ik)
}

fn marker_arcs(scene: &Scene) -> Vec<f64> {
    let robot = scene.robot().unwrap();
    scene
        .markers
        .iter()
        .map(|m| robot.node_arc()[m.node.unwrap()])
        .collect()
}

/// A load field that is not zero: a uniform 0.5 N/m downward and a bit sideways.
fn some_load(n: usize) -> Vec<f64> {
    let mut f = vec![0.0; n];
    f.iter_mut().step_by(4).for_each(|w| *w = 0.2);
    f.iter_mut().skip(1).step_by(4).for_each(|w| *w = -0.5);
    f
}

#[test]
fn ik_jacobian_and_dq_dp_match_finite_differences() {
    let (_, mut ik) = setup();
    let n = ik.robot().n_q();
    let f = some_load(n);
    let p = [35e3, 5e3, 10e3, 40e3];
    let (q, _) = ik.forward(&p, &f, None).unwrap();
    let jac = ik.jacobian(q.as_slice(), &p, &f).unwrap();
    let dqdp = ik.dq_dp(q.as_slice(), &p, &f).unwrap();
    let h = 10.0; // Pa
    let mut worst_q = 0.0f64;
    for c in 0..4 {
        let (mut pp, mut pm) = (p, p);
        pp[c] += h;
        pm[c] -= h;
        let (qp, xp) = ik.forward(&pp, &f, Some(q.as_slice())).unwrap();
        let (qm, xm) = ik.forward(&pm, &f, Some(q.as_slice())).unwrap();
        for k in 0..2 {
            let fd = (xp[k] - xm[k]) / (2.0 * h);
            assert!(
                (fd - jac[(k, c)]).abs() <= 1e-6 * jac.column(c).amax() + 1e-14,
                "x{k}/P{c}: fd {fd:e} vs {:e}",
                jac[(k, c)]
            );
        }
        let col_max = dqdp.column(c).amax();
        for i in 0..n {
            let fd = (qp[i] - qm[i]) / (2.0 * h);
            worst_q = worst_q.max((fd - dqdp[(i, c)]).abs() / col_max);
        }
    }
    assert!(worst_q < 1e-6, "dq/dP vs finite differences: {worst_q:e}");
}

#[test]
fn ik_reaches_targets_with_chambers_at_their_bounds_exactly() {
    let (_, mut ik) = setup();
    let n = ik.robot().n_q();
    let zero = vec![0.0; n];
    // a target made by section 1 at its maximum pressure; the least sum of
    // squares puts each antagonist exactly on its lower bound
    let p_true = [100e3, 0.0, 20e3, 0.0];
    let (q_t, x_t) = ik.forward(&p_true, &zero, None).unwrap();
    let sol = ik.solve(x_t.as_slice(), &zero).unwrap();
    assert!(sol.status.is_reached(), "{:?}", sol.status);
    assert!(sol.status.error_m() < 1e-7);
    assert!(
        (sol.pressures_pa[0] - 100e3).abs() < 1.0,
        "{:?}",
        sol.pressures_pa
    );
    assert!(
        (sol.pressures_pa[2] - 20e3).abs() < 1.0,
        "{:?}",
        sol.pressures_pa
    );
    for c in [1, 3] {
        assert_eq!(sol.pressures_pa[c], 0.0);
        assert_eq!(sol.bounds[c], PressureBound::Min);
    }
    // equilibrium holds at the solution: the tip is where the IK says
    let (_, x) = ik
        .forward(sol.pressures_pa.as_slice(), &zero, None)
        .unwrap();
    assert!((x[0] - sol.effector_m[0]).abs() < 1e-12 && (x[1] - sol.effector_m[1]).abs() < 1e-12);
    // 2 mm further in the direction more pressure in chamber 0 would move the
    // tip: the closest pose has chamber 0 exactly at its maximum
    let jac = ik.jacobian(q_t.as_slice(), &p_true, &zero).unwrap();
    let dir = jac.column(0).normalize();
    let beyond = [x_t[0] + 2e-3 * dir[0], x_t[1] + 2e-3 * dir[1]];
    let sol = ik.solve(&beyond, &zero).unwrap();
    let IkStatus::Unreachable { distance_m } = sol.status else {
        panic!("expected unreachable, got {:?}", sol.status);
    };
    assert!(
        distance_m > 0.0 && distance_m <= 2e-3 + 1e-9,
        "{distance_m}"
    );
    assert_eq!(sol.pressures_pa[0], 100e3);
    assert_eq!(sol.bounds[0], PressureBound::Max);
}

#[test]
fn ik_with_a_load_field_compensates_it() {
    let (_, mut ik) = setup();
    let n = ik.robot().n_q();
    let f = some_load(n);
    let target = [0.21, 0.095];
    let sol = ik.solve(&target, &f).unwrap();
    assert!(sol.status.is_reached(), "{:?}", sol.status);
    let (_, x) = ik.forward(sol.pressures_pa.as_slice(), &f, None).unwrap();
    assert!((x[0] - target[0]).abs() < 1e-7 && (x[1] - target[1]).abs() < 1e-7);
    // without the load the same pressures miss the target by millimetres
    let (_, x0) = ik
        .forward(sol.pressures_pa.as_slice(), &vec![0.0; n], None)
        .unwrap();
    assert!(((x0[0] - target[0]).powi(2) + (x0[1] - target[1]).powi(2)).sqrt() > 1e-3);
}

#[test]
fn unreachable_target_gives_the_closest_pose_with_its_status() {
    let (_, mut ik) = setup();
    let n = ik.robot().n_q();
    let zero = vec![0.0; n];
    let target = [0.30, 0.0]; // beyond the robot's 0.24 m
    let sol = ik.solve(&target, &zero).unwrap();
    let IkStatus::Unreachable { distance_m } = sol.status else {
        panic!("expected unreachable, got {:?}", sol.status);
    };
    let d =
        ((sol.effector_m[0] - target[0]).powi(2) + (sol.effector_m[1] - target[1]).powi(2)).sqrt();
    assert!((d - distance_m).abs() < 1e-12);
    for (p, (lo, hi)) in sol.pressures_pa.iter().zip(ik.robot().pressure_bounds()) {
        assert!(*p >= lo && *p <= hi);
    }
    // no pose on a grid of pressures comes closer
    let mut best = f64::INFINITY;
    for a in [0.0, 25e3, 50e3, 100e3] {
        for b in [0.0, 25e3, 50e3, 100e3] {
            for (p1, p2) in [(a, 0.0), (0.0, a)] {
                let (_, x) = ik.forward(&[p1, p2, b, 0.0], &zero, None).unwrap();
                best = best.min(((x[0] - target[0]).powi(2) + (x[1] - target[1]).powi(2)).sqrt());
            }
        }
    }
    assert!(distance_m <= best + 1e-9, "IK {distance_m} vs grid {best}");
}

#[test]
fn updater_step_response_is_the_closed_form() {
    // e(t) = e0 (1 - 2t) exp(-2t) for K_P = K_I = 4, F_hat at rest at 0, F_bar = e0
    for rate in [30.0, 1000.0] {
        let dt = 1.0 / rate;
        let e0 = 2.5;
        let mut u = ParameterUpdater::new(1, UpdaterGains::default(), dt).unwrap();
        let mut min_e = f64::INFINITY;
        let mut t_min = 0.0;
        let mut last_outside = 0.0;
        for k in 1..=(6.0 * rate) as usize {
            let t = k as f64 * dt;
            let e = e0 - u.step(&[e0]).unwrap()[0];
            let exact = e0 * (1.0 - 2.0 * t) * (-2.0 * t).exp();
            assert!((e - exact).abs() < 1e-11, "t {t}: {e} vs {exact}");
            if e < min_e {
                min_e = e;
                t_min = t;
            }
            if e.abs() > 0.02 * e0 {
                last_outside = t;
            }
        }
        // undershoot e^-2 = 13.5 % at t = 1 s; within 2 % from 2.70 s on
        assert!(
            (min_e / e0 + (-2.0f64).exp()).abs() < 1e-3,
            "{}",
            min_e / e0
        );
        assert!((t_min - 1.0).abs() <= dt);
        assert!(
            (last_outside + dt - 2.70).abs() < 0.01 + dt,
            "2 % settling at {}",
            last_outside + dt
        );
    }
}

/// A plant whose markers are NaN in one frame (a camera dropout).
struct Dropout {
    inner: SimulatedPlant,
    frame: usize,
    bad: usize,
}

impl Plant for Dropout {
    fn n_pressures(&self) -> usize {
        self.inner.n_pressures()
    }
    fn command(&mut self, p: &[f64]) -> softrod::Result<()> {
        self.inner.command(p)
    }
    fn advance(&mut self, dt: f64) -> softrod::Result<MarkerFrame> {
        let mut f = self.inner.advance(dt)?;
        self.frame += 1;
        if self.frame == self.bad {
            f.positions_m
                .iter_mut()
                .flatten()
                .for_each(|v| *v = f64::NAN);
        }
        Ok(f)
    }
    fn time_s(&self) -> f64 {
        self.inner.time_s()
    }
}

#[test]
fn closed_loop_converges_against_a_plant_with_errors_and_survives_a_dropout() {
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let arcs = marker_arcs(&scene);
    // hold a point for 4 s: the plant has EI +15 %, gain -10 %, EA -5 %, a
    // finer mesh, a 10 g tip mass, noise and lag
    let target = [0.21, 0.095];
    let traj = Trajectory::new(&[0.0, 4.0], &[nalgebra::Vector2::from(target); 2]).unwrap();
    let plant_settings = PlantSettings {
        payloads: PayloadSchedule::tip_mass(0.01, 0.24),
        ..Default::default()
    };
    let mut errors = vec![];
    for controller in [ControllerKind::Ff, ControllerKind::FfUpdater] {
        let inner = SimulatedPlant::new(&scene, &arcs, plant_settings.clone()).unwrap();
        let mut plant = Dropout {
            inner,
            frame: 0,
            bad: 60,
        };
        let settings = LoopSettings {
            controller,
            ..Default::default()
        };
        let mut lp =
            ClosedLoop::new(robot.clone(), scene.loads().unwrap(), &arcs, settings).unwrap();
        let ts = lp
            .run(&mut plant, &traj, |p| p.inner.true_tip_m().ok())
            .unwrap();
        assert_eq!(ts.samples.len(), 120);
        assert!(ts.samples.iter().all(|s| s.ik.is_reached()));
        let (mean, _) = ts.mean_max_after(3.0);
        errors.push(mean);
        if controller == ControllerKind::FfUpdater {
            // the dropout frame kept the last good estimate and said so
            let s = &ts.samples[59];
            assert!(
                matches!(s.estimate, EstimateFlag::KeptLast { .. }),
                "{:?}",
                s.estimate
            );
            assert_eq!(s.f_bar_resultant_n, ts.samples[58].f_bar_resultant_n);
            assert!(
                ts.samples
                    .iter()
                    .filter(|s| s.estimate == EstimateFlag::Converged)
                    .count()
                    >= 118
            );
        }
    }
    let (ff, upd) = (errors[0], errors[1]);
    assert!(
        ff > 5e-3,
        "feedforward error only {ff} m: the plant is too close to the model"
    );
    assert!(
        upd < 0.3e-3,
        "with the updater: mean error {upd} m after 3 s (feedforward {ff} m)"
    );
}

#[test]
fn bad_input_is_a_typed_error_naming_the_field() {
    let field = |e: softrod::Error| {
        e.field()
            .map(str::to_owned)
            .unwrap_or_else(|| format!("{e}"))
    };
    // trajectories
    assert_eq!(
        field(Trajectory::new::<2>(&[], &[]).unwrap_err()),
        "trajectory.times_s"
    );
    let e = Trajectory::new(
        &[0.0, 1.0],
        &[
            nalgebra::Vector2::new(0.2, 0.0),
            nalgebra::Vector2::new(f64::NAN, 0.0),
        ],
    )
    .unwrap_err();
    assert_eq!(field(e), "trajectory.points_m[1]");
    let e = Trajectory::new(&[0.0, 1.0, 0.5], &[nalgebra::Vector2::new(0.2, 0.0); 3]).unwrap_err();
    assert_eq!(field(e), "trajectory.times_s[2]");
    // control rate and gains
    for r in [0.0, -30.0, 20e3, f64::NAN] {
        let s = LoopSettings {
            control_rate_hz: r,
            ..Default::default()
        };
        assert_eq!(field(s.validate().unwrap_err()), "loop.control_rate_hz");
    }
    for (kp, ki, name) in [
        (0.0, 4.0, "updater.k_p_per_s"),
        (4.0, -1.0, "updater.k_i_per_s2"),
    ] {
        let g = UpdaterGains {
            k_p_per_s: kp,
            k_i_per_s2: ki,
        };
        assert_eq!(field(ParameterUpdater::new(1, g, 0.1).unwrap_err()), name);
    }
    // the inverse kinematics
    let (scene, mut ik) = setup();
    let n = ik.robot().n_q();
    assert!(field(ik.solve(&[f64::NAN, 0.1], &vec![0.0; n]).unwrap_err()).starts_with("x_d"));
    assert!(
        field(ik.solve(&[0.2, 0.1], &vec![f64::INFINITY; n]).unwrap_err()).starts_with("f_hat")
    );
    let mut loads = scene.loads().unwrap();
    loads.pressures_pa[2] = 150e3;
    let e =
        InverseKinematics::new(scene.robot().unwrap(), loads, IkSettings::default()).unwrap_err();
    assert_eq!(field(e), "pressures_pa[2]");
    // the loop: a trajectory of another dimension, no markers
    let robot = scene.robot().unwrap();
    let arcs = marker_arcs(&scene);
    let mut lp = ClosedLoop::new(
        robot.clone(),
        scene.loads().unwrap(),
        &arcs,
        LoopSettings::default(),
    )
    .unwrap();
    let mut plant = SimulatedPlant::new(&scene, &arcs, PlantSettings::default()).unwrap();
    let t3 = Trajectory::new(&[0.0, 1.0], &[nalgebra::Vector3::new(0.2, 0.0, 0.0); 2]).unwrap();
    assert_eq!(
        field(
            lp.run(&mut plant, &t3, |_| None::<nalgebra::Vector2<f64>>)
                .unwrap_err()
        ),
        "trajectory.points_m[0]"
    );
    let e =
        ClosedLoop::new(robot, scene.loads().unwrap(), &[], LoopSettings::default()).unwrap_err();
    assert_eq!(field(e), "markers");
}

#[test]
fn virtual_payload_recorded_without_payload_leaves_the_real_one() {
    // Fig. 5: against a plant with model error the estimator reports a load
    // on the unloaded robot; recorded along a payload-free run (keyed by the
    // desired tip position) and subtracted, a 20 g tip mass remains
    use softrod::control::VirtualPayload;
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let arcs = marker_arcs(&scene);
    let c = [0.1911, 0.1203];
    let traj = Trajectory::line(
        nalgebra::Vector2::new(c[0] - 0.003, c[1] - 0.003),
        nalgebra::Vector2::new(c[0] + 0.003, c[1] + 0.003),
        8.0,
        8.0,
        2.0,
    )
    .unwrap();
    let run = |payloads: PayloadSchedule| {
        let settings = PlantSettings {
            payloads,
            ..Default::default()
        };
        let mut plant = SimulatedPlant::new(&scene, &arcs, settings).unwrap();
        let mut lp = ClosedLoop::new(
            robot.clone(),
            scene.loads().unwrap(),
            &arcs,
            LoopSettings::default(),
        )
        .unwrap();
        let ts = lp
            .run(&mut plant, &traj, |_| None::<nalgebra::Vector2<f64>>)
            .unwrap();
        (lp, ts)
    };
    let (_, free) = run(PayloadSchedule::none());
    let mut vp = VirtualPayload::new(4).unwrap();
    for s in free.samples.iter().filter(|s| s.time_s >= 1.0) {
        vp.record(&s.desired_m, &s.f_bar).unwrap();
    }
    let (lp, loaded) = run(PayloadSchedule::tip_mass(0.02, 0.24));
    let weight = -0.02 * 9.81;
    let (mut raw, mut sub, mut k) = (0.0, 0.0, 0.0);
    for s in loaded.samples.iter().filter(|s| s.time_s >= 2.0) {
        raw += s.f_bar_resultant_n[1];
        sub += lp.resultant(vp.subtract(&s.desired_m, &s.f_bar).unwrap().as_slice())[1];
        k += 1.0;
    }
    let (raw, sub) = (raw / k, sub / k);
    let virtual_y = raw - sub;
    println!(
        "resultant y: estimated {raw:.4} N, minus the virtual payload {sub:.4} N, true {weight:.4} N"
    );
    assert!(
        virtual_y.abs() > 0.02,
        "the virtual payload is only {virtual_y} N"
    );
    assert!(
        (sub - weight).abs() < 0.25 * weight.abs(),
        "payload {sub} N vs {weight} N (raw {raw} N)"
    );
    assert!((sub - weight).abs() < (raw - weight).abs());
}
