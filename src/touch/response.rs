//! The markers' response to a point force anywhere on the robot: at an
//! equilibrium `q` with tangent `K` (`dq = M K⁻¹ Mᵀ dQ`), a force `f` at
//! arc coordinate `s` (generalized force `S(s)ᵀ f`) moves marker
//! coordinate `y_i = c_i · q` by `(S(s) z_i) · f`, with the adjoint field
//! `z_i = M K⁻¹ Mᵀ c_i` (`K` symmetric). One factorization and one solve
//! per marker coordinate give the response to a force at every `s`: the
//! adjoint fields are cable fields, evaluated at `s` by Hermite
//! interpolation.

use nalgebra::DMatrix;

use crate::assembly::Robot;
use crate::element::{ArcPoint, PlanarCable};
use crate::error::{Error, Result};
use crate::linsolve::{AutoSolver, FactorOptions, SolverKind, SymmetricMatrix, TangentSolver};
use crate::loads::Loads;
use crate::sensitivity::Sensitivity;

/// Planar: two position components per point, four numbers per node.
const DIM: usize = 2;

/// The rows `c_i` of the marker coordinates (`DIM` per marker, marker-major)
/// over all `n_q` coordinates.
pub(crate) fn marker_rows(
    robot: &Robot<PlanarCable>,
    marker_s_m: &[f64],
) -> Result<Vec<Vec<(usize, f64)>>> {
    let mut rows = Vec::with_capacity(DIM * marker_s_m.len());
    for (i, &s) in marker_s_m.iter().enumerate() {
        let p = robot.arc_point(&format!("markers[{i}].s_m"), s)?;
        for d in 0..DIM {
            rows.push(
                (0..4)
                    .map(|k| {
                        let node = p.element + k / 2;
                        (node * 2 * DIM + (k % 2) * DIM + d, p.values[k])
                    })
                    .collect(),
            );
        }
    }
    Ok(rows)
}

/// The factors of the tangent of `robot` under `loads` at `q`.
fn tangent_factors(
    robot: &Robot<PlanarCable>,
    loads: &Loads,
    q: &[f64],
) -> Result<<AutoSolver as TangentSolver>::Factors> {
    let pattern = robot.tangent_pattern();
    let mut k = SymmetricMatrix::zeros(pattern.clone());
    robot.tangent_into(q, loads, &mut k)?;
    let mut solver = AutoSolver::with_kind(pattern, SolverKind::Auto)?;
    Ok(solver.factor(&k, FactorOptions::default())?)
}

/// (43) `∂q/∂P = −(∂Q/∂q)⁻¹ ∂Q/∂P` (`n_q × n_pressures`, m/Pa) at the
/// equilibrium `q` of `robot` under `loads`.
///
/// # Errors
/// [`Error::Singular`] if the tangent is singular there.
pub(crate) fn dq_dp(robot: &Robot<PlanarCable>, loads: &Loads, q: &[f64]) -> Result<DMatrix<f64>> {
    let factors = tangent_factors(robot, loads, q)?;
    Sensitivity::new(robot, &factors)?.dq_dp(q)
}

/// `∂y/∂f` of the markers for a point force at any arc coordinate, at one
/// equilibrium (see the [module documentation](crate::touch)).
///
/// # Example
/// A force at the tip moves the tip marker most:
/// ```
/// use softrod::touch::{five_section_scene, MarkerResponse};
/// let scene = five_section_scene(4);
/// let (robot, loads) = (scene.robot()?, scene.loads()?);
/// let q = softrod::statics::StaticSolver::default().solve(&robot, &loads, None)?.q;
/// let r = MarkerResponse::new(&robot, &loads, q.as_slice(), &[0.093, 0.465])?;
/// let g = r.at(0.465)?; // 4 × 2: (markers × xy) × force xy
/// assert!(g[(2, 0)] > g[(0, 0)] && g[(0, 0)] > 0.0);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct MarkerResponse {
    node_arc: Vec<f64>,
    /// Adjoint fields, one column per marker coordinate (`n_q × 2m`).
    z: DMatrix<f64>,
}

impl MarkerResponse {
    /// The response at the equilibrium `q` of `robot` under `loads` (whose
    /// pressures and load field enter the tangent), for markers at the
    /// arc coordinates `marker_s_m` (m).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (`markers[i].s_m`) for a marker off the
    /// robot; [`Error::Singular`] if the tangent is singular there.
    pub fn new(
        robot: &Robot<PlanarCable>,
        loads: &Loads,
        q: &[f64],
        marker_s_m: &[f64],
    ) -> Result<Self> {
        let rows = marker_rows(robot, marker_s_m)?;
        let factors = tangent_factors(robot, loads, q)?;
        let adj = Sensitivity::new(robot, &factors)?.adjoints(rows.iter().map(|r| &r[..]))?;
        Ok(MarkerResponse {
            node_arc: robot.node_arc().to_vec(),
            z: adj.full,
        })
    }

    /// Number of marker coordinates (rows of [`MarkerResponse::at`]).
    pub fn n_outputs(&self) -> usize {
        self.z.ncols()
    }

    /// `∂y/∂f` (`2m × 2`, m/N) for a force at arc coordinate `s` (m).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (`s_m`) for an `s` off the robot.
    pub fn at(&self, s: f64) -> Result<DMatrix<f64>> {
        let p = ArcPoint::locate(&self.node_arc, s)
            .ok_or_else(|| Error::invalid("s_m", s, "must lie on the robot (0 <= s <= length)"))?;
        let m = self.z.ncols();
        let mut g = DMatrix::zeros(m, DIM);
        let mut out = [0.0; DIM];
        for i in 0..m {
            p.value_into(self.z.column(i).as_slice(), &mut out)?;
            for d in 0..DIM {
                g[(i, d)] = out[d];
            }
        }
        Ok(g)
    }
}
