//! The streaming estimator's scenario, shared by `tests/estimate_work.rs`
//! and `benches/estimate.rs`: the two-section robot with `n` elements, an
//! unknown 20 g tip mass plus a 0.5 N/m uniform load (added in eight steps
//! from the known loads' equilibrium: a cold solve of the true loads does
//! not converge at 450 elements and more), `m` markers at arc lengths
//! `k L / m`, `k = 1..=m`, and noisy frames of them (0.01 mm, seed = frame
//! index).
#![allow(dead_code)]

use softrod::assembly::Robot;
use softrod::element::PlanarCable;
use softrod::estimate::{MarkerObservation, Observation};
use softrod::loads::{LineLoad, Loads, PointForce};
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

/// The robot with `n` elements, its known loads and `frames` noisy
/// observations of `m` markers on the true shape.
pub fn streaming_case(
    n: usize,
    m: usize,
    frames: u64,
) -> (Robot<PlanarCable>, Loads, Vec<Observation>) {
    let mut scene = Scene::two_section();
    scene.robot.sections[0].elements = n / 2;
    scene.robot.sections[1].elements = n - n / 2;
    let robot = scene.robot().unwrap();
    assert_eq!(robot.elements().len(), n);
    let known = scene.loads().unwrap();
    let truth_at = |k: f64| {
        let mut truth = known.clone();
        truth.point_forces.push(PointForce {
            s_m: robot.length(),
            force_n: vec![0.0, -0.02 * 9.81 * k],
        });
        truth.line_loads.push(LineLoad::Uniform {
            w_n_per_m: vec![0.0, -0.5 * k],
        });
        truth
    };
    let solver = StaticSolver::default();
    let mut q = solver.solve(&robot, &known, None).unwrap().q;
    for k in 1..=8 {
        q = solver
            .solve(&robot, &truth_at(f64::from(k) / 8.0), Some(q.as_slice()))
            .unwrap()
            .q;
    }
    let markers: Vec<MarkerObservation> = (1..=m)
        .map(|k| {
            let s = robot.length() * k as f64 / m as f64;
            MarkerObservation::at_arc(s, robot.position_at(q.as_slice(), s).unwrap())
        })
        .collect();
    let frames = (0..frames)
        .map(|k| {
            Observation {
                markers: markers.clone(),
            }
            .with_noise(1e-5, k)
        })
        .collect();
    (robot, known, frames)
}
