//! # softrod
//!
//! Shape and distributed-force estimation for slender pneumatic soft robots,
//! modelled with ANCF cable elements — an open implementation of Huang, Yuan,
//! Yang and Gu, "Precise Control of Soft Robots Amidst Uncertain Environmental
//! Contacts and Forces", IEEE T-RO 2024. Equation numbers `(n)` in the docs
//! are the paper's.
//!
//! Modules, one concept each:
//! - [`element`]: the cable element (14)–(16), energy, gradient, tangent.
//! - [`assembly`]: a multi-section robot, loads (22), actuation (18).
//! - [`loads`]: the loads of scenes and code (one type, [`loads::Load`]), dead
//!   and configuration-dependent, and the actuation.
//! - [`contact`]: rigid obstacles and frictionless contact in the static model.
//! - [`statics`]: Newton's method on the equilibrium (17), and its warm
//!   tracker for equilibria at nearby loads.
//! - [`structure`]: rods, rigid bodies and joints; the map `q = φ(u)` from free
//!   to all coordinates.
//! - [`sensitivity`]: `∂q/∂F` (28), `∂q/∂P` (43) and output gradients by
//!   adjoint solves.
//! - [`site`]: points of any model (a rod at an arc coordinate, a rigid body) as rows over `q`.
//! - [`observe`]: marker observations and the observation operator `A` (25).
//! - [`estimate`]: shape and load estimation (25)–(30), backends `newton` and `sqp`.
//! - [`scene`]: JSON scene files; [`params`]: the values the paper leaves open.
//! - [`shape`]: typed results (nalgebra): positions, angles, tip pose, clamp reaction, the estimated load and its covariance.
//! - [`outcome`]: how a solve ended: the status enums and the reports errors carry.
//! - [`refine`]: `"elements": "auto"`, the smallest mesh meeting a tolerance.
//! - [`linsolve`]: linear solvers for the tangent (faer sparse); [`quadrature`]: Gauss rules.
//! - [`control`]: inverse kinematics, the parameter updater (31), the closed loop.
//! - [`plant`]: the robot a controller acts on; a simulated plant that is not the model.
//! - [`grasp`]: the two-finger gripper, objects with friction, the adaptive grasp (45)–(52).
//! - [`touch`]: where an obstacle touches the robot, from the markers alone, and
//!   steering around it (Sec. V).
//! - [`parallel`]: the soft parallel robot (Figs. 7–8) and its payload estimate (32)–(35).
//! - [`error`]: the one error type; every refusal names the field it is about.
//! - `report` (feature `report`): `softrod report`, the speed–accuracy chart and the stability map.
//!
//! Features: the library needs only its numerical dependencies (nalgebra,
//! faer, clarabel, serde). `report` adds the charts, progress bars and the
//! report sweeps (plotters, indicatif, rayon); `cli` adds the `softrod`
//! command line (clap) on top of `report`.
//!
//! All quantities are SI (m, N, Pa, rad).
//!
//! Typed inputs and results are [nalgebra] types. The crate re-exports the
//! nalgebra it is built with as `softrod::nalgebra`, so a user names the
//! same types without pinning a matching version of their own:
//! ```
//! use softrod::element::SpatialCable;
//! use softrod::nalgebra::{Point2, Vector3};
//! use softrod::{scene::Scene, statics::StaticSolver};
//! // a planar result: the tip of the built-in robot as a point (m)
//! let scene = Scene::two_section();
//! let robot = scene.robot()?;
//! let eq = StaticSolver::default().solve(&robot, &scene.loads()?, None)?;
//! let tip: Point2<f64> = eq.shape(&robot)?.tip_pose()?.position_m;
//! assert!(tip.coords.norm() < 0.24);
//! // a spatial one: the curvature vector (1/m) of a straight element
//! let element = SpatialCable::new(0.1, 300.0, 0.025)?;
//! let qe = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.1, 0.0, 0.0, 1.0, 0.0, 0.0];
//! let (axial_strain, curvature_per_m): (f64, Vector3<f64>) = element.strains(&qe, 0.5);
//! assert!(axial_strain.abs() < 1e-15 && curvature_per_m == Vector3::zeros());
//! # Ok::<(), softrod::Error>(())
//! ```
//!
//! # Example
//! ```
//! use softrod::{scene::Scene, statics::StaticSolver};
//! let scene = Scene::two_section();
//! let robot = scene.robot()?;
//! let eq = StaticSolver::default().solve(&robot, &scene.loads()?, None)?;
//! assert!(eq.report.status.is_converged());
//! # Ok::<(), softrod::Error>(())
//! ```
#![warn(missing_docs)]
// docs.rs (Cargo.toml: `--cfg docsrs`) marks what a feature gates, e.g. `report`
#![cfg_attr(docsrs, feature(doc_cfg))]
#![cfg_attr(test, allow(clippy::unwrap_used, clippy::expect_used, clippy::panic))]

pub mod assembly;
mod cone;
pub mod contact;
pub mod control;
pub mod element;
pub mod error;
pub mod estimate;
pub mod grasp;
pub mod linsolve;
pub mod loads;
pub(crate) mod numeric;
pub mod observe;
pub mod outcome;
pub mod parallel;
pub mod params;
pub mod plant;
pub mod quadrature;
pub mod refine;
#[cfg(feature = "report")]
pub mod report;
pub(crate) mod rng;
pub mod scene;
pub mod sensitivity;
pub mod shape;
pub mod site;
pub mod statics;
pub mod structure;
pub mod touch;

pub use error::{Error, Result};
/// The linear algebra crate of the typed inputs and results (points, poses,
/// resultants, covariances), re-exported: `softrod::nalgebra::Vector3` is the
/// type the library's functions take and return.
pub use nalgebra;
