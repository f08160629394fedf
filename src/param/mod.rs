//! Per-cell area/angle-preserving parameterization (Degener, Meseth & Klein 2003).
//!
//! Data types:
//! - [`ParamMesh`]: one cell's triangulated surface in a cell-local f64 frame (metres),
//!   a consistently oriented manifold disc, triangles counter-clockwise seen from +z.
//! - [`ParamOptions`]: the energy's area/angle balance θ, the relaxation budget, the
//!   global finish's budget and the texture size/gutter used for packing.
//! - [`Chart`]: one UV per input vertex, inside \[0,1\]², plus the similarity that placed
//!   the chart in the square and its [`ChartMetrics`].
//!
//! Method: the mesh is simplified by rounds of independent half-edge collapses down to one
//! triangle, which is laid out with its 3D shape; the rounds are then undone in reverse
//! order, each re-inserted vertex placed inside the kernel of its 1-ring, and after each
//! round the vertices are relaxed one at a time against the energy
//! E = (s1/s2 + s2/s1)·(s1·s2 + 1/(s1·s2))^θ (area-weighted, +∞ for flipped
//! triangles), so no step can create a flip. The UV area is kept equal to the 3D area
//! after every round. With θ = 1 (the symmetric Dirichlet energy) a global projected-Newton
//! finish then converges all UVs at once (`newton.rs`; other θ: an all-vertex relaxation).
//! If the chart's boundary crosses itself it is rebuilt from a Tutte layout with
//! crossing-free steps (`overlap.rs`); a planar projection with a lower energy than the
//! finished chart is finished too and kept if it stays lower (`planar.rs`).
//! Finally the chart is rotated to its minimum-area bounding rectangle and scaled uniformly
//! into the texture square. See docs/parameterization.md.

// `!(x > 0.0)` is deliberate throughout: it also rejects NaN. Small fixed-size
// matrix loops read better with indices.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

mod base;
mod collapse;
mod energy;
mod mesh;
mod metrics;
mod newton;
mod overlap;
mod pack;
mod planar;
mod relax;
mod split;
mod sym_dirichlet;

pub use metrics::{ChartMetrics, chart_metrics, degener_energy};

use crate::error::{Error, Result};
use mesh::{Topo, VertId};
use relax::Relaxer;

/// A cell's surface: positions in a cell-local frame (f64, metres; any offset is
/// accepted and removed internally) and triangles with indices into `positions`,
/// counter-clockwise seen from above (+z), forming one manifold disc.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ParamMesh {
    /// Vertex positions (x east, y north, z up), metres.
    pub positions: Vec<[f64; 3]>,
    /// Triangles as vertex indices, counter-clockwise seen from +z.
    pub triangles: Vec<[u32; 3]>,
}

/// Parameters of [`parameterize`].
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ParamOptions {
    /// Area/angle balance θ >= 0 of the energy: 0 is purely conformal, larger values
    /// penalise area distortion more. Default 1, where the energy equals the symmetric
    /// Dirichlet energy; on steep terrain cells it gives the lowest symmetric Dirichlet
    /// energy of the values measured (0, 0.5, 1, 2, 3; see docs/parameterization.md);
    /// VCGLib's default 3 trades more angle distortion for less area distortion.
    pub theta: f64,
    /// Relaxation after each refinement round stops when one sweep lowers the total
    /// energy by less than this fraction (>= 0). Default 1e-2: the finish does the rest
    /// (Newton for θ = 1; for θ ≠ 1 a relaxation of all vertices at min(this, 1e-4),
    /// ≤ 32 sweeps; docs/parameterization.md).
    pub relax_tolerance: f64,
    /// At most this many relaxation sweeps per refinement round. Default 4.
    pub max_sweeps: u32,
    /// Empty border, in texels of `texture_size`, kept on every side of the chart
    /// (>= 0, less than half the texture). Default 2.
    pub gutter_texels: f64,
    /// Texture edge length in texels the chart is packed for (>= 1). Default 256.
    pub texture_size: u32,
    /// Global finish (θ = 1, where the energy is the symmetric Dirichlet energy): at most
    /// this many projected-Newton iterations over all UVs after the hierarchy. 0 disables
    /// the finish (for θ ≠ 1 too, whose finish is the all-vertex relaxation). Default 20.
    pub newton_iterations: u32,
    /// The global finish stops when an iteration lowers the excess energy (E − 4) by less
    /// than this fraction, or the Newton decrement falls below it (relative to E − 4).
    /// Default 1e-3.
    pub newton_tolerance: f64,
    /// What the global finish returns (see [`Objective`]). Default
    /// [`Objective::Distortion`].
    #[serde(default)]
    pub objective: Objective,
}

/// What the global finish optimises for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Objective {
    /// The converged minimum of the symmetric Dirichlet energy (SLIM's objective): the
    /// least distortion, whatever the chart's outline. The default.
    #[default]
    Distortion,
    /// Of the hierarchy's layout and every Newton iterate, the one with the lowest packed
    /// L² stretch: Sander's L² stretch of the texture→surface map at the scale the chart
    /// gets in the square texture (its minimum-area rectangle's longer side fills it), i.e.
    /// the finest mean texel spacing on the surface for a given texture size. A converged
    /// low-distortion chart can fill less of the square (measured: ≤ 7 % finer texel
    /// spacing than `Distortion` on the store cells, at up to 4× its excess distortion).
    PackedStretch,
}

impl Default for ParamOptions {
    fn default() -> Self {
        ParamOptions {
            theta: 1.0,
            relax_tolerance: 1e-2,
            max_sweeps: 4,
            gutter_texels: 2.0,
            texture_size: 256,
            newton_iterations: 20,
            newton_tolerance: 1e-3,
            objective: Objective::Distortion,
        }
    }
}

impl ParamOptions {
    /// Checks every field's range; errors name the option.
    pub fn validate(&self) -> Result<()> {
        if !(self.theta.is_finite() && self.theta >= 0.0) {
            return Err(Error::BadOption(format!(
                "theta must be finite and >= 0, got {}",
                self.theta
            )));
        }
        if !(self.relax_tolerance.is_finite() && self.relax_tolerance >= 0.0) {
            return Err(Error::BadOption(format!(
                "relax tolerance must be finite and >= 0, got {}",
                self.relax_tolerance
            )));
        }
        if !(self.newton_tolerance.is_finite() && self.newton_tolerance >= 0.0) {
            return Err(Error::BadOption(format!(
                "newton tolerance must be finite and >= 0, got {}",
                self.newton_tolerance
            )));
        }
        if self.texture_size == 0 {
            return Err(Error::BadOption(
                "texture size must be at least 1 texel".into(),
            ));
        }
        if !(self.gutter_texels.is_finite()
            && self.gutter_texels >= 0.0
            && 2.0 * self.gutter_texels < self.texture_size as f64)
        {
            return Err(Error::BadOption(format!(
                "gutter must be >= 0 texels and less than half the texture ({} texels), got {}",
                self.texture_size, self.gutter_texels
            )));
        }
        Ok(())
    }
}

/// A parameterized cell.
#[derive(Clone, Debug, PartialEq)]
pub struct Chart {
    /// One texture coordinate per input vertex, inside \[0,1\]² (u right, v up), with no
    /// flipped triangle unless `metrics.flipped` says otherwise.
    pub uvs: Vec<[f64; 2]>,
    /// Distortion of the final chart (see [`ChartMetrics`]; base area = xy bounding
    /// rectangle of the input).
    pub metrics: ChartMetrics,
    /// Rotation (radians, counter-clockwise) applied to the area-preserving layout (whose
    /// UV area equals the 3D area, in metres) before scaling.
    pub rotation: f64,
    /// Texture units per metre of the area-preserving layout: uv = offset + scale·R·w.
    pub scale: f64,
    /// Translation of the packed chart in texture units.
    pub offset: [f64; 2],
    /// Number of simplification rounds (hierarchy depth).
    pub rounds: usize,
    /// True if simplification stopped above one triangle and the base mesh was laid out
    /// by a Tutte embedding instead (see docs/parameterization.md).
    pub tutte_base: bool,
    /// Projected-Newton iterations of the global finish (0 if it did not run).
    pub newton_iterations: u32,
    /// True if the hierarchy's layout had a self-crossing boundary and was replaced by the
    /// global symmetric Dirichlet minimiser from a Tutte start, with every step kept free
    /// of boundary crossings (see docs/parameterization.md).
    pub overlap_repaired: bool,
    /// True if the finish started from a planar projection (horizontal or mean-normal
    /// plane) because that projection already had a lower energy than the hierarchy's
    /// finished layout; the lower of the finished layouts is returned
    /// ([`Objective::Distortion`] only).
    pub projection_start: bool,
}

/// Computes a flip-free, area/angle-balanced chart of `mesh` packed into the unit square.
/// Deterministic for the same input. Errors only on invalid options or a mesh that is not
/// a valid disc (the error says which triangle/vertex is wrong).
pub fn parameterize(mesh: &ParamMesh, opts: &ParamOptions) -> Result<Chart> {
    opts.validate()?;
    mesh::validate(mesh)?;
    run(mesh, opts, usize::MAX)
}

/// The pipeline; `max_rounds` caps the simplification (tests use it to exercise the
/// Tutte base).
fn run(mesh: &ParamMesh, opts: &ParamOptions, max_rounds: usize) -> Result<Chart> {
    let n = mesh.positions.len();
    // Local frame: subtract the centroid (UTM-sized coordinates lose precision otherwise).
    let mut c = [0.0; 3];
    for p in &mesh.positions {
        for k in 0..3 {
            c[k] += p[k] / n as f64;
        }
    }
    let pos: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .map(|p| [p[0] - c[0], p[1] - c[1], p[2] - c[2]])
        .collect();

    let mut topo = Topo::new(mesh);
    let mut hier = collapse::simplify_capped(&mut topo, &pos, max_rounds);
    let mut uvs = vec![[0.0f64; 2]; n];
    let mut rx = Relaxer {
        geom: Vec::new(),
        theta: opts.theta,
        guard: None,
    };
    let tutte_base = topo.alive_faces > 1;
    if tutte_base {
        base::tutte(&topo, &pos, &mut uvs);
        rx.refresh(&topo, &pos);
        normalize_area(&topo, &rx, &mut uvs);
        let all: Vec<VertId> = (0..n as u32)
            .map(VertId)
            .filter(|v| topo.vert_alive[v.ix()])
            .collect();
        rx.relax(&topo, &mut uvs, all, opts.relax_tolerance, opts.max_sweeps);
    } else {
        base::triangle(&topo, &pos, &mut uvs);
    }
    let rounds = hier.rounds.len();
    while let Some(round) = hier.rounds.pop() {
        let mut inserted = Vec::with_capacity(round.len());
        for col in round.iter().rev() {
            split::undo(&mut topo, col);
            let p = split::place(&topo, &pos, &uvs, col.u)
                .unwrap_or_else(|| fallback_place(&topo, &uvs, col));
            uvs[col.u.ix()] = p;
            inserted.push(col.u);
        }
        rx.refresh(&topo, &pos);
        normalize_area(&topo, &rx, &mut uvs);
        let mut start: Vec<VertId> = Vec::new();
        for &u in &inserted {
            start.push(u);
            start.extend(topo.neighbours(u));
        }
        start.sort_unstable();
        start.dedup();
        rx.relax(
            &topo,
            &mut uvs,
            start,
            opts.relax_tolerance,
            opts.max_sweeps,
        );
    }
    rx.refresh(&topo, &pos);
    normalize_area(&topo, &rx, &mut uvs);
    let boundary = overlap::BoundaryLoop::new(n, &mesh.triangles);
    let overlap_repaired = boundary.overlaps(&uvs);
    if overlap_repaired {
        // The hierarchy's layout folds over itself: restart from a layout whose boundary is
        // a circle and let the finish keep it simple.
        base::tutte(&topo, &pos, &mut uvs);
        normalize_area(&topo, &rx, &mut uvs);
    }
    rx.guard = Some((boundary.clone(), boundary.index_of(n)));
    let geom: Vec<energy::FaceGeom> = mesh
        .triangles
        .iter()
        .map(|t| energy::FaceGeom::new(pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]))
        .collect();
    let mut newton_iterations = finish_layout(
        &pos,
        &mesh.triangles,
        &topo,
        &rx,
        &mut uvs,
        opts,
        &boundary,
        overlap_repaired,
    );
    // A planar projection that already beats the result is a better basin: finish from it
    // too and keep the lower objective (jagged cells; never the case on the store's steep
    // cells measured, where the hierarchy's layout wins by far).
    let mut score = layout_energy(&geom, &mesh.triangles, &uvs, opts);
    let mut projection_start = false;
    let candidates = if opts.objective == Objective::Distortion {
        planar::projections(&pos, &mesh.triangles)
    } else {
        Vec::new()
    };
    for mut cand in candidates {
        normalize_area(&topo, &rx, &mut cand);
        if boundary.overlaps(&cand) || !(layout_energy(&geom, &mesh.triangles, &cand, opts) < score)
        {
            continue;
        }
        let it = finish_layout(
            &pos,
            &mesh.triangles,
            &topo,
            &rx,
            &mut cand,
            opts,
            &boundary,
            false,
        );
        let sc = layout_energy(&geom, &mesh.triangles, &cand, opts);
        if sc < score {
            (uvs, score, newton_iterations, projection_start) = (cand, sc, it, true);
        }
    }
    let fit = pack::fit(&mut uvs, opts.gutter_texels / opts.texture_size as f64);
    let mut metrics = chart_metrics(&mesh.positions, &mesh.triangles, &uvs, None)?;
    metrics.boundary_crossings = boundary.crossings(&uvs);
    Ok(Chart {
        uvs,
        metrics,
        rotation: fit.rotation,
        scale: fit.scale,
        offset: fit.offset,
        rounds,
        tutte_base,
        newton_iterations,
        overlap_repaired,
        projection_start,
    })
}

/// The finish from `uvs`: for θ = 1 the global Newton solve (at least
/// [`REPAIR_ITERATIONS`] when `repair`), otherwise the boundary-guarded local relaxation
/// over every vertex (`rx.guard` must be set). Returns the Newton iterations run.
#[allow(clippy::too_many_arguments)]
fn finish_layout(
    pos: &[[f64; 3]],
    tris: &[[u32; 3]],
    topo: &Topo,
    rx: &Relaxer,
    uvs: &mut [[f64; 2]],
    opts: &ParamOptions,
    boundary: &overlap::BoundaryLoop,
    repair: bool,
) -> u32 {
    let all = || (0..uvs.len() as u32).map(VertId).collect::<Vec<_>>();
    if opts.theta == 1.0 {
        let iters = if repair {
            opts.newton_iterations.max(REPAIR_ITERATIONS)
        } else {
            opts.newton_iterations
        };
        if iters > 0 {
            return finish(pos, tris, uvs, iters, opts, boundary);
        }
    } else if repair {
        rx.relax(topo, uvs, all(), opts.relax_tolerance, REPAIR_SWEEPS);
    } else if opts.newton_iterations > 0 {
        // No global solve for θ ≠ 1: the relaxation at the quality setting (the
        // hierarchy's rounds stop early at the default tolerance).
        rx.relax(
            topo,
            uvs,
            all(),
            LOCAL_FINISH_TOLERANCE.min(opts.relax_tolerance),
            LOCAL_FINISH_SWEEPS,
        );
    }
    0
}

/// The area-weighted energy (θ) of a layout, for comparing layouts of one mesh; +∞ if a
/// triangle is flipped.
fn layout_energy(
    geom: &[energy::FaceGeom],
    tris: &[[u32; 3]],
    uvs: &[[f64; 2]],
    opts: &ParamOptions,
) -> f64 {
    let (mut e, mut a) = (0.0, 0.0);
    for (g, t) in geom.iter().zip(tris) {
        if !(g.area > 0.0) {
            continue;
        }
        e += g.area
            * energy::energy(
                &g.jacobian([uvs[t[0] as usize], uvs[t[1] as usize], uvs[t[2] as usize]]),
                opts.theta,
            );
        a += g.area;
    }
    if a > 0.0 { e / a } else { f64::INFINITY }
}

/// The global finish: Newton iterations from `uvs`; with [`Objective::PackedStretch`] the
/// iterate (or start) with the lowest packed L² stretch is kept. Returns the iterations run.
fn finish(
    pos: &[[f64; 3]],
    tris: &[[u32; 3]],
    uvs: &mut [[f64; 2]],
    iters: u32,
    opts: &ParamOptions,
    boundary: &overlap::BoundaryLoop,
) -> u32 {
    let geom: Vec<energy::FaceGeom> = tris
        .iter()
        .map(|t| energy::FaceGeom::new(pos[t[0] as usize], pos[t[1] as usize], pos[t[2] as usize]))
        .collect();
    let mut best: Option<(f64, Vec<[f64; 2]>)> = None;
    let mut observe = |x: &[[f64; 2]]| {
        if opts.objective == Objective::PackedStretch {
            let q = packed_stretch(&geom, tris, x);
            if best.as_ref().is_none_or(|b| q < b.0) {
                best = Some((q, x.to_vec()));
            }
        }
    };
    let it = newton::minimize(
        pos,
        tris,
        uvs,
        iters,
        opts.newton_tolerance,
        Some(boundary),
        &mut observe,
    )
    .iterations;
    if let Some((_, b)) = best {
        uvs.copy_from_slice(&b);
    }
    it
}

/// Packed L² stretch of a layout, up to a constant factor: (longer side of the minimum-area
/// rectangle) × sqrt(area-weighted mean of (1/s1² + 1/s2²)/2), which is invariant to the
/// layout's scale and proportional to Sander's L² stretch once packed into the square.
fn packed_stretch(geom: &[energy::FaceGeom], tris: &[[u32; 3]], uvs: &[[f64; 2]]) -> f64 {
    let (mut s, mut a) = (0.0, 0.0);
    for (g, t) in geom.iter().zip(tris) {
        let j = g.jacobian([uvs[t[0] as usize], uvs[t[1] as usize], uvs[t[2] as usize]]);
        let d = energy::det2(&j);
        if !(d > 0.0) {
            return f64::INFINITY;
        }
        let fro = j[0][0] * j[0][0] + j[0][1] * j[0][1] + j[1][0] * j[1][0] + j[1][1] * j[1][1];
        s += g.area * 0.5 * fro / (d * d);
        a += g.area;
    }
    pack::packed_side(uvs) * (s / a).sqrt()
}

/// Relative tolerance of the finishing relaxation over all vertices when θ ≠ 1 (the
/// measured quality setting, docs/parameterization.md).
const LOCAL_FINISH_TOLERANCE: f64 = 1e-4;

/// Sweep budget of the finishing relaxation when θ ≠ 1.
const LOCAL_FINISH_SWEEPS: u32 = 32;

/// Iteration budget of the global solve when it repairs an overlapping chart from a Tutte
/// start (far from the optimum, so more than the finishing default).
const REPAIR_ITERATIONS: u32 = 100;

/// Sweep budget of the guarded local relaxation when it repairs an overlapping chart
/// (θ ≠ 1) from a Tutte start.
const REPAIR_SWEEPS: u32 = 200;

/// Last resort when the 1-ring kernel is numerically empty: a point just off `v` towards
/// the centroid of the ring (the relaxation cannot repair flips, so this is reported by
/// the metrics if it ever happens).
fn fallback_place(topo: &Topo, uvs: &[[f64; 2]], col: &collapse::Collapse) -> [f64; 2] {
    let nb = topo.neighbours(col.u);
    let mut c = [0.0, 0.0];
    for w in &nb {
        c[0] += uvs[w.ix()][0] / nb.len() as f64;
        c[1] += uvs[w.ix()][1] / nb.len() as f64;
    }
    let v = uvs[col.v.ix()];
    [v[0] + 1e-3 * (c[0] - v[0]), v[1] + 1e-3 * (c[1] - v[1])]
}

/// Scales the alive UVs about their centroid so the UV area equals the 3D area.
fn normalize_area(topo: &Topo, rx: &Relaxer, uvs: &mut [[f64; 2]]) {
    let (mut a3, mut auv) = (0.0, 0.0);
    for (f, t) in topo.faces.iter().enumerate() {
        if !topo.face_alive[f] {
            continue;
        }
        a3 += rx.geom[f].area;
        let (a, b, c) = (uvs[t[0] as usize], uvs[t[1] as usize], uvs[t[2] as usize]);
        auv += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
    }
    if !(auv > 0.0 && a3 > 0.0) {
        return;
    }
    let k = (a3 / auv).sqrt();
    let mut cen = [0.0, 0.0];
    let mut cnt = 0.0;
    for (v, uv) in uvs.iter().enumerate() {
        if topo.vert_alive[v] {
            cen[0] += uv[0];
            cen[1] += uv[1];
            cnt += 1.0;
        }
    }
    cen = [cen[0] / cnt, cen[1] / cnt];
    for (v, uv) in uvs.iter_mut().enumerate() {
        if topo.vert_alive[v] {
            *uv = [(uv[0] - cen[0]) * k, (uv[1] - cen[1]) * k];
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// An n x n unit grid with heights f(x, y), two CCW triangles per quad.
    pub(crate) fn grid(n: usize, f: impl Fn(f64, f64) -> f64) -> ParamMesh {
        let mut positions = Vec::new();
        for r in 0..n {
            for c in 0..n {
                positions.push([c as f64, r as f64, f(c as f64, r as f64)]);
            }
        }
        let mut triangles = Vec::new();
        for r in 0..n - 1 {
            for c in 0..n - 1 {
                let a = (r * n + c) as u32;
                triangles.push([a, a + 1, a + 1 + n as u32]);
                triangles.push([a, a + 1 + n as u32, a + n as u32]);
            }
        }
        ParamMesh {
            positions,
            triangles,
        }
    }

    #[test]
    fn tutte_base_path_gives_valid_chart() {
        let m = grid(12, |x, y| if x > 5.5 { 8.0 } else { 0.0 } + 0.1 * y);
        for cap in [0, 1, 3] {
            let ch = run(&m, &ParamOptions::default(), cap).unwrap();
            assert!(ch.tutte_base);
            assert_eq!(ch.metrics.flipped, 0, "cap {cap}");
            assert!(
                ch.metrics.angle_distortion_mean < 2.0,
                "cap {cap}: {:?}",
                ch.metrics
            );
        }
    }

    #[test]
    fn options_are_validated() {
        let m = grid(3, |_, _| 0.0);
        for o in [
            ParamOptions {
                theta: -1.0,
                ..Default::default()
            },
            ParamOptions {
                theta: f64::NAN,
                ..Default::default()
            },
            ParamOptions {
                relax_tolerance: -1.0,
                ..Default::default()
            },
            ParamOptions {
                texture_size: 0,
                ..Default::default()
            },
            ParamOptions {
                gutter_texels: 200.0,
                ..Default::default()
            },
        ] {
            assert!(
                matches!(parameterize(&m, &o), Err(Error::BadOption(_))),
                "{o:?}"
            );
        }
    }
}
