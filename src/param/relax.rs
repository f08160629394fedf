//! Local relaxation: moves one vertex at a time to lower the energy of its 1-ring.
//!
//! Each move is a Newton step (analytic 2x2 Hessian of the 1-ring energy, gradient
//! direction when that Hessian is not positive definite) with an Armijo
//! backtracking line search. The step is first capped where the first incident triangle
//! would reach det = 0 (det J is linear in one vertex's UV), and every trial point has
//! finite energy, so a move can never flip a triangle.

use super::energy::{FaceGeom, det_slope, det2, energy, vertex_grad_hess};
use super::mesh::{Topo, VertId};
use super::overlap::BoundaryLoop;

/// Relaxation state: per-face 3D geometry (valid for alive faces) and the weight θ.
pub(crate) struct Relaxer {
    /// Geometry of every face id in its current corner assignment.
    pub geom: Vec<FaceGeom>,
    /// Area/angle balance θ.
    pub theta: f64,
    /// If set, moves of boundary vertices that would make the (full mesh's) boundary
    /// cross itself are rejected: the loop and each vertex's position in it.
    pub guard: Option<(BoundaryLoop, Vec<usize>)>,
}

/// What one relaxation call did.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct RelaxStats {
    /// Sweeps performed.
    pub sweeps: u32,
    /// Vertex moves attempted.
    pub moves: u64,
}

impl Relaxer {
    /// Recomputes the geometry of every alive face.
    pub fn refresh(&mut self, topo: &Topo, pos: &[[f64; 3]]) {
        self.geom.resize(topo.faces.len(), FaceGeom::default());
        for (f, t) in topo.faces.iter().enumerate() {
            if topo.face_alive[f] {
                self.geom[f] =
                    FaceGeom::new(pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]);
            }
        }
    }

    fn corners(
        topo: &Topo,
        uvs: &[[f64; 2]],
        f: usize,
        v: VertId,
        x: [f64; 2],
    ) -> ([[f64; 2]; 3], usize) {
        let t = topo.faces[f];
        let mut uv = [uvs[t[0] as usize], uvs[t[1] as usize], uvs[t[2] as usize]];
        let k = t.iter().position(|&w| w == v.0).unwrap_or(0);
        uv[k] = x;
        (uv, k)
    }

    /// Area-weighted energy of the faces around `v` with `v` at `x` (+∞ if one flips).
    fn local_energy(&self, topo: &Topo, uvs: &[[f64; 2]], v: VertId, x: [f64; 2]) -> f64 {
        let mut e = 0.0;
        for &f in &topo.vert_faces[v.ix()] {
            let (uv, _) = Self::corners(topo, uvs, f.ix(), v, x);
            let g = &self.geom[f.ix()];
            e += g.area * energy(&g.jacobian(uv), self.theta);
        }
        e
    }

    fn local_grad_hess(
        &self,
        topo: &Topo,
        uvs: &[[f64; 2]],
        v: VertId,
        x: [f64; 2],
    ) -> Option<(f64, [f64; 2], [[f64; 2]; 2])> {
        let mut e = 0.0;
        let mut gr = [0.0, 0.0];
        let mut hs = [[0.0; 2]; 2];
        for &f in &topo.vert_faces[v.ix()] {
            let (uv, k) = Self::corners(topo, uvs, f.ix(), v, x);
            let g = &self.geom[f.ix()];
            let (ef, gf, hf) = vertex_grad_hess(g, &g.jacobian(uv), k, self.theta)?;
            e += g.area * ef;
            for r in 0..2 {
                gr[r] += g.area * gf[r];
                for c in 0..2 {
                    hs[r][c] += g.area * hf[r][c];
                }
            }
        }
        Some((e, gr, hs))
    }

    /// Total area-weighted energy of the alive faces.
    pub fn total_energy(&self, topo: &Topo, uvs: &[[f64; 2]]) -> f64 {
        let mut e = 0.0;
        for (f, t) in topo.faces.iter().enumerate() {
            if topo.face_alive[f] {
                let g = &self.geom[f];
                e += g.area
                    * energy(
                        &g.jacobian([uvs[t[0] as usize], uvs[t[1] as usize], uvs[t[2] as usize]]),
                        self.theta,
                    );
            }
        }
        e
    }

    /// Moves `v` to lower its local energy; returns the energy decrease (>= 0) and the
    /// local energy before the move.
    pub fn optimize_vertex(&self, topo: &Topo, uvs: &mut [[f64; 2]], v: VertId) -> (f64, f64) {
        let x0 = uvs[v.ix()];
        let Some((e0, g0, h0)) = self.local_grad_hess(topo, uvs, v, x0) else {
            return (0.0, f64::INFINITY);
        };
        (self.optimize_from(topo, uvs, v, e0, g0, h0), e0)
    }

    fn optimize_from(
        &self,
        topo: &Topo,
        uvs: &mut [[f64; 2]],
        v: VertId,
        e0: f64,
        g0: [f64; 2],
        h0: [[f64; 2]; 2],
    ) -> f64 {
        let x0 = uvs[v.ix()];
        let gn = (g0[0] * g0[0] + g0[1] * g0[1]).sqrt();
        if !(gn > 0.0) || !gn.is_finite() {
            return 0.0;
        }
        // Ring scale: mean UV distance to the neighbours.
        let mut scale = 0.0;
        let mut n = 0;
        for &f in &topo.vert_faces[v.ix()] {
            let (p, _) = topo.others(f, v);
            let d = [uvs[p.ix()][0] - x0[0], uvs[p.ix()][1] - x0[1]];
            scale += (d[0] * d[0] + d[1] * d[1]).sqrt();
            n += 1;
        }
        if n == 0 || !(scale > 0.0) {
            return 0.0;
        }
        scale /= n as f64;
        // Already (numerically) at the local minimum: the first-order decrease over a
        // ring-sized move would be negligible.
        if gn * scale < 1e-9 * e0 {
            return 0.0;
        }
        let mut dir = [-g0[0] / gn * 0.25 * scale, -g0[1] / gn * 0.25 * scale];
        {
            let a = h0[0][0];
            let d = h0[1][1];
            let b = 0.5 * (h0[0][1] + h0[1][0]);
            let det = a * d - b * b;
            if a > 0.0 && det > 0.0 {
                let nd = [
                    -(d * g0[0] - b * g0[1]) / det,
                    -(-b * g0[0] + a * g0[1]) / det,
                ];
                let len = (nd[0] * nd[0] + nd[1] * nd[1]).sqrt();
                if len.is_finite() && nd[0] * g0[0] + nd[1] * g0[1] < 0.0 {
                    let cap = if len > scale { scale / len } else { 1.0 };
                    dir = [nd[0] * cap, nd[1] * cap];
                }
            }
        }
        // Barrier: largest t before any incident det reaches zero.
        let mut tmax = f64::INFINITY;
        for &f in &topo.vert_faces[v.ix()] {
            let (uv, k) = Self::corners(topo, uvs, f.ix(), v, x0);
            let g = &self.geom[f.ix()];
            let j = g.jacobian(uv);
            let d0 = det2(&j);
            let s = det_slope(g, &j, k);
            let slope = s[0] * dir[0] + s[1] * dir[1];
            if slope < 0.0 {
                tmax = tmax.min(d0 / -slope);
            }
        }
        let mut t: f64 = 1.0f64.min(0.9 * tmax);
        let slope = g0[0] * dir[0] + g0[1] * dir[1];
        for _ in 0..30 {
            let x = [x0[0] + t * dir[0], x0[1] + t * dir[1]];
            let e = self.local_energy(topo, uvs, v, x);
            let crosses = || match &self.guard {
                Some((bl, ix)) if ix[v.ix()] != usize::MAX => bl.move_crosses(uvs, ix[v.ix()], x),
                _ => false,
            };
            if e.is_finite() && e <= e0 + 1e-4 * t * slope && !crosses() {
                uvs[v.ix()] = x;
                return e0 - e;
            }
            t *= 0.5;
        }
        0.0
    }

    /// Relaxes starting from `start` (deterministic order); after each sweep the
    /// neighbours of the vertices that moved are queued for the next one. Stops when a
    /// sweep lowers the total energy by less than `tol` (relative) or after `max_sweeps`.
    pub fn relax(
        &self,
        topo: &Topo,
        uvs: &mut [[f64; 2]],
        start: Vec<VertId>,
        tol: f64,
        max_sweeps: u32,
    ) -> RelaxStats {
        let mut st = RelaxStats::default();
        let mut total = self.total_energy(topo, uvs);
        if !total.is_finite() || total <= 0.0 {
            // A flipped triangle (only possible if a placement failed): relax anyway,
            // vertices with a flipped face do not move.
            total = f64::MAX;
        }
        let mut queue = start;
        let mut mark = vec![u32::MAX; uvs.len()];
        while st.sweeps < max_sweeps && !queue.is_empty() {
            let mut dec = 0.0;
            let mut next = Vec::new();
            for &v in &queue {
                let (d, e0) = self.optimize_vertex(topo, uvs, v);
                st.moves += 1;
                dec += d;
                // Only a significant local change can make the neighbours worth revisiting.
                if d > tol * e0 {
                    for &f in &topo.vert_faces[v.ix()] {
                        for &w in &topo.faces[f.ix()] {
                            if mark[w as usize] != st.sweeps {
                                mark[w as usize] = st.sweeps;
                                next.push(VertId(w));
                            }
                        }
                    }
                }
            }
            st.sweeps += 1;
            let before = total;
            total -= dec;
            if dec <= tol * before {
                break;
            }
            queue = next;
        }
        st
    }
}
