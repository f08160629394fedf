//! `cliffmap build`: DEM (+ ortho) to a cell store.

use std::path::PathBuf;

use cliffmap::pipeline::{BuildRecipe, RECIPE_VERSION, build_from_recipe};
use cliffmap::{DemLoadOptions, WorldRect};

use super::stats::print_summary;

/// Flags of `cliffmap build`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The DEM file (GeoTIFF, 16-bit PNG, Terrain-RGB PNG or raw little-endian f32).
    #[arg(long)]
    pub(super) dem: PathBuf,
    /// DEM format; inferred from the extension (and PNG colour type) when omitted.
    #[arg(long, value_enum)]
    dem_format: Option<super::values::DemFormatArg>,
    /// Width in samples (raw f32).
    #[arg(long)]
    width: Option<usize>,
    /// Height in samples (raw f32).
    #[arg(long)]
    height: Option<usize>,
    /// Height = stored value * z-scale + z-offset.
    #[arg(long, allow_hyphen_values = true)]
    z_scale: Option<f64>,
    /// Height offset added after scaling.
    #[arg(long, allow_hyphen_values = true)]
    z_offset: Option<f64>,
    /// Sample spacing in world units (overrides the file's georeference).
    #[arg(long, allow_hyphen_values = true)]
    spacing: Option<f64>,
    /// World X,Y of the centre of the north-west sample (overrides the file's georeference).
    #[arg(long, value_parser = super::parse_pair, allow_hyphen_values = true)]
    origin: Option<(f64, f64)>,
    /// Stored value meaning no-data (overrides GDAL_NODATA); "nan" declares NaN as no-data.
    /// Without it (and without a no-data tag) the common markers -9999, -32768, -3.4e38 and
    /// NaN are taken as no-data, with a message; "none" keeps every value as a height.
    #[arg(long, allow_hyphen_values = true, value_parser = parse_nodata)]
    nodata: Option<NodataArg>,
    /// Finest level's max vertical error in world units; doubles per coarser level.
    #[arg(long, default_value_t = 0.5, allow_hyphen_values = true)]
    max_error: f64,
    /// Texture side in texels per cell (power of two).
    #[arg(long, default_value_t = 256)]
    cell_texels: u32,
    /// Sample intervals per side of a finest-level cell (power of two).
    #[arg(long, default_value_t = 64)]
    cell_intervals: u32,
    /// PNG compression of the textures written: fast (fdeflate, the default), balanced or
    /// best. Same pixels; balanced files are ~0.77× the size of fast ones at ~1/18 the
    /// encoding speed (docs/performance.md, "PNG encoding").
    #[arg(long, value_enum, default_value = "fast")]
    png_compression: super::values::PngCompressionArg,
    /// Ortho image (PNG, JPEG or GeoTIFF); without it textures are derived from the DEM.
    #[arg(long)]
    pub(super) ortho: Option<PathBuf>,
    /// The ortho's pixel (r, c) lies on DEM sample (r, c).
    #[arg(long, conflicts_with = "ortho_extent")]
    ortho_same_grid: bool,
    /// World extent MINX,MINY,MAXX,MAXY of the ortho's outer pixel edges.
    #[arg(long, value_parser = parse_extent, allow_hyphen_values = true)]
    ortho_extent: Option<WorldRect>,
    /// Ortho pixels of exactly this colour R,G,B have no image data (e.g. 0,0,0).
    #[arg(long, value_parser = parse_colour)]
    ortho_nodata_colour: Option<[u8; 3]>,
    /// Refuse inputs that would need more memory than this (e.g. 8G).
    #[arg(long, value_parser = super::parse_bytes, default_value = "8G")]
    max_memory: u64,
    /// Output store directory.
    #[arg(long)]
    pub(super) out: PathBuf,
    /// Rebuild over an existing store made from other inputs or options.
    #[arg(long)]
    pub(super) force: bool,
    /// No progress bars or summary.
    #[arg(long)]
    pub(super) quiet: bool,
}

fn parse_colour(s: &str) -> Result<[u8; 3], String> {
    let v: Vec<u8> = s
        .split(',')
        .map(|p| {
            p.trim()
                .parse::<u8>()
                .map_err(|_| format!("not a colour component 0..255: {p:?}"))
        })
        .collect::<Result<_, _>>()?;
    <[u8; 3]>::try_from(v).map_err(|_| format!("expected R,G,B, got {s:?}"))
}

fn parse_extent(s: &str) -> Result<WorldRect, String> {
    let v = super::parse_list(s, 4)?;
    let r = WorldRect {
        min_x: v[0],
        min_y: v[1],
        max_x: v[2],
        max_y: v[3],
    };
    if r.max_x <= r.min_x || r.max_y <= r.min_y {
        return Err(format!(
            "extent {s:?} must be MINX,MINY,MAXX,MAXY with MAX > MIN"
        ));
    }
    Ok(r)
}

/// Runs `build`: loads and checks every input before creating the store directory, and
/// records the build's recipe in the store (for `cliffmap verify --repair`).
pub fn run(a: Args) -> anyhow::Result<()> {
    let recipe = recipe_of(&a);
    let manifest = build_from_recipe(
        &recipe,
        &a.out,
        super::progress::progress_sink(a.quiet),
        a.force,
    )?;
    if !a.quiet {
        println!(
            "built {} cells in {} levels into {}",
            manifest.cells.len(),
            manifest.quadtree.levels,
            a.out.display()
        );
        print_summary(&a.out, &manifest, 1.1)?;
    }
    Ok(())
}

/// A `--nodata` value: a number (or nan), or `none` (no value, no sentinels).
#[derive(Clone, Copy, Debug, PartialEq)]
enum NodataArg {
    Value(f64),
    None,
}

fn parse_nodata(s: &str) -> Result<NodataArg, String> {
    if s.eq_ignore_ascii_case("none") {
        return Ok(NodataArg::None);
    }
    s.trim()
        .parse::<f64>()
        .map(NodataArg::Value)
        .map_err(|_| format!("{s:?} is not a number, nan or none"))
}

/// The build recipe the flags describe (paths as given).
pub(super) fn recipe_of(a: &Args) -> BuildRecipe {
    BuildRecipe {
        recipe_version: RECIPE_VERSION,
        dem: a.dem.clone(),
        dem_load: DemLoadOptions {
            format: a.dem_format.map(Into::into),
            width: a.width,
            height: a.height,
            z_scale: a.z_scale,
            z_offset: a.z_offset,
            spacing: a.spacing,
            origin: a.origin,
            nodata: match a.nodata {
                Some(NodataArg::Value(v)) => Some(v),
                _ => None,
            },
            nodata_sentinels: a.nodata != Some(NodataArg::None),
            max_memory: a.max_memory,
        },
        ortho: a.ortho.clone(),
        ortho_same_grid: a.ortho_same_grid,
        ortho_extent: a.ortho_extent,
        ortho_nodata_colour: a.ortho_nodata_colour,
        max_error: a.max_error,
        cell_intervals: a.cell_intervals,
        cell_texels: a.cell_texels,
        png_compression: a.png_compression.into(),
    }
}
