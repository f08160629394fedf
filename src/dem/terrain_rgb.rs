//! Mapbox Terrain-RGB reader: `height = -10000 + (R*65536 + G*256 + B) * 0.1` metres, then
//! `* z_scale + z_offset` if given. RGB or RGBA (palette PNGs are expanded); alpha 0 marks
//! no-data. A declared no-data value is compared with the decoded height (before
//! z_scale/z_offset) to within half a code step (0.05 m). No georeference in the file.

use std::path::Path;

use image::{ColorType, ImageFormat};

use super::convert;
use super::{Decoded, DemLoadOptions, limits};
use crate::error::Result;

/// Decoded height in metres of a Terrain-RGB pixel.
#[inline]
pub fn decode_terrain_rgb(r: u8, g: u8, b: u8) -> f64 {
    -10000.0 + ((r as u32) << 16 | (g as u32) << 8 | b as u32) as f64 * 0.1
}

/// Reads a Terrain-RGB PNG (or any 8-bit colour image the image crate decodes).
pub(crate) fn read(path: &Path, opts: &DemLoadOptions) -> Result<Decoded> {
    let img = limits::decode_image(
        path,
        ImageFormat::Png,
        opts.max_memory,
        |w, h, ct: ColorType| {
            super::check_size(path, w as usize, h as usize)?;
            // decoded buffer + the RGBA8 copy
            let per = ct.bytes_per_pixel() as u64 + 4 + limits::DEM_BYTES_PER_SAMPLE;
            limits::check(path, w as u64, h as u64, per, opts.max_memory)
        },
    )?;
    let has_alpha = img.color().has_alpha();
    let rgba = img.into_rgba8();
    let (w, h) = (rgba.width() as usize, rgba.height() as usize);
    let px = rgba.as_raw();
    let nodata = opts.nodata;
    let (heights, void) = convert::to_heights(
        path,
        w,
        w * h,
        super::scaling(opts),
        nodata.is_some(),
        |i| {
            let p = &px[4 * i..4 * i + 4];
            let v = decode_terrain_rgb(p[0], p[1], p[2]);
            let nd = nodata.is_some_and(|nd| (v - nd).abs() < 0.05);
            (v, nd || (has_alpha && p[3] == 0))
        },
    )?;
    Ok(Decoded {
        sentinels: Default::default(),
        width: w,
        height: h,
        heights,
        void,
        georef: None,
        crs: None,
        geographic: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::{DemLoadOptions, load_dem};
    use image::{ImageBuffer, Rgb, Rgba};

    fn encode(hm: f64) -> [u8; 3] {
        let code = ((hm + 10000.0) * 10.0).round() as u32;
        [(code >> 16) as u8, (code >> 8) as u8, code as u8]
    }

    #[test]
    fn formula_and_round_trip() {
        assert_eq!(decode_terrain_rgb(0, 0, 0), -10000.0);
        assert!((decode_terrain_rgb(1, 134, 160) - 0.0).abs() < 1e-9); // 100000 * 0.1 = 10000
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("tile.png");
        let hs: Vec<f64> = (0..20).map(|i| 439.0 + i as f64 * 91.3).collect();
        let img: ImageBuffer<Rgb<u8>, Vec<u8>> =
            ImageBuffer::from_fn(5, 4, |x, y| Rgb(encode(hs[(y * 5 + x) as usize])));
        img.save(&p).unwrap();
        let dem = load_dem(&p, &DemLoadOptions::default()).unwrap();
        for (a, b) in dem.heights.iter().zip(&hs) {
            assert!((*a as f64 - b).abs() < 0.05 + 1e-4, "{a} vs {b}");
        }

        // RGBA with a transparent pixel and a declared no-data height
        let p2 = d.path().join("tile4.png");
        let img: ImageBuffer<Rgba<u8>, Vec<u8>> = ImageBuffer::from_fn(3, 3, |x, y| {
            let [r, g, b] = encode(if (x, y) == (2, 0) {
                -10000.0
            } else {
                1000.0 + x as f64
            });
            Rgba([r, g, b, if (x, y) == (0, 2) { 0 } else { 255 }])
        });
        img.save(&p2).unwrap();
        let dem = load_dem(
            &p2,
            &DemLoadOptions {
                nodata: Some(-10000.0),
                ..Default::default()
            },
        )
        .unwrap();
        assert!(dem.is_void(0, 2) && dem.is_void(2, 0));
        assert_eq!(dem.void.iter().filter(|v| **v).count(), 2);
        assert!(dem.heights.iter().all(|h| (1000.0..=1002.0).contains(h)));
    }
}
