//! Finite-difference tests of the map `q = φ(u)`: `T(u)` through every
//! scatter, and the second derivative `Σ g_i ∂²φ_i/∂u²`.

use super::*;

/// A planar map with every rule: a clamp, free nodes, a free body pose
/// and a rigid end on it, a fixed block.
fn map() -> DofMap {
    DofMap::new(vec![
        BlockRule::Affine {
            offset: vec![0.1, 0.0, 0.0, 1.0],
            directions: vec![vec![0.0, 0.0, 0.0, 1.0]],
        },
        BlockRule::Free { len: 4 },
        BlockRule::PlanarRigidEnd {
            body_block: 4,
            attachment: PlanarAttachment {
                point_m: nalgebra::Vector2::new(0.1, -0.02),
                direction: nalgebra::Vector2::new(0.0, 1.0),
            },
        },
        BlockRule::Affine {
            offset: vec![1.0, 2.0, 3.0],
            directions: vec![],
        },
        BlockRule::Free { len: 3 },
    ])
    .unwrap()
}

fn u_at(m: &DofMap) -> Vec<f64> {
    (0..m.n_u())
        .map(|i| 0.3 * ((i as f64) * 1.7 + 0.2).sin())
        .collect()
}

#[test]
fn numbering_follows_the_blocks() {
    let m = map();
    assert_eq!(m.n_q(), 4 + 4 + 4 + 3 + 3);
    assert_eq!(m.n_u(), 9); // stretch, node, rigid-end stretch, (fixed), pose
    assert_eq!(m.free(2), Some(5..6));
    assert_eq!(m.free(4), Some(6..9));
    assert_eq!(m.coordinates(4), Some(15..18));
    assert!(!m.is_linear());
    assert_eq!(m.contiguous_free(4, 4), Some(1));
    assert_eq!(m.contiguous_free(0, 8), None);
    assert_eq!(m.contiguous_free(4, 8), None);
    assert_eq!(m.contiguous_free(16, 2), Some(7));
}

/// `T(u)` of expand, restrict, add_force and add_stiffness equals the
/// central-difference Jacobian of `φ`, and the geometric term equals the
/// difference of `T(u)ᵀ g` (step 1e-6; bounds 1e-9).
#[test]
fn jacobian_and_second_derivative_match_finite_differences() {
    check_derivatives(&map());
}

/// A spatial map: a full 3-D node and a spatial-cable node joined to one
/// free body pose `(x, ψ)`, a clamp, a free node.
fn spatial_map() -> DofMap {
    let d = [0.36, 0.48, 0.8];
    let a2 = [0.8, -0.6, 0.0];
    let a3 = [0.48, 0.64, -0.6]; // d × a2
    let at = |nd| {
        SpatialAttachment::new(
            nalgebra::Vector3::new(0.05, -0.02, 0.01),
            crate::structure::rigid::frame_of_columns([d, a2, a3]),
            nd,
        )
        .unwrap()
    };
    DofMap::new(vec![
        BlockRule::Affine {
            offset: vec![0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
            directions: vec![vec![0.0, 0.0, 0.0, 0.0, 0.0, 1.0]],
        },
        BlockRule::Free { len: 6 },
        BlockRule::SpatialRigidEnd {
            body_block: 4,
            attachment: at(12),
        },
        BlockRule::SpatialRigidEnd {
            body_block: 4,
            attachment: at(6),
        },
        BlockRule::Free { len: 6 },
    ])
    .unwrap()
}

/// The same checks for the spatial rigid ends: `∂φ/∂u` and `∂²φ/∂u²`
/// of both node kinds by central differences.
#[test]
fn spatial_rigid_ends_match_finite_differences() {
    let m = spatial_map();
    assert_eq!((m.n_q(), m.n_u()), (6 + 6 + 12 + 6 + 6, 1 + 6 + 1 + 1 + 6));
    assert_eq!(m.free(4), Some(9..15));
    check_derivatives(&m);
    // q back to u
    let u = u_at(&m);
    let q = m.configuration(&u).unwrap();
    let back = m.free_coordinates_of(q.as_slice()).unwrap();
    let worst = u
        .iter()
        .zip(&back)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-14, "free_coordinates_of: {worst:e}");
    // a body block of the wrong size is refused, naming the field
    let e = DofMap::new(vec![
        BlockRule::Free { len: 3 },
        BlockRule::SpatialRigidEnd {
            body_block: 0,
            attachment: SpatialAttachment::new(
                nalgebra::Vector3::zeros(),
                nalgebra::Matrix3::identity(),
                6,
            )
            .unwrap(),
        },
    ])
    .unwrap_err();
    assert_eq!(e.field(), Some("dof_map.blocks[1].body_block"));
}

fn check_derivatives(m: &DofMap) {
    let u = u_at(m);
    let (nu, nq) = (m.n_u(), m.n_q());
    let h = 1e-6;
    let mut t_fd = nalgebra::DMatrix::zeros(nq, nu);
    for j in 0..nu {
        let (mut up, mut um) = (u.clone(), u.clone());
        up[j] += h;
        um[j] -= h;
        let (qp, qm) = (m.configuration(&up).unwrap(), m.configuration(&um).unwrap());
        for i in 0..nq {
            t_fd[(i, j)] = (qp[i] - qm[i]) / (2.0 * h);
        }
    }
    // columns of T by expand
    let mut worst = 0.0f64;
    for j in 0..nu {
        let mut du = vec![0.0; nu];
        du[j] = 1.0;
        let mut dq = vec![0.0; nq];
        m.expand_into(&u, &du, &mut dq).unwrap();
        for i in 0..nq {
            worst = worst.max((dq[i] - t_fd[(i, j)]).abs());
        }
    }
    println!("dof map FD: T by expand {worst:.1e}");
    assert!(worst < 1e-9, "expand: {worst:e}");
    // Tᵀ g by restrict and by add_force over all coordinates
    let g: Vec<f64> = (0..nq).map(|i| ((i as f64) * 0.9).cos()).collect();
    let mut r1 = vec![0.0; nu];
    m.restrict_into(&u, &g, &mut r1).unwrap();
    let mut r2 = vec![0.0; nu];
    let all: Vec<usize> = (0..nq).collect();
    for chunk in all.chunks(MAX_DOFS) {
        let gs: Vec<f64> = chunk.iter().map(|&i| g[i]).collect();
        m.add_force(&u, chunk, &gs, 1.0, &mut r2).unwrap();
    }
    let tg = t_fd.transpose() * nalgebra::DVector::from_vec(g.clone());
    for j in 0..nu {
        assert!((r1[j] - tg[j]).abs() < 1e-9, "restrict {j}");
        assert!((r2[j] - tg[j]).abs() < 1e-9, "add_force {j}");
    }
    // Tᵀ H T by add_stiffness on a random symmetric H over at most
    // MAX_DOFS coordinates (ending 6 before the last: the rigid ends)
    let sel: Vec<usize> = if nq <= MAX_DOFS {
        all.clone()
    } else {
        (nq - 6 - MAX_DOFS..nq - 6).collect()
    };
    let ns = sel.len();
    let hm = nalgebra::DMatrix::from_fn(ns, ns, |i, j| ((i * 7 + j * 7 + i * j) as f64).sin());
    let mut k = nalgebra::DMatrix::zeros(nu, nu);
    let hv: Vec<f64> = (0..ns * ns).map(|x| hm[(x / ns, x % ns)]).collect();
    m.add_stiffness(&u, &sel, &hv, 1.0, &mut k).unwrap();
    let t_sel = nalgebra::DMatrix::from_fn(ns, nu, |i, j| t_fd[(sel[i], j)]);
    let expect = t_sel.transpose() * &hm * &t_sel;
    assert!((k - expect).amax() < 1e-8);
    // geometric term: d(Tᵀ g)/du at fixed g
    let mut kg = nalgebra::DMatrix::zeros(nu, nu);
    m.add_geometric_stiffness(&u, &g, &mut kg).unwrap();
    let mut worst = 0.0f64;
    for j in 0..nu {
        let (mut up, mut um) = (u.clone(), u.clone());
        up[j] += h;
        um[j] -= h;
        let (mut rp, mut rm) = (vec![0.0; nu], vec![0.0; nu]);
        m.restrict_into(&up, &g, &mut rp).unwrap();
        m.restrict_into(&um, &g, &mut rm).unwrap();
        for i in 0..nu {
            worst = worst.max(((rp[i] - rm[i]) / (2.0 * h) - kg[(i, j)]).abs());
        }
    }
    println!("dof map FD: geometric stiffness {worst:.1e}");
    assert!(worst < 1e-9, "geometric stiffness: {worst:e}");
    assert!(kg.amax() > 0.1, "the test must exercise the term");
}

#[test]
fn bad_rules_are_refused_with_their_field() {
    let e = DofMap::new(vec![BlockRule::PlanarRigidEnd {
        body_block: 3,
        attachment: PlanarAttachment {
            point_m: nalgebra::Vector2::zeros(),
            direction: nalgebra::Vector2::x(),
        },
    }])
    .unwrap_err();
    assert_eq!(e.field(), Some("dof_map.blocks[0].body_block"));
    let e = DofMap::new(vec![
        BlockRule::Free { len: 4 },
        BlockRule::PlanarRigidEnd {
            body_block: 0,
            attachment: PlanarAttachment {
                point_m: nalgebra::Vector2::zeros(),
                direction: nalgebra::Vector2::x(),
            },
        },
    ])
    .unwrap_err();
    assert_eq!(e.field(), Some("dof_map.blocks[1].body_block"));
    let e = DofMap::new(vec![BlockRule::Affine {
        offset: vec![0.0; 4],
        directions: vec![vec![0.0; 3]],
    }])
    .unwrap_err();
    assert_eq!(e.field(), Some("dof_map.blocks[0].directions[0]"));
    assert!(DofMap::new(vec![BlockRule::Free { len: 0 }]).is_err());
}
