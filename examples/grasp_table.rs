//! Table I in simulation: the nine objects, five seeded tries each, both
//! strategies; prints every trial with the cause of each failure, the
//! table and the holding masses, and writes the rows as JSON to the path
//! given (default `grasp_table.json`).
//!
//! `cargo run --release --features cli --example grasp_table [-- OUT.json]`
//!
//! A subset (quick reruns): `GRASP_OBJECTS=0,6` (indices into
//! [`softrod::report::grasp::table::table_objects`]), `GRASP_STRATEGIES=adaptive`
//! (or `open-loop`), `GRASP_TRIES=5`.
use softrod::grasp::gripper::GripperSpec;
use softrod::grasp::trial::{GraspSettings, Strategy};
use softrod::report::grasp::table::{TableRow, run_row, table_objects};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "grasp_table.json".into());
    let all = table_objects();
    let objects: Vec<_> = match std::env::var("GRASP_OBJECTS") {
        Ok(v) => v
            .split(',')
            .filter_map(|s| s.trim().parse::<usize>().ok())
            .filter_map(|i| all.get(i).cloned())
            .collect(),
        Err(_) => all.clone(),
    };
    let strategies: Vec<Strategy> = match std::env::var("GRASP_STRATEGIES") {
        Ok(v) => [Strategy::Adaptive, Strategy::OpenLoop]
            .into_iter()
            .filter(|s| v.split(',').any(|x| x.trim() == s.name()))
            .collect(),
        Err(_) => vec![Strategy::Adaptive, Strategy::OpenLoop],
    };
    let tries = std::env::var("GRASP_TRIES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(5);
    let start = std::time::Instant::now();
    let mut rows = Vec::new();
    for o in &objects {
        let i = all.iter().position(|a| a == o).unwrap_or(0);
        for &s in &strategies {
            let mut t = std::time::Instant::now();
            rows.push(run_row(
                &GripperSpec::default(),
                o,
                i,
                s,
                tries,
                &GraspSettings::default(),
                1,
                |out| {
                    println!(
                        "{:16} {:10} offset {:+.4} m turn {:+.3} rad: {} {:?} ({:.1} s)",
                        out.object,
                        out.strategy.name(),
                        out.placement.offset_m,
                        out.placement.angle_rad,
                        if out.success { "held" } else { "FAILED" },
                        out.failure,
                        t.elapsed().as_secs_f64()
                    );
                    t = std::time::Instant::now();
                },
            )?);
        }
    }
    println!(
        "{:16} {:>9} {:>9}  holding mass (adaptive, kg)",
        "object", "adaptive", "open-loop"
    );
    for o in &objects {
        let get = |s| {
            rows.iter()
                .find(|r: &&TableRow| r.object == o.name && r.strategy == s)
        };
        let (a, b) = (get(Strategy::Adaptive), get(Strategy::OpenLoop));
        let cell = |r: Option<&TableRow>| {
            r.map_or("-".to_string(), |r| format!("{}/{}", r.successes, r.tries))
        };
        let max = a.map_or(0.0, |a| {
            a.holding_mass_kg.iter().copied().fold(0.0, f64::max)
        });
        println!("{:16} {:>9} {:>9}  {:.3}", o.name, cell(a), cell(b), max);
    }
    for s in &strategies {
        let (ok, n) = rows
            .iter()
            .filter(|r| r.strategy == *s)
            .fold((0, 0), |(a, b), r| (a + r.successes, b + r.tries));
        println!("{} total {ok}/{n}", s.name());
    }
    println!("{:.1} s", start.elapsed().as_secs_f64());
    std::fs::write(&out, serde_json::to_string_pretty(&rows)?)?;
    Ok(())
}
