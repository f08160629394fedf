//! Fitting a chart into the unit texture square: rotation to the minimum-area bounding
//! rectangle (rotating calipers on the convex hull), then a uniform scale into [0,1]²
//! minus a gutter.

fn cross(o: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])
}

/// Convex hull (Andrew's monotone chain), counter-clockwise, without collinear points.
pub(crate) fn convex_hull(points: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut p: Vec<[f64; 2]> = points.to_vec();
    p.sort_by(|a, b| a[0].total_cmp(&b[0]).then(a[1].total_cmp(&b[1])));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let mut h: Vec<[f64; 2]> = Vec::with_capacity(2 * p.len());
    for &x in &p {
        while h.len() >= 2 && cross(h[h.len() - 2], h[h.len() - 1], x) <= 0.0 {
            h.pop();
        }
        h.push(x);
    }
    let lower = h.len() + 1;
    for &x in p.iter().rev().skip(1) {
        while h.len() >= lower && cross(h[h.len() - 2], h[h.len() - 1], x) <= 0.0 {
            h.pop();
        }
        h.push(x);
    }
    h.pop();
    h
}

/// The minimum-area enclosing rectangle of a CCW convex hull: returns (angle of the
/// rectangle side collinear with a hull edge, area). Rotating calipers, O(hull size).
pub(crate) fn min_area_rect(h: &[[f64; 2]]) -> (f64, f64) {
    let m = h.len();
    if m < 3 {
        let ang = if m == 2 {
            (h[1][1] - h[0][1]).atan2(h[1][0] - h[0][0])
        } else {
            0.0
        };
        return (ang, 0.0);
    }
    let dirs: Vec<[f64; 2]> = (0..m)
        .map(|i| {
            let a = h[i];
            let b = h[(i + 1) % m];
            let l = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
            [(b[0] - a[0]) / l, (b[1] - a[1]) / l]
        })
        .collect();
    let proj = |p: [f64; 2], d: [f64; 2]| p[0] * d[0] + p[1] * d[1];
    let nrm = |d: [f64; 2]| [-d[1], d[0]];
    // Caliper indices: farthest along d (right), along n (top), against d (left).
    let (mut r, mut t, mut l) = (0usize, 0usize, 0usize);
    let d0 = dirs[0];
    for i in 0..m {
        if proj(h[i], d0) > proj(h[r], d0) {
            r = i;
        }
        if proj(h[i], nrm(d0)) > proj(h[t], nrm(d0)) {
            t = i;
        }
        if proj(h[i], d0) < proj(h[l], d0) {
            l = i;
        }
    }
    let mut best = (f64::INFINITY, 0usize);
    for i in 0..m {
        let d = dirs[i];
        let n = nrm(d);
        // Projections are unimodal around a convex polygon and the extremes turn with
        // the edge direction, so each caliper only moves forward.
        while proj(h[(r + 1) % m], d) > proj(h[r], d) {
            r = (r + 1) % m;
        }
        while proj(h[(t + 1) % m], n) > proj(h[t], n) {
            t = (t + 1) % m;
        }
        while proj(h[(l + 1) % m], d) < proj(h[l], d) {
            l = (l + 1) % m;
        }
        let w = proj(h[r], d) - proj(h[l], d);
        let ht = proj(h[t], n) - proj(h[i], n);
        let area = w * ht;
        if area < best.0 * (1.0 - 1e-12) {
            best = (area, i);
        }
    }
    (dirs[best.1][1].atan2(dirs[best.1][0]), best.0)
}

/// The side of the smallest square (over rotations) holding `uvs`: what [`fit`] scales to
/// the texture's side.
pub(crate) fn packed_side(uvs: &[[f64; 2]]) -> f64 {
    min_square_rotation(&convex_hull(uvs)).1
}

/// The similarity applied by [`fit`]: uv' = offset + scale · R(rotation) · uv.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fit {
    pub rotation: f64,
    pub scale: f64,
    pub offset: [f64; 2],
}

/// Bounding box (min, max corners) of `points` rotated by `rot` radians about the origin.
fn rotated_bounds(points: &[[f64; 2]], rot: f64) -> ([f64; 2], [f64; 2]) {
    let (c, s) = (rot.cos(), rot.sin());
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        let q = [c * p[0] - s * p[1], s * p[0] + c * p[1]];
        for k in 0..2 {
            lo[k] = lo[k].min(q[k]);
            hi[k] = hi[k].max(q[k]);
        }
    }
    (lo, hi)
}

/// The rotation (radians) that minimises the longer side of the axis-aligned bounding box
/// of the convex hull `h`, i.e. that lets the chart fill most of a square texture, and that
/// side. The side is a piecewise-smooth function of the angle with period 90°: sampled every
/// 0.5° (and at the minimum-area rectangle's angle, a good candidate for elongated charts),
/// then refined by golden-section search around the best sample. Deterministic.
pub(crate) fn min_square_rotation(h: &[[f64; 2]]) -> (f64, f64) {
    let side = |rot: f64| {
        let (lo, hi) = rotated_bounds(h, rot);
        (hi[0] - lo[0]).max(hi[1] - lo[1])
    };
    if h.len() < 2 {
        return (0.0, 0.0);
    }
    let step = 0.5f64.to_radians();
    let mut best = (-min_area_rect(h).0, f64::INFINITY);
    best.1 = side(best.0);
    for i in 0..180 {
        let r = i as f64 * step;
        let v = side(r);
        if v < best.1 {
            best = (r, v);
        }
    }
    // Golden-section refinement on [best - step, best + step].
    let (mut a, mut b) = (best.0 - step, best.0 + step);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (side(x1), side(x2));
    for _ in 0..40 {
        if f1 < f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = side(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = side(x2);
        }
    }
    let (r, v) = if f1 < f2 { (x1, f1) } else { (x2, f2) };
    if v < best.1 { (r, v) } else { best }
}

/// Rotates `uvs` so that their bounding box has the shortest possible longer side
/// ([`min_square_rotation`]), scales them uniformly into [g, 1-g]² (g = gutter fraction,
/// < 0.5) and centres them there.
pub(crate) fn fit(uvs: &mut [[f64; 2]], gutter: f64) -> Fit {
    let hull = convex_hull(uvs);
    let (rot, _) = min_square_rotation(&hull);
    let (lo, hi) = rotated_bounds(uvs, rot);
    let (c, s) = (rot.cos(), rot.sin());
    for p in uvs.iter_mut() {
        *p = [c * p[0] - s * p[1], s * p[0] + c * p[1]];
    }
    let avail = 1.0 - 2.0 * gutter;
    let ext = (hi[0] - lo[0]).max(hi[1] - lo[1]);
    let scale = if ext > 0.0 { avail / ext } else { 1.0 };
    let mut off = [0.0; 2];
    for k in 0..2 {
        off[k] = gutter + 0.5 * (avail - scale * (hi[k] - lo[k])) - scale * lo[k];
    }
    for p in uvs.iter_mut() {
        for k in 0..2 {
            p[k] = (off[k] + scale * p[k]).clamp(0.0, 1.0);
        }
    }
    Fit {
        rotation: rot,
        scale,
        offset: off,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rotated_rectangle_is_found() {
        let a: f64 = 0.3;
        let (c, s) = (a.cos(), a.sin());
        let mut pts = Vec::new();
        for i in 0..=10 {
            for j in 0..=3 {
                let (x, y) = (i as f64 * 0.4, j as f64 * 0.5);
                pts.push([c * x - s * y + 7.0, s * x + c * y - 2.0]);
            }
        }
        let h = convex_hull(&pts);
        assert!(h.len() >= 4);
        let (ang, area) = min_area_rect(&h);
        assert!((area - 4.0 * 1.5).abs() < 1e-9, "{area}");
        let m = (ang - a).rem_euclid(std::f64::consts::FRAC_PI_2);
        assert!(
            m < 1e-9 || (std::f64::consts::FRAC_PI_2 - m) < 1e-9,
            "{ang}"
        );
        let f = fit(&mut pts, 0.01);
        let mut lo = [1.0f64; 2];
        let mut hi = [0.0f64; 2];
        for p in &pts {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let ext = (hi[0] - lo[0]).max(hi[1] - lo[1]);
        assert!((ext - 0.98).abs() < 1e-9, "{lo:?} {hi:?}");
        // A 4 x 1.5 rectangle fills a square best turned by 45°: its box is then
        // (4 + 1.5)/√2 = 3.89 on both sides, less than its length 4.
        let side = 5.5 / 2f64.sqrt();
        assert!(
            (f.scale - 0.98 / side).abs() < 1e-9,
            "scale {} rotation {}",
            f.scale,
            f.rotation
        );
    }

    #[test]
    fn min_square_matches_a_fine_brute_force_search() {
        let mut seed = 777u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..20 {
            // random skewed point clouds (parallelogram-like, as converged charts are)
            let (k, a) = (rnd() * 2.0 - 1.0, rnd() * 3.0);
            let pts: Vec<[f64; 2]> = (0..40)
                .map(|_| {
                    let (x, y) = (rnd() * 3.0, rnd());
                    [x + k * y * 3.0, y + a * 0.2 * x]
                })
                .collect();
            let h = convex_hull(&pts);
            let (rot, side) = min_square_rotation(&h);
            let side_at = |r: f64| {
                let (c, s) = (r.cos(), r.sin());
                let xs: Vec<f64> = h.iter().map(|p| c * p[0] - s * p[1]).collect();
                let ys: Vec<f64> = h.iter().map(|p| s * p[0] + c * p[1]).collect();
                let ext = |v: &[f64]| {
                    v.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
                        - v.iter().cloned().fold(f64::INFINITY, f64::min)
                };
                ext(&xs).max(ext(&ys))
            };
            assert!((side_at(rot) - side).abs() < 1e-12);
            let brute = (0..90_000)
                .map(|i| side_at((i as f64 * 0.001).to_radians()))
                .fold(f64::INFINITY, f64::min);
            assert!(side <= brute * (1.0 + 1e-6), "{side} vs brute {brute}");
            // never worse than the minimum-area rectangle's orientation
            assert!(side <= side_at(-min_area_rect(&h).0) + 1e-12);
        }
    }

    #[test]
    fn calipers_match_brute_force_on_random_hulls() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        for _ in 0..50 {
            let pts: Vec<[f64; 2]> = (0..30).map(|_| [rnd() * 3.0, rnd()]).collect();
            let h = convex_hull(&pts);
            let (_, area) = min_area_rect(&h);
            let mut brute = f64::INFINITY;
            for i in 0..h.len() {
                let a = h[i];
                let b = h[(i + 1) % h.len()];
                let l = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
                let d = [(b[0] - a[0]) / l, (b[1] - a[1]) / l];
                let (mut lo, mut hi, mut top) =
                    (f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
                for p in &h {
                    let x = p[0] * d[0] + p[1] * d[1];
                    let y = -p[0] * d[1] + p[1] * d[0] - (-a[0] * d[1] + a[1] * d[0]);
                    lo = lo.min(x);
                    hi = hi.max(x);
                    top = top.max(y);
                }
                brute = brute.min((hi - lo) * top);
            }
            assert!((area - brute).abs() < 1e-9 * brute, "{area} vs {brute}");
        }
    }
}
