//! Coordinate reference systems by EPSG code or PROJ string (`proj4rs`, pure Rust; EPSG
//! definitions from `crs-definitions`), shared by the exports (to ECEF) and the camera
//! registration (EXIF GPS fixes into the store's CRS).

use glam::DVec3;
use proj4rs::Proj;

use crate::error::{Error, Result};

/// The PROJ string of `crs` (`EPSG:CODE` looked up, a `+proj=` string as given).
pub fn proj_string(crs: &str) -> Result<String> {
    let t = crs.trim();
    if t.starts_with('+') {
        return Ok(t.to_string());
    }
    let code = t
        .strip_prefix("EPSG:")
        .or_else(|| t.strip_prefix("epsg:"))
        .and_then(|c| c.parse::<u16>().ok())
        .ok_or_else(|| {
            Error::BadOption(format!(
                "CRS {crs:?}: expected EPSG:CODE or a PROJ string (+proj=...)"
            ))
        })?;
    crs_definitions::from_code(code)
        .map(|d| d.proj4.to_string())
        .ok_or_else(|| Error::BadOption(format!("CRS {crs:?}: EPSG code {code} is not known")))
}

/// The point at WGS 84 longitude `lon_deg`, latitude `lat_deg` (degrees) in `crs`: x, y in
/// the CRS's units (degrees for a geographic one), z = `height` unchanged (the datum shift
/// between WGS 84 and the CRS's datum, if any, applied to x and y only; heights are not
/// converted between ellipsoid and geoid).
pub fn from_lon_lat(crs: &str, lon_deg: f64, lat_deg: f64, height: f64) -> Result<DVec3> {
    let def = proj_string(crs)?;
    let dst = Proj::from_proj_string(&def)
        .map_err(|e| Error::BadOption(format!("CRS {crs:?} ({def}): {e}")))?;
    let src = Proj::from_proj_string("+proj=longlat +datum=WGS84 +no_defs")
        .map_err(|e| Error::BadOption(format!("geographic CRS: {e}")))?;
    let (x, y, _) = proj4rs::adaptors::transform_xyz(
        &src,
        &dst,
        lon_deg.to_radians(),
        lat_deg.to_radians(),
        0.0,
    )
    .map_err(|e| {
        Error::BadOption(format!(
            "cannot transform {lat_deg}, {lon_deg} to {crs}: {e}"
        ))
    })?;
    let (x, y) = if dst.is_latlong() {
        (x.to_degrees(), y.to_degrees())
    } else {
        (x, y)
    };
    let p = DVec3::new(x, y, height);
    if p.is_finite() {
        Ok(p)
    } else {
        Err(Error::BadOption(format!(
            "cannot transform {lat_deg}, {lon_deg} to {crs} (not finite)"
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_on_a_utm_central_meridian_has_the_false_easting() {
        // 15° E is the central meridian of UTM zone 33: easting 500 000 m; the northing of
        // 60° N with the zone's 0.9996 scale is 6 651 411.2 m (pyproj 3.6)
        let p = from_lon_lat("EPSG:32633", 15.0, 60.0, 770.0).unwrap();
        assert!((p.x - 500_000.0).abs() < 1e-3, "{p}");
        assert!((p.y - 6_651_411.2).abs() < 1.0, "{p}");
        assert_eq!(p.z, 770.0);
        let g = from_lon_lat("EPSG:4326", 15.0, 60.0, 1.0).unwrap();
        assert!(
            (g.x - 15.0).abs() < 1e-9 && (g.y - 60.0).abs() < 1e-9,
            "{g}"
        );
        assert!(from_lon_lat("EPSG:1", 15.0, 60.0, 0.0).is_err());
    }
}
