//! The command line's output format (issue 37): every record carries the
//! header (`format_version`, `command`, `scene`, `scene_kind`, `outcome`)
//! and a typed `status`; its JSON Schema is generated from the Rust types
//! (`softrod schema`) and committed under schema/; every example's output
//! validates against its schema; a renamed field fails; the exit codes are
//! 0 success, 2 goal not met (record written), 1 error.
//!
//! The validator here covers the keywords the generated schemas use and
//! panics on any other, so a schema it does not understand cannot pass.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::path::{Path, PathBuf};

use serde_json::Value;

const ROOT: &str = env!("CARGO_MANIFEST_DIR");

#[path = "common/cli.rs"]
mod cli;
use cli::softrod as run;

fn schema(name: &str) -> Value {
    let path = format!("{ROOT}/schema/{name}.schema.json");
    serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap()
}

/// The keywords that only annotate.
const ANNOTATIONS: [&str; 5] = ["$schema", "title", "description", "default", "format"];

/// The errors of `v` against `s` (root `root` for `$ref`s), each with the
/// path of the value in the record.
fn validate(root: &Value, s: &Value, v: &Value, at: &str, errors: &mut Vec<String>) {
    let s = match s {
        Value::Bool(true) => return,
        Value::Bool(false) => {
            errors.push(format!("{at}: no value allowed"));
            return;
        }
        Value::Object(o) => o,
        _ => panic!("{at}: schema {s} is neither an object nor a boolean"),
    };
    for (k, kv) in s {
        match k.as_str() {
            k if ANNOTATIONS.contains(&k) => {}
            "$defs" => {}
            "$ref" => {
                let name = kv.as_str().unwrap().strip_prefix("#/$defs/").unwrap();
                validate(root, &root["$defs"][name], v, at, errors);
            }
            "type" => {
                let types: Vec<&str> = match kv {
                    Value::String(t) => vec![t.as_str()],
                    Value::Array(ts) => ts.iter().map(|t| t.as_str().unwrap()).collect(),
                    _ => panic!("{at}: type {kv}"),
                };
                let ok = types.iter().any(|t| match *t {
                    "object" => v.is_object(),
                    "array" => v.is_array(),
                    "string" => v.is_string(),
                    "boolean" => v.is_boolean(),
                    "null" => v.is_null(),
                    "number" => v.is_number(),
                    "integer" => v.is_u64() || v.is_i64(),
                    other => panic!("{at}: unknown type {other}"),
                });
                if !ok {
                    errors.push(format!("{at}: {v} is not of type {kv}"));
                }
            }
            "properties" => {
                if let Some(o) = v.as_object() {
                    for (name, ps) in kv.as_object().unwrap() {
                        if let Some(x) = o.get(name) {
                            validate(root, ps, x, &format!("{at}.{name}"), errors);
                        }
                    }
                }
            }
            "required" => {
                if let Some(o) = v.as_object() {
                    for name in kv.as_array().unwrap() {
                        let name = name.as_str().unwrap();
                        if !o.contains_key(name) {
                            errors.push(format!("{at}: missing `{name}`"));
                        }
                    }
                }
            }
            "additionalProperties" => {
                if let Some(o) = v.as_object() {
                    let known = s.get("properties").and_then(Value::as_object);
                    for (name, x) in o {
                        if known.is_some_and(|p| p.contains_key(name)) {
                            continue;
                        }
                        match kv {
                            Value::Bool(false) => {
                                errors.push(format!("{at}: unknown field `{name}`"))
                            }
                            _ => validate(root, kv, x, &format!("{at}.{name}"), errors),
                        }
                    }
                }
            }
            "items" => {
                if let Some(a) = v.as_array() {
                    let skip = s
                        .get("prefixItems")
                        .and_then(Value::as_array)
                        .map_or(0, Vec::len);
                    for (i, x) in a.iter().enumerate().skip(skip) {
                        validate(root, kv, x, &format!("{at}[{i}]"), errors);
                    }
                }
            }
            "prefixItems" => {
                if let Some(a) = v.as_array() {
                    for (i, (ps, x)) in kv.as_array().unwrap().iter().zip(a).enumerate() {
                        validate(root, ps, x, &format!("{at}[{i}]"), errors);
                    }
                }
            }
            "minItems" | "maxItems" => {
                if let Some(a) = v.as_array() {
                    let n = kv.as_u64().unwrap() as usize;
                    if (k == "minItems" && a.len() < n) || (k == "maxItems" && a.len() > n) {
                        errors.push(format!("{at}: {} items, {k} {n}", a.len()));
                    }
                }
            }
            "minimum" => {
                if let Some(x) = v.as_f64()
                    && x < kv.as_f64().unwrap()
                {
                    errors.push(format!("{at}: {x} below {kv}"));
                }
            }
            "enum" => {
                if !kv.as_array().unwrap().contains(v) {
                    errors.push(format!("{at}: {v} is not one of {kv}"));
                }
            }
            "const" => {
                if kv != v {
                    errors.push(format!("{at}: {v} is not {kv}"));
                }
            }
            "oneOf" | "anyOf" => {
                let passing = kv
                    .as_array()
                    .unwrap()
                    .iter()
                    .filter(|b| {
                        let mut e = Vec::new();
                        validate(root, b, v, at, &mut e);
                        e.is_empty()
                    })
                    .count();
                if passing == 0 || (k == "oneOf" && passing > 1) {
                    errors.push(format!("{at}: {v} matches {passing} branches of {k}"));
                }
            }
            "allOf" => {
                for b in kv.as_array().unwrap() {
                    validate(root, b, v, at, errors);
                }
            }
            other => panic!("{at}: schema keyword `{other}` not understood by this validator"),
        }
    }
}

fn errors_of(schema: &Value, v: &Value) -> Vec<String> {
    let mut e = Vec::new();
    validate(schema, schema, v, "$", &mut e);
    e
}

fn temp(name: &str) -> PathBuf {
    std::env::temp_dir().join(format!(
        "softrod-output-schema-{}-{name}",
        std::process::id()
    ))
}

/// The committed schemas are the types' own: `softrod schema` regenerates
/// every file of schema/ byte for byte (a renamed field changes the schema
/// and fails here until the files are regenerated, and `format_version`
/// bumped if a reader of version 1 would misread the record).
#[test]
fn committed_schemas_are_generated_from_the_types() {
    let dir = temp("schemas");
    let (code, _, err) = run(&["schema", "--out", dir.to_str().unwrap()]);
    assert_eq!(code, 0, "{err}");
    let mut generated: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    generated.sort();
    let mut committed: Vec<_> = std::fs::read_dir(format!("{ROOT}/schema"))
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    committed.sort();
    assert_eq!(generated, committed);
    assert_eq!(generated.len(), 8, "{generated:?}");
    for f in &generated {
        let a = std::fs::read_to_string(dir.join(f)).unwrap();
        let b = std::fs::read_to_string(Path::new(ROOT).join("schema").join(f)).unwrap();
        assert!(
            a == b,
            "schema/{f} differs from the types: regenerate with \
             `cargo run --release --features cli -- schema --out schema` (and bump \
             FORMAT_VERSION in src/cli/output.rs if a field was renamed, removed or retyped)"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A short parallel tracking run (the example's settings, 2 s instead of 20).
fn short_parallel_settings() -> String {
    let text =
        std::fs::read_to_string(format!("{ROOT}/examples/parallel_track_settings.json")).unwrap();
    let mut v: Value = serde_json::from_str(&text).unwrap();
    v["duration_s"] = 2.0.into();
    v["hold_s"] = 1.0.into();
    v["score_from_s"] = 1.0.into();
    let p = temp("parallel_track_settings.json");
    std::fs::write(&p, v.to_string()).unwrap();
    p.to_string_lossy().into_owned()
}

/// Every example input through the command that reads it, each output
/// validated against its schema: the header, the typed status, no unknown
/// field, every required one. Every example file is used (a new one without
/// a line here fails).
#[test]
fn every_example_output_validates_against_its_schema() {
    let settings = short_parallel_settings();
    let mut cases: Vec<(Vec<String>, &str)> = Vec::new();
    let mut add = |args: &[&str], schema: &'static str| {
        cases.push((args.iter().map(|s| s.to_string()).collect(), schema));
    };
    // one leg of the parallel robot as a robot scene (it has no markers)
    add(&["solve", "examples/parallel_leg_ancf3d.json"], "solve");
    for scene in [
        "two_section",
        "spatial_cantilever",
        "ancf3d_cantilever",
        "auto_tip",
        "track_scene",
    ] {
        let f = format!("examples/{scene}.json");
        add(&["solve", &f], "solve");
        add(&["estimate", &f], "estimate");
    }
    let markers = [
        ("auto_load", "auto_load_markers", "estimate"),
        ("ancf3d_cantilever", "ancf3d_cantilever_markers", "estimate"),
        ("two_section", "two_section_payload_markers", "estimate"),
        (
            "two_section",
            "two_section_payload_frames",
            "estimate_stream",
        ),
    ];
    for (scene, m, schema) in markers {
        let (s, m) = (
            format!("examples/{scene}.json"),
            format!("examples/{m}.json"),
        );
        add(&["estimate", &s, "--markers", &m], schema);
    }
    for p in [
        "parallel_estimate",
        "parallel_robot",
        "parallel_twist",
        "parallel_track",
    ] {
        add(&["solve", &format!("examples/{p}.json")], "solve_parallel");
    }
    add(
        &["estimate", "examples/parallel_estimate.json"],
        "estimate_parallel",
    );
    add(
        &[
            "estimate",
            "examples/parallel_estimate.json",
            "--markers",
            "examples/parallel_markers.json",
        ],
        "estimate_parallel",
    );
    add(
        &[
            "track",
            "examples/parallel_track.json",
            "--trajectory",
            &settings,
        ],
        "track",
    );
    add(&["track", "examples/track_scene.json"], "track");
    for t in ["circle", "figure_eight", "line"] {
        let t = format!("examples/trajectory_{t}.json");
        add(
            &["track", "examples/track_scene.json", "--trajectory", &t],
            "track",
        );
    }
    for p in ["mixed", "sliding", "tip"] {
        let p = format!("examples/payload_{p}.json");
        add(
            &[
                "track",
                "examples/track_scene.json",
                "--trajectory",
                "examples/trajectory_line.json",
                "--payload",
                &p,
                "--controller",
                "ff",
            ],
            "track",
        );
    }
    for a in ["avoid_disk", "avoid_two_obstacles"] {
        add(&["avoid", &format!("examples/{a}.json")], "avoid");
    }
    add(&["grasp", "examples/grasp_apple.json"], "grasp");
    add(
        &[
            "grasp",
            "examples/grasp_apple.json",
            "--strategy",
            "open_loop",
        ],
        "grasp",
    );

    // every example input is read by some case (parallel_track_settings
    // through its shortened copy)
    let used: String = cases.iter().map(|(a, _)| a.join(" ")).collect();
    for e in std::fs::read_dir(format!("{ROOT}/examples")).unwrap() {
        let name = e.unwrap().file_name().into_string().unwrap();
        if name.ends_with(".json") && name != "parallel_track_settings.json" {
            assert!(
                used.contains(&format!("examples/{name}")),
                "{name} is not run"
            );
        }
    }

    let mut failures = Vec::new();
    for (args, name) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, out, err) = run(&args);
        let what = args.join(" ");
        assert_eq!(code, 0, "{what}: {err}");
        let v: Value = serde_json::from_str(&out).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(v["format_version"], "1", "{what}");
        assert_eq!(v["command"], args[0], "{what}");
        assert_eq!(v["outcome"], "success", "{what}");
        assert!(v.get("status").is_some_and(|s| !s.is_null()) || *name == "estimate_parallel");
        let e = errors_of(&schema(name), &v);
        if !e.is_empty() {
            failures.push(format!("{what} against {name}: {}", e.join("; ")));
        }
    }
    std::fs::remove_file(&settings).unwrap();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    println!("{} outputs validated", cases.len());
}

/// The validation can fail: a renamed field (top level or nested), a
/// removed one, another version, or a misspelt enum value is refused.
#[test]
fn a_renamed_field_fails_validation() {
    let (code, out, err) = run(&["solve", "examples/two_section.json"]);
    assert_eq!(code, 0, "{err}");
    let good: Value = serde_json::from_str(&out).unwrap();
    let s = schema("solve");
    assert!(errors_of(&s, &good).is_empty());
    let rename = |v: &Value, path: &[&str], to: &str| {
        let mut v = v.clone();
        let mut o = &mut v;
        for p in &path[..path.len() - 1] {
            o = &mut o[*p];
        }
        let map = o.as_object_mut().unwrap();
        let x = map.remove(path[path.len() - 1]).unwrap();
        map.insert(to.to_string(), x);
        v
    };
    for (path, to) in [
        (&["tip_position_m"][..], "tip_pos_m"),
        (&["format_version"][..], "version"),
        (&["report", "residual_norm_n"][..], "residual_n"),
        (&["scene_kind"][..], "kind"),
    ] {
        let bad = rename(&good, path, to);
        assert!(!errors_of(&s, &bad).is_empty(), "{path:?} -> {to} passed");
    }
    let mut bad = good.clone();
    bad["format_version"] = "2".into();
    assert!(!errors_of(&s, &bad).is_empty());
    let mut bad = good.clone();
    bad["status"] = serde_json::json!({"converged": "residue"});
    assert!(!errors_of(&s, &bad).is_empty());
    let mut bad = good.clone();
    bad["nodes"][3]["position"] = bad["nodes"][3]["position_m"].take();
    assert!(!errors_of(&s, &bad).is_empty());
    // the parallel pose has named parts
    let (_, out, _) = run(&["solve", "examples/parallel_robot.json"]);
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(
        v["platform_pose"]["position_m"].as_array().unwrap().len(),
        3
    );
    assert_eq!(
        v["platform_pose"]["rotation_vector_rad"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
    let bad = rename(&v, &["platform_pose", "position_m"], "position");
    assert!(!errors_of(&schema("solve_parallel"), &bad).is_empty());
}

/// Exit code 2 for a run that wrote its record but missed its goal
/// (`outcome: goal_not_met`): an estimate that does not fit, a grasp that
/// does not hold, an unreachable avoidance goal; 1 for bad input (no
/// record); `--help` states them. Before: the failed grasp exited 0, the
/// missed goal and the unfit estimate 1.
#[test]
fn exit_codes_say_success_goal_not_met_or_error() {
    let check = |args: &[&str], schema_name: &str| {
        let (code, out, err) = run(args);
        assert_eq!(code, 2, "{args:?}: {err}");
        assert!(err.contains("softrod: goal not met:"), "{err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["outcome"], "goal_not_met", "{args:?}");
        let e = errors_of(&schema(schema_name), &v);
        assert!(e.is_empty(), "{args:?}: {e:?}");
        v
    };
    // an estimate allowed one iteration (the last frame of the example
    // stream, with its payload): iteration_limit
    let text = std::fs::read_to_string(format!("{ROOT}/examples/two_section.json")).unwrap();
    let mut scene: Value = serde_json::from_str(&text).unwrap();
    scene["solver"]["estimator"]["max_iterations"] = 1.into();
    let one = temp("one_iteration.json");
    std::fs::write(&one, scene.to_string()).unwrap();
    let text = std::fs::read_to_string(format!("{ROOT}/examples/two_section_payload_frames.json"))
        .unwrap();
    let frames: Value = serde_json::from_str(&text).unwrap();
    let markers = temp("last_frame.json");
    let last = frames["frames"].as_array().unwrap().last().unwrap();
    std::fs::write(
        &markers,
        serde_json::json!({"markers": last["markers"]}).to_string(),
    )
    .unwrap();
    let v = check(
        &[
            "estimate",
            one.to_str().unwrap(),
            "--markers",
            markers.to_str().unwrap(),
        ],
        "estimate",
    );
    assert!(
        v["status"].get("iteration_limit").is_some(),
        "{}",
        v["status"]
    );
    // a grasp of an object thirty times the apple's mass
    let text = std::fs::read_to_string(format!("{ROOT}/examples/grasp_apple.json")).unwrap();
    let mut g: Value = serde_json::from_str(&text).unwrap();
    g["object"]["mass_kg"] = 5.0.into();
    let heavy = temp("heavy.json");
    std::fs::write(&heavy, g.to_string()).unwrap();
    let v = check(&["grasp", heavy.to_str().unwrap()], "grasp");
    assert_eq!(v["status"], "failed");
    assert_eq!(v["success"], false);
    // an avoidance goal outside the workspace
    let text = std::fs::read_to_string(format!("{ROOT}/examples/avoid_disk.json")).unwrap();
    let mut a: Value = serde_json::from_str(&text).unwrap();
    a["goal_m"] = serde_json::json!([0.0, 0.6]);
    let far = temp("far_goal.json");
    std::fs::write(&far, a.to_string()).unwrap();
    let v = check(&["avoid", far.to_str().unwrap()], "avoid");
    assert_eq!(v["status"]["status"], "goal_unreachable");
    // bad input: exit 1, nothing on standard output
    std::fs::write(
        &markers,
        r#"{"markers": [{"node": 20, "position": [0.2, 0.0]}]}"#,
    )
    .unwrap();
    let (code, out, err) = run(&[
        "estimate",
        "examples/two_section.json",
        "--markers",
        markers.to_str().unwrap(),
    ]);
    assert_eq!(code, 1, "{err}");
    assert!(
        out.is_empty() && err.contains("markers[0].position"),
        "{err}"
    );
    let (code, out, _) = run(&["--help"]);
    assert_eq!(code, 0);
    assert!(
        out.contains("Exit codes:") && out.contains("2  goal not met"),
        "{out}"
    );
    for f in [markers, heavy, far, one] {
        std::fs::remove_file(f).unwrap();
    }
}

/// One spelling per enum: the JSON's snake_case on the command line too
/// (`ff_updater`, `open_loop`), the older flag spellings still accepted,
/// and the summary on standard error spelled as the JSON.
#[test]
fn enums_are_spelled_as_in_the_json() {
    let (code, out, err) = run(&[
        "track",
        "examples/track_scene.json",
        "--controller",
        "ff_updater",
    ]);
    assert_eq!(code, 0, "{err}");
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["controller"], "ff_updater");
    assert_eq!(v["summary"]["controller"], "ff_updater");
    assert!(err.contains("softrod: track: ff_updater at"), "{err}");
    let (code, _, err) = run(&[
        "track",
        "examples/track_scene.json",
        "--controller",
        "ff+updater",
    ]);
    assert_eq!(code, 0, "the old spelling: {err}");
    for s in ["open_loop", "open-loop"] {
        let (code, out, err) = run(&["grasp", "examples/grasp_apple.json", "--strategy", s]);
        assert_eq!(code, 0, "{s}: {err}");
        let v: Value = serde_json::from_str(&out).unwrap();
        assert_eq!(v["strategy"], "open_loop");
        assert!(err.contains("(open_loop)"), "{err}");
    }
}
