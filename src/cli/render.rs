//! `cliffmap render`: one frame of a store from a camera, written as PNG.

use std::path::PathBuf;

use anyhow::Context;
use cliffmap::camera::camera_from_json_file;
use cliffmap::fsutil::write_png_atomic;
use cliffmap::render::{
    DistortionMode, FrameOptions, GeomorphOptions, Overlay, SceneOptions, StoreRenderer, UvMode,
};

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
    /// Tint cells by quadtree level (same as `--overlay levels`).
    #[arg(long)]
    levels: bool,
    /// Texture source: each cell's best texture (photo-enhanced, else reparameterized, else
    /// orthographic; the default), or force the reparameterized or orthographic one.
    #[arg(long, value_enum, default_value_t = TextureMode::Photo)]
    mode: TextureMode,
    /// Overlay: level colours + bounding boxes, the per-texel stretch heat map, or the
    /// per-texel photo share.
    #[arg(long, value_enum, default_value_t = OverlayArg::None)]
    overlay: OverlayArg,
    /// Blend cells towards their parents' shape and texel density near LOD switches.
    #[arg(long)]
    geomorph: bool,
    /// Render a camera with radial distortion (k1, k2) as a pinhole (by default its frame is
    /// distorted like the photo, pixel for pixel).
    #[arg(long)]
    no_distortion: bool,
    /// Look textures up where the view ray meets the TIN, not where it meets the DEM surface
    /// the store's relief maps describe (relief mapping is on by default; docs/rendering.md).
    #[arg(long)]
    no_relief: bool,
    /// Samples per pixel side (1..=4): the frame is rendered this many times larger and
    /// averaged in linear light (the LOD stays that of the output size).
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u32).range(1..=4))]
    supersample: u32,
}

/// Texture source of `render` (and `view`).
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum TextureMode {
    /// Orthographic files of every cell.
    Ortho,
    /// Each cell's reparameterized variant where it has one (as stored).
    Reparam,
    /// Each cell's best texture: photo-enhanced where present, else as reparam (the default).
    Photo,
}

impl TextureMode {
    /// The renderer mode.
    pub fn uv_mode(self) -> UvMode {
        match self {
            TextureMode::Ortho => UvMode::Ortho,
            TextureMode::Reparam => UvMode::Mixed,
            TextureMode::Photo => UvMode::Photo,
        }
    }
}

/// Overlay flag values.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum OverlayArg {
    /// No overlay.
    None,
    /// Level colours and cell bounding boxes.
    Levels,
    /// Per-texel stretch heat map (blue 1, yellow 2, red ≥ 4).
    Stretch,
    /// Per-texel photo share: yellow where the projected photos supply the colour, green
    /// half, blue none (the cell's existing texture), grey cells without a photo texture.
    PhotoShare,
}

impl OverlayArg {
    /// The renderer overlay.
    pub fn overlay(self) -> Overlay {
        match self {
            OverlayArg::None => Overlay::None,
            OverlayArg::Levels => Overlay::Levels,
            OverlayArg::Stretch => Overlay::Stretch,
            OverlayArg::PhotoShare => Overlay::PhotoShare,
        }
    }
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
    let (ow, oh) = a.size;
    // supersampled internally, at most 16384 pixels a side
    let ss = (1..=a.supersample)
        .rev()
        .find(|s| ow * s <= 16384 && oh * s <= 16384)
        .unwrap_or(1);
    let (w, h) = (ow * ss, oh * ss);
    let cam = camera_from_json_file(&a.camera, (ow, oh))?.resized(w, h);
    let overlay = match (a.unlit, a.levels, a.overlay.overlay()) {
        // --unlit is the texture colour alone: no tint or boxes, but an overlay that replaces
        // the texture is shown as it is (unshaded)
        (true, _, o) if o.replaces_texture() => o,
        (true, _, _) => Overlay::None,
        (false, true, _) => Overlay::Levels,
        (false, false, o) => o,
    };
    let opts = SceneOptions {
        sse_px: a.sse * ss as f64,
        uv_mode: a.mode.uv_mode(),
        overlay,
        frame: FrameOptions {
            lit: !a.unlit,
            ..Default::default()
        },
        geomorph: GeomorphOptions {
            enabled: a.geomorph,
            ..Default::default()
        },
        distortion: if a.no_distortion {
            DistortionMode::Off
        } else {
            DistortionMode::Auto
        },
        relief: !a.no_relief,
        ..Default::default()
    };
    let store = cliffmap::store::Store::open(&a.store)?;
    let place = cliffmap::store::CameraPlacement::of(&store, &cam)?;
    if place.is_underground() {
        eprintln!(
            "warning: {}: the camera is {}; it sees the terrain from below",
            a.camera.display(),
            place.describe()
        );
    }
    let mut scene = StoreRenderer::open(&a.store, w, h, opts)?;
    eprintln!("adapter: {}", scene.gpu().describe());
    if matches!(a.mode, TextureMode::Photo) && !scene.has_photo() {
        eprintln!(
            "note: the store has no photo-enhanced textures (run `cliffmap project`); showing reparam"
        );
    }
    if let Some(d) = scene.distorted_view(&cam)? {
        eprintln!(
            "lens distortion k1 {} k2 {}: rasterized as a {}x{} pinhole view (focal x{:.3}), then resampled{}",
            cam.k1,
            cam.k2,
            d.pinhole.width,
            d.pinhole.height,
            d.scale,
            if d.limited {
                " (view shrunk to the texture size limit: parts are undersampled)"
            } else {
                ""
            }
        );
    }
    let r = scene.frame(&cam, true)?;
    let img = cliffmap::render::downsample_rgba(&scene.read_rgba()?, ss);
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
