//! The exact reference images of one view: ground truth, the oracle and the baseline, all
//! ray cast against the full-resolution DEM, with the class of every pixel.

use glam::DVec3;
use image::RgbImage;
use rayon::prelude::*;

use crate::camera::CameraModel;
use crate::colour::{linear_to_srgb, srgb_to_linear};
use crate::demo_scene::{DemHit, DemTracer, DemoScene, FLAT_DEG, SKY_COLOUR, STEEP_DEG};
use crate::error::{Error, Result};
use crate::ortho::Ortho;
use crate::photo::PhotoInput;

/// Pixel class bit: the centre ray hits the terrain.
pub const TERRAIN: u8 = 1;
/// Pixel class bit: terrain steeper than [`STEEP_DEG`] (60°) at the centre hit.
pub const STEEP: u8 = 2;
/// Pixel class bit: terrain flatter than [`FLAT_DEG`] (30°) at the centre hit.
pub const FLAT: u8 = 4;
/// Pixel class bit: some photo sees the centre hit (inside its image, unoccluded).
pub const COVERED: u8 = 8;

/// What the reference images are made from: the scene's solid texture (truth), the DEM, the
/// ortho image (baseline) and the photos with their exact cameras (oracle).
pub struct ReferenceSources<'a> {
    /// The scene (its [`DemoScene::surface_colour`] is the truth).
    pub scene: &'a DemoScene,
    /// Exact ray casting against the scene's DEM.
    pub tracer: &'a DemTracer<'a>,
    /// The ortho image the store was built from.
    pub ortho: &'a Ortho,
    /// The photos given to `project`, with their cameras.
    pub photos: &'a [PhotoInput],
}

/// The reference images of one view (row-major, row 0 at the top) and per pixel its class
/// bits ([`TERRAIN`], [`STEEP`], [`FLAT`], [`COVERED`]) and the photo the oracle took the
/// centre ray's colour from.
#[derive(Clone, Debug)]
pub struct Reference {
    /// Ground truth: the solid texture at the exact hit points.
    pub truth: RgbImage,
    /// The oracle: per ray, the photo with the finest surface footprint that sees the hit
    /// point, sampled at its projection filtered over the ray's footprint
    /// ([`oracle_colour`]), else the ortho.
    pub oracle: RgbImage,
    /// The baseline: the ortho draped at the exact hit points (bilinear).
    pub baseline: RgbImage,
    /// Class bits per pixel.
    pub classes: Vec<u8>,
    /// Per pixel, the index (into the photos) of the oracle's photo at the centre ray, or
    /// `u8::MAX` (ortho or sky).
    pub oracle_photo: Vec<u8>,
}

/// Absolute part of the oracle's visibility tolerance, metres: a photo sees a hit point if its
/// ray towards it hits the surface no more than `0.1 m + 0.003 · distance` before it. The DEM
/// grid's near-vertical walls are zig-zags of slivers, so two rays from different sides
/// towards one wall point can meet different slivers decimetres apart; a real occluder
/// (a ridge, a spur) is metres in front.
pub const VISIBILITY_TOLERANCE_M: f64 = 0.1;
/// Relative part of the oracle's visibility tolerance (per metre of distance).
pub const VISIBILITY_TOLERANCE_REL: f64 = 0.003;

/// The photo whose surface footprint at `hit` (seen from the view ray) is finest among
/// those that see it cleanly: `(index, pixel [u, v], footprint m)`. The footprint is
/// `distance / (f · |cos|)` with `f = √(fx·fy)` and the angle between the photo's ray and the
/// surface normal: the length of a pixel on the surface along the direction it is
/// foreshortened in. A photo sees the point if its ray towards it meets the surface no more
/// than [`VISIBILITY_TOLERANCE_M`] + [`VISIBILITY_TOLERANCE_REL`] · distance before it, and sees
/// it cleanly if moreover the rays through the centres of the 2 × 2 pixels the point falls
/// between all hit the surface within that tolerance (or 10 %) of where they meet the
/// surface's tangent plane at the point: a point next to one of the photo's silhouettes would
/// take sky or an occluder's colour.
pub fn finest_photo(src: &ReferenceSources, hit: &DemHit) -> Option<(usize, [f64; 2], f64)> {
    finest_photo_with(src.photos, hit, |from, dir, t_max| {
        src.tracer.nearest(from, dir, t_max).map(|h| h.t)
    })
}

/// [`finest_photo`] among `photos` against another surface, given by `cast(from, unit
/// direction, t_max)`: the distance of the ray's nearest hit within `t_max`.
pub fn finest_photo_with(
    photos: &[PhotoInput],
    hit: &DemHit,
    cast: impl Fn(DVec3, DVec3, f64) -> Option<f64>,
) -> Option<(usize, [f64; 2], f64)> {
    let mut candidates: Vec<(usize, [f64; 2], f64, f64)> = Vec::new();
    for (i, p) in photos.iter().enumerate() {
        let cam = &p.camera;
        let Some([u, v]) = cam.project(hit.point) else {
            continue;
        };
        if !(u >= 0.0 && v >= 0.0 && u <= (cam.width - 1) as f64 && v <= (cam.height - 1) as f64) {
            continue;
        }
        let d = hit.point - cam.position;
        let dist = d.length();
        let cos = (d / dist).dot(hit.normal).abs();
        if cos <= 1e-6 || !dist.is_finite() {
            continue;
        }
        candidates.push((i, [u, v], dist / ((cam.fx * cam.fy).sqrt() * cos), dist));
    }
    candidates.sort_by(|a, b| a.2.total_cmp(&b.2).then(a.0.cmp(&b.0)));
    candidates.into_iter().find_map(|(i, uv, footprint, dist)| {
        let cam = &photos[i].camera;
        let tol = VISIBILITY_TOLERANCE_M + VISIBILITY_TOLERANCE_REL * dist;
        let seen = cast(cam.position, (hit.point - cam.position) / dist, dist + tol)
            .is_none_or(|t| t >= dist - tol);
        if !seen {
            return None;
        }
        let (x0, y0) = (uv[0].floor(), uv[1].floor());
        let clean = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)]
            .iter()
            .all(|(dx, dy)| {
                let (x, y) = (
                    (x0 + dx).min((cam.width - 1) as f64),
                    (y0 + dy).min((cam.height - 1) as f64),
                );
                let Some(dir) = cam.pixel_ray(x, y) else {
                    return false;
                };
                // where the ray would meet the surface's tangent plane at the point
                let dn = dir.dot(hit.normal);
                let plane = if dn.abs() > 1e-9 {
                    (hit.point - cam.position).dot(hit.normal) / dn
                } else {
                    dist
                };
                let expect = if plane > 0.0 && plane.is_finite() {
                    plane
                } else {
                    dist
                };
                let slack = tol.max(0.1 * expect);
                cast(cam.position, dir, expect + slack).is_some_and(|t| (t - expect).abs() <= slack)
            });
        clean.then_some((i, uv, footprint))
    })
}

/// A photo's pyramid of 2 × 2 halvings in linear light, for oracle samples filtered over
/// the view pixel's footprint in the photo (as a renderer's mip mapping would: a photo
/// finer than the view is area-averaged, not point-sampled).
pub struct PhotoMips {
    levels: Vec<RgbImage>,
}

impl PhotoMips {
    /// The pyramid of `image` (level 0 = the image, down to 2 pixels a side).
    pub fn new(image: &RgbImage) -> PhotoMips {
        let mut levels = vec![image.clone()];
        while let Some(next) = levels
            .last()
            .and_then(|l| crate::photo::downsample2_in(l, crate::colour::ColourSpace::Linear))
        {
            levels.push(next);
        }
        PhotoMips { levels }
    }

    /// The colour (sRGB 0..1) at pixel `[u, v]` of level 0 filtered over `scale` pixels:
    /// trilinear between the levels around `log2(scale)` (level 0, bilinear, for `scale <= 1`),
    /// interpolated in linear light.
    pub fn sample(&self, u: f64, v: f64, scale: f64) -> [f64; 3] {
        let top = (self.levels.len() - 1) as f64;
        let l = if scale > 1.0 {
            scale.log2().min(top)
        } else {
            0.0
        };
        let l0 = l.floor();
        let t = l - l0;
        let at = |k: usize| {
            let f = (1u64 << k) as f64;
            bilinear_linear(&self.levels[k], (u + 0.5) / f - 0.5, (v + 0.5) / f - 0.5)
        };
        let a = at(l0 as usize);
        let c = if t > 0.0 { at(l0 as usize + 1) } else { a };
        std::array::from_fn(|k| linear_to_srgb(a[k] * (1.0 - t) + c[k] * t))
    }
}

/// Bilinear sample in linear light of `img` at `[u, v]` (pixel-centre convention, clamped).
fn bilinear_linear(img: &RgbImage, u: f64, v: f64) -> [f64; 3] {
    let (w, h) = img.dimensions();
    let u = u.clamp(0.0, (w - 1) as f64);
    let v = v.clamp(0.0, (h - 1) as f64);
    let (x0, y0) = (u.floor() as u32, v.floor() as u32);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (u - x0 as f64, v - y0 as f64);
    let p = |x, y| {
        img.get_pixel(x, y)
            .0
            .map(|c| crate::colour::decode_u8(c) as f64)
    };
    let (a, b, c, d) = (p(x0, y0), p(x1, y0), p(x0, y1), p(x1, y1));
    std::array::from_fn(|k| {
        (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy
    })
}

/// The oracle's colour (sRGB 0..1) at `hit`, seen along a view ray from `eye` whose
/// sub-pixel subtends `pixel_angle` radians: the finest photo that sees it cleanly
/// ([`finest_photo_with`] with the surface `cast`), filtered over the view sub-pixel's footprint in that photo
/// (`√(area of the view sub-pixel on the surface / area of a photo pixel there)` photo
/// pixels); `None` if no photo sees it.
pub fn oracle_colour(
    photos: &[PhotoInput],
    mips: &[PhotoMips],
    hit: &DemHit,
    eye: DVec3,
    pixel_angle: f64,
    cast: impl Fn(DVec3, DVec3, f64) -> Option<f64>,
) -> Option<[f64; 3]> {
    let (i, [u, v], _) = finest_photo_with(photos, hit, cast)?;
    let cam = &photos[i].camera;
    let (dv, dp) = (hit.point - eye, hit.point - cam.position);
    let (lv, lp) = (dv.length(), dp.length());
    let (cv, cp) = (
        (dv / lv).dot(hit.normal).abs().max(1e-6),
        (dp / lp).dot(hit.normal).abs().max(1e-6),
    );
    let photo_angle = 1.0 / (cam.fx * cam.fy).sqrt();
    let scale = (lv * pixel_angle) / (lp * photo_angle) * (cp / cv).sqrt();
    Some(mips.get(i)?.sample(u, v, scale))
}

/// Bilinear sample (sRGB 0..1) of the ortho's colour at world `(x, y)` (clamped to the image;
/// alpha ignored).
pub fn ortho_colour(ortho: &Ortho, x: f64, y: f64) -> [f64; 3] {
    let (row, col) = ortho.georef.grid(x, y);
    let (w, h) = ortho.image.dimensions();
    let u = col.clamp(0.0, (w - 1) as f64);
    let v = row.clamp(0.0, (h - 1) as f64);
    let (x0, y0) = (u.floor() as u32, v.floor() as u32);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (u - x0 as f64, v - y0 as f64);
    let p = |x, y| {
        let c = ortho.image.get_pixel(x, y).0;
        [c[0], c[1], c[2]].map(|c| c as f64 / 255.0)
    };
    let (a, b, c, d) = (p(x0, y0), p(x1, y0), p(x0, y1), p(x1, y1));
    std::array::from_fn(|k| {
        (a[k] * (1.0 - fx) + b[k] * fx) * (1.0 - fy) + (c[k] * (1.0 - fx) + d[k] * fx) * fy
    })
}

/// Ray casts the [`Reference`] of `camera` (a pinhole or distorted camera; rays through
/// undistorted pixel positions): `supersample` (1..=8) stratified rays per pixel side,
/// colours averaged in linear light as the demo photos are; classes and the oracle's photo from the
/// ray through the pixel centre. Misses are [`SKY_COLOUR`] in all three images.
/// Deterministic whatever the thread count.
pub fn reference_images(
    src: &ReferenceSources,
    camera: &CameraModel,
    supersample: u32,
) -> Result<Reference> {
    if !(1..=8).contains(&supersample) {
        return Err(Error::BadOption(format!(
            "supersample must be in 1..=8, got {supersample}"
        )));
    }
    if let Some(p) = camera.problem() {
        return Err(Error::BadOption(format!("evaluation view camera: {p}")));
    }
    if src.photos.len() >= u8::MAX as usize {
        return Err(Error::BadOption(format!(
            "at most 254 photos can be evaluated, got {}",
            src.photos.len()
        )));
    }
    let colour = src.scene.surface_colour_fn();
    let sky = SKY_COLOUR.map(|c| c as f64 / 255.0);
    let ss = supersample as usize;
    let mips: Vec<PhotoMips> = src
        .photos
        .iter()
        .map(|p| PhotoMips::new(&p.image))
        .collect();
    let pixel_angle = 1.0 / ((camera.fx * camera.fy).sqrt() * ss as f64);
    let (w, h) = (camera.width as usize, camera.height as usize);
    let cast = |u: f64, v: f64| -> Option<DemHit> {
        let dir: DVec3 = camera.pixel_ray(u, v)?;
        src.tracer.nearest(camera.position, dir, f64::INFINITY)
    };
    type Row = (Vec<u8>, Vec<u8>, Vec<u8>, Vec<u8>, Vec<u8>);
    let rows: Vec<Row> = (0..h)
        .into_par_iter()
        .map(|row| {
            let mut out: Row = (
                Vec::with_capacity(3 * w),
                Vec::with_capacity(3 * w),
                Vec::with_capacity(3 * w),
                vec![0; w],
                vec![u8::MAX; w],
            );
            for col in 0..w {
                let [t, o, b] = supersampled(col, row, ss, |u, v| match cast(u, v) {
                    None => [sky; 3],
                    Some(hit) => {
                        let p = hit.point;
                        let base = ortho_colour(src.ortho, p.x, p.y);
                        let cast =
                            |from, dir, t_max| src.tracer.nearest(from, dir, t_max).map(|h| h.t);
                        let oracle = oracle_colour(
                            src.photos,
                            &mips,
                            &hit,
                            camera.position,
                            pixel_angle,
                            cast,
                        )
                        .unwrap_or(base);
                        [colour(p.x, p.y, p.z, hit.slope_deg), oracle, base]
                    }
                });
                out.0.extend(t);
                out.1.extend(o);
                out.2.extend(b);
                if let Some(hit) = cast(col as f64, row as f64) {
                    let mut class = TERRAIN;
                    if hit.slope_deg > STEEP_DEG {
                        class |= STEEP;
                    }
                    if hit.slope_deg < FLAT_DEG {
                        class |= FLAT;
                    }
                    if let Some((i, _, _)) = finest_photo(src, &hit) {
                        class |= COVERED;
                        out.4[col] = i as u8;
                    }
                    out.3[col] = class;
                }
            }
            out
        })
        .collect();
    let mut planes: [Vec<u8>; 5] = Default::default();
    for r in rows {
        planes[0].extend(r.0);
        planes[1].extend(r.1);
        planes[2].extend(r.2);
        planes[3].extend(r.3);
        planes[4].extend(r.4);
    }
    let [truth, oracle, baseline, classes, oracle_photo] = planes;
    let img = |v: Vec<u8>| {
        RgbImage::from_raw(camera.width, camera.height, v)
            .ok_or_else(|| Error::BadOption("reference size mismatch".into()))
    };
    Ok(Reference {
        truth: img(truth)?,
        oracle: img(oracle)?,
        baseline: img(baseline)?,
        classes,
        oracle_photo,
    })
}

/// The mean in linear light of the `N` colours (sRGB, 0..1) `sample(u, v)` gives at the
/// `ss × ss` subpixel centres of pixel `(col, row)` (pixel-centre convention), as sRGB bytes.
pub(crate) fn supersampled<const N: usize>(
    col: usize,
    row: usize,
    ss: usize,
    mut sample: impl FnMut(f64, f64) -> [[f64; 3]; N],
) -> [[u8; 3]; N] {
    let mut acc = [[0.0f64; 3]; N];
    for sy in 0..ss {
        for sx in 0..ss {
            let u = col as f64 - 0.5 + (sx as f64 + 0.5) / ss as f64;
            let v = row as f64 - 0.5 + (sy as f64 + 0.5) / ss as f64;
            for (a, c) in acc.iter_mut().zip(sample(u, v)) {
                for k in 0..3 {
                    a[k] += srgb_to_linear(c[k]);
                }
            }
        }
    }
    let n = (ss * ss).max(1) as f64;
    acc.map(|a| a.map(|v| (linear_to_srgb(v / n) * 255.0).round().clamp(0.0, 255.0) as u8))
}
