//! Single-thread CPU time of `ortho_texture` and `normal_map` at 256² texels on the real
//! Engabreen data, for a 256-interval cell and the 1024-interval root. CPU time (from
//! /proc/self/stat, Linux only) is robust against other processes sharing the machine,
//! unlike the wall-clock medians of `benches/cell_images.rs`.
//! Run: `cargo run --release --example cell_images_cpu`.

#[path = "../tests/common/mod.rs"]
mod common;

use cliffmap::cells::{nominal_extent, normal_map, ortho_texture};
use cliffmap::{CellKey, Quadtree};

/// User + system CPU seconds of this process (10 ms resolution).
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").expect("/proc/self/stat (Linux only)");
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let tick = |k: usize| {
        fields
            .get(k)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (tick(11) + tick(12)) / 100.0
}

fn main() {
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
        .expect("rayon pool");
    let dem = common::engabreen_dem();
    let ortho = common::engabreen_ortho(&dem);
    let tree = Quadtree::new(507, 590, 64);
    let reps = 40;
    println!("| cell | ortho_texture ms CPU | normal_map ms CPU | both |");
    println!("|---|---|---|---|");
    for (name, key) in [
        (
            "2-0-0 (256 intervals)",
            CellKey {
                level: 2,
                x: 0,
                y: 0,
            },
        ),
        (
            "0-0-0 root (1024)",
            CellKey {
                level: 0,
                x: 0,
                y: 0,
            },
        ),
    ] {
        let ext = nominal_extent(&tree, &dem.georef, key);
        let t0 = cpu_seconds();
        for _ in 0..reps {
            std::hint::black_box(ortho_texture(&ortho, &dem, ext, 256));
        }
        let t1 = cpu_seconds();
        for _ in 0..reps {
            std::hint::black_box(normal_map(&dem, ext, 256));
        }
        let t2 = cpu_seconds();
        let (a, b) = ((t1 - t0) * 1e3 / reps as f64, (t2 - t1) * 1e3 / reps as f64);
        println!("| {name} | {a:.1} | {b:.1} | {:.1} |", a + b);
    }
}
