//! Obstacle avoidance by touch (the paper's Fig. 9) on the five-section
//! robot, the plant not the model (twice the mesh, EI +15 %, gain −10 %,
//! EA −5 %, σ = 0.05 mm, regulator lag 20 ms), 20 Hz, the paper's field
//! parameters: obstacle placements × goals (`softrod::report::touch::FIG9_*`), with
//! touch feedback and the baseline without it, 120 s each.
//!
//! Run: `cargo run --release --features cli --example avoid_fig9 [OUT.json] [--alpha=evidence|discrepancy]
//! [--disk=X,Y,R ...] [--goal=X,Y ...] [--duration=S]` (prints the table; writes
//! every row as JSON if a path is given; `--disk`/`--goal` replace the
//! table's placements/goals, m).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use softrod::estimate::AlphaRule;
use softrod::plant::PlantSettings;
use softrod::report::touch::{AvoidSummary, FIG9_GOALS, FIG9_PLACEMENTS, avoidance_table};
use softrod::touch::{AvoidSettings, AvoidStatus};

fn numbers(s: &str) -> Vec<f64> {
    s.split(',').map(|v| v.parse().expect("a number")).collect()
}

fn main() -> softrod::Result<()> {
    let mut out = None;
    let mut settings = AvoidSettings {
        duration_s: 120.0,
        ..AvoidSettings::default()
    };
    let (mut disks, mut goals) = (Vec::new(), Vec::new());
    for a in std::env::args().skip(1) {
        if let Some(v) = a.strip_prefix("--alpha=") {
            settings.alpha_rule = serde_json::from_str(&format!("\"{v}\"")).expect("a rule");
        } else if let Some(v) = a.strip_prefix("--disk=") {
            let n = numbers(v);
            disks.push((nalgebra::Vector2::new(n[0], n[1]), n[2]));
        } else if let Some(v) = a.strip_prefix("--goal=") {
            let n = numbers(v);
            goals.push(nalgebra::Vector2::new(n[0], n[1]));
        } else if let Some(v) = a.strip_prefix("--duration=") {
            settings.duration_s = v.parse().expect("seconds");
        } else {
            out = Some(a);
        }
    }
    if disks.is_empty() {
        disks = FIG9_PLACEMENTS.to_vec();
    }
    if goals.is_empty() {
        goals = FIG9_GOALS.to_vec();
    }
    let rule = match settings.alpha_rule {
        AlphaRule::Evidence => "evidence",
        AlphaRule::Discrepancy => "discrepancy",
    };
    println!("alpha rule: {rule}; {} s per run", settings.duration_s);
    println!(
        "disk (m)                 goal (m)         | touch: status     final(mm) f_before(N) f_after(N) touches wall(s) \
         | baseline: status final(mm) closest(mm) f_max(N) contact(s)  f_end(N) tip_end(m) at_bounds wall(s)"
    );
    let status = |s: &AvoidSummary| match s.status {
        AvoidStatus::Reached { time_s } => format!("reached {time_s:5.1} s"),
        AvoidStatus::NotReached { .. } => "not reached    ".into(),
        AvoidStatus::GoalUnreachable { .. } => "unreachable    ".into(),
    };
    let mut rows = Vec::new();
    for &disk in &disks {
        for &goal in &goals {
            let row = match avoidance_table(&[disk], &[goal], &PlantSettings::default(), &settings)
            {
                Ok(mut r) => r.remove(0),
                Err(e) => {
                    println!(
                        "{:?} {:?}: error {e}",
                        (disk.0.as_slice(), disk.1),
                        goal.as_slice()
                    );
                    continue;
                }
            };
            let (a, b) = (&row.touch, &row.baseline);
            let span = match (b.first_contact_s, b.last_contact_s) {
                (Some(f), Some(l)) => format!("{f:4.1}-{l:5.1}"),
                _ => "  none    ".into(),
            };
            println!(
                "({:.3}, {:.3}) r {:.3}  ({:.3}, {:.3}) | {} {:9.2} {:11.4} {:10.4} {:7} {:7.1} | {} {:9.2} {:11.2} {:8.4} {span} {:8.4} ({:.3}, {:.3}) {:9} {:7.1}{}",
                disk.0[0],
                disk.0[1],
                disk.1,
                goal[0],
                goal[1],
                status(a),
                a.final_error_m * 1e3,
                a.max_force_before_n,
                a.max_force_after_n,
                a.touches,
                a.wall_s,
                status(b),
                b.final_error_m * 1e3,
                b.closest_m * 1e3,
                b.max_force_before_n,
                b.final_force_n,
                b.final_tip_m[0],
                b.final_tip_m[1],
                b.pressures_at_bounds,
                b.wall_s,
                if row.baseline_met_obstacle() {
                    ""
                } else {
                    "  (baseline never meets the disk: not a placement)"
                }
            );
            rows.push(row);
        }
    }
    if let Some(path) = out {
        std::fs::write(&path, serde_json::to_string_pretty(&rows).unwrap()).unwrap();
        println!("wrote {path}");
    }
    Ok(())
}
