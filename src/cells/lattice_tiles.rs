//! A compact, cache-friendly copy of the heights on one sample lattice.
//!
//! The lattice samples (every stride-th sample from the lattice origin) are stored in 4x4
//! tiles of one 64-byte cache line each, so scanning a small triangle touches few cache
//! lines whatever the DEM width.

use super::raster::Lattice;

/// Sixteen heights, 4 rows of 4, one cache line.
#[derive(Clone, Copy)]
#[repr(align(64))]
pub(crate) struct Tile(pub [f32; 16]);

/// Heights of a [`Lattice`]'s samples from its origin up to `(c_hi, r_hi)`, tiled 4x4.
pub(crate) struct LatticeTiles {
    tiles: Vec<Tile>,
    tiles_x: usize,
    /// Stored lattice indices are `0..ni` x `0..nj`.
    ni: usize,
    nj: usize,
    /// The lattice (origin, stride and bounds) these heights were taken from.
    pub lat: Lattice,
}

impl LatticeTiles {
    /// Copies the lattice samples of a row-major height grid of `width` columns, from the
    /// lattice origin up to `(store_c_hi, store_c_hi)` (which must lie inside the grid and
    /// cover `lat`'s bounds).
    pub fn new(
        heights: &[f32],
        width: usize,
        lat: Lattice,
        store_c_hi: i64,
        store_r_hi: i64,
    ) -> LatticeTiles {
        let s = lat.stride;
        let ni = ((store_c_hi.max(lat.c_hi) - lat.origin_c).max(0) / s + 1) as usize;
        let nj = ((store_r_hi.max(lat.r_hi) - lat.origin_r).max(0) / s + 1) as usize;
        let (tiles_x, tiles_y) = (ni.div_ceil(4), nj.div_ceil(4));
        let mut tiles = vec![Tile([0.0; 16]); tiles_x * tiles_y];
        for j in 0..nj {
            let row = (lat.origin_r + j as i64 * s) as usize * width;
            let (tj, rj) = (j >> 2, (j & 3) * 4);
            let out = &mut tiles[tj * tiles_x..(tj + 1) * tiles_x];
            if s == 1 {
                // the row's samples are contiguous: four at a time into each tile's row
                // (whole fours as fixed-size copies, not a `memmove` call each)
                let src = &heights[row + lat.origin_c as usize..][..ni];
                let fours = src.chunks_exact(4);
                let rest = fours.remainder();
                for (tile, four) in out.iter_mut().zip(fours) {
                    let dst = &mut tile.0[rj..rj + 4];
                    // kept as an element loop (see above) rather than `copy_from_slice`
                    #[allow(clippy::manual_memcpy)]
                    for k in 0..4 {
                        dst[k] = four[k];
                    }
                }
                if let Some(tile) = out.get_mut(ni / 4).filter(|_| !rest.is_empty()) {
                    tile.0[rj..rj + rest.len()].copy_from_slice(rest);
                }
            } else {
                for i in 0..ni {
                    let col = (lat.origin_c + i as i64 * s) as usize;
                    out[i >> 2].0[rj + (i & 3)] = heights[row + col];
                }
            }
        }
        LatticeTiles {
            tiles,
            tiles_x,
            ni,
            nj,
            lat,
        }
    }

    /// Height of sample `(col, row)` if it is a stored lattice sample.
    #[inline]
    pub fn get(&self, col: i64, row: i64) -> Option<f32> {
        let s = self.lat.stride;
        let (dc, dr) = (col - self.lat.origin_c, row - self.lat.origin_r);
        if dc < 0 || dr < 0 {
            return None;
        }
        let (i, j) = if s == 1 {
            (dc as usize, dr as usize)
        } else if dc % s != 0 || dr % s != 0 {
            return None;
        } else {
            ((dc / s) as usize, (dr / s) as usize)
        };
        (i < self.ni && j < self.nj)
            .then(|| self.tiles[(j >> 2) * self.tiles_x + (i >> 2)].0[(j & 3) * 4 + (i & 3)])
    }

    /// Lattice row `j`'s tiles and the offset of the row within each tile: columns
    /// `4k..4k + 4` are `tiles[k].0[offset..offset + 4]` (beyond the stored ones, 0).
    #[cfg(target_arch = "x86_64")]
    #[inline(always)]
    pub fn row_tiles(&self, j: usize) -> (&[Tile], usize) {
        let tj = j >> 2;
        (
            &self.tiles[tj * self.tiles_x..(tj + 1) * self.tiles_x],
            (j & 3) * 4,
        )
    }

    /// Calls `f(i, h)` for the lattice columns `i0..=i1` (lattice indices) of lattice row
    /// `j`, in increasing order, with their heights.
    #[inline]
    pub fn for_row(&self, j: usize, i0: usize, i1: usize, mut f: impl FnMut(usize, f32)) {
        let (tj, rj) = (j >> 2, (j & 3) * 4);
        let row = &self.tiles[tj * self.tiles_x..(tj + 1) * self.tiles_x];
        let mut i = i0;
        while i <= i1 {
            let end = i1.min(i | 3);
            let t = &row[i >> 2].0[rj..rj + 4];
            for ii in i..=end {
                f(ii, t[ii & 3]);
            }
            i = end + 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tiles_return_the_lattice_heights() {
        let (w, h) = (23usize, 17usize);
        let heights: Vec<f32> = (0..w * h).map(|i| i as f32 * 0.5).collect();
        for stride in [1i64, 2, 3, 4] {
            let lat = Lattice {
                origin_c: 2,
                origin_r: 1,
                stride,
                c_lo: 3,
                c_hi: 20,
                r_lo: 2,
                r_hi: 14,
            };
            let t = LatticeTiles::new(&heights, w, lat, 22, 16);
            for r in 0..h as i64 {
                for c in 0..w as i64 {
                    let on = c >= 2 && r >= 1 && (c - 2) % stride == 0 && (r - 1) % stride == 0;
                    let want = on.then(|| heights[r as usize * w + c as usize]);
                    assert_eq!(t.get(c, r), want, "stride {stride} ({c},{r})");
                }
            }
            let mut got = Vec::new();
            t.for_row(3, 1, 5, |i, v| got.push((i, v)));
            let row = (1 + 3 * stride) as usize;
            let want: Vec<_> = (1..=5)
                .map(|i| (i, heights[row * w + (2 + i as i64 * stride) as usize]))
                .collect();
            assert_eq!(got, want);
        }
    }
}
