//! The estimator against deflections computed by codes we did not write
//! (issue "Motion–force estimator", point 6): exudyn's ANCF cable at 128
//! elements and scikit-fem's plane-stress strip (slender, L/h = 30), under the
//! uniform, linearly varying and Gaussian-bump loads of `reference/`, small
//! and large. Markers are sampled from the reference shapes at 3, 5 and 11
//! equally spaced points, with 0.01 mm of seeded noise; softrod estimates the
//! unknown distributed load with its own 20-element model and the
//! discrepancy-principle alpha. The load that made the reference is known
//! (`params.loads`), so the resultant force, the resultant moment about the
//! base, the backbone and the bump's location can all be checked.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;
use common::reference;

use softrod::element::hermite;
use softrod::estimate::{AlphaRule, Backend, EstimatorSettings, MarkerObservation, Observation};
use softrod::loads::Load;
use softrod::loads::{LineLoad, Loads};
use softrod::scene::Scene;

const L: f64 = 0.24;

/// The reference's shape as a function of the undeformed arc coordinate.
enum Shape {
    /// exudyn nodes `[x, y, x', y']`, equally spaced: Hermite interpolation.
    Nodes(Vec<Vec<f64>>),
    /// scikit-fem centreline samples `(X, x, y)`: linear interpolation.
    Line(Vec<f64>, Vec<f64>, Vec<f64>),
}

impl Shape {
    fn at(&self, s: f64) -> [f64; 2] {
        match self {
            Shape::Nodes(n) => {
                let ne = n.len() - 1;
                let le = L / ne as f64;
                let e = ((s / le).floor() as usize).min(ne - 1);
                let xi = (s - e as f64 * le) / le;
                let (w, _, _) = hermite(xi, le);
                let (a, b) = (&n[e], &n[e + 1]);
                let c = |i: usize| w[0] * a[i] + w[1] * a[i + 2] + w[2] * b[i] + w[3] * b[i + 2];
                [c(0), c(1)]
            }
            Shape::Line(xs, x, y) => {
                let k = xs.partition_point(|v| *v <= s).clamp(1, xs.len() - 1);
                let t = (s - xs[k - 1]) / (xs[k] - xs[k - 1]);
                [
                    x[k - 1] + t * (x[k] - x[k - 1]),
                    y[k - 1] + t * (y[k] - y[k - 1]),
                ]
            }
        }
    }
}

struct Outcome {
    rms_m: f64,
    force_rel: f64,
    moment_rel: f64,
    peak_m: f64,
}

/// Estimates the load from `markers` points of the reference `name`.
fn run(name: &str, markers: usize, backend: Backend, seed: u64, sigma_model_m: f64) -> Outcome {
    let r = reference(name);
    let p = &r["params"];
    let shape = if name.starts_with("exudyn") {
        let runs = r["values"]["runs"].as_array().unwrap();
        let fine = runs
            .iter()
            .max_by_key(|x| x["elements"].as_u64().unwrap())
            .unwrap();
        Shape::Nodes(serde_json::from_value(fine["nodes"].clone()).unwrap())
    } else {
        let c = &r["values"]["centerline"];
        let v = |k: &str| -> Vec<f64> { serde_json::from_value(c[k].clone()).unwrap() };
        Shape::Line(v("X_m"), v("x_m"), v("y_m"))
    };
    // the model: the reference's sections (the strip's equivalent EA for
    // scikit-fem), 10 elements each, weightless, no actuation
    let mut scene = Scene::two_section();
    for (sec, rs) in scene
        .robot
        .sections
        .iter_mut()
        .zip(p["sections"].as_array().unwrap())
    {
        sec.ea_n = rs["ea_n"].as_f64().unwrap();
        sec.ei_nm2 = rs["ei_nm2"].as_f64().unwrap();
        sec.mass_per_length_kg_per_m = 0.0;
        sec.chambers.clear();
    }
    scene.pressures_pa.clear();
    let robot = scene.robot().unwrap();
    // the true load
    let loads: Vec<LineLoad> = p["loads"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| match serde_json::from_value(l.clone()).unwrap() {
            Load::Distributed(d) => d,
            other => panic!("{name}: not a distributed load: {other:?}"),
        })
        .collect();
    let w_true = |s: f64| -> [f64; 2] {
        loads.iter().fold([0.0, 0.0], |a, l| {
            let w = l.at(s, L);
            [a[0] + w[0], a[1] + w[1]]
        })
    };
    let k = 4800;
    let ds = L / k as f64;
    let (mut f, mut m) = ([0.0, 0.0], 0.0);
    for i in 0..k {
        let s = (i as f64 + 0.5) * ds;
        let (w, rp) = (w_true(s), shape.at(s));
        f[0] += w[0] * ds;
        f[1] += w[1] * ds;
        m += (rp[0] * w[1] - rp[1] * w[0]) * ds;
    }
    let obs = Observation {
        markers: (1..=markers)
            .map(|j| {
                let s = L * j as f64 / markers as f64;
                MarkerObservation::at_arc(s, nalgebra::Vector2::from(shape.at(s)))
            })
            .collect(),
    }
    .with_noise(1e-5, seed);
    let settings = EstimatorSettings {
        noise_sigma_m: sigma_model_m,
        // The file's subject is the discrepancy-principle α (its bounds were
        // measured with it). The crate's default is now the evidence rule, whose
        // intervals are checked in tests/coverage.rs; on `uniform_small` with 5
        // markers it over-smooths to a 55 % resultant error (measured), so it is
        // not held to these bounds.
        alpha_rule: AlphaRule::Discrepancy,
        ..EstimatorSettings::default()
    };
    let mut est = softrod::estimate::EstimatorSettings {
        backend,
        ..settings
    }
    .build_for(&robot, &Loads::default())
    .unwrap();
    let e = est.step(&obs).unwrap();
    assert!(e.report.status.is_converged(), "{name}: {:?}", e.report);
    let nodes = e.node_positions::<2>().unwrap();
    let n = nodes.len();
    let rms = (nodes
        .iter()
        .enumerate()
        .map(|(i, x)| {
            let t = shape.at(L * i as f64 / (n - 1) as f64);
            (x[0] - t[0]).powi(2) + (x[1] - t[1]).powi(2)
        })
        .sum::<f64>()
        / n as f64)
        .sqrt();
    let fe = &e.resultant_force_n;
    let force_rel = ((fe[0] - f[0]).powi(2) + (fe[1] - f[1]).powi(2)).sqrt() / f[0].hypot(f[1]);
    let moment_rel = (e.resultant_moment_nm[0] - m).abs() / m.abs();
    let peak_m = (0..=480)
        .map(|i| L * i as f64 / 480.0)
        .max_by(|a, b| e.load_at(*a)[1].abs().total_cmp(&e.load_at(*b)[1].abs()))
        .unwrap();
    Outcome {
        rms_m: rms,
        force_rel,
        moment_rel,
        peak_m,
    }
}

const CASES: [&str; 6] = [
    "uniform_small",
    "uniform_large",
    "linear_small",
    "linear_large",
    "gaussian_small",
    "gaussian_large",
];

/// exudyn's shapes, 0.01 mm noise, σ declared 0.01 mm. Bounds, each failed by
/// an estimator that returns no load (RMS = the deflection, 0.5 mm to 0.1 m;
/// errors 100 %): backbone RMS < 0.1 mm; resultant moment about the base
/// < 15 %; resultant force < 40 % with 5 and 11 markers (with 3 position-only
/// markers the force is not separated from the moment: 85 % measured, not
/// bounded); the Gaussian bump's peak within 2 cm of 0.16 m. Measured (newton,
/// seed 7): RMS ≤ 5.7e-5 m, moment ≤ 10.7 %, force ≤ 36.6 % (5, 11 markers;
/// the penalty ∫w² biases a uniform load's resultant low), peak at 0.144 to
/// 0.162 m. The sqp backend is run with 5 markers and held to the same bounds.
#[test]
fn estimates_from_exudyn_deflections() {
    for case in CASES {
        for (k, backend) in [
            (3, Backend::Newton),
            (5, Backend::Newton),
            (11, Backend::Newton),
            (5, Backend::Sqp),
        ] {
            let o = run(&format!("exudyn_{case}"), k, backend, 7, 1e-5);
            println!(
                "exudyn {case:15} {k:2} markers {:6}: rms {:.2e} m, force {:.1} %, moment {:.1} %, peak {:.3} m",
                backend.name(),
                o.rms_m,
                100.0 * o.force_rel,
                100.0 * o.moment_rel,
                o.peak_m
            );
            assert!(o.rms_m < 1e-4, "{case} {k}: rms {}", o.rms_m);
            assert!(o.moment_rel < 0.15, "{case} {k}: moment {}", o.moment_rel);
            if k >= 5 {
                assert!(o.force_rel < 0.40, "{case} {k}: force {}", o.force_rel);
            }
            if case.starts_with("gaussian") {
                assert!(
                    (o.peak_m - 0.16).abs() < 0.02,
                    "{case} {k}: peak at {}",
                    o.peak_m
                );
            }
        }
    }
}

/// scikit-fem's slender strip. Small cases: as for exudyn (0.01 mm noise and
/// σ; the bump's peak checked with 5 and 11 markers: 3 put it at 0.131 m).
/// Large cases: rod theory misses the continuum by about 0.4 mm (shear, the
/// clamp, the material law: `tests/references.rs`), 40 times the noise; with
/// σ = 0.01 mm the estimator fits that model error with spurious loads (the
/// paper's virtual payload: force errors 31 to 155 %, growing with the marker
/// count). So the large cases declare σ = 0.2 mm, the model error's size, and
/// are held to: backbone RMS < 0.5 mm, moment < 10 %; the force resultant is
/// not identifiable under that model error and is reported, not bounded.
/// Measured (newton, seed 7): small: RMS ≤ 9.7e-6 m, moment ≤ 11.8 %, force
/// ≤ 38.4 % (5, 11 markers); large: RMS ≤ 2.8e-4 m, moment ≤ 5.5 %, force
/// 42 to 53 %.
#[test]
fn estimates_from_scikit_fem_deflections() {
    for case in CASES {
        let large = case.ends_with("large");
        let sigma = if large { 2e-4 } else { 1e-5 };
        for k in [3usize, 5, 11] {
            let o = run(
                &format!("skfem_slender_{case}"),
                k,
                Backend::Newton,
                7,
                sigma,
            );
            println!(
                "skfem  {case:15} {k:2} markers: rms {:.2e} m, force {:.1} %, moment {:.1} %, peak {:.3} m",
                o.rms_m,
                100.0 * o.force_rel,
                100.0 * o.moment_rel,
                o.peak_m
            );
            if large {
                assert!(o.rms_m < 5e-4 && o.moment_rel < 0.10, "{case} {k}");
            } else {
                assert!(o.rms_m < 1e-4 && o.moment_rel < 0.15, "{case} {k}");
                if k >= 5 {
                    assert!(o.force_rel < 0.40, "{case} {k}: force {}", o.force_rel);
                    if case.starts_with("gaussian") {
                        assert!(
                            (o.peak_m - 0.16).abs() < 0.02,
                            "{case} {k}: peak at {}",
                            o.peak_m
                        );
                    }
                }
            }
        }
    }
}
