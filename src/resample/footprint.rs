//! Texel footprints: the affine map from texture space to source pixel space of one chart
//! triangle, and the parallelogram a texel's four corners map to under it.

use super::{ChartMesh, PixelMap};

/// An affine map `(s, t) -> (col, row)`: `col = m[0][0]*s + m[0][1]*t + m[0][2]`, same for row.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Affine2 {
    pub m: [[f64; 3]; 2],
}

impl Affine2 {
    /// Image of the point `(s, t)`.
    #[inline]
    pub fn apply(&self, s: f64, t: f64) -> [f64; 2] {
        let m = &self.m;
        [
            m[0][0] * s + m[0][1] * t + m[0][2],
            m[1][0] * s + m[1][1] * t + m[1][2],
        ]
    }

    /// The footprint of texel `(i, j)` (texture column i, row j), i.e. the image of the
    /// square `[i, i+1] x [j, j+1]` in texel units.
    #[inline]
    pub fn texel_footprint(&self, i: u32, j: u32) -> Footprint {
        let m = &self.m;
        Footprint {
            p0: self.apply(i as f64, j as f64),
            a: [m[0][0], m[1][0]],
            b: [m[0][1], m[1][1]],
        }
    }
}

/// The affine map from texture space in texel units (`s = u * texels`, `t = v * texels`)
/// to source pixel coordinates for triangle `tri` of `chart`, or `None` when the
/// triangle has (numerically) zero area in texture space or a non-finite map.
pub(crate) fn triangle_map(
    chart: &ChartMesh,
    tri: [u32; 3],
    texels: u32,
    to_pixel: &PixelMap,
) -> Option<Affine2> {
    let t = texels as f64;
    let st = |k: u32| {
        let uv = chart.uvs[k as usize];
        [uv[0] * t, uv[1] * t]
    };
    let px = |k: u32| {
        let p = chart.positions[k as usize];
        to_pixel.apply(p[0], p[1])
    };
    let (q0, q1, q2) = (st(tri[0]), st(tri[1]), st(tri[2]));
    let (e1, e2) = (
        [q1[0] - q0[0], q1[1] - q0[1]],
        [q2[0] - q0[0], q2[1] - q0[1]],
    );
    let det = e1[0] * e2[1] - e1[1] * e2[0];
    // Below 1e-9 texel² the triangle covers no texel centre anyway (the rasterizer works on
    // a 1/256 texel grid); its map would only amplify rounding noise.
    // negated so that a NaN determinant is rejected too
    #[allow(clippy::neg_cmp_op_on_partial_ord)]
    if !(det.abs() > 1e-9) {
        return None;
    }
    // inverse of [e1 e2]
    let id = 1.0 / det;
    let inv = [[e2[1] * id, -e2[0] * id], [-e1[1] * id, e1[0] * id]];
    let (p0, p1, p2) = (px(tri[0]), px(tri[1]), px(tri[2]));
    let (d1, d2) = (
        [p1[0] - p0[0], p1[1] - p0[1]],
        [p2[0] - p0[0], p2[1] - p0[1]],
    );
    // J = [d1 d2] * inv
    let mut m = [[0.0; 3]; 2];
    for r in 0..2 {
        let (a, b) = (d1[r], d2[r]);
        m[r][0] = a * inv[0][0] + b * inv[1][0];
        m[r][1] = a * inv[0][1] + b * inv[1][1];
        m[r][2] = p0[r] - m[r][0] * q0[0] - m[r][1] * q0[1];
    }
    m.iter()
        .flatten()
        .all(|v| v.is_finite())
        .then_some(Affine2 { m })
}

/// A parallelogram in source pixel space: corners `p0`, `p0 + a`, `p0 + a + b`, `p0 + b`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Footprint {
    pub p0: [f64; 2],
    pub a: [f64; 2],
    pub b: [f64; 2],
}

impl Footprint {
    /// The four corners in order around the parallelogram.
    #[inline]
    pub fn corners(&self) -> [[f64; 2]; 4] {
        let (p, a, b) = (self.p0, self.a, self.b);
        [
            p,
            [p[0] + a[0], p[1] + a[1]],
            [p[0] + a[0] + b[0], p[1] + a[1] + b[1]],
            [p[0] + b[0], p[1] + b[1]],
        ]
    }

    /// Area in source pixels² (0 for a collapsed footprint).
    #[cfg(test)]
    pub fn area(&self) -> f64 {
        (self.a[0] * self.b[1] - self.a[1] * self.b[0]).abs()
    }

    /// The centre (image of the texel centre).
    #[inline]
    pub fn centre(&self) -> [f64; 2] {
        [
            self.p0[0] + 0.5 * (self.a[0] + self.b[0]),
            self.p0[1] + 0.5 * (self.a[1] + self.b[1]),
        ]
    }

    /// Bounding box `[min_col, min_row, max_col, max_row]` of the corners `c`.
    pub fn bbox(c: &[[f64; 2]; 4]) -> [f64; 4] {
        let mut bb = [c[0][0], c[0][1], c[0][0], c[0][1]];
        for p in &c[1..] {
            bb[0] = bb[0].min(p[0]);
            bb[1] = bb[1].min(p[1]);
            bb[2] = bb[2].max(p[0]);
            bb[3] = bb[3].max(p[1]);
        }
        bb
    }

    /// Extent along axis `1 - axis` of the footprint within the strip `lo <= p[axis] <= hi`
    /// (axis 1 = a horizontal strip of rows, giving a column range), or `None` if they do
    /// not meet.
    #[cfg(test)]
    pub fn range_in_strip(&self, axis: usize, lo: f64, hi: f64) -> Option<(f64, f64)> {
        range_in_strip(&self.corners(), axis, lo, hi)
    }

    /// Parametric coordinates: a map taking a point to `(alpha, beta)` with the footprint
    /// being `[0,1]²`. `None` for a collapsed footprint (area below `min_area`).
    pub fn param(&self, min_area: f64) -> Option<Param> {
        let det = self.a[0] * self.b[1] - self.a[1] * self.b[0];
        #[allow(clippy::neg_cmp_op_on_partial_ord)] // rejects NaN too
        if !(det.abs() >= min_area) || det == 0.0 {
            return None;
        }
        let inv = [
            [self.b[1] / det, -self.b[0] / det],
            [-self.a[1] / det, self.a[0] / det],
        ];
        Some(Param { p0: self.p0, inv })
    }
}

/// One of the two constraints `-eps <= g <= 1 + eps` of a footprint (`g` = alpha or beta,
/// see [`Footprint::param`]) solved for one coordinate: relative to the footprint origin
/// `p0`, the solved coordinate lies in `[lo + slope * o, hi + slope * o]` where `o` is the
/// other coordinate (also relative to `p0`); `lo0`, `hi0` likewise for `0 <= g <= 1` (the
/// exact edges). Unbounded (`-inf`, `+inf`) when `g` does not depend on the solved
/// coordinate.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Slab {
    pub lo: f64,
    pub hi: f64,
    pub lo0: f64,
    pub hi0: f64,
    pub slope: f64,
}

impl Slab {
    fn new(g_solved: f64, g_other: f64) -> Slab {
        if g_solved == 0.0 {
            return Slab {
                lo: f64::NEG_INFINITY,
                hi: f64::INFINITY,
                lo0: f64::NEG_INFINITY,
                hi0: f64::INFINITY,
                slope: 0.0,
            };
        }
        let r = 1.0 / g_solved;
        let (e0, e1) = (-PARAM_EPS * r, (1.0 + PARAM_EPS) * r);
        Slab {
            lo: e0.min(e1),
            hi: e0.max(e1),
            lo0: r.min(0.0),
            hi0: r.max(0.0),
            slope: -g_other * r,
        }
    }
}

/// What all footprints of one triangle share: they are translates of one parallelogram
/// (`p0 + alpha a + beta b`, alpha, beta in [0, 1]), so everything but `p0` is computed once
/// per triangle and the subtexel kernel needs no division per texel. Coordinates relative
/// to `p0`, in source pixels.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Shape {
    /// Edge vectors.
    pub a: [f64; 2],
    pub b: [f64; 2],
    /// Bounding box of the corners: `[min x, min y, max x, max y]`.
    pub bb: [f64; 4],
    /// Rows: alpha = inv[0] . (p - p0), beta = inv[1] . (p - p0) (as [`Footprint::param`]).
    pub inv: [[f64; 2]; 2],
    /// x in terms of y: alpha and beta constraints.
    pub x_of_y: [Slab; 2],
    /// y in terms of x: alpha and beta constraints.
    pub y_of_x: [Slab; 2],
}

impl Shape {
    /// The shape of the footprints of `map`, or `None` when they are collapsed (area below
    /// `min_area`, the same test as [`Footprint::param`]).
    pub fn new(map: &Affine2, min_area: f64) -> Option<Shape> {
        let fp = map.texel_footprint(0, 0);
        let par = fp.param(min_area)?;
        let (a, b) = (fp.a, fp.b);
        let inv = par.inv;
        let xs = [0.0, a[0], a[0] + b[0], b[0]];
        let ys = [0.0, a[1], a[1] + b[1], b[1]];
        let bb = [
            xs.iter().copied().fold(f64::INFINITY, f64::min),
            ys.iter().copied().fold(f64::INFINITY, f64::min),
            xs.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            ys.iter().copied().fold(f64::NEG_INFINITY, f64::max),
        ];
        Some(Shape {
            a,
            b,
            bb,
            inv,
            x_of_y: [
                Slab::new(inv[0][0], inv[0][1]),
                Slab::new(inv[1][0], inv[1][1]),
            ],
            y_of_x: [
                Slab::new(inv[0][1], inv[0][0]),
                Slab::new(inv[1][1], inv[1][0]),
            ],
        })
    }

    /// Whether the point `(x, y)` (relative to `p0`) lies in the footprint ([`inside`]).
    #[inline]
    pub fn contains(&self, x: f64, y: f64) -> bool {
        let i = &self.inv;
        inside([i[0][0] * x + i[0][1] * y, i[1][0] * x + i[1][1] * y])
    }

    /// The footprint's chord at `o` along the other axis between its exact edges: for
    /// `slabs = x_of_y`, the x-interval `(lo, hi)` at height `y = o` (empty when `lo > hi`);
    /// likewise for `y_of_x`.
    #[inline]
    fn chord_exact(slabs: &[Slab; 2], o: f64) -> (f64, f64) {
        let [s, t] = slabs;
        (
            (s.lo0 + s.slope * o).max(t.lo0 + t.slope * o),
            (s.hi0 + s.slope * o).min(t.hi0 + t.slope * o),
        )
    }

    /// The four corners relative to `p0`, in order around the parallelogram.
    #[inline]
    pub fn corners(&self) -> [[f64; 2]; 4] {
        let (a, b) = (self.a, self.b);
        [[0.0, 0.0], a, [a[0] + b[0], a[1] + b[1]], b]
    }

    /// For the strips `k0 ..= k1` of axis `axis` (0: pixel columns, strip k = `k - 0.5 <= x
    /// <= k + 0.5`; 1: pixel rows, in y), the extent along the other axis of the footprint
    /// within each strip, relative to `p0`, written to `out[k - k0]` (`(inf, -inf)` where
    /// they do not meet). `origin` is `p0`'s coordinate along `axis` and `corner_strip[q]`
    /// the strip holding corner q (`floor(origin + corner + 0.5)`). One pass: each corner
    /// goes to its strip and each strip boundary inside the footprint adds the footprint's
    /// chord there to the two strips it separates, which gives the same extents as clipping
    /// the footprint to each strip.
    pub fn strip_extents(
        &self,
        axis: usize,
        origin: f64,
        corner_strip: &[i64; 4],
        k0: i64,
        k1: i64,
        out: &mut Vec<(f64, f64)>,
    ) {
        let o = 1 - axis;
        out.clear();
        out.resize((k1 - k0 + 1) as usize, (f64::INFINITY, f64::NEG_INFINITY));
        let add = |e: &mut (f64, f64), lo: f64, hi: f64| {
            e.0 = e.0.min(lo);
            e.1 = e.1.max(hi);
        };
        for (c, &k) in self.corners().iter().zip(corner_strip) {
            if k >= k0 && k <= k1 {
                let v = c[o];
                add(&mut out[(k - k0) as usize], v, v);
            }
        }
        let slabs = if axis == 1 {
            &self.x_of_y
        } else {
            &self.y_of_x
        };
        let (bmin, bmax) = (self.bb[axis], self.bb[axis + 2]);
        // boundary between strips k - 1 and k
        for k in k0..=k1 + 1 {
            let line = k as f64 - 0.5 - origin;
            if line > bmin && line < bmax {
                let (l, h) = Self::chord_exact(slabs, line);
                if l <= h {
                    if k > k0 {
                        add(&mut out[(k - 1 - k0) as usize], l, h);
                    }
                    if k <= k1 {
                        add(&mut out[(k - k0) as usize], l, h);
                    }
                }
            }
        }
    }
}

/// Extent along axis `1 - axis` of the convex polygon `c` (a footprint's corners) within
/// the strip `lo <= p[axis] <= hi` (axis 1 = a horizontal strip of rows, giving a column
/// range), or `None` if they do not meet.
#[inline]
pub(crate) fn range_in_strip(
    c: &[[f64; 2]; 4],
    axis: usize,
    lo: f64,
    hi: f64,
) -> Option<(f64, f64)> {
    let o = 1 - axis;
    let (mut mn, mut mx) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut add = |v: f64| {
        mn = mn.min(v);
        mx = mx.max(v);
    };
    for k in 0..4 {
        let (p, q) = (c[k], c[(k + 1) % 4]);
        if p[axis] >= lo && p[axis] <= hi {
            add(p[o]);
        }
        let d = q[axis] - p[axis];
        if d != 0.0 {
            for line in [lo, hi] {
                let f = (line - p[axis]) / d;
                if f > 0.0 && f < 1.0 {
                    add(p[o] + f * (q[o] - p[o]));
                }
            }
        }
    }
    (mn <= mx).then_some((mn, mx))
}

/// Parametric coordinates of a non-degenerate footprint (see [`Footprint::param`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Param {
    p0: [f64; 2],
    /// Rows: alpha = inv[0] . (p - p0), beta = inv[1] . (p - p0).
    pub inv: [[f64; 2]; 2],
}

impl Param {
    /// `(alpha, beta)` of point `(x, y)`.
    #[inline]
    pub fn at(&self, x: f64, y: f64) -> [f64; 2] {
        let (dx, dy) = (x - self.p0[0], y - self.p0[1]);
        [
            self.inv[0][0] * dx + self.inv[0][1] * dy,
            self.inv[1][0] * dx + self.inv[1][1] * dy,
        ]
    }
}

/// Tolerance on parametric coordinates for "inside" (absorbs rounding when a footprint edge
/// lies exactly on a source pixel edge, as in orthographic charts).
pub(crate) const PARAM_EPS: f64 = 1e-9;

/// Whether parametric coordinates lie in the footprint.
#[inline]
pub(crate) fn inside(ab: [f64; 2]) -> bool {
    ab[0] >= -PARAM_EPS
        && ab[0] <= 1.0 + PARAM_EPS
        && ab[1] >= -PARAM_EPS
        && ab[1] <= 1.0 + PARAM_EPS
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strip_range_of_a_diamond() {
        // diamond with corners (0,1),(1,0),(2,1),(1,2)
        let f = Footprint {
            p0: [0.0, 1.0],
            a: [1.0, -1.0],
            b: [1.0, 1.0],
        };
        assert!((f.area() - 2.0).abs() < 1e-12);
        let (lo, hi) = f.range_in_strip(1, 0.5, 1.5).unwrap();
        assert!((lo - 0.0).abs() < 1e-12 && (hi - 2.0).abs() < 1e-12);
        let (lo, hi) = f.range_in_strip(1, 0.0, 0.5).unwrap();
        assert!(
            (lo - 0.5).abs() < 1e-12 && (hi - 1.5).abs() < 1e-12,
            "{lo} {hi}"
        );
        assert!(f.range_in_strip(1, 2.5, 3.0).is_none());
        let (lo, hi) = f.range_in_strip(0, 1.5, 3.0).unwrap();
        assert!(
            (lo - 0.5).abs() < 1e-12 && (hi - 1.5).abs() < 1e-12,
            "{lo} {hi}"
        );
        let p = f.param(1e-3).unwrap();
        assert!(inside(p.at(1.0, 1.0)) && !inside(p.at(0.2, 0.2)));
        let flat = Footprint {
            p0: [0.0, 0.0],
            a: [1.0, 1.0],
            b: [2.0, 2.0],
        };
        assert!(flat.param(1e-3).is_none() && flat.area() == 0.0);
    }
}
