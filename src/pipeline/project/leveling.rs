//! The colour leveling of each photo against the ortho, fitted on a cast of a small level
//! of its pyramid (whose footprints the main loop may reuse).

use super::*;

/// Most footprints (over all photos) kept from the leveling casts for the main loop
/// (about 56 bytes each).
pub(super) const MAX_CACHED_FOOTPRINTS: usize = 8 << 20;

/// The leveling transform of one photo, its sample count and the footprints it was fitted
/// on with their level, as [`estimate_leveling`] returns them.
pub(super) type Leveled = (ColourTransform, usize, Option<(usize, FootprintSet)>);

/// The leveling transform of one photo, its sample count and the footprints it was fitted
/// on with their level (see the module docs).
pub(super) fn estimate_leveling(
    store: &Store,
    pyr: &PhotoPyramid,
    masks: &super::PhotoMasks,
    finest: usize,
    opts: &ProjectOptions,
    buffers: &FootprintBuffers,
) -> Result<Leveled> {
    let k_est = leveling_step(pyr, finest, opts);
    let attempts: Vec<usize> = if k_est > 0 { vec![k_est, 0] } else { vec![0] };
    for step in attempts {
        let level = finest - step;
        let (img, cam) = pyr.level(step);
        let scene = super::level_scene(store, level as u8, cam.position, opts)?;
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
        )
        .with_mask(masks.at(step))
        .with_min_distance(opts.min_distance_m);
        let mut pas: Vec<Option<PhotoAccum>> = vec![None; cells.len()];
        splat_batch(&fs, &mut pas, cells, &[], level as u8, &samples);
        let parts: Vec<Result<ColourPairs>> = pas
            .par_iter()
            .enumerate()
            .filter_map(|(ci, pa)| pa.as_ref().map(|pa| (&cells[ci], pa)))
            .map(|(rec, pa)| {
                let ctx = cell_context(store, rec)?;
                let existing = read_checked_active(store, rec, ctx.base_texels)?;
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
pub(super) fn leveling_step(pyr: &PhotoPyramid, finest: usize, opts: &ProjectOptions) -> usize {
    let (w, h) = pyr.level(0).0.dimensions();
    let mut k = 0;
    while k < finest && (w as u64 >> k) * (h as u64 >> k) > opts.leveling_max_pixels {
        k += 1;
    }
    k
}
