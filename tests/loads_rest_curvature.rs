//! Rest curvature as a function of arc length (a section's
//! `rest_curvature_profile`): the element's energy derivatives against
//! finite differences, the equilibrium against exudyn's ANCF cable with its
//! per-element `referenceCurvature` (`reference/exudyn_rest_curvature_*.json`,
//! written by `validation/exudyn_rest_curvature.py`), and against the closed
//! form of a rod whose rest curvature is a ramp under a tip moment: its
//! curvature is `κ0(X) + M / EI`, its tangent angle
//! `θ(X) = (a + M/EI) X + b X² / 2`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use softrod::assembly::{RestCurvatureProfile, Robot, RobotSpec, Section};
use softrod::element::{Element, PlanarCable};
use softrod::loads::{Loads, NodeMoment, PointForce};
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

const L: f64 = 0.24;
const EI: f64 = 0.025;
const EA: f64 = 300.0;

fn robot(
    profile: RestCurvatureProfile,
    elements: usize,
    bending_points: usize,
) -> Robot<PlanarCable> {
    let mut s = Section::uniform(L, EA, EI, elements);
    s.rest_curvature_profile = Some(profile);
    let mut spec = RobotSpec::new(vec![s]);
    spec.gravity_m_per_s2 = vec![0.0, 0.0];
    spec.bending_gauss_points = bending_points;
    spec.build_planar().unwrap()
}

fn solve(robot: &Robot<PlanarCable>, loads: &Loads) -> Vec<f64> {
    let eq = StaticSolver::default().solve(robot, loads, None).unwrap();
    assert!(eq.report.status.is_converged(), "{:?}", eq.report.status);
    eq.q.data.into()
}

#[test]
fn the_energy_derivatives_of_a_varying_rest_curvature_match_finite_differences() {
    let le = 0.06;
    let e = PlanarCable::with_rest_curvature(le, EA, EI, |x| 3.0 + 40.0 * x - 200.0 * x * x, 5, 3)
        .unwrap();
    let qe = [0.01, -0.02, 0.9, 0.3, 0.06, 0.02, 0.7, 0.75];
    let mut g = [0.0; 8];
    e.add_energy_gradient(&qe, &mut g);
    let mut h = [0.0; 64];
    e.add_energy_hessian(&qe, &mut h);
    let step = 1e-6;
    let (mut eg, mut eh) = (0.0f64, 0.0f64);
    for j in 0..8 {
        let (mut p, mut m) = (qe, qe);
        p[j] += step;
        m[j] -= step;
        let fd = (e.energy(&p) - e.energy(&m)) / (2.0 * step);
        eg = eg.max((fd - g[j]).abs());
        let (mut gp, mut gm) = ([0.0; 8], [0.0; 8]);
        e.add_energy_gradient(&p, &mut gp);
        e.add_energy_gradient(&m, &mut gm);
        for i in 0..8 {
            eh = eh.max(((gp[i] - gm[i]) / (2.0 * step) - h[i * 8 + j]).abs());
        }
    }
    let gs = g.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    let hs = h.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(eg < 1e-7 * gs, "gradient: {eg} of {gs}");
    assert!(eh < 1e-6 * hs, "Hessian: {eh} of {hs}");
    // and the rest curvature is really in them: a constant κ0 differs
    let c = PlanarCable::with_rules(le, EA, EI, 3.0, 5, 3).unwrap();
    let mut gc = [0.0; 8];
    c.add_energy_gradient(&qe, &mut gc);
    let d = g
        .iter()
        .zip(&gc)
        .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
    assert!(d > 1e-3 * gs, "{d}");
}

/// The staircase profile of the exudyn reference: the section's own JSON.
fn exudyn_case(name: &str) -> (serde_json::Value, Robot<PlanarCable>, Loads) {
    let r = common::reference(&format!("exudyn_rest_curvature_{name}"));
    let section: Section = serde_json::from_value(r["params"]["sections"][0].clone()).unwrap();
    let n = section.elements;
    let mut spec = RobotSpec::new(vec![section]);
    spec.gravity_m_per_s2 = vec![0.0, 0.0];
    spec.bending_gauss_points = r["params"]["discretization"]["gauss_points_bending"]
        .as_u64()
        .unwrap() as usize;
    let robot = spec.build_planar().unwrap();
    let mut loads = Loads::default();
    for l in r["params"]["loads"].as_array().unwrap() {
        match l["type"].as_str().unwrap() {
            "tip_force" => loads.point_forces.push(PointForce {
                s_m: L,
                force_n: serde_json::from_value(l["force_n"].clone()).unwrap(),
            }),
            "tip_moment" => loads.node_moments.push(NodeMoment {
                node: n,
                moment_nm: vec![l["moment_nm"].as_f64().unwrap()],
            }),
            t => panic!("{t}"),
        }
    }
    (r, robot, loads)
}

#[test]
fn a_rest_curvature_staircase_matches_exudyns_reference_curvature() {
    for name in ["unloaded", "loaded"] {
        let (r, robot, loads) = exudyn_case(name);
        let q = solve(&robot, &loads);
        let nodes = r["values"]["nodes"].as_array().unwrap();
        assert_eq!(nodes.len(), robot.n_nodes());
        let mut err = 0.0f64;
        for (i, node) in nodes.iter().enumerate() {
            for c in 0..2 {
                err = err.max((node[c].as_f64().unwrap() - q[4 * i + c]).abs());
            }
        }
        // the same mesh and Gauss rules; positions only: softrod's clamp
        // fixes the base's position and direction but leaves its stretch
        // |r'_0| free, exudyn's fixes all four coordinates (a difference of
        // 3.3e-4 in r'_0 under the tip force, 5.9e-7 m along the rod).
        // Measured: 2.7e-9 m unloaded, 5.9e-7 m loaded.
        let tol = if name == "unloaded" { 1e-8 } else { 1e-6 };
        assert!(err < tol, "{name}: {err}");
        // the rest curvature moves the tip by decimetres: not a no-op
        assert!(q[4 * robot.n_nodes() - 3] > 0.09, "{name}");
    }
}

/// Tangent angle and position at `x` of the exact solution, by
/// composite Simpson on `θ(X) = k X + b X² / 2`.
fn exact(k: f64, b: f64, x: f64) -> (f64, f64, f64) {
    let th = |s: f64| k * s + 0.5 * b * s * s;
    let n = 2000;
    let h = x / n as f64;
    let (mut px, mut py) = (0.0, 0.0);
    for i in 0..=n {
        let w = if i == 0 || i == n {
            1.0
        } else if i % 2 == 1 {
            4.0
        } else {
            2.0
        };
        px += w * th(i as f64 * h).cos();
        py += w * th(i as f64 * h).sin();
    }
    (th(x), px * h / 3.0, py * h / 3.0)
}

#[test]
fn a_rest_curvature_ramp_under_a_tip_moment_bends_by_m_over_ei_everywhere() {
    let (a, b) = (2.0, 25.0);
    let profile = RestCurvatureProfile {
        s_m: vec![0.0, L],
        kappa_per_m: vec![a, a + b * L],
    };
    let mut errs = Vec::new();
    for elements in [8, 16, 32] {
        let robot = robot(profile.clone(), elements, 5);
        let m = -0.006;
        let loads = Loads {
            node_moments: vec![NodeMoment {
                node: elements,
                moment_nm: vec![m],
            }],
            ..Loads::default()
        };
        let q = solve(&robot, &loads);
        let mut err = 0.0f64;
        for (i, &x) in robot.node_arc().iter().enumerate() {
            let (th, px, py) = exact(a + m / EI, b, x);
            let node = &q[4 * i..4 * i + 4];
            err = err
                .max((node[0] - px).abs())
                .max((node[1] - py).abs())
                .max(L * (node[3].atan2(node[2]) - th).abs());
        }
        errs.push(err);
    }
    // fourth order in the element length (measured 1.5e-6, 7.6e-8, 4.5e-9 m)
    assert!(errs[2] < 1e-8, "{errs:?}");
    assert!(errs[0] / errs[2] > 100.0, "{errs:?}");
}

#[test]
fn a_scene_takes_a_rest_curvature_profile_and_names_its_faults() {
    let scene = |profile: &str, constant: f64| {
        format!(
            r#"{{"robot": {{"element": "planar_cable", "sections": [{{"length_m": 0.24, "ea_n": 300,
            "ei_nm2": 0.025, "elements": 8, "rest_curvature_per_m": {constant},
            "rest_curvature_profile": {profile}}}]}}, "gravity_m_per_s2": [0, 0]}}"#
        )
    };
    let ok = Scene::from_json(&scene(r#"{"s_m": [0, 0.24], "kappa_per_m": [1, 3]}"#, 0.0)).unwrap();
    let robot = ok.robot().unwrap();
    let q = solve(&robot, &ok.loads().unwrap());
    // unloaded: the tip turns by ∫ κ0 = 0.24 · 2 rad
    let th = q[4 * 8 + 3].atan2(q[4 * 8 + 2]);
    assert!((th - 0.48).abs() < 1e-6, "{th}");
    for (profile, constant, field) in [
        (
            r#"{"s_m": [0, 0.2], "kappa_per_m": [1, 3]}"#,
            0.0,
            "robot.sections[0].rest_curvature_profile.s_m[1]",
        ),
        (
            r#"{"s_m": [0.01, 0.24], "kappa_per_m": [1, 3]}"#,
            0.0,
            "robot.sections[0].rest_curvature_profile.s_m[0]",
        ),
        (
            r#"{"s_m": [0, 0.2, 0.1, 0.24], "kappa_per_m": [1, 3, 3, 1]}"#,
            0.0,
            "robot.sections[0].rest_curvature_profile.s_m[2]",
        ),
        (
            r#"{"s_m": [0, 0.24], "kappa_per_m": [1]}"#,
            0.0,
            "robot.sections[0].rest_curvature_profile.kappa_per_m",
        ),
        (
            r#"{"s_m": [0, 0.24], "kappa_per_m": [1, 1e308]}"#,
            0.0,
            "robot.sections[0].rest_curvature_profile.kappa_per_m[1]",
        ),
        (
            r#"{"s_m": [0, 0.24], "kappa_per_m": [1, 3]}"#,
            2.0,
            "robot.sections[0].rest_curvature_per_m",
        ),
    ] {
        let err = Scene::from_json(&scene(profile, constant))
            .and_then(|s| s.robot().map(|_| ()))
            .unwrap_err();
        assert_eq!(err.field(), Some(field), "{profile}: {err}");
    }
}
