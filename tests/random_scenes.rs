//! Random scenes through parse, solve and estimate (issue 33, point 6: the
//! fallback of the `scene_estimate` fuzz target that always runs): valid
//! and corrupted scenes, with and without a markers file, held to the same
//! invariants as the fuzz targets (`tests/common/scene_checks.rs`: no
//! panic, finite numbers in every accepted answer, a converged static
//! status within its stated bound, a converged estimate within its fit test
//! and with finite covariances).
//!
//! Two generators: the wide one of the JSON round trips
//! (`tests/common/scene_strategy.rs`, every field anywhere in its valid
//! range: most of its scenes have no reachable equilibrium), and a moderate
//! one whose scenes mostly solve, so the estimators run: the two-section
//! robot with random meshes, a second section up to 1e4 times stiffer,
//! pressures within their bounds, a tip force, a uniform load, a tip moment,
//! random markers and estimator settings. Either may be corrupted (one
//! field set to −1, 0, 1e308, −1e−300, 1e9 or a non-finite number) and may
//! come with a markers file of random positions. A fixed seed and a modest
//! case count keep it to seconds in release.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use proptest::prelude::*;
use softrod::estimate::{BoundFrame, LoadBound};
use softrod::loads::{LineLoad, Load};
use softrod::scene::{Marker, Scene, UnknownLoad};

#[path = "common/scene_checks.rs"]
mod scene_checks;
#[path = "common/scene_strategy.rs"]
mod scene_strategy;

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        // a fixed seed: the same cases on every machine and run
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x5ce7_e57a),
        ..ProptestConfig::default()
    }
}

/// The estimator's part of a moderate scene.
#[derive(Debug, Clone)]
struct EstimatorCase {
    alpha_exp: Option<f64>,
    noise_exp: f64,
    statistical: bool,
    unknown: u8,
    point_frac: f64,
    bound: bool,
}

fn estimator_case() -> impl Strategy<Value = EstimatorCase> {
    (
        prop::option::of(-16.0..-10.0f64),
        -6.0..-3.0f64,
        any::<bool>(),
        0u8..3,
        0.0..1.0f64,
        prop::bool::weighted(0.2),
    )
        .prop_map(
            |(alpha_exp, noise_exp, statistical, unknown, point_frac, bound)| EstimatorCase {
                alpha_exp,
                noise_exp,
                statistical,
                unknown,
                point_frac,
                bound,
            },
        )
}

/// Scenes that mostly solve: the two-section robot, random meshes and
/// stiffness contrast, moderate loads, random markers and estimator.
fn moderate_scene() -> impl Strategy<Value = Scene> {
    (
        (1usize..=12, 1usize..=12, 0.0..4.0f64, 0.005..0.1f64),
        (
            prop::collection::vec(0.0..100e3f64, 4),
            prop::array::uniform2(-0.3..0.3f64),
            prop::array::uniform2(-2.0..2.0f64),
            -0.05..0.05f64,
        ),
        prop::collection::vec((0.0..1.0f64, any::<bool>()), 0..6),
        estimator_case(),
    )
        .prop_map(
            |((n1, n2, contrast, ei), (p, tip, w, moment), markers, est)| {
                let mut s = Scene::two_section();
                s.robot.sections[0].elements = n1;
                s.robot.sections[1].elements = n2;
                s.robot.sections[0].ei_nm2 = ei;
                s.robot.sections[1].ei_nm2 = ei * 10f64.powf(contrast);
                s.pressures_pa = p;
                s.loads = vec![
                    Load::TipForce {
                        force_n: tip.to_vec(),
                    },
                    Load::Distributed(LineLoad::Uniform {
                        w_n_per_m: w.to_vec(),
                    }),
                    Load::TipMoment {
                        moment_nm: moment.into(),
                    },
                ];
                // on the robot, each node once (a node past the tip or a
                // repeated one is refused: the corruptions below try those)
                let nodes = n1 + n2;
                let mut picked: Vec<(usize, bool)> = markers
                    .into_iter()
                    .map(|(x, tangent)| (1 + (x * nodes as f64) as usize % nodes, tangent))
                    .collect();
                picked.sort_unstable_by_key(|m| m.0);
                picked.dedup_by_key(|m| m.0);
                s.markers = picked
                    .into_iter()
                    .map(|(node, tangent)| Marker {
                        node: Some(node),
                        s_m: None,
                        tangent,
                    })
                    .collect();
                // a point load acts at a node
                let at = node_arc(&s, 1 + (est.point_frac * nodes as f64) as usize % nodes);
                s.unknown_load = match est.unknown {
                    0 => None,
                    1 => Some(UnknownLoad::Distributed),
                    _ => Some(UnknownLoad::Point { s_m: at }),
                };
                let e = &mut s.solver.estimator;
                e.alpha = est.alpha_exp.map(|x| 10f64.powf(x));
                e.noise_sigma_m = 10f64.powf(est.noise_exp);
                e.statistical_tolerance = if est.statistical { 0.1 } else { 0.0 };
                if est.bound {
                    e.bounds = vec![LoadBound {
                        s_m: at,
                        frame: BoundFrame::Local,
                        direction: vec![0.0, 1.0],
                        min_n_per_m: Some(0.0),
                        max_n_per_m: None,
                    }];
                }
                s
            },
        )
}

/// The odd values a corrupted field gets.
const ODD: [f64; 7] = [-1.0, 0.0, 1e308, -1e-300, 1e9, f64::NAN, f64::INFINITY];

/// Sets field `field` (of the list below) of `s` to `x`.
fn corrupt(s: &mut Scene, field: usize, x: f64) {
    let sec = |s: &mut Scene, i: usize| s.robot.sections.len().min(i + 1) - 1;
    match field {
        0 => {
            let i = sec(s, 0);
            s.robot.sections[i].length_m = x;
        }
        1 => {
            let i = sec(s, 0);
            s.robot.sections[i].ea_n = x;
        }
        2 => {
            let i = sec(s, 1);
            s.robot.sections[i].ei_nm2 = x;
        }
        3 => {
            let i = sec(s, 1);
            s.robot.sections[i].elements = x.abs().min(1e6) as usize;
        }
        4 => s.pressures_pa.iter_mut().take(1).for_each(|p| *p = x),
        5 => s.base.angle_rad = x,
        6 => s.gravity_m_per_s2.iter_mut().take(1).for_each(|g| *g = x),
        7 => s.solver.estimator.noise_sigma_m = x,
        8 => s.solver.estimator.alpha = Some(x),
        9 => s.solver.statics.residual_tolerance = x,
        10 => s.solver.estimator.max_observation_jump_m = x,
        11 => s.loads.push(Load::TipForce {
            force_n: vec![x, 0.0],
        }),
        12 => s.loads.push(Load::TipMass { mass_kg: x }),
        _ => s.markers.push(Marker {
            node: None,
            s_m: Some(x),
            tangent: false,
        }),
    }
}

/// Undeformed arc coordinate of node `k` of the scene's mesh (m).
fn node_arc(s: &Scene, k: usize) -> f64 {
    let mut before = 0usize;
    let mut arc = 0.0;
    for sec in &s.robot.sections {
        if k <= before + sec.elements {
            return arc + sec.length_m * (k - before) as f64 / sec.elements.max(1) as f64;
        }
        before += sec.elements;
        arc += sec.length_m;
    }
    arc
}

/// A markers file for `s`: random nodes (as fractions of the mesh), each
/// at its place on the straight robot moved by `d` (m).
fn markers_file(s: &Scene, picks: &[(f64, [f64; 2])]) -> String {
    let nodes: usize = s.robot.sections.iter().map(|x| x.elements).sum();
    let markers: Vec<serde_json::Value> = picks
        .iter()
        .map(|&(x, d)| {
            let node = (x * nodes as f64).round() as usize;
            let arc = node_arc(s, node);
            serde_json::json!({"node": node, "position_m": [arc + d[0], d[1]]})
        })
        .collect();
    serde_json::json!({ "markers": markers }).to_string()
}

/// One case: a scene (either generator), maybe corrupted, maybe a markers
/// file, and the noise seed.
fn case() -> impl Strategy<Value = (Scene, Option<String>, u64)> {
    (
        prop_oneof![1 => scene_strategy::scene_strategy(), 3 => moderate_scene()],
        prop::option::weighted(0.3, (0usize..14, 0usize..ODD.len())),
        prop::option::weighted(
            0.3,
            prop::collection::vec((0.0..1.0f64, prop::array::uniform2(-0.05..0.05f64)), 1..6),
        ),
        any::<u64>(),
    )
        .prop_map(|(mut s, bad, picks, seed)| {
            let markers = picks.map(|p| markers_file(&s, &p));
            if let Some((field, k)) = bad {
                corrupt(&mut s, field, ODD[k]);
            }
            (s, markers, seed)
        })
}

proptest! {
    #![proptest_config(config(256))]

    /// Parse, solve and estimate (both backends, two frames or the markers
    /// file's), every answer held to the fuzz targets' invariants. 256 cases.
    fn random_scenes_solve_and_estimate_honestly((scene, markers, seed) in case()) {
        // a non-finite number is written as `null` (refused by the parser)
        let text = serde_json::to_string(&scene).unwrap();
        if markers.is_some() {
            scene_checks::solve_scene(&text);
        }
        scene_checks::estimate_scene(&text, markers.as_deref(), seed);
    }
}

/// The cases reach the estimators: the property run here and the process's
/// counts read after it (the property's own, plus the two parses of
/// `caps_and_split` if it ran meanwhile).
#[test]
fn random_scenes_reach_the_estimators() {
    random_scenes_solve_and_estimate_honestly();
    let [scenes, equilibria, estimates, converged] = scene_checks::reached::counts();
    println!(
        "{scenes} scenes within the caps, {equilibria} equilibria, {estimates} estimates ({converged} converged)"
    );
    assert!(scenes >= 32 && equilibria >= 16 && estimates >= 32 && converged >= 8);
}

/// The caps skip what they should and the split finds the markers.
#[test]
fn caps_and_split() {
    let scene = serde_json::to_string(&Scene::two_section()).unwrap();
    assert!(scene_checks::parse(&scene, 20).is_some());
    assert!(scene_checks::parse(&scene, 19).is_none());
    let mut data = scene.clone().into_bytes();
    data.push(scene_checks::SEPARATOR);
    data.extend_from_slice(br#"{"markers": []}"#);
    let (s, m) = scene_checks::split_input(&data).unwrap();
    assert_eq!((s, m), (scene.as_str(), Some(r#"{"markers": []}"#)));
    assert!(scene_checks::split_input(&vec![b' '; scene_checks::MAX_INPUT + 1]).is_none());
}
