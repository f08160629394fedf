//! Which pixels of a photo show the terrain it may colour ([`PixelMask`]): a user's mask file
//! (0 = ignore) and the automatic mask of uniform borders ([`uniform_border`]: the white
//! frame of a scanned print, the black padding of a stabilised frame, a banner of one colour
//! with text on it). Takes an RGB8 image (and a greyscale mask image); returns a bit per
//! pixel and, for the automatic mask, a report of what it took.

use image::{GrayImage, RgbImage};

use crate::error::{Error, Result};

/// One bit per pixel: `true` = left out (does not show terrain to use).
#[derive(Clone, Debug, PartialEq)]
pub struct PixelMask {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Row-major, `true` = masked.
    pub masked: Vec<bool>,
}

impl PixelMask {
    /// A mask that leaves nothing out.
    pub fn none(width: u32, height: u32) -> PixelMask {
        PixelMask {
            width,
            height,
            masked: vec![false; width as usize * height as usize],
        }
    }

    /// A user's mask image (`path` names it in errors) for a `width × height` photo: 0 =
    /// ignore the pixel, anything else = use it. Its size must be the photo's.
    pub fn from_image(
        mask: &GrayImage,
        width: u32,
        height: u32,
        path: &std::path::Path,
    ) -> Result<PixelMask> {
        if mask.dimensions() != (width, height) {
            return Err(Error::bad_input(
                path,
                format!(
                    "mask is {}x{} pixels but its photo is {width}x{height}",
                    mask.width(),
                    mask.height()
                ),
            ));
        }
        Ok(PixelMask {
            width,
            height,
            masked: mask.as_raw().iter().map(|&v| v == 0).collect(),
        })
    }

    /// Reads the mask image at `path` for a `width × height` photo ([`PixelMask::from_image`]).
    /// Errors name the file.
    pub fn read(path: &std::path::Path, width: u32, height: u32) -> Result<PixelMask> {
        let m = image::open(path)
            .map_err(|e| Error::bad_input(path, format!("cannot read mask image: {e}")))?
            .to_luma8();
        PixelMask::from_image(&m, width, height, path)
    }

    /// Whether pixel `[column, row]` is left out (pixels outside the image are).
    #[inline]
    pub fn is_masked(&self, pixel: [u32; 2]) -> bool {
        let [c, r] = pixel;
        c >= self.width
            || r >= self.height
            || self.masked[r as usize * self.width as usize + c as usize]
    }

    /// Pixels left out.
    pub fn count(&self) -> u64 {
        self.masked.iter().filter(|m| **m).count() as u64
    }

    /// Masks every pixel `other` masks (same size; otherwise nothing changes).
    pub fn union(&mut self, other: &PixelMask) {
        if (self.width, self.height) == (other.width, other.height) {
            for (a, b) in self.masked.iter_mut().zip(&other.masked) {
                *a |= *b;
            }
        }
    }

    /// The mask of the image halved as [`crate::photo::downsample2`] halves it (an odd last
    /// column or row cropped): a pixel is masked when any of its four is, since the
    /// halving mixes their colours. `None` if a side is below 2 pixels.
    pub fn halved(&self) -> Option<PixelMask> {
        let (w, h) = (self.width / 2, self.height / 2);
        if w == 0 || h == 0 {
            return None;
        }
        let sw = self.width as usize;
        let at = |c: usize, r: usize| self.masked[r * sw + c];
        let masked = (0..h as usize)
            .flat_map(|j| (0..w as usize).map(move |i| (i, j)))
            .map(|(i, j)| {
                at(2 * i, 2 * j)
                    || at(2 * i + 1, 2 * j)
                    || at(2 * i, 2 * j + 1)
                    || at(2 * i + 1, 2 * j + 1)
            })
            .collect();
        Some(PixelMask {
            width: w,
            height: h,
            masked,
        })
    }
}

/// Colour distance (largest channel difference) within which pixels count as the border's
/// colour (JPEG noise on a flat frame stays within a few levels).
pub const BORDER_TOLERANCE: u8 = 10;

/// At least this share of a side's edge pixels must have the side's colour for the side to
/// have a border.
pub const BORDER_EDGE_SHARE: f64 = 0.9;

/// A side with at least this share of near-black edge pixels (every channel at most
/// [`BORDER_TOLERANCE`]) has black padding there even when the rest of the edge is image (the
/// corner wedges of a rotated, stabilised video frame). Black only: a white run along an
/// edge may be clipped snow, which must stay.
pub const PADDING_EDGE_SHARE: f64 = 0.2;

/// A border reaches at most this share of the image's side into it.
pub const BORDER_MAX_DEPTH: f64 = 0.25;

/// What [`uniform_border`] masked on one side of the image.
#[derive(Clone, Debug, PartialEq)]
pub struct BorderSide {
    /// "top", "bottom", "left" or "right".
    pub side: &'static str,
    /// The border's colour (sRGB).
    pub colour: [u8; 3],
    /// Pixels masked from this side.
    pub pixels: u64,
}

/// The automatic mask of uniform borders of `image`: per side whose edge pixels (at least
/// [`BORDER_EDGE_SHARE`] of them) share one colour (within [`BORDER_TOLERANCE`] of their
/// median), or at least [`PADDING_EDGE_SHARE`] of them are near black (padding), the pixels
/// of that colour connected to the edge, at most [`BORDER_MAX_DEPTH`] of the image deep and
/// ending before that depth in the middle half of the side (a clear sky or a snowfield that
/// goes on is image, not a border); then the pixels the borders enclose (cut off from the image's
/// centre: a banner's text). Returns the mask and what each side gave (empty: no border).
pub fn uniform_border(image: &RgbImage) -> (PixelMask, Vec<BorderSide>) {
    let (mut mask, mut sides) = one_border_layer(image);
    // a border inside a border (a banner inside a scan's frame): once more inside the rows
    // and columns the first layer masks whole
    if let Some([x0, y0, x1, y1]) = inner_rectangle(&mask)
        && (x1 - x0, y1 - y0) != image.dimensions()
    {
        let inner = image::imageops::crop_imm(image, x0, y0, x1 - x0, y1 - y0).to_image();
        let (m, more) = one_border_layer(&inner);
        let mut new = 0u64;
        for y in 0..m.height {
            for x in 0..m.width {
                let i = (y + y0) as usize * mask.width as usize + (x + x0) as usize;
                if m.is_masked([x, y]) && !mask.masked[i] {
                    mask.masked[i] = true;
                    new += 1;
                }
            }
        }
        // (the rest of a first-layer border seen again adds nothing)
        if new > 0 {
            sides.extend(more);
        }
    }
    (mask, sides)
}

/// The rectangle `[x0, y0, x1, y1)` left after the rows and columns `mask` masks whole from
/// each edge; `None` when nothing (or everything) is masked that way.
fn inner_rectangle(mask: &PixelMask) -> Option<[u32; 4]> {
    let (w, h) = (mask.width, mask.height);
    let row = |y: u32| (0..w).all(|x| mask.is_masked([x, y]));
    let col = |x: u32| (0..h).all(|y| mask.is_masked([x, y]));
    let y0 = (0..h).find(|&y| !row(y))?;
    let y1 = (0..h).rev().find(|&y| !row(y))? + 1;
    let x0 = (0..w).find(|&x| !col(x))?;
    let x1 = (0..w).rev().find(|&x| !col(x))? + 1;
    (x1 > x0 + 4 && y1 > y0 + 4).then_some([x0, y0, x1, y1])
}

/// One layer of [`uniform_border`]: the borders along the image's own edges.
fn one_border_layer(image: &RgbImage) -> (PixelMask, Vec<BorderSide>) {
    let (w, h) = image.dimensions();
    let mut mask = PixelMask::none(w, h);
    let mut sides = Vec::new();
    if w < 4 || h < 4 {
        return (mask, sides);
    }
    for side in [Side::Top, Side::Bottom, Side::Left, Side::Right] {
        let Some(colour) = side_colour(image, side) else {
            continue;
        };
        let before = mask.count();
        fill_from_side(image, side, colour, &mut mask);
        let pixels = mask.count() - before;
        if pixels > 0 {
            sides.push(BorderSide {
                side: side.name(),
                colour,
                pixels,
            });
        }
    }
    if !sides.is_empty() {
        let before = mask.count();
        mask_enclosed(&mut mask);
        if let Some(s) = sides.first_mut() {
            // (what the borders enclose counts with the first side that has one)
            s.pixels += mask.count() - before;
        }
    }
    (mask, sides)
}

/// Masks the unmasked pixels not 4-connected to the image's centre through unmasked
/// pixels (nothing when the centre is masked).
fn mask_enclosed(mask: &mut PixelMask) {
    let (w, h) = (mask.width as usize, mask.height as usize);
    let centre = (h / 2) * w + w / 2;
    if mask.masked[centre] {
        return;
    }
    let mut reached = vec![false; w * h];
    let mut stack = vec![centre];
    reached[centre] = true;
    while let Some(i) = stack.pop() {
        let (c, r) = (i % w, i / w);
        let mut visit = |j: usize| {
            if !reached[j] && !mask.masked[j] {
                reached[j] = true;
                stack.push(j);
            }
        };
        if c > 0 {
            visit(i - 1);
        }
        if c + 1 < w {
            visit(i + 1);
        }
        if r > 0 {
            visit(i - w);
        }
        if r + 1 < h {
            visit(i + w);
        }
    }
    for (m, r) in mask.masked.iter_mut().zip(reached) {
        *m |= !r;
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Side {
    Top,
    Bottom,
    Left,
    Right,
}

impl Side {
    fn name(self) -> &'static str {
        match self {
            Side::Top => "top",
            Side::Bottom => "bottom",
            Side::Left => "left",
            Side::Right => "right",
        }
    }

    /// Lines (rows for top/bottom, columns for left/right) from the edge inwards: the
    /// line's index at depth `d` and the line length, for a `w × h` image.
    fn line(self, d: u32, w: u32, h: u32) -> u32 {
        match self {
            Side::Top | Side::Left => d,
            Side::Bottom => h - 1 - d,
            Side::Right => w - 1 - d,
        }
    }

    fn horizontal(self) -> bool {
        matches!(self, Side::Top | Side::Bottom)
    }

    /// Pixel `k` of line `l`.
    fn pixel(self, l: u32, k: u32) -> [u32; 2] {
        if self.horizontal() { [k, l] } else { [l, k] }
    }
}

fn close(a: [u8; 3], b: [u8; 3]) -> bool {
    (0..3).all(|k| a[k].abs_diff(b[k]) <= BORDER_TOLERANCE)
}

/// The colour of `side`'s edge line if most of its pixels share it (their per-channel
/// median).
fn side_colour(image: &RgbImage, side: Side) -> Option<[u8; 3]> {
    let (w, h) = image.dimensions();
    let (l, n) = (side.line(0, w, h), if side.horizontal() { w } else { h });
    let px: Vec<[u8; 3]> = (0..n)
        .map(|k| {
            let [c, r] = side.pixel(l, k);
            image.get_pixel(c, r).0
        })
        .collect();
    let median = |k: usize| {
        let mut v: Vec<u8> = px.iter().map(|p| p[k]).collect();
        v.sort_unstable();
        v[v.len() / 2]
    };
    let colour = [median(0), median(1), median(2)];
    let share = px.iter().filter(|p| close(**p, colour)).count() as f64 / n as f64;
    if share >= BORDER_EDGE_SHARE {
        return Some(colour);
    }
    let black = px.iter().filter(|p| close(**p, [0, 0, 0])).count() as f64 / n as f64;
    (black >= PADDING_EDGE_SHARE).then_some([0, 0, 0])
}

/// Masks the pixels of `colour` 4-connected to `side`'s edge, within the depth limit.
fn fill_from_side(image: &RgbImage, side: Side, colour: [u8; 3], mask: &mut PixelMask) {
    let (w, h) = image.dimensions();
    let depth = ((if side.horizontal() { h } else { w }) as f64 * BORDER_MAX_DEPTH) as u32;
    let inside = |c: u32, r: u32| {
        let d = match side {
            Side::Top => r,
            Side::Bottom => h - 1 - r,
            Side::Left => c,
            Side::Right => w - 1 - c,
        };
        d < depth.max(1)
    };
    let mut seen = vec![false; w as usize * h as usize];
    let mut stack: Vec<[u32; 2]> = Vec::new();
    let n = if side.horizontal() { w } else { h };
    for k in 0..n {
        stack.push(side.pixel(side.line(0, w, h), k));
    }
    let mut filled: Vec<usize> = Vec::new();
    // (depth, position along the side) of a pixel
    let place = |c: u32, r: u32| match side {
        Side::Top => (r, c),
        Side::Bottom => (h - 1 - r, c),
        Side::Left => (c, r),
        Side::Right => (w - 1 - c, r),
    };
    let mut reaches_limit = false;
    while let Some([c, r]) = stack.pop() {
        let i = r as usize * w as usize + c as usize;
        if seen[i] || !inside(c, r) || !close(image.get_pixel(c, r).0, colour) {
            continue;
        }
        seen[i] = true;
        filled.push(i);
        let (d, k) = place(c, r);
        reaches_limit |= d + 1 >= depth && (n / 4..3 * n / 4).contains(&k);
        if c > 0 {
            stack.push([c - 1, r]);
        }
        if c + 1 < w {
            stack.push([c + 1, r]);
        }
        if r > 0 {
            stack.push([c, r - 1]);
        }
        if r + 1 < h {
            stack.push([c, r + 1]);
        }
    }
    // a frame, banner or padding ends inside the image; a region that goes on through the
    // depth limit in the side's middle half is image (a clear sky, a snowfield)
    if !reaches_limit {
        for i in filled {
            mask.masked[i] = true;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A textured photo: no two neighbours alike, no flat region.
    fn photo(w: u32, h: u32) -> RgbImage {
        RgbImage::from_fn(w, h, |x, y| {
            let v = ((x * 37 + y * 91) % 97) as u8;
            image::Rgb([60 + v, 50 + (v / 2), 40 + (v / 3)])
        })
    }

    #[test]
    fn a_textured_photo_has_no_border() {
        let (m, sides) = uniform_border(&photo(200, 150));
        assert!(sides.is_empty() && m.count() == 0);
    }

    #[test]
    fn a_scan_border_a_banner_and_padding_are_masked() {
        let (w, h) = (200u32, 150u32);
        let mut img = photo(w, h);
        // white scan border of 6 px all round (with JPEG-like noise of ±3)
        for (x, y, p) in img.enumerate_pixels_mut() {
            if x < 6 || y < 6 || x >= w - 6 || y >= h - 6 {
                let n = ((x + y) % 7) as u8;
                *p = image::Rgb([252 - n, 253 - n / 2, 250]);
            }
        }
        let (m, sides) = uniform_border(&img);
        assert_eq!(sides.len(), 4, "{sides:?}");
        assert_eq!(m.count() as u32, w * h - (w - 12) * (h - 12));
        assert!(!m.is_masked([100, 75]));
        // a black banner of 12 rows at the bottom with white text in it
        let mut img = photo(w, h);
        for (x, y, p) in img.enumerate_pixels_mut() {
            if y >= h - 12 {
                let text = (40..120).contains(&x) && (h - 9..h - 3).contains(&y) && x % 3 == 0;
                *p = if text {
                    image::Rgb([255, 255, 255])
                } else {
                    image::Rgb([0, 0, 0])
                };
            }
        }
        let (m, sides) = uniform_border(&img);
        assert_eq!(sides.len(), 1);
        assert_eq!(sides[0].side, "bottom");
        assert_eq!(m.count() as u32, 12 * w, "the text goes with the banner");
        // black padding of a stabilised frame: a wedge on the left
        let mut img = photo(w, h);
        for (x, y, p) in img.enumerate_pixels_mut() {
            if x < 20 - y / 8 {
                *p = image::Rgb([0, 0, 0]);
            }
        }
        let (m, sides) = uniform_border(&img);
        assert_eq!(sides.iter().map(|s| s.side).collect::<Vec<_>>(), ["left"]);
        let wedge: u32 = (0..h).map(|y| 20u32.saturating_sub(y / 8)).sum();
        assert_eq!(m.count() as u32, wedge);
    }

    #[test]
    fn a_banner_inside_a_scan_frame_is_masked_too() {
        let (w, h) = (200u32, 150u32);
        let mut img = photo(w, h);
        for (x, y, p) in img.enumerate_pixels_mut() {
            if x < 6 || y < 6 || x >= w - 6 || y >= h - 6 {
                *p = image::Rgb([252, 252, 250]);
            } else if y >= h - 18 {
                let text = (40..120).contains(&x) && (h - 15..h - 9).contains(&y) && x % 3 == 0;
                *p = if text {
                    image::Rgb([255, 255, 255])
                } else {
                    image::Rgb([0, 0, 0])
                };
            }
        }
        let (m, sides) = uniform_border(&img);
        // the frame, and the 12 banner rows inside it with their text
        let frame = w * h - (w - 12) * (h - 12);
        assert_eq!(m.count() as u32, frame + 12 * (w - 12), "{sides:?}");
        assert!(sides.iter().any(|s| s.colour == [0, 0, 0]), "{sides:?}");
        assert!(!m.is_masked([100, 60]));
    }

    #[test]
    fn a_uniform_sky_along_the_top_is_not_a_border() {
        let (w, h) = (200u32, 150u32);
        let mut img = photo(w, h);
        for (_, y, p) in img.enumerate_pixels_mut() {
            if y < 60 {
                *p = image::Rgb([170, 200, 235]);
            }
        }
        let (m, sides) = uniform_border(&img);
        assert!(sides.is_empty() && m.count() == 0, "{sides:?}");
        // the same sky above a white scan frame: the frame alone
        for (x, y, p) in img.enumerate_pixels_mut() {
            if x < 6 || y < 6 || x >= w - 6 || y >= h - 6 {
                *p = image::Rgb([252, 252, 250]);
            }
        }
        let (m, _) = uniform_border(&img);
        assert_eq!(m.count() as u32, w * h - (w - 12) * (h - 12));
    }

    #[test]
    fn corner_wedges_of_black_padding_are_masked() {
        // a rotated stabilised frame: black wedges in two corners, covering part of the edges
        let (w, h) = (200u32, 150u32);
        let mut img = photo(w, h);
        let wedge = |x: u32, y: u32| x * 3 + y * 2 < 120 || (w - 1 - x) * 3 + (h - 1 - y) * 2 < 100;
        for (x, y, p) in img.enumerate_pixels_mut() {
            if wedge(x, y) {
                *p = image::Rgb([2, 1, 3]);
            }
        }
        let (m, sides) = uniform_border(&img);
        assert!(!sides.is_empty());
        let n = (0..w * h).filter(|i| wedge(i % w, i / w)).count() as u64;
        assert_eq!(m.count(), n, "{sides:?}");
        assert!(!m.is_masked([100, 75]));
    }

    #[test]
    fn a_flat_region_touching_one_edge_in_part_is_kept() {
        // blown-out snow on the lower left third: the bottom edge is not mostly one colour
        let (w, h) = (210u32, 150u32);
        let mut img = photo(w, h);
        for (x, y, p) in img.enumerate_pixels_mut() {
            if x < 70 && y > 100 {
                *p = image::Rgb([255, 255, 255]);
            }
        }
        let (m, sides) = uniform_border(&img);
        assert!(sides.is_empty() && m.count() == 0, "{sides:?}");
    }

    #[test]
    fn halving_masks_a_pixel_when_any_of_its_four_is() {
        let mut m = PixelMask::none(5, 4);
        m.masked[5 + 3] = true; // (3, 1)
        let h = m.halved().unwrap();
        assert_eq!((h.width, h.height), (2, 2));
        assert_eq!(h.masked, vec![false, true, false, false]);
        assert!(h.is_masked([2, 0]), "outside is masked");
    }

    #[test]
    fn a_user_mask_of_another_size_is_refused_naming_it() {
        let e = PixelMask::from_image(&GrayImage::new(3, 3), 4, 4, std::path::Path::new("m.png"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("m.png") && e.contains("3x3"), "{e}");
    }
}
