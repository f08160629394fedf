//! Geoid undulation grids: orthometric → ellipsoidal heights for 3D Tiles.
//!
//! Data type: [`GeoidGrid`], geoid heights N (metres above the WGS 84 ellipsoid) on a
//! regular longitude/latitude grid (degrees, sample centres), read from a single-band
//! GeoTIFF the user supplies (e.g. PROJ's `us_nga_egm96_15.tif` or `us_nga_egm08_25.tif`,
//! or any GDAL-written EGM96/EGM2008 grid in EPSG:4326). Ellipsoidal height h = H + N with
//! N bilinear between the four surrounding samples; longitudes wrap by 360° so global
//! grids stored as 0..360 or −180..180 both work. No-data samples and points outside
//! the grid are errors naming the file and the point, never a silent zero.

use std::path::{Path, PathBuf};

use crate::dem::{Dem, DemLoadOptions, load_dem};
use crate::error::{Error, Result};

/// A geoid height grid in geographic coordinates (module docs).
#[derive(Clone, Debug)]
pub struct GeoidGrid {
    dem: Dem,
    path: PathBuf,
}

impl GeoidGrid {
    /// Reads a GeoTIFF geoid grid. Errors if the file is not a readable single-band GeoTIFF
    /// with a georeference, if it declares a CRS other than a geographic one (EPSG:4326,
    /// 4979 or 4258), or if its extent is not in degrees.
    pub fn read(path: &Path) -> Result<GeoidGrid> {
        let bad = |why: String| Error::BadOption(format!("geoid grid {}: {why}", path.display()));
        let dem = load_dem(path, &DemLoadOptions::default())?;
        if let Some(crs) = &dem.crs
            && !matches!(crs.as_str(), "EPSG:4326" | "EPSG:4979" | "EPSG:4258")
        {
            return Err(bad(format!(
                "declares {crs}; a geoid grid must be in geographic longitude/latitude (EPSG:4326)"
            )));
        }
        let g = &dem.georef;
        let (w, h) = (dem.width as f64, dem.height as f64);
        let (x0, x1) = (g.origin_x, g.origin_x + (w - 1.0) * g.spacing_x);
        let (y1, y0) = (g.origin_y, g.origin_y - (h - 1.0) * g.spacing_y);
        if !(x0 >= -360.0 && x1 <= 360.0 && y0 >= -90.0 - 1e-9 && y1 <= 90.0 + 1e-9) {
            return Err(bad(format!(
                "extent x {x0}..{x1}, y {y0}..{y1} is not in degrees of longitude/latitude (no georeference?)"
            )));
        }
        Ok(GeoidGrid {
            dem,
            path: path.to_path_buf(),
        })
    }

    /// A grid from samples (row-major, north row first) with sample (0, 0) at
    /// (`lon0`, `lat0`) degrees and spacings `dlon`, `dlat` > 0 (rows run south).
    pub fn from_samples(
        width: usize,
        height: usize,
        values: Vec<f32>,
        lon0: f64,
        lat0: f64,
        dlon: f64,
        dlat: f64,
    ) -> Result<GeoidGrid> {
        let georef = crate::georef::GridGeoref {
            origin_x: lon0,
            origin_y: lat0,
            spacing_x: dlon,
            spacing_y: dlat,
        };
        Ok(GeoidGrid {
            dem: Dem::from_heights(width, height, values, georef)?,
            path: PathBuf::from("(samples)"),
        })
    }

    /// The file the grid was read from.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Geoid height N (metres) at longitude `lon`, latitude `lat` (degrees): bilinear in the
    /// grid. Errors outside the grid or next to a no-data sample.
    // indexed loops: each index serves more than one array or lookup
    #[allow(clippy::needless_range_loop)]
    pub fn undulation(&self, lon: f64, lat: f64) -> Result<f64> {
        let g = &self.dem.georef;
        let (w, h) = (self.dem.width, self.dem.height);
        let row = (g.origin_y - lat) / g.spacing_y;
        let span = (w - 1) as f64;
        let mut col = f64::NAN;
        for k in [0.0, -360.0, 360.0] {
            let c = (lon + k - g.origin_x) / g.spacing_x;
            if (0.0..=span).contains(&c) {
                col = c;
                break;
            }
        }
        if !(col.is_finite() && (0.0..=(h - 1) as f64).contains(&row)) {
            return Err(Error::BadOption(format!(
                "geoid grid {}: longitude {lon:.6}°, latitude {lat:.6}° is outside the grid",
                self.path.display()
            )));
        }
        let (c0, r0) = (
            (col.floor() as usize).min(w - 2),
            (row.floor() as usize).min(h - 2),
        );
        let (fc, fr) = (col - c0 as f64, row - r0 as f64);
        let mut v = [[0.0f64; 2]; 2];
        for dr in 0..2 {
            for dc in 0..2 {
                let i = (r0 + dr) * w + c0 + dc;
                let weight =
                    if dr == 0 { 1.0 - fr } else { fr } * if dc == 0 { 1.0 - fc } else { fc };
                if weight > 0.0 && self.dem.void[i] {
                    return Err(Error::BadOption(format!(
                        "geoid grid {}: no data next to longitude {lon:.6}°, latitude {lat:.6}°",
                        self.path.display()
                    )));
                }
                v[dr][dc] = self.dem.heights[i] as f64;
            }
        }
        // Lerp form: exact for a constant grid.
        let lerp = |a: f64, b: f64, t: f64| a + t * (b - a);
        Ok(lerp(
            lerp(v[0][0], v[0][1], fc),
            lerp(v[1][0], v[1][1], fc),
            fr,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// N = 20 + 0.5·lon − 0.25·lat on a 1° grid over 10..20°E, 60..70°N: bilinear is exact.
    fn plane() -> GeoidGrid {
        let (w, h) = (11, 11);
        let v: Vec<f32> = (0..h)
            .flat_map(|r| {
                (0..w).map(move |c| {
                    (20.0 + 0.5 * (10.0 + c as f64) - 0.25 * (70.0 - r as f64)) as f32
                })
            })
            .collect();
        GeoidGrid::from_samples(w, h, v, 10.0, 70.0, 1.0, 1.0).unwrap()
    }

    #[test]
    fn bilinear_is_exact_on_a_plane_and_longitudes_wrap() {
        let g = plane();
        for (lon, lat) in [(10.0, 60.0), (13.7, 66.25), (20.0, 70.0), (14.01, 61.99)] {
            let want = 20.0 + 0.5 * lon - 0.25 * lat;
            assert!(
                (g.undulation(lon, lat).unwrap() - want).abs() < 1e-5,
                "{lon} {lat}"
            );
            assert!((g.undulation(lon - 360.0, lat).unwrap() - want).abs() < 1e-5);
        }
    }

    #[test]
    fn outside_the_grid_is_an_error_naming_the_point() {
        let g = plane();
        let e = g.undulation(21.0, 65.0).unwrap_err().to_string();
        assert!(e.contains("outside the grid") && e.contains("21.0"), "{e}");
        assert!(g.undulation(15.0, 59.5).is_err());
    }
}
