//! The `softrod` binary run from the crate's root, for the tests of the
//! command line (`#[path = "common/cli.rs"] mod cli;` in each; they need
//! feature `cli`, which builds the binary).
#![allow(dead_code, clippy::unwrap_used)]

use std::process::Command;

/// Exit code, standard output and standard error of `softrod ARGS`.
pub fn softrod(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_softrod"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}
