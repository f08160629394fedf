//! Subtexel estimate of the area of (footprint ∩ source pixel): N x N stratified samples
//! at the cell centres of a grid over a box that contains the intersection.

use super::footprint::{Param, inside};

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

#[cfg(test)]
mod tests {
    use super::super::footprint::Footprint;
    use super::*;

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
