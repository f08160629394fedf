//! Shared helpers for integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// Path of a file in the shared real-data directory: `$CLIFFMAP_SHARED_DATA` if set, else
/// `$CARGO_MANIFEST_DIR/../shared/data/real`, else `/work/shared/data/real`. Panics (the test
/// fails loudly) if the file does not exist.
pub fn real_data(rel: &str) -> PathBuf {
    let candidates = [
        std::env::var_os("CLIFFMAP_SHARED_DATA").map(PathBuf::from),
        Some(PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/real"))),
        Some(PathBuf::from("/work/shared/data/real")),
    ];
    for dir in candidates.into_iter().flatten() {
        let p = dir.join(rel);
        if p.exists() {
            return p;
        }
    }
    panic!("real test data {rel} not found (set CLIFFMAP_SHARED_DATA to the shared/data/real directory)");
}
