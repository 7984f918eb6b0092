//! The grasp: a small seeded version of Table I's trials and the bad inputs.
//! (The friction check's closed forms, the Jacobian's finite differences and
//! the gripper's structure are unit tests in `src/grasp/`.)
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::grasp::friction::hold_check;
use softrod::grasp::gripper::GripperSpec;
#[cfg(feature = "report")]
use softrod::grasp::gripper::Side;
use softrod::grasp::object::{GraspObject, Shape};
use softrod::grasp::trial::{Failure, GraspSettings, Placement, Strategy, run_trial};
#[cfg(feature = "report")]
use softrod::report::grasp::table::{placement, table_objects};

fn disc(radius_m: f64, mass_kg: f64, mu: f64) -> GraspObject {
    GraspObject {
        name: "disc".into(),
        shape: Shape::Circle { radius_m },
        mass_kg,
        mu,
    }
}

#[test]
fn adaptive_holds_a_disc_the_open_loop_strategy_drops() {
    let g = GripperSpec::default();
    let s = GraspSettings::default();
    let o = disc(0.03, 0.25, 0.5);
    let p = Placement::default();
    let open = run_trial(&g, &o, p, Strategy::OpenLoop, &s, 1).unwrap();
    let adaptive = run_trial(&g, &o, p, Strategy::Adaptive, &s, 1).unwrap();
    assert!(!open.success, "{:?}", open.failure);
    assert!(
        matches!(open.failure, Some(Failure::Slips { weight_factor, .. } | Failure::Dropped { weight_factor, .. }) if weight_factor < 1.0)
    );
    // the object the open loop cannot hold slides down (its pose follows
    // from the contact solves) by more than the allowed slip, at the
    // contacts and as a whole
    assert!(open.slip_m > s.max_slip_m, "{}", open.slip_m);
    let fell = open.pose.position_m[1] - open.final_pose.position_m[1];
    assert!(fell > s.max_slip_m, "{fell}");
    assert!(adaptive.success, "{:?}", adaptive.failure);
    assert!(adaptive.slip_m <= s.max_slip_m);
    // the adaptive grasp squeezes harder: it holds more than the baseline's
    assert!(adaptive.holding_mass_kg > 1.5 * open.holding_mass_kg);
    // the estimated contact point is within 2 cm of the true one (paper: about 1.5 cm)
    let e = adaptive.contact_estimate_error_m.unwrap();
    assert!(e < 0.02, "{e}");
    // the outcome's verdict is the friction check on its last frame's contacts
    let last = adaptive.frames.last().unwrap();
    assert!(last.contacts.iter().any(|c| c.point_m[0] < 0.0));
    assert!(last.contacts.iter().any(|c| c.point_m[0] > 0.0));
    let contacts: Vec<_> = last
        .contacts
        .iter()
        .map(|c| softrod::grasp::friction::FrictionContact {
            point_m: c.point_m,
            normal: c.normal,
            max_normal_force_n: c.force_n,
        })
        .collect();
    let h = hold_check(
        &contacts,
        o.mass_kg,
        adaptive.final_pose.position_m.into(),
        o.mu,
        g.gravity_m_per_s2.into(),
    )
    .unwrap();
    assert!(h.holds && (h.weight_factor - adaptive.hold.unwrap().weight_factor).abs() < 1e-9);
}

#[cfg(feature = "report")]
#[test]
fn a_table_object_that_is_not_a_disc() {
    // the tangerine (an ellipse, its circle cover in the plant)
    let o = &table_objects()[4];
    let p = placement(1, 4, 0);
    assert!(p.offset_m.abs() <= 0.006 && p.angle_rad.abs() <= 0.15 && p != Placement::default());
    let out = run_trial(
        &GripperSpec::default(),
        o,
        Placement::default(),
        Strategy::Adaptive,
        &GraspSettings::default(),
        1,
    )
    .unwrap();
    assert!(out.success, "{:?}", out.failure);
    assert!(out.holding_mass_kg > o.mass_kg);
}

#[test]
fn bad_input_names_the_field() {
    let g = GripperSpec::default();
    let s = GraspSettings::default();
    let p = Placement::default();
    let field = |o: &GraspObject, p: Placement| {
        run_trial(&g, o, p, Strategy::OpenLoop, &s, 1)
            .unwrap_err()
            .field()
            .map(str::to_string)
    };
    assert_eq!(
        field(&disc(0.03, 0.1, -0.2), p).as_deref(),
        Some("object.mu")
    );
    assert_eq!(
        field(&disc(0.03, 0.0, 0.5), p).as_deref(),
        Some("object.mass_kg")
    );
    assert_eq!(
        field(&disc(0.03, -1.0, 0.5), p).as_deref(),
        Some("object.mass_kg")
    );
    // wider than the 94 mm opening: a disc's width is its radius's
    assert_eq!(
        field(&disc(0.05, 0.1, 0.5), p).as_deref(),
        Some("object.shape.radius_m")
    );
    // overlapping the left finger at the start
    let off = Placement {
        offset_m: -0.02,
        angle_rad: 0.0,
    };
    assert_eq!(
        field(&disc(0.035, 0.1, 0.5), off).as_deref(),
        Some("placement.offset_m")
    );
    let bad = GraspSettings {
        u1_m_per_s: -1.0,
        ..GraspSettings::default()
    };
    let e = run_trial(&g, &disc(0.03, 0.1, 0.5), p, Strategy::Adaptive, &bad, 1).unwrap_err();
    assert_eq!(e.field(), Some("settings.u1_m_per_s"));
    // the noise is measured from the calibration frames' scatter: one is not enough
    for (bad, name) in [
        (
            GraspSettings {
                calibration_frames: 1,
                ..GraspSettings::default()
            },
            "settings.calibration_frames",
        ),
        (
            GraspSettings {
                contact_false_alarm_probability: 1.0,
                ..GraspSettings::default()
            },
            "settings.contact_false_alarm_probability",
        ),
        (
            GraspSettings {
                contact_false_alarm_probability: 0.0,
                ..GraspSettings::default()
            },
            "settings.contact_false_alarm_probability",
        ),
    ] {
        let e = run_trial(&g, &disc(0.03, 0.1, 0.5), p, Strategy::Adaptive, &bad, 1).unwrap_err();
        assert_eq!(e.field(), Some(name));
    }
}

#[cfg(feature = "report")]
#[test]
fn the_quick_report_part_writes_the_table_and_the_sequences() {
    let dir = std::env::temp_dir().join(format!("softrod_grasp_report_{}", std::process::id()));
    let opts = softrod::report::ReportOptions {
        quick: true,
        quiet: true,
        ..softrod::report::ReportOptions::new(&dir)
    };
    std::fs::create_dir_all(&dir).unwrap();
    let (r, files) = softrod::report::grasp::run(&opts).unwrap();
    for name in ["grasp.json", "grasp.md", "grasp.png", "grasp.svg"] {
        assert!(files.iter().any(|f| f.ends_with(name)), "{name}");
        assert!(
            std::fs::metadata(dir.join(name)).unwrap().len() > 100,
            "{name}"
        );
    }
    // one object (the bottle), both strategies, one sequence each
    assert_eq!(r.rows.len(), 2);
    assert_eq!(r.sequences.len(), 2);
    assert_eq!(r.sequences[0].strategy, Strategy::Adaptive);
    assert_eq!(r.sequences[1].strategy, Strategy::OpenLoop);
    let md = std::fs::read_to_string(dir.join("grasp.md")).unwrap();
    assert!(md.contains("| plastic bottle |"), "{md}");
    assert_eq!(r.sequences[0].success, r.rows[0].successes == 1);
    std::fs::remove_dir_all(&dir).ok();
}

#[cfg(feature = "report")]
#[test]
fn the_ruler_set_down_turned_stands_up_and_holds() {
    // the ruler (a 3 mm × 30 mm section on its 3 mm edge, covered by 37
    // circles of 1.5 mm) set down turned by less than 0.1 rad (its centre of
    // mass above its base) comes back upright on the table before the
    // gripper closes (its base's corners 3 mm apart within the 1 µm contact
    // tolerance); tries 0, 1 and 3 (set down at +0.011, −0.079 and +0.051
    // rad) are then held with at most 5 mm of slip. Try 0 failed while a
    // contact was detected on noise: the right finger, touching the ruler
    // with 0.04 N, took 0.28 N of noise for its contact, turned off it and
    // never came back (fixed by the significance test of the detection).
    let o = &table_objects()[0];
    let s = GraspSettings::default();
    for k in [0, 1, 3] {
        let out = run_trial(
            &GripperSpec::default(),
            o,
            placement(1, 0, k),
            Strategy::Adaptive,
            &s,
            1 ^ (k as u64),
        )
        .unwrap();
        let rest = out.frames[0].object_angle_rad;
        let w0 = out.hold.as_ref().unwrap().weight_factor;
        let turn = (out.final_pose.angle_rad - rest).abs();
        assert!(rest.abs() * 0.003 <= 1e-6, "try {k}: {rest}");
        assert!(out.success, "try {k}: {:?}", out.failure);
        assert!(out.slip_m <= s.max_slip_m, "try {k}: {}", out.slip_m);
        if k == 0 {
            // both fingers hold it
            let last = out.frames.last().unwrap();
            for side in [Side::Left, Side::Right] {
                assert!(
                    last.contacts.iter().any(|c| c.side == side),
                    "try 0: {side:?}"
                );
            }
            continue;
        }
        assert!(out.pose.angle_rad.abs() > 0.05, "try {k}");
        // upright, it is still touched at unequal heights: the couple cannot
        // be balanced by friction on 3 mm (weight factor 0 after the lift),
        // so it turns in the pinch (0.04 and 0.06 rad, measured) until its
        // contacts line up, rolling on the fingertips
        assert!(w0 < 1e-6 && turn > 0.02, "try {k}: {w0} {turn}");
    }
}

#[cfg(feature = "report")]
#[test]
fn noise_alone_does_not_make_a_contact() {
    // red apple, try 3: the second estimate of the left finger, 50 mm from
    // the apple, had a resultant of 0.30 N (noise) and was taken for a
    // contact; the finger turned outward and held nothing. Contact is now
    // detected on a full averaging window only.
    let o = &table_objects()[5];
    let out = run_trial(
        &GripperSpec::default(),
        o,
        placement(1, 5, 3),
        Strategy::Adaptive,
        &GraspSettings::default(),
        1 ^ 503,
    )
    .unwrap();
    assert!(out.success, "{:?}", out.failure);
    let last = out.frames.last().unwrap();
    assert!(
        last.contacts
            .iter()
            .any(|c| c.point_m[0] < out.final_pose.position_m[0])
    );
    assert!(
        last.contacts
            .iter()
            .any(|c| c.point_m[0] > out.final_pose.position_m[0])
    );
}
