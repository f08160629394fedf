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
#[inline]
pub(crate) fn for_each_span(
    tri: [[i64; 2]; 3],
    lat: &Lattice,
    mut f: impl FnMut(i64, usize, usize, usize),
) {
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
    if c == 0 {
        return;
    }
    // c < 0: p1 lies right of the long edge, so the long edge bounds the rows on the left
    let long_left = c < 0;
    let s = lat.stride;
    let ymax = p2[1].min(lat.r_hi);
    let mut y = snap_up(p0[1].max(lat.r_lo), lat.origin_r, s);
    if y > ymax {
        return;
    }
    let mut j = ((y - lat.origin_r) / s) as usize;
    // rows before `top_end` are bounded by p0-p1, the others by p1-p2
    let top_end = if p1[1] == p2[1] { p2[1] + 1 } else { p1[1] };
    let mut on_top = y < top_end;
    let mut long = EdgeWalk::new(p0, p2, y, s);
    let mut short = if on_top {
        EdgeWalk::new(p0, p1, y, s)
    } else {
        EdgeWalk::new(p1, p2, y, s)
    };
    let oc = lat.origin_c;
    while y <= ymax {
        if on_top && y >= top_end {
            short = EdgeWalk::new(p1, p2, y, s);
            on_top = false;
        }
        let (lo, hi) = if long_left {
            (long.ceil(), short.floor())
        } else {
            (short.ceil(), long.floor())
        };
        let (lo, hi) = (lo.max(lat.c_lo), hi.min(lat.c_hi));
        if lo <= hi {
            let (i0, i1) = if s == 1 {
                (lo - oc, hi - oc)
            } else {
                (ceil_div(lo - oc, s), floor_div(hi - oc, s))
            };
            if i0 <= i1 {
                f(y, j, i0 as usize, i1 as usize);
            }
        }
        long.step();
        short.step();
        y += s;
        j += 1;
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
