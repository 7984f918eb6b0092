//! Payload-mass estimation (Fig. 8): the concentrated-load model (32)–(35)
//! against a plant that is not the model, its Jacobian by finite
//! differences, bad input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::control::{MassEstimator, MassForce, MassReference, MassSettings, WeighingExperiment};
use softrod::scene::Scene;

#[test]
fn mass_jacobian_matches_finite_differences() {
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    for (load_s, p) in [
        (0.24, [60e3, 0.0, 0.0, 30e3]),
        (0.12, [0.0, 0.0, 50e3, 0.0]),
    ] {
        let mut est = MassEstimator::new(
            robot.clone(),
            scene.loads().unwrap(),
            load_s,
            &scene.gravity_m_per_s2,
            MassSettings::default(),
        )
        .unwrap();
        let f = [0.1, -0.6];
        let jac = est.jacobian(&p, &f).unwrap();
        let h = 1e-4; // N
        for c in 0..2 {
            let (mut fp, mut fm) = (f, f);
            fp[c] += h;
            fm[c] -= h;
            let (_, xp) = est.forward(&p, &fp).unwrap();
            let (_, xm) = est.forward(&p, &fm).unwrap();
            let scale = jac[(0, c)].abs().max(jac[(1, c)].abs());
            for r in 0..2 {
                let fd = (xp[r] - xm[r]) / (2.0 * h);
                assert!(
                    (fd - jac[(r, c)]).abs() <= 1e-6 * scale,
                    "s {load_s}: dx{r}/dF{c} fd {fd:e} vs {:e}",
                    jac[(r, c)]
                );
            }
        }
    }
}

#[test]
fn hanging_masses_are_estimated_within_5_g_in_three_configurations() {
    // a small seeded version of `examples/track_mass.rs`: the default plant
    // (finer mesh, EI +15 %, gain -10 %, EA -5 %, 0.05 mm noise, lag),
    // masses 0-200 g at the tip, calibrated once with 150 g (straight,
    // seed 99)
    let mut e = WeighingExperiment::paper_like(Scene::two_section());
    e.masses_kg = vec![0.0, 0.03, 0.07, 0.11, 0.16, 0.2];
    e.frames = 5;
    let t = e.run().unwrap();
    assert!(t.rows.iter().all(|r| r.converged));
    let mut raw_worst = 0.0f64;
    for c in 0..3 {
        let mean = t.mean_abs_error_kg(c, false);
        let raw = t.mean_abs_error_kg(c, true);
        println!(
            "{}: mean abs error {:.2} g (raw {:.2} g)",
            t.configurations[c].name,
            mean * 1e3,
            raw * 1e3
        );
        assert!(mean <= 5e-3, "configuration {c}: {mean} kg");
        raw_worst = raw_worst.max(raw);
    }
    // the plant is stiffer than the model: without the calibration the
    // masses come out ~13 % light
    assert!(raw_worst > 8e-3, "raw error only {raw_worst} kg");
    assert!((t.scale - 1.15).abs() < 0.05, "scale {}", t.scale);
}

#[test]
fn the_model_itself_as_plant_gives_the_mass_back() {
    // no plant error, no noise: the reference cases agree with the hung mass
    // (checks the estimator, not the experiment)
    let mut e = WeighingExperiment::paper_like(Scene::two_section());
    e.plant = softrod::plant::PlantSettings {
        mesh_factor: 1,
        ei_factor: 1.0,
        gain_factor: 1.0,
        ea_factor: 1.0,
        noise_sigma_m: 0.0,
        regulator_time_constant_s: 0.0,
        ..Default::default()
    };
    e.masses_kg = vec![0.05, 0.2];
    e.frames = 1;
    e.calibration = None;
    for reference in [
        MassReference::Relative,
        MassReference::Absolute,
        MassReference::Matched,
    ] {
        e.settings.reference = reference;
        let t = e.run().unwrap();
        for r in &t.rows {
            assert!(
                (r.estimated_kg - r.true_kg).abs() < 1e-6,
                "{reference:?}: {} vs {}",
                r.estimated_kg,
                r.true_kg
            );
        }
    }
}

#[test]
fn mass_bad_input_names_the_field() {
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let new = |s: f64, g: &[f64], settings: MassSettings| {
        MassEstimator::new(robot.clone(), scene.loads().unwrap(), s, g, settings)
    };
    let field = |e: softrod::Error| e.field().map(str::to_owned).unwrap();
    let g = &scene.gravity_m_per_s2;
    assert_eq!(
        field(new(0.3, g, MassSettings::default()).unwrap_err()),
        "mass.load_s_m"
    );
    assert_eq!(
        field(new(0.125, g, MassSettings::default()).unwrap_err()),
        "mass.load_s_m"
    );
    assert_eq!(
        field(new(0.0, g, MassSettings::default()).unwrap_err()),
        "mass.load_s_m"
    );
    assert_eq!(
        field(new(0.24, &[0.0, 0.0], MassSettings::default()).unwrap_err()),
        "gravity_m_per_s2"
    );
    let bad = MassSettings {
        scale: -1.0,
        ..Default::default()
    };
    assert_eq!(field(new(0.24, g, bad).unwrap_err()), "mass.scale");
    let mut est = new(0.24, g, MassSettings::default()).unwrap();
    let p = [0.0; 4];
    assert!(
        field(
            est.estimate(&p, &[0.24, f64::NAN], &[0.24, 0.0])
                .unwrap_err()
        )
        .starts_with("unloaded_m")
    );
    assert_eq!(
        field(
            est.calibrate(&p, &[0.24, 0.0], &[0.24, 0.0], 0.0)
                .unwrap_err()
        ),
        "known_kg"
    );
    assert!(
        field(
            est.estimate(&[200e3, 0.0, 0.0, 0.0], &[0.24, 0.0], &[0.24, 0.0])
                .unwrap_err()
        )
        .starts_with("pressures_pa")
    );
}

#[test]
fn the_weight_is_the_least_squares_weight_with_its_standard_deviation() {
    // the estimate through the one estimator (a force along gravity at the
    // load node, `LoadModel::Along`) checked on its answer with the forward
    // map and its Jacobian (finite-difference tested above): the residual
    // of the end effector is orthogonal to dx/dθ = J ĝ (the normal
    // equation of the one-parameter least squares), and σ_m = σ / (|J ĝ| |g|)
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let g = &scene.gravity_m_per_s2;
    let gn = (g[0] * g[0] + g[1] * g[1]).sqrt();
    for (load_s, p) in [
        (0.24, [60e3, 0.0, 0.0, 30e3]),
        (0.12, [80e3, 0.0, 60e3, 0.0]),
    ] {
        let sigma = 2e-5;
        let settings = MassSettings {
            noise_sigma_m: sigma,
            reference: MassReference::Absolute,
            ..MassSettings::default()
        };
        let mut est =
            MassEstimator::new(robot.clone(), scene.loads().unwrap(), load_s, g, settings).unwrap();
        let (_, x0) = est.forward(&p, &[0.0, 0.0]).unwrap();
        // 6 mm down and 3 mm sideways: no weight explains the sideways part
        let target = [x0[0] + 3e-3, x0[1] - 6e-3];
        let e = est.estimate(&p, x0.as_slice(), &target).unwrap();
        assert!(e.converged && e.mass_kg > 0.0, "{e:?}");
        // the misfit is 1-2 mm against 0.02 mm of noise: said so
        assert!(
            matches!(
                e.status,
                softrod::estimate::EstimateStatus::MisfitBeyondNoise { .. }
            ),
            "{}",
            e.status
        );
        let (_, x) = est.forward(&p, e.force_n.as_slice()).unwrap();
        let r = nalgebra::Vector2::new(target[0] - x[0], target[1] - x[1]);
        assert!(
            (r.norm() - e.residual_m).abs() < 1e-12,
            "{} {}",
            r.norm(),
            e.residual_m
        );
        let j = est.jacobian(&p, e.force_n.as_slice()).unwrap();
        let c = &j * nalgebra::dvector![g[0] / gn, g[1] / gn];
        let cos = c.dot(&nalgebra::dvector![r[0], r[1]]) / (c.norm() * r.norm());
        assert!(
            cos.abs() < 1e-6,
            "s {load_s}: cos(residual, dx/dθ) = {cos:e}"
        );
        assert!(r.norm() > 1e-4, "{}", r.norm());
        let std_kg = sigma / (c.norm() * gn);
        assert!(
            (e.std_kg - std_kg).abs() <= 1e-6 * std_kg,
            "std {} vs {std_kg}",
            e.std_kg
        );
        // the force is a weight: along gravity
        let cross = e.force_n[0] * g[1] - e.force_n[1] * g[0];
        assert!(cross.abs() <= 1e-12 * gn * e.force_n.iter().map(|v| v.abs()).sum::<f64>());
    }
}

#[test]
fn the_free_force_puts_the_end_effector_on_the_target() {
    // `MassForce::Free`: two force components from two coordinates, the
    // exactly determined estimate; its answer checked by the forward map
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let settings = MassSettings {
        force: MassForce::Free,
        reference: MassReference::Absolute,
        ..MassSettings::default()
    };
    let g = &scene.gravity_m_per_s2;
    let mut est = MassEstimator::new(robot, scene.loads().unwrap(), 0.24, g, settings).unwrap();
    let p = [60e3, 0.0, 0.0, 30e3];
    let (_, x0) = est.forward(&p, &[0.0, 0.0]).unwrap();
    let (_, xl) = est.forward(&p, &[0.05, -0.4]).unwrap();
    let e = est.estimate(&p, x0.as_slice(), xl.as_slice()).unwrap();
    assert!(e.status.is_converged(), "{}", e.status);
    assert!(e.residual_m < 1e-9, "{}", e.residual_m);
    assert!(
        (e.force_n[0] - 0.05).abs() < 1e-6 && (e.force_n[1] + 0.4).abs() < 1e-6,
        "{:?}",
        e.force_n
    );
    let (_, x) = est.forward(&p, e.force_n.as_slice()).unwrap();
    assert!((x - xl).norm() < 1e-9);
}
