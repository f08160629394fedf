//! The base of the hierarchy: one triangle laid out with its exact 3D shape, or (if the
//! simplification got stuck above one triangle) a Tutte embedding of the base mesh.

use super::mesh::{Topo, VertId, cross3, dot3, len3, sub3};

/// Lays out the single alive triangle of `topo` congruent to its 3D shape, CCW.
pub(crate) fn triangle(topo: &Topo, pos: &[[f64; 3]], uvs: &mut [[f64; 2]]) {
    let Some(f) = topo.face_alive.iter().position(|&a| a) else {
        return;
    };
    let t = topo.faces[f];
    let (a, b, c) = (pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]);
    let e1 = sub3(b, a);
    let e2 = sub3(c, a);
    let l1 = len3(e1);
    let x = [e1[0] / l1, e1[1] / l1, e1[2] / l1];
    let h = len3(cross3(x, e2));
    uvs[t[0] as usize] = [0.0, 0.0];
    uvs[t[1] as usize] = [l1, 0.0];
    uvs[t[2] as usize] = [dot3(e2, x), h];
}

/// Tutte embedding of the alive mesh: boundary on a circle (spaced by 3D arc length, in
/// the orientation of the faces), interior vertices at the average of their neighbours
/// (conjugate gradients). Floater's theorem guarantees no flips in exact arithmetic.
pub(crate) fn tutte(topo: &Topo, pos: &[[f64; 3]], uvs: &mut [[f64; 2]]) {
    let nv = pos.len();
    // Boundary loop from the directed boundary edges a->b of alive faces.
    let mut next = vec![u32::MAX; nv];
    let mut start = None;
    for (f, t) in topo.faces.iter().enumerate() {
        if !topo.face_alive[f] {
            continue;
        }
        for k in 0..3 {
            let (a, b) = (VertId(t[k]), VertId(t[(k + 1) % 3]));
            if topo.edge_faces(a, b).len() == 1 {
                next[a.ix()] = b.0;
                if start.is_none_or(|s: u32| a.0 < s) {
                    start = Some(a.0);
                }
            }
        }
    }
    let Some(start) = start else { return };
    let mut lp = vec![start];
    let mut cur = next[start as usize];
    while cur != start && cur != u32::MAX && lp.len() <= nv {
        lp.push(cur);
        cur = next[cur as usize];
    }
    let mut cum = vec![0.0];
    for i in 0..lp.len() {
        let d = len3(sub3(
            pos[lp[(i + 1) % lp.len()] as usize],
            pos[lp[i] as usize],
        ));
        cum.push(cum[i] + d);
    }
    let total = cum[lp.len()].max(f64::MIN_POSITIVE);
    let area: f64 = topo
        .faces
        .iter()
        .enumerate()
        .filter(|(f, _)| topo.face_alive[*f])
        .map(|(_, t)| {
            super::mesh::area2_3d(pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]) * 0.5
        })
        .sum();
    let radius = (area / std::f64::consts::PI).sqrt();
    let mut fixed = vec![false; nv];
    for (i, &v) in lp.iter().enumerate() {
        let a = 2.0 * std::f64::consts::PI * cum[i] / total;
        uvs[v as usize] = [radius * a.cos(), radius * a.sin()];
        fixed[v as usize] = true;
    }
    // Interior unknowns.
    let interior: Vec<usize> = (0..nv)
        .filter(|&v| topo.vert_alive[v] && !fixed[v])
        .collect();
    if interior.is_empty() {
        return;
    }
    let mut index = vec![usize::MAX; nv];
    for (i, &v) in interior.iter().enumerate() {
        index[v] = i;
    }
    let nbrs: Vec<Vec<VertId>> = interior
        .iter()
        .map(|&v| topo.neighbours(VertId(v as u32)))
        .collect();
    for dim in 0..2 {
        // A x = b with A = deg I - adjacency(interior), b = sum of fixed neighbours.
        let mut b = vec![0.0; interior.len()];
        for (i, nb) in nbrs.iter().enumerate() {
            for w in nb {
                if fixed[w.ix()] {
                    b[i] += uvs[w.ix()][dim];
                }
            }
        }
        let apply = |x: &[f64], out: &mut [f64]| {
            for (i, nb) in nbrs.iter().enumerate() {
                let mut s = nb.len() as f64 * x[i];
                for w in nb {
                    if index[w.ix()] != usize::MAX {
                        s -= x[index[w.ix()]];
                    }
                }
                out[i] = s;
            }
        };
        let n = interior.len();
        let mut x = vec![0.0; n];
        let mut r = b.clone();
        let mut p = r.clone();
        let mut ap = vec![0.0; n];
        let mut rr: f64 = r.iter().map(|v| v * v).sum();
        let bb = rr.max(f64::MIN_POSITIVE);
        for _ in 0..(4 * n + 100) {
            if rr <= 1e-28 * bb {
                break;
            }
            apply(&p, &mut ap);
            let pap: f64 = p.iter().zip(&ap).map(|(a, b)| a * b).sum();
            if !(pap > 0.0) {
                break;
            }
            let alpha = rr / pap;
            for i in 0..n {
                x[i] += alpha * p[i];
                r[i] -= alpha * ap[i];
            }
            let rr2: f64 = r.iter().map(|v| v * v).sum();
            let beta = rr2 / rr;
            rr = rr2;
            for i in 0..n {
                p[i] = r[i] + beta * p[i];
            }
        }
        for (i, &v) in interior.iter().enumerate() {
            uvs[v][dim] = x[i];
        }
    }
}
