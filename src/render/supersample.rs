//! Supersampled frames: a frame rendered at `factor` times the output size in each axis is
//! reduced by averaging each `factor × factor` block in linear light (RGB decoded from
//! sRGB, averaged, encoded; alpha averaged). With the screen-space error threshold scaled
//! by the same factor, the LOD selection is the one of the output size.

use image::RgbaImage;

use crate::colour::{decode_u8, encode_u8};

/// `img` reduced by `factor` (≥ 1) per axis as described in the module docs (`src/render/supersample.rs`); sides
/// not divisible by `factor` lose their last partial block. `factor` 1 returns a copy.
pub fn downsample_rgba(img: &RgbaImage, factor: u32) -> RgbaImage {
    let f = factor.max(1);
    if f == 1 {
        return img.clone();
    }
    let (w, h) = (img.width() / f, img.height() / f);
    let n = (f * f) as f32;
    RgbaImage::from_fn(w, h, |x, y| {
        let mut acc = [0.0f32; 4];
        for dy in 0..f {
            for dx in 0..f {
                let p = img.get_pixel(x * f + dx, y * f + dy).0;
                for k in 0..3 {
                    acc[k] += decode_u8(p[k]);
                }
                acc[3] += p[3] as f32;
            }
        }
        image::Rgba([
            encode_u8(acc[0] / n),
            encode_u8(acc[1] / n),
            encode_u8(acc[2] / n),
            (acc[3] / n).round() as u8,
        ])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn averages_blocks_in_linear_light() {
        let img = RgbaImage::from_fn(4, 2, |x, _| {
            if x % 2 == 0 {
                image::Rgba([0, 0, 0, 255])
            } else {
                image::Rgba([255, 255, 255, 255])
            }
        });
        let d = downsample_rgba(&img, 2);
        assert_eq!(d.dimensions(), (2, 1));
        // half black, half white: 50 % intensity = sRGB 188
        assert_eq!(d.get_pixel(0, 0).0, [188, 188, 188, 255]);
        assert_eq!(downsample_rgba(&img, 1), img);
        let c = RgbaImage::from_pixel(6, 6, image::Rgba([17, 99, 201, 128]));
        assert!(
            downsample_rgba(&c, 3)
                .pixels()
                .all(|p| p.0 == [17, 99, 201, 128])
        );
    }
}
