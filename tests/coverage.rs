//! The reported uncertainty means what it says: the true resultant force
//! of a load the estimator is not told about lies in the reported 95 %
//! region at about the nominal rate, or the estimate says that its σ is a
//! prior's width (weakly informed). The truth comes from a "real robot"
//! that is not the estimator's model (a mesh twice as fine, markers between
//! the coarse nodes): see `softrod::report::coverage`. The full study (200
//! trials per family, both backends) is `softrod report --only coverage`;
//! the test runs the same trials, and a guard family drawn per day.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::Error;
use softrod::estimate::MarkerObservation;
use softrod::estimate::{AlphaRule, Backend, EstimateStatus, EstimatorSettings, Observation};
use softrod::report::coverage::{Family, KindSet, sweep};
use softrod::scene::Scene;

/// The full study of `softrod report --only coverage` (1.6 s in release on
/// the loaded 2-core machine, 2 000 trials): 200 seeded trials per load
/// family (3–11 markers, 5–100 µm noise), both backends, `α` by the
/// evidence. Every family: the truth lies in the reported 95 % ellipse or
/// the estimate says it is weakly informed in at least 90 % of the trials
/// (measured 95.0–99.5 %; a miss not flagged is the failure a user cannot
/// see). Smooth, point, two-point and sine loads: at most 99 % in the
/// ellipse (measured 93.0, 94.5, 96.5, 77.0 %); smooth and point loads also
/// 90–99 % without the flags, as before (93.0, 94.5 %), the smooth ones'
/// median squared distance near χ²₂'s median 1.39. The payload (a uniform
/// load plus a tip mass) is covered 99.5 %, its σ too wide (median d²
/// 0.40): the σ of a concentrated force in the distributed model is
/// conservative (a tip force alone: 100 %, median d² 0.19; the uniform load
/// alone: 93 %, 0.97), held here to a median d² of at least 0.2 (about 2.6
/// times too wide a σ at most). The backends agree to 1 %.
#[test]
fn every_family_is_covered_or_flagged() {
    let r = sweep(
        200,
        1,
        &[Backend::Newton, Backend::Sqp],
        &Family::SINGLE,
        AlphaRule::Evidence,
        true,
    )
    .unwrap();
    eprint!("{}\n{}", r.markdown(), r.misses_markdown());
    assert_eq!(r.rows.len(), 2 * Family::SINGLE.len());
    for row in &r.rows {
        assert_eq!(row.converged, 200, "{row:?}");
        covered_or_flagged(row);
        match row.family {
            Family::Smooth | Family::Point => {
                assert!(
                    (0.90..=0.99).contains(&row.coverage),
                    "{:?} {:?}: coverage {}",
                    row.family,
                    row.backend,
                    row.coverage
                );
                if row.family == Family::Smooth {
                    assert!(
                        (0.7..=2.8).contains(&row.median_d2),
                        "median d² {}",
                        row.median_d2
                    );
                }
            }
            Family::Payload => assert!(row.coverage >= 0.90 && row.median_d2 >= 0.2, "{row:?}"),
            _ => assert!(row.coverage <= 0.99, "{row:?}"),
        }
    }
    readme_tables_are_this_study(&r);
    // The study's worst trial (smooth trial 175: 5 markers that the true
    // 0.065 N load moves by 0.16–1.06 σ; estimate ≈ 0 ± 3.8e-5 N, d² ≈
    // 3e6) is weakly informed for its few determined directions (γ ≈
    // 5e-4); every gross miss is flagged.
    let few: Vec<(Family, u64)> = r
        .outcomes
        .iter()
        .filter(|o| o.determined_directions < softrod::estimate::WEAKLY_INFORMED_DIRECTIONS)
        .map(|o| (o.family, o.seed))
        .collect();
    assert!(few.contains(&(Family::Smooth, 175)), "{few:?}");
    for o in &r.outcomes {
        assert!(
            o.d2 <= 1e2 || o.weakly_informed,
            "a gross miss not flagged: {o:?}"
        );
    }
    for fam in Family::SINGLE {
        let c: Vec<f64> = r
            .rows
            .iter()
            .filter(|row| row.family == fam)
            .map(|row| row.coverage)
            .collect();
        assert!((c[0] - c[1]).abs() <= 0.01, "{fam:?}: {c:?}");
    }
}

/// A row's trials are covered or flagged weakly informed in at least 90 %
/// of the trials: at most one trial in ten a miss the estimate does not
/// warn of.
fn covered_or_flagged(row: &softrod::report::coverage::CoverageRow) {
    assert!(
        row.covered_or_flagged >= 0.90,
        "{} {:?}: covered or flagged {} (coverage {}, {} flagged)",
        row.family.label(),
        row.backend,
        row.covered_or_flagged,
        row.coverage,
        row.flagged
    );
}

/// The guard: a family the tests were not tuned on, drawn per day (a
/// mixture of two or more of the single families, each trial summing one
/// load of each kind, and its seeds), 300 trials per backend: covered or
/// flagged in at least 90 % of the trials, its σ at most about 2.6 times too
/// wide (median d² ≥ 0.2), no miss beyond d² = 100 unflagged (measured on
/// the single families at two seed ranges: at most 23). The family and seeds are printed; set
/// `SOFTROD_COVERAGE_GUARD_DAY` to the printed day to replay a failure.
/// Measured on the 26 mixtures at two seed ranges (200 trials, newton):
/// covered or flagged 91.5–100 %, in the ellipse 87–100 %, median d²
/// 0.25–1.31 (the mixtures with a concentrated force over-cover, as the
/// payload does).
#[test]
fn a_family_drawn_at_random_per_run_is_covered_or_flagged() {
    let day = std::env::var("SOFTROD_COVERAGE_GUARD_DAY")
        .ok()
        .and_then(|v| v.parse::<u64>().ok())
        .unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_secs() / 86_400)
        });
    // a set of two or more kinds and a seed range, from the day
    let mixed = |k: u64| {
        day.wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .rotate_left(k as u32 * 17)
    };
    let sets: Vec<u8> = (3u8..32).filter(|b| b.count_ones() >= 2).collect();
    let kinds = KindSet::from_bits(sets[(mixed(1) % sets.len() as u64) as usize]);
    let family = Family::Mixture(kinds);
    let seed = 1_000_000 + mixed(2) % 1_000_000_000;
    eprintln!(
        "coverage guard: {} at seeds {seed}.. (SOFTROD_COVERAGE_GUARD_DAY={day} replays)",
        family.label()
    );
    let r = sweep(
        300,
        seed,
        &[Backend::Newton, Backend::Sqp],
        &[family],
        AlphaRule::Evidence,
        true,
    )
    .unwrap();
    eprint!("{}", r.markdown());
    assert_eq!(r.rows.len(), 2);
    for row in &r.rows {
        assert_eq!(row.converged, 300, "{row:?}");
        covered_or_flagged(row);
        assert!(row.median_d2 >= 0.2, "{row:?}");
    }
    for o in &r.outcomes {
        assert!(
            o.d2 <= 1e2 || o.weakly_informed,
            "a gross miss not flagged: {o:?}"
        );
    }
}

/// The README's coverage tables are the ones this study gives: the counts
/// and coverages exactly, the medians to their last printed digit; the
/// table of where the misses are exactly. After a change that moves them,
/// rerun `softrod report --only coverage --out validation/figures` and copy
/// its tables into the README.
fn readme_tables_are_this_study(r: &softrod::report::coverage::CoverageReport) {
    let readme = include_str!("../README.md");
    let cells = |line: &str| -> Vec<String> {
        line.trim_matches('|')
            .split(" | ")
            .map(|c| c.trim().trim_matches('|').trim().to_string())
            .collect()
    };
    let markdown = r.markdown();
    for row in markdown.lines().skip(2) {
        let want = cells(row);
        let key = format!("| {} | {} |", want[0], want[1]);
        let line = readme
            .lines()
            .find(|l| l.starts_with(&key) && cells(l).len() == want.len())
            .unwrap_or_else(|| panic!("README: no coverage row `{key}`"));
        let got = cells(line);
        for k in 0..want.len() {
            if k == 7 || k == 8 {
                let num = |c: &str| c.trim_end_matches(" %").parse::<f64>().unwrap();
                assert!(
                    (num(&got[k]) - num(&want[k])).abs() <= 0.011,
                    "README row `{line}`, study `{row}`"
                );
            } else {
                assert_eq!(got[k], want[k], "README row `{line}`, study `{row}`");
            }
        }
    }
    for row in r.misses_markdown().lines().skip(2) {
        assert!(
            readme.lines().any(|l| l == row),
            "README: no row `{row}` of where the misses are"
        );
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
