//! Footprint reconstruction: texture positions of the pixel corners whose ray did not hit
//! the pixel's cell, extrapolated from the corners that did.
//!
//! Rules, applied to the missing corners in order 0..4, repeated until nothing changes:
//! 1. parallelogram: if the other three corners of the pixel are known,
//!    `t_k = t_{k−1} + t_{k+1} − t_{k+2}` (e.g. `t22 = t21 + t12 − t11`);
//! 2. adjacent footprints: linear extrapolation along the corner grid's row and column
//!    through the pixel, `t(i, j) = 2·t(i+dx, j) − t(i+2dx, j)` (and the same along `j`),
//!    where `(i+dx, j)` is the pixel's neighbouring corner (known) and `(i+2dx, j)` is a corner
//!    of the adjacent pixel that hit the same cell; both directions available are averaged.
//!
//! Corners not found after that make the pixel unrecoverable (dropped by the caller).

/// Corner order of a pixel: (col, row), (col+1, row), (col+1, row+1), (col, row+1).
pub(crate) const CORNER_OFFSETS: [[i64; 2]; 4] = [[0, 0], [1, 0], [1, 1], [0, 1]];

/// Completes `corners` (texture positions, `None` = missing) of the pixel whose corner 0 is
/// grid corner `(i0, j0)`; `grid(i, j)` is the texture position of grid corner `(i, j)` if
/// its ray hit the pixel's cell. Returns the number of corners reconstructed, or `None` if
/// some corner cannot be.
pub(crate) fn reconstruct(
    corners: &mut [Option<[f32; 2]>; 4],
    i0: i64,
    j0: i64,
    grid: impl Fn(i64, i64) -> Option<[f32; 2]>,
) -> Option<u8> {
    let mut made = 0u8;
    for _ in 0..4 {
        let mut changed = false;
        for k in 0..4 {
            if corners[k].is_some() {
                continue;
            }
            let (a, b, o) = (
                corners[(k + 3) % 4],
                corners[(k + 1) % 4],
                corners[(k + 2) % 4],
            );
            let value = if let (Some(a), Some(b), Some(o)) = (a, b, o) {
                Some([a[0] + b[0] - o[0], a[1] + b[1] - o[1]])
            } else {
                let [ci, cj] = CORNER_OFFSETS[k];
                let (i, j) = (i0 + ci, j0 + cj);
                let dx = if ci == 0 { 1 } else { -1 };
                let dy = if cj == 0 { 1 } else { -1 };
                // The pixel's own neighbours of corner k along the row and the column.
                let along_x = corners[k ^ 1];
                let along_y = corners[3 - k];
                let mut sum = [0.0f32; 2];
                let mut n = 0;
                if let (Some(near), Some(far)) = (along_x, grid(i + 2 * dx, j)) {
                    sum = [
                        sum[0] + 2.0 * near[0] - far[0],
                        sum[1] + 2.0 * near[1] - far[1],
                    ];
                    n += 1;
                }
                if let (Some(near), Some(far)) = (along_y, grid(i, j + 2 * dy)) {
                    sum = [
                        sum[0] + 2.0 * near[0] - far[0],
                        sum[1] + 2.0 * near[1] - far[1],
                    ];
                    n += 1;
                }
                (n > 0).then(|| [sum[0] / n as f32, sum[1] / n as f32])
            };
            if let Some(v) = value {
                corners[k] = Some(v);
                made += 1;
                changed = true;
            }
        }
        if corners.iter().all(Option::is_some) {
            return Some(made);
        }
        if !changed {
            return None;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An affine texture map of the corner grid.
    fn affine(i: i64, j: i64) -> [f32; 2] {
        [
            3.0 + 0.5 * i as f32 - 0.1 * j as f32,
            7.0 + 0.2 * i as f32 + 0.4 * j as f32,
        ]
    }

    fn close(a: [f32; 2], b: [f32; 2]) -> bool {
        (a[0] - b[0]).abs() < 1e-5 && (a[1] - b[1]).abs() < 1e-5
    }

    #[test]
    // indexed loops: each index serves more than one array or lookup
    #[allow(clippy::needless_range_loop)]
    fn affine_maps_are_reconstructed_exactly() {
        let (i0, j0) = (10, 20);
        let truth: [[f32; 2]; 4] = CORNER_OFFSETS.map(|[a, b]| affine(i0 + a, j0 + b));
        // Every subset of missing corners; the adjacent footprints' corners are known.
        for mask in 1u32..15 {
            let mut c = truth.map(Some);
            for k in 0..4 {
                if mask & (1 << k) != 0 {
                    c[k] = None;
                }
            }
            let missing = mask.count_ones() as u8;
            let got = reconstruct(&mut c, i0, j0, |i, j| {
                (!(i0..=i0 + 1).contains(&i) || !(j0..=j0 + 1).contains(&j)).then(|| affine(i, j))
            });
            assert_eq!(got, Some(missing), "mask {mask:b}");
            for k in 0..4 {
                assert!(close(c[k].unwrap(), truth[k]), "mask {mask:b} corner {k}");
            }
        }
        // Nothing known around a lone corner: unrecoverable.
        let mut c = [Some(truth[0]), None, None, None];
        assert_eq!(reconstruct(&mut c, i0, j0, |_, _| None), None);
    }
}
