//! The parameter updater (31): `dF̂/dt = K_P (F̄ − F̂) + K_I ∫(F̄ − F̂) dt`.
//!
//! `F̄` is the estimator's load, `F̂` the one the feedforward uses. Per
//! component the state `(F̂, I)` with `I = ∫(F̄ − F̂) dt` obeys the linear
//! system
//!
//! ```text
//! d/dt [F̂; I] = [−K_P  K_I; −1  0] [F̂; I] + [K_P; 1] F̄
//! ```
//!
//! discretized at the control rate exactly for an `F̄` held over each
//! interval (zero-order hold: the matrix exponential of the augmented
//! system). So the samples of a step response are those of the continuous
//! law: with `K_P = K_I = 4` the error `e = F̄ − F̂` after a step `e₀` is
//! `e₀ (1 − 2t) e^{−2t}` (its slope at 0 is `−K_P e₀`, from (31) with
//! `I(0) = 0`): zero at 0.5 s, an undershoot of `e^{−2}` = 13.5 % at 1 s, and
//! within 2 % from 2.70 s on.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_all_finite, check_len};

/// The largest proportional gain of the updater (1/s): a time constant of
/// 0.1 ms, one period of the fastest control rate a loop accepts (10 kHz);
/// far beyond it the discretization's matrix exponential overflows (at
/// `1e308` every sample's load was NaN).
pub const MAX_K_P_PER_S: f64 = 1e4;

/// The largest integral gain of the updater (1/s²): `MAX_K_P_PER_S²`.
pub const MAX_K_I_PER_S2: f64 = 1e8;

/// Gains of the updater (31); defaults `K_P = 4` (1/s), `K_I = 4` (1/s²).
///
/// # Example
/// ```
/// softrod::control::UpdaterGains::default().validate()?;
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct UpdaterGains {
    /// Proportional gain `K_P` (1/s, in `(0, MAX_K_P_PER_S]`; default 4).
    pub k_p_per_s: f64,
    /// Integral gain `K_I` (1/s², in `(0, MAX_K_I_PER_S2]`; default 4).
    pub k_i_per_s2: f64,
}

impl Default for UpdaterGains {
    fn default() -> Self {
        UpdaterGains {
            k_p_per_s: 4.0,
            k_i_per_s2: 4.0,
        }
    }
}

impl UpdaterGains {
    /// Checks the gains.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `updater.k_p_per_s` or
    /// `updater.k_i_per_s2` for a gain ≤ 0, not finite or above
    /// [`MAX_K_P_PER_S`] / [`MAX_K_I_PER_S2`].
    pub fn validate(&self) -> Result<()> {
        self.validate_at("updater.")
    }

    /// [`UpdaterGains::validate`] with the fields named `prefix` + name
    /// (`loop.gains.` in a trajectory file).
    pub(crate) fn validate_at(&self, prefix: &str) -> Result<()> {
        for (name, v, max) in [
            ("k_p_per_s", self.k_p_per_s, MAX_K_P_PER_S),
            ("k_i_per_s2", self.k_i_per_s2, MAX_K_I_PER_S2),
        ] {
            if !(v.is_finite() && v > 0.0 && v <= max) {
                return Err(Error::invalid(
                    format!("{prefix}{name}"),
                    v,
                    format!("must be > 0 and at most {max:e}"),
                ));
            }
        }
        Ok(())
    }
}

/// The updater's state for a load vector of fixed length (see the [module
/// documentation](crate::control)).
///
/// # Example
/// A step of `F̄` from 0 to 1, sampled at 30 Hz: after 1 s the estimate has
/// overshot by `e^{−2}`.
/// ```
/// use softrod::control::{ParameterUpdater, UpdaterGains};
/// let mut u = ParameterUpdater::new(1, UpdaterGains::default(), 1.0 / 30.0)?;
/// for _ in 0..30 { u.step(&[1.0])?; }
/// assert!((u.estimate()[0] - (1.0 + (-2.0f64).exp())).abs() < 1e-12);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct ParameterUpdater {
    gains: UpdaterGains,
    dt_s: f64,
    /// `exp(A dt)` and `∫₀^dt exp(A s) ds B`, row-major 2×2 and 2.
    phi: [[f64; 2]; 2],
    gamma: [f64; 2],
    f_hat: Vec<f64>,
    integral: Vec<f64>,
}

impl ParameterUpdater {
    /// An updater for `n` parameters at rest at zero, stepping every
    /// `dt_s` seconds.
    ///
    /// # Errors
    /// As [`UpdaterGains::validate`]; [`Error::InvalidParameter`] naming
    /// `dt_s` for a step ≤ 0 or not finite.
    pub fn new(n: usize, gains: UpdaterGains, dt_s: f64) -> Result<Self> {
        gains.validate()?;
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(Error::invalid("dt_s", dt_s, "must be finite and > 0"));
        }
        let (kp, ki) = (gains.k_p_per_s, gains.k_i_per_s2);
        // augmented system [A B; 0 0] dt, exponentiated
        let m = [
            [-kp * dt_s, ki * dt_s, kp * dt_s],
            [-dt_s, 0.0, dt_s],
            [0.0, 0.0, 0.0],
        ];
        let e = expm3(m);
        Ok(ParameterUpdater {
            gains,
            dt_s,
            phi: [[e[0][0], e[0][1]], [e[1][0], e[1][1]]],
            gamma: [e[0][2], e[1][2]],
            f_hat: vec![0.0; n],
            integral: vec![0.0; n],
        })
    }

    /// Starts from `f_hat` at rest (the integral state such that
    /// `dF̂/dt = 0` if `F̄ = F̂`: zero).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a wrong length; non-finite values.
    pub fn reset_to(&mut self, f_hat: &[f64]) -> Result<()> {
        check_len("f_hat", self.f_hat.len(), f_hat.len())?;
        check_all_finite("f_hat", f_hat)?;
        self.f_hat.copy_from_slice(f_hat);
        self.integral.iter_mut().for_each(|v| *v = 0.0);
        Ok(())
    }

    /// The gains.
    pub fn gains(&self) -> UpdaterGains {
        self.gains
    }

    /// The control interval (s).
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// The current `F̂`.
    pub fn estimate(&self) -> &[f64] {
        &self.f_hat
    }

    /// Advances one interval with the estimator's `F̄` held over it; returns
    /// the new `F̂`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a wrong length,
    /// [`Error::InvalidParameter`] (field `f_bar`) for non-finite values.
    pub fn step(&mut self, f_bar: &[f64]) -> Result<&[f64]> {
        check_len("f_bar", self.f_hat.len(), f_bar.len())?;
        check_all_finite("f_bar", f_bar)?;
        let (p, g) = (self.phi, self.gamma);
        for ((f, i), fb) in self.f_hat.iter_mut().zip(&mut self.integral).zip(f_bar) {
            let (f0, i0) = (*f, *i);
            *f = p[0][0] * f0 + p[0][1] * i0 + g[0] * fb;
            *i = p[1][0] * f0 + p[1][1] * i0 + g[1] * fb;
        }
        Ok(&self.f_hat)
    }
}

/// `exp(M)` of a 3×3 matrix by scaling and squaring of its Taylor series.
fn expm3(m: [[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let norm = m
        .iter()
        .map(|r| r.iter().map(|v| v.abs()).sum::<f64>())
        .fold(0.0f64, f64::max);
    let mut s = 0u32;
    while norm / f64::from(1u32 << s.min(30)) > 0.25 && s < 30 {
        s += 1;
    }
    let scale = f64::from(1u32 << s);
    let a: Vec<[f64; 3]> = m
        .iter()
        .map(|r| [r[0] / scale, r[1] / scale, r[2] / scale])
        .collect();
    let mul = |x: &[[f64; 3]; 3], y: &[[f64; 3]; 3]| {
        let mut z = [[0.0; 3]; 3];
        for (i, zi) in z.iter_mut().enumerate() {
            for (j, zij) in zi.iter_mut().enumerate() {
                *zij = (0..3).map(|k| x[i][k] * y[k][j]).sum();
            }
        }
        z
    };
    let a = [a[0], a[1], a[2]];
    let mut result = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let mut term = result;
    for k in 1..=20 {
        term = mul(&term, &a);
        let kf = f64::from(k);
        term.iter_mut().flatten().for_each(|v| *v /= kf);
        result
            .iter_mut()
            .flatten()
            .zip(term.iter().flatten())
            .for_each(|(r, t)| *r += t);
    }
    for _ in 0..s {
        result = mul(&result, &result);
    }
    result
}
