//! Scan conversion of chart triangles in texture space (CPU, exact integer edge functions).
//!
//! Texture coordinates are snapped to a fixed-point grid of 1/[`SUBPIXEL`] texel; texel
//! centres lie exactly on that grid, so the edge functions are evaluated exactly in `i64`.
//! Points on a shared edge go to exactly one triangle (top-left rule), so a watertight
//! chart covers each texel centre once. Where triangles overlap, the lowest index wins.

/// Marker for a texel whose centre no triangle covers.
pub(crate) const EMPTY: u32 = u32::MAX;

/// Fixed-point subdivisions per texel.
pub(crate) const SUBPIXEL: i64 = 256;

/// Snaps a texel-space coordinate to the fixed-point grid. The caller guarantees
/// `|v| <= 2^30 / SUBPIXEL`.
#[inline]
fn fixed(v: f64) -> i64 {
    // round half away from zero, without a libm call (x - t is exact for |x| < 2^52)
    let x = v * SUBPIXEL as f64;
    let t = x as i64;
    let f = x - t as f64;
    t + i64::from(f >= 0.5) - i64::from(f <= -0.5)
}

/// Whether an edge with direction `d` (y down) is a top or left edge of a triangle whose
/// interior lies where the edge function is positive. Antisymmetric in `d`, so exactly one of
/// two triangles sharing an edge owns the points on it.
#[inline]
fn top_left(d: [i64; 2]) -> bool {
    d[1] < 0 || (d[1] == 0 && d[0] > 0)
}

/// For every texel of a `texels x texels` texture (row-major, row = v), the index of the
/// triangle covering its centre, or [`EMPTY`]. `st` holds the vertices' texel-space
/// coordinates (`u * texels`, `v * texels`); triangles for which `usable(index)` is false
/// are skipped.
pub(crate) fn rasterize(
    st: &[[f64; 2]],
    triangles: &[[u32; 3]],
    texels: u32,
    usable: impl Fn(usize) -> bool,
) -> Vec<u32> {
    let n = texels as usize;
    let mut ids = vec![EMPTY; n * n];
    let half = SUBPIXEL / 2;
    let fx: Vec<[i64; 2]> = st.iter().map(|p| [fixed(p[0]), fixed(p[1])]).collect();
    for (ti, tri) in triangles.iter().enumerate() {
        if !usable(ti) {
            continue;
        }
        let mut v = tri.map(|k| fx[k as usize]);
        let cross = |a: [i64; 2], b: [i64; 2], c: [i64; 2]| {
            (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
        };
        let area2 = cross(v[0], v[1], v[2]);
        if area2 == 0 {
            continue;
        }
        if area2 < 0 {
            v.swap(1, 2);
        }
        // Edge k goes from v[k] to v[k+1]; E(p) = d x (p - v[k]) > 0 inside.
        let mut d = [[0i64; 2]; 3];
        let mut bias = [0i64; 3];
        for k in 0..3 {
            let (p, q) = (v[k], v[(k + 1) % 3]);
            d[k] = [q[0] - p[0], q[1] - p[1]];
            bias[k] = if top_left(d[k]) { 0 } else { -1 };
        }
        let min_x = v.iter().map(|p| p[0]).min().unwrap_or(0);
        let max_x = v.iter().map(|p| p[0]).max().unwrap_or(0);
        let min_y = v.iter().map(|p| p[1]).min().unwrap_or(0);
        let max_y = v.iter().map(|p| p[1]).max().unwrap_or(0);
        // texel i has its centre at i*SUBPIXEL + half
        let first = |lo: i64| {
            (lo - half).div_euclid(SUBPIXEL) + i64::from((lo - half).rem_euclid(SUBPIXEL) != 0)
        };
        let last = |hi: i64| (hi - half).div_euclid(SUBPIXEL);
        let (i0, i1) = (first(min_x).max(0), last(max_x).min(n as i64 - 1));
        let (j0, j1) = (first(min_y).max(0), last(max_y).min(n as i64 - 1));
        if i0 > i1 || j0 > j1 {
            continue;
        }
        for j in j0..=j1 {
            let py = j * SUBPIXEL + half;
            let px = i0 * SUBPIXEL + half;
            let mut e = [0i64; 3];
            for k in 0..3 {
                e[k] = d[k][0] * (py - v[k][1]) - d[k][1] * (px - v[k][0]) + bias[k];
            }
            let step = [
                -d[0][1] * SUBPIXEL,
                -d[1][1] * SUBPIXEL,
                -d[2][1] * SUBPIXEL,
            ];
            let row = &mut ids[j as usize * n..(j as usize + 1) * n];
            for cell in &mut row[i0 as usize..=i1 as usize] {
                if e[0] >= 0 && e[1] >= 0 && e[2] >= 0 && *cell == EMPTY {
                    *cell = ti as u32;
                }
                e[0] += step[0];
                e[1] += step[1];
                e[2] += step[2];
            }
        }
    }
    ids
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shared_edges_cover_each_centre_once() {
        // A 4x4-texel square split along a diagonal through texel centres, plus a fan
        // with a vertex exactly on a texel centre.
        let st = [[0.0, 0.0], [4.0, 0.0], [4.0, 4.0], [0.0, 4.0], [1.5, 2.5]];
        let tris = [[0, 1, 2], [0, 2, 3]];
        let ids = rasterize(&st, &tris, 4, |_| true);
        assert!(ids.iter().all(|&t| t != EMPTY));
        let fan = [[0, 1, 4], [1, 2, 4], [2, 3, 4], [3, 0, 4]];
        let ids2 = rasterize(&st, &fan, 4, |_| true);
        assert!(ids2.iter().all(|&t| t != EMPTY));
        // Count per triangle equals the number of centres strictly inside or owned: total 16.
        let mut counts = [0; 4];
        for &t in &ids2 {
            counts[t as usize] += 1;
        }
        assert_eq!(counts.iter().sum::<i32>(), 16);
        // Clockwise input is handled like counter-clockwise.
        let cw = [[0, 2, 1], [0, 3, 2]];
        assert_eq!(
            rasterize(&st, &cw, 4, |_| true)
                .iter()
                .filter(|&&t| t != EMPTY)
                .count(),
            16
        );
        // Disjoint half: only the triangle's own centres.
        let half = rasterize(&st, &tris[..1], 4, |_| true);
        // centres (i+.5, j+.5) with j+.5 < i+.5 are inside, diagonal ones go to one side only
        let strictly = (0..4)
            .flat_map(|j| (0..4).map(move |i| (i, j)))
            .filter(|(i, j)| j < i)
            .count();
        let n = half.iter().filter(|&&t| t == 0).count();
        assert!(n == strictly || n == strictly + 4, "{n}");
    }

    #[test]
    fn degenerate_and_outside_triangles_cover_nothing() {
        let st = [
            [0.0, 0.0],
            [2.0, 2.0],
            [4.0, 4.0],
            [-9.0, -9.0],
            [-8.0, -9.0],
            [-9.0, -8.0],
        ];
        let ids = rasterize(&st, &[[0, 1, 2], [3, 4, 5]], 4, |_| true);
        assert!(ids.iter().all(|&t| t == EMPTY));
    }
}
