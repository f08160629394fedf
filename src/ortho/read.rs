//! Decoding ortho images to RGBA8: PNG and JPEG through the image crate, (Geo)TIFF through
//! the `tiff` crate so its GeoTIFF tags can be read too.
//!
//! Coverage: PNG alpha is kept (alpha 0 = no data); black pixels are ordinary colour.
//! In a GeoTIFF, alpha (ExtraSamples) is kept and a pixel whose colour samples all equal
//! GDAL_NODATA gets alpha 0.

use std::path::Path;

use image::{ImageFormat, RgbaImage};
use tiff::ColorType;
use tiff::decoder::DecodingResult;

use crate::dem::limits;
use crate::error::{Error, Result};
use crate::geotiff::{self as gt, GeoTags};

/// A decoded ortho image and whatever georeference its file carries.
pub(crate) struct Decoded {
    pub image: RgbaImage,
    pub tags: Option<GeoTags>,
}

fn is_tiff(path: &Path) -> Result<bool> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    if let Some(e) = ext.as_deref() {
        if matches!(e, "tif" | "tiff" | "gtiff") {
            return Ok(true);
        }
        if matches!(e, "png" | "jpg" | "jpeg") {
            return Ok(false);
        }
    }
    use std::io::Read;
    let mut b = [0u8; 4];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut b))
        .map_err(|e| Error::io(path, e))?;
    Ok(n == 4 && matches!(b, [b'I', b'I', 42 | 43, 0] | [b'M', b'M', 0, 42 | 43]))
}

/// Reads `path` as RGBA8, refusing images over `max_memory` before decoding pixels.
pub(crate) fn read(path: &Path, max_memory: u64) -> Result<Decoded> {
    if is_tiff(path)? {
        return read_tiff(path, max_memory);
    }
    let fallback = match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("jpg" | "jpeg") => ImageFormat::Jpeg,
        _ => ImageFormat::Png,
    };
    let img = limits::decode_image(path, fallback, max_memory, |w, h, ct| {
        limits::check(
            path,
            w as u64,
            h as u64,
            ct.bytes_per_pixel() as u64 + 4,
            max_memory,
        )
    })?;
    Ok(Decoded {
        image: img.into_rgba8(),
        tags: None,
    })
}

fn read_tiff(path: &Path, max_memory: u64) -> Result<Decoded> {
    let mut dec = gt::open(path, max_memory)?;
    let (w, h) = dec.dimensions().map_err(|e| gt::tiff_err(path, e))?;
    let ct = dec.colortype().map_err(|e| gt::tiff_err(path, e))?;
    let samples = match ct {
        ColorType::Gray(8) => 1usize,
        ColorType::RGB(8) => 3,
        ColorType::RGBA(8) => 4,
        other => {
            return Err(Error::bad_input(
                path,
                format!(
                    "ortho TIFF has colour type {other:?}; supported are 8-bit RGB, RGBA and greyscale"
                ),
            ));
        }
    };
    if gt::sample_format(path, &mut dec)? != 1 {
        return Err(Error::bad_input(
            path,
            "ortho TIFF samples must be unsigned 8-bit integers",
        ));
    }
    if samples > 1 && gt::is_planar(path, &mut dec)? {
        return Err(Error::bad_input(
            path,
            "ortho TIFF stores colour planes separately (PlanarConfiguration=2), which is not supported; rewrite it pixel-interleaved",
        ));
    }
    limits::check(path, w as u64, h as u64, samples as u64 + 4, max_memory)?;
    let tags = gt::read_geo_tags(path, &mut dec)?;
    let data = dec.read_image().map_err(|e| gt::tiff_err(path, e))?;
    let DecodingResult::U8(v) = data else {
        return Err(Error::bad_input(
            path,
            "ortho TIFF did not decode to 8-bit samples",
        ));
    };
    let n = w as usize * h as usize;
    if v.len() < n * samples {
        return Err(Error::bad_input(
            path,
            format!(
                "TIFF decoded to {} samples, expected {}",
                v.len(),
                n * samples
            ),
        ));
    }
    let nd = tags
        .nodata
        .filter(|x| x.fract() == 0.0 && (0.0..=255.0).contains(x))
        .map(|x| x as u8);
    let mut rgba = Vec::with_capacity(n * 4);
    for p in v.chunks_exact(samples).take(n) {
        let (rgb, a) = match samples {
            1 => ([p[0]; 3], 255),
            3 => ([p[0], p[1], p[2]], 255),
            _ => ([p[0], p[1], p[2]], p[3]),
        };
        let a = if nd.is_some_and(|nd| rgb.iter().all(|&c| c == nd)) {
            0
        } else {
            a
        };
        rgba.extend_from_slice(&[rgb[0], rgb[1], rgb[2], a]);
    }
    let image = RgbaImage::from_raw(w, h, rgba)
        .ok_or_else(|| Error::bad_input(path, "decoded ortho has an inconsistent size"))?;
    Ok(Decoded {
        image,
        tags: Some(tags),
    })
}
