//! Configuration-dependent forces: a potential `V(q)` over a model's
//! coordinates with its generalized force `−∂V/∂q` and its stiffness
//! `∂²V/∂q²`.
//!
//! The equilibrium (17) sums generalized forces; dead loads do not depend on
//! `q`, the elastic forces and the actuation (18) do. A [`ForceField`] is any
//! further conservative force that depends on the configuration — a spring
//! that holds a point, and later a contact penalty or barrier — written the
//! way an element is: energy, force and stiffness at `q`, so the assembler
//! adds `V` to the total potential, `−∂V/∂q` to the residual and `∂²V/∂q²` to
//! the tangent without knowing what the field is.
//!
//! Stiffness entries go to a [`StiffnessSink`] (a triplet list, a banded or
//! a dense matrix), one `(row, column, value)` at a time, so a field that
//! couples distant coordinates (a contact between two rods) needs no band.

use nalgebra::SVector;

use crate::error::{Error, Result, check_all_finite, check_index};

/// Where stiffness entries go: `add(i, j, v)` adds `v` to entry `(i, j)`.
///
/// Implemented by [`crate::structure::Triplets`], by
/// [`crate::linsolve::BandedMatrix`] (entries outside the band are dropped:
/// only band-limited contributions may be sent to it) and by a dense
/// `nalgebra::DMatrix<f64>`.
///
/// # Example
/// ```
/// use softrod::loads::force_field::StiffnessSink;
/// let mut k = nalgebra::DMatrix::<f64>::zeros(2, 2);
/// k.add(0, 1, 3.0);
/// k.add(0, 1, 1.0);
/// assert_eq!(k[(0, 1)], 4.0);
/// ```
pub trait StiffnessSink {
    /// Adds `value` to entry `(row, col)`.
    fn add(&mut self, row: usize, col: usize, value: f64);
}

impl StiffnessSink for nalgebra::DMatrix<f64> {
    fn add(&mut self, row: usize, col: usize, value: f64) {
        if let Some(x) = self.get_mut((row, col)) {
            *x += value;
        }
    }
}

impl StiffnessSink for crate::linsolve::BandedMatrix {
    fn add(&mut self, row: usize, col: usize, value: f64) {
        // `BandedMatrix::add` ignores entries outside the band
        crate::linsolve::BandedMatrix::add(self, row, col, value);
    }
}

impl StiffnessSink for crate::linsolve::SymmetricMatrix {
    /// Adds an entry of the upper triangle (`row <= col`); entries below
    /// the diagonal are skipped, as their mirror image is the same stored
    /// value (a symmetric scatter sends both), and entries outside the
    /// pattern are dropped, as for the band.
    fn add(&mut self, row: usize, col: usize, value: f64) {
        if row <= col {
            self.add_if_present(row, col, value);
        }
    }
}

/// A conservative, configuration-dependent force: potential `V(q)` (J) over
/// the model's coordinates `q` (all of them, `n_q` numbers), its generalized
/// force `−∂V/∂q` and its stiffness `∂²V/∂q²`.
///
/// Kernels are infallible and must not panic: a model calls
/// [`ForceField::check`] once with its `n_q` before it evaluates the field,
/// and a field given a shorter `q` adds nothing (and returns NaN energy).
///
/// # Example
/// ```
/// use softrod::loads::force_field::{ForceField, PointSpring};
/// // a zero-length spring of 10 N/m from the point (q[0], q[1]) to the origin
/// let s = PointSpring::new([0, 1], nalgebra::Vector2::zeros(), 10.0, 0.0).unwrap();
/// let q = [0.3, -0.4];
/// assert!((s.energy(&q) - 0.5 * 10.0 * 0.25).abs() < 1e-15);
/// let mut f = [0.0; 2];
/// s.add_force(&q, &mut f);
/// assert!((f[0] + 3.0).abs() < 1e-15 && (f[1] - 4.0).abs() < 1e-15);
/// ```
pub trait ForceField: std::fmt::Debug + Send + Sync {
    /// Checks that the field fits a model with `n_q` coordinates.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] for a coordinate index `>= n_q`.
    fn check(&self, n_q: usize) -> Result<()>;
    /// The potential `V(q)` (J).
    fn energy(&self, q: &[f64]) -> f64;
    /// Adds the generalized force `−∂V/∂q` into `force` (`n_q` entries).
    fn add_force(&self, q: &[f64], force: &mut [f64]);
    /// Adds the stiffness `∂²V/∂q²` into `sink` (symmetric).
    fn add_stiffness(&self, q: &[f64], sink: &mut dyn StiffnessSink);
}

/// A linear spring from a point of the model to a fixed anchor:
/// `V = ½ k (|r − a| − ℓ0)²`, `r` the point's position (the coordinates
/// `q[dofs[i]]`), `a` the anchor, `k` the stiffness, `ℓ0` the rest length.
///
/// Force `−k (d − ℓ0) d̂` with `d = |r − a|`, `d̂ = (r − a)/d`; stiffness
/// `k [d̂ d̂ᵀ + (1 − ℓ0/d)(I − d̂ d̂ᵀ)]`. At `d = 0` the direction is
/// undefined: the spring then acts as a zero-length spring (force 0,
/// stiffness `k I`), never NaN.
///
/// # Example
/// ```
/// use softrod::loads::force_field::{ForceField, PointSpring};
/// // a spring of rest length 0.1 m stretched to 0.3 m along x
/// let s = PointSpring::new([4, 5], nalgebra::Vector2::zeros(), 2.0, 0.1).unwrap();
/// let mut q = vec![0.0; 8];
/// q[4] = 0.3;
/// let mut f = vec![0.0; 8];
/// s.add_force(&q, &mut f);
/// assert!((f[4] + 2.0 * 0.2).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct PointSpring {
    dofs: Vec<usize>,
    anchor_m: Vec<f64>,
    stiffness_n_per_m: f64,
    rest_length_m: f64,
}

/// Largest dimension of a spring's point.
const MAX_DIM: usize = 3;

impl PointSpring {
    /// A spring on the point whose coordinates are `q[dofs[0]], q[dofs[1]], …`
    /// (m), anchored at `anchor_m` (m), of stiffness `stiffness_n_per_m` (N/m)
    /// and rest length `rest_length_m` (m).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a point of 0 or more than 3
    /// coordinates (`spring.dofs`), a non-finite anchor, a negative or
    /// non-finite stiffness or rest length.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector3;
    /// use softrod::loads::force_field::PointSpring;
    /// assert!(PointSpring::new([0, 1, 2], Vector3::new(0.0, 0.0, 0.1), 5.0, 0.0).is_ok());
    /// let bad = PointSpring::new([0, 1], nalgebra::Vector2::zeros(), -1.0, 0.0).unwrap_err();
    /// assert_eq!(bad.field(), Some("spring.stiffness_n_per_m"));
    /// ```
    pub fn new<const D: usize>(
        dofs: [usize; D],
        anchor_m: SVector<f64, D>,
        stiffness_n_per_m: f64,
        rest_length_m: f64,
    ) -> Result<Self> {
        if D == 0 || D > MAX_DIM {
            return Err(Error::invalid(
                "spring.dofs",
                format!("{D} coordinates"),
                "a point has 1 to 3 coordinates",
            ));
        }
        let (dofs, anchor_m) = (dofs.to_vec(), anchor_m.as_slice().to_vec());
        check_all_finite("spring.anchor_m", &anchor_m)?;
        for (name, v) in [
            ("spring.stiffness_n_per_m", stiffness_n_per_m),
            ("spring.rest_length_m", rest_length_m),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(name, v, "must be finite and >= 0"));
            }
        }
        Ok(PointSpring {
            dofs,
            anchor_m,
            stiffness_n_per_m,
            rest_length_m,
        })
    }

    /// `r − a` into a fixed buffer and its length; `None` if `q` is too short.
    fn offset(&self, q: &[f64]) -> Option<([f64; MAX_DIM], f64)> {
        let mut d = [0.0; MAX_DIM];
        for ((di, &i), a) in d.iter_mut().zip(&self.dofs).zip(&self.anchor_m) {
            *di = q.get(i)? - a;
        }
        let n = d.iter().map(|x| x * x).sum::<f64>().sqrt();
        Some((d, n))
    }
}

impl ForceField for PointSpring {
    fn check(&self, n_q: usize) -> Result<()> {
        for (k, &i) in self.dofs.iter().enumerate() {
            check_index(&format!("spring.dofs[{k}]"), i, n_q)?;
        }
        Ok(())
    }

    fn energy(&self, q: &[f64]) -> f64 {
        match self.offset(q) {
            Some((_, d)) => 0.5 * self.stiffness_n_per_m * (d - self.rest_length_m).powi(2),
            None => f64::NAN,
        }
    }

    fn add_force(&self, q: &[f64], force: &mut [f64]) {
        let Some((v, d)) = self.offset(q) else {
            return;
        };
        // −k (d − ℓ0) d̂ = −k (1 − ℓ0/d) (r − a)
        let c = if d > 0.0 {
            self.stiffness_n_per_m * (1.0 - self.rest_length_m / d)
        } else {
            self.stiffness_n_per_m
        };
        for (&i, vi) in self.dofs.iter().zip(&v) {
            if let Some(f) = force.get_mut(i) {
                *f -= c * vi;
            }
        }
    }

    fn add_stiffness(&self, q: &[f64], sink: &mut dyn StiffnessSink) {
        let Some((v, d)) = self.offset(q) else {
            return;
        };
        let k = self.stiffness_n_per_m;
        let n = self.dofs.len();
        // k [d̂ d̂ᵀ + (1 − ℓ0/d)(I − d̂ d̂ᵀ)] = k (1 − ℓ0/d) I + k (ℓ0/d) d̂ d̂ᵀ
        let (iso, dyad) = if d > 0.0 {
            let r = self.rest_length_m / d;
            (k * (1.0 - r), k * r / (d * d))
        } else {
            (k, 0.0)
        };
        for a in 0..n {
            for b in 0..n {
                let mut h = dyad * v[a] * v[b];
                if a == b {
                    h += iso;
                }
                sink.add(self.dofs[a], self.dofs[b], h);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Force = −(central difference of the energy), stiffness = −(central
    /// difference of the force), at stretched, compressed and oblique points.
    #[test]
    fn force_and_stiffness_are_the_derivatives_of_the_energy() {
        let n_q = 7;
        let s = PointSpring::new(
            [5, 1, 3],
            nalgebra::Vector3::new(0.1, -0.2, 0.05),
            7.0,
            0.15,
        )
        .unwrap();
        s.check(n_q).unwrap();
        for q in [
            [0.3, 0.2, -0.1, 0.4, 0.0, -0.3, 9.0],
            [0.0, -0.18, 0.0, 0.1, 0.0, 0.12, 0.0],
            [1.0, 2.0, 3.0, -4.0, 5.0, 6.0, 7.0],
        ] {
            let mut f = vec![0.0; n_q];
            s.add_force(&q, &mut f);
            let mut k = nalgebra::DMatrix::zeros(n_q, n_q);
            s.add_stiffness(&q, &mut k);
            let h = 1e-6;
            let fscale = f.iter().fold(1e-3f64, |m, v| m.max(v.abs()));
            let kscale = k.amax();
            for j in 0..n_q {
                let (mut qp, mut qm) = (q, q);
                qp[j] += h;
                qm[j] -= h;
                let fd = -(s.energy(&qp) - s.energy(&qm)) / (2.0 * h);
                assert!(
                    (fd - f[j]).abs() < 1e-8 * fscale,
                    "force {j}: {fd} vs {}",
                    f[j]
                );
                let (mut fp, mut fm) = (vec![0.0; n_q], vec![0.0; n_q]);
                s.add_force(&qp, &mut fp);
                s.add_force(&qm, &mut fm);
                for i in 0..n_q {
                    let fd = -(fp[i] - fm[i]) / (2.0 * h);
                    assert!(
                        (fd - k[(i, j)]).abs() < 1e-7 * kscale,
                        "stiffness ({i},{j}): {fd} vs {}",
                        k[(i, j)]
                    );
                }
            }
            assert!((k.clone() - k.transpose()).amax() <= 1e-15 * kscale);
        }
    }

    #[test]
    fn a_spring_on_its_anchor_is_finite_and_a_bad_index_is_refused() {
        let s = PointSpring::new([0, 1], nalgebra::Vector2::new(0.5, 0.5), 3.0, 0.2).unwrap();
        let q = [0.5, 0.5];
        assert!((s.energy(&q) - 0.5 * 3.0 * 0.04).abs() < 1e-15);
        let mut f = [0.0; 2];
        s.add_force(&q, &mut f);
        assert_eq!(f, [0.0, 0.0]);
        let mut k = nalgebra::DMatrix::zeros(2, 2);
        s.add_stiffness(&q, &mut k);
        assert_eq!(k, nalgebra::DMatrix::identity(2, 2) * 3.0);
        let err = s.check(1).unwrap_err();
        assert_eq!(err.field(), Some("spring.dofs[1]"));
        assert!(PointSpring::new([0], nalgebra::Vector1::new(0.0), -1.0, 0.0).is_err());
        assert!(PointSpring::new([], nalgebra::SVector::<f64, 0>::zeros(), 1.0, 0.0).is_err());
        assert!(PointSpring::new([0, 1], nalgebra::Vector2::new(f64::NAN, 0.0), 1.0, 0.0).is_err());
    }
}
