//! The candidate meshes of a scene with `"elements": "auto"` sections: the
//! ladder [`crate::refine`] climbs (here, since validating a scene needs it).

use super::{DEFAULT_MAX_REFINED_ELEMENTS, NODE_MATCH, Scene, UnknownLoad};
use crate::error::{Error, Result};

/// The candidate meshes of a scene: fixed sections keep their count, auto
/// section `i` gets `t c_i` elements at scale `t` (see the
/// [`crate::refine`] module documentation).
///
/// # Example
/// ```
/// use softrod::{refine::Ladder, scene::Scene};
/// let mut scene = Scene::two_section();
/// scene.robot.sections[1].auto_elements = true;
/// let ladder = Ladder::new(&scene)?;
/// assert_eq!(ladder.elements(3), vec![10, 3]);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Ladder {
    base: Vec<usize>,
    auto: Vec<bool>,
}

impl Ladder {
    /// The candidates of a scene (its lengths must be valid: see
    /// [`Scene::validate`]).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming `refinement.max_elements` when a
    /// section's base count alone exceeds it, or `unknown_load.s_m` when no
    /// uniform mesh of its section within `max_elements` has a node at the
    /// point.
    pub fn new(scene: &Scene) -> Result<Ladder> {
        let max = scene
            .refinement
            .map_or(DEFAULT_MAX_REFINED_ELEMENTS, |t| t.max_elements());
        let sections = &scene.robot.sections;
        let total: f64 = sections.iter().map(|s| s.length_m).sum();
        let shortest = sections
            .iter()
            .filter(|s| s.auto_elements)
            .map(|s| s.length_m)
            .fold(f64::INFINITY, f64::min);
        let mut base = Vec::with_capacity(sections.len());
        for (i, s) in sections.iter().enumerate() {
            if !s.auto_elements {
                base.push(s.elements);
                continue;
            }
            let ratio = (s.length_m / shortest).round().max(1.0);
            if ratio.is_nan() || ratio > max as f64 {
                return Err(Error::invalid(
                    "refinement.max_elements",
                    max,
                    format!(
                        "robot.sections[{i}] alone needs {ratio:e} elements to keep the \
                         element lengths of the auto sections alike"
                    ),
                ));
            }
            base.push(ratio as usize);
        }
        if let Some(UnknownLoad::Point { s_m }) = scene.unknown_load {
            let tol = NODE_MATCH * total;
            let mut start = 0.0;
            for (i, s) in sections.iter().enumerate() {
                let end = start + s.length_m;
                if s.auto_elements && s_m > start + tol && s_m < end - tol {
                    let f = (s_m - start) / s.length_m;
                    let k = (1..=max)
                        .find(|&k| {
                            let x = f * k as f64;
                            (x - x.round()).abs() * s.length_m / k as f64 <= tol
                        })
                        .ok_or_else(|| {
                            Error::invalid(
                                "unknown_load.s_m",
                                s_m,
                                format!(
                                    "no uniform mesh of robot.sections[{i}] with at most \
                                     refinement.max_elements = {max} elements has a node there"
                                ),
                            )
                        })?;
                    base[i] = base[i].div_ceil(k).saturating_mul(k);
                }
                start = end;
            }
        }
        Ok(Ladder {
            base,
            auto: sections.iter().map(|s| s.auto_elements).collect(),
        })
    }

    /// Elements per section at scale `t` (saturating).
    pub fn elements(&self, t: usize) -> Vec<usize> {
        self.base
            .iter()
            .zip(&self.auto)
            .map(|(&c, &auto)| if auto { c.saturating_mul(t) } else { c })
            .collect()
    }

    /// Elements in all at scale `t` (saturating).
    pub fn total_elements(&self, t: usize) -> usize {
        self.elements(t)
            .into_iter()
            .fold(0usize, usize::saturating_add)
    }
}
