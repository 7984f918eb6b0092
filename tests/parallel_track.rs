//! Tracking a platform circle on the soft parallel robot under an unknown
//! hanging mass (100 g), plant ≠ model (twice the model's elements, EI +15 %,
//! GJ +10 %, EA +2 %, chamber gain −10 %, σ = 0.05 mm on the platform
//! marker, one frame per instant): feedforward only misses by the payload's
//! and the model errors' displacement; feedforward + updater (31) tracks
//! within the target of 0.2 mm mean after settling.
//!
//! Small version of `examples/parallel_track.rs` (the full 20 s circle):
//! a 2 s hold (the updater settles: its error is within 5.5 % of the
//! initial one at 2 s) and 2 s of the circle at 10 Hz, scored from 2 s;
//! the model has 1 element per section, the plant (2 elements per section
//! from `elements_per_section = 1` doubled) 2.
#![allow(clippy::unwrap_used, clippy::expect_used, missing_docs)]

use softrod::control::parallel::{TrackSettings, run_track};
use softrod::control::{ControllerKind, EstimateFlag};
use softrod::parallel::ParallelSpec;

#[test]
fn updater_tracks_the_platform_within_0_2_mm_where_feedforward_misses() {
    let spec = ParallelSpec {
        elements_per_section: 1,
        ..ParallelSpec::default()
    };
    let settings = |controller| TrackSettings {
        controller,
        model_elements_per_section: 1,
        hold_s: 2.0,
        duration_s: 2.0,
        score_from_s: 2.0,
        ..TrackSettings::default()
    };
    let ff = run_track(&spec, &[], &settings(ControllerKind::Ff)).unwrap();
    let up = run_track(&spec, &[], &settings(ControllerKind::FfUpdater)).unwrap();
    let (a, b) = (&ff.summary, &up.summary);
    println!(
        "FF: mean {:.4} mm, max {:.4} mm; FF+updater: mean {:.4} mm, max {:.4} mm ({} samples, from {} s)",
        a.mean_error_m * 1e3,
        a.max_error_m * 1e3,
        b.mean_error_m * 1e3,
        b.max_error_m * 1e3,
        b.samples,
        b.score_from_s
    );
    // one per control instant after the first command: 4 s at 10 Hz
    assert_eq!(b.samples, 40);
    assert!(a.mean_error_m > 0.5e-3, "feedforward alone should miss");
    assert!(b.mean_error_m <= 0.2e-3, "the updater's target");
    assert!(b.max_error_m <= 0.4e-3);
    assert_eq!(b.ik_not_reached, 0);
    // the updater's load carries the payload's weight (and the model errors')
    let last = up.samples.last().unwrap();
    assert!(last.estimated_load_n[2] < -0.5);
    // every estimate of the run converged (none kept the last good one)
    let kept = up
        .samples
        .iter()
        .filter(|s| s.estimate != EstimateFlag::Converged)
        .count();
    assert_eq!(kept, 0, "estimates that kept the last good force");
}

/// The controller's estimator (the one estimator of every model, its
/// equilibria chord solves sharing the inverse kinematics' factors) finds
/// the force that put the model's platform where it is measured: a force
/// of the platform's own size applied to the model, its platform read
/// without noise, recovered to 1e-4 of its size (the estimator stops at a
/// step of a tenth of the tolerance, 1e-7 m, against a compliance of about
/// 1.4e-4 m/N); the feedforward controller estimates nothing.
#[test]
fn the_controllers_estimate_recovers_a_known_platform_force() {
    use softrod::control::parallel::{centre_pressures, controller};
    use softrod::plant::MarkerFrame;
    let spec = ParallelSpec {
        elements_per_section: 1,
        ..ParallelSpec::default()
    };
    let model = spec.build_full().unwrap();
    let p = centre_pressures(&spec);
    let force = [0.05, -0.03, -0.4];
    let loaded = model
        .solve(&model.loads(p.as_slice(), force, [0.0; 3]).unwrap(), None)
        .unwrap();
    let x = model.platform_pose(loaded.q.as_slice()).unwrap();
    let at = vec![x[0], x[1], x[2]];
    let frame = MarkerFrame {
        time_s: 0.1,
        positions_m: vec![at.clone()],
    };
    let settings = |controller| TrackSettings {
        controller,
        ..TrackSettings::default()
    };
    let mut lp = controller(
        model.clone(),
        &settings(ControllerKind::FfUpdater),
        p.as_slice(),
    )
    .unwrap();
    // the estimate is at the start pressures p (the command before it)
    let first = lp.control_step(&frame, &at, &at).unwrap();
    assert_eq!(first.estimate, EstimateFlag::Converged);
    let scale = force.iter().map(|v| v * v).sum::<f64>().sqrt();
    let err = (0..3)
        .map(|i| (first.f_bar[i] - force[i]).powi(2))
        .sum::<f64>()
        .sqrt();
    println!("estimated {:?} N against {force:?} N", first.f_bar);
    assert!(err <= 1e-4 * scale, "{:?} against {force:?}", first.f_bar);
    let mut ff = controller(model, &settings(ControllerKind::Ff), p.as_slice()).unwrap();
    let s = ff.control_step(&frame, &at, &at).unwrap();
    assert_eq!((s.estimate, s.f_bar), (EstimateFlag::NotRun, vec![0.0; 3]));
}

#[test]
fn bad_settings_name_their_field() {
    let spec = ParallelSpec::default();
    let bad = |s: TrackSettings| run_track(&spec, &[], &s).unwrap_err();
    let e = bad(TrackSettings {
        control_rate_hz: 0.0,
        ..TrackSettings::default()
    });
    assert_eq!(e.field(), Some("track.control_rate_hz"), "{e}");
    let e = bad(TrackSettings {
        payload_kg: -0.1,
        ..TrackSettings::default()
    });
    assert_eq!(e.field(), Some("track.payload_kg"), "{e}");
    let e = bad(TrackSettings {
        model_elements_per_section: 0,
        ..TrackSettings::default()
    });
    assert_eq!(e.field(), Some("track.model_elements_per_section"), "{e}");
    let e = run_track(&spec, &[1.0; 4], &TrackSettings::default()).unwrap_err();
    assert_eq!(e.field(), Some("pressures_pa"), "{e}");
    let e: Result<TrackSettings, _> = serde_json::from_str(r#"{"payload_kilos": 1}"#);
    assert!(e.unwrap_err().to_string().contains("payload_kilos"));
}

/// The platform's compliance and pressure Jacobian of the warm solver
/// against central differences of static solves.
#[test]
fn platform_sensitivities_match_finite_differences() {
    use softrod::parallel::warm::WarmStatics;
    let spec = ParallelSpec {
        elements_per_section: 1,
        ..ParallelSpec::default()
    };
    let robot = spec.build_full().unwrap();
    let mut p = softrod::control::parallel::centre_pressures(&spec)
        .as_slice()
        .to_vec();
    // every chamber inside its bounds, so central differences stay in them
    p.iter_mut()
        .enumerate()
        .for_each(|(k, v)| *v += 5e3 + 1e3 * k as f64);
    let f = [0.1, -0.2, -0.5];
    let loads = robot.loads(&p, f, [0.0; 3]).unwrap();
    let eq = robot.solve(&loads, None).unwrap();
    let mut warm = WarmStatics::new(robot.clone()).unwrap();
    warm.factor_at(eq.u.as_slice(), &loads).unwrap();
    let s = warm.sensitivities(eq.u.as_slice()).unwrap();
    let x = |p: &[f64], f: [f64; 3]| {
        let e = robot
            .solve(&robot.loads(p, f, [0.0; 3]).unwrap(), Some(eq.q.as_slice()))
            .unwrap();
        robot.platform_pose(e.q.as_slice()).unwrap()
    };
    let mut worst = 0.0f64;
    for j in 0..3 {
        let h = 1e-3;
        let (mut fp, mut fm) = (f, f);
        fp[j] += h;
        fm[j] -= h;
        let (a, b) = (x(&p, fp), x(&p, fm));
        for i in 0..3 {
            let fd = (a[i] - b[i]) / (2.0 * h);
            let an = s.compliance_m_per_n[(i, j)];
            worst = worst.max((fd - an).abs() / s.compliance_m_per_n.amax());
        }
    }
    println!("compliance: worst relative difference {worst:.2e}");
    assert!(worst < 1e-5);
    let mut worst = 0.0f64;
    for k in [0, 1, 4, 9, 17] {
        let h = 100.0;
        let (mut pp, mut pm) = (p.clone(), p.clone());
        pp[k] += h;
        pm[k] -= h;
        let (a, b) = (x(&pp, f), x(&pm, f));
        for i in 0..3 {
            let fd = (a[i] - b[i]) / (2.0 * h);
            let an = s.jacobian_m_per_pa[(i, k)];
            worst = worst.max((fd - an).abs() / s.jacobian_m_per_pa.amax());
        }
    }
    println!("pressure Jacobian: worst relative difference {worst:.2e}");
    assert!(worst < 1e-5);
}
