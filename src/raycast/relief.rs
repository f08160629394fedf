//! Projection onto the relief surface: where a photo's ray meets the DEM surface (a cell's
//! TIN plus its relief map, [`crate::cells::relief`]) near where it meets the TIN, in the
//! cell's texture. The renderer looks textures up the same way (`shaders/terrain.wgsl`,
//! `relief_shift`), so a texel holds the colour of the DEM point that both the photo and the
//! view see there.
//!
//! The search runs in the relief map's own grid; the hit's move in (x, y) is then carried
//! into the texture through the hit triangle's affine map from (x, y) to texels, so photo
//! textures of any size (photo-driven sizes) get it. Only cells drawn with orthographic
//! texture coordinates are projected so ([`super::LevelScene::load_reliefs`]).

use glam::Vec3;

/// A cell's relief map, decoded, over the cell's nominal square.
#[derive(Clone, Debug, PartialEq)]
pub struct CellRelief {
    /// Side of the map in texels.
    pub side: u32,
    /// Heights of the DEM surface above the TIN at the texel centres, metres, row-major.
    pub heights: Vec<f32>,
    /// Largest absolute height, metres (> 0).
    pub range: f32,
    /// Map position change per metre of world x and of world y (u east, v south:
    /// `[side / width, −side / height]`).
    pub texels_per_m: [f32; 2],
    /// Cell-local (x, y) of the nominal square's north-west corner (map position (0, 0)).
    pub corner: [f32; 2],
    /// Triangles whose unit normal's up component is below this are left out
    /// ([`crate::cells::relief::ORTHO_MIN_NORMAL_Z`] or `CHART_MIN_NORMAL_Z`).
    pub min_normal_z: f32,
}

/// Longest search along a ray, in texels of the map (as the renderer).
const MAX_SPAN: f32 = crate::cells::relief::MAX_SEARCH_TEXELS;

impl CellRelief {
    /// From a stored relief map of the cell whose nominal square has its north-west corner at
    /// cell-local `corner` and measures `width × height` metres, relief-mapping triangles
    /// whose normal's up component is at least `min_normal_z`; `None` for a map of range 0 or
    /// a degenerate square.
    pub fn new(
        map: &crate::cells::ReliefMap,
        corner: [f64; 2],
        width: f64,
        height: f64,
        min_normal_z: f32,
    ) -> Option<CellRelief> {
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
            corner: [corner[0] as f32, corner[1] as f32],
            min_normal_z,
        })
    }

    /// Height at map position `tex` (texel units), bilinear between texel centres, clamped
    /// to the map.
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

    /// How far, in cell-local (x, y) metres, the point where the ray along unit `dir` meets
    /// "the triangle's plane + relief" lies from the TIN point `xy` the ray hit, on a
    /// triangle of unit normal `normal` (facing the ray): searched between the ray's heights
    /// +range and −range above the plane, at most 8 steps of about 4 map texels, then two
    /// false-position steps (as the renderer). Steep triangles (up component below
    /// `min_normal_z`), rays along the plane, searches shorter than 0.02 texel or longer
    /// than 48 texels give `[0, 0]`.
    pub fn shift(&self, xy: [f32; 2], dir: Vec3, normal: [f32; 3]) -> [f32; 2] {
        const NONE: [f32; 2] = [0.0, 0.0];
        if !(normal[2] >= self.min_normal_z) {
            return NONE;
        }
        let k = (dir.x * normal[0] + dir.y * normal[1] + dir.z * normal[2]) / normal[2];
        // NaN (a degenerate direction) fails this test too
        if k.is_nan() || k >= -1e-4 {
            return NONE;
        }
        let (s0, s1) = (self.range / k, -self.range / k);
        let du = [dir.x * self.texels_per_m[0], dir.y * self.texels_per_m[1]];
        let span = (s1 - s0).abs() * (du[0] * du[0] + du[1] * du[1]).sqrt();
        if !(0.02..=MAX_SPAN).contains(&span) {
            return NONE;
        }
        let tex = [
            (xy[0] - self.corner[0]) * self.texels_per_m[0],
            (xy[1] - self.corner[1]) * self.texels_per_m[1],
        ];
        let f = |s: f32| s * k - self.height([tex[0] + s * du[0], tex[1] + s * du[1]]);
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
        [hit * dir.x, hit * dir.y]
    }
}

/// The texel move of a move `d` in cell-local (x, y) metres on the triangle with cell-local
/// vertices `p` and texel positions `t`: its affine map from (x, y) to texels, extended
/// beyond the triangle. `None` for a triangle degenerate in (x, y) (vertical).
pub(crate) fn texel_shift(p: [[f32; 3]; 3], t: [[f32; 2]; 3], d: [f32; 2]) -> Option<[f32; 2]> {
    let (e1, e2) = (
        [p[1][0] - p[0][0], p[1][1] - p[0][1]],
        [p[2][0] - p[0][0], p[2][1] - p[0][1]],
    );
    let det = e1[0] * e2[1] - e2[0] * e1[1];
    let scale = (e1[0] * e1[0] + e1[1] * e1[1]).max(e2[0] * e2[0] + e2[1] * e2[1]);
    if !(det.abs() > 1e-6 * scale) {
        return None;
    }
    // d in the triangle's edge basis: d = a·e1 + b·e2
    let a = (d[0] * e2[1] - e2[0] * d[1]) / det;
    let b = (e1[0] * d[1] - d[0] * e1[1]) / det;
    Some([
        a * (t[1][0] - t[0][0]) + b * (t[2][0] - t[0][0]),
        a * (t[1][1] - t[0][1]) + b * (t[2][1] - t[0][1]),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A map over a square of `size_m` whose north-west corner is at cell-local (0, size_m).
    fn relief(img: image::GrayImage, range: f64, size_m: f64) -> CellRelief {
        let map = crate::cells::ReliefMap {
            image: img,
            range_m: range,
        };
        CellRelief::new(&map, [0.0, size_m], size_m, size_m, 0.25).expect("relief")
    }

    #[test]
    fn a_constant_relief_moves_the_hit_to_the_raised_plane() {
        // 64 texels over 100 m, the DEM r above a flat TIN
        let rel = relief(
            image::GrayImage::from_pixel(64, 64, image::Luma([223])),
            8.0,
            100.0,
        );
        let r = (223.0 / 255.0 * 2.0 - 1.0) * 8.0f32;
        let dir = Vec3::new(0.6, 0.3, -0.74).normalize();
        let xy = [30.0, 70.0];
        let got = rel.shift(xy, dir, [0.0, 0.0, 1.0]);
        // the ray meets z = r at s = r / dir.z (s < 0: before the TIN point)
        let s = r / dir.z;
        let want = [s * dir.x, s * dir.y];
        assert!(
            (got[0] - want[0]).abs() < 1e-3 && (got[1] - want[1]).abs() < 1e-3,
            "{got:?} vs {want:?}"
        );
        // steep triangles leave the hit alone; the chart limit leaves out 60° too
        assert_eq!(rel.shift(xy, dir, [0.99, 0.0, 0.14]), [0.0, 0.0]);
        let chart = CellRelief {
            min_normal_z: crate::cells::relief::CHART_MIN_NORMAL_Z,
            ..rel.clone()
        };
        let n60 = [-60f32.to_radians().sin(), 0.0, 60f32.to_radians().cos()];
        assert_eq!(chart.shift(xy, dir, n60), [0.0, 0.0]);
        assert_ne!(rel.shift(xy, dir, n60), [0.0, 0.0]);
        // no relief: no map
        let map = crate::cells::ReliefMap {
            image: image::GrayImage::from_pixel(8, 8, image::Luma([128])),
            range_m: 0.0,
        };
        assert!(CellRelief::new(&map, [0.0, 10.0], 10.0, 10.0, 0.25).is_none());
    }

    #[test]
    fn the_first_crossing_of_a_bump_is_found() {
        // a 1-m ridge along y at map u = 40 (x = 40 m), on a flat TIN; a ray descending
        // eastwards
        let side = 64u32;
        let range = 1.0f64;
        let img = image::GrayImage::from_fn(side, side, |i, _| {
            let h = (-((i as f64 + 0.5 - 40.0) / 3.0).powi(2)).exp();
            image::Luma([((h / range * 0.5 + 0.5) * 255.0).round() as u8])
        });
        let rel = relief(img, range, 64.0);
        // the TIN point lies behind the ridge (x = 44); the ray comes from the west, low
        let dir = Vec3::new(1.0, 0.0, -0.08).normalize();
        let d = rel.shift([44.0, 32.0], dir, [0.0, 0.0, 1.0]);
        // it must stop on the ridge's west flank, before its crest at x = 40 (height 1 m
        // there), not at the TIN point
        assert!(44.0 + d[0] < 41.5 && 44.0 + d[0] > 33.0, "{d:?}");
        assert!(d[1].abs() < 1e-4);
    }

    #[test]
    fn texel_shifts_follow_the_triangles_map() {
        // a triangle whose texels are a rotation by 90° and a scale of 2 of its (x, y)
        let p = [[0.0, 0.0, 5.0], [1.0, 0.0, 5.5], [0.0, 1.0, 4.0]];
        let t = [[10.0, 10.0], [10.0, 12.0], [8.0, 10.0]];
        let got = texel_shift(p, t, [0.5, -0.25]).expect("shift");
        assert!(
            (got[0] - 0.5).abs() < 1e-6 && (got[1] - 1.0).abs() < 1e-6,
            "{got:?}"
        );
        // a vertical triangle has no map
        let v = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [2.0, 0.0, 3.0]];
        assert!(texel_shift(v, t, [0.5, 0.5]).is_none());
    }
}
