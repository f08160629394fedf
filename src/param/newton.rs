//! Global finish: projected-Newton minimisation of the symmetric Dirichlet energy over all
//! UVs at once, starting from a flip-free layout.
//!
//! Each iteration assembles the gradient and the Hessian of E = Σ A_t Ψ(J_t) / Σ A_t with
//! every triangle's Hessian projected to PSD analytically ([`super::sym_dirichlet`]), adds
//! a small multiple of the identity (the energy is invariant under translations and
//! rotations, so the Hessian is singular), factors it with faer's sparse Cholesky (the
//! symbolic analysis, with its fill-reducing ordering, is done once) and solves for the
//! Newton direction d. The step starts at min(1, 0.8 t*) where t* is the first step at
//! which any triangle would reach det J = 0 (det J(t) is a quadratic in t, Smith &
//! Schaefer 2015), so no iterate ever flips a triangle; an Armijo backtracking search
//! then requires a sufficient decrease, and, when the boundary of the start does not
//! cross itself, a boundary that still does not cross itself (a filter that keeps the
//! chart globally injective). It stops when the Newton decrement −gᵀd/2 or an
//! iteration's decrease falls below `tolerance` × (E − 4) + 10⁻⁷ (E − 4 is the excess over
//! an isometry; the floor stops developable cells once numerically isometric), or after
//! `max_iterations`.
//!
//! Sequential and deterministic.

use super::energy::FaceGeom;
use super::overlap::BoundaryLoop;
use super::sym_dirichlet;
use faer::linalg::solvers::Solve;
use faer::sparse::linalg::solvers::{Llt, SymbolicLlt};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Mat, Side};

/// What the global finish did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct NewtonStats {
    /// Newton iterations taken.
    pub iterations: u32,
    /// Mean symmetric Dirichlet energy before and after.
    pub energy_before: f64,
    pub energy_after: f64,
}

/// Minimises the area-weighted mean symmetric Dirichlet energy of `uvs` (a flip-free
/// layout of `triangles` over the 3D `pos`, all vertices used) in place. `observe` sees the
/// start and every accepted iterate.
/// `keep_boundary_simple`: reject steps whose boundary crosses itself (only meaningful if
/// the start's boundary does not).
pub(crate) fn minimize(
    pos: &[[f64; 3]],
    triangles: &[[u32; 3]],
    uvs: &mut [[f64; 2]],
    max_iterations: u32,
    tolerance: f64,
    boundary: Option<&BoundaryLoop>,
    observe: &mut dyn FnMut(&[[f64; 2]]),
) -> NewtonStats {
    let n = uvs.len();
    let geom: Vec<FaceGeom> = triangles
        .iter()
        .map(|t| FaceGeom::new(pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]))
        .collect();
    let total_area: f64 = geom.iter().map(|g| g.area).sum();
    let e0 = mean_energy(&geom, triangles, uvs, total_area);
    let mut stats = NewtonStats {
        iterations: 0,
        energy_before: e0,
        energy_after: e0,
    };
    observe(uvs);
    if max_iterations == 0 || n < 3 || !(total_area > 0.0) || !e0.is_finite() {
        return stats;
    }
    let pattern = Pattern::new(n, triangles);
    let Ok(symbolic) = SymbolicLlt::try_new(pattern.symbolic.as_ref(), Side::Lower) else {
        return stats;
    };
    let mut e = e0;
    let mut vals = vec![0.0; pattern.nnz()];
    let mut grad = vec![0.0; 2 * n];
    for _ in 0..max_iterations {
        vals.iter_mut().for_each(|v| *v = 0.0);
        grad.iter_mut().for_each(|v| *v = 0.0);
        let mut trace = 0.0;
        for (t, tri) in triangles.iter().enumerate() {
            let g = &geom[t];
            let uv = [
                uvs[tri[0] as usize],
                uvs[tri[1] as usize],
                uvs[tri[2] as usize],
            ];
            let Some((_, pg, ph)) = sym_dirichlet::eval(&g.jacobian(uv)) else {
                return stats; // cannot happen from a flip-free start
            };
            let w = g.area / total_area;
            // dF[r][c]/d uv_k[r] = grad_k[c]; dof (k, r) -> local 2k + r.
            let mut d = [[0.0; 4]; 6]; // d[local dof][F index]
            for k in 0..3 {
                for r in 0..2 {
                    for c in 0..2 {
                        d[2 * k + r][2 * r + c] = g.grad[k][c];
                    }
                }
            }
            let mut dh = [[0.0; 4]; 6];
            for a in 0..6 {
                for j in 0..4 {
                    dh[a][j] = (0..4).map(|i| d[a][i] * ph[i][j]).sum();
                }
            }
            for a in 0..6 {
                let ga: f64 = (0..4).map(|i| d[a][i] * pg[i]).sum();
                grad[2 * tri[a / 2] as usize + a % 2] += w * ga;
                for b in 0..6 {
                    let (ra, rb) = (
                        2 * tri[a / 2] as usize + a % 2,
                        2 * tri[b / 2] as usize + b % 2,
                    );
                    if ra < rb {
                        continue; // lower triangle only
                    }
                    // (ra == rb only for a == b: a triangle's corners are distinct)
                    let hab: f64 = (0..4).map(|j| dh[a][j] * d[b][j]).sum();
                    vals[pattern.slot(t, a, b)] += w * hab;
                    if ra == rb {
                        trace += w * hab;
                    }
                }
            }
        }
        // Regularise: the energy is invariant under rigid motions.
        let mut mu = 1e-8 * trace / (2 * n) as f64;
        let dir = loop {
            let mut v = vals.clone();
            for &s in &pattern.diag {
                v[s] += mu;
            }
            let m = SparseColMatRef::new(pattern.symbolic.as_ref(), &v);
            match Llt::try_new_with_symbolic(symbolic.clone(), m, Side::Lower) {
                Ok(llt) => {
                    let mut rhs = Mat::from_fn(2 * n, 1, |i, _| -grad[i]);
                    llt.solve_in_place(rhs.as_mut());
                    break Some((0..2 * n).map(|i| rhs[(i, 0)]).collect::<Vec<f64>>());
                }
                Err(_) if mu < trace => mu = (mu * 100.0).max(1e-12),
                Err(_) => break None,
            }
        };
        let Some(dir) = dir else { break };
        let slope: f64 = grad.iter().zip(&dir).map(|(g, d)| g * d).sum();
        // Converged: the predicted decrease is below the tolerance's share of the excess
        // (plus an absolute floor, so a developable cell stops once it is numerically
        // isometric instead of chasing relative gains on a vanishing excess).
        let enough = tolerance * (e - 4.0).max(0.0) + ABSOLUTE_FLOOR;
        if !(slope < 0.0) || -0.5 * slope <= enough {
            break;
        }
        let t_max = max_step(&geom, triangles, uvs, &dir);
        let mut t = (0.8 * t_max).min(1.0);
        let mut trial = uvs.to_vec();
        let mut accepted = false;
        for _ in 0..40 {
            for v in 0..n {
                trial[v] = [uvs[v][0] + t * dir[2 * v], uvs[v][1] + t * dir[2 * v + 1]];
            }
            let et = mean_energy(&geom, triangles, &trial, total_area);
            if et <= e + 1e-4 * t * slope && boundary.is_none_or(|b| !b.overlaps(&trial)) {
                accepted = true;
                uvs.copy_from_slice(&trial);
                observe(uvs);
                stats.iterations += 1;
                let gain = e - et;
                let enough = tolerance * (e - 4.0).max(0.0) + ABSOLUTE_FLOOR;
                e = et;
                if gain < enough {
                    stats.energy_after = e;
                    return stats;
                }
                break;
            }
            t *= 0.5;
        }
        if !accepted {
            break;
        }
    }
    stats.energy_after = e;
    stats
}

/// Excess changes below this (on a mean energy of 4 + excess) count as converged.
const ABSOLUTE_FLOOR: f64 = 1e-7;

/// Area-weighted mean Ψ (+∞ if any triangle is flipped or degenerate).
fn mean_energy(
    geom: &[FaceGeom],
    triangles: &[[u32; 3]],
    uvs: &[[f64; 2]],
    total_area: f64,
) -> f64 {
    let mut s = 0.0;
    for (g, t) in geom.iter().zip(triangles) {
        let j = g.jacobian([uvs[t[0] as usize], uvs[t[1] as usize], uvs[t[2] as usize]]);
        s += g.area * sym_dirichlet::energy(&j);
    }
    s / total_area
}

/// The largest t such that no triangle's det J reaches 0 on [0, t) along `dir`
/// (+∞ if none ever does).
fn max_step(geom: &[FaceGeom], triangles: &[[u32; 3]], uvs: &[[f64; 2]], dir: &[f64]) -> f64 {
    let mut t_min = f64::INFINITY;
    for (g, t) in geom.iter().zip(triangles) {
        let uv = [uvs[t[0] as usize], uvs[t[1] as usize], uvs[t[2] as usize]];
        let du = [0, 1, 2].map(|k| [dir[2 * t[k] as usize], dir[2 * t[k] as usize + 1]]);
        let j = g.jacobian(uv);
        let dj = g.jacobian(du);
        // det(J + t dJ) = det J + t (J00 dJ11 + dJ00 J11 − J01 dJ10 − dJ01 J10) + t² det dJ
        let c0 = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let c1 = j[0][0] * dj[1][1] + dj[0][0] * j[1][1] - j[0][1] * dj[1][0] - dj[0][1] * j[1][0];
        let c2 = dj[0][0] * dj[1][1] - dj[0][1] * dj[1][0];
        if let Some(r) = smallest_positive_root(c2, c1, c0) {
            t_min = t_min.min(r);
        }
    }
    t_min
}

/// Smallest positive root of a t² + b t + c (c > 0), if any.
fn smallest_positive_root(a: f64, b: f64, c: f64) -> Option<f64> {
    let scale = a.abs().max(b.abs()).max(c.abs());
    if a.abs() <= 1e-14 * scale {
        return if b < 0.0 { Some(-c / b) } else { None };
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return None;
    }
    let sq = disc.sqrt();
    // Numerically stable pair of roots.
    let q = -0.5 * (b + b.signum() * sq);
    let r1 = q / a;
    let r2 = if q != 0.0 { c / q } else { f64::INFINITY };
    [r1, r2]
        .into_iter()
        .filter(|r| *r > 0.0)
        .min_by(|x, y| x.total_cmp(y))
}

/// The lower-triangle CSC pattern of the 2n x 2n Hessian (dof 2v + r) and, per triangle,
/// where each local entry goes.
struct Pattern {
    symbolic: SymbolicSparseColMat<usize>,
    /// Per triangle, 6x6 slots (usize::MAX for upper-triangle entries).
    slots: Vec<[[usize; 6]; 6]>,
    /// Slot of each diagonal entry.
    diag: Vec<usize>,
}

impl Pattern {
    fn new(n: usize, triangles: &[[u32; 3]]) -> Pattern {
        // Vertex adjacency including the vertex itself, only neighbours >= v.
        let mut adj: Vec<Vec<u32>> = (0..n as u32).map(|v| vec![v]).collect();
        for t in triangles {
            for a in 0..3 {
                for b in 0..3 {
                    if t[a] > t[b] {
                        adj[t[b] as usize].push(t[a]);
                    }
                }
            }
        }
        for a in &mut adj {
            a.sort_unstable();
            a.dedup();
        }
        let mut col_ptr = Vec::with_capacity(2 * n + 1);
        let mut row_idx = Vec::new();
        col_ptr.push(0usize);
        for v in 0..n {
            for s in 0..2 {
                for &w in &adj[v] {
                    for r in 0..2 {
                        let row = 2 * w as usize + r;
                        if row >= 2 * v + s {
                            row_idx.push(row);
                        }
                    }
                }
                col_ptr.push(row_idx.len());
            }
        }
        let find = |row: usize, col: usize| -> usize {
            let lo = col_ptr[col];
            let hi = col_ptr[col + 1];
            lo + row_idx[lo..hi].binary_search(&row).unwrap_or(0)
        };
        let diag: Vec<usize> = (0..2 * n).map(|i| find(i, i)).collect();
        let slots = triangles
            .iter()
            .map(|t| {
                let mut s = [[usize::MAX; 6]; 6];
                for a in 0..6 {
                    for b in 0..6 {
                        let (ra, rb) =
                            (2 * t[a / 2] as usize + a % 2, 2 * t[b / 2] as usize + b % 2);
                        if ra >= rb {
                            s[a][b] = find(ra, rb);
                        }
                    }
                }
                s
            })
            .collect();
        let symbolic = SymbolicSparseColMat::new_checked(2 * n, 2 * n, col_ptr, None, row_idx);
        Pattern {
            symbolic,
            slots,
            diag,
        }
    }

    fn nnz(&self) -> usize {
        self.symbolic.row_idx().len()
    }

    fn slot(&self, t: usize, a: usize, b: usize) -> usize {
        self.slots[t][a][b]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::param::tests::grid;

    #[test]
    fn roots() {
        // (t - 2)(t - 3) = t² - 5t + 6
        assert!((smallest_positive_root(1.0, -5.0, 6.0).unwrap() - 2.0).abs() < 1e-12);
        assert!(smallest_positive_root(1.0, 5.0, 6.0).is_none());
        assert!((smallest_positive_root(0.0, -2.0, 1.0).unwrap() - 0.5).abs() < 1e-12);
    }

    #[test]
    fn converges_to_an_isometry_on_a_developable_wall() {
        // A folded sheet (a 60° ridge) is developable: the optimum is symD = 4 exactly.
        let m = grid(9, |x, _| if x < 4.0 { x * 1.7 } else { (8.0 - x) * 1.7 });
        // Start: the orthographic layout (flip-free, distorted).
        let mut uvs: Vec<[f64; 2]> = m.positions.iter().map(|p| [p[0], p[1]]).collect();
        let st = minimize(
            &m.positions,
            &m.triangles,
            &mut uvs,
            50,
            1e-9,
            None,
            &mut |_| {},
        );
        assert!(st.energy_before > 4.5, "{st:?}");
        assert!(st.energy_after - 4.0 < 1e-6, "{st:?}");
        assert!(st.iterations < 30, "{st:?}");
    }

    #[test]
    fn energy_never_rises_and_nothing_flips() {
        let m = grid(12, |x, y| {
            3.0 * ((0.7 * x).sin() * (0.5 * y).cos()) + 0.2 * x * y
        });
        let mut uvs: Vec<[f64; 2]> = m.positions.iter().map(|p| [p[0], p[1]]).collect();
        let mut last = f64::INFINITY;
        for _ in 0..6 {
            let st = minimize(
                &m.positions,
                &m.triangles,
                &mut uvs,
                1,
                0.0,
                None,
                &mut |_| {},
            );
            assert!(st.energy_after <= st.energy_before && st.energy_after <= last);
            last = st.energy_after;
            let met = crate::param::chart_metrics(&m.positions, &m.triangles, &uvs, None).unwrap();
            assert_eq!(met.flipped, 0);
        }
    }
}
