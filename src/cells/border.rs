//! Crack-free cell borders: each side of each cell of a level is simplified once.
//!
//! A cell side is the polyline of DEM samples along one edge of the cell's clipped
//! rectangle. It is simplified by 1D greedy insertion (equivalent to Douglas-Peucker with
//! vertical distance): first over the level's lattice (every stride-th sample from the
//! side's start, plus its end), then every full-resolution sample is checked and insertion
//! continues until all are within epsilon. Both cells sharing a side use the same kept
//! samples, so their TINs meet along identical edges.

use rayon::prelude::*;

use super::{CellKey, Quadtree, SampleRect};
use crate::dem::Dem;
use crate::error::{Error, Result};

/// Kept sample positions of one straight run of samples `p0..=p1` whose heights are `h(p)`.
/// Always keeps both ends; every sample is within `epsilon` (vertical) of the linear
/// interpolation between its kept neighbours. Sorted, unique, deterministic.
pub(crate) fn simplify_run(
    h: impl Fn(u32) -> f64,
    p0: u32,
    p1: u32,
    stride: u32,
    epsilon: f64,
) -> Vec<u32> {
    let mut kept = vec![p0];
    if p1 > p0 {
        kept.push(p1);
    }
    let stride = stride.max(1);
    if stride > 1 {
        refine(&h, p0, p1, p0, stride, epsilon, &mut kept);
        kept.sort_unstable();
    }
    let coarse = kept.clone();
    for w in coarse.windows(2) {
        refine(&h, w[0], w[1], w[0], 1, epsilon, &mut kept);
    }
    kept.sort_unstable();
    kept.dedup();
    kept
}

/// Inserts into `out` the samples needed between `a` and `b` (exclusive) so that every
/// candidate (positions `origin + k*step`) is within `epsilon` of the polyline.
fn refine(
    h: &impl Fn(u32) -> f64,
    a: u32,
    b: u32,
    origin: u32,
    step: u32,
    epsilon: f64,
    out: &mut Vec<u32>,
) {
    let mut stack = vec![(a, b)];
    while let Some((a, b)) = stack.pop() {
        if b - a < 2 {
            continue;
        }
        let (ha, hb) = (h(a), h(b));
        let span = (b - a) as f64;
        let first = origin + (a + 1 - origin).div_ceil(step) * step;
        let mut best = (epsilon, u32::MAX);
        let mut p = first;
        while p < b {
            let z = ha + (hb - ha) * ((p - a) as f64 / span);
            let e = (h(p) - z).abs();
            if e > best.0 {
                best = (e, p);
            }
            p += step;
        }
        if best.1 != u32::MAX {
            out.push(best.1);
            stack.push((best.1, b));
            stack.push((a, best.1));
        }
    }
}

/// Largest vertical distance from the samples `p0..=p1` to the polyline through the kept
/// positions `kept` (sorted, containing `p0` and `p1`).
pub(crate) fn run_error(h: impl Fn(u32) -> f64, kept: &[u32]) -> f64 {
    let mut worst = 0.0f64;
    for w in kept.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (ha, hb) = (h(a), h(b));
        let span = (b - a) as f64;
        for p in a..=b {
            let z = ha + (hb - ha) * ((p - a) as f64 / span);
            worst = worst.max((h(p) - z).abs());
        }
    }
    worst
}

/// The four sides of `rect` as runs: (fixed coordinate, is_row, start, end).
fn sides(rect: SampleRect) -> [(u32, bool, u32, u32); 4] {
    [
        (rect.r0, true, rect.c0, rect.c1),  // north: row r0
        (rect.c1, false, rect.r0, rect.r1), // east: column c1
        (rect.r1, true, rect.c0, rect.c1),  // south: row r1
        (rect.c0, false, rect.r0, rect.r1), // west: column c0
    ]
}

fn side_height(dem: &Dem, fixed: u32, is_row: bool) -> impl Fn(u32) -> f64 + '_ {
    move |p| {
        if is_row {
            dem.at(fixed as usize, p as usize) as f64
        } else {
            dem.at(p as usize, fixed as usize) as f64
        }
    }
}

/// Assembles the border vertex list (clockwise in image order from the north-west corner:
/// north W->E, east N->S, south E->W, west S->N; each corner once) from the kept positions
/// of the four sides.
fn assemble(
    rect: SampleRect,
    north: &[u32],
    east: &[u32],
    south: &[u32],
    west: &[u32],
) -> Vec<[u32; 2]> {
    let mut out = Vec::with_capacity(north.len() + east.len() + south.len() + west.len());
    out.extend(north.iter().map(|&c| [c, rect.r0]));
    out.extend(east.iter().skip(1).map(|&r| [rect.c1, r]));
    out.extend(south.iter().rev().skip(1).map(|&c| [c, rect.r1]));
    let n = west.len();
    out.extend(
        west.iter()
            .rev()
            .skip(1)
            .take(n.saturating_sub(2))
            .map(|&r| [rect.c0, r]),
    );
    out
}

/// Simplifies the whole boundary of `rect` on its own (no neighbours): the border a
/// single TIN over `rect` needs. Same order and guarantees as [`LevelBorders::cell_border`].
pub fn simplify_rect_border(
    dem: &Dem,
    rect: SampleRect,
    stride: u32,
    epsilon: f64,
) -> Vec<[u32; 2]> {
    let runs: Vec<Vec<u32>> = sides(rect)
        .iter()
        .map(|&(fixed, is_row, a, b)| {
            simplify_run(side_height(dem, fixed, is_row), a, b, stride, epsilon)
        })
        .collect();
    assemble(rect, &runs[0], &runs[1], &runs[2], &runs[3])
}

/// Largest vertical distance from any sample on the boundary of `rect` to the polyline
/// through the border vertices of `border` that lie on that boundary (corners included).
pub(crate) fn border_error(dem: &Dem, rect: SampleRect, border: &[[u32; 2]]) -> f64 {
    let mut worst = 0.0f64;
    for (fixed, is_row, a, b) in sides(rect) {
        let mut kept: Vec<u32> = border
            .iter()
            .filter(|v| if is_row { v[1] == fixed } else { v[0] == fixed })
            .map(|v| if is_row { v[0] } else { v[1] })
            .chain([a, b])
            .collect();
        kept.sort_unstable();
        kept.dedup();
        worst = worst.max(run_error(side_height(dem, fixed, is_row), &kept));
    }
    worst
}

/// The simplified cell sides of one quadtree level. Every side shared by two cells is
/// stored once, so neighbouring cells get identical vertices along it (crack-free).
#[derive(Clone, Debug)]
pub struct LevelBorders {
    tree: Quadtree,
    level: u8,
    /// Cells per side with positive area in x and y.
    nx: u32,
    ny: u32,
    /// Horizontal sides, index `j * nx + x` for line `j in 0..=ny`: kept columns.
    h_sides: Vec<Vec<u32>>,
    /// Vertical sides, index `y * (nx + 1) + i` for line `i in 0..=nx`: kept rows.
    v_sides: Vec<Vec<u32>>,
}

impl LevelBorders {
    /// Simplifies every cell side of `level` to within `epsilon` (height units) of every
    /// full-resolution DEM sample on it, using the level's stride for the first pass.
    /// Errors if the tree does not match the DEM, the level does not exist or `epsilon` is
    /// negative or not finite. Deterministic whatever the thread count.
    pub fn compute(dem: &Dem, tree: &Quadtree, level: u8, epsilon: f64) -> Result<LevelBorders> {
        check_tree(dem, tree, level)?;
        check_epsilon(epsilon)?;
        let n = tree.cell_intervals(level);
        let (w, h) = (tree.dem_width, tree.dem_height);
        let nx = (w - 1).div_ceil(n);
        let ny = (h - 1).div_ceil(n);
        let stride = tree.stride(level);
        let col_range = |x: u32| (x * n, ((x + 1) * n).min(w - 1));
        let row_range = |y: u32| (y * n, ((y + 1) * n).min(h - 1));
        let h_sides: Vec<Vec<u32>> = (0..(ny + 1) * nx)
            .into_par_iter()
            .map(|idx| {
                let (j, x) = (idx / nx, idx % nx);
                let row = (j * n).min(h - 1);
                let (a, b) = col_range(x);
                simplify_run(side_height(dem, row, true), a, b, stride, epsilon)
            })
            .collect();
        let v_sides: Vec<Vec<u32>> = (0..ny * (nx + 1))
            .into_par_iter()
            .map(|idx| {
                let (y, i) = (idx / (nx + 1), idx % (nx + 1));
                let col = (i * n).min(w - 1);
                let (a, b) = row_range(y);
                simplify_run(side_height(dem, col, false), a, b, stride, epsilon)
            })
            .collect();
        Ok(LevelBorders {
            tree: *tree,
            level,
            nx,
            ny,
            h_sides,
            v_sides,
        })
    }

    /// The level these borders belong to.
    pub fn level(&self) -> u8 {
        self.level
    }

    /// Border vertices `[col, row]` of a cell of this level: all kept samples on its clipped
    /// rectangle's boundary, the four corners always included, clockwise in image order
    /// (north W->E, east N->S, south E->W, west S->N) starting at the north-west corner.
    /// Empty if the key is not a cell of this level.
    pub fn cell_border(&self, key: CellKey) -> Vec<[u32; 2]> {
        if key.level != self.level || key.x >= self.nx || key.y >= self.ny {
            return Vec::new();
        }
        let Some(rect) = self.tree.clipped(key) else {
            return Vec::new();
        };
        let (x, y, nx) = (key.x, key.y, self.nx);
        let north = &self.h_sides[(y * nx + x) as usize];
        let south = &self.h_sides[((y + 1) * nx + x) as usize];
        let west = &self.v_sides[(y * (nx + 1) + x) as usize];
        let east = &self.v_sides[(y * (nx + 1) + x + 1) as usize];
        assemble(rect, north, east, south, west)
    }
}

pub(crate) fn check_tree(dem: &Dem, tree: &Quadtree, level: u8) -> Result<()> {
    if tree.dem_width as usize != dem.width || tree.dem_height as usize != dem.height {
        return Err(Error::BadOption(format!(
            "quadtree is for a {}x{} DEM but the DEM is {}x{}",
            tree.dem_width, tree.dem_height, dem.width, dem.height
        )));
    }
    if level >= tree.levels {
        return Err(Error::BadOption(format!(
            "level {level} does not exist (the quadtree has {} levels)",
            tree.levels
        )));
    }
    Ok(())
}

pub(crate) fn check_epsilon(epsilon: f64) -> Result<()> {
    if !(epsilon.is_finite() && epsilon >= 0.0) {
        return Err(Error::BadOption(format!(
            "maximum error must be a finite number >= 0, got {epsilon}"
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn run_is_within_epsilon_and_keeps_ends() {
        let hs: Vec<f64> = (0..200)
            .map(|i| ((i as f64) * 0.37).sin() * 10.0 + if i == 77 { 30.0 } else { 0.0 })
            .collect();
        for stride in [1, 2, 4, 16] {
            for eps in [0.0, 0.5, 3.0, 100.0] {
                let k = simplify_run(|p| hs[p as usize], 3, 190, stride, eps);
                assert_eq!((k[0], *k.last().unwrap()), (3, 190));
                assert!(k.windows(2).all(|w| w[0] < w[1]));
                assert!(run_error(|p| hs[p as usize], &k) <= eps + 1e-12);
                if eps == 0.5 {
                    assert!(k.contains(&77));
                }
            }
        }
        // flat and collinear runs keep only the ends
        assert_eq!(
            simplify_run(|p| p as f64 * 2.0 - 5.0, 0, 50, 4, 1e-9),
            vec![0, 50]
        );
        assert_eq!(simplify_run(|_| 1.0, 7, 8, 4, 0.0), vec![7, 8]);
    }
}
