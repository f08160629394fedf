//! Geomorphing (CPU side): per-vertex morph targets on the parent cell's surface, the per-draw
//! morph factor from screen-space errors, and the texture mip shift towards the parent.
//!
//! A drawn cell `c` with parent `p` is blended towards `p`'s shape: the vertex shader moves each
//! vertex from its own height `z` to the target `z_p` (the parent's surface height at the
//! vertex's x, y, see [`morph_targets`]) by the factor `t` of [`morph_factor`], and the fragment
//! shader blends the cell's colour and normal samples by `t` towards the parent's textures,
//! sampled at the parent's texture coordinates of the same surface point (interpolated per
//! vertex by [`morph_targets`]). If the parent's textures are not resident, the cell's own
//! textures are sampled at a level of detail up to `t · shift` coarser instead, where they are
//! finer than the parent's (see [`mip_shift`]). `t = 1` exactly when the parent's screen-space error
//! reaches the refinement threshold, i.e. at the moment the LOD selection switches between `p`
//! and its children, so the switch shows (up to the differences of the two triangulations)
//! the same surface on both sides; `t = 0` from `band ×` the threshold on, and always before
//! the cell's own children take over.

use glam::DVec3;

use crate::cells::CellMesh;

/// Geomorphing settings of a scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GeomorphOptions {
    /// Morph cells towards their parents (off: every cell is drawn as stored).
    pub enabled: bool,
    /// Width of the morph band as a ratio of screen-space errors (> 1): a cell is fully morphed
    /// when its parent's error equals the threshold and unmorphed from `band ×` the threshold
    /// on (by distance: over the farther half of the range where the cell is selected, for 2).
    pub band: f64,
}

impl Default for GeomorphOptions {
    fn default() -> Self {
        GeomorphOptions {
            enabled: false,
            band: 2.0,
        }
    }
}

/// Morph factor in [0, 1] of a drawn cell (0 = its own shape, 1 = its parent's).
///
/// `parent_ratio` is the parent's screen-space error divided by the threshold (≥ 1 whenever
/// the cell is selected); `own_ratio` the cell's own ratio if it has children (`None` for a
/// leaf). With `x = ln max(parent_ratio, 1)`, `b = ln band`, shortened to `x − ln own_ratio`
/// if that is smaller (so the morph is over before the cell's children would replace it),
/// the factor is `clamp(1 − x / b, 0, 1)`: linear in log screen-space error (log distance),
/// 1 at the switch from the parent, 0 from `band` on. Non-finite ratios (the camera inside a
/// bounding box) give 0, as does `band ≤ 1`.
pub fn morph_factor(parent_ratio: f64, own_ratio: Option<f64>, band: f64) -> f32 {
    if !(band > 1.0 && band.is_finite()) || parent_ratio.is_nan() || parent_ratio == f64::INFINITY {
        return 0.0;
    }
    let x = parent_ratio.max(1.0).ln();
    let mut b = band.ln();
    if let Some(o) = own_ratio {
        if o.is_nan() || o == f64::INFINITY {
            // Camera inside the cell's box: it would be refined.
            return 0.0;
        }
        if o > 0.0 {
            b = b.min(x - o.ln());
        }
    }
    if b <= 0.0 {
        return 0.0;
    }
    (1.0 - x / b).clamp(0.0, 1.0) as f32
}

/// LOD shift (mip levels, ≥ 0) between a cell's texture and its parent's over the same ground:
/// `log2((texels_c / width_c) / (texels_p / width_p))` — 1 when the parent has as many texels
/// over twice the width (the store's layout). Non-finite or non-positive inputs give 0.
pub fn mip_shift(
    child_texels: u32,
    child_width: f64,
    parent_texels: u32,
    parent_width: f64,
) -> f32 {
    let (tc, tp) = (child_texels as f64, parent_texels as f64);
    let r = (tc / child_width.abs()) / (tp / parent_width.abs());
    if r.is_finite() && r > 1.0 {
        r.log2() as f32
    } else {
        0.0
    }
}

/// Heights of a triangulated height field (a cell surface), found by point location on a
/// uniform grid over the triangles' x, y bounding boxes.
#[derive(Clone, Debug)]
pub struct SurfaceLocator {
    tris: Vec<[DVec3; 3]>,
    /// Vertex indices of `tris`.
    idx: Vec<[u32; 3]>,
    bins: Vec<Vec<u32>>,
    n: usize,
    min: [f64; 2],
    step: [f64; 2],
}

impl SurfaceLocator {
    /// Indexes the triangles `triangles` over `positions` (any frame; indices out of range and
    /// triangles without area in x, y are skipped).
    pub fn new(positions: &[DVec3], triangles: &[[u32; 3]]) -> SurfaceLocator {
        let idx: Vec<[u32; 3]> = triangles
            .iter()
            .filter(|t| t.iter().all(|&k| (k as usize) < positions.len()))
            .filter(|t| {
                let p = t.map(|k| positions[k as usize]);
                cross2(p[1] - p[0], p[2] - p[0]).abs() > 0.0
            })
            .copied()
            .collect();
        let tris: Vec<[DVec3; 3]> = idx
            .iter()
            .map(|t| t.map(|k| positions[k as usize]))
            .collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in tris.iter().flatten() {
            lo = [lo[0].min(p.x), lo[1].min(p.y)];
            hi = [hi[0].max(p.x), hi[1].max(p.y)];
        }
        let n = ((tris.len() as f64 / 2.0).sqrt().ceil() as usize).clamp(1, 256);
        let step = if tris.is_empty() {
            [1.0, 1.0]
        } else {
            [
                ((hi[0] - lo[0]) / n as f64).max(1e-12),
                ((hi[1] - lo[1]) / n as f64).max(1e-12),
            ]
        };
        let mut s = SurfaceLocator {
            tris: Vec::new(),
            idx,
            bins: vec![Vec::new(); n * n],
            n,
            min: lo,
            step,
        };
        for (k, t) in tris.iter().enumerate() {
            let (bx0, by0) = s.bin(
                t.iter().map(|p| p.x).fold(f64::INFINITY, f64::min),
                t.iter().map(|p| p.y).fold(f64::INFINITY, f64::min),
            );
            let (bx1, by1) = s.bin(
                t.iter().map(|p| p.x).fold(f64::NEG_INFINITY, f64::max),
                t.iter().map(|p| p.y).fold(f64::NEG_INFINITY, f64::max),
            );
            for by in by0..=by1 {
                for bx in bx0..=bx1 {
                    s.bins[by * n + bx].push(k as u32);
                }
            }
        }
        s.tris = tris;
        s
    }

    fn bin(&self, x: f64, y: f64) -> (usize, usize) {
        let f = |v: f64, k: usize| {
            let i = ((v - self.min[k]) / self.step[k]).floor();
            if i.is_nan() {
                0
            } else {
                (i.max(0.0) as usize).min(self.n - 1)
            }
        };
        (f(x, 0), f(y, 1))
    }

    /// Internal triangle index and barycentric weights of the point (see [`Self::locate`]).
    fn locate_internal(&self, x: f64, y: f64) -> Option<(usize, [f64; 3])> {
        if self.tris.is_empty() || !(x.is_finite() && y.is_finite()) {
            return None;
        }
        let (bx, by) = self.bin(x, y);
        for &k in &self.bins[by * self.n + bx] {
            let b = barycentric(&self.tris[k as usize], x, y);
            if b.iter().all(|&w| w >= -1e-9) {
                return Some((k as usize, b));
            }
        }
        // Outside (rounding at the border, or beyond it): nearest point of the nearest triangle.
        let q = glam::DVec2::new(x, y);
        let mut best = (f64::INFINITY, 0usize, [1.0, 0.0, 0.0]);
        for (k, t) in self.tris.iter().enumerate() {
            let (d2, w) = nearest_on_triangle(t, q);
            if d2 < best.0 {
                best = (d2, k, w);
            }
        }
        Some((best.1, best.2))
    }

    /// The triangle (its vertex indices) containing `(x, y)` and the point's barycentric
    /// weights in it (tolerance 1e-9); outside every triangle, the nearest point of the nearest
    /// triangle (weights ≥ 0). `None` without triangles or for non-finite input.
    pub fn locate(&self, x: f64, y: f64) -> Option<([u32; 3], [f64; 3])> {
        self.locate_internal(x, y).map(|(k, w)| (self.idx[k], w))
    }

    /// Height of the surface at `(x, y)`: linear interpolation in the triangle containing the
    /// point; outside every triangle, the height at the nearest point of the nearest triangle
    /// (see [`SurfaceLocator::locate`]). `None` without triangles or for non-finite input.
    pub fn height_at(&self, x: f64, y: f64) -> Option<f64> {
        let (k, w) = self.locate_internal(x, y)?;
        let t = &self.tris[k];
        Some(w[0] * t[0].z + w[1] * t[1].z + w[2] * t[2].z)
    }
}

fn cross2(a: DVec3, b: DVec3) -> f64 {
    a.x * b.y - a.y * b.x
}

fn barycentric(t: &[DVec3; 3], x: f64, y: f64) -> [f64; 3] {
    let p = DVec3::new(x, y, 0.0);
    let area = cross2(t[1] - t[0], t[2] - t[0]);
    let w0 = cross2(t[1] - p, t[2] - p) / area;
    let w1 = cross2(t[2] - p, t[0] - p) / area;
    [w0, w1, 1.0 - w0 - w1]
}

/// Squared x, y distance from `q` to triangle `t` and the barycentric weights (≥ 0) of the
/// nearest point.
fn nearest_on_triangle(t: &[DVec3; 3], q: glam::DVec2) -> (f64, [f64; 3]) {
    let b = barycentric(t, q.x, q.y);
    if b.iter().all(|&w| w >= 0.0) {
        return (0.0, b);
    }
    let mut best = (f64::INFINITY, [1.0, 0.0, 0.0]);
    for k in 0..3 {
        let (a2, c2) = (t[k].truncate(), t[(k + 1) % 3].truncate());
        let e = c2 - a2;
        let s = if e.length_squared() > 0.0 {
            ((q - a2).dot(e) / e.length_squared()).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let d2 = (a2 + e * s - q).length_squared();
        if d2 < best.0 {
            let mut w = [0.0; 3];
            w[k] = 1.0 - s;
            w[(k + 1) % 3] = s;
            best = (d2, w);
        }
    }
    best
}

/// Morph targets of every vertex of `child` (cell-local f32 around `child_origin`), as
/// `[z, u, v]`: the height of `parent`'s surface (its surface triangles, cell-local around
/// `parent_origin`) at the vertex's world x, y, in the child's local frame, and the parent's
/// texture coordinates there (`parent_uvs[k]` of parent vertex `k`, interpolated linearly in
/// the parent triangle). Offsets between the frames are taken in f64. Skirt vertices (after
/// `surface_vertices`) hang `parent_skirt` metres below the target of the surface vertex at
/// the same x, y (the parent's skirt depth, so at `t = 1` the skirts match the parent's; their
/// own drop if `parent_skirt` is not a positive number) and take its texture coordinates; a
/// skirt vertex without a surface vertex, or any vertex when the parent has no surface, keeps
/// its own height (and gets uv (0, 0)).
pub fn morph_targets(
    child_origin: DVec3,
    child: &CellMesh,
    parent_origin: DVec3,
    parent: &CellMesh,
    parent_uvs: &[[f32; 2]],
    parent_skirt: f64,
) -> Vec<[f32; 3]> {
    let ns_p = (parent.surface_vertices as usize).min(parent.positions.len());
    let pos: Vec<DVec3> = parent.positions[..ns_p]
        .iter()
        .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
        .collect();
    let loc = SurfaceLocator::new(&pos, parent.surface());
    let uv_of = |k: u32| parent_uvs.get(k as usize).copied().unwrap_or([0.0, 0.0]);
    let off = child_origin - parent_origin;
    let ns = (child.surface_vertices as usize).min(child.positions.len());
    let mut out: Vec<[f32; 3]> = child.positions[..ns]
        .iter()
        .map(|p| {
            let q = DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64) + off;
            match loc.locate_internal(q.x, q.y) {
                Some((k, w)) => {
                    let (t, i) = (&loc.tris[k], loc.idx[k]);
                    let h = w[0] * t[0].z + w[1] * t[1].z + w[2] * t[2].z;
                    let uv = [0, 1].map(|c| {
                        (w[0] * uv_of(i[0])[c] as f64
                            + w[1] * uv_of(i[1])[c] as f64
                            + w[2] * uv_of(i[2])[c] as f64) as f32
                    });
                    [(h - off.z) as f32, uv[0], uv[1]]
                }
                None => [p[2], 0.0, 0.0],
            }
        })
        .collect();
    let key = |p: &[f32; 3]| (p[0].to_bits(), p[1].to_bits());
    let surface: std::collections::HashMap<(u32, u32), usize> = child.positions[..ns]
        .iter()
        .enumerate()
        .map(|(i, p)| (key(p), i))
        .collect();
    for p in &child.positions[ns..] {
        out.push(match surface.get(&key(p)) {
            Some(&j) => {
                let drop = if parent_skirt > 0.0 && parent_skirt.is_finite() {
                    parent_skirt as f32
                } else {
                    child.positions[j][2] - p[2]
                };
                [out[j][0] - drop, out[j][1], out[j][2]]
            }
            None => [p[2], 0.0, 0.0],
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morph_factor_is_one_at_the_switch_and_zero_from_the_band_on() {
        let band = 2.0;
        assert_eq!(morph_factor(1.0, None, band), 1.0);
        assert_eq!(
            morph_factor(0.7, None, band),
            1.0,
            "below the threshold: parent shape"
        );
        assert_eq!(morph_factor(2.0, None, band), 0.0);
        assert_eq!(morph_factor(5.0, None, band), 0.0);
        // Linear in log ratio: half-way at sqrt(band).
        assert!((morph_factor(2f64.sqrt(), None, band) - 0.5).abs() < 1e-6);
        // Monotone non-increasing in the parent's ratio.
        let mut last = 1.0;
        for i in 0..=100 {
            let t = morph_factor(1.0 + i as f64 * 0.02, Some(0.3), band);
            assert!(t <= last + 1e-7 && (0.0..=1.0).contains(&t));
            last = t;
        }
        // The morph ends before the cell's own children take over: own ratio 1 gives 0 ...
        assert_eq!(morph_factor(1.3, Some(1.0), band), 0.0);
        // ... and a short interval shrinks the band: parent 1.2, own 0.8 → b = ln 1.5.
        let t = morph_factor(1.2, Some(0.8), band) as f64;
        assert!((t - (1.0 - 1.2f64.ln() / 1.5f64.ln())).abs() < 1e-6, "{t}");
        // Non-finite errors (camera inside a box) and a degenerate band: no morph.
        assert_eq!(morph_factor(f64::INFINITY, None, band), 0.0);
        assert_eq!(morph_factor(1.0, Some(f64::INFINITY), band), 0.0);
        assert_eq!(morph_factor(f64::NAN, None, band), 0.0);
        assert_eq!(morph_factor(1.0, None, 1.0), 0.0);
    }

    #[test]
    fn mip_shift_of_the_store_layout_is_one_level() {
        assert!((mip_shift(64, 50.0, 64, 100.0) - 1.0).abs() < 1e-6);
        assert!((mip_shift(128, 50.0, 64, 100.0) - 2.0).abs() < 1e-6);
        assert_eq!(mip_shift(32, 50.0, 64, 100.0), 0.0);
        assert_eq!(mip_shift(0, 50.0, 64, 100.0), 0.0);
        assert_eq!(mip_shift(64, 0.0, 64, 100.0), 0.0);
    }

    /// A parent "tent" over [-50, 50]²: four triangles around an apex at (0, 0, 10), corners 0.
    fn tent() -> CellMesh {
        CellMesh {
            positions: vec![
                [-50.0, 50.0, 0.0],
                [50.0, 50.0, 0.0],
                [50.0, -50.0, 0.0],
                [-50.0, -50.0, 0.0],
                [0.0, 0.0, 10.0],
            ],
            uvs: None,
            triangles: vec![[0, 4, 1], [1, 4, 2], [2, 4, 3], [3, 4, 0]],
            surface_vertices: 5,
            surface_triangles: 4,
        }
    }

    fn tent_height(x: f64, y: f64) -> f64 {
        10.0 * (1.0 - x.abs().max(y.abs()) / 50.0)
    }

    #[test]
    fn targets_lie_on_the_parent_surface_and_skirts_keep_their_drop() {
        // Parent origin at UTM magnitudes; the child is its NE quadrant, with its own origin
        // (centre of the quadrant, 3 m higher) and a 5×5 grid of vertices at heights 100 + i.
        let parent_origin = DVec3::new(500_050.0, 7_000_050.0, 200.0);
        let child_origin = parent_origin + DVec3::new(25.0, 25.0, 3.0);
        let mut positions = Vec::new();
        for j in 0..5 {
            for i in 0..5 {
                positions.push([
                    -25.0 + 12.5 * i as f32,
                    -25.0 + 12.5 * j as f32,
                    (100 + i) as f32,
                ]);
            }
        }
        let mut triangles = Vec::new();
        for j in 0..4u32 {
            for i in 0..4u32 {
                let a = j * 5 + i;
                triangles.push([a, a + 1, a + 6]);
                triangles.push([a, a + 6, a + 5]);
            }
        }
        // Skirt: the west border lowered by 2 m, plus one stray vertex with no border partner.
        let ns = positions.len() as u32;
        for j in 0..5 {
            let p = positions[j * 5];
            positions.push([p[0], p[1], p[2] - 2.0]);
        }
        positions.push([3.3, 3.3, -7.0]);
        let child = CellMesh {
            positions: positions.clone(),
            uvs: None,
            triangles,
            surface_vertices: ns,
            surface_triangles: 32,
        };
        // Parent texture coordinates: ortho over its square (u east, v south).
        let uvs: Vec<[f32; 2]> = tent()
            .positions
            .iter()
            .map(|p| [(p[0] + 50.0) / 100.0, (50.0 - p[1]) / 100.0])
            .collect();
        let t = morph_targets(child_origin, &child, parent_origin, &tent(), &uvs, 4.5);
        assert_eq!(t.len(), positions.len());
        for (k, p) in positions[..ns as usize].iter().enumerate() {
            let (x, y) = (p[0] as f64 + 25.0, p[1] as f64 + 25.0);
            let want = tent_height(x, y) - 3.0;
            assert!(
                (t[k][0] as f64 - want).abs() < 1e-4,
                "vertex {k} at ({x}, {y}): {:?} vs {want}",
                t[k]
            );
            // Ortho coordinates are affine in x, y: interpolation reproduces them exactly.
            let (u, v) = ((x + 50.0) / 100.0, (50.0 - y) / 100.0);
            assert!(
                (t[k][1] as f64 - u).abs() < 1e-6 && (t[k][2] as f64 - v).abs() < 1e-6,
                "uv of {k}"
            );
        }
        for j in 0..5 {
            let (s, b) = (ns as usize + j, j * 5);
            assert!(
                (t[s][0] - (t[b][0] - 4.5)).abs() < 1e-5,
                "skirt {j} hangs the parent's depth below its border vertex"
            );
            assert_eq!((t[s][1], t[s][2]), (t[b][1], t[b][2]));
        }
        assert_eq!(
            t[t.len() - 1][0],
            -7.0,
            "a skirt vertex without a border vertex is not moved"
        );
        // Without a parent skirt depth the skirt keeps its own drop.
        let t = morph_targets(child_origin, &child, parent_origin, &tent(), &uvs, 0.0);
        assert!((t[ns as usize][0] - (t[0][0] - 2.0)).abs() < 1e-5);
    }

    #[test]
    fn points_outside_the_surface_take_the_nearest_height() {
        let pos: Vec<DVec3> = tent()
            .positions
            .iter()
            .map(|p| DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64))
            .collect();
        let loc = SurfaceLocator::new(&pos, &tent().triangles);
        assert!((loc.height_at(0.0, 0.0).unwrap() - 10.0).abs() < 1e-12);
        assert!((loc.height_at(25.0, -10.0).unwrap() - 5.0).abs() < 1e-12);
        // Just outside the east edge at y = 0: the edge's height there (0).
        assert!(loc.height_at(50.0 + 1e-7, 0.0).unwrap().abs() < 1e-9);
        assert!((loc.height_at(60.0, 0.0).unwrap()).abs() < 1e-9);
        assert!(loc.height_at(f64::NAN, 0.0).is_none());
        assert!(SurfaceLocator::new(&pos, &[]).height_at(0.0, 0.0).is_none());
    }
}
