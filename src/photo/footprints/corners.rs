//! Pixel-corner rays: one nearest-hit ray per corner of the photo's pixel grid.
//!
//! Corner `(i, j)` (`i ∈ 0..=W`, `j ∈ 0..=H`) is at pixel position `(i − 0.5, j − 0.5)`
//! (pixel-centre convention), so pixel `(c, r)` has the corners `(c, r)`, `(c+1, r)`,
//! `(c+1, r+1)`, `(c, r+1)`. A corner hit is kept only on the front face of a triangle
//! (the surface is one-sided: a camera below the terrain sees nothing).

use glam::Vec3;

use crate::camera::{PlaneRay, RayCaster};
use crate::raycast::Caster;
use crate::raycast::TriHit;
use crate::raycast::ViewGrid;
use crate::raycast::{LevelScene, NO_TRI};

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
    pub const MISS: CornerHit = CornerHit {
        tri: NO_TRI,
        cell: u32::MAX,
        tex: [0.0; 2],
        t: 0.0,
        cos: 0.0,
    };

    /// `true` if the ray hit a front face.
    #[inline]
    pub fn is_hit(&self) -> bool {
        self.tri != NO_TRI
    }
}

/// Casts the corner rays of corner row `j` (all `out.len()` = W + 1 columns) from `origin`
/// (camera centre in the scene's frame). With the view grid, consecutive rays of one bin
/// are cast together ([`ViewGrid::nearest_packet`], the same hits as one by one).
pub(crate) fn cast_corner_row(
    scene: &LevelScene,
    caster: &Caster,
    rays: &RayCaster,
    origin: Vec3,
    j: u32,
    out: &mut [CornerHit],
) {
    let Caster::Grid(grid) = caster else {
        rays.row_with(-0.5, j as f64 - 0.5, out.len(), |i, ray| {
            out[i] = ray.map_or(CornerHit::MISS, |r| cast_corner(scene, caster, origin, &r));
        });
        return;
    };
    if !origin.is_finite() {
        out.fill(CornerHit::MISS);
        return;
    }
    let mut pk = Packet {
        scene,
        grid,
        bin: usize::MAX,
        n: 0,
        first: 0,
        dirs: [Vec3::ZERO; 4],
    };
    rays.row_with(-0.5, j as f64 - 0.5, out.len(), |i, ray| {
        let Some(r) = ray else {
            out[i] = CornerHit::MISS;
            return;
        };
        let dir = r.dir.as_vec3();
        let bin = if dir.is_finite() && dir != Vec3::ZERO {
            grid.bin_at(r.xy)
        } else {
            None
        };
        match bin {
            Some(b) => {
                if pk.n == 4 || (pk.n > 0 && (pk.bin != b || pk.first + pk.n != i)) {
                    pk.flush(out);
                }
                if pk.n == 0 {
                    (pk.bin, pk.first) = (b, i);
                }
                pk.dirs[pk.n] = dir;
                pk.n += 1;
            }
            None => out[i] = finish_hit(scene, dir, grid.nearest_at(origin, dir, r.xy)),
        }
    });
    pk.flush(out);
}

/// The corner ray `(i, j)` alone: the hit [`cast_corner_row`] gives it when the caster's
/// rays are independent of their row (`RayCaster::rays_independent`).
pub(crate) fn cast_corner_alone(
    scene: &LevelScene,
    caster: &Caster,
    rays: &RayCaster,
    origin: Vec3,
    i: u32,
    j: u32,
) -> CornerHit {
    let mut hit = CornerHit::MISS;
    rays.row_with(i as f64 - 0.5, j as f64 - 0.5, 1, |_, ray| {
        hit = ray.map_or(CornerHit::MISS, |r| cast_corner(scene, caster, origin, &r));
    });
    hit
}

/// Up to four consecutive rays of one row that fall into the same grid bin.
struct Packet<'a> {
    scene: &'a LevelScene,
    grid: &'a ViewGrid,
    bin: usize,
    n: usize,
    /// Column of the first ray.
    first: usize,
    dirs: [Vec3; 4],
}

impl Packet<'_> {
    /// Casts the pending rays into `out[first..first + n]` and empties the packet.
    fn flush(&mut self, out: &mut [CornerHit]) {
        if self.n == 0 {
            return;
        }
        let mut hits = [None; 4];
        self.grid
            .nearest_packet(self.bin, &self.dirs[..self.n], &mut hits[..self.n]);
        for k in 0..self.n {
            out[self.first + k] = finish_hit(self.scene, self.dirs[k], hits[k]);
        }
        self.n = 0;
    }
}

fn cast_corner(scene: &LevelScene, caster: &Caster, origin: Vec3, ray: &PlaneRay) -> CornerHit {
    let dir = ray.dir.as_vec3();
    finish_hit(scene, dir, caster.nearest(origin, dir, ray.xy))
}

/// The corner record of the nearest hit `hit` of the ray along `dir` (front faces only).
#[inline]
fn finish_hit(scene: &LevelScene, dir: Vec3, hit: Option<TriHit>) -> CornerHit {
    let Some(hit) = hit else {
        return CornerHit::MISS;
    };
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
    let cell = scene.cell_of(hit.triangle);
    let d = scene.relief_texel_shift(hit.triangle, b, dir);
    let tex = [tex[0] + d[0], tex[1] + d[1]];
    if !(tex[0].is_finite() && tex[1].is_finite()) {
        return CornerHit::MISS;
    }
    CornerHit {
        tri: hit.triangle,
        cell,
        tex,
        t: hit.t,
        cos: -cos,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{CameraModel, rotation_look_at};
    use crate::raycast::{RayAccel, SceneCell, ViewGridParams};
    use glam::DVec3;

    /// A bumpy heightfield with a steep ridge: many small triangles, occlusion, grazing rays.
    fn terrain() -> SceneCell {
        let n = 60u32;
        let mut positions = Vec::new();
        let mut texcoords = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f64, j as f64);
                let z = 2.0 * (0.3 * x).sin() * (0.2 * y).cos()
                    + 12.0 / (1.0 + ((y - 35.0) / 2.0).powi(2));
                positions.push([x as f32, y as f32, z as f32]);
                texcoords.push([x as f32, (n as f64 - y) as f32]);
            }
        }
        let v = |i: u32, j: u32| j * (n + 1) + i;
        let mut triangles = Vec::new();
        for j in 0..n {
            for i in 0..n {
                triangles.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                triangles.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
        SceneCell {
            cell: 0,
            origin: DVec3::new(431_000.0, 6_878_000.0, 500.0),
            positions,
            triangles,
            texcoords,
            texels: 64,
        }
    }

    #[test]
    fn packets_give_the_scalar_hits() {
        let cell = terrain();
        let o = cell.origin;
        let pos = o + DVec3::new(30.3, -8.0, 6.0);
        let mut cam = CameraModel::with_fov(
            pos,
            rotation_look_at(pos, o + DVec3::new(30.0, 40.0, 2.0)).unwrap(),
            160,
            120,
            1.2,
        );
        cam.k1 = -0.05;
        for bin_px in [8.0, 2.0, 33.0] {
            let scene = LevelScene::new(
                vec![cell.clone()],
                pos,
                RayAccel::ViewGrid(ViewGridParams { bin_px }),
            );
            let origin = (cam.position - scene.frame_origin).as_vec3();
            let rays = cam.ray_caster().with_table();
            let caster = Caster::Grid(ViewGrid::build(
                scene.triangles(),
                &cam,
                &rays,
                origin,
                ViewGridParams { bin_px },
            ));
            let (mut hits, mut packets) = (0, vec![CornerHit::MISS; 161]);
            for j in 0..=120 {
                cast_corner_row(&scene, &caster, &rays, origin, j, &mut packets);
                let mut single = vec![CornerHit::MISS; 161];
                rays.row_with(-0.5, j as f64 - 0.5, 161, |i, r| {
                    single[i] = r.map_or(CornerHit::MISS, |r| {
                        cast_corner(&scene, &caster, origin, &r)
                    });
                });
                for (a, b) in packets.iter().zip(&single) {
                    assert_eq!(
                        (
                            a.tri,
                            a.cell,
                            a.tex.map(f32::to_bits),
                            a.t.to_bits(),
                            a.cos.to_bits()
                        ),
                        (
                            b.tri,
                            b.cell,
                            b.tex.map(f32::to_bits),
                            b.t.to_bits(),
                            b.cos.to_bits()
                        ),
                        "row {j}"
                    );
                }
                hits += single.iter().filter(|h| h.is_hit()).count();
                // a corner cast alone (the halo rows of a band) gets the same hit
                for i in (0..=160u32).step_by(9) {
                    let (a, b) = (
                        cast_corner_alone(&scene, &caster, &rays, origin, i, j),
                        packets[i as usize],
                    );
                    assert_eq!(
                        (a.tri, a.tex.map(f32::to_bits), a.t.to_bits()),
                        (b.tri, b.tex.map(f32::to_bits), b.t.to_bits())
                    );
                }
            }
            assert!(hits > 5000, "the camera sees the terrain: {hits} hits");
        }
    }
}
