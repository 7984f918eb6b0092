//! `softrod report --only tracking` in its quick form: the tracking and
//! mass-estimation figures are written (PNG, SVG, JSON) and say what the
//! loop did.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::control::ControllerKind;
use softrod::report::{Part, ReportOptions, run};

#[test]
fn quick_tracking_report_writes_both_figures() {
    let dir = std::env::temp_dir().join(format!("softrod-track-report-{}", std::process::id()));
    let opts = ReportOptions {
        quick: true,
        only: Some(Part::Tracking),
        quiet: true,
        ..ReportOptions::new(&dir)
    };
    let summary = run(&opts, &[]).unwrap();
    assert!(summary.pareto.is_none() && summary.stability.is_none());
    for f in [
        "tracking.png",
        "tracking.svg",
        "tracking.json",
        "tracking_mass.png",
        "tracking_mass.svg",
        "tracking_mass.json",
    ] {
        let len = std::fs::metadata(dir.join(f)).unwrap().len();
        assert!(len > 1000, "{f}: {len} bytes");
    }
    let t = summary.tracking.unwrap();
    assert_eq!(t.rows.len(), 4);
    for pair in t.rows.chunks(2) {
        let (ff, upd) = (&pair[0], &pair[1]);
        assert_eq!(
            (ff.controller, upd.controller),
            (ControllerKind::Ff, ControllerKind::FfUpdater)
        );
        assert!(ff.failure.is_none() && upd.failure.is_none());
        assert!(upd.mean_error_m.unwrap() < 0.1 * ff.mean_error_m.unwrap());
    }
    let m = t.mass.unwrap();
    assert_eq!(m.rows.len(), 9);
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("tracking.json")).unwrap()).unwrap();
    assert_eq!(json["rows"].as_array().unwrap().len(), 4);
}

#[test]
fn quick_loop_report_writes_the_speed_chart_and_the_failure_map() {
    use softrod::report::loop_failure::{LoopCause, LoopVerdict};
    use softrod::report::{loop_failure, loop_pareto};
    let dir = std::env::temp_dir().join(format!("softrod-loop-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let opts = ReportOptions {
        quick: true,
        only: Some(Part::Loop),
        quiet: true,
        ..ReportOptions::new(&dir)
    };
    let p = loop_pareto::run(&opts).unwrap();
    let f = loop_failure::run(&opts).unwrap();
    let mut files = p.write(&dir).unwrap();
    files.extend(f.write(&dir).unwrap());
    for name in [
        "loop_pareto.png",
        "loop_pareto.svg",
        "loop_pareto.json",
        "loop_failure.png",
        "loop_failure.svg",
        "loop_failure.json",
    ] {
        assert!(files.contains(&dir.join(name)), "{name}");
        let len = std::fs::metadata(dir.join(name)).unwrap().len();
        assert!(len > 500, "{name}: {len} bytes");
    }
    // speed against accuracy: both sizes ran, the finer model is slower
    assert_eq!(p.rows.len(), 2);
    for r in &p.rows {
        assert!(r.failure.is_none(), "{r:?}");
        assert!(r.mean_error_m.unwrap().is_finite());
    }
    assert!(p.rows[1].median_step_time_s.unwrap() > p.rows[0].median_step_time_s.unwrap());
    // the failure map: every case an outcome; no payload converges, five
    // robot weights do not, and (the sweep runs without the watchdog) for
    // the cause a user can act on: the plant itself cannot reach the path
    assert_eq!(f.rows.len(), 8);
    for r in &f.rows {
        let o = r.outcome.as_ref().unwrap_or_else(|| panic!("{r:?}"));
        let light = r.case.payload_weights == 0.0;
        assert_eq!(o.verdict == LoopVerdict::Converged, light, "{o:?}");
        if !light {
            assert_eq!(o.cause, LoopCause::IkUnreachable, "{o:?}");
            let reach = f
                .plant_reach
                .iter()
                .find(|p| {
                    p.payload_weights == r.case.payload_weights && p.ei_error == r.case.ei_error
                })
                .and_then(|p| p.reach_m)
                .unwrap_or_else(|| panic!("no plant reach for {r:?}"));
            assert!(
                reach > softrod::report::loop_failure::UNREACHABLE_M,
                "{reach}"
            );
        }
    }
}
