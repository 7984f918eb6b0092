//! The mutation sweep: every number of every example scene, replaced by each
//! of −1, 0, 1e308, −1e−300 and 1e9, is either accepted — and then the scene
//! solves to a finite shape or fails with a typed error — or refused with a
//! message that names the field the user wrote, by its path in the file.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use serde_json::Value;
use softrod::scene::{Scene, SceneRobot};
use softrod::statics::StaticSolver;

const VALUES: [f64; 5] = [-1.0, 0.0, 1e308, -1e-300, 1e9];

/// The values that are not numbers: the string "NaN", a string, an empty array.
fn odd_values() -> [Value; 3] {
    [
        Value::from("NaN"),
        Value::from("a string"),
        Value::Array(Vec::new()),
    ]
}

/// Every number in `v` with its path as a user reads it (`robot.sections[0].length_m`).
fn numbers(v: &Value, path: String, out: &mut Vec<(String, Vec<PathStep>)>, steps: Vec<PathStep>) {
    walk(v, path, out, steps, &|x| x.is_number());
}

/// Every value in `v` that `pick` selects, with its path and steps.
fn walk(
    v: &Value,
    path: String,
    out: &mut Vec<(String, Vec<PathStep>)>,
    steps: Vec<PathStep>,
    pick: &dyn Fn(&Value) -> bool,
) {
    if pick(v) {
        out.push((path.clone(), steps.clone()));
    }
    match v {
        Value::Array(a) => {
            for (i, x) in a.iter().enumerate() {
                let mut s = steps.clone();
                s.push(PathStep::Index(i));
                walk(x, format!("{path}[{i}]"), out, s, pick);
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
                walk(x, p, out, s, pick);
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

/// Every mutant of a file: each number (by its JSON path) set to each of
/// [`VALUES`], with the path and the value it got.
fn mutants(base: &Value) -> impl Iterator<Item = (String, f64, Value)> + '_ {
    let mut paths = Vec::new();
    numbers(base, String::new(), &mut paths, Vec::new());
    paths.into_iter().flat_map(move |(path, steps)| {
        VALUES.into_iter().map(move |x| {
            let mut v = base.clone();
            set(&mut v, &steps, serde_json::json!(x));
            (path.clone(), x, v)
        })
    })
}

/// The mutants beyond [`mutants`]: each number set to each of
/// [`odd_values`], each object key deleted and each duplicated (the same
/// key and value written twice). Yields the path the refusal must name, a
/// description and the mutated text (a duplicated key has no `Value`).
fn more_mutants(base: &Value) -> Vec<(String, String, String)> {
    let mut out = Vec::new();
    let mut paths = Vec::new();
    numbers(base, String::new(), &mut paths, Vec::new());
    for (path, steps) in &paths {
        for x in odd_values() {
            let mut v = base.clone();
            set(&mut v, steps, x.clone());
            out.push((path.clone(), format!("= {x}"), v.to_string()));
        }
    }
    // every key of every object (the values under a key: objects' members)
    let mut keys = Vec::new();
    walk(base, String::new(), &mut keys, Vec::new(), &|_| true);
    for (path, steps) in keys {
        let Some(PathStep::Key(k)) = steps.last() else {
            continue;
        };
        let parent = &steps[..steps.len() - 1];
        let mut v = base.clone();
        remove(&mut v, parent, k);
        out.push((path.clone(), "deleted".into(), v.to_string()));
        out.push((
            path.clone(),
            "duplicated".into(),
            duplicate(base, parent, k),
        ));
    }
    out
}

fn remove(v: &mut Value, parent: &[PathStep], key: &str) {
    let mut cur = v;
    for s in parent {
        cur = match s {
            PathStep::Key(k) => cur.get_mut(k.as_str()).unwrap(),
            PathStep::Index(i) => cur.get_mut(*i).unwrap(),
        };
    }
    cur.as_object_mut().unwrap().remove(key);
}

/// `base` as text with `key` of the object at `parent` written twice.
fn duplicate(base: &Value, parent: &[PathStep], key: &str) -> String {
    const MARK: &str = "\u{1}duplicate\u{1}";
    let mut v = base.clone();
    let mut cur = &mut v;
    for s in parent {
        cur = match s {
            PathStep::Key(k) => cur.get_mut(k.as_str()).unwrap(),
            PathStep::Index(i) => cur.get_mut(*i).unwrap(),
        };
    }
    let o = cur.as_object_mut().unwrap();
    let x = o[key].clone();
    o.insert(MARK.to_string(), x);
    let text = v.to_string();
    let marked = serde_json::to_string(MARK).unwrap();
    text.replace(&marked, &serde_json::to_string(key).unwrap())
}

fn set(v: &mut Value, steps: &[PathStep], x: Value) {
    let mut cur = v;
    for s in steps {
        cur = match s {
            PathStep::Key(k) => cur.get_mut(k.as_str()).unwrap(),
            PathStep::Index(i) => cur.get_mut(*i).unwrap(),
        };
    }
    *cur = x;
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
        for (path, x, v) in mutants(&base) {
            total += 1;
            let name = file.file_name().unwrap().to_string_lossy();
            match Scene::from_json(&v.to_string()) {
                Err(e) => {
                    refused += 1;
                    let m = e.to_string();
                    if !names(&m, &path) {
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

/// The markers files of the examples (`{"markers": [...]}`), swept like the
/// scenes against the robot of `examples/two_section.json` (the same
/// 0.24 m length; 3-D markers against `examples/ancf3d_cantilever.json`'s): every number × every value, each refusal naming
/// `observation.<path>` (the file's path under `observation.`).
#[test]
fn every_refused_marker_mutation_names_its_field() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let scene =
        Scene::from_json(&std::fs::read_to_string(format!("{dir}/two_section.json")).unwrap())
            .unwrap();
    let robot = scene.robot().unwrap();
    // 3-D markers go against the robot of the ancf3d example (also 0.24 m)
    let spatial = Scene::from_json(
        &std::fs::read_to_string(format!("{dir}/ancf3d_cantilever.json")).unwrap(),
    )
    .unwrap()
    .robot_as::<softrod::element::Ancf3d>()
    .unwrap();
    let (mut total, mut refused, mut wrong) = (0, 0, Vec::new());
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|f| f.to_string_lossy().ends_with("markers.json"))
        .collect();
    files.sort();
    for file in &files {
        let mut base: Value =
            serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        if base.get("markers").is_none() {
            continue; // a parallel robot's measurement, not planar markers
        }
        // the file's free text (read by the markers file, not by the
        // observation parsed here)
        if let Some(o) = base.as_object_mut() {
            o.remove("description");
        }
        let three_d = base["markers"][0]["position_m"]
            .as_array()
            .is_some_and(|p| p.len() == 3);
        for (path, x, v) in mutants(&base) {
            total += 1;
            let obs: softrod::estimate::Observation = serde_json::from_value(v).unwrap();
            let op = if three_d {
                softrod::observe::ObservationOperator::new(&spatial, &obs, 1e-5, 1e-3)
            } else {
                softrod::observe::ObservationOperator::new(&robot, &obs, 1e-5, 1e-3)
            };
            if let Err(e) = op {
                refused += 1;
                let m = e.to_string();
                if !names(&m, &format!("observation.{path}")) {
                    wrong.push(format!("{}: {path} = {x:e}: {m}", file.display()));
                }
            }
        }
    }
    println!(
        "{total} marker mutations: {refused} refused, {} wrong",
        wrong.len()
    );
    assert!(total >= 50, "only {total}");
    assert!(wrong.is_empty(), "{}", wrong.join("\n"));
}

#[test]
fn magnitudes_that_can_only_overflow_are_refused_with_their_path() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let base: Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{dir}/two_section.json")).unwrap())
            .unwrap();
    // α, a tip force, a line load, a moment 1e13 times the robot's scale
    for (patch, field) in [
        (
            serde_json::json!({"solver": {"estimator": {"alpha": 1e300}}}),
            "solver.estimator.alpha",
        ),
        (
            serde_json::json!({"loads": [{"type": "tip_force", "force_n": [0.0, -1e13]}]}),
            "loads[0].force_n[1]",
        ),
        (
            serde_json::json!({"loads": [{"type": "distributed", "profile": "uniform", "w_n_per_m": [1e14, 0.0]}]}),
            "loads[0].w_n_per_m[0]",
        ),
        (
            serde_json::json!({"loads": [{"type": "tip_moment", "moment_nm": 1e12}]}),
            "loads[0].moment_nm",
        ),
        (
            serde_json::json!({"loads": [{"type": "tip_mass", "mass_kg": 1e12}]}),
            "loads[0].mass_kg",
        ),
        (
            serde_json::json!({"loads": [{"type": "follower", "pressure_n_per_m": -1e14}]}),
            "loads[0].pressure_n_per_m",
        ),
    ] {
        let mut v = base.clone();
        for (k, x) in patch.as_object().unwrap() {
            if k == "solver" {
                v["solver"]["estimator"]["alpha"] = x["estimator"]["alpha"].clone();
            } else {
                v[k] = x.clone();
            }
        }
        let err = Scene::from_json(&v.to_string()).unwrap_err();
        assert_eq!(err.field(), Some(field), "{err}");
    }
    // the same loads at 1e9 times less are accepted
    let mut v = base.clone();
    v["loads"] = serde_json::json!([{"type": "tip_force", "force_n": [0.0, -1e4]}]);
    assert!(Scene::from_json(&v.to_string()).is_ok());
    // a marker's tangent of zero length, a weight and a position beyond scale
    let scene = Scene::from_json(&base.to_string()).unwrap();
    let robot = scene.robot().unwrap();
    for (marker, field) in [
        (
            r#"{"s_m": 0.24, "position_m": [0.2, 0.0], "tangent": [0, 0]}"#,
            "observation.markers[0].tangent",
        ),
        (
            r#"{"s_m": 0.24, "position_m": [0.2, 0.0], "position_weight": [1e300, 1]}"#,
            "observation.markers[0].position_weight[0]",
        ),
        (
            r#"{"s_m": 0.24, "position_m": [1e300, 0.0]}"#,
            "observation.markers[0].position_m[0]",
        ),
    ] {
        let obs: softrod::estimate::Observation =
            serde_json::from_str(&format!(r#"{{"markers": [{marker}]}}"#)).unwrap();
        let err = softrod::observe::ObservationOperator::new(&robot, &obs, 1e-5, 1e-3).unwrap_err();
        assert_eq!(err.field(), Some(field), "{err}");
    }
}

/// The parallel-robot scenes of the examples (`{"parallel": ...}`), swept
/// like the others (every number × the same values): every refusal names
/// the field the user wrote. Accepted mutations are not solved here (the
/// parallel robot's solves are `tests/parallel_scene.rs`'s).
#[test]
fn every_refused_parallel_mutation_names_its_field() {
    use softrod::scene::parallel::ParallelScene;
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|f| f.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    let (mut total, mut refused, mut scenes, mut wrong) = (0, 0, 0, Vec::new());
    for file in &files {
        let text = std::fs::read_to_string(file).unwrap();
        if !ParallelScene::is_parallel(&text) {
            continue;
        }
        scenes += 1;
        let base: Value = serde_json::from_str(&text).unwrap();
        for (path, x, v) in mutants(&base) {
            total += 1;
            if let Err(e) = ParallelScene::from_json(&v.to_string()) {
                refused += 1;
                let m = e.to_string();
                if !names(&m, &path) {
                    let name = file.file_name().unwrap().to_string_lossy();
                    wrong.push(format!("{name}: {path} = {x:e}: {m}"));
                }
            }
        }
    }
    println!(
        "{scenes} parallel scenes, {total} mutations: {refused} refused, {} wrong",
        wrong.len()
    );
    assert!(
        scenes >= 3 && total > 100,
        "{scenes} scenes, {total} mutations"
    );
    assert!(
        wrong.is_empty(),
        "{} of {refused} refusals name the wrong field:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}

/// Does the error name `path` or one of its ancestors (`obstacles[1]` for
/// `obstacles[1].vertices_m[2][0]`), never the root alone?
fn names_it_or_an_ancestor(message: &str, path: &str) -> bool {
    let cuts = path
        .char_indices()
        .filter(|(_, c)| *c == '.' || *c == '[')
        .map(|(i, _)| i)
        .chain([path.len()]);
    cuts.filter(|&i| i > 0)
        .any(|i| message.contains(&format!("`{}`", &path[..i])))
}

/// The avoidance scenes of the examples (`{"obstacles": ..., "goal_m": ...}`,
/// the input of `softrod avoid`), swept like the others: every refusal of
/// `AvoidScene::from_json` (which parses and checks every field) names the
/// field the user wrote, or the object whose condition it breaks: a
/// circle's centre moved onto the robot is refused as `obstacles[0]`
/// overlapping it, a vertex that makes the polygon clockwise as
/// `obstacles[1].vertices_m`.
#[test]
fn every_refused_avoid_mutation_names_its_field() {
    use softrod::touch::AvoidScene;
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|f| {
            f.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with("avoid_"))
                && f.extension().is_some_and(|e| e == "json")
        })
        .collect();
    files.sort();
    let (mut total, mut refused, mut exact, mut wrong) = (0, 0, 0, Vec::new());
    for file in &files {
        let base: Value = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        AvoidScene::from_json(&base.to_string()).unwrap();
        for (path, x, v) in mutants(&base) {
            total += 1;
            if let Err(e) = AvoidScene::from_json(&v.to_string()) {
                refused += 1;
                let m = e.to_string();
                if names(&m, &path) {
                    exact += 1;
                } else if !names_it_or_an_ancestor(&m, &path) {
                    let name = file.file_name().unwrap().to_string_lossy();
                    wrong.push(format!("{name}: {path} = {x:e}: {m}"));
                }
            }
        }
    }
    println!(
        "{} avoid scenes, {total} mutations: {refused} refused ({exact} naming the field, \
         {} its obstacle or vertex list), {} wrong",
        files.len(),
        refused - exact - wrong.len(),
        wrong.len()
    );
    assert!(files.len() >= 2 && total >= 50, "{files:?}: {total}");
    // A 1e308 polygon vertex used to overflow the edge arithmetic and blame
    // another vertex; `Obstacle::validate` now bounds coordinates and radii.
    assert!(
        wrong.is_empty(),
        "{} of {refused} refusals name the wrong field:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}

/// The example files whose name starts with `prefix` (sorted).
fn example_files(prefix: &str) -> Vec<std::path::PathBuf> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|f| {
            f.file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with(prefix))
                && f.extension().is_some_and(|e| e == "json")
        })
        .collect();
    files.sort();
    files
}

/// Sweeps the mutants of `files` through `check` (the parse-and-validate
/// function the command line calls for that input): the file itself is
/// accepted, and every refusal names the field the user wrote. Returns
/// (mutations, refusals) after asserting 0 wrong names.
fn sweep_inputs(
    what: &str,
    files: &[std::path::PathBuf],
    check: impl Fn(&str) -> Result<(), softrod::Error>,
) -> (usize, usize) {
    let (mut total, mut refused, mut wrong) = (0, 0, Vec::new());
    for file in files {
        let name = file.file_name().unwrap().to_string_lossy();
        let base: Value = serde_json::from_str(&std::fs::read_to_string(file).unwrap()).unwrap();
        if let Err(e) = check(&base.to_string()) {
            panic!("{name} itself is refused: {e}");
        }
        for (path, x, v) in mutants(&base) {
            total += 1;
            if let Err(e) = check(&v.to_string()) {
                refused += 1;
                let m = e.to_string();
                if !names(&m, &path) {
                    wrong.push(format!("{name}: {path} = {x:e}: {m}"));
                }
            }
        }
    }
    println!(
        "{what}: {} files, {total} mutations: {refused} refused, {} wrong",
        files.len(),
        wrong.len()
    );
    assert!(
        wrong.is_empty(),
        "{what}: {} of {refused} refusals name the wrong field:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
    (total, refused)
}

/// `softrod track`'s inputs on the planar robot of `examples/track_scene.json`:
/// the trajectory files (`TrackFile::from_json`, then `check_track`, the
/// checks `run_track` makes before it runs) and the payload files
/// (`payloads_from_json`, then `check_track` with the circle's file).
#[test]
fn every_refused_track_mutation_names_its_field() {
    use softrod::control::{TrackFile, check_track, payloads_from_json};
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let scene =
        Scene::from_json(&std::fs::read_to_string(format!("{dir}/track_scene.json")).unwrap())
            .unwrap();
    let trajectories = example_files("trajectory_");
    let (total, _) = sweep_inputs("trajectory files", &trajectories, |text| {
        check_track(&scene, &TrackFile::from_json(text)?, None).map(|_| ())
    });
    assert!(trajectories.len() >= 3 && total >= 200, "{total}");
    let circle = TrackFile::from_json(
        &std::fs::read_to_string(format!("{dir}/trajectory_circle.json")).unwrap(),
    )
    .unwrap();
    let payloads = example_files("payload_");
    let (total, _) = sweep_inputs("payload files", &payloads, |text| {
        check_track(&scene, &circle, Some(&payloads_from_json(text)?)).map(|_| ())
    });
    assert!(payloads.len() >= 3 && total >= 50, "{total}");
}

/// The parallel robot's inputs besides its scenes: the tracking settings
/// (`TrackSettings::from_json`) and the platform markers
/// (`PlatformMarkers::from_json` against `examples/parallel_estimate.json`).
#[test]
fn every_refused_parallel_input_mutation_names_its_field() {
    use softrod::control::parallel::TrackSettings;
    use softrod::scene::parallel::{ParallelScene, PlatformMarkers};
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let (total, _) = sweep_inputs(
        "parallel tracking settings",
        &example_files("parallel_track_settings"),
        |text| TrackSettings::from_json(text).map(|_| ()),
    );
    assert!(total >= 50, "{total}");
    let scene = ParallelScene::from_json(
        &std::fs::read_to_string(format!("{dir}/parallel_estimate.json")).unwrap(),
    )
    .unwrap();
    let (total, _) = sweep_inputs(
        "platform markers",
        &example_files("parallel_markers"),
        |text| PlatformMarkers::from_json(text, &scene).map(|_| ()),
    );
    assert!(total >= 30, "{total}");
}

/// `softrod grasp`'s scene files (`GraspScene::from_json`: the checks
/// `run_trial` makes before it simulates).
#[test]
fn every_refused_grasp_mutation_names_its_field() {
    use softrod::grasp::scene::GraspScene;
    let files = example_files("grasp_");
    let (total, _) = sweep_inputs("grasp scenes", &files, |text| {
        GraspScene::from_json(text).map(|_| ())
    });
    assert!(!files.is_empty() && total >= 30, "{total}");
}

/// A parse-and-check function over a file's text.
type Check = Box<dyn Fn(&str) -> Result<(), softrod::Error>>;

/// The parse-and-check function the command line runs on an example file,
/// by the file's kind; `None` for a markers file (read by `softrod
/// estimate`'s own reader) and for the scenes the trajectory and payload
/// checks run against.
fn checker(name: &str, text: &str) -> Option<Check> {
    use softrod::control::parallel::TrackSettings;
    use softrod::control::{TrackFile, check_track, payloads_from_json};
    use softrod::grasp::scene::GraspScene;
    use softrod::scene::parallel::{ParallelScene, PlatformMarkers};
    use softrod::touch::AvoidScene;
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let read = |f: &str| std::fs::read_to_string(format!("{dir}/{f}")).unwrap();
    // markers files and recorded marker streams (`*_frames.json`) are the
    // estimate command's input, not a scene
    if (name.ends_with("markers.json") && !name.starts_with("parallel_"))
        || name.ends_with("_frames.json")
    {
        return None;
    }
    if ParallelScene::is_parallel(text) {
        return Some(Box::new(|t| ParallelScene::from_json(t).map(|_| ())));
    }
    if name.starts_with("avoid_") {
        return Some(Box::new(|t| AvoidScene::from_json(t).map(|_| ())));
    }
    if name.starts_with("grasp_") {
        return Some(Box::new(|t| GraspScene::from_json(t).map(|_| ())));
    }
    if name.starts_with("parallel_track_settings") {
        return Some(Box::new(|t| TrackSettings::from_json(t).map(|_| ())));
    }
    if name.starts_with("parallel_markers") {
        let scene = ParallelScene::from_json(&read("parallel_estimate.json")).unwrap();
        return Some(Box::new(move |t| {
            PlatformMarkers::from_json(t, &scene).map(|_| ())
        }));
    }
    let track_scene = Scene::from_json(&read("track_scene.json")).unwrap();
    if name.starts_with("trajectory_") {
        return Some(Box::new(move |t| {
            check_track(&track_scene, &TrackFile::from_json(t)?, None).map(|_| ())
        }));
    }
    if name.starts_with("payload_") {
        let circle = TrackFile::from_json(&read("trajectory_circle.json")).unwrap();
        return Some(Box::new(move |t| {
            check_track(&track_scene, &circle, Some(&payloads_from_json(t)?)).map(|_| ())
        }));
    }
    Some(Box::new(|t| {
        let scene = Scene::from_json(t)?;
        if !scene.has_auto_elements() && !solve_finite(&scene).unwrap_or(true) {
            return Err(softrod::Error::NonFinite {
                context: "accepted: the solved shape".into(),
            });
        }
        Ok(())
    }))
}

/// The extended sweep of issue 33: every example input (scenes, parallel,
/// avoidance and grasp scenes, trajectory, payload, parallel tracking and
/// platform-marker files) × each number set to "NaN", a string and `[]`,
/// plus the deletion and the duplication of every field. Every refusal
/// must name the exact field (its path as written: not an ancestor, not an
/// internal name); an accepted scene is solved and must be finite.
#[test]
fn every_odd_value_deleted_or_duplicated_field_is_refused_by_its_path() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/examples");
    let mut files: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|f| f.extension().is_some_and(|e| e == "json"))
        .collect();
    files.sort();
    let (mut total, mut refused, mut accepted, mut nan) = (0, 0, 0, 0);
    let mut wrong = Vec::new();
    for file in &files {
        let name = file.file_name().unwrap().to_string_lossy().to_string();
        let text = std::fs::read_to_string(file).unwrap();
        let Some(check) = checker(&name, &text) else {
            continue;
        };
        let base: Value = serde_json::from_str(&text).unwrap();
        for (path, what, t) in more_mutants(&base) {
            total += 1;
            match check(&t) {
                Ok(()) => accepted += 1,
                Err(softrod::Error::NonFinite { .. }) => {
                    nan += 1;
                    wrong.push(format!("{name}: {path} {what}: accepted, non-finite shape"));
                }
                Err(e) => {
                    refused += 1;
                    let m = e.to_string();
                    if !(names(&m, &path) || what == "deleted" && names_written(&m, &base)) {
                        wrong.push(format!("{name}: {path} {what}: {m}"));
                    }
                }
            }
        }
    }
    println!(
        "extended sweep: {total} mutations: {refused} refused, {accepted} accepted ({nan} with a NaN), {} wrong",
        wrong.len()
    );
    assert!(total > 1000, "only {total}");
    assert!(
        wrong.is_empty(),
        "{} of {refused} refusals name the wrong field:\n{}",
        wrong.len(),
        wrong.join("\n")
    );
}

/// For a deleted field whose default conflicts with another field (a
/// planar default against 3-D vectors, no chambers against the pressures)
/// or an object left without either of two alternatives (a marker's `node`
/// or `s_m`): the refusal names, by its exact path, a field the file still
/// has.
fn names_written(message: &str, doc: &Value) -> bool {
    let mut all = Vec::new();
    walk(doc, String::new(), &mut all, Vec::new(), &|_| true);
    all.iter()
        .any(|(p, _)| !p.is_empty() && message.contains(&format!("`{p}`")))
}
