//! Colour leveling: a per-photo, per-channel affine map `ortho ≈ gain · photo + offset`
//! (sRGB values in [0, 1]) that brings a photo's exposure and white balance to the existing
//! (ortho-derived) texture before blending.
//!
//! Samples are texels where both colours are trustworthy and comparable ([`collect_pairs`]):
//! the photo covers the texel (coverage confidence at least `min_confidence`) and resolves
//! it no worse than the ortho, the existing texel is fully known (alpha 255), the surface is
//! flat (normal-map slope below `max_slope_deg`, where the top-down ortho sees the same
//! surface as the photo) and well lit (luminance of both colours inside `luminance`, i.e.
//! neither in deep shadow nor clipped); colours are compared as block means at the
//! ortho's resolution. With fewer than `min_samples`
//! samples the photo keeps the identity map. Per channel the line is fitted by iteratively
//! reweighted least squares with Huber weights (scale from the median absolute deviation),
//! which ignores the minority of samples where photo and ortho show different things
//! (misregistration, shadows that moved, snow). A channel whose photo values barely vary
//! (standard deviation below `min_spread`) only gets an offset (the median difference);
//! a fitted gain outside `gain_range` is implausible and that channel keeps the identity.

use image::RgbaImage;

use crate::photo::blending::cell_accum::CellContext;
use crate::photo::splatting::accumulate::PhotoAccum;
pub use crate::photo::splatting::colour_transform::ColourTransform;

/// Which texels serve as leveling samples and how the fit is guarded.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LevelingParams {
    /// Fewest samples for a fit (default 500); fewer gives the identity.
    pub min_samples: usize,
    /// Samples beyond this are thinned with a deterministic stride (default 200 000).
    pub max_samples: usize,
    /// Steepest surface slope of a sample, degrees from horizontal (default 30).
    pub max_slope_deg: f64,
    /// Lowest photo coverage confidence of a sample (default 0.5).
    pub min_confidence: f32,
    /// Most oblique view of a sample, as `1 / cos_view` (default 2: within 60° of the
    /// surface normal).
    pub max_grazing: f32,
    /// Luminance range (0..1) both colours must lie in (default [0.04, 0.96]).
    pub luminance: [f32; 2],
    /// Below this standard deviation of a channel's photo values only an offset is fitted
    /// (default 0.02).
    pub min_spread: f64,
    /// Plausible gains (default [0.25, 4]).
    pub gain_range: [f64; 2],
}

impl Default for LevelingParams {
    fn default() -> Self {
        LevelingParams {
            min_samples: 500,
            max_samples: 200_000,
            max_slope_deg: 30.0,
            min_confidence: 0.5,
            max_grazing: 2.0,
            luminance: [0.04, 0.96],
            min_spread: 0.02,
            gain_range: [0.25, 4.0],
        }
    }
}

/// Corresponding colours: the photo's (untransformed) and the existing texture's, sRGB 0..1.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ColourPairs {
    /// Photo colours.
    pub photo: Vec<[f32; 3]>,
    /// Existing texture colours at the same texels.
    pub existing: Vec<[f32; 3]>,
}

#[inline]
fn luminance(c: [f32; 3]) -> f32 {
    0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]
}

/// Decoded `n_z` (cosine of the slope) of a normal-map texel (`n * 0.5 + 0.5` encoding).
#[inline]
pub fn normal_cos_slope(px: [u8; 3]) -> f64 {
    let n = px.map(|v| v as f64 / 255.0 * 2.0 - 1.0);
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    if len > 0.0 { n[2] / len } else { 1.0 }
}

/// Appends the samples of one cell: photo deposits `acc` (untransformed sRGB colours, at
/// the existing texture's size), the cell's existing texture and its [`CellContext`] (the
/// slopes of its normal map). Colours are averaged over blocks of `k × k` texels, `k` the
/// power of two that makes a block as large as the existing texture's ground sample
/// distance, so that the photo is compared at the ortho's resolution and its finer detail
/// does not bias the gain low. A block counts if all its texels qualify: the existing colour
/// fully known, the surface flat, the photo's coverage confidence at least `min_confidence`,
/// seen no more obliquely than `1 / cos_view = max_grazing`, its pixel footprint no larger
/// than the block and the displacement the TIN's error causes along its rays
/// (`ε · cos θ / cos_view`) within a block; and if both block means are well lit. On a
/// size mismatch nothing is added. Returns the number of samples added.
pub fn collect_pairs(
    acc: &PhotoAccum,
    existing: &RgbaImage,
    ctx: &CellContext,
    params: &LevelingParams,
    out: &mut ColourPairs,
) -> usize {
    let t = acc.texels;
    if existing.dimensions() != (t, t) || ctx.base_texels != t || acc.scale != 1 {
        return 0;
    }
    let before = out.photo.len();
    let cos_max = params.max_slope_deg.to_radians().cos() as f32;
    let ratio = ctx.existing_ground / ctx.texel_ground.max(1e-9);
    let mut k = 1u32;
    while (k as f32) < ratio && k < 16 && 2 * k <= t {
        k *= 2;
    }
    // a block's side on the ground, metres
    let block = k as f32 * ctx.texel_ground;
    let qualifies = |i: usize| -> Option<([f32; 3], [f32; 3])> {
        let e = existing.as_raw().get(4 * i..4 * i + 4)?;
        if e[3] != 255 || acc.confidence(i) < params.min_confidence || ctx.cos_at(i) < cos_max {
            return None;
        }
        let p = acc.colour_at(i)?;
        // seen within 60° of the normal, the pixel no larger than a block and the TIN's
        // displacement of it within a block: photo and ortho block show the same ground
        let [r, g] = acc.footprint_at(i);
        let misplaced = ctx.max_error * ctx.cos_at(i) * g;
        if !(g <= params.max_grazing && r <= block && misplaced <= block) {
            return None;
        }
        Some((p, [e[0], e[1], e[2]].map(|v| v as f32 / 255.0)))
    };
    let lum = params.luminance;
    for by in (0..t - t % k).step_by(k as usize) {
        'block: for bx in (0..t - t % k).step_by(k as usize) {
            let (mut sp, mut se) = ([0.0f32; 3], [0.0f32; 3]);
            for y in by..by + k {
                for x in bx..bx + k {
                    let Some((p, e)) = qualifies((y * t + x) as usize) else {
                        continue 'block;
                    };
                    for c in 0..3 {
                        sp[c] += p[c];
                        se[c] += e[c];
                    }
                }
            }
            let n = (k * k) as f32;
            let (p, e) = (sp.map(|v| v / n), se.map(|v| v / n));
            if [luminance(p), luminance(e)]
                .iter()
                .all(|&l| l >= lum[0] && l <= lum[1])
            {
                out.photo.push(p);
                out.existing.push(e);
            }
        }
    }
    out.photo.len() - before
}

/// Median of `v` (reorders it); 0 for an empty slice.
fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let k = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(k, f64::total_cmp);
    *m
}

/// Weighted least-squares line `y = g x + o`; `None` if `x` has (numerically) no spread.
fn weighted_line(x: &[f64], y: &[f64], w: &[f64]) -> Option<(f64, f64)> {
    let sw: f64 = w.iter().sum();
    if sw <= 0.0 {
        return None;
    }
    let mx = x.iter().zip(w).map(|(a, b)| a * b).sum::<f64>() / sw;
    let my = y.iter().zip(w).map(|(a, b)| a * b).sum::<f64>() / sw;
    let (mut sxx, mut sxy) = (0.0, 0.0);
    for ((a, b), c) in x.iter().zip(y).zip(w) {
        sxx += c * (a - mx) * (a - mx);
        sxy += c * (a - mx) * (b - my);
    }
    if sxx <= 1e-12 * sw {
        return None;
    }
    let g = sxy / sxx;
    Some((g, my - g * mx))
}

/// Robust (Huber IRLS) fit of `y ≈ g x + o` for one channel; see the [module docs](self).
fn fit_channel(x: &[f64], y: &[f64], params: &LevelingParams) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let sd = (x.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n).sqrt();
    if sd < params.min_spread {
        let mut d: Vec<f64> = x.iter().zip(y).map(|(a, b)| b - a).collect();
        return (1.0, median(&mut d));
    }
    let mut w = vec![1.0; x.len()];
    let Some(mut line) = weighted_line(x, y, &w) else {
        return (1.0, 0.0);
    };
    let mut r = vec![0.0; x.len()];
    for _ in 0..20 {
        for k in 0..x.len() {
            r[k] = y[k] - (line.0 * x[k] + line.1);
        }
        let mut tmp = r.clone();
        let med = median(&mut tmp);
        for v in tmp.iter_mut() {
            *v = (*v - med).abs();
        }
        let scale = (1.4826 * median(&mut tmp)).max(1e-4);
        let c = 1.345 * scale;
        for k in 0..x.len() {
            let a = r[k].abs();
            w[k] = if a <= c { 1.0 } else { c / a };
        }
        let Some(next) = weighted_line(x, y, &w) else {
            break;
        };
        let done = (next.0 - line.0).abs() < 1e-7 && (next.1 - line.1).abs() < 1e-7;
        line = next;
        if done {
            break;
        }
    }
    if line.0.is_finite()
        && line.1.is_finite()
        && line.0 >= params.gain_range[0]
        && line.0 <= params.gain_range[1]
    {
        line
    } else {
        (1.0, 0.0)
    }
}

/// Fits the photo → existing colour map from `pairs`; returns it and the number of samples
/// used (0 and the identity when there are fewer than `min_samples`). Deterministic.
pub fn fit_colour_transform(
    pairs: &ColourPairs,
    params: &LevelingParams,
) -> (ColourTransform, usize) {
    let n = pairs.photo.len().min(pairs.existing.len());
    if n < params.min_samples.max(2) {
        return (ColourTransform::IDENTITY, 0);
    }
    let stride = n.div_ceil(params.max_samples.max(params.min_samples).max(2));
    let idx: Vec<usize> = (0..n).step_by(stride.max(1)).collect();
    let mut t = ColourTransform::IDENTITY;
    for k in 0..3 {
        let x: Vec<f64> = idx.iter().map(|&i| pairs.photo[i][k] as f64).collect();
        let y: Vec<f64> = idx.iter().map(|&i| pairs.existing[i][k] as f64).collect();
        let (g, o) = fit_channel(&x, &y, params);
        t.gain[k] = g;
        t.offset[k] = o;
    }
    (t, idx.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photo::TexelSums;

    /// A deterministic pseudo-random value in [0, 1).
    fn hash01(i: u64) -> f64 {
        let mut z = i.wrapping_add(0x9e3779b97f4a7c15);
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn recovers_gain_and_offset_despite_outliers() {
        let truth = ColourTransform {
            gain: [0.8, 1.1, 1.3],
            offset: [0.05, -0.02, 0.01],
        };
        let mut pairs = ColourPairs::default();
        for i in 0..5000u64 {
            let p: [f32; 3] =
                std::array::from_fn(|k| (0.1 + 0.6 * hash01(3 * i + k as u64)) as f32);
            let mut e = truth.apply(p);
            // small noise everywhere, gross outliers on 15 % of the samples
            for (k, v) in e.iter_mut().enumerate() {
                *v += (0.01 * (hash01(7919 * i + k as u64) - 0.5)) as f32;
            }
            if hash01(104729 * i) < 0.15 {
                e = [0.9, 0.05, 0.5];
            }
            pairs.photo.push(p);
            pairs.existing.push(e);
        }
        let (t, used) = fit_colour_transform(&pairs, &LevelingParams::default());
        assert_eq!(used, 5000);
        for k in 0..3 {
            assert!(
                (t.gain[k] - truth.gain[k]).abs() < 0.02,
                "gain {k}: {:?}",
                t
            );
            assert!(
                (t.offset[k] - truth.offset[k]).abs() < 0.01,
                "offset {k}: {:?}",
                t
            );
        }
        // too few samples: identity
        let few = ColourPairs {
            photo: pairs.photo[..100].to_vec(),
            existing: pairs.existing[..100].to_vec(),
        };
        assert_eq!(
            fit_colour_transform(&few, &LevelingParams::default()),
            (ColourTransform::IDENTITY, 0)
        );
    }

    #[test]
    fn flat_photo_channel_gets_only_an_offset() {
        let mut pairs = ColourPairs::default();
        for i in 0..1000u64 {
            let v = (0.2 + 0.5 * hash01(i)) as f32;
            pairs.photo.push([v, 0.5, v]);
            pairs.existing.push([v, 0.6, v]);
        }
        let (t, _) = fit_colour_transform(&pairs, &LevelingParams::default());
        assert_eq!(t.gain[1], 1.0);
        assert!((t.offset[1] - 0.1).abs() < 1e-6);
        assert!((t.gain[0] - 1.0).abs() < 1e-6 && t.offset[0].abs() < 1e-6);
    }

    #[test]
    fn collects_only_flat_bright_confident_well_placed_texels() {
        let mut acc = PhotoAccum::new(2);
        // texel 0: confident and sharp; texel 1: steep; texel 2: dark; texel 3: smeared (a
        // pixel of 5 m on ground the ortho resolves to 1 m)
        for (t, c, r) in [
            (0usize, 0.5f32, 0.1f32),
            (1, 0.5, 0.1),
            (2, 0.01, 0.1),
            (3, 0.5, 5.0),
        ] {
            *acc.sums.get_mut(t).unwrap() = TexelSums {
                coverage: 1.0,
                weight: 1.0,
                colour: [c; 3],
                footprint: r,
                grazing: 1.2,
                clear: 1.0,
            };
        }
        let existing = RgbaImage::from_pixel(2, 2, image::Rgba([100, 100, 100, 255]));
        let ctx = CellContext {
            base_texels: 2,
            cos_slope: vec![1.0, 0.0, 1.0, 1.0],
            max_error: 0.0,
            existing_ground: 1.0,
            texel_ground: 1.0,
        };
        let lp = LevelingParams::default();
        let mut pairs = ColourPairs::default();
        assert_eq!(collect_pairs(&acc, &existing, &ctx, &lp, &mut pairs), 1);
        assert_eq!(pairs.photo, vec![[0.5; 3]]);
        assert_eq!(
            collect_pairs(&PhotoAccum::new(3), &existing, &ctx, &lp, &mut pairs),
            0
        );
        // seen too obliquely, or displaced too far by the TIN's error: no sample
        let mut oblique = acc.clone();
        oblique.sums.get_mut(0).unwrap().grazing = 2.5;
        assert_eq!(
            collect_pairs(&oblique, &existing, &ctx, &lp, &mut ColourPairs::default()),
            0
        );
        let rough = CellContext {
            max_error: 0.9,
            ..ctx.clone()
        };
        assert_eq!(
            collect_pairs(&acc, &existing, &rough, &lp, &mut ColourPairs::default()),
            0
        );
        // texels of half the ortho's spacing: 2 x 2 blocks, which texel 1 spoils here
        let half = CellContext {
            texel_ground: 0.5,
            ..ctx.clone()
        };
        assert_eq!(collect_pairs(&acc, &existing, &half, &lp, &mut pairs), 0);
        let mut flat = acc.clone();
        for t in 0..4 {
            *flat.sums.get_mut(t).unwrap() = TexelSums {
                coverage: 1.0,
                weight: 1.0,
                colour: [0.2 + 0.1 * t as f32; 3],
                footprint: 0.1,
                grazing: 1.2,
                clear: 1.0,
            };
        }
        let ok = CellContext {
            cos_slope: vec![1.0; 4],
            ..half
        };
        let mut pairs = ColourPairs::default();
        assert_eq!(collect_pairs(&flat, &existing, &ok, &lp, &mut pairs), 1);
        assert!((pairs.photo[0][0] - 0.35).abs() < 1e-6);
    }
}
