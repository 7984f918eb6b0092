//! Calibration of the model on contact-free data, before any contact is
//! looked for: the factors on every section's bending stiffness `EI` and
//! on every chamber's actuation gain that make the model's equilibria
//! match contact-free marker frames at several pressures (Gauss–Newton on
//! the two factors, central-difference Jacobian by static solves). The
//! paper's virtual payload absorbs a model error as a load; a load cannot
//! absorb a wrong compliance, which biases where a contact seems to act.
//! What the calibrated model still misses is left to the virtual payload.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, check_len};
use crate::scene::Scene;
use crate::statics::StaticSolver;

/// One contact-free observation: pressures held and the markers seen.
///
/// # Example
/// ```
/// let f = softrod::touch::FreeFrame { pressures_pa: vec![0.0; 10], markers_m: vec![vec![0.0, 0.0], vec![0.0, -0.465]] };
/// assert_eq!(f.marker(1), Some(nalgebra::Vector2::new(0.0, -0.465)));
/// assert_eq!(f.marker(2), None);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FreeFrame {
    /// Chamber pressures (Pa).
    pub pressures_pa: Vec<f64>,
    /// Marker positions (m), one per marker.
    pub markers_m: Vec<Vec<f64>>,
}

impl FreeFrame {
    /// Marker `i`'s position (m); `None` past the last marker or for a
    /// position that is not planar.
    ///
    /// # Example
    /// See [`FreeFrame`].
    pub fn marker(&self, i: usize) -> Option<nalgebra::Vector2<f64>> {
        match self.markers_m.get(i)?.as_slice() {
            [x, y] => Some(nalgebra::Vector2::new(*x, *y)),
            _ => None,
        }
    }
}

/// The calibrated factors.
///
/// # Example
/// ```
/// let c = softrod::touch::Calibration { ei_factor: 1.1, gain_factor: 0.9, rms_before_m: 1e-3, rms_after_m: 5e-5 };
/// let scene = c.apply(&softrod::touch::five_section_scene(4));
/// assert!((scene.robot.sections[0].ei_nm2 - 0.0275).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    /// Factor on every section's `EI`.
    pub ei_factor: f64,
    /// Factor on every chamber's actuation gain.
    pub gain_factor: f64,
    /// RMS marker misfit per component before (m).
    pub rms_before_m: f64,
    /// RMS marker misfit per component after (m).
    pub rms_after_m: f64,
}

impl Calibration {
    /// `scene` with the factors applied.
    pub fn apply(&self, scene: &Scene) -> Scene {
        scaled(scene, self.ei_factor, self.gain_factor)
    }
}

fn scaled(scene: &Scene, ei: f64, gain: f64) -> Scene {
    let mut s = scene.clone();
    for sec in &mut s.robot.sections {
        sec.ei_nm2 *= ei;
        for c in &mut sec.chambers {
            c.gain_nm_per_pa.iter_mut().for_each(|g| *g *= gain);
        }
    }
    s
}

/// Marker residuals `y − A q(θ)` over all frames.
fn residuals(
    scene: &Scene,
    marker_s_m: &[f64],
    frames: &[FreeFrame],
    th: [f64; 2],
) -> Result<Vec<f64>> {
    let sc = scaled(scene, th[0], th[1]);
    let robot = sc.robot()?;
    let base = sc.loads()?;
    let solver = StaticSolver::default();
    let mut out = Vec::new();
    for (k, f) in frames.iter().enumerate() {
        check_len(
            &format!("frames[{k}].markers_m"),
            marker_s_m.len(),
            f.markers_m.len(),
        )?;
        let mut loads = base.clone();
        loads.pressures_pa.clone_from(&f.pressures_pa);
        let q = solver.solve(&robot, &loads, None)?.q;
        for (&s, y) in marker_s_m.iter().zip(&f.markers_m) {
            let p = robot.position_at(q.as_slice(), s)?;
            check_len(&format!("frames[{k}].markers_m"), p.len(), y.len())?;
            out.extend(y.iter().zip(&p).map(|(a, b)| a - b));
        }
    }
    Ok(out)
}

fn rms(r: &[f64]) -> f64 {
    (r.iter().map(|v| v * v).sum::<f64>() / r.len().max(1) as f64).sqrt()
}

/// Calibrates `EI` and the actuation gain of `scene` (factors, starting at 1)
/// on `frames` (see the [module documentation](crate::touch)).
///
/// # Errors
/// [`Error::InvalidParameter`] (`frames`) for no frames or a calibration
/// that leaves the factors outside (0.2, 5); the static solver's errors.
///
/// # Example
/// See `tests/touch.rs`.
pub fn calibrate(scene: &Scene, marker_s_m: &[f64], frames: &[FreeFrame]) -> Result<Calibration> {
    if frames.is_empty() {
        return Err(Error::invalid(
            "frames",
            "[]",
            "calibration needs contact-free frames",
        ));
    }
    let mut th = [1.0, 1.0];
    let mut r = residuals(scene, marker_s_m, frames, th)?;
    let rms_before_m = rms(&r);
    let h = 1e-4;
    for _ in 0..8 {
        // J = ∂(Aq)/∂θ = −∂r/∂θ, central differences
        let mut cols = Vec::with_capacity(2);
        for j in 0..2 {
            let (mut a, mut b) = (th, th);
            a[j] += h;
            b[j] -= h;
            let ra = residuals(scene, marker_s_m, frames, a)?;
            let rb = residuals(scene, marker_s_m, frames, b)?;
            cols.push(
                ra.iter()
                    .zip(&rb)
                    .map(|(x, y)| -(x - y) / (2.0 * h))
                    .collect::<Vec<f64>>(),
            );
        }
        let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
        let (a11, a12, a22) = (
            dot(&cols[0], &cols[0]),
            dot(&cols[0], &cols[1]),
            dot(&cols[1], &cols[1]),
        );
        let (b1, b2) = (dot(&cols[0], &r), dot(&cols[1], &r));
        let det = a11 * a22 - a12 * a12;
        if !(det.is_finite() && det > 0.0) {
            break;
        }
        let d = [(a22 * b1 - a12 * b2) / det, (a11 * b2 - a12 * b1) / det];
        let mut step = 1.0;
        let old = dot(&r, &r);
        let mut accepted = false;
        while step > 1e-3 {
            let t = [th[0] + step * d[0], th[1] + step * d[1]];
            if t.iter().all(|v| *v > 0.2 && *v < 5.0) {
                let rn = residuals(scene, marker_s_m, frames, t)?;
                if dot(&rn, &rn) < old {
                    th = t;
                    r = rn;
                    accepted = true;
                    break;
                }
            }
            step *= 0.5;
        }
        if !accepted || (step * d[0]).hypot(step * d[1]) < 1e-6 {
            break;
        }
    }
    if !th.iter().all(|v| *v > 0.2 && *v < 5.0) {
        return Err(Error::invalid(
            "frames",
            format!("{th:?}"),
            "calibration left the factors outside (0.2, 5)",
        ));
    }
    Ok(Calibration {
        ei_factor: th[0],
        gain_factor: th[1],
        rms_before_m,
        rms_after_m: rms(&r),
    })
}
