//! Shared helpers for integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// Path of a file under the shared real-data directory: `$CLIFFMAP_SHARED_DATA` if set,
/// else `$CARGO_MANIFEST_DIR/../shared/data/real`, else `/work/shared/data/real`.
/// Panics (loudly) if the file does not exist: tests using real data never skip.
pub fn real_data(rel: &str) -> PathBuf {
    let candidates: Vec<PathBuf> = match std::env::var_os("CLIFFMAP_SHARED_DATA") {
        Some(d) => vec![PathBuf::from(d)],
        None => vec![
            PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/real")),
            PathBuf::from("/work/shared/data/real"),
        ],
    };
    for d in &candidates {
        let p = d.join(rel);
        if p.exists() {
            return p;
        }
    }
    panic!("real test data {rel} not found in {candidates:?} (set CLIFFMAP_SHARED_DATA)");
}
