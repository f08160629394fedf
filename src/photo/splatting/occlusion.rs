//! The occlusion margin: photo pixels close to an occlusion edge of the photo (a silhouette
//! of the terrain against the sky or against farther terrain, or a depth jump between
//! neighbouring pixels) are trusted less, because a small error of the camera pose or of the
//! TIN moves the edge, so that such a pixel may show the occluder's colour (or the sky's)
//! where the texture wants the surface behind it (docs/projection.md, "Occlusion margin").
//!
//! [`OcclusionMap`] is built once per photo from the footprints of a cast of the finest
//! level at a reduced image size: a map pixel is an *edge seed* if it carries no footprint
//! (sky, a rejected silhouette pixel, terrain outside the store) or if its distance differs
//! from a 4-neighbour's by more than `jump` times the nearer one. The map holds each pixel's
//! exact Euclidean distance to the nearest seed (Felzenszwalb–Huttenlocher, in map pixels,
//! capped). A photo pixel of any pyramid image looks up the map pixel under its centre.
//!
//! The weight of a photo pixel `d` full-resolution pixels from the nearest edge is
//! `smoothstep(d / M)` with the margin `M = m + f · ε / distance` (pixels): `m` the pose
//! uncertainty in pixels ([`ConfidenceParams::occlusion_margin_px`]) plus how far the cell
//! TIN's error `ε` (metres) can move an edge seen at that distance with the full-resolution
//! focal length `f`. It enters the choice between photos (each texel keeps the mean weight of
//! a photo's deposits, [`crate::photo::TexelSums::clear`], and the photo's selection weight is
//! scaled by it, with a floor so that a photo alone on a texel still gives it colour), not
//! the blend against the existing texture (docs/projection.md, "Occlusion margin", has the
//! measurement that decided this). `m = 0` switches the margin off.

use crate::photo::FootprintSet;
use crate::photo::splatting::confidence::smoothstep;

/// Distances are capped at this many map pixels (far beyond any margin).
const CAP: f32 = 256.0;

/// Per pixel of a (reduced) photo image, the distance to the nearest occlusion edge.
#[derive(Clone, Debug, PartialEq)]
pub struct OcclusionMap {
    width: u32,
    height: u32,
    /// Full-resolution pixels per map pixel side (4 for a map cast at a quarter size).
    full_per_map: f32,
    /// Row-major distances in map pixels, capped at [`CAP`].
    dist: Vec<f32>,
}

impl OcclusionMap {
    /// The map of the footprints `fs` cast for an image of `width × height` pixels that is
    /// `full_per_map` times smaller (per side) than the full-resolution photo; `jump` is the
    /// relative distance difference between 4-neighbours that counts as an edge (e.g. 0.1).
    pub fn from_footprints(
        fs: &FootprintSet,
        width: u32,
        height: u32,
        full_per_map: f32,
        jump: f32,
    ) -> OcclusionMap {
        let (w, h) = (width as usize, height as usize);
        let mut depth = vec![f32::NAN; w * h];
        for fp in fs.iter() {
            let [c, r] = fp.pixel;
            if (c as usize) < w && (r as usize) < h && fp.distance.is_finite() {
                depth[r as usize * w + c as usize] = fp.distance;
            }
        }
        let jumps = |a: f32, b: f32| !(b.is_finite()) || (a - b).abs() > jump * a.min(b);
        let seeds: Vec<bool> = (0..w * h)
            .map(|i| {
                let d = depth[i];
                if !d.is_finite() {
                    return true;
                }
                let (x, y) = (i % w, i / w);
                (x > 0 && jumps(d, depth[i - 1]))
                    || (x + 1 < w && jumps(d, depth[i + 1]))
                    || (y > 0 && jumps(d, depth[i - w]))
                    || (y + 1 < h && jumps(d, depth[i + w]))
            })
            .collect();
        OcclusionMap {
            width,
            height,
            full_per_map: full_per_map.max(1e-6),
            dist: distance_transform(&seeds, w, h),
        }
    }

    /// The map's size in pixels.
    pub fn dimensions(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    /// Distance (full-resolution pixels, capped) from the centre of pixel `pixel` of an
    /// image `step_scale` times smaller per side than the full-resolution photo to the
    /// nearest occlusion edge; 0 outside the map.
    #[inline]
    pub fn distance_px(&self, pixel: [u32; 2], step_scale: f32) -> f32 {
        let k = step_scale / self.full_per_map;
        let x = ((pixel[0] as f32 + 0.5) * k).floor();
        let y = ((pixel[1] as f32 + 0.5) * k).floor();
        if !(x >= 0.0 && y >= 0.0 && x < self.width as f32 && y < self.height as f32) {
            return 0.0;
        }
        self.dist[y as usize * self.width as usize + x as usize] * self.full_per_map
    }
}

/// The occlusion weight of a pixel `d` full-resolution pixels from the nearest edge for a
/// margin of `margin` pixels: `smoothstep(d / margin)`, 1 when `margin <= 0`.
#[inline]
pub fn occlusion_weight(d: f32, margin: f32) -> f32 {
    if !(margin > 0.0) {
        return 1.0;
    }
    smoothstep((d / margin) as f64) as f32
}

/// Exact Euclidean distance (pixels, capped at [`CAP`]) from every pixel centre to the
/// nearest seed, by two passes of the 1-D lower-envelope transform (Felzenszwalb and
/// Huttenlocher 2012); all [`CAP`] without seeds.
fn distance_transform(seeds: &[bool], w: usize, h: usize) -> Vec<f32> {
    let inf = (CAP as f64 + 1.0).powi(2) * 4.0;
    let mut g: Vec<f64> = seeds.iter().map(|&s| if s { 0.0 } else { inf }).collect();
    let mut buf = Vec::new();
    let mut out = vec![0.0; w.max(h)];
    // columns
    let mut col = vec![0.0; h];
    for x in 0..w {
        for y in 0..h {
            col[y] = g[y * w + x];
        }
        edt_1d(&col, &mut out[..h], &mut buf);
        for y in 0..h {
            g[y * w + x] = out[y];
        }
    }
    // rows
    for y in 0..h {
        let row = &mut g[y * w..][..w];
        edt_1d(row, &mut out[..w], &mut buf);
        row.copy_from_slice(&out[..w]);
    }
    g.into_iter().map(|v| (v.sqrt() as f32).min(CAP)).collect()
}

/// `out[q] = min_p (q − p)² + f[p]` (the lower envelope of parabolas); `f` finite.
fn edt_1d(f: &[f64], out: &mut [f64], buf: &mut Vec<(usize, f64)>) {
    let n = f.len();
    if n == 0 {
        return;
    }
    // the envelope's parabolas: (vertex, left end of the interval where it is lowest)
    buf.clear();
    buf.push((0, f64::NEG_INFINITY));
    for q in 1..n {
        let fq = f[q] + (q * q) as f64;
        loop {
            let &(p, z) = buf.last().expect("the first parabola is never removed");
            let s = (fq - (f[p] + (p * p) as f64)) / (2.0 * (q - p) as f64);
            if s <= z && buf.len() > 1 {
                buf.pop();
                continue;
            }
            buf.push((q, s.max(z)));
            break;
        }
    }
    let mut k = 0;
    for (q, o) in out.iter_mut().enumerate() {
        while k + 1 < buf.len() && buf[k + 1].1 < q as f64 {
            k += 1;
        }
        let p = buf[k].0;
        *o = (q as f64 - p as f64).powi(2) + f[p];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::photo::{CellFootprints, PixelFootprint};

    fn set(w: u32, h: u32, depth: impl Fn(u32, u32) -> Option<f32>) -> FootprintSet {
        let mut fps = Vec::new();
        for r in 0..h {
            for c in 0..w {
                if let Some(d) = depth(c, r) {
                    fps.push(PixelFootprint {
                        cell: 0,
                        pixel: [c, r],
                        corners: [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]],
                        cos_view: 1.0,
                        distance: d,
                        reconstructed: 0,
                    });
                }
            }
        }
        FootprintSet {
            cells: vec![CellFootprints {
                cell: 0,
                chunks: vec![fps],
            }],
            ..FootprintSet::default()
        }
    }

    #[test]
    fn distances_to_the_sky_and_to_depth_jumps() {
        // sky above row 10, terrain at 100 m below, a near rock (50 m) in columns 30..40
        let fs = set(64, 48, |c, r| {
            (r >= 10).then_some(if (30..40).contains(&c) && r >= 30 {
                50.0
            } else {
                100.0
            })
        });
        let m = OcclusionMap::from_footprints(&fs, 64, 48, 2.0, 0.1);
        // the first terrain row touches the sky: seeds there; full-resolution pixels are
        // twice the map's
        assert_eq!(m.distance_px([5, 10], 2.0), 0.0);
        assert_eq!(m.distance_px([5, 15], 2.0), 2.0 * 5.0);
        // the rock's edge (row 30 against 29, columns 29/30 and 39/40) is an edge too
        assert_eq!(m.distance_px([35, 30], 2.0), 0.0);
        assert_eq!(m.distance_px([35, 33], 2.0), 2.0 * 3.0);
        assert_eq!(m.distance_px([20, 40], 2.0), 2.0 * 9.0);
        // Euclidean, not city-block: the nearest seeds of (26, 26) are the terrain pixels
        // next to the rock's corner, (29, 30) and (30, 29), 5 pixels away
        let d = m.distance_px([26, 26], 2.0) / 2.0;
        assert!((d - 5.0).abs() < 1e-4, "{d}");
        // a full-resolution pixel (step scale 1) looks up the map pixel under its centre
        assert_eq!(m.distance_px([70, 30], 1.0), m.distance_px([35, 15], 2.0));
        // brute force everywhere
        let seeds: Vec<(u32, u32)> = (0..48)
            .flat_map(|r| (0..64).map(move |c| (c, r)))
            .filter(|&(c, r)| m.distance_px([c, r], 2.0) == 0.0)
            .collect();
        for r in 0..48u32 {
            for c in 0..64u32 {
                let bf = seeds
                    .iter()
                    .map(|&(x, y)| {
                        ((x as f32 - c as f32).powi(2) + (y as f32 - r as f32).powi(2)).sqrt()
                    })
                    .fold(f32::INFINITY, f32::min);
                assert!(
                    (m.distance_px([c, r], 2.0) / 2.0 - bf).abs() < 1e-3,
                    "{c},{r}"
                );
            }
        }
    }

    #[test]
    fn smooth_depth_changes_are_no_edge() {
        // a plane seen obliquely: 1 % more distance per row
        let fs = set(40, 40, |_, r| Some(100.0 * 1.01f32.powi(r as i32)));
        let m = OcclusionMap::from_footprints(&fs, 40, 40, 1.0, 0.1);
        assert!(m.distance_px([20, 20], 1.0) >= 19.0);
        // without seeds at all distances are capped, and outside the map they are 0
        assert_eq!(m.distance_px([100, 20], 1.0), 0.0);
    }

    #[test]
    fn weight_ramps_over_the_margin() {
        assert_eq!(occlusion_weight(0.0, 3.0), 0.0);
        assert_eq!(occlusion_weight(3.0, 3.0), 1.0);
        assert!((occlusion_weight(1.5, 3.0) - 0.5).abs() < 1e-6);
        assert_eq!(occlusion_weight(0.0, 0.0), 1.0);
        let mut last = 0.0;
        for i in 0..40 {
            let w = occlusion_weight(i as f32 * 0.1, 3.0);
            assert!(w >= last);
            last = w;
        }
    }
}
