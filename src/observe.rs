//! Observations of the robot and the observation operator `A` of (25).
//!
//! A marker measures the centreline position `r(X_m) = S(X_m) q` (16) at a
//! node or at an undeformed arc coordinate `X_m`, optionally the tangent
//! `r'(X_m)` too. Stacked, the observed quantities are linear in the
//! coordinates: `A q`, one row of `A` per observed scalar, compared with the
//! measurements `y` under diagonal weights `W` in the estimator's objective
//! `(A q − y)ᵀ W (A q − y)` (25). [`ObservationOperator`] is `(A, y, W)`.
//!
//! A row of `A` is sparse: the cable's four Hermite functions (14) weight one
//! component of the two node positions and the two node slopes of the element
//! holding the marker. Rows index the coordinates through the node layout
//! (`q_i = [r_i, r_i', …]`, `NODE_DOFS` per node, position first, then the
//! slope), so the same code serves the planar cable (4 per node) and the
//! spatial one (6 per node).

use nalgebra::{Dim, RawStorage, SVector, Vector};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_all_finite, check_len, check_positive};
use crate::rng::Gaussian;
use crate::site::{Site, Sites};

/// How far beyond the robot's scale a marker may be: positions beyond
/// `MAX_MARKER_SCALE` robot lengths, weights beyond `MAX_MARKER_SCALE`
/// times their default and tangents longer than it are refused (they can
/// only overflow the estimate).
pub const MAX_MARKER_SCALE: f64 = 1e12;

/// One marker measurement.
///
/// # Example
/// ```
/// let m = softrod::observe::MarkerObservation::at_node(20, nalgebra::Vector2::new(0.2, 0.05));
/// assert_eq!(m.node, Some(20));
/// assert_eq!(m.position_m, vec![0.2, 0.05]); // as a scene's JSON holds it
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MarkerObservation {
    /// The rod of `node` or `s_m` on a structure of several rods (default
    /// 0, the clamped robot's one rod).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rod: Option<usize>,
    /// Node index (of the rod), or
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub node: Option<usize>,
    /// undeformed arc coordinate (m, of the rod), or
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub s_m: Option<f64>,
    /// a rigid body's reference point (the parallel robot's platform centre,
    /// `body: 0`): exactly one of the three.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub body: Option<usize>,
    /// Measured position (m, world axes).
    pub position_m: Vec<f64>,
    /// Measured tangent `r'` (dimensionless), if observed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangent: Option<Vec<f64>>,
    /// Weights of the position components (1/m²); default `1/σ²`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position_weight: Option<Vec<f64>>,
    /// Weights of the tangent components (dimensionless); default `1/σ_t²`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tangent_weight: Option<Vec<f64>>,
}

impl MarkerObservation {
    /// A position-only marker at a node with default weights; `position_m`
    /// (m) is a vector of the robot's dimension (2 planar, 3 spatial): a
    /// `Vector2`/`Vector3`, or the `DVector` a robot's
    /// [`position_at`](crate::assembly::Robot::position_at) returns.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector3;
    /// let m = softrod::observe::MarkerObservation::at_node(4, Vector3::new(0.1, 0.0, 0.02));
    /// assert_eq!(m.position::<3>()?, Vector3::new(0.1, 0.0, 0.02));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn at_node<D: Dim, S: RawStorage<f64, D>>(
        node: usize,
        position_m: Vector<f64, D, S>,
    ) -> Self {
        MarkerObservation {
            rod: None,
            node: Some(node),
            s_m: None,
            body: None,
            position_m: position_m.iter().copied().collect(),
            tangent: None,
            position_weight: None,
            tangent_weight: None,
        }
    }

    /// A position-only marker at arc coordinate `s_m` with default weights;
    /// `position_m` (m) as in [`MarkerObservation::at_node`].
    ///
    /// # Example
    /// ```
    /// let m = softrod::observe::MarkerObservation::at_arc(0.12, nalgebra::Vector2::new(0.12, 0.0));
    /// assert_eq!(m.s_m, Some(0.12));
    /// ```
    pub fn at_arc<D: Dim, S: RawStorage<f64, D>>(s_m: f64, position_m: Vector<f64, D, S>) -> Self {
        MarkerObservation::at_arc_slice(s_m, position_m.iter().copied().collect())
    }

    /// [`MarkerObservation::at_arc`] from a position as a frame holds it.
    pub(crate) fn at_arc_slice(s_m: f64, position_m: Vec<f64>) -> Self {
        MarkerObservation {
            rod: None,
            node: None,
            s_m: Some(s_m),
            body: None,
            position_m,
            tangent: None,
            position_weight: None,
            tangent_weight: None,
        }
    }

    /// A position-only marker at `site` with default weights; `position_m`
    /// (m) as in [`MarkerObservation::at_node`].
    ///
    /// # Example
    /// ```
    /// use softrod::{observe::MarkerObservation, site::Site};
    /// let m = MarkerObservation::at_site(&Site::Body { body: 0 }, vec![0.0, 0.0, -0.1]);
    /// assert_eq!(m.body, Some(0));
    /// let m = MarkerObservation::at_site(&Site::Rod { rod: 2, s_m: 0.1 }, vec![0.0; 3]);
    /// assert_eq!((m.rod, m.s_m), (Some(2), Some(0.1)));
    /// ```
    pub fn at_site(site: &Site, position_m: Vec<f64>) -> Self {
        let (rod, s_m, body) = match *site {
            Site::Rod { rod, s_m } => ((rod != 0).then_some(rod), Some(s_m), None),
            Site::Body { body } => (None, None, Some(body)),
        };
        MarkerObservation {
            rod,
            node: None,
            s_m,
            body,
            position_m,
            tangent: None,
            position_weight: None,
            tangent_weight: None,
        }
    }

    /// The site this marker observes on `model`: its `node` or `s_m` on its
    /// `rod` (default 0), or its `body`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `field` unless exactly one of
    /// `node`, `s_m` and `body` is given, or for a `rod` beside `body`;
    /// [`Error::IndexOutOfRange`] named `field.node` / `field.rod` for a
    /// node or rod that does not exist.
    ///
    /// # Example
    /// ```
    /// use softrod::{observe::MarkerObservation, scene::Scene, site::Site};
    /// let robot = Scene::two_section().robot()?;
    /// let m = MarkerObservation::at_node(20, nalgebra::Vector2::new(0.2, 0.05));
    /// assert_eq!(m.site(&robot, "m")?, Site::Rod { rod: 0, s_m: robot.node_arc()[20] });
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn site<M: Sites>(&self, model: &M, field: &str) -> Result<Site> {
        let rod = self.rod.unwrap_or(0);
        match (self.node, self.s_m, self.body) {
            (Some(n), None, None) => Ok(Site::Rod {
                rod,
                s_m: model.node_arc_m(&format!("{field}.node"), rod, n)?,
            }),
            (None, Some(s_m), None) => Ok(Site::Rod { rod, s_m }),
            (None, None, Some(body)) if self.rod.is_none() => Ok(Site::Body { body }),
            (None, None, Some(_)) => Err(Error::invalid(
                format!("{field}.rod"),
                rod,
                "a body marker names no rod",
            )),
            _ => Err(Error::invalid(
                field,
                "",
                "give exactly one of `node`, `s_m` and `body`",
            )),
        }
    }

    /// The measured position as a `D`-vector (m, world axes).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `position_m` if it does not have
    /// `D` components.
    ///
    /// # Example
    /// ```
    /// use softrod::observe::MarkerObservation;
    /// let mut m = MarkerObservation::at_node(20, nalgebra::Vector2::new(0.2, 0.05));
    /// assert_eq!(m.position::<2>()?, nalgebra::Vector2::new(0.2, 0.05));
    /// assert!(m.position::<3>().is_err());
    /// assert_eq!(m.tangent_vector::<2>()?, None);
    /// m.tangent = Some(vec![1.0, 0.0]);
    /// assert_eq!(m.tangent_vector::<2>()?, Some(nalgebra::Vector2::x()));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn position<const D: usize>(&self) -> Result<SVector<f64, D>> {
        check_len("position_m", D, self.position_m.len())?;
        Ok(SVector::from_column_slice(&self.position_m))
    }

    /// The measured tangent `r'` as a `D`-vector (dimensionless), if
    /// observed.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `tangent` if it does not have `D`
    /// components.
    ///
    /// # Example
    /// See [`MarkerObservation::position`].
    pub fn tangent_vector<const D: usize>(&self) -> Result<Option<SVector<f64, D>>> {
        self.tangent
            .as_ref()
            .map(|t| {
                check_len("tangent", D, t.len())?;
                Ok(SVector::from_column_slice(t))
            })
            .transpose()
    }
}

/// One observation: the markers measured at one instant. This is also the
/// format of a markers file (`softrod estimate --markers FILE`):
/// `{"markers": [{"node": 4, "position_m": [0.05, 0.01]}, {"s_m": 0.24,
/// "position_m": [...], "tangent": [...]}, ...]}`.
///
/// # Example
/// ```
/// let o: softrod::observe::Observation = serde_json::from_str(
///     r#"{"markers": [{"node": 20, "position_m": [0.2, 0.05]}]}"#).unwrap();
/// assert_eq!(o.n_components(), 2);
/// ```
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Observation {
    /// The markers.
    pub markers: Vec<MarkerObservation>,
}

impl Observation {
    /// The exact positions of the configuration `q` of `robot` at the given
    /// nodes (a noise-free synthetic observation), refusing a node beyond
    /// the robot or a `q` of another size.
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] named `q`;
    /// [`crate::Error::IndexOutOfRange`] named `nodes[i]`.
    ///
    /// # Example
    /// ```
    /// use softrod::{observe::Observation, scene::Scene};
    /// let robot = Scene::two_section().robot()?;
    /// let q = robot.reference_configuration().as_slice().to_vec();
    /// let o = Observation::of_nodes(&robot, &q, &[10, 20])?;
    /// assert_eq!(o.markers[1].position_m, q[80..82].to_vec());
    /// assert!(Observation::of_nodes(&robot, &q, &[10, 21]).is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn of_nodes<M: Sites>(model: &M, q: &[f64], nodes: &[usize]) -> Result<Self> {
        check_len("q", model.n_q(), q.len())?;
        let mut markers = Vec::with_capacity(nodes.len());
        for (i, &n) in nodes.iter().enumerate() {
            let r = model.node_coordinates_of(&format!("nodes[{i}]"), 0, n)?;
            let p = &q[r.start..r.start + model.dim()];
            markers.push(MarkerObservation::at_node(
                n,
                nalgebra::DVectorView::from(p),
            ));
        }
        Ok(Observation { markers })
    }

    /// The exact positions of the configuration `q` of `model` at `sites`
    /// (a noise-free synthetic observation: the one way the simulated
    /// plants, the reports and the tests make markers).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] named `q`; a site that is not on
    /// the model as [`Sites::site_rows`], named `sites[i]`.
    ///
    /// # Example
    /// ```
    /// use softrod::{observe::Observation, scene::Scene, site::Site};
    /// let robot = Scene::two_section().robot()?;
    /// let q = robot.reference_configuration().as_slice().to_vec();
    /// let o = Observation::of_sites(&robot, &q, &[Site::Rod { rod: 0, s_m: 0.12 }])?;
    /// assert!((o.markers[0].position_m[0] - 0.12).abs() < 1e-12);
    /// assert!(Observation::of_sites(&robot, &q, &[Site::Rod { rod: 0, s_m: 0.5 }]).is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn of_sites<M: Sites>(model: &M, q: &[f64], sites: &[Site]) -> Result<Self> {
        check_len("q", model.n_q(), q.len())?;
        let mut markers = Vec::with_capacity(sites.len());
        for (i, site) in sites.iter().enumerate() {
            let p = model
                .site_rows(&format!("sites[{i}]"), site)?
                .position_at(q);
            markers.push(MarkerObservation::at_site(site, p));
        }
        Ok(Observation { markers })
    }

    /// Number of observed scalar components `n_ob`.
    ///
    /// # Example
    /// See [`Observation`].
    pub fn n_components(&self) -> usize {
        self.markers
            .iter()
            .map(|m| m.position_m.len() + m.tangent.as_ref().map_or(0, |t| t.len()))
            .sum()
    }

    /// Adds seeded Gaussian noise of standard deviation `sigma_m` to every
    /// position component (a deterministic generator: the same seed gives the
    /// same noise).
    ///
    /// # Example
    /// ```
    /// use softrod::observe::{MarkerObservation, Observation};
    /// let o = Observation { markers: vec![MarkerObservation::at_node(1, nalgebra::Vector2::zeros())] };
    /// let (a, b) = (o.clone().with_noise(1e-3, 7), o.with_noise(1e-3, 7));
    /// assert_eq!(a, b);
    /// assert!(a.markers[0].position_m.iter().all(|v| *v != 0.0 && v.abs() < 1e-2));
    /// ```
    pub fn with_noise(mut self, sigma_m: f64, seed: u64) -> Self {
        let mut rng = Gaussian::new(seed);
        for m in &mut self.markers {
            for p in &mut m.position_m {
                *p += sigma_m * rng.sample();
            }
        }
        self
    }
}

/// One row of the observation operator: an observed scalar
/// `Σ_j w_j q[j]`, sparse over all `n_q` coordinates.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ObsRow {
    entries: Vec<(usize, f64)>,
}

impl ObsRow {
    /// The entries `(coordinate index, weight)`.
    pub(crate) fn entries(&self) -> &[(usize, f64)] {
        &self.entries
    }

    /// The observed scalar at `q` (`n_q` coordinates; NaN if `q` is too short).
    pub(crate) fn apply(&self, q: &[f64]) -> f64 {
        crate::site::apply_row(&self.entries, q)
    }
}

/// Whether two markers' sites are one point: the same body, or the same
/// rod within `1e-9` of the model's length.
fn same_site(a: &Site, b: &Site, length_m: f64) -> bool {
    match (a, b) {
        (Site::Body { body: x }, Site::Body { body: y }) => x == y,
        (Site::Rod { rod: r, s_m: s }, Site::Rod { rod: q, s_m: t }) => {
            r == q && (t - s).abs() <= 1e-9 * length_m
        }
        _ => false,
    }
}

/// The observation operator `A`, the measurements `y` and the diagonal
/// weights `W` of an [`Observation`] on a robot, as the estimator's objective
/// `(A q − y)ᵀ W (A q − y)` (25) uses them.
///
/// Default weights are noise-whitened: `1/σ²` for a position component,
/// `1/σ_t²` for a tangent component (a marker's own weights override them).
///
/// # Example
/// ```
/// use softrod::{observe::{Observation, ObservationOperator}, scene::Scene};
/// let robot = Scene::two_section().robot()?;
/// let q = robot.reference_configuration();
/// let obs = Observation::of_nodes(&robot, q.as_slice(), &[4, 20])?;
/// let op = ObservationOperator::new(&robot, &obs, 1e-5, 1e-3)?;
/// assert_eq!(op.len(), 4); // two markers, two components each
/// assert!(!op.is_empty());
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct ObservationOperator {
    rows: Vec<ObsRow>,
    y: Vec<f64>,
    weights: Vec<f64>,
}

impl ObservationOperator {
    /// The operator of `obs` on `robot`, with default weights for the
    /// position noise `noise_sigma_m` (m) and the tangent noise
    /// `tangent_sigma`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `observation.markers[i].…` for a
    /// marker with neither or both of `node` and `s_m`, off the robot, at the
    /// position of another, with a non-finite value or a non-positive weight,
    /// or for no marker at all; [`Error::IndexOutOfRange`] for a node beyond
    /// the last; [`Error::DimensionMismatch`] for a vector that is not `DIM`
    /// long; for a `sigma` that is not finite and positive,
    /// [`Error::InvalidParameter`].
    pub fn new<M: Sites>(
        model: &M,
        obs: &Observation,
        noise_sigma_m: f64,
        tangent_sigma: f64,
    ) -> Result<Self> {
        check_positive("noise_sigma_m", noise_sigma_m)?;
        check_positive("tangent_sigma", tangent_sigma)?;
        let d = model.dim();
        if obs.markers.is_empty() {
            return Err(Error::invalid(
                "observation.markers",
                "[]",
                "needs at least one marker",
            ));
        }
        let mut op = ObservationOperator {
            rows: Vec::new(),
            y: Vec::new(),
            weights: Vec::new(),
        };
        let pw = 1.0 / (noise_sigma_m * noise_sigma_m);
        let tw = 1.0 / (tangent_sigma * tangent_sigma);
        let length = model.length_m();
        let mut seen: Vec<Site> = Vec::with_capacity(obs.markers.len());
        for (i, m) in obs.markers.iter().enumerate() {
            let field = format!("observation.markers[{i}]");
            let name = |f: &str| format!("{field}.{f}");
            let site = m.site(model, &field)?;
            let rows = model.site_rows(&field, &site)?;
            if seen.iter().any(|t| same_site(t, &site, length)) {
                let at = match site {
                    Site::Rod { s_m, .. } => s_m,
                    Site::Body { body } => body as f64,
                };
                return Err(Error::invalid(
                    field,
                    at,
                    "duplicates another marker's position",
                ));
            }
            seen.push(site);
            check_len(&name("position_m"), d, m.position_m.len())?;
            check_all_finite(&name("position_m"), &m.position_m)?;
            // magnitudes that can only overflow: 1e12 robot lengths away
            let far = MAX_MARKER_SCALE * length;
            if let Some(k) = m.position_m.iter().position(|v| v.abs() > far) {
                return Err(Error::invalid(
                    format!("{}[{k}]", name("position_m")),
                    m.position_m[k],
                    format!("is more than {MAX_MARKER_SCALE:e} robot lengths from the origin (m)"),
                ));
            }
            let weights = |w: &Option<Vec<f64>>, field: &str, default: f64| -> Result<Vec<f64>> {
                match w {
                    None => Ok(vec![default; d]),
                    Some(w) => {
                        check_len(&name(field), d, w.len())?;
                        for (k, v) in w.iter().enumerate() {
                            let n = format!("{}[{k}]", name(field));
                            check_positive(&n, *v)?;
                            if *v > MAX_MARKER_SCALE * default {
                                return Err(Error::invalid(
                                    n,
                                    v,
                                    format!(
                                        "is more than {MAX_MARKER_SCALE:e} times the default \
                                         weight {default:e} (1/sigma²): it can only overflow"
                                    ),
                                ));
                            }
                        }
                        Ok(w.clone())
                    }
                }
            };
            let wp = weights(&m.position_weight, "position_weight", pw)?;
            for ((row, y), w) in rows.position.into_iter().zip(&m.position_m).zip(&wp) {
                op.rows.push(ObsRow { entries: row });
                op.y.push(*y);
                op.weights.push(*w);
            }
            if let Some(t) = &m.tangent {
                let Some(tangent_rows) = rows.tangent else {
                    return Err(Error::invalid(
                        name("tangent"),
                        format!("{t:?}"),
                        "a rigid body's point has no tangent: observe its position only",
                    ));
                };
                check_len(&name("tangent"), d, t.len())?;
                check_all_finite(&name("tangent"), t)?;
                let norm = t.iter().map(|v| v * v).sum::<f64>().sqrt();
                if !(norm > 0.0 && norm <= MAX_MARKER_SCALE) {
                    return Err(Error::invalid(
                        name("tangent"),
                        format!("{t:?}"),
                        "must be a direction r' of length about 1 (a stretch), not zero \
                         and not beyond 1e12",
                    ));
                }
                let wtan = weights(&m.tangent_weight, "tangent_weight", tw)?;
                for ((row, y), w) in tangent_rows.into_iter().zip(t).zip(&wtan) {
                    op.rows.push(ObsRow { entries: row });
                    op.y.push(*y);
                    op.weights.push(*w);
                }
            }
        }
        Ok(op)
    }

    /// Number of observed scalars `n_ob` (rows of `A`).
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether there is no row (never, for an operator built by
    /// [`ObservationOperator::new`]).
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// The rows of `A`.
    pub(crate) fn rows(&self) -> &[ObsRow] {
        &self.rows
    }

    /// The measurements `y`.
    pub(crate) fn measurements(&self) -> &[f64] {
        &self.y
    }

    /// The diagonal of `W`.
    pub(crate) fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// `A q`.
    pub(crate) fn apply(&self, q: &[f64]) -> Vec<f64> {
        self.rows.iter().map(|r| r.apply(q)).collect()
    }

    /// `A q − y`.
    pub(crate) fn residual(&self, q: &[f64]) -> Vec<f64> {
        self.rows
            .iter()
            .zip(&self.y)
            .map(|(r, y)| r.apply(q) - y)
            .collect()
    }

    /// `eᵀ W e`.
    pub(crate) fn weighted(&self, e: &[f64]) -> f64 {
        e.iter().zip(&self.weights).map(|(e, w)| w * e * e).sum()
    }

    /// The same operator with the measurements `y` (as many as rows).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `y` has the wrong length.
    pub(crate) fn with_measurements(&self, y: Vec<f64>) -> Result<Self> {
        check_len("y", self.len(), y.len())?;
        Ok(ObservationOperator {
            rows: self.rows.clone(),
            y,
            weights: self.weights.clone(),
        })
    }
}
