//! The README is true: every `json` block is a scene that builds and solves,
//! or a fragment that, merged into an example scene, is accepted; every `sh`
//! block's commands run (the test command is the one CI runs).
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::process::Command;

use serde_json::Value;

const README: &str = include_str!("../README.md");
const CI: &str = include_str!("../.ci/run");

/// The fenced blocks of the README in language `lang`, with the line each starts on.
fn blocks(lang: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut current: Option<(usize, String)> = None;
    for (i, line) in README.lines().enumerate() {
        match (&mut current, line.trim_start().strip_prefix("```")) {
            (None, Some(tag)) if tag.trim() == lang => current = Some((i + 1, String::new())),
            (Some(_), Some("")) => out.push(current.take().unwrap()),
            (Some((_, text)), _) => {
                text.push_str(line);
                text.push('\n');
            }
            _ => {}
        }
    }
    assert!(current.is_none(), "README: unterminated ```{lang} block");
    out
}

#[path = "common/cli.rs"]
mod cli;
use cli::softrod;

fn temp_file(name: &str, text: &str) -> String {
    let path = std::env::temp_dir().join(format!("softrod-readme-{}-{name}", std::process::id()));
    std::fs::write(&path, text).unwrap();
    path.to_string_lossy().into_owned()
}

#[test]
fn json_blocks_are_scenes_that_solve_or_fragments_that_are_accepted() {
    let base: Value = serde_json::from_str(include_str!("../examples/auto_load.json")).unwrap();
    let (mut scenes, mut fragments) = (0, 0);
    for (line, text) in blocks("json") {
        let value: Value = serde_json::from_str(&text)
            .unwrap_or_else(|e| panic!("README line {line}: not JSON: {e}\n{text}"));
        if value.get("robot").is_some() {
            // a whole scene: `softrod solve` accepts it and converges
            let path = temp_file(&format!("scene-{line}.json"), &text);
            let (code, stdout, stderr) = softrod(&["solve", &path]);
            assert_eq!(code, 0, "README line {line}: {stderr}");
            let out: Value = serde_json::from_str(&stdout).unwrap();
            assert!(
                out["report"]["status"]["converged"].is_string(),
                "README line {line}: {}",
                out["report"]
            );
            assert!(stderr.is_empty(), "README line {line}: {stderr}");
            scenes += 1;
        } else {
            // a fragment: its fields replace those of an auto-element example
            let mut merged = base.clone();
            for (k, v) in value.as_object().unwrap() {
                merged[k] = v.clone();
            }
            let text = serde_json::to_string(&merged).unwrap();
            softrod::scene::Scene::from_json(&text)
                .and_then(|s| s.validate())
                .unwrap_or_else(|e| panic!("README line {line}: fragment refused: {e}"));
            fragments += 1;
        }
    }
    assert!(
        scenes >= 1 && fragments >= 2,
        "{scenes} scenes, {fragments} fragments"
    );
}

#[test]
fn sh_blocks_run_and_the_test_command_is_ci_s() {
    let mut ran = 0;
    let mut test_commands = 0;
    for (line, text) in blocks("sh") {
        for cmd in text.lines() {
            let cmd = cmd.split('#').next().unwrap().trim();
            if cmd.is_empty() {
                continue;
            }
            if cmd.starts_with("cargo test") {
                assert!(
                    CI.lines().any(|l| l.trim() == cmd),
                    "README line {line}: `{cmd}` is not the test command of .ci/run"
                );
                test_commands += 1;
                continue;
            }
            let rest = cmd
                .strip_prefix("cargo run --release --features cli")
                .unwrap_or_else(|| {
                    panic!("README line {line}: `{cmd}` is not a command this test knows")
                });
            let args: Vec<&str> = rest
                .trim()
                .strip_prefix("--")
                .unwrap_or(rest)
                .split_whitespace()
                .collect();
            let (code, stdout, stderr) = softrod(&args);
            assert_eq!(code, 0, "README line {line}: `{cmd}`: {stderr}");
            // a command with `--out FILE` writes the file instead (the
            // next command of its block may read it)
            let wrote = args
                .iter()
                .position(|a| *a == "--out")
                .and_then(|i| args.get(i + 1))
                .and_then(|f| {
                    std::fs::metadata(std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join(f)).ok()
                })
                .is_some_and(|m| m.len() > 0);
            assert!(
                !stdout.is_empty() || wrote,
                "README line {line}: `{cmd}` printed nothing"
            );
            ran += 1;
        }
    }
    assert_eq!(test_commands, 1, "the README names the test command once");
    assert!(ran >= 3, "only {ran} commands ran");
}

/// The module table of "What is in it" and the crate's rustdoc list every
/// public module of `src/lib.rs`.
#[test]
fn the_module_table_and_the_crate_docs_list_every_public_module() {
    let lib = include_str!("../src/lib.rs");
    let modules: Vec<&str> = lib
        .lines()
        .filter_map(|l| l.trim().strip_prefix("pub mod "))
        .map(|l| l.trim_end_matches(';').trim())
        .collect();
    assert!(modules.len() >= 20, "{modules:?}");
    let docs: String = lib
        .lines()
        .filter_map(|l| l.strip_prefix("//!"))
        .collect::<Vec<_>>()
        .join("\n");
    let mut missing = Vec::new();
    for m in &modules {
        if !README.contains(&format!("\n| `{m}` |")) {
            missing.push(format!("README's module table: `{m}`"));
        }
        if !docs.contains(&format!("[`{m}`]")) && !docs.contains(&format!("- `{m}`")) {
            missing.push(format!("the crate docs (src/lib.rs): `{m}`"));
        }
    }
    assert!(missing.is_empty(), "not listed:\n{}", missing.join("\n"));
}

/// `softrod report` writes into `target/report` of the directory it runs
/// in unless `--out` is given (so a run in a checkout leaves the committed
/// figures alone): the quick coverage part, run in an empty directory.
#[test]
fn report_writes_into_target_report_unless_out_is_given() {
    let dir = std::env::temp_dir().join(format!("softrod-readme-{}-report", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let run = |extra: &[&str]| {
        let out = Command::new(env!("CARGO_BIN_EXE_softrod"))
            .args(["report", "--only", "coverage", "--quick", "--quiet"])
            .args(extra)
            .current_dir(&dir)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    run(&[]);
    assert!(dir.join("target/report/coverage.json").is_file());
    run(&["--out", "elsewhere"]);
    assert!(dir.join("elsewhere/coverage.json").is_file());
    let written: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(written.len(), 2, "{written:?}");
    std::fs::remove_dir_all(&dir).unwrap();
}
