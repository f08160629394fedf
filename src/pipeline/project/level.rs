//! One level's projection: each photo cast onto the level's cells and splatted into
//! per-cell accumulators, with the photo texture sizes chosen first ([`LevelRun`]).

use super::*;
use crate::photo::Exclusion;

/// Per manifest cell, its footprints in `fs`; cells not on `level` (a footprint set from a
/// foreign scene) get none.
pub(super) fn group_by_cell<'a>(
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
pub(super) fn splat_batch(
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
/// (the larger of the ortho's spacing, when the store records it, and the texel size;
/// infinite where the texture was derived from the DEM: it holds no image detail, so any
/// photo that sees the surface resolves more).
pub(super) fn cell_context(store: &Store, rec: &CellRecord) -> Result<CellContext> {
    let normals = store.read_active_normal_map(rec)?;
    let t = active_texels(rec);
    if normals.dimensions() != (t, t) {
        return Err(Error::store(
            store.dir.join(active_normal_path(rec)),
            format!(
                "normal map {:?} is not the cell's {t}x{t} texels",
                normals.dimensions()
            ),
        ));
    }
    let texel = rec.extent.width().max(rec.extent.height()) / rec.texels.max(1) as f64;
    let ground = if store.manifest.textures_hold_an_image() {
        store.manifest.ortho_spacing.unwrap_or(0.0).max(texel)
    } else {
        f64::INFINITY
    };
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
pub(super) fn active_normal_path(rec: &CellRecord) -> String {
    rec.reparam
        .as_ref()
        .map_or(&rec.files.normal, |r| &r.files.normal)
        .path
        .clone()
}

/// What every level's projection of a run shares.
pub(super) struct LevelRun<'a> {
    pub(super) store: &'a Store,
    pub(super) pyramids: &'a [PhotoPyramid<'a>],
    /// Per photo, its masks by pyramid step.
    pub(super) masks: &'a [super::PhotoMasks],
    /// Per photo, its colour leveling.
    pub(super) transforms: &'a [ColourTransform],
    pub(super) opts: &'a ProjectOptions,
    pub(super) buffers: &'a FootprintBuffers,
    pub(super) bars: &'a [Box<dyn ProgressTask>],
    pub(super) finest: usize,
    /// TIN error (metres) per manifest cell, for the occlusion margin.
    pub(super) cell_errors: Vec<f32>,
    /// Where finished cells' photo textures go (cells a lone photo is done with are written
    /// during its casts).
    pub(super) writer: &'a BackgroundWriter,
}

/// A cell the last photo's remaining rows cannot reach, to be finished now: its deposits
/// from that photo, what earlier photos left, and its context if loaded.
pub(super) struct Finishing {
    cell: usize,
    photo: Option<PhotoAccum>,
    acc: Option<CellAccum>,
    context: Option<CellContext>,
}

/// One level's projection: per manifest cell its accumulator, the texture sizes, and the
/// outcomes of the cells already written (a lone photo's cells that no later batch of rows
/// could reach, blended and written while the rest were cast), by manifest index.
pub(super) struct LevelProjection {
    pub(super) accs: Vec<Option<CellAccum>>,
    pub(super) sizing: LevelSizing,
    pub(super) early: Vec<(usize, Result<CellOutcome>)>,
}

impl LevelRun<'_> {
    /// Casts and splats every photo onto the cells of `level` (using a photo's footprints
    /// cached from the leveling where they are of this level, and `first_scene`, the first
    /// photo's finest scene, if given) and returns the per-cell accumulators (indexed by
    /// manifest cell); adds to the photos' reports.
    pub(super) fn project_level(
        &self,
        level: usize,
        occlusion: &mut [Option<OcclusionMap>],
        cached: &mut [Option<(usize, FootprintSet)>],
        first_scene: &mut Option<LevelScene>,
        reports: &mut [PhotoReport],
        timer: &mut StageTimer,
    ) -> Result<LevelProjection> {
        let step = self.finest - level;
        let mut early: Vec<(usize, Result<CellOutcome>)> = Vec::new();
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
            // (made from the sizing cast where there was one, else cast here)
            if self.wants_occlusion(level) && occlusion[pi].is_none() {
                occlusion[pi] = match sizing.occlusion.get_mut(pi).and_then(Option::take) {
                    Some(map) => Some(map),
                    None => Some(self.occlusion_map(pyr, level, &mut scenes[pi])?),
                };
                timer.lap(&format!("level {level} photo {pi}: occlusion map"));
            }
            let mut samples = PhotoSamples::new(
                img,
                [cam.fx, cam.fy],
                &self.transforms[pi],
                &self.opts.confidence,
                self.opts.colour_space,
            )
            .with_mask(self.masks[pi].at(step))
            .with_min_distance(self.opts.min_distance_m);
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
            // (finest level: per pixel, whether its colour reaches a texture)
            let focal = (cam.fx * cam.fy).sqrt();
            let mut supply = SupplyCounts::default();
            let counts = match cached[pi].take() {
                Some((l, fs)) if l == level => {
                    splat_batch(&fs, &mut pas, cells, &sizing.scales, level as u8, &samples);
                    if level == self.finest {
                        supply.add(self.count_supplying(
                            &fs,
                            &mut sizing.contexts,
                            focal,
                            &samples,
                        ));
                    }
                    let mut counts = FootprintSet::default();
                    counts.add_counts(&fs);
                    self.buffers.recycle(fs);
                    counts
                }
                other => {
                    cached[pi] = other;
                    let scene = match scenes[pi].take() {
                        Some(scene) => scene,
                        None => level_scene(self.store, level as u8, cam.position, self.opts)?,
                    };
                    let mut counts = FootprintSet::default();
                    // with the last photo (a lone one, or the last of several) a cell is
                    // finished as soon as no later rows can reach it: its records go back
                    // to the spare chunks for the rest
                    let mut last_row = vec![u32::MAX; cells.len()];
                    if pi + 1 == self.pyramids.len() {
                        for (sc, r) in scene.cells.iter().zip(scene.last_rows(&cam)) {
                            if let (Some(r), Some(l)) = (r, last_row.get_mut(sc.cell as usize)) {
                                *l = r;
                            }
                        }
                    }
                    let contexts = &mut sizing.contexts;
                    for_each_footprint_batch_rows_in(
                        self.buffers,
                        &scene,
                        &cam,
                        &self.opts.footprint,
                        |batch, rows| {
                            splat_batch(
                                batch,
                                &mut pas,
                                cells,
                                &sizing.scales,
                                level as u8,
                                &samples,
                            );
                            counts.add_counts(batch);
                            if level == self.finest {
                                supply.add(self.count_supplying(batch, contexts, focal, &samples));
                            }
                            let done: Vec<Finishing> = pas
                                .iter_mut()
                                .zip(accs.iter_mut())
                                .enumerate()
                                .filter(|(ci, (pa, acc))| {
                                    (pa.is_some() || acc.is_some()) && last_row[*ci] < rows[1]
                                })
                                .map(|(ci, (pa, acc))| Finishing {
                                    cell: ci,
                                    photo: pa.take(),
                                    acc: acc.take(),
                                    context: contexts[ci].take(),
                                })
                                .collect();
                            if !done.is_empty() {
                                for (ci, outcome, written) in self.finish_early(done, pi) {
                                    reports[pi].texels_written += written;
                                    early.push((ci, outcome));
                                }
                            }
                        },
                    );
                    counts
                }
            };
            timer.lap(&format!("level {level} photo {pi}: footprints and splat"));
            if level == self.finest {
                let r = &mut reports[pi];
                let [supplying, outweighed, masked, near] = supply.result()?;
                r.pixels_supplying = supplying;
                r.pixels_outweighed = outweighed;
                r.pixels_masked = masked;
                r.pixels_near = near;
                r.pixels_dropped = counts.dropped;
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
                .filter_map(|(ci, ((acc, pa), ctx))| pa.map(|pa| (ci, acc, pa, ctx)))
                .collect();
            work.sort_by_key(|(ci, _, pa, _)| Reverse((pa.sums.allocated(), Reverse(*ci))));
            let written: Vec<Result<u64>> = work
                .into_par_iter()
                .with_max_len(1)
                .map(|(ci, acc, pa, ctx)| match acc.as_mut() {
                    Some(acc) => Ok(acc.merge(&pa, pi as u16)),
                    None => {
                        let (first, n) = self.first_accum(ci, pa, ctx.take(), pi)?;
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
        Ok(LevelProjection {
            accs,
            sizing,
            early,
        })
    }

    /// Splits the footprints of `batch` (of the finest level, cast from an image of focal
    /// length `focal` pixels, splatted with `samples`) into `[supplying, outweighed, masked,
    /// near]`: pixels whose colour the resolution rule lets dominate the existing texture
    /// ([`resolves_more`]), the others it splats, and those it leaves out
    /// ([`crate::photo::Exclusion`]). Loads the contexts of cells not seen before into
    /// `contexts` (kept for the merge).
    fn count_supplying(
        &self,
        batch: &FootprintSet,
        contexts: &mut [Option<CellContext>],
        focal: f64,
        samples: &PhotoSamples,
    ) -> Result<[u64; 4]> {
        let cells = &self.store.manifest.cells;
        let missing: Vec<usize> = batch
            .cells
            .iter()
            .map(|c| c.cell as usize)
            .filter(|&ci| contexts.get(ci).is_some_and(Option::is_none))
            .collect();
        let loaded: Vec<(usize, CellContext)> = missing
            .into_par_iter()
            .map(|ci| cell_context(self.store, &cells[ci]).map(|c| (ci, c)))
            .collect::<Result<_>>()?;
        for (ci, c) in loaded {
            contexts[ci] = Some(c);
        }
        let contexts = &*contexts;
        let weights = &self.opts.confidence;
        let counts = batch
            .cells
            .par_iter()
            .map(|cf| {
                let ctx = contexts.get(cf.cell as usize).and_then(Option::as_ref);
                let mut n = [0u64; 4];
                for fp in cf.iter() {
                    let k = match (samples.excluded(fp), ctx) {
                        (Some(Exclusion::Masked), _) => 2,
                        (Some(Exclusion::Near), _) => 3,
                        (None, Some(ctx)) if resolves_more(ctx, fp, focal, weights) => 0,
                        (None, _) => 1,
                    };
                    n[k] += 1;
                }
                n
            })
            .reduce(|| [0; 4], |a, b| [0, 1, 2, 3].map(|k| a[k] + b[k]));
        Ok(counts)
    }

    /// Blends and writes the cells `done` that the last photo `pi`'s remaining rows cannot
    /// reach (its deposits merged into what earlier photos left, as the merge stage would),
    /// costliest first, one task each; per cell its outcome and the texels photo `pi` gave
    /// colour where that is known now (a lone photo's are counted by the blend).
    fn finish_early(
        &self,
        mut done: Vec<Finishing>,
        pi: usize,
    ) -> Vec<(usize, Result<CellOutcome>, u64)> {
        let cells = &self.store.manifest.cells;
        let cost = |f: &Finishing| {
            f.photo.as_ref().map_or(0, |p| p.sums.allocated())
                + f.acc.as_ref().map_or(0, CellAccum::allocated)
        };
        done.sort_by_key(|f| Reverse((cost(f), Reverse(f.cell))));
        done.into_par_iter()
            .with_max_len(1)
            .map(|f| {
                let ci = f.cell;
                let mut written = 0;
                let outcome = (|| {
                    let acc = match (f.acc, f.photo) {
                        (Some(mut acc), Some(pa)) => {
                            written = acc.merge(&pa, pi as u16);
                            acc
                        }
                        (Some(acc), None) => acc,
                        (None, Some(pa)) => {
                            let (acc, n) = self.first_accum(ci, pa, f.context, pi)?;
                            written = n;
                            acc
                        }
                        (None, None) => {
                            return finish_cell(
                                self.store,
                                &cells[ci],
                                None,
                                self.opts,
                                self.writer,
                            );
                        }
                    };
                    finish_cell(self.store, &cells[ci], Some(&acc), self.opts, self.writer)
                })();
                (ci, outcome, written)
            })
            .collect()
    }

    /// The accumulator of cell `ci` from its first photo `pi`'s deposits `pa` (`ctx`: the
    /// cell's context if loaded) and the texels that photo gave colour: a lone photo's sums
    /// go to the blend as they are ([`CellAccum::deferred`], its texels counted there: 0
    /// here), otherwise they are turned into records now.
    fn first_accum(
        &self,
        ci: usize,
        pa: PhotoAccum,
        ctx: Option<CellContext>,
        pi: usize,
    ) -> Result<(CellAccum, u64)> {
        let ctx = match ctx {
            Some(c) => c,
            None => cell_context(self.store, &self.store.manifest.cells[ci])?,
        };
        let mode = accumulator_mode(self.opts.blend, self.pyramids.len());
        let conf = &self.opts.confidence;
        Ok(if self.pyramids.len() == 1 {
            (CellAccum::deferred(pa, pi as u16, mode, ctx, conf), 0)
        } else {
            CellAccum::from_photo(pa, pi as u16, mode, ctx, conf)
        })
    }

    /// Whether photos on `level` need occlusion maps: on the finest level, with several
    /// photos and a margin. (The occlusion weight only enters the choice between photos,
    /// docs/projection.md "Occlusion margin", so a lone photo needs no map.)
    fn wants_occlusion(&self, level: usize) -> bool {
        level == self.finest
            && self.pyramids.len() > 1
            && self.opts.confidence.occlusion_margin_px > 0.0
    }

    /// The occlusion map of a photo ([`OcclusionMap`]) where the sizing made none (fixed
    /// photo texture sizes): its pyramid image [`OCCLUSION_STEP`] halvings smaller (or its
    /// smallest) cast onto the finest level `level` (with `scene`, built there if `None`
    /// and kept).
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
            None => scene.insert(level_scene(
                self.store,
                level as u8,
                cam.position,
                self.opts,
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
        // (with the pyramid step each set was cast from)
        let mut sets: Vec<(std::borrow::Cow<FootprintSet>, f32, f64)> = Vec::new();
        let mut cast_steps: Vec<usize> = Vec::new();
        for (pi, pyr) in self.pyramids.iter().enumerate() {
            let (_, cam) = pyr.level(step);
            let focal = (cam.fx * cam.fy).sqrt();
            if let Some((l, fs)) = &cached[pi]
                && *l == level
            {
                sets.push((std::borrow::Cow::Borrowed(fs), 1.0, focal));
                cast_steps.push(step);
                continue;
            }
            let scene = match scenes[pi].take() {
                Some(s) => s,
                None => level_scene(self.store, level as u8, cam.position, self.opts)?,
            };
            let coarse = (step + SIZING_STEPS).min(pyr.steps());
            let (_, ccam) = pyr.level(coarse);
            let fs = photo_footprints_in(self.buffers, &scene, &ccam, &self.opts.footprint);
            sets.push((
                std::borrow::Cow::Owned(fs),
                0.5f32.powi((coarse - step) as i32),
                focal,
            ));
            cast_steps.push(coarse);
            scenes[pi] = Some(scene);
        }
        // the finest level's occlusion maps from the same casts (a map pixel per cast pixel:
        // a quarter of the photo's side, or its full size where the leveling's cast of a
        // small photo is reused), so no photo is cast again for them
        if self.wants_occlusion(level) {
            out.occlusion = sets
                .iter()
                .zip(&cast_steps)
                .zip(self.pyramids)
                .map(|(((fs, ..), &k), pyr)| {
                    let (img, _) = pyr.level(k);
                    Some(OcclusionMap::from_footprints(
                        fs,
                        img.width(),
                        img.height(),
                        (1u64 << k) as f32,
                        self.opts.footprint.max_depth_jump,
                    ))
                })
                .collect();
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
        // cells with finer children are drawn only from afar: no detail finer than such views
        // show (`coarse_scale_cap`)
        let keys: std::collections::HashSet<CellKey> = cells.iter().map(|c| c.key()).collect();
        let requests: Vec<SizeRequest> = level_cells
            .iter()
            .map(|&ci| {
                let rec = &cells[ci];
                let base = active_texels(rec);
                let mut max_scale = (topt.max_texels / base.max(1)).max(1);
                if rec.key().children().iter().any(|k| keys.contains(k)) {
                    let texel = rec.extent.width().max(rec.extent.height()) / base.max(1) as f64;
                    let cap = coarse_scale_cap(rec.error(), texel, topt.coarse_sse_px);
                    max_scale = max_scale.min(cap);
                }
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
/// cast from when the sizing made none (edges located to a map pixel, 4 full-resolution
/// pixels), as the finest level's sizing cast ([`SIZING_STEPS`]).
pub(super) const OCCLUSION_STEP: usize = SIZING_STEPS;

/// Pyramid halvings between a level's image and its sizing cast's.
pub(super) const SIZING_STEPS: usize = 2;

/// A photo's `[supplying, outweighed, masked, near]` pixels summed over batches, or the
/// first error.
#[derive(Default)]
struct SupplyCounts {
    counts: [u64; 4],
    failed: Option<Error>,
}

impl SupplyCounts {
    fn add(&mut self, batch: Result<[u64; 4]>) {
        match batch {
            Ok(n) => {
                for (c, v) in self.counts.iter_mut().zip(n) {
                    *c += v;
                }
            }
            Err(e) => {
                self.failed.get_or_insert(e);
            }
        }
    }

    fn result(self) -> Result<[u64; 4]> {
        match self.failed {
            Some(e) => Err(e),
            None => Ok(self.counts),
        }
    }
}

/// The photo texture sizes of one level.
#[derive(Clone, Debug, Default)]
pub(super) struct LevelSizing {
    /// Per manifest cell, the factor of its photo texture's side over its active texture's.
    pub(super) scales: Vec<u32>,
    /// Cells that wanted a larger photo texture.
    pub(super) wanted: u64,
    /// Cells that got one.
    pub(super) upsized: u64,
    /// This level's share of the budget, bytes.
    pub(super) budget_bytes: u64,
    /// The cells' resolution contexts loaded for the sizing (indexed by manifest cell).
    pub(super) contexts: Vec<Option<CellContext>>,
    /// Per photo, its occlusion map made from the sizing cast (finest level, several
    /// photos; empty otherwise).
    pub(super) occlusion: Vec<Option<OcclusionMap>>,
}

/// Whether the photo pixel of footprint `fp` (cast for an image of focal length `focal`
/// pixels) would get weight against cell `ctx`'s existing texture by the resolution rule
/// (the texel under its centre; [`ConfidenceParams::resolution_weight`] at least 1/2: the
/// photo dominates there).
pub(super) fn resolves_more(
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

/// The blend mode a cell accumulator runs in for `mode` with `photos` photos: with one photo
/// the weighted mean is that photo's colour, so the accumulator keeps it as `Best` does
/// (its colour and resolution, not sums to divide again; equal up to float rounding).
fn accumulator_mode(mode: BlendMode, photos: usize) -> BlendMode {
    if photos > 1 { mode } else { BlendMode::Best }
}
