//! Helpers shared by the parameterization benchmarks (included with `#[path]`).
#![allow(dead_code)]

use std::io::Write;
use std::path::{Path, PathBuf};

use cliffmap::ParamMesh;

/// Path of a file in the shared real-data folder: `$CLIFFMAP_SHARED_DATA/rel`, else
/// `<repo>/../shared/data/real/rel`, else `/work/shared/data/real/rel`.
pub fn shared_data(rel: &str) -> PathBuf {
    if let Some(d) = std::env::var_os("CLIFFMAP_SHARED_DATA") {
        return PathBuf::from(d).join(rel);
    }
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/real")).join(rel);
    if p.exists() { p } else { PathBuf::from("/work/shared/data/real").join(rel) }
}

/// Writes `m` with texture coordinates `uvs` as OBJ (`v`, `vt`, `f v/vt`).
pub fn write_obj(path: &Path, m: &ParamMesh, uvs: &[[f64; 2]]) -> std::io::Result<()> {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path)?);
    for p in &m.positions {
        writeln!(f, "v {:.6} {:.6} {:.6}", p[0], p[1], p[2])?;
    }
    for uv in uvs {
        writeln!(f, "vt {:.9} {:.9}", uv[0], uv[1])?;
    }
    for t in &m.triangles {
        writeln!(f, "f {}/{} {}/{} {}/{}", t[0] + 1, t[0] + 1, t[1] + 1, t[1] + 1, t[2] + 1, t[2] + 1)?;
    }
    f.flush()
}

/// Median of `v` (mean of the two middle values for an even count).
pub fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 { v[n / 2] } else { 0.5 * (v[n / 2 - 1] + v[n / 2]) }
}
