//! Ground photos of the demo scene: cameras placed from the scene's geometry, ray-traced
//! ground-truth images of the solid texture, and a `photos.json` set on disk.

use std::path::{Path, PathBuf};

use glam::DVec3;
use image::RgbImage;
use rayon::prelude::*;

use super::tracer::DemTracer;
use super::{DemoScene, Noises, PLATEAU_ROUNDING, surface_colour};
use crate::camera::{CameraModel, camera_to_json, rotation_look_at};
use crate::colour::{linear_to_srgb, srgb_to_linear};
use crate::dem::Dem;
use crate::error::{Error, Result};
use crate::fsutil::write_atomic;

/// Colour (sRGB 8-bit) of rays that miss the terrain in [`DemoScene::render_truth_photo`].
pub const SKY_COLOUR: [u8; 3] = [170, 200, 235];

/// Default size of the demo photos (pixels).
const PHOTO_SIZE: (u32, u32) = (1600, 1200);
/// Vertical field of view of the demo photos, degrees.
const PHOTO_FOV_Y_DEG: f64 = 40.0;
/// Vertical field of view of the novel evaluation views, degrees.
const VIEW_FOV_Y_DEG: f64 = 35.0;
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
        DemoPhotoOptions {
            width: PHOTO_SIZE.0,
            height: PHOTO_SIZE.1,
            supersample: 2,
        }
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
    /// Whether scene-local (east, south) lies at least 2 % of the scene's side inside it.
    fn inside_margin(&self, e: f64, s: f64) -> bool {
        let l = self.size_m();
        let m = 0.02 * l;
        (m..=l - m).contains(&e) && (m..=l - m).contains(&s)
    }

    /// The aims that [`DemoScene::photo_shots`] found a place for, with that photo.
    fn aims_with_photos(&self, n: &Noises) -> Vec<(Aim, PhotoShot)> {
        let photos = self.photo_shots();
        self.aims(n)
            .into_iter()
            .filter_map(|aim| {
                let p = photos.iter().find(|p| p.name == aim.name)?.clone();
                Some((aim, p))
            })
            .collect()
    }

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
            target: [
                e1,
                s1,
                self.height_local(n, e1, s1) + 0.4 * self.relief.canyon,
            ],
            outward: [0.0, -1.0],
            distances: &[160.0, 130.0, 100.0],
            k1: 0.0,
        });
        aims
    }

    /// The demo's ground photos: 3–4 cameras standing `EYE_HEIGHT` (1.7 m) above the
    /// ground, a few hundred metres from the plateau's walls (south and east, the east one
    /// with radial distortion k1 = −0.06), the escarpment and inside the canyon, each at the
    /// first candidate distance with a clear line of sight to its target. 1600 x 1200
    /// pixels, 40° vertical field of view. Deterministic for a scene.
    pub fn photo_shots(&self) -> Vec<PhotoShot> {
        let n = self.noises();
        let mut shots = Vec::new();
        for aim in self.aims(&n) {
            for &d in aim.distances {
                let d = d * self.photo_distance;
                let mut e = aim.target[0] + d * aim.outward[0];
                let mut s = aim.target[1] + d * aim.outward[1];
                if aim.name == "canyon" {
                    // Stay on the canyon floor (the axis), d metres up-canyon.
                    s = aim.target[1] - d;
                    e = self.canyon_axis(s);
                }
                if !self.inside_margin(e, s) {
                    continue;
                }
                let eye = [e, s, self.height_local(&n, e, s) + EYE_HEIGHT];
                if !self.line_of_sight(&n, eye, aim.target, 3.0) {
                    continue;
                }
                let pos = self.world(eye[0], eye[1], eye[2]);
                let target = self.world(aim.target[0], aim.target[1], aim.target[2]);
                let Some(rot) = rotation_look_at(pos, target) else {
                    continue;
                };
                let mut camera = CameraModel::with_fov(
                    pos,
                    rot,
                    PHOTO_SIZE.0,
                    PHOTO_SIZE.1,
                    PHOTO_FOV_Y_DEG.to_radians(),
                );
                camera.k1 = aim.k1;
                shots.push(PhotoShot {
                    name: aim.name.to_string(),
                    camera,
                });
                break;
            }
        }
        shots
    }

    /// Second photos of the demo photos' targets taken elsewhere, for placing a photo from a
    /// placed one (docs/registration.md, "Ties between different places"): per photo of
    /// [`DemoScene::photo_shots`], a camera turned `turn_deg` around its target (either
    /// side, the first with a clear line of sight) at `distance_ratio` × the photo's
    /// horizontal distance, standing `EYE_HEIGHT` above the ground; inside the canyon
    /// `distance_ratio` × the distance up-canyon on its floor instead (a move along the
    /// view). Aimed at a point 5 m off the target, the photo's size and field of view, no
    /// distortion; named `"<photo>_second"`. Deterministic.
    pub fn second_shots(&self, turn_deg: f64, distance_ratio: f64) -> Vec<PhotoShot> {
        let n = self.noises();
        let mut out = Vec::new();
        for (aim, photo) in self.aims_with_photos(&n) {
            let t = aim.target;
            let tw = self.world(t[0], t[1], t[2]);
            let d = (photo.camera.position - tw).truncate().length() * distance_ratio;
            let mut candidates = Vec::new();
            if aim.name == "canyon" {
                let s = t[1] - d;
                candidates.push([self.canyon_axis(s), s]);
            } else {
                for sign in [1.0, -1.0] {
                    let (sn, cs) = (sign * turn_deg).to_radians().sin_cos();
                    let o = [
                        cs * aim.outward[0] - sn * aim.outward[1],
                        sn * aim.outward[0] + cs * aim.outward[1],
                    ];
                    candidates.push([t[0] + d * o[0], t[1] + d * o[1]]);
                }
            }
            let look = [t[0] + 4.0, t[1] - 3.0, t[2] + 2.0];
            for [e, s] in candidates {
                if !self.inside_margin(e, s) {
                    continue;
                }
                let eye = [e, s, self.height_local(&n, e, s) + EYE_HEIGHT];
                if !self.line_of_sight(&n, eye, look, 3.0) {
                    continue;
                }
                let pos = self.world(eye[0], eye[1], eye[2]);
                let Some(rot) = rotation_look_at(pos, self.world(look[0], look[1], look[2])) else {
                    continue;
                };
                out.push(PhotoShot {
                    name: format!("{}_second", aim.name),
                    camera: CameraModel::with_fov(
                        pos,
                        rot,
                        PHOTO_SIZE.0,
                        PHOTO_SIZE.1,
                        PHOTO_FOV_Y_DEG.to_radians(),
                    ),
                });
                break;
            }
        }
        out
    }

    /// Novel views for render-space evaluation (docs/evaluation.md): per photo target, a
    /// `width × height` pinhole view with a 35° vertical field of view that looks at the same
    /// point from elsewhere: turned 25–40° around the target (either side) at 0.6–1.0 × the
    /// photo's distance, 12 m above the ground (inside the canyon: further up-canyon, 15 m
    /// above its floor), the first candidate with a clear line of sight. Deterministic.
    pub fn novel_views(&self, width: u32, height: u32) -> Vec<PhotoShot> {
        let n = self.noises();
        let mut views = Vec::new();
        for (aim, photo) in self.aims_with_photos(&n) {
            let t = self.world(aim.target[0], aim.target[1], aim.target[2]);
            let d = (photo.camera.position - t).truncate().length();
            let mut candidates = Vec::new();
            if aim.name == "canyon" {
                for k in [1.3, 1.15, 1.5] {
                    let s = aim.target[1] - k * d;
                    let e = self.canyon_axis(s);
                    candidates.push([e, s, self.height_local(&n, e, s) + 15.0]);
                }
            } else {
                for k in [0.8, 1.0, 0.6] {
                    for deg in [25.0f64, -25.0, 40.0, -40.0] {
                        let (sn, cs) = deg.to_radians().sin_cos();
                        let o = [
                            cs * aim.outward[0] - sn * aim.outward[1],
                            sn * aim.outward[0] + cs * aim.outward[1],
                        ];
                        let (e, s) = (aim.target[0] + k * d * o[0], aim.target[1] + k * d * o[1]);
                        if self.inside_margin(e, s) {
                            candidates.push([e, s, self.height_local(&n, e, s) + 12.0]);
                        }
                    }
                }
            }
            for eye in candidates {
                if !self.inside_margin(eye[0], eye[1])
                    || !self.line_of_sight(&n, eye, aim.target, 3.0)
                {
                    continue;
                }
                let pos = self.world(eye[0], eye[1], eye[2]);
                let Some(rot) = rotation_look_at(pos, t) else {
                    continue;
                };
                let camera =
                    CameraModel::with_fov(pos, rot, width, height, VIEW_FOV_Y_DEG.to_radians());
                views.push(PhotoShot {
                    name: format!("view_{}", aim.name),
                    camera,
                });
                break;
            }
        }
        views
    }

    /// The cameras of [`DemoScene::photo_shots`].
    pub fn photo_cameras(&self) -> Vec<CameraModel> {
        self.photo_shots().into_iter().map(|s| s.camera).collect()
    }

    /// Ray-traces the ground truth seen by `camera`: the full-resolution DEM grid as two
    /// triangles per quad (BVH in an f32 frame centred on the camera), each hit coloured by
    /// [`DemoScene::surface_colour`] at the hit point with the slope of the hit triangle,
    /// [`SKY_COLOUR`] for misses. `supersample` (1..=8) rays per pixel side, stratified,
    /// averaged in linear light (like the demo ortho). Radial distortion is applied (rays through
    /// undistorted pixel positions). Deterministic whatever the thread count.
    pub fn render_truth_photo(
        &self,
        dem: &Dem,
        camera: &CameraModel,
        supersample: u32,
    ) -> Result<RgbImage> {
        if !(1..=8).contains(&supersample) {
            return Err(Error::BadOption(format!(
                "supersample must be in 1..=8, got {supersample}"
            )));
        }
        if let Some(p) = camera.problem() {
            return Err(Error::BadOption(format!("truth photo camera: {p}")));
        }
        if dem.width < 2 || dem.height < 2 {
            return Err(Error::BadOption(
                "truth photo needs a DEM of at least 2 x 2 samples".into(),
            ));
        }
        let pixels = camera.width as u64 * camera.height as u64 * (supersample as u64).pow(2);
        if pixels > 400_000_000 {
            return Err(Error::BadOption(format!(
                "truth photo of {pixels} rays is too large"
            )));
        }
        let tracer = DemTracer::new(dem, camera.position)?;
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
                            let c = self.trace(&n, &tracer, camera, u, v);
                            for k in 0..3 {
                                acc[k] += srgb_to_linear(c[k]);
                            }
                        }
                    }
                    for a in acc {
                        out.push(
                            (linear_to_srgb(a / (ss * ss) as f64) * 255.0)
                                .round()
                                .clamp(0.0, 255.0) as u8,
                        );
                    }
                }
                out
            })
            .collect();
        RgbImage::from_raw(camera.width, camera.height, rows.concat())
            .ok_or_else(|| Error::BadOption("truth photo size mismatch".into()))
    }

    /// Colour (sRGB 0..1) seen along the ray through pixel position (u, v).
    fn trace(
        &self,
        n: &Noises,
        tracer: &DemTracer,
        camera: &CameraModel,
        u: f64,
        v: f64,
    ) -> [f64; 3] {
        let sky = SKY_COLOUR.map(|c| c as f64 / 255.0);
        let Some(dir) = camera.pixel_ray(u, v) else {
            return sky;
        };
        let Some(hit) = tracer.nearest(camera.position, dir, f64::INFINITY) else {
            return sky;
        };
        surface_colour(
            n,
            self,
            hit.point.x,
            hit.point.y,
            hit.point.z,
            hit.slope_deg,
        )
    }

    /// Renders every [`DemoScene::photo_shots`] photo (resized to `opts`' size) with
    /// [`DemoScene::render_truth_photo`] into `dir` as `NAME.jpg` (JPEG quality 95) with its
    /// cliffmap Camera JSON `NAME.json`, then writes `dir/photos.json` listing them (relative
    /// paths) and returns its path. Every file is written atomically; `photos.json` last.
    pub fn write_demo_photos(
        &self,
        dem: &Dem,
        dir: &Path,
        opts: &DemoPhotoOptions,
    ) -> Result<PathBuf> {
        if opts.width == 0 || opts.height == 0 || opts.width > 16_384 || opts.height > 16_384 {
            return Err(Error::BadOption(format!(
                "demo photo size {} x {} must be in 1..=16384",
                opts.width, opts.height
            )));
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
