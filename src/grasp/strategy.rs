//! The adaptive pinch grasp's pieces (45)–(52): the finger's pose at the
//! contact point, its Jacobian with respect to the pressures, and the
//! bounded least-squares step that realizes the laws (51) and (52).
//!
//! - Pose (46)–(49): `x_c = [p_c, θ]` with `p_c = S(X_c) q_ec` and the
//!   axial direction `η = S'(X_c) q_ec`. The paper's (48)
//!   `θ = arcsin |η × η0|` is unsigned and assumes `|η| = 1`; here
//!   `θ = atan2(η0 × η, η0 · η)` with `η0 = (0, −1)`: signed (positive
//!   counter-clockwise, i.e. inward for the left finger) and exact for a
//!   stretched `η`.
//! - Jacobian (50): `J_c = ∂x_c/∂q · ∂q/∂P` with `∂q/∂P = −(∂Q/∂q)⁻¹ ∂Q/∂P`
//!   (43) ([`crate::sensitivity::Sensitivity::dq_dp`]) at the estimated
//!   equilibrium; `∂θ/∂q = (η × ∂η/∂q)/|η|²`.
//! - `J_c` is 3 × 4 (four chambers per finger): (51) and (52) are solved as
//!   a bounded least-squares problem
//!   `min |W (J_c ΔP − ẋ_d Δt)|² + ε |ΔP|²` subject to the pressure
//!   bounds (clarabel), `W` scaling positions by the finger length so that
//!   metres and radians weigh alike, `ε` a 1e-8 relative Tikhonov term that
//!   picks the smallest step among the exact ones (the minimum-norm
//!   solution of the pseudo-inverse when no bound is active).

use nalgebra::{DMatrix, DVector, Vector3};

use crate::assembly::Robot;
use crate::element::PlanarCable;
use crate::error::{Error, Result, check_len};
use crate::loads::Loads;

/// The finger's pose at arc coordinate `s_m`: `[p_x, p_y, θ]` (m, m, rad),
/// (46)–(49) with the signed angle from the downward vertical.
///
/// # Errors
/// [`Error::InvalidParameter`] for `s_m` off the finger; dimension errors.
///
/// # Example
/// ```
/// use softrod::grasp::gripper::{GripperSpec, Side};
/// use softrod::grasp::strategy::contact_pose;
/// let f = GripperSpec::default().finger(Side::Left)?;
/// let x = contact_pose(&f, f.reference_configuration().as_slice(), 0.1)?;
/// // the straight finger hangs down: tip at (−0.055, −0.1), θ = 0
/// assert!((x.x + 0.055).abs() < 1e-12 && (x.y + 0.1).abs() < 1e-12 && x.z.abs() < 1e-12);
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn contact_pose(robot: &Robot<PlanarCable>, q: &[f64], s_m: f64) -> Result<Vector3<f64>> {
    let point = robot.arc_point("s_m", s_m)?;
    let (mut p, mut eta) = ([0.0; 2], [0.0; 2]);
    point.value_into(q, &mut p)?;
    point.slope_into(q, &mut eta)?;
    // η0 = (0, −1): η0 × η = η_x, η0 · η = −η_y
    Ok(Vector3::new(p[0], p[1], eta[0].atan2(-eta[1])))
}

/// (50) `J_c = ∂x_c/∂P` (3 × n_pressures; m/Pa, m/Pa, rad/Pa) at the
/// equilibrium `q` of `robot` under `loads` (pressures and the estimated
/// load field), for the pose at `s_m`.
///
/// # Errors
/// [`Error::Singular`] if the tangent cannot be factored; bad `s_m`; dimension errors.
///
/// # Example
/// ```
/// use softrod::grasp::gripper::{GripperSpec, Side};
/// use softrod::grasp::strategy::contact_jacobian;
/// use softrod::loads::Loads;
/// let f = GripperSpec::default().finger(Side::Left)?;
/// let loads = Loads { pressures_pa: vec![0.0; 4], ..Loads::default() };
/// let q = softrod::statics::StaticSolver::default().solve(&f, &loads, None)?.q;
/// let j = contact_jacobian(&f, q.as_slice(), &loads, 0.1)?;
/// // the proximal inward chamber turns the tip inward (θ grows), the outward one the other way
/// assert!(j[(2, 0)] > 0.0 && j[(2, 1)] < 0.0);
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn contact_jacobian(
    robot: &Robot<PlanarCable>,
    q: &[f64],
    loads: &Loads,
    s_m: f64,
) -> Result<DMatrix<f64>> {
    // (43) `∂q/∂P` at the equilibrium `q` under `loads`
    let dqdp = crate::control::adapter::dq_dp(robot, loads, q)?;
    let point = robot.arc_point("s_m", s_m)?;
    let mut eta = [0.0; 2];
    point.slope_into(q, &mut eta)?;
    let e2 = eta[0] * eta[0] + eta[1] * eta[1];
    let mut j = DMatrix::zeros(3, dqdp.ncols());
    let (mut dp, mut de) = ([0.0; 2], [0.0; 2]);
    for (c, col) in dqdp.column_iter().enumerate() {
        point.value_into(col.as_slice(), &mut dp)?;
        point.slope_into(col.as_slice(), &mut de)?;
        j[(0, c)] = dp[0];
        j[(1, c)] = dp[1];
        j[(2, c)] = (eta[0] * de[1] - eta[1] * de[0]) / e2;
    }
    Ok(j)
}

/// One step of (51)/(52): the pressure change `ΔP` (Pa) that moves the pose
/// by `xdot · dt_s` in the bounded least-squares sense (module docs), with
/// `P + ΔP` inside `bounds`; `length_m` scales the position rows.
///
/// # Errors
/// [`crate::Error::DimensionMismatch`] for sizes that do not fit;
/// [`Error::InvalidParameter`] for more than 8 chambers (field
/// `pressures_pa`) or if no face is feasible (field `pressure_step`; not
/// reached for pressures within their bounds).
///
/// # Example
/// ```
/// use nalgebra::{DMatrix, Vector3};
/// use softrod::grasp::strategy::bounded_step;
/// // two chambers move x alike; the first is at its bound
/// let j = DMatrix::from_row_slice(3, 2, &[1e-6, 1e-6, 0.0, 0.0, 0.0, 0.0]);
/// let dp = bounded_step(&j, &Vector3::new(1e-3, 0.0, 0.0), 1.0, &[1e5, 0.0], &[(0.0, 1e5), (0.0, 1e5)], 0.1)?;
/// assert!(dp[0].abs() < 1e-3 && (dp[1] - 1e3).abs() < 1e-2);
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn bounded_step(
    j: &DMatrix<f64>,
    xdot: &Vector3<f64>,
    dt_s: f64,
    pressures_pa: &[f64],
    bounds: &[(f64, f64)],
    length_m: f64,
) -> Result<DVector<f64>> {
    let n = j.ncols();
    check_len("xdot", j.nrows(), xdot.len())?;
    check_len("pressures_pa", n, pressures_pa.len())?;
    check_len("bounds", n, bounds.len())?;
    // unknowns x = ΔP / scale
    let scale = bounds
        .iter()
        .map(|(lo, hi)| (hi - lo).abs())
        .fold(0.0, f64::max)
        .max(1.0);
    let w: Vec<f64> = (0..j.nrows())
        .map(|r| if r < 2 { 1.0 / length_m } else { 1.0 })
        .collect();
    let a = DMatrix::from_fn(j.nrows(), n, |r, c| w[r] * j[(r, c)] * scale);
    let b: Vec<f64> = xdot.iter().zip(&w).map(|(v, w)| v * w * dt_s).collect();
    // lower and upper room of each unknown
    let room: Vec<(f64, f64)> = bounds
        .iter()
        .zip(pressures_pa)
        .map(|((lo, hi), pc)| (((lo - pc) / scale).min(0.0), ((hi - pc) / scale).max(0.0)))
        .collect();
    // every assignment of the unknowns to {free, lower, upper}: the convex
    // problem's minimizer is the best feasible face minimizer (n <= 8)
    if n > 8 {
        return Err(Error::invalid(
            "pressures_pa",
            n,
            "at most 8 chambers per finger",
        ));
    }
    let reg = 1e-10 * a.norm_squared().max(1e-300);
    let mut best: Option<(f64, Vec<f64>)> = None;
    for code in 0..3usize.pow(n as u32) {
        let mut x = vec![0.0; n];
        let mut free = Vec::with_capacity(n);
        let mut c = code;
        for (i, xi) in x.iter_mut().enumerate() {
            match c % 3 {
                0 => free.push(i),
                1 => *xi = room[i].0,
                _ => *xi = room[i].1,
            }
            c /= 3;
        }
        if !free.is_empty() {
            let af = DMatrix::from_fn(a.nrows(), free.len(), |r, k| a[(r, free[k])]);
            let fixed = &a * nalgebra::DVector::from_column_slice(&x);
            let rhs = nalgebra::DVector::from_fn(a.nrows(), |r, _| b[r] - fixed[r]);
            // Tikhonov-regularized least squares on the free unknowns
            let mut h = af.tr_mul(&af);
            for k in 0..free.len() {
                h[(k, k)] += reg;
            }
            let Some(xf) = h.cholesky().map(|ch| ch.solve(&af.tr_mul(&rhs))) else {
                continue;
            };
            for (k, &i) in free.iter().enumerate() {
                x[i] = xf[k];
            }
        }
        if x.iter()
            .zip(&room)
            .any(|(xi, (lo, hi))| *xi < lo - 1e-12 || *xi > hi + 1e-12)
        {
            continue;
        }
        let r = &a * nalgebra::DVector::from_column_slice(&x)
            - nalgebra::DVector::from_column_slice(&b);
        let obj = r.norm_squared() + reg * x.iter().map(|v| v * v).sum::<f64>();
        if best.as_ref().is_none_or(|(o, _)| obj < *o) {
            best = Some((obj, x));
        }
    }
    let Some((_, x)) = best else {
        return Err(Error::invalid("pressure_step", "none", "no feasible step"));
    };
    Ok(DVector::from_iterator(
        n,
        x.iter()
            .zip(bounds.iter().zip(pressures_pa))
            .map(|(x, ((lo, hi), pc))| (pc + x * scale).clamp(*lo, *hi) - pc),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp::gripper::{GripperSpec, Side};
    use crate::statics::StaticSolver;

    #[test]
    fn jacobian_matches_finite_differences() {
        let g = GripperSpec::default();
        for side in [Side::Left, Side::Right] {
            let f = g.finger(side).unwrap();
            // a pressure state and a load field (a lateral line load on the distal part)
            let p = vec![40e3, 5e3, 20e3, 10e3];
            let mut field = vec![0.0; f.n_q()];
            for node in 5..f.n_nodes() {
                field[4 * node] = -side.inward() * 3.0; // N/m, pushing outward
            }
            let loads = |p: &[f64]| Loads {
                pressures_pa: p.to_vec(),
                distributed_f: field.clone(),
                ..Loads::default()
            };
            let solver = StaticSolver::default();
            let q = solver.solve(&f, &loads(&p), None).unwrap().q;
            for s in [0.07, 0.1] {
                let j = contact_jacobian(&f, q.as_slice(), &loads(&p), s).unwrap();
                // the pose at the pressures with chamber c changed by dp
                let pose_at = |c: usize, dp: f64| {
                    let mut pp = p.clone();
                    pp[c] += dp;
                    let qp = solver.solve(&f, &loads(&pp), Some(q.as_slice())).unwrap().q;
                    contact_pose(&f, qp.as_slice(), s).unwrap()
                };
                for c in 0..4 {
                    let h = 50.0;
                    let (xp, xm) = (pose_at(c, h), pose_at(c, -h));
                    for r in 0..3 {
                        let fd = (xp[r] - xm[r]) / (2.0 * h);
                        let scale = j.column(c).amax();
                        assert!(
                            (fd - j[(r, c)]).abs() < 1e-6 * scale,
                            "{side:?} s {s} row {r} col {c}: {fd:e} vs {:e}",
                            j[(r, c)]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn the_angle_is_signed() {
        let g = GripperSpec::default();
        let solver = StaticSolver::default();
        for (side, sign) in [(Side::Left, 1.0), (Side::Right, -1.0)] {
            let f = g.finger(side).unwrap();
            let loads = Loads {
                pressures_pa: vec![30e3, 0.0, 0.0, 0.0],
                ..Loads::default()
            };
            let q = solver.solve(&f, &loads, None).unwrap().q;
            let th = contact_pose(&f, q.as_slice(), 0.1).unwrap()[2];
            // inward bending: counter-clockwise for the left finger
            assert!(th * sign > 0.3, "{side:?} {th}");
            // the paper's unsigned (48) gives |θ| for a unit η
            let a = f.angle_at(q.as_slice(), 0.1).unwrap() + std::f64::consts::FRAC_PI_2;
            assert!((th - a).abs() < 1e-9);
        }
    }

    #[test]
    fn the_step_is_least_squares_within_bounds() {
        // unconstrained: the minimum-norm exact solution J⁺ v dt
        let j = DMatrix::from_row_slice(
            3,
            4,
            &[1.0, 2.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0, 0.0, 0.0, 2.0],
        ) * 1e-6;
        let v = Vector3::new(1e-3, -2e-3, 0.5e-3);
        let bounds = vec![(0.0, 1e5); 4];
        let p = vec![5e4; 4];
        let dp = bounded_step(&j, &v, 1.0, &p, &bounds, 1.0).unwrap();
        let pinv = j.clone().pseudo_inverse(1e-18).unwrap();
        let expect = pinv * v;
        for (a, b) in dp.iter().zip(expect.iter()) {
            assert!((a - b).abs() < 1e-5 * expect.amax(), "{dp:?} {expect:?}");
        }
        // a bound binds: the result stays inside
        let p = vec![99e3, 1e3, 50e3, 50e3];
        let dp = bounded_step(&j, &Vector3::x(), 1.0, &p, &bounds, 1.0).unwrap();
        for (d, pc) in dp.iter().zip(&p) {
            assert!(pc + d >= -1e-9 && pc + d <= 1e5 + 1e-9);
        }
    }
}
