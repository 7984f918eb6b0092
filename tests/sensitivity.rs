//! Sensitivities of an equilibrium (`softrod::sensitivity`): `∂q/∂F` (28)
//! and `∂q/∂P` (43) against central finite differences of re-solved
//! equilibria (the globalized static solver, not the tracker), and the
//! adjoint output gradients against the forward ones. Bound: 1e-6 of the
//! largest entry (a wrong sign, a missing restriction to the free
//! coordinates, a transposed `K` or a tangent without the actuation's
//! Hessian are off by O(1)).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use nalgebra::DMatrix;
use softrod::assembly::Robot;
use softrod::element::PlanarCable;
use softrod::estimate::LoadModel;
use softrod::loads::Loads;
use softrod::scene::Scene;
use softrod::sensitivity::Sensitivity;
use softrod::statics::{EquilibriumTracker, LinearLoad, StaticSettings, StaticSolver};

fn robot_and_loads() -> (Robot<PlanarCable>, Loads) {
    let mut s = Scene::two_section();
    for sec in &mut s.robot.sections {
        sec.elements = 6;
    }
    (s.robot().unwrap(), s.loads().unwrap())
}

/// The equilibrium under `known` plus `F` of `model`, from `q0`, solved
/// tightly by the globalized static solver.
fn solve(
    robot: &Robot<PlanarCable>,
    known: &Loads,
    model: LoadModel,
    f: &[f64],
    q0: &[f64],
) -> Vec<f64> {
    let settings = StaticSettings {
        residual_tolerance: 1e-13,
        ..StaticSettings::default()
    };
    let loads = model.add_to(robot, known, f);
    StaticSolver::new(settings)
        .unwrap()
        .solve(robot, &loads, Some(q0))
        .unwrap()
        .q
        .data
        .into()
}

/// Largest entry difference relative to the largest entry of `exact`.
fn rel_err(exact: &DMatrix<f64>, fd: &DMatrix<f64>) -> f64 {
    let scale = exact.amax();
    assert!(scale > 0.0, "a zero sensitivity tests nothing");
    (exact - fd).amax() / scale
}

#[test]
fn dq_df_matches_finite_differences_of_resolved_equilibria() {
    let (robot, known) = robot_and_loads();
    let along = LoadModel::Along {
        site: softrod::site::Site::Rod { rod: 0, s_m: 0.2 },
        direction: [0.3, -1.0, 0.0],
    };
    for model in [
        LoadModel::Distributed,
        LoadModel::Concentrated { node: 9 },
        along,
    ] {
        let n_f = model.n_params(&robot);
        // a loaded, bent state: a small downward load on every node
        let f0: Vec<f64> = (0..n_f)
            .map(|j| if j % 4 == 1 || n_f <= 2 { -0.2 } else { 0.0 })
            .collect();
        let mut tracker =
            EquilibriumTracker::new(robot.clone(), known.clone(), StaticSettings::default())
                .unwrap();
        let start = robot.arc_configuration(&known.pressures_pa);
        let eq = tracker.solve(&model, &f0, start.as_slice()).unwrap();
        let exact = Sensitivity::new(&robot, &eq.factors)
            .unwrap()
            .dq_df(&model)
            .unwrap();
        assert_eq!(exact.shape(), (robot.n_q(), n_f));
        let h = 3e-4;
        let mut fd = DMatrix::zeros(robot.n_q(), n_f);
        for j in 0..n_f {
            let (mut fp, mut fm) = (f0.clone(), f0.clone());
            fp[j] += h;
            fm[j] -= h;
            let qp = solve(&robot, &known, model, &fp, eq.q.as_slice());
            let qm = solve(&robot, &known, model, &fm, eq.q.as_slice());
            for i in 0..robot.n_q() {
                fd[(i, j)] = (qp[i] - qm[i]) / (2.0 * h);
            }
        }
        let err = rel_err(&exact, &fd);
        println!("{model:?}: |dq/dF - FD| / max = {err:.2e}");
        assert!(err < 1e-6, "{model:?}: {err:e}");
    }
}

#[test]
fn dq_dp_matches_finite_differences_of_resolved_equilibria() {
    let (robot, mut known) = robot_and_loads();
    // every chamber inside its range, so that P ± h is too
    known.pressures_pa = vec![60.0e3, 10.0e3, 20.0e3, 30.0e3];
    assert_eq!(robot.n_pressures(), known.pressures_pa.len());
    let model = LoadModel::Concentrated { node: 12 };
    let f0 = [0.0, -0.1];
    let mut tracker =
        EquilibriumTracker::new(robot.clone(), known.clone(), StaticSettings::default()).unwrap();
    let eq = tracker
        .solve(
            &model,
            &f0,
            robot.arc_configuration(&known.pressures_pa).as_slice(),
        )
        .unwrap();
    let exact = Sensitivity::new(&robot, &eq.factors)
        .unwrap()
        .dq_dp(eq.q.as_slice())
        .unwrap();
    let np = robot.n_pressures();
    assert_eq!(exact.shape(), (robot.n_q(), np));
    let h = 30.0; // Pa, against pressures of 10 to 60 kPa
    let mut fd = DMatrix::zeros(robot.n_q(), np);
    for c in 0..np {
        let shifted = |d: f64| {
            let mut k = known.clone();
            k.pressures_pa[c] += d;
            solve(&robot, &k, model, &f0, eq.q.as_slice())
        };
        let (qp, qm) = (shifted(h), shifted(-h));
        for i in 0..robot.n_q() {
            fd[(i, c)] = (qp[i] - qm[i]) / (2.0 * h);
        }
    }
    let err = rel_err(&exact, &fd);
    println!("|dq/dP - FD| / max = {err:.2e}");
    assert!(err < 1e-6, "{err:e}");
}

/// One adjoint solve per output gives what `n_F` (or `n_P`) forward solves
/// give: `∇_F y_i = (∂q/∂F)ᵀ c_i`, `∇_P y_i = (∂q/∂P)ᵀ c_i`, for outputs
/// touching the clamped base node and the tip.
#[test]
fn adjoint_gradients_equal_the_forward_sensitivities() {
    let along = LoadModel::Along {
        site: softrod::site::Site::Rod { rod: 0, s_m: 0.15 },
        direction: [0.0, -2.0, 0.0],
    };
    for model in [LoadModel::Distributed, along] {
        adjoint_gradients_equal_the_forward_sensitivities_of(model);
    }
}

fn adjoint_gradients_equal_the_forward_sensitivities_of(model: LoadModel) {
    let (robot, known) = robot_and_loads();
    let n_f = model.n_params(&robot);
    let mut tracker =
        EquilibriumTracker::new(robot.clone(), known.clone(), StaticSettings::default()).unwrap();
    let eq = tracker
        .solve(
            &model,
            &vec![0.0; n_f],
            robot.arc_configuration(&known.pressures_pa).as_slice(),
        )
        .unwrap();
    let s = Sensitivity::new(&robot, &eq.factors).unwrap();
    let nq = robot.n_q();
    let rows: Vec<Vec<(usize, f64)>> = vec![
        vec![(nq - 4, 1.0)],                 // tip x
        vec![(nq - 3, 0.5), (nq - 7, 0.5)],  // mean y of the last two nodes
        vec![(0, 1.0), (2, 0.3), (5, -0.2)], // touches the clamped base
    ];
    let adj = s.adjoints(rows.iter().map(Vec::as_slice)).unwrap();
    let c = DMatrix::from_fn(nq, rows.len(), |i, k| {
        rows[k]
            .iter()
            .filter(|(j, _)| *j == i)
            .map(|(_, w)| w)
            .sum()
    });
    let by_adjoint = s.load_gradients(&model, &adj).unwrap();
    let forward = s.dq_df(&model).unwrap().tr_mul(&c);
    let err = rel_err(&forward, &by_adjoint);
    assert!(err < 1e-10, "load gradients: {err:e}");
    let by_adjoint = s.pressure_gradients(eq.q.as_slice(), &adj).unwrap();
    let forward = s.dq_dp(eq.q.as_slice()).unwrap().tr_mul(&c);
    let err = rel_err(&forward, &by_adjoint);
    assert!(err < 1e-10, "pressure gradients: {err:e}");
}
