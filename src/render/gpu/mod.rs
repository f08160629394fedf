//! Headless wgpu terrain renderer: offscreen colour + depth target, frames of resident
//! cells, PNG and depth readback. One file per part: `pipelines.rs` (shader, layouts and the
//! five terrain pipelines), `upload.rs` (a cell's buffers and mipmapped textures onto the
//! GPU), `draw.rs` (one frame's terrain pass); this file holds the types they share, the
//! frame entry point [`TerrainRenderer::render`] and readback.

mod draw;
mod pipelines;
mod upload;

use glam::DVec3;

use super::camera::RenderCamera;
pub use super::cell_data::{CellData, MorphData, UvMode, colour_mip_chain, mip_chain};
pub use super::context::GpuContext;
use super::distort_pass::DistortPass;
use super::distortion::DistortedView;
use super::target::RenderTarget;
pub use super::target::{COLOR_FORMAT, DEPTH_FORMAT};
use crate::error::{Error, Result};

/// Bytes of the shader's per-draw `Draw` uniform (mvp, extent, tint, morph, relief,
/// relief_limits).
const DRAW_BYTES: u64 = 144;
/// Byte stride of the per-draw uniform slots (the dynamic-offset alignment wgpu guarantees).
const DRAW_STRIDE: u64 = 256;

/// A cell resident on the GPU.
pub struct GpuCell {
    positions: wgpu::Buffer,
    uvs: Option<wgpu::Buffer>,
    morph: Option<wgpu::Buffer>,
    mip_shift: [f32; 2],
    indices: wgpu::Buffer,
    index_count: u32,
    box_lines: wgpu::Buffer,
    textures: wgpu::BindGroup,
    colour_view: wgpu::TextureView,
    normal_view: wgpu::TextureView,
    /// World origin of the cell-local frame.
    pub origin: DVec3,
    /// (min_x − origin_x, max_y − origin_y, width, height) of the nominal square, metres.
    pub extent_rel: [f32; 4],
    /// Quadtree level (for the overlay).
    pub level: u8,
    /// Range of the relief map, metres (0: no relief mapping).
    pub relief_m: f32,
    /// Smallest up component of a relief-mapped triangle's unit normal.
    pub relief_min_normal_z: f32,
    /// Whether the colour texture's alpha is the share of the base texture (group 1,
    /// binding 4: the chart's own texture under its photo texture) in each texel, the part
    /// relief mapping moves.
    pub share_relief: bool,
    /// Whether group 1, binding 5 holds the chart's orthographic texture.
    pub ortho_beside: bool,
    /// Triangles drawn (surface + skirt).
    pub triangles: u32,
    /// GPU bytes held (buffers and textures with mips).
    pub bytes: u64,
}

impl GpuCell {
    /// Whether the cell carries morph targets (it can be geomorphed).
    pub fn can_morph(&self) -> bool {
        self.morph.is_some()
    }
}

/// One cell of a frame and its morph factor (0 = as stored, 1 = its parent's shape and
/// textures; ignored for cells without morph targets).
#[derive(Clone, Copy)]
pub struct CellDraw<'a> {
    /// The cell.
    pub cell: &'a GpuCell,
    /// Morph factor in [0, 1].
    pub morph: f32,
    /// The parent cell, if resident: its textures are blended in by `morph` (without it the
    /// cell's own textures are sampled coarser instead).
    pub parent: Option<&'a GpuCell>,
}

/// Options of one frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FrameOptions {
    /// Lighting from the normal maps (false: texture colour only).
    pub lit: bool,
    /// Direction towards the sun, world (need not be unit).
    pub sun_dir: DVec3,
    /// Ambient fraction of lit shading, in [0, 1].
    pub ambient: f32,
    /// Sky colour, sRGB 8-bit.
    pub sky: [u8; 3],
    /// Tint cells by quadtree level.
    pub level_overlay: bool,
    /// Draw each cell's world bounding box (lines in its level colour).
    pub bounding_boxes: bool,
}

impl Default for FrameOptions {
    fn default() -> Self {
        FrameOptions {
            lit: true,
            sun_dir: DVec3::new(-0.5, 0.6, 0.62),
            ambient: 0.35,
            sky: [170, 200, 235],
            level_overlay: false,
            bounding_boxes: false,
        }
    }
}

/// Pipelines, uniforms and an offscreen colour + depth target (resizable), plus the pinhole
/// target and pass of distorted frames.
pub struct TerrainRenderer {
    /// The device.
    pub ctx: GpuContext,
    target: RenderTarget,
    /// Pinhole target of distorted frames (allocated on first use, reused while its size holds).
    pinhole: Option<RenderTarget>,
    distort: DistortPass,
    /// Whether the last frame went through the distortion pass (its depth is the pinhole's).
    last_distorted: bool,
    pipeline_ortho: wgpu::RenderPipeline,
    pipeline_uv: wgpu::RenderPipeline,
    pipeline_ortho_morph: wgpu::RenderPipeline,
    pipeline_uv_morph: wgpu::RenderPipeline,
    pipeline_lines: wgpu::RenderPipeline,
    cell_layout: wgpu::BindGroupLayout,
    parent_layout: wgpu::BindGroupLayout,
    /// Group 2 of draws without parent textures (1×1 placeholders).
    no_parent: wgpu::BindGroup,
    /// Group 1's relief map of cells without one: 1×1 R8, the TIN's own height (128).
    no_relief: wgpu::TextureView,
    /// Group 1's chart or orthographic texture of cells without one: 1×1 sRGB black.
    no_colour: wgpu::TextureView,
    frame_layout: wgpu::BindGroupLayout,
    frame_buf: wgpu::Buffer,
    draw_buf: wgpu::Buffer,
    draw_capacity: u64,
    frame_group: wgpu::BindGroup,
    sampler: wgpu::Sampler,
}

fn srgb_to_linear(c: u8) -> f64 {
    let c = c as f64 / 255.0;
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

fn check_size(ctx: &GpuContext, width: u32, height: u32) -> Result<()> {
    let max = ctx.device.limits().max_texture_dimension_2d;
    if width == 0 || height == 0 || width > max || height > max {
        return Err(Error::BadOption(format!(
            "frame size {width}x{height} must be within 1..={max} per side"
        )));
    }
    Ok(())
}

fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

impl TerrainRenderer {
    /// Target width in pixels.
    pub fn width(&self) -> u32 {
        self.target.width
    }

    /// Target height in pixels.
    pub fn height(&self) -> u32 {
        self.target.height
    }

    /// Reallocates the colour and depth target at `width × height` (each in 1..=max texture
    /// size); the next frame renders at that size. A no-op if the size is unchanged.
    pub fn resize(&mut self, width: u32, height: u32) -> Result<()> {
        check_size(&self.ctx, width, height)?;
        if (width, height) != (self.target.width, self.target.height) {
            self.target = RenderTarget::new(&self.ctx.device, width, height);
            self.last_distorted = false;
        }
        Ok(())
    }

    /// Renders `draws` seen from `cam` and waits until the GPU is done; returns the number of
    /// triangles drawn. Without `distorted`, `cam` must have the target's size and renders
    /// straight into it. With `distorted`, `cam` must be `distorted.pinhole` (any size within
    /// the device limits) and `distorted.output` the target's size: the terrain is rendered into
    /// a pinhole target, then resampled through the distortion into the target (the frame's
    /// depth is then only available as the pinhole view's, see [`TerrainRenderer::read_depth`]).
    pub fn render(
        &mut self,
        cam: &RenderCamera,
        draws: &[CellDraw<'_>],
        opts: &FrameOptions,
        distorted: Option<&DistortedView>,
    ) -> Result<u64> {
        let (w, h) = (self.target.width, self.target.height);
        let out_size = distorted.map_or((cam.model.width, cam.model.height), |d| {
            (d.output.width, d.output.height)
        });
        if out_size != (w, h) {
            return Err(Error::BadOption(format!(
                "camera is {}x{} but the target is {w}x{h}",
                out_size.0, out_size.1
            )));
        }
        let sky = opts.sky.map(srgb_to_linear);
        if draws.len() as u64 > self.draw_capacity {
            let device = &self.ctx.device;
            self.draw_capacity = (draws.len() as u64).next_power_of_two();
            self.draw_buf = Self::draw_buffer(device, self.draw_capacity);
            self.frame_group =
                Self::frame_group(device, &self.frame_layout, &self.frame_buf, &self.draw_buf);
        }
        let Some(view) = distorted else {
            self.last_distorted = false;
            return self.draw_terrain(&self.target, cam, draws, opts, sky, None);
        };
        let (pw, ph) = (view.pinhole.width, view.pinhole.height);
        if (cam.model.width, cam.model.height) != (pw, ph) {
            return Err(Error::BadOption(format!(
                "camera is {}x{} but the pinhole view is {pw}x{ph}",
                cam.model.width, cam.model.height
            )));
        }
        check_size(&self.ctx, pw, ph)?;
        let pinhole = match self.pinhole.take() {
            Some(t) if (t.width, t.height) == (pw, ph) => t,
            _ => RenderTarget::new(&self.ctx.device, pw, ph),
        };
        let r = self.draw_terrain(&pinhole, cam, draws, opts, sky, Some((view, &self.target)));
        self.pinhole = Some(pinhole);
        self.last_distorted = true;
        r
    }

    /// Copies the last rendered frame back (sRGB RGBA8, row 0 at the top).
    pub fn read_rgba(&self) -> Result<image::RgbaImage> {
        let t = &self.target;
        let out = t.read(
            &self.ctx.device,
            &self.ctx.queue,
            &t.colour,
            wgpu::TextureAspect::All,
            4,
        )?;
        image::RgbaImage::from_raw(t.width, t.height, out)
            .ok_or_else(|| Error::Gpu("readback size mismatch".into()))
    }

    /// Copies the last frame's depth buffer back: `width × height` values, row 0 at the top,
    /// reverse-Z (`near / z_camera`, 0 where nothing was drawn). Needs a backend that can
    /// copy depth textures (Vulkan, Metal, DX12; not GL). Fails after a distorted frame (its
    /// depth exists only in the pinhole view's geometry; render it with distortion off).
    pub fn read_depth(&self) -> Result<Vec<f32>> {
        if self.last_distorted {
            return Err(Error::BadOption(
                "the depth of a distorted frame is not available (render it with distortion off)"
                    .into(),
            ));
        }
        let t = &self.target;
        let out = t.read(
            &self.ctx.device,
            &self.ctx.queue,
            &t.depth,
            wgpu::TextureAspect::DepthOnly,
            4,
        )?;
        Ok(out
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect())
    }
}
