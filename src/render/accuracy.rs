//! Measuring what the LOD selection costs on screen: surface displacement between two depth
//! buffers of the same camera, and per-pixel image differences.
//!
//! **Displacement metric.** Each drawn pixel `p` of frame A gives a surface point `X` (from its
//! depth). Its counterpart on surface B is the nearest point of B to `X` in 3D, searched among
//! B's pixel samples `q` within a square window around `p`, then refined to sub-pixel
//! precision: the nearest point on the surface interpolated between B's samples (two triangles
//! per 2×2 block of continuous samples) within 2 px of the best sample `q*`. Where no such block
//! exists the sample `F(q*)` itself is used (pixel-quantised; counted as point-matched).
//! The displacement of `p` is
//! the screen distance between `p` and the counterpart's pinhole projection. This is done in
//! both directions (A→B and B→A, a screen-space symmetric Hausdorff distance), so silhouettes
//! that move, and surface that appears on only one side, are measured rather than skipped;
//! a pixel with no B sample at all in the window counts as `window + 1` px (unmatched).
//!
//! **Silhouettes are excluded.** Next to an occluding contour the true counterpart may lie on
//! a hidden part of the other surface (the back of a ridge), and the nearest *visible* sample
//! can be pixels away although the surface moved less: per-pixel comparison is meaningless
//! there. Pixels within `exclude_radius` of a depth discontinuity of either frame (a 4-neighbour
//! that is empty, or whose depth differs by more than [`DEPTH_JUMP`] relative) are not
//! measured; their count is reported.

use glam::DVec3;
use rayon::prelude::*;

use super::camera::RenderCamera;

/// Camera-relative surface points of a depth buffer (row 0 at the top), `None` where empty.
pub fn depth_points(cam: &RenderCamera, depth: &[f32]) -> Vec<Option<DVec3>> {
    let w = cam.model.width as usize;
    depth
        .iter()
        .enumerate()
        .map(|(i, &d)| cam.unproject_relative((i % w) as f64, (i / w) as f64, d))
        .collect()
}

/// Screen-space displacement between two surfaces seen by one camera.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct Displacement {
    /// Largest displacement over both directions, pixels.
    pub max_px: f64,
    /// Largest displacement scaled by `cos²θ` of its pixel's viewing ray (θ off the optical
    /// axis), pixels: the quantity the screen-space error formula `e · fy / d` bounds (an
    /// offset `e` at distance `d` moves a pixel by up to `e · fy / (d · cos²θ)`).
    pub max_on_axis_px: f64,
    /// 99th percentile, pixels.
    pub p99_px: f64,
    /// Mean, pixels.
    pub mean_px: f64,
    /// Pixel `[x, y]` of the largest on-axis displacement.
    pub worst_pixel: [usize; 2],
    /// Drawn pixels left out as silhouette neighbourhoods (both directions together).
    pub excluded: usize,
    /// Pixels measured (both directions together).
    pub measured: usize,
    /// Of those, matched to a single sample (no continuous 2×2 sample block nearby).
    pub point_matched: usize,
    /// Pixels with no surface sample of the other frame inside the window (counted as
    /// `window + 1` px).
    pub unmatched: usize,
}

/// Relative depth jump between 4-neighbours treated as a discontinuity (10 %).
pub const DEPTH_JUMP: f64 = 0.1;

/// Pixels within `radius` (square neighbourhood) of a depth discontinuity of `depth`.
fn discontinuity_mask(depth: &[f32], w: usize, h: usize, radius: usize) -> Vec<bool> {
    let mut edge = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let c = depth[y * w + x] as f64;
            let jump = |xx: usize, yy: usize| {
                let d = depth[yy * w + xx] as f64;
                let (lo, hi) = (c.min(d), c.max(d));
                (lo <= 0.0 && hi > 0.0) || (lo > 0.0 && hi > lo * (1.0 + DEPTH_JUMP))
            };
            let e = (x > 0 && jump(x - 1, y))
                || (x + 1 < w && jump(x + 1, y))
                || (y > 0 && jump(x, y - 1))
                || (y + 1 < h && jump(x, y + 1));
            edge[y * w + x] = e;
        }
    }
    if radius == 0 {
        return edge;
    }
    // Separable square dilation.
    let mut rows = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let (x0, x1) = (x.saturating_sub(radius), (x + radius + 1).min(w));
            rows[y * w + x] = edge[y * w + x0..y * w + x1].iter().any(|&b| b);
        }
    }
    let mut out = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let (y0, y1) = (y.saturating_sub(radius), (y + radius + 1).min(h));
            out[y * w + x] = (y0..y1).any(|yy| rows[yy * w + x]);
        }
    }
    out
}

/// Closest point to `p` on triangle `abc` (Ericson, Real-Time Collision Detection 5.1.5).
fn closest_on_triangle(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    a + ab * (vb * denom) + ac * (vc * denom)
}

/// Whether two depth samples belong to one continuous surface (both drawn, jump ≤ [`DEPTH_JUMP`]).
fn continuous(a: f32, b: f32) -> bool {
    let (lo, hi) = (a.min(b) as f64, a.max(b) as f64);
    lo > 0.0 && hi <= lo * (1.0 + DEPTH_JUMP)
}

/// Nearest point to `p` on the surface interpolated between the samples of `b` (two triangles
/// per 2×2 block of continuous samples) within `r` pixels of sample `(qx, qy)`.
#[allow(clippy::too_many_arguments)]
fn closest_on_samples(
    p: DVec3,
    b: &[Option<DVec3>],
    depth: &[f32],
    w: usize,
    h: usize,
    qx: usize,
    qy: usize,
    r: usize,
) -> Option<DVec3> {
    let mut best: Option<(f64, DVec3)> = None;
    for y in qy.saturating_sub(r)..(qy + r).min(h - 1) {
        for x in qx.saturating_sub(r)..(qx + r).min(w - 1) {
            let k = [
                y * w + x,
                y * w + x + 1,
                (y + 1) * w + x,
                (y + 1) * w + x + 1,
            ];
            let d = k.map(|i| depth[i]);
            let ok = continuous(d[0], d[1])
                && continuous(d[0], d[2])
                && continuous(d[1], d[3])
                && continuous(d[2], d[3]);
            if !ok {
                continue;
            }
            let (Some(v0), Some(v1), Some(v2), Some(v3)) = (b[k[0]], b[k[1]], b[k[2]], b[k[3]])
            else {
                continue;
            };
            for (t0, t1, t2) in [(v0, v1, v3), (v0, v3, v2)] {
                let c = closest_on_triangle(p, t0, t1, t2);
                let d2 = (c - p).length_squared();
                if best.is_none_or(|(b2, _)| d2 < b2) {
                    best = Some((d2, c));
                }
            }
        }
    }
    best.map(|(_, c)| c)
}

/// One direction: displacement of each drawn pixel of `a` against surface `b`.
fn one_way(
    cam: &RenderCamera,
    a: &[Option<DVec3>],
    b: &[Option<DVec3>],
    b_depth: &[f32],
    excluded: &[bool],
    window: usize,
) -> Vec<(f64, bool, bool, f64, [usize; 2])> {
    let (w, h) = (cam.model.width as usize, cam.model.height as usize);
    (0..h)
        .into_par_iter()
        .map(|y| {
            let mut row = Vec::new();
            for x in 0..w {
                let Some(p) = a[y * w + x] else { continue };
                if excluded[y * w + x] {
                    continue;
                }
                let m = &cam.model;
                let (tx, ty) = ((x as f64 - m.cx) / m.fx, (y as f64 - m.cy) / m.fy);
                let cos2 = 1.0 / (1.0 + tx * tx + ty * ty);
                let mut best: Option<(f64, usize, usize)> = None;
                for qy in y.saturating_sub(window)..(y + window + 1).min(h) {
                    for qx in x.saturating_sub(window)..(x + window + 1).min(w) {
                        if let Some(f) = b[qy * w + qx] {
                            let d2 = (f - p).length_squared();
                            if best.is_none_or(|(b2, _, _)| d2 < b2) {
                                best = Some((d2, qx, qy));
                            }
                        }
                    }
                }
                let Some((_, qx, qy)) = best else {
                    row.push((window as f64 + 1.0, false, true, cos2, [x, y]));
                    continue;
                };
                let point_px =
                    ((qx as f64 - x as f64).powi(2) + (qy as f64 - y as f64).powi(2)).sqrt();
                // Sub-pixel counterpart on the sample surface around the best sample.
                let refined = closest_on_samples(p, b, b_depth, w, h, qx, qy, 2)
                    .and_then(|c| cam.project_relative(c))
                    .map(|s| (s[0] - x as f64).hypot(s[1] - y as f64));
                match refined {
                    Some(px) => row.push((px, false, false, cos2, [x, y])),
                    None => row.push((point_px, true, false, cos2, [x, y])),
                }
            }
            row
        })
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// Symmetric screen-space displacement between the surfaces of depth buffers `a` and `b`
/// (both `width × height` of `cam`, reverse-Z as read by
/// [`TerrainRenderer::read_depth`](super::TerrainRenderer::read_depth)), searching
/// counterparts within `window` pixels and leaving out pixels within `exclude_radius` of a
/// silhouette of either frame. Deterministic for any thread count.
pub fn surface_displacement(
    cam: &RenderCamera,
    a_depth: &[f32],
    b_depth: &[f32],
    window: usize,
    exclude_radius: usize,
) -> Displacement {
    let (w, h) = (cam.model.width as usize, cam.model.height as usize);
    let a = depth_points(cam, a_depth);
    let b = depth_points(cam, b_depth);
    let ma = discontinuity_mask(a_depth, w, h, exclude_radius);
    let mb = discontinuity_mask(b_depth, w, h, exclude_radius);
    let excluded: Vec<bool> = ma.iter().zip(&mb).map(|(x, y)| *x || *y).collect();
    let drawn = a.iter().chain(&b).filter(|p| p.is_some()).count();
    let mut all = one_way(cam, &a, &b, b_depth, &excluded, window);
    all.extend(one_way(cam, &b, &a, a_depth, &excluded, window));
    let mut out = Displacement {
        excluded: drawn - all.len(),
        measured: all.len(),
        point_matched: all.iter().filter(|v| v.1).count(),
        unmatched: all.iter().filter(|v| v.2).count(),
        ..Default::default()
    };
    for v in &all {
        if v.0 * v.3 > out.max_on_axis_px {
            out.max_on_axis_px = v.0 * v.3;
            out.worst_pixel = v.4;
        }
    }
    let mut v: Vec<f64> = all.iter().map(|v| v.0).collect();
    if v.is_empty() {
        return out;
    }
    out.mean_px = v.iter().sum::<f64>() / v.len() as f64;
    v.sort_by(f64::total_cmp);
    out.max_px = v[v.len() - 1];
    out.p99_px = percentile(&v, 0.99);
    out
}

/// Per-pixel difference of two RGBA images of the same size (RGB channels only).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ImageDiff {
    /// Mean absolute difference over pixels and RGB channels, 8-bit levels.
    pub mean_abs: f64,
    /// Largest channel difference, 8-bit levels.
    pub max_abs: u8,
    /// Fraction of pixels whose largest channel difference exceeds the tolerance, in [0, 1].
    pub frac_over: f64,
}

/// Compares `a` with `b` (same dimensions, else `None`); `tol` is the per-channel tolerance
/// used for [`ImageDiff::frac_over`].
pub fn image_difference(a: &image::RgbaImage, b: &image::RgbaImage, tol: u8) -> Option<ImageDiff> {
    if a.dimensions() != b.dimensions() || a.width() == 0 || a.height() == 0 {
        return None;
    }
    let (mut sum, mut max, mut over) = (0u64, 0u8, 0usize);
    for (p, q) in a.pixels().zip(b.pixels()) {
        let m = (0..3).map(|c| p.0[c].abs_diff(q.0[c])).max().unwrap_or(0);
        sum += (0..3).map(|c| p.0[c].abs_diff(q.0[c]) as u64).sum::<u64>();
        max = max.max(m);
        over += usize::from(m > tol);
    }
    let n = (a.width() * a.height()) as f64;
    Some(ImageDiff {
        mean_abs: sum as f64 / (3.0 * n),
        max_abs: max,
        frac_over: over as f64 / n,
    })
}

/// Nearest-rank percentile (`q` in [0, 1]) of `v`; NaN if empty.
pub fn percentile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let rank = ((q.clamp(0.0, 1.0) * s.len() as f64).ceil() as usize).clamp(1, s.len());
    s[rank - 1]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{CameraModel, rotation_look_at};

    fn cam() -> RenderCamera {
        let pos = DVec3::new(500_000.0, 7_000_000.0, 100.0);
        let r = rotation_look_at(pos, pos + DVec3::new(0.0, 1.0, -0.4)).unwrap();
        RenderCamera::new(CameraModel::with_fov(pos, r, 96, 64, 1.0), 1.0)
    }

    /// Depth buffer of the horizontal plane z = height (camera-relative), ray-traced.
    fn plane_depth(cam: &RenderCamera, height: f64) -> Vec<f32> {
        let m = &cam.model;
        let mut out = Vec::new();
        for v in 0..m.height {
            for u in 0..m.width {
                let dir_cam = DVec3::new((u as f64 - m.cx) / m.fx, (v as f64 - m.cy) / m.fy, 1.0);
                let dir = m.world_to_camera.transpose() * dir_cam;
                let t = height / dir.z;
                out.push(if t > 0.0 { (cam.near / t) as f32 } else { 0.0 });
            }
        }
        out
    }

    #[test]
    fn identical_surfaces_do_not_move() {
        let c = cam();
        let d = plane_depth(&c, -50.0);
        let r = surface_displacement(&c, &d, &d, 4, 0);
        assert!(r.measured > 0 && r.unmatched == 0);
        assert!(r.max_px < 1e-3, "{r:?}");
    }

    #[test]
    fn a_raised_plane_moves_by_its_projected_offset() {
        let c = cam();
        let (a, b) = (plane_depth(&c, -50.0), plane_depth(&c, -49.0));
        let r = surface_displacement(&c, &a, &b, 12, 0);
        // A 1 m vertical offset seen from ≥ ~50 m moves points by about fy · 1 m · cos / d:
        // the largest displacement is at the nearest visible ground (bottom rows).
        let m = &c.model;
        let want_max = (0..m.width)
            .map(|u| {
                let x = c
                    .unproject_relative(
                        u as f64,
                        (m.height - 1) as f64,
                        a[((m.height - 1) * m.width + u) as usize],
                    )
                    .unwrap();
                let foot = x + DVec3::Z; // nearest point of the raised plane
                let s = c.project_relative(foot).unwrap();
                (s[0] - u as f64).hypot(s[1] - (m.height - 1) as f64)
            })
            .fold(0.0, f64::max);
        assert!(r.unmatched == 0, "{r:?}");
        assert!(
            r.max_px > 0.5 * want_max && r.max_px < want_max + 0.75,
            "{r:?} vs {want_max}"
        );
        assert!(r.mean_px > 0.1, "{r:?}");
    }

    #[test]
    fn image_difference_counts_pixels_over_tolerance() {
        let a = image::RgbaImage::from_pixel(4, 4, image::Rgba([10, 10, 10, 255]));
        let mut b = a.clone();
        b.put_pixel(0, 0, image::Rgba([30, 10, 10, 255]));
        let d = image_difference(&a, &b, 5).unwrap();
        assert_eq!(d.max_abs, 20);
        assert!((d.frac_over - 1.0 / 16.0).abs() < 1e-12);
        assert!(image_difference(&a, &image::RgbaImage::new(3, 4), 5).is_none());
    }
}
