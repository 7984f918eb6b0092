//! Random valid scenes (every field of the two-section scene drawn from its
//! valid range): shared by `tests/properties.rs` (JSON round trips) and
//! `tests/random_scenes.rs` (parse, solve and estimate invariants).
#![allow(dead_code)]

use proptest::prelude::*;
use softrod::loads::{LineLoad, Load};
use softrod::scene::{Marker, Scene};

/// Random valid scenes: every field of the two-section scene drawn from
/// its valid range, loads of every kind, markers by node and by arc.
pub fn scene_strategy() -> impl Strategy<Value = Scene> {
    let num = || -1e3..1e3f64;
    let pos = || 1e-3..1e3f64;
    (
        (
            1usize..=20,
            1usize..=20,
            pos(),
            pos(),
            pos(),
            pos(),
            0.0..2.0f64,
            num(),
        ),
        (
            num(),
            num(),
            // gravity, inside its documented range (100 g)
            -900.0..900.0f64,
            // base.angle_rad, inside its documented range |θ| ≤ 2π
            -6.0..6.0f64,
            num(),
            0.0..0.24f64,
            1usize..=20,
            1usize..=8,
        ),
        (
            prop::array::uniform4(0.0..1.0f64),
            prop::array::uniform4(-1e-5..1e-5f64),
            1e-12..0.1f64,
            1usize..=50,
            1e-3..3.0f64,
        ),
        (".{0,12}", any::<bool>(), 1usize..=32, 1usize..=32),
    )
        .prop_map(
            |(
                (n1, n2, l1, l2, ea, ei, mass, kappa),
                (a, b, c, angle, m, s_frac, node, mass_kg),
                (p, gains, tol, iters, rot),
                (name, tangent, ax, be),
            )| {
                let mut s = Scene::two_section();
                s.name = name;
                s.robot.axial_gauss_points = ax;
                s.robot.bending_gauss_points = be;
                let (l1, l2) = (l1 * 1e-3, l2 * 1e-3);
                for (sec, (n, l)) in s.robot.sections.iter_mut().zip([(n1, l1), (n2, l2)]) {
                    sec.elements = n;
                    sec.length_m = l;
                    sec.ea_n = ea;
                    sec.ei_nm2 = ei;
                    sec.mass_per_length_kg_per_m = mass;
                    sec.rest_curvature_per_m = kappa;
                }
                for (k, ch) in s
                    .robot
                    .sections
                    .iter_mut()
                    .flat_map(|s| s.chambers.iter_mut())
                    .enumerate()
                {
                    ch.gain_nm_per_pa = vec![gains[k]];
                }
                s.pressures_pa = p.iter().map(|f| f * 1e5).collect();
                s.base.position_m = vec![a, b];
                s.base.angle_rad = angle;
                s.gravity_m_per_s2 = vec![c, -c.abs()];
                let total = l1 + l2;
                let nodes = n1 + n2;
                s.loads = vec![
                    Load::TipForce {
                        force_n: vec![a, b],
                    },
                    Load::PointForce {
                        s_m: s_frac / 0.24 * total,
                        force_n: vec![c, m],
                    },
                    Load::TipMoment {
                        moment_nm: m.into(),
                    },
                    Load::NodeMoment {
                        node: 1 + node % nodes,
                        moment_nm: (-m).into(),
                    },
                    Load::SelfWeight {
                        mass_per_length_kg_per_m: mass,
                        gravity_m_per_s2: vec![a, c],
                    },
                    Load::TipMass {
                        mass_kg: mass_kg as f64 * 0.01,
                    },
                    Load::Distributed(LineLoad::Gaussian {
                        amplitude_n_per_m: vec![a, b],
                        // on the robot (a bump centred off it is refused)
                        center_m: s_frac / 0.24 * total,
                        width_m: tol,
                    }),
                    Load::Distributed(LineLoad::Linear {
                        w_start_n_per_m: vec![m, a],
                        w_end_n_per_m: vec![b, c],
                    }),
                ];
                s.markers = vec![
                    Marker {
                        node: Some(node % (nodes + 1)),
                        s_m: None,
                        tangent,
                    },
                    Marker {
                        node: None,
                        s_m: Some(total * (0.5 + 0.5 * s_frac / 0.24) * 0.999 + 1e-9),
                        tangent: !tangent,
                    },
                ];
                s.solver.statics.residual_tolerance = tol;
                s.solver.statics.max_iterations = iters;
                s.solver.statics.max_total_iterations = iters * 10;
                s.solver.statics.max_step_rotation = rot;
                s
            },
        )
}
