//! Scene files (JSON): a robot, its base, gravity, known loads, pressures,
//! markers and solver settings.
//!
//! Unknown fields and missing required ones are errors that name the field.
//! See `README.md` for the format and `examples/two_section.json` for the
//! paper's two-section robot.

use serde::{Deserialize, Serialize};

use crate::assembly::{Base, Chamber, Robot, RobotSpec, Section};
use crate::element::{PlanarCable, DEFAULT_GAUSS_POINTS};
use crate::error::{
    check_all_finite, check_at_most, check_finite, check_index, check_len, check_positive, Error,
    Result,
};
use crate::estimate::EstimatorSettings;
use crate::loads::{LineLoad, Loads, NodeMoment, PointForce};
use crate::params;
use crate::statics::StaticSettings;

/// The largest scene file [`Scene::from_file`] reads (64 MiB).
pub const MAX_SCENE_BYTES: usize = 64 << 20;

/// The element family a scene uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ElementKind {
    /// Planar ANCF cable (2-D, 4 coordinates per node).
    #[default]
    PlanarCable,
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
    params::GRAVITY_M_PER_S2.to_vec()
}

/// A known load of a scene (dead, world axes, SI).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum SceneLoad {
    /// A distributed load with a profile (`uniform`, `linear`, `gaussian`).
    Distributed(LineLoad),
    /// A force at the tip (N).
    TipForce {
        /// Force (N).
        force_n: Vec<f64>,
    },
    /// A force at arc coordinate `s_m` (N).
    PointForce {
        /// Arc coordinate (m).
        s_m: f64,
        /// Force (N).
        force_n: Vec<f64>,
    },
    /// A moment at the tip node (N·m).
    TipMoment {
        /// Moment (N·m, counter-clockwise positive in 2-D).
        moment_nm: f64,
    },
    /// A moment at a node (N·m).
    NodeMoment {
        /// Node index (1 ..= number of elements).
        node: usize,
        /// Moment (N·m).
        moment_nm: f64,
    },
    /// An extra uniform weight (kg/m) under its own gravity vector.
    SelfWeight {
        /// Mass per length (kg/m).
        mass_per_length_kg_per_m: f64,
        /// Gravity (m/s²).
        gravity_m_per_s2: Vec<f64>,
    },
    /// A mass hanging at the tip (kg), under the scene's gravity.
    TipMass {
        /// Mass (kg).
        mass_kg: f64,
    },
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

/// Solver settings of a scene.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSettings {
    /// Static solver settings.
    #[serde(default, rename = "static")]
    pub statics: StaticSettings,
    /// Estimator settings (`"estimator": {"backend": "newton" | "sqp",
    /// "alpha": ..., "noise_sigma_m": ..., ...}`, every field optional; see
    /// [`EstimatorSettings`] for the fields and their defaults).
    #[serde(default)]
    pub estimator: EstimatorSettings,
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
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Name.
    #[serde(default)]
    pub name: String,
    /// Free text.
    #[serde(default)]
    pub description: String,
    /// The robot.
    pub robot: RobotDef,
    /// Base pose (default at the origin, along +x).
    #[serde(default)]
    pub base: Base,
    /// Gravity (m/s², default `[0, -9.81]`).
    #[serde(default = "gravity")]
    pub gravity_m_per_s2: Vec<f64>,
    /// Known loads.
    #[serde(default)]
    pub loads: Vec<SceneLoad>,
    /// Chamber pressures (Pa), one per chamber in section order; default all zero.
    #[serde(default)]
    pub pressures_pa: Vec<f64>,
    /// Markers.
    #[serde(default)]
    pub markers: Vec<Marker>,
    /// Solver settings.
    #[serde(default)]
    pub solver: SolverSettings,
}

impl Scene {
    /// Parses and validates a scene.
    ///
    /// # Errors
    /// [`Error::Scene`] for malformed JSON, unknown or missing fields, wrong
    /// types (the message starts with the path of the field at fault, e.g.
    /// `robot.sections[0].elements: invalid value ...`, and gives the line and
    /// column); the errors of [`Scene::validate`].
    pub fn from_json(text: &str) -> Result<Scene> {
        let de = &mut serde_json::Deserializer::from_str(text);
        let scene: Scene = serde_path_to_error::deserialize(de).map_err(|e| {
            // `?` marks a segment the parser had not identified yet (truncated input)
            let path = e.path().to_string();
            let path = path.trim_end_matches(".?").trim_end_matches('?');
            let inner = e.into_inner();
            Error::Scene {
                message: if path.is_empty() || path == "." {
                    inner.to_string()
                } else {
                    format!("{path}: {inner}")
                },
            }
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
    pub fn validate(&self) -> Result<()> {
        let robot = self.robot()?;
        for (i, load) in self.loads.iter().enumerate() {
            validate_scene_load(&robot, load)
                .map_err(|e| e.with_prefix(&format!("loads[{i}].")))?;
        }
        robot.validate_loads(&self.loads()?)?;
        self.solver
            .statics
            .validate()
            .map_err(|e| e.with_prefix("solver.static."))?;
        self.solver
            .estimator
            .validate()
            .map_err(|e| e.with_prefix("solver.estimator."))?;
        let total = robot.length();
        let mut seen: Vec<f64> = Vec::new();
        for (i, m) in self.markers.iter().enumerate() {
            let s = match (m.node, m.s_m) {
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
                    ))
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
        Ok(())
    }

    /// The robot's spec.
    pub fn robot_spec(&self) -> RobotSpec {
        RobotSpec {
            sections: self.robot.sections.clone(),
            base: self.base.clone(),
            gravity_m_per_s2: self.gravity_m_per_s2.clone(),
            axial_gauss_points: self.robot.axial_gauss_points,
            bending_gauss_points: self.robot.bending_gauss_points,
        }
    }

    /// Builds the robot.
    ///
    /// # Errors
    /// As [`Robot::new`].
    pub fn robot(&self) -> Result<Robot<PlanarCable>> {
        match self.robot.element {
            ElementKind::PlanarCable => self.robot_spec().build_planar(),
        }
    }

    /// The scene's loads and pressures as [`Loads`] (pressures default to zero).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a non-positive tip mass or a negative
    /// extra weight; [`Error::DimensionMismatch`] for a gravity vector of the
    /// wrong size.
    pub fn loads(&self) -> Result<Loads> {
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
        for (i, l) in self.loads.iter().enumerate() {
            match l {
                SceneLoad::Distributed(p) => loads.line_loads.push(p.clone()),
                SceneLoad::TipForce { force_n } => loads.point_forces.push(PointForce {
                    s_m: total,
                    force_n: force_n.clone(),
                }),
                SceneLoad::PointForce { s_m, force_n } => loads.point_forces.push(PointForce {
                    s_m: *s_m,
                    force_n: force_n.clone(),
                }),
                SceneLoad::TipMoment { moment_nm } => loads.node_moments.push(NodeMoment {
                    node: n_nodes - 1,
                    moment_nm: vec![*moment_nm],
                }),
                SceneLoad::NodeMoment { node, moment_nm } => loads.node_moments.push(NodeMoment {
                    node: *node,
                    moment_nm: vec![*moment_nm],
                }),
                SceneLoad::SelfWeight {
                    mass_per_length_kg_per_m: m,
                    gravity_m_per_s2: g,
                } => {
                    if !(m.is_finite() && *m >= 0.0) {
                        return Err(Error::invalid(
                            format!("loads[{i}].mass_per_length_kg_per_m"),
                            m,
                            "must be finite and >= 0",
                        ));
                    }
                    check_len(&format!("loads[{i}].gravity_m_per_s2"), 2, g.len())?;
                    loads.line_loads.push(LineLoad::Uniform {
                        w_n_per_m: g.iter().map(|g| m * g).collect(),
                    })
                }
                SceneLoad::TipMass { mass_kg } => {
                    check_positive(&format!("loads[{i}].mass_kg"), *mass_kg)?;
                    check_len("gravity_m_per_s2", 2, self.gravity_m_per_s2.len())?;
                    loads.point_forces.push(PointForce {
                        s_m: total,
                        force_n: self.gravity_m_per_s2.iter().map(|g| mass_kg * g).collect(),
                    })
                }
            }
        }
        Ok(loads)
    }

    /// The paper's two-section robot (MODEL.md §5) with the values of
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
            rest_curvature_per_m: 0.0,
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
        }
    }
}

/// Checks one scene load against the robot, naming its fields as in the
/// scene file (the caller prefixes `loads[i].`).
fn validate_scene_load(robot: &Robot<PlanarCable>, load: &SceneLoad) -> Result<()> {
    let vec2 = |name: &str, v: &[f64]| -> Result<()> {
        check_len(name, 2, v.len())?;
        check_all_finite(name, v)
    };
    match load {
        SceneLoad::Distributed(l) => l.validate("", 2),
        SceneLoad::TipForce { force_n } => vec2("force_n", force_n),
        SceneLoad::PointForce { s_m, force_n } => {
            vec2("force_n", force_n)?;
            robot.locate("s_m", *s_m).map(|_| ())
        }
        SceneLoad::TipMoment { moment_nm } => check_finite("moment_nm", *moment_nm),
        SceneLoad::NodeMoment { node, moment_nm } => {
            check_finite("moment_nm", *moment_nm)?;
            check_index("node", *node, robot.n_nodes())?;
            if *node == 0 {
                return Err(Error::invalid(
                    "node",
                    0,
                    "the clamped base takes no moment: must be a free node, >= 1",
                ));
            }
            Ok(())
        }
        SceneLoad::SelfWeight {
            mass_per_length_kg_per_m: m,
            gravity_m_per_s2: g,
        } => {
            if !(m.is_finite() && *m >= 0.0) {
                return Err(Error::invalid(
                    "mass_per_length_kg_per_m",
                    m,
                    "must be finite and >= 0",
                ));
            }
            vec2("gravity_m_per_s2", g)
        }
        SceneLoad::TipMass { mass_kg } => check_positive("mass_kg", *mass_kg),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn example_file_is_the_built_in_scene() {
        let text = include_str!("../examples/two_section.json");
        assert_eq!(Scene::from_json(text).unwrap(), Scene::two_section());
    }

    #[test]
    fn unknown_and_missing_fields_are_named() {
        let bad = r#"{"robot": {"sections": [{"length_m": 0.1, "ea_n": 1, "ei_nm2": 1, "elements": 2, "colour": 3}]}}"#;
        let msg = Scene::from_json(bad).unwrap_err().to_string();
        assert!(msg.contains("colour"), "{msg}");
        let missing = r#"{"robot": {"sections": [{"length_m": 0.1, "ea_n": 1, "elements": 2}]}}"#;
        let msg = Scene::from_json(missing).unwrap_err().to_string();
        assert!(msg.contains("ei_nm2"), "{msg}");
    }

    #[test]
    fn nested_load_tags_parse() {
        let text = r#"{"robot": {"sections": [{"length_m": 0.2, "ea_n": 300, "ei_nm2": 0.02, "elements": 4}]},
            "loads": [{"type": "distributed", "profile": "gaussian", "amplitude_n_per_m": [0, -1], "center_m": 0.1, "width_m": 0.01},
                      {"type": "tip_moment", "moment_nm": 0.01}, {"type": "tip_mass", "mass_kg": 0.02}]}"#;
        let scene = Scene::from_json(text).unwrap();
        let loads = scene.loads().unwrap();
        assert_eq!(loads.line_loads.len(), 1);
        assert_eq!(loads.node_moments[0].node, 4);
        assert!((loads.point_forces[0].force_n[1] + 0.02 * 9.81).abs() < 1e-15);
        let bad = text.replace("\"width_m\"", "\"sigma\"");
        assert!(Scene::from_json(&bad)
            .unwrap_err()
            .to_string()
            .contains("sigma"));
    }
}
