//! `build`: DEM (+ ortho) -> quadtree of TIN cells with textures, normal maps and stats.

use std::path::Path;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::derived_ortho;
use crate::cells::local_mesh;
use crate::cells::{self, CellKey, LevelBorders, Quadtree};
use crate::dem::Dem;
use crate::error::{Error, Result};
use crate::fsutil::{PngCompression, encode_png, write_atomic};
use crate::ortho::Ortho;
use crate::progress::ProgressSink;
use crate::stats;
use crate::store::{
    self, CellFiles, CellRecord, DemInfo, Manifest, Parameterization, STORE_FORMAT, STORE_VERSION,
    cell_stem, write_file,
};

/// Options of a build. Defaults: 0.5 m finest error, 64-interval finest cells, 256² textures.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BuildOptions {
    /// Max vertical error of the finest level (world units, > 0); doubles per coarser level.
    pub max_error: f64,
    /// Sample intervals per side of a finest cell (power of two, 2..=4096).
    pub cell_intervals: u32,
    /// Texture side in texels (power of two, 8..=8192).
    pub cell_texels: u32,
    /// PNG compression of the textures and normal maps (same pixels; part of the build's
    /// identity unless `fast`, what earlier stores used, so they keep their key).
    #[serde(default, skip_serializing_if = "is_default_png")]
    pub png_compression: PngCompression,
    /// Where progress is reported (default: nowhere).
    #[serde(skip)]
    pub progress: ProgressSink,
    /// Rebuild over an existing store built from other inputs or options.
    #[serde(skip)]
    pub force: bool,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            max_error: 0.5,
            cell_intervals: 64,
            cell_texels: 256,
            png_compression: PngCompression::default(),
            progress: ProgressSink::none(),
            force: false,
        }
    }
}

fn is_default_png(c: &PngCompression) -> bool {
    *c == PngCompression::Fast
}

impl BuildOptions {
    /// Rejects out-of-range options with a message naming the flag.
    pub fn validate(&self) -> Result<()> {
        if !(self.max_error.is_finite() && self.max_error > 0.0) {
            return Err(Error::BadOption(format!(
                "--max-error must be a positive number, got {}",
                self.max_error
            )));
        }
        if !self.cell_intervals.is_power_of_two() || !(2..=4096).contains(&self.cell_intervals) {
            return Err(Error::BadOption(format!(
                "--cell-intervals must be a power of two in 2..=4096, got {}",
                self.cell_intervals
            )));
        }
        if !self.cell_texels.is_power_of_two() || !(8..=8192).contains(&self.cell_texels) {
            return Err(Error::BadOption(format!(
                "--cell-texels must be a power of two in 8..=8192, got {}",
                self.cell_texels
            )));
        }
        Ok(())
    }
}

/// The inputs of a build and how to describe them in the manifest.
pub struct BuildInputs<'a> {
    /// The DEM.
    pub dem: &'a Dem,
    /// The ortho image; `None` derives a hypsometric + hillshade texture from the DEM.
    pub ortho: Option<&'a Ortho>,
    /// Description of the DEM source (path or generator).
    pub dem_source: String,
    /// Description of the ortho source.
    pub ortho_source: Option<String>,
    /// A fingerprint of the input content (e.g. CRC of the files); part of the build key.
    pub fingerprint: String,
}

#[derive(Serialize, Deserialize)]
struct BuildMarker {
    build_key: String,
}

/// Builds (or resumes) the store in `out`. Inputs are already validated; the store directory
/// is created only now. Cells whose record and files are intact from an interrupted build with
/// the same inputs and options are kept. Writes `manifest.json` last.
pub fn build_store(inp: &BuildInputs, opts: &BuildOptions, out: &Path) -> Result<Manifest> {
    opts.validate()?;
    let dem = inp.dem;
    let tree = Quadtree::new(dem.width as u32, dem.height as u32, opts.cell_intervals);
    let key_src = format!(
        "{STORE_VERSION}|{}|{}|{}|{:?}|{:?}",
        inp.fingerprint,
        serde_json::to_string(opts).unwrap_or_default(),
        serde_json::to_string(&dem.georef).unwrap_or_default(),
        inp.dem_source,
        inp.ortho_source
    );
    let build_key = store::crc32_hex(key_src.as_bytes());
    // Lock the directory before touching it, unless it is something else (prepare_dir
    // then refuses it without leaving a lock file in it).
    if !out.exists() {
        std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    }
    let ours = out.is_dir()
        && (is_empty_dir(out)?
            || out.join("manifest.json").exists()
            || out.join("build.json").exists());
    let _lock = if ours {
        Some(store::StoreLock::acquire(out, "cliffmap build")?)
    } else {
        None
    };
    prepare_dir(out, &build_key, opts.force)?;
    write_atomic(
        &out.join("build.json"),
        &serde_json::to_vec(&BuildMarker {
            build_key: build_key.clone(),
        })
        .unwrap_or_default(),
    )?;

    let derived;
    let ortho = match inp.ortho {
        Some(o) => o,
        None => {
            derived = derived_ortho(dem);
            &derived
        }
    };
    let total: usize = (0..tree.levels).map(|l| tree.cells(l).len()).sum();
    let pb = opts.progress.task(total as u64, "cells");
    let mut records = Vec::with_capacity(total);
    for level in 0..tree.levels {
        let eps = cells::level_epsilon(&tree, level, opts.max_error);
        let keys = tree.cells(level);
        let borders = LevelBorders::compute(dem, &tree, level, eps)?;
        let recs: Vec<Result<CellRecord>> = keys
            .par_iter()
            .map(|&key| {
                let r = match resume_record(out, key) {
                    Some(rec) => Ok(rec),
                    None => build_cell(dem, ortho, &tree, &borders, key, eps, opts, out),
                };
                pb.inc(1);
                r
            })
            .collect();
        for r in recs {
            records.push(r?);
        }
    }
    pb.finish();

    let (lo, hi) = dem.height_range();
    let mut manifest = Manifest {
        format: STORE_FORMAT.into(),
        version: STORE_VERSION,
        generator: format!("cliffmap {}", env!("CARGO_PKG_VERSION")),
        crs: dem.crs.clone(),
        georef: dem.georef,
        dem: DemInfo {
            source: inp.dem_source.clone(),
            width: dem.width as u32,
            height: dem.height as u32,
            height_min: lo as f64,
            height_max: hi as f64,
            void_fraction: dem.void_fraction(),
        },
        ortho: inp.ortho_source.clone(),
        ortho_spacing: inp
            .ortho
            .map(|o| o.georef.spacing_x.max(o.georef.spacing_y)),
        quadtree: tree,
        max_error: opts.max_error,
        cell_texels: opts.cell_texels,
        build_key,
        cells: records,
        reparam: None,
        photos: None,
        content_crc32: None,
    };
    write_stats(out, &manifest, 1.1)?;
    manifest.write(out)?;
    Ok(manifest)
}

/// Writes `stats.json` and `stats_histogram.png` for the store's cells; returns the JSON.
pub fn write_stats(out: &Path, manifest: &Manifest, threshold: f64) -> Result<serde_json::Value> {
    let entries: Vec<stats::CellStatsEntry> = manifest
        .cells
        .iter()
        .map(|c| stats::CellStatsEntry {
            id: c.id.clone(),
            level: c.level,
            x: c.x,
            y: c.y,
            triangles: c.triangles,
            max_error: c.max_error,
            stats: c.stats.clone(),
        })
        .collect();
    let mut json = stats::stats_json(&entries, threshold);
    add_parameterization(&mut json, manifest);
    super::photo_stats::add_photos(&mut json, manifest);
    write_atomic(
        &out.join("stats.json"),
        &serde_json::to_vec_pretty(&json).map_err(|e| Error::store(out, e.to_string()))?,
    )?;
    let rel: Vec<f64> = manifest.cells.iter().map(|c| c.stats.rel_texel).collect();
    stats::write_histogram_png(&out.join("stats_histogram.png"), &rel, threshold)?;
    Ok(json)
}

/// Adds each cell's parameterization (and its chart metrics and Rel_texel after
/// reparameterization) to the `stats.json` document, and a per-mode summary: Rel_texel
/// before (ortho) and after (the parameterization each cell uses), texture memory per mode.
fn add_parameterization(json: &mut serde_json::Value, manifest: &Manifest) {
    use serde_json::json;
    let mut after = Vec::with_capacity(manifest.cells.len());
    if let Some(cells) = json["cells"].as_array_mut() {
        for (c, v) in manifest.cells.iter().zip(cells.iter_mut()) {
            v["parameterization"] = json!(c.parameterization);
            v["rel_texel_ortho"] = json!(c.stats.rel_texel);
            let eff = c
                .reparam
                .as_ref()
                .map_or(c.stats.rel_texel, |r| r.rel_texel);
            v["rel_texel_effective"] = json!(eff);
            after.push(eff);
            if let Some(r) = &c.reparam {
                v["reparam"] = json!({
                    "texels": r.texels,
                    "rel_texel": r.rel_texel,
                    "texel_stretch": r.texel_stretch,
                    "metrics": r.metrics,
                    "bilinear_fallbacks": r.bilinear_fallbacks,
                });
            }
        }
    }
    let before: Vec<f64> = manifest.cells.iter().map(|c| c.stats.rel_texel).collect();
    let pct = |v: &[f64]| {
        let mut v = v.to_vec();
        serde_json::to_value(stats::Percentiles::of(&mut v)).unwrap_or_default()
    };
    let worst = |f: &dyn Fn(&crate::store::CellRecord) -> f64| {
        manifest.cells.iter().map(f).fold(0.0f64, f64::max)
    };
    json["summary"]["parameterization"] = json!({
        "cells_reparam": manifest.cells.iter().filter(|c| c.reparam.is_some()).count(),
        "settings": manifest.reparam,
        "rel_texel_before": pct(&before),
        "rel_texel_after": pct(&after),
        "texel_stretch_max_before": worst(&|c| c.stats.texel_stretch.max),
        "texel_stretch_max_after": worst(&|c| c.reparam.as_ref().map_or(c.stats.texel_stretch.max, |r| r.texel_stretch.max)),
        "texture_memory": super::texture_memory(&manifest.cells, manifest.cell_texels),
        "distortion": chart_distortion(manifest),
    });
}

/// Distortion of the reparameterized charts, as excess over an isometry: percentiles over
/// the cells of symD − 4, mean |ln(s1 s2)| and mean s1/s2 − 1, and the worst flips and
/// boundary crossings.
fn chart_distortion(manifest: &crate::store::Manifest) -> serde_json::Value {
    let metrics: Vec<&crate::param::ChartMetrics> = manifest
        .cells
        .iter()
        .filter_map(|c| c.reparam.as_ref().map(|r| &r.metrics))
        .collect();
    let pct = |f: &dyn Fn(&crate::param::ChartMetrics) -> f64| {
        let mut v: Vec<f64> = metrics.iter().map(|m| f(m)).collect();
        serde_json::to_value(stats::Percentiles::of(&mut v)).unwrap_or_default()
    };
    serde_json::json!({
        "symmetric_dirichlet_excess": pct(&|m| m.symmetric_dirichlet_excess()),
        "area_distortion": pct(&|m| m.area_distortion_mean),
        "angle_distortion_excess": pct(&|m| m.angle_distortion_mean - 1.0),
        "packed_stretch_l2": pct(&|m| m.packed_stretch_l2()),
        "flipped_max": metrics.iter().map(|m| m.flipped).max().unwrap_or(0),
        "boundary_crossings_max": metrics.iter().map(|m| m.boundary_crossings).max().unwrap_or(0),
    })
}

/// True if `dir` holds nothing but (possibly) the store's lock file.
fn is_empty_dir(dir: &Path) -> Result<bool> {
    for e in std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))? {
        let e = e.map_err(|e| Error::io(dir, e))?;
        if e.file_name() != ".lock" {
            return Ok(false);
        }
    }
    Ok(true)
}

/// Makes sure `out` can hold this build: absent or empty, or a cliffmap store of the same
/// build key (resume), or (with `force`) any earlier cliffmap store, whose cells are removed.
fn prepare_dir(out: &Path, build_key: &str, force: bool) -> Result<()> {
    if !out.exists() {
        return std::fs::create_dir_all(out).map_err(|e| Error::io(out, e));
    }
    if !out.is_dir() {
        return Err(Error::BadOption(format!(
            "output {} exists and is not a directory",
            out.display()
        )));
    }
    if is_empty_dir(out)? {
        return Ok(());
    }
    let previous_key = std::fs::read(out.join("build.json"))
        .ok()
        .and_then(|b| serde_json::from_slice::<BuildMarker>(&b).ok())
        .map(|m| m.build_key)
        .or_else(|| Manifest::read(out).ok().map(|m| m.build_key));
    match previous_key {
        Some(k) if k == build_key => Ok(()),
        Some(_) if force => {
            for name in [
                "cells",
                "manifest.json",
                "stats.json",
                "stats_histogram.png",
                "build.json",
            ] {
                let p = out.join(name);
                let _ = if p.is_dir() {
                    std::fs::remove_dir_all(&p)
                } else {
                    std::fs::remove_file(&p)
                };
            }
            Ok(())
        }
        Some(_) => Err(Error::BadOption(format!(
            "{} holds a cliffmap store built from other inputs or options; remove it, choose another --out, or pass --force",
            out.display()
        ))),
        None => Err(Error::BadOption(format!(
            "{} exists, is not empty and is not a cliffmap store; refusing to write into it",
            out.display()
        ))),
    }
}

/// The record of a cell finished by an earlier run of the same build, if all its files are intact.
fn resume_record(out: &Path, key: CellKey) -> Option<CellRecord> {
    let path = out.join(format!("{}.json", cell_stem(key.level, key.x, key.y)));
    let rec: CellRecord = serde_json::from_slice(&std::fs::read(path).ok()?).ok()?;
    let f = &rec.files;
    (rec.key() == key
        && [&f.mesh, &f.texture, &f.normal]
            .into_iter()
            .chain(rec.relief.as_ref().map(|r| &r.file))
            .all(|r| store::is_intact(out, r)))
    .then_some(rec)
}

#[allow(clippy::too_many_arguments)]
fn build_cell(
    dem: &Dem,
    ortho: &Ortho,
    tree: &Quadtree,
    borders: &LevelBorders,
    key: CellKey,
    eps: f64,
    opts: &BuildOptions,
    out: &Path,
) -> Result<CellRecord> {
    let rect = tree
        .clipped(key)
        .ok_or_else(|| Error::BadOption(format!("cell {} lies outside the DEM", key.id())))?;
    let tin = cells::build_tin(
        dem,
        rect,
        tree.stride(key.level),
        eps,
        &borders.cell_border(key),
    )?;
    let skirt_depth = 2.0 * eps.max(tin.max_error);
    let lm = local_mesh(dem, rect, &tin, skirt_depth);
    let extent = cells::nominal_extent(tree, &dem.georef, key);
    let texture = cells::ortho_texture(ortho, dem, extent, opts.cell_texels);
    let normal = cells::normal_map(dem, extent, opts.cell_texels);
    // at most twice the measured TIN error (cells::relief: walls would waste the 8 bits)
    let relief_limit = 2.0 * eps.max(tin.max_error);
    let relief = cells::relief_map(
        dem,
        extent,
        opts.cell_texels,
        &lm.mesh,
        lm.origin,
        relief_limit,
    );
    let cell_stats = stats::cell_stats(dem, tree, key, &tin, opts.cell_texels);

    let stem = cell_stem(key.level, key.x, key.y);
    let mesh_ref = write_file(out, &format!("{stem}.mesh"), &lm.mesh.to_bytes())?;
    let tex_ref = write_png(out, &format!("{stem}.png"), &texture, opts.png_compression)?;
    let nrm_ref = write_png(
        out,
        &format!("{stem}.normal.png"),
        &normal,
        opts.png_compression,
    )?;
    let relief_ref = write_png(
        out,
        &format!("{stem}.relief.png"),
        &relief.image,
        opts.png_compression,
    )?;
    let rec = CellRecord {
        id: key.id(),
        level: key.level,
        x: key.x,
        y: key.y,
        rect,
        origin: lm.origin,
        extent,
        bbox_min: lm.bbox_min,
        bbox_max: lm.bbox_max,
        epsilon: eps,
        max_error: tin.max_error,
        vertices: lm.mesh.surface_vertices,
        triangles: lm.mesh.surface_triangles,
        skirt_depth,
        parameterization: Parameterization::Ortho,
        texels: opts.cell_texels,
        files: CellFiles {
            mesh: mesh_ref,
            texture: tex_ref,
            normal: nrm_ref,
        },
        stats: cell_stats,
        reparam: None,
        photo: None,
        relief: Some(store::ReliefRecord {
            file: relief_ref,
            range_m: relief.range_m,
        }),
    };
    write_atomic(
        &out.join(format!("{stem}.json")),
        &serde_json::to_vec(&rec).map_err(|e| Error::store(out, e.to_string()))?,
    )?;
    Ok(rec)
}

pub(crate) fn write_png<P, C>(
    out: &Path,
    rel: &str,
    img: &image::ImageBuffer<P, C>,
    compression: PngCompression,
) -> Result<store::FileRef>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    C: std::ops::Deref<Target = [P::Subpixel]>,
{
    write_file(out, rel, &encode_png(&out.join(rel), img, compression)?)
}
