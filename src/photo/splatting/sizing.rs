//! Photo-driven texture sizes: how large a cell's photo texture must be to hold the finest
//! detail the photos deliver on it, within a cap and a memory budget (docs/projection.md,
//! "Texture sizes").
//!
//! Per cell, [`SizingBins`] divides the existing texture into 16 × 16 bins and keeps in each
//! the side (in existing texels, `√area` of the footprint scaled to the full-resolution
//! photo) of the finest photo pixel whose footprint centre falls there, over all photos,
//! among the pixels the blend would let dominate (photo resolution at least twice the
//! existing texture's there), and counts all the pixels the cell receives. The
//! cell wants the scale `2^m` (a power of two) that makes a texel no larger than the median
//! of those bin minima: `m = max(0, ⌈log2(k / side)⌉)` for `k` texels per pixel side
//! (default 1), capped so that the side stays within `max_texels` and the texture holds no
//! more than `texels_per_delivered` texels per full-resolution photo pixel the cell receives
//! (a speed and memory knob, unbounded by default: a cell the photos cover only in part
//! otherwise gets a large texture that is mostly magnified ortho; Engabreen: 604 MB of photo
//! textures for one 12-MP photo unbounded, 97 MB at 4 texels per pixel, docs/projection.md). (Allowing texels up to
//! 1.19× the pixel instead lost 5 % of the oracle's gain in one evaluation view and saved
//! 8 % of the memory, docs/evaluation.md.) [`choose_scales`] then fits the wanted scales of one level
//! into that level's byte budget by halving, one step at a time, the cell whose photo bins
//! cover the smallest fraction of it (then the larger texture, then the lower index), so the
//! memory goes where the photos cover most of the cell. Deterministic.

use crate::photo::PixelFootprint;
use crate::photo::splatting::splat::footprint_area;

/// Bins per side of [`SizingBins`].
pub const SIZING_BINS: usize = 16;

/// GPU bytes of an RGBA8 texture of `texels × texels` with its full mip chain (4/3).
pub fn texture_bytes(texels: u32) -> u64 {
    (texels as u64 * texels as u64 * 4 * 4).div_ceil(3)
}

/// Per bin of a cell's existing texture, the side of the finest full-resolution photo pixel
/// seen there (existing texels; infinite where no footprint fell), and how many
/// full-resolution photo pixels the cell receives (all photos).
#[derive(Clone, Debug, PartialEq)]
pub struct SizingBins {
    /// Row-major [`SIZING_BINS`]² minima.
    pub side: Vec<f32>,
    /// Full-resolution photo pixels whose footprints fell on the texture (a footprint of an
    /// image `1/side_scale` times smaller counts `1/side_scale²`).
    pub pixels: f64,
}

impl Default for SizingBins {
    fn default() -> Self {
        SizingBins {
            side: vec![f32::INFINITY; SIZING_BINS * SIZING_BINS],
            pixels: 0.0,
        }
    }
}

impl SizingBins {
    /// Adds a footprint (corners in texels of a `base_texels` existing texture) cast from a
    /// photo image `1 / side_scale` times smaller than the full-resolution one (its side is
    /// multiplied by `side_scale` to give the full-resolution pixel's): it counts as
    /// `1 / side_scale²` delivered pixels, and its side enters the bins if `sizes` (the
    /// pixels the blend would give weight to).
    pub fn add(&mut self, fp: &PixelFootprint, base_texels: u32, side_scale: f32, sizes: bool) {
        let area = footprint_area(&fp.corners);
        if !(area > 0.0) {
            return;
        }
        let c = fp
            .corners
            .iter()
            .fold([0.0f32; 2], |a, p| [a[0] + 0.25 * p[0], a[1] + 0.25 * p[1]]);
        let n = SIZING_BINS as f32 / base_texels.max(1) as f32;
        let (bx, by) = ((c[0] * n).floor(), (c[1] * n).floor());
        if !(bx >= 0.0 && by >= 0.0 && bx < SIZING_BINS as f32 && by < SIZING_BINS as f32) {
            return;
        }
        self.pixels += 1.0 / (side_scale as f64 * side_scale as f64);
        if !sizes {
            return;
        }
        let side = area.sqrt() as f32 * side_scale;
        let b = &mut self.side[by as usize * SIZING_BINS + bx as usize];
        if side < *b {
            *b = side;
        }
    }

    /// Bins some footprint fell into.
    pub fn covered(&self) -> usize {
        self.side.iter().filter(|s| s.is_finite()).count()
    }

    /// The scale (a power of two, at least 1, at most `max_scale`) the bins want for
    /// `texels_per_pixel` texels per photo pixel side (1 in the module docs (`src/photo/sizing.rs`)), and no
    /// more than `texels_per_delivered` texels (at the existing texture's side `base_texels`
    /// times the scale) per photo pixel the cell receives; 1 without covered bins.
    pub fn wanted_scale(
        &self,
        max_scale: u32,
        texels_per_pixel: f64,
        base_texels: u32,
        texels_per_delivered: f64,
    ) -> u32 {
        let mut v: Vec<f32> = self
            .side
            .iter()
            .copied()
            .filter(|s| s.is_finite())
            .collect();
        if v.is_empty() {
            return 1;
        }
        let k = v.len() / 2;
        let (_, median, _) = v.select_nth_unstable_by(k, f32::total_cmp);
        let want = (texels_per_pixel.max(1e-3) / median.max(1e-6) as f64).log2() - 1e-9;
        let m = want.ceil().clamp(0.0, 16.0) as u32;
        let mut scale = 1u32 << m;
        let allowed = texels_per_delivered * self.pixels;
        while scale > max_scale.max(1)
            || (scale > 1 && (base_texels as f64 * scale as f64).powi(2) > allowed)
        {
            scale /= 2;
        }
        scale
    }
}

/// One cell's request for [`choose_scales`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SizeRequest {
    /// Side of the cell's existing texture, texels.
    pub base_texels: u32,
    /// The scale it wants ([`SizingBins::wanted_scale`]).
    pub scale: u32,
    /// Fraction of its bins photos cover, in [0, 1].
    pub covered: f64,
}

/// The scales granted to `requests` (same order) so that the photo textures of the cells
/// that want more than scale 1 fit into `budget_bytes` ([`texture_bytes`]; the cells at
/// scale 1 are not counted: their photo texture replaces one of the existing size), as in
/// the module docs (`src/photo/sizing.rs`).
pub fn choose_scales(requests: &[SizeRequest], budget_bytes: u64) -> Vec<u32> {
    let mut scales: Vec<u32> = requests.iter().map(|r| r.scale.max(1)).collect();
    let bytes = |i: usize, s: u32| {
        if s > 1 {
            texture_bytes(requests[i].base_texels * s)
        } else {
            0
        }
    };
    let mut total: u64 = (0..requests.len()).map(|i| bytes(i, scales[i])).sum();
    while total > budget_bytes {
        // the upsized cell photos cover least, then the larger texture, then the lower index
        let Some(i) = (0..requests.len())
            .filter(|&i| scales[i] > 1)
            .min_by(|&a, &b| {
                requests[a]
                    .covered
                    .total_cmp(&requests[b].covered)
                    .then(
                        (requests[b].base_texels * scales[b])
                            .cmp(&(requests[a].base_texels * scales[a])),
                    )
                    .then(a.cmp(&b))
            })
        else {
            break;
        };
        total -= bytes(i, scales[i]);
        scales[i] /= 2;
        total += bytes(i, scales[i]);
    }
    scales
}

#[cfg(test)]
mod tests {
    use super::*;

    fn fp(x: f32, y: f32, s: f32) -> PixelFootprint {
        PixelFootprint {
            cell: 0,
            pixel: [0, 0],
            corners: [[x, y], [x + s, y], [x + s, y + s], [x, y + s]],
            cos_view: 1.0,
            distance: 1.0,
            reconstructed: 0,
        }
    }

    #[test]
    fn wanted_scale_matches_the_finest_pixels() {
        // pixels of a tenth of a texel on the left half, 2 texels on the right half
        let mut b = SizingBins::default();
        for j in 0..64 {
            for i in 0..32 {
                b.add(&fp(i as f32 * 4.0, j as f32 * 4.0, 0.1), 256, 1.0, true);
            }
        }
        assert_eq!(b.covered(), 128);
        // a tenth: 2^ceil(log2(10)) = 16
        assert_eq!(b.wanted_scale(64, 1.0, 256, f64::INFINITY), 16);
        assert_eq!(b.wanted_scale(4, 1.0, 256, f64::INFINITY), 4);
        for j in 0..64 {
            for i in 32..64 {
                b.add(&fp(i as f32 * 4.0, j as f32 * 4.0, 2.0), 256, 1.0, true);
            }
        }
        // the median bin now holds a coarse pixel: no upsizing
        assert_eq!(b.wanted_scale(64, 1.0, 256, f64::INFINITY), 1);
        // a pixel of 0.6 texel: scale 2 (texels of 0.83 pixel),
        // cast from a 4x smaller image
        let mut c = SizingBins::default();
        c.add(&fp(10.0, 10.0, 2.4), 256, 0.25, true);
        assert_eq!(c.wanted_scale(64, 1.0, 256, f64::INFINITY), 2);
        // two texels per pixel side: one doubling more
        assert_eq!(c.wanted_scale(64, 2.0, 256, f64::INFINITY), 4);
        // a pixel of exactly half a texel: scale 2, not 4
        let mut e = SizingBins::default();
        e.add(&fp(10.0, 10.0, 0.5), 256, 1.0, true);
        assert_eq!(e.wanted_scale(64, 1.0, 256, f64::INFINITY), 2);
        assert_eq!(
            SizingBins::default().wanted_scale(64, 1.0, 256, f64::INFINITY),
            1
        );
        // 2048 footprints of a tenth of a texel: at 4 texels per delivered pixel, at most
        // 8192 texels, i.e. no enlargement of a 256-texel texture (65 536 texels)
        let mut few = SizingBins::default();
        for i in 0..2048 {
            few.add(
                &fp((i % 64) as f32 * 4.0, (i / 64) as f32 * 4.0, 0.1),
                256,
                1.0,
                true,
            );
        }
        assert_eq!(few.pixels, 2048.0);
        assert_eq!(few.wanted_scale(64, 1.0, 256, f64::INFINITY), 16);
        assert_eq!(few.wanted_scale(64, 1.0, 256, 4.0), 1);
        assert_eq!(few.wanted_scale(64, 1.0, 32, 4.0), 2);
        // footprints the blend would not use count as delivered pixels but do not size
        let mut unused = SizingBins::default();
        unused.add(&fp(10.0, 10.0, 0.1), 256, 1.0, false);
        assert_eq!((unused.pixels, unused.covered()), (1.0, 0));
        // footprints outside the texture are ignored
        let mut d = SizingBins::default();
        d.add(&fp(-5.0, 10.0, 0.1), 256, 1.0, true);
        d.add(&fp(300.0, 10.0, 0.1), 256, 1.0, true);
        assert_eq!(d.covered(), 0);
    }

    #[test]
    fn budget_goes_to_the_best_covered_cells() {
        let r = |scale, covered| SizeRequest {
            base_texels: 256,
            scale,
            covered,
        };
        let reqs = [r(8, 0.9), r(8, 0.1), r(4, 0.5), r(1, 1.0)];
        // everything fits
        let all: u64 = [2048u32, 2048, 1024]
            .iter()
            .map(|&t| texture_bytes(t))
            .sum();
        assert_eq!(choose_scales(&reqs, all), vec![8, 8, 4, 1]);
        // a little less: the least covered cell halves first
        assert_eq!(choose_scales(&reqs, all - 1), vec![8, 4, 4, 1]);
        // nothing: everyone back to the existing size
        assert_eq!(choose_scales(&reqs, 0), vec![1, 1, 1, 1]);
        // the granted bytes never exceed the budget
        for budget in [1u64 << 20, 5 << 20, 20 << 20, 40 << 20] {
            let s = choose_scales(&reqs, budget);
            let used: u64 = s
                .iter()
                .filter(|&&x| x > 1)
                .map(|&x| texture_bytes(256 * x))
                .sum();
            assert!(used <= budget, "{budget}: {s:?}");
        }
    }
}
