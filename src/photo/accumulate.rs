//! Per-texel accumulation of photo colour: one photo's deposits in one cell
//! ([`PhotoAccum`]) and all photos of a run in one cell ([`CellAccum`], by confidence-weighted
//! blend or best view).
//!
//! Colours are accumulated as sRGB-encoded values in [0, 1] (the encoding the photos, the
//! ortho textures and the resampling stage use), not in linear light: the stores' textures
//! are averaged in sRGB everywhere else too, so photo and ortho colours stay comparable
//! (and the per-photo colour leveling is an affine map in the same space).
//!
//! Per texel `t` and photo `p`, with footprints `f` depositing area `a_ft` (texels²) and
//! confidence `q_f` ([`super::ConfidenceParams`]):
//! `A = Σ a_ft` (coverage), `Q = Σ a_ft q_f`, `C = Σ a_ft q_f c_f`; the photo's colour at
//! the texel is `C / Q` and its confidence `Q / max(1, A)` (a texel only partly covered
//! counts only partly). Sums are f32 and formed in footprint order, so results do not
//! depend on threads.

use image::RgbImage;

use super::confidence::{BorderFeather, ConfidenceParams, confidence_with_border};
use super::level::ColourTransform;
use super::splat::{Splat, SplatKind, footprint_shape, splat_polygon};
use super::PixelFootprint;

/// How several photos' colours combine in a texel.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum BlendMode {
    /// Average of the photos' colours weighted by their confidence-weighted coverage `Q`.
    #[default]
    Confidence,
    /// The colour of the photo with the highest texel confidence (first photo on ties).
    Best,
}

impl BlendMode {
    /// The name stored in the manifest: "blend" or "best".
    pub fn name(self) -> &'static str {
        match self {
            BlendMode::Confidence => "blend",
            BlendMode::Best => "best",
        }
    }
}

/// The sums of one texel (kept together: a deposit touches one record).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexelSums {
    /// `A`: deposited footprint area (texels²).
    pub coverage: f32,
    /// `Q`: confidence-weighted area.
    pub weight: f32,
    /// `C`: confidence-weighted area times colour (sRGB 0..1).
    pub colour: [f32; 3],
}

/// A photo image prepared for splatting: its 8-bit values mapped by a colour transform
/// (per channel, the same numbers as applying the transform to each pixel) and the border
/// feather of every pixel ([`ConfidenceParams::border_feather`]).
#[derive(Clone, Debug)]
pub struct PhotoSamples<'a> {
    image: &'a RgbImage,
    lut: [[f32; 256]; 3],
    feather: BorderFeather,
}

impl<'a> PhotoSamples<'a> {
    /// Prepares `image` with `transform` and the feather of `params`.
    pub fn new(image: &'a RgbImage, transform: &ColourTransform, params: &ConfidenceParams) -> PhotoSamples<'a> {
        let lut = std::array::from_fn(|k| {
            std::array::from_fn(|v| {
                let mut rgb = [0.0; 3];
                rgb[k] = v as f32 / 255.0;
                transform.apply(rgb)[k]
            })
        });
        PhotoSamples { image, lut, feather: params.border_feather(image.width(), image.height()) }
    }
}

/// One photo's deposits in one `texels × texels` cell texture (row-major per texel).
#[derive(Clone, Debug, PartialEq)]
pub struct PhotoAccum {
    /// Texture side in texels.
    pub texels: u32,
    /// Per texel, row-major: the sums `A`, `Q`, `C`.
    pub sums: Vec<TexelSums>,
    /// Footprints deposited exactly / by the bilinear fallback / skipped.
    pub kinds: [u64; 3],
}

impl PhotoAccum {
    /// An empty accumulator.
    pub fn new(texels: u32) -> PhotoAccum {
        let n = texels as usize * texels as usize;
        PhotoAccum { texels, sums: vec![TexelSums::default(); n], kinds: [0; 3] }
    }

    /// Deposits a footprint of colour `rgb` (sRGB 0..1) and confidence `conf(area)` (given
    /// the footprint's area in texels², see [`footprint_area`]).
    pub fn add(&mut self, fp: &PixelFootprint, rgb: [f32; 3], conf: impl FnOnce(f64) -> f64) {
        let shape = footprint_shape(&fp.corners);
        let q = conf(shape.map_or(0.0, |(_, a)| if a.is_finite() { a } else { 0.0 })) as f32;
        let sums = &mut self.sums;
        let deposit = |i: usize, w: f64| {
            let w = w as f32;
            let s = &mut sums[i];
            s.coverage += w;
            let wq = w * q;
            s.weight += wq;
            for k in 0..3 {
                s.colour[k] += wq * rgb[k];
            }
        };
        let s = match shape {
            Some((poly, area)) => splat_polygon(&poly, area, self.texels, deposit),
            None => Splat { area: 0.0, kind: SplatKind::Skipped },
        };
        self.kinds[match s.kind {
            SplatKind::Exact => 0,
            SplatKind::Bilinear => 1,
            SplatKind::Skipped => 2,
        }] += 1;
    }

    /// Deposits every footprint of `footprints` (all of this accumulator's cell) with the
    /// colour of its pixel in `image` (the image the footprints were cast for) mapped by
    /// `transform`, and confidence from `params`. (Preparing [`PhotoSamples`] once and calling
    /// [`PhotoAccum::add_samples`] gives the same sums.)
    pub fn add_all<'f>(
        &mut self,
        footprints: impl IntoIterator<Item = &'f PixelFootprint>,
        image: &RgbImage,
        transform: &ColourTransform,
        params: &ConfidenceParams,
    ) {
        self.add_samples(footprints, &PhotoSamples::new(image, transform, params));
    }

    /// [`PhotoAccum::add_all`] with the photo's colours and border feather prepared.
    pub fn add_samples<'f>(&mut self, footprints: impl IntoIterator<Item = &'f PixelFootprint>, photo: &PhotoSamples) {
        let (w, h) = photo.image.dimensions();
        let (raw, lut) = (photo.image.as_raw(), &photo.lut);
        for fp in footprints {
            let [c, r] = fp.pixel;
            if c >= w || r >= h {
                continue;
            }
            let o = 3 * (r as usize * w as usize + c as usize);
            let rgb = [lut[0][raw[o] as usize], lut[1][raw[o + 1] as usize], lut[2][raw[o + 2] as usize]];
            let border = photo.feather.at(fp.pixel);
            self.add(fp, rgb, |area| confidence_with_border(fp.cos_view as f64, area, border));
        }
    }

    /// The photo's confidence at texel `t`: `Q / max(1, A)`, in [0, 1].
    #[inline]
    pub fn confidence(&self, t: usize) -> f32 {
        let s = &self.sums[t];
        (s.weight / s.coverage.max(1.0)).clamp(0.0, 1.0)
    }

    /// The photo's colour (sRGB 0..1) at texel `t`, if any confident deposit reached it.
    #[inline]
    pub fn colour_at(&self, t: usize) -> Option<[f32; 3]> {
        let s = &self.sums[t];
        (s.weight > 0.0).then(|| s.colour.map(|c| (c / s.weight).clamp(0.0, 1.0)))
    }
}

/// All photos' contributions to one cell texture on one level.
#[derive(Clone, Debug, PartialEq)]
pub struct CellAccum {
    /// Blend mode.
    pub mode: BlendMode,
    /// Texture side in texels.
    pub texels: u32,
    /// Per texel: the highest single-photo confidence ([`PhotoAccum::confidence`]), in [0, 1].
    pub confidence: Vec<f32>,
    /// Per texel: some photo gave it colour.
    pub has_colour: Vec<bool>,
    /// Per texel, blend mode: `Σ_p Q` and `Σ_p C` (`weight`, `colour`); best mode: the best
    /// photo's colour (`colour`). `coverage` is not used.
    sums: Vec<TexelSums>,
}

impl CellAccum {
    /// An empty accumulator.
    pub fn new(texels: u32, mode: BlendMode) -> CellAccum {
        let n = texels as usize * texels as usize;
        CellAccum { mode, texels, confidence: vec![0.0; n], has_colour: vec![false; n], sums: vec![TexelSums::default(); n] }
    }

    /// The accumulator of one photo's deposits `p`, as [`CellAccum::new`] followed by
    /// [`CellAccum::merge`] of `p`, using `p`'s memory; also returns how many texels `p`
    /// gave colour.
    pub fn from_photo(p: PhotoAccum, mode: BlendMode) -> (CellAccum, u64) {
        let n = p.sums.len();
        let (mut confidence, mut has_colour) = (vec![0.0; n], vec![false; n]);
        let mut written = 0;
        for t in 0..n {
            if p.colour_at(t).is_some() {
                written += 1;
                confidence[t] = p.confidence(t).max(0.0);
                has_colour[t] = true;
            }
        }
        let texels = p.texels;
        let mut sums = p.sums;
        if mode == BlendMode::Best {
            // the best (only) photo's colour where it gave colour
            for (s, _) in sums.iter_mut().zip(&has_colour).filter(|(_, h)| **h) {
                s.colour = s.colour.map(|c| (c / s.weight).clamp(0.0, 1.0));
            }
        }
        (CellAccum { mode, texels, confidence, has_colour, sums }, written)
    }

    /// Adds one photo's deposits (same texture size); returns how many texels it gave colour.
    pub fn merge(&mut self, p: &PhotoAccum) -> u64 {
        let mut written = 0;
        for t in 0..self.confidence.len().min(p.sums.len()) {
            let Some(c) = p.colour_at(t) else { continue };
            written += 1;
            let conf = p.confidence(t);
            let s = &mut self.sums[t];
            match self.mode {
                BlendMode::Confidence => {
                    s.weight += p.sums[t].weight;
                    for k in 0..3 {
                        s.colour[k] += p.sums[t].colour[k];
                    }
                }
                BlendMode::Best => {
                    // the first photo with colour, then any strictly more confident one
                    if !self.has_colour[t] || conf > self.confidence[t] {
                        s.colour = c;
                    }
                }
            }
            self.confidence[t] = self.confidence[t].max(conf);
            self.has_colour[t] = true;
        }
        written
    }

    /// The combined photo colour (sRGB 0..1) at texel `t`, if any photo gave it colour.
    pub fn colour_at(&self, t: usize) -> Option<[f32; 3]> {
        if !self.has_colour[t] {
            return None;
        }
        let s = &self.sums[t];
        Some(match self.mode {
            BlendMode::Confidence => s.colour.map(|c| (c / s.weight).clamp(0.0, 1.0)),
            BlendMode::Best => s.colour,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn fp(pixel: [u32; 2], corners: [[f32; 2]; 4], cos_view: f32) -> PixelFootprint {
        PixelFootprint { cell: 0, pixel, corners, cos_view, distance: 10.0, reconstructed: 0 }
    }

    fn square(x: f32, y: f32, s: f32) -> [[f32; 2]; 4] {
        [[x, y], [x + s, y], [x + s, y + s], [x, y + s]]
    }

    /// No feather: every pixel of the small test images counts fully.
    fn params() -> ConfidenceParams {
        ConfidenceParams { feather: 0.0, ..ConfidenceParams::default() }
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
                fp([c, r], [map(cf, rf), map(cf + 1.0, rf), map(cf + 1.0, rf + 1.0), map(cf, rf + 1.0)], 0.8)
            })
            .collect();
        let mut a = PhotoAccum::new(8);
        a.add_all(&fps, &img, &ColourTransform::IDENTITY, &params());
        let want = [200.0 / 255.0, 40.0 / 255.0, 90.0 / 255.0];
        let mut n = 0;
        for t in 0..64 {
            if let Some(c) = a.colour_at(t) {
                n += 1;
                for k in 0..3 {
                    assert!((c[k] - want[k]).abs() < 1e-5, "texel {t}: {c:?}");
                }
                let q = a.confidence(t);
                assert!((0.0..=0.8 + 1e-6).contains(&q), "{q}");
            }
        }
        assert!(n >= 49, "{n} texels coloured");
        // interior texels are fully covered: confidence = the view cosine
        assert!((a.confidence(3 * 8 + 3) - 0.8).abs() < 1e-4);
    }

    #[test]
    fn texel_aligned_and_finer_footprints_reproduce_a_texture() {
        let tex = RgbImage::from_fn(6, 6, |x, y| image::Rgb([(x * 40) as u8, (y * 40) as u8, ((x * y) * 7) as u8]));
        // one photo pixel per texel, exactly covering it
        let fps: Vec<PixelFootprint> =
            (0..6).flat_map(|r| (0..6).map(move |c| fp([c, r], square(c as f32, r as f32, 1.0), 1.0))).collect();
        let mut a = PhotoAccum::new(6);
        a.add_all(&fps, &tex, &ColourTransform::IDENTITY, &params());
        for (x, y, p) in tex.enumerate_pixels() {
            let c = a.colour_at((y * 6 + x) as usize).unwrap();
            for k in 0..3 {
                assert!((c[k] * 255.0 - p.0[k] as f32).abs() < 1e-3);
            }
            assert!((a.confidence((y * 6 + x) as usize) - 1.0).abs() < 1e-6);
        }
        // 2x2 photo pixels per texel: each texel gets the box average of its four pixels
        let fine = RgbImage::from_fn(12, 12, |x, y| image::Rgb([(x * 20) as u8, (y * 20) as u8, ((x + y) % 3 * 50) as u8]));
        let fps: Vec<PixelFootprint> = (0..12)
            .flat_map(|r| (0..12).map(move |c| fp([c, r], square(c as f32 * 0.5, r as f32 * 0.5, 0.5), 1.0)))
            .collect();
        let mut a = PhotoAccum::new(6);
        a.add_all(&fps, &fine, &ColourTransform::IDENTITY, &params());
        for j in 0..6u32 {
            for i in 0..6u32 {
                let c = a.colour_at((j * 6 + i) as usize).unwrap();
                for k in 0..3 {
                    let mean: f32 = [(0, 0), (1, 0), (0, 1), (1, 1)]
                        .iter()
                        .map(|(dx, dy)| fine.get_pixel(2 * i + dx, 2 * j + dy).0[k] as f32)
                        .sum::<f32>()
                        / 4.0;
                    assert!((c[k] * 255.0 - mean).abs() < 1e-3, "texel {i},{j} ch {k}: {} vs {mean}", c[k] * 255.0);
                }
            }
        }
    }

    #[test]
    fn degenerate_footprints_give_no_nan() {
        let img = RgbImage::from_pixel(4, 1, image::Rgb([10, 20, 30]));
        let fps = [
            fp([0, 0], [[1.0, 1.0]; 4], 1.0),
            fp([1, 0], [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]], 0.0),
            fp([2, 0], [[f32::NAN, 1.0], [2.0, 1.0], [2.0, 2.0], [1.0, 2.0]], f32::NAN),
            fp([3, 0], [[0.5, 0.5], [3.5, 3.5], [3.5, 0.5], [0.5, 3.5]], 1.0),
        ];
        let mut a = PhotoAccum::new(4);
        a.add_all(&fps, &img, &ColourTransform::IDENTITY, &params());
        for t in 0..16 {
            assert!(a.confidence(t).is_finite());
            let s = a.sums[t];
            assert!(s.colour.iter().chain([&s.weight, &s.coverage]).all(|v| v.is_finite()));
            if let Some(c) = a.colour_at(t) {
                assert!(c.iter().all(|v| v.is_finite()));
            }
        }
        assert_eq!(a.kinds[2], 1); // the NaN footprint
    }

    #[test]
    fn blend_and_best_view() {
        let red = RgbImage::from_pixel(1, 1, image::Rgb([255, 0, 0]));
        let blue = RgbImage::from_pixel(1, 1, image::Rgb([0, 0, 255]));
        let one = |cos: f32, img: &RgbImage| {
            let mut a = PhotoAccum::new(1);
            a.add_all(&[fp([0, 0], square(0.0, 0.0, 1.0), cos)], img, &ColourTransform::IDENTITY, &params());
            a
        };
        let (a, b) = (one(0.9, &red), one(0.3, &blue));
        for (mode, first_red) in [(BlendMode::Confidence, true), (BlendMode::Best, true), (BlendMode::Best, false)] {
            let mut acc = CellAccum::new(1, mode);
            let written = if first_red { acc.merge(&a) + acc.merge(&b) } else { acc.merge(&b) + acc.merge(&a) };
            assert_eq!(written, 2);
            let c = acc.colour_at(0).unwrap();
            assert!((acc.confidence[0] - 0.9).abs() < 1e-6);
            match mode {
                BlendMode::Confidence => {
                    assert!((c[0] - 0.75).abs() < 1e-6 && (c[2] - 0.25).abs() < 1e-6, "{c:?}")
                }
                BlendMode::Best => assert_eq!(c, [1.0, 0.0, 0.0]),
            }
        }
        let empty = CellAccum::new(1, BlendMode::Best);
        assert!(empty.colour_at(0).is_none());
    }

    #[test]
    fn first_photo_adopted_equals_merged() {
        // a photo covering part of a 4 x 4 texture, then a second one over all of it
        let img = RgbImage::from_fn(8, 8, |x, y| image::Rgb([(x * 30) as u8, (y * 30) as u8, 77]));
        let fps: Vec<PixelFootprint> = (0..8)
            .flat_map(|r| (0..8).map(move |c| fp([c, r], square(0.3 * c as f32, 0.25 * r as f32, 0.3), 0.7)))
            .collect();
        let mut a = PhotoAccum::new(4);
        a.add_all(&fps, &img, &ColourTransform::IDENTITY, &params());
        let mut b = PhotoAccum::new(4);
        b.add_all(&[fp([3, 3], square(0.0, 0.0, 4.0), 0.9)], &img, &ColourTransform::IDENTITY, &params());
        for mode in [BlendMode::Confidence, BlendMode::Best] {
            let mut merged = CellAccum::new(4, mode);
            let n = merged.merge(&a);
            let (mut adopted, m) = CellAccum::from_photo(a.clone(), mode);
            assert_eq!(n, m);
            assert!(n > 0 && n < 16, "{n}");
            assert_eq!(merged.merge(&b), adopted.merge(&b));
            for t in 0..16 {
                assert_eq!(merged.colour_at(t), adopted.colour_at(t), "{mode:?} texel {t}");
            }
            assert_eq!((&merged.confidence, &merged.has_colour), (&adopted.confidence, &adopted.has_colour));
        }
    }
}
