//! The baseline on the store's own geometry: the ortho draped at the hit points of rays cast
//! against one level's TIN surfaces (not the DEM). Against the DEM-draped baseline it
//! separates what the TIN's geometric error costs from what texturing and filtering cost.

use glam::{DVec3, Vec3};
use image::RgbImage;
use rayon::prelude::*;

use super::reference::ortho_colour;
use crate::camera::CameraModel;
use crate::colour::{linear_to_srgb, srgb_to_linear};
use crate::error::{Error, Result};
use crate::ortho::Ortho;
use crate::photo::{BvhQuality, TriangleBvh};
use crate::scene::SKY_COLOUR;
use crate::store::Store;

/// The surface triangles of every cell of one level of a store, in a BVH (f32 frame centred
/// on an origin, vertices kept in f64 world coordinates for the hit points).
pub struct TinTracer {
    origin: DVec3,
    bvh: TriangleBvh,
    tris: Vec<[DVec3; 3]>,
}

impl TinTracer {
    /// Reads the active meshes of the cells of `level` (surface triangles only).
    pub fn new(store: &Store, level: u8, origin: DVec3) -> Result<TinTracer> {
        let mut tris = Vec::new();
        for rec in store.manifest.cells.iter().filter(|c| c.level == level) {
            let mesh = store.read_active_mesh(rec)?;
            let o = DVec3::from_array(rec.origin);
            let p = |k: u32| -> Result<DVec3> {
                let v = mesh.positions.get(k as usize).ok_or_else(|| Error::store(&store.dir, format!("cell {}: vertex {k} out of range", rec.id)))?;
                Ok(o + Vec3::from_array(*v).as_dvec3())
            };
            for t in mesh.surface() {
                tris.push([p(t[0])?, p(t[1])?, p(t[2])?]);
            }
        }
        if tris.is_empty() {
            return Err(Error::store(&store.dir, format!("no surface triangles on level {level}")));
        }
        let local: Vec<[Vec3; 3]> = tris.iter().map(|t| t.map(|v| (v - origin).as_vec3())).collect();
        Ok(TinTracer { origin, bvh: TriangleBvh::build(&local, BvhQuality::Medium), tris })
    }

    /// The nearest hit point (world) of the ray from `from` along unit `dir`.
    pub fn nearest(&self, from: DVec3, dir: DVec3) -> Option<DVec3> {
        let hit = self.bvh.nearest((from - self.origin).as_vec3(), dir.as_vec3(), 0.0, f32::INFINITY)?;
        let t = self.tris.get(hit.triangle as usize)?;
        let b = hit.bary.map(|x| x as f64);
        Some(t[0] * b[0] + t[1] * b[1] + t[2] * b[2])
    }
}

/// The ortho draped on `tracer`'s TIN as seen by `camera`: `supersample` (1..=8) rays per
/// pixel side averaged in linear light, like [`super::reference_images`]; misses are
/// [`SKY_COLOUR`].
pub fn tin_baseline(tracer: &TinTracer, ortho: &Ortho, camera: &CameraModel, supersample: u32) -> Result<RgbImage> {
    if !(1..=8).contains(&supersample) {
        return Err(Error::BadOption(format!("supersample must be in 1..=8, got {supersample}")));
    }
    let ss = supersample as usize;
    let (w, h) = (camera.width as usize, camera.height as usize);
    let sky = SKY_COLOUR.map(|c| c as f64 / 255.0);
    let rows: Vec<Vec<u8>> = (0..h)
        .into_par_iter()
        .map(|row| {
            let mut out = Vec::with_capacity(3 * w);
            for col in 0..w {
                let mut acc = [0.0f64; 3];
                for sy in 0..ss {
                    for sx in 0..ss {
                        let u = col as f64 - 0.5 + (sx as f64 + 0.5) / ss as f64;
                        let v = row as f64 - 0.5 + (sy as f64 + 0.5) / ss as f64;
                        let c = camera
                            .pixel_ray(u, v)
                            .and_then(|d| tracer.nearest(camera.position, d))
                            .map_or(sky, |p| ortho_colour(ortho, p.x, p.y));
                        for k in 0..3 {
                            acc[k] += srgb_to_linear(c[k]);
                        }
                    }
                }
                out.extend(acc.map(|a| (linear_to_srgb(a / (ss * ss) as f64) * 255.0).round().clamp(0.0, 255.0) as u8));
            }
            out
        })
        .collect();
    RgbImage::from_raw(camera.width, camera.height, rows.concat()).ok_or_else(|| Error::BadOption("baseline size mismatch".into()))
}
