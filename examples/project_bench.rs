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
//! `ACCELS` is a comma-separated list of `--ray-accel` values (default `grid,bvh:fast`).

#[path = "bench_util/mod.rs"]
mod bench_util;

use std::path::{Path, PathBuf};
use std::time::Instant;

use bench_util::{cpu_seconds, median, shared_data};
use cliffmap::pipeline::{project_store, reparam_store, ProjectOptions, ReparamOptions};
use cliffmap::photo::{read_photo_list, RayAccel};


fn engabreen_store(dir: &Path) -> anyhow::Result<()> {
    bench_util::build_engabreen_store(dir, "project-bench")?;
    reparam_store(dir, &ReparamOptions { quiet: true, ..ReparamOptions::default() })?;
    Ok(())
}

fn copy_dir(from: &Path, to: &Path) -> std::io::Result<()> {
    std::fs::create_dir_all(to)?;
    for e in std::fs::read_dir(from)? {
        let e = e?;
        let dest = to.join(e.file_name());
        if e.file_type()?.is_dir() {
            copy_dir(&e.path(), &dest)?;
        } else {
            std::fs::copy(e.path(), dest)?;
        }
    }
    Ok(())
}

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let tmp = tempfile::tempdir()?;
    let dir = args.get(1).map_or_else(|| tmp.path().join("store"), PathBuf::from);
    let runs: usize = args.get(2).map(|s| s.parse()).transpose()?.unwrap_or(3).max(1);
    let accels: Vec<RayAccel> = args
        .get(3)
        .map_or("grid,bvh:fast", String::as_str)
        .split(',')
        .map(|m| RayAccel::parse(m).ok_or_else(|| anyhow::anyhow!("bad acceleration {m}")))
        .collect::<anyhow::Result<_>>()?;
    if !dir.join("manifest.json").is_file() {
        engabreen_store(&dir)?;
    }
    let list = tmp.path().join("photos.json");
    let data = shared_data("engabreen");
    std::fs::write(
        &list,
        serde_json::json!({"photos": [{"image": data.join("IMG_8902.jpg"), "imgraft": data.join("engabreen_camera_IMG_8902.json")}]})
            .to_string(),
    )?;
    let t = Instant::now();
    let photos = read_photo_list(&list)?;
    let decode = t.elapsed().as_secs_f64();
    let (w, h) = photos[0].image.dimensions();
    println!(
        "Engabreen store {}, photo IMG_8902 {w} × {h} (decoded in {decode:.2} s, not counted), {} threads, {runs} runs\n",
        dir.display(),
        rayon::current_num_threads()
    );

    let mut wall = vec![Vec::new(); accels.len()];
    let mut cpu = vec![Vec::new(); accels.len()];
    let mut stages: Vec<Vec<Vec<(String, f64)>>> = vec![Vec::new(); accels.len()];
    for run in 0..runs {
        for (k, accel) in accels.iter().enumerate() {
            let work = tmp.path().join(format!("run{run}-{k}"));
            copy_dir(&dir, &work)?;
            let opts = ProjectOptions { ray: *accel, quiet: true, ..ProjectOptions::default() };
            let (c0, t0) = (cpu_seconds(), Instant::now());
            let report = project_store(&work, &photos, &opts)?;
            wall[k].push(t0.elapsed().as_secs_f64());
            cpu[k].push(cpu_seconds() - c0);
            stages[k].push(report.stage_seconds);
        }
    }
    let base = median(wall[0].clone());
    println!("| acceleration | wall s (median) | CPU s (median) | wall × first |");
    println!("|---|---|---|---|");
    for (k, accel) in accels.iter().enumerate() {
        let m = median(wall[k].clone());
        println!("| {} | {m:.2} | {:.2} | {:.2} |", accel.name(), median(cpu[k].clone()), m / base);
    }
    println!("\nStage wall seconds (medians):\n");
    print!("| stage |");
    for a in &accels {
        print!(" {} |", a.name());
    }
    println!();
    println!("|---|{}", "---|".repeat(accels.len()));
    for (i, (name, _)) in stages[0][0].iter().enumerate() {
        print!("| {name} |");
        for st in &stages {
            let v: Vec<f64> = st.iter().filter_map(|r| r.get(i).map(|x| x.1)).collect();
            print!(" {:.3} |", median(v));
        }
        println!();
    }
    Ok(())
}
