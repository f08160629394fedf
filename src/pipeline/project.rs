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

use std::path::Path;

use indicatif::{MultiProgress, ProgressBar};
use rayon::prelude::*;

use super::{progress_bar, write_stats};
use crate::error::{Error, Result};
use crate::fsutil::{encode_png, write_atomic};
use crate::photo::{
    BlendMode, CellAccum, CellFootprints, ColourPairs, ColourTransform, ConfidenceParams, FootprintOptions, FootprintSet, LevelScene,
    LevelingParams, PhotoAccum, PhotoInput, PhotoSamples, PhotoPyramid, RayAccel, blend_cell, collect_pairs,
    fit_colour_transform, for_each_footprint_batch_in, normal_cos_slope, photo_footprints_in, FootprintBuffers,
};
use crate::stats::texel_stretch;
use crate::store::{
    BackgroundWriter, CellRecord, FileRef, PhotoCellRecord, PhotoLevelReport, PhotoReport, PhotoSettings, Store,
    active_texels, cell_stem, texcoord,
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
            quiet: false,
        }
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
        StageTimer { last: std::time::Instant::now(), laps: Vec::new() }
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
pub fn project_store(dir: &Path, photos: &[PhotoInput], opts: &ProjectOptions) -> Result<ProjectReport> {
    opts.confidence.validate()?;
    let mut timer = StageTimer::new();
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
    let pyramids: Vec<PhotoPyramid> = photos.iter().map(|p| PhotoPyramid::new(&p.image, p.camera, finest)).collect();
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
    let prebuild = !opts.level_colours || pyramids.first().is_some_and(|pyr| leveling_step(pyr, finest, opts) > 0);
    let (leveled, first_scene) = rayon::join(
        || -> Result<Vec<(ColourTransform, usize, Option<(usize, FootprintSet)>)>> {
            if !opts.level_colours {
                return Ok(Vec::new());
            }
            pyramids.iter().map(|pyr| estimate_leveling(&store, pyr, finest, opts, &buffers)).collect()
        },
        || {
            let first = photos.first().filter(|_| prebuild);
            first.map(|p| LevelScene::from_store(&store, finest as u8, p.camera.position, opts.ray)).transpose()
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
    timer.lap(if opts.level_colours { "colour leveling (alongside the first finest scene)" } else { "first finest scene" });

    let mut records: Vec<Option<PhotoCellRecord>> = vec![None; ncells];
    let mut level_reports = Vec::with_capacity(levels);
    // Finest level first; the cells of each level are blended and written while the next
    // coarser level is cast and splatted (levels are independent, so the output is the same
    // as level by level).
    let run = LevelRun { store: &store, pyramids: &pyramids, transforms: &transforms, opts, buffers: &buffers, bars: &bars, finest };
    let mut pending: Option<(usize, Vec<Option<CellAccum>>)> = None;
    // The photo textures are written on a thread of their own (the fsyncs do not hold up
    // the workers); all are on disk before the manifest refers to them.
    let writer = BackgroundWriter::new(dir);
    for level in (0..levels).rev().map(Some).chain([None]) {
        let (finished, projected) = rayon::join(
            || {
                pending.take().map(|(l, accs)| {
                    let t = std::time::Instant::now();
                    (l, finish_level(&store, l, &accs, opts, &writer), t.elapsed().as_secs_f64())
                })
            },
            || -> Result<Option<(usize, Vec<Option<CellAccum>>)>> {
                let Some(level) = level else { return Ok(None) };
                Ok(Some((level, run.project_level(level, &mut cached, &mut first_scene, &mut reports, &mut timer)?)))
            },
        );
        if let Some((l, result, secs)) = finished {
            let (lr, recs) = result?;
            for (ci, rec) in recs {
                records[ci] = Some(rec);
            }
            level_reports.push(lr);
            timer.note(&format!("level {l}: cells written (alongside the next level)"), secs);
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
            tracing::warn!("photo {}: it sees no terrain of the store (no texels written)", r.name);
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
        photos: reports,
        levels: level_reports,
    };
    store.manifest.photos = Some(settings.clone());
    let threshold = store.manifest.reparam.as_ref().map_or(1.1, |r| r.threshold);
    write_stats(dir, &store.manifest, threshold)?;
    write_atomic(
        &dir.join("manifest.json"),
        &serde_json::to_vec_pretty(&store.manifest).map_err(|e| Error::store(dir, e.to_string()))?,
    )?;
    remove_stale_photo_files(dir, &store.manifest.cells);
    timer.lap("manifest and stats");
    Ok(ProjectReport { settings, cells_written, stage_seconds: timer.laps })
}

/// Removes the photo textures of cells without a photo record (left by an earlier run).
pub(crate) fn remove_stale_photo_files(dir: &Path, cells: &[CellRecord]) {
    for c in cells.iter().filter(|c| c.photo.is_none()) {
        for ext in ["photo.png", "photo.conf.png"] {
            let _ = std::fs::remove_file(dir.join(format!("{}.{ext}", cell_stem(c.level, c.x, c.y))));
        }
    }
}

/// Per manifest cell, its footprints in `fs`; cells not on `level` (a footprint set from a
/// foreign scene) get none.
fn group_by_cell<'a>(fs: &'a FootprintSet, cells: &[CellRecord], level: u8) -> Vec<Option<&'a CellFootprints>> {
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
/// use), in parallel over cells, each cell's footprints in order.
fn splat_batch(
    batch: &FootprintSet,
    pas: &mut [Option<PhotoAccum>],
    cells: &[CellRecord],
    level: u8,
    samples: &PhotoSamples,
) {
    let groups = group_by_cell(batch, cells, level);
    pas.par_iter_mut().zip(groups).enumerate().for_each(|(ci, (pa, cf))| {
        if let Some(cf) = cf {
            pa.get_or_insert_with(|| PhotoAccum::new(active_texels(&cells[ci]))).add_samples(cf.iter(), samples);
        }
    });
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
}

impl LevelRun<'_> {
    /// Casts and splats every photo onto the cells of `level` (using a photo's footprints
    /// cached from the leveling where they are of this level, and `first_scene`, the first
    /// photo's finest scene, if given) and returns the per-cell accumulators (indexed by
    /// manifest cell); adds to the photos' reports.
    fn project_level(
        &self,
        level: usize,
        cached: &mut [Option<(usize, FootprintSet)>],
        first_scene: &mut Option<LevelScene>,
        reports: &mut [PhotoReport],
        timer: &mut StageTimer,
    ) -> Result<Vec<Option<CellAccum>>> {
        let step = self.finest - level;
        let mut accs: Vec<Option<CellAccum>> = vec![None; self.store.manifest.cells.len()];
        for (pi, pyr) in self.pyramids.iter().enumerate() {
            let (img, cam) = pyr.level(step);
            let cells = &self.store.manifest.cells;
            let samples = PhotoSamples::new(img, &self.transforms[pi], &self.opts.confidence);
            // This photo's deposits per manifest cell, filled batch by batch in row order.
            let mut pas: Vec<Option<PhotoAccum>> = vec![None; self.store.manifest.cells.len()];
            let counts = match cached[pi].take() {
                Some((l, fs)) if l == level => {
                    splat_batch(&fs, &mut pas, cells, level as u8, &samples);
                    let mut counts = FootprintSet::default();
                    counts.add_counts(&fs);
                    self.buffers.recycle(fs);
                    counts
                }
                other => {
                    cached[pi] = other;
                    let scene = match first_scene.take() {
                        Some(scene) if pi == 0 && level == self.finest => scene,
                        _ => LevelScene::from_store(self.store, level as u8, cam.position, self.opts.ray)?,
                    };
                    let mut counts = FootprintSet::default();
                    for_each_footprint_batch_in(self.buffers, &scene, &cam, &self.opts.footprint, |batch| {
                        splat_batch(batch, &mut pas, cells, level as u8, &samples);
                        counts.add_counts(batch);
                    });
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
            let written: Vec<u64> = accs
                .par_iter_mut()
                .zip(pas.into_par_iter())
                .map(|(acc, pa)| match (acc.as_mut(), pa) {
                    (_, None) => 0,
                    (Some(acc), Some(pa)) => acc.merge(&pa),
                    (None, Some(pa)) => {
                        let (first, n) = CellAccum::from_photo(pa, self.opts.blend);
                        *acc = Some(first);
                        n
                    }
                })
                .collect();
            reports[pi].texels_written += written.iter().sum::<u64>();
            self.bars[pi].inc(1);
            timer.lap(&format!("level {level} photo {pi}: merge"));
        }
        Ok(accs)
    }
}

/// Blends and writes the photo textures of every cell of `level` from its accumulators
/// `accs` (indexed by manifest cell): the level's report and the new cell records.
fn finish_level(
    store: &Store,
    level: usize,
    accs: &[Option<CellAccum>],
    opts: &ProjectOptions,
    writer: &BackgroundWriter,
) -> Result<(PhotoLevelReport, Vec<(usize, PhotoCellRecord)>)> {
    let cells = &store.manifest.cells;
    let level_cells: Vec<usize> = (0..cells.len()).filter(|&i| cells[i].level as usize == level).collect();
    let results: Vec<Result<CellOutcome>> =
        level_cells.par_iter().map(|&ci| finish_cell(store, &cells[ci], accs.get(ci).and_then(Option::as_ref), opts, writer)).collect();
    let mut lr = PhotoLevelReport { level: level as u8, ..PhotoLevelReport::default() };
    let mut records = Vec::new();
    for (&ci, r) in level_cells.iter().zip(results) {
        let o = r?;
        lr.steep_texels += o.steep_texels;
        if let Some(rec) = o.record {
            lr.cells_with_photo += 1;
            lr.photo_texels += rec.photo_texels;
            lr.steep_photo_texels += rec.steep_photo_texels;
            records.push((ci, rec));
        }
    }
    Ok((lr, records))
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
        let samples = PhotoSamples::new(img, &ColourTransform::IDENTITY, &opts.confidence);
        let mut pas: Vec<Option<PhotoAccum>> = vec![None; cells.len()];
        splat_batch(&fs, &mut pas, cells, level as u8, &samples);
        let parts: Vec<Result<ColourPairs>> = pas
            .par_iter()
            .enumerate()
            .filter_map(|(ci, pa)| pa.as_ref().map(|pa| (&cells[ci], pa)))
            .map(|(rec, pa)| {
                let existing = store.read_active_texture(rec)?;
                let normals = store.read_active_normal_map(rec)?;
                check_size(store, rec, existing.dimensions(), normals.dimensions())?;
                let mut pairs = ColourPairs::default();
                collect_pairs(pa, &existing, &normals, &opts.leveling, &mut pairs);
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
        let f = rec.reparam.as_ref().map_or(&rec.files.texture, |r| &r.files.texture);
        return Err(Error::store(
            store.dir.join(&f.path),
            format!("texture {tex:?} or normal map {nrm:?} is not the cell's {t}x{t} texels"),
        ));
    }
    Ok(())
}

/// A finished cell: its photo record (if it got photo colour) and its steep texel count.
struct CellOutcome {
    record: Option<PhotoCellRecord>,
    steep_texels: u64,
}

/// Steep and covered masks of a cell's active texture (row-major): covered = texel centre
/// on a surface triangle in texture space, steep = covered and normal-map slope above
/// [`STEEP_SLOPE_DEG`].
fn surface_masks(store: &Store, rec: &CellRecord, normals: &image::RgbImage) -> Result<(Vec<bool>, Vec<bool>)> {
    let mesh = store.read_active_mesh(rec)?;
    let ns = (mesh.surface_vertices as usize).min(mesh.positions.len());
    let positions: Vec<[f64; 3]> = mesh.positions[..ns].iter().map(|p| p.map(f64::from)).collect();
    let uvs: Vec<[f64; 2]> = (0..ns).map(|i| texcoord(rec, &mesh, i).map(f64::from)).collect();
    let triangles: Vec<[u32; 3]> =
        mesh.surface().iter().copied().filter(|t| t.iter().all(|&k| (k as usize) < ns)).collect();
    let t = active_texels(rec);
    let covered: Vec<bool> = texel_stretch(&positions, &triangles, &uvs, t, 1.0).iter().map(|s| !s.is_nan()).collect();
    let cos_steep = STEEP_SLOPE_DEG.to_radians().cos();
    let steep = covered.iter().zip(normals.pixels()).map(|(&c, n)| c && normal_cos_slope(n.0) < cos_steep).collect();
    Ok((covered, steep))
}

/// Encodes `img` as PNG and queues it for `dir/rel` on `writer`.
fn submit_png<P, C>(writer: &BackgroundWriter, dir: &Path, rel: &str, img: &image::ImageBuffer<P, C>) -> Result<FileRef>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    C: std::ops::Deref<Target = [P::Subpixel]>,
{
    writer.submit(rel, encode_png(&dir.join(rel), img)?)
}

fn finish_cell(
    store: &Store,
    rec: &CellRecord,
    acc: Option<&CellAccum>,
    opts: &ProjectOptions,
    writer: &BackgroundWriter,
) -> Result<CellOutcome> {
    let normals = store.read_active_normal_map(rec)?;
    let (covered, steep) = surface_masks(store, rec, &normals)?;
    let steep_texels = steep.iter().filter(|&&s| s).count() as u64;
    let Some(acc) = acc else { return Ok(CellOutcome { record: None, steep_texels }) };
    let existing = store.read_active_texture(rec)?;
    check_size(store, rec, existing.dimensions(), normals.dimensions())?;
    let b = blend_cell(&existing, acc, &opts.confidence, &covered, &steep);
    if b.confidence.pixels().all(|p| p.0[0] == 0) {
        return Ok(CellOutcome { record: None, steep_texels });
    }
    let stem = cell_stem(rec.level, rec.x, rec.y);
    let record = PhotoCellRecord {
        texels: active_texels(rec),
        texture: submit_png(writer, &store.dir, &format!("{stem}.photo.png"), &b.texture)?,
        confidence: submit_png(writer, &store.dir, &format!("{stem}.photo.conf.png"), &b.confidence)?,
        photo_texels: b.photo_texels,
        steep_texels: b.steep_texels,
        steep_photo_texels: b.steep_photo_texels,
    };
    Ok(CellOutcome { record: Some(record), steep_texels })
}
