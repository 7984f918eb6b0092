//! Estimation (Sec. III): analytic derivatives against finite differences,
//! agreement of the two backends, and synthetic-truth estimation against a
//! finer "real robot". Every test states the bound a broken estimator fails.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;
use common::lcg;
use proptest::prelude::*;
use softrod::assembly::Robot;
use softrod::element::{Element, PlanarCable};
use softrod::estimate::{
    Backend, Estimate, EstimatorSettings, LoadModel, MarkerObservation, NewtonEstimator,
    Observation,
};
use softrod::loads::{LineLoad, Loads, PointForce};
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

fn two_section(elements_per_section: usize) -> Robot<PlanarCable> {
    let mut s = Scene::two_section();
    for sec in &mut s.robot.sections {
        sec.elements = elements_per_section;
    }
    s.robot().unwrap()
}

/// Solved at the model's optimum: converged, or stopped there with a
/// misfit the fit test puts beyond the noise (a bound held active against
/// the data, or a load model that cannot explain the truth: the honest
/// status since the fit test, the optimum the same).
fn solved(s: &softrod::outcome::EstimateStatus) -> bool {
    s.is_converged()
        || matches!(
            s,
            softrod::outcome::EstimateStatus::MisfitBeyondNoise { .. }
        )
}

fn known() -> Loads {
    Scene::two_section().loads().unwrap()
}

/// The marker Jacobian `∂(Aq)/∂F` (adjoint solves) equals central finite
/// differences of the static solve, for the distributed load (84 columns,
/// positions and a tangent) and the concentrated force. Bound: 1e-6 of the
/// largest entry (a wrong sign, a missing restriction to the free rows or a
/// transposed K would be off by O(1)).
#[test]
fn marker_jacobian_matches_finite_differences() {
    let robot = two_section(10);
    for model in [LoadModel::Distributed, LoadModel::Concentrated { node: 15 }] {
        let settings = EstimatorSettings {
            load_model: model,
            alpha: Some(1.0),
            ..EstimatorSettings::default()
        };
        let mut est = NewtonEstimator::new(&robot, &known(), &settings).unwrap();
        let n_f = match model {
            LoadModel::Distributed => robot.n_q(),
            _ => 2,
        };
        let f: Vec<f64> = lcg(3, n_f).iter().map(|v| 0.3 * v).collect();
        let mut obs = Observation {
            markers: vec![
                MarkerObservation::at_node(7, nalgebra::Vector2::zeros()),
                MarkerObservation::at_arc(0.173, nalgebra::Vector2::zeros()),
            ],
        };
        obs.markers[1].tangent = Some(vec![1.0, 0.0]);
        let (_, jac) = est.markers_and_jacobian(&obs, &f).unwrap();
        let m = obs.n_components();
        let scale = jac.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        let h = 1e-3;
        let mut worst = 0.0f64;
        for j in 0..n_f {
            let mut fp = f.clone();
            let mut fm = f.clone();
            fp[j] += h;
            fm[j] -= h;
            let (yp, _) = est.markers_and_jacobian(&obs, &fp).unwrap();
            let (ym, _) = est.markers_and_jacobian(&obs, &fm).unwrap();
            for i in 0..m {
                let fd = (yp[i] - ym[i]) / (2.0 * h);
                worst = worst.max((fd - jac[(i, j)]).abs() / scale);
            }
        }
        eprintln!("{model:?}: max |J_fd - J| / max|J| = {worst:.2e}");
        assert!(worst < 1e-6, "{model:?}: {worst}");
    }
}

/// The reduced gradient (29) equals central finite differences of the
/// objective, componentwise for the concentrated force and along random
/// directions for the distributed load. Bound: relative 1e-6.
#[test]
fn gradient_matches_finite_differences() {
    let robot = two_section(10);
    let eq = StaticSolver::default()
        .solve(&robot, &known(), None)
        .unwrap();
    let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[4, 8, 12, 16, 20])
        .unwrap()
        .with_noise(1e-4, 11);
    for model in [LoadModel::Distributed, LoadModel::Concentrated { node: 20 }] {
        let settings = EstimatorSettings {
            load_model: model,
            alpha: Some(3.0),
            ..EstimatorSettings::default()
        };
        let mut est = NewtonEstimator::new(&robot, &known(), &settings).unwrap();
        let n_f = match model {
            LoadModel::Distributed => robot.n_q(),
            _ => 2,
        };
        let f: Vec<f64> = lcg(5, n_f).iter().map(|v| 0.1 * v).collect();
        let (_, g) = est.objective_and_gradient(&obs, &f, 3.0).unwrap();
        let dirs: Vec<Vec<f64>> = if n_f == 2 {
            vec![vec![1.0, 0.0], vec![0.0, 1.0]]
        } else {
            (0..6).map(|k| lcg(100 + k, n_f)).collect()
        };
        let mut worst = 0.0f64;
        for dir in dirs {
            let h = 1e-4;
            let fp: Vec<f64> = f.iter().zip(&dir).map(|(a, b)| a + h * b).collect();
            let fm: Vec<f64> = f.iter().zip(&dir).map(|(a, b)| a - h * b).collect();
            let (jp, _) = est.objective_and_gradient(&obs, &fp, 3.0).unwrap();
            let (jm, _) = est.objective_and_gradient(&obs, &fm, 3.0).unwrap();
            let fd = (jp - jm) / (2.0 * h);
            let an: f64 = g.iter().zip(&dir).map(|(a, b)| a * b).sum();
            let rel = (fd - an).abs() / an.abs().max(1e-12);
            worst = worst.max(rel);
        }
        eprintln!("{model:?}: gradient relative error {worst:.2e}");
        assert!(worst < 1e-6, "{model:?}: {worst}");
    }
}

fn backbone_rms(
    coarse: &Robot<PlanarCable>,
    q_est: &[f64],
    fine: &Robot<PlanarCable>,
    q_true: &[f64],
) -> f64 {
    let n = 100;
    let l = coarse.length();
    let s2: f64 = (0..=n)
        .map(|i| {
            let s = l * i as f64 / n as f64;
            let a = coarse.position_at(q_est, s).unwrap();
            let b = fine.position_at(q_true, s).unwrap();
            (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)
        })
        .sum();
    (s2 / (n + 1) as f64).sqrt()
}

/// Resultant force and moment (about the base, in the deformed shape) of a
/// line load on a solved configuration, by 5-point Gauss per element.
fn true_resultant(robot: &Robot<PlanarCable>, q: &[f64], load: &LineLoad) -> ([f64; 2], f64) {
    let rule = softrod::quadrature::GaussRule::new(5).unwrap();
    let (mut f, mut m) = ([0.0; 2], 0.0);
    let l = robot.length();
    let r0 = robot.position_at(q, 0.0).unwrap();
    for e in 0..robot.n_elements() {
        let (s0, s1) = (robot.node_arc()[e], robot.node_arc()[e + 1]);
        for (xi, wt) in rule.iter() {
            let s = s0 + xi * (s1 - s0);
            let w = load.at(s, l);
            let r = robot.position_at(q, s).unwrap();
            let dw = wt * (s1 - s0);
            f[0] += dw * w[0];
            f[1] += dw * w[1];
            m += dw * ((r[0] - r0[0]) * w[1] - (r[1] - r0[1]) * w[0]);
        }
    }
    (f, m)
}

struct Truth {
    name: &'static str,
    load: LineLoad,
}

fn truths() -> Vec<Truth> {
    vec![
        Truth {
            name: "uniform",
            load: LineLoad::Uniform {
                w_n_per_m: vec![0.0, -1.0],
            },
        },
        Truth {
            name: "linear",
            load: LineLoad::Linear {
                w_start_n_per_m: vec![0.0, 0.0],
                w_end_n_per_m: vec![0.5, -2.0],
            },
        },
        Truth {
            name: "gaussian",
            load: LineLoad::Gaussian {
                amplitude_n_per_m: vec![0.0, -20.0],
                center_m: 0.16,
                width_m: 0.01,
            },
        },
    ]
}

fn estimate_truth(
    truth: &Truth,
    n_markers: usize,
    backend: Backend,
    seed: u64,
) -> (Estimate, f64, f64, f64) {
    let fine = two_section(20);
    let coarse = two_section(10);
    let mut loads = known();
    loads.line_loads.push(truth.load.clone());
    let eq = StaticSolver::default().solve(&fine, &loads, None).unwrap();
    // markers evenly spaced over the coarse nodes, the tip always included
    let n_nodes = coarse.n_nodes();
    let nodes: Vec<usize> = (1..=n_markers)
        .map(|k| (k * (n_nodes - 1) + n_markers / 2) / n_markers)
        .collect();
    let obs = Observation {
        markers: nodes
            .iter()
            .map(|&n| {
                let s = coarse.node_arc()[n];
                MarkerObservation::at_node(n, fine.position_at(eq.q.as_slice(), s).unwrap())
            })
            .collect(),
    }
    .with_noise(1e-5, seed);
    let settings = EstimatorSettings::default();
    let mut est = softrod::estimate::EstimatorSettings {
        backend,
        ..settings
    }
    .build_for(&coarse, &known())
    .unwrap();
    let e = est.step(&obs).unwrap();
    let rms = backbone_rms(&coarse, e.q.as_slice(), &fine, eq.q.as_slice());
    let (f_true, m_true) = true_resultant(&fine, eq.q.as_slice(), &truth.load);
    let df = ((e.resultant_force_n[0] - f_true[0]).powi(2)
        + (e.resultant_force_n[1] - f_true[1]).powi(2))
    .sqrt();
    let dm = (e.resultant_moment_nm[0] - m_true).abs();
    (e, rms, df, dm)
}

/// Synthetic truth: the "real robot" is the static solution on a mesh twice
/// as fine (2 x 20 elements) under a load the estimator does not know
/// (uniform 1 N/m, linear to 2 N/m, Gaussian bump of 20 N/m at 0.16 m with
/// sigma 0.01 m); 3 to 11 markers with 0.01 mm seeded noise; the coarse model
/// (2 x 10 elements) estimates with alpha from the discrepancy principle.
/// Bounds (a broken estimator, e.g. one that ignores the markers, is off by
/// the whole deflection, centimetres, and by the whole resultant):
/// backbone RMS below 0.1 mm; resultant force error below 25 % of the true
/// resultant; moment error below 25 %; with 11 markers the Gaussian bump's
/// peak within 3 cm of 0.16 m.
#[test]
fn synthetic_truth_is_recovered() {
    for truth in truths() {
        for &n in &[3usize, 5, 11] {
            let (e, rms, df, dm) = estimate_truth(&truth, n, Backend::Newton, 42 + n as u64);
            let fine = two_section(20);
            let mut loads = known();
            loads.line_loads.push(truth.load.clone());
            let eq = StaticSolver::default().solve(&fine, &loads, None).unwrap();
            let (f_true, m_true) = true_resultant(&fine, eq.q.as_slice(), &truth.load);
            let fnorm = (f_true[0].powi(2) + f_true[1].powi(2)).sqrt();
            let peak = e
                .sample_load(241)
                .into_iter()
                .max_by(|a, b| {
                    let na = a.1[0].hypot(a.1[1]);
                    let nb = b.1[0].hypot(b.1[1]);
                    na.partial_cmp(&nb).unwrap()
                })
                .unwrap()
                .0;
            eprintln!(
                "{:>8} {:2} markers: rms {:.3e} m, |dF| {:.3e} N ({:.1} % of {:.3}), |dM| {:.3e} N m ({:.1} %), peak at {:.3} m, alpha {:.2e}, {} it",
                truth.name,
                n,
                rms,
                df,
                100.0 * df / fnorm,
                fnorm,
                dm,
                100.0 * dm / m_true.abs(),
                peak,
                e.report.alpha,
                e.report.iterations
            );
            assert!(e.report.status.is_converged());
            assert!(rms < 1e-4, "{} {n}: rms {rms}", truth.name);
            assert!(df < 0.25 * fnorm, "{} {n}: dF {df}", truth.name);
            assert!(dm < 0.25 * m_true.abs(), "{} {n}: dM {dm}", truth.name);
            if truth.name == "gaussian" && n == 11 {
                assert!((peak - 0.16).abs() < 0.03, "peak at {peak}");
            }
        }
    }
}

fn pressures(u: &[f64]) -> Vec<f64> {
    vec![50e3 * (1.0 + u[0]), 0.0, 0.0, 30e3 * (1.0 + u[1])]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 6, rng_seed: proptest::test_runner::RngSeed::Fixed(0x50f7_70d4), .. ProptestConfig::default() })]

    /// Both backends solve (25): on randomized problems (pressures, unknown
    /// tip force and uniform load, marker noise, alpha over two decades,
    /// both load models) they agree at convergence: F to a relative 1e-6,
    /// node positions to 1e-9 m. A backend with a wrong gradient, a wrong
    /// constraint or an early stop differs by far more.
    #[test]
    fn backends_agree(u in prop::collection::vec(-1.0f64..1.0, 6), seed in 0u64..1000, concentrated in any::<bool>()) {
        let robot = two_section(10);
        let mut k = known();
        k.pressures_pa = pressures(&u);
        let mut truth = k.clone();
        truth.point_forces.push(PointForce { s_m: 0.24, force_n: vec![0.05 * u[2], -0.1 - 0.05 * u[3]] });
        truth.line_loads.push(LineLoad::Uniform { w_n_per_m: vec![0.0, -0.5 + 0.3 * u[4]] });
        let eq = StaticSolver::default().solve(&robot, &truth, None).unwrap();
        let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[4, 8, 12, 16, 20]).unwrap().with_noise(1e-5, seed);
        let alpha = 10f64.powf(1.0 + u[5]);
        let model = if concentrated { LoadModel::Concentrated { node: 20 } } else { LoadModel::Distributed };
        // both at the tight tolerance only (the statistical test would stop
        // each within 10 % of a standard deviation of the optimum, not 1e-6)
        let settings = EstimatorSettings { alpha: Some(alpha), load_model: model, statistical_tolerance: 0.0, ..EstimatorSettings::default() };
        let en = softrod::estimate::EstimatorSettings { backend: Backend::Newton, ..settings.clone() }.build_for(&robot, &k).unwrap().step(&obs).unwrap();
        let es = softrod::estimate::EstimatorSettings { backend: Backend::Sqp, ..settings }.build_for(&robot, &k).unwrap().step(&obs).unwrap();
        prop_assert!(solved(&en.report.status) && solved(&es.report.status));
        let nf: f64 = en.f.iter().map(|v| v * v).sum::<f64>().sqrt();
        let df: f64 = en.f.iter().zip(&es.f).map(|(a, b)| (a - b).powi(2)).sum::<f64>().sqrt();
        let dq = en.node_positions::<2>().unwrap().iter().zip(es.node_positions::<2>().unwrap()).map(|(a, b)| (a - b).norm()).fold(0.0f64, f64::max);
        eprintln!("{model:?} alpha {alpha:.2e}: |dF|/|F| = {:.2e}, max node distance {:.2e} m (newton {} it, sqp {} it)", df / nf, dq, en.report.iterations, es.report.iterations);
        prop_assert!(df <= 1e-6 * nf, "F differs: {}", df / nf);
        prop_assert!(dq <= 1e-9, "positions differ: {dq}");
    }
}

/// A warm step on the same observation converges at once and returns the
/// same estimate; an observation far from the last one is taken in
/// intermediate steps (and gives the same answer as a cold start).
#[test]
fn warm_steps_and_incremental_observations() {
    let robot = two_section(10);
    let k = known();
    let mut truth = k.clone();
    truth.point_forces.push(PointForce {
        s_m: 0.24,
        force_n: vec![0.0, -0.2],
    });
    let eq1 = StaticSolver::default().solve(&robot, &truth, None).unwrap();
    truth.point_forces[0].force_n = vec![0.0, -1.0];
    let eq2 = StaticSolver::default().solve(&robot, &truth, None).unwrap();
    let o1 = Observation::of_nodes(&robot, eq1.q.as_slice(), &[4, 8, 12, 16, 20]).unwrap();
    let o2 = Observation::of_nodes(&robot, eq2.q.as_slice(), &[4, 8, 12, 16, 20]).unwrap();
    let settings = EstimatorSettings {
        alpha: Some(10.0),
        max_observation_jump_m: 0.01,
        // the tight tolerance: two paths to one optimum compared to 1e-6
        statistical_tolerance: 0.0,
        ..EstimatorSettings::default()
    };
    let mut est = softrod::estimate::EstimatorSettings {
        backend: Backend::Newton,
        ..settings.clone()
    }
    .build_for(&robot, &k)
    .unwrap();
    let a = est.step(&o1).unwrap();
    let b = est.step(&o1).unwrap();
    assert!(b.report.iterations <= 1, "{}", b.report);
    let d: f64 =
        a.f.iter()
            .zip(&b.f)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
    assert!(d < 1e-6, "{d}");
    let c = est.step(&o2).unwrap();
    assert!(c.report.sub_steps > 1, "{}", c.report);
    let mut cold = softrod::estimate::EstimatorSettings {
        backend: Backend::Newton,
        ..settings
    }
    .build_for(&robot, &k)
    .unwrap();
    let c2 = cold.step(&o2).unwrap();
    let nf: f64 = c2.f.iter().map(|v| v * v).sum::<f64>().sqrt();
    let d: f64 =
        c.f.iter()
            .zip(&c2.f)
            .map(|(x, y)| (x - y).powi(2))
            .sum::<f64>()
            .sqrt();
    assert!(d < 1e-6 * nf, "{d}");
}

/// Five noisy markers (σ 0.01 mm, seed 3) on `robot` bent by the known
/// loads and a 1 cm wide Gaussian bump of -20 N/m at 0.16 m.
fn bump_observation(robot: &Robot<PlanarCable>, known: &Loads) -> Observation {
    let mut truth = known.clone();
    truth.line_loads.push(LineLoad::Gaussian {
        amplitude_n_per_m: vec![0.0, -20.0],
        center_m: 0.16,
        width_m: 0.01,
    });
    let eq = StaticSolver::default().solve(robot, &truth, None).unwrap();
    Observation::of_nodes(robot, eq.q.as_slice(), &[4, 8, 12, 16, 20])
        .unwrap()
        .with_noise(1e-5, 3)
}

/// Bounds on the component of `w` along (0, 1) in `frame` at every
/// centimetre from the base to 0.24 m.
fn bounds_every_cm(
    frame: softrod::estimate::BoundFrame,
    min_n_per_m: Option<f64>,
    max_n_per_m: Option<f64>,
) -> Vec<softrod::estimate::LoadBound> {
    (0..=24)
        .map(|i| softrod::estimate::LoadBound {
            s_m: 0.01 * i as f64,
            frame,
            direction: vec![0.0, 1.0],
            min_n_per_m,
            max_n_per_m,
        })
        .collect()
}

/// The sqp estimates at `α = 10` of `obs` with the bounds of `settings` and
/// without any: the bounded one, the free one.
fn sqp_bounded_and_free(
    robot: &Robot<PlanarCable>,
    k: &Loads,
    obs: &Observation,
    settings: EstimatorSettings,
) -> (Estimate, Estimate) {
    let run = |s: EstimatorSettings| {
        EstimatorSettings {
            backend: Backend::Sqp,
            alpha: Some(10.0),
            ..s
        }
        .build_for(robot, k)
        .unwrap()
        .step(obs)
        .unwrap()
    };
    (run(settings), run(EstimatorSettings::default()))
}

/// A contact that can only push: with a lower bound on the normal component
/// of w (local frame) the SQP estimate respects it at every bounded point,
/// and the Newton backend refuses bounds.
#[test]
fn sqp_respects_load_bounds() {
    use softrod::estimate::BoundFrame;
    let robot = two_section(10);
    let k = known();
    let obs = bump_observation(&robot, &k);
    let bounds = bounds_every_cm(BoundFrame::World, None, Some(0.0));
    let settings = EstimatorSettings {
        alpha: Some(10.0),
        bounds: bounds.clone(),
        ..EstimatorSettings::default()
    };
    assert!(
        softrod::estimate::EstimatorSettings {
            backend: Backend::Newton,
            ..settings.clone()
        }
        .build_for(&robot, &k)
        .is_err()
    );
    let (e, free) = sqp_bounded_and_free(&robot, &k, &obs, settings);
    let worst = bounds
        .iter()
        .map(|b| e.load_at(b.s_m)[1])
        .fold(f64::MIN, f64::max);
    let worst_free = bounds
        .iter()
        .map(|b| free.load_at(b.s_m)[1])
        .fold(f64::MIN, f64::max);
    eprintln!("max w_y at bounded points: {worst:.3e} N/m (unbounded: {worst_free:.3e})");
    assert!(e.report.status.is_converged());
    assert!(worst <= 1e-6, "{worst}");
    assert!(
        worst_free > 1e-3,
        "the test needs an active bound: {worst_free}"
    );
}

/// Bounds in the robot's local frame: a contact that can only push along the
/// local normal (`n · w ≥ 0`, `n` the tangent turned by +90°). The SQP
/// estimate satisfies it in its own final shape at every bounded point
/// (bound: -1e-5 N/m; the frame is lagged one iteration and the final shape
/// re-solved, measured -8e-7), while the unbounded estimate violates it by
/// several N/m.
#[test]
fn sqp_respects_local_frame_bounds() {
    use softrod::estimate::BoundFrame;
    let robot = two_section(10);
    let k = known();
    let obs = bump_observation(&robot, &k);
    let bounds = bounds_every_cm(BoundFrame::Local, Some(0.0), None);
    let normal_load = |e: &Estimate, s: f64| {
        let (el, xi) = robot.locate("s", s).unwrap();
        let le = robot.elements()[el].length();
        let (_, ds, _) = softrod::element::hermite(xi, le);
        let qe = &e.q.as_slice()[el * 4..el * 4 + 8];
        let t: Vec<f64> = (0..2)
            .map(|i| (0..4).map(|k| ds[k] * qe[2 * k + i]).sum())
            .collect();
        let tn = t[0].hypot(t[1]);
        let w = e.load_at(s);
        (-t[1] * w[0] + t[0] * w[1]) / tn
    };
    let settings = EstimatorSettings {
        alpha: Some(10.0),
        bounds: bounds.clone(),
        ..EstimatorSettings::default()
    };
    let (e, free) = sqp_bounded_and_free(&robot, &k, &obs, settings);
    let worst = bounds
        .iter()
        .map(|b| normal_load(&e, b.s_m))
        .fold(f64::MAX, f64::min);
    let worst_free = bounds
        .iter()
        .map(|b| normal_load(&free, b.s_m))
        .fold(f64::MAX, f64::min);
    eprintln!("min n.w at bounded points: {worst:.3e} N/m (unbounded: {worst_free:.3e})");
    assert!(solved(&e.report.status), "{}", e.report);
    assert!(worst >= -1e-5, "{worst}");
    assert!(
        worst_free < -1e-3,
        "the test needs an active bound: {worst_free}"
    );
}

/// The estimator is generic over the element: on the spatial cable (6
/// coordinates per node, 3-D markers, 3-D load field) both backends
/// converge, agree with each other (the same problem), and recover an
/// out-of-plane tip force from four markers. Bounds: backends within 1e-6 of
/// the resultant; the concentrated force within 2 % of its magnitude (an
/// estimator that returns no force, or a planar one, is off by 100 %).
#[test]
fn both_backends_estimate_on_the_spatial_cable() {
    use softrod::assembly::{RobotSpec, Section};
    let mut spec = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 12)]);
    spec.base.position_m = vec![0.0, 0.0, 0.0];
    spec.base.direction = Some(vec![1.0, 0.0, 0.0]);
    spec.gravity_m_per_s2 = vec![0.0, 0.0, 0.0];
    let robot = spec.build_spatial().unwrap();
    let force = [0.0, -0.05, 0.03];
    let truth = Loads {
        point_forces: vec![PointForce {
            s_m: 0.24,
            force_n: force.to_vec(),
        }],
        ..Loads::default()
    };
    let eq = StaticSolver::default().solve(&robot, &truth, None).unwrap();
    let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[3, 6, 9, 12])
        .unwrap()
        .with_noise(1e-6, 1);
    assert_eq!(obs.n_components(), 12);
    for model in [LoadModel::Distributed, LoadModel::Concentrated { node: 12 }] {
        let estimates: Vec<Estimate> = [Backend::Newton, Backend::Sqp]
            .into_iter()
            .map(|backend| {
                let settings = EstimatorSettings {
                    backend,
                    load_model: model,
                    alpha: Some(1e-3),
                    statistical_tolerance: 0.0,
                    noise_sigma_m: 1e-6,
                    ..EstimatorSettings::default()
                };
                let mut est = softrod::estimate::EstimatorSettings {
                    backend,
                    ..settings
                }
                .build_for(&robot, &Loads::default())
                .unwrap();
                let e = est.step(&obs).unwrap();
                assert!(e.report.status.is_converged(), "{model:?}: {}", e.report);
                assert_eq!(e.resultant_force_n.len(), 3);
                e
            })
            .collect();
        let (n, s) = (
            &estimates[0].resultant_force_n,
            &estimates[1].resultant_force_n,
        );
        let scale = n.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = n
            .iter()
            .zip(s)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff <= 1e-6 * scale, "{model:?}: {n:?} vs {s:?}");
        if model != LoadModel::Distributed {
            let err = n
                .iter()
                .zip(force)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt();
            let size = force.iter().map(|v| v * v).sum::<f64>().sqrt();
            assert!(err <= 0.02 * size, "{n:?} vs {force:?}");
        }
    }
}
