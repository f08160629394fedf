//! Camera-space binning of a scene's triangles: exact nearest hits for the rays of one
//! camera centre, without a tree traversal.
//!
//! Every ray of a photo starts at the camera centre, so a triangle can only be hit by rays
//! whose direction lies in the triangle's central projection. The grid covers the photo's
//! rays on the undistorted image plane (`x = c.x / c.z`, `y = c.y / c.z` in the camera frame)
//! with square bins of [`ViewGridParams::bin_px`] pixels (at the larger focal length).
//! Each triangle, clipped to camera depths `z ≥` [`Z_NEAR`], is entered into every bin its
//! projected bounding box (widened by a small margin) overlaps, with its smallest camera
//! depth `z_min`; bins list their triangles by increasing `z_min`. A ray tests the
//! triangles of its bin in that order with the same intersection routine as the BVH
//! ([`obvhs::triangle::Triangle::intersect`]) and stops once `z_min` exceeds the depth of its
//! best hit: no triangle further down the list can be nearer. The result is the nearest hit
//! of the ray among all triangles, as the BVH gives (up to the choice between triangles hit
//! at the same distance, e.g. on a shared edge), except for hits closer than [`Z_NEAR`] in
//! camera depth, which are ignored. Rays outside the grid (not produced by the photo's
//! pixel corners) are answered by testing every triangle. Up to four rays of one bin can be
//! tested together, one SIMD lane each ([`ViewGrid::nearest_packet`]), with the same hits.

use glam::{BVec4A, DMat3, DVec3, Vec3, Vec3A, Vec4};
use obvhs::triangle::Triangle;
use rayon::prelude::*;

use super::TriHit;
use super::triangle::PreTri;
use crate::camera::{CameraModel, RayCaster};

/// Triangle parts closer than this camera depth (metres) are not entered into the grid.
pub const Z_NEAR: f64 = 1e-3;

/// Most bins of one grid (a guard against degenerate cameras; bins grow to stay below it).
const MAX_BINS: f64 = 8.0e6;

/// Settings of the camera-space grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewGridParams {
    /// Side of a bin in photo pixels (at the larger focal length, on the undistorted image
    /// plane). Smaller bins hold fewer triangles per ray but enter large triangles into more
    /// bins; default 8 (docs/projection.md, "Ray casting").
    pub bin_px: f32,
}

impl Default for ViewGridParams {
    fn default() -> Self {
        ViewGridParams { bin_px: 8.0 }
    }
}

/// One grid entry: a triangle and the smallest camera depth of its clipped part.
#[derive(Clone, Copy, Debug)]
struct Entry {
    z_min: f32,
    tri: u32,
}

/// Triangles binned by their central projection for one camera centre (see module docs).
pub struct ViewGrid {
    /// `tris` prepared for rays from the grid's origin.
    pre: Vec<PreTri>,
    /// World (= scene frame) to camera rotation.
    rot: DMat3,
    /// The optical axis (scene frame), enlarged by 1e-5 so that `t · (fwd · dir)` bounds the
    /// camera depth of a hit from above despite f32 rounding.
    fwd: Vec3A,
    /// Undistorted-plane position of bin (0, 0)'s corner, and bins per unit.
    x0: f64,
    y0: f64,
    scale: f64,
    nx: usize,
    ny: usize,
    /// `nx` and `ny` as floats (for the bin lookup of every ray).
    nx_f: f64,
    ny_f: f64,
    /// CSR: entries of bin `b` are `entries[starts[b]..starts[b + 1]]`.
    starts: Vec<u32>,
    entries: Vec<Entry>,
}

/// Grid statistics (for benchmarks).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ViewGridStats {
    /// Bins along x and y.
    pub bins: [usize; 2],
    /// Triangle entries over all bins.
    pub entries: usize,
    /// Triangles entered at least once.
    pub triangles_binned: usize,
}

impl ViewGrid {
    /// Bins the triangles of `scene` for the pixel-corner rays of `camera` (its centre must
    /// be where the rays start; the scene's frame origin is usually at it).
    pub fn for_camera(
        scene: &super::LevelScene,
        camera: &CameraModel,
        params: ViewGridParams,
    ) -> ViewGrid {
        let origin = (camera.position - scene.frame_origin).as_vec3();
        ViewGrid::build(
            scene.triangles(),
            camera,
            &camera.ray_caster(),
            origin,
            params,
        )
    }

    /// Bins `tris` (scene frame, camera centre at `origin`) for the rays of `camera`'s pixel
    /// corners.
    pub(crate) fn build(
        tris: &[Triangle],
        camera: &CameraModel,
        rays: &RayCaster,
        origin: Vec3,
        params: ViewGridParams,
    ) -> ViewGrid {
        let rot = camera.world_to_camera;
        let o = Vec3A::from(origin);
        let pre = tris.par_iter().map(|t| PreTri::new(t, o)).collect();
        let fwd = Vec3A::from((rot.row(2) * (1.0 + 1e-5)).as_vec3());
        let mut grid = ViewGrid {
            pre,
            rot,
            fwd,
            x0: 0.0,
            y0: 0.0,
            scale: 0.0,
            nx: 0,
            ny: 0,
            nx_f: 0.0,
            ny_f: 0.0,
            starts: vec![0],
            entries: Vec::new(),
        };
        let Some([xmin, ymin, xmax, ymax]) = ray_bounds(camera, rays) else {
            return grid;
        };
        let f = camera.fx.abs().max(camera.fy.abs());
        let bin_px = if params.bin_px.is_finite() && params.bin_px > 0.0 {
            params.bin_px as f64
        } else {
            8.0
        };
        let mut scale = f / bin_px; // bins per unit of the undistorted plane
        // One bin of margin on every side.
        let (w, h) = (xmax - xmin, ymax - ymin);
        while (w * scale + 2.0) * (h * scale + 2.0) > MAX_BINS {
            scale *= 0.5;
        }
        if !(scale.is_finite() && scale > 0.0) {
            return grid;
        }
        grid.scale = scale;
        grid.x0 = xmin - 1.0 / scale;
        grid.y0 = ymin - 1.0 / scale;
        grid.nx = ((w * scale).ceil() as usize + 2).max(1);
        grid.ny = ((h * scale).ceil() as usize + 2).max(1);
        (grid.nx_f, grid.ny_f) = (grid.nx as f64, grid.ny as f64);

        // Per triangle: its bin rectangle and z_min (parallel, in order).
        let (gx, gy, nx, ny) = (grid.x0, grid.y0, grid.nx, grid.ny);
        let rects: Vec<Option<([u32; 4], f32)>> = tris
            .par_iter()
            .map(|t| {
                let v = [t.v0, t.v1, t.v2]
                    .map(|p| rot * (Vec3::from(p).as_dvec3() - origin.as_dvec3()));
                let (bb, z_min) = projected_bounds(&v)?;
                let to_bin = |x: f64, o: f64, n: usize| {
                    ((x - o) * scale).floor().clamp(0.0, n as f64 - 1.0) as u32
                };
                let (bx0, bx1) = (to_bin(bb[0], gx, nx), to_bin(bb[2], gx, nx));
                let (by0, by1) = (to_bin(bb[1], gy, ny), to_bin(bb[3], gy, ny));
                // Entirely outside the grid: no pixel-corner ray can hit it.
                if bb[2] < gx
                    || bb[0] > gx + nx as f64 / scale
                    || bb[3] < gy
                    || bb[1] > gy + ny as f64 / scale
                {
                    return None;
                }
                // Round z_min down so f32 storage never exceeds the true bound.
                let z = (z_min * (1.0 - 1e-6) - 1e-6) as f32;
                Some(([bx0, by0, bx1, by1], z))
            })
            .collect();
        // Insert in increasing (z_min, triangle) order, so every bin is sorted.
        let mut order: Vec<u32> = (0..tris.len() as u32)
            .filter(|&i| rects[i as usize].is_some())
            .collect();
        order.par_sort_unstable_by(|&a, &b| {
            let (za, zb) = (
                rects[a as usize].map_or(0.0, |r| r.1),
                rects[b as usize].map_or(0.0, |r| r.1),
            );
            za.total_cmp(&zb).then(a.cmp(&b))
        });
        let mut counts = vec![0u32; nx * ny + 1];
        for &i in &order {
            let ([x0, y0, x1, y1], _) = rects[i as usize].unwrap_or(([1, 1, 0, 0], 0.0));
            for y in y0..=y1 {
                let row = y as usize * nx;
                for x in x0..=x1 {
                    counts[row + x as usize + 1] += 1;
                }
            }
        }
        for b in 1..counts.len() {
            counts[b] += counts[b - 1];
        }
        let total = counts[nx * ny] as usize;
        let mut entries = vec![Entry { z_min: 0.0, tri: 0 }; total];
        let mut fill = counts.clone();
        for &i in &order {
            let Some(([x0, y0, x1, y1], z)) = rects[i as usize] else {
                continue;
            };
            for y in y0..=y1 {
                let row = y as usize * nx;
                for x in x0..=x1 {
                    let slot = &mut fill[row + x as usize];
                    entries[*slot as usize] = Entry { z_min: z, tri: i };
                    *slot += 1;
                }
            }
        }
        grid.starts = counts;
        grid.entries = entries;
        grid
    }

    /// Bin counts and entries.
    pub fn stats(&self) -> ViewGridStats {
        let mut seen = vec![false; self.pre.len()];
        for e in &self.entries {
            seen[e.tri as usize] = true;
        }
        ViewGridStats {
            bins: [self.nx, self.ny],
            entries: self.entries.len(),
            triangles_binned: seen.iter().filter(|&&s| s).count(),
        }
    }

    /// The nearest hit of the ray `origin + t·dir` (`origin` = the camera centre the grid was
    /// built for, `dir` a unit vector, scene frame), both faces, `t ≥ 0`.
    pub fn nearest(&self, origin: Vec3, dir: Vec3) -> Option<TriHit> {
        let c = self.rot * dir.as_dvec3();
        let xy = if c.z > 0.0 {
            [c.x / c.z, c.y / c.z]
        } else {
            [f64::NAN; 2]
        };
        self.nearest_at(origin, dir, xy)
    }

    /// [`ViewGrid::nearest`] for a ray whose point on the undistorted image plane is known
    /// (`xy`; NaN if it points backwards).
    #[inline]
    pub(crate) fn nearest_at(&self, origin: Vec3, dir: Vec3, xy: [f64; 2]) -> Option<TriHit> {
        if !(origin.is_finite() && dir.is_finite()) || dir == Vec3::ZERO {
            return None;
        }
        let d = Vec3A::from(dir + Vec3::ZERO);
        let (mut best_t, mut best, mut best_uv) = (f32::INFINITY, u32::MAX, [0.0f32; 2]);
        let mut test = |i: u32, tmax: &mut f32| {
            let (t, uv) = self.pre[i as usize].intersect(d, *tmax);
            if t < *tmax {
                *tmax = t;
                best = i;
                best_uv = uv;
            }
        };
        match self.bin_of(xy[0], xy[1]) {
            Some(b) => {
                // Camera depth of the point at distance t is t·cz (dir is a unit vector).
                let cz = self.fwd.dot(d);
                let (s, e) = (self.starts[b] as usize, self.starts[b + 1] as usize);
                for en in &self.entries[s..e] {
                    if en.z_min > best_t * cz {
                        break;
                    }
                    test(en.tri, &mut best_t);
                }
            }
            None => {
                for i in 0..self.pre.len() as u32 {
                    test(i, &mut best_t);
                }
            }
        }
        if !best_t.is_finite() {
            return None;
        }
        Some(TriHit {
            triangle: best,
            t: best_t,
            bary: PreTri::barycentric(best_uv),
        })
    }

    /// The bin of the undistorted-plane point `xy`, if inside the grid.
    #[inline]
    pub(crate) fn bin_at(&self, xy: [f64; 2]) -> Option<usize> {
        self.bin_of(xy[0], xy[1])
    }

    /// [`ViewGrid::nearest_at`] for up to four rays whose plane points all lie in bin `bin`
    /// (`dirs`: finite non-zero unit vectors, scene frame), one SIMD lane per ray: every
    /// lane does the scalar test's arithmetic in the same order and scans the bin's list
    /// with the same stopping rule, so each `out[k]` equals `nearest_at` of ray `k`.
    pub(crate) fn nearest_packet(&self, bin: usize, dirs: &[Vec3], out: &mut [Option<TriHit>]) {
        let n = dirs.len().min(out.len()).min(4);
        if n == 0 {
            return;
        }
        let d: [Vec3; 4] = std::array::from_fn(|k| dirs[k.min(n - 1)] + Vec3::ZERO);
        let (dx, dy, dz) = (
            Vec4::new(d[0].x, d[1].x, d[2].x, d[3].x),
            Vec4::new(d[0].y, d[1].y, d[2].y, d[3].y),
            Vec4::new(d[0].z, d[1].z, d[2].z, d[3].z),
        );
        let sp = Vec4::splat;
        // dot products as glam's SSE2 `Vec3A::dot`: (x·x' + y·y') + z·z'
        let cz = (sp(self.fwd.x) * dx + sp(self.fwd.y) * dy) + sp(self.fwd.z) * dz;
        let mut live = BVec4A::from_array([true, n > 1, n > 2, n > 3]);
        let (mut best_t, mut best_u, mut best_v) = (Vec4::INFINITY, Vec4::ZERO, Vec4::ZERO);
        let mut best = [u32::MAX; 4];
        let (s, e) = (self.starts[bin] as usize, self.starts[bin + 1] as usize);
        for en in &self.entries[s..e] {
            live &= !sp(en.z_min).cmpgt(best_t * cz);
            if !live.any() {
                break;
            }
            let p = &self.pre[en.tri as usize];
            let (c, e1, e2, nn) = (p.c, p.e1, p.e2, p.n);
            // r = d × c as glam's SSE2 `Vec3A::cross` (no fused multiply-add)
            let rx = dy * sp(c.z) - dz * sp(c.y);
            let ry = dz * sp(c.x) - dx * sp(c.z);
            let rz = dx * sp(c.y) - dy * sp(c.x);
            let det = (sp(nn.x) * dx + sp(nn.y) * dy) + sp(nn.z) * dz;
            let a = (rx * sp(e2.x) + ry * sp(e2.y)) + rz * sp(e2.z);
            let b = (rx * sp(e1.x) + ry * sp(e1.y)) + rz * sp(e1.z);
            let dneg = det.is_negative_mask();
            let cand = live & !((a.is_negative_mask() ^ dneg) | (b.is_negative_mask() ^ dneg));
            if !cand.any() {
                continue;
            }
            let inv = Vec4::ONE / det;
            let (u, v) = (a * inv, b * inv);
            let w = (Vec4::ONE - u) - v;
            let inside = !(u.is_negative_mask() | v.is_negative_mask() | w.is_negative_mask())
                & inv.cmpne(Vec4::ZERO);
            let t = sp(p.nc) * inv;
            let take = cand & inside & t.cmpge(Vec4::ZERO) & t.cmplt(best_t);
            if take.any() {
                best_t = Vec4::select(take, t, best_t);
                best_u = Vec4::select(take, u, best_u);
                best_v = Vec4::select(take, v, best_v);
                for (k, b) in best.iter_mut().enumerate() {
                    if take.test(k) {
                        *b = en.tri;
                    }
                }
            }
        }
        let (t, u, v) = (best_t.to_array(), best_u.to_array(), best_v.to_array());
        for k in 0..n {
            out[k] = t[k].is_finite().then(|| TriHit {
                triangle: best[k],
                t: t[k],
                bary: PreTri::barycentric([u[k], v[k]]),
            });
        }
    }

    fn bin_of(&self, x: f64, y: f64) -> Option<usize> {
        let bx = (x - self.x0) * self.scale;
        let by = (y - self.y0) * self.scale;
        if !((bx >= 0.0) & (by >= 0.0) & (bx < self.nx_f) & (by < self.ny_f)) {
            return None;
        }
        // (signed conversions: one instruction each on x86-64)
        Some(by as i64 as usize * self.nx + bx as i64 as usize)
    }
}

/// Bounding box `[xmin, ymin, xmax, ymax]` on the undistorted image plane of the rays of
/// the camera's pixel corners: the image border (every corner) and an interior lattice
/// (every 16th corner), so a distortion model whose extremes are not on the border is
/// covered too. `None` if no corner has a ray.
fn ray_bounds(camera: &CameraModel, rays: &RayCaster) -> Option<[f64; 4]> {
    let (w, h) = (camera.width as i64, camera.height as i64);
    let rot = camera.world_to_camera;
    let mut bb = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut add = |i: i64, j: i64| {
        if let Some(d) = rays.ray(i as f64 - 0.5, j as f64 - 0.5) {
            let c = rot * d;
            if c.z > 0.0 {
                let (x, y) = (c.x / c.z, c.y / c.z);
                bb = [bb[0].min(x), bb[1].min(y), bb[2].max(x), bb[3].max(y)];
            }
        }
    };
    for i in 0..=w {
        add(i, 0);
        add(i, h);
    }
    for j in 0..=h {
        add(0, j);
        add(w, j);
    }
    for j in (0..=h).step_by(16) {
        for i in (0..=w).step_by(16) {
            add(i, j);
        }
    }
    // A margin for the rays' f32 rounding.
    let m = 1e-6
        * (1.0
            + bb[0]
                .abs()
                .max(bb[2].abs())
                .max(bb[1].abs())
                .max(bb[3].abs()));
    (bb[0] <= bb[2] && bb[1] <= bb[3] && bb.iter().all(|v| v.is_finite()))
        .then(|| [bb[0] - m, bb[1] - m, bb[2] + m, bb[3] + m])
}

/// The projected bounding box (widened by a margin for the f32 hit test) and smallest
/// depth of the triangle's part at camera depths `z ≥ Z_NEAR`; `None` if nothing is left.
fn projected_bounds(v: &[DVec3; 3]) -> Option<([f64; 4], f64)> {
    if !v.iter().all(|p| p.is_finite()) {
        return None;
    }
    // Clip the triangle against z = Z_NEAR (at most 4 vertices).
    let mut poly = [DVec3::ZERO; 4];
    let mut n = 0;
    for k in 0..3 {
        let (a, b) = (v[k], v[(k + 1) % 3]);
        let (ina, inb) = (a.z >= Z_NEAR, b.z >= Z_NEAR);
        if ina {
            poly[n] = a;
            n += 1;
        }
        if ina != inb {
            let s = (Z_NEAR - a.z) / (b.z - a.z);
            let mut p = a + (b - a) * s;
            p.z = Z_NEAR;
            poly[n] = p;
            n += 1;
        }
    }
    if n < 3 {
        return None;
    }
    let mut bb = [
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    ];
    let mut z_min = f64::INFINITY;
    for p in &poly[..n] {
        let (x, y) = (p.x / p.z, p.y / p.z);
        bb = [bb[0].min(x), bb[1].min(y), bb[2].max(x), bb[3].max(y)];
        z_min = z_min.min(p.z);
    }
    // The f32 intersection test accepts rays a few ulps outside the triangle.
    let m = 1e-5
        * (1.0
            + bb[0]
                .abs()
                .max(bb[2].abs())
                .max(bb[1].abs())
                .max(bb[3].abs()));
    Some(([bb[0] - m, bb[1] - m, bb[2] + m, bb[3] + m], z_min))
}

/// `Vec3A` triangles from plain arrays (the BVH's and the grid's representation).
pub(crate) fn to_triangles(tris: &[[Vec3; 3]]) -> Vec<Triangle> {
    tris.iter()
        .map(|t| Triangle {
            v0: Vec3A::from(t[0]),
            v1: Vec3A::from(t[1]),
            v2: Vec3A::from(t[2]),
        })
        .collect()
}
