//! Full-build benchmark: generates the procedural scene at a given size and times
//! `build_store` on it, printing one table row (samples, cells, triangles, seconds, peak RSS).
//! Run each size in its own process so peak memory is per size:
//!
//! ```sh
//! for n in 1025 2049 4097; do cargo run --release --example build_bench -- $n; done
//! ```

use std::time::Instant;

use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};
use cliffmap::scene::DemoScene;

fn peak_rss_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| {
                l.split_whitespace()
                    .nth(1)
                    .and_then(|v| v.parse::<f64>().ok())
            })
        })
        .map_or(f64::NAN, |kib| kib / 1024.0)
}

fn main() -> anyhow::Result<()> {
    let samples: usize = std::env::args()
        .nth(1)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(1025);
    let texels: u32 = std::env::args()
        .nth(2)
        .map(|s| s.parse())
        .transpose()?
        .unwrap_or(256);
    let scene = DemoScene {
        samples,
        ..DemoScene::default()
    };
    let t0 = Instant::now();
    let (dem, ortho) = scene.generate()?;
    let gen_s = t0.elapsed().as_secs_f64();
    let dir = tempfile::tempdir()?;
    let opts = BuildOptions {
        quiet: true,
        cell_texels: texels,
        ..BuildOptions::default()
    };
    let inputs = BuildInputs {
        dem: &dem,
        ortho: Some(&ortho),
        dem_source: "bench".into(),
        ortho_source: None,
        fingerprint: format!("bench-{samples}"),
    };
    let t1 = Instant::now();
    let m = build_store(&inputs, &opts, dir.path())?;
    let build_s = t1.elapsed().as_secs_f64();
    let tris: u64 = m.cells.iter().map(|c| c.triangles as u64).sum();
    let n = (samples * samples) as f64;
    println!(
        "| {samples}² | {:.1} M | {} | {} | {} | {:.1} | {:.2} | {:.0} | {:.0} |",
        n / 1e6,
        m.quadtree.levels,
        m.cells.len(),
        tris,
        gen_s,
        build_s,
        build_s / n * 1e9,
        peak_rss_mib()
    );
    Ok(())
}
