//! From the store's projected CRS to Earth-centred, Earth-fixed coordinates (EPSG:4978,
//! WGS 84) and back, vertex by vertex in f64 (`proj4rs`, pure Rust; EPSG codes through
//! `crs-definitions`), and the east-north-up frame 3D Tiles content is written in.

use glam::{DMat3, DVec3};
use proj4rs::Proj;

use super::geoid::GeoidGrid;
pub use crate::crs::proj_string;
use crate::error::{Error, Result};

/// A projected (or geographic) CRS paired with WGS 84 geocentric coordinates.
/// [`ToEcef::to_ecef`] adds the geoid height N (metres; a constant, or bilinear in a
/// [`GeoidGrid`] at the point's longitude/latitude) to the store's heights first, so
/// orthometric store heights become ellipsoidal ones; [`ToEcef::from_ecef`] removes it.
pub struct ToEcef {
    src: Proj,
    geocent: Proj,
    longlat: Proj,
    heights: Heights,
    latlong: bool,
}

/// What is added to the store's heights.
enum Heights {
    Offset(f64),
    Grid(GeoidGrid),
}

impl ToEcef {
    /// `crs`: `EPSG:CODE` or a PROJ string (`+proj=utm +zone=33 +datum=WGS84`).
    pub fn new(crs: &str, height_offset: f64) -> Result<ToEcef> {
        let def = proj_string(crs)?;
        let src = Proj::from_proj_string(&def)
            .map_err(|e| Error::BadOption(format!("CRS {crs:?} ({def}): {e}")))?;
        let geocent = Proj::from_proj_string("+proj=geocent +datum=WGS84 +units=m +no_defs")
            .map_err(|e| Error::BadOption(format!("geocentric CRS: {e}")))?;
        if !height_offset.is_finite() {
            return Err(Error::BadOption(format!(
                "geoid offset {height_offset} is not finite"
            )));
        }
        let longlat = Proj::from_proj_string("+proj=longlat +datum=WGS84 +no_defs")
            .map_err(|e| Error::BadOption(format!("geographic CRS: {e}")))?;
        Ok(ToEcef {
            latlong: src.is_latlong(),
            src,
            geocent,
            longlat,
            heights: Heights::Offset(height_offset),
        })
    }

    /// As [`ToEcef::new`], with the geoid height taken from `grid` at every point.
    pub fn with_geoid(crs: &str, grid: GeoidGrid) -> Result<ToEcef> {
        let mut t = ToEcef::new(crs, 0.0)?;
        t.heights = Heights::Grid(grid);
        Ok(t)
    }

    /// The geoid height N (metres) [`ToEcef::to_ecef`] adds at `p` (the store's CRS).
    pub fn geoid_height(&self, p: DVec3) -> Result<f64> {
        match &self.heights {
            Heights::Offset(m) => Ok(*m),
            Heights::Grid(g) => {
                let (lon, lat) = if self.latlong {
                    (p.x, p.y)
                } else {
                    let (a, b, _) =
                        proj4rs::adaptors::transform_xyz(&self.src, &self.longlat, p.x, p.y, p.z)
                            .map_err(|e| {
                            Error::BadOption(format!(
                                "cannot transform {p} to longitude/latitude: {e}"
                            ))
                        })?;
                    (a.to_degrees(), b.to_degrees())
                };
                g.undulation(lon, lat)
            }
        }
    }

    /// The ECEF position (metres) of a point in the CRS (x, y in its units, degrees for a
    /// geographic CRS; z the store's height).
    pub fn to_ecef(&self, p: DVec3) -> Result<DVec3> {
        let (x, y) = if self.latlong {
            (p.x.to_radians(), p.y.to_radians())
        } else {
            (p.x, p.y)
        };
        let (a, b, c) = proj4rs::adaptors::transform_xyz(
            &self.src,
            &self.geocent,
            x,
            y,
            p.z + self.geoid_height(p)?,
        )
        .map_err(|e| Error::BadOption(format!("cannot transform {p} to ECEF: {e}")))?;
        let q = DVec3::new(a, b, c);
        if !q.is_finite() {
            return Err(Error::BadOption(format!(
                "cannot transform {p} to ECEF (not finite)"
            )));
        }
        Ok(q)
    }

    /// The inverse of [`ToEcef::to_ecef`] (the height offset removed again).
    pub fn from_ecef(&self, q: DVec3) -> Result<DVec3> {
        let (a, b, c) = proj4rs::adaptors::transform_xyz(&self.geocent, &self.src, q.x, q.y, q.z)
            .map_err(|e| Error::BadOption(format!("cannot transform ECEF {q}: {e}")))?;
        let (a, b) = if self.latlong {
            (a.to_degrees(), b.to_degrees())
        } else {
            (a, b)
        };
        let n = match &self.heights {
            Heights::Offset(m) => *m,
            Heights::Grid(g) => {
                let (lon, lat) = geodetic_lon_lat(q);
                g.undulation(lon.to_degrees(), lat.to_degrees())?
            }
        };
        Ok(DVec3::new(a, b, c - n))
    }
}

/// Rotation from ECEF to the east-north-up frame at ECEF point `q` (rows east, north, up,
/// WGS 84 geodetic latitude).
pub fn ecef_to_enu(q: DVec3) -> DMat3 {
    let (lon, lat) = geodetic_lon_lat(q);
    let (so, co) = lon.sin_cos();
    let (sa, ca) = lat.sin_cos();
    let east = DVec3::new(-so, co, 0.0);
    let north = DVec3::new(-sa * co, -sa * so, ca);
    let up = DVec3::new(ca * co, ca * so, sa);
    DMat3::from_cols(east, north, up).transpose()
}

/// Geodetic longitude and latitude (radians, WGS 84) of an ECEF point (Bowring's formula,
/// exact to far below a millimetre near the surface).
fn geodetic_lon_lat(q: DVec3) -> (f64, f64) {
    let a = 6_378_137.0f64;
    let f = 1.0 / 298.257_223_563;
    let b = a * (1.0 - f);
    let e2 = f * (2.0 - f);
    let ep2 = (a * a - b * b) / (b * b);
    let p = (q.x * q.x + q.y * q.y).sqrt();
    let th = (q.z * a).atan2(p * b);
    let lat = (q.z + ep2 * b * th.sin().powi(3)).atan2(p - e2 * a * th.cos().powi(3));
    (q.y.atan2(q.x), lat)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn utm_central_meridian_on_the_equator_is_on_the_axis_plane() {
        let t = ToEcef::new("EPSG:32633", 0.0).unwrap();
        let q = t.to_ecef(DVec3::new(500_000.0, 0.0, 0.0)).unwrap();
        let a = 6_378_137.0f64;
        let want = DVec3::new(
            a * 15f64.to_radians().cos(),
            a * 15f64.to_radians().sin(),
            0.0,
        );
        assert!((q - want).length() < 1e-3, "{q} vs {want}");
    }

    #[test]
    fn round_trip_is_within_a_millimetre_and_the_offset_is_a_height() {
        let t = ToEcef::new("EPSG:32633", 35.0).unwrap();
        let p = DVec3::new(446_722.0, 7_396_671.0, 770.0);
        let q = t.to_ecef(p).unwrap();
        let back = t.from_ecef(q).unwrap();
        assert!((back - p).length() < 1e-3, "{back} vs {p}");
        let q0 = ToEcef::new("EPSG:32633", 0.0).unwrap().to_ecef(p).unwrap();
        let up = ecef_to_enu(q0).row(2);
        assert!(((q - q0).dot(up) - 35.0).abs() < 1e-6 && (q - q0).length() < 35.0 + 1e-6);
    }

    /// N = 10 + 0.05·lon + 0.1·lat on a global 1° grid (bilinear is exact on it).
    fn plane_grid() -> GeoidGrid {
        let (w, h) = (361, 181);
        let v: Vec<f32> = (0..h)
            .flat_map(|r| {
                (0..w).map(move |c| {
                    (10.0 + 0.05 * (c as f64 - 180.0) + 0.1 * (90.0 - r as f64)) as f32
                })
            })
            .collect();
        GeoidGrid::from_samples(w, h, v, -180.0, 90.0, 1.0, 1.0).unwrap()
    }

    #[test]
    fn a_geoid_grid_adds_its_value_at_the_point_and_round_trips() {
        let t = ToEcef::with_geoid("EPSG:32633", plane_grid()).unwrap();
        // UTM 33N's central meridian on the equator: longitude 15°, latitude 0.
        let n = t.geoid_height(DVec3::new(500_000.0, 0.0, 0.0)).unwrap();
        assert!((n - 10.75).abs() < 1e-5, "{n}");
        let p = DVec3::new(446_722.0, 7_396_671.0, 770.0);
        let q = t.to_ecef(p).unwrap();
        let (lon, lat) = geodetic_lon_lat(q);
        let want = 10.0 + 0.05 * lon.to_degrees() + 0.1 * lat.to_degrees();
        let q_const = ToEcef::new("EPSG:32633", want).unwrap().to_ecef(p).unwrap();
        assert!((q - q_const).length() < 1e-4, "{}", (q - q_const).length());
        assert!((t.from_ecef(q).unwrap() - p).length() < 1e-3);
        // A geographic store CRS takes the point's own degrees.
        let g = ToEcef::with_geoid("EPSG:4326", plane_grid()).unwrap();
        let n = g.geoid_height(DVec3::new(-120.5, 46.25, 0.0)).unwrap();
        assert!(
            (n - (10.0 - 0.05 * 120.5 + 0.1 * 46.25)).abs() < 1e-5,
            "{n}"
        );
    }

    #[test]
    fn enu_frame_is_orthonormal_and_up_is_the_ellipsoid_normal() {
        let t = ToEcef::new("EPSG:32633", 0.0).unwrap();
        let p = DVec3::new(446_722.0, 7_396_671.0, 0.0);
        let q = t.to_ecef(p).unwrap();
        let r = ecef_to_enu(q);
        assert!(
            (r * r.transpose() - DMat3::IDENTITY)
                .abs()
                .to_cols_array()
                .iter()
                .all(|v| *v < 1e-12)
        );
        // 100 m up in height moves along the frame's up axis.
        let q2 = t.to_ecef(p + DVec3::Z * 100.0).unwrap();
        let d = r * (q2 - q);
        assert!(
            d.x.abs() < 1e-6 && d.y.abs() < 1e-6 && (d.z - 100.0).abs() < 1e-6,
            "{d}"
        );
    }

    #[test]
    fn bad_crs_names_are_refused() {
        assert!(ToEcef::new("EPSG:1", 0.0).is_err());
        assert!(
            ToEcef::new("UTM33", 0.0)
                .err()
                .is_some_and(|e| e.to_string().contains("UTM33"))
        );
    }
}
