//! Global injectivity of a chart's free boundary: does the boundary polygon cross itself?
//!
//! A flip-free chart can still fold over itself when its boundary wraps around (a strongly
//! curved or twisted surface whose low-distortion layout turns by more than a full circle).
//! [`BoundaryLoop`] holds the boundary vertices in order; [`BoundaryLoop::crossings`]
//! counts pairs of non-adjacent boundary segments that intersect (touching counts), by a
//! sweep over the segments sorted by their smallest u: O(B log B + pairs whose u-ranges
//! overlap). A chart with no flips and no crossing is injective (a local homeomorphism of
//! a disc whose boundary is a simple curve is a bijection onto its interior).

/// The boundary of a disc mesh as one closed loop of vertex indices (the orientation of
/// its faces).
#[derive(Clone, Debug, Default)]
pub(crate) struct BoundaryLoop {
    /// Vertex indices in boundary order; segment i joins `verts[i]` and `verts[i+1 mod n]`.
    pub verts: Vec<u32>,
}

impl BoundaryLoop {
    /// The boundary loop of a manifold disc with `nv` vertices (the edges a→b whose
    /// reverse is not an edge). Empty if there is no boundary edge.
    pub fn new(nv: usize, triangles: &[[u32; 3]]) -> BoundaryLoop {
        let mut edges: Vec<(u32, u32)> = Vec::with_capacity(3 * triangles.len());
        for t in triangles {
            for k in 0..3 {
                edges.push((t[k], t[(k + 1) % 3]));
            }
        }
        edges.sort_unstable();
        let has = |a: u32, b: u32| edges.binary_search(&(a, b)).is_ok();
        let mut next = vec![u32::MAX; nv];
        let mut start = u32::MAX;
        for &(a, b) in &edges {
            if !has(b, a) && (a as usize) < nv {
                next[a as usize] = b;
                start = start.min(a);
            }
        }
        if start == u32::MAX {
            return BoundaryLoop::default();
        }
        let mut verts = vec![start];
        let mut cur = next[start as usize];
        while cur != start && cur != u32::MAX && verts.len() <= nv {
            verts.push(cur);
            cur = next[cur as usize];
        }
        BoundaryLoop { verts }
    }

    /// Number of pairs of non-adjacent boundary segments of the layout `uvs` that
    /// intersect or touch (0 = the boundary is a simple closed curve).
    pub fn crossings(&self, uvs: &[[f64; 2]]) -> usize {
        self.count(uvs, usize::MAX)
    }

    /// True if the boundary of `uvs` crosses itself anywhere (stops at the first crossing).
    pub fn overlaps(&self, uvs: &[[f64; 2]]) -> bool {
        self.count(uvs, 1) > 0
    }

    /// Position of every vertex in the loop (`usize::MAX` for interior vertices).
    pub fn index_of(&self, nv: usize) -> Vec<usize> {
        let mut ix = vec![usize::MAX; nv];
        for (i, &v) in self.verts.iter().enumerate() {
            ix[v as usize] = i;
        }
        ix
    }

    /// True if moving the boundary vertex at loop position `i` to `x` (all others as in
    /// `uvs`) makes one of its two segments meet a non-adjacent boundary segment. O(B).
    pub fn move_crosses(&self, uvs: &[[f64; 2]], i: usize, x: [f64; 2]) -> bool {
        let n = self.verts.len();
        if n < 4 {
            return false;
        }
        let at = |k: usize| {
            if k == i {
                x
            } else {
                uvs[self.verts[k] as usize]
            }
        };
        let (prev, next) = ((i + n - 1) % n, (i + 1) % n);
        for (a, b) in [(prev, i), (i, next)] {
            let (pa, pb) = (at(a), at(b));
            for j in 0..n {
                let j1 = (j + 1) % n;
                // skip the segment itself and the ones sharing an endpoint with it
                if j == a || j == b || j1 == a || j1 == b {
                    continue;
                }
                if segments_meet(pa, pb, at(j), at(j1)) {
                    return true;
                }
            }
        }
        false
    }

    fn count(&self, uvs: &[[f64; 2]], stop_at: usize) -> usize {
        let n = self.verts.len();
        if n < 4 {
            return 0;
        }
        let seg = |i: usize| {
            (
                uvs[self.verts[i] as usize],
                uvs[self.verts[(i + 1) % n] as usize],
            )
        };
        let mut order: Vec<(f64, f64, usize)> = (0..n)
            .map(|i| {
                let (a, b) = seg(i);
                (a[0].min(b[0]), a[0].max(b[0]), i)
            })
            .collect();
        order.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.2.cmp(&y.2)));
        let mut found = 0;
        for (k, &(_, hi, i)) in order.iter().enumerate() {
            let (a, b) = seg(i);
            for &(lo2, _, j) in &order[k + 1..] {
                if lo2 > hi {
                    break;
                }
                let adjacent = (i + 1) % n == j || (j + 1) % n == i;
                if adjacent {
                    continue;
                }
                let (c, d) = seg(j);
                if segments_meet(a, b, c, d) {
                    found += 1;
                    if found >= stop_at {
                        return found;
                    }
                }
            }
        }
        found
    }
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

fn on_segment(a: [f64; 2], b: [f64; 2], p: [f64; 2]) -> bool {
    p[0] >= a[0].min(b[0])
        && p[0] <= a[0].max(b[0])
        && p[1] >= a[1].min(b[1])
        && p[1] <= a[1].max(b[1])
}

/// Closed segments ab and cd share a point.
fn segments_meet(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let (d1, d2) = (orient(c, d, a), orient(c, d, b));
    let (d3, d4) = (orient(a, b, c), orient(a, b, d));
    if ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
    {
        return true;
    }
    (d1 == 0.0 && on_segment(c, d, a))
        || (d2 == 0.0 && on_segment(c, d, b))
        || (d3 == 0.0 && on_segment(a, b, c))
        || (d4 == 0.0 && on_segment(a, b, d))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_loop_is_simple_and_a_bow_tie_is_not() {
        // Two triangles forming the square 0-1-2-3.
        let tris = [[0, 1, 2], [0, 2, 3]];
        let bl = BoundaryLoop::new(4, &tris);
        assert_eq!(bl.verts, vec![0, 1, 2, 3]);
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert_eq!(bl.crossings(&sq), 0);
        let bow = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
        assert_eq!(bl.crossings(&bow), 1);
        assert!(bl.overlaps(&bow));
    }

    #[test]
    fn a_single_move_is_checked_against_the_rest() {
        let tris = [[0, 1, 2], [0, 2, 3]];
        let bl = BoundaryLoop::new(4, &tris);
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(!bl.move_crosses(&sq, 2, [0.9, 0.8]));
        // Vertex 2 dragged left of the square: segment 1-2 crosses segment 3-0.
        assert!(bl.move_crosses(&sq, 2, [-0.5, 0.5]));
        assert_eq!(bl.index_of(4), vec![0, 1, 2, 3]);
    }

    #[test]
    fn touching_counts_as_overlap() {
        // A pentagon-like loop whose vertex 3 lies exactly on segment 0-1.
        let tris = [[0, 1, 2], [0, 2, 3], [0, 3, 4]];
        let bl = BoundaryLoop::new(5, &tris);
        let uv = [[0.0, 0.0], [2.0, 0.0], [2.0, 2.0], [1.0, 0.0], [0.0, 2.0]];
        assert!(bl.overlaps(&uv));
    }
}
