//! Shared helpers of the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// Path of a file in the shared real-data folder: `$CLIFFMAP_SHARED_DATA/rel` if set, else
/// `<repo>/../shared/data/real/rel` (as in CI), else `/work/shared/data/real/rel`.
/// Panics (fails the test) if the file does not exist: real-data tests never skip.
pub fn real_data(rel: &str) -> PathBuf {
    let candidates = [
        std::env::var_os("CLIFFMAP_SHARED_DATA").map(PathBuf::from),
        Some(PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/real"))),
        Some(PathBuf::from("/work/shared/data/real")),
    ];
    for base in candidates.into_iter().flatten() {
        let p = base.join(rel);
        if p.exists() {
            return p;
        }
    }
    panic!("real test data {rel} not found (set CLIFFMAP_SHARED_DATA to the shared/data/real folder)");
}
