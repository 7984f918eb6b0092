//! The mutation sweep: every number of every example scene, replaced by each
//! of −1, 0, 1e308, −1e−300 and 1e9, is either accepted — and then the scene
//! solves to a finite shape or fails with a typed error — or refused with a
//! message that names the field the user wrote, by its path in the file.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use serde_json::Value;
use softrod::scene::{Scene, SceneRobot};
use softrod::statics::StaticSolver;

const VALUES: [f64; 5] = [-1.0, 0.0, 1e308, -1e-300, 1e9];

/// Every number in `v` with its path as a user reads it (`robot.sections[0].length_m`).
fn numbers(v: &Value, path: String, out: &mut Vec<(String, Vec<PathStep>)>, steps: Vec<PathStep>) {
    match v {
        Value::Number(_) => out.push((path, steps)),
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                let mut s = steps.clone();
                s.push(PathStep::Index(i));
                numbers(x, format!("{path}[{i}]"), out, s);
            }
        }
        Value::Object(o) => {
            for (k, x) in o {
                let mut s = steps.clone();
                s.push(PathStep::Key(k.clone()));
                let p = if path.is_empty() {
                    k.clone()
                } else {
                    format!("{path}.{k}")
                };
                numbers(x, p, out, s);
            }
        }
        _ => {}
    }
}

#[derive(Clone, Debug)]
enum PathStep {
    Key(String),
    Index(usize),
}

fn set(v: &mut Value, steps: &[PathStep], x: f64) {
    let mut cur = v;
    for s in steps {
        cur = match s {
            PathStep::Key(k) => cur.get_mut(k.as_str()).unwrap(),
            PathStep::Index(i) => cur.get_mut(*i).unwrap(),
        };
    }
    *cur = serde_json::json!(x);
}

/// Does the error name the field: its path, or the array holding it?
fn names(message: &str, path: &str) -> bool {
    let parent = path
        .rsplit_once('[')
        .map(|(p, _)| p)
        .filter(|_| path.ends_with(']'));
    message.contains(&format!("`{path}`"))
        || message.contains(&format!("{path}:"))
        || message.contains(&format!("`{path}["))
        || parent.is_some_and(|p| {
            message.contains(&format!("`{p}`")) || message.contains(&format!("{p}:"))
        })
}

fn solve_finite(scene: &Scene) -> Result<bool, softrod::Error> {
    let solver = StaticSolver::new(scene.solver.statics.clone())?;
    let loads = scene.loads()?;
    let q = match scene.build()? {
        SceneRobot::Planar(r) => solver.solve(&r, &loads, None)?.q,
        SceneRobot::Spatial(r) => solver.solve(&r, &loads, None)?.q,
        SceneRobot::Full(r) => solver.solve(&r, &loads, None)?.q,
    };
    Ok(q.iter().all(|x| x.is_finite()))
}

#[test]
fn every_refused_mutation_names_its_field() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let mut wrong = Vec::new();
    let (mut refused, mut accepted, mut total) = (0, 0, 0);
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    files.sort();
    for file in files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "json"))
    {
        let base: Value = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        if base.get("robot").is_none() {
            continue; // a markers file, not a scene
        }
        let mut paths = Vec::new();
        numbers(&base, String::new(), &mut paths, Vec::new());
        for (path, steps) in &paths {
            for x in VALUES {
                total += 1;
                let mut v = base.clone();
                set(&mut v, steps, x);
                let name = file.file_name().unwrap().to_string_lossy();
                match Scene::from_json(&v.to_string()) {
                    Err(e) => {
                        refused += 1;
                        let m = e.to_string();
                        if !names(&m, path) {
                            wrong.push(format!("{name}: {path} = {x:e}: {m}"));
                        }
                    }
                    Ok(scene) => {
                        accepted += 1;
                        if scene.has_auto_elements() {
                            continue;
                        }
                        match solve_finite(&scene) {
                            Ok(true) | Err(_) => {}
                            Ok(false) => wrong.push(format!(
                                "{name}: {path} = {x:e}: accepted, non-finite shape"
                            )),
                        }
                    }
                }
            }
        }
    }
    println!(
        "{total} mutations: {refused} refused, {accepted} accepted, {} wrong",
        wrong.len()
    );
    assert!(total > 500, "only {total} mutations");
    assert!(
        wrong.is_empty(),
        "{} of {refused} refusals name the wrong field:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}
