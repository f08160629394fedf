//! A stand-in ortho image derived from the DEM (hypsometric tint with hillshade), used when
//! no orthophoto is given, so every cell still gets a meaningful colour texture.

use rayon::prelude::*;

use crate::dem::Dem;
use crate::ortho::Ortho;

/// An RGBA ortho on the DEM's grid: colour by relative height (green lowlands to grey rock to
/// white summits), shaded by a sun from the north-west at 45° elevation. DEM voids get alpha 0.
pub fn derived_ortho(dem: &Dem) -> Ortho {
    let (lo, hi) = dem.height_range();
    let span = (hi - lo).max(1e-6) as f64;
    let (w, h) = (dem.width, dem.height);
    let (sx, sy) = (dem.georef.spacing_x, dem.georef.spacing_y);
    let sun = glam::DVec3::new(-1.0, 1.0, std::f64::consts::SQRT_2).normalize();
    let px: Vec<[u8; 4]> = (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (r, c) = (i / w, i % w);
            let hz = |rr: usize, cc: usize| dem.at(rr, cc) as f64;
            let (c0, c1) = (c.saturating_sub(1), (c + 1).min(w - 1));
            let (r0, r1) = (r.saturating_sub(1), (r + 1).min(h - 1));
            let dzdx = (hz(r, c1) - hz(r, c0)) / ((c1 - c0) as f64 * sx);
            let dzdy = (hz(r0, c) - hz(r1, c)) / ((r1 - r0) as f64 * sy); // y grows north
            let n = glam::DVec3::new(-dzdx, -dzdy, 1.0).normalize();
            let shade = 0.35 + 0.65 * n.dot(sun).max(0.0);
            let t = (hz(r, c) - lo as f64) / span;
            let tint = ramp(t);
            let q = |v: f64| (v * shade * 255.0).round().clamp(0.0, 255.0) as u8;
            let a = if dem.void[i] { 0 } else { 255 };
            [q(tint[0]), q(tint[1]), q(tint[2]), a]
        })
        .collect();
    let image = image::RgbaImage::from_raw(w as u32, h as u32, px.into_flattened())
        .unwrap_or_else(|| image::RgbaImage::new(w as u32, h as u32));
    Ortho {
        image,
        georef: dem.georef,
    }
}

/// Hypsometric colour ramp for t in [0, 1].
fn ramp(t: f64) -> [f64; 3] {
    const STOPS: [(f64, [f64; 3]); 4] = [
        (0.0, [0.33, 0.52, 0.30]),
        (0.4, [0.62, 0.60, 0.45]),
        (0.75, [0.55, 0.52, 0.50]),
        (1.0, [0.95, 0.95, 0.97]),
    ];
    let t = t.clamp(0.0, 1.0);
    for w in STOPS.windows(2) {
        let ((t0, c0), (t1, c1)) = (w[0], w[1]);
        if t <= t1 {
            let f = (t - t0) / (t1 - t0);
            return [0, 1, 2].map(|k| c0[k] + (c1[k] - c0[k]) * f);
        }
    }
    STOPS[3].1
}
