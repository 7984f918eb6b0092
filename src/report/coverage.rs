//! Coverage of the reported uncertainty: how often the true resultant
//! force lies in the estimate's 95 % region.
//!
//! Every trial draws, from its seed, a load the estimator is not told
//! about, a marker set and a noise level; a "real robot" makes the
//! measurement and the estimator (the two-section robot of
//! [`Scene::two_section`], 2 × 10 elements, its known pressures and
//! self-weight) estimates the load with `α` by [`AlphaRule`]. The real robot
//! is *not* the estimator's model: a mesh twice as fine (2 × 20 elements),
//! its own static solve, marker positions read off it at arc coordinates
//! that are not nodes of the coarse mesh.
//!
//! - Load families ([`Family`]): `smooth` (a table of 41 entries of a
//!   random sum of the first four cosine modes over the robot, both
//!   components, amplitude 0.2–2 N/m log-uniform), `point` (one force of
//!   0.02–0.3 N log-uniform in a random direction at a random arc
//!   coordinate in `[0.3 L, L]`), `two_point` (two such forces, drawn
//!   independently), `sine` (`A sin(2π k X / L + φ)` in a random
//!   direction, `A` 0.2–2 N/m log-uniform, `k` 0.5–4 waves, `φ` uniform;
//!   a table of 81 entries), `payload` (a uniform load of 0.2–2 N/m
//!   log-uniform in a random direction plus a tip mass of 2–30 g
//!   log-uniform under gravity), and a `mixture` of any set of them,
//!   summed.
//! - Markers: the tip and 2–10 more at uniformly drawn arc coordinates in
//!   `[0.1 L, L]` (3–11 in all), seeded Gaussian noise of σ = 5–100 µm
//!   (log-uniform), the estimator told that σ.
//!
//! A trial is covered when the true resultant lies in the 95 % ellipse of
//! the reported covariance (`d² = Δᵀ Σ⁻¹ Δ ≤ χ²₂(0.95) = 5.991`); also per
//! component (`|Δ_i| ≤ 1.96 σ_i`, what `force_std_n` promises). A trial
//! that did not converge counts as not covered.
//! Outputs: `coverage.{png,svg,json}`.

use std::path::{Path, PathBuf};

use nalgebra::Vector2;
use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::assembly::Robot;
use crate::element::PlanarCable;
use crate::error::Result;
use crate::estimate::{AlphaRule, Backend, EstimatorSettings, MarkerObservation, Observation};
use crate::loads::{LineLoad, Loads, PointForce};
use crate::rng::SplitMix64;
use crate::scene::Scene;
use crate::statics::StaticSolver;

use super::{Machine, ReportOptions, plot, progress, write_json};

/// `χ²` with two degrees of freedom at 0.95: `−2 ln 0.05`.
pub(crate) const CHI2_2_95: f64 = 5.991_464_547_107_979;

/// A family of true loads.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    /// A smooth distributed load (four cosine modes per component).
    Smooth,
    /// One concentrated force at an arc coordinate.
    Point,
    /// Two concentrated forces at independent arc coordinates.
    TwoPoint,
    /// A sine wave along the arc in one random direction (random
    /// wavenumber, phase and amplitude).
    Sine,
    /// A payload: a uniform distributed load in a random direction plus a
    /// tip mass (a force along gravity at the tip).
    Payload,
    /// Every kind of the set at once, each drawn as its own family draws
    /// it, summed: the guard family a test draws at random per run.
    Mixture(KindSet),
}

/// A set of the single families (`Smooth` … `Payload`), as the bits
/// `1 << index` of [`Family::SINGLE`]: the kinds a [`Family::Mixture`]
/// sums.
///
/// # Example
/// ```
/// use softrod::report::coverage::{Family, KindSet};
/// let k = KindSet::from_bits(0b10110);
/// assert_eq!(k.kinds(), vec![Family::Point, Family::TwoPoint, Family::Payload]);
/// assert_eq!(Family::Mixture(k).label(), "mixture(point+two_point+payload)");
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct KindSet(u8);

impl KindSet {
    /// The set of bits `bits` (bits beyond the single families dropped).
    pub fn from_bits(bits: u8) -> Self {
        KindSet(bits & ((1 << Family::SINGLE.len()) - 1))
    }

    /// The kinds in the set, in [`Family::SINGLE`]'s order.
    pub fn kinds(self) -> Vec<Family> {
        Family::SINGLE
            .iter()
            .enumerate()
            .filter(|(i, _)| self.0 & (1 << i) != 0)
            .map(|(_, f)| *f)
            .collect()
    }
}

impl Family {
    /// The single families, in the order of their index (the first two
    /// are the original study's, their seeded trials unchanged).
    pub const SINGLE: [Family; 5] = [
        Family::Smooth,
        Family::Point,
        Family::TwoPoint,
        Family::Sine,
        Family::Payload,
    ];

    /// The family's name (a mixture's: `mixture`; see [`Family::label`]).
    pub fn name(self) -> &'static str {
        match self {
            Family::Smooth => "smooth",
            Family::Point => "point",
            Family::TwoPoint => "two_point",
            Family::Sine => "sine",
            Family::Payload => "payload",
            Family::Mixture(_) => "mixture",
        }
    }

    /// The name with a mixture's kinds: `mixture(point+sine)`.
    pub fn label(self) -> String {
        match self {
            Family::Mixture(k) => format!(
                "mixture({})",
                k.kinds()
                    .iter()
                    .map(|f| f.name())
                    .collect::<Vec<_>>()
                    .join("+")
            ),
            f => f.name().to_string(),
        }
    }

    /// The number the family's trials mix into their seeds (the single
    /// families' index; a mixture's `0x100` plus its set).
    fn stream(self) -> u64 {
        match self {
            Family::Smooth => 0,
            Family::Point => 1,
            Family::TwoPoint => 2,
            Family::Sine => 3,
            Family::Payload => 4,
            Family::Mixture(k) => 0x100 | k.0 as u64,
        }
    }
}

/// What one trial draws from its seed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialSpec {
    /// The load family.
    pub family: Family,
    /// The seed everything below is drawn from.
    pub seed: u64,
    /// The unknown distributed load, if the family has one.
    pub line_loads: Vec<LineLoad>,
    /// The unknown concentrated forces, if the family has them.
    pub point_forces: Vec<PointForce>,
    /// Marker arc coordinates (m), increasing, the tip last.
    pub marker_s_m: Vec<f64>,
    /// Marker noise σ (m), per component.
    pub noise_sigma_m: f64,
}

/// The outcome of one trial for one backend.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialOutcome {
    /// The family.
    pub family: Family,
    /// The backend.
    pub backend: Backend,
    /// The trial's seed.
    pub seed: u64,
    /// Number of markers.
    pub markers: usize,
    /// Marker noise σ (m).
    pub noise_sigma_m: f64,
    /// The true resultant of the unknown load (N).
    pub truth_n: [f64; 2],
    /// The estimated resultant (N).
    pub estimate_n: [f64; 2],
    /// The reported standard deviations (N).
    pub std_n: [f64; 2],
    /// Squared Mahalanobis distance of the truth under the reported
    /// covariance (`NaN` if the estimation failed).
    pub d2: f64,
    /// The truth in the 95 % ellipse (and the estimate converged).
    pub covered: bool,
    /// The truth within 1.96 σ in each component.
    pub covered_components: [bool; 2],
    /// The `α` chosen.
    pub alpha: f64,
    /// The estimator's status, or the error.
    pub status: String,
    /// Whether it converged.
    pub converged: bool,
    /// Load directions the markers determine
    /// ([`crate::estimate::Estimate::determined_directions`]; `NaN` if the
    /// estimation failed).
    #[serde(default)]
    pub determined_directions: f64,
    /// The estimate said its σ is (mostly) a prior's width
    /// ([`crate::estimate::Estimate::weakly_informed`]).
    #[serde(default)]
    pub weakly_informed: bool,
    /// The fraction of the resultant's prior variance the markers leave
    /// ([`crate::estimate::Estimate::resultant_prior_fraction`]; `NaN` if
    /// the estimation failed).
    #[serde(default)]
    pub resultant_prior_fraction: f64,
}

impl TrialOutcome {
    /// [`TrialOutcome::truth_n`] as a vector (N).
    ///
    /// # Example
    /// ```
    /// use softrod::report::coverage::{Family, TrialOutcome};
    /// let o = TrialOutcome { family: Family::Smooth, backend: softrod::estimate::Backend::Newton,
    ///     seed: 1, markers: 4, noise_sigma_m: 1e-5, truth_n: [0.02, -0.1], estimate_n: [0.021, -0.098],
    ///     std_n: [0.002, 0.004], d2: 0.5, covered: true, covered_components: [true; 2], alpha: 1e-6,
    ///     status: "converged".into(), converged: true, determined_directions: 1.8, weakly_informed: false,
    ///     resultant_prior_fraction: 0.3 };
    /// assert!((o.estimate() - o.truth()).norm() < 3e-3 && o.std().x == 0.002);
    /// assert!(o.z().iter().all(|z| (z + 0.5).abs() < 1e-12));
    /// ```
    pub fn truth(&self) -> Vector2<f64> {
        Vector2::from(self.truth_n)
    }

    /// [`TrialOutcome::estimate_n`] as a vector (N).
    ///
    /// # Example
    /// See [`TrialOutcome::truth`].
    pub fn estimate(&self) -> Vector2<f64> {
        Vector2::from(self.estimate_n)
    }

    /// [`TrialOutcome::std_n`] as a vector (N, per component).
    ///
    /// # Example
    /// See [`TrialOutcome::truth`].
    pub fn std(&self) -> Vector2<f64> {
        Vector2::from(self.std_n)
    }

    /// The standardized errors `z_i = (truth_i − estimate_i) / σ_i` of the
    /// components (none if the trial did not converge; a zero σ gives an
    /// infinite `z`).
    ///
    /// # Example
    /// See [`TrialOutcome::truth`].
    pub fn z(&self) -> Vec<f64> {
        if !self.converged {
            return Vec::new();
        }
        (0..2)
            .map(|a| (self.truth_n[a] - self.estimate_n[a]) / self.std_n[a])
            .collect()
    }
}

/// Coverage of one family and backend.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoverageRow {
    /// The family.
    pub family: Family,
    /// The backend.
    pub backend: Backend,
    /// Trials run.
    pub trials: usize,
    /// Trials that converged.
    pub converged: usize,
    /// Fraction of trials whose truth lies in the 95 % ellipse.
    pub coverage: f64,
    /// Fractions per component (x, y) within 1.96 σ.
    pub coverage_components: [f64; 2],
    /// Median `d²` (the χ²₂ median is 1.386).
    pub median_d2: f64,
    /// Median relative error of the resultant `|Δ| / |F_true|`.
    pub median_rel_error: f64,
    /// Trials the estimate flagged weakly informed.
    #[serde(default)]
    pub flagged: usize,
    /// Fraction of trials covered or flagged (a miss the estimate did not
    /// warn of is neither).
    #[serde(default)]
    pub covered_or_flagged: f64,
    /// Fraction of the components whose `z = Δ_i / σ_i` exceeds 4 in
    /// magnitude (a normal `z`: 6e-5).
    #[serde(default)]
    pub z_beyond_4: f64,
    /// Where the misses are.
    #[serde(default)]
    pub misses: Misses,
}

/// Covered trials out of trials, in one class.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Tally {
    /// Trials in the ellipse.
    pub covered: usize,
    /// Trials.
    pub trials: usize,
}

/// Where a row's misses are: the coverage by the evidence's `α` (m/N²:
/// below 1e2, 1e2–1e3, from 1e3), by marker count (3–5, 6–8, 9–11) and by
/// noise (below 20 µm, 20–50 µm, from 50 µm).
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Misses {
    /// Trials not in the ellipse.
    pub total: usize,
    /// Of those, the ones the estimate flagged weakly informed.
    pub flagged: usize,
    /// Of those, the shrunk estimates (the truth farther from zero than the
    /// estimate).
    pub shrunk: usize,
    /// By `α`: below 1e2, 1e2–1e3, from 1e3.
    pub by_alpha: [Tally; 3],
    /// By marker count: 3–5, 6–8, 9–11.
    pub by_markers: [Tally; 3],
    /// By noise: below 20 µm, 20–50 µm, from 50 µm.
    pub by_noise: [Tally; 3],
}

impl Misses {
    /// The breakdown of `outcomes`.
    fn of(outcomes: &[&TrialOutcome]) -> Self {
        let class =
            |x: f64, edges: [f64; 2]| usize::from(x >= edges[0]) + usize::from(x >= edges[1]);
        let mut m = Misses::default();
        for o in outcomes {
            let cells = [
                (&mut m.by_alpha, class(o.alpha, [1e2, 1e3])),
                (&mut m.by_markers, class(o.markers as f64, [6.0, 9.0])),
                (&mut m.by_noise, class(o.noise_sigma_m, [2e-5, 5e-5])),
            ];
            for (tallies, k) in cells {
                tallies[k].trials += 1;
                tallies[k].covered += usize::from(o.covered);
            }
            if !o.covered {
                m.total += 1;
                m.flagged += usize::from(o.weakly_informed);
                m.shrunk += usize::from(o.truth().norm() > o.estimate().norm());
            }
        }
        m
    }
}

/// The coverage study.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoverageReport {
    /// The rule `α` was chosen by.
    pub alpha_rule: AlphaRule,
    /// Trials per family.
    pub trials_per_family: usize,
    /// The first seed (trial `k` of a family uses `seed + k`).
    pub seed: u64,
    /// One row per family and backend.
    pub rows: Vec<CoverageRow>,
    /// Every trial.
    pub outcomes: Vec<TrialOutcome>,
    /// The machine.
    pub machine: Machine,
}

/// The estimator's scene: the two-section robot.
pub fn scene() -> Scene {
    Scene::two_section()
}

/// The robot of `scene` with `elements` per section.
fn robot(scene: &Scene, elements: usize) -> Result<Robot<PlanarCable>> {
    let mut s = scene.clone();
    for sec in &mut s.robot.sections {
        sec.elements = elements;
    }
    s.robot()
}

/// What trial `seed` of `family` draws, on a robot of length `length_m`:
/// the markers and the noise first, then the load (a mixture draws its
/// kinds in [`Family::SINGLE`]'s order from the same stream).
pub(crate) fn trial_spec(family: Family, seed: u64, length_m: f64) -> TrialSpec {
    let mut rng = SplitMix64::new(seed.wrapping_mul(0x2545_F491_4F6C_DD1D) ^ family.stream());
    let l = length_m;
    let n = 3 + (rng.uniform() * 9.0) as usize; // 3..=11
    let mut marker_s_m: Vec<f64> = (1..n).map(|_| rng.range(0.1 * l, l)).collect();
    marker_s_m.sort_by(f64::total_cmp);
    marker_s_m.push(l);
    let noise_sigma_m = rng.log_range(5e-6, 1e-4);
    let (mut line_loads, mut point_forces) = (Vec::new(), Vec::new());
    let kinds = match family {
        Family::Mixture(k) => k.kinds(),
        f => vec![f],
    };
    for kind in kinds {
        draw_load(kind, &mut rng, l, &mut line_loads, &mut point_forces);
    }
    TrialSpec {
        family,
        seed,
        line_loads,
        point_forces,
        marker_s_m,
        noise_sigma_m,
    }
}

/// Tip masses of the `payload` family (kg, log-uniform); with the
/// scene's gravity a tip force of 0.02–0.29 N.
const TIP_MASS_KG: (f64, f64) = (0.002, 0.03);

/// Intervals of the `sine` family's table (81 entries: 20 per wave at
/// the largest wavenumber; `smooth` keeps the original study's 41).
const SINE_TABLE: usize = 80;

/// One kind's load drawn from `rng` (a single family; a mixture is not a
/// kind), pushed to `line_loads` / `point_forces`.
fn draw_load(
    kind: Family,
    rng: &mut SplitMix64,
    l: f64,
    line_loads: &mut Vec<LineLoad>,
    point_forces: &mut Vec<PointForce>,
) {
    use std::f64::consts::PI;
    let table = |m: usize, w: &dyn Fn(f64) -> [f64; 2]| {
        let s_m: Vec<f64> = (0..=m).map(|i| l * i as f64 / m as f64).collect();
        let w_n_per_m = s_m.iter().map(|&s| w(s).to_vec()).collect();
        LineLoad::Tabulated { s_m, w_n_per_m }
    };
    let point = |rng: &mut SplitMix64, lo: f64| {
        let mag = rng.log_range(0.02, 0.3);
        let ang = rng.range(0.0, 2.0 * PI);
        let s = rng.range(lo * l, l);
        PointForce {
            s_m: s,
            force_n: vec![mag * ang.cos(), mag * ang.sin()],
        }
    };
    match kind {
        Family::Smooth => {
            let amp = rng.log_range(0.2, 2.0);
            let c: Vec<[f64; 2]> = (0..4)
                .map(|k| {
                    let s = amp / (1.0 + k as f64);
                    [rng.range(-s, s), rng.range(-s, s)]
                })
                .collect();
            line_loads.push(table(40, &|s| {
                [0, 1].map(|a| {
                    c.iter()
                        .enumerate()
                        .map(|(k, ck)| ck[a] * (k as f64 * PI * s / l).cos())
                        .sum()
                })
            }));
        }
        Family::Point => point_forces.push(point(rng, 0.3)),
        Family::TwoPoint => {
            point_forces.push(point(rng, 0.3));
            point_forces.push(point(rng, 0.3));
        }
        Family::Sine => {
            let amp = rng.log_range(0.2, 2.0);
            let ang = rng.range(0.0, 2.0 * PI);
            let waves = rng.range(0.5, 4.0);
            let phase = rng.range(0.0, 2.0 * PI);
            line_loads.push(table(SINE_TABLE, &|s| {
                let w = amp * (2.0 * PI * waves * s / l + phase).sin();
                [w * ang.cos(), w * ang.sin()]
            }));
        }
        Family::Payload => {
            let amp = rng.log_range(0.2, 2.0);
            let ang = rng.range(0.0, 2.0 * PI);
            // uniform: a table of two entries, base to tip
            line_loads.push(table(1, &|_| [amp * ang.cos(), amp * ang.sin()]));
            let m = rng.log_range(TIP_MASS_KG.0, TIP_MASS_KG.1);
            point_forces.push(PointForce {
                s_m: l,
                force_n: (crate::params::GRAVITY_M_PER_S2 * m).as_slice().to_vec(),
            });
        }
        Family::Mixture(_) => {}
    }
}

/// The true resultant of the spec's unknown load (N): the tables integrated
/// exactly (linear between entries), plus the forces.
///
/// # Example
/// ```
/// use softrod::loads::PointForce;
/// use softrod::report::coverage::{true_resultant, Family, TrialSpec};
/// let spec = TrialSpec { family: Family::Point, seed: 1, line_loads: vec![],
///     point_forces: vec![PointForce { s_m: 0.2, force_n: vec![0.01, -0.02] }],
///     marker_s_m: vec![0.12, 0.24], noise_sigma_m: 1e-5 };
/// assert_eq!(true_resultant(&spec), nalgebra::Vector2::new(0.01, -0.02));
/// ```
pub fn true_resultant(spec: &TrialSpec) -> Vector2<f64> {
    let mut r = [0.0; 2];
    for ll in &spec.line_loads {
        let LineLoad::Tabulated { s_m, w_n_per_m } = ll else {
            continue; // the families draw tables only
        };
        for k in 1..s_m.len() {
            let h = s_m[k] - s_m[k - 1];
            for (a, ra) in r.iter_mut().enumerate() {
                *ra += 0.5 * h * (w_n_per_m[k - 1][a] + w_n_per_m[k][a]);
            }
        }
    }
    for p in &spec.point_forces {
        r[0] += p.force_n[0];
        r[1] += p.force_n[1];
    }
    Vector2::from(r)
}

/// The real robot's markers for `spec`: the fine mesh's static solution
/// under the known loads and the unknown one, read at the marker arc
/// coordinates, with seeded noise.
pub fn measure(fine: &Robot<PlanarCable>, known: &Loads, spec: &TrialSpec) -> Result<Observation> {
    let mut loads = known.clone();
    loads.line_loads.extend(spec.line_loads.iter().cloned());
    loads.point_forces.extend(spec.point_forces.iter().cloned());
    let eq = StaticSolver::default().solve(fine, &loads, None)?;
    let markers = spec
        .marker_s_m
        .iter()
        .map(|&s| {
            Ok(MarkerObservation::at_arc(
                s,
                fine.position_at(eq.q.as_slice(), s)?,
            ))
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Observation { markers }.with_noise(spec.noise_sigma_m, spec.seed ^ 0x5EED))
}

/// Runs one trial: the measurement on the fine robot, the estimate on the
/// coarse one (`coarse`, the estimator's model) by `backend` with `rule`.
pub fn run_trial(
    coarse: &Robot<PlanarCable>,
    fine: &Robot<PlanarCable>,
    known: &Loads,
    spec: &TrialSpec,
    backend: Backend,
    rule: AlphaRule,
) -> TrialOutcome {
    let truth_n = true_resultant(spec);
    let mut out = TrialOutcome {
        family: spec.family,
        backend,
        seed: spec.seed,
        markers: spec.marker_s_m.len(),
        noise_sigma_m: spec.noise_sigma_m,
        truth_n: truth_n.into(),
        estimate_n: [f64::NAN; 2],
        std_n: [f64::NAN; 2],
        d2: f64::NAN,
        covered: false,
        covered_components: [false; 2],
        alpha: f64::NAN,
        status: String::new(),
        converged: false,
        determined_directions: f64::NAN,
        weakly_informed: false,
        resultant_prior_fraction: f64::NAN,
    };
    let settings = EstimatorSettings {
        backend,
        alpha_rule: rule,
        noise_sigma_m: spec.noise_sigma_m,
        ..EstimatorSettings::default()
    };
    let est =
        measure(fine, known, spec).and_then(|obs| settings.build_for(coarse, known)?.step(&obs));
    let e = match est {
        Ok(e) => e,
        Err(err) => {
            out.status = err.to_string();
            return out;
        }
    };
    let f = &e.resultant_force_n;
    let c = e.resultant_force_cov();
    let dx = [truth_n[0] - f[0], truth_n[1] - f[1]];
    let det = c[0] * c[3] - c[1] * c[2];
    out.d2 = if det > 0.0 {
        (c[3] * dx[0] * dx[0] - (c[1] + c[2]) * dx[0] * dx[1] + c[0] * dx[1] * dx[1]) / det
    } else {
        f64::INFINITY
    };
    out.estimate_n = [f[0], f[1]];
    out.std_n = [c[0].max(0.0).sqrt(), c[3].max(0.0).sqrt()];
    out.converged = e.report.status.is_converged();
    out.covered = out.converged && out.d2 <= CHI2_2_95;
    out.covered_components = [0, 1].map(|a| out.converged && dx[a].abs() <= 1.96 * out.std_n[a]);
    out.alpha = e.report.alpha;
    out.determined_directions = e.determined_directions();
    out.weakly_informed = e.weakly_informed();
    out.resultant_prior_fraction = e.resultant_prior_fraction();
    out.status = e.report.status.to_string();
    out
}

/// The rows of `outcomes`, one per family and backend present.
pub(crate) fn summarize(outcomes: &[TrialOutcome]) -> Vec<CoverageRow> {
    let mut keys: Vec<(Family, Backend)> = outcomes.iter().map(|o| (o.family, o.backend)).collect();
    keys.sort_by_key(|(f, b)| (*f, b.name()));
    keys.dedup();
    keys.into_iter()
        .map(|(family, backend)| {
            let os: Vec<&TrialOutcome> = outcomes
                .iter()
                .filter(|o| o.family == family && o.backend == backend)
                .collect();
            let n = os.len().max(1) as f64;
            let frac =
                |p: &dyn Fn(&TrialOutcome) -> bool| os.iter().filter(|o| p(o)).count() as f64 / n;
            let median = |mut v: Vec<f64>| {
                v.retain(|x| !x.is_nan());
                v.sort_by(f64::total_cmp);
                v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
            };
            CoverageRow {
                family,
                backend,
                trials: os.len(),
                converged: os.iter().filter(|o| o.converged).count(),
                coverage: frac(&|o| o.covered),
                coverage_components: [
                    frac(&|o| o.covered_components[0]),
                    frac(&|o| o.covered_components[1]),
                ],
                median_d2: median(os.iter().map(|o| o.d2).collect()),
                median_rel_error: median(
                    os.iter()
                        .map(|o| {
                            (o.estimate_n[0] - o.truth_n[0]).hypot(o.estimate_n[1] - o.truth_n[1])
                                / o.truth_n[0].hypot(o.truth_n[1])
                        })
                        .collect(),
                ),
                flagged: os.iter().filter(|o| o.weakly_informed).count(),
                covered_or_flagged: frac(&|o| o.covered || o.weakly_informed),
                z_beyond_4: {
                    let z: Vec<f64> = os.iter().flat_map(|o| o.z()).collect();
                    z.iter().filter(|v| v.abs() > 4.0).count() as f64 / z.len().max(1) as f64
                },
                misses: Misses::of(&os),
            }
        })
        .collect()
}

/// Runs `trials` trials per family (seeds `seed ..`) for each backend.
///
/// # Errors
/// As [`Scene::robot`] and [`Scene::loads`] for the fixed scene (they do
/// not fail); a failing trial is an outcome.
pub fn sweep(
    trials: usize,
    seed: u64,
    backends: &[Backend],
    families: &[Family],
    rule: AlphaRule,
    quiet: bool,
) -> Result<CoverageReport> {
    let sc = scene();
    let coarse = robot(&sc, 10)?;
    let fine = robot(&sc, 20)?;
    let known = sc.loads()?;
    let l = coarse.length();
    let mut machine = Machine::detect();
    let cases: Vec<(TrialSpec, Backend)> = families
        .iter()
        .flat_map(|&fam| (0..trials).map(move |k| trial_spec(fam, seed + k as u64, l)))
        .flat_map(|spec| backends.iter().map(move |&b| (spec.clone(), b)))
        .collect();
    let pb = progress(cases.len(), quiet, "coverage");
    let outcomes: Vec<TrialOutcome> = cases
        .par_iter()
        .map(|(spec, b)| {
            let o = run_trial(&coarse, &fine, &known, spec, *b, rule);
            pb.inc(1);
            o
        })
        .collect();
    pb.finish_and_clear();
    machine.sample_load();
    Ok(CoverageReport {
        alpha_rule: rule,
        trials_per_family: trials,
        seed,
        rows: summarize(&outcomes),
        outcomes,
        machine,
    })
}

/// The report part: 200 trials per family (20 with `quick`), both backends,
/// `α` by the evidence; `coverage.{png,svg,json}` in the output directory.
///
/// # Errors
/// [`crate::Error::Io`] when a file cannot be written.
pub fn run(opts: &ReportOptions) -> Result<(CoverageReport, Vec<PathBuf>)> {
    let trials = if opts.quick { 20 } else { 200 };
    let r = sweep(
        trials,
        1,
        &[Backend::Newton, Backend::Sqp],
        &Family::SINGLE,
        AlphaRule::Evidence,
        opts.quiet,
    )?;
    let files = r.write(&opts.out_dir)?;
    Ok((r, files))
}

impl CoverageReport {
    /// Writes `coverage.{png,svg,json}` into `dir`.
    ///
    /// # Errors
    /// [`crate::Error::Io`] when a file cannot be written.
    pub fn write(&self, dir: &Path) -> Result<Vec<PathBuf>> {
        let json = dir.join("coverage.json");
        write_json(&json, self)?;
        let mut files = plot::both(
            dir,
            "coverage",
            (1640, 540),
            |a| draw(self, a),
            |a| draw(self, a),
        )?;
        files.push(json);
        Ok(files)
    }

    /// The rows as a Markdown table.
    pub fn markdown(&self) -> String {
        let mut s = String::from(
            "| load | backend | trials | converged | in 95 % ellipse | x within 1.96 σ | y within 1.96 σ | median d² (χ²₂: 1.39) | median error | flagged | covered or flagged | \\|z\\| > 4 |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        );
        for r in &self.rows {
            s += &format!(
                "| {} | {} | {} | {} | {:.1} % | {:.1} % | {:.1} % | {:.2} | {:.1} % | {} | {:.1} % | {:.1} % |\n",
                r.family.label(),
                r.backend.name(),
                r.trials,
                r.converged,
                100.0 * r.coverage,
                100.0 * r.coverage_components[0],
                100.0 * r.coverage_components[1],
                r.median_d2,
                100.0 * r.median_rel_error,
                r.flagged,
                100.0 * r.covered_or_flagged,
                100.0 * r.z_beyond_4,
            );
        }
        s
    }

    /// Where the misses are, one row per family and backend: misses (of
    /// them flagged, shrunk), then covered / trials by `α`, marker count
    /// and noise ([`Misses`]).
    pub fn misses_markdown(&self) -> String {
        let mut s = String::from(
            "| load | backend | misses | flagged | shrunk | α < 1e2 | 1e2–1e3 | ≥ 1e3 | 3–5 markers | 6–8 | 9–11 | σ < 20 µm | 20–50 µm | ≥ 50 µm |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        );
        for r in &self.rows {
            let m = &r.misses;
            s += &format!(
                "| {} | {} | {} | {} | {} |",
                r.family.label(),
                r.backend.name(),
                m.total,
                m.flagged,
                m.shrunk
            );
            for t in m.by_alpha.iter().chain(&m.by_markers).chain(&m.by_noise) {
                s += &format!(" {}/{} |", t.covered, t.trials);
            }
            s += "\n";
        }
        s
    }
}

/// A family's colour (the `sqp` backend's paler).
fn colour(f: Family, b: Backend) -> RGBColor {
    let RGBColor(r, g, bl) = match f {
        Family::Smooth => RGBColor(31, 119, 180),
        Family::Point => RGBColor(214, 39, 40),
        Family::TwoPoint => RGBColor(44, 160, 44),
        Family::Sine => RGBColor(148, 103, 189),
        Family::Payload => RGBColor(140, 86, 75),
        Family::Mixture(_) => RGBColor(100, 100, 100),
    };
    match b {
        Backend::Sqp => {
            let pale = |c: u8| ((c as u16 + 2 * 255) / 3) as u8;
            RGBColor(pale(r), pale(g), pale(bl))
        }
        _ => RGBColor(r, g, bl),
    }
}

/// The families of `r`'s rows, in row order, each once.
fn families(r: &CoverageReport) -> Vec<Family> {
    let mut f: Vec<Family> = r.rows.iter().map(|row| row.family).collect();
    f.dedup();
    f
}

/// Bins of the z histogram: width 0.5 over `[−Z_MAX, Z_MAX]`, a `z` beyond
/// counted in the outer bin.
const Z_MAX: f64 = 6.0;

/// (a) coverage per family and backend against the 95 % nominal rate and
/// the 90–99 % target band, with the rate of trials covered or flagged;
/// (b) the empirical distribution of `d²` against χ²₂'s, `P(d² ≤ x) = 1 −
/// exp(−x/2)` (calibrated intervals lie on it), `newton`; (c) the
/// histogram of the components' `z = Δ_i / σ_i` of every family (`newton`),
/// flagged and not, against the standard normal density.
fn draw<DB: DrawingBackend>(
    r: &CoverageReport,
    root: &DrawingArea<DB, Shift>,
) -> std::result::Result<(), String> {
    use plot::ms;
    root.fill(&WHITE).map_err(ms)?;
    let (left, rest) = root.split_horizontally(640);
    let (middle, right) = rest.split_horizontally(500);
    draw_rates(r, &left)?;
    draw_d2(r, &middle)?;
    draw_z(r, &right)
}

/// The legend of a panel's series at `at`.
fn legend<'a, DB: DrawingBackend + 'a, X: Ranged, Y: Ranged>(
    c: &mut ChartContext<'a, DB, Cartesian2d<X, Y>>,
    at: SeriesLabelPosition,
) -> std::result::Result<(), String> {
    c.configure_series_labels()
        .position(at)
        .background_style(WHITE.mix(0.85))
        .border_style(BLACK)
        .label_font(("sans-serif", 14))
        .draw()
        .map_err(plot::ms)
}

/// Panel (a) of [`draw`]: a group of bars per family (`newton` dark, `sqp`
/// pale), each with its binomial 95 % interval and a mark at the rate of
/// trials covered or flagged.
fn draw_rates<DB: DrawingBackend>(
    r: &CoverageReport,
    area: &DrawingArea<DB, Shift>,
) -> std::result::Result<(), String> {
    use plot::ms;
    let fams = families(r);
    let n = fams.len().max(1) as f64;
    // binomial standard error (%) of a row's rate
    let se_of = |row: &CoverageRow| {
        let p = row.coverage;
        100.0 * (p * (1.0 - p) / row.trials.max(1) as f64).sqrt()
    };
    let ymax = 130.0;
    let mut c = ChartBuilder::on(area)
        .caption(
            "(a) truth in the 95 % region (newton | sqp)",
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(0f64..n, 0f64..ymax)
        .map_err(ms)?;
    c.configure_mesh()
        .disable_x_mesh()
        .x_labels(0)
        .y_desc("coverage (%)")
        .y_label_formatter(&|v| {
            if *v <= 100.0 {
                format!("{v}")
            } else {
                String::new()
            }
        })
        .draw()
        .map_err(ms)?;
    super::layout::data_in(c.plotting_area());
    c.draw_series([Rectangle::new(
        [(0.0, 90.0), (n, 99.0)],
        RGBColor(222, 222, 222).filled(),
    )])
    .map_err(ms)?
    .label("90–99 % band, 95 % nominal")
    .legend(|(x, y)| {
        Rectangle::new(
            [(x, y - 5), (x + 18, y + 5)],
            RGBColor(222, 222, 222).filled(),
        )
    });
    c.draw_series([PathElement::new(
        vec![(0.0, 95.0), (n, 95.0)],
        BLACK.stroke_width(2),
    )])
    .map_err(ms)?;
    for row in &r.rows {
        let Some(i) = fams.iter().position(|f| *f == row.family) else {
            continue;
        };
        let x = i as f64
            + if row.backend == Backend::Sqp {
                0.5
            } else {
                0.0
            };
        let p = 100.0 * row.coverage;
        c.draw_series([Rectangle::new(
            [(x + 0.08, 0.0), (x + 0.44, p)],
            colour(row.family, row.backend).filled(),
        )])
        .map_err(ms)?;
        let se = se_of(row);
        c.draw_series([PathElement::new(
            vec![(x + 0.26, p - 1.96 * se), (x + 0.26, p + 1.96 * se)],
            BLACK.stroke_width(2),
        )])
        .map_err(ms)?;
        let cf = 100.0 * row.covered_or_flagged;
        c.draw_series([PathElement::new(
            vec![(x + 0.08, cf), (x + 0.44, cf)],
            RGBColor(230, 120, 0).stroke_width(3),
        )])
        .map_err(ms)?;
        // the rate above the bar, its interval and its mark
        c.draw_series([Text::new(
            format!("{p:.1}"),
            (x + 0.26, (p + 1.96 * se).max(cf) + 2.0),
            ("sans-serif", 13)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Center, VPos::Bottom)),
        )])
        .map_err(ms)?;
    }
    // the legend entry of the marks (drawn off the data)
    c.draw_series([PathElement::new(
        vec![(-1.0, -1.0), (-1.0, -1.0)],
        RGBColor(230, 120, 0).stroke_width(3),
    )])
    .map_err(ms)?
    .label("covered or flagged")
    .legend(|(x, y)| {
        PathElement::new(
            vec![(x, y), (x + 18, y)],
            RGBColor(230, 120, 0).stroke_width(3),
        )
    });
    // the groups' names below the axis
    super::layout::annotations();
    for (i, f) in fams.iter().enumerate() {
        c.draw_series([EmptyElement::at((i as f64 + 0.5, 0.0))
            + Text::new(
                f.name().to_string(),
                (0, 8),
                ("sans-serif", 15)
                    .into_font()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Center, VPos::Top)),
            )])
        .map_err(ms)?;
    }
    legend(&mut c, SeriesLabelPosition::UpperLeft)
}

/// Panel (b) of [`draw`]: the empirical distribution of `d²` per family
/// (`newton`; the backends agree) against χ²₂'s.
fn draw_d2<DB: DrawingBackend>(
    r: &CoverageReport,
    area: &DrawingArea<DB, Shift>,
) -> std::result::Result<(), String> {
    use plot::ms;
    let xmax = 16.0;
    let mut c = ChartBuilder::on(area)
        .caption("(b) P(d² ≤ x) against χ²₂ (newton)", ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(0f64..xmax, 0f64..1f64)
        .map_err(ms)?;
    c.configure_mesh()
        .x_desc("squared Mahalanobis distance d² of the truth")
        .y_desc("fraction of trials")
        .draw()
        .map_err(ms)?;
    super::layout::data_in(c.plotting_area());
    c.draw_series(LineSeries::new(
        (0..=160).map(|i| {
            let x = xmax * i as f64 / 160.0;
            (x, 1.0 - (-x / 2.0).exp())
        }),
        BLACK.stroke_width(3),
    ))
    .map_err(ms)?
    .label("χ²₂ (calibrated)")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(3)));
    for row in r.rows.iter().filter(|row| row.backend == Backend::Newton) {
        let mut d: Vec<f64> = r
            .outcomes
            .iter()
            .filter(|o| o.family == row.family && o.backend == row.backend)
            .map(|o| {
                if o.converged && !o.d2.is_nan() {
                    o.d2
                } else {
                    f64::INFINITY
                }
            })
            .collect();
        d.sort_by(f64::total_cmp);
        let m = d.len().max(1) as f64;
        let col = colour(row.family, row.backend);
        c.draw_series(LineSeries::new(
            d.iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite())
                .map(|(i, v)| (v.min(xmax), (i + 1) as f64 / m)),
            col.stroke_width(2),
        ))
        .map_err(ms)?
        .label(row.family.name())
        .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], col.stroke_width(2)));
    }
    super::layout::annotations();
    legend(&mut c, SeriesLabelPosition::LowerRight)
}

/// Panel (c) of [`draw`]: the density of `z` over all families' components
/// (`newton`), the trials not flagged (bars) and the flagged ones (a
/// step line), each as a fraction of all, against `N(0, 1)`; log scale.
fn draw_z<DB: DrawingBackend>(
    r: &CoverageReport,
    area: &DrawingArea<DB, Shift>,
) -> std::result::Result<(), String> {
    use plot::ms;
    let width = 0.5;
    let bins = (2.0 * Z_MAX / width) as usize;
    let (mut plain, mut flagged) = (vec![0.0; bins], vec![0.0; bins]);
    let mut total = 0usize;
    for o in r.outcomes.iter().filter(|o| o.backend == Backend::Newton) {
        for z in o.z() {
            let k = (((z.clamp(-Z_MAX, Z_MAX) + Z_MAX) / width) as usize).min(bins - 1);
            if o.weakly_informed {
                flagged[k] += 1.0;
            } else {
                plain[k] += 1.0;
            }
            total += 1;
        }
    }
    let dens = |v: &mut Vec<f64>| v.iter_mut().for_each(|c| *c /= total.max(1) as f64 * width);
    dens(&mut plain);
    dens(&mut flagged);
    let (y0, y1) = (1e-4, 1.0);
    let mut c = ChartBuilder::on(area)
        .caption(
            "(c) z = (truth − estimate) / σ (newton)",
            ("sans-serif", 20),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(55)
        .build_cartesian_2d(-Z_MAX..Z_MAX, (y0..y1).log_scale())
        .map_err(ms)?;
    c.configure_mesh()
        .x_desc("z per component (beyond ±6 in the outer bins)")
        .y_desc("density")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(ms)?;
    super::layout::data_in(c.plotting_area());
    let lo = |k: usize| -Z_MAX + width * k as f64;
    c.draw_series(
        plain
            .iter()
            .enumerate()
            .filter(|(_, v)| **v > 0.0)
            .map(|(k, v)| {
                Rectangle::new(
                    [(lo(k) + 0.03, y0), (lo(k) + width - 0.03, v.max(y0))],
                    RGBColor(170, 170, 170).filled(),
                )
            }),
    )
    .map_err(ms)?
    .label("not flagged")
    .legend(|(x, y)| {
        Rectangle::new(
            [(x, y - 5), (x + 18, y + 5)],
            RGBColor(170, 170, 170).filled(),
        )
    });
    let red = RGBColor(214, 39, 40);
    c.draw_series(LineSeries::new(
        (0..bins).flat_map(|k| {
            let v = flagged[k].max(y0);
            [(lo(k), v), (lo(k) + width, v)]
        }),
        red.stroke_width(2),
    ))
    .map_err(ms)?
    .label("flagged weakly informed")
    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], red.stroke_width(2)));
    c.draw_series(LineSeries::new(
        (0..=240).map(|i| {
            let z = -Z_MAX + 2.0 * Z_MAX * i as f64 / 240.0;
            let p = (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt();
            (z, p.max(y0))
        }),
        BLACK.stroke_width(2),
    ))
    .map_err(ms)?
    .label("N(0, 1)")
    .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK.stroke_width(2)));
    super::layout::annotations();
    legend(&mut c, SeriesLabelPosition::UpperRight)
}
