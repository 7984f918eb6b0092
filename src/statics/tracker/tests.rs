//! The one warm tracker against the recorded behaviour of the three warm
//! solvers it replaced (the estimators' `EquilibriumTracker`, the parallel
//! robot's `WarmStatics` chord solver, the inverse kinematics' corrector).
//!
//! Commit 1072545 kept the old three beside the new tracker and ran the
//! same scenarios through both: equal bits of every shape, residual and
//! factors, equal counts. The digests below were recorded there (the new
//! path's, equal to the old one's) when the old paths were deleted: a change
//! of any bit of an answer, or of the work done, fails here.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use super::*;
use crate::estimate::LoadModel;
use crate::scene::Scene;
use crate::structure::Stepping;

/// A load of size `k` of the model: every node pulled down (distributed) or
/// a force at node 12.
fn load_at(load: LoadModel, n_f: usize, k: f64) -> Vec<f64> {
    match load {
        LoadModel::Distributed => (0..n_f)
            .map(|i| if i % 4 == 1 { -0.05 * k } else { 0.0 })
            .collect(),
        _ => vec![0.01 * k, -0.02 * k],
    }
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

/// The estimators' calls on the robot (two load models): a cold solve, warm
/// solves along a load path, a trial without fallback, a far jump (the
/// fallback): the digest of every answer, and the counts.
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

/// The parallel robot's tracking solves: nudged pressures and platform
/// forces, the factors kept across loads, explicit refactors, the platform
/// sensitivities: the digests and counts.
fn parallel_scenario() -> (Vec<u64>, WarmCounts) {
    use crate::parallel::ParallelSpec;
    use crate::parallel::warm::WarmStatics;
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

/// The robot's and the parallel robot's scenarios give the recorded bits and
/// counts of the old trackers.
#[test]
fn warm_solves_give_the_recorded_bits_and_counts_of_the_old_solvers() {
    let (digests, counts) = robot_scenario();
    assert_eq!(digests, ROBOT_DIGESTS);
    assert_eq!((counts.solves, counts.fallbacks), (18, 4), "{counts:?}");
    // recorded on the new path (the old tracker kept no counts)
    assert_eq!(
        (counts.residuals, counts.factorizations, counts.steps),
        (54, 46, 78),
        "{counts:?}"
    );
    let (digests, counts) = parallel_scenario();
    assert_eq!(digests, PARALLEL_DIGESTS);
    // the old solver's counts, and the steps of the new
    assert_eq!(
        (
            counts.solves,
            counts.residuals,
            counts.factorizations,
            counts.fallbacks,
            counts.steps
        ),
        (24, 185, 8, 0, 181)
    );
}

/// The inverse kinematics' corrector from starts predicted along `∂q/∂P`
/// (pressure changes of 0.1 to 100 kPa): the old corrector's answers
/// (digests) and steps; the two largest changes given up.
#[test]
fn newton_strategy_gives_the_recorded_answers_and_steps_of_the_old_corrector() {
    let (answers, steps) = newton_scenario();
    assert_eq!(answers, NEWTON_DIGESTS);
    assert_eq!(steps, NEWTON_STEPS);
}

/// The corrector's scenario: per start the digest of the answer (`None`
/// where it gives up) and the steps taken.
fn newton_scenario() -> (Vec<Option<u64>>, Vec<usize>) {
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let known = scene.loads().unwrap();
    let mut t = EquilibriumTracker::new(robot.clone(), known.clone(), StaticSettings::default())
        .unwrap()
        .with_strategy(WarmStrategy::Newton { max_steps: 6 })
        .unwrap();
    let eq = StaticSolver::default().solve(&robot, &known, None).unwrap();
    let tangent = t.factor_tangent(eq.q.as_slice()).unwrap();
    let dqdp = crate::sensitivity::Sensitivity::new(&robot, &tangent.factors)
        .unwrap()
        .dq_dp(eq.q.as_slice())
        .unwrap();
    let (mut answers, mut steps) = (Vec::new(), Vec::new());
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
        let before = t.counts().steps;
        t.set_known(loads).unwrap();
        let u0 = robot.free_coordinates_of(&start).unwrap();
        let got = t.try_solve_free(u0.as_slice()).unwrap();
        steps.push((t.counts().steps - before).max(1));
        if let Some(b) = &got {
            assert!(b.status.is_converged() && b.factors.is_positive_definite());
        }
        answers.push(got.map(|b| digest(b.q.as_slice()).to_bits()));
    }
    (answers, steps)
}

/// [`robot_scenario`]'s digests, recorded (see the module documentation).
const ROBOT_DIGESTS: [u64; 20] = [
    4653874434017115452,
    4653873099853374332,
    4653871761350402596,
    4653870418502324515,
    4653869071303280428,
    4653867719747426959,
    4653866363828937169,
    4653853963290763922,
    4653514947876754119,
    4439934453459010052,
    4653874434017115452,
    4653871246761974492,
    4653868039001724200,
    4653864810756377125,
    4653861562046694159,
    4653858292894184018,
    4653855003321102591,
    4653824482278700180,
    4652896182766998136,
    4437147937684692702,
];

/// [`parallel_scenario`]'s digests (shape, pressure Jacobian per solve).
const PARALLEL_DIGESTS: [u64; 48] = [
    4633514734530263098,
    4501901970826434338,
    4633524248690207312,
    4501901970826434182,
    4633544043106199654,
    4501901970826434158,
    4633576873716805972,
    4501936509355968306,
    4633571924999290253,
    4501936509355968146,
    4633542405291547548,
    4501936509355968220,
    4633517816901244789,
    4501936509355968250,
    4633443388575956545,
    4501936509355968228,
    4633571308602577505,
    4501936509355968216,
    4633586009001309178,
    4501936509355968326,
    4633742629193483935,
    4501906240247190928,
    4633566125224732875,
    4501906240247191026,
    4633358199997095925,
    4501906240247190988,
    4633273892055814792,
    4501906240247191080,
    4633615765765702350,
    4501906240247191022,
    4633883134577295419,
    4501641894124764006,
    4634036782238469774,
    4501641894124763932,
    4633584703271345909,
    4501894997260605828,
    4633436124525386555,
    4501894997260605630,
    4633496113907136860,
    4501894997260605646,
    4633608772895447107,
    4501894997260605666,
    4633768233197437471,
    4501894997260605754,
    4633734574024585158,
    4502285361352781204,
    4633607058586476192,
    4501894840755932828,
];

/// [`newton_scenario`]'s digests.
const NEWTON_DIGESTS: [Option<u64>; 6] = [
    Some(4653877472466768359),
    Some(4653844028850847754),
    Some(4654004114119096679),
    Some(4652932266093807538),
    None,
    None,
];

/// [`newton_scenario`]'s steps.
const NEWTON_STEPS: [usize; 6] = [3, 4, 5, 5, 1, 1];
