//! The checks every camera source shares: a camera usable for projection
//! ([`validate_camera`]), a camera fitted to the real size of its image
//! ([`fit_camera_to_image`]) and a small change of view angles ([`apply_rotation_delta`]).

use std::path::Path;

use super::{CameraModel, rotation_from_yaw_pitch_roll, yaw_pitch_roll_from_rotation};
use crate::error::{Error, Result};

/// Checks that `cam` can be used for projection: finite everywhere, positive size and focal
/// lengths, orthonormal rotation (determinant +1), radial distortion invertible inside the
/// image ([`CameraModel::problem`]). The error names `source`.
pub fn validate_camera(cam: &CameraModel, source: &Path) -> Result<()> {
    match cam.problem() {
        Some(msg) => Err(Error::bad_input(source, msg)),
        None => Ok(()),
    }
}

/// The camera rotated by a small change of its ImGRAFT view angles (degrees, added to yaw,
/// pitch and roll as ImGRAFT's `camB.viewdir = camA.viewdir + delta`): yaw turns the optical
/// axis counter-clockwise seen from above (the scene moves right in the image), pitch
/// positive looks further down (the scene moves up), roll tilts the horizon. Position and
/// intrinsics are unchanged.
pub fn apply_rotation_delta(cam: &CameraModel, delta_deg: [f64; 3]) -> CameraModel {
    let (yaw, pitch, roll) = yaw_pitch_roll_from_rotation(&cam.world_to_camera);
    let r = rotation_from_yaw_pitch_roll(
        yaw + delta_deg[0].to_radians(),
        pitch + delta_deg[1].to_radians(),
        roll + delta_deg[2].to_radians(),
    );
    CameraModel {
        world_to_camera: r,
        ..*cam
    }
}

/// `cam` (read from `source`) for an image of `size`: unchanged if the sizes agree, else
/// [`CameraModel::resized`] when the aspect ratios agree within 1 %, else an error naming
/// both files.
pub fn fit_camera_to_image(
    cam: CameraModel,
    size: (u32, u32),
    source: &Path,
    image: &Path,
) -> Result<CameraModel> {
    if (cam.width, cam.height) == size {
        return Ok(cam);
    }
    let a_cam = cam.width as f64 / cam.height as f64;
    let a_img = size.0 as f64 / size.1 as f64;
    if (a_cam / a_img - 1.0).abs() > 0.01 {
        return Err(Error::bad_input(
            source,
            format!(
                "camera is for a {} x {} image but {} is {} x {} (aspect ratios differ by more than 1 %)",
                cam.width,
                cam.height,
                image.display(),
                size.0,
                size.1
            ),
        ));
    }
    Ok(cam.resized(size.0, size.1))
}
