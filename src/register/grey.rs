//! A photo as grey levels: f32 luminance (Rec. 709 weights of the sRGB values), box-filtered
//! to smaller sizes; what the patch matchers and the silhouette-edge stage read. Also the
//! matchers' primitives: zero-mean patches, normalised cross-correlation of a template and
//! its exhaustive search, bilinear samples, Lucas-Kanade sub-pixel refinement.

use image::RgbImage;

/// A grey image as f32 luminance (Rec. 709 weights of the sRGB values).
pub(crate) struct Grey {
    /// Width in pixels.
    pub(crate) w: usize,
    /// Height in pixels.
    pub(crate) h: usize,
    /// Row-major luminance (0..255).
    pub(crate) v: Vec<f32>,
}

impl Grey {
    pub(crate) fn of(img: &RgbImage) -> Grey {
        let v = img
            .pixels()
            .map(|p| 0.2126 * p.0[0] as f32 + 0.7152 * p.0[1] as f32 + 0.0722 * p.0[2] as f32)
            .collect();
        Grey {
            w: img.width() as usize,
            h: img.height() as usize,
            v,
        }
    }

    /// Box-filtered by `k` (the last partial blocks dropped).
    pub(crate) fn reduced(&self, k: usize) -> Grey {
        let (w, h) = (self.w / k, self.h / k);
        let mut v = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                for dy in 0..k {
                    let row = &self.v[(y * k + dy) * self.w + x * k..][..k];
                    s += row.iter().sum::<f32>();
                }
                v[y * w + x] = s / (k * k) as f32;
            }
        }
        Grey { w, h, v }
    }
}

impl Grey {
    /// The patch of half size `r` at integer centre `(cx, cy)` with its mean removed, and
    /// its norm; `None` outside the image.
    pub(crate) fn patch(&self, cx: i64, cy: i64, r: i64) -> Option<(Vec<f32>, f32)> {
        if cx - r < 0 || cy - r < 0 || cx + r >= self.w as i64 || cy + r >= self.h as i64 {
            return None;
        }
        let n = (2 * r + 1) as usize;
        let mut p = Vec::with_capacity(n * n);
        for y in cy - r..=cy + r {
            let row = &self.v[y as usize * self.w + (cx - r) as usize..][..n];
            p.extend_from_slice(row);
        }
        let mean = p.iter().sum::<f32>() / p.len() as f32;
        p.iter_mut().for_each(|v| *v -= mean);
        let norm = p.iter().map(|v| v * v).sum::<f32>().sqrt();
        Some((p, norm))
    }

    /// NCC of the zero-mean template `t` (norm `tn`, half size `r`) at centre `(cx, cy)`,
    /// read straight from the image rows (no patch copy: this is the search's inner loop).
    /// As `Σ t = 0`, `Σ t·(p − p̄) = Σ t·p` and `‖p − p̄‖² = Σ p² − (Σ p)² / n`.
    pub(crate) fn ncc(&self, t: &[f32], tn: f32, cx: i64, cy: i64, r: i64) -> Option<f64> {
        if cx - r < 0
            || cy - r < 0
            || cx + r >= self.w as i64
            || cy + r >= self.h as i64
            || !(tn > 0.0)
        {
            return None;
        }
        let n = (2 * r + 1) as usize;
        let (mut dot, mut sum, mut sq) = (0.0f64, 0.0f64, 0.0f64);
        for (row, tr) in (cy - r..=cy + r).zip(t.chunks_exact(n)) {
            let pr = &self.v[row as usize * self.w + (cx - r) as usize..][..n];
            let (mut d, mut s1, mut s2) = (0.0f32, 0.0f32, 0.0f32);
            for (&a, &b) in pr.iter().zip(tr) {
                d += a * b;
                s1 += a;
                s2 += a * a;
            }
            (dot, sum, sq) = (dot + d as f64, sum + s1 as f64, sq + s2 as f64);
        }
        let pn2 = sq - sum * sum / (n * n) as f64;
        (pn2 > 0.0).then(|| dot / (pn2.sqrt() * tn as f64))
    }

    /// The best NCC of template `t` over centres within `rad` of `(cx, cy)`: (x, y, ncc),
    /// and whether the best lies on the search border.
    pub(crate) fn search(
        &self,
        t: &[f32],
        tn: f32,
        c: (i64, i64),
        rad: i64,
        r: i64,
    ) -> Option<(i64, i64, f64, bool)> {
        let mut best: Option<(i64, i64, f64)> = None;
        for y in c.1 - rad..=c.1 + rad {
            for x in c.0 - rad..=c.0 + rad {
                if let Some(s) = self.ncc(t, tn, x, y, r)
                    && best.is_none_or(|b| s > b.2)
                {
                    best = Some((x, y, s));
                }
            }
        }
        best.map(|(x, y, s)| (x, y, s, (x - c.0).abs() == rad || (y - c.1).abs() == rad))
    }
}

impl Grey {
    /// Bilinear sample at `(x, y)` (pixel centres at integers), `None` outside.
    #[inline]
    pub(crate) fn at(&self, x: f64, y: f64) -> Option<f32> {
        let (x0, y0) = (x.floor(), y.floor());
        if x0 < 0.0 || y0 < 0.0 || x0 + 1.0 >= self.w as f64 || y0 + 1.0 >= self.h as f64 {
            return None;
        }
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let i = y0 as usize * self.w + x0 as usize;
        let (a, b, c, d) = (
            self.v[i],
            self.v[i + 1],
            self.v[i + self.w],
            self.v[i + self.w + 1],
        );
        Some(a + (b - a) * fx + (c - a) * fy + (a - b - c + d) * fx * fy)
    }

    /// The sub-pixel position of the NCC peak of the zero-mean template `t` (norm `tn`, half
    /// size `r`) found at the integer centre `(x, y)` with score `s`: a parabola through the
    /// neighbours in each axis, then [`Grey::refine`]; `None` at the image's edge or if the
    /// refinement fails.
    pub(crate) fn peak_sub_pixel(
        &self,
        t: &[f32],
        tn: f32,
        (x, y): (i64, i64),
        s: f64,
        r: i64,
    ) -> Option<[f64; 2]> {
        let at = |dx: i64, dy: i64| self.ncc(t, tn, x + dx, y + dy, r);
        let (l, rr, u, d) = (at(-1, 0)?, at(1, 0)?, at(0, -1)?, at(0, 1)?);
        let start = [x as f64 + parabola(l, s, rr), y as f64 + parabola(u, s, d)];
        self.refine(t, tn, start, r)
    }

    /// Lucas-Kanade refinement of the position `p` in this image of the zero-mean template
    /// `t` (half size `r`): Gauss-Newton on the translation, both patches normalised to zero
    /// mean and unit norm (so gain and offset do not matter); `None` if it leaves the image
    /// or moves more than a pixel.
    pub(crate) fn refine(&self, t: &[f32], tn: f32, p: [f64; 2], r: i64) -> Option<[f64; 2]> {
        let n = (2 * r + 1) as usize;
        let tt: Vec<f64> = t.iter().map(|&v| (v / tn) as f64).collect();
        let mut q = p;
        for _ in 0..8 {
            let mut s = Vec::with_capacity(n * n);
            let mut g = Vec::with_capacity(n * n);
            for dy in -r..=r {
                for dx in -r..=r {
                    let (x, y) = (q[0] + dx as f64, q[1] + dy as f64);
                    s.push(self.at(x, y)? as f64);
                    g.push([
                        0.5 * (self.at(x + 1.0, y)? - self.at(x - 1.0, y)?) as f64,
                        0.5 * (self.at(x, y + 1.0)? - self.at(x, y - 1.0)?) as f64,
                    ]);
                }
            }
            let mean = s.iter().sum::<f64>() / s.len() as f64;
            let norm = s
                .iter()
                .map(|v| (v - mean) * (v - mean))
                .sum::<f64>()
                .sqrt();
            if !(norm > 0.0) {
                return None;
            }
            let (mut a, mut b) = ([0.0f64; 3], [0.0f64; 2]);
            for ((sv, gv), tv) in s.iter().zip(&g).zip(&tt) {
                let res = (sv - mean) / norm - tv;
                let j = [gv[0] / norm, gv[1] / norm];
                a[0] += j[0] * j[0];
                a[1] += j[0] * j[1];
                a[2] += j[1] * j[1];
                b[0] += j[0] * res;
                b[1] += j[1] * res;
            }
            let det = a[0] * a[2] - a[1] * a[1];
            if !(det.abs() > 1e-12) {
                return None;
            }
            let step = [
                -(a[2] * b[0] - a[1] * b[1]) / det,
                -(a[0] * b[1] - a[1] * b[0]) / det,
            ];
            q = [q[0] + step[0], q[1] + step[1]];
            if (q[0] - p[0]).abs() > 1.0 || (q[1] - p[1]).abs() > 1.0 {
                return None;
            }
            if step[0].abs() < 1e-3 && step[1].abs() < 1e-3 {
                break;
            }
        }
        Some(q)
    }
}

/// Sub-pixel offset of a parabola's vertex through `(−1, a)`, `(0, b)`, `(1, c)`, in [−0.5, 0.5].
pub(crate) fn parabola(a: f64, b: f64, c: f64) -> f64 {
    let d = a - 2.0 * b + c;
    if d < 0.0 {
        (0.5 * (a - c) / d).clamp(-0.5, 0.5)
    } else {
        0.0
    }
}

/// Centres of a square grid of `spacing` pixels over a `w × h` image, `margin` pixels from its
/// edges, row by row.
pub(crate) fn grid_centres(w: usize, h: usize, margin: i64, spacing: i64) -> Vec<(i64, i64)> {
    let (w, h, spacing) = (w as i64, h as i64, spacing.max(1));
    let mut centres = Vec::new();
    let mut y = margin;
    while y < h - margin {
        let mut x = margin;
        while x < w - margin {
            centres.push((x, y));
            x += spacing;
        }
        y += spacing;
    }
    centres
}
