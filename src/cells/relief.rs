//! Per-cell relief maps: how far the full-resolution DEM surface lies above the cell's TIN.
//!
//! Texel layout as for [`normal_map`](crate::cells::normal_map): `T x T` texels over the
//! cell's nominal square, row 0 north, each texel's value taken at its centre. The value is
//! `h_dem(x, y) − h_tin(x, y)` in world units, where `h_dem` is the DEM's full-resolution
//! grid surface (two triangles per quad of samples, split north-west to south-east, as
//! [`crate::demo_scene::DemTracer`] casts it) and `h_tin` the cell's TIN surface (its mesh's surface
//! triangles; skirts excluded). Texels the TIN does not cover (beyond a clipped cell's data)
//! get 0. The renderer uses the map to find where a view ray meets the DEM surface near
//! where it meets the TIN (relief mapping), so textures of flat ground are looked up at the
//! right place although the TIN is up to its error bound off.
//!
//! Encoding: 8-bit grey, `v = round((r / range · 0.5 + 0.5) · 255)` with `range` the largest
//! `|r|` of the map but at most a given limit (so `r = (v / 255 · 2 − 1) · range`, a step of
//! `range / 127.5`; heights beyond ±range saturate). The build passes twice the cell's measured
//! TIN error: that is what the TIN misses on ground; on a near-vertical wall the DEM's own
//! quads and the TIN's triangles can split a quad along different diagonals, and the heights
//! there reach tens of metres between samples, which would waste the map's 8 bits (and the
//! renderer skips steep triangles anyway).

use image::GrayImage;

use crate::cells::CellMesh;
use crate::dem::Dem;
use crate::georef::WorldRect;

/// Ranges below this (metres) are stored as 0: the f32 rounding of cell-local positions.
pub const MIN_RANGE_M: f64 = 1e-3;

/// Relief mapping leaves out triangles whose unit normal has a smaller up component than
/// this where the texture is in the orthographic layout (slopes over 75.5°): the map samples
/// a wall too coarsely in (x, y). Used alike by the renderer and the photo projection.
pub const ORTHO_MIN_NORMAL_Z: f32 = 0.25;

/// The same limit where the texture is a reparameterized chart: slopes over 45° are left
/// out. Charts give walls their texels, and a wall's relief, sampled on the orthographic
/// grid and capped at twice the TIN error, moved wall lookups away from the photos' colour
/// (docs/rendering.md); gentler ground gains as orthographic cells do.
pub const CHART_MIN_NORMAL_Z: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// Longest relief search along a ray, in texels of the relief map (the renderer's and the
/// projection's cap: beyond it the drawn triangle's plane no longer stands for the TIN).
pub const MAX_SEARCH_TEXELS: f32 = 48.0;

/// The longest (x, y) move a relief search can give on a map of `side` texels over a nominal
/// square `width` metres wide, metres (the cap of [`crate::cells::relief_reach()`]).
pub fn max_shift_m(width: f64, side: u32) -> f32 {
    (MAX_SEARCH_TEXELS as f64 * width / side.max(1) as f64) as f32
}

/// A cell's relief map and its scale (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct ReliefMap {
    /// `T x T` encoded heights of the DEM above the TIN, row 0 north.
    pub image: GrayImage,
    /// Largest `|h_dem − h_tin|` over the texel centres, world units (0: the TIN is within
    /// [`MIN_RANGE_M`] at every centre, and every texel encodes 0 as 128).
    pub range_m: f64,
}

impl ReliefMap {
    /// The decoded height of the DEM above the TIN at texel `(i, j)`, world units.
    pub fn height(&self, i: u32, j: u32) -> f64 {
        decode(self.image.get_pixel(i, j).0[0], self.range_m)
    }
}

/// The height encoded by 8-bit value `v` in a map of range `range_m`.
pub fn decode(v: u8, range_m: f64) -> f64 {
    (v as f64 / 255.0 * 2.0 - 1.0) * range_m
}

/// Height of the DEM's full-resolution grid surface at fractional grid position
/// `(row, col)`, clamped to the grid: the two triangles per quad of samples that
/// [`crate::demo_scene::DemTracer`] casts against (the quad split from (r, c) to (r+1, c+1)).
pub fn grid_surface_height(dem: &Dem, row: f64, col: f64) -> f64 {
    let ([h00, h01, h10, h11], fr, fc) = dem.quad_at(row, col);
    if fr >= fc {
        h00 + fr * (h10 - h00) + fc * (h11 - h10)
    } else {
        h00 + fc * (h01 - h00) + fr * (h11 - h01)
    }
}

/// The `texels x texels` relief map of the cell whose surface is `mesh` (cell-local
/// positions relative to the world point `origin`) over the world rectangle `extent`, as
/// defined in the [module docs](self), its range at most `limit_m` (heights beyond saturate).
/// Deterministic. A degenerate `extent`, `texels == 0` or a `limit_m` that is not positive
/// gives an all-zero map of range 0.
pub fn relief_map(
    dem: &Dem,
    extent: WorldRect,
    texels: u32,
    mesh: &CellMesh,
    origin: [f64; 3],
    limit_m: f64,
) -> ReliefMap {
    let t = texels as usize;
    let mut heights = vec![f64::NAN; t * t];
    let valid = t > 0
        && extent.width() > 0.0
        && extent.height() > 0.0
        && extent.width().is_finite()
        && extent.height().is_finite();
    if valid {
        let (dx, dy) = (extent.width() / t as f64, extent.height() / t as f64);
        // texel centre (i, j) in cell-local coordinates
        let lx = |i: f64| extent.min_x + dx * (i + 0.5) - origin[0];
        let ly = |j: f64| extent.max_y - dy * (j + 0.5) - origin[1];
        let p = |k: u32| {
            let q = mesh.positions[k as usize];
            [q[0] as f64, q[1] as f64, q[2] as f64]
        };
        for tri in mesh.surface() {
            if tri.iter().any(|&k| k as usize >= mesh.positions.len()) {
                continue;
            }
            let [a, b, c] = [p(tri[0]), p(tri[1]), p(tri[2])];
            let det = (b[0] - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (b[1] - a[1]);
            if det.abs() < 1e-12 {
                continue;
            }
            let (x0, x1) = (a[0].min(b[0]).min(c[0]), a[0].max(b[0]).max(c[0]));
            let (y0, y1) = (a[1].min(b[1]).min(c[1]), a[1].max(b[1]).max(c[1]));
            // texel index ranges whose centres may lie in the box
            let ix = |x: f64| (x + origin[0] - extent.min_x) / dx - 0.5;
            let jy = |y: f64| (extent.max_y - (y + origin[1])) / dy - 0.5;
            let i0 = ix(x0).ceil().max(0.0) as usize;
            let i1 = (ix(x1).floor() + 1.0).clamp(0.0, t as f64) as usize;
            let j0 = jy(y1).ceil().max(0.0) as usize;
            let j1 = (jy(y0).floor() + 1.0).clamp(0.0, t as f64) as usize;
            for j in j0..j1 {
                let y = ly(j as f64);
                for i in i0..i1 {
                    if !heights[j * t + i].is_nan() {
                        continue;
                    }
                    let x = lx(i as f64);
                    let wb = ((x - a[0]) * (c[1] - a[1]) - (c[0] - a[0]) * (y - a[1])) / det;
                    let wc = ((b[0] - a[0]) * (y - a[1]) - (x - a[0]) * (b[1] - a[1])) / det;
                    let wa = 1.0 - wb - wc;
                    const TOL: f64 = -1e-9;
                    if wa < TOL || wb < TOL || wc < TOL {
                        continue;
                    }
                    let z_tin = wa * a[2] + wb * b[2] + wc * c[2] + origin[2];
                    let (row, col) = dem.georef.grid(x + origin[0], y + origin[1]);
                    heights[j * t + i] = grid_surface_height(dem, row, col) - z_tin;
                }
            }
        }
    }
    let limit = if limit_m > 0.0 { limit_m } else { 0.0 };
    let range_m = heights
        .iter()
        .filter(|h| h.is_finite())
        .fold(0.0f64, |m, h| m.max(h.abs()))
        .min(limit);
    // below a millimetre it is the mesh's f32 rounding, not relief
    let range_m = if range_m < MIN_RANGE_M { 0.0 } else { range_m };
    let image = GrayImage::from_fn(texels, texels, |i, j| {
        let h = heights[j as usize * t + i as usize];
        let r = if h.is_finite() && range_m > 0.0 {
            (h / range_m).clamp(-1.0, 1.0)
        } else {
            0.0
        };
        image::Luma([((r * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8])
    });
    ReliefMap { image, range_m }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::georef::GridGeoref;

    fn dem(f: impl Fn(f64, f64) -> f64, n: usize) -> Dem {
        let g = GridGeoref {
            origin_x: 1000.0,
            origin_y: 2000.0,
            spacing_x: 2.0,
            spacing_y: 2.0,
        };
        let heights = (0..n * n)
            .map(|k| {
                let (x, y) = g.world((k / n) as f64, (k % n) as f64);
                f(x, y) as f32
            })
            .collect();
        Dem::from_heights(n, n, heights, g).expect("dem")
    }

    /// Two triangles over the square [x0, x1] × [y0, y1] (world), heights from `h`, in the
    /// frame of `origin`.
    fn square_mesh(ext: WorldRect, origin: [f64; 3], h: impl Fn(f64, f64) -> f64) -> CellMesh {
        let corners = [
            (ext.min_x, ext.max_y),
            (ext.max_x, ext.max_y),
            (ext.max_x, ext.min_y),
            (ext.min_x, ext.min_y),
        ];
        let positions = corners
            .iter()
            .map(|&(x, y)| {
                [
                    (x - origin[0]) as f32,
                    (y - origin[1]) as f32,
                    (h(x, y) - origin[2]) as f32,
                ]
            })
            .collect();
        CellMesh {
            positions,
            uvs: None,
            triangles: vec![[0, 3, 2], [0, 2, 1]],
            surface_vertices: 4,
            surface_triangles: 2,
        }
    }

    /// The 64-m square both map tests cover.
    fn square() -> WorldRect {
        WorldRect {
            min_x: 1000.0,
            min_y: 1936.0,
            max_x: 1064.0,
            max_y: 2000.0,
        }
    }

    #[test]
    fn a_plane_on_its_own_tin_has_no_relief() {
        let plane = |x: f64, y: f64| 100.0 + 0.3 * (x - 1000.0) - 0.2 * (y - 2000.0);
        let d = dem(plane, 33);
        let ext = square();
        let origin = [1032.0, 1968.0, 95.0];
        let m = relief_map(&d, ext, 16, &square_mesh(ext, origin, plane), origin, 1.0);
        assert_eq!(m.range_m, 0.0);
        assert!(m.image.pixels().all(|p| p.0[0] == 128));
    }

    #[test]
    fn a_bump_over_a_flat_tin_is_measured_at_texel_centres() {
        // DEM: a ridge along y, 3 m high; TIN: the flat plane z = 50 (misses the ridge)
        let ridge = |x: f64, _y: f64| 50.0 + 3.0 * (-((x - 1032.0) / 8.0).powi(2)).exp();
        let d = dem(ridge, 33);
        let ext = square();
        let origin = [1032.0, 1968.0, 50.0];
        let flat = square_mesh(ext, origin, |_, _| 50.0);
        // a limit below the bump saturates it
        let low = relief_map(&d, ext, 32, &flat, origin, 1.0);
        assert_eq!(low.range_m, 1.0);
        assert!((low.height(16, 16) - 1.0).abs() < 1e-9);
        let m = relief_map(&d, ext, 32, &flat, origin, 10.0);
        assert!((m.range_m - 3.0).abs() < 0.1, "range {}", m.range_m);
        for j in 0..32 {
            for i in 0..32 {
                let x = 1000.0 + 2.0 * (i as f64 + 0.5);
                let y = 2000.0 - 2.0 * (j as f64 + 0.5);
                let (row, col) = d.georef.grid(x, y);
                let want = grid_surface_height(&d, row, col) - 50.0;
                let step = m.range_m / 127.5;
                assert!(
                    (m.height(i, j) - want).abs() <= 0.5 * step + 1e-6,
                    "texel {i},{j}: {} vs {want}",
                    m.height(i, j)
                );
            }
        }
    }

    #[test]
    fn grid_surface_matches_the_grid_triangles() {
        let d = dem(|x, y| (x * 0.37).sin() * 5.0 + (y * 0.11).cos() * 3.0, 9);
        // at samples the surface is the sample
        for (r, c) in [(0, 0), (3, 5), (8, 8), (7, 2)] {
            assert!((grid_surface_height(&d, r as f64, c as f64) - d.at(r, c) as f64).abs() < 1e-9);
        }
        // on the quad's diagonal both triangles agree; inside, each is linear
        let (r, c) = (2.0, 4.0);
        let mid = grid_surface_height(&d, r + 0.5, c + 0.5);
        let want = 0.5 * (d.at(2, 4) as f64 + d.at(3, 5) as f64);
        assert!((mid - want).abs() < 1e-9);
        let lower = grid_surface_height(&d, r + 0.75, c + 0.25); // (r,c) (r+1,c) (r+1,c+1)
        let want = d.at(2, 4) as f64
            + 0.75 * (d.at(3, 4) as f64 - d.at(2, 4) as f64)
            + 0.25 * (d.at(3, 5) as f64 - d.at(3, 4) as f64);
        assert!((lower - want).abs() < 1e-9);
    }
}
