//! Per-cell normal maps from the full-resolution DEM.
//!
//! Texel layout as for [`ortho_texture`](crate::cells::ortho_texture): `T x T` texels over
//! the cell's nominal square, row 0 north. Each texel stores the unit surface normal in
//! the cell-local frame, whose axes are the world axes (x east, y north, z up), encoded
//! per channel as `round((n * 0.5 + 0.5) * 255)`.
//!
//! **Filter**: the normal is built from the *mean gradient* of the bilinear DEM surface over
//! the texel's filter box — the texel square widened about its centre to at least one DEM
//! sample spacing per axis. By the divergence theorem the mean of `dh/dx` over a box is the
//! difference of the mean heights along its east and west edges divided by its width; the
//! edge means are integrated exactly (the bilinear surface is piecewise linear along a grid
//! line; per texel row the column-line means and row-line integrals are tabulated once, so
//! each texel costs O(1)). At coarse levels (texel wider than a sample) this is the gradient box-filtered over
//! the texel footprint; at fine levels it is a central difference of bilinear heights at
//! ±half a sample. Near and beyond the DEM's data rectangle the box is shifted (and if
//! necessary shrunk) to lie inside it, i.e. the normal of the nearest data is used. Any
//! plane is reproduced exactly.

use image::RgbImage;
use rayon::prelude::*;

use crate::dem::Dem;
use crate::georef::WorldRect;

/// Renders the `texels x texels` normal map of `dem` over the world rectangle `extent`
/// (normally a cell's nominal square), as defined in the [module docs](self): unit normals in
/// the world frame (x east, y north, z up) encoded `n * 0.5 + 0.5` in 0..=255, computed from
/// the full-resolution DEM with footprint-filtered gradients, clamped to the DEM's data.
/// Row 0 is the north edge. Deterministic for any thread count. A degenerate or non-finite
/// `extent` gives "straight up" normals `(128, 128, 255)`.
pub fn normal_map(dem: &Dem, extent: WorldRect, texels: u32) -> RgbImage {
    let t = texels as usize;
    let mut buf = vec![0u8; t * t * 3];
    let valid = extent.width() > 0.0
        && extent.height() > 0.0
        && extent.width().is_finite()
        && extent.height().is_finite();
    if !valid {
        for px in buf.chunks_exact_mut(3) {
            px.copy_from_slice(&encode([0.0, 0.0, 1.0]));
        }
        return RgbImage::from_raw(texels, texels, buf).unwrap_or_default();
    }
    let g = dem.georef;
    // filter boxes in grid coordinates, per texel column (cols) and row (rows)
    let cols: Vec<(f64, f64)> = (0..t)
        .map(|i| {
            let x = extent.min_x + extent.width() * ((i as f64 + 0.5) / t as f64);
            let c = (x - g.origin_x) / g.spacing_x;
            let fw = extent.width() / t as f64 / g.spacing_x;
            filter_box(c, fw, dem.width)
        })
        .collect();
    let rows: Vec<(f64, f64)> = (0..t)
        .map(|j| {
            let y = extent.max_y - extent.height() * ((j as f64 + 0.5) / t as f64);
            let r = (g.origin_y - y) / g.spacing_y;
            let fh = extent.height() / t as f64 / g.spacing_y;
            filter_box(r, fh, dem.height)
        })
        .collect();

    // integer DEM columns touched by any filter box
    let kmin = (cols
        .iter()
        .map(|c| c.0)
        .fold(f64::INFINITY, f64::min)
        .floor()
        .max(0.0) as usize)
        .min(dem.width - 2);
    let kmax = (cols.iter().map(|c| c.1).fold(0.0, f64::max).ceil() as usize)
        .clamp(kmin + 1, dem.width - 1);
    let span = kmax - kmin + 1;

    buf.par_chunks_mut(t * 3).enumerate().for_each(|(j, row)| {
        let (r0, r1) = rows[j];
        // Per texel row (allocated once per row): for every integer column k of the span,
        // m[k] = mean of h(., k) over rows [r0, r1] (the bilinear surface is linear in the
        // column between integer columns, so column-line means interpolate linearly), and the
        // running integrals along the row lines r0 and r1 (for the row-line means).
        let mut m = Vec::with_capacity(span);
        let (mut g0, mut g1) = (Vec::with_capacity(span), Vec::with_capacity(span));
        for k in kmin..=kmax {
            m.push(line_mean(dem, Line::Col(k as f64), r0, r1));
            g0.push(height_on_col(dem, k, r0));
            g1.push(height_on_col(dem, k, r1));
        }
        let (p0, p1) = (prefix_integral(&g0), prefix_integral(&g1));
        for (i, &(c0, c1)) in cols.iter().enumerate() {
            let (a, b) = (c0 - kmin as f64, c1 - kmin as f64);
            let dh_dcol = (lerp_at(&m, b) - lerp_at(&m, a)) / (c1 - c0);
            let mean_r1 = (integral_to(&p1, &g1, b) - integral_to(&p1, &g1, a)) / (c1 - c0);
            let mean_r0 = (integral_to(&p0, &g0, b) - integral_to(&p0, &g0, a)) / (c1 - c0);
            let dh_drow = (mean_r1 - mean_r0) / (r1 - r0);
            let gx = dh_dcol / g.spacing_x;
            let gy = -dh_drow / g.spacing_y; // rows run south
            let len = (gx * gx + gy * gy + 1.0).sqrt();
            row[i * 3..i * 3 + 3].copy_from_slice(&encode([-gx / len, -gy / len, 1.0 / len]));
        }
    });
    RgbImage::from_raw(texels, texels, buf).unwrap_or_default()
}

/// Bilinear height at integer column `k` and fractional row `r` (inside the data).
fn height_on_col(dem: &Dem, k: usize, r: f64) -> f64 {
    let r0 = (r.floor().max(0.0) as usize).min(dem.height - 2);
    let f = r - r0 as f64;
    let (p, q) = (dem.at(r0, k) as f64, dem.at(r0 + 1, k) as f64);
    p + (q - p) * f
}

/// `out[k]` = integral from 0 to k of the piecewise-linear function through `v`.
fn prefix_integral(v: &[f64]) -> Vec<f64> {
    let mut out = Vec::with_capacity(v.len());
    let mut acc = 0.0;
    out.push(0.0);
    for w in v.windows(2) {
        acc += 0.5 * (w[0] + w[1]);
        out.push(acc);
    }
    out
}

/// Linear interpolation of `v` (at least 2 values) at fractional index `x` in `[0, len - 1]`.
#[inline]
fn lerp_at(v: &[f64], x: f64) -> f64 {
    let k = (x.floor().max(0.0) as usize).min(v.len() - 2);
    let f = x - k as f64;
    v[k] + (v[k + 1] - v[k]) * f
}

/// Integral from 0 to `x` of the piecewise-linear function through `v`, given its
/// [`prefix_integral`] `p`.
#[inline]
fn integral_to(p: &[f64], v: &[f64], x: f64) -> f64 {
    let k = (x.floor().max(0.0) as usize).min(v.len() - 2);
    let f = x - k as f64;
    p[k] + f * (v[k] + 0.5 * f * (v[k + 1] - v[k]))
}

fn encode(n: [f64; 3]) -> [u8; 3] {
    n.map(|v| ((v * 0.5 + 0.5) * 255.0).round().clamp(0.0, 255.0) as u8)
}

/// The filter interval along one grid axis of `n >= 2` samples: width `max(footprint, 1)`
/// (capped at the data width `n - 1`), centred on `centre`, shifted inside `[0, n - 1]`.
fn filter_box(centre: f64, footprint: f64, n: usize) -> (f64, f64) {
    let span = (n - 1) as f64;
    let w = footprint.max(1.0).min(span);
    let lo = (centre - 0.5 * w).clamp(0.0, span - w);
    (lo, lo + w)
}

/// A grid line at a fractional column (varying row) or fractional row (varying column).
#[derive(Clone, Copy)]
#[cfg_attr(not(test), allow(dead_code))]
enum Line {
    Col(f64),
    Row(f64),
}

/// Exact mean of the bilinear DEM surface along `line` between positions `a < b` of the
/// varying coordinate (all inside the data rectangle).
fn line_mean(dem: &Dem, line: Line, a: f64, b: f64) -> f64 {
    let (w, h) = (dem.width, dem.height);
    // value at integer position k of the varying axis, interpolated across the fixed axis
    let (fixed, n_fixed, n_var) = match line {
        Line::Col(c) => (c, w, h),
        Line::Row(r) => (r, h, w),
    };
    let f0 = (fixed.floor().max(0.0) as usize).min(n_fixed - 2);
    let ff = fixed - f0 as f64;
    let node = |k: usize| -> f64 {
        let (p, q) = match line {
            Line::Col(_) => (dem.at(k, f0) as f64, dem.at(k, f0 + 1) as f64),
            Line::Row(_) => (dem.at(f0, k) as f64, dem.at(f0 + 1, k) as f64),
        };
        p + (q - p) * ff
    };
    let at = |s: f64| -> f64 {
        let k = (s.floor().max(0.0) as usize).min(n_var - 2);
        let fs = s - k as f64;
        let (p, q) = (node(k), node(k + 1));
        p + (q - p) * fs
    };
    // trapezoid rule with breakpoints at the integer positions inside (a, b): exact
    let mut sum = 0.0;
    let mut s0 = a;
    let mut v0 = at(a);
    let mut k = a.floor() + 1.0;
    while k < b {
        let v = at(k);
        sum += 0.5 * (v0 + v) * (k - s0);
        s0 = k;
        v0 = v;
        k += 1.0;
    }
    let vb = at(b);
    sum += 0.5 * (v0 + vb) * (b - s0);
    sum / (b - a)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::georef::GridGeoref;

    fn plane_dem(w: usize, h: usize, g: GridGeoref, p: f64, q: f64) -> Dem {
        let mut z = Vec::with_capacity(w * h);
        for r in 0..h {
            for c in 0..w {
                let (x, y) = g.world(r as f64, c as f64);
                z.push((p * (x - g.origin_x) + q * (y - g.origin_y) + 100.0) as f32);
            }
        }
        Dem::from_heights(w, h, z, g).unwrap()
    }

    #[test]
    fn tilted_plane_gives_analytic_normal_everywhere() {
        let g = GridGeoref {
            origin_x: 445302.0,
            origin_y: 7396769.0,
            spacing_x: 3.0,
            spacing_y: 2.0,
        };
        let (p, q) = (0.75, -1.25); // dh/dx, dh/dy
        let dem = plane_dem(70, 50, g, p, q);
        let len = (p * p + q * q + 1.0f64).sqrt();
        let want = encode([-p / len, -q / len, 1.0 / len]);
        let data = dem.extent();
        // coarse (texel 4 x 4 samples), fine (texel 1/4 sample), and extending past the DEM
        let cases = [
            (
                WorldRect {
                    min_x: data.min_x,
                    max_x: data.min_x + 192.0,
                    min_y: data.max_y - 128.0,
                    max_y: data.max_y,
                },
                16,
            ),
            (
                WorldRect {
                    min_x: data.min_x + 30.0,
                    max_x: data.min_x + 54.0,
                    min_y: data.min_y + 20.0,
                    max_y: data.min_y + 36.0,
                },
                32,
            ),
            (
                WorldRect {
                    min_x: data.min_x + 150.0,
                    max_x: data.min_x + 406.0,
                    min_y: data.min_y - 100.0,
                    max_y: data.min_y + 156.0,
                },
                64,
            ),
        ];
        for (ext, t) in cases {
            let nm = normal_map(&dem, ext, t);
            for (i, j, px) in nm.enumerate_pixels() {
                for k in 0..3 {
                    assert!(
                        (px.0[k] as i32 - want[k] as i32).abs() <= 1,
                        "texel ({i},{j}): {:?} vs {want:?}",
                        px.0
                    );
                }
            }
        }
    }

    #[test]
    fn flat_dem_points_up_and_ridge_is_resolved() {
        let g = GridGeoref::new(0.0, 16.0, 1.0);
        let dem = Dem::from_heights(17, 17, vec![5.0; 17 * 17], g).unwrap();
        let ext = dem.extent();
        assert!(
            normal_map(&dem, ext, 8)
                .pixels()
                .all(|p| p.0 == [128, 128, 255])
        );
        // a west-facing slope (h = -x) east of x = 8, flat to the west
        let z: Vec<f32> = (0..17 * 17)
            .map(|k| -((k % 17) as f32 - 8.0).max(0.0))
            .collect();
        let dem = Dem::from_heights(17, 17, z, g).unwrap();
        let nm = normal_map(&dem, ext, 16);
        let s = (0.5f64).sqrt();
        assert_eq!(nm.get_pixel(15, 5).0, encode([s, 0.0, s]));
        assert_eq!(nm.get_pixel(2, 5).0, [128, 128, 255]);
    }

    #[test]
    fn line_mean_is_exact_for_piecewise_linear_data() {
        let g = GridGeoref::new(0.0, 3.0, 1.0);
        // column 0 heights along rows: 0, 4, 4, 0
        let z = vec![0.0, 0.0, 4.0, 4.0, 4.0, 4.0, 0.0, 0.0];
        let dem = Dem::from_heights(2, 4, z, g).unwrap();
        // mean over rows [0.5, 2.5]: pieces 0.5*(2+4)/2 + 1*4 + 0.5*(4+2)/2 = 1.5 + 4 + 1.5 = 7 over 2
        assert!((line_mean(&dem, Line::Col(0.0), 0.5, 2.5) - 3.5).abs() < 1e-12);
        assert!((line_mean(&dem, Line::Row(1.0), 0.0, 1.0) - 4.0).abs() < 1e-12);
    }
}
