//! Normalised mutual information between a view's sample labels and a photo's grey levels
//! (Studholme et al. 1999), with partial-volume binning of the photo's interpolated grey so
//! the score changes continuously with the camera.

use image::RgbImage;
use rayon::prelude::*;

use super::view::{LABELS, Sample, SampleAt};
use crate::camera::CameraModel;

/// Photo luma classes.
const LUMA: usize = 8;
/// Photo chroma classes (blue against yellow-red: sky against rock and ground).
const CHROMA: usize = 4;
/// Photo classes, plus one for samples that project outside the photo (so that dropping
/// samples off the image's edge is not free).
const BINS: usize = LUMA * CHROMA + 1;
const OUTSIDE_BIN: bool = false;
/// Samples per histogram chunk (fixed, so sums do not depend on the thread count).
const CHUNK: usize = 4096;

/// A photo as grey levels (0 ..= BINS − 1, from its 1st–99th percentiles) at one scale.
#[derive(Clone, Debug)]
pub struct GreyImage {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    data: Vec<f32>,
    /// Per pixel, whether it holds no masked photo pixel (`None`: every pixel is valid).
    valid: Option<Vec<bool>>,
}

impl GreyImage {
    /// The photo box-filtered by `factor` (a power of two ≥ 1) per axis as luma and chroma
    /// (blue − red over their sum), each stretched so its 1st and 99th percentiles span
    /// its classes.
    pub fn from_photo(photo: &RgbImage, factor: u32) -> GreyImage {
        Self::from_photo_masked(photo, None, factor)
    }

    /// [`GreyImage::from_photo`] with the pixels `mask` marks left out: a reduced pixel that
    /// holds one is outside the photo ([`GreyImage::at`] gives `None` next to it), and the
    /// stretch's percentiles come from the others.
    pub fn from_photo_masked(
        photo: &RgbImage,
        mask: Option<&crate::photo::PixelMask>,
        factor: u32,
    ) -> GreyImage {
        let f = factor.max(1);
        let (w, h) = ((photo.width() / f).max(1), (photo.height() / f).max(1));
        let px: Vec<[f32; 2]> = (0..h)
            .into_par_iter()
            .flat_map_iter(|y| {
                (0..w).map(move |x| {
                    let mut s = [0.0f32; 3];
                    let mut n = 0u32;
                    for yy in y * f..((y + 1) * f).min(photo.height()) {
                        for xx in x * f..((x + 1) * f).min(photo.width()) {
                            let c = photo.get_pixel(xx, yy).0;
                            for k in 0..3 {
                                s[k] += c[k] as f32;
                            }
                            n += 1;
                        }
                    }
                    let s = s.map(|v| v / n.max(1) as f32);
                    [
                        0.2126 * s[0] + 0.7152 * s[1] + 0.0722 * s[2],
                        (s[2] - s[0]) / (s[0] + s[1] + s[2] + 30.0),
                    ]
                })
            })
            .collect();
        let valid = mask
            .map(|m| super::edges::reduced_validity(m, f, w as usize, h as usize))
            .filter(|v| v.iter().any(|ok| *ok));
        let stretch = |k: usize, classes: usize| -> (f32, f32) {
            let mut v: Vec<f32> = match &valid {
                Some(ok) => px
                    .iter()
                    .zip(ok)
                    .filter(|(_, ok)| **ok)
                    .map(|(p, _)| p[k])
                    .collect(),
                None => px.iter().map(|p| p[k]).collect(),
            };
            v.sort_unstable_by(f32::total_cmp);
            let lo = v[v.len() / 100];
            let hi = v[(v.len() * 99 / 100).min(v.len() - 1)];
            (
                lo,
                if hi > lo {
                    (classes - 1) as f32 / (hi - lo)
                } else {
                    0.0
                },
            )
        };
        let (l0, ls) = stretch(0, LUMA);
        let (c0, cs) = stretch(1, CHROMA);
        let mut data = Vec::with_capacity(px.len() * 2);
        for p in &px {
            data.push(((p[0] - l0) * ls).clamp(0.0, (LUMA - 1) as f32));
            data.push(((p[1] - c0) * cs).clamp(0.0, (CHROMA - 1) as f32));
        }
        GreyImage {
            width: w,
            height: h,
            data,
            valid,
        }
    }

    /// Bilinear (luma, chroma) at pixel position (u, v) (pixel-centre convention), `None`
    /// outside. Luma in 0 ..= 7, chroma in 0 ..= 3 (the classes, continuous).
    #[inline]
    pub fn at(&self, u: f64, v: f64) -> Option<[f32; 2]> {
        if !(u >= 0.0 && v >= 0.0 && u <= (self.width - 1) as f64 && v <= (self.height - 1) as f64)
        {
            return None;
        }
        let (x0, y0) = (u.floor() as usize, v.floor() as usize);
        let (fx, fy) = ((u - x0 as f64) as f32, (v - y0 as f64) as f32);
        let w = self.width as usize;
        let x1 = (x0 + 1).min(w - 1);
        let y1 = (y0 + 1).min(self.height as usize - 1);
        if let Some(ok) = &self.valid
            && !(ok[y0 * w + x0] && ok[y0 * w + x1] && ok[y1 * w + x0] && ok[y1 * w + x1])
        {
            return None;
        }
        let d = &self.data;
        let g = |k: usize| {
            let top = d[2 * (y0 * w + x0) + k] * (1.0 - fx) + d[2 * (y0 * w + x1) + k] * fx;
            let bot = d[2 * (y1 * w + x0) + k] * (1.0 - fx) + d[2 * (y1 * w + x1) + k] * fx;
            top * (1.0 - fy) + bot * fy
        };
        Some([g(0), g(1)])
    }
}

/// The normalised mutual information `(H(L) + H(G)) / H(L, G)` (1 = independent, 2 = one
/// determines the other) of the samples' labels L and the photo's classes G (luma ×
/// chroma, partial-volume) where `cam` (sized like `photo`) projects them; samples outside
/// the photo or behind the camera fall in a class of their own. 1.0 when fewer than 64 samples land. Deterministic whatever the thread count.
pub fn nmi(samples: &[Sample], cam: &CameraModel, photo: &GreyImage) -> f64 {
    nmi_by(samples.len(), |i| {
        let s = &samples[i];
        (
            s.label,
            sample_pixel(s, cam).and_then(|px| photo.at(px[0], px[1])),
        )
    })
}

/// Where `cam` shows a sample (pixel position, with distortion): a terrain point projected,
/// a sky direction turned by the camera's rotation alone; `None` behind the camera.
#[inline]
pub fn sample_pixel(s: &Sample, cam: &CameraModel) -> Option<[f64; 2]> {
    match s.at {
        SampleAt::Point(p) => cam.project(p),
        SampleAt::Sky(d) => project_dir(cam, cam.world_to_camera * d),
    }
}

/// The normalised mutual information of `n` (label, photo value) pairs given by `value(i)`
/// (the photo value as [`GreyImage::at`] gives it, `None` where the sample misses the
/// photo), as [`nmi`] scores them. Deterministic whatever the thread count.
pub fn nmi_by(n: usize, value: impl Fn(usize) -> (u8, Option<[f32; 2]>) + Sync) -> f64 {
    let chunks = n.div_ceil(CHUNK);
    let hists: Vec<Vec<f32>> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut joint = vec![0.0f32; LABELS * BINS];
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                let (label, g) = value(i);
                let row = label as usize * BINS;
                let Some(g) = g else {
                    if OUTSIDE_BIN {
                        joint[row + BINS - 1] += 1.0;
                    }
                    continue;
                };
                let (l, c) = (
                    (g[0].floor() as usize).min(LUMA - 2),
                    (g[1].floor() as usize).min(CHROMA - 2),
                );
                let (fl, fc) = (g[0] - l as f32, g[1] - c as f32);
                joint[row + c * LUMA + l] += (1.0 - fl) * (1.0 - fc);
                joint[row + c * LUMA + l + 1] += fl * (1.0 - fc);
                joint[row + (c + 1) * LUMA + l] += (1.0 - fl) * fc;
                joint[row + (c + 1) * LUMA + l + 1] += fl * fc;
            }
            joint
        })
        .collect();
    let mut joint = vec![0.0f64; LABELS * BINS];
    for h in &hists {
        for (a, b) in joint.iter_mut().zip(h) {
            *a += *b as f64;
        }
    }
    let n: f64 = joint.iter().sum();
    if n < 64.0 {
        return 1.0;
    }
    let mut pl = vec![0.0f64; LABELS];
    let mut pg = vec![0.0f64; BINS];
    let mut h_joint = 0.0;
    for l in 0..LABELS {
        for g in 0..BINS {
            let p = joint[l * BINS + g] / n;
            pl[l] += p;
            pg[g] += p;
            if p > 0.0 {
                h_joint -= p * p.ln();
            }
        }
    }
    let ent = |v: &[f64]| {
        -v.iter()
            .filter(|&&p| p > 0.0)
            .map(|&p| p * p.ln())
            .sum::<f64>()
    };
    if h_joint <= 0.0 {
        return 1.0;
    }
    (ent(&pl) + ent(&pg)) / h_joint
}

/// Pixel of a camera-frame direction (with distortion), `None` behind the camera.
#[inline]
fn project_dir(cam: &CameraModel, c: glam::DVec3) -> Option<[f64; 2]> {
    if c.z <= 0.0 || c.z.is_nan() {
        return None;
    }
    let (x, y) = (c.x / c.z, c.y / c.z);
    let r2 = (x * x + y * y).min(4.0);
    let d = 1.0 + cam.k1 * r2 + cam.k2 * r2 * r2;
    Some([cam.fx * x * d + cam.cx, cam.fy * y * d + cam.cy])
}
