//! The per-texel kernel: area-weighted average of the source pixels under a footprint,
//! with the bilinear fallback for collapsed footprints.

use super::footprint::{Footprint, inside, range_in_strip};
pub use super::texel::MIN_FOOTPRINT_AREA;
pub(crate) use super::texel::{AreaSum, Scratch, TexelColour, bilinear_at};
use super::{Mode, SrcView, exact, subtexel};

/// Colour of the texel whose footprint in source pixel space is `fp`.
pub(crate) fn texel_colour(
    src: &SrcView,
    fp: &Footprint,
    mode: Mode,
    scratch: &mut Scratch,
) -> TexelColour {
    if mode == Mode::Bilinear {
        return bilinear_at(src, fp, false);
    }
    // total intersection area <= footprint area: collapsed footprints skip the area pass
    let Some(par) = fp.param(MIN_FOOTPRINT_AREA) else {
        return bilinear_at(src, fp, true);
    };
    let corners = fp.corners();
    let bb = Footprint::bbox(&corners);
    let pix = |v: f64| (v + 0.5).floor();
    let (c0, c1) = (pix(bb[0]).max(0.0), pix(bb[2]).min(src.w as f64 - 1.0));
    let (r0, r1) = (pix(bb[1]).max(0.0), pix(bb[3]).min(src.h as f64 - 1.0));
    if !(c0 <= c1 && r0 <= r1) {
        return bilinear_at(src, fp, true);
    }
    let (c0, c1, r0, r1) = (c0 as i64, c1 as i64, r0 as i64, r1 as i64);
    scratch.col_ranges.clear();
    for c in c0..=c1 {
        let cf = c as f64;
        scratch.col_ranges.push(
            range_in_strip(&corners, 0, cf - 0.5, cf + 0.5)
                .unwrap_or((f64::INFINITY, f64::NEG_INFINITY)),
        );
    }
    let mut sum = AreaSum::default();
    for r in r0..=r1 {
        let rf = r as f64;
        let Some((xa, xb)) = range_in_strip(&corners, 1, rf - 0.5, rf + 0.5) else {
            continue;
        };
        let (ca, cb) = ((pix(xa) as i64).max(c0), (pix(xb) as i64).min(c1));
        for c in ca..=cb {
            let cf = c as f64;
            let (ya, yb) = scratch.col_ranges[(c - c0) as usize];
            let (x0, x1) = ((cf - 0.5).max(xa), (cf + 0.5).min(xb));
            let (y0, y1) = ((rf - 0.5).max(ya), (rf + 0.5).min(yb));
            if !(x1 > x0 && y1 > y0) {
                continue;
            }
            // whole pixel inside the (convex) footprint?
            let base = par.at(cf - 0.5, rf - 0.5);
            let (ix, iy) = (
                [par.inv[0][0], par.inv[1][0]],
                [par.inv[0][1], par.inv[1][1]],
            );
            let full = inside(base)
                && inside([base[0] + ix[0], base[1] + ix[1]])
                && inside([base[0] + iy[0], base[1] + iy[1]])
                && inside([base[0] + ix[0] + iy[0], base[1] + ix[1] + iy[1]]);
            let a = if full {
                1.0
            } else {
                match mode {
                    Mode::Subtexel(n) => subtexel::area(&par, n, x0, x1, y0, y1),
                    _ => exact::area(fp, cf, rf),
                }
            };
            if a > 0.0 {
                sum.add(a, src.get(c, r));
            }
        }
    }
    sum.colour().unwrap_or_else(|| bilinear_at(src, fp, true))
}
