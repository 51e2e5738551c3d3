//! Helpers shared by the end-to-end tests of the `isomorph` binary.

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs the binary with `args`.
pub fn isomorph(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_isomorph")).args(args).output().expect("the binary runs")
}

/// Runs `isomorph morph --method METHOD --source SOURCE --target TARGET`
/// followed by `extra`.
#[allow(dead_code, reason = "not every test file morphs")]
pub fn morph(method: &str, source: &str, target: &str, extra: &[&str]) -> Output {
    isomorph(&[&["morph", "--method", method, "--source", source, "--target", target], extra].concat())
}

/// Panics with the command's standard error unless it succeeded.
#[track_caller]
#[allow(dead_code, reason = "not every test file runs successful commands")]
pub fn assert_ok(o: &Output) {
    assert!(o.status.success(), "{}", stderr(o));
}

/// The command's standard error as text.
#[allow(dead_code, reason = "not every test file reads the error text")]
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A fresh (removed) path in the temporary folder, unique to this process.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("isomorph-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The JSON file at `path` (a `report.json`), parsed.
#[allow(dead_code, reason = "not every test file reads reports")]
pub fn read_json(path: impl AsRef<std::path::Path>) -> serde_json::Value {
    let path = path.as_ref();
    let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("cannot read {}: {e}", path.display()));
    serde_json::from_slice(&bytes).unwrap_or_else(|e| panic!("{} is not JSON: {e}", path.display()))
}
