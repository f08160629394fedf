//! View frustum planes and box tests.

use glam::{DMat4, DVec3, DVec4};

/// Five planes (left, right, bottom, top, near) with inward unit normals, in the frame of the
/// matrix they were extracted from. A point `p` is inside when `n·p + d ≥ 0` for all planes.
/// The far plane is at infinity (reverse-Z).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frustum {
    /// `(n.x, n.y, n.z, d)` per plane, `|n| = 1`.
    pub planes: [DVec4; 5],
}

impl Frustum {
    /// Extracts the planes of a reverse-Z clip transform `m` (clip x, y ∈ [−w, w], depth z ≤ w).
    pub fn from_view_proj(m: &DMat4) -> Frustum {
        let (r0, r1, r2, r3) = (m.row(0), m.row(1), m.row(2), m.row(3));
        let norm = |p: DVec4| {
            let l = p.truncate().length();
            if l > 0.0 { p / l } else { p }
        };
        Frustum {
            planes: [
                norm(r3 + r0),
                norm(r3 - r0),
                norm(r3 + r1),
                norm(r3 - r1),
                norm(r3 - r2),
            ],
        }
    }

    /// True if the axis-aligned box `[min, max]` may intersect the frustum (conservative:
    /// boxes outside one plane are rejected, a few boxes near corners are kept).
    pub fn intersects_aabb(&self, min: DVec3, max: DVec3) -> bool {
        self.planes.iter().all(|p| {
            let v = DVec3::new(
                if p.x >= 0.0 { max.x } else { min.x },
                if p.y >= 0.0 { max.y } else { min.y },
                if p.z >= 0.0 { max.z } else { min.z },
            );
            p.truncate().dot(v) + p.w >= 0.0
        })
    }

    /// True if `p` is inside all planes.
    pub fn contains_point(&self, p: DVec3) -> bool {
        self.planes
            .iter()
            .all(|pl| pl.truncate().dot(p) + pl.w >= 0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::super::RenderCamera;
    use crate::camera::{CameraModel, rotation_look_at};
    use glam::DVec3;

    #[test]
    fn boxes_in_front_behind_and_aside() {
        let r = rotation_look_at(DVec3::ZERO, DVec3::X).unwrap();
        let cam = RenderCamera::new(CameraModel::with_fov(DVec3::ZERO, r, 100, 100, 1.0), 0.5);
        let f = cam.frustum();
        let b = |c: [f64; 3], h: f64| (DVec3::from(c) - h, DVec3::from(c) + h);
        let inside = |(a, c): (DVec3, DVec3)| f.intersects_aabb(a, c);
        assert!(inside(b([10.0, 0.0, 0.0], 1.0)));
        assert!(!inside(b([-10.0, 0.0, 0.0], 1.0)));
        assert!(!inside(b([10.0, 30.0, 0.0], 1.0)));
        assert!(!inside(b([10.0, 0.0, -30.0], 1.0)));
        assert!(inside(b([10.0, 6.0, 0.0], 1.0))); // straddles the left edge (tan 0.5 * 10 ≈ 5.46)
        assert!(!inside(b([0.2, 0.0, 0.0], 0.1))); // before the near plane
        assert!(f.contains_point(DVec3::new(1e6, 0.0, 0.0)));
    }
}
