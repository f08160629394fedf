//! Texel-stretch statistics: how much the orthographic texture parameterization stretches
//! texels on steep ground (cliffmap's foundation issue). Definitions are in docs/stats.md.
//!
//! All areas are in world units² (m²), angles in degrees. For one cell with nominal square of
//! side `n` sample intervals (spacings `sx`, `sy`) and a `T x T` texture:
//! - `base_area = (n sx) (n sy)`: the area of the NOMINAL square, which the texture budget
//!   (`T²` texels) was made for.
//! - `clipped_area`: area of the cell's rectangle clipped to the DEM's data rectangle.
//! - `used_fraction = clipped_area / base_area`: the part of the texture the ortho
//!   parameterization actually uses.
//! - `surface_area_tin`: 3D area of the cell's TIN (vertices are DEM samples, heights from
//!   the DEM). `surface_area_dem`: 3D area of the full-resolution DEM surface in the clipped
//!   rectangle (two triangles per grid quad, split along the NW–SE diagonal).
//! - `rel_texel = (surface_area_tin / base_area) / used_fraction
//!   = surface_area_tin / clipped_area`: the average stretch of the used texels; 1 for flat
//!   ground (also in clipped edge cells), `1 / cos(a)` for a plane of slope `a`.
//! - per-texel stretch (see [`texel_stretch`]): the 3D area mapped to a texel relative to the
//!   optimum `base_area / T²`; for the ortho map it is `1 / |n_z|` of the TIN triangle
//!   covering the texel centre. [`CellStats::texel_stretch`] summarises it over the covered
//!   texels, [`CellStats::steep_texel_fraction`] counts texels on triangles steeper than 60°
//!   (stretch > 2), [`CellStats::stretch_histogram`] bins it by [`stretch_bin_edges`].
//! - `max_slope_deg` / `mean_slope_deg`: steepest and mean slope of the full-resolution grid
//!   triangles in the clipped rectangle; the mean is weighted by 3D triangle area.
//!
//! Data types: [`CellStats`] (one cell), [`Percentiles`], [`CellStatsEntry`] (a cell's stats
//! with its address, as stored in `stats.json`), [`StatsSummary`] / [`LevelSummary`] /
//! [`HistogramBin`] (aggregates over cells).

mod area;
mod cell;
mod histogram;
mod stretch;
mod summary;

pub use area::{DemSurface, dem_surface, tin_surface_area, triangle_area_3d};
pub use cell::cell_stats;
pub use histogram::{RelTexelBins, rel_texel_bins, write_histogram_png};
pub use stretch::{
    CellSurface, STEEP_STRETCH, StretchSummary, cell_texel_stretch, stretch_bin_edges,
    summarize_stretch, texel_stretch,
};
pub use summary::{
    CellStatsEntry, HistogramBin, LevelSummary, StatsSummary, stats_json, summarize,
};

use serde::{Deserialize, Serialize};

/// Order statistics of a sample. Percentiles interpolate linearly between closest ranks
/// (`p = v[floor(q (n-1))] .. v[ceil(q (n-1))]`, as numpy's default). All zero for an empty
/// sample.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Percentiles {
    /// Median.
    pub p50: f64,
    /// 90th percentile.
    pub p90: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Largest value.
    pub max: f64,
    /// Arithmetic mean.
    pub mean: f64,
}

impl Percentiles {
    /// Percentiles of the finite values of `values` (non-finite ones are ignored). Sorts
    /// `values` in place.
    pub fn of(values: &mut Vec<f64>) -> Percentiles {
        values.retain(|v| v.is_finite());
        if values.is_empty() {
            return Percentiles::default();
        }
        values.sort_unstable_by(f64::total_cmp);
        let n = values.len();
        let mean = values.iter().sum::<f64>() / n as f64;
        Percentiles {
            p50: quantile_sorted(values, 0.5),
            p90: quantile_sorted(values, 0.9),
            p99: quantile_sorted(values, 0.99),
            max: values[n - 1],
            mean,
        }
    }
}

/// Quantile `q` in [0, 1] of a non-empty ascending slice, interpolating between closest ranks.
pub(crate) fn quantile_sorted(v: &[f64], q: f64) -> f64 {
    let pos = q.clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let (k, f) = (pos.floor() as usize, pos - pos.floor());
    if k + 1 < v.len() {
        v[k] + (v[k + 1] - v[k]) * f
    } else {
        v[k]
    }
}

/// Texel-stretch statistics of one cell (definitions in the [module docs](self)). All fields
/// are finite; areas in world units², angles in degrees.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct CellStats {
    /// 3D area of the cell's TIN triangles.
    pub surface_area_tin: f64,
    /// 3D area of the full-resolution DEM surface inside the clipped rectangle.
    pub surface_area_dem: f64,
    /// Planar area of the cell's nominal square (what the texture budget was made for).
    pub base_area: f64,
    /// Planar area of the cell's rectangle clipped to the DEM.
    pub clipped_area: f64,
    /// `clipped_area / base_area`, in (0, 1].
    pub used_fraction: f64,
    /// Average texel stretch, `surface_area_tin / clipped_area` (>= 1 for a TIN on the DEM).
    pub rel_texel: f64,
    /// Steepest full-resolution grid triangle in the clipped rectangle, degrees.
    pub max_slope_deg: f64,
    /// Mean slope of the full-resolution grid triangles weighted by 3D area, degrees.
    pub mean_slope_deg: f64,
    /// Per-texel stretch over the covered texels.
    pub texel_stretch: Percentiles,
    /// Fraction of covered texels on TIN triangles steeper than 60° (stretch > 2).
    pub steep_texel_fraction: f64,
    /// Number of texels whose centre is covered by a TIN triangle.
    pub covered_texels: u64,
    /// Covered texels per stretch bin of [`stretch_bin_edges`] (last bin open-ended).
    pub stretch_histogram: Vec<u64>,
}
