//! Error-bounded TIN simplification of one cell by greedy insertion (Garland-Heckbert).
//!
//! The cell's border vertices (from [`super::border`]) are triangulated first; then the
//! worst sample of the triangle with the largest vertical error is inserted into that
//! triangle of a Delaunay triangulation ([`super::halfedge`], no point location), and the
//! triangles the insertion wrote are rescanned, until every sample is within epsilon.
//! Phase 1 uses the level's lattice (every stride-th sample); phase 2 rescans every
//! triangle against all full-resolution samples and continues with full-resolution
//! candidates, so the bound holds for every DEM sample of the cell. Work is in integer
//! grid coordinates, with exact predicates. Where the CPU has AVX2, rows are scanned four
//! samples at a time ([`super::scan_x4`]), with the same result bit for bit.

use super::border::{LevelBorders, border_error, check_epsilon, check_tree};
use super::face_heap::FaceHeap;
use super::halfedge::{MAX_COORD, Mesh};
use super::lattice_tiles::LatticeTiles;
use super::raster::{Lattice, Plane, for_each_span};
use super::{CellKey, Quadtree, SampleRect, Tin};
use crate::dem::Dem;
use crate::error::{Error, Result};
use rayon::prelude::*;

/// The error bound of `level`: `max_error_finest * 2^(finest - level)` (height units).
pub fn level_epsilon(tree: &Quadtree, level: u8, max_error_finest: f64) -> f64 {
    max_error_finest * (1u64 << tree.finest_level().saturating_sub(level)) as f64
}

/// The vertical distance of height `h` at lattice column index `i` from the plane
/// `base + step · i` of [`Plane::lattice_row`] (the error every scan uses).
#[inline(always)]
fn lattice_error(h: f32, (base, step): (f64, f64), i: usize) -> f64 {
    // i < 2^32 always (a DEM side is u32); u32 -> f64 is one cheap conversion
    (h as f64 - (base + step * (i as u32) as f64)).abs()
}

/// The worst lattice sample of a triangle that is not one of its corners:
/// `(error, col, row)`, or error -1 if the triangle holds no such sample. Corner heights
/// come from the full-resolution grid (corners need not be on the lattice).
#[inline(always)]
fn worst_sample(
    heights: &[f32],
    width: usize,
    p: [[i64; 2]; 3],
    grid: &LatticeTiles,
    simd: Lanes,
) -> (f64, i64, i64) {
    // corners from the compact copy when stored there (always at stride 1), else the DEM
    let hz = |q: [i64; 2]| {
        grid.get(q[0], q[1])
            .unwrap_or_else(|| heights[q[1] as usize * width + q[0] as usize]) as f64
    };
    // Twice the area in samples²: a triangle of area 1/2 (or 0) holds no sample but its
    // corners (Pick's theorem), the common case of a dense TIN
    let twice_area =
        (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[2][0] - p[0][0]) * (p[1][1] - p[0][1]);
    if twice_area.abs() <= 1 {
        return (-1.0, -1, -1);
    }
    let plane = Plane::new(p, [hz(p[0]), hz(p[1]), hz(p[2])]);
    if twice_area.abs() == 2 {
        // area 1: no interior sample and one more on the boundary (B = 4), the midpoint of
        // the edge whose both coordinate differences are even; its error as the scan
        // computes it (same plane, same expression)
        return lone_sample(p, &plane, grid);
    }
    #[cfg(target_arch = "x86_64")]
    if let Some(v3) = simd {
        return super::scan_x4::scan_triangle_x4(v3, p, &plane, grid);
    }
    let _ = simd;
    scan_triangle(p, &plane, grid)
}

/// The four-lane scan's token where the CPU has AVX2 (x86-64), else the scalar scan.
#[cfg(target_arch = "x86_64")]
type Lanes = Option<pulp::x86::V3>;
/// The four-lane scan's token where the CPU has AVX2 (x86-64), else the scalar scan.
#[cfg(not(target_arch = "x86_64"))]
type Lanes = Option<()>;

/// The four-lane scan's token if this CPU can run it and the environment variable
/// `CLIFFMAP_SCALAR_TIN` is unset (set, it selects the scalar scan, for benchmarks; the
/// TINs are the same either way).
fn detect_lanes() -> Lanes {
    static LANES: std::sync::OnceLock<Lanes> = std::sync::OnceLock::new();
    *LANES.get_or_init(|| {
        if std::env::var_os("CLIFFMAP_SCALAR_TIN").is_some() {
            return None;
        }
        #[cfg(target_arch = "x86_64")]
        {
            crate::cpu::v3()
        }
        #[cfg(not(target_arch = "x86_64"))]
        {
            None
        }
    })
}

/// [`worst_sample`] by scanning every lattice sample of the closed triangle `p` whose
/// heights the plane `plane` interpolates.
#[inline]
pub(super) fn scan_triangle(
    p: [[i64; 2]; 3],
    plane: &Plane,
    grid: &LatticeTiles,
) -> (f64, i64, i64) {
    let lat = &grid.lat;
    let (oc, s) = (lat.origin_c, lat.stride);
    let mut best = (-1.0f64, -1i64, -1i64);
    for_each_span(p, lat, |y, j, i0, i1| {
        let row = plane.lattice_row(y, oc, s);
        let corner_row = p.iter().any(|q| q[1] == y);
        let mut err = best.0;
        let mut found = usize::MAX;
        grid.for_row(j, i0, i1, |i, h| {
            let e = lattice_error(h, row, i);
            if e > err && !(corner_row && is_corner(p, oc + i as i64 * s, y)) {
                err = e;
                found = i;
            }
        });
        if found != usize::MAX {
            best = (err, oc + found as i64 * s, y);
        }
    });
    best
}

/// [`worst_sample`] of a triangle of area 1 (in samples²), whose only sample besides its
/// corners is the midpoint of one edge: that sample's error if it is a lattice sample
/// inside the lattice's bounds, as [`scan_triangle`] finds it (bit for bit).
#[inline]
fn lone_sample(p: [[i64; 2]; 3], plane: &Plane, grid: &LatticeTiles) -> (f64, i64, i64) {
    let none = (-1.0, -1, -1);
    let Some([x, y]) = (0..3).find_map(|k| {
        let (a, b) = (p[k], p[(k + 1) % 3]);
        ((b[0] - a[0]) % 2 == 0 && (b[1] - a[1]) % 2 == 0)
            .then(|| [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2])
    }) else {
        return none;
    };
    let lat = &grid.lat;
    let (oc, s) = (lat.origin_c, lat.stride);
    let inside = (lat.c_lo..=lat.c_hi).contains(&x) && (lat.r_lo..=lat.r_hi).contains(&y);
    if !inside || (x - oc).rem_euclid(s) != 0 || (y - lat.origin_r).rem_euclid(s) != 0 {
        return none;
    }
    let Some(h) = grid.get(x, y) else {
        return none;
    };
    let e = lattice_error(h, plane.lattice_row(y, oc, s), ((x - oc) / s) as usize);
    if e > -1.0 { (e, x, y) } else { none }
}

#[inline]
fn is_corner(p: [[i64; 2]; 3], x: i64, y: i64) -> bool {
    p.iter().any(|q| q[0] == x && q[1] == y)
}

/// Greedy refinement state: the triangulation and, per triangle slot, the triangle's worst
/// sample (candidate) and error; triangles whose error exceeds epsilon are in `heap`.
struct Greedy<'a> {
    heights: &'a [f32],
    width: usize,
    epsilon: f64,
    mesh: Mesh,
    /// Per triangle slot: worst non-corner sample `[col, row]` and the triangle's error.
    cand: Vec<([u32; 2], f64)>,
    heap: FaceHeap,
    dirty: Vec<u32>,
    /// The four-lane scan, where available.
    lanes: Lanes,
}

impl Greedy<'_> {
    #[inline(always)]
    fn rescan(&mut self, t: u32, lat: &LatticeTiles) {
        let idx = t as usize;
        if idx >= self.cand.len() {
            let n = self.mesh.num_triangles().max(idx + 1);
            self.cand.resize(n, ([0; 2], 0.0));
        }
        let p = self.mesh.corners(t);
        let (err, col, row) = worst_sample(self.heights, self.width, p, lat, self.lanes);
        self.cand[idx] = ([col as u32, row as u32], err.max(0.0));
        if err > self.epsilon {
            self.heap.set(t, Some(err));
        } else {
            self.heap.set(t, None);
        }
    }

    /// Rescans the triangles written since the last rescan.
    #[inline(always)]
    fn rescan_dirty(&mut self, lat: &LatticeTiles) {
        let mut dirty = std::mem::take(&mut self.dirty);
        self.mesh.take_dirty(&mut dirty);
        for &t in &dirty {
            self.rescan(t, lat);
        }
        self.dirty = dirty;
    }

    /// Scans every triangle, then inserts worst samples until all are within epsilon.
    fn refine(&mut self, lat: &LatticeTiles) {
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = self.lanes {
            // (the scans compiled for AVX2: the token is only handed out where it runs)
            return v3.vectorize(Refine(self, lat));
        }
        Refine(self, lat).run();
    }

    #[inline(always)]
    fn rescan_all(&mut self, lat: &LatticeTiles) {
        self.heap.clear();
        self.mesh.take_dirty(&mut self.dirty);
        for t in 0..self.mesh.num_triangles() as u32 {
            self.rescan(t, lat);
        }
    }

    #[inline(always)]
    fn run(&mut self, lat: &LatticeTiles) {
        while let Some((_, t)) = self.heap.peek() {
            // the candidate lies in the closed triangle and is not one of its corners
            self.mesh.insert(t, self.cand[t as usize].0);
            self.rescan_dirty(lat);
        }
    }
}

/// [`Greedy::refine`]'s work, as one call for [`pulp`]'s dispatch.
struct Refine<'g, 'h, 'l>(&'g mut Greedy<'h>, &'l LatticeTiles);

impl Refine<'_, '_, '_> {
    #[inline(always)]
    fn run(self) {
        let Refine(g, lat) = self;
        g.rescan_all(lat);
        g.run(lat);
    }
}

#[cfg(target_arch = "x86_64")]
impl pulp::NullaryFnOnce for Refine<'_, '_, '_> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        self.run()
    }
}

fn check_rect(dem: &Dem, rect: SampleRect) -> Result<()> {
    if !(rect.c0 < rect.c1
        && rect.r0 < rect.r1
        && (rect.c1 as usize) < dem.width
        && (rect.r1 as usize) < dem.height)
    {
        return Err(Error::BadOption(format!(
            "sample rectangle {rect:?} is empty or outside the {}x{} DEM",
            dem.width, dem.height
        )));
    }
    if rect.c1 >= MAX_COORD || rect.r1 >= MAX_COORD {
        return Err(Error::BadOption(format!(
            "sample rectangle {rect:?} reaches beyond {MAX_COORD} samples"
        )));
    }
    Ok(())
}

/// Simplifies the samples of `rect` into a TIN whose vertical distance to every
/// full-resolution DEM sample in `rect` is at most `epsilon` (height units), provided the
/// border polylines are within `epsilon` (as [`LevelBorders`] and
/// [`super::simplify_rect_border`] guarantee). `border` lists boundary samples `[col, row]` that
/// must be vertices (points off the rectangle's boundary are ignored; the four corners are
/// always added); the interior is refined on the `stride` lattice anchored at
/// `(rect.c0, rect.r0)`, then at full resolution. [`Tin::max_error`] is the measured
/// maximum over all samples of `rect`. Triangles are CCW in world (x east, y north).
/// Errors on an empty or out-of-DEM rectangle (or one reaching 2^30 samples), stride 0, or a negative / non-finite epsilon.
/// Deterministic.
pub fn build_tin(
    dem: &Dem,
    rect: SampleRect,
    stride: u32,
    epsilon: f64,
    border: &[[u32; 2]],
) -> Result<Tin> {
    check_rect(dem, rect)?;
    check_epsilon(epsilon)?;
    if stride == 0 {
        return Err(Error::BadOption("TIN lattice stride must be >= 1".into()));
    }
    Ok(greedy_tin(
        dem,
        rect,
        stride,
        epsilon,
        border,
        false,
        detect_lanes(),
    ))
}

/// [`build_tin`] after its checks. With `refine_boundary`, the rectangle's boundary
/// samples are candidates too (inserted greedily like interior ones, splitting a boundary
/// edge), so `border` needs only the corners and the bound covers the boundary itself.
/// `lanes`: the four-lane scan's token, or `None` for the scalar scan (the same TIN).
fn greedy_tin(
    dem: &Dem,
    rect: SampleRect,
    stride: u32,
    epsilon: f64,
    border: &[[u32; 2]],
    refine_boundary: bool,
    lanes: Lanes,
) -> Tin {
    let on_boundary = |v: &[u32; 2]| {
        let (c, r) = (v[0], v[1]);
        (rect.c0..=rect.c1).contains(&c)
            && (rect.r0..=rect.r1).contains(&r)
            && (c == rect.c0 || c == rect.c1 || r == rect.r0 || r == rect.r1)
    };
    let mut pts: Vec<[u32; 2]> = border.iter().copied().filter(on_boundary).collect();
    pts.extend([
        [rect.c0, rect.r0],
        [rect.c1, rect.r0],
        [rect.c1, rect.r1],
        [rect.c0, rect.r1],
    ]);
    pts.sort_unstable_by_key(|v| (v[1], v[0]));
    pts.dedup();
    let mut g = Greedy {
        heights: &dem.heights,
        width: dem.width,
        epsilon,
        mesh: Mesh::rectangle(rect, &pts),
        cand: Vec::with_capacity(super::halfedge::reserved_triangles(rect)),
        heap: FaceHeap::with_capacity(super::halfedge::reserved_triangles(rect)),
        dirty: Vec::new(),
        lanes,
    };
    let inner = if refine_boundary { 0 } else { 1 };
    let interior = |s: u32| Lattice {
        origin_c: rect.c0 as i64,
        origin_r: rect.r0 as i64,
        stride: s as i64,
        c_lo: rect.c0 as i64 + inner,
        c_hi: rect.c1 as i64 - inner,
        r_lo: rect.r0 as i64 + inner,
        r_hi: rect.r1 as i64 - inner,
    };
    let coarse = LatticeTiles::new(
        &dem.heights,
        dem.width,
        interior(stride),
        rect.c1 as i64,
        rect.r1 as i64,
    );
    g.refine(&coarse);
    drop(coarse);
    if stride > 1 {
        let fine = LatticeTiles::new(
            &dem.heights,
            dem.width,
            interior(1),
            rect.c1 as i64,
            rect.r1 as i64,
        );
        g.refine(&fine);
    }
    let interior_err = g.cand.iter().map(|c| c.1).fold(0.0f64, f64::max);
    // with `refine_boundary` the scanned lattice holds every sample of `rect`
    let max_error = if refine_boundary {
        interior_err
    } else {
        interior_err.max(border_error(dem, rect, &pts))
    };
    let triangles = (0..g.mesh.num_triangles() as u32)
        .map(|t| g.mesh.triangle(t))
        .collect();
    Tin {
        vertices: g.mesh.vertices().to_vec(),
        triangles,
        max_error,
    }
}

/// One TIN over the whole DEM within `epsilon` (height units) of every sample, the DEM's
/// outer edge included. As Delatin, it starts from the four corners and refines the outer
/// edge greedily with the interior (a boundary sample is a candidate like any other).
/// Deterministic. Errors on a negative or non-finite epsilon.
pub fn build_dem_tin(dem: &Dem, epsilon: f64) -> Result<Tin> {
    check_epsilon(epsilon)?;
    let rect = SampleRect {
        c0: 0,
        r0: 0,
        c1: dem.width as u32 - 1,
        r1: dem.height as u32 - 1,
    };
    check_rect(dem, rect)?;
    // as Delatin: start from the four corners and refine the outer edge greedily with the
    // interior (pre-inserting a simplified outer edge instead makes long slivers across
    // the whole DEM, which the first insertions rescan again and again)
    Ok(greedy_tin(dem, rect, 1, epsilon, &[], true, detect_lanes()))
}

/// TINs of every cell of `level`, in [`Quadtree::cells`] order, each within
/// [`level_epsilon`]`(tree, level, max_error_finest)` of every full-resolution sample of
/// its clipped rectangle, and crack-free with its neighbours (shared sides have identical
/// vertices). Cells run in parallel; the output does not depend on the thread count.
pub fn build_level(
    dem: &Dem,
    tree: &Quadtree,
    level: u8,
    max_error_finest: f64,
) -> Result<Vec<(CellKey, Tin)>> {
    check_tree(dem, tree, level)?;
    check_epsilon(max_error_finest)?;
    let eps = level_epsilon(tree, level, max_error_finest);
    let borders = LevelBorders::compute(dem, tree, level, eps)?;
    let stride = tree.stride(level);
    tree.cells(level)
        .into_par_iter()
        .map(|key| {
            let rect = tree
                .clipped(key)
                .ok_or_else(|| Error::BadOption(format!("cell {} has no samples", key.id())))?;
            Ok((
                key,
                build_tin(dem, rect, stride, eps, &borders.cell_border(key))?,
            ))
        })
        .collect()
}

/// Largest vertical distance from any full-resolution sample of `rect` to `tin` (height
/// units), measured by scanning every triangle. Infinity if the TIN does not cover every
/// sample of `rect` or references a vertex outside the DEM.
pub fn measure_max_error(dem: &Dem, rect: SampleRect, tin: &Tin) -> f64 {
    if check_rect(dem, rect).is_err() {
        return f64::INFINITY;
    }
    let (w, h) = (
        (rect.c1 - rect.c0 + 1) as usize,
        (rect.r1 - rect.r0 + 1) as usize,
    );
    let mut covered = vec![false; w * h];
    let lat = Lattice {
        origin_c: 0,
        origin_r: 0,
        stride: 1,
        c_lo: rect.c0 as i64,
        c_hi: rect.c1 as i64,
        r_lo: rect.r0 as i64,
        r_hi: rect.r1 as i64,
    };
    let mut worst = 0.0f64;
    for t in &tin.triangles {
        let mut p = [[0i64; 2]; 3];
        let mut hz = [0.0; 3];
        for k in 0..3 {
            let Some(v) = tin.vertices.get(t[k] as usize) else {
                return f64::INFINITY;
            };
            if v[0] as usize >= dem.width || v[1] as usize >= dem.height {
                return f64::INFINITY;
            }
            p[k] = [v[0] as i64, v[1] as i64];
            hz[k] = dem.at(v[1] as usize, v[0] as usize) as f64;
        }
        let plane = Plane::new(p, hz);
        for_each_span(p, &lat, |y, _, x0, x1| {
            let (base, a) = plane.row(y);
            for x in x0 as i64..=x1 as i64 {
                let e = (dem.at(y as usize, x as usize) as f64 - (base + a * x as f64)).abs();
                worst = worst.max(e);
                covered[(y - rect.r0 as i64) as usize * w + (x - rect.c0 as i64) as usize] = true;
            }
        });
    }
    if covered.iter().all(|&c| c) {
        worst
    } else {
        f64::INFINITY
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn four_lane_and_scalar_scans_build_the_same_tins() {
        // a rough random DEM (plateaus of equal heights give ties): whole-DEM TINs and
        // cell TINs on a stride-2 lattice, bit for bit the same with either scan
        let Some(lanes) = detect_lanes() else {
            return;
        };
        let (w, h) = (97usize, 83usize);
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let heights: Vec<f32> = (0..w * h)
            .map(|k| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
                let (c, r) = ((k % w) as f32, (k / w) as f32);
                if c < 15.0 {
                    7.0
                } else {
                    (c * 0.3).sin() * 9.0 + r * 0.2 + (state >> 40) as f32 * 2e-7
                }
            })
            .collect();
        let dem = Dem::from_heights(w, h, heights, crate::georef::GridGeoref::new(0.0, 0.0, 1.0))
            .expect("dem");
        let whole = SampleRect {
            c0: 0,
            r0: 0,
            c1: w as u32 - 1,
            r1: h as u32 - 1,
        };
        let cell = SampleRect {
            c0: 8,
            r0: 4,
            c1: 72,
            r1: 68,
        };
        for (rect, stride, eps, boundary) in [(whole, 1, 0.5, true), (cell, 2, 0.3, false)] {
            let a = greedy_tin(&dem, rect, stride, eps, &[], boundary, None);
            let b = greedy_tin(&dem, rect, stride, eps, &[], boundary, Some(lanes));
            assert!(a.triangles.len() > 500, "{} triangles", a.triangles.len());
            assert_eq!(a.vertices, b.vertices);
            assert_eq!(a.triangles, b.triangles);
            assert_eq!(a.max_error.to_bits(), b.max_error.to_bits());
        }
    }

    #[test]
    fn area_one_triangles_find_the_sample_the_scan_finds() {
        // every triangle of area 1 with short edges, at every position of a small DEM, on
        // lattices of stride 1 to 3 with bounds that cut some of them: the lone midpoint
        // gives the scan's answer bit for bit
        let (w, h) = (24usize, 22usize);
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let heights: Vec<f32> = (0..w * h)
            .map(|_| {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1);
                (state >> 40) as f32 * 1e-3
            })
            .collect();
        let mut shapes = Vec::new();
        for (ex, ey) in (-2i64..=2).flat_map(|u| (-2i64..=2).map(move |v| (2 * u, 2 * v))) {
            for (wx, wy) in (-4i64..=4).flat_map(|x| (-4i64..=4).map(move |y| (x, y))) {
                if (ex * wy - ey * wx).abs() == 2 {
                    shapes.push([[0, 0], [ex, ey], [wx, wy]]);
                }
            }
        }
        assert!(shapes.len() > 50, "{} shapes", shapes.len());
        let (mut found, mut compared) = (0, 0);
        for stride in [1i64, 2, 3] {
            let lat = Lattice {
                origin_c: 1,
                origin_r: 2,
                stride,
                c_lo: 2,
                c_hi: 20,
                r_lo: 3,
                r_hi: 18,
            };
            let grid = LatticeTiles::new(&heights, w, lat, 22, 20);
            for shape in &shapes {
                for (ox, oy) in (4i64..18).flat_map(|x| (4i64..17).map(move |y| (x, y))) {
                    let p = shape.map(|q| [q[0] + ox, q[1] + oy]);
                    let z = p.map(|q| heights[q[1] as usize * w + q[0] as usize] as f64);
                    let plane = Plane::new(p, z);
                    let want = scan_triangle(p, &plane, &grid);
                    assert_eq!(lone_sample(p, &plane, &grid), want, "stride {stride} {p:?}");
                    assert_eq!(worst_sample(&heights, w, p, &grid, None), want);
                    assert_eq!(worst_sample(&heights, w, p, &grid, detect_lanes()), want);
                    compared += 1;
                    found += (want.1 >= 0) as usize;
                }
            }
        }
        assert!(found > 1000 && found < compared, "{found} of {compared}");
    }
}
