//! `reparam`: give the stretched cells of a store an area/angle-preserving parameterization
//! and resample their textures into it ("model only what a scene requires": cells at or
//! below the threshold keep the orthographic map and are not touched).

use std::collections::HashMap;
use std::path::Path;

use rayon::prelude::*;

use super::build::write_png;
use super::write_stats;
use crate::cells::CellMesh;
use crate::error::{Error, Result};
use crate::fsutil::PngCompression;
use crate::georef::GridGeoref;
use crate::param::{ParamMesh, ParamOptions, chart_metrics, parameterize};
use crate::progress::ProgressSink;
use crate::resample::{ChartMesh, Mode, PixelMap, ResampleOptions, Source, resample};
use crate::stats::{self, texel_stretch};
use crate::store::{
    CellFiles, CellRecord, Parameterization, ReparamRecord, ReparamSettings, Store, cell_stem,
    write_file,
};

/// Options of `reparam`.
#[derive(Clone, Debug)]
pub struct ReparamOptions {
    /// Cells whose ortho Rel_texel is above this get a new parameterization (default 1.1).
    pub threshold: f64,
    /// Parameterization settings (theta, relaxation budget, gutter); `texture_size` is set per cell.
    pub param: ParamOptions,
    /// Reparameterized cells get textures of twice the side (4x the texels).
    pub mixed_resolution: bool,
    /// Resampling filter and fill; `texels` is set per cell.
    pub resample: ResampleOptions,
    /// PNG compression of the reparameterized textures (default fast).
    pub png_compression: PngCompression,
    /// Where progress is reported (default: nowhere).
    pub progress: ProgressSink,
}

impl Default for ReparamOptions {
    fn default() -> Self {
        ReparamOptions {
            threshold: 1.1,
            param: ParamOptions::default(),
            mixed_resolution: false,
            resample: ResampleOptions::default(),
            png_compression: PngCompression::default(),
            progress: ProgressSink::none(),
        }
    }
}

/// Texture memory of the three rendering modes, bytes of RGBA8 colour + RGB8 normals with
/// full mip chains (4/3 of the base level).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TextureMemory {
    /// Every cell orthographic at the store's resolution.
    pub ortho_bytes: u64,
    /// Stretched cells reparameterized at the store's resolution.
    pub reparam_bytes: u64,
    /// Stretched cells reparameterized at twice the side.
    pub mixed_bytes: u64,
    /// As stored, with each cell's photo texture where it has one (the default render):
    /// photo colour at its own size, normal map at the active size.
    #[serde(default)]
    pub photo_bytes: u64,
}

/// Texture memory per mode for a store's cells (independent of which mode was built).
pub fn texture_memory(cells: &[CellRecord], cell_texels: u32) -> TextureMemory {
    let per = |t: u32| (t as u64 * t as u64 * 7 * 4).div_ceil(3); // (4 + 3) bytes, mips 4/3
    let mips = |t: u32, bytes: u64| (t as u64 * t as u64 * bytes * 4).div_ceil(3);
    let base = per(cell_texels);
    let n = cells.len() as u64;
    let n_re = cells.iter().filter(|c| c.reparam.is_some()).count() as u64;
    let photo_bytes = cells
        .iter()
        .map(|c| {
            let active = crate::store::active_texels(c);
            let colour = c.photo.as_ref().map_or(active, |p| p.texels);
            mips(colour, 4) + mips(active, 3)
        })
        .sum();
    TextureMemory {
        ortho_bytes: n * base,
        reparam_bytes: n * base,
        mixed_bytes: (n - n_re) * base + n_re * per(2 * cell_texels),
        photo_bytes,
    }
}

/// Runs `reparam` on the store in `dir`: parameterizes every cell above the threshold,
/// resamples its texture and normal map into the chart, records metrics, and rewrites
/// `stats.json` and `manifest.json` (atomically, manifest last). A cell whose
/// parameterization fails keeps the ortho map and is listed in `failed_cells`.
/// Re-running with other options starts again from the orthographic originals. Photo
/// textures of an earlier `project` run are dropped (records and files): their layout
/// follows the old texture coordinates; run `project` again.
pub fn reparam_store(dir: &Path, opts: &ReparamOptions) -> Result<Store> {
    if !(opts.threshold.is_finite() && opts.threshold > 0.0) {
        return Err(Error::BadOption(format!(
            "--threshold must be a positive number, got {}",
            opts.threshold
        )));
    }
    opts.param.validate()?;
    let _lock = crate::store::StoreLock::acquire(dir, "cliffmap reparam")?;
    let mut store = Store::open(dir)?;
    let t = store.manifest.cell_texels;
    let texels = if opts.mixed_resolution { 2 * t } else { t };
    let chosen: Vec<usize> = (0..store.manifest.cells.len())
        .filter(|&i| store.manifest.cells[i].stats.rel_texel > opts.threshold)
        .collect();
    let pb = opts.progress.task(chosen.len() as u64, "reparam");
    let results: Vec<(usize, Result<ReparamRecord>)> = chosen
        .par_iter()
        .map(|&i| {
            let r = reparam_cell(&store, &store.manifest.cells[i], texels, opts);
            pb.inc(1);
            (i, r)
        })
        .collect();
    pb.finish();
    let mut failed = Vec::new();
    for c in &mut store.manifest.cells {
        c.reparam = None;
        c.parameterization = Parameterization::Ortho;
        // photo textures were laid out in the old texture coordinates: drop them
        c.photo = None;
    }
    store.manifest.photos = None;
    for (i, r) in results {
        let c = &mut store.manifest.cells[i];
        match r {
            Ok(rec) => {
                c.reparam = Some(rec);
                c.parameterization = Parameterization::Reparam;
            }
            Err(e) => {
                tracing::warn!(
                    "cell {}: parameterization failed, keeping the ortho map: {e}",
                    c.id
                );
                failed.push(c.id.clone());
            }
        }
    }
    store.manifest.reparam = Some(ReparamSettings {
        threshold: opts.threshold,
        theta: opts.param.theta,
        newton_iterations: if opts.param.theta == 1.0 {
            opts.param.newton_iterations
        } else {
            0
        },
        mixed_resolution: opts.mixed_resolution,
        resample: match opts.resample.mode {
            Mode::Subtexel(n) => format!("subtexel:{n}"),
            Mode::Bilinear => "bilinear".into(),
            Mode::Exact => "exact".into(),
        },
        failed_cells: failed,
        param: Some(opts.param),
        fill: Some(match opts.resample.fill {
            crate::resample::Fill::PullPush => "pull-push".into(),
            _ => "average-border".into(),
        }),
        png_compression: opts.png_compression,
    });
    write_stats(dir, &store.manifest, opts.threshold)?;
    store.manifest.write(dir)?;
    // Reparameterized files of cells that no longer use them are stale: remove them.
    for c in store.manifest.cells.iter().filter(|c| c.reparam.is_none()) {
        for ext in ["reparam.mesh", "reparam.png", "reparam.normal.png"] {
            let _ =
                std::fs::remove_file(dir.join(format!("{}.{ext}", cell_stem(c.level, c.x, c.y))));
        }
    }
    super::project::remove_stale_photo_files(dir, &store.manifest.cells);
    Ok(store)
}

/// The options of the store's last `reparam` run, from its recorded settings; `None` if the
/// store has none or was reparameterized before every option was recorded.
pub fn recorded_reparam_options(settings: &ReparamSettings) -> Option<ReparamOptions> {
    let mode = match settings.resample.as_str() {
        "bilinear" => Mode::Bilinear,
        "exact" => Mode::Exact,
        s => Mode::Subtexel(s.strip_prefix("subtexel:")?.parse().ok()?),
    };
    let fill = match settings.fill.as_deref()? {
        "pull-push" => crate::resample::Fill::PullPush,
        _ => crate::resample::Fill::AverageBorder,
    };
    Some(ReparamOptions {
        threshold: settings.threshold,
        param: settings.param?,
        mixed_resolution: settings.mixed_resolution,
        resample: ResampleOptions {
            mode,
            fill,
            ..ResampleOptions::default()
        },
        png_compression: settings.png_compression,
        progress: ProgressSink::none(),
    })
}

/// Redoes the reparameterized variant of the cells `ids` (which must have one) with the
/// store's recorded options, rewriting their files and records in `store.manifest` (the
/// caller writes the manifest). Deterministic: the same inputs give the same files.
pub fn redo_reparam_cells(store: &mut Store, ids: &[String], opts: &ReparamOptions) -> Result<()> {
    for id in ids {
        let i = store
            .manifest
            .cells
            .iter()
            .position(|c| &c.id == id)
            .ok_or_else(|| Error::BadOption(format!("cell {id} is not in the store")))?;
        let texels = store.manifest.cells[i]
            .reparam
            .as_ref()
            .map(|r| r.texels)
            .ok_or_else(|| {
                Error::BadOption(format!("cell {id} has no reparameterized variant to redo"))
            })?;
        let rec = reparam_cell(store, &store.manifest.cells[i], texels, opts)?;
        store.manifest.cells[i].reparam = Some(rec);
    }
    Ok(())
}

fn reparam_cell(
    store: &Store,
    rec: &CellRecord,
    texels: u32,
    opts: &ReparamOptions,
) -> Result<ReparamRecord> {
    let mesh = store.read_mesh(rec)?;
    let ns = mesh.surface_vertices as usize;
    let positions: Vec<[f64; 3]> = mesh.positions[..ns]
        .iter()
        .map(|p| p.map(f64::from))
        .collect();
    let triangles = mesh.surface().to_vec();
    let popts = ParamOptions {
        texture_size: texels,
        ..opts.param
    };
    let chart = parameterize(
        &ParamMesh {
            positions: positions.clone(),
            triangles: triangles.clone(),
        },
        &popts,
    )?;
    let base_area = rec.stats.base_area;
    let metrics = chart_metrics(&positions, &triangles, &chart.uvs, Some(base_area))?;
    // The chart's v axis points up; the store's texture coordinates run down the image rows.
    let tex_uvs: Vec<[f64; 2]> = chart.uvs.iter().map(|&[u, v]| [u, 1.0 - v]).collect();
    if metrics.flipped > 0 {
        return Err(Error::BadOption(format!(
            "chart of cell {} has {} flipped triangles",
            rec.id, metrics.flipped
        )));
    }

    // Texture coordinates for every vertex: skirt vertices copy their border vertex's.
    let key = |p: &[f32; 3]| (p[0].to_bits(), p[1].to_bits());
    let border: HashMap<(u32, u32), usize> = mesh.positions[..ns]
        .iter()
        .enumerate()
        .map(|(i, p)| (key(p), i))
        .collect();
    let mut uvs: Vec<[f32; 2]> = tex_uvs.iter().map(|u| [u[0] as f32, u[1] as f32]).collect();
    for p in &mesh.positions[ns..] {
        let src = border.get(&key(p)).copied().ok_or_else(|| {
            Error::store(
                store.dir.join(&rec.files.mesh.path),
                "skirt vertex without a border vertex",
            )
        })?;
        uvs.push(uvs[src]);
    }
    let new_mesh = CellMesh {
        uvs: Some(uvs),
        ..mesh
    };

    // Resample the cell's ortho texture and normal map (both over the nominal square).
    let e = &rec.extent;
    let t_old = rec.texels as f64;
    let tex_georef = GridGeoref {
        origin_x: e.min_x + 0.5 * e.width() / t_old,
        origin_y: e.max_y - 0.5 * e.height() / t_old,
        spacing_x: e.width() / t_old,
        spacing_y: e.height() / t_old,
    };
    let to_pixel = PixelMap::from_georef(&tex_georef, [rec.origin[0], rec.origin[1]]);
    let chart_mesh = ChartMesh {
        positions: &positions,
        triangles: &triangles,
        uvs: &tex_uvs,
    };
    let ropts = ResampleOptions {
        texels,
        ..opts.resample
    };
    let colour = store.read_texture(rec)?;
    let col = resample(
        &chart_mesh,
        &Source {
            image: &colour,
            to_pixel,
        },
        &ropts,
    )?;
    let normal = store.read_normal_map(rec)?;
    let normal_rgba = image::DynamicImage::ImageRgb8(normal).to_rgba8();
    let nrm = resample(
        &chart_mesh,
        &Source {
            image: &normal_rgba,
            to_pixel,
        },
        &ropts,
    )?;
    let nrm_rgb = image::DynamicImage::ImageRgba8(nrm.image).to_rgb8();

    let stem = cell_stem(rec.level, rec.x, rec.y);
    let files = CellFiles {
        mesh: write_file(
            &store.dir,
            &format!("{stem}.reparam.mesh"),
            &new_mesh.to_bytes(),
        )?,
        texture: write_png(
            &store.dir,
            &format!("{stem}.reparam.png"),
            &col.image,
            opts.png_compression,
        )?,
        normal: write_png(
            &store.dir,
            &format!("{stem}.reparam.normal.png"),
            &nrm_rgb,
            opts.png_compression,
        )?,
    };
    // Per-texel stretch relative to an ortho texel (base area / cell_texels²).
    let ratio = texels as f64 / t_old;
    let stretch = texel_stretch(
        &positions,
        &triangles,
        &tex_uvs,
        texels,
        base_area * ratio * ratio,
    );
    Ok(ReparamRecord {
        texels,
        files,
        rel_texel: metrics.rel_texel / (ratio * ratio),
        metrics,
        texel_stretch: stats::summarize_stretch(&stretch).percentiles,
        bilinear_fallbacks: col.stats.bilinear_fallbacks as u64,
    })
}
