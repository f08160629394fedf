//! # cliffmap
//!
//! Better terrain textures on cliffs. cliffmap cuts a DEM into a quadtree of
//! error-bounded TIN cells with per-cell ortho textures, measures how much the
//! orthographic parameterization stretches texels on steep ground, and (in later
//! stages) reparameterizes steep cells, resamples textures, projects ground photos and
//! renders the result.
//!
//! Stages (one module each, plain data types in and out):
//! - [`dem`], [`ortho`]: inputs ([`Dem`], [`Ortho`]), georeferenced in f64.
//! - [`cells`]: quadtree addressing and TIN simplification ([`Quadtree`], [`Tin`]).
//! - [`stats`]: texel-stretch statistics.
//! - [`param`]: per-cell area/angle-preserving reparameterization ([`ParamMesh`] -> [`Chart`]).
//! - [`store`]: the on-disk cell store (manifest, meshes, textures).
//! - [`scene`]: the embedded procedural demo scene.

#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod cells;
pub mod dem;
pub mod error;
pub mod georef;
pub mod ortho;
pub mod param;

pub use cells::{CellKey, Quadtree, SampleRect, Tin};
pub use dem::{Dem, DemFormat, DemLoadOptions, load_dem};
pub use error::{Error, Result};
pub use georef::{GridGeoref, WorldRect};
pub use ortho::{Ortho, OrthoPlacement, load_ortho};
pub use param::{Chart, ChartMetrics, ParamMesh, ParamOptions, chart_metrics, parameterize};
