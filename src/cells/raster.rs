//! Scan conversion of lattice samples inside triangles with integer vertices.
//!
//! Exact integer scanline: a sample is inside a triangle when it is on the inner side of,
//! or exactly on, each of its edges. Per lattice row the inside columns form one span,
//! bounded by the triangle's left and right edges, whose columns are stepped row by row
//! as integer quotient and remainder (a few divisions per triangle, none per row); no
//! allocation per triangle.

/// A set of sample positions `(col, row)`: columns `origin_c + k * stride` within
/// `[c_lo, c_hi]` and rows `origin_r + k * stride` within `[r_lo, r_hi]` (inclusive, any
/// k >= 0). Invariant: `c_lo >= origin_c` and `r_lo >= origin_r`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Lattice {
    pub origin_c: i64,
    pub origin_r: i64,
    pub stride: i64,
    pub c_lo: i64,
    pub c_hi: i64,
    pub r_lo: i64,
    pub r_hi: i64,
}

/// Smallest `origin + k * s >= v` (s > 0).
#[inline]
fn snap_up(v: i64, origin: i64, s: i64) -> i64 {
    origin + ceil_div(v - origin, s) * s
}

/// `ceil(n / d)` for `d > 0`.
#[inline]
fn ceil_div(n: i64, d: i64) -> i64 {
    -floor_div(-n, d)
}

/// `floor(n / d)` for `d > 0`; a shift for powers of two.
#[inline]
fn floor_div(n: i64, d: i64) -> i64 {
    if d & (d - 1) == 0 {
        n >> d.trailing_zeros()
    } else {
        n.div_euclid(d)
    }
}

/// An edge's column on successive rows, exactly: `floor` and `ceil` of
/// `p.col + (row - p.row) * (q.col - p.col) / (q.row - p.row)`, kept as an integer quotient
/// and remainder and stepped `stride` rows at a time without division.
#[derive(Clone, Copy)]
struct EdgeWalk {
    x0: i64,
    q: i64,
    r: i64,
    dy: i64,
    qs: i64,
    rs: i64,
}

impl EdgeWalk {
    /// The edge from `p` to `q` (`p[1] < q[1]`) at row `y`, stepping `s` rows.
    #[inline]
    fn new(p: [i64; 2], q: [i64; 2], y: i64, s: i64) -> EdgeWalk {
        let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
        let num = (y - p[1]) * dx;
        let qq = num.div_euclid(dy);
        let step = dx * s;
        let qs = step.div_euclid(dy);
        EdgeWalk {
            x0: p[0],
            q: qq,
            r: num - qq * dy,
            dy,
            qs,
            rs: step - qs * dy,
        }
    }

    #[inline]
    fn floor(&self) -> i64 {
        self.x0 + self.q
    }

    #[inline]
    fn ceil(&self) -> i64 {
        self.x0 + self.q + (self.r != 0) as i64
    }

    #[inline]
    fn step(&mut self) {
        self.q += self.qs;
        self.r += self.rs;
        if self.r >= self.dy {
            self.r -= self.dy;
            self.q += 1;
        }
    }
}

/// Calls `f(row, j, i0, i1)` for every lattice row that has lattice samples inside the
/// closed triangle `tri` (`[col, row]` vertices, any orientation): `j` is the row's lattice
/// index (`row = origin_r + j * stride`) and the inside samples are the lattice columns
/// `i0..=i1` (`col = origin_c + i * stride`). Rows are visited in increasing order.
/// Degenerate triangles visit nothing. Exact integer scanline: per row, the columns
/// between the ceiling of the left edge and the floor of the right edge.
#[inline(always)]
pub(crate) fn for_each_span(
    tri: [[i64; 2]; 3],
    lat: &Lattice,
    mut f: impl FnMut(i64, usize, usize, usize),
) {
    for (y, j, i0, i1) in Spans::new(tri, lat) {
        f(y, j, i0, i1);
    }
}

/// [`for_each_span`]'s rows as an iterator of `(row, j, i0, i1)` (for code that must not
/// go through a closure).
pub(crate) struct Spans {
    p1: [i64; 2],
    p2: [i64; 2],
    long_left: bool,
    y: i64,
    ymax: i64,
    j: usize,
    top_end: i64,
    on_top: bool,
    long: EdgeWalk,
    short: EdgeWalk,
    lat: Lattice,
}

impl Spans {
    /// The spans of the closed triangle `tri` on `lat` (none for a degenerate triangle).
    #[inline(always)]
    pub(crate) fn new(tri: [[i64; 2]; 3], lat: &Lattice) -> Spans {
        // sort by row: p0 top, p2 bottom; the long edge p0-p2 spans every row
        let [mut p0, mut p1, mut p2] = tri;
        if p1[1] < p0[1] {
            std::mem::swap(&mut p0, &mut p1);
        }
        if p2[1] < p1[1] {
            std::mem::swap(&mut p1, &mut p2);
        }
        if p1[1] < p0[1] {
            std::mem::swap(&mut p0, &mut p1);
        }
        let c = (p2[0] - p0[0]) * (p1[1] - p0[1]) - (p2[1] - p0[1]) * (p1[0] - p0[0]);
        let s = lat.stride;
        let ymax = p2[1].min(lat.r_hi);
        let y = snap_up(p0[1].max(lat.r_lo), lat.origin_r, s);
        let idle = EdgeWalk {
            x0: 0,
            q: 0,
            r: 0,
            dy: 1,
            qs: 0,
            rs: 0,
        };
        let mut out = Spans {
            p1,
            p2,
            // c < 0: p1 lies right of the long edge, so the long edge bounds the rows on
            // the left
            long_left: c < 0,
            y,
            ymax: y - 1,
            j: 0,
            top_end: 0,
            on_top: false,
            long: idle,
            short: idle,
            lat: *lat,
        };
        if c == 0 || y > ymax {
            return out;
        }
        out.ymax = ymax;
        out.j = ((y - lat.origin_r) / s) as usize;
        // rows before `top_end` are bounded by p0-p1, the others by p1-p2
        out.top_end = if p1[1] == p2[1] { p2[1] + 1 } else { p1[1] };
        out.on_top = y < out.top_end;
        out.long = EdgeWalk::new(p0, p2, y, s);
        out.short = if out.on_top {
            EdgeWalk::new(p0, p1, y, s)
        } else {
            EdgeWalk::new(p1, p2, y, s)
        };
        out
    }
}

impl Iterator for Spans {
    type Item = (i64, usize, usize, usize);

    #[inline(always)]
    fn next(&mut self) -> Option<Self::Item> {
        let (lat, s) = (&self.lat, self.lat.stride);
        let oc = lat.origin_c;
        while self.y <= self.ymax {
            let y = self.y;
            if self.on_top && y >= self.top_end {
                self.short = EdgeWalk::new(self.p1, self.p2, y, s);
                self.on_top = false;
            }
            let (lo, hi) = if self.long_left {
                (self.long.ceil(), self.short.floor())
            } else {
                (self.short.ceil(), self.long.floor())
            };
            let (lo, hi) = (lo.max(lat.c_lo), hi.min(lat.c_hi));
            let j = self.j;
            self.long.step();
            self.short.step();
            self.y += s;
            self.j += 1;
            if lo <= hi {
                let (i0, i1) = if s == 1 {
                    (lo - oc, hi - oc)
                } else {
                    (ceil_div(lo - oc, s), floor_div(hi - oc, s))
                };
                if i0 <= i1 {
                    return Some((y, j, i0 as usize, i1 as usize));
                }
            }
        }
        None
    }
}

/// Plane through three grid points with heights: `z(col,row) = h0 + a*(col-c0) + b*(row-r0)`.
#[derive(Clone, Copy)]
pub(super) struct Plane {
    c0: f64,
    r0: f64,
    h0: f64,
    a: f64,
    b: f64,
}

impl Plane {
    pub(super) fn new(p: [[i64; 2]; 3], h: [f64; 3]) -> Plane {
        let (dx1, dy1) = ((p[1][0] - p[0][0]) as f64, (p[1][1] - p[0][1]) as f64);
        let (dx2, dy2) = ((p[2][0] - p[0][0]) as f64, (p[2][1] - p[0][1]) as f64);
        let (dh1, dh2) = (h[1] - h[0], h[2] - h[0]);
        let det = dx1 * dy2 - dx2 * dy1;
        let (a, b) = if det != 0.0 {
            ((dh1 * dy2 - dh2 * dy1) / det, (dx1 * dh2 - dx2 * dh1) / det)
        } else {
            (0.0, 0.0)
        };
        Plane {
            c0: p[0][0] as f64,
            r0: p[0][1] as f64,
            h0: h[0],
            a,
            b,
        }
    }

    /// `(base, a)` such that z(col, row) = base + a * col on this row.
    #[inline]
    pub(super) fn row(&self, row: i64) -> (f64, f64) {
        (
            self.h0 + self.b * (row as f64 - self.r0) - self.a * self.c0,
            self.a,
        )
    }

    /// The plane along `row` by lattice column index: `(base, step)` with
    /// z(oc + i·s, row) = base + step · i.
    #[inline(always)]
    pub(super) fn lattice_row(&self, row: i64, oc: i64, s: i64) -> (f64, f64) {
        let (base, a) = self.row(row);
        (base + a * oc as f64, a * s as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute(tri: [[i64; 2]; 3], lat: &Lattice) -> Vec<(i64, i64)> {
        let mut out = Vec::new();
        let cross = |p: [i64; 2], q: [i64; 2], r: [i64; 2]| {
            (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
        };
        let o = cross(tri[0], tri[1], tri[2]);
        if o == 0 {
            return out;
        }
        for y in lat.r_lo..=lat.r_hi {
            if (y - lat.origin_r).rem_euclid(lat.stride) != 0 {
                continue;
            }
            for x in lat.c_lo..=lat.c_hi {
                if (x - lat.origin_c).rem_euclid(lat.stride) != 0 {
                    continue;
                }
                let p = [x, y];
                let e = [
                    cross(tri[0], tri[1], p),
                    cross(tri[1], tri[2], p),
                    cross(tri[2], tri[0], p),
                ];
                if e.iter().all(|&v| v * o.signum() >= 0) {
                    out.push((y, x));
                }
            }
        }
        out
    }

    #[test]
    fn spans_match_brute_force() {
        let mut seed = 12345u64;
        let mut rnd = |m: i64| {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 33) % m as u64) as i64
        };
        for case in 0..4000 {
            // small triangles with many ties and flat edges, then larger ones
            let m = if case < 3000 { 30 } else { 160 };
            let tri = [[rnd(m), rnd(m)], [rnd(m), rnd(m)], [rnd(m), rnd(m)]];
            let stride = 1 + rnd(4);
            let (origin_c, origin_r) = (rnd(5), rnd(5));
            let lat = Lattice {
                origin_c,
                origin_r,
                stride,
                c_lo: origin_c + rnd(4),
                c_hi: m * 2 / 3 + rnd(m / 3),
                r_lo: origin_r + rnd(4),
                r_hi: m * 2 / 3 + rnd(m / 3),
            };
            let mut got = Vec::new();
            for_each_span(tri, &lat, |y, j, i0, i1| {
                assert_eq!(y, lat.origin_r + j as i64 * stride);
                for i in i0..=i1 {
                    got.push((y, lat.origin_c + i as i64 * stride));
                }
            });
            assert_eq!(got, brute(tri, &lat), "{tri:?} {lat:?}");
        }
    }
}
