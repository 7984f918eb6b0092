//! The one warm tracker against the three warm solvers it replaced, run on
//! the same scenarios: the estimators' robot tracker (`old`), the parallel
//! robot's chord solver (`crate::parallel::warm::old`) and the inverse
//! kinematics' corrector (`crate::control::corrector`). Equal means equal
//! bits: shapes, residuals, the factors (a solve with each) and the counts.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use super::*;
use crate::estimate::LoadModel;
use crate::scene::Scene;

/// The two factorizations give the same bits on a fixed right-hand side.
fn assert_same_factors(a: &AutoFactors, b: &AutoFactors) {
    let n = a.n();
    let mut x: Vec<f64> = (0..n).map(|i| (0.37 * i as f64).sin()).collect();
    let mut y = x.clone();
    a.solve_in_place(&mut x).unwrap();
    b.solve_in_place(&mut y).unwrap();
    assert_eq!(x, y);
}

/// A load of size `k` of the model: every node pulled down (distributed) or
/// a force at node 12.
fn load_at(load: LoadModel, n_f: usize, k: f64) -> Vec<f64> {
    match load {
        LoadModel::Distributed => (0..n_f)
            .map(|i| if i % 4 == 1 { -0.05 * k } else { 0.0 })
            .collect(),
        LoadModel::Concentrated { .. } => vec![0.01 * k, -0.02 * k],
    }
}

/// The estimators' calls: a cold solve, warm solves along a load path, a
/// repeat, a trial without fallback, a chord step, factors kept from
/// outside, a far jump.
#[test]
fn robot_tracker_gives_the_old_trackers_bits() {
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let known = scene.loads().unwrap();
    let mut statuses = Vec::new();
    for load in [LoadModel::Distributed, LoadModel::Concentrated { node: 12 }] {
        let n_f = LinearLoad::n_params(&load, &robot);
        let mut old =
            old::EquilibriumTracker::new(robot.clone(), known.clone(), Default::default()).unwrap();
        let mut new =
            EquilibriumTracker::new(robot.clone(), known.clone(), Default::default()).unwrap();
        let check = |a: &old::TrackedEquilibrium, b: &TrackedEquilibrium| {
            assert_eq!(a.q, b.q);
            assert_eq!(a.residual_n, b.residual_n);
            assert_same_factors(&a.factors, &b.factors);
        };
        let start = robot.arc_configuration(&known.pressures_pa);
        let f0 = load_at(load, n_f, 0.0);
        let (a, b) = (
            old.solve(&load, &f0, start.as_slice()).unwrap(),
            new.solve(&load, &f0, start.as_slice()).unwrap(),
        );
        check(&a, &b);
        statuses.push((b.path, b.status));
        let mut q = b.q;
        let mut f = f0;
        for k in 1..=6 {
            f = load_at(load, n_f, 0.2 * k as f64);
            let (a, b) = (
                old.solve(&load, &f, q.as_slice()).unwrap(),
                new.solve(&load, &f, q.as_slice()).unwrap(),
            );
            check(&a, &b);
            statuses.push((b.path, b.status));
            q = b.q;
        }
        // asked again at the answer
        let (a, b) = (
            old.solve(&load, &f, q.as_slice()).unwrap(),
            new.solve(&load, &f, q.as_slice()).unwrap(),
        );
        check(&a, &b);
        assert_eq!(b.path, WarmPath::Repeated);
        // a line-search trial, far: no fallback
        let f = load_at(load, n_f, 3.0);
        let (a, b) = (
            old.try_solve(&load, &f, q.as_slice()).unwrap(),
            new.try_solve(&load, &f, q.as_slice()).unwrap(),
        );
        assert_eq!(a.is_some(), b.is_some());
        if let (Some(a), Some(b)) = (&a, &b) {
            check(a, b);
            q = b.q.clone();
        }
        // a tiny last step by chord steps only
        let mut f = load_at(load, n_f, if b.is_some() { 3.0 } else { 1.2 });
        f[1] *= 1.0 + 1e-7;
        let (a, b) = (
            old.solve_chord(&load, &f, q.as_slice()).unwrap(),
            new.solve_chord(&load, &f, q.as_slice()).unwrap(),
        );
        assert_eq!(a, b);
        // factors kept from outside, then a warm solve from them
        let (ta, tb) = (
            old.factor_tangent(q.as_slice()).unwrap(),
            new.factor_tangent(q.as_slice()).unwrap(),
        );
        assert_same_factors(&ta.factors, &tb.factors);
        old.keep_factors(q.as_slice(), ta.factors).unwrap();
        new.keep_factors(q.as_slice(), tb.factors).unwrap();
        let f = load_at(load, n_f, 1.0);
        let (a, b) = (
            old.solve(&load, &f, q.as_slice()).unwrap(),
            new.solve(&load, &f, q.as_slice()).unwrap(),
        );
        check(&a, &b);
        // a far jump: the fallback
        let f = load_at(load, n_f, 40.0);
        let (a, b) = (
            old.solve(&load, &f, q.as_slice()).unwrap(),
            new.solve(&load, &f, q.as_slice()).unwrap(),
        );
        check(&a, &b);
        statuses.push((b.path, b.status));
        // new known loads
        let mut k2 = known.clone();
        k2.pressures_pa[0] += 2e3;
        old.set_known(k2.clone()).unwrap();
        new.set_known(k2).unwrap();
        let (a, b) = (
            old.solve(&load, &f, b.q.as_slice()).unwrap(),
            new.solve(&load, &f, b.q.as_slice()).unwrap(),
        );
        check(&a, &b);
        statuses.push((b.path, b.status));
    }
    println!("{statuses:?}");
}

/// The parallel robot's tracking loop: nudged pressures and platform
/// forces, the factors kept across loads, an explicit factorization, the
/// platform sensitivities.
#[test]
fn parallel_warm_solves_give_the_old_solvers_bits_and_counts() {
    use crate::parallel::warm::{old, WarmStatics};
    use crate::parallel::ParallelSpec;
    let spec = ParallelSpec {
        elements_per_section: 1,
        ..ParallelSpec::default()
    };
    let robot = spec.build_full().unwrap();
    let p0 = crate::control::parallel::centre_pressures(&spec);
    let mut p: Vec<f64> = p0.as_slice().to_vec();
    let loads = robot.loads(&p, [0.0; 3], [0.0; 3]).unwrap();
    let eq = robot.solve(&loads, None).unwrap();
    let mut a = old::WarmStatics::new(robot.clone()).unwrap();
    let mut b = WarmStatics::new(robot.clone()).unwrap();
    a.factor_at(eq.u.as_slice(), &loads).unwrap();
    b.factor_at(eq.u.as_slice(), &loads).unwrap();
    let mut u = eq.u.clone();
    for k in 0..24 {
        let np = p.len();
        p[k % np] += 500.0 * (1.0 + k as f64);
        let f = [0.0, 0.0, -0.1 * k as f64];
        let loads = robot.loads(&p, f, [0.0; 3]).unwrap();
        if k % 7 == 3 {
            a.factor_at(u.as_slice(), &loads).unwrap();
            b.factor_at(u.as_slice(), &loads).unwrap();
        }
        let (ua, ub) = (
            a.solve(&loads, u.as_slice()).unwrap(),
            b.solve(&loads, u.as_slice()).unwrap(),
        );
        assert_eq!(ua, ub, "solve {k}");
        let (sa, sb) = (
            a.sensitivities(ub.as_slice()).unwrap(),
            b.sensitivities(ub.as_slice()).unwrap(),
        );
        assert_eq!(sa.compliance_m_per_n, sb.compliance_m_per_n);
        assert_eq!(sa.jacobian_m_per_pa, sb.jacobian_m_per_pa);
        u = ub;
    }
    // a far jump: the fallback
    let loads = robot.loads(&p, [0.3, 0.0, -3.0], [0.0; 3]).unwrap();
    let (ua, ub) = (
        a.solve(&loads, eq.u.as_slice()).unwrap(),
        b.solve(&loads, eq.u.as_slice()).unwrap(),
    );
    assert_eq!(ua, ub);
    let (ca, cb) = (a.counts(), b.counts());
    println!("old {ca:?}, new {cb:?}");
    assert_eq!(
        (ca.solves, ca.residuals, ca.factorizations, ca.fallbacks),
        (cb.solves, cb.residuals, cb.factorizations, cb.fallbacks)
    );
}

/// The inverse kinematics' corrector: from starts predicted along `∂q/∂P`
/// (small and large pressure changes, one too large for it), the answer,
/// its factors and the steps.
#[test]
fn newton_strategy_gives_the_old_correctors_bits_and_steps() {
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let known = scene.loads().unwrap();
    let settings = StaticSettings::default();
    let mut linear =
        AutoSolver::with_kind(robot.tangent_pattern(), settings.linear_solver).unwrap();
    let mut new = EquilibriumTracker::new(robot.clone(), known.clone(), settings.clone())
        .unwrap()
        .with_strategy(WarmStrategy::Newton { max_steps: 6 })
        .unwrap();
    let eq = StaticSolver::default().solve(&robot, &known, None).unwrap();
    let t = new.factor_tangent(eq.q.as_slice()).unwrap();
    let dqdp = crate::sensitivity::Sensitivity::new(&robot, &t.factors)
        .unwrap()
        .dq_dp(eq.q.as_slice())
        .unwrap();
    let mut given_up = 0;
    for (k, dp) in [1e2, 1e3, 5e3, 2e4, 6e4, 1e5].iter().enumerate() {
        let mut loads = known.clone();
        let dpv: Vec<f64> = (0..loads.pressures_pa.len())
            .map(|c| if c == k % 2 { *dp } else { -0.5 * dp })
            .collect();
        loads
            .pressures_pa
            .iter_mut()
            .zip(&dpv)
            .for_each(|(a, b)| *a = (*a + b).clamp(0.0, 1e5));
        let dq = &dqdp * nalgebra::DVector::from_vec(dpv);
        let start: Vec<f64> = eq.q.iter().zip(dq.iter()).map(|(a, b)| a + b).collect();
        let (old, steps) =
            crate::control::corrector::correct(&robot, &loads, &start, &settings, &mut linear);
        let before = new.counts().steps;
        new.set_known(loads.clone()).unwrap();
        let u0 = robot.free_coordinates_of(&start).unwrap();
        let got = new.try_solve_free(u0.as_slice()).unwrap();
        assert_eq!(steps, (new.counts().steps - before).max(1), "dp {dp}");
        assert_eq!(old.is_some(), got.is_some(), "dp {dp}");
        if let (Some(a), Some(b)) = (old, got) {
            assert_eq!(a.q, b.q.as_slice());
            assert_same_factors(&a.factors, &b.factors);
            assert!(b.status.is_converged());
        } else {
            given_up += 1;
        }
    }
    println!("given up {given_up} of 6");
}

/// Chord steps contracting at a constant rate `ρ` from an error of
/// `7e-4 L` (a short path: its length is not what is tested here): the test stops where the distance left is below
/// `1e-10 L` (never above it), for `ρ` up to 1/2, and at ρ = 0.1 one
/// step before the step itself falls below the bound (what it saves);
/// a first step, or a slower contraction, stops only below the bound.
#[test]
fn chord_steps_stop_where_the_contraction_predicts_the_bound() {
    let len = 0.24;
    let tol = 1e-10 * len;
    for rho in [0.01, 0.1, 0.3, 0.5] {
        let mut err: f64 = 7e-4 * len;
        let mut prev = f64::INFINITY;
        let mut steps = 0;
        loop {
            let step = err * (1.0 - rho);
            err *= rho;
            steps += 1;
            if chord_converged(step, prev, 0.0, len) {
                break;
            }
            prev = step;
            assert!(steps < 100);
        }
        assert!(err <= tol * (1.0 + 1e-12), "rho {rho}: {err:e} left");
        // the plain test would take the step after, below the bound
        let plain = (1..100)
            .find(|&k| 7e-4 * len * rho.powi(k - 1) * (1.0 - rho) <= tol)
            .unwrap_or(100);
        if rho == 0.1 {
            assert_eq!(steps + 1, plain, "rho {rho}");
        }
        assert!(steps <= plain);
    }
    // a first step is taken on its own size only
    assert!(!chord_converged(2.0 * tol, f64::INFINITY, 0.0, len));
    assert!(chord_converged(0.5 * tol, f64::INFINITY, 0.0, len));
    // a contraction slower than 1/2 is not trusted
    assert!(!chord_converged(1.1 * tol, 1.9 * tol, 0.0, len));
    assert!(chord_converged(1.1 * tol, 40.0 * tol, 0.0, len));
    // nor one along a path longer than 1e-4 L (far from the solution)
    assert!(!chord_converged(1.1 * tol, 40.0 * tol, 2e-4 * len, len));
}

/// `Σ_i (i + 1) v_i`: a digest of a shape that changes with any of its bits
/// (almost surely).
fn digest(v: &[f64]) -> f64 {
    v.iter().enumerate().map(|(i, x)| (i + 1) as f64 * x).sum()
}

/// The robot scenario of [`robot_tracker_gives_the_old_trackers_bits`] on
/// the new tracker alone: the digest of every answer, and the counts.
fn robot_scenario() -> (Vec<u64>, WarmCounts) {
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let known = scene.loads().unwrap();
    let mut out = Vec::new();
    let mut counts = WarmCounts::default();
    for load in [LoadModel::Distributed, LoadModel::Concentrated { node: 12 }] {
        let n_f = LinearLoad::n_params(&load, &robot);
        let mut t =
            EquilibriumTracker::new(robot.clone(), known.clone(), Default::default()).unwrap();
        let start = robot.arc_configuration(&known.pressures_pa);
        let mut q = t
            .solve(&load, &load_at(load, n_f, 0.0), start.as_slice())
            .unwrap()
            .q;
        out.push(digest(q.as_slice()).to_bits());
        for k in 1..=6 {
            let f = load_at(load, n_f, 0.2 * k as f64);
            q = t.solve(&load, &f, q.as_slice()).unwrap().q;
            out.push(digest(q.as_slice()).to_bits());
        }
        let f = load_at(load, n_f, 3.0);
        if let Some(b) = t.try_solve(&load, &f, q.as_slice()).unwrap() {
            q = b.q;
        }
        out.push(digest(q.as_slice()).to_bits());
        let f = load_at(load, n_f, 40.0);
        let b = t.solve(&load, &f, q.as_slice()).unwrap();
        out.push(digest(b.q.as_slice()).to_bits());
        out.push(b.residual_n.to_bits());
        let c = t.counts();
        counts.solves += c.solves;
        counts.residuals += c.residuals;
        counts.factorizations += c.factorizations;
        counts.fallbacks += c.fallbacks;
        counts.steps += c.steps;
    }
    (out, counts)
}

/// The parallel scenario on the new solver alone: the digests and counts.
fn parallel_scenario() -> (Vec<u64>, WarmCounts) {
    use crate::parallel::warm::WarmStatics;
    use crate::parallel::ParallelSpec;
    let spec = ParallelSpec {
        elements_per_section: 1,
        ..ParallelSpec::default()
    };
    let robot = spec.build_full().unwrap();
    let mut p: Vec<f64> = crate::control::parallel::centre_pressures(&spec)
        .as_slice()
        .to_vec();
    let loads = robot.loads(&p, [0.0; 3], [0.0; 3]).unwrap();
    let eq = robot.solve(&loads, None).unwrap();
    let mut b = WarmStatics::new(robot.clone()).unwrap();
    b.factor_at(eq.u.as_slice(), &loads).unwrap();
    let mut u = eq.u.clone();
    let mut out = Vec::new();
    for k in 0..24 {
        let np = p.len();
        p[k % np] += 500.0 * (1.0 + k as f64);
        let loads = robot
            .loads(&p, [0.0, 0.0, -0.1 * k as f64], [0.0; 3])
            .unwrap();
        if k % 7 == 3 {
            b.factor_at(u.as_slice(), &loads).unwrap();
        }
        u = b.solve(&loads, u.as_slice()).unwrap();
        let s = b.sensitivities(u.as_slice()).unwrap();
        out.push(digest(u.as_slice()).to_bits());
        out.push(digest(s.jacobian_m_per_pa.as_slice()).to_bits());
    }
    (out, b.counts())
}

/// Prints the digests the regression test records.
#[test]
fn print_digests() {
    println!("robot {:?}", robot_scenario());
    println!("parallel {:?}", parallel_scenario());
}
