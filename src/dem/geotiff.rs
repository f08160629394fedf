//! GeoTIFF DEM reader: one band of u8/i8/u16/i16/u32/i32/u64/i64/f16/f32/f64 samples,
//! strips or tiles, any compression the `tiff` crate decodes (none, LZW, deflate,
//! PackBits, with or without predictor). Placement comes from the GeoTIFF tags (see
//! [`crate::geotiff`]); GDAL_NODATA marks voids unless `opts.nodata` overrides it.
//! Dimensions, band count and sample type are checked against `opts.max_memory` before
//! any pixel is decoded.

use std::path::Path;

use tiff::ColorType;
use tiff::decoder::DecodingResult;

use super::convert::{self, Sample, Scaling};
use super::{Decoded, DemLoadOptions, limits};
use crate::error::{Error, Result};
use crate::geotiff as gt;

fn convert_all<T: Sample>(path: &Path, w: usize, v: &[T], s: Scaling, nodata: Option<f64>) -> Result<(Vec<f32>, Vec<bool>)> {
    convert::to_heights(path, w, v.len(), s, nodata.is_some(), |i| {
        (v[i].to_f64(), nodata.is_some_and(|nd| v[i].is_nodata(nd)))
    })
}

/// Reads a single-band (Geo)TIFF DEM.
pub(crate) fn read(path: &Path, opts: &DemLoadOptions) -> Result<Decoded> {
    let mut dec = gt::open(path, opts.max_memory)?;
    let (w, h) = dec.dimensions().map_err(|e| gt::tiff_err(path, e))?;
    let (w, h) = (w as usize, h as usize);
    let ct = dec.colortype().map_err(|e| gt::tiff_err(path, e))?;
    let bits = match ct {
        ColorType::Gray(b) => b,
        ColorType::Multiband { num_samples, .. } => {
            return Err(Error::bad_input(
                path,
                format!("TIFF has {num_samples} bands; a DEM must have exactly one (extract the height band first)"),
            ));
        }
        other => {
            return Err(Error::bad_input(
                path,
                format!("TIFF is a colour image ({other:?}), not a single-band height grid"),
            ));
        }
    };
    let fmt = gt::sample_format(path, &mut dec)?;
    let kind = match fmt {
        1 | 4 => "unsigned integer",
        2 => "signed integer",
        3 => "floating-point",
        5 | 6 => {
            return Err(Error::bad_input(path, "TIFF holds complex samples, which cannot be heights"));
        }
        other => return Err(Error::bad_input(path, format!("TIFF has unknown SampleFormat {other}"))),
    };
    let ok = match fmt {
        3 => matches!(bits, 16 | 32 | 64),
        _ => matches!(bits, 8 | 16 | 32 | 64),
    };
    if !ok {
        return Err(Error::bad_input(
            path,
            format!("unsupported TIFF sample type: {bits}-bit {kind} (supported: 8/16/32/64-bit integers, 16/32/64-bit floats)"),
        ));
    }
    super::check_size(path, w, h)?;
    limits::check(path, w as u64, h as u64, bits as u64 / 8 + limits::DEM_BYTES_PER_SAMPLE, opts.max_memory)?;

    let tags = gt::read_geo_tags(path, &mut dec)?;
    let nodata = opts.nodata.or(tags.nodata);
    let data = dec.read_image().map_err(|e| gt::tiff_err(path, e))?;
    let n = w * h;
    let s = super::scaling(opts);
    let (heights, void) = match &data {
        DecodingResult::U8(v) => convert_all(path, w, short(path, v, n)?, s, nodata)?,
        DecodingResult::I8(v) => convert_all(path, w, short(path, v, n)?, s, nodata)?,
        DecodingResult::U16(v) => convert_all(path, w, short(path, v, n)?, s, nodata)?,
        DecodingResult::I16(v) => convert_all(path, w, short(path, v, n)?, s, nodata)?,
        DecodingResult::U32(v) => convert_all(path, w, short(path, v, n)?, s, nodata)?,
        DecodingResult::I32(v) => convert_all(path, w, short(path, v, n)?, s, nodata)?,
        DecodingResult::U64(v) => convert_all(path, w, short(path, v, n)?, s, nodata)?,
        DecodingResult::I64(v) => convert_all(path, w, short(path, v, n)?, s, nodata)?,
        DecodingResult::F16(v) => {
            let v: Vec<f32> = short(path, v, n)?.iter().map(|x| x.to_f32()).collect();
            convert_all(path, w, &v, s, nodata)?
        }
        DecodingResult::F32(v) => convert_all(path, w, short(path, v, n)?, s, nodata)?,
        DecodingResult::F64(v) => convert_all(path, w, short(path, v, n)?, s, nodata)?,
    };
    if tags.geographic && opts.spacing.is_none() {
        tracing::warn!(
            "{}: georeferenced in geographic coordinates (degrees, {}); cliffmap expects metres — reproject the DEM or pass --spacing/--origin",
            path.display(),
            tags.crs.as_deref().unwrap_or("unknown CRS")
        );
    }
    Ok(Decoded { width: w, height: h, heights, void, georef: tags.georef, crs: tags.crs, geographic: tags.geographic })
}

/// The first `n` decoded samples, or an error if the decoder returned fewer.
fn short<'a, T>(path: &Path, v: &'a [T], n: usize) -> Result<&'a [T]> {
    v.get(..n).ok_or_else(|| Error::bad_input(path, format!("TIFF decoded to {} samples, expected {n}", v.len())))
}
