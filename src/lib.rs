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
//! - [`cells`]: quadtree addressing, TIN simplification ([`Quadtree`], [`Tin`],
//!   [`cells::build_tin`]) and per-cell images ([`ortho_texture`], [`normal_map`]).
//! - [`stats`]: texel-stretch statistics ([`cell_stats`], [`stats::stats_json`]).
//! - [`store`]: the on-disk cell store (manifest, meshes, textures).
//! - [`param`]: area/angle-preserving parameterization of a cell (Degener et al. 2003,
//!   [`param::parameterize`]) and chart metrics.
//! - [`pipeline`]: the stages composed into the commands' jobs ([`pipeline::build_store`]).
//! - [`resample`]: resampling a colour source into a new chart with area-weighted
//!   subtexel filtering ([`resample::resample`]).
//! - [`photo`]: ground-photo projection into the cell textures (BVH ray casts through
//!   pixel corners, footprints, area-weighted splatting, multi-photo blending).
//! - [`scene`]: the embedded procedural demo scene (ground truth, exact ray casting).
//! - [`eval`]: render-space evaluation against the scene's truth, an oracle and a baseline.
//! - [`camera`]: pinhole cameras and Camera JSON; [`render`]: the wgpu quadtree renderer.
//! - [`verify`]: integrity checks of a store and the plan of a repair.
//!
//! Guarantees: georeferenced coordinates are f64 (cell meshes are f32 relative to an f64
//! cell origin, so UTM-sized coordinates keep millimetre precision); every TIN is within its
//! error bound of every DEM sample; outputs are identical whatever the thread count; bad
//! input is an [`Error`] naming the file, never a panic; every file is written atomically.
//!
//! ```
//! use cliffmap::{Dem, GridGeoref, Quadtree, cells};
//!
//! // A 65 x 65 DEM with a 40 m cliff, 2 m spacing, at UTM-sized coordinates.
//! let heights: Vec<f32> = (0..65 * 65)
//!     .map(|i| if i % 65 < 30 { 100.0 } else { 140.0 } + ((i / 65) as f32 * 0.2).sin())
//!     .collect();
//! let dem = Dem::from_heights(65, 65, heights, GridGeoref::new(500_000.0, 7_000_000.0, 2.0))?;
//! let tree = Quadtree::new(65, 65, 32); // finest cells of 32 intervals: 2 levels
//! assert_eq!(tree.levels, 2);
//! for (key, tin) in cells::build_level(&dem, &tree, tree.finest_level(), 0.25)? {
//!     assert!(tin.max_error <= 0.25, "cell {} error {}", key.id(), tin.max_error);
//! }
//! # Ok::<(), cliffmap::Error>(())
//! ```

#![forbid(unsafe_code)]
#![warn(missing_docs)]
// Negated comparisons like `!(x > 0.0)` are how this crate makes NaN fail a check.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

pub mod camera;
pub mod cells;
pub mod colour;
mod cpu;
pub mod crs;
pub mod dem;
pub mod error;
pub mod eval;
pub mod export;
mod fastmath;
mod font;
pub mod fsutil;
pub mod georef;
pub mod geotiff;
pub mod ortho;
pub mod param;
pub mod photo;
pub mod pipeline;
pub mod progress;
pub mod raycast;
pub mod register;
pub mod render;
pub mod resample;
pub mod scene;
pub mod stats;
pub mod store;
pub mod verify;

/// Test-only TIFF writers shared with the integration tests.
#[cfg(test)]
#[path = "../tests/common/tiffgen.rs"]
pub(crate) mod tiffgen;

pub use cells::{CellKey, Quadtree, SampleRect, Tin, normal_map, ortho_texture};
pub use dem::{Dem, DemFormat, DemLoadOptions, load_dem};
pub use error::{Error, Result};
pub use georef::{GridGeoref, WorldRect};
pub use ortho::{Ortho, OrthoPlacement, load_ortho};
pub use param::{Chart, ChartMetrics, ParamMesh, ParamOptions, chart_metrics, parameterize};
pub use stats::{CellStats, CellStatsEntry, StatsSummary, cell_stats};
