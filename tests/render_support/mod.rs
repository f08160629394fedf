//! Hand-built cell stores for the renderer tests: a full quadtree over a square at UTM
//! magnitudes, flat or tilted, written with the store API.

#![allow(dead_code)]

use std::path::Path;

use cliffmap::cells::CellMesh;
use cliffmap::cells::{CellKey, Quadtree, SampleRect};
use cliffmap::georef::{GridGeoref, WorldRect};
use cliffmap::store::{
    CellFiles, CellRecord, DemInfo, FileRef, Manifest, Parameterization, STORE_FORMAT,
    STORE_VERSION, cell_stem, write_file,
};

/// World x of the root's west edge.
pub const X0: f64 = 500_000.0;
/// World y of the root's north edge.
pub const Y0: f64 = 7_000_000.0;

/// Shape of a synthetic store.
#[derive(Clone, Copy, Debug)]
pub struct Synth {
    /// Levels (root = 0).
    pub levels: u8,
    /// Root side, metres.
    pub size: f64,
    /// Height of the flat plane, metres.
    pub z: f64,
    /// Finest-level geometric error, metres (doubles per coarser level).
    pub finest_error: f64,
    /// Texture side in texels.
    pub texels: u32,
}

/// Grid intervals per finest cell in the synthetic quadtree.
pub const S: u32 = 8;

fn file(path: String) -> FileRef {
    FileRef {
        path,
        bytes: 0,
        crc32: "00000000".into(),
    }
}

/// The record of `key` (files not written: sizes/checksums zero).
pub fn record(s: &Synth, key: CellKey) -> CellRecord {
    let side = s.size / (1u64 << key.level) as f64;
    let (min_x, max_y) = (X0 + key.x as f64 * side, Y0 - key.y as f64 * side);
    let extent = WorldRect {
        min_x,
        min_y: max_y - side,
        max_x: min_x + side,
        max_y,
    };
    let n = S << (s.levels - 1 - key.level);
    let stem = cell_stem(key.level, key.x, key.y);
    CellRecord {
        id: key.id(),
        level: key.level,
        x: key.x,
        y: key.y,
        rect: SampleRect {
            c0: key.x * n,
            r0: key.y * n,
            c1: (key.x + 1) * n,
            r1: (key.y + 1) * n,
        },
        origin: [min_x + side / 2.0, max_y - side / 2.0, s.z.round()],
        extent,
        bbox_min: [extent.min_x, extent.min_y, s.z],
        bbox_max: [extent.max_x, extent.max_y, s.z],
        epsilon: s.finest_error * (1u64 << (s.levels - 1 - key.level)) as f64,
        max_error: s.finest_error * (1u64 << (s.levels - 1 - key.level)) as f64,
        vertices: 4,
        triangles: 2,
        skirt_depth: 1.0,
        parameterization: Parameterization::Ortho,
        texels: s.texels,
        files: CellFiles {
            mesh: file(format!("{stem}.mesh")),
            texture: file(format!("{stem}.png")),
            normal: file(format!("{stem}.normal.png")),
        },
        stats: Default::default(),
        reparam: None,
        photo: None,
        relief: None,
    }
}

/// All records of a full quadtree, root first, row-major within a level.
pub fn records(s: &Synth) -> Vec<CellRecord> {
    let mut out = Vec::new();
    for level in 0..s.levels {
        for y in 0..1u32 << level {
            for x in 0..1u32 << level {
                out.push(record(s, CellKey { level, x, y }));
            }
        }
    }
    out
}

/// A flat cell mesh (two triangles over the nominal square plus a skirt) in the cell-local frame.
pub fn flat_mesh(rec: &CellRecord, uvs: bool) -> CellMesh {
    let e = rec.extent;
    let o = rec.origin;
    let z = (rec.bbox_min[2] - o[2]) as f32;
    let corners = [
        [e.min_x, e.max_y],
        [e.max_x, e.max_y],
        [e.max_x, e.min_y],
        [e.min_x, e.min_y],
    ];
    let mut positions: Vec<[f32; 3]> = corners
        .iter()
        .map(|c| [(c[0] - o[0]) as f32, (c[1] - o[1]) as f32, z])
        .collect();
    let mut triangles = vec![[0, 3, 2], [0, 2, 1]];
    let d = rec.skirt_depth as f32;
    for i in 0..4u32 {
        let p = positions[i as usize];
        positions.push([p[0], p[1], p[2] - d]);
    }
    for i in 0..4u32 {
        let j = (i + 1) % 4;
        triangles.push([i, j, 4 + j]);
        triangles.push([i, 4 + j, 4 + i]);
    }
    let uv = uvs.then(|| {
        positions
            .iter()
            .map(|p| {
                let x = p[0] as f64 + o[0];
                let y = p[1] as f64 + o[1];
                [
                    ((x - e.min_x) / e.width()) as f32,
                    ((e.max_y - y) / e.height()) as f32,
                ]
            })
            .collect()
    });
    CellMesh {
        positions,
        uvs: uv,
        triangles,
        surface_vertices: 4,
        surface_triangles: 2,
    }
}

/// Writes a complete store to `dir`: every cell flat, textured with `colour(record)` (uniform
/// RGBA) and an upward normal map; `reparam(record)` selects cells stored with explicit UVs.
pub fn write_store(
    dir: &Path,
    s: &Synth,
    colour: impl Fn(&CellRecord) -> [u8; 4],
    reparam: impl Fn(&CellRecord) -> bool,
) -> Manifest {
    write_store_textured(
        dir,
        s,
        |rec| image::RgbaImage::from_pixel(s.texels, s.texels, image::Rgba(colour(rec))),
        reparam,
    )
}

/// Like [`write_store`], with each cell's texture (`s.texels` square, u east, v south over the
/// cell's nominal square) from `texture(record)`.
pub fn write_store_textured(
    dir: &Path,
    s: &Synth,
    texture: impl Fn(&CellRecord) -> image::RgbaImage,
    reparam: impl Fn(&CellRecord) -> bool,
) -> Manifest {
    let mut cells = records(s);
    for rec in &mut cells {
        let rp = reparam(rec);
        rec.parameterization = if rp {
            Parameterization::Reparam
        } else {
            Parameterization::Ortho
        };
        let mesh = flat_mesh(rec, rp);
        let stem = cell_stem(rec.level, rec.x, rec.y);
        let tex = texture(rec);
        let nrm = image::RgbImage::from_pixel(s.texels, s.texels, image::Rgb([128, 128, 255]));
        let png = |img: &dyn Fn(&mut std::io::Cursor<Vec<u8>>)| {
            let mut c = std::io::Cursor::new(Vec::new());
            img(&mut c);
            c.into_inner()
        };
        let tex_bytes = png(&|c| tex.write_to(c, image::ImageFormat::Png).unwrap());
        let nrm_bytes = png(&|c| nrm.write_to(c, image::ImageFormat::Png).unwrap());
        rec.files.mesh = write_file(dir, &format!("{stem}.mesh"), &mesh.to_bytes()).unwrap();
        rec.files.texture = write_file(dir, &format!("{stem}.png"), &tex_bytes).unwrap();
        rec.files.normal = write_file(dir, &format!("{stem}.normal.png"), &nrm_bytes).unwrap();
    }
    let n = S << (s.levels - 1);
    let spacing = s.size / n as f64;
    let m = Manifest {
        format: STORE_FORMAT.into(),
        version: STORE_VERSION,
        generator: "render test".into(),
        crs: None,
        georef: GridGeoref {
            origin_x: X0,
            origin_y: Y0,
            spacing_x: spacing,
            spacing_y: spacing,
        },
        dem: DemInfo {
            source: "synthetic".into(),
            width: n + 1,
            height: n + 1,
            height_min: s.z,
            height_max: s.z,
            void_fraction: 0.0,
        },
        ortho: None,
        ortho_spacing: None,
        quadtree: Quadtree {
            dem_width: n + 1,
            dem_height: n + 1,
            finest_intervals: S,
            levels: s.levels,
        },
        max_error: s.finest_error,
        cell_texels: s.texels,
        reparam: None,
        photos: None,
        build_key: "00000000".into(),
        cells,
        content_crc32: None,
    };
    let text = serde_json::to_string_pretty(&m).unwrap();
    cliffmap::fsutil::write_atomic(&dir.join("manifest.json"), text.as_bytes()).unwrap();
    m
}
