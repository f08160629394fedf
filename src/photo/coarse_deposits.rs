//! Deposits of footprints that are large against an enlarged photo texture's texels, held on
//! coarser grids and spread into the texture's own grid once a photo's splatting is done.
//!
//! A photo texture is sized for the finest photo pixels a cell receives
//! ([`super::sizing`]), so elsewhere in the cell one photo pixel can span tens of texels;
//! splatting it exactly texel by texel costs one random-access deposit per covered texel.
//! Such a footprint is instead deposited, exactly (the same box-area splat), on the
//! coarsest grid of the texture's pyramid on which the shorter side of its bounding box
//! still spans at least [`MIN_SPAN`] texels (level `j`: `side >> j` texels, `j ≤ log2
//! scale`), i.e. on texels at most a quarter of the pixel across, so no detail the pixel
//! carries is lost.
//!
//! [`CoarseDeposits::spread_into`] then moves every coarse texel's sums, coarsest level
//! first, into its four children: in proportion to the part of each child that deposits on
//! finer grids left *uncovered* (`max(0, 1 − coverage)`), evenly where they cover all four.
//! So where coarse and fine deposits of neighbouring pixels meet inside a coarse texel, the
//! coarse ones fill the gap instead of being smeared over texels the fine ones already
//! cover (a texel covered once stays at coverage 1, no seam of half-confident texels). The
//! sums are areas in texel² of the grid they are on; a child gets `4 × weight` of its
//! parent's (its area is a quarter), so totals are preserved. All in a fixed order: the
//! result does not depend on threads.

use super::texel_tiles::{TexelSums, TexelTiles};

/// The shorter side of a footprint's bounding box, in texels of the grid it is deposited
/// on, is at least this (unless it is deposited on the texture's own grid).
pub const MIN_SPAN: f64 = 4.0;

/// The coarser grids of a `texels × texels` photo texture (see the [module docs](self)).
#[derive(Clone, Debug, PartialEq)]
pub struct CoarseDeposits {
    /// `levels[j − 1]`: the grid of level `j`, `texels >> j` texels per side.
    levels: Vec<TexelTiles>,
    /// `MIN_SPAN · 2^(j+1)` for `j` = 0, 1, …: the span (texels of the finest grid) from
    /// which a footprint goes to level `j + 1`.
    thresholds: Vec<f64>,
}

impl CoarseDeposits {
    /// The grids of levels `1..=L` of a texture of `texels` side enlarged `scale` times
    /// (`L` = log2 of `scale`'s largest power-of-two factor that also divides `texels`; none
    /// for `scale` 1, so a texture of its active size is splatted exactly as before).
    pub fn new(texels: u32, scale: u32) -> CoarseDeposits {
        let l = scale
            .max(1)
            .trailing_zeros()
            .min(texels.max(1).trailing_zeros());
        CoarseDeposits {
            levels: (1..=l).map(|j| TexelTiles::new(texels >> j)).collect(),
            thresholds: (1..=l).map(|j| MIN_SPAN * (1u64 << j) as f64).collect(),
        }
    }

    /// The level (0 = the texture's own grid) for a footprint whose bounding box's shorter
    /// side spans `span` texels of the texture's grid; 0 for a NaN span.
    #[inline]
    pub fn level_for(&self, span: f64) -> usize {
        self.thresholds.iter().take_while(|&&t| span >= t).count()
    }

    /// The grid of level `j` (1 ≤ j ≤ the number of levels).
    #[inline]
    pub fn grid_mut(&mut self, j: usize) -> &mut TexelTiles {
        &mut self.levels[j - 1]
    }

    /// Whether nothing is held on a coarser grid.
    pub fn is_empty(&self) -> bool {
        self.levels.iter().all(|g| g.allocated() == 0)
    }

    /// Moves every coarse deposit into `fine` (the texture's own grid, `texels` side), as the
    /// [module docs](self) describe, and empties the coarse grids.
    pub fn spread_into(&mut self, fine: &mut TexelTiles) {
        if self.is_empty() {
            return;
        }
        let l = self.levels.len();
        // below[j - 1] for levels j = 1..l-1: the coverage of a level-j texel by deposits on
        // levels ≤ j, as a fraction of its area (dense; level 0's is read from `fine`)
        let mut below: Vec<Vec<f32>> = Vec::with_capacity(l.saturating_sub(1));
        for j in 1..l {
            let side = (fine.side() >> j) as usize;
            let child_side = 2 * side;
            let mut h = vec![0f32; side * side];
            let mut add_child = |c: usize, cov: f32| {
                let (x, y) = (c % child_side, c / child_side);
                h[(y / 2) * side + x / 2] += 0.25 * cov;
            };
            match below.last() {
                None => fine.for_each(|c, s| add_child(c, s.coverage)),
                Some(prev) => prev
                    .iter()
                    .enumerate()
                    .filter(|(_, v)| **v != 0.0)
                    .for_each(|(c, &v)| add_child(c, v)),
            }
            self.levels[j - 1].for_each(|t, s| h[t] += s.coverage);
            below.push(h);
        }
        for j in (1..=l).rev() {
            let grid = std::mem::replace(&mut self.levels[j - 1], TexelTiles::new(0));
            let side = grid.side() as usize;
            let child_side = 2 * side;
            let (target, cover): (&mut TexelTiles, Option<&[f32]>) = if j == 1 {
                (&mut *fine, None)
            } else {
                let (lo, _) = self.levels.split_at_mut(j - 1);
                (&mut lo[j - 2], Some(&below[j - 2]))
            };
            grid.for_each(|t, s| {
                if s.coverage == 0.0 {
                    return;
                }
                let (x, y) = (t % side, t / side);
                let c0 = 2 * y * child_side + 2 * x;
                let children = [c0, c0 + 1, c0 + child_side, c0 + child_side + 1];
                let free = children.map(|c| {
                    let cov = match cover {
                        Some(h) => h[c],
                        None => target.get(c).coverage,
                    };
                    (1.0 - cov).max(0.0)
                });
                let total: f32 = free.iter().sum();
                for (k, &c) in children.iter().enumerate() {
                    let share = if total > 1e-3 {
                        4.0 * free[k] / total
                    } else {
                        1.0
                    };
                    if share > 0.0
                        && let Some(d) = target.get_mut(c)
                    {
                        add_scaled(d, s, share);
                    }
                }
            });
        }
    }
}

/// `d += k · s`, every sum.
#[inline]
fn add_scaled(d: &mut TexelSums, s: &TexelSums, k: f32) {
    d.coverage += k * s.coverage;
    d.weight += k * s.weight;
    for i in 0..3 {
        d.colour[i] += k * s.colour[i];
    }
    d.footprint += k * s.footprint;
    d.grazing += k * s.grazing;
    d.clear += k * s.clear;
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sums(cov: f32, colour: f32) -> TexelSums {
        TexelSums {
            coverage: cov,
            weight: cov,
            colour: [cov * colour; 3],
            footprint: cov * 0.1,
            grazing: cov,
            clear: cov,
        }
    }

    #[test]
    fn levels_follow_the_scale_and_the_span() {
        assert_eq!(CoarseDeposits::new(256, 1).levels.len(), 0);
        assert_eq!(CoarseDeposits::new(1024, 4).levels.len(), 2);
        // a scale that does not divide the side evenly is cut to what does
        assert_eq!(CoarseDeposits::new(12, 8).levels.len(), 2);
        let c = CoarseDeposits::new(2048, 8);
        assert_eq!(c.level_for(7.9), 0);
        assert_eq!(c.level_for(8.0), 1);
        assert_eq!(c.level_for(16.0), 2);
        assert_eq!(c.level_for(1000.0), 3);
        assert_eq!(c.level_for(f64::NAN), 0);
    }

    #[test]
    fn a_coarse_deposit_fills_what_fine_ones_left_uncovered() {
        // 8 × 8 fine grid, one level up (4 × 4): fine deposits cover the left column of
        // a coarse texel's children, a coarse deposit of half its area the rest
        let mut fine = TexelTiles::new(8);
        let mut c = CoarseDeposits::new(8, 2);
        for c_idx in [0usize, 8] {
            *fine.get_mut(c_idx).unwrap() = sums(1.0, 0.2);
        }
        *c.grid_mut(1).get_mut(0).unwrap() = sums(0.5, 0.8);
        // and a lone coarse texel elsewhere, spread evenly
        *c.grid_mut(1).get_mut(4 * 3 + 3).unwrap() = sums(1.0, 0.6);
        c.spread_into(&mut fine);
        assert!(c.is_empty());
        for (t, want_cov, want_col) in [(0, 1.0, 0.2), (8, 1.0, 0.2), (1, 1.0, 0.8), (9, 1.0, 0.8)] {
            let s = fine.get(t);
            assert!((s.coverage - want_cov).abs() < 1e-6, "texel {t}: {s:?}");
            assert!((s.colour[0] / s.weight - want_col).abs() < 1e-6, "texel {t}");
        }
        for t in [6 * 8 + 6, 6 * 8 + 7, 7 * 8 + 6, 7 * 8 + 7] {
            assert!((fine.get(t).coverage - 1.0).abs() < 1e-6);
        }
        assert_eq!(fine.get(2).coverage, 0.0);
    }

    #[test]
    fn spreading_keeps_totals_through_several_levels() {
        let mut fine = TexelTiles::new(64);
        let mut c = CoarseDeposits::new(64, 8);
        let mut total = 0.0f64;
        for (t, v) in [(5usize, 0.7f32), (40, 1.0), (33 * 64 + 2, 0.3)] {
            *fine.get_mut(t).unwrap() = sums(v, 0.5);
            total += v as f64;
        }
        for j in 1..=3 {
            let side = 64 >> j;
            for t in (0..side * side).step_by(3) {
                let v = 0.25 + 0.1 * (t % 5) as f32;
                *c.grid_mut(j).get_mut(t).unwrap() = sums(v, 0.5);
                total += v as f64 * (1u64 << (2 * j)) as f64;
            }
        }
        c.spread_into(&mut fine);
        let mut got = 0.0f64;
        fine.for_each(|_, s| {
            got += s.coverage as f64;
            if s.weight > 0.0 {
                assert!((s.colour[1] / s.weight - 0.5).abs() < 1e-5);
            }
        });
        assert!((got - total).abs() < 1e-3 * total, "{got} vs {total}");
    }
}
