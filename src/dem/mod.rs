//! Stage 0 input: digital elevation models.
//!
//! Data type: [`Dem`], a north-up grid of f32 heights (world units, metres) with an
//! f64 [`GridGeoref`] and a void mask. Voids (no-data) are already filled for geometry
//! by the rule in [`fill`]; `void[i]` stays true there so textures can mark them unknown.
//!
//! Readers: GeoTIFF (f32/f64/i16/u16/i32/u32, strips and tiles, deflate/LZW/none,
//! ModelPixelScale + ModelTiepoint, GDAL_NODATA), 16-bit greyscale PNG with scale/offset,
//! Mapbox Terrain-RGB PNG, and raw little-endian f32. Every reader refuses inputs whose
//! header would need more than [`DemLoadOptions::max_memory`] bytes.

use std::path::Path;

use crate::error::{Error, Result};
use crate::georef::{GridGeoref, WorldRect};

/// On-disk DEM formats cliffmap reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DemFormat {
    /// GeoTIFF (or plain TIFF with explicit spacing/origin).
    Geotiff,
    /// 16-bit greyscale PNG; height = value * z_scale + z_offset.
    Png16,
    /// Mapbox Terrain-RGB PNG; height = -10000 + (R*65536 + G*256 + B) * 0.1.
    TerrainRgb,
    /// Raw little-endian f32, row-major, rows north to south; needs width and height.
    F32,
}

/// How to read a DEM file. Unset fields fall back to the file's own metadata or defaults.
#[derive(Clone, Debug)]
pub struct DemLoadOptions {
    /// Format; inferred from the extension (and for PNG from the colour type) when `None`.
    pub format: Option<DemFormat>,
    /// Width in samples (required for raw f32).
    pub width: Option<usize>,
    /// Height in samples (required for raw f32).
    pub height: Option<usize>,
    /// Multiplier applied to stored values (PNG16; also applied to other formats when set).
    pub z_scale: Option<f64>,
    /// Offset added after scaling.
    pub z_offset: Option<f64>,
    /// Sample spacing in world units; overrides the file's georeference.
    pub spacing: Option<f64>,
    /// World position of the centre of the north-west sample; overrides the file's.
    pub origin: Option<(f64, f64)>,
    /// Value that marks no-data (overrides GDAL_NODATA). `Some(NAN)` declares NaN as no-data.
    pub nodata: Option<f64>,
    /// Refuse inputs whose decoded size would exceed this many bytes.
    pub max_memory: u64,
}

impl Default for DemLoadOptions {
    fn default() -> Self {
        DemLoadOptions {
            format: None,
            width: None,
            height: None,
            z_scale: None,
            z_offset: None,
            spacing: None,
            origin: None,
            nodata: None,
            max_memory: 8 << 30,
        }
    }
}

/// A north-up height grid. Invariants: `heights.len() == void.len() == width * height`,
/// `width, height >= 2`, every height finite (voids filled), georef validated.
#[derive(Clone, Debug)]
pub struct Dem {
    /// Samples per row (west to east).
    pub width: usize,
    /// Rows (north to south).
    pub height: usize,
    /// Heights in world units, row-major.
    pub heights: Vec<f32>,
    /// True where the source had no data (height filled by [`fill`]).
    pub void: Vec<bool>,
    /// Placement of sample centres in the world.
    pub georef: GridGeoref,
    /// Coordinate reference system if the file declared one (e.g. "EPSG:32633").
    pub crs: Option<String>,
}

impl Dem {
    /// Builds a DEM from complete, finite heights (no voids). Errors on size mismatch,
    /// fewer than 2x2 samples, non-finite heights or an invalid georeference.
    pub fn from_heights(width: usize, height: usize, heights: Vec<f32>, georef: GridGeoref) -> Result<Dem> {
        if width < 2 || height < 2 {
            return Err(Error::BadOption(format!("a DEM needs at least 2x2 samples, got {width}x{height}")));
        }
        if heights.len() != width * height {
            return Err(Error::BadOption(format!(
                "DEM of {width}x{height} needs {} heights, got {}",
                width * height,
                heights.len()
            )));
        }
        if let Some(i) = heights.iter().position(|h| !h.is_finite()) {
            return Err(Error::BadOption(format!(
                "height at row {}, column {} is not finite ({})",
                i / width,
                i % width,
                heights[i]
            )));
        }
        georef.validate()?;
        let void = vec![false; heights.len()];
        Ok(Dem { width, height, heights, void, georef, crs: None })
    }

    /// Height of sample (row, col). Panics if out of range (internal use with checked indices).
    #[inline]
    pub fn at(&self, row: usize, col: usize) -> f32 {
        self.heights[row * self.width + col]
    }

    /// Whether sample (row, col) was no-data in the source.
    #[inline]
    pub fn is_void(&self, row: usize, col: usize) -> bool {
        self.void[row * self.width + col]
    }

    /// Bilinear height at a fractional grid position, clamped to the grid.
    pub fn bilinear(&self, row: f64, col: f64) -> f64 {
        let r = row.clamp(0.0, (self.height - 1) as f64);
        let c = col.clamp(0.0, (self.width - 1) as f64);
        let r0 = (r.floor() as usize).min(self.height - 2);
        let c0 = (c.floor() as usize).min(self.width - 2);
        let (fr, fc) = (r - r0 as f64, c - c0 as f64);
        let h = |rr: usize, cc: usize| self.at(rr, cc) as f64;
        let top = h(r0, c0) * (1.0 - fc) + h(r0, c0 + 1) * fc;
        let bot = h(r0 + 1, c0) * (1.0 - fc) + h(r0 + 1, c0 + 1) * fc;
        top * (1.0 - fr) + bot * fr
    }

    /// World rectangle spanned by the sample centres.
    pub fn extent(&self) -> WorldRect {
        let (x0, y0) = self.georef.world(0.0, 0.0);
        let (x1, y1) = self.georef.world((self.height - 1) as f64, (self.width - 1) as f64);
        WorldRect { min_x: x0, min_y: y1, max_x: x1, max_y: y0 }
    }

    /// Smallest and largest height.
    pub fn height_range(&self) -> (f32, f32) {
        self.heights.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &h| (a.min(h), b.max(h)))
    }

    /// Fraction of samples that were no-data.
    pub fn void_fraction(&self) -> f64 {
        self.void.iter().filter(|&&v| v).count() as f64 / self.void.len() as f64
    }
}

/// Reads a DEM file. Errors name the file and the problem; no panics on any input.
pub fn load_dem(path: &Path, opts: &DemLoadOptions) -> Result<Dem> {
    let _ = opts;
    Err(Error::bad_input(path, "DEM readers are not implemented yet"))
}
