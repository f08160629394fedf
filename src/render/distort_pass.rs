//! The GPU distortion pass: resamples a frame's pinhole image (see [`super::distortion`])
//! into the output target through the camera's radial distortion (`shaders/distort.wgsl`).

use super::context::GpuContext;
use super::distortion::{DistortedView, NEWTON_STEPS};
use super::target::{OPAQUE_TARGET, RenderTarget, fragment_sampler_entry, fragment_texture_entry};

/// Pipeline, sampler and uniform buffer of the distortion pass.
pub(crate) struct DistortPass {
    pipeline: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    sampler: wgpu::Sampler,
    params: wgpu::Buffer,
}

/// Bytes of the shader's `Params` (five vec4<f32>).
const PARAMS_BYTES: u64 = 80;

impl DistortPass {
    /// Creates the pipeline (output format [`COLOR_FORMAT`](super::target::COLOR_FORMAT), no depth).
    pub fn new(device: &wgpu::Device) -> DistortPass {
        let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("distort.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/distort.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("distort"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: wgpu::BufferSize::new(PARAMS_BYTES),
                    },
                    count: None,
                },
                fragment_texture_entry(1),
                fragment_sampler_entry(2),
            ],
        });
        let pl = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("distort"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("distort"),
            layout: Some(&pl),
            vertex: wgpu::VertexState {
                module: &shader,
                entry_point: Some("vs_full"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState::default(),
            depth_stencil: None,
            multisample: Default::default(),
            fragment: Some(wgpu::FragmentState {
                module: &shader,
                entry_point: Some("fs_distort"),
                compilation_options: Default::default(),
                targets: &OPAQUE_TARGET,
            }),
            multiview_mask: None,
            cache: None,
        });
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("distort"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            mag_filter: wgpu::FilterMode::Linear,
            min_filter: wgpu::FilterMode::Linear,
            mipmap_filter: wgpu::MipmapFilterMode::Nearest,
            ..Default::default()
        });
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("distort params"),
            size: PARAMS_BYTES,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        DistortPass {
            pipeline,
            layout,
            sampler,
            params,
        }
    }

    /// Records the pass into `enc`: every pixel of `dst` (the output camera's size) samples
    /// `src` (the pinhole view's size); `sky` (linear RGB) where no sample exists.
    pub fn encode(
        &self,
        ctx: &GpuContext,
        enc: &mut wgpu::CommandEncoder,
        src: &RenderTarget,
        dst: &RenderTarget,
        view: &DistortedView,
        sky: [f64; 3],
    ) {
        let (o, p) = (&view.output, &view.pinhole);
        let v = [
            o.fx,
            o.fy,
            o.cx,
            o.cy,
            o.k1,
            o.k2,
            NEWTON_STEPS as f64,
            // the largest distorted radius with a ray (beyond: sky); f32::MAX for none
            o.fold_radius().min(f32::MAX as f64),
            p.fx,
            p.fy,
            p.cx,
            p.cy,
            src.width as f64,
            src.height as f64,
            0.0,
            0.0,
            sky[0],
            sky[1],
            sky[2],
            1.0,
        ];
        let bytes: Vec<u8> = v.iter().flat_map(|x| (*x as f32).to_le_bytes()).collect();
        ctx.queue.write_buffer(&self.params, 0, &bytes);
        let group = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("distort"),
            layout: &self.layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: self.params.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: wgpu::BindingResource::TextureView(&src.colour_view),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: wgpu::BindingResource::Sampler(&self.sampler),
                },
            ],
        });
        let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("distort"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &dst.colour_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: None,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &group, &[]);
        pass.draw(0..3, 0..1);
    }
}
