//! Mesh sequencing: a cold solve of a fine mesh starts from the
//! equilibrium of a coarse mesh of the same model
//! ([`MeshSequencing::coarse_model`](crate::structure::MeshSequencing::coarse_model)), interpolated onto the fine one
//! ([`MeshSequencing::prolong`](crate::structure::MeshSequencing::prolong)).
//!
//! Why (measured, `benches/statics_scaling.rs`): the continuation's load
//! steps are set by the rotation of the solution, not by the mesh, but on a
//! fine mesh each corrector contracts more slowly: a concentrated moment
//! acts on one node slope, whose stretch only `EA L_e` holds, and the
//! predictor's error in the stiff axial coordinates grows with `n`
//! (tip moment 0.3 × its own EI/L: 11 iterations at 8 elements, 69 at 2000;
//! a tip moment rolling the rod into a circle: 31 at 8, 237 at 2000). The
//! coarse mesh follows the load path at a cost that does not depend on the
//! fine mesh; the interpolated coarse equilibrium differs from the fine one
//! by the coarse discretization error only, which plain Newton removes in a
//! few full steps whatever the fine mesh.

use super::StaticSolver;
use super::newton::{Target, Work};
use crate::error::{Error, Result};
use crate::linsolve::AutoSolver;
use crate::outcome::{StaticStatus, StaticWarning};
use crate::structure::Model;

/// Newton iterations on the fine mesh from the interpolated coarse
/// equilibrium (full steps only); past them the solve goes on as without a
/// coarse start.
const FINE_ITERATIONS: usize = 8;

/// What the coarse start gave.
pub(super) struct CoarseStart {
    /// The fine free coordinates of the coarse equilibrium (`None`: the
    /// coarse solve failed).
    pub(super) u: Option<Vec<f64>>,
    /// Newton iterations the coarse solve took (counted in the report).
    pub(super) iterations: usize,
    /// Its load steps.
    pub(super) load_steps: usize,
    /// The critical points its load path passed
    /// ([`StaticWarning::Bifurcation`]; its stability warning is the coarse
    /// answer's, not the fine one's, and is not carried).
    pub(super) warnings: Vec<StaticWarning>,
}

impl StaticSolver {
    /// Solves `coarse`, the coarse model of `model` with its loads
    /// ([`MeshSequencing::coarse_model`](crate::structure::MeshSequencing::coarse_model)), cold and interpolates its equilibrium
    /// onto `model`.
    pub(super) fn coarse_start<M: Model>(
        &self,
        model: &M,
        (coarse, coarse_loads): (M, M::Loads),
        budget: usize,
    ) -> Result<CoarseStart> {
        let pattern = coarse.tangent_pattern()?;
        let mut solver = AutoSolver::with_kind(&pattern, self.settings.linear_solver)?;
        let u0: Vec<f64> = coarse.start_free_coordinates(&coarse_loads)?.data.into();
        let inner = StaticSolver {
            settings: super::StaticSettings {
                max_total_iterations: budget.max(self.settings.max_iterations),
                ..self.settings.clone()
            },
        };
        match inner.run(&coarse, &coarse_loads, u0, true, &mut solver) {
            Ok(eq) => Ok(CoarseStart {
                u: Some(model.prolong(&coarse, eq.q.as_slice())?.data.into()),
                iterations: eq.report.iterations,
                load_steps: eq.report.load_steps,
                warnings: (eq.report.warnings.into_iter())
                    .filter(|w| matches!(w, StaticWarning::Bifurcation { .. }))
                    .collect(),
            }),
            Err(Error::NotConverged { report }) => Ok(CoarseStart {
                u: None,
                iterations: report.iterations,
                load_steps: report.load_steps,
                warnings: Vec::new(),
            }),
            Err(e) => Err(e),
        }
    }

    /// Plain Newton (full steps) on the full loads from the prolonged
    /// coarse equilibrium in `u` (`w.q = φ(u)`).
    pub(super) fn fine_newton<M: Model>(
        &self,
        model: &M,
        full: &Target<'_, M>,
        u: &mut [f64],
        w: &mut Work<'_>,
        scale: f64,
    ) -> Result<StaticStatus> {
        let fine = StaticSolver {
            settings: super::StaticSettings {
                max_iterations: self.settings.max_iterations.min(FINE_ITERATIONS),
                ..self.settings.clone()
            },
        };
        fine.newton(model, full, u, w, scale)
    }
}
