//! Input validation and the mutable adjacency used by simplification and refinement.
//!
//! [`Topo`] stores triangles by [`FaceId`] and, per vertex ([`VertId`]), the list of alive
//! faces around it. Edge collapses and their undo only flip `alive` flags and rewrite one
//! corner of a face, so face ids stay stable across the whole hierarchy.

use super::ParamMesh;
use crate::error::{Error, Result};

/// Index of a vertex in the input mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct VertId(pub u32);

/// Index of a triangle in the input mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) struct FaceId(pub u32);

impl VertId {
    pub(crate) fn ix(self) -> usize {
        self.0 as usize
    }
}
impl FaceId {
    pub(crate) fn ix(self) -> usize {
        self.0 as usize
    }
}

fn bad(msg: impl Into<String>) -> Error {
    Error::BadOption(format!("parameterization input mesh: {}", msg.into()))
}

/// Twice the area of the 3D triangle (length of the cross product).
pub(crate) fn area2_3d(a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let n = cross3(sub3(b, a), sub3(c, a));
    (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt()
}

pub(crate) fn sub3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
pub(crate) fn cross3(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
pub(crate) fn dot3(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
pub(crate) fn len3(a: [f64; 3]) -> f64 {
    dot3(a, a).sqrt()
}

/// Checks that `mesh` is a consistently oriented, connected, manifold triangulated disc
/// with finite coordinates, no unused vertices and no (numerically) zero-area triangles.
pub(crate) fn validate(mesh: &ParamMesh) -> Result<()> {
    let nv = mesh.positions.len();
    let nf = mesh.triangles.len();
    if nf == 0 {
        return Err(bad("no triangles"));
    }
    if nv > u32::MAX as usize / 2 || nf > u32::MAX as usize / 2 {
        return Err(bad("too many vertices or triangles"));
    }
    for (i, p) in mesh.positions.iter().enumerate() {
        if !p.iter().all(|c| c.is_finite()) {
            return Err(bad(format!("vertex {i} has a non-finite coordinate {p:?}")));
        }
    }
    let mut used = vec![false; nv];
    // Directed edges, to check orientation consistency and manifold edges.
    let mut directed: Vec<(u32, u32, u32)> = Vec::with_capacity(nf * 3);
    let mut sorted_tris: Vec<([u32; 3], usize)> = Vec::with_capacity(nf);
    for (f, t) in mesh.triangles.iter().enumerate() {
        for &i in t {
            if i as usize >= nv {
                return Err(bad(format!(
                    "triangle {f} refers to vertex {i}, but there are only {nv} vertices"
                )));
            }
            used[i as usize] = true;
        }
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return Err(bad(format!("triangle {f} {t:?} repeats a vertex")));
        }
        let (a, b, c) = (
            mesh.positions[t[0] as usize],
            mesh.positions[t[1] as usize],
            mesh.positions[t[2] as usize],
        );
        let e = [len3(sub3(b, a)), len3(sub3(c, b)), len3(sub3(a, c))];
        let emax = e[0].max(e[1]).max(e[2]);
        if !(area2_3d(a, b, c) > 1e-14 * emax * emax) {
            return Err(bad(format!("triangle {f} {t:?} has zero area")));
        }
        for k in 0..3 {
            directed.push((t[k], t[(k + 1) % 3], f as u32));
        }
        let mut s = *t;
        s.sort_unstable();
        sorted_tris.push((s, f));
    }
    if let Some(i) = used.iter().position(|u| !u) {
        return Err(bad(format!("vertex {i} is not used by any triangle")));
    }
    sorted_tris.sort_unstable();
    for w in sorted_tris.windows(2) {
        if w[0].0 == w[1].0 {
            return Err(bad(format!(
                "triangles {} and {} use the same vertices {:?}",
                w[0].1, w[1].1, w[0].0
            )));
        }
    }
    directed.sort_unstable();
    for w in directed.windows(2) {
        if w[0].0 == w[1].0 && w[0].1 == w[1].1 {
            return Err(bad(format!(
                "edge {}->{} is used in the same direction by triangles {} and {} (inconsistent orientation or non-manifold edge)",
                w[0].0, w[0].1, w[0].2, w[1].2
            )));
        }
    }
    // Undirected edges: each in one or two faces (two means opposite directions, by the
    // check above, so more than two is impossible once directed edges are unique... except
    // a->b, b->a, a->b which is caught above).
    let mut undirected: Vec<(u32, u32)> = directed
        .iter()
        .map(|&(a, b, _)| (a.min(b), a.max(b)))
        .collect();
    undirected.sort_unstable();
    let mut ne = 0usize;
    let mut i = 0;
    while i < undirected.len() {
        let mut j = i + 1;
        while j < undirected.len() && undirected[j] == undirected[i] {
            j += 1;
        }
        if j - i > 2 {
            return Err(bad(format!(
                "edge {:?} is shared by more than two triangles",
                undirected[i]
            )));
        }
        ne += 1;
        i = j;
    }
    // Vertex links: each must be a single path or a single cycle.
    let topo = Topo::new(mesh);
    for v in 0..nv {
        let faces = &topo.vert_faces[v];
        // Link edges b->c for faces (v,b,c).
        let mut link: Vec<(u32, u32)> = faces
            .iter()
            .map(|&f| {
                let t = topo.faces[f.ix()];
                let k = t.iter().position(|&x| x == v as u32).unwrap_or(0);
                (t[(k + 1) % 3], t[(k + 2) % 3])
            })
            .collect();
        link.sort_unstable();
        let has_in = |x: u32| link.iter().any(|&(_, c)| c == x);
        let starts: Vec<u32> = link
            .iter()
            .map(|&(b, _)| b)
            .filter(|&b| !has_in(b))
            .collect();
        let (start, want) = match starts.len() {
            0 => (link[0].0, link.len()),
            1 => (starts[0], link.len()),
            _ => {
                return Err(bad(format!(
                    "vertex {v} is non-manifold (its triangles form {} separate fans)",
                    starts.len()
                )));
            }
        };
        let mut cur = start;
        let mut walked = 0;
        while let Ok(k) = link.binary_search_by(|&(b, _)| b.cmp(&cur)) {
            walked += 1;
            cur = link[k].1;
            if cur == start || walked > link.len() {
                break;
            }
        }
        if walked != want {
            return Err(bad(format!(
                "vertex {v} is non-manifold (its triangles form more than one fan)"
            )));
        }
    }
    // Connected + Euler characteristic 1 => a disc.
    let mut seen = vec![false; nv];
    let mut stack = vec![mesh.triangles[0][0] as usize];
    seen[stack[0]] = true;
    let mut count = 1;
    while let Some(v) = stack.pop() {
        for &f in &topo.vert_faces[v] {
            for &w in &topo.faces[f.ix()] {
                if !seen[w as usize] {
                    seen[w as usize] = true;
                    count += 1;
                    stack.push(w as usize);
                }
            }
        }
    }
    if count != nv {
        return Err(bad(format!(
            "mesh is not connected ({count} of {nv} vertices reachable from the first triangle)"
        )));
    }
    let euler = nv as i64 - ne as i64 + nf as i64;
    if euler != 1 {
        return Err(bad(format!(
            "mesh is not a disc (Euler characteristic {euler}, a disc has 1)"
        )));
    }
    Ok(())
}

/// Mutable triangle adjacency: faces by id with alive flags, faces around each vertex.
#[derive(Clone, Debug)]
pub(crate) struct Topo {
    /// Corner vertex indices of every face (current state; a collapsed corner is rewritten).
    pub faces: Vec<[u32; 3]>,
    /// Whether each face is part of the current (simplified) mesh.
    pub face_alive: Vec<bool>,
    /// Alive faces around each vertex (empty for removed vertices).
    pub vert_faces: Vec<Vec<FaceId>>,
    /// Whether each vertex is part of the current mesh.
    pub vert_alive: Vec<bool>,
    /// Whether each vertex lies on the disc boundary (invariant under the allowed collapses).
    pub boundary: Vec<bool>,
    /// Number of alive faces.
    pub alive_faces: usize,
}

impl Topo {
    /// Builds the adjacency of a (validated or not) mesh.
    pub fn new(mesh: &ParamMesh) -> Topo {
        let nv = mesh.positions.len();
        let mut vert_faces = vec![Vec::new(); nv];
        for (f, t) in mesh.triangles.iter().enumerate() {
            for &v in t {
                if (v as usize) < nv {
                    vert_faces[v as usize].push(FaceId(f as u32));
                }
            }
        }
        let mut topo = Topo {
            faces: mesh.triangles.clone(),
            face_alive: vec![true; mesh.triangles.len()],
            vert_faces,
            vert_alive: vec![true; nv],
            boundary: vec![false; nv],
            alive_faces: mesh.triangles.len(),
        };
        for v in 0..nv {
            let b = topo
                .neighbours(VertId(v as u32))
                .into_iter()
                .any(|w| topo.edge_faces(VertId(v as u32), w).len() == 1);
            topo.boundary[v] = b;
        }
        topo
    }

    /// Sorted, deduplicated neighbours of `v` in the current mesh.
    pub fn neighbours(&self, v: VertId) -> Vec<VertId> {
        let mut out: Vec<VertId> = Vec::with_capacity(8);
        for &f in &self.vert_faces[v.ix()] {
            for &w in &self.faces[f.ix()] {
                if w != v.0 {
                    out.push(VertId(w));
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Alive faces containing both `a` and `b`.
    pub fn edge_faces(&self, a: VertId, b: VertId) -> Vec<FaceId> {
        self.vert_faces[a.ix()]
            .iter()
            .copied()
            .filter(|f| self.faces[f.ix()].contains(&b.0))
            .collect()
    }

    /// The corner of face `f` opposite to edge {a, b}.
    pub fn opposite(&self, f: FaceId, a: VertId, b: VertId) -> VertId {
        let t = self.faces[f.ix()];
        VertId(
            t.iter()
                .copied()
                .find(|&x| x != a.0 && x != b.0)
                .unwrap_or(t[0]),
        )
    }

    /// The two other corners (in CCW order) of face `f` seen from its corner `v`.
    pub fn others(&self, f: FaceId, v: VertId) -> (VertId, VertId) {
        let t = self.faces[f.ix()];
        let k = t.iter().position(|&x| x == v.0).unwrap_or(0);
        (VertId(t[(k + 1) % 3]), VertId(t[(k + 2) % 3]))
    }
}
