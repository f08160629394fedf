//! `cliffmap export-tiles`: the store as a 3D Tiles 1.1 tileset (one GLB per cell).

use std::path::PathBuf;

use cliffmap::export::{TextureSource, TilesOptions, export_tiles};

/// Flags of `cliffmap export-tiles`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store directory.
    store: PathBuf,
    /// Output folder (tileset.json and tiles/).
    #[arg(long)]
    out: PathBuf,
    /// The store's CRS, "EPSG:CODE" or a PROJ string, when its manifest records none.
    #[arg(long)]
    crs: Option<String>,
    /// Geoid height in metres added to the store's heights (orthometric → ellipsoidal).
    #[arg(long, allow_hyphen_values = true, conflicts_with = "geoid")]
    geoid_offset: Option<f64>,
    /// Geoid height grid (single-band GeoTIFF in EPSG:4326 longitude/latitude, e.g. PROJ's
    /// us_nga_egm96_15.tif) whose bilinear value at each vertex is added instead.
    #[arg(long)]
    geoid: Option<PathBuf>,
    /// Texture modes to export, comma-separated from photo (the best texture each cell has,
    /// always written as tileset.json), reparam and ortho, or "all"; each other mode gets
    /// tileset_MODE.json + tiles_MODE/, and the page offers a toggle (`?mode=MODE`).
    #[arg(long, default_value = "photo", value_parser = parse_modes)]
    modes: Modes,
    /// Embed colour textures as JPEG of this quality (1..=100) instead of the store's PNGs
    /// (Engabreen with IMG_8902 projected: 114 MB of tiles as PNG, 22 MB at quality 85;
    /// docs/export.md).
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=100))]
    jpeg_quality: Option<u8>,
    /// External child tilesets every N levels (subtrees/LEVEL/X-Y.json), 0 for one
    /// tileset.json; default: every 4 levels when the store has more than 2000 cells.
    #[arg(long)]
    subtree_levels: Option<u8>,
    /// Camera JSON(s) to write as views for the page (`index.html?camera=views/NAME.json`,
    /// NAME the file's stem); repeatable.
    #[arg(long)]
    view: Vec<PathBuf>,
    /// Lit materials: the normal maps in tangent space with NORMAL and TANGENT attributes,
    /// instead of unlit ones (KHR_materials_unlit) showing the texture as it is.
    #[arg(long)]
    lit: bool,
    /// Per-texel stretch and photo share as EXT_structural_metadata property textures.
    #[arg(long)]
    metadata: bool,
    /// Only warnings and errors.
    #[arg(long)]
    quiet: bool,
}

/// Runs `export-tiles`.
pub fn run(a: Args) -> anyhow::Result<()> {
    if let Some(m) = a.geoid_offset
        && !(m.is_finite() && m.abs() < 200.0)
    {
        anyhow::bail!("--geoid-offset must be a height in metres within ±200, got {m}");
    }
    let mut views = Vec::new();
    for v in &a.view {
        let cam = cliffmap::camera::camera_from_json_file(v, (0, 0))?;
        cliffmap::camera::validate_camera(&cam, v)?;
        let name = v
            .file_stem()
            .map_or_else(|| "view".to_string(), |s| s.to_string_lossy().into_owned());
        views.push((name, cam));
    }
    let r = export_tiles(
        &a.store,
        &a.out,
        &TilesOptions {
            crs: a.crs,
            geoid_offset: a.geoid_offset,
            geoid_grid: a.geoid,
            extra_modes: a.modes.0,
            jpeg_quality: a.jpeg_quality,
            lit: a.lit,
            metadata: a.metadata,
            subtree_levels: a.subtree_levels,
            progress: super::progress::progress_sink(a.quiet),
            views,
        },
    )?;
    if !a.quiet {
        println!(
            "wrote {} ({} tiles, {} external child tilesets, {} left out where children do not cover their parent; textures: {} photo, {} reparam, {} ortho; {:.1} MB)",
            a.out.join("tileset.json").display(),
            r.tiles,
            r.subtrees,
            r.pruned,
            r.textures[0],
            r.textures[1],
            r.textures[2],
            r.bytes as f64 / 1e6
        );
        println!("heights: {}", r.heights);
        if r.resumed > 0 {
            println!(
                "resumed: {} GLBs kept from an earlier run of this export",
                r.resumed
            );
        }
    }
    Ok(())
}

/// The texture modes of `--modes` (besides the best texture).
#[derive(Clone, Debug)]
struct Modes(Vec<TextureSource>);

fn parse_modes(s: &str) -> Result<Modes, String> {
    let mut out = Vec::new();
    for m in s.split(',').map(str::trim) {
        let list: &[TextureSource] = match m {
            "photo" | "best" => &[],
            "reparam" => &[TextureSource::Reparam],
            "ortho" => &[TextureSource::Ortho],
            "all" => &[TextureSource::Reparam, TextureSource::Ortho],
            _ => {
                return Err(format!(
                    "unknown texture mode {m:?}: expected photo, reparam, ortho or all"
                ));
            }
        };
        for t in list {
            if !out.contains(t) {
                out.push(*t);
            }
        }
    }
    Ok(Modes(out))
}
