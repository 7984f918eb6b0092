//! The soft parallel robot (Figs. 7–8 of the paper): legs from a base
//! circle to a rigid platform, each leg a chain of pneumatic sections.
//!
//! Geometry: the legs are clamped at `z = 0` on the base circle of radius
//! `ρ_b`, at the angles `90° + 360° i / n`, and hang down (the platform is
//! below the base, the payload hangs from the platform) to the platform
//! circle of radius `ρ_p` at the same angles, at the depth
//! `h = √(L² − (ρ_b − ρ_p)²)`: straight legs of length `L`. The platform's
//! centre of mass is the centre of its circle.
//!
//! Each leg's end is joined rigidly to the platform
//! ([`crate::structure::BlockRule::SpatialRigidEnd`]): with the full 3-D
//! element ([`crate::element::Ancf3d`]) the joint holds the section frame,
//! so the legs resist the platform's twist by bending and by torsion; with
//! the spatial cable ([`crate::element::SpatialCable`]) it holds the
//! tangent only, and the legs resist the twist by bending alone.
//!
//! Each section has three chambers at `0°, 120°, 240°` about its axis,
//! measured from the section axis `e₂` of the leg's straight reference; a
//! chamber at `n = cos β e₂ + sin β e₃` bends the section away from itself:
//! its torque is `G P (n × t)` (`t` the leg's tangent), written in world
//! axes at the reference (the work `M · φ` of the node rotations makes it a
//! torque in the section frame for bending about a fixed axis).
//!
//! - [`ParallelSpec`]: the numbers ([`crate::params::parallel`] by default)
//!   and the checks; [`ParallelRobot`]: the built structure, its loads, its
//!   platform pose.
//! - [`payload`]: the payload estimation (32)–(35) from the platform
//!   position.

pub mod payload;
pub mod warm;

use serde::{Deserialize, Serialize};

use crate::element::{Ancf3d, Ancf3dStiffness, DEFAULT_GAUSS_POINTS, Element, SpatialCable};
use crate::error::{Error, Result, check_all_finite, check_at_most, check_len};
use crate::params::parallel as p;
use crate::statics::{Equilibrium, StaticSolver};
use crate::structure::{
    BodyLoad, Chamber, JointSpec, RigidBodySpec, RodEnd, RodSpec, Section, Structure,
    StructureLoads, StructureSpec,
};

/// Which element the legs are made of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LegElement {
    /// The spatial cable: no section frame, no torsion.
    SpatialCable,
    /// The full 3-D element: section frame and torsion.
    Ancf3d,
}

/// The numbers of a soft parallel robot.
///
/// # Example
/// ```
/// let spec = softrod::parallel::ParallelSpec::default();
/// assert_eq!(spec.legs, 3);
/// assert!(spec.platform_depth_m().unwrap() < spec.leg_length_m);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParallelSpec {
    /// Number of legs.
    #[serde(default = "default_legs")]
    pub legs: usize,
    /// Radius of the base circle (m).
    pub base_radius_m: f64,
    /// Radius of the circle the legs are joined to the platform on (m).
    pub platform_radius_m: f64,
    /// Radius of the platform itself (m): the joints must lie on it.
    #[serde(default = "default_disc")]
    pub platform_disc_radius_m: f64,
    /// Leg length (m).
    pub leg_length_m: f64,
    /// Sections per leg (three chambers each).
    pub sections_per_leg: usize,
    /// Elements per section.
    pub elements_per_section: usize,
    /// Axial stiffness EA (N).
    pub ea_n: f64,
    /// Bending stiffness EI (N·m²).
    pub ei_nm2: f64,
    /// Torsional stiffness GJ (N·m²; read by the full 3-D element only).
    pub gj_nm2: f64,
    /// Mass per length of a leg (kg/m).
    #[serde(default)]
    pub mass_per_length_kg_per_m: f64,
    /// Platform mass (kg).
    pub platform_mass_kg: f64,
    /// Torque per chamber pressure (N·m/Pa).
    pub gain_nm_per_pa: f64,
    /// Gravity (m/s²).
    #[serde(default = "default_gravity")]
    pub gravity_m_per_s2: Vec<f64>,
}

fn default_legs() -> usize {
    p::LEGS
}
fn default_disc() -> f64 {
    p::PLATFORM_DISC_RADIUS_M
}
fn default_gravity() -> Vec<f64> {
    vec![0.0, 0.0, -9.81]
}

impl Default for ParallelSpec {
    /// The robot of [`crate::params::parallel`].
    fn default() -> Self {
        ParallelSpec {
            legs: p::LEGS,
            base_radius_m: p::BASE_RADIUS_M,
            platform_radius_m: p::PLATFORM_RADIUS_M,
            platform_disc_radius_m: p::PLATFORM_DISC_RADIUS_M,
            leg_length_m: p::LEG_LENGTH_M,
            sections_per_leg: p::SECTIONS_PER_LEG,
            elements_per_section: p::ELEMENTS_PER_SECTION,
            ea_n: p::EA_N,
            ei_nm2: p::EI_NM2,
            gj_nm2: p::GJ_NM2,
            mass_per_length_kg_per_m: p::MASS_PER_LENGTH_KG_PER_M,
            platform_mass_kg: p::PLATFORM_MASS_KG,
            gain_nm_per_pa: p::GAIN_NM_PER_PA,
            gravity_m_per_s2: default_gravity(),
        }
    }
}

/// Chambers per section.
pub const CHAMBERS_PER_SECTION: usize = 3;

impl ParallelSpec {
    /// Checks the numbers, each error naming its field (`parallel.…`).
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] for a non-positive or non-finite length,
    /// radius or stiffness, legs that cannot reach the platform
    /// (`|ρ_b − ρ_p| >= L`), legs joined off the platform (`ρ_p` beyond
    /// `platform_disc_radius_m`), no legs, no sections or
    /// elements; [`Error::TooLarge`] for more than
    /// [`MAX_ELEMENTS`](crate::assembly::MAX_ELEMENTS) elements over all legs
    /// (naming the first count that overflows the room the ones before it
    /// leave: `legs`, `sections_per_leg`, `elements_per_section`);
    /// [`Error::DimensionMismatch`] for a gravity not of 3.
    ///
    /// # Example
    /// ```
    /// let mut spec = softrod::parallel::ParallelSpec::default();
    /// spec.leg_length_m = 0.0;
    /// assert_eq!(spec.validate().unwrap_err().field(), Some("parallel.leg_length_m"));
    /// ```
    pub fn validate(&self) -> Result<()> {
        let f = |n: &str| format!("parallel.{n}");
        for (name, v) in [
            ("leg_length_m", self.leg_length_m),
            ("ea_n", self.ea_n),
            ("ei_nm2", self.ei_nm2),
            ("gj_nm2", self.gj_nm2),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(f(name), v, "must be finite and > 0"));
            }
        }
        for (name, v) in [
            ("base_radius_m", self.base_radius_m),
            ("platform_radius_m", self.platform_radius_m),
            ("platform_disc_radius_m", self.platform_disc_radius_m),
            ("mass_per_length_kg_per_m", self.mass_per_length_kg_per_m),
            ("platform_mass_kg", self.platform_mass_kg),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(f(name), v, "must be finite and >= 0"));
            }
        }
        if !self.gain_nm_per_pa.is_finite() {
            return Err(Error::invalid(
                f("gain_nm_per_pa"),
                self.gain_nm_per_pa,
                "must be finite",
            ));
        }
        if self.legs == 0 {
            let why = if self.platform_mass_kg == 0.0 {
                "a platform with no mass and no legs is undetermined"
            } else {
                "a platform with no legs falls: it needs at least one leg"
            };
            return Err(Error::invalid(f("legs"), 0, why));
        }
        for (name, v) in [
            ("sections_per_leg", self.sections_per_leg),
            ("elements_per_section", self.elements_per_section),
        ] {
            if v == 0 {
                return Err(Error::invalid(f(name), v, "must be >= 1"));
            }
        }
        // the one element limit (`assembly::MAX_ELEMENTS`) over all legs,
        // checked before the legs are laid out: each count against the room
        // the counts before it leave
        let max = crate::assembly::MAX_ELEMENTS;
        check_at_most(&f("legs"), self.legs, max)?;
        check_at_most(
            &f("sections_per_leg"),
            self.sections_per_leg,
            max / self.legs,
        )?;
        check_at_most(
            &f("elements_per_section"),
            self.elements_per_section,
            max / (self.legs * self.sections_per_leg),
        )?;
        if self.platform_radius_m > self.platform_disc_radius_m {
            return Err(Error::invalid(
                f("platform_radius_m"),
                self.platform_radius_m,
                format!(
                    "joins the legs off the platform (`parallel.platform_disc_radius_m` = {} m)",
                    self.platform_disc_radius_m
                ),
            ));
        }
        let gap = (self.base_radius_m - self.platform_radius_m).abs();
        if gap >= self.leg_length_m {
            return Err(Error::invalid(
                f("leg_length_m"),
                self.leg_length_m,
                format!(
                    "legs must be longer than the difference of `parallel.base_radius_m` = {} m \
                     and `parallel.platform_radius_m` = {} m ({gap:e} m) to reach the platform",
                    self.base_radius_m, self.platform_radius_m
                ),
            ));
        }
        check_len(&f("gravity_m_per_s2"), 3, self.gravity_m_per_s2.len())?;
        check_all_finite(&f("gravity_m_per_s2"), &self.gravity_m_per_s2)?;
        Ok(())
    }

    /// Depth of the platform below the base, `√(L² − (ρ_b − ρ_p)²)` (m).
    ///
    /// # Errors
    /// As [`ParallelSpec::validate`].
    pub fn platform_depth_m(&self) -> Result<f64> {
        self.validate()?;
        let gap = self.base_radius_m - self.platform_radius_m;
        Ok((self.leg_length_m.powi(2) - gap * gap).sqrt())
    }

    /// The angle of leg `i` about the vertical axis (rad).
    pub fn leg_angle(&self, i: usize) -> f64 {
        std::f64::consts::FRAC_PI_2 + std::f64::consts::TAU * i as f64 / self.legs.max(1) as f64
    }

    /// Gravity as a 3-D vector (m/s²).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] named `parallel.gravity_m_per_s2` if it
    /// does not have three entries.
    ///
    /// # Example
    /// ```
    /// let spec = softrod::parallel::ParallelSpec::default();
    /// assert_eq!(spec.gravity()?, nalgebra::Vector3::new(0.0, 0.0, -9.81));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn gravity(&self) -> Result<nalgebra::Vector3<f64>> {
        crate::numeric::fixed("parallel.gravity_m_per_s2", &self.gravity_m_per_s2)
    }

    /// The platform's reference position (m): the centre of its circle.
    ///
    /// # Errors
    /// As [`ParallelSpec::validate`].
    ///
    /// # Example
    /// ```
    /// let spec = softrod::parallel::ParallelSpec::default();
    /// let x0 = spec.platform_reference_m()?;
    /// assert_eq!(x0, nalgebra::Vector3::new(0.0, 0.0, -spec.platform_depth_m()?));
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn platform_reference_m(&self) -> Result<nalgebra::Vector3<f64>> {
        Ok(nalgebra::Vector3::new(0.0, 0.0, -self.platform_depth_m()?))
    }

    /// The leg's unit tangent and the section axes `e₂`, `e₃` of its
    /// straight reference (those the full 3-D element carries).
    fn leg_frame(&self, i: usize, h: f64) -> [[f64; 3]; 3] {
        use crate::element::NodeKinematics;
        let a = self.leg_angle(i);
        let (s, c) = a.sin_cos();
        let d = self.platform_radius_m - self.base_radius_m;
        let l = self.leg_length_m;
        let t = [d * c / l, d * s / l, -h / l];
        let n = Ancf3d::straight_node(&[0.0; 3], &t);
        [t, [n[6], n[7], n[8]], [n[9], n[10], n[11]]]
    }

    /// Number of chamber pressures: legs × sections × 3, leg-major, then
    /// section, then chamber.
    pub fn n_pressures(&self) -> usize {
        self.legs * self.sections_per_leg * CHAMBERS_PER_SECTION
    }

    /// The structure: one rod per leg (clamped at the base, its end joined
    /// to the platform), the platform (body 0).
    ///
    /// # Errors
    /// As [`ParallelSpec::validate`].
    ///
    /// # Example
    /// ```
    /// let s = softrod::parallel::ParallelSpec::default().structure_spec().unwrap();
    /// assert_eq!((s.rods.len(), s.joints.len()), (3, 3));
    /// ```
    pub fn structure_spec(&self) -> Result<StructureSpec> {
        let h = self.platform_depth_m()?;
        let ls = self.leg_length_m / self.sections_per_leg as f64;
        let mut rods = Vec::with_capacity(self.legs);
        let mut joints = Vec::with_capacity(self.legs);
        for i in 0..self.legs {
            let (s, c) = self.leg_angle(i).sin_cos();
            let [t, e2, e3] = self.leg_frame(i, h);
            let chambers: Vec<Chamber> = (0..CHAMBERS_PER_SECTION)
                .map(|k| {
                    let (sb, cb) = (std::f64::consts::TAU * k as f64 / 3.0).sin_cos();
                    let n: [f64; 3] = std::array::from_fn(|j| cb * e2[j] + sb * e3[j]);
                    // n × t
                    let m = [
                        n[1] * t[2] - n[2] * t[1],
                        n[2] * t[0] - n[0] * t[2],
                        n[0] * t[1] - n[1] * t[0],
                    ];
                    Chamber {
                        gain_nm_per_pa: m.iter().map(|x| x * self.gain_nm_per_pa).collect(),
                        pressure_min_pa: crate::params::PRESSURE_MIN_PA,
                        pressure_max_pa: crate::params::PRESSURE_MAX_PA,
                    }
                })
                .collect();
            let sections = (0..self.sections_per_leg)
                .map(|_| {
                    let mut sec =
                        Section::uniform(ls, self.ea_n, self.ei_nm2, self.elements_per_section);
                    sec.mass_per_length_kg_per_m = self.mass_per_length_kg_per_m;
                    sec.chambers = chambers.clone();
                    sec
                })
                .collect();
            rods.push(RodSpec::clamped(
                sections,
                nalgebra::Vector3::new(self.base_radius_m * c, self.base_radius_m * s, 0.0),
                nalgebra::Vector3::from(t),
            ));
            joints.push(JointSpec::RodToBody {
                rod: i,
                end: RodEnd::End,
                body: 0,
                point_m: Some(vec![
                    self.platform_radius_m * c,
                    self.platform_radius_m * s,
                    0.0,
                ]),
                direction: None,
            });
        }
        let mut spec = StructureSpec::new(
            rods,
            vec![RigidBodySpec {
                mass_kg: self.platform_mass_kg,
                position_m: vec![0.0, 0.0, -h],
                orientation_rad: vec![0.0; 3],
            }],
            joints,
        );
        spec.gravity_m_per_s2 = self.gravity_m_per_s2.clone();
        Ok(spec)
    }

    /// The robot with legs of the full 3-D element.
    ///
    /// # Errors
    /// As [`ParallelSpec::validate`] and [`Structure::new`].
    pub fn build_full(&self) -> Result<ParallelRobot<Ancf3d>> {
        let gj = self.gj_nm2;
        let s = Structure::new(self.structure_spec()?, move |sec, le, _, be| {
            let mut k = Ancf3dStiffness::isotropic(sec.ea_n, sec.ei_nm2, gj);
            k.ei_z_nm2 = sec.ei_nm2;
            Ancf3d::with_stiffness(le, k, be.max(DEFAULT_GAUSS_POINTS))
        })?;
        Ok(ParallelRobot::new(self.clone(), s))
    }

    /// The robot with legs of the spatial cable.
    ///
    /// # Errors
    /// As [`ParallelSpec::validate`] and [`Structure::new`].
    pub fn build_cable(&self) -> Result<ParallelRobot<SpatialCable>> {
        let s = Structure::new(self.structure_spec()?, |sec, le, ax, be| {
            SpatialCable::with_rules(le, sec.ea_n, sec.ei_nm2, ax, be)
        })?;
        Ok(ParallelRobot::new(self.clone(), s))
    }
}

/// A built soft parallel robot: its structure and how to load it.
///
/// # Example
/// ```
/// use softrod::parallel::ParallelSpec;
/// let robot = ParallelSpec::default().build_full()?;
/// let loads = robot.loads(&[], [0.0, 0.0, -0.5], [0.0; 3])?;
/// let eq = robot.solve(&loads, None)?;
/// // the platform sinks under its weight and the 0.5 N load
/// assert!(robot.platform_pose(eq.q.as_slice())?[2] < robot.spec().platform_reference_m()?[2]);
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone)]
pub struct ParallelRobot<E: Element> {
    spec: ParallelSpec,
    structure: Structure<E>,
}

impl<E: Element> ParallelRobot<E> {
    fn new(spec: ParallelSpec, structure: Structure<E>) -> Self {
        ParallelRobot { spec, structure }
    }

    /// The robot's numbers.
    pub fn spec(&self) -> &ParallelSpec {
        &self.spec
    }

    /// The structure (rods = legs, body 0 = the platform).
    pub fn structure(&self) -> &Structure<E> {
        &self.structure
    }

    /// Loads: the chamber pressures (Pa; [`ParallelSpec::n_pressures`] or
    /// none), a force (N) and a moment (N·m) on the platform at its centre
    /// (world axes; `Vector3`s, or `[f64; 3]` arrays).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] (`pressures_pa`) for a wrong count,
    /// [`Error::InvalidParameter`] for non-finite numbers.
    ///
    /// # Example
    /// ```
    /// use nalgebra::Vector3;
    /// let robot = softrod::parallel::ParallelSpec::default().build_cable()?;
    /// let a = robot.loads(&[], Vector3::new(0.0, 0.0, -0.1), Vector3::zeros())?;
    /// assert_eq!(a, robot.loads(&[], [0.0, 0.0, -0.1], [0.0; 3])?);
    /// assert_eq!(a.bodies[0].force::<3>()?.z, -0.1);
    /// assert!(robot.loads(&[1.0], [0.0; 3], [0.0; 3]).is_err());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn loads(
        &self,
        pressures_pa: &[f64],
        force_n: impl Into<nalgebra::Vector3<f64>>,
        moment_nm: impl Into<nalgebra::Vector3<f64>>,
    ) -> Result<StructureLoads> {
        let (force_n, moment_nm) = (force_n.into(), moment_nm.into());
        let n = self.spec.n_pressures();
        if !pressures_pa.is_empty() {
            check_len("pressures_pa", n, pressures_pa.len())?;
        }
        check_all_finite("pressures_pa", pressures_pa)?;
        check_all_finite("force_n", force_n.as_slice())?;
        check_all_finite("moment_nm", moment_nm.as_slice())?;
        let per_leg = n / self.spec.legs.max(1);
        let rods = if pressures_pa.is_empty() {
            Vec::new()
        } else {
            pressures_pa
                .chunks(per_leg)
                .map(|p| crate::loads::Loads {
                    pressures_pa: p.to_vec(),
                    ..Default::default()
                })
                .collect()
        };
        Ok(StructureLoads {
            rods,
            bodies: vec![BodyLoad {
                body: 0,
                force_n: force_n.as_slice().to_vec(),
                moment_nm: moment_nm.as_slice().to_vec(),
            }],
        })
    }

    /// The platform's pose `(x, ψ)` (m, rad: position of its centre and
    /// rotation vector) in a configuration `q`: `[x, y, z, ψx, ψy, ψz]`
    /// (`pose.fixed_rows::<3>(0)` is the position, `fixed_rows::<3>(3)`
    /// the rotation vector).
    ///
    /// # Errors
    /// [`Error::DimensionMismatch`] for a `q` of the wrong size.
    ///
    /// # Example
    /// ```
    /// let robot = softrod::parallel::ParallelSpec::default().build_cable()?;
    /// let eq = robot.solve(&robot.loads(&[], [0.0; 3], [0.0; 3])?, None)?;
    /// let pose = robot.platform_pose(eq.q.as_slice())?;
    /// // unloaded and unpressurized: where the reference puts it, not turned
    /// assert!((pose.fixed_rows::<3>(0) - robot.spec().platform_reference_m()?).norm() < 1e-3);
    /// assert!(pose.fixed_rows::<3>(3).norm() < 1e-9);
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn platform_pose(&self, q: &[f64]) -> Result<nalgebra::Vector6<f64>> {
        check_len("q", self.structure.n_q(), q.len())?;
        let r = self.structure.body_coordinates(0)?;
        Ok(nalgebra::Vector6::from_fn(|k, _| q[r.start + k]))
    }

    /// The index in the free coordinates `u` of the platform's position
    /// (its three coordinates follow each other).
    ///
    /// # Errors
    /// None for a built robot (its platform is body 0).
    pub fn platform_free_start(&self) -> Result<usize> {
        Ok(self.structure.body_free_coordinates(0)?.start)
    }

    /// The static equilibrium under `loads`, from `q0` or the straight
    /// reference.
    ///
    /// # Errors
    /// As [`StaticSolver::solve`] (a solve that does not converge is an error).
    pub fn solve(&self, loads: &StructureLoads, q0: Option<&[f64]>) -> Result<Equilibrium> {
        StaticSolver::default().solve(&self.structure, loads, q0)
    }
}
