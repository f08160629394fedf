//! Running the `cliffmap` binary from integration tests (not for examples: the binary's
//! path is only known to integration tests).
#![allow(dead_code)]

use std::process::{Command, Output};

/// Runs the `cliffmap` binary with `args`.
pub fn cliffmap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cliffmap")).args(args).output().expect("cannot start cliffmap")
}

/// Runs `cliffmap` and fails the test (printing its output) unless it succeeds.
pub fn ok(args: &[&str]) -> Output {
    let o = cliffmap(args);
    assert!(
        o.status.success(),
        "cliffmap {args:?} failed:\nstdout: {}\nstderr: {}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// Runs `cliffmap` and fails the test unless it fails, without a panic, naming `needle`.
pub fn fails_naming(args: &[&str], needle: &str) {
    let o = cliffmap(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success(), "cliffmap {args:?} should fail");
    assert!(err.contains(needle), "error of {args:?} should name {needle:?}: {err}");
    assert!(!err.contains("panicked"), "cliffmap {args:?} panicked: {err}");
}
