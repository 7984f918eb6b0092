//! Both solvers through the trait, in the style of faer's own tests:
//! residuals `|K x − b|` over seeded random symmetric positive definite and
//! indefinite matrices of several sizes, on a chain and on a pattern that
//! is not banded (two chains joined to one shared block), plus the
//! agreements (many right-hand sides = one at a time, refactor = fresh
//! factorization) and the typed failures.

use super::*;
use crate::linsolve::sparse::Ordering;
use crate::rng::Lcg;

/// A chain of `elements` elements coupling two nodes of `b` dofs each.
fn chain(elements: usize, b: usize) -> (usize, Vec<Vec<usize>>) {
    let els = (0..elements)
        .map(|e| (e * b..(e + 2) * b).collect())
        .collect();
    ((elements + 1) * b, els)
}

/// Two chains of `elements` elements each (nodes of `b` dofs) whose tips
/// are joined to one shared block of `s` dofs numbered first: the coupling
/// of the block with the far tips makes the pattern wide, not banded.
fn joined(elements: usize, b: usize, s: usize) -> (usize, Vec<Vec<usize>>) {
    let n_chain = (elements + 1) * b;
    let mut els = Vec::new();
    for c in 0..2 {
        let base = s + c * n_chain;
        for e in 0..elements {
            els.push((base + e * b..base + (e + 2) * b).collect());
        }
        // the tip node with the block
        let tip = base + elements * b;
        let mut joint: Vec<usize> = (tip..tip + b).collect();
        joint.extend(0..s);
        els.push(joint);
    }
    (s + 2 * n_chain, els)
}

/// Random element blocks: `Gᵀ G + 0.1 I` (positive definite sum) or a
/// random symmetric block plus `diag` on the diagonal (indefinite); then
/// the whole matrix scaled `S K S` with `s_i` over six decades.
fn random_matrix(
    n: usize,
    elements: &[Vec<usize>],
    spd: bool,
    diag: f64,
    rng: &mut Lcg,
) -> SymmetricMatrix {
    let p = Arc::new(SymmetricPattern::from_elements(n, elements).unwrap());
    let mut k = SymmetricMatrix::zeros(p);
    for (e, el) in elements.iter().enumerate() {
        let m = el.len();
        let g: Vec<f64> = (0..m * m).map(|_| rng.centered()).collect();
        let mut block = vec![0.0; m * m];
        for a in 0..m {
            for c in a..m {
                let v = if spd {
                    (0..m).map(|r| g[r * m + a] * g[r * m + c]).sum::<f64>()
                        + if a == c { 0.1 } else { 0.0 }
                } else {
                    g[a * m + c] + if a == c { diag } else { 0.0 }
                };
                block[a * m + c] = v;
                block[c * m + a] = v;
            }
        }
        k.add_element(e, &block).unwrap();
    }
    let s: Vec<f64> = (0..n).map(|i| 10f64.powi((i % 7) as i32 - 3)).collect();
    let pattern = k.pattern().clone();
    for j in 0..n {
        for idx in pattern.col_ptr()[j]..pattern.col_ptr()[j + 1] {
            let i = pattern.row_idx()[idx];
            k.values_mut()[idx] *= s[i] * s[j];
        }
    }
    k
}

fn dense(k: &SymmetricMatrix) -> nalgebra::DMatrix<f64> {
    nalgebra::DMatrix::from_fn(k.n(), k.n(), |i, j| k.get(i, j))
}

/// Componentwise backward error `max_i |K x − b|_i / (|K| |x| + |b|)_i`.
fn backward_error(k: &SymmetricMatrix, x: &[f64], b: &[f64]) -> f64 {
    let n = k.n();
    let mut r = vec![0.0; n];
    k.mul_vec_into(x, &mut r).unwrap();
    let mut den: Vec<f64> = b.iter().map(|v| v.abs()).collect();
    for (i, j, v) in k.iter_upper() {
        den[i] += v.abs() * x[j].abs();
        if i != j {
            den[j] += v.abs() * x[i].abs();
        }
    }
    (0..n)
        .map(|i| (r[i] - b[i]).abs() / den[i].max(f64::MIN_POSITIVE))
        .fold(0.0, f64::max)
}

/// A solver under test: its name and its `factor`, boxed.
type Factor =
    Box<dyn FnMut(&SymmetricMatrix, FactorOptions) -> Result<Box<dyn Solve>, LinsolveError>>;

/// The solvers under test, each analyzed for `p`.
fn solvers(p: &Arc<SymmetricPattern>) -> Vec<(&'static str, Factor)> {
    let mut out: Vec<(&'static str, Factor)> = Vec::new();
    for (name, settings) in [
        ("sparse ldlt amd", SparseSettings::default()),
        (
            "sparse llt amd",
            SparseSettings {
                cholesky: CholeskyKind::Llt,
                ..SparseSettings::default()
            },
        ),
        (
            "sparse ldlt natural",
            SparseSettings {
                ordering: Ordering::Natural,
                ..SparseSettings::default()
            },
        ),
    ] {
        let mut s = SparseSolver::with_settings(p, settings).unwrap();
        out.push((
            name,
            Box::new(move |k, o| s.factor(k, o).map(|f| Box::new(f) as Box<dyn Solve>)),
        ));
    }
    for kind in [SolverKind::Auto, SolverKind::Sparse, SolverKind::Band] {
        // (the band kind only where the pattern is a narrow band)
        let Ok(mut a) = AutoSolver::with_kind(p, kind) else {
            assert_eq!(kind, SolverKind::Band);
            continue;
        };
        let name = match kind {
            SolverKind::Auto => "auto",
            SolverKind::Sparse => "sparse kind",
            _ => "band kind",
        };
        out.push((
            name,
            Box::new(move |k, o| a.factor(k, o).map(|f| Box::new(f) as Box<dyn Solve>)),
        ));
    }
    out
}

/// [`Factorization`] without `Clone`, for boxing.
trait Solve {
    fn which(&self) -> FactorMethod;
    fn signs(&self) -> Option<Inertia>;
    fn solve(&self, b: &mut [f64]) -> Result<(), LinsolveError>;
    fn solve_cols(&self, b: &mut [f64], r: usize) -> Result<(), LinsolveError>;
}

impl<F: Factorization> Solve for F {
    fn which(&self) -> FactorMethod {
        Factorization::method(self)
    }
    fn signs(&self) -> Option<Inertia> {
        Factorization::inertia(self)
    }
    fn solve(&self, b: &mut [f64]) -> Result<(), LinsolveError> {
        self.solve_in_place(b)
    }
    fn solve_cols(&self, b: &mut [f64], r: usize) -> Result<(), LinsolveError> {
        self.solve_columns_in_place(b, r)
    }
}

/// The test patterns: chains of 4-dof nodes (the planar cable's layout)
/// and joined chains, several sizes.
fn patterns() -> Vec<(String, usize, Vec<Vec<usize>>)> {
    let mut out = Vec::new();
    for e in [1, 2, 10, 50, 300] {
        let (n, els) = chain(e, 4);
        out.push((format!("chain {e}"), n, els));
    }
    for e in [1, 5, 40] {
        let (n, els) = joined(e, 4, 6);
        out.push((format!("joined {e}"), n, els));
    }
    out
}

#[test]
fn residuals_are_small_for_random_spd_and_indefinite_matrices() {
    let mut rng = Lcg::new(17);
    for (name, n, els) in patterns() {
        for spd in [true, false] {
            let k = random_matrix(n, &els, spd, 0.3, &mut rng);
            let neg = if n <= 300 {
                let eig = dense(&k).symmetric_eigenvalues();
                let neg = eig.iter().filter(|v| **v < 0.0).count();
                assert_eq!(neg == 0, spd, "{name}: the test matrix's definiteness");
                Some(neg)
            } else {
                None
            };
            let b: Vec<f64> = (0..n).map(|_| rng.centered()).collect();
            for (solver, mut factor) in solvers(k.pattern()) {
                let f = factor(&k, FactorOptions::default()).unwrap();
                if spd {
                    assert_ne!(f.which(), FactorMethod::Lu, "{name} {solver}");
                    assert_eq!(f.signs().map(|i| i.negative), Some(0));
                } else {
                    assert_eq!(f.which(), FactorMethod::Lu, "{name} {solver}");
                    if let (Some(i), Some(neg)) = (f.signs(), neg) {
                        // Sylvester: the L D Lᵀ pivots' signs are the eigenvalues'
                        assert_eq!(i.negative, neg, "{name} {solver}");
                        assert_eq!(i.positive + i.negative, n);
                    }
                }
                let mut x = b.clone();
                f.solve(&mut x).unwrap();
                let be = backward_error(&k, &x, &b);
                assert!(
                    be < 1e-12,
                    "{name} spd={spd} {solver}: backward error {be:e}"
                );
            }
        }
    }
}

#[test]
fn the_inertia_is_found_on_simplicial_and_supernodal_factors() {
    // the supernodal path (blocked factors) is taken for wide fronts: a
    // joined structure with a large shared block
    let mut rng = Lcg::new(5);
    let mut seen = [false; 2];
    for (n, els) in [chain(40, 4), joined(10, 6, 150)] {
        for kind in [CholeskyKind::Ldlt, CholeskyKind::Llt] {
            let p = Arc::new(SymmetricPattern::from_elements(n, &els).unwrap());
            let settings = SparseSettings {
                cholesky: kind,
                ..SparseSettings::default()
            };
            let mut s = SparseSolver::with_settings(&p, settings).unwrap();
            seen[usize::from(s.is_supernodal())] = true;
            for spd in [true, false] {
                let k = random_matrix(n, &els, spd, 0.2, &mut rng);
                let eig = dense(&k).symmetric_eigenvalues();
                let neg = eig.iter().filter(|v| **v < 0.0).count();
                let f = s.factor(&k, FactorOptions::default()).unwrap();
                let i = Factorization::inertia(&f).unwrap();
                assert_eq!((i.positive, i.negative), (n - neg, neg), "n={n} {kind:?}");
                assert_eq!(f.is_positive_definite(), spd);
                // the solve of either layout, through the LU when indefinite
                let b: Vec<f64> = (0..n).map(|_| rng.centered()).collect();
                let mut x = b.clone();
                f.solve_in_place(&mut x).unwrap();
                let be = backward_error(&k, &x, &b);
                assert!(be < 1e-12, "n={n} {kind:?} spd={spd}: {be:e}");
            }
        }
    }
    assert_eq!(seen, [true, true], "both factor layouts are exercised");
}

#[test]
fn many_right_hand_sides_equal_one_at_a_time() {
    let mut rng = Lcg::new(9);
    for (name, n, els) in patterns().into_iter().skip(2) {
        for spd in [true, false] {
            let k = random_matrix(n, &els, spd, 0.3, &mut rng);
            for (solver, mut factor) in solvers(k.pattern()) {
                let f = factor(&k, FactorOptions::default()).unwrap();
                for r in [1usize, 3, 10] {
                    let b: Vec<f64> = (0..n * r).map(|_| rng.centered()).collect();
                    let mut x = b.clone();
                    f.solve_cols(&mut x, r).unwrap();
                    for c in 0..r {
                        let mut xc = b[c * n..(c + 1) * n].to_vec();
                        f.solve(&mut xc).unwrap();
                        let scale = xc.iter().fold(0.0f64, |m, v| m.max(v.abs()));
                        let diff = xc
                            .iter()
                            .zip(&x[c * n..(c + 1) * n])
                            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
                        assert!(
                            diff <= 1e-13 * scale,
                            "{name} spd={spd} {solver} r={r} column {c}: {diff:e}"
                        );
                    }
                }
                assert!(matches!(
                    f.solve_cols(&mut vec![0.0; 2 * n + 1], 2),
                    Err(LinsolveError::DimensionMismatch { .. })
                ));
                assert!(matches!(
                    f.solve(&mut vec![0.0; n + 1]),
                    Err(LinsolveError::DimensionMismatch { .. })
                ));
                f.solve_cols(&mut [], 0).unwrap();
            }
        }
    }
}

#[test]
fn a_refactorization_equals_a_fresh_one() {
    let mut rng = Lcg::new(23);
    for (name, n, els) in patterns() {
        let k1 = random_matrix(n, &els, true, 0.3, &mut rng);
        let k2 = random_matrix(n, &els, false, 0.3, &mut rng);
        let k3 = random_matrix(n, &els, true, 0.3, &mut rng);
        let b: Vec<f64> = (0..n).map(|_| rng.centered()).collect();
        let mut reused = SparseSolver::analyze(k1.pattern()).unwrap();
        for k in [&k1, &k2, &k3] {
            // the same pattern, another Arc: accepted
            let fresh_pattern = Arc::new((**k.pattern()).clone());
            let mut k_fresh = SymmetricMatrix::zeros(fresh_pattern.clone());
            k_fresh.values_mut().copy_from_slice(k.values());
            let mut fresh = SparseSolver::analyze(&fresh_pattern).unwrap();
            let (mut x, mut y) = (b.clone(), b.clone());
            reused
                .factor(k, FactorOptions::default())
                .unwrap()
                .solve_in_place(&mut x)
                .unwrap();
            fresh
                .factor(&k_fresh, FactorOptions::default())
                .unwrap()
                .solve_in_place(&mut y)
                .unwrap();
            assert_eq!(x, y, "{name}: sparse");
        }
    }
}

#[test]
fn the_shift_solves_the_shifted_system() {
    let mut rng = Lcg::new(3);
    let (n, els) = joined(6, 4, 6);
    for spd in [true, false] {
        let k = random_matrix(n, &els, spd, 0.3, &mut rng);
        let mu = 0.4;
        let mut shifted = k.clone();
        for j in 0..n {
            shifted.add(j, j, mu * k.get(j, j).abs()).unwrap();
        }
        let b: Vec<f64> = (0..n).map(|_| rng.centered()).collect();
        for (solver, mut factor) in solvers(k.pattern()) {
            let o = FactorOptions {
                shift: mu,
                ..FactorOptions::default()
            };
            let mut x = b.clone();
            factor(&k, o).unwrap().solve(&mut x).unwrap();
            let be = backward_error(&shifted, &x, &b);
            assert!(be < 1e-12, "spd={spd} {solver}: {be:e}");
        }
    }
}

#[test]
fn singular_and_bad_inputs_give_typed_errors_not_panics() {
    // [[1, 1], [1, 1]] coupled to a healthy chain: singular
    let (n, mut els) = chain(3, 1);
    els.push(vec![0, 1]);
    let p = Arc::new(SymmetricPattern::from_elements(n, &els).unwrap());
    let mut k = SymmetricMatrix::zeros(p.clone());
    k.add_element(3, &[1.0, 1.0, 1.0, 1.0]).unwrap();
    k.add(2, 2, 2.0).unwrap();
    k.add(3, 3, 2.0).unwrap();
    for (solver, mut factor) in solvers(&p) {
        match factor(&k, FactorOptions::default()) {
            Err(LinsolveError::Singular { index, .. }) => {
                assert!(index <= 1, "{solver}: index {index}")
            }
            Err(e) => panic!("{solver}: expected Singular, got {e:?}"),
            Ok(_) => panic!("{solver}: expected Singular, got factors"),
        }
        // positive definiteness required: the error names the pivot
        match factor(
            &k,
            FactorOptions {
                require_positive_definite: true,
                ..FactorOptions::default()
            },
        ) {
            Err(LinsolveError::NotPositiveDefinite { index, pivot }) => {
                assert!(
                    index <= 1 && pivot.abs() < 1e-12,
                    "{solver}: {index} {pivot}"
                )
            }
            other => panic!(
                "{solver}: expected NotPositiveDefinite, got {:?}",
                other.is_ok()
            ),
        }
        // a shift makes it solvable
        let f = factor(
            &k,
            FactorOptions {
                shift: 1e-3,
                ..FactorOptions::default()
            },
        )
        .unwrap();
        assert_eq!(f.signs().map(|i| i.negative), Some(0));
    }
    // an indefinite matrix when positive definiteness is required
    let mut ind = SymmetricMatrix::zeros(p.clone());
    for (j, v) in [(0, 2.0), (1, 2.0), (2, -1.0), (3, 2.0)] {
        ind.add(j, j, v).unwrap();
    }
    for (solver, mut factor) in solvers(&p) {
        let o = FactorOptions {
            require_positive_definite: true,
            ..FactorOptions::default()
        };
        match factor(&ind, o) {
            Err(LinsolveError::NotPositiveDefinite { index, pivot }) => {
                assert_eq!((index, pivot), (2, -1.0), "{solver}");
            }
            other => panic!(
                "{solver}: expected NotPositiveDefinite, got {:?}",
                other.is_ok()
            ),
        }
        let f = factor(&ind, FactorOptions::default()).unwrap();
        assert_eq!(
            f.signs(),
            Some(Inertia {
                positive: 3,
                negative: 1
            })
        );
        // an uncoupled zero row
        let mut zero = ind.clone();
        let slot = zero.pattern().diagonal_slots()[3];
        zero.values_mut()[slot] = 0.0;
        assert!(matches!(
            factor(&zero, FactorOptions::default()),
            Err(LinsolveError::Singular { index: 3, .. })
        ));
        // NaN and infinity name their entry
        let mut nan = ind.clone();
        nan.add(2, 1, f64::NAN).unwrap();
        assert_eq!(
            factor(&nan, FactorOptions::default()).err(),
            Some(LinsolveError::NonFinite { row: 1, col: 2 })
        );
        let bad_shift = FactorOptions {
            shift: f64::NAN,
            ..FactorOptions::default()
        };
        assert!(matches!(
            factor(&ind, bad_shift),
            Err(LinsolveError::InvalidOption { name: "shift", .. })
        ));
        // a matrix on another pattern
        let other = SymmetricMatrix::zeros(Arc::new(
            SymmetricPattern::from_elements(4, [[0, 3]]).unwrap(),
        ));
        assert_eq!(
            factor(&other, FactorOptions::default()).err(),
            Some(LinsolveError::PatternMismatch)
        );
    }
}

#[test]
fn rank_deficient_matrices_never_give_nan() {
    // B Bᵀ with B of rank n − 2: singular to working precision; whatever
    // round-off leaves, the answer is an error or a finite solution
    let mut rng = Lcg::new(31);
    for (name, n, els) in patterns().into_iter().take(6) {
        let p = Arc::new(SymmetricPattern::from_elements(n, &els).unwrap());
        let mut k = SymmetricMatrix::zeros(p.clone());
        // each element block G Gᵀ with G of rank m − 2 ... summed over a
        // chain it stays singular when two global directions are free: use
        // blocks that annihilate the same two global vectors (rigid modes)
        for (e, el) in els.iter().enumerate() {
            let m = el.len();
            let mut block = vec![0.0; m * m];
            for _ in 0..m.saturating_sub(2) {
                // v ⟂ the constants on even and on odd dofs
                let mut v: Vec<f64> = (0..m).map(|_| rng.centered()).collect();
                for parity in 0..2 {
                    let idx: Vec<usize> = (0..m).filter(|a| el[*a] % 2 == parity).collect();
                    let mean = idx.iter().map(|&a| v[a]).sum::<f64>() / idx.len().max(1) as f64;
                    idx.iter().for_each(|&a| v[a] -= mean);
                }
                for a in 0..m {
                    for c in 0..m {
                        block[a * m + c] += v[a] * v[c];
                    }
                }
            }
            k.add_element(e, &block).unwrap();
        }
        let b: Vec<f64> = (0..n).map(|_| rng.centered()).collect();
        for (solver, mut factor) in solvers(&p) {
            match factor(&k, FactorOptions::default()) {
                Err(LinsolveError::Singular { pivot, scale, .. }) => {
                    assert!(pivot.is_finite() && scale.is_finite(), "{name} {solver}");
                }
                Err(e) => panic!("{name} {solver}: {e:?}"),
                Ok(f) => {
                    let mut x = b.clone();
                    f.solve(&mut x).unwrap();
                    assert!(x.iter().all(|v| v.is_finite()), "{name} {solver}");
                }
            }
        }
    }
}

#[test]
fn llt_and_ldlt_first_give_the_same_solution() {
    let mut rng = Lcg::new(41);
    for (name, n, els) in patterns() {
        let k = random_matrix(n, &els, true, 0.0, &mut rng);
        let b: Vec<f64> = (0..n).map(|_| rng.centered()).collect();
        let mut xs = Vec::new();
        for cholesky in [CholeskyKind::Ldlt, CholeskyKind::Llt] {
            let mut s = SparseSolver::with_settings(
                k.pattern(),
                SparseSettings {
                    cholesky,
                    ..SparseSettings::default()
                },
            )
            .unwrap();
            let f = s.factor(&k, FactorOptions::default()).unwrap();
            assert_eq!(
                Factorization::method(&f),
                match cholesky {
                    CholeskyKind::Ldlt => FactorMethod::Ldlt,
                    CholeskyKind::Llt => FactorMethod::Llt,
                }
            );
            let mut x = b.clone();
            f.solve_in_place(&mut x).unwrap();
            xs.push(x);
        }
        let scale = xs[0].iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let diff = xs[0]
            .iter()
            .zip(&xs[1])
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(diff <= 1e-8 * scale, "{name}: {diff:e}");
    }
}

#[test]
fn the_robot_tangent_on_its_connectivity_pattern_solves_as_the_band_does() {
    // the two-section robot's tangent at its loaded equilibrium, assembled
    // into the band as today and copied onto the pattern built from the
    // element connectivity in free coordinates (element 0: the base's free
    // directions and node 1; element e: nodes e and e + 1)
    let scene = crate::scene::Scene::two_section();
    let robot = scene.robot().unwrap();
    let loads = scene.loads().unwrap();
    let eq = crate::statics::StaticSolver::default()
        .solve(&robot, &loads, None)
        .unwrap();
    let nf = robot.n_free();
    let mut kb = BandedMatrix::zeros(nf, 7, 7);
    robot
        .tangent_into(eq.q.as_slice(), &loads, &mut kb)
        .unwrap();
    let nb = robot.n_base_free();
    let elements: Vec<Vec<usize>> = (0..robot.elements().len())
        .map(|e| match e {
            0 => (0..nb + 4).collect(),
            _ => (nb + 4 * (e - 1)..nb + 4 * (e + 1)).collect(),
        })
        .collect();
    let p = Arc::new(SymmetricPattern::from_elements(nf, &elements).unwrap());
    let mut k = SymmetricMatrix::zeros(p.clone());
    let entries: Vec<(usize, usize)> = k.iter_upper().map(|(i, j, _)| (i, j)).collect();
    for (i, j) in entries {
        k.add(i, j, kb.get(i, j)).unwrap();
    }
    // nothing of the assembled band lies outside the pattern
    assert_eq!(k.to_banded().unwrap(), kb);
    let b: Vec<f64> = (0..nf).map(|i| (i % 5) as f64 - 2.0).collect();
    // reference: a dense LU of the band (nalgebra)
    let dense = nalgebra::DMatrix::from_fn(nf, nf, |i, j| kb.get(i, j));
    let reference: Vec<f64> = dense
        .lu()
        .solve(&nalgebra::DVector::from_vec(b.clone()))
        .unwrap()
        .iter()
        .copied()
        .collect();
    let scale = reference.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    for (solver, mut factor) in solvers(&p) {
        let f = factor(&k, FactorOptions::default()).unwrap();
        assert_eq!(f.signs().map(|i| i.negative), Some(0), "{solver}");
        let mut x = b.clone();
        f.solve(&mut x).unwrap();
        let diff = x
            .iter()
            .zip(&reference)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        // agreement to what the conditioning allows (the orderings round
        // differently), and a backward error at round-off
        assert!(diff <= 1e-10 * scale, "{solver}: {diff:e} of {scale:e}");
        let be = backward_error(&k, &x, &b);
        assert!(be < 1e-14, "{solver}: backward error {be:e}");
    }
}

#[test]
fn empty_and_one_dof_matrices_factor() {
    for n in [0usize, 1] {
        let p = Arc::new(SymmetricPattern::from_elements(n, Vec::<Vec<usize>>::new()).unwrap());
        let mut k = SymmetricMatrix::zeros(p.clone());
        if n == 1 {
            k.add(0, 0, -4.0).unwrap();
        }
        for (solver, mut factor) in solvers(&p) {
            let f = factor(&k, FactorOptions::default()).unwrap();
            assert_eq!(
                f.signs(),
                Some(Inertia {
                    positive: 0,
                    negative: n
                }),
                "{solver}"
            );
            let mut x = vec![2.0; n];
            f.solve(&mut x).unwrap();
            assert!(x.iter().all(|v| *v == -0.5), "{solver}");
            f.solve_cols(&mut vec![2.0; 3 * n], 3).unwrap();
        }
    }
}

/// The largest `|a_i − b_i|` and the largest `|b_i|`.
fn max_diff(a: &[f64], b: &[f64]) -> (f64, f64) {
    let diff = a
        .iter()
        .zip(b)
        .fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
    (diff, b.iter().fold(0.0f64, |m, v| m.max(v.abs())))
}

/// The static solve with the linear solver `kind` at a tolerance of 1e-12.
fn solve_with<M: crate::structure::Model>(
    model: &M,
    loads: &M::Loads,
    kind: SolverKind,
) -> crate::Result<crate::statics::Equilibrium> {
    let settings = crate::statics::StaticSettings {
        linear_solver: kind,
        residual_tolerance: 1e-12,
        ..Default::default()
    };
    crate::statics::StaticSolver::new(settings)?.solve(model, loads, None)
}

/// The setting takes the path it names: on the robot's tangent (a chain,
/// a narrow band) `Auto` and `Band` factor by the band kernels and
/// `Sparse` by faer, at the loaded equilibrium (positive definite) as at
/// an indefinite tangent (a compressed straight robot). The three static
/// solves reach one equilibrium to 1e-10 of the largest coordinate, `Band`
/// bit for bit `Auto`'s (the same kernels).
#[test]
fn each_solver_kind_takes_its_path_on_a_robot_and_solves_alike() {
    let scene = crate::scene::Scene::two_section();
    let robot = scene.robot().unwrap();
    let loads = scene.loads().unwrap();
    let reference = solve_with(&robot, &loads, SolverKind::Auto).unwrap();
    let p = robot.tangent_pattern();
    let mut k = SymmetricMatrix::zeros(p.clone());
    // an indefinite tangent: the straight robot shortened by 10 % (axial
    // strain −0.1 everywhere: a compressive force far above the buckling
    // load in the geometric stiffness)
    let compressed: Vec<f64> = robot
        .reference_configuration()
        .iter()
        .map(|v| 0.9 * v)
        .collect();
    for kind in [SolverKind::Auto, SolverKind::Sparse, SolverKind::Band] {
        let mut solver = AutoSolver::with_kind(p, kind).unwrap();
        let banded = kind != SolverKind::Sparse;
        let expected = if banded {
            SolverKind::Band
        } else {
            SolverKind::Sparse
        };
        assert_eq!(solver.kind(), expected, "{kind:?}");
        for q in [reference.q.as_slice(), &compressed[..]] {
            robot.tangent_into(q, &loads, &mut k).unwrap();
            let f = solver.factor(&k, FactorOptions::default()).unwrap();
            assert_eq!(f.is_banded(), banded, "{kind:?}");
        }
        let f = solver.factor(&k, FactorOptions::default()).unwrap();
        assert!(
            f.inertia().is_some_and(|i| i.negative > 0),
            "{kind:?}: {:?}",
            f.inertia()
        );
        let eq = solve_with(&robot, &loads, kind).unwrap();
        assert!(eq.report.status.is_converged(), "{kind:?}: {}", eq.report);
        let (diff, scale) = max_diff(eq.q.as_slice(), reference.q.as_slice());
        assert!(diff <= 1e-10 * scale, "{kind:?}: {diff:e} of {scale:e}");
        if kind == SolverKind::Band {
            assert_eq!(eq.q, reference.q);
        }
    }
}

/// On structures: the gripper's two fingers (two chains, numbered one
/// after the other: a narrow band) take the band path under `Auto` and
/// `Band`; the parallel robot (three legs joined to one platform whose
/// coordinates couple the far ends of the legs) is not a narrow band:
/// `Auto` takes faer's path, `Band` is refused with a typed error naming
/// the setting. Every kind that solves reaches `Sparse`'s equilibrium to
/// 1e-10 of the largest coordinate.
#[test]
fn each_solver_kind_takes_its_path_on_structures_and_solves_alike() {
    use crate::structure::{Assembled, StructureLoads};
    // the gripper: pressures in both fingers
    let gripper = crate::grasp::gripper::GripperSpec::default()
        .structure()
        .unwrap();
    let finger = crate::loads::Loads {
        pressures_pa: vec![60e3, 0.0, 20e3, 0.0],
        ..Default::default()
    };
    let loads = StructureLoads {
        rods: vec![finger.clone(), finger],
        ..Default::default()
    };
    let p = gripper.tangent_pattern().unwrap();
    let reference = solve_with(&gripper, &loads, SolverKind::Sparse).unwrap();
    for kind in [SolverKind::Auto, SolverKind::Band] {
        assert_eq!(
            AutoSolver::with_kind(&p, kind).unwrap().kind(),
            SolverKind::Band
        );
        let eq = solve_with(&gripper, &loads, kind).unwrap();
        let (diff, scale) = max_diff(eq.q.as_slice(), reference.q.as_slice());
        assert!(diff <= 1e-10 * scale, "{kind:?}: {diff:e} of {scale:e}");
    }
    // the parallel robot under a platform load
    let robot = crate::parallel::ParallelSpec::default()
        .build_cable()
        .unwrap();
    let parallel = robot.structure();
    let loads = robot.loads(&[], [0.0, 0.0, -0.1], [0.0; 3]).unwrap();
    let p = parallel.tangent_pattern().unwrap();
    let kinds = |kind| AutoSolver::with_kind(&p, kind).map(|s| s.kind());
    assert_eq!(kinds(SolverKind::Auto), Ok(SolverKind::Sparse));
    assert_eq!(kinds(SolverKind::Sparse), Ok(SolverKind::Sparse));
    assert!(matches!(
        kinds(SolverKind::Band),
        Err(LinsolveError::NotBanded { .. })
    ));
    let reference = solve_with(parallel, &loads, SolverKind::Sparse).unwrap();
    let eq = solve_with(parallel, &loads, SolverKind::Auto).unwrap();
    let (diff, scale) = max_diff(eq.q.as_slice(), reference.q.as_slice());
    assert!(diff <= 1e-10 * scale, "{diff:e} of {scale:e}");
    match solve_with(parallel, &loads, SolverKind::Band) {
        Err(crate::Error::InvalidParameter { name, .. }) => assert_eq!(name, "linear_solver"),
        other => panic!(
            "expected the band kind refused, got {:?}",
            other.map(|e| e.report)
        ),
    }
}
