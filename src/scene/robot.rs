//! The robot a scene builds, for each element family: generic code takes
//! a [`SceneElement`], code that serves any scene matches on [`SceneRobot`].

use super::{ElementKind, Scene};
use crate::assembly::{Robot, RobotSpec};
use crate::element::{Ancf3d, Ancf3dStiffness, Element, PlanarCable, SpatialCable};
use crate::error::{Error, Result};

/// An element a scene can build its robot of.
///
/// # Example
/// ```
/// use softrod::element::SpatialCable;
/// use softrod::scene::{ElementKind, SceneElement};
/// assert_eq!(SpatialCable::KIND, ElementKind::SpatialCable);
/// ```
pub trait SceneElement: Element {
    /// The element's name in scene files.
    const KIND: ElementKind;

    /// Builds the robot of `spec` with this element.
    ///
    /// # Errors
    /// As [`Robot::new`].
    fn build_robot(spec: &RobotSpec) -> Result<Robot<Self>>;
}

impl SceneElement for PlanarCable {
    const KIND: ElementKind = ElementKind::PlanarCable;
    fn build_robot(spec: &RobotSpec) -> Result<Robot<Self>> {
        spec.build_planar()
    }
}

impl SceneElement for SpatialCable {
    const KIND: ElementKind = ElementKind::SpatialCable;
    fn build_robot(spec: &RobotSpec) -> Result<Robot<Self>> {
        spec.build_spatial()
    }
}

impl SceneElement for Ancf3d {
    const KIND: ElementKind = ElementKind::Ancf3d;
    /// `GJ = EI/1.5` and `EI` about both axes (see [`ElementKind::Ancf3d`]);
    /// no rest curvature.
    fn build_robot(spec: &RobotSpec) -> Result<Robot<Self>> {
        Robot::new(spec.clone(), |s, le, ax, be| {
            if s.rest_curvature_per_m != 0.0 {
                return Err(Error::invalid(
                    "rest_curvature_per_m",
                    s.rest_curvature_per_m,
                    "the ancf3d scene element has no rest curvature: must be 0",
                ));
            }
            let k = Ancf3dStiffness::isotropic(s.ea_n, s.ei_nm2, s.ei_nm2 / 1.5);
            Ancf3d::with_stiffness(le, k, ax.max(be))
        })
    }
}

/// The robot of a scene, of the element family the scene names.
///
/// # Example
/// ```
/// use softrod::scene::{Scene, SceneRobot};
/// let scene = Scene::from_json(r#"{"robot": {"element": "spatial_cable",
///     "sections": [{"length_m": 0.24, "ea_n": 300, "ei_nm2": 0.025, "elements": 8}]}}"#)?;
/// match scene.build()? {
///     SceneRobot::Spatial(robot) => assert_eq!(robot.n_q(), 9 * 6),
///     SceneRobot::Planar(_) | SceneRobot::Full(_) => unreachable!(),
/// }
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub enum SceneRobot {
    /// A robot of planar cables.
    Planar(Robot<PlanarCable>),
    /// A robot of spatial cables.
    Spatial(Robot<SpatialCable>),
    /// A robot of full 3-D elements.
    Full(Robot<Ancf3d>),
}

impl Scene {
    /// Builds the robot as a robot of element `E`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `robot.element` when the scene
    /// names another element; as [`Scene::robot`].
    ///
    /// # Example
    /// ```
    /// use softrod::element::{PlanarCable, SpatialCable};
    /// let scene = softrod::scene::Scene::two_section();
    /// assert_eq!(scene.robot_as::<PlanarCable>()?.n_nodes(), 21);
    /// assert!(scene.robot_as::<SpatialCable>().is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn robot_as<E: SceneElement>(&self) -> Result<Robot<E>> {
        self.check_resolved()?;
        if self.robot.element != E::KIND {
            return Err(Error::invalid(
                "robot.element",
                self.robot.element.name(),
                format!(
                    "this call builds a {} robot: match on Scene::build for any scene",
                    E::KIND.name()
                ),
            ));
        }
        E::build_robot(&self.robot_spec())
    }

    /// Builds the robot of the element family the scene names.
    ///
    /// # Errors
    /// As [`Scene::robot`].
    pub fn build(&self) -> Result<SceneRobot> {
        Ok(match self.robot.element {
            ElementKind::PlanarCable => SceneRobot::Planar(self.robot_as()?),
            ElementKind::SpatialCable => SceneRobot::Spatial(self.robot_as()?),
            ElementKind::Ancf3d => SceneRobot::Full(self.robot_as()?),
        })
    }
}
