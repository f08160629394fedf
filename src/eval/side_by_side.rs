//! Side-by-side comparison images with captions.

use image::RgbImage;
use plotters::prelude::*;

/// Height of the caption strip above each image, pixels.
const CAPTION: u32 = 30;
/// Gap between images, pixels.
const GAP: u32 = 4;

/// The images (all of one size) side by side in one row, separated by white 4-pixel
/// columns, each under a white strip with its caption; `None` for no images, images of
/// different sizes, or if the captions cannot be drawn.
pub fn side_by_side(images: &[(&RgbImage, &str)]) -> Option<RgbImage> {
    let (first, _) = images.first()?;
    let (w, h) = first.dimensions();
    if images.iter().any(|(i, _)| i.dimensions() != (w, h)) {
        return None;
    }
    let n = images.len() as u32;
    let (tw, th) = (n * w + (n - 1) * GAP, h + CAPTION);
    let mut buf = vec![255u8; (tw * th * 3) as usize];
    crate::font::register_font().ok()?;
    {
        let root = BitMapBackend::with_buffer(&mut buf, (tw, th)).into_drawing_area();
        for (k, (_, label)) in images.iter().enumerate() {
            let x = (k as u32 * (w + GAP) + 8) as i32;
            root.draw(&Text::new(
                label.to_string(),
                (x, 5),
                ("sans-serif", 20).into_font().color(&BLACK),
            ))
            .ok()?;
        }
        root.present().ok()?;
    }
    let mut out = RgbImage::from_raw(tw, th, buf)?;
    for (k, (img, _)) in images.iter().enumerate() {
        image::imageops::replace(
            &mut out,
            *img,
            (k as u32 * (w + GAP)) as i64,
            CAPTION as i64,
        );
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Rgb;

    #[test]
    fn tiles_images_under_captions() {
        let a = RgbImage::from_pixel(40, 20, Rgb([200, 0, 0]));
        let b = RgbImage::from_pixel(40, 20, Rgb([0, 0, 200]));
        let s = side_by_side(&[(&a, "a"), (&b, "b")]).unwrap();
        assert_eq!(s.dimensions(), (84, 50));
        assert_eq!(s.get_pixel(10, 40).0, [200, 0, 0]);
        assert_eq!(s.get_pixel(60, 40).0, [0, 0, 200]);
        assert_eq!(s.get_pixel(42, 40).0, [255, 255, 255]);
        // the caption strip has some dark text pixels
        assert!(
            (0..84)
                .flat_map(|x| (0..30).map(move |y| (x, y)))
                .any(|(x, y)| s.get_pixel(x, y).0[0] < 100)
        );
        let c = RgbImage::new(10, 10);
        assert!(side_by_side(&[(&a, "a"), (&c, "c")]).is_none());
        assert!(side_by_side(&[]).is_none());
    }
}
