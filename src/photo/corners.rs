//! Pixel-corner rays: one nearest-hit ray per corner of the photo's pixel grid.
//!
//! Corner `(i, j)` (`i ∈ 0..=W`, `j ∈ 0..=H`) is at pixel position `(i − 0.5, j − 0.5)`
//! (pixel-centre convention), so pixel `(c, r)` has the corners `(c, r)`, `(c+1, r)`,
//! `(c+1, r+1)`, `(c, r+1)`. A corner hit is kept only on the front face of a triangle
//! (the surface is one-sided: a camera below the terrain sees nothing).

use glam::Vec3;

use super::accel::Caster;
use super::scene::{LevelScene, NO_TRI};
use crate::camera::{PlaneRay, RayCaster};

/// The compact result of one corner ray (24 bytes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct CornerHit {
    /// BVH triangle hit (front face), or [`NO_TRI`].
    pub tri: u32,
    /// Index into the scene's cells of that triangle (unspecified on a miss).
    pub cell: u32,
    /// Texture position (texel units of the hit cell's active texture).
    pub tex: [f32; 2],
    /// Distance from the camera centre, metres.
    pub t: f32,
    /// |cos| of the angle between the ray and the triangle normal.
    pub cos: f32,
}

impl CornerHit {
    /// No front-face hit.
    pub const MISS: CornerHit = CornerHit { tri: NO_TRI, cell: u32::MAX, tex: [0.0; 2], t: 0.0, cos: 0.0 };

    /// `true` if the ray hit a front face.
    #[inline]
    pub fn is_hit(&self) -> bool {
        self.tri != NO_TRI
    }
}

/// Casts the corner rays of corner row `j` (all `out.len()` = W + 1 columns) from `origin`
/// (camera centre in the scene's frame).
pub(crate) fn cast_corner_row(scene: &LevelScene, caster: &Caster, rays: &RayCaster, origin: Vec3, j: u32, out: &mut [CornerHit]) {
    rays.row_with(-0.5, j as f64 - 0.5, out.len(), |i, ray| {
        out[i] = ray.map_or(CornerHit::MISS, |r| cast_corner(scene, caster, origin, &r));
    });
}

fn cast_corner(scene: &LevelScene, caster: &Caster, origin: Vec3, ray: &PlaneRay) -> CornerHit {
    let dir = ray.dir.as_vec3();
    let Some(hit) = caster.nearest(origin, dir, ray.xy) else { return CornerHit::MISS };
    let p = scene.plane(hit.triangle);
    let cos = p[0] * dir.x + p[1] * dir.y + p[2] * dir.z;
    // Back face (or an edge-on / degenerate triangle): the surface is seen from below.
    if !(cos < 0.0) || !hit.t.is_finite() {
        return CornerHit::MISS;
    }
    let tc = scene.tri_texcoords(hit.triangle);
    let b = hit.bary;
    let tex = [
        b[0] * tc[0][0] + b[1] * tc[1][0] + b[2] * tc[2][0],
        b[0] * tc[0][1] + b[1] * tc[1][1] + b[2] * tc[2][1],
    ];
    if !(tex[0].is_finite() && tex[1].is_finite()) {
        return CornerHit::MISS;
    }
    CornerHit { tri: hit.triangle, cell: scene.cell_of(hit.triangle), tex, t: hit.t, cos: -cos }
}
