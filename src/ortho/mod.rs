//! Stage 0 input: the orthophoto.
//!
//! Data type: [`Ortho`], an RGBA8 image (alpha 0 = no coverage, 255 = known colour) with
//! an f64 [`GridGeoref`] for its pixel centres, north-up. Readers: PNG, JPEG and GeoTIFF
//! (RGB/RGBA/grey, 8-bit), placed by GeoTIFF tags, by an explicit extent, or on the DEM's
//! grid ([`OrthoPlacement`]). Pure black is ordinary colour; only alpha 0 (or a GeoTIFF's
//! GDAL_NODATA colour) marks pixels without data.

mod placement;
mod read;

pub use placement::{dem_area, georef_from_extent};

use std::path::Path;

use image::RgbaImage;

use crate::dem::Dem;
use crate::error::{Error, Result};
use crate::georef::{GridGeoref, WorldRect};

/// Where the ortho image lies in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OrthoPlacement {
    /// From the file's GeoTIFF tags (ModelPixelScale + ModelTiepoint).
    FromFile,
    /// Pixel (r, c) lies on DEM sample (r, c) (same grid; sizes must match).
    SameGridAsDem,
    /// The image's outer pixel edges span this world rectangle.
    Extent(WorldRect),
}

/// An orthophoto: colour with coverage, placed in the world.
#[derive(Clone, Debug)]
pub struct Ortho {
    /// Colour; alpha 0 marks pixels without image data.
    pub image: RgbaImage,
    /// Pixel-centre georeference (same convention as the DEM's).
    pub georef: GridGeoref,
}

impl Ortho {
    /// World rectangle covered by the image's outer pixel edges.
    pub fn extent(&self) -> WorldRect {
        let g = &self.georef;
        let (w, h) = (self.image.width() as f64, self.image.height() as f64);
        let (x0, y0) = g.world(-0.5, -0.5);
        let (x1, y1) = g.world(h - 0.5, w - 0.5);
        WorldRect { min_x: x0, min_y: y1, max_x: x1, max_y: y0 }
    }
}

/// Reads an ortho image and places it. Errors (naming the file) if it is unreadable, too
/// large for `max_memory` (checked from the header before decoding), lacks the placement
/// information `placement` needs, or does not overlap the DEM's sample areas.
pub fn load_ortho(path: &Path, placement: OrthoPlacement, dem: &Dem, max_memory: u64) -> Result<Ortho> {
    let d = read::read(path, max_memory)?;
    let georef = placement::place(path, placement, d.image.width(), d.image.height(), d.tags.as_ref(), dem)?;
    let ortho = Ortho { image: d.image, georef };
    let area = dem_area(dem);
    let e = ortho.extent();
    if e.intersect(&area).is_none() {
        return Err(Error::bad_input(
            path,
            format!(
                "ortho covers x {:.3}..{:.3}, y {:.3}..{:.3}, which does not overlap the DEM (x {:.3}..{:.3}, y {:.3}..{:.3})",
                e.min_x, e.max_x, e.min_y, e.max_y, area.min_x, area.max_x, area.min_y, area.max_y
            ),
        ));
    }
    if let (Some(t), Some(dc)) = (d.tags.as_ref().and_then(|t| t.crs.as_deref()), dem.crs.as_deref()) {
        if t != dc && placement == OrthoPlacement::FromFile {
            return Err(Error::bad_input(path, format!("ortho CRS {t} differs from the DEM's {dc}; reproject one of them")));
        }
    }
    Ok(ortho)
}
