//! Control of the planar robot (Sec. IV): feedforward inverse kinematics
//! with the estimated load, the parameter updater (31), the virtual payload
//! (Fig. 5) and the closed loop
//!
//! ```text
//! plant markers → estimator (F̄) → updater (31) (F̂) → f_IK(x_d, F̂) → pressures → plant
//! ```
//!
//! - [`InverseKinematics`]: `f_IK(x_d, F̂)`, equilibrium (17) plus "end
//!   effector at `x_d`" by Newton in the pressure bounds, redundancy by
//!   minimum `Σ P̂²`, unreachable targets reported.
//! - [`ParameterUpdater`]: (31), exact at the control rate.
//! - [`MassEstimator`]: the mass hanging at a point from the end effector's
//!   displacement, with the concentrated-load model (32)–(35).
//! - [`VirtualPayload`]: the load estimated on a payload-free run, as a
//!   function of the configuration, to subtract.
//! - [`ClosedLoop`]: one controller stepping against a [`crate::plant::Plant`].
//! - [`parallel`]: the same loop on the soft parallel robot (its own
//!   inverse kinematics and platform estimator, this module's updater).
//!
//! The sweep of where the loop fails (payload × stiffness error × noise ×
//! rate) is an experiment: `report::loop_failure` (feature `report`).

pub(crate) mod adapter;
pub(crate) mod boxqp;
mod closed_loop;
mod ik;
mod ik_settings;
mod mass;
pub mod parallel;
mod track;
mod trajectory;
mod updater;
mod virtual_payload;
mod weighing;

pub use closed_loop::{
    ClosedLoop, ControllerKind, EstimateFlag, LoopSample, LoopSettings, StepStatus, TimeSeries,
};
pub use ik::{IkSolution, InverseKinematics, RESTART_RADIUS_M};
pub use ik_settings::{IkSettings, IkStatus, PressureBound};
pub use mass::{MassEstimate, MassEstimator, MassForce, MassReference, MassSettings};
pub use track::{
    CircleSpec, FigureEightSpec, LineSpec, MAX_TRACK_STEPS, PressuresSpec, SamplesSpec, TrackFile,
    TrackRun, TrackSample, TrackSummary, TrajectorySpec, build_trajectory, check_track,
    payloads_from_json, run_track,
};
pub use trajectory::Trajectory;
pub use updater::{MAX_K_I_PER_S2, MAX_K_P_PER_S, ParameterUpdater, UpdaterGains};
pub use virtual_payload::VirtualPayload;
pub use weighing::{MassConfiguration, MassRow, MassTable, WeighingExperiment};
