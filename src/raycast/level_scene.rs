//! The terrain of one quadtree level as one ray-castable triangle set.
//!
//! Every cell's surface triangles go into one f32 frame relative to `frame_origin`
//! (`cell origin − frame origin` in f64 first, then the cell-local offsets added in f64 and
//! the sum rounded to f32), so UTM-sized coordinates keep millimetre precision near the
//! camera. Per BVH triangle the scene keeps its cell, its local index, its plane (for the
//! facing test and view cosine) and its neighbours across each edge within its cell (for
//! the silhouette walk).

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use obvhs::triangle::Triangle;

use super::viewgrid::to_triangles;
use super::{RayAccel, TriangleBvh};
use crate::camera::CameraModel;
use crate::error::{Error, Result};
use crate::store::Store;

/// Marks "no triangle" in adjacency and lookups.
pub(crate) const NO_TRI: u32 = u32::MAX;

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

/// All cells of one level, as triangles in an f32 frame centred on `frame_origin`, with the
/// ray-casting acceleration chosen at construction (a BVH, or nothing until a photo's
/// camera-space grid is built by `crate::photo::photo_footprints`).
///
/// Triangles are one-sided for the photo stage: the front face is the one the vertices
/// run counter-clockwise around (seen from above for terrain). Triangles with an index
/// out of range of their cell's positions or texcoords are left out.
pub struct LevelScene {
    /// World position (f64) the BVH's f32 frame is relative to (near the camera).
    pub frame_origin: DVec3,
    /// The cells, in the order given.
    pub cells: Vec<SceneCell>,
    /// The acceleration chosen at construction.
    pub accel: RayAccel,
    /// Every cell's triangles in the frame (index = BVH triangle index).
    tris: Vec<Triangle>,
    /// BVH over `tris` (with [`RayAccel::Bvh`] only).
    bvh: Option<TriangleBvh>,
    /// Per BVH triangle: `[index into cells, local triangle index]`.
    tri_ref: Vec<[u32; 2]>,
    /// Per BVH triangle: what a hit needs, in one place (see [`TriInfo`]).
    info: Vec<TriInfo>,
    /// Per BVH triangle: the BVH triangle across edge k (`v[k] → v[k+1]`) in the same cell,
    /// or [`NO_TRI`].
    adjacency: Vec<[u32; 3]>,
    /// Per cell (index into `cells`), its relief map when projecting onto the relief surface
    /// ([`LevelScene::load_reliefs`]); empty: none.
    reliefs: Vec<Option<super::relief::CellRelief>>,
}

impl LevelScene {
    /// Builds the scene from in-memory cells (a BVH is built now with [`RayAccel::Bvh`]).
    pub fn new(
        cells: Vec<SceneCell>,
        frame_origin: DVec3,
        accel: impl Into<RayAccel>,
    ) -> LevelScene {
        let accel = accel.into();
        // Cells in parallel, concatenated in order.
        let parts: Vec<CellPart> = cells
            .par_iter()
            .enumerate()
            .map(|(ci, c)| cell_part(ci as u32, c, frame_origin))
            .collect();
        let total: usize = parts.iter().map(|p| p.tris.len()).sum();
        let (mut tris, mut tri_ref, mut info, mut adjacency) = (
            Vec::with_capacity(total),
            Vec::with_capacity(total),
            Vec::with_capacity(total),
            Vec::with_capacity(total),
        );
        for p in parts {
            let first = tris.len() as u32;
            tris.extend(p.tris);
            tri_ref.extend(p.tri_ref);
            info.extend(p.info);
            adjacency.extend(
                p.adjacency
                    .into_iter()
                    .map(|a| a.map(|n| if n == NO_TRI { NO_TRI } else { n + first })),
            );
        }
        let bvh = match accel {
            RayAccel::Bvh(q) => Some(TriangleBvh::build(&tris, q)),
            RayAccel::ViewGrid(_) => None,
        };
        let tris = to_triangles(&tris);
        LevelScene {
            frame_origin,
            cells,
            accel,
            tris,
            bvh,
            tri_ref,
            info,
            adjacency,
            reliefs: Vec::new(),
        }
    }

    /// Loads the relief maps of the cells whose active texture is orthographic from `store`,
    /// so that hits are moved onto the relief surface (`super::relief::CellRelief::shift`,
    /// slopes up to 75.5°, as the renderer). Reparameterized cells keep their TIN hits: the
    /// renderer leaves the photo's colour of their photo textures where it was projected and
    /// relief-maps only the chart texture's share (docs/rendering.md, "Photo charts by
    /// share"; projecting charts onto the relief surface put wall colour into ground
    /// texels). Cells without a relief map
    /// (stores built before 2026-12-06) keep their TIN hits too. Errors name a damaged file.
    pub fn load_reliefs(&mut self, store: &Store) -> Result<()> {
        let cells = &store.manifest.cells;
        let o = self.frame_origin;
        self.reliefs = self
            .cells
            .par_iter()
            .map(|c| {
                let Some(rec) = cells.get(c.cell as usize) else {
                    return Ok(None);
                };
                if rec.reparam.is_some() {
                    return Ok(None);
                }
                // the map's north-west corner in the scene's frame
                let corner = [rec.extent.min_x - o.x, rec.extent.max_y - o.y];
                let (w, h) = (rec.extent.width(), rec.extent.height());
                let min_z = crate::cells::relief::ORTHO_MIN_NORMAL_Z;
                Ok(store
                    .read_relief_map(rec)?
                    .and_then(|m| super::relief::CellRelief::new(&m, corner, w, h, min_z)))
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(())
    }

    /// The texel move (in the cell's texture) of the hit at barycentrics `bary` on BVH
    /// triangle `tri` by a ray along unit `dir`, from the TIN onto the cell's relief
    /// surface; `[0, 0]` where the cell has no relief map loaded or the triangle is left out.
    #[inline]
    pub(crate) fn relief_texel_shift(&self, tri: u32, bary: [f32; 3], dir: Vec3) -> [f32; 2] {
        const NONE: [f32; 2] = [0.0, 0.0];
        let info = &self.info[tri as usize];
        let Some(r) = self
            .reliefs
            .get(info.cell as usize)
            .and_then(|r| r.as_ref())
        else {
            return NONE;
        };
        let t = &self.tris[tri as usize];
        let v = [t.v0, t.v1, t.v2];
        let xy = [0, 1].map(|k| bary[0] * v[0][k] + bary[1] * v[1][k] + bary[2] * v[2][k]);
        let n = [info.plane[0], info.plane[1], info.plane[2]];
        let d = r.shift(xy, dir, n);
        if d == NONE {
            return NONE;
        }
        super::relief::texel_shift(v.map(|q| q.to_array()), info.tex, d).unwrap_or(NONE)
    }

    /// Builds the scene from the active meshes (reparameterized if present) of every cell of
    /// `level` in the store.
    pub fn from_store(
        store: &Store,
        level: u8,
        frame_origin: DVec3,
        accel: impl Into<RayAccel>,
    ) -> Result<LevelScene> {
        let levels = store.manifest.quadtree.levels;
        if u32::from(level) >= u32::from(levels) {
            return Err(Error::BadOption(format!(
                "level {level} is not in store {} (it has levels 0..{})",
                store.dir.display(),
                levels
            )));
        }
        if !frame_origin.is_finite() {
            return Err(Error::BadOption(format!(
                "frame origin {frame_origin} is not finite"
            )));
        }
        // Meshes are read and checked in parallel, collected in manifest order.
        let recs: Vec<(usize, &crate::store::CellRecord)> = store
            .manifest
            .cells
            .iter()
            .enumerate()
            .filter(|(_, r)| r.level == level)
            .collect();
        let cells = recs
            .into_par_iter()
            .map(|(index, rec)| scene_cell(store, index, rec))
            .collect::<Result<Vec<_>>>()?;
        Ok(LevelScene::new(cells, frame_origin, accel))
    }

    /// Per scene cell, the last pixel row of `camera`'s image that can hold a footprint on
    /// it (a pixel whose corner or centre ray hits the cell), or `None` when that is not
    /// bounded (a vertex not in front of the camera, an empty cell, non-finite values).
    ///
    /// The bound: the largest `y / z` of the cell's vertices in the camera frame (the
    /// pinhole projection of a triangle is the triangle of its corners' projections), turned
    /// into a distorted row with the largest (for `y ≥ 0`) or smallest (`y < 0`) radial
    /// factor over the image's undistorted radii, plus two rows (the pixel corners half a
    /// row away, a reconstructed corner's neighbour). Rows past the image mean every batch.
    pub fn last_rows(&self, camera: &CameraModel) -> Vec<Option<u32>> {
        let (w, h) = (camera.width as f64, camera.height as f64);
        // the radial factor's range over the image's undistorted radii
        let corners = [
            (-0.5, -0.5),
            (w - 0.5, -0.5),
            (-0.5, h - 0.5),
            (w - 0.5, h - 0.5),
        ];
        let mut r2max: f64 = 0.0;
        for (u, v) in corners {
            match camera.pixel_ray(u, v) {
                Some(d) => {
                    let c = camera.world_to_camera * d;
                    if !(c.z > 0.0) {
                        return vec![None; self.cells.len()];
                    }
                    r2max = r2max.max((c.x / c.z).powi(2) + (c.y / c.z).powi(2));
                }
                None => return vec![None; self.cells.len()],
            }
        }
        let factor = |r2: f64| 1.0 + camera.k1 * r2 + camera.k2 * r2 * r2;
        let mut at = vec![0.0, r2max];
        if camera.k2 != 0.0 {
            let stationary = -camera.k1 / (2.0 * camera.k2);
            if stationary > 0.0 && stationary < r2max {
                at.push(stationary);
            }
        }
        let (dmin, dmax) = at
            .iter()
            .map(|&r2| factor(r2))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), d| {
                (lo.min(d), hi.max(d))
            });
        self.cells
            .iter()
            .map(|c| {
                let mut ymax = f64::NEG_INFINITY;
                for p in &c.positions {
                    let world = c.origin + DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64);
                    let q = camera.to_camera(world);
                    if !(q.z > 0.0) {
                        return None;
                    }
                    ymax = ymax.max(q.y / q.z);
                }
                let d = if ymax >= 0.0 { dmax } else { dmin };
                let v = camera.fy * ymax * d + camera.cy;
                (v.is_finite() && d > 0.0).then(|| (v + 0.5).floor().clamp(0.0, h + 2.0) as u32 + 2)
            })
            .collect()
    }

    /// Number of triangles in the BVH.
    pub fn triangle_count(&self) -> usize {
        self.tri_ref.len()
    }

    /// The BVH (built with [`RayAccel::Bvh`] only).
    pub fn bvh(&self) -> Option<&TriangleBvh> {
        self.bvh.as_ref()
    }

    /// The scene's triangles (frame coordinates; index = BVH triangle index).
    pub(crate) fn triangles(&self) -> &[Triangle] {
        &self.tris
    }

    /// `(index into cells, local triangle index)` of BVH triangle `tri`.
    pub fn triangle_source(&self, tri: u32) -> Option<(usize, usize)> {
        self.tri_ref
            .get(tri as usize)
            .map(|r| (r[0] as usize, r[1] as usize))
    }

    /// Index into `cells` of BVH triangle `tri` (in range).
    #[inline]
    pub(crate) fn cell_of(&self, tri: u32) -> u32 {
        self.info[tri as usize].cell
    }

    /// Texture positions (texel units) of the three vertices of BVH triangle `tri`.
    #[inline]
    pub(crate) fn tri_texcoords(&self, tri: u32) -> [[f32; 2]; 3] {
        self.info[tri as usize].tex
    }

    /// Unit normal (frame) and plane offset of BVH triangle `tri`.
    #[inline]
    pub(crate) fn plane(&self, tri: u32) -> [f32; 4] {
        self.info[tri as usize].plane
    }

    /// Neighbours of BVH triangle `tri` across its edges (see the field).
    #[inline]
    pub(crate) fn neighbours(&self, tri: u32) -> [u32; 3] {
        self.adjacency[tri as usize]
    }
}

/// One cell's share of a scene (adjacency in cell-local triangle numbers).
struct CellPart {
    tris: Vec<[Vec3; 3]>,
    tri_ref: Vec<[u32; 2]>,
    info: Vec<TriInfo>,
    adjacency: Vec<[u32; 3]>,
}

/// The valid triangles of scene cell `ci`, in Morton order, in the frame at `frame_origin`.
fn cell_part(ci: u32, c: &SceneCell, frame_origin: DVec3) -> CellPart {
    let offset = c.origin - frame_origin;
    let local = |i: u32| {
        let p = c.positions[i as usize];
        offset + DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64)
    };
    let mut part = CellPart {
        tris: Vec::new(),
        tri_ref: Vec::new(),
        info: Vec::new(),
        adjacency: Vec::new(),
    };
    let mut kept: Vec<[u32; 3]> = Vec::new();
    for ti in morton_order(c) {
        let t = &c.triangles[ti];
        let p = [local(t[0]), local(t[1]), local(t[2])];
        if !p.iter().all(|q| q.is_finite()) {
            continue;
        }
        let normal = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        part.info.push(TriInfo {
            plane: [
                normal.x as f32,
                normal.y as f32,
                normal.z as f32,
                normal.dot(p[0]) as f32,
            ],
            tex: t.map(|i| c.texcoords[i as usize]),
            cell: ci,
        });
        part.tris.push(p.map(|q| q.as_vec3()));
        part.tri_ref.push([ci, ti as u32]);
        kept.push(*t);
    }
    part.adjacency = cell_adjacency(&kept);
    part
}

/// The active mesh of manifest cell `index` as a scene cell.
fn scene_cell(store: &Store, index: usize, rec: &crate::store::CellRecord) -> Result<SceneCell> {
    let mesh = store.read_active_mesh(rec)?;
    let texels = rec.reparam.as_ref().map_or(rec.texels, |r| r.texels);
    let nv = (mesh.surface_vertices as usize).min(mesh.positions.len());
    let tx = texels as f32;
    let texcoords = (0..nv)
        .map(|i| {
            let uv = crate::store::texcoord(rec, &mesh, i);
            [uv[0] * tx, uv[1] * tx]
        })
        .collect();
    Ok(SceneCell {
        cell: index as u32,
        origin: DVec3::from_array(rec.origin),
        positions: mesh.positions[..nv].to_vec(),
        triangles: mesh.surface().to_vec(),
        texcoords,
        texels,
    })
}

/// Per scene triangle, the data a hit and a silhouette walk read (kept together, so a hit
/// costs one cache line).
#[derive(Clone, Copy, Debug)]
struct TriInfo {
    /// Unit normal (frame) and plane offset `n·v0`.
    plane: [f32; 4],
    /// Texture positions (texel units) of the three vertices.
    tex: [[f32; 2]; 3],
    /// Index into the scene's cells.
    cell: u32,
}

/// The cell's valid triangles (vertex indices within its positions and texcoords), ordered
/// along a Morton curve of their centroids' x-y (ties by index), so that triangles near each
/// other on the ground are near each other in memory (the ray casts touch them together).
fn morton_order(c: &SceneCell) -> Vec<usize> {
    let n = c.positions.len().min(c.texcoords.len());
    let valid = |t: &[u32; 3]| t.iter().all(|&i| (i as usize) < n);
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for p in &c.positions[..n] {
        for k in 0..2 {
            if p[k].is_finite() {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    let scale = [0, 1].map(|k| {
        if hi[k] > lo[k] {
            65535.0 / (hi[k] - lo[k])
        } else {
            0.0
        }
    });
    let mut keyed: Vec<(u64, usize)> = c
        .triangles
        .iter()
        .enumerate()
        .filter(|(_, t)| valid(t))
        .map(|(ti, t)| {
            let q = [0, 1].map(|k| {
                let m = t.iter().map(|&i| c.positions[i as usize][k]).sum::<f32>() / 3.0;
                let v = ((m - lo[k]) * scale[k]).clamp(0.0, 65535.0);
                if v.is_finite() { v as u32 } else { 0 }
            });
            (interleave(q[0]) | interleave(q[1]) << 1, ti)
        })
        .collect();
    keyed.sort_unstable();
    keyed.into_iter().map(|(_, ti)| ti).collect()
}

/// Spreads the low 16 bits of `v` to the even bits.
fn interleave(v: u32) -> u64 {
    let mut x = u64::from(v & 0xffff);
    x = (x | (x << 8)) & 0x00ff_00ff;
    x = (x | (x << 4)) & 0x0f0f_0f0f;
    x = (x | (x << 2)) & 0x3333_3333;
    (x | (x << 1)) & 0x5555_5555
}

/// For each triangle, the triangle sharing edge k (`v[k] → v[k+1]`), or [`NO_TRI`] on the
/// boundary and at non-manifold edges (more than two triangles).
fn cell_adjacency(tris: &[[u32; 3]]) -> Vec<[u32; 3]> {
    let mut edges: Vec<(u32, u32, u32, u8)> = Vec::with_capacity(tris.len() * 3);
    for (ti, t) in tris.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a != b {
                edges.push((a.min(b), a.max(b), ti as u32, k as u8));
            }
        }
    }
    edges.sort_unstable();
    let mut adj = vec![[NO_TRI; 3]; tris.len()];
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && (edges[j].0, edges[j].1) == (edges[i].0, edges[i].1) {
            j += 1;
        }
        if j - i == 2 {
            let (x, y) = (edges[i], edges[i + 1]);
            adj[x.2 as usize][x.3 as usize] = y.2;
            adj[y.2 as usize][y.3 as usize] = x.2;
        }
        i = j;
    }
    adj
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adjacency_pairs_shared_edges_only() {
        // Two triangles sharing edge 1-2, a third sharing 0-1 with the first.
        let t = [[0, 1, 2], [2, 1, 3], [1, 0, 4]];
        let a = cell_adjacency(&t);
        assert_eq!(a[0], [2, 1, NO_TRI]);
        assert_eq!(a[1], [0, NO_TRI, NO_TRI]);
        assert_eq!(a[2], [0, NO_TRI, NO_TRI]);
        // A non-manifold edge gets no neighbour.
        let a = cell_adjacency(&[[0, 1, 2], [1, 0, 3], [0, 1, 4]]);
        assert_eq!(a[0][0], NO_TRI);
    }

    #[test]
    fn scene_frame_keeps_precision_and_skips_bad_triangles() {
        let cell = SceneCell {
            cell: 7,
            origin: DVec3::new(431_000.25, 6_878_000.5, 600.0),
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [1.0, 1.0, 0.0],
            ],
            triangles: vec![[0, 1, 2], [2, 1, 3], [0, 1, 9]],
            texcoords: vec![[0.0, 8.0], [8.0, 8.0], [0.0, 0.0], [8.0, 0.0]],
            texels: 8,
        };
        let s = LevelScene::new(
            vec![cell],
            DVec3::new(431_000.0, 6_878_000.0, 600.0),
            super::super::BvhQuality::Fast,
        );
        assert_eq!(s.triangle_count(), 2);
        // Triangles are stored in Morton order of their centroids: (0, 1, 2) first.
        assert_eq!(s.triangle_source(0), Some((0, 0)));
        assert_eq!(s.triangle_source(1), Some((0, 1)));
        assert_eq!(s.neighbours(0)[1], 1);
        let h = s
            .bvh()
            .unwrap()
            .nearest(Vec3::new(0.5, 0.75, 10.0), -Vec3::Z, 0.0, f32::INFINITY)
            .unwrap();
        assert_eq!(h.triangle, 0);
        assert!((h.t - 10.0).abs() < 1e-5);
        let p = s.plane(0);
        assert!((p[2] - 1.0).abs() < 1e-6 && p[3].abs() < 1e-6);
    }
}
