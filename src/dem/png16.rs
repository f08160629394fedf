//! Greyscale PNG DEM reader: `height = value * z_scale + z_offset` (defaults 1 and 0).
//! 16-bit grey (or grey+alpha) is the normal case; 8-bit grey is accepted only when the
//! format is given explicitly. Alpha 0 marks no-data. The file carries no georeference.

use std::path::Path;

use image::{ColorType, DynamicImage, ImageFormat};

use super::convert::{self, Sample};
use super::{Decoded, DemLoadOptions, limits};
use crate::error::{Error, Result};

/// Reads a greyscale PNG DEM; the no-data value is compared with the stored integer.
pub(crate) fn read(path: &Path, opts: &DemLoadOptions) -> Result<Decoded> {
    let img = limits::decode_image(path, ImageFormat::Png, opts.max_memory, |w, h, ct| {
        match ct {
            ColorType::L16 | ColorType::La16 | ColorType::L8 | ColorType::La8 => {}
            other => {
                return Err(Error::bad_input(
                    path,
                    format!(
                        "is not a greyscale image ({other:?}); for Terrain-RGB pass --dem-format terrain-rgb"
                    ),
                ));
            }
        }
        super::check_size(path, w as usize, h as usize)?;
        limits::check(
            path,
            w as u64,
            h as u64,
            ct.bytes_per_pixel() as u64 + limits::DEM_BYTES_PER_SAMPLE,
            opts.max_memory,
        )
    })?;
    let (w, h) = (img.width() as usize, img.height() as usize);
    let nodata = opts.nodata;
    let scaling = super::scaling(opts);
    let declared = nodata.is_some();
    let (heights, void) = match &img {
        DynamicImage::ImageLuma16(b) => {
            let s = b.as_raw();
            convert::to_heights(path, w, w * h, scaling, declared, |i| {
                (s[i] as f64, nodata.is_some_and(|nd| s[i].is_nodata(nd)))
            })?
        }
        DynamicImage::ImageLumaA16(b) => {
            let s = b.as_raw();
            convert::to_heights(path, w, w * h, scaling, declared, |i| {
                let (v, a) = (s[2 * i], s[2 * i + 1]);
                (v as f64, a == 0 || nodata.is_some_and(|nd| v.is_nodata(nd)))
            })?
        }
        DynamicImage::ImageLuma8(b) => {
            let s = b.as_raw();
            convert::to_heights(path, w, w * h, scaling, declared, |i| {
                (s[i] as f64, nodata.is_some_and(|nd| s[i].is_nodata(nd)))
            })?
        }
        DynamicImage::ImageLumaA8(b) => {
            let s = b.as_raw();
            convert::to_heights(path, w, w * h, scaling, declared, |i| {
                let (v, a) = (s[2 * i], s[2 * i + 1]);
                (v as f64, a == 0 || nodata.is_some_and(|nd| v.is_nodata(nd)))
            })?
        }
        other => {
            return Err(Error::bad_input(
                path,
                format!("unexpected decoded colour type {:?}", other.color()),
            ));
        }
    };
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
    use crate::dem::{DemFormat, load_dem};
    use crate::georef::GridGeoref;
    use image::{ImageBuffer, Luma, LumaA};

    #[test]
    fn round_trip_scale_offset_nodata_alpha() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("sth.png");
        let img: ImageBuffer<Luma<u16>, Vec<u16>> =
            ImageBuffer::from_fn(5, 4, |x, y| Luma([1000 + (y * 5 + x) as u16 * 7]));
        img.save(&p).unwrap();
        let opts = DemLoadOptions {
            z_scale: Some(0.1),
            z_offset: Some(-50.0),
            spacing: Some(10.0),
            ..Default::default()
        };
        let dem = load_dem(&p, &opts).unwrap();
        assert_eq!((dem.width, dem.height), (5, 4));
        for (i, &hgt) in dem.heights.iter().enumerate() {
            let v = 1000.0 + i as f64 * 7.0;
            assert_eq!(hgt, (v * 0.1 - 50.0) as f32);
        }
        assert_eq!(dem.georef, GridGeoref::new(0.0, 0.0, 10.0));

        // nodata on the stored integer
        let dem = load_dem(
            &p,
            &DemLoadOptions {
                nodata: Some(1007.0),
                ..opts.clone()
            },
        )
        .unwrap();
        assert!(dem.void[1] && dem.void_fraction() == 1.0 / 20.0);

        // grey+alpha: alpha 0 is void
        let p2 = d.path().join("la.png");
        let img: ImageBuffer<LumaA<u16>, Vec<u16>> = ImageBuffer::from_fn(3, 3, |x, y| {
            LumaA([
                100 * (x + y) as u16,
                if (x, y) == (1, 1) { 0 } else { 65535 },
            ])
        });
        img.save(&p2).unwrap();
        let dem = load_dem(&p2, &DemLoadOptions::default()).unwrap();
        assert!(dem.is_void(1, 1));
        assert_eq!(dem.at(1, 1), 200.0); // mean of the 8 neighbours 0,100,200,100,300,200,300,400
        assert_eq!(dem.at(2, 2), 400.0);
    }

    #[test]
    fn eight_bit_only_when_explicit() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("g8.png");
        let img: ImageBuffer<Luma<u8>, Vec<u8>> =
            ImageBuffer::from_fn(3, 3, |x, _| Luma([x as u8 * 10]));
        img.save(&p).unwrap();
        assert!(load_dem(&p, &DemLoadOptions::default()).is_err());
        let opts = DemLoadOptions {
            format: Some(DemFormat::Png16),
            z_scale: Some(2.0),
            ..Default::default()
        };
        let dem = load_dem(&p, &opts).unwrap();
        assert_eq!(&dem.heights[..3], &[0.0, 20.0, 40.0]);
    }
}
