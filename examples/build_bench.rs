//! Full-build benchmark: generates the procedural scene at a given size and times
//! `build_store` on it, printing one table row (samples, cells, triangles, seconds, peak RSS).
//! Run each size in its own process so peak memory is per size:
//!
//! ```sh
//! for n in 1025 2049 4097; do cargo run --release --example build_bench -- $n; done
//! cargo run --release --example build_bench -- 1025 256 fast,balanced   # PNG compression knob
//! cargo run --release --example build_bench -- 8193 256 fast fractal     # large, quick to generate
//! ```
//! Arguments: samples per side (default 1025), texture side (default 256) and a
//! comma-separated list of `--png-compression` values (default `fast`); the scene is
//! generated once and built once per value (peak RSS is then the maximum so far). Each row
//! also gives the bytes of the PNG files written and the seconds spent encoding them
//! (measured by re-encoding the store's PNGs in this process after the build, one thread).
//! A fourth argument `fractal` replaces the procedural scene (slow to generate beyond 4097²:
//! ~22 µs per sample) by the diamond-square fractal DEM of `tin_bench` (10 m spacing, the
//! side must be 2^k + 1) without an ortho (textures derived from the DEM). A fifth argument
//! names a folder to build into and keep (e.g. for timing `export-tiles` on the store).

use std::time::Instant;

use cliffmap::demo_scene::DemoScene;
use cliffmap::fsutil::{PngCompression, encode_png};
use cliffmap::pipeline::{BuildInputs, BuildOptions, build_store};

#[path = "bench_util/mod.rs"]
mod bench_util;

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
    let compressions: Vec<PngCompression> = match std::env::args().nth(3) {
        None => vec![PngCompression::Fast],
        Some(list) => list
            .split(',')
            .map(|c| {
                c.parse::<PngCompression>()
                    .map_err(|e| anyhow::anyhow!("{c}: {e}"))
            })
            .collect::<anyhow::Result<_>>()?,
    };
    let fractal = std::env::args().nth(4).as_deref() == Some("fractal");
    let t0 = Instant::now();
    let (dem, ortho) = if fractal {
        anyhow::ensure!(
            samples >= 3 && (samples - 1).is_power_of_two(),
            "a fractal DEM needs 2^k + 1 samples per side"
        );
        (bench_util::fractal(samples, 42), None)
    } else {
        let (dem, ortho) = DemoScene {
            samples,
            ..DemoScene::default()
        }
        .generate()?;
        (dem, Some(ortho))
    };
    let gen_s = t0.elapsed().as_secs_f64();
    println!(
        "| DEM | samples | levels | cells | triangles | scene gen (s) | PNG compression | build (s) | ns/sample | PNG MB | PNG encode s (1 thread) | peak RSS (MiB) |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|---|---|");
    // a fifth argument: build into that folder and keep the (last) store there
    let keep = std::env::args().nth(5).map(std::path::PathBuf::from);
    for compression in compressions {
        let tmp = tempfile::tempdir()?;
        let dir = keep.clone().unwrap_or_else(|| tmp.path().to_path_buf());
        let opts = BuildOptions {
            cell_texels: texels,
            png_compression: compression,
            ..BuildOptions::default()
        };
        let inputs = BuildInputs {
            dem: &dem,
            ortho: ortho.as_ref(),
            dem_source: if fractal {
                "fractal".into()
            } else {
                "bench".into()
            },
            ortho_source: None,
            fingerprint: format!("bench-{samples}"),
        };
        let t1 = Instant::now();
        let m = build_store(&inputs, &opts, &dir)?;
        let build_s = t1.elapsed().as_secs_f64();
        let tris: u64 = m.cells.iter().map(|c| c.triangles as u64).sum();
        let (mut png_bytes, mut enc_s) = (0u64, 0.0f64);
        for c in &m.cells {
            for f in [&c.files.texture, &c.files.normal] {
                let path = dir.join(&f.path);
                png_bytes += std::fs::metadata(&path)?.len();
                let img = image::open(&path)?;
                let t = Instant::now();
                match img {
                    image::DynamicImage::ImageRgb8(i) => drop(encode_png(&path, &i, compression)?),
                    other => drop(encode_png(&path, &other.to_rgba8(), compression)?),
                }
                enc_s += t.elapsed().as_secs_f64();
            }
        }
        let n = (samples * samples) as f64;
        println!(
            "| {}{samples}² | {:.1} M | {} | {} | {} | {:.1} | {compression:?} | {:.2} | {:.0} | {:.1} | {:.2} | {:.0} |",
            if fractal { "fractal " } else { "" },
            n / 1e6,
            m.quadtree.levels,
            m.cells.len(),
            tris,
            gen_s,
            build_s,
            build_s / n * 1e9,
            png_bytes as f64 / 1e6,
            enc_s,
            peak_rss_mib()
        );
    }
    Ok(())
}
