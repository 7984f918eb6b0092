//! One grasp trial, quasi-static: the gripper closes on an object resting
//! on a table, lifts it, and the friction check decides whether it holds.
//!
//! # The scene
//! The palm at `y = 0`, fingers hanging down; the table top
//! `table_clearance_m` below the straight fingertips' surface; the object
//! is set down on it (its lowest point on the table), shifted sideways by
//! the placement's offset and turned by its angle (both randomized in
//! Table I), and comes to rest as a planar rigid body under gravity with
//! the table's friction `table_mu` (`crate::grasp::rest`): a disc rests
//! where it is set down, an ellipse rolls back onto its flat side, a
//! rectangle or rounded square set down on a corner tips until it lies on
//! a face (measured: the tape measure set down turned by −0.138 rad lies
//! flat 3.4 mm further left; before this it stood turned on its corner, the
//! fingers touched it 30 mm apart in height, and after the lift it turned in
//! the pinch by 0.22 rad and slipped by 16.6 mm). The fingers' pushes
//! move it on the table only with `push_object_on_table` (default off: it
//! stays where it came to rest).
//!
//! # The strategies
//! - **Open loop** (the baseline of the paper's ref. \[53\]): the proximal
//!   segments' inward chambers ramp linearly to a predetermined pressure
//!   (default: the pressure at which the free model's fingertips meet at
//!   the centreline) over `open_loop_ramp_s`, then stay; no feedback.
//! - **Adaptive** (45)–(52), per finger, at `control_rate_hz`: the estimator
//!   ([`crate::estimate`], on the controller's model, from the plant's
//!   noisy markers) gives the load field `F̄`; the virtual payload (the
//!   estimates recorded while nothing touches, keyed by the pressures: a
//!   payload-free run of the approach law, `calibration_frames` marker
//!   frames estimated at each pressure, their mean recorded and their
//!   scatter measuring the estimate's noise) is subtracted; contact is
//!   detected when the remainder's resultant, averaged over three
//!   estimates, exceeds `contact_threshold_n` and is beyond the measured
//!   noise (χ² test at `contact_false_alarm_probability` per control
//!   instant). Measured without the test: 12 of the 90 fingers of Table I
//!   took noise for a contact, and in the ruler's try 0 a finger touching
//!   with 0.04 N detected 0.28 N (mostly noise), turned off the ruler and
//!   never came back; payload-free runs on other noise: 2 of 20 fingers
//!   detected a contact with the threshold alone, 0 of 20 with the test.
//!   The contact point is where the remainder peaks. Before contact the pose (49) is taken at the
//!   fingertip and (51) moves it inward at `u1` while keeping it vertical
//!   (the paper ramps the proximal segment instead: in this geometry that
//!   lifts the fingertips by about 12 mm and misses low objects, measured
//!   by the open-loop trials). A bent finger is shorter than a straight
//!   one, so the fingertips rise as they close (25 mm at 55 mm of travel):
//!   while a finger approaches, the arm lowers the palm by the fingertips'
//!   rise as the controller estimates it (the smaller of the approaching
//!   fingers', less 1 mm; measured: stopping at the first contact let the
//!   second fingertip pass over the marking pen), keeping the object's top `palm_clearance_m` below the
//!   palm (measured: without it the fingertips passed over the marking pen
//!   and the walnut, "missed"). The contact solver takes no obstacle that
//!   overlaps the straight fingers, so once the palm is lower than the
//!   table clearance the table is left out of the plant (the fingertips,
//!   risen with the palm's descent, stay above it); after contact (51) pushes the contact point
//!   inward at `u1` and turns the finger to `θ = 0` at `u2`; when a pressure
//!   comes within `bound_margin` of its upper bound, (52) turns only, and
//!   once `|θ| < theta_tolerance_rad` the pressures are held.
//!
//! # Success
//! After closing, the gripper lifts by `lift_height_m`: the table no longer
//! supports the object, the plant is solved again at the held pressures, and
//! the friction check ([`crate::grasp::friction::hold_check`]) is run on
//! the fingers' contact forces (normal forces as the bound of each contact's
//! push, friction cones about the object's own outline at each contact,
//! [`GraspObject::surface_normal`]). While the weight is not balanced inside
//! the friction cones (weight factor `< 1`) the object moves as a planar
//! rigid body (position and rotation): quasi-static steps along the
//! acceleration the contacts of least constraint leave it (at most
//! `slip_step_m` for any contact point or its centre of mass, at most
//! 0.02 rad), the fingers solved against it again at the held pressures
//! after each, until it holds or a finger loses it (dropped). An unequal
//! pinch turns a thin object until its contacts line up. The slip is the
//! sliding at the contacts: the tangential relative displacement of the
//! object's and the finger's material points that touched, summed over the
//! steps (an object that rolls on the fingertips as it turns does not
//! slip). The trial succeeds iff the object is held after the lift with a
//! slip `<= max_slip_m`; with the pressures held and no creep in this
//! quasi-static model, a held object stays through the hold time
//! `hold_time_s`. A plant contact solve that does not converge ends the
//! trial as a failure with the solver's status.

use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::contact::{Obstacle, Obstacles};
use crate::control::VirtualPayload;
use crate::element::PlanarCable;
use crate::error::{Error, Result};
use crate::estimate::{Estimator, EstimatorSettings};
use crate::grasp::friction::{FrictionContact, HoldCheck};
use crate::grasp::gripper::{FINGER_PRESSURES, GripperSpec, Side};
use crate::grasp::object::{GraspObject, Pose};
use crate::grasp::plant::{FingerState, GripperPlant, GripperPlantSettings, PlantStep};
use crate::grasp::rest::{TableTop, rest_on_table};
use crate::grasp::slip::{Grip, Touch, settle};
use crate::grasp::strategy::{bounded_step, contact_jacobian, contact_pose};
use crate::loads::Loads;
use crate::outcome::ContactStatus;
use crate::statics::StaticSolver;

mod finger;
mod lift;
mod record;
mod simulate;
use finger::{FingerController, calibrate};
use lift::{friction_contacts, lifted_grip};
use record::{Stop, contact_records};
use simulate::{Scene, simulate};

/// Which grasp strategy.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum Strategy {
    /// (45)–(52) with the estimator.
    Adaptive,
    /// Proximal segments to a predetermined pressure, no feedback
    /// (`open_loop`; the older spelling `open-loop` is read too).
    #[serde(alias = "open-loop")]
    OpenLoop,
}

impl Strategy {
    /// The name used on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Strategy::Adaptive => "adaptive",
            Strategy::OpenLoop => "open_loop",
        }
    }
}

/// Settings of a trial; every field has a documented default.
///
/// # Example
/// ```
/// let s = softrod::grasp::trial::GraspSettings::default();
/// assert_eq!((s.control_rate_hz, s.u1_m_per_s), (20.0, 0.03));
/// s.validate()?;
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct GraspSettings {
    /// Control rate `f_c` (Hz; paper: 20).
    pub control_rate_hz: f64,
    /// Speed of the contact point toward the centreline `u1` (m/s; paper: 30 mm/s).
    pub u1_m_per_s: f64,
    /// Turning rate `u2` (rad/s; paper: π/24).
    pub u2_rad_per_s: f64,
    /// Contact is detected when the estimated load minus the virtual
    /// payload (averaged over the last three estimates) has a resultant
    /// above this (N; default 0.25, above the noise of the estimate).
    pub contact_threshold_n: f64,
    /// Marker frames estimated at each pressure of the payload-free
    /// calibration run: their mean is the virtual payload's record there, their
    /// scatter measures the estimate's noise (default 4; at least 2).
    pub calibration_frames: usize,
    /// A contact is detected only where the averaged resultant is also
    /// beyond the measured noise: noise alone passes this test with this
    /// probability per control instant (χ² test with two degrees of
    /// freedom; default 1e-4).
    pub contact_false_alarm_probability: f64,
    /// (52) takes over when a pressure is within this fraction of its
    /// upper bound (default 0.05).
    pub bound_margin: f64,
    /// The pressures are held once `|θ|` is below this (rad; default 0.03).
    pub theta_tolerance_rad: f64,
    /// After contact, (52) replaces (51) while `|θ|` exceeds this (rad;
    /// default 0.1): a contact blocks the contact point, so the pressures
    /// (51) adds to move it turn the finger instead (measured: without the
    /// band `θ` drifted to −0.3 rad within 1 s on a 60 mm disc).
    pub theta_band_rad: f64,
    /// Longest closing phase (s; default 12: measured, the red apple's
    /// grasp reaches the pressure bound and squares the fingertips after
    /// 11 s; with 6 s it stopped at 80 % of the bound, |θ| = 0.1).
    pub max_time_s: f64,
    /// Table top below the straight fingertips' surface (m; default 0.004).
    pub table_clearance_m: f64,
    /// Friction coefficient between the object and the table (default 0.4:
    /// plastic, fruit skin or cardboard on a laminated table top).
    pub table_mu: f64,
    /// Whether the fingers' pushes move the object on the table while the
    /// gripper closes (default false: it stays where it came to rest, held
    /// by the table). Measured with true on Table I: the green apple, pushed
    /// 12 mm by the first finger, reached the other finger's straight
    /// shape, an obstacle the plant's contact solver refuses; a marking pen
    /// pushed on the table was dropped after the lift.
    pub push_object_on_table: bool,
    /// Lift height (m; default 0.05): quasi-static, it only removes the table.
    pub lift_height_m: f64,
    /// Hold time (s; default 3): quasi-static, see the module docs.
    pub hold_time_s: f64,
    /// Largest slip of a success: the sliding at the contacts after the
    /// lift (m; default 0.005).
    pub max_slip_m: f64,
    /// An approaching finger has missed when its fingertip's surface is
    /// this far past the centreline (m; default 0.012: the largest
    /// placement offset of Table I, 6 mm, plus the 0.15 s of travel the
    /// averaged contact detection lags at `u1`, 4.5 mm). The plant has no
    /// finger–finger contact: past the centreline the fingers may cross.
    pub miss_overshoot_m: f64,
    /// Step of a slipping object: the largest move of its centre of mass or
    /// of a contact point per step (m; default 0.002).
    pub slip_step_m: f64,
    /// During the approach the palm is lowered at most until the object's
    /// top is this far below it (m; default 0.005).
    pub palm_clearance_m: f64,
    /// Ramp time of the open-loop strategy (s; default 2).
    pub open_loop_ramp_s: f64,
    /// Open-loop proximal pressure (Pa); `None` (default): where the free
    /// model's fingertips meet at the centreline.
    pub open_loop_pressure_pa: Option<f64>,
    /// The estimator's regularization weight `α` (m/N², whitened weights;
    /// default 1). The discrepancy principle picks `α` on the first frame,
    /// where nothing touches and the markers fit to the noise: it then
    /// shrank the contact load so much (a 0.9 N contact estimated below
    /// 0.1 N, measured) that contact went undetected.
    pub estimator_alpha: f64,
    /// Marker arc coordinates on each finger (m; default four, every 25 mm).
    pub markers_s_m: Vec<f64>,
    /// How the plant differs from the model.
    pub plant: GripperPlantSettings,
}

impl Default for GraspSettings {
    fn default() -> Self {
        GraspSettings {
            control_rate_hz: 20.0,
            u1_m_per_s: 0.03,
            u2_rad_per_s: std::f64::consts::PI / 24.0,
            contact_threshold_n: 0.25,
            calibration_frames: 4,
            contact_false_alarm_probability: 1e-4,
            bound_margin: 0.05,
            theta_tolerance_rad: 0.03,
            theta_band_rad: 0.1,
            max_time_s: 12.0,
            table_clearance_m: 0.004,
            table_mu: 0.4,
            push_object_on_table: false,
            lift_height_m: 0.05,
            hold_time_s: 3.0,
            max_slip_m: 0.005,
            miss_overshoot_m: 0.012,
            slip_step_m: 0.002,
            palm_clearance_m: 0.005,
            open_loop_ramp_s: 2.0,
            open_loop_pressure_pa: None,
            estimator_alpha: 1.0,
            markers_s_m: vec![0.025, 0.05, 0.075, 0.1],
            plant: GripperPlantSettings::default(),
        }
    }
}

impl GraspSettings {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the field (`settings.<field>`).
    pub fn validate(&self) -> Result<()> {
        for (n, v) in [
            ("control_rate_hz", self.control_rate_hz),
            ("u1_m_per_s", self.u1_m_per_s),
            ("u2_rad_per_s", self.u2_rad_per_s),
            ("contact_threshold_n", self.contact_threshold_n),
            ("bound_margin", self.bound_margin),
            ("theta_tolerance_rad", self.theta_tolerance_rad),
            ("theta_band_rad", self.theta_band_rad),
            ("max_time_s", self.max_time_s),
            ("table_clearance_m", self.table_clearance_m),
            ("lift_height_m", self.lift_height_m),
            ("hold_time_s", self.hold_time_s),
            ("max_slip_m", self.max_slip_m),
            ("slip_step_m", self.slip_step_m),
            ("miss_overshoot_m", self.miss_overshoot_m),
            ("palm_clearance_m", self.palm_clearance_m),
            ("open_loop_ramp_s", self.open_loop_ramp_s),
            ("estimator_alpha", self.estimator_alpha),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(
                    format!("settings.{n}"),
                    v,
                    "must be finite and > 0",
                ));
            }
        }
        if self.calibration_frames < 2 || self.calibration_frames > 1000 {
            return Err(Error::invalid(
                "settings.calibration_frames",
                self.calibration_frames,
                "must be 2 to 1000: the noise is measured from their scatter",
            ));
        }
        let p = self.contact_false_alarm_probability;
        if !(p.is_finite() && p > 0.0 && p < 1.0) {
            return Err(Error::invalid(
                "settings.contact_false_alarm_probability",
                p,
                "must be in (0, 1)",
            ));
        }
        if self.max_time_s * self.control_rate_hz > 10_000.0 {
            return Err(Error::invalid(
                "settings.max_time_s",
                self.max_time_s,
                "at most 10000 control steps",
            ));
        }
        if !(self.table_mu.is_finite() && self.table_mu >= 0.0) {
            return Err(Error::invalid(
                "settings.table_mu",
                self.table_mu,
                "must be finite and >= 0",
            ));
        }
        if let Some(p) = self.open_loop_pressure_pa
            && !(p.is_finite() && p >= 0.0)
        {
            return Err(Error::invalid(
                "settings.open_loop_pressure_pa",
                p,
                "must be finite and >= 0",
            ));
        }
        if self.markers_s_m.is_empty() {
            return Err(Error::invalid(
                "settings.markers_s_m",
                "[]",
                "needs at least one marker",
            ));
        }
        self.plant.validate()
    }
}

/// Where the object is put: sideways offset of its centre from the
/// gripper's centreline and its rotation.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Placement {
    /// Offset of the object's bounding box centre from `x = 0` (m).
    pub offset_m: f64,
    /// Rotation of the object (rad).
    pub angle_rad: f64,
}

/// A finger controller's phase.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Phase {
    /// No contact yet.
    Approach,
    /// (51): push the contact point inward, square the finger.
    Squeeze,
    /// (52): a pressure is near its bound; square the finger only.
    Align,
    /// Pressures held.
    Hold,
    /// The open-loop ramp.
    Ramp,
}

/// One contact force on the object, for reports.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ContactRecord {
    /// The finger.
    pub side: Side,
    /// Point on the object's surface (m).
    pub point_m: [f64; 2],
    /// Unit normal into the object (the finger's push).
    pub normal: [f64; 2],
    /// Normal force (N).
    pub force_n: f64,
}

impl ContactRecord {
    /// The contact point as a vector (m; the field `point_m`).
    ///
    /// # Example
    /// ```
    /// use softrod::grasp::{gripper::Side, trial::ContactRecord};
    /// let c = ContactRecord { side: Side::Left, point_m: [-0.03, -0.08], normal: [1.0, 0.0], force_n: 0.5 };
    /// assert_eq!(c.point(), nalgebra::Vector2::new(-0.03, -0.08));
    /// assert_eq!(c.force(), nalgebra::Vector2::new(0.5, 0.0));
    /// ```
    pub fn point(&self) -> nalgebra::Vector2<f64> {
        self.point_m.into()
    }

    /// The normal force on the object as a vector (N): `force_n` along `normal`.
    ///
    /// # Example
    /// See [`ContactRecord::point`].
    pub fn force(&self) -> nalgebra::Vector2<f64> {
        nalgebra::Vector2::from(self.normal) * self.force_n
    }

    /// The unit normal into the object as a vector (the field `normal`).
    ///
    /// # Example
    /// ```
    /// use softrod::grasp::{gripper::Side, trial::ContactRecord};
    /// let c = ContactRecord { side: Side::Right, point_m: [0.03, -0.08], normal: [-1.0, 0.0], force_n: 0.5 };
    /// assert_eq!(c.unit_normal(), -nalgebra::Vector2::x());
    /// ```
    pub fn unit_normal(&self) -> nalgebra::Vector2<f64> {
        self.normal.into()
    }
}

/// The state after one control interval.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Frame {
    /// Time (s).
    pub time_s: f64,
    /// Each finger's phase.
    pub phases: [Phase; 2],
    /// Each finger's pressures (Pa).
    pub pressures_pa: [Vec<f64>; 2],
    /// Each finger's centreline (the plant's nodes, m).
    pub centreline_m: [Vec<[f64; 2]>; 2],
    /// Contacts on the object.
    pub contacts: Vec<ContactRecord>,
    /// The adaptive controller's contact pose `[p_x, p_y, θ]` per finger.
    pub contact_pose: [Option<[f64; 3]>; 2],
    /// The object's centre of mass in the palm's frame (m).
    pub object_position_m: [f64; 2],
    /// The object's rotation (rad, counter-clockwise; it turns after the lift).
    pub object_angle_rad: f64,
}

impl Frame {
    /// The finger's index in the per-finger fields (left 0, right 1).
    fn index(side: Side) -> usize {
        match side {
            Side::Left => 0,
            Side::Right => 1,
        }
    }

    /// The object's centre of mass as a vector (m; the field `object_position_m`).
    ///
    /// # Example
    /// ```
    /// use softrod::grasp::{gripper::Side, trial::{Frame, Phase}};
    /// let f = Frame {
    ///     time_s: 0.05,
    ///     phases: [Phase::Approach; 2],
    ///     pressures_pa: [vec![1e3, 0.0, 0.0, 0.0], vec![2e3, 0.0, 0.0, 0.0]],
    ///     centreline_m: [vec![[-0.055, 0.0], [-0.055, -0.1]], vec![[0.055, 0.0], [0.055, -0.1]]],
    ///     contacts: vec![],
    ///     contact_pose: [Some([-0.05, -0.1, 0.01]), None],
    ///     object_position_m: [0.001, -0.09],
    ///     object_angle_rad: 0.0,
    /// };
    /// assert_eq!(f.object_position(), nalgebra::Vector2::new(0.001, -0.09));
    /// assert_eq!(f.pressures(Side::Right), nalgebra::dvector![2e3, 0.0, 0.0, 0.0]);
    /// assert_eq!(f.centreline(Side::Left)[1], nalgebra::Vector2::new(-0.055, -0.1));
    /// assert_eq!(f.contact_pose(Side::Left), Some(nalgebra::Vector3::new(-0.05, -0.1, 0.01)));
    /// assert_eq!(f.contact_pose(Side::Right), None);
    /// ```
    pub fn object_position(&self) -> nalgebra::Vector2<f64> {
        self.object_position_m.into()
    }

    /// One finger's pressures (Pa; the field `pressures_pa`).
    ///
    /// # Example
    /// See [`Frame::object_position`].
    pub fn pressures(&self, side: Side) -> nalgebra::DVector<f64> {
        nalgebra::DVector::from_column_slice(&self.pressures_pa[Self::index(side)])
    }

    /// One finger's centreline points (m; the field `centreline_m`).
    ///
    /// # Example
    /// See [`Frame::object_position`].
    pub fn centreline(&self, side: Side) -> Vec<nalgebra::Vector2<f64>> {
        self.centreline_m[Self::index(side)]
            .iter()
            .map(|p| nalgebra::Vector2::from(*p))
            .collect()
    }

    /// One finger's contact pose `[p_x, p_y, θ]` (m, m, rad; the field
    /// `contact_pose`), if its controller computed one.
    ///
    /// # Example
    /// See [`Frame::object_position`].
    pub fn contact_pose(&self, side: Side) -> Option<nalgebra::Vector3<f64>> {
        self.contact_pose[Self::index(side)].map(nalgebra::Vector3::from)
    }
}

/// Why a trial failed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(tag = "cause", rename_all = "snake_case")]
pub enum Failure {
    /// The object cannot be held after the lift: it slid by more than
    /// `max_slip_m` before the contacts held it.
    Slips {
        /// The largest weight factor the contacts balance right after the lift.
        weight_factor: f64,
        /// How far it slid (m).
        slip_m: f64,
    },
    /// The object slid out of the fingers (one finger lost it).
    Dropped {
        /// The largest weight factor the contacts balance right after the lift.
        weight_factor: f64,
        /// How far it slid until then (m).
        slip_m: f64,
    },
    /// A finger passed the centreline by `miss_overshoot_m` or reached its
    /// pressure bound without detecting contact.
    Missed {
        /// The finger.
        side: Side,
    },
    /// The plant's contact solve did not converge.
    PlantSolve {
        /// The finger.
        side: Side,
        /// The contact solver's status (never converged).
        status: ContactStatus,
    },
    /// The object's motion on the table could not be computed (its
    /// least-constraint program was not solved).
    ObjectMotion {
        /// The solver's message.
        message: String,
    },
    /// The controller could not compute a step (estimator or Jacobian).
    Controller {
        /// The error.
        message: String,
    },
}

/// The result of a trial.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialOutcome {
    /// The object's name.
    pub object: String,
    /// The strategy.
    pub strategy: Strategy,
    /// The placement.
    pub placement: Placement,
    /// The object's pose on the table, in the palm's frame at the start.
    pub pose: Pose,
    /// The object's pose at the end (m, rad; palm frame): lowered palm and
    /// slip included.
    pub final_pose: Pose,
    /// How far the object slid at the contacts after the lift (m; module docs).
    pub slip_m: f64,
    /// The object as an obstacle (for drawings).
    pub outline: Obstacle,
    /// Whether the grasp held.
    pub success: bool,
    /// Why not.
    pub failure: Option<Failure>,
    /// The friction check right after the lift (when the trial got there).
    pub hold: Option<HoldCheck>,
    /// The heaviest object of this geometry the final grasp holds (kg).
    pub holding_mass_kg: f64,
    /// The largest distance between a finger's estimated contact point and
    /// its true one at the end (m; adaptive only, fingers in contact).
    pub contact_estimate_error_m: Option<f64>,
    /// Every control interval, the last one after the lift.
    pub frames: Vec<Frame>,
}

/// The object's pose on the table for `placement`.
fn resting_pose(object: &GraspObject, placement: &Placement, table_y: f64) -> Pose {
    let probe = Pose {
        position_m: [0.0, 0.0],
        angle_rad: placement.angle_rad,
    };
    let b = object.bounds(&probe);
    Pose {
        position_m: [placement.offset_m - 0.5 * (b[0] + b[1]), table_y - b[2]],
        angle_rad: placement.angle_rad,
    }
}

/// The pressure at which the free model's fingertips meet at the centreline
/// (proximal inward chambers only), by bisection; the upper bound if they
/// never do.
///
/// # Errors
/// Static solve failures.
pub fn meeting_pressure_pa(gripper: &GripperSpec) -> Result<f64> {
    let f = gripper.finger(Side::Left)?;
    let solver = StaticSolver::default();
    let gap = |p: f64, q0: Option<&[f64]>| -> Result<(f64, Vec<f64>)> {
        let loads = Loads {
            pressures_pa: vec![p, 0.0, 0.0, 0.0],
            ..Loads::default()
        };
        let q: Vec<f64> = solver.solve(&f, &loads, q0)?.q.data.into();
        let tip = f.position_at(q.as_slice(), gripper.finger_length_m())?;
        Ok((-(tip[0] + gripper.finger_radius_m), q))
    };
    let (mut lo, mut hi) = (0.0, gripper.pressure_max_pa);
    let (g_hi, _) = gap(hi, None)?;
    if g_hi > 0.0 {
        return Ok(hi);
    }
    let mut q = None;
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        let (g, qm) = gap(mid, q.as_deref())?;
        q = Some(qm);
        if g > 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// The table top at height `y` (m).
fn table_at(y: f64) -> Obstacle {
    Obstacle::Polygon {
        vertices_m: vec![[-0.5, y - 0.05], [0.5, y - 0.05], [0.5, y], [-0.5, y]],
    }
}

/// Checks a trial's inputs as [`run_trial`] does before it simulates: the
/// gripper, the object (fields `object.…`), the settings (`settings.…`),
/// the placement (finite; the object narrower than the opening and clear
/// of the fingers at the start), without running the trial.
///
/// # Errors
/// As [`run_trial`]'s checks.
///
/// # Example
/// ```
/// use softrod::grasp::gripper::GripperSpec;
/// use softrod::grasp::object::{GraspObject, Shape};
/// use softrod::grasp::trial::{check_trial, GraspSettings, Placement};
/// let apple = GraspObject { name: "apple".into(), shape: Shape::Circle { radius_m: 0.035 }, mass_kg: -0.15, mu: 0.6 };
/// let e = check_trial(&GripperSpec::default(), &apple, &Placement::default(), &GraspSettings::default()).unwrap_err();
/// assert_eq!(e.field(), Some("object.mass_kg"), "{e}");
/// ```
pub fn check_trial(
    gripper: &GripperSpec,
    object: &GraspObject,
    placement: &Placement,
    settings: &GraspSettings,
) -> Result<()> {
    start(gripper, object, placement, settings).map(|_| ())
}

/// How far from the gripper's centreline an object may be put (m): a
/// kilometre, far beyond any grasp, but a number the geometry can hold.
const MAX_OFFSET_M: f64 = 1e3;

/// The checked start of a trial: the table's height, the object's resting
/// pose on it and its contact cover.
fn start(
    gripper: &GripperSpec,
    object: &GraspObject,
    placement: &Placement,
    settings: &GraspSettings,
) -> Result<(f64, Pose, Vec<Obstacle>)> {
    gripper.validate()?;
    object.validate("object")?;
    settings.validate()?;
    for (n, v) in [
        ("placement.offset_m", placement.offset_m),
        ("placement.angle_rad", placement.angle_rad),
    ] {
        if !v.is_finite() {
            return Err(Error::invalid(n, v, "must be finite"));
        }
    }
    if placement.offset_m.abs() > MAX_OFFSET_M {
        return Err(Error::invalid(
            "placement.offset_m",
            placement.offset_m,
            format!("must be within {MAX_OFFSET_M} m of the gripper's centreline"),
        ));
    }
    let r = gripper.finger_radius_m;
    let table_y = -(gripper.finger_length_m() + r + settings.table_clearance_m);
    let pose = resting_pose(object, placement, table_y);
    let b = object.bounds(&pose);
    if b[1] - b[0] >= gripper.opening_m() {
        // a disc's width is its radius's; other shapes' their sizes together
        let field = match object.shape {
            crate::grasp::object::Shape::Circle { .. } => "object.shape.radius_m",
            _ => "object.shape",
        };
        return Err(Error::invalid(
            field,
            format!("{:.4e} m wide", b[1] - b[0]),
            format!(
                "wider than the gripper's opening ({:.4} m)",
                gripper.opening_m()
            ),
        ));
    }
    let cover = object.contact_cover(&pose)?;
    let obstacles = Obstacles::new(cover.clone(), r)?;
    for side in [Side::Left, Side::Right] {
        let f = gripper.finger(side)?;
        let overlap = obstacles
            .gaps(&f, f.reference_configuration().as_slice())?
            .iter()
            .any(|g| g.gap_m < 0.0);
        if overlap {
            return Err(Error::invalid(
                "placement.offset_m",
                placement.offset_m,
                format!("the object overlaps the {side:?} finger at the start"),
            ));
        }
    }
    Ok((table_y, pose, cover))
}

/// Runs one trial of `strategy` on `object` at `placement` (see the module
/// docs); `seed` seeds the marker noise.
///
/// # Errors
/// Bad input, each naming its field: the object ([`GraspObject::validate`],
/// path `object`), an object wider than the gripper's opening
/// (`object.shape`), an object overlapping a finger at the start
/// (`placement.offset_m`), the settings, the gripper. A failed plant solve
/// or controller step is not an error: the outcome says so.
///
/// # Example
/// ```no_run
/// use softrod::grasp::{gripper::GripperSpec, object::{GraspObject, Shape}};
/// use softrod::grasp::trial::{run_trial, GraspSettings, Placement, Strategy};
/// let apple = GraspObject { name: "apple".into(), shape: Shape::Circle { radius_m: 0.035 }, mass_kg: 0.15, mu: 0.6 };
/// let out = run_trial(&GripperSpec::default(), &apple, Placement::default(), Strategy::Adaptive, &GraspSettings::default(), 1)?;
/// println!("{} {:?}", out.success, out.failure);
/// # Ok::<(), softrod::Error>(())
/// ```
pub fn run_trial(
    gripper: &GripperSpec,
    object: &GraspObject,
    placement: Placement,
    strategy: Strategy,
    settings: &GraspSettings,
    seed: u64,
) -> Result<TrialOutcome> {
    let (table_y, pose, cover) = start(gripper, object, &placement, settings)?;
    let outline = object.obstacle(&pose);
    let table = table_at(table_y);
    let mut plant = GripperPlant::new(
        gripper,
        &settings.plant,
        cover,
        Some(table),
        &settings.markers_s_m,
        seed,
    )?;
    let mut out = TrialOutcome {
        object: object.name.clone(),
        strategy,
        placement,
        pose,
        final_pose: pose,
        slip_m: 0.0,
        outline,
        success: false,
        failure: None,
        hold: None,
        holding_mass_kg: 0.0,
        contact_estimate_error_m: None,
        frames: Vec::new(),
    };
    let scene = Scene {
        gripper,
        object,
        settings,
        strategy,
        seed,
        table_y,
    };
    match simulate(&scene, &mut plant, &mut out) {
        Ok(()) => Ok(out),
        Err(Stop::Fail(f)) => {
            out.failure = Some(f);
            Ok(out)
        }
        Err(Stop::Bad(e)) => Err(e),
    }
}
