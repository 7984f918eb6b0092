//! The object on the table as a planar rigid body while the gripper closes.
//!
//! An object set down on the table comes to rest under gravity, and the
//! fingers' pushes move it once the friction cannot hold it. At each pose
//! the fingers are solved against it at their pressures (the caller's
//! contact solve): each finger pushes with its normal force `N_i` (the
//! frictionless contact solve's) and its friction `|τ_i| ≤ μ N_i` about the
//! object's outline; the table supports the object's lowest points with any
//! normal force and friction `|τ| ≤ μ_t λ` (`μ_t`: the table's). If these
//! forces cannot balance the weight and the pushes, the object moves along
//! the acceleration of least constraint ([`crate::grasp::slip`], the same
//! program with the fingers' normal forces fixed and the table rigid), in
//! steps of at most `step_m` for its centre of mass, the contact points and
//! the supports, and 0.02 rad; a step that would put another point of the
//! outline through the table is shortened to where it touches (so a square
//! set down on a corner tips until it lies flat, and stops there), and the
//! object is kept on the table (its lowest point on the table top when it
//! would sink into it). When the direction reverses, the step halves, down
//! to an eighth.

use crate::grasp::friction::FrictionContact;
use crate::grasp::object::{GraspObject, Pose, Shape};
use crate::grasp::slip::{MAX_TURN_RAD, MIN_STEP_FRACTION, Support, least_constraint};

/// A point of the outline within this of the table top supports the object (m).
const TOUCH_M: f64 = 1e-6;
/// At rest: the largest point's acceleration under this fraction of gravity.
const REST_FRACTION: f64 = 1e-4;

/// The table under the object: its top (m, palm frame) and friction
/// coefficient against the object.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct TableTop {
    pub(crate) top_m: f64,
    pub(crate) mu: f64,
}

/// The outline's candidates for the lowest point at `pose`: the lowest
/// point of a circle or an ellipse; a rectangle's corners; the bottoms of a
/// rounded polygon's corner circles.
pub(crate) fn support_candidates(object: &GraspObject, pose: &Pose) -> Vec<[f64; 2]> {
    let (s, c) = pose.angle_rad.sin_cos();
    let p = pose.position_m;
    let world = |[x, y]: [f64; 2]| [p[0] + c * x - s * y, p[1] + s * x + c * y];
    match &object.shape {
        Shape::Circle { radius_m } => vec![[p[0], p[1] - radius_m]],
        Shape::Ellipse {
            semi_axes_m: [a, b],
        } => {
            // the world height of (a cos t, b sin t) is p_y + a s cos t + b c sin t:
            // least at (cos t, sin t) ∝ −(a s, b c)
            let (u, v) = (a * s, b * c);
            let l = u.hypot(v);
            vec![world([-a * u / l, -b * v / l])]
        }
        Shape::Rectangle { size_m: [w, h] } => {
            let (x, y) = (0.5 * w, 0.5 * h);
            [[-x, -y], [x, -y], [x, y], [-x, y]]
                .into_iter()
                .map(world)
                .collect()
        }
        Shape::RoundedPolygon {
            vertices_m,
            corner_radius_m,
        } => vertices_m
            .iter()
            .map(|v| {
                let w = world(*v);
                [w[0], w[1] - corner_radius_m]
            })
            .collect(),
    }
}

/// The lowest height of `pose`'s support candidates (m).
fn lowest(object: &GraspObject, pose: &Pose) -> f64 {
    support_candidates(object, pose)
        .iter()
        .map(|p| p[1])
        .fold(f64::INFINITY, f64::min)
}

/// `pose` moved up so that it does not sink into the table.
fn on_table(object: &GraspObject, mut pose: Pose, table: &TableTop) -> Pose {
    let low = lowest(object, &pose);
    if low < table.top_m {
        pose.position_m[1] += table.top_m - low;
    }
    pose
}

/// How the object ended on the table.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Rested {
    /// Where it is.
    pub(crate) pose: Pose,
    /// Whether it is at rest there (else it ran out of steps).
    pub(crate) at_rest: bool,
    /// Steps it moved.
    pub(crate) steps: usize,
    /// Why it stopped moving early: the least-constraint program was not
    /// solved (clarabel's status).
    pub(crate) failed: Option<String>,
}

/// Lets `object` come to rest on `table` from `start` (module docs):
/// `grip` solves the fingers against the object at a pose and gives their
/// contacts (normals into the object, `max_normal_force_n` the finger's
/// normal force there). At most `max_steps` steps.
///
/// # Errors
/// Whatever `grip` returns. A least-constraint program that is not solved
/// ends the motion with [`Rested::failed`].
pub(crate) fn rest_on_table<E: From<crate::Error>>(
    object: &GraspObject,
    start: Pose,
    table: &TableTop,
    gravity_m_per_s2: [f64; 2],
    step_m: f64,
    max_steps: usize,
    mut grip: impl FnMut(&Pose) -> std::result::Result<Vec<FrictionContact>, E>,
) -> std::result::Result<Rested, E> {
    let m = object.mass_kg;
    let inertia = object.moment_of_inertia_kg_m2();
    let g = gravity_m_per_s2[0].hypot(gravity_m_per_s2[1]);
    let mut pose = on_table(object, start, table);
    let mut h = step_m;
    let mut previous: Option<[f64; 3]> = None;
    for k in 0..=max_steps {
        let fingers = grip(&pose)?;
        if k == max_steps {
            return Ok(Rested {
                pose,
                at_rest: false,
                steps: k,
                failed: None,
            });
        }
        let low = lowest(object, &pose);
        let mut supports: Vec<Support> = fingers
            .iter()
            .map(|f| Support {
                point_m: f.point_m,
                normal: f.normal,
                min_normal_force_n: f.max_normal_force_n,
                max_normal_force_n: f.max_normal_force_n,
                mu: object.mu,
            })
            .collect();
        let touching: Vec<[f64; 2]> = support_candidates(object, &pose)
            .into_iter()
            .filter(|p| p[1] <= low.max(table.top_m) + TOUCH_M && low <= table.top_m + TOUCH_M)
            .collect();
        supports.extend(touching.iter().map(|p| Support {
            point_m: *p,
            normal: [0.0, 1.0],
            min_normal_force_n: 0.0,
            max_normal_force_n: f64::INFINITY,
            mu: table.mu,
        }));
        let c = pose.position_m;
        let lc = match least_constraint(&supports, m, inertia, c, gravity_m_per_s2) {
            Ok(lc) => lc,
            Err(e) => {
                return Ok(Rested {
                    pose,
                    at_rest: false,
                    steps: k,
                    failed: Some(e.to_string()),
                });
            }
        };
        let a = lc.acceleration;
        // the table carries it (not lifted off by the fingers): it stays on
        // the table. The program's cones are convex: for a body that slides
        // on the table they also leave an acceleration off it, about μ_t
        // times the sliding one, that Coulomb's law has not
        let carried = lc.normal_forces_n[fingers.len()..]
            .iter()
            .any(|l| *l > 1e-9 * m * g);
        let reach = supports
            .iter()
            .map(|f| [f.point_m[0] - c[0], f.point_m[1] - c[1]])
            .chain(std::iter::once([0.0, 0.0]))
            .map(|r| (a[0] - a[2] * r[1]).hypot(a[1] + a[2] * r[0]))
            .fold(0.0, f64::max);
        if !(reach.is_finite() && reach > REST_FRACTION * g) {
            return Ok(Rested {
                pose,
                at_rest: true,
                steps: k,
                failed: None,
            });
        }
        if let Some(p) = previous
            && m * (a[0] * p[0] + a[1] * p[1]) + inertia * a[2] * p[2] < 0.0
        {
            h = (0.5 * h).max(MIN_STEP_FRACTION * step_m);
        }
        previous = Some(a);
        let s = (h / reach).min(h / step_m * MAX_TURN_RAD / a[2].abs().max(1e-300));
        let moved = |f: f64| Pose {
            position_m: [c[0] + f * s * a[0], c[1] + f * s * a[1]],
            angle_rad: pose.angle_rad + f * s * a[2],
        };
        // the candidates that do not touch now must not pass through the
        // table: shorten the step to where the first of them touches
        let free: Vec<usize> = support_candidates(object, &pose)
            .iter()
            .enumerate()
            .filter(|(_, p)| p[1] > low.max(table.top_m) + TOUCH_M)
            .map(|(i, _)| i)
            .collect();
        let clears = |f: f64| {
            let (pm, top) = (moved(f), table.top_m);
            let cand = support_candidates(object, &pm);
            // the touching points may sink by a second-order amount: measure
            // the free ones against the lowest touching one
            let base = cand
                .iter()
                .enumerate()
                .filter(|(i, _)| !free.contains(i))
                .map(|(_, p)| p[1])
                .fold(f64::INFINITY, f64::min)
                .min(top);
            free.iter().all(|&i| cand[i][1] >= base)
        };
        let mut f = 1.0;
        if !clears(1.0) {
            let (mut lo, mut hi) = (0.0, 1.0);
            for _ in 0..40 {
                let mid = 0.5 * (lo + hi);
                if clears(mid) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            f = lo;
        }
        pose = moved(f);
        if carried {
            // back onto the table
            pose.position_m[1] += table.top_m.max(low) - lowest(object, &pose);
        }
        pose = on_table(object, pose, table);
    }
    // not reached: the loop returns at k == max_steps
    Ok(Rested {
        pose,
        at_rest: false,
        steps: max_steps,
        failed: None,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: [f64; 2] = [0.0, -9.81];

    fn square(turn: f64) -> (GraspObject, Pose) {
        let a = 0.0245;
        let o = GraspObject {
            name: "tape".into(),
            shape: Shape::RoundedPolygon {
                vertices_m: vec![[-a, -a], [a, -a], [a, a], [-a, a]],
                corner_radius_m: 0.008,
            },
            mass_kg: 0.2,
            mu: 0.5,
        };
        let pose = Pose {
            position_m: [0.0, 0.0],
            angle_rad: turn,
        };
        (o, pose)
    }

    #[test]
    fn a_square_set_down_on_a_corner_tips_flat_and_a_disc_stays() {
        let table = TableTop {
            top_m: -0.05,
            mu: 0.4,
        };
        for turn in [-0.138, 0.092] {
            let (o, pose) = square(turn);
            let out = rest_on_table(&o, pose, &table, G, 0.002, 200, |_| {
                Ok::<_, crate::Error>(Vec::new())
            })
            .unwrap();
            assert!(out.at_rest, "{out:?}");
            // flat on its face: both corners of the face within the contact
            // tolerance of the table (their distance 49 mm), the centre half
            // the side above it
            let q = out.pose.angle_rad / std::f64::consts::FRAC_PI_2;
            assert!(
                (q - q.round()).abs() * std::f64::consts::FRAC_PI_2 * 0.049 <= TOUCH_M,
                "{out:?}"
            );
            assert!(
                (out.pose.position_m[1] - (table.top_m + 0.0325)).abs() < TOUCH_M,
                "{out:?}"
            );
            // it tipped about the corner it stood on: the table's friction
            // held that corner, so the centre moved sideways by the corner's
            // arc (less than the half diagonal times the turn)
            assert!(out.pose.position_m[0].abs() < 0.05 * turn.abs(), "{out:?}");
        }
        let disc = GraspObject {
            name: "disc".into(),
            shape: Shape::Circle { radius_m: 0.03 },
            mass_kg: 0.1,
            mu: 0.5,
        };
        // set down on the table, turned: it rests where it is
        let pose = Pose {
            position_m: [0.01, -0.02],
            angle_rad: 0.3,
        };
        let out = rest_on_table(&disc, pose, &table, G, 0.002, 200, |_| {
            Ok::<_, crate::Error>(Vec::new())
        })
        .unwrap();
        assert!(out.at_rest && out.steps == 0, "{out:?}");
        assert_eq!(out.pose, pose);
    }

    #[test]
    fn a_push_moves_the_object_only_past_the_table_friction() {
        // a flat square pushed sideways at its centre's height by a finger
        // pressing with N: it slides iff N > μ_t (m g + μ N), the pusher's
        // friction pressing it onto the table at most (μ: the object's
        // against the finger); without friction at the finger iff N > μ_t m g
        let table = TableTop {
            top_m: -0.0325,
            mu: 0.4,
        };
        for mu in [0.0, 0.5] {
            let (mut o, pose) = square(0.0);
            o.mu = mu;
            let limit = table.mu * o.mass_kg * 9.81 / (1.0 - table.mu * mu);
            for (force, moves) in [(0.97 * limit, false), (1.03 * limit, true)] {
                let push = |p: &Pose| {
                    Ok::<_, crate::Error>(vec![FrictionContact {
                        point_m: [p.position_m[0] - 0.0325, p.position_m[1]],
                        normal: [1.0, 0.0],
                        max_normal_force_n: force,
                    }])
                };
                let out = rest_on_table(&o, pose, &table, G, 0.001, 5, push).unwrap();
                assert_eq!(out.at_rest, !moves, "mu {mu} N {force} {out:?}");
                if moves {
                    // it slides along the table, flat, in the push's direction
                    assert!(out.pose.position_m[0] > 0.004, "{out:?}");
                    assert!(out.pose.angle_rad.abs() < 1e-9, "{out:?}");
                    assert!((out.pose.position_m[1] - pose.position_m[1]).abs() < 1e-9);
                } else {
                    assert_eq!(out.pose, pose);
                }
            }
        }
    }
}
