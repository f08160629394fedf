//! Subtexel estimate of the area of (footprint ∩ source pixel): N x N stratified samples
//! at the cell centres of a grid over a box that contains the intersection.
//!
//! [`texel_colour`] is the per-texel kernel of `Mode::Subtexel`. It works with the
//! triangle's precomputed [`Shape`] (no division per texel), in coordinates relative to the
//! footprint origin, and counts the samples inside the footprint per sample row in O(1)
//! from the footprint's chord at that row, so a pixel costs O(N), not O(N²). The sample set
//! and the inside test are those of [`area`], the sample-by-sample form kept as the
//! reference (the two agree up to samples lying within rounding of the footprint's edge).

use super::SrcView;
use super::footprint::{Affine2, Param, Shape, inside};
use super::texel::{AreaSum, Scratch, TexelColour, bilinear_at};
use crate::fastmath::{ceil_f, floor_f, floor_i};

/// Largest accepted subtexel count per axis.
pub const MAX_SUBTEXELS: u32 = 64;

/// Estimated area of the footprint (given by its parametric map `par`) inside the box
/// `[x0, x1] x [y0, y1]` (which must contain footprint ∩ pixel and lie in the pixel), with
/// `n x n` samples: (samples inside / n²) x box area.
#[inline]
pub(crate) fn area(par: &Param, n: u32, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let (w, h) = (x1 - x0, y1 - y0);
    let inv_n = 1.0 / n as f64;
    let (dx, dy) = (w * inv_n, h * inv_n);
    // alpha/beta change per sample step
    let (da_x, db_x) = (par.inv[0][0] * dx, par.inv[1][0] * dx);
    let mut count = 0u32;
    for ky in 0..n {
        let y = y0 + (ky as f64 + 0.5) * dy;
        let mut ab = par.at(x0 + 0.5 * dx, y);
        for _ in 0..n {
            count += inside(ab) as u32;
            ab[0] += da_x;
            ab[1] += db_x;
        }
    }
    count as f64 * inv_n * inv_n * w * h
}

/// Estimated area of the footprint `sh` inside the box `[x0, x1] x [y0, y1]` (relative to
/// the footprint origin; the box must contain footprint ∩ pixel and lie in the pixel) with
/// the `n x n` samples of [`area`], counted row by row: in sample row y the samples inside
/// are those within the footprint's chord at y.
#[inline]
pub(crate) fn area_by_rows(sh: &Shape, n: u32, x0: f64, x1: f64, y0: f64, y1: f64) -> f64 {
    let (w, h) = (x1 - x0, y1 - y0);
    let nf = n as f64;
    let inv_n = 1.0 / nf;
    let dy = h * inv_n;
    // Sample (kx, ky) is at (x0 + (kx + 0.5) w / n, y0 + (ky + 0.5) dy). In row ky the
    // samples inside are those with lo(y) <= x <= hi(y) (the chord), i.e. kx in
    // [max_s u_lo_s(ky), min_s u_hi_s(ky)] with u = (bound - x0) n / w - 0.5, each bound
    // linear in ky: u(ky) = u0 + u1 ky.
    let per_x = nf / w;
    let yc = y0 + 0.5 * dy;
    let [sa, sb] = &sh.x_of_y;
    let lin =
        |bound: f64, slope: f64| ((bound + slope * yc - x0) * per_x - 0.5, slope * dy * per_x);
    let (la, lb, ha, hb) = (
        lin(sa.lo, sa.slope),
        lin(sb.lo, sb.slope),
        lin(sa.hi, sa.slope),
        lin(sb.hi, sb.slope),
    );
    let top = nf - 1.0;
    let mut count = 0.0;
    for k in 0..n {
        let kf = k as f64;
        let lo = max_f(la.0 + la.1 * kf, lb.0 + lb.1 * kf);
        let hi = min_f(ha.0 + ha.1 * kf, hb.0 + hb.1 * kf);
        let first = max_f(ceil_f(max_f(lo, -1.0)), 0.0);
        let last = min_f(floor_f(min_f(hi, nf)), top);
        count += max_f(last - first + 1.0, 0.0);
    }
    count * inv_n * inv_n * w * h
}

/// `max` without NaN handling (returns `b` when `a` is NaN).
#[inline(always)]
fn max_f(a: f64, b: f64) -> f64 {
    if a > b { a } else { b }
}

/// `min` without NaN handling (returns `b` when `a` is NaN).
#[inline(always)]
fn min_f(a: f64, b: f64) -> f64 {
    if a < b { a } else { b }
}

/// Colour of texel `(i, j)` of a triangle with map `map` by the subtexel estimate with
/// `n x n` samples per overlapped source pixel; `shape` is `Shape::new(map)` (`None`:
/// collapsed footprints, bilinear fallback). Same result as the generic kernel in
/// `Mode::Subtexel(n)`, except that a footprint lying inside a single source pixel takes
/// that pixel's colour directly (its overlap is the whole footprint, exactly).
pub(crate) fn texel_colour(
    src: &SrcView,
    map: &Affine2,
    shape: Option<&Shape>,
    i: u32,
    j: u32,
    n: u32,
    scratch: &mut Scratch,
) -> TexelColour {
    let Some(sh) = shape else {
        return bilinear_at(src, &map.texel_footprint(i, j), true);
    };
    let p0 = map.apply(i as f64, j as f64);
    // pixel c covers [c - 0.5, c + 0.5]
    let pix = |v: f64| floor_i(v + 0.5);
    let corners = sh.corners();
    let cs = corners.map(|q| pix(p0[0] + q[0]));
    let rs = corners.map(|q| pix(p0[1] + q[1]));
    let (c_lo, c_hi) = (
        cs.iter().copied().fold(i64::MAX, i64::min),
        cs.iter().copied().fold(i64::MIN, i64::max),
    );
    let (r_lo, r_hi) = (
        rs.iter().copied().fold(i64::MAX, i64::min),
        rs.iter().copied().fold(i64::MIN, i64::max),
    );
    let (c0, c1) = (c_lo.max(0), c_hi.min(src.w - 1));
    let (r0, r1) = (r_lo.max(0), r_hi.min(src.h - 1));
    if c0 > c1 || r0 > r1 {
        return bilinear_at(src, &map.texel_footprint(i, j), true);
    }
    if c_lo == c_hi && r_lo == r_hi {
        // inside one pixel (of the image, as c0 <= c1, r0 <= r1): area = |a x b| >= MIN
        return match src.get(c0, r0) {
            Some(px) => TexelColour {
                rgb: px.map(f64::from),
                known: true,
                fallback: false,
            },
            None => TexelColour::default(),
        };
    }
    let pix_rel = |c: i64, p: f64| c as f64 - 0.5 - p;
    sh.strip_extents(0, p0[0], &cs, c0, c1, &mut scratch.col_ranges);
    sh.strip_extents(1, p0[1], &rs, r0, r1, &mut scratch.row_ranges);
    let mut sum = AreaSum::default();
    for r in r0..=r1 {
        let ylo = pix_rel(r, p0[1]);
        let yhi = ylo + 1.0;
        let (xa, xb) = scratch.row_ranges[(r - r0) as usize];
        if !(xa <= xb) {
            continue;
        }
        let (ca, cb) = (pix(xa + p0[0]).max(c0), pix(xb + p0[0]).min(c1));
        for c in ca..=cb {
            let xlo = pix_rel(c, p0[0]);
            let xhi = xlo + 1.0;
            let (ya, yb) = scratch.col_ranges[(c - c0) as usize];
            let (x0, x1) = (xlo.max(xa), xhi.min(xb));
            let (y0, y1) = (ylo.max(ya), yhi.min(yb));
            if !(x1 > x0 && y1 > y0) {
                continue;
            }
            // a pixel inside the (convex) footprint has the pixel as its box
            let full = x0 == xlo
                && x1 == xhi
                && y0 == ylo
                && y1 == yhi
                && sh.contains(xlo, ylo)
                && sh.contains(xhi, ylo)
                && sh.contains(xlo, yhi)
                && sh.contains(xhi, yhi);
            let a = if full {
                1.0
            } else {
                area_by_rows(sh, n, x0, x1, y0, y1)
            };
            if a > 0.0 {
                sum.add(a, src.get(c, r));
            }
        }
    }
    sum.colour()
        .unwrap_or_else(|| bilinear_at(src, &map.texel_footprint(i, j), true))
}

#[cfg(test)]
mod tests {
    use super::super::footprint::Footprint;
    use super::super::{Mode, kernel};
    use super::*;

    #[test]
    fn floor_and_ceil_without_libm() {
        for x in [
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            2.9999999999999996,
            -2.9999999999999996,
            1e-300,
            -1e-300,
            63.5,
            64.0,
            -1.0000000000000002,
            1125899906842623.5,
            -1e15 - 0.25,
        ] {
            assert_eq!(floor_f(x), x.floor(), "{x}");
            assert_eq!(ceil_f(x), x.ceil(), "{x}");
            assert_eq!(floor_i(x), x.floor() as i64, "{x}");
        }
    }

    /// The row-counting kernel against the generic sample-by-sample kernel on random
    /// footprints (sizes 0.05 to 6 pixels, any orientation, partly off the image) over an
    /// image with unknown pixels.
    #[test]
    fn fast_kernel_matches_the_sample_by_sample_kernel() {
        let (w, h) = (12i64, 10i64);
        let mut s = 0x9e3779b97f4a7c15u64;
        let mut rnd = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let data: Vec<u8> = (0..w * h * 4)
            .map(|k| {
                if k % 4 == 3 {
                    if k % 28 == 3 { 0 } else { 255 }
                } else {
                    (k * 37 % 251) as u8
                }
            })
            .collect();
        let src = SrcView { data: &data, w, h };
        let (mut scratch, mut scratch2) = (Scratch::default(), Scratch::default());
        let (mut same, mut total) = (0, 0);
        for trial in 0..20000 {
            let size = 0.05 + 6.0 * rnd() * rnd();
            let ang = 6.3 * rnd();
            let skew = 0.2 + 1.6 * rnd();
            let stretch = 0.05 + 2.0 * rnd();
            let a = [size * ang.cos(), size * ang.sin()];
            let b = [
                -size * stretch * (ang + skew).sin(),
                size * stretch * (ang + skew).cos(),
            ];
            let p0 = [-2.0 + (w + 2) as f64 * rnd(), -2.0 + (h + 2) as f64 * rnd()];
            // map (s, t) -> p0 + s a + t b at texel (0, 0)
            let map = Affine2 {
                m: [[a[0], b[0], p0[0]], [a[1], b[1], p0[1]]],
            };
            let n = [1, 2, 3, 4, 8][trial % 5];
            let shape = Shape::new(&map, super::super::texel::MIN_FOOTPRINT_AREA);
            let fast = texel_colour(&src, &map, shape.as_ref(), 0, 0, n, &mut scratch);
            let slow = kernel::texel_colour(
                &src,
                &map.texel_footprint(0, 0),
                Mode::Subtexel(n),
                &mut scratch2,
            );
            total += 1;
            let close = fast.known == slow.known
                && fast.fallback == slow.fallback
                && (!fast.known
                    || fast
                        .rgb
                        .iter()
                        .zip(slow.rgb)
                        .all(|(x, y)| (x - y).abs() < 1e-6));
            if close {
                same += 1;
            } else if total - same <= 5 {
                eprintln!("trial {trial} n {n} a {a:?} b {b:?} p0 {p0:?}: {fast:?} vs {slow:?}");
            }
        }
        assert!(
            total - same <= total / 2000,
            "{} of {total} differ",
            total - same
        );
    }

    #[test]
    fn half_covered_pixel() {
        // footprint = the left half of pixel [0,1]^2 extended: x in [0, 0.5], y in [0, 1]
        let f = Footprint {
            p0: [0.0, 0.0],
            a: [0.5, 0.0],
            b: [0.0, 1.0],
        };
        let p = f.param(0.0).unwrap();
        // box already tight: full
        assert!((area(&p, 4, 0.0, 0.5, 0.0, 1.0) - 0.5).abs() < 1e-12);
        // a loose box: 8 samples per axis, 4 of each row inside
        assert!((area(&p, 8, 0.0, 1.0, 0.0, 1.0) - 0.5).abs() < 1e-12);
    }
}
