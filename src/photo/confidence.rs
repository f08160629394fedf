//! How much to trust one photo pixel's colour in a texel, and how photo confidence turns
//! into the weight of photo colour against the existing texture.
//!
//! A footprint's confidence is the product of three terms, each in [0, 1]:
//! - **view**: the cosine between the ray and the surface normal (1 head-on, → 0 grazing);
//! - **resolution**: `1 / max(1, area)` with `area` the footprint's area in texels²: photo
//!   pixels no larger than a texel carry full detail, a pixel spread over `a` texels
//!   carries `1/a` of a texel's detail;
//! - **border feather**: `smoothstep(d / (feather · min(w, h)))` with `d` the distance
//!   (pixels) from the pixel centre to the nearest image edge, so photo coverage fades out
//!   towards the image border instead of ending in a seam (and vignetting is avoided).
//!
//! Per texel a photo's confidence is its confidence-weighted coverage, `Σ a·q / max(1, Σ a)`
//! (see [`super::accumulate`]); the weight of photo colour is [`ConfidenceParams::blend_weight`]
//! of it, a smoothstep ramp from `ramp[0]` (no photo) to `ramp[1]` (photo only).

use crate::error::{Error, Result};

/// Parameters of the confidence terms and the blend ramp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConfidenceParams {
    /// Width of the border feather as a fraction of the image's shorter side, in [0, 0.5]
    /// (0 = no feather). Default 0.05.
    pub feather: f64,
    /// Texel confidence at which photo colour starts to count, and at which it replaces the
    /// existing colour entirely; `0 <= ramp[0] < ramp[1] <= 1`. Default `[0.05, 0.35]`.
    pub ramp: [f64; 2],
}

impl Default for ConfidenceParams {
    fn default() -> Self {
        ConfidenceParams { feather: 0.05, ramp: [0.05, 0.35] }
    }
}

/// `3t² − 2t³` of `t` clamped to [0, 1] (0 for NaN).
#[inline]
pub fn smoothstep(t: f64) -> f64 {
    if t.is_nan() {
        return 0.0;
    }
    let t = t.clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

impl ConfidenceParams {
    /// Rejects parameters outside their documented ranges.
    pub fn validate(&self) -> Result<()> {
        if !(0.0..=0.5).contains(&self.feather) {
            return Err(Error::BadOption(format!("border feather must be in [0, 0.5], got {}", self.feather)));
        }
        let [lo, hi] = self.ramp;
        if !(lo >= 0.0 && lo < hi && hi <= 1.0) {
            return Err(Error::BadOption(format!("confidence ramp must satisfy 0 <= lo < hi <= 1, got [{lo}, {hi}]")));
        }
        Ok(())
    }

    /// Confidence in [0, 1] of a footprint with view cosine `cos_view`, area `area`
    /// (texels²), for pixel `[col, row]` of a `width × height` image. 0 for NaN inputs.
    pub fn footprint_confidence(&self, cos_view: f64, area: f64, pixel: [u32; 2], width: u32, height: u32) -> f64 {
        confidence_with_border(cos_view, area, self.border_term(pixel, width, height))
    }

    /// The border feather of every pixel of a `width × height` image, as two tables
    /// ([`BorderFeather::at`] equals [`ConfidenceParams::border_term`] bit for bit).
    pub fn border_feather(&self, width: u32, height: u32) -> BorderFeather {
        // The feather is a non-decreasing function of the distance to the nearest edge, so
        // the smaller of the column and row terms is the term of the smaller distance.
        let band = self.feather * width.min(height) as f64;
        let table = |n: u32| (0..n).map(|i| feather_at(edge_distance(i, n), band)).collect();
        BorderFeather { cols: table(width), rows: table(height) }
    }

    /// The border feather of pixel `[col, row]` in a `width × height` image, in [0, 1].
    pub fn border_term(&self, pixel: [u32; 2], width: u32, height: u32) -> f64 {
        let band = self.feather * width.min(height) as f64;
        feather_at(edge_distance(pixel[0], width).min(edge_distance(pixel[1], height)), band)
    }

    /// Weight in [0, 1] of photo colour for a texel of photo confidence `conf`: smooth
    /// (C¹) and non-decreasing, 0 at or below `ramp[0]`, 1 at or above `ramp[1]`.
    pub fn blend_weight(&self, conf: f64) -> f64 {
        smoothstep((conf - self.ramp[0]) / (self.ramp[1] - self.ramp[0]))
    }
}

/// Distance (pixels, >= 0) from the centre of pixel `i` to the nearer end of `0..n`.
#[inline]
fn edge_distance(i: u32, n: u32) -> f64 {
    let c = i as f64 + 0.5;
    c.min(n as f64 - c).max(0.0)
}

/// The feather of a pixel centre `d` pixels from the border, for a feather band of `band`
/// pixels (1 everywhere without a band).
#[inline]
fn feather_at(d: f64, band: f64) -> f64 {
    if band <= 0.0 { 1.0 } else { smoothstep(d / band) }
}

/// `view · resolution · border` (see the [module docs](self)) of a footprint with view
/// cosine `cos_view` and area `area` (texels²) and the border feather `border` of its pixel;
/// 0 for NaN inputs.
#[inline]
pub(crate) fn confidence_with_border(cos_view: f64, area: f64, border: f64) -> f64 {
    let view = if cos_view.is_nan() { 0.0 } else { cos_view.clamp(0.0, 1.0) };
    let res = if area.is_nan() {
        0.0
    } else if area <= 1.0 {
        1.0
    } else {
        1.0 / area
    };
    view * res * border
}

/// The border feather of every pixel of one image ([`ConfidenceParams::border_feather`]).
#[derive(Clone, Debug, PartialEq)]
pub struct BorderFeather {
    cols: Vec<f64>,
    rows: Vec<f64>,
}

impl BorderFeather {
    /// The feather of pixel `[col, row]`, in [0, 1] (0 outside the image).
    #[inline]
    pub fn at(&self, pixel: [u32; 2]) -> f64 {
        match (self.cols.get(pixel[0] as usize), self.rows.get(pixel[1] as usize)) {
            (Some(c), Some(r)) => c.min(*r),
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terms_and_ramp() {
        let p = ConfidenceParams::default();
        p.validate().unwrap();
        // centre pixel, head-on, small footprint: full confidence
        assert_eq!(p.footprint_confidence(1.0, 0.3, [500, 400], 1000, 800), 1.0);
        // a pixel spread over 4 texels and viewed at 60 degrees
        assert!((p.footprint_confidence(0.5, 4.0, [500, 400], 1000, 800) - 0.125).abs() < 1e-12);
        // the border pixel is (almost) untrusted, and the feather rises monotonically
        assert!(p.footprint_confidence(1.0, 1.0, [0, 400], 1000, 800) < 0.01);
        let f: Vec<f64> = (0..50).map(|c| p.border_term([c, 400], 1000, 800)).collect();
        assert!(f.windows(2).all(|w| w[0] <= w[1]) && f[49] == 1.0);
        assert_eq!(p.footprint_confidence(f64::NAN, 1.0, [500, 400], 1000, 800), 0.0);
        // ramp: 0 below, 1 above, smooth and monotone in between
        assert_eq!(p.blend_weight(0.0), 0.0);
        assert_eq!(p.blend_weight(0.9), 1.0);
        assert!((p.blend_weight(0.2) - 0.5).abs() < 1e-12);
        let w: Vec<f64> = (0..=100).map(|k| p.blend_weight(k as f64 / 100.0)).collect();
        assert!(w.windows(2).all(|x| x[1] >= x[0] && x[1] - x[0] < 0.06));
        assert!(ConfidenceParams { ramp: [0.5, 0.5], ..p }.validate().is_err());
        assert!(ConfidenceParams { feather: -1.0, ..p }.validate().is_err());
    }

    #[test]
    fn feather_tables_equal_the_direct_term() {
        let d = ConfidenceParams::default();
        for p in [d, ConfidenceParams { feather: 0.0, ..d }, ConfidenceParams { feather: 0.5, ..d }] {
            for (w, h) in [(1000u32, 800u32), (7, 300), (1, 1)] {
                let t = p.border_feather(w, h);
                for r in (0..h).step_by(3) {
                    for c in (0..w).step_by(5) {
                        assert_eq!(t.at([c, r]).to_bits(), p.border_term([c, r], w, h).to_bits(), "{w}x{h} {c},{r}");
                    }
                }
                assert_eq!(t.at([w, 0]), 0.0);
            }
        }
    }
}
