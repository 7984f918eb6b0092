//! `G F` of the load models (a [`LinearLoad`] on every model): the
//! distributed field (8) with `G = B = ∫ Sᵀ S dX` (22), (23) on the clamped
//! robot's rod, and a force at a site (32)–(35) with `G = A_xᵀ`, `A_x` the
//! site's position rows ([`crate::site::SiteRows`]) on any model.

use nalgebra::{DMatrix, DVector};

use super::{EstimationModel, LoadModel};
use crate::error::{Error, Result, check_len};
use crate::site::{Site, SiteRows, Sites, block_position_rows};
use crate::statics::LinearLoad;
use crate::structure::Rod;

impl LoadModel {
    /// The site of a concentrated load on `model` (`None` for the
    /// distributed field): `Concentrated { node }` at the node of rod 0.
    ///
    /// # Errors
    /// [`Error::IndexOutOfRange`] named `load_model.node` for a node that
    /// does not exist.
    pub(crate) fn site<M: Sites>(&self, model: &M) -> Result<Option<Site>> {
        match *self {
            LoadModel::Distributed => Ok(None),
            LoadModel::Concentrated { node } => Ok(Some(Site::Rod {
                rod: 0,
                s_m: model.node_arc_m("load_model.node", 0, node)?,
            })),
            LoadModel::AtSite { site } | LoadModel::Along { site, .. } => Ok(Some(site)),
        }
    }

    /// Refuses the distributed field on a model that has no field rod (a
    /// structure: it is defined on the clamped robot's rod only), as
    /// [`field_rod`] does, naming the load model `name`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] named `name`.
    pub(crate) fn check_defined_on<M: EstimationModel>(&self, model: &M, name: &str) -> Result<()> {
        match self {
            LoadModel::Distributed => field_rod_named(model, name).map(|_| ()),
            LoadModel::Concentrated { .. } | LoadModel::AtSite { .. } | LoadModel::Along { .. } => {
                Ok(())
            }
        }
    }

    /// The position rows `A_x` of a concentrated load's site (`None` for
    /// the distributed field): at a node, its position coordinates exactly
    /// (no interpolation, whose weights at the last node are 1 and 0 only
    /// to round-off).
    pub(crate) fn site_rows<M: Sites>(&self, model: &M) -> Result<Option<SiteRows>> {
        match *self {
            LoadModel::Distributed => Ok(None),
            LoadModel::Concentrated { node } => {
                let r = model.node_coordinates_of("load_model.node", 0, node)?;
                Ok(Some(block_position_rows(r, model.dim())))
            }
            LoadModel::AtSite { site } | LoadModel::Along { site, .. } => {
                model.site_rows("load_model.site", &site).map(Some)
            }
        }
    }
}

/// Refuses a concentrated load at a site that does not move (every column
/// of `Tᵀ G` zero at the reference: the clamp, a body fixed to the
/// ground): no observation can tell its force.
///
/// # Errors
/// [`Error::InvalidParameter`] named `estimator.load_model`.
pub(crate) fn check_site_moves<M: EstimationModel>(load: &LoadModel, model: &M) -> Result<()> {
    if !load.is_concentrated() {
        return Ok(());
    }
    let u = model.reference_free_coordinates();
    let n = load.n_params(model);
    let mut out = vec![0.0; model.n_free()];
    let mut moves = false;
    for j in 0..n {
        let mut e = vec![0.0; n];
        e[j] = 1.0;
        let g = load.force(model, &e)?;
        model.restrict_into(u.as_slice(), g.as_slice(), &mut out)?;
        moves |= out.iter().any(|v| *v != 0.0);
    }
    if moves {
        Ok(())
    } else {
        Err(Error::invalid(
            "estimator.load_model",
            format!("{load:?}"),
            "the site does not move (the clamp, or a body fixed to the ground): \
             no observation can tell a force there",
        ))
    }
}

/// `A_xᵀ F` over all `n_q` coordinates (34), `F = basis θ` the force of
/// the parameters `θ` ([`LoadModel::force_basis`]).
fn site_force(
    rows: &SiteRows,
    basis: &DMatrix<f64>,
    n_q: usize,
    th: &[f64],
) -> Result<DVector<f64>> {
    check_len("f", basis.ncols(), th.len())?;
    check_len("load_model.site", rows.position.len(), basis.nrows())?;
    let f = basis * DVector::from_column_slice(th);
    let mut g = DVector::zeros(n_q);
    for (row, fc) in rows.position.iter().zip(f.iter()) {
        for &(j, w) in row {
            g[j] += w * fc;
        }
    }
    Ok(g)
}

/// `basisᵀ A_x v`.
fn site_force_transpose(
    rows: &SiteRows,
    basis: &DMatrix<f64>,
    n_q: usize,
    v: &[f64],
) -> Result<DVector<f64>> {
    check_len("v", n_q, v.len())?;
    let ax = DVector::from_iterator(
        rows.position.len(),
        rows.position.iter().map(|r| crate::site::apply_row(r, v)),
    );
    check_len("load_model.site", basis.nrows(), ax.len())?;
    Ok(basis.tr_mul(&ax))
}

/// The rod of the distributed field.
///
/// # Errors
/// [`Error::InvalidParameter`] named `estimator.load_model` for a model
/// without one.
pub(crate) fn field_rod<M: EstimationModel>(model: &M) -> Result<&Rod<M::Element>> {
    field_rod_named(model, "estimator.load_model")
}

/// [`field_rod`], its refusal naming the load model `name`.
fn field_rod_named<'a, M: EstimationModel>(
    model: &'a M,
    name: &str,
) -> Result<&'a Rod<M::Element>> {
    model.field_rod().ok_or_else(|| {
        Error::invalid(
            name,
            "distributed",
            "the distributed field is defined on the clamped robot's rod only: on a structure, \
             take a force at a site ({\"kind\": \"at_site\", \"site\": …})",
        )
    })
}

impl<M: EstimationModel> LinearLoad<M> for LoadModel {
    fn n_params(&self, model: &M) -> usize {
        match self {
            LoadModel::Distributed => model.n_q(),
            LoadModel::Along { .. } => 1,
            LoadModel::Concentrated { .. } | LoadModel::AtSite { .. } => model.dim(),
        }
    }

    fn force(&self, model: &M, f: &[f64]) -> Result<DVector<f64>> {
        match (self.site_rows(model)?, self.force_basis(model.dim())?) {
            (Some(rows), Some(basis)) => site_force(&rows, &basis, model.n_q(), f),
            _ => field_rod(model)?.apply_load_gram(f),
        }
    }

    fn force_transpose(&self, model: &M, v: &[f64]) -> Result<DVector<f64>> {
        match (self.site_rows(model)?, self.force_basis(model.dim())?) {
            (Some(rows), Some(basis)) => site_force_transpose(&rows, &basis, model.n_q(), v),
            _ => field_rod(model)?.apply_load_gram(v),
        }
    }

    fn add_to(&self, model: &M, known: &M::Loads, f: &[f64]) -> M::Loads {
        match self.site(model) {
            Ok(None) => model.with_distributed(known, f),
            Ok(Some(site)) => match self.force_basis(model.dim()) {
                Ok(Some(basis)) if basis.ncols() == f.len() => {
                    let force = basis * DVector::from_column_slice(f);
                    model.with_point_force(known, &site, force.as_slice())
                }
                // refused by the loads' check (a force of the wrong size)
                _ => model.with_point_force(known, &site, &vec![f64::NAN; model.dim()]),
            },
            // refused by the loads' check (a point off the model)
            Err(_) => model.with_point_force(
                known,
                &Site::Rod {
                    rod: 0,
                    s_m: f64::NAN,
                },
                f,
            ),
        }
    }
}
