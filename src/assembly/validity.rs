//! Where a configuration leaves the model's validity.
//!
//! The cable's axial law is linear in `ε = |r'| − 1` with a constant `EA`, and
//! the section is rigid: both are models of an elastomer only at moderate
//! strain. [`MAX_AXIAL_STRAIN`] states the bound; beyond it a solve still
//! converges (the equations have a solution) but the answer describes the
//! model, not a robot. The clamp's body is not modelled either: a node behind
//! the base plane sits where the clamp would be (legitimate for a rod curling
//! back on itself, a mistake for a rod pushed through its base). The cable
//! is a slender rod: a section whose radius of gyration `√(EI/EA)` exceeds
//! the robot's length (EA and EI swapped, say) is outside it whatever the
//! configuration.

use serde::{Deserialize, Serialize};

use super::Robot;
use crate::element::Element;
use crate::error::{Result, check_len};

/// Largest axial strain `|ε|` (dimensionless) inside the model's validity.
pub const MAX_AXIAL_STRAIN: f64 = 0.1;

/// Sample points per element at which the axial strain is evaluated
/// (`ξ = 0, 1/4, …, 1`).
const STRAIN_SAMPLES: usize = 5;

/// A configuration outside the model's validity: what, and where.
///
/// # Example
/// ```
/// use softrod::assembly::{RobotSpec, Section, ValidityWarning};
/// let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 4)]).build_planar()?;
/// let mut q = robot.reference_configuration().as_slice().to_vec();
/// for node in q.chunks_mut(4) {
///     node[0] *= 1.5; // stretch by 50 %
///     node[2] *= 1.5;
/// }
/// let w = robot.validity(&q)?;
/// assert!(matches!(w[0], ValidityWarning::AxialStrain { strain, .. } if (strain - 0.5).abs() < 1e-6));
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ValidityWarning {
    /// The largest axial strain exceeds [`MAX_AXIAL_STRAIN`].
    AxialStrain {
        /// Arc coordinate (m) of the largest `|ε|` sampled.
        s_m: f64,
        /// The strain there (dimensionless; negative in compression).
        strain: f64,
        /// The bound it exceeds.
        bound: f64,
    },
    /// Nodes lie behind the clamp's plane (the plane through the base
    /// position normal to the base direction).
    BehindClamp {
        /// The node farthest behind.
        node: usize,
        /// How far behind (m).
        distance_m: f64,
        /// How many nodes are behind.
        nodes: usize,
    },
    /// A section's radius of gyration `√(EI/EA)` exceeds the robot's
    /// length: not a slender rod (a section larger than the robot; EA and
    /// EI swapped give this).
    Slenderness {
        /// The section (0-based, as in the spec).
        section: usize,
        /// Its radius of gyration `√(EI/EA)` (m).
        radius_of_gyration_m: f64,
        /// The robot's length (m).
        length_m: f64,
    },
}

impl std::fmt::Display for ValidityWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ValidityWarning::AxialStrain { s_m, strain, bound } => write!(
                f,
                "axial strain {:.3} % at s = {s_m:.4} m exceeds the model's bound of {:.0} %: \
                 the result describes the model, not an elastomer",
                strain * 100.0,
                bound * 100.0
            ),
            ValidityWarning::BehindClamp {
                node,
                distance_m,
                nodes,
            } => write!(
                f,
                "{nodes} node(s) behind the clamp's plane (node {node} by {distance_m:.4e} m): \
                 the clamp's body is not modelled"
            ),
            ValidityWarning::Slenderness {
                section,
                radius_of_gyration_m,
                length_m,
            } => write!(
                f,
                "section {section}'s radius of gyration √(EI/EA) = {radius_of_gyration_m:.4e} m \
                 exceeds the robot's length {length_m:.4} m: not a slender rod (EA and EI swapped?)"
            ),
        }
    }
}

impl<E: Element> Robot<E> {
    /// What in configuration `q` lies outside the model's validity (see
    /// [`ValidityWarning`]); empty when nothing does. The strain is sampled
    /// at five points per element from the centreline's slope (central
    /// differences of [`Robot::position_at`], exact to about `1e-9`).
    ///
    /// # Errors
    /// [`crate::Error::DimensionMismatch`] if `q` does not have
    /// [`Robot::n_q`] entries.
    pub fn validity(&self, q: &[f64]) -> Result<Vec<ValidityWarning>> {
        check_len("q", self.n_q(), q.len())?;
        let arc = self.node_arc();
        let mut worst: Option<(f64, f64)> = None;
        for e in 0..self.n_elements() {
            let (a, b) = (arc[e], arc[e + 1]);
            let h = 1e-6 * (b - a);
            for k in 0..STRAIN_SAMPLES {
                let s = a + (b - a) * k as f64 / (STRAIN_SAMPLES - 1) as f64;
                let (lo, hi) = ((s - h).max(a), (s + h).min(b));
                let r0 = self.position_at(q, lo)?;
                let r1 = self.position_at(q, hi)?;
                let stretch = r0
                    .iter()
                    .zip(&r1)
                    .map(|(x, y)| (y - x).powi(2))
                    .sum::<f64>()
                    .sqrt()
                    / (hi - lo);
                let strain = stretch - 1.0;
                if worst.is_none_or(|(_, w)| strain.abs() > w.abs()) {
                    worst = Some((s, strain));
                }
            }
        }
        let mut out = Vec::new();
        if let Some((s_m, strain)) =
            worst.filter(|(_, w)| w.abs() > MAX_AXIAL_STRAIN || !w.is_finite())
        {
            out.push(ValidityWarning::AxialStrain {
                s_m,
                strain,
                bound: MAX_AXIAL_STRAIN,
            });
        }
        let d = E::DIM;
        let base = &self.base_node()[..d];
        let t = E::node_tangent(self.base_node());
        let norm = t.iter().map(|x| x * x).sum::<f64>().sqrt();
        let tol = 1e-9 * self.length();
        let (mut behind, mut far) = (0, (0, 0.0));
        for (i, r) in self.node_positions(q).column_iter().enumerate().skip(1) {
            let ahead = r
                .iter()
                .zip(base)
                .zip(&t)
                .map(|((x, b), t)| (x - b) * t)
                .sum::<f64>()
                / norm;
            if ahead < -tol {
                behind += 1;
                if -ahead > far.1 {
                    far = (i, -ahead);
                }
            }
        }
        if behind > 0 {
            out.push(ValidityWarning::BehindClamp {
                node: far.0,
                distance_m: far.1,
                nodes: behind,
            });
        }
        out.extend(self.slenderness());
        Ok(out)
    }

    /// The sections that are not slender rods (see
    /// [`ValidityWarning::Slenderness`]).
    fn slenderness(&self) -> Vec<ValidityWarning> {
        let length_m = self.length();
        self.spec()
            .sections
            .iter()
            .enumerate()
            .filter_map(|(section, s)| {
                let radius_of_gyration_m = (s.ei_nm2 / s.ea_n).sqrt();
                (radius_of_gyration_m > length_m).then_some(ValidityWarning::Slenderness {
                    section,
                    radius_of_gyration_m,
                    length_m,
                })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use crate::assembly::{RobotSpec, Section, ValidityWarning};

    #[test]
    fn a_straight_rod_is_valid_and_a_rod_pushed_through_its_clamp_is_not() {
        let robot = RobotSpec::new(vec![Section::uniform(0.24, 300.0, 0.025, 6)])
            .build_planar()
            .unwrap();
        let q = robot.reference_configuration();
        assert!(robot.validity(q.as_slice()).unwrap().is_empty());
        // 5 % stretch: inside the bound
        let mut q5 = q.clone();
        for node in q5.as_mut_slice().chunks_mut(4) {
            node[0] *= 1.05;
            node[2] *= 1.05;
        }
        assert!(robot.validity(q5.as_slice()).unwrap().is_empty());
        // flipped back through the base and stretched 2×: nodes behind it
        let mut qb = q.clone();
        for node in qb.as_mut_slice().chunks_mut(4) {
            node[0] *= -2.0;
            node[2] *= -2.0;
        }
        let w = robot.validity(qb.as_slice()).unwrap();
        assert!(
            matches!(w[0], ValidityWarning::AxialStrain { strain, .. } if (strain - 1.0).abs() < 1e-6),
            "{w:?}"
        );
        assert!(
            matches!(
                w[1],
                ValidityWarning::BehindClamp {
                    node: 6,
                    nodes: 6,
                    ..
                }
            ),
            "{w:?}"
        );
        assert!(robot.validity(&q.as_slice()[1..]).is_err());
    }

    /// EA = 0.025 N and EI = 300 N·m² (the two swapped): a radius of
    /// gyration of √(300/0.025) = 109.5 m against 0.24 m of robot, flagged
    /// at every configuration; the unswapped section (9.1 mm) is not.
    #[test]
    fn a_section_with_ea_and_ei_swapped_is_not_a_slender_rod() {
        let swapped = RobotSpec::new(vec![
            Section::uniform(0.12, 300.0, 0.025, 3),
            Section::uniform(0.12, 0.025, 300.0, 3),
        ])
        .build_planar()
        .unwrap();
        let w = swapped
            .validity(swapped.reference_configuration().as_slice())
            .unwrap();
        assert_eq!(w.len(), 1, "{w:?}");
        let ValidityWarning::Slenderness {
            section,
            radius_of_gyration_m,
            length_m,
        } = w[0]
        else {
            panic!("{w:?}")
        };
        assert_eq!(section, 1);
        assert!((radius_of_gyration_m - (300.0f64 / 0.025).sqrt()).abs() < 1e-9);
        assert!((length_m - 0.24).abs() < 1e-15);
        assert!(w[0].to_string().contains("EA and EI swapped"));
    }
}
