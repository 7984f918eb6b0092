//! Rigid planar obstacles and their signed distance: value, outward normal
//! and curvature at a point.

use nalgebra::{Matrix2, Vector2};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_positive};

/// Largest coordinate or radius (m) an obstacle may have: beyond it the gap
/// arithmetic (squared lengths, cross products) can only overflow, so
/// [`Obstacle::validate`] refuses it by the field the user wrote.
///
/// # Example
/// ```
/// use softrod::contact::{Obstacle, MAX_OBSTACLE_EXTENT_M};
/// let far = Obstacle::Circle { center_m: [2.0 * MAX_OBSTACLE_EXTENT_M, 0.0], radius_m: 0.01 };
/// assert!(far.validate("obstacles[0]").unwrap_err().to_string().contains("obstacles[0].center_m"));
/// ```
pub const MAX_OBSTACLE_EXTENT_M: f64 = 1e12;

/// A rigid obstacle fixed in the world plane (coordinates in m).
///
/// Serialized with a `"shape"` tag:
/// `{"shape": "circle", "center_m": [0.1, -0.02], "radius_m": 0.01}`.
///
/// # Example
/// ```
/// use softrod::contact::Obstacle;
/// let o: Obstacle = serde_json::from_str(r#"{"shape": "circle", "center_m": [0.1, -0.02], "radius_m": 0.01}"#)?;
/// o.validate("obstacles[0]")?;
/// // a point 0.03 m from the centre is 0.02 m from the surface
/// assert!((o.signed_distance(nalgebra::Vector2::new(0.1, 0.01)).distance_m - 0.02).abs() < 1e-15);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum Obstacle {
    /// A disk.
    Circle {
        /// Centre (m).
        center_m: [f64; 2],
        /// Radius (m), positive.
        radius_m: f64,
    },
    /// The points within `radius_m` of the segment from `start_m` to `end_m`
    /// (a stadium; a zero-length segment is a disk).
    Capsule {
        /// One end of the axis (m).
        start_m: [f64; 2],
        /// The other end of the axis (m).
        end_m: [f64; 2],
        /// Radius (m), positive.
        radius_m: f64,
    },
    /// A convex polygon, vertices counter-clockwise (m), at least three, no
    /// three consecutive ones collinear.
    Polygon {
        /// Vertices, counter-clockwise (m).
        vertices_m: Vec<[f64; 2]>,
    },
}

/// Signed distance of a point to an obstacle's surface (positive outside),
/// its gradient (the outward unit normal at the closest surface point) and
/// its Hessian.
///
/// # Example
/// ```
/// use nalgebra::{Matrix2, Vector2};
/// use softrod::contact::Obstacle;
/// let o = Obstacle::Capsule { start_m: [0.0, 0.0], end_m: [1.0, 0.0], radius_m: 0.1 };
/// let d = o.signed_distance(Vector2::new(0.5, 0.3));
/// assert!((d.distance_m - 0.2).abs() < 1e-15 && d.normal == Vector2::new(0.0, 1.0));
/// assert_eq!(d.hessian_per_m, Matrix2::zeros()); // flat side: no curvature
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SignedDistance {
    /// Distance to the surface (m; negative inside).
    pub distance_m: f64,
    /// Unit gradient of the distance: the outward normal.
    pub normal: Vector2<f64>,
    /// Hessian of the distance (1/m): `(I − n nᵀ)/d` from a point or a
    /// rounded end at distance `d` from its centre, 0 from a flat side.
    pub hessian_per_m: Matrix2<f64>,
}

/// The closest-point features of an obstacle: what the distance is measured
/// to in each region of the plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Feature {
    /// Distance `|x − c| − radius`.
    Point { c: [f64; 2], radius: f64 },
    /// Distance `n·(x − p) − offset` (`n` unit).
    Line {
        p: [f64; 2],
        n: [f64; 2],
        offset: f64,
    },
}

fn sub(a: &[f64; 2], b: &[f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}
fn dot(a: &[f64; 2], b: &[f64; 2]) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn cross(a: &[f64; 2], b: &[f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// Distance from `x` to the point `c`, minus `radius`: curved.
fn from_point(x: &[f64; 2], c: &[f64; 2], radius: f64) -> SignedDistance {
    let v = sub(x, c);
    let d = dot(&v, &v).sqrt();
    if d == 0.0 || !d.is_finite() {
        // at the centre the normal is undefined: any unit vector, no curvature
        return SignedDistance {
            distance_m: d - radius,
            normal: Vector2::new(1.0, 0.0),
            hessian_per_m: Matrix2::zeros(),
        };
    }
    let n = [v[0] / d, v[1] / d];
    SignedDistance {
        distance_m: d - radius,
        normal: Vector2::from(n),
        hessian_per_m: Matrix2::new(
            (1.0 - n[0] * n[0]) / d,
            -n[0] * n[1] / d,
            -n[0] * n[1] / d,
            (1.0 - n[1] * n[1]) / d,
        ),
    }
}

/// Distance from `x` to the segment `a`–`b`, minus `radius`.
fn from_segment(x: &[f64; 2], a: &[f64; 2], b: &[f64; 2], radius: f64) -> SignedDistance {
    let e = sub(b, a);
    let l2 = dot(&e, &e);
    let t = if l2 > 0.0 {
        dot(&sub(x, a), &e) / l2
    } else {
        0.0
    };
    if t <= 0.0 {
        return from_point(x, a, radius);
    }
    if t >= 1.0 {
        return from_point(x, b, radius);
    }
    let c = [a[0] + t * e[0], a[1] + t * e[1]];
    let v = sub(x, &c);
    let d = dot(&v, &v).sqrt();
    let l = l2.sqrt();
    // on the axis: the left normal of the segment
    let n = if d > 0.0 {
        [v[0] / d, v[1] / d]
    } else {
        [-e[1] / l, e[0] / l]
    };
    SignedDistance {
        distance_m: d - radius,
        normal: Vector2::from(n),
        hessian_per_m: Matrix2::zeros(),
    }
}

impl Obstacle {
    /// A disk of centre `center_m` (m) and radius `radius_m` (m), from a
    /// typed point (unchecked, like the variant: see [`Obstacle::validate`]).
    ///
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::contact::Obstacle;
    /// let o = Obstacle::circle(Vector2::new(0.1, 0.0), 0.02);
    /// assert_eq!(o, Obstacle::Circle { center_m: [0.1, 0.0], radius_m: 0.02 });
    /// assert!((o.signed_distance(Vector2::new(0.1, 0.05)).distance_m - 0.03).abs() < 1e-15);
    /// ```
    pub fn circle(center_m: Vector2<f64>, radius_m: f64) -> Obstacle {
        Obstacle::Circle {
            center_m: center_m.into(),
            radius_m,
        }
    }

    /// A capsule (stadium) around the segment from `start_m` to `end_m`
    /// (m), radius `radius_m` (m), from typed points.
    ///
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::contact::Obstacle;
    /// let o = Obstacle::capsule(Vector2::zeros(), Vector2::new(1.0, 0.0), 0.1);
    /// assert_eq!(o.points()[1], Vector2::new(1.0, 0.0));
    /// ```
    pub fn capsule(start_m: Vector2<f64>, end_m: Vector2<f64>, radius_m: f64) -> Obstacle {
        Obstacle::Capsule {
            start_m: start_m.into(),
            end_m: end_m.into(),
            radius_m,
        }
    }

    /// A convex polygon from its vertices, counter-clockwise (m).
    ///
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::contact::Obstacle;
    /// let square = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]].map(Vector2::from);
    /// let o = Obstacle::polygon(&square);
    /// o.validate("obstacles[0]")?;
    /// assert_eq!(o.points().len(), 4);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn polygon(vertices_m: &[Vector2<f64>]) -> Obstacle {
        Obstacle::Polygon {
            vertices_m: vertices_m.iter().map(|&v| v.into()).collect(),
        }
    }

    /// The points that place the obstacle, as vectors (m): a disk's centre,
    /// a capsule's two ends, a polygon's vertices.
    ///
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::contact::Obstacle;
    /// let o = Obstacle::Circle { center_m: [0.1, 0.2], radius_m: 0.01 };
    /// assert_eq!(o.points(), vec![Vector2::new(0.1, 0.2)]);
    /// ```
    pub fn points(&self) -> Vec<Vector2<f64>> {
        match self {
            Obstacle::Circle { center_m, .. } => vec![Vector2::from(*center_m)],
            Obstacle::Capsule { start_m, end_m, .. } => {
                vec![Vector2::from(*start_m), Vector2::from(*end_m)]
            }
            Obstacle::Polygon { vertices_m } => {
                vertices_m.iter().map(|&v| Vector2::from(v)).collect()
            }
        }
    }

    /// Checks the obstacle; errors name `path.field` (`path` is where the
    /// obstacle sits, e.g. `obstacles[2]`).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a non-finite coordinate, a radius
    /// that is not positive and finite, a polygon with fewer than three
    /// vertices, a zero-length edge, three collinear consecutive vertices,
    /// clockwise order, or a polygon that is not convex (it turns right, or
    /// winds around more than once). Nothing is reordered or repaired.
    ///
    /// # Example
    /// ```
    /// use softrod::contact::Obstacle;
    /// let cw = Obstacle::Polygon { vertices_m: vec![[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]] };
    /// let err = cw.validate("obstacles[1]").unwrap_err();
    /// assert_eq!(err.field(), Some("obstacles[1].vertices_m"));
    /// ```
    pub fn validate(&self, path: &str) -> Result<()> {
        let field = |f: &str| format!("{path}.{f}");
        // Magnitudes that can only overflow the gap arithmetic (squared
        // edge lengths, cross products) are refused up front, by the field
        // the user wrote, instead of blaming a neighbouring vertex later.
        let point = |f: &str, p: &[f64; 2]| -> Result<()> {
            if !p.iter().all(|v| v.is_finite()) {
                Err(Error::invalid(field(f), format!("{p:?}"), "must be finite"))
            } else if p.iter().any(|v| v.abs() > MAX_OBSTACLE_EXTENT_M) {
                Err(Error::invalid(
                    field(f),
                    format!("{p:?}"),
                    format!("must lie within {MAX_OBSTACLE_EXTENT_M:e} m of the origin"),
                ))
            } else {
                Ok(())
            }
        };
        let radius = |r: f64| -> Result<()> {
            check_positive(&field("radius_m"), r)?;
            if r > MAX_OBSTACLE_EXTENT_M {
                return Err(Error::invalid(
                    field("radius_m"),
                    r,
                    format!("must not exceed {MAX_OBSTACLE_EXTENT_M:e} m"),
                ));
            }
            Ok(())
        };
        match self {
            Obstacle::Circle { center_m, radius_m } => {
                point("center_m", center_m)?;
                radius(*radius_m)
            }
            Obstacle::Capsule {
                start_m,
                end_m,
                radius_m,
            } => {
                point("start_m", start_m)?;
                point("end_m", end_m)?;
                radius(*radius_m)
            }
            Obstacle::Polygon { vertices_m } => {
                let name = field("vertices_m");
                let n = vertices_m.len();
                if n < 3 {
                    return Err(Error::invalid(
                        name,
                        n,
                        "a polygon needs at least 3 vertices",
                    ));
                }
                for (i, p) in vertices_m.iter().enumerate() {
                    point(&format!("vertices_m[{i}]"), p)?;
                }
                let mut turning = 0.0;
                for i in 0..n {
                    let a = &vertices_m[i];
                    let b = &vertices_m[(i + 1) % n];
                    let c = &vertices_m[(i + 2) % n];
                    let (e1, e2) = (sub(b, a), sub(c, b));
                    let (l1, l2) = (dot(&e1, &e1).sqrt(), dot(&e2, &e2).sqrt());
                    if l1 == 0.0 || !l1.is_finite() {
                        return Err(Error::invalid(
                            format!("{name}[{}]", (i + 1) % n),
                            format!("{b:?}"),
                            format!("repeats vertex {i} (zero-length edge)"),
                        ));
                    }
                    let s = cross(&e1, &e2) / (l1 * l2);
                    if s.abs() <= 1e-12 && dot(&e1, &e2) > 0.0 {
                        return Err(Error::invalid(
                            format!("{name}[{}]", (i + 1) % n),
                            format!("{b:?}"),
                            "lies on the line of its neighbours: remove it",
                        ));
                    }
                    if s <= 0.0 {
                        let total: f64 = (0..n)
                            .map(|j| {
                                let a = &vertices_m[j];
                                let b = &vertices_m[(j + 1) % n];
                                cross(a, b)
                            })
                            .sum();
                        let reason = if total < 0.0 {
                            "vertices must be counter-clockwise (they are clockwise)"
                        } else {
                            "polygon is not convex"
                        };
                        return Err(Error::invalid(name, format!("{:?}", vertices_m), reason));
                    }
                    turning += cross(&e1, &e2).atan2(dot(&e1, &e2));
                }
                if (turning - std::f64::consts::TAU).abs() > 1e-6 {
                    return Err(Error::invalid(
                        name,
                        format!("{:?}", vertices_m),
                        "polygon winds around more than once (not convex)",
                    ));
                }
                Ok(())
            }
        }
    }

    /// Signed distance of the point `x` (m) to the obstacle's surface,
    /// positive outside, with its gradient and Hessian (see
    /// [`SignedDistance`]). Inside a polygon: the largest signed distance to
    /// its edges' lines.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector2;
    /// use softrod::contact::Obstacle;
    /// let disk = Obstacle::Circle { center_m: [0.0, 0.0], radius_m: 0.1 };
    /// let d = disk.signed_distance(Vector2::new(0.0, -0.3));
    /// assert!((d.distance_m - 0.2).abs() < 1e-15);
    /// assert!((d.normal - Vector2::new(0.0, -1.0)).norm() < 1e-15);
    /// ```
    pub fn signed_distance(&self, x: Vector2<f64>) -> SignedDistance {
        let x: &[f64; 2] = &x.into();
        match self {
            Obstacle::Circle { center_m, radius_m } => from_point(x, center_m, *radius_m),
            Obstacle::Capsule {
                start_m,
                end_m,
                radius_m,
            } => from_segment(x, start_m, end_m, *radius_m),
            Obstacle::Polygon { vertices_m } => {
                let n = vertices_m.len();
                let mut inside = true;
                let mut best_line = (f64::NEG_INFINITY, [1.0, 0.0]);
                let mut best_seg: Option<SignedDistance> = None;
                for i in 0..n {
                    let a = &vertices_m[i];
                    let b = &vertices_m[(i + 1) % n];
                    let e = sub(b, a);
                    let l = dot(&e, &e).sqrt();
                    let nrm = [e[1] / l, -e[0] / l];
                    let h = dot(&nrm, &sub(x, a));
                    if h > 0.0 {
                        inside = false;
                    }
                    if h > best_line.0 {
                        best_line = (h, nrm);
                    }
                    let s = from_segment(x, a, b, 0.0);
                    if best_seg.is_none_or(|b| s.distance_m < b.distance_m) {
                        best_seg = Some(s);
                    }
                }
                match best_seg {
                    Some(s) if !inside => s,
                    _ => SignedDistance {
                        distance_m: best_line.0,
                        normal: Vector2::from(best_line.1),
                        hessian_per_m: Matrix2::zeros(),
                    },
                }
            }
        }
    }

    /// The closest-point features: the stationary points of the distance
    /// along a curve are among the stationary points of the features'
    /// distances (and, inside a polygon, the crossings of two edge lines).
    pub(crate) fn features(&self) -> Vec<Feature> {
        match self {
            Obstacle::Circle { center_m, radius_m } => vec![Feature::Point {
                c: *center_m,
                radius: *radius_m,
            }],
            Obstacle::Capsule {
                start_m,
                end_m,
                radius_m,
            } => {
                let mut f = vec![
                    Feature::Point {
                        c: *start_m,
                        radius: *radius_m,
                    },
                    Feature::Point {
                        c: *end_m,
                        radius: *radius_m,
                    },
                ];
                let e = sub(end_m, start_m);
                let l = dot(&e, &e).sqrt();
                if l > 0.0 {
                    for sign in [1.0, -1.0] {
                        f.push(Feature::Line {
                            p: *start_m,
                            n: [-sign * e[1] / l, sign * e[0] / l],
                            offset: *radius_m,
                        });
                    }
                }
                f
            }
            Obstacle::Polygon { vertices_m } => {
                let n = vertices_m.len();
                let mut f: Vec<Feature> = vertices_m
                    .iter()
                    .map(|c| Feature::Point { c: *c, radius: 0.0 })
                    .collect();
                for i in 0..n {
                    let a = &vertices_m[i];
                    let e = sub(&vertices_m[(i + 1) % n], a);
                    let l = dot(&e, &e).sqrt();
                    f.push(Feature::Line {
                        p: *a,
                        n: [e[1] / l, -e[0] / l],
                        offset: 0.0,
                    });
                }
                f
            }
        }
    }
}
