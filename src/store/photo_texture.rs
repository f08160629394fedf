//! How a cell's photo texture is stored: dense (one PNG of the texture's side) or in blocks
//! (docs/formats.md, "Photo textures").
//!
//! A photo usually changes a fraction of an enlarged photo texture (a fifth of the texels of
//! a 12-MP photo's finest Engabreen cells); everywhere else the texture is the cell's active
//! texture magnified. So `cliffmap project` stores only the `side × side`-texel blocks where
//! photo colour has some weight ([`PhotoBlocks`]), packed row by row into an atlas PNG (the
//! confidence map into an atlas of the same layout); a reader gets the whole texture back
//! with [`compose`]: the active texture magnified by [`magnify`] (bilinear in linear light,
//! the function the projection itself starts from, so the result is bit for bit the texture
//! the projection blended), the blocks pasted over it, confidence 0 outside the blocks.

use image::{GrayImage, ImageBuffer, Pixel, RgbaImage};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::colour::{decode_u8, encode_u8};

/// Block side (texels) of the photo textures `cliffmap project` writes in blocks.
pub const PHOTO_BLOCK: u32 = 64;

/// Which blocks of a photo texture are stored (the others are the magnified active texture
/// with confidence 0).
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct PhotoBlocks {
    /// Block side in texels (> 0); blocks at the right and bottom edges may be cut by the
    /// texture's edge.
    pub side: u32,
    /// The stored blocks as a bit set over the row-major grid of `⌈texels / side⌉²` blocks,
    /// in hexadecimal: digit `k` holds blocks `4k..4k+3`, block `4k` in its highest bit.
    pub mask: String,
}

impl PhotoBlocks {
    /// The blocks of a texture of side `texels` marked in `present` (row-major over the block
    /// grid of [`PhotoBlocks::grid`]).
    pub fn new(side: u32, present: &[bool]) -> PhotoBlocks {
        let mask = present
            .chunks(4)
            .map(|c| {
                let v = c
                    .iter()
                    .enumerate()
                    .fold(0u32, |v, (i, &p)| v | (u32::from(p) << (3 - i)));
                char::from_digit(v, 16).unwrap_or('0')
            })
            .collect();
        PhotoBlocks { side, mask }
    }

    /// Blocks per row and column of a texture of side `texels`.
    pub fn grid(side: u32, texels: u32) -> u32 {
        texels.div_ceil(side.max(1))
    }

    /// The stored blocks of a texture of side `texels`, row-major; an error says what is
    /// wrong with the record (zero side, a mask of the wrong length or not hexadecimal).
    pub fn present(&self, texels: u32) -> Result<Vec<bool>, String> {
        if self.side == 0 {
            return Err("photo texture block side is 0".into());
        }
        let g = Self::grid(self.side, texels) as usize;
        let n = g * g;
        if self.mask.len() != n.div_ceil(4) {
            return Err(format!(
                "photo texture block mask has {} digits, a {texels}-texel texture in {}-texel blocks needs {}",
                self.mask.len(),
                self.side,
                n.div_ceil(4)
            ));
        }
        let mut out = Vec::with_capacity(n);
        for c in self.mask.chars() {
            let v = c
                .to_digit(16)
                .ok_or_else(|| format!("photo texture block mask has a non-hex digit {c:?}"))?;
            for i in 0..4 {
                out.push(v & (8 >> i) != 0);
            }
        }
        if out[n..].iter().any(|&p| p) {
            return Err("photo texture block mask marks blocks past the grid".into());
        }
        out.truncate(n);
        Ok(out)
    }
}

/// Blocks per row and rows of blocks of the atlas holding `count` blocks: `⌈√count⌉` per
/// row, as many rows as needed.
pub fn atlas_blocks(count: usize) -> (usize, usize) {
    if count == 0 {
        return (0, 0);
    }
    let cols = (count as f64).sqrt().ceil() as usize;
    (cols, count.div_ceil(cols))
}

/// The texel rectangle `(x0, y0, w, h)` of block `i` (row-major) in a texture of side
/// `texels` (cut at its edges).
fn block_rect(i: usize, side: u32, texels: u32) -> (usize, usize, usize, usize) {
    let g = PhotoBlocks::grid(side, texels) as usize;
    let (s, n) = (side as usize, texels as usize);
    let (x0, y0) = ((i % g) * s, (i / g) * s);
    (x0, y0, s.min(n - x0), s.min(n - y0))
}

/// Calls `copy(texture_offset, atlas_offset, len)` (in texels) for every row of every block
/// marked in `present` of a texture of side `texels`, in the atlas of [`atlas_blocks`] blocks
/// per row (the `k`-th marked block at atlas block `k`, row-major, atlas width `aw`).
fn block_rows(
    present: &[bool],
    side: u32,
    texels: u32,
    cols: usize,
    aw: usize,
    mut copy: impl FnMut(usize, usize, usize),
) {
    let blocks = present.iter().enumerate().filter(|p| *p.1).map(|p| p.0);
    for (k, i) in blocks.enumerate() {
        let (x0, y0, w, h) = block_rect(i, side, texels);
        let (ax, ay) = ((k % cols) * side as usize, (k / cols) * side as usize);
        for r in 0..h {
            copy((y0 + r) * texels as usize + x0, (ay + r) * aw + ax, w);
        }
    }
}

/// The atlas blocks per row and the atlas size (texels) for the blocks `present` marks.
fn atlas_layout(present: &[bool], side: u32) -> (usize, usize, usize, usize) {
    let count = present.iter().filter(|&&p| p).count();
    let (cols, rows) = atlas_blocks(count);
    (count, cols, cols * side as usize, rows * side as usize)
}

/// The blocks of `full` marked in `present` packed into an atlas ([`atlas_blocks`] blocks of
/// `side²` texels, the `k`-th marked block at atlas block `k`, row-major; texels past a cut
/// block 0).
pub fn pack<P: Pixel<Subpixel = u8>>(
    full: &ImageBuffer<P, Vec<u8>>,
    side: u32,
    present: &[bool],
) -> ImageBuffer<P, Vec<u8>> {
    let (_, cols, aw, ah) = atlas_layout(present, side);
    let ch = P::CHANNEL_COUNT as usize;
    let mut atlas = vec![0u8; aw * ah * ch];
    let src = full.as_raw();
    block_rows(present, side, full.width(), cols, aw, |t, a, n| {
        atlas[a * ch..(a + n) * ch].copy_from_slice(&src[t * ch..(t + n) * ch]);
    });
    ImageBuffer::from_raw(aw as u32, ah as u32, atlas).unwrap_or_else(|| ImageBuffer::new(0, 0))
}

/// Pastes the blocks of `atlas` (laid out by [`pack`]) into `full`; an error if the atlas
/// has another size than `present` needs.
pub fn unpack<P: Pixel<Subpixel = u8>>(
    atlas: &ImageBuffer<P, Vec<u8>>,
    full: &mut ImageBuffer<P, Vec<u8>>,
    side: u32,
    present: &[bool],
) -> Result<(), String> {
    let (count, cols, aw, ah) = atlas_layout(present, side);
    if (atlas.width() as usize, atlas.height() as usize) != (aw, ah) || count == 0 {
        return Err(format!(
            "photo texture atlas is {}x{}, its {count} blocks of {side} texels need {aw}x{ah}",
            atlas.width(),
            atlas.height()
        ));
    }
    let ch = P::CHANNEL_COUNT as usize;
    let texels = full.width();
    let (src, dst) = (atlas.as_raw(), &mut **full);
    block_rows(present, side, texels, cols, aw, |t, a, n| {
        dst[t * ch..(t + n) * ch].copy_from_slice(&src[a * ch..(a + n) * ch]);
    });
    Ok(())
}

/// The whole photo texture and confidence map of side `active.width() · scale` from the
/// cell's active texture `active` and the stored atlases: [`magnify`] of `active`, the
/// blocks pasted over it; confidence 0 outside the blocks.
pub fn compose(
    active: &RgbaImage,
    scale: u32,
    blocks: &PhotoBlocks,
    texture_atlas: &RgbaImage,
    confidence_atlas: &GrayImage,
) -> Result<(RgbaImage, GrayImage), String> {
    let mut texture = magnify(active, scale);
    let texels = texture.width();
    let present = blocks.present(texels)?;
    unpack(texture_atlas, &mut texture, blocks.side, &present)?;
    Ok((
        texture,
        compose_confidence(texels, blocks, confidence_atlas)?,
    ))
}

/// The whole confidence map of side `texels` from its stored atlas: the blocks pasted over
/// 0 ([`compose`] without the colour texture).
pub fn compose_confidence(
    texels: u32,
    blocks: &PhotoBlocks,
    confidence_atlas: &GrayImage,
) -> Result<GrayImage, String> {
    let present = blocks.present(texels)?;
    let mut confidence = GrayImage::new(texels, texels);
    unpack(confidence_atlas, &mut confidence, blocks.side, &present)?;
    Ok(confidence)
}

/// `existing` magnified `scale` times (a power of two) by bilinear interpolation between
/// texel centres (edges clamped), colour in linear light (as a GPU filters an sRGB texture),
/// alpha as it is; `scale` 1 returns a copy.
pub fn magnify(existing: &RgbaImage, scale: u32) -> RgbaImage {
    let (w, h) = existing.dimensions();
    if scale <= 1 || w == 0 || h == 0 {
        return existing.clone();
    }
    let m = Magnifier::new(existing, scale);
    let (ow, oh) = m.dimensions();
    let (ow, band) = (ow as usize, scale as usize);
    let mut out = vec![0u8; ow * oh as usize * 4];
    // bands of the `scale` output rows one pair of source rows serves
    out.par_chunks_mut(ow * 4 * band).enumerate().for_each_init(
        MagnifyScratch::default,
        |scratch, (b, chunk)| {
            let rows = chunk.len() / (ow * 4);
            m.fill([0, b * band], [ow, rows], chunk, ow, scratch);
        },
    );
    RgbaImage::from_raw(w * scale, h * scale, out).unwrap_or_else(|| existing.clone())
}

/// [`magnify`] of one texture, texel rectangle by rectangle: [`Magnifier::fill`] writes
/// bit for bit the texels [`magnify`] gives there.
#[derive(Clone, Debug)]
pub struct Magnifier {
    /// The source texels, colour decoded to linear light, alpha as its 8-bit value.
    lin: Vec<f32>,
    /// Floats per source row.
    row_len: usize,
    /// Per output column / row: the two source texels and the weight of the second.
    cols: Vec<(usize, usize, f32)>,
    rows: Vec<(usize, usize, f32)>,
}

/// Reusable rows of [`Magnifier::fill`] (the two source rows interpolated along x).
#[derive(Clone, Debug, Default)]
pub struct MagnifyScratch {
    top: Vec<f32>,
    bottom: Vec<f32>,
}

impl Magnifier {
    /// A magnifier of `existing` by `scale` (a power of two; 0 counts as 1).
    pub fn new(existing: &RgbaImage, scale: u32) -> Magnifier {
        let (w, h) = existing.dimensions();
        let scale = scale.max(1);
        let s = scale as f64;
        let taps = |n: u32| -> Vec<(usize, usize, f32)> {
            (0..n * scale)
                .map(|i| {
                    let u = ((i as f64 + 0.5) / s - 0.5).clamp(0.0, n.saturating_sub(1) as f64);
                    let i0 = u.floor() as usize;
                    (
                        i0,
                        (i0 + 1).min((n as usize).saturating_sub(1)),
                        (u - i0 as f64) as f32,
                    )
                })
                .collect()
        };
        Magnifier {
            lin: existing
                .as_raw()
                .iter()
                .enumerate()
                .map(|(i, &v)| if i % 4 == 3 { v as f32 } else { decode_u8(v) })
                .collect(),
            row_len: w as usize * 4,
            cols: taps(w),
            rows: taps(h),
        }
    }

    /// The magnified texture's size (texels).
    pub fn dimensions(&self) -> (u32, u32) {
        (self.cols.len() as u32, self.rows.len() as u32)
    }

    /// Writes the magnified RGBA8 texels of the rectangle at `origin` (column, row) of
    /// `size` (columns, rows) into `out`, row-major with `stride` texels per row (parts
    /// outside the magnified texture are left as they are).
    pub fn fill(
        &self,
        origin: [usize; 2],
        size: [usize; 2],
        out: &mut [u8],
        stride: usize,
        scratch: &mut MagnifyScratch,
    ) {
        let [x0, y0] = origin;
        let x1 = (x0 + size[0]).min(self.cols.len());
        let y1 = (y0 + size[1]).min(self.rows.len());
        if x0 >= x1 || y0 >= y1 {
            return;
        }
        let w = x1 - x0;
        let (top, bottom) = (&mut scratch.top, &mut scratch.bottom);
        top.resize(w * 4, 0.0);
        bottom.resize(w * 4, 0.0);
        // source row `y` interpolated along x over the columns x0..x1
        let across = |y: usize, buf: &mut [f32]| {
            let row = &self.lin[y * self.row_len..][..self.row_len];
            for (b, &(c0, c1, fx)) in buf.chunks_exact_mut(4).zip(&self.cols[x0..x1]) {
                for k in 0..4 {
                    b[k] = row[4 * c0 + k] + (row[4 * c1 + k] - row[4 * c0 + k]) * fx;
                }
            }
        };
        let mut have = (usize::MAX, usize::MAX);
        for (r, &(s0, s1, fy)) in self.rows[y0..y1].iter().enumerate() {
            if have != (s0, s1) {
                across(s0, top);
                across(s1, bottom);
                have = (s0, s1);
            }
            let Some(px) = out.get_mut(4 * r * stride..4 * (r * stride + w)) else {
                return;
            };
            for ((p, t), b) in px
                .chunks_exact_mut(4)
                .zip(top.chunks_exact(4))
                .zip(bottom.chunks_exact(4))
            {
                p[0] = encode_u8(t[0] + (b[0] - t[0]) * fy);
                p[1] = encode_u8(t[1] + (b[1] - t[1]) * fy);
                p[2] = encode_u8(t[2] + (b[2] - t[2]) * fy);
                p[3] = (t[3] + (b[3] - t[3]) * fy + 0.5) as u8;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(n: u32) -> RgbaImage {
        RgbaImage::from_fn(n, n, |x, y| {
            image::Rgba([
                (x * 53 + y * 17) as u8,
                (y * 90) as u8,
                ((x * y * 31) % 256) as u8,
                (40 + x * 40) as u8,
            ])
        })
    }

    #[test]
    fn masks_round_trip_and_bad_ones_are_refused() {
        let present: Vec<bool> = (0..25).map(|i| i % 3 == 0 || i == 24).collect();
        let b = PhotoBlocks::new(64, &present);
        assert_eq!(b.mask.len(), 7);
        assert_eq!(b.present(64 * 5).unwrap(), present);
        // a texture whose side is not a multiple of the block: the grid rounds up
        assert_eq!(b.present(64 * 4 + 1).unwrap(), present);
        assert!(b.present(64 * 4).is_err(), "wrong grid");
        assert!(
            PhotoBlocks {
                side: 64,
                mask: "g000000".into()
            }
            .present(320)
            .is_err()
        );
        assert!(
            PhotoBlocks {
                side: 0,
                mask: String::new()
            }
            .present(320)
            .is_err()
        );
        // a bit past the 25 blocks (the last digit holds block 24 and three spare bits)
        assert!(
            PhotoBlocks {
                side: 64,
                mask: "0000001".into()
            }
            .present(320)
            .is_err()
        );
    }

    #[test]
    fn blocks_pack_and_unpack_to_the_same_texture() {
        for (n, side) in [(64u32, 16u32), (70, 16), (32, 64)] {
            let full = texture(n);
            let g = PhotoBlocks::grid(side, n) as usize;
            let present: Vec<bool> = (0..g * g).map(|i| i % 2 == 1 || i + 1 == g * g).collect();
            let atlas = pack(&full, side, &present);
            let count = present.iter().filter(|&&p| p).count();
            let (c, r) = atlas_blocks(count);
            assert_eq!(atlas.dimensions(), ((c as u32) * side, (r as u32) * side));
            let mut back = RgbaImage::new(n, n);
            unpack(&atlas, &mut back, side, &present).unwrap();
            for (x, y, p) in back.enumerate_pixels() {
                let i = (y / side) as usize * g + (x / side) as usize;
                let want = if present[i] {
                    *full.get_pixel(x, y)
                } else {
                    image::Rgba([0; 4])
                };
                assert_eq!(*p, want, "{n} {side} at {x},{y}");
            }
            // an atlas of the wrong size is refused
            assert!(unpack(&RgbaImage::new(side, side + 1), &mut back, side, &present).is_err());
        }
    }

    #[test]
    fn magnifier_rectangles_equal_magnify_there() {
        let img = texture(9);
        for scale in [1u32, 2, 4, 8] {
            let full = magnify(&img, scale);
            let m = Magnifier::new(&img, scale);
            assert_eq!(m.dimensions(), full.dimensions());
            let n = full.width() as usize;
            let mut scratch = MagnifyScratch::default();
            // rectangles inside, cut by the right and bottom edges, and past them
            for (x0, y0, w, h) in [
                (0, 0, 4, 4),
                (3, 5, 7, 2),
                (n - 3, n - 2, 8, 8),
                (n, 0, 2, 2),
            ] {
                let stride = w + 1;
                let mut out = vec![7u8; 4 * stride * h];
                m.fill([x0, y0], [w, h], &mut out, stride, &mut scratch);
                for r in 0..h {
                    for c in 0..stride {
                        let got = &out[4 * (r * stride + c)..][..4];
                        let (x, y) = (x0 + c, y0 + r);
                        if c < w && x < n && y < n {
                            let want = full.get_pixel(x as u32, y as u32).0;
                            assert_eq!(got, want, "scale {scale} at {x},{y}");
                        } else {
                            assert_eq!(got, [7; 4], "scale {scale}: written outside");
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn compose_gives_the_magnified_texture_with_the_blocks_over_it() {
        let active = texture(8);
        let scale = 4;
        let mut blended = magnify(&active, scale);
        let side = 8;
        let g = PhotoBlocks::grid(side, 32) as usize;
        let present: Vec<bool> = (0..g * g).map(|i| i == 5 || i == 10).collect();
        let mut conf = GrayImage::new(32, 32);
        for (x, y, p) in blended.enumerate_pixels_mut() {
            if present[(y / side) as usize * g + (x / side) as usize] {
                *p = image::Rgba([1, 2, 3, 255]);
                conf.put_pixel(x, y, image::Luma([200]));
            }
        }
        let blocks = PhotoBlocks::new(side, &present);
        let (t, c) = compose(
            &active,
            scale,
            &blocks,
            &pack(&blended, side, &present),
            &pack(&conf, side, &present),
        )
        .unwrap();
        assert_eq!(t, blended);
        assert_eq!(c, conf);
    }

    #[test]
    fn magnify_is_bilinear_in_linear_light_at_every_texel() {
        let img = RgbaImage::from_fn(5, 3, |x, y| {
            image::Rgba([
                (x * 53 + y * 17) as u8,
                (y * 90) as u8,
                ((x * y * 31) % 256) as u8,
                (40 + x * 40) as u8,
            ])
        });
        for scale in [2u32, 4, 8] {
            let m = magnify(&img, scale);
            for (ox, oy, p) in m.enumerate_pixels() {
                let at = |o: u32, n: u32| {
                    let u = ((o as f64 + 0.5) / scale as f64 - 0.5).clamp(0.0, (n - 1) as f64);
                    let i = u.floor() as u32;
                    (i, (i + 1).min(n - 1), (u - i as f64) as f32)
                };
                let ((x0, x1, fx), (y0, y1, fy)) = (at(ox, 5), at(oy, 3));
                for k in 0..4 {
                    let v = |x, y| {
                        let b = img.get_pixel(x, y).0[k];
                        if k == 3 { b as f32 } else { decode_u8(b) }
                    };
                    let top = v(x0, y0) + (v(x1, y0) - v(x0, y0)) * fx;
                    let bottom = v(x0, y1) + (v(x1, y1) - v(x0, y1)) * fx;
                    let l = top + (bottom - top) * fy;
                    let want = if k == 3 {
                        (l + 0.5) as u8
                    } else {
                        encode_u8(l)
                    };
                    assert_eq!(p.0[k], want, "scale {scale} texel {ox},{oy} channel {k}");
                }
            }
        }
    }

    #[test]
    fn magnify_keeps_constants_and_centres() {
        let img = RgbaImage::from_fn(4, 4, |x, y| {
            image::Rgba([(x * 60) as u8, (y * 60) as u8, 7, 255])
        });
        assert_eq!(magnify(&img, 1), img);
        let m = magnify(&img, 2);
        assert_eq!(m.dimensions(), (8, 8));
        // corners clamp to the corner texels; between centres it interpolates in linear light
        assert_eq!(m.get_pixel(0, 0).0, [0, 0, 7, 255]);
        assert_eq!(m.get_pixel(7, 7).0, [180, 180, 7, 255]);
        let lin = |v: u8| decode_u8(v);
        assert_eq!(
            m.get_pixel(1, 0).0[0],
            encode_u8(0.75 * lin(0) + 0.25 * lin(60))
        );
        assert_eq!(
            m.get_pixel(2, 0).0[0],
            encode_u8(0.25 * lin(0) + 0.75 * lin(60))
        );
        assert!(m.pixels().all(|p| p.0[2] == 7 && p.0[3] == 255));
    }
}
