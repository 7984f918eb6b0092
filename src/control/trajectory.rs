//! Desired end-effector trajectories: samples in time, linear between them.

use nalgebra::{DVector, SVector, Vector2};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Sampling interval of the built-in trajectories (s).
const SAMPLE_S: f64 = 0.01;
/// The longest sampled path, hold included (s): an hour of closed loop.
const MAX_DURATION_S: f64 = 3600.0;

/// A desired end-effector path `x_d(t)`: positions at increasing times,
/// linear in between, held before the first and after the last.
///
/// # Example
/// ```
/// use nalgebra::Vector2;
/// use softrod::control::Trajectory;
/// let t = Trajectory::new(&[0.0, 1.0], &[Vector2::new(0.2, 0.0), Vector2::new(0.2, 0.01)])?;
/// assert!((t.at(0.5)[1] - 0.005).abs() < 1e-15);
/// assert!(Trajectory::new::<2>(&[], &[]).is_err());
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Trajectory {
    /// Times (s), strictly increasing.
    pub times_s: Vec<f64>,
    /// Positions (m), one per time, all of one dimension (typed:
    /// [`Trajectory::point`]).
    pub points_m: Vec<Vec<f64>>,
}

impl Trajectory {
    /// A checked trajectory through the points `points_m` (m, `D`
    /// components each: 2 for a planar robot's tip, 3 for a platform) at
    /// the times `times_s` (s).
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector3;
    /// use softrod::control::Trajectory;
    /// let t = Trajectory::new(&[0.0, 2.0], &[Vector3::new(0.0, 0.0, 0.3), Vector3::new(0.01, 0.0, 0.3)])?;
    /// assert_eq!(t.dim(), 3);
    /// assert!((t.at(1.0)[0] - 0.005).abs() < 1e-15);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field: `trajectory.times_s`
    /// for an empty trajectory, `trajectory.points_m` for a count different
    /// from the times', `trajectory.points_m[i]` for a non-finite point or
    /// one of another dimension, `trajectory.times_s[i]` for a non-finite
    /// time or one not after the previous (time going backwards).
    pub fn new<const D: usize>(times_s: &[f64], points_m: &[SVector<f64, D>]) -> Result<Self> {
        Trajectory::from_rows(
            times_s.to_vec(),
            points_m.iter().map(|p| p.as_slice().to_vec()).collect(),
        )
    }

    /// A checked trajectory from rows as a scene holds them.
    pub(crate) fn from_rows(times_s: Vec<f64>, points_m: Vec<Vec<f64>>) -> Result<Self> {
        let t = Trajectory { times_s, points_m };
        t.validate()?;
        Ok(t)
    }

    /// The `i`-th sample point (m, [`Trajectory::dim`] components), or
    /// `None` past the end.
    ///
    /// # Example
    /// ```
    /// use nalgebra::{dvector, Vector2};
    /// use softrod::control::Trajectory;
    /// let t = Trajectory::new(&[0.0, 1.0], &[Vector2::new(0.2, 0.0), Vector2::new(0.2, 0.01)])?;
    /// assert_eq!(t.point(1), Some(dvector![0.2, 0.01]));
    /// assert_eq!(t.point(2), None);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn point(&self, i: usize) -> Option<DVector<f64>> {
        self.points_m.get(i).map(|p| DVector::from_column_slice(p))
    }

    /// Checks the fields (see [`Trajectory::new`]).
    ///
    /// # Errors
    /// As [`Trajectory::new`].
    pub fn validate(&self) -> Result<()> {
        if self.times_s.is_empty() {
            return Err(Error::invalid(
                "trajectory.times_s",
                "[]",
                "the trajectory is empty: give at least one point",
            ));
        }
        if self.points_m.len() != self.times_s.len() {
            return Err(Error::invalid(
                "trajectory.points_m",
                self.points_m.len(),
                format!("must have one point per time ({})", self.times_s.len()),
            ));
        }
        let dim = self.points_m[0].len();
        for (i, (t, p)) in self.times_s.iter().zip(&self.points_m).enumerate() {
            if p.is_empty() || p.len() != dim || p.iter().any(|v| !v.is_finite()) {
                return Err(Error::invalid(
                    format!("trajectory.points_m[{i}]"),
                    format!("{p:?}"),
                    format!("must be {dim} finite coordinates (m)"),
                ));
            }
            if !t.is_finite() {
                return Err(Error::invalid(
                    format!("trajectory.times_s[{i}]"),
                    t,
                    "must be finite",
                ));
            }
            if i > 0 && *t <= self.times_s[i - 1] {
                return Err(Error::invalid(
                    format!("trajectory.times_s[{i}]"),
                    t,
                    format!(
                        "must be after times_s[{}] = {} s (time cannot go backwards)",
                        i - 1,
                        self.times_s[i - 1]
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The dimension of the points.
    pub fn dim(&self) -> usize {
        self.points_m.first().map_or(0, Vec::len)
    }

    /// The last time (s).
    pub fn end_s(&self) -> f64 {
        self.times_s.last().copied().unwrap_or(0.0)
    }

    /// `x_d(t)` (m, [`Trajectory::dim`] components): linear between
    /// samples, held outside them (empty for an empty trajectory).
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::control::Trajectory;
    /// let t = Trajectory::new(&[0.0, 1.0], &[Vector2::new(0.2, 0.0), Vector2::new(0.2, 0.01)])?;
    /// assert!((t.at(0.5) - nalgebra::dvector![0.2, 0.005]).norm() < 1e-15);
    /// assert_eq!(t.at(-1.0), nalgebra::dvector![0.2, 0.0]); // held before the start
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn at(&self, t: f64) -> DVector<f64> {
        let i = self.times_s.partition_point(|&s| s <= t);
        if i == 0 {
            return DVector::from_vec(self.points_m.first().cloned().unwrap_or_default());
        }
        if i >= self.times_s.len() {
            return DVector::from_vec(self.points_m.last().cloned().unwrap_or_default());
        }
        let (t0, t1) = (self.times_s[i - 1], self.times_s[i]);
        let a = (t - t0) / (t1 - t0);
        DVector::from_iterator(
            self.points_m[i - 1].len(),
            self.points_m[i - 1]
                .iter()
                .zip(&self.points_m[i])
                .map(|(p, q)| p + a * (q - p)),
        )
    }

    /// Samples `f(τ)` for `τ` from 0 to `duration_s` after holding
    /// `f(0)` for `hold_s` (a start from rest).
    fn sampled(hold_s: f64, duration_s: f64, f: impl Fn(f64) -> Vec<f64>) -> Result<Self> {
        for (name, v) in [
            ("trajectory.hold_s", hold_s),
            ("trajectory.duration_s", duration_s),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(name, v, "must be finite and >= 0"));
            }
        }
        if hold_s + duration_s > MAX_DURATION_S {
            // the larger of the two is blamed, the other named
            let (name, v, other) = if hold_s > duration_s {
                ("trajectory.hold_s", hold_s, "trajectory.duration_s")
            } else {
                ("trajectory.duration_s", duration_s, "trajectory.hold_s")
            };
            return Err(Error::invalid(
                name,
                v,
                format!("with `{other}` at most {MAX_DURATION_S} s in all"),
            ));
        }
        let n = (duration_s / SAMPLE_S).ceil().min(1e7) as usize;
        let mut times = vec![0.0];
        let mut points = vec![f(0.0)];
        for k in 1..=n {
            let tau = (k as f64 * SAMPLE_S).min(duration_s);
            times.push(hold_s + tau);
            points.push(f(tau));
        }
        if hold_s > 0.0 && n == 0 {
            times.push(hold_s);
            points.push(f(0.0));
        }
        if hold_s > 0.0 && n > 0 {
            times.insert(1, hold_s);
            points.insert(1, f(0.0));
        }
        Trajectory::from_rows(times, points)
    }

    /// A circle of radius `radius_m` about `center_m` (2-D), counter-clockwise
    /// from the point at angle 0, one turn per `period_s`, for `duration_s`,
    /// after a hold of `hold_s` at the start point. The angle follows a
    /// smooth start (`θ(τ)` with zero speed at `τ = 0` over the first
    /// quarter period) so the path starts from rest.
    ///
    /// # Errors
    /// As [`Trajectory::new`]; [`Error::InvalidParameter`] for a period ≤ 0.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::control::Trajectory;
    /// let t = Trajectory::circle(Vector2::new(0.2, 0.0), 0.01, 4.0, 4.0, 1.0)?;
    /// // held at the point at angle 0 for the first second
    /// assert!((t.at(0.5) - nalgebra::dvector![0.21, 0.0]).norm() < 1e-15);
    /// assert!(Trajectory::circle(Vector2::new(0.2, 0.0), 0.01, 0.0, 4.0, 1.0).is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn circle(
        center_m: Vector2<f64>,
        radius_m: f64,
        period_s: f64,
        duration_s: f64,
        hold_s: f64,
    ) -> Result<Self> {
        let omega = angular_rate("trajectory.period_s", period_s)?;
        Trajectory::sampled(hold_s, duration_s, |tau| {
            let th = smooth_phase(omega, period_s / 4.0, tau);
            vec![
                center_m[0] + radius_m * th.cos(),
                center_m[1] + radius_m * th.sin(),
            ]
        })
    }

    /// A figure-eight (lemniscate of Gerono) of half-width `size_m` about
    /// `center_m`: `x = c + a sin θ`, `y = c + (a/2) sin 2θ`, one loop pair
    /// per `period_s`, smooth start as [`Trajectory::circle`].
    ///
    /// # Errors
    /// As [`Trajectory::circle`].
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::control::Trajectory;
    /// let t = Trajectory::figure_eight(Vector2::new(0.2, 0.0), 0.01, 4.0, 4.0, 0.0)?;
    /// assert!((t.at(0.0) - nalgebra::dvector![0.2, 0.0]).norm() < 1e-15);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn figure_eight(
        center_m: Vector2<f64>,
        size_m: f64,
        period_s: f64,
        duration_s: f64,
        hold_s: f64,
    ) -> Result<Self> {
        let omega = angular_rate("trajectory.period_s", period_s)?;
        Trajectory::sampled(hold_s, duration_s, |tau| {
            let th = smooth_phase(omega, period_s / 4.0, tau);
            vec![
                center_m[0] + size_m * th.sin(),
                center_m[1] + 0.5 * size_m * (2.0 * th).sin(),
            ]
        })
    }

    /// Back and forth on the segment `from_m`–`to_m`, one return trip per
    /// `period_s` (`x = a + (b − a)(1 − cos ωτ)/2`: at rest at both ends).
    ///
    /// # Errors
    /// As [`Trajectory::circle`].
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::control::Trajectory;
    /// let t = Trajectory::line(Vector2::new(0.2, 0.0), Vector2::new(0.2, 0.02), 2.0, 2.0, 0.0)?;
    /// // half a period: at the far end
    /// assert!((t.at(1.0) - nalgebra::dvector![0.2, 0.02]).norm() < 1e-12);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn line(
        from_m: Vector2<f64>,
        to_m: Vector2<f64>,
        period_s: f64,
        duration_s: f64,
        hold_s: f64,
    ) -> Result<Self> {
        let omega = angular_rate("trajectory.period_s", period_s)?;
        Trajectory::sampled(hold_s, duration_s, |tau| {
            let a = 0.5 * (1.0 - (omega * tau).cos());
            vec![
                from_m[0] + a * (to_m[0] - from_m[0]),
                from_m[1] + a * (to_m[1] - from_m[1]),
            ]
        })
    }
}

fn angular_rate(name: &str, period_s: f64) -> Result<f64> {
    if !(period_s.is_finite() && period_s > 0.0) {
        return Err(Error::invalid(name, period_s, "must be finite and > 0"));
    }
    Ok(2.0 * std::f64::consts::PI / period_s)
}

/// A phase that starts at rest: `θ = ω τ²/(2 T)` for `τ < T`, then `ω (τ − T/2)`
/// (continuous in value and rate).
fn smooth_phase(omega: f64, ramp_s: f64, tau: f64) -> f64 {
    if tau < ramp_s {
        omega * tau * tau / (2.0 * ramp_s)
    } else {
        omega * (tau - 0.5 * ramp_s)
    }
}
