//! The cold start of a contact solve: the shapes of the actuation alone
//! (circular arcs, [`Robot::arc_configuration`]) followed as the pressures
//! grow from zero, up to the last one that touches no obstacle.
//!
//! The full actuation's shape is no start when it lies wholly beyond a thin
//! obstacle: every gap is open on the far side, and the solve converges
//! there although the loading path meets the obstacle (measured: a gripper
//! finger curling past a 3 mm strip ended 65–80 mm from the equilibrium
//! that a pressure ramp reaches). Along the path the shapes are sampled so
//! finely that no obstacle fits between two samples (no node moves by more
//! than a quarter of the thinnest obstacle's thickness plus the rod's
//! diameter), and the first penetrating sample is bisected back to the
//! touching one. The SQP then continues from the near side, where the
//! linearized gap of the first contact holds the rod.

use super::{Obstacle, Obstacles};
use crate::assembly::Robot;
use crate::element::PlanarCable;
use crate::error::Result;

/// Most samples of the path; beyond, its steps are coarser than the
/// thinnest obstacle (a path that long is not met in practice: the
/// gripper's finger at full pressure takes about 30).
const MAX_SAMPLES: usize = 4096;

/// Bisections of the first penetrating step.
const BISECTIONS: usize = 40;

/// The thinnest extent of an obstacle (m): a disk's or a capsule's
/// diameter, a convex polygon's width (the smallest, over its edges, of
/// the farthest vertex from the edge's line).
fn thickness_m(o: &Obstacle) -> f64 {
    match o {
        Obstacle::Circle { radius_m, .. } | Obstacle::Capsule { radius_m, .. } => 2.0 * radius_m,
        Obstacle::Polygon { vertices_m } => {
            let n = vertices_m.len();
            (0..n)
                .map(|i| {
                    let a = vertices_m[i];
                    let b = vertices_m[(i + 1) % n];
                    let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
                    let len = ex.hypot(ey);
                    vertices_m
                        .iter()
                        .map(|v| ((v[0] - a[0]) * ey - (v[1] - a[1]) * ex).abs() / len)
                        .fold(0.0, f64::max)
                })
                .fold(f64::INFINITY, f64::min)
        }
    }
}

/// Whether `q` penetrates an obstacle (a gap below zero).
fn penetrates(robot: &Robot<PlanarCable>, obstacles: &Obstacles, q: &[f64]) -> Result<bool> {
    Ok(obstacles
        .gaps(robot, q)?
        .iter()
        .any(|g| g.gap_m < 0.0 || g.gap_m.is_nan()))
}

/// The largest node displacement between two configurations (m).
fn node_move_m(a: &[f64], b: &[f64]) -> f64 {
    a.chunks(4)
        .zip(b.chunks(4))
        .map(|(p, q)| (p[0] - q[0]).hypot(p[1] - q[1]))
        .fold(0.0, f64::max)
}

/// The cold start (module docs): the last shape of the actuation path
/// `arc_configuration(t · pressures)`, `t` from 0 to 1, that touches no
/// obstacle; the reference configuration if the path's first shape
/// already penetrates.
pub(super) fn cold_start(
    robot: &Robot<PlanarCable>,
    pressures_pa: &[f64],
    obstacles: &Obstacles,
) -> Result<Vec<f64>> {
    let arc = |t: f64| -> Vec<f64> {
        let p: Vec<f64> = pressures_pa.iter().map(|p| t * p).collect();
        robot.arc_configuration(&p).data.into()
    };
    let mut q = arc(0.0);
    if penetrates(robot, obstacles, &q)? {
        return Ok(robot.reference_configuration().data.into());
    }
    let thinnest = obstacles
        .obstacles()
        .iter()
        .map(thickness_m)
        .fold(f64::INFINITY, f64::min);
    if !thinnest.is_finite() {
        // no obstacle: the actuation's shape
        return Ok(arc(1.0));
    }
    let max_move = 0.25 * (thinnest + 2.0 * obstacles.rod_radius_m());
    let mut t = 0.0;
    let mut dt = 1.0f64;
    for _ in 0..MAX_SAMPLES {
        // the next sample: no node moves further than `max_move`
        let mut t1 = (t + dt).min(1.0);
        let mut q1 = arc(t1);
        while node_move_m(&q, &q1) > max_move && t1 - t > 1.0 / MAX_SAMPLES as f64 {
            dt *= 0.5;
            t1 = t + dt;
            q1 = arc(t1);
        }
        if penetrates(robot, obstacles, &q1)? {
            // bisect back to the last shape that touches nothing
            let (mut lo, mut hi) = (t, t1);
            for _ in 0..BISECTIONS {
                let mid = 0.5 * (lo + hi);
                let qm = arc(mid);
                if penetrates(robot, obstacles, &qm)? {
                    hi = mid;
                } else {
                    lo = mid;
                    q = qm;
                }
            }
            return Ok(q);
        }
        q = q1;
        t = t1;
        if t >= 1.0 {
            break;
        }
        dt *= 2.0;
    }
    Ok(q)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_polygon_is_as_thick_as_its_narrowest_width() {
        // a 3 × 30 mm rectangle, turned
        let (c, s) = (0.3f64.cos(), 0.3f64.sin());
        let v: Vec<[f64; 2]> = [[0.0, 0.0], [0.003, 0.0], [0.003, 0.03], [0.0, 0.03]]
            .iter()
            .map(|p| [c * p[0] - s * p[1], s * p[0] + c * p[1]])
            .collect();
        let t = thickness_m(&Obstacle::Polygon { vertices_m: v });
        assert!((t - 0.003).abs() < 1e-15, "{t}");
        let d = thickness_m(&Obstacle::Circle {
            center_m: [0.0, 0.0],
            radius_m: 0.01,
        });
        assert_eq!(d, 0.02);
    }
}
