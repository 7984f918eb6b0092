//! The lifted object as a planar rigid body (position and rotation) that
//! settles quasi-statically in the fingers.
//!
//! After the lift nothing but the fingers carries the object. At each pose
//! the fingers are solved against it at their held pressures (the caller's
//! contact solve), and the friction check
//! ([`crate::grasp::friction::hold_check`]) decides whether the contact forces
//! can balance its weight inside the friction cones. If they cannot, the
//! object moves: from rest it accelerates along `a = M⁻¹ r`, where `r` is
//! the unbalanced wrench (force and moment about the centre of mass) left
//! by the contact forces that minimize `rᵀ M⁻¹ r` (Gauss's principle of
//! least constraint with the same cones and normal-force bounds as the
//! friction check; `M = diag(m, m, I)`). The object takes a step along
//! `a`, scaled so that no point of interest (the centre of mass, the
//! contact points) moves by more than the step length and it turns by at
//! most 0.02 rad, the fingers are
//! solved again, and so on until it holds or a finger loses it. When the
//! direction reverses (`a_k · M a_(k−1) < 0`) the step and the turn halve,
//! down to an eighth. An unequal pinch (the two contacts at different heights on a
//! thin object) leaves a couple the friction cannot balance: the object
//! turns until the contact normals line up, as a ruler turns in a pinch.
//!
//! The slip is the sliding at the contacts: per step, the tangential part
//! of the relative displacement of the object's and the finger's material
//! points that touched before the step (the object's move as a rigid body,
//! the finger's from its new contact solve), the larger of the two
//! fingers', summed over the steps. An object that slides down between
//! fingers that stay slips by its descent; one that rolls on the fingertips
//! while it turns does not slip.

use clarabel::algebra::CscMatrix;
use clarabel::solver::{NonnegativeConeT, SecondOrderConeT, SupportedConeT};

use crate::error::{Error, Result};
use crate::grasp::friction::{FrictionContact, HoldCheck, hold_check, solve_cone_program};
use crate::grasp::object::{GraspObject, Pose};

/// The smallest step, as a fraction of the step length.
pub(crate) const MIN_STEP_FRACTION: f64 = 0.125;
/// The largest turn of a full step (rad): a turn of 0.4 rad in one 2 mm step
/// of a contact 5 mm from the centre of mass overshot on the ruler and made
/// it rock (measured).
pub(crate) const MAX_TURN_RAD: f64 = 0.02;

/// A contact of the rigid body for its least-constraint program: the
/// normal force `λ` bounded by `min_normal_force_n ≤ λ ≤ max_normal_force_n`
/// (the upper bound may be infinite: a rigid support), the friction force
/// `|τ| ≤ μ λ`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Support {
    /// Contact point (m).
    pub(crate) point_m: [f64; 2],
    /// Unit normal into the object (the direction of the push).
    pub(crate) normal: [f64; 2],
    /// Smallest normal force (N, `>= 0`).
    pub(crate) min_normal_force_n: f64,
    /// Largest normal force (N, `>= min`; `f64::INFINITY`: unbounded).
    pub(crate) max_normal_force_n: f64,
    /// Friction coefficient there.
    pub(crate) mu: f64,
}

/// The acceleration `[a_x, a_y, α]` (m/s², m/s², rad/s²) of a rigid body at
/// rest under gravity and the contact forces of least constraint (module
/// docs): zero iff the friction check holds at weight factor 1.
pub(crate) fn least_constraint_acceleration(
    contacts: &[FrictionContact],
    mass_kg: f64,
    inertia_kg_m2: f64,
    com_m: [f64; 2],
    mu: f64,
    gravity_m_per_s2: [f64; 2],
) -> Result<[f64; 3]> {
    let supports: Vec<Support> = contacts
        .iter()
        .map(|c| Support {
            point_m: c.point_m,
            normal: c.normal,
            min_normal_force_n: 0.0,
            max_normal_force_n: c.max_normal_force_n,
            mu,
        })
        .collect();
    Ok(least_constraint(&supports, mass_kg, inertia_kg_m2, com_m, gravity_m_per_s2)?.acceleration)
}

/// [`least_constraint_acceleration`] for general supports: the forces in
/// their bounds and cones that minimize `rᵀ M⁻¹ r` (module docs); a support
/// whose lower bound is positive pushes at least that hard (a finger
/// pressing on an object on the table), an unbounded one is rigid (the
/// table: the acceleration it leaves does not point into it).
pub(crate) fn least_constraint(
    contacts: &[Support],
    mass_kg: f64,
    inertia_kg_m2: f64,
    com_m: [f64; 2],
    gravity_m_per_s2: [f64; 2],
) -> Result<LeastConstraint> {
    let k = contacts.len();
    let g = gravity_m_per_s2;
    if k == 0 {
        return Ok(LeastConstraint {
            acceleration: [g[0], g[1], 0.0],
            normal_forces_n: Vec::new(),
        });
    }
    // scaled: forces by the weight, moments by weight · ell
    let weight = mass_kg * g[0].hypot(g[1]);
    let ell = contacts
        .iter()
        .map(|c| (c.point_m[0] - com_m[0]).hypot(c.point_m[1] - com_m[1]))
        .fold(0.0, f64::max)
        .max(1e-12);
    // r = A x + w with x the free forces (λ_i, τ_i of a support whose normal
    // force is free, τ_i alone of one whose normal force is fixed: its push
    // goes into w), w = (m g + fixed pushes) / W
    let mut w = [mass_kg * g[0] / weight, mass_kg * g[1] / weight, 0.0];
    let mut a: Vec<[f64; 3]> = Vec::with_capacity(2 * k);
    // per support: the column of its λ (None: fixed) and of its τ
    let mut cols: Vec<(Option<usize>, usize)> = Vec::with_capacity(k);
    for c in contacts {
        let n = c.normal;
        let t = [-n[1], n[0]];
        let r = [c.point_m[0] - com_m[0], c.point_m[1] - com_m[1]];
        let an = [n[0], n[1], (r[0] * n[1] - r[1] * n[0]) / ell];
        let at = [t[0], t[1], (r[0] * t[1] - r[1] * t[0]) / ell];
        let fixed = c.max_normal_force_n <= c.min_normal_force_n;
        let ln = if fixed {
            for d in 0..3 {
                w[d] += an[d] * c.min_normal_force_n / weight;
            }
            None
        } else {
            a.push(an);
            Some(a.len() - 1)
        };
        a.push(at);
        cols.push((ln, a.len() - 1));
    }
    // M⁻¹ in these units: force rows 1, the moment row m ell² / I
    let minv = [1.0, 1.0, mass_kg * ell * ell / inertia_kg_m2];
    let nx = a.len();
    // P = Aᵀ M⁻¹ A (upper triangle), q = Aᵀ M⁻¹ w
    let (mut pr, mut pc, mut pv) = (Vec::new(), Vec::new(), Vec::new());
    let mut q = vec![0.0; nx];
    for col in 0..nx {
        for row in 0..=col {
            let v: f64 = (0..3).map(|d| a[row][d] * minv[d] * a[col][d]).sum();
            if v != 0.0 {
                pr.push(row);
                pc.push(col);
                pv.push(v);
            }
        }
        q[col] = (0..3).map(|d| a[col][d] * minv[d] * w[d]).sum();
    }
    // constraints: min_i ≤ λ_i (≤ max_i when bounded); a fixed normal
    // force's |τ_i| ≤ μ_i N_i; then (μ_i λ_i, τ_i) in the second-order cone
    let (mut ri, mut ci, mut vi, mut b) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut row = 0;
    for (c, &(ln, lt)) in contacts.iter().zip(&cols) {
        let mut push = |col: usize, v: f64, rhs: f64| {
            ri.push(row);
            ci.push(col);
            vi.push(v);
            b.push(rhs);
            row += 1;
        };
        match ln {
            Some(l) => {
                push(l, -1.0, -c.min_normal_force_n / weight);
                if c.max_normal_force_n.is_finite() {
                    push(l, 1.0, c.max_normal_force_n / weight);
                }
            }
            None => {
                let cap = c.mu * c.min_normal_force_n / weight;
                push(lt, 1.0, cap);
                push(lt, -1.0, cap);
            }
        }
    }
    let bounds = row;
    let mut cones: Vec<SupportedConeT<f64>> = vec![NonnegativeConeT(bounds)];
    for (c, &(ln, lt)) in contacts.iter().zip(&cols) {
        if let Some(l) = ln {
            ri.extend([row, row + 1]);
            ci.extend([l, lt]);
            vi.extend([-c.mu, -1.0]);
            b.extend([0.0, 0.0]);
            row += 2;
            cones.push(SecondOrderConeT(2));
        }
    }
    let amat = CscMatrix::new_from_triplets(row, nx, ri, ci, vi);
    let p = CscMatrix::new_from_triplets(nx, nx, pr, pc, pv);
    let x = solve_cone_program("least_constraint", &p, &q, &amat, &b, &cones, 1e-12)?;
    let mut r = w;
    for (j, col) in a.iter().enumerate() {
        for d in 0..3 {
            r[d] += col[d] * x[j];
        }
    }
    Ok(LeastConstraint {
        acceleration: [
            r[0] * weight / mass_kg,
            r[1] * weight / mass_kg,
            r[2] * weight * ell / inertia_kg_m2,
        ],
        normal_forces_n: contacts
            .iter()
            .zip(&cols)
            .map(|(c, (ln, _))| ln.map_or(c.min_normal_force_n, |l| x[l] * weight))
            .collect(),
    })
}

/// The answer of [`least_constraint`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct LeastConstraint {
    /// `[a_x, a_y, α]` (m/s², m/s², rad/s²).
    pub(crate) acceleration: [f64; 3],
    /// Each support's normal force (N).
    pub(crate) normal_forces_n: Vec<f64>,
}

/// How the object ended after the lift.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Settled {
    /// The pose where it holds, or where it was lost.
    pub(crate) pose: Pose,
    /// Whether the contacts hold it there.
    pub(crate) holds: bool,
    /// The friction check right after the lift.
    pub(crate) first: HoldCheck,
    /// The slip (module docs, m).
    pub(crate) slip_m: f64,
}

/// A finger's contact with the object, to follow its material points.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Touch {
    /// Where the finger touches along it (its undeformed arc coordinate, m;
    /// the caller's label of the finger's material point).
    pub(crate) s_m: f64,
    /// The side of the finger's centreline the point is on (`±1`; the caller's).
    pub(crate) side: f64,
    /// The contact point on the object's surface (m).
    pub(crate) point_m: [f64; 2],
    /// The finger's surface point there (m).
    pub(crate) finger_point_m: [f64; 2],
    /// The contact's unit normal into the object.
    pub(crate) normal: [f64; 2],
}

/// What the caller's contact solve gives at a pose: the contacts (normals
/// into the object), whether both fingers still touch it, each finger's
/// main contact, and where the finger material points of the last solve's
/// main contacts are now.
pub(crate) struct Grip {
    pub(crate) contacts: Vec<FrictionContact>,
    pub(crate) both_fingers: bool,
    pub(crate) touches: [Option<Touch>; 2],
    pub(crate) followed_m: [Option<[f64; 2]>; 2],
}

/// The sliding between object and finger at a contact from one solve to
/// the next: the tangential part of the relative displacement of the two
/// material points that touched at `before` (the object's at its poses
/// `from` → `to`, the finger's from `before.finger_point_m` to `followed`).
fn sliding(before: &Touch, from: &Pose, to: &Pose, followed: [f64; 2]) -> f64 {
    let (s0, c0) = from.angle_rad.sin_cos();
    let (s1, c1) = to.angle_rad.sin_cos();
    let d = [
        before.point_m[0] - from.position_m[0],
        before.point_m[1] - from.position_m[1],
    ];
    let local = [c0 * d[0] + s0 * d[1], -s0 * d[0] + c0 * d[1]];
    let now = [
        to.position_m[0] + c1 * local[0] - s1 * local[1],
        to.position_m[1] + s1 * local[0] + c1 * local[1],
    ];
    let rel = [
        now[0] - before.point_m[0] - (followed[0] - before.finger_point_m[0]),
        now[1] - before.point_m[1] - (followed[1] - before.finger_point_m[1]),
    ];
    let t = [-before.normal[1], before.normal[0]];
    (rel[0] * t[0] + rel[1] * t[1]).abs()
}

/// Lets `object` settle from `start` (module docs): `grip` solves the
/// fingers against the object at a pose, following the finger material
/// points of the touches it is given. Ends when it holds, when a finger
/// lost it, or after `max_steps` steps (lost). `step_m` is the step length.
///
/// # Errors
/// Whatever `grip` returns; [`Error::InvalidParameter`] if a program is
/// not solved.
pub(crate) fn settle<E: From<Error>>(
    object: &GraspObject,
    start: Pose,
    gravity_m_per_s2: [f64; 2],
    step_m: f64,
    max_steps: usize,
    mut grip: impl FnMut(&Pose, [Option<Touch>; 2]) -> std::result::Result<Grip, E>,
) -> std::result::Result<Settled, E> {
    let m = object.mass_kg;
    let inertia = object.moment_of_inertia_kg_m2();
    let mut pose = start;
    let mut last: Option<(Pose, [Option<Touch>; 2])> = None;
    let mut slip = 0.0;
    let mut h = step_m;
    let mut first: Option<HoldCheck> = None;
    let mut previous: Option<[f64; 3]> = None;
    for k in 0..=max_steps {
        let before = last.map_or([None, None], |(_, t)| t);
        let Grip {
            contacts,
            both_fingers,
            touches,
            followed_m,
        } = grip(&pose, before)?;
        if let Some((from, _)) = &last {
            // the sliding of this step: the larger of the two fingers'
            slip += before
                .iter()
                .zip(followed_m)
                .filter_map(|(b, f)| Some(sliding(b.as_ref()?, from, &pose, f?)))
                .fold(0.0, f64::max);
        }
        last = Some((pose, touches));
        let c = pose.position_m;
        let hold = hold_check(&contacts, m, c.into(), object.mu, gravity_m_per_s2.into())?;
        let holds = hold.holds;
        let first = first.get_or_insert(hold);
        if holds || !both_fingers || k == max_steps {
            return Ok(Settled {
                pose,
                holds,
                first: first.clone(),
                slip_m: slip,
            });
        }
        let a =
            least_constraint_acceleration(&contacts, m, inertia, c, object.mu, gravity_m_per_s2)?;
        if let Some(p) = previous
            && m * (a[0] * p[0] + a[1] * p[1]) + inertia * a[2] * p[2] < 0.0
        {
            h = (0.5 * h).max(MIN_STEP_FRACTION * step_m);
        }
        previous = Some(a);
        // the largest displacement per unit of `a` among the points of interest
        let reach = contacts
            .iter()
            .map(|f| [f.point_m[0] - c[0], f.point_m[1] - c[1]])
            .chain(std::iter::once([0.0, 0.0]))
            .map(|r| (a[0] - a[2] * r[1]).hypot(a[1] + a[2] * r[0]))
            .fold(0.0, f64::max);
        if !(reach.is_finite() && reach > 0.0) {
            // nothing moves although the check fails: at the check's tolerance
            return Ok(Settled {
                pose,
                holds: false,
                first: first.clone(),
                slip_m: slip,
            });
        }
        // at most the step length, and a turn of at most `MAX_TURN_RAD`
        // (it changes where the fingers touch a thin object fastest)
        let s = (h / reach).min(h / step_m * MAX_TURN_RAD / a[2].abs().max(1e-300));
        pose.position_m[0] += s * a[0];
        pose.position_m[1] += s * a[1];
        pose.angle_rad += s * a[2];
    }
    // not reached: the loop returns at k == max_steps
    Err(Error::invalid("settle", max_steps, "no steps").into())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::grasp::fixtures::{disc_pinch, flat_jaws};
    use crate::grasp::friction::disc_pinch_threshold_n;
    use crate::grasp::object::Shape;

    const G: [f64; 2] = [0.0, -9.81];

    fn rod(width_m: f64, mu: f64) -> GraspObject {
        GraspObject {
            name: "rod".into(),
            shape: Shape::Rectangle {
                size_m: [width_m, 0.03],
            },
            mass_kg: 0.02,
            mu,
        }
    }

    /// Two fingertip discs (radius `R`) at fixed centres pressing the object
    /// with a linear spring `k` on their overlap with its outline; a
    /// disc's material points are fixed (`s_m`: the angle on the disc).
    fn discs(
        object: &GraspObject,
        centres: [[f64; 2]; 2],
        radius: f64,
        k: f64,
    ) -> impl FnMut(&Pose, [Option<Touch>; 2]) -> Result<Grip> + '_ {
        move |pose: &Pose, before: [Option<Touch>; 2]| {
            let outline = object.obstacle(pose);
            let mut contacts = Vec::new();
            let mut touches = [None, None];
            for (i, c) in centres.into_iter().enumerate() {
                let d = outline.signed_distance(c.into());
                let overlap = radius - d.distance_m;
                if overlap > 0.0 {
                    // the outline's nearest point and the normal into the object
                    let n: [f64; 2] = object.surface_normal(pose, c.into()).into();
                    let p = [c[0] - d.distance_m * n[0], c[1] - d.distance_m * n[1]];
                    contacts.push(FrictionContact {
                        point_m: p,
                        normal: [-n[0], -n[1]],
                        max_normal_force_n: k * overlap,
                    });
                    let a = (-n[1]).atan2(-n[0]);
                    touches[i] = Some(Touch {
                        s_m: a,
                        side: 1.0,
                        point_m: p,
                        finger_point_m: [c[0] + radius * a.cos(), c[1] + radius * a.sin()],
                        normal: [-n[0], -n[1]],
                    });
                }
            }
            let followed_m = [0, 1].map(|i| {
                before[i].map(|t| {
                    [
                        centres[i][0] + radius * t.s_m.cos(),
                        centres[i][1] + radius * t.s_m.sin(),
                    ]
                })
            });
            Ok(Grip {
                both_fingers: contacts.len() == 2,
                contacts,
                touches,
                followed_m,
            })
        }
    }

    #[test]
    fn a_block_too_heavy_for_its_jaws_accelerates_by_the_missing_friction() {
        // flat jaws pressing N each, 2 μ N < m g: a_y = −(m g − 2 μ N)/m, no turn
        let (m, mu, n) = (0.1, 0.4, 0.8);
        let jaws = flat_jaws(0.02, [0.01, 0.01], n);
        let a = least_constraint_acceleration(&jaws, m, 1e-4, [0.0, 0.0], mu, G).unwrap();
        let expect = -(m * 9.81 - 2.0 * mu * n) / m;
        assert!(
            a[0].abs() < 1e-6 && (a[1] - expect).abs() < 1e-6 * 9.81 && a[2].abs() < 1e-4,
            "{a:?}"
        );
        // strong enough: no acceleration
        let a = least_constraint_acceleration(&jaws, 0.05, 1e-4, [0.0, 0.0], mu, G).unwrap();
        assert!(a.iter().all(|v| v.abs() < 1e-5), "{a:?}");
        // a disc pinched above its centre: the closed form's missing weight
        let (r, theta): (f64, f64) = (0.03, 0.3);
        let pinch = disc_pinch(r, theta, n);
        let held = disc_pinch_threshold_n(mu, n, theta);
        let m = 2.0 * held / 9.81;
        let a =
            least_constraint_acceleration(&pinch, m, 0.5 * m * r * r, [0.0, 0.0], mu, G).unwrap();
        assert!((a[1] + (m * 9.81 - held) / m).abs() < 1e-5 * 9.81, "{a:?}");
        assert!(a[0].abs() < 1e-6 && a[2].abs() < 1e-3, "{a:?}");
    }

    #[test]
    fn a_rod_pinched_off_centre_turns_until_it_holds() {
        // a thin rod between two fingertip discs whose centres are `h` apart
        // in height: the normals make a couple the friction on the 3 mm rod
        // cannot balance (offset d > μ w); the rod turns clockwise (its top
        // toward the lower finger) until the offset of its contacts along it
        // is at most μ w (closed form: N d ≤ (w/2)(2 μ N − m g cos φ), so
        // d ≤ μ w) and at least μ w − w m g / (2 N) less one step
        let (w, mu, radius, k) = (0.003, 0.5, 0.008, 2000.0);
        let o = rod(w, mu);
        let (x, h) = (0.5 * w + radius - 0.001, 0.005);
        let centres = [[-x, 0.5 * h], [x, -0.5 * h]];
        let start = Pose {
            position_m: [0.0, 0.0],
            angle_rad: 0.0,
        };
        let step = 2e-4;
        let out = settle(&o, start, G, step, 400, discs(&o, centres, radius, k)).unwrap();
        assert!(out.holds, "{out:?}");
        assert!(out.first.weight_factor < 1e-6);
        let phi = -out.pose.angle_rad;
        assert!(phi > 0.0, "{out:?}");
        // the offset along the rod's axis (sin φ, cos φ) of the fingertip centres
        let axis = [(-out.pose.angle_rad).sin(), out.pose.angle_rad.cos()];
        let d =
            (centres[0][0] - centres[1][0]) * axis[0] + (centres[0][1] - centres[1][1]) * axis[1];
        let n = k * 0.001; // about the squeeze
        assert!(d <= mu * w + 1e-9, "d {d} phi {phi}");
        let per_step = 2.0 * x * step / 0.0015; // the offset changes by 2x dφ, dφ ≤ step / (w/2)
        assert!(
            d >= mu * w - w * o.mass_kg * 9.81 / (2.0 * 0.5 * n) - per_step,
            "d {d} phi {phi}"
        );
        // it turned about the pinch: the centre of mass moved little
        let c = out.pose.position_m;
        assert!(c[0].hypot(c[1]) < 1e-3, "{out:?}");
        // on fixed discs it slides by the turn at its faces (w/2 per radian)
        // and by its centre's move, no more
        assert!(
            out.slip_m <= 0.5 * w * phi + c[0].hypot(c[1]) + 1e-6,
            "{out:?}"
        );
    }

    #[test]
    fn a_square_pinch_holds_where_it_is_and_a_weak_one_drops() {
        let (w, radius, k) = (0.003, 0.008, 2000.0);
        let x = 0.5 * w + radius - 0.001;
        let o = rod(w, 0.5);
        let start = Pose {
            position_m: [0.0, 0.0],
            angle_rad: 0.0,
        };
        let square = [[-x, 0.0], [x, 0.0]];
        let out = settle(&o, start, G, 2e-4, 400, discs(&o, square, radius, k)).unwrap();
        assert!(
            out.holds && out.slip_m == 0.0 && out.pose == start,
            "{out:?}"
        );
        // 2 μ N < m g: it slides down until a fingertip loses it
        let weak = rod(w, 0.04);
        assert!(2.0 * 0.04 * k * 0.001 < weak.mass_kg * 9.81);
        let out = settle(&weak, start, G, 1e-3, 400, discs(&weak, square, radius, k)).unwrap();
        assert!(!out.holds, "{out:?}");
        // the closed form of the flat pinch: weight factor 2 μ N / (m g)
        let expect = 2.0 * 0.04 * k * 0.001 / (weak.mass_kg * 9.81);
        assert!((out.first.weight_factor - expect).abs() < 1e-7, "{out:?}");
        // it slid straight down past the fingertips (the rod's top at 15 mm)
        let (c, phi) = (out.pose.position_m, out.pose.angle_rad.abs());
        assert!(c[1] < -0.015 && phi < 0.02, "{out:?}");
        // between fixed fingertips it slips by its descent (at the end its
        // corner passes a fingertip and it rocks a little: 1.3 %, measured)
        assert!(out.slip_m >= -c[1] - 1e-9, "{out:?}");
        assert!(out.slip_m <= 1.02 * c[0].hypot(c[1]), "{out:?}");
    }
}
