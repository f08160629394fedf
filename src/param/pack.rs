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
        let ang = if m == 2 { (h[1][1] - h[0][1]).atan2(h[1][0] - h[0][0]) } else { 0.0 };
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

/// The similarity applied by [`fit`]: uv' = offset + scale · R(rotation) · uv.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Fit {
    pub rotation: f64,
    pub scale: f64,
    pub offset: [f64; 2],
}

/// Rotates `uvs` so the minimum-area bounding rectangle is axis-aligned, scales them
/// uniformly into [g, 1-g]² (g = gutter fraction, < 0.5) and centres them there.
pub(crate) fn fit(uvs: &mut [[f64; 2]], gutter: f64) -> Fit {
    let hull = convex_hull(uvs);
    let (ang, _) = min_area_rect(&hull);
    let rot = -ang;
    let (c, s) = (rot.cos(), rot.sin());
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in uvs.iter_mut() {
        *p = [c * p[0] - s * p[1], s * p[0] + c * p[1]];
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
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
    Fit { rotation: rot, scale, offset: off }
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
        assert!(m < 1e-9 || (std::f64::consts::FRAC_PI_2 - m) < 1e-9, "{ang}");
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
        assert!((f.scale - 0.98 / 4.0).abs() < 1e-9);
    }

    #[test]
    fn calipers_match_brute_force_on_random_hulls() {
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
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
                let (mut lo, mut hi, mut top) = (f64::INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY);
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
