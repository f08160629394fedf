//! The render camera: a [`CameraModel`] plus a near plane, with matrices computed relative to
//! the camera position in f64 and only then rounded to f32 (no jitter at UTM magnitudes).
//!
//! Clip space is wgpu's (x right, y up, depth in [0, 1]) with **reverse-Z and an infinite far
//! plane**: depth = near / distance-along-axis, 1 at the near plane, → 0 at infinity.

use glam::{DMat4, DVec3, DVec4, Mat4};

use super::frustum::Frustum;
use crate::camera::CameraModel;

/// A camera ready for rendering at `model.width × model.height` pixels.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderCamera {
    /// Pose and intrinsics. The rasterizer is a pinhole and ignores `k1`/`k2`; a distorted
    /// frame is rasterized through the pinhole view of [`super::DistortedView`] and resampled.
    pub model: CameraModel,
    /// Near plane distance along the optical axis, metres (> 0).
    pub near: f64,
}

impl RenderCamera {
    /// A render camera with near plane `near` metres (clamped to at least 1 mm).
    pub fn new(model: CameraModel, near: f64) -> RenderCamera {
        RenderCamera {
            model,
            near: if near.is_finite() {
                near.max(1e-3)
            } else {
                0.1
            },
        }
    }

    /// Projection from the camera frame (x right, y down, z forward) to clip space.
    pub fn projection(&self) -> DMat4 {
        let m = &self.model;
        let (w, h) = (m.width as f64, m.height as f64);
        let rows = [
            [2.0 * m.fx / w, 0.0, 2.0 * (m.cx + 0.5) / w - 1.0, 0.0],
            [0.0, -2.0 * m.fy / h, 1.0 - 2.0 * (m.cy + 0.5) / h, 0.0],
            [0.0, 0.0, 0.0, self.near],
            [0.0, 0.0, 1.0, 0.0],
        ];
        DMat4::from_cols_array_2d(&rows).transpose()
    }

    /// Maps camera-relative world coordinates (world − position, metres) to clip space.
    pub fn view_proj_relative(&self) -> DMat4 {
        let r = self.model.world_to_camera;
        let view = DMat4::from_cols(
            r.x_axis.extend(0.0),
            r.y_axis.extend(0.0),
            r.z_axis.extend(0.0),
            DVec4::W,
        );
        self.projection() * view
    }

    /// Model-view-projection (f32) for a mesh whose local frame has its origin at world `origin`:
    /// the offset `origin − position` is taken in f64 before rounding.
    pub fn mvp_for_origin(&self, origin: DVec3) -> Mat4 {
        (self.view_proj_relative() * DMat4::from_translation(origin - self.model.position))
            .as_mat4()
    }

    /// The view frustum in camera-relative world coordinates.
    pub fn frustum(&self) -> Frustum {
        Frustum::from_view_proj(&self.view_proj_relative())
    }

    /// The point seen at pixel `(u, v)` (pixel centres at integer coordinates, the camera
    /// model's convention) with reverse-Z depth-buffer value `depth` (= near / z), as an offset
    /// from the camera position in world metres; `None` for depth ≤ 0 (nothing drawn) or NaN.
    pub fn unproject_relative(&self, u: f64, v: f64, depth: f32) -> Option<DVec3> {
        if !(depth > 0.0) {
            return None;
        }
        let m = &self.model;
        let z = self.near / depth as f64;
        let cam = DVec3::new((u - m.cx) / m.fx * z, (v - m.cy) / m.fy * z, z);
        Some(m.world_to_camera.transpose() * cam)
    }

    /// Pinhole projection (no distortion, as rasterized) of a camera-relative world offset to
    /// pixel coordinates; `None` behind the camera.
    pub fn project_relative(&self, rel: DVec3) -> Option<[f64; 2]> {
        let m = &self.model;
        let c = m.world_to_camera * rel;
        (c.z > 1e-12).then(|| [m.fx * c.x / c.z + m.cx, m.fy * c.y / c.z + m.cy])
    }

    /// Pixels covered by one metre seen face-on at `distance` metres (vertical focal length / d).
    pub fn pixels_per_metre(&self, distance: f64) -> f64 {
        self.model.fy / distance.max(1e-9)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::rotation_look_at;

    #[test]
    fn projects_like_the_camera_model_at_utm_magnitudes() {
        let pos = DVec3::new(446_722.0, 7_396_671.0, 770.0);
        let r = rotation_look_at(pos, pos + DVec3::new(-1.0, -0.8, -0.1)).unwrap();
        let mut model = CameraModel::with_fov(pos, r, 320, 200, 0.9);
        model.cx = 150.0;
        let cam = RenderCamera::new(model, 1.0);
        let origin = DVec3::new(446_000.0, 7_396_000.0, 600.0);
        let local = glam::Vec3::new(12.25, -3.5, 40.0);
        let clip = cam.mvp_for_origin(origin) * local.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        let px = [
            (ndc.x as f64 + 1.0) / 2.0 * 320.0 - 0.5,
            (1.0 - ndc.y as f64) / 2.0 * 200.0 - 0.5,
        ];
        let want = model.project(origin + local.as_dvec3()).unwrap();
        assert!(
            (px[0] - want[0]).abs() < 1e-3 && (px[1] - want[1]).abs() < 1e-3,
            "{px:?} vs {want:?}"
        );
        assert!(ndc.z > 0.0 && ndc.z < 1.0);
        // The depth value round-trips through unprojection to the same point.
        let world = origin + local.as_dvec3();
        let p = cam.project_relative(world - pos).unwrap();
        let back = cam.unproject_relative(p[0], p[1], ndc.z).unwrap() + pos;
        assert!(
            (back - world).length() < 1e-3 * (world - pos).length(),
            "{back} vs {world}"
        );
        assert!(cam.unproject_relative(1.0, 1.0, 0.0).is_none());
    }
}
