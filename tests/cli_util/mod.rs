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

/// Runs the Khronos glTF validator (tools/js, installed by `.ci/run` with `npm ci --prefix
/// tools/js`) on `files` and fails the test unless every file has 0 errors. Fails, saying
/// how to install it, when the validator is missing.
pub fn validate_gltf(files: &[&std::path::Path]) {
    let tools = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/js");
    assert!(
        tools.join("node_modules/gltf-validator").exists(),
        "the glTF validator is not installed: run `npm ci --prefix tools/js` (as .ci/run does)"
    );
    let o = Command::new("node").arg(tools.join("validate_gltf.mjs")).args(files).output().expect("cannot start node");
    assert!(o.status.success(), "glTF validation failed:\n{}{}", String::from_utf8_lossy(&o.stdout), String::from_utf8_lossy(&o.stderr));
}
