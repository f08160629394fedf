//! Resampling a cell's colour into a new parameterization (a chart's texture).
//!
//! Data types:
//! - [`ChartMesh`]: the chart, a triangle mesh with 3D `positions` (any frame whose x, y map
//!   affinely to the source image: world, or cell-local plus an offset), `triangles` (vertex
//!   indices, either orientation) and per-vertex `uvs`, the target texture coordinates in
//!   `[0, 1]²` (u east/right, v down = image rows; texel `(i, j)` covers
//!   `u ∈ [i, i+1] / texels`, `v ∈ [j, j+1] / texels`).
//! - [`Source`]: a top-down (ortho) RGBA image (alpha 0 = unknown colour) and a
//!   [`PixelMap`], the affine map from a position's `(x, y)` to fractional source pixel
//!   coordinates `(col, row)` with pixel centres at integers. A 3D point's colour is the
//!   source colour at its `(x, y)`.
//! - [`ResampleOptions`]: [`Mode`] (subtexel estimate, bilinear only, or exact), the
//!   texture size `texels` (square), the [`Fill`] for texels no triangle covers and the
//!   gutter width.
//! - [`Resampled`]: the texture, the per-texel coverage mask and [`ResampleStats`].
//!
//! [`resample`] scan-converts the chart in texture space (exact integer edge functions,
//! top-left rule), maps each covered texel's square through its triangle's affine map
//! (texture → surface → source pixels) to a parallelogram footprint, and averages the
//! known source pixels it overlaps, weighted by overlap area (estimated with N x N
//! subtexels, or exact by polygon clipping). Footprints whose total overlap is below
//! [`MIN_FOOTPRINT_AREA`] source pixels (vertical walls, where the footprint collapses to
//! a segment) use a bilinear lookup at the footprint centre instead. Texels without a
//! known colour are then filled (gutter dilation, then average border colour or pull-push)
//! in RGB only, with alpha 0. For an orthographic chart (uv = planar position over the
//! cell square) this is plain area-averaged resampling of the source.
//!
//! The result is identical whatever the rayon thread count; work is parallel over texture
//! rows with per-row scratch space and no per-texel allocation.

mod bilinear;
mod exact;
pub mod fill;
mod footprint;
mod kernel;
mod raster;
mod subtexel;
mod texel;

use std::time::{Duration, Instant};

use image::RgbaImage;
use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::georef::GridGeoref;

#[cfg(test)]
pub(crate) use exact::polygon_box_area;
pub use kernel::MIN_FOOTPRINT_AREA;
pub use subtexel::MAX_SUBTEXELS;

/// Largest accepted texture size (texels per side).
pub const MAX_TEXELS: u32 = 8192;

/// Subtexels per axis used by [`ResampleOptions::default`] (see docs/resampling.md).
pub const DEFAULT_SUBTEXELS: u32 = 4;

/// Largest accepted |u| or |v| (the texture itself is `[0, 1]²`; the bound keeps the
/// integer rasterizer exact).
pub const MAX_ABS_UV: f64 = 64.0;

/// A chart: a triangle mesh with 3D positions and target texture coordinates.
#[derive(Clone, Copy, Debug)]
pub struct ChartMesh<'a> {
    /// Vertex positions; only x and y are used to look up colour (see [`Source`]).
    pub positions: &'a [[f64; 3]],
    /// Vertex indices per triangle (either winding).
    pub triangles: &'a [[u32; 3]],
    /// Per-vertex texture coordinates, `[0, 1]²`, u right, v down; same length as `positions`.
    pub uvs: &'a [[f64; 2]],
}

/// An affine map from a position's `(x, y)` to fractional source pixel coordinates:
/// `col = m[0][0]*x + m[0][1]*y + m[0][2]`, `row = m[1][0]*x + m[1][1]*y + m[1][2]`
/// (pixel centres at integer coordinates).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PixelMap {
    /// The 2x3 matrix.
    pub m: [[f64; 3]; 2],
}

impl PixelMap {
    /// For a source image georeferenced by `georef` (pixel centres) and positions given in
    /// a frame whose origin is at world `(frame_offset[0], frame_offset[1])` (use
    /// `[0.0, 0.0]` for world positions).
    pub fn from_georef(georef: &GridGeoref, frame_offset: [f64; 2]) -> Self {
        let (sx, sy) = (georef.spacing_x, georef.spacing_y);
        PixelMap {
            m: [
                [1.0 / sx, 0.0, (frame_offset[0] - georef.origin_x) / sx],
                [0.0, -1.0 / sy, (georef.origin_y - frame_offset[1]) / sy],
            ],
        }
    }

    /// Source pixel coordinates `(col, row)` of `(x, y)`.
    #[inline]
    pub fn apply(&self, x: f64, y: f64) -> [f64; 2] {
        let m = &self.m;
        [
            m[0][0] * x + m[0][1] * y + m[0][2],
            m[1][0] * x + m[1][1] * y + m[1][2],
        ]
    }
}

/// The colour source: a top-down image placed by an affine pixel map.
#[derive(Clone, Copy, Debug)]
pub struct Source<'a> {
    /// RGBA colour; alpha 0 marks unknown colour (such pixels never contribute).
    pub image: &'a RgbaImage,
    /// From position `(x, y)` to source pixel `(col, row)`.
    pub to_pixel: PixelMap,
}

/// How a texel's colour is computed from the source pixels under its footprint.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Mode {
    /// Area-weighted average with each overlap area estimated by n x n subtexels
    /// (1 ..= [`MAX_SUBTEXELS`]).
    Subtexel(u32),
    /// A single bilinear lookup at the footprint centre (no area averaging).
    Bilinear,
    /// Area-weighted average with exact overlap areas (polygon clipping): the reference.
    Exact,
}

/// How texels without a known colour are filled (RGB only; their alpha stays 0).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fill {
    /// One colour: the mean of the known texels bordering an unknown one.
    AverageBorder,
    /// Pull-push (mip pyramid) interpolation of the known colours.
    PullPush,
}

/// Parameters of [`resample`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResampleOptions {
    /// Colour computation.
    pub mode: Mode,
    /// Texture size in texels per side (1 ..= [`MAX_TEXELS`]).
    pub texels: u32,
    /// Fill of texels without a known colour.
    pub fill: Fill,
    /// Gutter width: known colours are dilated this many texels into the empty area before
    /// the fill, so mipmapped rendering does not pull the fill colour into chart borders.
    pub gutter_texels: u32,
}

impl Default for ResampleOptions {
    fn default() -> Self {
        ResampleOptions {
            mode: Mode::Subtexel(DEFAULT_SUBTEXELS),
            texels: 256,
            fill: Fill::AverageBorder,
            gutter_texels: 4,
        }
    }
}

impl ResampleOptions {
    /// Rejects out-of-range sizes and subtexel counts.
    pub fn validate(&self) -> Result<()> {
        if self.texels == 0 || self.texels > MAX_TEXELS {
            return Err(Error::BadOption(format!(
                "texture size must be 1..={MAX_TEXELS} texels, got {}",
                self.texels
            )));
        }
        if let Mode::Subtexel(n) = self.mode
            && (n == 0 || n > MAX_SUBTEXELS)
        {
            return Err(Error::BadOption(format!(
                "subtexel count must be 1..={MAX_SUBTEXELS}, got {n}"
            )));
        }
        Ok(())
    }
}

/// Counts describing one [`resample`] run.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ResampleStats {
    /// Texels whose centre a chart triangle covers.
    pub covered_texels: usize,
    /// Covered texels that got a known colour (alpha 255).
    pub known_texels: usize,
    /// Covered texels whose footprint collapsed and used the bilinear fallback.
    pub bilinear_fallbacks: usize,
    /// Covered texels with no known source colour under them (alpha 0, filled).
    pub unknown_covered_texels: usize,
    /// Texels coloured by gutter dilation.
    pub gutter_texels: usize,
    /// Texels coloured by the fill after the gutter (covered-unknown or empty).
    pub filled_texels: usize,
}

/// The resampled texture.
#[derive(Clone, Debug)]
pub struct Resampled {
    /// `texels x texels` RGBA; alpha 255 exactly on covered texels with a known colour,
    /// 0 elsewhere (whose RGB holds the gutter/fill colour).
    pub image: RgbaImage,
    /// Row-major, per texel: a chart triangle covers its centre.
    pub covered: Vec<bool>,
    /// Counts.
    pub stats: ResampleStats,
}

/// Read-only view of the source pixels.
pub(crate) struct SrcView<'a> {
    data: &'a [u8],
    w: i64,
    h: i64,
}

impl SrcView<'_> {
    /// RGB of pixel `(c, r)` if inside the image and known (alpha > 0).
    #[inline]
    fn get(&self, c: i64, r: i64) -> Option<[u8; 3]> {
        if c < 0 || r < 0 || c >= self.w || r >= self.h {
            return None;
        }
        let i = ((r * self.w + c) * 4) as usize;
        let p = &self.data[i..i + 4];
        (p[3] > 0).then(|| [p[0], p[1], p[2]])
    }
}

fn check_chart(chart: &ChartMesh, to_pixel: &PixelMap) -> Result<()> {
    if chart.uvs.len() != chart.positions.len() {
        return Err(Error::BadOption(format!(
            "chart has {} positions but {} uvs",
            chart.positions.len(),
            chart.uvs.len()
        )));
    }
    if !to_pixel.m.iter().flatten().all(|v| v.is_finite()) {
        return Err(Error::BadOption("source pixel map is not finite".into()));
    }
    for (i, (p, uv)) in chart.positions.iter().zip(chart.uvs).enumerate() {
        if !p.iter().all(|v| v.is_finite()) {
            return Err(Error::BadOption(format!(
                "chart position {i} is not finite: {p:?}"
            )));
        }
        if !uv.iter().all(|v| v.is_finite() && v.abs() <= MAX_ABS_UV) {
            return Err(Error::BadOption(format!(
                "chart uv {i} is not finite or beyond ±{MAX_ABS_UV}: {uv:?}"
            )));
        }
    }
    let n = chart.positions.len();
    if let Some((t, tri)) = chart
        .triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&k| k as usize >= n))
    {
        return Err(Error::BadOption(format!(
            "chart triangle {t} {tri:?} refers to a vertex beyond the {n} vertices"
        )));
    }
    Ok(())
}

/// Resamples the source colour into a `texels x texels` texture for `chart`.
///
/// Errors (never panics) on invalid options, mismatched `uvs`/`positions` lengths,
/// out-of-range vertex indices, non-finite coordinates or |uv| > [`MAX_ABS_UV`].
/// Zero-area and degenerate triangles are allowed (they cover nothing, or collapse to
/// the bilinear fallback). Deterministic for any thread count.
pub fn resample(chart: &ChartMesh, src: &Source, opts: &ResampleOptions) -> Result<Resampled> {
    resample_timed(chart, src, opts).map(|(r, _)| r)
}

/// Wall-clock time spent in each stage of one [`resample`] call (for benchmarks; the
/// texture does not depend on it).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ResampleTimings {
    /// Validation, per-triangle maps and scan conversion.
    pub prepare: Duration,
    /// The per-texel colour kernel (area weights or bilinear), all rows.
    pub kernel: Duration,
    /// Coverage counts, gutter dilation and fill.
    pub fill: Duration,
}

/// [`resample`], also returning how long each stage took. The result is identical to
/// [`resample`]'s.
pub fn resample_timed(
    chart: &ChartMesh,
    src: &Source,
    opts: &ResampleOptions,
) -> Result<(Resampled, ResampleTimings)> {
    let t_start = Instant::now();
    opts.validate()?;
    check_chart(chart, &src.to_pixel)?;
    let t = opts.texels;
    let n = t as usize;
    let maps: Vec<Option<footprint::Affine2>> = chart
        .triangles
        .par_iter()
        .map(|&tri| footprint::triangle_map(chart, tri, t, &src.to_pixel))
        .collect();
    let st: Vec<[f64; 2]> = chart
        .uvs
        .iter()
        .map(|uv| [uv[0] * t as f64, uv[1] * t as f64])
        .collect();
    let ids = raster::rasterize(&st, chart.triangles, t, |i| maps[i].is_some());
    // per-triangle footprint constants for the subtexel kernel
    let shapes: Vec<Option<footprint::Shape>> = match opts.mode {
        Mode::Subtexel(_) => maps
            .par_iter()
            .map(|m| m.and_then(|m| footprint::Shape::new(&m, MIN_FOOTPRINT_AREA)))
            .collect(),
        _ => Vec::new(),
    };

    let view = SrcView {
        data: src.image.as_raw(),
        w: src.image.width() as i64,
        h: src.image.height() as i64,
    };
    let t_kernel = Instant::now();
    let mut buf = vec![0u8; n * n * 4];
    let mut known = vec![false; n * n];
    let mut fallbacks = vec![0usize; n];
    buf.par_chunks_mut(n * 4)
        .zip(known.par_chunks_mut(n))
        .zip(fallbacks.par_iter_mut())
        .enumerate()
        .for_each_init(
            kernel::Scratch::default,
            |scratch, (j, ((row, krow), nfb))| {
                for i in 0..n {
                    let tri = ids[j * n + i];
                    if tri == raster::EMPTY {
                        continue;
                    }
                    let Some(map) = maps[tri as usize] else {
                        continue;
                    };
                    let (iu, ju) = (i as u32, j as u32);
                    let tc = match opts.mode {
                        Mode::Subtexel(sub) => subtexel::texel_colour(
                            &view,
                            &map,
                            shapes[tri as usize].as_ref(),
                            iu,
                            ju,
                            sub,
                            scratch,
                        ),
                        _ => kernel::texel_colour(
                            &view,
                            &map.texel_footprint(iu, ju),
                            opts.mode,
                            scratch,
                        ),
                    };
                    *nfb += tc.fallback as usize;
                    if tc.known {
                        let px = &mut row[i * 4..i * 4 + 4];
                        for (p, c) in px.iter_mut().zip(tc.rgb) {
                            // round half up (c >= 0 after the clamp); no libm call
                            *p = (c.clamp(0.0, 255.0) + 0.5) as u8;
                        }
                        px[3] = 255;
                        krow[i] = true;
                    }
                }
            },
        );
    let t_fill = Instant::now();
    let Some(mut image) = RgbaImage::from_raw(t, t, buf) else {
        return Err(Error::BadOption(format!(
            "texture of {t} x {t} texels could not be allocated"
        )));
    };
    let covered: Vec<bool> = ids.iter().map(|&i| i != raster::EMPTY).collect();
    let covered_texels = covered.iter().filter(|&&c| c).count();
    let known_texels = known.iter().filter(|&&k| k).count();
    let mut assigned = known;
    let gutter_texels = fill::dilate_gutter(&mut image, &mut assigned, opts.gutter_texels);
    let filled_texels = match opts.fill {
        Fill::AverageBorder => fill::fill_average_border(&mut image, &assigned),
        Fill::PullPush => fill::fill_pull_push(&mut image, &assigned),
    };
    let resampled = Resampled {
        image,
        covered,
        stats: ResampleStats {
            covered_texels,
            known_texels,
            bilinear_fallbacks: fallbacks.iter().sum(),
            unknown_covered_texels: covered_texels - known_texels,
            gutter_texels,
            filled_texels,
        },
    };
    let t_end = Instant::now();
    Ok((
        resampled,
        ResampleTimings {
            prepare: t_kernel - t_start,
            kernel: t_fill - t_kernel,
            fill: t_end - t_fill,
        },
    ))
}
