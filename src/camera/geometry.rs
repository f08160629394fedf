//! Inverse geometry of [`CameraModel`]: ImGRAFT angles from a rotation, undistortion and
//! pixel rays, and the consistency check every camera source applies.

use glam::{DMat3, DVec3};

use super::CameraModel;

/// ImGRAFT angles `(yaw, pitch, roll)` in radians of a world-to-camera rotation (rows right,
/// down, forward), the inverse of [`super::rotation_from_yaw_pitch_roll`]: yaw in (−π, π],
/// pitch in [−π/2, π/2]. Looking straight up or down (yaw and roll coincide), roll is 0 and
/// yaw carries the image's orientation. Exact up to rounding for orthonormal rotations.
pub fn yaw_pitch_roll_from_rotation(r: &DMat3) -> (f64, f64, f64) {
    let (right, down, fwd) = (r.row(0), r.row(1), r.row(2));
    let pitch = (-fwd.z).clamp(-1.0, 1.0).asin();
    let horiz = fwd.x.hypot(fwd.y);
    if horiz < 1e-12 {
        // right = (sin yaw, −cos yaw, 0) with roll 0.
        return (right.x.atan2(-right.y), pitch, 0.0);
    }
    let yaw = fwd.y.atan2(fwd.x);
    let (sy, cy) = yaw.sin_cos();
    let right0 = DVec3::new(sy, -cy, 0.0);
    let down0 = fwd.cross(right0);
    // right = cos(roll)·right0 + sin(roll)·down0; `down` gives the same angle redundantly.
    let roll = (right.dot(down0) - down.dot(right0)).atan2(right.dot(right0) + down.dot(down0));
    (yaw, pitch, roll)
}

impl CameraModel {
    /// Why this camera is unusable, or `None`: a non-finite value anywhere, a zero size,
    /// non-positive focal lengths, a rotation that is not orthonormal with determinant +1
    /// (tolerance 1e-6), or a radial distortion that folds before the nearest image edge
    /// (the radial map must increase up to the distorted radius of the image edge nearest
    /// the principal point). A model that folds only
    /// beyond that, in the image's corners, is accepted: pixels beyond the fold have no ray
    /// ([`CameraModel::rayless_share`]; `project` casts none there, `render` shows them as
    /// sky). This is the one rule every command applies (docs/formats.md, "Validity").
    pub fn problem(&self) -> Option<String> {
        if self.width == 0 || self.height == 0 {
            return Some(format!(
                "image size {} x {} must be positive",
                self.width, self.height
            ));
        }
        let scalars = [self.fx, self.fy, self.cx, self.cy, self.k1, self.k2];
        if !self.position.is_finite()
            || !self.world_to_camera.is_finite()
            || scalars.iter().any(|v| !v.is_finite())
        {
            return Some(
                "camera has a non-finite value (NaN or infinity) in its pose or intrinsics".into(),
            );
        }
        if !(self.fx > 0.0 && self.fy > 0.0) {
            return Some(format!(
                "focal lengths must be positive, got fx {} fy {}",
                self.fx, self.fy
            ));
        }
        let r = self.world_to_camera;
        let err = (r * r.transpose() - DMat3::IDENTITY)
            .to_cols_array()
            .iter()
            .fold(0.0f64, |m, v| m.max(v.abs()));
        if err > 1e-6 || (r.determinant() - 1.0).abs() > 1e-6 {
            return Some(format!(
                "rotation is not orthonormal with determinant +1 (max |R·Rᵀ − I| = {err:.3e}, det = {:.6})",
                r.determinant()
            ));
        }
        if self.k1 != 0.0 || self.k2 != 0.0 {
            let f_fold = super::undistort::Radial::new(self.k1, self.k2).fold_radius();
            let edge = self.nearest_edge_radius();
            if f_fold < edge {
                return Some(format!(
                    "radial distortion k1 {} k2 {} folds at {:.0} % of the distance from the \
                     principal point to the nearest image edge: the model has no ray for most \
                     of the image",
                    self.k1,
                    self.k2,
                    100.0 * f_fold / edge
                ));
            }
        }
        None
    }

    /// The largest normalized distorted radius the radial model gives a ray (its fold;
    /// infinite when the model increases everywhere): pixels farther from the principal
    /// point (in `((u − cx)/fx, (v − cy)/fy)`) have none.
    pub fn fold_radius(&self) -> f64 {
        super::undistort::Radial::new(self.k1, self.k2).fold_radius()
    }

    /// Normalized distorted radius of the image edge nearest the principal point (pixel
    /// edges: the centres of the outer pixels plus half a pixel).
    fn nearest_edge_radius(&self) -> f64 {
        let x = (self.cx + 0.5).min(self.width as f64 - 0.5 - self.cx) / self.fx;
        let y = (self.cy + 0.5).min(self.height as f64 - 0.5 - self.cy) / self.fy;
        x.min(y).max(0.0)
    }

    /// The share of the image's pixels (sampled on a grid of at most 256 × 256 pixel
    /// centres) whose distorted radius lies beyond the radial model's fold: pixels the model
    /// gives no ray (0 for a model that increases over the whole image).
    pub fn rayless_share(&self) -> f64 {
        let f_fold = super::undistort::Radial::new(self.k1, self.k2).fold_radius();
        if !f_fold.is_finite() {
            return 0.0;
        }
        let (nu, nv) = (self.width.min(256), self.height.min(256));
        let mut beyond = 0u64;
        for j in 0..nv {
            let v = (j as f64 + 0.5) * self.height as f64 / nv as f64 - 0.5;
            for i in 0..nu {
                let u = (i as f64 + 0.5) * self.width as f64 / nu as f64 - 0.5;
                let r = ((u - self.cx) / self.fx).hypot((v - self.cy) / self.fy);
                beyond += (r > f_fold) as u64;
            }
        }
        beyond as f64 / (nu as f64 * nv as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{rotation_from_yaw_pitch_roll, rotation_look_at};

    #[test]
    fn angles_round_trip() {
        for &(y, p, r) in &[
            (0.3, 0.1, -0.02),
            (3.8262, 0.1011, -0.0132),
            (-2.0, -1.2, 0.5),
            (1.0, 0.0, 3.0),
        ] {
            let m = rotation_from_yaw_pitch_roll(y, p, r);
            let (y2, p2, r2) = yaw_pitch_roll_from_rotation(&m);
            let m2 = rotation_from_yaw_pitch_roll(y2, p2, r2);
            assert!(
                (m - m2).to_cols_array().iter().all(|v| v.abs() < 1e-12),
                "{y} {p} {r}"
            );
            assert!((p - p2).abs() < 1e-12);
        }
        let down = rotation_look_at(DVec3::ZERO, DVec3::new(0.0, 0.0, -1.0)).unwrap();
        let (y, p, r) = yaw_pitch_roll_from_rotation(&down);
        let again = rotation_from_yaw_pitch_roll(y, p, r);
        assert!(
            (down - again)
                .to_cols_array()
                .iter()
                .all(|v| v.abs() < 1e-12)
        );
    }

    #[test]
    fn undistort_inverts_project_and_problems_are_found() {
        let r = rotation_look_at(DVec3::ZERO, DVec3::new(1.0, 0.2, 0.1)).unwrap();
        let mut c = CameraModel::with_fov(DVec3::new(1.0, 2.0, 3.0), r, 400, 300, 1.0);
        c.k1 = -0.12;
        c.k2 = 0.03;
        assert_eq!(c.problem(), None);
        for &(u, v) in &[(0.0, 0.0), (399.0, 299.0), (200.0, 10.0), (c.cx, c.cy)] {
            let d = c.pixel_ray(u, v).unwrap();
            let p = c.project(c.position + 50.0 * d).unwrap();
            assert!(
                (p[0] - u).abs() < 1e-6 && (p[1] - v).abs() < 1e-6,
                "{u} {v} -> {p:?}"
            );
        }
        let mut bad = c;
        bad.k1 = -2.0;
        assert!(bad.problem().unwrap().contains("folds"));
        assert!(bad.rayless_share() > 0.5);
        // folding only in the corners: accepted, with the corners' share without a ray
        let mut corners = c;
        corners.k1 = -0.4;
        assert_eq!(corners.problem(), None);
        let share = corners.rayless_share();
        assert!(share > 0.0 && share < 0.3, "{share}");
        assert!(corners.pixel_ray(0.0, 0.0).is_none());
        assert!(corners.pixel_ray(c.cx, 10.0).is_some());
        assert_eq!(c.rayless_share(), 0.0);
        bad = c;
        bad.fx = 0.0;
        assert!(bad.problem().unwrap().contains("focal"));
        bad = c;
        bad.cy = f64::NAN;
        assert!(bad.problem().unwrap().contains("non-finite"));
        bad = c;
        bad.world_to_camera *= 1.01;
        assert!(bad.problem().unwrap().contains("orthonormal"));
        bad = c;
        bad.height = 0;
        assert!(bad.problem().unwrap().contains("size"));
    }
}
