//! Contact localization beyond the paper: what touches the robot is a
//! concentrated force at an unknown arc position. For every candidate `s`
//! (a 1-D search over a grid) the force that best explains the markers is a
//! linear least-squares problem through the markers' response
//! ([`MarkerResponse`]); the `s` of the least misfit is the contact. The
//! model carries the virtual payload as a known load, so the force explains
//! only what the contact-free robot would not show. Two Gauss–Newton
//! passes re-linearize at the equilibrium with the found force.
//!
//! Contact is frictionless, so the force is along the rod's normal
//! ([`PointSearchSettings::normal_only`], the default: one unknown per
//! `s`, its sign giving the obstacle's side); with `normal_only = false`
//! both components are fitted.

use nalgebra::{DMatrix, DVector, Vector2};
use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::element::PlanarCable;
use crate::error::{Error, Result, check_len, check_positive};
use crate::loads::{Loads, PointForce};
use crate::statics::StaticSolver;

use super::MarkerResponse;

/// Settings of [`locate_point_force`]; every field has a documented default.
///
/// # Example
/// ```
/// let s = softrod::touch::PointSearchSettings::default();
/// assert_eq!((s.grid_step_m, s.passes, s.normal_only), (5e-4, 2, true));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct PointSearchSettings {
    /// Spacing of the candidate arc coordinates (m, default 0.5 mm).
    pub grid_step_m: f64,
    /// Linearizations (1: about the contact-free equilibrium only; default 2).
    pub passes: usize,
    /// Fit the force along the rod's normal only (default true).
    pub normal_only: bool,
}

impl Default for PointSearchSettings {
    fn default() -> Self {
        PointSearchSettings {
            grid_step_m: 5e-4,
            passes: 2,
            normal_only: true,
        }
    }
}

/// A contact found by [`locate_point_force`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PointContact {
    /// Arc coordinate of the force (m).
    pub s_m: f64,
    /// The force on the robot (N, world axes).
    pub force_n: [f64; 2],
    /// The markers' misfit at the answer, `Σ (y − ŷ)²` over the components
    /// (m²), of the last linearization.
    pub misfit_m2: f64,
    /// The markers' misfit with no force (m²).
    pub misfit_free_m2: f64,
}

impl PointContact {
    /// [`PointContact::force_n`] as a vector (N, world axes).
    ///
    /// # Example
    /// ```
    /// let c = softrod::touch::PointContact { s_m: 0.1, force_n: [0.0, -0.02],
    ///     misfit_m2: 0.0, misfit_free_m2: 1e-6 };
    /// assert_eq!(c.force(), nalgebra::Vector2::new(0.0, -0.02));
    /// ```
    pub fn force(&self) -> Vector2<f64> {
        Vector2::from(self.force_n)
    }
}

/// The point force on `robot` (under the known loads `known`, the virtual
/// payload in `known.distributed_f`) that best explains the marker
/// positions `markers_m` at the arc coordinates `marker_s_m` (see the
/// [module documentation](crate::touch)). `offset_m` (empty, or one vector per
/// marker, m) is what the model with the virtual payload still misses of
/// the contact-free markers, recorded with it ([`marker_offset`]); it is
/// subtracted from the markers.
///
/// # Errors
/// [`Error::DimensionMismatch`] for markers and positions of different
/// counts; [`Error::InvalidParameter`] for settings out of range or markers
/// off the robot; the static solver's errors.
///
/// # Example
/// See `tests/touch.rs`.
pub fn locate_point_force(
    robot: &Robot<PlanarCable>,
    known: &Loads,
    marker_s_m: &[f64],
    markers_m: &[Vector2<f64>],
    offset_m: &[Vector2<f64>],
    settings: &PointSearchSettings,
) -> Result<PointContact> {
    check_len("markers", marker_s_m.len(), markers_m.len())?;
    if !offset_m.is_empty() {
        check_len("offset_m", marker_s_m.len(), offset_m.len())?;
    }
    check_positive("grid_step_m", settings.grid_step_m)?;
    if settings.passes == 0 {
        return Err(Error::invalid("passes", 0, "must be >= 1"));
    }
    let mut y: Vec<f64> = markers_m.iter().flat_map(|v| v.iter().copied()).collect();
    if !offset_m.is_empty() {
        let o: Vec<f64> = offset_m.iter().flat_map(|v| v.iter().copied()).collect();
        check_len("offset_m", y.len(), o.len())?;
        y.iter_mut().zip(&o).for_each(|(a, b)| *a -= b);
    }
    let statics = StaticSolver::default();
    let q_free = statics.solve(robot, known, None)?.q;
    let length = robot.length();
    let n_grid = ((length / settings.grid_step_m).ceil() as usize).max(1);
    let grid: Vec<f64> = (1..=n_grid)
        .map(|i| (i as f64 * length / n_grid as f64).min(length))
        .collect();
    let mut q = q_free.clone();
    let mut loads = known.clone();
    let mut current: Option<(f64, [f64; 2])> = None;
    let mut best = PointContact {
        s_m: 0.0,
        force_n: [0.0; 2],
        misfit_m2: 0.0,
        misfit_free_m2: misfit(robot, q_free.as_slice(), marker_s_m, &y)?,
    };
    for _ in 0..settings.passes {
        let resp = MarkerResponse::new(robot, &loads, q.as_slice(), marker_s_m)?;
        let mut d = DVector::from_vec(residual(robot, q.as_slice(), marker_s_m, &y)?);
        // the linearization holds the present force: d = y − A q + G(s0) f0
        if let Some((s0, f0)) = current {
            d += resp.at(s0)? * DVector::from_row_slice(&f0);
        }
        let mut pick: Option<(f64, f64, [f64; 2])> = None;
        for &s in &grid {
            let g = resp.at(s)?;
            let (f, r) = fit(
                &g,
                &d,
                normal(robot, q.as_slice(), s)?,
                settings.normal_only,
            );
            if pick.is_none_or(|(r0, _, _)| r < r0) {
                pick = Some((r, s, f));
            }
        }
        let Some((r, s, f)) = pick else { break };
        best.s_m = s;
        best.force_n = f;
        best.misfit_m2 = r;
        current = Some((s, f));
        loads = known.clone();
        loads.point_forces.push(PointForce {
            s_m: s,
            force_n: f.to_vec(),
        });
        q = statics.solve(robot, &loads, Some(q.as_slice()))?.q;
    }
    Ok(best)
}

/// What the model under `known` (with the virtual payload) misses of the
/// contact-free markers `free_markers_m`: `y_free − A q(known)` per marker
/// (m), to record with the virtual payload.
///
/// # Errors
/// As [`locate_point_force`].
///
/// # Example
/// The model's own contact-free markers leave no offset:
/// ```
/// use softrod::{statics::StaticSolver, touch::{five_section_scene, marker_arcs, marker_offset}};
/// let scene = five_section_scene(2);
/// let (robot, loads) = (scene.robot()?, scene.loads()?);
/// let arcs = marker_arcs(6);
/// let q = StaticSolver::default().solve(&robot, &loads, None)?.q;
/// let free: Vec<nalgebra::Vector2<f64>> = arcs
///     .iter()
///     .map(|&s| robot.position_at_fixed(q.as_slice(), s))
///     .collect::<softrod::Result<_>>()?;
/// let offset = marker_offset(&robot, &loads, arcs.as_slice(), &free)?;
/// assert!(offset.len() == 6 && offset.iter().all(|o| o.norm() < 1e-12));
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn marker_offset(
    robot: &Robot<PlanarCable>,
    known: &Loads,
    marker_s_m: &[f64],
    free_markers_m: &[Vector2<f64>],
) -> Result<Vec<Vector2<f64>>> {
    check_len("markers", marker_s_m.len(), free_markers_m.len())?;
    let q = StaticSolver::default().solve(robot, known, None)?.q;
    marker_s_m
        .iter()
        .zip(free_markers_m)
        .map(|(&s, y)| {
            let p: Vector2<f64> = robot.position_at_fixed(q.as_slice(), s)?;
            Ok(y - p)
        })
        .collect()
}

/// `y − A q` of the markers (m).
fn residual(robot: &Robot<PlanarCable>, q: &[f64], s_m: &[f64], y: &[f64]) -> Result<Vec<f64>> {
    let mut out = Vec::with_capacity(y.len());
    for &s in s_m {
        out.extend(robot.position_at(q, s)?.iter());
    }
    out.iter_mut().zip(y).for_each(|(a, b)| *a = b - *a);
    Ok(out)
}

fn misfit(robot: &Robot<PlanarCable>, q: &[f64], s_m: &[f64], y: &[f64]) -> Result<f64> {
    Ok(residual(robot, q, s_m, y)?.iter().map(|v| v * v).sum())
}

/// The unit normal (tangent turned by +90°) of the shape `q` at `s`.
fn normal(robot: &Robot<PlanarCable>, q: &[f64], s: f64) -> Result<[f64; 2]> {
    let mut t = [0.0; 2];
    robot.arc_point("s_m", s)?.slope_into(q, &mut t)?;
    let n = t[0].hypot(t[1]);
    Ok(if n > 0.0 {
        [-t[1] / n, t[0] / n]
    } else {
        [0.0; 2]
    })
}

/// The force minimizing `|d − G f|²` (along `n` only if `normal_only`)
/// and the misfit; no force if `G` does not see it.
fn fit(g: &DMatrix<f64>, d: &DVector<f64>, n: [f64; 2], normal_only: bool) -> ([f64; 2], f64) {
    let dd = d.norm_squared();
    if normal_only {
        let gn = g * DVector::from_row_slice(&n);
        let a = gn.norm_squared();
        if a <= 1e-300 {
            return ([0.0; 2], dd);
        }
        let lam = gn.dot(d) / a;
        ([lam * n[0], lam * n[1]], (d - gn * lam).norm_squared())
    } else {
        let gtg = g.transpose() * g;
        let gtd = g.transpose() * d;
        match gtg.clone().cholesky() {
            Some(c) if gtg.determinant() > 1e-24 * gtg.trace().powi(2) => {
                let f = c.solve(&gtd);
                ([f[0], f[1]], (d - g * &f).norm_squared())
            }
            _ => ([0.0; 2], dd),
        }
    }
}
