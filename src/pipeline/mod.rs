//! Orchestration of the stages into the commands' jobs. Data in: a [`Dem`] and optionally
//! an [`Ortho`] with [`BuildOptions`]; data out: a cell store on disk and its [`Manifest`].

mod build;
mod derived_ortho;
mod mesh;
mod progress;

pub use build::{BuildInputs, BuildOptions, build_store, write_stats};
pub use derived_ortho::derived_ortho;
pub use mesh::{LocalMesh, local_mesh};
pub use progress::progress_bar;

#[allow(unused_imports)]
use crate::{dem::Dem, ortho::Ortho, store::Manifest};
