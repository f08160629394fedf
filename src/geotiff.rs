//! GeoTIFF tag parsing shared by the DEM and ortho readers.
//!
//! Data type: [`GeoTags`], the georeference, CRS and no-data value a TIFF declares.
//! Tags read: ModelPixelScale (33550), ModelTiepoint (33922), ModelTransformation (34264,
//! axis-aligned only), GeoKeyDirectory (34735: raster type, projected/geographic EPSG code)
//! and GDAL_NODATA (42113).
//!
//! Georeference convention: GeoTIFF maps *raster space* (I, J) to the model. With
//! `PixelIsArea` (the default) raster point (0, 0) is the outer corner of the north-west
//! pixel, so its centre is (0.5, 0.5); with `PixelIsPoint` raster point (0, 0) is that
//! pixel's centre. [`GeoTags::georef`] is always converted to cliffmap's convention: the
//! world position of the **centre** of sample (0, 0), computed in f64.

use std::fs::File;
use std::io::{BufReader, Read, Seek};
use std::path::Path;

use tiff::TiffError;
use tiff::decoder::{Decoder, Limits};
use tiff::tags::Tag;

use crate::error::{Error, Result};
use crate::georef::GridGeoref;

/// GeoKey ids used here (GeoTIFF 1.0 spec, section 6.2).
const GT_MODEL_TYPE: u16 = 1024;
const GT_RASTER_TYPE: u16 = 1025;
const GEOGRAPHIC_TYPE: u16 = 2048;
const PROJECTED_CS_TYPE: u16 = 3072;
/// RasterPixelIsPoint value of the GTRasterTypeGeoKey.
const RASTER_PIXEL_IS_POINT: u16 = 2;
/// ModelTypeGeographic value of the GTModelTypeGeoKey.
const MODEL_TYPE_GEOGRAPHIC: u16 = 2;

/// What a TIFF declares about its placement. All fields are `None`/false for a plain TIFF.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GeoTags {
    /// Centre of sample (0, 0) and the (positive) spacings, in model units, if the file is
    /// georeferenced by scale + tiepoint or an axis-aligned transformation.
    pub georef: Option<GridGeoref>,
    /// "EPSG:n" from the ProjectedCSType or GeographicType GeoKey, if declared.
    pub crs: Option<String>,
    /// The GDAL_NODATA value (NaN if the tag says "nan"), in stored sample units.
    pub nodata: Option<f64>,
    /// True if the GeoKeys declare `RasterPixelIsPoint` (tiepoints address pixel centres).
    pub pixel_is_point: bool,
    /// True if the GeoKeys declare a geographic model (coordinates in degrees, not metres).
    pub geographic: bool,
}

/// Describes a TIFF decoding error for a user, naming the file.
pub(crate) fn tiff_err(path: &Path, e: TiffError) -> Error {
    let msg = match e {
        TiffError::IoError(io) if io.kind() == std::io::ErrorKind::UnexpectedEof => {
            "truncated TIFF: the file ends before the data its header points to".to_string()
        }
        TiffError::IoError(io) => return Error::io(path, io),
        TiffError::FormatError(f) => format!("not a valid TIFF (truncated or corrupt?): {f}"),
        TiffError::UnsupportedError(u) => format!("unsupported TIFF feature: {u}"),
        TiffError::LimitsExceeded => {
            "TIFF exceeds the decoder's memory limits (raise --max-memory)".to_string()
        }
        other => format!("cannot decode the TIFF: {other}"),
    };
    Error::bad_input(path, msg)
}

/// Opens a TIFF and reads its first directory (no pixel data yet). The decoder's buffer
/// limits are set from `max_memory`.
pub(crate) fn open(path: &Path, max_memory: u64) -> Result<Decoder<BufReader<File>>> {
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let dec = Decoder::new(BufReader::new(file)).map_err(|e| tiff_err(path, e))?;
    let cap = usize::try_from(max_memory).unwrap_or(usize::MAX);
    let mut limits = Limits::default();
    limits.decoding_buffer_size = cap;
    limits.intermediate_buffer_size = cap;
    limits.ifd_value_size = cap.min(1 << 28);
    Ok(dec.with_limits(limits))
}

/// The SampleFormat tag's first value (1 uint, 2 int, 3 float, 4 void, 5/6 complex); 1 if absent.
pub(crate) fn sample_format<R: Read + Seek>(path: &Path, dec: &mut Decoder<R>) -> Result<u16> {
    match dec
        .find_tag(Tag::SampleFormat)
        .map_err(|e| tag_err(path, "SampleFormat", e))?
    {
        None => Ok(1),
        Some(v) => {
            let v = v
                .into_u16_vec()
                .map_err(|e| tag_err(path, "SampleFormat", e))?;
            Ok(v.first().copied().unwrap_or(1))
        }
    }
}

/// True if the image stores each sample plane separately (PlanarConfiguration = 2).
pub(crate) fn is_planar<R: Read + Seek>(path: &Path, dec: &mut Decoder<R>) -> Result<bool> {
    Ok(dec
        .find_tag_unsigned::<u16>(Tag::PlanarConfiguration)
        .map_err(|e| tag_err(path, "PlanarConfiguration", e))?
        == Some(2))
}

fn tag_err(path: &Path, tag: &str, e: impl std::fmt::Display) -> Error {
    Error::bad_input(path, format!("cannot read the GeoTIFF {tag} tag: {e}"))
}

/// Parses the GDAL_NODATA ASCII value ("-9999", "nan", "-3.4e+38", ...).
pub(crate) fn parse_nodata(path: &Path, s: &str) -> Result<f64> {
    let t = s
        .trim_matches(|c: char| c == '\0' || c.is_whitespace())
        .to_ascii_lowercase();
    match t.as_str() {
        "nan" | "-nan" | "+nan" => Ok(f64::NAN),
        _ => t.parse::<f64>().map_err(|_| {
            Error::bad_input(
                path,
                format!("GDAL_NODATA tag holds {s:?}, which is not a number"),
            )
        }),
    }
}

/// Reads the geo tags of the decoder's current image. Errors (naming `path`) on malformed
/// or unsupported georeferencing (rotation, several tiepoints without a scale, zero or
/// negative spacing); a TIFF without geo tags gives `GeoTags::default()`.
pub(crate) fn read_geo_tags<R: Read + Seek>(path: &Path, dec: &mut Decoder<R>) -> Result<GeoTags> {
    let mut out = GeoTags::default();

    if let Some(v) = dec
        .find_tag(Tag::GdalNodata)
        .map_err(|e| tag_err(path, "GDAL_NODATA", e))?
    {
        let s = v
            .into_string()
            .map_err(|e| tag_err(path, "GDAL_NODATA", e))?;
        out.nodata = Some(parse_nodata(path, &s)?);
    }

    if let Some(v) = dec
        .find_tag(Tag::GeoKeyDirectoryTag)
        .map_err(|e| tag_err(path, "GeoKeyDirectory", e))?
    {
        let keys = v
            .into_u16_vec()
            .map_err(|e| tag_err(path, "GeoKeyDirectory", e))?;
        // Header: version, revision, minor, number of keys; then 4 shorts per key.
        let n = keys.get(3).copied().unwrap_or(0) as usize;
        let (mut projected, mut geographic_cs) = (None, None);
        for k in keys.get(4..).unwrap_or(&[]).chunks_exact(4).take(n) {
            let (id, loc, value) = (k[0], k[1], k[3]);
            if loc != 0 {
                continue; // value stored in another tag (strings, doubles): not needed here
            }
            match id {
                GT_RASTER_TYPE => out.pixel_is_point = value == RASTER_PIXEL_IS_POINT,
                GT_MODEL_TYPE => out.geographic |= value == MODEL_TYPE_GEOGRAPHIC,
                PROJECTED_CS_TYPE if (1..32767).contains(&value) => projected = Some(value),
                GEOGRAPHIC_TYPE if (1..32767).contains(&value) => geographic_cs = Some(value),
                _ => {}
            }
        }
        // A geographic CRS without a projected one means coordinates in degrees.
        out.geographic |= projected.is_none() && geographic_cs.is_some();
        out.crs = projected.or(geographic_cs).map(|c| format!("EPSG:{c}"));
    }
    // Pixel centre of sample (0,0) in raster space.
    let c = if out.pixel_is_point { 0.0 } else { 0.5 };

    let transform = dec
        .find_tag(Tag::ModelTransformationTag)
        .map_err(|e| tag_err(path, "ModelTransformation", e))?;
    let scale = dec
        .find_tag(Tag::ModelPixelScaleTag)
        .map_err(|e| tag_err(path, "ModelPixelScale", e))?;
    let ties = dec
        .find_tag(Tag::ModelTiepointTag)
        .map_err(|e| tag_err(path, "ModelTiepoint", e))?;

    let georef = if let Some(t) = transform {
        let m = t
            .into_f64_vec()
            .map_err(|e| tag_err(path, "ModelTransformation", e))?;
        if m.len() != 16 {
            return Err(Error::bad_input(
                path,
                format!("ModelTransformation has {} values, expected 16", m.len()),
            ));
        }
        if m[1] != 0.0 || m[4] != 0.0 {
            return Err(Error::bad_input(
                path,
                "ModelTransformation is rotated or sheared; only north-up grids are supported (warp the file first)",
            ));
        }
        // x = m0*I + m3, y = m5*J + m7
        Some(GridGeoref {
            origin_x: m[3] + c * m[0],
            origin_y: m[7] + c * m[5],
            spacing_x: m[0],
            spacing_y: -m[5],
        })
    } else {
        match (scale, ties) {
            (None, None) => None,
            (Some(_), None) => {
                return Err(Error::bad_input(
                    path,
                    "has ModelPixelScale but no ModelTiepoint",
                ));
            }
            (None, Some(_)) => {
                return Err(Error::bad_input(
                    path,
                    "has ModelTiepoint but no ModelPixelScale (ground-control-point georeferencing is not supported; warp the file first)",
                ));
            }
            (Some(s), Some(t)) => {
                let s = s
                    .into_f64_vec()
                    .map_err(|e| tag_err(path, "ModelPixelScale", e))?;
                let t = t
                    .into_f64_vec()
                    .map_err(|e| tag_err(path, "ModelTiepoint", e))?;
                if s.len() < 2 || t.len() < 6 {
                    return Err(Error::bad_input(
                        path,
                        format!(
                            "ModelPixelScale has {} values and ModelTiepoint {}; need at least 2 and 6",
                            s.len(),
                            t.len()
                        ),
                    ));
                }
                let (sx, sy) = (s[0], s[1]);
                let (i, j, x, y) = (t[0], t[1], t[3], t[4]);
                Some(GridGeoref {
                    origin_x: x + (c - i) * sx,
                    origin_y: y - (c - j) * sy,
                    spacing_x: sx,
                    spacing_y: sy,
                })
            }
        }
    };

    if let Some(g) = &georef {
        if !(g.spacing_x.is_finite()
            && g.spacing_x > 0.0
            && g.spacing_y.is_finite()
            && g.spacing_y != 0.0)
        {
            return Err(Error::bad_input(
                path,
                format!(
                    "GeoTIFF pixel size ({}, {}) is not a positive finite number",
                    g.spacing_x, g.spacing_y
                ),
            ));
        }
        if g.spacing_y < 0.0 {
            return Err(Error::bad_input(
                path,
                "GeoTIFF is south-up (negative y pixel scale); only north-up grids are supported",
            ));
        }
        if !(g.origin_x.is_finite() && g.origin_y.is_finite()) {
            return Err(Error::bad_input(path, "GeoTIFF tiepoint is not finite"));
        }
    }
    out.georef = georef;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nodata_strings() {
        let p = Path::new("x.tif");
        assert_eq!(parse_nodata(p, "-9999\0").unwrap(), -9999.0);
        assert!(parse_nodata(p, "nan").unwrap().is_nan());
        assert!(parse_nodata(p, "NaN").unwrap().is_nan());
        assert_eq!(
            parse_nodata(p, " -3.4028234663852886e+38 ").unwrap(),
            f32::MIN as f64
        );
        let e = parse_nodata(p, "none").unwrap_err().to_string();
        assert!(e.contains("x.tif") && e.contains("none"), "{e}");
    }
}
