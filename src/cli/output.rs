// The records the command line writes: one public serde type per output,
// each with a JSON Schema generated from the type (`softrod schema`, the
// committed files under schema/).
//
// # The format
// Every record starts with the same five fields (`Header`):
// - `format_version`: [`FORMAT_VERSION`]. It is bumped (to "2", "3", ...)
//   whenever a record changes so that a reader of the previous version may
//   misread it: a field renamed, removed, retyped or given another unit, an
//   enum value renamed or removed, a field's meaning changed. Adding a field
//   or an enum value does not bump it (readers ignore what they do not
//   know); the schemas under schema/ are regenerated either way and the
//   `output_schema` test fails until they are.
// - `command`: the subcommand that wrote it (`solve`, `estimate`, ...).
// - `scene`: the scene's name; `scene_kind`: what was run (the element of a
//   robot scene, `parallel`, `avoid`, `grasp`).
// - `outcome`: `success` (exit code 0) or `goal_not_met` (exit code 2: the
//   run finished and its record is written, but it did not reach what it
//   was asked: an estimate or a solve that did not converge, a missed goal,
//   a grasp that did not hold, a tracking run stopped early).
// Then a typed `status` saying how the run ended (the library's status
// enums: `{"converged": "residual"}`, `{"misfit_beyond_noise": {...}}`,
// ...) and the command's own fields.
//
// # Conventions
// - Units in the field names (`_m`, `_n`, `_rad`, `_pa`, `_s`, `_kg`).
// - A vector is an array of its world-axis components in axis order:
//   `[x, y]` for a planar robot, `[x, y, z]` in 3-D (the schemas give the
//   length where it is fixed).
// - A pose or any other compound quantity is an object with named parts,
//   e.g. the parallel robot's `platform_pose`:
//   `{"position_m": [x, y, z], "rotation_vector_rad": [rx, ry, rz]}`.
// - Enums are spelled in snake_case in the JSON, on the command line and
//   in the summaries on standard error (`ff_updater`, `open_loop`).
// - Where there is an estimate, its uncertainty sits beside it: standard
//   deviations as `*_std_*` (1σ, for the stated marker noise), covariances
//   as `*_cov_*` (row-major nested arrays).

use schemars::JsonSchema;
use serde::Serialize;

use softrod::assembly::ValidityWarning;
use softrod::estimate::{Backend, EstimateReport};
use softrod::outcome::{EstimateStatus, StaticReport, StaticStatus};
use softrod::refine::Refinement;

/// The version of the output format (see the module notes for when it is
/// bumped).
pub const FORMAT_VERSION: &str = "1";

/// Exit code of a run that finished and wrote its record but did not reach
/// its goal (`outcome: goal_not_met`).
pub const EXIT_GOAL_NOT_MET: i32 = 2;

/// The error a subcommand returns after writing a `goal_not_met` record:
/// `main` reports it on standard error and exits with
/// [`EXIT_GOAL_NOT_MET`].
#[derive(Debug)]
pub struct GoalNotMet(pub String);

impl std::fmt::Display for GoalNotMet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for GoalNotMet {}

/// [`FORMAT_VERSION`] as a string field whose schema holds it as a constant.
#[derive(Debug, Clone, Serialize)]
pub struct FormatVersion(&'static str);

impl Default for FormatVersion {
    fn default() -> Self {
        FormatVersion(FORMAT_VERSION)
    }
}

impl JsonSchema for FormatVersion {
    fn schema_name() -> std::borrow::Cow<'static, str> {
        "FormatVersion".into()
    }

    fn json_schema(_: &mut schemars::SchemaGenerator) -> schemars::Schema {
        schemars::json_schema!({
            "description": "The output format's version (bumped when a field is renamed, removed, retyped or changes meaning).",
            "type": "string",
            "const": FORMAT_VERSION,
        })
    }
}

/// The subcommand that wrote a record.
#[derive(Debug, Clone, Copy, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum CommandName {
    Solve,
    Estimate,
    Track,
    Avoid,
    Grasp,
}

/// What a record is of.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum SceneKind {
    /// A robot scene of planar cable elements.
    PlanarCable,
    /// A robot scene of spatial cable elements.
    SpatialCable,
    /// A robot scene of full 3-D elements.
    Ancf3d,
    /// A soft parallel robot (its legs' element in `element`).
    Parallel,
    /// An obstacle-avoidance scene (the five-section planar robot).
    Avoid,
    /// A grasp scene (the two-finger gripper).
    Grasp,
}

impl SceneKind {
    /// The kind of a robot scene.
    pub fn of(scene: &softrod::scene::Scene) -> Self {
        use softrod::scene::ElementKind;
        match scene.robot.element {
            ElementKind::PlanarCable => SceneKind::PlanarCable,
            ElementKind::SpatialCable => SceneKind::SpatialCable,
            ElementKind::Ancf3d => SceneKind::Ancf3d,
        }
    }
}

/// Whether the run reached its goal (and the exit code that says it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Exit code 0.
    Success,
    /// Exit code 2: the record is written with its status.
    GoalNotMet,
}

impl Outcome {
    /// `Success` if `ok`.
    pub fn from_ok(ok: bool) -> Self {
        if ok {
            Outcome::Success
        } else {
            Outcome::GoalNotMet
        }
    }
}

/// The fields every record starts with.
#[derive(Debug, Clone, Serialize, JsonSchema)]
pub struct Header {
    pub format_version: FormatVersion,
    pub command: CommandName,
    /// The scene's name (a grasp: the object's).
    pub scene: String,
    pub scene_kind: SceneKind,
    pub outcome: Outcome,
}

impl Header {
    pub fn new(command: CommandName, scene: &str, scene_kind: SceneKind, outcome: Outcome) -> Self {
        Header {
            format_version: FormatVersion::default(),
            command,
            scene: scene.to_string(),
            scene_kind,
            outcome,
        }
    }
}

/// One node of a result.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct NodeRecord {
    /// Undeformed arc coordinate (m).
    pub s_m: f64,
    /// Position (m), world axes.
    pub position_m: Vec<f64>,
    /// Slope r' (dimensionless; its norm is 1 + axial strain).
    pub slope: Vec<f64>,
    /// Planar: the tangent's angle from the x axis (rad), unwrapped along
    /// the backbone (a full circle ends at 2π).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub angle_rad: Option<f64>,
}

/// The result of `softrod solve` on a robot scene.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct SolveRecord {
    #[serde(flatten)]
    pub header: Header,
    /// How the solve ended (also `report.status`).
    pub status: StaticStatus,
    pub pressures_pa: Vec<f64>,
    pub nodes: Vec<NodeRecord>,
    /// The tip's position (m), world axes.
    pub tip_position_m: Vec<f64>,
    /// Planar: the tip tangent's angle from the x axis (rad).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tip_angle_rad: Option<f64>,
    /// 3-D: the unit tangent at the tip, world axes.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tip_direction: Option<Vec<f64>>,
    /// Spatial: the angle between the tip tangent and the base tangent (rad).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tip_angle_from_base_rad: Option<f64>,
    pub report: StaticReport,
    /// The configuration (not written).
    #[serde(skip)]
    #[schemars(skip)]
    pub q: Vec<f64>,
    /// Where the result leaves the model's validity (also on stderr).
    pub warnings: Vec<ValidityWarning>,
    /// How the counts of "elements": "auto" sections were chosen.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refinement: Option<Refinement>,
}

/// One sample of the estimated load.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct LoadSample {
    /// Undeformed arc coordinate (m).
    pub s: f64,
    /// Load per undeformed length, world axes (N/m).
    pub w: Vec<f64>,
    /// Standard deviation (1σ) of each component of `w` from the stated
    /// marker noise alone (N/m): the square roots of the diagonal of
    /// `S(s) L Lᵀ S(s)ᵀ`, `w = S(s) F` (8) and `L` the estimate's noise
    /// covariance factor (`softrod::estimate::Estimate::cov_factor`; the
    /// penalty's bias is not in it). Absent for a concentrated load.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub w_std: Option<Vec<f64>>,
}

/// Where an estimated point force acts (the estimator's concentrated load
/// model).
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct PointForceRecord {
    /// The node it acts at.
    pub node: usize,
    /// The node's undeformed arc coordinate (m).
    pub s_m: f64,
    /// The node's position in the estimated shape (m), world axes.
    pub position_m: Vec<f64>,
}

/// A marker the estimate was fitted to.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct MarkerFitRecord {
    /// Undeformed arc coordinate of the marker (m).
    pub s_m: f64,
    /// Its node, if it was given by node.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub node: Option<usize>,
    /// Where it was measured (m), world axes.
    pub measured_position_m: Vec<f64>,
    /// Where the estimated shape puts it (m), world axes.
    pub fitted_position_m: Vec<f64>,
}

/// Resultant of the estimated load, with its uncertainty.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct ResultantRecord {
    /// Force (N), world axes.
    pub force_n: Vec<f64>,
    /// Standard deviation (1σ) of each force component for the stated
    /// marker noise (N).
    pub force_std_n: Vec<f64>,
    /// Covariance of the force (N², row-major, world axes): its diagonal
    /// is `force_std_n` squared.
    pub force_cov_n2: Vec<Vec<f64>>,
    /// Moment about the base position, in the estimated shape (N·m).
    pub moment_nm: Vec<f64>,
}

/// The estimator that ran.
#[derive(Debug, Clone, Copy, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum BackendName {
    Newton,
    Sqp,
}

impl From<Backend> for BackendName {
    fn from(b: Backend) -> Self {
        match b {
            Backend::Newton => BackendName::Newton,
            Backend::Sqp => BackendName::Sqp,
        }
    }
}

/// What an estimation did (the library's `EstimateReport`, field by field).
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct EstimateReportRecord {
    pub backend: BackendName,
    pub status: EstimateStatus,
    /// Outer iterations (Gauss–Newton steps or QPs) of the solves at the
    /// chosen `α` (an `α` search's are in `alpha_search`).
    pub iterations: usize,
    /// Intermediate observations used (1: the observation was taken directly).
    pub sub_steps: usize,
    /// Final objective `(Aq − y)ᵀW(Aq − y) + α FᵀHF`.
    pub objective: f64,
    /// Final weighted residual `(Aq − y)ᵀW(Aq − y)`.
    pub weighted_residual: f64,
    /// Observed components `n_ob`.
    pub n_observations: usize,
    /// Norm of the reduced gradient (29).
    pub gradient_norm: f64,
    /// Final equilibrium residual `|Q|_2` (N).
    pub equilibrium_residual_n: f64,
    /// The regularization weight used.
    pub alpha: f64,
    /// Wall time of the step (s).
    pub wall_time_s: f64,
    /// Tangent factorizations and right-hand sides solved (the library's
    /// `softrod::linsolve::LinearWork`).
    pub linear_work: serde_json::Value,
    /// The Newton backend's far start, if a solve took it (the library's
    /// `softrod::estimate::FarStart`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub far_start: Option<serde_json::Value>,
    /// The choice of `α` this step made, if it made one: the rule, the
    /// solves of its search and their iterations, which `iterations` does
    /// not count (the library's `softrod::estimate::AlphaSearch`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub alpha_search: Option<softrod::estimate::AlphaSearch>,
}

impl From<&EstimateReport> for EstimateReportRecord {
    fn from(r: &EstimateReport) -> Self {
        EstimateReportRecord {
            backend: r.backend.into(),
            status: r.status,
            iterations: r.iterations,
            sub_steps: r.sub_steps,
            objective: r.objective,
            weighted_residual: r.weighted_residual,
            n_observations: r.n_observations,
            gradient_norm: r.gradient_norm,
            equilibrium_residual_n: r.equilibrium_residual_n,
            alpha: r.alpha,
            wall_time_s: r.wall_time_s,
            linear_work: serde_json::to_value(r.linear_work).unwrap_or_default(),
            far_start: r
                .far_start
                .as_ref()
                .and_then(|f| serde_json::to_value(f).ok()),
            alpha_search: r.alpha_search,
        }
    }
}

/// One estimate of a robot scene (the body of `softrod estimate`'s record,
/// and of each frame of a stream).
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct EstimateBody {
    /// How the estimate ended (also `report.status`).
    pub status: EstimateStatus,
    pub backend: BackendName,
    /// Where the observation came from.
    pub observation: String,
    /// The known chamber pressures (Pa) the estimate is for.
    pub pressures_pa: Vec<f64>,
    /// Node coordinates of the estimated shape (m).
    pub nodes: Vec<NodeRecord>,
    /// The estimated distributed load on an evenly spaced grid of
    /// `load_grid_points` arc coordinates.
    pub load: Vec<LoadSample>,
    pub load_grid_points: usize,
    /// The raw load parameters F (N/m, N/m², node-major [w, w']; or the force, N).
    pub load_parameters: Vec<f64>,
    /// A concentrated load model: where the force (`load_parameters`, also
    /// `resultant.force_n`) acts.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub point_force: Option<PointForceRecord>,
    pub resultant: ResultantRecord,
    /// Marker residuals A q - y (m), in observation order.
    pub marker_residuals_m: Vec<f64>,
    /// Each marker measured and fitted (positions only), in observation
    /// order (what `softrod plot` draws).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub markers: Vec<MarkerFitRecord>,
    /// Standard deviation (1σ) of the estimated marker-space shape (m), per
    /// observed component.
    pub marker_std_m: Vec<f64>,
    /// Largest standard deviation (1σ) of a load parameter (N/m or N).
    pub max_load_parameter_std: f64,
    /// The marker noise the covariances are stated for (m).
    pub noise_sigma_m: f64,
    /// Load directions the markers determine (the evidence's effective
    /// number of parameters).
    pub determined_directions: f64,
    /// The largest fraction of the resultant's prior variance the markers
    /// leave in any direction (0: they fix it; 1: they say nothing of it
    /// in some direction).
    pub resultant_prior_fraction: f64,
    /// `force_std_n` is (mostly) a prior's width, not knowledge (also on
    /// stderr): fewer than 0.5 load directions determined (the markers
    /// barely see the load), or more than 0.8 of the resultant's prior
    /// variance left (they do not see the resultant).
    pub weakly_informed: bool,
    /// Why `weakly_informed` (absent when it is false).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weakly_informed_reason: Option<softrod::estimate::WeakInformation>,
    pub report: EstimateReportRecord,
    /// The estimated configuration (not written).
    #[serde(skip)]
    #[schemars(skip)]
    pub q: Vec<f64>,
    /// Where the estimated shape leaves the model's validity (also on stderr).
    pub warnings: Vec<ValidityWarning>,
    /// How the counts of "elements": "auto" sections were chosen.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refinement: Option<Refinement>,
}

/// The result of `softrod estimate` on a robot scene with one observation.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct EstimateRecord {
    #[serde(flatten)]
    pub header: Header,
    #[serde(flatten)]
    pub body: EstimateBody,
}

/// How a recorded stream's estimates ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum StreamStatus {
    /// Every frame's estimate converged.
    AllConverged,
    /// Some did not (their indices in `not_converged`).
    NotAllConverged,
}

/// One frame's estimate in the record of a stream.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct FrameRecord {
    /// Time of the frame (s).
    pub t_s: f64,
    /// How its estimate ended (also in `estimate.status`).
    pub status: EstimateStatus,
    pub estimate: EstimateBody,
}

/// The result of `softrod estimate` on a recorded stream: one record per
/// frame, the estimator kept warm from frame to frame.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct StreamRecord {
    #[serde(flatten)]
    pub header: Header,
    pub status: StreamStatus,
    pub backend: BackendName,
    pub observation: String,
    pub n_frames: usize,
    /// Frames whose estimate did not converge (their index).
    pub not_converged: Vec<usize>,
    pub frames: Vec<FrameRecord>,
}

/// A rigid body's pose: position and rotation vector (axis × angle).
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct PoseRecord {
    /// Position of the body's centre (m), world axes `[x, y, z]`.
    pub position_m: [f64; 3],
    /// Rotation vector from the reference orientation (rad), world axes
    /// `[rx, ry, rz]`: its direction the axis, its norm the angle.
    pub rotation_vector_rad: [f64; 3],
}

impl PoseRecord {
    /// From the library's six numbers `[x, y, z, rx, ry, rz]`.
    pub fn from_six(p: &[f64; 6]) -> Self {
        PoseRecord {
            position_m: [p[0], p[1], p[2]],
            rotation_vector_rad: [p[3], p[4], p[5]],
        }
    }
}

/// The legs' element of a parallel robot.
#[derive(Debug, Clone, Copy, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum LegElementName {
    SpatialCable,
    Ancf3d,
}

impl From<softrod::parallel::LegElement> for LegElementName {
    fn from(e: softrod::parallel::LegElement) -> Self {
        match e {
            softrod::parallel::LegElement::SpatialCable => LegElementName::SpatialCable,
            softrod::parallel::LegElement::Ancf3d => LegElementName::Ancf3d,
        }
    }
}

/// How a parallel robot's solve ended.
#[derive(Debug, Clone, Copy, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ParallelSolveStatus {
    /// The structure's Newton solve met its residual test (a solve that
    /// does not is an error, exit code 1, with no record).
    Converged,
}

/// The result of `softrod solve` on a parallel-robot scene.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct ParallelSolveRecord {
    #[serde(flatten)]
    pub header: Header,
    pub status: ParallelSolveStatus,
    pub element: LegElementName,
    pub pressures_pa: Vec<f64>,
    pub platform_pose: PoseRecord,
    /// Every leg's node positions (m), base to platform.
    pub legs_m: Vec<Vec<[f64; 3]>>,
    /// Newton iterations.
    pub iterations: usize,
}

/// The result of `softrod estimate` on a parallel-robot scene: the payload
/// at the platform.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct ParallelEstimateRecord {
    #[serde(flatten)]
    pub header: Header,
    /// How the estimate ended (the estimator's status, its fit test on
    /// the answer); always given (`null` only in records of format 1
    /// written before the payload went through the estimator).
    pub status: Option<EstimateStatus>,
    /// The estimator's backend.
    pub backend: BackendName,
    pub element: LegElementName,
    /// Where the observation came from.
    pub observation: String,
    /// The force on the platform's centre (N), world axes.
    pub force_n: [f64; 3],
    /// Standard deviation (1σ) of each force component (N) under the
    /// scene's `marker_sigma_m`.
    pub force_std_n: Option<[f64; 3]>,
    /// The payload's mass `F·g/|g|²` (kg).
    pub mass_kg: f64,
    /// Standard deviation (1σ) of the mass (kg).
    pub mass_std_kg: Option<f64>,
    /// The estimator's iterations.
    pub iterations: usize,
    /// The distance of the model's platform from the observed one at the end (m).
    pub residual_m: f64,
}

/// How a tracking run ended.
#[derive(Debug, Clone, Copy, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum TrackStatus {
    /// The trajectory ran to its end.
    Completed,
    /// The plant's equilibrium failed and the run stopped.
    PlantFailed {
        /// When (s).
        at_s: f64,
    },
    /// The watchdog (`loop.abort_error_m`) stopped the run.
    Aborted {
        /// When (s).
        at_s: f64,
    },
}

/// The controller of a tracking run.
#[derive(Debug, Clone, Copy, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum ControllerName {
    Ff,
    FfUpdater,
}

impl From<softrod::control::ControllerKind> for ControllerName {
    fn from(c: softrod::control::ControllerKind) -> Self {
        match c {
            softrod::control::ControllerKind::Ff => ControllerName::Ff,
            softrod::control::ControllerKind::FfUpdater => ControllerName::FfUpdater,
        }
    }
}

impl ControllerName {
    /// The spelling of the JSON and of `--controller`.
    pub fn name(self) -> &'static str {
        match self {
            ControllerName::Ff => "ff",
            ControllerName::FfUpdater => "ff_updater",
        }
    }
}

/// The top level of the library's tracking run (`softrod::control::TrackRun`
/// or `softrod::control::parallel::TrackRun`), for the schema: the summary
/// is that type's, the samples `softrod::control::TrackSample` for both
/// (see their documentation).
#[derive(JsonSchema)]
#[schemars(deny_unknown_fields)]
#[allow(dead_code)]
struct TrackRunFields {
    /// The run's summary (`TrackSummary` of the library).
    summary: serde_json::Map<String, serde_json::Value>,
    /// One sample per control instant (`TrackSample` of the library).
    samples: Vec<serde_json::Map<String, serde_json::Value>>,
}

/// The result of `softrod track` (a robot scene or a parallel one).
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct TrackRecord<R: Serialize> {
    #[serde(flatten)]
    pub header: Header,
    pub status: TrackStatus,
    pub controller: ControllerName,
    #[serde(flatten)]
    #[schemars(with = "TrackRunFields")]
    pub run: R,
}

/// The top level of the library's `softrod::touch::AvoidRun`, for the
/// schema (its status typed, the rest that type's).
#[derive(JsonSchema)]
#[schemars(deny_unknown_fields)]
#[allow(dead_code)]
struct AvoidRunFields {
    status: softrod::touch::AvoidStatus,
    /// The goal (m), `[x, y]`.
    goal_m: [f64; 2],
    /// Final distance from the goal (m); `null` when the run was not made
    /// (`goal_unreachable`).
    final_error_m: Option<f64>,
    max_force_before_n: f64,
    max_force_after_n: f64,
    final_force_n: f64,
    calibration: serde_json::Map<String, serde_json::Value>,
    touched: Vec<serde_json::Map<String, serde_json::Value>>,
    samples: Vec<serde_json::Map<String, serde_json::Value>>,
    /// True shapes `(t_s, nodes_m)`.
    shapes: Vec<(f64, Vec<[f64; 2]>)>,
}

/// The result of `softrod avoid` (its `status` is the run's).
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct AvoidRecord {
    #[serde(flatten)]
    pub header: Header,
    #[serde(flatten)]
    #[schemars(with = "AvoidRunFields")]
    pub run: softrod::touch::AvoidRun,
}

/// How a grasp ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum GraspStatus {
    /// The grasp held (the cause of a failure is in `failure`).
    Held,
    /// It did not.
    Failed,
}

/// The top level of the library's `softrod::grasp::trial::TrialOutcome`,
/// for the schema (the failure and the strategy typed, the rest that
/// type's).
#[derive(JsonSchema)]
#[schemars(deny_unknown_fields)]
#[allow(dead_code)]
struct TrialOutcomeFields {
    object: String,
    strategy: softrod::grasp::trial::Strategy,
    placement: serde_json::Map<String, serde_json::Value>,
    pose: serde_json::Map<String, serde_json::Value>,
    final_pose: serde_json::Map<String, serde_json::Value>,
    slip_m: f64,
    outline: serde_json::Value,
    success: bool,
    failure: Option<softrod::grasp::trial::Failure>,
    hold: Option<serde_json::Map<String, serde_json::Value>>,
    holding_mass_kg: f64,
    contact_estimate_error_m: Option<f64>,
    frames: Vec<serde_json::Map<String, serde_json::Value>>,
}

/// The result of `softrod grasp`.
#[derive(Debug, Clone, Serialize, JsonSchema)]
#[schemars(deny_unknown_fields)]
pub struct GraspRecord {
    #[serde(flatten)]
    pub header: Header,
    pub status: GraspStatus,
    #[serde(flatten)]
    #[schemars(with = "TrialOutcomeFields")]
    pub trial: softrod::grasp::trial::TrialOutcome,
}

/// Every record's schema: `(file stem, schema)`, written by `softrod schema`
/// and committed under schema/.
pub fn schemas() -> Vec<(&'static str, schemars::Schema)> {
    use schemars::schema_for;
    vec![
        ("solve", schema_for!(SolveRecord)),
        ("solve_parallel", schema_for!(ParallelSolveRecord)),
        ("estimate", schema_for!(EstimateRecord)),
        ("estimate_stream", schema_for!(StreamRecord)),
        ("estimate_parallel", schema_for!(ParallelEstimateRecord)),
        ("track", schema_for!(TrackRecord<serde_json::Value>)),
        ("avoid", schema_for!(AvoidRecord)),
        ("grasp", schema_for!(GraspRecord)),
    ]
}

/// `value` as compact JSON: a status or a cause in a summary line spelled
/// as in the record (`{"cause":"slips",...}`).
pub fn json_text<T: Serialize>(value: &T) -> String {
    serde_json::to_string(value).unwrap_or_default()
}
