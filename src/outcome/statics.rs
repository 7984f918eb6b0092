//! The static solver's status and report.

use serde::{Deserialize, Serialize};

use super::NonFiniteAt;

/// Which test ended a converged static solve.
///
/// # Example
/// ```
/// use softrod::outcome::StaticCriterion;
/// assert_eq!(serde_json::to_string(&StaticCriterion::RoundOffFloor).unwrap(), "\"round_off_floor\"");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum StaticCriterion {
    /// `|Q| <= residual_tolerance × load scale`.
    Residual,
    /// `|Q|` reached the round-off floor (see
    /// [`residual_floor`](crate::statics::residual_floor)); one more Newton
    /// step was taken there, and `|Q| <= floor` holds on the answer.
    RoundOffFloor,
    /// A full Newton step below `increment_tolerance × L`, at a residual
    /// within [`INCREMENT_RESIDUAL_MULTIPLE`](crate::statics::INCREMENT_RESIDUAL_MULTIPLE)
    /// times the larger of the tolerance and the floor.
    Increment,
}

impl StaticCriterion {
    /// The test in words ("residual").
    pub fn name(self) -> &'static str {
        match self {
            StaticCriterion::Residual => "residual",
            StaticCriterion::RoundOffFloor => "round-off floor",
            StaticCriterion::Increment => "increment",
        }
    }
}

/// How a static solve ended.
///
/// # Example
/// ```
/// use softrod::{scene::Scene, statics::{StaticSettings, StaticSolver, StaticStatus}, Error};
/// let scene = Scene::two_section();
/// let robot = scene.robot()?;
/// let eq = StaticSolver::default().solve(&robot, &scene.loads()?, None)?;
/// assert!(eq.report.status.is_converged());
/// // one iteration cannot reach equilibrium from the straight robot
/// let tight = StaticSolver::new(StaticSettings { max_iterations: 1, max_total_iterations: 1, ..Default::default() })?;
/// match tight.solve(&robot, &scene.loads()?, None) {
///     Err(Error::NotConverged { report }) => {
///         assert_eq!(report.status, StaticStatus::IterationLimit { iterations: 1 })
///     }
///     other => panic!("{other:?}"),
/// }
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
#[non_exhaustive]
pub enum StaticStatus {
    /// Equilibrium reached; the test that ended the solve.
    Converged(StaticCriterion),
    /// The iteration budget (`max_total_iterations`) ran out.
    IterationLimit {
        /// Newton iterations taken.
        iterations: usize,
    },
    /// The line search found no step that decreases the potential or the
    /// residual along the Newton direction (one load step; the homotopy then
    /// shortens the step).
    LineSearchFailed,
    /// No shift of the tangent's diagonal gave a factorization with a
    /// descent direction.
    SingularTangent,
    /// The homotopy step fell below `min_load_step`.
    LoadStepTooSmall {
        /// The load fraction `λ` the homotopy had reached (0 to 1).
        load_fraction: f64,
    },
    /// A number that is not finite appeared.
    NonFinite {
        /// Where.
        at: NonFiniteAt,
    },
    /// The iteration ended on `criterion`, but that test does not hold on
    /// the returned configuration's own residual (in the report, with the
    /// tolerance and the floor): e.g. a stiffness contrast between sections
    /// beyond what double precision resolves, whose stiff rows set a
    /// round-off floor the soft rows' loads are below.
    Unverified {
        /// The test the iteration ended on.
        criterion: StaticCriterion,
    },
}

impl StaticStatus {
    /// Whether equilibrium was reached.
    pub fn is_converged(&self) -> bool {
        matches!(self, StaticStatus::Converged(_))
    }

    /// The test that ended a converged solve.
    pub fn criterion(&self) -> Option<StaticCriterion> {
        match self {
            StaticStatus::Converged(c) => Some(*c),
            _ => None,
        }
    }
}

impl std::fmt::Display for StaticStatus {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StaticStatus::Converged(c) => write!(f, "converged ({} test)", c.name()),
            StaticStatus::IterationLimit { iterations } => {
                write!(f, "iteration limit ({iterations} iterations)")
            }
            StaticStatus::LineSearchFailed => write!(f, "line search failed"),
            StaticStatus::SingularTangent => write!(f, "singular tangent"),
            StaticStatus::LoadStepTooSmall { load_fraction } => {
                write!(
                    f,
                    "load step too small (at load fraction {load_fraction:.4})"
                )
            }
            StaticStatus::NonFinite { at } => write!(f, "non-finite {}", at.name()),
            StaticStatus::Unverified { criterion } => write!(
                f,
                "not converged (the {} test does not hold on the answer's residual)",
                criterion.name()
            ),
        }
    }
}

/// How the branch of a solve that passed a critical point of its load
/// path (a bifurcation, such as a column's buckling load, or a limit point)
/// was chosen ([`StaticWarning::Bifurcation`]).
///
/// # Example
/// ```
/// use softrod::outcome::BranchChoice;
/// assert_eq!(serde_json::to_string(&BranchChoice::LoadPath).unwrap(), "\"load_path\"");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum BranchChoice {
    /// The side toward which the load path leaned before the critical
    /// point (a lateral load, a tilted base, a load off the axis): the
    /// branch connected to the unloaded state along the load path (the
    /// path's tangent at its last stable point, projected on the direction
    /// of negative curvature, had that sign).
    LoadPath,
    /// Ambiguous: the load path did not lean to either side (a symmetric
    /// load, such as the weight of a perfectly upright column); the side of
    /// the lower potential was taken, and its mirror image is an
    /// equilibrium as well.
    Symmetric,
    /// The answer was a saddle reached off the load path (the full-load
    /// Newton runs): it was left toward the side of the lower potential,
    /// which need not be the branch the load path leads to.
    LowerPotential,
}

/// A warning about a converged static answer: the equilibrium holds, but
/// something about it needs the user's attention.
///
/// # Example
/// ```
/// use softrod::outcome::{BranchChoice, StaticWarning};
/// let w = StaticWarning::Unstable { negative_eigenvalues: 2 };
/// assert_eq!(serde_json::to_string(&w).unwrap(), r#"{"unstable":{"negative_eigenvalues":2}}"#);
/// assert!(w.to_string().contains("2 negative eigenvalues"));
/// let b = StaticWarning::Bifurcation { from_load_fraction: 0.5, to_load_fraction: 1.0, branch: BranchChoice::Symmetric };
/// assert!(b.to_string().contains("ambiguous"));
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
#[serde(rename_all = "snake_case")]
pub enum StaticWarning {
    /// The equilibrium is not stable: the tangent at it has negative
    /// eigenvalues (a saddle or a maximum of the total potential that the
    /// solver could not leave); the slightest disturbance moves the robot
    /// away from it.
    Unstable {
        /// How many ([`StaticReport::negative_eigenvalues`]).
        negative_eigenvalues: usize,
    },
    /// The load path passed a critical point (a bifurcation, such as a
    /// column's buckling load, or a limit point): a load step from a stable
    /// equilibrium landed on an unstable one, which was left along its
    /// direction of negative curvature for a stable branch; `branch` says
    /// how the side was chosen. The load factors (fractions of the full
    /// loads) bracket the critical point; `1.0` and `1.0`: a saddle at the
    /// full load.
    Bifurcation {
        /// The load factor of the path's last stable point before it (0:
        /// the unloaded start).
        from_load_fraction: f64,
        /// The load factor at which the path was found unstable and left.
        to_load_fraction: f64,
        /// How the branch was chosen.
        branch: BranchChoice,
    },
}

impl std::fmt::Display for StaticWarning {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StaticWarning::Unstable {
                negative_eigenvalues,
            } => write!(
                f,
                "unstable equilibrium: its tangent has {negative_eigenvalues} negative \
                 eigenvalues (a saddle of the potential the solver could not leave; a small \
                 disturbance moves the robot off it)"
            ),
            StaticWarning::Bifurcation {
                from_load_fraction,
                to_load_fraction,
                branch,
            } => {
                write!(
                    f,
                    "bifurcation passed between load factors {from_load_fraction} and \
                     {to_load_fraction}; "
                )?;
                match branch {
                    BranchChoice::LoadPath => write!(
                        f,
                        "branch chosen by the load path's lean (the branch connected to the \
                         unloaded state)"
                    ),
                    BranchChoice::Symmetric => write!(
                        f,
                        "ambiguous: symmetric load (the path leans to neither side; the side \
                         of lower potential was taken, its mirror image is an equilibrium too)"
                    ),
                    BranchChoice::LowerPotential => write!(
                        f,
                        "a saddle at the full load left for the side of lower potential (not \
                         traced along the load path)"
                    ),
                }
            }
        }
    }
}

/// What a static solve did.
///
/// # Example
/// ```
/// use softrod::{scene::Scene, statics::StaticSolver};
/// let scene = Scene::two_section();
/// let eq = StaticSolver::default().solve(&scene.robot()?, &scene.loads()?, None)?;
/// let r = &eq.report;
/// assert!(r.status.is_converged() && r.residual_norm_n <= r.residual_tolerance_n.max(r.residual_floor_n));
/// println!("{r}");
/// # Ok::<(), softrod::Error>(())
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "schema", derive(schemars::JsonSchema))]
pub struct StaticReport {
    /// How the solve ended.
    pub status: StaticStatus,
    /// Newton iterations in all.
    pub iterations: usize,
    /// Homotopy steps taken (0: the full problem converged directly).
    pub load_steps: usize,
    /// Final `|Q|_2` (N).
    pub residual_norm_n: f64,
    /// `residual_tolerance × load_scale_n` (N).
    pub residual_tolerance_n: f64,
    /// Estimated round-off floor of `|Q|_2` (N).
    pub residual_floor_n: f64,
    /// Norm of the applied generalized forces (N).
    pub load_scale_n: f64,
    /// Last Newton step `|dq|_∞` (m).
    pub increment_norm_m: f64,
    /// Negative eigenvalues of the tangent at the returned configuration,
    /// from the signs of its `L D Lᵀ` pivots: `Some(0)` a stable
    /// equilibrium (a local minimum of the potential), more a saddle or a
    /// maximum the solver could not leave, `None` when no `L D Lᵀ` of the
    /// tangent exists (singular), under a follower load (no potential) or
    /// when nothing was solved.
    #[serde(default)]
    pub negative_eigenvalues: Option<usize>,
    /// Warnings about the answer: [`StaticWarning::Unstable`] whenever
    /// `negative_eigenvalues` is more than zero, [`StaticWarning::Bifurcation`]
    /// when the solve passed a critical point and chose a branch (empty:
    /// none; not written then).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<StaticWarning>,
    /// Wall time (s).
    pub wall_time_s: f64,
}

impl StaticReport {
    /// Whether the answer is a stable equilibrium: its tangent is positive
    /// definite (no negative eigenvalue).
    ///
    /// # Example
    /// ```
    /// use softrod::{scene::Scene, statics::StaticSolver};
    /// let scene = Scene::two_section();
    /// let eq = StaticSolver::default().solve(&scene.robot()?, &scene.loads()?, None)?;
    /// assert!(eq.report.is_stable());
    /// # Ok::<(), softrod::Error>(())
    /// ```
    pub fn is_stable(&self) -> bool {
        self.negative_eigenvalues == Some(0)
    }
}

impl std::fmt::Display for StaticReport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{}{}; {} iterations ({} load steps), |Q| = {:.3e} N (tolerance {:.3e} N, round-off floor {:.3e} N), last step {:.3e} m{}",
            self.status,
            match self.negative_eigenvalues {
                Some(0) => String::from(", stable"),
                Some(k) => format!(", unstable ({k} negative eigenvalues)"),
                None => String::new(),
            },
            self.iterations,
            self.load_steps,
            self.residual_norm_n,
            self.residual_tolerance_n,
            self.residual_floor_n,
            self.increment_norm_m,
            self.warnings
                .iter()
                .map(|w| format!("; warning: {w}"))
                .collect::<String>()
        )
    }
}
