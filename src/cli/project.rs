//! `cliffmap project`: merge ground photos into a store's cell textures.

use std::path::PathBuf;

use cliffmap::colour::ColourSpace;
use cliffmap::photo::{BlendMode, FootprintOptions, PhotoInput};
use cliffmap::pipeline::{PhotoTextureOptions, ProjectOptions, project_store};
use cliffmap::raycast::{BvhQuality, RayAccel};

use super::stats::print_summary;

/// Flags of `cliffmap project`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store directory (made by `cliffmap build`, optionally `cliffmap reparam`).
    pub store: PathBuf,
    /// Photo list: {"photos": [{"image": "A.jpg", "camera": "A.json"} | {"image": ..., "imgraft": ...}]}.
    #[arg(long, required_unless_present = "colmap", conflicts_with = "colmap")]
    pub photos: Option<PathBuf>,
    /// COLMAP text model directory (cameras.txt, images.txt) instead of --photos.
    #[arg(long)]
    pub colmap: Option<PathBuf>,
    /// Per texel: blend photos weighted by coverage and sharpness (the sharpest dominates),
    /// or take the single best photo.
    #[arg(long, default_value = "confidence", value_parser = ["confidence", "best"])]
    pub blend: String,
    /// Largest photo texture side in texels (a power of two, 64..=8192): cells the photos
    /// resolve finely get photo textures up to this size.
    #[arg(long, default_value_t = 2048)]
    pub max_photo_texels: u32,
    /// GPU memory (RGBA8 with mips) all enlarged photo textures may take, e.g. 512M or 2G;
    /// cells whose photos cover least give way first.
    #[arg(long, value_parser = super::parse_bytes, default_value = "1G")]
    pub photo_texture_budget: u64,
    /// Texels per photo pixel side the photo-driven sizes aim at (0.25..=4).
    #[arg(long, default_value_t = 1.0)]
    pub texels_per_pixel: f64,
    /// Most texels an enlarged photo texture may hold per photo pixel its cell receives, e.g.
    /// 4: cells the photos cover only in part get smaller textures (faster, less memory,
    /// less detail; docs/projection.md "Texture sizes"). Default: no bound.
    #[arg(long, default_value_t = f64::INFINITY)]
    pub max_texels_per_photo_pixel: f64,
    /// The largest screen-space error (pixels) views will draw the coarser levels at: their
    /// photo textures get no detail finer than such views show (a texel of the cell's error
    /// over PX metres). cliffmap's renderer and exported page draw at 0.5; `inf` sizes
    /// coarser levels like the finest (e.g. for CesiumJS at its default 16 px).
    #[arg(long, default_value_t = 2.0, value_name = "PX")]
    pub coarse_sse: f64,
    /// Keep every photo texture at its active texture's size (no photo-driven sizes).
    #[arg(long)]
    pub fixed_photo_texels: bool,
    /// Project onto the TIN, not onto the DEM surface the store's relief maps describe (the
    /// surface the renderer's relief mapping looks textures up on; docs/projection.md).
    #[arg(long)]
    pub no_relief: bool,
    /// Also project photos a registered list marks `"registered": false` (their cameras
    /// could not be confirmed by `cliffmap register`); by default they are left out with a
    /// warning, since a wrong pose makes the terrain worse than no photo.
    #[arg(long)]
    pub include_unregistered: bool,
    /// Occlusion margin: photo pixels closer than PX (pose uncertainty, full-resolution
    /// pixels) plus the TIN error's displacement to an occlusion edge of the photo (a
    /// silhouette, the skyline, a depth jump) count less when photos compete for a texel (a
    /// lone photo needs no map); 0 switches it off.
    #[arg(long, default_value_t = 2.0, value_name = "PX")]
    pub occlusion_margin: f64,
    /// Border feather: a photo's pixels within F × its shorter side of the image's edge
    /// fade out, in [0, 0.5]. Default 0: a photo's colour reaches the edge of its frame, as
    /// ideal projective texturing's does (0.01, the default before 2026-12-06, cost up to 9 % of
    /// the photos' gain; docs/projection.md, "Confidence and resolution").
    #[arg(long, default_value_t = 0.0, value_name = "F")]
    pub feather: f64,
    /// Colour space photo colours are averaged and blended in.
    #[arg(long, default_value = "linear", value_parser = ["linear", "srgb"])]
    pub colour_space: String,
    /// Do not reconstruct missing footprint corners (pixels at cell borders are dropped).
    #[arg(long)]
    pub no_reconstruct: bool,
    /// Do not level photo colours (gain/offset per channel) to the existing textures.
    #[arg(long)]
    pub no_level_colours: bool,
    /// Ray-casting acceleration: `grid` (camera-space bins, default), `grid:BIN_PX` (bin side
    /// in pixels, default 8), `bvh` or `bvh:PRESET` (an obvhs BVH; presets fastest, fast,
    /// medium, slow, very-slow). Both give the same nearest hits; see docs/projection.md.
    #[arg(long, default_value = "grid", value_parser = parse_ray_accel, conflicts_with = "bvh")]
    pub ray_accel: RayAccel,
    /// Shorthand for `--ray-accel bvh:PRESET`.
    #[arg(long, value_parser = ["fastest", "fast", "medium", "slow", "very-slow"])]
    pub bvh: Option<String>,
    /// PNG compression of the textures written: fast (fdeflate, the default), balanced or
    /// best. Same pixels; balanced files are ~0.77× the size of fast ones at ~1/18 the
    /// encoding speed (docs/performance.md, "PNG encoding").
    #[arg(long, value_enum, default_value = "fast")]
    pub png_compression: super::values::PngCompressionArg,
    /// No progress bars or summary.
    #[arg(long)]
    pub quiet: bool,
    /// Use the whole frame: do not leave out uniform borders (a scan's white frame, the
    /// black padding of a stabilised video frame, a banner of one colour with text).
    #[arg(long)]
    pub no_border_mask: bool,
    /// Leave out what is nearer to the camera than M metres (people, rocks, roofs in the
    /// foreground); a per-photo "mask" in the photo list leaves out chosen pixels.
    #[arg(long, default_value_t = 0.0, value_name = "M")]
    pub min_distance: f64,
    /// Print the run's report as JSON on stdout (per photo: terrain pixels, the pixels and
    /// texels it supplied, warnings; per level: cells and texture memory) instead of the
    /// summary.
    #[arg(long)]
    pub json: bool,
}

/// The library options these flags describe.
pub fn options(a: &Args) -> ProjectOptions {
    ProjectOptions {
        blend: if a.blend == "best" {
            BlendMode::Best
        } else {
            BlendMode::Confidence
        },
        footprint: FootprintOptions {
            reconstruct: !a.no_reconstruct,
            ..FootprintOptions::default()
        },
        level_colours: !a.no_level_colours,
        ray: match &a.bvh {
            Some(p) => RayAccel::Bvh(BvhQuality::parse(p).unwrap_or_default()),
            None => a.ray_accel,
        },
        colour_space: if a.colour_space == "srgb" {
            ColourSpace::Srgb
        } else {
            ColourSpace::Linear
        },
        texture: PhotoTextureOptions {
            photo_driven: !a.fixed_photo_texels,
            max_texels: a.max_photo_texels,
            budget_bytes: a.photo_texture_budget,
            texels_per_pixel: a.texels_per_pixel,
            texels_per_delivered: a.max_texels_per_photo_pixel,
            coarse_sse_px: a.coarse_sse,
        },
        onto_relief: !a.no_relief,
        confidence: cliffmap::photo::ConfidenceParams {
            occlusion_margin_px: a.occlusion_margin,
            feather: a.feather,
            ..Default::default()
        },
        png_compression: a.png_compression.into(),
        progress: super::progress::progress_sink(a.quiet || a.json),
        mask_borders: !a.no_border_mask,
        min_distance_m: a.min_distance,
        ..ProjectOptions::default()
    }
}

fn parse_ray_accel(s: &str) -> Result<RayAccel, String> {
    RayAccel::parse(s)
        .ok_or_else(|| format!("'{s}' is not grid, grid:BIN_PX (pixels > 0), bvh or bvh:PRESET"))
}

/// Reads the photos and their cameras from `--photos` or `--colmap`.
fn load_photos(a: &Args) -> anyhow::Result<Vec<PhotoInput>> {
    match (&a.photos, &a.colmap) {
        (Some(p), _) => {
            let specs = cliffmap::photo::read_photo_specs(p)?;
            let (keep, left): (Vec<_>, Vec<_>) = specs
                .into_iter()
                .partition(|s| a.include_unregistered || s.unregistered.is_none());
            for s in &left {
                eprintln!(
                    "warning: {}: left out ({}); --include-unregistered projects it anyway",
                    s.name,
                    s.unregistered.as_deref().unwrap_or_default()
                );
            }
            if keep.is_empty() && !left.is_empty() {
                anyhow::bail!(
                    "{}: every photo is marked \"registered\": false, nothing to project \
                     (--include-unregistered projects them with their given cameras)",
                    p.display()
                );
            }
            Ok(keep
                .iter()
                .map(cliffmap::photo::PhotoSpec::load)
                .collect::<Result<_, _>>()?)
        }
        (None, Some(d)) => Ok(cliffmap::photo::read_colmap(d)?),
        (None, None) => anyhow::bail!("give --photos PHOTOS.json or --colmap DIR"),
    }
}

/// Runs `project`.
pub fn run(a: Args) -> anyhow::Result<()> {
    // a bad store is reported before any photo is decoded
    cliffmap::store::Store::open(&a.store)?;
    let t = std::time::Instant::now();
    let photos = load_photos(&a)?;
    tracing::debug!(
        "project: {} photos decoded in {:.3} s",
        photos.len(),
        t.elapsed().as_secs_f64()
    );
    let report = project_store(&a.store, &photos, &options(&a))?;
    if a.json {
        let out = serde_json::json!({
            "cells_written": report.cells_written,
            "photos": report.settings.photos,
            "levels": report.settings.levels,
            "level_colours": report.settings.level_colours,
        });
        println!("{}", serde_json::to_string_pretty(&out)?);
    } else if !a.quiet {
        println!("photo textures for {} cells", report.cells_written);
        for p in &report.settings.photos {
            println!(
                "{}: {} pixels hit the terrain, {} ({:.1} %) supplied a texture; {} texels written, {} supplied, {} silhouette pixels rejected, {} footprints reconstructed, gain {:.3?}, offset {:.3?} ({} samples)",
                p.name,
                p.pixels_hit,
                p.pixels_supplying,
                100.0 * p.supplying_share(),
                p.texels_written,
                p.texels_supplied,
                p.rejected_silhouette,
                p.reconstructed_footprints,
                p.colour_gain,
                p.colour_offset,
                p.colour_samples
            );
            if !p.border_masked.is_empty() {
                println!("  uniform border left out: {}", p.border_masked.join("; "));
            }
            if p.pixels_masked + p.pixels_near > 0 {
                println!(
                    "  of its terrain pixels: {} masked, {} nearer than --min-distance",
                    p.pixels_masked, p.pixels_near
                );
            }
        }
        for l in &report.settings.levels {
            if l.cells_with_photo > 0 {
                println!(
                    "level {}: {} cells with photo colour, {} enlarged ({} wanted larger), photo textures {:.1} MB (budget {:.1} MB)",
                    l.level,
                    l.cells_with_photo,
                    l.upsized_cells,
                    l.wanted_larger,
                    l.photo_texture_bytes as f64 / 1e6,
                    l.texture_budget_bytes as f64 / 1e6
                );
            }
        }
        let store = cliffmap::store::Store::open(&a.store)?;
        let threshold = store.manifest.reparam.as_ref().map_or(1.1, |r| r.threshold);
        print_summary(&a.store, &store.manifest, threshold)?;
    }
    Ok(())
}
