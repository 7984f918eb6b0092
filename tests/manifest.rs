//! Cargo.toml says what an example needs: every example that uses the
//! feature-gated `report` tree (or the command line) is declared with
//! `required-features`, so `cargo run --example NAME` with too few features
//! names the missing feature instead of failing to compile, and
//! `cargo test` without features leaves it out.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

const MANIFEST: &str = include_str!("../Cargo.toml");

/// The `[[example]]` entries: name and required features.
fn declared_examples() -> Vec<(String, Vec<String>)> {
    let mut out = Vec::new();
    for block in MANIFEST.split("[[example]]").skip(1) {
        let block = block.split("\n[").next().unwrap();
        let value = |key: &str| {
            block
                .lines()
                .find_map(|l| l.trim().strip_prefix(key)?.trim().strip_prefix('='))
                .map(|v| v.trim().to_string())
        };
        let name = value("name").unwrap().trim_matches('"').to_string();
        let features = value("required-features")
            .map(|v| {
                v.trim_matches(|c| c == '[' || c == ']')
                    .split(',')
                    .map(|f| f.trim().trim_matches('"').to_string())
                    .filter(|f| !f.is_empty())
                    .collect()
            })
            .unwrap_or_default();
        out.push((name, features));
    }
    out
}

/// The feature an example's source needs, if any.
fn needed_feature(source: &str) -> Option<&'static str> {
    if source.contains("softrod::cli") {
        Some("cli")
    } else if source.contains("softrod::report") || source.contains("report::") {
        Some("report")
    } else {
        None
    }
}

#[test]
fn every_example_that_needs_a_feature_requires_it() {
    let declared = declared_examples();
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples");
    let mut checked = 0;
    let mut missing = Vec::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().and_then(|e| e.to_str()) != Some("rs") {
            continue;
        }
        let name = path.file_stem().unwrap().to_str().unwrap().to_string();
        let source = std::fs::read_to_string(&path).unwrap();
        let required = declared
            .iter()
            .find(|(n, _)| *n == name)
            .map(|(_, f)| f.clone())
            .unwrap_or_default();
        if let Some(feature) = needed_feature(&source) {
            // `cli` implies `report`: either satisfies an example of the report tree
            let ok = required.iter().any(|f| f == feature || f == "cli");
            if !ok {
                missing.push(format!("{name}: needs `{feature}`, requires {required:?}"));
            }
        }
        checked += 1;
    }
    assert!(checked >= 10, "only {checked} examples found in {dir:?}");
    assert!(
        missing.is_empty(),
        "add to Cargo.toml:\n[[example]]\nname = \"...\"\nrequired-features = [\"...\"]\n\n{}",
        missing.join("\n")
    );
    // and every declared example exists
    for (name, _) in &declared {
        assert!(
            dir.join(format!("{name}.rs")).is_file(),
            "Cargo.toml declares example `{name}`, examples/{name}.rs is missing"
        );
    }
}

/// The parser reads what it should: the report examples are declared with
/// `report` (so the test above cannot pass on an empty list).
#[test]
fn the_manifest_parser_reads_the_declared_features() {
    let declared = declared_examples();
    let avoid = declared.iter().find(|(n, _)| n == "avoid_fig9").unwrap();
    assert_eq!(avoid.1, vec!["report".to_string()]);
    assert!(declared.len() >= 7, "{declared:?}");
    assert!(needed_feature("use softrod::report::touch;") == Some("report"));
    assert!(needed_feature("use softrod::scene::Scene;").is_none());
}
