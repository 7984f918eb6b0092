//! One grasp trial of each strategy on a disc, printed: `cargo run --release --example grasp_one -- RADIUS_M MASS_KG MU OFFSET_M`.
use softrod::grasp::gripper::GripperSpec;
use softrod::grasp::object::{GraspObject, Shape};
use softrod::grasp::trial::{run_trial, GraspSettings, Placement, Strategy};

fn main() -> Result<(), softrod::Error> {
    let a: Vec<f64> = std::env::args()
        .skip(1)
        .filter_map(|s| s.parse().ok())
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
    let object = match std::env::var("GRASP_OBJECT")
        .ok()
        .and_then(|v| v.parse::<usize>().ok())
    {
        Some(i) => softrod::grasp::table::table_objects()[i].clone(),
        None => object,
    };
    let placement = Placement {
        offset_m: get(3, 0.0),
        angle_rad: 0.0,
    };
    for strategy in [Strategy::OpenLoop, Strategy::Adaptive] {
        let t = std::time::Instant::now();
        let out = run_trial(
            &GripperSpec::default(),
            &object,
            placement,
            strategy,
            &GraspSettings::default(),
            1,
        )?;
        println!(
            "{:10} success {} failure {:?} holding {:.3} kg, est err {:?}, {} frames, {:.2} s",
            strategy.name(),
            out.success,
            out.failure,
            out.holding_mass_kg,
            out.contact_estimate_error_m,
            out.frames.len(),
            t.elapsed().as_secs_f64()
        );
        for f in out.frames.iter().step_by(4).chain(out.frames.last()) {
            println!(
                "  t {:.2} {:?} P {:?} / {:?} pose {:?} contacts {:?}",
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
                    (p[0] * 1e3).round(),
                    (p[1] * 1e3).round(),
                    (p[2] * 1e3).round()
                ]),
                f.contacts
                    .iter()
                    .map(|c| (
                        c.side,
                        (c.point_m[1] * 1e3).round(),
                        (c.force_n * 1e3).round() / 1e3
                    ))
                    .collect::<Vec<_>>()
            );
        }
    }
    Ok(())
}
