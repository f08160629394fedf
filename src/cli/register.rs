//! `cliffmap register`: rough photo cameras refined against the store's terrain (no GCPs).

use std::path::PathBuf;

use cliffmap::pipeline::register_photos;
use cliffmap::register::{TerrainOptions, parse_free};

/// Flags of `cliffmap register`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The cell store.
    store: PathBuf,
    /// Photo list with rough cameras (`photos.json` format, as for `project`).
    #[arg(long)]
    photos: PathBuf,
    /// Output photo list (same format); camera files and a report are written beside it.
    #[arg(long)]
    out: PathBuf,
    /// Parameters to refine: yaw, pitch, roll, f (or fx, fy). The position stays as given
    /// (refining it against the terrain is not reliable yet: docs/registration.md,
    /// "Position").
    #[arg(long, default_value = "yaw,pitch,roll,f")]
    free: String,
    /// Half-widths of the coarse search over yaw, pitch and roll, degrees "Y,P,R".
    #[arg(long, default_value = "4,2.5,2")]
    search_deg: String,
    /// Restarts must agree within this many pixels for a photo to count as registered.
    #[arg(long, default_value_t = 1.0)]
    repeat_px: f64,
    /// Only warnings and errors.
    #[arg(long)]
    quiet: bool,
}

/// Runs `cliffmap register`.
pub fn run(a: Args) -> anyhow::Result<()> {
    let v =
        super::parse_list(&a.search_deg, 3).map_err(|e| anyhow::anyhow!("--search-deg: {e}"))?;
    if v.iter().any(|&x| !(0.0..=30.0).contains(&x)) {
        anyhow::bail!(
            "--search-deg: each half-width must be in 0..=30 degrees, got {}",
            a.search_deg
        );
    }
    if !(a.repeat_px.is_finite() && a.repeat_px > 0.0) {
        anyhow::bail!("--repeat-px must be positive, got {}", a.repeat_px);
    }
    let opts = TerrainOptions {
        free: parse_free(&a.free)?,
        search_deg: [v[0], v[1], v[2]],
        repeat_px: a.repeat_px,
        ..TerrainOptions::default()
    };
    opts.validate()?;
    let specs = cliffmap::photo::read_photo_specs(&a.photos)?;
    let mut warn = |s: &str| eprintln!("warning: {s}");
    let results = register_photos(&a.store, &specs, &a.out, &opts, &mut warn)?;
    if !a.quiet {
        println!(
            "{:<28} {:>10} {:>9} {:>9} {:>8} {:>7}",
            "photo", "verdict", "score", "repeat", "evals", "s"
        );
        for r in &results {
            println!(
                "{:<28} {:>10} {:>4.3}>{:.3} {:>7.2}px {:>8} {:>7.1}",
                r.name,
                if r.fit.converged {
                    "registered"
                } else {
                    "kept"
                },
                r.fit.score_start,
                r.fit.score_final,
                r.fit.repeat_px,
                r.fit.evaluations,
                r.fit.seconds
            );
        }
        println!("wrote {}", a.out.display());
    }
    Ok(())
}
