//! The repair of a store ([`repair_store`]): the damaged cells of a [`VerifyReport`] are
//! redone layer by layer. The base cells by re-running the store's build recipe
//! ([`crate::pipeline::BuildRecipe`]), which resumes and rebuilds only cells whose files
//! are not intact (inputs changed since the build are refused by its build key);
//! reparameterized variants with the store's recorded reparam options; photo textures cannot
//! be redone one cell at a time (the blend and colour leveling span cells), so their records
//! and files are removed and the notes say to run `cliffmap project` again.
//!
//! In: the store directory, its report and recipe; out: the notes of what was done, in
//! order (the caller prints them). The caller holds the store's writer lock.

use std::path::Path;

use super::{VerifyReport, merge_rebuilt, repair_plan};
use crate::error::{Error, Result};
use crate::pipeline::{
    BuildRecipe, build_without_recording, recorded_reparam_options, redo_reparam_cells, write_stats,
};
use crate::progress::ProgressSink;
use crate::store::{Manifest, Store, cell_stem};

/// Repairs the store in `dir` found damaged in `report`, rebuilding base cells from
/// `recipe`; returns what was done, one note per line.
pub fn repair_store(
    dir: &Path,
    report: &VerifyReport,
    recipe: &BuildRecipe,
) -> Result<Vec<String>> {
    let plan = repair_plan(report);
    let mut notes = Vec::new();
    if plan.manifest || !plan.base.is_empty() {
        rebuild_base_layer(dir, recipe, plan.manifest, &mut notes)?;
        notes.push(format!(
            "rebuilt base cells: {}",
            if plan.manifest {
                "all damaged ones".into()
            } else {
                plan.base.join(", ")
            }
        ));
    }
    let mut store = Store::open(dir)?;
    if !plan.reparam.is_empty() && !plan.manifest {
        redo_reparam_layer(&mut store, &plan.reparam)?;
        notes.push(format!(
            "redid reparameterized cells: {}",
            plan.reparam.join(", ")
        ));
    }
    if !plan.photo.is_empty() && !plan.manifest {
        drop_photo_layer(&mut store, &plan.photo);
        notes.push(format!(
            "removed the damaged photo textures of cells {} (they fall back to their reparameterized or ortho texture); run `cliffmap project` again to restore them",
            plan.photo.join(", ")
        ));
    }
    let threshold = store.manifest.reparam.as_ref().map_or(1.1, |r| r.threshold);
    write_stats(dir, &store.manifest, threshold)?;
    store.manifest.write(dir)?;
    Ok(notes)
}

/// Rebuilds the damaged base cells (all of them when the manifest is damaged, which is
/// kept as `manifest.json.damaged`) and merges the rebuilt records into the old manifest.
fn rebuild_base_layer(
    dir: &Path,
    recipe: &BuildRecipe,
    manifest_damaged: bool,
    notes: &mut Vec<String>,
) -> Result<()> {
    let old = Manifest::read(dir).ok();
    if manifest_damaged {
        // Keep the damaged manifest for the user; the build writes a new one.
        let _ = std::fs::rename(dir.join("manifest.json"), dir.join("manifest.json.damaged"));
    }
    rebuild_from_recipe(dir, recipe)?;
    let rebuilt = Manifest::read(dir)?;
    match old {
        Some(old) => {
            let (mut merged, dropped) = merge_rebuilt(&old, &rebuilt);
            merged.write(dir)?;
            if !dropped.is_empty() {
                notes.push(format!(
                    "cells {} were rebuilt with different files (another cliffmap version?): their reparameterized and photo variants were dropped; run `cliffmap reparam` and `cliffmap project` again",
                    dropped.join(", ")
                ));
            }
        }
        None => notes.push(
            "the manifest was damaged: the base cells were rebuilt (damaged manifest kept as manifest.json.damaged); the reparameterized and photo records were in it, so run `cliffmap reparam` and `cliffmap project` again".into(),
        ),
    }
    Ok(())
}

/// Re-runs the recipe's build into `dir` (resuming: only damaged cells are rebuilt).
fn rebuild_from_recipe(dir: &Path, recipe: &BuildRecipe) -> Result<()> {
    let missing = recipe.missing_inputs();
    if !missing.is_empty() {
        return Err(Error::store(
            dir,
            format!(
                "cannot repair: the recorded build inputs are missing: {}",
                missing
                    .iter()
                    .map(|p| p.display().to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        ));
    }
    build_without_recording(recipe, dir, ProgressSink::none(), false).map_err(|e| {
        Error::store(
            dir,
            format!(
                "rebuilding the damaged cells from the recorded inputs failed (if the inputs changed since the build, the store cannot be repaired from them): {e}"
            ),
        )
    })?;
    Ok(())
}

/// Redoes the reparameterized variants of `ids` with the store's recorded options.
fn redo_reparam_layer(store: &mut Store, ids: &[String]) -> Result<()> {
    let Some(settings) = store.manifest.reparam.clone() else {
        return Err(Error::store(
            &store.dir,
            "damaged reparameterized cells but the manifest records no reparam run",
        ));
    };
    let Some(opts) = recorded_reparam_options(&settings) else {
        return Err(Error::store(
            &store.dir,
            format!(
                "cells {} have damaged reparameterized files, but this store was reparameterized before its options were recorded: run `cliffmap reparam` again",
                ids.join(", ")
            ),
        ));
    };
    redo_reparam_cells(store, ids, &opts)
}

/// Removes the photo records and files of `ids` (their textures fall back to the
/// reparameterized or ortho one).
fn drop_photo_layer(store: &mut Store, ids: &[String]) {
    let dir = store.dir.clone();
    for c in store
        .manifest
        .cells
        .iter_mut()
        .filter(|c| ids.contains(&c.id))
    {
        c.photo = None;
        for ext in ["photo.png", "photo.conf.png"] {
            let _ =
                std::fs::remove_file(dir.join(format!("{}.{ext}", cell_stem(c.level, c.x, c.y))));
        }
    }
}
