//! Stage 0 input: the orthophoto.
//!
//! Data type: [`Ortho`], an RGBA8 image (alpha 0 = no coverage, 255 = known colour) with
//! an f64 [`GridGeoref`] for its pixel centres, north-up. Readers: PNG, JPEG and GeoTIFF
//! (RGB/RGBA, 8-bit), placed by GeoTIFF tags, by an explicit extent, or on the DEM's grid.

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

/// Reads an ortho image and places it. Errors if the file is unreadable, too large for
/// `max_memory`, or does not overlap `dem`.
pub fn load_ortho(path: &Path, placement: OrthoPlacement, dem: &Dem, max_memory: u64) -> Result<Ortho> {
    let _ = (placement, dem, max_memory);
    Err(Error::bad_input(path, "ortho readers are not implemented yet"))
}
