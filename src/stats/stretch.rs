//! Per-texel stretch of a texture parameterization, by scan conversion in texture space.

use crate::cells::CellMesh;
use crate::stats::Percentiles;

/// Stretch above which a texel counts as steep: 2 = `1 / cos 60°` for the ortho map.
pub const STEEP_STRETCH: f64 = 2.0;

/// Slopes (degrees) whose ortho stretch `1 / cos(slope)` gives the inner edges of the
/// stretch histogram bins.
const BIN_SLOPES_DEG: [f64; 10] = [10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0, 75.0, 80.0, 85.0];

/// Lower edges of the per-texel stretch histogram bins, ascending: `0`, `0.9` (values below
/// 0.9 only occur for non-orthographic parameterizations that compress), `1 - 1e-9` (so flat
/// texels with rounding error stay in the "< 10°" bin), then `1 / cos(s)` for
/// s = 10, 20, 30, 40, 50, 60, 70, 75, 80, 85°. Bin `k` holds `edges[k] <= s < edges[k+1]`;
/// the last bin is open-ended.
pub fn stretch_bin_edges() -> Vec<f64> {
    let mut e = vec![0.0, 0.9, 1.0 - 1e-9];
    e.extend(BIN_SLOPES_DEG.iter().map(|d| 1.0 / d.to_radians().cos()));
    e
}

/// Per-texel stretch of a triangle mesh under a texture parameterization, for any
/// parameterization (orthographic or not).
///
/// `positions` are cell-local 3D positions (world units), `uvs` their texture coordinates in
/// the unit square (u east / across columns, v down the rows), `triangles` index both, and
/// `base_area` is the planar area (world units²) the `texels x texels` texture was budgeted
/// for. For texel `(i, j)` whose centre `((i + 0.5) / T, (j + 0.5) / T)` lies in the UV image
/// of a triangle, the result (row-major, index `j * T + i`) is
/// `stretch = (A_3d / A_uv) / (base_area / T²)` with `A_uv` the triangle's UV area in texels²:
/// 1 is the optimum (every texel carries `base_area / T²` of surface), 2 means a texel is
/// spread over twice its share. For the ortho map (`uv` = planar position / extent) it equals
/// `1 / |n_z|` of the covering triangle. Texels not covered by any triangle are `NaN`.
/// Where UV triangles overlap (or share an edge through a texel centre) the first triangle in
/// `triangles` wins, so the result is deterministic. Triangles of either UV orientation are
/// accepted; triangles with zero UV area are skipped. Panics on an index out of range.
pub fn texel_stretch(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    uvs: &[[f64; 2]],
    texels: u32,
    base_area: f64,
) -> Vec<f32> {
    let t = texels as usize;
    let tf = texels as f64;
    let mut out = vec![f32::NAN; t * t];
    if t == 0 {
        return out;
    }
    let texel_share = base_area / (tf * tf);
    // points on an edge within this distance (texels) count as inside, so shared edges
    // through texel centres leave no gaps
    const EPS: f64 = 1e-7;
    for tri in triangles {
        let [a, b, c] = tri.map(|k| k as usize);
        let p = [uvs[a], uvs[b], uvs[c]].map(|q| [q[0] * tf, q[1] * tf]);
        let twice_uv =
            (p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]);
        if twice_uv == 0.0 || !twice_uv.is_finite() {
            continue;
        }
        let area_uv = 0.5 * twice_uv.abs();
        let area_3d = crate::stats::triangle_area_3d(positions[a], positions[b], positions[c]);
        let stretch = (area_3d / area_uv / texel_share) as f32;
        let sign = twice_uv.signum();
        // edge k from p[k] to p[k+1]: inside where sign * cross >= -EPS * |edge|
        let edges: [([f64; 2], [f64; 2], f64); 3] = std::array::from_fn(|k| {
            let (s, e) = (p[k], p[(k + 1) % 3]);
            let d = [e[0] - s[0], e[1] - s[1]];
            (s, d, EPS * (d[0] * d[0] + d[1] * d[1]).sqrt())
        });
        let (min_u, max_u) = (
            p[0][0].min(p[1][0]).min(p[2][0]),
            p[0][0].max(p[1][0]).max(p[2][0]),
        );
        let (min_v, max_v) = (
            p[0][1].min(p[1][1]).min(p[2][1]),
            p[0][1].max(p[1][1]).max(p[2][1]),
        );
        // texel centres k + 0.5 within [min - EPS, max + EPS]
        let i0 = (min_u - 0.5 - EPS).ceil().max(0.0);
        let i1 = (max_u - 0.5 + EPS).floor().min(tf - 1.0);
        let j0 = (min_v - 0.5 - EPS).ceil().max(0.0);
        let j1 = (max_v - 0.5 + EPS).floor().min(tf - 1.0);
        if !(i0 <= i1 && j0 <= j1) {
            continue;
        }
        for j in j0 as usize..=j1 as usize {
            let y = j as f64 + 0.5;
            for i in i0 as usize..=i1 as usize {
                let x = i as f64 + 0.5;
                let inside = edges
                    .iter()
                    .all(|(s, d, tol)| sign * (d[0] * (y - s[1]) - d[1] * (x - s[0])) >= -tol);
                let cell = &mut out[j * t + i];
                if inside && cell.is_nan() {
                    *cell = stretch;
                }
            }
        }
    }
    out
}

/// Summary of a per-texel stretch image (see [`summarize_stretch`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct StretchSummary {
    /// Percentiles over covered (non-NaN) texels.
    pub percentiles: Percentiles,
    /// Number of covered texels.
    pub covered: u64,
    /// Fraction of covered texels with stretch > [`STEEP_STRETCH`] (0 if none covered).
    pub steep_fraction: f64,
    /// Covered texels per bin of [`stretch_bin_edges`].
    pub histogram: Vec<u64>,
}

/// Percentiles, steep fraction and histogram of the covered (non-NaN) texels of a stretch
/// image from [`texel_stretch`].
pub fn summarize_stretch(stretch: &[f32]) -> StretchSummary {
    let edges = stretch_bin_edges();
    let mut histogram = vec![0u64; edges.len()];
    let mut vals: Vec<f64> = stretch
        .iter()
        .filter(|s| !s.is_nan())
        .map(|&s| s as f64)
        .collect();
    let mut steep = 0u64;
    for &v in &vals {
        histogram[bin_index(&edges, v)] += 1;
        steep += (v > STEEP_STRETCH) as u64;
    }
    let covered = vals.len() as u64;
    StretchSummary {
        percentiles: Percentiles::of(&mut vals),
        covered,
        steep_fraction: if covered > 0 {
            steep as f64 / covered as f64
        } else {
            0.0
        },
        histogram,
    }
}

/// Bin of `v` among ascending lower `edges` (values below the first edge go to bin 0).
pub(crate) fn bin_index(edges: &[f64], v: f64) -> usize {
    edges.partition_point(|&e| e <= v).saturating_sub(1)
}

/// [`texel_stretch`] of a cell drawn with `mesh` (its surface triangles) and the texture
/// coordinates `uvs` of its surface vertices ([`CellMesh::surface_texcoords`]) on a
/// `texels × texels` texture budgeted for the cell's nominal square of `base_area` m².
pub fn cell_texel_stretch(
    mesh: &CellMesh,
    uvs: &[[f32; 2]],
    base_area: f64,
    texels: u32,
) -> Vec<f32> {
    let s = CellSurface::of(mesh, uvs);
    texel_stretch(&s.positions, &s.triangles, &s.uvs, texels.max(1), base_area)
}

/// A cell's surface as [`texel_stretch`] takes it: the surface vertices (metres,
/// cell-local, widened to f64), their texture coordinates, and the surface triangles that
/// use only those vertices.
pub struct CellSurface {
    /// Surface vertex positions.
    pub positions: Vec<[f64; 3]>,
    /// Texture coordinates (0..1) per surface vertex.
    pub uvs: Vec<[f64; 2]>,
    /// Surface triangles (indices into `positions`).
    pub triangles: Vec<[u32; 3]>,
}

impl CellSurface {
    /// The surface of `mesh` with the texture coordinates `uvs` of its surface vertices
    /// ([`CellMesh::surface_texcoords`]).
    pub fn of(mesh: &CellMesh, uvs: &[[f32; 2]]) -> CellSurface {
        let n = (mesh.surface_vertices as usize)
            .min(mesh.positions.len())
            .min(uvs.len());
        CellSurface {
            positions: mesh.positions[..n]
                .iter()
                .map(|p| p.map(f64::from))
                .collect(),
            uvs: uvs[..n].iter().map(|uv| uv.map(f64::from)).collect(),
            triangles: mesh
                .surface()
                .iter()
                .copied()
                .filter(|t| t.iter().all(|&k| (k as usize) < n))
                .collect(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles covering the unit square of a `w x h` planar patch tilted with height
    /// `z = p x`, UVs = planar position.
    type Mesh = (Vec<[f64; 3]>, Vec<[u32; 3]>, Vec<[f64; 2]>);

    fn square(w: f64, h: f64, p: f64) -> Mesh {
        let pos = vec![
            [0.0, 0.0, 0.0],
            [0.0, -h, 0.0],
            [w, -h, p * w],
            [w, 0.0, p * w],
        ];
        let uv = pos.iter().map(|q| [q[0] / w, -q[1] / h]).collect();
        (pos, vec![[0, 1, 2], [0, 2, 3]], uv)
    }

    #[test]
    fn ortho_stretch_is_inverse_cosine_and_covers_every_texel() {
        for t in [1u32, 7, 16, 64] {
            let (pos, tri, uv) = square(30.0, 20.0, 0.75);
            let s = texel_stretch(&pos, &tri, &uv, t, 600.0);
            assert_eq!(s.len(), (t * t) as usize);
            for v in &s {
                assert!((*v as f64 - 1.25).abs() < 1e-6, "T={t}: {v}");
            }
        }
    }

    #[test]
    fn general_parameterization_and_uncovered_texels() {
        // triangle occupying the upper-left half of the texture (texels with i + j < T - 1
        // have centres strictly inside), planar
        let pos = vec![[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [0.0, -10.0, 0.0]];
        let uv = vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        let s = texel_stretch(&pos, &[[0, 1, 2]], &uv, 8, 100.0);
        for j in 0..8 {
            for i in 0..8 {
                let v = s[j * 8 + i];
                if i + j < 7 {
                    assert!((v - 1.0).abs() < 1e-6, "({i},{j}) {v}");
                } else if i + j > 7 {
                    assert!(v.is_nan(), "({i},{j}) {v}");
                }
            }
        }
        // the same surface squeezed into half the texture width: twice the stretch
        let uv2: Vec<[f64; 2]> = uv.iter().map(|q| [q[0] * 0.5, q[1]]).collect();
        let s = texel_stretch(&pos, &[[0, 1, 2]], &uv2, 8, 100.0);
        assert!((s[0] - 2.0).abs() < 1e-6);
        let sum = summarize_stretch(&s);
        assert_eq!(
            sum.covered as usize,
            s.iter().filter(|v| !v.is_nan()).count()
        );
        assert!(sum.covered > 0 && (sum.percentiles.max - 2.0).abs() < 1e-6);
        // exactly 2 is not "steep"
        assert_eq!(sum.steep_fraction, 0.0);
    }

    #[test]
    fn histogram_bins_by_equivalent_slope() {
        let e = stretch_bin_edges();
        assert!(e.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(bin_index(&e, 0.9999999999), 2);
        assert_eq!(bin_index(&e, 1.0), 2);
        assert_eq!(bin_index(&e, 1.0 / 15f64.to_radians().cos()), 3);
        assert_eq!(bin_index(&e, 100.0), e.len() - 1);
        assert_eq!(bin_index(&e, 0.5), 0);
        let s = summarize_stretch(&[1.0, 3.0, f32::NAN, 1.0, 1.0]);
        assert_eq!(s.covered, 4);
        assert_eq!(s.steep_fraction, 0.25);
        assert_eq!(s.histogram.iter().sum::<u64>(), 4);
        assert_eq!(s.percentiles.p50, 1.0);
        assert_eq!(s.percentiles.max, 3.0);
        assert_eq!(s.percentiles.mean, 1.5);
    }
}
