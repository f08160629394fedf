//! Fly-through benchmark of the renderer: alternates UV modes over several rounds on the same
//! store and default path, and prints a Markdown table of per-mode medians.
//!
//! Usage: `cargo run --release --example render_fly -- STORE [FRAMES] [WxH] [ROUNDS]`
//! (defaults 120 frames, 960x540, 3 rounds).

use std::path::PathBuf;

use cliffmap::render::{
    FlightPath, FlyReport, SceneOptions, StoreRenderer, UvMode, fly, percentile,
};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let store = PathBuf::from(
        args.first()
            .ok_or_else(|| anyhow::anyhow!("usage: render_fly STORE [FRAMES] [WxH] [ROUNDS]"))?,
    );
    let frames: usize = args.get(1).map(|s| s.parse()).transpose()?.unwrap_or(120);
    let (w, h) = match args.get(2) {
        Some(s) => {
            let (a, b) = s
                .split_once('x')
                .ok_or_else(|| anyhow::anyhow!("size must be WxH"))?;
            (a.parse()?, b.parse()?)
        }
        None => (960u32, 540u32),
    };
    let rounds: usize = args.get(3).map(|s| s.parse()).transpose()?.unwrap_or(3);
    let modes = [
        (UvMode::Ortho, "ortho"),
        (UvMode::Reparam, "reparam"),
        (UvMode::Mixed, "mixed"),
    ];
    let mut results: Vec<Vec<FlyReport>> = vec![Vec::new(); modes.len()];
    for _ in 0..rounds {
        for (k, (mode, name)) in modes.iter().enumerate() {
            let opts = SceneOptions {
                uv_mode: *mode,
                ..Default::default()
            };
            let mut scene = StoreRenderer::open(&store, w, h, opts)?;
            let path = FlightPath::default_for(&scene.store().manifest)?;
            let cams = path.cameras(frames.max(2), w, h);
            results[k].push(fly(
                &mut scene,
                &cams,
                name,
                opts.sse_px,
                opts.budget_bytes,
            )?);
        }
    }
    let first = &results[0][0];
    println!(
        "store {}, {w}x{h}, {frames} frames x {rounds} rounds, adapter {} ({}, {})",
        store.display(),
        first.adapter,
        first.backend,
        first.device_type
    );
    println!();
    println!(
        "| mode | fps median | fps p5 | frame ms p95 | triangles/frame | cells/frame | GPU MB max | stall frames | fps ratio vs ortho |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    let med = |v: Vec<f64>| percentile(&v, 0.5);
    let base = med(results[0].iter().map(|r| r.fps_median).collect());
    for (k, (_, name)) in modes.iter().enumerate() {
        let r = &results[k];
        let fps = med(r.iter().map(|x| x.fps_median).collect());
        println!(
            "| {name} | {:.1} | {:.1} | {:.0} | {:.0} | {:.0} | {:.1} | {:.0} | {:.2} |",
            fps,
            med(r.iter().map(|x| x.fps_p5).collect()),
            med(r.iter().map(|x| x.frame_ms_p95).collect()),
            med(r.iter().map(|x| x.triangles_per_frame_median).collect()),
            med(r.iter().map(|x| x.cells_per_frame_median).collect()),
            med(r.iter().map(|x| x.gpu_bytes_max as f64 / 1e6).collect()),
            med(r.iter().map(|x| x.load_stall_frames as f64).collect()),
            fps / base
        );
    }
    Ok(())
}
