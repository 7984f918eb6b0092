//! Branch following on post-buckled cases (issue 33, point 1): a cold solve
//! follows the branch connected to the unloaded state along the load path,
//! the same branch at every mesh, within 60 Newton iterations (summed over
//! load steps, as the README's iteration table counts them), and says how
//! it chose the branch where a critical point was passed
//! ([`StaticWarning::Bifurcation`]).
//!
//! The cases: a column clamped pointing straight up beyond its buckling load
//! (`q L³/EI = 12`, its own weight along it; the straight column buckles at
//! 7.837) with a 0.01 N lateral tip force, either way; the column tilted
//! 0.01 rad, no lateral force; a uniform heavy rod (weight by gravity) with a
//! tip mass, tilted the other way. The physical branch leans with the
//! lateral force (the tilt).
//!
//! Before the fix (main at b786a2b, the same cases): with the force toward
//! +x the tip leaned +x at 8 and 32 elements but −x at 16, 64 and 128
//! (the 32-element solve took 160 iterations and 30 load steps); reversed,
//! −x at 8, 16, 64, 128 but +x at 32, and 164–170 iterations at 16, 64 and
//! 128; the tip-mass case (a 1 N tip load and the 0.01 N force) leaned
//! against the force at 16 to 128 elements.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[path = "common/statics_cases.rs"]
mod cases;

use softrod::scene::Scene;
use softrod::statics::{BranchChoice, StaticSolver, StaticWarning};

/// The meshes every case is solved on.
const MESHES: [usize; 5] = [8, 16, 32, 64, 128];
/// The iteration budget of the issue.
const MAX_ITERATIONS: usize = 60;

/// The upright column with a lateral tip force (N) toward +x.
fn lateral(n: usize, lateral_n: f64) -> Scene {
    cases::lateral_column(n, lateral_n)
}

/// The column tilted by `tilt_rad` toward +x (no lateral force).
fn tilted(n: usize, tilt_rad: f64) -> Scene {
    let mut s = cases::hard("buckled_column", n);
    s.base.angle_rad = std::f64::consts::FRAC_PI_2 - tilt_rad;
    s
}

/// The column with a tip mass, tilted by `tilt_rad` toward +x.
fn tip_mass(n: usize, tilt_rad: f64) -> Scene {
    cases::tip_mass_column(n, tilt_rad)
}

/// Solves `scene` cold and checks the answer: converged, stable, within the
/// iteration budget, the tip leaning to the side `side` (±1) by more than
/// 0.1 m, and a bifurcation warning naming the load path as the chooser
/// whenever one was passed. Returns the tip x (m).
fn leans(label: &str, scene: &Scene, side: f64) -> f64 {
    let (robot, loads) = (scene.robot().unwrap(), scene.loads().unwrap());
    let eq = StaticSolver::default()
        .solve(&robot, &loads, None)
        .unwrap_or_else(|e| panic!("{label}: {e}"));
    let r = &eq.report;
    assert!(r.status.is_converged() && r.is_stable(), "{label}: {r}");
    let x = eq.q[eq.q.len() - 4];
    assert!(
        x * side > 0.1,
        "{label}: the tip leans to x = {x} m, the load to {side}: {r}"
    );
    assert!(r.iterations <= MAX_ITERATIONS, "{label}: {r}");
    for w in &r.warnings {
        match w {
            StaticWarning::Bifurcation { branch, .. } => {
                assert_eq!(*branch, BranchChoice::LoadPath, "{label}: {r}")
            }
            other => panic!("{label}: {other}"),
        }
    }
    x
}

/// The 64- and 128-element tips agree to this (m): the mesh's
/// discretization error of the tip (measured after the fix: 7e-10 m for the
/// lateral force, 4e-10 m for the tilt, 1e-9 m for the tip mass; the tilted
/// column's tip against the elastica at 128 elements: 1.4e-9 m,
/// `tests/statics_stability.rs`).
const MESH_AGREEMENT_M: f64 = 1e-8;

#[test]
fn the_column_leans_with_the_lateral_force_at_every_mesh() {
    for side in [1.0, -1.0] {
        let tips: Vec<f64> = MESHES
            .iter()
            .map(|&n| {
                leans(
                    &format!("{side} N/100, {n} el"),
                    &lateral(n, 0.01 * side),
                    side,
                )
            })
            .collect();
        assert!(
            (tips[3] - tips[4]).abs() < MESH_AGREEMENT_M,
            "64 / 128 elements: {tips:?}"
        );
        if side < 0.0 {
            // the mirror image of the +x answer
            let plus: Vec<f64> = MESHES
                .iter()
                .map(|&n| {
                    let s = lateral(n, 0.01);
                    let (robot, loads) = (s.robot().unwrap(), s.loads().unwrap());
                    let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
                    eq.q[eq.q.len() - 4]
                })
                .collect();
            for (a, b) in plus.iter().zip(&tips) {
                assert!((a + b).abs() < 1e-9, "+x {plus:?}, −x {tips:?}");
            }
        }
    }
}

#[test]
fn the_tilted_column_leans_with_its_tilt_at_every_mesh() {
    for side in [1.0, -1.0] {
        let tips: Vec<f64> = MESHES
            .iter()
            .map(|&n| {
                leans(
                    &format!("tilt {side}, {n} el"),
                    &tilted(n, 0.01 * side),
                    side,
                )
            })
            .collect();
        assert!(
            (tips[3] - tips[4]).abs() < MESH_AGREEMENT_M,
            "64 / 128 elements: {tips:?}"
        );
    }
}

#[test]
fn a_column_with_a_tip_mass_leans_with_its_tilt_at_every_mesh() {
    for side in [1.0, -1.0] {
        let tips: Vec<f64> = MESHES
            .iter()
            .map(|&n| {
                leans(
                    &format!("tip mass, tilt {side}, {n} el"),
                    &tip_mass(n, 0.01 * side),
                    side,
                )
            })
            .collect();
        assert!(
            (tips[3] - tips[4]).abs() < MESH_AGREEMENT_M,
            "64 / 128 elements: {tips:?}"
        );
    }
}

/// The perfect column (no lateral force, no tilt: symmetric but for the
/// round-off of `cos(π/2)`): either side is an answer, and the report says
/// the choice was ambiguous.
#[test]
fn a_symmetric_column_reports_an_ambiguous_branch() {
    for n in [8, 32] {
        let s = tilted(n, 0.0);
        let (robot, loads) = (s.robot().unwrap(), s.loads().unwrap());
        let eq = StaticSolver::default().solve(&robot, &loads, None).unwrap();
        let r = &eq.report;
        assert!(r.is_stable(), "{n}: {r}");
        assert!(eq.q[eq.q.len() - 4].abs() > 0.1, "{n}: {r}");
        assert!(
            r.warnings.iter().any(|w| matches!(
                w,
                StaticWarning::Bifurcation {
                    branch: BranchChoice::Symmetric,
                    ..
                }
            )),
            "{n}: {r}"
        );
        assert!(r.to_string().contains("ambiguous: symmetric load"), "{r}");
    }
}

/// The command line prints the bifurcation warning on standard error, as
/// it does the stability warning, and writes it into the report.
#[test]
fn the_cli_prints_the_branch_choice() {
    let dir = std::env::temp_dir().join(format!("softrod_branch_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("column.json");
    std::fs::write(&path, serde_json::to_string(&lateral(16, 0.01)).unwrap()).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args(["solve", path.to_str().unwrap()])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("softrod: warning: bifurcation passed between load factors")
            && stderr.contains("branch chosen by the load path"),
        "{stderr}"
    );
    assert!(stdout.contains("\"bifurcation\""), "{stdout}");
    std::fs::remove_dir_all(&dir).ok();
}
