//! The worst lattice sample of a triangle, four samples at a time (x86-64 with AVX2).
//!
//! The same scan as `tin::scan_triangle` (same spans, same plane, the same error
//! expression `|h − (base + step · i)|` evaluated with the same IEEE operations, so every
//! error is bit for bit the scalar one), but each lattice row is taken a 4-column group of
//! the height tiles at a time. Each of the four lanes keeps its largest error and the
//! first sample (in row-major scan order) that reached it; the result is the largest of
//! the lanes' errors at the earliest such sample, which is exactly the scalar scan's
//! "first sample whose error exceeds every earlier one". Columns outside the span and the
//! triangle's own corners are masked out. Runtime-dispatched: callers enter
//! [`pulp::x86::V3::vectorize`] once per greedy run and pass the token down.

use pulp::x86::V3;
use pulp::{f32x4, f64x4};

use super::lattice_tiles::LatticeTiles;
use super::raster::Plane;
use super::raster::Spans;

/// Scan order key of lattice sample `(i, j)`: row-major, exact in an `f64` (`i < 2^32`,
/// `j < 2^20`).
const ROW_KEY: f64 = 4_294_967_296.0;

/// `tin::scan_triangle` with four lanes: `(error, col, row)` of the worst lattice sample of
/// the closed triangle `p` that is not one of its corners, or error −1 if there is none.
/// (No closures around the vector code: a closure would be compiled without the AVX2
/// features its caller is compiled with.)
#[inline(always)]
pub(super) fn scan_triangle_x4(
    simd: V3,
    p: [[i64; 2]; 3],
    plane: &Plane,
    grid: &LatticeTiles,
) -> (f64, i64, i64) {
    let lat = &grid.lat;
    let (oc, s) = (lat.origin_c, lat.stride);
    let none = simd.splat_f64x4(f64::NEG_INFINITY);
    let mut best_e = simd.splat_f64x4(-1.0);
    let mut best_k = simd.splat_f64x4(0.0);
    let lanes = f64x4(0.0, 1.0, 2.0, 3.0);
    for (y, j, i0, i1) in Spans::new(p, lat) {
        let (base, step) = plane.lattice_row(y, oc, s);
        let (base, step) = (simd.splat_f64x4(base), simd.splat_f64x4(step));
        let (lo, hi) = (simd.splat_f64x4(i0 as f64), simd.splat_f64x4(i1 as f64));
        // the lattice columns of the corners on this row (NaN: no corner, never equal)
        let mut corners = [f64::NAN; 3];
        for (c, q) in corners.iter_mut().zip(p) {
            let d = q[0] - oc;
            if q[1] == y && d >= 0 && d % s == 0 {
                *c = (d / s) as f64;
            }
        }
        let corners = corners.map(|c| simd.splat_f64x4(c));
        let row_key = simd.splat_f64x4(j as f64 * ROW_KEY);
        let (tiles, off) = grid.row_tiles(j);
        let mut k = i0 >> 2;
        while k <= i1 >> 2 {
            let t = &tiles[k].0[off..off + 4];
            let i = simd.add_f64x4(simd.splat_f64x4((4 * k) as f64), lanes);
            let h = simd.convert_f32x4_to_f64x4(f32x4(t[0], t[1], t[2], t[3]));
            // (h − (base + step · i)).abs(), as `tin::lattice_error`
            let e =
                simd.abs_f64x4(simd.sub_f64x4(h, simd.add_f64x4(base, simd.mul_f64x4(step, i))));
            let mut keep = simd.and_m64x4(simd.cmp_ge_f64x4(i, lo), simd.cmp_le_f64x4(i, hi));
            keep = simd.and_m64x4(keep, simd.cmp_not_eq_f64x4(i, corners[0]));
            keep = simd.and_m64x4(keep, simd.cmp_not_eq_f64x4(i, corners[1]));
            keep = simd.and_m64x4(keep, simd.cmp_not_eq_f64x4(i, corners[2]));
            let e = simd.select_f64x4(keep, e, none);
            let better = simd.cmp_gt_f64x4(e, best_e);
            best_e = simd.select_f64x4(better, e, best_e);
            best_k = simd.select_f64x4(better, simd.add_f64x4(row_key, i), best_k);
            k += 1;
        }
    }
    let (e, k) = (
        [best_e.0, best_e.1, best_e.2, best_e.3],
        [best_k.0, best_k.1, best_k.2, best_k.3],
    );
    let mut worst = -1.0f64;
    for v in e {
        if v > worst {
            worst = v;
        }
    }
    if !(worst > -1.0) {
        return (-1.0, -1, -1);
    }
    let mut key = f64::INFINITY;
    for l in 0..4 {
        if e[l] == worst && k[l] < key {
            key = k[l];
        }
    }
    let (j, i) = ((key / ROW_KEY) as i64, (key % ROW_KEY) as i64);
    (worst, oc + i * s, lat.origin_r + j * s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cells::raster::Lattice;

    #[test]
    fn four_lanes_find_the_sample_the_scalar_scan_finds() {
        // random triangles from slivers to 70 samples across on lattices of stride 1 to 3
        // whose bounds cut some of them, over heights with many exact ties (multiples of
        // 1/8, a plateau) and a few NaNs: the same (error, col, row) bit for bit
        let Some(simd) = V3::try_new() else {
            return;
        };
        let (w, h) = (90usize, 84usize);
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut rnd = move |m: u64| {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 33) % m
        };
        let heights: Vec<f32> = (0..w * h)
            .map(|k| match (k % w, rnd(500)) {
                (_, 0) => f32::NAN,
                (c, _) if c < 20 => 3.0,
                _ => rnd(64) as f32 / 8.0,
            })
            .collect();
        let (mut found, mut tied) = (0, 0);
        for case in 0..6000u64 {
            let stride = 1 + (case % 3) as i64;
            let lat = Lattice {
                origin_c: rnd(3) as i64,
                origin_r: rnd(3) as i64,
                stride,
                c_lo: 3,
                c_hi: 80,
                r_lo: 2,
                r_hi: 76,
            };
            let grid = LatticeTiles::new(&heights, w, lat, 86, 80);
            let m = [6, 20, 72][(case % 7 % 3) as usize];
            let (ox, oy) = (rnd(84 - m) as i64, rnd(80 - m) as i64);
            let p = [0; 3].map(|_| [ox + rnd(m + 1) as i64, oy + rnd(m + 1) as i64]);
            let z = p.map(|q| heights[q[1] as usize * w + q[0] as usize] as f64);
            let plane = Plane::new(p, z);
            let want = crate::cells::tin::scan_triangle(p, &plane, &grid);
            let got = scan_triangle_x4(simd, p, &plane, &grid);
            assert_eq!(
                (got.0.to_bits(), got.1, got.2),
                (want.0.to_bits(), want.1, want.2),
                "case {case} {p:?} stride {stride}"
            );
            found += (want.1 >= 0) as usize;
            tied += (want.0 == 0.0) as usize;
        }
        assert!(
            found > 3000 && tied > 50,
            "{found} found, {tied} on a plane"
        );
    }
}
