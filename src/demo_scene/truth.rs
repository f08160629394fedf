//! Texel-level evaluation of a store against the demo scene's ground truth: each texel
//! centre is mapped through the cell's chart to its 3D point on the cell mesh and compared
//! with [`DemoScene::surface_colour`] there.

use image::RgbaImage;
use rayon::prelude::*;
use serde::Serialize;

use super::{DemoScene, surface_colour};
use crate::error::{Error, Result};
use crate::store::{CellRecord, Store, texcoord};

/// Which texture of each cell to evaluate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureChoice {
    /// The active texture: the reparameterized one if the cell has it, else the orthographic
    /// (magnified to the photo texture's size where the cell has a larger one, so that both
    /// choices score the same points).
    Active,
    /// The photo-enhanced texture (`rec.photo`) where the cell has one, else the active one.
    Photo,
}

/// Slope above which a texel counts as steep, degrees.
pub const STEEP_DEG: f64 = 60.0;
/// Slope below which a texel counts as flat, degrees.
pub const FLAT_DEG: f64 = 30.0;

/// PSNR of one level's textures against the ground truth, by slope class. PSNR is in dB
/// over the three 8-bit sRGB channels (`10·log10(255² / MSE)`), infinite for a perfect
/// match, NaN (JSON `null`) for a class without texels.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TruthReport {
    /// Quadtree level evaluated.
    pub level: u8,
    /// Cells evaluated.
    pub cells: usize,
    /// Cells whose photo-enhanced texture was used ([`TextureChoice::Photo`] only).
    pub photo_cells: usize,
    /// PSNR over texels whose surface slope exceeds [`STEEP_DEG`] (60°).
    pub steep_psnr: f64,
    /// PSNR over texels whose slope is below [`FLAT_DEG`] (30°).
    pub flat_psnr: f64,
    /// PSNR over texels with slopes from 30° to 60°.
    pub mid_psnr: f64,
    /// PSNR over all evaluated texels.
    pub all_psnr: f64,
    /// Steep texels evaluated.
    pub steep_texels: u64,
    /// Flat texels evaluated.
    pub flat_texels: u64,
    /// Texels with slopes from 30° to 60°.
    pub mid_texels: u64,
    /// Texels whose centre lies on the cell's surface chart but with alpha 0 (unknown
    /// colour), not evaluated.
    pub unknown_texels: u64,
}

/// Squared-error sums and texel counts per class: steep, flat, mid.
#[derive(Clone, Copy, Default)]
struct Sums {
    sq: [f64; 3],
    n: [u64; 3],
    unknown: u64,
}

fn psnr(sq: f64, n: u64) -> f64 {
    if n == 0 {
        return f64::NAN;
    }
    let mse = sq / (3 * n) as f64;
    10.0 * (255.0f64 * 255.0 / mse).log10()
}

/// Marker of a texel centre outside every triangle.
const EMPTY: u32 = u32::MAX;

/// For each texel centre of an `n × n` texture, the first triangle (in index order) that
/// contains it in texture space (`st`, texel units) and its barycentric weights, clamped to
/// the triangle. Exact f64 edge tests with a 1e-9 tolerance (so centres on shared edges go
/// to the lower triangle index); no snapping, because on walls a tiny texture-space offset
/// is a large 3D one.
fn locate_texel_centres(st: &[[f64; 2]], tris: &[[u32; 3]], n: u32) -> (Vec<u32>, Vec<[f64; 3]>) {
    let nn = n as usize;
    let mut ids = vec![EMPTY; nn * nn];
    let mut weights = vec![[0.0; 3]; nn * nn];
    for (ti, t) in tris.iter().enumerate() {
        let [a, b, c] = t.map(|v| st[v as usize]);
        let den = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        if den.abs() <= 1e-300 || !den.is_finite() {
            continue;
        }
        let lo = |k: usize| (a[k].min(b[k]).min(c[k]) - 0.5).ceil().max(0.0);
        let hi = |k: usize| (a[k].max(b[k]).max(c[k]) - 0.5).floor().min(n as f64 - 1.0);
        let (i0, i1, j0, j1) = (lo(0), hi(0), lo(1), hi(1));
        if i0 > i1 || j0 > j1 {
            continue;
        }
        for j in j0 as usize..=j1 as usize {
            for i in i0 as usize..=i1 as usize {
                let k = j * nn + i;
                if ids[k] != EMPTY {
                    continue;
                }
                let p = [i as f64 + 0.5, j as f64 + 0.5];
                let w1 = ((p[0] - a[0]) * (c[1] - a[1]) - (p[1] - a[1]) * (c[0] - a[0])) / den;
                let w2 = ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / den;
                let w0 = 1.0 - w1 - w2;
                const TOL: f64 = -1e-9;
                if w0 < TOL || w1 < TOL || w2 < TOL {
                    continue;
                }
                let w = [w0.max(0.0), w1.max(0.0), w2.max(0.0)];
                let sum = w[0] + w[1] + w[2];
                ids[k] = ti as u32;
                weights[k] = w.map(|x| x / sum);
            }
        }
    }
    (ids, weights)
}

/// Evaluates the finest level of `store` against `scene` with the chosen texture.
pub fn texel_truth(store: &Store, scene: &DemoScene, which: TextureChoice) -> Result<TruthReport> {
    let level = store.manifest.quadtree.levels.saturating_sub(1);
    let mut photo_cells = 0;
    for rec in store.manifest.cells.iter().filter(|c| c.level == level) {
        photo_cells += usize::from(which == TextureChoice::Photo && rec.photo.is_some());
    }
    let mut report = texel_truth_with(store, scene, level, |rec| {
        let active = rec
            .reparam
            .as_ref()
            .map_or(&rec.files.texture, |r| &r.files.texture);
        match (&rec.photo, which) {
            (Some(p), TextureChoice::Photo) => Ok(store.read_photo_texture(rec, p)?.0),
            (Some(p), TextureChoice::Active) => {
                // on the photo texture's texels, so that both choices score the same points
                let img = store.read_png(active)?.to_rgba8();
                let k = if img.width() > 0 && p.texels % img.width() == 0 {
                    p.texels / img.width()
                } else {
                    1
                };
                Ok(crate::photo::magnify(&img, k))
            }
            (None, _) => Ok(store.read_png(active)?.to_rgba8()),
        }
    })?;
    report.photo_cells = photo_cells;
    Ok(report)
}

/// Evaluates the finest level's photo-covered texels only (photo weight > 0.5 in the cell's
/// confidence map), before projection (active texture, magnified to the photo texture's
/// size where that is larger) and after (photo texture), so both reports score exactly the
/// same texels: the gain where photos actually contributed.
pub fn texel_truth_covered(store: &Store, scene: &DemoScene) -> Result<(TruthReport, TruthReport)> {
    let level = store.manifest.quadtree.levels.saturating_sub(1);
    let masked = |photo: bool| {
        move |rec: &CellRecord| -> Result<RgbaImage> {
            let active = rec
                .reparam
                .as_ref()
                .map_or(&rec.files.texture, |r| &r.files.texture);
            let Some(p) = &rec.photo else {
                // No photo colour: every texel is excluded.
                let mut img = store.read_png(active)?.to_rgba8();
                img.pixels_mut().for_each(|px| px[3] = 0);
                return Ok(img);
            };
            let (photo_texture, conf) = store.read_photo_texture(rec, p)?;
            let mut img = if photo {
                photo_texture
            } else {
                store.read_png(active)?.to_rgba8()
            };
            if !photo
                && conf.width() > img.width()
                && img.width() > 0
                && conf.width() % img.width() == 0
            {
                // a photo texture larger than the active one: compare on its texels
                img = crate::photo::magnify(&img, conf.width() / img.width());
            }
            if conf.dimensions() != img.dimensions() {
                return Err(crate::Error::store(
                    store.dir.join(&p.confidence.path),
                    "confidence map and texture differ in size",
                ));
            }
            for (px, c) in img.pixels_mut().zip(conf.pixels()) {
                if c[0] <= 127 {
                    px[3] = 0;
                }
            }
            Ok(img)
        }
    };
    let before = texel_truth_with(store, scene, level, masked(false))?;
    let after = texel_truth_with(store, scene, level, masked(true))?;
    Ok((before, after))
}

/// Evaluates every cell of `level` with the texture `texture(rec)` returns (square, laid out
/// over the cell's active chart: `store::texcoord` of the active mesh times its side). Each
/// texel centre is located in the chart triangle covering it (exact f64 point location; a
/// centre on a shared edge goes to the lower triangle index), mapped by barycentric weights to the 3D point on the cell mesh
/// (f64 world), and compared with `surface_colour` there, using the slope of that mesh
/// triangle. Cells run in parallel; sums are combined in cell order (deterministic).
pub fn texel_truth_with(
    store: &Store,
    scene: &DemoScene,
    level: u8,
    texture: impl Fn(&CellRecord) -> Result<RgbaImage> + Sync,
) -> Result<TruthReport> {
    let cells: Vec<&CellRecord> = store
        .manifest
        .cells
        .iter()
        .filter(|c| c.level == level)
        .collect();
    if cells.is_empty() {
        return Err(Error::store(
            &store.dir,
            format!("no cells on level {level}"),
        ));
    }
    let noises = scene.noises();
    let per_cell: Vec<Sums> = cells
        .par_iter()
        .map(|rec| -> Result<Sums> {
            let mesh = store.read_active_mesh(rec)?;
            let img = texture(rec)?;
            let n = img.width();
            if img.height() != n || n == 0 || n > crate::resample::MAX_TEXELS {
                return Err(Error::store(
                    &store.dir,
                    format!(
                        "cell {}: texture is {} x {}, expected a square",
                        rec.id,
                        img.width(),
                        img.height()
                    ),
                ));
            }
            let nv = mesh.surface_vertices as usize;
            let st: Vec<[f64; 2]> = (0..nv)
                .map(|i| {
                    let t = texcoord(rec, &mesh, i);
                    [t[0] as f64 * n as f64, t[1] as f64 * n as f64]
                })
                .collect();
            let tris = mesh.surface();
            if tris.iter().flatten().any(|&k| k as usize >= nv) {
                return Err(Error::store(
                    &store.dir,
                    format!("cell {}: surface triangle uses a skirt vertex", rec.id),
                ));
            }
            let (ids, weights) = locate_texel_centres(&st, tris, n);
            let origin = glam::DVec3::from_array(rec.origin);
            let mut sums = Sums::default();
            for (k, &id) in ids.iter().enumerate() {
                if id == EMPTY {
                    continue;
                }
                let (i, j) = (k as u32 % n, k as u32 / n);
                let px = img.get_pixel(i, j).0;
                if px[3] == 0 {
                    sums.unknown += 1;
                    continue;
                }
                let tri = tris[id as usize];
                let [w0, w1, w2] = weights[k];
                let pos = tri.map(|v| {
                    origin + glam::Vec3::from_array(mesh.positions[v as usize]).as_dvec3()
                });
                let x = pos[0] * w0 + pos[1] * w1 + pos[2] * w2;
                let normal = (pos[1] - pos[0]).cross(pos[2] - pos[0]);
                let slope = (normal.z.abs() / normal.length())
                    .clamp(0.0, 1.0)
                    .acos()
                    .to_degrees();
                let truth = surface_colour(&noises, scene, x.x, x.y, x.z, slope);
                let err: f64 = (0..3)
                    .map(|q| (px[q] as f64 - truth[q] * 255.0).powi(2))
                    .sum();
                let class = if slope > STEEP_DEG {
                    0
                } else if slope < FLAT_DEG {
                    1
                } else {
                    2
                };
                sums.sq[class] += err;
                sums.n[class] += 1;
            }
            Ok(sums)
        })
        .collect::<Result<_>>()?;
    let mut total = Sums::default();
    for s in &per_cell {
        for c in 0..3 {
            total.sq[c] += s.sq[c];
            total.n[c] += s.n[c];
        }
        total.unknown += s.unknown;
    }
    Ok(TruthReport {
        level,
        cells: cells.len(),
        photo_cells: 0,
        steep_psnr: psnr(total.sq[0], total.n[0]),
        flat_psnr: psnr(total.sq[1], total.n[1]),
        mid_psnr: psnr(total.sq[2], total.n[2]),
        all_psnr: psnr(total.sq.iter().sum(), total.n.iter().sum()),
        steep_texels: total.n[0],
        flat_texels: total.n[1],
        mid_texels: total.n[2],
        unknown_texels: total.unknown,
    })
}
