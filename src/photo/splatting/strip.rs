//! Splatting strips of footprints that share their edges (neighbouring pixels of up to
//! [`STRIP_ROWS`] photo rows on the same cell) in blocks ([`StripSplatter`]).
//!
//! The pixels of a photo tile the surface, so neighbouring footprints share edges. Every
//! footprint deposits `area(footprint ∩ texel) · v` into each texel, with `v` its 8 values
//! per texel² (the [`TexelSums`] fields: 1, feather, feather × colour, …). By signed-area
//! accumulation along texel rows (as font rasterizers, and [`crate::photo::splatting::splat`]'s row
//! rasterizer, do for one polygon) an edge adds, per texel row it crosses, its signed height
//! split between the columns it passes; a running sum along the row then gives each texel
//! its covered area. The sum is linear in the values, so a block of footprints is
//! rasterized at once with vector values: each footprint's values are `σ v` (`σ` = ±1 by its
//! orientation, so that every footprint adds `+area · v`); an edge two footprints of the
//! block share (the right edge of one and the left edge of its right neighbour, or the
//! bottom edge of one and the top edge of the one below) is drawn once, carrying the
//! difference of the two sides' values, and every other edge carries its footprint's own.
//! One running sum per texel row of the block then gives every texel `Σ area · v` over the
//! block, deposited with one tile lookup per tile row. A block is up to [`BLOCK_COLS`]
//! pixels of up to [`STRIP_ROWS`] rows whose box stays within [`BLOCK_BOX_MAX`] texels:
//! footprints arrive row by row, so the splatter holds a strip of rows and splats it one
//! column block at a time. Per footprint that is about two edges drawn (four alone, three
//! in runs along one row) and each texel resolved and deposited about once per block.
//!
//! The result equals the footprint-by-footprint exact splat ([`crate::photo::splatting::splat`]) up to f32
//! rounding of the sums (a test compares them); texels whose resolved coverage is below
//! [`MIN_RESOLVED`] texels² (rounding noise of the running sums) get nothing. Only simple
//! quads (not self-intersecting) whose area is at least [`crate::photo::MIN_SPLAT_AREA`] and whose
//! box spans at most [`FOOTPRINT_BOX_MAX`] texels each way join a strip; the rest take the
//! footprint-by-footprint path. The order of the deposits depends only on the footprints
//! offered (not on threads).

use crate::fastmath::{ceil_f, floor_f};
use crate::photo::splatting::texel_tiles::{TexelSums, TexelTiles};

/// A footprint's values per texel² of its area, in [`TexelSums`] field order: coverage,
/// weight, colour (3), footprint, grazing, clear.
pub(crate) type Values = [f32; 8];

/// Footprints whose box spans more texels than this either way are splatted alone.
pub(crate) const FOOTPRINT_BOX_MAX: f64 = 16.0;
/// Footprints that lie within this many texel columns and rows (the texel lines around
/// their box) are splatted alone: [`crate::photo::splatting::splat`]'s constant-size cases for one to four
/// texels cost less than a block, which pays by sharing edges and depositing each texel
/// once and so saves little when a footprint touches at most four texels (Engabreen
/// IMG_8902 with texture sizes fixed, whose footprints are mostly under a texel: 1.1 CPU-s of
/// 4.1 more in blocks; docs/projection.md, "Splatting cost").
pub(crate) const ALONE_TEXELS: f64 = 2.0;

/// Photo rows of a strip.
pub(crate) const STRIP_ROWS: u32 = 16;
/// Pixel columns of a block.
pub(crate) const BLOCK_COLS: u32 = 32;
/// The largest box (texels, columns × rows) of one block (a row's footprints that need
/// more are split into several blocks).
pub(crate) const BLOCK_BOX_MAX: usize = 4096;
/// Resolved coverage (texels²) below which a texel gets nothing: the running sums' f32
/// rounding (values of order 1 over tens of columns) stays far below it.
pub(crate) const MIN_RESOLVED: f32 = 1e-5;

/// One footprint of a strip: its corners (texel units of the accumulator, in pixel order:
/// top left, top right, bottom right, bottom left), values already multiplied by its
/// orientation sign, its photo pixel and its box (texel lines `[x0, x1, y0, y1]`).
#[derive(Clone, Copy, Debug)]
struct Item {
    corners: [[f32; 2]; 4],
    values: Values,
    pixel: [u32; 2],
    bounds: [f32; 4],
}

/// Collects strips of edge-sharing footprints and splats each in blocks (module docs).
/// Reusable: its buffers keep their capacity.
#[derive(Default)]
pub(crate) struct StripSplatter {
    /// The footprints of the current strip.
    items: Vec<Item>,
    /// The strip's first photo row.
    first_row: u32,
    /// Per row of the strip (in order), the index of its first item.
    rows: Vec<usize>,
    /// Row segments (item ranges) of the block being gathered.
    segs: Vec<[usize; 2]>,
    /// Per texel of a block's box (plus one column), the vector signed-area deltas; all
    /// zero between blocks.
    cells: Vec<Values>,
    /// Per box row, the local columns written.
    spans: Vec<[usize; 2]>,
}

/// Whether the quad is simple (not self-intersecting) and its signed doubled area (shoelace
/// over the corners in order, y down).
#[inline]
fn simple_signed_area(q: &[[f32; 2]; 4]) -> (bool, f64) {
    let p = q.map(|c| [c[0] as f64, c[1] as f64]);
    let cross = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let (s012, s023) = (cross(p[0], p[1], p[2]), cross(p[0], p[2], p[3]));
    if s012 * s023 >= 0.0 {
        return (true, s012 + s023);
    }
    let (s123, s130) = (cross(p[1], p[2], p[3]), cross(p[1], p[3], p[0]));
    (s123 * s130 >= 0.0, s012 + s023)
}

/// The union of two boxes `[x0, x1, y0, y1]`.
#[inline]
fn joined(a: [f32; 4], b: [f32; 4]) -> [f32; 4] {
    [
        a[0].min(b[0]),
        a[1].max(b[1]),
        a[2].min(b[2]),
        a[3].max(b[3]),
    ]
}

/// Texels of the deltas buffer a box needs (one column more than it spans).
#[inline]
fn box_texels(b: [f32; 4]) -> f64 {
    (b[1] - b[0] + 1.0) as f64 * (b[3] - b[2]) as f64
}

impl StripSplatter {
    /// Offers footprint `corners` (finite, texel units of `sums`) of photo pixel `pixel` with
    /// values `values` per texel²: `true` if it joined the current strip (a strip it cannot
    /// join, one of other rows, is splatted into `sums` first), `false` if it must be
    /// splatted alone (collapsed, self-intersecting or too large).
    #[inline]
    pub(crate) fn offer(
        &mut self,
        corners: [[f32; 2]; 4],
        pixel: [u32; 2],
        values: Values,
        sums: &mut TexelTiles,
    ) -> bool {
        let (simple, twice) = simple_signed_area(&corners);
        let area = 0.5 * twice.abs();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for c in &corners {
            for a in 0..2 {
                lo[a] = lo[a].min(c[a] as f64);
                hi[a] = hi[a].max(c[a] as f64);
            }
        }
        let box_ok = hi[0] - lo[0] <= FOOTPRINT_BOX_MAX && hi[1] - lo[1] <= FOOTPRINT_BOX_MAX;
        if !(simple && area >= crate::photo::MIN_SPLAT_AREA && box_ok && area.is_finite()) {
            return false;
        }
        // (the rasterizer's running sum gives −area for a quad of positive shoelace area)
        let sigma = if twice > 0.0 { -1.0 } else { 1.0 };
        let bounds = [floor_f(lo[0]), ceil_f(hi[0]), floor_f(lo[1]), ceil_f(hi[1])];
        if bounds[1] - bounds[0] <= ALONE_TEXELS && bounds[3] - bounds[2] <= ALONE_TEXELS {
            return false;
        }
        // (a strip keeps row-major order: rows ascending, columns ascending in a row)
        if let Some(last) = self.items.last()
            && (pixel[1] >= self.first_row.saturating_add(STRIP_ROWS)
                || pixel[1] < last.pixel[1]
                || (pixel[1] == last.pixel[1] && pixel[0] <= last.pixel[0]))
        {
            self.flush(sums);
        }
        match self.items.last() {
            None => {
                self.first_row = pixel[1];
                self.rows.push(0);
            }
            Some(last) if last.pixel[1] != pixel[1] => self.rows.push(self.items.len()),
            Some(_) => {}
        }
        self.items.push(Item {
            corners,
            values: values.map(|v| sigma * v),
            pixel,
            bounds: bounds.map(|b| b as f32),
        });
        true
    }

    /// Splats the current strip (if any) into `sums` and empties it.
    pub(crate) fn flush(&mut self, sums: &mut TexelTiles) {
        if self.items.is_empty() {
            return;
        }
        #[cfg(target_arch = "x86_64")]
        if let Some(v3) = crate::cpu::v3() {
            // (the same operations compiled for AVX2: the same sums, bit for bit)
            return v3.vectorize(Flush(self, sums));
        }
        self.flush_strip(sums);
    }

    /// [`StripSplatter::flush`] of a non-empty strip: column block by column block (each
    /// row's items of a block are a contiguous range: items arrive in row-major order),
    /// each cut by rows where its box would grow beyond [`BLOCK_BOX_MAX`].
    #[inline(always)]
    fn flush_strip(&mut self, sums: &mut TexelTiles) {
        let items = std::mem::take(&mut self.items);
        let mut rows = std::mem::take(&mut self.rows);
        let mut segs = std::mem::take(&mut self.segs);
        let n_rows = rows.len();
        rows.push(items.len());
        // per row, the first item not yet splatted
        let mut cursor: Vec<usize> = rows[..n_rows].to_vec();
        while let Some(block) = (0..n_rows)
            .filter(|&r| cursor[r] < rows[r + 1])
            .map(|r| items[cursor[r]].pixel[0] / BLOCK_COLS)
            .min()
        {
            segs.clear();
            let mut bounds = [0.0f32; 4];
            for r in 0..n_rows {
                let (a, end) = (cursor[r], rows[r + 1]);
                let mut b = a;
                let mut seg_box = match items.get(a) {
                    Some(it) if a < end => it.bounds,
                    _ => continue,
                };
                while b < end && items[b].pixel[0] / BLOCK_COLS == block {
                    seg_box = joined(seg_box, items[b].bounds);
                    b += 1;
                }
                if b == a {
                    continue;
                }
                cursor[r] = b;
                if box_texels(seg_box) > BLOCK_BOX_MAX as f64 {
                    // a row too wide for one block: pieces of it alone
                    if !segs.is_empty() {
                        self.splat_block(&items, &segs, bounds, sums);
                        segs.clear();
                    }
                    let mut p = a;
                    while p < b {
                        let mut pb = items[p].bounds;
                        let mut q = p + 1;
                        while q < b
                            && box_texels(joined(pb, items[q].bounds)) <= BLOCK_BOX_MAX as f64
                        {
                            pb = joined(pb, items[q].bounds);
                            q += 1;
                        }
                        self.splat_block(&items, &[[p, q]], pb, sums);
                        p = q;
                    }
                } else if segs.is_empty() {
                    segs.push([a, b]);
                    bounds = seg_box;
                } else if box_texels(joined(bounds, seg_box)) > BLOCK_BOX_MAX as f64 {
                    self.splat_block(&items, &segs, bounds, sums);
                    segs.clear();
                    segs.push([a, b]);
                    bounds = seg_box;
                } else {
                    segs.push([a, b]);
                    bounds = joined(bounds, seg_box);
                }
            }
            if !segs.is_empty() {
                self.splat_block(&items, &segs, bounds, sums);
            }
        }
        let mut items = items;
        items.clear();
        rows.clear();
        (self.items, self.rows, self.segs) = (items, rows, segs);
    }

    /// Splats the block made of the row segments `segs` of `items` (ranges, rows ascending,
    /// columns ascending within each; box `bounds`) into `sums`.
    #[inline(always)]
    fn splat_block(
        &mut self,
        items: &[Item],
        segs: &[[usize; 2]],
        bounds: [f32; 4],
        sums: &mut TexelTiles,
    ) {
        let [x0, x1, y0, y1] = bounds.map(|b| b as f64);
        let (w, h) = ((x1 - x0) as usize + 1, (y1 - y0) as usize);
        if h == 0 || w < 2 || segs.is_empty() {
            return;
        }
        if self.cells.len() < w * h {
            self.cells.resize(w * h, [0.0; 8]);
        }
        self.spans.clear();
        self.spans.resize(h, [usize::MAX, 0]);
        let local = |c: [f32; 2]| [c[0] as f64 - x0, c[1] as f64 - y0];
        // The neighbours: left and right in the same segment, above and below in the
        // segments of the rows before and after (cursors moving with the column).
        let row_of = |k: usize| items[segs[k][0]].pixel[1];
        for (si, seg) in segs.iter().enumerate() {
            let r = row_of(si);
            let mut up = (si > 0 && row_of(si - 1) + 1 == r).then(|| segs[si - 1]);
            let mut down = (si + 1 < segs.len() && row_of(si + 1) == r + 1).then(|| segs[si + 1]);
            for i in seg[0]..seg[1] {
                let it = &items[i];
                let c = it.pixel[0];
                let q = it.corners.map(local);
                let (v, k) = (&it.values, &it.corners);
                let left = (i > seg[0] && items[i - 1].pixel[0] + 1 == c).then(|| &items[i - 1]);
                let right =
                    (i + 1 < seg[1] && items[i + 1].pixel[0] == c + 1).then(|| &items[i + 1]);
                let near = |s: &mut Option<[usize; 2]>| {
                    let range = s.as_mut()?;
                    while range[0] < range[1] && items[range[0]].pixel[0] < c {
                        range[0] += 1;
                    }
                    (range[0] < range[1] && items[range[0]].pixel[0] == c).then(|| &items[range[0]])
                };
                let (above, below) = (near(&mut up), near(&mut down));
                // left and top: drawn by the neighbour when it shares the edge
                match left {
                    Some(n) if n.corners[1] == k[0] && n.corners[2] == k[3] => {}
                    _ => self.edge(q[3], q[0], v, w),
                }
                match above {
                    Some(n) if n.corners[3] == k[0] && n.corners[2] == k[1] => {}
                    _ => self.edge(q[0], q[1], v, w),
                }
                // right and bottom: the difference of the two sides where shared
                match right {
                    Some(n) if n.corners[0] == k[1] && n.corners[3] == k[2] => {
                        let d: Values = std::array::from_fn(|j| v[j] - n.values[j]);
                        self.edge(q[1], q[2], &d, w);
                    }
                    _ => self.edge(q[1], q[2], v, w),
                }
                match below {
                    Some(n) if n.corners[0] == k[3] && n.corners[1] == k[2] => {
                        let d: Values = std::array::from_fn(|j| v[j] - n.values[j]);
                        self.edge(q[2], q[3], &d, w);
                    }
                    _ => self.edge(q[2], q[3], v, w),
                }
            }
        }
        self.resolve(sums, [x0, y0], w);
    }

    /// Adds the signed-area deltas of the edge `a → b` (local texel units of the run's box,
    /// `w` columns) carrying values `v`.
    #[inline(always)]
    // indexed loops: each index serves more than one array or lookup
    #[allow(clippy::needless_range_loop)]
    fn edge(&mut self, a: [f64; 2], b: [f64; 2], v: &Values, w: usize) {
        let dy_edge = b[1] - a[1];
        if dy_edge == 0.0 {
            return;
        }
        let h = self.spans.len();
        // walked downwards, the sign kept for the deltas
        let (top, bottom, sign) = if dy_edge > 0.0 {
            (a, b, 1.0)
        } else {
            (b, a, -1.0)
        };
        let slope = (bottom[0] - top[0]) / (bottom[1] - top[1]);
        let first = floor_f(top[1]).max(0.0) as usize;
        let last = (ceil_f(bottom[1]) as usize).min(h);
        let xmax = (w - 1) as f64;
        let x_at = |y: f64| (top[0] + (y - top[1]) * slope).clamp(0.0, xmax);
        let mut y0 = top[1].max(first as f64);
        let mut xa = x_at(y0);
        for j in first..last {
            let y1 = bottom[1].min(j as f64 + 1.0);
            let xb = x_at(y1);
            let dyv = y1 - y0;
            let x_prev = xa;
            y0 = y1;
            xa = xb;
            if !(dyv > 0.0) {
                continue;
            }
            let dy = sign * dyv;
            let xa = x_prev;
            let (xl, xr) = (xa.min(xb), xa.max(xb));
            // (xl >= 0: truncation is the floor)
            let il = (xl as usize).min(w - 2);
            let ir = (ceil_f(xr) as usize).max(il + 1).min(w - 1);
            let span = &mut self.spans[j];
            span[0] = span[0].min(il);
            span[1] = span[1].max(ir + 1);
            let row = &mut self.cells[j * w..][..w];
            if ir - il == 1 {
                let m = (0.5 * (xl + xr) - il as f64).clamp(0.0, 1.0);
                add(&mut row[il], v, (dy * (1.0 - m)) as f32);
                add(&mut row[il + 1], v, (dy * m) as f32);
                continue;
            }
            // the piece in each column it crosses, its height in proportion to its width:
            // column i gets the left share of its own piece and the right share of the
            // previous column's, one vector add per column
            let per_x = dy / (xr - xl);
            let mut carry = 0.0f64;
            for i in il..ir {
                let (p0, p1) = (xl.max(i as f64), xr.min(i as f64 + 1.0));
                let (mut left, mut right) = (0.0, 0.0);
                if p1 > p0 {
                    let d = per_x * (p1 - p0);
                    let m = (0.5 * (p0 + p1) - i as f64).clamp(0.0, 1.0);
                    left = d * (1.0 - m);
                    right = d * m;
                }
                add(&mut row[i], v, (carry + left) as f32);
                carry = right;
            }
            add(&mut row[ir], v, carry as f32);
        }
    }

    /// Running sums along each row of the run's box (origin `o`, `w` columns), deposited
    /// into `sums` where the texture is and the coverage reaches [`MIN_RESOLVED`]; clears the
    /// deltas.
    #[inline(always)]
    fn resolve(&mut self, sums: &mut TexelTiles, o: [f64; 2], w: usize) {
        let side = sums.side() as i64;
        let (ox, oy) = (o[0] as i64, o[1] as i64);
        for (j, span) in self.spans.iter().enumerate() {
            let [lo, hi] = *span;
            if lo >= hi {
                continue;
            }
            let row = &mut self.cells[j * w..][lo..hi];
            let mut s = [0.0f32; 8];
            for c in row.iter_mut() {
                for k in 0..8 {
                    s[k] += c[k];
                }
                *c = s;
            }
            let y = oy + j as i64;
            // the texture's columns among lo..hi: ox + i in [0, side)
            let a = (lo as i64).max(-ox);
            let b = (hi as i64).min(side - ox);
            if (0..side).contains(&y) && a < b {
                let t0 = (y * side + ox + a) as usize;
                deposit_run(
                    sums,
                    t0,
                    &row[(a - lo as i64) as usize..(b - lo as i64) as usize],
                );
            }
            row.fill([0.0; 8]);
        }
    }
}

/// [`StripSplatter::flush_strip`] as a call `pulp` can compile for AVX2.
#[cfg(target_arch = "x86_64")]
struct Flush<'s, 't>(&'s mut StripSplatter, &'t mut TexelTiles);

#[cfg(target_arch = "x86_64")]
impl pulp::NullaryFnOnce for Flush<'_, '_> {
    type Output = ();

    #[inline(always)]
    fn call(self) {
        self.0.flush_strip(self.1)
    }
}

/// `cell += v · f`, channel by channel.
#[inline(always)]
fn add(cell: &mut Values, v: &Values, f: f32) {
    for k in 0..8 {
        cell[k] += v[k] * f;
    }
}

/// Adds the resolved values `vals` to texels `t, t + 1, …` of one row of `sums`, one tile
/// row at a time, skipping texels whose coverage is below [`MIN_RESOLVED`] (a tile is
/// allocated only for a texel that gets something).
#[inline(always)]
fn deposit_run(sums: &mut TexelTiles, t: usize, vals: &[Values]) {
    let mut k = 0;
    while k < vals.len() {
        let n = sums.run_len(t + k, vals.len() - k);
        if n == 0 {
            return;
        }
        let part = &vals[k..k + n];
        if part.iter().any(|v| v[0] >= MIN_RESOLVED)
            && let Some(records) = sums.run_mut(t + k, n)
        {
            for (r, v) in records.iter_mut().zip(part) {
                if v[0] >= MIN_RESOLVED {
                    add_record(r, v);
                }
            }
        }
        k += n;
    }
}

/// Adds resolved values to a record (negative rounding noise clamped to 0).
#[inline(always)]
fn add_record(r: &mut TexelSums, v: &Values) {
    r.coverage += v[0];
    r.weight += v[1].max(0.0);
    for c in 0..3 {
        r.colour[c] += v[2 + c].max(0.0);
    }
    r.footprint += v[5].max(0.0);
    r.grazing += v[6].max(0.0);
    r.clear += v[7].max(0.0);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photo::splatting::splat::splat_footprint;

    /// Corners of pixel `(c, r)` of a warped pixel mesh (shared between neighbours): pixels
    /// `scale` texels wide, sheared and bent, shifted by `origin`; `mirror` flips x.
    fn corner(c: u32, r: u32, scale: f64, origin: [f64; 2], mirror: bool) -> [f32; 2] {
        let (x, y) = (c as f64, r as f64);
        let u = scale * (x + 0.3 * y + 0.8 * (0.21 * y).sin() + 0.05 * x * x / 40.0);
        let v = scale * (0.6 * y + 0.15 * x + 0.5 * (0.17 * x).cos());
        let u = if mirror { -u } else { u };
        [(origin[0] + u) as f32, (origin[1] + v) as f32]
    }

    /// Per texel, the 8 sums of footprint-by-footprint exact splats (f64).
    fn reference(fps: &[([[f32; 2]; 4], Values)], texels: u32) -> Vec<[f64; 8]> {
        let mut out = vec![[0.0f64; 8]; (texels * texels) as usize];
        for (corners, v) in fps {
            splat_footprint(corners, texels, |t, w| {
                for k in 0..8 {
                    out[t][k] += w * v[k] as f64;
                }
            });
        }
        out
    }

    #[test]
    fn blocks_equal_footprint_by_footprint_splats() {
        let texels = 64u32;
        for (scale, origin, mirror) in [
            (0.45, [-3.0, 2.0], false),
            (1.3, [-8.5, -4.25], false),
            (2.6, [70.0, -10.0], true),
            (5.5, [-20.0, 3.0], false),
        ] {
            // (150 columns: several column blocks; rows past a strip's 16)
            let (cols, rows) = (150u32, 40u32);
            let mut fps = Vec::new();
            let mut pixels = Vec::new();
            for r in 0..rows {
                for c in 0..cols {
                    if (c * 31 + r * 17) % 23 == 0 {
                        continue; // a gap: its neighbours draw their own edges
                    }
                    let mut corners = [
                        corner(c, r, scale, origin, mirror),
                        corner(c + 1, r, scale, origin, mirror),
                        corner(c + 1, r + 1, scale, origin, mirror),
                        corner(c, r + 1, scale, origin, mirror),
                    ];
                    if (c + 3 * r) % 19 == 0 {
                        // corners not shared with any neighbour
                        corners = corners.map(|k| [k[0] + 0.01, k[1] - 0.02]);
                    }
                    let q = 0.5 + 0.5 * ((c * 7 + r * 3) % 11) as f32 / 10.0;
                    let g = ((c * 13 + r * 5) % 17) as f32 / 16.0;
                    let v = [1.0, q, q * g, q * (1.0 - g), q * 0.3, q * 0.02, q * 1.7, q];
                    fps.push((corners, v));
                    pixels.push([c, r]);
                    if (c * 5 + r) % 37 == 0 {
                        // the same pixel offered twice (it starts a new strip)
                        fps.push((corners, v));
                        pixels.push([c, r]);
                    }
                }
            }
            let want = reference(&fps, texels);
            let mut sums = TexelTiles::new(texels);
            let mut strips = StripSplatter::default();
            // (the refused ones, footprints within 2 × 2 texels, are splatted alone as by
            // the accumulator)
            let mut alone = Vec::new();
            for ((corners, v), &p) in fps.iter().zip(&pixels) {
                if !strips.offer(*corners, p, *v, &mut sums) {
                    alone.push((*corners, *v));
                }
            }
            strips.flush(&mut sums);
            let offered = fps.len() - alone.len();
            assert!(
                offered > fps.len() / 2 || scale < 1.0,
                "scale {scale}: {offered}"
            );
            assert!(
                alone.len() > fps.len() / 2 || scale > 1.0,
                "scale {scale}: {offered}"
            );
            let alone = reference(&alone, texels);
            let mut covered = 0;
            for (t, w) in want.iter().enumerate() {
                let s = sums.get(t);
                let a = alone[t];
                let got = [
                    s.coverage,
                    s.weight,
                    s.colour[0],
                    s.colour[1],
                    s.colour[2],
                    s.footprint,
                    s.grazing,
                    s.clear,
                ];
                covered += (w[0] > 0.5) as usize;
                for k in 0..8 {
                    assert!(
                        (got[k] as f64 + a[k] - w[k]).abs() <= 2e-5 * (1.0 + w[k].abs()),
                        "scale {scale} texel {t} channel {k}: {} against {}",
                        got[k],
                        w[k]
                    );
                }
            }
            assert!(covered > 100, "scale {scale}: {covered} texels covered");
        }
    }

    #[test]
    fn folded_collapsed_large_and_small_footprints_are_refused() {
        let mut sums = TexelTiles::new(32);
        let mut strips = StripSplatter::default();
        let v = [1.0; 8];
        // self-intersecting (a bow tie)
        let bow = [[1.0, 1.0], [4.0, 4.0], [4.0, 1.0], [1.0, 4.0]];
        assert!(!strips.offer(bow, [0, 0], v, &mut sums));
        // collapsed to a sliver
        let sliver = [[1.0, 1.0], [2.5, 2.5], [4.0, 4.0], [2.5, 2.5]];
        assert!(!strips.offer(sliver, [1, 0], v, &mut sums));
        // a box beyond FOOTPRINT_BOX_MAX texels
        let large = [[0.0, 0.0], [20.0, 0.0], [20.0, 2.0], [0.0, 2.0]];
        assert!(!strips.offer(large, [2, 0], v, &mut sums));
        // non-finite corners
        let nan = [[f32::NAN, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(!strips.offer(nan, [3, 0], v, &mut sums));
        strips.flush(&mut sums);
        assert_eq!(sums.allocated(), 0);
        // within 2 × 2 texels (cheaper alone), even across texel lines
        for (k, x) in [0.2f32, 0.6, 5.0].into_iter().enumerate() {
            let small = [[x, 1.5], [x + 1.0, 1.5], [x + 1.0, 2.4], [x, 2.4]];
            assert!(!strips.offer(small, [k as u32, 3], v, &mut sums));
        }
        strips.flush(&mut sums);
        assert_eq!(sums.allocated(), 0);
        // a run broken by a gap (pixel 3 missing) or by corners not shared is still exact
        let sq = |x: f32| [[x, 4.0], [x + 2.5, 4.0], [x + 2.5, 6.0], [x, 6.0]];
        for (p, x) in [(0u32, 2.0f32), (1, 4.5), (2, 7.0), (4, 12.0), (5, 14.6)] {
            assert!(strips.offer(sq(x), [p, 7], v, &mut sums));
        }
        strips.flush(&mut sums);
        let total: f32 = (0..32 * 32).map(|t| sums.get(t).coverage).sum();
        assert!((total - 5.0 * 5.0).abs() < 1e-4, "{total}");
    }
}
