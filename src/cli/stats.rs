//! `cliffmap stats`: texel-stretch summary, stats.json and histogram of a store.

use std::path::{Path, PathBuf};

use cliffmap::pipeline::write_stats;
use cliffmap::store::{Manifest, Store};

/// Flags of `cliffmap stats`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store directory.
    store: PathBuf,
    /// Rel_texel above which a cell counts as stretched.
    #[arg(long, default_value_t = 1.1)]
    threshold: f64,
    /// Print the JSON document on stdout instead of the summary.
    #[arg(long)]
    json: bool,
}

/// Runs `stats`.
pub fn run(a: Args) -> anyhow::Result<()> {
    if !(a.threshold.is_finite() && a.threshold > 0.0) {
        anyhow::bail!("--threshold must be a positive number, got {}", a.threshold);
    }
    let store = Store::open(&a.store)?;
    if a.json {
        let json = write_stats(&a.store, &store.manifest, a.threshold)?;
        println!("{}", serde_json::to_string_pretty(&json)?);
    } else {
        print_summary(&a.store, &store.manifest, a.threshold)?;
    }
    Ok(())
}

/// Writes stats.json and the histogram, and prints a human summary.
pub fn print_summary(dir: &Path, manifest: &Manifest, threshold: f64) -> anyhow::Result<()> {
    let json = write_stats(dir, manifest, threshold)?;
    let s = &json["summary"];
    println!("{}", serde_json::to_string_pretty(s)?);
    println!("wrote {} and {}", dir.join("stats.json").display(), dir.join("stats_histogram.png").display());
    Ok(())
}
