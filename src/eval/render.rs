//! cliffmap's own renders of a store for evaluation: headless, unlit, one texture mode.

use std::path::Path;

use image::RgbImage;

use crate::camera::CameraModel;
use crate::error::{Error, Result};
use crate::render::{FrameOptions, SceneOptions, StoreRenderer, UvMode};

/// Renders `cameras` (all of one size) of the store in `dir` in each of `modes`, unlit (the
/// texture colour alone, as `cliffmap render --unlit`), with screen-space error `sse_px`,
/// `supersample` × `supersample` samples per pixel ([`crate::render::downsample_rgba`];
/// the LOD is the output size's): `out[mode][camera]`. Errors without a GPU driver (Mesa's
/// software drivers suffice) or for cameras of different sizes.
pub fn render_views(
    dir: &Path,
    cameras: &[CameraModel],
    modes: &[UvMode],
    sse_px: f64,
    supersample: u32,
) -> Result<Vec<Vec<RgbImage>>> {
    render_views_relief(dir, cameras, modes, sse_px, supersample, true)
}

/// [`render_views`] with relief mapping on or off ([`SceneOptions::relief`]).
pub fn render_views_relief(
    dir: &Path,
    cameras: &[CameraModel],
    modes: &[UvMode],
    sse_px: f64,
    supersample: u32,
    relief: bool,
) -> Result<Vec<Vec<RgbImage>>> {
    let Some(first) = cameras.first() else {
        return Ok(vec![Vec::new(); modes.len()]);
    };
    let (w, h) = (first.width, first.height);
    if let Some(c) = cameras.iter().find(|c| (c.width, c.height) != (w, h)) {
        return Err(Error::BadOption(format!(
            "evaluation views differ in size: {w}x{h} and {}x{}",
            c.width, c.height
        )));
    }
    let s = supersample.clamp(1, 8);
    let mut out = Vec::with_capacity(modes.len());
    for &mode in modes {
        let opts = SceneOptions {
            sse_px: sse_px * s as f64,
            uv_mode: mode,
            frame: FrameOptions {
                lit: false,
                ..FrameOptions::default()
            },
            relief,
            ..SceneOptions::default()
        };
        let mut scene = StoreRenderer::open(dir, w * s, h * s, opts)?;
        let mut imgs = Vec::with_capacity(cameras.len());
        for cam in cameras {
            scene.frame(&cam.resized(w * s, h * s), true)?;
            let img = crate::render::downsample_rgba(&scene.read_rgba()?, s);
            imgs.push(image::DynamicImage::ImageRgba8(img).to_rgb8());
        }
        out.push(imgs);
    }
    Ok(out)
}
