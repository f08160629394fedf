//! Registering a photo to another taken from the same place (a fixed time-lapse camera that
//! turned a little, ImGRAFT's "camera B = camera A rotated"): patch matches between the two
//! images, then a rotation-only fit.
//!
//! Matching: on a regular grid over photo A (margin of a patch and the search radius),
//! each patch of `2·half + 1` pixels square with enough texture (standard deviation ≥ 2
//! grey levels) is searched in photo B by normalised cross-correlation (NCC), first on both
//! images box-filtered 4× (radius `radius / 4 + 2`), then at full resolution within ±4
//! pixels of that; the peak is refined to sub-pixel by a parabola through it and its
//! neighbours in each axis. A match counts if its NCC is at least `min_ncc` and the peak is
//! not at the edge of the search; the sub-pixel position then comes from a Lucas-Kanade
//! refinement of the translation (Gauss-Newton on bilinear samples of B, both patches
//! normalised to zero mean and unit norm; the parabola alone is biased towards whole
//! pixels by up to 0.2 px). Deterministic (grid order, no randomness).
//!
//! Fit: each match becomes a ground control point for B: the world point 10 km along A's
//! ray through the matched pixel (A's distortion removed), observed at B's pixel. With B's
//! position fixed at A's, only B's angles are fitted ([`crate::register::fit_camera`], robust): the
//! points are effectively at infinity, so the fit is the rotation alone and its RMSE is the
//! match residual in pixels.

use glam::DVec3;
use image::RgbImage;
use rayon::prelude::*;

use crate::camera::CameraModel;
use crate::error::{Error, Result};
use crate::register::gcps::fit::{CameraFit, FitOptions, fit_camera};
use crate::register::gcps::gcp::Gcp;
use crate::register::grey::{Grey, grid_centres};
use crate::register::params::Param;

/// How [`match_photos`] matches.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MatchOptions {
    /// Patch half size, pixels (patch side `2·half + 1`). Default 15.
    pub half: u32,
    /// Largest shift searched, pixels. Default 64.
    pub radius: u32,
    /// Grid spacing of the patches in A, pixels. Default 96.
    pub spacing: u32,
    /// Lowest NCC of a match. Default 0.8.
    pub min_ncc: f64,
}

impl Default for MatchOptions {
    fn default() -> Self {
        MatchOptions {
            half: 15,
            radius: 64,
            spacing: 96,
            min_ncc: 0.8,
        }
    }
}

/// A patch of A found in B.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PatchMatch {
    /// Patch centre in A (0-based pixels).
    pub a: [f64; 2],
    /// Its position in B (sub-pixel).
    pub b: [f64; 2],
    /// NCC at the peak.
    pub ncc: f64,
}

/// Matches patches of photo `a` in photo `b` (same size; see the module docs (`src/register/pair.rs`)), in
/// grid order.
pub fn match_photos(a: &RgbImage, b: &RgbImage, opts: &MatchOptions) -> Result<Vec<PatchMatch>> {
    if a.dimensions() != b.dimensions() {
        return Err(Error::BadOption(format!(
            "photos of different sizes: {:?} and {:?}",
            a.dimensions(),
            b.dimensions()
        )));
    }
    let (ga, gb) = (Grey::of(a), Grey::of(b));
    let k = 4usize;
    let (ca, cb) = (ga.reduced(k), gb.reduced(k));
    let (half, radius) = (opts.half.max(2) as i64, opts.radius as i64);
    let margin = half + radius + 8;
    let centres = grid_centres(ga.w, ga.h, margin, opts.spacing as i64);
    let coarse_half = (half / k as i64).max(4);
    let coarse_rad = radius / k as i64 + 2;
    let found: Vec<Option<PatchMatch>> = centres
        .par_iter()
        .map(|&(x, y)| {
            let (t, tn) = ga.patch(x, y, half)?;
            if tn / ((2 * half + 1) as f32) < 2.0 {
                return None; // std below 2 grey levels: no texture to match
            }
            let (ct, ctn) = ca.patch(x / k as i64, y / k as i64, coarse_half)?;
            let (cx, cy, _, _) = cb.search(
                &ct,
                ctn,
                (x / k as i64, y / k as i64),
                coarse_rad,
                coarse_half,
            )?;
            let (fx, fy, s, edge) = gb.search(
                &t,
                tn,
                (cx * k as i64 + k as i64 / 2, cy * k as i64 + k as i64 / 2),
                4 + k as i64,
                half,
            )?;
            if edge || s < opts.min_ncc {
                return None;
            }
            let b = gb.peak_sub_pixel(&t, tn, (fx, fy), s, half)?;
            Some(PatchMatch {
                a: [x as f64, y as f64],
                b,
                ncc: s,
            })
        })
        .collect();
    Ok(found.into_iter().flatten().collect())
}

/// The matches whose ray from camera `a` meets the surface (`surface(origin, unit dir)`
/// gives the nearest hit point) at a point `stable` accepts: for matching stable ground only
/// (ImGRAFT matches rock, not the moving glacier); matches whose ray meets no surface (sky,
/// clouds) are left out too.
pub fn stable_matches(
    a: &CameraModel,
    matches: &[PatchMatch],
    surface: impl Fn(DVec3, DVec3) -> Option<DVec3>,
    stable: impl Fn(DVec3) -> bool,
) -> Vec<PatchMatch> {
    matches
        .iter()
        .copied()
        .filter(|m| {
            a.pixel_ray(m.a[0], m.a[1])
                .and_then(|d| surface(a.position, d))
                .is_some_and(&stable)
        })
        .collect()
}

/// Fits photo B's rotation from `matches` with A's camera `a` (B at A's position, A's
/// intrinsics; see the module docs (`src/register/pair.rs`)). The result's RMSE is the match residual.
pub fn fit_rotation(a: &CameraModel, matches: &[PatchMatch]) -> Result<CameraFit> {
    let gcps: Vec<Gcp> = matches
        .iter()
        .enumerate()
        .filter_map(|(i, m)| {
            let dir: DVec3 = a.pixel_ray(m.a[0], m.a[1])?;
            Some(Gcp {
                name: format!("match {i}"),
                world: a.position + dir * 1e4,
                pixel: m.b,
                weight: 1.0,
            })
        })
        .collect();
    fit_camera(
        a,
        &gcps,
        &FitOptions {
            free: vec![Param::Yaw, Param::Pitch, Param::Roll],
            ..FitOptions::default()
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_known_subpixel_shift() {
        // a smooth random texture, and the same shifted by (7.3, -2.6) px
        let tex = |x: f64, y: f64| {
            let v = (x * 0.21).sin() * (y * 0.17).cos()
                + (x * 0.05 + y * 0.11).sin()
                + ((x * 0.13 - y * 0.07).cos() * 0.5);
            (128.0 + 50.0 * v).clamp(0.0, 255.0) as u8
        };
        let a = RgbImage::from_fn(400, 300, |x, y| {
            let v = tex(x as f64, y as f64);
            image::Rgb([v, v, v])
        });
        let b = RgbImage::from_fn(400, 300, |x, y| {
            let v = tex(x as f64 - 7.3, y as f64 + 2.6);
            image::Rgb([v, v, v])
        });
        let m = match_photos(
            &a,
            &b,
            &MatchOptions {
                radius: 16,
                spacing: 40,
                ..MatchOptions::default()
            },
        )
        .unwrap();
        assert!(m.len() >= 10, "{} matches", m.len());
        for p in &m {
            let (du, dv) = (p.b[0] - p.a[0], p.b[1] - p.a[1]);
            assert!((du - 7.3).abs() < 0.03 && (dv + 2.6).abs() < 0.03, "{p:?}");
        }
        assert!(match_photos(&a, &RgbImage::new(10, 10), &MatchOptions::default()).is_err());
    }
}
