//! The one element limit ([`softrod::assembly::MAX_ELEMENTS`]): every entry
//! point refuses a larger mesh up front, with an error naming the field and
//! the limit, instead of a solve or an estimate that runs for minutes (an
//! estimate at 10 000 elements failed its line search after 20 s, one at
//! 150 000 never ended, before the limit was lowered to where the solvers
//! are measured).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use serde_json::json;
use softrod::assembly::{RobotSpec, Section, MAX_ELEMENTS};
use softrod::scene::Scene;
use softrod::Error;

fn scene(elements: [usize; 2]) -> serde_json::Value {
    let section =
        |k: usize| json!({"length_m": 0.12, "ea_n": 300.0, "ei_nm2": 0.025, "elements": k});
    json!({"robot": {"sections": [section(elements[0]), section(elements[1])]}})
}

fn refused(e: Error, field: &str, max: usize) {
    let text = e.to_string();
    match e {
        Error::TooLarge { name, max: m, .. } => {
            assert_eq!((name.as_str(), m), (field, max), "{text}");
            assert!(text.contains(&max.to_string()), "{text}");
        }
        other => panic!("not TooLarge: {other}"),
    }
}

#[test]
fn ten_thousand_elements_are_refused_by_every_entry_point() {
    // a scene (what `softrod solve` and `softrod estimate` read)
    let s: Scene = serde_json::from_value(scene([5000, 5000])).unwrap();
    refused(
        s.validate().unwrap_err(),
        "robot.sections[0].elements",
        MAX_ELEMENTS,
    );
    refused(
        s.robot().unwrap_err(),
        "robot.sections[0].elements",
        MAX_ELEMENTS,
    );
    // a robot specification (the estimator and the solvers take built robots)
    let spec = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 10_000)]);
    refused(
        spec.build_planar().unwrap_err(),
        "robot.sections[0].elements",
        MAX_ELEMENTS,
    );
    // sections that fit alone but not together: the room left
    let s: Scene = serde_json::from_value(scene([1500, 1500])).unwrap();
    refused(
        s.validate().unwrap_err(),
        "robot.sections[1].elements",
        MAX_ELEMENTS - 1500,
    );
}

#[test]
fn the_limit_itself_is_accepted() {
    let s: Scene =
        serde_json::from_value(scene([MAX_ELEMENTS / 2, MAX_ELEMENTS - MAX_ELEMENTS / 2])).unwrap();
    s.validate().unwrap();
    assert_eq!(s.robot().unwrap().n_elements(), MAX_ELEMENTS);
}
