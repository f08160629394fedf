//! TIN benchmark: cliffmap's greedy TIN against pydelatin (same algorithm, C++), and the
//! growth of the celled build with DEM size. Prints markdown tables.
//!
//! Usage:
//!   cargo run --release --example tin_bench -- [--runs N] [--no-peer] [--growth] [--skip-real]
//!
//! Real DEMs (resolved like the tests: $CLIFFMAP_SHARED_DATA, ../shared/data/real,
//! /work/shared/data/real): St Helens 2000x2000 16-bit PNG (h = v * 0.1, 10 m) and the
//! Grand Canyon 2x2 Terrain-RGB mosaic (512x512, ~30.9 m). The peer runs through
//! `python3 benches/peers/tin_pydelatin.py` (install with benches/peers/setup.sh).
//! Times are medians of N runs, wall clock and on-CPU time of the calling thread.

#[path = "bench_util/mod.rs"]
mod bench_util;

use std::path::PathBuf;
use std::process::Command;
use std::time::Instant;

use cliffmap::cells::{build_dem_tin, build_level, level_epsilon};
use cliffmap::{Dem, GridGeoref, Quadtree};

fn data_dir() -> PathBuf {
    let c = [
        std::env::var_os("CLIFFMAP_SHARED_DATA").map(PathBuf::from),
        Some(PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../shared/data/real"
        ))),
        Some(PathBuf::from("/work/shared/data/real")),
    ];
    c.into_iter()
        .flatten()
        .find(|p| p.exists())
        .unwrap_or_else(|| PathBuf::from("/work/shared/data/real"))
}

/// On-CPU nanoseconds of the calling thread (Linux; 0 elsewhere).
fn thread_cpu_ns() -> u64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next().and_then(|v| v.parse().ok()))
        .unwrap_or(0)
}

/// On-CPU nanoseconds of the process's live threads (Linux `/proc/self/task/*/schedstat`,
/// nanosecond resolution; 0 elsewhere). The benchmark's rayon pools live across each
/// measurement, so no thread that worked exits inside one (the process clock of
/// `/proc/self/stat`, which would count exited threads, ticks in 10 ms, the size of the
/// differences measured here).
fn process_cpu_ns() -> u64 {
    let Ok(tasks) = std::fs::read_dir("/proc/self/task") else {
        return 0;
    };
    tasks
        .flatten()
        .filter_map(|t| std::fs::read_to_string(t.path().join("schedstat")).ok())
        .filter_map(|s| {
            s.split_whitespace()
                .next()
                .and_then(|v| v.parse::<u64>().ok())
        })
        .sum()
}

/// The value after flag `name` parsed, if present and valid.
fn flag_value<T: std::str::FromStr>(args: &[String], name: &str) -> Option<T> {
    let i = args.iter().position(|a| a == name)?;
    args.get(i + 1)?.parse().ok()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn load_png16(path: &PathBuf, spacing: f64) -> anyhow::Result<Dem> {
    let img = image::open(path)?.into_luma16();
    let (w, h) = img.dimensions();
    let hs = img
        .as_raw()
        .iter()
        .map(|&v| (v as f64 * 0.1) as f32)
        .collect();
    Ok(Dem::from_heights(
        w as usize,
        h as usize,
        hs,
        GridGeoref::new(0.0, 0.0, spacing),
    )?)
}

fn load_terrain_rgb_mosaic(paths: &[PathBuf], spacing: f64) -> anyhow::Result<Dem> {
    let tiles: Vec<_> = paths
        .iter()
        .map(|p| image::open(p).map(|i| i.to_rgba8()))
        .collect::<Result<_, _>>()?;
    let (tw, th) = tiles[0].dimensions();
    let (w, h) = (tw * 2, th * 2);
    let mut hs = vec![0f32; (w * h) as usize];
    for (k, t) in tiles.iter().enumerate() {
        let (ox, oy) = ((k as u32 % 2) * tw, (k as u32 / 2) * th);
        for (x, y, p) in t.enumerate_pixels() {
            let v = -10000.0 + (p[0] as f64 * 65536.0 + p[1] as f64 * 256.0 + p[2] as f64) * 0.1;
            hs[((oy + y) * w + ox + x) as usize] = v as f32;
        }
    }
    Ok(Dem::from_heights(
        w as usize,
        h as usize,
        hs,
        GridGeoref::new(0.0, 0.0, spacing),
    )?)
}

struct Peer {
    version: String,
    ms: f64,
    cpu_ms: f64,
    triangles: u64,
    error: f64,
}

fn pydelatin(kind: &str, paths: &[PathBuf], runs: usize, err: f64) -> Option<Peer> {
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/benches/peers/tin_pydelatin.py"
    );
    let joined = paths
        .iter()
        .map(|p| p.display().to_string())
        .collect::<Vec<_>>()
        .join(",");
    let out = Command::new("python3")
        .args([script, kind, &joined, &runs.to_string(), &err.to_string()])
        .output()
        .ok()?;
    if !out.status.success() {
        eprintln!("pydelatin failed: {}", String::from_utf8_lossy(&out.stderr));
        return None;
    }
    let line = String::from_utf8_lossy(&out.stdout)
        .lines()
        .next()?
        .to_string();
    let v: serde_json::Value = serde_json::from_str(&line).ok()?;
    Some(Peer {
        version: v["version"].as_str().unwrap_or("?").to_string(),
        ms: v["median_ms"].as_f64()?,
        cpu_ms: v["median_cpu_ms"].as_f64()?,
        triangles: v["triangles"].as_u64()?,
        error: v["measured_error"].as_f64()?,
    })
}

fn bench_real(
    name: &str,
    dem: &Dem,
    kind: &str,
    paths: &[PathBuf],
    errors: &[f64],
    runs: usize,
    peer: bool,
) {
    println!("\n### {name} ({}x{})\n", dem.width, dem.height);
    println!(
        "| max error (m) | build | median wall (ms) | median CPU (ms) | triangles | measured max error (m) | wall speed vs pydelatin (>1 = faster) | CPU speed vs pydelatin (>1 = faster) |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for &err in errors {
        let p = if peer {
            pydelatin(kind, paths, runs, err)
        } else {
            None
        };
        let (mut wall, mut cpu) = (Vec::new(), Vec::new());
        let mut tin = None;
        for _ in 0..runs {
            let (t0, c0) = (Instant::now(), thread_cpu_ns());
            let t = build_dem_tin(dem, err).expect("whole-DEM TIN");
            cpu.push((thread_cpu_ns() - c0) as f64 / 1e6);
            wall.push(t0.elapsed().as_secs_f64() * 1e3);
            tin = Some(t);
        }
        let tin = tin.expect("runs >= 1");
        let (wm, cm) = (median(wall), median(cpu));
        let ratio = |ours: f64, theirs: Option<f64>| {
            theirs.map_or("n/a".to_string(), |t| format!("{:.2}x", t / ours))
        };
        println!(
            "| {err} | cliffmap whole-DEM TIN (1 thread) | {wm:.0} | {cm:.0} | {} | {:.3} | {} | {} |",
            tin.triangles.len(),
            tin.max_error,
            ratio(wm, p.as_ref().map(|p| p.ms)),
            ratio(cm, p.as_ref().map(|p| p.cpu_ms))
        );
        if let Some(p) = &p {
            println!(
                "| {err} | pydelatin {} (C++, 1 thread) | {:.0} | {:.0} | {} | {:.3} | 1 | 1 |",
                p.version, p.ms, p.cpu_ms, p.triangles, p.error
            );
        }
        for s in [64u32, 128] {
            let tree = Quadtree::new(dem.width as u32, dem.height as u32, s);
            let level = tree.finest_level();
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(2)
                .build()
                .expect("thread pool");
            let (mut wall, mut cpu) = (Vec::new(), Vec::new());
            let mut tris = 0;
            let mut worst = 0.0f64;
            for _ in 0..runs {
                let (t0, c0) = (Instant::now(), process_cpu_ns());
                let cells = pool
                    .install(|| build_level(dem, &tree, level, err))
                    .expect("level");
                cpu.push((process_cpu_ns().saturating_sub(c0)) as f64 / 1e6);
                wall.push(t0.elapsed().as_secs_f64() * 1e3);
                tris = cells.iter().map(|(_, t)| t.triangles.len()).sum::<usize>();
                worst = cells.iter().map(|(_, t)| t.max_error).fold(0.0, f64::max);
            }
            println!(
                "| {err} | cliffmap finest level, S={s} ({} cells, 2 threads) | {:.0} | {:.0} (all threads) | {tris} | {worst:.3} | | |",
                tree.cells(level).len(),
                median(wall),
                median(cpu)
            );
        }
    }
}

fn growth(runs: usize) {
    println!(
        "\n### Growth with DEM size (diamond-square fractal, displacement 0.4 m * step^0.9, 10 m spacing, S = 64, max error 1 m at the finest level, 2 threads)\n"
    );
    println!(
        "| DEM | samples | levels | wall, all levels (ms) | ns per sample per level | triangles, finest level | per level wall (ms), root first |"
    );
    println!("|---|---|---|---|---|---|---|");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .expect("thread pool");
    for k in [10, 11, 12] {
        let n = (1usize << k) + 1;
        let dem = bench_util::fractal(n, 42);
        let tree = Quadtree::new(n as u32, n as u32, 64);
        let mut per_level = vec![Vec::new(); tree.levels as usize];
        let mut finest_tris = 0;
        for _ in 0..runs {
            for level in 0..tree.levels {
                let t0 = Instant::now();
                let cells = pool
                    .install(|| build_level(&dem, &tree, level, 1.0))
                    .expect("level");
                per_level[level as usize].push(t0.elapsed().as_secs_f64() * 1e3);
                if level == tree.finest_level() {
                    finest_tris = cells.iter().map(|(_, t)| t.triangles.len()).sum::<usize>();
                }
                let eps = level_epsilon(&tree, level, 1.0);
                assert!(cells.iter().all(|(_, t)| t.max_error <= eps));
            }
        }
        let meds: Vec<f64> = per_level.into_iter().map(median).collect();
        let total: f64 = meds.iter().sum();
        let samples = (n * n) as f64;
        println!(
            "| {n}x{n} | {:.1} M | {} | {total:.0} | {:.0} | {finest_tris} | {} |",
            samples / 1e6,
            tree.levels,
            total * 1e6 / (samples * tree.levels as f64),
            meds.iter()
                .map(|m| format!("{m:.0}"))
                .collect::<Vec<_>>()
                .join(" / ")
        );
    }
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let runs = flag_value(&args, "--runs").unwrap_or(3usize).max(1);
    let peer = !args.iter().any(|a| a == "--no-peer");
    println!("cliffmap TIN benchmark, {runs} runs per figure (median)");
    if args.iter().any(|a| a == "--quick") {
        // one whole-DEM build of each real DEM at 2 m, for profiling
        let dir = data_dir();
        let gc: Vec<PathBuf> = ["12-758-1608", "12-759-1608", "12-758-1609", "12-759-1609"]
            .iter()
            .map(|t| dir.join(format!("grand_canyon_tiles/{t}.terrain.png")))
            .collect();
        let dems = [
            (
                "St Helens",
                load_png16(&dir.join("argudo_glaciers/sthelens_10m.png"), 10.0)?,
            ),
            ("Grand Canyon", load_terrain_rgb_mosaic(&gc, 30.9)?),
        ];
        // --error E (default 2 m) and --reps N (default 3) for the celled level
        let err: f64 = flag_value(&args, "--error").unwrap_or(2.0);
        let reps: usize = flag_value(&args, "--reps").unwrap_or(3);
        if args.iter().any(|a| a == "--level") {
            // the celled finest level (S = 64) instead, `reps` times each, on --threads N
            // (default 2)
            let threads: usize = flag_value(&args, "--threads").unwrap_or(2);
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .expect("thread pool");
            for (name, dem) in &dems {
                let tree = Quadtree::new(dem.width as u32, dem.height as u32, 64);
                let mut cpu = Vec::with_capacity(reps);
                for _ in 0..reps {
                    let (t0, c0) = (Instant::now(), process_cpu_ns());
                    let cells = pool
                        .install(|| build_level(dem, &tree, tree.finest_level(), err))
                        .expect("level");
                    cpu.push(process_cpu_ns().saturating_sub(c0) as f64 / 1e6);
                    println!(
                        "{name} finest level S=64 {err} m, {threads} threads: wall {:.0} ms, CPU {:.0} ms, {} triangles",
                        t0.elapsed().as_secs_f64() * 1e3,
                        process_cpu_ns().saturating_sub(c0) as f64 / 1e6,
                        cells.iter().map(|(_, t)| t.triangles.len()).sum::<usize>()
                    );
                }
                println!("{name} median CPU {:.1} ms", median(cpu));
            }
            return Ok(());
        }
        for (name, dem) in &dems {
            let (t0, c0) = (Instant::now(), thread_cpu_ns());
            let tin = build_dem_tin(dem, 2.0)?;
            println!(
                "{name} whole-DEM 2 m: wall {:.0} ms, CPU {:.0} ms, {} triangles",
                t0.elapsed().as_secs_f64() * 1e3,
                (thread_cpu_ns() - c0) as f64 / 1e6,
                tin.triangles.len()
            );
        }
        return Ok(());
    }
    if !args.iter().any(|a| a == "--skip-real") {
        let dir = data_dir();
        let sth = vec![dir.join("argudo_glaciers/sthelens_10m.png")];
        let dem = load_png16(&sth[0], 10.0)?;
        bench_real(
            "St Helens 10 m",
            &dem,
            "png16",
            &sth,
            &[2.0, 5.0],
            runs,
            peer,
        );
        let gc: Vec<PathBuf> = ["12-758-1608", "12-759-1608", "12-758-1609", "12-759-1609"]
            .iter()
            .map(|t| dir.join(format!("grand_canyon_tiles/{t}.terrain.png")))
            .collect();
        let dem = load_terrain_rgb_mosaic(&gc, 30.9)?;
        bench_real(
            "Grand Canyon Terrain-RGB 2x2 mosaic, ~30.9 m",
            &dem,
            "terrain-rgb",
            &gc,
            &[2.0, 5.0],
            runs,
            peer,
        );
    }
    if args.iter().any(|a| a == "--growth") {
        growth(runs);
    }
    Ok(())
}
