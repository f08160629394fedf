//! How far relief mapping may move a texture lookup on a reparameterized chart.
//!
//! Relief mapping moves a lookup from the drawn point by a shift in (x, y) and carries it
//! into texture coordinates through the drawn triangle's own map, extended beyond the
//! triangle ([`crate::cells::relief`]). On an orthographic texture that extension is exact.
//! On a chart it holds only while the neighbouring triangles share the map: across a chart
//! seam (a mesh boundary edge) or onto a wall (a triangle too steep to be relief-mapped, whose
//! chart map is stretched differently) it lands on texels of other surface points. The
//! photo projection would then put one point's colour into another's texels, and the view
//! read them (measured: streaks on walls, specks on the ground; docs/rendering.md).
//!
//! The reach of a vertex is its (x, y) distance to the nearest such edge, halved (the
//! distance to a segment set is not linear inside a triangle; half keeps the interpolated
//! value inside the true distance on the triangles this meets), at most `cap`. The renderer
//! and the projection interpolate it over the triangle and shorten longer shifts to it.

/// Per vertex of `positions` (cell-local metres), its relief reach in metres, in `0..=cap`:
/// half its (x, y) distance to the nearest boundary edge of `triangles` (an edge one triangle
/// uses) or edge of a triangle whose unit normal's up component is below `min_normal_z`
/// (vertices of those edges: 0). Vertices no triangle uses get 0. Deterministic.
pub fn relief_reach(
    positions: &[[f32; 3]],
    triangles: &[[u32; 3]],
    min_normal_z: f32,
    cap: f32,
) -> Vec<f32> {
    let n = positions.len();
    let cap = if cap.is_finite() && cap > 0.0 {
        cap
    } else {
        0.0
    };
    let valid = |t: &[u32; 3]| t.iter().all(|&i| (i as usize) < n);
    // edges, sorted by their vertex pair, with the count of triangles using them
    let mut edges: Vec<(u32, u32, bool)> = Vec::with_capacity(triangles.len() * 3);
    let mut used = vec![false; n];
    for t in triangles.iter().filter(|t| valid(t)) {
        let p = t.map(|i| glam::Vec3::from(positions[i as usize]));
        let nrm = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let steep = !(nrm.z.abs() >= min_normal_z);
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            edges.push((a.min(b), a.max(b), steep));
            used[t[k] as usize] = true;
        }
    }
    edges.sort_unstable();
    // unsafe segments: boundary edges and edges of steep triangles
    let mut segs: Vec<[[f32; 2]; 2]> = Vec::new();
    let mut i = 0;
    while i < edges.len() {
        let mut j = i;
        let mut steep = false;
        while j < edges.len() && edges[j].0 == edges[i].0 && edges[j].1 == edges[i].1 {
            steep |= edges[j].2;
            j += 1;
        }
        if j - i == 1 || steep {
            let (a, b) = (
                positions[edges[i].0 as usize],
                positions[edges[i].1 as usize],
            );
            segs.push([[a[0], a[1]], [b[0], b[1]]]);
        }
        i = j;
    }
    let mut reach = vec![0.0f32; n];
    if cap == 0.0 {
        return reach;
    }
    // segments binned on a grid of side cap / 4 over the vertices' box
    let (mut lo, mut hi) = ([f32::INFINITY; 2], [f32::NEG_INFINITY; 2]);
    for p in positions {
        for k in 0..2 {
            if p[k].is_finite() {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
    }
    if !(lo[0] <= hi[0] && lo[1] <= hi[1]) {
        return reach;
    }
    let side = cap / 4.0;
    let dims = [0, 1].map(|k| (((hi[k] - lo[k]) / side).floor() as usize + 1).min(4096));
    let bin = |x: f32, k: usize| (((x - lo[k]) / side).floor().max(0.0) as usize).min(dims[k] - 1);
    let mut bins: Vec<Vec<u32>> = vec![Vec::new(); dims[0] * dims[1]];
    for (s, seg) in segs.iter().enumerate() {
        let (x0, x1) = (seg[0][0].min(seg[1][0]), seg[0][0].max(seg[1][0]));
        let (y0, y1) = (seg[0][1].min(seg[1][1]), seg[0][1].max(seg[1][1]));
        if !(x0.is_finite() && x1.is_finite() && y0.is_finite() && y1.is_finite()) {
            continue;
        }
        for by in bin(y0, 1)..=bin(y1, 1) {
            for bx in bin(x0, 0)..=bin(x1, 0) {
                bins[by * dims[0] + bx].push(s as u32);
            }
        }
    }
    // twice the cap: the reach is half the distance
    let rings = 8usize;
    for (v, r) in reach.iter_mut().enumerate() {
        let p = positions[v];
        if !(used[v] && p[0].is_finite() && p[1].is_finite()) {
            continue;
        }
        let (bx, by) = (bin(p[0], 0) as isize, bin(p[1], 1) as isize);
        let mut best = 2.0 * cap;
        for ring in 0..=rings as isize {
            // every point of this ring's bins is at least (ring − 1) bins away
            if (ring - 1).max(0) as f32 * side >= best {
                break;
            }
            for dy in -ring..=ring {
                for dx in -ring..=ring {
                    if dx.abs() != ring && dy.abs() != ring {
                        continue;
                    }
                    let (x, y) = (bx + dx, by + dy);
                    if x < 0 || y < 0 || x >= dims[0] as isize || y >= dims[1] as isize {
                        continue;
                    }
                    for &s in &bins[y as usize * dims[0] + x as usize] {
                        best = best.min(segment_distance([p[0], p[1]], segs[s as usize]));
                    }
                }
            }
        }
        *r = (0.5 * best).min(cap);
    }
    reach
}

/// Distance from `p` to the segment `s`.
fn segment_distance(p: [f32; 2], s: [[f32; 2]; 2]) -> f32 {
    let d = [s[1][0] - s[0][0], s[1][1] - s[0][1]];
    let q = [p[0] - s[0][0], p[1] - s[0][1]];
    let len2 = d[0] * d[0] + d[1] * d[1];
    let t = if len2 > 0.0 {
        ((q[0] * d[0] + q[1] * d[1]) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (ex, ey) = (q[0] - t * d[0], q[1] - t * d[1]);
    (ex * ex + ey * ey).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 10 × 10 grid of 1-m quads, z = 0, with the column of quads at x in [6, 7] raised
    /// into a wall (its east vertices 20 m up).
    fn grid(wall: bool) -> (Vec<[f32; 3]>, Vec<[u32; 3]>) {
        let n = 10u32;
        let mut pos = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let z = if wall && i >= 7 { 20.0 } else { 0.0 };
                pos.push([i as f32, j as f32, z]);
            }
        }
        let v = |i: u32, j: u32| j * (n + 1) + i;
        let mut tris = Vec::new();
        for j in 0..n {
            for i in 0..n {
                tris.push([v(i, j), v(i + 1, j), v(i + 1, j + 1)]);
                tris.push([v(i, j), v(i + 1, j + 1), v(i, j + 1)]);
            }
        }
        (pos, tris)
    }

    #[test]
    fn reach_is_half_the_distance_to_boundaries_and_walls() {
        let (pos, tris) = grid(false);
        let r = relief_reach(&pos, &tris, 0.7, 100.0);
        // the boundary is the square's edge: vertex (3, 5) lies 3 m from it
        assert_eq!(r[5 * 11 + 3], 1.5);
        assert_eq!(r[0], 0.0);
        // capped
        let r = relief_reach(&pos, &tris, 0.7, 1.0);
        assert_eq!(r[5 * 11 + 5], 1.0);
        // a wall between x = 6 and 7: vertex (3, 5) is 3 m from the wall's foot, (2, 5) 2 m
        // from the western boundary
        let (pos, tris) = grid(true);
        let r = relief_reach(&pos, &tris, 0.7, 100.0);
        assert_eq!(r[5 * 11 + 4], 1.0);
        assert_eq!(r[5 * 11 + 6], 0.0);
        assert_eq!(r[5 * 11 + 2], 1.0);
        // a cap of 0 gives nothing, invalid triangles are ignored
        assert!(
            relief_reach(&pos, &tris, 0.7, 0.0)
                .iter()
                .all(|&x| x == 0.0)
        );
        let r = relief_reach(&pos, &[[0, 1, 999]], 0.7, 10.0);
        assert!(r.iter().all(|&x| x == 0.0));
    }
}
