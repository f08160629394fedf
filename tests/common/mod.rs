//! Shared helpers for integration tests.
#![allow(dead_code)]

pub mod tiffgen;

use std::path::PathBuf;

/// Path of a file in the shared real-data directory: `$CLIFFMAP_SHARED_DATA`, else
/// `$CARGO_MANIFEST_DIR/../shared/data/real`, else `/work/shared/data/real`. Panics (so the
/// test fails loudly) if the file does not exist.
pub fn real_data(rel: &str) -> PathBuf {
    let candidates = [
        std::env::var_os("CLIFFMAP_SHARED_DATA").map(PathBuf::from),
        Some(PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/real"))),
        Some(PathBuf::from("/work/shared/data/real")),
    ];
    for dir in candidates.into_iter().flatten() {
        if dir.is_dir() {
            let p = dir.join(rel);
            assert!(p.exists(), "real data file {} is missing", p.display());
            return p;
        }
    }
    panic!("real data directory not found (set CLIFFMAP_SHARED_DATA)");
}

use cliffmap::{Dem, DemLoadOptions, Ortho, OrthoPlacement, SampleRect, Tin};

/// A full grid triangulation of `rect` on every `stride`-th sample (plus the last row and
/// column), two triangles per quad split NW–SE, CCW seen from above in world coordinates.
pub fn grid_tin(rect: SampleRect, stride: u32) -> Tin {
    let axis = |a: u32, b: u32| {
        let mut v: Vec<u32> = (a..b).step_by(stride as usize).collect();
        v.push(b);
        v
    };
    let (cols, rows) = (axis(rect.c0, rect.c1), axis(rect.r0, rect.r1));
    let nc = cols.len() as u32;
    let vertices = rows.iter().flat_map(|&r| cols.iter().map(move |&c| [c, r])).collect();
    let mut triangles = Vec::new();
    for j in 0..rows.len() as u32 - 1 {
        for i in 0..nc - 1 {
            let (nw, ne, sw, se) = (j * nc + i, j * nc + i + 1, (j + 1) * nc + i, (j + 1) * nc + i + 1);
            triangles.push([nw, sw, se]);
            triangles.push([nw, se, ne]);
        }
    }
    Tin { vertices, triangles, max_error: 0.0 }
}

/// The Engabreen DEM (507 x 590 at 3 m, UTM 33N) through the raw f32 reader.
pub fn engabreen_dem() -> Dem {
    let opts = DemLoadOptions {
        width: Some(507),
        height: Some(590),
        spacing: Some(3.0),
        origin: Some((445302.17, 7396769.45)),
        ..Default::default()
    };
    cliffmap::load_dem(&real_data("engabreen/engabreen_dem_3m_507x590.f32"), &opts).unwrap()
}

/// The Engabreen ortho on the DEM grid; pure black pixels (the wedge without image data)
/// get alpha 0, as `--ortho-nodata-colour 0,0,0` does on the command line.
pub fn engabreen_ortho(dem: &Dem) -> Ortho {
    let p = real_data("engabreen/engabreen_ortho_3m_507x590.png");
    let mut o = cliffmap::load_ortho(&p, OrthoPlacement::SameGridAsDem, dem, 1 << 30).unwrap();
    for px in o.image.pixels_mut() {
        if px.0[..3] == [0, 0, 0] {
            px.0[3] = 0;
        }
    }
    o
}
