//! What a scene asks of the solvers: their settings, the refinement target
//! of `"elements": "auto"`, and where the unknown load acts.

use serde::{Deserialize, Serialize};

#[cfg(doc)]
use super::Scene;
use crate::estimate::EstimatorSettings;
#[cfg(doc)]
use crate::estimate::LoadModel;
use crate::statics::StaticSettings;

/// Solver settings of a scene.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSettings {
    /// Static solver settings.
    #[serde(default, rename = "static")]
    pub statics: StaticSettings,
    /// Estimator settings (`"estimator": {"backend": "newton" | "sqp",
    /// "alpha": ..., "noise_sigma_m": ..., ...}`, every field optional; see
    /// [`EstimatorSettings`] for the fields and their defaults).
    #[serde(default)]
    pub estimator: EstimatorSettings,
}

/// The default of [`RefinementTarget`]'s `max_elements`.
pub const DEFAULT_MAX_REFINED_ELEMENTS: usize = 2000;

fn max_refined() -> usize {
    DEFAULT_MAX_REFINED_ELEMENTS
}

/// What the refinement of `"elements": "auto"` sections must achieve: a
/// tolerance on one named quantity, with the unit in the field name
/// (`"refinement": {"quantity": "tip_position", "tolerance_m": 1e-5}`).
/// See [`crate::refine`] for how the mesh is chosen.
///
/// # Example
/// ```
/// use softrod::scene::RefinementTarget;
/// let t: RefinementTarget = serde_json::from_str(
///     r#"{"quantity": "load_resultant", "tolerance_n": 1e-3, "max_elements": 400}"#).unwrap();
/// assert_eq!(t.tolerance(), 1e-3);
/// assert_eq!(t.max_elements(), 400);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(
    tag = "quantity",
    rename_all = "snake_case",
    deny_unknown_fields,
    try_from = "RefinementFile"
)]
pub enum RefinementTarget {
    /// The tip position of the scene's static equilibrium (its loads and
    /// pressures): the Euclidean norm of its error at most `tolerance_m`.
    TipPosition {
        /// Tolerance on the tip position error (m).
        tolerance_m: f64,
        /// Most elements (in all, fixed sections included) a tried mesh may
        /// have (default [`DEFAULT_MAX_REFINED_ELEMENTS`]).
        #[serde(default = "max_refined")]
        max_elements: usize,
    },
    /// The resultant force of the estimated unknown load, fitted to an
    /// observation (see [`crate::refine`]): the norm of its error at most
    /// `tolerance_n`.
    LoadResultant {
        /// Tolerance on the resultant force error (N).
        tolerance_n: f64,
        /// Most elements (in all) a tried mesh may have (default
        /// [`DEFAULT_MAX_REFINED_ELEMENTS`]).
        #[serde(default = "max_refined")]
        max_elements: usize,
    },
}

/// `refinement` as written in the file: a plain struct, so that an error in
/// one of its fields is reported under that field's path (a tagged enum
/// would report every error at `refinement`).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RefinementFile {
    quantity: RefinementQuantity,
    tolerance_m: Option<f64>,
    tolerance_n: Option<f64>,
    #[serde(default = "max_refined")]
    max_elements: usize,
}

#[derive(Deserialize)]
#[serde(rename_all = "snake_case")]
enum RefinementQuantity {
    TipPosition,
    LoadResultant,
}

impl TryFrom<RefinementFile> for RefinementTarget {
    type Error = String;
    fn try_from(f: RefinementFile) -> std::result::Result<Self, String> {
        let max_elements = f.max_elements;
        match (f.quantity, f.tolerance_m, f.tolerance_n) {
            (RefinementQuantity::TipPosition, Some(tolerance_m), None) => {
                Ok(RefinementTarget::TipPosition {
                    tolerance_m,
                    max_elements,
                })
            }
            (RefinementQuantity::LoadResultant, None, Some(tolerance_n)) => {
                Ok(RefinementTarget::LoadResultant {
                    tolerance_n,
                    max_elements,
                })
            }
            (RefinementQuantity::TipPosition, _, Some(_)) => Err(
                "unknown field `tolerance_n` for quantity tip_position: its tolerance is `tolerance_m` (m)".into(),
            ),
            (RefinementQuantity::LoadResultant, Some(_), _) => Err(
                "unknown field `tolerance_m` for quantity load_resultant: its tolerance is `tolerance_n` (N)".into(),
            ),
            (RefinementQuantity::TipPosition, None, _) => {
                Err("missing field `tolerance_m` (m) of quantity tip_position".into())
            }
            (RefinementQuantity::LoadResultant, _, None) => {
                Err("missing field `tolerance_n` (N) of quantity load_resultant".into())
            }
        }
    }
}

impl RefinementTarget {
    /// The tolerance, in the quantity's unit (m or N).
    pub fn tolerance(&self) -> f64 {
        match *self {
            RefinementTarget::TipPosition { tolerance_m, .. } => tolerance_m,
            RefinementTarget::LoadResultant { tolerance_n, .. } => tolerance_n,
        }
    }

    /// The most elements a tried mesh may have.
    pub fn max_elements(&self) -> usize {
        match *self {
            RefinementTarget::TipPosition { max_elements, .. }
            | RefinementTarget::LoadResultant { max_elements, .. } => max_elements,
        }
    }

    /// The tolerance's field name in the scene (`tolerance_m` or `tolerance_n`).
    pub fn tolerance_field(&self) -> &'static str {
        match self {
            RefinementTarget::TipPosition { .. } => "tolerance_m",
            RefinementTarget::LoadResultant { .. } => "tolerance_n",
        }
    }
}

/// Where the unknown load of an estimation acts, independently of the mesh
/// (`"unknown_load": {"acts_at": "point", "s_m": 0.24}`). A point load is
/// estimated as a concentrated force at the node at `s_m`
/// ([`LoadModel::Concentrated`]); the node must exist (on a fixed mesh) or
/// is kept by the refinement (with `"elements": "auto"`). See
/// [`Scene::estimator_settings`].
///
/// # Example
/// ```
/// use softrod::scene::UnknownLoad;
/// let u: UnknownLoad = serde_json::from_str(r#"{"acts_at": "point", "s_m": 0.24}"#).unwrap();
/// assert_eq!(u, UnknownLoad::Point { s_m: 0.24 });
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "acts_at", rename_all = "snake_case", deny_unknown_fields)]
pub enum UnknownLoad {
    /// A distributed load along the whole backbone ([`LoadModel::Distributed`]).
    Distributed,
    /// A force at one point of the backbone.
    Point {
        /// Undeformed arc coordinate of the point (m, > 0: the clamped base
        /// takes no load).
        s_m: f64,
    },
}
