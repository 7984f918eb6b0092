//! The SQP subproblem with bounds on the load: active-set iterations on the
//! reduced Gauss–Newton system, seeded by clarabel's interior-point
//! solution of the full-space QP when there is no active set to start from
//! (see the [parent module](super)).

use clarabel::algebra::CscMatrix;
use clarabel::solver::{NonnegativeConeT, SupportedConeT, ZeroConeT};

use crate::cone::{self, Failure, Tolerances};
use nalgebra::{Cholesky, DMatrix, DVector, Dyn};

use crate::element::{ArcPoint, Element, NodeKinematics};
use crate::error::{Error, Result};
use crate::linsolve::{AutoFactors, Factorization, SymmetricMatrix};
use crate::numeric::{dot, norm2};
use crate::observe::ObservationOperator;

use super::super::gn_form::weighted_columns;
use super::super::gn_form::{GnForm, count_dense};
use super::super::load_model::field_rod;
use super::super::problem::{Derivs, Problem};
use super::super::{BoundFrame, EstimationModel, LoadBound, LoadModel};
use super::{QpError, QpStep, SqpEstimator, Unconstrained};

/// One bound row `a · dF ≤ h` (`a` sparse over the load parameters).
pub(super) struct Ineq {
    pub a: Vec<(usize, f64)>,
    pub h: f64,
}

/// `t` scaled to unit length.
fn unit(mut t: Vec<f64>) -> Vec<f64> {
    let n = norm2(&t).max(1e-300);
    t.iter_mut().for_each(|v| *v /= n);
    t
}

/// The bound's direction in world axes: in the local frame (planar), its
/// components along the unit tangent `t` and the normal; else as given
/// (3-D local bounds are refused when the problem is built: no section
/// frame).
fn world_direction(b: &LoadBound, tangent: Option<Vec<f64>>) -> Vec<f64> {
    match (b.frame, tangent) {
        (BoundFrame::Local, Some(t)) if t.len() == 2 => {
            let nrm = [-t[1], t[0]];
            (0..2)
                .map(|i| b.direction[0] * t[i] + b.direction[1] * nrm[i])
                .collect()
        }
        _ => b.direction.clone(),
    }
}

impl<M: EstimationModel> SqpEstimator<M> {
    /// Rows `(coefficients over F, lo, hi)` of the load bounds at shape `q`.
    #[allow(clippy::type_complexity)]
    fn bound_rows(&self, q: &[f64]) -> Result<Vec<(Vec<(usize, f64)>, Option<f64>, Option<f64>)>> {
        let d: usize = M::Element::DIM;
        let nd = M::Element::NODE_DOFS;
        let problem = &self.stream.problem;
        let model = problem.robot();
        // slot k of element e: node e + k/2, its value (k even) or slope
        let slot = |e: usize, k: usize, i: usize| (e + k / 2) * nd + (k % 2) * d + i;
        // the unit tangent at a rod's point when the bound is in the local frame
        let rod_tangent = |b: &LoadBound, p: &ArcPoint| -> Result<Option<Vec<f64>>> {
            match b.frame {
                BoundFrame::World => Ok(None),
                BoundFrame::Local => {
                    let mut t = vec![0.0; d];
                    p.slope_into(q, &mut t)?;
                    Ok(Some(unit(t)))
                }
            }
        };
        // a force of basis θ: the bound reads basisᵀ dir · θ
        let basis_coeffs = |dir: &[f64]| -> Result<Vec<(usize, f64)>> {
            let basis = problem.load().force_basis(d)?.unwrap_or_default();
            Ok((0..basis.ncols())
                .map(|j| (j, (0..d).map(|i| basis[(i, j)] * dir[i]).sum()))
                .collect())
        };
        let mut rows = Vec::new();
        for b in &problem.settings().bounds {
            let coeffs: Vec<(usize, f64)> = match problem.load() {
                LoadModel::Distributed => {
                    // the field's shape functions at the bound's point
                    let p = field_rod(model)?.arc_point("bound.s_m", b.s_m)?;
                    let dir = world_direction(b, rod_tangent(b, &p)?);
                    let mut c = Vec::new();
                    for (k, sk) in p.values.iter().enumerate() {
                        for (i, di) in dir.iter().enumerate() {
                            if sk * di != 0.0 {
                                c.push((slot(p.element, k, i), sk * di));
                            }
                        }
                    }
                    c
                }
                LoadModel::Concentrated { node } => {
                    let rod = field_rod(model)?;
                    let (e, xi) = if node == 0 { (0, 0.0) } else { (node - 1, 1.0) };
                    let p = ArcPoint::new(e, xi, rod.elements()[e].length());
                    basis_coeffs(&world_direction(b, rod_tangent(b, &p)?))?
                }
                LoadModel::AtSite { site } | LoadModel::Along { site, .. } => {
                    let tangent = match b.frame {
                        BoundFrame::World => None,
                        BoundFrame::Local => {
                            let t = model
                                .site_rows("estimator.load_model.site", &site)?
                                .tangent_at(q)
                                .ok_or_else(|| {
                                    crate::Error::invalid(
                                        "estimator.bounds.frame",
                                        "local",
                                        "a rigid body's site has no tangent: bound it in the world frame",
                                    )
                                })?;
                            Some(unit(t))
                        }
                    };
                    basis_coeffs(&world_direction(b, tangent))?
                }
            };
            rows.push((coeffs, b.min_n_per_m, b.max_n_per_m));
        }
        Ok(rows)
    }

    /// The bounds as rows `a · dF ≤ h` over the load step at `(q, F)`.
    pub(super) fn inequalities(&self, q: &[f64], f: &[f64]) -> Result<Vec<Ineq>> {
        let mut ineq = Vec::new();
        for (coeffs, lo, hi) in self.bound_rows(q)? {
            let val: f64 = coeffs.iter().map(|(k, v)| v * f[*k]).sum();
            if let Some(lo) = lo {
                ineq.push(Ineq {
                    a: coeffs.iter().map(|(k, v)| (*k, -v)).collect(),
                    h: val - lo,
                });
            }
            if let Some(hi) = hi {
                ineq.push(Ineq {
                    a: coeffs.clone(),
                    h: hi - val,
                });
            }
        }
        Ok(ineq)
    }

    /// The QP with bounds, at the tangent `k` (factored: `lu`). The bounds
    /// act on `F` only, so on a known active set the QP is
    /// equality-constrained and solved exactly through the reduced
    /// Gauss–Newton system ([`Reduced`]): the unconstrained step `dF₀`
    /// corrected by the active rows' multipliers. An active set is accepted
    /// only with its optimality certificate (every inactive bound holds,
    /// every active multiplier has the right sign; the QP is convex, so these
    /// KKT conditions are sufficient). Tried in turn: the active set of the
    /// last QP, none (`dF₀` itself), and the one clarabel's interior-point
    /// solution identifies; if that too fails the certificate, clarabel's
    /// step is taken as it is. Returns the step and its active set.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn bounded_qp(
        &self,
        k: &SymmetricMatrix,
        lu: &AutoFactors,
        op: &ObservationOperator,
        u: &[f64],
        q: &[f64],
        f: &[f64],
        e: &[f64],
        r: &[f64],
        alpha: f64,
        c: Vec<f64>,
    ) -> std::result::Result<(QpStep, Vec<usize>), QpError> {
        let ineq = self.inequalities(q, f)?;
        let problem = &self.stream.problem;
        let Unconstrained { dv, df0, g1, fac } =
            self.unconstrained(lu, op, u, f, e, r, alpha, None)?;
        let reduced = Reduced::new(problem, self.gram_lu.as_ref(), &dv, op, alpha);
        let solve_from = |start: &[usize]| -> Option<(Vec<f64>, Vec<usize>)> {
            active_set_solve(reduced.as_ref()?, &ineq, f, &df0, start)
        };
        let warm = self.active_set.as_deref().and_then(solve_from);
        let (df, act, exact) = match warm {
            Some((df, act)) => (df, act, true),
            None => {
                let (df_ip, act) = self.clarabel_df(k, op, u, r, alpha, &c, &ineq)?;
                match solve_from(&act) {
                    Some((df, act)) => (df, act, true),
                    None => (df_ip, act, false),
                }
            }
        };
        // the bounds at the current F (they move with the shape in the
        // local frame): the largest violation relative to the row's scale
        let bound_violation = ineq
            .iter()
            .map(|ie| {
                let size: f64 = ie.a.iter().map(|(j, v)| (v * f[*j]).abs()).sum();
                -ie.h / (size + ie.h.abs()).max(1e-300)
            })
            .fold(0.0f64, f64::max);
        let dec_opt = exact.then(|| (-dot(&g1, &df)).max(0.0));
        let du = self.du_from(lu, r, &df)?;
        let lambda_max = self.lambda_max(&dv, op, u, e, &du)?;
        Ok((
            QpStep {
                du,
                df,
                lambda_max,
                c,
                active: !act.is_empty(),
                exact,
                bound_violation,
                dec_opt,
                derivs: Some((dv, fac)),
                tangent_max_abs: k.max_abs(),
            },
            act,
        ))
    }

    /// The full-space QP with bounds by clarabel's interior-point method at
    /// the tangent `k` at `u`: its load step and the bounds active in its
    /// solution.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn clarabel_df(
        &self,
        k: &SymmetricMatrix,
        op: &ObservationOperator,
        u: &[f64],
        r: &[f64],
        alpha: f64,
        c: &[f64],
        ineq: &[Ineq],
    ) -> std::result::Result<(Vec<f64>, Vec<usize>), QpError> {
        let problem = &self.stream.problem;
        let robot = problem.robot();
        let nfree = robot.n_free();
        let nq = robot.n_q();
        let nf = problem.n_f();
        let n = nfree + nf;
        // objective
        let mut pt: std::collections::BTreeMap<(usize, usize), f64> = Default::default();
        let mut dense = vec![0.0; nq];
        for (row, w) in op.rows().iter().zip(op.weights()) {
            dense.iter_mut().for_each(|v| *v = 0.0);
            for &(j, v) in row.entries() {
                dense[j] += v;
            }
            let ma = problem.restrict(u, &dense)?;
            let nz: Vec<(usize, f64)> = ma
                .iter()
                .copied()
                .enumerate()
                .filter(|(_, v)| *v != 0.0)
                .collect();
            for &(a, va) in &nz {
                for &(b, vb) in &nz {
                    if a <= b {
                        *pt.entry((a, b)).or_insert(0.0) += 2.0 * w * va * vb;
                    }
                }
            }
        }
        for &(i, j, v) in &self.h_upper {
            *pt.entry((nfree + i, nfree + j)).or_insert(0.0) += 2.0 * alpha * v;
        }
        let pmax = pt.values().fold(0.0f64, |m, v| m.max(v.abs())).max(1e-300);
        // scaling: objective by 1/pmax, unknowns by γ
        let cmax = c.iter().fold(0.0f64, |m, v| m.max(v.abs())) / pmax;
        let bmax = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let gamma = cmax.max(bmax).max(1e-300);
        let (mut ri, mut ci, mut vi) = (Vec::new(), Vec::new(), Vec::new());
        for ((a, b), v) in &pt {
            ri.push(*a);
            ci.push(*b);
            vi.push(v / pmax);
        }
        let p_mat = CscMatrix::new_from_triplets(n, n, ri, ci, vi);
        let c_s: Vec<f64> = c.iter().map(|v| v / (pmax * gamma)).collect();
        let (mut ri, mut ci, mut vi) = (Vec::new(), Vec::new(), Vec::new());
        // the linearized equilibrium: −K du + Mᵀ G dF = −Q
        for (i, j, v) in k.iter_upper() {
            if v != 0.0 {
                ri.push(i);
                ci.push(j);
                vi.push(-v);
                if i != j {
                    ri.push(j);
                    ci.push(i);
                    vi.push(-v);
                }
            }
        }
        for &(i, j, v) in &self.g_free {
            ri.push(i);
            ci.push(nfree + j);
            vi.push(v);
        }
        let m_eq = nfree;
        for (row, ie) in ineq.iter().enumerate() {
            for &(k, v) in &ie.a {
                ri.push(m_eq + row);
                ci.push(nfree + k);
                vi.push(v);
            }
        }
        let m = m_eq + ineq.len();
        let a_mat = CscMatrix::new_from_triplets(m, n, ri, ci, vi);
        let mut b: Vec<f64> = r.iter().map(|v| -v / gamma).collect();
        b.extend(ineq.iter().map(|ie| ie.h / gamma));
        let mut cones: Vec<SupportedConeT<f64>> = vec![ZeroConeT(m_eq)];
        if !ineq.is_empty() {
            cones.push(NonnegativeConeT(ineq.len()));
        }
        let sol = match cone::solve(&p_mat, &c_s, &a_mat, &b, &cones, Tolerances::all(1e-10)) {
            Ok(sol) => sol,
            Err(Failure::Status(s)) => return Err(QpError::Clarabel(s)),
            Err(Failure::Rejected(e)) => {
                return Err(Error::invalid("clarabel problem", e, "internal").into());
            }
        };
        let sol = &sol;
        let df: Vec<f64> = sol.x[nfree..].iter().map(|v| v * gamma).collect();
        let act: Vec<usize> = sol.s[m_eq..]
            .iter()
            .zip(&sol.z[m_eq..])
            .enumerate()
            .filter(|(_, (s, z))| **s <= 1e-6 || **z > 1e-6 * s.max(1e-300))
            .map(|(k, _)| k)
            .collect();
        Ok((df, act))
    }
}

/// The QP's load step by active-set iterations from the rows `start`: each
/// solves the equality-constrained QP on the current set, drops the row
/// with the most negative multiplier or else adds the most violated
/// inactive bound, and stops when neither exists: then every inactive
/// bound holds (to 1e-9 of its row's scale) and no active multiplier is
/// negative (beyond 1e-9 of the largest), the KKT conditions of the convex
/// QP, so the step is its solution. `None` if that takes more than
/// `2 n_rows + 8` solves or a solve fails (dependent active rows).
pub(super) fn active_set_solve(
    red: &Reduced<'_>,
    ineq: &[Ineq],
    f: &[f64],
    df0: &[f64],
    start: &[usize],
) -> Option<(Vec<f64>, Vec<usize>)> {
    let mut act: Vec<usize> = start.iter().copied().filter(|&k| k < ineq.len()).collect();
    act.sort_unstable();
    act.dedup();
    for _ in 0..2 * ineq.len() + 8 {
        let (df, nu) = if act.is_empty() {
            (df0.to_vec(), Vec::new())
        } else {
            red.solve_on(&act, ineq, df0)?
        };
        if !df.iter().chain(&nu).all(|v| v.is_finite()) {
            return None;
        }
        let numax = nu.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let (i_min, nu_min) =
            nu.iter()
                .copied()
                .enumerate()
                .fold(
                    (0, f64::INFINITY),
                    |m, (i, v)| if v < m.1 { (i, v) } else { m },
                );
        if nu_min < -1e-9 * numax {
            act.remove(i_min);
            continue;
        }
        let (k_max, viol_max) = ineq
            .iter()
            .enumerate()
            .filter(|(k, _)| act.binary_search(k).is_err())
            .map(|(k, ie)| {
                let lhs: f64 = ie.a.iter().map(|(j, v)| v * df[*j]).sum();
                let size: f64 =
                    ie.a.iter()
                        .map(|(j, v)| v.abs() * (f[*j].abs() + df[*j].abs()))
                        .sum();
                (k, (lhs - ie.h) / (size + ie.h.abs()).max(1e-300))
            })
            .fold(
                (0, f64::NEG_INFINITY),
                |m, (k, v)| if v > m.1 { (k, v) } else { m },
            );
        if viol_max > 1e-9 {
            if let Err(pos) = act.binary_search(&k_max) {
                act.insert(pos, k_max);
            }
            continue;
        }
        return Some((df, act));
    }
    None
}

/// The reduced Gauss–Newton Hessian (30) `N = Jᵀ W J + α H` at one
/// linearization, applied as `N⁻¹`, in the problem's form
/// ([`Problem::gn_form`]): in the representer form (the distributed load,
/// `J = Z B`, `H = B`, at most `n_F` observed components) by Woodbury,
/// `N⁻¹ = α⁻¹ (B⁻¹ − Zᵀ S⁻¹ Z)`, `S = α W⁻¹ + Z B Zᵀ` (`n_ob × n_ob`);
/// in the primal form `N` itself (`n_F × n_F`, accumulated over the marker
/// rows).
pub(super) struct Reduced<'a> {
    /// The adjoint fields, column `i` each.
    z: &'a DMatrix<f64>,
    chol: Cholesky<f64, Dyn>,
    gram_lu: Option<&'a AutoFactors>,
    alpha: f64,
}

impl<'a> Reduced<'a> {
    pub(super) fn new<M: EstimationModel>(
        problem: &Problem<M>,
        gram_lu: Option<&'a AutoFactors>,
        dv: &'a Derivs,
        op: &ObservationOperator,
        alpha: f64,
    ) -> Option<Self> {
        let m = op.len();
        let w = op.weights();
        let (mat, gram_lu) = match problem.gn_form(m).ok()? {
            GnForm::Representer => {
                gram_lu?;
                // Zᵀ B Z (B z_j = J_j), symmetrized
                count_dense(m * m * dv.jt.nrows() + m * m * m / 3);
                let zj = dv.z.tr_mul(&dv.jt);
                let s = DMatrix::from_fn(m, m, |i, j| {
                    0.5 * (zj[(i, j)] + zj[(j, i)]) + if i == j { alpha / w[i] } else { 0.0 }
                });
                (s, gram_lu)
            }
            GnForm::Primal(h) => {
                // N = Jᵀ W J + α H over the marker rows
                let nf = dv.jt.nrows();
                count_dense(m * nf * nf + nf * nf * nf / 3);
                let mut n = weighted_columns(&dv.jt, w) * dv.jt.transpose();
                n.zip_apply(&h.h, |a, b| *a += alpha * b);
                (n, None)
            }
        };
        Some(Reduced {
            z: &dv.z,
            chol: mat.cholesky()?,
            gram_lu,
            alpha,
        })
    }

    /// `N⁻¹ a` for a sparse `a` over the load parameters (`n_f` long).
    fn n_inv(&self, a: &[(usize, f64)], nf: usize) -> Option<Vec<f64>> {
        let mut x = vec![0.0; nf];
        for &(j, v) in a {
            x[j] += v;
        }
        match self.gram_lu {
            Some(lu) => {
                let t = DVector::from_fn(self.z.ncols(), |i, _| {
                    a.iter().map(|(j, v)| v * self.z[(*j, i)]).sum::<f64>()
                });
                let s = self.chol.solve(&t);
                lu.solve_in_place(&mut x).ok()?;
                for (zi, si) in self.z.column_iter().zip(s.iter()) {
                    x.iter_mut().zip(zi.iter()).for_each(|(a, b)| *a -= si * b);
                }
                x.iter_mut().for_each(|v| *v /= self.alpha);
                Some(x)
            }
            None => {
                let v = self.chol.solve(&DVector::from_vec(x));
                Some(v.iter().copied().collect())
            }
        }
    }

    /// The step with the rows `act` held at equality, `a_k · dF = h_k`:
    /// `dF = dF₀ − Σ_k ν_k N⁻¹ a_k`, `(C N⁻¹ Cᵀ) ν = C dF₀ − h`; also `ν`
    /// (the rows' multipliers, up to a positive factor).
    fn solve_on(&self, act: &[usize], ineq: &[Ineq], df0: &[f64]) -> Option<(Vec<f64>, Vec<f64>)> {
        let nf = df0.len();
        let y: Vec<Vec<f64>> = act
            .iter()
            .map(|&k| self.n_inv(&ineq.get(k)?.a, nf))
            .collect::<Option<_>>()?;
        let rowdot =
            |k: usize, v: &[f64]| -> f64 { ineq[k].a.iter().map(|(j, c)| c * v[*j]).sum() };
        let na = act.len();
        let mmat = DMatrix::from_fn(na, na, |i, j| {
            0.5 * (rowdot(act[i], &y[j]) + rowdot(act[j], &y[i]))
        });
        let rhs = DVector::from_fn(na, |i, _| rowdot(act[i], df0) - ineq[act[i]].h);
        let nu = mmat.cholesky()?.solve(&rhs);
        let mut df = df0.to_vec();
        for (yk, nk) in y.iter().zip(nu.iter()) {
            df.iter_mut().zip(yk).for_each(|(a, b)| *a -= nk * b);
        }
        Some((df, nu.iter().copied().collect()))
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::super::super::{EstimatorSettings, LoadBound, Observation};
    use super::*;
    use crate::loads::LineLoad;
    use crate::scene::Scene;
    use crate::statics::StaticSolver;

    /// The bounded QP's exact solution by active-set iterations: from the
    /// empty set and from the set clarabel's interior-point solution
    /// identifies it reaches the same step (the QP is strictly convex in
    /// `dF`), with bounds active, every bound held, and a reduced objective
    /// `(e' + J dF)ᵀ W (e' + J dF) + α (F + dF)ᵀ H (F + dF)` not above that of
    /// clarabel's step (an independent solver of the same QP). A wrong
    /// active set or a wrong multiplier sign gives a higher objective or a
    /// violated bound.
    #[test]
    fn active_set_step_solves_the_bounded_qp() {
        let mut scene = Scene::two_section();
        for s in &mut scene.robot.sections {
            s.elements = 10;
        }
        let robot = scene.robot().unwrap();
        let known = scene.loads().unwrap();
        let mut truth = known.clone();
        truth.line_loads.push(LineLoad::Gaussian {
            amplitude_n_per_m: vec![0.0, -20.0],
            center_m: 0.16,
            width_m: 0.01,
        });
        let eq = StaticSolver::default().solve(&robot, &truth, None).unwrap();
        let obs = Observation::of_nodes(&robot, eq.q.as_slice(), &[4, 8, 12, 16, 20])
            .unwrap()
            .with_noise(1e-5, 3);
        let bounds = (0..=24)
            .map(|i| LoadBound {
                s_m: 0.01 * f64::from(i),
                frame: BoundFrame::World,
                direction: vec![0.0, 1.0],
                min_n_per_m: None,
                max_n_per_m: Some(0.0),
            })
            .collect();
        let alpha = 10.0;
        let settings = EstimatorSettings {
            backend: crate::estimate::Backend::Sqp,
            alpha: Some(alpha),
            bounds,
            ..EstimatorSettings::default()
        };
        let mut est = SqpEstimator::new(&robot, &known, &settings).unwrap();
        let (f, q) = est.stream.start().unwrap();
        let t = est.stream.problem.factor_tangent(&q).unwrap();
        let (k, lu) = (&t.matrix, &t.factors);
        let problem = &est.stream.problem;
        let op = problem.operator(&obs).unwrap();
        let (_, _, e) = problem.objective(&op, &q, &f, alpha).unwrap();
        let r = problem.residual(&q, &f).unwrap();
        let u: Vec<f64> = crate::structure::Stepping::free_coordinates_of(&robot, &q)
            .unwrap()
            .data
            .into();
        let c = est.linear_term(&op, &u, &f, &e, alpha).unwrap();
        let ineq = est.inequalities(&q, &f).unwrap();
        let un = est
            .unconstrained(lu, &op, &u, &f, &e, &r, alpha, None)
            .unwrap();
        let mut w0 = r.clone();
        lu.solve_in_place(&mut w0).unwrap();
        let dq0 = problem.expand(&u, &w0).unwrap();
        let e1: Vec<f64> = (0..op.len())
            .map(|i| e[i] + op.rows()[i].apply(dq0.as_slice()))
            .collect();
        let reduced_objective = |df: &[f64]| {
            let wr: f64 = (0..op.len())
                .map(|i| op.weights()[i] * (e1[i] + dot(un.dv.jt.column(i).as_slice(), df)).powi(2))
                .sum();
            let ft: Vec<f64> = f.iter().zip(df).map(|(a, b)| a + b).collect();
            wr + alpha * problem.penalty(&ft).unwrap()
        };
        let red = Reduced::new(problem, est.gram_lu.as_ref(), &un.dv, &op, alpha).unwrap();
        let (df_ip, act_ip) = est.clarabel_df(k, &op, &u, &r, alpha, &c, &ineq).unwrap();
        let (df_a, act_a) = active_set_solve(&red, &ineq, &f, &un.df0, &[]).unwrap();
        let (df_b, act_b) = active_set_solve(&red, &ineq, &f, &un.df0, &act_ip).unwrap();
        assert!(!act_a.is_empty(), "the test needs active bounds");
        assert_eq!(act_a, act_b);
        let nrm = norm2(&df_a);
        let diff: Vec<f64> = df_a.iter().zip(&df_b).map(|(a, b)| a - b).collect();
        assert!(norm2(&diff) <= 1e-9 * nrm, "{}", norm2(&diff) / nrm);
        // every bound holds: w_y(s_j; F + dF) <= 0
        let worst = ineq
            .iter()
            .map(|ie| ie.a.iter().map(|(j, v)| v * df_a[*j]).sum::<f64>() - ie.h)
            .fold(f64::MIN, f64::max);
        assert!(worst <= 1e-9, "bound violated by {worst}");
        let (phi_a, phi_ip, phi_0) = (
            reduced_objective(&df_a),
            reduced_objective(&df_ip),
            reduced_objective(&un.df0),
        );
        eprintln!(
            "active {act_a:?} (clarabel {act_ip:?}); objective exact {phi_a:.12e}, clarabel {phi_ip:.12e}, unbounded {phi_0:.12e}"
        );
        assert!(phi_a <= phi_ip * (1.0 + 1e-9), "{phi_a} > {phi_ip}");
        assert!(phi_a > phi_0, "the bounds must cost something");
    }
}
