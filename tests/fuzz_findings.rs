//! Regression tests of what the fuzz targets (`tests/fuzz/`) found, one per
//! finding, each failing before its fix.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::Error;
use softrod::scene::Scene;
use softrod::scene::markers::MarkersFile;

/// Found by `scene_estimate` (2026-12-02): a scene followed by more text
/// (here the tail of another scene) was accepted, the rest silently
/// ignored: the parser stopped after the first JSON value. Every input file
/// goes through the same parser; `serde_json::from_str` refuses such text
/// ("trailing characters").
#[test]
fn text_after_the_scene_is_refused() {
    let scene = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/two_section.json"
    ))
    .unwrap();
    assert!(Scene::from_json(&scene).is_ok());
    // trailing whitespace is fine
    assert!(Scene::from_json(&format!("{scene}\n \n")).is_ok());
    for tail in [r#"}"#, r#", "markers": []}"#, r#"{"robot": {}}"#, "x"] {
        let text = format!("{scene}{tail}");
        match Scene::from_json(&text) {
            Err(Error::Scene { message }) => assert!(
                message.contains("trailing characters") && message.contains("line"),
                "{tail}: {message}"
            ),
            other => panic!("{tail}: accepted or another error: {other:?}"),
        }
    }
}

/// The same for a markers file: refused as a whole (`(file)`).
#[test]
fn text_after_the_markers_is_refused() {
    let m = r#"{"markers": [{"node": 20, "position_m": [0.24, 0.0]}]}"#;
    assert!(MarkersFile::from_json(m).is_ok());
    let e = MarkersFile::from_json(&format!("{m} {{\"markers\": []}}")).unwrap_err();
    assert_eq!(e.field(), Some("(file)"), "{e}");
    assert!(e.to_string().contains("trailing characters"), "{e}");
}
