//! Per-cell ortho textures.
//!
//! A cell texture of `T x T` texels covers the cell's nominal square (see
//! [`nominal_extent`](crate::cells::nominal_extent)); texel `(i, j)` (column `i` west to
//! east, row `j` north to south) is the square `[u_i, u_{i+1}] x [v_j, v_{j+1}]` of the
//! extent with `u_i = i / T`, `v_j = j / T` (v measured southwards from the north edge), so
//! its centre lies at `((i + 0.5) / T, (j + 0.5) / T)`.
//!
//! **Filter** (one area-weighted formulation for both regimes): the texel's colour is the
//! average of the ortho pixels (each a unit square around its centre) weighted by their
//! exact overlap with the texel's *filter footprint*: the texel square, widened about its
//! centre to at least one ortho pixel along each axis. When a texel spans more than one
//! pixel (minification, coarse levels) this is an exact box filter with fractional pixel
//! coverage; when it is smaller (magnification) the one-pixel box around the texel centre
//! gives exactly the bilinear-interpolation weights between the neighbouring pixel centres.
//! Pixel weights are multiplied by the ortho alpha, so unknown pixels never contribute colour
//! (at the image border this behaves like clamp-to-edge).
//!
//! **Alpha** = `round(255 * known)` where `known` is the fraction of the texel's *true*
//! square that is known: `known = ortho_known * dem_known`, with `ortho_known` the
//! alpha-weighted fraction covered by ortho pixels (0 outside the image or under alpha-0
//! pixels) and `dem_known` the fraction inside the DEM's data rectangle (the rectangle of
//! sample centres) and not over a void sample (each sample owns the unit square around its
//! centre). Fully known texels get 255, unknown ones 0, partly known ones the rounded
//! fraction (not binarised). DEM voids lower the alpha but do not change the colour.
//! Texels without any known ortho pixel in their filter footprint are `[0, 0, 0, 0]`.

use image::RgbaImage;
use rayon::prelude::*;

use crate::cells::taps::{AxisTaps, footprints};
use crate::dem::Dem;
use crate::georef::WorldRect;
use crate::ortho::Ortho;

/// Renders the `texels x texels` RGBA texture of `ortho` over the world rectangle `extent`
/// (normally a cell's nominal square), as defined in the [module docs](self): area-filtered
/// colour, alpha = rounded known fraction (0 outside the ortho, under ortho alpha 0, outside
/// the DEM data rectangle and over DEM voids). Row 0 is the north edge. Deterministic for
/// any thread count. A degenerate or non-finite `extent` gives a fully transparent image.
pub fn ortho_texture(ortho: &Ortho, dem: &Dem, extent: WorldRect, texels: u32) -> RgbaImage {
    let t = texels as usize;
    let mut buf = vec![0u8; t * t * 4];
    let valid = extent.width() > 0.0
        && extent.height() > 0.0
        && extent.width().is_finite()
        && extent.height().is_finite();
    let (iw, ih) = (ortho.image.width() as usize, ortho.image.height() as usize);
    if t == 0 || !valid || iw == 0 || ih == 0 {
        return RgbaImage::from_raw(texels, texels, buf).unwrap_or_default();
    }

    // Ortho taps (pixel squares, widened filter of one pixel).
    let og = ortho.georef;
    let ox = AxisTaps::new(
        iw,
        footprints(extent.min_x, extent.max_x, texels, |x| {
            (x - og.origin_x) / og.spacing_x
        }),
        (-0.5, iw as f64 - 0.5),
        1.0,
    );
    // rows: north (max_y) to south; grid row increases southwards
    let oy = AxisTaps::new(
        ih,
        footprints(-extent.max_y, -extent.min_y, texels, |ny| {
            (og.origin_y + ny) / og.spacing_y
        }),
        (-0.5, ih as f64 - 0.5),
        1.0,
    );
    // DEM coverage taps (sample squares clipped to the data rectangle).
    let dg = dem.georef;
    let (dw, dh) = (dem.width, dem.height);
    let dx = AxisTaps::new(
        dw,
        footprints(extent.min_x, extent.max_x, texels, |x| {
            (x - dg.origin_x) / dg.spacing_x
        }),
        (0.0, dw as f64 - 1.0),
        0.0,
    );
    let dy = AxisTaps::new(
        dh,
        footprints(-extent.max_y, -extent.min_y, texels, |ny| {
            (dg.origin_y + ny) / dg.spacing_y
        }),
        (0.0, dh as f64 - 1.0),
        0.0,
    );
    let any_void = match (dx.span(), dy.span()) {
        (Some((c0, c1)), Some((r0, r1))) => {
            (r0..=r1).any(|r| dem.void[r * dw + c0..=r * dw + c1].iter().any(|&v| v))
        }
        _ => false,
    };
    let dx_sum: Vec<f64> = (0..t).map(|i| dx.cov_sum(i)).collect();
    let raw = ortho.image.as_raw();

    buf.par_chunks_mut(t * 4).enumerate().for_each(|(j, row)| {
        let yr = oy.range(j);
        let dy_sum = dy.cov_sum(j);
        for i in 0..t {
            let xr = ox.range(i);
            let (mut cov, mut wsum) = (0.0f64, 0.0f64);
            let mut rgb = [0.0f64; 3];
            for (k, yo) in yr.clone().enumerate() {
                let (wcy, wfy) = (oy.cov[yo], oy.filt[yo]);
                let base = (oy.first[j] + k) * iw;
                for (m, xo) in xr.clone().enumerate() {
                    let p = (base + ox.first[i] + m) * 4;
                    let a = raw[p + 3] as f64;
                    if a == 0.0 {
                        continue;
                    }
                    cov += wcy * ox.cov[xo] * a;
                    let w = wfy * ox.filt[xo] * a;
                    wsum += w;
                    rgb[0] += w * raw[p] as f64;
                    rgb[1] += w * raw[p + 1] as f64;
                    rgb[2] += w * raw[p + 2] as f64;
                }
            }
            let area = ox.len[i] * oy.len[j];
            let ortho_known = cov / (255.0 * area);
            let dem_area = dx.len[i] * dy.len[j];
            let dem_known = if any_void {
                dem_known_with_voids(dem, &dx, &dy, i, j)
            } else {
                dx_sum[i] * dy_sum
            } / dem_area;
            let known = (ortho_known * dem_known).clamp(0.0, 1.0);
            let px = &mut row[i * 4..i * 4 + 4];
            if wsum > 0.0 {
                for c in 0..3 {
                    px[c] = (rgb[c] / wsum).round().clamp(0.0, 255.0) as u8;
                }
                px[3] = (known * 255.0).round() as u8;
            }
        }
    });
    RgbaImage::from_raw(texels, texels, buf).unwrap_or_default()
}

/// Area of texel (i, j)'s footprint over non-void samples inside the DEM data rectangle.
fn dem_known_with_voids(dem: &Dem, dx: &AxisTaps, dy: &AxisTaps, i: usize, j: usize) -> f64 {
    let mut s = 0.0;
    for (k, yo) in dy.range(j).enumerate() {
        let r = dy.first[j] + k;
        for (m, xo) in dx.range(i).enumerate() {
            if !dem.void[r * dem.width + dx.first[i] + m] {
                s += dy.cov[yo] * dx.cov[xo];
            }
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::georef::GridGeoref;
    use image::Rgba;

    fn flat_dem(w: usize, h: usize, g: GridGeoref) -> Dem {
        Dem::from_heights(w, h, vec![0.0; w * h], g).unwrap()
    }

    fn ortho_from(w: u32, h: u32, g: GridGeoref, f: impl Fn(u32, u32) -> [u8; 4]) -> Ortho {
        Ortho {
            image: RgbaImage::from_fn(w, h, |c, r| Rgba(f(c, r))),
            georef: g,
        }
    }

    #[test]
    fn constant_ortho_gives_constant_texture() {
        let g = GridGeoref::new(500.0, 900.0, 1.0);
        let dem = flat_dem(101, 101, g);
        let ortho = ortho_from(101, 101, g, |_, _| [10, 200, 77, 255]);
        let ext = WorldRect {
            min_x: 510.0,
            min_y: 820.0,
            max_x: 574.0,
            max_y: 884.0,
        };
        for t in [16, 64, 256] {
            let tex = ortho_texture(&ortho, &dem, ext, t);
            assert_eq!(tex.dimensions(), (t, t));
            assert!(tex.pixels().all(|p| p.0 == [10, 200, 77, 255]), "T={t}");
        }
    }

    /// Ortho whose red channel is 2 * column and green 3 * row (exact at pixel centres).
    fn gradient_ortho(g: GridGeoref) -> Ortho {
        ortho_from(120, 80, g, |c, r| [(2 * c) as u8, (3 * r) as u8, 50, 255])
    }

    fn check_gradient(t: u32, ext: WorldRect, g: GridGeoref, tol: f64) {
        let dem = flat_dem(121, 81, g);
        let ortho = gradient_ortho(g);
        let tex = ortho_texture(&ortho, &dem, ext, t);
        let mut worst = 0.0f64;
        for j in 0..t {
            for i in 0..t {
                let x = ext.min_x + ext.width() * (i as f64 + 0.5) / t as f64;
                let y = ext.max_y - ext.height() * (j as f64 + 0.5) / t as f64;
                let (row, col) = g.grid(x, y);
                let p = tex.get_pixel(i, j).0;
                assert_eq!(p[3], 255);
                assert_eq!(p[2], 50);
                worst = worst
                    .max((p[0] as f64 - 2.0 * col).abs())
                    .max((p[1] as f64 - 3.0 * row).abs());
            }
        }
        assert!(worst <= tol, "T={t}: worst error {worst} > {tol}");
    }

    #[test]
    fn gradient_magnified_is_bilinear() {
        // 20 x 20 pixels onto 160 x 160 texels (8 texels per pixel), away from the border
        let g = GridGeoref {
            origin_x: 1000.0,
            origin_y: 2000.0,
            spacing_x: 2.0,
            spacing_y: 2.0,
        };
        let ext = WorldRect {
            min_x: 1000.0 + 2.0 * 30.0,
            max_x: 1000.0 + 2.0 * 50.0,
            min_y: 2000.0 - 2.0 * 60.0,
            max_y: 2000.0 - 2.0 * 40.0,
        };
        check_gradient(160, ext, g, 0.5 + 1e-9);
    }

    #[test]
    fn gradient_minified_is_box_average() {
        // 100 x 64 pixels onto 16 x 16 texels (6.25 x 4 pixels per texel, fractional coverage)
        let g = GridGeoref::new(0.0, 0.0, 1.0);
        let ext = WorldRect {
            min_x: 5.0,
            max_x: 105.0,
            min_y: -72.0,
            max_y: -8.0,
        };
        // box average of the pixel staircase deviates from the linear value by at most
        // slope / (8 * footprint) per axis, plus 0.5 for rounding
        check_gradient(16, ext, g, 0.5 + 3.0 / 32.0 + 1e-9);
    }

    #[test]
    fn alpha_at_ortho_edge_and_alpha_zero_pixels() {
        // DEM 0..=63; ortho covers columns 0..=31 only (pixel edges -0.5..31.5)
        let g = GridGeoref::new(0.0, 63.0, 1.0);
        let dem = flat_dem(64, 64, g);
        let ortho = ortho_from(32, 64, g, |c, r| {
            if r >= 40 && c < 8 {
                [9, 9, 9, 0]
            } else {
                [100, 100, 100, 255]
            }
        });
        // extent [-0.5, 63.5] split into 64 texels of one pixel each: texel i == pixel i
        let ext = WorldRect {
            min_x: -0.5,
            max_x: 63.5,
            min_y: -0.5,
            max_y: 63.5,
        };
        let tex = ortho_texture(&ortho, &dem, ext, 64);
        for j in 1..63 {
            for i in 1..63 {
                let a = tex.get_pixel(i, j).0[3];
                let want = if i >= 32 || (j >= 40 && i < 8) {
                    0
                } else {
                    255
                };
                assert_eq!(a, want, "texel ({i},{j})");
                if want == 255 {
                    assert_eq!(&tex.get_pixel(i, j).0[..3], &[100, 100, 100]);
                }
            }
        }
        // texels half over the ortho: 2 texels per pixel, ortho edge at x = 31.5
        let ext = WorldRect {
            min_x: 30.0,
            max_x: 34.0,
            min_y: 10.0,
            max_y: 14.0,
        };
        let tex = ortho_texture(&ortho, &dem, ext, 4);
        let alphas: Vec<u8> = (0..4).map(|i| tex.get_pixel(i, 1).0[3]).collect();
        // texel columns [30,31], [31,32], [32,33], [33,34]: known 1, 0.5, 0, 0
        assert_eq!(alphas, vec![255, 128, 0, 0]);
        assert_eq!(
            &tex.get_pixel(1, 1).0[..3],
            &[100, 100, 100],
            "colour from known pixels only"
        );
        assert_eq!(
            tex.get_pixel(2, 1).0,
            [0, 0, 0, 0],
            "no ortho pixel in the filter footprint"
        );
        // magnified texel [31.375, 31.625]: bilinear footprint [31, 32] sees only pixel 31
        let ext = WorldRect {
            min_x: 31.375,
            max_x: 31.625,
            min_y: 10.0,
            max_y: 10.25,
        };
        assert_eq!(
            ortho_texture(&ortho, &dem, ext, 1).get_pixel(0, 0).0,
            [100, 100, 100, 128]
        );
    }

    #[test]
    fn alpha_outside_dem_and_over_voids() {
        let g = GridGeoref::new(0.0, 31.0, 1.0);
        let mut dem = flat_dem(32, 32, g);
        // void block: samples rows 10..=13, cols 20..=23 -> world x [19.5, 23.5], y [17.5, 21.5]
        for r in 10..14 {
            for c in 20..24 {
                dem.void[r * 32 + c] = true;
            }
        }
        // ortho much larger than the DEM
        let og = GridGeoref::new(-50.0, 81.0, 0.5);
        let ortho = ortho_from(300, 300, og, |_, _| [1, 2, 3, 255]);
        // extent [0, 64] x [-33, 31]: the DEM data rectangle is x in [0, 31], y in [0, 31]
        let ext = WorldRect {
            min_x: 0.0,
            max_x: 64.0,
            min_y: -33.0,
            max_y: 31.0,
        };
        let tex = ortho_texture(&ortho, &dem, ext, 128); // texel = 0.5 world units
        for j in 0..128u32 {
            for i in 0..128u32 {
                let x0 = i as f64 * 0.5;
                let y1 = 31.0 - j as f64 * 0.5;
                let (x1, y0) = (x0 + 0.5, y1 - 0.5);
                let outside = x0 >= 31.0 || y1 <= 0.0;
                let in_void = x0 >= 19.5 && x1 <= 23.5 && y0 >= 17.5 && y1 <= 21.5;
                let inside =
                    x1 <= 31.0 && y0 >= 0.0 && !(x1 > 19.5 && x0 < 23.5 && y1 > 17.5 && y0 < 21.5);
                let a = tex.get_pixel(i, j).0[3];
                if outside || in_void {
                    assert_eq!(a, 0, "texel ({i},{j})");
                } else if inside {
                    assert_eq!(a, 255, "texel ({i},{j})");
                }
            }
        }
        // a texel straddling the void's west edge by a quarter: [19.25, 19.75] -> known 0.5
        let ext = WorldRect {
            min_x: 19.25,
            max_x: 19.75,
            min_y: 18.0,
            max_y: 18.5,
        };
        assert_eq!(
            ortho_texture(&ortho, &dem, ext, 1).get_pixel(0, 0).0[3],
            128
        );
    }

    #[test]
    fn degenerate_inputs_do_not_panic() {
        let g = GridGeoref::new(0.0, 10.0, 1.0);
        let dem = flat_dem(11, 11, g);
        let ortho = ortho_from(11, 11, g, |_, _| [5, 5, 5, 255]);
        let ext = WorldRect {
            min_x: 3.0,
            max_x: 3.0,
            min_y: 0.0,
            max_y: 5.0,
        };
        assert!(
            ortho_texture(&ortho, &dem, ext, 8)
                .pixels()
                .all(|p| p.0 == [0; 4])
        );
        assert_eq!(ortho_texture(&ortho, &dem, ext, 0).dimensions(), (0, 0));
        let far = WorldRect {
            min_x: 1e6,
            max_x: 1e6 + 10.0,
            min_y: 0.0,
            max_y: 10.0,
        };
        assert!(
            ortho_texture(&ortho, &dem, far, 8)
                .pixels()
                .all(|p| p.0 == [0; 4])
        );
    }

    #[test]
    fn output_does_not_depend_on_thread_count() {
        let g = GridGeoref::new(0.0, 99.0, 1.0);
        let z: Vec<f32> = (0..100 * 100)
            .map(|k| ((k % 100) as f32 * 0.37).sin() * 20.0 + (k / 100) as f32)
            .collect();
        let mut dem = Dem::from_heights(100, 100, z, g).unwrap();
        dem.void[4321] = true;
        let ortho = ortho_from(140, 140, GridGeoref::new(-10.0, 110.0, 0.8), |c, r| {
            [
                (c * 7 % 256) as u8,
                (r * 13 % 256) as u8,
                ((c + r) % 256) as u8,
                if (c + r) % 17 == 0 { 0 } else { 255 },
            ]
        });
        let ext = WorldRect {
            min_x: 20.0,
            max_x: 148.0,
            min_y: -20.0,
            max_y: 108.0,
        };
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap();
        for t in [37, 256] {
            let (a, b) = pool.install(|| {
                (
                    ortho_texture(&ortho, &dem, ext, t),
                    crate::cells::normal_map(&dem, ext, t),
                )
            });
            assert_eq!(a, ortho_texture(&ortho, &dem, ext, t));
            assert_eq!(b, crate::cells::normal_map(&dem, ext, t));
        }
    }
}
