//! Filling texels without a known colour: gutter dilation, average border colour and
//! pull-push. All functions write only the RGB of texels whose `assigned` flag is false
//! and never change alpha.

use crate::fastmath::to_u8;
use image::RgbaImage;

/// The 8-neighbour offsets `(dx, dy)` of a texel, row by row.
pub(crate) const N8: [(i64, i64); 8] = [
    (-1, -1),
    (0, -1),
    (1, -1),
    (-1, 0),
    (1, 0),
    (-1, 1),
    (0, 1),
    (1, 1),
];

fn check(image: &RgbaImage, assigned: &[bool]) {
    debug_assert_eq!(
        assigned.len(),
        image.width() as usize * image.height() as usize
    );
}

/// Pushes assigned colours outward by `passes` texels: in each pass every unassigned texel
/// with an assigned 8-neighbour (as of the previous pass) gets their rounded mean colour and
/// becomes assigned. Returns the number of texels so coloured. Deterministic.
pub fn dilate_gutter(image: &mut RgbaImage, assigned: &mut [bool], passes: u32) -> usize {
    check(image, assigned);
    let (w, h) = (image.width() as i64, image.height() as i64);
    let mut changed = Vec::new();
    let mut total = 0;
    for _ in 0..passes {
        changed.clear();
        {
            let data: &[u8] = image.as_raw();
            for y in 0..h {
                let row = (y * w) as usize;
                for x in 0..w {
                    if assigned[row + x as usize] {
                        continue;
                    }
                    let (mut s, mut n) = ([0u32; 3], 0u32);
                    for (dx, dy) in N8 {
                        let (nx, ny) = (x + dx, y + dy);
                        if nx < 0 || ny < 0 || nx >= w || ny >= h {
                            continue;
                        }
                        let k = (ny * w + nx) as usize;
                        if assigned[k] {
                            let p = &data[4 * k..4 * k + 3];
                            for c in 0..3 {
                                s[c] += p[c] as u32;
                            }
                            n += 1;
                        }
                    }
                    if n > 0 {
                        changed.push((row + x as usize, s.map(|v| ((v + n / 2) / n) as u8)));
                    }
                }
            }
        }
        if changed.is_empty() {
            break;
        }
        let data: &mut [u8] = &mut *image;
        for &(k, rgb) in &changed {
            data[4 * k..4 * k + 3].copy_from_slice(&rgb);
            assigned[k] = true;
        }
        total += changed.len();
    }
    total
}

/// The average border colour: the mean RGB of the assigned texels that have an unassigned
/// 4-neighbour, or `None` if there is none (nothing or everything assigned).
pub fn average_border_colour(image: &RgbaImage, assigned: &[bool]) -> Option<[u8; 3]> {
    check(image, assigned);
    let (w, h) = (image.width() as usize, image.height() as usize);
    let data: &[u8] = image.as_raw();
    let (mut s, mut n) = ([0u64; 3], 0u64);
    for y in 0..h {
        let row = y * w;
        for x in 0..w {
            let k = row + x;
            if !assigned[k] {
                continue;
            }
            let borders = (x > 0 && !assigned[k - 1])
                || (x + 1 < w && !assigned[k + 1])
                || (y > 0 && !assigned[k - w])
                || (y + 1 < h && !assigned[k + w]);
            if borders {
                for c in 0..3 {
                    s[c] += data[4 * k + c] as u64;
                }
                n += 1;
            }
        }
    }
    (n > 0).then(|| s.map(|v| ((v + n / 2) / n) as u8))
}

/// Sets every unassigned texel to the [average border colour](average_border_colour)
/// (black if no texel is assigned). Returns the number of texels filled.
pub fn fill_average_border(image: &mut RgbaImage, assigned: &[bool]) -> usize {
    let c = average_border_colour(image, assigned).unwrap_or([0; 3]);
    let mut n = 0;
    for (p, &a) in image.pixels_mut().zip(assigned) {
        if !a {
            p.0[..3].copy_from_slice(&c);
            n += 1;
        }
    }
    n
}

/// Pull-push fill: a mip pyramid of weighted colours is built from the assigned texels
/// (pull, 2x2 box), then each unassigned texel takes the colour interpolated down from the
/// coarser levels (push). Filled colours are convex combinations of assigned ones; black if
/// nothing is assigned. Returns the number of texels filled.
pub fn fill_pull_push(image: &mut RgbaImage, assigned: &[bool]) -> usize {
    check(image, assigned);
    let (w0, h0) = (image.width() as usize, image.height() as usize);
    if w0 == 0 || h0 == 0 {
        return 0;
    }
    // level: (w, h, colour (premultiplied by weight), weight in [0, 1])
    struct Level {
        w: usize,
        h: usize,
        c: Vec<[f64; 3]>,
        a: Vec<f64>,
    }
    let mut base = Level {
        w: w0,
        h: h0,
        c: vec![[0.0; 3]; w0 * h0],
        a: vec![0.0; w0 * h0],
    };
    for (i, (p, &a)) in image.pixels().zip(assigned).enumerate() {
        if a {
            base.c[i] = [p[0] as f64, p[1] as f64, p[2] as f64];
            base.a[i] = 1.0;
        }
    }
    let mut levels = vec![base];
    // pull
    while {
        let l = &levels[levels.len() - 1];
        l.w > 1 || l.h > 1
    } {
        let l = &levels[levels.len() - 1];
        let (w, h) = (l.w.div_ceil(2), l.h.div_ceil(2));
        let mut next = Level {
            w,
            h,
            c: vec![[0.0; 3]; w * h],
            a: vec![0.0; w * h],
        };
        for y in 0..h {
            for x in 0..w {
                let (mut s, mut wt) = ([0.0; 3], 0.0);
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let (cx, cy) = (2 * x + dx, 2 * y + dy);
                    if cx < l.w && cy < l.h {
                        let i = cy * l.w + cx;
                        for (sk, ck) in s.iter_mut().zip(l.c[i]) {
                            *sk += l.a[i] * ck;
                        }
                        wt += l.a[i];
                    }
                }
                let i = y * w + x;
                if wt > 0.0 {
                    next.c[i] = s.map(|v| v / wt);
                    next.a[i] = wt.min(1.0);
                }
            }
        }
        levels.push(next);
    }
    // push: colour_k = a_k c_k + (1 - a_k) * parent
    for k in (0..levels.len() - 1).rev() {
        let (lo, hi) = levels.split_at_mut(k + 1);
        let (l, p) = (&mut lo[k], &hi[0]);
        for y in 0..l.h {
            for x in 0..l.w {
                let i = y * l.w + x;
                let pi = (y / 2) * p.w + x / 2;
                let a = l.a[i];
                for c in 0..3 {
                    l.c[i][c] = a * l.c[i][c] + (1.0 - a) * p.c[pi][c];
                }
                l.a[i] = 1.0;
            }
        }
    }
    let mut n = 0;
    for (i, (p, &a)) in image.pixels_mut().zip(assigned).enumerate() {
        if !a {
            let c = levels[0].c[i];
            p.0[..3].copy_from_slice(&c.map(to_u8));
            n += 1;
        }
    }
    n
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gutter_grows_one_ring_per_pass() {
        let mut img = RgbaImage::new(7, 7);
        let mut assigned = vec![false; 49];
        img.put_pixel(3, 3, image::Rgba([10, 20, 30, 255]));
        assigned[3 * 7 + 3] = true;
        assert_eq!(dilate_gutter(&mut img, &mut assigned, 1), 8);
        assert_eq!(dilate_gutter(&mut img, &mut assigned, 1), 16);
        assert_eq!(img.get_pixel(1, 5).0, [10, 20, 30, 0]);
        assert_eq!(img.get_pixel(0, 0).0, [0, 0, 0, 0]);
    }
}
