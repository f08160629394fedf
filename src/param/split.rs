//! Vertex splits: undoing a [`Collapse`] and placing the re-inserted vertex in the plane
//! so that none of its triangles is flipped.

use super::collapse::Collapse;
use super::mesh::{Topo, VertId, dot3, sub3};

/// Reverts `c` on `topo` (the inverse of [`super::collapse::apply`]).
pub(crate) fn undo(topo: &mut Topo, c: &Collapse) {
    let (u, v) = (c.u, c.v);
    for &f in &c.modified {
        for x in topo.faces[f.ix()].iter_mut() {
            if *x == v.0 {
                *x = u.0;
            }
        }
        topo.vert_faces[v.ix()].retain(|&g| g != f);
        topo.vert_faces[u.ix()].push(f);
    }
    for &f in &c.deleted {
        topo.face_alive[f.ix()] = true;
        topo.alive_faces += 1;
        for &w in &topo.faces[f.ix()] {
            topo.vert_faces[w as usize].push(f);
        }
    }
    topo.vert_alive[u.ix()] = true;
}

fn cross2(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}
fn sub2(a: [f64; 2], b: [f64; 2]) -> [f64; 2] {
    [a[0] - b[0], a[1] - b[1]]
}

/// The half-planes (p, q) a position of `u` must lie strictly left of: one per face
/// (u, p, q) of `u`.
fn constraints(topo: &Topo, uvs: &[[f64; 2]], u: VertId) -> Vec<([f64; 2], [f64; 2])> {
    topo.vert_faces[u.ix()]
        .iter()
        .map(|&f| {
            let (p, q) = topo.others(f, u);
            (uvs[p.ix()], uvs[q.ix()])
        })
        .collect()
}

/// Whether `x` is strictly inside every half-plane, with a small relative margin.
fn valid(cons: &[([f64; 2], [f64; 2])], x: [f64; 2]) -> bool {
    cons.iter().all(|&(p, q)| {
        let e = sub2(q, p);
        cross2(e, sub2(x, p)) > 1e-9 * (e[0] * e[0] + e[1] * e[1])
    })
}

/// The UV of the re-inserted vertex `u` (all its neighbours have UVs). Tries the
/// area-weighted mean of the positions that make each incident triangle similar to its
/// 3D shape; if that flips a triangle, moves to a point of the 1-ring's kernel
/// (half-plane intersection). Returns `None` only if the kernel is numerically empty.
pub(crate) fn place(
    topo: &Topo,
    pos: &[[f64; 3]],
    uvs: &[[f64; 2]],
    u: VertId,
) -> Option<[f64; 2]> {
    let pu = pos[u.ix()];
    let mut acc = [0.0, 0.0];
    let mut wsum = 0.0;
    for &f in &topo.vert_faces[u.ix()] {
        let (p, q) = topo.others(f, u);
        let (pp, pq) = (pos[p.ix()], pos[q.ix()]);
        let e = sub3(pq, pp);
        let d = sub3(pu, pp);
        let ee = dot3(e, e);
        let t = dot3(d, e) / ee;
        let perp = sub3(d, [e[0] * t, e[1] * t, e[2] * t]);
        let hgt = (dot3(perp, perp) / ee).sqrt();
        let (a, b) = (uvs[p.ix()], uvs[q.ix()]);
        let g = sub2(b, a);
        let x = [a[0] + t * g[0] - hgt * g[1], a[1] + t * g[1] + hgt * g[0]];
        let w = super::mesh::area2_3d(pu, pp, pq);
        acc[0] += w * x[0];
        acc[1] += w * x[1];
        wsum += w;
    }
    let cand = if wsum > 0.0 {
        [acc[0] / wsum, acc[1] / wsum]
    } else {
        uvs[u.ix()]
    };
    let cons = constraints(topo, uvs, u);
    if cand[0].is_finite() && cand[1].is_finite() && valid(&cons, cand) {
        return Some(cand);
    }
    let kernel = kernel_polygon(&cons)?;
    let c = centroid(&kernel)?;
    if !valid(&cons, c) {
        return None;
    }
    // Walk from the kernel centroid toward the candidate, stopping half-way to the kernel
    // boundary (every constraint is linear along the segment).
    let dir = sub2(cand, c);
    let mut tmax: f64 = 1.0;
    if dir[0].is_finite() && dir[1].is_finite() {
        for &(p, q) in &cons {
            let e = sub2(q, p);
            let s0 = cross2(e, sub2(c, p));
            let s1 = cross2(e, dir);
            if s1 < 0.0 {
                tmax = tmax.min(s0 / -s1);
            }
        }
        let x = [c[0] + 0.5 * tmax * dir[0], c[1] + 0.5 * tmax * dir[1]];
        if valid(&cons, x) {
            return Some(x);
        }
    }
    Some(c)
}

/// Intersection of the left half-planes of the directed lines p->q, clipped to a box
/// around them (the kernel of a boundary vertex's fan may be unbounded).
fn kernel_polygon(cons: &[([f64; 2], [f64; 2])]) -> Option<Vec<[f64; 2]>> {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for &(p, q) in cons {
        for x in [p, q] {
            for k in 0..2 {
                lo[k] = lo[k].min(x[k]);
                hi[k] = hi[k].max(x[k]);
            }
        }
    }
    let ext = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-300);
    let (lo, hi) = ([lo[0] - ext, lo[1] - ext], [hi[0] + ext, hi[1] + ext]);
    let mut poly = vec![lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]];
    for &(p, q) in cons {
        let e = sub2(q, p);
        let side = |x: [f64; 2]| cross2(e, sub2(x, p));
        let mut out = Vec::with_capacity(poly.len() + 1);
        for i in 0..poly.len() {
            let a = poly[i];
            let b = poly[(i + 1) % poly.len()];
            let (sa, sb) = (side(a), side(b));
            if sa > 0.0 {
                out.push(a);
            }
            if (sa > 0.0) != (sb > 0.0) {
                let t = sa / (sa - sb);
                out.push([a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])]);
            }
        }
        poly = out;
        if poly.len() < 3 {
            return None;
        }
    }
    Some(poly)
}

/// Area centroid of a convex polygon; `None` if its area is zero.
fn centroid(poly: &[[f64; 2]]) -> Option<[f64; 2]> {
    let o = poly[0];
    let (mut a, mut cx, mut cy) = (0.0, 0.0, 0.0);
    for i in 1..poly.len() - 1 {
        let p = sub2(poly[i], o);
        let q = sub2(poly[i + 1], o);
        let w = cross2(p, q);
        a += w;
        cx += w * (p[0] + q[0]) / 3.0;
        cy += w * (p[1] + q[1]) / 3.0;
    }
    if !(a > 0.0) {
        return None;
    }
    Some([o[0] + cx / a, o[1] + cy / a])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn kernel_of_non_convex_fan_is_found() {
        // A star-shaped but non-convex ring around the origin (CCW); the constraints are
        // the ring edges. The kernel must contain a valid point.
        let ring = [[1.0, 0.0], [0.1, 0.1], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]];
        let cons: Vec<_> = (0..ring.len())
            .map(|i| (ring[i], ring[(i + 1) % ring.len()]))
            .collect();
        let k = kernel_polygon(&cons).unwrap();
        let c = centroid(&k).unwrap();
        assert!(valid(&cons, c), "{c:?}");
        // A point far to the upper right is outside.
        assert!(!valid(&cons, [0.5, 0.5]));
    }

    #[test]
    fn empty_kernel_is_reported() {
        // y > 1 and y < 0.
        let cons = vec![([0.0, 1.0], [1.0, 1.0]), ([1.0, 0.0], [0.0, 0.0])];
        assert!(kernel_polygon(&cons).is_none());
    }
}
