//! Placing a decoded ortho image in the world: from GeoTIFF tags, on the DEM's grid, or
//! by an explicit extent of the outer pixel edges. All arithmetic in f64.

use std::path::Path;

use super::OrthoPlacement;
use crate::dem::Dem;
use crate::error::{Error, Result};
use crate::georef::{GridGeoref, WorldRect};
use crate::geotiff::GeoTags;

/// Pixel-centre georeference of a `width x height` image whose outer pixel edges span `r`.
pub fn georef_from_extent(r: &WorldRect, width: u32, height: u32) -> GridGeoref {
    let sx = r.width() / width as f64;
    let sy = r.height() / height as f64;
    GridGeoref {
        origin_x: r.min_x + 0.5 * sx,
        origin_y: r.max_y - 0.5 * sy,
        spacing_x: sx,
        spacing_y: sy,
    }
}

/// Computes the pixel-centre georeference for `placement`. Errors name the file.
pub(crate) fn place(
    path: &Path,
    placement: OrthoPlacement,
    width: u32,
    height: u32,
    tags: Option<&GeoTags>,
    dem: &Dem,
) -> Result<GridGeoref> {
    let g = match placement {
        OrthoPlacement::FromFile => match tags.and_then(|t| t.georef) {
            Some(g) => g,
            None => {
                return Err(Error::bad_input(
                    path,
                    "ortho has no georeference (no GeoTIFF tags); pass --ortho-same-grid or --ortho-extent MINX,MINY,MAXX,MAXY",
                ));
            }
        },
        OrthoPlacement::SameGridAsDem => {
            if (width as usize, height as usize) != (dem.width, dem.height) {
                return Err(Error::bad_input(
                    path,
                    format!(
                        "ortho is {width}x{height} pixels but the DEM is {}x{} samples; --ortho-same-grid needs identical sizes (use --ortho-extent otherwise)",
                        dem.width, dem.height
                    ),
                ));
            }
            dem.georef
        }
        OrthoPlacement::Extent(r) => {
            let finite = [r.min_x, r.min_y, r.max_x, r.max_y]
                .iter()
                .all(|v| v.is_finite());
            if !finite || r.max_x <= r.min_x || r.max_y <= r.min_y {
                return Err(Error::BadOption(format!(
                    "--ortho-extent {},{},{},{} for {}: needs finite MINX<MAXX and MINY<MAXY",
                    r.min_x,
                    r.min_y,
                    r.max_x,
                    r.max_y,
                    path.display()
                )));
            }
            georef_from_extent(&r, width, height)
        }
    };
    g.validate()
        .map_err(|e| Error::bad_input(path, e.to_string()))?;
    Ok(g)
}

/// World rectangle of the DEM's sample areas (centres ± half a spacing).
pub fn dem_area(dem: &Dem) -> WorldRect {
    let e = dem.extent();
    let (hx, hy) = (0.5 * dem.georef.spacing_x, 0.5 * dem.georef.spacing_y);
    WorldRect {
        min_x: e.min_x - hx,
        min_y: e.min_y - hy,
        max_x: e.max_x + hx,
        max_y: e.max_y + hy,
    }
}
