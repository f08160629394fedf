//! Distortion metrics of any 3D triangle mesh with texture coordinates.
//!
//! Every per-triangle measure uses the singular values s1 >= s2 of the Jacobian of the
//! map from the 3D triangle to the plane, after scaling all UVs uniformly so that the total
//! UV area equals the total 3D area (so the measures do not depend on the texture size).
//! Averages are weighted by 3D triangle area.

use super::energy::{FaceGeom, singular_values};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Distortion and texture-use figures of one chart.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ChartMetrics {
    /// Number of triangles.
    pub triangles: usize,
    /// Triangles whose UV orientation is reversed or whose UV area is zero.
    pub flipped: usize,
    /// Area-weighted mean of |ln(s1·s2)| (0 = every triangle keeps its relative area).
    pub area_distortion_mean: f64,
    /// Maximum of |ln(s1·s2)| (∞ if a triangle has zero UV area).
    pub area_distortion_max: f64,
    /// Area-weighted mean of s1/s2 (1 = conformal).
    pub angle_distortion_mean: f64,
    /// Maximum of s1/s2 (∞ if a triangle has zero UV area).
    pub angle_distortion_max: f64,
    /// Area-weighted mean of the symmetric Dirichlet energy s1²+s2²+1/s1²+1/s2² (4 = isometric).
    pub symmetric_dirichlet_mean: f64,
    /// Sander et al. (2001) L² stretch of the texture-to-surface map (1 = isometric, >= 1).
    pub stretch_l2: f64,
    /// Sander et al. (2001) L∞ stretch: the largest 1/s2 (texels stretched most on the surface).
    pub stretch_linf: f64,
    /// Total UV area of the chart as given (for a chart packed into \[0,1\]²: the fraction
    /// of the texture covered).
    pub used_fraction: f64,
    /// Total 3D surface area, in the units of the positions squared.
    pub surface_area: f64,
    /// The base (map) area the chart replaces, same units as `surface_area`.
    pub base_area: f64,
    /// (surface_area / base_area) / used_fraction: texels this chart needs, relative to an
    /// orthographic texture of the base area, for the same mean texel density on the
    /// surface as the ortho texture has on flat ground.
    pub rel_texel: f64,
    /// Pairs of non-adjacent boundary segments of the chart that cross or touch (0 = the
    /// chart is globally injective, given no flips). Only [`crate::param::parameterize`]
    /// fills it; [`chart_metrics`] leaves 0.
    #[serde(default)]
    pub boundary_crossings: usize,
}

impl ChartMetrics {
    /// Excess of the mean symmetric Dirichlet energy over an isometry's 4 (0 = isometric):
    /// the distortion to compare between methods.
    pub fn symmetric_dirichlet_excess(&self) -> f64 {
        self.symmetric_dirichlet_mean - 4.0
    }

    /// Sander's L² stretch of the chart as packed: `stretch_l2 · sqrt(rel_texel)`, the RMS
    /// surface length per texel relative to an ortho texel on flat ground (1), for a
    /// texture of the same size. What a fixed texture budget resolves: lower is finer.
    pub fn packed_stretch_l2(&self) -> f64 {
        self.stretch_l2 * self.rel_texel.sqrt()
    }
}

/// Measures the chart `uvs` of the mesh (`positions`, `triangles`). `base_area` is the
/// map area the chart stands for; `None` uses the area of the xy bounding rectangle of
/// `positions` (right for a square cell patch). Errors if lengths or indices disagree.
pub fn chart_metrics(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    uvs: &[[f64; 2]],
    base_area: Option<f64>,
) -> Result<ChartMetrics> {
    if uvs.len() != positions.len() {
        return Err(Error::BadOption(format!(
            "chart metrics: {} UVs for {} vertices",
            uvs.len(),
            positions.len()
        )));
    }
    for (f, t) in triangles.iter().enumerate() {
        if t.iter().any(|&i| i as usize >= positions.len()) {
            return Err(Error::BadOption(format!(
                "chart metrics: triangle {f} {t:?} refers to a missing vertex"
            )));
        }
    }
    let mut m = ChartMetrics {
        triangles: triangles.len(),
        ..Default::default()
    };
    let mut geoms = Vec::with_capacity(triangles.len());
    let mut uv_area = 0.0;
    for t in triangles {
        let g = FaceGeom::new(
            positions[t[0] as usize],
            positions[t[1] as usize],
            positions[t[2] as usize],
        );
        let uv = [uvs[t[0] as usize], uvs[t[1] as usize], uvs[t[2] as usize]];
        let signed = 0.5
            * ((uv[1][0] - uv[0][0]) * (uv[2][1] - uv[0][1])
                - (uv[1][1] - uv[0][1]) * (uv[2][0] - uv[0][0]));
        if !(signed > 0.0) {
            m.flipped += 1;
        }
        uv_area += signed.abs();
        m.surface_area += g.area;
        geoms.push((g, uv));
    }
    m.used_fraction = uv_area;
    let k = if uv_area > 0.0 {
        (m.surface_area / uv_area).sqrt()
    } else {
        f64::INFINITY
    };
    let (mut a_sum, mut ang_sum, mut sd_sum, mut l2_sum) = (0.0, 0.0, 0.0, 0.0);
    for (g, uv) in &geoms {
        if !(g.area > 0.0) {
            continue;
        }
        let mut j = g.jacobian(*uv);
        for r in j.iter_mut() {
            for c in r.iter_mut() {
                *c *= k;
            }
        }
        let (s1, s2) = singular_values(&j);
        let area_d = (s1 * s2).ln().abs();
        let ang = s1 / s2;
        let sd = s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2);
        let l2 = 0.5 * (1.0 / (s1 * s1) + 1.0 / (s2 * s2));
        a_sum += g.area * area_d;
        ang_sum += g.area * ang;
        sd_sum += g.area * sd;
        l2_sum += g.area * l2;
        m.area_distortion_max = m.area_distortion_max.max(area_d);
        m.angle_distortion_max =
            m.angle_distortion_max
                .max(if ang.is_nan() { f64::INFINITY } else { ang });
        m.stretch_linf = m.stretch_linf.max(1.0 / s2);
    }
    let w = m.surface_area;
    if w > 0.0 {
        m.area_distortion_mean = a_sum / w;
        m.angle_distortion_mean = ang_sum / w;
        m.symmetric_dirichlet_mean = sd_sum / w;
        m.stretch_l2 = (l2_sum / w).sqrt();
    }
    m.base_area = match base_area {
        Some(a) => a,
        None => {
            let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
            for p in positions {
                for d in 0..2 {
                    lo[d] = lo[d].min(p[d]);
                    hi[d] = hi[d].max(p[d]);
                }
            }
            if positions.is_empty() {
                0.0
            } else {
                (hi[0] - lo[0]) * (hi[1] - lo[1])
            }
        }
    };
    m.rel_texel = (m.surface_area / m.base_area) / m.used_fraction;
    Ok(m)
}

/// The Degener energy Σ A·E / Σ A of the chart (UVs normalised to the 3D area), with
/// area/angle weight `theta`: 2·2^θ for an isometry, +∞ if any triangle is flipped or
/// degenerate. Errors if lengths or indices disagree.
pub fn degener_energy(
    positions: &[[f64; 3]],
    triangles: &[[u32; 3]],
    uvs: &[[f64; 2]],
    theta: f64,
) -> Result<f64> {
    let m = chart_metrics(positions, triangles, uvs, None)?;
    let k = (m.surface_area / m.used_fraction).sqrt();
    let mut e = 0.0;
    for t in triangles {
        let g = FaceGeom::new(
            positions[t[0] as usize],
            positions[t[1] as usize],
            positions[t[2] as usize],
        );
        if !(g.area > 0.0) {
            continue;
        }
        let uv = [uvs[t[0] as usize], uvs[t[1] as usize], uvs[t[2] as usize]]
            .map(|p| [p[0] * k, p[1] * k]);
        e += g.area * super::energy::energy(&g.jacobian(uv), theta);
    }
    Ok(e / m.surface_area)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn orthographic_map_of_a_slope() {
        // A 45° ramp mapped orthographically: s1 = 1, s2 = cos 45° before normalisation.
        let positions = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
            [0.0, 1.0, 1.0],
        ];
        let tris = [[0, 1, 2], [0, 2, 3]];
        let uvs: Vec<[f64; 2]> = positions.iter().map(|p| [p[0], p[1]]).collect();
        let m = chart_metrics(&positions, &tris, &uvs, None).unwrap();
        assert_eq!(m.flipped, 0);
        let r = std::f64::consts::SQRT_2;
        assert!((m.angle_distortion_mean - r).abs() < 1e-12);
        assert!(
            m.area_distortion_mean.abs() < 1e-12,
            "normalised: same area everywhere"
        );
        assert!((m.surface_area - r).abs() < 1e-12);
        assert!((m.base_area - 1.0).abs() < 1e-12);
        assert!((m.rel_texel - r).abs() < 1e-12);
        // After normalisation s1 = 2^(1/4), s2 = 2^(-1/4).
        let (s1, s2) = (2f64.powf(0.25), 2f64.powf(-0.25));
        assert!(
            (m.symmetric_dirichlet_mean - (s1 * s1 + s2 * s2 + 1.0 / (s1 * s1) + 1.0 / (s2 * s2)))
                .abs()
                < 1e-12
        );
        assert!((m.stretch_linf - 1.0 / s2).abs() < 1e-12);
    }

    #[test]
    fn flips_are_counted_and_errors_reported() {
        let positions = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let m = chart_metrics(
            &positions,
            &[[0, 1, 2]],
            &[[0.0, 0.0], [0.0, 1.0], [1.0, 0.0]],
            None,
        )
        .unwrap();
        assert_eq!(m.flipped, 1);
        assert!(chart_metrics(&positions, &[[0, 1, 5]], &[[0.0; 2]; 3], None).is_err());
        assert!(chart_metrics(&positions, &[[0, 1, 2]], &[[0.0; 2]; 2], None).is_err());
    }
}
