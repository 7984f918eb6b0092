//! Where the trajectories of `track_fig6` can lie: the model's IK pressures
//! on a circle about candidate centres (all chambers must stay well inside
//! their bounds, the plant needing more pressure than the model).
//! Run: `cargo run --release --features cli --example track_workspace`.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]
use softrod::control::{IkSettings, InverseKinematics};
use softrod::scene::Scene;
fn main() -> softrod::Result<()> {
    let scene = Scene::two_section();
    let robot = scene.robot()?;
    let n = robot.n_q();
    let mut ik = InverseKinematics::new(robot, scene.loads()?, IkSettings::default())?;
    for p in [
        [40e3, 0.0, 40e3, 0.0],
        [50e3, 0.0, 30e3, 0.0],
        [60e3, 0.0, 20e3, 0.0],
        [45e3, 0.0, 45e3, 0.0],
        [30e3, 0.0, 50e3, 0.0],
    ] {
        let (_, c) = ik.forward(&p, &vec![0.0; n], None)?;
        let mut worst = 0.0f64;
        let mut ok = true;
        for k in 0..16 {
            let th = k as f64 * std::f64::consts::PI / 8.0;
            let x = [c[0] + 0.005 * th.cos(), c[1] + 0.005 * th.sin()];
            let s = ik.solve(&x, &vec![0.0; n])?;
            ok &= s.status.is_reached();
            worst = worst.max(s.pressures_pa.iter().fold(0.0f64, |m, v| m.max(*v)));
        }
        println!(
            "P {p:?}: centre ({:.4}, {:.4}) r 5 mm: all reached {ok}, max pressure {:.0} Pa",
            c[0], c[1], worst
        );
    }
    Ok(())
}
