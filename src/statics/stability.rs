//! The stability of a converged equilibrium, and leaving a saddle.
//!
//! Newton's method finds every equilibrium `R(u) = 0`, the unstable ones
//! too: a column loaded beyond its buckling load has a straight equilibrium
//! (a saddle of the total potential) next to the bent, stable one, and a
//! load continuation that steps over the bifurcation lands on the saddle.
//! After convergence the tangent at the answer is factored once more: the
//! signs of its `L D Lᵀ` pivots are the signs of its eigenvalues (Sylvester's
//! law of inertia), so a negative pivot means a saddle or a maximum. Then
//! the direction of most negative curvature is found by inverse iteration
//! on the Jacobi-scaled pencil `(K + μ D)⁻¹ D` with the smallest decade-and-
//! bisection shift `μ` that makes `K + μ D` positive definite (its dominant
//! eigenvector is that of the most negative eigenvalue of `K x = λ D x`), the
//! configuration is moved along it (the sign with the lower potential) and
//! a descent Newton run (positive definite shifted tangents only, steps
//! accepted only when they lower the potential) goes down to a minimum,
//! whose inertia is checked again. A saddle the solver cannot leave is
//! returned as it is, with its negative eigenvalues in the report.
//!
//! The side: given the load path's tangent at its last stable point (the
//! continuation's escape, [`super::continuation`]), the side it leaned to
//! (the sign of its projection on the direction), which for an imperfect
//! bifurcation (a lateral load, a tilt: the path bends away smoothly) is the
//! branch connected to the unloaded state; the side of the lower potential
//! when the path leans to neither (a symmetric load, [`BranchChoice::Symmetric`])
//! or no path is known (a saddle at the full load,
//! [`BranchChoice::LowerPotential`]; [`BranchChoice::Symmetric`] when the
//! load vector has no component along the direction). Comparing the potentials alone chose
//! by round-off: on the upright column with a 0.01 N lateral tip force the
//! two sides' potentials differed by 1e-3 of their change, and the side
//! flipped from mesh to mesh (+x at 8 elements, −x at 16).

use super::StaticSolver;
use super::newton::{Target, Work};
use crate::error::Result;
use crate::linsolve::{FactorOptions, Factorization, Inertia, LinsolveError, TangentSolver};
use crate::outcome::{BranchChoice, StaticStatus};
use crate::structure::{Model, ModelLoads};

/// Escapes from a saddle tried at most before the saddle is returned.
const ESCAPES: usize = 3;
/// Rotation (rad) of the largest node slope of the first move along the
/// negative-curvature direction: far enough that the potential drops by
/// more than round-off, small enough to stay in the saddle's basin side.
const ESCAPE_ROTATION: f64 = 0.2;
/// Inverse iterations for the negative-curvature direction.
const INVERSE_ITERATIONS: usize = 30;
/// A path tangent whose projection on the direction of negative curvature
/// (or the load vector's, for a saddle at the full load) is below this
/// fraction of the product of their norms leans to neither side
/// ([`BranchChoice::Symmetric`]). (Measured on the post-buckled columns of
/// `tests/statics_branch.rs`: 0.5 to 1.0 with a 0.01 N lateral tip force,
/// a 0.01 rad tilt or a tip mass; the perfectly upright column, whose only
/// asymmetry is the round-off of `cos(π/2)`, falls below it at 8 and 32
/// elements and is reported ambiguous.)
const LEAN_FRACTION: f64 = 1e-8;

/// What [`StaticSolver::stabilize`] gives.
pub(super) struct Stabilized {
    /// The status of the answer.
    pub(super) status: StaticStatus,
    /// Its inertia (`None` when no `L D Lᵀ` of its tangent exists).
    pub(super) inertia: Option<Inertia>,
    /// How the side was chosen when a saddle was left (`None`: none was).
    pub(super) branch: Option<BranchChoice>,
}

impl StaticSolver {
    /// The inertia of the tangent at `u` under the full loads (`None` when
    /// no `L D Lᵀ` of it exists); when it has a negative eigenvalue, leaves
    /// the saddle for a stable equilibrium (`u`, `w.q` updated) if it can,
    /// the first time toward the side `path` (the load path's tangent at its
    /// last stable point) leans to, when given and leaning (see the module
    /// documentation); without a path, the side of the lower potential, and
    /// the choice is called symmetric when the load vector has no component
    /// along the direction. Returns the status of the answer, its inertia and how
    /// a side was chosen.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn stabilize<M: Model>(
        &self,
        model: &M,
        dead: &[f64],
        loads: &M::Loads,
        u: &mut Vec<f64>,
        w: &mut Work<'_>,
        scale: f64,
        status: StaticStatus,
        path: Option<&[f64]>,
    ) -> Result<Stabilized> {
        let mut out = Stabilized {
            status,
            inertia: None,
            branch: None,
        };
        if !loads.conservative() {
            // no potential: the symmetric tangent is not the stability
            return Ok(out);
        }
        let zero = vec![0.0; model.n_free()];
        for _ in 0..=ESCAPES {
            out.inertia = self.inertia_at(model, dead, loads, u, w)?;
            let Some(i) = out.inertia else {
                return Ok(out);
            };
            if i.negative == 0 {
                return Ok(out);
            }
            let Some(d) = negative_curvature(w)? else {
                return Ok(out);
            };
            let (saddle_u, saddle_q) = (u.clone(), w.q.clone());
            let (side, choice) = match path {
                Some(t) => match lean(t, &d) {
                    Some(sign) => (Some(sign), BranchChoice::LoadPath),
                    None => (None, BranchChoice::Symmetric),
                },
                // no path: whether the loads lean along d at all
                None => match lean(&self.load_vector(model, dead, loads, u, w)?, &d) {
                    Some(_) => (None, BranchChoice::LowerPotential),
                    None => (None, BranchChoice::Symmetric),
                },
            };
            self.leave_along(model, dead, loads, u, w, &d, side)?;
            let descent = Target::<M> {
                dead,
                loads,
                offset: &zero,
                strict: false,
                descent: true,
                definite_only: false,
                full: true,
            };
            let mut next = self.newton(model, &descent, u, w, scale)?;
            if !next.is_converged() {
                // the descent stopped short of the minimum (measured: the
                // upright column with a lateral tip force at 32 elements,
                // after 29 iterations): plain Newton from where it stopped;
                // the inertia test of the next pass tells what it reached
                let plain = Target::<M> {
                    descent: false,
                    ..descent
                };
                next = self.newton(model, &plain, u, w, scale)?;
            }
            if !next.is_converged() {
                // the saddle, reported with its inertia (the iterations spent
                // trying stay counted)
                u.copy_from_slice(&saddle_u);
                w.q.copy_from_slice(&saddle_q);
                return Ok(out);
            }
            out.branch = Some(choice);
            out.status = next;
        }
        out.inertia = self.inertia_at(model, dead, loads, u, w)?;
        Ok(out)
    }

    /// The generalized load vector at `u`, `R(u; loads) − R(u; no loads)`.
    fn load_vector<M: Model>(
        &self,
        model: &M,
        dead: &[f64],
        loads: &M::Loads,
        u: &[f64],
        w: &Work<'_>,
    ) -> Result<Vec<f64>> {
        let n = model.n_free();
        let (mut r1, mut r0) = (vec![0.0; n], vec![0.0; n]);
        model.residual_into(u, &w.q, dead, loads, &mut r1)?;
        let unloaded = loads.scaled(0.0);
        model.residual_into(u, &w.q, &vec![0.0; model.n_q()], &unloaded, &mut r0)?;
        r1.iter_mut().zip(&r0).for_each(|(a, b)| *a -= b);
        Ok(r1)
    }

    /// Factors the tangent at `u` (full loads) for its inertia.
    fn inertia_at<M: Model>(
        &self,
        model: &M,
        dead: &[f64],
        loads: &M::Loads,
        u: &[f64],
        w: &mut Work<'_>,
    ) -> Result<Option<Inertia>> {
        model.tangent_into(u, &w.q, dead, loads, &mut w.k)?;
        match w.solver.factor(&w.k, FactorOptions::default()) {
            Ok(f) => Ok(f.inertia()),
            Err(LinsolveError::Singular { .. } | LinsolveError::NonFinite { .. }) => Ok(None),
            Err(e) => Err(e.into()),
        }
    }

    /// Moves `u` from the saddle along `±d` by [`ESCAPE_ROTATION`]: the
    /// sign `side` when given, else the sign with the lower potential.
    #[allow(clippy::too_many_arguments)]
    fn leave_along<M: Model>(
        &self,
        model: &M,
        dead: &[f64],
        loads: &M::Loads,
        u: &mut Vec<f64>,
        w: &mut Work<'_>,
        d: &[f64],
        side: Option<f64>,
    ) -> Result<()> {
        let mut dq = vec![0.0; model.n_q()];
        model.step_into(u, d, &mut dq)?;
        let rotation = model.step_rotation(&dq);
        let s = if rotation > 0.0 {
            ESCAPE_ROTATION / rotation
        } else {
            1.0
        };
        let mut energies = Vec::new();
        model.energies_into(&w.q, &mut energies)?;
        let mut best: Option<(f64, Vec<f64>, Vec<f64>)> = None;
        let signs: &[f64] = match &side {
            Some(sign) => std::slice::from_ref(sign),
            None => &[1.0, -1.0],
        };
        for &sign in signs {
            let (mut u_try, mut q_try) = (u.clone(), w.q.clone());
            model.advance_into(u, &w.q, d, &dq, sign * s, &mut u_try, &mut q_try)?;
            let dpi =
                model.potential_change_from(u, &w.q, &energies, &u_try, &q_try, dead, loads)?;
            if dpi.is_finite() && best.as_ref().is_none_or(|(b, _, _)| dpi < *b) {
                best = Some((dpi, u_try, q_try));
            }
        }
        if let Some((_, u_new, q_new)) = best {
            *u = u_new;
            w.q = q_new;
        }
        Ok(())
    }
}

/// The side (`±1`) the path tangent `t` leans to along `d`, `None` when its
/// projection is below [`LEAN_FRACTION`] of `|t| |d|`.
fn lean(t: &[f64], d: &[f64]) -> Option<f64> {
    let dot: f64 = t.iter().zip(d).map(|(a, b)| a * b).sum();
    let scale = crate::numeric::norm2(t) * crate::numeric::norm2(d);
    (dot.abs() > LEAN_FRACTION * scale && dot.is_finite()).then(|| dot.signum())
}

/// The direction of most negative curvature of the tangent in `w.k` (the
/// eigenvector of the most negative eigenvalue of `K x = λ D x`,
/// `D = diag|k_ii|`), or `None` when none is found (no shift makes
/// `K + μ D` positive definite, or the iterate's curvature `xᵀ K x` is not
/// negative).
fn negative_curvature(w: &mut Work<'_>) -> Result<Option<Vec<f64>>> {
    let n = w.k.n();
    let diag: Vec<f64> = (0..n).map(|i| w.k.get(i, i).abs()).collect();
    let definite = |w: &mut Work<'_>, mu: f64| -> Result<bool> {
        let options = FactorOptions {
            shift: mu,
            require_positive_definite: true,
        };
        match w.solver.factor(&w.k, options) {
            Ok(f) => Ok(f.is_positive_definite()),
            Err(LinsolveError::NotPositiveDefinite { .. } | LinsolveError::Singular { .. }) => {
                Ok(false)
            }
            Err(e) => Err(e.into()),
        }
    };
    // bracket the shift that makes K + μ D definite by decades, then bisect
    // (in log) so that μ + λ_min is small against the next eigenvalue's
    let mut hi = 1e-16;
    while !definite(w, hi)? {
        hi *= 10.0;
        if hi > 1e3 {
            return Ok(None);
        }
    }
    let mut lo = hi / 10.0;
    for _ in 0..5 {
        let mid = (lo * hi).sqrt();
        if definite(w, mid)? {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    let options = FactorOptions {
        shift: hi,
        require_positive_definite: true,
    };
    let f = w.solver.factor(&w.k, options)?;
    // a deterministic start with a component along every mode
    let mut seed: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut x: Vec<f64> = (0..n)
        .map(|_| {
            seed = seed
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
        })
        .collect();
    for _ in 0..INVERSE_ITERATIONS {
        x.iter_mut().zip(&diag).for_each(|(v, d)| *v *= d);
        f.solve_in_place(&mut x)?;
        let norm = x.iter().map(|v| v * v).sum::<f64>().sqrt();
        if !(norm.is_finite() && norm > 0.0) {
            return Ok(None);
        }
        x.iter_mut().for_each(|v| *v /= norm);
    }
    let mut kx = vec![0.0; n];
    w.k.mul_vec_into(&x, &mut kx)?;
    let curvature: f64 = x.iter().zip(&kx).map(|(a, b)| a * b).sum();
    Ok((curvature < 0.0).then_some(x))
}
