//! Projection onto the relief surface: where a photo's ray meets the DEM surface (a cell's
//! TIN plus its relief map, [`crate::cells::relief`]) near where it meets the TIN, in the
//! cell's texture. The renderer looks orthographic textures up the same way
//! (`shaders/terrain.wgsl`, `relief_uv`), so a texel holds the colour of the DEM point that
//! both the photo and the view see at that (x, y).

use glam::Vec3;

/// A cell's relief map, decoded, in the texel grid of its orthographic texture.
#[derive(Clone, Debug, PartialEq)]
pub struct CellRelief {
    /// Side of the map in texels (= the cell's orthographic texture side).
    pub side: u32,
    /// Heights of the DEM surface above the TIN at the texel centres, metres, row-major.
    pub heights: Vec<f32>,
    /// Largest absolute height, metres (> 0).
    pub range: f32,
    /// Texture position change per metre of world x and of world y (u east, v south:
    /// `[side / width, −side / height]`).
    pub texels_per_m: [f32; 2],
}

/// Longest search along a ray, in texels of the map (the renderer's cap: beyond it the
/// triangle's plane no longer stands for the TIN).
const MAX_SPAN: f32 = 48.0;

impl CellRelief {
    /// From a stored relief map of the cell whose nominal square is `width × height` metres;
    /// `None` for a map of range 0 or a degenerate square.
    pub fn new(map: &crate::cells::ReliefMap, width: f64, height: f64) -> Option<CellRelief> {
        let side = map.image.width();
        if map.range_m <= 0.0 || side == 0 || map.image.height() != side {
            return None;
        }
        if !(width > 0.0 && height > 0.0 && width.is_finite() && height.is_finite()) {
            return None;
        }
        let heights = map
            .image
            .pixels()
            .map(|p| crate::cells::relief::decode(p.0[0], map.range_m) as f32)
            .collect();
        Some(CellRelief {
            side,
            heights,
            range: map.range_m as f32,
            texels_per_m: [(side as f64 / width) as f32, -(side as f64 / height) as f32],
        })
    }

    /// Height at texture position `tex` (texel units of the map), bilinear between texel
    /// centres, clamped to the map.
    fn height(&self, tex: [f32; 2]) -> f32 {
        let n = self.side as usize;
        let hi = (self.side - 1) as f32;
        let x = (tex[0] - 0.5).clamp(0.0, hi);
        let y = (tex[1] - 0.5).clamp(0.0, hi);
        let (x0, y0) = (x.floor() as usize, y.floor() as usize);
        let (x1, y1) = ((x0 + 1).min(n - 1), (y0 + 1).min(n - 1));
        let (fx, fy) = (x - x0 as f32, y - y0 as f32);
        let h = |i: usize, j: usize| self.heights[j * n + i];
        let top = h(x0, y0) + (h(x1, y0) - h(x0, y0)) * fx;
        let bot = h(x0, y1) + (h(x1, y1) - h(x0, y1)) * fx;
        top + (bot - top) * fy
    }

    /// The texture position (texel units of the map) where the ray along unit `dir` through
    /// the TIN point at `tex`, on a triangle of unit normal `normal` (facing the ray), meets
    /// "the triangle's plane + relief": searched between the ray's heights +range and −range
    /// above the plane, at most 8 steps of about 4 texels, then two false-position steps (as
    /// the renderer). Steep triangles (normal more than 75.5° from up), rays along the plane,
    /// searches shorter than 0.02 texel or longer than 48 texels return `tex`.
    pub fn project(&self, tex: [f32; 2], dir: Vec3, normal: [f32; 3]) -> [f32; 2] {
        if normal[2] < 0.25 {
            return tex;
        }
        let k = (dir.x * normal[0] + dir.y * normal[1] + dir.z * normal[2]) / normal[2];
        // NaN (a degenerate direction) fails this test too
        if k.is_nan() || k >= -1e-4 {
            return tex;
        }
        let (s0, s1) = (self.range / k, -self.range / k);
        let du = [dir.x * self.texels_per_m[0], dir.y * self.texels_per_m[1]];
        let span = (s1 - s0).abs() * (du[0] * du[0] + du[1] * du[1]).sqrt();
        if !(0.02..=MAX_SPAN).contains(&span) {
            return tex;
        }
        let at = |s: f32| [tex[0] + s * du[0], tex[1] + s * du[1]];
        let f = |s: f32| s * k - self.height(at(s));
        let steps = (span / 4.0).ceil().clamp(1.0, 8.0) as u32;
        let (mut a, mut fa, mut b, mut fb) = (s0, 0.0f32, s1, -1.0f32);
        for j in 0..=steps {
            let s = s0 + (s1 - s0) * (j as f32 / steps as f32);
            let v = f(s);
            if v <= 0.0 {
                b = s;
                fb = v;
                break;
            }
            a = s;
            fa = v;
        }
        let mut hit = b;
        if fa > 0.0 {
            for _ in 0..2 {
                let s = a + (b - a) * fa / (fa - fb).max(1e-12);
                let v = f(s);
                if v > 0.0 {
                    a = s;
                    fa = v;
                } else {
                    b = s;
                    fb = v;
                }
            }
            hit = a + (b - a) * fa / (fa - fb).max(1e-12);
        }
        at(hit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constant(side: u32, v: u8, range: f64, size_m: f64) -> CellRelief {
        let map = crate::cells::ReliefMap {
            image: image::GrayImage::from_pixel(side, side, image::Luma([v])),
            range_m: range,
        };
        CellRelief::new(&map, size_m, size_m).expect("relief")
    }

    #[test]
    fn a_constant_relief_moves_the_hit_to_the_raised_plane() {
        // 64 texels over 100 m, the DEM r above a flat TIN
        let rel = constant(64, 223, 8.0, 100.0);
        let r = (223.0 / 255.0 * 2.0 - 1.0) * 8.0f32;
        let dir = Vec3::new(0.6, 0.3, -0.74).normalize();
        let tex = [30.0, 20.0];
        let got = rel.project(tex, dir, [0.0, 0.0, 1.0]);
        // the ray meets z = r at s = r / dir.z (s < 0: before the TIN point)
        let s = r / dir.z;
        let want = [tex[0] + s * dir.x * 0.64, tex[1] - s * dir.y * 0.64];
        assert!(
            (got[0] - want[0]).abs() < 1e-3 && (got[1] - want[1]).abs() < 1e-3,
            "{got:?} vs {want:?}"
        );
        // steep triangles and no relief leave the hit alone
        assert_eq!(rel.project(tex, dir, [0.99, 0.0, 0.14]), tex);
        let map = crate::cells::ReliefMap {
            image: image::GrayImage::from_pixel(8, 8, image::Luma([128])),
            range_m: 0.0,
        };
        assert!(CellRelief::new(&map, 10.0, 10.0).is_none());
    }

    #[test]
    fn the_first_crossing_of_a_bump_is_found() {
        // a 1-m ridge along v at u = 40 (texels), on a flat TIN; a ray descending eastwards
        let side = 64u32;
        let range = 1.0f64;
        let img = image::GrayImage::from_fn(side, side, |i, _| {
            let h = (-((i as f64 + 0.5 - 40.0) / 3.0).powi(2)).exp();
            image::Luma([((h / range * 0.5 + 0.5) * 255.0).round() as u8])
        });
        let rel = CellRelief::new(
            &crate::cells::ReliefMap {
                image: img,
                range_m: range,
            },
            64.0,
            64.0,
        )
        .expect("relief");
        // the TIN point lies behind the ridge (u = 44); the ray comes from the west, low
        let dir = Vec3::new(1.0, 0.0, -0.08).normalize();
        let got = rel.project([44.0, 32.0], dir, [0.0, 0.0, 1.0]);
        // it must stop on the ridge's west flank, before its crest at u = 40 + ... (height 1 m
        // there), not at the TIN point
        assert!(got[0] < 41.5 && got[0] > 33.0, "{got:?}");
        assert!((got[1] - 32.0).abs() < 1e-4);
    }
}
