//! Exact area of (footprint ∩ source pixel) by Sutherland-Hodgman clipping of the
//! footprint parallelogram against the pixel square: the accuracy reference.

use super::footprint::Footprint;

/// Vertex capacity of a clipped polygon: a convex 8-gon gains at most one vertex per
/// half-plane (12); the margin covers the non-convex quads of photo footprints.
const CAP: usize = 16;

/// A small polygon on the stack.
#[derive(Clone, Copy)]
struct Poly {
    v: [[f64; 2]; CAP],
    n: usize,
}

/// Clips `p` to the half-plane `s * (q[axis] - c) <= 0` (s = +1 keeps `q[axis] <= c`).
fn clip(p: &Poly, axis: usize, c: f64, s: f64) -> Poly {
    let mut out = Poly {
        v: [[0.0; 2]; CAP],
        n: 0,
    };
    if p.n == 0 {
        return out;
    }
    let mut push = |q: [f64; 2]| {
        if out.n < CAP {
            out.v[out.n] = q;
            out.n += 1;
        }
    };
    for k in 0..p.n {
        let (a, b) = (p.v[k], p.v[(k + 1) % p.n]);
        let (da, db) = (s * (a[axis] - c), s * (b[axis] - c));
        let (ina, inb) = (da <= 0.0, db <= 0.0);
        if ina {
            push(a);
        }
        if ina != inb {
            let f = da / (da - db);
            let mut q = [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])];
            q[axis] = c;
            push(q);
        }
    }
    out
}

/// Exact area (source pixels²) of `fp` ∩ the pixel square centred on `(col, row)`.
pub(crate) fn area(fp: &Footprint, col: f64, row: f64) -> f64 {
    polygon_box_area(&fp.corners(), [col - 0.5, row - 0.5, col + 0.5, row + 0.5])
}

/// Exact area of the simple polygon `poly` (either orientation, convex or not, at most 8
/// vertices; extra vertices are ignored) inside the axis-aligned box
/// `[x0, y0, x1, y1]`, by Sutherland-Hodgman clipping against the box's four sides (correct
/// for non-convex subject polygons since the clip region is convex; the spurious edges it
/// adds along the box enclose no area). 0 for degenerate input; never NaN for finite input.
pub(crate) fn polygon_box_area(poly: &[[f64; 2]], bx: [f64; 4]) -> f64 {
    let mut p = Poly {
        v: [[0.0; 2]; CAP],
        n: poly.len().min(8),
    };
    p.v[..p.n].copy_from_slice(&poly[..p.n]);
    p = clip(&p, 0, bx[0], -1.0);
    p = clip(&p, 0, bx[2], 1.0);
    p = clip(&p, 1, bx[1], -1.0);
    p = clip(&p, 1, bx[3], 1.0);
    let mut a2 = 0.0;
    for k in 0..p.n {
        let (a, b) = (p.v[k], p.v[(k + 1) % p.n]);
        a2 += a[0] * b[1] - a[1] * b[0];
    }
    0.5 * a2.abs()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn diamond_over_pixel() {
        // diamond |x|+|y| <= 1 (area 2) contains the whole pixel square |x|,|y| <= 0.5
        let f = Footprint {
            p0: [0.0, -1.0],
            a: [1.0, 1.0],
            b: [-1.0, 1.0],
        };
        assert!((area(&f, 0.0, 0.0) - 1.0).abs() < 1e-12);
        // pixel (1, 0): region 0.5<=x<=1, |y| <= 1 - x: triangle of area 0.25
        assert!((area(&f, 1.0, 0.0) - 0.25).abs() < 1e-12);
        // the pixel areas sum to the footprint area
        let mut s = 0.0;
        for r in -2..=2 {
            for c in -2..=2 {
                s += area(&f, c as f64, r as f64);
            }
        }
        assert!((s - 2.0).abs() < 1e-12, "{s}");
        let flat = Footprint {
            p0: [0.0, 0.0],
            a: [1.0, 1.0],
            b: [2.0, 2.0],
        };
        assert_eq!(area(&flat, 0.0, 0.0), 0.0);
    }
}
