//! A cell onto the GPU: vertex, UV, morph-target and index buffers, its mipmapped colour
//! texture (sRGB) and normal map, its bounding-box lines, and the bytes it holds.

use glam::DVec3;
use wgpu::util::DeviceExt;

use super::{CellData, GpuCell, TerrainRenderer, f32_bytes};
use crate::error::{Error, Result};
use crate::store::CellRecord;

/// The relief reach of vertices that have none (orthographic coordinates: unbounded), as the
/// shader's `NO_REACH`.
const NO_REACH: f32 = 1.0e9;

impl TerrainRenderer {
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
        check_uploadable(rec, data, self.ctx.device.limits().max_texture_dimension_2d)?;
        let mesh = self.mesh_buffers(data);
        let (colour, cb) = self.texture(
            "colour",
            &data.colour_mips,
            wgpu::TextureFormat::Rgba8UnormSrgb,
        );
        let (normal, nb) =
            self.texture("normal", &data.normal_mips, wgpu::TextureFormat::Rgba8Unorm);
        let cv = colour.create_view(&Default::default());
        let nv = normal.create_view(&Default::default());
        // the relief map, the base texture whose share relief mapping moves and the chart's
        // orthographic texture, each else the shared placeholder
        let relief = data.relief.as_ref().map(|img| self.relief_view(img));
        let colour_extra = |label: &str, mips: &Option<Vec<image::RgbaImage>>| {
            mips.as_ref().map(|m| {
                let (tex, bytes) = self.texture(label, m, wgpu::TextureFormat::Rgba8UnormSrgb);
                (tex.create_view(&Default::default()), bytes)
            })
        };
        let base = colour_extra("base colour", &data.base_mips);
        let ortho = colour_extra("chart's orthographic colour", &data.ortho_mips);
        let extra_bytes: u64 = [&relief, &base, &ortho]
            .iter()
            .filter_map(|t| t.as_ref().map(|(_, b)| *b))
            .sum();
        let textures = self.cell_bind_group(
            &rec.id,
            [
                &cv,
                &nv,
                relief.as_ref().map_or(&self.no_relief, |(v, _)| v),
                base.as_ref().map_or(&self.no_colour, |(v, _)| v),
                ortho.as_ref().map_or(&self.no_colour, |(v, _)| v),
            ],
        );
        let origin = DVec3::from(rec.origin);
        let box_lines = self
            .ctx
            .device
            .create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("bbox lines"),
                contents: &f32_bytes(&bbox_lines(rec)),
                usage: wgpu::BufferUsages::VERTEX,
            });
        let e = rec.extent;
        Ok(GpuCell {
            positions: mesh.positions,
            uvs: mesh.uvs,
            morph: mesh.morph,
            mip_shift: data
                .morph
                .as_ref()
                .map_or([0.0; 2], |m| [m.colour_shift, m.normal_shift]),
            indices: mesh.indices,
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
            relief_m: if data.relief.is_some() {
                data.relief_m
            } else {
                0.0
            },
            relief_min_normal_z: data.relief_min_normal_z,
            share_relief: data.base_mips.is_some() && data.relief.is_some(),
            ortho_beside: data.ortho_mips.is_some() && data.relief.is_some(),
            triangles: data.mesh.triangles.len() as u32,
            bytes: mesh.bytes + cb + nb + extra_bytes,
        })
    }

    /// The vertex buffers (positions; UVs with each vertex's relief reach; morph targets)
    /// and the index buffer of a cell's mesh, and their bytes.
    fn mesh_buffers(&self, data: &CellData) -> MeshBuffers {
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
            // (u, v, relief reach) per vertex; without a reach, unbounded
            let reach = data.relief_reach.as_deref().unwrap_or(&[]);
            let flat: Vec<f32> = uv
                .iter()
                .enumerate()
                .flat_map(|(k, t)| [t[0], t[1], reach.get(k).copied().unwrap_or(NO_REACH)])
                .collect();
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
        let bytes = pos.len() as u64 * 4
            + idx.len() as u64
            + data.uvs.as_ref().map_or(0, |u| u.len() as u64 * 12)
            + data
                .morph
                .as_ref()
                .map_or(0, |m| m.targets.len() as u64 * 12);
        MeshBuffers {
            positions,
            uvs,
            morph,
            indices,
            bytes,
        }
    }

    /// The relief map as an R8 texture (one level, read texel by texel) and its bytes.
    fn relief_view(&self, img: &image::GrayImage) -> (wgpu::TextureView, u64) {
        let tex = self.ctx.device.create_texture_with_data(
            &self.ctx.queue,
            &wgpu::TextureDescriptor {
                label: Some("relief"),
                size: wgpu::Extent3d {
                    width: img.width(),
                    height: img.height(),
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::R8Unorm,
                usage: wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            },
            wgpu::util::TextureDataOrder::LayerMajor,
            img.as_raw(),
        );
        (
            tex.create_view(&Default::default()),
            img.as_raw().len() as u64,
        )
    }

    /// The cell's bind group: colour, normal map, sampler, relief map, base colour and the
    /// chart's orthographic colour (`views` in that order, the sampler between).
    fn cell_bind_group(&self, label: &str, views: [&wgpu::TextureView; 5]) -> wgpu::BindGroup {
        let [cv, nv, rv, bv, ov] = views;
        self.ctx
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout: &self.cell_layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(cv),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: wgpu::BindingResource::TextureView(nv),
                    },
                    wgpu::BindGroupEntry {
                        binding: 2,
                        resource: wgpu::BindingResource::Sampler(&self.sampler),
                    },
                    wgpu::BindGroupEntry {
                        binding: 3,
                        resource: wgpu::BindingResource::TextureView(rv),
                    },
                    wgpu::BindGroupEntry {
                        binding: 4,
                        resource: wgpu::BindingResource::TextureView(bv),
                    },
                    wgpu::BindGroupEntry {
                        binding: 5,
                        resource: wgpu::BindingResource::TextureView(ov),
                    },
                ],
            })
    }
}

/// A cell's mesh on the GPU.
struct MeshBuffers {
    positions: wgpu::Buffer,
    uvs: Option<wgpu::Buffer>,
    morph: Option<wgpu::Buffer>,
    indices: wgpu::Buffer,
    /// Bytes of the four buffers.
    bytes: u64,
}

/// Refuses an empty mesh, morph targets that do not match the vertices, and an empty
/// texture or one over the device's `max` side.
fn check_uploadable(rec: &CellRecord, data: &CellData, max: u32) -> Result<()> {
    let first = |m: &[image::RgbaImage]| m.first().map_or((0, 0), |i| i.dimensions());
    // the chart texture under a photo texture (relief mapping by share), the chart's
    // orthographic texture and the relief map are optional
    for (what, size) in [
        ("texture", Some(first(&data.colour_mips))),
        ("normal map", Some(first(&data.normal_mips))),
        ("chart texture", data.base_mips.as_deref().map(first)),
        (
            "orthographic texture",
            data.ortho_mips.as_deref().map(first),
        ),
        ("relief map", data.relief.as_ref().map(|r| r.dimensions())),
    ] {
        if let Some((w, h)) = size
            && (w == 0 || h == 0 || w > max || h > max)
        {
            return Err(Error::Gpu(format!(
                "cell {}: {what} of {w}x{h} texels cannot be uploaded (limit {max})",
                rec.id
            )));
        }
    }
    if data.mesh.triangles.is_empty() {
        return Err(Error::Gpu(format!("cell {}: empty mesh", rec.id)));
    }
    if let Some(m) = &data.morph
        && m.targets.len() != data.mesh.positions.len()
    {
        return Err(Error::Gpu(format!(
            "cell {}: {} morph targets for {} vertices",
            rec.id,
            m.targets.len(),
            data.mesh.positions.len()
        )));
    }
    Ok(())
}

/// The twelve edges of the cell's bounding box as line-list vertices in its local frame.
fn bbox_lines(rec: &CellRecord) -> Vec<f32> {
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
    lines
}
