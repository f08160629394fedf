//! Merging the accumulated photo colour of a cell with its existing texture.
//!
//! Per texel with photo colour `p`, coverage confidence `c` (the highest single-photo one)
//! and photo resolution `r_p`, against the existing texture's resolution `r_e` there
//! ([`CellContext`]), the photo's weight is `β = blend_weight(c) · resolution_weight(r_e /
//! r_p)` ([`ConfidenceParams::photo_weight`]): photo colour fades in across the edge of photo
//! coverage instead of ending in a seam, and only where the photo resolves the surface more
//! finely than the existing texture does. The existing texel (alpha `α`, the known fraction
//! of its colour) claims its resolution only for that fraction: `β = blend_weight(c) · (α ·
//! resolution_weight + 1 − α)` (where the texture has no data, α = 0, any photo that sees
//! the texel supplies it). It counts with weight `(1 − β)·α`, so the photo's share of the result is
//! `s = β / (β + (1 − β) α)` (`s = β` on fully known texels, 1 where the existing colour is
//! unknown and the photo saw the texel, 0 where `β = 0`). Result: `rgb = s·p + (1 − s)·existing`
//! mixed in the working [`ColourSpace`], alpha `max(α, β)`; the confidence map stores `s`
//! (0..255). A photo texture finer than the existing one (`scale` > 1) starts from the
//! existing texture magnified bilinearly (texel centres, edges clamped); texels the photos
//! do not reach keep that colour, except the gutter beside photo colour (off the chart, or
//! of unknown colour: alpha below 255), which takes the photo colour out to `2 · scale`
//! texels ([`crate::photo::blending::gutter`]) so that filtering at a chart's edge stays photo colour.

use image::{GrayImage, RgbaImage};

use crate::photo::blending::cell_accum::{CellAccum, CellContext};
use crate::photo::blending::gutter::{SlotBlocks, fill_gutter_from_photo};
use crate::photo::splatting::confidence::ConfidenceParams;

use crate::colour::ColourSpace;
pub use crate::store::magnify;
use crate::store::photo_texture::{Magnifier, MagnifyScratch, compose};
use crate::store::{PHOTO_BLOCK, PhotoBlocks};
use rayon::prelude::*;

/// A cell's photo-enhanced texture and its statistics.
#[derive(Clone, Debug, PartialEq)]
pub struct Blended {
    /// The stored blocks of the RGBA8 texture of the accumulator's size (with the existing
    /// texture's layout), packed into an atlas as [`crate::store::photo_texture::pack`] lays
    /// them out; outside the blocks the texture is the existing one magnified
    /// ([`Blended::compose`] gives the whole texture).
    pub texture: RgbaImage,
    /// Per texel of the blocks the photo's share `s` of the colour, 0..255, in the same
    /// atlas layout (0 outside the blocks).
    pub confidence: GrayImage,
    /// Block side (texels) of `blocks`.
    pub block_side: u32,
    /// The blocks where some texel got photo weight `β > 0` or photo colour in its gutter
    /// (those stored): elsewhere the texture equals the existing one magnified.
    pub blocks: PhotoBlocks,
    /// Covered texels with `s > 0.5`.
    pub photo_texels: u64,
    /// Covered texels marked steep.
    pub steep_texels: u64,
    /// Steep covered texels with `s > 0.5`.
    pub steep_photo_texels: u64,
    /// Per photo (by the index given to [`CellAccum::merge`]): covered texels with `s > 0.5`
    /// whose heaviest photo it is.
    pub supplied: Vec<u64>,
    /// Texels some photo gave colour (those [`CellAccum::for_each_coloured`] visits).
    pub coloured: u64,
}

impl Blended {
    /// The whole texture and confidence map (of `existing`'s size times `scale`, the
    /// arguments given to [`blend_cell`] and the accumulator's scale): `existing` magnified
    /// with the blocks over it, confidence 0 outside the blocks.
    pub fn compose(&self, existing: &RgbaImage, scale: u32) -> (RgbaImage, GrayImage) {
        let texture = crate::store::magnify(existing, scale);
        let (w, h) = texture.dimensions();
        if self.texture.width() == 0 {
            return (texture, GrayImage::new(w, h));
        }
        match compose(
            existing,
            scale,
            &self.blocks,
            &self.texture,
            &self.confidence,
        ) {
            Ok(both) => both,
            // (not reached: the atlases are laid out from these blocks)
            Err(_) => (texture, GrayImage::new(w, h)),
        }
    }
}

/// Blends `acc` into `existing` (the cell's existing texture, `acc.scale` times smaller than
/// `acc`) as described in the module docs (`src/photo/blend.rs`), mixing in `space` (the space `acc`'s
/// colours are in), in the blocks of [`PHOTO_BLOCK`] texels (at most the texture's side)
/// that footprints reached. `covered[b]` marks existing texels on the cell's surface and
/// `steep[b]` those steeper than the steep threshold (both row-major, of the existing
/// texture's size; shorter slices count as false).
pub fn blend_cell(
    existing: &RgbaImage,
    acc: &CellAccum,
    params: &ConfidenceParams,
    space: ColourSpace,
    covered: &[bool],
    steep: &[bool],
) -> Blended {
    let side = PHOTO_BLOCK.min(acc.texels).max(1);
    let magnifier = Magnifier::new(existing, acc.scale);
    let (w, h) = magnifier.dimensions();
    let grid = PhotoBlocks::grid(side, w) as usize;
    // The blocks footprints reached, each blended in its own slot of `side²` texels
    // (block-major): no buffer of the whole texture.
    let computed = acc.touched_blocks(side);
    let mut slot_of = vec![u32::MAX; grid * grid];
    let mut slots = Vec::new();
    for (i, _) in computed.iter().enumerate().filter(|c| *c.1) {
        if i < slot_of.len() {
            slot_of[i] = slots.len() as u32;
            slots.push(i);
        }
    }
    let (sd, bt) = (side as usize, side as usize * side as usize);
    let mut px = vec![0u8; slots.len() * bt * 4];
    let mut cv = vec![0u8; slots.len() * bt];
    px.par_chunks_mut(bt * 4).zip(&slots).for_each_init(
        MagnifyScratch::default,
        |scratch, (out, &i)| {
            let origin = [(i % grid) * sd, (i / grid) * sd];
            magnifier.fill(origin, [sd, sd], out, sd, scratch);
        },
    );
    let ctx: &CellContext = &acc.context;
    let (mut photo_texels, mut steep_photo_texels) = (0, 0);
    let mut supplied: Vec<u64> = Vec::new();
    let n = (w as usize * h as usize).min(acc.len());
    let base_n = ctx.base_texels as usize * ctx.base_texels as usize;
    let steep_texels = covered
        .iter()
        .zip(steep)
        .take(base_n)
        .filter(|(c, s)| **c && **s)
        .count() as u64
        * (acc.scale as u64).pow(2);
    let mut stored = vec![false; grid * grid];
    let base_index = ctx.base_indexer(acc.texels, acc.scale);
    let block_index = block_indexer(w as usize, sd, grid);
    let within_block = within_indexer(w as usize, sd);
    let resolution_weight = params.resolution_weight_fn();
    // (per existing texel and per alpha value, computed once: the same values bit for bit)
    let existing_res: Vec<f64> = (0..base_n)
        .map(|b| ctx.existing_resolution(b) as f64)
        .collect();
    let alphas: [f64; 256] = std::array::from_fn(|a| a as f64 / 255.0);
    let mut coloured = 0;
    acc.for_each_coloured(|t, p, confidence, resolution, best| {
        coloured += 1;
        if t >= n {
            return;
        }
        let b = base_index(t);
        let e_res = match existing_res.get(b) {
            Some(&r) => r,
            None => ctx.existing_resolution(b) as f64,
        };
        let ratio = e_res / resolution as f64;
        let coverage = params.blend_weight(confidence as f64);
        let sharper = resolution_weight(ratio);
        if !(coverage > 0.0) {
            return;
        }
        let block = block_index(t);
        // (every texel with colour lies in a block footprints reached)
        let Some(&slot) = slot_of.get(block).filter(|&&k| k != u32::MAX) else {
            return;
        };
        let at = slot as usize * bt + within_block(t);
        let e = &mut px[4 * at..4 * at + 4];
        let alpha = alphas[e[3] as usize];
        // (= params.photo_weight(confidence, ratio) on a fully known texel; the resolution
        // rule holds only for the known fraction α of the existing colour)
        let beta = if e[3] == 255 {
            coverage * sharper
        } else {
            coverage * (alpha * sharper + 1.0 - alpha)
        };
        if !(beta > 0.0) {
            return;
        }
        // (x / 1 is x: most texels are fully known and most such denominators are 1)
        let d = beta + (1.0 - beta) * alpha;
        let s = if d == 1.0 { beta } else { beta / d };
        for k in 0..3 {
            let old = space.decode_u8(e[k]) as f64;
            e[k] = space.encode_u8((s * p[k] as f64 + (1.0 - s) * old) as f32);
        }
        e[3] = e[3].max(crate::fastmath::to_u8(beta * 255.0));
        cv[at] = crate::fastmath::to_u8(s * 255.0);
        // (stored wherever the photo had weight, even a share that rounds to 0)
        stored[block] = true;
        let cov = covered.get(b).copied().unwrap_or(false);
        if s > 0.5 && cov {
            photo_texels += 1;
            steep_photo_texels += steep.get(b).copied().unwrap_or(false) as u64;
            if let Some(i) = best.map(usize::from) {
                if supplied.len() <= i {
                    supplied.resize(i + 1, 0);
                }
                supplied[i] += 1;
            }
        }
    });
    // photo colour into the gutter beside it (chart and cell edges), as far as a renderer's
    // filtering reaches: the magnified existing texture's edge ramp plus a texel per scale
    let blocks_held = SlotBlocks {
        slot_of: &slot_of,
        slots: &slots,
        side: sd,
        grid,
        size: [w as usize, h as usize],
    };
    let filled =
        fill_gutter_from_photo(&mut px, &mut cv, &blocks_held, space, 2 * acc.scale.max(1));
    for (&i, _) in slots.iter().zip(&filled).filter(|(_, f)| **f > 0) {
        stored[i] = true;
    }
    let kept: Vec<usize> = slots.iter().copied().filter(|&i| stored[i]).collect();
    Blended {
        texture: atlas_of(&px, 4, &kept, &slot_of, [side, w, h]),
        confidence: atlas_of(&cv, 1, &kept, &slot_of, [side, w, h]),
        block_side: side,
        blocks: PhotoBlocks::new(side, &stored),
        photo_texels,
        steep_texels,
        steep_photo_texels,
        supplied,
        coloured,
    }
}

/// The atlas ([`crate::store::photo_texture::pack`]'s layout) of the blocks `kept`
/// (row-major block numbers, ascending) of a texture of `[side, width, height]` whose
/// blocks are stored block-major in `slots` (`ch` bytes per texel, block `i` in slot
/// `slot_of[i]`); texels past a block cut by the texture's edge are 0.
fn atlas_of<P: image::Pixel<Subpixel = u8>>(
    slots: &[u8],
    ch: usize,
    kept: &[usize],
    slot_of: &[u32],
    [side, w, h]: [u32; 3],
) -> image::ImageBuffer<P, Vec<u8>> {
    let (cols, rows) = crate::store::photo_texture::atlas_blocks(kept.len());
    let (sd, grid) = (side as usize, PhotoBlocks::grid(side, w) as usize);
    let aw = cols * sd;
    let mut atlas = vec![0u8; aw * rows * sd * ch];
    for (k, &i) in kept.iter().enumerate() {
        let (x0, y0) = ((i % grid) * sd, (i / grid) * sd);
        let (bw, bh) = (sd.min(w as usize - x0), sd.min(h as usize - y0));
        let src = &slots[slot_of[i] as usize * sd * sd * ch..][..sd * sd * ch];
        let (ax, ay) = ((k % cols) * sd, (k / cols) * sd);
        for r in 0..bh {
            let d = ((ay + r) * aw + ax) * ch;
            atlas[d..d + bw * ch].copy_from_slice(&src[r * sd * ch..(r * sd + bw) * ch]);
        }
    }
    image::ImageBuffer::from_raw((aw) as u32, (rows * sd) as u32, atlas)
        .unwrap_or_else(|| image::ImageBuffer::new(0, 0))
}

/// The position of texel `t` of a row-major texture `w` texels wide within its block of
/// `side` texels (row-major in the block); shifts when both are powers of two.
fn within_indexer(w: usize, side: usize) -> impl Fn(usize) -> usize + Copy {
    let (w, side) = (w.max(1), side.max(1));
    let shifts = (w.is_power_of_two() && side.is_power_of_two())
        .then(|| (w.trailing_zeros(), side.trailing_zeros()));
    move |t: usize| match shifts {
        Some((lw, ls)) => (((t >> lw) & (side - 1)) << ls) + (t & (w - 1) & (side - 1)),
        None => ((t / w) % side) * side + (t % w) % side,
    }
}

/// The block (row-major over a `grid`-wide grid of `side`-texel blocks) of texel `t` of a
/// row-major texture `w` texels wide; shifts when `w` and `side` are powers of two (the
/// usual sizes), divisions otherwise.
fn block_indexer(w: usize, side: usize, grid: usize) -> impl Fn(usize) -> usize + Copy {
    let (w, side) = (w.max(1), side.max(1));
    let shifts = (w.is_power_of_two() && side.is_power_of_two())
        .then(|| (w.trailing_zeros(), side.trailing_zeros()));
    move |t: usize| match shifts {
        Some((lw, ls)) => ((t >> lw) >> ls) * grid + ((t & (w - 1)) >> ls),
        None => (t / w / side) * grid + (t % w) / side,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photo::{BlendMode, ColourTransform, PhotoAccum, PhotoSamples, PixelFootprint};
    use image::RgbImage;

    fn footprints(n: u32, scale_cos: bool) -> Vec<PixelFootprint> {
        (0..n)
            .map(|i| {
                let x = i as f32;
                PixelFootprint {
                    cell: 0,
                    pixel: [i, 0],
                    corners: [[x, 0.0], [x + 1.0, 0.0], [x + 1.0, 1.0], [x, 1.0]],
                    cos_view: if scale_cos {
                        1.0 - i as f32 / n as f32
                    } else {
                        1.0
                    },
                    distance: 5.0,
                    reconstructed: 0,
                }
            })
            .collect()
    }

    #[test]
    fn photo_where_it_resolves_more_existing_where_not_smooth_between() {
        // 32 x 1 texels; the photo's view cosine falls from 1 to 1/32 along x, so its
        // resolution on the surface coarsens from 5 mm to 16 cm against 4 cm of the ortho
        let n = 32u32;
        let img = RgbImage::from_pixel(n, 1, image::Rgb([250, 250, 250]));
        let params = ConfidenceParams {
            feather: 0.0,
            ..ConfidenceParams::default()
        };
        let mut pa = PhotoAccum::new(n);
        pa.add_samples(
            &footprints(n, true),
            &PhotoSamples::new(
                &img,
                [1000.0; 2],
                &ColourTransform::IDENTITY,
                &params,
                ColourSpace::Srgb,
            ),
        );
        let ctx = CellContext::flat(n, 0.0, 0.04);
        let mut acc = CellAccum::new(n, 1, BlendMode::Confidence, ctx, &params);
        acc.merge(&pa, 0);
        let mut existing = RgbaImage::from_pixel(n, n, image::Rgba([10, 10, 10, 255]));
        // an unknown existing texel where the photo is coarse
        existing.put_pixel(30, 0, image::Rgba([0, 0, 0, 0]));
        let covered = vec![true; (n * n) as usize];
        let steep: Vec<bool> = (0..n * n).map(|t| t % 2 == 0).collect();
        let b = blend_cell(
            &existing,
            &acc,
            &params,
            ColourSpace::Srgb,
            &covered,
            &steep,
        );
        let (texture, confidence) = b.compose(&existing, 1);
        let r: Vec<u8> = (0..n).map(|i| texture.get_pixel(i, 0).0[0]).collect();
        let s: Vec<u8> = (0..n).map(|i| confidence.get_pixel(i, 0).0[0]).collect();
        // where the photo is 4x finer: photo colour, share 255
        assert_eq!((r[0], s[0]), (250, 255));
        assert_eq!((r[15], s[15]), (250, 255), "{r:?}");
        // coarser: existing colour, untouched
        assert_eq!((r[31], s[31]), (10, 0));
        // in between: monotone (but for the unknown texel)
        for i in 0..31 {
            if i != 29 && i != 30 {
                assert!(r[i + 1] <= r[i], "{r:?}");
            }
        }
        assert!(r.iter().any(|&v| v > 10 && v < 250), "no ramp: {r:?}");
        // the unknown existing texel takes the photo colour however coarse the photo is
        // there (the existing texture claims its resolution only where it knows its colour)
        assert_eq!((r[30], s[30]), (250, 255), "{r:?} {s:?}");
        // rows the photo did not reach are unchanged
        assert_eq!(texture.get_pixel(5, 3).0, [10, 10, 10, 255]);
        assert_eq!(b.steep_texels, (n * n / 2) as u64);
        let photo = s.iter().filter(|&&v| v > 127).count() as u64;
        assert_eq!(b.photo_texels, photo);
        assert_eq!(
            b.steep_photo_texels,
            s.iter().step_by(2).filter(|&&v| v > 127).count() as u64
        );
        assert_eq!(b.supplied, vec![photo]);
    }

    #[test]
    fn a_larger_texture_never_lowers_the_photo_share() {
        // the same photo (a sheared grid of pixels of varying view angle) splatted into the
        // existing texture's size and into 2x and 4x finer textures: every fully covered
        // texel of the larger textures has exactly the share of the existing texel under it,
        // and the mean share over the surface does not fall
        let params = ConfidenceParams {
            feather: 0.0,
            ..ConfidenceParams::default()
        };
        // (pixels half an existing texel wide: 2 and 4 texels wide in the finer textures)
        let img = RgbImage::from_fn(12, 12, |x, y| {
            image::Rgb([(x * 20) as u8, (y * 20) as u8, 90])
        });
        let fps: Vec<PixelFootprint> = (0..12)
            .flat_map(|r| (0..12).map(move |c| (c, r)))
            .map(|(c, r)| {
                let (x, y) = (
                    1.0 + 0.5 * c as f32 + 0.04 * r as f32,
                    1.0 + 0.45 * r as f32,
                );
                PixelFootprint {
                    cell: 0,
                    pixel: [c, r],
                    corners: [
                        [x, y],
                        [x + 0.5, y],
                        [x + 0.54, y + 0.45],
                        [x + 0.04, y + 0.45],
                    ],
                    cos_view: 0.5 + 0.3 * c as f32 / 12.0,
                    distance: 100.0,
                    reconstructed: 0,
                }
            })
            .collect();
        let base = 8u32;
        let existing = RgbaImage::from_pixel(base, base, image::Rgba([10, 60, 10, 255]));
        let ctx = CellContext {
            base_texels: base,
            cos_slope: (0..64).map(|i| 0.3 + 0.7 * (i % 8) as f32 / 8.0).collect(),
            max_error: 0.02,
            existing_ground: 0.15,
            texel_ground: 0.15,
        };
        let samples = PhotoSamples::new(
            &img,
            [1000.0; 2],
            &ColourTransform::IDENTITY,
            &params,
            ColourSpace::Linear,
        );
        let mut shares = Vec::new();
        for scale in [1u32, 2, 4] {
            let t = base * scale;
            let mut pa = PhotoAccum::with_scale(t, scale);
            pa.add_samples(&fps, &samples);
            let mut acc = CellAccum::new(t, scale, BlendMode::Confidence, ctx.clone(), &params);
            acc.merge(&pa, 0);
            let b = blend_cell(&existing, &acc, &params, ColourSpace::Linear, &[], &[]);
            let (texture, confidence) = b.compose(&existing, scale);
            assert_eq!(texture.dimensions(), (t, t));
            shares.push((
                scale,
                confidence,
                (0..t * t)
                    .map(|i| acc.confidence(i as usize))
                    .collect::<Vec<f32>>(),
            ));
        }
        // over the surface the photo covers fully at the existing size, the mean share of
        // the finer textures is no lower, and no texel's share falls by more than rounding
        // and the averaging of the view angle over a smaller texel
        let (_, c1, k1) = &shares[0];
        let full: Vec<(u32, u32)> = (0..base)
            .flat_map(|y| (0..base).map(move |x| (x, y)))
            .filter(|&(x, y)| k1[(y * base + x) as usize] > 0.999)
            .collect();
        assert!(full.len() >= 16, "{}", full.len());
        // (the photo and the existing texture resolve about equally: shares in between)
        assert!(
            full.iter()
                .any(|&(x, y)| (40..215).contains(&c1.get_pixel(x, y).0[0])),
            "no intermediate share"
        );
        let mean1 = full
            .iter()
            .map(|&(x, y)| c1.get_pixel(x, y).0[0] as f64)
            .sum::<f64>()
            / full.len() as f64;
        for (scale, c, _) in &shares[1..] {
            let mut sum = 0.0;
            for &(bx, by) in &full {
                for dy in 0..*scale {
                    for dx in 0..*scale {
                        let (a, b) = (
                            c.get_pixel(bx * scale + dx, by * scale + dy).0[0] as i32,
                            c1.get_pixel(bx, by).0[0] as i32,
                        );
                        assert!(
                            b - a <= 12,
                            "scale {scale} texel {bx},{by}+{dx},{dy}: {a} < {b}"
                        );
                        sum += a as f64;
                    }
                }
            }
            let mean = sum / (full.len() as f64 * (*scale as f64).powi(2));
            assert!(
                mean >= mean1 - 0.5,
                "scale {scale}: mean share {mean} < {mean1}"
            );
        }
    }

    #[test]
    fn block_indices_by_shifts_equal_those_by_division() {
        for (w, side) in [
            (256usize, 64usize),
            (2048, 64),
            (64, 64),
            (96, 32),
            (100, 7),
        ] {
            let grid = w.div_ceil(side);
            let f = block_indexer(w, side, grid);
            for t in (0..w * w).step_by(13) {
                let (x, y) = (t % w, t / w);
                assert_eq!(f(t), (y / side) * grid + x / side, "{w} {side} {t}");
                let g = within_indexer(w, side);
                assert_eq!(g(t), (y % side) * side + x % side, "{w} {side} {t}");
            }
        }
    }
}
