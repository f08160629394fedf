//! Image metrics of the evaluation: PSNR over a pixel mask, at full resolution and after a
//! Gaussian low-pass.

use image::RgbImage;
use serde::Serialize;

/// An image as f32 sRGB values (0..255) per pixel, row-major.
pub type Plane = Vec<[f32; 3]>;

/// The pixels of `img` as a [`Plane`].
pub fn plane(img: &RgbImage) -> Plane {
    img.pixels().map(|p| p.0.map(f32::from)).collect()
}

/// `img` filtered with a Gaussian of standard deviation `sigma` pixels (separable, radius
/// `ceil(3σ)`, weights normalised, edges clamped); `sigma <= 0` returns a copy.
pub fn low_pass(img: &Plane, width: usize, height: usize, sigma: f64) -> Plane {
    if sigma <= 0.0 || img.len() != width * height || img.is_empty() {
        return img.clone();
    }
    let r = (3.0 * sigma).ceil() as isize;
    let mut k: Vec<f32> = (-r..=r)
        .map(|i| (-(i * i) as f64 / (2.0 * sigma * sigma)).exp() as f32)
        .collect();
    let sum: f32 = k.iter().sum();
    k.iter_mut().for_each(|v| *v /= sum);
    let pass = |src: &Plane, horizontal: bool| -> Plane {
        let mut out = vec![[0.0f32; 3]; src.len()];
        for y in 0..height {
            for x in 0..width {
                let mut acc = [0.0f32; 3];
                for (j, &kw) in k.iter().enumerate() {
                    let o = j as isize - r;
                    let (sx, sy) = if horizontal {
                        ((x as isize + o).clamp(0, width as isize - 1) as usize, y)
                    } else {
                        (x, (y as isize + o).clamp(0, height as isize - 1) as usize)
                    };
                    let p = src[sy * width + sx];
                    for c in 0..3 {
                        acc[c] += kw * p[c];
                    }
                }
                out[y * width + x] = acc;
            }
        }
        out
    };
    pass(&pass(img, true), false)
}

/// PSNR in dB (`10·log10(255² / MSE)` over the three channels) of `a` against `b` on the
/// pixels where `mask` holds, and their number; infinite for identical pixels, NaN for an
/// empty mask.
pub fn psnr_masked(a: &Plane, b: &Plane, mask: impl Fn(usize) -> bool) -> (f64, u64) {
    let (mut sq, mut n) = (0.0f64, 0u64);
    for (i, (p, q)) in a.iter().zip(b).enumerate() {
        if mask(i) {
            for c in 0..3 {
                let d = (p[c] - q[c]) as f64;
                sq += d * d;
            }
            n += 1;
        }
    }
    if n == 0 {
        return (f64::NAN, 0);
    }
    let mse = sq / (3 * n) as f64;
    (10.0 * (255.0f64 * 255.0 / mse).log10(), n)
}

/// PSNR of one method on one pixel class.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ClassScore {
    /// Pixels in the class.
    pub pixels: u64,
    /// PSNR at full resolution, dB (NaN/JSON null without pixels).
    pub psnr: f64,
    /// PSNR after the Gaussian low-pass of both images, dB.
    pub psnr_low: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psnr_of_a_known_error() {
        // a constant error of 10 grey levels on the masked half: MSE 100
        let a: Plane = vec![[100.0; 3]; 64];
        let mut b = a.clone();
        for p in b.iter_mut().take(32) {
            *p = [110.0; 3];
        }
        let (db, n) = psnr_masked(&a, &b, |i| i < 32);
        assert_eq!(n, 32);
        assert!(
            (db - 10.0 * (65025.0f64 / 100.0).log10()).abs() < 1e-9,
            "{db}"
        );
        assert_eq!(psnr_masked(&a, &b, |i| i >= 32).0, f64::INFINITY);
        assert!(psnr_masked(&a, &b, |_| false).0.is_nan());
    }

    #[test]
    fn low_pass_keeps_constants_and_spreads_an_impulse_with_unit_sum() {
        let (w, h) = (21, 17);
        let c: Plane = vec![[42.0, 7.0, 200.0]; w * h];
        for (p, q) in low_pass(&c, w, h, 2.0).iter().zip(&c) {
            for k in 0..3 {
                assert!((p[k] - q[k]).abs() < 1e-3);
            }
        }
        let mut imp: Plane = vec![[0.0; 3]; w * h];
        imp[8 * w + 10] = [1000.0; 3];
        let f = low_pass(&imp, w, h, 2.0);
        let sum: f32 = f.iter().map(|p| p[0]).sum();
        assert!((sum - 1000.0).abs() < 0.05, "{sum}");
        // the peak drops to 1000 / (2π σ²) and the spread is symmetric
        assert!(
            (f[8 * w + 10][0] - 1000.0 / (std::f32::consts::TAU * 4.0)).abs() < 0.5,
            "{}",
            f[8 * w + 10][0]
        );
        assert!((f[8 * w + 12][0] - f[8 * w + 8][0]).abs() < 1e-4);
        assert!((f[6 * w + 10][0] - f[8 * w + 12][0]).abs() < 1e-4);
    }
}
