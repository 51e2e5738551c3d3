//! Helpers shared by the end-to-end tests of the `isomorph` binary.

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs the binary with `args`.
pub fn isomorph(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_isomorph")).args(args).output().expect("the binary runs")
}

/// A fresh (removed) path in the temporary folder, unique to this process.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("isomorph-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}
