//! Ground photos of the demo scene: cameras placed from the scene's geometry, ray-traced
//! ground-truth images of the solid texture, and a `photos.json` set on disk.

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use image::RgbImage;
use rayon::prelude::*;

use super::{DemoScene, Noises, PLATEAU_ROUNDING, surface_colour};
use crate::camera::{CameraModel, camera_to_json, rotation_look_at};
use crate::dem::Dem;
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;
use crate::photo::{BvhQuality, TriangleBvh};

/// Colour (sRGB 8-bit) of rays that miss the terrain in [`DemoScene::render_truth_photo`].
pub const SKY_COLOUR: [u8; 3] = [170, 200, 235];

/// Default size of the demo photos (pixels).
const PHOTO_SIZE: (u32, u32) = (1600, 1200);
/// Vertical field of view of the demo photos, degrees.
const PHOTO_FOV_Y_DEG: f64 = 40.0;
/// Eye height above the ground, metres.
const EYE_HEIGHT: f64 = 1.7;
/// Radial distortion of the one distorted demo camera (barrel, like a wide-angle zoom).
const DEMO_K1: f64 = -0.06;

/// One demo ground photo: a file-name stem and its camera (world frame).
#[derive(Clone, Debug, PartialEq)]
pub struct PhotoShot {
    /// File-name stem, e.g. `"plateau_south"`.
    pub name: String,
    /// The camera, 1600 x 1200 pixels, 40° vertical field of view.
    pub camera: CameraModel,
}

/// Size and sampling of the photos [`DemoScene::write_demo_photos`] renders.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DemoPhotoOptions {
    /// Image width in pixels (the cameras are [`CameraModel::resized`] from 1600 x 1200).
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Rays per pixel side (1..=8).
    pub supersample: u32,
}

impl Default for DemoPhotoOptions {
    /// 1600 x 1200 pixels, 2 x 2 rays per pixel.
    fn default() -> Self {
        DemoPhotoOptions { width: PHOTO_SIZE.0, height: PHOTO_SIZE.1, supersample: 2 }
    }
}

/// What a camera looks at, in scene-local coordinates (east, south, up; metres).
struct Aim {
    name: &'static str,
    /// The point looked at.
    target: [f64; 3],
    /// Unit direction (east, south) from the target towards the camera.
    outward: [f64; 2],
    /// Camera distances to try, best first.
    distances: &'static [f64],
    k1: f64,
}

impl DemoScene {
    /// World position of scene-local (east, south, up).
    fn world(&self, e: f64, s: f64, z: f64) -> DVec3 {
        DVec3::new(self.origin_x + e, self.origin_y - s, z)
    }

    /// `true` if the terrain stays below the straight line from `a` to `b` (scene-local),
    /// ignoring the last `skip_end` metres before `b`.
    fn line_of_sight(&self, n: &Noises, a: [f64; 3], b: [f64; 3], skip_end: f64) -> bool {
        let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
        let steps = (len / 1.0).ceil().max(1.0) as usize;
        (1..steps).all(|i| {
            let t = i as f64 / steps as f64;
            if len * (1.0 - t) < skip_end {
                return true;
            }
            let (e, s) = (a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]));
            self.height_local(n, e, s) < a[2] + t * (b[2] - a[2]) - 0.3
        })
    }

    /// The scene-local points the demo cameras look at, derived from the plateau,
    /// escarpment and canyon geometry.
    fn aims(&self, n: &Noises) -> Vec<Aim> {
        let l = self.size_m();
        let [cx, cy, hx, hy] = self.plateau_rect();
        // Mid-height of a wall between its foot (outside) and top (inside), 8 m each way.
        let wall_mid = |e: f64, s: f64, out: [f64; 2]| {
            let foot = self.height_local(n, e + 8.0 * out[0], s + 8.0 * out[1]);
            let top = self.height_local(n, e - 8.0 * out[0], s - 8.0 * out[1]);
            [e, s, 0.5 * (foot + top)]
        };
        let mut aims = Vec::new();
        // Plateau south wall, seen from the south.
        let (e, s) = (cx, cy + hy + PLATEAU_ROUNDING);
        aims.push(Aim {
            name: "plateau_south",
            target: wall_mid(e, s, [0.0, 1.0]),
            outward: [0.0, 1.0],
            distances: &[250.0, 300.0, 200.0, 350.0, 150.0],
            k1: 0.0,
        });
        // Plateau east wall, seen from the east and slightly south, with lens distortion.
        let (e, s) = (cx + hx + PLATEAU_ROUNDING, cy + 0.3 * hy);
        let out = [0.94, 0.342]; // 20° south of east
        aims.push(Aim {
            name: "plateau_east",
            target: wall_mid(e, s, [1.0, 0.0]),
            outward: out,
            distances: &[200.0, 170.0, 240.0, 140.0, 280.0],
            k1: DEMO_K1,
        });
        // Escarpment wall halfway between the plateau and the canyon, seen from the south.
        let e = 0.5 * (cx + hx + self.canyon_axis(0.78 * l));
        let s = self.escarpment_line(n, e);
        aims.push(Aim {
            name: "escarpment",
            target: wall_mid(e, s, [0.0, 1.0]),
            outward: [0.0, 1.0],
            distances: &[180.0, 150.0, 200.0, 120.0],
            k1: 0.0,
        });
        // Canyon, from its floor, looking down-canyon (south) at the walls of the next bend.
        let s0 = 0.12 * l;
        let s1 = s0 + 160.0;
        let e1 = self.canyon_axis(s1);
        aims.push(Aim {
            name: "canyon",
            target: [e1, s1, self.height_local(n, e1, s1) + 0.4 * super::CANYON_DEPTH],
            outward: [0.0, -1.0],
            distances: &[160.0, 130.0, 100.0],
            k1: 0.0,
        });
        aims
    }

    /// The demo's ground photos: 3–4 cameras standing [`EYE_HEIGHT`] (1.7 m) above the
    /// ground, a few hundred metres from the plateau's walls (south and east, the east one
    /// with radial distortion k1 = −0.06), the escarpment and inside the canyon, each at the
    /// first candidate distance with a clear line of sight to its target. 1600 x 1200
    /// pixels, 40° vertical field of view. Deterministic for a scene.
    pub fn photo_shots(&self) -> Vec<PhotoShot> {
        let n = self.noises();
        let l = self.size_m();
        let mut shots = Vec::new();
        for aim in self.aims(&n) {
            for &d in aim.distances {
                let mut e = aim.target[0] + d * aim.outward[0];
                let mut s = aim.target[1] + d * aim.outward[1];
                if aim.name == "canyon" {
                    // Stay on the canyon floor (the axis), d metres up-canyon.
                    s = aim.target[1] - d;
                    e = self.canyon_axis(s);
                }
                let margin = 0.02 * l;
                if !(margin..=l - margin).contains(&e) || !(margin..=l - margin).contains(&s) {
                    continue;
                }
                let eye = [e, s, self.height_local(&n, e, s) + EYE_HEIGHT];
                if !self.line_of_sight(&n, eye, aim.target, 3.0) {
                    continue;
                }
                let pos = self.world(eye[0], eye[1], eye[2]);
                let target = self.world(aim.target[0], aim.target[1], aim.target[2]);
                let Some(rot) = rotation_look_at(pos, target) else { continue };
                let mut camera =
                    CameraModel::with_fov(pos, rot, PHOTO_SIZE.0, PHOTO_SIZE.1, PHOTO_FOV_Y_DEG.to_radians());
                camera.k1 = aim.k1;
                shots.push(PhotoShot { name: aim.name.to_string(), camera });
                break;
            }
        }
        shots
    }

    /// The cameras of [`DemoScene::photo_shots`].
    pub fn photo_cameras(&self) -> Vec<CameraModel> {
        self.photo_shots().into_iter().map(|s| s.camera).collect()
    }

    /// Ray-traces the ground truth seen by `camera`: the full-resolution DEM grid as two
    /// triangles per quad (BVH in an f32 frame centred on the camera), each hit coloured by
    /// [`DemoScene::surface_colour`] at the hit point with the slope of the hit triangle,
    /// [`SKY_COLOUR`] for misses. `supersample` (1..=8) rays per pixel side, stratified,
    /// averaged in sRGB (like the demo ortho). Radial distortion is applied (rays through
    /// undistorted pixel positions). Deterministic whatever the thread count.
    pub fn render_truth_photo(&self, dem: &Dem, camera: &CameraModel, supersample: u32) -> Result<RgbImage> {
        if !(1..=8).contains(&supersample) {
            return Err(Error::BadOption(format!("supersample must be in 1..=8, got {supersample}")));
        }
        if let Some(p) = camera.problem() {
            return Err(Error::BadOption(format!("truth photo camera: {p}")));
        }
        if dem.width < 2 || dem.height < 2 {
            return Err(Error::BadOption("truth photo needs a DEM of at least 2 x 2 samples".into()));
        }
        let pixels = camera.width as u64 * camera.height as u64 * (supersample as u64).pow(2);
        if pixels > 400_000_000 {
            return Err(Error::BadOption(format!("truth photo of {pixels} rays is too large")));
        }
        let (w, h) = (dem.width, dem.height);
        let world = |r: usize, c: usize| {
            let (x, y) = dem.georef.world(r as f64, c as f64);
            DVec3::new(x, y, dem.at(r, c) as f64)
        };
        // Triangle 2q is (r,c) (r+1,c) (r+1,c+1), 2q+1 is (r,c) (r+1,c+1) (r,c+1), q = r·(w−1)+c.
        let corners = |i: usize| {
            let q = i / 2;
            let (r, c) = (q / (w - 1), q % (w - 1));
            if i % 2 == 0 {
                [(r, c), (r + 1, c), (r + 1, c + 1)]
            } else {
                [(r, c), (r + 1, c + 1), (r, c + 1)]
            }
        };
        let origin = camera.position;
        let tris: Vec<[Vec3; 3]> = (0..2 * (w - 1) * (h - 1))
            .into_par_iter()
            .map(|i| corners(i).map(|(r, c)| (world(r, c) - origin).as_vec3()))
            .collect();
        let bvh = TriangleBvh::build(&tris, BvhQuality::Medium);
        let n = self.noises();
        let ss = supersample as usize;
        let cw = camera.width as usize;
        let rows: Vec<Vec<u8>> = (0..camera.height as usize)
            .into_par_iter()
            .map(|row| {
                let mut out = Vec::with_capacity(cw * 3);
                for col in 0..cw {
                    let mut acc = [0.0f64; 3];
                    for sy in 0..ss {
                        for sx in 0..ss {
                            let u = col as f64 - 0.5 + (sx as f64 + 0.5) / ss as f64;
                            let v = row as f64 - 0.5 + (sy as f64 + 0.5) / ss as f64;
                            let c = self.trace(&n, &bvh, camera, &corners, &world, u, v);
                            for k in 0..3 {
                                acc[k] += c[k];
                            }
                        }
                    }
                    for a in acc {
                        out.push((a / (ss * ss) as f64 * 255.0).round().clamp(0.0, 255.0) as u8);
                    }
                }
                out
            })
            .collect();
        RgbImage::from_raw(camera.width, camera.height, rows.concat())
            .ok_or_else(|| Error::BadOption("truth photo size mismatch".into()))
    }

    /// Colour (sRGB 0..1) seen along the ray through pixel position (u, v).
    #[allow(clippy::too_many_arguments)]
    fn trace(
        &self,
        n: &Noises,
        bvh: &TriangleBvh,
        camera: &CameraModel,
        corners: &impl Fn(usize) -> [(usize, usize); 3],
        world: &impl Fn(usize, usize) -> DVec3,
        u: f64,
        v: f64,
    ) -> [f64; 3] {
        let sky = SKY_COLOUR.map(|c| c as f64 / 255.0);
        let Some(dir) = camera.pixel_ray(u, v) else { return sky };
        let Some(hit) = bvh.nearest(Vec3::ZERO, dir.as_vec3(), 0.0, f32::INFINITY) else { return sky };
        let p = corners(hit.triangle as usize).map(|(r, c)| world(r, c));
        let b = hit.bary.map(|x| x as f64);
        let x = p[0] * b[0] + p[1] * b[1] + p[2] * b[2];
        let normal = (p[1] - p[0]).cross(p[2] - p[0]);
        let slope = (normal.z.abs() / normal.length()).clamp(0.0, 1.0).acos().to_degrees();
        surface_colour(n, self, x.x, x.y, x.z, slope)
    }

    /// Renders every [`DemoScene::photo_shots`] photo (resized to `opts`' size) with
    /// [`DemoScene::render_truth_photo`] into `dir` as `NAME.jpg` (JPEG quality 95) with its
    /// cliffmap Camera JSON `NAME.json`, then writes `dir/photos.json` listing them (relative
    /// paths) and returns its path. Every file is written atomically; `photos.json` last.
    pub fn write_demo_photos(&self, dem: &Dem, dir: &Path, opts: &DemoPhotoOptions) -> Result<PathBuf> {
        if opts.width == 0 || opts.height == 0 || opts.width > 16_384 || opts.height > 16_384 {
            return Err(Error::BadOption(format!("demo photo size {} x {} must be in 1..=16384", opts.width, opts.height)));
        }
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        let mut entries = Vec::new();
        for mut shot in self.photo_shots() {
            shot.camera = shot.camera.resized(opts.width, opts.height);
            let img = self.render_truth_photo(dem, &shot.camera, opts.supersample)?;
            let jpg = dir.join(format!("{}.jpg", shot.name));
            let mut bytes = Vec::new();
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut bytes, 95)
                .encode_image(&img)
                .map_err(|e| Error::bad_input(&jpg, format!("cannot encode JPEG: {e}")))?;
            write_atomic(&jpg, &bytes)?;
            let cam = dir.join(format!("{}.json", shot.name));
            let text = serde_json::to_string_pretty(&camera_to_json(&shot.camera))
                .map_err(|e| Error::bad_input(&cam, e.to_string()))?;
            write_atomic(&cam, text.as_bytes())?;
            entries.push(serde_json::json!({"image": format!("{}.jpg", shot.name), "camera": format!("{}.json", shot.name)}));
        }
        let list = dir.join("photos.json");
        let text = serde_json::to_string_pretty(&serde_json::json!({ "photos": entries }))
            .map_err(|e| Error::bad_input(&list, e.to_string()))?;
        write_atomic(&list, text.as_bytes())?;
        Ok(list)
    }
}

