//! Export of a store's cells to glTF for other viewers (docs/export.md).
//!
//! Data types: [`CellSelection`] (which cells: a level, an error bound, a region) and
//! [`select_cells`]; [`ExportCell`] (one cell's world positions in f64, texture coordinates,
//! surface and skirt triangles, its best texture's bytes as stored: photo, else
//! reparameterized, else ortho) read by [`read_export_cell`]; [`write_glb`] writes cells as
//! one GLB in a caller-given local frame; [`export_glb`] is `cliffmap export-glb`: the chosen
//! cells in a y-up frame around an f64 origin recorded in the file's `extras`.
//! [`export_tiles`] is `cliffmap export-tiles`: a 3D Tiles 1.1 tileset (one GLB per cell,
//! explicit quadtree, positions through ECEF by [`ToEcef`] into an east-north-up frame).

mod cells;
mod ecef;
mod geoid;
mod glb;
pub mod metadata;
pub mod normals;
mod tiles;

use std::path::Path;

use glam::DVec3;
use rayon::prelude::*;
use serde_json::json;

pub use cells::{
    CellSelection, ExportCell, TextureSource, read_export_cell, read_export_cell_as,
    read_export_positions, select_cells,
};
pub use ecef::{ToEcef, ecef_to_enu, proj_string};
pub use geoid::GeoidGrid;
pub use glb::write_glb;
pub use tiles::{
    EXPORT_KEY_FILE, TilesOptions, TilesReport, export_tiles, tile_path, tile_path_for,
    tileset_name,
};

use crate::error::Result;
use crate::store::Store;

/// Variants of [`export_glb`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GlbOptions {
    /// Lit materials ([`ExportCell::make_lit`]) instead of unlit ones.
    pub lit: bool,
    /// Per-texel stretch and photo share as `EXT_structural_metadata` property textures
    /// ([`ExportCell::make_metadata`]).
    pub metadata: bool,
}

/// What [`export_glb`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct GlbReport {
    /// Cells written.
    pub cells: usize,
    /// Surface triangles written.
    pub triangles: usize,
    /// The frame's origin (world metres, the store's CRS).
    pub origin: DVec3,
    /// Cells per texture source: photo, reparam, ortho.
    pub textures: [usize; 3],
    /// Bytes written.
    pub bytes: u64,
}

/// The glTF frame of [`export_glb`]: x east, y up, z south (glTF's y-up, right-handed),
/// metres from `origin`.
pub fn local_y_up(origin: DVec3, p: DVec3) -> [f64; 3] {
    let d = p - origin;
    [d.x, d.z, -d.y]
}

/// Writes the cells `sel` picks from the store in `dir` as one GLB at `out` (atomically):
/// positions in [`local_y_up`] around the centre of the cells' bounding box (rounded to the
/// metre), and in the glTF's `extras`: `{"cliffmap": {"crs", "origin", "axes", "cells",
/// "level"}}`; options: the lit variant and per-texel metadata ([`GlbOptions`]).
pub fn export_glb(
    dir: &Path,
    sel: &CellSelection,
    out: &Path,
    opts: &GlbOptions,
) -> Result<GlbReport> {
    let store = Store::open(dir)?;
    let picked = select_cells(&store, sel)?;
    let cells: Vec<ExportCell> = picked
        .par_iter()
        .map(|&i| {
            let rec = &store.manifest.cells[i];
            let mut c = read_export_cell(&store, rec)?;
            if opts.lit {
                c.make_lit(&store)?;
            }
            if opts.metadata {
                c.make_metadata(&store, rec, TextureSource::Photo)?;
            }
            Ok(c)
        })
        .collect::<Result<_>>()?;
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for &i in &picked {
        let c = &store.manifest.cells[i];
        lo = lo.min(DVec3::from_array(c.bbox_min));
        hi = hi.max(DVec3::from_array(c.bbox_max));
    }
    let origin = ((lo + hi) * 0.5).round();
    let level = store.manifest.cells[picked[0]].level;
    let extras = json!({ "cliffmap": {
        "crs": store.manifest.crs,
        "origin": [origin.x, origin.y, origin.z],
        "axes": "x east, y up, z south (metres from origin, in the store's CRS)",
        "level": level,
        "cells": cells.iter().map(|c| json!({"id": c.id, "texture": c.texture.name(), "max_error_m": c.max_error})).collect::<Vec<_>>(),
    }});
    let bytes = write_glb(
        &cells,
        &|c, v| local_y_up(origin, cells[c].positions[v]),
        &extras,
    )?;
    crate::fsutil::write_atomic(out, &bytes)?;
    let mut textures = [0usize; 3];
    for c in &cells {
        textures[c.texture.index()] += 1;
    }
    Ok(GlbReport {
        cells: cells.len(),
        triangles: cells.iter().map(|c| c.surface.len()).sum(),
        origin,
        textures,
        bytes: bytes.len() as u64,
    })
}
