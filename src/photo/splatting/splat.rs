//! Splatting one photo pixel's footprint into a cell texture: which texels the footprint
//! quad covers and by how much.
//!
//! The footprint is the quad of the pixel's four corner positions in texel units (x right,
//! y down, texel `(i, j)` = `[i, i+1] × [j, j+1]`). It may be non-convex or, where a corner
//! was reconstructed or the surface folds, self-intersecting; a self-intersecting quad is
//! replaced by the convex hull of its corners. Each texel receives the exact area
//! (texels²) of quad ∩ texel square (tested against the resampler's exact-mode clipping,
//! generalised to any simple polygon): footprints larger than 4 × 4 texels by signed-area
//! accumulation along texel rows ([`raster_splat`], as font rasterizers do: work grows with
//! the perimeter and the box, no clipping per texel). Footprints within 4 × 4 texels
//! get their pieces from boundary integrals instead, without clipping or branches per edge,
//! and those within 2 × 2 texels (nearly all of a photo sharper than the texture) from
//! three of them: the areas left of and above the box's inner lines and of the quadrant
//! they cut off (pieces under a billionth of the footprint, rounding noise, are dropped;
//! the common cases are inlined into the caller). A *collapsed* footprint, of area
//! below [`MIN_SPLAT_AREA`] texels² (a point or a sliver, not merely a pixel much smaller than
//! a texel), deposits its area at its centre with bilinear weights
//! over the four nearest texel centres (the weights of a one-texel box around the centre,
//! as in the resampling fallback). Deposits outside the texture are dropped (they belong
//! to a neighbouring cell). Non-finite corners and footprints whose bounding box exceeds
//! [`MAX_SPLAT_BBOX`] texels² deposit nothing. Never produces NaN.

use crate::fastmath::{ceil_f, floor_f};

/// Footprints with a smaller area (texels²) count as collapsed and use the bilinear
/// fallback: a pixel a thousandth of a texel across or a sliver of (nearly) collinear corners.
/// Everything larger, however small against the texel, is deposited exactly (box-filtered
/// by the texel).
pub const MIN_SPLAT_AREA: f64 = 1e-6;

/// Footprints whose bounding box is larger than this (texels²) are skipped: a single pixel
/// smeared over thousands of texels carries no usable detail (grazing views).
pub const MAX_SPLAT_BBOX: f64 = 4096.0;

/// How a footprint was deposited.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SplatKind {
    /// Exact area-weighted deposit into every covered texel.
    Exact,
    /// Collapsed footprint: bilinear deposit at its centre.
    Bilinear,
    /// Nothing deposited (non-finite corners, or bounding box above [`MAX_SPLAT_BBOX`]).
    Skipped,
}

/// The outcome of [`splat_footprint`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Splat {
    /// Area of the footprint in texels² (of the convex hull for a self-intersecting quad);
    /// finite and >= 0, 0 when skipped.
    pub area: f64,
    /// How it was deposited.
    pub kind: SplatKind,
}

/// Where a splat puts its pieces: [`Deposit::texel`] adds weight `w` (texels², > 0) to texel
/// `t` (row-major index), [`Deposit::run`] the weights `ws` to texels `t, t + 1, …` of one
/// texel row (a weight of 0 adds nothing). Every `FnMut(usize, f64)` is one, its `run`
/// calling it for each positive weight; an accumulator can take a run in one slice.
pub(crate) trait Deposit {
    /// Adds `w` (> 0) to texel `t`.
    fn texel(&mut self, t: usize, w: f64);

    /// Adds `ws[k]` to texel `t + k` for every positive `ws[k]` (texels of one row).
    #[inline]
    fn run(&mut self, t: usize, ws: &[f64]) {
        for (k, &w) in ws.iter().enumerate() {
            if w > 0.0 {
                self.texel(t + k, w);
            }
        }
    }
}

impl<F: FnMut(usize, f64)> Deposit for F {
    #[inline(always)]
    fn texel(&mut self, t: usize, w: f64) {
        self(t, w)
    }
}

/// Twice the signed area of triangle `a, b, c`.
#[inline(always)]
fn cross(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// The polygon to clip (the quad itself if simple, else its convex hull) and its area.
#[inline(always)]
pub(crate) fn footprint_polygon(q: &[[f64; 2]; 4]) -> ([[f64; 2]; 4], f64) {
    // Simple (convex or with one reflex corner) if one diagonal separates the other two
    // corners: the shoelace area. The second diagonal is only needed if the first fails.
    let (s012, s023) = (cross(q[0], q[1], q[2]), cross(q[0], q[2], q[3]));
    if s012 * s023 >= 0.0 {
        return (*q, 0.5 * (s012 + s023).abs());
    }
    let (s123, s130) = (cross(q[1], q[2], q[3]), cross(q[1], q[3], q[0]));
    if s123 * s130 >= 0.0 {
        return (*q, 0.5 * (s012 + s023).abs());
    }
    // Self-intersecting: all four corners lie on the hull; the hull is the vertex order
    // with the largest area.
    let orders = [[0, 2, 1, 3], [0, 1, 3, 2]];
    let mut best = (*q, 0.0);
    for o in orders {
        let p = o.map(|k| q[k]);
        let a = 0.5 * (cross(p[0], p[1], p[2]) + cross(p[0], p[2], p[3])).abs();
        if a > best.1 {
            best = (p, a);
        }
    }
    best
}

/// Area in texels² of the footprint with corners `corners` (of the convex hull if the quad
/// is self-intersecting); 0 for non-finite corners. The area [`splat_footprint`] reports.
pub fn footprint_area(corners: &[[f32; 2]; 4]) -> f64 {
    let q = corners.map(|c| [c[0] as f64, c[1] as f64]);
    if !q.iter().flatten().all(|v| v.is_finite()) {
        return 0.0;
    }
    let a = footprint_polygon(&q).1;
    if a.is_finite() { a } else { 0.0 }
}

/// Deposits the footprint with corners `corners` (texel units, in order around the pixel)
/// into a `texels × texels` texture: calls `deposit(texel_index, weight)` (row-major index
/// `j * texels + i`, weight in texels², > 0) for every texel it covers, as described in the
/// module docs (`src/photo/splat.rs`). The weights sum to the footprint's area minus what falls outside
/// the texture.
pub fn splat_footprint(
    corners: &[[f32; 2]; 4],
    texels: u32,
    deposit: impl FnMut(usize, f64),
) -> Splat {
    match footprint_shape(corners) {
        Some((poly, area)) => splat_polygon(&poly, area, texels, deposit),
        None => SKIP,
    }
}

const SKIP: Splat = Splat {
    area: 0.0,
    kind: SplatKind::Skipped,
};

/// The polygon [`splat_footprint`] deposits and its area ([`footprint_polygon`] of the
/// corners in f64), or `None` for non-finite corners.
#[inline(always)]
pub(crate) fn footprint_shape(corners: &[[f32; 2]; 4]) -> Option<([[f64; 2]; 4], f64)> {
    let q = corners.map(|c| [c[0] as f64, c[1] as f64]);
    q.iter()
        .flatten()
        .all(|v| v.is_finite())
        .then(|| footprint_polygon(&q))
}

/// [`splat_footprint`] of the polygon `poly` of area `area` (from [`footprint_shape`]).
/// The common cases (footprints within 2 × 2 texels) are inlined into the caller; the rest
/// is [`splat_collapsed`] and [`splat_large`].
#[inline(always)]
pub(crate) fn splat_polygon(
    poly: &[[f64; 2]; 4],
    area: f64,
    texels: u32,
    deposit: impl FnMut(usize, f64),
) -> Splat {
    splat_polygon_limited(poly, area, texels, MAX_SPLAT_BBOX, deposit)
}

/// [`splat_polygon`] with the size guard at `max_bbox` texels² instead of [`MAX_SPLAT_BBOX`]
/// (for footprints scaled into a finer texture).
#[inline(always)]
pub(crate) fn splat_polygon_limited(
    poly: &[[f64; 2]; 4],
    area: f64,
    texels: u32,
    max_bbox: f64,
    mut deposit: impl Deposit,
) -> Splat {
    if texels == 0 {
        return SKIP;
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in poly {
        for k in 0..2 {
            // (plain comparisons: like f64::min / max, a NaN coordinate is passed over)
            if p[k] < lo[k] {
                lo[k] = p[k];
            }
            if p[k] > hi[k] {
                hi[k] = p[k];
            }
        }
    }
    if !((hi[0] - lo[0]) * (hi[1] - lo[1]) <= max_bbox) || !area.is_finite() {
        return SKIP;
    }
    if area < MIN_SPLAT_AREA {
        return splat_collapsed(poly, area, texels, deposit);
    }
    let t = texels as f64;
    let n = texels as usize;
    // Texel lines around the bounding box.
    let (ci0, ci1) = (floor_f(lo[0]), ceil_f(hi[0]));
    let (cj0, cj1) = (floor_f(lo[1]), ceil_f(hi[1]));
    let (nx, ny) = (ci1 - ci0, cj1 - cj0);
    let inside = ci0 >= 0.0 && cj0 >= 0.0 && ci1 <= t && cj1 <= t;
    if nx == 1.0 && ny == 1.0 && inside {
        // wholly inside one texel: no clipping needed
        // (in [0, t): signed conversions, one instruction each on x86-64)
        deposit.texel(cj0 as i64 as usize * n + ci0 as i64 as usize, area);
        return Splat {
            area,
            kind: SplatKind::Exact,
        };
    }
    if nx <= 2.0 && ny <= 2.0 {
        // One or two texels each way (nearly all footprints of a photo sharper than the
        // texture): half-plane and quadrant areas in the box's own frame.
        small_splat(
            poly,
            area,
            [ci0, cj0],
            nx == 2.0,
            ny == 2.0,
            texel_pieces(area, texels, inside, deposit),
        );
        return Splat {
            area,
            kind: SplatKind::Exact,
        };
    }
    splat_large(poly, area, texels, [ci0, ci1, cj0, cj1], deposit)
}

/// The `put(i, j, piece)` of the piecewise splits (texel `(i, j)` as floats) that deposits a
/// piece of a footprint of area `area` into a `texels × texels` texture: pieces below a
/// billionth of the footprint (rounding noise of the subtractions) and texels outside the
/// texture are dropped; `inside` says the footprint's box lies in the texture.
#[inline(always)]
fn texel_pieces(
    area: f64,
    texels: u32,
    inside: bool,
    mut deposit: impl Deposit,
) -> impl FnMut(f64, f64, f64) {
    let (t, n) = (texels as f64, texels as usize);
    let min_piece = 1e-9 * area;
    move |i, j, w| {
        if w > min_piece && (inside || (i >= 0.0 && j >= 0.0 && i < t && j < t)) {
            // (in [0, t): signed conversions, one instruction each on x86-64)
            deposit.texel(j as i64 as usize * n + i as i64 as usize, w);
        }
    }
}

/// [`splat_polygon`] of a collapsed footprint (area below [`MIN_SPLAT_AREA`]): its area at
/// its centre, with bilinear weights.
#[inline(never)]
fn splat_collapsed(q: &[[f64; 2]; 4], area: f64, texels: u32, mut deposit: impl Deposit) -> Splat {
    let (t, n) = (texels as f64, texels as usize);
    if area > 0.0 {
        let c = [
            0.25 * q.iter().map(|p| p[0]).sum::<f64>() - 0.5,
            0.25 * q.iter().map(|p| p[1]).sum::<f64>() - 0.5,
        ];
        let (i0, j0) = (floor_f(c[0]), floor_f(c[1]));
        let (fx, fy) = (c[0] - i0, c[1] - j0);
        for (di, dj, w) in [
            (0.0, 0.0, (1.0 - fx) * (1.0 - fy)),
            (1.0, 0.0, fx * (1.0 - fy)),
            (0.0, 1.0, (1.0 - fx) * fy),
            (1.0, 1.0, fx * fy),
        ] {
            let (i, j) = (i0 + di, j0 + dj);
            if w > 0.0 && i >= 0.0 && j >= 0.0 && i < t && j < t {
                deposit.texel(j as usize * n + i as usize, w * area);
            }
        }
    }
    Splat {
        area,
        kind: SplatKind::Bilinear,
    }
}

/// [`splat_polygon`] of a footprint whose bounding box (texel lines `[ci0, ci1] × [cj0, cj1]`)
/// spans more than two texels one way.
#[inline(never)]
fn splat_large(
    poly: &[[f64; 2]; 4],
    area: f64,
    texels: u32,
    lines: [f64; 4],
    deposit: impl Deposit,
) -> Splat {
    let [ci0, ci1, cj0, cj1] = lines;
    let t = texels as f64;
    // The texture's texels among the lines.
    let (i0, i1) = (ci0.max(0.0), ci1.min(t));
    let (j0, j1) = (cj0.max(0.0), cj1.min(t));
    if i1 <= i0 || j1 <= j0 {
        return Splat {
            area,
            kind: SplatKind::Exact,
        };
    }
    let (nx, ny) = (ci1 - ci0, cj1 - cj0);
    if nx <= GRID_MAX as f64 && ny <= GRID_MAX as f64 {
        // At most GRID_MAX × GRID_MAX texels: boundary integrals give every piece.
        grid_splat(
            poly,
            [ci0, cj0],
            nx as i64 as usize,
            ny as i64 as usize,
            texel_pieces(area, texels, false, deposit),
        );
        return Splat {
            area,
            kind: SplatKind::Exact,
        };
    }
    raster_splat(
        poly,
        [ci0, cj0],
        nx as i64 as usize,
        [j0 - cj0, j1 - cj0],
        area,
        texels,
        deposit,
    );
    Splat {
        area,
        kind: SplatKind::Exact,
    }
}

/// Scratch of [`raster_splat`]: the rows' signed areas, all zero between calls (a call
/// clears what it wrote), and per row the columns it wrote.
#[derive(Default)]
struct RasterScratch {
    cells: Vec<f64>,
    spans: Vec<[usize; 2]>,
}

thread_local! {
    /// [`raster_splat`]'s scratch (reused; a footprint of the largest allowed box needs a
    /// few megabytes once per thread).
    static RASTER: std::cell::RefCell<RasterScratch> = std::cell::RefCell::new(RasterScratch::default());
}

/// Exact pieces of a simple polygon of area `area` whose bounding box starts at texel `c`
/// and spans `nx` texels in x, for the box rows `rows[0]..rows[1]` (inside the `texels ×
/// texels` texture): one [`Deposit::run`] per row over the columns the polygon's edges reach
/// or enclose, inside the texture, with pieces under a billionth of `area` (rounding noise)
/// set to 0.
///
/// Signed-area accumulation, as in font rasterizers: within each texel row, every edge's
/// part is cut at the integer x lines; a piece of signed height `dy` (its `y` extent, signed
/// by direction) in column `i` whose mean fractional `x` is `m` adds `dy·(1 − m)` to column
/// `i` (the trapezoid between the piece and the column's right side) and `dy·m` to column
/// `i + 1`, so that a running sum along the row gives every texel the area of the polygon's
/// part in it (the winding number integrated over the texel: ±area for a simple polygon,
/// either orientation). The running sum is taken only over the columns some piece wrote
/// (outside them it is 0 before the first and returns to 0 after the last, the edges of a
/// closed polygon adding up to no height), so work grows with the perimeter and the texels
/// covered, not with the bounding box.
#[inline(never)]
fn raster_splat(
    poly: &[[f64; 2]; 4],
    c: [f64; 2],
    nx: usize,
    rows: [f64; 2],
    area: f64,
    texels: u32,
    mut deposit: impl Deposit,
) {
    let (r0, r1) = (rows[0].max(0.0) as usize, rows[1].max(0.0) as usize);
    if r1 <= r0 || nx == 0 {
        return;
    }
    let w = nx + 1;
    RASTER.with_borrow_mut(|scratch| {
        let RasterScratch { cells, spans } = scratch;
        if cells.len() < w * (r1 - r0) {
            cells.resize(w * (r1 - r0), 0.0);
        }
        spans.clear();
        spans.resize(r1 - r0, [usize::MAX, 0]);
        let p = poly.map(|v| [v[0] - c[0], v[1] - c[1]]);
        let xmax = nx as f64;
        for k in 0..4 {
            let (a, b) = (p[k], p[(k + 1) & 3]);
            let dy_edge = b[1] - a[1];
            if dy_edge == 0.0 {
                continue;
            }
            let sign = dy_edge.signum();
            let slope = (b[0] - a[0]) / dy_edge;
            let (ylo, yhi) = (a[1].min(b[1]), a[1].max(b[1]));
            let first = (floor_f(ylo).max(r0 as f64)) as usize;
            let last = (ceil_f(yhi).min(r1 as f64)) as usize;
            for j in first..last {
                let (y0, y1) = (ylo.max(j as f64), yhi.min(j as f64 + 1.0));
                if !(y1 > y0) {
                    continue;
                }
                let dy = sign * (y1 - y0);
                let xa = (a[0] + (y0 - a[1]) * slope).clamp(0.0, xmax);
                let xb = (a[0] + (y1 - a[1]) * slope).clamp(0.0, xmax);
                let row = &mut cells[(j - r0) * w..][..w];
                let (xl, xr) = (xa.min(xb), xa.max(xb));
                // (xl >= 0: truncation is the floor)
                let il = (xl as usize).min(nx - 1);
                let ir = (ceil_f(xr) as usize).max(il + 1).min(nx);
                let span = &mut spans[j - r0];
                span[0] = span[0].min(il);
                span[1] = span[1].max(ir + 1);
                if ir - il == 1 {
                    let m = (0.5 * (xl + xr) - il as f64).clamp(0.0, 1.0);
                    row[il] += dy * (1.0 - m);
                    row[il + 1] += dy * m;
                    continue;
                }
                // the piece in each column it crosses, its height in proportion to its width
                let per_x = dy / (xr - xl);
                for i in il..ir {
                    let (p0, p1) = (xl.max(i as f64), xr.min(i as f64 + 1.0));
                    if !(p1 > p0) {
                        continue;
                    }
                    let d = per_x * (p1 - p0);
                    let m = (0.5 * (p0 + p1) - i as f64).clamp(0.0, 1.0);
                    row[i] += d * (1.0 - m);
                    row[i + 1] += d * m;
                }
            }
        }
        let min_piece = 1e-9 * area;
        let n = texels as usize;
        // the texture's columns among the box's: c[0] + i in [0, texels)
        let (ci, t) = (c[0] as i64, texels as i64);
        let (i_min, i_max) = ((-ci).max(0) as usize, (t - ci).clamp(0, nx as i64) as usize);
        for (jr, &[lo, hi]) in spans.iter().enumerate() {
            if lo >= hi {
                continue;
            }
            let row = &mut cells[jr * w..][lo..hi];
            let mut s = 0.0;
            for v in row.iter_mut() {
                s += *v;
                let a = s.abs();
                *v = if a > min_piece { a.min(1.0) } else { 0.0 };
            }
            let (a, b) = (lo.max(i_min), hi.min(i_max));
            if a < b {
                let y = (c[1] as i64 + (r0 + jr) as i64) as usize;
                deposit.run(y * n + (ci + a as i64) as usize, &row[a - lo..b - lo]);
            }
            row.fill(0.0);
        }
    });
}

/// Pieces of a polygon of area `area` whose bounding box spans one or two texels each way
/// from texel `c` (two in x if `wide`, two in y if `tall`, not both single): `put(i, j,
/// area)` for each texel of the box, pieces clamped at 0 against rounding.
///
/// In the box's frame (origin at `c`) the dividing lines are `x = 1` and `y = 1`. The part
/// of the polygon left of `x = 1` has the area `|∮ min(x − 1, 0) dy| ` over the polygon's
/// boundary (Green's theorem; the cut along the line adds nothing), the part above `y = 1`
/// likewise; the upper-left quadrant needs each edge clipped to `y <= 1` first. The other
/// pieces follow from these and the total.
#[inline(always)]
fn small_splat(
    poly: &[[f64; 2]; 4],
    area: f64,
    c: [f64; 2],
    wide: bool,
    tall: bool,
    mut put: impl FnMut(f64, f64, f64),
) {
    let p = poly.map(|v| [v[0] - c[0], v[1] - c[1]]);
    match (wide, tall) {
        (true, false) => {
            let left = below_line_area(&p, 0, 1.0);
            put(c[0], c[1], left);
            put(c[0] + 1.0, c[1], (area - left).max(0.0));
        }
        (false, true) => {
            let top = below_line_area(&p, 1, 1.0);
            put(c[0], c[1], top);
            put(c[0], c[1] + 1.0, (area - top).max(0.0));
        }
        _ => {
            let (left, top, q) = (
                below_line_area(&p, 0, 1.0),
                below_line_area(&p, 1, 1.0),
                quadrant_area(&p),
            );
            put(c[0], c[1], q);
            put(c[0] + 1.0, c[1], (top - q).max(0.0));
            put(c[0], c[1] + 1.0, (left - q).max(0.0));
            put(c[0] + 1.0, c[1] + 1.0, (area - left - top + q).max(0.0));
        }
    }
}

/// The mean over `s ∈ [0, 1]` of `min(a + (b − a)·s, 0)`, times 2.
#[inline(always)]
fn twice_mean_negative(a: f64, b: f64) -> f64 {
    // (f − |f|)/2 averaged: the mean of |f| is (|a| + |b|)/2 less |ab|/(|a| + |b|) where
    // the sign changes
    let cross = (-(a * b)).max(0.0) / (a.abs() + b.abs()).max(f64::MIN_POSITIVE);
    a.min(0.0) + b.min(0.0) + cross
}

/// Area of the part of the simple polygon `p` where coordinate `axis` is at most `c`.
#[inline(always)]
fn below_line_area(p: &[[f64; 2]; 4], axis: usize, c: f64) -> f64 {
    let o = 1 - axis;
    let mut s = 0.0;
    for k in 0..4 {
        let (a, b) = (p[k], p[(k + 1) & 3]);
        s += (b[o] - a[o]) * twice_mean_negative(a[axis] - c, b[axis] - c);
    }
    0.5 * s.abs()
}

/// Area of the part of the simple polygon `p` in `x <= 1, y <= 1`.
#[inline(always)]
fn quadrant_area(p: &[[f64; 2]; 4]) -> f64 {
    let mut s = 0.0;
    for k in 0..4 {
        let (a, b) = (p[k], p[(k + 1) & 3]);
        // the edge's parameters with y <= 1, and x − 1 at their ends
        let [s0, s1] = below_interval(a[1] - 1.0, b[1] - 1.0);
        let len = (s1 - s0).max(0.0);
        let dx = b[0] - a[0];
        let (fa, fb) = (a[0] - 1.0 + s0 * dx, a[0] - 1.0 + s1 * dx);
        s += (b[1] - a[1]) * len * twice_mean_negative(fa, fb);
    }
    0.5 * s.abs()
}

/// Most texels per side of a footprint split by [`grid_splat`] (larger ones are cut into
/// strips).
const GRID_MAX: usize = 4;

/// Pieces of a polygon spanning `nx × ny` texels (at most [`GRID_MAX`] each way) from texel
/// `c`: `put(i, j, area)` for each texel.
///
/// With the lines `X_i = c[0] + i`, `Y_j = c[1] + j`, the area `Q(i, j)` of the polygon's part
/// in `x ≤ X_i, y ≤ Y_j` is a boundary integral (Green's theorem) of `(x − X_i) dy` over
/// the parts of the polygon's edges inside that quadrant: the quadrant's own boundary lies
/// on `x = X_i` (where `x − X_i = 0`) or `y = Y_j` (where `dy = 0`) and adds nothing. Each
/// edge's part inside a quadrant is a parameter interval, so no clipping, no polygon buffer
/// and no branch per edge is needed; valid for any simple polygon. A texel's piece is
/// `Q(i+1, j+1) − Q(i, j+1) − Q(i+1, j) + Q(i, j)` (clamped at 0 against rounding), with
/// the last line of each axis unconstrained.
#[inline(always)]
fn grid_splat(
    poly: &[[f64; 2]; 4],
    c: [f64; 2],
    nx: usize,
    ny: usize,
    put: impl FnMut(f64, f64, f64),
) {
    // The common shapes (those within 2 × 2 texels go to `small_splat`) with constant bounds
    // (unrolled, sums in registers).
    match (nx, ny) {
        (3, 1) => grid_splat_n(poly, c, 3, 1, put),
        (1, 3) => grid_splat_n(poly, c, 1, 3, put),
        (3, 2) => grid_splat_n(poly, c, 3, 2, put),
        (2, 3) => grid_splat_n(poly, c, 2, 3, put),
        (3, 3) => grid_splat_n(poly, c, 3, 3, put),
        _ => grid_splat_n(poly, c, nx, ny, put),
    }
}

/// [`grid_splat`] for `nx × ny` texels (inlined, so constant sizes unroll).
#[inline(always)]
// indexed loops: each index serves more than one array or lookup
#[allow(clippy::needless_range_loop)]
fn grid_splat_n(
    poly: &[[f64; 2]; 4],
    c: [f64; 2],
    nx: usize,
    ny: usize,
    mut put: impl FnMut(f64, f64, f64),
) {
    let (nx, ny) = (nx.clamp(1, GRID_MAX), ny.clamp(1, GRID_MAX));
    // q[j][i] = |Q(i, j)|; row and column 0 stay 0.
    let mut q = [[0.0f64; GRID_MAX + 1]; GRID_MAX + 1];
    for k in 0..4 {
        let (a, b) = (poly[k], poly[(k + 1) & 3]);
        let dy = b[1] - a[1];
        let mut xs = [[0.0, 1.0]; GRID_MAX + 1];
        let mut ys = [[0.0, 1.0]; GRID_MAX + 1];
        for i in 1..nx {
            let x = c[0] + i as f64;
            xs[i] = below_interval(a[0] - x, b[0] - x);
        }
        for j in 1..ny {
            let y = c[1] + j as f64;
            ys[j] = below_interval(a[1] - y, b[1] - y);
        }
        for i in 1..=nx {
            let ax = a[0] - (c[0] + i as f64);
            let dx = b[0] - a[0];
            for j in 1..=ny {
                let s0 = xs[i][0].max(ys[j][0]);
                let s1 = xs[i][1].min(ys[j][1]).max(s0);
                // ∫ (x − X_i) dy over the edge's parameters s ∈ [s0, s1]
                q[j][i] += dy * (s1 - s0) * (ax + 0.5 * dx * (s1 + s0));
            }
        }
    }
    for j in 0..ny {
        for i in 0..nx {
            let w = q[j + 1][i + 1].abs() - q[j][i + 1].abs() - q[j + 1][i].abs() + q[j][i].abs();
            put(c[0] + i as f64, c[1] + j as f64, w.max(0.0));
        }
    }
}

/// The parameters `s ∈ [0, 1]` with `da + (db − da)·s <= 0`, as `[s0, s1]` (`s1 < s0` or
/// `s1 = s0` if none).
#[inline(always)]
// not `clamp`: `max(0.0).min(1.0)` maps a NaN ratio (da = dd = 0) to 0, `clamp` keeps NaN
#[allow(clippy::manual_clamp)]
fn below_interval(da: f64, db: f64) -> [f64; 2] {
    let dd = db - da;
    let s = (-da / dd).max(0.0).min(1.0);
    let lo = if dd < 0.0 { s } else { 0.0 };
    let hi = if dd > 0.0 {
        s
    } else if dd < 0.0 || da <= 0.0 {
        1.0
    } else {
        0.0
    };
    [lo, hi]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::resample::polygon_box_area;

    fn collect(c: [[f32; 2]; 4], texels: u32) -> (Splat, Vec<(usize, f64)>) {
        let mut v = Vec::new();
        let s = splat_footprint(&c, texels, |i, w| v.push((i, w)));
        (s, v)
    }

    #[test]
    fn unit_texel_goes_to_that_texel() {
        let (s, v) = collect([[2.0, 1.0], [3.0, 1.0], [3.0, 2.0], [2.0, 2.0]], 4);
        assert_eq!(s.kind, SplatKind::Exact);
        assert_eq!(v, vec![(4 + 2, 1.0)]);
    }

    #[test]
    fn straddling_square_splits_by_area() {
        // 1x1 square at [1.5, 2.5] x [1.25, 2.25]: quarters 0.5*0.75 etc.
        let (s, v) = collect([[1.5, 1.25], [2.5, 1.25], [2.5, 2.25], [1.5, 2.25]], 4);
        assert!((s.area - 1.0).abs() < 1e-12);
        let total: f64 = v.iter().map(|x| x.1).sum();
        assert!((total - 1.0).abs() < 1e-12);
        let get = |i: usize| v.iter().find(|x| x.0 == i).map_or(0.0, |x| x.1);
        assert!((get(4 + 1) - 0.375).abs() < 1e-12);
        assert!((get(8 + 2) - 0.125).abs() < 1e-12);
    }

    #[test]
    fn non_convex_and_bowtie_quads() {
        // dart: reflex corner at (1, 1) inside the triangle (0,0),(2,0),(1,2)... order 0,1,2,3
        let dart = [[0.0, 0.0], [2.0, 0.0], [1.0, 2.0], [1.0, 0.5]]
            .map(|p: [f32; 2]| [p[0] + 0.3, p[1] + 0.2]);
        let (s, v) = collect(dart, 8);
        // area = triangle (0,0),(2,0),(1,2) = 2 minus triangle (0,0),(1,0.5),(1,2)... via shoelace
        let expect = 0.5
            * ((0.0f64 * 0.0 - 2.0 * 0.0)
                + (2.0 * 2.0 - 1.0 * 0.0)
                + (1.0 * 0.5 - 1.0 * 2.0)
                + (1.0 * 0.0 - 0.0 * 0.5))
                .abs();
        assert!((s.area - expect).abs() < 1e-6, "{} {expect}", s.area);
        let total: f64 = v.iter().map(|x| x.1).sum();
        assert!((total - expect).abs() < 1e-6);
        // bow-tie: hull is the unit square scaled by 2
        let (s, v) = collect([[0.0, 0.0], [2.0, 2.0], [2.0, 0.0], [0.0, 2.0]], 4);
        assert!((s.area - 4.0).abs() < 1e-9);
        assert_eq!(v.len(), 4);
        assert!(v.iter().all(|x| (x.1 - 1.0).abs() < 1e-9));
    }

    #[test]
    fn degenerate_quads_never_nan() {
        let cases: [[[f32; 2]; 4]; 5] = [
            [[1.0, 1.0]; 4],
            [[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]],
            [[0.5, 0.5], [3.5, 0.5], [3.5, 0.5], [0.5, 0.5]],
            [[f32::NAN, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
            [[0.0, 0.0], [1e30, 0.0], [1e30, 1e30], [0.0, 1e30]],
        ];
        for c in cases {
            let (s, v) = collect(c, 4);
            assert!(s.area.is_finite() && s.area >= 0.0);
            assert!(v.iter().all(|x| x.1.is_finite() && x.1 > 0.0));
        }
        // collinear: area 0, bilinear with nothing deposited
        let (s, v) = collect([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0], [3.0, 3.0]], 4);
        assert_eq!((s.kind, s.area, v.len()), (SplatKind::Bilinear, 0.0, 0));
    }

    #[test]
    fn collapsed_footprint_is_bilinear_at_centre() {
        // 2^-11 x 2^-11 square (exact in f32) centred on (2.0, 1.5): halfway between texel
        // centres 1.5 and 2.5 in x, on the centre row in y
        let h = 1.0 / 4096.0;
        let (s, v) = collect(
            [
                [2.0 - h, 1.5 - h],
                [2.0 + h, 1.5 - h],
                [2.0 + h, 1.5 + h],
                [2.0 - h, 1.5 + h],
            ],
            4,
        );
        assert_eq!(s.kind, SplatKind::Bilinear);
        let a = s.area;
        assert_eq!(a, 4.0 * h as f64 * h as f64);
        assert_eq!(v.len(), 2);
        assert!(v.iter().all(|x| (x.1 - 0.5 * a).abs() < 1e-12));
    }

    #[test]
    fn small_footprint_is_exact() {
        // 0.2 x 0.2 square at [1.7, 1.9] x [1.3, 1.5]: inside texel (1, 1), where the bilinear
        // fallback would have spread it over four texels
        let (s, v) = collect([[1.7, 1.3], [1.9, 1.3], [1.9, 1.5], [1.7, 1.5]], 4);
        assert_eq!(s.kind, SplatKind::Exact);
        assert_eq!(v.len(), 1);
        assert_eq!(v[0].0, 4 + 1);
        assert!((v[0].1 - 0.04).abs() < 1e-7);
        // straddling x = 2: split by area
        let (s, v) = collect([[1.95, 1.3], [2.15, 1.3], [2.15, 1.5], [1.95, 1.5]], 4);
        assert_eq!(s.kind, SplatKind::Exact);
        let get = |i: usize| v.iter().find(|x| x.0 == i).map_or(0.0, |x| x.1);
        assert!(
            (get(4 + 1) - 0.01).abs() < 1e-7 && (get(4 + 2) - 0.03).abs() < 1e-7,
            "{v:?}"
        );
    }

    #[test]
    fn strip_cutting_matches_box_clipping() {
        // pseudo-random convex, concave and self-intersecting quads, partly outside
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        // sides up to 30 texels: the boundary-integral grid (up to 4 × 4) and the row
        // accumulation, partly outside the texture on every side
        for n in 0..1500 {
            let big = if n % 3 == 0 { 22.0 } else { 0.0 };
            let c = [
                rnd() * 14.0 - 1.0 - big / 2.0,
                rnd() * 14.0 - 1.0 - big / 2.0,
            ];
            let s = 0.3 + rnd() * 8.0 + big;
            let q: [[f32; 2]; 4] =
                std::array::from_fn(|_| [(c[0] + s * rnd()) as f32, (c[1] + s * rnd()) as f32]);
            let (sp, v) = collect(q, 16);
            let (poly, area) = footprint_polygon(&q.map(|p| [p[0] as f64, p[1] as f64]));
            assert!((sp.area - area).abs() < 1e-12);
            if sp.kind != SplatKind::Exact {
                continue;
            }
            for j in 0..16 {
                for i in 0..16 {
                    let want = polygon_box_area(
                        &poly,
                        [i as f64, j as f64, i as f64 + 1.0, j as f64 + 1.0],
                    );
                    let got = v.iter().find(|x| x.0 == j * 16 + i).map_or(0.0, |x| x.1);
                    // (pieces under a billionth of the footprint are dropped)
                    assert!(
                        (got - want).abs() < 1e-9 * area.max(1.0),
                        "{q:?} texel {i},{j}: {got} vs {want}"
                    );
                }
            }
        }
    }

    #[test]
    fn small_footprints_match_box_clipping() {
        // quads of 0.3-1.5 texels: 1×1, 1×2, 2×1 and 2×2 texels,
        // convex, concave and self-intersecting, also across the texture border
        let mut seed = 777u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut exact = 0;
        for _ in 0..4000 {
            let c = [rnd() * 5.0 - 0.5, rnd() * 5.0 - 0.5];
            let s = 0.3 + rnd() * 1.2;
            let q: [[f32; 2]; 4] =
                std::array::from_fn(|_| [(c[0] + s * rnd()) as f32, (c[1] + s * rnd()) as f32]);
            let (sp, v) = collect(q, 4);
            if sp.kind != SplatKind::Exact {
                continue;
            }
            exact += 1;
            let (poly, _) = footprint_polygon(&q.map(|p| [p[0] as f64, p[1] as f64]));
            for j in 0..4 {
                for i in 0..4 {
                    let want = polygon_box_area(
                        &poly,
                        [i as f64, j as f64, i as f64 + 1.0, j as f64 + 1.0],
                    );
                    let got = v.iter().find(|x| x.0 == j * 4 + i).map_or(0.0, |x| x.1);
                    assert!(
                        (got - want).abs() < 1e-9,
                        "{q:?} texel {i},{j}: {got} vs {want}"
                    );
                }
            }
        }
        assert!(exact > 1000, "{exact}");
    }

    #[test]
    fn outside_parts_are_dropped() {
        let (s, v) = collect([[-0.5, 0.0], [0.5, 0.0], [0.5, 1.0], [-0.5, 1.0]], 2);
        assert!((s.area - 1.0).abs() < 1e-12);
        assert_eq!(v, vec![(0, 0.5)]);
    }
}
