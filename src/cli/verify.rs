//! `cliffmap verify STORE [--repair]`: integrity check and repair of a store.
//!
//! The check is [`cliffmap::verify::verify_store`], the repair
//! [`cliffmap::verify::repair_store`] from the store's build recipe (`STORE/recipe.json`;
//! a command line recorded by an older cliffmap is parsed into a recipe here).

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Parser;
use cliffmap::pipeline::{BuildRecipe, RECIPE_FILE, RecordedRecipe, read_recipe};
use cliffmap::verify::{VerifyReport, repair_store, verify_store};

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

/// Repairs `dir` from its recorded recipe (a command line recorded by an older cliffmap is
/// parsed into one) and prints what was done.
fn repair(dir: &Path, report: &VerifyReport) -> anyhow::Result<()> {
    let recipe = match read_recipe(dir)? {
        RecordedRecipe::Current(r) => *r,
        RecordedRecipe::CommandLine { cwd, argv } => recipe_of_command_line(dir, &cwd, &argv)?,
    };
    for note in repair_store(dir, report, &recipe)? {
        println!("{note}");
    }
    Ok(())
}

/// The recipe of a `cliffmap build` command line recorded (with its working directory) by
/// a cliffmap before the recipe was data.
fn recipe_of_command_line(dir: &Path, cwd: &Path, argv: &[String]) -> anyhow::Result<BuildRecipe> {
    let path = dir.join(RECIPE_FILE);
    let cli = super::Cli::try_parse_from(argv).with_context(|| {
        format!(
            "{}: the recorded command line does not parse",
            path.display()
        )
    })?;
    let super::Command::Build(b) = cli.command else {
        bail!(
            "{}: the recorded command is not `cliffmap build`",
            path.display()
        );
    };
    Ok(super::build::recipe_of(&b).resolved_against(cwd))
}
