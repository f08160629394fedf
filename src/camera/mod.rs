//! Pinhole cameras in the world frame, shared by the renderer and the photo stage.
//!
//! Data types: [`CameraModel`] is a full camera: world position (f64), world-to-camera
//! rotation (rows = camera right, down, forward; x east, y north, z up in the world),
//! intrinsics in pixels of an image of `width × height` (pixel-centre convention: the
//! centre of the top-left pixel is (0, 0)) and ImGRAFT radial distortion `k1`, `k2`.
//! [`camera_from_json_file`] reads the "Camera JSON" of docs/formats.md: either a
//! cliffmap camera or an ImGRAFT-style description (e.g. the Engabreen camera file).
//! [`CameraModel::pixel_ray`] inverts the projection (undistorting first) for ray casting.

mod checks;
mod exif;
mod geometry;
mod json;
mod rough;
mod undistort;

pub use checks::{apply_rotation_delta, fit_camera_to_image, validate_camera};
pub use exif::{ExifFocal, ExifGps, exif_camera_body, exif_focal_px, exif_gps};
pub use geometry::yaw_pitch_roll_from_rotation;
pub use json::{
    camera_from_json_file, camera_from_json_str, camera_to_imgraft_json, camera_to_json,
};
pub use rough::{DEFAULT_HEIGHT_ABOVE_GROUND_M, RoughCamera, RoughPose, rough_camera};
pub(crate) use undistort::{PlaneRay, RayCaster};

use glam::{DMat3, DVec3};

/// A pinhole camera with optional radial distortion.
///
/// Projection (ImGRAFT `camera.m`): `c = R·(X − position)`; `x = c.x/c.z`, `y = c.y/c.z`;
/// `r² = min(x² + y², 4)`; `(x, y) *= 1 + k1·r² + k2·r⁴`; pixel `u = fx·x + cx`,
/// `v = fy·y + cy` (u right, v down, 0-based, centre of the top-left pixel = (0, 0)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraModel {
    /// Centre of projection, world metres (f64).
    pub position: DVec3,
    /// World-to-camera rotation; its rows are the camera's right, down and forward axes in world.
    pub world_to_camera: DMat3,
    /// Image width in pixels the intrinsics refer to.
    pub width: u32,
    /// Image height in pixels the intrinsics refer to.
    pub height: u32,
    /// Horizontal focal length, pixels.
    pub fx: f64,
    /// Vertical focal length, pixels.
    pub fy: f64,
    /// Principal point column, 0-based pixel-centre convention.
    pub cx: f64,
    /// Principal point row, 0-based pixel-centre convention.
    pub cy: f64,
    /// First radial distortion coefficient (0 = none).
    pub k1: f64,
    /// Second radial distortion coefficient (0 = none).
    pub k2: f64,
}

/// Rotation (rows right, down, forward) of a camera with ImGRAFT angles in radians: `yaw` is
/// the azimuth of the optical axis counter-clockwise from east, `pitch` is positive looking
/// down, `roll` tilts the horizon (positive turns the image's right axis towards image-down).
pub fn rotation_from_yaw_pitch_roll(yaw: f64, pitch: f64, roll: f64) -> DMat3 {
    let (sy, cy) = yaw.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sr, cr) = roll.sin_cos();
    let forward = DVec3::new(cp * cy, cp * sy, -sp);
    let right0 = DVec3::new(sy, -cy, 0.0);
    let down0 = forward.cross(right0);
    let right = cr * right0 + sr * down0;
    let down = -sr * right0 + cr * down0;
    DMat3::from_cols(right, down, forward).transpose()
}

/// Rotation (rows right, down, forward) of a camera at `position` looking at `target` with
/// world z up (image top towards +z; looking straight down, image top is north). `None` if
/// the two points coincide or are not finite.
pub fn rotation_look_at(position: DVec3, target: DVec3) -> Option<DMat3> {
    let forward = (target - position).try_normalize()?;
    let right = forward
        .cross(DVec3::Z)
        .try_normalize()
        .or_else(|| forward.cross(DVec3::Y).try_normalize())?;
    let down = forward.cross(right);
    Some(DMat3::from_cols(right, down, forward).transpose())
}

impl CameraModel {
    /// A distortion-free camera for a `width × height` image with vertical field of view
    /// `fov_y` (radians, in (0, π)), square pixels and the principal point at the image centre.
    pub fn with_fov(
        position: DVec3,
        world_to_camera: DMat3,
        width: u32,
        height: u32,
        fov_y: f64,
    ) -> CameraModel {
        let f = height as f64 / 2.0 / (fov_y / 2.0).tan();
        CameraModel::pinhole(position, world_to_camera, width, height, f)
    }

    /// A distortion-free camera for a `width × height` image with focal length `f` pixels
    /// (square pixels) and the principal point at the image centre (0-based pixel centres).
    pub fn pinhole(
        position: DVec3,
        world_to_camera: DMat3,
        width: u32,
        height: u32,
        f: f64,
    ) -> CameraModel {
        CameraModel {
            position,
            world_to_camera,
            width,
            height,
            fx: f,
            fy: f,
            cx: (width as f64 - 1.0) / 2.0,
            cy: (height as f64 - 1.0) / 2.0,
            k1: 0.0,
            k2: 0.0,
        }
    }

    /// The same camera for an image of `width × height`: focal lengths and principal point
    /// scale per axis, so both fields of view and the principal point's relative position
    /// are kept (pixels become non-square if the aspect ratio changes).
    pub fn resized(&self, width: u32, height: u32) -> CameraModel {
        let sx = width as f64 / self.width as f64;
        let sy = height as f64 / self.height as f64;
        CameraModel {
            width,
            height,
            fx: self.fx * sx,
            fy: self.fy * sy,
            cx: (self.cx + 0.5) * sx - 0.5,
            cy: (self.cy + 0.5) * sy - 0.5,
            ..*self
        }
    }

    /// Vertical field of view in radians (pinhole, distortion ignored).
    pub fn fov_y(&self) -> f64 {
        2.0 * (self.height as f64 / 2.0 / self.fy).atan()
    }

    /// The optical axis (unit vector, world).
    pub fn forward(&self) -> DVec3 {
        self.world_to_camera.row(2)
    }

    /// `world` in the camera frame (x right, y down, z forward; metres).
    pub fn to_camera(&self, world: DVec3) -> DVec3 {
        self.world_to_camera * (world - self.position)
    }

    /// Pixel `[u, v]` (0-based pixel-centre convention) of a world point, with distortion;
    /// `None` if the point is not in front of the camera. The pixel may lie outside the image.
    pub fn project(&self, world: DVec3) -> Option<[f64; 2]> {
        let c = self.to_camera(world);
        if c.z.is_nan() || c.z <= 0.0 {
            return None;
        }
        let (x, y) = (c.x / c.z, c.y / c.z);
        let r2 = (x * x + y * y).min(4.0);
        let d = 1.0 + self.k1 * r2 + self.k2 * r2 * r2;
        Some([self.fx * x * d + self.cx, self.fy * y * d + self.cy])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_frames_are_right_handed_and_upright() {
        let r = rotation_look_at(DVec3::ZERO, DVec3::new(10.0, 0.0, 0.0)).unwrap();
        assert!((r.row(0) - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-12); // right = south
        assert!((r.row(1) - DVec3::new(0.0, 0.0, -1.0)).length() < 1e-12); // down = -z
        let down = rotation_look_at(DVec3::ZERO, DVec3::new(0.0, 0.0, -5.0)).unwrap();
        assert!((down.row(1) - DVec3::new(0.0, -1.0, 0.0)).length() < 1e-12); // image down = south
        assert!(rotation_look_at(DVec3::ONE, DVec3::ONE).is_none());
    }

    #[test]
    fn yaw_pitch_roll_matches_look_at_without_roll() {
        let yaw = 0.7f64;
        let pitch = 0.2f64;
        let a = rotation_from_yaw_pitch_roll(yaw, pitch, 0.0);
        let dir = DVec3::new(
            pitch.cos() * yaw.cos(),
            pitch.cos() * yaw.sin(),
            -pitch.sin(),
        );
        let b = rotation_look_at(DVec3::ZERO, dir).unwrap();
        assert!((a.row(0) - b.row(0)).length() < 1e-12 && (a.row(1) - b.row(1)).length() < 1e-12);
    }

    #[test]
    fn projection_centre_and_resize() {
        let r = rotation_look_at(DVec3::ZERO, DVec3::X).unwrap();
        let c = CameraModel::with_fov(DVec3::ZERO, r, 101, 51, 1.0);
        let p = c.project(DVec3::new(100.0, 0.0, 0.0)).unwrap();
        assert!((p[0] - 50.0).abs() < 1e-9 && (p[1] - 25.0).abs() < 1e-9);
        assert!(c.project(DVec3::new(-1.0, 0.0, 0.0)).is_none());
        // A point up and to the left lands in the upper left quadrant.
        let q = c.project(DVec3::new(100.0, 10.0, 10.0)).unwrap();
        assert!(q[0] < 50.0 && q[1] < 25.0);
        let big = c.resized(202, 102);
        assert!((big.fov_y() - c.fov_y()).abs() < 1e-12);
        let q2 = big.project(DVec3::new(100.0, 10.0, 10.0)).unwrap();
        assert!(((q2[0] + 0.5) - 2.0 * (q[0] + 0.5)).abs() < 1e-9);
    }
}
