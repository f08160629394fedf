//! The terrain of one quadtree level as one ray-castable triangle set (owned by the raycast
//! work; signatures fixed, bodies to be written).

use glam::DVec3;

use super::{BvhQuality, TriangleBvh};
use crate::error::Result;
use crate::store::Store;

/// One cell's surface (skirts excluded) with its texture coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneCell {
    /// Index of the cell in the manifest's `cells` list.
    pub cell: u32,
    /// World position (f64) of the cell-local frame's origin.
    pub origin: DVec3,
    /// Vertex positions relative to `origin`, metres.
    pub positions: Vec<[f32; 3]>,
    /// Triangles (vertex indices), counter-clockwise seen from above.
    pub triangles: Vec<[u32; 3]>,
    /// Per-vertex texture position in texel units of the cell's active texture (x right, y down).
    pub texcoords: Vec<[f32; 2]>,
    /// Side of the cell's active texture in texels.
    pub texels: u32,
}

/// All cells of one level, as triangles in an f32 frame centred on `frame_origin`, with a BVH.
pub struct LevelScene {
    /// World position (f64) the BVH's f32 frame is relative to (near the camera).
    pub frame_origin: DVec3,
    /// The cells, in the order given.
    pub cells: Vec<SceneCell>,
    /// BVH over every cell's triangles.
    pub bvh: TriangleBvh,
}

impl LevelScene {
    /// Builds the scene from in-memory cells.
    pub fn new(_cells: Vec<SceneCell>, _frame_origin: DVec3, _quality: BvhQuality) -> LevelScene {
        todo!("raycast work")
    }

    /// Builds the scene from the active meshes (reparameterized if present) of every cell of
    /// `level` in the store.
    pub fn from_store(_store: &Store, _level: u8, _frame_origin: DVec3, _quality: BvhQuality) -> Result<LevelScene> {
        todo!("raycast work")
    }
}
