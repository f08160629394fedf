//! The pieces every start-camera method shares: the rotation that best maps world bearings
//! onto camera bearings (Wahba's problem, [`rotation_from_bearings`]), the focal-length
//! search over the field of view (`search_focal`) and the deterministic RANSAC sample
//! picker (`sample_picker`).

use glam::{DMat3, DVec3};
use nalgebra::Matrix3;

/// The world-to-camera rotation (rows right, down, forward) that best maps the world
/// bearings `world[i]` onto the camera bearings `cam[i]` (unit vectors, weights `w[i]`);
/// `None` for fewer than two non-parallel pairs.
pub fn rotation_from_bearings(cam: &[DVec3], world: &[DVec3], w: &[f64]) -> Option<DMat3> {
    let mut b = Matrix3::<f64>::zeros();
    for ((c, v), &wi) in cam.iter().zip(world).zip(w) {
        b += wi
            * Matrix3::new(
                c.x * v.x,
                c.x * v.y,
                c.x * v.z,
                c.y * v.x,
                c.y * v.y,
                c.y * v.z,
                c.z * v.x,
                c.z * v.y,
                c.z * v.z,
            );
    }
    let svd = b.svd(true, true);
    let (u, vt) = (svd.u?, svd.v_t?);
    let s = svd.singular_values;
    if !(s[1] > 1e-12 * s[0].max(1e-300)) {
        return None;
    }
    let d = (u * vt).determinant().signum();
    let r = u * Matrix3::from_diagonal(&nalgebra::Vector3::new(1.0, 1.0, d)) * vt;
    let m = DMat3::from_cols(
        DVec3::new(r[(0, 0)], r[(1, 0)], r[(2, 0)]),
        DVec3::new(r[(0, 1)], r[(1, 1)], r[(2, 1)]),
        DVec3::new(r[(0, 2)], r[(1, 2)], r[(2, 2)]),
    );
    m.is_finite().then_some(m)
}

/// A deterministic pseudo-random index picker (xorshift64 from `seed`, non-zero): each call
/// `next(n)` gives an index in `0..n` (`n` > 0), for RANSAC samples.
pub(crate) fn sample_picker(seed: u64) -> impl FnMut(usize) -> usize {
    let mut s = seed | 1;
    move |n| {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s % n as u64) as usize
    }
}

/// The focal length (pixels, for an image `width` pixels wide) minimising `cost`: the
/// horizontal field of view over 3°–140° on a log grid of `steps` steps, then golden section
/// between the best step's neighbours (40 rounds).
pub(crate) fn search_focal(width: f64, steps: usize, cost: impl Fn(f64) -> f64) -> f64 {
    let (lo, hi) = (3f64.ln(), 140f64.ln());
    let f_of = |k: f64| {
        let fov = (lo + (hi - lo) * k / steps as f64).exp();
        width / 2.0 / (fov.to_radians() / 2.0).tan()
    };
    let cost_k = |k: f64| cost(f_of(k));
    let (mut k_best, mut c_best) = (0usize, f64::INFINITY);
    for k in 0..=steps {
        let c = cost_k(k as f64);
        if c < c_best {
            (k_best, c_best) = (k, c);
        }
    }
    let (mut a, mut b) = (
        (k_best as f64 - 1.0).max(0.0),
        (k_best as f64 + 1.0).min(steps as f64),
    );
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..40 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if cost_k(c) < cost_k(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let k = 0.5 * (a + b);
    if cost_k(k) <= c_best {
        f_of(k)
    } else {
        f_of(k_best as f64)
    }
}
