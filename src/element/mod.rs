//! Finite elements of a slender body: the ANCF cable elements, their shape
//! functions (14), elastic energy (19), its gradient and tangent stiffness.
//!
//! An element joins two nodes. A cable's node coordinates are
//! `q_i = [r_i, r_i']` (eq. (15)): 4 per node for the [`PlanarCable`], 6 for
//! the [`SpatialCable`]. The element's `q_e = [q_1; q_2]`, and the centreline
//! is `r(X) = S(X) q_e` (16) with the cubic Hermite functions (14),
//! `ξ = X / L_e`:
//!
//! `s1 = 1 - 3ξ² + 2ξ³`, `s2 = L_e (ξ - 2ξ² + ξ³)`, `s3 = 3ξ² - 2ξ³`, `s4 = L_e (ξ³ - ξ²)`.
//!
//! The elastic energy (19) is `U_E = ½ ∫ (EA ε² + EI |κ - κ0|²) dX` with the
//! axial strain `ε = |r'| - 1` and the bending strain `κ = (r' × r'') / (r'·r')`
//! (a scalar in the plane, a vector in space). Both integrals use Gauss–Legendre
//! rules that can differ (exudyn's cables use 5 points for the axial and 3 for
//! the bending term).
//!
//! An element is two traits:
//! - [`Element`]: the energy kernels (energy, gradient, Hessian) and the
//!   interpolation the loads need;
//! - [`NodeKinematics`]: what a node's coordinates mean (its tangent, its
//!   rotation, the work of a concentrated moment on it, the directions a clamp
//!   leaves free, the straight stress-free node).
//!
//! [`hermite`] and [`ArcPoint`] are the one cubic Hermite interpolation every
//! cable field (positions, slopes, distributed loads) goes through.

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result, check_len, check_positive};
use crate::quadrature::GaussRule;

mod ancf3d;
/// Forward-mode jets (value, gradient, Hessian), shared with the rigid ends.
pub(crate) use ancf3d::jet;
mod planar_cable;
mod spatial_cable;

pub use ancf3d::{Ancf3d, Ancf3dStiffness};
pub use planar_cable::PlanarCable;
pub use spatial_cable::SpatialCable;

/// Default number of Gauss points for both the axial and the bending integral.
pub const DEFAULT_GAUSS_POINTS: usize = 5;

/// What a node's coordinates mean: its tangent and rotation, the work of a
/// concentrated moment on it, and the directions a clamp leaves free.
///
/// Slices named `node` hold `NODE_DOFS` coordinates. `reference` is a node's
/// coordinates in the reference configuration (only its tangent is read): the
/// rotation of a node, and so the work of a moment, is measured from it.
/// Hessians are written row-major, `NODE_DOFS²` numbers.
///
/// Implementations must not panic on slices of the wrong length: they return
/// NaN for scalar results (NaN coordinates for `straight_node` and the vector
/// results, no directions for `clamp_free_directions`) and add nothing to the
/// buffers ([`crate::assembly::Robot`] checks every size first).
///
/// # Example
/// ```
/// use softrod::element::{NodeKinematics, SpatialCable};
/// // a node turned by 90° about z from a reference along x
/// let reference = SpatialCable::straight_node(&[0.0; 3], &[1.0, 0.0, 0.0]);
/// let node = [0.1, 0.0, 0.0, 0.0, 2.0, 0.0];
/// let phi = SpatialCable::node_rotation(reference.as_slice(), &node);
/// assert!((phi[2] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
/// // a moment about z does the work M φ_z; about x (the reference tangent) none
/// let w = SpatialCable::moment_work_between(reference.as_slice(), reference.as_slice(), &node, &[0.5, 0.0, 0.0]);
/// assert_eq!(w, 0.0);
/// ```
pub trait NodeKinematics {
    /// Spatial dimension of the centreline (2 or 3).
    const DIM: usize;
    /// Coordinates per node.
    const NODE_DOFS: usize;
    /// Components of a concentrated moment (1 in 2-D, 3 in 3-D).
    const MOMENT_DIM: usize;

    /// Node coordinates of the stress-free straight element's node at
    /// `position` with unit tangent `direction` (length `DIM` each).
    fn straight_node(position: &[f64], direction: &[f64]) -> DVector<f64>;
    /// Unit tangent `r'/|r'|` of a node (`DIM` numbers).
    fn node_tangent(node: &[f64]) -> DVector<f64>;
    /// Rotation `θ` of a node from `reference` (`MOMENT_DIM` numbers, rad): the
    /// quantity a concentrated moment `M` is work-conjugate to, `W = M · θ`.
    fn node_rotation(reference: &[f64], node: &[f64]) -> DVector<f64>;
    /// Gradient and Hessian (row-major) of the work `W = M · θ` of a
    /// concentrated moment `moment` at a node with coordinates `node`, with
    /// respect to the node coordinates, added into `grad` and `hess`; `θ` is
    /// [`NodeKinematics::node_rotation`] from `reference`.
    fn add_moment_work(
        reference: &[f64],
        node: &[f64],
        moment: &[f64],
        grad: &mut [f64],
        hess: &mut [f64],
    );
    /// Directions in node-coordinate space that a clamp leaves free at a node
    /// with coordinates `node`: for a cable, the stretch along the prescribed
    /// tangent (a clamp fixes position and direction, not the axial strain).
    /// A `NODE_DOFS × k` matrix, one direction per column (none when the
    /// node's tangent is degenerate).
    fn clamp_free_directions(node: &[f64]) -> DMatrix<f64>;
    /// Work `M · (θ(to) − θ(from))` of a constant moment while a node moves
    /// from the coordinates `from` to `to` (rotations below π).
    fn moment_work_between(reference: &[f64], from: &[f64], to: &[f64], moment: &[f64]) -> f64;
}

/// A finite element of a slender body: energy, gradient and Hessian in its
/// element coordinates, and the interpolation the loads need.
///
/// Slices named `qe` hold `2 * NODE_DOFS` element coordinates; Hessians are
/// written row-major, `(2 NODE_DOFS)²` numbers. `_into` methods write into the
/// caller's buffer.
///
/// These are low-level, infallible kernels ([`crate::assembly::Robot`] checks
/// every size before calling them). Implementations must not panic on slices
/// of the wrong length: they then return NaN for scalar results and add
/// nothing to the buffers.
///
/// # Example
/// ```
/// use softrod::element::{Element, PlanarCable};
/// let e = PlanarCable::new(0.1, 300.0, 0.025)?;
/// // stretched by 1 %: U = ½ EA ε² L_e
/// let qe = [0.0, 0.0, 1.01, 0.0, 0.101, 0.0, 1.01, 0.0];
/// assert!((e.energy(&qe) - 0.5 * 300.0 * 1e-4 * 0.1).abs() < 1e-15);
/// let mut g = [0.0; 8];
/// e.add_energy_gradient(&qe, &mut g);
/// assert!((g[4] - 300.0 * 0.01).abs() < 1e-12); // the axial force at node 2
/// # Ok::<(), softrod::Error>(())
/// ```
pub trait Element: NodeKinematics + Clone + std::fmt::Debug + Send + Sync + 'static {
    /// Undeformed length `L_e` (m).
    fn length(&self) -> f64;
    /// Elastic energy `U_E` of the element (J).
    fn energy(&self, qe: &[f64]) -> f64;
    /// Adds `dU_E/dq_e` (N, generalized) into `grad`.
    fn add_energy_gradient(&self, qe: &[f64], grad: &mut [f64]);
    /// Adds the tangent stiffness `d²U_E/dq_e²` into `hess` (row-major).
    fn add_energy_hessian(&self, qe: &[f64], hess: &mut [f64]);
    /// Adds the gradient into `grad` and the Hessian into `hess` in one
    /// pass (Newton's method needs both at the same point). The default
    /// calls the two kernels; the cables share the work per Gauss point.
    fn add_energy_gradient_and_hessian(&self, qe: &[f64], grad: &mut [f64], hess: &mut [f64]) {
        self.add_energy_gradient(qe, grad);
        self.add_energy_hessian(qe, hess);
    }
    /// Interpolation weights of the node quantities at `ξ = X/L_e` (`S(X)` is
    /// `[w_0 I, w_1 I, ...]`): the cable's four Hermite functions.
    fn shape(&self, xi: f64) -> [f64; 4];
}

/// Cubic Hermite shape functions (14) at `ξ`, for an element of length `le`:
/// values, first and second derivatives with respect to `X`.
///
/// # Example
/// ```
/// let (s, _, _) = softrod::element::hermite(0.5, 2.0);
/// assert!((s[0] - 0.5).abs() < 1e-15 && (s[2] - 0.5).abs() < 1e-15);
/// ```
pub fn hermite(xi: f64, le: f64) -> ([f64; 4], [f64; 4], [f64; 4]) {
    let x2 = xi * xi;
    let x3 = x2 * xi;
    let s = [
        1.0 - 3.0 * x2 + 2.0 * x3,
        le * (xi - 2.0 * x2 + x3),
        3.0 * x2 - 2.0 * x3,
        le * (x3 - x2),
    ];
    let ds = [
        (-6.0 * xi + 6.0 * x2) / le,
        1.0 - 4.0 * xi + 3.0 * x2,
        (6.0 * xi - 6.0 * x2) / le,
        3.0 * x2 - 2.0 * xi,
    ];
    let dds = [
        (-6.0 + 12.0 * xi) / (le * le),
        (-4.0 + 6.0 * xi) / le,
        (6.0 - 12.0 * xi) / (le * le),
        (6.0 * xi - 2.0) / le,
    ];
    (s, ds, dds)
}

/// A point of a chain of cable elements and the Hermite weights there: the one
/// "interpolate a cable field at an arc position" of the crate.
///
/// A cable field is node-major with `2 DIM` numbers per node, `[v_i, v_i']`
/// (the coordinates `q`, or the load parameters `F` of (8)); its value at the
/// point is `v(X) = Σ_k s_k(ξ) v_k` (16) over the element's four slots, and
/// its derivative `v'(X) = Σ_k s_k'(ξ) v_k`.
///
/// # Example
/// ```
/// use softrod::element::ArcPoint;
/// // two elements of 0.1 m; a straight cable along x, q_i = [x, y, x', y']
/// let q = [0.0, 0.0, 1.0, 0.0, 0.1, 0.0, 1.0, 0.0, 0.2, 0.0, 1.0, 0.0];
/// let p = ArcPoint::locate(&[0.0, 0.1, 0.2], 0.15).unwrap();
/// assert_eq!(p.element, 1);
/// let mut r = [0.0; 2];
/// p.value_into(&q, &mut r).unwrap();
/// assert!((r[0] - 0.15).abs() < 1e-15 && r[1] == 0.0);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArcPoint {
    /// Index of the element holding the point.
    pub element: usize,
    /// Local coordinate `ξ = (X − X_e)/L_e` in `[0, 1]`.
    pub xi: f64,
    /// The element's undeformed length `L_e` (m).
    pub length_m: f64,
    /// Shape function values `s_k(ξ)` (14).
    pub values: [f64; 4],
    /// Their derivatives `ds_k/dX` (1/m for `k = 0, 2`, 1 for `k = 1, 3`).
    pub slopes: [f64; 4],
}

impl ArcPoint {
    /// The point at `ξ` of element `element`, of length `length_m` (m).
    ///
    /// # Example
    /// ```
    /// let p = softrod::element::ArcPoint::new(3, 0.0, 0.1);
    /// assert_eq!(p.values, [1.0, 0.0, 0.0, 0.0]);
    /// ```
    pub fn new(element: usize, xi: f64, length_m: f64) -> Self {
        let (values, slopes, _) = hermite(xi, length_m);
        ArcPoint {
            element,
            xi,
            length_m,
            values,
            slopes,
        }
    }

    /// The point at arc coordinate `s` (m) on a chain whose nodes sit at the
    /// undeformed arc coordinates `node_arc` (increasing, from 0): the element
    /// holding `s` (the later one at a node), `L_e` the distance of its nodes.
    /// `None` for fewer than two nodes, a non-finite `s`, or an `s` off
    /// `[0, L]` by more than `1e-12 L`; within that, `ξ` is clamped to `[0, 1]`.
    ///
    /// # Example
    /// ```
    /// use softrod::element::ArcPoint;
    /// let p = ArcPoint::locate(&[0.0, 0.1, 0.2], 0.2).unwrap();
    /// assert_eq!((p.element, p.xi), (1, 1.0));
    /// assert!(ArcPoint::locate(&[0.0, 0.1, 0.2], 0.3).is_none());
    /// ```
    pub fn locate(node_arc: &[f64], s: f64) -> Option<Self> {
        let n_el = node_arc.len().checked_sub(1).filter(|n| *n > 0)?;
        let total = node_arc[n_el];
        if !(s >= -1e-12 * total && s <= total * (1.0 + 1e-12)) {
            return None;
        }
        let e = node_arc
            .partition_point(|&x| x <= s)
            .saturating_sub(1)
            .min(n_el - 1);
        let le = node_arc[e + 1] - node_arc[e];
        let xi = ((s - node_arc[e]) / le).clamp(0.0, 1.0);
        Some(Self::new(e, xi, le))
    }

    /// `v(X) = Σ_k s_k v_k` of the cable field `field` at the point, into
    /// `out` (`DIM = out.len()` components; the field holds `2 DIM` numbers
    /// per node).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `field` ends before the element's
    /// second node.
    ///
    /// # Example
    /// ```
    /// // a spatial field: 6 numbers per node; the midpoint of a straight element along z
    /// let q = [0.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.4, 0.0, 0.0, 1.0];
    /// let mut r = [0.0; 3];
    /// softrod::element::ArcPoint::new(0, 0.5, 0.4).value_into(&q, &mut r)?;
    /// assert!((r[2] - 0.2).abs() < 1e-15);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn value_into(&self, field: &[f64], out: &mut [f64]) -> Result<()> {
        self.combine(&self.values, field, out)
    }

    /// `v'(X) = Σ_k s_k' v_k` of the cable field `field` at the point, into
    /// `out` (as [`ArcPoint::value_into`]).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `field` ends before the element's
    /// second node.
    ///
    /// # Example
    /// ```
    /// let p = softrod::element::ArcPoint::new(0, 0.3, 0.5);
    /// let q = [0.0, 0.0, 0.0, 1.0, 0.0, 0.5, 0.0, 1.0]; // straight along y
    /// let mut t = [0.0; 2];
    /// p.slope_into(&q, &mut t).unwrap();
    /// assert!(t[0].abs() < 1e-15 && (t[1] - 1.0).abs() < 1e-14);
    /// ```
    pub fn slope_into(&self, field: &[f64], out: &mut [f64]) -> Result<()> {
        self.combine(&self.slopes, field, out)
    }

    /// [`ArcPoint::value_into`] for a field of `node_dofs` numbers per node
    /// whose first `2 DIM` are `[v_i, v_i']` (`DIM = out.len()`): a full 3-D
    /// element's coordinates `[r, r_X, r_Y, r_Z]` (12 per node), or a load
    /// field laid out like them. `node_dofs = 2 DIM` is
    /// [`ArcPoint::value_into`].
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `field` ends before the element's
    /// second node; [`Error::InvalidParameter`] naming `node_dofs` if it is
    /// below `2 DIM`.
    ///
    /// # Example
    /// ```
    /// // a full 3-D element along z: [r, r_X, r_Y, r_Z] per node
    /// let mut q = [0.0; 24];
    /// q[5] = 1.0; // r_X of node 0 along z
    /// q[14] = 0.4; // r of node 1
    /// q[17] = 1.0; // r_X of node 1
    /// let p = softrod::element::ArcPoint::new(0, 0.5, 0.4);
    /// let (mut r, mut t) = ([0.0; 3], [0.0; 3]);
    /// p.node_value_into(&q, 12, &mut r)?;
    /// p.node_slope_into(&q, 12, &mut t)?;
    /// assert!((r[2] - 0.2).abs() < 1e-15 && (t[2] - 1.0).abs() < 1e-14);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn node_value_into(&self, field: &[f64], node_dofs: usize, out: &mut [f64]) -> Result<()> {
        self.combine_strided(&self.values, field, node_dofs, out)
    }

    /// [`ArcPoint::slope_into`] for a field of `node_dofs` numbers per node
    /// (as [`ArcPoint::node_value_into`]).
    ///
    /// # Errors
    /// As [`ArcPoint::node_value_into`].
    ///
    /// # Example
    /// See [`ArcPoint::node_value_into`].
    pub fn node_slope_into(&self, field: &[f64], node_dofs: usize, out: &mut [f64]) -> Result<()> {
        self.combine_strided(&self.slopes, field, node_dofs, out)
    }

    fn combine(&self, w: &[f64; 4], field: &[f64], out: &mut [f64]) -> Result<()> {
        self.combine_strided(w, field, 2 * out.len(), out)
    }

    fn combine_strided(
        &self,
        w: &[f64; 4],
        field: &[f64],
        nd: usize,
        out: &mut [f64],
    ) -> Result<()> {
        let d = out.len();
        if nd < 2 * d {
            return Err(Error::invalid(
                "node_dofs",
                nd,
                format!("a node holds at least [v, v']: {} numbers", 2 * d),
            ));
        }
        let start = self.element.saturating_mul(nd);
        let needed = start.saturating_add(nd).saturating_add(2 * d);
        if field.len() < needed {
            check_len("cable field", needed, field.len())?;
        }
        // slot k: node e + k/2, its value (k even) or slope (k odd)
        let at = |k: usize, i: usize| field[start + (k / 2) * nd + (k % 2) * d + i];
        for (i, o) in out.iter_mut().enumerate() {
            // the sum in slot order from 0.0, as Robot::position_at always did
            *o = (0..4).map(|k| w[k] * at(k, i)).sum();
        }
        Ok(())
    }
}

/// Precomputed derivatives of the shape functions at one Gauss point, with
/// the point's weights in the two integrals (zero where the point belongs to
/// one rule only).
#[derive(Debug, Clone, Copy)]
struct GaussPoint {
    /// `ds_k/dX`.
    d1: [f64; 4],
    /// `d²s_k/dX²`.
    d2: [f64; 4],
    /// Axial weight: quadrature weight × `L_e` × EA (N·m), 0 if not an
    /// axial point.
    ca: f64,
    /// Bending weight: quadrature weight × `L_e` × EI (N·m³), 0 if not a
    /// bending point.
    cb: f64,
}

/// Checks a cable's length and stiffnesses (`length_m`, `ea_n`, `ei_nm2`).
/// The directions `dirs` (each `rows` numbers) as the columns of a matrix.
fn direction_columns(rows: usize, dirs: Vec<Vec<f64>>) -> DMatrix<f64> {
    DMatrix::from_fn(rows, dirs.len(), |i, k| {
        dirs[k].get(i).copied().unwrap_or(f64::NAN)
    })
}

/// The columns of a direction matrix as a list (the form the DOF map's
/// blocks hold).
pub(crate) fn direction_list(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    m.column_iter()
        .map(|c| c.iter().copied().collect())
        .collect()
}

fn check_cable(le: f64, ea: f64, ei: f64) -> Result<()> {
    check_positive("length_m", le)?;
    if !(1.0 / (le * le)).is_finite() {
        // the shape functions' second derivatives (∝ 1/L_e²) overflow
        return Err(Error::invalid(
            "length_m",
            le,
            "element too short: 1/L_e² overflows",
        ));
    }
    check_positive("ea_n", ea)?;
    check_positive("ei_nm2", ei)
}

/// The Gauss points of a cable's two integrals: one list when the two rules
/// coincide, else the axial points followed by the bending points.
///
/// # Errors
/// [`Error::InvalidParameter`] for a rule of 0 points, [`Error::TooLarge`]
/// above [`crate::quadrature::MAX_POINTS`], named `axial_gauss_points` or
/// `bending_gauss_points`.
fn gauss_points(
    le: f64,
    ea: f64,
    ei: f64,
    axial_points: usize,
    bending_points: usize,
) -> Result<Vec<GaussPoint>> {
    let rule = |n: usize, name: &str| -> Result<GaussRule> {
        // the rule's own error, under this parameter's name
        GaussRule::new(n).map_err(|e| match e {
            Error::TooLarge { value, max, .. } => Error::TooLarge {
                name: name.into(),
                value,
                max,
            },
            _ => Error::invalid(name, n, "must be >= 1"),
        })
    };
    let axial = rule(axial_points, "axial_gauss_points")?;
    let bending = rule(bending_points, "bending_gauss_points")?;
    let point = |xi: f64, ca: f64, cb: f64| {
        let (_, d1, d2) = hermite(xi, le);
        GaussPoint { d1, d2, ca, cb }
    };
    Ok(if axial == bending {
        axial
            .iter()
            .map(|(xi, w)| point(xi, w * le * ea, w * le * ei))
            .collect()
    } else {
        axial
            .iter()
            .map(|(xi, w)| point(xi, w * le * ea, 0.0))
            .chain(bending.iter().map(|(xi, w)| point(xi, 0.0, w * le * ei)))
            .collect()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arc_point_interpolates_a_cubic_exactly() {
        // r(X) = (X³, X²) on [0, 0.3], three elements: nodal values and slopes
        let arcs = [0.0, 0.1, 0.2, 0.3];
        let q: Vec<f64> = arcs
            .iter()
            .flat_map(|&x| [x * x * x, x * x, 3.0 * x * x, 2.0 * x])
            .collect();
        for s in [0.0, 0.03, 0.1, 0.17, 0.25, 0.3] {
            let p = ArcPoint::locate(&arcs, s).unwrap();
            let (mut r, mut t) = ([0.0; 2], [0.0; 2]);
            p.value_into(&q, &mut r).unwrap();
            p.slope_into(&q, &mut t).unwrap();
            assert!((r[0] - s * s * s).abs() < 1e-15 && (r[1] - s * s).abs() < 1e-15);
            assert!((t[0] - 3.0 * s * s).abs() < 1e-14 && (t[1] - 2.0 * s).abs() < 1e-14);
        }
        // off the chain, a short field, a chain of one node
        assert!(ArcPoint::locate(&arcs, -0.01).is_none());
        assert!(ArcPoint::locate(&arcs, f64::NAN).is_none());
        assert!(ArcPoint::locate(&[0.0], 0.0).is_none());
        let p = ArcPoint::locate(&arcs, 0.25).unwrap();
        assert!(p.value_into(&q[..12], &mut [0.0; 2]).is_err());
    }
}
