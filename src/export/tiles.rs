//! A 3D Tiles 1.1 tileset of the store's quadtree: one GLB per cell, an explicit tree in
//! `tileset.json`, `refine: REPLACE`, box bounding volumes in an east-north-up frame whose
//! `transform` (on the root) places it in ECEF.

use std::path::Path;

use glam::{DMat3, DVec3};
use rayon::prelude::*;
use serde_json::{Value, json};

use super::ecef::{ToEcef, ecef_to_enu};
use super::{ExportCell, TextureSource, read_export_cell_as, read_export_positions, write_glb};
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use crate::store::Store;

/// Options of [`export_tiles`].
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TilesOptions {
    /// The store's CRS (`EPSG:CODE` or a PROJ string) when its manifest has none, or to
    /// override it.
    pub crs: Option<String>,
    /// Geoid height (metres) added to the store's (orthometric) heights to make them
    /// ellipsoidal; `None`: the heights are written as they are.
    pub geoid_offset: Option<f64>,
    /// A geoid height grid (GeoTIFF in longitude/latitude, [`super::GeoidGrid`]) whose
    /// bilinear value at each vertex is added instead of a constant; excludes
    /// `geoid_offset`.
    pub geoid_grid: Option<std::path::PathBuf>,
    /// Texture modes exported besides the best texture (`tileset.json`, `tiles/`): each as
    /// `tileset_MODE.json` + `tiles_MODE/` ([`tileset_name`], [`tile_path_for`]), listed in
    /// every tileset's `asset.extras.cliffmap.modes` for the page's toggle.
    pub extra_modes: Vec<TextureSource>,
    /// Embed colour textures as JPEG of this quality (1..=100) instead of the store's PNG
    /// bytes (smaller tiles for the web; alpha is not shown by the opaque materials).
    pub jpeg_quality: Option<u8>,
    /// The lit variant: materials shaded by the cells' normal maps in tangent space, with
    /// `NORMAL` and `TANGENT` attributes ([`super::ExportCell::make_lit`]), instead of
    /// `KHR_materials_unlit`.
    pub lit: bool,
    /// Per-texel stretch and photo share as `EXT_structural_metadata` property textures
    /// ([`super::ExportCell::make_metadata`]).
    pub metadata: bool,
    /// External child tilesets: the subtree under every cell whose level is a positive
    /// multiple of `n` is written as its own tileset (`subtrees/LEVEL/X-Y.json`,
    /// `subtree_path_for`) and referenced from its parent, so no tileset file lists more
    /// than `n` levels. `None`: every 4 levels when the store has more than
    /// `SUBTREE_AUTO_CELLS` cells, else one file; `Some(0)`: one file.
    pub subtree_levels: Option<u8>,
    /// Where progress is reported (default: nowhere).
    pub progress: crate::progress::ProgressSink,
    /// Cameras (name, camera in the store's CRS) written as `views/NAME.json` for the page's
    /// `?camera=` (ECEF position, direction and up, the field of view of the larger side).
    pub views: Vec<(String, crate::camera::CameraModel)>,
}

/// Above this many cells a tileset is split into external child tilesets every 4 levels
/// by default ([`TilesOptions::subtree_levels`]); a 4097² DEM's store has 5 461.
pub const SUBTREE_AUTO_CELLS: usize = 2000;

/// What [`export_tiles`] wrote.
#[derive(Clone, Debug, PartialEq)]
pub struct TilesReport {
    /// Tiles with content (one per cell).
    pub tiles: usize,
    /// Cells left out of the tree because their parent's children do not cover it (the
    /// parent is drawn instead, so no hole appears).
    pub pruned: usize,
    /// Cells per texture source: photo, reparam, ortho.
    pub textures: [usize; 3],
    /// Bytes of GLB written.
    pub bytes: u64,
    /// External child tilesets written (per texture mode).
    pub subtrees: usize,
    /// How heights were made ellipsoidal.
    pub heights: String,
    /// GLBs kept from an earlier, interrupted run of the same export (all modes).
    pub resumed: usize,
}

/// The file in the output folder that records what an export writes (the store's manifest
/// checksum and every option that changes a file), so that a rerun of the same export
/// resumes: GLBs already there are kept.
pub const EXPORT_KEY_FILE: &str = ".cliffmap-export.json";

/// Writes `out/tileset.json` and `out/tiles/LEVEL/X-Y.glb` for every cell of the store in
/// `dir` (module docs). Positions are transformed vertex by vertex in f64 to ECEF and then
/// to the root's east-north-up frame (at the centre of the store, f32 in the GLBs, glTF
/// y-up: x east, y up, z south). A tile's `geometricError` is its cell's error (metres); a
/// cell's children are listed only when together they cover its whole footprint (the x-y
/// bounds of its mesh), so REPLACE refinement leaves no hole. Every file is written atomically, `tileset.json` last.
pub fn export_tiles(dir: &Path, out: &Path, opts: &TilesOptions) -> Result<TilesReport> {
    let store = Store::open(dir)?;
    let crs = opts
        .crs
        .clone()
        .or_else(|| store.manifest.crs.clone())
        .ok_or_else(|| {
            Error::BadOption(format!(
                "store {} records no CRS: give it with --crs EPSG:CODE",
                dir.display()
            ))
        })?;
    let to_ecef = match (&opts.geoid_grid, opts.geoid_offset) {
        (Some(_), Some(_)) => {
            return Err(Error::BadOption(
                "give either a geoid offset or a geoid grid, not both".into(),
            ));
        }
        (Some(path), None) => ToEcef::with_geoid(&crs, super::GeoidGrid::read(path)?)?,
        (None, m) => ToEcef::new(&crs, m.unwrap_or(0.0))?,
    };
    let cells = &store.manifest.cells;
    if cells.is_empty() {
        return Err(Error::store(
            dir.join("manifest.json"),
            "the store has no cells",
        ));
    }
    // Frame: ENU at the centre of the store's bounding box.
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for c in cells {
        lo = lo.min(DVec3::from_array(c.bbox_min));
        hi = hi.max(DVec3::from_array(c.bbox_max));
    }
    let centre = to_ecef.to_ecef((lo + hi) * 0.5)?;
    let rot = ecef_to_enu(centre);
    let to_enu = |p: DVec3| -> Result<DVec3> { Ok(rot * (to_ecef.to_ecef(p)? - centre)) };

    // Heights report (the extent's corners and centre for a grid).
    let heights = match (&opts.geoid_grid, opts.geoid_offset) {
        (Some(path), _) => {
            let (mut n0, mut n1) = (f64::INFINITY, f64::NEG_INFINITY);
            for x in [lo.x, (lo.x + hi.x) * 0.5, hi.x] {
                for y in [lo.y, (lo.y + hi.y) * 0.5, hi.y] {
                    let n = to_ecef.geoid_height(DVec3::new(x, y, 0.0))?;
                    (n0, n1) = (n0.min(n), n1.max(n));
                }
            }
            format!(
                "store heights + geoid grid {} (bilinear per vertex; N {n0:.2}..{n1:.2} m over the store's extent) (ellipsoidal, WGS 84)",
                path.display()
            )
        }
        (None, Some(m)) => format!("store heights + constant geoid offset {m} m (ellipsoidal, WGS 84)"),
        (None, None) => "store heights written as they are (taken as ellipsoidal; give --geoid-offset or --geoid for orthometric heights)".to_string(),
    };

    let mut modes = vec![TextureSource::Photo];
    for m in &opts.extra_modes {
        if !modes.contains(m) {
            modes.push(*m);
        }
    }
    let listing: Vec<Value> = modes
        .iter()
        .map(|&m| json!({"mode": m.name(), "tileset": tileset_name(m)}))
        .collect();
    // Resuming: the same store and options as the run that left the folder; otherwise the
    // earlier run's outputs are removed before anything is written.
    let subtree_levels = match opts.subtree_levels {
        Some(n) => n,
        None if store.manifest.cells.len() > SUBTREE_AUTO_CELLS => 4,
        None => 0,
    };
    let key = json!({
        "format": "cliffmap-export-tiles",
        "generator": format!("cliffmap {}", env!("CARGO_PKG_VERSION")),
        "store": store.manifest.content_crc32,
        "crs": crs,
        "heights": heights,
        "geoid_grid_bytes": opts.geoid_grid.as_ref().and_then(|p| std::fs::metadata(p).ok()).map(|m| m.len()),
        "modes": listing,
        "jpeg_quality": opts.jpeg_quality,
        "lit": opts.lit,
        "metadata": opts.metadata,
        "subtree_levels": subtree_levels,
    });
    let key_path = out.join(EXPORT_KEY_FILE);
    let resume = store.manifest.content_crc32.is_some()
        && std::fs::read(&key_path)
            .ok()
            .and_then(|b| serde_json::from_slice::<Value>(&b).ok())
            .is_some_and(|k| k == key);
    if !resume {
        // (only what an earlier export of this kind wrote, known by its key file: a folder
        // that never held one keeps its files, as before resuming existed)
        if key_path.is_file() {
            remove_earlier_export(out)?;
        }
        let text = serde_json::to_string_pretty(&key)
            .map_err(|e| Error::BadOption(format!("{EXPORT_KEY_FILE}: {e}")))?;
        write_atomic(&key_path, text.as_bytes())?;
    }
    let progress = opts.progress.task(
        (store.manifest.cells.len() * modes.len()) as u64,
        "export-tiles",
    );
    let ctx = TilesetContext {
        store: &store,
        out,
        to_enu: &to_enu,
        rot,
        centre,
        crs: &crs,
        heights: &heights,
        modes: &listing,
        jpeg_quality: opts.jpeg_quality,
        lit: opts.lit,
        metadata: opts.metadata,
        subtree_levels,
        resume,
        progress: progress.as_ref(),
    };
    let mut report = None;
    let (mut bytes, mut resumed) = (0, 0);
    for &m in &modes {
        let r = write_tileset(&ctx, m)?;
        bytes += r.bytes;
        resumed += r.resumed;
        report.get_or_insert(r);
    }
    progress.finish();
    for (name, cam) in &opts.views {
        let v = view_json(&to_ecef, cam)?;
        write_atomic(
            &out.join("views").join(format!("{name}.json")),
            v.to_string().as_bytes(),
        )?;
    }
    write_atomic(
        &out.join("index.html"),
        include_str!("index.html").as_bytes(),
    )?;
    let mut r = report.ok_or_else(|| Error::BadOption("no texture mode to export".into()))?;
    r.bytes = bytes;
    r.resumed = resumed;
    r.heights = heights;
    Ok(r)
}

/// What every mode's tileset shares.
struct TilesetContext<'a> {
    store: &'a Store,
    out: &'a Path,
    to_enu: &'a (dyn Fn(DVec3) -> Result<DVec3> + Sync),
    rot: DMat3,
    centre: DVec3,
    crs: &'a str,
    heights: &'a str,
    modes: &'a [Value],
    jpeg_quality: Option<u8>,
    lit: bool,
    metadata: bool,
    /// Levels per tileset file (0: one file).
    subtree_levels: u8,
    /// Keep GLBs an earlier run of the same export wrote.
    resume: bool,
    progress: &'a dyn crate::progress::ProgressTask,
}

/// Removes what an earlier export wrote into `out` (tileset files, `tiles*/`, `subtrees/`,
/// `views/`, the key file); other files are left alone.
fn remove_earlier_export(out: &Path) -> Result<()> {
    let Ok(entries) = std::fs::read_dir(out) else {
        return Ok(());
    };
    for e in entries {
        let e = e.map_err(|err| Error::io(out, err))?;
        let name = e.file_name().to_string_lossy().into_owned();
        let path = e.path();
        let ours_dir =
            name == "tiles" || name.starts_with("tiles_") || name == "subtrees" || name == "views";
        let ours_file =
            (name.starts_with("tileset") && name.ends_with(".json")) || name == EXPORT_KEY_FILE;
        if ours_dir && path.is_dir() {
            std::fs::remove_dir_all(&path).map_err(|err| Error::io(&path, err))?;
        } else if ours_file && path.is_file() {
            std::fs::remove_file(&path).map_err(|err| Error::io(&path, err))?;
        }
    }
    Ok(())
}

/// The tileset file of a texture mode: `tileset.json` for the best texture (photo), else
/// `tileset_MODE.json`.
pub fn tileset_name(mode: TextureSource) -> String {
    match mode {
        TextureSource::Photo => "tileset.json".into(),
        m => format!("tileset_{}.json", m.name()),
    }
}

/// Writes one mode's GLBs and tileset (its tileset file last); the report's `heights` is
/// left empty.
fn write_tileset(ctx: &TilesetContext, mode: TextureSource) -> Result<TilesReport> {
    let (store, out) = (ctx.store, ctx.out);
    let cells = &store.manifest.cells;
    // GLBs in parallel (one cell at a time in memory per thread), bounding boxes back.
    let results: Vec<(usize, [DVec3; 2], TextureSource, u64, bool)> = (0..cells.len())
        .into_par_iter()
        .map(|i| {
            let rec = &cells[i];
            let path = out.join(tile_path_for(mode, rec.level, rec.x, rec.y));
            ctx.progress.inc(1);
            if ctx.resume
                && let Ok(m) = std::fs::metadata(&path) {
                    // written by the interrupted run (GLBs are written atomically): only its
                    // bounding box is needed
                    let (positions, source) = read_export_positions(store, rec, mode)?;
                    let (mut a, mut b) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
                    for &p in &positions {
                        let q = (ctx.to_enu)(p)?;
                        a = a.min(q);
                        b = b.max(q);
                    }
                    return Ok((i, [a, b], source, m.len(), true));
                }
            let mut cell: ExportCell = read_export_cell_as(store, rec, mode)?;
            if ctx.lit {
                cell.make_lit(store)?;
            }
            if ctx.metadata {
                cell.make_metadata(store, rec, mode)?;
            }
            if let Some(q) = ctx.jpeg_quality {
                cell.texture_to_jpeg(q)?;
            }
            let enu: Vec<DVec3> = cell.positions.iter().map(|&p| (ctx.to_enu)(p)).collect::<Result<_>>()?;
            let (mut a, mut b) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for p in &enu {
                a = a.min(*p);
                b = b.max(*p);
            }
            let extras = json!({"cliffmap": {"cell": rec.id, "texture": cell.texture.name(), "max_error_m": rec.max_error}});
            let bytes = write_glb(
                std::slice::from_ref(&cell),
                &|_, v| [enu[v].x, enu[v].z, -enu[v].y],
                &extras,
            )?;
            write_atomic(&path, &bytes)?;
            Ok((i, [a, b], cell.texture, bytes.len() as u64, false))
        })
        .collect::<Result<_>>()?;
    let mut boxes = vec![[DVec3::ZERO; 2]; cells.len()];
    let mut textures = [0usize; 3];
    let (mut bytes, mut resumed) = (0, 0);
    for (i, bx, t, n, kept) in results {
        resumed += usize::from(kept);
        boxes[i] = bx;
        textures[t.index()] += 1;
        bytes += n;
    }
    // The explicit tree.
    let index: std::collections::HashMap<(u8, u32, u32), usize> = cells
        .iter()
        .enumerate()
        .map(|(i, c)| ((c.level, c.x, c.y), i))
        .collect();
    let top: Vec<usize> = cells
        .iter()
        .enumerate()
        .filter(|(_, c)| c.level == 0)
        .map(|(i, _)| i)
        .collect();
    let mut children = Vec::new();
    let mut tree = Tree {
        mode,
        store,
        index: &index,
        boxes: &boxes,
        pruned: 0,
        listed: 0,
        split: ctx.subtree_levels,
        external: Vec::new(),
    };
    for &i in &top {
        children.push(tree.tile_json(i));
    }
    let (pruned, listed) = (tree.pruned, tree.listed);
    let subtrees = tree.external.len();
    let asset =
        json!({"version": "1.1", "generator": format!("cliffmap {}", env!("CARGO_PKG_VERSION"))});
    for (path, root) in tree.external {
        let sub = json!({
            "asset": asset,
            "geometricError": root["geometricError"],
            "root": root,
        });
        let text =
            serde_json::to_string(&sub).map_err(|e| Error::BadOption(format!("{path}: {e}")))?;
        write_atomic(&out.join(&path), text.as_bytes())?;
    }
    let top_error = top.iter().map(|&i| cells[i].max_error).fold(0.0, f64::max);
    let (mut a, mut b) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for bx in &boxes {
        a = a.min(bx[0]);
        b = b.max(bx[1]);
    }
    let root_error = (2.0 * top_error).max(1.0);
    let tileset = json!({
        "asset": {"version": "1.1", "generator": format!("cliffmap {}", env!("CARGO_PKG_VERSION")),
                  "extras": {"cliffmap": {"crs": ctx.crs, "heights": ctx.heights, "texture_mode": mode.name(), "modes": ctx.modes,
                                          "frame": "east-north-up at the root transform's origin"}}},
        "geometricError": root_error,
        "root": {
            "transform": enu_to_ecef_matrix(ctx.rot, ctx.centre),
            "boundingVolume": {"box": box_json([a, b])},
            "geometricError": root_error,
            "refine": "REPLACE",
            "children": children,
        }
    });
    let text = serde_json::to_string(&tileset)
        .map_err(|e| Error::BadOption(format!("{}: {e}", tileset_name(mode))))?;
    write_atomic(&out.join(tileset_name(mode)), text.as_bytes())?;
    Ok(TilesReport {
        tiles: listed,
        pruned,
        textures,
        bytes,
        subtrees,
        heights: String::new(),
        resumed,
    })
}

/// A camera for the page: ECEF position, forward and up directions (through ECEF by
/// differences of points a metre apart, so grid convergence is included), and the field of
/// view of the image's larger side (Cesium's `fov`). The principal point is taken as centred.
fn view_json(to_ecef: &ToEcef, cam: &crate::camera::CameraModel) -> Result<Value> {
    let p = to_ecef.to_ecef(cam.position)?;
    let dir =
        |d: DVec3| -> Result<DVec3> { Ok((to_ecef.to_ecef(cam.position + d)? - p).normalize()) };
    let forward = dir(cam.world_to_camera.row(2))?;
    let up = dir(-cam.world_to_camera.row(1))?;
    let fov = if cam.width >= cam.height {
        2.0 * (cam.width as f64 / (2.0 * cam.fx)).atan()
    } else {
        2.0 * (cam.height as f64 / (2.0 * cam.fy)).atan()
    };
    Ok(
        json!({"position_ecef": p.to_array(), "direction_ecef": forward.to_array(), "up_ecef": up.to_array(),
              "fov_larger_rad": fov, "width": cam.width, "height": cam.height}),
    )
}

/// The GLB of cell (level, x, y) in the best-texture tileset, relative to the tileset's
/// folder.
pub fn tile_path(level: u8, x: u32, y: u32) -> String {
    tile_path_for(TextureSource::Photo, level, x, y)
}

/// The GLB of cell (level, x, y) in the tileset of texture mode `mode` (`tiles/` for the
/// best texture, `tiles_MODE/` for the others).
pub fn tile_path_for(mode: TextureSource, level: u8, x: u32, y: u32) -> String {
    match mode {
        TextureSource::Photo => format!("tiles/{level}/{x}-{y}.glb"),
        m => format!("tiles_{}/{level}/{x}-{y}.glb", m.name()),
    }
}

/// The external child tileset of cell (level, x, y) in the tileset of texture mode `mode`
/// (`subtrees/` for the best texture, `subtrees_MODE/` for the others), relative to the
/// tileset's folder; its GLBs are referenced as `../../tiles/...`.
pub fn subtree_path_for(mode: TextureSource, level: u8, x: u32, y: u32) -> String {
    match mode {
        TextureSource::Photo => format!("subtrees/{level}/{x}-{y}.json"),
        m => format!("subtrees_{}/{level}/{x}-{y}.json", m.name()),
    }
}

/// Builds the explicit tree of one texture mode, collecting external child tilesets.
struct Tree<'a> {
    mode: TextureSource,
    store: &'a Store,
    index: &'a std::collections::HashMap<(u8, u32, u32), usize>,
    boxes: &'a [[DVec3; 2]],
    pruned: usize,
    listed: usize,
    /// Levels per tileset file (0: one file).
    split: u8,
    /// (path, root tile) of each external tileset, URIs relative to its own folder.
    external: Vec<(String, Value)>,
}

impl Tree<'_> {
    /// The tile of cell `i` with its subtree; a cell at a positive multiple of `split`
    /// levels with children becomes a reference to its own external tileset.
    fn tile_json(&mut self, i: usize) -> Value {
        self.tile_in(i, "")
    }

    /// [`Tree::tile_json`] with content URIs prefixed by `prefix` (the way from the file
    /// that lists the tile back to the tileset's folder).
    fn tile_in(&mut self, i: usize, prefix: &str) -> Value {
        let (store, index) = (self.store, self.index);
        let c = &store.manifest.cells[i];
        self.listed += 1;
        let kids: Vec<usize> = [(0, 0), (1, 0), (0, 1), (1, 1)]
            .iter()
            .filter_map(|&(dx, dy)| {
                index
                    .get(&(c.level + 1, 2 * c.x + dx, 2 * c.y + dy))
                    .copied()
            })
            .collect();
        // Footprints are the meshes' x-y bounds (a cell's nominal square may reach past the
        // DEM, where no child exists).
        let area = |k: usize| {
            let r = &store.manifest.cells[k];
            (r.bbox_max[0] - r.bbox_min[0]).max(0.0) * (r.bbox_max[1] - r.bbox_min[1]).max(0.0)
        };
        let covered = !kids.is_empty()
            && kids.iter().map(|&k| area(k)).sum::<f64>() >= area(i) * (1.0 - 1e-6);
        let split_here = covered && self.split > 0 && c.level > 0 && c.level % self.split == 0;
        // inside an external tileset at subtrees/L/X-Y.json the tileset folder is ../../
        let own = if split_here { "../../" } else { prefix };
        let mut t = json!({
            "boundingVolume": {"box": box_json(self.boxes[i])},
            "geometricError": c.max_error,
            "content": {"uri": format!("{own}{}", tile_path_for(self.mode, c.level, c.x, c.y))},
        });
        if covered {
            let children: Vec<Value> = kids.iter().map(|&k| self.tile_in(k, own)).collect();
            t["children"] = Value::Array(children);
        } else if !kids.is_empty() {
            self.pruned += count_subtree(c.level, c.x, c.y, index) - 1;
        }
        if !split_here {
            return t;
        }
        t["refine"] = json!("REPLACE");
        let path = subtree_path_for(self.mode, c.level, c.x, c.y);
        let reference = json!({
            "boundingVolume": t["boundingVolume"],
            "geometricError": c.max_error,
            "content": {"uri": format!("{prefix}{path}")},
        });
        self.external.push((path, t));
        reference
    }
}

/// Cells in the subtree of (level, x, y), itself included.
fn count_subtree(
    level: u8,
    x: u32,
    y: u32,
    index: &std::collections::HashMap<(u8, u32, u32), usize>,
) -> usize {
    if !index.contains_key(&(level, x, y)) {
        return 0;
    }
    1 + [(0, 0), (1, 0), (0, 1), (1, 1)]
        .iter()
        .map(|&(dx, dy)| count_subtree(level + 1, 2 * x + dx, 2 * y + dy, index))
        .sum::<usize>()
}

/// 3D Tiles `box`: centre, then the three half-axes (axis-aligned in the tile frame).
fn box_json(b: [DVec3; 2]) -> Value {
    let c = (b[0] + b[1]) * 0.5;
    let h = ((b[1] - b[0]) * 0.5).max(DVec3::splat(0.01));
    json!([c.x, c.y, c.z, h.x, 0.0, 0.0, 0.0, h.y, 0.0, 0.0, 0.0, h.z])
}

/// The column-major 4×4 matrix from the ENU frame (rotation `rot` ECEF → ENU, origin
/// `centre`) to ECEF.
fn enu_to_ecef_matrix(rot: DMat3, centre: DVec3) -> Value {
    let m = rot.transpose(); // columns: east, north, up in ECEF
    let c = m.to_cols_array();
    json!([
        c[0], c[1], c[2], 0.0, c[3], c[4], c[5], 0.0, c[6], c[7], c[8], 0.0, centre.x, centre.y,
        centre.z, 1.0
    ])
}
