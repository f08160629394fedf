//! Per-texel accumulation of photo colour: one photo's deposits in one cell
//! ([`PhotoAccum`]); all photos of a run in one cell are merged by
//! [`crate::photo::blending::cell_accum::CellAccum`] (the sharpest photos win, weighted or best view).
//!
//! Colours are accumulated in the working space of a [`ColourSpace`] (linear light by
//! default: photo bytes decoded after the colour leveling, averaged, encoded when the cell
//! is blended).
//!
//! Per texel `t` and photo `p`, with footprints `f` depositing area `a_ft` (texels²), border
//! feather `φ_f`, surface footprint `r_f` (metres: `distance · pixel angle / cos_view`, the
//! length of the pixel on the surface where it is foreshortened) and view cosine `cos_f`:
//! `A = Σ a`, `W = Σ a φ`, `C = Σ a φ c`, `R = Σ a φ r`, `G = Σ a φ / cos`. The photo's colour
//! at the texel is `C / W` (the box filter of its pixels over the texel), its coverage
//! confidence `W / max(1, A)` (a texel only partly covered counts partly), and its
//! resolution there ([`CellContext::photo_resolution`]) `R/W + ε·cos θ·G/W`: the pixel size on
//! the surface plus the displacement an error `ε` of the cell's TIN causes along the photo's
//! rays. Sums are f32 and formed in footprint order, so results do not depend on threads.

use image::RgbImage;

use crate::colour::ColourSpace;
use crate::photo::PixelFootprint;
use crate::photo::splatting::colour_transform::ColourTransform;
use crate::photo::splatting::confidence::ConfidenceParams;
pub use crate::photo::splatting::samples::PhotoSamples;
use crate::photo::splatting::splat::{
    Deposit, MAX_SPLAT_BBOX, Splat, SplatKind, footprint_shape, splat_polygon_limited,
};
use crate::photo::splatting::strip::StripSplatter;
pub use crate::photo::splatting::texel_tiles::{TexelSums, TexelTiles};

/// One photo's deposits in one `texels × texels` cell texture (row-major per texel).
#[derive(Clone, Debug, PartialEq)]
pub struct PhotoAccum {
    /// Texture side in texels.
    pub texels: u32,
    /// Factor (a power of two, >= 1) from the footprints' texel units (the cell's active
    /// texture) to this texture's.
    pub scale: u32,
    /// Per texel, row-major: the sums (tiles allocated where footprints deposited).
    pub sums: TexelTiles,
    /// Footprints deposited exactly / by the bilinear fallback / skipped.
    pub kinds: [u64; 3],
}

impl PhotoAccum {
    /// An empty accumulator for footprints in this texture's texel units.
    pub fn new(texels: u32) -> PhotoAccum {
        PhotoAccum::with_scale(texels, 1)
    }

    /// An empty accumulator of `texels` side for footprints given in texel units of a
    /// texture `scale` times smaller (`scale` a power of two; corners are multiplied by it,
    /// exactly, and the size guard [`MAX_SPLAT_BBOX`] applies in the footprints' units).
    pub fn with_scale(texels: u32, scale: u32) -> PhotoAccum {
        PhotoAccum {
            texels,
            scale: scale.max(1),
            sums: TexelTiles::new(texels),
            kinds: [0; 3],
        }
    }

    /// Deposits a footprint of colour `rgb` (working space 0..1) with border feather
    /// `feather`, surface footprint `footprint_m` (metres) and `1 / cos_view` `grazing`.
    pub fn add(
        &mut self,
        fp: &PixelFootprint,
        rgb: [f32; 3],
        feather: f32,
        footprint_m: f32,
        grazing: f32,
    ) {
        self.add_clear(fp, rgb, feather, 1.0, footprint_m, grazing);
    }

    /// [`PhotoAccum::add`] of a pixel with occlusion weight `clear` in [0, 1].
    pub fn add_clear(
        &mut self,
        fp: &PixelFootprint,
        rgb: [f32; 3],
        feather: f32,
        clear: f32,
        footprint_m: f32,
        grazing: f32,
    ) {
        let sc = self.scale as f32;
        let corners = if self.scale == 1 {
            fp.corners
        } else {
            fp.corners.map(|c| [c[0] * sc, c[1] * sc])
        };
        let shape = footprint_shape(&corners);
        let q = feather;
        let deposit = SumsDeposit {
            sums: &mut self.sums,
            pixel: PixelSums {
                rgb,
                q,
                qr: q * footprint_m,
                qg: q * grazing,
                qo: q * clear,
            },
        };
        let bbox = MAX_SPLAT_BBOX * (self.scale as f64 * self.scale as f64);
        let s = match shape {
            Some((poly, area)) => splat_polygon_limited(&poly, area, self.texels, bbox, deposit),
            None => Splat {
                area: 0.0,
                kind: SplatKind::Skipped,
            },
        };
        self.kinds[match s.kind {
            SplatKind::Exact => 0,
            SplatKind::Bilinear => 1,
            SplatKind::Skipped => 2,
        }] += 1;
    }

    /// Deposits every footprint of `footprints` (all of this accumulator's cell) with the
    /// colour of its pixel in `image` (the image the footprints were cast for, by a camera
    /// of focal lengths `focal_px`) mapped by `transform`, feather from `params`, averaged
    /// in linear light. (Preparing [`PhotoSamples`] once and calling
    /// [`PhotoAccum::add_samples`] gives the same sums.)
    pub fn add_all<'f>(
        &mut self,
        footprints: impl IntoIterator<Item = &'f PixelFootprint>,
        image: &RgbImage,
        focal_px: [f64; 2],
        transform: &ColourTransform,
        params: &ConfidenceParams,
    ) {
        self.add_samples(
            footprints,
            &PhotoSamples::new(image, focal_px, transform, params, ColourSpace::Linear),
        );
    }

    /// [`PhotoAccum::add_all`] with the photo's colours, border feather and pixel angle prepared.
    pub fn add_samples<'f>(
        &mut self,
        footprints: impl IntoIterator<Item = &'f PixelFootprint>,
        photo: &PhotoSamples,
    ) {
        STRIPS.with_borrow_mut(|strips| self.add_samples_with(footprints, photo, strips));
    }

    /// [`PhotoAccum::add_samples`] with the given run splatter (module [`crate::photo::splatting::strip`]):
    /// strips of footprints that share edges are splatted together, the others (and those
    /// within 2 × 2 texels, [`crate::photo::splatting::strip::ALONE_TEXELS`]) one by one.
    fn add_samples_with<'f>(
        &mut self,
        footprints: impl IntoIterator<Item = &'f PixelFootprint>,
        photo: &PhotoSamples,
        strips: &mut StripSplatter,
    ) {
        let (w, h) = photo.image.dimensions();
        let (raw, lut) = (photo.image.as_raw(), &photo.lut);
        let sc = self.scale as f32;
        for fp in footprints {
            let [c, r] = fp.pixel;
            if c >= w || r >= h || photo.excluded(fp).is_some() {
                continue;
            }
            let o = 3 * (r as usize * w as usize + c as usize);
            let rgb = [
                lut[0][raw[o] as usize],
                lut[1][raw[o + 1] as usize],
                lut[2][raw[o + 2] as usize],
            ];
            let border = photo.feather.at(fp.pixel) as f32;
            let clear = photo.occlusion_weight(fp);
            let grazing = 1.0 / fp.cos_view.max(MIN_COS_VIEW);
            let footprint = fp.distance * photo.pixel_angle * grazing;
            if !(grazing.is_finite() && footprint.is_finite()) {
                self.kinds[2] += 1;
                continue;
            }
            let corners = if self.scale == 1 {
                fp.corners
            } else {
                fp.corners.map(|c| [c[0] * sc, c[1] * sc])
            };
            let q = border;
            let values = [
                1.0,
                q,
                q * rgb[0],
                q * rgb[1],
                q * rgb[2],
                q * footprint,
                q * grazing,
                q * clear,
            ];
            if corners.iter().flatten().all(|v| v.is_finite())
                && strips.offer(corners, fp.pixel, values, &mut self.sums)
            {
                self.kinds[0] += 1;
                continue;
            }
            // (alone; the strip goes on)
            self.add_clear(fp, rgb, border, clear, footprint, grazing);
        }
        strips.flush(&mut self.sums);
    }

    /// The photo's coverage confidence at texel `t`: `W / max(1, A)`, in [0, 1].
    #[inline]
    pub fn confidence(&self, t: usize) -> f32 {
        let s = self.sums.get(t);
        (s.weight / s.coverage.max(1.0)).clamp(0.0, 1.0)
    }

    /// The photo's colour (working space 0..1) at texel `t`, if any feathered deposit
    /// reached it.
    #[inline]
    pub fn colour_at(&self, t: usize) -> Option<[f32; 3]> {
        let s = self.sums.get(t);
        (s.weight > 0.0).then(|| s.colour.map(|c| (c / s.weight).clamp(0.0, 1.0)))
    }

    /// The mean surface footprint (metres) and mean `1 / cos_view` of the photo's deposits at
    /// texel `t` (NaN without deposits).
    #[inline]
    pub fn footprint_at(&self, t: usize) -> [f32; 2] {
        let s = self.sums.get(t);
        [s.footprint / s.weight, s.grazing / s.weight]
    }
}

/// One pixel's contribution per texel² of its footprint to a [`TexelSums`] record.
#[derive(Clone, Copy)]
struct PixelSums {
    rgb: [f32; 3],
    /// Feather, and the feather times the footprint (metres), `1 / cos_view` and occlusion
    /// weight.
    q: f32,
    qr: f32,
    qg: f32,
    qo: f32,
}

impl PixelSums {
    /// Adds the pixel's sums over `w` texels² of its footprint to `s`.
    #[inline(always)]
    fn add_to(&self, s: &mut TexelSums, w: f64) {
        let w = w as f32;
        s.coverage += w;
        let wq = w * self.q;
        s.weight += wq;
        for k in 0..3 {
            s.colour[k] += wq * self.rgb[k];
        }
        s.footprint += w * self.qr;
        s.grazing += w * self.qg;
        s.clear += w * self.qo;
    }
}

/// A pixel's [`Deposit`] into a cell's texel sums: single texels by lookup, runs of a texel
/// row one tile row at a time.
struct SumsDeposit<'a> {
    sums: &'a mut TexelTiles,
    pixel: PixelSums,
}

impl Deposit for SumsDeposit<'_> {
    #[inline(always)]
    fn texel(&mut self, t: usize, w: f64) {
        if let Some(s) = self.sums.get_mut(t) {
            self.pixel.add_to(s, w);
        }
    }

    #[inline]
    fn run(&mut self, t: usize, ws: &[f64]) {
        let mut k = 0;
        while k < ws.len() {
            let n = self.sums.run_len(t + k, ws.len() - k);
            if n == 0 {
                return;
            }
            let part = &ws[k..k + n];
            // (a tile is allocated only for a positive weight, as by single texels)
            if part.iter().any(|&w| w > 0.0)
                && let Some(records) = self.sums.run_mut(t + k, n)
            {
                for (s, &w) in records.iter_mut().zip(part) {
                    if w > 0.0 {
                        self.pixel.add_to(s, w);
                    }
                }
            }
            k += n;
        }
    }
}

thread_local! {
    /// The run splatter of [`PhotoAccum::add_samples`] (its buffers reused per thread).
    static STRIPS: std::cell::RefCell<StripSplatter> = std::cell::RefCell::new(StripSplatter::default());
}

/// View cosines below this count as this (a ray grazing the surface).
const MIN_COS_VIEW: f32 = 1e-3;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photo::blending::cell_accum::{BlendMode, CellAccum, CellContext};
    use crate::photo::splatting::occlusion::OcclusionMap;

    pub(crate) fn fp(pixel: [u32; 2], corners: [[f32; 2]; 4], cos_view: f32) -> PixelFootprint {
        PixelFootprint {
            cell: 0,
            pixel,
            corners,
            cos_view,
            distance: 10.0,
            reconstructed: 0,
        }
    }

    fn square(x: f32, y: f32, s: f32) -> [[f32; 2]; 4] {
        [[x, y], [x + s, y], [x + s, y + s], [x, y + s]]
    }

    /// No feather: every pixel of the small test images counts fully.
    fn params() -> ConfidenceParams {
        ConfidenceParams {
            feather: 0.0,
            ..ConfidenceParams::default()
        }
    }

    /// Samples of `img` averaged as sRGB values, focal length 1000 px.
    fn srgb_samples<'a>(img: &'a RgbImage) -> PhotoSamples<'a> {
        PhotoSamples::new(
            img,
            [1000.0; 2],
            &ColourTransform::IDENTITY,
            &params(),
            ColourSpace::Srgb,
        )
    }

    #[test]
    fn a_photo_clear_of_its_occlusion_edges_wins_over_one_next_to_them() {
        // two 16 x 8 photos whose every pixel deposits into its own texel; photo A's rows
        // 0..2 are sky (an occlusion edge along row 2), photo B sees everything and is 1.5x
        // coarser on the surface (distance 15 m against 10 m)
        let (red, blue) = (
            RgbImage::from_pixel(16, 8, image::Rgb([250, 0, 0])),
            RgbImage::from_pixel(16, 8, image::Rgb([0, 0, 250])),
        );
        let grid = |rows: std::ops::Range<u32>, distance: f32| -> Vec<PixelFootprint> {
            rows.flat_map(|r| (0..16u32).map(move |c| (c, r)))
                .map(|(c, r)| PixelFootprint {
                    distance,
                    ..fp([c, r], square(c as f32, r as f32, 1.0), 1.0)
                })
                .collect()
        };
        let (fa, fb) = (grid(2..8, 10.0), grid(0..8, 15.0));
        let set = crate::photo::FootprintSet {
            cells: vec![crate::photo::CellFootprints {
                cell: 0,
                chunks: vec![fa.clone()],
            }],
            ..crate::photo::FootprintSet::default()
        };
        let map = OcclusionMap::from_footprints(&set, 16, 8, 1.0, 0.1);
        let errors = [0.0f32];
        let merged = |margin: f64, with_b: bool| {
            let p = ConfidenceParams {
                occlusion_margin_px: margin,
                ..params()
            };
            let sa = PhotoSamples::new(
                &red,
                [1000.0; 2],
                &ColourTransform::IDENTITY,
                &p,
                ColourSpace::Srgb,
            )
            .with_occlusion(&map, 1.0, 1000.0, &errors, &p);
            let mut a = PhotoAccum::new(16);
            a.add_samples(&fa, &sa);
            let ctx = CellContext::flat(16, 0.0, 1.0);
            let (mut acc, _) = CellAccum::from_photo(a, 0, BlendMode::Confidence, ctx, &p);
            if with_b {
                let sb = PhotoSamples::new(
                    &blue,
                    [1000.0; 2],
                    &ColourTransform::IDENTITY,
                    &p,
                    ColourSpace::Srgb,
                );
                let mut b = PhotoAccum::new(16);
                b.add_samples(&fb, &sb);
                acc.merge(&b, 1);
            }
            acc
        };
        let acc = merged(3.0, true);
        // row 2 touches A's edge: B wins there; rows from 5 on are clear in A: A wins (the
        // sharper); in between the weights cross over
        assert_eq!(acc.best_photo(2 * 16 + 8), Some(1));
        let red_share = |t: usize| acc.colour_at(t).map(|c| c[0] / (c[0] + c[2])).unwrap();
        assert!(red_share(2 * 16 + 8) < 0.01);
        assert_eq!(acc.best_photo(6 * 16 + 8), Some(0));
        assert!(red_share(6 * 16 + 8) > 0.8);
        assert!(red_share(3 * 16 + 8) < red_share(4 * 16 + 8));
        // without the margin A wins everywhere it sees
        let acc = merged(0.0, true);
        assert_eq!(acc.best_photo(2 * 16 + 8), Some(0));
        // and alone, A gives its colour next to its edge as well, with full confidence
        let acc = merged(3.0, false);
        assert!(acc.colour_at(2 * 16 + 8).is_some_and(|c| c[0] > 0.9));
        assert_eq!(acc.confidence(2 * 16 + 8), 1.0);
    }

    #[test]
    fn constant_colour_stays_constant_under_any_footprints() {
        let img = RgbImage::from_pixel(40, 40, image::Rgb([200, 40, 90]));
        // a sheared, rotated, non-uniform grid of quads (a perspective-like map) over 8x8 texels
        let map = |c: f32, r: f32| {
            let (u, v) = (c / 40.0, r / 40.0);
            [0.3 + 7.2 * u + 0.4 * v * v, 0.2 + 7.5 * v + 0.6 * u * v]
        };
        let fps: Vec<PixelFootprint> = (0..40)
            .flat_map(|r| (0..40).map(move |c| (c, r)))
            .map(|(c, r)| {
                let (cf, rf) = (c as f32, r as f32);
                fp(
                    [c, r],
                    [
                        map(cf, rf),
                        map(cf + 1.0, rf),
                        map(cf + 1.0, rf + 1.0),
                        map(cf, rf + 1.0),
                    ],
                    0.8,
                )
            })
            .collect();
        for space in [ColourSpace::Linear, ColourSpace::Srgb] {
            let mut a = PhotoAccum::new(8);
            a.add_samples(
                &fps,
                &PhotoSamples::new(
                    &img,
                    [1000.0; 2],
                    &ColourTransform::IDENTITY,
                    &params(),
                    space,
                ),
            );
            let want = [200u8, 40, 90].map(|v| space.decode_u8(v));
            let mut n = 0;
            for t in 0..64 {
                if let Some(c) = a.colour_at(t) {
                    n += 1;
                    for k in 0..3 {
                        assert!((c[k] - want[k]).abs() < 1e-5, "texel {t}: {c:?}");
                    }
                    let q = a.confidence(t);
                    assert!((0.0..=1.0 + 1e-6).contains(&q), "{q}");
                    // every pixel is 10 m away, 1 mrad, seen at cos 0.8
                    let [r, g] = a.footprint_at(t);
                    assert!(
                        (r - 0.01 / 0.8).abs() < 1e-6 && (g - 1.25).abs() < 1e-5,
                        "{r} {g}"
                    );
                }
            }
            assert!(n >= 49, "{n} texels coloured");
            // interior texels are fully covered: full confidence (the view angle is in the resolution)
            assert!((a.confidence(3 * 8 + 3) - 1.0).abs() < 1e-4);
        }
    }

    #[test]
    // indexed loops: each index serves more than one array or lookup
    #[allow(clippy::needless_range_loop)]
    fn texel_aligned_and_finer_footprints_reproduce_a_texture() {
        let tex = RgbImage::from_fn(6, 6, |x, y| {
            image::Rgb([(x * 40) as u8, (y * 40) as u8, ((x * y) * 7) as u8])
        });
        // one photo pixel per texel, exactly covering it
        let fps: Vec<PixelFootprint> = (0..6)
            .flat_map(|r| (0..6).map(move |c| fp([c, r], square(c as f32, r as f32, 1.0), 1.0)))
            .collect();
        let mut a = PhotoAccum::new(6);
        a.add_samples(&fps, &srgb_samples(&tex));
        for (x, y, p) in tex.enumerate_pixels() {
            let c = a.colour_at((y * 6 + x) as usize).unwrap();
            for k in 0..3 {
                assert!((c[k] * 255.0 - p.0[k] as f32).abs() < 1e-3);
            }
            assert!((a.confidence((y * 6 + x) as usize) - 1.0).abs() < 1e-6);
        }
        // 2x2 photo pixels per texel: each texel gets the box average of its four pixels,
        // of the sRGB values or of the linear intensities
        let fine = RgbImage::from_fn(12, 12, |x, y| {
            image::Rgb([(x * 20) as u8, (y * 20) as u8, ((x + y) % 3 * 50) as u8])
        });
        let fps: Vec<PixelFootprint> = (0..12)
            .flat_map(|r| {
                (0..12).map(move |c| fp([c, r], square(c as f32 * 0.5, r as f32 * 0.5, 0.5), 1.0))
            })
            .collect();
        for space in [ColourSpace::Srgb, ColourSpace::Linear] {
            let mut a = PhotoAccum::new(6);
            a.add_samples(
                &fps,
                &PhotoSamples::new(
                    &fine,
                    [1000.0; 2],
                    &ColourTransform::IDENTITY,
                    &params(),
                    space,
                ),
            );
            for j in 0..6u32 {
                for i in 0..6u32 {
                    let c = a.colour_at((j * 6 + i) as usize).unwrap();
                    for k in 0..3 {
                        let mean: f32 = [(0, 0), (1, 0), (0, 1), (1, 1)]
                            .iter()
                            .map(|(dx, dy)| {
                                space.decode_u8(fine.get_pixel(2 * i + dx, 2 * j + dy).0[k])
                            })
                            .sum::<f32>()
                            / 4.0;
                        assert!(
                            (c[k] - mean).abs() < 1e-5,
                            "{space:?} texel {i},{j} ch {k}: {} vs {mean}",
                            c[k]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn a_finer_texture_gets_the_same_deposits_as_scaled_footprints() {
        let img = RgbImage::from_fn(16, 16, |x, y| {
            image::Rgb([(x * 13) as u8, (y * 11) as u8, ((x ^ y) * 9) as u8])
        });
        let fps: Vec<PixelFootprint> = (0..16)
            .flat_map(|r| (0..16).map(move |c| (c, r)))
            .map(|(c, r)| {
                let (x, y) = (0.37 * c as f32 + 0.1, 0.29 * r as f32 + 0.05 * c as f32);
                fp(
                    [c, r],
                    [
                        [x, y],
                        [x + 0.37, y + 0.05],
                        [x + 0.4, y + 0.33],
                        [x, y + 0.29],
                    ],
                    0.6,
                )
            })
            .collect();
        let doubled: Vec<PixelFootprint> = fps
            .iter()
            .map(|f| PixelFootprint {
                corners: f.corners.map(|c| [2.0 * c[0], 2.0 * c[1]]),
                ..*f
            })
            .collect();
        let s = srgb_samples(&img);
        let mut scaled = PhotoAccum::with_scale(16, 2);
        scaled.add_samples(&fps, &s);
        let mut direct = PhotoAccum::new(16);
        direct.add_samples(&doubled, &s);
        assert_eq!(scaled.sums, direct.sums);
        let mut n = 0;
        scaled.sums.for_each(|_, t| n += (t.weight > 0.0) as usize);
        assert!(n > 100);
    }

    #[test]
    fn large_footprints_deposit_row_runs_as_single_texels() {
        // footprints of 5 to 30 texels, partly outside the texture: the rasterizer's row runs
        // give the same records as depositing every texel's piece on its own (the run
        // splatter, which takes the footprints of up to 16 texels, up to f32 rounding)
        let img = RgbImage::from_fn(8, 8, |x, y| {
            image::Rgb([(x * 31) as u8, (y * 29) as u8, 77])
        });
        let s = srgb_samples(&img);
        let fps: Vec<PixelFootprint> = (0..8)
            .flat_map(|r| (0..8).map(move |c| (c, r)))
            .map(|(c, r)| {
                let (x, y) = (9.0 * c as f32 - 7.3, 8.0 * r as f32 - 5.1);
                let (u, v) = (5.0 + 3.0 * (c % 4) as f32, 2.5 + 4.0 * (r % 3) as f32);
                fp(
                    [c, r],
                    [
                        [x, y],
                        [x + u, y + 0.4 * v],
                        [x + 0.7 * u, y + v],
                        [x - 0.2 * u, y + 0.8 * v],
                    ],
                    0.8,
                )
            })
            .collect();
        let mut acc = PhotoAccum::new(64);
        acc.add_samples(&fps, &s);
        let mut single = TexelTiles::new(64);
        for f in &fps {
            let [c, r] = f.pixel;
            let o = 3 * (r as usize * 8 + c as usize);
            let raw = s.image.as_raw();
            let pixel = PixelSums {
                rgb: [0, 1, 2].map(|k| s.lut[k][raw[o + k] as usize]),
                q: s.feather.at(f.pixel) as f32,
                qr: 0.0,
                qg: 0.0,
                qo: 0.0,
            };
            let grazing = 1.0 / f.cos_view.max(MIN_COS_VIEW);
            let footprint = f.distance * s.pixel_angle * grazing;
            let pixel = PixelSums {
                qr: pixel.q * footprint,
                qg: pixel.q * grazing,
                qo: pixel.q * s.occlusion_weight(f),
                ..pixel
            };
            let kind = crate::photo::splat_footprint(&f.corners, 64, |t, w| {
                if let Some(rec) = single.get_mut(t) {
                    pixel.add_to(rec, w);
                }
            });
            assert_eq!(kind.kind, SplatKind::Exact);
        }
        // (equal up to the f32 rounding of the run splatter's sums, `super::strip`)
        for t in 0..64 * 64 {
            let (a, b) = (acc.sums.get(t), single.get(t));
            let (fa, fb) = (
                [
                    a.coverage,
                    a.weight,
                    a.colour[0],
                    a.colour[1],
                    a.colour[2],
                    a.footprint,
                ],
                [
                    b.coverage,
                    b.weight,
                    b.colour[0],
                    b.colour[1],
                    b.colour[2],
                    b.footprint,
                ],
            );
            for (x, y) in fa.iter().zip(&fb) {
                assert!(
                    (x - y).abs() <= 2e-5 * (1.0 + y.abs()),
                    "texel {t}: {a:?} {b:?}"
                );
            }
            assert!((a.grazing - b.grazing).abs() <= 2e-5 * (1.0 + b.grazing.abs()));
            assert!((a.clear - b.clear).abs() <= 2e-5 * (1.0 + b.clear.abs()));
        }
        let mut n = 0;
        acc.sums.for_each(|_, t| n += (t.weight > 0.0) as usize);
        assert!(n > 1500, "{n} texels");
    }

    #[test]
    fn degenerate_footprints_give_no_nan() {
        let img = RgbImage::from_pixel(4, 1, image::Rgb([10, 20, 30]));
        let fps = [
            fp([0, 0], [[1.0, 1.0]; 4], 1.0),
            fp(
                [1, 0],
                [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]],
                0.0,
            ),
            fp(
                [2, 0],
                [[f32::NAN, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]],
                f32::NAN,
            ),
            fp(
                [3, 0],
                [[0.5, 0.5], [3.5, 3.5], [3.5, 0.5], [0.5, 3.5]],
                1.0,
            ),
        ];
        let mut a = PhotoAccum::new(4);
        a.add_all(
            &fps,
            &img,
            [1000.0; 2],
            &ColourTransform::IDENTITY,
            &params(),
        );
        for t in 0..16 {
            assert!(a.confidence(t).is_finite());
            let s = *a.sums.get(t);
            assert!(
                s.colour
                    .iter()
                    .chain([&s.weight, &s.coverage, &s.footprint, &s.grazing])
                    .all(|v| v.is_finite())
            );
            if let Some(c) = a.colour_at(t) {
                assert!(c.iter().all(|v| v.is_finite()));
                assert!(a.footprint_at(t).iter().all(|v| v.is_finite()));
            }
        }
        assert_eq!(a.kinds[2], 1); // the NaN footprint
    }

    #[test]
    fn the_sharper_photo_wins() {
        // two photos of one texel: red from 10 m, blue from 40 m (4x coarser)
        let red = RgbImage::from_pixel(1, 1, image::Rgb([255, 0, 0]));
        let blue = RgbImage::from_pixel(1, 1, image::Rgb([0, 0, 255]));
        let one = |dist: f32, img: &RgbImage| {
            let mut a = PhotoAccum::new(1);
            let f = PixelFootprint {
                distance: dist,
                ..fp([0, 0], square(0.0, 0.0, 1.0), 1.0)
            };
            a.add_samples(&[f], &srgb_samples(img));
            a
        };
        let (a, b) = (one(10.0, &red), one(40.0, &blue));
        let ctx = CellContext::flat(1, 0.0, 1.0);
        for (mode, first_red) in [
            (BlendMode::Confidence, true),
            (BlendMode::Confidence, false),
            (BlendMode::Best, true),
            (BlendMode::Best, false),
        ] {
            let mut acc = CellAccum::new(1, 1, mode, ctx.clone(), &params());
            // the same two merges in either order: the result must not depend on it
            #[allow(clippy::if_same_then_else)]
            let written = if first_red {
                acc.merge(&a, 0) + acc.merge(&b, 1)
            } else {
                acc.merge(&b, 1) + acc.merge(&a, 0)
            };
            assert_eq!(written, 2);
            let c = acc.colour_at(0).unwrap();
            assert!((acc.confidence(0) - 1.0).abs() < 1e-6);
            match mode {
                // weights 1 : 4^-4: red with 255/256 of the weight
                BlendMode::Confidence => {
                    assert!((c[0] - 256.0 / 257.0).abs() < 1e-5 && c[2] < 0.004, "{c:?}")
                }
                BlendMode::Best => assert_eq!(c, [1.0, 0.0, 0.0]),
            }
            assert!(acc.resolution_at(0) < 0.0105, "{}", acc.resolution_at(0));
            // the red photo (number 0) supplies the texel
            assert_eq!(acc.best_photo(0), Some(0));
        }
        // a cell's first photo handed over equals merging it into an empty accumulator
        for mode in [BlendMode::Confidence, BlendMode::Best] {
            let mut merged = CellAccum::new(1, 1, mode, ctx.clone(), &params());
            let n = merged.merge(&a, 0) + merged.merge(&b, 1);
            let (mut adopted, m) =
                CellAccum::from_photo(a.clone(), 0, mode, ctx.clone(), &params());
            assert_eq!(n, m + adopted.merge(&b, 1));
            assert_eq!(merged, adopted);
        }
        let empty = CellAccum::new(1, 1, BlendMode::Best, ctx, &params());
        assert!(empty.colour_at(0).is_none());
        assert_eq!(empty.resolution_at(0), f32::INFINITY);
    }

    #[test]
    // indexed loops: each index serves more than one array or lookup
    #[allow(clippy::needless_range_loop)]
    fn coloured_texels_visit_what_the_accessors_give() {
        // two photos over parts of a 40 x 40 texture (several tiles, some untouched)
        let img = RgbImage::from_fn(8, 8, |x, y| {
            image::Rgb([(x * 30) as u8, (y * 30) as u8, 99])
        });
        let photo = |x0: f32, y0: f32, dist: f32| {
            let mut a = PhotoAccum::new(40);
            let fps: Vec<PixelFootprint> = (0..8)
                .flat_map(|r| (0..8).map(move |c| (c, r)))
                .map(|(c, r)| PixelFootprint {
                    distance: dist,
                    ..fp(
                        [c, r],
                        square(x0 + 1.7 * c as f32, y0 + 1.3 * r as f32, 1.6),
                        0.9,
                    )
                })
                .collect();
            a.add_samples(&fps, &srgb_samples(&img));
            a
        };
        let ctx = CellContext::flat(40, 0.1, 1.0);
        for mode in [BlendMode::Confidence, BlendMode::Best] {
            let mut acc = CellAccum::new(40, 1, mode, ctx.clone(), &params());
            acc.merge(&photo(0.5, 0.5, 10.0), 0);
            acc.merge(&photo(6.2, 3.1, 14.0), 1);
            let mut seen = vec![false; 1600];
            acc.for_each_coloured(|t, c, conf, res, best| {
                seen[t] = true;
                assert_eq!(Some(c), acc.colour_at(t));
                assert_eq!(
                    (conf, res, best),
                    (acc.confidence(t), acc.resolution_at(t), acc.best_photo(t))
                );
            });
            for t in 0..1600 {
                assert_eq!(seen[t], acc.has_colour(t), "texel {t}");
            }
            assert!(seen.iter().filter(|s| **s).count() > 100 && seen.iter().any(|s| !*s));
        }
    }

    #[test]
    fn a_deferred_photo_reads_as_its_settled_records() {
        // one photo over part of a 40 x 40 texture: the deferred accumulator's visits and
        // accessors equal those of `from_photo`'s records, bit for bit, in both modes
        let img = RgbImage::from_fn(8, 8, |x, y| {
            image::Rgb([(x * 30) as u8, (y * 30) as u8, 99])
        });
        let fps: Vec<PixelFootprint> = (0..8)
            .flat_map(|r| (0..8).map(move |c| (c, r)))
            .map(|(c, r)| {
                fp(
                    [c, r],
                    square(0.5 + 1.7 * c as f32, 0.5 + 1.3 * r as f32, 1.6),
                    0.5 + 0.05 * c as f32,
                )
            })
            .collect();
        let ctx = CellContext::flat(40, 0.1, 1.0);
        for mode in [BlendMode::Confidence, BlendMode::Best] {
            let photo = || {
                let mut a = PhotoAccum::new(40);
                a.add_samples(&fps, &srgb_samples(&img));
                a
            };
            let (settled, written) =
                CellAccum::from_photo(photo(), 3, mode, ctx.clone(), &params());
            let mut deferred = CellAccum::deferred(photo(), 3, mode, ctx.clone(), &params());
            assert_eq!(deferred.deferred_photo(), Some(3));
            let visits = |acc: &CellAccum| {
                let mut v = Vec::new();
                acc.for_each_coloured(|t, c, conf, res, best| v.push((t, c, conf, res, best)));
                v
            };
            let (a, b) = (visits(&settled), visits(&deferred));
            assert_eq!(a, b);
            assert_eq!(a.len() as u64, written);
            for t in 0..1600 {
                assert_eq!(settled.has_colour(t), deferred.has_colour(t));
                assert_eq!(settled.colour_at(t), deferred.colour_at(t));
                assert_eq!(settled.best_photo(t), deferred.best_photo(t));
                assert_eq!(
                    settled.confidence(t).to_bits(),
                    deferred.confidence(t).to_bits()
                );
                assert_eq!(
                    settled.resolution_at(t).to_bits(),
                    deferred.resolution_at(t).to_bits()
                );
            }
            assert_eq!(deferred.settle(), written);
            assert_eq!(deferred, settled);
            assert_eq!(deferred.settle(), 0, "settled twice");
        }
    }

    #[test]
    fn resolution_rule_terms() {
        // a 2 x 2 existing texture: flat, 60°, vertical and 87°; ortho of 1 m, TIN error 0.5 m
        let ctx = CellContext {
            base_texels: 2,
            cos_slope: vec![1.0, 0.5, 0.0, 0.05],
            max_error: 0.5,
            existing_ground: 1.0,
            texel_ground: 0.25,
        };
        assert_eq!(ctx.existing_resolution(0), 1.5);
        assert_eq!(ctx.existing_resolution(1), 2.5);
        assert_eq!(ctx.existing_resolution(2), 20.5);
        assert_eq!(ctx.existing_resolution(3), 20.5);
        // a photo pixel of 0.1 m seen at cos 0.25 (g = 4): on flat ground the TIN error moves
        // it by 2 m, on the vertical texel not at all
        assert_eq!(ctx.photo_resolution(0, [0.1, 4.0]), 2.1);
        assert_eq!(ctx.photo_resolution(2, [0.1, 4.0]), 0.1);
        // texels of a 4x finer texture map onto the existing ones
        assert_eq!(ctx.base_index(0, 8, 4), 0);
        assert_eq!(ctx.base_index(7, 8, 4), 1);
        assert_eq!(ctx.base_index(4 * 8 + 3, 8, 4), 2);
        assert_eq!(ctx.base_index(63, 8, 4), 3);
        // the indexer agrees with base_index, by shifts and by division
        for (texels, scale, base) in [(8u32, 4u32, 2u32), (12, 3, 4), (16, 1, 16), (10, 2, 5)] {
            let c = CellContext::flat(base, 0.0, 1.0);
            let f = c.base_indexer(texels, scale);
            for t in 0..(texels * texels) as usize {
                assert_eq!(f(t), c.base_index(t, texels, scale), "{texels} {scale} {t}");
            }
        }
    }
}
