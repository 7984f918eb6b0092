//! Can an object be held? Quasi-static Coulomb friction as a second-order
//! cone program.
//!
//! A rigid planar object of mass `m` under gravity `g` touches the fingers
//! at points `p_i` with inward unit normals `n_i` (pointing into the
//! object) and tangents `t_i = (−n_iy, n_ix)`. At contact `i` the finger
//! pushes with a normal force `λ_i` and a friction force `τ_i`:
//!
//! ```text
//! f_i = λ_i n_i + τ_i t_i,   |τ_i| ≤ μ λ_i  (the friction cone, a 2-D SOC),
//! 0 ≤ λ_i ≤ N_i              (the squeeze the finger can give there),
//! Σ f_i + s m g = 0,  Σ (p_i − c) × f_i = 0     (forces and moment about the
//!                                                centre of mass c)
//! ```
//!
//! and the program maximizes the weight factor `s ≥ 0`. The object can be
//! held iff `s_max ≥ 1`; `s_max · m` is the heaviest object of the same
//! geometry the same squeeze holds. `N_i` are the normal forces of the
//! frictionless squeeze (the contact solve of the fingers around the
//! object): friction can use them, not exceed them.
//!
//! Closed forms (tested below): a block between two flat vertical jaws,
//! each pressing with `N`, holds iff `2 μ N ≥ m g`. A disc pinched by two
//! jaws that touch it at points at elevation `θ` above its centre
//! (`θ < 0`: below), normals tilted by `θ` from the horizontal squeeze,
//! holds iff `2 N (μ cos θ − sin θ) ≥ m g` (derived in
//! [`disc_pinch_threshold_n`]).
//!
//! # Example
//! ```
//! use softrod::grasp::friction::{hold_check, FrictionContact};
//! // a 100 g block pinched with 1 N per side, μ = 0.5: 2 μ N = 1 N ≥ 0.981 N
//! let jaws = [
//!     FrictionContact { point_m: [-0.02, 0.0], normal: [1.0, 0.0], max_normal_force_n: 1.0 },
//!     FrictionContact { point_m: [0.02, 0.0], normal: [-1.0, 0.0], max_normal_force_n: 1.0 },
//! ];
//! let g = nalgebra::Vector2::new(0.0, -9.81);
//! let h = hold_check(&jaws, 0.1, nalgebra::Vector2::zeros(), 0.5, g)?;
//! assert!(h.holds && (h.weight_factor - 1.0 / 0.981).abs() < 1e-6);
//! # Ok::<(), softrod::Error>(())
//! ```

use clarabel::algebra::CscMatrix;
use clarabel::solver::{NonnegativeConeT, SecondOrderConeT, SupportedConeT, ZeroConeT};

use crate::cone::{self, Failure, Tolerances};
use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_all_finite, check_len};

/// The largest weight factor the program looks for: an object in a cup of
/// contacts that can carry any weight reports this value.
pub const WEIGHT_FACTOR_CAP: f64 = 1.0e6;

/// One contact between a finger and the object.
///
/// # Example
/// ```
/// let c = softrod::grasp::friction::FrictionContact { point_m: [0.0, 0.0], normal: [1.0, 0.0], max_normal_force_n: 2.0 };
/// assert_eq!(c.normal, [1.0, 0.0]);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrictionContact {
    /// Contact point on the object's surface (m).
    pub point_m: [f64; 2],
    /// Unit normal pointing into the object: the direction of the finger's push.
    pub normal: [f64; 2],
    /// The largest normal force the finger gives there (N, `>= 0`).
    pub max_normal_force_n: f64,
}

impl FrictionContact {
    /// The contact point as a vector (m; the field `point_m`).
    ///
    /// # Example
    /// ```
    /// let c = softrod::grasp::friction::FrictionContact { point_m: [0.02, 0.0], normal: [-1.0, 0.0], max_normal_force_n: 1.0 };
    /// assert_eq!((c.point(), c.unit_normal()), (nalgebra::Vector2::new(0.02, 0.0), -nalgebra::Vector2::x()));
    /// ```
    pub fn point(&self) -> Vector2<f64> {
        self.point_m.into()
    }

    /// The unit normal into the object as a vector (the field `normal`).
    ///
    /// # Example
    /// See [`FrictionContact::point`].
    pub fn unit_normal(&self) -> Vector2<f64> {
        self.normal.into()
    }
}

/// The answer of [`hold_check`].
///
/// # Example
/// See [`hold_check`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HoldCheck {
    /// Whether the weight is balanced inside the friction cones: `weight_factor >= 1`.
    pub holds: bool,
    /// The largest multiple of the weight the contacts balance (capped at
    /// [`WEIGHT_FACTOR_CAP`]).
    pub weight_factor: f64,
    /// Normal force per contact at that largest weight (N).
    pub normal_forces_n: Vec<f64>,
    /// Friction force per contact at that largest weight (N, along `t = (−n_y, n_x)`).
    pub friction_forces_n: Vec<f64>,
}

impl HoldCheck {
    /// The heaviest object of the same geometry this squeeze holds (kg):
    /// `weight_factor · mass_kg`.
    pub fn holding_mass_kg(&self, mass_kg: f64) -> f64 {
        self.weight_factor * mass_kg
    }

    /// The force on the object at each of `contacts` (the check's input,
    /// same order) as a vector (N): `λ_i n_i + τ_i t_i` with the fields
    /// `normal_forces_n` and `friction_forces_n`, `t = (−n_y, n_x)`.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `contacts` is not the check's list.
    ///
    /// # Example
    /// ```
    /// use softrod::grasp::friction::{hold_check, FrictionContact};
    /// use nalgebra::Vector2;
    /// let jaws = [
    ///     FrictionContact { point_m: [-0.01, 0.0], normal: [1.0, 0.0], max_normal_force_n: 5.0 },
    ///     FrictionContact { point_m: [0.01, 0.0], normal: [-1.0, 0.0], max_normal_force_n: 5.0 },
    /// ];
    /// let h = hold_check(&jaws, 0.1, Vector2::zeros(), 0.5, Vector2::new(0.0, -9.81))?;
    /// let total: Vector2<f64> = h.forces(&jaws)?.iter().sum();
    /// // at the largest weight the contacts carry `weight_factor` times the weight
    /// assert!((total.y - h.weight_factor * 0.1 * 9.81).abs() < 1e-4 * total.y);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn forces(&self, contacts: &[FrictionContact]) -> Result<Vec<Vector2<f64>>> {
        check_len("contacts", self.normal_forces_n.len(), contacts.len())?;
        Ok(contacts
            .iter()
            .zip(self.normal_forces_n.iter().zip(&self.friction_forces_n))
            .map(|(c, (l, t))| {
                let n = c.unit_normal();
                n * *l + Vector2::new(-n.y, n.x) * *t
            })
            .collect())
    }
}

/// Decides whether the object (mass `mass_kg`, centre of mass `com_m`,
/// friction coefficient `mu`) is held by `contacts` under gravity
/// `gravity_m_per_s2` (see the module docs for the program).
///
/// # Errors
/// [`Error::InvalidParameter`] naming the field: `mass_kg <= 0`, `mu < 0`,
/// a zero gravity, a normal that is not a unit vector
/// (`contacts[i].normal`), a negative or non-finite force bound, anything
/// not finite; [`Error::InvalidParameter`] (field `hold_check`) if
/// clarabel does not solve the program (it always has the feasible point
/// `s = 0`).
///
/// # Example
/// ```
/// use softrod::grasp::friction::{hold_check, FrictionContact};
/// let jaws = [
///     FrictionContact { point_m: [-0.02, 0.0], normal: [1.0, 0.0], max_normal_force_n: 1.0 },
///     FrictionContact { point_m: [0.02, 0.0], normal: [-1.0, 0.0], max_normal_force_n: 1.0 },
/// ];
/// // 2 μ N = 0.8 N < m g = 0.981 N: it slips
/// let g = nalgebra::Vector2::new(0.0, -9.81);
/// let h = hold_check(&jaws, 0.1, nalgebra::Vector2::zeros(), 0.4, g)?;
/// assert!(!h.holds);
/// assert!(hold_check(&jaws, 0.1, nalgebra::Vector2::zeros(), -0.1, g).is_err());
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn hold_check(
    contacts: &[FrictionContact],
    mass_kg: f64,
    com_m: Vector2<f64>,
    mu: f64,
    gravity_m_per_s2: Vector2<f64>,
) -> Result<HoldCheck> {
    let (com_m, gravity_m_per_s2): ([f64; 2], [f64; 2]) = (com_m.into(), gravity_m_per_s2.into());
    if !(mass_kg.is_finite() && mass_kg > 0.0) {
        return Err(Error::invalid("mass_kg", mass_kg, "must be finite and > 0"));
    }
    if !(mu.is_finite() && mu >= 0.0) {
        return Err(Error::invalid("mu", mu, "must be finite and >= 0"));
    }
    check_all_finite("com_m", &com_m)?;
    check_all_finite("gravity_m_per_s2", &gravity_m_per_s2)?;
    if gravity_m_per_s2 == [0.0, 0.0] {
        return Err(Error::invalid(
            "gravity_m_per_s2",
            "[0, 0]",
            "must not be zero",
        ));
    }
    for (i, c) in contacts.iter().enumerate() {
        check_all_finite(&format!("contacts[{i}].point_m"), &c.point_m)?;
        let n = c.normal;
        let len = (n[0] * n[0] + n[1] * n[1]).sqrt();
        let unit = (len - 1.0).abs() < 1e-9;
        if !unit {
            return Err(Error::invalid(
                format!("contacts[{i}].normal"),
                format!("{n:?}"),
                "must be a unit vector",
            ));
        }
        if !(c.max_normal_force_n.is_finite() && c.max_normal_force_n >= 0.0) {
            return Err(Error::invalid(
                format!("contacts[{i}].max_normal_force_n"),
                c.max_normal_force_n,
                "must be finite and >= 0",
            ));
        }
    }
    let k = contacts.len();
    if k == 0 {
        return Ok(HoldCheck {
            holds: false,
            weight_factor: 0.0,
            normal_forces_n: Vec::new(),
            friction_forces_n: Vec::new(),
        });
    }
    // scale forces by the weight so the program is O(1)
    let weight = mass_kg * (gravity_m_per_s2[0].hypot(gravity_m_per_s2[1]));
    let gdir = [
        mass_kg * gravity_m_per_s2[0] / weight,
        mass_kg * gravity_m_per_s2[1] / weight,
    ];
    // a length scale for the moment row
    let ell = contacts
        .iter()
        .map(|c| (c.point_m[0] - com_m[0]).hypot(c.point_m[1] - com_m[1]))
        .fold(0.0, f64::max)
        .max(1e-12);
    // x = [λ_0, τ_0, …, λ_{k−1}, τ_{k−1}, s]
    let nx = 2 * k + 1;
    let is = 2 * k;
    let (mut ri, mut ci, mut vi) = (Vec::new(), Vec::new(), Vec::new());
    let mut b = Vec::new();
    let mut push = |r: usize, c: usize, v: f64| {
        if v != 0.0 {
            ri.push(r);
            ci.push(c);
            vi.push(v);
        }
    };
    // zero cone: forces (2 rows) and the moment (1 row)
    for (i, c) in contacts.iter().enumerate() {
        let n = c.normal;
        let t = [-n[1], n[0]];
        let r = [c.point_m[0] - com_m[0], c.point_m[1] - com_m[1]];
        for d in 0..2 {
            push(d, 2 * i, n[d]);
            push(d, 2 * i + 1, t[d]);
        }
        push(2, 2 * i, (r[0] * n[1] - r[1] * n[0]) / ell);
        push(2, 2 * i + 1, (r[0] * t[1] - r[1] * t[0]) / ell);
    }
    push(0, is, gdir[0]);
    push(1, is, gdir[1]);
    b.extend([0.0; 3]);
    // nonnegative: N_i/W − λ_i ≥ 0, cap − s ≥ 0
    let mut row = 3;
    for (i, c) in contacts.iter().enumerate() {
        push(row, 2 * i, 1.0);
        b.push(c.max_normal_force_n / weight);
        row += 1;
    }
    push(row, is, 1.0);
    b.push(WEIGHT_FACTOR_CAP);
    row += 1;
    // second-order cones: (μ λ_i, τ_i)
    for i in 0..k {
        push(row, 2 * i, -mu);
        push(row + 1, 2 * i + 1, -1.0);
        b.extend([0.0, 0.0]);
        row += 2;
    }
    let m = row;
    let mut cones: Vec<SupportedConeT<f64>> = vec![ZeroConeT(3), NonnegativeConeT(k + 1)];
    cones.extend((0..k).map(|_| SecondOrderConeT(2)));
    let a = CscMatrix::new_from_triplets(m, nx, ri, ci, vi);
    let p = CscMatrix::zeros((nx, nx));
    let mut q = vec![0.0; nx];
    q[is] = -1.0;
    let x = solve_cone_program("hold_check", &p, &q, &a, &b, &cones, 1e-10)?;
    let s = x[is].clamp(0.0, WEIGHT_FACTOR_CAP);
    Ok(HoldCheck {
        // the interior-point tolerance: a threshold case within 1e-8 holds
        holds: s >= 1.0 - 1e-8,
        weight_factor: s,
        normal_forces_n: (0..k).map(|i| x[2 * i] * weight).collect(),
        friction_forces_n: (0..k).map(|i| x[2 * i + 1] * weight).collect(),
    })
}

/// The closed form of a disc pinched symmetrically: the weight (N) that two
/// contacts at elevation `theta_rad` above the centre, each with normal
/// force up to `max_normal_force_n`, hold with friction `mu`.
///
/// Derivation: left contact at `R(−cos θ, sin θ)`, inward normal
/// `n = (cos θ, −sin θ)`, tangent `t = (sin θ, cos θ)`; the right one mirrored.
/// The horizontal balance gives `λ_L = λ_R = λ`, the moment about the centre
/// (normals pass through it) `τ_L = τ_R = τ`, and the vertical balance
/// `2 (τ cos θ − λ sin θ) = m g`. With `|τ| ≤ μ λ`, `λ ≤ N`, the left side is
/// at most `2 N (μ cos θ − sin θ)` (when that is positive, else 0).
///
/// # Example
/// ```
/// use softrod::grasp::friction::disc_pinch_threshold_n;
/// assert!((disc_pinch_threshold_n(0.5, 2.0, 0.0) - 2.0).abs() < 1e-15); // 2 μ N
/// ```
pub fn disc_pinch_threshold_n(mu: f64, max_normal_force_n: f64, theta_rad: f64) -> f64 {
    (2.0 * max_normal_force_n * (mu * theta_rad.cos() - theta_rad.sin())).max(0.0)
}

/// Solves the cone program `min ½xᵀPx + qᵀx` s.t. `b − Ax ∈ cones` with
/// clarabel (gap tolerance `tol_gap_abs`, relative gap and feasibility
/// 1e-10, 200 iterations) and returns `x`; `what` names the program in the
/// error when clarabel rejects it or does not solve it.
pub(crate) fn solve_cone_program(
    what: &str,
    p: &CscMatrix<f64>,
    q: &[f64],
    a: &CscMatrix<f64>,
    b: &[f64],
    cones: &[SupportedConeT<f64>],
    tol_gap_abs: f64,
) -> Result<Vec<f64>> {
    let tol = Tolerances {
        gap_abs: tol_gap_abs,
        ..Tolerances::all(1e-10)
    };
    match cone::solve(p, q, a, b, cones, tol) {
        Ok(sol) => Ok(sol.x),
        Err(Failure::Rejected(e)) => Err(Error::invalid(what, e, "clarabel rejected the program")),
        Err(Failure::Status(s)) => Err(Error::invalid(
            what,
            format!("{s:?}"),
            "clarabel did not solve the program",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp::fixtures::{disc_pinch, flat_jaws};

    const G: [f64; 2] = [0.0, -9.81];

    fn jaws(n: f64) -> [FrictionContact; 2] {
        flat_jaws(0.03, [0.01, 0.01], n)
    }

    #[test]
    fn block_between_flat_jaws_holds_iff_two_mu_n_ge_mg() {
        // the jaws' line of action passes 1 cm above the centre of mass:
        // no moment from it, the closed form is unchanged
        for &(mu, n) in &[(0.3, 2.0), (0.8, 0.5), (0.5, 1.0)] {
            let threshold = 2.0 * mu * n / 9.81; // kg
            let h = hold_check(&jaws(n), threshold, Vector2::zeros(), mu, G.into()).unwrap();
            assert!((h.weight_factor - 1.0).abs() < 1e-7, "{h:?}");
            for (m, expect) in [(threshold * 0.99, true), (threshold * 1.01, false)] {
                let h = hold_check(&jaws(n), m, Vector2::zeros(), mu, G.into()).unwrap();
                assert_eq!(h.holds, expect, "mu {mu} n {n} m {m}: {h:?}");
            }
        }
    }

    #[test]
    fn disc_pinched_off_the_normal_matches_the_closed_form() {
        let (mu, n, r) = (0.5, 2.0, 0.03);
        // elevation above the centre: below helps, above hurts; atan(μ) ≈ 26.6° is the limit
        for &theta in &[-0.6, -0.2, 0.0, 0.2, 0.4] {
            let contacts = disc_pinch(r, theta, n);
            let w = disc_pinch_threshold_n(mu, n, theta);
            assert!(w > 0.0);
            let m = w / 9.81;
            let h = hold_check(&contacts, m, Vector2::zeros(), mu, G.into()).unwrap();
            assert!((h.weight_factor - 1.0).abs() < 1e-7, "θ {theta}: {h:?}");
            assert!(
                hold_check(&contacts, 0.99 * m, Vector2::zeros(), mu, G.into())
                    .unwrap()
                    .holds
            );
            assert!(
                !hold_check(&contacts, 1.01 * m, Vector2::zeros(), mu, G.into())
                    .unwrap()
                    .holds
            );
        }
        // above atan(μ) nothing is held, however light
        let theta: f64 = 0.5;
        assert!(theta > mu.atan());
        assert_eq!(disc_pinch_threshold_n(mu, n, theta), 0.0);
        let h = hold_check(
            &disc_pinch(r, theta, n),
            1e-3,
            Vector2::zeros(),
            mu,
            G.into(),
        )
        .unwrap();
        assert!(!h.holds && h.weight_factor < 1e-6, "{h:?}");
    }

    #[test]
    fn a_thin_rod_pinched_at_unequal_heights_matches_the_closed_form() {
        // a rod of width w, contacts on its faces at heights ±d/2 about its
        // centre of mass: the normals' couple N d must come from friction on
        // the lever w: (w/2)(τ_R − τ_L) with τ_L + τ_R = m g, |τ| ≤ μ N, so
        // it holds iff N (μ w − d) ≥ w m g / 2, i.e. m ≤ 2 N (μ w − d)/(w g)
        let (w, mu, n) = (0.003, 0.5, 0.7);
        for d in [0.0, 0.0005, 0.001, 0.0014] {
            let rod = flat_jaws(0.5 * w, [0.5 * d, -0.5 * d], n);
            let m = 2.0 * n * (mu * w - d) / (w * 9.81);
            let h = hold_check(&rod, m, Vector2::zeros(), mu, G.into()).unwrap();
            assert!((h.weight_factor - 1.0).abs() < 1e-6, "d {d}: {h:?}");
        }
        // d ≥ μ w: nothing is held, however light (the ruler's 5 mm offset)
        let rod = flat_jaws(0.5 * w, [0.0025, -0.0025], n);
        let h = hold_check(&rod, 1e-3, Vector2::zeros(), mu, G.into()).unwrap();
        assert!(!h.holds && h.weight_factor < 1e-6, "{h:?}");
    }

    #[test]
    fn frictionless_jaws_hold_nothing_and_a_cup_holds_anything() {
        let h = hold_check(&jaws(10.0), 0.01, Vector2::zeros(), 0.0, G.into()).unwrap();
        assert!(!h.holds && h.weight_factor < 1e-6);
        // a support from below through the centre of mass: any weight
        let cup = [FrictionContact {
            point_m: [0.0, -0.02],
            normal: [0.0, 1.0],
            max_normal_force_n: 1.0,
        }];
        let h = hold_check(&cup, 0.05, Vector2::zeros(), 0.0, G.into()).unwrap();
        assert!(h.holds && (h.weight_factor - 1.0 / (0.05 * 9.81)).abs() < 1e-6);
        // off the centre of mass one contact cannot balance the moment
        let off = [FrictionContact {
            point_m: [0.01, -0.02],
            normal: [0.0, 1.0],
            max_normal_force_n: 1.0,
        }];
        assert!(
            !hold_check(&off, 0.05, Vector2::zeros(), 0.5, G.into())
                .unwrap()
                .holds
        );
    }

    #[test]
    fn bad_input_names_the_field() {
        let j = jaws(1.0);
        let f = |r: Result<HoldCheck>| r.unwrap_err().field().map(str::to_string);
        assert_eq!(
            f(hold_check(&j, 0.0, Vector2::zeros(), 0.5, G.into())).as_deref(),
            Some("mass_kg")
        );
        assert_eq!(
            f(hold_check(&j, 0.1, Vector2::zeros(), -0.5, G.into())).as_deref(),
            Some("mu")
        );
        assert_eq!(
            f(hold_check(&j, 0.1, Vector2::zeros(), 0.5, Vector2::zeros())).as_deref(),
            Some("gravity_m_per_s2")
        );
        let mut bad = j;
        bad[1].normal = [-2.0, 0.0];
        assert_eq!(
            f(hold_check(&bad, 0.1, Vector2::zeros(), 0.5, G.into())).as_deref(),
            Some("contacts[1].normal")
        );
        bad = j;
        bad[0].max_normal_force_n = -1.0;
        assert_eq!(
            f(hold_check(&bad, 0.1, Vector2::zeros(), 0.5, G.into())).as_deref(),
            Some("contacts[0].max_normal_force_n")
        );
        assert!(
            !hold_check(&[], 0.1, Vector2::zeros(), 0.5, G.into())
                .unwrap()
                .holds
        );
    }
}
