//! A store's build recipe (`STORE/recipe.json`): the inputs and options of `build` as
//! versioned data, written by [`build_from_recipe`] and read by the repair
//! (`crate::verify::repair_store`) to rebuild damaged cells from the same inputs.
//!
//! In: a [`BuildRecipe`] (DEM file and how to read it, optional ortho file and how to place
//! it, build options); out: the loaded inputs ([`BuildRecipe::load_inputs`]) or a built
//! store. Paths are absolute (made so when the recipe is recorded), so a repair works from
//! any directory. A key this version does not know is an error (the recipe controls the
//! geometry). Stores built before the recipe was data hold the command line instead
//! (`{"cwd": ..., "argv": [...]}`): [`read_recipe`] returns it as
//! [`RecordedRecipe::CommandLine`] for the command-line interface to turn into a recipe.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::build::{BuildInputs, BuildOptions, build_store};
use crate::dem::{Dem, DemLoadOptions, load_dem};
use crate::error::{Error, Result};
use crate::fsutil::{PngCompression, write_atomic};
use crate::georef::WorldRect;
use crate::ortho::{Ortho, OrthoPlacement, load_ortho};
use crate::progress::ProgressSink;
use crate::store::{Manifest, crc32_hex};

/// The recipe file in a store directory.
pub const RECIPE_FILE: &str = "recipe.json";

/// The version of the recipe format this cliffmap writes and reads.
pub const RECIPE_VERSION: u32 = 1;

/// What `build` was given: the inputs, how they are read and placed, and the options.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BuildRecipe {
    /// [`RECIPE_VERSION`].
    pub recipe_version: u32,
    /// The DEM file.
    pub dem: PathBuf,
    /// How the DEM is read.
    pub dem_load: DemLoadOptions,
    /// The ortho image; `None` derives the textures from the DEM.
    pub ortho: Option<PathBuf>,
    /// The ortho is on the DEM's grid (one pixel per sample).
    #[serde(default)]
    pub ortho_same_grid: bool,
    /// The ortho's world extent, when neither its file nor the DEM's grid places it.
    #[serde(default)]
    pub ortho_extent: Option<WorldRect>,
    /// Ortho pixels of exactly this colour hold no data.
    #[serde(default)]
    pub ortho_nodata_colour: Option<[u8; 3]>,
    /// Max vertical error of the finest level ([`BuildOptions::max_error`]).
    pub max_error: f64,
    /// Sample intervals per side of a finest cell ([`BuildOptions::cell_intervals`]).
    pub cell_intervals: u32,
    /// Texture side in texels ([`BuildOptions::cell_texels`]).
    pub cell_texels: u32,
    /// PNG compression of the textures ([`BuildOptions::png_compression`]).
    #[serde(default)]
    pub png_compression: PngCompression,
}

/// The inputs a recipe names, loaded and described for the manifest.
pub struct LoadedInputs {
    /// The DEM.
    pub dem: Dem,
    /// The ortho, with its no-data colour masked.
    pub ortho: Option<Ortho>,
    /// Everything that shapes the inputs (file contents, how they were read and placed):
    /// part of the store's build key.
    pub fingerprint: String,
}

/// A recipe as found in a store: data, or (stores built before it was data) the command
/// line of the build.
#[derive(Clone, Debug, PartialEq)]
pub enum RecordedRecipe {
    /// A recipe of this format.
    Current(Box<BuildRecipe>),
    /// The recorded command line of an older store: working directory and arguments.
    CommandLine {
        /// The working directory the command ran in.
        cwd: PathBuf,
        /// The arguments, program name first.
        argv: Vec<String>,
    },
}

/// The command-line form older stores recorded.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CommandLineRecipe {
    cwd: PathBuf,
    argv: Vec<String>,
}

impl BuildRecipe {
    /// The build options of this recipe (no progress, no forced rebuild).
    pub fn build_options(&self) -> BuildOptions {
        BuildOptions {
            max_error: self.max_error,
            cell_intervals: self.cell_intervals,
            cell_texels: self.cell_texels,
            png_compression: self.png_compression,
            ..BuildOptions::default()
        }
    }

    /// The recipe with relative paths made absolute against `cwd`.
    pub fn resolved_against(mut self, cwd: &Path) -> BuildRecipe {
        fn abs(cwd: &Path, p: &Path) -> PathBuf {
            if p.is_absolute() {
                p.to_path_buf()
            } else {
                cwd.join(p)
            }
        }
        self.dem = abs(cwd, &self.dem);
        self.ortho = self.ortho.as_deref().map(|p| abs(cwd, p));
        self
    }

    /// The input files that do not exist (any at all makes a rebuild impossible).
    pub fn missing_inputs(&self) -> Vec<PathBuf> {
        std::iter::once(&self.dem)
            .chain(self.ortho.iter())
            .filter(|p| !p.is_file())
            .cloned()
            .collect()
    }

    /// Loads and checks the DEM and the ortho as the recipe says; errors name the file.
    pub fn load_inputs(&self) -> Result<LoadedInputs> {
        let dem = load_dem(&self.dem, &self.dem_load)?;
        let ortho = match &self.ortho {
            Some(p) => Some(self.load_ortho(p, &dem)?),
            None => None,
        };
        let fingerprint = format!(
            "{}|{}|{:?}|{:?}|{:?}|{}",
            file_crc(&self.dem)?,
            self.ortho
                .as_deref()
                .map(file_crc)
                .transpose()?
                .unwrap_or_default(),
            self.dem_load,
            self.ortho_extent,
            self.ortho_nodata_colour,
            self.ortho_same_grid
        );
        Ok(LoadedInputs {
            dem,
            ortho,
            fingerprint,
        })
    }

    fn load_ortho(&self, path: &Path, dem: &Dem) -> Result<Ortho> {
        let placement = if self.ortho_same_grid {
            OrthoPlacement::SameGridAsDem
        } else if let Some(e) = self.ortho_extent {
            OrthoPlacement::Extent(e)
        } else {
            OrthoPlacement::FromFile
        };
        let mut o = load_ortho(path, placement, dem, self.dem_load.max_memory)?;
        if let Some(c) = self.ortho_nodata_colour {
            let n = o.mask_colour(c);
            tracing::info!(
                "{}: {n} pixels of colour {c:?} marked as no data",
                path.display()
            );
        }
        Ok(o)
    }

    /// Writes the recipe as `dir/recipe.json` (atomically).
    pub fn write(&self, dir: &Path) -> Result<()> {
        let path = dir.join(RECIPE_FILE);
        let text = serde_json::to_vec_pretty(self)
            .map_err(|e| Error::bad_input(&path, format!("cannot encode the recipe: {e}")))?;
        write_atomic(&path, &text)
    }
}

/// Reads `dir/recipe.json`: a recipe of this format, or the command line an older store
/// recorded. Errors name the file: missing, unreadable, of another version, or with a key
/// this version does not know.
pub fn read_recipe(dir: &Path) -> Result<RecordedRecipe> {
    let path = dir.join(RECIPE_FILE);
    let bytes = std::fs::read(&path).map_err(|e| {
        Error::bad_input(
            &path,
            format!("no build recipe ({e}; the store was not made by `cliffmap build` of this version); rebuild it with the original `cliffmap build` command"),
        )
    })?;
    let value: serde_json::Value = serde_json::from_slice(&bytes)
        .map_err(|e| Error::bad_input(&path, format!("invalid build recipe: {e}")))?;
    if value.get("argv").is_some() {
        let old: CommandLineRecipe = serde_json::from_value(value)
            .map_err(|e| Error::bad_input(&path, format!("invalid build recipe: {e}")))?;
        return Ok(RecordedRecipe::CommandLine {
            cwd: old.cwd,
            argv: old.argv,
        });
    }
    match value.get("recipe_version").and_then(|v| v.as_u64()) {
        Some(v) if v == RECIPE_VERSION as u64 => {}
        Some(v) => {
            return Err(Error::bad_input(
                &path,
                format!(
                    "recipe version {v} is not supported (this cliffmap reads version {RECIPE_VERSION})"
                ),
            ));
        }
        None => {
            return Err(Error::bad_input(
                &path,
                "invalid build recipe: no \"recipe_version\"",
            ));
        }
    }
    let recipe: BuildRecipe = serde_json::from_value(value)
        .map_err(|e| Error::bad_input(&path, format!("invalid build recipe: {e}")))?;
    Ok(RecordedRecipe::Current(Box::new(recipe)))
}

/// Builds (or resumes) the store in `out` from `recipe` and records the recipe in it, its
/// paths made absolute against the current directory (the manifest names the inputs as
/// the recipe gives them). `force` rebuilds over a store built from other inputs or
/// options.
pub fn build_from_recipe(
    recipe: &BuildRecipe,
    out: &Path,
    progress: ProgressSink,
    force: bool,
) -> Result<Manifest> {
    let cwd = std::env::current_dir().map_err(|e| Error::io(".", e))?;
    let manifest = build_without_recording(recipe, out, progress, force)?;
    recipe.clone().resolved_against(&cwd).write(out)?;
    Ok(manifest)
}

/// [`build_from_recipe`] without writing the recipe (the repair keeps the one it read).
pub(crate) fn build_without_recording(
    recipe: &BuildRecipe,
    out: &Path,
    progress: ProgressSink,
    force: bool,
) -> Result<Manifest> {
    let opts = BuildOptions {
        progress,
        force,
        ..recipe.build_options()
    };
    opts.validate()?;
    let loaded = recipe.load_inputs()?;
    let inputs = BuildInputs {
        dem: &loaded.dem,
        ortho: loaded.ortho.as_ref(),
        dem_source: recipe.dem.display().to_string(),
        ortho_source: recipe.ortho.as_ref().map(|p| p.display().to_string()),
        fingerprint: loaded.fingerprint,
    };
    build_store(&inputs, &opts, out)
}

/// The CRC-32 of a file's bytes (hex).
fn file_crc(p: &Path) -> Result<String> {
    let bytes = std::fs::read(p).map_err(|e| Error::io(p, e))?;
    Ok(crc32_hex(&bytes))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn recipe() -> BuildRecipe {
        BuildRecipe {
            recipe_version: RECIPE_VERSION,
            dem: PathBuf::from("/data/dem.tif"),
            dem_load: DemLoadOptions::default(),
            ortho: Some(PathBuf::from("ortho.png")),
            ortho_same_grid: true,
            ortho_extent: None,
            ortho_nodata_colour: Some([0, 0, 0]),
            max_error: 0.5,
            cell_intervals: 64,
            cell_texels: 256,
            png_compression: PngCompression::Fast,
        }
    }

    #[test]
    fn a_recipe_round_trips_and_resolves_relative_paths() {
        let dir = tempfile::tempdir().unwrap();
        let r = recipe().resolved_against(Path::new("/work"));
        assert_eq!(r.dem, PathBuf::from("/data/dem.tif"));
        assert_eq!(r.ortho.as_deref(), Some(Path::new("/work/ortho.png")));
        r.write(dir.path()).unwrap();
        assert_eq!(
            read_recipe(dir.path()).unwrap(),
            RecordedRecipe::Current(Box::new(r))
        );
    }

    #[test]
    fn unknown_keys_other_versions_and_old_command_lines() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join(RECIPE_FILE);
        let mut v = serde_json::to_value(recipe()).unwrap();
        v["max_eror"] = serde_json::json!(0.25);
        std::fs::write(&path, v.to_string()).unwrap();
        let e = read_recipe(dir.path()).unwrap_err().to_string();
        assert!(e.contains("recipe.json") && e.contains("max_eror"), "{e}");
        let mut v = serde_json::to_value(recipe()).unwrap();
        v["recipe_version"] = serde_json::json!(RECIPE_VERSION + 1);
        std::fs::write(&path, v.to_string()).unwrap();
        let e = read_recipe(dir.path()).unwrap_err().to_string();
        assert!(e.contains("recipe version"), "{e}");
        std::fs::write(&path, r#"{"cwd": "/w", "argv": ["cliffmap", "build"]}"#).unwrap();
        assert_eq!(
            read_recipe(dir.path()).unwrap(),
            RecordedRecipe::CommandLine {
                cwd: PathBuf::from("/w"),
                argv: vec!["cliffmap".into(), "build".into()]
            }
        );
        std::fs::remove_file(&path).unwrap();
        let e = read_recipe(dir.path()).unwrap_err().to_string();
        assert!(e.contains("no build recipe"), "{e}");
    }
}
