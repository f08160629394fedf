//! Side-by-side comparison images.

use image::{Rgb, RgbImage};

/// The images (all of one size) side by side in one row, separated by 4-pixel white
/// columns; `None` for no images or images of different sizes.
pub fn side_by_side(images: &[&RgbImage]) -> Option<RgbImage> {
    let first = images.first()?;
    let (w, h) = first.dimensions();
    if images.iter().any(|i| i.dimensions() != (w, h)) {
        return None;
    }
    const GAP: u32 = 4;
    let n = images.len() as u32;
    let mut out = RgbImage::from_pixel(n * w + (n - 1) * GAP, h, Rgb([255, 255, 255]));
    for (k, img) in images.iter().enumerate() {
        image::imageops::replace(&mut out, *img, (k as u32 * (w + GAP)) as i64, 0);
    }
    Some(out)
}
