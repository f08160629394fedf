//! Texel-stretch statistics, textures and normal maps on the real Engabreen data.

mod common;

use cliffmap::cells::{nominal_extent, normal_map, ortho_texture};
use cliffmap::stats::{CellStatsEntry, cell_stats, stats_json, write_histogram_png};
use cliffmap::{CellKey, Quadtree};

#[test]
fn engabreen_statistics_are_consistent() {
    let dem = common::engabreen_dem();
    let tree = Quadtree::new(507, 590, 64);
    let mut entries = Vec::new();
    for key in tree.all_cells() {
        let rect = tree.clipped(key).unwrap();
        let tin = common::grid_tin(rect, tree.stride(key.level));
        let s = cell_stats(&dem, &tree, key, &tin, 128);
        assert!(s.rel_texel >= 1.0 - 1e-12, "{key:?}: {}", s.rel_texel);
        assert!(s.texel_stretch.p50 >= 1.0 - 1e-6 && s.texel_stretch.max >= s.texel_stretch.p99);
        assert!(s.used_fraction > 0.0 && s.used_fraction <= 1.0);
        assert!(s.max_slope_deg < 90.0 && s.mean_slope_deg <= s.max_slope_deg);
        if key.level == tree.finest_level() {
            // the full-resolution grid TIN is the DEM surface itself
            assert!((s.surface_area_tin - s.surface_area_dem).abs() < 1e-9 * s.surface_area_dem);
        }
        entries.push(CellStatsEntry::new(key, &tin, s));
    }
    // the data has rock walls: some finest cells are well above 1.2, and steep texels exist
    let finest: Vec<_> = entries
        .iter()
        .filter(|e| e.level == tree.finest_level())
        .collect();
    assert!(finest.iter().any(|e| e.stats.rel_texel > 1.5));
    assert!(finest.iter().any(|e| e.stats.steep_texel_fraction > 0.1));
    let v = stats_json(&entries, 1.2);
    assert_eq!(v["cells"].as_array().unwrap().len(), entries.len());
    assert!(v["summary"]["cells_above"].as_u64().unwrap() > 0);

    let dir = tempfile::tempdir().unwrap();
    let rels: Vec<f64> = entries.iter().map(|e| e.stats.rel_texel).collect();
    let png = std::env::var_os("CLIFFMAP_KEEP_HISTOGRAM").map_or_else(
        || dir.path().join("rel_texel_histogram.png"),
        std::path::PathBuf::from,
    );
    write_histogram_png(&png, &rels, 1.2).unwrap();
    assert_eq!(image::image_dimensions(&png).unwrap(), (1000, 600));
}

#[test]
fn engabreen_textures_and_normals() {
    let dem = common::engabreen_dem();
    let ortho = common::engabreen_ortho(&dem);
    let tree = Quadtree::new(507, 590, 64);
    // level 2: 256-interval cells; cell 2-1-0 covers columns 256..=506 (clipped at 506)
    let key = CellKey {
        level: 2,
        x: 1,
        y: 0,
    };
    let ext = nominal_extent(&tree, &dem.georef, key);
    let tex = ortho_texture(&ortho, &dem, ext, 256);
    let nm = normal_map(&dem, ext, 256);
    // texel i covers columns 256 + i .. 257 + i: the last texels lie beyond column 506
    for j in 0..256 {
        assert_eq!(tex.get_pixel(255, j).0[3], 0, "beyond the DEM");
        assert!(nm.get_pixel(255, j).0[2] >= 128, "normals point up");
    }
    let known = tex.pixels().filter(|p| p.0[3] == 255).count();
    assert!(known > 200 * 200, "{known}");
    // fine-level normals agree with central differences of the DEM at a texel centre
    let key = CellKey {
        level: 4,
        x: 2,
        y: 3,
    };
    let (c0, r0, n) = tree.nominal(key);
    let ext = nominal_extent(&tree, &dem.georef, key);
    let nm = normal_map(&dem, ext, n); // texel = one sample interval, centre between samples
    for (i, j) in [(5u32, 7u32), (30, 40), (60, 2)] {
        let (c, r) = ((c0 + i) as usize, (r0 + j) as usize);
        let h = |r: usize, c: usize| dem.at(r, c) as f64;
        // mean gradient over the quad [c, c+1] x [r, r+1] of the bilinear surface
        let gx = (h(r, c + 1) + h(r + 1, c + 1) - h(r, c) - h(r + 1, c)) / (2.0 * 3.0);
        let gy = -(h(r + 1, c) + h(r + 1, c + 1) - h(r, c) - h(r, c + 1)) / (2.0 * 3.0);
        let len = (gx * gx + gy * gy + 1.0).sqrt();
        let want =
            [-gx / len, -gy / len, 1.0 / len].map(|v| ((v * 0.5 + 0.5) * 255.0).round() as i32);
        let got = nm.get_pixel(i, j).0;
        for k in 0..3 {
            assert!(
                (got[k] as i32 - want[k]).abs() <= 1,
                "({i},{j}): {got:?} vs {want:?}"
            );
        }
    }
}
