//! GeoTIFF DEM reader: one band of u8/i8/u16/i16/u32/i32/u64/i64/f16/f32/f64 samples,
//! strips or tiles, any compression the `tiff` crate decodes (none, LZW, deflate,
//! PackBits, with or without predictor). Placement comes from the GeoTIFF tags (see
//! [`crate::geotiff`]); GDAL_NODATA marks voids unless `opts.nodata` overrides it.
//! Dimensions, band count and sample type are checked against `opts.max_memory` before
//! any pixel is decoded.

use std::path::Path;

use tiff::ColorType;
use tiff::decoder::DecodingResult;

use super::convert::{self, Sample, Scaling, SentinelCounts, VoidRule};
use super::{Decoded, DemLoadOptions, limits};
use crate::error::{Error, Result};
use crate::geotiff as gt;

fn convert_all<T: Sample>(
    path: &Path,
    w: usize,
    v: &[T],
    s: Scaling,
    rule: VoidRule,
) -> Result<(Vec<f32>, Vec<bool>, SentinelCounts)> {
    let mut counts = SentinelCounts::default();
    let (heights, void) = convert::to_heights(path, w, v.len(), s, rule.declared(), |i| {
        (v[i].to_f64(), counts.note(rule, rule.matches(v[i])))
    })?;
    Ok((heights, void, counts))
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
                format!(
                    "TIFF has {num_samples} bands; a DEM must have exactly one (extract the height band first)"
                ),
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
            return Err(Error::bad_input(
                path,
                "TIFF holds complex samples, which cannot be heights",
            ));
        }
        other => {
            return Err(Error::bad_input(
                path,
                format!("TIFF has unknown SampleFormat {other}"),
            ));
        }
    };
    let ok = match fmt {
        3 => matches!(bits, 16 | 32 | 64),
        _ => matches!(bits, 8 | 16 | 32 | 64),
    };
    if !ok {
        return Err(Error::bad_input(
            path,
            format!(
                "unsupported TIFF sample type: {bits}-bit {kind} (supported: 8/16/32/64-bit integers, 16/32/64-bit floats)"
            ),
        ));
    }
    super::check_size(path, w, h)?;
    limits::check(
        path,
        w as u64,
        h as u64,
        bits as u64 / 8 + limits::DEM_BYTES_PER_SAMPLE,
        opts.max_memory,
    )?;

    let tags = gt::read_geo_tags(path, &mut dec)?;
    let nodata = VoidRule::new(opts.nodata.or(tags.nodata), opts.nodata_sentinels);
    let data = dec.read_image().map_err(|e| gt::tiff_err(path, e))?;
    let n = w * h;
    let s = super::scaling(opts);
    let (heights, void, sentinels) = match &data {
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
    Ok(Decoded {
        sentinels,
        width: w,
        height: h,
        heights,
        void,
        georef: tags.georef,
        crs: tags.crs,
        geographic: tags.geographic,
    })
}

/// The first `n` decoded samples, or an error if the decoder returned fewer.
fn short<'a, T>(path: &Path, v: &'a [T], n: usize) -> Result<&'a [T]> {
    v.get(..n).ok_or_else(|| {
        Error::bad_input(
            path,
            format!("TIFF decoded to {} samples, expected {n}", v.len()),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::load_dem;
    use crate::georef::GridGeoref;
    use crate::tiffgen::{self, Geo, Raw};
    use tiff::encoder::{Compression, DeflateLevel, colortype};
    use tiff::tags::Predictor;

    fn geo(point: bool, nodata: Option<&str>) -> Geo {
        Geo {
            scale: (30.0, 30.0),
            tie: (0.0, 0.0, 627175.0, 4852085.0),
            pixel_is_point: point,
            epsg: Some(32718),
            nodata: nodata.map(str::to_string),
        }
    }

    fn f32_grid(w: usize, h: usize) -> Vec<f32> {
        (0..w * h)
            .map(|i| 500.0 + (i % w) as f32 * 1.5 - (i / w) as f32 * 0.25 + 0.125)
            .collect()
    }

    #[test]
    fn f32_strips_pixel_is_area_and_point() {
        let d = tempfile::tempdir().unwrap();
        let (w, h) = (7usize, 5usize);
        let v = f32_grid(w, h);
        for (point, name) in [(false, "area.tif"), (true, "point.tif")] {
            let p = d.path().join(name);
            tiffgen::write_strips::<colortype::Gray32Float>(
                &p,
                w as u32,
                h as u32,
                &v,
                Compression::Uncompressed,
                Predictor::None,
                Some(&geo(point, None)),
            );
            let dem = load_dem(&p, &Default::default()).unwrap();
            assert_eq!((dem.width, dem.height), (w, h));
            assert_eq!(dem.heights, v);
            assert_eq!(dem.crs.as_deref(), Some("EPSG:32718"));
            // PixelIsArea: tiepoint is the NW pixel's outer corner, centre is half a pixel in.
            let want = if point {
                (627175.0, 4852085.0)
            } else {
                (627190.0, 4852070.0)
            };
            assert_eq!(dem.georef, GridGeoref::new(want.0, want.1, 30.0));
        }
    }

    #[test]
    fn georef_is_exact_at_utm_scale_and_options_override() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("utm.tif");
        let v = f32_grid(4, 3);
        let g = Geo {
            scale: (3.0, 3.0),
            tie: (0.0, 0.0, 445302.17, 7396769.45),
            pixel_is_point: true,
            epsg: None,
            nodata: None,
        };
        tiffgen::write_strips::<colortype::Gray32Float>(
            &p,
            4,
            3,
            &v,
            Compression::Uncompressed,
            Predictor::None,
            Some(&g),
        );
        let dem = load_dem(&p, &Default::default()).unwrap();
        assert_eq!(dem.georef, GridGeoref::new(445302.17, 7396769.45, 3.0));
        assert_eq!(dem.crs, None);
        let o = DemLoadOptions {
            spacing: Some(2.0),
            origin: Some((1.0, 2.0)),
            ..Default::default()
        };
        assert_eq!(
            load_dem(&p, &o).unwrap().georef,
            GridGeoref::new(1.0, 2.0, 2.0)
        );
    }

    #[test]
    fn integer_types_compressions_and_predictor() {
        let d = tempfile::tempdir().unwrap();
        let (w, h) = (9u32, 8u32);
        let vi: Vec<i16> = (0..w * h).map(|i| i as i16 * 13 - 300).collect();
        let vu: Vec<u16> = (0..w * h).map(|i| 1000 + i as u16 * 17).collect();
        let cases = [
            ("i16_lzw.tif", Compression::Lzw, Predictor::Horizontal),
            (
                "i16_deflate.tif",
                Compression::Deflate(DeflateLevel::Balanced),
                Predictor::None,
            ),
            ("i16_none.tif", Compression::Uncompressed, Predictor::None),
        ];
        for (name, c, pred) in cases {
            let p = d.path().join(name);
            tiffgen::write_strips::<colortype::GrayI16>(
                &p,
                w,
                h,
                &vi,
                c,
                pred,
                Some(&geo(false, None)),
            );
            let dem = load_dem(&p, &Default::default()).unwrap();
            let want: Vec<f32> = vi.iter().map(|&x| x as f32).collect();
            assert_eq!(dem.heights, want, "{name}");
        }
        let p = d.path().join("u16_lzw.tif");
        tiffgen::write_strips::<colortype::Gray16>(
            &p,
            w,
            h,
            &vu,
            Compression::Lzw,
            Predictor::Horizontal,
            Some(&geo(false, Some("1017"))),
        );
        let o = DemLoadOptions {
            z_scale: Some(0.1),
            z_offset: Some(-100.0),
            ..Default::default()
        };
        let dem = load_dem(&p, &o).unwrap();
        assert!(dem.void[1] && dem.void.iter().filter(|v| **v).count() == 1);
        for i in (0..vu.len()).filter(|&i| i != 1) {
            assert_eq!(dem.heights[i], (vu[i] as f64 * 0.1 - 100.0) as f32);
        }
        // f64 + deflate
        let p = d.path().join("f64.tif");
        let v64: Vec<f64> = (0..w * h).map(|i| 1234.5678901 + i as f64).collect();
        tiffgen::write_strips::<colortype::Gray64Float>(
            &p,
            w,
            h,
            &v64,
            Compression::Deflate(DeflateLevel::Fast),
            Predictor::None,
            None,
        );
        let dem = load_dem(
            &p,
            &DemLoadOptions {
                spacing: Some(1.0),
                origin: Some((0.0, 0.0)),
                ..Default::default()
            },
        )
        .unwrap();
        assert!(dem.heights.iter().zip(&v64).all(|(a, b)| *a == *b as f32));
        // i32 and u8
        let p = d.path().join("i32.tif");
        let v32: Vec<i32> = (0..w * h).map(|i| i as i32 - 20).collect();
        tiffgen::write_strips::<colortype::GrayI32>(
            &p,
            w,
            h,
            &v32,
            Compression::Lzw,
            Predictor::None,
            None,
        );
        assert_eq!(load_dem(&p, &Default::default()).unwrap().heights[0], -20.0);
        let p = d.path().join("u8.tif");
        let v8: Vec<u8> = (0..w * h).map(|i| i as u8).collect();
        tiffgen::write_strips::<colortype::Gray8>(
            &p,
            w,
            h,
            &v8,
            Compression::Uncompressed,
            Predictor::None,
            None,
        );
        assert_eq!(load_dem(&p, &Default::default()).unwrap().heights[70], 70.0);
    }

    #[test]
    fn tiled_f32_with_partial_edge_tiles_and_nan_nodata() {
        let d = tempfile::tempdir().unwrap();
        let (w, h) = (37usize, 21usize);
        let mut v = f32_grid(w, h);
        v[5 * w + 30] = f32::NAN;
        let raw = Raw {
            width: w as u32,
            height: h as u32,
            bits: 32,
            sample_format: 3,
            samples: 1,
            photometric: 1,
            tile: Some((16, 16)),
            extra_alpha: false,
        };
        let p = d.path().join("tiled.tif");
        tiffgen::write_raw(
            &p,
            &raw,
            &tiffgen::f32_bytes(&v),
            Some(&geo(false, Some("nan"))),
            false,
        );
        let dem = load_dem(&p, &Default::default()).unwrap();
        assert_eq!((dem.width, dem.height), (w, h));
        assert!(dem.is_void(5, 30));
        for i in (0..w * h).filter(|&i| i != 5 * w + 30) {
            assert_eq!(dem.heights[i], v[i], "sample {i}");
        }
        assert!(dem.at(5, 30).is_finite());
        assert_eq!(dem.georef.origin_x, 627190.0);
    }

    #[test]
    fn void_fill_from_gdal_nodata() {
        let d = tempfile::tempdir().unwrap();
        let (w, h) = (6usize, 6usize);
        let mut v = f32_grid(w, h);
        for r in 1..4 {
            for c in 2..5 {
                v[r * w + c] = -9999.0;
            }
        }
        let p = d.path().join("holes.tif");
        tiffgen::write_strips::<colortype::Gray32Float>(
            &p,
            w as u32,
            h as u32,
            &v,
            Compression::Lzw,
            Predictor::None,
            Some(&geo(false, Some("-9999"))),
        );
        let dem = load_dem(&p, &Default::default()).unwrap();
        assert_eq!(dem.void.iter().filter(|x| **x).count(), 9);
        let valid: Vec<f32> = v.iter().copied().filter(|&x| x != -9999.0).collect();
        let (lo, hi) = valid
            .iter()
            .fold((f32::MAX, f32::MIN), |(a, b), &x| (a.min(x), b.max(x)));
        assert!(dem.heights.iter().all(|&x| x >= lo && x <= hi));
        // opts.nodata overrides the tag: -9999 is then a plausible (if odd) height
        let dem = load_dem(
            &p,
            &DemLoadOptions {
                nodata: Some(-1.0),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(dem.void_fraction(), 0.0);
        assert_eq!(dem.at(2, 3), -9999.0);
    }
}
