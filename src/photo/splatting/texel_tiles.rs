//! A sparse square grid of per-texel sums ([`TexelSums`]) stored in 16 × 16 tiles that are
//! allocated on the first write: a photo usually reaches a fraction of a cell's texture (a
//! third of the texels of a 12-MP photo's finest cells on Engabreen), so the accumulators of
//! large photo textures hold only the tiles some footprint touched.
//!
//! Texels are addressed by their row-major index `t = y · side + x`, as the splatter gives
//! them. Tiles are appended in the order of their first write; two grids written in the same
//! order compare equal (the accumulators write in footprint order, whatever the threads).
//!
//! Tiles live in chunks of [`CHUNK_TILES`] tiles that are never reallocated (a growing grid
//! adds a chunk, it does not copy), and a dropped grid gives its chunks to a process-wide
//! spare list (at most [`SPARE_BYTES_MAX`]) that later grids take from before asking the
//! allocator: a 12-MP photo fills ~0.7 GB of records, and fresh pages from the kernel
//! (zeroed on first touch) and the copies of a doubling vector took about a fifth of the
//! projection's CPU time (docs/projection.md, "Splatting cost"). A tile is zeroed when it is
//! allocated, so what a grid holds never depends on a chunk's past.

/// The per-texel accumulator record (see `crate::photo::splatting::accumulate`); all zero is the empty texel.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexelSums {
    /// `A`: deposited footprint area (texels²).
    pub coverage: f32,
    /// `W`: feathered area.
    pub weight: f32,
    /// `C`: feathered area times colour (working space 0..1).
    pub colour: [f32; 3],
    /// `R`: feathered area times the surface footprint (metres).
    pub footprint: f32,
    /// `G`: feathered area over the view cosine.
    pub grazing: f32,
    /// `O`: feathered area times the occlusion weight (`crate::photo::splatting::occlusion`), so that
    /// `O / W` is the mean occlusion weight of the deposits.
    pub clear: f32,
}

/// Texels per tile side.
pub const TILE: u32 = 16;
const TILE_TEXELS: usize = (TILE * TILE) as usize;
const NONE: u32 = u32::MAX;

/// Tiles per chunk of storage (128 KiB of records).
pub const CHUNK_TILES: usize = 16;
const CHUNK_LEN: usize = CHUNK_TILES * TILE_TEXELS;
/// The most bytes of dropped chunks kept for reuse.
pub const SPARE_BYTES_MAX: usize = 1 << 30;
const SPARE_MAX: usize = SPARE_BYTES_MAX / (CHUNK_LEN * std::mem::size_of::<TexelSums>());

/// Chunks given back by dropped grids, for the next ones.
static SPARE: std::sync::Mutex<Vec<Box<[TexelSums]>>> = std::sync::Mutex::new(Vec::new());

/// A chunk from the spare list, else a new one (contents unspecified: tiles are zeroed as
/// they are allocated).
fn take_chunk() -> Box<[TexelSums]> {
    let spare = SPARE.lock().ok().and_then(|mut s| s.pop());
    spare.unwrap_or_else(|| vec![ZERO; CHUNK_LEN].into_boxed_slice())
}

/// A `side × side` grid of [`TexelSums`], zero where never written.
#[derive(Clone, Debug)]
pub struct TexelTiles {
    side: u32,
    tiles_x: u32,
    /// log2 of `side` when it is a power of two (index split by shifts).
    shift: Option<u32>,
    /// Per tile (row-major over tiles): its number among the allocated tiles, or `NONE`.
    index: Vec<u32>,
    /// Allocated tiles.
    tiles: u32,
    /// The storage: tile `k` is records `(k % CHUNK_TILES) · TILE²..` of chunk
    /// `k / CHUNK_TILES`, row-major within the tile.
    chunks: Vec<Box<[TexelSums]>>,
}

impl Drop for TexelTiles {
    fn drop(&mut self) {
        if self.chunks.is_empty() {
            return;
        }
        if let Ok(mut spare) = SPARE.lock() {
            let room = SPARE_MAX.saturating_sub(spare.len());
            let n = self.chunks.len().min(room);
            spare.extend(self.chunks.drain(..n));
        }
    }
}

impl PartialEq for TexelTiles {
    /// Same size, same tiles allocated in the same order, same records in them.
    fn eq(&self, other: &Self) -> bool {
        self.side == other.side
            && self.index == other.index
            && (0..self.tiles as usize).all(|k| self.tile(k) == other.tile(k))
    }
}

const ZERO: TexelSums = TexelSums {
    coverage: 0.0,
    weight: 0.0,
    colour: [0.0; 3],
    footprint: 0.0,
    grazing: 0.0,
    clear: 0.0,
};

impl TexelTiles {
    /// An empty grid of `side × side` texels.
    pub fn new(side: u32) -> TexelTiles {
        let tiles_x = side.div_ceil(TILE);
        TexelTiles {
            side,
            tiles_x,
            shift: side.is_power_of_two().then(|| side.trailing_zeros()),
            index: vec![NONE; tiles_x as usize * tiles_x as usize],
            tiles: 0,
            chunks: Vec::new(),
        }
    }

    /// Side of the grid in texels.
    pub fn side(&self) -> u32 {
        self.side
    }

    /// Texels of the grid (`side²`).
    pub fn len(&self) -> usize {
        self.side as usize * self.side as usize
    }

    /// Whether the grid has no texels.
    pub fn is_empty(&self) -> bool {
        self.side == 0
    }

    /// Texels held by allocated tiles (a multiple of `TILE²`).
    pub fn allocated(&self) -> usize {
        self.tiles as usize * TILE_TEXELS
    }

    /// The records of allocated tile `k`.
    #[inline]
    fn tile(&self, k: usize) -> &[TexelSums] {
        &self.chunks[k / CHUNK_TILES][(k % CHUNK_TILES) * TILE_TEXELS..][..TILE_TEXELS]
    }

    /// The records of allocated tile `k`, for writing.
    #[inline]
    fn tile_mut(&mut self, k: usize) -> &mut [TexelSums] {
        &mut self.chunks[k / CHUNK_TILES][(k % CHUNK_TILES) * TILE_TEXELS..][..TILE_TEXELS]
    }

    /// Allocates a zeroed tile and returns its number.
    #[cold]
    fn new_tile(&mut self) -> u32 {
        let k = self.tiles;
        if k as usize == self.chunks.len() * CHUNK_TILES {
            self.chunks.push(take_chunk());
        }
        self.tiles += 1;
        self.tile_mut(k as usize).fill(ZERO);
        k
    }

    /// The tile number and the position within the tile of texel `t` (`t < len()`).
    #[inline]
    fn locate(&self, t: usize) -> (usize, usize) {
        let (x, y) = match self.shift {
            Some(s) => (t & ((1usize << s) - 1), t >> s),
            None => (t % self.side as usize, t / self.side as usize),
        };
        let tile = (y / TILE as usize) * self.tiles_x as usize + x / TILE as usize;
        (
            tile,
            (y % TILE as usize) * TILE as usize + x % TILE as usize,
        )
    }

    /// The sums of texel `t` (zero if never written or outside the grid).
    #[inline]
    pub fn get(&self, t: usize) -> &TexelSums {
        if t >= self.len() {
            return &ZERO;
        }
        let (tile, within) = self.locate(t);
        match self.index[tile] {
            NONE => &ZERO,
            k => &self.tile(k as usize)[within],
        }
    }

    /// The allocated tile holding texel `t` (`t < len()`; allocated, zeroed, on first use)
    /// and `t`'s position within it.
    #[inline]
    fn tile_of(&mut self, t: usize) -> (usize, usize) {
        let (tile, within) = self.locate(t);
        let k = match self.index[tile] {
            NONE => {
                let k = self.new_tile();
                self.index[tile] = k;
                k
            }
            k => k,
        };
        (k as usize, within)
    }

    /// The sums of texel `t` for writing, allocating its tile (zeroed) on first use; `None`
    /// outside the grid.
    #[inline]
    pub fn get_mut(&mut self, t: usize) -> Option<&mut TexelSums> {
        if t >= self.len() {
            return None;
        }
        let (k, within) = self.tile_of(t);
        Some(&mut self.tile_mut(k)[within])
    }

    /// How many of the texels `t, t + 1, …, t + len − 1` (one texel row) lie in `t`'s tile
    /// and the grid: the length of [`TexelTiles::run_mut`]'s slice (0 outside the grid).
    #[inline]
    pub fn run_len(&self, t: usize, len: usize) -> usize {
        if t >= self.len() {
            return 0;
        }
        let x = match self.shift {
            Some(s) => t & ((1usize << s) - 1),
            None => t % self.side as usize,
        };
        let tile_end = (x / TILE as usize + 1) * TILE as usize;
        len.min(tile_end.min(self.side as usize) - x)
    }

    /// The records of texels `t .. t + n` for writing, `n` at most [`TexelTiles::run_len`]
    /// (`t`'s tile allocated, zeroed, on first use); `None` outside the grid or for an empty
    /// or longer run.
    #[inline]
    pub fn run_mut(&mut self, t: usize, n: usize) -> Option<&mut [TexelSums]> {
        if n == 0 || n > self.run_len(t, n) {
            return None;
        }
        let (k, within) = self.tile_of(t);
        Some(&mut self.tile_mut(k)[within..within + n])
    }

    /// Per block of the row-major grid of `⌈side / block⌉²` blocks of `block` texels: whether
    /// an allocated tile overlaps it.
    pub fn touched_blocks(&self, block: u32) -> Vec<bool> {
        let block = block.max(1) as usize;
        let n = self.side as usize;
        let g = n.div_ceil(block);
        let mut out = vec![false; g * g];
        for (tile, &k) in self.index.iter().enumerate() {
            if k == NONE {
                continue;
            }
            let t = TILE as usize;
            let (x0, y0) = (
                (tile % self.tiles_x as usize) * t,
                (tile / self.tiles_x as usize) * t,
            );
            let (x1, y1) = ((x0 + t).min(n), (y0 + t).min(n));
            for by in y0 / block..=(y1 - 1) / block {
                for bx in x0 / block..=(x1 - 1) / block {
                    out[by * g + bx] = true;
                }
            }
        }
        out
    }

    /// Calls `f(t, sums)` for every texel of every allocated tile (texels outside the grid's
    /// last partial tiles skipped), tiles in row-major tile order, texels row-major within
    /// a tile.
    pub fn for_each_mut(&mut self, mut f: impl FnMut(usize, &mut TexelSums)) {
        let walk = TileWalk {
            side: self.side as usize,
            tiles_x: self.tiles_x as usize,
        };
        for tile in 0..self.index.len() {
            let k = self.index[tile];
            if k != NONE {
                let block = self.tile_mut(k as usize);
                walk.texels(tile, |w, t| f(t, &mut block[w]));
            }
        }
    }

    /// [`TexelTiles::for_each_mut`] without writing.
    pub fn for_each(&self, mut f: impl FnMut(usize, &TexelSums)) {
        let walk = TileWalk {
            side: self.side as usize,
            tiles_x: self.tiles_x as usize,
        };
        for (tile, &k) in self.index.iter().enumerate() {
            if k != NONE {
                let block = self.tile(k as usize);
                walk.texels(tile, |w, t| f(t, &block[w]));
            }
        }
    }
}

/// The grid's texel indices of a tile's records.
struct TileWalk {
    side: usize,
    tiles_x: usize,
}

impl TileWalk {
    /// Calls `f(w, t)` for each record `w` of tile `tile` that lies in the grid, with its
    /// row-major texel index `t`.
    #[inline]
    fn texels(&self, tile: usize, mut f: impl FnMut(usize, usize)) {
        let (x0, y0) = (
            (tile % self.tiles_x) * TILE as usize,
            (tile / self.tiles_x) * TILE as usize,
        );
        for w in 0..TILE_TEXELS {
            let (x, y) = (x0 + w % TILE as usize, y0 + w / TILE as usize);
            if x < self.side && y < self.side {
                f(w, y * self.side + x);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_land_where_read_and_only_touched_tiles_exist() {
        for side in [1u32, 15, 16, 37, 64] {
            let mut g = TexelTiles::new(side);
            let n = g.len();
            let picks: Vec<usize> = (0..n).filter(|t| t % 7 == 3).collect();
            for &t in &picks {
                g.get_mut(t).unwrap().weight += t as f32;
            }
            assert!(g.get_mut(n).is_none());
            for t in 0..n {
                let want = if t % 7 == 3 { t as f32 } else { 0.0 };
                assert_eq!(g.get(t).weight, want, "side {side} texel {t}");
            }
            assert_eq!(g.get(n + 5).weight, 0.0);
            let mut seen = Vec::new();
            g.for_each(|t, s| {
                if s.weight > 0.0 || t % 7 == 3 {
                    seen.push(t);
                }
            });
            seen.sort_unstable();
            assert_eq!(seen, picks, "side {side}");
        }
        // one corner write allocates one tile
        let mut g = TexelTiles::new(1024);
        g.get_mut(1024 * 1024 - 1).unwrap().coverage = 1.0;
        assert_eq!(g.allocated(), (TILE * TILE) as usize);
        // ... in the last block of 64 texels
        let b = g.touched_blocks(64);
        assert_eq!(b.len(), 256);
        assert_eq!(b.iter().position(|&t| t), Some(255));
        assert_eq!(b.iter().filter(|&&t| t).count(), 1);
        // a tile (texels 32..48 each way) across the lines of blocks of 40 texels: 4 blocks
        let mut g = TexelTiles::new(100);
        g.get_mut(40 * 100 + 40).unwrap().coverage = 1.0;
        let b = g.touched_blocks(40);
        let on: Vec<usize> = (0..9).filter(|&i| b[i]).collect();
        assert_eq!(on, vec![0, 1, 3, 4]);
    }

    #[test]
    fn runs_stop_at_tile_and_grid_ends_and_write_where_single_texels_do() {
        for side in [5u32, 16, 37, 64] {
            let n = side as usize;
            let (mut by_run, mut single) = (TexelTiles::new(side), TexelTiles::new(side));
            for y in (0..n).step_by(3) {
                let mut x = y % 7;
                while x < n {
                    let t = y * n + x;
                    let len = side.div_ceil(3) as usize;
                    let k = by_run.run_len(t, len);
                    // to the tile's or the grid's row end, never beyond the run
                    assert!(k >= 1 && k <= len, "side {side} at ({x}, {y})");
                    assert_eq!(k, len.min((x / 16 + 1) * 16 - x).min(n - x));
                    for (i, s) in by_run.run_mut(t, k).unwrap().iter_mut().enumerate() {
                        s.weight += (t + i) as f32;
                    }
                    for i in 0..k {
                        single.get_mut(t + i).unwrap().weight += (t + i) as f32;
                    }
                    x += k + 1;
                }
            }
            assert_eq!(by_run, single, "side {side}");
            assert_eq!(by_run.run_len(n * n, 4), 0);
            assert!(by_run.run_mut(n * n, 1).is_none());
            assert!(by_run.run_mut(0, 0).is_none());
            assert!(by_run.run_mut(n - 1, 2).is_none(), "past the row's end");
        }
    }

    #[test]
    fn reused_chunks_start_zero_and_grids_compare_by_content() {
        // fill many tiles with non-zero records and drop the grid: its chunks go spare
        let mut g = TexelTiles::new(256);
        for t in 0..g.len() {
            let s = g.get_mut(t).unwrap();
            s.coverage = 1.0 + t as f32;
            s.colour = [2.0; 3];
        }
        assert_eq!(g.allocated(), 256 * 256);
        drop(g);
        // new grids (likely on those chunks) read zero wherever they were not written
        let mut a = TexelTiles::new(256);
        let mut b = TexelTiles::new(256);
        for t in [5usize, 40_000, 65_535] {
            a.get_mut(t).unwrap().weight = 3.0;
            b.get_mut(t).unwrap().weight = 3.0;
        }
        a.for_each(|t, s| {
            let want = if [5, 40_000, 65_535].contains(&t) {
                3.0
            } else {
                0.0
            };
            assert_eq!(
                (s.weight, s.coverage, s.colour),
                (want, 0.0, [0.0; 3]),
                "texel {t}"
            );
        });
        assert_eq!(a, b);
        assert_eq!(a.clone(), b);
        b.get_mut(6).unwrap().clear = 1.0;
        assert_ne!(a, b);
        // more tiles than one chunk holds
        let mut c = TexelTiles::new(1024);
        for t in (0..c.len()).step_by(16) {
            c.get_mut(t).unwrap().footprint = t as f32;
        }
        assert_eq!(c.allocated(), c.len());
        for t in (0..c.len()).step_by(16) {
            assert_eq!(c.get(t).footprint, t as f32);
            assert_eq!(c.get(t + 1).footprint, 0.0);
        }
    }
}
