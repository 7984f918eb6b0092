//! Scene text in, everything the command line does with it, and the
//! honesty invariants checked on every answer: shared by the fuzz targets
//! (`tests/fuzz/fuzz_targets/`, which include this file by `#[path]`),
//! the random-scene property test (`tests/random_scenes.rs`) and the
//! report check of `tests/bad_inputs.rs`.
//!
//! The invariants, each cheap to check on the answer alone:
//! - no panic, and every refusal renders as text;
//! - every number of a returned equilibrium, of its report and of a
//!   returned estimate is finite (a failed solve's report too, except the
//!   residual and step of a `non_finite` one);
//! - a `converged` static status holds on the answer: the reported
//!   residual, and the residual recomputed through the public API, is at
//!   most the larger of the stated tolerance and the round-off floor
//!   (`INCREMENT_RESIDUAL_MULTIPLE` times that for the increment test);
//!   negative eigenvalues carry the `unstable` warning;
//! - a `converged` estimate passed its fit test (weighted misfit within
//!   the `FIT_QUANTILE` χ² quantile of its observed components) and has
//!   finite covariances.
//!
//! Work per input is bounded by the caps below: scenes with more elements
//! are skipped, iteration budgets clamped (the library's own limits are tested in
//! `tests/bad_inputs.rs` and `tests/bad_inputs_ranges.rs`).
#![allow(dead_code, clippy::panic)]

use softrod::Error;
use softrod::assembly::Robot;
use softrod::element::Element;
use softrod::estimate::{
    Backend, Estimate, EstimatorSettings, FIT_QUANTILE, Observation, chi2_quantile,
};
use softrod::loads::Loads;
use softrod::outcome::{StaticCriterion, StaticReport, StaticStatus, StaticWarning};
use softrod::scene::markers::MarkersFile;
use softrod::scene::{Scene, SceneRobot};
use softrod::site::Site;
use softrod::statics::{Equilibrium, INCREMENT_RESIDUAL_MULTIPLE, StaticSettings, StaticSolver};

/// Largest input text (bytes).
pub const MAX_INPUT: usize = 16 * 1024;
/// Largest element count solved.
pub const MAX_ELEMENTS: usize = 500;
/// Largest element count estimated (an estimate costs tens of solves).
pub const MAX_ESTIMATE_ELEMENTS: usize = 40;
/// Largest static iteration budget (`max_total_iterations`) run: larger
/// ones are clamped to it.
pub const MAX_ITERATIONS: usize = 200;
/// Largest estimator iteration budget (`max_iterations`) run: larger ones
/// are clamped to it.
pub const MAX_ESTIMATE_ITERATIONS: usize = 10;
/// Largest iteration budget of the estimator's own static solves
/// (`solver.estimator.static`): each solve of an estimate (tens in an α
/// search) may run a few whole ones (its start, a far start, one in the
/// newton backend's line searches; before the fix of fuzz finding 1 that
/// was up to 23 per iteration: minutes on one input, see
/// `tests/fuzz/regressions/scene_estimate/`).
pub const MAX_ESTIMATE_STATIC_ITERATIONS: usize = 30;
/// Most markers per observation estimated.
pub const MAX_MARKERS: usize = 12;
/// Most observations (frames) estimated per backend.
pub const MAX_FRAMES: usize = 4;

/// How far the inputs got (counted over the process, for the property
/// test to show that its cases reach the estimators).
pub mod reached {
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// Scenes accepted by the parser and within the caps.
    pub static SCENES: AtomicUsize = AtomicUsize::new(0);
    /// Static solves that returned an equilibrium.
    pub static EQUILIBRIA: AtomicUsize = AtomicUsize::new(0);
    /// Estimates returned (either backend, every frame).
    pub static ESTIMATES: AtomicUsize = AtomicUsize::new(0);
    /// Of those, converged.
    pub static CONVERGED_ESTIMATES: AtomicUsize = AtomicUsize::new(0);

    pub(super) fn count(c: &AtomicUsize) {
        c.fetch_add(1, Ordering::Relaxed);
    }

    /// The four counts, in the order above.
    pub fn counts() -> [usize; 4] {
        [&SCENES, &EQUILIBRIA, &ESTIMATES, &CONVERGED_ESTIMATES].map(|c| c.load(Ordering::Relaxed))
    }
}

/// The separator of a scene and its markers file in one fuzz input (a byte
/// no JSON text contains).
pub const SEPARATOR: u8 = 0;

/// A fuzz input as a scene text and an optional markers text (after the
/// first [`SEPARATOR`]); `None` for an input too long or not UTF-8.
pub fn split_input(data: &[u8]) -> Option<(&str, Option<&str>)> {
    if data.len() > MAX_INPUT {
        return None;
    }
    let (scene, markers) = match data.iter().position(|&b| b == SEPARATOR) {
        Some(i) => (&data[..i], Some(&data[i + 1..])),
        None => (data, None),
    };
    let scene = std::str::from_utf8(scene).ok()?;
    let markers = match markers {
        Some(m) => Some(std::str::from_utf8(m).ok()?),
        None => None,
    };
    Some((scene, markers))
}

/// A seed from the input bytes (FNV-1a), for the synthesized markers' noise.
pub fn seed_of(data: &[u8]) -> u64 {
    data.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// An error rendered (it must not panic); its message.
fn render(e: &Error) -> String {
    let s = e.to_string();
    if let Error::NotConverged { report } = e {
        check_failed_report(report);
    }
    s
}

/// The scene of `text` with its iteration budgets clamped to the caps, or
/// `None` when it is refused (the refusal rendered), has `"auto"` elements
/// or more than `max_elements`.
pub fn parse(text: &str, max_elements: usize) -> Option<Scene> {
    if text.len() > MAX_INPUT {
        return None;
    }
    let mut scene = match Scene::from_json(text) {
        Ok(s) => s,
        Err(e) => {
            render(&e);
            return None;
        }
    };
    let total = scene
        .robot
        .sections
        .iter()
        .fold(0usize, |a, s| a.saturating_add(s.elements));
    if total > max_elements || scene.has_auto_elements() {
        return None;
    }
    reached::count(&reached::SCENES);
    // (the defaults, 2000 static iterations, would be skipped otherwise)
    clamp(&mut scene.solver.statics, MAX_ITERATIONS);
    clamp(
        &mut scene.solver.estimator.statics,
        MAX_ESTIMATE_STATIC_ITERATIONS,
    );
    let est = &mut scene.solver.estimator;
    est.max_iterations = est.max_iterations.min(MAX_ESTIMATE_ITERATIONS);
    Some(scene)
}

/// The static budgets at most `cap` (`max_iterations ≤
/// max_total_iterations` stays true).
fn clamp(s: &mut StaticSettings, cap: usize) {
    s.max_iterations = s.max_iterations.min(cap);
    s.max_total_iterations = s.max_total_iterations.min(cap);
}

/// Runs `f` on the scene's robot, whatever its element family; `None` when
/// the robot or the loads are refused.
macro_rules! with_robot {
    ($scene:expr, |$robot:ident, $loads:ident| $body:expr) => {{
        let built = match $scene.build() {
            Ok(r) => r,
            Err(e) => {
                render(&e);
                return;
            }
        };
        let $loads = match $scene.loads() {
            Ok(l) => l,
            Err(e) => {
                render(&e);
                return;
            }
        };
        match built {
            SceneRobot::Planar($robot) => $body,
            SceneRobot::Spatial($robot) => $body,
            SceneRobot::Full($robot) => $body,
        }
    }};
}

/// What `softrod solve` does with the scene text: parse, build, solve (and
/// warm-start a second solve from the answer), every answer checked.
pub fn solve_scene(text: &str) {
    let Some(scene) = parse(text, MAX_ELEMENTS) else {
        return;
    };
    with_robot!(scene, |robot, loads| solve_checked(&scene, &robot, &loads));
}

/// The scene's static solve with its invariants checked; the equilibrium
/// if it converged.
fn solve_checked<E: Element + 'static>(
    scene: &Scene,
    robot: &Robot<E>,
    loads: &Loads,
) -> Option<Equilibrium> {
    let solver = match StaticSolver::new(scene.solver.statics.clone()) {
        Ok(s) => s,
        Err(e) => {
            render(&e);
            return None;
        }
    };
    let eq = match solver.solve(robot, loads, None) {
        Ok(eq) => eq,
        Err(e) => {
            render(&e);
            return None;
        }
    };
    check_equilibrium(robot, loads, &eq);
    for m in &scene.markers {
        if let Some(s) = m.s_m {
            assert!(
                robot.position_at(eq.q.as_slice(), s).is_ok(),
                "validated marker s_m = {s} off the robot"
            );
        }
    }
    let _ = robot.node_positions(eq.q.as_slice());
    let _ = robot.elastic_energy(eq.q.as_slice());
    // a warm start from the solution must also be fine
    match solver.solve(robot, loads, Some(eq.q.as_slice())) {
        Ok(warm) => check_equilibrium(robot, loads, &warm),
        Err(e) => {
            render(&e);
        }
    }
    Some(eq)
}

/// A returned (converged) equilibrium: finite, its report honest, and its
/// residual recomputed through the public API within the reported bound.
pub fn check_equilibrium<E: Element>(robot: &Robot<E>, loads: &Loads, eq: &Equilibrium) {
    reached::count(&reached::EQUILIBRIA);
    let r = &eq.report;
    assert!(eq.q.iter().all(|v| v.is_finite()), "non-finite q: {r}");
    assert!(eq.u.iter().all(|v| v.is_finite()), "non-finite u: {r}");
    check_static_report(r);
    let Some(c) = r.status.criterion() else {
        panic!("an equilibrium returned with status {}", r.status);
    };
    let bound = converged_bound(r, c);
    if let Ok(dead) = robot.dead_force(loads)
        && let Ok(q) = robot.residual(eq.q.as_slice(), dead.as_slice(), loads)
    {
        let true_norm = q.norm();
        assert!(
            true_norm <= bound * (1.0 + 1e-6),
            "|Q| = {true_norm:e} recomputed above the bound {bound:e} of a converged answer: {r}"
        );
    }
}

/// The residual bound a `converged` status by `c` states.
fn converged_bound(r: &StaticReport, c: StaticCriterion) -> f64 {
    let base = r.residual_tolerance_n.max(r.residual_floor_n);
    match c {
        StaticCriterion::Increment => INCREMENT_RESIDUAL_MULTIPLE * base,
        StaticCriterion::Residual | StaticCriterion::RoundOffFloor => base,
    }
}

/// Whether every number of a static report is finite: its residual and
/// step, the tolerance, floor and load scale they are judged by, and its
/// wall time (also used by `tests/bad_inputs.rs`).
pub fn report_is_finite(r: &StaticReport) -> bool {
    [
        r.residual_norm_n,
        r.residual_tolerance_n,
        r.residual_floor_n,
        r.load_scale_n,
        r.increment_norm_m,
        r.wall_time_s,
    ]
    .iter()
    .all(|v| v.is_finite())
}

/// The report of a returned solve: every number finite, a converged status
/// within its bound, negative eigenvalues warned.
pub fn check_static_report(r: &StaticReport) {
    assert!(report_is_finite(r), "non-finite number in the report: {r}");
    if let Some(c) = r.status.criterion() {
        let bound = converged_bound(r, c);
        assert!(
            r.residual_norm_n <= bound,
            "converged ({}) with |Q| = {:e} above its bound {bound:e}: {r}",
            c.name(),
            r.residual_norm_n
        );
    }
    check_warnings(r);
}

/// The report of a failed solve: finite scales (its residual and step may
/// be the non-finite numbers a `non_finite` status names).
fn check_failed_report(r: &StaticReport) {
    assert!(!r.status.is_converged(), "a converged solve failed: {r}");
    for v in [
        r.residual_tolerance_n,
        r.residual_floor_n,
        r.load_scale_n,
        r.wall_time_s,
    ] {
        assert!(v.is_finite(), "non-finite scale in a failed report: {r}");
    }
    if !matches!(r.status, StaticStatus::NonFinite { .. }) {
        assert!(
            r.residual_norm_n.is_finite() && r.increment_norm_m.is_finite(),
            "non-finite residual or step without a non_finite status: {r}"
        );
    }
    check_warnings(r);
}

fn check_warnings(r: &StaticReport) {
    if let Some(k) = r.negative_eigenvalues
        && k > 0
    {
        assert!(
            r.warnings.iter().any(|w| matches!(
                w,
                StaticWarning::Unstable { negative_eigenvalues } if *negative_eigenvalues == k
            )),
            "{k} negative eigenvalues without the unstable warning: {r}"
        );
    }
}

/// What `softrod estimate` does with the scene text (and a markers text, or
/// without one, markers synthesized on the solved shape with noise seeded
/// by `seed`): parse, build, solve, estimate with both backends, the
/// estimator kept warm over the frames; every answer checked.
pub fn estimate_scene(text: &str, markers: Option<&str>, seed: u64) {
    let Some(scene) = parse(text, MAX_ESTIMATE_ELEMENTS) else {
        return;
    };
    let settings = match scene.estimator_settings() {
        Ok(s) => s,
        Err(e) => {
            render(&e);
            return;
        }
    };
    if settings.bounds.len() > MAX_MARKERS {
        return;
    }
    with_robot!(scene, |robot, loads| estimate_checked(
        &scene, &robot, &loads, settings, markers, seed
    ));
}

/// The observations to estimate from: the markers file's frames, or two
/// frames synthesized on the scene's equilibrium (its markers, or the tip
/// without any), seeded noise of the stated σ; `None` when refused or
/// beyond the caps.
fn observations<E: Element + 'static>(
    scene: &Scene,
    robot: &Robot<E>,
    loads: &Loads,
    sigma_m: f64,
    markers: Option<&str>,
    seed: u64,
) -> Option<Vec<Observation>> {
    if let Some(text) = markers {
        let file = match MarkersFile::from_json(text)
            .and_then(|m| m.check_work(robot.n_elements()).map(|()| m))
        {
            Ok(m) => m,
            Err(e) => {
                render(&e);
                return None;
            }
        };
        let obs: Vec<Observation> = file.observations().into_iter().map(|(_, o)| o).collect();
        let within = obs.len() <= MAX_FRAMES && obs.iter().all(|o| o.markers.len() <= MAX_MARKERS);
        return within.then_some(obs);
    }
    let eq = solve_checked(scene, robot, loads)?;
    let mut sites = Vec::new();
    for m in scene.markers.iter().take(MAX_MARKERS) {
        let s = match (m.node, m.s_m) {
            (Some(n), _) => *robot
                .node_arc()
                .get(n)
                .unwrap_or_else(|| panic!("validated marker node {n} off the robot")),
            (None, Some(s)) => s,
            (None, None) => panic!("a validated marker without node or s_m"),
        };
        sites.push(Site::Rod { rod: 0, s_m: s });
    }
    if sites.is_empty() {
        sites.push(Site::Rod {
            rod: 0,
            s_m: robot.length(),
        });
    }
    let exact = match Observation::of_sites(robot, eq.q.as_slice(), &sites) {
        Ok(o) => o,
        Err(e) => panic!("markers of a validated scene refused on its equilibrium: {e}"),
    };
    Some(
        (0..2)
            .map(|k| exact.clone().with_noise(sigma_m, seed.wrapping_add(k)))
            .collect(),
    )
}

/// Both backends over the observations, every estimate checked.
fn estimate_checked<E: Element + 'static>(
    scene: &Scene,
    robot: &Robot<E>,
    loads: &Loads,
    mut settings: EstimatorSettings,
    markers: Option<&str>,
    seed: u64,
) {
    let Some(frames) = observations(scene, robot, loads, settings.noise_sigma_m, markers, seed)
    else {
        return;
    };
    for backend in [Backend::Newton, Backend::Sqp] {
        settings.backend = backend;
        let mut est = match settings.build_for(robot, loads) {
            Ok(e) => e,
            Err(e) => {
                render(&e);
                continue;
            }
        };
        for obs in &frames {
            match est.step(obs) {
                Ok(e) => check_estimate(&e, obs),
                Err(e) => {
                    render(&e);
                }
            }
        }
    }
}

/// A returned estimate (converged or the last iterate): every number
/// finite; converged only if its misfit passed the fit test, and then with
/// finite covariances.
pub fn check_estimate(e: &Estimate, obs: &Observation) {
    reached::count(&reached::ESTIMATES);
    let r = &e.report;
    let what = || format!("{} estimate, {}: {r:?}", r.backend.name(), r.status);
    let vectors = [
        ("q", &e.q),
        ("f", &e.f),
        ("resultant_force_n", &e.resultant_force_n),
        ("resultant_moment_nm", &e.resultant_moment_nm),
        ("marker_residuals", &e.marker_residuals),
    ];
    for (name, v) in vectors {
        assert!(
            v.iter().all(|x| x.is_finite()),
            "non-finite {name}: {}",
            what()
        );
    }
    for (name, v) in [
        ("noise_sigma_m", e.noise_sigma_m),
        ("objective", r.objective),
        ("weighted_residual", r.weighted_residual),
        ("gradient_norm", r.gradient_norm),
        ("equilibrium_residual_n", r.equilibrium_residual_n),
        ("alpha", r.alpha),
        ("wall_time_s", r.wall_time_s),
    ] {
        assert!(v.is_finite(), "non-finite report.{name} = {v}: {}", what());
    }
    let n_ob = obs.n_components();
    assert_eq!(r.n_observations, n_ob, "{}", what());
    assert_eq!(e.marker_residuals.len(), n_ob, "{}", what());
    if !r.status.is_converged() {
        return;
    }
    reached::count(&reached::CONVERGED_ESTIMATES);
    if n_ob > 0 {
        let quantile = chi2_quantile(FIT_QUANTILE, n_ob);
        assert!(
            r.weighted_residual <= quantile,
            "converged with a weighted misfit {:e} above the chi-square quantile {quantile:e}: {}",
            r.weighted_residual,
            what()
        );
    }
    let cov = e.resultant_force_cov();
    assert!(
        cov.iter().all(|x| x.is_finite()),
        "converged with a non-finite resultant covariance {cov}: {}",
        what()
    );
    assert!(
        (0..cov.nrows()).all(|i| cov[(i, i)] >= 0.0),
        "converged with a negative resultant variance {cov}: {}",
        what()
    );
    assert!(
        e.std_f().iter().all(|x| x.is_finite()),
        "converged with a non-finite std_f: {}",
        what()
    );
}
