//! Headless wgpu: device set-up, cell uploads (vertex/index buffers, mipmapped colour
//! texture and normal map), the terrain pipelines, offscreen frames and PNG readback.

use glam::DVec3;
use wgpu::util::DeviceExt;

use super::camera::RenderCamera;
pub use super::cell_data::{CellData, MorphData, UvMode, colour_mip_chain, mip_chain};
pub use super::context::GpuContext;
use super::distort_pass::DistortPass;
use super::distortion::DistortedView;
pub use super::target::{COLOR_FORMAT, DEPTH_FORMAT};
use super::target::{OPAQUE_TARGET, RenderTarget};
use crate::error::{Error, Result};
use crate::store::CellRecord;

/// Bytes of the shader's per-draw `Draw` uniform (mvp, extent, tint, morph).
const DRAW_BYTES: u64 = 112;
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

fn level_tint(level: u8) -> [f32; 4] {
    const T: [[f32; 3]; 8] = [
        [0.9, 0.1, 0.1],
        [0.9, 0.6, 0.1],
        [0.8, 0.9, 0.1],
        [0.2, 0.8, 0.2],
        [0.1, 0.8, 0.8],
        [0.2, 0.3, 0.9],
        [0.6, 0.2, 0.9],
        [0.9, 0.2, 0.7],
    ];
    let t = T[level as usize % T.len()];
    [t[0], t[1], t[2], 1.0]
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
    /// Creates pipelines and a `width × height` target (each in 1..=max texture size).
    pub fn new(ctx: GpuContext, width: u32, height: u32) -> Result<TerrainRenderer> {
        check_size(&ctx, width, height)?;
        let device = &ctx.device;
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("terrain.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/terrain.wgsl").into()),
        });
        let uniform = |binding, dynamic: bool| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: dynamic,
                min_binding_size: None,
            },
            count: None,
        };
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("frame"),
            entries: &[uniform(0, false), uniform(1, true)],
        });
        let tex = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::FRAGMENT,
            ty: wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Float { filterable: true },
                view_dimension: wgpu::TextureViewDimension::D2,
                multisampled: false,
            },
            count: None,
        };
        let cell_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cell"),
            entries: &[
                tex(0),
                tex(1),
                wgpu::BindGroupLayoutEntry {
                    binding: 2,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                    count: None,
                },
            ],
        });
        let parent_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("parent textures"),
            entries: &[tex(0), tex(1)],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("terrain"),
            bind_group_layouts: &[
                Some(&frame_layout),
                Some(&cell_layout),
                Some(&parent_layout),
            ],
            immediate_size: 0,
        });
        let pos_layout = wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &[wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
                offset: 0,
                shader_location: 0,
            }],
        };
        let uv_layout = wgpu::VertexBufferLayout {
            array_stride: 8,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &[wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x2,
                offset: 0,
                shader_location: 1,
            }],
        };
        let make = |entry: &str,
                    buffers: &[Option<wgpu::VertexBufferLayout>],
                    topology: wgpu::PrimitiveTopology,
                    fragment: &str| {
            let lines = topology == wgpu::PrimitiveTopology::LineList;
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(entry),
                layout: Some(&layout),
                vertex: wgpu::VertexState {
                    module: &shader,
                    entry_point: Some(entry),
                    compilation_options: Default::default(),
                    buffers,
                },
                primitive: wgpu::PrimitiveState {
                    topology,
                    cull_mode: None,
                    ..Default::default()
                },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(!lines),
                    depth_compare: Some(if lines {
                        wgpu::CompareFunction::GreaterEqual
                    } else {
                        wgpu::CompareFunction::Greater
                    }),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &shader,
                    entry_point: Some(fragment),
                    compilation_options: Default::default(),
                    targets: &OPAQUE_TARGET,
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        let tris = wgpu::PrimitiveTopology::TriangleList;
        let pipeline_ortho = make("vs_ortho", &[Some(pos_layout.clone())], tris, "fs_main");
        let pipeline_lines = make(
            "vs_ortho",
            &[Some(pos_layout.clone())],
            wgpu::PrimitiveTopology::LineList,
            "fs_line",
        );
        let morph_layout = wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &[wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
                offset: 0,
                shader_location: 2,
            }],
        };
        let pipeline_uv = make(
            "vs_uv",
            &[Some(pos_layout.clone()), Some(uv_layout.clone())],
            tris,
            "fs_main",
        );
        let pipeline_ortho_morph = make(
            "vs_ortho_morph",
            &[Some(pos_layout.clone()), Some(morph_layout.clone())],
            tris,
            "fs_main",
        );
        let pipeline_uv_morph = make(
            "vs_uv_morph",
            &[Some(pos_layout), Some(uv_layout), Some(morph_layout)],
            tris,
            "fs_main",
        );
        let frame_buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frame uniforms"),
            size: 32,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("terrain"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Linear,
            anisotropy_clamp: 8,
            ..Default::default()
        });
        let placeholder = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("no parent"),
            size: wgpu::Extent3d {
                width: 1,
                height: 1,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba8Unorm,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let pv = placeholder.create_view(&Default::default());
        let no_parent = Self::parent_group(device, &parent_layout, &pv, &pv);
        let target = RenderTarget::new(device, width, height);
        let distort = DistortPass::new(device);
        let draw_capacity = 64;
        let draw_buf = Self::draw_buffer(device, draw_capacity);
        let frame_group = Self::frame_group(device, &frame_layout, &frame_buf, &draw_buf);
        Ok(TerrainRenderer {
            ctx,
            target,
            pinhole: None,
            distort,
            last_distorted: false,
            pipeline_ortho,
            pipeline_uv,
            pipeline_ortho_morph,
            pipeline_uv_morph,
            pipeline_lines,
            cell_layout,
            parent_layout,
            no_parent,
            frame_layout,
            frame_buf,
            draw_buf,
            draw_capacity,
            frame_group,
            sampler,
        })
    }

    fn parent_group(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        colour: &wgpu::TextureView,
        normal: &wgpu::TextureView,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("parent textures"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(colour),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(normal),
                },
            ],
        })
    }

    fn draw_buffer(device: &wgpu::Device, capacity: u64) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("draw uniforms"),
            size: capacity * DRAW_STRIDE,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    fn frame_group(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        frame: &wgpu::Buffer,
        draw: &wgpu::Buffer,
    ) -> wgpu::BindGroup {
        device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("frame"),
            layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: frame.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer: draw,
                        offset: 0,
                        size: wgpu::BufferSize::new(DRAW_BYTES),
                    }),
                },
            ],
        })
    }

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

    fn texture(
        &self,
        label: &str,
        mips: &[image::RgbaImage],
        format: wgpu::TextureFormat,
    ) -> (wgpu::Texture, u64) {
        let (w, h) = mips[0].dimensions();
        let tex = self.ctx.device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width: w,
                height: h,
                depth_or_array_layers: 1,
            },
            mip_level_count: mips.len() as u32,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
            view_formats: &[],
        });
        let mut bytes = 0;
        for (level, img) in mips.iter().enumerate() {
            let (mw, mh) = img.dimensions();
            self.ctx.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &tex,
                    mip_level: level as u32,
                    origin: wgpu::Origin3d::ZERO,
                    aspect: wgpu::TextureAspect::All,
                },
                img.as_raw(),
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(4 * mw),
                    rows_per_image: Some(mh),
                },
                wgpu::Extent3d {
                    width: mw,
                    height: mh,
                    depth_or_array_layers: 1,
                },
            );
            bytes += img.as_raw().len() as u64;
        }
        (tex, bytes)
    }

    /// Uploads a cell. Fails on an empty mesh or texture, or a texture over the device limit.
    pub fn upload(&self, rec: &CellRecord, data: &CellData) -> Result<GpuCell> {
        let max = self.ctx.device.limits().max_texture_dimension_2d;
        for (what, mips) in [
            ("texture", &data.colour_mips),
            ("normal map", &data.normal_mips),
        ] {
            let (w, h) = mips.first().map(|m| m.dimensions()).unwrap_or((0, 0));
            if w == 0 || h == 0 || w > max || h > max {
                return Err(Error::Gpu(format!(
                    "cell {}: {what} of {w}x{h} texels cannot be uploaded (limit {max})",
                    rec.id
                )));
            }
        }
        if data.mesh.triangles.is_empty() {
            return Err(Error::Gpu(format!("cell {}: empty mesh", rec.id)));
        }
        if let Some(m) = &data.morph {
            if m.targets.len() != data.mesh.positions.len() {
                return Err(Error::Gpu(format!(
                    "cell {}: {} morph targets for {} vertices",
                    rec.id,
                    m.targets.len(),
                    data.mesh.positions.len()
                )));
            }
        }
        let device = &self.ctx.device;
        let pos: Vec<f32> = data.mesh.positions.iter().flatten().copied().collect();
        let idx: Vec<u8> = data
            .mesh
            .triangles
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let positions = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("positions"),
            contents: &f32_bytes(&pos),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let uvs = data.uvs.as_ref().map(|uv| {
            let flat: Vec<f32> = uv.iter().flatten().copied().collect();
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("uvs"),
                contents: &f32_bytes(&flat),
                usage: wgpu::BufferUsages::VERTEX,
            })
        });
        let morph = data.morph.as_ref().map(|m| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("morph targets"),
                contents: &f32_bytes(m.targets.as_flattened()),
                usage: wgpu::BufferUsages::VERTEX,
            })
        });
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("indices"),
            contents: &idx,
            usage: wgpu::BufferUsages::INDEX,
        });
        let (colour, cb) = self.texture(
            "colour",
            &data.colour_mips,
            wgpu::TextureFormat::Rgba8UnormSrgb,
        );
        let (normal, nb) =
            self.texture("normal", &data.normal_mips, wgpu::TextureFormat::Rgba8Unorm);
        let cv = colour.create_view(&Default::default());
        let nv = normal.create_view(&Default::default());
        let textures = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(&rec.id),
            layout: &self.cell_layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: wgpu::BindingResource::TextureView(&cv),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&nv),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        });
        let origin = DVec3::from(rec.origin);
        let (lo, hi) = (
            (DVec3::from(rec.bbox_min) - origin).as_vec3(),
            (DVec3::from(rec.bbox_max) - origin).as_vec3(),
        );
        let corner = |k: usize| {
            [
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            ]
        };
        let mut lines = Vec::with_capacity(72);
        for a in 0..8usize {
            for bit in [1, 2, 4] {
                if a & bit == 0 {
                    lines.extend(corner(a));
                    lines.extend(corner(a | bit));
                }
            }
        }
        let box_lines = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("bbox lines"),
            contents: &f32_bytes(&lines),
            usage: wgpu::BufferUsages::VERTEX,
        });
        let e = rec.extent;
        let bytes = pos.len() as u64 * 4
            + idx.len() as u64
            + data.uvs.as_ref().map_or(0, |u| u.len() as u64 * 8)
            + data
                .morph
                .as_ref()
                .map_or(0, |m| m.targets.len() as u64 * 12)
            + cb
            + nb;
        Ok(GpuCell {
            positions,
            uvs,
            morph,
            mip_shift: data
                .morph
                .as_ref()
                .map_or([0.0; 2], |m| [m.colour_shift, m.normal_shift]),
            indices,
            index_count: data.mesh.triangles.len() as u32 * 3,
            box_lines,
            textures,
            colour_view: cv,
            normal_view: nv,
            origin,
            extent_rel: [
                (e.min_x - origin.x) as f32,
                (e.max_y - origin.y) as f32,
                e.width() as f32,
                e.height() as f32,
            ],
            level: rec.level,
            triangles: data.mesh.triangles.len() as u32,
            bytes,
        })
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

    /// Draws the terrain into `target` (then, with `distort`, resamples it into that target).
    fn draw_terrain(
        &self,
        target: &RenderTarget,
        cam: &RenderCamera,
        draws: &[CellDraw<'_>],
        opts: &FrameOptions,
        sky: [f64; 3],
        distort: Option<(&DistortedView, &RenderTarget)>,
    ) -> Result<u64> {
        let device = &self.ctx.device;
        let sun = opts.sun_dir.try_normalize().unwrap_or(DVec3::Z).as_vec3();
        let frame = [
            sun.x,
            sun.y,
            sun.z,
            0.0,
            f32::from(u8::from(opts.lit)),
            opts.ambient.clamp(0.0, 1.0),
            f32::from(u8::from(opts.level_overlay)),
            0.0,
        ];
        self.ctx
            .queue
            .write_buffer(&self.frame_buf, 0, &f32_bytes(&frame));
        // A draw morphs only if it has targets and a positive factor.
        let morph_of = |d: &CellDraw| {
            if d.cell.morph.is_some() && d.morph > 0.0 {
                d.morph.min(1.0)
            } else {
                0.0
            }
        };
        if !draws.is_empty() {
            let mut bytes = vec![0u8; draws.len() * DRAW_STRIDE as usize];
            for (i, d) in draws.iter().enumerate() {
                let c = d.cell;
                let mut v: Vec<f32> = cam.mvp_for_origin(c.origin).to_cols_array().to_vec();
                v.extend_from_slice(&c.extent_rel);
                v.extend_from_slice(&level_tint(c.level));
                let has_parent = f32::from(u8::from(d.parent.is_some()));
                v.extend_from_slice(&[morph_of(d), c.mip_shift[0], c.mip_shift[1], has_parent]);
                let b = f32_bytes(&v);
                bytes[i * DRAW_STRIDE as usize..i * DRAW_STRIDE as usize + b.len()]
                    .copy_from_slice(&b);
            }
            self.ctx.queue.write_buffer(&self.draw_buf, 0, &bytes);
        }
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("frame"),
        });
        let mut triangles = 0u64;
        // Parent textures of morphing draws (bind groups live until the pass is recorded).
        let parent_groups: Vec<Option<wgpu::BindGroup>> = draws
            .iter()
            .map(|d| match d.parent {
                Some(p) if morph_of(d) > 0.0 => Some(Self::parent_group(
                    device,
                    &self.parent_layout,
                    &p.colour_view,
                    &p.normal_view,
                )),
                _ => None,
            })
            .collect();
        {
            let frame_group = &self.frame_group;
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("terrain"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target.colour_view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: sky[0],
                            g: sky[1],
                            b: sky[2],
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &target.depth_view,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            for (i, d) in draws.iter().enumerate() {
                let c = d.cell;
                let morph = c.morph.as_ref().filter(|_| morph_of(d) > 0.0);
                match (&c.uvs, morph) {
                    (Some(uv), None) => {
                        pass.set_pipeline(&self.pipeline_uv);
                        pass.set_vertex_buffer(1, uv.slice(..));
                    }
                    (Some(uv), Some(m)) => {
                        pass.set_pipeline(&self.pipeline_uv_morph);
                        pass.set_vertex_buffer(1, uv.slice(..));
                        pass.set_vertex_buffer(2, m.slice(..));
                    }
                    (None, None) => pass.set_pipeline(&self.pipeline_ortho),
                    (None, Some(m)) => {
                        pass.set_pipeline(&self.pipeline_ortho_morph);
                        pass.set_vertex_buffer(1, m.slice(..));
                    }
                }
                pass.set_bind_group(0, frame_group, &[(i as u64 * DRAW_STRIDE) as u32]);
                pass.set_bind_group(1, &c.textures, &[]);
                pass.set_bind_group(2, parent_groups[i].as_ref().unwrap_or(&self.no_parent), &[]);
                pass.set_vertex_buffer(0, c.positions.slice(..));
                pass.set_index_buffer(c.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(0..c.index_count, 0, 0..1);
                triangles += c.triangles as u64;
            }
            if opts.bounding_boxes {
                pass.set_pipeline(&self.pipeline_lines);
                for (i, d) in draws.iter().enumerate() {
                    pass.set_bind_group(0, frame_group, &[(i as u64 * DRAW_STRIDE) as u32]);
                    pass.set_bind_group(1, &d.cell.textures, &[]);
                    pass.set_bind_group(2, &self.no_parent, &[]);
                    pass.set_vertex_buffer(0, d.cell.box_lines.slice(..));
                    pass.draw(0..24, 0..1);
                }
            }
        }
        if let Some((view, out)) = distort {
            self.distort
                .encode(&self.ctx, &mut enc, target, out, view, sky);
        }
        self.ctx.queue.submit([enc.finish()]);
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for the frame failed: {e}")))?;
        Ok(triangles)
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
