//! The public API is a committed list, so that a change to it is deliberate.
//!
//! `tests/public_api.txt` lists every `pub` item of the library's source
//! (the command line, `src/main.rs` and `src/cli/`, is not the library;
//! the experiments of feature `report`, `src/report/`, are listed apart in
//! `tests/public_api_report.txt`, so the library's list is the numerics a
//! user calls):
//! one line per item, `module | container | signature`, where the
//! container is the `impl`, `struct`, `enum` or `trait` the item sits in
//! and the signature is the item's declaration with its whitespace
//! collapsed (a function up to its body, a field with its type). Items of
//! `#[cfg(test)]` code are left out. Nightly-only tools (`cargo
//! public-api`) are not needed: the list is read from the source.
//!
//! A change to the public API changes the list; the test then fails with
//! the lines added and removed. Regenerate the file after a deliberate
//! change with
//!
//! ```text
//! SOFTROD_BLESS_API=1 cargo test --release --test api_snapshot
//! ```
//!
//! (The list is textual: a `pub` item inside a private module is listed
//! too, which only makes the check stricter.)
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

const SNAPSHOT: &str = "tests/public_api.txt";

/// The report tree's list (feature `report`: the studies, tables and
/// paper-figure runs).
const SNAPSHOT_REPORT: &str = "tests/public_api_report.txt";

/// Whether a source file (relative path, `/`-separated) is in the report
/// tree.
fn in_report(r: &str) -> bool {
    r.starts_with("src/report/")
}

/// Item keywords after `pub `.
const KINDS: [&str; 11] = [
    "fn ",
    "struct ",
    "enum ",
    "trait ",
    "type ",
    "const ",
    "static ",
    "mod ",
    "use ",
    "unsafe fn ",
    "async fn ",
];

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|e| e == "rs") {
            out.push(p);
        }
    }
}

/// `src/a/b.rs` → `a::b`, `src/a/mod.rs` → `a`, `src/lib.rs` → `crate`.
fn module_path(rel: &Path) -> String {
    let s = rel.with_extension("");
    let parts: Vec<String> = s
        .components()
        .skip(1)
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .filter(|c| c != "mod")
        .collect();
    if parts == ["lib"] {
        "crate".into()
    } else {
        parts.join("::")
    }
}

fn collapse(s: &str) -> String {
    s.split_whitespace()
        .collect::<Vec<_>>()
        .join(" ")
        .replace("( ", "(")
        .replace(", )", ")")
        .replace(" )", ")")
}

/// The declaration starting at line `i`: up to its body `{`, its `;` or a
/// field's `,`.
fn declaration(lines: &[&str], i: usize, field: bool) -> String {
    if lines[i].trim_start().starts_with("pub use ") {
        let text = lines[i..].join(" ");
        return collapse(text.split(';').next().unwrap_or(""));
    }
    let mut text = String::new();
    let mut depth = 0i32;
    for line in &lines[i..] {
        for ch in line.chars() {
            match ch {
                '(' | '<' | '[' => depth += 1,
                ')' | '>' | ']' => depth -= 1,
                '{' if depth <= 0 => return collapse(&text),
                ';' if depth <= 0 => return collapse(&text),
                ',' if field && depth <= 0 => return collapse(&text),
                _ => {}
            }
            // `->` is not a closing bracket, `<<` (a shift) no bracket
            if ch == '>' && text.ends_with('-') {
                depth += 1;
            }
            if ch == '<' && text.ends_with('<') {
                depth -= 2;
            }
            text.push(ch);
        }
        text.push(' ');
    }
    collapse(&text)
}

/// The listing of the library (`report == false`) or of the report tree.
fn listing(root: &Path, report: bool) -> BTreeSet<String> {
    let mut files = Vec::new();
    rust_files(&root.join("src"), &mut files);
    let mut out = BTreeSet::new();
    for path in files {
        let rel = path.strip_prefix(root).unwrap().to_path_buf();
        let r = rel.to_string_lossy().replace('\\', "/");
        if r == "src/main.rs"
            || r.starts_with("src/cli/")
            || r.ends_with("/tests.rs")
            || in_report(&r) != report
        {
            continue;
        }
        let module = module_path(&rel);
        let text = std::fs::read_to_string(&path).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        let mut container = String::new();
        for (i, line) in lines.iter().enumerate() {
            if line.starts_with("#[cfg(test)]") {
                // the listing ends at a file's first test item: a public
                // item after it would be left out, so test items go last
                let hidden = lines[i..].iter().find(|l| l.starts_with("pub "));
                assert!(
                    hidden.is_none(),
                    "{r}: public item after the test item at line {}: {hidden:?} (move the test item to the end of the file)",
                    i + 1
                );
                break;
            }
            let trimmed = line.trim_start();
            let top = trimmed.len() == line.len();
            if top
                && [
                    "impl",
                    "pub struct",
                    "pub enum",
                    "pub trait",
                    "struct",
                    "enum",
                    "trait",
                ]
                .iter()
                .any(|k| trimmed.starts_with(k))
            {
                container = declaration(&lines, i, false);
            } else if top
                && !trimmed.is_empty()
                && !trimmed.starts_with("//")
                && !trimmed.starts_with('#')
                && !trimmed.starts_with('}')
            {
                container.clear();
            }
            // a public trait's methods are public without `pub`
            let in_trait = !top && container.starts_with("pub trait") && trimmed.starts_with("fn ");
            let Some(rest) = trimmed.strip_prefix("pub ").or(in_trait.then_some(trimmed)) else {
                continue;
            };
            let item = KINDS.iter().any(|k| rest.starts_with(k));
            let field = !item
                && rest
                    .split_once(':')
                    .is_some_and(|(name, _)| name.chars().all(|c| c.is_alphanumeric() || c == '_'));
            if !(item || field) {
                continue;
            }
            let sig = declaration(&lines, i, field);
            let ctx = if top { "" } else { container.as_str() };
            out.insert(format!("{module} | {ctx} | {sig}"));
        }
    }
    out
}

#[test]
fn the_public_api_is_the_committed_list() {
    check_listing(false, SNAPSHOT);
}

#[test]
fn the_report_trees_public_api_is_its_committed_list() {
    check_listing(true, SNAPSHOT_REPORT);
}

/// The listing of the library or of the report tree against its committed
/// file (rewritten under `SOFTROD_BLESS_API`).
fn check_listing(report: bool, snapshot: &str) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let now = listing(root, report);
    let file = root.join(snapshot);
    if std::env::var_os("SOFTROD_BLESS_API").is_some() {
        let text: String = now.iter().map(|l| format!("{l}\n")).collect();
        std::fs::write(&file, text).unwrap();
        return;
    }
    let committed: BTreeSet<String> = std::fs::read_to_string(&file)
        .unwrap_or_default()
        .lines()
        .map(str::to_owned)
        .collect();
    let added: Vec<&String> = now.difference(&committed).collect();
    let removed: Vec<&String> = committed.difference(&now).collect();
    assert!(
        added.is_empty() && removed.is_empty(),
        "the public API changed ({} added, {} removed); if deliberate, regenerate {snapshot} \
         with SOFTROD_BLESS_API=1 cargo test --release --test api_snapshot\n\
         added:\n  {}\nremoved:\n  {}",
        added.len(),
        removed.len(),
        added
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join("\n  "),
        removed
            .iter()
            .map(|s| s.as_str())
            .collect::<Vec<_>>()
            .join("\n  "),
    );
}

/// The scanner sees what it must: a new public function, a changed
/// signature and a public field change the listing; a private function
/// and test code do not.
#[test]
fn the_listing_notices_a_change() {
    let dir = std::env::temp_dir().join(format!("softrod-api-{}", std::process::id()));
    let src = dir.join("src").join("m");
    std::fs::create_dir_all(&src).unwrap();
    let write = |body: &str| {
        std::fs::write(src.join("mod.rs"), body).unwrap();
        listing(&dir, false)
    };
    let base = write(
        "pub struct A {\n    pub x_m: f64,\n    y: f64,\n}\nimpl A {\n    pub fn f(&self, a: Vec<f64>) -> f64 {\n        0.0\n    }\n    fn g() {}\n}\n#[cfg(test)]\nmod tests {\n    pub fn t() {}\n}\n",
    );
    assert_eq!(base.len(), 3, "{base:?}");
    assert!(
        base.contains("m | impl A | pub fn f(&self, a: Vec<f64>) -> f64"),
        "{base:?}"
    );
    assert!(base.contains("m | pub struct A | pub x_m: f64"), "{base:?}");
    let changed = write(
        "pub struct A {\n    pub x_m: f32,\n    y: f64,\n}\nimpl A {\n    pub fn f(&self, a: &[f64]) -> f64 {\n        0.0\n    }\n    fn g() {}\n    fn h() {}\n}\n",
    );
    assert_eq!(changed.len(), 3);
    assert_eq!(base.intersection(&changed).count(), 1, "{changed:?}");
    // the report tree is listed apart from the library
    let report = dir.join("src").join("report");
    std::fs::create_dir_all(&report).unwrap();
    std::fs::write(report.join("study.rs"), "pub fn run() {}\n").unwrap();
    assert!(!listing(&dir, false).iter().any(|l| l.starts_with("report")));
    assert_eq!(
        listing(&dir, true).into_iter().collect::<Vec<_>>(),
        ["report::study |  | pub fn run()"]
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
