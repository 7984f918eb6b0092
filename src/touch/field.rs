//! The artificial potential field of the paper's obstacle avoidance
//! (36)–(44), on the shape `q` of a planar robot:
//!
//! - attractive (36): `U_att = ζ |x_e − x_goal|` on the end effector, its
//!   gradient (37) `ζ (x_e − x_goal) / |x_e − x_goal|`;
//! - repulsive (38): `U_rep = Σ_i α_r (1/d_i − 1/Q0)²` over the control
//!   points `x_ci`, on every element the point closest to an obstacle point
//!   `x_obs`, if `d_i = |x_ci − x_obs| < Q0`. Its exact gradient is
//!   `∂U_rep/∂x_ci = −2 α_r (1/d_i − 1/Q0) (x_ci − x_obs) / d_i³`; the
//!   paper's (39) (`α (1/Q0 − 1/d) (x − x_obs)/d^{3/2}`) is not the gradient
//!   of (38) (a power and the factor 2 differ). `tests/touch.rs` checks
//!   this one by finite differences.
//!
//! `∂U/∂q` (41) chains these through `∂x/∂q = S(X)` (16) at the control
//! points' fixed arc coordinates: each control point minimizes its
//! distance along its element, so moving it along the element changes `d`
//! to second order only (at an interior minimum) and the gradient at fixed
//! `X` is the total one.

use nalgebra::{DVector, Vector2};
use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::element::{ArcPoint, Element, PlanarCable};
use crate::error::{Error, Result, check_len, check_positive};

/// The paper's parameters of (36)–(44) (SI units), with a documented
/// default each: `Q0 = 10 cm`, `α_r = 0.02`, `ζ = 200`, `v_d = 5 mm/s`.
///
/// # Example
/// ```
/// let p = softrod::touch::FieldParams::default();
/// assert_eq!((p.q0_m, p.alpha_r, p.zeta, p.v_d_m_per_s), (0.1, 0.02, 200.0, 0.005));
/// p.validate()?;
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FieldParams {
    /// Range of the repulsive field `Q0` (m, default 0.1).
    pub q0_m: f64,
    /// Repulsive gain `α_r` (N·m… the unit of `U` is arbitrary; default 0.02).
    pub alpha_r: f64,
    /// Attractive gain `ζ` (per m, default 200).
    pub zeta: f64,
    /// Speed of the end effector the step `β` (44) is set for (m/s, default 0.005).
    pub v_d_m_per_s: f64,
}

impl Default for FieldParams {
    fn default() -> Self {
        FieldParams {
            q0_m: 0.1,
            alpha_r: 0.02,
            zeta: 200.0,
            v_d_m_per_s: 0.005,
        }
    }
}

impl FieldParams {
    /// Checks every field (finite, > 0).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `field.<name>`.
    pub fn validate(&self) -> Result<()> {
        check_positive("field.q0_m", self.q0_m)?;
        check_positive("field.alpha_r", self.alpha_r)?;
        check_positive("field.zeta", self.zeta)?;
        check_positive("field.v_d_m_per_s", self.v_d_m_per_s)
    }
}

/// The repulsive potential (38) of one control point at distance `d` (m)
/// and its gradient with respect to the point, `(U, ∂U/∂x)`; zero beyond
/// `Q0`.
///
/// # Example
/// ```
/// use nalgebra::Vector2;
/// use softrod::touch::{repulsive, FieldParams};
/// let p = FieldParams::default();
/// let (u, g) = repulsive(&p, Vector2::new(0.05, 0.0), Vector2::zeros());
/// assert!((u - 0.02 * (20.0f64 - 10.0).powi(2)).abs() < 1e-12);
/// assert!(g.x < 0.0); // the potential falls away from the obstacle
/// assert_eq!(repulsive(&p, Vector2::new(0.2, 0.0), Vector2::zeros()), (0.0, Vector2::zeros()));
/// ```
pub fn repulsive(p: &FieldParams, x: Vector2<f64>, x_obs: Vector2<f64>) -> (f64, Vector2<f64>) {
    let r = x - x_obs;
    let d = r.x.hypot(r.y);
    if d.is_nan() || d >= p.q0_m || d <= 0.0 {
        return (0.0, Vector2::zeros());
    }
    let a = 1.0 / d - 1.0 / p.q0_m;
    let c = -2.0 * p.alpha_r * a / (d * d * d);
    (p.alpha_r * a * a, r * c)
}

/// The closest point of element `e` of the shape `q` to `x`: `(ξ, point,
/// distance)`, by sampling then Newton on `ξ` (the end points included).
pub(crate) fn closest_on_element(
    robot: &Robot<PlanarCable>,
    q: &[f64],
    e: usize,
    x: [f64; 2],
) -> Result<(f64, [f64; 2], f64)> {
    let le = robot.elements()[e].length();
    let at = |xi: f64| -> Result<([f64; 2], [f64; 2])> {
        let p = ArcPoint::new(e, xi, le);
        let (mut r, mut t) = ([0.0; 2], [0.0; 2]);
        p.value_into(q, &mut r)?;
        p.slope_into(q, &mut t)?;
        Ok((r, t))
    };
    let dist = |r: [f64; 2]| (r[0] - x[0]).hypot(r[1] - x[1]);
    let mut best = (0.0, at(0.0)?.0);
    for k in 1..=16 {
        let xi = k as f64 / 16.0;
        let r = at(xi)?.0;
        if dist(r) < dist(best.1) {
            best = (xi, r);
        }
    }
    // Newton on (r − x)·r' = 0, the slope per unit ξ being L_e r'
    let mut xi = best.0;
    for _ in 0..20 {
        let h = 1e-7;
        let f = |xi: f64| -> Result<f64> {
            let (r, t) = at(xi)?;
            Ok((r[0] - x[0]) * t[0] + (r[1] - x[1]) * t[1])
        };
        let f0 = f(xi)?;
        let df = (f((xi + h).min(1.0))? - f((xi - h).max(0.0))?)
            / ((xi + h).min(1.0) - (xi - h).max(0.0))
            / le;
        if !(df.is_finite() && df > 0.0) {
            break;
        }
        let next = (xi - f0 / (df * le)).clamp(0.0, 1.0);
        let done = (next - xi).abs() < 1e-13;
        xi = next;
        if done {
            break;
        }
    }
    let r = at(xi)?.0;
    let (xi, r) = if dist(r) <= dist(best.1) {
        (xi, r)
    } else {
        best
    };
    Ok((xi, r, dist(r)))
}

/// The total potential `U_t = U_att + U_rep` (36), (38) at the shape `q`
/// (J), and its gradient `∂U_t/∂q` over all `n_q` coordinates (41).
///
/// # Errors
/// [`Error::DimensionMismatch`] for a `q` of the wrong length;
/// [`Error::InvalidParameter`] for invalid parameters or a non-finite goal.
///
/// # Example
/// At the goal only the repulsion acts:
/// ```
/// use softrod::touch::{field_gradient, five_section_scene, FieldParams};
/// let robot = five_section_scene(4).robot()?;
/// let q = robot.reference_configuration();
/// let tip = robot.position_at(q.as_slice(), robot.length())?;
/// let goal = nalgebra::Vector2::new(tip[0], tip[1] + 0.01);
/// let (u, g) = field_gradient(&robot, q.as_slice(), &FieldParams::default(), goal, &[])?;
/// assert!((u - 200.0 * 0.01).abs() < 1e-9 && g.len() == robot.n_q());
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn field_gradient(
    robot: &Robot<PlanarCable>,
    q: &[f64],
    p: &FieldParams,
    goal_m: Vector2<f64>,
    obstacles_m: &[Vector2<f64>],
) -> Result<(f64, DVector<f64>)> {
    p.validate()?;
    check_len("q", robot.n_q(), q.len())?;
    if !goal_m.iter().all(|v| v.is_finite()) {
        return Err(Error::invalid(
            "goal_m",
            format!("[{}, {}]", goal_m.x, goal_m.y),
            "must be finite",
        ));
    }
    let mut g = DVector::zeros(q.len());
    let add = |g: &mut DVector<f64>, p: &ArcPoint, dx: Vector2<f64>| {
        for k in 0..4 {
            let node = p.element + k / 2;
            for (d, v) in dx.iter().enumerate() {
                g[node * 4 + (k % 2) * 2 + d] += p.values[k] * v;
            }
        }
    };
    // (36), (37)
    let n_el = robot.n_elements();
    let tip = ArcPoint::new(n_el - 1, 1.0, robot.elements()[n_el - 1].length());
    let mut xe = [0.0; 2];
    tip.value_into(q, &mut xe)?;
    let r = [xe[0] - goal_m[0], xe[1] - goal_m[1]];
    let dist = r[0].hypot(r[1]);
    let mut u = p.zeta * dist;
    if dist > 0.0 {
        add(
            &mut g,
            &tip,
            Vector2::new(p.zeta * r[0] / dist, p.zeta * r[1] / dist),
        );
    }
    // (38) with its exact gradient
    for x_obs in obstacles_m {
        for e in 0..n_el {
            let (xi, xc, d) = closest_on_element(robot, q, e, (*x_obs).into())?;
            if d >= p.q0_m {
                continue;
            }
            let (ur, gr) = repulsive(p, Vector2::from(xc), *x_obs);
            u += ur;
            add(
                &mut g,
                &ArcPoint::new(e, xi, robot.elements()[e].length()),
                gr,
            );
        }
    }
    Ok((u, g))
}
