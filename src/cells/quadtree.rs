//! Quadtree addressing over a DEM grid.
//!
//! Rule (documented in docs/formats.md): the root cell spans `S * 2^(levels-1)` sample
//! intervals per side, anchored at the north-west sample, i.e. the DEM is virtually padded
//! to `S * 2^(levels-1) + 1` samples per side (a power of two times S, plus one). Padding
//! samples do not exist: every cell is **clipped** to the DEM's data rectangle, and cells
//! that lie entirely in the padding are not created. Level 0 is the root (coarsest); the
//! finest level `levels - 1` has cells of `S` intervals, and a cell of level `l` uses every
//! `stride(l) = 2^(levels-1-l)`-th sample for its grid.

use serde::{Deserialize, Serialize};

/// Identifies one cell: its level (0 = root) and index (x east, y south) within the level.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
pub struct CellKey {
    /// Quadtree level, 0 = root.
    pub level: u8,
    /// Column of the cell within its level (west to east).
    pub x: u32,
    /// Row of the cell within its level (north to south).
    pub y: u32,
}

impl CellKey {
    /// The cell's id string, `"{level}-{x}-{y}"`, as used in the store and on the CLI.
    pub fn id(&self) -> String {
        format!("{}-{}-{}", self.level, self.x, self.y)
    }

    /// Parses an id of the form `"{level}-{x}-{y}"`.
    pub fn parse(id: &str) -> Option<CellKey> {
        let mut it = id.trim().split('-');
        let level = it.next()?.parse().ok()?;
        let x = it.next()?.parse().ok()?;
        let y = it.next()?.parse().ok()?;
        it.next().is_none().then_some(CellKey { level, x, y })
    }

    /// The four children (NW, NE, SW, SE) one level finer.
    pub fn children(&self) -> [CellKey; 4] {
        let (l, x, y) = (self.level + 1, self.x * 2, self.y * 2);
        [
            CellKey { level: l, x, y },
            CellKey {
                level: l,
                x: x + 1,
                y,
            },
            CellKey {
                level: l,
                x,
                y: y + 1,
            },
            CellKey {
                level: l,
                x: x + 1,
                y: y + 1,
            },
        ]
    }

    /// The parent cell, or `None` for the root.
    pub fn parent(&self) -> Option<CellKey> {
        (self.level > 0).then(|| CellKey {
            level: self.level - 1,
            x: self.x / 2,
            y: self.y / 2,
        })
    }
}

/// An inclusive rectangle of full-resolution DEM sample indices.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct SampleRect {
    /// First column.
    pub c0: u32,
    /// First row.
    pub r0: u32,
    /// Last column (inclusive), > c0.
    pub c1: u32,
    /// Last row (inclusive), > r0.
    pub r1: u32,
}

impl SampleRect {
    /// Number of samples covered.
    pub fn sample_count(&self) -> u64 {
        (self.c1 - self.c0 + 1) as u64 * (self.r1 - self.r0 + 1) as u64
    }
}

/// The quadtree's shape for one DEM.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Quadtree {
    /// DEM width in samples.
    pub dem_width: u32,
    /// DEM height in samples.
    pub dem_height: u32,
    /// Sample intervals per side of a finest-level cell (S), a power of two >= 2.
    pub finest_intervals: u32,
    /// Number of levels (>= 1); level `levels - 1` is the finest.
    pub levels: u8,
}

impl Quadtree {
    /// The smallest quadtree whose root covers the whole DEM with finest cells of
    /// `finest_intervals` intervals. `finest_intervals` must be a power of two >= 2 and the
    /// DEM at least 2x2 (checked by the caller; see [`crate::cells`]).
    pub fn new(dem_width: u32, dem_height: u32, finest_intervals: u32) -> Quadtree {
        let span = dem_width.max(dem_height).saturating_sub(1).max(1) as u64;
        let mut levels = 1u8;
        while (finest_intervals as u64) << (levels - 1) < span {
            levels += 1;
        }
        Quadtree {
            dem_width,
            dem_height,
            finest_intervals,
            levels,
        }
    }

    /// The finest level index.
    pub fn finest_level(&self) -> u8 {
        self.levels - 1
    }

    /// Sample intervals per side of a cell at `level` (nominal, before clipping).
    pub fn cell_intervals(&self, level: u8) -> u32 {
        self.finest_intervals << (self.finest_level() - level)
    }

    /// Grid stride of `level`: a cell of this level uses every stride-th sample.
    pub fn stride(&self, level: u8) -> u32 {
        1 << (self.finest_level() - level)
    }

    /// Number of cells per side at `level` in the padded square.
    pub fn cells_per_side(&self, level: u8) -> u32 {
        1 << level
    }

    /// Nominal (unclipped) north-west sample `(col, row)` of the cell and its side in intervals.
    pub fn nominal(&self, key: CellKey) -> (u32, u32, u32) {
        let n = self.cell_intervals(key.level);
        (key.x * n, key.y * n, n)
    }

    /// The cell's samples clipped to the DEM, or `None` if the cell has no area inside it.
    pub fn clipped(&self, key: CellKey) -> Option<SampleRect> {
        let (c0, r0, n) = self.nominal(key);
        let c1 = (c0 + n).min(self.dem_width - 1);
        let r1 = (r0 + n).min(self.dem_height - 1);
        (c0 < c1 && r0 < r1).then_some(SampleRect { c0, r0, c1, r1 })
    }

    /// Cells of `level` that intersect the DEM with positive area, in row-major order.
    pub fn cells(&self, level: u8) -> Vec<CellKey> {
        let n = self.cells_per_side(level);
        let mut out = Vec::new();
        for y in 0..n {
            for x in 0..n {
                let k = CellKey { level, x, y };
                if self.clipped(k).is_some() {
                    out.push(k);
                }
            }
        }
        out
    }

    /// All cells of all levels, root first.
    pub fn all_cells(&self) -> Vec<CellKey> {
        (0..self.levels).flat_map(|l| self.cells(l)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn covers_dem_and_clips() {
        let q = Quadtree::new(507, 590, 64);
        assert_eq!(q.levels, 5); // 64 * 16 = 1024 >= 589
        assert_eq!(q.cell_intervals(0), 1024);
        let fin = q.cells(q.finest_level());
        // 506/64 -> 8 columns, 589/64 -> 10 rows (the last ones clipped)
        assert_eq!(fin.len(), 8 * 10);
        let last = q
            .clipped(CellKey {
                level: 4,
                x: 7,
                y: 9,
            })
            .unwrap();
        assert_eq!((last.c1, last.r1), (506, 589));
        assert!(
            q.clipped(CellKey {
                level: 4,
                x: 8,
                y: 0
            })
            .is_none()
        );
        assert_eq!(
            CellKey::parse("4-7-9"),
            Some(CellKey {
                level: 4,
                x: 7,
                y: 9
            })
        );
        assert_eq!(CellKey::parse("4-7"), None);
        for k in q.cells(2) {
            for c in k.children() {
                assert_eq!(c.parent(), Some(k));
            }
        }
    }

    #[test]
    fn tiny_dem_has_one_level() {
        let q = Quadtree::new(3, 2, 64);
        assert_eq!(q.levels, 1);
        assert_eq!(q.cells(0).len(), 1);
    }
}
