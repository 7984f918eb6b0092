//! Cold static solves over cases × sizes: every exudyn reference case and
//! four hard loads (`tests/common/statics_cases.rs`) at 8, 32, 128, 512 and
//! 2000 elements.
//!
//! - `statics_scaling/<case>/<n>`: one cold solve (criterion), for the cost
//!   exponent over the sizes (`python3 benches/fit_exponent.py
//!   statics_scaling/<case> 8`);
//! - `cargo bench --bench statics_scaling -- --table`: instead of timing, the
//!   table of Newton iterations (total, load steps) per case and size, as
//!   JSON lines, for the README (`STATICS_SIZES=8,128` picks the sizes);
//! - `cargo bench --bench statics_scaling -- --one CASE N`: one solve's
//!   report and its node slopes' lengths.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic, missing_docs)]

#[path = "../tests/common/statics_cases.rs"]
mod cases;

use std::hint::black_box;

use criterion::{BenchmarkId, Criterion};
use softrod::statics::StaticSolver;

const SIZES: [usize; 5] = [8, 32, 128, 512, 2000];

fn table() {
    let solver = StaticSolver::default();
    let sizes: Vec<usize> = match std::env::var("STATICS_SIZES") {
        Ok(v) => v.split(',').map(|s| s.parse().unwrap()).collect(),
        Err(_) => SIZES.to_vec(),
    };
    for &n in &sizes {
        for (name, scene) in cases::all(n) {
            let robot = scene.robot().unwrap();
            let loads = scene.loads().unwrap();
            let t = std::time::Instant::now();
            let out = solver.solve(&robot, &loads, None);
            let dt = t.elapsed().as_secs_f64();
            let (status, report) = match &out {
                Ok(eq) => ("converged".to_string(), eq.report.clone()),
                Err(softrod::Error::NotConverged { report }) => {
                    (format!("{}", report.status), (**report).clone())
                }
                Err(e) => panic!("{name}/{n}: {e}"),
            };
            let tip = out.as_ref().map(|eq| {
                let nq = eq.q.len();
                (eq.q[nq - 4], eq.q[nq - 3])
            });
            println!(
                "{{\"case\": \"{name}\", \"elements\": {n}, \"iterations\": {}, \"load_steps\": {}, \"status\": \"{status}\", \"criterion\": \"{:?}\", \"time_s\": {dt:.4}, \"tip\": \"{tip:?}\"}}",
                report.iterations, report.load_steps, report.status
            );
        }
    }
}

fn scaling(c: &mut Criterion) {
    let solver = StaticSolver::default();
    let mut group = c.benchmark_group("statics_scaling");
    // case by case, all sizes of a case in a row: on a shared machine the
    // load drifts over the run, and a fit is over one case's sizes
    let names: Vec<String> = cases::all(8).into_iter().map(|(name, _)| name).collect();
    for name in &names {
        for &n in &SIZES {
            let Some((name, scene)) = cases::all(n).into_iter().find(|(c, _)| c == name) else {
                continue;
            };
            let robot = scene.robot().unwrap();
            let loads = scene.loads().unwrap();
            if solver.solve(&robot, &loads, None).is_err() {
                eprintln!("statics_scaling/{name}/{n}: not converged, not timed");
                continue;
            }
            group.bench_with_input(BenchmarkId::new(name, n), &n, |b, _| {
                b.iter(|| solver.solve(&robot, black_box(&loads), None).unwrap())
            });
        }
    }
    group.finish();
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if let Some(i) = args.iter().position(|a| a == "--one") {
        let n: usize = args[i + 2].parse().unwrap();
        let (_, scene) = cases::all(n)
            .into_iter()
            .find(|(c, _)| *c == args[i + 1])
            .unwrap();
        let out =
            StaticSolver::default().solve(&scene.robot().unwrap(), &scene.loads().unwrap(), None);
        if let Ok(eq) = &out {
            let m: Vec<String> =
                eq.q.as_slice()
                    .chunks(4)
                    .enumerate()
                    .filter(|(i, _)| i % (n / 8).max(1) == 0 || *i == n)
                    .map(|(i, c)| format!("{i}:{:.4}", (c[2] * c[2] + c[3] * c[3]).sqrt()))
                    .collect();
            println!("|r'| {}", m.join(" "));
        }
        println!("{:?}", out.map(|e| e.report));
        return;
    }
    if std::env::args().any(|a| a == "--table") {
        table();
        return;
    }
    // 16 cases × 5 sizes, up to a second a solve at 2000 elements: short
    // defaults (the command line overrides them)
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(std::time::Duration::from_millis(500))
        .measurement_time(std::time::Duration::from_secs(2))
        .configure_from_args();
    scaling(&mut c);
    c.final_summary();
}
