//! The full 3-D ANCF element (`Ancf3d`) against exudyn's geometrically exact
//! beam (`ObjectBeamGeometricallyExact`, Simo–Reissner) and, where it
//! converges, its ANCF beam (`ObjectANCFBeam`): 3-D cantilevers with
//! torsion and combined loads, small and large (`reference/exudyn_beam3d_*.json`,
//! written by `validation/exudyn_beam3d.py`).
//!
//! What is compared: the tip position and the tip section frame (its rotation
//! vector from the straight reference) of a converged `Ancf3d` rod (32
//! elements; its own discretization error is below 1e-7 L, tests/ancf3d.rs)
//! with exudyn's Richardson estimate from its finest meshes (8, 16, 32
//! elements; exudyn's Newton fails from 64 on). Why the
//! bound `1e-4 L` (and `1e-4 rad`): the two beam theories differ by the shear
//! deformation Simo–Reissner has and a Kirchhoff rod has not, `|F| L / GA`
//! in linear theory (at most 4e-5 L on these slender cases, written in each
//! reference); exudyn's own discretization error after extrapolation is
//! checked to be ten times below the bound.
//!
//! Loads: dead tip forces; tip moments only where exudyn's dead torque and
//! the element's moment potential `M · φ` agree (a twist about a fixed
//! axis, and the small case); a couple of dead forces at two points of the
//! tip section for large torsion with bending (a potential in both codes).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use std::sync::Arc;

use common::reference;
use serde_json::Value;
use softrod::assembly::Section;
use softrod::element::{Ancf3d, Ancf3dStiffness, NodeKinematics};
use softrod::loads::force_field::{ForceField, StiffnessSink};
use softrod::loads::{Loads, NodeMoment, PointForce};
use softrod::statics::StaticSolver;
use softrod::structure::{RodSpec, Structure, StructureLoads, StructureSpec};

const CASES: [&str; 4] = [
    "combined_small",
    "oblique_large",
    "twist_large",
    "couple_large",
];
const ELEMENTS: usize = 32;

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap()
}

fn vec3(v: &Value) -> [f64; 3] {
    let v: Vec<f64> = serde_json::from_value(v.clone()).unwrap();
    [v[0], v[1], v[2]]
}

fn mat3(v: &Value) -> [[f64; 3]; 3] {
    let rows: Vec<Vec<f64>> = serde_json::from_value(v.clone()).unwrap();
    [0, 1, 2].map(|i| [rows[i][0], rows[i][1], rows[i][2]])
}

/// Dead forces at points `(Y, Z)` of the tip section: the force `F` at
/// `r + Y r_Y + Z r_Z` does the work `F · (r + Y r_Y + Z r_Z)` (a potential,
/// linear in `q`), scaled by `scale`.
#[derive(Debug, Clone)]
struct SectionForces {
    start: usize,
    forces: Vec<(f64, f64, [f64; 3])>,
    scale: f64,
}

impl ForceField for SectionForces {
    fn check(&self, n_q: usize) -> softrod::Result<()> {
        assert!(self.start + 12 <= n_q, "the tip node is in the model");
        Ok(())
    }
    fn energy(&self, q: &[f64]) -> f64 {
        let mut g = vec![0.0; q.len()];
        self.add_force(q, &mut g);
        -g.iter().zip(q).map(|(a, b)| a * b).sum::<f64>()
    }
    fn add_force(&self, _q: &[f64], force: &mut [f64]) {
        for (y, z, fv) in &self.forces {
            for i in 0..3 {
                let fi = self.scale * fv[i];
                force[self.start + i] += fi;
                force[self.start + 6 + i] += y * fi;
                force[self.start + 9 + i] += z * fi;
            }
        }
    }
    fn add_stiffness(&self, _q: &[f64], _sink: &mut dyn StiffnessSink) {}
}

/// The reference's rod with `n` elements: tip position and tip rotation vector.
fn solve(r: &Value, n: usize) -> ([f64; 3], Vec<f64>) {
    let p = &r["params"];
    let l = f(&p["length_m"]);
    let mut stiffness =
        Ancf3dStiffness::isotropic(f(&p["ea_n"]), f(&p["ei_y_nm2"]), f(&p["gj_nm2"]));
    stiffness.ei_z_nm2 = f(&p["ei_z_nm2"]);
    let rod = RodSpec::clamped(
        vec![Section::uniform(l, stiffness.ea_n, stiffness.ei_y_nm2, n)],
        nalgebra::Vector3::repeat(0.0),
        nalgebra::Vector3::new(1.0, 0.0, 0.0),
    );
    let mut spec = StructureSpec::new(vec![rod], vec![], vec![]);
    spec.gravity_m_per_s2 = vec![0.0; 3];
    let base = Structure::new(spec, |_, le, ax, be| {
        Ancf3d::with_stiffness(le, stiffness, ax.max(be))
    })
    .unwrap();
    let tip = base.node_coordinates(0, n).unwrap();
    let mut loads = Loads::default();
    let mut field = SectionForces {
        start: tip.start,
        forces: Vec::new(),
        scale: 1.0,
    };
    for ld in p["loads"].as_array().unwrap() {
        match ld["type"].as_str().unwrap() {
            "tip_force" => loads.point_forces.push(PointForce {
                s_m: l,
                force_n: vec3(&ld["force_n"]).to_vec(),
            }),
            "tip_moment" => loads.node_moments.push(NodeMoment {
                node: n,
                moment_nm: vec3(&ld["moment_nm"]).to_vec(),
            }),
            "section_force" => {
                field
                    .forces
                    .push((f(&ld["y_m"]), f(&ld["z_m"]), vec3(&ld["force_n"])))
            }
            other => panic!("unexpected load {other}"),
        }
    }
    // load steps by hand: the section forces are a field the solver does not scale
    let steps = f(&p["discretization"]["load_steps"]) as usize;
    let mut q: Vec<f64> = Vec::new();
    for k in 1..=steps {
        let s = k as f64 / steps as f64;
        let mut model = base.clone();
        field.scale = s;
        model.add_force_field(Arc::new(field.clone())).unwrap();
        let sl = StructureLoads {
            rods: vec![loads.scaled(s)],
            ..Default::default()
        };
        let q0 = (!q.is_empty()).then_some(q.as_slice());
        let eq = StaticSolver::default().solve(&model, &sl, q0).unwrap();
        assert!(
            eq.report.status.is_converged(),
            "step {k}/{steps}: {}",
            eq.report
        );
        q = eq.q.data.into();
    }
    let node = &q[tip];
    let reference = Ancf3d::straight_node(&[0.0; 3], &[1.0, 0.0, 0.0]);
    (
        [node[0], node[1], node[2]],
        Ancf3d::node_rotation(reference.as_slice(), node)
            .data
            .into(),
    )
}

/// The rotation vector of a rotation matrix (below π).
fn rotation_vector(m: &[[f64; 3]; 3]) -> [f64; 3] {
    let c = ((m[0][0] + m[1][1] + m[2][2] - 1.0) / 2.0).clamp(-1.0, 1.0);
    let th = c.acos();
    let w = [m[2][1] - m[1][2], m[0][2] - m[2][0], m[1][0] - m[0][1]];
    let k = if th < 1e-12 {
        0.5
    } else {
        th / (2.0 * th.sin())
    };
    w.map(|x| k * x)
}

/// exudyn's Richardson estimate (second order) of the tip position (from
/// the reference) and of the tip rotation vector (from the two finest
/// converged runs), and the error estimate of the extrapolation (the distance
/// of the extrapolations one mesh apart); `None` without three meshes.
fn extrapolated(model: &Value) -> Option<([f64; 3], [f64; 3], f64)> {
    let p = vec3(model.get("tip_position_extrapolated_m")?);
    let e = model.get("extrapolation_error_estimate_m")?.as_f64()?;
    let runs: Vec<&Value> = model["runs"]
        .as_array()?
        .iter()
        .filter(|r| r["converged"].as_bool() == Some(true))
        .collect();
    let [.., a, b] = runs.as_slice() else {
        return None;
    };
    assert_eq!(b["elements"].as_u64()?, 2 * a["elements"].as_u64()?);
    let (ra, rb) = (
        rotation_vector(&mat3(&a["tip_frame"])),
        rotation_vector(&mat3(&b["tip_frame"])),
    );
    let r = [0, 1, 2].map(|i| rb[i] + (rb[i] - ra[i]) / 3.0);
    Some((p, r, e))
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).powi(2))
        .sum::<f64>()
        .sqrt()
}

#[test]
fn ancf3d_agrees_with_exudyns_geometrically_exact_beam() {
    for case in CASES {
        let r = reference(&format!("exudyn_beam3d_{case}"));
        assert_eq!(r["versions"]["exudyn"], "1.13.6");
        let l = f(&r["params"]["length_m"]);
        let (p_ex, phi_ex, disc) = extrapolated(&r["values"]["geometrically_exact"]).unwrap();
        // the reference is converged well inside the bound, and the theories' gap is small
        assert!(
            disc < 1e-5 * l,
            "{case}: exudyn extrapolation error {disc:.2e}"
        );
        let gap = f(&r["values"]["shear_gap_estimate_m"]);
        assert!(gap < 0.5e-4 * l, "{case}: shear gap {gap:.2e}");
        let (p, phi) = solve(&r, ELEMENTS);
        let (dp, dphi) = (dist(&p, &p_ex), dist(&phi, &phi_ex));
        println!(
            "{case:<16} |Δ tip| = {:.2e} L  |Δ rotation| = {dphi:.2e} rad  (tip moved {:.3} L, turned {:.3} rad; \
             exudyn disc. {:.1e} L, shear gap {:.1e} L)",
            dp / l,
            dist(&p, &[l, 0.0, 0.0]) / l,
            dist(&phi, &[0.0; 3]),
            disc / l,
            gap / l
        );
        assert!(dp < 1e-4 * l, "{case}: tip {p:?} vs exudyn {p_ex:?}");
        assert!(dphi < 1e-4, "{case}: rotation {phi:?} vs exudyn {phi_ex:?}");
        // the case is what it says: large cases move far, small ones do not
        let moved = dist(&p, &[l, 0.0, 0.0]) / l;
        if case.ends_with("_large") {
            assert!(
                moved > 0.2 || dist(&phi, &[0.0; 3]) > 1.0,
                "{case}: {moved}"
            );
        } else {
            assert!(moved < 1e-2, "{case}: {moved}");
        }
    }
}

#[test]
fn ancf3d_agrees_with_exudyns_ancf_beam_where_it_converges() {
    let mut compared = 0;
    for case in CASES {
        let r = reference(&format!("exudyn_beam3d_{case}"));
        let l = f(&r["params"]["length_m"]);
        let Some((p_ex, phi_ex, disc)) = extrapolated(&r["values"]["ancf_beam"]) else {
            println!("{case:<16} ObjectANCFBeam: not converged on three meshes");
            continue;
        };
        if disc > 1e-5 * l {
            println!(
                "{case:<16} ObjectANCFBeam: discretization {:.1e} L, not converged",
                disc / l
            );
            continue;
        }
        let (p, phi) = solve(&r, ELEMENTS);
        let (dp, dphi) = (dist(&p, &p_ex), dist(&phi, &phi_ex));
        println!(
            "{case:<16} ObjectANCFBeam |Δ tip| = {:.2e} L  |Δ rotation| = {dphi:.2e} rad (its disc. {:.1e} L)",
            dp / l,
            disc / l
        );
        assert!(dp < 1e-4 * l, "{case}: tip {p:?} vs exudyn ANCF {p_ex:?}");
        assert!(
            dphi < 1e-4,
            "{case}: rotation {phi:?} vs exudyn ANCF {phi_ex:?}"
        );
        compared += 1;
    }
    assert!(compared >= 1, "the ANCF beam converged on no case");
}
