//! `softrod report --only touch` in its quick form: the localization and
//! avoidance figure is written (PNG, SVG, JSON) and says what was measured.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::report::{ReportOptions, touch};

#[test]
fn quick_touch_report_writes_the_figure_and_its_data() {
    let dir = std::env::temp_dir().join(format!("softrod-touch-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let opts = ReportOptions {
        quick: true,
        quiet: true,
        ..ReportOptions::new(&dir)
    };
    let (r, files) = touch::run(&opts).unwrap();
    for f in ["touch.png", "touch.svg", "touch.json"] {
        assert!(files.contains(&dir.join(f)), "{files:?}");
        let len = std::fs::metadata(dir.join(f)).unwrap().len();
        assert!(len > 1000, "{f}: {len} bytes");
    }
    // three contact positions, both methods; the point search within 5 mm
    assert_eq!(r.localization.len(), 3);
    assert!(r.point_mean_max_m.1 <= 5e-3, "{:?}", r.point_mean_max_m);
    // the avoidance run reached its goal after touching the disk once or more
    let a = &r.avoidance;
    assert!(
        a.status.is_reached() && !a.touched.is_empty(),
        "{:?}",
        a.status
    );
    assert!(!a.shapes.is_empty());
    // the table (quick: one placement and goal): by touch reached, the
    // baseline met the disk and did not
    assert_eq!(r.table.len(), 1);
    let row = &r.table[0];
    assert!(row.touch.status.is_reached(), "{row:?}");
    assert!(row.touch.touches >= 1 && row.touch.final_error_m <= 2e-3);
    assert!(row.baseline_met_obstacle() && !row.baseline.status.is_reached());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("touch.json")).unwrap()).unwrap();
    assert_eq!(json["localization"].as_array().unwrap().len(), 3);
    assert_eq!(json["table"].as_array().unwrap().len(), 1);
    std::fs::remove_dir_all(&dir).ok();
}
