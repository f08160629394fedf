//! Photo-over-render images for the registration pages: the photo blended half and half
//! with the store rendered from a camera, the GCPs marked (red cross: where the photo shows
//! the point; cyan ring edged in black: where the camera puts it; yellow: the line between).

use cliffmap::camera::CameraModel;
use cliffmap::register::Gcp;
use image::{Rgb, RgbImage};

fn put(img: &mut RgbImage, x: i64, y: i64, c: [u8; 3]) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, Rgb(c));
    }
}

/// A line of thickness `t` pixels from `a` to `b`.
fn line(img: &mut RgbImage, a: [f64; 2], b: [f64; 2], t: i64, c: [u8; 3]) {
    let n = ((b[0] - a[0]).hypot(b[1] - a[1]).ceil() as usize).max(1);
    for k in 0..=n {
        let f = k as f64 / n as f64;
        let (x, y) = (a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]));
        for dy in -t / 2..=t / 2 {
            for dx in -t / 2..=t / 2 {
                put(img, x.round() as i64 + dx, y.round() as i64 + dy, c);
            }
        }
    }
}

/// `photo` blended 50 % with `render` (same size), GCP markers scaled for a photo of this
/// size, then reduced by `reduce` (≥ 1).
pub fn photo_over_render(
    photo: &RgbImage,
    render: &RgbImage,
    cam: &CameraModel,
    gcps: &[Gcp],
    reduce: u32,
) -> RgbImage {
    let mut out = RgbImage::from_fn(photo.width(), photo.height(), |x, y| {
        let (p, r) = (photo.get_pixel(x, y).0, render.get_pixel(x, y).0);
        Rgb([0, 1, 2].map(|k| ((p[k] as u16 + r[k] as u16) / 2) as u8))
    });
    let s = (photo.width() as f64 / 800.0).max(1.0);
    let t = (1.5 * s).round() as i64;
    let r = 7.0 * s;
    for g in gcps {
        let o = g.pixel;
        if let Some(p) = cam.project(g.world) {
            line(&mut out, o, p, t, [255, 230, 0]);
            // a cyan ring on a dark one, visible on ice and rock alike
            for (width, colour) in [(3 * t, [0, 0, 0]), (t, [0, 230, 255])] {
                for k in 0..64 {
                    let a = k as f64 / 64.0 * std::f64::consts::TAU;
                    let b = (k + 1) as f64 / 64.0 * std::f64::consts::TAU;
                    line(
                        &mut out,
                        [p[0] + r * a.cos(), p[1] + r * a.sin()],
                        [p[0] + r * b.cos(), p[1] + r * b.sin()],
                        width,
                        colour,
                    );
                }
            }
        }
        line(
            &mut out,
            [o[0] - r, o[1] - r],
            [o[0] + r, o[1] + r],
            t,
            [255, 30, 30],
        );
        line(
            &mut out,
            [o[0] - r, o[1] + r],
            [o[0] + r, o[1] - r],
            t,
            [255, 30, 30],
        );
    }
    let f = reduce.max(1);
    image::imageops::resize(
        &out,
        out.width() / f,
        out.height() / f,
        image::imageops::FilterType::Triangle,
    )
}

/// Images side by side with a white gap of `gap` pixels (heights must agree).
pub fn side_by_side(images: &[RgbImage], gap: u32) -> RgbImage {
    let h = images.iter().map(RgbImage::height).max().unwrap_or(0);
    let w = images.iter().map(RgbImage::width).sum::<u32>()
        + gap * images.len().saturating_sub(1) as u32;
    let mut out = RgbImage::from_pixel(w, h, Rgb([255, 255, 255]));
    let mut x0 = 0;
    for im in images {
        image::imageops::replace(&mut out, im, x0 as i64, 0);
        x0 += im.width() + gap;
    }
    out
}
