//! `project`: ground photos merged into the cell textures of every quadtree level
//! (docs/projection.md, "Splatting, blending and leveling").
//!
//! Per photo, the colour leveling (if on) is fitted first on a coarse level (the pyramid
//! step whose image has at most `leveling_max_pixels`; if that gives too few samples, once
//! more at full resolution). Then per level, finest first, per photo in input order: the level's cells
//! become a ray-castable scene near the camera, the photo's pyramid image for the level
//! (halved once per level above the finest) is cast into footprints batch by batch of
//! pixel rows; each batch is splatted per cell in parallel into that photo's accumulators
//! while the next batch is cast (each cell's deposits stay in row order, so the sums do not
//! depend on the batching), and the accumulators are merged into the level's per-cell
//! accumulators. Finally (while the next coarser level is cast) every cell of the level
//! that received photo colour gets `{stem}.photo.png` (the active texture blended with
//! photo colour) and `{stem}.photo.conf.png` (the photo share), and every cell's steep
//! texels are counted. Casts share one set of scratch buffers ([`FootprintBuffers`]).
//! Each run starts from the active textures (never from earlier photo textures), so the
//! same photos give byte-identical files; records and files of an earlier run that this
//! run does not write are removed. The manifest is written last.

use std::cmp::Reverse;
use std::path::Path;

use indicatif::{MultiProgress, ProgressBar};
use rayon::prelude::*;

use super::{progress_bar, write_stats};
use crate::colour::ColourSpace;
use crate::error::{Error, Result};
use crate::fsutil::{PngCompression, encode_png};
use crate::photo::{
    BlendMode, CellAccum, CellContext, CellFootprints, ColourPairs, ColourTransform,
    ConfidenceParams, FootprintBuffers, FootprintOptions, FootprintSet, LevelScene, LevelingParams,
    OcclusionMap, PhotoAccum, PhotoInput, PhotoPyramid, PhotoSamples, RayAccel, SIZING_BINS,
    SizeRequest, SizingBins, blend_cell, choose_scales, collect_pairs, fit_colour_transform,
    for_each_footprint_batch_in, normal_cos_slope, photo_footprints_in, texture_bytes,
};
use crate::stats::texel_stretch;
use crate::store::photo_texture::pack;
use crate::store::{
    BackgroundWriter, CellRecord, FileRef, PhotoCellRecord, PhotoLevelReport, PhotoReport,
    PhotoSettings, Store, active_texels, cell_stem, texcoord,
};

/// Texels steeper than this (degrees from horizontal) count as steep.
pub const STEEP_SLOPE_DEG: f64 = 60.0;

/// Options of `project`.
#[derive(Clone, Debug)]
pub struct ProjectOptions {
    /// How photos combine per texel.
    pub blend: BlendMode,
    /// Footprint formation (reconstruction, silhouette rejection).
    pub footprint: FootprintOptions,
    /// Fit and apply a per-photo colour transform towards the existing texture.
    pub level_colours: bool,
    /// Ray-casting acceleration for the pixel-corner rays.
    pub ray: RayAccel,
    /// Confidence terms and blend ramp.
    pub confidence: ConfidenceParams,
    /// Leveling sample selection and guards.
    pub leveling: LevelingParams,
    /// The leveling is fitted on the first pyramid image with at most this many pixels.
    pub leveling_max_pixels: u64,
    /// The space photo colours are averaged and blended in.
    pub colour_space: ColourSpace,
    /// Photo texture sizes.
    pub texture: PhotoTextureOptions,
    /// PNG compression of the photo textures and confidence maps (default fast).
    pub png_compression: PngCompression,
    /// Hide progress bars.
    pub quiet: bool,
}

impl Default for ProjectOptions {
    fn default() -> Self {
        ProjectOptions {
            blend: BlendMode::Confidence,
            footprint: FootprintOptions::default(),
            level_colours: true,
            ray: RayAccel::default(),
            confidence: ConfidenceParams::default(),
            leveling: LevelingParams::default(),
            leveling_max_pixels: 1 << 20,
            colour_space: ColourSpace::Linear,
            texture: PhotoTextureOptions::default(),
            png_compression: PngCompression::default(),
            quiet: false,
        }
    }
}

/// How large the photo textures are (docs/projection.md, "Texture sizes").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PhotoTextureOptions {
    /// Size each cell's photo texture by the finest detail the photos deliver on it
    /// ([`SizingBins`]); `false`: every photo texture has its active texture's size.
    pub photo_driven: bool,
    /// Largest photo texture side, texels (a power of two, 64..=8192). Default 2048.
    pub max_texels: u32,
    /// GPU bytes (RGBA8 with mips) the enlarged photo textures of all levels may take
    /// together: 3/4 for the finest level, a quarter of the previous share for each coarser
    /// one. Default 1 GiB.
    pub budget_bytes: u64,
    /// Texels per photo pixel side the sizing aims at, in [0.25, 4]. Default 1.
    pub texels_per_pixel: f64,
    /// Most texels an enlarged texture holds per full-resolution photo pixel its cell
    /// receives (> 0; a speed and memory knob: cells the photos cover only in part get
    /// smaller textures). Default infinite (no bound: sizes follow the finest detail).
    pub texels_per_delivered: f64,
}

impl Default for PhotoTextureOptions {
    fn default() -> Self {
        PhotoTextureOptions {
            photo_driven: true,
            max_texels: 2048,
            budget_bytes: 1 << 30,
            texels_per_pixel: 1.0,
            texels_per_delivered: f64::INFINITY,
        }
    }
}

impl PhotoTextureOptions {
    /// Rejects a cap that is not a power of two in 64..=8192.
    pub fn validate(&self) -> Result<()> {
        if !(self.max_texels.is_power_of_two() && (64..=8192).contains(&self.max_texels)) {
            return Err(Error::BadOption(format!(
                "--max-photo-texels must be a power of two in 64..=8192, got {}",
                self.max_texels
            )));
        }
        if !(self.texels_per_delivered > 0.0) {
            return Err(Error::BadOption(format!(
                "texels per delivered pixel must be positive, got {}",
                self.texels_per_delivered
            )));
        }
        if !(0.25..=4.0).contains(&self.texels_per_pixel) {
            return Err(Error::BadOption(format!(
                "--texels-per-pixel must be in [0.25, 4], got {}",
                self.texels_per_pixel
            )));
        }
        Ok(())
    }
}

/// What a `project` run did.
#[derive(Clone, Debug, PartialEq)]
pub struct ProjectReport {
    /// The settings and per-photo / per-level reports, as stored in the manifest.
    pub settings: PhotoSettings,
    /// Cells (all levels) that got a photo texture.
    pub cells_written: usize,
    /// Wall-clock seconds each stage of the run took, in order (stage name, seconds): colour
    /// leveling, then per level and photo the footprints and the splat, and the cells
    /// written per level. For benchmarks; not stored.
    pub stage_seconds: Vec<(String, f64)>,
}

/// Wall-clock durations of consecutive stages (also logged at debug level).
struct StageTimer {
    last: std::time::Instant,
    laps: Vec<(String, f64)>,
}

impl StageTimer {
    fn new() -> StageTimer {
        StageTimer {
            last: std::time::Instant::now(),
            laps: Vec::new(),
        }
    }

    fn lap(&mut self, stage: &str) {
        let now = std::time::Instant::now();
        let dt = (now - self.last).as_secs_f64();
        self.last = now;
        self.note(stage, dt);
    }

    /// Records a stage that ran alongside others (does not start a new lap).
    fn note(&mut self, stage: &str, dt: f64) {
        tracing::debug!("project: {stage}: {dt:.3} s");
        self.laps.push((stage.to_string(), dt));
    }
}

/// Runs `project` on the store in `dir` with `photos` (see the [module docs](self)).
/// Errors on an unreadable store, a photo whose image size differs from its camera's, or a
/// failed write; a photo that sees no terrain only logs a warning.
pub fn project_store(
    dir: &Path,
    photos: &[PhotoInput],
    opts: &ProjectOptions,
) -> Result<ProjectReport> {
    opts.confidence.validate()?;
    opts.texture.validate()?;
    if photos.len() >= u16::MAX as usize {
        return Err(Error::BadOption(format!(
            "at most {} photos per run, got {}",
            u16::MAX - 1,
            photos.len()
        )));
    }
    let mut timer = StageTimer::new();
    let _lock = crate::store::StoreLock::acquire(dir, "cliffmap project")?;
    let mut store = Store::open(dir)?;
    for p in photos {
        if p.image.dimensions() != (p.camera.width, p.camera.height) {
            return Err(Error::bad_input(
                &p.image_path,
                format!(
                    "image is {}x{} pixels but its camera is for {}x{}",
                    p.image.width(),
                    p.image.height(),
                    p.camera.width,
                    p.camera.height
                ),
            ));
        }
    }
    let ncells = store.manifest.cells.len();
    let levels = store.manifest.quadtree.levels as usize;
    let finest = levels.saturating_sub(1);
    timer.lap("open store");
    let pyramids: Vec<PhotoPyramid> = photos
        .iter()
        .map(|p| PhotoPyramid::new_in(&p.image, p.camera, finest + SIZING_STEPS, opts.colour_space))
        .collect();
    timer.lap("photo pyramids");

    let multi = MultiProgress::new();
    let steps = levels as u64 + opts.level_colours as u64;
    let bars: Vec<ProgressBar> = photos
        .iter()
        .map(|p| {
            let pb = progress_bar(steps, &p.name, opts.quiet);
            if opts.quiet { pb } else { multi.add(pb) }
        })
        .collect();

    let mut reports: Vec<PhotoReport> = photos
        .iter()
        .map(|p| PhotoReport {
            name: p.name.clone(),
            image: crate::fsutil::relative_path(&p.image_path, dir),
            texels_written: 0,
            texels_supplied: 0,
            pixels_hit: 0,
            rejected_silhouette: 0,
            reconstructed_footprints: 0,
            colour_gain: [1.0; 3],
            colour_offset: [0.0; 3],
            colour_samples: 0,
        })
        .collect();

    let mut transforms = vec![ColourTransform::IDENTITY; photos.len()];
    // Scratch memory of all casts of this run.
    let buffers = FootprintBuffers::default();
    // Footprints cast for the leveling are kept for the main loop while they are few.
    let mut cached: Vec<Option<(usize, FootprintSet)>> = vec![None; photos.len()];
    let mut cached_len = 0usize;
    // The first photo's finest scene is built alongside the leveling (which leaves cores
    // idle in its smaller steps); it is the first scene the level loop needs, unless the
    // leveling casts the finest level itself (a photo of at most `leveling_max_pixels`).
    let prebuild = !opts.level_colours
        || pyramids
            .first()
            .is_some_and(|pyr| leveling_step(pyr, finest, opts) > 0);
    let (leveled, first_scene) = rayon::join(
        || -> Result<Vec<(ColourTransform, usize, Option<(usize, FootprintSet)>)>> {
            if !opts.level_colours {
                return Ok(Vec::new());
            }
            pyramids
                .iter()
                .map(|pyr| estimate_leveling(&store, pyr, finest, opts, &buffers))
                .collect()
        },
        || {
            let first = photos.first().filter(|_| prebuild);
            first
                .map(|p| LevelScene::from_store(&store, finest as u8, p.camera.position, opts.ray))
                .transpose()
        },
    );
    for (i, (t, n, fs)) in leveled?.into_iter().enumerate() {
        if let Some((level, fs)) = fs {
            if cached_len + fs.len() <= MAX_CACHED_FOOTPRINTS {
                cached_len += fs.len();
                cached[i] = Some((level, fs));
            }
        }
        transforms[i] = t;
        reports[i].colour_gain = t.gain;
        reports[i].colour_offset = t.offset;
        reports[i].colour_samples = n as u64;
        bars[i].inc(1);
    }
    let mut first_scene = first_scene?;
    timer.lap(if opts.level_colours {
        "colour leveling (alongside the first finest scene)"
    } else {
        "first finest scene"
    });

    let mut records: Vec<Option<PhotoCellRecord>> = vec![None; ncells];
    let mut level_reports = Vec::with_capacity(levels);
    // Finest level first; the cells of each level are blended and written while the next
    // coarser level is cast and splatted (levels are independent, so the output is the same
    // as level by level).
    let run = LevelRun {
        store: &store,
        pyramids: &pyramids,
        transforms: &transforms,
        opts,
        buffers: &buffers,
        bars: &bars,
        finest,
        cell_errors: store
            .manifest
            .cells
            .iter()
            .map(|c| c.max_error.max(0.0) as f32)
            .collect(),
    };
    let mut pending: Option<(usize, (Vec<Option<CellAccum>>, LevelSizing))> = None;
    // The photo textures are written on a thread of their own (the fsyncs do not hold up
    // the workers); all are on disk before the manifest refers to them.
    let writer = BackgroundWriter::new(dir);
    // per photo, its occlusion map (made at the finest level, used by every level)
    let mut occlusion: Vec<Option<OcclusionMap>> = photos.iter().map(|_| None).collect();
    for level in (0..levels).rev().map(Some).chain([None]) {
        let (finished, projected) = rayon::join(
            || {
                pending.take().map(|(l, (accs, sizing))| {
                    let t = std::time::Instant::now();
                    (
                        l,
                        finish_level(&store, l, accs, &sizing, opts, &writer),
                        t.elapsed().as_secs_f64(),
                    )
                })
            },
            || -> Result<Option<(usize, (Vec<Option<CellAccum>>, LevelSizing))>> {
                let Some(level) = level else { return Ok(None) };
                Ok(Some((
                    level,
                    run.project_level(
                        level,
                        &mut occlusion,
                        &mut cached,
                        &mut first_scene,
                        &mut reports,
                        &mut timer,
                    )?,
                )))
            },
        );
        if let Some((l, result, secs)) = finished {
            let (lr, recs, supplied) = result?;
            for (ci, rec) in recs {
                records[ci] = Some(rec);
            }
            for (r, n) in reports.iter_mut().zip(supplied) {
                r.texels_supplied += n;
            }
            level_reports.push(lr);
            timer.note(
                &format!("level {l}: cells written (alongside the next level)"),
                secs,
            );
            // The time after the next level's casts until these writes were done.
            timer.lap(&format!("level {l}: rest of its cell writes"));
        }
        pending = projected?;
    }
    writer.finish()?;
    timer.lap("photo textures on disk");
    level_reports.sort_by_key(|r| r.level);
    for pb in &bars {
        pb.finish_and_clear();
    }
    for r in &reports {
        if r.texels_written == 0 {
            tracing::warn!(
                "photo {}: it sees no terrain of the store (no texels written)",
                r.name
            );
        }
    }

    let cells_written = records.iter().filter(|r| r.is_some()).count();
    for (c, r) in store.manifest.cells.iter_mut().zip(records) {
        c.photo = r;
    }
    let settings = PhotoSettings {
        blend: opts.blend.name().to_string(),
        reconstruct: opts.footprint.reconstruct,
        level_colours: opts.level_colours,
        ray_accel: opts.ray.name(),
        colour_space: opts.colour_space.name().to_string(),
        photo_driven_sizes: opts.texture.photo_driven,
        max_photo_texels: opts.texture.max_texels,
        photo_texture_budget: opts.texture.budget_bytes,
        occlusion_margin_px: opts.confidence.occlusion_margin_px,
        photos: reports,
        levels: level_reports,
    };
    store.manifest.photos = Some(settings.clone());
    let threshold = store.manifest.reparam.as_ref().map_or(1.1, |r| r.threshold);
    write_stats(dir, &store.manifest, threshold)?;
    store.manifest.write(dir)?;
    remove_stale_photo_files(dir, &store.manifest.cells);
    timer.lap("manifest and stats");
    Ok(ProjectReport {
        settings,
        cells_written,
        stage_seconds: timer.laps,
    })
}

/// Removes the photo textures of cells without a photo record (left by an earlier run).
pub(crate) fn remove_stale_photo_files(dir: &Path, cells: &[CellRecord]) {
    for c in cells.iter().filter(|c| c.photo.is_none()) {
        for ext in ["photo.png", "photo.conf.png"] {
            let _ =
                std::fs::remove_file(dir.join(format!("{}.{ext}", cell_stem(c.level, c.x, c.y))));
        }
    }
}

/// Per manifest cell, its footprints in `fs`; cells not on `level` (a footprint set from a
/// foreign scene) get none.
fn group_by_cell<'a>(
    fs: &'a FootprintSet,
    cells: &[CellRecord],
    level: u8,
) -> Vec<Option<&'a CellFootprints>> {
    let mut out = vec![None; cells.len()];
    for cf in &fs.cells {
        let cell = cf.cell as usize;
        if cell < cells.len() && cells[cell].level == level {
            out[cell] = Some(cf);
        }
    }
    out
}

/// Splats a batch of one photo's footprints on `level` (cells of other levels are ignored)
/// into the photo's per-cell accumulators `pas` (indexed by manifest cell, created on first
/// use with the cell's photo texture scale `scales[cell]`), in parallel over cells, each
/// cell's footprints in order.
fn splat_batch(
    batch: &FootprintSet,
    pas: &mut [Option<PhotoAccum>],
    cells: &[CellRecord],
    scales: &[u32],
    level: u8,
    samples: &PhotoSamples,
) {
    let groups = group_by_cell(batch, cells, level);
    // the cells with footprints, the costliest first (footprints times texture scale²), one
    // task each, so that the largest one does not start last
    let mut work: Vec<(usize, &mut Option<PhotoAccum>, &CellFootprints)> = pas
        .iter_mut()
        .zip(groups)
        .enumerate()
        .filter_map(|(ci, (pa, cf))| cf.map(|cf| (ci, pa, cf)))
        .collect();
    let cost = |ci: usize, cf: &CellFootprints| {
        let s = scales.get(ci).copied().unwrap_or(1).max(1) as usize;
        cf.len() * s * s
    };
    work.sort_by_key(|(ci, _, cf)| Reverse((cost(*ci, cf), Reverse(*ci))));
    work.into_par_iter()
        .with_max_len(1)
        .for_each(|(ci, pa, cf)| {
            let scale = scales.get(ci).copied().unwrap_or(1).max(1);
            pa.get_or_insert_with(|| {
                PhotoAccum::with_scale(active_texels(&cells[ci]) * scale, scale)
            })
            .add_samples(cf.iter(), samples);
        });
}

/// The resolution rule's view of cell `rec` ([`CellContext`]): slopes from its active normal
/// map, its TIN's measured error, and the ground sample distance of its existing texture
/// (the larger of the ortho's spacing, when the store records it, and the texel size).
fn cell_context(store: &Store, rec: &CellRecord) -> Result<CellContext> {
    let normals = store.read_active_normal_map(rec)?;
    let t = active_texels(rec);
    if normals.dimensions() != (t, t) {
        return Err(Error::store(
            store.dir.join(&active_normal_path(rec)),
            format!(
                "normal map {:?} is not the cell's {t}x{t} texels",
                normals.dimensions()
            ),
        ));
    }
    let texel = rec.extent.width().max(rec.extent.height()) / rec.texels.max(1) as f64;
    let ground = store.manifest.ortho_spacing.unwrap_or(0.0).max(texel);
    Ok(CellContext {
        base_texels: t,
        cos_slope: normals
            .pixels()
            .map(|p| normal_cos_slope(p.0).abs() as f32)
            .collect(),
        max_error: rec.max_error.max(0.0) as f32,
        existing_ground: ground as f32,
        texel_ground: texel as f32,
    })
}

/// Path of the cell's active normal map (for messages).
fn active_normal_path(rec: &CellRecord) -> String {
    rec.reparam
        .as_ref()
        .map_or(&rec.files.normal, |r| &r.files.normal)
        .path
        .clone()
}

/// What every level's projection of a run shares.
struct LevelRun<'a> {
    store: &'a Store,
    pyramids: &'a [PhotoPyramid<'a>],
    /// Per photo, its colour leveling.
    transforms: &'a [ColourTransform],
    opts: &'a ProjectOptions,
    buffers: &'a FootprintBuffers,
    bars: &'a [ProgressBar],
    finest: usize,
    /// TIN error (metres) per manifest cell, for the occlusion margin.
    cell_errors: Vec<f32>,
}

impl LevelRun<'_> {
    /// Casts and splats every photo onto the cells of `level` (using a photo's footprints
    /// cached from the leveling where they are of this level, and `first_scene`, the first
    /// photo's finest scene, if given) and returns the per-cell accumulators (indexed by
    /// manifest cell); adds to the photos' reports.
    fn project_level(
        &self,
        level: usize,
        occlusion: &mut [Option<OcclusionMap>],
        cached: &mut [Option<(usize, FootprintSet)>],
        first_scene: &mut Option<LevelScene>,
        reports: &mut [PhotoReport],
        timer: &mut StageTimer,
    ) -> Result<(Vec<Option<CellAccum>>, LevelSizing)> {
        let step = self.finest - level;
        let ncells = self.store.manifest.cells.len();
        let mut accs: Vec<Option<CellAccum>> = vec![None; ncells];
        // This level's scenes, one per photo, built once for the sizing and the main casts.
        let mut scenes: Vec<Option<LevelScene>> = (0..self.pyramids.len()).map(|_| None).collect();
        if let Some(scene) = first_scene.take() {
            if level == self.finest {
                scenes[0] = Some(scene);
            } else {
                *first_scene = Some(scene);
            }
        }
        let mut sizing = self.size_level(level, cached, &mut scenes)?;
        timer.lap(&format!("level {level}: texture sizes"));
        for (pi, pyr) in self.pyramids.iter().enumerate() {
            let (img, cam) = pyr.level(step);
            let cells = &self.store.manifest.cells;
            if level == self.finest
                && self.opts.confidence.occlusion_margin_px > 0.0
                && occlusion[pi].is_none()
            {
                occlusion[pi] = Some(self.occlusion_map(pyr, level, &mut scenes[pi])?);
                timer.lap(&format!("level {level} photo {pi}: occlusion map"));
            }
            let mut samples = PhotoSamples::new(
                img,
                [cam.fx, cam.fy],
                &self.transforms[pi],
                &self.opts.confidence,
                self.opts.colour_space,
            );
            if let Some(map) = &occlusion[pi] {
                let (_, full) = pyr.level(0);
                samples = samples.with_occlusion(
                    map,
                    (1u64 << step) as f32,
                    (full.fx * full.fy).sqrt(),
                    &self.cell_errors,
                    &self.opts.confidence,
                );
            }
            // This photo's deposits per manifest cell, filled batch by batch in row order.
            let mut pas: Vec<Option<PhotoAccum>> = vec![None; ncells];
            let counts = match cached[pi].take() {
                Some((l, fs)) if l == level => {
                    splat_batch(&fs, &mut pas, cells, &sizing.scales, level as u8, &samples);
                    let mut counts = FootprintSet::default();
                    counts.add_counts(&fs);
                    self.buffers.recycle(fs);
                    counts
                }
                other => {
                    cached[pi] = other;
                    let scene = match scenes[pi].take() {
                        Some(scene) => scene,
                        None => LevelScene::from_store(
                            self.store,
                            level as u8,
                            cam.position,
                            self.opts.ray,
                        )?,
                    };
                    let mut counts = FootprintSet::default();
                    for_each_footprint_batch_in(
                        self.buffers,
                        &scene,
                        &cam,
                        &self.opts.footprint,
                        |batch| {
                            splat_batch(
                                batch,
                                &mut pas,
                                cells,
                                &sizing.scales,
                                level as u8,
                                &samples,
                            );
                            counts.add_counts(batch);
                        },
                    );
                    counts
                }
            };
            timer.lap(&format!("level {level} photo {pi}: footprints and splat"));
            if level == self.finest {
                let r = &mut reports[pi];
                r.pixels_hit = counts.pixels_hit;
                r.rejected_silhouette = counts.rejected_silhouette;
                r.reconstructed_footprints = counts.reconstructed;
            }
            // the cells this photo reached, the largest accumulators first, one task each
            let mut work: Vec<_> = accs
                .iter_mut()
                .zip(pas)
                .zip(sizing.contexts.iter_mut())
                .enumerate()
                .filter(|(_, ((_, pa), _))| pa.is_some())
                .collect();
            work.sort_by_key(|(ci, ((_, pa), _))| {
                Reverse((pa.as_ref().map_or(0, |p| p.sums.allocated()), Reverse(*ci)))
            });
            let written: Vec<Result<u64>> = work
                .into_par_iter()
                .with_max_len(1)
                .map(|(ci, ((acc, pa), ctx))| match (acc.as_mut(), pa) {
                    (_, None) => Ok(0),
                    (Some(acc), Some(pa)) => Ok(acc.merge(&pa, pi as u16)),
                    (None, Some(pa)) => {
                        let ctx = match ctx.take() {
                            Some(c) => c,
                            None => cell_context(self.store, &cells[ci])?,
                        };
                        let (first, n) = CellAccum::from_photo(
                            pa,
                            pi as u16,
                            self.opts.blend,
                            ctx,
                            &self.opts.confidence,
                        );
                        *acc = Some(first);
                        Ok(n)
                    }
                })
                .collect();
            for w in written {
                reports[pi].texels_written += w?;
            }
            self.bars[pi].inc(1);
            timer.lap(&format!("level {level} photo {pi}: merge"));
        }
        Ok((accs, sizing))
    }

    /// The occlusion map of a photo ([`OcclusionMap`]): its pyramid image at half size (or
    /// the full one if it has no smaller image) cast onto the finest level `level` (with
    /// `scene`, built there if `None` and kept).
    fn occlusion_map(
        &self,
        pyr: &PhotoPyramid,
        level: usize,
        scene: &mut Option<LevelScene>,
    ) -> Result<OcclusionMap> {
        let step = OCCLUSION_STEP.min(pyr.steps());
        let (img, cam) = pyr.level(step);
        let scene = match scene {
            Some(s) => s,
            None => scene.insert(LevelScene::from_store(
                self.store,
                level as u8,
                cam.position,
                self.opts.ray,
            )?),
        };
        let fs = photo_footprints_in(self.buffers, scene, &cam, &self.opts.footprint);
        let map = OcclusionMap::from_footprints(
            &fs,
            img.width(),
            img.height(),
            (1u64 << step) as f32,
            self.opts.footprint.max_depth_jump,
        );
        self.buffers.recycle(fs);
        Ok(map)
    }

    /// The photo texture scale of every cell of `level` (indexed by manifest cell; 1 for
    /// other levels): from sizing casts of each photo's image two halvings coarser than the
    /// level's (or from its footprints cached from the leveling), [`SizingBins`] per cell,
    /// then [`choose_scales`] within this level's share of the budget (see
    /// [`PhotoTextureOptions`]). Fills `scenes` with the photos' scenes it built.
    fn size_level(
        &self,
        level: usize,
        cached: &[Option<(usize, FootprintSet)>],
        scenes: &mut [Option<LevelScene>],
    ) -> Result<LevelSizing> {
        let cells = &self.store.manifest.cells;
        let topt = &self.opts.texture;
        let mut out = LevelSizing {
            scales: vec![1; cells.len()],
            contexts: vec![None; cells.len()],
            ..LevelSizing::default()
        };
        if !topt.photo_driven {
            return Ok(out);
        }
        let step = self.finest - level;
        // each photo's footprints for the sizing: cached from the leveling, or cast from the
        // image two halvings coarser (side scale: coarse pixel side to this level's)
        let mut sets: Vec<(std::borrow::Cow<FootprintSet>, f32, f64)> = Vec::new();
        for (pi, pyr) in self.pyramids.iter().enumerate() {
            let (_, cam) = pyr.level(step);
            let focal = (cam.fx * cam.fy).sqrt();
            if let Some((l, fs)) = &cached[pi] {
                if *l == level {
                    sets.push((std::borrow::Cow::Borrowed(fs), 1.0, focal));
                    continue;
                }
            }
            let scene = match scenes[pi].take() {
                Some(s) => s,
                None => {
                    LevelScene::from_store(self.store, level as u8, cam.position, self.opts.ray)?
                }
            };
            let coarse = (step + SIZING_STEPS).min(pyr.steps());
            let (_, ccam) = pyr.level(coarse);
            let fs = photo_footprints_in(self.buffers, &scene, &ccam, &self.opts.footprint);
            sets.push((
                std::borrow::Cow::Owned(fs),
                0.5f32.powi((coarse - step) as i32),
                focal,
            ));
            scenes[pi] = Some(scene);
        }
        // the resolution rule's view of every cell the photos reach
        let mut seen = vec![false; cells.len()];
        for (fs, ..) in &sets {
            for cf in &fs.cells {
                if let Some(v) = seen.get_mut(cf.cell as usize) {
                    *v = cells[cf.cell as usize].level as usize == level;
                }
            }
        }
        let contexts: Vec<Option<CellContext>> = (0..cells.len())
            .into_par_iter()
            .map(|ci| {
                if seen[ci] {
                    cell_context(self.store, &cells[ci]).map(Some)
                } else {
                    Ok(None)
                }
            })
            .collect::<Result<_>>()?;
        // every footprint counts as a delivered pixel; only those the blend lets dominate
        // size the texture
        let weights = &self.opts.confidence;
        let mut bins: Vec<Option<SizingBins>> = vec![None; cells.len()];
        for (fs, side_scale, focal) in &sets {
            for cf in &fs.cells {
                let ci = cf.cell as usize;
                let Some(ctx) = contexts.get(ci).and_then(Option::as_ref) else {
                    continue;
                };
                let b = bins[ci].get_or_insert_with(SizingBins::default);
                for fp in cf.iter() {
                    b.add(
                        fp,
                        ctx.base_texels,
                        *side_scale,
                        resolves_more(ctx, fp, *focal, weights),
                    );
                }
            }
        }
        for (fs, _, _) in sets {
            if let std::borrow::Cow::Owned(fs) = fs {
                self.buffers.recycle(fs);
            }
        }
        out.contexts = contexts;
        let level_cells: Vec<usize> = (0..cells.len())
            .filter(|&i| cells[i].level as usize == level)
            .collect();
        let requests: Vec<SizeRequest> = level_cells
            .iter()
            .map(|&ci| {
                let base = active_texels(&cells[ci]);
                let max_scale = (topt.max_texels / base.max(1)).max(1);
                match &bins[ci] {
                    Some(b) => SizeRequest {
                        base_texels: base,
                        scale: b.wanted_scale(
                            max_scale,
                            topt.texels_per_pixel,
                            base,
                            topt.texels_per_delivered,
                        ),
                        covered: b.covered() as f64 / (SIZING_BINS * SIZING_BINS) as f64,
                    },
                    None => SizeRequest {
                        base_texels: base,
                        scale: 1,
                        covered: 0.0,
                    },
                }
            })
            .collect();
        // the finest level's share is 3/4 of the budget, each coarser one a quarter of that
        let share = 0.75 * 0.25f64.powi(step as i32);
        out.budget_bytes = (topt.budget_bytes as f64 * share) as u64;
        let granted = choose_scales(&requests, out.budget_bytes);
        for ((&ci, &g), r) in level_cells.iter().zip(&granted).zip(&requests) {
            out.scales[ci] = g;
            out.wanted += (r.scale > 1) as u64;
            out.upsized += (g > 1) as u64;
        }
        Ok(out)
    }
}

/// Pyramid halvings between the full-resolution photo and the image its occlusion map is
/// cast from (edges located to a map pixel, 2 full-resolution pixels).
const OCCLUSION_STEP: usize = 1;

/// Pyramid halvings between a level's image and its sizing cast's.
const SIZING_STEPS: usize = 2;

/// The photo texture sizes of one level.
#[derive(Clone, Debug, Default)]
struct LevelSizing {
    /// Per manifest cell, the factor of its photo texture's side over its active texture's.
    scales: Vec<u32>,
    /// Cells that wanted a larger photo texture.
    wanted: u64,
    /// Cells that got one.
    upsized: u64,
    /// This level's share of the budget, bytes.
    budget_bytes: u64,
    /// The cells' resolution contexts loaded for the sizing (indexed by manifest cell).
    contexts: Vec<Option<CellContext>>,
}

/// Whether the photo pixel of footprint `fp` (cast for an image of focal length `focal`
/// pixels) would get weight against cell `ctx`'s existing texture by the resolution rule
/// (the texel under its centre; [`ConfidenceParams::resolution_weight`] at least 1/2: the
/// photo dominates there).
fn resolves_more(
    ctx: &CellContext,
    fp: &crate::photo::PixelFootprint,
    focal: f64,
    weights: &ConfidenceParams,
) -> bool {
    let c = fp
        .corners
        .iter()
        .fold([0.0f32; 2], |a, p| [a[0] + 0.25 * p[0], a[1] + 0.25 * p[1]]);
    let n = ctx.base_texels as f32;
    if !(c[0] >= 0.0 && c[1] >= 0.0 && c[0] < n && c[1] < n) {
        return false;
    }
    let b = c[1] as usize * ctx.base_texels as usize + c[0] as usize;
    let g = 1.0 / fp.cos_view.max(1e-3);
    let r = fp.distance / focal as f32 * g;
    let ratio = ctx.existing_resolution(b) as f64 / ctx.photo_resolution(b, [r, g]) as f64;
    weights.resolution_weight(ratio) >= 0.5
}

/// Blends and writes the photo textures of every cell of `level` from its accumulators
/// `accs` (indexed by manifest cell): the level's report and the new cell records. Each
/// cell's accumulator is dropped as soon as the cell is written, so its texel records go
/// back to the spare chunks (`photo/texel_tiles.rs`) for the next level's splat,
/// which runs alongside, instead of that level faulting in fresh pages.
fn finish_level(
    store: &Store,
    level: usize,
    mut accs: Vec<Option<CellAccum>>,
    sizing: &LevelSizing,
    opts: &ProjectOptions,
    writer: &BackgroundWriter,
) -> Result<(PhotoLevelReport, Vec<(usize, PhotoCellRecord)>, Vec<u64>)> {
    let cells = &store.manifest.cells;
    let level_cells: Vec<usize> = (0..cells.len())
        .filter(|&i| cells[i].level as usize == level)
        .collect();
    let mut work: Vec<(usize, usize, Option<CellAccum>)> = level_cells
        .iter()
        .enumerate()
        .map(|(k, &ci)| (k, ci, accs.get_mut(ci).and_then(Option::take)))
        .collect();
    drop(accs);
    // the largest accumulators first, one task each (a 2048² cell takes as long as many
    // small ones; in index order it could start last); the results back in cell order
    work.sort_by_key(|(k, _, acc)| {
        Reverse((acc.as_ref().map_or(0, CellAccum::allocated), Reverse(*k)))
    });
    let mut results: Vec<(usize, Result<CellOutcome>)> = work
        .into_par_iter()
        .with_max_len(1)
        .map(|(k, ci, acc)| {
            (
                k,
                finish_cell(store, &cells[ci], acc.as_ref(), opts, writer),
            )
        })
        .collect();
    results.sort_by_key(|(k, _)| *k);
    let results = results.into_iter().map(|(_, r)| r);
    let mut lr = PhotoLevelReport {
        level: level as u8,
        wanted_larger: sizing.wanted,
        upsized_cells: sizing.upsized,
        texture_budget_bytes: sizing.budget_bytes,
        ..PhotoLevelReport::default()
    };
    let mut records = Vec::new();
    let mut supplied: Vec<u64> = Vec::new();
    for (&ci, r) in level_cells.iter().zip(results) {
        let o = r?;
        if supplied.len() < o.supplied_base.len() {
            supplied.resize(o.supplied_base.len(), 0);
        }
        for (s, n) in supplied.iter_mut().zip(&o.supplied_base) {
            *s += n;
        }
        lr.steep_texels += o.steep_texels;
        if let Some(rec) = o.record {
            lr.cells_with_photo += 1;
            lr.photo_texture_bytes += texture_bytes(rec.texels);
            lr.photo_texels += o.photo_base;
            lr.steep_photo_texels += o.steep_photo_base;
            records.push((ci, rec));
        }
    }
    Ok((lr, records, supplied))
}

/// Most footprints (over all photos) kept from the leveling casts for the main loop
/// (about 56 bytes each).
const MAX_CACHED_FOOTPRINTS: usize = 8 << 20;

/// The leveling transform of one photo, its sample count and the footprints it was fitted
/// on with their level (see the module docs).
fn estimate_leveling(
    store: &Store,
    pyr: &PhotoPyramid,
    finest: usize,
    opts: &ProjectOptions,
    buffers: &FootprintBuffers,
) -> Result<(ColourTransform, usize, Option<(usize, FootprintSet)>)> {
    let k_est = leveling_step(pyr, finest, opts);
    let attempts: Vec<usize> = if k_est > 0 { vec![k_est, 0] } else { vec![0] };
    for step in attempts {
        let level = finest - step;
        let (img, cam) = pyr.level(step);
        let scene = LevelScene::from_store(store, level as u8, cam.position, opts.ray)?;
        let fs = photo_footprints_in(buffers, &scene, &cam, &opts.footprint);
        drop(scene);
        let cells = &store.manifest.cells;
        // (the leveling compares sRGB values at the existing texture's size)
        let samples = PhotoSamples::new(
            img,
            [cam.fx, cam.fy],
            &ColourTransform::IDENTITY,
            &opts.confidence,
            ColourSpace::Srgb,
        );
        let mut pas: Vec<Option<PhotoAccum>> = vec![None; cells.len()];
        splat_batch(&fs, &mut pas, cells, &[], level as u8, &samples);
        let parts: Vec<Result<ColourPairs>> = pas
            .par_iter()
            .enumerate()
            .filter_map(|(ci, pa)| pa.as_ref().map(|pa| (&cells[ci], pa)))
            .map(|(rec, pa)| {
                let existing = store.read_active_texture(rec)?;
                let ctx = cell_context(store, rec)?;
                check_size(
                    store,
                    rec,
                    existing.dimensions(),
                    (ctx.base_texels, ctx.base_texels),
                )?;
                let mut pairs = ColourPairs::default();
                collect_pairs(pa, &existing, &ctx, &opts.leveling, &mut pairs);
                Ok(pairs)
            })
            .collect();
        let mut all = ColourPairs::default();
        for p in parts {
            let p = p?;
            all.photo.extend(p.photo);
            all.existing.extend(p.existing);
        }
        let (t, n) = fit_colour_transform(&all, &opts.leveling);
        tracing::debug!(
            "project: leveling on level {level} (pyramid step {step}): {} samples, {n} used",
            all.photo.len()
        );
        if n > 0 {
            return Ok((t, n, Some((level, fs))));
        }
        buffers.recycle(fs);
    }
    Ok((ColourTransform::IDENTITY, 0, None))
}

/// The pyramid step the leveling of `pyr` is fitted on first: the first with at most
/// `leveling_max_pixels` (at most `finest`).
fn leveling_step(pyr: &PhotoPyramid, finest: usize, opts: &ProjectOptions) -> usize {
    let (w, h) = pyr.level(0).0.dimensions();
    let mut k = 0;
    while k < finest && (w as u64 >> k) * (h as u64 >> k) > opts.leveling_max_pixels {
        k += 1;
    }
    k
}

/// Errors unless the active texture and normal map have the cell's active texture size.
fn check_size(store: &Store, rec: &CellRecord, tex: (u32, u32), nrm: (u32, u32)) -> Result<()> {
    let t = active_texels(rec);
    if tex != (t, t) || nrm != (t, t) {
        let f = rec
            .reparam
            .as_ref()
            .map_or(&rec.files.texture, |r| &r.files.texture);
        return Err(Error::store(
            store.dir.join(&f.path),
            format!("texture {tex:?} or normal map {nrm:?} is not the cell's {t}x{t} texels"),
        ));
    }
    Ok(())
}

/// A finished cell: its photo record (if it got photo colour) and its steep texel count
/// (in texels of its active texture).
struct CellOutcome {
    record: Option<PhotoCellRecord>,
    steep_texels: u64,
    /// Covered steep texels with mostly photo colour, in texels of the active texture
    /// (the photo texture's count divided by the squared scale).
    steep_photo_base: u64,
    /// Covered texels with mostly photo colour, likewise.
    photo_base: u64,
    /// Per photo, the covered texels it supplies (mostly photo colour, this photo the
    /// heaviest), in texels of the active texture.
    supplied_base: Vec<u64>,
}

/// Which texel centres of a `texels × texels` texture of cell `rec` (active layout) lie on a
/// surface triangle in texture space (row-major).
fn covered_mask(store: &Store, rec: &CellRecord, texels: u32) -> Result<Vec<bool>> {
    let mesh = store.read_active_mesh(rec)?;
    let ns = (mesh.surface_vertices as usize).min(mesh.positions.len());
    let positions: Vec<[f64; 3]> = mesh.positions[..ns]
        .iter()
        .map(|p| p.map(f64::from))
        .collect();
    let uvs: Vec<[f64; 2]> = (0..ns)
        .map(|i| texcoord(rec, &mesh, i).map(f64::from))
        .collect();
    let triangles: Vec<[u32; 3]> = mesh
        .surface()
        .iter()
        .copied()
        .filter(|t| t.iter().all(|&k| (k as usize) < ns))
        .collect();
    Ok(texel_stretch(&positions, &triangles, &uvs, texels, 1.0)
        .iter()
        .map(|s| !s.is_nan())
        .collect())
}

/// Encodes `img` as PNG and queues it for `dir/rel` on `writer`.
fn submit_png<P, C>(
    writer: &BackgroundWriter,
    dir: &Path,
    rel: &str,
    img: &image::ImageBuffer<P, C>,
    compression: PngCompression,
) -> Result<FileRef>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    C: std::ops::Deref<Target = [P::Subpixel]>,
{
    writer.submit(rel, encode_png(&dir.join(rel), img, compression)?)
}

fn finish_cell(
    store: &Store,
    rec: &CellRecord,
    acc: Option<&CellAccum>,
    opts: &ProjectOptions,
    writer: &BackgroundWriter,
) -> Result<CellOutcome> {
    let cos_steep = STEEP_SLOPE_DEG.to_radians().cos() as f32;
    let Some(acc) = acc else {
        let normals = store.read_active_normal_map(rec)?;
        let covered = covered_mask(store, rec, active_texels(rec))?;
        let steep_texels = covered
            .iter()
            .zip(normals.pixels())
            .filter(|(c, n)| **c && (normal_cos_slope(n.0) as f32) < cos_steep)
            .count() as u64;
        return Ok(CellOutcome {
            record: None,
            steep_texels,
            steep_photo_base: 0,
            photo_base: 0,
            supplied_base: Vec::new(),
        });
    };
    let existing = store.read_active_texture(rec)?;
    let ctx = &acc.context;
    check_size(
        store,
        rec,
        existing.dimensions(),
        (ctx.base_texels, ctx.base_texels),
    )?;
    // (the active texture's masks, looked up for the photo texture's texels: these masks only
    // feed the texel counts)
    let covered = covered_mask(store, rec, ctx.base_texels)?;
    let steep: Vec<bool> = covered
        .iter()
        .enumerate()
        .map(|(b, &c)| c && ctx.cos_at(b) < cos_steep)
        .collect();
    let b = blend_cell(
        &existing,
        acc,
        &opts.confidence,
        opts.colour_space,
        &covered,
        &steep,
    );
    let area = (acc.scale as u64).pow(2);
    let steep_texels = b.steep_texels / area;
    let present = b
        .blocks
        .present(acc.texels)
        .map_err(|e| Error::store(&store.dir, e))?;
    if !present.contains(&true) {
        return Ok(CellOutcome {
            record: None,
            steep_texels,
            steep_photo_base: 0,
            photo_base: 0,
            supplied_base: Vec::new(),
        });
    }
    let stem = cell_stem(rec.level, rec.x, rec.y);
    let record = PhotoCellRecord {
        texels: acc.texels,
        texture: submit_png(
            writer,
            &store.dir,
            &format!("{stem}.photo.png"),
            &pack(&b.texture, b.block_side, &present),
            opts.png_compression,
        )?,
        confidence: submit_png(
            writer,
            &store.dir,
            &format!("{stem}.photo.conf.png"),
            &pack(&b.confidence, b.block_side, &present),
            opts.png_compression,
        )?,
        photo_texels: b.photo_texels,
        steep_texels: b.steep_texels,
        steep_photo_texels: b.steep_photo_texels,
        blocks: Some(b.blocks),
    };
    Ok(CellOutcome {
        record: Some(record),
        steep_texels,
        steep_photo_base: b.steep_photo_texels / area,
        photo_base: b.photo_texels / area,
        supplied_base: b.supplied.iter().map(|n| n / area).collect(),
    })
}
