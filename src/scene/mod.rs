//! Scene files (JSON): a robot, its base, gravity, known loads, pressures,
//! markers and solver settings.
//!
//! Unknown fields and missing required ones are errors that name the field.
//! Format: `README.md`; the paper's two-section robot: `examples/two_section.json`.

pub(crate) mod json;
mod ladder;
mod load;
pub mod markers;
pub mod parallel;
pub mod ranges;
mod robot;
mod settings;

use serde::{Deserialize, Serialize};

use crate::assembly::{Base, Chamber, Robot, RobotSpec, Section};
use crate::element::{DEFAULT_GAUSS_POINTS, Element, NodeKinematics, PlanarCable, SpatialCable};
use crate::error::{Error, Result, check_at_most, check_index, check_len, check_positive};
use crate::estimate::{EstimatorSettings, LoadModel};
use crate::loads::{Load, Loads};
use crate::params;

pub use ladder::Ladder;
pub use robot::{SceneElement, SceneRobot};
pub use settings::{DEFAULT_MAX_REFINED_ELEMENTS, RefinementTarget, SolverSettings, UnknownLoad};

/// The largest scene file [`Scene::from_file`] reads (64 MiB).
pub const MAX_SCENE_BYTES: usize = 64 << 20;

/// The element family a scene uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ElementKind {
    /// Planar ANCF cable (2-D, 4 coordinates per node).
    #[default]
    PlanarCable,
    /// Spatial ANCF cable (3-D, 6 coordinates per node: `[r, r']`); the
    /// scene's vectors (base position and direction, gravity, forces,
    /// moments, chamber gains) have three components.
    SpatialCable,
    /// Full 3-D ANCF element (12 coordinates per node: `[r, r_X, r_Y,
    /// r_Z]`, a section frame and torsion); 3-D vectors as the spatial
    /// cable's. Its torsional stiffness is `GJ = EI/1.5` (an isotropic,
    /// incompressible elastomer section, ν = 0.5, `J = 2I`), its bending
    /// stiffness `EI` about both section axes.
    Ancf3d,
}

impl ElementKind {
    /// The number of space dimensions of the element (2 or 3).
    ///
    /// # Example
    /// ```
    /// use softrod::scene::ElementKind;
    /// assert_eq!(ElementKind::SpatialCable.dim(), 3);
    /// ```
    pub fn dim(self) -> usize {
        match self {
            ElementKind::PlanarCable => PlanarCable::DIM,
            ElementKind::SpatialCable => SpatialCable::DIM,
            ElementKind::Ancf3d => crate::element::Ancf3d::DIM,
        }
    }

    /// The name in scene files (`planar_cable`, `spatial_cable`).
    pub fn name(self) -> &'static str {
        match self {
            ElementKind::PlanarCable => "planar_cable",
            ElementKind::SpatialCable => "spatial_cable",
            ElementKind::Ancf3d => "ancf3d",
        }
    }

    /// The default base of a scene with this element: at the origin,
    /// along +x.
    pub fn default_base(self) -> Base {
        match self {
            ElementKind::PlanarCable => Base::default(),
            ElementKind::SpatialCable | ElementKind::Ancf3d => RobotSpec::spatial(Vec::new()).base,
        }
    }

    /// The default gravity of a scene with this element (m/s², [`ElementKind::dim`]
    /// components): 9.81 down the y axis in 2-D, down the z axis in 3-D.
    ///
    /// # Example
    /// ```
    /// use softrod::scene::ElementKind;
    /// assert_eq!(ElementKind::PlanarCable.default_gravity(), nalgebra::dvector![0.0, -9.81]);
    /// assert_eq!(ElementKind::Ancf3d.default_gravity(), nalgebra::dvector![0.0, 0.0, -9.81]);
    /// ```
    pub fn default_gravity(self) -> nalgebra::DVector<f64> {
        match self {
            ElementKind::PlanarCable => nalgebra::DVector::from_vec(gravity()),
            ElementKind::SpatialCable | ElementKind::Ancf3d => {
                nalgebra::dvector![0.0, 0.0, params::GRAVITY_M_PER_S2[1]]
            }
        }
    }
}

/// The robot of a scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotDef {
    /// Element family (default `planar_cable`).
    #[serde(default)]
    pub element: ElementKind,
    /// Sections from base to tip.
    pub sections: Vec<Section>,
    /// Gauss points of the axial integral (default 5).
    #[serde(default = "gauss")]
    pub axial_gauss_points: usize,
    /// Gauss points of the bending integral (default 5; 3 matches exudyn).
    #[serde(default = "gauss")]
    pub bending_gauss_points: usize,
}

fn gauss() -> usize {
    DEFAULT_GAUSS_POINTS
}
fn gravity() -> Vec<f64> {
    params::GRAVITY_M_PER_S2.as_slice().to_vec()
}

/// A marker: a tracked point of the backbone at a node or at an arc coordinate.
///
/// # Example
/// ```
/// let m: softrod::scene::Marker = serde_json::from_str(r#"{"s_m": 0.12}"#).unwrap();
/// assert_eq!(m.s_m, Some(0.12));
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Marker {
    /// Node index, or
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub node: Option<usize>,
    /// undeformed arc coordinate (m): exactly one of the two.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub s_m: Option<f64>,
    /// Whether the marker also observes the tangent `r'` (default false).
    #[serde(default)]
    pub tangent: bool,
}

/// A scene.
///
/// # Example
/// ```
/// let scene = softrod::scene::Scene::two_section();
/// let robot = scene.robot().unwrap();
/// assert_eq!(robot.n_elements(), 20);
/// let json = serde_json::to_string(&scene).unwrap();
/// assert_eq!(softrod::scene::Scene::from_json(&json).unwrap(), scene);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "SceneFile")]
pub struct Scene {
    /// Name.
    pub name: String,
    /// Free text.
    pub description: String,
    /// The robot.
    pub robot: RobotDef,
    /// Base pose (default at the origin, along +x).
    pub base: Base,
    /// Gravity (m/s², default `[0, -9.81]` in 2-D, `[0, 0, -9.81]` in 3-D).
    pub gravity_m_per_s2: Vec<f64>,
    /// Known loads.
    pub loads: Vec<Load>,
    /// Chamber pressures (Pa), one per chamber in section order; default all zero.
    pub pressures_pa: Vec<f64>,
    /// Markers.
    pub markers: Vec<Marker>,
    /// Solver settings.
    pub solver: SolverSettings,
    /// The tolerance that chooses the element counts of `"elements": "auto"`
    /// sections (required with them, refused without them).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refinement: Option<RefinementTarget>,
    /// Where the unknown load of an estimation acts (default: the estimator's
    /// `load_model`, itself distributed by default).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub unknown_load: Option<UnknownLoad>,
}

/// A scene as written in a file: the base and gravity are optional, their
/// defaults depend on the element (see [`ElementKind::default_base`]).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFile {
    #[serde(default)]
    name: String,
    #[serde(default)]
    description: String,
    robot: RobotDef,
    #[serde(default, deserialize_with = "present")]
    base: Option<Base>,
    #[serde(default, deserialize_with = "present")]
    gravity_m_per_s2: Option<Vec<f64>>,
    #[serde(default)]
    loads: Vec<Load>,
    #[serde(default)]
    pressures_pa: Vec<f64>,
    #[serde(default)]
    markers: Vec<Marker>,
    #[serde(default)]
    solver: SolverSettings,
    #[serde(default)]
    refinement: Option<RefinementTarget>,
    #[serde(default)]
    unknown_load: Option<UnknownLoad>,
}

/// An optional field that, when present, is not `null`.
fn present<'de, D: serde::Deserializer<'de>, T: Deserialize<'de>>(
    d: D,
) -> std::result::Result<Option<T>, D::Error> {
    T::deserialize(d).map(Some)
}

impl From<SceneFile> for Scene {
    fn from(f: SceneFile) -> Scene {
        let kind = f.robot.element;
        Scene {
            name: f.name,
            description: f.description,
            base: f.base.unwrap_or_else(|| kind.default_base()),
            gravity_m_per_s2: f
                .gravity_m_per_s2
                .unwrap_or_else(|| kind.default_gravity().data.into()),
            robot: f.robot,
            loads: f.loads,
            pressures_pa: f.pressures_pa,
            markers: f.markers,
            solver: f.solver,
            refinement: f.refinement,
            unknown_load: f.unknown_load,
        }
    }
}

impl Scene {
    /// [`Scene::gravity_m_per_s2`] as a `D`-vector (m/s²).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `gravity_m_per_s2` if it has
    /// another number of components.
    ///
    /// # Example
    /// ```
    /// let scene = softrod::scene::Scene::two_section();
    /// assert_eq!(scene.gravity::<2>()?, nalgebra::Vector2::new(0.0, -9.81));
    /// assert!(scene.gravity::<3>().is_err());
    /// assert_eq!(scene.pressures().len(), scene.pressures_pa.len());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn gravity<const D: usize>(&self) -> Result<nalgebra::SVector<f64, D>> {
        crate::numeric::fixed("gravity_m_per_s2", &self.gravity_m_per_s2)
    }

    /// [`Scene::pressures_pa`] as a vector (Pa, one per chamber).
    ///
    /// # Example
    /// See [`Scene::gravity`].
    pub fn pressures(&self) -> nalgebra::DVector<f64> {
        nalgebra::DVector::from_column_slice(&self.pressures_pa)
    }

    /// Parses and validates a scene.
    ///
    /// # Errors
    /// [`Error::Scene`] for malformed JSON, unknown or missing fields, wrong
    /// types (the message starts with the path of the field at fault, e.g.
    /// `robot.sections[0].elements: invalid value ...`, and gives the line and
    /// column); the errors of [`Scene::validate`].
    pub fn from_json(text: &str) -> Result<Scene> {
        let scene: Scene = json::parse(text).map_err(|e| Error::Scene {
            message: e.located(),
        })?;
        scene.validate()?;
        Ok(scene)
    }

    /// Reads a scene file.
    ///
    /// # Errors
    /// [`Error::Scene`] if the file cannot be read; [`Error::TooLarge`] for
    /// a file above [`MAX_SCENE_BYTES`] (refused before reading it); as
    /// [`Scene::from_json`].
    pub fn from_file(path: &std::path::Path) -> Result<Scene> {
        let cannot_read = |e: std::io::Error| Error::Scene {
            message: format!("cannot read {}: {e}", path.display()),
        };
        let size = std::fs::metadata(path).map_err(cannot_read)?.len();
        check_at_most(
            &format!("size of {} (bytes)", path.display()),
            usize::try_from(size).unwrap_or(usize::MAX),
            MAX_SCENE_BYTES,
        )?;
        let text = std::fs::read_to_string(path).map_err(cannot_read)?;
        Scene::from_json(&text).map_err(|e| match e {
            Error::Scene { message } => Error::Scene {
                message: format!("{}: {message}", path.display()),
            },
            other => other,
        })
    }

    /// Checks everything that can be checked without solving: the robot, the
    /// loads, the pressures (count and bounds), the markers, the settings.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`], [`Error::DimensionMismatch`],
    /// [`Error::TooLarge`] or [`Error::IndexOutOfRange`] naming the field
    /// with its path in the scene (`loads[2].force_n`, `markers[1].node`,
    /// `solver.static.max_iterations`, ...).
    ///
    /// A scene with `"elements": "auto"` sections is checked on the smallest
    /// mesh its refinement may try, and the combinations that depend on the
    /// mesh are refused: a missing `refinement` (or one without an auto
    /// section), a tolerance that is not finite and positive, a
    /// `max_elements` below the smallest mesh, markers, moments or a
    /// concentrated `load_model` given by node index.
    ///
    /// A spatial scene's vectors have three components (a two-component
    /// force, gravity or base position is refused, naming the field, and so
    /// is a three-component one in a planar scene); a spatial scene's
    /// element counts are fixed (`"auto"` is planar only).
    pub fn validate(&self) -> Result<()> {
        ranges::check(self)?;
        match self.robot.element {
            ElementKind::PlanarCable => self.validate_as::<PlanarCable>(),
            ElementKind::SpatialCable | ElementKind::Ancf3d => {
                if let Some(i) = self.robot.sections.iter().position(|s| s.auto_elements) {
                    return Err(Error::invalid(
                        format!("robot.sections[{i}].elements"),
                        "\"auto\"",
                        "the refinement of element counts is planar only: give a count",
                    ));
                }
                if self.robot.element == ElementKind::Ancf3d {
                    self.validate_as::<crate::element::Ancf3d>()
                } else {
                    self.validate_as::<SpatialCable>()
                }
            }
        }
    }

    /// [`Scene::validate`] for a scene of element `E`.
    fn validate_as<E: SceneElement>(&self) -> Result<()> {
        let auto = self.has_auto_elements();
        let smallest;
        let mesh = if auto {
            smallest = self.smallest_refined_mesh()?;
            &smallest
        } else {
            if let Some(t) = &self.refinement {
                return Err(Error::invalid(
                    "refinement",
                    t.tolerance(),
                    "no section has \"elements\": \"auto\": remove `refinement` or set a \
                     section's elements to \"auto\"",
                ));
            }
            self
        };
        let robot = mesh.robot_as::<E>()?;
        for (i, load) in self.loads.iter().enumerate() {
            if let (true, Load::NodeMoment { node, .. }) = (auto, load) {
                return Err(Error::invalid(
                    format!("loads[{i}].node"),
                    node,
                    "a node index depends on the mesh, which \"elements\": \"auto\" leaves \
                     to the refinement: use a tip_moment, or fixed element counts",
                ));
            }
            load::validate_scene_load(&robot, load, &self.gravity_m_per_s2)
                .map_err(|e| e.with_prefix(&format!("loads[{i}].")))?;
        }
        self.check_pressure_bounds()?;
        robot.validate_loads(&mesh.loads()?)?;
        self.solver.statics.validate("solver.static")?;
        self.solver
            .estimator
            .validate()
            // (the estimator names its fields `estimator.…`)
            .map_err(|e| e.with_prefix("solver."))?;
        self.check_alpha_scale(&robot)?;
        let total = robot.length();
        let mut seen: Vec<f64> = Vec::new();
        for (i, m) in self.markers.iter().enumerate() {
            let s = match (m.node, m.s_m) {
                (Some(n), None) if auto => {
                    return Err(Error::invalid(
                        format!("markers[{i}].node"),
                        n,
                        "a node index depends on the mesh, which \"elements\": \"auto\" \
                         leaves to the refinement: give the marker's s_m",
                    ));
                }
                (Some(n), None) => {
                    check_index(&format!("markers[{i}].node"), n, robot.n_nodes())?;
                    robot.node_arc().get(n).copied().unwrap_or(f64::NAN)
                }
                (None, Some(s)) => {
                    robot.locate(&format!("markers[{i}].s_m"), s)?;
                    s
                }
                _ => {
                    return Err(Error::invalid(
                        format!("markers[{i}]"),
                        "",
                        "give exactly one of `node` and `s_m`",
                    ));
                }
            };
            if seen.iter().any(|t| (t - s).abs() <= 1e-9 * total) {
                return Err(Error::invalid(
                    format!("markers[{i}]"),
                    s,
                    "duplicates another marker's position",
                ));
            }
            seen.push(s);
        }
        ranges::check_estimate_work("markers", self.markers.len(), robot.n_elements())?;
        if auto {
            Ok(()) // checked on the way to the smallest mesh
        } else {
            self.check_unknown_load(&robot, false)
        }
    }

    /// Refuses an `alpha` so large that it can only overflow: beyond
    /// `MAX_LOAD_SCALE` times the ratio of the markers' misfit at the
    /// robot's length, `L² / σ²`, to the penalty of a load at the robot's
    /// scale, `(EI / L³)² L` (at that ratio the markers no longer count).
    fn check_alpha_scale<E: Element>(&self, robot: &Robot<E>) -> Result<()> {
        let Some(alpha) = self.solver.estimator.alpha else {
            return Ok(());
        };
        let l = robot.length();
        let ei = robot
            .rod()
            .sections()
            .iter()
            .fold(0.0f64, |m, s| m.max(s.ei_nm2));
        let sigma = self.solver.estimator.noise_sigma_m;
        let w = ei / (l * l * l);
        let max = load::MAX_LOAD_SCALE * (l * l / (sigma * sigma)) / (w * w * l);
        // (a stiffness or length that itself overflows the scale is not
        // alpha's fault: no bound then)
        if max > 0.0 && max.is_finite() && alpha > max {
            return Err(Error::invalid(
                "solver.estimator.alpha",
                alpha,
                format!(
                    "must be at most {max:.3e}: beyond that the penalty outweighs the markers \
                     by more than {:e} and the estimate can only overflow",
                    load::MAX_LOAD_SCALE
                ),
            ));
        }
        Ok(())
    }

    /// Each given pressure within its chamber's bounds; the error names the
    /// pressure and the two bounds by their paths in the file (which of them
    /// is wrong only the user knows).
    fn check_pressure_bounds(&self) -> Result<()> {
        let chambers = self
            .robot
            .sections
            .iter()
            .enumerate()
            .flat_map(|(i, s)| s.chambers.iter().enumerate().map(move |(c, ch)| (i, c, ch)));
        for (k, (p, (i, c, ch))) in self.pressures_pa.iter().zip(chambers).enumerate() {
            if p.is_finite() && (*p < ch.pressure_min_pa || *p > ch.pressure_max_pa) {
                let b = format!("robot.sections[{i}].chambers[{c}]");
                return Err(Error::invalid(
                    format!("pressures_pa[{k}]"),
                    p,
                    format!(
                        "must lie in [{}, {}] Pa, the bounds `{b}.pressure_min_pa` and `{b}.pressure_max_pa`",
                        ch.pressure_min_pa, ch.pressure_max_pa
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Whether any section asks for `"elements": "auto"`.
    pub fn has_auto_elements(&self) -> bool {
        self.robot.sections.iter().any(|s| s.auto_elements)
    }

    /// The scene with the given element count for every section (auto ones
    /// included): `auto_elements` cleared and `refinement` dropped, so the
    /// result is a plain scene that builds its robot. This is how
    /// [`crate::refine`] resolves an `"auto"` scene.
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] if `counts` does not have one entry per
    /// section. (The counts are checked when the robot is built.)
    ///
    /// # Example
    /// ```
    /// let scene = softrod::scene::Scene::two_section().with_elements(&[3, 5])?;
    /// assert_eq!(scene.robot()?.n_elements(), 8);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn with_elements(&self, counts: &[usize]) -> Result<Scene> {
        check_len("elements", self.robot.sections.len(), counts.len())?;
        let mut scene = self.clone();
        for (s, &n) in scene.robot.sections.iter_mut().zip(counts) {
            s.elements = n;
            s.auto_elements = false;
        }
        scene.refinement = None;
        Ok(scene)
    }

    /// The estimator settings of the scene: `solver.estimator`, with the load
    /// model that `unknown_load` states (a point load becomes
    /// [`LoadModel::Concentrated`] at the node at its arc coordinate).
    ///
    /// # Errors
    /// As [`Scene::robot`] when the scene states a point load (the node is
    /// looked up on the robot); [`Error::InvalidParameter`] naming
    /// `unknown_load.s_m` if no node lies there.
    ///
    /// # Example
    /// ```
    /// use softrod::{estimate::LoadModel, scene::{Scene, UnknownLoad}};
    /// let mut scene = Scene::two_section();
    /// scene.unknown_load = Some(UnknownLoad::Point { s_m: 0.18 });
    /// assert_eq!(scene.estimator_settings()?.load_model, LoadModel::Concentrated { node: 15 });
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn estimator_settings(&self) -> Result<EstimatorSettings> {
        let mut settings = self.solver.estimator.clone();
        match self.unknown_load {
            None => {}
            Some(UnknownLoad::Distributed) => settings.load_model = LoadModel::Distributed,
            Some(UnknownLoad::Point { s_m }) => {
                let node = match self.build()? {
                    SceneRobot::Planar(r) => node_at(&r, "unknown_load.s_m", s_m)?,
                    SceneRobot::Spatial(r) => node_at(&r, "unknown_load.s_m", s_m)?,
                    SceneRobot::Full(r) => node_at(&r, "unknown_load.s_m", s_m)?,
                };
                settings.load_model = LoadModel::Concentrated { node };
            }
        }
        Ok(settings)
    }

    /// The smallest mesh the refinement of an `"auto"` scene may try, after
    /// checking the refinement's fields.
    fn smallest_refined_mesh(&self) -> Result<Scene> {
        let Some(target) = self.refinement else {
            let i = self
                .robot
                .sections
                .iter()
                .position(|s| s.auto_elements)
                .unwrap_or(0);
            return Err(Error::invalid(
                "refinement",
                "none",
                format!(
                    "robot.sections[{i}].elements is \"auto\": give the tolerance it must meet, \
                     e.g. \"refinement\": {{\"quantity\": \"tip_position\", \"tolerance_m\": 1e-5}}"
                ),
            ));
        };
        check_positive(
            &format!("refinement.{}", target.tolerance_field()),
            target.tolerance(),
        )?;
        check_at_most(
            "refinement.max_elements",
            target.max_elements(),
            crate::assembly::MAX_ELEMENTS,
        )?;
        // the sections' own fields first, on one element per auto section
        let ones: Vec<usize> = self
            .robot
            .sections
            .iter()
            .map(|s| if s.auto_elements { 1 } else { s.elements })
            .collect();
        let robot = self.with_elements(&ones)?.robot()?;
        self.check_unknown_load(&robot, true)?;
        let ladder = Ladder::new(self)?;
        let smallest = ladder.total_elements(1);
        if smallest > target.max_elements() {
            return Err(Error::invalid(
                "refinement.max_elements",
                target.max_elements(),
                format!("must be at least {smallest}, the smallest mesh the refinement can try"),
            ));
        }
        self.with_elements(&ladder.elements(1))
    }

    /// Checks `unknown_load` against the robot (on a fixed mesh, a point
    /// load must fall on a node) and against the estimator's `load_model`.
    fn check_unknown_load<E: Element>(&self, robot: &Robot<E>, auto: bool) -> Result<()> {
        if let (true, LoadModel::Concentrated { node }) = (auto, self.solver.estimator.load_model) {
            return Err(Error::invalid(
                "solver.estimator.load_model.node",
                node,
                "a node index depends on the mesh, which \"elements\": \"auto\" leaves to the \
                 refinement: give \"unknown_load\": {\"acts_at\": \"point\", \"s_m\": ...}",
            ));
        }
        let Some(u) = self.unknown_load else {
            return Ok(());
        };
        if self.solver.estimator.load_model != LoadModel::default() {
            return Err(Error::invalid(
                "unknown_load",
                format!("{u:?}"),
                "solver.estimator.load_model is also given: state the load model in one place",
            ));
        }
        if let UnknownLoad::Point { s_m } = u {
            robot.locate("unknown_load.s_m", s_m)?;
            if s_m <= NODE_MATCH * robot.length() {
                return Err(Error::invalid(
                    "unknown_load.s_m",
                    s_m,
                    "the clamped base takes no load: must be > 0",
                ));
            }
            if !auto {
                node_at(robot, "unknown_load.s_m", s_m)?;
            }
        }
        Ok(())
    }

    /// The robot's spec.
    pub fn robot_spec(&self) -> RobotSpec {
        RobotSpec {
            sections: self.robot.sections.clone(),
            base: crate::assembly::Base {
                // (−π, π]: an angle is reduced before use (bit for bit the
                // same inside)
                angle_rad: ranges::reduce_angle(self.base.angle_rad),
                ..self.base.clone()
            },
            gravity_m_per_s2: self.gravity_m_per_s2.clone(),
            axial_gauss_points: self.robot.axial_gauss_points,
            bending_gauss_points: self.robot.bending_gauss_points,
        }
    }

    /// Builds the planar robot (for any element: [`Scene::build`]).
    ///
    /// # Errors
    /// As [`Robot::new`]; [`Error::InvalidParameter`] naming
    /// `robot.sections[i].elements` for a section whose count is `"auto"`
    /// (resolve the scene with [`crate::refine::auto_elements`] or
    /// [`Scene::with_elements`] first), or naming `robot.element` for a
    /// scene of another element.
    pub fn robot(&self) -> Result<Robot<PlanarCable>> {
        self.robot_as()
    }

    /// The scene's loads and pressures as [`Loads`] (pressures default to zero).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] or [`Error::DimensionMismatch`] naming
    /// `loads[i].…` for a load's values (sizes, finiteness, a non-positive
    /// tip mass, a negative extra weight: the robot-free part of
    /// [`Load::validate`]); [`Error::DimensionMismatch`] for a gravity
    /// vector of the wrong size; as [`Scene::robot`] for an `"auto"` section (a tip
    /// moment's node depends on the mesh).
    pub fn loads(&self) -> Result<Loads> {
        self.check_resolved()?;
        let d = self.robot.element.dim();
        let n_chambers: usize = self.robot.sections.iter().map(|s| s.chambers.len()).sum();
        let total: f64 = self.robot.sections.iter().map(|s| s.length_m).sum();
        let mut loads = Loads {
            pressures_pa: if self.pressures_pa.is_empty() {
                vec![0.0; n_chambers]
            } else {
                self.pressures_pa.clone()
            },
            ..Loads::default()
        };
        let n_nodes: usize = self
            .robot
            .sections
            .iter()
            .fold(1usize, |a, s| a.saturating_add(s.elements));
        // a moment has one component in 2-D, three in 3-D
        let moment_dim = if d == 2 { 1 } else { 3 };
        for (i, l) in self.loads.iter().enumerate() {
            l.check_values(d, moment_dim)
                .map_err(|e| e.with_prefix(&format!("loads[{i}].")))?;
            l.resolve_into(d, total, n_nodes, &self.gravity_m_per_s2, &mut loads)
                .map_err(|e| match e.field() {
                    // the scene's own gravity is a top-level field
                    Some("gravity_m_per_s2") if matches!(l, Load::TipMass { .. }) => e,
                    _ => e.with_prefix(&format!("loads[{i}].")),
                })?;
        }
        Ok(loads)
    }

    /// Refuses a scene with an `"auto"` section (one that is not resolved).
    fn check_resolved(&self) -> Result<()> {
        match self.robot.sections.iter().position(|s| s.auto_elements) {
            None => Ok(()),
            Some(i) => Err(Error::invalid(
                format!("robot.sections[{i}].elements"),
                "\"auto\"",
                "the count is chosen by refinement: resolve the scene with \
                 softrod::refine::auto_elements (or Scene::with_elements) first",
            )),
        }
    }

    /// The paper's two-section robot (two 120 mm sections, Sec. IV) with the values of
    /// [`crate::params`], horizontal, under its own weight and the default
    /// pressures; five markers. This is the built-in default scene and equals
    /// `examples/two_section.json`.
    pub fn two_section() -> Scene {
        let chamber = |sign: f64| Chamber {
            gain_nm_per_pa: vec![sign * params::ACTUATION_GAIN_NM_PER_PA],
            pressure_min_pa: params::PRESSURE_MIN_PA,
            pressure_max_pa: params::PRESSURE_MAX_PA,
        };
        let section = Section {
            length_m: params::SECTION_LENGTH_M,
            ea_n: params::EA_N,
            ei_nm2: params::EI_NM2,
            mass_per_length_kg_per_m: params::MASS_PER_LENGTH_KG_PER_M,
            elements: params::ELEMENTS_PER_SECTION,
            auto_elements: false,
            rest_curvature_per_m: 0.0,
            rest_curvature_profile: None,
            chambers: vec![chamber(1.0), chamber(-1.0)],
        };
        Scene {
            name: "two_section".into(),
            description: "The paper's two-section robot (Sec. IV): 2 x 120 mm, EI 0.025 N m^2, EA 300 N; open values from softrod::params.".into(),
            robot: RobotDef { element: ElementKind::PlanarCable, sections: vec![section.clone(), section], axial_gauss_points: 5, bending_gauss_points: 5 },
            base: Base::default(),
            gravity_m_per_s2: gravity(),
            loads: vec![],
            pressures_pa: params::DEFAULT_PRESSURES_PA.to_vec(),
            markers: [4, 8, 12, 16, 20].iter().map(|&n| Marker { node: Some(n), s_m: None, tangent: false }).collect(),
            solver: SolverSettings::default(),
            refinement: None,
            unknown_load: None,
        }
    }
}

/// A node matches an arc coordinate within this fraction of the robot's length.
pub(crate) const NODE_MATCH: f64 = 1e-9;

/// The node at arc coordinate `s` (within [`NODE_MATCH`] of the length).
fn node_at<E: Element>(robot: &Robot<E>, name: &str, s: f64) -> Result<usize> {
    robot.locate(name, s)?;
    let arc = robot.node_arc();
    let tol = NODE_MATCH * robot.length();
    let i = arc.partition_point(|&x| x < s - tol);
    match arc.get(i) {
        Some(&x) if (x - s).abs() <= tol => Ok(i),
        _ => {
            let near: Vec<String> = [i.checked_sub(1), Some(i)]
                .into_iter()
                .flatten()
                .filter_map(|j| arc.get(j).map(|x| format!("node {j} at {x} m")))
                .collect();
            Err(Error::invalid(
                name,
                s,
                format!(
                    "no node lies there (nearest: {}); a point load needs a node",
                    near.join(", ")
                ),
            ))
        }
    }
}

#[cfg(test)]
mod tests;
