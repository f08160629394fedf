//! Whole-photo projection benchmark (docs/projection.md, "Projecting one 12-MP photo").
//!
//! Projects IMG_8902 (4290 × 2856) onto the reparameterized Engabreen store (built into
//! STORE_DIR with the default build and reparam options if it holds no store yet) with
//! `pipeline::project_store`, the function behind `cliffmap project`: colour leveling, every
//! level's corner rays and footprints, splatting, blending and the PNG writes. Each run starts
//! from a fresh copy of the store; the copies are removed when the benchmark ends (removing
//! one before the next run makes ext4 without a journal slow to create the next run's files,
//! docs/projection.md, "Session 7"). The ray-casting accelerations given (default: the view
//! grid and the BVH) are interleaved run by run, so both see the same machine load; the
//! photo is decoded once, outside the timings (its decode time is printed).
//!
//! Prints per acceleration the median wall-clock and CPU seconds (user + system, all
//! threads) and the median time of each stage, and the ratio to the first acceleration.
//!
//! ```sh
//! cargo run --release --example project_bench -- [STORE_DIR] [RUNS] [ACCELS]
//! ```
//! `ACCELS` is a comma-separated list of variants `ACCEL[+TEXTURES]`: a `--ray-accel` value,
//! optionally with the photo texture sizes `fixed` (the cells' own sizes,
//! `--fixed-photo-texels`), `tpdN` (`--max-texels-per-photo-pixel N`) or `kK`
//! (`--texels-per-pixel K`), and a suffix `@tin` projects onto the TIN instead of the relief
//! surface (`cliffmap project --no-relief`); default
//! `grid,bvh:fast` (photo-driven sizes, the defaults of `cliffmap project`). The table also
//! gives the photo texture memory each variant wrote (GPU, RGBA8 with mips) and the bytes
//! of its photo texture files.

#[path = "bench_util/mod.rs"]
mod bench_util;

use std::time::Instant;

use bench_util::{cpu_seconds, median};
use cliffmap::pipeline::{PhotoTextureOptions, ProjectOptions, project_store};
use cliffmap::raycast::RayAccel;

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let tmp = tempfile::tempdir()?;
    let dir = bench_util::store_arg(&args, tmp.path());
    let runs = bench_util::runs_arg(&args, 2, 3)?;
    let variants: Vec<(String, RayAccel, PhotoTextureOptions)> = args
        .get(3)
        .map_or("grid,bvh:fast", String::as_str)
        .split(',')
        .map(parse_variant)
        .collect::<anyhow::Result<_>>()?;
    if !dir.join("manifest.json").is_file() {
        bench_util::build_engabreen_reparam_store(&dir, "project-bench")?;
    }
    let t = Instant::now();
    let photos = bench_util::img8902_photos(tmp.path())?;
    let decode = t.elapsed().as_secs_f64();
    let (w, h) = photos[0].image.dimensions();
    println!(
        "Engabreen store {}, photo IMG_8902 {w} × {h} (decoded in {decode:.2} s, not counted), {} threads, {runs} runs\n",
        dir.display(),
        rayon::current_num_threads()
    );

    let n = variants.len();
    let mut wall = vec![Vec::new(); n];
    let mut cpu = vec![Vec::new(); n];
    let mut bytes = vec![0u64; n];
    let mut disk = vec![0u64; n];
    let mut stages: Vec<Vec<Vec<(String, f64)>>> = vec![Vec::new(); n];
    for run in 0..runs {
        for (k, (name, accel, texture)) in variants.iter().enumerate() {
            let work = tmp.path().join(format!("run{run}-{k}"));
            bench_util::copy_dir(&dir, &work)?;
            let opts = ProjectOptions {
                ray: *accel,
                texture: *texture,
                onto_relief: !name.ends_with("@tin"),
                ..ProjectOptions::default()
            };
            let (c0, t0) = (cpu_seconds(), Instant::now());
            let report = project_store(&work, &photos, &opts)?;
            wall[k].push(t0.elapsed().as_secs_f64());
            cpu[k].push(cpu_seconds() - c0);
            bytes[k] = report
                .settings
                .levels
                .iter()
                .map(|l| l.photo_texture_bytes)
                .sum();
            stages[k].push(report.stage_seconds);
            disk[k] = cliffmap::store::Store::open(&work)?
                .manifest
                .cells
                .iter()
                .filter_map(|c| c.photo.as_ref())
                .map(|p| p.texture.bytes + p.confidence.bytes)
                .sum();
        }
    }
    let base = median(wall[0].clone());
    println!(
        "| variant | wall s (median) | CPU s (median) | wall × first | photo textures GPU MB | photo files on disk MB |"
    );
    println!("|---|---|---|---|---|---|");
    for (k, (name, ..)) in variants.iter().enumerate() {
        let m = median(wall[k].clone());
        println!(
            "| {name} | {m:.2} | {:.2} | {:.2} | {:.0} | {:.0} |",
            median(cpu[k].clone()),
            m / base,
            bytes[k] as f64 / 1e6,
            disk[k] as f64 / 1e6
        );
    }
    println!("\nStage wall seconds (medians; - where a variant has no such stage):\n");
    print!("| stage |");
    for (name, ..) in &variants {
        print!(" {name} |");
    }
    println!();
    println!("|---|{}", "---|".repeat(n));
    let mut names: Vec<&String> = Vec::new();
    for st in &stages {
        for (name, _) in &st[0] {
            if !names.contains(&name) {
                names.push(name);
            }
        }
    }
    for name in names {
        print!("| {name} |");
        for st in &stages {
            let v: Vec<f64> = st
                .iter()
                .filter_map(|r| r.iter().find(|x| &x.0 == name).map(|x| x.1))
                .collect();
            if v.is_empty() {
                print!(" - |");
            } else {
                print!(" {:.3} |", median(v));
            }
        }
        println!();
    }
    Ok(())
}

/// A variant `ACCEL[+fixed|+tpdN|+kK]` (see the module docs).
fn parse_variant(name: &str) -> anyhow::Result<(String, RayAccel, PhotoTextureOptions)> {
    let v = name.strip_suffix("@tin").unwrap_or(name);
    let (accel, texture) = v.split_once('+').map_or((v, None), |(a, t)| (a, Some(t)));
    let accel =
        RayAccel::parse(accel).ok_or_else(|| anyhow::anyhow!("bad acceleration {accel}"))?;
    let mut opts = PhotoTextureOptions::default();
    match texture {
        None => {}
        Some("fixed") => opts.photo_driven = false,
        Some(t) if t.starts_with('k') => {
            opts.texels_per_pixel = t[1..]
                .parse()
                .map_err(|_| anyhow::anyhow!("bad texture variant {t}"))?;
        }
        Some(t) => {
            let n: f64 = t
                .strip_prefix("tpd")
                .and_then(|n| n.parse().ok())
                .ok_or_else(|| anyhow::anyhow!("bad texture variant {t}"))?;
            opts.texels_per_delivered = n;
        }
    }
    Ok((name.replace(':', " "), accel, opts))
}
