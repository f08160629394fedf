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
    #[arg(long, default_value_t = 1.1, allow_hyphen_values = true)]
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
    let f = |v: &serde_json::Value| v.as_f64().unwrap_or(f64::NAN);
    let r = &s["rel_texel"];
    println!(
        "{} cells, {} ({:.1}%) above Rel_texel {threshold}; Rel_texel p50 {:.3}, p90 {:.3}, p99 {:.3}, max {:.3}",
        s["cells"],
        s["cells_above"],
        f(&s["percent_above"]),
        f(&r["p50"]),
        f(&r["p90"]),
        f(&r["p99"]),
        f(&r["max"])
    );
    println!(
        "{:>5} {:>6} {:>7} {:>9} {:>9}",
        "level", "cells", "above", "p50", "max"
    );
    for l in s["levels"].as_array().into_iter().flatten() {
        println!(
            "{:>5} {:>6} {:>7} {:>9.3} {:>9.3}",
            l["level"].as_u64().unwrap_or(0),
            l["cells"].as_u64().unwrap_or(0),
            l["cells_above"].as_u64().unwrap_or(0),
            f(&l["rel_texel"]["p50"]),
            f(&l["rel_texel"]["max"])
        );
    }
    let p = &s["parameterization"];
    if p["cells_reparam"].as_u64().unwrap_or(0) > 0 {
        let m = &p["texture_memory"];
        let mib = |v: &serde_json::Value| v.as_f64().unwrap_or(0.0) / (1u64 << 20) as f64;
        println!(
            "reparameterized {} cells: Rel_texel max {:.3} -> {:.3}, texel stretch max {:.2} -> {:.2}; texture memory ortho {:.1} MiB, reparam {:.1} MiB, mixed {:.1} MiB, as stored with photo textures {:.1} MiB",
            p["cells_reparam"],
            f(&p["rel_texel_before"]["max"]),
            f(&p["rel_texel_after"]["max"]),
            f(&p["texel_stretch_max_before"]),
            f(&p["texel_stretch_max_after"]),
            mib(&m["ortho_bytes"]),
            mib(&m["reparam_bytes"]),
            mib(&m["mixed_bytes"]),
            mib(&m["photo_bytes"])
        );
        let d = &p["distortion"];
        println!(
            "chart distortion (excess over an isometry, median / max over cells): symmetric Dirichlet - 4 {:.4} / {:.4}, mean |ln(s1 s2)| {:.4} / {:.4}, mean s1/s2 - 1 {:.4} / {:.4}; flipped triangles max {}, boundary crossings max {}",
            f(&d["symmetric_dirichlet_excess"]["p50"]),
            f(&d["symmetric_dirichlet_excess"]["max"]),
            f(&d["area_distortion"]["p50"]),
            f(&d["area_distortion"]["max"]),
            f(&d["angle_distortion_excess"]["p50"]),
            f(&d["angle_distortion_excess"]["max"]),
            d["flipped_max"],
            d["boundary_crossings_max"]
        );
    }
    if let Some(photos) = s["photos"].as_array().filter(|p| !p.is_empty()) {
        println!(
            "photos: {} projected; steep texels (> 60°) now mainly from photos: {:.1}% on the finest level, {:.1}% over all levels",
            photos.len(),
            100.0 * f(&s["photo_improved_steep_fraction"]),
            100.0 * f(&s["photo_improved_steep_fraction_all_levels"])
        );
    }
    println!(
        "wrote {} and {}",
        dir.join("stats.json").display(),
        dir.join("stats_histogram.png").display()
    );
    Ok(())
}
