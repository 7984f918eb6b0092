use super::gap::{poly_eval, real_roots};
use super::*;
use crate::assembly::{RobotSpec, Section};
use crate::loads::{Loads, PointForce};

fn robot(n: usize) -> Robot<PlanarCable> {
    let mut spec = RobotSpec::new(vec![Section::uniform(0.3, 300.0, 0.02, n)]);
    spec.gravity_m_per_s2 = vec![0.0, 0.0];
    spec.build_planar().unwrap()
}

/// A bent configuration: a circular arc of curvature 4 /m plus a wobble.
fn bent(robot: &Robot<PlanarCable>) -> Vec<f64> {
    let mut q = Vec::new();
    for &s in robot.node_arc() {
        let k = 4.0;
        let th = k * s + 0.3 * (20.0 * s).sin() * s;
        let dth = k + 0.3 * (20.0 * s).sin() + 6.0 * s * (20.0 * s).cos();
        let _ = dth;
        // position by the arc of curvature k (the wobble only in the slope)
        q.extend([
            (k * s).sin() / k,
            (1.0 - (k * s).cos()) / k,
            th.cos(),
            th.sin(),
        ]);
    }
    q
}

#[test]
fn real_roots_of_a_quintic_with_close_roots() {
    // (x − 0.1)(x − 0.1001)(x − 0.5)(x − 0.9)(x + 2)
    let roots = [0.1, 0.1001, 0.5, 0.9, -2.0];
    let mut p = vec![1.0];
    for r in roots {
        let mut next = vec![0.0; p.len() + 1];
        for (k, c) in p.iter().enumerate() {
            next[k + 1] += c;
            next[k] -= r * c;
        }
        p = next;
    }
    let found = real_roots(&p, 0.0, 1.0);
    assert_eq!(found.len(), 4, "{found:?}");
    for (f, r) in found.iter().zip([0.1, 0.1001, 0.5, 0.9]) {
        assert!((f - r).abs() < 1e-12, "{f} vs {r}");
        assert!(poly_eval(&p, *f).abs() < 1e-14);
    }
    assert!(real_roots(&[0.0, 0.0], 0.0, 1.0).is_empty());
    assert!(real_roots(&[1.0, 0.0, 1.0], 0.0, 1.0).is_empty());
}

/// Obstacles beside the middle of [`bent`]'s arc (centre of curvature
/// (0, 0.25), radius 0.25; the point at s = 0.15 has the outward radial `u`
/// and the tangent `t`): a circle on the concave side, a capsule's flat
/// side, a capsule's end, a polygon's edge and a polygon's vertex on the
/// convex side, each 0.05 m from the centreline.
fn shapes() -> Vec<Obstacle> {
    let u = [0.6f64.sin(), -0.6f64.cos()];
    let t = [0.6f64.cos(), 0.6f64.sin()];
    let at = |d: f64, along: f64| {
        [
            (0.25 + d) * u[0] + along * t[0],
            0.25 + (0.25 + d) * u[1] + along * t[1],
        ]
    };
    vec![
        Obstacle::Circle {
            center_m: at(-0.07, 0.0),
            radius_m: 0.02,
        },
        Obstacle::Capsule {
            start_m: at(0.07, -0.03),
            end_m: at(0.07, 0.03),
            radius_m: 0.02,
        },
        Obstacle::Capsule {
            start_m: at(0.07, 0.0),
            end_m: at(0.12, 0.0),
            radius_m: 0.02,
        },
        Obstacle::Polygon {
            vertices_m: vec![
                at(0.05, -0.03),
                at(0.1, -0.03),
                at(0.1, 0.03),
                at(0.05, 0.03),
            ],
        },
        Obstacle::Polygon {
            vertices_m: vec![at(0.05, 0.0), at(0.1, -0.03), at(0.1, 0.03)],
        },
    ]
}

/// The gap of `obstacles.gaps(q)` continuing `g` (same obstacle, nearest in arc).
fn value_near(obstacles: &Obstacles, robot: &Robot<PlanarCable>, q: &[f64], g: &Gap) -> f64 {
    obstacles
        .gaps(robot, q)
        .unwrap()
        .into_iter()
        .filter(|x| x.obstacle == g.obstacle)
        .min_by(|a, b| (a.s_m - g.s_m).abs().total_cmp(&(b.s_m - g.s_m).abs()))
        .unwrap()
        .gap_m
}

#[test]
fn gap_gradient_and_hessian_match_finite_differences() {
    let robot = robot(6);
    let q = bent(&robot);
    for (k, shape) in shapes().into_iter().enumerate() {
        let obstacles = Obstacles::new(vec![shape], 0.004).unwrap();
        let gaps = obstacles.gaps(&robot, &q).unwrap();
        let g = gaps
            .iter()
            .min_by(|a, b| a.gap_m.total_cmp(&b.gap_m))
            .unwrap()
            .clone();
        assert!(g.stationary && g.xi > 0.0 && g.xi < 1.0, "shape {k}: {g:?}");
        let e = g.element;
        let h = 1e-6;
        let grad_at = |qq: &[f64]| -> nalgebra::SVector<f64, 8> {
            let gs = obstacles.gaps(&robot, qq).unwrap();
            gs.into_iter()
                .filter(|x| x.obstacle == g.obstacle)
                .min_by(|a, b| (a.s_m - g.s_m).abs().total_cmp(&(b.s_m - g.s_m).abs()))
                .unwrap()
                .gradient
        };
        for a in 0..8 {
            let i = 4 * e + a;
            let (mut qp, mut qm) = (q.clone(), q.clone());
            qp[i] += h;
            qm[i] -= h;
            let fd = (value_near(&obstacles, &robot, &qp, &g)
                - value_near(&obstacles, &robot, &qm, &g))
                / (2.0 * h);
            assert!(
                (fd - g.gradient[a]).abs() < 1e-7,
                "shape {k} gradient {a}: fd {fd} analytic {}",
                g.gradient[a]
            );
            // the Hessian's column a: central differences of the gradient
            let (gp, gm) = (grad_at(&qp), grad_at(&qm));
            let scale = g.hessian.iter().fold(1.0f64, |m, v| m.max(v.abs()));
            for b in 0..8 {
                let fd = (gp[b] - gm[b]) / (2.0 * h);
                let an = g.hessian[(b, a)];
                assert!(
                    (fd - an).abs() < 1e-5 * scale,
                    "shape {k} hessian ({b}, {a}): fd {fd} analytic {an}"
                );
            }
        }
    }
}

/// Central differences of the gap continuing `g` in the free coordinates
/// against [`ElementMap`]'s gradient and Hessian (the clamp's stretch
/// included), and of the element gradient against the element Hessian.
fn check_free_derivatives(robot: &Robot<PlanarCable>, obstacles: &Obstacles, q: &[f64], g: &Gap) {
    let map = super::solver::ElementMap::new(robot).unwrap();
    let n = robot.n_free();
    let grad = map.gradient(g, n);
    let mut hess = nalgebra::DMatrix::zeros(n, n);
    map.add_hessian(g, 1.0, &mut hess);
    let h = 1e-6;
    let at = |du: &[f64]| -> (f64, Vec<f64>) {
        let dq = robot.expand_step(du).unwrap();
        let qq: Vec<f64> = q.iter().zip(&dq).map(|(a, b)| a + b).collect();
        let x = obstacles
            .gaps(robot, &qq)
            .unwrap()
            .into_iter()
            .filter(|x| x.obstacle == g.obstacle)
            .min_by(|a, b| (a.s_m - g.s_m).abs().total_cmp(&(b.s_m - g.s_m).abs()))
            .unwrap();
        (x.gap_m, map.gradient(&x, n))
    };
    let scale = hess.iter().fold(1.0f64, |m, v| m.max(v.abs()));
    let mut touched = 0;
    for i in 0..n {
        let mut du = vec![0.0; n];
        du[i] = h;
        let (gp, dp) = at(&du);
        du[i] = -h;
        let (gm, dm) = at(&du);
        let fd = (gp - gm) / (2.0 * h);
        assert!(
            (fd - grad[i]).abs() < 1e-7,
            "u {i}: fd {fd} analytic {}",
            grad[i]
        );
        for j in 0..n {
            let fd = (dp[j] - dm[j]) / (2.0 * h);
            assert!(
                (fd - hess[(j, i)]).abs() < 1e-5 * scale,
                "hessian ({j}, {i}): fd {fd} analytic {}",
                hess[(j, i)]
            );
        }
        if grad[i] != 0.0 {
            touched += 1;
        }
    }
    assert!(touched >= 2, "{grad:?}");
}

#[test]
fn gap_derivatives_in_the_free_coordinates_match_finite_differences() {
    let robot = robot(6);
    let q = bent(&robot);
    // beside the first element (the clamp's stretch is a free coordinate)
    // and beyond the tip (a fixed material point, no sliding term)
    let tip = [q[q.len() - 4], q[q.len() - 3]];
    let (tx, ty) = (q[q.len() - 2], q[q.len() - 1]);
    for (o, stationary) in [
        (
            Obstacle::Circle {
                center_m: [0.02, -0.04],
                radius_m: 0.02,
            },
            true,
        ),
        (
            Obstacle::Circle {
                center_m: [
                    tip[0] + 0.05 * tx - 0.01 * ty,
                    tip[1] + 0.05 * ty + 0.01 * tx,
                ],
                radius_m: 0.02,
            },
            false,
        ),
    ] {
        let obstacles = Obstacles::new(vec![o], 0.003).unwrap();
        let gaps = obstacles.gaps(&robot, &q).unwrap();
        let g = gaps
            .iter()
            .min_by(|a, b| a.gap_m.total_cmp(&b.gap_m))
            .unwrap();
        assert_eq!(g.stationary, stationary, "{g:?}");
        assert!(
            stationary == (g.element == 0) && (stationary || g.xi == 1.0),
            "{g:?}"
        );
        check_free_derivatives(&robot, &obstacles, &q, g);
        // the element-0 gap moves with the clamp's stretch
        let map = super::solver::ElementMap::new(&robot).unwrap();
        assert_eq!(map.gradient(g, robot.n_free())[0] != 0.0, stationary);
    }
}

#[test]
fn the_tip_gap_is_a_fixed_material_point() {
    let robot = robot(4);
    let q = robot.reference_configuration();
    // a circle beyond the tip, on the axis: the tip is closest
    let obstacles = Obstacles::new(
        vec![Obstacle::Circle {
            center_m: [0.4, 0.0],
            radius_m: 0.05,
        }],
        0.0,
    )
    .unwrap();
    let gaps = obstacles.gaps(&robot, q.as_slice()).unwrap();
    assert_eq!(gaps.len(), 1);
    let g = &gaps[0];
    assert!(!g.stationary && g.xi == 1.0 && (g.gap_m - 0.05).abs() < 1e-15);
    // its gradient is the normal at the tip node's position, (−1, 0)
    assert!((g.gradient[4] + 1.0).abs() < 1e-15 && g.gradient[5].abs() < 1e-15);
}

#[test]
fn a_node_shared_by_two_elements_is_one_gap() {
    let robot = robot(4);
    let q = robot.reference_configuration();
    // above the node at s = 0.15
    let obstacles = Obstacles::new(
        vec![Obstacle::Circle {
            center_m: [0.15, 0.1],
            radius_m: 0.05,
        }],
        0.0,
    )
    .unwrap();
    let gaps = obstacles.gaps(&robot, q.as_slice()).unwrap();
    assert_eq!(gaps.len(), 1, "{gaps:?}");
    assert!((gaps[0].s_m - 0.15).abs() < 1e-12);
}

#[test]
fn bad_obstacles_are_refused_with_the_field() {
    let cases: Vec<(Obstacle, &str)> = vec![
        (
            Obstacle::Circle {
                center_m: [0.0, 1.0],
                radius_m: 0.0,
            },
            "obstacles[0].radius_m",
        ),
        (
            Obstacle::Circle {
                center_m: [f64::NAN, 1.0],
                radius_m: 0.1,
            },
            "obstacles[0].center_m",
        ),
        (
            Obstacle::Capsule {
                start_m: [0.0, 1.0],
                end_m: [f64::INFINITY, 1.0],
                radius_m: 0.1,
            },
            "obstacles[0].end_m",
        ),
        (
            Obstacle::Capsule {
                start_m: [0.0, 1.0],
                end_m: [1.0, 1.0],
                radius_m: -0.1,
            },
            "obstacles[0].radius_m",
        ),
        (
            Obstacle::Polygon {
                vertices_m: vec![[0.0, 1.0], [1.0, 1.0]],
            },
            "obstacles[0].vertices_m",
        ),
        // clockwise
        (
            Obstacle::Polygon {
                vertices_m: vec![[0.0, 1.0], [0.0, 2.0], [1.0, 2.0], [1.0, 1.0]],
            },
            "obstacles[0].vertices_m",
        ),
        // not convex (a dart)
        (
            Obstacle::Polygon {
                vertices_m: vec![[0.0, 1.0], [1.0, 1.0], [0.3, 1.3], [0.0, 2.0]],
            },
            "obstacles[0].vertices_m",
        ),
        // a pentagram: turns left at every vertex, winds twice
        (
            Obstacle::Polygon {
                vertices_m: (0..5)
                    .map(|k| {
                        let a = std::f64::consts::TAU * (2 * k) as f64 / 5.0;
                        [a.cos(), 3.0 + a.sin()]
                    })
                    .collect(),
            },
            "obstacles[0].vertices_m",
        ),
        (
            Obstacle::Polygon {
                vertices_m: vec![[0.0, 1.0], [1.0, 1.0], [1.0, f64::NAN]],
            },
            "obstacles[0].vertices_m[2]",
        ),
        // a collinear middle vertex
        (
            Obstacle::Polygon {
                vertices_m: vec![[0.0, 1.0], [0.5, 1.0], [1.0, 1.0], [0.0, 2.0]],
            },
            "obstacles[0].vertices_m[1]",
        ),
    ];
    for (o, field) in cases {
        let err = Obstacles::new(vec![o.clone()], 0.01).unwrap_err();
        assert_eq!(err.field(), Some(field), "{o:?}: {err}");
    }
    let err = Obstacles::new(vec![], -0.01).unwrap_err();
    assert_eq!(err.field(), Some("rod_radius_m"));
    // overlapping the base, the reference configuration
    let robot = robot(4);
    for (o, why) in [
        (
            Obstacle::Circle {
                center_m: [0.0, 0.0],
                radius_m: 0.01,
            },
            "base",
        ),
        (
            Obstacle::Polygon {
                vertices_m: vec![[0.1, -0.01], [0.2, -0.01], [0.2, 0.01], [0.1, 0.01]],
            },
            "reference configuration",
        ),
    ] {
        let obs = Obstacles::new(vec![o], 0.0).unwrap();
        let err = obs.check_robot(&robot).unwrap_err();
        assert_eq!(err.field(), Some("obstacles[0]"));
        assert!(err.to_string().contains(why), "{err}");
        let solve = ContactSolver::default().solve(&robot, &Loads::default(), &obs, None);
        assert!(solve.is_err());
    }
}

#[test]
fn an_impossible_start_is_reported_not_converged() {
    // a start deep inside a polygon that the linearized gaps cannot leave
    // within the SQP budget of one iteration: never "converged"
    let robot = robot(4);
    let obs = Obstacles::new(
        vec![Obstacle::Polygon {
            vertices_m: vec![[0.05, 0.05], [0.35, 0.05], [0.35, 0.3], [0.05, 0.3]],
        }],
        0.0,
    )
    .unwrap();
    // the start: the rod bent up through the polygon
    let q = bent(&robot);
    let solver = ContactSolver::new(ContactSettings {
        max_iterations: 1,
        ..Default::default()
    })
    .unwrap();
    let loads = Loads {
        point_forces: vec![PointForce {
            s_m: 0.3,
            force_n: vec![0.0, 0.05],
        }],
        ..Loads::default()
    };
    let sol = solver.solve(&robot, &loads, &obs, Some(&q)).unwrap();
    assert!(!sol.is_converged(), "{}", sol.report);
    assert!(sol.report.min_gap_m < 0.0);
}

#[test]
fn a_tip_load_toward_a_polygon_ends_on_it_without_penetration() {
    let robot = robot(8);
    // a block below the rod's second half, its top face 2 cm below
    let obs = Obstacles::new(
        vec![Obstacle::Polygon {
            vertices_m: vec![[0.15, -0.1], [0.4, -0.1], [0.4, -0.02], [0.15, -0.02]],
        }],
        0.005,
    )
    .unwrap();
    let loads = Loads {
        point_forces: vec![PointForce {
            s_m: 0.3,
            force_n: vec![0.0, -0.2],
        }],
        ..Loads::default()
    };
    let sol = ContactSolver::default()
        .solve(&robot, &loads, &obs, None)
        .unwrap();
    assert!(sol.is_converged(), "{}", sol.report);
    assert!(sol.report.min_gap_m >= -1e-10);
    assert!(!sol.contacts.is_empty());
    // force balance in y: the contact forces carry what the clamp does not;
    // the equilibrium residual with the forces is at its tolerance
    assert!(sol.report.residual_norm_n <= sol.report.residual_tolerance_n * 10.0);
    for c in &sol.contacts {
        assert!(c.force_n > 0.0 && c.gap_m.abs() < 1e-10, "{c:?}");
    }
}
