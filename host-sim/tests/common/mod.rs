//! What the command-line tests share: running `host-sim` as a user does, reading what it printed,
//! the shipped scenes and a scratch directory per test.

// Each test file uses some of these.
#![allow(dead_code)]

use std::path::PathBuf;
use std::process::{Command, Output};

/// Runs `host-sim` with `args`.
pub fn host_sim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_host-sim"))
        .args(args)
        .output()
        .expect("host-sim runs")
}

/// What it printed on standard output.
pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// What it printed on standard error.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Its exit code, after checking it did not panic, abort an allocation or die of a signal.
pub fn code(o: &Output) -> i32 {
    let err = stderr(o);
    assert!(
        !err.contains("panicked")
            && !err.contains("backtrace")
            && !err.contains("memory allocation"),
        "{err}"
    );
    o.status
        .code()
        .unwrap_or_else(|| panic!("killed by a signal: {err}"))
}

/// The path of a shipped scene (`host-sim/scenes/`).
pub fn scene(name: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
        .display()
        .to_string()
}

/// An empty scratch directory for `name` (each test binary is its own process: the process id
/// keeps them apart).
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("host-sim-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// `text` written as `scene.toml` in the scratch directory of `name`; its path.
pub fn write_scene(name: &str, text: &str) -> String {
    let path = temp_dir(name).join("scene.toml");
    std::fs::write(&path, text).expect("scene written");
    path.display().to_string()
}
