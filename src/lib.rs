//! # cliffmap
//!
//! Better terrain textures on cliffs. cliffmap cuts a DEM into a quadtree of
//! error-bounded TIN cells with per-cell ortho textures, measures how much the
//! orthographic parameterization stretches texels on steep ground, and (in later
//! stages) reparameterizes steep cells, resamples textures, projects ground photos and
//! renders the result.
//!
//! Stages (one module each, plain data types in and out):
//! - [`dem`], [`ortho`]: inputs ([`Dem`], [`Ortho`]), georeferenced in f64
//!   ([`geotiff`] holds the GeoTIFF tag parsing both share).
//! - [`cells`]: quadtree addressing and TIN simplification ([`Quadtree`], [`Tin`]).
//! - [`stats`]: texel-stretch statistics.
//! - [`store`]: the on-disk cell store (manifest, meshes, textures).
//! - [`scene`]: the embedded procedural demo scene.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod cells;
pub mod dem;
pub mod error;
pub mod georef;
pub mod geotiff;
pub mod ortho;

pub use cells::{CellKey, Quadtree, SampleRect, Tin};
pub use dem::{Dem, DemFormat, DemLoadOptions, load_dem};
pub use error::{Error, Result};
pub use georef::{GridGeoref, WorldRect};
pub use ortho::{Ortho, OrthoPlacement, load_ortho};

/// Test-only TIFF writers shared with the integration tests.
#[cfg(test)]
#[path = "../tests/common/tiffgen.rs"]
pub(crate) mod tiffgen;
