//! Offscreen render targets (colour + depth of one size) and their readback.

use crate::error::{Error, Result};

/// Colour target format: sRGB, so unlit output bytes equal the texture's bytes.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// The colour target of every pipeline: [`COLOR_FORMAT`], no blending, all channels.
pub(crate) const OPAQUE_TARGET: [Option<wgpu::ColorTargetState>; 1] =
    [Some(wgpu::ColorTargetState {
        format: COLOR_FORMAT,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    })];
/// Bind-group-layout entry of a filterable 2-D float texture read by the fragment stage.
pub(crate) fn fragment_texture_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Texture {
            sample_type: wgpu::TextureSampleType::Float { filterable: true },
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        count: None,
    }
}

/// Bind-group-layout entry of a filtering sampler used by the fragment stage.
pub(crate) fn fragment_sampler_entry(binding: u32) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::FRAGMENT,
        ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
        count: None,
    }
}

/// Depth format (reverse-Z: cleared to 0, closer = larger).
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// A colour texture ([`COLOR_FORMAT`]) and a depth texture ([`DEPTH_FORMAT`]) of `width × height`
/// pixels; both can be copied out, the colour one can also be sampled.
pub(crate) struct RenderTarget {
    pub colour: wgpu::Texture,
    pub colour_view: wgpu::TextureView,
    pub depth: wgpu::Texture,
    pub depth_view: wgpu::TextureView,
    pub width: u32,
    pub height: u32,
}

impl RenderTarget {
    /// Allocates a target (sizes must be within the device limits; the caller checks).
    pub fn new(device: &wgpu::Device, width: u32, height: u32) -> RenderTarget {
        let size = wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        };
        let colour = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("colour target"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: COLOR_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::COPY_SRC
                | wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        });
        let depth = device.create_texture(&wgpu::TextureDescriptor {
            label: Some("depth target"),
            size,
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: DEPTH_FORMAT,
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        });
        let colour_view = colour.create_view(&Default::default());
        let depth_view = depth.create_view(&Default::default());
        RenderTarget {
            colour,
            colour_view,
            depth,
            depth_view,
            width,
            height,
        }
    }

    /// Copies one aspect of `texture` (a full-size texture of this target) into tightly packed
    /// rows, row 0 at the top (the copy itself uses rows padded to 256 bytes).
    pub fn read(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        texture: &wgpu::Texture,
        aspect: wgpu::TextureAspect,
        bytes_per_pixel: u32,
    ) -> Result<Vec<u8>> {
        let (width, height) = (self.width, self.height);
        let row = bytes_per_pixel * width;
        let padded =
            row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
        let buf = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size: padded as u64 * height as u64,
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("readback"),
        });
        enc.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buf,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded),
                    rows_per_image: Some(height),
                },
            },
            wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
        );
        queue.submit([enc.finish()]);
        let (tx, rx) = std::sync::mpsc::channel();
        buf.slice(..).map_async(wgpu::MapMode::Read, move |r| {
            let _ = tx.send(r);
        });
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Gpu(format!("waiting for the readback failed: {e}")))?;
        rx.recv()
            .map_err(|_| Error::Gpu("readback was cancelled".into()))?
            .map_err(|e| Error::Gpu(format!("cannot map the readback buffer: {e}")))?;
        let mut out = Vec::with_capacity((row * height) as usize);
        {
            let view = buf
                .get_mapped_range(..)
                .map_err(|e| Error::Gpu(format!("cannot read the readback buffer: {e}")))?;
            for r in 0..height as usize {
                out.extend_from_slice(
                    &view[r * padded as usize..r * padded as usize + row as usize],
                );
            }
        }
        buf.unmap();
        Ok(out)
    }
}
