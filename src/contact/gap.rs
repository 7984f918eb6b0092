//! Gaps between the rod and the obstacles: the local minima of the distance
//! along the rod, found exactly, with their first and second derivatives
//! with respect to the element coordinates.
//!
//! On one element the centreline is the cubic `r(ξ) = a0 + a1 ξ + a2 ξ² +
//! a3 ξ³` (the Hermite interpolation (14), (16) in the power basis). The
//! distance to a point feature (a circle's centre, a capsule's end, a
//! polygon's vertex) is stationary where `(r − c)·r_ξ = 0`, a quintic; to a
//! flat feature (a capsule's side, a polygon's edge) where `n·r_ξ = 0`, a
//! quadratic; inside a polygon the distance is the largest of its edge
//! distances, with kinks where two of them are equal (a cubic). Every real
//! root of these polynomials in `[0, 1]` is isolated exactly (between two
//! consecutive roots of its derivative a polynomial is monotone, so one
//! bisection finds its single root there; recursively down to degree one).
//! With the element ends they cut `[0, 1]` into pieces on which the true
//! distance is monotone, so its local minima along the whole rod are among
//! these candidates: those lower than both neighbours (a node shared by two
//! elements is one candidate, counted once, so no two constraints sample
//! the same point). The clamped base point never moves and is no constraint.

use nalgebra::{SMatrix, SVector, Vector2};

use super::obstacle::{Feature, Obstacle, SignedDistance};
use crate::element::hermite;

/// One gap: a local minimum, along the rod, of the distance from the rod's
/// surface (its centreline offset by the rod radius) to one obstacle.
///
/// # Example
/// ```
/// use softrod::assembly::{RobotSpec, Section};
/// use softrod::contact::{Obstacle, Obstacles};
/// let robot = RobotSpec::new(vec![Section::uniform(0.2, 300.0, 0.02, 4)]).build_planar()?;
/// let obstacles = Obstacles::new(vec![Obstacle::Circle { center_m: [0.12, -0.05], radius_m: 0.02 }], 0.005)?;
/// let gaps = obstacles.gaps(&robot, robot.reference_configuration().as_slice())?;
/// assert_eq!(gaps.len(), 1);
/// // the straight rod's closest point is above the centre: 0.05 − 0.02 − 0.005
/// assert!((gaps[0].s_m - 0.12).abs() < 1e-12 && (gaps[0].gap_m - 0.025).abs() < 1e-12);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct Gap {
    /// Index of the obstacle.
    pub obstacle: usize,
    /// Element holding the closest point.
    pub element: usize,
    /// Local coordinate `ξ` of the closest point in the element.
    pub xi: f64,
    /// Undeformed arc coordinate of the closest point (m).
    pub s_m: f64,
    /// Gap: signed distance of the centreline point to the obstacle minus
    /// the rod radius (m; negative: penetration).
    pub gap_m: f64,
    /// The centreline point (m).
    pub point_m: Vector2<f64>,
    /// Outward normal of the obstacle at the closest point: the direction
    /// of the contact force on the rod.
    pub normal: Vector2<f64>,
    /// Whether the minimum is stationary in `ξ` (it slides along the rod
    /// with the configuration) or at the tip end (a fixed material point).
    pub stationary: bool,
    /// `∂g/∂q_e` over the element's 8 coordinates.
    pub gradient: SVector<f64, 8>,
    /// `∂²g/∂q_e²` (8 × 8, symmetric).
    pub hessian: SMatrix<f64, 8, 8>,
}

/// Polynomial with coefficients `p[k]` of `ξ^k` at `x` (Horner).
pub(crate) fn poly_eval(p: &[f64], x: f64) -> f64 {
    p.iter().rev().fold(0.0, |acc, c| acc * x + c)
}

/// The real roots of the polynomial `p` (coefficients low to high) in
/// `[lo, hi]`, increasing; none for the zero polynomial.
pub(crate) fn real_roots(p: &[f64], lo: f64, hi: f64) -> Vec<f64> {
    let deg = match p.iter().rposition(|c| *c != 0.0) {
        Some(d) => d,
        None => return Vec::new(),
    };
    let p = &p[..=deg];
    if deg == 0 {
        return Vec::new();
    }
    if deg == 1 {
        let x = -p[0] / p[1];
        return if x >= lo && x <= hi && x.is_finite() {
            vec![x]
        } else {
            Vec::new()
        };
    }
    let dp: Vec<f64> = (1..=deg).map(|k| k as f64 * p[k]).collect();
    let mut knots = vec![lo];
    knots.extend(
        real_roots(&dp, lo, hi)
            .into_iter()
            .filter(|x| *x > lo && *x < hi),
    );
    knots.push(hi);
    let mut roots: Vec<f64> = Vec::new();
    let push = |x: f64, roots: &mut Vec<f64>| {
        if roots.last().is_none_or(|r| *r < x) {
            roots.push(x);
        }
    };
    for w in knots.windows(2) {
        let (mut a, mut b) = (w[0], w[1]);
        let (fa, fb) = (poly_eval(p, a), poly_eval(p, b));
        if fa == 0.0 {
            push(a, &mut roots);
            continue;
        }
        if fb == 0.0 || fa.signum() == fb.signum() {
            continue;
        }
        // monotone on [a, b] with a sign change: bisect to machine precision
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if m <= a || m >= b {
                break;
            }
            let fm = poly_eval(p, m);
            if fm == 0.0 {
                a = m;
                b = m;
                break;
            }
            if fm.signum() == fa.signum() {
                a = m;
            } else {
                b = m;
            }
        }
        let x = if poly_eval(p, a).abs() <= poly_eval(p, b).abs() {
            a
        } else {
            b
        };
        push(x, &mut roots);
    }
    if poly_eval(p, hi) == 0.0 {
        push(hi, &mut roots);
    }
    roots
}

/// Product of two polynomials.
fn poly_mul(a: &[f64], b: &[f64]) -> Vec<f64> {
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            out[i + j] += x * y;
        }
    }
    out
}

/// One element's centreline in the power basis of `ξ`: `coef[k]` multiplies
/// `ξ^k` (two components each).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Cubic {
    pub(crate) coef: [[f64; 2]; 4],
}

impl Cubic {
    /// From the element's 8 coordinates `[r1, r1', r2, r2']` and length `le`.
    pub fn new(qe: &[f64], le: f64) -> Self {
        let mut coef = [[0.0; 2]; 4];
        for i in 0..2 {
            let (r1, t1, r2, t2) = (qe[i], le * qe[2 + i], qe[4 + i], le * qe[6 + i]);
            coef[0][i] = r1;
            coef[1][i] = t1;
            coef[2][i] = -3.0 * r1 - 2.0 * t1 + 3.0 * r2 - t2;
            coef[3][i] = 2.0 * r1 + t1 - 2.0 * r2 + t2;
        }
        Cubic { coef }
    }
    fn component(&self, i: usize) -> [f64; 4] {
        [
            self.coef[0][i],
            self.coef[1][i],
            self.coef[2][i],
            self.coef[3][i],
        ]
    }
    /// `n · r(ξ) − c` as a polynomial.
    fn along(&self, n: &[f64; 2], c: f64) -> [f64; 4] {
        let mut p = [0.0; 4];
        for (k, pk) in p.iter_mut().enumerate() {
            *pk = n[0] * self.coef[k][0] + n[1] * self.coef[k][1];
        }
        p[0] -= c;
        p
    }
    /// The ξ in `(0, 1)` where the distance to `f` is stationary.
    fn stationary(&self, f: &Feature) -> Vec<f64> {
        match f {
            Feature::Point { c, .. } => {
                let mut p = vec![0.0; 6];
                for (i, ci) in c.iter().enumerate() {
                    let mut w = self.component(i);
                    w[0] -= ci;
                    let d = [w[1], 2.0 * w[2], 3.0 * w[3]];
                    for (k, v) in poly_mul(&w, &d).iter().enumerate() {
                        p[k] += v;
                    }
                }
                real_roots(&p, 0.0, 1.0)
            }
            Feature::Line { n, .. } => {
                let h = self.along(n, 0.0);
                real_roots(&[h[1], 2.0 * h[2], 3.0 * h[3]], 0.0, 1.0)
            }
        }
    }
}

/// The candidate local coordinates of one element against one obstacle:
/// the ends, the stationary points of every feature's distance and, for a
/// polygon, the crossings of two edge distances; increasing.
pub(crate) fn element_candidates(cubic: &Cubic, obstacle: &Obstacle) -> Vec<f64> {
    let features = obstacle.features();
    let mut xs = vec![0.0, 1.0];
    for f in &features {
        xs.extend(cubic.stationary(f));
    }
    if let Obstacle::Polygon { .. } = obstacle {
        let lines: Vec<([f64; 2], [f64; 2])> = features
            .iter()
            .filter_map(|f| match f {
                Feature::Line { p, n, .. } => Some((*p, *n)),
                Feature::Point { .. } => None,
            })
            .collect();
        for (i, (pi, ni)) in lines.iter().enumerate() {
            for (pj, nj) in &lines[i + 1..] {
                let dn = [ni[0] - nj[0], ni[1] - nj[1]];
                let c = ni[0] * pi[0] + ni[1] * pi[1] - nj[0] * pj[0] - nj[1] * pj[1];
                xs.extend(real_roots(&cubic.along(&dn, c), 0.0, 1.0));
            }
        }
    }
    xs.retain(|x| x.is_finite());
    xs.sort_by(f64::total_cmp);
    xs.dedup();
    xs
}

/// The point, first and second derivatives of the centreline with respect
/// to `ξ`, and the Hermite weights `s_k` and `ds_k/dξ`.
struct Local {
    r: [f64; 2],
    r_xi: [f64; 2],
    r_xixi: [f64; 2],
    s: [f64; 4],
    s_xi: [f64; 4],
}

fn local(qe: &[f64], le: f64, xi: f64) -> Local {
    let (s, ds, dds) = hermite(xi, le);
    let mut l = Local {
        r: [0.0; 2],
        r_xi: [0.0; 2],
        r_xixi: [0.0; 2],
        s,
        s_xi: [0.0; 4],
    };
    for k in 0..4 {
        l.s_xi[k] = le * ds[k];
        for i in 0..2 {
            l.r[i] += s[k] * qe[2 * k + i];
            l.r_xi[i] += le * ds[k] * qe[2 * k + i];
            l.r_xixi[i] += le * le * dds[k] * qe[2 * k + i];
        }
    }
    l
}

/// The gap at `ξ` of an element with coordinates `qe`, and its derivatives
/// with respect to `qe`: at a fixed material point (`stationary = false`),
/// or following the closest point (`stationary = true`: `∂g/∂ξ = 0` there,
/// so the gradient is the same and the Hessian loses `b bᵀ / g_ξξ`, `b =
/// ∂g_ξ/∂q_e`; if `g_ξξ` is not positive, a flat contact, the term is left
/// out).
#[allow(clippy::too_many_arguments)]
pub(crate) fn gap_at(
    obstacle_index: usize,
    obstacle: &Obstacle,
    rod_radius: f64,
    element: usize,
    s_m: f64,
    qe: &[f64],
    le: f64,
    xi: f64,
    stationary: bool,
) -> Gap {
    let l = local(qe, le, xi);
    let SignedDistance {
        distance_m,
        normal: n,
        hessian_per_m: h,
    } = obstacle.signed_distance(Vector2::from(l.r));
    let mut gradient = SVector::<f64, 8>::zeros();
    let mut hessian = SMatrix::<f64, 8, 8>::zeros();
    for k in 0..4 {
        for i in 0..2 {
            gradient[2 * k + i] = l.s[k] * n[i];
            for m in 0..4 {
                for j in 0..2 {
                    hessian[(2 * k + i, 2 * m + j)] = l.s[k] * l.s[m] * h[(i, j)];
                }
            }
        }
    }
    if stationary {
        let hr = [
            h[(0, 0)] * l.r_xi[0] + h[(0, 1)] * l.r_xi[1],
            h[(1, 0)] * l.r_xi[0] + h[(1, 1)] * l.r_xi[1],
        ];
        let g_xixi =
            l.r_xi[0] * hr[0] + l.r_xi[1] * hr[1] + n[0] * l.r_xixi[0] + n[1] * l.r_xixi[1];
        if g_xixi > 0.0 && g_xixi.is_finite() {
            let mut b = [0.0; 8];
            for k in 0..4 {
                for i in 0..2 {
                    b[2 * k + i] = l.s[k] * hr[i] + l.s_xi[k] * n[i];
                }
            }
            for a in 0..8 {
                for c in 0..8 {
                    hessian[(a, c)] -= b[a] * b[c] / g_xixi;
                }
            }
        }
    }
    Gap {
        obstacle: obstacle_index,
        element,
        xi,
        s_m,
        gap_m: distance_m - rod_radius,
        point_m: Vector2::from(l.r),
        normal: n,
        stationary,
        gradient,
        hessian,
    }
}

/// The gap function along the rod `g(ξ)` at one point (no derivatives).
pub(crate) fn gap_value(obstacle: &Obstacle, rod_radius: f64, cubic: &Cubic, xi: f64) -> f64 {
    let mut r = [0.0; 2];
    let mut p = 1.0;
    for c in &cubic.coef {
        r[0] += p * c[0];
        r[1] += p * c[1];
        p *= xi;
    }
    obstacle.signed_distance(Vector2::from(r)).distance_m - rod_radius
}
