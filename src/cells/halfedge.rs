//! A half-edge Delaunay triangulation of a grid rectangle for greedy refinement.
//!
//! Purpose-built for greedy insertion (as Delatin): a point is inserted into a triangle
//! the caller already knows contains it (no point location), the triangle (or the edge
//! the point lies on) is split, and the edges opposite the new point are legalised by
//! Lawson flips. Triangle `t` owns half-edges `3t`, `3t + 1`, `3t + 2`; half-edge `e` runs
//! from vertex `tri[e]` to the next corner of its triangle, and `twin[e]` is the
//! neighbour's opposite half-edge, or [`NONE`] on the rectangle's boundary. Triangles are
//! counter-clockwise in world coordinates (x = column east, y = -row north). Predicates
//! are exact integer arithmetic on grid coordinates below [`MAX_COORD`], so the
//! triangulation stays Delaunay; cocircular ties are never flipped, so the result is
//! deterministic. Flips reuse triangle slots; every slot written since the last
//! [`Mesh::take_dirty`] is reported there.

use super::SampleRect;

/// No twin: the half-edge lies on the rectangle's boundary.
pub(crate) const NONE: u32 = u32::MAX;

/// Grid coordinates must be below this (exact `i64` orientation, `i128` in-circle).
pub(crate) const MAX_COORD: u32 = 1 << 30;

#[inline]
fn next(e: u32) -> u32 {
    if e % 3 == 2 { e - 2 } else { e + 1 }
}

#[inline]
fn prev(e: u32) -> u32 {
    if e.is_multiple_of(3) { e + 2 } else { e - 1 }
}

/// Twice the signed area of `(a, b, c)` in world orientation (> 0: counter-clockwise),
/// for grid points `[col, row]` (rows run south).
#[inline]
pub(crate) fn ccw(a: [i64; 2], b: [i64; 2], c: [i64; 2]) -> i64 {
    (b[1] - a[1]) * (c[0] - a[0]) - (b[0] - a[0]) * (c[1] - a[1])
}

/// Whether `d` is strictly inside the circumcircle of the world-CCW triangle `(a, b, c)`.
#[inline]
fn in_circle(a: [i64; 2], b: [i64; 2], c: [i64; 2], d: [i64; 2]) -> bool {
    let (adx, ady) = (a[0] - d[0], a[1] - d[1]);
    let (bdx, bdy) = (b[0] - d[0], b[1] - d[1]);
    let (cdx, cdy) = (c[0] - d[0], c[1] - d[1]);
    let al = (adx * adx + ady * ady) as i128;
    let bl = (bdx * bdx + bdy * bdy) as i128;
    let cl = (cdx * cdx + cdy * cdy) as i128;
    let det = al * (bdx * cdy - cdx * bdy) as i128
        + bl * (cdx * ady - adx * cdy) as i128
        + cl * (adx * bdy - bdx * ady) as i128;
    // the usual determinant is > 0 inside for y-up CCW; rows run south, so the sign flips
    det < 0
}

/// The triangulation: vertices, triangles (three vertex ids each) and twins.
pub(crate) struct Mesh {
    coords: Vec<[u32; 2]>,
    tri: Vec<u32>,
    twin: Vec<u32>,
    /// Per boundary vertex (ids below its length): its outgoing boundary half-edge.
    hull_out: Vec<u32>,
    dirty: Vec<u32>,
    is_dirty: Vec<bool>,
    stack: Vec<u32>,
}

/// Rectangles of at most this many samples reserve their densest triangulation's storage
/// up front ([`Mesh::rectangle`]): a finest-level cell (129² samples at most) does.
const RESERVE_SAMPLES: usize = 1 << 15;

/// Triangle slots to reserve for a triangulation of `rect`'s samples: two per sample (the
/// densest) for a rectangle of at most [`RESERVE_SAMPLES`], else none (it grows).
pub(crate) fn reserved_triangles(rect: SampleRect) -> usize {
    let samples = (rect.c1 - rect.c0 + 1) as usize * (rect.r1 - rect.r0 + 1) as usize;
    if samples <= RESERVE_SAMPLES {
        2 * samples
    } else {
        0
    }
}

impl Mesh {
    /// The Delaunay triangulation of `rect`'s four corners and the `border` points that lie
    /// strictly inside one of its sides (other points are ignored; duplicates are merged).
    /// Vertices 0..4 are the corners; the boundary vertices come first. `rect` must be
    /// non-empty (`c0 < c1`, `r0 < r1`) with `c1`, `r1` below [`MAX_COORD`]. Every triangle
    /// is dirty.
    pub fn rectangle(rect: SampleRect, border: &[[u32; 2]]) -> Mesh {
        let SampleRect { c0, r0, c1, r1 } = rect;
        // the four sides in counter-clockwise (world) order, as (start, points along it)
        let mut left: Vec<u32> = Vec::new();
        let mut bottom: Vec<u32> = Vec::new();
        let mut right: Vec<u32> = Vec::new();
        let mut top: Vec<u32> = Vec::new();
        for &[c, r] in border {
            let in_c = c0 < c && c < c1;
            let in_r = r0 < r && r < r1;
            if c == c0 && in_r {
                left.push(r);
            } else if r == r1 && in_c {
                bottom.push(c);
            } else if c == c1 && in_r {
                right.push(r);
            } else if r == r0 && in_c {
                top.push(c);
            }
        }
        left.sort_unstable();
        bottom.sort_unstable();
        right.sort_unstable_by(|a, b| b.cmp(a));
        top.sort_unstable_by(|a, b| b.cmp(a));
        for side in [&mut left, &mut bottom, &mut right, &mut top] {
            side.dedup();
        }
        let n_boundary = 4 + left.len() + bottom.len() + right.len() + top.len();
        // a cell-sized rectangle gets room for its densest triangulation at once (no
        // regrowth while refining); larger ones grow as they refine
        let t = reserved_triangles(rect);
        let mut coords = Vec::with_capacity((t / 2).max(4));
        coords.extend([[c0, r0], [c0, r1], [c1, r1], [c1, r0]]);
        let mut m = Mesh {
            coords,
            tri: Vec::with_capacity(3 * t),
            twin: Vec::with_capacity(3 * t),
            hull_out: vec![NONE; n_boundary],
            dirty: Vec::new(),
            is_dirty: Vec::with_capacity(t),
            stack: Vec::new(),
        };
        let (tl, bl, br, tr) = (0, 1, 2, 3);
        m.set_tri(0, [tl, bl, br]);
        m.set_tri(1, [tl, br, tr]);
        for (e, o) in [(0, NONE), (1, NONE), (2, 3), (4, NONE), (5, NONE)] {
            m.link(e, o);
        }
        let sides = [
            (tl, left.iter().map(|&r| [c0, r]).collect::<Vec<_>>()),
            (bl, bottom.iter().map(|&c| [c, r1]).collect()),
            (br, right.iter().map(|&r| [c1, r]).collect()),
            (tr, top.iter().map(|&c| [c, r0]).collect()),
        ];
        for (start, pts) in sides {
            let mut from = start;
            for p in pts {
                let e = m.hull_out[from as usize];
                from = m.split_edge(e, p);
            }
        }
        m
    }

    /// Number of triangles (slots `0..n`, all live).
    pub fn num_triangles(&self) -> usize {
        self.tri.len() / 3
    }

    /// The vertices `[col, row]`, in insertion order.
    pub fn vertices(&self) -> &[[u32; 2]] {
        &self.coords
    }

    /// The vertex ids of triangle `t`, counter-clockwise in world coordinates.
    #[inline]
    pub fn triangle(&self, t: u32) -> [u32; 3] {
        let e = 3 * t as usize;
        [self.tri[e], self.tri[e + 1], self.tri[e + 2]]
    }

    /// The corners of triangle `t` as `[col, row]`, counter-clockwise in world coordinates.
    #[inline]
    pub fn corners(&self, t: u32) -> [[i64; 2]; 3] {
        self.triangle(t).map(|v| {
            let q = self.coords[v as usize];
            [q[0] as i64, q[1] as i64]
        })
    }

    /// Moves the triangles written since the last call into `out` (cleared first), each
    /// once, in the order they were first written.
    pub fn take_dirty(&mut self, out: &mut Vec<u32>) {
        out.clear();
        std::mem::swap(out, &mut self.dirty);
        for &t in out.iter() {
            self.is_dirty[t as usize] = false;
        }
    }

    /// Inserts grid point `p`, which must lie in the closed triangle `t` and not be one of
    /// its corners, splitting `t` (or the edge `p` lies on, with its neighbour), then
    /// restores the Delaunay property by flips. Returns the new vertex id.
    pub fn insert(&mut self, t: u32, p: [u32; 2]) -> u32 {
        let q = [p[0] as i64, p[1] as i64];
        let [a, b, c] = self.corners(t);
        let e = 3 * t;
        if ccw(a, b, q) == 0 {
            self.split_edge(e, p)
        } else if ccw(b, c, q) == 0 {
            self.split_edge(e + 1, p)
        } else if ccw(c, a, q) == 0 {
            self.split_edge(e + 2, p)
        } else {
            let v = self.add_vertex(p);
            let xs = self.triangle(t);
            let ext = [e, e + 1, e + 2].map(|k| self.twin[k as usize]);
            let n = self.num_triangles() as u32;
            self.fan(v, &[t, n, n + 1], &xs, &ext, true);
            v
        }
    }

    fn add_vertex(&mut self, p: [u32; 2]) -> u32 {
        self.coords.push(p);
        self.coords.len() as u32 - 1
    }

    /// Splits half-edge `e` (and its twin's triangle, if any) at `p`, which must lie
    /// strictly inside the edge. Returns the new vertex id.
    fn split_edge(&mut self, e: u32, p: [u32; 2]) -> u32 {
        let v = self.add_vertex(p);
        let ta = e / 3;
        let (u, w) = (self.tri[e as usize], self.tri[prev(e) as usize]);
        let vv = self.tri[next(e) as usize];
        let ext_vw = self.twin[next(e) as usize];
        let ext_wu = self.twin[prev(e) as usize];
        let b = self.twin[e as usize];
        let n = self.num_triangles() as u32;
        if b == NONE {
            self.fan(v, &[ta, n], &[vv, w, u], &[ext_vw, ext_wu], false);
        } else {
            let tb = b / 3;
            let z = self.tri[prev(b) as usize];
            let ext_uz = self.twin[next(b) as usize];
            let ext_zv = self.twin[prev(b) as usize];
            self.fan(
                v,
                &[tb, n, ta, n + 1],
                &[u, z, vv, w],
                &[ext_uz, ext_zv, ext_vw, ext_wu],
                true,
            );
        }
        v
    }

    /// Writes the fan of triangles `(xs[i], xs[i + 1], v)` into `slots` (a new slot is the
    /// next unused one), half-edge `xs[i] -> xs[i + 1]` twinned with `ext[i]`; `closed`
    /// wraps `xs` around `v`, else the fan's two outer sides are boundary. Then legalises
    /// the edges opposite `v`.
    fn fan(&mut self, v: u32, slots: &[u32], xs: &[u32], ext: &[u32], closed: bool) {
        let k = slots.len();
        for i in 0..k {
            let x1 = if i + 1 < xs.len() { xs[i + 1] } else { xs[0] };
            self.set_tri(slots[i], [xs[i], x1, v]);
        }
        for i in 0..k {
            let t = 3 * slots[i];
            self.link(t, ext[i]);
            if i + 1 < k {
                self.link(t + 1, 3 * slots[i + 1] + 2);
            } else if closed {
                self.link(t + 1, 3 * slots[0] + 2);
            } else {
                self.link(t + 1, NONE);
            }
        }
        if !closed {
            self.link(3 * slots[0] + 2, NONE);
        }
        for &s in slots {
            self.legalize(3 * s);
        }
    }

    fn set_tri(&mut self, t: u32, v: [u32; 3]) {
        let e = 3 * t as usize;
        if e == self.tri.len() {
            self.tri.extend_from_slice(&v);
            self.twin.extend_from_slice(&[NONE; 3]);
            self.is_dirty.push(false);
        } else {
            self.tri[e..e + 3].copy_from_slice(&v);
        }
        if !self.is_dirty[t as usize] {
            self.is_dirty[t as usize] = true;
            self.dirty.push(t);
        }
    }

    /// Makes `e` and `o` twins (the triangle of `e` must be written), or marks `e` as a
    /// boundary half-edge for `o == NONE`.
    #[inline]
    fn link(&mut self, e: u32, o: u32) {
        self.twin[e as usize] = o;
        if o == NONE {
            if let Some(h) = self.hull_out.get_mut(self.tri[e as usize] as usize) {
                *h = e;
            }
        } else {
            self.twin[o as usize] = e;
        }
    }

    #[inline]
    fn point(&self, v: u32) -> [i64; 2] {
        let q = self.coords[v as usize];
        [q[0] as i64, q[1] as i64]
    }

    /// Flips half-edge `e0` and, recursively, the edges it exposes, while the vertex
    /// across an edge is strictly inside the circumcircle of the edge's triangle. The
    /// vertex opposite every stacked edge (`tri[prev(e)]`) is the newly inserted one.
    fn legalize(&mut self, e0: u32) {
        self.stack.push(e0);
        while let Some(a) = self.stack.pop() {
            let b = self.twin[a as usize];
            if b == NONE {
                continue;
            }
            let (an, ap) = (next(a), prev(a));
            let (bn, bp) = (next(b), prev(b));
            let u = self.tri[a as usize];
            let v = self.tri[an as usize];
            let p = self.tri[ap as usize];
            let q = self.tri[bp as usize];
            if !in_circle(self.point(u), self.point(v), self.point(p), self.point(q)) {
                continue;
            }
            let (har, hal) = (self.twin[ap as usize], self.twin[an as usize]);
            let (hbn, hbp) = (self.twin[bn as usize], self.twin[bp as usize]);
            let (ta, tb) = (a / 3, b / 3);
            self.set_tri(ta, [p, u, q]);
            self.set_tri(tb, [q, v, p]);
            let (ea, eb) = (3 * ta, 3 * tb);
            self.link(ea, har);
            self.link(ea + 1, hbn);
            self.link(ea + 2, eb + 2);
            self.link(eb, hbp);
            self.link(eb + 1, hal);
            self.stack.push(eb);
            self.stack.push(ea + 1);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Rng(u64);
    impl Rng {
        fn below(&mut self, m: u32) -> u32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 33) % m as u64) as u32
        }
    }

    /// Twins, orientation, area, boundary and the empty-circumcircle property.
    fn check(m: &Mesh, rect: SampleRect) {
        let n = m.num_triangles() as u32;
        let mut area = 0;
        for t in 0..n {
            let [a, b, c] = m.corners(t);
            assert!(ccw(a, b, c) > 0, "triangle {t} not CCW");
            area += ccw(a, b, c);
            for k in 0..3 {
                let e = 3 * t + k;
                let o = m.twin[e as usize];
                if o == NONE {
                    let (p, q) = (m.point(m.tri[e as usize]), m.point(m.tri[next(e) as usize]));
                    let on = |i: usize, v: u32| p[i] == v as i64 && q[i] == v as i64;
                    assert!(on(0, rect.c0) || on(0, rect.c1) || on(1, rect.r0) || on(1, rect.r1));
                    assert_eq!(m.hull_out[m.tri[e as usize] as usize], e);
                } else {
                    assert_eq!(m.twin[o as usize], e);
                    assert_eq!(m.tri[o as usize], m.tri[next(e) as usize]);
                    assert_eq!(m.tri[next(o) as usize], m.tri[e as usize]);
                }
            }
            for v in 0..m.coords.len() as u32 {
                assert!(
                    !in_circle(a, b, c, m.point(v)),
                    "vertex {v} in circle of {t}"
                );
            }
        }
        let w = (rect.c1 - rect.c0) as i64;
        let h = (rect.r1 - rect.r0) as i64;
        assert_eq!(area, 2 * w * h);
    }

    #[test]
    fn predicates_have_world_orientation() {
        // world CCW = down the left side then right along the bottom (rows run south)
        assert!(ccw([0, 0], [0, 1], [1, 1]) > 0);
        assert!(in_circle([0, 0], [0, 2], [2, 2], [1, 1]));
        assert!(!in_circle([0, 0], [0, 2], [2, 2], [2, 0])); // cocircular
        assert!(!in_circle([0, 0], [0, 2], [2, 2], [5, 0]));
    }

    #[test]
    fn random_insertions_stay_delaunay() {
        let mut rng = Rng(7);
        for case in 0..300 {
            let rect = SampleRect {
                c0: rng.below(5),
                r0: rng.below(5),
                c1: 6 + rng.below(12),
                r1: 6 + rng.below(12),
            };
            let mut border = Vec::new();
            for _ in 0..rng.below(12) {
                let (c, r) = (
                    rect.c0 + rng.below(rect.c1 - rect.c0 + 1),
                    rect.r0 + rng.below(rect.r1 - rect.r0 + 1),
                );
                border.push(match rng.below(4) {
                    0 => [rect.c0, r],
                    1 => [rect.c1, r],
                    2 => [c, rect.r0],
                    _ => [c, rect.r1],
                });
            }
            border.push([rect.c0 + 1, rect.r0 + 1]); // not on the boundary: ignored
            let mut m = Mesh::rectangle(rect, &border);
            check(&m, rect);
            let mut dirty = Vec::new();
            m.take_dirty(&mut dirty);
            assert_eq!(dirty.len(), m.num_triangles());
            for _ in 0..rng.below(40) {
                let p = [
                    rect.c0 + 1 + rng.below(rect.c1 - rect.c0 - 1),
                    rect.r0 + 1 + rng.below(rect.r1 - rect.r0 - 1),
                ];
                if m.coords.contains(&p) {
                    continue;
                }
                let q = [p[0] as i64, p[1] as i64];
                let t = (0..m.num_triangles() as u32)
                    .find(|&t| {
                        let [a, b, c] = m.corners(t);
                        ccw(a, b, q) >= 0 && ccw(b, c, q) >= 0 && ccw(c, a, q) >= 0
                    })
                    .expect("covered");
                let before = m.num_triangles();
                m.insert(t, p);
                m.take_dirty(&mut dirty);
                // every new slot is reported, each once
                assert!((before..m.num_triangles()).all(|s| dirty.contains(&(s as u32))));
                let mut sorted = dirty.clone();
                sorted.sort_unstable();
                sorted.dedup();
                assert_eq!(sorted.len(), dirty.len());
                check(&m, rect);
            }
            assert_eq!(
                m.coords.len() * 2 - m.hull_out.len() - 2,
                m.num_triangles(),
                "{case}"
            );
        }
    }
}
