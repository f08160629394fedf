//! The terrain shader's bind-group layouts and pipelines (ortho or chart UVs, with or
//! without morph targets, and the bounding-box lines), created once per renderer, and the
//! bind groups the frames rebuild.

use wgpu::util::DeviceExt;

use super::{DRAW_BYTES, DRAW_STRIDE, GpuContext, TerrainRenderer, check_size};
use crate::error::Result;
use crate::render::distort_pass::DistortPass;
use crate::render::target::{
    DEPTH_FORMAT, OPAQUE_TARGET, RenderTarget, fragment_sampler_entry, fragment_texture_entry,
};

impl TerrainRenderer {
    /// Creates pipelines and a `width × height` target (each in 1..=max texture size).
    pub fn new(ctx: GpuContext, width: u32, height: u32) -> Result<TerrainRenderer> {
        check_size(&ctx, width, height)?;
        let device = &ctx.device;
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("terrain.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../shaders/terrain.wgsl").into()),
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
        let tex = fragment_texture_entry;
        let cell_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("cell"),
            entries: &[
                tex(0),
                tex(1),
                fragment_sampler_entry(2),
                tex(3),
                tex(4),
                tex(5),
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
        // texture coordinates and the vertex's relief reach
        let uv_layout = wgpu::VertexBufferLayout {
            array_stride: 12,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &[wgpu::VertexAttribute {
                format: wgpu::VertexFormat::Float32x3,
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
        // (zero texels: draws without a parent never sample it)
        let pv = Self::one_texel(
            &ctx,
            "no parent",
            wgpu::TextureFormat::Rgba8Unorm,
            &[0, 0, 0, 0],
        );
        let no_parent = Self::parent_group(device, &parent_layout, &pv, &pv);
        // one placeholder of each kind for every cell that lacks the texture (never sampled
        // by such a cell's draw, but every binding of group 1 needs a view)
        let no_relief =
            Self::one_texel(&ctx, "no relief map", wgpu::TextureFormat::R8Unorm, &[128]);
        let no_colour = Self::one_texel(
            &ctx,
            "no chart or orthographic texture",
            wgpu::TextureFormat::Rgba8UnormSrgb,
            &[0, 0, 0, 255],
        );
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
            no_relief,
            no_colour,
            frame_layout,
            frame_buf,
            draw_buf,
            draw_capacity,
            frame_group,
            sampler,
        })
    }

    /// A view of a 1×1 texture of `format` holding `texel`.
    fn one_texel(
        ctx: &GpuContext,
        label: &str,
        format: wgpu::TextureFormat,
        texel: &[u8],
    ) -> wgpu::TextureView {
        ctx.device
            .create_texture_with_data(
                &ctx.queue,
                &wgpu::TextureDescriptor {
                    label: Some(label),
                    size: wgpu::Extent3d {
                        width: 1,
                        height: 1,
                        depth_or_array_layers: 1,
                    },
                    mip_level_count: 1,
                    sample_count: 1,
                    dimension: wgpu::TextureDimension::D2,
                    format,
                    usage: wgpu::TextureUsages::TEXTURE_BINDING,
                    view_formats: &[],
                },
                wgpu::util::TextureDataOrder::LayerMajor,
                texel,
            )
            .create_view(&Default::default())
    }

    pub(super) fn parent_group(
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

    pub(super) fn draw_buffer(device: &wgpu::Device, capacity: u64) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("draw uniforms"),
            size: capacity * DRAW_STRIDE,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    pub(super) fn frame_group(
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
}
