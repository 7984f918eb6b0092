//! Where `"elements": "auto"` lands on the Pareto chart.
//!
//! For each marker count of the sweep, the estimator's model of every
//! reference is written as a scene with `"elements": "auto"` and a
//! `load_resultant` refinement (tolerance [`AUTO_FORCE_FRACTION`] of the
//! reference's resultant force), the unknown load declared distributed;
//! [`crate::refine::auto_elements`] picks the element count from the same
//! noisy markers the sweep's measured frame uses. That count then runs as an
//! ordinary case of the sweep (backend `newton`), and its errors and median
//! time become a labelled point of the chart.

use std::sync::Arc;

use serde_json::json;

use super::ReportOptions;
use super::pareto::{LabelledPoint, ParetoGrid};
use super::reference::Reference;
use super::sweep::{marker_arcs, median, observe, run_guarded};
use crate::error::Result;
use crate::estimate::Backend;
use crate::refine::auto_elements;
use crate::scene::Scene;

/// Tolerance of the auto refinement: this fraction of the reference's
/// resultant force magnitude (the discretization's share of the resultant's
/// error, 1 %).
pub const AUTO_FORCE_FRACTION: f64 = 0.01;

/// The largest model the auto refinement may choose (elements).
pub(crate) const AUTO_MAX_ELEMENTS: usize = 256;

/// The scene of `reference`'s estimator model with `"elements": "auto"`,
/// the unknown load distributed, and a `load_resultant` refinement of
/// tolerance `tolerance_n` (N). Same model as
/// [`super::sweep::model_robot`]: weightless sections, full clamp, 3 Gauss
/// points for bending.
///
/// # Errors
/// The errors of [`Scene::from_json`] (an invalid reference).
pub fn auto_scene(reference: &Reference, noise_m: f64, tolerance_n: f64) -> Result<Scene> {
    let sections: Vec<_> = reference
        .sections
        .iter()
        .map(|s| {
            json!({"length_m": s.length_m, "ea_n": s.ea_n, "ei_nm2": s.ei_nm2, "elements": "auto"})
        })
        .collect();
    let scene = json!({
        "name": format!("auto model of {}", reference.name),
        "robot": {"sections": sections, "bending_gauss_points": 3},
        "base": {"position_m": [0.0, 0.0], "angle_rad": 0.0, "clamp": "full"},
        "gravity_m_per_s2": [0.0, 0.0],
        "unknown_load": {"acts_at": "distributed"},
        "solver": {"estimator": {"noise_sigma_m": noise_m}},
        "refinement": {
            "quantity": "load_resultant",
            "tolerance_n": tolerance_n,
            "max_elements": AUTO_MAX_ELEMENTS
        }
    });
    Scene::from_json(&scene.to_string())
}

/// The auto points of the Pareto chart: one per marker count of `grid`
/// (errors averaged and times pooled over the references, like the sweep's
/// points). A marker count for which a refinement or a case fails gives no
/// point; the reason is in the returned notes.
///
/// # Errors
/// [`crate::Error::Io`] when an embedded reference is malformed.
pub fn auto_points(
    opts: &ReportOptions,
    grid: &ParetoGrid,
) -> Result<(Vec<LabelledPoint>, Vec<String>)> {
    let refs: Vec<Arc<Reference>> = grid
        .references
        .iter()
        .map(|n| Reference::embedded(n).map(Arc::new))
        .collect::<Result<_>>()?;
    let mut points = Vec::new();
    let mut notes = Vec::new();
    'markers: for &markers in &grid.markers {
        let mut chosen = Vec::new();
        let mut errs = Vec::new();
        let mut times = Vec::new();
        for r in &refs {
            let resultant = r.resultant_force_n();
            let tol = AUTO_FORCE_FRACTION * resultant[0].hypot(resultant[1]);
            let scene = auto_scene(r, grid.noise_m, tol)?;
            // the sweep's measured frame (seed 7)
            let obs = observe(
                r,
                marker_arcs(r.length_m, markers).as_slice(),
                grid.noise_m,
                7,
            );
            let refinement = match auto_elements(&scene, Some(&obs)) {
                Ok(x) => x,
                Err(e) => {
                    notes.push(format!("auto, {markers} markers, {}: {e}", r.name));
                    continue 'markers;
                }
            };
            let spec = grid.case(
                Backend::Newton,
                r.clone(),
                refinement.total_elements,
                markers,
            );
            let out = run_guarded(&spec, opts.case_cap);
            match (out.is_converged(), out.errors) {
                (true, Some(e)) => {
                    chosen.push(refinement.total_elements);
                    errs.push(e);
                    times.extend(out.warm_step_s.iter().copied());
                }
                _ => {
                    notes.push(format!(
                        "auto, {markers} markers, {}: {} elements did not converge ({})",
                        r.name,
                        refinement.total_elements,
                        out.failure()
                            .map(|f| f.message.as_str())
                            .unwrap_or_default()
                    ));
                    continue 'markers;
                }
            }
        }
        let n = errs.len().max(1) as f64;
        let Some(t) = median(&mut times) else {
            continue;
        };
        let counts: Vec<String> = chosen.iter().map(|c| c.to_string()).collect();
        points.push(LabelledPoint {
            label: format!("auto {markers} mk: {} el", counts.join("/")),
            median_step_s: t,
            backbone_rms_m: errs.iter().map(|e| e.backbone_rms_m).sum::<f64>() / n,
            load_rel_l2: errs.iter().map(|e| e.load_rel_l2).sum::<f64>() / n,
            force_rel: errs.iter().map(|e| e.force_rel).sum::<f64>() / n,
        });
    }
    Ok((points, notes))
}
