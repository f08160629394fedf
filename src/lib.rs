//! # cliffmap
//!
//! Better terrain textures on cliffs. cliffmap cuts a DEM into a quadtree of error-bounded
//! TIN cells with per-cell ortho textures, measures how much the orthographic
//! parameterization stretches texels on steep ground, gives stretched cells an
//! area/angle-preserving chart with a resampled texture, projects ground photos into the
//! cell textures, registers photo cameras, and renders and exports the result.
//!
//! ## Stages
//! One module per stage, plain data types in and out; a module only uses the modules listed
//! before it (docs/architecture.md, "Layers"; `tests/layering.rs` checks it).
//! - Shared: [`error`] ([`Error`], [`Result`]), [`fsutil`] (atomic writes, PNG encoding),
//!   [`georef`] ([`GridGeoref`], [`WorldRect`]), [`crs`], [`colour`], [`progress`]
//!   ([`Progress`], [`ProgressSink`]: how long steps report progress), [`geotiff`].
//! - Inputs: [`dem`] ([`Dem`], [`load_dem`]), [`ortho`] ([`Ortho`], [`load_ortho`]).
//! - [`camera`]: [`CameraModel`], Camera JSON and ImGRAFT files, EXIF, validation, rough
//!   start cameras from a photographer's pose ([`camera::rough_camera`]).
//! - [`cells`]: quadtree addressing and TIN simplification ([`Quadtree`], [`CellKey`],
//!   [`Tin`], [`cells::build_tin`]), the cell mesh ([`CellMesh`]) and per-cell images
//!   ([`ortho_texture`], [`normal_map`]).
//! - [`stats`]: texel-stretch statistics ([`cell_stats`], [`stats::stats_json`]).
//! - [`param`]: area/angle-preserving parameterization of a cell (Degener et al. 2003,
//!   [`parameterize`]) and chart metrics.
//! - [`resample`]: resampling a colour source into a new chart with area-weighted subtexel
//!   filtering ([`resample::resample`]).
//! - [`store`]: the on-disk cell store ([`Store`]: manifest, meshes, textures, locks).
//! - [`raycast`]: ray casting against a level's cells (BVH, camera-space grid, silhouettes).
//! - [`photo`]: ground-photo projection into the cell textures (footprints, area-weighted
//!   splatting, multi-photo blending, colour leveling; [`PhotoInput`]).
//! - [`register`]: camera registration (GCPs, terrain, ties between photos, resection,
//!   bundle adjustment).
//! - [`render`]: the wgpu quadtree renderer ([`StoreRenderer`]).
//! - [`demo_scene`]: the embedded procedural demo scene (ground truth, exact ray casting).
//! - [`pipeline`]: the stages composed into the commands' jobs ([`build_store`],
//!   [`reparam_store`], [`project_store`], [`register_photos`]).
//! - [`export`]: GLB and 3D Tiles 1.1 ([`export_glb`], [`export_tiles`]).
//! - [`verify`]: integrity checks of a store and the plan of a repair ([`verify_store`]).
//! - [`eval`]: render-space evaluation against the scene's truth, an oracle and a baseline.
//!
//! Guarantees: georeferenced coordinates are f64 (cell meshes are f32 relative to an f64
//! cell origin, so UTM-sized coordinates keep millimetre precision); every TIN is within its
//! error bound of every DEM sample; outputs are identical whatever the thread count; bad
//! input is an [`Error`] naming the file, never a panic; every file is written atomically.
//!
//! ## Examples
//! One level of TIN cells from a DEM in memory:
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
//!
//! A store on disk (the main path: build, reparameterize the stretched cells, verify):
//! ```
//! use cliffmap::{BuildInputs, BuildOptions, Dem, GridGeoref, ReparamOptions, Store};
//!
//! let heights: Vec<f32> = (0..65 * 65)
//!     .map(|i| if i % 65 < 30 { 100.0 } else { 140.0 })
//!     .collect();
//! let dem = Dem::from_heights(65, 65, heights, GridGeoref::new(500_000.0, 7_000_000.0, 2.0))?;
//! let dir = std::env::temp_dir().join(format!("cliffmap-doc-{}", std::process::id()));
//! let inputs = BuildInputs {
//!     dem: &dem,
//!     ortho: None, // textures derived from the DEM (tint and hillshade)
//!     dem_source: "doc example".into(),
//!     ortho_source: None,
//!     fingerprint: "doc".into(),
//! };
//! let opts = BuildOptions { cell_intervals: 32, cell_texels: 64, ..BuildOptions::default() };
//! let manifest = cliffmap::build_store(&inputs, &opts, &dir)?;
//! assert_eq!(manifest.cells.len(), 5); // a root and its four children
//! let store: Store = cliffmap::reparam_store(&dir, &ReparamOptions::default())?;
//! assert!(store.manifest.cells.iter().any(|c| c.reparam.is_some())); // the cliff's cells
//! assert!(cliffmap::verify_store(&dir).is_intact());
//! # std::fs::remove_dir_all(&dir).ok();
//! # Ok::<(), cliffmap::Error>(())
//! ```
//!
//! Projecting photos ([`project_store`]) and rendering a view ([`StoreRenderer`], which
//! needs a GPU driver or Mesa's software drivers):
//! ```no_run
//! use std::path::Path;
//! use cliffmap::{ProjectOptions, SceneOptions, StoreRenderer, camera_from_json_file};
//!
//! let store = Path::new("engabreen.store");
//! let photos = cliffmap::photo::read_photo_list(Path::new("photos.json"))?;
//! let report = cliffmap::project_store(store, &photos, &ProjectOptions::default())?;
//! for p in &report.settings.photos {
//!     println!("{}: {} texels supplied", p.name, p.texels_supplied);
//! }
//!
//! let camera = camera_from_json_file(Path::new("camera.json"), (1280, 852))?.resized(1280, 852);
//! let mut view = StoreRenderer::open(store, 1280, 852, SceneOptions::default())?;
//! view.frame(&camera, true)?;
//! view.read_rgba()?.save("view.png").expect("write view.png");
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
pub mod demo_scene;
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
pub mod stats;
pub mod store;
pub mod verify;

/// Test-only TIFF writers shared with the integration tests.
#[cfg(test)]
#[path = "../tests/common/tiffgen.rs"]
pub(crate) mod tiffgen;

pub use camera::{CameraModel, camera_from_json_file};
pub use cells::{CellKey, CellMesh, Quadtree, SampleRect, Tin, normal_map, ortho_texture};
pub use dem::{Dem, DemFormat, DemLoadOptions, load_dem};
pub use error::{Error, Result};
pub use export::{GlbOptions, TilesOptions, export_glb, export_tiles};
pub use georef::{GridGeoref, WorldRect};
pub use ortho::{Ortho, OrthoPlacement, load_ortho};
pub use param::{Chart, ChartMetrics, ParamMesh, ParamOptions, chart_metrics, parameterize};
pub use photo::PhotoInput;
pub use pipeline::{
    BuildInputs, BuildOptions, ProjectOptions, ReparamOptions, build_store, project_store,
    register_photos, reparam_store,
};
pub use progress::{Progress, ProgressSink, ProgressTask};
#[cfg(feature = "render")]
pub use render::{SceneOptions, StoreRenderer};
pub use stats::{CellStats, CellStatsEntry, StatsSummary, cell_stats};
pub use store::Store;
pub use verify::verify_store;
