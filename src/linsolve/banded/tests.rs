//! Tests of the banded matrix (storage, products, symmetry).

use super::*;
use crate::rng::Lcg;

fn random_symmetric(n: usize, kb: usize, diag: f64, rng: &mut Lcg) -> BandedMatrix {
    let mut a = BandedMatrix::zeros(n, kb, kb);
    for i in 0..n {
        for j in i.saturating_sub(kb)..i {
            let v = rng.centered();
            a.add(i, j, v);
            a.add(j, i, v);
        }
        a.add(i, i, diag + rng.centered());
    }
    a
}

fn dense_of(a: &BandedMatrix) -> nalgebra::DMatrix<f64> {
    let n = a.n();
    nalgebra::DMatrix::from_fn(n, n, |i, j| a.get(i, j))
}

#[test]
fn symmetry_is_detected_exactly() {
    let mut rng = Lcg::new(1);
    let mut a = random_symmetric(20, 3, 4.0, &mut rng);
    assert!(a.is_symmetric());
    a.add(7, 5, 1e-300);
    assert!(a.is_symmetric()); // below the entry's ulp: unchanged
    a.add(7, 5, 1e-3);
    assert!(!a.is_symmetric());
    assert!(!BandedMatrix::zeros(4, 1, 2).is_symmetric());
}

#[test]
fn mul_vec_into_matches_the_dense_product() {
    let mut rng = Lcg::new(4);
    let mut a = BandedMatrix::zeros(30, 2, 4);
    for i in 0..30usize {
        for j in i.saturating_sub(2)..(i + 5).min(30) {
            a.add(i, j, rng.centered());
        }
    }
    let x: Vec<f64> = (0..30).map(|_| rng.centered()).collect();
    let yd = dense_of(&a) * nalgebra::DVector::from_vec(x.clone());
    let mut y = vec![0.0; 30];
    a.mul_vec_into(&x, &mut y).unwrap();
    for i in 0..30 {
        assert!((y[i] - yd[i]).abs() < 1e-14);
    }
    assert!(a.mul_vec_into(&x, &mut [0.0; 3]).is_err());
}
