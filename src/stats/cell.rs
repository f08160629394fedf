//! Statistics of one cell under the orthographic parameterization.

use crate::cells::{CellKey, Quadtree, Tin};
use crate::dem::Dem;
use crate::stats::CellStats;
use crate::stats::area::{dem_surface, local_position, triangle_area_3d};
use crate::stats::stretch::{summarize_stretch, texel_stretch};

/// Texel-stretch statistics of cell `key` with TIN `tin` and a `texels x texels` ortho
/// texture over its nominal square (definitions in [`crate::stats`]). For a key without area
/// inside the DEM, or an empty TIN, the area-derived fields are 0. Deterministic. Panics if
/// the TIN references samples outside the DEM (TINs are built by cliffmap and validated when
/// loaded).
pub fn cell_stats(dem: &Dem, tree: &Quadtree, key: CellKey, tin: &Tin, texels: u32) -> CellStats {
    let g = &dem.georef;
    let (c0, r0, n) = tree.nominal(key);
    let (side_x, side_y) = (n as f64 * g.spacing_x, n as f64 * g.spacing_y);
    let base_area = side_x * side_y;
    let Some(rect) = tree.clipped(key) else {
        return CellStats {
            base_area,
            stretch_histogram: summarize_stretch(&[]).histogram,
            ..CellStats::default()
        };
    };
    let surface = dem_surface(dem, rect);
    let clipped_area = surface.planar_area;

    // cell-local frame: origin at the nominal north-west corner sample, x east, y north
    let positions: Vec<[f64; 3]> = tin
        .vertices
        .iter()
        .map(|v| local_position(dem, c0, r0, v[0], v[1]))
        .collect();
    let surface_area_tin: f64 = tin
        .triangles
        .iter()
        .map(|t| {
            triangle_area_3d(
                positions[t[0] as usize],
                positions[t[1] as usize],
                positions[t[2] as usize],
            )
        })
        .sum();
    // orthographic parameterization: uv = planar position / nominal extent (v southwards)
    let uvs: Vec<[f64; 2]> = positions
        .iter()
        .map(|p| [p[0] / side_x, -p[1] / side_y])
        .collect();
    let stretch = summarize_stretch(&texel_stretch(
        &positions,
        &tin.triangles,
        &uvs,
        texels,
        base_area,
    ));

    let used_fraction = clipped_area / base_area;
    CellStats {
        surface_area_tin,
        surface_area_dem: surface.area_3d,
        base_area,
        clipped_area,
        used_fraction,
        rel_texel: if clipped_area > 0.0 {
            surface_area_tin / clipped_area
        } else {
            0.0
        },
        max_slope_deg: surface.max_slope_deg,
        mean_slope_deg: surface.mean_slope_deg,
        texel_stretch: stretch.percentiles,
        steep_texel_fraction: stretch.steep_fraction,
        covered_texels: stretch.covered,
        stretch_histogram: stretch.histogram,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cells::grid_tin;
    use crate::georef::GridGeoref;

    /// DEM with heights `p * x + q * y` (x east, y north of the origin sample).
    fn plane_dem(w: usize, h: usize, g: GridGeoref, p: f64, q: f64) -> Dem {
        let z = (0..w * h)
            .map(|k| (p * (k % w) as f64 * g.spacing_x - q * (k / w) as f64 * g.spacing_y) as f32)
            .collect();
        Dem::from_heights(w, h, z, g).unwrap()
    }

    #[test]
    fn flat_cell_has_rel_texel_one() {
        let g = GridGeoref {
            origin_x: 445302.17,
            origin_y: 7396769.45,
            spacing_x: 3.0,
            spacing_y: 3.0,
        };
        let dem = plane_dem(129, 129, g, 0.0, 0.0);
        let tree = Quadtree::new(129, 129, 32);
        for key in tree.all_cells() {
            let rect = tree.clipped(key).unwrap();
            for stride in [1, tree.stride(key.level)] {
                let tin = grid_tin(rect, stride);
                let s = cell_stats(&dem, &tree, key, &tin, 64);
                assert!((s.rel_texel - 1.0).abs() < 1e-9, "{key:?}: {}", s.rel_texel);
                assert!((s.surface_area_dem - s.base_area).abs() < 1e-9 * s.base_area);
                assert_eq!(s.used_fraction, 1.0);
                assert_eq!(
                    (s.max_slope_deg, s.mean_slope_deg, s.steep_texel_fraction),
                    (0.0, 0.0, 0.0)
                );
                assert_eq!(s.covered_texels, 64 * 64);
                assert!(
                    (s.texel_stretch.max - 1.0).abs() < 1e-6
                        && (s.texel_stretch.p50 - 1.0).abs() < 1e-6
                );
            }
        }
    }

    #[test]
    fn tilted_plane_has_rel_texel_inverse_cosine() {
        let g = GridGeoref {
            origin_x: 1000.0,
            origin_y: 2000.0,
            spacing_x: 2.0,
            spacing_y: 2.0,
        };
        // (dh/dx, dh/dy) pairs; exact in f32 on this grid
        for (p, q) in [(0.5, 0.0), (0.0, -1.0), (1.25, 0.75), (3.0, 2.0)] {
            let dem = plane_dem(65, 65, g, p, q);
            let tree = Quadtree::new(65, 65, 16);
            let cos_a = 1.0 / (1.0 + p * p + q * q).sqrt();
            let slope = cos_a.acos().to_degrees();
            for key in tree.all_cells() {
                let rect = tree.clipped(key).unwrap();
                let tin = grid_tin(rect, tree.stride(key.level));
                let s = cell_stats(&dem, &tree, key, &tin, 32);
                assert!(
                    (s.rel_texel - 1.0 / cos_a).abs() < 1e-6,
                    "{key:?} ({p},{q}): {}",
                    s.rel_texel
                );
                assert!((s.surface_area_dem - s.base_area / cos_a).abs() < 1e-6 * s.base_area);
                assert!((s.surface_area_tin - s.surface_area_dem).abs() < 1e-6 * s.base_area);
                assert!(
                    (s.max_slope_deg - slope).abs() < 1e-6
                        && (s.mean_slope_deg - slope).abs() < 1e-6
                );
                assert!(
                    (s.texel_stretch.p50 - 1.0 / cos_a).abs() < 1e-5
                        && (s.texel_stretch.max - 1.0 / cos_a).abs() < 1e-5
                );
                let steep = if slope > 60.0 { 1.0 } else { 0.0 };
                assert_eq!(s.steep_texel_fraction, steep, "slope {slope}");
            }
        }
    }

    #[test]
    fn clipped_edge_cell_of_flat_dem_has_rel_texel_one() {
        let g = GridGeoref::new(0.0, 0.0, 1.5);
        let dem = plane_dem(71, 45, g, 0.0, 0.0);
        let tree = Quadtree::new(71, 45, 16); // root spans 128 intervals: edge cells clipped
        let mut clipped_seen = 0;
        for key in tree.all_cells() {
            let rect = tree.clipped(key).unwrap();
            let tin = grid_tin(rect, tree.stride(key.level));
            let s = cell_stats(&dem, &tree, key, &tin, 64);
            assert!((s.rel_texel - 1.0).abs() < 1e-9, "{key:?}: {}", s.rel_texel);
            let (_, _, n) = tree.nominal(key);
            let want_used =
                (rect.c1 - rect.c0) as f64 * (rect.r1 - rect.r0) as f64 / (n as f64 * n as f64);
            assert!((s.used_fraction - want_used).abs() < 1e-12);
            assert!(
                (s.surface_area_tin - s.used_fraction * s.base_area).abs() < 1e-9 * s.base_area
            );
            if s.used_fraction < 1.0 {
                clipped_seen += 1;
                // only the texels over the clipped rectangle are covered
                let want = want_used * 64.0 * 64.0;
                assert!(
                    (s.covered_texels as f64 - want).abs() <= 2.0 * 64.0 + 1.0,
                    "{key:?}: {} vs {want}",
                    s.covered_texels
                );
            }
        }
        assert!(clipped_seen >= 3);
        // a key outside the DEM gives zero areas, no panic
        let s = cell_stats(
            &dem,
            &tree,
            CellKey {
                level: 3,
                x: 7,
                y: 7,
            },
            &Tin::default(),
            8,
        );
        assert_eq!(
            (s.rel_texel, s.covered_texels, s.clipped_area),
            (0.0, 0, 0.0)
        );
    }
}
