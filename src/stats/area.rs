//! Surface areas and slopes of TINs and of the full-resolution DEM surface.

use rayon::prelude::*;

use crate::cells::{SampleRect, Tin};
use crate::dem::Dem;

/// 3D area of the triangle `a, b, c` (same units as the coordinates, squared).
#[inline]
pub fn triangle_area_3d(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let n = cross(a, b, c);
    0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

/// Unnormalised normal `(b - a) x (c - a)`.
#[inline]
pub(crate) fn cross(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> [f64; 3] {
    let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
    [
        u[1] * v[2] - u[2] * v[1],
        u[2] * v[0] - u[0] * v[2],
        u[0] * v[1] - u[1] * v[0],
    ]
}

/// Slope in degrees of a triangle with unnormalised normal `n` (0 = horizontal).
#[inline]
pub(crate) fn slope_deg(n: [f64; 3]) -> f64 {
    (n[0] * n[0] + n[1] * n[1])
        .sqrt()
        .atan2(n[2].abs())
        .to_degrees()
}

/// Cell-local position of DEM sample `(col, row)`: metres east and north of sample
/// `(c0, r0)`, height from the DEM.
#[inline]
pub(crate) fn local_position(dem: &Dem, c0: u32, r0: u32, col: u32, row: u32) -> [f64; 3] {
    let g = &dem.georef;
    [
        (col as f64 - c0 as f64) * g.spacing_x,
        (r0 as f64 - row as f64) * g.spacing_y,
        dem.at(row as usize, col as usize) as f64,
    ]
}

/// 3D area (world units²) of the TIN's triangles: x/y from the DEM georeference, heights from
/// the DEM. Panics if a vertex lies outside the DEM or a triangle names a missing vertex
/// (TINs are built by cliffmap and validated when loaded).
pub fn tin_surface_area(dem: &Dem, tin: &Tin) -> f64 {
    let (c0, r0) = tin
        .vertices
        .iter()
        .fold((u32::MAX, u32::MAX), |(c, r), v| (c.min(v[0]), r.min(v[1])));
    let p: Vec<[f64; 3]> = tin
        .vertices
        .iter()
        .map(|v| local_position(dem, c0, r0, v[0], v[1]))
        .collect();
    tin.triangles
        .iter()
        .map(|t| triangle_area_3d(p[t[0] as usize], p[t[1] as usize], p[t[2] as usize]))
        .sum()
}

/// Area and slope of the full-resolution DEM surface over a sample rectangle, triangulated
/// with two triangles per grid quad (split along the NW–SE diagonal). Areas in world units²,
/// slopes in degrees.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DemSurface {
    /// 3D surface area.
    pub area_3d: f64,
    /// Planar (map) area of the rectangle.
    pub planar_area: f64,
    /// Slope of the steepest grid triangle.
    pub max_slope_deg: f64,
    /// Mean triangle slope weighted by 3D triangle area.
    pub mean_slope_deg: f64,
}

/// Surface area and slopes of the full-resolution DEM inside `rect` (see [`DemSurface`]).
/// Deterministic (rows are reduced in order). Panics if `rect` exceeds the DEM.
pub fn dem_surface(dem: &Dem, rect: SampleRect) -> DemSurface {
    let rows: Vec<(f64, f64, f64)> = (rect.r0..rect.r1)
        .into_par_iter()
        .map(|r| {
            let (mut area, mut slope_area, mut max_slope) = (0.0, 0.0, 0.0f64);
            for c in rect.c0..rect.c1 {
                let nw = local_position(dem, rect.c0, rect.r0, c, r);
                let ne = local_position(dem, rect.c0, rect.r0, c + 1, r);
                let sw = local_position(dem, rect.c0, rect.r0, c, r + 1);
                let se = local_position(dem, rect.c0, rect.r0, c + 1, r + 1);
                for n in [cross(nw, sw, se), cross(nw, se, ne)] {
                    let a = 0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                    let s = slope_deg(n);
                    area += a;
                    slope_area += s * a;
                    max_slope = max_slope.max(s);
                }
            }
            (area, slope_area, max_slope)
        })
        .collect();
    let (mut area, mut slope_area, mut max_slope) = (0.0, 0.0, 0.0f64);
    for (a, s, m) in rows {
        area += a;
        slope_area += s;
        max_slope = max_slope.max(m);
    }
    let g = &dem.georef;
    DemSurface {
        area_3d: area,
        planar_area: (rect.c1 - rect.c0) as f64
            * g.spacing_x
            * (rect.r1 - rect.r0) as f64
            * g.spacing_y,
        max_slope_deg: max_slope,
        mean_slope_deg: if area > 0.0 { slope_area / area } else { 0.0 },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::georef::GridGeoref;

    #[test]
    fn triangle_area_and_slope() {
        let a = triangle_area_3d([0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [0.0, 4.0, 0.0]);
        assert_eq!(a, 6.0);
        // a 45° ramp rising to the east
        let n = cross([0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 0.0]);
        assert!((slope_deg(n) - 45.0).abs() < 1e-12);
        assert!(
            (triangle_area_3d([0.0, 0.0, 0.0], [1.0, 0.0, 1.0], [0.0, 1.0, 0.0])
                - 0.5 * 2f64.sqrt())
            .abs()
                < 1e-15
        );
    }

    #[test]
    fn dem_surface_of_a_tilted_plane() {
        // h = 0.5 x + 0.25 y (exact in f32), spacings 2 x 3
        let g = GridGeoref {
            origin_x: 0.0,
            origin_y: 0.0,
            spacing_x: 2.0,
            spacing_y: 3.0,
        };
        let (w, h) = (20usize, 15usize);
        let z: Vec<f32> = (0..w * h)
            .map(|k| (0.5 * 2.0 * (k % w) as f64 - 0.25 * 3.0 * (k / w) as f64) as f32)
            .collect();
        let dem = Dem::from_heights(w, h, z, g).unwrap();
        let rect = SampleRect {
            c0: 3,
            r0: 2,
            c1: 17,
            r1: 11,
        };
        let s = dem_surface(&dem, rect);
        let planar = 14.0 * 2.0 * 9.0 * 3.0;
        let k = (1.0f64 + 0.25 + 0.0625).sqrt();
        assert_eq!(s.planar_area, planar);
        assert!(
            (s.area_3d - planar * k).abs() < 1e-9 * planar,
            "{} vs {}",
            s.area_3d,
            planar * k
        );
        let slope = (1.0 / k).acos().to_degrees();
        assert!(
            (s.max_slope_deg - slope).abs() < 1e-9 && (s.mean_slope_deg - slope).abs() < 1e-9,
            "{s:?}"
        );
    }
}
