//! Merging the accumulated photo colour of a cell with its existing texture.
//!
//! Per texel with photo colour `p` and texel confidence `c` (the highest single-photo
//! confidence), the photo's weight is `β = ConfidenceParams::blend_weight(c)`, a smooth
//! ramp, so photo colour fades in across the edge of photo coverage instead of ending in a
//! seam. The existing texel (alpha `α`, the known fraction of its colour) counts with
//! weight `(1 − β)·α`, so the photo's share of the result is `s = β / (β + (1 − β) α)`
//! (`s = β` on fully known texels, 1 where the existing colour is unknown and the photo saw
//! the texel, 0 where `β = 0`). Result: `rgb = s·p + (1 − s)·existing`, alpha
//! `max(α, β)`; the confidence map stores `s` (0..255).

use image::{GrayImage, RgbaImage};

use super::accumulate::CellAccum;
use super::confidence::ConfidenceParams;
use crate::fastmath::to_u8;

/// A cell's photo-enhanced texture and its statistics.
#[derive(Clone, Debug, PartialEq)]
pub struct Blended {
    /// RGBA8 texture, same size and layout as the existing one.
    pub texture: RgbaImage,
    /// Per texel the photo's share `s` of the colour, 0..255.
    pub confidence: GrayImage,
    /// Covered texels with `s > 0.5`.
    pub photo_texels: u64,
    /// Covered texels marked steep.
    pub steep_texels: u64,
    /// Steep covered texels with `s > 0.5`.
    pub steep_photo_texels: u64,
}

/// Blends `acc` into `existing` (same size) as described in the [module docs](self).
/// `covered[t]` marks texels on the cell's surface and `steep[t]` those steeper than the
/// steep threshold (both row-major, of the texture's size; shorter slices count as false).
pub fn blend_cell(existing: &RgbaImage, acc: &CellAccum, params: &ConfidenceParams, covered: &[bool], steep: &[bool]) -> Blended {
    let (w, h) = existing.dimensions();
    let mut texture = existing.clone();
    let mut conf = GrayImage::new(w, h);
    let (mut photo_texels, mut steep_texels, mut steep_photo_texels) = (0, 0, 0);
    let n = (w as usize * h as usize).min(acc.confidence.len());
    for (t, (px, cv)) in texture.pixels_mut().zip(conf.pixels_mut()).enumerate() {
        let cov = covered.get(t).copied().unwrap_or(false);
        let st = cov && steep.get(t).copied().unwrap_or(false);
        steep_texels += st as u64;
        if t >= n {
            continue;
        }
        let Some(p) = acc.colour_at(t) else { continue };
        let beta = params.blend_weight(acc.confidence[t] as f64);
        if beta <= 0.0 {
            continue;
        }
        let alpha = px.0[3] as f64 / 255.0;
        let s = beta / (beta + (1.0 - beta) * alpha);
        for k in 0..3 {
            let v = s * p[k] as f64 * 255.0 + (1.0 - s) * px.0[k] as f64;
            px.0[k] = to_u8(v);
        }
        px.0[3] = px.0[3].max(to_u8(beta * 255.0));
        cv.0[0] = to_u8(s * 255.0);
        if s > 0.5 && cov {
            photo_texels += 1;
            steep_photo_texels += st as u64;
        }
    }
    Blended { texture, confidence: conf, photo_texels, steep_texels, steep_photo_texels }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photo::{BlendMode, ColourTransform, PhotoAccum, PixelFootprint};
    use image::RgbImage;

    #[test]
    fn photo_where_confident_existing_where_not_smooth_between() {
        // 32 x 1 texels; the photo's view cosine falls from 1 to 0 along x
        let n = 32u32;
        let img = RgbImage::from_pixel(n, 1, image::Rgb([250, 250, 250]));
        let params = ConfidenceParams { feather: 0.0, ..ConfidenceParams::default() };
        let fps: Vec<PixelFootprint> = (0..n)
            .map(|i| {
                let x = i as f32;
                PixelFootprint {
                    cell: 0,
                    pixel: [i, 0],
                    corners: [[x, 0.0], [x + 1.0, 0.0], [x + 1.0, 1.0], [x, 1.0]],
                    cos_view: 1.0 - i as f32 / (n - 1) as f32,
                    distance: 5.0,
                    reconstructed: 0,
                }
            })
            .collect();
        let mut pa = PhotoAccum::new(n);
        pa.add_all(&fps, &img, &ColourTransform::IDENTITY, &params);
        let mut acc = CellAccum::new(n, BlendMode::Confidence);
        acc.merge(&pa);
        let mut existing = RgbaImage::from_pixel(n, n, image::Rgba([10, 10, 10, 255]));
        // an unknown existing texel that the photo sees with low confidence
        existing.put_pixel(29, 0, image::Rgba([0, 0, 0, 0]));
        let covered = vec![true; (n * n) as usize];
        let steep: Vec<bool> = (0..n * n).map(|t| t % 2 == 0).collect();
        let b = blend_cell(&existing, &acc, &params, &covered, &steep);
        let r: Vec<u8> = (0..n).map(|i| b.texture.get_pixel(i, 0).0[0]).collect();
        let s: Vec<u8> = (0..n).map(|i| b.confidence.get_pixel(i, 0).0[0]).collect();
        // confident texels: photo colour, confidence 255
        assert_eq!((r[0], s[0]), (250, 255));
        // no confidence: existing colour, untouched
        assert_eq!((r[30], s[30]), (10, 0));
        assert_eq!(b.texture.get_pixel(30, 0).0, [10, 10, 10, 255]);
        // in between: monotone and without jumps larger than the ramp allows
        for i in 0..28 {
            assert!(r[i + 1] <= r[i] && r[i] - r[i + 1] <= 40, "{r:?}");
        }
        assert!(r.iter().any(|&v| v > 10 && v < 250), "no ramp: {r:?}");
        // the unknown existing texel takes the photo colour wherever the photo has weight
        if params.blend_weight(acc.confidence[29] as f64) > 0.0 {
            assert_eq!((r[29], s[29]), (250, 255));
        }
        // rows the photo did not reach are unchanged
        assert_eq!(b.texture.get_pixel(5, 3).0, [10, 10, 10, 255]);
        assert_eq!(b.steep_texels, (n * n / 2) as u64);
        let photo = s.iter().filter(|&&v| v > 127).count() as u64;
        assert_eq!(b.photo_texels, photo);
        assert_eq!(b.steep_photo_texels, s.iter().step_by(2).filter(|&&v| v > 127).count() as u64);
    }
}
