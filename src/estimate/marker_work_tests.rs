//! The estimator's work in the number of markers: the primal form of the
//! Gauss–Newton systems ([`super::gn_form`]) gives the representer form's
//! estimates (the code path the distributed load took at every marker
//! count before), and its dense work grows linearly in the markers.

use crate::assembly::Robot;
use crate::element::PlanarCable;
use crate::estimate::{Backend, Estimate, Estimator, EstimatorSettings};
use crate::estimate::{MarkerObservation, NewtonEstimator, Observation, SqpEstimator};
use crate::linsolve::LinearWork;
use crate::loads::{LineLoad, Loads, PointForce};
use crate::scene::Scene;
use crate::statics::StaticSolver;

use super::gn_form::{GnForm, dense_work};
use super::problem::Problem;

/// The two-section robot with `n` elements, its known loads and two noisy
/// frames (σ = 0.01 mm, seeds 0 and 1) of `m` markers at `L k / m` on its
/// equilibrium under an unknown 20 g tip mass plus 0.5 N/m (the benches'
/// scenario, `tests/common/streaming.rs`).
fn case(n: usize, m: usize) -> (Robot<PlanarCable>, Loads, Vec<Observation>) {
    let mut scene = Scene::two_section();
    scene.robot.sections[0].elements = n / 2;
    scene.robot.sections[1].elements = n - n / 2;
    let robot = scene.robot().unwrap();
    let known = scene.loads().unwrap();
    let solver = StaticSolver::default();
    let mut q = solver.solve(&robot, &known, None).unwrap().q;
    for k in 1..=8 {
        let k = f64::from(k) / 8.0;
        let mut truth = known.clone();
        truth.point_forces.push(PointForce {
            s_m: robot.length(),
            force_n: vec![0.0, -0.02 * 9.81 * k],
        });
        truth.line_loads.push(LineLoad::Uniform {
            w_n_per_m: vec![0.0, -0.5 * k],
        });
        q = solver.solve(&robot, &truth, Some(q.as_slice())).unwrap().q;
    }
    let markers: Vec<MarkerObservation> = (1..=m)
        .map(|k| {
            let s = robot.length() * k as f64 / m as f64;
            MarkerObservation::at_arc(s, robot.position_at(q.as_slice(), s).unwrap())
        })
        .collect();
    let frames = (0..2)
        .map(|k| {
            Observation {
                markers: markers.clone(),
            }
            .with_noise(1e-5, k)
        })
        .collect();
    (robot, known, frames)
}

/// An estimator of `backend` with `alpha`, the representer form kept up
/// to `representer_max` observed components.
fn estimator(
    backend: Backend,
    alpha: Option<f64>,
    robot: &Robot<PlanarCable>,
    known: &Loads,
    representer_max: Option<usize>,
) -> Box<dyn Estimator> {
    let settings = EstimatorSettings {
        backend,
        alpha,
        ..EstimatorSettings::default()
    };
    estimator_with(settings, robot, known, representer_max)
}

/// [`estimator`] with the given settings.
fn estimator_with(
    settings: EstimatorSettings,
    robot: &Robot<PlanarCable>,
    known: &Loads,
    representer_max: Option<usize>,
) -> Box<dyn Estimator> {
    let backend = settings.backend;
    let set = |p: &mut Problem<Robot<PlanarCable>>| {
        if let Some(r) = representer_max {
            p.set_representer_max(r);
        }
    };
    match backend {
        Backend::Newton => {
            let mut e = NewtonEstimator::new(robot, known, &settings).unwrap();
            set(e.problem_mut());
            Box::new(e)
        }
        Backend::Sqp => {
            let mut e = SqpEstimator::new(robot, known, &settings).unwrap();
            set(e.problem_mut());
            Box::new(e)
        }
    }
}

/// `|a − b|∞ ≤ tol · max(|b|∞, floor)`.
fn close(a: &[f64], b: &[f64], tol: f64, floor: f64) -> bool {
    let scale = b.iter().fold(floor, |x, v| x.max(v.abs()));
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| (x - y).abs() <= tol * scale)
}

/// The estimates, their covariance and determined directions agree.
fn assert_same(new: &Estimate, old: &Estimate, what: &str) {
    assert_eq!(new.report.status, old.report.status, "{what}");
    assert_eq!(new.report.iterations, old.report.iterations, "{what}");
    assert_eq!(new.report.alpha, old.report.alpha, "{what}");
    let tol = 1e-10;
    let d = |a: &[f64], b: &[f64]| {
        let s = b.iter().fold(0.0f64, |x, v| x.max(v.abs()));
        a.iter()
            .zip(b)
            .fold(0.0f64, |x, (p, q)| x.max((p - q).abs()))
            / s
    };
    println!(
        "{what}: relative differences F {:.1e} q {:.1e} resultant {:.1e}",
        d(new.f.as_slice(), old.f.as_slice()),
        d(new.q.as_slice(), old.q.as_slice()),
        d(
            new.resultant_force_n.as_slice(),
            old.resultant_force_n.as_slice()
        )
    );
    // the load parameters' weakly determined directions (the slopes `w'`,
    // penalized by α = 31 against weights 1e10) carry either form's
    // round-off amplified by the system's conditioning: measured 6e-10 to
    // 2e-8 of max |F|; what the markers determine (shape, resultant)
    // agrees to 1e-11
    assert!(
        close(new.f.as_slice(), old.f.as_slice(), 1e-7, 0.0),
        "{what}: F"
    );
    assert!(
        close(new.q.as_slice(), old.q.as_slice(), tol, 0.0),
        "{what}: q"
    );
    assert!(
        close(
            new.resultant_force_n.as_slice(),
            old.resultant_force_n.as_slice(),
            tol,
            0.0
        ),
        "{what}: {} vs {}",
        new.resultant_force_n,
        old.resultant_force_n
    );
    let rel = (new.report.objective - old.report.objective).abs() / old.report.objective;
    assert!(rel <= tol, "{what}: objective {rel:e}");
    let (cn, co) = (new.resultant_force_cov(), old.resultant_force_cov());
    // with α by the evidence the covariance is averaged over α with the
    // width of the evidence's curvature, `2 uᵀPu − α pen − tr T² + γ`, a
    // sum of terms of O(n_F) that nearly cancel (measured 2.5e-9 relative)
    let dc = d(cn.as_slice(), co.as_slice());
    println!("{what}: resultant covariance {dc:.1e}");
    assert!(
        close(cn.as_slice(), co.as_slice(), 1e-8, 0.0),
        "{what}: covariance {dc:e}"
    );
    let (gn, go) = (new.determined_directions(), old.determined_directions());
    // γ = n_F − α tr(N⁻¹ B) = n_ob − α tr(S⁻¹ W⁻¹): 84 − 77 or 120 − 113,
    // a difference of nearly equal traces (measured 6e-10 relative)
    assert!(
        (gn - go).abs() <= 1e-8 * go.abs().max(1.0),
        "{what}: γ {gn} vs {go}"
    );
}

/// At 60 markers on 20 elements (120 observed components, 84 load
/// parameters) the default estimator solves its Gauss–Newton systems in
/// the primal form; its estimates (a first step and a warm one, `α` given
/// and by the evidence, both backends, and the sqp backend with a load
/// bound active at the solution) equal those of the representer
/// form, the code path of every marker count before, within 1e-10
/// relative: shape, resultant and objective (the load parameters within
/// 1e-7, `γ` and the resultant's posterior covariance within 1e-8, see
/// [`assert_same`]);
/// the same status, iterations and `α`.
#[test]
fn primal_form_gives_the_representer_forms_estimates() {
    let (robot, known, frames) = case(20, 60);
    for backend in [Backend::Newton, Backend::Sqp] {
        for alpha in [Some(31.0), None] {
            let mut new = estimator(backend, alpha, &robot, &known, None);
            let mut old = estimator(backend, alpha, &robot, &known, Some(usize::MAX));
            for (k, frame) in frames.iter().enumerate() {
                let what = format!("{} α {alpha:?} frame {k}", backend.name());
                let (a, b) = (new.step(frame).unwrap(), old.step(frame).unwrap());
                assert!(
                    a.report.status.is_converged(),
                    "{what}: {:?}",
                    a.report.status
                );
                assert_same(&a, &b, &what);
                // the resultant's covariance alone is the one formed with
                // the markers' (n_ob × n_ob)
                let r = a.resultant_force_cov().clone();
                assert_eq!(a.marker_cov().shape(), (120, 120));
                assert_eq!(&r, a.resultant_force_cov(), "{what}");
            }
        }
    }
    // the sqp backend with a load bound active at the solution (w_y ≥ −0.3
    // N/m at mid-length, the benches' bound): its QP's reduced system in
    // either form
    let bounded = EstimatorSettings {
        backend: Backend::Sqp,
        alpha: Some(31.0),
        bounds: vec![crate::estimate::LoadBound {
            s_m: 0.5 * robot.length(),
            frame: crate::estimate::BoundFrame::World,
            direction: vec![0.0, 1.0],
            min_n_per_m: Some(-0.3),
            max_n_per_m: None,
        }],
        ..EstimatorSettings::default()
    };
    let mut new = estimator_with(bounded.clone(), &robot, &known, None);
    let mut old = estimator_with(bounded, &robot, &known, Some(usize::MAX));
    for (k, frame) in frames.iter().enumerate() {
        let what = format!("sqp bounded frame {k}");
        let (a, b) = (new.step(frame).unwrap(), old.step(frame).unwrap());
        assert!(
            a.report.status.is_converged(),
            "{what}: {:?}",
            a.report.status
        );
        assert_same(&a, &b, &what);
    }
    // the test compares the two forms: the default takes the primal one
    let settings = EstimatorSettings::default();
    let mut p = Problem::new(robot.clone(), known.clone(), settings).unwrap();
    assert!(matches!(p.gn_form(120).unwrap(), GnForm::Primal(_)));
    assert!(matches!(p.gn_form(84).unwrap(), GnForm::Representer));
    p.set_representer_max(usize::MAX);
    assert!(matches!(p.gn_form(120).unwrap(), GnForm::Representer));
}

/// The dense work (flops of the Gauss–Newton, evidence and covariance
/// systems, `gn_form::count_dense`) and the solved right-hand sides of a
/// first step and a warm step.
fn step_work(backend: Backend, alpha: Option<f64>, m: usize) -> [(u64, usize); 2] {
    let (robot, known, frames) = case(4, m);
    let mut est = estimator(backend, alpha, &robot, &known, None);
    let mut out = [(0, 0); 2];
    for (o, frame) in out.iter_mut().zip(&frames) {
        let (d0, l0) = (dense_work(), LinearWork::now());
        let e = est.step(frame).unwrap();
        assert!(e.report.status.is_converged(), "{m}: {:?}", e.report.status);
        let _ = e.resultant_force_cov();
        *o = (dense_work() - d0, LinearWork::now().since(l0).solves);
    }
    out
}

/// The estimator's work is linear in the markers: on 4 elements (20 load
/// parameters), from 100 to 1 000 markers (200 to 2 000 observed
/// components) the dense work of a first step (with the resultant's
/// covariance) and of a warm step grows by at most 12× (linear: 10×; the
/// representer form at every count grew by ~1 000×, its `m³`), and the
/// solved right-hand sides (the adjoint solves, two per marker and
/// linearization) by at most 12×, for both backends, `α` given and by the
/// evidence. From 10 to 100 markers (the representer form at 10) the
/// growth is below 25× (the fixed `n_F³` part).
#[test]
fn estimator_work_is_linear_in_the_markers() {
    for backend in [Backend::Newton, Backend::Sqp] {
        for alpha in [Some(31.0), None] {
            let w: Vec<[(u64, usize); 2]> = [10, 100, 1000]
                .iter()
                .map(|&m| step_work(backend, alpha, m))
                .collect();
            println!("{} α {alpha:?}: {w:?}", backend.name());
            for s in 0..2 {
                let (d, l) = (|i: usize| w[i][s].0 as f64, |i: usize| w[i][s].1 as f64);
                let what = format!("{} α {alpha:?} step {s}: {w:?}", backend.name());
                assert!(d(2) <= 12.0 * d(1) && d(1) <= 25.0 * d(0), "{what}");
                assert!(l(2) <= 12.0 * l(1) && l(1) <= 12.0 * l(0), "{what}");
                assert!(d(2) > 0.0 && l(2) > 0.0, "{what}");
            }
        }
    }
}
