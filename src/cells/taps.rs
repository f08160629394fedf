//! Separable area-filter taps: for each texel along one texture axis, the overlap lengths
//! of its footprint with the cells of a source grid axis (ortho pixels or DEM samples).

/// Taps of one texture axis against one source grid axis. Source cell `s` covers
/// `[s - 0.5, s + 0.5]` in grid coordinates, clipped to the axis' valid interval.
pub(crate) struct AxisTaps {
    /// First source index of texel `k`'s taps.
    pub first: Vec<usize>,
    /// Texel `k`'s taps are `offs[k]..offs[k + 1]` in `cov` / `filt`.
    pub offs: Vec<usize>,
    /// Overlap length of the texel's true footprint with the source cell.
    pub cov: Vec<f64>,
    /// Overlap length of the texel's filter footprint (true footprint widened to at least
    /// `min_filter` around its centre) with the source cell.
    pub filt: Vec<f64>,
    /// Length of the texel's true footprint.
    pub len: Vec<f64>,
}

impl AxisTaps {
    /// Builds taps for `footprints` (true footprint `[lo, hi]` of each texel, grid
    /// coordinates, `lo < hi`) against `n` source cells whose union is clipped to `clip`.
    pub fn new(
        n: usize,
        footprints: impl Iterator<Item = (f64, f64)>,
        clip: (f64, f64),
        min_filter: f64,
    ) -> AxisTaps {
        let mut t = AxisTaps {
            first: Vec::new(),
            offs: vec![0],
            cov: Vec::new(),
            filt: Vec::new(),
            len: Vec::new(),
        };
        for (lo, hi) in footprints {
            let c = 0.5 * (lo + hi);
            let half = (0.5 * (hi - lo)).max(0.5 * min_filter);
            let (flo, fhi) = (c - half, c + half);
            // cell s overlaps (flo, fhi) iff s + 0.5 > flo and s - 0.5 < fhi
            let s_min = ((flo - 0.5).floor() + 1.0).max(0.0);
            let s_max = ((fhi + 0.5).ceil() - 1.0).min(n as f64 - 1.0);
            let first = s_min as usize; // saturating cast; NaN -> 0
            t.first.push(first);
            if s_min <= s_max {
                for s in first..=(s_max as usize) {
                    let cell_lo = (s as f64 - 0.5).max(clip.0);
                    let cell_hi = (s as f64 + 0.5).min(clip.1);
                    t.cov.push((hi.min(cell_hi) - lo.max(cell_lo)).max(0.0));
                    t.filt.push((fhi.min(cell_hi) - flo.max(cell_lo)).max(0.0));
                }
            }
            t.offs.push(t.cov.len());
            t.len.push(hi - lo);
        }
        t
    }

    /// Index range into `cov` / `filt` of texel `k`.
    #[inline]
    pub fn range(&self, k: usize) -> std::ops::Range<usize> {
        self.offs[k]..self.offs[k + 1]
    }

    /// Sum of the coverage overlaps of texel `k` (the part of its footprint over the grid).
    pub fn cov_sum(&self, k: usize) -> f64 {
        self.cov[self.range(k)].iter().sum()
    }

    /// Smallest and largest source index touched by any texel, if any.
    pub fn span(&self) -> Option<(usize, usize)> {
        let mut out: Option<(usize, usize)> = None;
        for k in 0..self.first.len() {
            let n = self.offs[k + 1] - self.offs[k];
            if n > 0 {
                let (a, b) = (self.first[k], self.first[k] + n - 1);
                out = Some(out.map_or((a, b), |(x, y)| (x.min(a), y.max(b))));
            }
        }
        out
    }
}

/// The true footprints of `texels` equal texels splitting `[a, b]` (texel `k` covers
/// `[a + k (b - a) / T, a + (k + 1) (b - a) / T]`), mapped through the increasing affine
/// map `g`.
pub(crate) fn footprints(
    a: f64,
    b: f64,
    texels: u32,
    g: impl Fn(f64) -> f64,
) -> impl Iterator<Item = (f64, f64)> {
    let t = texels as f64;
    (0..texels).map(move |k| {
        let lo = a + (b - a) * (k as f64 / t);
        let hi = a + (b - a) * ((k + 1) as f64 / t);
        (g(lo), g(hi))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overlaps_partition_the_footprint() {
        // footprint [0.2, 2.7] over 5 cells: cells 0..=3 overlap
        let t = AxisTaps::new(5, [(0.2, 2.7), (3.6, 3.8)].into_iter(), (-0.5, 4.5), 1.0);
        assert_eq!(t.first[0], 0);
        let r = t.range(0);
        assert_eq!(r.len(), 4);
        let cov = &t.cov[r.clone()];
        let want = [0.3, 1.0, 1.0, 0.2];
        for (a, b) in cov.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{cov:?}");
        }
        assert!((t.cov_sum(0) - 2.5).abs() < 1e-12);
        // magnified texel: filter widened to [3.2, 4.2] -> linear interpolation weights
        let r = t.range(1);
        assert_eq!(t.first[1], 3);
        let (f, c) = (&t.filt[r.clone()], &t.cov[r]);
        assert!(
            (f[0] - 0.3).abs() < 1e-12 && (f[1] - 0.7).abs() < 1e-12,
            "{f:?}"
        );
        assert!(c[0].abs() < 1e-12 && (c[1] - 0.2).abs() < 1e-12, "{c:?}");
        assert_eq!(t.span(), Some((0, 4)));
        // clipped axis: cell 4 covers only [3.5, 4.0], so [3, 5] has 1.0 over data
        let t = AxisTaps::new(5, [(3.0, 5.0)].into_iter(), (0.0, 4.0), 0.0);
        assert!((t.cov_sum(0) - 1.0).abs() < 1e-12);
    }
}
