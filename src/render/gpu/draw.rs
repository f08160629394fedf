//! One frame's terrain pass: frame and per-draw uniforms, the pipeline each cell needs
//! (chart UVs or ortho, morphing or not), parent textures of morphing cells, bounding-box
//! lines, then the distortion pass when the frame is distorted.

use glam::DVec3;

use super::{CellDraw, DRAW_STRIDE, FrameOptions, TerrainRenderer, f32_bytes};
use crate::error::{Error, Result};
use crate::render::camera::RenderCamera;
use crate::render::distortion::DistortedView;
use crate::render::target::RenderTarget;

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

impl TerrainRenderer {
    /// Draws the terrain into `target` (then, with `distort`, resamples it into that target).
    pub(super) fn draw_terrain(
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
                // relief: range (0 = off) and the eye in the cell-local frame (f64 difference)
                let eye = (cam.model.position - c.origin).as_vec3();
                v.extend_from_slice(&[c.relief_m, eye.x, eye.y, eye.z]);
                // relief limits: slope limit, and 1 if texture coordinates are a vertex
                // stream (the lookup moves through the triangle's map, not planar_uv)
                let stream = f32::from(u8::from(c.uvs.is_some()));
                v.extend_from_slice(&[
                    c.relief_min_normal_z,
                    stream,
                    f32::from(u8::from(c.share_relief)),
                    f32::from(u8::from(c.ortho_beside)),
                ]);
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
}
