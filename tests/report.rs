//! `softrod report`: the quick sweep end to end (files, every outcome, no
//! panics), the Pareto front's definition, the failure classification of
//! constructed failing cases, the guard, and the reference interpolation.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::sync::Arc;
use std::time::Duration;

use clarabel::solver::SolverStatus;
use proptest::prelude::*;
use serde_json::Value;
use softrod::Error;
use softrod::estimate::{
    Backend, EstimateStatus, EstimatorSettings, LoadBound, MarkerObservation, Observation,
};
use softrod::loads::Loads;
use softrod::report::auto_point::{AUTO_FORCE_FRACTION, auto_scene};
use softrod::report::pareto::{pareto_front, pareto_front_tol};
use softrod::report::reference::{Reference, embedded_names};
use softrod::report::sweep::{
    CaseSpec, FailureCause, Outcome, Stage, marker_arcs, model_robot, observe, run_case,
    run_guarded, run_guarded_with,
};
use softrod::report::{Part, ReportOptions, run};
use softrod::statics::StaticStatus;

fn spec(backend: Backend) -> CaseSpec {
    CaseSpec {
        backend,
        reference: Arc::new(Reference::embedded("exudyn_family_uniform_3").unwrap()),
        elements: 8,
        markers: 5,
        noise_m: 1e-5,
        declared_noise_m: 1e-5,
        alpha: None,
        jump_m: 0.0,
        warm_frames: 0,
        seed: 3,
        max_iterations: 100,
    }
}

fn is_png(p: &std::path::Path) -> bool {
    let b = std::fs::read(p).unwrap();
    b.len() > 1000 && b.starts_with(&[0x89, b'P', b'N', b'G', 0x0d, 0x0a, 0x1a, 0x0a])
}

fn is_svg(p: &std::path::Path) -> bool {
    let t = std::fs::read_to_string(p).unwrap();
    t.contains("<svg") && t.trim_end().ends_with("</svg>") && t.contains("<text")
}

#[test]
fn quick_report_writes_every_file_and_records_every_case() {
    let dir = std::env::temp_dir().join(format!("softrod-report-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let opts = ReportOptions {
        quick: true,
        quiet: true,
        ..ReportOptions::new(&dir)
    };
    let summary = run(&opts, &[]).unwrap();
    // every chart passes the layout check (no text off its canvas or over
    // another label, no data outside its axes)
    assert!(summary.layout.is_empty(), "{:#?}", summary.layout);
    let names: Vec<String> = summary
        .files
        .iter()
        .map(|f| f.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    for want in [
        "pareto.json",
        "pareto.png",
        "pareto.svg",
        "stability.json",
        "stability.md",
        "stability_noise_load.png",
        "stability_noise_load.svg",
        "stability_markers_jump.png",
        "stability_alpha_noise.svg",
    ] {
        assert!(
            names.iter().any(|n| n == want),
            "{want} missing from {names:?}"
        );
    }
    for f in &summary.files {
        assert!(f.exists(), "{}", f.display());
        match f.extension().and_then(|e| e.to_str()) {
            Some("png") => assert!(is_png(f), "{} is not a PNG", f.display()),
            Some("svg") => assert!(is_svg(f), "{} is not an SVG", f.display()),
            Some("json") => {
                let _: Value = serde_json::from_str(&std::fs::read_to_string(f).unwrap()).unwrap();
            }
            _ => {}
        }
    }
    // the Pareto sweep: one case per configuration and reference; every
    // configuration a point; the fronts non-empty
    let p = summary.pareto.unwrap();
    let g = &p.grid;
    let configs = g.backends.len() * g.elements.len() * g.markers.len();
    assert_eq!(p.points.len(), configs);
    assert_eq!(p.cases.len(), configs * g.references.len());
    assert!(p.points.iter().any(|q| q.front_backbone));
    assert!(p.points.iter().any(|q| q.front_load));
    for q in p.points.iter().filter(|q| q.converged) {
        assert!(q.median_step_s > 0.0 && q.backbone_rms_m > 0.0 && q.load_rel_l2.is_finite());
    }
    // where "elements": "auto" lands: one point per marker count, each on
    // a mesh whose estimated resultant error meets the tolerance
    assert!(p.auto_notes.is_empty(), "{:?}", p.auto_notes);
    assert_eq!(p.auto_points.len(), g.markers.len());
    for a in &p.auto_points {
        assert!(a.label.starts_with("auto"), "{}", a.label);
        assert!(a.median_step_s > 0.0 && a.backbone_rms_m.is_finite() && a.force_rel.is_finite());
    }
    let reference = Reference::embedded(&g.references[0]).unwrap();
    let r = reference.resultant_force_n();
    let tol = AUTO_FORCE_FRACTION * r[0].hypot(r[1]);
    let scene = auto_scene(&reference, g.noise_m, tol).unwrap();
    let obs = observe(
        &reference,
        marker_arcs(reference.length_m, g.markers[0]).as_slice(),
        g.noise_m,
        7,
    );
    let chosen = softrod::refine::auto_elements(&scene, Some(&obs)).unwrap();
    assert!(chosen.estimated_error <= tol);
    assert!(
        p.auto_points[0]
            .label
            .ends_with(&format!(": {} el", chosen.total_elements))
    );
    // the stability sweep: every cell of every map for every backend, each
    // with an outcome: converged with finite errors, or a cause
    let s = summary.stability.unwrap();
    let expected: usize = s
        .maps
        .iter()
        .map(|m| m.x_values.len() * m.y_values.len() * s.backends.len())
        .sum();
    assert_eq!(s.cells.len(), expected);
    assert_eq!(s.panics, 0);
    for c in &s.cells {
        let o = &c.outcome;
        assert_ne!(o.cause(), Some(FailureCause::Panic), "{:?}", o.failure());
        if o.is_converged() {
            let e = o.errors.unwrap();
            assert!(e.backbone_rms_m.is_finite() && e.load_rel_l2.is_finite());
        } else {
            // a failure carries its cause, its message and where it happened
            let f = o.failure().unwrap();
            assert!(!f.message.is_empty(), "{f:?}");
        }
    }
    // the JSON holds them all, and the Markdown table names every backend and map
    let j: Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("stability.json")).unwrap())
            .unwrap();
    assert_eq!(j["cells"].as_array().unwrap().len(), expected);
    let md = std::fs::read_to_string(dir.join("stability.md")).unwrap();
    for b in ["newton", "sqp"] {
        assert!(md.contains(&format!("| {b} |")));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn only_one_part_runs_when_asked() {
    let dir = std::env::temp_dir().join(format!("softrod-report-only-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let opts = ReportOptions {
        quick: true,
        quiet: true,
        only: Some(Part::Pareto),
        ..ReportOptions::new(&dir)
    };
    let s = run(&opts, &[]).unwrap();
    assert!(s.pareto.is_some() && s.stability.is_none());
    assert!(!dir.join("stability.json").exists());
    std::fs::remove_dir_all(&dir).unwrap();
}

fn dominates(q: (f64, f64), p: (f64, f64)) -> bool {
    q.0 <= p.0 && q.1 <= p.1 && (q.0 < p.0 || q.1 < p.1)
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, rng_seed: proptest::test_runner::RngSeed::Fixed(5), ..ProptestConfig::default() })]
    /// Front members are dominated by no point; every other finite point is
    /// dominated by some front member; ties and duplicates are allowed.
    #[test]
    fn pareto_front_is_the_set_of_non_dominated_points(
        pts in prop::collection::vec((0u8..12, 0u8..12), 1..40)
    ) {
        let pts: Vec<(f64, f64)> = pts.iter().map(|&(a, b)| (a as f64, b as f64)).collect();
        let front = pareto_front(&pts);
        for (i, p) in pts.iter().enumerate() {
            let dominated = pts.iter().any(|q| dominates(*q, *p));
            prop_assert_eq!(front[i], !dominated);
            if !front[i] {
                prop_assert!(pts.iter().zip(&front).any(|(q, f)| *f && dominates(*q, *p)));
            }
        }
        prop_assert!(front.iter().any(|f| *f));
    }

    /// With a tolerance, a member is still dominated by no point in the exact
    /// sense unless an equally fast point is within the tolerance; NaN points
    /// are never members.
    #[test]
    fn tolerant_front_members_are_not_beaten_by_a_margin(
        pts in prop::collection::vec((1u8..12, 1u8..12), 1..30), nan in 0usize..30
    ) {
        let mut pts: Vec<(f64, f64)> = pts.iter().map(|&(a, b)| (a as f64, b as f64)).collect();
        let k = nan % pts.len();
        pts[k] = (f64::NAN, 1.0);
        let front = pareto_front_tol(&pts, 1e-3);
        prop_assert!(!front[k]);
        for (i, p) in pts.iter().enumerate().filter(|(i, _)| front[*i]) {
            prop_assert!(!pts.iter().enumerate().any(|(j, q)| j != i && q.0 < p.0 && q.1 < p.1 * (1.0 - 1e-3)));
        }
    }
}

#[test]
fn constructed_failures_are_classified() {
    // no markers: the library refuses the observation
    let o = run_case(&CaseSpec {
        markers: 0,
        ..spec(Backend::Newton)
    });
    assert!(!o.is_converged());
    assert_eq!(
        o.cause(),
        Some(FailureCause::InvalidInput),
        "{:?}",
        o.failure()
    );
    // an element count the two sections cannot share
    let o = run_case(&CaseSpec {
        elements: 7,
        ..spec(Backend::Newton)
    });
    assert_eq!(o.cause(), Some(FailureCause::InvalidInput));
    assert_eq!(o.failure().map(|f| f.at), Some(Stage::Setup));
    // one iteration from the straight robot to a 68 mm deflection: the
    // budget runs out
    let o = run_case(&CaseSpec {
        max_iterations: 1,
        alpha: Some(1e-2),
        ..spec(Backend::Newton)
    });
    assert!(!o.is_converged());
    assert_eq!(
        o.cause(),
        Some(FailureCause::IterationLimit),
        "{:?}",
        o.failure()
    );
    // the SQP iterate after one QP is off the equilibrium manifold; the
    // final static solve at its load then fails (the homotopy stalls), and
    // that error, not the iteration limit, is what the estimator returns
    let o = run_case(&CaseSpec {
        max_iterations: 1,
        alpha: Some(1e-2),
        ..spec(Backend::Sqp)
    });
    assert!(!o.is_converged());
    assert!(
        matches!(
            o.cause(),
            Some(FailureCause::IterationLimit | FailureCause::Divergence)
        ),
        "{:?}",
        o.failure()
    );
    // a non-finite marker position: invalid input, typed
    let r = Reference::embedded("exudyn_family_uniform_3").unwrap();
    let robot = model_robot(&r, 8).unwrap();
    let mut est = softrod::estimate::EstimatorSettings {
        backend: Backend::Newton,
        ..EstimatorSettings::default()
    }
    .build_for(&robot, &Loads::default())
    .unwrap();
    let bad = Observation {
        markers: vec![MarkerObservation::at_arc(
            0.24,
            nalgebra::Vector2::new(f64::NAN, 0.0),
        )],
    };
    assert_eq!(
        FailureCause::classify(&est.step(&bad).unwrap_err()),
        FailureCause::InvalidInput
    );
    // contradictory load bounds at one point: the SQP subproblem is infeasible
    let settings = EstimatorSettings {
        alpha: Some(1.0),
        bounds: vec![
            LoadBound {
                s_m: 0.12,
                frame: Default::default(),
                direction: vec![0.0, 1.0],
                min_n_per_m: Some(10.0),
                max_n_per_m: None,
            },
            LoadBound {
                s_m: 0.12,
                frame: Default::default(),
                direction: vec![0.0, 1.0],
                min_n_per_m: None,
                max_n_per_m: Some(-10.0),
            },
        ],
        ..EstimatorSettings::default()
    };
    let mut est = softrod::estimate::EstimatorSettings {
        backend: Backend::Sqp,
        ..settings
    }
    .build_for(&robot, &Loads::default())
    .unwrap();
    let obs = Observation {
        markers: (1..=5)
            .map(|j| {
                let s = 0.048 * j as f64;
                MarkerObservation::at_arc(s, r.position_at(s))
            })
            .collect(),
    };
    // the estimator returns its last iterate with the typed status
    let e = est.step(&obs).unwrap();
    assert!(
        matches!(
            e.report.status,
            EstimateStatus::QpNotSolved(
                SolverStatus::PrimalInfeasible | SolverStatus::DualInfeasible
            )
        ),
        "{}",
        e.report
    );
    assert_eq!(
        FailureCause::of_estimate(&e.report.status),
        FailureCause::QpInfeasible,
        "{}",
        e.report
    );
}

#[test]
fn one_marker_under_a_distributed_load_is_a_recorded_outcome() {
    // the library does not refuse a single marker: the penalty keeps the
    // problem well posed, both backends converge to the same (poor) answer,
    // and the sweep records it with finite errors
    let outcomes: Vec<Outcome> = [Backend::Newton, Backend::Sqp]
        .into_iter()
        .map(|b| {
            run_guarded(
                &CaseSpec {
                    markers: 1,
                    noise_m: 1e-3,
                    declared_noise_m: 1e-3,
                    ..spec(b)
                },
                Duration::from_secs(60),
            )
        })
        .collect();
    for o in &outcomes {
        assert!(
            // converged: no cause, no failure stage (the status is one enum)
            o.is_converged() && o.cause().is_none() && o.failure().is_none(),
            "{o:?}"
        );
        let e = o
            .errors
            .as_ref()
            .expect("a converged case records its errors");
        assert!(
            e.backbone_rms_m.is_finite() && e.load_rel_l2.is_finite() && e.force_rel.is_finite(),
            "{o:?}"
        );
        assert!(
            o.alpha_used.is_some_and(|a| a.is_finite() && a > 0.0),
            "{o:?}"
        );
    }
    let (n, s) = (
        outcomes[0].errors.as_ref().unwrap(),
        outcomes[1].errors.as_ref().unwrap(),
    );
    assert!(
        (n.backbone_rms_m - s.backbone_rms_m).abs() <= 1e-6 * n.backbone_rms_m
            && (n.load_rel_l2 - s.load_rel_l2).abs() <= 1e-6 * n.load_rel_l2,
        "backends disagree: {n:?} vs {s:?}"
    );
}

/// The failure categories come from typed statuses and errors, never from
/// a message: the same table the messages were read by before.
#[test]
fn typed_failures_map_to_categories() {
    for (status, want) in [
        (
            EstimateStatus::QpNotSolved(SolverStatus::PrimalInfeasible),
            FailureCause::QpInfeasible,
        ),
        (
            EstimateStatus::QpNotSolved(SolverStatus::NumericalError),
            FailureCause::IllConditioning,
        ),
        (
            EstimateStatus::QpNotSolved(SolverStatus::MaxIterations),
            FailureCause::IterationLimit,
        ),
        (
            EstimateStatus::IterationLimit { iterations: 3 },
            FailureCause::IterationLimit,
        ),
        (
            EstimateStatus::LineSearchFailed,
            FailureCause::LineSearchFailed,
        ),
        (
            EstimateStatus::NotPositiveDefinite,
            FailureCause::IllConditioning,
        ),
        (
            EstimateStatus::SingularTangent,
            FailureCause::SingularTangent,
        ),
    ] {
        assert_eq!(FailureCause::of_estimate(&status), want, "{status}");
    }
    for (status, want) in [
        (
            StaticStatus::IterationLimit { iterations: 9 },
            FailureCause::IterationLimit,
        ),
        (
            StaticStatus::LoadStepTooSmall { load_fraction: 0.3 },
            FailureCause::Divergence,
        ),
        (StaticStatus::SingularTangent, FailureCause::SingularTangent),
    ] {
        assert_eq!(FailureCause::of_statics(&status), want, "{status}");
    }
    for (err, want) in [
        (
            Error::NotPositiveDefinite {
                context: "the Gauss-Newton matrix of the estimator".into(),
            },
            FailureCause::IllConditioning,
        ),
        (
            Error::NonFinite {
                context: "residual".into(),
            },
            FailureCause::Divergence,
        ),
    ] {
        assert_eq!(FailureCause::classify(&err), want, "{err}");
    }
}

fn panics(_: &CaseSpec) -> Outcome {
    panic!("deliberate")
}

fn sleeps(s: &CaseSpec) -> Outcome {
    std::thread::sleep(Duration::from_millis(400));
    run_case(s)
}

#[test]
fn the_guard_turns_a_panic_and_an_overrun_into_outcomes() {
    let o = run_guarded_with(&spec(Backend::Newton), Duration::from_secs(10), panics);
    assert_eq!(o.cause(), Some(FailureCause::Panic));
    assert_eq!(o.failure().map(|f| f.message.as_str()), Some("deliberate"));
    let o = run_guarded_with(&spec(Backend::Newton), Duration::from_millis(50), sleeps);
    assert_eq!(o.cause(), Some(FailureCause::Timeout));
    let o = run_guarded(&spec(Backend::Newton), Duration::from_secs(60));
    assert!(o.is_converged(), "{o:?}");
}

/// The reference's Hermite interpolation reproduces its own nodes (position
/// and slope), and between the 128-element nodes it matches exudyn's
/// independent 64-element solution at that run's nodes to discretization
/// accuracy.
#[test]
fn reference_interpolation_reproduces_the_reference_nodes() {
    for name in embedded_names() {
        let r = Reference::embedded(name).unwrap();
        let ne = r.n_elements();
        for (i, n) in r.nodes.iter().enumerate() {
            let s = r.length_m * i as f64 / ne as f64;
            let (p, t) = (r.position_at(s), r.slope_at(s));
            for k in 0..2 {
                assert!((p[k] - n[k]).abs() < 1e-14, "{name} node {i}");
                assert!((t[k] - n[2 + k]).abs() < 1e-12, "{name} node {i}");
            }
        }
    }
    let path = format!(
        "{}/reference/exudyn_gaussian_large.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let v: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    let r = Reference::embedded("exudyn_gaussian_large").unwrap();
    let run64 = v["values"]["runs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|x| x["elements"] == 64)
        .unwrap();
    let nodes: Vec<[f64; 4]> = serde_json::from_value(run64["nodes"].clone()).unwrap();
    let mut worst = 0.0f64;
    for (i, n) in nodes.iter().enumerate() {
        let p = r.position_at(r.length_m * i as f64 / 64.0);
        worst = worst.max((p[0] - n[0]).hypot(p[1] - n[1]));
    }
    // a wrong interpolation (e.g. linear, or slopes scaled wrongly) is off by
    // micrometres to millimetres at the odd nodes; exudyn's 64 and 128
    // element solutions agree to about 1e-7 m
    assert!(worst < 1e-6, "worst {worst:e} m");
    // the applied load: 180 N/m Gaussian bump of width 0.01 m → resultant
    // 180 · 0.01 · √(2π) N in -y
    let f = r.resultant_force_n();
    assert!((f[1] + 180.0 * 0.01 * (2.0 * std::f64::consts::PI).sqrt()).abs() < 1e-6);
}
