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

use super::confidence::ConfidenceParams;
use super::level::ColourTransform;
use super::splat::{SplatKind, footprint_area, splat_footprint};
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

/// One photo's deposits in one `texels × texels` cell texture (row-major per texel).
#[derive(Clone, Debug, PartialEq)]
pub struct PhotoAccum {
    /// Texture side in texels.
    pub texels: u32,
    /// `A`: deposited footprint area per texel (texels²).
    pub coverage: Vec<f32>,
    /// `Q`: confidence-weighted area per texel.
    pub weight: Vec<f32>,
    /// `C`: confidence-weighted area times colour (sRGB 0..1) per texel.
    pub colour: Vec<[f32; 3]>,
    /// Footprints deposited exactly / by the bilinear fallback / skipped.
    pub kinds: [u64; 3],
}

impl PhotoAccum {
    /// An empty accumulator.
    pub fn new(texels: u32) -> PhotoAccum {
        let n = texels as usize * texels as usize;
        PhotoAccum { texels, coverage: vec![0.0; n], weight: vec![0.0; n], colour: vec![[0.0; 3]; n], kinds: [0; 3] }
    }

    /// Deposits a footprint of colour `rgb` (sRGB 0..1) and confidence `conf(area)` (given
    /// the footprint's area in texels², see [`footprint_area`]).
    pub fn add(&mut self, fp: &PixelFootprint, rgb: [f32; 3], conf: impl FnOnce(f64) -> f64) {
        let q = conf(footprint_area(&fp.corners)) as f32;
        let (coverage, weight, colour) = (&mut self.coverage, &mut self.weight, &mut self.colour);
        let s = splat_footprint(&fp.corners, self.texels, |i, w| {
            let w = w as f32;
            coverage[i] += w;
            let wq = w * q;
            weight[i] += wq;
            for k in 0..3 {
                colour[i][k] += wq * rgb[k];
            }
        });
        self.kinds[match s.kind {
            SplatKind::Exact => 0,
            SplatKind::Bilinear => 1,
            SplatKind::Skipped => 2,
        }] += 1;
    }

    /// Deposits every footprint of `footprints` (all of this accumulator's cell) with the
    /// colour of its pixel in `image` (the image the footprints were cast for) mapped by
    /// `transform`, and confidence from `params`.
    pub fn add_all(
        &mut self,
        footprints: &[PixelFootprint],
        image: &RgbImage,
        transform: &ColourTransform,
        params: &ConfidenceParams,
    ) {
        let (w, h) = image.dimensions();
        for fp in footprints {
            let [c, r] = fp.pixel;
            if c >= w || r >= h {
                continue;
            }
            let px = image.get_pixel(c, r).0;
            let rgb = transform.apply([px[0], px[1], px[2]].map(|v| v as f32 / 255.0));
            self.add(fp, rgb, |area| params.footprint_confidence(fp.cos_view as f64, area, fp.pixel, w, h));
        }
    }

    /// The photo's confidence at texel `t`: `Q / max(1, A)`, in [0, 1].
    #[inline]
    pub fn confidence(&self, t: usize) -> f32 {
        (self.weight[t] / self.coverage[t].max(1.0)).clamp(0.0, 1.0)
    }

    /// The photo's colour (sRGB 0..1) at texel `t`, if any confident deposit reached it.
    #[inline]
    pub fn colour_at(&self, t: usize) -> Option<[f32; 3]> {
        let q = self.weight[t];
        (q > 0.0).then(|| self.colour[t].map(|c| (c / q).clamp(0.0, 1.0)))
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
    /// Blend mode: `Σ_p Q`; best mode: empty.
    weight: Vec<f32>,
    /// Blend mode: `Σ_p C`; best mode: the best photo's colour.
    colour: Vec<[f32; 3]>,
}

impl CellAccum {
    /// An empty accumulator.
    pub fn new(texels: u32, mode: BlendMode) -> CellAccum {
        let n = texels as usize * texels as usize;
        let weight = if mode == BlendMode::Confidence { vec![0.0; n] } else { Vec::new() };
        CellAccum { mode, texels, confidence: vec![0.0; n], has_colour: vec![false; n], weight, colour: vec![[0.0; 3]; n] }
    }

    /// Adds one photo's deposits (same texture size); returns how many texels it gave colour.
    pub fn merge(&mut self, p: &PhotoAccum) -> u64 {
        let mut written = 0;
        for t in 0..self.confidence.len().min(p.weight.len()) {
            let Some(c) = p.colour_at(t) else { continue };
            written += 1;
            let conf = p.confidence(t);
            match self.mode {
                BlendMode::Confidence => {
                    self.weight[t] += p.weight[t];
                    for k in 0..3 {
                        self.colour[t][k] += p.colour[t][k];
                    }
                }
                BlendMode::Best => {
                    // the first photo with colour, then any strictly more confident one
                    if !self.has_colour[t] || conf > self.confidence[t] {
                        self.colour[t] = c;
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
        Some(match self.mode {
            BlendMode::Confidence => {
                let q = self.weight[t];
                self.colour[t].map(|c| (c / q).clamp(0.0, 1.0))
            }
            BlendMode::Best => self.colour[t],
        })
    }
}
