//! Objects to grasp: rigid planar shapes (the section in the gripper's
//! plane) with a mass and a friction coefficient.
//!
//! Every shape is convex and its centre of mass is its pose's position
//! (uniform density, symmetric shapes; a rounded polygon's core polygon is
//! given about its centroid). Its outline ([`GraspObject::obstacle`]) is a
//! circle or a convex polygon (an ellipse by 64 vertices, a rounded
//! polygon's corners by 8 vertices each on their arcs).
//!
//! In the plant's contact solve an object is its *circle cover*
//! ([`GraspObject::contact_cover`]): fixed circles whose union approximates
//! the shape. The contact solver converges reliably on circles, but in our
//! grasps it did not on polygons and capsules once a finger touched them
//! (measured: an ellipse as a 64-gon or as a stadium, a rounded rectangle as
//! a polygon: `IterationLimit` or `LineSearchFailed` at the first contact,
//! 90–130 s for the 64-gon), so the cover is what the fingers touch. Its
//! error is stated per shape there.

use nalgebra::Vector2;
use serde::{Deserialize, Serialize};

use crate::contact::Obstacle;
use crate::error::{Error, Result};

/// Vertices of an ellipse's polygon.
const ELLIPSE_VERTICES: usize = 64;
/// Vertices on each rounded corner's arc.
const CORNER_VERTICES: usize = 8;

/// The section of an object in the gripper's plane, about its centre of
/// mass, in its own frame.
///
/// # Example
/// ```
/// use softrod::grasp::object::Shape;
/// let s: Shape = serde_json::from_str(r#"{"shape": "ellipse", "semi_axes_m": [0.03, 0.02]}"#)?;
/// assert_eq!(s, Shape::Ellipse { semi_axes_m: [0.03, 0.02] });
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "shape", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// A disc.
    Circle {
        /// Radius (m).
        radius_m: f64,
    },
    /// An ellipse, axes along the object's frame.
    Ellipse {
        /// Semi-axes along x and y of the object's frame (m).
        semi_axes_m: [f64; 2],
    },
    /// A rectangle.
    Rectangle {
        /// Width and height (m).
        size_m: [f64; 2],
    },
    /// A convex polygon offset outward by `corner_radius_m` (its corners
    /// rounded, its edges moved out).
    RoundedPolygon {
        /// The core polygon, counter-clockwise, about the centre of mass (m).
        vertices_m: Vec<[f64; 2]>,
        /// The rounding radius (m).
        corner_radius_m: f64,
    },
}

/// An object: its shape, mass and friction coefficient against the fingers.
///
/// # Example
/// ```
/// use softrod::grasp::object::{GraspObject, Shape};
/// let o = GraspObject { name: "walnut".into(), shape: Shape::Circle { radius_m: 0.015 }, mass_kg: 0.01, mu: 0.5 };
/// o.validate("object")?;
/// let bad = GraspObject { mu: -0.1, ..o };
/// assert_eq!(bad.validate("object").unwrap_err().field(), Some("object.mu"));
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GraspObject {
    /// A name for reports.
    pub name: String,
    /// Its section.
    pub shape: Shape,
    /// Mass (kg, > 0).
    pub mass_kg: f64,
    /// Coulomb friction coefficient against the fingers (>= 0).
    pub mu: f64,
}

/// Where an object lies: its centre of mass and its rotation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Centre of mass (m).
    pub position_m: [f64; 2],
    /// Rotation of the object's frame (rad, counter-clockwise).
    pub angle_rad: f64,
}

impl Pose {
    /// The centre of mass as a vector (m; the field `position_m`).
    ///
    /// # Example
    /// ```
    /// use softrod::grasp::object::Pose;
    /// let p = Pose { position_m: [0.01, -0.08], angle_rad: 0.1 };
    /// assert_eq!(p.position(), nalgebra::Vector2::new(0.01, -0.08));
    /// ```
    pub fn position(&self) -> Vector2<f64> {
        self.position_m.into()
    }
}

/// The friction coefficients an object accepts: from 0.01 (ice on steel)
/// to 10 (far above any rubber). At `mu = 0` the hold check's friction
/// cone degenerates and its program ended in `InsufficientProgress`.
pub const MU_RANGE: (f64, f64) = (0.01, 10.0);

fn positive(path: &str, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(Error::invalid(path, v, "must be finite and > 0"))
    }
}

impl GraspObject {
    /// Checks the mass (`> 0`), `mu` (in [`MU_RANGE`]) and the shape (positive
    /// sizes; a rounded polygon's core convex and counter-clockwise, at
    /// least three vertices); field paths start with `path`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field.
    pub fn validate(&self, path: &str) -> Result<()> {
        positive(&format!("{path}.mass_kg"), self.mass_kg)?;
        let (lo, hi) = MU_RANGE;
        if !(self.mu.is_finite() && (lo..=hi).contains(&self.mu)) {
            return Err(Error::invalid(
                format!("{path}.mu"),
                self.mu,
                format!(
                    "must lie in [{lo}, {hi}]: a pinch without friction holds no weight \
                     (and its cone program degenerates), and no rubber grips above {hi}"
                ),
            ));
        }
        let sp = format!("{path}.shape");
        match &self.shape {
            Shape::Circle { radius_m } => positive(&format!("{sp}.radius_m"), *radius_m),
            Shape::Ellipse { semi_axes_m } => {
                for (k, v) in semi_axes_m.iter().enumerate() {
                    positive(&format!("{sp}.semi_axes_m[{k}]"), *v)?;
                }
                Ok(())
            }
            Shape::Rectangle { size_m } => {
                for (k, v) in size_m.iter().enumerate() {
                    positive(&format!("{sp}.size_m[{k}]"), *v)?;
                }
                Ok(())
            }
            Shape::RoundedPolygon {
                vertices_m,
                corner_radius_m,
            } => {
                positive(&format!("{sp}.corner_radius_m"), *corner_radius_m)?;
                let n = vertices_m.len();
                if n < 3 {
                    return Err(Error::invalid(
                        format!("{sp}.vertices_m"),
                        n,
                        "needs at least 3 vertices",
                    ));
                }
                for (i, &a) in vertices_m.iter().enumerate() {
                    let (b, c) = (vertices_m[(i + 1) % n], vertices_m[(i + 2) % n]);
                    let cr = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]);
                    if !(cr.is_finite() && cr > 0.0) {
                        return Err(Error::invalid(
                            format!("{sp}.vertices_m[{}]", (i + 1) % n),
                            format!("{b:?}"),
                            "the core polygon must be convex and counter-clockwise",
                        ));
                    }
                }
                Ok(())
            }
        }
    }

    /// The boundary in the object's frame: exact vertices for polygons,
    /// points on the curve for the ellipse and the rounded corners, none
    /// for a circle.
    fn local_vertices(&self) -> Vec<[f64; 2]> {
        match &self.shape {
            Shape::Circle { .. } => Vec::new(),
            Shape::Ellipse {
                semi_axes_m: [a, b],
            } => (0..ELLIPSE_VERTICES)
                .map(|k| {
                    let t = std::f64::consts::TAU * k as f64 / ELLIPSE_VERTICES as f64;
                    [a * t.cos(), b * t.sin()]
                })
                .collect(),
            Shape::Rectangle { size_m: [w, h] } => {
                let (w, h) = (0.5 * w, 0.5 * h);
                vec![[-w, -h], [w, -h], [w, h], [-w, h]]
            }
            Shape::RoundedPolygon {
                vertices_m,
                corner_radius_m: r,
            } => {
                let n = vertices_m.len();
                let normal = |i: usize| {
                    let (a, b) = (vertices_m[i], vertices_m[(i + 1) % n]);
                    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                    let l = dx.hypot(dy);
                    (-dx / l)
                        .atan2(dy / l) // outward normal (dy, −dx)/l of the edge i → i+1, as an angle
                        .rem_euclid(std::f64::consts::TAU)
                };
                let mut out = Vec::with_capacity(n * CORNER_VERTICES);
                for (i, &v) in vertices_m.iter().enumerate() {
                    let a0 = normal((i + n - 1) % n);
                    let mut a1 = normal(i);
                    if a1 < a0 {
                        a1 += std::f64::consts::TAU;
                    }
                    for k in 0..CORNER_VERTICES {
                        let t = a0 + (a1 - a0) * k as f64 / (CORNER_VERTICES - 1) as f64;
                        out.push([v[0] + r * t.cos(), v[1] + r * t.sin()]);
                    }
                }
                out
            }
        }
    }

    /// The obstacle the object is at `pose`.
    ///
    /// # Example
    /// ```
    /// use softrod::grasp::object::{GraspObject, Pose, Shape};
    /// let o = GraspObject { name: "box".into(), shape: Shape::Rectangle { size_m: [0.04, 0.02] }, mass_kg: 0.1, mu: 0.5 };
    /// let obs = o.obstacle(&Pose { position_m: [0.0, -0.1], angle_rad: 0.0 });
    /// let d = obs.signed_distance([0.03, -0.1].into());
    /// assert!((d.distance_m - 0.01).abs() < 1e-12);
    /// ```
    pub fn obstacle(&self, pose: &Pose) -> Obstacle {
        let (s, c) = pose.angle_rad.sin_cos();
        if let Shape::Circle { radius_m } = self.shape {
            return Obstacle::Circle {
                center_m: pose.position_m,
                radius_m,
            };
        }
        let mut vertices: Vec<[f64; 2]> = self
            .local_vertices()
            .into_iter()
            .map(|[x, y]| {
                [
                    pose.position_m[0] + c * x - s * y,
                    pose.position_m[1] + s * x + c * y,
                ]
            })
            .collect();
        // rounding arcs of adjacent corners may share a point: drop repeats
        vertices.dedup_by(|a, b| (a[0] - b[0]).hypot(a[1] - b[1]) < 1e-12);
        Obstacle::Polygon {
            vertices_m: vertices,
        }
    }

    /// The circle cover of the object at `pose` (see the module docs):
    /// - a circle: itself (exact);
    /// - a rounded polygon: circles of the corner radius centred along the
    ///   core polygon's boundary, at most half a radius apart: its outline
    ///   with shallow valleys between the circles (depth at most
    ///   `r (1 − cos 14.5°) = 0.032 r`);
    /// - a rectangle: circles of half its smaller side along its longer axis
    ///   (the same spacing): a stadium, the corners rounded off;
    /// - an ellipse: circles of its smaller semi-axis along the longer one:
    ///   the stadium with the same axes (exact at the four ends of the axes).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (field `object.shape`) if it needs more
    /// than 200 circles.
    ///
    /// # Example
    /// ```
    /// use softrod::grasp::object::{GraspObject, Pose, Shape};
    /// let o = GraspObject { name: "box".into(), shape: Shape::Rectangle { size_m: [0.04, 0.02] }, mass_kg: 0.1, mu: 0.5 };
    /// let cover = o.contact_cover(&Pose { position_m: [0.0, 0.0], angle_rad: 0.0 })?;
    /// // the stadium reaches the rectangle's ends and sides
    /// let d = |p: [f64; 2]| cover.iter().map(|c| c.signed_distance(p.into()).distance_m).fold(f64::INFINITY, f64::min);
    /// assert!((d([0.03, 0.0]) - 0.01).abs() < 1e-12 && (d([0.0, 0.02]) - 0.01).abs() < 1e-12);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn contact_cover(&self, pose: &Pose) -> Result<Vec<Obstacle>> {
        let (s, c) = pose.angle_rad.sin_cos();
        let p = pose.position_m;
        let world = |[x, y]: [f64; 2]| [p[0] + c * x - s * y, p[1] + s * x + c * y];
        // circles of radius r at most r/2 apart from a to b (b left out; local frame)
        let along = |a: [f64; 2], b: [f64; 2], r: f64, out: &mut Vec<[f64; 2]>| {
            let len = (b[0] - a[0]).hypot(b[1] - a[1]);
            let n = (len / (0.5 * r)).ceil().max(1.0) as usize;
            for k in 0..n {
                let t = k as f64 / n as f64;
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        };
        let mut centres = Vec::new();
        let r = match &self.shape {
            Shape::Circle { radius_m } => {
                return Ok(vec![Obstacle::Circle {
                    center_m: p,
                    radius_m: *radius_m,
                }]);
            }
            Shape::Ellipse {
                semi_axes_m: [a, b],
            }
            | Shape::Rectangle { size_m: [a, b] } => {
                let half = matches!(self.shape, Shape::Rectangle { .. });
                let (a, b) = if half { (0.5 * a, 0.5 * b) } else { (*a, *b) };
                let r = a.min(b);
                let ends = if a >= b {
                    [[-(a - r), 0.0], [a - r, 0.0]]
                } else {
                    [[0.0, -(b - r)], [0.0, b - r]]
                };
                along(ends[0], ends[1], r, &mut centres);
                centres.push(ends[1]);
                centres.dedup_by(|u, v| (u[0] - v[0]).hypot(u[1] - v[1]) < 1e-15);
                r
            }
            Shape::RoundedPolygon {
                vertices_m,
                corner_radius_m,
            } => {
                for (i, a) in vertices_m.iter().enumerate() {
                    let b = vertices_m[(i + 1) % vertices_m.len()];
                    along(*a, b, *corner_radius_m, &mut centres);
                }
                *corner_radius_m
            }
        };
        if centres.len() > 200 {
            return Err(Error::invalid(
                "object.shape",
                format!("{} circles", centres.len()),
                "its circle cover needs more than 200 circles (too thin for its size)",
            ));
        }
        Ok(centres
            .into_iter()
            .map(|x| Obstacle::Circle {
                center_m: world(x),
                radius_m: r,
            })
            .collect())
    }

    /// The moment of inertia about the centre of mass, normal to the plane
    /// (kg·m²), uniform density: a circle `m r²/2`, an ellipse
    /// `m (a² + b²)/4`, a rectangle `m (w² + h²)/12`, a rounded polygon that
    /// of its outline polygon (the corners by 8 vertices each).
    ///
    /// # Example
    /// ```
    /// use softrod::grasp::object::{GraspObject, Shape};
    /// let rod = GraspObject { name: "rod".into(), shape: Shape::Rectangle { size_m: [0.003, 0.03] }, mass_kg: 0.02, mu: 0.5 };
    /// let i = rod.moment_of_inertia_kg_m2();
    /// assert!((i - 0.02 * (0.003f64.powi(2) + 0.03f64.powi(2)) / 12.0).abs() < 1e-15);
    /// ```
    pub fn moment_of_inertia_kg_m2(&self) -> f64 {
        let m = self.mass_kg;
        match &self.shape {
            Shape::Circle { radius_m } => 0.5 * m * radius_m * radius_m,
            Shape::Ellipse {
                semi_axes_m: [a, b],
            } => 0.25 * m * (a * a + b * b),
            Shape::Rectangle { size_m: [w, h] } => m * (w * w + h * h) / 12.0,
            Shape::RoundedPolygon { .. } => m * polygon_gyration_m2(&self.local_vertices()),
        }
    }

    /// The unit normal of the object's true outline (not its circle cover)
    /// at the boundary point nearest to `point_m`, pointing out of the
    /// object, at `pose`. The friction check takes its cones about these:
    /// the plant touches the circle cover, whose normals in the valleys
    /// between two circles tilt by up to 14.5° from the outline's.
    ///
    /// # Example
    /// ```
    /// use softrod::grasp::object::{GraspObject, Pose, Shape};
    /// let sq = GraspObject { name: "sq".into(), shape: Shape::RoundedPolygon { vertices_m: vec![[-0.02, -0.02], [0.02, -0.02], [0.02, 0.02], [-0.02, 0.02]], corner_radius_m: 0.008 }, mass_kg: 0.2, mu: 0.5 };
    /// let pose = Pose { position_m: [0.0, 0.0], angle_rad: 0.0 };
    /// // a point on the right face, 1 mm inside: the face's normal
    /// let n = sq.surface_normal(&pose, nalgebra::Vector2::new(0.027, 0.011));
    /// assert!((n.x - 1.0).abs() < 1e-12 && n.y.abs() < 1e-12);
    /// ```
    pub fn surface_normal(&self, pose: &Pose, point_m: Vector2<f64>) -> Vector2<f64> {
        let (s, c) = pose.angle_rad.sin_cos();
        let d = [
            point_m[0] - pose.position_m[0],
            point_m[1] - pose.position_m[1],
        ];
        // the point in the object's frame
        let p = [c * d[0] + s * d[1], -s * d[0] + c * d[1]];
        let unit = |v: [f64; 2]| {
            let l = v[0].hypot(v[1]);
            if l > 0.0 && l.is_finite() {
                [v[0] / l, v[1] / l]
            } else {
                [0.0, 1.0]
            }
        };
        let local = match &self.shape {
            Shape::Circle { .. } => unit(p),
            Shape::Ellipse {
                semi_axes_m: [a, b],
            } => {
                // the nearest point (a cos t, b sin t): Newton on the
                // stationarity of the distance, from the radial guess
                let mut t = (a * p[1]).atan2(b * p[0]);
                for _ in 0..30 {
                    let (st, ct) = t.sin_cos();
                    let f = (a * a - b * b) * st * ct - p[0] * a * st + p[1] * b * ct;
                    let df = (a * a - b * b) * (ct * ct - st * st) - p[0] * a * ct - p[1] * b * st;
                    if df.abs() < 1e-300 {
                        break;
                    }
                    let step = f / df;
                    t -= step.clamp(-0.5, 0.5);
                    if step.abs() < 1e-14 {
                        break;
                    }
                }
                let (st, ct) = t.sin_cos();
                unit([b * ct, a * st])
            }
            Shape::Rectangle { size_m: [w, h] } => {
                let core = [
                    [-0.5 * w, -0.5 * h],
                    [0.5 * w, -0.5 * h],
                    [0.5 * w, 0.5 * h],
                    [-0.5 * w, 0.5 * h],
                ];
                polygon_normal(&core, p)
            }
            Shape::RoundedPolygon { vertices_m, .. } => polygon_normal(vertices_m, p),
        };
        Vector2::new(c * local[0] - s * local[1], s * local[0] + c * local[1])
    }

    /// The object's extent at `pose` (m): `[min x, max x, min y, max y]`.
    pub fn bounds(&self, pose: &Pose) -> [f64; 4] {
        if let Shape::Circle { radius_m } = self.shape {
            let p = pose.position_m;
            return [
                p[0] - radius_m,
                p[0] + radius_m,
                p[1] - radius_m,
                p[1] + radius_m,
            ];
        }
        let mut b = [
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::INFINITY,
            f64::NEG_INFINITY,
        ];
        if let Obstacle::Polygon { vertices_m } = self.obstacle(pose) {
            for v in vertices_m {
                b = [
                    b[0].min(v[0]),
                    b[1].max(v[0]),
                    b[2].min(v[1]),
                    b[3].max(v[1]),
                ];
            }
        }
        b
    }
}

/// The outward normal of a convex counter-clockwise polygon at the boundary
/// point nearest to `p`: from the nearest point when `p` is outside, the
/// nearest edge's normal when inside.
fn polygon_normal(vertices: &[[f64; 2]], p: [f64; 2]) -> [f64; 2] {
    let n = vertices.len();
    // (distance, direction) of the nearest boundary point; (depth, normal)
    // of the shallowest edge for a point inside
    let mut nearest: Option<(f64, [f64; 2])> = None;
    let mut shallowest: Option<(f64, [f64; 2])> = None;
    let mut inside = true;
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
        let e = [b[0] - a[0], b[1] - a[1]];
        let len2 = e[0] * e[0] + e[1] * e[1];
        let len = len2.sqrt();
        let out = [e[1] / len, -e[0] / len];
        let side = (p[0] - a[0]) * out[0] + (p[1] - a[1]) * out[1];
        inside &= side <= 0.0;
        if shallowest.is_none_or(|(d, _)| -side < d) {
            shallowest = Some((-side, out));
        }
        let t = (((p[0] - a[0]) * e[0] + (p[1] - a[1]) * e[1]) / len2).clamp(0.0, 1.0);
        let dq = [p[0] - a[0] - t * e[0], p[1] - a[1] - t * e[1]];
        let dist = dq[0].hypot(dq[1]);
        if nearest.is_none_or(|(d, _)| dist < d) {
            let dir = if dist > 1e-15 {
                [dq[0] / dist, dq[1] / dist]
            } else {
                out
            };
            nearest = Some((dist, dir));
        }
    }
    let pick = if inside { shallowest } else { nearest };
    pick.map_or([0.0, 1.0], |(_, v)| v)
}

/// The squared radius of gyration of a uniform polygon (counter-clockwise)
/// about the origin (m²): `∫ r² dA / A`.
fn polygon_gyration_m2(vertices: &[[f64; 2]]) -> f64 {
    let n = vertices.len();
    let (mut area2, mut j12) = (0.0, 0.0);
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
        let cr = a[0] * b[1] - b[0] * a[1];
        area2 += cr;
        j12 += cr
            * (a[0] * a[0] + a[0] * b[0] + b[0] * b[0] + a[1] * a[1] + a[1] * b[1] + b[1] * b[1]);
    }
    // polar moment ∫ r² dA = Σ cr (…)/12, area = Σ cr / 2
    (j12 / 12.0) / (0.5 * area2)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polygons_are_valid_obstacles_of_the_right_size() {
        let pose = Pose {
            position_m: [0.01, -0.1],
            angle_rad: 0.3,
        };
        let shapes = [
            Shape::Ellipse {
                semi_axes_m: [0.03, 0.02],
            },
            Shape::Rectangle {
                size_m: [0.04, 0.02],
            },
            Shape::RoundedPolygon {
                vertices_m: vec![[-0.02, -0.01], [0.02, -0.01], [0.0, 0.02]],
                corner_radius_m: 0.005,
            },
        ];
        for shape in shapes {
            let o = GraspObject {
                name: "x".into(),
                shape,
                mass_kg: 0.1,
                mu: 0.5,
            };
            o.validate("object").unwrap();
            let obs = o.obstacle(&pose);
            obs.validate("o").unwrap();
            // the centre is inside, a point far away outside
            assert!(obs.signed_distance(pose.position_m.into()).distance_m < 0.0);
            assert!(obs.signed_distance([1.0, 1.0].into()).distance_m > 0.9);
        }
        // a rounded square: the distance from its centre along an axis is half-side + r
        let sq = GraspObject {
            name: "sq".into(),
            shape: Shape::RoundedPolygon {
                vertices_m: vec![[-0.01, -0.01], [0.01, -0.01], [0.01, 0.01], [-0.01, 0.01]],
                corner_radius_m: 0.004,
            },
            mass_kg: 0.1,
            mu: 0.5,
        };
        let obs = sq.obstacle(&Pose {
            position_m: [0.0, 0.0],
            angle_rad: 0.0,
        });
        assert!((obs.signed_distance([0.05, 0.0].into()).distance_m - 0.036).abs() < 1e-12);
        let b = sq.bounds(&Pose {
            position_m: [0.0, 0.0],
            angle_rad: 0.0,
        });
        assert!((b[1] - 0.014).abs() < 1e-12 && (b[2] + 0.014).abs() < 1e-12);
    }

    #[test]
    fn surface_normals_are_the_outlines() {
        let pose = Pose {
            position_m: [0.01, -0.08],
            angle_rad: 0.4,
        };
        let (s, c) = pose.angle_rad.sin_cos();
        let world = |p: [f64; 2]| {
            Vector2::new(
                pose.position_m[0] + c * p[0] - s * p[1],
                pose.position_m[1] + s * p[0] + c * p[1],
            )
        };
        let turn = |n: [f64; 2]| [c * n[0] - s * n[1], s * n[0] + c * n[1]];
        let close = |a: Vector2<f64>, b: [f64; 2]| (a.x - b[0]).hypot(a.y - b[1]) < 1e-9;
        let obj = |shape| GraspObject {
            name: "x".into(),
            shape,
            mass_kg: 0.1,
            mu: 0.5,
        };
        // an ellipse: at (a cos t, b sin t) the normal is ∝ (cos t / a, sin t / b),
        // also from a point 1 mm off the curve along it
        let (a, b) = (0.03, 0.02);
        let e = obj(Shape::Ellipse {
            semi_axes_m: [a, b],
        });
        for t in [0.0, 0.3, 1.2, 2.5, 4.0] {
            let (st, ct) = f64::sin_cos(t);
            let l = (ct / a).hypot(st / b);
            let n = [ct / a / l, st / b / l];
            for off in [0.0, 0.001, -0.001] {
                let p = [a * ct + off * n[0], b * st + off * n[1]];
                assert!(
                    close(e.surface_normal(&pose, world(p)), turn(n)),
                    "t {t} off {off}"
                );
            }
        }
        // a circle: radial
        let ci = obj(Shape::Circle { radius_m: 0.02 });
        assert!(close(
            ci.surface_normal(&pose, world([0.0, 0.03])),
            turn([0.0, 1.0])
        ));
        // a rectangle: the face normal inside and outside, radial off a corner
        let r = obj(Shape::Rectangle {
            size_m: [0.04, 0.02],
        });
        assert!(close(
            r.surface_normal(&pose, world([0.019, 0.003])),
            turn([1.0, 0.0])
        ));
        assert!(close(
            r.surface_normal(&pose, world([-0.01, -0.0105])),
            turn([0.0, -1.0])
        ));
        let k = std::f64::consts::FRAC_1_SQRT_2;
        assert!(close(
            r.surface_normal(&pose, world([0.021, 0.011])),
            turn([k, k])
        ));
        // a rounded square: the faces are flat, the corners arcs about the core's corners
        let sq = obj(Shape::RoundedPolygon {
            vertices_m: vec![
                [-0.0245, -0.0245],
                [0.0245, -0.0245],
                [0.0245, 0.0245],
                [-0.0245, 0.0245],
            ],
            corner_radius_m: 0.008,
        });
        for y in [-0.024, 0.0, 0.02] {
            assert!(close(
                sq.surface_normal(&pose, world([0.032, y])),
                turn([1.0, 0.0])
            ));
        }
        let (sa, ca) = f64::sin_cos(0.7);
        let corner = [0.0245 + 0.008 * ca, 0.0245 + 0.008 * sa];
        assert!(close(
            sq.surface_normal(&pose, world(corner)),
            turn([ca, sa])
        ));
    }

    #[test]
    fn moments_of_inertia_match_the_closed_forms() {
        let obj = |shape| GraspObject {
            name: "x".into(),
            shape,
            mass_kg: 0.2,
            mu: 0.5,
        };
        // the polygon formula on a rectangle: m (w² + h²)/12
        let (w, h) = (0.04, 0.01);
        let rect = [
            [-w / 2.0, -h / 2.0],
            [w / 2.0, -h / 2.0],
            [w / 2.0, h / 2.0],
            [-w / 2.0, h / 2.0],
        ];
        assert!((0.2 * polygon_gyration_m2(&rect) - 0.2 * (w * w + h * h) / 12.0).abs() < 1e-15);
        // a rounded polygon with a tiny radius tends to its core
        let tiny = obj(Shape::RoundedPolygon {
            vertices_m: rect.to_vec(),
            corner_radius_m: 1e-7,
        });
        let i = tiny.moment_of_inertia_kg_m2();
        assert!(
            (i / (0.2 * (w * w + h * h) / 12.0) - 1.0).abs() < 1e-4,
            "{i}"
        );
        // a rounded square of core side a, radius r: a disc's polygon limit when a → 0
        let r = 0.01;
        let round = obj(Shape::RoundedPolygon {
            vertices_m: vec![[-1e-7, -1e-7], [1e-7, -1e-7], [1e-7, 1e-7], [-1e-7, 1e-7]],
            corner_radius_m: r,
        });
        // the 32-gon inscribed in the circle: within 1 % of m r²/2
        let i = round.moment_of_inertia_kg_m2();
        assert!((i / (0.5 * 0.2 * r * r) - 1.0).abs() < 0.01, "{i}");
        assert_eq!(
            obj(Shape::Circle { radius_m: r }).moment_of_inertia_kg_m2(),
            0.5 * 0.2 * r * r
        );
    }

    #[test]
    fn bad_objects_name_the_field() {
        let mut o = GraspObject {
            name: "x".into(),
            shape: Shape::Circle { radius_m: 0.01 },
            mass_kg: 0.0,
            mu: 0.5,
        };
        assert_eq!(
            o.validate("object").unwrap_err().field(),
            Some("object.mass_kg")
        );
        o.mass_kg = 0.1;
        o.shape = Shape::Rectangle {
            size_m: [0.01, -1.0],
        };
        assert_eq!(
            o.validate("object").unwrap_err().field(),
            Some("object.shape.size_m[1]")
        );
        o.shape = Shape::RoundedPolygon {
            vertices_m: vec![[0.0, 0.0], [0.0, 0.01], [0.01, 0.0]],
            corner_radius_m: 0.001,
        };
        assert!(
            o.validate("object")
                .unwrap_err()
                .field()
                .is_some_and(|f| f.starts_with("object.shape.vertices_m"))
        );
    }
}
