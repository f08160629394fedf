//! Stage 0 input: digital elevation models.
//!
//! Data type: [`Dem`], a north-up grid of f32 heights (world units, metres) with an
//! f64 [`GridGeoref`] and a void mask. Voids (no-data) are already filled for geometry
//! by the rule in [`fill`]; `void[i]` stays true there so textures can mark them unknown.
//!
//! Readers: GeoTIFF (8–64-bit integer and 16/32/64-bit float samples, strips and tiles,
//! deflate/LZW/PackBits/none, ModelPixelScale + ModelTiepoint, GDAL_NODATA), greyscale PNG
//! with scale/offset, Mapbox Terrain-RGB PNG, and raw little-endian f32. Every reader
//! refuses inputs whose header would need more than [`DemLoadOptions::max_memory`] bytes
//! before decoding pixel data. See `docs/inputs.md` for formats, flags and conventions.
//!
//! Pipeline of [`load_dem`]: validate options → pick the format ([`DemFormat`], inferred
//! from extension/PNG header when not given) → reader decodes samples and marks no-data →
//! values become heights (`value * z_scale + z_offset`, checked finite and within
//! ±100 km) → voids are filled by [`fill::fill_voids`] → georeference from the file or
//! the options (spacing 1, origin (0, 0) with a warning if neither).

mod convert;
mod detect;
pub mod fill;
mod geotiff;
pub(crate) mod limits;
mod plausibility;
mod png16;
mod raw_f32;
mod terrain_rgb;

pub use convert::{MAX_ABS_HEIGHT, NODATA_SENTINELS};
pub use terrain_rgb::decode_terrain_rgb;

use std::path::Path;

use crate::error::{Error, Result};
use crate::georef::{GridGeoref, WorldRect};

/// On-disk DEM formats cliffmap reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
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
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
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
    /// Without a declared no-data value (neither `nodata` nor the file's tag), take the
    /// common sentinels ([`NODATA_SENTINELS`]: −9999, −32768, −3.4e38, NaN) as no-data, with
    /// a message naming value and count (raw f32 and GeoTIFF). Default on (`--nodata none`
    /// turns it off).
    #[serde(default = "sentinels_on")]
    pub nodata_sentinels: bool,
    /// Refuse inputs whose decoded size would exceed this many bytes.
    pub max_memory: u64,
}

fn sentinels_on() -> bool {
    true
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
            nodata_sentinels: true,
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
    pub fn from_heights(
        width: usize,
        height: usize,
        heights: Vec<f32>,
        georef: GridGeoref,
    ) -> Result<Dem> {
        if width < 2 || height < 2 {
            return Err(Error::BadOption(format!(
                "a DEM needs at least 2x2 samples, got {width}x{height}"
            )));
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
        Ok(Dem {
            width,
            height,
            heights,
            void,
            georef,
            crs: None,
        })
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

    /// The quad of samples around a fractional grid position, clamped to the grid: its
    /// corner heights `[h(r0, c0), h(r0, c0+1), h(r0+1, c0), h(r0+1, c0+1)]` and the
    /// position's fractions `(fr, fc)` in [0, 1] within it.
    pub fn quad_at(&self, row: f64, col: f64) -> ([f64; 4], f64, f64) {
        let r = row.clamp(0.0, (self.height - 1) as f64);
        let c = col.clamp(0.0, (self.width - 1) as f64);
        let r0 = (r.floor() as usize).min(self.height - 2);
        let c0 = (c.floor() as usize).min(self.width - 2);
        let h = |rr: usize, cc: usize| self.at(rr, cc) as f64;
        (
            [h(r0, c0), h(r0, c0 + 1), h(r0 + 1, c0), h(r0 + 1, c0 + 1)],
            r - r0 as f64,
            c - c0 as f64,
        )
    }

    /// Bilinear height at a fractional grid position, clamped to the grid.
    pub fn bilinear(&self, row: f64, col: f64) -> f64 {
        let ([h00, h01, h10, h11], fr, fc) = self.quad_at(row, col);
        let top = h00 * (1.0 - fc) + h01 * fc;
        let bot = h10 * (1.0 - fc) + h11 * fc;
        top * (1.0 - fr) + bot * fr
    }

    /// World rectangle spanned by the sample centres.
    pub fn extent(&self) -> WorldRect {
        let (x0, y0) = self.georef.world(0.0, 0.0);
        let (x1, y1) = self
            .georef
            .world((self.height - 1) as f64, (self.width - 1) as f64);
        WorldRect {
            min_x: x0,
            min_y: y1,
            max_x: x1,
            max_y: y0,
        }
    }

    /// Smallest and largest height.
    pub fn height_range(&self) -> (f32, f32) {
        self.heights
            .iter()
            .fold((f32::INFINITY, f32::NEG_INFINITY), |(a, b), &h| {
                (a.min(h), b.max(h))
            })
    }

    /// Fraction of samples that were no-data.
    pub fn void_fraction(&self) -> f64 {
        self.void.iter().filter(|&&v| v).count() as f64 / self.void.len() as f64
    }
}

/// Samples as decoded by a reader, before void filling and georeference defaults.
pub(crate) struct Decoded {
    pub width: usize,
    pub height: usize,
    pub heights: Vec<f32>,
    pub void: Vec<bool>,
    pub georef: Option<GridGeoref>,
    pub crs: Option<String>,
    #[allow(dead_code)]
    pub geographic: bool,
    /// Samples taken as no-data by the undeclared sentinels (raw f32 and GeoTIFF).
    pub sentinels: convert::SentinelCounts,
}

/// Refuses grids smaller than 2x2 (and absurd sizes that overflow indices).
pub(crate) fn check_size(path: &Path, width: usize, height: usize) -> Result<()> {
    if width < 2 || height < 2 {
        return Err(Error::bad_input(
            path,
            format!("a DEM needs at least 2x2 samples, the file has {width}x{height}"),
        ));
    }
    if width
        .checked_mul(height)
        .is_none_or(|n| n > u32::MAX as usize * 4)
    {
        return Err(Error::bad_input(
            path,
            format!("absurd DEM size {width}x{height}"),
        ));
    }
    Ok(())
}

pub(crate) fn scaling(opts: &DemLoadOptions) -> convert::Scaling {
    convert::Scaling {
        scale: opts.z_scale.unwrap_or(1.0),
        offset: opts.z_offset.unwrap_or(0.0),
    }
}

fn validate_options(path: &Path, opts: &DemLoadOptions) -> Result<()> {
    let bad = |flag: &str, v: String, why: &str| {
        Err(Error::BadOption(format!(
            "{flag} {v} for {}: {why}",
            path.display()
        )))
    };
    if let Some(s) = opts.spacing
        && !(s.is_finite() && s > 0.0)
    {
        return bad(
            "--spacing",
            s.to_string(),
            "must be a positive finite number of metres",
        );
    }
    if let Some((x, y)) = opts.origin
        && !(x.is_finite() && y.is_finite())
    {
        return bad(
            "--origin",
            format!("{x},{y}"),
            "must be two finite coordinates",
        );
    }
    if let Some(z) = opts.z_scale
        && !(z.is_finite() && z != 0.0)
    {
        return bad(
            "--z-scale",
            z.to_string(),
            "must be a finite non-zero number",
        );
    }
    if let Some(z) = opts.z_offset
        && !z.is_finite()
    {
        return bad("--z-offset", z.to_string(), "must be finite");
    }
    if let Some(nd) = opts.nodata
        && nd.is_infinite()
    {
        return bad("--nodata", nd.to_string(), "must be a number or nan");
    }
    for (flag, v) in [("--width", opts.width), ("--height", opts.height)] {
        if v == Some(0) {
            return bad(flag, "0".into(), "must be at least 2");
        }
    }
    if opts.max_memory == 0 {
        return bad("--max-memory", "0".into(), "must be positive");
    }
    Ok(())
}

/// Names of values commonly used as undeclared no-data markers that are still plausible heights.
const SUSPECT_NODATA: [f32; 3] = [-9999.0, -32768.0, -32767.0];

/// Reads a DEM file. Errors name the file and the problem; no panics on any input.
///
/// Guarantees on success: the [`Dem`] invariants hold (≥ 2x2, finite heights, validated
/// georef); `void[i]` marks samples that were no-data (filled by [`fill::fill_voids`]);
/// `georef` is the file's GeoTIFF georeference (sample centres, f64) with `opts.spacing`
/// / `opts.origin` overriding it, or spacing 1 and origin (0, 0) when neither exists.
pub fn load_dem(path: &Path, opts: &DemLoadOptions) -> Result<Dem> {
    validate_options(path, opts)?;
    let format = match opts.format {
        Some(f) => f,
        None => detect::detect(path)?,
    };
    let d = match format {
        DemFormat::Geotiff => geotiff::read(path, opts)?,
        DemFormat::Png16 => png16::read(path, opts)?,
        DemFormat::TerrainRgb => terrain_rgb::read(path, opts)?,
        DemFormat::F32 => raw_f32::read(path, opts)?,
    };
    let Decoded {
        width,
        height,
        mut heights,
        void,
        georef,
        crs,
        sentinels,
        ..
    } = d;
    if let Some(found) = sentinels.describe() {
        tracing::warn!(
            "{}: taken as no-data (no --nodata given and no no-data tag in the file): {found}; \
             `--nodata none` keeps every value as a height",
            path.display()
        );
    }
    if format != DemFormat::F32 {
        for (flag, v, actual) in [
            ("--width", opts.width, width),
            ("--height", opts.height, height),
        ] {
            if v.is_some_and(|v| v != actual) {
                return Err(Error::bad_input(
                    path,
                    format!(
                        "{flag} {} does not match the file's size ({width}x{height})",
                        v.unwrap_or(0)
                    ),
                ));
            }
        }
    }
    let nvoid = void.iter().filter(|&&v| v).count();
    if nvoid == void.len() {
        return Err(Error::bad_input(
            path,
            "every sample is no-data; check --nodata",
        ));
    }
    if nvoid > 0 {
        fill::fill_voids(width, height, &mut heights, &void);
    }
    if opts.nodata.is_none() {
        for s in SUSPECT_NODATA {
            let count = heights
                .iter()
                .zip(&void)
                .filter(|(h, v)| !**v && **h == s)
                .count();
            if count > 0 {
                tracing::warn!(
                    "{}: {count} samples have height {s}, a common no-data marker; pass --nodata {s} if they are missing data",
                    path.display()
                );
            }
        }
    }

    let mut g = georef.unwrap_or(GridGeoref::new(0.0, 0.0, 1.0));
    match opts.spacing {
        Some(s) => (g.spacing_x, g.spacing_y) = (s, s),
        None if georef.is_none() => {
            tracing::warn!(
                "{}: no georeference in the file and no --spacing; using spacing 1",
                path.display()
            )
        }
        None => {}
    }
    match opts.origin {
        Some((x, y)) => (g.origin_x, g.origin_y) = (x, y),
        None if georef.is_none() => {
            tracing::warn!(
                "{}: no georeference in the file and no --origin; using origin (0, 0)",
                path.display()
            )
        }
        None => {}
    }
    g.validate()
        .map_err(|e| Error::bad_input(path, e.to_string()))?;
    if let Some(w) = plausibility::implausible_walls(width, height, &heights, &void, &g) {
        tracing::warn!("{}: {w}", path.display());
    }
    Ok(Dem {
        width,
        height,
        heights,
        void,
        georef: g,
        crs,
    })
}
