//! Ray casting against the terrain: the stage `photo`, `register`, `scene` and `eval` share
//! to find what a camera ray hits.
//!
//! Data types and entry points:
//! - [`TriangleBvh`] / [`TriHit`]: nearest-hit ray casting (`obvhs` CWBVH) over f32
//!   triangles in a local frame; [`BvhQuality`] is the build preset; [`nearest_brute_force`]
//!   is the reference.
//! - [`ViewGrid`]: the triangles binned by their central projection from one camera centre
//!   (a camera-space grid, scanned front to back with early exit); [`ViewGridParams`] its
//!   bin size.
//! - [`RayAccel`]: which of the two a cast uses (they return the same nearest hits).
//! - [`LevelScene`]: all cells of one quadtree level ([`SceneCell`]: surface triangles,
//!   texture positions) in one f32 frame near the camera, with per-triangle planes, mesh
//!   adjacency and the cells' relief maps (hits moved onto the relief surface).
//! - Silhouettes: whether a texture-space segment of one cell crosses an edge between a
//!   front-facing and a back-facing triangle (`crosses_silhouette`, crate-internal).
//!
//! In: a [`crate::store::Store`]'s cells (or plain triangles) and a
//! [`crate::camera::CameraModel`]; out: nearest hits (triangle, distance, barycentrics).

mod accel;
mod bvh;
mod level_scene;
mod relief;
mod silhouette;
mod triangle;
mod viewgrid;

pub(crate) use accel::Caster;
pub use accel::RayAccel;
pub use bvh::{BvhQuality, TriHit, TriangleBvh, nearest_brute_force};
pub(crate) use level_scene::NO_TRI;
pub use level_scene::{LevelScene, SceneCell};
pub(crate) use silhouette::crosses_silhouette;
pub use viewgrid::{ViewGrid, ViewGridParams, ViewGridStats, Z_NEAR};
