//! The fit test of an estimate: whether the returned answer explains the
//! markers to their stated noise.
//!
//! With noise-whitened weights (`W = I/σ²`, or a marker's own weights read
//! as inverse variances) the weighted misfit of the true shape,
//! `χ² = (A q − y)ᵀ W (A q − y)`, is χ²-distributed with `n_ob` degrees of
//! freedom (`n_ob` the observed components). An estimate whose misfit at
//! its own equilibrium exceeds the [`FIT_QUANTILE`] (0.999) quantile of
//! that distribution does not explain the observation: either the model
//! cannot (an unmodelled effect, a wrong noise level) or the penalty holds
//! the load back (an `α` far too large, a prior that forbids the load the
//! markers show). Such an estimate ends as
//! [`EstimateStatus::MisfitBeyondNoise`](super::EstimateStatus::MisfitBeyondNoise),
//! never as converged.
//!
//! The test is one-sided: a misfit below the band is no failure of the fit
//! (noise-free data, an overfitted small `α`). It is conservative for a
//! regularized estimate, whose misfit has expectation `n_ob − γ` rather
//! than `n_ob` (`γ` the determined load directions): a false alarm on an
//! estimate of the true model has probability below `1 − FIT_QUANTILE`.

/// The quantile of the χ² distribution the weighted misfit of a converged
/// estimate is held to: a correct model with correctly stated noise fails
/// it in 1 frame out of 1000.
pub const FIT_QUANTILE: f64 = 0.999;

/// The `p`-quantile of the χ² distribution with `k` degrees of freedom:
/// the `x` with `P(k/2, x/2) = p` (`P` the regularized lower incomplete
/// gamma function), by Newton's method on the distribution function from
/// the Wilson–Hilferty approximation `k (1 − 2/(9k) + z_p √(2/(9k)))³`
/// (`z_p` the normal quantile), to about 1e-12 relative. `NaN` for `p`
/// outside `(0, 1)` or `k = 0`.
///
/// # Example
/// ```
/// use softrod::estimate::chi2_quantile;
/// // two degrees of freedom: the exponential distribution, −2 ln(1 − p)
/// assert!((chi2_quantile(0.95, 2) - 5.991_464_547_107_979).abs() < 1e-10);
/// // the 0.999 quantile for 10 observed components (5 planar markers)
/// assert!((chi2_quantile(0.999, 10) - 29.588).abs() < 1e-3);
/// assert!(chi2_quantile(1.0, 3).is_nan());
/// ```
pub fn chi2_quantile(p: f64, k: usize) -> f64 {
    if !(p > 0.0 && p < 1.0) || k == 0 {
        return f64::NAN;
    }
    let kf = k as f64;
    let a = 0.5 * kf;
    let h = 2.0 / (9.0 * kf);
    let wh = kf * (1.0 - h + normal_quantile(p) * h.sqrt()).powi(3);
    let mut x = if wh > 0.0 { wh } else { kf * p.powf(2.0 / kf) };
    let ln_norm = a * std::f64::consts::LN_2 + ln_gamma(a);
    // the tail on the side of p: the smaller of P and 1 − P, for accuracy
    let upper = p > 0.5;
    let target = if upper { 1.0 - p } else { p };
    for _ in 0..100 {
        let (lower_p, upper_q) = gamma_pq(a, 0.5 * x);
        let f = if upper {
            target - upper_q
        } else {
            lower_p - target
        };
        // the density of χ²_k at x
        let pdf = ((a - 1.0) * x.ln() - 0.5 * x - ln_norm).exp();
        if !(pdf > 0.0 && pdf.is_finite()) {
            break;
        }
        let mut next = x - f / pdf;
        if next.is_nan() || next <= 0.0 {
            next = 0.5 * x;
        }
        let dx = (next - x).abs();
        x = next;
        if dx <= 1e-13 * x {
            break;
        }
    }
    x
}

/// The fit test: `Ok(())` when the weighted misfit `weighted_residual` of
/// `n_ob` observed components is within the [`FIT_QUANTILE`] quantile of
/// χ²(`n_ob`), else `Err(quantile)`. No observation: no test.
pub(crate) fn fit_test(weighted_residual: f64, n_ob: usize) -> std::result::Result<(), f64> {
    if n_ob == 0 {
        return Ok(());
    }
    let quantile = chi2_quantile(FIT_QUANTILE, n_ob);
    // (a NaN misfit fails the test)
    if weighted_residual <= quantile {
        Ok(())
    } else {
        Err(quantile)
    }
}

/// The standard normal quantile by Abramowitz & Stegun 26.2.23 (absolute
/// error below 4.5e-4): a starting point only.
fn normal_quantile(p: f64) -> f64 {
    let tail = if p < 0.5 { p } else { 1.0 - p };
    let t = (-2.0 * tail.ln()).sqrt();
    let z = t
        - (2.515_517 + 0.802_853 * t + 0.010_328 * t * t)
            / (1.0 + 1.432_788 * t + 0.189_269 * t * t + 0.001_308 * t * t * t);
    if p < 0.5 { -z } else { z }
}

/// `ln Γ(a)` for `a > 0` (Lanczos, g = 7, nine coefficients; about 1e-15
/// relative).
fn ln_gamma(a: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if a < 0.5 {
        // reflection: Γ(a) Γ(1 − a) = π / sin(π a)
        let pi = std::f64::consts::PI;
        return (pi / (pi * a).sin()).ln() - ln_gamma(1.0 - a);
    }
    let x = a - 1.0;
    let mut s = C[0];
    for (i, c) in C.iter().enumerate().skip(1) {
        s += c / (x + i as f64);
    }
    let t = x + G + 0.5;
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + s.ln()
}

/// The regularized incomplete gamma functions `(P(a, x), Q(a, x))`,
/// `P + Q = 1`: the series below `x = a + 1`, the continued fraction
/// (modified Lentz) above, each computing the smaller one directly.
fn gamma_pq(a: f64, x: f64) -> (f64, f64) {
    if x <= 0.0 {
        return (0.0, 1.0);
    }
    let ln_pre = -x + a * x.ln() - ln_gamma(a);
    if x < a + 1.0 {
        let mut term = 1.0 / a;
        let mut sum = term;
        for n in 1..10_000 {
            term *= x / (a + f64::from(n));
            sum += term;
            if term.abs() <= sum.abs() * 1e-17 {
                break;
            }
        }
        let p = sum * ln_pre.exp();
        (p, 1.0 - p)
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..10_000 {
            let an = -f64::from(i) * (f64::from(i) - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() <= 1e-17 {
                break;
            }
        }
        let q = ln_pre.exp() * h;
        (1.0 - q, q)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Against tabulated χ² quantiles (NIST/SEMATECH e-Handbook, table
    /// 1.3.6.7.4, three decimals) and closed forms: `k = 2`,
    /// `−2 ln(1 − p)`; `k = 1`, `z²_{(1+p)/2}` (z to 16 digits).
    #[test]
    fn chi2_quantiles_match_the_tables() {
        let table = [
            (0.999, 1, 10.828),
            (0.999, 2, 13.816),
            (0.999, 3, 16.266),
            (0.999, 5, 20.515),
            (0.999, 10, 29.588),
            (0.999, 15, 37.697),
            (0.999, 20, 45.315),
            (0.999, 30, 59.703),
            (0.999, 50, 86.661),
            (0.999, 100, 149.449),
            (0.95, 1, 3.841),
            (0.95, 10, 18.307),
            (0.95, 100, 124.342),
            (0.05, 10, 3.940),
            (0.01, 5, 0.554),
        ];
        for (p, k, want) in table {
            let got = chi2_quantile(p, k);
            assert!(
                (got - want).abs() <= 6e-4,
                "chi2({p}, {k}) = {got}, table {want}"
            );
        }
        for p in [0.01f64, 0.5, 0.95, 0.999, 0.999_999] {
            let want = -2.0 * (1.0 - p).ln();
            let got = chi2_quantile(p, 2);
            assert!(
                (got - want).abs() <= 1e-11 * want,
                "k = 2, p = {p}: {got} vs {want}"
            );
        }
        // z_0.9995 = 3.290526731491926 (k = 1 at p = 0.999)
        let z: f64 = 3.290_526_731_491_926;
        assert!((chi2_quantile(0.999, 1) - z * z).abs() <= 1e-10);
        // large k: Wilson–Hilferty is then accurate to 1e-4 relative
        let k = 20_000;
        let wh = {
            let h = 2.0 / (9.0 * k as f64);
            k as f64 * (1.0 - h + 3.090_232_306_167_813 * h.sqrt()).powi(3)
        };
        assert!((chi2_quantile(0.999, k) / wh - 1.0).abs() < 1e-4);
        assert!(chi2_quantile(0.0, 3).is_nan() && chi2_quantile(0.5, 0).is_nan());
    }

    /// The fit test passes at the quantile and fails above it (and on NaN).
    #[test]
    fn fit_test_is_the_quantile() {
        let q = chi2_quantile(FIT_QUANTILE, 15);
        assert_eq!(fit_test(q, 15), Ok(()));
        assert_eq!(fit_test(2.1e6, 15), Err(q));
        assert!(fit_test(f64::NAN, 15).is_err());
        assert_eq!(fit_test(1e9, 0), Ok(()));
    }
}
