//! `cliffmap fly`: a timed fly-through over a store, reported as JSON.

use std::path::PathBuf;

use anyhow::Context;
use cliffmap::fsutil::write_atomic;
use cliffmap::render::{
    FlightPath, FrameOptions, GeomorphOptions, SceneOptions, StoreRenderer, UvMode, fly,
};

use super::render::parse_size;

/// Texture-coordinate mode of `fly`.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum Mode {
    /// Every cell derives UVs from x, y in the vertex shader.
    Ortho,
    /// Every cell reads a UV vertex stream.
    Reparam,
    /// Each cell as stored, without photo textures.
    Mixed,
    /// Each cell's best texture: photo-enhanced, else as stored (the default).
    Photo,
}

/// Flags of `cliffmap fly`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store directory.
    store: PathBuf,
    /// Flight path JSON ({"fov_y_deg", "keys": [{"position", "look_at"}, ...]}); default: a
    /// low flight over the store's steepest cells.
    #[arg(long)]
    path: Option<PathBuf>,
    /// Frame size, e.g. 1280x720.
    #[arg(long, value_parser = parse_size, default_value = "960x540")]
    size: (u32, u32),
    /// Frames to render (the first is an untimed warm-up).
    #[arg(long, default_value_t = 300)]
    frames: usize,
    /// Texture-coordinate mode.
    #[arg(long, value_enum, default_value_t = Mode::Photo)]
    mode: Mode,
    /// Screen-space error threshold in pixels.
    #[arg(long, default_value_t = 0.5)]
    sse: f64,
    /// GPU memory budget for cached cells, e.g. 256M.
    #[arg(long, value_parser = super::parse_bytes, default_value = "512M")]
    budget: u64,
    /// Blend cells towards their parents' shape and texel density near LOD switches.
    #[arg(long)]
    geomorph: bool,
    /// Report JSON.
    #[arg(long)]
    out: PathBuf,
}

/// Runs the command.
pub fn run(a: Args) -> anyhow::Result<()> {
    let (w, h) = a.size;
    let (uv_mode, name) = match a.mode {
        Mode::Ortho => (UvMode::Ortho, "ortho"),
        Mode::Reparam => (UvMode::Reparam, "reparam"),
        Mode::Mixed => (UvMode::Mixed, "mixed"),
        Mode::Photo => (UvMode::Photo, "photo"),
    };
    let opts = SceneOptions {
        sse_px: a.sse,
        budget_bytes: a.budget,
        uv_mode,
        frame: FrameOptions::default(),
        geomorph: GeomorphOptions {
            enabled: a.geomorph,
            ..Default::default()
        },
        ..Default::default()
    };
    let mut scene = StoreRenderer::open(&a.store, w, h, opts)?;
    let path = match &a.path {
        Some(p) => FlightPath::from_json_file(p)?,
        None => FlightPath::default_for(&scene.store().manifest)?,
    };
    let cams = path.cameras(a.frames.max(2), w, h);
    eprintln!(
        "adapter: {}; {} frames at {w}x{h}, mode {name}{}",
        scene.gpu().describe(),
        cams.len(),
        if a.geomorph { ", geomorphing" } else { "" }
    );
    let report = fly(&mut scene, &cams, name, a.sse, a.budget)?;
    let text = serde_json::to_string_pretty(&report)?;
    write_atomic(&a.out, text.as_bytes())
        .with_context(|| format!("writing {}", a.out.display()))?;
    println!("{text}");
    Ok(())
}
