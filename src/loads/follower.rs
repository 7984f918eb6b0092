//! A follower load: a pressure normal to the deformed backbone.
//!
//! A pressure `p` (N/m: force per deformed length) on the piece
//! `[s_start_m, s_end_m]` of a planar rod pushes along the normal
//! `n = e_z × t` (the tangent turned a quarter counter-clockwise), so the
//! force per undeformed length is `f(X) = p J r'(X)`, `J = [[0, −1], [1, 0]]`
//! (`|r'|` converts deformed into undeformed length). With
//! `r'(X) = S'(X) q` this is linear in the coordinates, and its
//! generalized force is `Q = C q`, `C = p ∫ Sᵀ J S' dX`: a constant matrix
//! that is not symmetric. By parts,
//! `C − Cᵀ = p [Sᵀ J S]` at the piece's two ends, so the load is
//! conservative inside the piece and non-conservative only through its end
//! points (on a cantilever whose tip is loaded: the tip, as for Beck's
//! column). The stiffness `−∂Q/∂q = −C` enters the tangent.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_finite};

/// A pressure normal to the deformed backbone of a planar rod, over the
/// undeformed arc interval `[s_start_m, s_end_m]` (the whole rod when both
/// are left out).
///
/// Positive `pressure_n_per_m` pushes toward the left of the direction of
/// travel from base to tip (`+y` on a rod along `+x`); the force per
/// deformed length is `pressure_n_per_m`, turning with the backbone. A
/// small follower load deflects a cantilever as the dead load
/// `p e_y` does (to first order); at large deflection it stays normal.
///
/// # Example
/// ```
/// use softrod::loads::{FollowerLoad, Loads};
/// let f: FollowerLoad = serde_json::from_str(r#"{"pressure_n_per_m": -2.0}"#).unwrap();
/// assert_eq!(f.interval(0.24), (0.0, 0.24));
/// let loads = Loads { follower_loads: vec![f], ..Loads::default() };
/// assert_eq!(loads.scaled(0.5).follower_loads[0].pressure_n_per_m, -1.0);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FollowerLoad {
    /// Pressure: force per deformed length along the left normal (N/m).
    pub pressure_n_per_m: f64,
    /// Start of the loaded piece (m, undeformed arc coordinate; 0 if absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub s_start_m: Option<f64>,
    /// End of the loaded piece (m; the robot's length if absent).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub s_end_m: Option<f64>,
}

impl FollowerLoad {
    /// The loaded interval `(start, end)` (m) on a robot of length `total`.
    pub fn interval(&self, total: f64) -> (f64, f64) {
        (self.s_start_m.unwrap_or(0.0), self.s_end_m.unwrap_or(total))
    }

    /// Checks the values on a robot of length `total` (m); fields are named
    /// `name.field` (or `field` for an empty `name`).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a non-finite pressure, an end off
    /// `[0, total]` or an empty interval.
    pub fn validate(&self, name: &str, total: f64) -> Result<()> {
        let path = |f: &str| {
            if name.is_empty() {
                f.to_string()
            } else {
                format!("{name}.{f}")
            }
        };
        check_finite(&path("pressure_n_per_m"), self.pressure_n_per_m)?;
        let tol = 1e-12 * total;
        let (a, b) = self.interval(total);
        for (field, v) in [("s_start_m", a), ("s_end_m", b)] {
            if !(v >= -tol && v <= total + tol) {
                return Err(super::outside(&path(field), v, total));
            }
        }
        if b <= a {
            return Err(Error::invalid(
                path("s_end_m"),
                b,
                format!("must be greater than s_start_m = {a} m"),
            ));
        }
        Ok(())
    }
}

/// `C_kl = ∫ s_k(X) s_l'(X) dX` over the part `[x0, x1]` of an element of
/// length `le` (local coordinates, `0 <= x0 < x1 <= le`), by a Gauss rule
/// exact for the quintic integrand.
pub(crate) fn shape_slope_gram(
    shape: impl Fn(f64) -> ([f64; 4], [f64; 4]),
    rule: &crate::quadrature::GaussRule,
    le: f64,
    x0: f64,
    x1: f64,
) -> [[f64; 4]; 4] {
    let mut c = [[0.0; 4]; 4];
    let h = x1 - x0;
    for (xi, w) in rule.iter() {
        let (s, d1) = shape((x0 + xi * h) / le);
        for k in 0..4 {
            for l in 0..4 {
                c[k][l] += w * h * s[k] * d1[l];
            }
        }
    }
    c
}
