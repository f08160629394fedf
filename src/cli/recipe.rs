//! `STORE/recipe.json`: the command line a store was built with, which `verify --repair`
//! replays to rebuild damaged cells.

use std::path::{Path, PathBuf};

use anyhow::Context;

/// The recorded build command: working directory and argument vector.
#[derive(serde::Serialize, serde::Deserialize)]
pub(super) struct Recipe {
    pub(super) cwd: PathBuf,
    pub(super) argv: Vec<String>,
}

/// Records this process's command line as `STORE/recipe.json` (called by `build`).
pub(super) fn write_recipe(store: &Path) -> anyhow::Result<()> {
    let cwd = std::env::current_dir().context("cannot read the current directory")?;
    let recipe = Recipe {
        cwd,
        argv: std::env::args().collect(),
    };
    cliffmap::fsutil::write_atomic(
        &store.join("recipe.json"),
        &serde_json::to_vec_pretty(&recipe)?,
    )?;
    Ok(())
}
