//! Silhouette test: does the straight texture-space segment between two points of one cell
//! cross an edge between a front-facing and a back-facing triangle?
//!
//! The walk starts in the triangle of the first point and steps, with the cell's mesh
//! adjacency, through the edge where the segment leaves the current triangle (in the
//! cell's texture space), until it reaches the target triangle, a triangle containing the
//! end point, the mesh boundary, or a texture-degenerate triangle (zero area in texture
//! space, e.g. a vertical wall under an orthographic parameterization). Only a facing
//! change met on the way counts as a silhouette; a walk that stops early is no evidence.

use glam::Vec3;

use super::level_scene::{LevelScene, NO_TRI};

/// Most triangles one walk visits (a pixel footprint spans a handful).
const MAX_STEPS: usize = 4096;

/// `true` if the camera at `cam` (scene frame) sees the front face of BVH triangle `tri`.
#[inline]
pub(crate) fn front_facing(scene: &LevelScene, cam: Vec3, tri: u32) -> bool {
    let p = scene.plane(tri);
    p[0] * cam.x + p[1] * cam.y + p[2] * cam.z > p[3]
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn f64x2(p: [f32; 2]) -> [f64; 2] {
    [p[0] as f64, p[1] as f64]
}

/// Walks from BVH triangle `from` (containing texture point `p`) towards texture point `q`
/// (in triangle `target`, or [`NO_TRI`] if unknown) and returns `true` if it crosses an
/// edge between triangles of different facing seen from `cam`.
pub(crate) fn crosses_silhouette(
    scene: &LevelScene,
    cam: Vec3,
    from: u32,
    p: [f32; 2],
    target: u32,
    q: [f32; 2],
) -> bool {
    let (p, q) = (f64x2(p), f64x2(q));
    let mut cur = from;
    let mut prev = NO_TRI;
    let mut cur_front = front_facing(scene, cam, cur);
    for _ in 0..MAX_STEPS {
        if cur == target {
            return false;
        }
        let tv = scene.tri_texcoords(cur).map(f64x2);
        let s = orient(tv[0], tv[1], tv[2]);
        if s == 0.0 || !s.is_finite() {
            return false;
        }
        let nb = scene.neighbours(cur);
        let mut next = None;
        for k in 0..3 {
            let (a, b) = (tv[k], tv[(k + 1) % 3]);
            if nb[k] == prev && prev != NO_TRI {
                continue;
            }
            // q strictly outside edge k, and the segment p→q meets the edge.
            if orient(a, b, q) * s < 0.0 && orient(p, q, a) * orient(p, q, b) <= 0.0 {
                next = Some(nb[k]);
                break;
            }
        }
        let Some(n) = next else { return false };
        if n == NO_TRI {
            return false;
        }
        let n_front = front_facing(scene, cam, n);
        if n_front != cur_front {
            return true;
        }
        prev = cur;
        cur = n;
        cur_front = n_front;
    }
    false
}
