//! Radial lens distortion in the renderer (CPU side): the pinhole view a distorted frame is
//! resampled from, and the reference of the shader's inverse mapping.
//!
//! A frame of a camera with `k1`/`k2` ≠ 0 is rendered in two passes: the terrain is rasterized
//! by a distortion-free pinhole camera with the same pose ([`DistortedView::pinhole`]) whose
//! field of view covers the whole distorted image (the image border undistorted, plus a margin)
//! at a pixel density at least the output's everywhere; then a full-screen pass
//! (`shaders/distort.wgsl`) maps each output pixel `(u, v)` to normalized distorted coordinates
//! `((u − cx)/fx, (v − cy)/fy)`, undistorts them (Newton on the radial model, as
//! [`undistort_radius_f32`]) and samples the pinhole image bilinearly there. A world point
//! therefore appears where [`CameraModel::project`] puts it, up to the bilinear resampling.

use crate::camera::CameraModel;
use crate::error::{Error, Result};

/// When a frame applies its camera's radial distortion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DistortionMode {
    /// When the camera has `k1` or `k2` ≠ 0 (the default).
    #[default]
    Auto,
    /// Never: distorted cameras are rendered as pinholes (the distortion is ignored).
    Off,
    /// Always, also for distortion-free cameras (for tests: the resampling pass alone).
    Always,
}

impl DistortionMode {
    /// Whether a frame of `cam` goes through the distortion pass.
    pub fn applies_to(self, cam: &CameraModel) -> bool {
        match self {
            DistortionMode::Auto => cam.k1 != 0.0 || cam.k2 != 0.0,
            DistortionMode::Off => false,
            DistortionMode::Always => true,
        }
    }
}

/// Margin of the pinhole view beyond the undistorted image border, pixels of the pinhole view
/// (room for the bilinear footprint).
pub const MARGIN_PX: f64 = 2.0;

/// Newton steps of the shader's radial inversion (converges monotonically from `r = rd` for
/// monotone convex or concave models; 10 steps reach f32 precision for |k1| ≤ 0.5).
pub const NEWTON_STEPS: u32 = 10;

/// A distorted output camera and the pinhole view its frame is resampled from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistortedView {
    /// The output camera (with its distortion), size = the frame's.
    pub output: CameraModel,
    /// Same pose, no distortion, focal lengths `scale ×` the output's, principal point and size
    /// such that the undistorted output border lies `MARGIN_PX` inside its pixel edges.
    pub pinhole: CameraModel,
    /// Pinhole focal length / output focal length: the largest local magnification of the
    /// distortion over the image (≥ 1), unless the pinhole view had to be shrunk to `max_side`.
    pub scale: f64,
    /// True if `scale` was reduced below the needed magnification to fit `max_side`
    /// (parts of the frame are then resampled from a coarser image).
    pub limited: bool,
}

impl DistortedView {
    /// The pinhole view of `output` with sides at most `max_side` pixels. Fails if the camera
    /// is unusable ([`CameraModel::problem`]). Where the distortion folds inside the image
    /// (in its corners) the view reaches the fold: pixels beyond it have no ray and the
    /// distortion pass shows them as sky.
    pub fn new(output: &CameraModel, max_side: u32) -> Result<DistortedView> {
        if let Some(p) = output.problem() {
            return Err(Error::BadOption(format!("camera cannot be rendered: {p}")));
        }
        let (w, h) = (output.width as f64, output.height as f64);
        // The border at pixel edges, sampled at most every pixel.
        let mut pts = Vec::new();
        let (nu, nv) = (output.width as usize + 1, output.height as usize + 1);
        for i in 0..=nu {
            let u = -0.5 + w * i as f64 / nu as f64;
            pts.push((u, -0.5));
            pts.push((u, h - 0.5));
        }
        for j in 0..=nv {
            let v = -0.5 + h * j as f64 / nv as f64;
            pts.push((-0.5, v));
            pts.push((w - 0.5, v));
        }
        let (mut lo, mut hi, mut r_max) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2], 0.0f64);
        for (u, v) in pts {
            let (mut xd, mut yd) = ((u - output.cx) / output.fx, (v - output.cy) / output.fy);
            // beyond the fold: the fold's radius in that direction (just inside it)
            let rd = xd.hypot(yd);
            let fold = output.fold_radius() * (1.0 - 1e-9);
            if rd > fold {
                (xd, yd) = (xd * fold / rd, yd * fold / rd);
            }
            let Some([x, y]) = output.undistort(xd, yd) else {
                return Err(Error::BadOption(format!(
                    "radial distortion k1 {} k2 {} has no inverse at the image border (pixel {u}, {v})",
                    output.k1, output.k2
                )));
            };
            lo = [lo[0].min(x), lo[1].min(y)];
            hi = [hi[0].max(x), hi[1].max(y)];
            r_max = r_max.max(x.hypot(y));
        }
        let need = magnification(output.k1, output.k2, r_max);
        let span = |s: f64| {
            [
                (hi[0] - lo[0]) * output.fx * s + 2.0 * MARGIN_PX,
                (hi[1] - lo[1]) * output.fy * s + 2.0 * MARGIN_PX,
            ]
        };
        let mut scale = need;
        let fit = |extent: f64, f: f64| (max_side as f64 - 1.0 - 2.0 * MARGIN_PX) / (extent * f);
        let s_max = fit(hi[0] - lo[0], output.fx).min(fit(hi[1] - lo[1], output.fy));
        let limited = scale > s_max;
        if limited {
            scale = s_max;
        }
        if !(scale.is_finite() && scale > 0.0) {
            return Err(Error::BadOption(format!(
                "cannot fit the undistorted view of a {}x{} frame into {max_side} pixels per side",
                output.width, output.height
            )));
        }
        // Sizes: ceil with a little slack so an exact integer extent (no distortion) is kept.
        let [sw, sh] = span(scale);
        let (pw, ph) = ((sw - 1e-6).ceil().max(1.0), (sh - 1e-6).ceil().max(1.0));
        let (fx, fy) = (output.fx * scale, output.fy * scale);
        let pinhole = CameraModel {
            width: pw as u32,
            height: ph as u32,
            fx,
            fy,
            cx: MARGIN_PX - 0.5 - fx * lo[0],
            cy: MARGIN_PX - 0.5 - fy * lo[1],
            k1: 0.0,
            k2: 0.0,
            ..*output
        };
        Ok(DistortedView {
            output: *output,
            pinhole,
            scale,
            limited,
        })
    }

    /// Where output pixel `(u, v)` (pixel-centre convention) samples the pinhole image, in
    /// pinhole pixel coordinates (f64 reference of the shader); `None` where the distortion
    /// has no inverse.
    pub fn source_pixel(&self, u: f64, v: f64) -> Option<[f64; 2]> {
        let o = &self.output;
        let [x, y] = o.undistort((u - o.cx) / o.fx, (v - o.cy) / o.fy)?;
        let p = &self.pinhole;
        Some([p.fx * x + p.cx, p.fy * y + p.cy])
    }
}

/// Largest local magnification `max(f'(r), f(r)/r)` of the radial map `f(r) = r·d(min(r², 4))`
/// over undistorted radii `[0, r_max]` (≥ 1): how much denser than the output's pixels the
/// pinhole pixels must be so no output pixel samples the pinhole image coarser than its own size.
pub fn magnification(k1: f64, k2: f64, r_max: f64) -> f64 {
    let steps = 1024;
    let mut m = 1.0f64;
    for i in 0..=steps {
        let r = r_max * i as f64 / steps as f64;
        let s = (r * r).min(4.0);
        let d = 1.0 + k1 * s + k2 * s * s;
        let df = if r * r < 4.0 {
            1.0 + 3.0 * k1 * s + 5.0 * k2 * s * s
        } else {
            d
        };
        m = m.max(d).max(df);
    }
    m
}

/// The shader's radial inversion in f32 (for tests): the undistorted radius `r` with
/// `r·(1 + k1·s + k2·s²) = rd`, `s = min(r², 4)`, by [`NEWTON_STEPS`] Newton steps from `rd`
/// (a step stops where the model's derivative is not positive, i.e. beyond its fold).
pub fn undistort_radius_f32(k1: f32, k2: f32, rd: f32) -> f32 {
    let mut r = rd;
    for _ in 0..NEWTON_STEPS {
        let s = (r * r).min(4.0);
        let d = 1.0 + k1 * s + k2 * s * s;
        let df = if r * r < 4.0 {
            1.0 + 3.0 * k1 * s + 5.0 * k2 * s * s
        } else {
            d
        };
        if df <= 0.0 {
            break;
        }
        r = (r - (r * d - rd) / df).max(0.0);
    }
    r
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::rotation_from_yaw_pitch_roll;
    use glam::DVec3;

    fn cam(w: u32, h: u32, k1: f64, k2: f64) -> CameraModel {
        let r = rotation_from_yaw_pitch_roll(3.8, 0.1, -0.01);
        let mut c = CameraModel::with_fov(DVec3::new(446_722.0, 7_396_671.0, 770.0), r, w, h, 0.9);
        c.cx += 7.0;
        c.cy -= 3.0;
        c.k1 = k1;
        c.k2 = k2;
        c
    }

    #[test]
    fn the_pinhole_view_covers_every_output_pixel_at_least_as_densely() {
        for (k1, k2) in [(-0.115, 0.0), (0.08, 0.02), (-0.2, 0.05), (0.0, 0.0)] {
            let c = cam(640, 427, k1, k2);
            let v = DistortedView::new(&c, 16384).unwrap();
            assert!(!v.limited && v.scale >= 1.0);
            let p = &v.pinhole;
            assert_eq!((p.k1, p.k2), (0.0, 0.0));
            assert_eq!(
                (p.position, p.world_to_camera),
                (c.position, c.world_to_camera)
            );
            let (pw, ph) = (p.width as f64, p.height as f64);
            let m = MARGIN_PX - 1e-6;
            for j in 0..=40 {
                for i in 0..=64 {
                    let (u, vv) = (
                        -0.5 + 640.0 * i as f64 / 64.0,
                        -0.5 + 427.0 * j as f64 / 40.0,
                    );
                    let [su, sv] = v.source_pixel(u, vv).unwrap();
                    assert!(
                        su >= m - 0.5 && su <= pw - 0.5 - m,
                        "k ({k1},{k2}): u {u} -> {su} of {pw}"
                    );
                    assert!(
                        sv >= m - 0.5 && sv <= ph - 0.5 - m,
                        "k ({k1},{k2}): v {vv} -> {sv} of {ph}"
                    );
                    // One output pixel spans at least one pinhole pixel in both directions.
                    let [du, _] = v.source_pixel(u + 0.01, vv).unwrap();
                    let [_, dv] = v.source_pixel(u, vv + 0.01).unwrap();
                    assert!((du - su) / 0.01 >= 1.0 - 1e-3 && (dv - sv) / 0.01 >= 1.0 - 1e-3);
                    // A world point on the pixel's ray projects through the pinhole to the sample.
                    let ray = c.pixel_ray(u, vv).unwrap();
                    let q = p.project(c.position + 300.0 * ray).unwrap();
                    assert!((q[0] - su).abs() < 1e-6 && (q[1] - sv).abs() < 1e-6);
                }
            }
        }
    }

    #[test]
    fn no_distortion_gives_an_integer_shift_of_the_output() {
        let c = cam(320, 200, 0.0, 0.0);
        let v = DistortedView::new(&c, 4096).unwrap();
        let m = MARGIN_PX;
        assert_eq!(
            (v.pinhole.width, v.pinhole.height),
            (320 + 2 * m as u32, 200 + 2 * m as u32)
        );
        assert_eq!(v.scale, 1.0);
        assert!(
            (v.pinhole.cx - (c.cx + m)).abs() < 1e-9 && (v.pinhole.cy - (c.cy + m)).abs() < 1e-9
        );
        let [su, sv] = v.source_pixel(10.0, 20.0).unwrap();
        assert!((su - (10.0 + m)).abs() < 1e-9 && (sv - (20.0 + m)).abs() < 1e-9);
    }

    #[test]
    fn barrel_distortion_needs_no_magnification_and_pincushion_does() {
        assert_eq!(magnification(-0.115, 0.0, 0.5), 1.0);
        let m = magnification(0.08, 0.0, 0.5);
        assert!((m - (1.0 + 3.0 * 0.08 * 0.25)).abs() < 1e-9, "{m}");
        // The Engabreen camera: the pinhole view is a little wider than the photo's.
        let mut e = cam(4290, 2856, -0.11454086509291705, 0.0);
        e.fx = 6014.4;
        e.fy = 6021.5;
        e.cx = 2144.5;
        e.cy = 1427.5;
        let v = DistortedView::new(&e, 16384).unwrap();
        assert_eq!(v.scale, 1.0);
        assert!(
            v.pinhole.width > 4290 + 4 && v.pinhole.width < 4600,
            "{}",
            v.pinhole.width
        );
        // Shrunk to fit a small limit, flagged.
        let small = DistortedView::new(&e, 2048).unwrap();
        assert!(small.limited && small.pinhole.width <= 2048 && small.pinhole.height <= 2048);
        // A folding camera is refused.
        let bad = cam(640, 480, -2.0, 0.0);
        assert!(DistortedView::new(&bad, 4096).is_err());
    }

    #[test]
    fn f32_newton_matches_the_f64_inverse() {
        for (k1, k2) in [(-0.115, 0.0), (0.08, 0.02), (-0.2, 0.05), (0.3, -0.05)] {
            let c = cam(640, 480, k1, k2);
            for i in 1..=200 {
                let rd = 0.0035 * i as f64; // up to 0.7
                let Some([r, _]) = c.undistort(rd, 0.0) else {
                    continue;
                };
                let r32 = undistort_radius_f32(k1 as f32, k2 as f32, rd as f32) as f64;
                // At a focal length of 6000 px this is < 1e-3 px.
                assert!(
                    (r32 - r).abs() < 1.5e-7,
                    "k ({k1},{k2}) rd {rd}: {r32} vs {r}"
                );
            }
        }
        assert_eq!(undistort_radius_f32(0.0, 0.0, 0.4), 0.4);
    }
}
