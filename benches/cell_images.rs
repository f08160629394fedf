//! Per-cell image and statistics costs on the real Engabreen data (507 x 590 at 3 m):
//! `ortho_texture` and `normal_map` at 256² texels for a 256-interval cell (one texel per
//! sample) and for the 1024-interval root (four samples per texel), and `cell_stats`.
//! Run: `cargo bench --bench cell_images`; medians are in target/criterion/*/new/estimates.json.

#[path = "../tests/common/mod.rs"]
mod common;

use std::time::Duration;

use cliffmap::cells::{nominal_extent, normal_map, ortho_texture};
use cliffmap::stats::cell_stats;
use cliffmap::{CellKey, Quadtree};
use criterion::{Criterion, criterion_group, criterion_main};

fn bench(c: &mut Criterion) {
    let dem = common::engabreen_dem();
    let ortho = common::engabreen_ortho(&dem);
    let tree = Quadtree::new(507, 590, 64);
    let mut g = c.benchmark_group("cell_images");
    g.sample_size(20).measurement_time(Duration::from_secs(4));
    for (name, key) in [
        (
            "level2_256",
            CellKey {
                level: 2,
                x: 0,
                y: 0,
            },
        ),
        (
            "root_1024",
            CellKey {
                level: 0,
                x: 0,
                y: 0,
            },
        ),
    ] {
        let ext = nominal_extent(&tree, &dem.georef, key);
        g.bench_function(format!("ortho_texture_256/{name}"), |b| {
            b.iter(|| ortho_texture(&ortho, &dem, ext, 256))
        });
        g.bench_function(format!("normal_map_256/{name}"), |b| {
            b.iter(|| normal_map(&dem, ext, 256))
        });
        g.bench_function(format!("texture_plus_normals_256/{name}"), |b| {
            b.iter(|| {
                (
                    ortho_texture(&ortho, &dem, ext, 256),
                    normal_map(&dem, ext, 256),
                )
            })
        });
    }
    let key = CellKey {
        level: 2,
        x: 0,
        y: 0,
    };
    let tin = common::grid_tin(tree.clipped(key).unwrap(), tree.stride(key.level));
    g.bench_function("cell_stats_256/level2_full_grid_tin", |b| {
        b.iter(|| cell_stats(&dem, &tree, key, &tin, 256))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
