//! Property tests (issue "Hardening", point 4): equilibrium at every returned
//! solution, rigid-motion invariance of the elastic energy, a symmetric
//! tangent, scene JSON round trips, and bitwise-repeatable solves.
//!
//! Case counts are modest so the file runs in a few seconds in release; each
//! property states its count in its `ProptestConfig`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use proptest::prelude::*;
use softrod::Error;
use softrod::assembly::Robot;
use softrod::element::PlanarCable;
use softrod::linsolve::BandedMatrix;
use softrod::loads::{LineLoad, Loads, NodeMoment, PointForce};
use softrod::scene::Scene;
use softrod::statics::StaticSolver;

#[path = "common/scene_strategy.rs"]
mod scene_strategy;
use scene_strategy::scene_strategy;

fn config(cases: u32) -> ProptestConfig {
    ProptestConfig {
        cases,
        failure_persistence: None,
        // a fixed seed: the same cases on every machine and run
        rng_seed: proptest::test_runner::RngSeed::Fixed(0x50f7_70d5),
        ..ProptestConfig::default()
    }
}

/// The two-section scene with `n1`, `n2` elements.
fn scene(n1: usize, n2: usize) -> Scene {
    let mut s = Scene::two_section();
    s.robot.sections[0].elements = n1;
    s.robot.sections[1].elements = n2;
    s.markers.clear();
    s
}

/// Random loads that the robot can carry: pressures within their bounds,
/// a tip force, a uniform load and a tip moment of moderate size.
#[derive(Debug, Clone)]
struct LoadCase {
    n1: usize,
    n2: usize,
    pressures: Vec<f64>,
    tip_force: [f64; 2],
    uniform: [f64; 2],
    tip_moment: f64,
}

fn load_case() -> impl Strategy<Value = LoadCase> {
    (
        1usize..=12,
        1usize..=12,
        prop::collection::vec(0.0..100e3f64, 4),
        prop::array::uniform2(-0.3..0.3f64),
        prop::array::uniform2(-2.0..2.0f64),
        -0.05..0.05f64,
    )
        .prop_map(
            |(n1, n2, pressures, tip_force, uniform, tip_moment)| LoadCase {
                n1,
                n2,
                pressures,
                tip_force,
                uniform,
                tip_moment,
            },
        )
}

fn build(c: &LoadCase) -> (Robot<PlanarCable>, Loads) {
    let robot = scene(c.n1, c.n2).robot().unwrap();
    let loads = Loads {
        pressures_pa: c.pressures.clone(),
        point_forces: vec![PointForce {
            s_m: robot.length(),
            force_n: c.tip_force.to_vec(),
        }],
        line_loads: vec![LineLoad::Uniform {
            w_n_per_m: c.uniform.to_vec(),
        }],
        node_moments: vec![NodeMoment {
            node: robot.n_nodes() - 1,
            moment_nm: vec![c.tip_moment],
        }],
        ..Loads::default()
    };
    (robot, loads)
}

fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// A deterministic deformed configuration: the reference configuration
/// with every free coordinate perturbed.
fn deformed(robot: &Robot<PlanarCable>, amplitude: f64, seed: u64) -> Vec<f64> {
    let mut q = robot.reference_configuration();
    let mut s = seed;
    for v in q.iter_mut().skip(4) {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        *v += amplitude * (((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5);
    }
    q.data.into()
}

/// Regression (found by a CI run on a clean clone, when the seed was still
/// random): 2 + 12 elements, high pressures and a small tip force. The solve
/// ended on the increment test with |Q| = 2.2e-11 N, above the round-off floor
/// then estimated (0.02 ε |K| |q| √n = 1.9e-11 N): the floor was too low for
/// small meshes. The same property must hold here.
#[test]
fn regression_small_mesh_residual_stays_below_the_floor() {
    let c = LoadCase {
        n1: 2,
        n2: 12,
        pressures: vec![
            65419.97799099239,
            2504.1760277334806,
            64893.85055138125,
            23550.515822922494,
        ],
        tip_force: [0.009077662677940194, 0.006819537927385738],
        uniform: [0.0, 0.0],
        tip_moment: 0.0,
    };
    let (robot, loads) = build(&c);
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    let dead = robot.dead_force(&loads).unwrap();
    let res = norm(
        robot
            .residual(eq.q.as_slice(), dead.as_slice(), &loads)
            .unwrap()
            .as_slice(),
    );
    let r = &eq.report;
    assert!(
        res <= r.residual_tolerance_n.max(r.residual_floor_n),
        "|Q| = {res:e}: {r}"
    );
}

proptest! {
    #![proptest_config(config(48))]

    /// At every returned solution the equilibrium residual, recomputed from
    /// the public API, is below the reported tolerance or round-off floor,
    /// and every returned number is finite. 48 cases.
    #[test]
    fn residual_is_below_the_reported_tolerance_at_every_solution(c in load_case()) {
        let (robot, loads) = build(&c);
        let eq = match StaticSolver::default().solve(&robot, &loads, None) {
            Ok(eq) => eq,
            // loads this moderate must converge
            Err(e) => return Err(TestCaseError::fail(format!("{e}"))),
        };
        let r = &eq.report;
        prop_assert!(eq.q.iter().all(|v| v.is_finite()));
        let dead = robot.dead_force(&loads).unwrap();
        let res = norm(robot.residual(eq.q.as_slice(), dead.as_slice(), &loads).unwrap().as_slice());
        let bound = r.residual_tolerance_n.max(r.residual_floor_n);
        prop_assert!(res <= bound * (1.0 + 1e-9), "|Q| = {res:e} > {bound:e}: {r}");
        prop_assert!((res - r.residual_norm_n).abs() <= 1e-12 * bound.max(res), "{res} vs {r}");
    }

    /// Solving the same problem twice, with a freshly built robot, gives
    /// bitwise identical coordinates and reports (wall time aside). 48 cases.
    #[test]
    fn solves_are_bitwise_repeatable(c in load_case()) {
        let (robot, loads) = build(&c);
        let (robot2, loads2) = build(&c);
        let solver = StaticSolver::default();
        let a = solver.solve(&robot, &loads, None);
        let b = solver.solve(&robot2, &loads2, None);
        match (a, b) {
            (Ok(a), Ok(b)) => {
                let bits = |q: &[f64]| q.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
                prop_assert_eq!(bits(a.q.as_slice()), bits(b.q.as_slice()));
                let mut ra = a.report.clone();
                ra.wall_time_s = b.report.wall_time_s;
                prop_assert_eq!(
                    format!("{ra:?}").replace(' ', ""),
                    format!("{:?}", b.report).replace(' ', "")
                );
                prop_assert_eq!(ra.residual_norm_n.to_bits(), b.report.residual_norm_n.to_bits());
            }
            (Err(Error::NotConverged { report: ra }), Err(Error::NotConverged { report: rb })) => {
                prop_assert_eq!(ra.iterations, rb.iterations);
                prop_assert_eq!(ra.residual_norm_n.to_bits(), rb.residual_norm_n.to_bits());
            }
            (a, b) => prop_assert!(false, "outcomes differ: {a:?} vs {b:?}"),
        }
    }
}

proptest! {
    #![proptest_config(config(64))]

    /// The elastic energy of a deformed configuration does not change when
    /// the whole configuration is rotated and translated (positions
    /// `R r + t`, slopes `R r'`). 64 cases.
    #[test]
    fn elastic_energy_is_invariant_under_rigid_motions(
        n in 1usize..=10,
        seed in any::<u64>(),
        amplitude in 0.0..0.05f64,
        angle in -10.0..10.0f64,
        t in prop::array::uniform2(-5.0..5.0f64),
    ) {
        let robot = scene(n, n).robot().unwrap();
        let q = deformed(&robot, amplitude, seed);
        let (c, s) = (angle.cos(), angle.sin());
        let moved: Vec<f64> = q
            .chunks_exact(4)
            .flat_map(|p| {
                [
                    c * p[0] - s * p[1] + t[0],
                    s * p[0] + c * p[1] + t[1],
                    c * p[2] - s * p[3],
                    s * p[2] + c * p[3],
                ]
            })
            .collect();
        let u0 = robot.elastic_energy(&q).unwrap();
        let u1 = robot.elastic_energy(&moved).unwrap();
        prop_assert!(u0.is_finite() && u1.is_finite());
        prop_assert!((u0 - u1).abs() <= 1e-9 * u0.abs() + 1e-15, "{u0} vs {u1}");
    }

    /// The tangent stiffness (elastic part plus the moment loads of the
    /// actuation and of concentrated moments: all conservative) is
    /// symmetric at any configuration. 64 cases.
    #[test]
    fn tangent_is_symmetric(
        n1 in 1usize..=8,
        n2 in 1usize..=8,
        seed in any::<u64>(),
        amplitude in 0.0..0.1f64,
        pressures in prop::collection::vec(0.0..100e3f64, 4),
        moment in -0.1..0.1f64,
    ) {
        let robot = scene(n1, n2).robot().unwrap();
        let q = deformed(&robot, amplitude, seed);
        let loads = Loads {
            pressures_pa: pressures,
            node_moments: vec![NodeMoment { node: n1, moment_nm: vec![moment] }],
            ..Loads::default()
        };
        let mut k = BandedMatrix::zeros(1, 0, 0);
        robot.tangent_into(&q, &loads, &mut k).unwrap();
        let scale = k.max_abs();
        prop_assert!(scale.is_finite() && scale > 0.0);
        let n = robot.n_free();
        for i in 0..n {
            for j in i + 1..n {
                let (a, b) = (k.get(i, j), k.get(j, i));
                prop_assert!((a - b).abs() <= 1e-12 * scale, "K[{i},{j}] = {a} vs K[{j},{i}] = {b}");
            }
        }
    }
}

proptest! {
    #![proptest_config(config(128))]

    /// Serialize → parse gives the same scene, and serializing again gives
    /// the same text. 128 cases.
    #[test]
    fn scene_json_round_trips_unchanged(s in scene_strategy()) {
        let text = serde_json::to_string(&s).unwrap();
        let parsed: Scene = serde_json::from_str(&text).unwrap();
        prop_assert_eq!(&parsed, &s);
        prop_assert_eq!(serde_json::to_string(&parsed).unwrap(), text.clone());
        // the validating parser accepts it unless it is a duplicate marker
        match Scene::from_json(&text) {
            Ok(v) => prop_assert_eq!(v, s),
            Err(Error::InvalidParameter { name, .. }) if name == "markers[1]" => {}
            Err(e) => prop_assert!(false, "{e}"),
        }
    }
}
