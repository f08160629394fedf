//! Pixel footprints of a photo in the cells' textures (owned by the raycast work;
//! signatures fixed, bodies to be written).

use super::scene::LevelScene;
use super::FootprintSet;
use crate::camera::CameraModel;

/// How footprints are formed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootprintOptions {
    /// Complete footprints with missing corners (parallelogram / adjacent footprints).
    pub reconstruct: bool,
    /// Reject pixels whose footprint crosses a silhouette edge.
    pub reject_silhouettes: bool,
}

impl Default for FootprintOptions {
    fn default() -> Self {
        FootprintOptions { reconstruct: true, reject_silhouettes: true }
    }
}

/// Casts rays through every pixel corner of `camera`'s image (undistorted) against `scene`
/// and returns every pixel's footprint in the texture of the cell it belongs to.
pub fn photo_footprints(_scene: &LevelScene, _camera: &CameraModel, _opts: &FootprintOptions) -> FootprintSet {
    todo!("raycast work")
}
