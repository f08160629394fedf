//! How much to trust photo colour in a texel, and how that trust turns into the weight of
//! photo colour against the existing texture (docs/projection.md, "Blending").
//!
//! - **Border feather** (per photo pixel): `smoothstep(d / (feather · min(w, h)))` with `d`
//!   the distance (pixels) from the pixel centre to the nearest image edge, so photo coverage
//!   can fade out towards the image border instead of ending in a seam. Off by default
//!   (`feather` 0): every band measured handed photo detail to a coarser source.
//! - **Coverage confidence** (per texel and photo): the feathered fraction of the texel the
//!   photo's footprints cover, `Σ a·φ / max(1, Σ a)` ([`crate::photo::splatting::accumulate`]). The weight of
//!   photo colour rises with it along [`ConfidenceParams::blend_weight`], a smoothstep ramp
//!   from `ramp[0]` (no photo) to `ramp[1]`.
//! - **Resolution** (per texel): what each source resolves there, in metres on the surface
//!   ([`crate::photo::CellContext`]): the photo's pixel footprint `distance / (f · cos_view)` plus the
//!   displacement the TIN's error causes along its rays, against the existing texture's
//!   ground sample distance stretched along the fall line. The photo's weight rises with
//!   `log2(existing / photo)` along [`ConfidenceParams::resolution_weight`] (default: none
//!   while the photo is coarser, full when it is 4× finer). Neither term depends on the
//!   size of the texture the photo is splatted into, so a larger texture never lowers the
//!   photo's share (tested).
//! - Between photos, each texel weights a photo by its coverage confidence times its
//!   resolution to the power `−sharpness_power`, so the sharpest photo wins, times its
//!   occlusion term ([`crate::photo::splatting::occlusion`]), so that a photo seeing the texel clear of its own
//!   occlusion edges wins over one seeing it next to them.

use crate::error::{Error, Result};

/// Parameters of the confidence terms and the blend ramps.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConfidenceParams {
    /// Width of the border feather as a fraction of the image's shorter side, in [0, 0.5]
    /// (0 = no feather: coverage still fades over the last texel through the coverage ramp).
    /// Default 0: in the render-space evaluation (docs/evaluation.md) every band cost
    /// photo detail, 5 % of the shorter side 2–10 % of the oracle's gain and 1 % (the
    /// default until 2026-12-06) up to 9 %, since it hands a photo's edge to a coarser source.
    pub feather: f64,
    /// Coverage confidence at which photo colour starts to count, and at which it counts
    /// fully; `0 <= ramp[0] < ramp[1] <= 1`. Default `[0.05, 0.35]`.
    pub ramp: [f64; 2],
    /// `log2(existing resolution / photo resolution)` at which photo colour starts to count,
    /// and at which it counts fully; `lo < hi`. Default `[0, 2]`: a photo must resolve the
    /// surface at least as finely as the existing texture to count and 4× as finely to
    /// replace it (with `[-1, 1]`, flat ground seen at grazing angles took photo colour at
    /// par and lost 0.4 dB in the evaluation, docs/evaluation.md).
    pub resolution_ramp: [f64; 2],
    /// γ of the per-texel photo weight `confidence · resolution^−γ` between photos, in
    /// [0, 16]. Default 4 (a photo 2× sharper weighs 16×).
    pub sharpness_power: f64,
    /// Pose uncertainty (full-resolution photo pixels, in [0, 1000]) of the occlusion
    /// margin (`crate::photo::splatting::occlusion`): photo pixels closer than this plus the TIN error's
    /// displacement (pixels) to an occlusion edge of the photo count less. 0 = no margin.
    /// Default 2.
    pub occlusion_margin_px: f64,
}

impl Default for ConfidenceParams {
    fn default() -> Self {
        ConfidenceParams {
            feather: 0.0,
            ramp: [0.05, 0.35],
            resolution_ramp: [0.0, 2.0],
            sharpness_power: 4.0,
            occlusion_margin_px: 2.0,
        }
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
            return Err(Error::BadOption(format!(
                "border feather must be in [0, 0.5], got {}",
                self.feather
            )));
        }
        let [lo, hi] = self.ramp;
        if !(lo >= 0.0 && lo < hi && hi <= 1.0) {
            return Err(Error::BadOption(format!(
                "confidence ramp must satisfy 0 <= lo < hi <= 1, got [{lo}, {hi}]"
            )));
        }
        let [rlo, rhi] = self.resolution_ramp;
        if !(rlo.is_finite() && rhi.is_finite() && rlo < rhi) {
            return Err(Error::BadOption(format!(
                "resolution ramp must satisfy lo < hi, got [{rlo}, {rhi}]"
            )));
        }
        if !(0.0..=16.0).contains(&self.sharpness_power) {
            return Err(Error::BadOption(format!(
                "sharpness power must be in [0, 16], got {}",
                self.sharpness_power
            )));
        }
        if !(0.0..=1000.0).contains(&self.occlusion_margin_px) {
            return Err(Error::BadOption(format!(
                "occlusion margin must be in [0, 1000] pixels, got {}",
                self.occlusion_margin_px
            )));
        }
        Ok(())
    }

    /// The border feather of every pixel of a `width × height` image, as two tables
    /// ([`BorderFeather::at`] equals [`ConfidenceParams::border_term`] bit for bit).
    pub fn border_feather(&self, width: u32, height: u32) -> BorderFeather {
        // The feather is a non-decreasing function of the distance to the nearest edge, so
        // the smaller of the column and row terms is the term of the smaller distance.
        let band = self.feather * width.min(height) as f64;
        let table = |n: u32| {
            (0..n)
                .map(|i| feather_at(edge_distance(i, n), band))
                .collect()
        };
        BorderFeather {
            cols: table(width),
            rows: table(height),
        }
    }

    /// The border feather of pixel `[col, row]` in a `width × height` image, in [0, 1].
    pub fn border_term(&self, pixel: [u32; 2], width: u32, height: u32) -> f64 {
        let band = self.feather * width.min(height) as f64;
        feather_at(
            edge_distance(pixel[0], width).min(edge_distance(pixel[1], height)),
            band,
        )
    }

    /// Weight in [0, 1] of photo colour for a texel of photo confidence `conf`: smooth
    /// (C¹) and non-decreasing, 0 at or below `ramp[0]`, 1 at or above `ramp[1]`.
    pub fn blend_weight(&self, conf: f64) -> f64 {
        smoothstep((conf - self.ramp[0]) / (self.ramp[1] - self.ramp[0]))
    }

    /// Weight in [0, 1] of photo colour for the resolution ratio `ratio` = existing
    /// resolution / photo resolution (both metres on the surface; > 1: the photo is finer):
    /// smooth and non-decreasing in the ratio, 0 at or below `2^resolution_ramp[0]`, 1 at or
    /// above `2^resolution_ramp[1]`; 0 for NaN, 1 for an infinite ratio.
    pub fn resolution_weight(&self, ratio: f64) -> f64 {
        self.resolution_weight_fn()(ratio)
    }

    /// [`Self::resolution_weight`] as a function with the ramp's ends computed once (for
    /// loops over texels; the same values bit for bit).
    pub fn resolution_weight_fn(&self) -> impl Fn(f64) -> f64 + Copy {
        let [lo, hi] = self.resolution_ramp;
        let (rlo, rhi) = (lo.exp2(), hi.exp2());
        move |ratio: f64| {
            if ratio.is_nan() || ratio <= rlo {
                return 0.0;
            }
            if ratio >= rhi {
                return 1.0;
            }
            smoothstep((ratio.log2() - lo) / (hi - lo))
        }
    }

    /// The photo's weight `β` in [0, 1] on a texel: [`Self::blend_weight`] of its coverage
    /// confidence times [`Self::resolution_weight`] of the resolution ratio.
    pub fn photo_weight(&self, conf: f64, ratio: f64) -> f64 {
        self.blend_weight(conf) * self.resolution_weight(ratio)
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
    if band <= 0.0 {
        1.0
    } else {
        smoothstep(d / band)
    }
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
        match (
            self.cols.get(pixel[0] as usize),
            self.rows.get(pixel[1] as usize),
        ) {
            (Some(c), Some(r)) => c.min(*r),
            _ => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn occlusion_margin_outside_its_range_is_refused() {
        for m in [-1.0, f64::NAN, 1e4] {
            let p = ConfidenceParams {
                occlusion_margin_px: m,
                ..ConfidenceParams::default()
            };
            assert!(
                p.validate()
                    .is_err_and(|e| e.to_string().contains("occlusion margin")),
                "{m}"
            );
        }
        for m in [0.0, 2.0, 1000.0] {
            ConfidenceParams {
                occlusion_margin_px: m,
                ..ConfidenceParams::default()
            }
            .validate()
            .unwrap();
        }
    }

    #[test]
    fn terms_and_ramps() {
        let p = ConfidenceParams::default();
        p.validate().unwrap();
        // no band by default: every pixel, the border one too, counts fully
        assert_eq!(p.border_term([0, 400], 1000, 800), 1.0);
        // with a band the border pixel is (almost) untrusted, and the feather rises monotonically
        let p = ConfidenceParams { feather: 0.01, ..p };
        assert!(p.border_term([0, 400], 1000, 800) < 0.02);
        let f: Vec<f64> = (0..50)
            .map(|c| p.border_term([c, 400], 1000, 800))
            .collect();
        assert!(f.windows(2).all(|w| w[0] <= w[1]) && f[49] == 1.0);
        // coverage ramp: 0 below, 1 above, smooth and monotone in between
        assert_eq!(p.blend_weight(0.0), 0.0);
        assert_eq!(p.blend_weight(0.9), 1.0);
        assert!((p.blend_weight(0.2) - 0.5).abs() < 1e-12);
        let w: Vec<f64> = (0..=100)
            .map(|k| p.blend_weight(k as f64 / 100.0))
            .collect();
        assert!(w.windows(2).all(|x| x[1] >= x[0] && x[1] - x[0] < 0.06));
        // resolution ramp: none up to par, half when 2x finer, full when 4x finer
        assert_eq!(p.resolution_weight(0.5), 0.0);
        assert_eq!(p.resolution_weight(1.0), 0.0);
        assert!((p.resolution_weight(2.0) - 0.5).abs() < 1e-12);
        assert_eq!(p.resolution_weight(4.0), 1.0);
        assert_eq!(p.resolution_weight(f64::INFINITY), 1.0);
        assert_eq!(p.resolution_weight(f64::NAN), 0.0);
        assert_eq!(p.resolution_weight(0.0), 0.0);
        let r: Vec<f64> = (0..=200)
            .map(|k| p.resolution_weight(2f64.powf(k as f64 / 50.0 - 2.0)))
            .collect();
        assert!(r.windows(2).all(|x| x[1] >= x[0]));
        assert_eq!(p.photo_weight(0.9, 4.0), 1.0);
        assert!((p.photo_weight(0.2, 2.0) - 0.25).abs() < 1e-12);
        assert!(
            ConfidenceParams {
                ramp: [0.5, 0.5],
                ..p
            }
            .validate()
            .is_err()
        );
        assert!(ConfidenceParams { feather: -1.0, ..p }.validate().is_err());
        assert!(
            ConfidenceParams {
                resolution_ramp: [1.0, 1.0],
                ..p
            }
            .validate()
            .is_err()
        );
        assert!(
            ConfidenceParams {
                sharpness_power: f64::NAN,
                ..p
            }
            .validate()
            .is_err()
        );
    }

    #[test]
    fn feather_tables_equal_the_direct_term() {
        let d = ConfidenceParams::default();
        for p in [
            d,
            ConfidenceParams { feather: 0.01, ..d },
            ConfidenceParams { feather: 0.5, ..d },
        ] {
            for (w, h) in [(1000u32, 800u32), (7, 300), (1, 1)] {
                let t = p.border_feather(w, h);
                for r in (0..h).step_by(3) {
                    for c in (0..w).step_by(5) {
                        assert_eq!(
                            t.at([c, r]).to_bits(),
                            p.border_term([c, r], w, h).to_bits(),
                            "{w}x{h} {c},{r}"
                        );
                    }
                }
                assert_eq!(t.at([w, 0]), 0.0);
            }
        }
    }
}
