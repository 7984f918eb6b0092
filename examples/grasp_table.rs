//! Table I in simulation: the nine objects, five seeded tries each, both
//! strategies; prints the table and the holding masses, writes the rows as
//! JSON to the path given (default `grasp_table.json`).
//!
//! `cargo run --release --example grasp_table [-- OUT.json]`
use softrod::grasp::gripper::GripperSpec;
use softrod::grasp::table::{run_table, table_objects};
use softrod::grasp::trial::{GraspSettings, Strategy};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let out = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "grasp_table.json".into());
    let start = std::time::Instant::now();
    let rows = run_table(
        &GripperSpec::default(),
        &table_objects(),
        &[Strategy::Adaptive, Strategy::OpenLoop],
        5,
        &GraspSettings::default(),
        1,
        |_| {},
    )?;
    println!(
        "{:16} {:>9} {:>9}  holding mass (adaptive, kg)  failures",
        "object", "adaptive", "open-loop"
    );
    for pair in rows.chunks(2) {
        let (a, o) = (&pair[0], &pair[1]);
        let max = a.holding_mass_kg.iter().copied().fold(0.0, f64::max);
        println!(
            "{:16} {:>7}/{} {:>7}/{}  {:.3}  {:?} | {:?}",
            a.object,
            a.successes,
            a.tries,
            o.successes,
            o.tries,
            max,
            a.failures.iter().flatten().collect::<Vec<_>>(),
            o.failures.iter().flatten().collect::<Vec<_>>()
        );
    }
    let total: usize = rows
        .iter()
        .filter(|r| r.strategy == Strategy::Adaptive)
        .map(|r| r.successes)
        .sum();
    println!(
        "adaptive total {total}/45; {:.1} s",
        start.elapsed().as_secs_f64()
    );
    std::fs::write(&out, serde_json::to_string_pretty(&rows)?)?;
    Ok(())
}
