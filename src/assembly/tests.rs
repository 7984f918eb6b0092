//! Unit tests of the robot's assembly: tangent against finite differences,
//! the pressure Jacobian, the load Gram matrix, fused and cached kernels.

use super::*;
use crate::element::PlanarCable;

fn robot(n: usize) -> Robot<PlanarCable> {
    let mut s1 = Section::uniform(0.12, 300.0, 0.025, n);
    s1.mass_per_length_kg_per_m = 0.15;
    s1.chambers = vec![Chamber {
        gain_nm_per_pa: vec![3e-6],
        pressure_min_pa: 0.0,
        pressure_max_pa: 1e5,
    }];
    let mut s2 = s1.clone();
    s2.ei_nm2 = 0.02;
    RobotSpec::new(vec![s1, s2]).build_planar().unwrap()
}

fn perturbed(r: &Robot<PlanarCable>, seed: u64) -> Vec<f64> {
    let mut q: Vec<f64> = r.reference_configuration().data.into();
    let mut rng = crate::rng::Lcg::new(seed);
    q[2] *= 1.003; // a stretched base
    for v in q.iter_mut().skip(4) {
        *v += 0.02 * rng.centered();
    }
    q
}

/// The assembled tangent equals the central-difference Jacobian of
/// `−Q` along every free coordinate (step 1e-7), to 1e-6 of its largest entry.
fn assert_tangent_is_the_fd_jacobian(
    r: &Robot<PlanarCable>,
    q: &[f64],
    dead: &[f64],
    loads: &Loads,
) {
    let mut k = BandedMatrix::zeros(1, 0, 0);
    r.tangent_into(q, loads, &mut k).unwrap();
    let scale = k.max_abs();
    let h = 1e-7;
    for j in 0..r.n_free() {
        let mut du = vec![0.0; r.n_free()];
        du[j] = h;
        let dq = r.expand_step(&du).unwrap();
        let qp: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a + b).collect();
        let qm: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a - b).collect();
        let rp = r.residual(&qp, dead, loads).unwrap();
        let rm = r.residual(&qm, dead, loads).unwrap();
        for i in 0..r.n_free() {
            let fd = -(rp[i] - rm[i]) / (2.0 * h);
            assert!(
                (fd - k.get(i, j)).abs() < 1e-6 * scale,
                "({i},{j}) {fd} vs {}",
                k.get(i, j)
            );
        }
    }
}

#[test]
fn full_clamp_has_no_free_base_coordinate_and_a_consistent_tangent() {
    let mut spec = robot(2).spec().clone();
    spec.base.clamp = Clamp::Full;
    let r = spec.build_planar().unwrap();
    assert_eq!(r.n_base_free(), 0);
    assert_eq!(r.n_free(), r.n_q() - 4);
    let loads = Loads {
        pressures_pa: vec![3e4, 1e4],
        ..Loads::default()
    };
    let dead = r.dead_force(&loads).unwrap();
    assert_tangent_is_the_fd_jacobian(&r, &perturbed(&r, 9), dead.as_slice(), &loads);
}

#[test]
fn tangent_is_the_finite_difference_jacobian_of_the_residual() {
    let r = robot(3);
    let loads = Loads {
        pressures_pa: vec![4e4, 2e4],
        node_moments: vec![crate::loads::NodeMoment {
            node: 4,
            moment_nm: vec![0.01],
        }],
        ..Loads::default()
    };
    let dead = r.dead_force(&loads).unwrap();
    assert_tangent_is_the_fd_jacobian(&r, &perturbed(&r, 3), dead.as_slice(), &loads);
}

#[test]
fn pressure_jacobian_matches_finite_differences() {
    let r = robot(2);
    let q = perturbed(&r, 5);
    let jac = r.pressure_jacobian(&q).unwrap();
    let base = Loads {
        pressures_pa: vec![1e4, 1e4],
        ..Loads::default()
    };
    let dead = r.dead_force(&base).unwrap();
    for c in 0..2 {
        let mut lp = base.clone();
        let mut lm = base.clone();
        lp.pressures_pa[c] += 100.0;
        lm.pressures_pa[c] -= 100.0;
        let rp = r.residual(&q, dead.as_slice(), &lp).unwrap();
        let rm = r.residual(&q, dead.as_slice(), &lm).unwrap();
        for i in 0..r.n_free() {
            let fd = (rp[i] - rm[i]) / 200.0;
            assert!((fd - jac[(i, c)]).abs() < 1e-9, "{i} {c}");
        }
    }
}

#[test]
fn gram_integrates_products_of_fields() {
    // F describing w = (1, 2) uniform: F_i = [1, 2, 0, 0]; q = straight line
    // r = (s, 0); then q·J F = ∫ r·w ds = ∫ s ds = L²/2.
    let r = robot(4);
    let n = r.n_nodes();
    let f: Vec<f64> = (0..n).flat_map(|_| [1.0, 2.0, 0.0, 0.0]).collect();
    let q = r.reference_configuration();
    let jf = r.load_gram().mul_vec(&f).unwrap();
    let work: f64 = q.iter().zip(&jf).map(|(a, b)| a * b).sum();
    let l = r.length();
    assert!((work - l * l / 2.0).abs() < 1e-14);
    // total force of a uniform load = w L in each component
    let fx: f64 = (0..n).map(|i| jf[4 * i]).sum();
    let fy: f64 = (0..n).map(|i| jf[4 * i + 1]).sum();
    assert!((fx - l).abs() < 1e-14 && (fy - 2.0 * l).abs() < 1e-14);
}

#[test]
fn self_weight_sums_to_the_weight() {
    let r = robot(5);
    let g = r.gravity_force();
    let fy: f64 = (0..r.n_nodes()).map(|i| g[4 * i + 1]).sum();
    assert!((fy - (-9.81 * 0.15 * 0.24)).abs() < 1e-14);
}

#[test]
fn locate_finds_the_element() {
    let r = robot(2);
    assert_eq!(r.locate("s", 0.0).unwrap(), (0, 0.0));
    let (e, xi) = r.locate("s", 0.24).unwrap();
    assert_eq!(e, 3);
    assert!((xi - 1.0).abs() < 1e-12);
    let (e, xi) = r.locate("s", 0.09).unwrap();
    assert_eq!(e, 1);
    assert!((xi - 0.5).abs() < 1e-12);
    assert!(r.locate("s", 0.3).is_err());
}

#[test]
fn fused_and_cached_kernels_equal_the_plain_ones() {
    let r = robot(3);
    let loads = Loads {
        pressures_pa: vec![4e4, 2e4],
        node_moments: vec![crate::loads::NodeMoment {
            node: 4,
            moment_nm: vec![0.01],
        }],
        ..Loads::default()
    };
    let dead = r.dead_force(&loads).unwrap();
    let q = perturbed(&r, 11);
    // residual and tangent in one pass: bit for bit the separate ones
    let (mut r1, mut r2) = (vec![0.0; r.n_free()], vec![0.0; r.n_free()]);
    let mut k1 = BandedMatrix::zeros(1, 0, 0);
    let mut k2 = BandedMatrix::zeros(1, 0, 0);
    r.residual_into(&q, dead.as_slice(), &loads, &mut r1)
        .unwrap();
    r.tangent_into(&q, &loads, &mut k1).unwrap();
    r.residual_and_tangent_into(&q, dead.as_slice(), &loads, &mut r2, &mut k2)
        .unwrap();
    assert_eq!(r1, r2);
    assert_eq!(k1, k2);
    assert!(k1.is_symmetric());
    // the element-wise Gram product against the banded one
    let f: Vec<f64> = (0..r.n_q()).map(|i| (i as f64 * 0.37).sin()).collect();
    let a = r.apply_load_gram(&f).unwrap();
    let b = r.load_gram().mul_vec(&f).unwrap();
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= 1e-15 * (1.0 + y.abs()));
    }
    // the potential change from cached energies: the same number
    let to = perturbed(&r, 12);
    let mut u = vec![0.0; r.n_elements()];
    r.element_energies_into(&q, &mut u).unwrap();
    assert_eq!(
        r.potential_change(&q, &to, dead.as_slice(), &loads)
            .unwrap(),
        r.potential_change_from(&q, &u, &to, dead.as_slice(), &loads)
            .unwrap()
    );
    // the moment force: residual with and without the moments
    let mut m = vec![0.0; r.n_free()];
    r.moment_force_into(&q, &loads, &mut m).unwrap();
    let zero = vec![0.0; r.n_q()];
    let none = Loads {
        pressures_pa: vec![0.0, 0.0],
        ..Loads::default()
    };
    let (mut with, mut without) = (vec![0.0; r.n_free()], vec![0.0; r.n_free()]);
    r.residual_into(&q, &zero, &loads, &mut with).unwrap();
    r.residual_into(&q, &zero, &none, &mut without).unwrap();
    let scale = m.iter().fold(0.0f64, |x, v| x.max(v.abs()));
    assert!(scale > 0.0);
    for ((a, b), c) in m.iter().zip(&with).zip(&without) {
        assert!((a - (b - c)).abs() <= 1e-9 * scale);
    }
    // and the allocation-free maps equal the allocating ones
    let du: Vec<f64> = (0..r.n_free()).map(|i| i as f64).collect();
    let mut dq = vec![0.0; r.n_q()];
    r.expand_step_into(&du, &mut dq).unwrap();
    assert_eq!(dq, r.expand_step(&du).unwrap().as_slice());
    let mut uu = vec![0.0; r.n_free()];
    r.restrict_into(&f, &mut uu).unwrap();
    assert_eq!(uu, r.restrict(&f).unwrap().as_slice());
}

#[test]
fn tangent_on_the_connectivity_pattern_equals_the_band() {
    // both clamps, actuation and a concentrated moment (node blocks whose
    // (i, j) and (j, i) share one stored entry): every entry of the band is
    // in the pattern with the same value, and nothing else is stored
    for clamp in [Clamp::PositionAndDirection, Clamp::Full] {
        let mut spec = robot(3).spec().clone();
        spec.base.clamp = clamp;
        let r = spec.build_planar().unwrap();
        let loads = Loads {
            pressures_pa: vec![4e4, 2e4],
            node_moments: vec![crate::loads::NodeMoment {
                node: 4,
                moment_nm: vec![0.01],
            }],
            ..Loads::default()
        };
        let q = perturbed(&r, 5);
        let dead = r.dead_force(&loads).unwrap();
        let mut band = BandedMatrix::zeros(1, 0, 0);
        let mut rb = vec![0.0; r.n_free()];
        r.residual_and_tangent_into(&q, dead.as_slice(), &loads, &mut rb, &mut band)
            .unwrap();
        // a matrix on another pattern is put on the robot's
        let other = Arc::new(SymmetricPattern::from_elements(2, [[0, 1]]).unwrap());
        let mut k = crate::linsolve::SymmetricMatrix::zeros(other);
        let mut rs = vec![0.0; r.n_free()];
        r.residual_and_tangent_into(&q, dead.as_slice(), &loads, &mut rs, &mut k)
            .unwrap();
        assert!(Arc::ptr_eq(k.pattern(), r.tangent_pattern()));
        assert_eq!(rs, rb);
        assert_eq!(k.to_banded().unwrap(), band);
        let mut k2 = k.clone();
        k2.values_mut().fill(7.0);
        r.tangent_into(&q, &loads, &mut k2).unwrap();
        assert_eq!(k2, k);
        assert!(band.max_abs() > 0.0);
    }
}

#[test]
fn kept_reference_tangent_equals_the_assembled_one() {
    // at the reference configuration the sparse tangent comes from the
    // robot's kept element tangent (the band matrix is always assembled):
    // the same entries, with and without load terms, for both clamps,
    // before and after the cache is filled, and on a clone of the robot
    for clamp in [Clamp::PositionAndDirection, Clamp::Full] {
        let mut spec = robot(3).spec().clone();
        spec.base.clamp = clamp;
        let r = spec.build_planar().unwrap();
        let q: Vec<f64> = r.reference_configuration().data.into();
        let none = Loads {
            pressures_pa: vec![0.0, 0.0],
            ..Loads::default()
        };
        let moment = Loads {
            pressures_pa: vec![4e4, 2e4],
            node_moments: vec![crate::loads::NodeMoment {
                node: 4,
                moment_nm: vec![0.01],
            }],
            ..Loads::default()
        };
        let copy = r.clone();
        for (pass, loads) in [none, moment.clone(), moment].iter().enumerate() {
            let robot = if pass == 2 { &copy } else { &r };
            let mut band = BandedMatrix::zeros(1, 0, 0);
            robot.tangent_into(&q, loads, &mut band).unwrap();
            let mut k = crate::linsolve::SymmetricMatrix::zeros(r.tangent_pattern().clone());
            k.values_mut().fill(3.0);
            robot.tangent_into(&q, loads, &mut k).unwrap();
            assert_eq!(k.to_banded().unwrap(), band, "pass {pass}");
            assert!(r.reference_element_tangent(&q).is_some());
            // another configuration is assembled, not taken from the cache
            let mut q2 = q.clone();
            q2[9] += 1e-3;
            assert!(r.reference_element_tangent(&q2).is_none());
            robot.tangent_into(&q2, loads, &mut band).unwrap();
            robot.tangent_into(&q2, loads, &mut k).unwrap();
            assert_eq!(k.to_banded().unwrap(), band, "pass {pass}");
        }
    }
}

#[test]
fn kept_coarse_robot_equals_a_fresh_one() {
    let fine = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 80)])
        .build_planar()
        .unwrap();
    let (a, _) = fine.coarsened(&Loads::default()).unwrap().unwrap();
    let (b, _) = fine.clone().coarsened(&Loads::default()).unwrap().unwrap();
    let fresh = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 16)])
        .build_planar()
        .unwrap();
    assert!(fine.cache.coarse.get().is_some());
    for c in [&a, &b] {
        assert_eq!(c.spec(), fresh.spec());
        assert_eq!(c.reference_configuration(), fresh.reference_configuration());
    }
}

#[test]
fn kept_unactuated_start_equals_the_arcs_of_no_pressure() {
    use crate::structure::{RestCurvatureProfile, SolverHints, Stepping};
    let mut curved = Section::uniform(0.12, 300.0, 0.025, 6);
    curved.rest_curvature_profile = Some(RestCurvatureProfile {
        s_m: vec![0.0, 0.12],
        kappa_per_m: vec![2.0, -5.0],
    });
    let robots = [
        crate::scene::Scene::two_section().robot().unwrap(),
        RobotSpec::new(vec![curved, Section::uniform(0.1, 300.0, 0.02, 4)])
            .build_planar()
            .unwrap(),
    ];
    for robot in robots {
        let fresh = |p: &[f64]| {
            Stepping::free_coordinates_of(&robot, robot.arc_configuration(p).as_slice()).unwrap()
        };
        let zeros = vec![0.0; robot.n_pressures()];
        let mut minus = zeros.clone();
        minus.iter_mut().for_each(|p| *p = -0.0);
        for p in [zeros.clone(), minus] {
            let loads = Loads {
                pressures_pa: p.clone(),
                ..Loads::default()
            };
            // twice: formed, then kept; bit for bit the arcs computed afresh
            for _ in 0..2 {
                let u = SolverHints::start_free_coordinates(&robot, &loads).unwrap();
                assert_eq!(u, fresh(&p));
                assert_eq!(u, fresh(&[]));
            }
        }
        assert!(robot.cache.unactuated_start.get().is_some());
        // a pressure: its own arcs, not the kept start
        let mut p = zeros;
        let Some(p0) = p.first_mut() else { continue };
        *p0 = 2e4;
        let loads = Loads {
            pressures_pa: p.clone(),
            ..Loads::default()
        };
        let u = SolverHints::start_free_coordinates(&robot, &loads).unwrap();
        assert_eq!(u, fresh(&p));
        assert_ne!(Some(&u), robot.unactuated_start());
    }
}
