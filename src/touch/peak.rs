//! The paper's contact localization (Sec. V, Fig. 9(c)): the estimated
//! load field minus the virtual payload (the load estimated without
//! contact at the same configuration), its peak as the contact location.

use crate::assembly::Robot;
use crate::element::{ArcPoint, PlanarCable};
use crate::error::{Result, check_len};

/// A contact located by the peak of a load field.
///
/// # Example
/// See [`peak_contact`].
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PeakContact {
    /// Arc coordinate of the peak of `|w|` (m).
    pub s_m: f64,
    /// The load per length there (N/m, world axes).
    pub peak_n_per_m: [f64; 2],
    /// Resultant `∫ w dX` of the whole difference field (N): the force
    /// estimate of the method.
    pub resultant_n: [f64; 2],
}

impl PeakContact {
    /// [`PeakContact::peak_n_per_m`] as a vector (N/m).
    ///
    /// # Example
    /// ```
    /// let p = softrod::touch::PeakContact { s_m: 0.3, peak_n_per_m: [0.0, 3.0], resultant_n: [0.0, 0.1] };
    /// assert_eq!(p.peak(), nalgebra::Vector2::new(0.0, 3.0));
    /// assert_eq!(p.resultant(), nalgebra::Vector2::new(0.0, 0.1));
    /// ```
    pub fn peak(&self) -> nalgebra::Vector2<f64> {
        nalgebra::Vector2::from(self.peak_n_per_m)
    }

    /// [`PeakContact::resultant_n`] as a vector (N).
    ///
    /// # Example
    /// See [`PeakContact::peak`].
    pub fn resultant(&self) -> nalgebra::Vector2<f64> {
        nalgebra::Vector2::from(self.resultant_n)
    }
}

/// Samples per element when searching the peak of a Hermite field.
const SAMPLES_PER_ELEMENT: usize = 50;

/// The peak of `|w(s)|` of the load field `f − f_virtual` (both `n_q`
/// parameters of the distributed field (8) on `robot`), searched at 50
/// points per element and every node.
///
/// # Errors
/// [`crate::Error::DimensionMismatch`] for fields of the wrong length.
///
/// # Example
/// A field that is zero but for a bump at node 10:
/// ```
/// use softrod::touch::{five_section_scene, peak_contact};
/// let robot = five_section_scene(4).robot()?;
/// let mut f = vec![0.0; robot.n_q()];
/// f[4 * 10 + 1] = 3.0; // w_y = 3 N/m at node 10
/// let p = peak_contact(&robot, &f, &vec![0.0; robot.n_q()])?;
/// assert!((p.s_m - robot.node_arc()[10]).abs() < 1e-12 && (p.peak_n_per_m[1] - 3.0).abs() < 1e-12);
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn peak_contact(
    robot: &Robot<PlanarCable>,
    f: &[f64],
    f_virtual: &[f64],
) -> Result<PeakContact> {
    check_len("f", robot.n_q(), f.len())?;
    check_len("f_virtual", robot.n_q(), f_virtual.len())?;
    let diff: Vec<f64> = f.iter().zip(f_virtual).map(|(a, b)| a - b).collect();
    let mut best = PeakContact {
        s_m: 0.0,
        peak_n_per_m: [0.0; 2],
        resultant_n: [0.0; 2],
    };
    let mut best_norm = -1.0;
    let mut w = [0.0; 2];
    for (e, el) in robot.elements().iter().enumerate() {
        let le = crate::element::Element::length(el);
        for k in 0..=SAMPLES_PER_ELEMENT {
            let xi = k as f64 / SAMPLES_PER_ELEMENT as f64;
            ArcPoint::new(e, xi, le).value_into(&diff, &mut w)?;
            let n = w[0].hypot(w[1]);
            if n > best_norm {
                best_norm = n;
                best.s_m = robot.node_arc()[e] + xi * le;
                best.peak_n_per_m = w;
            }
        }
    }
    let g = robot.apply_load_gram(&diff)?;
    // the generalized force's position rows sum to ∫ w dX
    best.resultant_n = [g.iter().step_by(4).sum(), g.iter().skip(1).step_by(4).sum()];
    Ok(best)
}
