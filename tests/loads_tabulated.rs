//! A tabulated distributed load (`LineLoad::Tabulated`, the scene's
//! `{"type": "distributed", "profile": "tabulated"}`): small-load tip
//! deflections against Euler–Bernoulli closed forms, and a table that
//! reproduces a `linear` profile against that profile.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::assembly::{Robot, RobotSpec, Section};
use softrod::element::PlanarCable;
use softrod::loads::{LineLoad, Loads};
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

const L: f64 = 0.24;
const EI: f64 = 0.025;
const EA: f64 = 300.0;

fn cantilever(elements: usize) -> Robot<PlanarCable> {
    let mut spec = RobotSpec::new(vec![Section::uniform(L, EA, EI, elements)]);
    spec.gravity_m_per_s2 = vec![0.0, 0.0];
    spec.build_planar().unwrap()
}

fn solve(robot: &Robot<PlanarCable>, loads: &Loads) -> Vec<f64> {
    let eq = StaticSolver::default().solve(robot, loads, None).unwrap();
    assert!(eq.report.status.is_converged(), "{:?}", eq.report.status);
    eq.q.data.into()
}

fn table(s: &[f64], wy: &[f64]) -> Loads {
    Loads {
        line_loads: vec![LineLoad::Tabulated {
            s_m: s.to_vec(),
            w_n_per_m: wy.iter().map(|w| vec![0.0, *w]).collect(),
        }],
        ..Loads::default()
    }
}

/// Tip deflection of the Euler–Bernoulli cantilever under the
/// piecewise-linear load `w` (N/m) through the points `(s, wy)`, zero
/// outside: the integral of `w(x)` against the tip's influence line
/// `x² (3L − x) / (6 EI)` (Maxwell–Betti), by 3-point Gauss–Legendre per
/// table segment (the integrand is a quartic there: exact).
fn euler_bernoulli_tip(s: &[f64], wy: &[f64]) -> f64 {
    let g = [
        (-(0.6f64).sqrt(), 5.0 / 9.0),
        (0.0, 8.0 / 9.0),
        ((0.6f64).sqrt(), 5.0 / 9.0),
    ];
    let mut d = 0.0;
    for k in 0..s.len() - 1 {
        let (a, b) = (s[k], s[k + 1]);
        for (t, wt) in g {
            let x = 0.5 * (a + b) + 0.5 * (b - a) * t;
            let w = wy[k] + (x - a) / (b - a) * (wy[k + 1] - wy[k]);
            d += 0.5 * (b - a) * wt * w * x * x * (3.0 * L - x) / (6.0 * EI);
        }
    }
    d
}

/// Small loads: a triangle falling from `w0` at the base to 0 at the tip
/// (`δ = w0 L⁴ / 30 EI`), a trapezoid (`w_b L⁴/30EI + 11 w_t L⁴/120EI`) and
/// an irregular patch table whose entries sit inside elements and which
/// ends before the tip (against the influence-line integral). Each load
/// makes the tip deflect by 1e-4 L. Cubic Hermite elements with exactly
/// integrated consistent loads are nodally exact in linear theory, so what
/// remains is the geometric nonlinearity, O((δ/L)²): measured by solving
/// at twice the load (the relative deviation must grow about 4-fold,
/// between 3.5 and 4.5, which shows it is that correction and not a
/// discretization error) and bounded at 1e-6 relative (measured: 7e-9,
/// growing to 2.8e-8 at twice the load, ratio 4.00).
#[test]
fn small_tabulated_loads_match_euler_bernoulli() {
    let robot = cantilever(10);
    let delta = 1e-4 * L;
    let unit = L.powi(4) / EI;
    let cases: Vec<(&str, Vec<f64>, Vec<f64>, f64)> = vec![
        ("triangle", vec![0.0, L], vec![1.0, 0.0], unit / 30.0),
        (
            "trapezoid",
            vec![0.0, L],
            vec![1.0, 0.4],
            unit / 30.0 + 0.4 * 11.0 * unit / 120.0,
        ),
        (
            "patch",
            vec![0.013, 0.05, 0.117, 0.2],
            vec![0.3, 1.0, -0.2, 0.6],
            f64::NAN,
        ),
    ];
    for (name, s, shape, closed) in cases {
        let per_unit = euler_bernoulli_tip(&s, &shape);
        if closed.is_finite() {
            // the influence integral reproduces the textbook closed forms
            assert!(
                (per_unit - closed).abs() < 1e-14 * closed,
                "{name}: {per_unit} vs {closed}"
            );
        }
        let scale = delta / per_unit;
        let mut rel = Vec::new();
        for f in [1.0, 2.0] {
            let wy: Vec<f64> = shape.iter().map(|w| -f * scale * w).collect();
            let q = solve(&robot, &table(&s, &wy));
            let want = -f * delta;
            rel.push((q[q.len() - 3] - want).abs() / (f * delta));
        }
        println!(
            "{name}: relative tip error {:.3e} at δ = 1e-4 L, {:.3e} at twice the load (ratio {:.2})",
            rel[0],
            rel[1],
            rel[1] / rel[0]
        );
        assert!(rel[0] < 1e-6, "{name}: {rel:?}");
        let ratio = rel[1] / rel[0];
        assert!((3.5..4.5).contains(&ratio), "{name}: {rel:?}");
    }
}

/// A table through points of a `linear` profile (entries at irregular arc
/// positions, inside elements) gives the linear profile's equilibrium to
/// 1e-12 m, at a large deflection (6 N/m at the tip on EI = 0.025 N·m²).
#[test]
fn a_table_on_a_line_is_the_linear_profile() {
    let robot = cantilever(12);
    let (w0, w1) = ([0.9, -1.5], [-1.2, -6.0]);
    let linear = Loads {
        line_loads: vec![LineLoad::Linear {
            w_start_n_per_m: w0.to_vec(),
            w_end_n_per_m: w1.to_vec(),
        }],
        ..Loads::default()
    };
    let s = [0.0, 0.037, 0.1, 0.1305, 0.2, L];
    let tab = Loads {
        line_loads: vec![LineLoad::Tabulated {
            s_m: s.to_vec(),
            w_n_per_m: s
                .iter()
                .map(|x| (0..2).map(|i| w0[i] + x / L * (w1[i] - w0[i])).collect())
                .collect(),
        }],
        ..Loads::default()
    };
    let (a, b) = (solve(&robot, &linear), solve(&robot, &tab));
    let worst = a
        .iter()
        .zip(&b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    let tip = a[a.len() - 3];
    println!("table vs linear: worst coordinate difference {worst:e} (tip y {tip} m)");
    assert!(tip < -0.05, "the case must bend the robot far: tip y {tip}");
    assert!(worst < 1e-12, "{worst}");
}

/// The scene's tabulated profile is the code's; a NaN value in code is
/// refused naming its field.
#[test]
fn scene_table_and_code_refusals() {
    let text = r#"{"robot": {"sections": [{"length_m": 0.24, "ea_n": 300, "ei_nm2": 0.025, "elements": 8}]},
        "gravity_m_per_s2": [0, 0],
        "loads": [{"type": "distributed", "profile": "tabulated", "s_m": [0, 0.1, 0.24],
                   "w_n_per_m": [[0, -1], [0, -0.5], [0, 0]]}]}"#;
    let loads = Scene::from_json(text).unwrap().loads().unwrap();
    assert_eq!(
        loads.line_loads,
        vec![LineLoad::Tabulated {
            s_m: vec![0.0, 0.1, 0.24],
            w_n_per_m: vec![vec![0.0, -1.0], vec![0.0, -0.5], vec![0.0, 0.0]],
        }]
    );
    let robot = cantilever(8);
    let mut bad = table(&[0.0, 0.1], &[1.0, 2.0]);
    if let LineLoad::Tabulated { w_n_per_m, .. } = &mut bad.line_loads[0] {
        w_n_per_m[1][0] = f64::NAN;
    }
    let err = robot.validate_loads(&bad).unwrap_err();
    assert_eq!(err.field(), Some("line_loads[0].w_n_per_m[1][0]"));
    let off = table(&[0.1, 0.25], &[1.0, 2.0]);
    assert_eq!(
        robot.dead_force(&off).unwrap_err().field(),
        Some("line_loads[0].s_m[1]")
    );
}
