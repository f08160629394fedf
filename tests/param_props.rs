//! Property tests: random height fields on small grids, and steep real terrain.

mod common;
mod param_util;

use cliffmap::param::degener_energy;
use cliffmap::{ParamOptions, parameterize};
use param_util::{grid_mesh, height_grid};
use proptest::prelude::*;

fn max_slope_deg(n: usize, h: &[f64]) -> f64 {
    let mut m: f64 = 0.0;
    for r in 0..n {
        for c in 0..n {
            if c + 1 < n {
                m = m.max((h[r * n + c + 1] - h[r * n + c]).abs());
            }
            if r + 1 < n {
                m = m.max((h[(r + 1) * n + c] - h[r * n + c]).abs());
            }
        }
    }
    m.atan().to_degrees()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]

    #[test]
    fn random_height_fields(n in 3usize..10, seed in any::<u64>(), amp in 0.0f64..40.0, theta in prop_oneof![Just(0.0), Just(1.0), Just(3.0)]) {
        let mut s = seed | 1;
        let h: Vec<f64> = (0..n * n).map(|_| {
            s ^= s << 13; s ^= s >> 7; s ^= s << 17;
            amp * ((s >> 11) as f64 / (1u64 << 53) as f64 - 0.5)
        }).collect();
        let m = height_grid(n, |r, c| h[r * n + c]);
        let opts = ParamOptions { theta, ..ParamOptions::default() };
        let ch = parameterize(&m, &opts).unwrap();
        prop_assert_eq!(ch.metrics.flipped, 0);
        prop_assert_eq!(ch.metrics.boundary_crossings, 0);
        for uv in &ch.uvs {
            prop_assert!(uv[0].is_finite() && uv[1].is_finite());
            prop_assert!((0.0..=1.0).contains(&uv[0]) && (0.0..=1.0).contains(&uv[1]), "uv {:?}", uv);
        }
        prop_assert!(ch.metrics.symmetric_dirichlet_mean.is_finite());
        prop_assert!(ch.metrics.used_fraction > 0.0 && ch.metrics.used_fraction <= 1.0);
        if max_slope_deg(n, &h) > 70.0 {
            let ortho: Vec<[f64; 2]> = m.positions.iter().map(|p| [p[0], p[1]]).collect();
            let ours = degener_energy(&m.positions, &m.triangles, &ch.uvs, theta).unwrap();
            let o = degener_energy(&m.positions, &m.triangles, &ortho, theta).unwrap();
            prop_assert!(ours <= o, "steep cell: ours {} ortho {}", ours, o);
        }
    }
}

/// The steepest 17x17 patch of the Engabreen DEM (3 m spacing, mean slope over ~50°).
#[test]
fn steepest_engabreen_patch() {
    let path = common::real_data("engabreen/engabreen_dem_3m_507x590.f32");
    let bytes = std::fs::read(&path).unwrap();
    let (cols, rows) = (507usize, 590usize);
    assert_eq!(bytes.len(), cols * rows * 4);
    let z: Vec<f64> = bytes
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64)
        .collect();
    let n = 17;
    let mut best = (f64::NEG_INFINITY, 0, 0);
    for r0 in (0..rows - n).step_by(4) {
        for c0 in (0..cols - n).step_by(4) {
            let mut s = 0.0;
            for r in r0..r0 + n - 1 {
                for c in c0..c0 + n - 1 {
                    let gx = (z[r * cols + c + 1] - z[r * cols + c]) / 3.0;
                    let gy = (z[(r + 1) * cols + c] - z[r * cols + c]) / 3.0;
                    s += (gx * gx + gy * gy).sqrt().atan().to_degrees();
                }
            }
            let mean = s / ((n - 1) * (n - 1)) as f64;
            if mean > best.0 {
                best = (mean, r0, c0);
            }
        }
    }
    assert!(best.0 > 50.0, "steepest patch mean slope {}", best.0);
    let (_, r0, c0) = best;
    let xs: Vec<f64> = (0..n).map(|i| 3.0 * i as f64).collect();
    // Rows run south; flip them so y points north and triangles stay CCW from above.
    // World offsets as in the file's georeference (UTM 33N).
    let m = grid_mesh(
        &xs,
        &xs,
        |r, c| z[(r0 + n - 1 - r) * cols + c0 + c],
        [
            445302.17 + 3.0 * c0 as f64,
            7396769.45 - 3.0 * (r0 + n - 1) as f64,
            0.0,
        ],
    );
    let ch = parameterize(&m, &ParamOptions::default()).unwrap();
    assert_eq!(ch.metrics.flipped, 0);
    let ortho: Vec<[f64; 2]> = m.positions.iter().map(|p| [p[0], p[1]]).collect();
    let om = cliffmap::chart_metrics(&m.positions, &m.triangles, &ortho, None).unwrap();
    assert!(ch.metrics.angle_distortion_mean < 1.3, "{:?}", ch.metrics);
    assert!(om.angle_distortion_mean > 1.5, "{:?}", om);
    assert!(ch.metrics.symmetric_dirichlet_mean < om.symmetric_dirichlet_mean);
    assert!(ch.metrics.rel_texel > 1.0 && ch.metrics.rel_texel.is_finite());
}
