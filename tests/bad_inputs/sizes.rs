//! Bad inputs: pressures, mismatched and absurd sizes, static settings (rows of the table of `tests/bad_inputs.rs`).

use super::*;

#[allow(clippy::too_many_lines, unused_variables)]
pub(super) fn cases() -> Vec<Case> {
    use Kind::*;
    let nan = f64::NAN;
    let inf = f64::INFINITY;
    vec![
        // --- pressures ---
        case(
            "pressure above its bound",
            move || scene(|s| s.pressures_pa[0] = 1e6),
            Invalid,
            "pressures_pa[0]",
        ),
        case(
            "pressure below its bound",
            move || scene(|s| s.pressures_pa[1] = -1.0),
            Invalid,
            "pressures_pa[1]",
        ),
        case(
            "too few pressures",
            move || scene(|s| s.pressures_pa.pop().map(|_| ()).unwrap_or(())),
            Dim,
            "pressures_pa",
        ),
        case(
            "too many pressures (API)",
            move || {
                solve(
                    Loads {
                        pressures_pa: vec![0.0; 5],
                        ..Loads::default()
                    },
                    None,
                )
            },
            Dim,
            "pressures_pa",
        ),
        case(
            "inverted pressure bounds",
            move || scene(|s| s.robot.sections[0].chambers[0].pressure_min_pa = 2e5),
            Invalid,
            "robot.sections[0].chambers[0].pressure_max_pa",
        ),
        // --- mismatched dimensions ---
        case(
            "3-entry base position",
            move || scene(|s| s.base.position_m.push(0.0)),
            Dim,
            "base.position_m",
        ),
        case(
            "3-entry gravity",
            move || scene(|s| s.gravity_m_per_s2 = vec![0.0, -9.81, 0.0]),
            Dim,
            "gravity_m_per_s2",
        ),
        case(
            "3-entry tip force",
            move || {
                scene_load(Load::TipForce {
                    force_n: vec![0.0, 1.0, 0.0],
                })
            },
            Dim,
            "loads[0].force_n",
        ),
        case(
            "1-entry linear load",
            move || {
                scene_load(Load::Distributed(LineLoad::Linear {
                    w_start_n_per_m: vec![0.0, 0.0],
                    w_end_n_per_m: vec![1.0],
                }))
            },
            Dim,
            "loads[0].w_end_n_per_m",
        ),
        case(
            "3-entry extra-weight gravity",
            move || {
                scene_load(Load::SelfWeight {
                    mass_per_length_kg_per_m: 0.1,
                    gravity_m_per_s2: vec![0.0, -9.81, 0.0],
                })
            },
            Dim,
            "loads[0].gravity_m_per_s2",
        ),
        case(
            "2-entry chamber gain",
            move || scene(|s| s.robot.sections[1].chambers[0].gain_nm_per_pa.push(1e-6)),
            Dim,
            "robot.sections[1].chambers[0].gain_nm_per_pa",
        ),
        case(
            "q0 of the wrong length",
            move || solve(default_loads(), Some(vec![0.0; 80])),
            Dim,
            "q0",
        ),
        case(
            "distributed-load parameters of the wrong length",
            move || {
                solve(
                    Loads {
                        distributed_f: vec![0.0; 83],
                        ..default_loads()
                    },
                    None,
                )
            },
            Dim,
            "distributed_f",
        ),
        case(
            "2-entry moment (API)",
            move || {
                solve(
                    Loads {
                        node_moments: vec![NodeMoment {
                            node: 3,
                            moment_nm: vec![0.0, 1.0],
                        }],
                        ..default_loads()
                    },
                    None,
                )
            },
            Dim,
            "node_moments[0].moment_nm",
        ),
        case(
            "node moment at the clamped base",
            move || {
                scene_load(Load::NodeMoment {
                    node: 0,
                    moment_nm: 0.1.into(),
                })
            },
            Invalid,
            "loads[0].node",
        ),
        case(
            "node moment beyond the tip",
            move || {
                scene_load(Load::NodeMoment {
                    node: 99,
                    moment_nm: 0.1.into(),
                })
            },
            Index,
            "loads[0].node",
        ),
        case(
            "node moment beyond the tip (API)",
            move || {
                solve(
                    Loads {
                        node_moments: vec![NodeMoment {
                            node: 21,
                            moment_nm: vec![0.1],
                        }],
                        ..default_loads()
                    },
                    None,
                )
            },
            Index,
            "node_moments[0].node",
        ),
        case(
            "point force beyond the tip",
            move || {
                scene_load(Load::PointForce {
                    s_m: 0.25,
                    force_n: vec![0.0, 1.0],
                })
            },
            Invalid,
            "loads[0].s_m",
        ),
        // --- low-level API with wrong sizes ---
        case(
            "sparse solve with a short right-hand side",
            || {
                let p = std::sync::Arc::new(SymmetricPattern::from_elements(3, &[vec![0, 1, 2]])?);
                let mut k = SymmetricMatrix::zeros(p.clone());
                for i in 0..3 {
                    k.add(i, i, 1.0)?;
                }
                let f = AutoSolver::analyze(&p)?.factor(&k, FactorOptions::default())?;
                Ok(f.solve_in_place(&mut [1.0, 2.0])?)
            },
            Dim,
            "b",
        ),
        case(
            "banded entry outside the band",
            || BandedMatrix::zeros(5, 1, 1).try_add(0, 3, 1.0),
            Invalid,
            "j",
        ),
        case(
            "banded entry beyond the matrix",
            || BandedMatrix::zeros(5, 1, 1).try_add(5, 5, 1.0),
            Index,
            "i",
        ),
        case(
            "position_at with a short q",
            || {
                let r = Scene::two_section().robot()?;
                r.position_at(&[0.0; 8], 0.1).map(|_| ())
            },
            Dim,
            "q",
        ),
        case(
            "position_at off the robot",
            || {
                let r = Scene::two_section().robot()?;
                r.position_at(r.reference_configuration().as_slice(), 1.0)
                    .map(|_| ())
            },
            Invalid,
            "s_m",
        ),
        case(
            "residual_into with a short output",
            || {
                let r = Scene::two_section().robot()?;
                let q = r.reference_configuration();
                r.residual_into(
                    q.as_slice(),
                    &vec![0.0; r.n_q()],
                    &default_loads(),
                    &mut [0.0; 3],
                )
            },
            Dim,
            "residual",
        ),
        case(
            "residual with a moment beyond the tip",
            || {
                let r = Scene::two_section().robot()?;
                let q = r.reference_configuration();
                let l = Loads {
                    node_moments: vec![NodeMoment {
                        node: 50,
                        moment_nm: vec![1.0],
                    }],
                    ..default_loads()
                };
                r.residual(q.as_slice(), &vec![0.0; r.n_q()], &l)
                    .map(|_| ())
            },
            Index,
            "node_moments[0].node",
        ),
        case(
            "tangent with an empty moment",
            || {
                let r = Scene::two_section().robot()?;
                let q = r.reference_configuration();
                let l = Loads {
                    node_moments: vec![NodeMoment {
                        node: 5,
                        moment_nm: vec![],
                    }],
                    ..default_loads()
                };
                r.tangent_into(q.as_slice(), &l, &mut BandedMatrix::zeros(1, 0, 0))
            },
            Dim,
            "node_moments[0].moment_nm",
        ),
        case(
            "expand_step with a long step",
            || {
                let r = Scene::two_section().robot()?;
                r.expand_step(&vec![0.0; r.n_free() + 1]).map(|_| ())
            },
            Dim,
            "du",
        ),
        // --- absurd sizes, refused before allocating ---
        case(
            "10^9 elements",
            move || scene(|s| s.robot.sections[0].elements = 1_000_000_000),
            TooLarge,
            "robot.sections[0].elements",
        ),
        case(
            "usize::MAX elements",
            move || scene(|s| s.robot.sections[1].elements = usize::MAX),
            TooLarge,
            "robot.sections[1].elements",
        ),
        case(
            "elements too many only in sum",
            move || {
                scene(|s| {
                    s.robot.sections[0].elements = MAX_ELEMENTS / 2 + 1;
                    s.robot.sections[1].elements = MAX_ELEMENTS / 2 + 1
                })
            },
            TooLarge,
            "robot.sections[1].elements",
        ),
        case(
            "10^9 elements (JSON)",
            move || json(|v| v["robot"]["sections"][0]["elements"] = json!(1_000_000_000u64)),
            TooLarge,
            "robot.sections[0].elements",
        ),
        case(
            "10^6 axial Gauss points",
            move || scene(|s| s.robot.axial_gauss_points = 1_000_000),
            TooLarge,
            "robot.axial_gauss_points",
        ),
        case(
            "zero bending Gauss points",
            move || scene(|s| s.robot.bending_gauss_points = 0),
            Invalid,
            "robot.bending_gauss_points",
        ),
        case(
            "Gauss rule of usize::MAX points",
            || GaussRule::new(usize::MAX).map(|_| ()),
            TooLarge,
            "gauss_points",
        ),
        case(
            "element rule of 33 points",
            || PlanarCable::with_rules(0.1, 1.0, 1.0, 0.0, 33, 3).map(|_| ()),
            TooLarge,
            "axial_gauss_points",
        ),
        case(
            "banded matrix of usize::MAX rows",
            || BandedMatrix::try_zeros(usize::MAX, 7, 7).map(|_| ()),
            TooLarge,
            "n",
        ),
        case(
            "robot spec of 10^12 elements",
            || {
                RobotSpec::new(vec![Section::uniform(1.0, 1.0, 1.0, 1_000_000_000_000)])
                    .build_planar()
                    .map(|_| ())
            },
            TooLarge,
            "robot.sections[0].elements",
        ),
        // --- static settings out of range ---
        case(
            "zero iterations",
            move || settings(|t| t.max_iterations = 0),
            Invalid,
            "solver.static.max_iterations",
        ),
        case(
            "10^9 total iterations",
            move || settings(|t| t.max_total_iterations = 1_000_000_000),
            TooLarge,
            "solver.static.max_total_iterations",
        ),
        case(
            "total budget below the per-step budget",
            move || settings(|t| t.max_total_iterations = 10),
            Invalid,
            "solver.static.max_total_iterations",
        ),
        case(
            "zero residual tolerance",
            move || settings(|t| t.residual_tolerance = 0.0),
            Invalid,
            "solver.static.residual_tolerance",
        ),
        case(
            "residual tolerance of 2",
            move || settings(|t| t.residual_tolerance = 2.0),
            Invalid,
            "solver.static.residual_tolerance",
        ),
        case(
            "increment tolerance of 1",
            move || settings(|t| t.increment_tolerance = 1.0),
            Invalid,
            "solver.static.increment_tolerance",
        ),
        case(
            "negative max step rotation",
            move || settings(|t| t.max_step_rotation = -0.5),
            Invalid,
            "solver.static.max_step_rotation",
        ),
        case(
            "min load step of 1.5",
            move || settings(|t| t.min_load_step = 1.5),
            Invalid,
            "solver.static.min_load_step",
        ),
        case(
            "NaN increment tolerance (API)",
            || {
                StaticSolver::new(StaticSettings {
                    increment_tolerance: f64::NAN,
                    ..Default::default()
                })
                .map(|_| ())
            },
            Invalid,
            "increment_tolerance",
        ),
    ]
}
