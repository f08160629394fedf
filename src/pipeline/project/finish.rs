//! A level's cells finished: each cell's accumulated photo colour blended with its
//! existing texture, its photo texture and confidence map encoded and handed to the
//! background writer, and the level's report.

use super::*;

/// What [`finish_level`] gives back: the level's report, the photo records of its cells
/// (manifest index), and per photo the texels it supplies (mostly its colour) and, for
/// deferred accumulators, the texels it gave colour.
pub(super) type LevelFinish = (
    PhotoLevelReport,
    Vec<(usize, PhotoCellRecord)>,
    Vec<u64>,
    Vec<u64>,
);

/// Blends and writes the photo textures of every cell of `level` from its accumulators
/// `accs` (indexed by manifest cell): the level's report and the new cell records. Each
/// cell's accumulator is dropped as soon as the cell is written, so its texel records go
/// back to the spare chunks (`photo/texel_tiles.rs`) for the next level's splat,
/// which runs alongside, instead of that level faulting in fresh pages.
pub(super) fn finish_level(
    store: &Store,
    level: usize,
    projection: LevelProjection,
    opts: &ProjectOptions,
    writer: &BackgroundWriter,
) -> Result<LevelFinish> {
    let LevelProjection {
        mut accs,
        sizing,
        early,
    } = projection;
    let sizing = &sizing;
    let cells = &store.manifest.cells;
    let level_cells: Vec<usize> = (0..cells.len())
        .filter(|&i| cells[i].level as usize == level)
        .collect();
    // the cells written during the casts keep their outcomes
    let mut early: std::collections::HashMap<usize, Result<CellOutcome>> =
        early.into_iter().collect();
    let mut done: Vec<(usize, Result<CellOutcome>)> = Vec::new();
    let mut work: Vec<(usize, usize, Option<CellAccum>)> = Vec::new();
    for (k, &ci) in level_cells.iter().enumerate() {
        match early.remove(&ci) {
            Some(outcome) => {
                if accs.get(ci).is_some_and(Option::is_some) {
                    // (not expected: the row bound of `LevelScene::last_rows` is conservative)
                    tracing::warn!(
                        "cell {}: footprints arrived after the cell was written; they are left out",
                        cells[ci].id
                    );
                }
                done.push((k, outcome))
            }
            None => work.push((k, ci, accs.get_mut(ci).and_then(Option::take))),
        }
    }
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
    results.extend(done);
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
    let mut written: Vec<u64> = Vec::new();
    for (&ci, r) in level_cells.iter().zip(results) {
        let o = r?;
        if let Some((p, n)) = o.written {
            let p = p as usize;
            if written.len() <= p {
                written.resize(p + 1, 0);
            }
            written[p] += n;
        }
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
    Ok((lr, records, supplied, written))
}

/// The cell's active texture, checked (with the normal map's side `normal_texels`, as its
/// resolution context read it) against the cell's active texture size; errors name the file.
pub(super) fn read_checked_active(
    store: &Store,
    rec: &CellRecord,
    normal_texels: u32,
) -> Result<image::RgbaImage> {
    let existing = store.read_active_texture(rec)?;
    let (tex, nrm) = (existing.dimensions(), (normal_texels, normal_texels));
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
    Ok(existing)
}

/// A finished cell: its photo record (if it got photo colour) and its steep texel count
/// (in texels of its active texture).
pub(super) struct CellOutcome {
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
    /// A deferred accumulator's photo ([`CellAccum::deferred`]) and the texels it gave colour
    /// (counted by the blend; other photos' counts were reported when merged).
    written: Option<(u16, u64)>,
}

impl CellOutcome {
    /// A cell that gets no photo texture, with its count of covered steep texels.
    fn without_photo(steep_texels: u64) -> CellOutcome {
        CellOutcome {
            record: None,
            steep_texels,
            steep_photo_base: 0,
            photo_base: 0,
            supplied_base: Vec::new(),
            written: None,
        }
    }
}

/// Which texel centres of a `texels × texels` texture of cell `rec` (active layout) lie on a
/// surface triangle in texture space (row-major).
pub(super) fn covered_mask(store: &Store, rec: &CellRecord, texels: u32) -> Result<Vec<bool>> {
    let mesh = store.read_active_mesh(rec)?;
    let s = crate::stats::CellSurface::of(&mesh, &rec.surface_texcoords(&mesh));
    Ok(
        texel_stretch(&s.positions, &s.triangles, &s.uvs, texels, 1.0)
            .iter()
            .map(|s| !s.is_nan())
            .collect(),
    )
}

/// Encodes `img` as PNG and queues it for `dir/rel` on `writer`.
pub(super) fn submit_png<P, C>(
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

pub(super) fn finish_cell(
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
        return Ok(CellOutcome::without_photo(steep_texels));
    };
    let ctx = &acc.context;
    let existing = read_checked_active(store, rec, ctx.base_texels)?;
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
    let written = acc.deferred_photo().map(|p| (p, b.coloured));
    if !present.contains(&true) {
        return Ok(CellOutcome {
            written,
            ..CellOutcome::without_photo(steep_texels)
        });
    }
    let stem = cell_stem(rec.level, rec.x, rec.y);
    let record = PhotoCellRecord {
        texels: acc.texels,
        texture: submit_png(
            writer,
            &store.dir,
            &format!("{stem}.photo.png"),
            &b.texture,
            opts.png_compression,
        )?,
        confidence: submit_png(
            writer,
            &store.dir,
            &format!("{stem}.photo.conf.png"),
            &b.confidence,
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
        written,
    })
}
