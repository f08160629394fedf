//! `cliffmap register`: rough photo cameras refined against the store's terrain (no GCPs).

use std::path::PathBuf;

use cliffmap::pipeline::{TieSettings, register_photos_with, resolve_photo_entries};
use cliffmap::register::{LabelTexture, ResectOptions, TerrainOptions, TieOptions, parse_free};

/// Flags of `cliffmap register`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The cell store.
    store: PathBuf,
    /// Photo list with rough cameras (`photos.json` format, as for `project`), or entries
    /// with `"rough"` poses made from EXIF GPS, compass heading and focal length
    /// (docs/formats.md).
    #[arg(long)]
    photos: PathBuf,
    /// Output photo list (same format); camera files and a report are written beside it.
    #[arg(long)]
    out: PathBuf,
    /// Parameters the terrain search refines: yaw, pitch, roll, f (or fx, fy). It keeps the
    /// position (refining it against the terrain alone is not reliable yet:
    /// docs/registration.md, "Position"; but see --position-search-m); a resection against
    /// a placed photo fits the position too.
    #[arg(long, default_value = "yaw,pitch,roll,f")]
    free: String,
    /// Also search the camera position, by the terrain score, in steps of M, M/2 and M/4
    /// metres up, across the view and along it (0 < M <= 50; about 1.5 for a GPS position a
    /// few metres off); a search that does not settle on a peak keeps the given camera.
    /// Experimental and slow (3-6 minutes per photo): on the demo scene it registered 2 of 8
    /// starts 3-5 m off, each about half a metre from the truth; on Engabreen a
    /// 3-m-off position's GCP RMSE fell from 14-25 px to about 4 px (docs/registration.md,
    /// "Position by the score at full resolution").
    #[arg(long)]
    position_search_m: Option<f64>,
    /// Half-widths of the coarse search over yaw, pitch and roll, degrees "Y,P,R".
    #[arg(long, default_value = "4,2.5,2")]
    search_deg: String,
    /// Restarts must agree within this many pixels for a photo to count as registered.
    #[arg(long, default_value_t = 1.0)]
    repeat_px: f64,
    /// Photos (names as in the list, comma-separated) whose given cameras are trusted, e.g.
    /// fitted with GCPs: kept as they are, and anchors for the photo-to-photo ties.
    #[arg(long, value_delimiter = ',')]
    known: Vec<String>,
    /// A photo the terrain does not place is tied to a placed photo taken within this many
    /// metres of it (same place: rotation from patch matches between the two).
    #[arg(long, default_value_t = 2.0)]
    tie_distance_m: f64,
    /// Most RMSE (pixels) of a tie's inlier matches.
    #[arg(long, default_value_t = 1.0)]
    tie_rmse_px: f64,
    /// A photo not placed by a tie is resected (position included) against the nearest
    /// photo with a trusted position (known, or resected) given within this many metres
    /// of it: its pixels put on the terrain and found in the photo; 0 turns it off.
    #[arg(long, default_value_t = 1000.0)]
    resect_distance_m: f64,
    /// Most RMSE (pixels) of a resection's inlier matches.
    #[arg(long, default_value_t = 1.5)]
    resect_rmse_px: f64,
    /// Surfaces that moved between photos (a glacier), left out of the ties' matches: a
    /// grey PNG on the store's DEM grid, values >= 128 moving. Optional: a rotation
    /// consensus leaves out matches that disagree with the still ground, and refuses a tie
    /// when two motions have similar support (then a mask decides).
    #[arg(long)]
    moving_mask: Option<PathBuf>,
    /// What the terrain search matches the photo against: `active` (the ortho or
    /// reparameterized textures; never photo textures, so an earlier projection with a
    /// wrong camera cannot pull the fit) or `best`: the pixels of the list's trusted photos
    /// (--known, tied, resected) where they show the terrain, else photo textures where
    /// `cliffmap project` wrote them, else the active textures; then every photo the
    /// terrain placed is registered again against the other placed photos' pixels
    /// (docs/registration.md, "Registering against projected photos"). With `best`, a photo
    /// the store's textures were projected from is refused unless named with --known.
    #[arg(long, value_enum, default_value = "active")]
    textures: Textures,
    /// Only warnings and errors.
    #[arg(long)]
    quiet: bool,
}

/// `--textures`: what labels the terrain's samples.
#[derive(clap::ValueEnum, Clone, Copy, Debug)]
pub enum Textures {
    /// The ortho or reparameterized textures.
    Active,
    /// Photo textures where present, else the active ones.
    Best,
}

/// Runs `cliffmap register`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let v =
        super::parse_list(&a.search_deg, 3).map_err(|e| anyhow::anyhow!("--search-deg: {e}"))?;
    let opts = TerrainOptions {
        free: parse_free(&a.free)?,
        search_deg: [v[0], v[1], v[2]],
        repeat_px: a.repeat_px,
        position_search_m: a.position_search_m,
        labels: match a.textures {
            Textures::Active => LabelTexture::Active,
            Textures::Best => LabelTexture::Best,
        },
        ..TerrainOptions::default()
    };
    opts.validate()?;
    let moving_mask = match &a.moving_mask {
        Some(p) => {
            Some(image::DynamicImage::ImageRgb8(cliffmap::fsutil::decode_rgb8(p)?).to_luma8())
        }
        None => None,
    };
    let ties = TieSettings {
        known: a
            .known
            .iter()
            .map(|k| k.trim().to_string())
            .filter(|k| !k.is_empty())
            .collect(),
        options: TieOptions {
            max_distance_m: a.tie_distance_m,
            max_rmse_px: a.tie_rmse_px,
            ..TieOptions::default()
        },
        moving_mask,
        resect_distance_m: a.resect_distance_m,
        resection: ResectOptions {
            max_rmse_px: a.resect_rmse_px,
            ..ResectOptions::default()
        },
    };
    ties.validate()?;
    let entries = cliffmap::photo::read_photo_entries(&a.photos)?;
    let quiet = a.quiet;
    let specs = resolve_photo_entries(&a.store, entries, &mut |name, line| {
        if !quiet {
            eprintln!("{name}: rough {line}");
        }
    })?;
    let mut warn = |s: &str| eprintln!("warning: {s}");
    let results = register_photos_with(&a.store, &specs, &a.out, &opts, &ties, &mut warn)?;
    if !a.quiet {
        println!(
            "{:<28} {:>10} {:>9} {:>9} {:>8} {:>7}",
            "photo", "verdict", "score", "repeat", "evals", "s"
        );
        for r in &results {
            let verdict = match (r.fit.converged, r.method) {
                (true, "terrain" | "terrain_photos") => "registered",
                (true, m) => m,
                (false, _) => "kept",
            };
            let (score, repeat) = if r.fit.score_start.is_finite() {
                (
                    format!("{:.3}>{:.3}", r.fit.score_start, r.fit.score_final),
                    format!("{:.2}px", r.fit.repeat_px),
                )
            } else {
                match &r.tie {
                    Some((anchor, t)) if t.accepted => (
                        format!("tie {anchor}"),
                        format!("{:.2}px", t.rmse_inliers_px),
                    ),
                    _ => match &r.resection {
                        Some((anchor, f)) if f.accepted => (
                            format!("resect {anchor}"),
                            format!("{:.2}px", f.rmse_inliers_px),
                        ),
                        _ => ("-".into(), "-".into()),
                    },
                }
            };
            println!(
                "{:<28} {:>10} {:>9} {:>9} {:>8} {:>7.1}",
                r.name, verdict, score, repeat, r.fit.evaluations, r.fit.seconds
            );
        }
        for r in &results {
            if r.fit.converged && a.position_search_m.is_some() && r.method.starts_with("terrain") {
                let moved = r.fit.found.position - r.rough.position;
                println!(
                    "note: {}: position moved by ({:+.2}, {:+.2}, {:+.2}) m (x, y, z) by the \
                     experimental position search",
                    r.name, moved.x, moved.y, moved.z
                );
            }
            if let (true, Some(p)) = (r.fit.converged, r.fit.position_kept_parallax_px_per_m) {
                println!(
                    "note: {}: its given position was kept (only the view direction and focal \
                     length were fitted); each metre of error in it shifts the near terrain \
                     against the far by up to {p:.1} px",
                    r.name
                );
            }
        }
        println!("wrote {}", a.out.display());
    }
    Ok(())
}
