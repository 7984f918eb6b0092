//! `softrod report --only tracking` in its quick form: the tracking and
//! mass-estimation figures are written (PNG, SVG, JSON) and say what the
//! loop did.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::control::ControllerKind;
use softrod::report::{run, Part, ReportOptions};

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
