//! The paper's five-section robot (Sec. V): 5 × 93 mm, otherwise the
//! two-section robot of Sec. IV (the values of [`crate::params`]), hanging
//! from its base (base tangent along −y, gravity −y), six markers: the base
//! connector, the four section joints and the tip.

use nalgebra::DVector;

use crate::assembly::Base;
use crate::params;
use crate::scene::{Marker, Scene};

/// Length of one section (m).
pub const SECTION_LENGTH_M: f64 = 0.093;
/// Number of sections.
pub const SECTIONS: usize = 5;
/// Radius of the robot's body (m): the distance from the centreline at
/// which an obstacle touches it. The paper gives no value; 10 mm is the
/// order of its pneumatic sections (a chosen value).
pub const ROD_RADIUS_M: f64 = 0.010;

/// The five-section scene with `elements_per_section` elements per section
/// and the six markers of the paper (base connector, joints, tip), every
/// chamber at zero pressure.
///
/// # Example
/// ```
/// let scene = softrod::touch::five_section_scene(4);
/// let robot = scene.robot()?;
/// assert!((robot.length() - 0.465).abs() < 1e-12);
/// assert_eq!((robot.n_pressures(), scene.markers.len()), (10, 6));
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn five_section_scene(elements_per_section: usize) -> Scene {
    let mut scene = Scene::two_section();
    scene.name = "five_section".into();
    scene.description = "The paper's five-section robot (Sec. V): 5 x 93 mm, otherwise as the \
                         two-section robot; hanging from its base; six markers on the base \
                         connector, the section joints and the tip."
        .into();
    let mut section = scene.robot.sections[0].clone();
    section.length_m = SECTION_LENGTH_M;
    section.elements = elements_per_section;
    scene.robot.sections = vec![section; SECTIONS];
    scene.base = Base {
        angle_rad: -std::f64::consts::FRAC_PI_2,
        ..Base::default()
    };
    scene.gravity_m_per_s2 = params::GRAVITY_M_PER_S2.as_slice().to_vec();
    scene.pressures_pa = vec![0.0; 2 * SECTIONS];
    scene.markers = marker_arcs(6)
        .iter()
        .map(|&s| Marker {
            node: None,
            s_m: Some(s),
            tangent: false,
        })
        .collect();
    scene
}

/// `count` (≥ 2) marker arc coordinates evenly spaced from the base to the
/// tip (m): 6 gives the paper's base connector, four joints and the tip.
///
/// # Example
/// ```
/// let s = softrod::touch::marker_arcs(6);
/// assert!((s[1] - 0.093).abs() < 1e-12 && (s[5] - 0.465).abs() < 1e-12);
/// // a robot's markers take a slice
/// let scene = softrod::touch::five_section_scene(2);
/// let plant = softrod::plant::SimulatedPlant::new(&scene, s.as_slice(), Default::default())?;
/// assert_eq!(plant.true_markers_m()?.len(), 6);
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn marker_arcs(count: usize) -> DVector<f64> {
    let n = count.max(2);
    // summed as the robot sums its sections, so the last one is its tip
    let length: f64 = (0..SECTIONS).map(|_| SECTION_LENGTH_M).sum();
    DVector::from_fn(n, |i, _| {
        if i + 1 == n {
            length
        } else {
            length * i as f64 / (n - 1) as f64
        }
    })
}
