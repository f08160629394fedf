//! Pixel footprints of a photo in the cells' textures.
//!
//! One ray per pixel corner (`(W+1)·(H+1)` rays, [`crate::photo::footprints::corners`]), nearest front-face hit
//! → texture position `Σ b_i·t_i` in the hit triangle's cell. Per pixel:
//! 1. **Cell**: the cell hit by most of the pixel's four corners; ties go to the lowest
//!    manifest index. Corners that hit another cell or nothing are *missing*.
//! 2. **Occlusion boundary**: a corner that hit another cell at a distance outside
//!    `[d_min·(1 − j) − 2s, d_max·(1 + j) + 2s]`, where `d_min`, `d_max` are the distances of
//!    the pixel's own corners, `s = d_max − d_min` their spread (so grazing views, where the
//!    distance changes fast from corner to corner, do not trigger it) and `j` =
//!    [`FootprintOptions::max_depth_jump`], means the pixel straddles a depth discontinuity
//!    between cells (a silhouette whose two sides lie in different cells): it is rejected as
//!    a silhouette pixel.
//! 3. **Silhouette** (unless all corners hit one triangle): for each edge of the polygon of
//!    the present corners whose ends lie in different triangles, walk the cell's mesh in
//!    texture space ([`crate::raycast`]); crossing an edge between a front- and a
//!    back-facing triangle rejects the pixel.
//! 4. **Reconstruction** ([`crate::photo::footprints::reconstruct`], switchable): missing corners from the
//!    parallelogram rule or from the adjacent footprints' corners in the same cell. A
//!    reconstructed corner is also walked to from a present one, so a completion reaching
//!    over a silhouette (e.g. a ridge against the sky) rejects the pixel instead.
//!    Silhouette pixels are never reconstructed; pixels that cannot be completed are dropped.
//! 5. **Size guard**: footprints with a non-finite corner, an area above
//!    [`FootprintOptions::max_area`] texels² or a side/diagonal longer than
//!    [`FootprintOptions::max_extent`] texels (grazing rays) are dropped.
//!
//! `cos_view` and `distance` are the means over the pixel's present corners (no extra
//! centre ray: that would double the ray count for a quantity that varies little within a
//! pixel). Rows are processed in bands in parallel (each band casts its own corner rows;
//! the few corners of the rows just above and below that the adjacent-footprint rule asks
//! for are cast one by one, with the same hits), collected in order, so the result does not
//! depend on the thread count. [`for_each_footprint_batch`] hands the
//! footprints over in batches of bands (in row order) and reuses their buffers, so a
//! 12-MP photo never holds all of its ~10 M footprints (about 56 bytes each) at once.

use std::sync::Mutex;

use glam::Vec3;
use rayon::prelude::*;

use crate::camera::{CameraModel, RayCaster};
use crate::photo::footprints::corners::{CornerHit, cast_corner_alone, cast_corner_row};
use crate::photo::footprints::reconstruct::reconstruct;
use crate::photo::{CellFootprints, FootprintSet, PixelFootprint};
use crate::raycast::Caster;
use crate::raycast::LevelScene;
use crate::raycast::RayAccel;
use crate::raycast::ViewGrid;
use crate::raycast::crosses_silhouette;

/// Pixel rows per parallel band.
const BAND_ROWS: u32 = 64;

/// How footprints are formed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FootprintOptions {
    /// Complete footprints with missing corners (parallelogram / adjacent footprints).
    pub reconstruct: bool,
    /// Reject pixels whose footprint crosses a silhouette edge.
    pub reject_silhouettes: bool,
    /// Largest footprint area kept, texels² of the cell's texture (larger ones, from rays
    /// grazing the surface, are dropped). Default 256 (a pixel over 16 × 16 texels).
    pub max_area: f32,
    /// Longest footprint side or diagonal kept, texels. Default 64.
    pub max_extent: f32,
    /// Relative distance jump between a pixel's corners in its cell and a corner in
    /// another cell above which the pixel is rejected as a silhouette (step 2 of the module
    /// docs); `f32::INFINITY` disables it. Default 0.1. Only with `reject_silhouettes`.
    pub max_depth_jump: f32,
}

impl Default for FootprintOptions {
    fn default() -> Self {
        FootprintOptions {
            reconstruct: true,
            reject_silhouettes: true,
            max_area: 256.0,
            max_extent: 64.0,
            max_depth_jump: 0.1,
        }
    }
}

/// Casts rays through every pixel corner of `camera`'s image (undistorted) against `scene`
/// and returns every pixel's footprint in the texture of the cell it belongs to.
pub fn photo_footprints(
    scene: &LevelScene,
    camera: &CameraModel,
    opts: &FootprintOptions,
) -> FootprintSet {
    photo_footprints_in(&FootprintBuffers::default(), scene, camera, opts)
}

/// [`photo_footprints`] with its chunks taken from `buffers` (give them back with
/// [`FootprintBuffers::recycle`] once used). The footprints are the same.
pub fn photo_footprints_in(
    buffers: &FootprintBuffers,
    scene: &LevelScene,
    camera: &CameraModel,
    opts: &FootprintOptions,
) -> FootprintSet {
    let mut all = FootprintSet::default();
    for_each_footprint_batch_in(buffers, scene, camera, opts, |batch| all.append(batch));
    all
}

/// [`photo_footprints`] in batches of consecutive pixel rows, handed to `sink` in row order
/// as they are cast (the footprints of the whole photo are never held at once: a batch's
/// buffers are reused once `sink` returns, and the next batch is cast while `sink` runs).
/// Each batch is a [`FootprintSet`] of its rows (cells by increasing manifest index, counts
/// of its rows); `sink` may take its chunks. Concatenating the batches per cell gives exactly
/// [`photo_footprints`]' result, whatever the thread count.
pub fn for_each_footprint_batch(
    scene: &LevelScene,
    camera: &CameraModel,
    opts: &FootprintOptions,
    sink: impl FnMut(&mut FootprintSet) + Send,
) {
    for_each_footprint_batch_in(&FootprintBuffers::default(), scene, camera, opts, sink);
}

/// [`for_each_footprint_batch`] with its scratch memory taken from (and left in) `buffers`,
/// so that the casts of several photos and levels reuse the same memory. The footprints
/// are the same.
pub fn for_each_footprint_batch_in(
    buffers: &FootprintBuffers,
    scene: &LevelScene,
    camera: &CameraModel,
    opts: &FootprintOptions,
    mut sink: impl FnMut(&mut FootprintSet) + Send,
) {
    for_each_footprint_batch_rows_in(buffers, scene, camera, opts, |set, _| sink(set));
}

/// [`for_each_footprint_batch_in`] with each batch's pixel rows `[first, end)` given to
/// `sink` too: no later batch holds a footprint of a row before `end`.
pub fn for_each_footprint_batch_rows_in(
    buffers: &FootprintBuffers,
    scene: &LevelScene,
    camera: &CameraModel,
    opts: &FootprintOptions,
    mut sink: impl FnMut(&mut FootprintSet, [u32; 2]) + Send,
) {
    let (w, h) = (camera.width, camera.height);
    let origin = (camera.position - scene.frame_origin).as_vec3();
    if w == 0 || h == 0 || scene.triangle_count() == 0 || !origin.is_finite() {
        return;
    }
    let rays = camera.ray_caster().with_table();
    let caster = match (scene.accel, scene.bvh()) {
        (RayAccel::Bvh(_), Some(bvh)) => Caster::Bvh(bvh),
        (RayAccel::ViewGrid(p), _) => {
            Caster::Grid(ViewGrid::build(scene.triangles(), camera, &rays, origin, p))
        }
        (RayAccel::Bvh(_), None) => return,
    };
    // Output buckets: scene cells ordered by manifest index (then scene order).
    let mut order: Vec<usize> = (0..scene.cells.len()).collect();
    order.sort_by_key(|&i| (scene.cells[i].cell, i));
    let mut bucket = vec![0u32; scene.cells.len()];
    for (b, &i) in order.iter().enumerate() {
        bucket[i] = b as u32;
    }
    let ctx = Ctx {
        scene,
        caster: &caster,
        rays,
        origin,
        w,
        h,
        opts: *opts,
        bucket: &bucket,
        buffers,
    };
    let bands = h.div_ceil(BAND_ROWS);
    let mut pending: Option<(FootprintSet, [u32; 2])> = None;
    let mut b0 = 0;
    while b0 < bands || pending.is_some() {
        let b1 = (b0 + BATCH_BANDS).min(bands);
        let rows = [b0 * BAND_ROWS, (b1 * BAND_ROWS).min(h)];
        let (next, ()) = rayon::join(
            || (b0 < b1).then(|| (ctx.batch(b0..b1, &order), rows)),
            || {
                if let Some((mut done, done_rows)) = pending.take() {
                    sink(&mut done, done_rows);
                    buffers.recycle(done);
                }
            },
        );
        pending = next;
        b0 = b1;
    }
}

/// Pixel-row bands per batch of [`for_each_footprint_batch`] (with 64-row bands, 512 rows:
/// about 90 MB of footprints for a 4290-pixel-wide photo; smaller batches leave threads idle
/// at the join of casting and splatting, docs/projection.md).
const BATCH_BANDS: u32 = 8;

/// Scratch memory of footprint casts (corner hits and footprint chunks), reused across the
/// bands and batches of one cast and, when shared ([`for_each_footprint_batch_in`]), across
/// casts: fresh memory costs a page fault per 4 KiB on first touch. Holds at most what the
/// largest cast had in use at once; freed when dropped.
#[derive(Default)]
pub struct FootprintBuffers {
    hits: Mutex<Vec<Vec<CornerHit>>>,
    /// Empty chunks by size class ([`CHUNK_SIZES`]).
    chunks: Mutex<[Vec<Vec<PixelFootprint>>; 3]>,
}

/// Capacities (footprints) of the chunks a band fills per cell: the first chunk of a cell
/// in a band is small, later ones larger. Chunks never grow (no reallocation, no copy);
/// a full one is followed by a new one, so every chunk returns to its own size class.
const CHUNK_SIZES: [usize; 3] = [1 << 12, 1 << 14, 1 << 16];

impl FootprintBuffers {
    fn take_hits(&self) -> Vec<CornerHit> {
        self.hits
            .lock()
            .map(|mut p| p.pop())
            .ok()
            .flatten()
            .unwrap_or_default()
    }

    fn put_hits(&self, v: Vec<CornerHit>) {
        if let Ok(mut p) = self.hits.lock() {
            p.push(v);
        }
    }

    /// An empty chunk of at least the capacity of size class `class`.
    fn take_chunk(&self, class: usize) -> Vec<PixelFootprint> {
        let class = class.min(CHUNK_SIZES.len() - 1);
        let pooled = self
            .chunks
            .lock()
            .map(|mut p| p[class].pop())
            .ok()
            .flatten();
        pooled.unwrap_or_else(|| Vec::with_capacity(CHUNK_SIZES[class]))
    }

    /// Keeps the (emptied) chunk buffers of `set` (a consumed batch or footprint set) for
    /// later casts.
    pub fn recycle(&self, set: FootprintSet) {
        if let Ok(mut p) = self.chunks.lock() {
            for mut chunk in set.cells.into_iter().flat_map(|c| c.chunks) {
                // the largest class the chunk can serve
                if let Some(class) = CHUNK_SIZES.iter().rposition(|&n| chunk.capacity() >= n) {
                    chunk.clear();
                    p[class].push(chunk);
                }
            }
        }
    }
}

/// One band's footprints per output bucket (row-major), and its counts (in a set without
/// cells).
#[derive(Default)]
struct BandOut {
    /// Per bucket, its chunks in row order.
    buckets: Vec<Vec<Vec<PixelFootprint>>>,
    counts: FootprintSet,
}

/// What became of one pixel.
enum Outcome {
    Miss,
    Silhouette,
    Dropped,
    Footprint(PixelFootprint, u32),
}

/// Silhouette crossings of the pixel edges of one band that neighbouring pixels share,
/// each walked once, left to right or top to bottom (`crosses_silhouette` of a segment is
/// evaluated from its left or upper end): the right edge of the previous pixel in the row
/// and the bottom edges of the previous row. `None` where unknown (the neighbour was not a
/// one-cell pixel, or stopped before that edge).
struct EdgeCache {
    /// Right edge of the previous pixel of this row.
    right: Option<bool>,
    /// Bottom edges of the previous row's pixels (read as this row's top edges).
    above: Vec<Option<bool>>,
    /// Bottom edges of this row's pixels so far.
    below: Vec<Option<bool>>,
}

impl EdgeCache {
    fn new(w: usize) -> EdgeCache {
        EdgeCache {
            right: None,
            above: vec![None; w],
            below: vec![None; w],
        }
    }

    /// Starts a row: the last row's bottom edges become the top edges.
    fn next_row(&mut self) {
        std::mem::swap(&mut self.above, &mut self.below);
        self.below.fill(None);
        self.right = None;
    }

    fn top(&self, c: usize) -> Option<bool> {
        self.above.get(c).copied().flatten()
    }

    fn left(&self) -> Option<bool> {
        self.right
    }

    /// Records pixel `c`'s right and bottom edges (and moves on to pixel `c + 1`).
    fn set(&mut self, c: usize, right: Option<bool>, bottom: Option<bool>) {
        self.right = right;
        if let Some(b) = self.below.get_mut(c) {
            *b = bottom;
        }
    }
}

struct Ctx<'a> {
    scene: &'a LevelScene,
    caster: &'a Caster<'a>,
    rays: RayCaster,
    origin: Vec3,
    w: u32,
    h: u32,
    opts: FootprintOptions,
    bucket: &'a [u32],
    buffers: &'a FootprintBuffers,
}

/// The corner rows a band cast: rows `j_lo..=j_hi`, `stride` = W + 1 corners each.
struct CornerRows {
    hits: Vec<CornerHit>,
    j_lo: i64,
    j_hi: i64,
    stride: i64,
}

impl CornerRows {
    #[inline]
    fn get(&self, i: i64, j: i64) -> Option<&CornerHit> {
        if i < 0 || i >= self.stride || j < self.j_lo || j > self.j_hi {
            return None;
        }
        self.hits.get(((j - self.j_lo) * self.stride + i) as usize)
    }
}

impl Ctx<'_> {
    /// The footprints of bands `bands` (pixel rows `bands.start·BAND_ROWS..`), per cell in
    /// `order` (scene cells by manifest index), with their counts.
    fn batch(&self, bands: std::ops::Range<u32>, order: &[usize]) -> FootprintSet {
        let outs: Vec<BandOut> = bands.into_par_iter().map(|b| self.band(b)).collect();
        // Every bucket's chunks in band (= row) order: no footprint is copied.
        let mut set = FootprintSet::default();
        let mut cells: Vec<CellFootprints> = order
            .iter()
            .map(|&i| CellFootprints {
                cell: self.scene.cells[i].cell,
                chunks: Vec::new(),
            })
            .collect();
        for b in outs {
            set.add_counts(&b.counts);
            for (k, chunks) in b.buckets.into_iter().enumerate() {
                cells[k]
                    .chunks
                    .extend(chunks.into_iter().filter(|c| !c.is_empty()));
            }
        }
        set.cells = cells.into_iter().filter(|c| !c.chunks.is_empty()).collect();
        set
    }

    /// Casts and forms the footprints of pixel rows `b·BAND_ROWS..`.
    fn band(&self, b: u32) -> BandOut {
        let r0 = b * BAND_ROWS;
        let r1 = (r0 + BAND_ROWS).min(self.h);
        // Corner rows r0..=r1; the rows just above and below (corners of adjacent footprints
        // for reconstruction, rarely needed) are cast on demand when rays do not depend on
        // their row, else with the band.
        let halo = u32::from(!self.rays.rays_independent());
        let j_lo = r0.saturating_sub(halo);
        let j_hi = (r1 + halo).min(self.h);
        let stride = self.w as usize + 1;
        let mut hits = self.buffers.take_hits();
        hits.clear();
        hits.resize((j_hi - j_lo + 1) as usize * stride, CornerHit::MISS);
        for (row, j) in hits.chunks_exact_mut(stride).zip(j_lo..=j_hi) {
            cast_corner_row(self.scene, self.caster, &self.rays, self.origin, j, row);
        }
        let rows = CornerRows {
            hits,
            j_lo: j_lo as i64,
            j_hi: j_hi as i64,
            stride: stride as i64,
        };
        let mut out = BandOut {
            buckets: vec![Vec::new(); self.scene.cells.len()],
            ..BandOut::default()
        };
        // Silhouette crossings of pixel edges shared with the next pixel (its left edge) and
        // the next row (its top edges), walked in one direction (see `EdgeCache`).
        let mut edges = EdgeCache::new(self.w as usize);
        for r in r0..r1 {
            edges.next_row();
            for c in 0..self.w {
                match self.pixel(&rows, c, r, &mut edges) {
                    Outcome::Miss => continue,
                    Outcome::Silhouette => out.counts.rejected_silhouette += 1,
                    Outcome::Dropped => out.counts.dropped += 1,
                    Outcome::Footprint(fp, bucket) => {
                        out.counts.reconstructed += u64::from(fp.reconstructed > 0);
                        let chunks = &mut out.buckets[bucket as usize];
                        match chunks.last_mut() {
                            Some(chunk) if chunk.len() < chunk.capacity() => chunk.push(fp),
                            _ => {
                                let mut chunk = self.buffers.take_chunk(chunks.len());
                                chunk.push(fp);
                                chunks.push(chunk);
                            }
                        }
                    }
                }
                out.counts.pixels_hit += 1;
            }
        }
        self.buffers.put_hits(rows.hits);
        out
    }

    /// Corner `(i, j)` of the photo: from the band's rows, else cast alone (`None` outside
    /// the corner grid).
    fn corner(&self, rows: &CornerRows, i: i64, j: i64) -> Option<CornerHit> {
        if let Some(h) = rows.get(i, j) {
            return Some(*h);
        }
        let inside = (0..rows.stride).contains(&i) && (0..=self.h as i64).contains(&j);
        inside.then(|| {
            cast_corner_alone(
                self.scene,
                self.caster,
                &self.rays,
                self.origin,
                i as u32,
                j as u32,
            )
        })
    }

    /// The common case: all four corners hit the same cell.
    #[inline]
    fn full_pixel(&self, q: &[&CornerHit; 4], c: u32, r: u32, edges: &mut EdgeCache) -> Outcome {
        let scene = self.scene;
        let ci = c as usize;
        if self.opts.reject_silhouettes
            && !(q[0].tri == q[1].tri && q[0].tri == q[2].tri && q[0].tri == q[3].tri)
        {
            // Edges left to right and top to bottom: top TL→TR, left TL→BL, right TR→BR,
            // bottom BL→BR; the top and left ones may be known from the neighbours.
            let walk = |a: &CornerHit, b: &CornerHit| {
                a.tri != b.tri && crosses_silhouette(scene, self.origin, a.tri, a.tex, b.tri, b.tex)
            };
            let top = edges.top(ci).unwrap_or_else(|| walk(q[0], q[1]));
            if top || edges.left().unwrap_or_else(|| walk(q[0], q[3])) {
                edges.set(ci, None, None);
                return Outcome::Silhouette;
            }
            let right = walk(q[1], q[2]);
            if right {
                edges.set(ci, Some(true), None);
                return Outcome::Silhouette;
            }
            let bottom = walk(q[3], q[2]);
            edges.set(ci, Some(false), Some(bottom));
            if bottom {
                return Outcome::Silhouette;
            }
        } else {
            // all four corners on one triangle: no edge crosses anything
            edges.set(ci, Some(false), Some(false));
        }
        let corners = [q[0].tex, q[1].tex, q[2].tex, q[3].tex];
        if !footprint_ok(&corners, self.opts.max_area, self.opts.max_extent) {
            return Outcome::Dropped;
        }
        let fp = PixelFootprint {
            cell: scene.cells[q[0].cell as usize].cell,
            pixel: [c, r],
            corners,
            cos_view: (0.25 * (q[0].cos + q[1].cos + q[2].cos + q[3].cos))
                .clamp(f32::MIN_POSITIVE, 1.0),
            distance: 0.25 * (q[0].t + q[1].t + q[2].t + q[3].t),
            reconstructed: 0,
        };
        Outcome::Footprint(fp, self.bucket[q[0].cell as usize])
    }

    fn pixel(&self, rows: &CornerRows, c: u32, r: u32, edges: &mut EdgeCache) -> Outcome {
        let scene = self.scene;
        let (i0, j0) = (c as i64, r as i64);
        // Pixel rows r0..r1 of a band always have their corner rows r and r + 1 cast.
        let s = rows.stride as usize;
        let k = (j0 - rows.j_lo) as usize * s + c as usize;
        let (top, bottom) = (&rows.hits[k..k + 2], &rows.hits[k + s..k + s + 2]);
        let q: [&CornerHit; 4] = [&top[0], &top[1], &bottom[1], &bottom[0]];
        if q.iter().all(|h| h.is_hit() && h.cell == q[0].cell) {
            return self.full_pixel(&q, c, r, edges);
        }
        edges.set(c as usize, None, None);
        // 1. The pixel's cell: most corners, ties to the lowest manifest index.
        let cells: [u32; 4] = q.map(|h| if h.is_hit() { h.cell } else { u32::MAX });
        let mut best: Option<(usize, u32)> = None; // (votes, scene cell)
        for &ck in cells.iter().filter(|&&x| x != u32::MAX) {
            let votes = cells.iter().filter(|&&x| x == ck).count();
            let better = match best {
                None => true,
                Some((bv, bc)) => {
                    votes > bv
                        || (votes == bv && self.bucket[ck as usize] < self.bucket[bc as usize])
                }
            };
            if better {
                best = Some((votes, ck));
            }
        }
        let Some((_, cell)) = best else {
            return Outcome::Miss;
        };
        let present: [bool; 4] = cells.map(|x| x == cell);

        let (mut d_min, mut d_max, mut d_sum, mut cos_sum, mut n) =
            (f32::INFINITY, 0.0f32, 0.0f32, 0.0f32, 0.0f32);
        for k in (0..4).filter(|&k| present[k]) {
            d_min = d_min.min(q[k].t);
            d_max = d_max.max(q[k].t);
            d_sum += q[k].t;
            cos_sum += q[k].cos;
            n += 1.0;
        }
        if self.opts.reject_silhouettes {
            // 2. Depth discontinuity towards another cell.
            let j = self.opts.max_depth_jump;
            if j.is_finite() {
                let spread = 2.0 * (d_max - d_min);
                let (lo, hi) = (d_min * (1.0 - j) - spread, d_max * (1.0 + j) + spread);
                if (0..4).any(|k| q[k].is_hit() && !present[k] && (q[k].t < lo || q[k].t > hi)) {
                    return Outcome::Silhouette;
                }
            }
            // 3. Silhouette edges between the present corners.
            let first = (0..4).find(|&k| present[k]).unwrap_or(0);
            let same_tri = (0..4).all(|k| !present[k] || q[k].tri == q[first].tri);
            if !same_tri {
                let mut ring = [0usize; 4];
                let mut m = 0;
                for k in (0..4).filter(|&k| present[k]) {
                    ring[m] = k;
                    m += 1;
                }
                let pairs = if m == 2 { 1 } else { m };
                for e in 0..pairs {
                    let (a, b) = (q[ring[e]], q[ring[(e + 1) % m]]);
                    if a.tri != b.tri
                        && crosses_silhouette(scene, self.origin, a.tri, a.tex, b.tri, b.tex)
                    {
                        return Outcome::Silhouette;
                    }
                }
            }
        }
        // 4. Reconstruction.
        let mut corners: [Option<[f32; 2]>; 4] =
            [0, 1, 2, 3].map(|k| present[k].then_some(q[k].tex));
        let mut made = 0u8;
        if !present.iter().all(|&p| p) {
            if !self.opts.reconstruct {
                return Outcome::Dropped;
            }
            let grid = |i: i64, j: i64| {
                self.corner(rows, i, j)
                    .filter(|h| h.is_hit() && scene.cell_of(h.tri) == cell)
                    .map(|h| h.tex)
            };
            let Some(m) = reconstruct(&mut corners, i0, j0, grid) else {
                return Outcome::Dropped;
            };
            made = m;
            if self.opts.reject_silhouettes {
                for k in (0..4).filter(|&k| !present[k]) {
                    // Walk from a present neighbour along the footprint (else any present corner).
                    let from = [(k + 1) % 4, (k + 3) % 4, (k + 2) % 4]
                        .into_iter()
                        .find(|&a| present[a])
                        .unwrap_or(first_present(&present));
                    let target = corners[k].unwrap_or(q[from].tex);
                    if crosses_silhouette(
                        scene,
                        self.origin,
                        q[from].tri,
                        q[from].tex,
                        crate::raycast::NO_TRI,
                        target,
                    ) {
                        return Outcome::Silhouette;
                    }
                }
            }
        }
        let corners = corners.map(|c| c.unwrap_or([f32::NAN; 2]));
        // 5. Size guard.
        if !footprint_ok(&corners, self.opts.max_area, self.opts.max_extent) {
            return Outcome::Dropped;
        }
        let fp = PixelFootprint {
            cell: scene.cells[cell as usize].cell,
            pixel: [c, r],
            corners,
            cos_view: (cos_sum / n).clamp(f32::MIN_POSITIVE, 1.0),
            distance: d_sum / n,
            reconstructed: made,
        };
        Outcome::Footprint(fp, self.bucket[cell as usize])
    }
}

fn first_present(present: &[bool; 4]) -> usize {
    (0..4).find(|&k| present[k]).unwrap_or(0)
}

/// `true` if every corner is finite, the quad's area is at most `max_area` and no side or
/// diagonal is longer than `max_extent`.
#[inline(always)]
pub(crate) fn footprint_ok(c: &[[f32; 2]; 4], max_area: f32, max_extent: f32) -> bool {
    // Fast accept, only where the full test accepts with a wide margin: finite corners in a
    // bounding box with sides up to max_extent/2 (every side and diagonal is then at most
    // max_extent/√2) and area up to max_area/2 (the quad's area is at most the box's).
    let sum = c[0][0] + c[1][0] + c[2][0] + c[3][0] + c[0][1] + c[1][1] + c[2][1] + c[3][1];
    // Plain comparisons (w and h only count where `sum`, hence every corner, is finite).
    let side = |k: usize| {
        let (mut lo, mut hi) = (c[0][k], c[0][k]);
        for p in &c[1..] {
            lo = if p[k] < lo { p[k] } else { lo };
            hi = if p[k] > hi { p[k] } else { hi };
        }
        hi - lo
    };
    let (w, h) = (side(0), side(1));
    if sum.is_finite() && w <= 0.5 * max_extent && h <= 0.5 * max_extent && w * h <= 0.5 * max_area
    {
        return true;
    }
    footprint_ok_exact(c, max_area, max_extent)
}

/// [`footprint_ok`] without the fast accept.
#[inline(never)]
fn footprint_ok_exact(c: &[[f32; 2]; 4], max_area: f32, max_extent: f32) -> bool {
    if !c.iter().all(|p| p[0].is_finite() && p[1].is_finite()) {
        return false;
    }
    let mut twice_area = 0.0f32;
    for k in 0..4 {
        let (a, b) = (c[k], c[(k + 1) % 4]);
        twice_area += a[0] * b[1] - b[0] * a[1];
    }
    if !(0.5 * twice_area.abs() <= max_area) {
        return false;
    }
    let len2 = |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
    let m2 = max_extent * max_extent;
    (0..4).all(|k| len2(c[k], c[(k + 1) % 4]) <= m2)
        && len2(c[0], c[2]) <= m2
        && len2(c[1], c[3]) <= m2
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn size_guard() {
        let unit = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(footprint_ok(&unit, 1.0, 1.5));
        assert!(!footprint_ok(&unit, 0.99, 1.5));
        assert!(!footprint_ok(&unit, 1.0, 1.4)); // diagonal √2
        let sliver = [[0.0, 0.0], [100.0, 0.0], [100.0, 0.01], [0.0, 0.01]];
        assert!(!footprint_ok(&sliver, 256.0, 64.0));
        let nan = [[0.0, 0.0], [f32::NAN, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(!footprint_ok(&nan, 256.0, 64.0));
        let inf = [[0.0, 0.0], [f32::INFINITY, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!(!footprint_ok(&inf, 256.0, 64.0));
    }

    #[test]
    fn fast_accept_agrees_with_the_full_size_test() {
        fn full(c: &[[f32; 2]; 4], max_area: f32, max_extent: f32) -> bool {
            let a2: f32 = (0..4)
                .map(|k| c[k][0] * c[(k + 1) % 4][1] - c[(k + 1) % 4][0] * c[k][1])
                .sum();
            let len2 = |a: [f32; 2], b: [f32; 2]| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2);
            c.iter().flatten().all(|v| v.is_finite())
                && 0.5 * a2.abs() <= max_area
                && (0..4).all(|k| len2(c[k], c[(k + 1) % 4]) <= max_extent * max_extent)
                && len2(c[0], c[2]) <= max_extent * max_extent
                && len2(c[1], c[3]) <= max_extent * max_extent
        }
        let mut seed = 99u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 40) as f32 / (1u64 << 24) as f32
        };
        for _ in 0..20000 {
            let (o, s) = ([rnd() * 200.0, rnd() * 200.0], rnd() * rnd() * 40.0);
            let q: [[f32; 2]; 4] = std::array::from_fn(|_| [o[0] + s * rnd(), o[1] + s * rnd()]);
            let (a, e) = (1.0 + rnd() * 30.0, 2.0 + rnd() * 20.0);
            assert_eq!(footprint_ok(&q, a, e), full(&q, a, e), "{q:?} {a} {e}");
        }
    }
}
