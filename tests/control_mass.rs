//! Payload-mass estimation (Fig. 8): the concentrated-load model (32)–(35)
//! against a plant that is not the model, its Jacobian by finite
//! differences, bad input.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::control::{MassEstimator, MassReference, MassSettings, WeighingExperiment};
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
