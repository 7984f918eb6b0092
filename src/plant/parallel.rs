//! The soft parallel robot as a plant: a [`ParallelRobot`] (another mesh
//! and other stiffnesses than the controller's model, see
//! [`crate::parallel::payload::plant_spec`]) carrying a hung mass at the
//! platform's centre, solved statically at every control instant (a
//! quasi-static plant: the platform is taken to settle within a control
//! interval), its platform marker read with Gaussian noise.

use nalgebra::Vector3;

use super::{MarkerFrame, Plant, check_command};
use crate::element::Element;
use crate::error::{Error, Result};
use crate::parallel::ParallelRobot;
use crate::parallel::warm::{WarmCounts, WarmStatics};
use crate::rng::Gaussian;
use crate::structure::Actuated;

/// The parallel robot under a hung mass, one marker at the platform's
/// centre: pressures in, the marker out. It is another
/// [`ParallelRobot`] than the controller's model (another mesh and other
/// stiffnesses, [`crate::parallel::payload::plant_spec`]), solved
/// statically at every frame (quasi-static: the platform is taken to
/// settle within a control interval), its marker read with Gaussian noise.
///
/// # Example
/// ```
/// use softrod::plant::{ParallelPlant, Plant};
/// let mut spec = softrod::parallel::ParallelSpec::default();
/// spec.elements_per_section = 1;
/// let mut loaded = ParallelPlant::new(spec.build_cable()?, 0.1, 0.0, 1)?;
/// let mut empty = ParallelPlant::new(spec.build_cable()?, 0.0, 0.0, 1)?;
/// loaded.command(&vec![0.0; 18])?;
/// empty.command(&vec![0.0; 18])?;
/// let (a, b) = (loaded.advance(0.1)?, empty.advance(0.1)?);
/// // 100 g pulls the platform down; without noise the marker is the truth
/// assert!(a.positions_m[0][2] < b.positions_m[0][2] - 1e-5);
/// assert_eq!(a.positions_m[0], loaded.true_platform_m().unwrap().as_slice());
/// assert!(a.time_s == 0.1 && loaded.counts().solves == 0); // the first solve is cold
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct ParallelPlant<E: Element> {
    warm: WarmStatics<E>,
    /// The free coordinates of the last equilibrium (`None` before the
    /// first: a cold solve then).
    u: Option<Vec<f64>>,
    commanded_pa: Vec<f64>,
    weight_n: [f64; 3],
    noise_sigma_m: f64,
    noise: Gaussian,
    time_s: f64,
}

impl<E: Element + 'static> ParallelPlant<E> {
    /// The robot `robot` carrying `payload_kg` (kg, ≥ 0) at the platform's
    /// centre, its marker read with noise of `noise_sigma_m` (m, ≥ 0) per
    /// coordinate from the seed `seed`; the command zero until the first.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] (`payload_kg`, `noise_sigma_m`) for a
    /// negative or non-finite value; as [`WarmStatics::new`].
    pub fn new(
        robot: ParallelRobot<E>,
        payload_kg: f64,
        noise_sigma_m: f64,
        seed: u64,
    ) -> Result<Self> {
        for (field, v) in [("payload_kg", payload_kg), ("noise_sigma_m", noise_sigma_m)] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(field, v, "must be finite and >= 0"));
            }
        }
        let g = robot.spec().gravity_m_per_s2.clone();
        let n = robot.spec().n_pressures();
        Ok(ParallelPlant {
            warm: WarmStatics::new(robot)?,
            u: None,
            commanded_pa: vec![0.0; n],
            weight_n: [0, 1, 2].map(|i| payload_kg * g.get(i).copied().unwrap_or(0.0)),
            noise_sigma_m,
            noise: Gaussian::new(seed),
            time_s: 0.0,
        })
    }

    /// The true (noise-free) platform centre now (m; `None` before the
    /// first frame). For scoring only.
    pub fn true_platform_m(&self) -> Option<Vector3<f64>> {
        let x0 = self.warm.robot().platform_free_start().ok()?;
        let u = self.u.as_ref()?;
        Some(Vector3::new(*u.get(x0)?, *u.get(x0 + 1)?, *u.get(x0 + 2)?))
    }

    /// What the plant's static solves cost so far.
    pub fn counts(&self) -> WarmCounts {
        self.warm.counts()
    }
}

impl<E: Element + 'static> Plant for ParallelPlant<E> {
    fn n_pressures(&self) -> usize {
        self.commanded_pa.len()
    }

    fn command(&mut self, pressures_pa: &[f64]) -> Result<()> {
        check_command(
            &self.warm.robot().structure().pressure_bounds(),
            pressures_pa,
        )?;
        self.commanded_pa.copy_from_slice(pressures_pa);
        Ok(())
    }

    fn advance(&mut self, dt_s: f64) -> Result<MarkerFrame> {
        if !(dt_s.is_finite() && dt_s > 0.0) {
            return Err(Error::invalid("dt_s", dt_s, "must be finite and > 0"));
        }
        let robot = self.warm.robot();
        let loads = robot.loads(&self.commanded_pa, self.weight_n, [0.0; 3])?;
        let u: Vec<f64> = match &self.u {
            Some(u0) => self.warm.solve(&loads, u0)?.data.into(),
            None => robot.solve(&loads, None)?.u.data.into(),
        };
        self.u = Some(u);
        self.time_s += dt_s;
        let x = self.true_platform_m().ok_or_else(|| {
            Error::invalid(
                "plant",
                "no platform",
                "the equilibrium has no platform coordinates",
            )
        })?;
        let measured: Vec<f64> = x
            .iter()
            .map(|v| v + self.noise_sigma_m * self.noise.sample())
            .collect();
        Ok(MarkerFrame {
            time_s: self.time_s,
            positions_m: vec![measured],
        })
    }

    fn time_s(&self) -> f64 {
        self.time_s
    }
}
