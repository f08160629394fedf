//! References on the store's own geometry: rays cast against one level's TIN surfaces (not
//! the DEM), the ortho draped at their hits (baseline) and ideal projective texturing of the
//! photos through the TIN (oracle). Against the DEM references they separate what the TIN's
//! geometric error costs from what texturing and filtering cost.

use glam::{DVec3, Vec3};
use image::RgbImage;
use rayon::prelude::*;

use super::reference::{PhotoMips, oracle_colour, ortho_colour};
use crate::camera::CameraModel;
use crate::demo_scene::{DemHit, SKY_COLOUR};
use crate::error::{Error, Result};
use crate::ortho::Ortho;
use crate::photo::PhotoInput;
use crate::raycast::{BvhQuality, TriangleBvh};
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
                let v = mesh.positions.get(k as usize).ok_or_else(|| {
                    Error::store(
                        &store.dir,
                        format!("cell {}: vertex {k} out of range", rec.id),
                    )
                })?;
                Ok(o + Vec3::from_array(*v).as_dvec3())
            };
            for t in mesh.surface() {
                tris.push([p(t[0])?, p(t[1])?, p(t[2])?]);
            }
        }
        if tris.is_empty() {
            return Err(Error::store(
                &store.dir,
                format!("no surface triangles on level {level}"),
            ));
        }
        let local: Vec<[Vec3; 3]> = tris
            .iter()
            .map(|t| t.map(|v| (v - origin).as_vec3()))
            .collect();
        Ok(TinTracer {
            origin,
            bvh: TriangleBvh::build(&local, BvhQuality::Medium),
            tris,
        })
    }

    /// The nearest hit of the ray from `from` along unit `dir` within `t_max` metres.
    pub fn nearest(&self, from: DVec3, dir: DVec3, t_max: f64) -> Option<DemHit> {
        let hit = self.bvh.nearest(
            (from - self.origin).as_vec3(),
            dir.as_vec3(),
            0.0,
            t_max as f32,
        )?;
        let t = self.tris.get(hit.triangle as usize)?;
        Some(DemHit::on_triangle(hit.t as f64, *t, hit.bary))
    }

    /// Whether `point` is seen from `eye` (as [`crate::demo_scene::DemTracer::sees`]).
    pub fn sees(&self, eye: DVec3, point: DVec3, tolerance: f64) -> bool {
        crate::demo_scene::sees_with(eye, point, tolerance, |o, d, t| self.nearest(o, d, t))
    }
}

/// The two references on `tracer`'s TIN as seen by `camera`: the baseline (the ortho draped
/// at the TIN hit points) and the oracle on the TIN (per ray, the photo with the finest
/// footprint that sees the TIN point, filtered at its projection as [`super::oracle_colour`],
/// else the ortho: the best
/// projective texturing can do with this geometry). `supersample` (1..=8) rays per pixel
/// side averaged in linear light, like [`super::reference_images`]; misses are
/// [`SKY_COLOUR`].
pub fn tin_references(
    tracer: &TinTracer,
    ortho: &Ortho,
    photos: &[PhotoInput],
    camera: &CameraModel,
    supersample: u32,
) -> Result<(RgbImage, RgbImage)> {
    if !(1..=8).contains(&supersample) {
        return Err(Error::BadOption(format!(
            "supersample must be in 1..=8, got {supersample}"
        )));
    }
    let ss = supersample as usize;
    let (w, h) = (camera.width as usize, camera.height as usize);
    let sky = SKY_COLOUR.map(|c| c as f64 / 255.0);
    let mips: Vec<PhotoMips> = photos.iter().map(|p| PhotoMips::new(&p.image)).collect();
    let pixel_angle = 1.0 / ((camera.fx * camera.fy).sqrt() * ss as f64);
    let rows: Vec<(Vec<u8>, Vec<u8>)> =
        (0..h)
            .into_par_iter()
            .map(|row| {
                let (mut base, mut oracle) = (Vec::with_capacity(3 * w), Vec::with_capacity(3 * w));
                for col in 0..w {
                    let [b, o] = super::reference::supersampled(col, row, ss, |u, v| match camera
                        .pixel_ray(u, v)
                        .and_then(|d| tracer.nearest(camera.position, d, f64::INFINITY))
                    {
                        None => [sky; 2],
                        Some(hit) => {
                            let b = ortho_colour(ortho, hit.point.x, hit.point.y);
                            let cast =
                                |from, dir, t_max| tracer.nearest(from, dir, t_max).map(|h| h.t);
                            let o = oracle_colour(
                                photos,
                                &mips,
                                &hit,
                                camera.position,
                                pixel_angle,
                                cast,
                            )
                            .unwrap_or(b);
                            [b, o]
                        }
                    });
                    base.extend(b);
                    oracle.extend(o);
                }
                (base, oracle)
            })
            .collect();
    let (b, o): (Vec<Vec<u8>>, Vec<Vec<u8>>) = rows.into_iter().unzip();
    let img = |v: Vec<Vec<u8>>| {
        RgbImage::from_raw(camera.width, camera.height, v.concat())
            .ok_or_else(|| Error::BadOption("reference size mismatch".into()))
    };
    Ok((img(b)?, img(o)?))
}
