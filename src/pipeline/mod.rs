//! Orchestration of the stages into the commands' jobs.
//!
//! - [`build_store`]: a [`Dem`] and optionally an [`Ortho`] with [`BuildOptions`] in, a cell
//!   store on disk and its [`Manifest`] out.
//! - [`reparam_store`]: a store and [`ReparamOptions`] in; stretched cells gain a
//!   [`crate::store::ReparamRecord`] (chart, resampled texture, metrics).
//! - [`project_store`]: a store, [`crate::photo::PhotoInput`]s and [`ProjectOptions`] in;
//!   cells the photos see gain a [`crate::store::PhotoCellRecord`] (enhanced texture,
//!   confidence map, steep-texel counts).

mod build;
mod decoded_photos;
mod derived_ortho;
mod photo_stats;
mod project;
mod recipe;
mod register;
mod reparam;

pub use build::{BuildInputs, BuildOptions, build_store, write_stats};
pub use derived_ortho::derived_ortho;
pub use project::{
    PhotoTextureOptions, ProjectOptions, ProjectReport, STEEP_SLOPE_DEG, coarse_scale_cap,
    project_store,
};
pub(crate) use recipe::build_without_recording;
pub use recipe::{
    BuildRecipe, LoadedInputs, RECIPE_FILE, RECIPE_VERSION, RecordedRecipe, build_from_recipe,
    read_recipe,
};
pub use register::{
    PhotoRegistration, TieSettings, register_photos, register_photos_with, resolve_photo_entries,
};
pub use reparam::{
    ReparamOptions, TextureMemory, recorded_reparam_options, redo_reparam_cells, reparam_store,
    texture_memory,
};

#[allow(unused_imports)]
use crate::{dem::Dem, ortho::Ortho, store::Manifest};
