//! softrod's static solutions against references computed by codes we did not
//! write: exudyn's ANCF cable (`ObjectANCFCable2D`), the extensible elastica by
//! shooting (scipy), and a plane-stress continuum strip (scikit-fem). The
//! reference JSON is committed under `reference/`; `validation/` regenerates it.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;
#[path = "common/statics_cases.rs"]
mod statics_cases;
use common::reference;
// the exudyn reference cases: the one list the statics tests and benches share
use statics_cases::EXUDYN as CASES;

use serde_json::Value;
use softrod::assembly::Clamp;
use softrod::loads::Load;
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

const L: f64 = 0.24;

/// A softrod scene with the reference's sections, base and loads.
fn scene(r: &Value, elements: usize, bending_gauss: usize, clamp: Clamp) -> Scene {
    let p = &r["params"];
    let sections = p["sections"].as_array().unwrap();
    let mut text = serde_json::json!({
        "robot": {
            "sections": sections.iter().map(|s| serde_json::json!({
                "length_m": s["length_m"], "ea_n": s["ea_n"], "ei_nm2": s["ei_nm2"],
                "elements": elements / sections.len(),
            })).collect::<Vec<_>>(),
            "bending_gauss_points": bending_gauss,
        },
        "base": p["base"],
        "gravity_m_per_s2": [0.0, 0.0],
    });
    text["loads"] = p["loads"].clone();
    let mut s: Scene = serde_json::from_value(text).unwrap();
    s.base.clamp = clamp;
    let _: Vec<Load> = serde_json::from_value(p["loads"].clone()).unwrap();
    s.validate().unwrap();
    s
}

fn solve(s: &Scene) -> Vec<f64> {
    let robot = s.robot().unwrap();
    let eq = StaticSolver::default()
        .solve(&robot, &s.loads().unwrap(), None)
        .unwrap();
    assert!(eq.report.status.is_converged());
    eq.q.data.into()
}

fn tip(q: &[f64]) -> [f64; 2] {
    [q[q.len() - 4], q[q.len() - 3]]
}

fn dist(a: [f64; 2], b: &Value) -> f64 {
    let b: Vec<f64> = serde_json::from_value(b.clone()).unwrap();
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

fn exudyn_clamp(r: &Value) -> Clamp {
    let c = r["params"]["discretization"]["clamp"]
        .as_str()
        .unwrap_or("");
    if c.contains("all four") {
        Clamp::Full
    } else {
        Clamp::PositionAndDirection
    }
}

/// At equal element count, equal Gauss rules (5 axial, 3 bending) and the
/// same clamp (exudyn fixes all four base coordinates), softrod and exudyn
/// discretize the same energy, so their nodes must coincide up to the solvers'
/// tolerances (exudyn: relative 1e-8 on its residual). Measured: at most
/// 1.3e-11 m over all 12 cases and all meshes of 2 to 128 elements. Bound:
/// 1e-9 m; a 1e-6 relative change of EI moves the large-deflection tips by
/// about 1e-7 m, so the bound catches any change of the model.
#[test]
fn nodes_match_exudyn_at_equal_element_count() {
    for case in CASES {
        let ex = reference(&format!("exudyn_{case}"));
        let clamp = exudyn_clamp(&ex);
        assert_eq!(
            clamp,
            Clamp::Full,
            "{case}: the reference's clamp changed; update this test"
        );
        let runs = ex["values"]["runs"].as_array().unwrap();
        assert!(runs.len() >= 5, "{case}: too few exudyn runs");
        let mut worst = 0.0f64;
        for run in runs {
            let n = run["elements"].as_u64().unwrap() as usize;
            let q = solve(&scene(&ex, n, 3, clamp));
            let nodes: Vec<Vec<f64>> = serde_json::from_value(run["nodes"].clone()).unwrap();
            assert_eq!(nodes.len(), n + 1);
            for (a, b) in nodes.iter().zip(q.chunks(4)) {
                worst = worst.max(((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt());
            }
        }
        println!("{case:26} exudyn node-by-node: max {worst:.2e} m");
        assert!(worst < 1e-9, "{case}: {worst} m");
    }
}

/// Converged solutions: softrod at 256 elements (default rules and clamp)
/// against exudyn's finest mesh and the extensible elastica. The bound
/// is 1e-5 L for both. Measured: at most 7.2e-9 L against exudyn at 128
/// elements (exudyn's own discretization error) and 5.5e-11 L against the
/// elastica; so we also hold the elastica to 1e-9 L.
#[test]
fn converged_tips_match_exudyn_and_the_elastica() {
    for case in CASES {
        let ex = reference(&format!("exudyn_{case}"));
        let el = reference(&format!("elastica_{case}"));
        assert!(
            el["values"]["model"]
                .as_str()
                .unwrap_or("")
                .contains("extensible")
        );
        let fine = tip(&solve(&scene(&ex, 256, 5, Clamp::PositionAndDirection)));
        let e_ex = dist(fine, &ex["values"]["tip_position_m"]) / L;
        let e_el = dist(fine, &el["values"]["tip_position_m"]) / L;
        println!(
            "{case:26} 256 elements: vs exudyn {e_ex:.2e} L, vs extensible elastica {e_el:.2e} L"
        );
        assert!(e_ex < 1e-5 && e_el < 1e-5, "{case}: {e_ex} {e_el}");
        assert!(e_el < 1e-9, "{case}: {e_el}");
    }
}

/// The slender plane-stress strip (L/h = 30, scikit-fem, finest mesh) against
/// the rod with the strip's EI and EA = 12 EI/h². Rod theory neglects shear
/// and the continuum's clamp differs, so they differ by a fraction of a
/// percent. Bound: 0.25 % of L (the issue's) and the reference's own
/// `pass_bound` (twice the rod–continuum gap of the elastica plus the last
/// mesh change) where it gives one. Small cases are compared in y only (a
/// linear continuum analysis has no axial shortening).
#[test]
fn slender_strip_matches_the_rod_within_a_quarter_percent() {
    let mut checked = 0;
    for case in CASES {
        let path = format!(
            "{}/reference/skfem_slender_{case}.json",
            env!("CARGO_MANIFEST_DIR")
        );
        if !std::path::Path::new(&path).exists() {
            continue;
        }
        let sk = reference(&format!("skfem_slender_{case}"));
        let t = tip(&solve(&scene(&sk, 128, 5, Clamp::PositionAndDirection)));
        let want: Vec<f64> =
            serde_json::from_value(sk["values"]["tip_position_m"].clone()).unwrap();
        let bound = &sk["values"]["pass_bound"];
        let (err, own) = if let Some(b) = bound["tip_y_abs_m"].as_f64() {
            ((t[1] - want[1]).abs(), b)
        } else {
            (
                ((t[0] - want[0]).powi(2) + (t[1] - want[1]).powi(2)).sqrt(),
                bound["tip_position_abs_m"]
                    .as_f64()
                    .unwrap_or(f64::INFINITY),
            )
        };
        println!(
            "{case:26} scikit-fem slender strip: {err:.3e} m = {:.4} % of L (reference bound {own:.3e} m)",
            100.0 * err / L
        );
        assert!(err < 0.0025 * L, "{case}: {err}");
        assert!(err <= own, "{case}: {err} > {own}");
        checked += 1;
    }
    assert!(checked >= 6, "only {checked} scikit-fem cases found");
}
