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
        if dir.is_dir() {
            let p = dir.join(rel);
            assert!(p.exists(), "real test data {} is missing", p.display());
            return p;
        }
    }
    panic!("real test data directory not found (set CLIFFMAP_SHARED_DATA); needed {rel}");
}

use cliffmap::{Dem, GridGeoref, Ortho, SampleRect, Tin};

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

/// The Engabreen DEM (507 x 590 at 3 m, UTM 33N), read directly from the raw f32 file.
pub fn engabreen_dem() -> Dem {
    let p = real_data("engabreen/engabreen_dem_3m_507x590.f32");
    let bytes = std::fs::read(&p).unwrap();
    assert_eq!(bytes.len(), 507 * 590 * 4);
    let z = bytes.chunks_exact(4).map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]])).collect();
    Dem::from_heights(507, 590, z, GridGeoref::new(445302.17, 7396769.45, 3.0)).unwrap()
}

/// The Engabreen ortho on the DEM grid; pure black pixels (the wedge without image data)
/// get alpha 0.
pub fn engabreen_ortho(dem: &Dem) -> Ortho {
    let p = real_data("engabreen/engabreen_ortho_3m_507x590.png");
    let rgb = image::open(&p).unwrap().to_rgb8();
    let image = image::RgbaImage::from_fn(rgb.width(), rgb.height(), |c, r| {
        let [a, b, d] = rgb.get_pixel(c, r).0;
        image::Rgba([a, b, d, if [a, b, d] == [0, 0, 0] { 0 } else { 255 }])
    });
    Ortho { image, georef: dem.georef }
}
