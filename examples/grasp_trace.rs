//! Traces single grasp trials: every 20th frame of the closing, its last
//! frames and every frame after the lift: contacts (finger, height, normal,
//! force), the friction check's weight factor, the fingers' contact poses
//! and the object's pose.
//!
//! - Table I's objects: `GRASP_OBJECT=0 GRASP_TRY=0,1 GRASP_STRATEGY=adaptive
//!   cargo run --release --features cli --example grasp_trace` (the table's placements).
//! - A disc: `GRASP_DISC=RADIUS_M,MASS_KG,MU,OFFSET_M` (unturned, seed 1).
//!
//! `GRASP_STRATEGY`: `adaptive` (default), `open-loop` or `both`.
use softrod::grasp::friction::{FrictionContact, hold_check};
use softrod::grasp::gripper::GripperSpec;
use softrod::grasp::object::{GraspObject, Pose, Shape};
use softrod::grasp::trial::{GraspSettings, Placement, Strategy, run_trial};
use softrod::report::grasp::table::{placement, table_objects};

fn main() -> Result<(), softrod::Error> {
    let env = |k: &str, d: &str| std::env::var(k).unwrap_or_else(|_| d.to_string());
    let strategies = match env("GRASP_STRATEGY", "adaptive").as_str() {
        "open-loop" | "open_loop" => vec![Strategy::OpenLoop],
        "both" => vec![Strategy::Adaptive, Strategy::OpenLoop],
        _ => vec![Strategy::Adaptive],
    };
    // (label, object, placement, seed) of each trial
    let mut runs: Vec<(String, GraspObject, Placement, u64)> = Vec::new();
    if let Ok(disc) = std::env::var("GRASP_DISC") {
        let a: Vec<f64> = disc
            .split(',')
            .filter_map(|s| s.trim().parse().ok())
            .collect();
        let get = |i: usize, d: f64| a.get(i).copied().unwrap_or(d);
        let object = GraspObject {
            name: "disc".into(),
            shape: Shape::Circle {
                radius_m: get(0, 0.03),
            },
            mass_kg: get(1, 0.1),
            mu: get(2, 0.5),
        };
        let p = Placement {
            offset_m: get(3, 0.0),
            angle_rad: 0.0,
        };
        runs.push(("disc".into(), object, p, 1));
    } else {
        let i: usize = env("GRASP_OBJECT", "0").parse().unwrap_or(0);
        let o = &table_objects()[i];
        for k in env("GRASP_TRY", "0,1,2,3,4")
            .split(',')
            .filter_map(|s| s.trim().parse::<usize>().ok())
        {
            let seed = 1 ^ ((i * 100 + k) as u64);
            runs.push((
                format!("{} try {k}", o.name),
                o.clone(),
                placement(1, i, k),
                seed,
            ));
        }
    }
    let g = GripperSpec::default();
    let s = GraspSettings::default();
    for strategy in strategies {
        for (label, o, p, seed) in &runs {
            let (o, p) = (o, *p);
            let t = std::time::Instant::now();
            let out = run_trial(&g, o, p, strategy, &s, *seed)?;
            println!(
                "== {label} {} offset {:+.4} turn {:+.3}: success {} {:?} slip {:.4} holding {:.3} est err {:?} ({:.1} s)",
                strategy.name(),
                p.offset_m,
                p.angle_rad,
                out.success,
                out.failure,
                out.slip_m,
                out.holding_mass_kg,
                out.contact_estimate_error_m,
                t.elapsed().as_secs_f64()
            );
            println!("   start pose {:?} final {:?}", out.pose, out.final_pose);
            let n = out.frames.len();
            for (j, f) in out.frames.iter().enumerate() {
                if j + 8 < n && j % 20 != 0 {
                    continue;
                }
                // the friction check as the trial runs it: cones about the
                // object's outline at its pose in this frame
                let pose = Pose {
                    position_m: f.object_position_m,
                    angle_rad: f.object_angle_rad,
                };
                let cs: Vec<FrictionContact> = f
                    .contacts
                    .iter()
                    .map(|c| {
                        let n: [f64; 2] = o.surface_normal(&pose, c.point_m.into()).into();
                        FrictionContact {
                            point_m: c.point_m,
                            normal: [-n[0], -n[1]],
                            max_normal_force_n: c.force_n,
                        }
                    })
                    .collect();
                let h = hold_check(
                    &cs,
                    o.mass_kg,
                    f.object_position_m.into(),
                    o.mu,
                    g.gravity_m_per_s2.into(),
                )?;
                println!(
                    "  t {:6.2} {:?} P {:?}/{:?} xc {:?}/{:?} obj [{:.2},{:.2}] mm {:.3} rad wf {:.3}",
                    f.time_s,
                    f.phases,
                    f.pressures_pa[0]
                        .iter()
                        .map(|p| (p / 1e3).round())
                        .collect::<Vec<_>>(),
                    f.pressures_pa[1]
                        .iter()
                        .map(|p| (p / 1e3).round())
                        .collect::<Vec<_>>(),
                    f.contact_pose[0].map(|p| [
                        (p[0] * 1e4).round() / 10.0,
                        (p[1] * 1e4).round() / 10.0,
                        (p[2] * 1e3).round() / 1e3
                    ]),
                    f.contact_pose[1].map(|p| [
                        (p[0] * 1e4).round() / 10.0,
                        (p[1] * 1e4).round() / 10.0,
                        (p[2] * 1e3).round() / 1e3
                    ]),
                    f.object_position_m[0] * 1e3,
                    f.object_position_m[1] * 1e3,
                    f.object_angle_rad,
                    h.weight_factor
                );
                for (c, (lam, tau)) in f
                    .contacts
                    .iter()
                    .zip(h.normal_forces_n.iter().zip(&h.friction_forces_n))
                {
                    println!(
                        "      {:?} p [{:.2},{:.2}] mm n [{:.3},{:.3}] N {:.3} -> lam {:.3} tau {:.3}",
                        c.side,
                        c.point_m[0] * 1e3,
                        c.point_m[1] * 1e3,
                        c.normal[0],
                        c.normal[1],
                        c.force_n,
                        lam,
                        tau
                    );
                }
                // fingertip positions and angles from the centrelines
                let tip = |cl: &Vec<[f64; 2]>| {
                    let a = cl[cl.len() - 2];
                    let b = cl[cl.len() - 1];
                    format!(
                        "tip [{:.1},{:.1}] mm ang {:.3}",
                        b[0] * 1e3,
                        b[1] * 1e3,
                        (b[0] - a[0]).atan2(-(b[1] - a[1]))
                    )
                };
                println!(
                    "      L {}  R {}",
                    tip(&f.centreline_m[0]),
                    tip(&f.centreline_m[1])
                );
            }
        }
    }
    Ok(())
}
