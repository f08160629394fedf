//! Running the `cliffmap` binary from integration tests (not for examples: the binary's
//! path is only known to integration tests).
#![allow(dead_code)]

use std::process::{Command, Output};

/// Runs the `cliffmap` binary with `args`.
pub fn cliffmap(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_cliffmap"))
        .args(args)
        .output()
        .expect("cannot start cliffmap")
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
    assert!(
        err.contains(needle),
        "error of {args:?} should name {needle:?}: {err}"
    );
    assert!(
        !err.contains("panicked"),
        "cliffmap {args:?} panicked: {err}"
    );
}

/// Runs `tools/validate/validate.mjs` (the Khronos glTF validator and the 3D Tiles 1.1 JSON
/// schemas; installed by `.ci/run` with `npm ci --prefix tools/validate`) on `paths` (glTF
/// files, tileset JSON files or directories) and returns its exit code and its JSON summary
/// (`{"tools", "files": [{"file", "kind", "numErrors", "numWarnings", "numInfos", "numHints",
/// "issues": {CODE: {"severity", "count"}}, "messages"}], "totals"}`). Fails, saying how to
/// install it, when the validator is missing.
pub fn validate_export(paths: &[&std::path::Path]) -> (i32, serde_json::Value) {
    let tools = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tools/validate");
    assert!(
        tools.join("node_modules/gltf-validator").exists()
            && tools.join("node_modules/ajv").exists(),
        "the validators are not installed: run `npm ci --prefix tools/validate` (as .ci/run does)"
    );
    let o = Command::new("node")
        .arg(tools.join("validate.mjs"))
        .args(paths)
        .output()
        .expect("cannot start node (.ci/run installs it)");
    let summary = serde_json::from_slice(&o.stdout).unwrap_or_else(|e| {
        panic!(
            "validate.mjs gave no JSON summary ({e}):\n{}{}",
            String::from_utf8_lossy(&o.stdout),
            String::from_utf8_lossy(&o.stderr)
        )
    });
    (o.status.code().unwrap_or(-1), summary)
}

/// Validates glTF `files` with the Khronos glTF validator ([`validate_export`]) and fails
/// the test unless every file has 0 errors and 0 warnings.
pub fn validate_gltf(files: &[&std::path::Path]) {
    let (code, summary) = validate_export(files);
    let t = &summary["totals"];
    assert!(
        code == 0 && t["numErrors"] == 0 && t["numWarnings"] == 0 && t["gltf"] == files.len(),
        "glTF validation failed (exit {code}):\n{summary:#}"
    );
}

/// A path as `&str` for argument lists.
pub fn s(p: &std::path::Path) -> &str {
    p.to_str().expect("test paths are UTF-8")
}

/// Every file under `dir` (recursively), sorted.
pub fn files_under(dir: &std::path::Path) -> Vec<std::path::PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).expect("readable test directory") {
            let p = e.expect("readable entry").path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p);
            }
        }
    }
    out.sort();
    out
}

/// The small cliff DEM of the store tests: 129 x 129 raw f32 at 2 m with a 60 m cliff and
/// some relief (its store is ≈ 0.95 MB, 1.6 MB after `reparam`).
pub fn write_cliff_dem(path: &std::path::Path) {
    let n = 129;
    let mut bytes = Vec::with_capacity(n * n * 4);
    for r in 0..n {
        for c in 0..n {
            let (x, y) = (c as f32, r as f32);
            let cliff = if x + 0.3 * y > 70.0 { 60.0 } else { 0.0 };
            let z = 100.0 + cliff + 3.0 * (0.11 * x).sin() * (0.07 * y).cos() + 0.05 * y;
            bytes.extend_from_slice(&z.to_le_bytes());
        }
    }
    std::fs::write(path, bytes).expect("writable temp dir");
}

/// `cliffmap build` arguments for [`write_cliff_dem`]'s DEM into `out`.
pub fn cliff_build_args<'a>(dem: &'a std::path::Path, out: &'a std::path::Path) -> Vec<&'a str> {
    vec![
        "build",
        "--dem",
        s(dem),
        "--width",
        "129",
        "--height",
        "129",
        "--spacing",
        "2",
        "--cell-intervals",
        "32",
        "--quiet",
        "--out",
        s(out),
    ]
}
