//! Tests of the banded matrix and its factorizations.

use super::*;

fn lcg(seed: &mut u64) -> f64 {
    *seed = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    ((*seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
}

#[test]
fn solves_random_banded_systems_to_small_residual() {
    let mut seed = 7u64;
    for &(n, kl, ku) in &[
        (1, 0, 0),
        (5, 1, 1),
        (40, 7, 7),
        (84, 7, 7),
        (403, 7, 7),
        (50, 3, 5),
        (30, 11, 11),
    ] {
        let mut a = BandedMatrix::zeros(n, kl, ku);
        for i in 0..n {
            for j in i.saturating_sub(kl)..(i + ku + 1).min(n) {
                // indefinite, with small diagonals: pivoting is needed
                a.add(i, j, lcg(&mut seed) + if i == j { 0.01 } else { 0.0 });
            }
        }
        let x_true: Vec<f64> = (0..n).map(|_| lcg(&mut seed)).collect();
        let b = a.mul_vec(&x_true).unwrap();
        let mut x = b.clone();
        let lu = a.clone().factor("test").unwrap();
        lu.solve_in_place(&mut x).unwrap();
        let r = a.mul_vec(&x).unwrap();
        let res = r
            .iter()
            .zip(&b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max);
        let bn = b.iter().map(|v| v.abs()).fold(0.0, f64::max);
        assert!(res <= 1e-10 * bn.max(1.0), "n={n}: residual {res}");
    }
}

#[test]
fn matches_a_dense_solve() {
    let mut seed = 11u64;
    let n = 24;
    let mut a = BandedMatrix::zeros(n, 3, 3);
    let mut dense = nalgebra::DMatrix::<f64>::zeros(n, n);
    for i in 0..n {
        for j in i.saturating_sub(3)..(i + 4).min(n) {
            let v = lcg(&mut seed);
            a.add(i, j, v);
            dense[(i, j)] = v;
        }
    }
    let b: Vec<f64> = (0..n).map(|_| lcg(&mut seed)).collect();
    let xd = dense
        .lu()
        .solve(&nalgebra::DVector::from_vec(b.clone()))
        .unwrap();
    let mut x = b;
    a.factor("test").unwrap().solve_in_place(&mut x).unwrap();
    for i in 0..n {
        assert!((x[i] - xd[i]).abs() < 1e-9 * (1.0 + xd[i].abs()));
    }
}

#[test]
fn scaled_factorization_solves_badly_scaled_systems() {
    // rows scaled over 12 decades: A = S B S with B well conditioned
    let mut seed = 3u64;
    let n = 60;
    let mut a = BandedMatrix::zeros(n, 3, 3);
    let sc: Vec<f64> = (0..n).map(|i| 10f64.powi((i % 4) as i32 * 4 - 6)).collect();
    for i in 0..n {
        for j in i.saturating_sub(3)..(i + 4).min(n) {
            let b = if i == j { 4.0 } else { 0.3 * lcg(&mut seed) };
            a.add(i, j, sc[i] * b * sc[j]);
        }
    }
    let x_true: Vec<f64> = (0..n).map(|i| lcg(&mut seed) / sc[i]).collect();
    let b = a.mul_vec(&x_true).unwrap();
    let mut x = b.clone();
    a.clone()
        .factor_scaled(0.0, "test")
        .unwrap()
        .solve_in_place(&mut x)
        .unwrap();
    for i in 0..n {
        assert!(
            (x[i] - x_true[i]).abs() <= 1e-10 * x_true[i].abs().max(1e-300) + 1e-12 / sc[i],
            "{i}"
        );
    }
}

#[test]
fn singular_matrix_is_reported_with_its_pivot() {
    let mut a = BandedMatrix::zeros(3, 1, 1);
    a.add(0, 0, 1.0);
    a.add(1, 1, 1.0);
    match a.factor("K") {
        Err(Error::Singular { index, context, .. }) => {
            assert_eq!(index, 2);
            assert_eq!(context, "K");
        }
        other => panic!("expected Singular, got {other:?}"),
    }
    let mut nan = BandedMatrix::zeros(2, 1, 1);
    nan.add(0, 0, f64::NAN);
    assert!(matches!(nan.factor("K"), Err(Error::NonFinite { .. })));
}

/// A random symmetric band matrix: `B + Bᵀ` plus `diag` on the
/// diagonal (positive definite for a large enough `diag`).
fn random_symmetric(n: usize, kb: usize, diag: f64, seed: &mut u64) -> BandedMatrix {
    let mut a = BandedMatrix::zeros(n, kb, kb);
    for i in 0..n {
        for j in i.saturating_sub(kb)..i {
            let v = lcg(seed);
            a.add(i, j, v);
            a.add(j, i, v);
        }
        a.add(i, i, diag + lcg(seed));
    }
    a
}

fn dense_of(a: &BandedMatrix) -> nalgebra::DMatrix<f64> {
    let n = a.n();
    nalgebra::DMatrix::from_fn(n, n, |i, j| a.get(i, j))
}

fn max_rel_diff(x: &[f64], y: &[f64]) -> f64 {
    let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
    x.iter()
        .zip(y)
        .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()))
        / scale
}

#[test]
fn ldlt_matches_lu_and_dense_solves_on_spd_and_indefinite_bands() {
    let mut seed = 21u64;
    for &(n, kb, diag, spd) in &[
        (1, 0, 3.0, true),
        (6, 1, 3.0, true),
        (84, 7, 16.0, true),
        (403, 7, 16.0, true),
        (50, 3, 0.3, false),
        (84, 7, 0.5, false),
        (30, 11, 0.0, false),
    ] {
        let a = random_symmetric(n, kb, diag, &mut seed);
        assert!(a.is_symmetric());
        let dense = dense_of(&a);
        let eig = dense.clone().symmetric_eigenvalues();
        let neg = eig.iter().filter(|v| **v < 0.0).count();
        assert_eq!(
            neg == 0,
            spd,
            "n={n}: test matrix has {neg} negative eigenvalues"
        );
        let b: Vec<f64> = (0..n).map(|_| lcg(&mut seed)).collect();
        let xd: Vec<f64> = dense
            .clone()
            .lu()
            .solve(&nalgebra::DVector::from_vec(b.clone()))
            .unwrap()
            .iter()
            .copied()
            .collect();
        let ldlt = a.factor_ldlt("test").unwrap();
        assert!(ldlt.is_ldlt());
        // Sylvester: the pivots' signs are the eigenvalues' signs
        assert_eq!(ldlt.negative_pivots(), neg, "n={n}");
        let mut x = b.clone();
        ldlt.solve_in_place(&mut x).unwrap();
        assert!(max_rel_diff(&x, &xd) < 1e-9, "n={n}: ldlt vs dense");
        let mut xl = b.clone();
        a.clone()
            .factor("t")
            .unwrap()
            .solve_in_place(&mut xl)
            .unwrap();
        assert!(max_rel_diff(&x, &xl) < 1e-9, "n={n}: ldlt vs lu");
        // the scaled factorization takes LDLᵀ exactly when positive definite
        let scaled = a.clone().factor_scaled(0.0, "test").unwrap();
        assert_eq!(scaled.is_ldlt(), spd, "n={n}");
        let mut xs = b.clone();
        scaled.solve_in_place(&mut xs).unwrap();
        assert!(max_rel_diff(&xs, &xd) < 1e-9, "n={n}: scaled vs dense");
        let by_ref = a.factor_scaled_symmetric(0.0, "test").unwrap();
        assert_eq!(by_ref.is_ldlt(), spd);
    }
}

#[test]
fn shifted_scaled_factors_solve_the_shifted_system() {
    // (A + μ diag|a_ii|) x = b, for the LDLᵀ and the LU path alike
    let mut seed = 5u64;
    for diag in [16.0, 0.2] {
        let a = random_symmetric(40, 7, diag, &mut seed);
        let mu = 0.3;
        let mut shifted = a.clone();
        for i in 0..40 {
            shifted.add(i, i, mu * a.get(i, i).abs());
        }
        let b: Vec<f64> = (0..40).map(|_| lcg(&mut seed)).collect();
        let mut x = b.clone();
        a.clone()
            .factor_scaled(mu, "t")
            .unwrap()
            .solve_in_place(&mut x)
            .unwrap();
        let r = shifted.mul_vec(&x).unwrap();
        assert!(max_rel_diff(&r, &b) < 1e-10, "diag {diag}");
    }
}

#[test]
fn several_right_hand_sides_agree_with_one_at_a_time() {
    let mut seed = 9u64;
    let spd = random_symmetric(60, 7, 16.0, &mut seed);
    let mut general = BandedMatrix::zeros(60, 3, 5);
    for i in 0..60usize {
        for j in i.saturating_sub(3)..(i + 6).min(60) {
            general.add(i, j, lcg(&mut seed) + if i == j { 0.05 } else { 0.0 });
        }
    }
    let factors = [
        spd.factor_ldlt("t").unwrap(),
        spd.clone().factor_scaled(0.0, "t").unwrap(),
        general.clone().factor("t").unwrap(),
        general.clone().factor_scaled(0.0, "t").unwrap(),
    ];
    for f in &factors {
        for r in [1usize, 3, 10] {
            let cols: Vec<Vec<f64>> = (0..r)
                .map(|_| (0..60).map(|_| lcg(&mut seed)).collect())
                .collect();
            let mut b = vec![0.0; 60 * r];
            for i in 0..60 {
                for c in 0..r {
                    b[i * r + c] = cols[c][i];
                }
            }
            f.solve_many_in_place(&mut b, r).unwrap();
            for (c, col) in cols.iter().enumerate() {
                let mut x = col.clone();
                f.solve_in_place(&mut x).unwrap();
                let xm: Vec<f64> = (0..60).map(|i| b[i * r + c]).collect();
                assert!(max_rel_diff(&xm, &x) < 1e-13, "r {r} column {c}");
            }
        }
        assert!(matches!(
            f.solve_many_in_place(&mut [0.0; 7], 2),
            Err(Error::DimensionMismatch { .. })
        ));
    }
}

#[test]
fn ldlt_reports_a_singular_matrix_with_its_pivot() {
    // [[1, 1], [1, 1]] ⊕ [2]: the second pivot vanishes
    let mut a = BandedMatrix::zeros(3, 1, 1);
    for (i, j, v) in [
        (0, 0, 1.0),
        (0, 1, 1.0),
        (1, 0, 1.0),
        (1, 1, 1.0),
        (2, 2, 2.0),
    ] {
        a.add(i, j, v);
    }
    match a.factor_ldlt("K") {
        Err(Error::Singular {
            index,
            context,
            pivot,
            scale,
        }) => {
            assert_eq!((index, context.as_str()), (1, "K"));
            assert!(pivot.abs() <= 1e-15 && scale == 1.0);
        }
        other => panic!("expected Singular, got {other:?}"),
    }
    // a zero leading pivot of an invertible matrix: LDLᵀ cannot, LU can
    let mut b = BandedMatrix::zeros(2, 1, 1);
    for (i, j, v) in [(0, 1, 1.0), (1, 0, 1.0), (1, 1, 1.0)] {
        b.add(i, j, v);
    }
    assert!(matches!(
        b.factor_ldlt("K"),
        Err(Error::Singular { index: 0, .. })
    ));
    let f = b.clone().factor_scaled(0.0, "K").unwrap();
    assert!(!f.is_ldlt());
    let mut x = vec![1.0, 2.0];
    f.solve_in_place(&mut x).unwrap();
    assert!((x[0] - 1.0).abs() < 1e-15 && (x[1] - 1.0).abs() < 1e-15);
    // the scaled path still reports a truly singular matrix (from the LU)
    assert!(matches!(
        a.factor_scaled(0.0, "K"),
        Err(Error::Singular { .. })
    ));
    let mut nan = BandedMatrix::zeros(2, 1, 1);
    nan.add(1, 0, f64::NAN);
    assert!(matches!(nan.factor_ldlt("K"), Err(Error::NonFinite { .. })));
    assert!(matches!(
        nan.factor_scaled(0.0, "K"),
        Err(Error::NonFinite { .. })
    ));
}

#[test]
fn symmetry_is_detected_exactly() {
    let mut seed = 1u64;
    let mut a = random_symmetric(20, 3, 4.0, &mut seed);
    assert!(a.is_symmetric());
    a.add(7, 5, 1e-300);
    assert!(a.is_symmetric()); // below the entry's ulp: unchanged
    a.add(7, 5, 1e-3);
    assert!(!a.is_symmetric());
    assert!(!BandedMatrix::zeros(4, 1, 2).is_symmetric());
}

#[test]
fn mul_vec_into_matches_the_dense_product() {
    let mut seed = 4u64;
    let mut a = BandedMatrix::zeros(30, 2, 4);
    for i in 0..30usize {
        for j in i.saturating_sub(2)..(i + 5).min(30) {
            a.add(i, j, lcg(&mut seed));
        }
    }
    let x: Vec<f64> = (0..30).map(|_| lcg(&mut seed)).collect();
    let yd = dense_of(&a) * nalgebra::DVector::from_vec(x.clone());
    let mut y = vec![0.0; 30];
    a.mul_vec_into(&x, &mut y).unwrap();
    for i in 0..30 {
        assert!((y[i] - yd[i]).abs() < 1e-14);
    }
    assert!(a.mul_vec_into(&x, &mut [0.0; 3]).is_err());
}
