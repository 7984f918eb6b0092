//! Sites: the points of a model that observations and loads address, the
//! same way on every structure.
//!
//! A [`Site`] is a point of a rod's centreline at an undeformed arc
//! coordinate, or a rigid body's reference point (the centre of the parallel
//! robot's platform). Its position is linear in the coordinates `q` on every
//! model: on an ANCF rod `r(X) = S(X) q` (16), the four Hermite functions
//! (14) of the element holding `X` weighting the positions and slopes of its
//! two nodes; on a rigid body the first `DIM` coordinates of its pose. So a
//! site is a set of sparse rows over `q` ([`SiteRows`]): a marker observes
//! them (the operator `A` of (25), [`crate::observe::ObservationOperator`]),
//! a concentrated force `F` at the site has the generalized force
//! `Q_F = Aᵀ F` (34), and its sensitivity is one adjoint solve per row
//! ([`crate::sensitivity::Sensitivity::adjoints`]).
//!
//! A model says where its sites are through [`Sites`]; the clamped robot is
//! a structure of one rod and no bodies (`rod: 0`).

use serde::{Deserialize, Serialize};

use crate::element::Element;
use crate::error::{Error, Result, check_index};
use crate::structure::{Model, Rod};

/// A point of a model.
///
/// # Example
/// ```
/// use softrod::site::Site;
/// let tip: Site = serde_json::from_str(r#"{"kind": "rod", "rod": 0, "s_m": 0.24}"#).unwrap();
/// assert_eq!(tip, Site::Rod { rod: 0, s_m: 0.24 });
/// let platform: Site = serde_json::from_str(r#"{"kind": "body", "body": 0}"#).unwrap();
/// assert_eq!(platform, Site::Body { body: 0 });
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum Site {
    /// The centreline of rod `rod` at undeformed arc coordinate `s_m` (m,
    /// from the rod's first node).
    Rod {
        /// The rod (0 for the clamped robot).
        rod: usize,
        /// Undeformed arc coordinate (m).
        s_m: f64,
    },
    /// The reference point of rigid body `body` (the point its pose
    /// positions: the platform's centre).
    Body {
        /// The body.
        body: usize,
    },
}

/// One sparse row over all `n_q` coordinates: `Σ_j w_j q[j]` from the
/// entries `(j, w_j)`.
pub type SparseRow = Vec<(usize, f64)>;

/// The rows of a site: its position (`DIM` rows) and, on a rod, the
/// tangent `r'(X)` (`DIM` rows), each linear in `q`.
///
/// # Example
/// ```
/// use softrod::{scene::Scene, site::{Site, Sites}};
/// let robot = Scene::two_section().robot()?;
/// let q = robot.reference_configuration();
/// let rows = robot.site_rows("site", &Site::Rod { rod: 0, s_m: 0.24 })?;
/// // the straight reference along x: the tip at (0.24, 0), tangent (1, 0)
/// let p = rows.position_at(q.as_slice());
/// assert!((p[0] - 0.24).abs() < 1e-12 && p[1].abs() < 1e-12);
/// let t = rows.tangent_at(q.as_slice()).unwrap();
/// assert!((t[0] - 1.0).abs() < 1e-12);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct SiteRows {
    /// The position's rows (m per coordinate unit), one per component.
    pub position: Vec<SparseRow>,
    /// The tangent's rows, one per component, where the site has a
    /// tangent (a rod point); `None` on a rigid body.
    pub tangent: Option<Vec<SparseRow>>,
}

impl SiteRows {
    /// The position at `q` (m; NaN where `q` is too short).
    pub fn position_at(&self, q: &[f64]) -> Vec<f64> {
        self.position.iter().map(|r| apply_row(r, q)).collect()
    }

    /// The tangent `r'` at `q`, where the site has one.
    pub fn tangent_at(&self, q: &[f64]) -> Option<Vec<f64>> {
        self.tangent
            .as_ref()
            .map(|t| t.iter().map(|r| apply_row(r, q)).collect())
    }
}

/// `Σ_j w_j q[j]` (NaN if `q` is too short).
pub(crate) fn apply_row(row: &[(usize, f64)], q: &[f64]) -> f64 {
    row.iter()
        .map(|&(j, w)| w * q.get(j).copied().unwrap_or(f64::NAN))
        .sum()
}

/// Where the sites of a model are: what observations, concentrated loads
/// and contacts need of any structure.
///
/// # Example
/// ```
/// use softrod::site::{Site, Sites};
/// let robot = softrod::parallel::ParallelSpec::default().build_cable()?;
/// let s = robot.structure();
/// let q = s.configuration(s.reference_free_coordinates())?;
/// // the platform's centre, where the reference puts it
/// let p = s.site_rows("site", &Site::Body { body: 0 })?.position_at(q.as_slice());
/// let x = robot.spec().platform_reference_m()?;
/// assert!((p[2] - x[2]).abs() < 1e-12);
/// # Ok::<(), softrod::Error>(())
/// ```
pub trait Sites: Model {
    /// The dimension of a position (2 planar, 3 spatial).
    fn dim(&self) -> usize;

    /// The undeformed arc coordinate of node `node` of rod `rod` (m).
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] named `field` (node) or `field`'s rod for
    /// a node or rod that does not exist.
    fn node_arc_m(&self, field: &str, rod: usize, node: usize) -> Result<f64>;

    /// The coordinates (indices into `q`) of node `node` of rod `rod`:
    /// its position first (`dim` numbers), then its slopes.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] named `field` (node) or `field.rod`.
    fn node_coordinates_of(
        &self,
        field: &str,
        rod: usize,
        node: usize,
    ) -> Result<std::ops::Range<usize>>;

    /// The rows of `site`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `field.s_m` for an arc coordinate
    /// off the rod; [`Error::IndexOutOfRange`] named `field.rod` or
    /// `field.body` for a rod or body that does not exist.
    fn site_rows(&self, field: &str, site: &Site) -> Result<SiteRows>;
}

/// The rows of the point at arc coordinate `s` of `rod`, whose node `0`'s
/// coordinates start at `offset` in `q` (16): the element's four Hermite
/// slots `k` (the positions and slopes of its two nodes, position first
/// in each node's `NODE_DOFS`) weight one component each.
pub(crate) fn rod_rows<E: Element>(
    rod: &Rod<E>,
    offset: usize,
    field: &str,
    s: f64,
) -> Result<SiteRows> {
    let p = rod.arc_point(&format!("{field}.s_m"), s)?;
    let (d, nd, e) = (E::DIM, E::NODE_DOFS, p.element);
    let rows = |w: &[f64; 4]| -> Vec<SparseRow> {
        (0..d)
            .map(|comp| {
                (0..4)
                    .map(|k| (offset + (e + k / 2) * nd + (k % 2) * d + comp, w[k]))
                    .collect()
            })
            .collect()
    };
    Ok(SiteRows {
        position: rows(&p.values),
        tangent: Some(rows(&p.slopes)),
    })
}

/// The rows of the first `dim` coordinates of a block `range`, exactly:
/// a rigid body's reference point (its pose's position) or a node's
/// position (its coordinates start with it).
pub(crate) fn block_position_rows(range: std::ops::Range<usize>, dim: usize) -> SiteRows {
    SiteRows {
        position: range.take(dim).map(|j| vec![(j, 1.0)]).collect(),
        tangent: None,
    }
}

/// [`Sites::node_arc_m`] of `rod`.
pub(crate) fn rod_node_arc<E: Element>(rod: &Rod<E>, field: &str, node: usize) -> Result<f64> {
    check_index(field, node, rod.n_nodes())?;
    Ok(rod.node_arc()[node])
}

/// The refusal of a body site on a model without rigid bodies.
pub(crate) fn no_body(field: &str, body: usize) -> Error {
    Error::IndexOutOfRange {
        name: format!("{field}.body"),
        index: body,
        len: 0,
    }
}
