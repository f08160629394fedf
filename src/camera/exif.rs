//! A photo's focal length in pixels, and its GPS position and heading, from its EXIF data
//! (`kamadak-exif`).
//!
//! In order of preference: `FocalLength` (mm) times `FocalPlaneXResolution` (pixels per
//! `FocalPlaneResolutionUnit` on the sensor, scaled to the image's width when the EXIF
//! dimensions differ); `FocalLengthIn35mmFilm` as `f35 · diagonal_px / 43.27` (the 35 mm
//! equivalent is defined by the diagonal of a 36 × 24 mm frame); `FocalLength` with a
//! sensor width the caller gives (`f · width_px / sensor_mm`). A photo without EXIF, or
//! without these fields, gives `None`; malformed EXIF is an error naming the file.
//!
//! GPS ([`exif_gps`]): `GPSLatitude`/`GPSLongitude` (degrees, minutes, seconds) with their
//! `N`/`S`, `E`/`W` references, `GPSAltitude` with `GPSAltitudeRef` (1 = below sea level),
//! `GPSImgDirection` with `GPSImgDirectionRef` (`T` true north, `M` magnetic). The latitude
//! and longitude are WGS 84 (as the EXIF standard says); the altitude is above sea level,
//! i.e. close to an orthometric height like a DEM's, not an ellipsoidal one.

use std::path::Path;

use exif::{In, Tag, Value};

use crate::error::{Error, Result};

/// A focal length read from EXIF, and how it was derived.
#[derive(Clone, Debug, PartialEq)]
pub struct ExifFocal {
    /// Focal length in pixels of the image's width.
    pub focal_px: f64,
    /// Which fields gave it.
    pub source: &'static str,
}

fn rational(f: &exif::Field) -> Option<f64> {
    match &f.value {
        Value::Rational(v) => v
            .first()
            .filter(|r| r.denom != 0)
            .map(|r| r.num as f64 / r.denom as f64),
        _ => f.value.get_uint(0).map(f64::from),
    }
}

/// The EXIF data of the image at `path`, `None` without any; errors name the file.
fn read_exif(path: &Path) -> Result<Option<exif::Exif>> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    match exif::Reader::new().read_from_container(&mut std::io::BufReader::new(file)) {
        Ok(d) => Ok(Some(d)),
        Err(exif::Error::NotFound(_)) => Ok(None),
        Err(exif::Error::Io(e)) => Err(Error::io(path, e)),
        Err(e) => Err(Error::bad_input(path, format!("malformed EXIF data: {e}"))),
    }
}

/// The focal length in pixels of the `width × height` image at `path` (see the
/// module docs (`src/camera/exif.rs`)); `sensor_width_mm` is used when EXIF gives the focal length alone.
pub fn exif_focal_px(
    path: &Path,
    width: u32,
    height: u32,
    sensor_width_mm: Option<f64>,
) -> Result<Option<ExifFocal>> {
    let Some(data) = read_exif(path)? else {
        return Ok(None);
    };
    let get = |t: Tag| {
        data.get_field(t, In::PRIMARY)
            .and_then(rational)
            .filter(|v| v.is_finite() && *v > 0.0)
    };
    let focal_mm = get(Tag::FocalLength);
    let (w, h) = (width as f64, height as f64);
    if let (Some(f), Some(res)) = (focal_mm, get(Tag::FocalPlaneXResolution)) {
        let unit_mm = match data
            .get_field(Tag::FocalPlaneResolutionUnit, In::PRIMARY)
            .and_then(|u| u.value.get_uint(0))
        {
            Some(3) => 10.0,
            Some(4) => 1.0,
            Some(5) => 1e-3,
            _ => 25.4, // 2 = inch, the default
        };
        let exif_w = data
            .get_field(Tag::PixelXDimension, In::PRIMARY)
            .and_then(|v| v.value.get_uint(0))
            .map(f64::from);
        let scale = exif_w.filter(|&ew| ew > 0.0).map_or(1.0, |ew| w / ew);
        return Ok(Some(ExifFocal {
            focal_px: f * res / unit_mm * scale,
            source: "FocalLength x FocalPlaneXResolution",
        }));
    }
    if let Some(f35) = get(Tag::FocalLengthIn35mmFilm) {
        return Ok(Some(ExifFocal {
            focal_px: f35 * w.hypot(h) / 36f64.hypot(24.0),
            source: "FocalLengthIn35mmFilm",
        }));
    }
    if let (Some(f), Some(s)) = (
        focal_mm,
        sensor_width_mm.filter(|s| s.is_finite() && *s > 0.0),
    ) {
        return Ok(Some(ExifFocal {
            focal_px: f * w / s,
            source: "FocalLength and the given sensor width",
        }));
    }
    Ok(None)
}

/// The camera body and lens setting a photo was taken with, from EXIF: `Make`, `Model`,
/// `BodySerialNumber`, `LensModel` and `FocalLength` joined, or `None` when EXIF has no
/// `Make` and `Model`. Two photos with the same key and image size share their intrinsics
/// (a fixed-lens or same-zoom camera); errors only for malformed EXIF.
pub fn exif_camera_body(path: &Path) -> Result<Option<String>> {
    let Some(data) = read_exif(path)? else {
        return Ok(None);
    };
    let text = |t: Tag| -> String {
        data.get_field(t, In::PRIMARY)
            .map(|f| f.display_value().to_string().trim().to_string())
            .unwrap_or_default()
    };
    let (make, model) = (text(Tag::Make), text(Tag::Model));
    if make.is_empty() && model.is_empty() {
        return Ok(None);
    }
    Ok(Some(format!(
        "{make}|{model}|{}|{}|{}",
        text(Tag::BodySerialNumber),
        text(Tag::LensModel),
        text(Tag::FocalLength)
    )))
}

/// A photo's GPS fix and heading from EXIF (see the module docs (`src/camera/exif.rs`)).
#[derive(Clone, Debug, PartialEq)]
pub struct ExifGps {
    /// WGS 84 latitude, degrees north.
    pub lat_deg: f64,
    /// WGS 84 longitude, degrees east.
    pub lon_deg: f64,
    /// Altitude above sea level, metres, if recorded.
    pub altitude_m: Option<f64>,
    /// Direction the camera looked, degrees clockwise from north, if recorded.
    pub direction_deg: Option<f64>,
    /// Whether that direction is from magnetic north (`GPSImgDirectionRef` `M`) rather than
    /// true north.
    pub direction_magnetic: bool,
}

/// The GPS fix of the photo at `path`: `None` without EXIF or without a latitude and
/// longitude; an error for malformed EXIF or coordinates outside ±90° / ±180°.
pub fn exif_gps(path: &Path) -> Result<Option<ExifGps>> {
    let Some(data) = read_exif(path)? else {
        return Ok(None);
    };
    let field = |t: Tag| data.get_field(t, In::PRIMARY);
    let text = |t: Tag| -> Option<String> {
        match &field(t)?.value {
            Value::Ascii(v) => v
                .first()
                .map(|b| String::from_utf8_lossy(b).trim().to_ascii_uppercase()),
            _ => None,
        }
    };
    let dms = |t: Tag| -> Option<f64> {
        match &field(t)?.value {
            Value::Rational(v) if !v.is_empty() && v.iter().all(|r| r.denom != 0) => Some(
                v.iter()
                    .take(3)
                    .zip([1.0, 60.0, 3600.0])
                    .map(|(r, d)| r.num as f64 / r.denom as f64 / d)
                    .sum(),
            ),
            _ => None,
        }
    };
    let (Some(lat), Some(lon)) = (dms(Tag::GPSLatitude), dms(Tag::GPSLongitude)) else {
        return Ok(None);
    };
    let lat = if text(Tag::GPSLatitudeRef).as_deref() == Some("S") {
        -lat
    } else {
        lat
    };
    let lon = if text(Tag::GPSLongitudeRef).as_deref() == Some("W") {
        -lon
    } else {
        lon
    };
    if !(lat.abs() <= 90.0 && lon.abs() <= 180.0) {
        return Err(Error::bad_input(
            path,
            format!("EXIF GPS position {lat}, {lon} is not a latitude and longitude"),
        ));
    }
    let below = field(Tag::GPSAltitudeRef).and_then(|f| f.value.get_uint(0)) == Some(1);
    let altitude_m = field(Tag::GPSAltitude)
        .and_then(rational)
        .filter(|a| a.is_finite())
        .map(|a| if below { -a } else { a });
    let direction_deg = field(Tag::GPSImgDirection)
        .and_then(rational)
        .filter(|d| d.is_finite() && (0.0..=360.0).contains(d));
    Ok(Some(ExifGps {
        lat_deg: lat,
        lon_deg: lon,
        altitude_m,
        direction_deg,
        direction_magnetic: text(Tag::GPSImgDirectionRef).as_deref() == Some("M"),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn images_without_exif_give_none_and_missing_files_fail() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("plain.png");
        image::RgbImage::new(4, 3).save(&p).unwrap();
        assert_eq!(exif_focal_px(&p, 4, 3, Some(22.0)).unwrap(), None);
        let e = exif_focal_px(&dir.path().join("missing.jpg"), 4, 3, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing.jpg"), "{e}");
        assert_eq!(exif_gps(&p).unwrap(), None);
    }
}
