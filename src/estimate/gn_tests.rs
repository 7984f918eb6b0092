//! Tests of the Gauss–Newton system of [`super::problem::Problem`].

use crate::estimate::{EstimatorSettings, Observation};
use crate::scene::Scene;
use crate::statics::StaticSolver;

use super::problem::Problem;

/// The Gauss–Newton step from a factor at hand (formed by `gn_solve`
/// from the same derivatives and weights) is the one formed anew,
/// number for number, at another right-hand side (new residuals and
/// load); a factor formed at another `α` is not used (the step differs
/// from the reused one by O(1) relative).
#[test]
fn gn_step_from_the_factor_at_hand_is_the_one_formed_anew() {
    let scene = Scene::two_section();
    let (robot, known) = (scene.robot().unwrap(), scene.loads().unwrap());
    let mut p = Problem::new(robot.clone(), known.clone(), EstimatorSettings::default()).unwrap();
    let eq = StaticSolver::default().solve(&robot, &known, None).unwrap();
    let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[4, 8, 12, 16, 20]).unwrap();
    let op = p.operator(&obs).unwrap();
    let n_f = robot.n_q();
    let q = eq.q.as_slice().to_vec();
    let f0 = vec![0.0; n_f];
    let lu = p.equilibrium(&f0, &q).unwrap().factors;
    let dv = p.derivs(&q, &lu, &op).unwrap();
    let e: Vec<f64> = (0..op.len()).map(|i| 1e-4 * (i as f64 + 1.0)).collect();
    let f: Vec<f64> = (0..n_f).map(|i| 0.01 * (i % 7) as f64).collect();
    let (alpha, other) = (31.0, 0.5);
    let (_, fac) = p.gn_solve(&dv, &op, &e, &f0, alpha).unwrap();
    let (fresh, _) = p.gn_solve(&dv, &op, &e, &f, alpha).unwrap();
    let (reused, fac2) = p
        .gn_solve_reusing(&dv, &op, &e, &f, alpha, Some(fac.clone()))
        .unwrap();
    assert_eq!(fresh, reused);
    assert_eq!(fac2.gram, fac.gram);
    // at another α the factor at hand is formed anew
    let (fresh, _) = p.gn_solve(&dv, &op, &e, &f, other).unwrap();
    let (reused, _) = p
        .gn_solve_reusing(&dv, &op, &e, &f, other, Some(fac.clone()))
        .unwrap();
    assert_eq!(fresh, reused);
    let (wrong, _) = p.gn_solve(&dv, &op, &e, &f, alpha).unwrap();
    let diff = wrong
        .iter()
        .zip(&reused)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let size = reused.iter().map(|v| v.abs()).fold(0.0, f64::max);
    assert!(diff > 1e-3 * size, "{diff:e} {size:e}");
}
