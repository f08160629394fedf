//! `cliffmap render`: one frame of a store from a camera, written as PNG.

use std::path::PathBuf;

use anyhow::Context;
use cliffmap::camera::camera_from_json_file;
use cliffmap::fsutil::write_png_atomic;
use cliffmap::render::{FrameOptions, SceneOptions, TerrainScene, UvMode};

/// Flags of `cliffmap render`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store directory.
    store: PathBuf,
    /// Camera JSON (cliffmap camera or ImGRAFT-style, see docs/formats.md "Camera JSON").
    #[arg(long)]
    camera: PathBuf,
    /// Frame size, e.g. 1280x720. The camera's fields of view are kept.
    #[arg(long, value_parser = parse_size)]
    size: (u32, u32),
    /// Output PNG.
    #[arg(long)]
    out: PathBuf,
    /// Screen-space error threshold in pixels.
    #[arg(long, default_value_t = 0.5)]
    sse: f64,
    /// Texture colour only (no lighting), flat sky.
    #[arg(long)]
    unlit: bool,
    /// Tint cells by quadtree level.
    #[arg(long)]
    levels: bool,
}

/// Parses `WxH` into positive pixel counts.
pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got {s:?}"))?;
    let p = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| (1..=16384).contains(&n))
    };
    match (p(w), p(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(format!(
            "expected WIDTHxHEIGHT with each side in 1..=16384, got {s:?}"
        )),
    }
}

/// Runs the command.
pub fn run(a: Args) -> anyhow::Result<()> {
    let (w, h) = a.size;
    let cam = camera_from_json_file(&a.camera, (w, h))?.resized(w, h);
    let opts = SceneOptions {
        sse_px: a.sse,
        uv_mode: UvMode::Mixed,
        frame: FrameOptions {
            lit: !a.unlit,
            level_overlay: a.levels,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut scene = TerrainScene::open(&a.store, w, h, opts)?;
    eprintln!("adapter: {}", scene.gpu().describe());
    let r = scene.frame(&cam, true)?;
    let img = scene.read_rgba()?;
    write_png_atomic(&a.out, &img).with_context(|| format!("writing {}", a.out.display()))?;
    eprintln!(
        "{}: {} cells ({} culled), {} triangles, {:.1} ms",
        a.out.display(),
        r.drawn,
        r.culled,
        r.triangles,
        r.frame_ms
    );
    Ok(())
}
