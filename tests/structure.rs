//! Structures: rods, rigid bodies and joints (issue 10, point 4).
//!
//! - A single clamped rod built as a structure is the robot of wave 1:
//!   same free coordinates, residual, tangent and equilibrium.
//! - The structure's residual is minus the gradient of its total potential
//!   and its tangent the Jacobian of the residual (central differences), on
//!   a two-leg platform with every kind of load, turned and stretched so the
//!   nonlinear joint map and its second derivative matter.
//! - Two clamped legs whose tips are fixed to one rigid platform: the joint
//!   reactions balance the platform's load (free body of the platform), each
//!   leg's clamp reaction balances its joint reaction (free body of a leg),
//!   and in the small-load limit the platform moves as the closed form of
//!   two clamped–guided beams with axial stiffness says.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use std::sync::Arc;

use softrod::assembly::{Chamber, Section};
use softrod::element::{Element, PlanarCable};
use softrod::linsolve::BandedMatrix;
use softrod::loads::force_field::PointSpring;
use softrod::loads::{Loads, NodeMoment, PointForce};
use softrod::scene::Scene;
use softrod::statics::StaticSolver;
use softrod::structure::{
    BodyLoad, JointSpec, RigidBodySpec, RodEnd, RodSpec, Structure, StructureLoads, StructureSpec,
};

/// Leg length, half spacing, stiffnesses (the paper's simulated robot: EI
/// 0.02 N·m², EA 300 N).
const L: f64 = common::LEG_L;
const RHO: f64 = common::LEG_RHO;
const EI: f64 = common::LEG_EI;
const EA: f64 = common::LEG_EA;
use common::two_legs;

fn platform_load(force: [f64; 2], moment: f64) -> StructureLoads {
    StructureLoads {
        bodies: vec![BodyLoad {
            body: 0,
            force_n: force.to_vec(),
            moment_nm: vec![moment],
        }],
        ..StructureLoads::default()
    }
}

/// The static solver's equilibrium of the structure, its free coordinates.
fn solve(s: &Structure<PlanarCable>, loads: &StructureLoads) -> Vec<f64> {
    let eq = StaticSolver::default().solve(s, loads, None).unwrap();
    assert!(eq.report.status.is_converged(), "{}", eq.report);
    eq.u.data.into()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// The paper's two-section robot (weight, 60/30 kPa in two chambers, a tip
/// force, a moment) as a structure of one clamped rod: the same free
/// coordinates, residual and tangent as the robot (to round-off), and
/// Newton on the structure reaches the static solver's equilibrium.
#[test]
fn one_clamped_rod_is_the_single_chain() {
    let scene = Scene::two_section();
    let robot = scene.robot().unwrap();
    let mut loads = scene.loads().unwrap();
    loads.point_forces.push(PointForce {
        s_m: robot.length(),
        force_n: vec![0.01, -0.02],
    });
    loads.node_moments.push(NodeMoment {
        node: 7,
        moment_nm: vec![2e-3],
    });
    let spec = robot.spec();
    let a = spec.base.angle_rad;
    let mut s = StructureSpec::new(
        vec![RodSpec::clamped(
            spec.sections.clone(),
            nalgebra::Vector2::from_column_slice(&spec.base.position_m),
            nalgebra::Vector2::new(a.cos(), a.sin()),
        )],
        vec![],
        vec![],
    );
    s.gravity_m_per_s2 = spec.gravity_m_per_s2.clone();
    let structure = s.build_planar().unwrap();
    assert_eq!(structure.n_q(), robot.n_q());
    assert_eq!(structure.n_free(), robot.n_free());
    let sloads = StructureLoads {
        rods: vec![loads.clone()],
        ..StructureLoads::default()
    };
    // a perturbed state, as free coordinates of both
    let mut u = structure.reference_free_coordinates().to_vec();
    u.iter_mut()
        .enumerate()
        .for_each(|(i, v)| *v += 2e-3 * ((i as f64) * 0.77).sin());
    let q: Vec<f64> = structure.configuration(&u).unwrap().data.into();
    let q_robot = robot.dof_map().configuration(&u).unwrap();
    let dq = q
        .iter()
        .zip(&q_robot)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    assert!(dq < 1e-15, "{dq}");
    let dead_r = robot.dead_force(&loads).unwrap();
    let dead_s: Vec<f64> = structure.dead_force(&sloads).unwrap().data.into();
    assert_eq!(dead_r.as_slice(), dead_s);
    let mut r_robot = vec![0.0; robot.n_free()];
    let mut k_robot = BandedMatrix::zeros(1, 0, 0);
    robot
        .residual_and_tangent_into(&q, dead_r.as_slice(), &loads, &mut r_robot, &mut k_robot)
        .unwrap();
    let (r_s, k_s) = structure
        .residual_and_tangent(&u, &dead_s, &sloads)
        .unwrap();
    let k_s = k_s.to_dense();
    let rs = r_robot.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let ks = k_robot.max_abs();
    let mut worst = (0.0f64, 0.0f64);
    for i in 0..robot.n_free() {
        worst.0 = worst.0.max((r_robot[i] - r_s[i]).abs() / rs);
        for j in 0..robot.n_free() {
            worst.1 = worst.1.max((k_robot.get(i, j) - k_s[(i, j)]).abs() / ks);
        }
    }
    println!(
        "single chain: residual {:.1e}, tangent {:.1e} (relative to the largest entry)",
        worst.0, worst.1
    );
    assert!(worst.0 < 1e-13 && worst.1 < 1e-13, "{worst:?}");
    // the equilibria
    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
    assert!(eq.report.status.is_converged());
    let seq = StaticSolver::default()
        .solve(&structure, &sloads, None)
        .unwrap();
    assert!(seq.report.status.is_converged(), "{}", seq.report);
    let dq =
        eq.q.iter()
            .zip(&seq.q)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
    println!("single chain: equilibria differ by {dq:.1e} m");
    assert!(dq < 1e-10 * robot.length(), "{dq}");
}

/// Every load a structure takes, on the two-leg platform: weight of legs
/// and platform, a platform force and moment, pressures in a chamber of leg
/// 0 (its end torque acts at the joined node), a point force at leg 1's
/// joined tip, a moment at an interior node, and a spring from the platform
/// to a point. Checked at a turned (θ = 0.3), stretched, bent state.
fn loaded_platform() -> (Structure<PlanarCable>, StructureLoads, Vec<f64>) {
    let mut spec = two_legs(3, 0.05, true);
    for rod in &mut spec.rods {
        rod.sections[0].mass_per_length_kg_per_m = 0.1;
    }
    spec.rods[0].sections[0].chambers = vec![Chamber {
        gain_nm_per_pa: vec![3e-6],
        pressure_min_pa: 0.0,
        pressure_max_pa: 1e5,
    }];
    let mut s = spec.build_planar().unwrap();
    let pose = s.body_coordinates(0).unwrap();
    s.add_force_field(Arc::new(
        PointSpring::new(
            [pose.start, pose.start + 1],
            nalgebra::Vector2::new(0.05, 0.3),
            40.0,
            0.02,
        )
        .unwrap(),
    ))
    .unwrap();
    let loads = StructureLoads {
        rods: vec![
            Loads {
                pressures_pa: vec![4e4],
                node_moments: vec![NodeMoment {
                    node: 1,
                    moment_nm: vec![3e-3],
                }],
                ..Loads::default()
            },
            Loads {
                point_forces: vec![PointForce {
                    s_m: L,
                    force_n: vec![0.3, -0.2],
                }],
                ..Loads::default()
            },
        ],
        bodies: vec![BodyLoad {
            body: 0,
            force_n: vec![0.2, -0.1],
            moment_nm: vec![0.01],
        }],
    };
    let mut u = s.reference_free_coordinates().to_vec();
    for (i, v) in u.iter_mut().enumerate() {
        *v += 0.01 * ((i as f64) * 1.3 + 0.4).sin();
    }
    let th = s.body_free_coordinates(0).unwrap().start + 2;
    u[th] = 0.3;
    (s, loads, u)
}

/// `R = −∂Π/∂u` and `K_u = −∂R/∂u` by central differences (step 1e-6 on
/// every free coordinate), with the joint map's second derivative switched
/// on by a turned platform and loads at the joined nodes.
#[test]
fn residual_and_tangent_are_the_derivatives_of_the_potential() {
    let (s, loads, u) = loaded_platform();
    let dead: Vec<f64> = s.dead_force(&loads).unwrap().data.into();
    let (r, k) = s.residual_and_tangent(&u, &dead, &loads).unwrap();
    let k = k.to_dense();
    let n = s.n_free();
    let h = 1e-6;
    let rscale = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let kscale = k.amax();
    let (mut er, mut ek) = (0.0f64, 0.0f64);
    for j in 0..n {
        let (mut up, mut um) = (u.clone(), u.clone());
        up[j] += h;
        um[j] -= h;
        let dpi = s.potential_change(&um, &up, &dead, &loads).unwrap();
        er = er.max((-dpi / (2.0 * h) - r[j]).abs() / rscale);
        let rp = s.residual(&up, &dead, &loads).unwrap();
        let rm = s.residual(&um, &dead, &loads).unwrap();
        for i in 0..n {
            ek = ek.max((-(rp[i] - rm[i]) / (2.0 * h) - k[(i, j)]).abs() / kscale);
        }
    }
    // the geometric term Σ g_i ∂²φ_i/∂u² (g = −Q) is present at this state
    let mut g: Vec<f64> = s.generalized_force(&u, &dead, &loads).unwrap().data.into();
    g.iter_mut().for_each(|v| *v = -*v);
    let mut kg = nalgebra::DMatrix::zeros(n, n);
    s.dof_map()
        .add_geometric_stiffness(&u, &g, &mut kg)
        .unwrap();
    let geometric = kg.amax() / kscale;
    println!(
        "structure FD: residual {er:.1e}, tangent {ek:.1e} (relative); geometric term {geometric:.1e} of the tangent"
    );
    assert!(er < 1e-7, "residual vs potential: {er:e}");
    assert!(ek < 1e-7, "tangent vs residual: {ek:e}");
    assert!(
        geometric > 1e-4,
        "the state must exercise the joint's curvature"
    );
}

/// The small-load closed form of two legs and a platform.
///
/// Leg `i` stands at `x_i = ±ρ`, clamped at its base, its tip fixed to the
/// platform. The platform's reference point `(0, L)` moves by `(u_x, u_y)`
/// and turns by `θ`; a leg's tip then moves sideways by `u_x`, along its
/// axis by `u_y + θ x_i`, and turns by `θ`. Linear Euler–Bernoulli bending
/// of a clamped beam with tip deflection `w = u_x` and tip slope
/// `w' = −θ` (a counter-clockwise turn tilts the upward tangent to −x) has
/// energy `½ EI (12 w²/L³ − 12 w w'/L² + 4 w'²/L)`; the bar `½ (EA/L) (u_y
/// + θ x_i)²`. Summed over the two legs, with a force `(H, V)` and a moment
/// `T` on the platform:
///
/// `Π = EI (12 u_x²/L³ + 12 u_x θ/L² + 4 θ²/L) + (EA/L) (u_y² + ρ² θ²) − H u_x − V u_y − T θ`,
///
/// so `[24 EI/L³, 12 EI/L²; 12 EI/L², 8 EI/L + 2 EA ρ²/L] (u_x, θ) = (H, T)`
/// and `u_y = V L / (2 EA)`. With a rigid platform that does not turn
/// (`EA → ∞`) this is the clamped–guided sway `u_x = (H/2) L³/(12 EI)` of
/// each leg; a moment alone turns the platform by
/// `θ = T / (2 EA ρ²/L + 2 EI/L)` (the legs' axial push-pull plus their
/// bending under the end rotation, `8 EI/L − (12 EI/L²)²/(24 EI/L³)`).
fn closed_form(h: f64, v: f64, t: f64) -> [f64; 3] {
    let kxx = 24.0 * EI / L.powi(3);
    let kxt = 12.0 * EI / (L * L);
    let ktt = 8.0 * EI / L + 2.0 * EA * RHO * RHO / L;
    let det = kxx * ktt - kxt * kxt;
    [
        (ktt * h - kxt * t) / det,
        v * L / (2.0 * EA),
        (kxx * t - kxt * h) / det,
    ]
}

/// The platform's displacement `(u_x, u_y, θ)` at equilibrium under
/// `(H, V, T)` (weightless legs and platform).
fn platform_motion(s: &Structure<PlanarCable>, h: f64, v: f64, t: f64) -> [f64; 3] {
    let u = solve(s, &platform_load([h, v], t));
    let p = s.body_free_coordinates(0).unwrap().start;
    [u[p], u[p + 1] - L, u[p + 2]]
}

/// Small loads on the two-leg platform against the closed form above:
/// sideways force H, vertical force V, moment T, each alone, at two load
/// levels a decade apart (H = 1e-3 N, V = −0.1 N, T = 1e-4 N·m, then a
/// tenth). The discretization is exact for this linear problem (cubic
/// Hermite elements hold the cubic deflection, linear axial displacement),
/// so what is left is the geometric nonlinearity, second order in the load
/// for the sway, and the solver's round-off. Measured relative errors: sway
/// 8.8e-9 then 6.6e-11 (it shrinks a hundredfold), turn 3e-10 and 1.3e-10,
/// sink 7e-13 and 7e-12 (round-off). Bound 1e-7 on all: leaving out the
/// legs' bending under the end rotation (2 EI/L of 7.7 N·m) would be 2.6 %,
/// a wrong constant in the sway tens of percent.
#[test]
fn small_loads_move_the_platform_as_two_clamped_guided_legs() {
    let s = two_legs(4, 0.0, false).build_planar().unwrap();
    let mut errs = Vec::new();
    for scale in [1.0, 0.1] {
        let (h, v, t) = (1e-3 * scale, -1e-1 * scale, 1e-4 * scale);
        let sway = platform_motion(&s, h, 0.0, 0.0);
        let cf = closed_form(h, 0.0, 0.0);
        let e_sway = rel(sway[0], cf[0]).max(rel(sway[2], cf[2]));
        let turn = platform_motion(&s, 0.0, 0.0, t);
        let cf = closed_form(0.0, 0.0, t);
        let e_turn = rel(turn[2], cf[2]).max(rel(turn[0], cf[0]));
        let sink = platform_motion(&s, 0.0, v, 0.0);
        let cf = closed_form(0.0, v, 0.0);
        let e_sink = rel(sink[1], cf[1]);
        println!(
            "load x{scale}: sway u_x = {:.6e} m (closed form {:.6e}), rel. error {e_sway:.1e}; \
             turn θ = {:.6e} rad ({:.6e}), {e_turn:.1e}; sink u_y {e_sink:.1e}",
            sway[0],
            closed_form(h, 0.0, 0.0)[0],
            turn[2],
            closed_form(0.0, 0.0, t)[2],
        );
        errs.push([e_sway, e_turn, e_sink]);
    }
    for e in &errs {
        assert!(e.iter().all(|x| *x < 1e-7), "{errs:?}");
    }
    assert!(
        errs[1][0] < 0.1 * errs[0][0],
        "the sway's error must shrink with the load: {errs:?}"
    );
    // the clamped–guided limit itself: with the platform's turn suppressed
    // (EA → ∞) the sway is (H/2) L³ / (12 EI); the platform's small turn
    // softens it to H / (24 EI/L³ − (12 EI/L²)² / (8 EI/L + 2 EA ρ²/L)),
    // 7.8 % more here
    let guided = 0.5e-3 * L.powi(3) / (12.0 * EI);
    let cf = closed_form(1e-3, 0.0, 0.0)[0];
    println!("clamped–guided sway {guided:.6e} m, with the platform's turn {cf:.6e} m");
    assert!(cf > guided && rel(cf, guided) < 0.08);
}

/// The generalized force on a leg's joined tip node from the leg alone
/// (minus the last element's energy gradient there: weightless legs, no
/// loads on them) and the wrench it exerts on the platform about the
/// platform's reference point: force `F = Q_r`, moment `n × F + λ e × Q_r'`
/// with `n = r_tip − x_b`, `λ e = r'_tip`.
fn tip_wrench(s: &Structure<PlanarCable>, q: &[f64], rod: usize) -> [f64; 3] {
    let last = s.rods()[rod].n_elements() - 1;
    let a = s.node_coordinates(rod, last).unwrap();
    let b = s.node_coordinates(rod, last + 1).unwrap();
    let mut qe = q[a.clone()].to_vec();
    qe.extend_from_slice(&q[b.clone()]);
    let mut ge = vec![0.0; 8];
    s.rods()[rod].elements()[last].add_energy_gradient(&qe, &mut ge);
    let f: Vec<f64> = ge[4..].iter().map(|v| -v).collect();
    let x = s.body_coordinates(0).unwrap();
    let (n0, n1) = (q[b.start] - q[x.start], q[b.start + 1] - q[x.start + 1]);
    let (t0, t1) = (q[b.start + 2], q[b.start + 3]);
    let m = n0 * f[1] - n1 * f[0] + (t0 * f[3] - t1 * f[2]);
    [f[0], f[1], m]
}

/// Two legs, a 50 g platform under gravity, a sideways force and a moment
/// large enough to bend the legs visibly (sway ≈ 4 % of L): at Newton's
/// equilibrium the reactions of the two tips on the platform, computed from
/// the legs' element forces, plus the platform's weight and load sum to
/// zero (free body of the platform, 1e-9 of the loads); they equal the
/// library's `joint_reactions`; and each leg's clamp reaction is minus its
/// tip force (free body of a weightless leg).
#[test]
fn joint_reactions_balance_the_platform_and_the_legs() {
    let s = two_legs(8, 0.05, true).build_planar().unwrap();
    let (h, t) = (0.5, 0.02);
    let loads = platform_load([h, 0.0], t);
    let u = solve(&s, &loads);
    let q: Vec<f64> = s.configuration(&u).unwrap().data.into();
    let dead: Vec<f64> = s.dead_force(&loads).unwrap().data.into();
    let weight = -0.05 * 9.81;
    let w: Vec<[f64; 3]> = (0..2).map(|rod| tip_wrench(&s, &q, rod)).collect();
    let sum = [
        w[0][0] + w[1][0] + h,
        w[0][1] + w[1][1] + weight,
        w[0][2] + w[1][2] + t,
    ];
    let force_scale =
        w[0][0].abs() + w[1][0].abs() + w[0][1].abs() + w[1][1].abs() + h.abs() + weight.abs();
    let moment_scale = w[0][2].abs() + w[1][2].abs() + t.abs();
    let balance = ((sum[0].abs() + sum[1].abs()) / force_scale).max(sum[2].abs() / moment_scale);
    let p = s.body_free_coordinates(0).unwrap().start;
    println!(
        "platform at ({:.4e}, {:.4e}) m, θ = {:.4e} rad; tip forces {:?} {:?}; free-body balance {balance:.1e}",
        u[p],
        u[p + 1],
        u[p + 2],
        w[0],
        w[1]
    );
    assert!(
        u[p] > 0.03 * L,
        "the test must bend the legs: sway {}",
        u[p]
    );
    assert!(balance < 1e-9, "platform free body: {sum:?}");
    // the library's reactions are the same wrenches
    let reactions = s.joint_reactions(&u, &dead, &loads).unwrap();
    assert_eq!(reactions.len(), 2);
    for (r, w) in reactions.iter().zip(&w) {
        assert_eq!(r.body, 0);
        let d = (r.force_n[0] - w[0]).abs() + (r.force_n[1] - w[1]).abs();
        assert!(d < 1e-12 * force_scale && (r.moment_nm[0] - w[2]).abs() < 1e-12 * moment_scale);
    }
    // each leg: what it pushes on its clamp is minus what it pushes on the
    // platform (no load between)
    let qgen: Vec<f64> = s.generalized_force(&u, &dead, &loads).unwrap().data.into();
    for (rod, w) in w.iter().enumerate() {
        let base = s.node_coordinates(rod, 0).unwrap();
        let d = (qgen[base.start] + w[0]).abs() + (qgen[base.start + 1] + w[1]).abs();
        assert!(
            d < 1e-9 * force_scale,
            "leg {rod}: clamp {:?} vs tip {w:?}",
            &qgen[base]
        );
    }
}

/// A two-finger gripper: a palm (a rigid body fixed to the ground, turned
/// by 0.2 rad) carries two fingers of two actuated sections each, joined at
/// their starts, free at their tips. A joint to a fixed body is a clamp at
/// the joint's pose, so each finger must settle exactly as a robot clamped
/// at that pose does (the static solver of wave 1), under its weight and
/// its chamber pressures.
#[test]
fn a_gripper_on_a_fixed_palm_holds_each_finger_like_a_clamp() {
    let th = 0.2f64;
    let finger_sections = || {
        let mut s = Section::uniform(0.06, EA, 0.01, 5);
        s.mass_per_length_kg_per_m = 0.1;
        s.chambers = vec![Chamber {
            gain_nm_per_pa: vec![2e-6],
            pressure_min_pa: -1e5,
            pressure_max_pa: 1e5,
        }];
        vec![s.clone(), s]
    };
    // finger roots at (±0.02, 0) on the palm, pointing along the palm's y
    let dir = [-th.sin(), th.cos()];
    let root = |x: f64| [x * th.cos(), x * th.sin()];
    let finger = |x: f64| RodSpec {
        sections: finger_sections(),
        start_m: root(x).to_vec(),
        direction: dir.to_vec(),
        start: softrod::structure::EndSupport::Free,
        end: softrod::structure::EndSupport::Free,
    };
    let joint = |rod| JointSpec::RodToBody {
        rod,
        end: RodEnd::Start,
        body: 0,
        point_m: Some(vec![if rod == 0 { -0.02 } else { 0.02 }, 0.0]),
        direction: Some(vec![0.0, 1.0]),
    };
    let spec = StructureSpec::new(
        vec![finger(-0.02), finger(0.02)],
        vec![RigidBodySpec {
            mass_kg: 0.0,
            position_m: vec![0.0, 0.0],
            orientation_rad: vec![th],
        }],
        vec![joint(0), joint(1), JointSpec::BodyToGround { body: 0 }],
    );
    let s = spec.build_planar().unwrap();
    // the fixed palm has no free coordinates; each finger root only its stretch
    assert!(s.body_free_coordinates(0).unwrap().is_empty());
    assert_eq!(s.n_free(), 2 * (1 + 10 * 4));
    let pressures = [vec![6e4, 3e4], vec![-6e4, -2e4]];
    let loads = StructureLoads {
        rods: pressures
            .iter()
            .map(|p| Loads {
                pressures_pa: p.clone(),
                ..Loads::default()
            })
            .collect(),
        ..StructureLoads::default()
    };
    let u = solve(&s, &loads);
    let q: Vec<f64> = s.configuration(&u).unwrap().data.into();
    for (rod, x) in [(0usize, -0.02), (1, 0.02)] {
        let mut rs = softrod::assembly::RobotSpec::new(finger_sections());
        rs.base.position_m = root(x).to_vec();
        rs.base.angle_rad = th + std::f64::consts::FRAC_PI_2;
        let robot = rs.build_planar().unwrap();
        let l = &loads.rods[rod];
        let eq = StaticSolver::default().solve(&robot, l, None).unwrap();
        assert!(eq.report.status.is_converged());
        let r = s.node_coordinates(rod, 0).unwrap().start;
        let d =
            eq.q.iter()
                .zip(&q[r..r + robot.n_q()])
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        println!(
            "gripper finger {rod}: tip {:?}, differs from the clamped robot by {d:.1e}",
            &eq.q.as_slice()[robot.n_q() - 4..robot.n_q() - 2]
        );
        assert!(d < 1e-10, "finger {rod}: {d}");
    }
}
