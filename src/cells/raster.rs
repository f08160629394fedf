//! Scan conversion of lattice samples inside triangles with integer vertices.
//!
//! Exact integer edge functions: a sample is inside a triangle when it is on the inner
//! side of, or exactly on, each of its three edges. Per lattice row the inside columns
//! form one span, found with three integer divisions; no allocation per triangle.

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

/// Calls `f(row, j, i0, i1)` for every lattice row that has lattice samples inside the
/// closed triangle `tri` (`[col, row]` vertices, any orientation): `j` is the row's lattice
/// index (`row = origin_r + j * stride`) and the inside samples are the lattice columns
/// `i0..=i1` (`col = origin_c + i * stride`). Rows are visited in increasing order.
/// Degenerate triangles visit nothing.
#[inline]
pub(crate) fn for_each_span(
    tri: [[i64; 2]; 3],
    lat: &Lattice,
    mut f: impl FnMut(i64, usize, usize, usize),
) {
    let [a, mut b, mut c] = tri;
    let orient = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
    if orient == 0 {
        return;
    }
    if orient < 0 {
        std::mem::swap(&mut b, &mut c);
    }
    // Edge p->q: E(x, y) = (qx-px)(y-py) - (qy-py)(x-px) >= 0 inside.
    // For a fixed row: E = ax * x + k(y) with ax = -(qy-py), k(y) = (qx-px)(y-py) + (qy-py) px.
    let edges = [(a, b), (b, c), (c, a)];
    let s = lat.stride;
    let ymin = a[1].min(b[1]).min(c[1]).max(lat.r_lo);
    let ymax = a[1].max(b[1]).max(c[1]).min(lat.r_hi);
    let mut y = snap_up(ymin, lat.origin_r, s);
    let mut j = ((y - lat.origin_r) / s) as usize;
    let mut ax = [0i64; 3];
    let mut k = [0i64; 3];
    let mut dk = [0i64; 3];
    for (i, (p, q)) in edges.iter().enumerate() {
        ax[i] = -(q[1] - p[1]);
        k[i] = (q[0] - p[0]) * (y - p[1]) + (q[1] - p[1]) * p[0];
        dk[i] = (q[0] - p[0]) * s;
    }
    let inv = ax.map(|a| if a != 0 { 1.0 / a.abs() as f64 } else { 0.0 });
    while y <= ymax {
        let mut lo = lat.c_lo;
        let mut hi = lat.c_hi;
        let mut empty = false;
        for i in 0..3 {
            let (axi, ki) = (ax[i], k[i]);
            // Bound of ax * x + k >= 0, estimated in f64 then made exact in integers.
            if axi > 0 {
                let mut x = ((-ki) as f64 * inv[i]) as i64; // truncation, fixed below
                while axi * x + ki < 0 {
                    x += 1;
                }
                while axi * (x - 1) + ki >= 0 {
                    x -= 1;
                }
                lo = lo.max(x);
            } else if axi < 0 {
                let mut x = (ki as f64 * inv[i]) as i64; // truncation, fixed below
                while axi * x + ki < 0 {
                    x -= 1;
                }
                while axi * (x + 1) + ki >= 0 {
                    x += 1;
                }
                hi = hi.min(x);
            } else if ki < 0 {
                empty = true;
            }
        }
        if !empty && lo <= hi {
            let (i0, i1) = if s == 1 {
                (lo - lat.origin_c, hi - lat.origin_c)
            } else {
                (
                    ceil_div(lo - lat.origin_c, s),
                    floor_div(hi - lat.origin_c, s),
                )
            };
            if i0 <= i1 {
                f(y, j, i0 as usize, i1 as usize);
            }
        }
        for i in 0..3 {
            k[i] += dk[i];
        }
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
        for _ in 0..3000 {
            let tri = [[rnd(30), rnd(30)], [rnd(30), rnd(30)], [rnd(30), rnd(30)]];
            let stride = 1 + rnd(4);
            let (origin_c, origin_r) = (rnd(5), rnd(5));
            let lat = Lattice {
                origin_c,
                origin_r,
                stride,
                c_lo: origin_c + rnd(4),
                c_hi: 20 + rnd(10),
                r_lo: origin_r + rnd(4),
                r_hi: 20 + rnd(10),
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
