//! Photo colour pushed into the gutter next to it, so that a renderer's bilinear and mip
//! filtering at a chart's (or a cell's) edge does not mix in the existing texture's gutter.
//!
//! A texel of the blended blocks is *photo* if the photo supplies most of its colour
//! (confidence ≥ [`PHOTO_SHARE`]) and *gutter* if not and its alpha is below 255: off the
//! chart (alpha 0 in the existing texture, magnified into a ramp at its edge) or of unknown
//! colour. In each of
//! `passes` passes every gutter texel with a photo (or already filled) 8-neighbour, as of
//! the previous pass, takes their mean colour (in the working [`ColourSpace`]) and their
//! mean confidence; its alpha is kept, so the texture still says what is off the surface.
//! Fully known texels without photo colour (alpha 255) never change. The result does not
//! depend on the order texels are visited.
//!
//! Why: the existing (reparameterized) texture's gutter holds its own colours dilated, and
//! a photo texture starts from it magnified, so without this step every chart edge whose
//! surface took photo colour showed a thin line of the smeared existing colour in renders
//! (measured: docs/projection.md, "Photo colour in the gutter").

use crate::colour::ColourSpace;
use crate::resample::fill::N8;

/// Blocks of a texture held block-major in slots (as [`crate::photo::blend_cell`] keeps the
/// blocks footprints reached): block `i` (row-major over a `grid`-wide grid of `side`-texel
/// blocks) is in slot `slot_of[i]` (`u32::MAX`: not held), texels row-major in the block.
pub(crate) struct SlotBlocks<'a> {
    /// Slot of each block, `u32::MAX` where the block is not held.
    pub slot_of: &'a [u32],
    /// Block number held in each slot.
    pub slots: &'a [usize],
    /// Block side in texels.
    pub side: usize,
    /// Blocks per texture row.
    pub grid: usize,
    /// Texture size in texels.
    pub size: [usize; 2],
}

impl SlotBlocks<'_> {
    /// Index (texel number in slot order) of texel `(x, y)`, if its block is held.
    #[inline]
    fn index(&self, x: i64, y: i64) -> Option<usize> {
        if x < 0 || y < 0 || x >= self.size[0] as i64 || y >= self.size[1] as i64 {
            return None;
        }
        let (x, y) = (x as usize, y as usize);
        let block = (y / self.side) * self.grid + x / self.side;
        let slot = *self.slot_of.get(block)?;
        (slot != u32::MAX).then(|| {
            slot as usize * self.side * self.side + (y % self.side) * self.side + x % self.side
        })
    }

    /// The held 8-neighbours of slot-order index `at` (the first `count` entries): by offsets
    /// inside a block, through the texel's coordinates at a block's edge.
    #[inline]
    fn neighbours(&self, at: usize) -> ([usize; 8], usize) {
        let sd = self.side;
        let within = at % (sd * sd);
        let (rx, ry) = (within % sd, within / sd);
        if rx > 0 && ry > 0 && rx + 1 < sd && ry + 1 < sd {
            let list = [
                at - sd - 1,
                at - sd,
                at - sd + 1,
                at - 1,
                at + 1,
                at + sd - 1,
                at + sd,
                at + sd + 1,
            ];
            return (list, 8);
        }
        let (x, y) = self.texel(at);
        let mut out = [0usize; 8];
        let mut count = 0;
        for (dx, dy) in N8 {
            if let Some(j) = self.index(x + dx, y + dy) {
                out[count] = j;
                count += 1;
            }
        }
        (out, count)
    }

    /// The slots of the held blocks around slot `k`'s block, itself included.
    fn slot_and_neighbours(&self, k: usize) -> impl Iterator<Item = usize> + '_ {
        let block = self.slots[k];
        let grid = self.grid.max(1) as i64;
        let rows = self.slot_of.len().div_ceil(self.grid.max(1)) as i64;
        let (bx, by) = (block as i64 % grid, block as i64 / grid);
        (-1..=1i64)
            .flat_map(move |dy| (-1..=1i64).map(move |dx| (bx + dx, by + dy)))
            .filter(move |&(x, y)| x >= 0 && y >= 0 && x < grid && y < rows)
            .filter_map(move |(x, y)| {
                let s = *self.slot_of.get((y * grid + x) as usize)?;
                (s != u32::MAX).then_some(s as usize)
            })
    }

    /// Texel `(x, y)` of slot-order index `at`.
    #[inline]
    fn texel(&self, at: usize) -> (i64, i64) {
        let bt = self.side * self.side;
        let block = self.slots[at / bt];
        let within = at % bt;
        (
            ((block % self.grid) * self.side + within % self.side) as i64,
            ((block / self.grid) * self.side + within / self.side) as i64,
        )
    }
}

/// Confidence (photo share, 0..255) from which a texel's colour counts as the photo's: a
/// source of the fill. Gutter texels below it (a footprint's edge reaching just off the
/// chart gives them a sliver of photo weight) are filled like those with none.
pub(crate) const PHOTO_SHARE: u8 = 128;

/// Fills gutter texels next to photo texels as the [module docs](self) say, for `passes`
/// passes, in `px` (RGBA8, slot order) and `confidence` (one byte per texel, slot order).
/// Returns the texels filled per slot (so a caller knows which blocks changed).
pub(crate) fn fill_gutter_from_photo(
    px: &mut [u8],
    confidence: &mut [u8],
    blocks: &SlotBlocks,
    space: ColourSpace,
    passes: u32,
) -> Vec<u32> {
    const OTHER: u8 = 0;
    const GUTTER: u8 = 1;
    const FILLED: u8 = 2;
    const QUEUED: u8 = 3;
    let n = confidence.len().min(px.len() / 4);
    let mut filled_per_slot = vec![0u32; blocks.slots.len()];
    let mut state: Vec<u8> = (0..n)
        .map(|at| {
            if confidence[at] >= PHOTO_SHARE {
                FILLED
            } else if px[4 * at + 3] < 255 {
                GUTTER
            } else {
                OTHER
            }
        })
        .collect();
    let neighbours = |at: usize| {
        let (list, count) = blocks.neighbours(at);
        list.into_iter().take(count)
    };
    // the first front: gutter texels with a photo neighbour, looked for only in blocks that
    // hold gutter and have photo texels in them or in a held block around them
    let bt = blocks.side * blocks.side;
    let slots_n = (n / bt.max(1)).min(blocks.slots.len());
    let holds = |k: usize, what: u8| state[k * bt..(k + 1) * bt].contains(&what);
    let has_photo: Vec<bool> = (0..slots_n).map(|k| holds(k, FILLED)).collect();
    let mut front: Vec<usize> = Vec::new();
    for k in 0..slots_n {
        let near_photo = || {
            blocks
                .slot_and_neighbours(k)
                .any(|j| has_photo.get(j).copied().unwrap_or(false))
        };
        if holds(k, GUTTER) && near_photo() {
            front.extend(
                (k * bt..(k + 1) * bt).filter(|&at| {
                    state[at] == GUTTER && neighbours(at).any(|j| state[j] == FILLED)
                }),
            );
        }
    }
    for &at in &front {
        state[at] = QUEUED;
    }
    let mut updates: Vec<(usize, [u8; 3], u8)> = Vec::new();
    for _ in 0..passes {
        if front.is_empty() {
            break;
        }
        updates.clear();
        for &at in &front {
            let (mut sum, mut conf, mut count) = ([0.0f32; 3], 0u32, 0u32);
            for j in neighbours(at).filter(|&j| state[j] == FILLED) {
                for (k, s) in sum.iter_mut().enumerate() {
                    *s += space.decode_u8(px[4 * j + k]);
                }
                conf += confidence[j] as u32;
                count += 1;
            }
            // (every queued texel has a filled neighbour: it was queued next to one)
            let c = count.max(1) as f32;
            let rgb = sum.map(|s| space.encode_u8(s / c));
            let mean_conf = ((conf + count / 2) / count.max(1)).clamp(1, 255) as u8;
            updates.push((at, rgb, mean_conf));
        }
        for &(at, rgb, conf) in &updates {
            px[4 * at..4 * at + 3].copy_from_slice(&rgb);
            confidence[at] = conf;
            state[at] = FILLED;
            filled_per_slot[at / (blocks.side * blocks.side)] += 1;
        }
        front.clear();
        for &(at, _, _) in &updates {
            for j in neighbours(at) {
                if state[j] == GUTTER {
                    state[j] = QUEUED;
                    front.push(j);
                }
            }
        }
    }
    filled_per_slot
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The layout of [`block`]: one 8 x 8 block in slot 0.
    const ONE_BLOCK: SlotBlocks<'static> = SlotBlocks {
        slot_of: &[0],
        slots: &[0],
        side: 8,
        grid: 1,
        size: [8, 8],
    };

    /// One 8 x 8 block: the left half photo (red, confidence 200), column 4 and 5 gutter
    /// (alpha 0 and 100; texel (4, 0) with a share of 3), columns 6 and 7 known existing
    /// texels (alpha 255, green).
    fn block() -> (Vec<u8>, Vec<u8>) {
        let mut px = vec![0u8; 8 * 8 * 4];
        let mut cv = vec![0u8; 64];
        for y in 0..8 {
            for x in 0..8 {
                let at = y * 8 + x;
                let (rgba, c) = match x {
                    0..=3 => ([200, 0, 0, 255], 200),
                    4 => ([0, 90, 0, 0], 0),
                    5 => ([0, 90, 0, 100], 0),
                    _ => ([0, 90, 0, 255], 0),
                };
                px[4 * at..4 * at + 4].copy_from_slice(&rgba);
                // (a sliver of photo weight off the chart: still gutter)
                cv[at] = if (x, y) == (4, 0) { 3 } else { c };
            }
        }
        (px, cv)
    }

    #[test]
    fn gutter_next_to_photo_takes_its_colour_known_texels_do_not() {
        let (mut px, mut cv) = block();
        let blocks = ONE_BLOCK;
        let filled = fill_gutter_from_photo(&mut px, &mut cv, &blocks, ColourSpace::Linear, 4);
        assert_eq!(filled, vec![16]);
        for y in 0..8 {
            for x in 0..8 {
                let at = y * 8 + x;
                let p = &px[4 * at..4 * at + 4];
                match x {
                    0..=3 => assert_eq!((p, cv[at]), (&[200, 0, 0, 255][..], 200)),
                    // the gutter: photo colour and share, alpha kept
                    4 => assert_eq!((p, cv[at]), (&[200, 0, 0, 0][..], 200)),
                    5 => assert_eq!((p, cv[at]), (&[200, 0, 0, 100][..], 200)),
                    // known texels without photo colour: unchanged
                    _ => assert_eq!((p, cv[at]), (&[0, 90, 0, 255][..], 0)),
                }
            }
        }
    }

    #[test]
    fn neighbours_inside_and_across_blocks_match_the_coordinates() {
        // 3 x 2 blocks of 4 texels, blocks 1 and 5 not held, slots in a shuffled order
        let slot_of = [2u32, u32::MAX, 0, 3, 1, u32::MAX];
        let slots = [2usize, 4, 0, 3];
        let blocks = SlotBlocks {
            slot_of: &slot_of,
            slots: &slots,
            side: 4,
            grid: 3,
            size: [12, 8],
        };
        for at in 0..slots.len() * 16 {
            let (x, y) = blocks.texel(at);
            assert_eq!(blocks.index(x, y), Some(at));
            let mut want: Vec<usize> = N8
                .iter()
                .filter_map(|&(dx, dy)| blocks.index(x + dx, y + dy))
                .collect();
            let (list, count) = blocks.neighbours(at);
            let mut got = list[..count].to_vec();
            want.sort();
            got.sort();
            assert_eq!(got, want, "texel ({x}, {y})");
        }
        let mut around: Vec<usize> = blocks.slot_and_neighbours(3).collect();
        around.sort();
        // block 3 (slot 3) touches blocks 0 (slot 2), 4 (slot 1) and itself; 1 is not held
        assert_eq!(around, vec![1, 2, 3]);
    }

    #[test]
    fn one_pass_fills_one_ring_and_no_pass_fills_nothing() {
        let blocks = ONE_BLOCK;
        let (mut px, mut cv) = block();
        let (px0, cv0) = (px.clone(), cv.clone());
        assert_eq!(
            fill_gutter_from_photo(&mut px, &mut cv, &blocks, ColourSpace::Srgb, 0),
            vec![0]
        );
        assert_eq!((&px, &cv), (&px0, &cv0));
        fill_gutter_from_photo(&mut px, &mut cv, &blocks, ColourSpace::Srgb, 1);
        assert_eq!(cv[4], 200);
        assert_eq!(cv[5], 0, "column 5 is two texels from the photo");
        assert_eq!(&px[4 * 5..4 * 5 + 4], &[0, 90, 0, 100]);
    }

    #[test]
    fn fills_across_held_blocks_and_skips_blocks_not_held() {
        // 2 x 1 blocks of 4 texels: the photo in block 0's first columns, gutter everywhere
        // else; block 1 held in slot 0, block 0 in slot 1 (slot order need not be block order)
        let side = 4usize;
        let bt = side * side;
        let mut px = vec![0u8; 2 * bt * 4];
        let mut cv = vec![0u8; 2 * bt];
        for at in 0..bt {
            // slot 1 = block 0: columns 0..2 photo
            let x = at % side;
            let k = bt + at;
            if x < 2 {
                px[4 * k..4 * k + 4].copy_from_slice(&[50, 60, 70, 255]);
                cv[k] = 255;
            }
        }
        let slot_of = [1u32, 0];
        let slots = [1usize, 0];
        let blocks = SlotBlocks {
            slot_of: &slot_of,
            slots: &slots,
            side,
            grid: 2,
            size: [8, 4],
        };
        let filled = fill_gutter_from_photo(&mut px, &mut cv, &blocks, ColourSpace::Linear, 3);
        // block 0: columns 2, 3 (8 texels, slot 1); block 1: columns 4 (slot 0, 4 texels)
        assert_eq!(filled, vec![4, 8]);
        assert_eq!(&px[0..4], &[50, 60, 70, 0]);
        assert_eq!(cv[1], 0, "texel (5, 0) is three texels from the photo");
        // a texture whose other block is not held: nothing outside the held one changes
        let slot_of = [0u32, u32::MAX];
        let slots = [0usize];
        let blocks = SlotBlocks {
            slot_of: &slot_of,
            slots: &slots,
            side,
            grid: 2,
            size: [8, 4],
        };
        let mut px1 = px[bt * 4..].to_vec();
        let mut cv1 = vec![0u8; bt];
        for at in 0..bt {
            cv1[at] = if at % side < 2 { 255 } else { 0 };
            px1[4 * at + 3] = if at % side < 2 { 255 } else { 0 };
        }
        let filled = fill_gutter_from_photo(&mut px1, &mut cv1, &blocks, ColourSpace::Linear, 8);
        assert_eq!(filled, vec![8]);
    }
}
