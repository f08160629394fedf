//! `cliffmap verify STORE [--repair]`: integrity check and repair of a store.
//!
//! The check is [`cliffmap::verify::verify_store`]. The repair redoes exactly the damaged
//! cells, layer by layer: the base cells by re-running the recorded `cliffmap build`
//! command (`STORE/recipe.json`), which resumes and rebuilds only cells whose files are not
//! intact (inputs changed since the build are refused by its build key); reparameterized
//! variants with the store's recorded reparam options; photo textures cannot be redone
//! one cell at a time (the blend and colour leveling span cells), so their records and
//! files are removed and the command says to run `cliffmap project` again.

use std::path::{Path, PathBuf};

use super::recipe::Recipe;
use anyhow::{Context, bail};
use clap::Parser;
use cliffmap::pipeline::{recorded_reparam_options, redo_reparam_cells, write_stats};
use cliffmap::store::{Manifest, Store, cell_stem};
use cliffmap::verify::{VerifyReport, merge_rebuilt, repair_plan, verify_store};

/// Flags of `cliffmap verify`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store directory.
    pub store: PathBuf,
    /// Rebuild the damaged cells from the recorded inputs (see docs/reliability.md).
    #[arg(long)]
    pub repair: bool,
    /// Print the report as JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// Runs `verify`.
pub fn run(a: Args) -> anyhow::Result<()> {
    if !a.store.is_dir() {
        bail!(
            "{}: not a directory (expected a cliffmap store)",
            a.store.display()
        );
    }
    // A repair holds the writer lock from the first check on.
    let _lock = if a.repair {
        Some(cliffmap::store::StoreLock::acquire(
            &a.store,
            "cliffmap verify --repair",
        )?)
    } else {
        None
    };
    let report = verify_store(&a.store);
    print_report(&a, &report)?;
    if report.is_intact() {
        return Ok(());
    }
    if !a.repair {
        bail!(
            "{}: {} problem(s) found; `cliffmap verify --repair {}` rebuilds the damaged cells",
            a.store.display(),
            report.findings.len(),
            a.store.display()
        );
    }
    repair(&a.store, &report)?;
    let after = verify_store(&a.store);
    if !after.is_intact() {
        print_report(&a, &after)?;
        bail!(
            "{}: {} problem(s) remain after the repair",
            a.store.display(),
            after.findings.len()
        );
    }
    println!(
        "repaired: {} cells, {} files verified intact",
        after.cells, after.files_checked
    );
    Ok(())
}

fn print_report(a: &Args, r: &VerifyReport) -> anyhow::Result<()> {
    if a.json {
        println!("{}", serde_json::to_string_pretty(r)?);
        return Ok(());
    }
    for f in &r.findings {
        let cell = f
            .cell
            .as_deref()
            .map(|c| format!("cell {c}: "))
            .unwrap_or_default();
        println!("{cell}{}: {} ({:?} layer)", f.file, f.problem, f.layer);
    }
    println!(
        "{}: {} cells, {} files checked, {} problem(s)",
        a.store.display(),
        r.cells,
        r.files_checked,
        r.findings.len()
    );
    Ok(())
}

fn repair(dir: &Path, report: &VerifyReport) -> anyhow::Result<()> {
    let plan = repair_plan(report);
    if plan.manifest || !plan.base.is_empty() {
        let old = Manifest::read(dir).ok();
        if plan.manifest {
            // Keep the damaged manifest for the user; the build writes a new one.
            let _ = std::fs::rename(dir.join("manifest.json"), dir.join("manifest.json.damaged"));
        }
        rebuild_base(dir)?;
        let rebuilt = Manifest::read(dir)?;
        match old {
            Some(old) => {
                let (mut merged, dropped) = merge_rebuilt(&old, &rebuilt);
                merged.write(dir)?;
                if !dropped.is_empty() {
                    println!(
                        "cells {} were rebuilt with different files (another cliffmap version?): their reparameterized and photo variants were dropped; run `cliffmap reparam` and `cliffmap project` again",
                        dropped.join(", ")
                    );
                }
            }
            None => println!(
                "the manifest was damaged: the base cells were rebuilt (damaged manifest kept as manifest.json.damaged); the reparameterized and photo records were in it, so run `cliffmap reparam` and `cliffmap project` again"
            ),
        }
        println!(
            "rebuilt base cells: {}",
            if plan.manifest {
                "all damaged ones".into()
            } else {
                plan.base.join(", ")
            }
        );
    }
    let mut store = Store::open(dir)?;
    if !plan.reparam.is_empty() && !plan.manifest {
        let settings = store
            .manifest
            .reparam
            .clone()
            .context("damaged reparameterized cells but the manifest records no reparam run")?;
        let Some(opts) = recorded_reparam_options(&settings) else {
            bail!(
                "cells {} have damaged reparameterized files, but this store was reparameterized before its options were recorded: run `cliffmap reparam` again",
                plan.reparam.join(", ")
            );
        };
        redo_reparam_cells(&mut store, &plan.reparam, &opts)?;
        println!("redid reparameterized cells: {}", plan.reparam.join(", "));
    }
    if !plan.photo.is_empty() && !plan.manifest {
        for c in store
            .manifest
            .cells
            .iter_mut()
            .filter(|c| plan.photo.contains(&c.id))
        {
            c.photo = None;
            for ext in ["photo.png", "photo.conf.png"] {
                let _ = std::fs::remove_file(
                    dir.join(format!("{}.{ext}", cell_stem(c.level, c.x, c.y))),
                );
            }
        }
        println!(
            "removed the damaged photo textures of cells {} (they fall back to their reparameterized or ortho texture); run `cliffmap project` again to restore them",
            plan.photo.join(", ")
        );
    }
    let threshold = store.manifest.reparam.as_ref().map_or(1.1, |r| r.threshold);
    write_stats(dir, &store.manifest, threshold)?;
    store.manifest.write(dir)?;
    Ok(())
}

/// Re-runs the recorded `cliffmap build` into `dir` (resuming: only damaged cells are rebuilt).
// a false positive: the closure `abs` is called once and also passed to `map`
#[allow(clippy::redundant_closure_call)]
fn rebuild_base(dir: &Path) -> anyhow::Result<()> {
    let path = dir.join("recipe.json");
    let bytes = std::fs::read(&path).with_context(|| {
        format!("{}: no build recipe (the store was not made by `cliffmap build` of this version); rebuild it with the original `cliffmap build` command", path.display())
    })?;
    let recipe: Recipe = serde_json::from_slice(&bytes)
        .with_context(|| format!("{}: invalid build recipe", path.display()))?;
    let cli = super::Cli::try_parse_from(&recipe.argv).with_context(|| {
        format!(
            "{}: the recorded command line does not parse",
            path.display()
        )
    })?;
    let super::Command::Build(mut b) = cli.command else {
        bail!(
            "{}: the recorded command is not `cliffmap build`",
            path.display()
        );
    };
    let abs = |p: &Path| {
        if p.is_absolute() {
            p.to_path_buf()
        } else {
            recipe.cwd.join(p)
        }
    };
    b.dem = abs(&b.dem);
    b.ortho = b.ortho.as_deref().map(abs);
    let missing: Vec<String> = std::iter::once(&b.dem)
        .chain(b.ortho.iter())
        .filter(|p| !p.is_file())
        .map(|p| p.display().to_string())
        .collect();
    if !missing.is_empty() {
        bail!(
            "cannot repair {}: the recorded build inputs are missing: {}",
            dir.display(),
            missing.join(", ")
        );
    }
    b.out = dir.to_path_buf();
    b.quiet = true;
    b.force = false;
    super::build::execute(b, false).with_context(|| {
        format!("rebuilding the damaged cells of {} from the recorded inputs failed (if the inputs changed since the build, the store cannot be repaired from them)", dir.display())
    })
}
