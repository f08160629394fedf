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

use rayon::prelude::*;

use super::write_stats;
use crate::cells::CellKey;
use crate::colour::ColourSpace;
use crate::error::{Error, Result};
use crate::fsutil::{PngCompression, encode_png};
use crate::photo::{
    BlendMode, CellAccum, CellContext, CellFootprints, ColourPairs, ColourTransform,
    ConfidenceParams, FootprintBuffers, FootprintOptions, FootprintSet, LevelingParams,
    OcclusionMap, PhotoAccum, PhotoInput, PhotoPyramid, PhotoSamples, SIZING_BINS, SizeRequest,
    SizingBins, blend_cell, choose_scales, collect_pairs, fit_colour_transform,
    for_each_footprint_batch_rows_in, normal_cos_slope, photo_footprints_in, texture_bytes,
};
use crate::progress::{ProgressSink, ProgressTask};
use crate::raycast::{LevelScene, RayAccel};
use crate::stats::texel_stretch;
use crate::store::{
    BackgroundWriter, CameraPlacement, CellRecord, FileRef, PhotoCellRecord, PhotoLevelReport,
    PhotoReport, PhotoSettings, Store, active_texels, cell_stem,
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
    /// Where progress is reported (default: nowhere): a task per photo.
    pub progress: ProgressSink,
    /// Project onto the relief surface (the TIN plus each orthographic cell's relief map,
    /// `photo::CellRelief`, slopes up to 75.5°), as the renderer draws it; `false`: onto the
    /// TIN. Reparameterized cells are projected onto the TIN either way. Default on.
    pub onto_relief: bool,
    /// Leave out the uniform borders of each photo ([`crate::photo::uniform_border`]: a
    /// scan's frame, a stabilised frame's padding, a banner), reported. Default on.
    pub mask_borders: bool,
    /// Leave out surface points nearer to the camera than this (metres; foreground people,
    /// rocks, roofs), >= 0. Default 0.
    pub min_distance_m: f64,
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
            progress: ProgressSink::none(),
            onto_relief: true,
            mask_borders: true,
            min_distance_m: 0.0,
        }
    }
}

/// The photo stage's scene of `level` seen from `position`: [`LevelScene::from_store`], with
/// the relief maps loaded when `opts.onto_relief`.
pub(crate) fn level_scene(
    store: &Store,
    level: u8,
    position: glam::DVec3,
    opts: &ProjectOptions,
) -> Result<LevelScene> {
    let mut scene = LevelScene::from_store(store, level, position, opts.ray)?;
    if opts.onto_relief {
        scene.load_reliefs(store)?;
    }
    Ok(scene)
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
    /// The largest screen-space error (pixels) at which views will draw the store's cells
    /// that have finer children, > 0. A renderer refines such a cell while its error `ε`
    /// projects to more than this, so it draws the cell only from where a texel of `ε /
    /// coarse_sse_px` metres or less covers at most a pixel: finer detail is never shown and
    /// is not made ([`coarse_scale_cap`]). Default 2 (four times the 0.5 px cliffmap's
    /// renderer and exported page use); infinite: coarser levels are sized like the finest
    /// (e.g. for viewers at CesiumJS's default of 16 px).
    pub coarse_sse_px: f64,
}

/// The largest photo texture scale (a power of two, ≥ 1) worth giving a cell with finer
/// children, error `error` metres and an active texture of `active_texel` metres per texel
/// (the ground size, the finest a texel is on the surface), for views that draw it at no
/// more than `sse_px` of screen-space error: the texel must stay at least `error / sse_px`
/// metres (docs/projection.md, "Texture sizes"). `u32::MAX` (no cap) for an infinite
/// `sse_px` or a cell without a positive error.
pub fn coarse_scale_cap(error: f64, active_texel: f64, sse_px: f64) -> u32 {
    if !(error > 0.0 && active_texel > 0.0 && sse_px.is_finite() && sse_px > 0.0) {
        return u32::MAX;
    }
    let ratio = active_texel * sse_px / error;
    if ratio < 2.0 {
        return 1;
    }
    1u32 << (ratio.log2().floor().min(16.0) as u32)
}

impl Default for PhotoTextureOptions {
    fn default() -> Self {
        PhotoTextureOptions {
            photo_driven: true,
            max_texels: 2048,
            budget_bytes: 1 << 30,
            texels_per_pixel: 1.0,
            texels_per_delivered: f64::INFINITY,
            coarse_sse_px: 2.0,
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
        if !(self.coarse_sse_px > 0.0) {
            return Err(Error::BadOption(format!(
                "--coarse-sse must be a positive number of pixels (or inf), got {}",
                self.coarse_sse_px
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

/// Runs `project` on the store in `dir` with `photos` (see the module docs (`src/pipeline/project/mod.rs`)).
/// Errors on an unreadable store, a photo whose image size differs from its camera's, or a
/// failed write; a photo that sees no terrain only logs a warning.
pub fn project_store(
    dir: &Path,
    photos: &[PhotoInput],
    opts: &ProjectOptions,
) -> Result<ProjectReport> {
    check_project_options(photos, opts)?;
    let mut timer = StageTimer::new();
    let _lock = crate::store::StoreLock::acquire(dir, "cliffmap project")?;
    let mut store = Store::open(dir)?;
    check_photo_sizes(photos)?;
    let opts = &options_for_store(&store, opts);
    let placements = check_camera_placements(&store, photos)?;
    let levels = store.manifest.quadtree.levels as usize;
    let finest = levels.saturating_sub(1);
    timer.lap("open store");
    let pyramids: Vec<PhotoPyramid> = photos
        .iter()
        .map(|p| PhotoPyramid::new_in(&p.image, p.camera, finest + SIZING_STEPS, opts.colour_space))
        .collect();
    let masks: Vec<PhotoMasks> = photos
        .iter()
        .zip(&pyramids)
        .map(|(p, pyr)| PhotoMasks::of(p, pyr.steps(), opts.mask_borders))
        .collect();
    timer.lap("photo pyramids and masks");

    let steps = levels as u64 + opts.level_colours as u64;
    let bars: Vec<Box<dyn ProgressTask>> = photos
        .iter()
        .map(|p| opts.progress.task(steps, &p.name))
        .collect();
    let mut reports: Vec<PhotoReport> = photos.iter().map(|p| empty_report(p, dir)).collect();
    for (r, m) in reports.iter_mut().zip(&masks) {
        m.report(r);
    }
    // Scratch memory of all casts of this run.
    let buffers = FootprintBuffers::default();
    let LevelStart {
        transforms,
        mut cached,
        mut first_scene,
    } = level_colours(
        &store,
        &pyramids,
        &masks,
        opts,
        &buffers,
        &mut reports,
        &bars,
    )?;
    timer.lap(if opts.level_colours {
        "colour leveling (alongside the first finest scene)"
    } else {
        "first finest scene"
    });

    // The photo textures are written on a thread of their own (the fsyncs do not hold up
    // the workers); all are on disk before the manifest refers to them.
    let writer = BackgroundWriter::new(dir);
    let run = LevelRun {
        store: &store,
        pyramids: &pyramids,
        masks: &masks,
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
        writer: &writer,
    };
    let (records, level_reports) = project_levels(
        &run,
        &mut cached,
        &mut first_scene,
        &mut reports,
        &mut timer,
        &writer,
    )?;
    writer.finish()?;
    timer.lap("photo textures on disk");
    for pb in &bars {
        pb.finish();
    }
    explain_photos(&store, &placements, &mut reports);

    let cells_written = records.iter().filter(|r| r.is_some()).count();
    for (c, r) in store.manifest.cells.iter_mut().zip(records) {
        c.photo = r;
    }
    let settings = photo_settings(opts, reports, level_reports);
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

/// `opts` as they apply to `store`: no colour leveling where its textures were derived from
/// the DEM (a tint is no colour to level a photo towards; logged).
fn options_for_store(store: &Store, opts: &ProjectOptions) -> ProjectOptions {
    let mut o = opts.clone();
    if o.level_colours && !store.manifest.textures_hold_an_image() {
        tracing::info!(
            "project: no colour leveling: the store's textures were derived from the DEM \
             (built without an ortho)"
        );
        o.level_colours = false;
    }
    o
}

/// Refuses invalid confidence or texture options and more photos than a run can number.
fn check_project_options(photos: &[PhotoInput], opts: &ProjectOptions) -> Result<()> {
    opts.confidence.validate()?;
    opts.texture.validate()?;
    if !(opts.min_distance_m >= 0.0 && opts.min_distance_m.is_finite()) {
        return Err(Error::BadOption(format!(
            "--min-distance must be a finite number of metres >= 0, got {}",
            opts.min_distance_m
        )));
    }
    if photos.len() >= u16::MAX as usize {
        return Err(Error::BadOption(format!(
            "at most {} photos per run, got {}",
            u16::MAX - 1,
            photos.len()
        )));
    }
    Ok(())
}

/// Refuses a photo whose image size differs from its camera's, naming the image.
fn check_photo_sizes(photos: &[PhotoInput]) -> Result<()> {
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
    Ok(())
}

/// A photo's report before anything is projected.
fn empty_report(p: &PhotoInput, dir: &Path) -> PhotoReport {
    PhotoReport {
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
        pixels_supplying: 0,
        pixels_outweighed: 0,
        pixels_dropped: 0,
        pixels_masked: 0,
        pixels_near: 0,
        border_masked: Vec::new(),
        warnings: Vec::new(),
    }
}

/// What the level loop starts from: each photo's colour transform, the footprints the
/// leveling cast (kept while they are few), and the first photo's finest scene if it was
/// built alongside.
struct LevelStart {
    transforms: Vec<ColourTransform>,
    cached: Vec<Option<(usize, FootprintSet)>>,
    first_scene: Option<LevelScene>,
}

/// Fits each photo's colour leveling (when `opts.level_colours`) while the first photo's
/// finest scene is built (the leveling leaves cores idle in its smaller steps; the scene is
/// the first the level loop needs, unless the leveling casts the finest level itself: a
/// photo of at most `leveling_max_pixels`). Records the transforms in `reports`.
fn level_colours(
    store: &Store,
    pyramids: &[PhotoPyramid],
    masks: &[PhotoMasks],
    opts: &ProjectOptions,
    buffers: &FootprintBuffers,
    reports: &mut [PhotoReport],
    bars: &[Box<dyn ProgressTask>],
) -> Result<LevelStart> {
    let finest = (store.manifest.quadtree.levels as usize).saturating_sub(1);
    let mut transforms = vec![ColourTransform::IDENTITY; pyramids.len()];
    // Footprints cast for the leveling are kept for the main loop while they are few.
    let mut cached: Vec<Option<(usize, FootprintSet)>> = vec![None; pyramids.len()];
    let mut cached_len = 0usize;
    let prebuild = !opts.level_colours
        || pyramids
            .first()
            .is_some_and(|pyr| leveling_step(pyr, finest, opts) > 0);
    let (leveled, first_scene) = rayon::join(
        || -> Result<Vec<leveling::Leveled>> {
            if !opts.level_colours {
                return Ok(Vec::new());
            }
            pyramids
                .iter()
                .zip(masks)
                .map(|(pyr, m)| estimate_leveling(store, pyr, m, finest, opts, buffers))
                .collect()
        },
        || {
            let first = pyramids.first().filter(|_| prebuild);
            first
                .map(|pyr| level_scene(store, finest as u8, pyr.level(0).1.position, opts))
                .transpose()
        },
    );
    for (i, (t, n, fs)) in leveled?.into_iter().enumerate() {
        if let Some((level, fs)) = fs
            && cached_len + fs.len() <= MAX_CACHED_FOOTPRINTS
        {
            cached_len += fs.len();
            cached[i] = Some((level, fs));
        }
        transforms[i] = t;
        reports[i].colour_gain = t.gain;
        reports[i].colour_offset = t.offset;
        reports[i].colour_samples = n as u64;
        bars[i].inc(1);
    }
    Ok(LevelStart {
        transforms,
        cached,
        first_scene: first_scene?,
    })
}

/// Projects every level, finest first; the cells of each level are blended and written
/// while the next coarser level is cast and splatted (levels are independent, so the output
/// is the same as level by level). Returns each manifest cell's new photo record and the
/// levels' reports (coarsest first).
fn project_levels(
    run: &LevelRun,
    cached: &mut [Option<(usize, FootprintSet)>],
    first_scene: &mut Option<LevelScene>,
    reports: &mut [PhotoReport],
    timer: &mut StageTimer,
    writer: &BackgroundWriter,
) -> Result<(Vec<Option<PhotoCellRecord>>, Vec<PhotoLevelReport>)> {
    let store = run.store;
    let opts = run.opts;
    let levels = store.manifest.quadtree.levels as usize;
    let mut records: Vec<Option<PhotoCellRecord>> = vec![None; store.manifest.cells.len()];
    let mut level_reports = Vec::with_capacity(levels);
    let mut pending: Option<(usize, LevelProjection)> = None;
    // per photo, its occlusion map (made at the finest level when there are several
    // photos, used by every level)
    let mut occlusion: Vec<Option<OcclusionMap>> = run.pyramids.iter().map(|_| None).collect();
    for level in (0..levels).rev().map(Some).chain([None]) {
        let (finished, projected) = rayon::join(
            || {
                pending.take().map(|(l, p)| {
                    let t = std::time::Instant::now();
                    (
                        l,
                        finish_level(store, l, p, opts, writer),
                        t.elapsed().as_secs_f64(),
                    )
                })
            },
            || -> Result<Option<(usize, LevelProjection)>> {
                let Some(level) = level else { return Ok(None) };
                Ok(Some((
                    level,
                    run.project_level(level, &mut occlusion, cached, first_scene, reports, timer)?,
                )))
            },
        );
        if let Some((l, result, secs)) = finished {
            let (lr, recs, supplied, written) = result?;
            for (ci, rec) in recs {
                records[ci] = Some(rec);
            }
            for (r, n) in reports.iter_mut().zip(supplied) {
                r.texels_supplied += n;
            }
            for (r, n) in reports.iter_mut().zip(written) {
                r.texels_written += n;
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
    level_reports.sort_by_key(|r| r.level);
    Ok((records, level_reports))
}

/// Each photo's camera against the terrain; refuses a camera below the surface (by more
/// than the TIN's error there), naming the photo: it would see only back faces.
fn check_camera_placements(store: &Store, photos: &[PhotoInput]) -> Result<Vec<CameraPlacement>> {
    photos
        .iter()
        .map(|p| {
            let placement = CameraPlacement::of(store, &p.camera)?;
            if placement.is_underground() {
                return Err(Error::bad_input(
                    &p.image_path,
                    format!(
                        "its camera is {}: a camera below the ground sees no terrain to \
                         texture (a camera fitted without the DEM can end up there; check \
                         its position and height datum)",
                        placement.describe()
                    ),
                ));
            }
            Ok(placement)
        })
        .collect()
}

/// A photo whose terrain pixels mostly did not reach a texture gets a warning.
pub const LOW_SUPPLY_SHARE: f64 = 0.25;

/// Records (and logs) a warning for each photo that supplied little, with the reasons the
/// counts give: no terrain seen (and where the camera stands), terrain pixels outweighed by
/// a sharper existing texture, on silhouettes, incomplete, or outweighed by other photos.
fn explain_photos(store: &Store, placements: &[CameraPlacement], reports: &mut [PhotoReport]) {
    for (r, place) in reports.iter_mut().zip(placements) {
        if let Some(w) = supply_warning(store, place, r) {
            tracing::warn!("photo {}: {w}", r.name);
            r.warnings.push(w);
        }
    }
}

/// The warning for photo report `r` (camera at `place`), if it supplied little.
fn supply_warning(store: &Store, place: &CameraPlacement, r: &PhotoReport) -> Option<String> {
    if r.pixels_hit == 0 {
        return Some(format!(
            "it sees no terrain of the store (no texels written); its camera is {}",
            place.describe()
        ));
    }
    let share = r.supplying_share();
    let pct = |n: u64| 100.0 * n as f64 / r.pixels_hit as f64;
    if share < LOW_SUPPLY_SHARE {
        let existing = match store.manifest.ortho_spacing {
            Some(g) => format!("the existing texture (an ortho of {g:.2} m)"),
            None => "the existing texture".to_string(),
        };
        return Some(format!(
            "only {:.1} % of its {} terrain pixels supplied a texture: {:.1} % where {existing} \
             resolves the surface as finely or more, {:.1} % masked, {:.1} % nearer than \
             --min-distance, {:.1} % on silhouette edges, {:.1} % with incomplete footprints",
            100.0 * share,
            r.pixels_hit,
            pct(r.pixels_outweighed),
            pct(r.pixels_masked),
            pct(r.pixels_near),
            pct(r.rejected_silhouette),
            pct(r.pixels_dropped),
        ));
    }
    if r.texels_supplied == 0 {
        return Some(format!(
            "{:.1} % of its terrain pixels could supply a texture, but sharper photos \
             outweighed it on every texel",
            100.0 * share
        ));
    }
    None
}

/// The run's settings and reports as the manifest records them.
fn photo_settings(
    opts: &ProjectOptions,
    reports: Vec<PhotoReport>,
    levels: Vec<PhotoLevelReport>,
) -> PhotoSettings {
    PhotoSettings {
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
        levels,
    }
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

mod finish;
mod level;
mod leveling;
mod masks;

use finish::{CellOutcome, finish_cell, finish_level, read_checked_active};
use level::{LevelProjection, LevelRun, SIZING_STEPS, cell_context, splat_batch};
use leveling::{MAX_CACHED_FOOTPRINTS, estimate_leveling, leveling_step};
use masks::PhotoMasks;

#[cfg(test)]
mod tests {
    use super::coarse_scale_cap;

    #[test]
    fn texture_options_out_of_range_are_refused_by_name() {
        use super::PhotoTextureOptions;
        assert!(PhotoTextureOptions::default().validate().is_ok());
        let inf = PhotoTextureOptions {
            coarse_sse_px: f64::INFINITY,
            ..PhotoTextureOptions::default()
        };
        assert!(inf.validate().is_ok());
        for sse in [0.0, -1.0, f64::NAN] {
            let bad = PhotoTextureOptions {
                coarse_sse_px: sse,
                ..PhotoTextureOptions::default()
            };
            let e = bad.validate().unwrap_err().to_string();
            assert!(e.contains("--coarse-sse"), "{e}");
        }
        let e = PhotoTextureOptions {
            max_texels: 3000,
            ..PhotoTextureOptions::default()
        }
        .validate()
        .unwrap_err()
        .to_string();
        assert!(e.contains("--max-photo-texels"), "{e}");
    }

    #[test]
    fn coarse_cap_keeps_texels_at_least_the_error_over_the_sse() {
        // a cell of 1 m error, 1.5 m texels, drawn at up to 2 px: texels of >= 0.5 m, so 2x
        assert_eq!(coarse_scale_cap(1.0, 1.5, 2.0), 2);
        // at 0.5 px: texels of >= 2 m, so none finer than the active texture
        assert_eq!(coarse_scale_cap(1.0, 1.5, 0.5), 1);
        // at 16 px (CesiumJS's default): >= 6.25 cm, 24x -> 16x
        assert_eq!(coarse_scale_cap(1.0, 1.5, 16.0), 16);
        // exactly on a power of two
        assert_eq!(coarse_scale_cap(0.25, 1.0, 1.0), 4);
        for (e, t, s) in [(0.3, 0.7, 2.0), (2.0, 3.0, 0.5), (0.01, 1.0, 4.0)] {
            let c = coarse_scale_cap(e, t, s);
            assert!(c.is_power_of_two());
            assert!(c == 1 || t / (c as f64) >= e / s, "{e} {t} {s}: {c}");
            assert!(
                t / ((2 * c) as f64) < e / s,
                "{e} {t} {s}: {c} is not the largest"
            );
        }
        // no cap: infinite SSE, no error, bad input
        assert_eq!(coarse_scale_cap(1.0, 1.5, f64::INFINITY), u32::MAX);
        assert_eq!(coarse_scale_cap(0.0, 1.5, 2.0), u32::MAX);
        assert_eq!(coarse_scale_cap(f64::NAN, 1.5, 2.0), u32::MAX);
    }
}
