//! Gauss–Legendre quadrature on the unit interval.

use crate::error::{Error, Result};

/// The largest number of points a rule may have.
pub const MAX_POINTS: usize = 32;

/// A Gauss–Legendre rule on `[0, 1]`: `∫_0^1 f(ξ) dξ ≈ Σ w_i f(ξ_i)`.
///
/// Exact for polynomials of degree `2n - 1`.
///
/// # Example
/// ```
/// let rule = softrod::quadrature::GaussRule::new(3).unwrap();
/// let integral: f64 = rule.iter().map(|(x, w)| w * x.powi(5)).sum();
/// assert!((integral - 1.0 / 6.0).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct GaussRule {
    points: Vec<f64>,
    weights: Vec<f64>,
}

impl GaussRule {
    /// Builds the `n`-point rule (Newton iteration on the Legendre polynomial).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for `n = 0`, [`Error::TooLarge`] for
    /// `n > MAX_POINTS` (refused before allocating).
    pub fn new(n: usize) -> Result<Self> {
        if n == 0 {
            return Err(Error::invalid("gauss_points", n, "must be >= 1"));
        }
        crate::error::check_at_most("gauss_points", n, MAX_POINTS)?;
        let mut points = vec![0.0; n];
        let mut weights = vec![0.0; n];
        let nf = n as f64;
        for i in 0..n.div_ceil(2) {
            // Initial guess (Tricomi), then Newton on P_n.
            let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (nf + 0.5)).cos();
            let mut dp = 1.0;
            for _ in 0..100 {
                let (p, d) = legendre(n, x);
                dp = d;
                let dx = p / d;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let (_, d) = legendre(n, x);
            if d != 0.0 {
                dp = d;
            }
            let w = 2.0 / ((1.0 - x * x) * dp * dp);
            // map [-1, 1] -> [0, 1]
            points[i] = 0.5 * (1.0 - x);
            points[n - 1 - i] = 0.5 * (1.0 + x);
            weights[i] = 0.5 * w;
            weights[n - 1 - i] = 0.5 * w;
        }
        Ok(GaussRule { points, weights })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Always false (a rule has at least one point).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Iterates over `(ξ_i, w_i)` with `ξ_i` in `(0, 1)` and `Σ w_i = 1`.
    pub fn iter(&self) -> impl Iterator<Item = (f64, f64)> + '_ {
        self.points
            .iter()
            .copied()
            .zip(self.weights.iter().copied())
    }
}

/// `(P_n(x), P_n'(x))` by the three-term recurrence.
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let mut p0 = 1.0;
    let mut p1 = x;
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    let p = if n == 0 { 1.0 } else { p1 };
    let dp = n as f64 * (x * p - p0) / (x * x - 1.0);
    (p, dp)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_for_degree_2n_minus_1() {
        for n in 1..=12 {
            let rule = GaussRule::new(n).unwrap();
            assert_eq!(rule.len(), n);
            for deg in 0..(2 * n) {
                let got: f64 = rule.iter().map(|(x, w)| w * x.powi(deg as i32)).sum();
                let want = 1.0 / (deg as f64 + 1.0);
                assert!(
                    (got - want).abs() < 1e-14,
                    "n={n} deg={deg}: {got} vs {want}"
                );
            }
            // and not exact one degree higher (the error is still visible for small n)
            if n > 6 {
                continue;
            }
            let d = 2 * n;
            let got: f64 = rule.iter().map(|(x, w)| w * x.powi(d as i32)).sum();
            assert!((got - 1.0 / (d as f64 + 1.0)).abs() > 1e-12);
        }
    }

    #[test]
    fn refuses_bad_sizes() {
        assert!(GaussRule::new(0).is_err());
        assert!(GaussRule::new(MAX_POINTS + 1).is_err());
    }
}
