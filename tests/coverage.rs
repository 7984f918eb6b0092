//! The reported uncertainty means what it says: the true resultant force
//! of a load the estimator is not told about lies in the reported 95 %
//! region at about the nominal rate. The truth comes from a "real robot"
//! that is not the estimator's model (a mesh twice as fine, markers between
//! the coarse nodes): see `softrod::report::coverage`. The full study (200
//! trials per family, both backends) is `softrod report --only coverage`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::Error;
use softrod::estimate::MarkerObservation;
use softrod::estimate::{AlphaRule, Backend, EstimateStatus, EstimatorSettings, Observation};
use softrod::report::coverage::{Family, sweep};
use softrod::scene::Scene;

/// The full study of `softrod report --only coverage` (3.6 s in release on
/// a loaded 2-core machine): 200 seeded trials per load family (3–11
/// markers, 5–100 µm noise), both backends, `α` by the evidence. Smooth
/// loads: the truth lies in the reported 95 % ellipse in 90–99 % of the
/// trials (measured 93.0 %; the committed figure of an earlier main 92.5 %;
/// the posterior at the evidence's `α` without `α`'s own uncertainty
/// covered 89 %, the bias-blind covariance with the discrepancy principle
/// 20.5 %), the median squared distance near χ²₂'s median 1.39. Point loads
/// (not in the distributed model's span): the same 90–99 % (measured 94.5 %;
/// before 90 %). The backends agree to 1 %.
#[test]
fn loads_are_covered_at_about_the_nominal_rate() {
    let r = sweep(
        200,
        1,
        &[Backend::Newton, Backend::Sqp],
        &[Family::Smooth, Family::Point],
        AlphaRule::Evidence,
        true,
    )
    .unwrap();
    eprint!("{}", r.markdown());
    assert_eq!(r.rows.len(), 4);
    for row in &r.rows {
        assert_eq!(row.converged, 200, "{row:?}");
        match row.family {
            Family::Smooth => {
                assert!(
                    (0.90..=0.99).contains(&row.coverage),
                    "{:?}: coverage {}",
                    row.backend,
                    row.coverage
                );
                assert!(
                    (0.7..=2.8).contains(&row.median_d2),
                    "median d² {}",
                    row.median_d2
                );
            }
            Family::Point => assert!(
                (0.90..=0.99).contains(&row.coverage),
                "{:?}: coverage {}",
                row.backend,
                row.coverage
            ),
            f => panic!("{f:?}: not in this sweep"),
        }
    }
    readme_table_is_this_study(&r.markdown());
    // The one gross miss of the study (smooth trial 175: 5 markers that the
    // true 0.065 N load moves by 0.16–1.06 σ; estimate ≈ 0 ± 3.8e-5 N,
    // d² ≈ 3e6) is said to be weakly informed (γ ≈ 5e-4), and no other
    // trial is (the next smallest γ is 0.86).
    let flagged: Vec<(Family, u64)> = r
        .outcomes
        .iter()
        .filter(|o| o.weakly_informed)
        .map(|o| (o.family, o.seed))
        .collect();
    assert_eq!(
        flagged,
        vec![(Family::Smooth, 175), (Family::Smooth, 175)],
        "weakly informed trials"
    );
    for o in &r.outcomes {
        assert!(
            o.d2 <= 1e4 || o.weakly_informed,
            "a gross miss not flagged: {o:?}"
        );
    }
    for fam in [Family::Smooth, Family::Point] {
        let c: Vec<f64> = r
            .rows
            .iter()
            .filter(|row| row.family == fam)
            .map(|row| row.coverage)
            .collect();
        assert!((c[0] - c[1]).abs() <= 0.01, "{fam:?}: {c:?}");
    }
}

/// The README's coverage table is the one this study gives: the counts and
/// coverages exactly, the medians to their last printed digit. After a
/// change that moves them, rerun `softrod report --only coverage --out
/// validation/figures` and copy its table into the README.
fn readme_table_is_this_study(markdown: &str) {
    let readme = include_str!("../README.md");
    let cells = |line: &str| -> Vec<String> {
        line.trim_matches('|')
            .split('|')
            .map(|c| c.trim().to_string())
            .collect()
    };
    for row in markdown.lines().skip(2) {
        let want = cells(row);
        let key = format!("| {} | {} |", want[0], want[1]);
        let line = readme
            .lines()
            .find(|l| l.starts_with(&key))
            .unwrap_or_else(|| panic!("README: no coverage row `{key}`"));
        let got = cells(line);
        assert_eq!(got[..7], want[..7], "README row `{line}`, study `{row}`");
        for k in [7, 8] {
            let num = |c: &str| c.trim_end_matches(" %").parse::<f64>().unwrap();
            assert!(
                (num(&got[k]) - num(&want[k])).abs() <= 0.011,
                "README row `{line}`, study `{row}`"
            );
        }
    }
}

/// A single marker at the clamped base sees no load: the status says so
/// (not converged knowledge) and the standard deviation is the prior's,
/// not zero; for both backends and both rules.
#[test]
fn a_marker_at_the_clamped_base_is_no_information() {
    let scene = Scene::two_section();
    let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    let obs = Observation {
        markers: vec![MarkerObservation::at_arc(0.0, nalgebra::Vector2::zeros())],
    };
    for backend in [Backend::Newton, Backend::Sqp] {
        for rule in [AlphaRule::Evidence, AlphaRule::Discrepancy] {
            let settings = EstimatorSettings {
                alpha_rule: rule,
                ..EstimatorSettings::default()
            };
            let e = softrod::estimate::EstimatorSettings {
                backend,
                ..settings
            }
            .build_for(&robot, &loads)
            .unwrap()
            .step(&obs)
            .unwrap();
            assert_eq!(
                e.report.status,
                EstimateStatus::NoInformation,
                "{backend:?} {rule:?}"
            );
            assert!(e.resultant_force_cov()[0] > 0.0 && e.resultant_force_cov()[3] > 0.0);
            assert!(matches!(
                e.converged(),
                Err(Error::EstimateNotConverged { .. })
            ));
        }
    }
}

/// Markers that barely see the load: the evidence then makes the prior as
/// narrow as the data allow, so the estimate sits near zero with a tiny σ
/// whatever the load is. The estimate says so (`weakly_informed`, fewer
/// than 0.5 load directions determined) instead of passing the tiny σ off
/// as knowledge; `softrod estimate` warns on stderr and in the JSON.
#[test]
fn markers_that_barely_see_the_load_say_so() {
    // the coverage study's worst trial, both backends
    let r = sweep(
        1,
        175,
        &[Backend::Newton, Backend::Sqp],
        &[Family::Smooth],
        AlphaRule::Evidence,
        true,
    )
    .unwrap();
    for o in &r.outcomes {
        assert!(o.converged && !o.covered && o.d2 > 1e6, "{o:?}");
        assert!(o.weakly_informed && o.determined_directions < 0.01, "{o:?}");
    }
    // one marker 3 mm from the clamp, where no load the prior allows
    // moves it by its noise
    let text = include_str!("../examples/two_section.json");
    let scene = Scene::from_json(text).unwrap();
    let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    let q = softrod::statics::StaticSolver::new(scene.solver.statics.clone())
        .unwrap()
        .solve(&robot, &loads, None)
        .unwrap()
        .q;
    let p: Vec<f64> = robot.position_at(q.as_slice(), 0.003).unwrap().data.into();
    let obs = Observation {
        markers: vec![MarkerObservation::at_arc(
            0.003,
            nalgebra::DVector::from_column_slice(&p),
        )],
    };
    for backend in [Backend::Newton, Backend::Sqp] {
        let e = EstimatorSettings {
            backend,
            ..scene.estimator_settings().unwrap()
        }
        .build_for(&robot, &loads)
        .unwrap()
        .step(&obs)
        .unwrap();
        assert!(e.report.status.is_converged(), "{backend:?}: {}", e.report);
        assert!(
            e.weakly_informed() && e.determined_directions() < 0.5,
            "{backend:?}: {} directions",
            e.determined_directions()
        );
    }
    let dir = std::env::temp_dir().join(format!("softrod_weak_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let markers = dir.join("markers.json");
    std::fs::write(
        &markers,
        serde_json::json!({"markers": [{"s_m": 0.003, "position_m": p}]}).to_string(),
    )
    .unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args([
            "estimate",
            concat!(env!("CARGO_MANIFEST_DIR"), "/examples/two_section.json"),
            "--markers",
            markers.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("barely see the load"), "{stderr}");
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["weakly_informed"], true, "{v}");
    assert!(v["determined_directions"].as_f64().unwrap() < 0.5);
    std::fs::remove_dir_all(&dir).ok();
}
